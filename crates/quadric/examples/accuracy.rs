//! Measures the accuracy and cost of ray–quadric hits against a
//! high-precision reference, and prints the tables of `docs/quadric.md`.
//!
//! ```text
//! cargo run --release -p quadric --example accuracy
//! ```
//!
//! Three kernels are compared with the exact answer and with the rounding
//! floor (the error of rounding the exact hit point to doubles):
//! - *naive*: world-space coefficients (`Quadric::coefficients`) and the
//!   textbook `(-t ± √(t² - su)) / s`;
//! - *stable + FMA*: the same world-space coefficients, `t² - su` by a fused
//!   difference of products and the stable root pair;
//! - *ours*: `Quadric::intervals`.
//!
//! `--modes` prints instead the table of the precision modes
//! (`Precision::{Fast, Accurate, Certified}`): error and cost of each on the
//! same rays (`docs/quadric.md`, "Precision modes"):
//!
//! ```text
//! cargo run --release -p quadric --example accuracy -- --modes
//! ```

use std::hint::black_box;
use std::time::Instant;

use quadric::roots::{difference_of_products, stable_roots};
use quadric::{Bound, IntervalSet, Precision, Ray};
use reference::{median_max, other_shapes, unit_sphere, Judge, Rng, Scene, Shape, Tally};

const SEED: u64 = 0x4b6f_6d70_6c65_7801;
const SPHERE_RAYS: usize = 20_000;
const SHAPE_RAYS: usize = 5_000;
const CAMERA: f64 = 0.25;
const COST_ROUNDS: usize = 60;

/// A quadric as its ten world-space coefficients, the way a textbook kernel sees it.
#[derive(Clone, Copy)]
struct World {
    a: [[f64; 3]; 3],
    w: [f64; 3],
    k: f64,
}

impl World {
    fn new(scene: &Scene) -> World {
        let [a, b, c, d, e, f, g, h, j, k] = scene.world_coefficients();
        World { a: [[a, d, e], [d, b, f], [e, f, c]], w: [g, h, j], k }
    }

    /// `s`, `t`, `u` evaluated directly in world space.
    #[inline(always)]
    fn stu(&self, ray: &Ray) -> (f64, f64, f64) {
        let (p, r) = (ray.origin(), ray.direction());
        let (p, r) = ([p.x, p.y, p.z], [r.x, r.y, r.z]);
        let row = |i: usize, v: [f64; 3]| self.a[i][0] * v[0] + self.a[i][1] * v[1] + self.a[i][2] * v[2];
        let ar = [row(0, r), row(1, r), row(2, r)];
        let g = [row(0, p) + self.w[0], row(1, p) + self.w[1], row(2, p) + self.w[2]];
        let s = r[0] * ar[0] + r[1] * ar[1] + r[2] * ar[2];
        let t = r[0] * g[0] + r[1] * g[1] + r[2] * g[2];
        let u = p[0] * (g[0] + self.w[0]) + p[1] * (g[1] + self.w[1]) + p[2] * (g[2] + self.w[2]) + self.k;
        (s, t, u)
    }

    /// The textbook kernel.
    #[inline(never)]
    fn naive(&self, ray: &Ray) -> IntervalSet {
        let (s, t, u) = self.stu(ray);
        if s == 0.0 {
            linear(t, u)
        } else {
            let disc = t * t - s * u;
            if disc < 0.0 {
                if s > 0.0 {
                    IntervalSet::empty()
                } else {
                    whole_ray()
                }
            } else {
                let root = disc.sqrt();
                let (l1, l2) = ((-t - root) / s, (-t + root) / s);
                quadratic(s, l1.min(l2), l1.max(l2))
            }
        }
    }

    /// World-space coefficients, but stable roots and an FMA discriminant.
    #[inline(never)]
    fn stable(&self, ray: &Ray) -> IntervalSet {
        let (s, t, u) = self.stu(ray);
        if s == 0.0 {
            linear(t, u)
        } else {
            let disc = difference_of_products(t, t, s, u);
            if disc < 0.0 {
                if s > 0.0 {
                    IntervalSet::empty()
                } else {
                    whole_ray()
                }
            } else {
                let (l1, l2) = stable_roots(s, t, u, disc);
                quadratic(s, l1, l2)
            }
        }
    }
}

// The textbook kernels build their sets already clipped to `λ >= 0`, the
// same way `Quadric::intervals` does, so that the cost comparison is of the
// root finding alone.

fn whole_ray() -> IntervalSet {
    IntervalSet::from_interval(Bound::free(0.0), Bound::free(f64::INFINITY))
}

fn up_to(root: f64) -> IntervalSet {
    IntervalSet::from_interval(Bound::free(0.0), Bound::new(root + 0.0, 0))
}

fn from(root: f64) -> IntervalSet {
    let enter = if root >= 0.0 { Bound::new(root + 0.0, 0) } else { Bound::free(0.0) };
    IntervalSet::from_interval(enter, Bound::free(f64::INFINITY))
}

#[inline(always)]
fn linear(t: f64, u: f64) -> IntervalSet {
    if t == 0.0 {
        return if u <= 0.0 { whole_ray() } else { IntervalSet::empty() };
    }
    let root = -u / (2.0 * t);
    if t > 0.0 {
        up_to(root)
    } else {
        from(root)
    }
}

#[inline(always)]
fn quadratic(s: f64, l1: f64, l2: f64) -> IntervalSet {
    if s > 0.0 {
        let enter = if l1 >= 0.0 { Bound::new(l1 + 0.0, 0) } else { Bound::free(0.0) };
        IntervalSet::from_interval(enter, Bound::new(l2 + 0.0, 0))
    } else if l1 < l2 && l1 > 0.0 {
        up_to(l1).union(&from(l2)).unwrap_or_else(|_| whole_ray())
    } else if l1 < l2 {
        from(l2)
    } else if l1 == l2 {
        whole_ray()
    } else {
        IntervalSet::empty()
    }
}

/// Tallies for the floor and the three kernels over one scene.
struct Row {
    distance: f64,
    rays: usize,
    hits: usize,
    floor: Tally,
    naive: Tally,
    stable: Tally,
    ours: Tally,
}

const JUDGE: Judge = Judge { band_ulps: 4.0 };

fn measure(shape: &Shape, distance: f64, n: usize, rng: &mut Rng) -> (Row, Scene, Vec<Ray>) {
    let scene = Scene::new(shape, distance, rng);
    let rays = scene.rays(shape, CAMERA * distance.min(1.0), n, rng);
    let world = World::new(&scene);
    let mut row = Row {
        distance,
        rays: rays.len(),
        hits: 0,
        floor: Tally::default(),
        naive: Tally::default(),
        stable: Tally::default(),
        ours: Tally::default(),
    };
    for ray in &rays {
        let exact = scene.exact.solve(ray);
        if !exact.crossings().is_empty() {
            row.hits += 1;
        }
        row.floor.add_floor(&scene, ray, &exact);
        row.naive.add(&scene, ray, &exact, &world.naive(ray), &JUDGE);
        row.stable.add(&scene, ray, &exact, &world.stable(ray), &JUDGE);
        let point = |t| scene.solid.hit_point(ray, t);
        row.ours.add_with_points(&scene, ray, &exact, &scene.solid.intervals(ray, 0), &JUDGE, point);
    }
    (row, scene, rays)
}

fn cell(t: &Tally, floor: bool) -> String {
    let (med, max) = median_max(&t.size_units);
    if floor {
        format!("{med:.1e} / {max:.1e}")
    } else {
        format!("{med:.1e} / {max:.1e} | {} / {}", t.false_hits, t.false_misses)
    }
}

fn print_radii_table(rows: &[Row], label: &str) {
    println!("| {label} | rays (hit) | rounding floor | naive world-space | FH / FM | stable + FMA, world space | FH / FM | ours (`intervals`) | FH / FM |");
    println!("|---|---|---|---|---|---|---|---|---|");
    for r in rows {
        println!(
            "| {:.0e} | {} ({}) | {} | {} | {} | {} |",
            r.distance,
            r.rays,
            r.hits,
            cell(&r.floor, true),
            cell(&r.naive, false),
            cell(&r.stable, false),
            cell(&r.ours, false)
        );
    }
}

fn print_detail_table(rows: &[Row], label: &str) {
    println!("| {label} | floor (ulp) med / max | ours (ulp) med / max | ours / floor, med / max | ours λ rel. error med / max | ours false hits + misses (worst gap, ulp) |");
    println!("|---|---|---|---|---|---|");
    for r in rows {
        let (fm, fx) = median_max(&r.floor.ulps);
        let (om, ox) = median_max(&r.ours.ulps);
        let (lm, lx) = median_max(&r.ours.lambda_rel);
        let (fmr, fxr) = median_max(&r.floor.size_units);
        let (omr, oxr) = median_max(&r.ours.size_units);
        println!(
            "| {:.0e} | {fm:.2} / {fx:.2} | {om:.2} / {ox:.2} | {:.2} / {:.2} | {lm:.1e} / {lx:.1e} | {} ({:.2}) |",
            r.distance,
            omr / fmr,
            oxr / fxr,
            r.ours.false_hits + r.ours.false_misses,
            r.ours.worst_gap_ulps
        );
    }
}

/// Nanoseconds per call of `f` over `rays`, one round.
fn time_round(rays: &[Ray], f: &dyn Fn(&Ray) -> IntervalSet) -> f64 {
    let repeats = 200_000 / rays.len().max(1);
    let start = Instant::now();
    for _ in 0..repeats {
        for ray in rays {
            black_box(f(black_box(ray)));
        }
    }
    start.elapsed().as_nanos() as f64 / (repeats * rays.len()) as f64
}

/// Nanoseconds per call of each kernel, best of interleaved rounds (the
/// machine may be shared: the minimum is the least disturbed round). Each
/// round copies the rays to a new offset, since some address layouts make
/// every kernel slower (stores of the result aliasing loads of the next ray).
fn time_kernels(rays: &[Ray], kernels: &[&dyn Fn(&Ray) -> IntervalSet]) -> Vec<f64> {
    let mut best = vec![f64::INFINITY; kernels.len()];
    for round in 0..COST_ROUNDS {
        let shifted: Vec<Ray> = rays[..round % 7].iter().chain(rays).copied().collect();
        let rays = &shifted[round % 7..];
        for (b, f) in best.iter_mut().zip(kernels) {
            *b = b.min(time_round(rays, *f));
        }
    }
    best
}

fn main() {
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .map(|l| l.split(':').nth(1).unwrap_or("").trim().to_string())
        })
        .unwrap_or_else(|| "unknown".to_string());
    println!("`cargo run --release -p quadric --example accuracy`");
    println!();
    println!(
        "machine: {cpu}; FMA target feature: {}; seed {SEED:#x}; reference: exact dyadic arithmetic, roots to {} bits",
        if cfg!(target_feature = "fma") { "on" } else { "off" },
        reference::PRECISION
    );
    println!();
    println!(
        "Errors: exact distance from the true surface of the reported hit point (Komplex's Accurate and Certified: \
         Solid::hit_point, refined onto the surface; Fast and the textbook formulas: p + λr in f64), in radii (median / max);"
    );
    println!("FH / FM: rays with more / fewer surface crossings than the exact answer.");
    println!();

    if std::env::args().any(|a| a == "--modes") {
        print_modes();
        return;
    }
    // `--cost` skips the accuracy tables (quick timing runs).
    let cost_only = std::env::args().any(|a| a == "--cost");
    let mut rng = Rng::new(SEED);
    let sphere = unit_sphere();
    let mut rows = Vec::new();
    let mut timing = Vec::new();
    for distance in [1.0, 1e3, 1e6, 1e9] {
        if cost_only {
            let scene = Scene::new(&sphere, distance, &mut rng);
            let rays = scene.rays(&sphere, CAMERA * distance.min(1.0), 4096, &mut rng);
            timing.push((distance, scene, rays));
            continue;
        }
        let (row, scene, rays) = measure(&sphere, distance, SPHERE_RAYS, &mut rng);
        rows.push(row);
        timing.push((distance, scene, rays));
    }
    if cost_only {
        print_cost(&timing);
        return;
    }
    println!("### Unit sphere at distance D, camera within {CAMERA} of the origin");
    println!();
    print_radii_table(&rows, "D");
    println!();
    print_detail_table(&rows, "D");
    println!();

    for shape in other_shapes() {
        let rows: Vec<Row> = [1.0, 1e3, 1e6, 1e9].iter().map(|&d| measure(&shape, d, SHAPE_RAYS, &mut rng).0).collect();
        println!("### {} at distance D", shape.name);
        println!();
        print_radii_table(&rows, "D");
        println!();
        print_detail_table(&rows, "D");
        println!();
    }

    print_cost(&timing);
}

fn print_cost(timing: &[(f64, Scene, Vec<Ray>)]) {
    // The machine may be shared: say how busy it was.
    let load =
        std::fs::read_to_string("/proc/loadavg").ok().and_then(|l| l.split_whitespace().next().map(String::from));
    println!(
        "### Cost, ns per call (unit sphere rays above, best of {COST_ROUNDS} interleaved rounds; load average {})",
        load.as_deref().unwrap_or("unknown")
    );
    println!();
    println!("| D | naive world-space | stable + FMA | ours (`intervals`) | ours / naive |");
    println!("|---|---|---|---|---|");
    for (distance, scene, rays) in timing {
        let world = World::new(scene);
        let rays = &rays[..rays.len().min(4096)];
        let t = time_kernels(
            rays,
            &[&|r: &Ray| world.naive(r), &|r: &Ray| world.stable(r), &|r: &Ray| scene.solid.intervals(r, 0)],
        );
        let (naive, stable, ours) = (t[0], t[1], t[2]);
        println!("| {distance:.0e} | {naive:.1} | {stable:.1} | {ours:.1} | {:.2} |", ours / naive);
    }
}

const MODES: [(Precision, &str); 3] =
    [(Precision::Fast, "Fast"), (Precision::Accurate, "Accurate (default)"), (Precision::Certified, "Certified")];

/// Error and cost of each precision mode on the same rays: every shape at
/// every distance, the camera near the origin.
fn print_modes() {
    let mut rng = Rng::new(SEED ^ 0x6d6f_6465);
    let mut shapes = vec![unit_sphere()];
    shapes.extend(other_shapes());
    println!("### Precision modes: hit-point error in U (max over all shapes), worst error / rounding floor, false hits + misses");
    println!();
    println!(
        "| D | rays (hit) | floor max (U) | {} |",
        MODES.map(|(_, n)| format!("{n}: max U, max / floor, FH + FM (unexcused)")).join(" | ")
    );
    println!("|---|---|---|---|---|---|");
    let mut timing = Vec::new();
    for distance in [1.0, 1e3, 1e6, 1e9] {
        let mut floor = Tally::default();
        let mut tallies: Vec<Tally> = MODES.iter().map(|_| Tally::default()).collect();
        let (mut rays_total, mut hits) = (0, 0);
        // Worst ratio per scene (the floor is per scene: shapes differ in scale).
        let mut worst_ratio = [0.0f64; 3];
        for shape in &shapes {
            let scene = Scene::new(shape, distance, &mut rng);
            let rays = scene.rays(shape, CAMERA * distance.min(1.0), SHAPE_RAYS, &mut rng);
            let mut scene_floor = Tally::default();
            let mut scene_modes: Vec<Tally> = MODES.iter().map(|_| Tally::default()).collect();
            for ray in &rays {
                let exact = scene.exact.solve(ray);
                hits += usize::from(!exact.crossings().is_empty());
                scene_floor.add_floor(&scene, ray, &exact);
                floor.add_floor(&scene, ray, &exact);
                for (k, (mode, _)) in MODES.iter().enumerate() {
                    let set = scene.solid.intervals_with(ray, 0, *mode);
                    // The point each mode reports (`complex::Hit::point`):
                    // refined onto the surface except in Fast.
                    let point = |t| if *mode == Precision::Fast { ray.at(t) } else { scene.solid.hit_point(ray, t) };
                    scene_modes[k].add_with_points(&scene, ray, &exact, &set, &JUDGE, point);
                    tallies[k].add_with_points(&scene, ray, &exact, &set, &JUDGE, point);
                }
            }
            let (_, fmax) = median_max(&scene_floor.size_units);
            for k in 0..3 {
                let (_, m) = median_max(&scene_modes[k].size_units);
                worst_ratio[k] = worst_ratio[k].max(m / fmax);
            }
            rays_total += rays.len();
            if shape.name == "unit sphere" {
                timing.push((distance, scene, rays));
            }
        }
        let (_, fmax) = median_max(&floor.ulps);
        let cells: Vec<String> = (0..3)
            .map(|k| {
                let t = &tallies[k];
                let (_, m) = median_max(&t.ulps);
                format!("{m:.2}, {:.2}, {} ({})", worst_ratio[k], t.false_hits + t.false_misses, t.unexcused)
            })
            .collect();
        println!("| {distance:.0e} | {rays_total} ({hits}) | {fmax:.2} | {} |", cells.join(" | "));
    }
    println!();
    let load =
        std::fs::read_to_string("/proc/loadavg").ok().and_then(|l| l.split_whitespace().next().map(String::from));
    println!(
        "### Precision modes: cost, ns per call (unit sphere rays, best of {COST_ROUNDS} interleaved rounds; load average {})",
        load.as_deref().unwrap_or("unknown")
    );
    println!();
    println!("| D | Fast | Accurate (default) | Certified | Accurate / Fast | Certified / Fast |");
    println!("|---|---|---|---|---|---|");
    for (distance, scene, rays) in &timing {
        let rays = &rays[..rays.len().min(4096)];
        let t = time_kernels(
            rays,
            &[
                &|r: &Ray| scene.solid.intervals_with(r, 0, Precision::Fast),
                &|r: &Ray| scene.solid.intervals_with(r, 0, Precision::Accurate),
                &|r: &Ray| scene.solid.intervals_with(r, 0, Precision::Certified),
            ],
        );
        println!(
            "| {distance:.0e} | {:.1} | {:.1} | {:.1} | {:.2} | {:.2} |",
            t[0],
            t[1],
            t[2],
            t[1] / t[0],
            t[2] / t[0]
        );
    }
}
