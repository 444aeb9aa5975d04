//! Unit normals from gradients.

use nalgebra::Vector3;

/// `g / |g|`, computed after scaling by the largest component so that tiny
/// and huge gradients neither underflow nor overflow; `None` for a zero or
/// non-finite gradient.
///
/// ```
/// use nalgebra::Vector3;
/// use quadric::normal::unit;
/// assert_eq!(unit(Vector3::new(0.0, 3e-320, 0.0)), Some(Vector3::y()));
/// assert_eq!(unit(Vector3::new(f64::NAN, 1.0, 0.0)), None);
/// assert_eq!(unit(Vector3::zeros()), None);
/// ```
#[inline]
pub fn unit(g: Vector3<f64>) -> Option<Vector3<f64>> {
    // Checked per component: `amax` skips a NaN component.
    if !g.iter().all(|c| c.is_finite()) {
        return None;
    }
    let m = g.amax();
    if m == 0.0 {
        return None;
    }
    // Along an axis (two components exactly zero, the normal of most
    // half-spaces): the divisions below give that axis exactly, `±1` and the
    // two zeros with their signs.
    if g.iter().filter(|c| **c == 0.0).count() == 2 {
        return Some(g.map(|c| if c == 0.0 { c } else { c.signum() }));
    }
    Some(scaled(&g, m))
}

/// `g / |g|` by way of `g / m`, `m = max |gᵢ| > 0`.
#[inline(always)]
fn scaled(g: &Vector3<f64>, m: f64) -> Vector3<f64> {
    let g = crate::lanes::div(g, m);
    crate::lanes::div(&g, g.norm())
}

/// `n` turned to face against the direction `r` of an incoming ray.
#[inline]
pub fn facing(n: Vector3<f64>, r: &Vector3<f64>) -> Vector3<f64> {
    if n.dot(r) > 0.0 {
        -n
    } else {
        n
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// `check(n, r, want)`: `facing(n, r)` is `want`, bit for bit.
    fn check(n: [f64; 3], r: [f64; 3], want: [f64; 3]) {
        let got = facing(Vector3::from(n), &Vector3::from(r));
        assert_eq!(got.map(f64::to_bits), Vector3::from(want).map(f64::to_bits), "facing({n:?}, {r:?})");
    }

    #[test]
    fn facing_turns_the_normal_against_the_ray() {
        let up = [0.0, 1.0, 0.0];
        check(up, [0.0, -1.0, 0.0], up); // already against the ray
        check(up, [0.0, 1.0, 0.0], [-0.0, -1.0, -0.0]); // along it: turned
        check(up, [0.6, 0.8, 0.0], [-0.0, -1.0, -0.0]);
        check(up, [0.0, 1e-300, 1.0], [-0.0, -1.0, -0.0]); // barely along it
        check(up, [1.0, 0.0, 0.0], up); // grazing (n·r = 0): kept
        check(up, [1.0, -0.0, 0.0], up);
    }

    proptest! {
        /// The axis shortcut is what the divisions give, bit for bit.
        #[test]
        fn axis_normals_are_the_divided_ones(
            axis in 0usize..3,
            // Any finite non-zero value (drawn so, rather than rejected: at
            // a high case count the rejects would abort the test).
            c in prop_oneof![
                prop::num::f64::POSITIVE | prop::num::f64::NEGATIVE | prop::num::f64::NORMAL | prop::num::f64::SUBNORMAL,
                -1e3..1e3f64,
                Just(f64::MIN_POSITIVE / 7.0),
                Just(f64::MAX),
            ],
            zero_signs in any::<(bool, bool)>(),
        ) {
            prop_assume!(c != 0.0);
            let zero = |negative: bool| if negative { -0.0 } else { 0.0 };
            let mut g = Vector3::new(zero(zero_signs.0), zero(zero_signs.1), 0.0);
            g[2] = g[axis];
            g[axis] = c;
            let got = unit(g).expect("a non-zero finite gradient");
            let want = scaled(&g, g.amax());
            for k in 0..3 {
                prop_assert_eq!(got[k].to_bits(), want[k].to_bits(), "{:?}: {:?} against {:?}", g, got, want);
            }
        }
    }
}
