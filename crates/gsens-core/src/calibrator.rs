use crate::estimator::{GammaEstimate, GammaEstimator};
use crate::filter::HighPass;
use crate::math::dot3;
use crate::pll::{LinearLoop, ModelLoop};
use crate::regressor::{AxisRegressor, RegressorModel, interpolation_compensated};

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

/// Epochs to leave out at the start of a log while the model's start-up
/// transient dies out: ⌈warm-up / log interval⌉ (0 for a warm-up ≤ 0).
pub fn warmup_epochs(warmup_s: f64, log_interval_s: f64) -> u64 {
    libm::ceil(warmup_s / log_interval_s).max(0.0) as u64
}

/// What the calibrator made of one epoch.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FedEpoch {
    /// φ_a after the high-pass \[rad per Hz/(m/s²)\].
    pub phi_a: [f64; 3],
    /// φ after the high-pass \[rad\] (None when no channel was present).
    pub phase_err_rad: Option<f64>,
    /// Whether the estimator used the epoch (not in the warm-up, not settling after a gap).
    pub used: bool,
}

/// Regressor model + identical high-pass + estimator, fed one log epoch at a time.
///
/// Through a gap (no phase measured) the φ filter is fed the last measured φ
/// plus the change of the model's prediction φ_aᵀΓ̂ since then, and the epochs of the
/// gap and the filter's settling after it (up to 3 time constants, at most 4×
/// the gap) are left out of the estimate.
///
/// The per-epoch path of a receiver-side calibration: average the selected
/// channels' phase errors, advance the triad, update the estimator. No
/// allocation.
///
/// The model takes each epoch's specific force as given. Fed raw samples,
/// its linear interpolation between epochs and its point values standing
/// for each update's integration mean read a sinusoid at ω low by
/// c·(ωh)², c = [`RegressorModel::interpolation_compensation`] (h the log
/// interval), and Γ̂ comes out high by as much: feed it samples filtered by
/// [`crate::compensate_interpolation`] (a batch), or use
/// [`PrefilteredCalibrator`], which streams that filter one epoch late.
#[derive(Debug, Clone)]
pub struct Calibrator<E, L = ModelLoop> {
    model: RegressorModel<L>,
    estimator: E,
    skip_epochs: u64,
    epochs: u64,
    hp_phase: HighPass,
    hp_phi_a: [HighPass; 3],
    /// Last measured φ and the raw φ_a at that epoch.
    last_phase_rad: f64,
    last_raw_phi_a: [f64; 3],
    /// Γ̂ frozen at the start of the current gap.
    gap_gamma: [f64; 3],
    gap_epochs: u64,
    settle_left: u64,
}

impl<E: GammaEstimator, L: LinearLoop + Clone> Calibrator<E, L> {
    /// Runs `estimator` on the regressors of `model`, both high-passed at
    /// `highpass_hz` (0 = off) for epochs `log_interval_s` apart, ignoring the
    /// first `skip_epochs` epochs while the model's start-up transient (its
    /// loops start in the steady state of the first sample) dies out.
    pub fn new(
        model: RegressorModel<L>,
        estimator: E,
        skip_epochs: u64,
        highpass_hz: f64,
        log_interval_s: f64,
    ) -> Self {
        let hp = HighPass::new(highpass_hz, log_interval_s);
        Calibrator {
            model,
            estimator,
            skip_epochs,
            epochs: 0,
            hp_phase: hp,
            hp_phi_a: [hp; 3],
            last_phase_rad: 0.0,
            last_raw_phi_a: [0.0; 3],
            gap_gamma: [0.0; 3],
            gap_epochs: 0,
            settle_left: 0,
        }
    }

    /// One epoch: specific force `accel_mps2` and the averaged phase error
    /// (None when no channel was present; the model still advances).
    #[inline]
    pub fn feed(&mut self, accel_mps2: &[f64; 3], phase_err_rad: Option<f64>) -> FedEpoch {
        let raw = self.model.epoch(accel_mps2);
        let phi_a = [self.hp_phi_a[0].step(raw[0]), self.hp_phi_a[1].step(raw[1]), self.hp_phi_a[2].step(raw[2])];
        self.feed_regressed(&raw, &phi_a, phase_err_rad)
    }

    /// The regressor's three axes, each its loop model and φ_a high-pass in
    /// this calibrator's current state, as independent recursions
    /// ([`AxisStage`]): axis i fed a_i returns the raw and the high-passed
    /// φ_a,i that [`Calibrator::feed`] computes, bit for bit. A caller runs
    /// them (on any threads) and hands each epoch's values to
    /// [`Calibrator::feed_regressed`] in epoch order.
    pub fn axis_stages(&self) -> [AxisStage<L>; 3] {
        let [x, y, z] = self.model.axes();
        [
            AxisStage { regressor: x, highpass: self.hp_phi_a[0] },
            AxisStage { regressor: y, highpass: self.hp_phi_a[1] },
            AxisStage { regressor: z, highpass: self.hp_phi_a[2] },
        ]
    }

    /// One epoch whose regressors were computed by [`Calibrator::axis_stages`]:
    /// `raw_phi_a` (the loop models' φ_a) and `phi_a` (high-passed), and the
    /// averaged phase error (None when no channel was present). The phase's
    /// high-pass, the gap filling and the estimator's update of
    /// [`Calibrator::feed`]; this calibrator's own model does not advance,
    /// so a calibrator is fed one way or the other, not both.
    #[inline]
    pub fn feed_regressed(&mut self, raw_phi_a: &[f64; 3], phi_a: &[f64; 3], phase_err_rad: Option<f64>) -> FedEpoch {
        let (raw, phi_a) = (*raw_phi_a, *phi_a);
        self.epochs += 1;
        let (input, measured) = match phase_err_rad.filter(|p| p.is_finite()) {
            Some(p) => {
                self.last_phase_rad = p;
                self.last_raw_phi_a = raw;
                if self.gap_epochs > 0 {
                    let tau = self.hp_phase.time_constant_samples();
                    self.settle_left = ((3.0 * tau) as u64).min(4 * self.gap_epochs);
                    self.gap_epochs = 0;
                }
                (p, true)
            }
            None => {
                if self.gap_epochs == 0 {
                    self.gap_gamma = self.estimator.gamma_hz_per_mps2();
                }
                self.gap_epochs += 1;
                let d =
                    [raw[0] - self.last_raw_phi_a[0], raw[1] - self.last_raw_phi_a[1], raw[2] - self.last_raw_phi_a[2]];
                (self.last_phase_rad + dot3(&d, &self.gap_gamma), false)
            }
        };
        let phi = self.hp_phase.step(input);
        let mut used = false;
        if measured {
            if self.settle_left > 0 {
                self.settle_left -= 1;
            } else if self.epochs > self.skip_epochs {
                self.estimator.update(phi, &phi_a);
                used = true;
            }
        }
        FedEpoch { phi_a, phase_err_rad: measured.then_some(phi), used }
    }

    /// One epoch from the raw channel phases (NaN = absent) and their weights.
    #[inline]
    pub fn feed_channels(&mut self, accel_mps2: &[f64; 3], phase_err_rad: &[f64], weights: &[f64]) -> FedEpoch {
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

/// One axis of a [`Calibrator`]'s regressor ([`Calibrator::axis_stages`]):
/// the axis's loop model φ_a,i = L\[a_i\] and the high-pass H that follows
/// it, y_k = α·(y_{k−1} + x_k − x_{k−1}) (the calibrator's high-pass).
#[derive(Debug, Clone)]
pub struct AxisStage<L = ModelLoop> {
    regressor: AxisRegressor<L>,
    highpass: HighPass,
}

impl<L: LinearLoop> AxisStage<L> {
    /// The next epoch's specific force on this axis in \[m/s²\]; returns the
    /// raw φ_a,i and H\[φ_a,i\].
    #[inline]
    pub fn step(&mut self, accel_mps2: f64) -> (f64, f64) {
        let raw = self.regressor.epoch(accel_mps2);
        (raw, self.highpass.step(raw))
    }
}

/// A [`Calibrator`] whose model input carries the interpolation prefilter of
/// the batch path ([`crate::compensate_interpolation`]), streamed: epoch k's
/// specific force becomes a_k + c·(2a_k − a_{k−1} − a_{k+1}) once a_{k+1} has
/// arrived, so each epoch is processed one epoch late (at the ends the missing
/// neighbour is the sample itself, as in the batch path). Without it a model
/// whose loop runs faster than its log sees the specific force linearly
/// interpolated between epochs, attenuated by ≈ (1 − 1/n²)·(ωh)²/12, and Γ̂
/// comes out too large by that much (0.17 % at 0.9 Hz, 40 Hz logs, 1 ms
/// loop). c = [`RegressorModel::interpolation_compensation`]. No allocation.
#[derive(Debug, Clone)]
pub struct PrefilteredCalibrator<E, L = ModelLoop> {
    inner: Calibrator<E, L>,
    c: f64,
    /// The raw specific force of the epoch before the pending one.
    prev_raw: Option<[f64; 3]>,
    /// The epoch waiting for its successor: raw specific force and phase.
    pending: Option<([f64; 3], Option<f64>)>,
}

impl<E: GammaEstimator, L: LinearLoop + Clone> PrefilteredCalibrator<E, L> {
    /// Streams `inner` with the prefilter of its model.
    pub fn new(inner: Calibrator<E, L>) -> Self {
        let c = inner.model.interpolation_compensation();
        PrefilteredCalibrator { inner, c, prev_raw: None, pending: None }
    }

    fn filtered(&self, a: &[f64; 3], prev: &[f64; 3], next: &[f64; 3]) -> [f64; 3] {
        let c = self.c;
        [0, 1, 2].map(|i| interpolation_compensated(prev[i], a[i], next[i], c))
    }

    /// One epoch in; out comes the previous epoch, now that its successor is
    /// known (None for the first epoch).
    pub fn feed(&mut self, accel_mps2: &[f64; 3], phase_err_rad: Option<f64>) -> Option<FedEpoch> {
        let out = self.pending.map(|(a, p)| {
            let prev = self.prev_raw.unwrap_or(a);
            let f = self.filtered(&a, &prev, accel_mps2);
            self.prev_raw = Some(a);
            self.inner.feed(&f, p)
        });
        self.pending = Some((*accel_mps2, phase_err_rad));
        out
    }

    /// The last epoch, with itself as its missing successor (the end of a log).
    pub fn flush(&mut self) -> Option<FedEpoch> {
        let (a, p) = self.pending.take()?;
        let prev = self.prev_raw.unwrap_or(a);
        let f = self.filtered(&a, &prev, &a);
        self.prev_raw = Some(a);
        Some(self.inner.feed(&f, p))
    }

    /// The estimate over the epochs processed so far (all but the pending one).
    pub fn estimate(&self) -> GammaEstimate {
        self.inner.estimate()
    }

    /// The calibrator it streams.
    pub fn calibrator(&self) -> &Calibrator<E, L> {
        &self.inner
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

    /// The axes run on their own and handed to `feed_regressed` are `feed`,
    /// bit for bit: epochs, estimator and gaps (the model's prediction
    /// through them), for a lifted loop (25 updates an epoch) and one at the
    /// log rate, high-pass on and off.
    #[test]
    fn axis_stages_and_feed_regressed_are_feed_bit_for_bit() {
        use crate::estimator::BatchLeastSquares;
        use crate::pll::LoopSpec;
        use crate::regressor::LoggedPhase;
        let coeffs = LoopSpec::PAPER.coeffs().unwrap();
        // A seeded linear congruential sequence in [−1, 1).
        let mut seed: u64 = 3;
        let mut uniform = move || {
            seed = seed.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        let epochs: [([f64; 3], Option<f64>); 3000] = core::array::from_fn(|k| {
            let t = k as f64 * 0.025;
            let a = [libm::sin(5.7 * t) + 0.1 * uniform(), 0.3 * uniform(), 9.8 + libm::cos(3.1 * t)];
            // Gaps of 1, 7 and 40 epochs.
            let gap = k == 500 || (900..907).contains(&k) || (2000..2040).contains(&k);
            (a, (!gap).then(|| 0.1 * uniform()))
        });
        for (loop_interval_s, highpass_hz) in [(0.001, 0.05), (0.025, 0.05), (0.001, 0.0)] {
            let model = RegressorModel::new(coeffs, loop_interval_s, 0.025, LoggedPhase::Mean).unwrap();
            let new = || Calibrator::new(model.clone(), BatchLeastSquares::new(), 80, highpass_hz, 0.025);
            let (mut whole, mut split) = (new(), new());
            let mut axes = split.axis_stages();
            for (a, p) in &epochs {
                let want = whole.feed(a, *p);
                let [x, y, z] = core::array::from_fn(|i| axes[i].step(a[i]));
                let got = split.feed_regressed(&[x.0, y.0, z.0], &[x.1, y.1, z.1], *p);
                assert_eq!(got.phi_a.map(f64::to_bits), want.phi_a.map(f64::to_bits));
                assert_eq!(got.phase_err_rad.map(f64::to_bits), want.phase_err_rad.map(f64::to_bits));
                assert_eq!(got.used, want.used);
            }
            let bits = |c: &Calibrator<BatchLeastSquares>| {
                let ne = c.estimator().normal_equations();
                (ne.ata.map(f64::to_bits), ne.atb.map(f64::to_bits), ne.btb.to_bits(), ne.n)
            };
            assert_eq!(bits(&split), bits(&whole));
        }
    }
}
