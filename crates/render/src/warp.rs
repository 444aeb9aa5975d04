//! Warps from the unit square to directions and points, each with its
//! density (docs/model.md §5.8.2), and the orthonormal [`Basis`] that
//! carries a local direction (`z` along a chosen axis) into the world.
//!
//! Directions are unit vectors in a local frame whose `z` axis is the
//! normal (or, for a cone, the cone's axis); densities are per steradian.
//! The names follow pbrt-v4 (`sampling.h`).
//!
//! ```
//! use render::warp::{cosine_hemisphere_pdf, sample_cosine_hemisphere};
//! let w = sample_cosine_hemisphere([0.3, 0.8]);
//! assert!((w.norm() - 1.0).abs() < 1e-15 && w.z >= 0.0);
//! assert!(cosine_hemisphere_pdf(w.z) > 0.0);
//! ```

use std::f64::consts::{FRAC_1_PI, FRAC_PI_2, FRAC_PI_4, TAU};

use quadric::nalgebra::Vector3;

/// Shirley and Chiu's concentric map from `[0, 1)²` onto the unit disc:
/// uniform in area (density `1/π`), squares to rings, so stratification of
/// `u` survives.
pub fn sample_uniform_disk_concentric(u: [f64; 2]) -> [f64; 2] {
    let (x, y) = (2.0 * u[0] - 1.0, 2.0 * u[1] - 1.0);
    if x == 0.0 && y == 0.0 {
        return [0.0, 0.0];
    }
    let (r, theta) = if x.abs() > y.abs() { (x, FRAC_PI_4 * (y / x)) } else { (y, FRAC_PI_2 - FRAC_PI_4 * (x / y)) };
    [r * theta.cos(), r * theta.sin()]
}

/// The density of [`sample_uniform_disk_concentric`] per unit area.
pub const UNIFORM_DISK_PDF: f64 = FRAC_1_PI;

/// A direction in the `z ≥ 0` hemisphere with density `cos θ / π`
/// (Malley's method: a uniform point of the disc lifted onto the
/// hemisphere).
pub fn sample_cosine_hemisphere(u: [f64; 2]) -> Vector3<f64> {
    let [x, y] = sample_uniform_disk_concentric(u);
    Vector3::new(x, y, (1.0 - x * x - y * y).max(0.0).sqrt())
}

/// The density of [`sample_cosine_hemisphere`] at a direction with
/// `cos θ = cos_theta` (zero below the horizon).
pub fn cosine_hemisphere_pdf(cos_theta: f64) -> f64 {
    cos_theta.max(0.0) * FRAC_1_PI
}

/// A direction uniform over the sphere (`z = 1 − 2u₀` is uniform by
/// Archimedes' hat-box theorem).
pub fn sample_uniform_sphere(u: [f64; 2]) -> Vector3<f64> {
    let z = 1.0 - 2.0 * u[0];
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = TAU * u[1];
    Vector3::new(r * phi.cos(), r * phi.sin(), z)
}

/// The density of [`sample_uniform_sphere`]: `1/(4π)`.
pub const UNIFORM_SPHERE_PDF: f64 = 0.25 * FRAC_1_PI;

/// A direction uniform in solid angle within the cone of half-angle
/// `θ_max` around `+z` (`cos θ` uniform in `[cos θ_max, 1]`): a sphere light
/// seen from outside subtends such a cone. `cos_theta_max` is in `[−1, 1]`.
pub fn sample_uniform_cone(u: [f64; 2], cos_theta_max: f64) -> Vector3<f64> {
    let cos_theta = (1.0 - u[0]) + u[0] * cos_theta_max;
    let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    let phi = TAU * u[1];
    Vector3::new(sin_theta * phi.cos(), sin_theta * phi.sin(), cos_theta)
}

/// The density of [`sample_uniform_cone`] inside the cone,
/// `1 / (2π (1 − cos θ_max))`; infinite for a cone of no width.
pub fn uniform_cone_pdf(cos_theta_max: f64) -> f64 {
    1.0 / (TAU * (1.0 - cos_theta_max))
}

/// A right-handed orthonormal basis `(x, y, z)` with `z` a given unit
/// vector: local directions (`z` the normal or a lobe's axis) to the world
/// and back.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Basis {
    /// The first tangent.
    pub x: Vector3<f64>,
    /// The second tangent, `z × x`.
    pub y: Vector3<f64>,
    /// The axis the basis was built around.
    pub z: Vector3<f64>,
}

impl Basis {
    /// The basis around the unit vector `z`, without branches on its
    /// direction except the sign of `z.z` (Duff et al., "Building an
    /// Orthonormal Basis, Revisited", JCGT 2017): continuous everywhere but
    /// across `z.z = 0`, and exact to a few ulps.
    pub fn from_z(z: Vector3<f64>) -> Self {
        let sign = 1f64.copysign(z.z);
        let a = -1.0 / (sign + z.z);
        let b = z.x * z.y * a;
        let x = Vector3::new(1.0 + sign * z.x * z.x * a, sign * b, -sign * z.x);
        let y = Vector3::new(b, sign + z.y * z.y * a, -z.y);
        Self { x, y, z }
    }

    /// The world direction of local coordinates `v`.
    pub fn to_world(&self, v: &Vector3<f64>) -> Vector3<f64> {
        self.x * v.x + self.y * v.y + self.z * v.z
    }

    /// The local coordinates of the world direction `v`.
    pub fn to_local(&self, v: &Vector3<f64>) -> Vector3<f64> {
        Vector3::new(self.x.dot(v), self.y.dot(v), self.z.dot(v))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::chi_square::{chi_square_p_value, integrate_sphere, test_directions, Grid};
    use crate::sampling::Sampler;

    /// Each test's significance (Šidák-corrected over this file's tests).
    const ALPHA: f64 = 1e-3;
    const N: u64 = 100_000;

    fn check(name: &str, pdf: impl Fn(&Vector3<f64>) -> f64 + Copy, sample: impl Fn([f64; 2]) -> Vector3<f64>) {
        let mass = integrate_sphere(pdf);
        assert!((mass - 1.0).abs() < 1e-4, "{name}: the pdf integrates to {mass}");
        let o = test_directions(&Vector3::z(), pdf, |u| Some(sample(u)), N, 2);
        assert!(o.p > ALPHA, "{name}: chi-square p = {}", o.p);
        assert_eq!(o.failed, 0);
        for i in 0..1000 {
            let w = sample(Sampler::new(3, i, 0).uniform2(0));
            assert!((w.norm() - 1.0).abs() < 1e-14, "{name}: |{w:?}| ≠ 1");
        }
    }

    #[test]
    fn the_cosine_hemisphere_follows_its_pdf() {
        check("cosine hemisphere", |w| cosine_hemisphere_pdf(w.z), sample_cosine_hemisphere);
    }

    #[test]
    fn the_uniform_sphere_follows_its_pdf() {
        check("uniform sphere", |_| UNIFORM_SPHERE_PDF, sample_uniform_sphere);
    }

    #[test]
    fn uniform_cones_follow_their_pdf() {
        // Half-angles from a small light's 10° to wider than a hemisphere,
        // including a cone that the grid's cells cut through.
        for cos_max in [0.985, 0.8, 0.3, 0.0, -0.6] {
            let pdf = move |w: &Vector3<f64>| if w.z >= cos_max { uniform_cone_pdf(cos_max) } else { 0.0 };
            check(&format!("cone cos θmax = {cos_max}"), pdf, |u| sample_uniform_cone(u, cos_max));
            // Samples stay in the cone (a point on the boundary is fine).
            for i in 0..1000 {
                let w = sample_uniform_cone(Sampler::new(4, i, 0).uniform2(0), cos_max);
                assert!(w.z >= cos_max - 1e-15);
            }
        }
    }

    #[test]
    fn the_concentric_disc_is_uniform_in_area() {
        // Binned in (r², φ), where the uniform disc's density is the
        // constant 1/(2π): dA = r dr dφ = ½ d(r²) dφ.
        let grid = Grid { a: (0.0, 1.0), b: (0.0, TAU), na: 16, nb: 32 };
        let density = |_: f64, _: f64| UNIFORM_DISK_PDF / 2.0;
        let expected: Vec<f64> = grid.integrate(&density, 1e-9).iter().map(|m| m * N as f64).collect();
        assert!((expected.iter().sum::<f64>() / N as f64 - 1.0).abs() < 1e-12);
        let points = (0..N).map(|i| {
            let [x, y] = sample_uniform_disk_concentric(Sampler::new(5, i, 0).uniform2(0));
            let phi = y.atan2(x);
            (x * x + y * y, if phi < 0.0 { phi + TAU } else { phi })
        });
        let p = chi_square_p_value(&grid.histogram(points), &expected);
        assert!(p > ALPHA, "concentric disc: p = {p}");
    }

    #[test]
    fn bases_are_orthonormal_and_right_handed_and_invert() {
        for i in 0..10_000 {
            let z = sample_uniform_sphere(Sampler::new(6, i, 0).uniform2(0));
            let b = Basis::from_z(z);
            for (u, v, expected) in
                [(b.x, b.x, 1.0), (b.y, b.y, 1.0), (b.z, b.z, 1.0), (b.x, b.y, 0.0), (b.x, b.z, 0.0), (b.y, b.z, 0.0)]
            {
                assert!((u.dot(&v) - expected).abs() < 1e-14, "{z:?}");
            }
            assert!((b.x.cross(&b.y) - b.z).norm() < 1e-14, "right-handed at {z:?}");
            let w = Vector3::new(0.3, -0.5, 0.8);
            assert!((b.to_local(&b.to_world(&w)) - w).norm() < 1e-14);
        }
        for z in [Vector3::z(), -Vector3::z(), Vector3::x(), -Vector3::y()] {
            assert_eq!(Basis::from_z(z).z, z);
            assert!((Basis::from_z(z).x.cross(&Basis::from_z(z).y) - z).norm() < 1e-15);
        }
    }
}
