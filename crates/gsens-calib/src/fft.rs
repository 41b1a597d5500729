//! Forward FFTs of the lengths the estimate needs, planned once per process.
//!
//! A plan of the long transforms here (2¹⁹ points for an hour at 40 Hz)
//! costs as much as several transforms (its twiddle factors, a sine and a
//! cosine per point), and every estimate needs the same few lengths on
//! several threads: the covariance sandwich, the shaking verdicts and the
//! response check share one cache, so a length is planned once, not once by
//! every thread that transforms at it. A plan is the same whichever thread
//! made it (the planner's choice depends on the length and the CPU only).

use realfft::{RealFftPlanner, RealToComplex};
use rustfft::{Fft, FftPlanner};
use std::sync::{Arc, LazyLock, Mutex, PoisonError};

static PLANNER: LazyLock<Mutex<FftPlanner<f64>>> = LazyLock::new(|| Mutex::new(FftPlanner::new()));
static REAL_PLANNER: LazyLock<Mutex<RealFftPlanner<f64>>> = LazyLock::new(|| Mutex::new(RealFftPlanner::new()));

/// The forward FFT of length `n` (rustfft's, unnormalized).
pub(crate) fn forward(n: usize) -> Arc<dyn Fft<f64>> {
    // A planner left by a panicking thread still holds only finished plans.
    PLANNER.lock().unwrap_or_else(PoisonError::into_inner).plan_fft_forward(n)
}

/// The forward FFT of a real series of length `n` (realfft's, unnormalized):
/// bins 0 … n/2 of the complex transform, the others being their conjugates.
/// Half the work of [`forward`] on the same series.
pub(crate) fn real_forward(n: usize) -> Arc<dyn RealToComplex<f64>> {
    REAL_PLANNER.lock().unwrap_or_else(PoisonError::into_inner).plan_fft_forward(n)
}

/// The smallest even length ≥ `min` whose only prime factors are 2, 3 and 5
/// (rustfft's fastest radices): zero padding to it instead of the next power
/// of two saves up to half of every transform (for 2 × 144 000 epochs:
/// 288 000 = 2⁸·3²·5³ points, not 524 288).
pub(crate) fn fast_len(min: usize) -> usize {
    let target = min.max(2);
    let mut best = target.next_power_of_two();
    let mut p5 = 1usize;
    while p5 < best {
        let mut p35 = p5;
        while p35 < best {
            // The least power of two (at least 2: even) taking p35 to the target.
            let mut n = p35 * 2;
            while n < target {
                n *= 2;
            }
            best = best.min(n);
            p35 *= 3;
        }
        p5 *= 5;
    }
    best
}

#[cfg(test)]
mod tests {
    use super::fast_len;

    /// Against the definition: the first even 5-smooth number at or above each length.
    #[test]
    fn fast_len_is_the_least_even_5_smooth_length() {
        let smooth = |mut n: usize| {
            for p in [2, 3, 5] {
                while n.is_multiple_of(p) {
                    n /= p;
                }
            }
            n == 1
        };
        for min in 0usize..5000 {
            let want = (min.max(2)..).find(|&n: &usize| n.is_multiple_of(2) && smooth(n)).unwrap();
            assert_eq!(fast_len(min), want, "min {min}");
        }
        assert_eq!(fast_len(288_000), 288_000);
        assert_eq!(fast_len(288_001), 291_600);
    }
}
