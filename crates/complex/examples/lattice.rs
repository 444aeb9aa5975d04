//! The cost of a ray in an assembled scene (docs/benchmarks.md,
//! "Instances and lattices"): a lattice of tiles, each a 30 × 30 lattice
//! of balls on a slab, seen by a camera looking down at it, cast as one
//! batch (`Complex::cast_many`) on the current thread pool. With `--flat`
//! the same scene is built from its explicit expansion instead, for the
//! per-ray cost of the two.
//!
//! Usage: `cargo run --release -p complex --example lattice -- [TILES] [--flat] [--width W --height H]`
//! (TILES: tiles per side, default 1000: 9·10⁸ balls).

use std::sync::Arc;
use std::time::Instant;

use complex::{Block, Complex, ComplexOptions, MaterialKey, Member, Opacity, Placement};
use quadric::nalgebra::{Point3, Vector3};
use quadric::{Ray, Transform};

const BALLS: u32 = 30;

fn ball() -> Block {
    let solid = complex::shapes::sphere(Point3::new(0.5, 0.4, 0.5), 0.4).expect("a ball");
    Block::new("ball", vec![solid], Opacity::Opaque, MaterialKey(0)).expect("a block")
}

fn lattice(definition: Arc<Complex>, pitch: f64, n: u32) -> Member {
    Member::Placed(Placement {
        pitch: Vector3::new(pitch, 0.0, pitch),
        count: [n, 1, n],
        ..Placement::instance(definition, Transform::identity())
    })
}

fn assembled(tiles: u32) -> Complex {
    let one = Arc::new(Complex::new(vec![ball()], ComplexOptions::default()).expect("a ball"));
    let tile = Complex::assemble(vec![lattice(one, 1.0, BALLS)], ComplexOptions::default()).expect("a tile");
    Complex::assemble(vec![lattice(Arc::new(tile), f64::from(BALLS), tiles)], ComplexOptions::default())
        .expect("the scene")
}

fn flat(tiles: u32) -> Complex {
    let n = tiles * BALLS;
    let mut blocks = Vec::with_capacity((n * n) as usize);
    for k in 0..n {
        for i in 0..n {
            let m = Transform::translate(Vector3::new(f64::from(i), 0.0, f64::from(k))).expect("a translation");
            let b = ball();
            let solids = b.solids().iter().map(|s| s.transformed(&m)).collect();
            blocks.push(Block::new("ball", solids, Opacity::Opaque, MaterialKey(0)).expect("a block"));
        }
    }
    // The expansion numbers balls tile by tile; the flat list row by row:
    // the same blocks, so the same hits up to ids.
    Complex::new(blocks, ComplexOptions::default()).expect("the scene")
}

/// Peak resident memory of this process in MiB (Linux), if known.
fn peak_mib() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib / 1024.0)
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let value = |name: &str, default: u32| {
        args.iter().position(|a| a == name).and_then(|k| args.get(k + 1)?.parse().ok()).unwrap_or(default)
    };
    let tiles: u32 = args.first().and_then(|a| a.parse().ok()).unwrap_or(1000);
    let (width, height) = (value("--width", 640), value("--height", 480));
    let is_flat = args.iter().any(|a| a == "--flat");
    let start = Instant::now();
    let scene = if is_flat { flat(tiles) } else { assembled(tiles) };
    let built = start.elapsed().as_secs_f64();
    // A camera above one corner, looking across the lattice.
    let side = f64::from(tiles * BALLS);
    let eye = Point3::new(-0.05 * side, 0.08 * side + 3.0, -0.05 * side);
    let target = Point3::new(0.5 * side, 0.0, 0.5 * side);
    let forward = (target - eye).normalize();
    let right = forward.cross(&Vector3::y()).normalize();
    let up = right.cross(&forward);
    let rays: Vec<Ray> = (0..height)
        .flat_map(|y| (0..width).map(move |x| (x, y)))
        .map(|(x, y)| {
            let u = (f64::from(x) + 0.5) / f64::from(width) - 0.5;
            let v = 0.5 - (f64::from(y) + 0.5) / f64::from(height);
            let d = forward + right * (u * 0.8) + up * (v * 0.6);
            Ray::new(eye, d).expect("a ray")
        })
        .collect();
    let mut hits = vec![None; rays.len()];
    let start = Instant::now();
    scene.cast_many(&rays, f64::INFINITY, &mut hits).expect("lengths match");
    let cast = start.elapsed().as_secs_f64();
    let met = hits.iter().filter(|h| h.is_some()).count();
    println!(
        "{} blocks ({}): built in {built:.2} s; {} rays in {cast:.2} s ({:.2} µs/ray on {} threads), {met} hit; peak memory {:.0} MiB",
        scene.len(),
        if is_flat { "flat" } else { "assembled" },
        rays.len(),
        cast * 1e6 / rays.len() as f64 * rayon::current_num_threads() as f64,
        rayon::current_num_threads(),
        peak_mib().unwrap_or(f64::NAN),
    );
}
