//! The batch queries on the 100-block random scene (`random_scene.rs`,
//! opaque), on rayon pools of one and two threads: points classified
//! (`classify`, 2^18 points spread over the scene's cube) and rays cast
//! (`cast_many`) and traced (`trace_many`) (16,384 rays from outside the
//! cube at random points inside it), per second; `cast_many` on one thread
//! against `cast_ray` one by one, on those rays and on a camera's.
//! `classify_large` and `trace_many_large` do the same on the
//! 100,000-block scene (two threads).
//!
//! `cargo bench -p complex --bench batch`.

use complex::{Complex, Traces};
use divan::counter::ItemsCount;
use quadric::nalgebra::Point3;
use quadric::Ray;

// `scene` is `cast_ray`'s.
#[allow(dead_code)]
mod random_scene;
use random_scene::blocks_and_rays;

const BLOCKS: usize = 100;
const POINTS: usize = 1 << 18;
const RAYS: usize = 16_384;

fn main() {
    divan::main();
}

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("a pool")
}

/// The large scene's number of blocks.
const LARGE: usize = 100_000;

/// The complex of `BLOCKS` blocks and its rays.
fn complex_and_rays() -> (Complex, Vec<Ray>) {
    complex_and_rays_of(BLOCKS)
}

/// The complex of `n` blocks and its rays.
fn complex_and_rays_of(n: usize) -> (Complex, Vec<Ray>) {
    let (blocks, rays) = blocks_and_rays(n, false, RAYS);
    (Complex::new(blocks, complex::ComplexOptions::default()).expect("valid"), rays)
}

/// Points spread evenly over the cube of `BLOCKS` blocks.
fn points() -> Vec<Point3<f64>> {
    points_of(BLOCKS)
}

/// Points spread evenly (a Weyl sequence, no generator needed) over the
/// cube `n` blocks fill, a margin of 10 % around it.
fn points_of(n: usize) -> Vec<Point3<f64>> {
    let side = 2.0 * (n as f64).cbrt();
    let frac = |x: f64| x - x.floor();
    (0..POINTS)
        .map(|i| {
            let i = i as f64;
            let at = |a: f64| (1.2 * frac(0.5 + i * a) - 0.1) * side;
            Point3::new(at(0.819_172_513_396_164_4), at(0.671_043_606_703_789_2), at(0.549_700_477_901_970_5))
        })
        .collect()
}

#[divan::bench(args = [1, 2], sample_count = 20, sample_size = 1)]
fn classify(bencher: divan::Bencher, threads: usize) {
    let (c, _) = complex_and_rays();
    let points = points();
    let mut owners = vec![None; points.len()];
    let pool = pool(threads);
    bencher.counter(ItemsCount::new(points.len())).bench_local(|| {
        pool.install(|| c.classify(divan::black_box(&points), &mut owners).expect("lengths match"));
    });
}

#[divan::bench(args = [1, 2], sample_count = 20, sample_size = 1)]
fn cast_many(bencher: divan::Bencher, threads: usize) {
    let (c, rays) = complex_and_rays();
    let mut hits = vec![None; rays.len()];
    let pool = pool(threads);
    bencher.counter(ItemsCount::new(rays.len())).bench_local(|| {
        pool.install(|| c.cast_many(divan::black_box(&rays), f64::INFINITY, &mut hits).expect("lengths match"));
    });
}

#[divan::bench(args = [1, 2], sample_count = 20, sample_size = 1)]
fn trace_many(bencher: divan::Bencher, threads: usize) {
    let (c, rays) = complex_and_rays();
    let mut traces = Traces::new();
    let pool = pool(threads);
    bencher.counter(ItemsCount::new(rays.len())).bench_local(|| {
        pool.install(|| c.trace_many(divan::black_box(&rays), &mut traces));
    });
}

/// `classify` on the 100,000-block scene, two threads.
#[divan::bench(sample_count = 20, sample_size = 1)]
fn classify_large(bencher: divan::Bencher) {
    let (c, _) = complex_and_rays_of(LARGE);
    let points = points_of(LARGE);
    let mut owners = vec![None; points.len()];
    let pool = pool(2);
    bencher.counter(ItemsCount::new(points.len())).bench_local(|| {
        pool.install(|| c.classify(divan::black_box(&points), &mut owners).expect("lengths match"));
    });
}

/// `trace_many` on the 100,000-block scene, two threads.
#[divan::bench(sample_count = 20, sample_size = 1)]
fn trace_many_large(bencher: divan::Bencher) {
    let (c, rays) = complex_and_rays_of(LARGE);
    let mut traces = Traces::new();
    let pool = pool(2);
    bencher.counter(ItemsCount::new(rays.len())).bench_local(|| {
        pool.install(|| c.trace_many(divan::black_box(&rays), &mut traces));
    });
}

/// The baseline of `cast_many` with one thread: the same rays through
/// `cast_ray` one by one, without a pool.
#[divan::bench(sample_count = 20, sample_size = 1)]
fn cast_ray_loop(bencher: divan::Bencher) {
    let (c, rays) = complex_and_rays();
    loop_bench(bencher, &c, &rays);
}

/// Coherent rays, a 128×128 camera's in scanline order: `cast_many` on one
/// thread (four neighbouring pixels share the packet walk) ...
#[divan::bench(sample_count = 20, sample_size = 1)]
fn cast_many_camera(bencher: divan::Bencher) {
    let (c, _) = complex_and_rays();
    let rays = random_scene::camera_rays(BLOCKS, 128);
    let mut hits = vec![None; rays.len()];
    let pool = pool(1);
    bencher.counter(ItemsCount::new(rays.len())).bench_local(|| {
        pool.install(|| c.cast_many(divan::black_box(&rays), f64::INFINITY, &mut hits).expect("lengths match"));
    });
}

/// ... and `cast_ray` one by one.
#[divan::bench(sample_count = 20, sample_size = 1)]
fn cast_ray_loop_camera(bencher: divan::Bencher) {
    let (c, _) = complex_and_rays();
    loop_bench(bencher, &c, &random_scene::camera_rays(BLOCKS, 128));
}

fn loop_bench(bencher: divan::Bencher, c: &Complex, rays: &[Ray]) {
    let mut hits = vec![None; rays.len()];
    bencher.counter(ItemsCount::new(rays.len())).bench_local(|| {
        for (r, h) in divan::black_box(rays).iter().zip(&mut hits) {
            *h = c.cast_ray(r, f64::INFINITY);
        }
    });
}
