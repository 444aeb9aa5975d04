//! Interval sets along a ray: sorted, disjoint, closed intervals of `λ`.
//!
//! Sets are *regularised* (as in CSG): every interval has positive length and
//! two intervals never touch. Isolated points (a tangent ray touching a
//! surface) are therefore not part of any set, and union, intersection and
//! complement form an exact Boolean algebra on these sets.
//!
//! A set lives on the stack with a fixed capacity of [`IntervalSet::CAPACITY`]
//! intervals; operations that could exceed it return [`CapacityError`].

use core::fmt;

/// Marker for an endpoint that no solid produced (an infinite end, or the
/// start of a ray that begins inside a solid).
pub const NO_SOLID: u32 = u32::MAX;

/// One end of an interval: the ray parameter and the solid whose surface it is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bound {
    /// Ray parameter `λ` (a distance along the unit direction); may be `±∞`.
    pub t: f64,
    /// Index of the solid whose surface lies at `t`, or [`NO_SOLID`].
    pub solid: u32,
}

impl Bound {
    /// A bound produced by `solid` at `t`.
    #[inline]
    pub const fn new(t: f64, solid: u32) -> Self {
        Bound { t, solid }
    }

    /// A bound no solid produced (an infinite end or a clip).
    #[inline]
    pub const fn free(t: f64) -> Self {
        Bound { t, solid: NO_SOLID }
    }

    /// The solid whose surface this bound lies on, if any.
    #[inline]
    pub fn solid(&self) -> Option<u32> {
        (self.solid != NO_SOLID).then_some(self.solid)
    }
}

/// A closed interval `[enter, exit]` with `enter.t < exit.t`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Interval {
    /// Where the ray enters the set.
    pub enter: Bound,
    /// Where the ray leaves the set.
    pub exit: Bound,
}

impl Interval {
    /// The interval `[enter, exit]`.
    #[inline]
    pub const fn new(enter: Bound, exit: Bound) -> Self {
        Interval { enter, exit }
    }

    /// Whether `t` lies in the closed interval.
    #[inline]
    pub fn contains(&self, t: f64) -> bool {
        self.enter.t <= t && t <= self.exit.t
    }

    /// Length of the interval (`∞` if unbounded).
    #[inline]
    pub fn length(&self) -> f64 {
        self.exit.t - self.enter.t
    }
}

/// An operation needed more than [`IntervalSet::CAPACITY`] intervals.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[error("an interval set can hold at most {} intervals", IntervalSet::CAPACITY)]
pub struct CapacityError;

/// A sorted list of disjoint, non-touching closed intervals of positive length.
///
/// ```
/// use quadric::{Bound, IntervalSet};
/// let a = IntervalSet::from_interval(Bound::new(1.0, 0), Bound::new(4.0, 0));
/// let b = IntervalSet::from_interval(Bound::new(3.0, 1), Bound::new(6.0, 1));
/// let both = a.intersect(&b).unwrap();
/// assert_eq!(both.first_entry().map(|b| (b.t, b.solid)), Some((3.0, 1)));
/// assert!(a.union(&b).unwrap().contains(5.0));
/// ```
#[derive(Clone, Copy)]
pub struct IntervalSet {
    len: u8,
    items: [Interval; IntervalSet::CAPACITY],
}

const FILLER: Interval = Interval::new(Bound::free(0.0), Bound::free(0.0));

impl IntervalSet {
    /// How many intervals a set can hold. A block of quadrics with `n`
    /// non-convex members needs at most `n + 1`.
    pub const CAPACITY: usize = 8;

    /// The empty set.
    #[inline]
    pub const fn empty() -> Self {
        IntervalSet { len: 0, items: [FILLER; Self::CAPACITY] }
    }

    /// The whole line `(-∞, ∞)`.
    #[inline]
    pub const fn everything() -> Self {
        Self::single(Bound::free(f64::NEG_INFINITY), Bound::free(f64::INFINITY))
    }

    const fn single(enter: Bound, exit: Bound) -> Self {
        let mut s = Self::empty();
        s.items[0] = Interval::new(enter, exit);
        s.len = 1;
        s
    }

    /// The set holding `[enter, exit]`, or the empty set if `enter.t >= exit.t`
    /// or either end is NaN.
    #[inline]
    pub fn from_interval(enter: Bound, exit: Bound) -> Self {
        if enter.t < exit.t {
            Self::single(enter, exit)
        } else {
            Self::empty()
        }
    }

    /// Builds a set from intervals in any order; overlapping or touching ones
    /// are merged, empty or NaN ones dropped. Fails only if the merged result
    /// has more than [`Self::CAPACITY`] intervals.
    ///
    /// Not for the ray path: it sorts in a heap buffer, since merging in input
    /// order could overflow the capacity on the way to a result that fits.
    /// Where two intervals start together, the one listed first gives the entry.
    pub fn from_intervals<I: IntoIterator<Item = Interval>>(items: I) -> Result<Self, CapacityError> {
        let mut sorted: Vec<Interval> = items.into_iter().filter(|iv| iv.enter.t < iv.exit.t).collect();
        // Stable: ties keep the input order.
        sorted.sort_by(|x, y| x.enter.t.total_cmp(&y.enter.t));
        let mut acc = Self::empty();
        for iv in sorted {
            acc.push(iv, false)?;
        }
        Ok(acc)
    }

    /// The intervals, sorted.
    #[inline]
    pub fn as_slice(&self) -> &[Interval] {
        &self.items[..self.len as usize]
    }

    /// An iterator over the intervals, sorted.
    #[inline]
    pub fn iter(&self) -> core::slice::Iter<'_, Interval> {
        self.as_slice().iter()
    }

    /// Number of intervals.
    #[inline]
    pub fn len(&self) -> usize {
        self.len as usize
    }

    /// Whether the set is empty.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The first point where the ray enters the set (the smallest `λ`).
    #[inline]
    pub fn first_entry(&self) -> Option<Bound> {
        self.as_slice().first().map(|iv| iv.enter)
    }

    /// Whether `t` lies in one of the closed intervals.
    pub fn contains(&self, t: f64) -> bool {
        self.iter().any(|iv| iv.contains(t))
    }

    /// The interval containing `t`, if any.
    pub fn interval_at(&self, t: f64) -> Option<&Interval> {
        self.iter().find(|iv| iv.contains(t))
    }

    /// Appends an interval that starts no earlier than every interval already
    /// present, merging it with the last one if they touch. Empty intervals
    /// are ignored. If both end together, the new end is kept when `wins_ties`.
    #[inline]
    fn push(&mut self, iv: Interval, wins_ties: bool) -> Result<(), CapacityError> {
        // Empty, inverted or NaN intervals are dropped.
        if iv.enter.t.partial_cmp(&iv.exit.t) != Some(core::cmp::Ordering::Less) {
            return Ok(());
        }
        if let Some(last) = self.items[..self.len as usize].last_mut() {
            if iv.enter.t <= last.exit.t {
                if iv.exit.t > last.exit.t || (wins_ties && iv.exit.t == last.exit.t) {
                    last.exit = iv.exit;
                }
                return Ok(());
            }
        }
        if self.len as usize == Self::CAPACITY {
            return Err(CapacityError);
        }
        self.items[self.len as usize] = iv;
        self.len += 1;
        Ok(())
    }

    /// Intersection. Where two ends coincide, the end of `self` is kept.
    pub fn intersect(&self, other: &Self) -> Result<Self, CapacityError> {
        let (a, b) = (self.as_slice(), other.as_slice());
        let mut out = Self::empty();
        let (mut i, mut j) = (0, 0);
        while i < a.len() && j < b.len() {
            let (x, y) = (a[i], b[j]);
            let enter = if y.enter.t > x.enter.t { y.enter } else { x.enter };
            let exit = if y.exit.t < x.exit.t { y.exit } else { x.exit };
            out.push(Interval::new(enter, exit), false)?;
            if x.exit.t <= y.exit.t {
                i += 1;
            } else {
                j += 1;
            }
        }
        Ok(out)
    }

    /// Intersection with a single interval `[enter, exit]`; never exceeds the
    /// capacity (the fast path for convex solids).
    pub fn intersect_interval(&self, enter: Bound, exit: Bound) -> Self {
        let mut out = Self::empty();
        for x in self.iter() {
            let e = if enter.t > x.enter.t { enter } else { x.enter };
            let l = if exit.t < x.exit.t { exit } else { x.exit };
            if e.t < l.t {
                out.items[out.len as usize] = Interval::new(e, l);
                out.len += 1;
            }
        }
        out
    }

    /// Union. Where two ends coincide, the end of `self` is kept.
    pub fn union(&self, other: &Self) -> Result<Self, CapacityError> {
        let (a, b) = (self.as_slice(), other.as_slice());
        let mut out = Self::empty();
        let (mut i, mut j) = (0, 0);
        while i < a.len() || j < b.len() {
            let take_a = j >= b.len() || (i < a.len() && a[i].enter.t <= b[j].enter.t);
            let next = if take_a {
                i += 1;
                a[i - 1]
            } else {
                j += 1;
                b[j - 1]
            };
            // On coincident ends the end of `self` wins.
            out.push(next, take_a)?;
        }
        Ok(out)
    }

    /// Complement within `[lo, hi]` (for a ray, `[0, ∞)`): the gaps between
    /// the intervals. Each new end keeps the solid of the end it comes from.
    pub fn complement_within(&self, lo: f64, hi: f64) -> Result<Self, CapacityError> {
        let mut out = Self::empty();
        let mut start = Bound::free(lo);
        for iv in self.iter() {
            // A gap cut off at `hi` ends at no surface.
            let end = if iv.enter.t <= hi { iv.enter } else { Bound::free(hi) };
            out.push(Interval::new(start, end), false)?;
            start = if iv.exit.t > lo { iv.exit } else { Bound::free(lo) };
        }
        out.push(Interval::new(start, Bound::free(hi)), false)?;
        Ok(out)
    }

    /// Complement within the ray's domain `[0, ∞)`.
    pub fn complement(&self) -> Result<Self, CapacityError> {
        self.complement_within(0.0, f64::INFINITY)
    }

    /// The part of the set inside `[lo, hi]`; clipped ends carry no solid.
    /// An end at `-0.0` comes out as `+0.0`, so a ray's sets never show `-0`.
    pub fn clip(&self, lo: f64, hi: f64) -> Self {
        let mut out = self.intersect_interval(Bound::free(lo), Bound::free(hi));
        for iv in &mut out.items[..out.len as usize] {
            // `x + 0.0` is `x` except that it maps -0.0 to +0.0.
            iv.enter.t += 0.0;
            iv.exit.t += 0.0;
        }
        out
    }

    /// Keeps only the intervals for which `keep` is true.
    pub fn retain(&mut self, mut keep: impl FnMut(&Interval) -> bool) {
        let mut n = 0;
        for i in 0..self.len as usize {
            if keep(&self.items[i]) {
                self.items[n] = self.items[i];
                n += 1;
            }
        }
        self.len = n as u8;
    }

    /// Checks the invariants: sorted, each interval of positive length, gaps
    /// of positive length, no NaN. Always true for sets built by this module.
    pub fn is_normalised(&self) -> bool {
        let s = self.as_slice();
        s.iter().all(|iv| iv.enter.t < iv.exit.t) && s.windows(2).all(|w| w[0].exit.t < w[1].enter.t)
    }

    /// Whether both sets hold the same intervals (ignoring which solids
    /// produced the ends).
    pub fn same_points(&self, other: &Self) -> bool {
        self.len == other.len
            && self.iter().zip(other.iter()).all(|(a, b)| a.enter.t == b.enter.t && a.exit.t == b.exit.t)
    }
}

impl Default for IntervalSet {
    fn default() -> Self {
        Self::empty()
    }
}

impl PartialEq for IntervalSet {
    fn eq(&self, other: &Self) -> bool {
        self.as_slice() == other.as_slice()
    }
}

impl fmt::Debug for IntervalSet {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_list().entries(self.iter().map(|iv| (iv.enter.t, iv.exit.t))).finish()
    }
}

impl fmt::Display for IntervalSet {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.is_empty() {
            return f.write_str("∅");
        }
        for (n, iv) in self.iter().enumerate() {
            if n > 0 {
                f.write_str(" ∪ ")?;
            }
            write!(f, "[{}, {}]", iv.enter.t, iv.exit.t)?;
        }
        Ok(())
    }
}

impl<'a> IntoIterator for &'a IntervalSet {
    type Item = &'a Interval;
    type IntoIter = core::slice::Iter<'a, Interval>;
    fn into_iter(self) -> Self::IntoIter {
        self.iter()
    }
}

/// The set of one solid along a ray, at most two intervals: the inside of a
/// quadric is one interval, or two where the ray leaves and re-enters (the
/// two nappes of a cone, a hyperboloid of two sheets, the outside of a
/// cylinder's complement). The same sets as [`IntervalSet`] without its
/// fixed buffer of [`IntervalSet::CAPACITY`] intervals, which a kernel
/// returning one set per solid and ray would fill and copy every time.
///
/// ```
/// use quadric::{Bound, IntervalSet, Pieces};
/// let one = Pieces::from_interval(Bound::new(1.0, 0), Bound::new(4.0, 0));
/// assert_eq!(one.as_slice().len(), 1);
/// assert_eq!(IntervalSet::from(one), IntervalSet::from_interval(Bound::new(1.0, 0), Bound::new(4.0, 0)));
/// assert!(Pieces::from_interval(Bound::new(4.0, 0), Bound::new(1.0, 0)).as_slice().is_empty());
/// ```
#[derive(Clone, Copy)]
pub struct Pieces {
    len: u8,
    items: [Interval; 2],
}

impl Pieces {
    /// The empty set.
    #[inline(always)]
    pub const fn empty() -> Self {
        Pieces { len: 0, items: [FILLER; 2] }
    }

    /// `[enter, exit]`, or the empty set if `enter.t >= exit.t` or either end
    /// is NaN (as [`IntervalSet::from_interval`]).
    #[inline(always)]
    pub fn from_interval(enter: Bound, exit: Bound) -> Self {
        if enter.t < exit.t {
            Pieces { len: 1, items: [Interval::new(enter, exit), FILLER] }
        } else {
            Self::empty()
        }
    }

    /// `self` followed by `later`, whose intervals start no earlier than
    /// any of `self`'s: [`IntervalSet::union`] of the two (touching or
    /// overlapping intervals merge, `self`'s end winning ties), or `None`
    /// where that has more than two intervals.
    #[inline]
    pub(crate) fn then(self, later: Pieces) -> Option<Pieces> {
        let mut out = self;
        for &iv in later.as_slice() {
            if let Some(last) = out.items[..out.len as usize].last_mut() {
                if iv.enter.t <= last.exit.t {
                    if iv.exit.t > last.exit.t {
                        last.exit = iv.exit;
                    }
                    continue;
                }
            }
            if out.len == 2 {
                return None;
            }
            out.items[out.len as usize] = iv;
            out.len += 1;
        }
        Some(out)
    }

    /// The intervals, sorted.
    #[inline(always)]
    pub fn as_slice(&self) -> &[Interval] {
        &self.items[..self.len as usize]
    }
}

impl From<Pieces> for IntervalSet {
    #[inline]
    fn from(p: Pieces) -> Self {
        let mut set = IntervalSet::empty();
        set.items[..p.len as usize].copy_from_slice(p.as_slice());
        set.len = p.len;
        set
    }
}

impl Default for Pieces {
    fn default() -> Self {
        Self::empty()
    }
}

impl PartialEq for Pieces {
    fn eq(&self, other: &Self) -> bool {
        self.as_slice() == other.as_slice()
    }
}

impl fmt::Debug for Pieces {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_list().entries(self.as_slice().iter().map(|iv| (iv.enter.t, iv.exit.t))).finish()
    }
}
