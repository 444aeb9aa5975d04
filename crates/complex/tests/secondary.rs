//! Secondary rays from `Complex::spawn_ray` on a stress set, judged by an
//! independent oracle: the medium (empty, opaque, or a transparent
//! material) at double points along the spawned ray, each decided by the
//! exact sign of every solid's `f` (the `reference` crate's dyadic
//! arithmetic) and the priority rule. The complexes use ε = 0, so nothing
//! but the spawned origin keeps a ray from its own surface.
//!
//! For every hit of a primary ray and every spawned direction (mirror,
//! straight through, tangent ± 10⁻³ … 10⁻¹² of the normal, random), with
//! `m₀` the exact medium just off the hit point on the side the ray leaves on:
//! - *wrong side*: the medium at the spawned origin is not `m₀`;
//! - *self-intersection* (spurious hit): `cast_ray` reports a hit at a `t`
//!   where the exact ray does not cross the reported surface (within a
//!   tolerance for grazing roots);
//! - *missed surface*: the medium changes at a sample before the reported
//!   hit (or anywhere, if none is reported).
//!
//! Stress set: a ball, a pair of slabs `10⁻⁹` thick sharing a plane as
//! `+q`/`-q`, a glass ball inside a glass shell that is its `-Q`, nested
//! transparent balls, rotated quadrics; each at 1, 10³, 10⁶ and 10⁹ from the
//! origin (slabs thicken to `10⁻⁹ ×` the distance, which keeps them 10⁷ ulps
//! thick). Rays starting at the raw hit point are judged too: they must
//! fail, or the oracle would be blind.

use complex::{Block, BlockId, Complex, ComplexOptions, Hit, MaterialKey, Opacity};
use quadric::nalgebra::{Point3, Vector3};
use quadric::{Quadric, Ray, Solid, Transform};
use reference::{ExactQuadric, Rng};

use crate::common::*;

/// What fills a point: nothing, opaque matter, or a transparent material.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Medium {
    Empty,
    Opaque,
    Glass(u32),
}

/// A complex with its exact reference.
struct Stress {
    name: String,
    complex: Complex,
    exact: Vec<(Vec<ExactQuadric>, Opacity, u32)>,
    /// Where the scene sits, and its size.
    centre: Vector3<f64>,
    size: f64,
    /// The camera, relative to the centre in units of `size`.
    camera: Vector3<f64>,
    /// The first sample along a spawned ray: far above rounding, below any gap.
    h: f64,
    /// How far off the hit point the medium of a side is read: about 100
    /// ulps of the coordinates, so that edges rarely come between.
    probe: f64,
}

impl Stress {
    fn new(name: &str, blocks: Vec<(Vec<Solid>, Opacity, u32)>, at: f64, size: f64) -> Stress {
        let centre = Vector3::new(0.6, 0.64, -0.48) * at;
        let m = Transform::translate(centre).expect("finite");
        let blocks: Vec<_> = blocks.into_iter().map(|(s, o, k)| (moved(&s, &m), o, k)).collect();
        let exact = blocks.iter().map(|(s, o, k)| (s.iter().map(ExactQuadric::solid).collect(), *o, *k)).collect();
        let built = blocks.into_iter().map(|(s, o, k)| Block::new("b", s, o, MaterialKey(k)).expect("valid")).collect();
        let complex = Complex::new(built, ComplexOptions { epsilon: Some(0.0), ..Default::default() }).expect("valid");
        let (h, probe) = (1e-12 * at.max(1.0), 1e-14 * at.max(1.0));
        let camera = Vector3::new(0.3, 0.5, 6.0);
        Stress { name: format!("{name} at {at:e}"), complex, exact, centre, size, camera, h, probe }
    }

    fn seen_from(self, camera: Vector3<f64>) -> Stress {
        Stress { camera, ..self }
    }

    /// How far off the hit point the medium of a side is read: `probe` past
    /// the true surface (the hit point's exact distance from it added).
    fn off_surface(&self, hit: &Hit) -> f64 {
        let x = [hit.point.x, hit.point.y, hit.point.z];
        let d = self.exact[hit.block.index()].0[hit.solid as usize].distance_f64(x).unwrap_or(0.0);
        d + self.probe
    }

    /// Whether any solid's surface crosses the ray in `(0, t]` (exactly).
    fn crossed_before(&self, ray: &Ray, t: f64) -> bool {
        let crossings = |s: &ExactQuadric| s.solve(ray).crossings().iter().any(|l| l.signum() > 0 && l.to_f64() <= t);
        self.exact.iter().flat_map(|(solids, _, _)| solids).any(crossings)
    }

    /// The exact medium at a double point (priority rule of docs/model.md §3.4).
    fn medium(&self, x: &Point3<f64>) -> Medium {
        let x = [x.x, x.y, x.z];
        let mut glass = None;
        for (solids, opacity, material) in &self.exact {
            if solids.iter().all(|s| s.value(x).signum() <= 0) {
                match opacity {
                    Opacity::Opaque => return Medium::Opaque,
                    Opacity::Transparent => {
                        glass.get_or_insert(Medium::Glass(*material));
                    }
                }
            }
        }
        glass.unwrap_or(Medium::Empty)
    }
}

/// Failures of one way of spawning over a stress scene.
#[derive(Default, Debug)]
struct Tally {
    rays: usize,
    wrong_side: usize,
    self_hits: usize,
    misses: usize,
    /// The first few failures, for the message.
    examples: Vec<String>,
}

impl Tally {
    fn failures(&self) -> usize {
        self.wrong_side + self.self_hits + self.misses
    }

    fn note(&mut self, what: &str, scene: &Stress, ray: &Ray, detail: String) {
        if self.examples.len() < 4 {
            self.examples.push(format!("{what} in {}: {ray:?} {detail}", scene.name));
        }
    }
}

/// How far from an exact crossing a reported hit may lie and still be that
/// crossing: grazing rays have roots with large errors along the ray.
fn tolerance(scene: &Stress, t: f64) -> f64 {
    1e-2 * t + scene.h
}

/// Judges one spawned ray that should start in medium `m0`.
fn judge(scene: &Stress, ray: &Ray, m0: Medium, tally: &mut Tally) {
    tally.rays += 1;
    let start = scene.medium(&ray.origin());
    if start != m0 {
        tally.wrong_side += 1;
        tally.note("wrong side", scene, ray, format!("origin in {start:?}, want {m0:?}"));
        return;
    }
    let hit = scene.complex.cast_ray(ray, f64::INFINITY);
    if let Some(hit) = &hit {
        // The surface reported must really cross the ray there (exactly).
        let exact = &scene.exact[hit.block.index()].0[hit.solid as usize];
        let solved = exact.solve(ray);
        let near = solved.crossings().iter().any(|l| (l.to_f64() - hit.t).abs() <= tolerance(scene, hit.t));
        if !near {
            tally.self_hits += 1;
            tally.note(
                "spurious hit",
                scene,
                ray,
                format!("at t = {:e} on {:?} solid {}", hit.t, hit.block, hit.solid),
            );
            return;
        }
    }
    // Samples from `h` out past the scene, a factor √2 apart, up to the hit.
    let end = hit.map_or(16.0 * scene.size, |hit| hit.t - tolerance(scene, hit.t));
    let mut t = scene.h;
    while t < end {
        let m = scene.medium(&ray.at(t));
        // A sample is rounded to doubles, off the line by up to an ulp of its
        // coordinates: it counts only if some surface really crosses the ray
        // before it (exactly), else a grazing ray's sample may fall outside.
        if m != m0 && scene.crossed_before(ray, t) {
            tally.misses += 1;
            tally.note("missed surface", scene, ray, format!("{m:?} at t = {t:e}, reported {:?}", hit.map(|h| h.t)));
            return;
        }
        t *= core::f64::consts::SQRT_2;
    }
}

/// The directions spawned at a hit with outward normal `n` of a ray along `r`.
fn directions(r: &Vector3<f64>, n: &Vector3<f64>, rng: &mut Rng) -> Vec<Vector3<f64>> {
    let mirror = r - 2.0 * r.dot(n) * n;
    let tangent = (r - r.dot(n) * n).try_normalize(0.0).unwrap_or_else(|| n.cross(&Vector3::x()).normalize());
    let mut out = vec![mirror, *r];
    for k in [3, 6, 9, 12] {
        let tilt = 10f64.powi(-k);
        out.push(tangent + tilt * n);
        out.push(tangent - tilt * n);
    }
    for _ in 0..2 {
        out.push(Vector3::from(rng.direction()));
    }
    out
}

/// Spawns rays at the first hits of `primaries` rays into `scene`, by
/// `spawn`, and tallies the failures.
fn run(
    scene: &Stress,
    primaries: usize,
    seed: u64,
    spawn: impl Fn(&Complex, &Hit, &Vector3<f64>) -> Option<Ray>,
) -> Tally {
    let mut rng = Rng::new(seed);
    let mut tally = Tally::default();
    let camera = Point3::from(scene.centre + scene.camera * scene.size);
    for _ in 0..primaries {
        let target = Point3::from(scene.centre + Vector3::from(rng.in_ball(1.1 * scene.size)));
        let Ok(primary) = Ray::new(camera, target - camera) else { continue };
        // The first hit, then (for transparent scenes) one more along the ray.
        let mut ray = primary;
        for _ in 0..2 {
            let Some(hit) = scene.complex.cast_ray(&ray, f64::INFINITY) else { break };
            let n = hit.normal;
            if n == Vector3::zeros() {
                break;
            }
            for dir in directions(&ray.direction(), &n, &mut rng) {
                let sigma = dir.dot(&n).signum();
                let m0 = scene.medium(&(hit.point + sigma * scene.off_surface(&hit) * n));
                if let Some(s) = spawn(&scene.complex, &hit, &dir) {
                    judge(scene, &s, m0, &mut tally);
                }
            }
            match hit.spawn_ray(&scene.complex, &ray.direction()) {
                Ok(next) => ray = next,
                Err(_) => break,
            }
        }
    }
    tally
}

const OPAQUE: Opacity = Opacity::Opaque;
const GLASS: Opacity = Opacity::Transparent;

fn ball(r: f64) -> Solid {
    Solid::from(Quadric::sphere().transformed(&Transform::scale(r).expect("finite")))
}

/// The one-sheet hyperboloid with its waist at radius 0.8: it meets the unit
/// cylinder transversally (at radius 1 the two would touch along a circle,
/// a tangency no probe distance can resolve).
fn waisted() -> Solid {
    Solid::from(Quadric::hyperboloid_one_sheet().transformed(&Transform::scale(0.8).expect("finite")))
}

fn turned(s: Solid) -> Solid {
    let m = Transform::rotate_x_degrees(30.0).and_then(|a| Ok(a.then(&Transform::rotate_z_degrees(70.0)?)));
    s.transformed(&m.expect("valid"))
}

/// The stress scenes at distance `at` from the origin.
fn scenes(at: f64) -> Vec<Stress> {
    let thin = 1e-9 * at.max(1.0);
    let cube = |r: f64| cuboid([-r; 3], [r; 3]);
    let with = |mut a: Vec<Solid>, b: Vec<Solid>| {
        a.extend(b);
        a
    };
    let q = ball(1.0);
    vec![
        Stress::new("opaque ball", vec![(vec![q], OPAQUE, 0)], at, 1.0),
        Stress::new(
            "slabs 1e-9 thick sharing a plane as +q/-q",
            vec![
                (with(vec![hs(0.0, 1.0, 0.0, -thin), hs(0.0, -1.0, 0.0, 0.0)], cube(1.0)), GLASS, 1),
                (with(vec![hs(0.0, -1.0, 0.0, -thin), hs(0.0, 1.0, 0.0, 0.0)], cube(1.0)), OPAQUE, 0),
                (with(vec![hs(0.0, 1.0, 0.0, -3.0 * thin), hs(0.0, -1.0, 0.0, 2.0 * thin)], cube(1.0)), GLASS, 2),
            ],
            at,
            1.0,
        )
        .seen_from(Vector3::new(0.3, 4.0, 3.0)),
        Stress::new(
            "glass ball in a glass shell made of its -Q, opaque core",
            vec![
                (vec![turned(ball(0.3))], OPAQUE, 0),
                (vec![q], GLASS, 1),
                (vec![q.complement(), ball(2.0)], GLASS, 2),
            ],
            at,
            2.0,
        ),
        Stress::new(
            "nested transparent balls",
            vec![(vec![ball(1.0)], GLASS, 1), (vec![ball(1.5)], GLASS, 2), (vec![ball(2.0)], GLASS, 1)],
            at,
            2.0,
        ),
        Stress::new(
            "rotated cylinder, hyperboloid, paraboloid",
            vec![
                (with(vec![turned(Solid::from(Quadric::tube_y()))], cube(1.0)), OPAQUE, 0),
                (vec![turned(waisted()), ball(1.8)], GLASS, 1),
                (with(vec![Solid::from(Quadric::paraboloid())], cube(1.9)), GLASS, 2),
            ],
            at,
            2.0,
        ),
    ]
}

const DISTANCES: [f64; 4] = [1.0, 1e3, 1e6, 1e9];

#[test]
fn spawned_rays_never_hit_their_own_surface_nor_miss_a_near_one() {
    let mut total = Tally::default();
    for (i, at) in DISTANCES.into_iter().enumerate() {
        for scene in scenes(at) {
            let t = run(&scene, 24, 0x5ec0_0000 + i as u64, |c, hit, dir| hit.spawn_ray(c, dir).ok());
            total.rays += t.rays;
            total.wrong_side += t.wrong_side;
            total.self_hits += t.self_hits;
            total.misses += t.misses;
            total.examples.extend(t.examples);
            eprintln!(
                "{}: {} rays, {} wrong side, {} spurious, {} missed",
                scene.name, t.rays, t.wrong_side, t.self_hits, t.misses
            );
        }
    }
    assert!(total.rays > 3000, "too few rays judged: {}", total.rays);
    assert_eq!(total.failures(), 0, "{total:#?}");
}

#[test]
fn a_spawner_given_the_hit_normal_spawns_the_same_rays() {
    let compared = core::cell::Cell::new(0);
    for (i, at) in DISTANCES.into_iter().enumerate() {
        for scene in scenes(at) {
            // Compares the rays of `spawn_ray` and of a spawner given the
            // normal; nothing is returned, so `run` judges nothing.
            run(&scene, 12, 0x5ec0_1000 + i as u64, |c, hit, dir| {
                let want = hit.spawn_ray(c, dir);
                for n in [hit.normal, -hit.normal] {
                    let got = c.spawner_with_normal(hit.surface(), &hit.point, &n).ray(dir);
                    assert_eq!(got, want, "{}: normal {n:?}, direction {dir:?}", scene.name);
                    compared.set(compared.get() + 1);
                }
                None
            });
        }
    }
    assert!(compared.get() > 1000, "too few rays compared: {}", compared.get());
}

#[test]
fn unit_rays_leave_from_the_same_origins_and_pass_the_same_oracle() {
    // `Spawner::unit_ray` (the shadow rays' constructor) along a normalised
    // direction: `spawn_ray`'s origin, the direction kept bit for bit, and
    // no self-intersection, at every distance from the world origin.
    let mut total = Tally::default();
    for (i, at) in DISTANCES.into_iter().enumerate() {
        for scene in scenes(at) {
            let t = run(&scene, 12, 0x5ec0_2000 + i as u64, |c, hit, dir| {
                let unit = dir / dir.norm();
                let got = c.spawner_with_normal(hit.surface(), &hit.point, &hit.normal).unit_ray(&unit).ok()?;
                let want = hit.spawn_ray(c, &unit).ok()?;
                assert_eq!(got.origin(), want.origin(), "{}: direction {unit:?}", scene.name);
                assert_eq!(got.direction(), unit, "{}", scene.name);
                Some(got)
            });
            total.rays += t.rays;
            total.wrong_side += t.wrong_side;
            total.self_hits += t.self_hits;
            total.misses += t.misses;
            total.examples.extend(t.examples);
        }
    }
    assert!(total.rays > 1500, "too few rays judged: {}", total.rays);
    assert_eq!(total.failures(), 0, "{total:#?}");
}

#[test]
fn rays_from_the_raw_hit_point_fail_the_same_oracle() {
    // The control: the same harness must catch the acne `spawn_ray` removes.
    let mut failures = 0;
    for at in DISTANCES {
        for scene in scenes(at) {
            failures += run(&scene, 8, 0x5ec1, |_, hit, dir| Ray::new(hit.point, *dir).ok()).failures();
        }
    }
    assert!(failures > 0, "the oracle saw no self-intersection from raw hit points");
}

#[test]
fn spawning_keeps_the_block_and_side_for_shared_surfaces() {
    // A glass ball and the shell made of its complement: a ray spawned into
    // the shell from the ball's surface starts inside the shell, and back.
    let s = Stress::new(
        "±Q",
        vec![(vec![ball(1.0)], GLASS, 1), (vec![ball(1.0).complement(), ball(2.0)], GLASS, 2)],
        1e9,
        2.0,
    );
    let ray = Ray::new(Point3::from(s.centre + Vector3::new(-0.1, 0.2, -5.0)), Vector3::z()).expect("valid");
    let hit = s.complex.cast_ray(&ray, f64::INFINITY).expect("the shell");
    assert_eq!(hit.block, BlockId(1));
    let inward = hit.spawn_ray(&s.complex, &ray.direction()).expect("valid");
    assert_eq!(s.medium(&inward.origin()), Medium::Glass(2));
    let into_ball = s.complex.cast_ray(&inward, f64::INFINITY).expect("the ball");
    let back = into_ball.spawn_ray(&s.complex, &-ray.direction()).expect("valid");
    assert_eq!(s.medium(&back.origin()), Medium::Glass(2));
    let forward = into_ball.spawn_ray(&s.complex, &ray.direction()).expect("valid");
    assert_eq!(s.medium(&forward.origin()), Medium::Glass(1));
}
