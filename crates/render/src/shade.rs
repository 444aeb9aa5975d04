//! Whitted-style shading (docs/model.md §5): ambient, Phong or Blinn-Phong per
//! visible light, shadow rays, mirror reflection and Snell refraction with
//! the media taken from the ray's partition.
//!
//! Scenes pay only for what they use: without transparent blocks the first
//! hit comes from [`Complex::cast_ray`] and shadow rays stop at the first
//! blocker; the partition is only formed when some block is transparent.

use complex::{BlockId, Complex, Partition, Spawner};
use quadric::nalgebra::{Point3, Vector3};
use quadric::normal::facing;
use quadric::Ray;

use crate::world::{Material, Model, World};

/// Colours are linear RGB in `f64` while shading.
pub type Rgb = Vector3<f64>;

/// What the primary ray saw, for the AOVs: where it first met a visible
/// surface, and which block and solid that surface belongs to.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PrimaryHit {
    /// Distance along the ray.
    pub t: f64,
    /// World-space unit normal facing the camera (zero where undefined).
    pub normal: Vector3<f64>,
    /// The block hit (0-based).
    pub block: BlockId,
    /// The solid within the block (0-based).
    pub solid: u32,
}

/// The first visible surface event along a ray.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Event {
    pub(crate) t: f64,
    pub(crate) point: Point3<f64>,
    /// Outward normal of the surface's block.
    pub(crate) normal: Vector3<f64>,
    pub(crate) block: BlockId,
    pub(crate) solid: u32,
    /// Owner of the ray just before and just after the event.
    pub(crate) before: Option<BlockId>,
    pub(crate) after: Option<BlockId>,
}

/// Per-thread scratch space and counters.
#[derive(Debug, Default)]
pub struct Scratch {
    partition: Partition,
    /// The block that stopped the last shadow ray, per light (modulo
    /// [`OCCLUDERS`]) and for camera or secondary hits apart: tried first
    /// by the next such shadow ray (`Complex::occluded_with`).
    occluders: [[complex::Occluder; 2]; OCCLUDERS],
    /// Rays cast so far (primary, shadow, reflected, refracted).
    pub rays: u64,
    /// The hint of the path integrator's shadow rays.
    pub(crate) path_occluder: complex::Occluder,
}

/// Lights with a shadow-ray hint of their own in [`Scratch`]; further
/// lights share them (a hint never changes an answer).
const OCCLUDERS: usize = 8;

/// Secondary rays whose colour would be scaled by less than this (the
/// product of the `reflect`/`transmit` factors along their path, largest
/// channel) are not followed: adaptive depth control (Hall and Greenberg,
/// 1983). Without it a scene mixing mirrors and glass casts a ray tree that
/// grows by about 1.6x per bounce up to `max_depth`.
pub const MIN_PATH_WEIGHT: f64 = 1e-4;

/// Shades rays against one world.
#[derive(Clone, Debug)]
pub struct Shader<'w> {
    world: &'w World,
    complex: &'w Complex,
    eps: f64,
    transparent: bool,
}

/// `a ⊙ b`, where a zero factor gives zero even against infinity. Colours
/// and weights are finite and non-negative, but their products can overflow
/// (a light of 1e300 on a diffuse 1e300), and `0 · ∞` would be a NaN pixel;
/// no light (or a zero weight) is no light, however bright the other factor.
/// Without a branch per channel: the only NaN product of two such factors
/// is `0 · ∞`, which gives `+0`, and `+ 0.0` turns a zero product's sign
/// to `+` as a zero factor's result has it; every other product is itself.
pub(crate) fn weigh(a: &Rgb, b: &Rgb) -> Rgb {
    a.zip_map(b, |x, y| {
        let p = x * y;
        if p.is_nan() {
            0.0
        } else {
            p + 0.0
        }
    })
}

pub(crate) fn is_zero(c: &Rgb) -> bool {
    c.iter().all(|x| *x == 0.0)
}

impl<'w> Shader<'w> {
    /// A shader for `world`.
    pub fn new(world: &'w World) -> Self {
        let complex = &world.complex;
        Shader { world, complex, eps: complex.epsilon(), transparent: complex.has_transparent() }
    }

    /// The world it shades.
    pub fn world(&self) -> &'w World {
        self.world
    }

    /// The colour seen along a primary ray and what it hit.
    pub fn primary(&self, ray: &Ray, scratch: &mut Scratch) -> (Rgb, Option<PrimaryHit>) {
        match self.first_event(ray, scratch) {
            None => (self.background(), None),
            Some(e) => (self.shade(ray, &e, 0, 1.0, scratch), Some(e.primary_hit(ray))),
        }
    }

    /// What a primary ray hits, unshaded: [`Shader::primary`]'s hit
    /// without its colour (the AOVs of a supersampled pixel, whose colour
    /// comes from its sub-pixel rays).
    pub fn primary_hit(&self, ray: &Ray, scratch: &mut Scratch) -> Option<PrimaryHit> {
        self.first_event(ray, scratch).map(|e| e.primary_hit(ray))
    }

    /// [`Shader::primary`] of four rays: in a scene without transparent
    /// blocks their first hits come from one shared BVH walk
    /// ([`complex::Complex::cast_rays`]); the colours and hits are exactly
    /// those of four `primary` calls.
    pub fn primary4(&self, rays: &[Ray; 4], scratch: &mut Scratch) -> [(Rgb, Option<PrimaryHit>); 4] {
        if self.transparent {
            return rays.each_ref().map(|r| self.primary(r, scratch));
        }
        scratch.rays += 4;
        let hits = self.complex.cast_rays(rays, f64::INFINITY);
        [0, 1, 2, 3].map(|k| match hits[k] {
            None => (self.background(), None),
            Some(h) => {
                let e = Event::of_hit(&h);
                (self.shade(&rays[k], &e, 0, 1.0, scratch), Some(e.primary_hit(&rays[k])))
            }
        })
    }

    /// The colour seen along `ray` at recursion depth `depth`.
    pub fn trace(&self, ray: &Ray, depth: u32, scratch: &mut Scratch) -> Rgb {
        self.trace_weighted(ray, depth, 1.0, scratch)
    }

    /// [`Shader::trace`] for a ray whose colour will be scaled by at most
    /// `weight` (the product of the `reflect`/`transmit` factors on its path).
    fn trace_weighted(&self, ray: &Ray, depth: u32, weight: f64, scratch: &mut Scratch) -> Rgb {
        match self.first_event(ray, scratch) {
            None => self.background(),
            Some(e) => self.shade(ray, &e, depth, weight, scratch),
        }
    }

    fn background(&self) -> Rgb {
        Vector3::from(self.world.settings.background)
    }

    /// The first event after ε where something visible happens. Events
    /// between two transparent blocks of the same material are skipped:
    /// they are one medium (docs/model.md §3.7).
    pub(crate) fn first_event(&self, ray: &Ray, scratch: &mut Scratch) -> Option<Event> {
        scratch.rays += 1;
        if !self.transparent {
            return self.complex.cast_ray(ray, f64::INFINITY).map(|h| Event::of_hit(&h));
        }
        // The partition only as far as its first interface (`t > ε`, not
        // between two blocks of one medium), where this ray stops.
        self.complex.first_interface(ray, &mut scratch.partition).map(|e| Event {
            t: e.t,
            point: e.point,
            normal: e.normal,
            block: e.surface.block,
            solid: e.surface.solid,
            before: e.before,
            after: e.after,
        })
    }

    /// The medium a segment owner stands for: `None` for empty space,
    /// `Some(None)` for an opaque block, `Some(Some(m))` for a transparent one.
    fn medium(&self, owner: Option<BlockId>) -> Option<Option<&'w Material>> {
        let id = owner?;
        let block = self.complex.block(id);
        Some(block.is_transparent().then(|| self.world.block_material(id)))
    }

    pub(crate) fn ior(&self, owner: Option<BlockId>) -> Option<f64> {
        match self.medium(owner) {
            None => Some(1.0),
            Some(Some(m)) => Some(m.ior),
            // Light does not travel through an opaque block.
            Some(None) => None,
        }
    }

    fn shade(&self, ray: &Ray, e: &Event, depth: u32, weight: f64, scratch: &mut Scratch) -> Rgb {
        let world = self.world;
        let mat = world.surface_material(e.block, e.solid);
        let v = -ray.direction();
        let mut n = facing_normal(&e.normal, &ray.direction());
        // A textured material: its colours at the point, in the block's
        // frame, and the bumped shading normal (docs/model.md §5.9); the
        // geometry (spawned rays' origins, ownership) keeps the true one.
        // The frame is read only for a textured material: an untextured hit
        // touches no block data beyond its material.
        let frame = if mat.textures.is_some() { world.frame(e.block) } else { None };
        let textured;
        let mat = match (mat.textures.as_deref(), frame) {
            (Some(t), Some(frame)) => {
                let p = frame.apply_point(&e.point);
                if let Some(bump) = &t.bump {
                    let bumped = bump.normal(&p, &n, frame.linear());
                    if bumped.dot(&v) > 0.0 {
                        n = bumped;
                    }
                }
                // `at` gives an empty name and no textures, so nothing is
                // leaked by not dropping it, and the untextured path keeps
                // no drop flag and no drop call.
                textured = std::mem::ManuallyDrop::new(mat.at(&p));
                &*textured
            }
            _ => mat,
        };
        let ambient = Vector3::from(world.settings.ambient);
        let mut c = weigh(&mat.ambient, &ambient);

        // Every secondary ray of this point leaves from one of two origins.
        let surface = complex::Surface { block: e.block, solid: e.solid };
        let mut spawner = self.complex.spawner_with_normal(surface, &e.point, &e.normal);

        let wants_diffuse = !is_zero(&mat.diffuse);
        let wants_specular = !is_zero(&mat.specular);
        if wants_diffuse || wants_specular {
            for (index, light) in world.lights.iter().enumerate() {
                let to_light = light.position - e.point;
                let dist = to_light.norm();
                if dist.is_nan() || dist <= 0.0 {
                    continue;
                }
                let l = quadric::lanes::div(&to_light, dist);
                let nl = n.dot(&l);
                if nl <= 0.0 {
                    continue;
                }
                let hint = (index % OCCLUDERS, usize::from(depth > 0));
                let pass = self.transmittance(&mut spawner, &l, dist, hint, scratch);
                if is_zero(&pass) {
                    continue;
                }
                let mut lc = weigh(&mat.diffuse, &light.diffuse) * nl;
                if wants_specular {
                    let s = match mat.model {
                        Model::Phong => (2.0 * nl * n - l).dot(&v),
                        Model::BlinnPhong => {
                            let h = l + v;
                            let hn = h.norm();
                            if hn > 0.0 {
                                n.dot(&quadric::lanes::div(&h, hn))
                            } else {
                                0.0
                            }
                        }
                    };
                    if s > 0.0 {
                        lc += weigh(&weigh(&mat.specular, &light.specular), &Vector3::repeat(power(s, mat.shininess)));
                    }
                }
                c += weigh(&lc, &pass);
            }
        }

        if depth >= world.settings.max_depth {
            return c;
        }
        let cos_i = n.dot(&v);
        let mut kr = mat.reflect;
        if !is_zero(&mat.transmit) {
            if let (Some(n1), Some(n2)) = (self.ior(e.before), self.ior(e.after)) {
                let eta = n1 / n2;
                let sin2_t = eta * eta * (1.0 - cos_i * cos_i).max(0.0);
                if sin2_t > 1.0 {
                    // Total internal reflection: the transmitted share is reflected.
                    kr += mat.transmit;
                } else {
                    let dir = -eta * v + (eta * cos_i - (1.0 - sin2_t).sqrt()) * n;
                    let w = weight * mat.transmit.max();
                    if let (true, Ok(r)) = (w >= MIN_PATH_WEIGHT, spawner.unit_ray(&dir)) {
                        c += weigh(&mat.transmit, &self.trace_weighted(&r, depth + 1, w, scratch));
                    }
                }
            }
        }
        let w = weight * kr.max();
        if !is_zero(&kr) && w >= MIN_PATH_WEIGHT {
            let dir = 2.0 * cos_i * n - v;
            if let Ok(r) = spawner.unit_ray(&dir) {
                c += weigh(&kr, &self.trace_weighted(&r, depth + 1, w, scratch));
            }
        }
        c
    }

    /// How much light passes from the event's point towards a light `dist`
    /// away along `l` (the shadow ray from `spawner`, [`Complex::spawn_ray`]'s
    /// origin: no acne however far the surface is): zero if an opaque block is in the way, else the
    /// product of the `transmit` of each transparent medium crossed (once
    /// per passage).
    fn transmittance(
        &self,
        spawner: &mut Spawner,
        l: &Vector3<f64>,
        dist: f64,
        (light, secondary): (usize, usize),
        scratch: &mut Scratch,
    ) -> Rgb {
        let one = Vector3::repeat(1.0);
        if !self.world.settings.shadows {
            return one;
        }
        let Ok(ray) = spawner.unit_ray(l) else { return one };
        scratch.rays += 1;
        if !self.transparent {
            // Any blocker will do: an any-hit query, no nearest-hit ordering.
            let occluder = &mut scratch.occluders[light][secondary];
            return if self.complex.occluded_with(&ray, dist, occluder) { Vector3::zeros() } else { one };
        }
        // The media crossed are in the segments; no event (hit point, normal)
        // is needed, nor any block beyond the light. The segments that start
        // before `reach` are the partition's (the last one's end aside, which
        // stays past `reach > ε` as the partition's does), so the loop below
        // weighs exactly what it weighs over the whole partition.
        let reach = dist.max(2.0 * self.eps);
        self.complex.segments_within(&ray, reach, &mut scratch.partition);
        let mut pass = one;
        let mut previous: Option<complex::MaterialKey> = None;
        for s in &scratch.partition.segments {
            if s.end <= self.eps || s.start >= dist {
                continue;
            }
            match s.owner {
                None => previous = None,
                Some(id) => {
                    let block = self.complex.block(id);
                    if !block.is_transparent() {
                        return Vector3::zeros();
                    }
                    if previous != Some(block.material()) {
                        let m = self.world.block_material(id);
                        // A textured medium: its `transmit` where the shadow ray enters it.
                        let frame = if m.textures.is_some() { self.world.frame(id) } else { None };
                        let kt = match frame {
                            Some(frame) => m.at(&frame.apply_point(&ray.at(s.start.max(0.0)))).transmit,
                            None => m.transmit,
                        };
                        pass = weigh(&pass, &kt);
                        if is_zero(&pass) {
                            return pass;
                        }
                    }
                    previous = Some(block.material());
                }
            }
        }
        pass
    }
}

impl Event {
    /// What a primary ray reports of this event for the AOVs.
    pub(crate) fn primary_hit(&self, ray: &Ray) -> PrimaryHit {
        PrimaryHit {
            t: self.t,
            normal: facing_normal(&self.normal, &ray.direction()),
            block: self.block,
            solid: self.solid,
        }
    }

    /// The event of a hit in a scene without transparent blocks.
    fn of_hit(h: &complex::Hit) -> Self {
        let (before, after) = if h.entering { (None, Some(h.block)) } else { (Some(h.block), None) };
        Event { t: h.t, point: h.point, normal: h.normal, block: h.block, solid: h.solid, before, after }
    }
}

/// The largest exponent [`power`] raises to by repeated squaring.
const MAX_INTEGER_EXPONENT: u32 = 4096;

/// `s^e` for the specular term (`s > 0`, `e >= 0` finite): for a whole
/// exponent `n` up to [`MAX_INTEGER_EXPONENT`] (every shininess in
/// practice) by repeated squaring, at most 24 products where `powf` is a
/// libm call of a hundred-odd instructions; else `powf`. Each product is
/// rounded once and a squaring doubles the relative error of what it
/// squares, so the result is within about `n·u` (below `1e-12`) of `s^n`,
/// far below the `f32` of the image (the test checks it against `powf`).
fn power(s: f64, e: f64) -> f64 {
    let n = e as u32;
    if f64::from(n) != e || n > MAX_INTEGER_EXPONENT {
        return s.powf(e);
    }
    let (mut base, mut n, mut result) = (s, n, 1.0);
    while n > 0 {
        if n & 1 == 1 {
            result *= base;
        }
        n >>= 1;
        if n > 0 {
            base *= base;
        }
    }
    result
}

/// The unit normal turned towards the viewer; `-dir` where the surface has
/// no normal (a cone's apex), so shading stays finite.
pub(crate) fn facing_normal(outward: &Vector3<f64>, dir: &Vector3<f64>) -> Vector3<f64> {
    if outward.iter().all(|c| *c == 0.0) {
        -dir
    } else {
        facing(*outward, dir)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Bit for bit the rule it implements (a zero factor gives `+0`, else
    /// the product) for every pair of non-negative factors of these kinds:
    /// zeros of both signs, products that underflow or overflow, infinity.
    #[test]
    fn weigh_is_zero_for_a_zero_factor_else_the_product() {
        let values = [0.0, -0.0, 1e-300, 1e-200, 5e-324, 0.25, 1.0, 3.5, 1e200, 1e300, f64::MAX, f64::INFINITY];
        for x in values {
            for y in values {
                let want = if x == 0.0 || y == 0.0 { 0.0 } else { x * y };
                let got = weigh(&Rgb::new(x, 1.0, y), &Rgb::new(y, 1.0, x));
                assert_eq!(got[0].to_bits(), want.to_bits(), "{x} * {y}");
                assert_eq!(got[2].to_bits(), want.to_bits(), "{y} * {x}");
            }
        }
    }

    /// Against libm's `powf`, an independent implementation: within
    /// `(n + 1)·2u` relative for every whole exponent up to the limit,
    /// exactly `powf` above it and for fractional exponents.
    #[test]
    fn power_is_powf_to_within_the_rounding_of_its_products() {
        let u = f64::EPSILON / 2.0;
        let bases = [1.0, 0.999_999_9, 0.987_654_321, 0.75, 0.5, 0.123_456_789, 1e-3, 1e-9, 1.000_000_1];
        for n in 0..=MAX_INTEGER_EXPONENT {
            for s in bases {
                let (got, want) = (power(s, f64::from(n)), s.powf(f64::from(n)));
                let tolerance = f64::from(n + 1) * 2.0 * u * want + f64::MIN_POSITIVE;
                assert!((got - want).abs() <= tolerance, "{s}^{n}: {got:e} against {want:e}");
            }
        }
        for (s, e) in [(0.9, 2.5), (0.5, 0.1), (0.99, 4097.0), (0.999, 1e6), (0.7, 1e300)] {
            assert_eq!(power(s, e).to_bits(), s.powf(e).to_bits(), "{s}^{e}");
        }
    }
}
