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

#[cfg(test)]
impl<'a> EpochSeries<'a> {
    /// Epochs `log_interval_s` apart at `t_s`, the IMU read with no time offset.
    pub(crate) fn without_offset(
        log_interval_s: f64,
        t_s: &'a [f64],
        phase_err_rad: &'a [Option<f64>],
        accel_mps2: &'a [[f64; 3]],
    ) -> Self {
        EpochSeries { log_interval_s, t_s, phase_err_rad, accel_mps2, imu_time_offset_s: 0.0 }
    }
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
    let (estimate, fed, batch, history) = run_method(model, series, settings);
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
    let residuals = Residuals::of(&fed, &estimate.gamma_hz_per_mps2);
    let robust_ls = match &noise_fit {
        Some(g) => {
            let m = spectra.middle(&g.noise);
            let middle = [0, 1, 2].map(|i| [0, 1, 2].map(|j| m[(i, j)]));
            sandwich(&batch.normal_equations().pseudo_inverse(gsens_core::RANK_TOL).0, &middle)
        }
        None => {
            let max_lag = (settings.hac_lag_s / series.log_interval_s).round() as usize;
            hac_covariance(&residuals.phi_a, &residuals.resid, max_lag)
        }
    };
    let obs = assess(batch.normal_equations(), &estimate, &settings.criteria);
    let fits = Fits { estimate: &estimate, batch: &batch, noise_fit: noise_fit.as_ref(), huber: huber.as_ref() };
    let u = Uncertainty::of(&fits, &robust_ls, &obs, settings);
    let parts = CalibrationParts { estimate, obs, fed, normal: *batch.normal_equations(), noise_fit, huber, history };
    let calibration = assemble(series, settings, parts, u, residuals, substeps);
    Ok((calibration, *batch.normal_equations()))
}

/// Runs `settings.method` (GLS starts from the batch pass) from `model`
/// over `series`, the model fed the specific force compensated for its
/// interpolation between epochs.
fn run_method(
    model: RegressorModel,
    series: &EpochSeries,
    settings: &EstimateSettings,
) -> (GammaEstimate, Vec<FedEpoch>, BatchLeastSquares, History<'static>) {
    let accel = model_input(series.accel_mps2, &model);
    let model_series = EpochSeries { accel_mps2: &accel, ..*series };
    let skip = warmup_epochs(settings, series.log_interval_s);
    let (hp, t) = (settings.highpass_hz, series.log_interval_s);
    match settings.method {
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
    }
}

/// The residuals over the used epochs (high-passed) of an estimate Γ̂, for
/// the robust covariance and the RMS.
struct Residuals {
    /// The used epochs' φ_a.
    phi_a: Vec<[f64; 3]>,
    /// Their compensated phase φ − φ_aᵀΓ̂ \[rad\].
    resid: Vec<f64>,
    /// The phase's RMS before and after compensation, and of the g-induced part φ_aᵀΓ̂ \[rad\].
    rms_before_rad: f64,
    rms_after_rad: f64,
    rms_g_induced_rad: f64,
}

impl Residuals {
    fn of(fed: &[FedEpoch], gamma: &[f64; 3]) -> Self {
        let used: Vec<&FedEpoch> = fed.iter().filter(|e| e.used).collect();
        let mut phi_a = Vec::with_capacity(used.len());
        let mut resid = Vec::with_capacity(used.len());
        let (mut ss_before, mut ss_after, mut ss_g) = (0.0, 0.0, 0.0);
        for e in &used {
            let phi = e.phase_err_rad.unwrap_or(0.0);
            let r = compensated_phase_rad(phi, &e.phi_a, gamma);
            ss_before += phi * phi;
            ss_after += r * r;
            ss_g += (phi - r) * (phi - r);
            phi_a.push(e.phi_a);
            resid.push(r);
        }
        let m = used.len().max(1) as f64;
        Residuals {
            phi_a,
            resid,
            rms_before_rad: (ss_before / m).sqrt(),
            rms_after_rad: (ss_after / m).sqrt(),
            rms_g_induced_rad: (ss_g / m).sqrt(),
        }
    }
}

/// What compensating with a Γ̂ made elsewhere does to the session's phase
/// error: the RMS figures of [`Residuals`] and the predicted peak
/// |φ_aᵀΓ̂| \[rad\].
pub(crate) struct ResidualFigures {
    pub(crate) rms_before_rad: f64,
    pub(crate) rms_after_rad: f64,
    pub(crate) rms_g_induced_rad: f64,
    pub(crate) peak_phase_err_rad: f64,
}

/// [`ResidualFigures`] of `gamma` over the epochs the estimator uses, through
/// the loop model of `settings` (one batch pass of the regressors).
pub(crate) fn residual_figures(
    series: &EpochSeries,
    settings: &EstimateSettings,
    gamma: &[f64; 3],
) -> Result<ResidualFigures, CalibError> {
    let (fed, _) = search::batch_pass(series, settings)?;
    let r = Residuals::of(&fed, gamma);
    Ok(ResidualFigures {
        rms_before_rad: r.rms_before_rad,
        rms_after_rad: r.rms_after_rad,
        rms_g_induced_rad: r.rms_g_induced_rad,
        peak_phase_err_rad: peak_phase_err_rad(&fed, gamma),
    })
}

/// The largest predicted g-induced phase error |φ_aᵀΓ̂| over every epoch \[rad\].
fn peak_phase_err_rad(fed: &[FedEpoch], gamma: &[f64; 3]) -> f64 {
    fed.iter().map(|e| compensated_phase_rad(0.0, &e.phi_a, gamma).abs()).fold(0.0, f64::max)
}

/// The fits an estimate's uncertainty draws on.
struct Fits<'a> {
    /// The estimate given (the method's, GLS's or Huber's).
    estimate: &'a GammaEstimate,
    /// The batch least squares over the same epochs.
    batch: &'a BatchLeastSquares,
    noise_fit: Option<&'a gls::GlsFit>,
    huber: Option<&'a robust::HuberFit>,
}

/// Per axis: Γ̂ and its σ where observable, and the covariance.
struct Uncertainty {
    observable: [bool; 3],
    gamma: [Option<f64>; 3],
    sigma: [Option<f64>; 3],
    sigma_stat: [Option<f64>; 3],
    sigma_imu: [Option<f64>; 3],
    sigma_white: [f64; 3],
    covariance: [[Option<f64>; 3]; 3],
    /// The axes whose statistical σ came out exactly 0.
    no_information: Vec<usize>,
}

impl Uncertainty {
    /// The estimator's own covariance scaled per axis by the robust over the
    /// white variance (the same residual colour affects every estimator):
    /// Huber's own sandwich, GLS's prewhitened residuals, or the batch
    /// solution's `robust_ls` over its white covariance; combined with the
    /// IMU's systematic σ. An axis is observable only with a finite
    /// estimate and σ (a diverged estimator's NaN is not a number to present).
    fn of(f: &Fits, robust_ls: &[[f64; 3]; 3], obs: &gsens_core::Observability, settings: &EstimateSettings) -> Self {
        let (estimate, gamma) = (f.estimate, f.estimate.gamma_hz_per_mps2);
        let white_batch = f.batch.estimate();
        let sys = imu_systematic_sigma(&gamma, settings.imu_scale_sigma, settings.imu_misalignment_sigma_rad);
        let mut u = Uncertainty {
            observable: [false; 3],
            gamma: [None; 3],
            sigma: [None; 3],
            sigma_stat: [None; 3],
            sigma_imu: [None; 3],
            sigma_white: [0.0; 3],
            covariance: [[None; 3]; 3],
            no_information: Vec::new(),
        };
        let mut ratios = [1.0; 3];
        for i in 0..3 {
            let own = estimate.covariance[i][i];
            let ratio = match (&settings.method, f.noise_fit) {
                _ if f.huber.is_some() => {
                    f.huber.map_or(1.0, |h| if own > 0.0 { (h.covariance[i][i] / own).max(1.0) } else { 1.0 })
                }
                (Method::Gls, Some(g)) if own > 0.0 => (g.robust_covariance.map_or(own, |c| c[i][i]) / own).max(1.0),
                _ if white_batch.covariance[i][i] > 0.0 => (robust_ls[i][i] / white_batch.covariance[i][i]).max(1.0),
                _ => 1.0,
            };
            ratios[i] = ratio;
            u.sigma_white[i] = own.max(0.0).sqrt();
            let finite = gamma[i].is_finite() && (own * ratio).is_finite() && sys[i].is_finite();
            u.observable[i] = obs.observable[i] && finite;
            if u.observable[i] {
                let stat = (own * ratio).sqrt();
                u.sigma_stat[i] = Some(stat);
                u.sigma_imu[i] = Some(sys[i]);
                u.sigma[i] = Some(stat.hypot(sys[i]));
                u.gamma[i] = Some(gamma[i]);
            }
        }
        let observable = u.observable;
        u.covariance = [0, 1, 2].map(|i| {
            [0, 1, 2].map(|j| {
                let stat = estimate.covariance[i][j] * (ratios[i] * ratios[j]).sqrt();
                let imu = if i == j { sys[i] * sys[i] } else { 0.0 };
                (observable[i] && observable[j]).then_some(stat + imu)
            })
        });
        // σ exactly 0 is no uncertainty but no information (the estimator's
        // covariance dropped the axis, e.g. the pseudo-inverse's cut).
        u.no_information = (0..3).filter(|&i| observable[i] && u.sigma_stat[i] == Some(0.0)).collect();
        u
    }
}

/// What a [`Calibration`] is assembled from besides its uncertainty.
struct CalibrationParts {
    estimate: GammaEstimate,
    obs: gsens_core::Observability,
    fed: Vec<FedEpoch>,
    normal: gsens_core::NormalEquations,
    noise_fit: Option<gls::GlsFit>,
    huber: Option<robust::HuberFit>,
    history: Vec<HistoryPoint>,
}

/// The [`Calibration`] of an estimate: Γ̂ and σ in both units, the bound,
/// the shaking verdicts, the predicted peak phase and the RMS figures.
fn assemble(
    series: &EpochSeries,
    settings: &EstimateSettings,
    parts: CalibrationParts,
    u: Uncertainty,
    residuals: Residuals,
    substeps: u32,
) -> Calibration {
    let CalibrationParts { estimate, obs, fed, normal, noise_fit, huber, history } = parts;
    let gamma = estimate.gamma_hz_per_mps2;
    let ppb = |x: Option<f64>| x.map(|v| hz_per_mps2_to_ppb_per_g(v, settings.carrier_hz));
    let loop_used = settings.loop_at(series.log_interval_s);
    let axes = verdict::axis_verdicts(
        series.accel_mps2,
        series.log_interval_s,
        &loop_used,
        u.observable,
        obs.excitation_rms,
        settings.criteria.min_excitation_rms,
    );
    let peak_phase = peak_phase_err_rad(&fed, &gamma);
    let mut calibration = Calibration {
        gamma_hz_per_mps2: u.gamma,
        sigma_hz_per_mps2: u.sigma,
        sigma_statistical_hz_per_mps2: u.sigma_stat,
        sigma_imu_hz_per_mps2: u.sigma_imu,
        gamma_ppb_per_g: u.gamma.map(ppb),
        sigma_ppb_per_g: u.sigma.map(ppb),
        observable: u.observable,
        excitation_rms: obs.excitation_rms,
        covariance_hz_per_mps2_sq: u.covariance,
        condition_number: obs.condition_number.is_finite().then_some(obs.condition_number),
        gamma_raw_hz_per_mps2: gamma,
        sigma_white_hz_per_mps2: u.sigma_white.map(|s| s.is_finite().then_some(s)),
        crlb_hz_per_mps2: [0, 1, 2].map(|i| {
            let c = noise_fit.as_ref().map(|g| g.crlb_hz_per_mps2()[i]);
            c.filter(|c| c.is_finite() && u.observable[i])
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
        rms_before_rad: residuals.rms_before_rad,
        rms_after_rad: residuals.rms_after_rad,
        rms_g_induced_rad: residuals.rms_g_induced_rad,
        residual_sigma_rad: estimate.residual_variance_rad2.sqrt(),
        epochs_used: normal.n,
        epochs_total: series.accel_mps2.len(),
        log_interval_s: series.log_interval_s,
        history,
        model_substeps: substeps,
        loop_used,
        settings: *settings,
    };
    for i in u.no_information {
        calibration.make_unobservable(i, "its σ came out 0: the estimator's covariance holds no information on it");
    }
    calibration
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
fn run<'h, E: GammaEstimator + Copy + Send + Sync + 'h>(
    mut cal: Calibrator<E>,
    series: &EpochSeries<'_>,
) -> (GammaEstimate, Vec<FedEpoch>, BatchLeastSquares, History<'h>) {
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
    let history: History<'h> = Box::new(move || {
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
