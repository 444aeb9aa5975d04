//! Counter-based random numbers for path tracing (docs/model.md §5.8.1).
//!
//! A [`Sampler`] is keyed by the scene's seed, the pixel and the sample
//! number; the value of each dimension is a pure function of the key and the
//! dimension, so an image does not depend on the number of threads, on how
//! the image is split, or on the order in which dimensions are read.
//!
//! ```
//! use render::sampling::Sampler;
//! let s = Sampler::new(7, 1234, 0);
//! let u = s.uniform(3);
//! assert!((0.0..1.0).contains(&u));
//! assert_eq!(u, Sampler::new(7, 1234, 0).uniform(3)); // a pure function
//! assert_ne!(u, Sampler::new(8, 1234, 0).uniform(3)); // the seed changes it
//! ```

/// The golden-ratio increment of SplitMix64 (Steele, Lea and Flood 2014).
pub(crate) const GOLDEN: u64 = 0x9e37_79b9_7f4a_7c15;

/// 2^-53: the spacing of the `f64` values [`Sampler::uniform`] returns.
const UNIT: f64 = 1.0 / (1u64 << 53) as f64;

/// SplitMix64's output function (Stafford's "Mix13"): a bijection of `u64`
/// whose every output bit depends on every input bit.
#[inline]
pub(crate) fn mix(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// Folds one more word into a running hash. Each word is hashed on its own
/// before it is combined, so neighbouring pixels or samples (keys that differ
/// in a low bit) start unrelated streams.
#[inline]
fn absorb(h: u64, word: u64) -> u64 {
    mix(h ^ mix(word.wrapping_add(GOLDEN)))
}

/// The direction numbers of the second dimension of Sobol's sequence (the
/// primitive polynomial `x + 1`, the rows of Pascal's triangle mod 2):
/// `v₀ = 2³¹`, `vⱼ = vⱼ₋₁ ⊕ (vⱼ₋₁ >> 1)`.
const SOBOL_1: [u32; 32] = {
    let mut v = [0u32; 32];
    v[0] = 1 << 31;
    let mut j = 1;
    while j < 32 {
        v[j] = v[j - 1] ^ (v[j - 1] >> 1);
        j += 1;
    }
    v
};

/// [`SOBOL_1`] folded by byte and bit-reversed: entry `[b][v]` is the XOR
/// of the direction numbers `8b … 8b + 7` selected by the bits of `v`,
/// reversed, so that a point (reversed, as [`Sampler::pair`] scrambles it)
/// is four lookups.
const SOBOL_1_BYTES: [[u32; 256]; 4] = {
    let mut t = [[0u32; 256]; 4];
    let mut b = 0;
    while b < 4 {
        let mut v = 0;
        while v < 256 {
            let (mut x, mut j) = (0u32, 0);
            while j < 8 {
                if (v >> j) & 1 == 1 {
                    x ^= SOBOL_1[8 * b + j];
                }
                j += 1;
            }
            t[b][v] = x.reverse_bits();
            v += 1;
        }
        b += 1;
    }
    t
};

/// The Laine–Karras permutation with Burley's constants (Burley 2020,
/// "Practical Hash-based Owen Scrambling"): bit `k` of the result depends on
/// bits `0..=k` of `x` only, each flipped as a hash of `seed` and the bits
/// below it.
#[inline]
fn laine_karras(mut x: u32, seed: u32) -> u32 {
    x = x.wrapping_add(seed);
    x ^= x.wrapping_mul(0x6c50_b47c);
    x ^= x.wrapping_mul(0xb82f_1e52);
    x ^= x.wrapping_mul(0xc7af_e638);
    x ^= x.wrapping_mul(0x8d22_f6e6);
    x
}

/// The random numbers of one sample of one pixel, an Owen-scrambled Sobol
/// sequence padded in pairs of dimensions (docs/model.md §5.8.1): the
/// dimensions `2g` and `2g + 1` of the pixel's samples `0, 1, 2, …` are the
/// first two dimensions of Sobol's sequence, the sample number shuffled
/// and each dimension scrambled by hashes of (seed, pixel, `g`), so that
/// every pair is stratified on its own (any `2^k` consecutive samples form a
/// (0, k, 2)-net) and different pairs are independent. Each value has 32
/// such bits and 21 more from a hash. Cheap to copy and to build (two
/// hashes), so a render makes one per pixel sample.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Sampler {
    /// A hash of (seed, pixel, the sample number's high half).
    key: u64,
    /// The sample number's low half (the index into the sequence),
    /// bit-reversed.
    reversed: u32,
}

impl Sampler {
    /// The sampler of sample `sample` of pixel `pixel` (any numbering, such
    /// as `row × width + column`) under the scene's `seed`.
    pub fn new(seed: u64, pixel: u64, sample: u64) -> Self {
        Self { key: absorb(absorb(absorb(0, seed), pixel), sample >> 32), reversed: (sample as u32).reverse_bits() }
    }

    /// The pair `g` (dimensions `2g`, `2g + 1`) as 32-bit binary
    /// fractions, with the hash the bits below them come from: with
    /// `S(x, s) = rev(LK(rev(x), s))`, the shuffled index
    /// `i' = S(i, s_i)`, and Sobol's first two dimensions of it, `rev(i')`
    /// and `sobol₁(i')`, each scrambled by `S`. The reversals that cancel
    /// are left out: `i` is kept reversed, `S(rev(i'), s₀) = rev(LK(i', s₀))`,
    /// and the table holds `rev(sobol₁)`.
    #[inline]
    fn pair(&self, g: u32) -> ([u32; 2], u64) {
        let group = mix(self.key ^ GOLDEN.wrapping_mul(u64::from(g) + 1));
        let salt = mix(group);
        let index = laine_karras(self.reversed, group as u32).reverse_bits();
        let [b0, b1, b2, b3] = index.to_le_bytes();
        let t = &SOBOL_1_BYTES;
        let second = t[0][b0 as usize] ^ t[1][b1 as usize] ^ t[2][b2 as usize] ^ t[3][b3 as usize];
        // rev(i') scrambled: rev(LK(rev(rev(i')), s₀)) = rev(LK(i', s₀)).
        let x = laine_karras(index, (group >> 32) as u32).reverse_bits();
        let y = laine_karras(second, salt as u32).reverse_bits();
        ([x, y], salt)
    }

    /// 64 random bits for dimension `d`: 32 of the scrambled Sobol point
    /// above 32 of a hash of (seed, pixel, the pair).
    #[inline]
    pub fn bits(&self, d: u32) -> u64 {
        let (xy, low) = self.pair(d / 2);
        let c = (d % 2) as usize;
        (u64::from(xy[c]) << 32) | ((low >> (32 * c)) & 0xffff_ffff)
    }

    /// A uniform number in `[0, 1)` for dimension `d`, a multiple of 2^-53
    /// (every such value can come out).
    #[inline]
    pub fn uniform(&self, d: u32) -> f64 {
        (self.bits(d) >> 11) as f64 * UNIT
    }

    /// Two uniform numbers, dimensions `d` and `d + 1`: for an even `d`, a
    /// stratified pair, computed together.
    #[inline]
    pub fn uniform2(&self, d: u32) -> [f64; 2] {
        if d % 2 == 1 {
            return [self.uniform(d), self.uniform(d.wrapping_add(1))];
        }
        let ([x, y], low) = self.pair(d / 2);
        let f = |hi: u32, lo: u64| (((u64::from(hi) << 32) | (lo & 0xffff_ffff)) >> 11) as f64 * UNIT;
        [f(x, low), f(y, low >> 32)]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::chi_square::{chi_square_p_value, Grid};

    /// The significance of each statistical test: a correct generator fails
    /// one with this probability, and the seeds are fixed, so a failure is
    /// reproducible.
    const ALPHA: f64 = 1e-4;

    #[test]
    fn the_same_key_gives_the_same_numbers_in_any_order() {
        let s = Sampler::new(3, 99, 5);
        let forward: Vec<f64> = (0..64).map(|d| s.uniform(d)).collect();
        let backward: Vec<f64> = (0..64).rev().map(|d| Sampler::new(3, 99, 5).uniform(d)).collect();
        assert!(forward.iter().eq(backward.iter().rev()));
        assert_eq!(s.uniform2(10), [forward[10], forward[11]]);
    }

    #[test]
    fn seeds_pixels_and_samples_each_change_every_dimension() {
        let base = Sampler::new(1, 2, 3);
        for other in [Sampler::new(2, 2, 3), Sampler::new(1, 3, 3), Sampler::new(1, 2, 4), Sampler::new(0, 0, 0)] {
            for d in 0..256 {
                assert_ne!(base.bits(d), other.bits(d), "dimension {d}");
            }
        }
    }

    #[test]
    fn values_lie_in_the_unit_interval_with_53_random_bits() {
        let n = 200_000;
        let mut ones = [0u32; 53];
        for i in 0..n {
            let u = Sampler::new(11, i, 0).uniform(0);
            assert!((0.0..1.0).contains(&u));
            let m = (u * (1u64 << 53) as f64) as u64;
            assert_eq!(m as f64 * UNIT, u, "a multiple of 2^-53");
            for (b, count) in ones.iter_mut().enumerate() {
                *count += ((m >> b) & 1) as u32;
            }
        }
        // Each bit is a fair coin: within 5 standard deviations of n/2.
        let sd = (n as f64 * 0.25).sqrt();
        for (b, &c) in ones.iter().enumerate() {
            assert!((f64::from(c) - n as f64 / 2.0).abs() < 5.0 * sd, "bit {b}: {c} ones in {n}");
        }
    }

    #[test]
    fn the_mean_and_variance_are_those_of_a_uniform_variable() {
        // Across pixels for one dimension, and across dimensions for one pixel.
        let n = 100_000u32;
        let across_pixels = (0..n).map(|p| Sampler::new(5, u64::from(p), 0).uniform(7));
        let across_dims = (0..n).map(|d| Sampler::new(5, 42, 1).uniform(d));
        for values in [across_pixels.collect::<Vec<_>>(), across_dims.collect()] {
            let mean = values.iter().sum::<f64>() / f64::from(n);
            let var = values.iter().map(|u| (u - mean).powi(2)).sum::<f64>() / f64::from(n - 1);
            // Standard errors of a U(0,1) sample's mean and variance: √(1/12n), √(1/180n).
            assert!((mean - 0.5).abs() < 5.0 * (1.0 / (12.0 * f64::from(n))).sqrt(), "mean {mean}");
            assert!((var - 1.0 / 12.0).abs() < 5.0 * (1.0 / (180.0 * f64::from(n))).sqrt(), "variance {var}");
        }
    }

    /// Pairs of values that a careless hash would correlate, binned on a
    /// 32 × 32 grid of the unit square and tested for uniformity.
    fn assert_pairs_uniform(name: &str, pair: impl Fn(u64) -> (f64, f64)) {
        let grid = Grid { a: (0.0, 1.0), b: (0.0, 1.0), na: 32, nb: 32 };
        let n = 100_000u64;
        let observed = grid.histogram((0..n).map(pair));
        let expected = vec![n as f64 / grid.cells() as f64; grid.cells()];
        let p = chi_square_p_value(&observed, &expected);
        assert!(p > ALPHA, "{name}: p = {p}");
    }

    /// Every pair of dimensions `(2g, 2g + 1)` of `2^k` consecutive samples
    /// of a pixel is a (0, k, 2)-net: exactly one point in each of the
    /// `2^k` boxes `[a/2^i, (a+1)/2^i) × [b/2^(k−i), (b+1)/2^(k−i))`, for
    /// every `i` (the definition of a net, checked box by box).
    #[test]
    fn each_pair_of_dimensions_is_a_net_at_every_power_of_two() {
        for k in [0u32, 1, 2, 4, 6, 8] {
            let n = 1u64 << k;
            for (pixel, start) in [(0u64, 0u64), (12_345, n), (77, 5 * n)] {
                for g in [0u32, 1, 2, 7, 30] {
                    let points: Vec<[f64; 2]> =
                        (start..start + n).map(|s| Sampler::new(3, pixel, s).uniform2(2 * g)).collect();
                    for i in 0..=k {
                        let (cols, rows) = (1u64 << i, 1u64 << (k - i));
                        let mut seen = vec![false; n as usize];
                        for [u, v] in &points {
                            let cell = (u * cols as f64) as u64 * rows + (v * rows as f64) as u64;
                            assert!(!seen[cell as usize], "k {k}, pixel {pixel}, pair {g}, boxes {cols}x{rows}");
                            seen[cell as usize] = true;
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn neighbouring_pixels_samples_dimensions_and_seeds_are_uncorrelated() {
        assert_pairs_uniform("pixels", |i| (Sampler::new(9, i, 0).uniform(0), Sampler::new(9, i + 1, 0).uniform(0)));
        assert_pairs_uniform("dimensions", |i| {
            let s = Sampler::new(9, i, 3);
            (s.uniform(4), s.uniform(5))
        });
        assert_pairs_uniform("seeds", |i| (Sampler::new(i, 8, 0).uniform(1), Sampler::new(i + 1, 8, 0).uniform(1)));
        assert_pairs_uniform("pixel and sample swapped", |i| {
            (Sampler::new(9, i, i + 1).uniform(0), Sampler::new(9, i + 1, i).uniform(0))
        });
    }
}
