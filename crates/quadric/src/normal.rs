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
    let g = crate::lanes::div(&g, m);
    Some(crate::lanes::div(&g, g.norm()))
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
