//! Volume error against run time: the chord-length estimator of
//! `Complex::volumes` beside plain point sampling (OpenMC's stochastic
//! volume method: uniform points in a box, the volume is the box's times
//! the fraction inside) at equal time, on shapes with known volumes.
//!
//! `cargo run --release -p complex --example volume_error [-- SEEDS]`
//! `cargo run --release -p complex --example volume_error -- --coverage [SEEDS]`
//!
//! For each shape and line budget, the chord estimator runs one round of
//! that many lines per seed; point sampling then gets as many points as fit
//! in the chord estimator's median time (from a calibrated rate, checked by
//! timing it). Errors are root-mean-square over the seeds, relative to the
//! exact volume; the ratio compares them at (about) equal time, so it holds
//! up on a loaded machine. A second table gives `Complex::volumes` run to a
//! tolerance: time, lines and the error reached. With `--coverage`, how
//! often the exact volume lies beyond one to four reported standard errors
//! over `SEEDS` (default 1,000) runs at each of three tolerances.

use std::f64::consts::PI;
use std::time::{Duration, Instant};

use complex::{Aabb, Block, BlockId, Complex, ComplexOptions, MaterialKey, Opacity, VolumeOptions};
use quadric::nalgebra::{Point3, Vector3};
use quadric::{HalfSpace, Quadric, Solid, Transform};

fn hs(a: f64, b: f64, c: f64, d: f64) -> Solid {
    Solid::from(HalfSpace::new(a, b, c, d).expect("a valid half-space"))
}

fn shapes() -> Vec<(&'static str, Vec<Solid>, f64)> {
    let moved = |x: f64| Transform::translate(Vector3::new(x, 0.0, 0.0)).expect("finite");
    let mut drilled = vec![
        hs(-1.0, 0.0, 0.0, -1.0),
        hs(1.0, 0.0, 0.0, -1.0),
        hs(0.0, -1.0, 0.0, -1.0),
        hs(0.0, 1.0, 0.0, -1.0),
        hs(0.0, 0.0, -1.0, -1.0),
        hs(0.0, 0.0, 1.0, -1.0),
    ];
    let hole = Transform::scale_xyz(Vector3::new(0.5, 0.5, 1.0)).expect("finite");
    drilled.push(Solid::from(Quadric::tube_z().transformed(&hole).complement()));
    vec![
        ("sphere", vec![Solid::from(Quadric::sphere())], 4.0 / 3.0 * PI),
        ("drilled box", drilled, 8.0 - PI / 2.0),
        (
            "lens",
            vec![Solid::from(Quadric::sphere()), Solid::from(Quadric::sphere().transformed(&moved(1.0)))],
            5.0 / 12.0 * PI,
        ),
    ]
}

/// SplitMix64: the points' random numbers.
fn mix(mut x: u64) -> u64 {
    x = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    x = (x ^ (x >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    x ^ (x >> 31)
}

fn uniform(key: u64, i: u64) -> f64 {
    (mix(key ^ mix(i)) >> 11) as f64 / (1u64 << 53) as f64
}

/// Point sampling: `n` uniform points in `b`, classified in parallel
/// batches; the box's volume times the fraction inside.
fn point_estimate(c: &Complex, b: &Aabb, n: u64, seed: u64) -> f64 {
    const BATCH: u64 = 1 << 16;
    let key = mix(seed ^ 0xA5A5_A5A5);
    let size = b.size();
    let mut points = Vec::with_capacity(BATCH as usize);
    let mut owners = vec![None; BATCH as usize];
    let mut inside = 0u64;
    let mut start = 0;
    while start < n {
        let m = (n - start).min(BATCH);
        points.clear();
        points.extend((start..start + m).map(|i| {
            let r = |k: u64| uniform(key, 3 * i + k);
            Point3::new(b.min.x + r(0) * size.x, b.min.y + r(1) * size.y, b.min.z + r(2) * size.z)
        }));
        let out = &mut owners[..m as usize];
        c.classify(&points, out).expect("one slot per point");
        inside += out.iter().filter(|o| o.is_some()).count() as u64;
        start += m;
    }
    size.x * size.y * size.z * inside as f64 / n as f64
}

fn rms(errors: &[f64]) -> f64 {
    (errors.iter().map(|e| e * e).sum::<f64>() / errors.len() as f64).sqrt()
}

fn median(mut t: Vec<Duration>) -> Duration {
    t.sort();
    t[t.len() / 2]
}

/// How often the exact volume lies beyond 1, 2, 3 and 4 reported standard errors.
fn coverage(seeds: u64) {
    println!("runs beyond 1, 2, 3, 4 reported standard errors, of {seeds}");
    for (name, solids, exact) in shapes() {
        let block = Block::new(name, solids, Opacity::Opaque, MaterialKey(0)).expect("a valid block");
        let c = Complex::new(vec![block], ComplexOptions::default()).expect("a valid complex");
        for tolerance in [3e-2, 1e-3, 1e-4] {
            let mut beyond = [0; 4];
            for seed in 0..seeds {
                let v = c.volumes(&VolumeOptions { tolerance, seed, ..VolumeOptions::default() }).expect("valid");
                let e = v.blocks[0].own.expect("bounded");
                let z = (e.value - exact).abs() / e.error;
                for (k, b) in beyond.iter_mut().enumerate() {
                    *b += u32::from(z > (k + 1) as f64);
                }
            }
            println!("{name:<12} {tolerance:>8.0e} {beyond:?}");
        }
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.first().is_some_and(|a| a == "--coverage") {
        return coverage(args.get(1).and_then(|s| s.parse().ok()).unwrap_or(1000));
    }
    let seeds: u64 = args.first().and_then(|s| s.parse().ok()).unwrap_or(16);
    println!("equal time, {seeds} seeds, {} threads", rayon::current_num_threads());
    println!(
        "{:<12} {:>10} {:>10} {:>12} {:>11} {:>10} {:>12} {:>8}",
        "shape", "lines", "time ms", "chord error", "points", "time ms", "point error", "ratio"
    );
    for (name, solids, exact) in shapes() {
        let block = Block::new(name, solids, Opacity::Opaque, MaterialKey(0)).expect("a valid block");
        let c = Complex::new(vec![block], ComplexOptions::default()).expect("a valid complex");
        let b = c.block_aabb(BlockId(0));
        // The point rate, calibrated once per shape on a million points.
        let t = Instant::now();
        point_estimate(&c, &b, 1 << 20, u64::MAX);
        let rate = (1u64 << 20) as f64 / t.elapsed().as_secs_f64();
        for lines in [1u64 << 13, 1 << 15, 1 << 17, 1 << 19] {
            let options = VolumeOptions { tolerance: 1.0, initial_lines: lines, ..VolumeOptions::default() };
            let (mut errors, mut times, mut used) = (Vec::new(), Vec::new(), 0);
            for seed in 0..seeds {
                let t = Instant::now();
                let v = c.volumes(&VolumeOptions { seed, ..options }).expect("valid options");
                times.push(t.elapsed());
                used = v.lines;
                errors.push(v.blocks[0].own.expect("bounded").value / exact - 1.0);
            }
            let chord_time = median(times);
            let points = (rate * chord_time.as_secs_f64()).round().max(1.0) as u64;
            let (mut perrors, mut ptimes) = (Vec::new(), Vec::new());
            for seed in 0..seeds {
                let t = Instant::now();
                perrors.push(point_estimate(&c, &b, points, seed) / exact - 1.0);
                ptimes.push(t.elapsed());
            }
            let (ce, pe) = (rms(&errors), rms(&perrors));
            println!(
                "{:<12} {:>10} {:>10.2} {:>12.2e} {:>11} {:>10.2} {:>12.2e} {:>8.0}",
                name,
                used,
                chord_time.as_secs_f64() * 1e3,
                ce,
                points,
                median(ptimes).as_secs_f64() * 1e3,
                pe,
                pe / ce
            );
        }
    }
    println!();
    println!("to a tolerance (seed 0)");
    println!(
        "{:<12} {:>10} {:>10} {:>10} {:>14} {:>14}",
        "shape", "tolerance", "time ms", "lines", "reported SE", "actual error"
    );
    for (name, solids, exact) in shapes() {
        let block = Block::new(name, solids, Opacity::Opaque, MaterialKey(0)).expect("a valid block");
        let c = Complex::new(vec![block], ComplexOptions::default()).expect("a valid complex");
        for tolerance in [1e-3, 1e-4, 1e-5] {
            let t = Instant::now();
            let v = c.volumes(&VolumeOptions { tolerance, ..VolumeOptions::default() }).expect("valid options");
            let e = v.blocks[0].own.expect("bounded");
            println!(
                "{:<12} {:>10.0e} {:>10.1} {:>10} {:>14.2e} {:>14.2e}",
                name,
                tolerance,
                t.elapsed().as_secs_f64() * 1e3,
                v.lines,
                e.error / exact,
                (e.value / exact - 1.0).abs()
            );
        }
    }
}
