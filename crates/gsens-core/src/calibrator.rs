//! The per-epoch path of a receiver-side calibration: average the selected
//! channels' phase errors, advance the triad, update the estimator. No
//! allocation.

use crate::estimator::{GammaEstimate, GammaEstimator};
use crate::regressor::RegressorModel;

/// Weighted mean of the channels present at an epoch: Σwᵢφᵢ/Σwᵢ over the
/// channels whose phase is finite (absent channels are NaN). The weights are
/// renormalized over the present channels, so a channel dropping out does not
/// bias the common (oscillator) part. `None` when no channel is present.
#[inline]
pub fn average_phase_rad(phase_err_rad: &[f64], weights: &[f64]) -> Option<f64> {
    let mut sum = 0.0;
    let mut wsum = 0.0;
    for (p, w) in phase_err_rad.iter().zip(weights) {
        if p.is_finite() {
            sum += w * p;
            wsum += w;
        }
    }
    if wsum > 0.0 { Some(sum / wsum) } else { None }
}

/// Regressor model + estimator, fed one log epoch at a time.
#[derive(Debug, Clone)]
pub struct Calibrator<E> {
    model: RegressorModel,
    estimator: E,
    skip_epochs: u64,
    epochs: u64,
}

impl<E: GammaEstimator> Calibrator<E> {
    /// Runs `estimator` on the regressors of `model`, ignoring the first
    /// `skip_epochs` epochs while the model's start-up transient (its loops
    /// start in the steady state of the first sample) dies out.
    pub fn new(model: RegressorModel, estimator: E, skip_epochs: u64) -> Self {
        Calibrator { model, estimator, skip_epochs, epochs: 0 }
    }

    /// One epoch: specific force `accel_mps2` and the averaged phase error
    /// (None when no channel was present; the model still advances). Returns φ_a.
    #[inline]
    pub fn feed(&mut self, accel_mps2: &[f64; 3], phase_err_rad: Option<f64>) -> [f64; 3] {
        let phi_a = self.model.epoch(accel_mps2);
        self.epochs += 1;
        if let Some(phi) = phase_err_rad
            && self.epochs > self.skip_epochs
        {
            self.estimator.update(phi, &phi_a);
        }
        phi_a
    }

    /// One epoch from the raw channel phases (NaN = absent) and their weights.
    #[inline]
    pub fn feed_channels(&mut self, accel_mps2: &[f64; 3], phase_err_rad: &[f64], weights: &[f64]) -> [f64; 3] {
        self.feed(accel_mps2, average_phase_rad(phase_err_rad, weights))
    }

    /// The current estimate.
    pub fn estimate(&self) -> GammaEstimate {
        self.estimator.estimate()
    }

    /// Epochs ignored at the start.
    pub fn skip_epochs(&self) -> u64 {
        self.skip_epochs
    }

    /// The estimator.
    pub fn estimator(&self) -> &E {
        &self.estimator
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    #[test]
    fn average_renormalizes_over_present_channels() {
        let nan = f64::NAN;
        assert_eq!(average_phase_rad(&[1.0, 3.0, nan], &[1.0, 1.0, 1.0]), Some(2.0));
        assert_eq!(average_phase_rad(&[1.0, 3.0, 5.0], &[1.0, 1.0, 2.0]), Some(3.5));
        assert_eq!(average_phase_rad(&[nan, nan], &[1.0, 1.0]), None);
    }
}
