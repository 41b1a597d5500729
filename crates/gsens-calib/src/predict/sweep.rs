//! What compensation buys over a range of vibration levels (what `gsens
//! predict` tabulates): at each level the base vibration scaled (amplitudes
//! by the level, a spectrum by its square), the phase jitter without and
//! with compensation ([`jitter`]), and the narrowest noise bandwidth on
//! [`BN_GRID_HZ`] that keeps lock ([`narrowest_bn_hz`]); and the lock margin
//! against the bandwidth at one level, for a figure.

use super::{PredictionInput, Vibration, jitter, narrowest_bn_hz, second_order_loop};
use gsens_core::LoopError;
use serde::Serialize;

/// The noise bandwidths the narrowest-loop search and the lock-margin curve
/// run over: 0.1 to 20 Hz in 0.1 Hz steps.
pub const BN_GRID_HZ: [f64; 200] = {
    let mut grid = [0.0; 200];
    let mut k = 0;
    while k < 200 {
        grid[k] = 0.1 * (k + 1) as f64;
        k += 1;
    }
    grid
};

/// The inputs of a sweep: the prediction's input at level 1, the levels
/// and the 2nd-order loop.
#[derive(Debug, Clone, PartialEq)]
pub struct SweepSettings {
    /// Γ̂, its covariance, the vibration at level 1, the oscillator, the
    /// signal and the feed-forward's delay.
    pub base: PredictionInput,
    /// The levels (finite, ≥ 0).
    pub levels: Vec<f64>,
    /// The loop's noise bandwidth \[Hz\].
    pub bn_hz: f64,
    /// Its damping.
    pub zeta: f64,
    /// Its update interval \[s\].
    pub loop_interval_s: f64,
}

/// One level of a sweep (fields in the order `gsens predict --json` writes
/// its keys: alphabetical).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SweepRow {
    /// θₑ, the loop's dynamic stress under the Doppler rate \[rad\].
    pub dynamic_stress_rad: f64,
    /// Whether 3σ + θₑ ≤ 45° without and with compensation.
    pub keeps_lock: [bool; 2],
    /// The level.
    pub level: f64,
    /// The narrowest bandwidth on [`BN_GRID_HZ`] keeping lock without and
    /// with compensation \[Hz\] (`None`: none on the grid).
    pub narrowest_bn_hz: [Option<f64>; 2],
    /// 1σ of the oscillator's part \[rad\].
    pub oscillator_rad: f64,
    /// Probability of |φ| beyond the discriminator's range, without and with.
    pub p_beyond_linear_range: [f64; 2],
    /// 1σ of the thermal part \[rad\].
    pub thermal_rad: f64,
    /// 1σ in all, without and with \[rad\].
    pub total_rad: [f64; 2],
    /// 1σ of the vibration's part, without and with \[rad\].
    pub vibration_rad: [f64; 2],
    /// RMS acceleration per axis at this level \[m/s²\].
    pub vibration_rms_mps2: [f64; 3],
}

/// A sweep: the estimate it was made for, the loop's bandwidth, one row per
/// level (what `gsens predict --json` writes).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Sweep {
    /// The loop's noise bandwidth \[Hz\].
    pub bn_hz: f64,
    /// Γ̂'s covariance \[(Hz/(m/s²))²\].
    pub covariance_hz_per_mps2_sq: [[f64; 3]; 3],
    /// Γ̂ \[Hz/(m/s²)\].
    pub gamma_hz_per_mps2: [f64; 3],
    /// One row per level, in the order given.
    pub predictions: Vec<SweepRow>,
}

/// Why a sweep could not run.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SweepError {
    /// The loop is not stable or not valid at its interval.
    #[error("the loop (Bn {bn_hz} Hz, T {interval_s} s): {error}")]
    Loop {
        /// Its noise bandwidth \[Hz\].
        bn_hz: f64,
        /// Its update interval \[s\].
        interval_s: f64,
        /// Why.
        error: LoopError,
    },
    /// A level is negative or not finite.
    #[error("level {0}: must be finite and ≥ 0")]
    Level(f64),
}

impl SweepSettings {
    /// The prediction's input at `level`.
    pub fn input_at(&self, level: f64) -> PredictionInput {
        let vibration = match &self.base.vibration {
            Vibration::Spectrum(p) => {
                Vibration::Spectrum(p.iter().map(|(f, s)| (*f, s.map(|v| v * level * level))).collect())
            }
            Vibration::Tones(t) => Vibration::Tones(t.iter().map(|(f, a)| (*f, a.map(|v| v * level))).collect()),
        };
        PredictionInput { vibration, ..self.base.clone() }
    }

    /// The sweep over [`SweepSettings::levels`].
    pub fn sweep(&self) -> Result<Sweep, SweepError> {
        let receiver_loop = second_order_loop(self.bn_hz, self.zeta, self.loop_interval_s);
        receiver_loop.check().map_err(|error| SweepError::Loop {
            bn_hz: self.bn_hz,
            interval_s: self.loop_interval_s,
            error,
        })?;
        let mut predictions = Vec::with_capacity(self.levels.len());
        for &level in &self.levels {
            if !(level.is_finite() && level >= 0.0) {
                return Err(SweepError::Level(level));
            }
            let input = self.input_at(level);
            let j = jitter(&receiver_loop, self.bn_hz, self.loop_interval_s, &input);
            predictions.push(SweepRow {
                dynamic_stress_rad: j.dynamic_stress_rad,
                keeps_lock: j.keeps_lock,
                level,
                narrowest_bn_hz: narrowest_bn_hz(self.zeta, self.loop_interval_s, &input, &BN_GRID_HZ),
                oscillator_rad: j.oscillator_rad,
                p_beyond_linear_range: j.p_beyond_range,
                thermal_rad: j.thermal_rad,
                total_rad: j.total_rad,
                vibration_rad: j.vibration_rad,
                vibration_rms_mps2: input.vibration.rms_mps2(),
            });
        }
        Ok(Sweep {
            bn_hz: self.bn_hz,
            covariance_hz_per_mps2_sq: self.base.covariance,
            gamma_hz_per_mps2: self.base.gamma_hz_per_mps2,
            predictions,
        })
    }

    /// The lock margin 3σ + θₑ \[rad\] without and with compensation at
    /// `level`, against each stable bandwidth of [`BN_GRID_HZ`]: (Bn,
    /// without, with).
    pub fn lock_margin(&self, level: f64) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        let input = self.input_at(level);
        let (mut bns, mut without, mut with) = (Vec::new(), Vec::new(), Vec::new());
        for bn in BN_GRID_HZ {
            let l = second_order_loop(bn, self.zeta, self.loop_interval_s);
            if l.check().is_err() {
                continue;
            }
            let j = jitter(&l, bn, self.loop_interval_s, &input);
            bns.push(bn);
            without.push(3.0 * j.total_rad[0] + j.dynamic_stress_rad);
            with.push(3.0 * j.total_rad[1] + j.dynamic_stress_rad);
        }
        (bns, without, with)
    }
}
