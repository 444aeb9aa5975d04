//! Points classified and rays cast per second through the kernel's batch
//! queries, for a scene file: the Rust side of the Python module's
//! throughput comparison (`python/bench.py` builds the very same points and
//! rays; docs/python.md).
//!
//! `cargo run --release -p render --example batch_rate -- SCENE [N] [RUNS]`
//! (default 1,000,000 queries, best of 5 runs).

use std::time::Instant;

use quadric::nalgebra::{Point3, Vector3};
use quadric::Ray;

/// `x - floor(x)`.
fn frac(x: f64) -> f64 {
    x - x.floor()
}

/// Point `i`: a Weyl sequence over the box `[lo, hi]` (the same arithmetic
/// as `python/bench.py`, so both sides query the same points).
fn point(i: usize, lo: &Point3<f64>, hi: &Point3<f64>) -> Point3<f64> {
    const A: [f64; 3] = [0.819_172_513_396_164_4, 0.671_043_606_703_789_2, 0.549_700_477_901_970_5];
    let i = i as f64;
    Point3::from(std::array::from_fn(|k| lo[k] + (hi[k] - lo[k]) * frac(0.5 + i * A[k])))
}

/// Direction `i`: another Weyl sequence, centred.
fn direction(i: usize) -> Vector3<f64> {
    const B: [f64; 3] = [0.754_877_666_246_692_7, 0.569_840_290_998_053_3, 0.438_265_142_261_981_5];
    let i = i as f64;
    Vector3::from(std::array::from_fn(|k| frac(0.3 + i * B[k]) - 0.5))
}

/// The fastest of `runs` timings of `f`, in seconds.
fn best_of(runs: usize, mut f: impl FnMut()) -> f64 {
    (0..runs)
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed().as_secs_f64()
        })
        .fold(f64::INFINITY, f64::min)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let scene = args.first().ok_or("usage: batch_rate SCENE [N] [RUNS]")?;
    let n: usize = args.get(1).map_or(Ok(1_000_000), |s| s.parse())?;
    let runs: usize = args.get(2).map_or(Ok(5), |s| s.parse())?;
    let world = render::load(std::path::Path::new(scene))?;
    let bounds = world.complex.aabb();
    if !bounds.is_bounded() {
        return Err("the scene is unbounded".into());
    }
    let points: Vec<Point3<f64>> = (0..n).map(|i| point(i, &bounds.min, &bounds.max)).collect();
    let rays: Vec<Ray> = (0..n).map(|i| Ray::new(points[i], direction(i))).collect::<Result<_, _>>()?;
    let mut owners = vec![None; n];
    let classify = best_of(runs, || world.complex.classify(&points, &mut owners).expect("lengths match"));
    let mut hits = vec![None; n];
    let cast = best_of(runs, || world.complex.cast_many(&rays, f64::INFINITY, &mut hits).expect("lengths match"));
    let inside = owners.iter().filter(|o| o.is_some()).count();
    let hit = hits.iter().filter(|h| h.is_some()).count();
    println!("classify: {:.2} M points/s ({inside} of {n} inside)", n as f64 / classify / 1e6);
    println!("cast:     {:.2} M rays/s ({hit} of {n} hit)", n as f64 / cast / 1e6);
    Ok(())
}
