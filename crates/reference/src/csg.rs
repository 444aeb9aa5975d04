//! The exact reference for blocks (intersections of solids) and complexes
//! (unions of blocks with the priority partition of docs/model.md §3.5).
//!
//! Every root is held exactly as `(a + b√d)/e` with dyadic `a`, `d`, `e`
//! (`b ∈ {-1, 0, 1}`), so the order of any two ends — of the same solid, of
//! two solids of a block, of two blocks — is decided exactly (by squaring
//! with sign tracking), not by their approximations: an exact tie is a tie.

use core::cmp::Ordering;

use quadric::{Ray, Solid};

use crate::{Big, ExactQuadric};

/// A crossing `(a + b√d)/e` of a ray with a surface, exact, with its value
/// to [`PRECISION`](crate::PRECISION) bits.
#[derive(Clone, Debug)]
pub struct Root {
    a: Big,
    b: i32,
    d: Big,
    e: Big,
    /// The value, to about 256 bits.
    pub value: Big,
}

impl Root {
    /// The exact double `x` as a root (`b = 0`).
    pub fn of_f64(x: f64) -> Root {
        let one = Big::from_f64(1.0);
        Root { a: Big::from_f64(x), b: 0, d: Big::zero(), e: one, value: Big::from_f64(x) }
    }

    /// The nearest double.
    pub fn to_f64(&self) -> f64 {
        self.value.to_f64()
    }

    /// The exact order of two roots.
    pub fn cmp_exact(&self, o: &Root) -> Ordering {
        // Clear cases from the 256-bit values (each within 2⁻²⁵⁰ relative).
        let diff = &self.value - &o.value;
        let scale = self.value.abs().to_f64().max(o.value.abs().to_f64());
        let gap = diff.abs().to_f64();
        if gap > scale * 2f64.powi(-230) {
            return diff.signum().cmp(&0);
        }
        // x1/e1 - x2/e2 has the sign of (x1 e2 - x2 e1)·sign(e1 e2), where
        // x1 e2 - x2 e1 = (a1 e2 - a2 e1) + b1 e2 √d1 - b2 e1 √d2.
        let c = &(&self.a * &o.e) - &(&o.a * &self.e);
        let p = times(self.b, &o.e);
        let q = -&times(o.b, &self.e);
        (sign3(&c, &p, &self.d, &q, &o.d) * self.e.signum() * o.e.signum()).cmp(&0)
    }
}

fn times(b: i32, x: &Big) -> Big {
    match b.signum() {
        0 => Big::zero(),
        1 => x.clone(),
        _ => -x,
    }
}

/// The sign of `a + p√d`, `d >= 0`.
fn sign2(a: &Big, p: &Big, d: &Big) -> i32 {
    let sa = a.signum();
    let sp = if d.signum() == 0 { 0 } else { p.signum() };
    if sp == 0 {
        return sa;
    }
    if sa == 0 || sa == sp {
        return sp;
    }
    // Opposite signs: compare a² with p²d.
    (&(a * a) - &(&(p * p) * d)).signum() * sa
}

/// The sign of `c + p√d1 + q√d2` (`d1, d2 >= 0`): `L = c + p√d1` against
/// `-q√d2`; where they have the same sign, `L² - q²d2 = (c² + p²d1 - q²d2) + 2cp√d1`
/// decides, times the sign of `L`.
fn sign3(c: &Big, p: &Big, d1: &Big, q: &Big, d2: &Big) -> i32 {
    let sl = sign2(c, p, d1);
    let sr = if d2.signum() == 0 { 0 } else { -q.signum() };
    if sr == 0 {
        return sl;
    }
    if sl == 0 || sl != sr {
        return if sl == 0 { -sr } else { sl };
    }
    let rest = &(&(c * c) + &(&(p * p) * d1)) - &(&(q * q) * d2);
    let two_cp = &(c * p) + &(c * p);
    sign2(&rest, &two_cp, d1) * sl
}

/// One end of an exact interval along the ray `λ >= 0`.
#[derive(Clone, Debug)]
pub enum ExactEnd {
    /// The ray's origin `λ = 0`, where the ray starts inside (no surface).
    Start,
    /// `λ = ∞`.
    Infinity,
    /// A surface crossing of solid `solid` (its index in the block).
    Crossing {
        /// Where.
        root: Root,
        /// Which solid of the block.
        solid: u32,
    },
}

impl ExactEnd {
    /// The value as a double (`0`, `∞`, or the rounded root).
    pub fn to_f64(&self) -> f64 {
        match self {
            ExactEnd::Start => 0.0,
            ExactEnd::Infinity => f64::INFINITY,
            ExactEnd::Crossing { root, .. } => root.to_f64(),
        }
    }

    /// The exact order of two ends.
    pub fn cmp_exact(&self, o: &ExactEnd) -> Ordering {
        match (self, o) {
            (ExactEnd::Infinity, ExactEnd::Infinity) => Ordering::Equal,
            (ExactEnd::Infinity, _) => Ordering::Greater,
            (_, ExactEnd::Infinity) => Ordering::Less,
            (a, b) => a.root().cmp_exact(&b.root()),
        }
    }

    fn root(&self) -> Root {
        match self {
            ExactEnd::Crossing { root, .. } => root.clone(),
            _ => Root::of_f64(0.0),
        }
    }

    /// The solid whose surface this end lies on.
    pub fn solid(&self) -> Option<u32> {
        match self {
            ExactEnd::Crossing { solid, .. } => Some(*solid),
            _ => None,
        }
    }
}

/// A regularised set of closed intervals within `λ >= 0`, sorted, exact.
pub type ExactSet = Vec<(ExactEnd, ExactEnd)>;

/// The exact set of one solid along the ray, its ends tagged `index`.
pub fn solid_set(solid: &Solid, index: u32, ray: &Ray) -> ExactSet {
    let exact = ExactQuadric::solid(solid).solve(ray);
    let (s, t, u) = (&exact.s, &exact.t, &exact.u);
    let crossing = |root: Root| ExactEnd::Crossing { root, solid: index };
    let zero = Big::zero();
    // The line's set as (lo, hi) with None for -∞ / +∞.
    let line: Vec<(Option<Root>, Option<Root>)> = if s.signum() == 0 {
        if t.signum() == 0 {
            if u.signum() <= 0 {
                vec![(None, None)]
            } else {
                vec![]
            }
        } else {
            let e = t + t;
            let root = Root { value: (-u).div(&e), a: -u, b: 0, d: zero.clone(), e };
            if t.signum() > 0 {
                vec![(None, Some(root))]
            } else {
                vec![(Some(root), None)]
            }
        }
    } else {
        let d = &(t * t) - &(s * u);
        if d.signum() <= 0 {
            // No crossing, or a touching point (dropped: regularised).
            if s.signum() > 0 {
                vec![]
            } else {
                vec![(None, None)]
            }
        } else {
            let sq = d.sqrt();
            let q = if t.signum() >= 0 { -&(t + &sq) } else { -&(t - &sq) };
            let (v1, v2) = (q.div(s), u.div(&q));
            let (lo_v, hi_v) = if (&v1 - &v2).signum() <= 0 { (v1, v2) } else { (v2, v1) };
            // (-t + b√d)/s is the larger root for b·s > 0.
            let b_hi = s.signum();
            let lo = Root { a: -t, b: -b_hi, d: d.clone(), e: s.clone(), value: lo_v };
            let hi = Root { a: -t, b: b_hi, d, e: s.clone(), value: hi_v };
            if s.signum() > 0 {
                vec![(Some(lo), Some(hi))]
            } else {
                vec![(None, Some(lo)), (Some(hi), None)]
            }
        }
    };
    // Clip to λ >= 0: an interval ending at or before 0 goes; an entry
    // before 0 becomes the free start.
    let origin = Root::of_f64(0.0);
    line.into_iter()
        .filter(|(_, hi)| hi.as_ref().is_none_or(|h| h.cmp_exact(&origin) == Ordering::Greater))
        .map(|(lo, hi)| {
            let lo = match lo {
                Some(l) if l.cmp_exact(&origin) != Ordering::Less => crossing(l),
                _ => ExactEnd::Start,
            };
            (lo, hi.map_or(ExactEnd::Infinity, crossing))
        })
        .collect()
}

/// `a ∩ b`, exact; on equal ends the one of `a` is kept.
pub fn intersect(a: &ExactSet, b: &ExactSet) -> ExactSet {
    let mut out = Vec::new();
    let (mut i, mut j) = (0, 0);
    while i < a.len() && j < b.len() {
        let (a0, a1) = &a[i];
        let (b0, b1) = &b[j];
        let lo = if b0.cmp_exact(a0) == Ordering::Greater { b0 } else { a0 };
        let hi = if b1.cmp_exact(a1) == Ordering::Less { b1 } else { a1 };
        if lo.cmp_exact(hi) == Ordering::Less {
            out.push((lo.clone(), hi.clone()));
        }
        if a1.cmp_exact(b1) == Ordering::Less {
            i += 1;
        } else {
            j += 1;
        }
    }
    out
}

/// The exact set of a block (the intersection of its solids' sets; ends
/// tagged with the solid's index in the block).
pub fn block_set(solids: &[Solid], ray: &Ray) -> ExactSet {
    let mut acc = vec![(ExactEnd::Start, ExactEnd::Infinity)];
    for (i, s) in solids.iter().enumerate() {
        acc = intersect(&acc, &solid_set(s, i as u32, ray));
        if acc.is_empty() {
            break;
        }
    }
    acc
}

/// A block of the reference complex.
#[derive(Clone, Debug)]
pub struct ExactBlock {
    /// Its solids.
    pub solids: Vec<Solid>,
    /// Transparent blocks yield to opaque ones and to earlier transparent ones.
    pub transparent: bool,
}

/// A segment of the exact partition: `[start, end]` owned by `owner`.
#[derive(Clone, Debug)]
pub struct ExactSegment {
    /// Where it starts (exact).
    pub start: ExactEnd,
    /// Where it ends (exact).
    pub end: ExactEnd,
    /// The owning block's index, or `None` (outside every block).
    pub owner: Option<usize>,
}

/// The exact partition of a ray by a complex (docs/model.md §3.5).
#[derive(Clone, Debug)]
pub struct ExactPartition {
    /// Segments in order, covering `[0, ∞)`, consecutive owners different.
    pub segments: Vec<ExactSegment>,
    /// Each block's exact set (after the ε rule).
    pub sets: Vec<ExactSet>,
}

impl ExactPartition {
    /// The partition of `ray` by `blocks` in priority order: an interval
    /// contained in `[0, epsilon]` is no hit (docs/model.md §3.3); a point belongs to
    /// the first opaque block containing it, else the first transparent one.
    pub fn new(blocks: &[ExactBlock], ray: &Ray, epsilon: f64) -> ExactPartition {
        let eps = Root::of_f64(epsilon);
        let sets: Vec<ExactSet> = blocks
            .iter()
            .map(|b| {
                let mut set = block_set(&b.solids, ray);
                set.retain(|(_, hi)| match hi {
                    ExactEnd::Infinity => true,
                    end => end.root().cmp_exact(&eps) == Ordering::Greater,
                });
                set
            })
            .collect();
        let mut cuts: Vec<ExactEnd> = vec![ExactEnd::Start];
        for set in &sets {
            for (lo, hi) in set {
                cuts.push(lo.clone());
                cuts.push(hi.clone());
            }
        }
        cuts.push(ExactEnd::Infinity);
        cuts.sort_by(|a, b| a.cmp_exact(b));
        cuts.dedup_by(|a, b| a.cmp_exact(b) == Ordering::Equal);
        let mut segments: Vec<ExactSegment> = Vec::new();
        for w in cuts.windows(2) {
            let (a, b) = (&w[0], &w[1]);
            let contains = |set: &ExactSet| {
                set.iter().any(|(lo, hi)| lo.cmp_exact(a) != Ordering::Greater && hi.cmp_exact(b) != Ordering::Less)
            };
            let inside: Vec<usize> = (0..blocks.len()).filter(|&i| contains(&sets[i])).collect();
            let owner = inside.iter().copied().find(|&i| !blocks[i].transparent).or_else(|| inside.first().copied());
            match segments.last_mut() {
                Some(last) if last.owner == owner => last.end = b.clone(),
                _ => segments.push(ExactSegment { start: a.clone(), end: b.clone(), owner }),
            }
        }
        ExactPartition { segments, sets }
    }

    /// The exact owner at the double `λ`: of the segment containing it, the
    /// later one at an exact cut.
    pub fn owner_at(&self, lambda: f64) -> Option<usize> {
        let x = ExactEnd::Crossing { root: Root::of_f64(lambda), solid: 0 };
        self.segments.iter().rev().find(|s| s.start.cmp_exact(&x) != Ordering::Greater).and_then(|s| s.owner)
    }

    /// Ownership errors of a computed partition, given as `(start, end,
    /// owner)` segments: the computed segments and the exact ones longer than
    /// `2·tolerance` whose owner at their midpoint (exact for the computed
    /// ones, computed for the exact ones) differs. Disagreements confined to
    /// within `tolerance` of a cut are not counted.
    pub fn ownership_errors(&self, computed: &[(f64, f64, Option<usize>)], tolerance: f64) -> usize {
        let computed_at = |t: f64| computed.iter().find(|(a, b, _)| *a <= t && t <= *b).and_then(|s| s.2);
        let mid = |a: f64, b: f64| if b.is_finite() { 0.5 * (a + b) } else { a + 1.0 + a.abs() };
        let mut errors = 0;
        for &(a, b, owner) in computed {
            if b - a > 2.0 * tolerance && self.owner_at(mid(a, b)) != owner {
                errors += 1;
            }
        }
        for s in &self.segments {
            let (a, b) = (s.start.to_f64(), s.end.to_f64());
            if b - a > 2.0 * tolerance && computed_at(mid(a, b)) != s.owner {
                errors += 1;
            }
        }
        errors
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use quadric::nalgebra::{Point3, Vector3};
    use quadric::{HalfSpace, Quadric, Transform};

    fn ball(x: f64) -> Solid {
        Quadric::sphere().transformed(&Transform::translate(Vector3::new(x, 0.0, 0.0)).expect("valid")).into()
    }

    #[test]
    fn roots_of_different_solids_tie_exactly() {
        // The sphere around 0 and the plane x <= 1 meet the x axis both at 1.
        let ray = Ray::new(Point3::new(-3.0, 0.0, 0.0), Vector3::x()).expect("valid");
        let plane = Solid::from(HalfSpace::new(1.0, 0.0, 0.0, -1.0).expect("valid"));
        let a = solid_set(&ball(0.0), 0, &ray);
        let b = solid_set(&plane, 1, &ray);
        assert_eq!(a[0].1.cmp_exact(&b[0].1), Ordering::Equal);
        // Ties keep the first set's end.
        let both = intersect(&a, &b);
        assert_eq!((both[0].0.to_f64(), both[0].1.to_f64(), both[0].1.solid()), (2.0, 4.0, Some(0)));
    }

    #[test]
    fn partition_follows_priority() {
        let ray = Ray::new(Point3::new(-3.0, 0.0, 0.0), Vector3::x()).expect("valid");
        // Transparent ball at 0, opaque ball at 1 (overlapping), transparent at 0.5.
        let blocks = [
            ExactBlock { solids: vec![ball(0.0)], transparent: true },
            ExactBlock { solids: vec![ball(1.0)], transparent: false },
            ExactBlock { solids: vec![ball(0.5)], transparent: true },
        ];
        let p = ExactPartition::new(&blocks, &ray, 0.0);
        let got: Vec<(f64, f64, Option<usize>)> =
            p.segments.iter().map(|s| (s.start.to_f64(), s.end.to_f64(), s.owner)).collect();
        assert_eq!(got, [(0.0, 2.0, None), (2.0, 3.0, Some(0)), (3.0, 5.0, Some(1)), (5.0, f64::INFINITY, None)]);
        assert_eq!(p.owner_at(2.5), Some(0));
        assert_eq!(p.owner_at(3.0), Some(1));
        assert_eq!(p.ownership_errors(&got, 0.0), 0);
        let wrong = [(0.0, 2.0, None), (2.0, 5.0, Some(0)), (5.0, f64::INFINITY, None)];
        assert_eq!(p.ownership_errors(&wrong, 1e-9), 2);
    }
}
