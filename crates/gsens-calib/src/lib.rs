//! # gsens-calib
//!
//! The calibration job: from a uniform epoch series of channel-averaged phase
//! error φ [rad] and specific force a [m/s²] to Γ̂ with its uncertainty, the
//! observability verdict per axis, and what compensation removes.
//!
//! It wires the pure core ([`gsens_core`]) together and adds what needs the
//! whole series in memory: the residual series for an autocorrelation-robust
//! covariance (the residuals of a carrier loop are coloured, see
//! [`gsens_core::estimator::hac_covariance`]) and the RMS before and after
//! compensation. No file I/O: the CLI reads logs with `gsens-io`.
#![deny(missing_docs)]

use gsens_core::calibrator::FedEpoch;
pub mod gls;
pub mod robust;
pub mod search;
pub mod verdict;

use gsens_core::estimator::{
    BatchLeastSquares, GammaEstimate, GradientObserver, RecursiveLeastSquares, hac_covariance,
};
use gsens_core::observability::{ObservabilityCriteria, assess};
use gsens_core::pll::gnss_sdr::{GnssSdrPll, GnssSdrStage};
use gsens_core::pll::{LoopError, LoopSpec};
use gsens_core::regressor::{LoggedPhase, RegressorError, RegressorModel};
use gsens_core::units::hz_per_mps2_to_ppb_per_g;
use gsens_core::{Calibrator, GammaEstimator, compensate::compensated_phase_rad};
use serde::Serialize;

/// Which estimator produces Γ̂.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(tag = "name", rename_all = "lowercase")]
pub enum Method {
    /// The paper's gradient observer with constant gain k.
    Gradient {
        /// Gain k [1/s per unit φ_a²].
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
    /// its residuals (see [`gls`]); efficient under coloured noise.
    Gls,
}

/// Robust estimation against outlying epochs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Robust {
    /// Plain least squares.
    #[default]
    None,
    /// Huber's M-estimate by iteratively reweighted least squares (batch method
    /// only; see [`robust`]).
    Huber,
}

/// Everything that decides an estimate; reported with it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct EstimateSettings {
    /// The receiver's carrier loop.
    #[serde(serialize_with = "ser_loop")]
    pub loop_spec: LoopSpec,
    /// The receiver's loop update interval [s]; `None` = the log interval.
    pub loop_interval_s: Option<f64>,
    /// What a log row holds when the loop runs faster than the log.
    #[serde(serialize_with = "ser_logged")]
    pub logged_phase: LoggedPhase,
    /// The estimator.
    pub method: Method,
    /// Epochs in the first `warmup_s` seconds only drive the loop models.
    pub warmup_s: f64,
    /// Corner of the identical high-pass on φ and φ_a [Hz] (0 = off); see
    /// [`gsens_core::filter`].
    pub highpass_hz: f64,
    /// Longest lag of the autocorrelation-robust covariance [s].
    pub hac_lag_s: f64,
    /// Carrier frequency [Hz] for ppb/g.
    pub carrier_hz: f64,
    /// 1σ of the IMU's scale-factor error per axis (fraction, e.g. 1e-3),
    /// propagated into the uncertainty of Γ̂ (see [`imu_systematic_sigma`]).
    pub imu_scale_sigma: f64,
    /// 1σ of the IMU's axis misalignment [rad], propagated likewise.
    pub imu_misalignment_sigma_rad: f64,
    /// Observability thresholds.
    #[serde(serialize_with = "ser_criteria")]
    pub criteria: ObservabilityCriteria,
    /// Robust estimation against outlying epochs (default none).
    pub robust: Robust,
    /// The receiver runs GNSS-SDR's carrier loop, this stage of it (after bit
    /// synchronization): the loop models are then
    /// [`gsens_core::pll::gnss_sdr::GnssSdrPll`]s updated every
    /// `symbols` ms, and `loop_spec` only describes the loop nominally.
    /// `None` (default): the loop of `loop_spec` ([`gsens_core::pll`]'s docs).
    #[serde(serialize_with = "ser_gnss_sdr")]
    pub gnss_sdr_loop: Option<GnssSdrStage>,
}

fn ser_gnss_sdr<S: serde::Serializer>(g: &Option<GnssSdrStage>, s: S) -> Result<S::Ok, S::Error> {
    use serde::ser::SerializeMap;
    match g {
        None => s.serialize_none(),
        Some(g) => {
            let mut m = s.serialize_map(Some(4))?;
            m.serialize_entry("implementation", "GNSS-SDR GPS_L1_CA_DLL_PLL_Tracking (dll_pll_veml)")?;
            m.serialize_entry("pll_filter_order", &g.order)?;
            m.serialize_entry("pll_bw_hz", &g.bw_hz)?;
            m.serialize_entry("integration_ms", &g.symbols)?;
            m.end()
        }
    }
}

impl Default for EstimateSettings {
    fn default() -> Self {
        EstimateSettings {
            loop_spec: LoopSpec::PAPER,
            loop_interval_s: None,
            logged_phase: LoggedPhase::Last,
            method: Method::Batch,
            warmup_s: 2.0,
            highpass_hz: 0.05,
            hac_lag_s: 2.5,
            carrier_hz: gsens_core::units::GPS_L1_HZ,
            imu_scale_sigma: 0.0,
            imu_misalignment_sigma_rad: 0.0,
            criteria: ObservabilityCriteria::default(),
            robust: Robust::None,
            gnss_sdr_loop: None,
        }
    }
}

fn ser_loop<S: serde::Serializer>(l: &LoopSpec, s: S) -> Result<S::Ok, S::Error> {
    use serde::ser::SerializeMap;
    let mut m = s.serialize_map(None)?;
    match *l {
        LoopSpec::SecondOrder { bn_hz, zeta } => {
            m.serialize_entry("order", &2)?;
            m.serialize_entry("bn_hz", &bn_hz)?;
            m.serialize_entry("zeta", &zeta)?;
        }
        LoopSpec::ThirdOrder { bn_hz, a3, b3 } => {
            m.serialize_entry("order", &3)?;
            m.serialize_entry("bn_hz", &bn_hz)?;
            m.serialize_entry("a3", &a3)?;
            m.serialize_entry("b3", &b3)?;
        }
        LoopSpec::Coefficients(c) => {
            m.serialize_entry("c0_per_s", &c.c0_per_s)?;
            m.serialize_entry("c1_per_s2", &c.c1_per_s2)?;
            m.serialize_entry("c2_per_s3", &c.c2_per_s3)?;
        }
    }
    if let Some(wn) = l.wn_rad_per_s() {
        m.serialize_entry("natural_frequency_hz", &(wn / core::f64::consts::TAU))?;
    }
    m.end()
}

fn ser_logged<S: serde::Serializer>(l: &LoggedPhase, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(match l {
        LoggedPhase::Last => "last",
        LoggedPhase::Mean => "mean",
    })
}

fn ser_criteria<S: serde::Serializer>(c: &ObservabilityCriteria, s: S) -> Result<S::Ok, S::Error> {
    use serde::ser::SerializeMap;
    let mut m = s.serialize_map(Some(2))?;
    m.serialize_entry("min_excitation_rms", &c.min_excitation_rms)?;
    m.serialize_entry("max_sigma_hz_per_mps2", &c.max_sigma_hz_per_mps2)?;
    m.end()
}

/// Why a calibration could not run.
#[derive(Debug, thiserror::Error)]
pub enum CalibError {
    /// The loop specification is invalid.
    #[error("invalid loop: {0}")]
    Loop(LoopError),
    /// Loop and log intervals do not fit together.
    #[error("{0}")]
    Intervals(RegressorError),
    /// The discrete loop at this interval is unstable.
    #[error("the loop (Bn, order) is unstable when updated every {0} s; is --loop-interval-s right?")]
    UnstableAtInterval(f64),
    /// Series of different lengths or too short.
    #[error("{0}")]
    Input(String),
}

/// A calibration result: the public JSON interface of `gsens estimate`
/// (key names as in conventions.md).
#[derive(Debug, Clone, Serialize)]
pub struct Calibration {
    /// Γ̂ [Hz/(m/s²)]; `null` for an unobservable axis.
    pub gamma_hz_per_mps2: [Option<f64>; 3],
    /// Total 1σ [Hz/(m/s²)]: the statistical part (autocorrelation-robust) and
    /// the IMU-calibration part combined; `null` for an unobservable axis.
    pub sigma_hz_per_mps2: [Option<f64>; 3],
    /// Statistical 1σ alone [Hz/(m/s²)].
    pub sigma_statistical_hz_per_mps2: [Option<f64>; 3],
    /// 1σ from the assumed IMU scale-factor and misalignment errors [Hz/(m/s²)].
    pub sigma_imu_hz_per_mps2: [Option<f64>; 3],
    /// Γ̂ [ppb/g] at the carrier.
    pub gamma_ppb_per_g: [Option<f64>; 3],
    /// 1σ [ppb/g].
    pub sigma_ppb_per_g: [Option<f64>; 3],
    /// Whether the data observe each axis.
    pub observable: [bool; 3],
    /// Unexplained excitation RMS per axis [rad per Hz/(m/s²)].
    pub excitation_rms: [f64; 3],
    /// Condition number of the information matrix (null when singular).
    pub condition_number: Option<f64>,
    /// The estimate of every axis even when unobservable (for experts).
    pub gamma_raw_hz_per_mps2: [f64; 3],
    /// 1σ assuming white residuals (for comparison with the robust one).
    pub sigma_white_hz_per_mps2: [f64; 3],
    /// Cramér–Rao bound on each component [Hz/(m/s²)]: √(J⁻¹)_ii, J the Fisher
    /// information of the data under the noise spectrum fitted to the residuals
    /// (an AR model, see [`gls`]). The same for every method; `null` for an
    /// unobservable axis.
    pub crlb_hz_per_mps2: [Option<f64>; 3],
    /// Order of the AR model of the residual noise behind `crlb_hz_per_mps2`.
    pub noise_ar_order: usize,
    /// IMU time stamp minus true time applied to the IMU [s].
    pub imu_time_offset_s: f64,
    /// Whether `imu_time_offset_s` was estimated (false: assumed by the user).
    pub imu_time_offset_estimated: bool,
    /// 1σ of the estimated time offset [s] (when estimated).
    pub imu_time_offset_sigma_s: Option<f64>,
    /// The loop identification, when asked for.
    pub loop_identification: Option<search::LoopIdentification>,
    /// The Huber fit (with `robust = huber`): scale, threshold, epochs down-weighted.
    pub huber: Option<robust::HuberFit>,
    /// The verdict per axis (shaking frequency, sensitivity reached, advice).
    pub axes: [verdict::AxisVerdict; 3],
    /// Largest predicted g-induced phase error |φ_aᵀΓ̂| over the log [rad].
    pub predicted_peak_phase_err_rad: f64,
    /// The discriminator's linear range assumed for the check [rad] (π/4).
    pub discriminator_linear_range_rad: f64,
    /// RMS of the averaged phase error over the used epochs [rad].
    pub rms_before_rad: f64,
    /// RMS of φ − φ_aᵀΓ̂ over the same epochs [rad].
    pub rms_after_rad: f64,
    /// RMS of the g-induced part φ_aᵀΓ̂ [rad].
    pub rms_g_induced_rad: f64,
    /// Residual standard deviation [rad].
    pub residual_sigma_rad: f64,
    /// Epochs used by the estimator.
    pub epochs_used: u64,
    /// Epochs in the series (including gaps and warm-up).
    pub epochs_total: usize,
    /// Log interval [s].
    pub log_interval_s: f64,
    /// The estimate as it evolved (every `history_interval_s` after the warm-up).
    #[serde(skip)]
    pub history: Vec<HistoryPoint>,
    /// Loop updates per log epoch in the model.
    pub model_substeps: u32,
    /// Every setting used.
    pub settings: EstimateSettings,
}

/// The estimate at one epoch of the run (the paper's Fig. 4).
#[derive(Debug, Clone, Copy, Serialize)]
pub struct HistoryPoint {
    /// Epoch time [s].
    pub t_s: f64,
    /// Γ̂ so far [Hz/(m/s²)].
    pub gamma_hz_per_mps2: [f64; 3],
    /// Its 1σ so far, assuming white residuals [Hz/(m/s²)] (+∞ while unexcited).
    pub sigma_hz_per_mps2: [f64; 3],
}

/// Interval between two [`HistoryPoint`]s [s].
pub const HISTORY_INTERVAL_S: f64 = 0.25;

/// The per-epoch series a calibration needs (owned by the caller).
#[derive(Debug, Clone, Copy)]
pub struct EpochSeries<'a> {
    /// Uniform log interval [s].
    pub log_interval_s: f64,
    /// Epoch times [s].
    pub t_s: &'a [f64],
    /// Averaged phase error per epoch [rad]; `None` where no channel was present.
    pub phase_err_rad: &'a [Option<f64>],
    /// Specific force per epoch [m/s²] (IMU interpolated onto the epochs).
    pub accel_mps2: &'a [[f64; 3]],
    /// IMU time offset that was applied when interpolating [s].
    pub imu_time_offset_s: f64,
}

/// 1σ of Γ̂ per axis caused by IMU calibration errors [Hz/(m/s²)].
///
/// The IMU measures f_m = (I + E)·f with E = diag(s) + N (scale factors s,
/// misalignment N, zero diagonal), so the estimate is in the IMU's frame:
/// Δf = fᵀΓ = f_mᵀ(I + E)⁻ᵀΓ ⇒ Γ̂ ≈ Γ − EᵀΓ. With independent errors of 1σ
/// `scale_sigma` and `misalignment_sigma_rad`:
/// σ_i² = (σ_s·Γ_i)² + σ_m²·Σ_{j≠i} Γ_j².
pub fn imu_systematic_sigma(gamma: &[f64; 3], scale_sigma: f64, misalignment_sigma_rad: f64) -> [f64; 3] {
    let g2: [f64; 3] = gamma.map(|g| g * g);
    let total: f64 = g2.iter().sum();
    [0, 1, 2].map(|i| (scale_sigma * scale_sigma * g2[i] + misalignment_sigma_rad.powi(2) * (total - g2[i])).sqrt())
}

/// The regressor series φ_a for every epoch (the triad run over the whole series).
pub fn regressors(series: &EpochSeries, settings: &EstimateSettings) -> Result<Vec<[f64; 3]>, CalibError> {
    let mut model = build_model(series.log_interval_s, settings)?;
    let accel = model_input(series.accel_mps2, &model);
    Ok(accel.iter().map(|a| model.epoch(a)).collect())
}

/// One epoch of [`compensation_series`]: (φ, φ − φ_aᵀΓ̂) [rad], `None` where no
/// phase was measured.
pub type CompensatedEpoch = (Option<f64>, Option<f64>);

/// φ and φ − φ_aᵀΓ̂ per epoch as the estimator saw them: through the same
/// loop models, identical high-pass and gap handling (the paper's Fig. 5).
/// `None` where no phase was measured.
pub fn compensation_series(
    series: &EpochSeries,
    settings: &EstimateSettings,
    gamma_hz_per_mps2: &[f64; 3],
) -> Result<Vec<CompensatedEpoch>, CalibError> {
    let (fed, _) = search::batch_pass(series, settings)?;
    Ok(fed
        .iter()
        .map(|e| (e.phase_err_rad, e.phase_err_rad.map(|p| compensated_phase_rad(p, &e.phi_a, gamma_hz_per_mps2))))
        .collect())
}

/// What the loop models are fed: the specific force compensated for the
/// model's linear interpolation between epochs
/// ([`gsens_core::regressor::compensate_interpolation`]; without it Γ̂ is too
/// large by (ωh)²/12, 0.17 % at 0.9 Hz and 40 Hz), or the series as it is when
/// the loop runs at the log rate.
pub(crate) fn model_input<'a>(accel: &'a [[f64; 3]], model: &RegressorModel) -> std::borrow::Cow<'a, [[f64; 3]]> {
    let c = model.interpolation_compensation();
    if c == 0.0 {
        return std::borrow::Cow::Borrowed(accel);
    }
    let mut a = accel.to_vec();
    gsens_core::regressor::compensate_interpolation(&mut a, c);
    std::borrow::Cow::Owned(a)
}

pub(crate) fn build_model(log_interval_s: f64, settings: &EstimateSettings) -> Result<RegressorModel, CalibError> {
    if let Some(stage) = settings.gnss_sdr_loop {
        let pll = GnssSdrPll::new(stage).map_err(CalibError::Loop)?;
        if !pll.is_stable() {
            return Err(CalibError::UnstableAtInterval(stage.interval_s()));
        }
        return RegressorModel::with_loop(pll.into(), stage.interval_s(), log_interval_s, settings.logged_phase)
            .map_err(CalibError::Intervals);
    }
    let coeffs = settings.loop_spec.coeffs().map_err(CalibError::Loop)?;
    let loop_t = settings.loop_interval_s.unwrap_or(log_interval_s);
    if !coeffs.is_stable_at(loop_t) {
        return Err(CalibError::UnstableAtInterval(loop_t));
    }
    RegressorModel::new(coeffs, loop_t, log_interval_s, settings.logged_phase).map_err(CalibError::Intervals)
}

/// Runs the configured estimator over the series and assembles the result.
pub fn calibrate(series: &EpochSeries, settings: &EstimateSettings) -> Result<Calibration, CalibError> {
    let n = series.accel_mps2.len();
    if series.phase_err_rad.len() != n || series.t_s.len() != n {
        return Err(CalibError::Input("phase and specific-force series differ in length".into()));
    }
    let model = build_model(series.log_interval_s, settings)?;
    let substeps = model.substeps();
    // The model is fed the specific force compensated for its interpolation between epochs.
    let accel = model_input(series.accel_mps2, &model);
    let model_series = EpochSeries { accel_mps2: &accel, ..*series };
    let skip = (settings.warmup_s / series.log_interval_s).ceil().max(0.0) as u64;
    let (hp, t) = (settings.highpass_hz, series.log_interval_s);
    let (estimate, fed, batch, history) = match settings.method {
        Method::Batch | Method::Gls => {
            run(Calibrator::new(model, BatchLeastSquares::new(), skip, hp, t), &model_series)
        }
        Method::Rls { lambda } => run(
            Calibrator::new(model, RecursiveLeastSquares::new(lambda, RecursiveLeastSquares::DEFAULT_P0), skip, hp, t),
            &model_series,
        ),
        Method::Gradient { gain_k } => {
            run(Calibrator::new(model, GradientObserver::new(gain_k, t), skip, hp, t), &model_series)
        }
    };
    if batch.normal_equations().n < 10 {
        return Err(CalibError::Input(format!(
            "only {} epochs with a phase measurement after the {} s warm-up; need at least 10",
            batch.normal_equations().n,
            settings.warmup_s
        )));
    }
    // The noise model, the Cramér–Rao bound and the GLS estimate (all methods get the bound).
    let noise_fit = gls_pass(&fed, settings, series.log_interval_s);
    let estimate = match (&settings.method, &noise_fit) {
        (Method::Gls, Some(g)) => g.estimate,
        _ => estimate,
    };
    let huber = huber_pass(&fed, &estimate, settings, series.log_interval_s)?;
    let estimate = match &huber {
        Some(h) => GammaEstimate {
            gamma_hz_per_mps2: h.gamma_hz_per_mps2,
            covariance: h.covariance_white,
            residual_variance_rad2: h.scale_rad * h.scale_rad,
            epochs: h.epochs as u64,
        },
        None => estimate,
    };
    let gamma = estimate.gamma_hz_per_mps2;

    // Residuals over the used epochs (high-passed), for the robust covariance and the RMS.
    let used: Vec<&FedEpoch> = fed.iter().filter(|e| e.used).collect();
    let mut used_phi_a = Vec::with_capacity(used.len());
    let mut resid = Vec::with_capacity(used.len());
    let (mut ss_before, mut ss_after, mut ss_g) = (0.0, 0.0, 0.0);
    for e in &used {
        let phi = e.phase_err_rad.unwrap_or(0.0);
        let r = compensated_phase_rad(phi, &e.phi_a, &gamma);
        ss_before += phi * phi;
        ss_after += r * r;
        ss_g += (phi - r) * (phi - r);
        used_phi_a.push(e.phi_a);
        resid.push(r);
    }
    let m = used.len().max(1) as f64;
    let max_lag = (settings.hac_lag_s / series.log_interval_s).round() as usize;
    let hac = hac_covariance(&used_phi_a, &resid, max_lag);
    // The robust/white variance ratio of the batch solution scales the chosen
    // estimator's own covariance (the same residual colour affects them all).
    let white_batch = batch.estimate();
    let obs = assess(batch.normal_equations(), &estimate, &settings.criteria);
    let mut sigma = [None; 3];
    let mut sigma_stat = [None; 3];
    let mut sigma_imu = [None; 3];
    let sys = imu_systematic_sigma(&gamma, settings.imu_scale_sigma, settings.imu_misalignment_sigma_rad);
    let mut sigma_white = [0.0; 3];
    let mut gamma_out = [None; 3];
    for i in 0..3 {
        let own = estimate.covariance[i][i];
        let ratio = match (&settings.method, &noise_fit) {
            // Huber: its own sandwich, with the autocorrelation terms.
            _ if huber.is_some() => {
                huber.as_ref().map_or(1.0, |h| if own > 0.0 { (h.covariance[i][i] / own).max(1.0) } else { 1.0 })
            }
            // GLS: what colour its AR model missed, from its own prewhitened residuals.
            (Method::Gls, Some(g)) if own > 0.0 => (g.robust_covariance.map_or(own, |c| c[i][i]) / own).max(1.0),
            _ if white_batch.covariance[i][i] > 0.0 => (hac[i][i] / white_batch.covariance[i][i]).max(1.0),
            _ => 1.0,
        };
        sigma_white[i] = own.max(0.0).sqrt();
        if obs.observable[i] {
            let stat = (own * ratio).sqrt();
            sigma_stat[i] = Some(stat);
            sigma_imu[i] = Some(sys[i]);
            sigma[i] = Some(stat.hypot(sys[i]));
            gamma_out[i] = Some(gamma[i]);
        }
    }
    let ppb = |x: Option<f64>| x.map(|v| hz_per_mps2_to_ppb_per_g(v, settings.carrier_hz));
    let coeffs = settings.loop_spec.coeffs().map_err(CalibError::Loop)?;
    let loop_t = settings.loop_interval_s.unwrap_or(series.log_interval_s);
    let axes = verdict::axis_verdicts(
        series.accel_mps2,
        series.log_interval_s,
        &coeffs,
        loop_t,
        obs.observable,
        obs.excitation_rms,
    );
    let peak_phase = fed.iter().map(|e| compensated_phase_rad(0.0, &e.phi_a, &gamma).abs()).fold(0.0, f64::max);
    Ok(Calibration {
        gamma_hz_per_mps2: gamma_out,
        sigma_hz_per_mps2: sigma,
        sigma_statistical_hz_per_mps2: sigma_stat,
        sigma_imu_hz_per_mps2: sigma_imu,
        gamma_ppb_per_g: gamma_out.map(ppb),
        sigma_ppb_per_g: sigma.map(ppb),
        observable: obs.observable,
        excitation_rms: obs.excitation_rms,
        condition_number: obs.condition_number.is_finite().then_some(obs.condition_number),
        gamma_raw_hz_per_mps2: gamma,
        sigma_white_hz_per_mps2: sigma_white,
        crlb_hz_per_mps2: [0, 1, 2].map(|i| {
            let c = noise_fit.as_ref().map(|g| g.crlb_hz_per_mps2()[i]);
            c.filter(|c| c.is_finite() && obs.observable[i])
        }),
        noise_ar_order: noise_fit.as_ref().map_or(0, |g| g.noise.order()),
        imu_time_offset_s: series.imu_time_offset_s,
        imu_time_offset_estimated: false,
        imu_time_offset_sigma_s: None,
        loop_identification: None,
        huber,
        axes,
        predicted_peak_phase_err_rad: peak_phase,
        discriminator_linear_range_rad: verdict::DISCRIMINATOR_LINEAR_RANGE_RAD,
        rms_before_rad: (ss_before / m).sqrt(),
        rms_after_rad: (ss_after / m).sqrt(),
        rms_g_induced_rad: (ss_g / m).sqrt(),
        residual_sigma_rad: estimate.residual_variance_rad2.sqrt(),
        epochs_used: batch.normal_equations().n,
        epochs_total: n,
        log_interval_s: series.log_interval_s,
        history,
        model_substeps: substeps,
        settings: *settings,
    })
}

/// Huber IRLS over the used epochs, from the batch estimate (with `robust = huber`).
fn huber_pass(
    fed: &[FedEpoch],
    estimate: &GammaEstimate,
    settings: &EstimateSettings,
    log_interval_s: f64,
) -> Result<Option<robust::HuberFit>, CalibError> {
    if settings.robust == Robust::None {
        return Ok(None);
    }
    if settings.method != Method::Batch {
        // The recursive estimators have no second pass; GLS would need a robust
        // AR fit and IRLS on the prewhitened series (an outlier spreads over the
        // AR filter's length there).
        return Err(CalibError::Input(format!(
            "robust (Huber) estimation works with the batch method, not {:?}",
            settings.method
        )));
    }
    let (phase, phi_a): (Vec<f64>, Vec<[f64; 3]>) =
        fed.iter().filter(|e| e.used).map(|e| (e.phase_err_rad.unwrap_or(0.0), e.phi_a)).unzip();
    let max_lag = (settings.hac_lag_s / log_interval_s).round() as usize;
    Ok(robust::huber_irls(&phase, &phi_a, estimate.gamma_hz_per_mps2, gsens_core::robust::HuberWeights::K_95, max_lag))
}

/// GLS over the used epochs of a pass (their contiguous runs are the segments).
fn gls_pass(fed: &[FedEpoch], settings: &EstimateSettings, log_interval_s: f64) -> Option<gls::GlsFit> {
    let phase: Vec<f64> = fed.iter().map(|e| e.phase_err_rad.unwrap_or(0.0)).collect();
    let phi_a: Vec<[f64; 3]> = fed.iter().map(|e| e.phi_a).collect();
    let segments = gls::segments_of(fed.iter().map(|e| e.used));
    let gls_settings = gls::GlsSettings {
        // The robust covariance only where it is used: the GLS method's σ.
        hac_max_lag: (settings.method == Method::Gls).then(|| (settings.hac_lag_s / log_interval_s).round() as usize),
        max_ar_order: (gls::MAX_AR_SPAN_S / log_interval_s).ceil() as usize,
        ..gls::GlsSettings::default()
    };
    gls::gls(&phase, &phi_a, &segments, &gls_settings)
}

/// Runs an estimator and, alongside, a batch accumulator (for the
/// observability verdict and the robust covariance) over the series.
fn run<E: GammaEstimator>(
    mut cal: Calibrator<E>,
    series: &EpochSeries,
) -> (GammaEstimate, Vec<FedEpoch>, BatchLeastSquares, Vec<HistoryPoint>) {
    let mut batch = BatchLeastSquares::new();
    let every = ((HISTORY_INTERVAL_S / series.log_interval_s).round() as usize).max(1);
    let mut history = Vec::new();
    let mut fed = Vec::with_capacity(series.accel_mps2.len());
    for (k, (a, p)) in series.accel_mps2.iter().zip(series.phase_err_rad).enumerate() {
        let e = cal.feed(a, *p);
        if e.used {
            batch.update(e.phase_err_rad.unwrap_or(0.0), &e.phi_a);
        }
        fed.push(e);
        if k % every == 0 && batch.normal_equations().n >= 3 {
            let est = cal.estimate();
            history.push(HistoryPoint {
                t_s: series.t_s[k],
                gamma_hz_per_mps2: est.gamma_hz_per_mps2,
                sigma_hz_per_mps2: est.sigma_hz_per_mps2(),
            });
        }
    }
    (cal.estimate(), fed, batch, history)
}
