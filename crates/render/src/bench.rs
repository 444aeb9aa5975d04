//! `komplex bench`: throughput of the render loop on a scene.
//!
//! One render gives both figures: primary rays (one per pixel, the
//! anti-aliasing setting is forced to 1 so POV-Ray's `-A` renders compare)
//! and all rays (primary, shadow, reflected, refracted) over the same
//! wall-clock time of the render loop. Loading and building the kernel are
//! timed apart.
//!
//! ```
//! let dir = tempfile::tempdir().unwrap();
//! let path = dir.path().join("ball.json");
//! std::fs::write(&path, r#"{ "camera": { "eye": [0, 0, 5], "direction": [0, 0, -1] },
//!                            "lights": [ { "position": [2, 2, 5] } ],
//!                            "blocks": [ { "objects": [ { "sphere": {} } ] } ] }"#).unwrap();
//! let m = render::bench::measure(&path, (Some(8), Some(6)), Some(1), render::Precision::default()).unwrap();
//! assert_eq!((m.blocks, m.primary), (1, 48));
//! assert!(m.rays > m.primary); // shadow rays from the pixels that see the ball
//! ```

use std::path::Path;
use std::time::{Duration, Instant};

use complex::Precision;

use crate::convert::LoadTimes;
use crate::error::Error;

/// What one benchmark run measured.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Measurement {
    /// Blocks in the scene.
    pub blocks: usize,
    /// Reading, parsing and building the kernel (bounds, BVH).
    pub load: Duration,
    /// The load by stage.
    pub stages: LoadTimes,
    /// Image size.
    pub width: u32,
    /// Image size.
    pub height: u32,
    /// Primary rays cast (one per pixel).
    pub primary: u64,
    /// All rays cast.
    pub rays: u64,
    /// Wall-clock time of the render loop: the fastest of the runs.
    pub render: Duration,
    /// The median render time of the runs (with an even count, the faster
    /// of the two middle ones).
    pub median: Duration,
    /// Renders timed.
    pub runs: u32,
}

impl Measurement {
    /// Primary rays per second of render time.
    pub fn primary_per_second(&self) -> f64 {
        self.primary as f64 / self.render.as_secs_f64().max(1e-9)
    }

    /// All rays per second of render time.
    pub fn rays_per_second(&self) -> f64 {
        self.rays as f64 / self.render.as_secs_f64().max(1e-9)
    }
}

/// Loads `path`, renders it once at `size` (`(width, height)` overrides as
/// in [`Camera::resized`](crate::camera::Camera::resized); default: the
/// scene's) with `threads` workers, one ray per pixel and the kernel in
/// `precision` mode, and reports the times.
pub fn measure(
    path: &Path,
    size: (Option<u32>, Option<u32>),
    threads: Option<usize>,
    precision: Precision,
) -> Result<Measurement, Error> {
    measure_runs(path, size, threads, precision, 1)
}

/// [`measure`], with the scene loaded once and rendered `runs` times (at
/// least once): the render time is the fastest run, and the median is
/// reported too. On a shared machine single renders of a fraction of a
/// second swing by several percent; the fastest of several is the steadier
/// figure, and each run renders the same image (the ray counts agree).
pub fn measure_runs(
    path: &Path,
    size: (Option<u32>, Option<u32>),
    threads: Option<usize>,
    precision: Precision,
    runs: u32,
) -> Result<Measurement, Error> {
    let start = Instant::now();
    let (mut world, stages) = crate::convert::load_timed(path)?;
    let load = start.elapsed();
    world.complex.set_precision(precision);
    world.camera =
        world.camera.resized(size.0, size.1).map_err(|e| Error::Options(format!("--width/--height: {e}")))?;
    world.settings.samples = 1;
    let mut times: Vec<Duration> = Vec::new();
    let (mut width, mut height, mut rays) = (0, 0, 0);
    for _ in 0..runs.max(1) {
        let (frame, stats) = crate::frame::render(
            &world,
            crate::frame::Options { threads, colour_only: true, ..Default::default() },
            &|| {},
        )?;
        (width, height, rays) = (frame.width, frame.height, stats.rays);
        times.push(stats.elapsed);
    }
    times.sort_unstable();
    Ok(Measurement {
        blocks: world.complex.len(),
        load,
        stages,
        width,
        height,
        primary: u64::from(width) * u64::from(height),
        rays,
        render: times[0],
        median: times[(times.len() - 1) / 2],
        runs: times.len() as u32,
    })
}
