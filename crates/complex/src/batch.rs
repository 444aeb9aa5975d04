//! Batch queries: many points classified, many rays cast, many lines traced,
//! in parallel over rayon's current pool. Each answer is exactly the single
//! query's (`contains_point`, `cast_ray`, `segments_into`): the batch is cut
//! into fixed chunks, each chunk writes its own part of the output (or, for
//! the ragged traces, its own buffer, joined in order), so the result does
//! not depend on the number of threads. No query allocates; a batch of at
//! most one chunk runs on the calling thread without waking the pool.

use quadric::nalgebra::Point3;
use quadric::Ray;
use rayon::prelude::*;

use crate::{BlockId, Complex, ComplexError, Hit, Partition, Segment};

/// Points per chunk of [`Complex::classify`]: a point costs tens of
/// nanoseconds, so a chunk is tens of microseconds, far above rayon's cost
/// of a task.
const CLASSIFY_CHUNK: usize = 1024;

/// Rays per chunk of [`Complex::cast_many`]; a multiple of four, so the
/// packets of four are the same whatever the chunking.
const CAST_CHUNK: usize = 256;

/// Rays per chunk of [`Complex::trace_many`] (a partition costs more than a hit).
const TRACE_CHUNK: usize = 128;

/// Four rays go through the packet walk when each direction is within
/// about 2.6° of the first's (`cos ≥ 0.999`): a camera's neighbouring
/// pixels are far closer. The packet walk reads each BVH node once for the
/// four, which pays only when they visit mostly the same nodes; on
/// scattered rays it costs about 30 % over single rays, on a camera's it
/// saves about 6 % (`benches/batch.rs`). Either way each answer is
/// `cast_ray`'s.
const PACKET_COS: f64 = 0.999;

/// Whether four rays are near-parallel enough for the packet walk.
fn coherent(rays: &[Ray; 4]) -> bool {
    let d = rays[0].direction();
    rays[1..].iter().all(|r| r.direction().dot(&d) >= PACKET_COS)
}

/// The segments of many rays, ragged: ray `i`'s are
/// `segments()[offsets()[i]..offsets()[i + 1]]` ([`Traces::ray`]), exactly
/// what [`Complex::segments_into`] gives for it. Filled by
/// [`Complex::trace_many`]; a `Traces` reused batch after batch keeps its
/// buffers and allocates only when they must grow.
#[derive(Clone, Debug, Default)]
pub struct Traces {
    /// `offsets[i]` is where ray `i`'s segments start; one more entry than rays.
    offsets: Vec<usize>,
    segments: Vec<Segment>,
    /// One buffer per chunk, kept for the next batch.
    chunks: Vec<ChunkTraces>,
}

/// A chunk's segments and each of its rays' count, before they are joined.
#[derive(Clone, Debug, Default)]
struct ChunkTraces {
    scratch: Partition,
    segments: Vec<Segment>,
    counts: Vec<usize>,
}

impl Traces {
    /// An empty result (no rays).
    pub fn new() -> Self {
        Self::default()
    }

    /// How many rays were traced.
    pub fn len(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    /// Whether no ray was traced.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Where each ray's segments start in [`Traces::segments`], and at the
    /// end their total: `len() + 1` entries, non-decreasing, from 0 (empty
    /// before the first batch).
    pub fn offsets(&self) -> &[usize] {
        &self.offsets
    }

    /// Every ray's segments, ray after ray.
    pub fn segments(&self) -> &[Segment] {
        &self.segments
    }

    /// Ray `i`'s segments (`None` past the last ray).
    pub fn ray(&self, i: usize) -> Option<&[Segment]> {
        let (&start, &end) = (self.offsets.get(i)?, self.offsets.get(i + 1)?);
        Some(&self.segments[start..end])
    }

    /// Each ray's segments, in order.
    pub fn iter(&self) -> impl ExactSizeIterator<Item = &[Segment]> + '_ {
        self.offsets.windows(2).map(|w| &self.segments[w[0]..w[1]])
    }
}

/// Two results are equal when they hold the same rays' segments (the
/// buffers kept for the next batch are not compared).
impl PartialEq for Traces {
    fn eq(&self, other: &Self) -> bool {
        self.len() == other.len() && self.iter().eq(other.iter())
    }
}

/// `Err(LengthMismatch)` unless there is one answer slot per query.
fn check_lengths(queries: usize, answers: usize) -> Result<(), ComplexError> {
    if queries == answers {
        Ok(())
    } else {
        Err(ComplexError::LengthMismatch { queries, answers })
    }
}

/// `work` on each chunk of `chunk` inputs and its part of `out`: in
/// parallel if there is more than one chunk.
fn for_each_chunk<I: Sync, O: Send>(inputs: &[I], out: &mut [O], chunk: usize, work: impl Fn(&[I], &mut [O]) + Sync) {
    if inputs.len() <= chunk {
        work(inputs, out);
    } else {
        inputs.par_chunks(chunk).zip(out.par_chunks_mut(chunk)).for_each(|(i, o)| work(i, o));
    }
}

impl Complex {
    /// The owner of each point under the priority rule: `out[i]` is exactly
    /// `self.contains_point(&points[i])`. The answers go into a slice the
    /// caller owns (a numpy array, a buffer reused batch after batch), so a
    /// batch allocates nothing of its own; it runs in parallel on rayon's
    /// current pool (the global one, or the one of an enclosing
    /// `ThreadPool::install`), with the same answers for any number of
    /// threads. `Err(ComplexError::LengthMismatch)`, and `out` untouched,
    /// unless `out` is as long as `points`.
    ///
    /// ```
    /// use complex::{Block, BlockId, Complex, ComplexOptions, MaterialKey, Opacity};
    /// use quadric::nalgebra::Point3;
    /// use quadric::{Quadric, Solid};
    /// let ball = Block::new("ball", vec![Solid::from(Quadric::sphere())], Opacity::Opaque, MaterialKey(0)).unwrap();
    /// let scene = Complex::new(vec![ball], ComplexOptions::default()).unwrap();
    /// let points: Vec<Point3<f64>> = (0..5).map(|i| Point3::new(0.5 * i as f64, 0.0, 0.0)).collect();
    /// let mut owners = vec![None; points.len()];
    /// scene.classify(&points, &mut owners).unwrap();
    /// assert_eq!(owners, [Some(BlockId(0)), Some(BlockId(0)), Some(BlockId(0)), None, None]);
    /// assert!(scene.classify(&points, &mut owners[..4]).is_err());
    /// ```
    pub fn classify(&self, points: &[Point3<f64>], out: &mut [Option<BlockId>]) -> Result<(), ComplexError> {
        check_lengths(points.len(), out.len())?;
        for_each_chunk(points, out, CLASSIFY_CHUNK, |points, out| {
            for (p, o) in points.iter().zip(out) {
                *o = self.contains_point(p);
            }
        });
        Ok(())
    }

    /// The first hit of each ray: `out[i]` is exactly
    /// `self.cast_ray(&rays[i], max_t)`. Four consecutive rays with
    /// near-parallel directions (within about 2.6°, such as a camera's
    /// neighbouring pixels) go through [`Complex::cast_rays`] and share one
    /// walk of the BVH (each answer still its own ray's); the others go one
    /// by one. Parallel, allocation-free and with the same answers
    /// for any number of threads, as [`Complex::classify`];
    /// `Err(ComplexError::LengthMismatch)`, and `out` untouched, unless `out`
    /// is as long as `rays`.
    ///
    /// ```
    /// use complex::{Block, Complex, ComplexOptions, MaterialKey, Opacity};
    /// use quadric::nalgebra::{Point3, Vector3};
    /// use quadric::{Quadric, Ray, Solid};
    /// let ball = Block::new("ball", vec![Solid::from(Quadric::sphere())], Opacity::Opaque, MaterialKey(0)).unwrap();
    /// let scene = Complex::new(vec![ball], ComplexOptions::default()).unwrap();
    /// let rays: Vec<Ray> =
    ///     (0..6).map(|i| Ray::new(Point3::new(-5.0, 0.4 * i as f64, 0.0), Vector3::x()).unwrap()).collect();
    /// let mut hits = vec![None; rays.len()];
    /// scene.cast_many(&rays, f64::INFINITY, &mut hits).unwrap();
    /// for (ray, hit) in rays.iter().zip(&hits) {
    ///     assert_eq!(*hit, scene.cast_ray(ray, f64::INFINITY));
    /// }
    /// assert_eq!(hits.iter().filter(|h| h.is_some()).count(), 3);
    /// ```
    pub fn cast_many(&self, rays: &[Ray], max_t: f64, out: &mut [Option<Hit>]) -> Result<(), ComplexError> {
        check_lengths(rays.len(), out.len())?;
        for_each_chunk(rays, out, CAST_CHUNK, |rays, out| {
            let (fours, tail) = rays.as_chunks::<4>();
            let (out_fours, out_tail) = out.as_chunks_mut::<4>();
            for (four, o) in fours.iter().zip(out_fours) {
                *o = if coherent(four) {
                    self.cast_rays(four, max_t)
                } else {
                    four.each_ref().map(|r| self.cast_ray(r, max_t))
                };
            }
            for (ray, o) in tail.iter().zip(out_tail) {
                *o = self.cast_ray(ray, max_t);
            }
        });
        Ok(())
    }

    /// The segments of each ray's partition, without events: ray `i`'s
    /// segments in `out` ([`Traces::ray`]) are exactly what
    /// [`Complex::segments_into`] gives for `rays[i]` (starts, ends and
    /// owners covering `[0, ∞)`). `out`'s previous contents are replaced;
    /// its buffers are reused, so tracing batch after batch into one
    /// `Traces` allocates only when a batch needs more room than any before
    /// it. Parallel over chunks of rays, each into its own buffer, joined in
    /// order: the same result for any number of threads.
    ///
    /// ```
    /// use complex::{Block, BlockId, Complex, ComplexOptions, MaterialKey, Opacity, Traces};
    /// use quadric::nalgebra::{Point3, Vector3};
    /// use quadric::{Quadric, Ray, Solid};
    /// let ball = Block::new("ball", vec![Solid::from(Quadric::sphere())], Opacity::Transparent, MaterialKey(0)).unwrap();
    /// let scene = Complex::new(vec![ball], ComplexOptions::default()).unwrap();
    /// let through = Ray::new(Point3::new(-3.0, 0.0, 0.0), Vector3::x()).unwrap();
    /// let past = Ray::new(Point3::new(-3.0, 2.0, 0.0), Vector3::x()).unwrap();
    /// let mut traces = Traces::new();
    /// scene.trace_many(&[through, past], &mut traces);
    /// assert_eq!(traces.len(), 2);
    /// let owners: Vec<_> = traces.ray(0).unwrap().iter().map(|s| (s.start, s.end, s.owner)).collect();
    /// assert_eq!(owners, [(0.0, 2.0, None), (2.0, 4.0, Some(BlockId(0))), (4.0, f64::INFINITY, None)]);
    /// assert_eq!(traces.ray(1).unwrap().len(), 1);
    /// assert_eq!(traces.offsets(), [0, 3, 4]);
    /// ```
    pub fn trace_many(&self, rays: &[Ray], out: &mut Traces) {
        let n_chunks = rays.len().div_ceil(TRACE_CHUNK);
        if out.chunks.len() < n_chunks {
            out.chunks.resize_with(n_chunks, ChunkTraces::default);
        }
        let chunks = &mut out.chunks[..n_chunks];
        let trace = |rays: &[Ray], chunk: &mut ChunkTraces| {
            let ChunkTraces { scratch, segments, counts } = chunk;
            segments.clear();
            counts.clear();
            for ray in rays {
                self.segments_into(ray, scratch);
                counts.push(scratch.segments.len());
                segments.extend_from_slice(&scratch.segments);
            }
        };
        // One buffer per chunk of rays, in parallel if there is more than one.
        if n_chunks <= 1 {
            rays.chunks(TRACE_CHUNK).zip(chunks.iter_mut()).for_each(|(r, c)| trace(r, c));
        } else {
            rays.par_chunks(TRACE_CHUNK).zip(chunks.par_iter_mut()).for_each(|(r, c)| trace(r, c));
        }
        out.offsets.clear();
        out.segments.clear();
        out.offsets.reserve(rays.len() + 1);
        out.segments.reserve(chunks.iter().map(|c| c.segments.len()).sum());
        out.offsets.push(0);
        let mut end = 0;
        for chunk in chunks.iter() {
            for &count in &chunk.counts {
                end += count;
                out.offsets.push(end);
            }
            out.segments.extend_from_slice(&chunk.segments);
        }
    }
}
