//! Seeded random-number helpers shared by the simulator's models.
//!
//! Every random thing in the simulator takes its generator from the caller, so
//! that one `u64` seed reproduces a whole session bit for bit. The generator is
//! [`Xoshiro256PlusPlus`] (Blackman & Vigna, "Scrambled linear pseudorandom
//! number generators", ACM TOMS 47(4), 2021), seeded through
//! [`SeedableRng::seed_from_u64`] (which expands the seed with SplitMix64).
//!
//! Models that need independent streams (oscillator, IMU noise, motion jitter,
//! C/N0 offsets, …) should each get their own generator from
//! [`substream`]`(master_seed, stream_id)`, so that adding draws to one model
//! does not shift the random numbers of another.

use rand::Rng;
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
pub use rand_xoshiro::Xoshiro256PlusPlus;

/// The simulator's generator from a `u64` seed:
/// `Xoshiro256PlusPlus::seed_from_u64(seed)`.
pub fn seeded(seed: u64) -> Xoshiro256PlusPlus {
    Xoshiro256PlusPlus::seed_from_u64(seed)
}

/// One step of the SplitMix64 output function (Steele, Lea & Flood,
/// "Fast splittable pseudorandom number generators", OOPSLA 2014): a
/// bijective 64-bit mixer.
pub fn splitmix64(x: u64) -> u64 {
    let mut z = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Seed of the independent stream `stream_id` derived from `master_seed`:
/// `splitmix64(master_seed ⊕ splitmix64(stream_id))`. Distinct stream ids give
/// unrelated seeds (the mixer is a bijection, so two streams of one master
/// seed never share a seed).
pub fn substream_seed(master_seed: u64, stream_id: u64) -> u64 {
    splitmix64(master_seed ^ splitmix64(stream_id))
}

/// Generator of the independent stream `stream_id` of `master_seed`
/// ([`substream_seed`], then [`seeded`]).
pub fn substream(master_seed: u64, stream_id: u64) -> Xoshiro256PlusPlus {
    seeded(substream_seed(master_seed, stream_id))
}

/// One standard normal deviate N(0, 1) (`rand_distr::StandardNormal`, a
/// ziggurat sampler).
#[inline]
pub fn standard_normal<R: Rng + ?Sized>(rng: &mut R) -> f64 {
    StandardNormal.sample(rng)
}

/// A normal deviate N(0, σ²) with σ = `sigma` (σ = 0 returns 0 without
/// consuming a random number).
#[inline]
pub fn normal<R: Rng + ?Sized>(rng: &mut R, sigma: f64) -> f64 {
    if sigma == 0.0 { 0.0 } else { sigma * standard_normal(rng) }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rng_same_seed_same_bits_and_streams_differ() {
        let a: Vec<f64> = {
            let mut r = substream(42, 1);
            (0..8).map(|_| standard_normal(&mut r)).collect()
        };
        let b: Vec<f64> = {
            let mut r = substream(42, 1);
            (0..8).map(|_| standard_normal(&mut r)).collect()
        };
        let c: Vec<f64> = {
            let mut r = substream(42, 2);
            (0..8).map(|_| standard_normal(&mut r)).collect()
        };
        assert_eq!(
            a.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
            b.iter().map(|x| x.to_bits()).collect::<Vec<_>>()
        );
        assert_ne!(a, c);
        assert_ne!(substream_seed(1, 2), substream_seed(2, 1));
    }
}
