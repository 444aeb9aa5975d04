//! Component-wise divisions of a vector in one four-lane instruction.
//!
//! A direction or a gradient is normalised by dividing its three components
//! by one number, twice (by the largest magnitude, then by the length), and
//! a ray's slab test needs the three reciprocals of its direction. Done one
//! component at a time these are chains of scalar divisions, among the
//! slowest instructions there are; a secondary ray's setup had nine of
//! them. IEEE 754 division is correctly rounded lane by lane, so the packed
//! division (`f64x4` of the `wide` crate: AVX where the target has it, two
//! SSE2 halves otherwise) gives exactly the scalar values: nothing an
//! image or a test can see changes.
//!
//! ```
//! use nalgebra::Vector3;
//! use quadric::lanes;
//! let v = Vector3::new(1.0, -3.0, 1e-300);
//! assert_eq!(lanes::div(&v, 7.0), v / 7.0);
//! assert_eq!(lanes::recip([2.0, -0.0, 3.0]), [0.5, f64::NEG_INFINITY, 1.0 / 3.0]);
//! ```

use nalgebra::Vector3;
use wide::f64x4;

/// `v / s`, component-wise: the same values as `v / s`.
#[inline(always)]
pub fn div(v: &Vector3<f64>, s: f64) -> Vector3<f64> {
    // The fourth lane is padding (`s / s`; NaN for a zero `s` is harmless).
    let [x, y, z, _] = (f64x4::new([v.x, v.y, v.z, s]) / f64x4::splat(s)).to_array();
    Vector3::new(x, y, z)
}

/// `[1/x, 1/y, 1/z]`: the same values as three scalar divisions.
#[inline(always)]
pub fn recip(v: [f64; 3]) -> [f64; 3] {
    let [x, y, z, _] = (f64x4::splat(1.0) / f64x4::new([v[0], v[1], v[2], 1.0])).to_array();
    [x, y, z]
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn any_f64() -> impl Strategy<Value = f64> {
        prop_oneof![
            any::<f64>(),
            Just(0.0),
            Just(-0.0),
            Just(f64::INFINITY),
            Just(f64::NEG_INFINITY),
            Just(f64::MIN_POSITIVE / 3.0),
            -1e3..1e3f64,
        ]
    }

    fn same(a: f64, b: f64) -> bool {
        a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
    }

    proptest! {
        /// Bit for bit the scalar divisions, signed zeros, infinities,
        /// subnormals and NaN included.
        #[test]
        fn packed_divisions_are_the_scalar_ones(x in any_f64(), y in any_f64(), z in any_f64(), s in any_f64()) {
            let v = Vector3::new(x, y, z);
            let q = div(&v, s);
            for k in 0..3 {
                prop_assert!(same(q[k], v[k] / s), "{} / {} = {} packed, {} scalar", v[k], s, q[k], v[k] / s);
            }
            let r = recip([x, y, z]);
            for k in 0..3 {
                prop_assert!(same(r[k], 1.0 / v[k]), "1 / {}", v[k]);
            }
        }
    }
}
