//! The random-blocks benchmark scene as a program, for profilers and for
//! timing the build: `cargo run --release -p complex --example random_blocks -- N [RAYS] [--transparent] [--camera]`
//! prints the time to build the complex of `N` blocks (boxes and BVH), the
//! time to cast `RAYS` rays (default 100,000) and the number of hits. The
//! rays are random (incoherent: each one touches other parts of the
//! hierarchy), or with `--camera` the primary rays of a square image of
//! about `RAYS` pixels in scanline order (coherent), or with `--bench` the
//! bench's 1,024 random rays over and over (as `cargo bench` casts them:
//! after the first round, what they touch is in the caches). `--dry` does
//! everything but cast (for subtracting counters: `perf stat` of a run
//! minus that of the same run with `--dry` is the cost of the rays alone).
//!
//! Under callgrind, count only the rays:
//! `valgrind --tool=callgrind --toggle-collect='*cast_rays*' target/release/examples/random_blocks 100000`.

use std::time::Instant;

use complex::{Complex, ComplexOptions};
use quadric::Ray;

#[path = "../benches/random_scene.rs"]
#[allow(dead_code)]
mod random_scene;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let transparent = args.iter().any(|a| a == "--transparent");
    let camera = args.iter().any(|a| a == "--camera");
    let bench = args.iter().any(|a| a == "--bench");
    // Everything but the casting: subtracting such a run's counters from a
    // full run's leaves the cost of the rays alone.
    let dry = args.iter().any(|a| a == "--dry");
    let mut numbers = args.iter().filter(|a| !a.starts_with("--")).map(|a| a.parse::<usize>());
    let n = numbers.next().transpose()?.unwrap_or(100_000);
    let count = numbers.next().transpose()?.unwrap_or(100_000);
    let (blocks, mut rays) = random_scene::blocks_and_rays(n, transparent, count);
    if camera {
        rays = random_scene::camera_rays(n, (count as f64).sqrt().round() as usize);
    } else if bench {
        let (_, first) = random_scene::blocks_and_rays(n, transparent, 1024);
        rays = first.iter().copied().cycle().take(count).collect();
    }
    let start = Instant::now();
    let complex = Complex::new(blocks, ComplexOptions::default())?;
    let build = start.elapsed();
    let start = Instant::now();
    let hits = if dry { 0 } else { cast_rays(&complex, &rays) };
    let cast = start.elapsed();
    println!(
        "{n} blocks: build {:.1} ms; {} rays in {:.1} ms = {:.3} M rays/s; {hits} hits",
        build.as_secs_f64() * 1e3,
        rays.len(),
        cast.as_secs_f64() * 1e3,
        rays.len() as f64 / cast.as_secs_f64() / 1e6
    );
    Ok(())
}

/// The measured loop (a separate function so that profilers can single it out).
#[inline(never)]
fn cast_rays(complex: &Complex, rays: &[Ray]) -> usize {
    rays.iter().filter(|r| complex.cast_ray(r, f64::INFINITY).is_some()).count()
}
