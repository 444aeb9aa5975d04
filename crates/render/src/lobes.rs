//! A material as the path integrator sees it at one surface point: a sum of
//! coloured lobes (docs/model.md §5.10.2). Each part of the material that is
//! not black contributes its [`Bsdf`] scaled by its colour: `diffuse`
//! (Lambertian), `specular` (normalised Phong or Blinn-Phong), `reflect`
//! (a mirror) and `transmit` (a smooth dielectric, where light can cross).
//!
//! Sampling picks one lobe with probability proportional to its colour's
//! largest channel, then draws a direction from it. A delta lobe's sample
//! is weighted by its own colour over the choice's probability; a glossy
//! sample by the whole non-delta sum `f` over the whole non-delta density,
//! so that [`Lobes::eval`] and [`Lobes::pdf`] (what next-event estimation
//! and multiple importance sampling read) describe the same distribution
//! the samples follow.

use quadric::nalgebra::Vector3;

use crate::bsdf::Bsdf;
use crate::shade::Rgb;
use crate::world::{Material, Model};

/// At most one lobe per part of a material.
const MAX_LOBES: usize = 4;

/// The lobes of one surface point, in the local frame of [`Bsdf`] (`z` the
/// shading normal on the side of `wo`).
#[derive(Clone, Copy, Debug)]
pub struct Lobes {
    lobes: [(Bsdf, Rgb); MAX_LOBES],
    /// The probability of picking each lobe.
    chance: [f64; MAX_LOBES],
    len: usize,
}

/// A direction drawn by [`Lobes::sample`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LobeSample {
    /// The direction, local frame.
    pub wi: Vector3<f64>,
    /// `f |cos θi| / pdf`, per colour channel.
    pub weight: Rgb,
    /// The density of the non-delta lobes at `wi` (per steradian), for
    /// multiple importance sampling; meaningless for a delta sample.
    pub pdf: f64,
    /// Whether a delta lobe (mirror, dielectric) was sampled.
    pub delta: bool,
    /// `(ηt/ηi)²` for a refraction (else 1): the radiance scaling the weight
    /// holds, which Russian roulette undoes so that a path inside glass is
    /// not stopped for it (pbrt-v4's `etaScale`).
    pub eta_scale: f64,
}

impl Lobes {
    /// The lobes of `material` (already evaluated at the point, textures
    /// and all). `eta`: the index of refraction on the far side of the
    /// surface over the near side's, when light can cross it (a
    /// transparent block's surface between two media); `None` keeps the
    /// `transmit` part out.
    pub fn of(material: &Material, eta: Option<f64>) -> Self {
        let mut lobes = Lobes { lobes: [(Bsdf::Diffuse, Rgb::zeros()); MAX_LOBES], chance: [0.0; MAX_LOBES], len: 0 };
        let glossy = match material.model {
            Model::Phong => Bsdf::Phong { shininess: material.shininess },
            Model::BlinnPhong => Bsdf::BlinnPhong { shininess: material.shininess },
        };
        lobes.push(Bsdf::Diffuse, material.diffuse);
        lobes.push(glossy, material.specular);
        lobes.push(Bsdf::Mirror, material.reflect);
        if let Some(eta) = eta {
            lobes.push(Bsdf::Dielectric { eta }, material.transmit);
        }
        let total: f64 = lobes.chance[..lobes.len].iter().sum();
        for c in &mut lobes.chance[..lobes.len] {
            *c /= total;
        }
        lobes
    }

    fn push(&mut self, bsdf: Bsdf, colour: Rgb) {
        let weight = colour.max();
        if weight > 0.0 && weight.is_finite() {
            self.lobes[self.len] = (bsdf, colour);
            self.chance[self.len] = weight;
            self.len += 1;
        }
    }

    /// Whether the surface scatters no light at all.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Whether some lobe is not a delta: only then can a light sample
    /// (next-event estimation) reach the surface.
    pub fn has_glossy(&self) -> bool {
        self.lobes[..self.len].iter().any(|(b, _)| !b.is_delta())
    }

    /// `f(wo, wi)` of the non-delta lobes, per colour channel.
    pub fn eval(&self, wo: &Vector3<f64>, wi: &Vector3<f64>) -> Rgb {
        let mut f = Rgb::zeros();
        for (bsdf, colour) in &self.lobes[..self.len] {
            if !bsdf.is_delta() {
                f += colour * bsdf.eval(wo, wi);
            }
        }
        f
    }

    /// The density with which [`Lobes::sample`] draws `wi` through its
    /// non-delta lobes.
    pub fn pdf(&self, wo: &Vector3<f64>, wi: &Vector3<f64>) -> f64 {
        let mut pdf = 0.0;
        for ((bsdf, _), chance) in self.lobes[..self.len].iter().zip(&self.chance) {
            if !bsdf.is_delta() {
                pdf += chance * bsdf.pdf(wo, wi);
            }
        }
        pdf
    }

    /// Draws `wi` for `wo`: `pick` chooses the lobe, `u` the direction and
    /// `uc` a dielectric's choice between reflection and refraction (all
    /// uniform in `[0, 1)`). `None` where nothing can be drawn.
    pub fn sample(&self, wo: &Vector3<f64>, pick: f64, u: [f64; 2], uc: f64) -> Option<LobeSample> {
        if self.len == 0 {
            return None;
        }
        let mut k = 0;
        let mut below = self.chance[0];
        while pick >= below && k + 1 < self.len {
            k += 1;
            below += self.chance[k];
        }
        let (bsdf, colour) = self.lobes[k];
        let s = bsdf.sample(wo, u, uc)?;
        if s.delta {
            let weight = colour * (s.weight() / self.chance[k]);
            let eta_scale = match bsdf {
                Bsdf::Dielectric { eta } if s.wi.z * wo.z < 0.0 => {
                    let ratio = if wo.z > 0.0 { eta } else { 1.0 / eta };
                    ratio * ratio
                }
                _ => 1.0,
            };
            return Some(LobeSample { wi: s.wi, weight, pdf: 0.0, delta: true, eta_scale });
        }
        let pdf = self.pdf(wo, &s.wi);
        if pdf <= 0.0 {
            return None;
        }
        let weight = self.eval(wo, &s.wi) * (s.wi.z.abs() / pdf);
        Some(LobeSample { wi: s.wi, weight, pdf, delta: false, eta_scale: 1.0 })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Sampler;

    fn material(diffuse: f64, specular: f64, reflect: f64, transmit: f64) -> Material {
        Material {
            name: String::new(),
            ambient: Rgb::zeros(),
            diffuse: Rgb::repeat(diffuse),
            specular: Rgb::repeat(specular),
            shininess: 20.0,
            model: Model::Phong,
            reflect: Rgb::repeat(reflect),
            transmit: Rgb::repeat(transmit),
            ior: 1.5,
            emission: Rgb::zeros(),
            textures: None,
        }
    }

    /// The mean weight of many samples is the directional albedo, computed
    /// by hand: for a diffuse + Phong + mirror mixture at normal incidence,
    /// `ρd + ρs + ρr` (the normalised Phong lobe centred on the normal lies
    /// wholly above the surface, and `(p+2)/(2π) ∫ cos^p θ cos θ dω = 1`).
    #[test]
    fn the_mean_sample_weight_is_the_albedo() {
        let lobes = Lobes::of(&material(0.3, 0.2, 0.25, 0.0), None);
        let wo = Vector3::z();
        let n = 400_000;
        let mut sum = 0.0;
        let mut sum2 = 0.0;
        for i in 0..n {
            let s = Sampler::new(5, i, 0);
            let w = lobes.sample(&wo, s.uniform(0), s.uniform2(1), s.uniform(3)).map_or(0.0, |s| s.weight.x);
            sum += w;
            sum2 += w * w;
        }
        let mean = sum / n as f64;
        let se = ((sum2 / n as f64 - mean * mean) / n as f64).sqrt();
        let want = 0.3 + 0.2 + 0.25;
        assert!((mean - want).abs() < 4.0 * se, "{mean} ± {se}, want {want}");
    }

    /// A dielectric alone conserves energy: reflection plus refraction
    /// weigh `1` per sample in expectation once the `η²` radiance scaling
    /// of refraction is undone (here: both sides' weights averaged with the
    /// Fresnel probabilities give `R + T/η²`).
    #[test]
    fn a_dielectric_splits_by_fresnel() {
        let lobes = Lobes::of(&material(0.0, 0.0, 0.0, 1.0), Some(1.5));
        assert!(!lobes.has_glossy());
        let wo = Vector3::new(0.6, 0.0, 0.8);
        let r = crate::bsdf::fresnel_dielectric(0.8, 1.5);
        let (mut refl, mut trans, n) = (0usize, 0usize, 100_000);
        for i in 0..n {
            let s = Sampler::new(9, i, 0);
            let x = lobes.sample(&wo, s.uniform(0), s.uniform2(1), s.uniform(3)).expect("a dielectric always scatters");
            assert!(x.delta);
            if x.wi.z > 0.0 {
                refl += 1;
                assert!((x.weight.x - 1.0).abs() < 1e-12);
                assert_eq!(x.eta_scale, 1.0);
            } else {
                trans += 1;
                assert!((x.weight.x - 1.0 / (1.5 * 1.5)).abs() < 1e-12);
                assert!((x.weight.x * x.eta_scale - 1.0).abs() < 1e-12, "the scaling undone");
            }
        }
        let p = refl as f64 / n as f64;
        let se = (r * (1.0 - r) / n as f64).sqrt();
        assert!((p - r).abs() < 5.0 * se, "reflected {p}, Fresnel {r}");
        assert_eq!(refl + trans, n as usize);
    }

    #[test]
    fn black_parts_make_no_lobes() {
        assert!(Lobes::of(&material(0.0, 0.0, 0.0, 1.0), None).is_empty());
        let only_mirror = Lobes::of(&material(0.0, 0.0, 1.0, 0.0), Some(1.5));
        assert!(!only_mirror.is_empty() && !only_mirror.has_glossy());
    }
}
