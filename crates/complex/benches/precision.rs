//! `cast_ray` in each precision mode (`Complex::set_precision`) on the
//! random scenes of `cast_ray.rs` (opaque, 1,000 and 100,000 blocks; 1,024
//! rays from outside the cube per iteration).
//!
//! `cargo bench -p complex --bench precision`

use complex::Precision;
use divan::counter::ItemsCount;

#[allow(dead_code)]
mod random_scene;
use random_scene::scene;

fn main() {
    divan::main();
}

fn mode(name: &str) -> Precision {
    match name {
        "fast" => Precision::Fast,
        "certified" => Precision::Certified,
        _ => Precision::Accurate,
    }
}

#[divan::bench(args = ["fast", "accurate", "certified"], consts = [1_000, 100_000], sample_count = 20, sample_size = 4)]
fn cast_ray<const N: usize>(bencher: divan::Bencher, precision: &str) {
    let (mut c, rays) = scene(N, false);
    c.set_precision(mode(precision));
    bencher.counter(ItemsCount::new(rays.len())).bench_local(|| {
        let mut hits = 0usize;
        for r in &rays {
            hits += usize::from(c.cast_ray(divan::black_box(r), f64::INFINITY).is_some());
        }
        hits
    });
}
