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
const GOLDEN: u64 = 0x9e37_79b9_7f4a_7c15;

/// 2^-53: the spacing of the `f64` values [`Sampler::uniform`] returns.
const UNIT: f64 = 1.0 / (1u64 << 53) as f64;

/// SplitMix64's output function (Stafford's "Mix13"): a bijection of `u64`
/// whose every output bit depends on every input bit.
#[inline]
fn mix(mut z: u64) -> u64 {
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

/// The random numbers of one sample of one pixel: dimension `d` is the
/// `d`-th output of a SplitMix64 stream whose state is a hash of
/// (seed, pixel, sample). Cheap to copy and to build (three hashes), so a
/// render makes one per pixel sample.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Sampler {
    key: u64,
}

impl Sampler {
    /// The sampler of sample `sample` of pixel `pixel` (any numbering, such
    /// as `row × width + column`) under the scene's `seed`.
    pub fn new(seed: u64, pixel: u64, sample: u64) -> Self {
        Self { key: absorb(absorb(absorb(0, seed), pixel), sample) }
    }

    /// 64 random bits for dimension `d`.
    #[inline]
    pub fn bits(&self, d: u32) -> u64 {
        mix(self.key.wrapping_add(GOLDEN.wrapping_mul(u64::from(d) + 1)))
    }

    /// A uniform number in `[0, 1)` for dimension `d`, a multiple of 2^-53
    /// (every such value can come out).
    #[inline]
    pub fn uniform(&self, d: u32) -> f64 {
        (self.bits(d) >> 11) as f64 * UNIT
    }

    /// Two uniform numbers, dimensions `d` and `d + 1`.
    #[inline]
    pub fn uniform2(&self, d: u32) -> [f64; 2] {
        [self.uniform(d), self.uniform(d.wrapping_add(1))]
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

    #[test]
    fn neighbouring_pixels_samples_dimensions_and_seeds_are_uncorrelated() {
        assert_pairs_uniform("pixels", |i| (Sampler::new(9, i, 0).uniform(0), Sampler::new(9, i + 1, 0).uniform(0)));
        assert_pairs_uniform("samples", |i| (Sampler::new(9, 17, i).uniform(0), Sampler::new(9, 17, i + 1).uniform(0)));
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
