//! `cast_ray` over 10 to 100,000 random bounded blocks, all opaque or every
//! other one transparent; and the build of such a complex.
//!
//! `cargo bench -p complex --bench cast_ray`. The blocks (balls, capped
//! tubes and rotated boxes, radius 0.3–0.6) fill a cube whose side grows as
//! `N^(1/3)`, so the density stays fixed; each iteration casts 1,024 rays
//! from outside the cube at random points inside it; `cast_ray_camera`
//! casts the 16,384 primary rays of a camera instead.

use complex::{Complex, ComplexOptions};
use divan::counter::ItemsCount;
use quadric::Ray;

mod random_scene;
use random_scene::{blocks_and_rays, camera_rays, scene};

fn main() {
    divan::main();
}

#[divan::bench(args = [10, 100, 1_000, 10_000, 100_000], sample_count = 20, sample_size = 4)]
fn cast_ray(bencher: divan::Bencher, n: usize) {
    run(bencher, n, false);
}

/// The same scenes with every other block transparent: the path that
/// walks interval ends until the medium changes.
#[divan::bench(args = [10, 100, 1_000, 10_000, 100_000], sample_count = 20, sample_size = 4)]
fn cast_ray_half_transparent(bencher: divan::Bencher, n: usize) {
    run(bencher, n, true);
}

/// The opaque scenes seen by a 128×128 pinhole camera, rays in scanline
/// order: coherent rays, as a renderer casts them.
#[divan::bench(args = [100, 100_000], sample_count = 20, sample_size = 1)]
fn cast_ray_camera(bencher: divan::Bencher, n: usize) {
    let (c, _) = scene(n, false);
    cast(bencher, &c, &camera_rays(n, 128));
}

fn run(bencher: divan::Bencher, n: usize, transparent: bool) {
    let (c, rays) = scene(n, transparent);
    cast(bencher, &c, &rays);
}

fn cast(bencher: divan::Bencher, c: &Complex, rays: &[Ray]) {
    bencher.counter(ItemsCount::new(rays.len())).bench_local(|| {
        let mut hits = 0usize;
        for r in rays {
            hits += usize::from(c.cast_ray(divan::black_box(r), f64::INFINITY).is_some());
        }
        hits
    });
}

/// `Complex::new` (a box per block, then the BVH) for the opaque scenes.
#[divan::bench(args = [1_000, 100_000], sample_count = 5, sample_size = 1)]
fn build(bencher: divan::Bencher, n: usize) {
    let (blocks, _) = blocks_and_rays(n, false, 0);
    bencher
        .counter(ItemsCount::new(n))
        .with_inputs(|| blocks.clone())
        .bench_local_values(|b| Complex::new(b, ComplexOptions::default()).expect("valid"));
}
