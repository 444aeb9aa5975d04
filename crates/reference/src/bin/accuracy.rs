//! The accuracy benchmark: run time against error for each precision mode of
//! the kernel and for the textbook root formula POV-Ray uses, on the same
//! rays, judged by the exact reference. Prints the tables of
//! `docs/accuracy.md` and draws `docs/accuracy-time-error.png`.
//!
//! ```text
//! cargo run --release -p reference --features bench --bin accuracy [-- --quick] [--png PATH]
//! ```
//!
//! `-- --secondary [--fast]` runs only the secondary-ray count (with
//! `ACCURACY_VERBOSE=1` it prints every failure): a diagnostic.
//!
//! Rows: `Fast`, `Accurate` (the default) and `Certified` of
//! [`quadric::Precision`], and *textbook*: world-space coefficients,
//! `(-t ± √(t² - su)) / s`, hits closer than `1e-4` ignored and objects
//! beyond `1e7` dropped (POV-Ray 3.7's `MIN_ISECT_DEPTH` and
//! `MAX_DISTANCE`). Measured in one run, with fixed seeds:
//! - kernel time: ns per ray–solid call on the stress rays (the same rays
//!   the errors are measured on), best of interleaved rounds;
//! - render time: rays per second (primary, shadow, reflected, refracted)
//!   rendering `scenes/*.json` and `scenes/bench/*.json` single-threaded
//!   with the kernel in that mode (the textbook formula is not a kernel
//!   mode: no figure);
//! - hit-point error: distance from the true surface in ulps of the exact
//!   hit point's coordinates and in units of the solid's size; `λ`'s
//!   relative error; false hits and misses binned by how close the ray's
//!   line comes to tangency (in ulps of the solid's own coordinates);
//! - on the secondary-ray stress scenes (`crates/complex/tests/secondary.rs`,
//!   ε = 0): ownership errors of the partition (segments whose owner is not
//!   the exact owner at their midpoint) and the self-intersection and
//!   missed-surface rates of spawned rays (`Complex::spawn_ray`; for the
//!   textbook row, rays from the raw hit point with POV-Ray's `1e-4`).

use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::time::Instant;

use complex::{Block, Complex, ComplexOptions, Hit, MaterialKey, Opacity};
use quadric::nalgebra::{Point3, Vector3};
use quadric::{Bound, HalfSpace, IntervalSet, Precision, Quadric, Ray, Solid, Transform};
use reference::{computed_crossings, median_max, other_shapes, unit_sphere, ExactQuadric, Judge, Rng, Scene, Tally};

const SEED: u64 = 0x6163_6375_7261_6379;
const DISTANCES: [f64; 4] = [1.0, 1e3, 1e6, 1e9];
const CAMERA: f64 = 0.25;
/// POV-Ray 3.7: `MIN_ISECT_DEPTH` and `MAX_DISTANCE`.
const POV_MIN_DEPTH: f64 = 1e-4;
const POV_MAX_DISTANCE: f64 = 1e7;
/// Tangency bins, in ulps of the solid's own coordinates at the apex.
const BINS: [f64; 4] = [4.0, 1e4, 1e8, f64::INFINITY];
const BIN_NAMES: [&str; 4] = ["< 4", "4 … 1e4", "1e4 … 1e8", "> 1e8"];

#[derive(Clone, Copy, PartialEq)]
enum Mode {
    Kernel(Precision),
    Textbook,
}

const MODES: [Mode; 4] = [
    Mode::Kernel(Precision::Fast),
    Mode::Kernel(Precision::Accurate),
    Mode::Kernel(Precision::Certified),
    Mode::Textbook,
];

impl Mode {
    fn name(self) -> &'static str {
        match self {
            Mode::Kernel(Precision::Fast) => "Fast",
            Mode::Kernel(Precision::Accurate) => "Accurate (default)",
            Mode::Kernel(Precision::Certified) => "Certified",
            Mode::Kernel(_) => "other",
            Mode::Textbook => "textbook (POV-Ray)",
        }
    }
}

// ---------------------------------------------------------------------------
// The textbook kernel.

/// A solid as its ten world-space coefficients, the way POV-Ray's `quadric`
/// sees it.
#[derive(Clone, Copy)]
struct Textbook {
    a: [[f64; 3]; 3],
    w: [f64; 3],
    k: f64,
}

impl Textbook {
    fn new(scene: &Scene) -> Textbook {
        let [a, b, c, d, e, f, g, h, j, k] = scene.world_coefficients();
        Textbook { a: [[a, d, e], [d, b, f], [e, f, c]], w: [g, h, j], k }
    }

    /// `(-t ± √(t² - su)) / s` from world coefficients; crossings closer than
    /// `1e-4` or beyond `1e7` are no crossings (the set is clipped there).
    #[inline(never)]
    fn intervals(&self, ray: &Ray) -> IntervalSet {
        let (p, r) = (ray.origin(), ray.direction());
        let (p, r) = ([p.x, p.y, p.z], [r.x, r.y, r.z]);
        let row = |i: usize, v: [f64; 3]| self.a[i][0] * v[0] + self.a[i][1] * v[1] + self.a[i][2] * v[2];
        let ar = [row(0, r), row(1, r), row(2, r)];
        let g = [row(0, p) + self.w[0], row(1, p) + self.w[1], row(2, p) + self.w[2]];
        let s = r[0] * ar[0] + r[1] * ar[1] + r[2] * ar[2];
        let t = r[0] * g[0] + r[1] * g[1] + r[2] * g[2];
        let u = p[0] * (g[0] + self.w[0]) + p[1] * (g[1] + self.w[1]) + p[2] * (g[2] + self.w[2]) + self.k;
        let inside = u <= 0.0;
        let (l1, l2) = if s == 0.0 {
            if t == 0.0 {
                return if inside { whole() } else { IntervalSet::empty() };
            }
            let root = -u / (2.0 * t);
            if t > 0.0 {
                (f64::NEG_INFINITY, root)
            } else {
                (root, f64::INFINITY)
            }
        } else {
            let disc = t * t - s * u;
            if disc < 0.0 {
                return if s > 0.0 { IntervalSet::empty() } else { whole() };
            }
            let root = disc.sqrt();
            let (a, b) = ((-t - root) / s, (-t + root) / s);
            (a.min(b), a.max(b))
        };
        // POV-Ray keeps a crossing only in `[1e-4, 1e7]`; the inside/outside
        // state between crossings follows from the sign of `s` (convex
        // pieces for `s > 0`, the two outer pieces for `s < 0`).
        let keep = |l: f64| (POV_MIN_DEPTH..=POV_MAX_DISTANCE).contains(&l);
        let clip = |lo: f64, hi: f64| -> IntervalSet {
            let lo_b = if keep(lo) { Bound::new(lo, 0) } else { Bound::free(lo.clamp(0.0, POV_MAX_DISTANCE)) };
            let hi_b = if keep(hi) { Bound::new(hi, 0) } else { Bound::free(hi.clamp(0.0, f64::INFINITY)) };
            if hi_b.t <= lo_b.t || lo > POV_MAX_DISTANCE {
                IntervalSet::empty()
            } else {
                IntervalSet::from_interval(lo_b, hi_b)
            }
        };
        if s >= 0.0 {
            clip(l1, l2)
        } else {
            clip(f64::NEG_INFINITY, l1).union(&clip(l2, f64::INFINITY)).unwrap_or_else(|_| whole())
        }
    }
}

fn whole() -> IntervalSet {
    IntervalSet::from_interval(Bound::free(0.0), Bound::free(f64::INFINITY))
}

fn solve(mode: Mode, scene: &Scene, textbook: &Textbook, ray: &Ray) -> IntervalSet {
    match mode {
        Mode::Kernel(p) => scene.solid.intervals_with(ray, 0, p),
        Mode::Textbook => textbook.intervals(ray),
    }
}

// ---------------------------------------------------------------------------
// Errors of single solids on the stress rays.

#[derive(Default)]
struct ModeErrors {
    tally: Tally,
    /// Per tangency bin: rays, false hits, false misses.
    bins: [(usize, usize, usize); 4],
    /// ns per call, best round.
    ns: f64,
}

struct StressSet {
    scene: Scene,
    textbook: Textbook,
    rays: Vec<Ray>,
}

fn stress_sets(quick: bool) -> Vec<StressSet> {
    let mut rng = Rng::new(SEED);
    let mut shapes = vec![unit_sphere()];
    shapes.extend(other_shapes());
    let mut out = Vec::new();
    for shape in &shapes {
        for d in DISTANCES {
            let scene = Scene::new(shape, d, &mut rng);
            let n = if quick { 200 } else { 1500 };
            let rays = scene.rays(shape, CAMERA * d.min(1.0), n, &mut rng);
            out.push(StressSet { textbook: Textbook::new(&scene), scene, rays });
        }
    }
    out
}

/// How close the ray's line comes to tangency, in ulps of the solid's own
/// coordinates at the apex (or of the start point, if that is closer).
fn gap_ulps(set: &StressSet, ray: &Ray, exact: &reference::ExactRay) -> f64 {
    let scene = &set.scene;
    let gap = scene.apex_gap_ulps(ray, exact);
    let p = ray.origin();
    let p = [p.x, p.y, p.z];
    gap.min(scene.exact.distance_f64(p).map_or(f64::INFINITY, |d| d / scene.local_ulp(p)))
}

fn measure_errors(sets: &[StressSet]) -> (Vec<ModeErrors>, Tally) {
    let judge = Judge { band_ulps: BINS[0] };
    let mut out: Vec<ModeErrors> = MODES.iter().map(|_| ModeErrors::default()).collect();
    let mut floor = Tally::default();
    for set in sets {
        for ray in &set.rays {
            let exact = set.scene.exact.solve(ray);
            floor.add_floor(&set.scene, ray, &exact);
            let bin = BINS.iter().position(|b| gap_ulps(set, ray, &exact) < *b).unwrap_or(3);
            let want = exact.crossings().len();
            for (m, e) in MODES.iter().zip(out.iter_mut()) {
                let got = solve(*m, &set.scene, &set.textbook, ray);
                // The point each row reports: `Solid::hit_point` (refined
                // onto the surface, as `complex::Hit::point`) for Accurate
                // and Certified; `p + λr` for Fast and the textbook formula.
                let refined = matches!(m, Mode::Kernel(Precision::Accurate | Precision::Certified));
                let point = |t| if refined { set.scene.solid.hit_point(ray, t) } else { ray.at(t) };
                e.tally.add_with_points(&set.scene, ray, &exact, &got, &judge, point);
                let n = computed_crossings(&got).len();
                let b = &mut e.bins[bin];
                b.0 += 1;
                b.1 += usize::from(n > want);
                b.2 += usize::from(n < want);
            }
        }
    }
    (out, floor)
}

fn measure_kernel_time(sets: &[StressSet], errors: &mut [ModeErrors], rounds: usize) {
    for e in errors.iter_mut() {
        e.ns = f64::INFINITY;
    }
    for _ in 0..rounds {
        for (m, e) in MODES.iter().zip(errors.iter_mut()) {
            let mut calls = 0usize;
            let start = Instant::now();
            for set in sets {
                for ray in &set.rays {
                    black_box(solve(*m, &set.scene, &set.textbook, black_box(ray)));
                    calls += 1;
                }
            }
            e.ns = e.ns.min(start.elapsed().as_nanos() as f64 / calls as f64);
        }
    }
}

// ---------------------------------------------------------------------------
// Whole scenes: render throughput per mode.

fn scene_files(root: &Path) -> Vec<PathBuf> {
    let mut files = Vec::new();
    for dir in [root.join("scenes"), root.join("scenes/bench")] {
        if let Ok(rd) = std::fs::read_dir(&dir) {
            let mut v: Vec<PathBuf> = rd
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.extension().is_some_and(|x| x == "json"))
                .collect();
            v.sort();
            files.extend(v);
        }
    }
    files
}

/// `(rays, seconds)` per mode over all scenes, best of `rounds` per scene.
fn measure_renders(files: &[PathBuf], size: (u32, u32), rounds: usize) -> Vec<(String, [(u64, f64); 3])> {
    let mut out = Vec::new();
    for f in files {
        let Ok(mut world) = render::load(f) else { continue };
        let Ok(camera) = world.camera.with_size(size.0, size.1) else { continue };
        world.camera = camera;
        world.settings.samples = 1;
        let mut best = [(0u64, f64::INFINITY); 3];
        for _ in 0..rounds {
            for (k, p) in [Precision::Fast, Precision::Accurate, Precision::Certified].into_iter().enumerate() {
                world.complex.set_precision(p);
                let Ok((_, stats)) = render::frame::render(
                    &world,
                    render::frame::Options { threads: Some(1), colour_only: false, ..Default::default() },
                    &|| {},
                ) else {
                    continue;
                };
                let secs = stats.elapsed.as_secs_f64();
                if secs < best[k].1 {
                    best[k] = (stats.rays, secs);
                }
            }
        }
        let name = f.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        out.push((name, best));
    }
    out
}

// ---------------------------------------------------------------------------
// Complexes: ownership and secondary rays (the stress set of
// `crates/complex/tests/secondary.rs`).

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Medium {
    Empty,
    Opaque,
    Glass(u32),
}

struct Stress {
    complex: Complex,
    exact: Vec<(Vec<ExactQuadric>, Opacity, u32)>,
    centre: Vector3<f64>,
    size: f64,
    camera: Vector3<f64>,
    h: f64,
    probe: f64,
}

fn moved(solids: &[Solid], m: &Transform) -> Vec<Solid> {
    solids.iter().map(|s| s.transformed(m)).collect()
}

impl Stress {
    fn new(blocks: Vec<(Vec<Solid>, Opacity, u32)>, at: f64, size: f64, epsilon: f64) -> Stress {
        let centre = Vector3::new(0.6, 0.64, -0.48) * at;
        let m = Transform::translate(centre).expect("a finite translation");
        let blocks: Vec<_> = blocks.into_iter().map(|(s, o, k)| (moved(&s, &m), o, k)).collect();
        let exact = blocks.iter().map(|(s, o, k)| (s.iter().map(ExactQuadric::solid).collect(), *o, *k)).collect();
        let built = blocks.into_iter().map(|(s, o, k)| Block::new("b", s, o, MaterialKey(k)).expect("a valid block"));
        let complex = Complex::new(built.collect(), ComplexOptions { epsilon: Some(epsilon), ..Default::default() })
            .expect("a valid complex");
        let (h, probe) = (1e-12 * at.max(1.0), 1e-14 * at.max(1.0));
        Stress { complex, exact, centre, size, camera: Vector3::new(0.3, 0.5, 6.0), h, probe }
    }

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

    fn owner_medium(&self, owner: Option<complex::BlockId>) -> Medium {
        match owner {
            None => Medium::Empty,
            Some(id) => match self.exact[id.index()] {
                (_, Opacity::Opaque, _) => Medium::Opaque,
                (_, Opacity::Transparent, k) => Medium::Glass(k),
            },
        }
    }

    /// How far off the hit point the medium of a side is read: `probe` past
    /// the true surface (the hit point's exact distance from it added, so
    /// that an inaccurate hit point does not put the probe on the wrong side).
    fn off_surface(&self, hit: &Hit) -> f64 {
        let x = [hit.point.x, hit.point.y, hit.point.z];
        let d = self.exact[hit.block.index()].0[hit.solid as usize].distance_f64(x).unwrap_or(0.0);
        d + self.probe
    }

    fn crossed_before(&self, ray: &Ray, t: f64) -> bool {
        let crossings = |s: &ExactQuadric| s.solve(ray).crossings().iter().any(|l| l.signum() > 0 && l.to_f64() <= t);
        self.exact.iter().flat_map(|(solids, _, _)| solids).any(crossings)
    }
}

fn hs(a: f64, b: f64, c: f64, d: f64) -> Solid {
    Solid::from(HalfSpace::new(a, b, c, d).expect("a valid half-space"))
}

fn cube(r: f64) -> Vec<Solid> {
    vec![
        hs(-1.0, 0.0, 0.0, -r),
        hs(1.0, 0.0, 0.0, -r),
        hs(0.0, -1.0, 0.0, -r),
        hs(0.0, 1.0, 0.0, -r),
        hs(0.0, 0.0, -1.0, -r),
        hs(0.0, 0.0, 1.0, -r),
    ]
}

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
    s.transformed(&m.expect("valid rotations"))
}

fn complexes(at: f64, epsilon: f64) -> Vec<Stress> {
    const O: Opacity = Opacity::Opaque;
    const G: Opacity = Opacity::Transparent;
    let thin = 1e-9 * at.max(1.0);
    let with = |mut a: Vec<Solid>, b: Vec<Solid>| {
        a.extend(b);
        a
    };
    let q = ball(1.0);
    let mut slabs = Stress::new(
        vec![
            (with(vec![hs(0.0, 1.0, 0.0, -thin), hs(0.0, -1.0, 0.0, 0.0)], cube(1.0)), G, 1),
            (with(vec![hs(0.0, -1.0, 0.0, -thin), hs(0.0, 1.0, 0.0, 0.0)], cube(1.0)), O, 0),
            (with(vec![hs(0.0, 1.0, 0.0, -3.0 * thin), hs(0.0, -1.0, 0.0, 2.0 * thin)], cube(1.0)), G, 2),
        ],
        at,
        1.0,
        epsilon,
    );
    slabs.camera = Vector3::new(0.3, 4.0, 3.0);
    vec![
        Stress::new(vec![(vec![q], O, 0)], at, 1.0, epsilon),
        slabs,
        Stress::new(
            vec![(vec![turned(ball(0.3))], O, 0), (vec![q], G, 1), (vec![q.complement(), ball(2.0)], G, 2)],
            at,
            2.0,
            epsilon,
        ),
        Stress::new(vec![(vec![ball(1.0)], G, 1), (vec![ball(1.5)], G, 2), (vec![ball(2.0)], G, 1)], at, 2.0, epsilon),
        Stress::new(
            vec![
                (with(vec![turned(Solid::from(Quadric::tube_y()))], cube(1.0)), O, 0),
                (vec![turned(waisted()), ball(1.8)], G, 1),
                (with(vec![Solid::from(Quadric::paraboloid())], cube(1.9)), G, 2),
            ],
            at,
            2.0,
            epsilon,
        ),
    ]
}

#[derive(Default, Clone, Copy)]
struct Secondary {
    segments: usize,
    ownership_errors: usize,
    spawned: usize,
    self_hits: usize,
    misses: usize,
}

fn tolerance(s: &Stress, t: f64) -> f64 {
    1e-2 * t + s.h
}

/// Judges one spawned ray that should start in `m0` (see `secondary.rs`).
/// A self-intersection is a spawned origin on the wrong side, or a hit where
/// the exact ray does not cross the reported surface; for `raw` rays (from
/// the hit point itself, on either side of the surface by rounding) an
/// origin on the wrong side counts only if the ray then reports a hit
/// closer than `h` (it sees the surface it starts on: acne).
fn judge_spawned(s: &Stress, ray: &Ray, m0: Medium, raw: bool, out: &mut Secondary) {
    out.spawned += 1;
    let wrong_side = s.medium(&ray.origin()) != m0;
    if !raw && wrong_side {
        out.self_hits += 1;
        if std::env::var_os("ACCURACY_VERBOSE").is_some() {
            eprintln!("wrong side: {ray:?} in {:?}, want {m0:?}", s.medium(&ray.origin()));
        }
        return;
    }
    let hit = s.complex.cast_ray(ray, f64::INFINITY);
    if let Some(hit) = &hit {
        let exact = &s.exact[hit.block.index()].0[hit.solid as usize];
        let near = exact.solve(ray).crossings().iter().any(|l| (l.to_f64() - hit.t).abs() <= tolerance(s, hit.t));
        if !near || (raw && wrong_side && hit.t < s.h) {
            if std::env::var_os("ACCURACY_VERBOSE").is_some() && !raw {
                eprintln!(
                    "spurious: {ray:?} at {:e} on {:?}/{} exact {:?}",
                    hit.t,
                    hit.block,
                    hit.solid,
                    exact.solve(ray).crossings().iter().map(|l| l.to_f64()).collect::<Vec<_>>()
                );
            }
            out.self_hits += 1;
            return;
        }
    }
    let end = hit.map_or(16.0 * s.size, |hit| hit.t - tolerance(s, hit.t));
    let mut t = s.h;
    while t < end {
        if s.medium(&ray.at(t)) != m0 && s.crossed_before(ray, t) {
            out.misses += 1;
            return;
        }
        t *= core::f64::consts::SQRT_2;
    }
}

fn directions(r: &Vector3<f64>, n: &Vector3<f64>, rng: &mut Rng) -> Vec<Vector3<f64>> {
    let mirror = r - 2.0 * r.dot(n) * n;
    let tangent = (r - r.dot(n) * n).try_normalize(0.0).unwrap_or_else(|| n.cross(&Vector3::x()).normalize());
    let mut out = vec![mirror, *r];
    for k in [3, 6, 9, 12] {
        let tilt = 10f64.powi(-k);
        out.push(tangent + tilt * n);
        out.push(tangent - tilt * n);
    }
    out.extend((0..2).map(|_| Vector3::from(rng.direction())));
    out
}

/// Ownership and secondary-ray errors with the kernel in `precision`;
/// `raw`: rays start at the raw hit point (the textbook row, with ε = 1e-4).
fn measure_secondary(precision: Precision, raw: bool, primaries: usize) -> Secondary {
    let mut out = Secondary::default();
    let epsilon = if raw { POV_MIN_DEPTH } else { 0.0 };
    for (i, at) in DISTANCES.into_iter().enumerate() {
        for mut s in complexes(at, epsilon) {
            s.complex.set_precision(precision);
            let mut rng = Rng::new(SEED + i as u64);
            let camera = Point3::from(s.centre + s.camera * s.size);
            for _ in 0..primaries {
                let target = Point3::from(s.centre + Vector3::from(rng.in_ball(1.1 * s.size)));
                let Ok(primary) = Ray::new(camera, target - camera) else { continue };
                // Ownership: each finite segment against the exact owner at its midpoint.
                let p = s.complex.partition(&primary);
                for seg in p.segments.iter().filter(|g| g.end.is_finite() && g.end - g.start > 4.0 * s.h) {
                    out.segments += 1;
                    let mid = primary.at(0.5 * (seg.start + seg.end));
                    if s.medium(&mid) != s.owner_medium(seg.owner) {
                        out.ownership_errors += 1;
                    }
                }
                let Some(hit) = s.complex.cast_ray(&primary, f64::INFINITY) else { continue };
                let n = hit.normal;
                if n == Vector3::zeros() {
                    continue;
                }
                for dir in directions(&primary.direction(), &n, &mut rng) {
                    let sigma = dir.dot(&n).signum();
                    let m0 = s.medium(&(hit.point + sigma * s.off_surface(&hit) * n));
                    let spawned = if raw { Ray::new(hit.point, dir) } else { spawn(&s.complex, &hit, &dir) };
                    if std::env::var_os("ACCURACY_VERBOSE").is_some() {
                        if let Ok(r) = &spawned {
                            if s.medium(&r.origin()) != m0 && !raw {
                                let vals: Vec<Vec<i32>> = s
                                    .exact
                                    .iter()
                                    .map(|(so, _, _)| {
                                        so.iter()
                                            .map(|q| q.value([hit.point.x, hit.point.y, hit.point.z]).signum())
                                            .collect()
                                    })
                                    .collect();
                                let ovals: Vec<Vec<i32>> = s
                                    .exact
                                    .iter()
                                    .map(|(so, _, _)| {
                                        so.iter()
                                            .map(|q| q.value([r.origin().x, r.origin().y, r.origin().z]).signum())
                                            .collect()
                                    })
                                    .collect();
                                eprintln!("hit {hit:?} signs at hit {vals:?} at origin {ovals:?} primary {primary:?}");
                            }
                        }
                    }
                    if let Ok(r) = spawned {
                        judge_spawned(&s, &r, m0, raw, &mut out);
                    }
                }
            }
        }
    }
    out
}

fn spawn(c: &Complex, hit: &Hit, dir: &Vector3<f64>) -> Result<Ray, quadric::GeometryError> {
    hit.spawn_ray(c, dir)
}

// ---------------------------------------------------------------------------
// The plot: kernel time against maximum hit-point error, log-log, no text
// (the axes and markers are explained in docs/accuracy.md).

fn plot(path: &Path, points: &[(f64, f64, f64, [u8; 3])]) -> Result<(), image::ImageError> {
    let (w, h) = (640u32, 420u32);
    let mut img = image::RgbImage::from_pixel(w, h, image::Rgb([255, 255, 255]));
    let (left, right, top, bottom) = (60.0, 620.0, 20.0, 380.0);
    // x: ns per call, 1 … 1e4 (log); y: error in ulps, 0.01 … 1e10 (log).
    let (x0, x1, y0, y1) = (0.0f64, 4.0f64, -2.0f64, 10.0f64);
    let px = |ns: f64| left + (ns.max(1e-9).log10() - x0) / (x1 - x0) * (right - left);
    let py = |e: f64| bottom - (e.max(1e-9).log10().clamp(y0, y1) - y0) / (y1 - y0) * (bottom - top);
    let mut put = |x: f64, y: f64, c: [u8; 3]| {
        if x >= 0.0 && y >= 0.0 && (x as u32) < w && (y as u32) < h {
            img.put_pixel(x as u32, y as u32, image::Rgb(c));
        }
    };
    let grey = [200, 200, 200];
    for d in 0..=4 {
        let x = px(10f64.powi(d));
        for y in top as u32..=bottom as u32 {
            put(x, y as f64, grey);
        }
    }
    for d in -2..=10 {
        let y = py(10f64.powi(d));
        for x in left as u32..=right as u32 {
            put(x as f64, y, if d == 0 { [120, 120, 120] } else { grey });
        }
    }
    for (ns, median, max, c) in points {
        // A line from the median (small square) to the maximum (large disc).
        let (x, ym, yx) = (px(*ns), py(*median), py(*max));
        for y in ym.min(yx) as i32..=ym.max(yx) as i32 {
            put(x, y as f64, *c);
            put(x + 1.0, y as f64, *c);
        }
        for dy in -7i32..=7 {
            for dx in -7i32..=7 {
                if dx * dx + dy * dy <= 49 {
                    put(x + dx as f64, yx + dy as f64, *c);
                }
                if dx.abs() <= 4 && dy.abs() <= 4 {
                    put(x + dx as f64, ym + dy as f64, *c);
                }
            }
        }
    }
    img.save(path)
}

// ---------------------------------------------------------------------------

fn pct(n: usize, d: usize) -> String {
    if d == 0 {
        "–".into()
    } else {
        format!("{:.3}%", 100.0 * n as f64 / d as f64)
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let quick = args.iter().any(|a| a == "--quick");
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
    let png = args
        .iter()
        .position(|a| a == "--png")
        .and_then(|i| args.get(i + 1))
        .map_or_else(|| root.join("docs/accuracy-time-error.png"), PathBuf::from);
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .map(|l| l.split(':').nth(1).unwrap_or("").trim().to_string())
        })
        .unwrap_or_else(|| "unknown".into());
    let load =
        std::fs::read_to_string("/proc/loadavg").ok().and_then(|l| l.split_whitespace().next().map(String::from));
    println!(
        "`cargo run --release -p reference --features bench --bin accuracy{}`",
        if quick { " -- --quick" } else { "" }
    );
    println!();
    println!(
        "machine: {cpu}, load average {} at start; seed {SEED:#x}; reference: exact dyadic decisions, roots to {} bits",
        load.as_deref().unwrap_or("?"),
        reference::PRECISION
    );
    println!();

    if args.iter().any(|a| a == "--secondary") {
        let s = measure_secondary(
            if args.iter().any(|a| a == "--fast") { Precision::Fast } else { Precision::Accurate },
            false,
            24,
        );
        println!("{} of {} self-intersections, {} missed", s.self_hits, s.spawned, s.misses);
        return;
    }
    let sets = stress_sets(quick);
    let rays: usize = sets.iter().map(|s| s.rays.len()).sum();
    let (mut errors, floor) = measure_errors(&sets);
    measure_kernel_time(&sets, &mut errors, if quick { 3 } else { 15 });
    let files = scene_files(&root);
    let renders = measure_renders(&files, if quick { (80, 60) } else { (320, 240) }, if quick { 1 } else { 3 });
    let primaries = if quick { 6 } else { 24 };
    let secondary: Vec<Secondary> = MODES
        .iter()
        .map(|m| match m {
            Mode::Kernel(p) => measure_secondary(*p, false, primaries),
            Mode::Textbook => measure_secondary(Precision::Accurate, true, primaries),
        })
        .collect();
    let raw_eps0 = {
        // Raw hit points with ε = 0: what spawning removes.
        let mut out = Secondary::default();
        for at in DISTANCES {
            for s in complexes(at, 0.0) {
                let mut rng = Rng::new(SEED);
                let camera = Point3::from(s.centre + s.camera * s.size);
                for _ in 0..primaries {
                    let target = Point3::from(s.centre + Vector3::from(rng.in_ball(1.1 * s.size)));
                    let Ok(primary) = Ray::new(camera, target - camera) else { continue };
                    let Some(hit) = s.complex.cast_ray(&primary, f64::INFINITY) else { continue };
                    if hit.normal == Vector3::zeros() {
                        continue;
                    }
                    for dir in directions(&primary.direction(), &hit.normal, &mut rng) {
                        let m0 =
                            s.medium(&(hit.point + dir.dot(&hit.normal).signum() * s.off_surface(&hit) * hit.normal));
                        if let Ok(r) = Ray::new(hit.point, dir) {
                            judge_spawned(&s, &r, m0, true, &mut out);
                        }
                    }
                }
            }
        }
        out
    };

    println!("### Summary: {rays} stress rays (8 solids × distances 1, 1e3, 1e6, 1e9 from the origin), the same rays for every row");
    println!();
    println!("| mode | kernel ns/call (Mcalls/s) | render Mrays/s, example scenes | hit error, ulps: median / max | × solid size: median / max | λ rel. error: median / max | false hits / misses, clear rays (gap > 4 ulps) | ownership errors | self-intersections | missed near surfaces |");
    println!("|---|---|---|---|---|---|---|---|---|---|");
    let mut points = Vec::new();
    let colours = [[230, 120, 0], [0, 110, 220], [0, 160, 60], [200, 0, 0]];
    for (k, ((m, e), sec)) in MODES.iter().zip(&errors).zip(&secondary).enumerate() {
        let (um, ux) = median_max(&e.tally.ulps);
        let (sm, sx) = median_max(&e.tally.size_units);
        let (lm, lx) = median_max(&e.tally.lambda_rel);
        let clear: (usize, usize, usize) = e.bins[1..].iter().fold((0, 0, 0), |a, b| (a.0 + b.0, a.1 + b.1, a.2 + b.2));
        let render = match m {
            Mode::Kernel(_) => {
                let (r, t) = renders.iter().fold((0u64, 0.0f64), |a, (_, b)| (a.0 + b[k].0, a.1 + b[k].1));
                format!("{:.2}", r as f64 / t.max(1e-9) / 1e6)
            }
            Mode::Textbook => "–".into(),
        };
        println!(
            "| {} | {:.1} ({:.0}) | {render} | {um:.2} / {ux:.3e} | {sm:.1e} / {sx:.1e} | {lm:.1e} / {lx:.1e} | {} / {} | {} of {} | {} | {} |",
            m.name(),
            e.ns,
            1e3 / e.ns,
            pct(clear.1, clear.0),
            pct(clear.2, clear.0),
            sec.ownership_errors,
            sec.segments,
            pct(sec.self_hits, sec.spawned),
            pct(sec.misses, sec.spawned),
        );
        points.push((e.ns, um, ux, colours[k]));
    }
    let (fm, fx) = median_max(&floor.ulps);
    println!("| rounding floor (exact hit rounded to f64) | | | {fm:.2} / {fx:.2} | | | | | | |");
    println!();
    println!(
        "Secondary rays judged per row: {}; rays from the raw hit point with ε = 0: {} self-intersections, {} missed.",
        secondary[1].spawned,
        pct(raw_eps0.self_hits, raw_eps0.spawned),
        pct(raw_eps0.misses, raw_eps0.spawned)
    );
    println!();
    println!("### False hits / false misses by closeness to tangency (gap in ulps of the solid's coordinates; % of the rays in the bin)");
    println!();
    println!("| mode | {} |", BIN_NAMES.map(|b| format!("gap {b}")).join(" | "));
    println!("|---|---|---|---|---|");
    println!("| rays | {} |", errors[0].bins.iter().map(|b| b.0.to_string()).collect::<Vec<_>>().join(" | "));
    for (m, e) in MODES.iter().zip(&errors) {
        let cells: Vec<String> = e.bins.iter().map(|b| format!("{} / {}", pct(b.1, b.0), pct(b.2, b.0))).collect();
        println!("| {} | {} |", m.name(), cells.join(" | "));
    }
    println!();
    println!(
        "### Render throughput per scene (single thread, {} rays/s in millions, best of rounds)",
        if quick { "80×60" } else { "320×240" }
    );
    println!();
    println!("| scene | Fast | Accurate | Certified | Accurate / Fast time |");
    println!("|---|---|---|---|---|");
    for (name, b) in &renders {
        let rate = |k: usize| b[k].0 as f64 / b[k].1.max(1e-9) / 1e6;
        println!("| {name} | {:.2} | {:.2} | {:.2} | {:.2} |", rate(0), rate(1), rate(2), rate(0) / rate(1));
    }
    match plot(&png, &points) {
        Ok(()) => eprintln!("wrote {}", png.display()),
        Err(e) => eprintln!("could not write {}: {e}", png.display()),
    }
}
