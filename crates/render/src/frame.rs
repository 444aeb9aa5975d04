//! The render loop: one ray per pixel centre, rows in parallel.

use std::cell::RefCell;
use std::ops::Range;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use quadric::nalgebra::Vector3;

use crate::camera::Camera;
use crate::error::Error;
use crate::limits::{MAX_PIXELS, MAX_THREADS};
use crate::path::{PathOptions, PathTracer};
use crate::sampling::Sampler;
use crate::shade::{PrimaryHit, Scratch, Shader};
use crate::world::{Integrator, World};

/// One pixel of every output channel (read out of a [`Frame`]'s planes by
/// [`Frame::at`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Pixel {
    /// Linear RGB.
    pub rgb: [f32; 3],
    /// Coverage: the fraction of the pixel's samples that hit a block (with
    /// one sample per pixel: 1 on a hit, 0 on a miss).
    pub alpha: f32,
    /// Distance along the primary ray, `+∞` on a miss.
    pub depth: f32,
    /// World-space unit normal facing the camera, zero on a miss.
    pub normal: [f32; 3],
    /// 1-based block index in priority order, 0 on a miss.
    pub block: u32,
    /// 1-based solid index within the block, 0 on a miss.
    pub object: u32,
    /// The samples the pixel took (adaptive sampling only, else 0).
    pub spp: u32,
    /// The estimated relative standard error of the pixel's mean luminance
    /// (adaptive sampling only, else 0).
    pub error: f32,
}

/// A rendered image, or a band of its rows ([`Options::rows`]): one plane
/// per output channel (the channels of [`Pixel`]), each `width * height`
/// samples, row by row from the top-left pixel of the band; the band is
/// rows `first_row .. first_row + height` of an image `image_height` rows
/// high (a whole image: `first_row` 0, `image_height` = `height`). Planes rather than an array of pixels, so that the frame is
/// allocated zeroed (its pages mapped lazily, by the worker threads that
/// write them, not first cleared by one thread) and the EXR writer takes
/// each channel as it is. Every plane holds `width * height` samples, as
/// [`render`] makes them, except that a colour-only frame
/// ([`Options::colour_only`]) has empty AOV planes (`depth`, `normal`,
/// `block`, `object`).
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels: the rows the frame holds.
    pub height: u32,
    /// The image row (from the top) of the frame's first row.
    pub first_row: u32,
    /// The height of the whole image the frame's rows belong to.
    pub image_height: u32,
    /// Linear red, green and blue.
    pub rgb: [Vec<f32>; 3],
    /// Coverage ([`Pixel::alpha`]).
    pub alpha: Vec<f32>,
    /// Distance along the primary ray, `+∞` on a miss.
    pub depth: Vec<f32>,
    /// The world-space normal facing the camera, by component; zero on a miss.
    pub normal: [Vec<f32>; 3],
    /// 1-based block index, 0 on a miss.
    pub block: Vec<u32>,
    /// 1-based solid index within the block, 0 on a miss.
    pub object: Vec<u32>,
    /// Adaptive sampling only (else empty): the samples each pixel took.
    pub spp: Vec<u32>,
    /// Adaptive sampling only (else empty): the estimated relative standard
    /// error of each pixel's mean luminance.
    pub error: Vec<f32>,
}

impl Frame {
    /// A frame of `width × rows.len()` pixels, rows `rows` of an image
    /// `image_height` high, every sample zero. The planes are allocated
    /// zeroed (`vec![0.0; n]`), so their pages are mapped only when first
    /// written.
    fn zeroed(width: u32, rows: Range<u32>, image_height: u32, aovs: bool, adaptive: bool) -> Self {
        let height = rows.end - rows.start;
        let n = width as usize * height as usize;
        let f = || vec![0.0f32; n];
        let a = if aovs { n } else { 0 };
        let s = if adaptive { n } else { 0 };
        Frame {
            width,
            height,
            first_row: rows.start,
            image_height,
            rgb: [f(), f(), f()],
            alpha: f(),
            depth: vec![0.0; a],
            normal: [vec![0.0; a], vec![0.0; a], vec![0.0; a]],
            block: vec![0; a],
            object: vec![0; a],
            spp: vec![0; s],
            error: vec![0.0; s],
        }
    }

    /// Whether the frame holds the adaptive sampling planes (`spp`,
    /// `error`).
    pub fn has_adaptive(&self) -> bool {
        !self.spp.is_empty() && self.spp.len() == self.alpha.len() && self.error.len() == self.alpha.len()
    }

    /// Whether the frame holds the AOV planes (`Z`, the normal, the ids):
    /// always, unless rendered with [`Options::colour_only`].
    pub fn has_aovs(&self) -> bool {
        self.depth.len() == self.alpha.len()
    }

    /// The number of pixels, `width * height`.
    pub fn len(&self) -> usize {
        self.alpha.len()
    }

    /// Whether the frame has no pixels.
    pub fn is_empty(&self) -> bool {
        self.alpha.is_empty()
    }

    /// The number of samples in each plane, in EXR channel order
    /// (`R G B A Z N.X N.Y N.Z id.block id.object`): all `width * height`
    /// in a frame [`render`] made.
    pub fn plane_lengths(&self) -> [usize; 10] {
        let ([r, g, b], [nx, ny, nz]) = (&self.rgb, &self.normal);
        let f = [r, g, b, &self.alpha, &self.depth, nx, ny, nz].map(Vec::len);
        [f[0], f[1], f[2], f[3], f[4], f[5], f[6], f[7], self.block.len(), self.object.len()]
    }

    /// The pixel at index `k` of the planes (row `k / width`, column `k % width`).
    /// In a colour-only frame the AOV fields are zero (depth included).
    ///
    /// # Panics
    ///
    /// If `k` is not below [`Frame::len`].
    pub fn pixel(&self, k: usize) -> Pixel {
        let (rgb, alpha) = (self.rgb.each_ref().map(|c| c[k]), self.alpha[k]);
        let (spp, error) = if self.has_adaptive() { (self.spp[k], self.error[k]) } else { (0, 0.0) };
        if !self.has_aovs() {
            return Pixel { rgb, alpha, spp, error, ..Pixel::default() };
        }
        Pixel {
            rgb,
            alpha,
            depth: self.depth[k],
            normal: self.normal.each_ref().map(|c| c[k]),
            block: self.block[k],
            object: self.object[k],
            spp,
            error,
        }
    }

    /// The pixel in row `i` (from the frame's first row) and column `j`.
    ///
    /// # Panics
    ///
    /// If `i * width + j` is not below [`Frame::len`].
    pub fn at(&self, i: u32, j: u32) -> Pixel {
        self.pixel(i as usize * self.width as usize + j as usize)
    }

    /// Every pixel, row by row from the top-left.
    pub fn pixels(&self) -> impl ExactSizeIterator<Item = Pixel> + '_ {
        (0..self.len()).map(|k| self.pixel(k))
    }

    /// The frame cut into runs of `chunk` pixels (the last may be shorter),
    /// each writable on its own.
    fn runs_mut(&mut self, chunk: usize) -> Vec<Run<'_>> {
        let (aovs, adaptive) = (self.has_aovs(), self.has_adaptive());
        let Frame { rgb: [r, g, b], alpha, depth, normal: [nx, ny, nz], block, object, spp, error, .. } = self;
        let mut spp = spp.chunks_mut(chunk);
        let mut error = error.chunks_mut(chunk);
        let mut colour = [r, g, b, alpha].map(|p| p.chunks_mut(chunk));
        // Without AOVs their planes are empty, and so is each run's share.
        let mut f32s = [depth, nx, ny, nz].map(|p| p.chunks_mut(chunk));
        let mut u32s = [block, object].map(|p| p.chunks_mut(chunk));
        let mut runs = Vec::new();
        loop {
            let Some([r, g, b, alpha]) = transpose(colour.each_mut().map(Iterator::next)) else {
                return runs;
            };
            let ([depth, nx, ny, nz], [block, object]) = if aovs {
                match (transpose(f32s.each_mut().map(Iterator::next)), transpose(u32s.each_mut().map(Iterator::next))) {
                    (Some(f), Some(u)) => (f, u),
                    _ => return runs,
                }
            } else {
                (Default::default(), Default::default())
            };
            let (spp, error) = if adaptive {
                match (spp.next(), error.next()) {
                    (Some(s), Some(e)) => (s, e),
                    _ => return runs,
                }
            } else {
                (Default::default(), Default::default())
            };
            runs.push(Run { rgb: [r, g, b], alpha, depth, normal: [nx, ny, nz], block, object, spp, error });
        }
    }
}

/// `Some` of all the items, or `None` if any is missing (the planes have
/// equal lengths, so they run out together).
fn transpose<T, const N: usize>(items: [Option<T>; N]) -> Option<[T; N]> {
    items.into_iter().collect::<Option<Vec<T>>>()?.try_into().ok()
}

/// A run of consecutive pixels of a [`Frame`], writable: the same range of
/// every plane.
struct Run<'a> {
    rgb: [&'a mut [f32]; 3],
    alpha: &'a mut [f32],
    depth: &'a mut [f32],
    normal: [&'a mut [f32]; 3],
    block: &'a mut [u32],
    object: &'a mut [u32],
    spp: &'a mut [u32],
    error: &'a mut [f32],
}

impl Run<'_> {
    fn len(&self) -> usize {
        self.alpha.len()
    }

    /// Writes `pixels` (as many as the run holds) into the planes, a plane
    /// at a time.
    fn fill(&mut self, pixels: &[Pixel]) {
        fn plane<T>(out: &mut [T], pixels: &[Pixel], f: impl Fn(&Pixel) -> T) {
            for (o, p) in out.iter_mut().zip(pixels) {
                *o = f(p);
            }
        }
        for c in 0..3 {
            plane(self.rgb[c], pixels, |p| p.rgb[c]);
            plane(self.normal[c], pixels, |p| p.normal[c]);
        }
        plane(self.alpha, pixels, |p| p.alpha);
        plane(self.depth, pixels, |p| p.depth);
        plane(self.block, pixels, |p| p.block);
        plane(self.object, pixels, |p| p.object);
        plane(self.spp, pixels, |p| p.spp);
        plane(self.error, pixels, |p| p.error);
    }
}

thread_local! {
    /// The pixels of the task a worker is on, before they go into the
    /// frame's planes; kept from task to task, so it is allocated and
    /// first touched once per thread.
    static TASK_PIXELS: RefCell<Vec<Pixel>> = const { RefCell::new(Vec::new()) };
}

/// Renders the run of rows from `i0` on (see [`render_rows`]) into `out`,
/// through the worker's [`TASK_PIXELS`].
fn render_run(renderer: &Renderer, i0: u32, out: &mut Run) -> u64 {
    let n = out.len();
    let mut fresh = Vec::new();
    TASK_PIXELS.with(|buf| {
        let mut borrowed = buf.try_borrow_mut();
        let buf = borrowed.as_deref_mut().unwrap_or(&mut fresh);
        if buf.len() < n {
            buf.resize(n, Pixel::default());
        }
        let rays = match &renderer.sampled {
            Some(sampled) => sampled_rows(&renderer.shader, sampled, i0, &mut buf[..n]),
            None => render_rows(&renderer.shader, i0, &mut buf[..n]),
        };
        out.fill(&buf[..n]);
        rays
    })
}

/// How a render went.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stats {
    /// Rays cast: primary, shadow, reflected and refracted.
    pub rays: u64,
    /// Wall-clock time of the render loop.
    pub elapsed: Duration,
}

impl Stats {
    /// Rays per second.
    pub fn rays_per_second(&self) -> f64 {
        self.rays as f64 / self.elapsed.as_secs_f64().max(1e-9)
    }
}

/// Render options beyond the scene.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Options {
    /// Switches of the path integrator (both on by default).
    pub path: PathOptions,
    /// Worker threads (default: one per core).
    pub threads: Option<usize>,
    /// Only the colour and alpha planes: the frame's AOV planes (`Z`, the
    /// normal, the ids) stay empty ([`Frame::has_aovs`]), for a render whose
    /// output has none (`komplex bench`): 16 of the frame's 40 bytes a
    /// pixel, so fewer pages to map and fill.
    pub colour_only: bool,
    /// Only rows `start .. end` of the image (a band, e.g. a tile of
    /// `komplex render --tile`): the frame holds those rows alone
    /// ([`Frame::first_row`]), each pixel exactly as in the whole image
    /// (pixels are keyed by their place in the whole image). `None`: every
    /// row.
    pub rows: Option<(u32, u32)>,
}

/// A pool builder for `threads` workers (default: one per core), the count
/// checked.
fn pool_builder(threads: Option<usize>) -> Result<rayon::ThreadPoolBuilder, Error> {
    let builder = rayon::ThreadPoolBuilder::new();
    let Some(n) = threads else { return Ok(builder) };
    if n == 0 {
        return Err(Error::Options("--threads must be at least 1".into()));
    }
    // The pool starts every thread at once; far more than any machine's
    // cores only exhausts memory and process limits.
    if n > MAX_THREADS {
        return Err(Error::Options(format!("--threads must be at most {MAX_THREADS}, got {n}")));
    }
    Ok(builder.num_threads(n))
}

/// Sets the number of threads of rayon's global pool, which runs the work
/// outside a render (loading: the block boxes, flattening, the BVH build),
/// so that `--threads N` holds from the start; the render itself runs on a
/// pool of its own ([`Options::threads`]). Call it once, before loading;
/// `None` keeps rayon's default (one per core).
///
/// Errors on a count [`render`] would refuse (0, more than
/// [`MAX_THREADS`]), and if the global pool was already started.
pub fn set_global_threads(threads: Option<usize>) -> Result<(), Error> {
    let builder = pool_builder(threads)?;
    if threads.is_none() {
        return Ok(());
    }
    builder.build_global().map_err(|e| Error::Options(format!("cannot start worker threads: {e}")))
}

/// Renders `world` with its camera. `progress` is called once per finished
/// row (from worker threads).
pub fn render(world: &World, options: Options, progress: &(dyn Fn() + Sync)) -> Result<(Frame, Stats), Error> {
    render_until(world, options, progress, &AtomicBool::new(false))
}

/// [`render`], stopping early with [`Error::Interrupted`] once `cancel` is
/// set (e.g. by a Ctrl-C handler). Workers look at the flag before each task
/// (a band of sixteen rows), so the render stops within about one band's time.
pub fn render_until(
    world: &World,
    options: Options,
    progress: &(dyn Fn() + Sync),
    cancel: &AtomicBool,
) -> Result<(Frame, Stats), Error> {
    let pixels = u64::from(world.camera.width()) * u64::from(world.camera.height());
    if pixels > MAX_PIXELS {
        return Err(Error::Options(format!(
            "the image has {pixels} pixels; at most {MAX_PIXELS} are supported (about 16k x 16k)"
        )));
    }
    let image_height = world.camera.height();
    let rows = match options.rows {
        None => 0..image_height,
        Some((start, end)) if start < end && end <= image_height => start..end,
        Some((start, end)) => {
            return Err(Error::Options(format!(
                "rows {start}..{end} are not a non-empty band of the image's {image_height} rows"
            )))
        }
    };
    let pool = pool_builder(options.threads)?
        .build()
        .map_err(|e| Error::Options(format!("cannot start worker threads: {e}")))?;
    let start = Instant::now();
    // Rows are written in place: the frame is the only full-size buffer
    // (a collected list of rows would double the peak memory). Its pages are
    // first touched here, by the workers, in parallel.
    let width = world.camera.width() as usize;
    // One renderer for the frame, shared by the workers.
    let renderer = Renderer::new(world, options.path);
    let adaptive = renderer.sampled.as_ref().is_some_and(|s| s.noise.is_some());
    let first_row = rows.start;
    let mut frame = Frame::zeroed(world.camera.width(), rows, image_height, !options.colour_only, adaptive);
    let runs = frame.runs_mut(width * ROWS);
    // Every band of rows is its own task, taken in order from one queue by
    // whichever worker is free: rows differ in cost by orders of
    // magnitude (sky against glass), so a split made early from the thread
    // count alone (rayon's adaptive split) leaves one of two cores idle for
    // a quarter of the glass scene; and the workers render neighbouring bands,
    // which meet the same blocks, so a large scene's data is fetched into
    // the shared cache once for all of them (a split in halves has each
    // worker walk a different half of the scene).
    let runs = Mutex::new(runs.into_iter().enumerate());
    // The lock is held only to take the next run (a poisoned lock, after a
    // panic in another worker, ends this one too).
    let take = || runs.lock().ok().and_then(|mut r| r.next());
    let rays: u64 = pool
        .broadcast(|_| {
            let mut rays = 0;
            while let Some((b, mut out)) = take() {
                if cancel.load(Ordering::Relaxed) {
                    break;
                }
                rays += render_run(&renderer, first_row + (b * ROWS) as u32, &mut out);
                for _ in 0..out.len() / width {
                    progress();
                }
            }
            rays
        })
        .into_iter()
        .sum();
    let elapsed = start.elapsed();
    if cancel.load(Ordering::Relaxed) {
        return Err(Error::Interrupted);
    }
    Ok((frame, Stats { rays, elapsed }))
}

/// The smallest number of samples a pixel takes under adaptive sampling
/// (`settings.noise`, `--noise`), unless `spp` is smaller: fewer give too
/// poor an estimate of the pixel's variance to stop on.
pub const MIN_ADAPTIVE_SPP: u32 = 16;

/// Under adaptive sampling, a pixel not yet within its error bound takes
/// this many samples more before it is checked again.
const ADAPTIVE_BATCH: u32 = 8;

/// How the pixels of a render are estimated, shared by the workers.
struct Renderer<'w> {
    shader: Shader<'w>,
    /// `Some` when pixels take random samples (docs/model.md §5.10.5):
    /// under the path integrator, or when `settings.spp` is given.
    sampled: Option<Sampled<'w>>,
}

/// Random sampling of pixels.
struct Sampled<'w> {
    /// The path integrator; `None`: Whitted shading of each sample.
    tracer: Option<PathTracer<'w>>,
    /// Samples per pixel (the most, under adaptive sampling).
    spp: u32,
    /// Adaptive sampling's bound on the relative standard error.
    noise: Option<f64>,
    seed: u64,
}

impl<'w> Renderer<'w> {
    fn new(world: &'w World, path: PathOptions) -> Self {
        let s = &world.settings;
        let shader = Shader::new(world);
        let is_path = s.integrator == Integrator::Path;
        if !is_path && s.spp.is_none() && s.noise.is_none() {
            return Renderer { shader, sampled: None };
        }
        let tracer = is_path.then(|| PathTracer::new(world, path));
        let spp = s.spp.unwrap_or(s.samples.max(1).saturating_mul(s.samples.max(1)));
        Renderer { shader, sampled: Some(Sampled { tracer, spp, noise: s.noise, seed: s.seed }) }
    }
}

/// Whether an error estimate (perhaps NaN or infinite) is within the bound.
fn within(error: f64, bound: f64) -> bool {
    error <= bound
}

/// The luminance of linear Rec. 709 RGB.
fn luminance(c: &Vector3<f64>) -> f64 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// The relative standard error of a mean of `n` samples from Welford's
/// running `mean` and sum of squared deviations `m2`: `0` for samples all
/// zero, `∞` for fewer than two or a zero mean of samples not all zero.
fn relative_error(mean: f64, m2: f64, n: u32) -> f64 {
    if n < 2 {
        return f64::INFINITY;
    }
    let n = f64::from(n);
    let se = (m2.max(0.0) / (n - 1.0) / n).sqrt();
    if se == 0.0 {
        0.0
    } else if mean > 0.0 {
        se / mean
    } else {
        f64::INFINITY
    }
}

impl Sampled<'_> {
    /// Pixel `(i, j)`: the mean of its samples, each a ray through a random
    /// point of the pixel (a box filter) and of the lens; the AOVs of the
    /// pinhole ray through its centre. Under adaptive sampling, the pixel
    /// takes [`MIN_ADAPTIVE_SPP`] samples, then [`ADAPTIVE_BATCH`] more at a
    /// time until the relative standard error of its mean luminance is
    /// within `noise` or it has `spp`.
    fn pixel(&self, shader: &Shader, cam: &Camera, (i, j): (u32, u32), scratch: &mut Scratch) -> Pixel {
        let hit = shader.primary_hit(&cam.ray(i, j), scratch);
        let key = u64::from(i) * u64::from(cam.width()) + u64::from(j);
        let mut target = if self.noise.is_some() { MIN_ADAPTIVE_SPP.min(self.spp) } else { self.spp };
        let (mut sum, mut covered, mut n) = (Vector3::zeros(), 0u32, 0u32);
        let (mut mean, mut m2) = (0.0, 0.0);
        loop {
            while n < target {
                let sampler = Sampler::new(self.seed, key, u64::from(n));
                let [u, v] = sampler.uniform2(0);
                let lens = sampler.uniform2(2);
                let ray = cam.lens_ray(f64::from(i) + u - 0.5, f64::from(j) + v - 0.5, (lens[0], lens[1]));
                let (mut c, h) = match &self.tracer {
                    Some(t) => t.radiance(&ray, &sampler, scratch),
                    None => {
                        let (c, h) = shader.primary(&ray, scratch);
                        (c, h.is_some())
                    }
                };
                // A non-finite sample (an overflow) would poison the pixel:
                // it counts as black.
                if !c.iter().all(|x| x.is_finite()) {
                    c = Vector3::zeros();
                }
                n += 1;
                sum += c;
                covered += u32::from(h);
                let y = luminance(&c);
                let delta = y - mean;
                mean += delta / f64::from(n);
                m2 += delta * (y - mean);
            }
            match self.noise {
                Some(t) if n < self.spp && !within(relative_error(mean, m2, n), t) => {
                    target = n.saturating_add(ADAPTIVE_BATCH).min(self.spp);
                }
                _ => break,
            }
        }
        let mut p = pixel_of(sum / f64::from(n), (f64::from(covered) / f64::from(n)) as f32, hit);
        if self.noise.is_some() {
            p.spp = n;
            p.error = relative_error(mean, m2, n) as f32;
        }
        p
    }
}

/// Renders the rows from `i0` on into `out` (whole rows), each pixel from
/// its random samples.
fn sampled_rows(shader: &Shader, sampled: &Sampled, i0: u32, out: &mut [Pixel]) -> u64 {
    let mut scratch = Scratch::default();
    let cam = &shader.world().camera;
    let width = cam.width() as usize;
    for (k, pixel) in out.iter_mut().enumerate() {
        let at = (i0 + (k / width) as u32, (k % width) as u32);
        *pixel = sampled.pixel(shader, cam, at, &mut scratch);
    }
    scratch.rays
}

/// Rows per render task (a band): a multiple of two, so that four rays of
/// a 2×2 square of pixels can share one walk of the BVH; sixteen, so that
/// a band's tiles are square (see [`COLS`]), while the last band a worker
/// finishes alone is still short.
const ROWS: usize = 16;

/// Columns of a tile: a task's rows are rendered [`COLS`] columns at a
/// time, so that the rays that follow each other are neighbours in both
/// directions and find the blocks and nodes their neighbours read still in
/// the cache. A multiple of four, so that the 2×2 squares and 1×4 runs
/// fall on the same pixels as over whole rows.
const COLS: usize = 16;

/// Renders the rows from `i0` on into `out` (whole rows, at most
/// [`ROWS`]), returning the rays cast.
fn render_rows(shader: &Shader, i0: u32, out: &mut [Pixel]) -> u64 {
    let world = shader.world();
    let mut scratch = Scratch::default();
    let cam = &world.camera;
    let width = cam.width() as usize;
    let n = world.settings.samples.max(1);
    if n > 1 {
        for (di, row) in out.chunks_exact_mut(width).enumerate() {
            for (j, pixel) in (0..cam.width()).zip(row.iter_mut()) {
                *pixel = supersampled(shader, &mut scratch, cam, i0 + di as u32, j, n);
            }
        }
        return scratch.rays;
    }
    let rows = out.len() / width;
    for j0 in (0..width).step_by(COLS) {
        let j1 = (j0 + COLS).min(width);
        let mut r = 0;
        while r < rows {
            let i = i0 + r as u32;
            let pair = if rows - r >= 2 { 2 } else { 1 };
            // The pixel centres four at a time (docs/model.md §4.2): 2×2 squares, or
            // 1×4 runs on a last single row. The four rays share one walk of
            // the BVH (`Shader::primary4`), with the same results as one by
            // one.
            let tile_w = if pair == 2 { 2 } else { 4 };
            let mut j = j0;
            while j + tile_w <= j1 {
                let at = |k: usize| (i + (k / tile_w) as u32, (j + k % tile_w) as u32);
                let rays = cam.rays4([0, 1, 2, 3].map(|k| {
                    let (i, j) = at(k);
                    (f64::from(i), f64::from(j))
                }));
                for (k, (c, hit)) in shader.primary4(&rays, &mut scratch).into_iter().enumerate() {
                    let (i, j) = at(k);
                    out[(i - i0) as usize * width + j as usize] =
                        pixel_of(c, if hit.is_some() { 1.0 } else { 0.0 }, hit);
                }
                j += tile_w;
            }
            // Left over at the end of a row (only in the last tile).
            for i in i..i + pair as u32 {
                for j in j as u32..j1 as u32 {
                    let (c, hit) = shader.primary(&cam.ray(i, j), &mut scratch);
                    out[(i - i0) as usize * width + j as usize] =
                        pixel_of(c, if hit.is_some() { 1.0 } else { 0.0 }, hit);
                }
            }
            r += pair;
        }
    }
    scratch.rays
}

/// Pixel `(i, j)` from an `n × n` stratified grid of sub-pixel rays (each
/// from its own point of the lens, if the camera has one): the mean of
/// their colours, the fraction that hit, and the AOVs of the pinhole ray
/// through the centre (docs/model.md §4.3, §4.5). The sub-pixel rays go four at a time
/// through [`Shader::primary4`], summed in the same order as one by one.
fn supersampled(shader: &Shader, scratch: &mut Scratch, cam: &Camera, i: u32, j: u32, n: u32) -> Pixel {
    // The centre ray only for the AOVs: its colour would not be used.
    let hit = shader.primary_hit(&cam.ray(i, j), scratch);
    let sub = |k: u32| {
        let (a, b) = (k / n, k % n);
        let di = (f64::from(a) + 0.5) / f64::from(n) - 0.5;
        let dj = (f64::from(b) + 0.5) / f64::from(n) - 0.5;
        (f64::from(i) + di, f64::from(j) + dj)
    };
    // With a lens, sub-pixel ray `(a, b)` leaves the lens from the centre
    // of cell `(b, (a + b) mod n)` of an `n × n` grid on the lens square
    // (docs/model.md §4.5): a Latin square, so that every lens cell is used
    // once and each row or column of sub-pixels sees every lens row.
    let lens = |k: u32| {
        let (a, b) = (k / n, k % n);
        ((f64::from(b) + 0.5) / f64::from(n), (f64::from((a + b) % n) + 0.5) / f64::from(n))
    };
    let ray = |k: u32| {
        let (i, j) = sub(k);
        cam.lens_ray(i, j, lens(k))
    };
    let pinhole = cam.lens_radius() == 0.0;
    let mut c = Vector3::zeros();
    let mut covered = 0u32;
    let count = n * n;
    let mut k = 0;
    while k + 4 <= count {
        let rays = if pinhole {
            cam.rays4([sub(k), sub(k + 1), sub(k + 2), sub(k + 3)])
        } else {
            [k, k + 1, k + 2, k + 3].map(ray)
        };
        for (cs, h) in shader.primary4(&rays, scratch) {
            c += cs;
            covered += u32::from(h.is_some());
        }
        k += 4;
    }
    for k in k..count {
        let (cs, h) = shader.primary(&ray(k), scratch);
        c += cs;
        covered += u32::from(h.is_some());
    }
    c /= f64::from(count);
    pixel_of(c, (f64::from(covered) / f64::from(count)) as f32, hit)
}

/// The pixel of colour `c`, coverage `alpha` and the centre ray's `hit`.
fn pixel_of(c: Vector3<f64>, alpha: f32, hit: Option<PrimaryHit>) -> Pixel {
    let rgb = [c.x as f32, c.y as f32, c.z as f32];
    match hit {
        None => Pixel { rgb, alpha, depth: f32::INFINITY, ..Pixel::default() },
        Some(s) => Pixel {
            rgb,
            alpha,
            depth: s.t as f32,
            normal: [s.normal.x as f32, s.normal.y as f32, s.normal.z as f32],
            block: s.block.0 + 1,
            object: s.solid + 1,
            ..Pixel::default()
        },
    }
}
