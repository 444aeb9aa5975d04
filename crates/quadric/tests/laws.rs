//! The interval-set laws: regularised sets of `λ` form a Boolean algebra
//! within `[0, ∞)`. Checked three ways: the algebraic laws on the sets
//! themselves, membership at sampled points against the Boolean operation on
//! the inputs' membership, and a plain `Vec` reference for how many intervals
//! a result has (so that a capacity error is only ever reported when the true
//! result does not fit).
//!
//! Case counts come from `PROPTEST_CASES` (1000 in CI) through `ProptestConfig::default()`.

use proptest::prelude::*;
use quadric::strategies::interval_set;
use quadric::{Bound, CapacityError, Interval, IntervalSet};

const INF: f64 = f64::INFINITY;

/// Points to test membership at: every end of the strategy's sets lies on the
/// grid of quarters, so odd multiples of 1/8 are never on an end; plus
/// points far out on both sides.
fn probes() -> impl Iterator<Item = f64> {
    (-90..=90).map(|i| f64::from(2 * i + 1) / 8.0).chain([-1e300, -1e6, 1e6, 1e300])
}

/// `a ⊂ [0, ∞)` restricted: the part of `a` a ray can see.
fn ray_part(a: &IntervalSet) -> IntervalSet {
    a.clip(0.0, INF)
}

/// The everything-set of a ray.
fn whole_ray() -> IntervalSet {
    IntervalSet::from_interval(Bound::free(0.0), Bound::free(INF))
}

fn ends(a: &IntervalSet) -> Vec<Bound> {
    a.iter().flat_map(|iv| [iv.enter, iv.exit]).collect()
}

/// Every end of `out` is an end of one of `inputs` (same `t`, same solid), or
/// a free end at `0` or `±∞` (where the complement or a clip starts).
fn ends_come_from(out: &IntervalSet, inputs: &[&IntervalSet]) -> bool {
    ends(out).iter().all(|b| {
        inputs.iter().any(|s| ends(s).contains(b)) || (b.solid().is_none() && (b.t == 0.0 || b.t.is_infinite()))
    })
}

// A plain reference: closed intervals as `(lo, hi)` pairs, regularised by
// dropping intervals of zero length and merging those that touch.

fn pairs(a: &IntervalSet) -> Vec<(f64, f64)> {
    a.iter().map(|iv| (iv.enter.t, iv.exit.t)).collect()
}

fn merged(mut v: Vec<(f64, f64)>) -> Vec<(f64, f64)> {
    v.retain(|&(lo, hi)| lo < hi);
    v.sort_by(|x, y| x.0.total_cmp(&y.0));
    let mut out: Vec<(f64, f64)> = Vec::new();
    for (lo, hi) in v {
        match out.last_mut() {
            Some(last) if lo <= last.1 => last.1 = last.1.max(hi),
            _ => out.push((lo, hi)),
        }
    }
    out
}

fn ref_union(a: &IntervalSet, b: &IntervalSet) -> Vec<(f64, f64)> {
    merged(pairs(a).into_iter().chain(pairs(b)).collect())
}

fn ref_intersect(a: &IntervalSet, b: &IntervalSet) -> Vec<(f64, f64)> {
    let mut v = Vec::new();
    for (alo, ahi) in pairs(a) {
        for (blo, bhi) in pairs(b) {
            v.push((alo.max(blo), ahi.min(bhi)));
        }
    }
    merged(v)
}

fn ref_complement(a: &IntervalSet) -> Vec<(f64, f64)> {
    let mut v = Vec::new();
    let mut start = 0.0;
    for (lo, hi) in pairs(a) {
        v.push((start, lo));
        start = f64::max(start, hi);
    }
    v.push((start, INF));
    merged(v)
}

/// The operation's result agrees with the reference: the same intervals if
/// they fit, and a capacity error exactly when they do not.
fn agrees(got: Result<IntervalSet, CapacityError>, want: &[(f64, f64)]) -> Result<(), TestCaseError> {
    match got {
        Ok(set) => {
            prop_assert!(set.is_normalised(), "not normalised: {:?}", set);
            prop_assert_eq!(pairs(&set), want.to_vec());
        }
        Err(CapacityError) => prop_assert!(want.len() > IntervalSet::CAPACITY, "spurious capacity error: {:?}", want),
    }
    Ok(())
}

fn ok(r: Result<IntervalSet, CapacityError>) -> IntervalSet {
    r.expect("the strategy's sizes keep every result within capacity")
}

proptest! {
    // Cases from PROPTEST_CASES; failures are printed, not persisted (the
    // single test binary has no lib.rs for proptest to place a file beside).
    #![proptest_config(ProptestConfig { failure_persistence: None, ..ProptestConfig::default() })]

    // Up to 4 intervals: any union, intersection or complement of two sets fits.
    #[test]
    fn binary_laws(a in interval_set(4), b in interval_set(4)) {
        let (ab_and, ba_and) = (ok(a.intersect(&b)), ok(b.intersect(&a)));
        let (ab_or, ba_or) = (ok(a.union(&b)), ok(b.union(&a)));
        for s in [&ab_and, &ba_and, &ab_or, &ba_or] {
            prop_assert!(s.is_normalised(), "{:?}", s);
        }
        // Commutativity (as point sets; on coincident ends each keeps its own solid).
        prop_assert!(ab_and.same_points(&ba_and), "{:?} vs {:?}", ab_and, ba_and);
        prop_assert!(ab_or.same_points(&ba_or), "{:?} vs {:?}", ab_or, ba_or);
        // Idempotence (exactly, solids included).
        prop_assert_eq!(ok(a.intersect(&a)), a);
        prop_assert_eq!(ok(a.union(&a)), a);
        // Absorption.
        prop_assert!(ok(a.union(&ab_and)).same_points(&a));
        prop_assert!(ok(a.intersect(&ab_or)).same_points(&a));
        // Identity and null elements.
        prop_assert_eq!(ok(a.union(&IntervalSet::empty())), a);
        prop_assert_eq!(ok(a.intersect(&IntervalSet::everything())), a);
        prop_assert!(ok(a.intersect(&IntervalSet::empty())).is_empty());
        // De Morgan within the ray's domain [0, ∞).
        let (ca, cb) = (ok(a.complement()), ok(b.complement()));
        prop_assert!(ok(ab_or.complement()).same_points(&ok(ca.intersect(&cb))));
        prop_assert!(ok(ab_and.complement()).same_points(&ok(ca.union(&cb))));
        // Double complement gives back the part of the set on the ray.
        prop_assert!(ok(ca.complement()).same_points(&ray_part(&a)));
        // A set and its complement split the ray: nothing shared, everything covered.
        prop_assert!(ok(ca.intersect(&a)).is_empty());
        prop_assert!(ok(ca.union(&ray_part(&a))).same_points(&whole_ray()));
        // Ends come from the inputs, with their solids.
        for s in [&ab_and, &ba_and, &ab_or, &ba_or] {
            prop_assert!(ends_come_from(s, &[&a, &b]), "{:?}", s);
        }
        prop_assert!(ends_come_from(&ca, &[&a]), "{:?}", ca);
        // Where two ends coincide, the left operand's end is kept.
        for s in [&ab_and, &ab_or] {
            for e in ends(s) {
                if ends(&a).iter().any(|x| x.t == e.t) {
                    prop_assert!(ends(&a).contains(&e), "{:?} should keep a's end at {}", s, e.t);
                }
            }
        }
    }

    // Membership at points off every end agrees with the Boolean operation.
    #[test]
    fn pointwise_semantics(a in interval_set(4), b in interval_set(4), extra in proptest::collection::vec(-12.0f64..12.0, 8)) {
        let and = ok(a.intersect(&b));
        let or = ok(a.union(&b));
        let not_a = ok(a.complement());
        let clipped = a.clip(-1.5, 2.5);
        let on_end = |x: f64| [&a, &b].iter().any(|s| ends(s).iter().any(|e| e.t == x));
        for x in probes().chain(extra.into_iter().filter(|&x| !on_end(x))) {
            let (in_a, in_b) = (a.contains(x), b.contains(x));
            prop_assert_eq!(in_a, pairs(&a).iter().any(|&(lo, hi)| lo <= x && x <= hi));
            prop_assert_eq!(a.interval_at(x).is_some(), in_a);
            prop_assert_eq!(and.contains(x), in_a && in_b, "{} in {:?} ∩ {:?} = {:?}", x, a, b, and);
            prop_assert_eq!(or.contains(x), in_a || in_b, "{} in {:?} ∪ {:?} = {:?}", x, a, b, or);
            if x != 0.0 {
                prop_assert_eq!(not_a.contains(x), x > 0.0 && !in_a, "{} in ∁{:?} = {:?}", x, a, not_a);
            }
            if x != -1.5 && x != 2.5 {
                prop_assert_eq!(clipped.contains(x), in_a && (-1.5..=2.5).contains(&x));
            }
        }
        // The first entry is the smallest point of the set.
        prop_assert_eq!(a.first_entry().map(|e| e.t), pairs(&a).first().map(|p| p.0));
    }

    // Three sets of up to 2 intervals: every intermediate result fits.
    #[test]
    fn ternary_laws(a in interval_set(2), b in interval_set(2), c in interval_set(2)) {
        // Associativity.
        prop_assert!(ok(ok(a.union(&b)).union(&c)).same_points(&ok(a.union(&ok(b.union(&c))))));
        prop_assert!(ok(ok(a.intersect(&b)).intersect(&c)).same_points(&ok(a.intersect(&ok(b.intersect(&c))))));
        // Distributivity, both ways.
        let lhs = ok(a.intersect(&ok(b.union(&c))));
        let rhs = ok(ok(a.intersect(&b)).union(&ok(a.intersect(&c))));
        prop_assert!(lhs.same_points(&rhs), "{:?} vs {:?}", lhs, rhs);
        let lhs = ok(a.union(&ok(b.intersect(&c))));
        let rhs = ok(ok(a.union(&b)).intersect(&ok(a.union(&c))));
        prop_assert!(lhs.same_points(&rhs), "{:?} vs {:?}", lhs, rhs);
    }

    // Full-size sets: every operation either matches the reference or
    // reports that the true result has more intervals than fit.
    #[test]
    fn capacity_is_reported(a in interval_set(8), b in interval_set(8)) {
        agrees(a.union(&b), &ref_union(&a, &b))?;
        agrees(a.intersect(&b), &ref_intersect(&a, &b))?;
        agrees(a.complement(), &ref_complement(&a))?;
        // Building from a list of intervals in any order is a union.
        let all: Vec<Interval> = b.iter().rev().chain(a.iter()).copied().collect();
        agrees(IntervalSet::from_intervals(all), &ref_union(&a, &b))?;
        // Intersecting with one interval never overflows.
        let one = a.intersect_interval(Bound::new(-2.0, 9), Bound::new(3.0, 9));
        prop_assert!(one.is_normalised());
        prop_assert_eq!(pairs(&one), merged(pairs(&a).iter().map(|&(lo, hi)| (lo.max(-2.0), hi.min(3.0))).collect()));
    }

    // The complement within any window [lo, hi] is the gaps of the set there;
    // its ends come from the set or are free ends at lo and hi.
    #[test]
    fn complement_within_a_window(a in interval_set(4), lo in -44i32..44, len in 1i32..40) {
        let (lo, hi) = (f64::from(lo) / 4.0, f64::from(lo + len) / 4.0);
        let gaps = a.complement_within(lo, hi).expect("at most five gaps");
        prop_assert!(gaps.is_normalised(), "{:?}", gaps);
        for e in ends(&gaps) {
            prop_assert!(ends(&a).contains(&e) || (e.solid().is_none() && (e.t == lo || e.t == hi)), "{:?} in {:?}", e, gaps);
        }
        for x in probes().filter(|&x| x != lo && x != hi) {
            prop_assert_eq!(gaps.contains(x), lo < x && x < hi && !a.contains(x), "{} in {:?} vs {:?}", x, a, gaps);
        }
    }

    // `retain` keeps a normalised subset in order.
    #[test]
    fn retain_keeps_order(a in interval_set(8), cut in -10.0f64..10.0) {
        let mut kept = a;
        kept.retain(|iv| iv.enter.t >= cut);
        prop_assert!(kept.is_normalised());
        let want: Vec<_> = pairs(&a).into_iter().filter(|p| p.0 >= cut).collect();
        prop_assert_eq!(pairs(&kept), want);
    }
}

#[test]
fn capacity_overflow_examples() {
    // Nine disjoint intervals do not fit; the error is reported, not a wrong set.
    let unit =
        |i: i32| IntervalSet::from_interval(Bound::new(f64::from(2 * i), 0), Bound::new(f64::from(2 * i) + 1.0, 0));
    let eight = (0..8).try_fold(IntervalSet::empty(), |acc, i| acc.union(&unit(i))).expect("eight fit");
    assert_eq!(eight.len(), 8);
    assert_eq!(eight.union(&unit(8)), Err(CapacityError));
    // …but unions that merge into what is there fit.
    let extend = IntervalSet::from_interval(Bound::new(14.5, 1), Bound::new(20.0, 1));
    assert_eq!(eight.union(&extend).map(|s| s.len()), Ok(8));
    let bridge = IntervalSet::from_interval(Bound::new(0.5, 1), Bound::new(2.5, 1));
    assert_eq!(eight.union(&bridge).map(|s| s.len()), Ok(7));
    // The complement of eight bounded intervals within [0, ∞) starting after 0 has nine gaps.
    let shifted =
        (0..8).map(|i| Interval::new(Bound::new(f64::from(2 * i) + 1.0, 0), Bound::new(f64::from(2 * i) + 2.0, 0)));
    let shifted = IntervalSet::from_intervals(shifted).expect("eight fit");
    assert_eq!(shifted.complement(), Err(CapacityError));
    // The one starting at 0 leaves eight gaps.
    assert_eq!(eight.complement().map(|s| s.len()), Ok(8));
}

#[test]
fn empty_and_nan_intervals_are_dropped() {
    assert!(IntervalSet::from_interval(Bound::new(1.0, 0), Bound::new(1.0, 0)).is_empty());
    assert!(IntervalSet::from_interval(Bound::new(2.0, 0), Bound::new(1.0, 0)).is_empty());
    assert!(IntervalSet::from_interval(Bound::new(f64::NAN, 0), Bound::new(1.0, 0)).is_empty());
    assert!(IntervalSet::from_interval(Bound::new(0.0, 0), Bound::new(f64::NAN, 0)).is_empty());
    let touching =
        [Interval::new(Bound::new(0.0, 0), Bound::new(1.0, 0)), Interval::new(Bound::new(1.0, 1), Bound::new(2.0, 1))];
    let merged = IntervalSet::from_intervals(touching).expect("fits");
    assert_eq!(pairs(&merged), vec![(0.0, 2.0)]);
    assert_eq!((merged.as_slice()[0].enter.solid, merged.as_slice()[0].exit.solid), (0, 1));
    assert!(merged.is_normalised());
}
