//! One solid (from coefficients, a matrix, a half-space or an elementary
//! quadric, maybe complemented, moved by a chain of transforms), rays and
//! points. Checks: bad input is rejected with an error (in `komplex_fuzz`'s
//! builders); no panic; no NaN out of `intervals`, `value`, `gradient`,
//! `normal`; every interval set is normalised and tagged; a solid and its
//! complement partition the ray; set membership agrees with the sign of `f`
//! wherever that sign is certain; `f` is about zero at every finite end.
#![no_main]

use std::sync::atomic::{AtomicBool, Ordering};

use komplex_fuzz::{bound, QuadricInput};
use libfuzzer_sys::fuzz_target;
use quadric::nalgebra::Point3;
use quadric::{IntervalSet, Ray, Solid};

/// Accuracy is checked only in the moderate range (see `bound::moderate_solid`).
/// A bound on the error of `f` computed at `ray.at(t)`, in units of the
/// rounding unit: the evaluation error of `f` (relative to the magnitude of
/// its terms) plus the displacement of the rounded point (`|∇f|` times the
/// rounding of `p + t r` and of `r`, plus the curvature term for the change of
/// the gradient over that distance). Generous, so that a failure is a real
/// loss of accuracy, not an unlucky rounding.
const ULPS: f64 = 256.0;

const TAG: u32 = 7;

/// How far along a ray a solid and its complement must partition it.
const FAR: f64 = 1e100;

/// Whether the current input's numbers are all moderate (set per input).
static MODERATE_INPUT: AtomicBool = AtomicBool::new(false);

/// Whether the ray's origin and (unit) direction components are moderate: a
/// direction component of 1e-323 has no significant bits left.
fn moderate_ray(ray: &Ray) -> bool {
    ray.origin().iter().chain(ray.direction().iter()).all(|x| bound::moderate(*x))
}

fn tolerance(s: &Solid, ray: &Ray, t: f64) -> Option<f64> {
    let p = ray.at(t);
    if !(MODERATE_INPUT.load(Ordering::Relaxed)
        && moderate_ray(ray)
        && bound::moderate_solid(s)
        && p.iter().all(|x| bound::moderate(*x))
        && t <= 1e100)
    {
        return None;
    }
    let m = bound::magnitude(s, &p)?;
    let g = bound::gradient(s, &p)?;
    // How far the rounded point may be from the exact one.
    // (With absolute floors: relative bounds fail among subnormals.)
    let tiny = f64::from_bits(1);
    // The kernel's accuracy is stated relative to the distances involved,
    // including the one from the solid's centre (where it re-bases the ray).
    let from_centre = (ray.origin() - bound::centre(s)).amax();
    let h = ULPS * (f64::EPSILON * (ray.origin().coords.amax() + t.abs() + from_centre) + tiny);
    let tol = ULPS * (f64::EPSILON * m + f64::MIN_POSITIVE) + g * h + bound::curvature(s) * h * h;
    tol.is_finite().then_some(tol)
}

/// Whether no intermediate of `intervals` can overflow: the coefficients of
/// `f(p + λr) = sλ² + 2tλ + u` and `t² - su` are finite with room to spare.
/// Outside this range (coordinates or coefficients near 1e150 and beyond) the
/// kernel promises only "no NaN, no panic" (ARCHITECTURE.md).
fn in_range(solid: &Solid, ray: &Ray) -> bool {
    // Beyond moderate inputs (coefficients near 1e308 or 1e-320, which a
    // kernel may rescale into subnormals), only "no panic, no NaN" holds.
    if !(MODERATE_INPUT.load(Ordering::Relaxed) && moderate_ray(ray)) {
        return false;
    }
    let Some(m) = bound::magnitude(solid, &ray.origin()) else { return false };
    let room = f64::MAX / 64.0;
    match solid {
        Solid::HalfSpace(h) => {
            let n = h.normal_vector().amax();
            m < room && n * (1.0 + (ray.origin() - h.reference_point()).amax()) < room
        }
        Solid::Quadric(q) => {
            let (c, a, w, _) = q.local_parts();
            let d = (ray.origin() - c).amax();
            let (s, t) = (3.0 * a.amax(), 3.0 * a.amax() * d + w.amax());
            let disc = t * t + s * m;
            m < room && disc < room
        }
    }
}

/// Sample parameters: the midpoint of every interval and of every gap, and
/// points beyond the last end.
fn samples(set: &IntervalSet) -> Vec<f64> {
    let mut ends = vec![0.0];
    for iv in set {
        ends.push(iv.enter.t);
        ends.push(iv.exit.t);
    }
    let mut out = Vec::new();
    for w in ends.windows(2) {
        if w[0] < w[1] && w[1].is_finite() {
            out.push(0.5 * w[0] + 0.5 * w[1]);
        }
    }
    let last = ends.iter().copied().filter(|t| t.is_finite()).fold(0.0, f64::max);
    out.extend([last + 1.0, 2.0 * last + 1.0, last + 1e6]);
    out
}

fn check_ray(solid: &Solid, ray: &Ray) {
    let set = solid.intervals(ray, TAG);
    assert!(set.is_normalised(), "not normalised: {set:?}");
    for iv in &set {
        for b in [iv.enter, iv.exit] {
            assert!(b.t >= 0.0, "an end before the ray origin: {set:?}");
            // (An infinite end may carry the solid: a root that overflowed.)
            if b.t > 0.0 && b.t.is_finite() {
                assert_eq!(b.solid, TAG, "a finite end not tagged with the solid: {set:?}");
            }
        }
    }

    if !in_range(solid, ray) {
        return;
    }
    // The complement has exactly the other points: together they cover the
    // ray, and they overlap only if the whole ray lies in the surface. (Up to
    // `FAR` along it: roots beyond are outside the documented range.)
    let full = solid.complement().intervals(ray, TAG);
    assert!(full.is_normalised(), "complement not normalised: {full:?}");
    let (set, other) = (set.clip(0.0, FAR), full.clip(0.0, FAR));
    let union = set.union(&other).expect("two sets of at most two intervals each");
    assert!(
        union.len() == 1 && union.as_slice()[0].enter.t == 0.0 && union.as_slice()[0].exit.t == FAR,
        "a solid and its complement do not cover the ray: {set:?} ∪ {other:?}"
    );
    let both = set.intersect(&other).expect("within capacity");
    if !both.is_empty() {
        // Only a ray lying in the surface (f ≡ 0 along it) is in both.
        assert!(set == union && other == union, "a solid and its complement overlap: {set:?} ∩ {other:?}");
        let f = solid.value(&ray.origin());
        if let Some(tol) = tolerance(solid, ray, 0.0) {
            assert!(f.abs() <= tol, "the ray lies in the surface but f = {f:e} at its origin");
        }
    }

    let set = solid.intervals(ray, TAG);
    // Every finite end lies on the surface, to rounding.
    for iv in &set {
        for b in [iv.enter, iv.exit] {
            if b.t > 0.0 && b.t.is_finite() {
                let f = solid.value(&ray.at(b.t));
                if let Some(tol) = tolerance(solid, ray, b.t) {
                    assert!(f.abs() <= tol, "f = {f:e} at the end t = {:e} of {set:?} (tolerance {tol:e})", b.t);
                }
            }
        }
    }

    // Inside the set f <= 0 and outside f >= 0, wherever f's sign is certain.
    for t in samples(&set) {
        let p = ray.at(t);
        let f = solid.value(&p);
        if let Some(tol) = tolerance(solid, ray, t) {
            assert!(!f.is_nan(), "f is NaN at t = {t:e} within the documented range");
            if f.abs() > tol {
                assert_eq!(set.contains(t), f < 0.0, "t = {t:e}: f = {f:e} (tolerance {tol:e}) but the set is {set:?}");
            }
        }
    }
}

fn check_point(solid: &Solid, p: &Point3<f64>) {
    let f = solid.value(p);
    assert_eq!(solid.contains_point(p), f <= 0.0);
    // No overflow in any term (with a factor 8 of headroom for the sums):
    // then nothing may come out NaN or infinite.
    let small = |m: Option<f64>| m.is_some_and(|m| m < f64::MAX / 8.0);
    // (`f` goes through `A(x - c) + w`, the gradient: both must be small.)
    if small(bound::magnitude(solid, p)) && small(bound::gradient(solid, p)) {
        assert!(f.is_finite(), "f = {f} at {p:?}");
    }
    if let Solid::Quadric(q) = solid {
        let g = q.gradient(p);
        if small(bound::gradient(solid, p)) {
            assert!(g.iter().all(|c| c.is_finite()), "gradient {g:?} at {p:?}");
        }
        let n = q.normal(p);
        if g.iter().all(|c| c.is_finite()) && g.amax() > 0.0 {
            assert!(n.is_some(), "no normal where the gradient is {g:?}");
        }
    }
    if let Some(n) = solid.normal(p) {
        assert!(n.iter().all(|c| c.is_finite()) && (n.norm() - 1.0).abs() <= 1e-12, "normal {n:?} at {p:?}");
    }
}

fuzz_target!(|input: QuadricInput| {
    MODERATE_INPUT.store(input.solid.moderate(), Ordering::Relaxed);
    let rays: Vec<Ray> = input.rays.iter().filter_map(|r| r.build().ok()).collect();
    let Ok(solid) = input.solid.build() else { return };
    let finite = match &solid {
        Solid::Quadric(q) => q.is_finite(),
        Solid::HalfSpace(h) => h.is_finite(),
    };
    // A chain of finite steps can overflow; `Block::new` rejects such solids
    // (the `complex_queries` target checks that), so queries need not handle them.
    if !finite {
        return;
    }
    for ray in &rays {
        check_ray(&solid, ray);
    }
    for p in &input.points {
        check_point(&solid, &p.point());
    }
    for ray in &rays {
        for t in samples(&solid.intervals(ray, TAG)) {
            check_point(&solid, &ray.at(t));
        }
    }
});
