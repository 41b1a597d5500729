//! The estimation stage: an epoch series and settings in, a [`Calibration`] out.

use crate::result::{Calibration, HistoryPoint};
use crate::settings::{EstimateSettings, Method, Robust};
use crate::{CalibError, gls, robust, search, verdict};
use gsens_core::FedEpoch;
use gsens_core::LoopError;
use gsens_core::RegressorModel;
use gsens_core::assess;
use gsens_core::units::hz_per_mps2_to_ppb_per_g;
use gsens_core::{BatchLeastSquares, GammaEstimate, GradientObserver, RecursiveLeastSquares, hac_covariance};
use gsens_core::{Calibrator, GammaEstimator, compensated_phase_rad};

/// Interval between two [`HistoryPoint`]s \[s\].
pub const HISTORY_INTERVAL_S: f64 = 0.25;

/// The per-epoch series a calibration needs (owned by the caller).
#[derive(Debug, Clone, Copy)]
pub struct EpochSeries<'a> {
    /// Uniform log interval \[s\].
    pub log_interval_s: f64,
    /// Epoch times \[s\].
    pub t_s: &'a [f64],
    /// Averaged phase error per epoch \[rad\]; `None` where no channel was present.
    pub phase_err_rad: &'a [Option<f64>],
    /// Specific force per epoch \[m/s²\] (IMU interpolated onto the epochs).
    pub accel_mps2: &'a [[f64; 3]],
    /// IMU time offset that was applied when interpolating \[s\].
    pub imu_time_offset_s: f64,
}

/// 1σ of Γ̂ per axis caused by IMU calibration errors \[Hz/(m/s²)\].
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

/// One epoch of [`compensation_series`]: (φ, φ − φ_aᵀΓ̂) \[rad\], `None` where no
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
/// ([`gsens_core::compensate_interpolation`]; without it Γ̂ is too
/// large by (ωh)²/12, 0.17 % at 0.9 Hz and 40 Hz), or the series as it is when
/// the loop runs at the log rate.
pub(crate) fn model_input<'a>(accel: &'a [[f64; 3]], model: &RegressorModel) -> std::borrow::Cow<'a, [[f64; 3]]> {
    let c = model.interpolation_compensation();
    if c == 0.0 {
        return std::borrow::Cow::Borrowed(accel);
    }
    let mut a = accel.to_vec();
    gsens_core::compensate_interpolation(&mut a, c);
    std::borrow::Cow::Owned(a)
}

/// Epochs left out at the start while the model's start-up transient dies
/// out: ⌈warm-up / log interval⌉ ([`gsens_core::warmup_epochs`]).
pub fn warmup_epochs(settings: &EstimateSettings, log_interval_s: f64) -> u64 {
    gsens_core::warmup_epochs(settings.warmup_s, log_interval_s)
}

/// The batch path's estimator streamed, one epoch at a time: the same
/// regressor model (the receiver loop at the log interval), warm-up, high-pass and batch least
/// squares, with the interpolation prefilter applied one epoch late
/// ([`gsens_core::PrefilteredCalibrator`]). Fed the same epoch series it ends
/// at the batch pass's least-squares Γ̂ (exactly, up to rounding); what it
/// lacks is what needs the whole series: the screening, the time-offset
/// search, the noise model and the robust covariance (its covariance is the
/// white-noise one). Solve it with [`gsens_core::solve_in_observable_axes`].
pub fn streaming_calibrator(
    settings: &EstimateSettings,
    log_interval_s: f64,
) -> Result<gsens_core::PrefilteredCalibrator<BatchLeastSquares>, CalibError> {
    settings.validate()?;
    let model = build_model(log_interval_s, settings)?;
    let skip = warmup_epochs(settings, log_interval_s);
    Ok(gsens_core::PrefilteredCalibrator::new(Calibrator::new(
        model,
        BatchLeastSquares::new(),
        skip,
        settings.highpass_hz,
        log_interval_s,
    )))
}

/// The regressor triad for the receiver loop at this log interval (checked:
/// a valid, stable loop whose interval divides the log's).
pub(crate) fn build_model(log_interval_s: f64, settings: &EstimateSettings) -> Result<RegressorModel, CalibError> {
    let model_loop = settings.loop_at(log_interval_s);
    let runnable = model_loop.runnable().map_err(|e| match e {
        LoopError::UnstableAtInterval => {
            CalibError::UnstableAtInterval(model_loop.interval_s().unwrap_or(log_interval_s))
        }
        other => CalibError::Loop(other),
    })?;
    let loop_t = model_loop.interval_s().unwrap_or(log_interval_s);
    RegressorModel::with_loop(runnable, loop_t, log_interval_s, settings.logged_phase).map_err(CalibError::Intervals)
}

/// Runs the configured estimator over the series and assembles the result.
///
/// An axis the data cannot observe leaves the solve: its column of φ_a,
/// however small, is still correlated with the shaken axes' and would
/// inflate their σ (six-fold on a session shaken along x alone). The
/// estimate is then made again with that axis's specific force set to zero,
/// and the unobservable axis keeps the verdict and raw estimate of the first
/// pass.
pub fn calibrate(series: &EpochSeries, settings: &EstimateSettings) -> Result<Calibration, CalibError> {
    let (all, ne) = calibrate_all_axes(series, settings)?;
    let in_solve = gsens_core::axes_in_solve(&ne, &settings.criteria);
    let unobservable: Vec<usize> = (0..3).filter(|&i| !in_solve[i]).collect();
    if unobservable.is_empty() || unobservable.len() == 3 {
        return Ok(all);
    }
    let masked: Vec<[f64; 3]> = series
        .accel_mps2
        .iter()
        .map(|a| {
            let mut a = *a;
            for &i in &unobservable {
                a[i] = 0.0;
            }
            a
        })
        .collect();
    let (mut c, _) = calibrate_all_axes(&EpochSeries { accel_mps2: &masked, ..*series }, settings)?;
    for &i in &unobservable {
        c.make_unobservable(i, "");
        c.excitation_rms[i] = all.excitation_rms[i];
        c.gamma_raw_hz_per_mps2[i] = all.gamma_raw_hz_per_mps2[i];
        c.sigma_white_hz_per_mps2[i] = all.sigma_white_hz_per_mps2[i];
        c.axes[i] = all.axes[i].clone();
    }
    c.condition_number = all.condition_number;
    Ok(c)
}

/// [`calibrate`] with every axis in the solve, and the batch pass's normal
/// equations (which decide the axes that stay in it).
fn calibrate_all_axes(
    series: &EpochSeries,
    settings: &EstimateSettings,
) -> Result<(Calibration, gsens_core::NormalEquations), CalibError> {
    settings.validate()?;
    let n = series.accel_mps2.len();
    if series.phase_err_rad.len() != n || series.t_s.len() != n {
        return Err(CalibError::LengthMismatch {
            t_s: series.t_s.len(),
            phase_err_rad: series.phase_err_rad.len(),
            accel_mps2: n,
        });
    }
    let model = build_model(series.log_interval_s, settings)?;
    let substeps = model.substeps();
    // The model is fed the specific force compensated for its interpolation between epochs.
    let accel = model_input(series.accel_mps2, &model);
    let model_series = EpochSeries { accel_mps2: &accel, ..*series };
    let skip = warmup_epochs(settings, series.log_interval_s);
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
        return Err(CalibError::TooFewEpochs { epochs: batch.normal_equations().n, warmup_s: settings.warmup_s });
    }
    // The noise model, the Cramér–Rao bound and the GLS estimate (all methods
    // get the bound), while the estimate's history and the regressors'
    // transforms for the robust covariance (neither needs the model) are
    // computed as separate tasks alongside it.
    let segments = gls::segments_of(fed.iter().map(|e| e.used));
    let columns: Vec<Vec<f64>> = (0..3).map(|i| fed.iter().map(|e| e.phi_a[i]).collect()).collect();
    let (noise_fit, (history, spectra)) = rayon::join(
        || gls_pass(&fed, &segments, settings, series.log_interval_s),
        || rayon::join(history, || gls::ColumnSpectra::new(&columns, &segments)),
    );
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
    // The least-squares covariance under the residuals' own noise: the
    // sandwich with the AR model fitted for the bound (exact in the model),
    // or Newey–West where no model could be fitted.
    let robust_ls = match &noise_fit {
        Some(g) => {
            let m = spectra.middle(&g.noise);
            let middle = [0, 1, 2].map(|i| [0, 1, 2].map(|j| m[(i, j)]));
            sandwich(&batch.normal_equations().pseudo_inverse(gsens_core::RANK_TOL).0, &middle)
        }
        None => {
            let max_lag = (settings.hac_lag_s / series.log_interval_s).round() as usize;
            hac_covariance(&used_phi_a, &resid, max_lag)
        }
    };
    // The robust/white variance ratio of the batch solution scales the chosen
    // estimator's own covariance (the same residual colour affects them all).
    let white_batch = batch.estimate();
    let obs = assess(batch.normal_equations(), &estimate, &settings.criteria);
    let mut observable = [false; 3];
    let mut sigma = [None; 3];
    let mut sigma_stat = [None; 3];
    let mut sigma_imu = [None; 3];
    let sys = imu_systematic_sigma(&gamma, settings.imu_scale_sigma, settings.imu_misalignment_sigma_rad);
    let mut sigma_white = [0.0; 3];
    let mut gamma_out = [None; 3];
    let mut ratios = [1.0; 3];
    for i in 0..3 {
        let own = estimate.covariance[i][i];
        let ratio = match (&settings.method, &noise_fit) {
            // Huber: its own sandwich, with the autocorrelation terms.
            _ if huber.is_some() => {
                huber.as_ref().map_or(1.0, |h| if own > 0.0 { (h.covariance[i][i] / own).max(1.0) } else { 1.0 })
            }
            // GLS: what colour its AR model missed, from its own prewhitened residuals.
            (Method::Gls, Some(g)) if own > 0.0 => (g.robust_covariance.map_or(own, |c| c[i][i]) / own).max(1.0),
            _ if white_batch.covariance[i][i] > 0.0 => (robust_ls[i][i] / white_batch.covariance[i][i]).max(1.0),
            _ => 1.0,
        };
        ratios[i] = ratio;
        sigma_white[i] = own.max(0.0).sqrt();
        // An axis is observable only with a finite estimate and σ (a
        // diverged estimator's NaN is not a number to present).
        let finite = gamma[i].is_finite() && (own * ratio).is_finite() && sys[i].is_finite();
        observable[i] = obs.observable[i] && finite;
        if observable[i] {
            let stat = (own * ratio).sqrt();
            sigma_stat[i] = Some(stat);
            sigma_imu[i] = Some(sys[i]);
            sigma[i] = Some(stat.hypot(sys[i]));
            gamma_out[i] = Some(gamma[i]);
        }
    }
    let covariance = [0, 1, 2].map(|i| {
        [0, 1, 2].map(|j| {
            let stat = estimate.covariance[i][j] * (ratios[i] * ratios[j]).sqrt();
            let imu = if i == j { sys[i] * sys[i] } else { 0.0 };
            (observable[i] && observable[j]).then_some(stat + imu)
        })
    });
    let ppb = |x: Option<f64>| x.map(|v| hz_per_mps2_to_ppb_per_g(v, settings.carrier_hz));
    let loop_used = settings.loop_at(series.log_interval_s);
    let axes = verdict::axis_verdicts(
        series.accel_mps2,
        series.log_interval_s,
        &loop_used,
        observable,
        obs.excitation_rms,
        settings.criteria.min_excitation_rms,
    );
    // σ exactly 0 is no uncertainty but no information (the estimator's
    // covariance dropped the axis, e.g. the pseudo-inverse's cut).
    let no_information: Vec<usize> = (0..3).filter(|&i| observable[i] && sigma_stat[i] == Some(0.0)).collect();
    let peak_phase = fed.iter().map(|e| compensated_phase_rad(0.0, &e.phi_a, &gamma).abs()).fold(0.0, f64::max);
    let normal = *batch.normal_equations();
    let mut calibration = Calibration {
        gamma_hz_per_mps2: gamma_out,
        sigma_hz_per_mps2: sigma,
        sigma_statistical_hz_per_mps2: sigma_stat,
        sigma_imu_hz_per_mps2: sigma_imu,
        gamma_ppb_per_g: gamma_out.map(ppb),
        sigma_ppb_per_g: sigma.map(ppb),
        observable,
        excitation_rms: obs.excitation_rms,
        covariance_hz_per_mps2_sq: covariance,
        condition_number: obs.condition_number.is_finite().then_some(obs.condition_number),
        gamma_raw_hz_per_mps2: gamma,
        sigma_white_hz_per_mps2: sigma_white.map(|s| s.is_finite().then_some(s)),
        crlb_hz_per_mps2: [0, 1, 2].map(|i| {
            let c = noise_fit.as_ref().map(|g| g.crlb_hz_per_mps2()[i]);
            c.filter(|c| c.is_finite() && observable[i])
        }),
        noise_ar_order: noise_fit.as_ref().map_or(0, |g| g.noise.order()),
        imu_time_offset_s: series.imu_time_offset_s,
        imu_time_offset_estimated: false,
        imu_time_offset_sigma_s: None,
        joint_fit: None,
        huber,
        axes,
        predicted_peak_phase_err_rad: peak_phase,
        discriminator_linear_range_rad: settings.discriminator.unambiguous_range_rad(),
        rms_before_rad: (ss_before / m).sqrt(),
        rms_after_rad: (ss_after / m).sqrt(),
        rms_g_induced_rad: (ss_g / m).sqrt(),
        residual_sigma_rad: estimate.residual_variance_rad2.sqrt(),
        epochs_used: batch.normal_equations().n,
        epochs_total: n,
        log_interval_s: series.log_interval_s,
        history,
        model_substeps: substeps,
        loop_used,
        settings: *settings,
    };
    for i in no_information {
        calibration.make_unobservable(i, "its σ came out 0: the estimator's covariance holds no information on it");
    }
    Ok((calibration, normal))
}

/// P·M·P for a symmetric 3×3 P (nalgebra's) and M.
fn sandwich(p: &nalgebra::Matrix3<f64>, m: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let m = nalgebra::Matrix3::from_fn(|i, j| m[i][j]);
    let c = p * m * p;
    [0, 1, 2].map(|i| [0, 1, 2].map(|j| c[(i, j)]))
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
    let (phase, phi_a): (Vec<f64>, Vec<[f64; 3]>) =
        fed.iter().filter(|e| e.used).map(|e| (e.phase_err_rad.unwrap_or(0.0), e.phi_a)).unzip();
    let max_lag = (settings.hac_lag_s / log_interval_s).round() as usize;
    Ok(robust::huber_irls(&phase, &phi_a, estimate.gamma_hz_per_mps2, gsens_core::HuberWeights::K_95, max_lag))
}

/// GLS over the used epochs of a pass, `segments` their contiguous runs.
fn gls_pass(
    fed: &[FedEpoch],
    segments: &[core::ops::Range<usize>],
    settings: &EstimateSettings,
    log_interval_s: f64,
) -> Option<gls::GlsFit> {
    let phase: Vec<f64> = fed.iter().map(|e| e.phase_err_rad.unwrap_or(0.0)).collect();
    let phi_a: Vec<[f64; 3]> = fed.iter().map(|e| e.phi_a).collect();
    let gls_settings = gls::GlsSettings {
        // The robust covariance only where it is used: the GLS method's σ.
        hac_max_lag: (settings.method == Method::Gls).then(|| (settings.hac_lag_s / log_interval_s).round() as usize),
        max_ar_order: (gls::MAX_AR_SPAN_S / log_interval_s).ceil() as usize,
        ..gls::GlsSettings::default()
    };
    gls::gls(&phase, &phi_a, segments, &gls_settings)
}

/// The estimate's history, to be computed: every [`HISTORY_INTERVAL_S`] the
/// estimator as it stood then, each solved when asked for (in parallel).
type History<'a> = Box<dyn FnOnce() -> Vec<HistoryPoint> + Send + 'a>;

/// Runs an estimator and, alongside, a batch accumulator (for the
/// observability verdict and the robust covariance) over the series.
fn run<'a, E: GammaEstimator + Copy + Send + Sync + 'a>(
    mut cal: Calibrator<E>,
    series: &EpochSeries<'a>,
) -> (GammaEstimate, Vec<FedEpoch>, BatchLeastSquares, History<'a>) {
    use rayon::prelude::*;
    let mut batch = BatchLeastSquares::new();
    let every = ((HISTORY_INTERVAL_S / series.log_interval_s).round() as usize).max(1);
    // The estimator's state is a few numbers; solving it (an eigen-
    // decomposition for the least squares) is what costs.
    let mut states: Vec<(f64, E)> = Vec::new();
    let mut fed = Vec::with_capacity(series.accel_mps2.len());
    for (k, (a, p)) in series.accel_mps2.iter().zip(series.phase_err_rad).enumerate() {
        let e = cal.feed(a, *p);
        if e.used {
            batch.update(e.phase_err_rad.unwrap_or(0.0), &e.phi_a);
        }
        fed.push(e);
        if k % every == 0 && batch.normal_equations().n >= 3 {
            states.push((series.t_s[k], *cal.estimator()));
        }
    }
    let history: History<'a> = Box::new(move || {
        states
            .par_iter()
            .map(|(t_s, state)| {
                let est = state.estimate();
                HistoryPoint {
                    t_s: *t_s,
                    gamma_hz_per_mps2: est.gamma_hz_per_mps2,
                    sigma_hz_per_mps2: est.sigma_hz_per_mps2(),
                }
            })
            .collect()
    });
    (cal.estimate(), fed, batch, history)
}
