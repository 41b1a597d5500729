//! The settings of the estimation stage: the receiver's loop, the estimator
//! and the error model. Reported with every estimate.

use crate::CalibError;
use gsens_core::LoopModel;
use gsens_core::LoopSpec;
use gsens_core::ObservabilityCriteria;
use gsens_core::{Discriminator, LoggedPhase};
use serde::{Deserialize, Serialize};

/// Which estimator produces Γ̂.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "name", rename_all = "lowercase")]
pub enum Method {
    /// The paper's gradient observer with constant gain k.
    Gradient {
        /// Gain k \[1/s per unit φ_a²\].
        gain_k: f64,
    },
    /// Recursive least squares (Kalman-type gain) with forgetting factor λ.
    Rls {
        /// Forgetting factor λ (1 = none).
        lambda: f64,
    },
    /// Batch least squares over the whole log.
    Batch,
    /// Generalized least squares: the batch fit prewhitened by an AR model of
    /// its residuals (see [`crate::gls`]); efficient under coloured noise.
    Gls,
}

impl core::fmt::Display for Method {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Method::Gradient { gain_k } => write!(f, "gradient observer, gain k = {gain_k}"),
            Method::Rls { lambda } => write!(f, "recursive least squares, forgetting factor λ = {lambda}"),
            Method::Batch => write!(f, "batch least squares"),
            Method::Gls => write!(f, "generalized least squares (AR noise model)"),
        }
    }
}

/// Robust estimation against outlying epochs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum Robust {
    /// Plain least squares.
    #[default]
    None,
    /// Huber's M-estimate (iteratively reweighted least squares).
    ///
    /// Batch method only; see [`crate::huber_irls`].
    Huber,
}

/// Everything that decides an estimate from an epoch series; reported with it.
///
/// Build it from [`EstimateSettings::default`] (the paper's loop and the
/// batch estimator) and set the fields that differ.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[non_exhaustive]
pub struct EstimateSettings {
    /// The receiver's carrier loop. A [`LoopModel::Kaplan`] loop without an
    /// update interval is taken to run at the log interval.
    pub receiver_loop: LoopModel,
    /// What a log row holds when the loop runs faster than the log.
    pub logged_phase: LoggedPhase,
    /// The estimator.
    pub method: Method,
    /// Epochs in the first `warmup_s` seconds only drive the loop models.
    pub warmup_s: f64,
    /// Corner of the identical high-pass on φ and φ_a \[Hz\] (0 = off); see
    /// [`gsens_core::HighPass`].
    pub highpass_hz: f64,
    /// Longest lag of the autocorrelation-robust covariance \[s\].
    pub hac_lag_s: f64,
    /// Carrier frequency \[Hz\] for ppb/g.
    pub carrier_hz: f64,
    /// 1σ of the IMU's scale-factor error per axis (fraction, e.g. 1e-3),
    /// propagated into the uncertainty of Γ̂ (see [`crate::imu_systematic_sigma`]).
    pub imu_scale_sigma: f64,
    /// 1σ of the IMU's axis misalignment \[rad\], propagated likewise.
    pub imu_misalignment_sigma_rad: f64,
    /// Observability thresholds.
    pub criteria: ObservabilityCriteria,
    /// Robust estimation against outlying epochs (default none).
    pub robust: Robust,
    /// The receiver's carrier-phase discriminator, whose linear range the
    /// predicted peak phase error is checked against (default atan Costas,
    /// what GPS L1 C/A receivers use; absent in documents written before it
    /// existed, which read as atan Costas).
    #[serde(default)]
    pub discriminator: Discriminator,
}

impl Default for EstimateSettings {
    fn default() -> Self {
        EstimateSettings {
            receiver_loop: LoopModel::kaplan(LoopSpec::PAPER, None),
            logged_phase: LoggedPhase::Last,
            method: Method::Batch,
            warmup_s: crate::defaults::DEFAULT_WARMUP_S,
            highpass_hz: crate::defaults::DEFAULT_HIGHPASS_HZ,
            hac_lag_s: 2.5,
            carrier_hz: gsens_core::units::GPS_L1_HZ,
            imu_scale_sigma: 0.0,
            imu_misalignment_sigma_rad: 0.0,
            criteria: ObservabilityCriteria::default(),
            robust: Robust::None,
            discriminator: Discriminator::AtanCostas,
        }
    }
}

/// The shortest carrier-loop update interval \[s\]: one code period
/// ([`gsens_core::units::L1CA_CODE_PERIOD_S`]), less a rounding margin.
pub(crate) const MIN_LOOP_INTERVAL_S: f64 = gsens_core::units::L1CA_CODE_PERIOD_S * (1.0 - 1e-9);

/// `x` within `[lo, hi]`, else an error naming the setting and `expected`.
fn within(name: &'static str, x: f64, lo: f64, hi: f64, expected: &'static str) -> Result<(), CalibError> {
    if x >= lo && x <= hi { Ok(()) } else { Err(CalibError::Setting { name, value: x, expected }) }
}

/// `x` finite and ≥ 0 (or > 0 with `strict`), else an error naming the setting.
pub(crate) fn check_range(name: &'static str, x: f64, strict: bool) -> Result<(), CalibError> {
    let ok = x.is_finite() && if strict { x > 0.0 } else { x >= 0.0 };
    if ok {
        Ok(())
    } else {
        Err(CalibError::Setting {
            name, value: x, expected: if strict { "finite and > 0" } else { "finite and ≥ 0" }
        })
    }
}

impl EstimateSettings {
    /// These settings with the receiver loop `receiver_loop`.
    pub fn with_loop(mut self, receiver_loop: LoopModel) -> Self {
        self.receiver_loop = receiver_loop;
        self
    }

    /// These settings with the estimator `method`.
    pub fn with_method(mut self, method: Method) -> Self {
        self.method = method;
        self
    }

    /// These settings with robust estimation `robust`.
    pub fn with_robust(mut self, robust: Robust) -> Self {
        self.robust = robust;
        self
    }

    /// The loop the model runs for a log sampled every `log_interval_s`: the
    /// receiver loop, updated at the log interval when no interval is stated.
    pub fn loop_at(&self, log_interval_s: f64) -> LoopModel {
        self.receiver_loop.with_default_interval(log_interval_s)
    }

    /// Checks every value against its range (the loop is checked when the
    /// model is built, against the log interval).
    pub fn validate(&self) -> Result<(), CalibError> {
        match self.method {
            Method::Rls { lambda } if !(lambda > 0.0 && lambda <= 1.0) => {
                return Err(CalibError::Setting { name: "lambda", value: lambda, expected: "in (0, 1]" });
            }
            Method::Gradient { gain_k } => check_range("gain_k", gain_k, true)?,
            _ => {}
        }
        check_range("warmup_s", self.warmup_s, false)?;
        check_range("highpass_hz", self.highpass_hz, false)?;
        check_range("hac_lag_s", self.hac_lag_s, false)?;
        check_range("carrier_hz", self.carrier_hz, true)?;
        within(
            "carrier_hz",
            self.carrier_hz,
            1e8,
            1e11,
            "a radio carrier, 1e8 to 1e11 Hz (GNSS carriers are 1.1–1.7 GHz)",
        )?;
        check_range("imu_scale_sigma", self.imu_scale_sigma, false)?;
        within("imu_scale_sigma", self.imu_scale_sigma, 0.0, 1.0, "at most 1 (a scale factor error of 100 %)")?;
        check_range("imu_misalignment_sigma_rad", self.imu_misalignment_sigma_rad, false)?;
        let quarter_turn = core::f64::consts::FRAC_PI_2;
        within("imu_misalignment_sigma_rad", self.imu_misalignment_sigma_rad, 0.0, quarter_turn, "at most π/2 rad")?;
        // No GNSS open signal's code is shorter than 1 ms: no carrier loop integrates less.
        if let Some(t) = self.receiver_loop.interval_s() {
            let expected = "at least 0.001 s (one code period of GPS L1 C/A, the shortest of the GNSS open signals)";
            within("loop_interval_s", t, MIN_LOOP_INTERVAL_S, f64::INFINITY, expected)?;
        }
        if self.robust == Robust::Huber && self.method != Method::Batch {
            // The recursive estimators have no second pass; GLS would need a
            // robust AR fit and IRLS on the prewhitened series (an outlier
            // spreads over the AR filter's length there).
            return Err(CalibError::Unsupported("robust (Huber) estimation works with the batch method only"));
        }
        Ok(())
    }
}
