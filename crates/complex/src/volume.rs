//! Volumes and overlaps, measured by integrating exact chord lengths over
//! grids of parallel lines (Cavalieri: a solid's volume is the integral of
//! its chord length over the plane perpendicular to the lines).
//!
//! One *replicate* is a lattice of parallel lines in a random direction:
//! the box to measure is projected onto the plane perpendicular to the
//! direction, and the lines cross the projection's bounding rectangle at
//! the points of a randomly shifted Fibonacci lattice ([`Grid`]). Each
//! line's chords (the block's intervals, the partition's owned segments,
//! two blocks' shared intervals) are exact up to the kernel's rounding, so
//! a replicate's estimate `area per line × Σ chords` is unbiased;
//! replicates are independent, and the standard error is their sample
//! standard deviation over `√R`, widened by Student's t (see
//! [`t_factor`]). Rounds of replicates with more lines follow until every
//! standard error is below the tolerance. Randomness comes from a hash of
//! (seed, replicate), and the lines are cut into fixed chunks summed in
//! order: the result does not depend on the number of threads.

use quadric::nalgebra::{Point3, Vector3};
use quadric::{Interval, Ray};
use rayon::prelude::*;

use crate::partition::{BlockSpans, Partition};
use crate::{Aabb, BlockId, Complex, ComplexError};

/// The default relative standard error of [`Complex::volumes`] and [`Complex::overlaps`].
pub const DEFAULT_VOLUME_TOLERANCE: f64 = 1e-3;

/// Lines per chunk of a replicate: a line costs about a microsecond in a
/// small scene, so a chunk is far above rayon's cost of a task.
const LINES_PER_CHUNK: u64 = 512;

/// At most this many partial sums (one per quantity and chunk) are held at
/// once: 32 MiB of doubles, whatever the number of blocks.
const SUM_BUDGET: usize = 1 << 22;

/// How fast the standard error is assumed to fall with the lines per
/// replicate `M` when planning the second round (`SE ∝ M^(-ALPHA)`): a
/// cautious value (the lattice does better on the shapes of the tests,
/// `M^(-1.25)` to `M^(-1.5)`, but a chord length with jumps, from a face
/// parallel to the lines, falls slower). Later rounds measure the rate
/// from the last two.
const ALPHA: f64 = 1.0;

/// A shared chord of two blocks shorter than this fraction of the diagonal
/// of their common box is rounding (two blocks that only touch), not overlap.
const SHARED_CHORD_MIN: f64 = 1e-9;

/// Options of [`Complex::volumes`] and [`Complex::overlaps`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VolumeOptions {
    /// The target relative standard error of every volume measured
    /// (default [`DEFAULT_VOLUME_TOLERANCE`]); finite and `> 0`.
    pub tolerance: f64,
    /// Volumes smaller than `floor` times the volume of the box measured
    /// are measured to an absolute error of `tolerance · floor · box volume`
    /// instead (a relative error means nothing for a volume near zero);
    /// default `1e-6`, in `[0, 1]`.
    pub floor: f64,
    /// The seed of the random directions and offsets (default 0).
    pub seed: u64,
    /// Clip everything to this box: the volumes are those of the blocks'
    /// parts inside it, and unbounded blocks get one (default `None`).
    pub bounds: Option<Aabb>,
    /// Independent replicates per round, at least 8 (default 32).
    pub replicates: u32,
    /// Lines of the first round over all replicates (default 8192).
    pub initial_lines: u64,
    /// The most lines one round may use over all replicates (default
    /// 2²⁴); a round that needs more is run with this many and the result
    /// reported as not converged.
    pub max_lines: u64,
    /// [`Complex::overlaps`] measures no pair if more pairs of blocks than
    /// this have overlapping boxes (default 100,000).
    pub max_pairs: usize,
}

impl Default for VolumeOptions {
    fn default() -> Self {
        VolumeOptions {
            tolerance: DEFAULT_VOLUME_TOLERANCE,
            floor: 1e-6,
            seed: 0,
            bounds: None,
            replicates: 32,
            initial_lines: 8192,
            max_lines: 1 << 24,
            max_pairs: 100_000,
        }
    }
}

impl VolumeOptions {
    /// `Err(ComplexError::BadVolumeOption)` naming the first option out of range.
    fn check(&self) -> Result<(), ComplexError> {
        let bad = |option, expected, value: f64| Err(ComplexError::BadVolumeOption { option, expected, value });
        if !(self.tolerance.is_finite() && self.tolerance > 0.0) {
            return bad("tolerance", "a finite number > 0", self.tolerance);
        }
        if !(0.0..=1.0).contains(&self.floor) {
            return bad("floor", "a number in [0, 1]", self.floor);
        }
        if self.replicates < 8 {
            return bad("replicates", "at least 8", f64::from(self.replicates));
        }
        if self.initial_lines == 0 || self.max_lines == 0 {
            let (option, value) =
                if self.initial_lines == 0 { ("initial_lines", 0.0) } else { ("max_lines", self.max_lines as f64) };
            return bad(option, "at least 1", value);
        }
        if let Some(b) = self.bounds {
            let finite = b.min.iter().chain(b.max.iter()).all(|c| c.is_finite());
            if !finite || (0..3).any(|i| b.min[i] > b.max[i]) {
                return Err(ComplexError::BadVolumeBounds);
            }
        }
        Ok(())
    }
}

/// A measured volume and its standard error.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Estimate {
    /// The estimate (unbiased).
    pub value: f64,
    /// Its standard error, widened for the number of replicates: the true
    /// value lies within three of them in about 99.7 % of runs.
    pub error: f64,
}

/// One block's volumes (`None`: the block is unbounded and no box clips it).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BlockVolume {
    /// The volume the block owns under the priority rule (its part of the
    /// union; docs/model.md §3.4).
    pub owned: Option<Estimate>,
    /// The block's own volume, ignoring the others.
    pub own: Option<Estimate>,
}

/// What [`Complex::volumes`] measured.
#[derive(Clone, Debug, PartialEq)]
pub struct Volumes {
    /// One entry per block, in priority order.
    pub blocks: Vec<BlockVolume>,
    /// The volume of the union (`None` if a block is unbounded and no box clips it).
    pub union: Option<Estimate>,
    /// The box the lines cover: [`VolumeOptions::bounds`], else the box
    /// around the bounded blocks (empty if there is none).
    pub bounds: Aabb,
    /// Lines of the last round, over all replicates (the one reported).
    pub lines: u64,
    /// Replicates per round.
    pub replicates: u32,
    /// Rounds run.
    pub rounds: u32,
    /// Whether every standard error reached the tolerance (else the
    /// round cap [`VolumeOptions::max_lines`] was hit).
    pub converged: bool,
}

/// What [`Complex::group_volumes`] measures.
#[derive(Clone, Debug, PartialEq)]
pub struct GroupVolumes {
    /// Per group, the volume its blocks own (`None` if one is unbounded and no box clips it).
    pub groups: Vec<Option<Estimate>>,
    /// The volume of the union.
    pub union: Option<Estimate>,
    /// The box the lines cover.
    pub bounds: Aabb,
    /// Lines of the last round, over all replicates.
    pub lines: u64,
    /// Replicates per round.
    pub replicates: u32,
    /// Rounds run.
    pub rounds: u32,
    /// Whether every group's and the union's standard error reached the tolerance.
    pub converged: bool,
}

/// Two blocks whose own regions share a positive volume.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Overlap {
    /// The first block (the lower id).
    pub a: BlockId,
    /// The second block.
    pub b: BlockId,
    /// The volume they share.
    pub volume: Estimate,
    /// A point inside both: the midpoint of the longest shared chord found,
    /// checked with both blocks' [`crate::Block::contains_point`].
    pub point: Point3<f64>,
}

/// What [`Complex::overlaps`] found.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Overlaps {
    /// The overlapping pairs, by `(a, b)`.
    pub pairs: Vec<Overlap>,
    /// Pairs of blocks whose boxes overlap with positive volume (within
    /// [`VolumeOptions::bounds`]), the candidates; counted up to
    /// `max_pairs + 1`.
    pub candidates: usize,
    /// Whether the candidates were too many ([`VolumeOptions::max_pairs`])
    /// and none was measured.
    pub skipped: bool,
    /// Candidate pairs not measured because their common box is unbounded
    /// (give [`VolumeOptions::bounds`] to measure them).
    pub unbounded: Vec<(BlockId, BlockId)>,
    /// Whether every measured pair's standard error reached the tolerance.
    pub converged: bool,
    /// Lines cast over all pairs and rounds.
    pub lines: u64,
}

/// Student's t quantile over the normal one at the two-sided 99.73 % level
/// (three standard errors) for `R` replicates (`R - 1` degrees of
/// freedom), by the Cornish–Fisher series (within 0.1 % for `R ≥ 8`): the
/// factor the sample standard error is widened by so that three of them
/// cover the true value as often as three true standard errors would.
pub(crate) fn t_factor(replicates: u32) -> f64 {
    let z: f64 = 3.0;
    let nu = f64::from(replicates.max(2) - 1);
    let t = z
        + (z.powi(3) + z) / (4.0 * nu)
        + (5.0 * z.powi(5) + 16.0 * z.powi(3) + 3.0 * z) / (96.0 * nu * nu)
        + (3.0 * z.powi(7) + 19.0 * z.powi(5) + 17.0 * z.powi(3) - 15.0 * z) / (384.0 * nu.powi(3));
    t / z
}

/// SplitMix64's finaliser: a counter-based generator (the same numbers for
/// the same keys, on any thread).
fn mix(mut x: u64) -> u64 {
    x = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    x = (x ^ (x >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    x ^ (x >> 31)
}

/// A uniform number in `[0, 1)` for the keys.
fn uniform(key: u64, i: u64) -> f64 {
    (mix(key ^ mix(i)) >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// The volume of a bounded box.
fn box_volume(b: &Aabb) -> f64 {
    let s = b.size();
    s.x * s.y * s.z
}

/// One replicate: a lattice of parallel lines across a box.
///
/// The lines cross the plane perpendicular to the direction at the points
/// of a Fibonacci lattice (`F_k` points `(j/F_k, j·F_(k-1)/F_k)` mod 1, the
/// best two-dimensional rank-1 lattice rule) stretched over the bounding
/// rectangle of the box's projection and shifted by a uniform random
/// vector, modulo the rectangle (Cranley–Patterson rotation). Each point
/// alone is then uniform over the rectangle, so `area / F_k × Σ chords` is
/// an unbiased estimate of the volume; the lattice spreads the points far
/// more evenly than independent ones (or one jittered point per cell), so
/// the error falls about as `F_k^(-1.25)` to `F_k^(-1.5)` on the shapes of
/// the tests, against `F_k^(-1)` for jittered cells and `F_k^(-1/2)` for
/// independent points (docs/geometry.md, "Error against time").
struct Grid {
    center: Point3<f64>,
    d: Vector3<f64>,
    u: Vector3<f64>,
    v: Vector3<f64>,
    /// How far behind the centre every line starts: outside the box.
    back: f64,
    /// The lower corner of the projected rectangle, in `(u, v)`, and its sides.
    u0: f64,
    v0: f64,
    width: f64,
    height: f64,
    /// The lattice: `n = F_k` points, generator `g = F_(k-1)`, the random shift.
    n: u64,
    g: u64,
    shift: (f64, f64),
}

impl Grid {
    /// Replicate `replicate` of at most `lines` lines (the largest
    /// Fibonacci number not above it, at least 2) across the bounded box `b`.
    fn new(b: &Aabb, seed: u64, replicate: u64, lines: u64) -> Grid {
        let key = mix(mix(seed) ^ replicate.wrapping_mul(0xD6E8_FEB8_6659_FD93));
        // A direction uniform on the sphere.
        let z = 2.0 * uniform(key, 0) - 1.0;
        let phi = core::f64::consts::TAU * uniform(key, 1);
        let r = (1.0 - z * z).max(0.0).sqrt();
        let d = Vector3::new(r * phi.cos(), r * phi.sin(), z);
        // The axis least aligned with d completes an orthonormal basis.
        let axis = (0..3).min_by(|&i, &j| d[i].abs().total_cmp(&d[j].abs())).unwrap_or(0);
        let u = d.cross(&Vector3::ith(axis, 1.0)).normalize();
        let v = d.cross(&u);
        let center = b.center().unwrap_or_else(Point3::origin);
        let h = b.size() * 0.5;
        // The box's extent along a unit vector w is Σ|w_i| h_i either side.
        let extent = |w: &Vector3<f64>| w.abs().dot(&h);
        let (eu, ev) = (extent(&u), extent(&v));
        let (mut g, mut n) = (1u64, 2u64);
        // At most about 2⁴⁰ lines a replicate, far beyond any cap.
        while g + n <= lines && n < (1 << 40) {
            (g, n) = (n, g + n);
        }
        // Far enough behind that every line enters the box well after ε.
        let back = 1.25 * h.norm() + 1.0;
        Grid {
            center,
            d,
            u,
            v,
            back,
            u0: -eu,
            v0: -ev,
            width: 2.0 * eu,
            height: 2.0 * ev,
            n,
            g,
            shift: (uniform(key, 2), uniform(key, 3)),
        }
    }

    fn lines(&self) -> u64 {
        self.n
    }

    /// The area each line stands for.
    fn cell_area(&self) -> f64 {
        self.width * self.height / self.n as f64
    }

    /// Line `j`: through lattice point `j`.
    fn line(&self, j: u64) -> Option<Ray> {
        let n = self.n as f64;
        // `j · g mod n` exactly (in u128: the product exceeds 64 bits).
        let jg = (u128::from(j) * u128::from(self.g) % u128::from(self.n)) as f64;
        let x = (j as f64 / n + self.shift.0).fract();
        let y = (jg / n + self.shift.1).fract();
        let (a, b) = (self.u0 + x * self.width, self.v0 + y * self.height);
        Ray::new(self.center + a * self.u + b * self.v - self.back * self.d, self.d).ok()
    }
}

/// The length of `[start, end] ∩ [lo, hi]`.
fn clipped(start: f64, end: f64, lo: f64, hi: f64) -> f64 {
    (end.min(hi) - start.max(lo)).max(0.0)
}

/// The standard errors of one round: per quantity, the mean over
/// replicates and the widened standard error of the mean.
struct Stats {
    /// The first replicate's values, subtracted before summing (a shift
    /// that keeps the sum of squares free of cancellation).
    shift: Vec<f64>,
    sum: Vec<f64>,
    sum2: Vec<f64>,
    n: u32,
}

impl Stats {
    fn new(q: usize) -> Stats {
        Stats { shift: Vec::new(), sum: vec![0.0; q], sum2: vec![0.0; q], n: 0 }
    }

    fn add(&mut self, x: &[f64]) {
        if self.shift.is_empty() {
            self.shift = x.to_vec();
        }
        for (k, &v) in x.iter().enumerate() {
            let y = v - self.shift[k];
            self.sum[k] += y;
            self.sum2[k] += y * y;
        }
        self.n += 1;
    }

    fn estimate(&self, k: usize) -> Estimate {
        let n = f64::from(self.n.max(1));
        let (s, s2) = (self.sum[k], self.sum2[k]);
        let shift = self.shift.get(k).copied().unwrap_or(0.0);
        let var = if self.n > 1 { ((s2 - s * s / n) / (n - 1.0)).max(0.0) } else { 0.0 };
        Estimate { value: shift + s / n, error: (var / n).sqrt() * t_factor(self.n) }
    }
}

/// Runs `replicates` replicates of at most `per_replicate` lines across the
/// bounded box `b`: `line(ray, lo, hi, scratch, sums)` adds a line's chords
/// (within `[lo, hi]`, the part of the ray in the box) to `q` sums. The
/// replicates' estimates go into `stats`; each chunk's scratch is handed to
/// `keep` in order (the overlaps' witnesses). The lines of a replicate are
/// cut into fixed chunks and summed in order: the same result on any
/// number of threads.
#[allow(clippy::too_many_arguments)]
fn run_round<S: Send>(
    b: &Aabb,
    seed: u64,
    replicates: u32,
    per_replicate: u64,
    q: usize,
    scratch: impl Fn() -> S + Sync,
    line: impl Fn(&Ray, f64, f64, &mut S, &mut [f64]) + Sync,
    mut keep: impl FnMut(S),
    stats: &mut Stats,
) -> u64 {
    let grids: Vec<Grid> = (0..u64::from(replicates)).map(|r| Grid::new(b, seed, r, per_replicate)).collect();
    let lines: u64 = grids.iter().map(Grid::lines).sum();
    let max_chunks = (SUM_BUDGET / q.max(1)).max(1) as u64;
    // Tasks: (replicate, first line, end), fixed by the grids alone.
    let mut tasks = Vec::new();
    for (r, g) in grids.iter().enumerate() {
        // A chunk zeroes and adds `q` sums: with many blocks, more lines a
        // chunk keep that below a few per cent of the lines' own cost.
        let chunks = g.lines().div_ceil(LINES_PER_CHUNK.max(q as u64 / 64)).clamp(1, max_chunks);
        let size = g.lines().div_ceil(chunks);
        let mut start = 0;
        while start < g.lines() {
            tasks.push((r, start, (start + size).min(g.lines())));
            start += size;
        }
    }
    let work = |&(r, start, end): &(usize, u64, u64)| {
        let g = &grids[r];
        let mut s = scratch();
        let mut sums = vec![0.0; q];
        for j in start..end {
            let Some(ray) = g.line(j) else { continue };
            if let Some((lo, hi)) = b.ray_range(&ray, f64::INFINITY) {
                line(&ray, lo, hi, &mut s, &mut sums);
            }
        }
        (r, sums, s)
    };
    // Groups of tasks whose partial sums fit the budget, each in parallel.
    let group = (SUM_BUDGET / q.max(1)).max(1);
    let mut values = vec![0.0; q];
    let mut current = 0;
    for part in tasks.chunks(group) {
        let done: Vec<(usize, Vec<f64>, S)> =
            if part.len() == 1 { part.iter().map(work).collect() } else { part.par_iter().map(work).collect() };
        for (r, sums, s) in done {
            if r != current {
                finish(&grids[current], &mut values, stats);
                current = r;
            }
            for (v, x) in values.iter_mut().zip(&sums) {
                *v += x;
            }
            keep(s);
        }
    }
    finish(&grids[current], &mut values, stats);
    lines
}

/// A replicate's sums of chords times the area per line: its estimates.
fn finish(g: &Grid, values: &mut [f64], stats: &mut Stats) {
    let area = g.cell_area();
    for v in values.iter_mut() {
        *v *= area;
    }
    stats.add(values);
    values.fill(0.0);
}

/// Plans the rounds: the lines per replicate of the next one from the
/// worst ratio of standard error to target, with `SE ∝ M^(-α)` and `α`
/// measured from the last two rounds (else [`ALPHA`]).
struct Planner {
    per_replicate: u64,
    cap: u64,
    last: Option<(u64, f64)>,
}

impl Planner {
    fn new(options: &VolumeOptions) -> Planner {
        let replicates = u64::from(options.replicates);
        let cap = (options.max_lines / replicates).max(1);
        Planner { per_replicate: options.initial_lines.div_ceil(replicates).clamp(1, cap), cap, last: None }
    }

    /// After a round of `used` lines per replicate (the lattice's, at
    /// most those asked for) whose worst ratio was `worst`: `Some(lines
    /// per replicate)` to ask for next, or `None` if the cap was reached.
    fn next(&mut self, worst: f64, used: u64) -> Option<u64> {
        let m = used.max(1);
        let alpha = match self.last {
            Some((m0, w0)) if w0 > worst && worst > 0.0 => {
                ((w0 / worst).ln() / (m as f64 / m0 as f64).ln()).clamp(0.6, 2.0)
            }
            _ => ALPHA,
        };
        self.last = Some((m, worst));
        if self.per_replicate >= self.cap {
            return None;
        }
        // At least twice as many: past the next Fibonacci number.
        let grow = (worst.powf(1.0 / alpha) * 1.1).clamp(2.0, 64.0);
        self.per_replicate = ((m as f64 * grow).ceil() as u64).min(self.cap);
        Some(self.per_replicate)
    }
}

/// The quantities one round measures in a scene: each block's own volume,
/// each block's owned volume, the union's.
struct SceneLine {
    spans: BlockSpans,
    cuts: Vec<f64>,
    partition: Partition,
}

impl Complex {
    /// Every block's volume: the part it owns under the priority rule, its
    /// own ignoring the others, and the union's, each with a standard
    /// error, measured by exact chord lengths over random grids of parallel
    /// lines (the module's documentation; `docs/geometry.md`). Rounds with
    /// more lines follow until every relative standard error is at most
    /// `options.tolerance` (for volumes below `floor` of the box's, an
    /// absolute one) or a round would exceed `max_lines`
    /// ([`Volumes::converged`]). An unbounded block's volumes (and the
    /// union's) are `None` unless `options.bounds` clips everything to a
    /// box. Parallel on rayon's current pool, the same result for any
    /// number of threads; `Err(ComplexError::BadVolumeOption)` or
    /// `BadVolumeBounds` for options out of range.
    ///
    /// ```
    /// use complex::{Block, Complex, ComplexOptions, MaterialKey, Opacity, VolumeOptions};
    /// use quadric::nalgebra::Vector3;
    /// use quadric::{Quadric, Solid, Transform};
    /// let ball = |x: f64| {
    ///     let m = Transform::translate(Vector3::new(x, 0.0, 0.0)).unwrap();
    ///     Block::new("ball", vec![Solid::from(Quadric::sphere().transformed(&m))], Opacity::Opaque, MaterialKey(0))
    ///         .unwrap()
    /// };
    /// // Two unit balls whose centres are one apart: the first owns all of
    /// // itself, the second what the first leaves.
    /// let scene = Complex::new(vec![ball(0.0), ball(1.0)], ComplexOptions::default()).unwrap();
    /// let v = scene.volumes(&VolumeOptions { tolerance: 1e-3, ..VolumeOptions::default() }).unwrap();
    /// let ball_volume = 4.0 / 3.0 * std::f64::consts::PI;
    /// let lens = 5.0 / 12.0 * std::f64::consts::PI; // two caps of height 1/2
    /// let first = v.blocks[0].owned.unwrap();
    /// assert!((first.value - ball_volume).abs() < 4.0 * first.error);
    /// let second = v.blocks[1].owned.unwrap();
    /// assert!((second.value - (ball_volume - lens)).abs() < 4.0 * second.error);
    /// assert!(second.error <= 1e-3 * second.value);
    /// let union = v.union.unwrap();
    /// assert!((union.value - (2.0 * ball_volume - lens)).abs() < 4.0 * union.error);
    /// ```
    pub fn volumes(&self, options: &VolumeOptions) -> Result<Volumes, ComplexError> {
        options.check()?;
        let n = self.len();
        let (bounds, measured) = self.measured_blocks(options);
        let union_measured = measured.iter().all(|&m| m);
        let box_vol = if bounds.is_empty() { 0.0 } else { box_volume(&bounds) };
        let q = 2 * n + 1;
        let checked = |k: usize| if k == 2 * n { union_measured } else { measured[k % n.max(1)] };
        let (stats, lines, rounds, converged) =
            self.measure_rounds(options, &bounds, q, checked, |ray, lo, hi, s, sums| {
                self.scene_line(ray, lo, hi, s, sums)
            });
        let at = |k: usize, m: bool| m.then(|| if box_vol > 0.0 { stats.estimate(k) } else { Estimate::default() });
        let blocks = (0..n).map(|i| BlockVolume { own: at(i, measured[i]), owned: at(n + i, measured[i]) }).collect();
        Ok(Volumes {
            blocks,
            union: at(2 * n, union_measured),
            bounds,
            lines,
            replicates: options.replicates,
            rounds,
            converged,
        })
    }

    /// The box the lines cover (`options.bounds`, else the box around the
    /// bounded blocks) and, per block, whether it is measured: bounded or
    /// clipped (an empty block is bounded, of volume 0).
    fn measured_blocks(&self, options: &VolumeOptions) -> (Aabb, Vec<bool>) {
        let ids = || (0..self.len()).map(|i| BlockId(i as u32));
        let finite = |id: BlockId| self.block_aabb(id).is_empty() || self.block_aabb(id).is_bounded();
        match options.bounds {
            Some(b) => (b, vec![true; self.len()]),
            None => (
                ids().filter(|&id| finite(id)).fold(Aabb::EMPTY, |a, id| a.union(&self.block_aabb(id))),
                ids().map(finite).collect(),
            ),
        }
    }

    /// Rounds of random lines over `bounds` measuring `q` quantities (each
    /// line's lengths added by `line`), until every quantity `checked` says
    /// is measured reaches the tolerance or the line cap: the statistics of
    /// the last round, its lines, the rounds and whether it converged.
    fn measure_rounds(
        &self,
        options: &VolumeOptions,
        bounds: &Aabb,
        q: usize,
        checked: impl Fn(usize) -> bool,
        line: impl Fn(&Ray, f64, f64, &mut SceneLine, &mut [f64]) + Sync,
    ) -> (Stats, u64, u32, bool) {
        let box_vol = if bounds.is_empty() { 0.0 } else { box_volume(bounds) };
        let mut stats = Stats::new(q);
        let (mut lines, mut rounds, mut converged) = (0, 0, true);
        if box_vol > 0.0 {
            let mut plan = Planner::new(options);
            loop {
                stats = Stats::new(q);
                lines = run_round(
                    bounds,
                    options.seed.wrapping_add(u64::from(rounds) << 48),
                    options.replicates,
                    plan.per_replicate,
                    q,
                    || SceneLine { spans: BlockSpans::default(), cuts: Vec::new(), partition: Partition::default() },
                    &line,
                    |_| {},
                    &mut stats,
                );
                rounds += 1;
                let floor = options.floor * box_vol;
                let worst = (0..q)
                    .filter(|&k| checked(k))
                    .map(|k| {
                        let e = stats.estimate(k);
                        e.error / (options.tolerance * e.value.max(floor))
                    })
                    .fold(0.0, f64::max);
                if worst <= 1.0 || worst.is_nan() {
                    break;
                }
                if plan.next(worst, lines / u64::from(options.replicates)).is_none() {
                    converged = false;
                    break;
                }
            }
        }
        (stats, lines, rounds, converged)
    }

    /// The volume each group of blocks owns under the priority rule, and
    /// the union's, each with a standard error: [`Complex::volumes`] for
    /// the sums of owned volumes over the groups, `group[i]` being block
    /// `i`'s (below `groups`; `group` has one entry per block). Only the
    /// groups and the union need reach the tolerance, not each block, so
    /// a model whose regions are unions of many blocks (an imported
    /// OpenMC cell) is measured by its regions. A group with an unbounded
    /// block is `None` unless `options.bounds` clips everything.
    ///
    /// ```
    /// use complex::{Block, Complex, ComplexOptions, MaterialKey, Opacity, VolumeOptions};
    /// use quadric::nalgebra::Vector3;
    /// use quadric::{Quadric, Solid, Transform};
    /// let ball = |x: f64| {
    ///     let m = Transform::translate(Vector3::new(x, 0.0, 0.0)).unwrap();
    ///     Block::new("ball", vec![Solid::from(Quadric::sphere().transformed(&m))], Opacity::Transparent, MaterialKey(0))
    ///         .unwrap()
    /// };
    /// // Two overlapping balls in group 0, a third apart in group 1.
    /// let scene = Complex::new(vec![ball(0.0), ball(1.0), ball(4.0)], ComplexOptions::default()).unwrap();
    /// let v = scene.group_volumes(&VolumeOptions { tolerance: 1e-3, ..VolumeOptions::default() }, &[0, 0, 1], 2).unwrap();
    /// let ball_volume = 4.0 / 3.0 * std::f64::consts::PI;
    /// let lens = 5.0 / 12.0 * std::f64::consts::PI;
    /// let pair = v.groups[0].unwrap();
    /// assert!((pair.value - (2.0 * ball_volume - lens)).abs() < 4.0 * pair.error);
    /// let single = v.groups[1].unwrap();
    /// assert!((single.value - ball_volume).abs() < 4.0 * single.error);
    /// ```
    pub fn group_volumes(
        &self,
        options: &VolumeOptions,
        group: &[u32],
        groups: usize,
    ) -> Result<GroupVolumes, ComplexError> {
        options.check()?;
        let n = self.len();
        if group.len() != n || group.iter().any(|&g| g as usize >= groups) {
            return Err(ComplexError::BadVolumeOption {
                option: "group",
                expected: "one group below the number of groups for every block",
                value: groups as f64,
            });
        }
        let (bounds, blocks) = self.measured_blocks(options);
        let mut measured = vec![true; groups];
        for (i, m) in blocks.into_iter().enumerate() {
            measured[group[i] as usize] &= m;
        }
        let union_measured = measured.iter().all(|&m| m);
        let q = groups + 1;
        let checked = |k: usize| if k == groups { union_measured } else { measured[k] };
        let (stats, lines, rounds, converged) =
            self.measure_rounds(options, &bounds, q, checked, |ray, lo, hi, s, sums| {
                self.collect_spans(ray, f64::INFINITY, &mut s.spans);
                self.segments_of_spans(ray, &mut s.spans, &mut s.cuts, &mut s.partition);
                for seg in &s.partition.segments {
                    if let Some(o) = seg.owner {
                        let len = clipped(seg.start, seg.end, lo, hi);
                        sums[group[o.index()] as usize] += len;
                        sums[groups] += len;
                    }
                }
            });
        let box_vol = if bounds.is_empty() { 0.0 } else { box_volume(&bounds) };
        let at = |k: usize, m: bool| m.then(|| if box_vol > 0.0 { stats.estimate(k) } else { Estimate::default() });
        Ok(GroupVolumes {
            groups: (0..groups).map(|g| at(g, measured[g])).collect(),
            union: at(groups, union_measured),
            bounds,
            lines,
            replicates: options.replicates,
            rounds,
            converged,
        })
    }

    /// One line's chords within `[lo, hi]`: each block's own into
    /// `sums[i]`, each block's owned into `sums[n + i]`, the union's into
    /// `sums[2n]`.
    fn scene_line(&self, ray: &Ray, lo: f64, hi: f64, s: &mut SceneLine, sums: &mut [f64]) {
        let n = self.len();
        self.collect_spans(ray, f64::INFINITY, &mut s.spans);
        for (id, ivs) in s.spans.iter() {
            sums[id.index()] += ivs.iter().map(|iv| clipped(iv.enter.t, iv.exit.t, lo, hi)).sum::<f64>();
        }
        self.segments_of_spans(ray, &mut s.spans, &mut s.cuts, &mut s.partition);
        for seg in &s.partition.segments {
            if let Some(o) = seg.owner {
                let len = clipped(seg.start, seg.end, lo, hi);
                sums[n + o.index()] += len;
                sums[2 * n] += len;
            }
        }
    }

    /// Every pair of blocks whose own regions share a positive volume, with
    /// the volume, its standard error and a point inside both. Only pairs
    /// whose boxes overlap with positive volume are candidates (blocks that
    /// only touch are not); each is measured like [`Complex::volumes`] over
    /// its common box, with the chords the two blocks' intervals share
    /// (shared chords shorter than `1e-9` of that box's diagonal are
    /// rounding at a contact, not overlap). A pair is reported when its
    /// volume exceeds three standard errors and the midpoint of its longest
    /// shared chord lies in both blocks. Pairs with an unbounded common box
    /// are listed in [`Overlaps::unbounded`] unless `options.bounds` clips
    /// them; with more candidates than `options.max_pairs` none is measured
    /// ([`Overlaps::skipped`]).
    ///
    /// ```
    /// use complex::{Block, BlockId, Complex, ComplexOptions, MaterialKey, Opacity, VolumeOptions};
    /// use quadric::nalgebra::Vector3;
    /// use quadric::{Quadric, Solid, Transform};
    /// let ball = |x: f64| {
    ///     let m = Transform::translate(Vector3::new(x, 0.0, 0.0)).unwrap();
    ///     Block::new("ball", vec![Solid::from(Quadric::sphere().transformed(&m))], Opacity::Opaque, MaterialKey(0))
    ///         .unwrap()
    /// };
    /// // The first two share a lens; the third only touches the second.
    /// let scene = Complex::new(vec![ball(0.0), ball(1.0), ball(3.0)], ComplexOptions::default()).unwrap();
    /// let found = scene.overlaps(&VolumeOptions::default()).unwrap();
    /// assert_eq!(found.pairs.len(), 1);
    /// let lens = &found.pairs[0];
    /// assert_eq!((lens.a, lens.b), (BlockId(0), BlockId(1)));
    /// assert!((lens.volume.value - 5.0 / 12.0 * std::f64::consts::PI).abs() < 4.0 * lens.volume.error);
    /// assert!(scene.block(BlockId(0)).contains_point(&lens.point));
    /// ```
    pub fn overlaps(&self, options: &VolumeOptions) -> Result<Overlaps, ComplexError> {
        self.overlaps_where(options, |_, _| true)
    }

    /// [`Complex::overlaps`] among the pairs `(a, b)` (with `a < b`) for
    /// which `include(a, b)` holds, e.g. only pairs of opaque blocks; only
    /// those count towards [`VolumeOptions::max_pairs`].
    ///
    /// ```
    /// use complex::{Block, Complex, ComplexOptions, MaterialKey, Opacity, VolumeOptions};
    /// use quadric::nalgebra::Vector3;
    /// use quadric::{Quadric, Solid, Transform};
    /// let ball = |x: f64, opacity| {
    ///     let m = Transform::translate(Vector3::new(x, 0.0, 0.0)).unwrap();
    ///     Block::new("ball", vec![Solid::from(Quadric::sphere().transformed(&m))], opacity, MaterialKey(0)).unwrap()
    /// };
    /// let scene =
    ///     Complex::new(vec![ball(0.0, Opacity::Transparent), ball(1.0, Opacity::Opaque)], ComplexOptions::default())
    ///         .unwrap();
    /// let opaque = |a, b| [a, b].iter().all(|&id| !scene.block(id).is_transparent());
    /// assert!(scene.overlaps_where(&VolumeOptions::default(), opaque).unwrap().pairs.is_empty());
    /// assert_eq!(scene.overlaps(&VolumeOptions::default()).unwrap().pairs.len(), 1);
    /// ```
    pub fn overlaps_where(
        &self,
        options: &VolumeOptions,
        include: impl Fn(BlockId, BlockId) -> bool,
    ) -> Result<Overlaps, ComplexError> {
        options.check()?;
        let mut out = Overlaps { converged: true, ..Overlaps::default() };
        let candidates = self.overlap_candidates(options.bounds, options.max_pairs, include);
        out.candidates = candidates.len();
        if candidates.len() > options.max_pairs {
            out.skipped = true;
            return Ok(out);
        }
        for (a, b, common) in candidates {
            if !common.is_bounded() {
                out.unbounded.push((a, b));
                continue;
            }
            let (volume, witness, lines, converged) = self.pair_volume(a, b, &common, options);
            out.lines += lines;
            out.converged &= converged;
            let Some(point) = witness else { continue };
            let inside = self.block(a).contains_point(&point) && self.block(b).contains_point(&point);
            if volume.value > 3.0 * volume.error && inside {
                out.pairs.push(Overlap { a, b, volume, point });
            }
        }
        Ok(out)
    }

    /// The pairs `(a, b, common box)` with `a < b` whose boxes (clipped to
    /// `bounds`) overlap with positive volume and `include` holds, sorted; at most `limit + 1`
    /// (a sweep along x over the boxes sorted by their lower x).
    fn overlap_candidates(
        &self,
        bounds: Option<Aabb>,
        limit: usize,
        include: impl Fn(BlockId, BlockId) -> bool,
    ) -> Vec<(BlockId, BlockId, Aabb)> {
        let clip = bounds.unwrap_or(Aabb::INFINITE);
        let mut boxes: Vec<(u32, Aabb)> = (0..self.len() as u32)
            .map(|i| (i, self.block_aabb(BlockId(i)).intersection(&clip)))
            .filter(|(_, b)| (0..3).all(|k| b.min[k] < b.max[k]))
            .collect();
        boxes.sort_by(|x, y| x.1.min.x.total_cmp(&y.1.min.x).then(x.0.cmp(&y.0)));
        let mut out = Vec::new();
        'sweep: for (k, (i, bi)) in boxes.iter().enumerate() {
            for (j, bj) in &boxes[k + 1..] {
                if bj.min.x >= bi.max.x {
                    break;
                }
                let common = bi.intersection(bj);
                let (a, b) = if i < j { (*i, *j) } else { (*j, *i) };
                if (0..3).all(|c| common.min[c] < common.max[c]) && include(BlockId(a), BlockId(b)) {
                    out.push((BlockId(a), BlockId(b), common));
                    if out.len() > limit {
                        break 'sweep;
                    }
                }
            }
        }
        out.sort_by_key(|&(a, b, _)| (a, b));
        out
    }

    /// The volume blocks `a` and `b` share within `common`, the midpoint of
    /// the longest shared chord, the lines cast and whether the tolerance
    /// was reached.
    fn pair_volume(
        &self,
        a: BlockId,
        b: BlockId,
        common: &Aabb,
        options: &VolumeOptions,
    ) -> (Estimate, Option<Point3<f64>>, u64, bool) {
        let box_vol = box_volume(common);
        let min_chord = SHARED_CHORD_MIN * common.size().norm();
        let mut plan = Planner::new(options);
        let (mut lines, mut rounds) = (0, 0u32);
        let replicates = u64::from(options.replicates);
        // The longest shared chord: (length, midpoint).
        type Witness = Option<(f64, Point3<f64>)>;
        let longer = |x: Witness, y: Witness| match (x, y) {
            (Some(p), Some(q)) => Some(if q.0 > p.0 { q } else { p }),
            (p, q) => p.or(q),
        };
        let mut witness: Witness = None;
        loop {
            let mut stats = Stats::new(1);
            let mut round_witness: Witness = None;
            let used = run_round(
                common,
                options.seed.wrapping_add(u64::from(rounds) << 48),
                options.replicates,
                plan.per_replicate,
                1,
                || None,
                |ray, lo, hi, w: &mut Witness, sums| {
                    let (ia, ib) = (self.block_intervals(a, ray), self.block_intervals(b, ray));
                    for_each_shared(ia.as_slice(), ib.as_slice(), lo, hi, |s, e| {
                        if e - s > min_chord {
                            sums[0] += e - s;
                            *w = longer(*w, Some((e - s, ray.at(0.5 * (s + e)))));
                        }
                    });
                },
                |w| round_witness = longer(round_witness, w),
                &mut stats,
            );
            lines += used;
            rounds += 1;
            witness = longer(witness, round_witness);
            let e = stats.estimate(0);
            let worst = e.error / (options.tolerance * e.value.max(options.floor * box_vol));
            if worst <= 1.0 || worst.is_nan() {
                return (e, witness.map(|w| w.1), lines, true);
            }
            if plan.next(worst, used / replicates).is_none() {
                return (e, witness.map(|w| w.1), lines, false);
            }
        }
    }
}

/// Calls `f(start, end)` for each non-empty piece of `a ∩ b ∩ [lo, hi]`
/// (both sorted and disjoint).
fn for_each_shared(a: &[Interval], b: &[Interval], lo: f64, hi: f64, mut f: impl FnMut(f64, f64)) {
    let (mut i, mut j) = (0, 0);
    while i < a.len() && j < b.len() {
        let s = a[i].enter.t.max(b[j].enter.t).max(lo);
        let e = a[i].exit.t.min(b[j].exit.t).min(hi);
        if e > s {
            f(s, e);
        }
        if a[i].exit.t < b[j].exit.t {
            i += 1;
        } else {
            j += 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn t_factor_matches_tabulated_quantiles() {
        // t quantiles at 0.99865 (two-sided 99.73 %): 7 d.f. 4.53, 15 d.f.
        // 3.65, 31 d.f. 3.27 (e.g. R's qt), over z = 3.
        for (r, t) in [(8, 4.53), (16, 3.586), (32, 3.27)] {
            assert!((t_factor(r) - t / 3.0).abs() < 0.02 * t / 3.0, "{r}: {}", t_factor(r) * 3.0);
        }
    }

    #[test]
    fn shared_pieces_are_the_intersection() {
        let iv = |a: f64, b: f64| Interval::new(quadric::Bound::new(a, 0), quadric::Bound::new(b, 0));
        let mut got = Vec::new();
        for_each_shared(&[iv(0.0, 2.0), iv(3.0, 5.0)], &[iv(1.0, 4.0), iv(4.5, 9.0)], 0.0, 4.8, |s, e| {
            got.push((s, e))
        });
        assert_eq!(got, [(1.0, 2.0), (3.0, 4.0), (4.5, 4.8)]);
    }
}
