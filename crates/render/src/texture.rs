//! Procedural solid textures and bump mapping (docs/model.md §5.9): a
//! colour of a material as a function of the point in the textured block's
//! own frame, and a shading normal perturbed by the gradient of noise.
//!
//! The noise is Ken Perlin's improved gradient noise (SIGGRAPH 2002) with
//! his fixed permutation, evaluated together with its analytic gradient.
//! Everything here is plain arithmetic on the point: deterministic, with no
//! state and no allocation.

use quadric::nalgebra::{Matrix3, Point3, Vector3};

/// Colours are linear RGB.
pub type Rgb = Vector3<f64>;

/// A colour as a function of the point (in the block's frame).
#[derive(Clone, Debug, PartialEq)]
pub enum Texture {
    /// The same colour everywhere.
    Constant(Rgb),
    /// Unit cubes of side `scale` in alternating colours; the cell holding
    /// the origin's `+x +y +z` corner has `colors[0]`.
    Checker {
        /// Side of a cell.
        scale: f64,
        /// The two colours.
        colors: [Rgb; 2],
    },
    /// Fractal sum of `octaves` noise octaves, mapped from `[-1, 1]` onto
    /// the blend of the colours.
    Noise {
        /// Size of a noise feature (one lattice cell of the first octave).
        scale: f64,
        /// Octaves summed (each twice the frequency and half the weight).
        octaves: u32,
        /// The colours at -1 and at 1.
        colors: [Rgb; 2],
    },
    /// Stripes across x, one period per `scale`, warped by `turbulence`.
    Marble {
        /// The stripe period.
        scale: f64,
        /// Octaves of the turbulence.
        octaves: u32,
        /// How far the turbulence shifts a stripe, in periods.
        turbulence: f64,
        /// The colours of the two stripe kinds.
        colors: [Rgb; 2],
    },
    /// Rings around the y axis, one per `scale`, warped by `turbulence`.
    Wood {
        /// The ring spacing.
        scale: f64,
        /// Octaves of the turbulence.
        octaves: u32,
        /// How far the turbulence shifts a ring, in ring spacings.
        turbulence: f64,
        /// The colours at the start and the end of a ring.
        colors: [Rgb; 2],
    },
}

/// A bump map: the shading normal tilted by the gradient of fractal noise.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bump {
    /// Size of a bump (one lattice cell of the first octave).
    pub scale: f64,
    /// Slope of the bumps: the tangential gradient (per `scale`) is
    /// multiplied by it before it is subtracted from the normal.
    pub strength: f64,
    /// Octaves summed.
    pub octaves: u32,
}

/// Cell coordinates are floored after this shift (a millionth of a cell),
/// so that a face lying on a cell boundary (a floor at `y = 0`) shows one
/// cell, not the sign of its rounding error.
const CELL_BIAS: f64 = 1e-6;

impl Texture {
    /// The colour at `p` (the block's frame).
    pub fn at(&self, p: &Point3<f64>) -> Rgb {
        match self {
            Texture::Constant(c) => *c,
            Texture::Checker { colors, .. }
            | Texture::Noise { colors, .. }
            | Texture::Marble { colors, .. }
            | Texture::Wood { colors, .. } => {
                let t = self.pattern(p);
                colors[0] * (1.0 - t) + colors[1] * t
            }
        }
    }

    /// The blend factor in `[0, 1]` between the two colours at `p` (0 for
    /// a constant, and where a point far beyond its scale leaves no pattern).
    pub fn pattern(&self, p: &Point3<f64>) -> f64 {
        let t = self.raw_pattern(p);
        if t.is_nan() {
            0.0
        } else {
            t
        }
    }

    fn raw_pattern(&self, p: &Point3<f64>) -> f64 {
        match *self {
            Texture::Constant(_) => 0.0,
            Texture::Checker { scale, .. } => {
                let q = p.coords / scale;
                let sum: f64 = q.iter().map(|c| (c + CELL_BIAS).floor()).sum();
                // `sum` is a whole number; its parity picks the colour.
                if sum.rem_euclid(2.0) == 0.0 {
                    0.0
                } else {
                    1.0
                }
            }
            Texture::Noise { scale, octaves, .. } => {
                (0.5 * (1.0 + fractal(&(p.coords / scale), octaves).0)).clamp(0.0, 1.0)
            }
            Texture::Marble { scale, octaves, turbulence, .. } => {
                let q = p.coords / scale;
                let phase = q.x + turbulence * turbulent(&q, octaves);
                0.5 * (1.0 + (std::f64::consts::TAU * phase).sin())
            }
            Texture::Wood { scale, octaves, turbulence, .. } => {
                let q = p.coords / scale;
                let r = q.x.hypot(q.z) + turbulence * turbulent(&q, octaves);
                let t = r - r.floor();
                // `r - floor(r)` rounds to 1 for tiny negative `r`.
                if t < 1.0 {
                    t
                } else {
                    0.0
                }
            }
        }
    }
}

impl Bump {
    /// The world unit normal `n` tilted by the tangential part of the
    /// noise gradient at `p` (a point of the block's frame, which `to_frame`,
    /// the linear part of the world-to-frame map, maps world vectors into):
    /// the gradient of `x ↦ f(A x + c)` is `Aᵀ ∇f`. Returns `n` itself where
    /// the tilt would leave no normal.
    pub fn normal(&self, p: &Point3<f64>, n: &Vector3<f64>, to_frame: &Matrix3<f64>) -> Vector3<f64> {
        let g = to_frame.tr_mul(&fractal(&(p.coords / self.scale), self.octaves).1);
        let tangential = g - n * g.dot(n);
        let m = n - tangential * self.strength;
        let len = m.norm();
        if len > 0.0 && len.is_finite() {
            m / len
        } else {
            *n
        }
    }
}

/// Perlin's permutation of 0..=255 (Perlin 2002, the reference code).
const PERM: [u8; 256] = [
    151, 160, 137, 91, 90, 15, 131, 13, 201, 95, 96, 53, 194, 233, 7, 225, 140, 36, 103, 30, 69, 142, 8, 99, 37, 240,
    21, 10, 23, 190, 6, 148, 247, 120, 234, 75, 0, 26, 197, 62, 94, 252, 219, 203, 117, 35, 11, 32, 57, 177, 33, 88,
    237, 149, 56, 87, 174, 20, 125, 136, 171, 168, 68, 175, 74, 165, 71, 134, 139, 48, 27, 166, 77, 146, 158, 231, 83,
    111, 229, 122, 60, 211, 133, 230, 220, 105, 92, 41, 55, 46, 245, 40, 244, 102, 143, 54, 65, 25, 63, 161, 1, 216,
    80, 73, 209, 76, 132, 187, 208, 89, 18, 169, 200, 196, 135, 130, 116, 188, 159, 86, 164, 100, 109, 198, 173, 186,
    3, 64, 52, 217, 226, 250, 124, 123, 5, 202, 38, 147, 118, 126, 255, 82, 85, 212, 207, 206, 59, 227, 47, 16, 58, 17,
    182, 189, 28, 42, 223, 183, 170, 213, 119, 248, 152, 2, 44, 154, 163, 70, 221, 153, 101, 155, 167, 43, 172, 9, 129,
    22, 39, 253, 19, 98, 108, 110, 79, 113, 224, 232, 178, 185, 112, 104, 218, 246, 97, 228, 251, 34, 242, 193, 238,
    210, 144, 12, 191, 179, 162, 241, 81, 51, 145, 235, 249, 14, 239, 107, 49, 192, 214, 31, 181, 199, 106, 157, 184,
    84, 204, 176, 115, 121, 50, 45, 127, 4, 150, 254, 138, 236, 205, 93, 222, 114, 67, 29, 24, 72, 243, 141, 128, 195,
    78, 66, 215, 61, 156, 180,
];

/// The gradient Perlin's `grad(hash, ...)` takes the dot product with:
/// the twelve edge midpoints of the cube, four of them twice.
const GRADIENTS: [[f64; 3]; 16] = [
    [1.0, 1.0, 0.0],
    [-1.0, 1.0, 0.0],
    [1.0, -1.0, 0.0],
    [-1.0, -1.0, 0.0],
    [1.0, 0.0, 1.0],
    [-1.0, 0.0, 1.0],
    [1.0, 0.0, -1.0],
    [-1.0, 0.0, -1.0],
    [0.0, 1.0, 1.0],
    [0.0, -1.0, 1.0],
    [0.0, 1.0, -1.0],
    [0.0, -1.0, -1.0],
    [1.0, 1.0, 0.0],
    [0.0, -1.0, 1.0],
    [-1.0, 1.0, 0.0],
    [0.0, -1.0, -1.0],
];

fn perm(i: usize) -> usize {
    usize::from(PERM[i & 255])
}

/// Perlin's quintic fade `6t⁵ − 15t⁴ + 10t³` and its derivative.
fn fade(t: f64) -> (f64, f64) {
    (t * t * t * (t * (t * 6.0 - 15.0) + 10.0), 30.0 * t * t * (t * (t - 2.0) + 1.0))
}

/// Improved noise at `p` and its gradient. Zero at every lattice point,
/// `C²` everywhere; the value is Perlin's trilinear blend of the corner
/// ramps, written out as a polynomial in the faded coordinates so that the
/// gradient follows by the product rule.
pub fn noise(p: &Vector3<f64>) -> (f64, Vector3<f64>) {
    // A point beyond `f64` (a tiny scale) has no lattice cell.
    if !p.iter().all(|c| c.is_finite()) {
        return (0.0, Vector3::zeros());
    }
    let cell = p.map(f64::floor);
    let f = p - cell;
    // The lattice repeats every 256 cells (Perlin's `& 255`); coordinates
    // beyond `i64` wrap as well, which only matters for absurd scales.
    let [x, y, z] = [0, 1, 2].map(|k| (cell[k] as i64).rem_euclid(256) as usize);
    let corner = |dx: usize, dy: usize, dz: usize| {
        let h = perm(perm(perm(x + dx) + y + dy) + z + dz) & 15;
        let g = Vector3::from(GRADIENTS[h]);
        let d = Vector3::new(f.x - dx as f64, f.y - dy as f64, f.z - dz as f64);
        (g.dot(&d), g)
    };
    let (va, ga) = corner(0, 0, 0);
    let (vb, gb) = corner(1, 0, 0);
    let (vc, gc) = corner(0, 1, 0);
    let (vd, gd) = corner(1, 1, 0);
    let (ve, ge) = corner(0, 0, 1);
    let (vf, gf) = corner(1, 0, 1);
    let (vg, gg) = corner(0, 1, 1);
    let (vh, gh) = corner(1, 1, 1);
    let ((u, du), (v, dv), (w, dw)) = (fade(f.x), fade(f.y), fade(f.z));
    let k1 = vb - va;
    let k2 = vc - va;
    let k3 = ve - va;
    let k4 = va - vb - vc + vd;
    let k5 = va - vc - ve + vg;
    let k6 = va - vb - ve + vf;
    let k7 = -va + vb + vc - vd + ve - vf - vg + vh;
    let value = va + k1 * u + k2 * v + k3 * w + k4 * u * v + k5 * v * w + k6 * w * u + k7 * u * v * w;
    let gradient = ga
        + (gb - ga) * u
        + (gc - ga) * v
        + (ge - ga) * w
        + (ga - gb - gc + gd) * (u * v)
        + (ga - gc - ge + gg) * (v * w)
        + (ga - gb - ge + gf) * (w * u)
        + (-ga + gb + gc - gd + ge - gf - gg + gh) * (u * v * w)
        + Vector3::new(
            du * (k1 + k4 * v + k6 * w + k7 * v * w),
            dv * (k2 + k5 * w + k4 * u + k7 * w * u),
            dw * (k3 + k6 * u + k5 * v + k7 * u * v),
        );
    (value, gradient)
}

/// The weighted mean of `octaves` octaves of noise (octave `i` at `2^i`
/// times the frequency, weight `2^-i`), so in the range of one octave, and
/// its gradient.
fn fractal(q: &Vector3<f64>, octaves: u32) -> (f64, Vector3<f64>) {
    let (mut value, mut gradient, mut total) = (0.0, Vector3::zeros(), 0.0);
    let mut frequency = 1.0;
    for _ in 0..octaves.max(1) {
        let (n, g) = noise(&(q * frequency));
        let weight = 1.0 / frequency;
        value += weight * n;
        // d/dq n(f q) = f ∇n, times the weight 1/f.
        gradient += g;
        total += weight;
        frequency *= 2.0;
    }
    (value / total, gradient / total)
}

/// Perlin's turbulence: the weighted mean of `|noise|` over the octaves,
/// in `[0, 1]`.
fn turbulent(q: &Vector3<f64>, octaves: u32) -> f64 {
    let (mut sum, mut total, mut frequency) = (0.0, 0.0, 1.0);
    for _ in 0..octaves.max(1) {
        sum += noise(&(q * frequency)).0.abs() / frequency;
        total += 1.0 / frequency;
        frequency *= 2.0;
    }
    sum / total
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A deterministic spread of points (a Weyl sequence), not lattice-aligned.
    fn points(n: usize, span: f64) -> impl Iterator<Item = Vector3<f64>> {
        let a = [0.754_877_666_246_692_7, 0.569_840_290_998_053_3, 0.438_149_347_667_833_3];
        (1..=n).map(move |i| Vector3::from(a.map(|a| ((i as f64 * a).fract() - 0.5) * 2.0 * span)))
    }

    #[test]
    fn noise_is_zero_at_lattice_points() {
        for x in -5..=5 {
            for y in -5..=5 {
                for z in [-300, -1, 0, 1, 7, 255, 256, 1000] {
                    let p = Vector3::new(f64::from(x), f64::from(y), f64::from(z));
                    assert_eq!(noise(&p).0, 0.0, "{p:?}");
                }
            }
        }
    }

    #[test]
    fn noise_is_bounded_and_not_flat() {
        let (mut lo, mut hi) = (0.0_f64, 0.0_f64);
        for p in points(200_000, 40.0) {
            let n = noise(&p).0;
            assert!((-1.0..=1.0).contains(&n), "{n} at {p:?}");
            lo = lo.min(n);
            hi = hi.max(n);
        }
        // It uses most of its range.
        assert!(lo < -0.6 && hi > 0.6, "{lo} {hi}");
    }

    /// Continuity: a step of `h` changes the value by at most the
    /// gradient bound times `h` (each corner ramp has slope at most √2 and
    /// the fade's slope is at most 15/8, so |∇n| is below 20).
    #[test]
    fn noise_is_continuous() {
        let h = 1e-7;
        for p in points(20_000, 20.0) {
            for d in [Vector3::x(), Vector3::y(), Vector3::z(), Vector3::new(1.0, -1.0, 1.0).normalize()] {
                let change = (noise(&(p + d * h)).0 - noise(&p).0).abs();
                assert!(change <= 20.0 * h, "{change} at {p:?}");
            }
        }
        // Across lattice planes too.
        for k in -3..=3 {
            let p = Vector3::new(f64::from(k), 0.37, -2.61);
            let change = (noise(&(p + Vector3::x() * h)).0 - noise(&(p - Vector3::x() * h)).0).abs();
            assert!(change <= 40.0 * h, "{change} at {p:?}");
        }
    }

    /// The analytic gradient against central differences of the value.
    #[test]
    fn noise_gradient_matches_central_differences() {
        let h = 1e-5;
        for p in points(5_000, 30.0) {
            let g = noise(&p).1;
            for k in 0..3 {
                let mut e = Vector3::zeros();
                e[k] = h;
                let numeric = (noise(&(p + e)).0 - noise(&(p - e)).0) / (2.0 * h);
                assert!((g[k] - numeric).abs() < 1e-6, "axis {k} at {p:?}: {} against {numeric}", g[k]);
            }
        }
        // The fractal sum's gradient likewise.
        for p in points(500, 5.0) {
            let g = fractal(&p, 4).1;
            for k in 0..3 {
                let mut e = Vector3::zeros();
                e[k] = h;
                let numeric = (fractal(&(p + e), 4).0 - fractal(&(p - e), 4).0) / (2.0 * h);
                assert!((g[k] - numeric).abs() < 1e-5, "axis {k} at {p:?}: {} against {numeric}", g[k]);
            }
        }
    }

    fn two() -> [Rgb; 2] {
        [Rgb::new(1.0, 0.0, 0.0), Rgb::new(0.0, 0.0, 1.0)]
    }

    #[test]
    fn checker_alternates_on_cells() {
        let t = Texture::Checker { scale: 0.5, colors: two() };
        for i in -4..4 {
            for j in -4..4 {
                for k in -4..4 {
                    // The centre of cell (i, j, k) of side 0.5.
                    let p = Point3::new(f64::from(i) + 0.5, f64::from(j) + 0.5, f64::from(k) + 0.5) * 0.5;
                    let want = if (i + j + k) % 2 == 0 { two()[0] } else { two()[1] };
                    assert_eq!(t.at(&p), want, "cell {i} {j} {k}");
                    // A step to the next cell along x flips the colour.
                    let q = p + Vector3::x() * 0.5;
                    assert_ne!(t.at(&q), want);
                }
            }
        }
        // A face on a cell boundary takes the cell above it, whatever its rounding.
        for y in [0.0, -1e-15, 1e-15] {
            assert_eq!(t.at(&Point3::new(0.25, y, 0.25)), two()[0]);
        }
    }

    #[test]
    fn patterns_stay_in_the_unit_interval_and_repeat() {
        let textures = [
            Texture::Noise { scale: 0.7, octaves: 5, colors: two() },
            Texture::Marble { scale: 2.0, octaves: 4, turbulence: 3.0, colors: two() },
            Texture::Wood { scale: 0.3, octaves: 3, turbulence: 0.8, colors: two() },
        ];
        for t in &textures {
            let (mut lo, mut hi) = (1.0_f64, 0.0_f64);
            for p in points(20_000, 10.0) {
                let p = Point3::from(p);
                let v = t.pattern(&p);
                assert!((0.0..=1.0).contains(&v), "{v} at {p:?} for {t:?}");
                assert_eq!(v.to_bits(), t.pattern(&p).to_bits(), "deterministic");
                // The colour is the blend of the two.
                let c = t.at(&p);
                assert!((c - (two()[0] * (1.0 - v) + two()[1] * v)).amax() < 1e-15);
                lo = lo.min(v);
                hi = hi.max(v);
            }
            assert!(lo < 0.25 && hi > 0.75, "{t:?}: {lo} {hi}");
        }
    }

    #[test]
    fn marble_and_wood_without_turbulence_are_their_plain_waves() {
        let marble = Texture::Marble { scale: 2.0, octaves: 1, turbulence: 0.0, colors: two() };
        let wood = Texture::Wood { scale: 0.5, octaves: 1, turbulence: 0.0, colors: two() };
        for p in points(1000, 3.0) {
            let p = Point3::from(p);
            let want = 0.5 * (1.0 + (std::f64::consts::PI * p.x).sin());
            assert!((marble.pattern(&p) - want).abs() < 1e-12);
            let r = 2.0 * p.x.hypot(p.z);
            assert!((wood.pattern(&p) - r.fract()).abs() < 1e-12);
        }
    }

    #[test]
    fn bump_tilts_the_normal_by_the_tangential_gradient() {
        let bump = Bump { scale: 0.5, strength: 0.3, octaves: 2 };
        let n = Vector3::y();
        for p in points(1000, 4.0) {
            let p = Point3::from(p);
            let m = bump.normal(&p, &n, &Matrix3::identity());
            assert!((m.norm() - 1.0).abs() < 1e-12);
            // Against a central-difference gradient of the same fractal noise.
            let h = 1e-6;
            let q = p.coords / 0.5;
            let gx = (fractal(&(q + Vector3::x() * h), 2).0 - fractal(&(q - Vector3::x() * h), 2).0) / (2.0 * h);
            let gz = (fractal(&(q + Vector3::z() * h), 2).0 - fractal(&(q - Vector3::z() * h), 2).0) / (2.0 * h);
            let want = Vector3::new(-0.3 * gx, 1.0, -0.3 * gz).normalize();
            assert!((m - want).amax() < 1e-6, "{m:?} against {want:?}");
        }
        // Points beyond any lattice (a scale of 1e-320) give no pattern, not NaN.
        for t in [
            Texture::Noise { scale: 1e-320, octaves: 3, colors: two() },
            Texture::Marble { scale: 1e-320, octaves: 3, turbulence: 1.0, colors: two() },
            Texture::Wood { scale: 1e-320, octaves: 3, turbulence: 1.0, colors: two() },
            Texture::Checker { scale: 1e-320, colors: two() },
        ] {
            assert!(t.at(&Point3::new(0.5, 0.25, 1.0)).iter().all(|c| c.is_finite()), "{t:?}");
        }
        let tiny = Bump { scale: 1e-320, strength: 1.0, octaves: 3 };
        assert_eq!(tiny.normal(&Point3::new(0.5, 0.25, 1.0), &n, &Matrix3::identity()), n);
        let flat = Bump { scale: 1.0, strength: 0.0, octaves: 1 };
        assert_eq!(flat.normal(&Point3::new(0.3, 0.2, 0.1), &n, &Matrix3::identity()), n);
        // In a frame turned a quarter about z (frame x = world y, frame y =
        // -world x), the world gradient is the frame's turned back.
        let to_frame = Matrix3::new(0.0, 1.0, 0.0, -1.0, 0.0, 0.0, 0.0, 0.0, 1.0);
        let world_n = Vector3::z();
        for p in points(200, 4.0) {
            let p = Point3::from(p);
            let g = fractal(&(p.coords / 0.5), 2).1;
            let world_g = Vector3::new(-g.y, g.x, g.z);
            let want = (world_n - Vector3::new(world_g.x, world_g.y, 0.0) * 0.3).normalize();
            assert!((bump.normal(&p, &world_n, &to_frame) - want).amax() < 1e-12);
        }
    }
}
