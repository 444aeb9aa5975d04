//! The scattering lobes of the path integrator (docs/model.md §5.8.3), one
//! per part of a material: `diffuse` ([`Bsdf::Diffuse`]), `specular` with
//! its `shininess` and `model` ([`Bsdf::Phong`], [`Bsdf::BlinnPhong`]),
//! `reflect` ([`Bsdf::Mirror`]) and `transmit` with `ior`
//! ([`Bsdf::Dielectric`]). Each lobe is colourless (its albedo is at most
//! one); the material scales it by its colour.
//!
//! Directions are unit vectors in the local frame of the surface, `z` the
//! shading normal, and both point away from the surface (`wo` towards the
//! viewer, `wi` towards the light), as in pbrt-v4. `eval` is the BSDF value
//! `f(wo, wi)` (per steradian, without the cosine), `pdf` the density of
//! `sample` per steradian, and a sample's weight is `f |cos θi| / pdf`.
//! Perfectly specular lobes (mirror and dielectric) are Dirac deltas: their
//! `eval` and `pdf` are zero, and `sample` returns the weight through `f`
//! with `pdf` the probability of the discrete choice, `delta` set.
//!
//! ```
//! use render::bsdf::Bsdf;
//! use quadric::nalgebra::Vector3;
//! let wo = Vector3::new(0.6, 0.0, 0.8);
//! let s = Bsdf::Phong { shininess: 20.0 }.sample(&wo, [0.4, 0.7], 0.5).unwrap();
//! assert!(!s.delta && s.pdf > 0.0);
//! assert_eq!(s.f, Bsdf::Phong { shininess: 20.0 }.eval(&wo, &s.wi));
//! ```

use std::f64::consts::{FRAC_1_PI, TAU};

use quadric::nalgebra::Vector3;

use crate::warp::{cosine_hemisphere_pdf, sample_cosine_hemisphere, Basis};

/// One lobe of a material.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Bsdf {
    /// Lambertian reflection, `f = 1/π`: a `diffuse` colour is the albedo.
    Diffuse,
    /// Normalised Phong (Lewis 1994): `f = (p + 2)/(2π) cos^p α`, `α` the
    /// angle between `wi` and the mirror direction of `wo`.
    Phong {
        /// The exponent `p ≥ 0`.
        shininess: f64,
    },
    /// Normalised Blinn-Phong in the half vector `h` (Ashikhmin and Shirley
    /// 2000, isotropic, no Fresnel factor): `f = (p + 1)/(8π) cos^p θh /
    /// ((wi·h) max(cos θi, cos θo))`.
    BlinnPhong {
        /// The exponent `p ≥ 0`.
        shininess: f64,
    },
    /// A perfect mirror, reflectance 1.
    Mirror,
    /// A smooth dielectric boundary: exact unpolarised Fresnel reflection,
    /// Snell refraction, total internal reflection.
    Dielectric {
        /// The index of refraction of the `z < 0` side over that of the
        /// `z > 0` side (`ior` of the glass over the outside, with `z`
        /// pointing out of the glass).
        eta: f64,
    },
}

/// A direction drawn by [`Bsdf::sample`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BsdfSample {
    /// The sampled direction `wi`, a unit vector in the local frame.
    pub wi: Vector3<f64>,
    /// `f(wo, wi)`; for a delta lobe, the weight of the delta (so that
    /// `f |cos θi| / pdf` is the sample's weight in both cases).
    pub f: f64,
    /// The density of `wi` per steradian; for a delta lobe, the probability
    /// of the choice made (reflection or transmission).
    pub pdf: f64,
    /// Whether the lobe is a Dirac delta (mirror or dielectric): no light
    /// sample can reach it, and multiple importance sampling skips it.
    pub delta: bool,
}

impl BsdfSample {
    /// `f |cos θi| / pdf`, the factor the sample multiplies a path's
    /// throughput by (zero for a sample of zero density).
    pub fn weight(&self) -> f64 {
        if self.pdf > 0.0 {
            self.f * self.wi.z.abs() / self.pdf
        } else {
            0.0
        }
    }
}

/// The mirror image of `w` about the normal `z`.
fn mirror(w: &Vector3<f64>) -> Vector3<f64> {
    Vector3::new(-w.x, -w.y, w.z)
}

/// `wo` and `wi` on the same side of the surface (strictly).
fn same_side(wo: &Vector3<f64>, wi: &Vector3<f64>) -> bool {
    wo.z * wi.z > 0.0
}

/// A direction of the lobe `cos^p` around `+z` (`cos θ = u₀^{1/(p+1)}`),
/// with density `(p + 1)/(2π) cos^p θ` on the hemisphere.
fn sample_power_cosine(u: [f64; 2], p: f64) -> Vector3<f64> {
    let cos = u[0].powf(1.0 / (p + 1.0));
    let sin = (1.0 - cos * cos).max(0.0).sqrt();
    let phi = TAU * u[1];
    Vector3::new(sin * phi.cos(), sin * phi.sin(), cos)
}

/// The density of [`sample_power_cosine`] at `cos θ` (zero for `cos θ ≤ 0`).
fn power_cosine_pdf(cos: f64, p: f64) -> f64 {
    if cos > 0.0 {
        (p + 1.0) / TAU * cos.powf(p)
    } else {
        0.0
    }
}

/// The unpolarised Fresnel reflectance of a smooth dielectric boundary for
/// light arriving at `cos θi` from the normal's side (negative: from the
/// other side), `eta` the index of the far side of the normal over the
/// near side's; 1 under total internal reflection (pbrt-v4's
/// `FrDielectric`).
pub fn fresnel_dielectric(cos_theta_i: f64, eta: f64) -> f64 {
    let (mut cos_i, mut eta) = (cos_theta_i.clamp(-1.0, 1.0), eta);
    if cos_i < 0.0 {
        eta = 1.0 / eta;
        cos_i = -cos_i;
    }
    let sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).max(0.0).sqrt();
    let r_parallel = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_perpendicular = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    (r_parallel * r_parallel + r_perpendicular * r_perpendicular) / 2.0
}

/// The direction refracted from `wo` through the boundary with normal `+z`
/// and relative index `eta` (as [`Bsdf::Dielectric`]), with the ratio of
/// indices `η_t/η_i` along the way; `None` under total internal reflection.
/// The same formula as docs/model.md §5.5 with `η_r = η_i/η_t`.
pub fn refract(wo: &Vector3<f64>, eta: f64) -> Option<(Vector3<f64>, f64)> {
    let (mut cos_i, mut eta, mut n) = (wo.z, eta, Vector3::z());
    if cos_i < 0.0 {
        eta = 1.0 / eta;
        cos_i = -cos_i;
        n = -n;
    }
    let sin2_t = (1.0 - cos_i * cos_i).max(0.0) / (eta * eta);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some((-wo / eta + (cos_i / eta - cos_t) * n, eta))
}

impl Bsdf {
    /// Whether the lobe is a Dirac delta.
    pub fn is_delta(&self) -> bool {
        matches!(self, Bsdf::Mirror | Bsdf::Dielectric { .. })
    }

    /// `f(wo, wi)` per steradian; zero for delta lobes and for directions on
    /// opposite sides of a reflecting surface.
    pub fn eval(&self, wo: &Vector3<f64>, wi: &Vector3<f64>) -> f64 {
        match *self {
            Bsdf::Diffuse if same_side(wo, wi) => FRAC_1_PI,
            Bsdf::Phong { shininess: p } if same_side(wo, wi) => {
                let c = wi.dot(&mirror(wo));
                if c > 0.0 {
                    (p + 2.0) / TAU * c.powf(p)
                } else {
                    0.0
                }
            }
            Bsdf::BlinnPhong { shininess: p } if same_side(wo, wi) => {
                let h = (wo + wi).normalize();
                // wi·h = wo·h > 0: h bisects two directions on one side.
                (p + 1.0) / (4.0 * TAU) * h.z.abs().powf(p) / (wi.dot(&h) * wi.z.abs().max(wo.z.abs()))
            }
            _ => 0.0,
        }
    }

    /// The density of [`sample`](Self::sample) at `wi` per steradian, over
    /// the whole sphere (a glossy lobe may sample directions below the
    /// surface, where `f` is zero: its density integrates to one over the
    /// sphere, not over the hemisphere); zero for delta lobes.
    pub fn pdf(&self, wo: &Vector3<f64>, wi: &Vector3<f64>) -> f64 {
        match *self {
            Bsdf::Diffuse if same_side(wo, wi) => cosine_hemisphere_pdf(wi.z.abs()),
            Bsdf::Phong { shininess: p } => power_cosine_pdf(wi.dot(&mirror(wo)), p),
            Bsdf::BlinnPhong { shininess: p } => {
                let sum = wo + wi;
                let len = sum.norm();
                if len == 0.0 {
                    return 0.0;
                }
                let h = sum / len;
                // Sampled h and −h give the same wi: the half vector is read
                // up to sign, in the hemisphere it was drawn from.
                let d = power_cosine_pdf(h.z.abs(), p);
                if d == 0.0 {
                    0.0
                } else {
                    d / (4.0 * wo.dot(&h).abs())
                }
            }
            _ => 0.0,
        }
    }

    /// Draws `wi` for `wo` from two uniform numbers `u` (the direction) and
    /// one `uc` (the choice between reflection and refraction of a
    /// dielectric). `None` where no direction can be drawn: `wo` in the
    /// tangent plane, for every lobe but Phong (whose lobe around the
    /// tangent mirror direction still reaches above the surface).
    pub fn sample(&self, wo: &Vector3<f64>, u: [f64; 2], uc: f64) -> Option<BsdfSample> {
        let glossy =
            |wi: Vector3<f64>| Some(BsdfSample { wi, f: self.eval(wo, &wi), pdf: self.pdf(wo, &wi), delta: false });
        match *self {
            Bsdf::Diffuse => {
                if wo.z == 0.0 {
                    return None;
                }
                let mut wi = sample_cosine_hemisphere(u);
                wi.z = wi.z.copysign(wo.z);
                glossy(wi)
            }
            Bsdf::Phong { shininess: p } => glossy(Basis::from_z(mirror(wo)).to_world(&sample_power_cosine(u, p))),
            Bsdf::BlinnPhong { shininess: p } => {
                if wo.z == 0.0 {
                    return None;
                }
                let mut h = sample_power_cosine(u, p);
                h.z = h.z.copysign(wo.z);
                let wi = 2.0 * wo.dot(&h) * h - wo;
                glossy(wi.normalize())
            }
            // A tangent wo has no mirror direction off the surface.
            Bsdf::Mirror | Bsdf::Dielectric { .. } if wo.z == 0.0 => None,
            Bsdf::Mirror => {
                let wi = mirror(wo);
                Some(BsdfSample { wi, f: 1.0 / wi.z.abs(), pdf: 1.0, delta: true })
            }
            Bsdf::Dielectric { eta } => {
                let r = fresnel_dielectric(wo.z, eta);
                let t = 1.0 - r;
                if uc < r || t <= 0.0 {
                    let wi = mirror(wo);
                    return Some(BsdfSample { wi, f: r / wi.z.abs(), pdf: r, delta: true });
                }
                let (wi, eta_ratio) = refract(wo, eta)?;
                // Radiance is compressed into the narrower cone of the
                // denser medium: it scales by (η_i/η_t)² across the
                // boundary (pbrt-v4, "Radiance" transport).
                Some(BsdfSample { wi, f: t / wi.z.abs() / (eta_ratio * eta_ratio), pdf: t, delta: true })
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::chi_square::{integrate_sphere, test_directions};
    use crate::sampling::Sampler;
    use crate::warp::sample_uniform_sphere;

    const ALPHA: f64 = 1e-3;

    /// Incident directions at these angles from the normal (degrees), in an
    /// azimuth away from the grid's seams, above and below the surface.
    fn incident() -> Vec<Vector3<f64>> {
        let mut out = Vec::new();
        for deg in [0.0f64, 30.0, 60.0, 80.0] {
            let (t, phi) = (deg.to_radians(), 0.7f64);
            let w = Vector3::new(t.sin() * phi.cos(), t.sin() * phi.sin(), t.cos());
            out.push(w);
            out.push(Vector3::new(w.x, w.y, -w.z));
        }
        out
    }

    fn glossy() -> Vec<Bsdf> {
        let mut out = vec![Bsdf::Diffuse];
        for p in [0.0, 1.0, 10.0, 60.0] {
            out.push(Bsdf::Phong { shininess: p });
            out.push(Bsdf::BlinnPhong { shininess: p });
        }
        out
    }

    /// Each of the cases is a test at the level that makes the whole family's
    /// false-alarm rate [`ALPHA`] (Šidák's correction, as Mitsuba 3's
    /// chi-square tests apply it).
    #[test]
    fn glossy_samples_follow_their_pdf_and_the_pdf_integrates_to_one() {
        let cases = (glossy().len() * incident().len()) as f64;
        let alpha = 1.0 - (1.0 - ALPHA).powf(1.0 / cases);
        for bsdf in glossy() {
            for wo in incident() {
                // Blinn-Phong's density has an integrable 1/|wo·h| peak at
                // wi = −wo (h ⊥ wo), which grazing lobes reach: the grid is
                // centred on it.
                let pole = if matches!(bsdf, Bsdf::BlinnPhong { .. }) { -wo } else { Vector3::z() };
                let o = test_directions(
                    &pole,
                    |wi| bsdf.pdf(&wo, wi),
                    |u| bsdf.sample(&wo, u, 0.5).map(|s| s.wi),
                    50_000,
                    7,
                );
                assert!((o.mass - 1.0).abs() < 1e-4, "{bsdf:?} at {wo:?}: ∫pdf = {}", o.mass);
                assert_eq!(o.failed, 0);
                assert!(o.p > alpha, "{bsdf:?} at {wo:?}: p = {}", o.p);
            }
        }
    }

    #[test]
    fn a_sample_reports_the_lobes_own_value_and_density() {
        for bsdf in glossy() {
            for wo in incident() {
                for i in 0..200 {
                    let s = Sampler::new(9, i, 0);
                    let x = bsdf.sample(&wo, s.uniform2(0), s.uniform(2)).expect("wo is off the tangent plane");
                    assert!((x.wi.norm() - 1.0).abs() < 1e-13);
                    assert!(!x.delta);
                    assert_eq!(x.f, bsdf.eval(&wo, &x.wi));
                    assert_eq!(x.pdf, bsdf.pdf(&wo, &x.wi));
                    assert!(x.pdf > 0.0, "{bsdf:?}: a sample where the density is zero");
                }
            }
        }
    }

    #[test]
    fn glossy_lobes_are_reciprocal() {
        for bsdf in glossy() {
            for i in 0..2000 {
                let s = Sampler::new(10, i, 0);
                let (a, b) = (sample_uniform_sphere(s.uniform2(0)), sample_uniform_sphere(s.uniform2(2)));
                let (f, g) = (bsdf.eval(&a, &b), bsdf.eval(&b, &a));
                assert!((f - g).abs() <= 1e-12 * f.abs().max(g.abs()), "{bsdf:?}: {f} ≠ {g}");
            }
        }
    }

    #[test]
    fn glossy_lobes_conserve_energy() {
        // The albedo ∫ f |cos θi| dωi by quadrature of `eval` (not by the
        // sampler): at most 1, and exactly 1 for the diffuse lobe and for
        // Phong at normal incidence (∫ (p+2)/(2π) cos^{p+1} θ dω = 1).
        for bsdf in glossy() {
            for wo in incident() {
                let albedo = integrate_sphere(|wi| bsdf.eval(&wo, wi) * wi.z.abs());
                assert!(albedo <= 1.0 + 1e-4, "{bsdf:?} at {wo:?}: albedo {albedo}");
                let exact = matches!(bsdf, Bsdf::Diffuse) || (matches!(bsdf, Bsdf::Phong { .. }) && wo.z.abs() == 1.0);
                if exact {
                    assert!((albedo - 1.0).abs() < 1e-4, "{bsdf:?} at {wo:?}: albedo {albedo}");
                }
            }
        }
    }

    #[test]
    fn sampled_weights_estimate_the_albedo() {
        // The mean of f|cos|/pdf over samples against the quadrature of
        // eval: sampling and evaluation agree in the integrator's own terms.
        for bsdf in glossy() {
            let wo = incident()[2];
            let n = 20_000;
            let weights: Vec<f64> = (0..n)
                .map(|i| {
                    let s = Sampler::new(12, i, 0);
                    bsdf.sample(&wo, s.uniform2(0), 0.5).map_or(0.0, |x| x.weight())
                })
                .collect();
            let mean = weights.iter().sum::<f64>() / n as f64;
            let sd = (weights.iter().map(|w| (w - mean).powi(2)).sum::<f64>() / (n * (n - 1)) as f64).sqrt();
            let albedo = integrate_sphere(|wi| bsdf.eval(&wo, wi) * wi.z.abs());
            assert!((mean - albedo).abs() < 5.0 * sd + 1e-4, "{bsdf:?}: {mean} ± {sd} against {albedo}");
        }
    }

    #[test]
    fn every_lobe_gives_finite_non_negative_weights_in_every_direction() {
        let mut lobes = glossy();
        lobes.extend([
            Bsdf::Mirror,
            Bsdf::Dielectric { eta: 1.5 },
            Bsdf::Dielectric { eta: 1.0 / 1.5 },
            Bsdf::Dielectric { eta: 1.0 },
        ]);
        let tangent = [Vector3::x(), Vector3::new(0.6, -0.8, 0.0), Vector3::new(1.0, 0.0, 1e-300).normalize()];
        for bsdf in lobes {
            let directions = (0..2000).map(|i| sample_uniform_sphere(Sampler::new(14, i, 0).uniform2(0)));
            for wo in directions.chain(tangent) {
                for (i, u) in [[0.0, 0.0], [0.999_999, 0.5], [0.5, 0.999_999], [0.3, 0.6]].into_iter().enumerate() {
                    let Some(s) = bsdf.sample(&wo, u, i as f64 / 4.0) else {
                        assert!(wo.z == 0.0 && !matches!(bsdf, Bsdf::Phong { .. }), "{bsdf:?} failed at {wo:?}");
                        continue;
                    };
                    let w = s.weight();
                    assert!(w.is_finite() && w >= 0.0, "{bsdf:?} at {wo:?}: weight {w}");
                    assert!(
                        s.f.is_finite() && s.f >= 0.0 && s.pdf.is_finite() && s.pdf >= 0.0,
                        "{bsdf:?} at {wo:?}: {s:?}"
                    );
                    assert!((s.wi.norm() - 1.0).abs() < 1e-13, "{bsdf:?} at {wo:?}: {s:?}");
                }
            }
        }
    }

    /// The Fresnel reflectance from the angles (Fresnel's sine and tangent
    /// laws), independent of the cosine form in the code.
    fn fresnel_from_angles(theta_i: f64, n_i: f64, n_t: f64) -> f64 {
        let theta_t = (n_i / n_t * theta_i.sin()).asin();
        if theta_i == 0.0 {
            return ((n_i - n_t) / (n_i + n_t)).powi(2);
        }
        let rs = ((theta_i - theta_t).sin() / (theta_i + theta_t).sin()).powi(2);
        let rp = ((theta_i - theta_t).tan() / (theta_i + theta_t).tan()).powi(2);
        (rs + rp) / 2.0
    }

    #[test]
    fn fresnel_matches_the_sine_and_tangent_laws() {
        for n in [1.1, 1.333, 1.5, 2.4] {
            assert!((fresnel_dielectric(1.0, n) - ((n - 1.0) / (n + 1.0)).powi(2)).abs() < 1e-15);
            assert!((fresnel_dielectric(-1.0, n) - ((n - 1.0) / (n + 1.0)).powi(2)).abs() < 1e-15);
            for deg in [10.0f64, 30.0, 45.0, 60.0, 75.0, 89.0] {
                let t = deg.to_radians();
                // From outside into glass, and from inside towards the outside below the critical angle.
                assert!(
                    (fresnel_dielectric(t.cos(), n) - fresnel_from_angles(t, 1.0, n)).abs() < 1e-12,
                    "n = {n}, {deg}°"
                );
                let critical = (1.0 / n).asin();
                if t < critical - 1e-3 {
                    assert!((fresnel_dielectric(-t.cos(), n) - fresnel_from_angles(t, n, 1.0)).abs() < 1e-12);
                }
            }
            assert_eq!(fresnel_dielectric(0.0, n), 1.0, "grazing incidence reflects everything");
        }
    }

    #[test]
    fn light_inside_glass_beyond_the_critical_angle_is_totally_reflected() {
        let eta = 1.5;
        let critical = (1.0f64 / eta).asin();
        let glass = Bsdf::Dielectric { eta };
        for deg in [42.0f64, 50.0, 70.0, 89.0] {
            let t = deg.to_radians();
            assert!(t > critical);
            // wo inside the glass: below the surface, z < 0.
            let wo = Vector3::new(t.sin(), 0.0, -t.cos());
            assert_eq!(fresnel_dielectric(wo.z, eta), 1.0);
            assert!(refract(&wo, eta).is_none());
            for uc in [0.0, 0.5, 0.999_999] {
                let s = glass.sample(&wo, [0.5, 0.5], uc).expect("reflection is always possible");
                assert_eq!(s.wi, Vector3::new(-wo.x, -wo.y, wo.z));
                assert!((s.weight() - 1.0).abs() < 1e-15);
            }
        }
        // Just inside the critical angle, light still gets out.
        let t = critical - 1e-3;
        assert!(fresnel_dielectric(-t.cos(), eta) < 1.0);
    }

    #[test]
    fn refraction_obeys_snells_law_and_the_fresnel_split() {
        for eta in [1.333, 1.5, 1.0 / 1.5] {
            let glass = Bsdf::Dielectric { eta };
            for wo in incident() {
                let r = fresnel_dielectric(wo.z, eta);
                let n = 20_000u64;
                let mut reflected = 0u64;
                for i in 0..n {
                    let s = glass
                        .sample(&wo, [0.5, 0.5], Sampler::new(13, i, 0).uniform(0))
                        .expect("wo is off the tangent plane");
                    assert!(s.delta && (s.wi.norm() - 1.0).abs() < 1e-14);
                    if s.wi.z * wo.z > 0.0 {
                        reflected += 1;
                        assert_eq!(s.wi, Vector3::new(-wo.x, -wo.y, wo.z));
                        assert!((s.weight() - 1.0).abs() < 1e-14);
                    } else {
                        // Snell: η_i sin θi = η_t sin θt, in the plane of incidence, on the far side.
                        let (n_i, n_t) = if wo.z > 0.0 { (1.0, eta) } else { (eta, 1.0) };
                        let (sin_i, sin_t) = (wo.xy().norm(), s.wi.xy().norm());
                        assert!((n_i * sin_i - n_t * sin_t).abs() < 1e-14, "η = {eta}, wo = {wo:?}");
                        assert!(sin_i == 0.0 || (wo.xy() / sin_i + s.wi.xy() / sin_t).norm() < 1e-12);
                        // The weight: (1 − R)(η_i/η_t)² / P(transmit) = (η_i/η_t)².
                        assert!((s.weight() - (n_i / n_t).powi(2)).abs() < 1e-13);
                    }
                }
                // The reflected fraction is R within 5 binomial standard deviations.
                let sd = (r * (1.0 - r) / n as f64).sqrt();
                let frac = reflected as f64 / n as f64;
                assert!((frac - r).abs() <= 5.0 * sd + 1e-12, "η = {eta}, wo = {wo:?}: {frac} against R = {r}");
            }
        }
    }

    #[test]
    fn the_mirror_reflects_about_the_normal_with_unit_weight() {
        for wo in incident() {
            let s = Bsdf::Mirror.sample(&wo, [0.2, 0.9], 0.3).expect("a mirror always reflects");
            assert!(s.delta);
            assert!((s.wi - (2.0 * wo.z * Vector3::z() - wo)).norm() < 1e-15, "2(n·v)n − v (model §5.4)");
            assert_eq!(s.weight(), 1.0);
            assert_eq!(Bsdf::Mirror.eval(&wo, &s.wi), 0.0);
            assert_eq!(Bsdf::Mirror.pdf(&wo, &s.wi), 0.0);
        }
    }

    #[test]
    fn refraction_agrees_with_the_whitted_formula() {
        // docs/model.md §5.5: t = −η_r v + (η_r cos θi − √(1 − sin²θt)) n,
        // η_r = η_before/η_after, for v above the surface.
        for wo in incident().into_iter().filter(|w| w.z > 0.0) {
            let eta = 1.5;
            let eta_r = 1.0 / eta;
            let sin2_t = eta_r * eta_r * (1.0 - wo.z * wo.z);
            let t = -eta_r * wo + (eta_r * wo.z - (1.0 - sin2_t).sqrt()) * Vector3::z();
            let (wi, ratio) = refract(&wo, eta).expect("no total reflection from outside");
            assert!((wi - t).norm() < 1e-15);
            assert_eq!(ratio, eta);
        }
    }
}
