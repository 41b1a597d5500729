//! Forward FFTs of the lengths the estimate needs, planned once per thread.
//!
//! A plan of the long transforms here (2¹⁹ points for an hour at 40 Hz)
//! costs as much as several transforms (its twiddle factors), and every
//! estimate needs the same few lengths: the covariance sandwich, the shaking
//! verdicts and the response check share one cache per thread.

use realfft::{RealFftPlanner, RealToComplex};
use rustfft::{Fft, FftPlanner};
use std::cell::RefCell;
use std::sync::Arc;

thread_local! {
    static PLANNER: RefCell<FftPlanner<f64>> = RefCell::new(FftPlanner::new());
    static REAL_PLANNER: RefCell<RealFftPlanner<f64>> = RefCell::new(RealFftPlanner::new());
}

/// The forward FFT of length `n` (rustfft's, unnormalized).
pub(crate) fn forward(n: usize) -> Arc<dyn Fft<f64>> {
    PLANNER.with(|p| p.borrow_mut().plan_fft_forward(n))
}

/// The forward FFT of a real series of length `n` (realfft's, unnormalized):
/// bins 0 … n/2 of the complex transform, the others being their conjugates.
/// Half the work of [`forward`] on the same series.
pub(crate) fn real_forward(n: usize) -> Arc<dyn RealToComplex<f64>> {
    REAL_PLANNER.with(|p| p.borrow_mut().plan_fft_forward(n))
}
