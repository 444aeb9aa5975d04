//! The path integrator (docs/model.md §5.10): a Monte Carlo estimate of the
//! rendering equation along one random path per sample, with next-event
//! estimation towards point lights and emissive blocks, multiple importance
//! sampling between light and BSDF samples, and Russian roulette.
//!
//! The random numbers of a sample come from its [`Sampler`], one fixed
//! dimension per decision ([`CAMERA_DIMS`], [`DIMS_PER_BOUNCE`]), so a
//! pixel's value does not depend on threads, tiles or the order of work.

use std::borrow::Cow;
use std::f64::consts::PI;

use complex::{BlockId, Spawner, Surface};
use quadric::nalgebra::{Point3, SymmetricEigen, Vector3};
use quadric::{Ray, Solid};

use crate::lobes::Lobes;
use crate::sampling::Sampler;
use crate::shade::{facing_normal, is_zero, weigh, Event, Rgb, Scratch, Shader};
use crate::warp::{sample_uniform_cone, sample_uniform_sphere, uniform_cone_pdf, Basis};
use crate::world::{BlockInfo, Material, World};

/// The dimensions of a sample the camera reads: `0, 1` the point of the
/// pixel, `2, 3` the point of the lens.
pub const CAMERA_DIMS: u32 = 4;

/// The dimensions each bounce reads, from `CAMERA_DIMS + bounce ·
/// DIMS_PER_BOUNCE` on, in the stratified pairs of the [`Sampler`]: the
/// direction towards an emitter (`+0, +1`), the direction scattered
/// (`+2, +3`), the emitter picked and the lobe picked (`+4, +5`), a
/// dielectric's choice and Russian roulette (`+6, +7`).
pub const DIMS_PER_BOUNCE: u32 = 8;

/// The first bounce after which Russian roulette may end a path.
pub const ROULETTE_DEPTH: u32 = 5;

/// Switches of the path integrator that change the noise of an image, not
/// its expectation (the tests compare images made with and without them).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PathOptions {
    /// Next-event estimation: light samples towards emissive blocks, combined
    /// with BSDF samples by multiple importance sampling. Without it, emissive
    /// blocks are found only by BSDF samples (point lights, which a BSDF
    /// sample cannot hit, are always sampled).
    pub next_event: bool,
    /// Russian roulette after [`ROULETTE_DEPTH`] bounces.
    pub roulette: bool,
}

impl Default for PathOptions {
    fn default() -> Self {
        PathOptions { next_event: true, roulette: true }
    }
}

/// An emissive block that light samples aim at: a sphere around it, whose
/// cone of directions is sampled uniformly (the exact solid angle of a
/// spherical emitter; for other shapes, directions that miss the block carry
/// no light).
#[derive(Clone, Copy, Debug)]
struct Emitter {
    block: BlockId,
    centre: Point3<f64>,
    radius: f64,
    /// The probability of picking this emitter.
    chance: f64,
    /// The probability of picking this emitter or one before it: the
    /// cumulative distribution a pick is looked up in.
    upto: f64,
}

impl Emitter {
    /// The density (per steradian, from `p`) of [`Emitter::sample`]'s
    /// directions, and whether `p` is inside the sphere (then every
    /// direction is sampled, uniformly).
    fn cone(&self, p: &Point3<f64>) -> (f64, Option<(Vector3<f64>, f64)>) {
        let to = self.centre - p;
        let d = to.norm();
        if d.is_nan() || d <= self.radius {
            return (1.0 / (4.0 * PI), None);
        }
        let sin2 = (self.radius / d).powi(2);
        let cos_max = (1.0 - sin2).max(0.0).sqrt();
        // 1 − cos θmax without cancellation for small cones.
        let one_minus = sin2 / (1.0 + cos_max);
        (1.0 / (2.0 * PI * one_minus), Some((to / d, cos_max)))
    }

    /// A direction from `p` towards the emitter and its density.
    fn sample(&self, p: &Point3<f64>, u: [f64; 2]) -> (Vector3<f64>, f64) {
        match self.cone(p) {
            (pdf, None) => (sample_uniform_sphere(u), pdf),
            (_, Some((axis, cos_max))) => {
                let w = Basis::from_z(axis).to_world(&sample_uniform_cone(u, cos_max));
                (w, uniform_cone_pdf(cos_max))
            }
        }
    }
}

/// The power heuristic with exponent 2 (Veach 1997): the weight of a sample
/// drawn with density `a` against a second strategy of density `b`.
fn power_heuristic(a: f64, b: f64) -> f64 {
    match (a.is_infinite(), b.is_infinite()) {
        (true, true) => return 0.5,
        (true, false) => return 1.0,
        (false, true) => return 0.0,
        (false, false) => {}
    }
    let m = a.max(b);
    if m.is_nan() || m <= 0.0 {
        return 0.0;
    }
    // Scaled, so that the squares neither overflow nor underflow.
    let (a, b) = (a / m, b / m);
    a * a / (a * a + b * b)
}

/// The most placed copies of emissive blocks of definitions that light
/// samples aim at (docs/rendering.md, "Light sampling").
pub const MAX_EMITTERS: usize = 1 << 16;

/// The path integrator of one world.
#[derive(Clone, Debug)]
pub struct PathTracer<'w> {
    shader: Shader<'w>,
    world: &'w World,
    /// Sorted by block.
    emitters: Vec<Emitter>,
    options: PathOptions,
    transparent: bool,
}

impl<'w> PathTracer<'w> {
    /// The integrator of `world`: finds its emissive blocks and the sphere
    /// each light sample aims at.
    pub fn new(world: &'w World, options: PathOptions) -> Self {
        let complex = &world.complex;
        let mut emitters = Vec::new();
        let power = |info: &BlockInfo| {
            let materials = std::iter::once(info.material).chain(info.solid_materials.iter().copied());
            materials.map(|m| world.materials()[m].emission.max()).fold(0.0, f64::max)
        };
        let emissive = |info: &BlockInfo| power(info) > 0.0 && power(info).is_finite();
        // Placed copies of emissive blocks are light samples only up to
        // `MAX_EMITTERS`; beyond, those of definitions are left to BSDF
        // samples (their light density is 0, so MIS gives BSDF samples the
        // full weight there and the estimate stays unbiased).
        let ids = world.select_blocks(|_, info| emissive(info), MAX_EMITTERS).unwrap_or_else(|| {
            let top = |info: &BlockInfo| info.path.starts_with("blocks");
            world.select_blocks(|_, info| top(info) && emissive(info), usize::MAX).unwrap_or_default()
        });
        for id in ids {
            let power = power(world.block_info(id));
            if let Some((centre, radius)) = bounding_sphere(world, id) {
                emitters.push(Emitter { block: id, centre, radius, chance: power * radius * radius, upto: 0.0 });
            }
        }
        let total: f64 = emitters.iter().map(|e| e.chance).sum();
        if !(total > 0.0 && total.is_finite()) {
            emitters.clear();
        }
        let mut upto = 0.0;
        for e in &mut emitters {
            e.chance /= total;
            upto += e.chance;
            e.upto = upto;
        }
        PathTracer { shader: Shader::new(world), world, emitters, options, transparent: complex.has_transparent() }
    }

    /// The Whitted shader of the same world (the primary hits of the AOVs).
    pub fn shader(&self) -> &Shader<'w> {
        &self.shader
    }

    /// The radiance arriving along `ray` (docs/model.md §5.10), estimated
    /// from the random numbers of `sampler`, and whether the ray hit a
    /// block.
    pub fn radiance(&self, ray: &Ray, sampler: &Sampler, scratch: &mut Scratch) -> (Rgb, bool) {
        let world = self.world;
        let max_depth = world.settings.max_depth;
        let background = Rgb::from(world.settings.background);
        let mut l = Rgb::zeros();
        let mut beta = Rgb::repeat(1.0);
        let mut ray = *ray;
        // The last scattering was a delta lobe (or there was none yet):
        // emission then has no light-sample counterpart.
        let mut delta = true;
        let mut last_pdf = 0.0;
        let mut last_point = ray.origin();
        let mut hit = false;
        // The product of the refractions' `(ηt/ηi)²`: Russian roulette reads
        // `β` without the radiance scaling of refraction.
        let mut eta_scale = 1.0;
        for bounce in 0..=max_depth + 1 {
            let Some(e) = self.shader.first_event(&ray, scratch) else {
                l += weigh(&beta, &background);
                break;
            };
            hit |= bounce == 0;
            let dir = ray.direction();
            let (material, n) = self.local(&e, &dir);
            if dir.dot(&e.normal) < 0.0 && !is_zero(&material.emission) {
                let w = if delta || !self.options.next_event {
                    1.0
                } else {
                    power_heuristic(last_pdf, self.light_pdf(e.block, &last_point))
                };
                l += weigh(&beta, &material.emission) * w;
            }
            if bounce > max_depth {
                break;
            }
            let eta = match (self.shader.ior(e.before), self.shader.ior(e.after)) {
                (Some(near), Some(far)) => Some(far / near),
                _ => None,
            };
            let lobes = Lobes::of(&material, eta);
            if lobes.is_empty() {
                break;
            }
            let basis = Basis::from_z(n);
            let wo = basis.to_local(&-dir);
            let surface = Surface { block: e.block, solid: e.solid };
            let mut spawner = world.complex.spawner_with_normal(surface, &e.point, &e.normal);
            let d = CAMERA_DIMS + bounce * DIMS_PER_BOUNCE;
            let [pick_emitter, pick_lobe] = sampler.uniform2(d + 4);
            let [choice, roulette] = sampler.uniform2(d + 6);
            if lobes.has_glossy() {
                let light = (pick_emitter, sampler.uniform2(d));
                let direct = self.direct(&e, &lobes, &basis, &wo, &mut spawner, light, scratch);
                l += weigh(&beta, &direct);
            }
            let Some(s) = lobes.sample(&wo, pick_lobe, sampler.uniform2(d + 2), choice) else {
                break;
            };
            beta = weigh(&beta, &s.weight);
            eta_scale *= s.eta_scale;
            if is_zero(&beta) || !beta.iter().all(|c| c.is_finite()) {
                break;
            }
            let Ok(next) = spawner.unit_ray(&basis.to_world(&s.wi)) else { break };
            (delta, last_pdf, last_point, ray) = (s.delta, s.pdf, e.point, next);
            if self.options.roulette && bounce + 1 >= ROULETTE_DEPTH {
                // Survive with probability `1 − q`, weighted by `1/(1 − q)`: unbiased.
                let q = (1.0 - (beta * eta_scale).max()).max(0.0);
                if roulette < q {
                    break;
                }
                beta /= 1.0 - q;
            }
        }
        (l, hit)
    }

    /// The material at the event's point (its textures evaluated in the
    /// block's frame) and the shading normal facing the ray (bumped).
    fn local(&self, e: &Event, dir: &Vector3<f64>) -> (Cow<'w, Material>, Vector3<f64>) {
        let world = self.world;
        let material = world.surface_material(e.block, e.solid);
        let mut n = facing_normal(&e.normal, dir);
        let (Some(t), Some(frame)) = (material.textures.as_deref(), world.frame(e.block)) else {
            return (Cow::Borrowed(material), n);
        };
        let p = frame.apply_point(&e.point);
        if let Some(bump) = &t.bump {
            let bumped = bump.normal(&p, &n, frame.linear());
            if bumped.dot(dir) < 0.0 {
                n = bumped;
            }
        }
        (Cow::Owned(material.at(&p)), n)
    }

    /// The density with which a light sample from `from` reaches block
    /// `block` (0 for blocks light samples do not aim at).
    fn light_pdf(&self, block: BlockId, from: &Point3<f64>) -> f64 {
        match self.emitters.binary_search_by_key(&block, |e| e.block) {
            Ok(k) => self.emitters[k].chance * self.emitters[k].cone(from).0,
            Err(_) => 0.0,
        }
    }

    /// Light arriving directly at the event's point and scattered towards
    /// `wo`: from every point light, and from one emitter picked at random
    /// (by `pick`, its direction by `u`), weighted against BSDF sampling.
    #[allow(clippy::too_many_arguments)]
    fn direct(
        &self,
        e: &Event,
        lobes: &Lobes,
        basis: &Basis,
        wo: &Vector3<f64>,
        spawner: &mut Spawner,
        (pick, u): (f64, [f64; 2]),
        scratch: &mut Scratch,
    ) -> Rgb {
        let mut l = Rgb::zeros();
        for light in &self.world.lights {
            let to = light.position - e.point;
            let dist = to.norm();
            if !(dist > 0.0 && dist.is_finite()) {
                continue;
            }
            let w = to / dist;
            let wi = basis.to_local(&w);
            let f = lobes.eval(wo, &wi);
            if is_zero(&f) || !self.visible(spawner, &w, dist, scratch) {
                continue;
            }
            l += weigh(&f, &light.diffuse) * (wi.z.abs() / (dist * dist));
        }
        if !self.options.next_event || self.emitters.is_empty() {
            return l;
        }
        // Binary search of the cumulative distribution (the last emitter
        // takes what rounding leaves above its `upto`).
        let k = self.emitters.partition_point(|em| em.upto <= pick).min(self.emitters.len() - 1);
        let emitter = &self.emitters[k];
        let (w, pdf) = emitter.sample(&e.point, u);
        let light_pdf = emitter.chance * pdf;
        let wi = basis.to_local(&w);
        let f = lobes.eval(wo, &wi);
        if is_zero(&f) || light_pdf.is_nan() || light_pdf <= 0.0 {
            return l;
        }
        let Ok(ray) = spawner.unit_ray(&w) else { return l };
        let Some(h) = self.shader.first_event(&ray, scratch) else { return l };
        if h.block != emitter.block || w.dot(&h.normal) >= 0.0 {
            return l;
        }
        let (material, _) = self.local(&h, &w);
        if is_zero(&material.emission) {
            return l;
        }
        let mis = power_heuristic(light_pdf, lobes.pdf(wo, &wi));
        l + weigh(&f, &material.emission) * (wi.z.abs() * mis / light_pdf)
    }

    /// Whether nothing stands between the spawner's point and the point
    /// `dist` away along `w` (a transparent block blocks too: light crosses
    /// glass only along BSDF samples, which refract it).
    fn visible(&self, spawner: &mut Spawner, w: &Vector3<f64>, dist: f64, scratch: &mut Scratch) -> bool {
        if !self.world.settings.shadows {
            return true;
        }
        let Ok(ray) = spawner.unit_ray(w) else { return true };
        if !self.transparent {
            scratch.rays += 1;
            return !self.world.complex.occluded_with(&ray, dist, &mut scratch.path_occluder);
        }
        self.shader.first_event(&ray, scratch).is_none_or(|h| h.t >= dist)
    }
}

/// A sphere around block `id` (its centre and radius): the smallest of the
/// sphere around its box and the spheres around its ellipsoids; `None` if
/// the block is unbounded.
fn bounding_sphere(world: &World, id: BlockId) -> Option<(Point3<f64>, f64)> {
    let aabb = world.complex.block_aabb(id);
    let mut best = aabb.center().map(|c| (c, aabb.size().norm() / 2.0)).filter(|(_, r)| r.is_finite());
    // A placed block's solids are in its definition's frame: a sphere there
    // maps to one around the placed copy with the radius scaled by the
    // largest stretch of the placement (its linear part's spectral norm).
    let resolved = world.complex.resolve(id);
    let to_world = |(c, r): (Point3<f64>, f64)| match &resolved.to_world {
        None => (c, r),
        Some(t) => {
            let stretch = SymmetricEigen::new(t.linear().transpose() * t.linear()).eigenvalues.max().sqrt();
            (t.apply_point(&c), r * stretch * (1.0 + 1e-12))
        }
    };
    for solid in resolved.block.solids() {
        let Solid::Quadric(q) = solid else { continue };
        if !q.is_finite() {
            continue;
        }
        let m = q.matrix();
        let a = m.fixed_view::<3, 3>(0, 0).into_owned();
        let b = m.fixed_view::<3, 1>(0, 3).into_owned();
        let (Some(inverse), c) = (a.try_inverse(), m[(3, 3)]) else { continue };
        let centre = -(inverse * b);
        let level = -(c + b.dot(&centre));
        let lowest = SymmetricEigen::new(a).eigenvalues.min();
        let radius = (level / lowest).sqrt();
        let (centre, radius) = to_world((Point3::from(centre), radius));
        if radius.is_finite() && radius > 0.0 && best.is_none_or(|(_, r)| radius < r) {
            best = Some((centre, radius));
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The cone's density integrates to one over the directions it
    /// samples: its solid angle is `2π(1 − cos θmax)`, checked against the
    /// area formula of a spherical cap seen from distance `d`.
    #[test]
    fn the_cone_density_is_one_over_the_spheres_solid_angle() {
        let e = Emitter { block: BlockId(0), centre: Point3::new(0.0, 0.0, 10.0), radius: 2.0, chance: 1.0, upto: 1.0 };
        let (pdf, cone) = e.cone(&Point3::origin());
        let (axis, cos_max) = cone.expect("the origin is outside the sphere");
        assert_eq!(axis, Vector3::z());
        let solid_angle = 2.0 * PI * (1.0 - (1.0f64 - 0.04).sqrt());
        assert!((pdf * solid_angle - 1.0).abs() < 1e-12);
        assert!((cos_max - 0.96f64.sqrt()).abs() < 1e-15);
        let (inside, none) = e.cone(&Point3::new(0.5, 0.0, 10.0));
        assert!(none.is_none() && (inside - 1.0 / (4.0 * PI)).abs() < 1e-18);
    }

    #[test]
    fn the_power_heuristic_weights_sum_to_one() {
        for (a, b) in [(1.0, 1.0), (0.3, 7.0), (1e-300, 1e-300), (0.0, 2.0), (1e200, 1e200), (f64::INFINITY, 3.0)] {
            let sum = power_heuristic(a, b) + power_heuristic(b, a);
            assert!((sum - 1.0).abs() < 1e-12, "{a} {b}: {sum}");
        }
        assert!((power_heuristic(0.3, 7.0) - 0.09 / (0.09 + 49.0)).abs() < 1e-17);
        assert_eq!(power_heuristic(0.0, 0.0), 0.0);
    }
}
