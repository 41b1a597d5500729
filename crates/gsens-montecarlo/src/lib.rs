//! Simulated trials: the simulator's sessions through the calibration.
//!
//! [`scenario_settings`] states a scenario's receiver as a user who knows it
//! would; [`monte_carlo`] simulates and estimates many times, in parallel, and
//! compares each method's spread with the Cramér–Rao bound; [`validate`]
//! feeds a Γ̂ forward into the simulated receiver's NCO and compares the
//! phase error without and with it. The crate sits
//! above both `gsens_sim` and `gsens_calib`, so that neither knows the other.
//!
//! Run i simulates the scenario with seed S + i into memory, prepares the
//! session exactly as the pipeline prepares files (the same readers'
//! checks, selection and interpolation), and calibrates it with every method.
//! The error of a method is Γ̂ − Γ_imu, Γ_imu = M⁻ᵀΓ the g-sensitivity as seen
//! through the IMU's readings (truth.json's `gamma_imu_axes_hz_per_mps2`):
//! what an estimator fed the IMU log converges to, so that the IMU's fixed
//! scale-factor and misalignment errors do not count as noise. The errors
//! against the body-frame Γ are reported too.
//!
//! Per method and axis: the bias and RMSE over the runs, the bound as the RMS
//! over the runs of each run's Cramér–Rao bound (RMSE² ≥ mean CRLB² for an
//! unbiased estimator), their ratio, the fraction of runs whose error is
//! within 3σ (the statistical σ the method reported) and the RMS of the error
//! over that σ.

mod demo;
mod identified;
mod methods;
mod predict;
mod validate;
mod validate_text;
pub use demo::{Demo, DemoError, DemoFolder, render_demo_start, simulate_demo};
pub use identified::{
    IdentifiedMonteCarlo, IdentifiedRun, IdentifiedStats, identified_monte_carlo, identified_run, identified_stats,
    scenario_shapes,
};
pub use methods::method_settings;
pub use predict::frequency_noise;
pub use validate::{GammaSource, ValidateError, calibrate_scenario, default_bandwidths_hz, run_validation, validate};
pub use validate_text::{render_gamma_hat, render_trial_row, render_validate_footer, render_validate_header};

use gsens_calib::{
    Calibration, EstimateSettings, Measurement, MeasurementChoice, Method, Outcome, PipelineSettings, calibrate_logs,
};
use gsens_core::LoopModel;
use gsens_sim::scenario::Scenario;
use gsens_sim::{LogsError, simulate_logs};
use rayon::prelude::*;
use serde::Serialize;

/// One method's result in one run.
#[derive(Debug, Clone, Serialize)]
pub struct MethodRun {
    /// Γ̂ \[Hz/(m/s²)\] (null: unobservable).
    pub gamma_hz_per_mps2: [Option<f64>; 3],
    /// The method's statistical 1σ \[Hz/(m/s²)\].
    pub sigma_statistical_hz_per_mps2: [Option<f64>; 3],
    /// The Cramér–Rao bound of the run \[Hz/(m/s²)\].
    pub crlb_hz_per_mps2: [Option<f64>; 3],
    /// Estimated minus true IMU time offset \[s\] (when estimated).
    pub time_offset_error_s: Option<f64>,
    /// Identified minus true natural frequency ωn/2π \[Hz\] (when identified).
    pub natural_frequency_error_hz: Option<f64>,
    /// The joint fit's 1σ of the IMU time offset \[s\] (when estimated).
    pub sigma_imu_time_offset_s: Option<f64>,
    /// The joint fit's 1σ of ωn/2π \[Hz\] (when identified).
    pub sigma_natural_frequency_hz: Option<f64>,
    /// The correlation of the fitted loop's ln ωn with the offset (when both are fitted).
    pub correlation_loop_offset: Option<f64>,
    /// Order of the AR noise model.
    pub noise_ar_order: usize,
    /// Whether the result document called the estimate trustworthy.
    pub trustworthy: bool,
    /// The codes of the warnings it raised.
    pub warnings: Vec<gsens_calib::WarningCode>,
}

/// One run: its seed, truth and each method's result (or why it failed).
#[derive(Debug, Clone, Serialize)]
pub struct Run {
    /// Seed of the simulation.
    pub seed: u64,
    /// Γ in the body frame \[Hz/(m/s²)\].
    pub gamma_hz_per_mps2: [f64; 3],
    /// Γ as seen through the IMU, M⁻ᵀΓ \[Hz/(m/s²)\].
    pub gamma_imu_axes_hz_per_mps2: [f64; 3],
    /// Per method, in the order given.
    pub methods: Vec<MethodOutcome>,
}

/// One method's outcome in one run.
#[derive(Debug, Clone, Serialize)]
pub struct MethodOutcome {
    /// The method's name.
    pub method: &'static str,
    /// Its result.
    #[serde(flatten)]
    pub result: Option<MethodRun>,
    /// Why it failed.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
}

/// Mean and RMS of a sample.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct MeanRms {
    /// Mean.
    pub mean: f64,
    /// Root mean square.
    pub rms: f64,
}

fn mean_rms(x: &[f64]) -> Option<MeanRms> {
    if x.is_empty() {
        return None;
    }
    let n = x.len() as f64;
    Some(MeanRms { mean: x.iter().sum::<f64>() / n, rms: (x.iter().map(|v| v * v).sum::<f64>() / n).sqrt() })
}

/// Statistics of one method over the runs (per axis: three numbers each).
#[derive(Debug, Clone, Serialize)]
pub struct MethodStats {
    /// Runs where the method produced an estimate of every axis.
    pub runs: usize,
    /// Runs where it failed or left an axis unobservable.
    pub failures: usize,
    /// Mean of Γ̂ − Γ_imu \[Hz/(m/s²)\].
    pub bias: [f64; 3],
    /// RMS of Γ̂ − Γ_imu \[Hz/(m/s²)\].
    pub rmse: [f64; 3],
    /// RMS over the runs of the per-run Cramér–Rao bound \[Hz/(m/s²)\].
    pub crlb: [f64; 3],
    /// rmse / crlb.
    pub rmse_over_crlb: [f64; 3],
    /// Fraction of runs with |Γ̂ − Γ_imu| ≤ 1σ (the method's statistical σ;
    /// 68.3 % when σ is honest and the errors Gaussian).
    pub within_1sigma: [f64; 3],
    /// Fraction within 2σ (95.4 %).
    pub within_2sigma: [f64; 3],
    /// Fraction within 3σ (99.7 %).
    pub within_3sigma: [f64; 3],
    /// Fraction of the runs with an estimate that the result document
    /// flagged as not trustworthy (on a clean scenario: the false-alarm rate).
    pub untrustworthy: f64,
    /// How often each warning code was raised, over the runs with an estimate.
    pub warning_counts: std::collections::BTreeMap<&'static str, usize>,
    /// RMS of (Γ̂ − Γ_imu)/σ: 1 when the reported σ is honest.
    pub z_rms: [f64; 3],
    /// Mean of Γ̂ − Γ (body frame) \[Hz/(m/s²)\].
    pub bias_body: [f64; 3],
    /// RMS of Γ̂ − Γ (body frame) \[Hz/(m/s²)\].
    pub rmse_body: [f64; 3],
    /// Estimated minus true IMU time offset \[s\] (when estimated).
    pub time_offset_error_s: Option<MeanRms>,
    /// Identified minus true ωn/2π \[Hz\] (when identified).
    pub natural_frequency_error_hz: Option<MeanRms>,
}

/// The short name of a method, as in the result document's `settings.method.name`.
pub fn method_name(m: &Method) -> &'static str {
    match m {
        Method::Batch => "batch",
        Method::Rls { .. } => "rls",
        Method::Gradient { .. } => "gradient",
        Method::Gls => "gls",
    }
}

/// The statistics of method `j` over `runs`.
pub fn method_stats(runs: &[Run], j: usize) -> MethodStats {
    let ok: Vec<(&Run, &MethodRun)> = runs
        .iter()
        .filter_map(|r| match &r.methods[j].result {
            Some(m) if (0..3).all(|i| m.gamma_hz_per_mps2[i].is_some() && m.crlb_hz_per_mps2[i].is_some()) => {
                Some((r, m))
            }
            _ => None,
        })
        .collect();
    // No run with an estimate of every axis: every statistic is NaN (null in
    // JSON), not a 0 that reads as a perfect estimator.
    let n = ok.len() as f64;
    type PerRun<'a> = &'a dyn Fn(&Run, &MethodRun, usize) -> f64;
    let mean = |f: PerRun| [0, 1, 2].map(|i| ok.iter().map(|(r, m)| f(r, m, i)).sum::<f64>() / n);
    let rms = |f: PerRun| [0, 1, 2].map(|i| (ok.iter().map(|(r, m)| f(r, m, i).powi(2)).sum::<f64>() / n).sqrt());
    let err =
        |r: &Run, m: &MethodRun, i: usize| m.gamma_hz_per_mps2[i].unwrap_or(0.0) - r.gamma_imu_axes_hz_per_mps2[i];
    let err_body = |r: &Run, m: &MethodRun, i: usize| m.gamma_hz_per_mps2[i].unwrap_or(0.0) - r.gamma_hz_per_mps2[i];
    let crlb = |_: &Run, m: &MethodRun, i: usize| m.crlb_hz_per_mps2[i].unwrap_or(f64::NAN);
    let z = |r: &Run, m: &MethodRun, i: usize| err(r, m, i) / m.sigma_statistical_hz_per_mps2[i].unwrap_or(f64::NAN);
    let within1 = |r: &Run, m: &MethodRun, i: usize| if z(r, m, i).abs() <= 1.0 { 1.0 } else { 0.0 };
    let within2 = |r: &Run, m: &MethodRun, i: usize| if z(r, m, i).abs() <= 2.0 { 1.0 } else { 0.0 };
    let within = |r: &Run, m: &MethodRun, i: usize| if z(r, m, i).abs() <= 3.0 { 1.0 } else { 0.0 };
    let produced: Vec<&MethodRun> = runs.iter().filter_map(|r| r.methods[j].result.as_ref()).collect();
    let mut warning_counts = std::collections::BTreeMap::new();
    for m in &produced {
        for w in &m.warnings {
            *warning_counts.entry(w.as_str()).or_insert(0) += 1;
        }
    }
    let untrustworthy = produced.iter().filter(|m| !m.trustworthy).count() as f64 / produced.len() as f64;
    let rmse = rms(&err);
    let crlb_rms = rms(&crlb);
    let collect = |f: &dyn Fn(&MethodRun) -> Option<f64>| -> Vec<f64> { ok.iter().filter_map(|(_, m)| f(m)).collect() };
    MethodStats {
        runs: ok.len(),
        failures: runs.len() - ok.len(),
        bias: mean(&err),
        rmse,
        crlb: crlb_rms,
        rmse_over_crlb: [0, 1, 2].map(|i| rmse[i] / crlb_rms[i]),
        within_1sigma: mean(&within1),
        within_2sigma: mean(&within2),
        within_3sigma: mean(&within),
        untrustworthy,
        warning_counts,
        z_rms: rms(&z),
        bias_body: mean(&err_body),
        rmse_body: rms(&err_body),
        time_offset_error_s: mean_rms(&collect(&|m| m.time_offset_error_s)),
        natural_frequency_error_hz: mean_rms(&collect(&|m| m.natural_frequency_error_hz)),
    }
}

/// The name of the loop-free estimate's row beside the methods': the input
/// phase θ_NCO + φ regressed with no loop model
/// ([`gsens_calib::estimate_loop_free`]), made once per run (it does not
/// depend on the method) wherever the scenario logs the NCO's phase.
pub const LOOP_FREE: &str = "loop-free";

/// The name of the row of the estimate from the NCO's frequency through the
/// methods' loop model ([`gsens_calib::estimate_nco_frequency`]), made once
/// per run beside [`LOOP_FREE`] wherever the scenario logs the NCO.
pub const NCO_FREQUENCY: &str = "nco-frequency";

/// A method's result in a run from its `outcome` and the run's `truth`
/// (`true_fn_hz`: the scenario loop's ωn/2π).
fn method_run(outcome: &Outcome, truth: &gsens_sim::session::Truth, true_fn_hz: Option<f64>) -> MethodRun {
    let doc = outcome.document(Some(truth.sensitivity.gamma_hz_per_mps2));
    let c: &Calibration = &outcome.calibration;
    let joint = c.joint_fit.as_ref().filter(|_| outcome.measurement == Measurement::TrackingError);
    MethodRun {
        gamma_hz_per_mps2: c.gamma_hz_per_mps2,
        sigma_statistical_hz_per_mps2: c.sigma_statistical_hz_per_mps2,
        crlb_hz_per_mps2: c.crlb_hz_per_mps2,
        time_offset_error_s: c.imu_time_offset_estimated.then_some(c.imu_time_offset_s - truth.imu_time_offset_s),
        natural_frequency_error_hz: joint.and_then(|j| j.natural_frequency_hz.zip(true_fn_hz).map(|(f, t)| f - t)),
        sigma_imu_time_offset_s: joint.and_then(|j| j.sigma_imu_time_offset_s),
        sigma_natural_frequency_hz: joint.and_then(|j| j.sigma_natural_frequency_hz),
        correlation_loop_offset: joint.and_then(|j| j.correlation_loop_offset),
        noise_ar_order: c.noise_ar_order,
        trustworthy: doc.trustworthy,
        warnings: doc.warnings.iter().map(|w| w.code).collect(),
    }
}

/// Simulates run `seed` into memory and calibrates it with each of `methods`
/// (pipeline settings, one per method), as `gsens estimate` would the files;
/// where the scenario logs the NCO, the estimates from its phase and its
/// frequency follow as two more rows ([`LOOP_FREE`], [`NCO_FREQUENCY`]), each
/// judged as the document that presents it.
pub fn run_one(scenario: &Scenario, seed: u64, methods: &[PipelineSettings]) -> Result<Run, MonteCarloError> {
    let logs = simulate_logs(scenario, seed).map_err(|source| MonteCarloError::Simulation { seed, source })?;
    let (tracking, imu, truth) = (&logs.tracking, &logs.imu, &logs.truth);
    let imu_name = format!("simulated imu (seed {seed})");
    let true_fn_hz = scenario
        .tracking_loop
        .coeffs()
        .ok()
        .and_then(|c| gsens_core::LoopSpec::Coefficients(c).wn_rad_per_s())
        .map(|wn| wn / std::f64::consts::TAU);
    let mut results = Vec::with_capacity(methods.len() + 1);
    let mut from_the_nco: Vec<MethodOutcome> = Vec::new();
    for settings in methods {
        let method = method_name(&settings.estimate.method);
        let mut outcome = match calibrate_logs(tracking, imu, &imu_name, settings) {
            Ok(o) => o,
            Err(e) => {
                results.push(MethodOutcome { method, result: None, error: Some(e.to_string()) });
                continue;
            }
        };
        results.push(MethodOutcome { method, result: Some(method_run(&outcome, truth, true_fn_hz)), error: None });
        if from_the_nco.is_empty() && scenario.log.nco {
            for (method, choice) in
                [(LOOP_FREE, MeasurementChoice::InputPhase), (NCO_FREQUENCY, MeasurementChoice::NcoFrequency)]
            {
                from_the_nco.push(match outcome.choose_measurement(choice) {
                    Ok(()) => {
                        MethodOutcome { method, result: Some(method_run(&outcome, truth, true_fn_hz)), error: None }
                    }
                    Err(e) => MethodOutcome { method, result: None, error: Some(e.to_string()) },
                });
            }
        }
    }
    results.extend(from_the_nco);
    Ok(Run {
        seed,
        gamma_hz_per_mps2: truth.sensitivity.gamma_hz_per_mps2,
        gamma_imu_axes_hz_per_mps2: truth.sensitivity.gamma_imu_axes_hz_per_mps2,
        methods: results,
    })
}

/// The whole Monte Carlo: runs, statistics per method, timing.
#[derive(Debug, Clone, Serialize)]
pub struct MonteCarlo {
    /// Number of runs.
    pub runs: u64,
    /// Seed of run 0 (run i: seed + i).
    pub seed: u64,
    /// Scenario file, or "default".
    pub scenario: String,
    /// Wall time \[s\].
    pub wall_s: f64,
    /// Worker threads.
    pub threads: usize,
    /// Whether and how the methods were told the receiver's loop: its
    /// bandwidth stated this many times the true one, or `null`: not stated.
    pub stated_bn_scale: Option<f64>,
    /// The method whose largest RMSE/CRLB over the axes is smallest.
    pub best_method: Option<String>,
    /// Statistics per method, in the order given, then the estimates' from
    /// the NCO ([`LOOP_FREE`], [`NCO_FREQUENCY`]) where the scenario logs it.
    #[serde(serialize_with = "ser_stats")]
    pub methods: Vec<(&'static str, MethodStats)>,
    /// Every run's estimates.
    pub per_run: Vec<Run>,
}

/// The methods' stated bandwidth over the scenario's, `None` when the loop
/// was not stated (every method is stated alike).
fn stated_bn_scale(scenario: &Scenario, methods: &[PipelineSettings]) -> Option<f64> {
    let stated = methods.first().filter(|m| m.loop_stated)?.estimate.receiver_loop.bn_hz()?;
    Some(stated / scenario.tracking_loop.bn_hz)
}

fn ser_stats<S: serde::Serializer>(m: &[(&'static str, MethodStats)], s: S) -> Result<S::Ok, S::Error> {
    use serde::ser::SerializeMap;
    let mut map = s.serialize_map(Some(m.len()))?;
    for (name, st) in m {
        map.serialize_entry(name, st)?;
    }
    map.end()
}

/// Why a Monte Carlo could not run.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum MonteCarloError {
    /// No run or no method asked for.
    #[error("a Monte Carlo needs at least one run and one method")]
    Empty,
    /// A run could not be simulated.
    #[error("simulating seed {seed}: {source}")]
    Simulation {
        /// Its seed.
        seed: u64,
        /// Why.
        source: LogsError,
    },
    /// The options are not valid settings.
    #[error(transparent)]
    Settings(#[from] gsens_calib::CalibError),
}

/// The estimation settings for a simulated scenario: the receiver loop the
/// scenario ran (its filter and update interval), its logged phase, its
/// carrier and its IMU's datasheet accuracy (where `base` leaves them at 0),
/// as a user who knows the receiver would state them.
pub fn scenario_settings(scenario: &Scenario, base: &EstimateSettings) -> Result<EstimateSettings, MonteCarloError> {
    let l = &scenario.tracking_loop;
    let spec = l.spec();
    let mut s = *base;
    s.receiver_loop = LoopModel::kaplan(spec, Some(l.interval_s));
    s.logged_phase = scenario.log.phase;
    s.carrier_hz = scenario.oscillator.carrier_hz;
    let imu = scenario.imu.config();
    if s.imu_scale_sigma == 0.0 {
        s.imu_scale_sigma = imu.scale_factor_sigma_ppm * 1e-6;
    }
    if s.imu_misalignment_sigma_rad == 0.0 {
        s.imu_misalignment_sigma_rad = imu.misalignment_sigma_rad;
    }
    Ok(s)
}

/// Runs `runs` simulations (seeds `seed`, `seed + 1`, …) in parallel and
/// calibrates each with every method of `methods`; `progress` is called once
/// per finished run. Results are indexed by run, so the same seed gives the
/// same numbers whatever the thread count.
pub fn monte_carlo(
    scenario: &Scenario,
    scenario_name: &str,
    runs: u64,
    seed: u64,
    methods: &[PipelineSettings],
    progress: impl Fn() + Sync,
) -> Result<MonteCarlo, MonteCarloError> {
    if runs == 0 || methods.is_empty() {
        return Err(MonteCarloError::Empty);
    }
    let start = std::time::Instant::now();
    let per_run: Vec<Run> = (0..runs)
        .into_par_iter()
        .map(|i| {
            let r = run_one(scenario, seed + i, methods);
            progress();
            r
        })
        .collect::<Result<Vec<_>, _>>()?;
    let wall_s = start.elapsed().as_secs_f64();
    let mut stats: Vec<(&'static str, MethodStats)> =
        methods.iter().enumerate().map(|(j, m)| (method_name(&m.estimate.method), method_stats(&per_run, j))).collect();
    if scenario.log.nco {
        stats.push((LOOP_FREE, method_stats(&per_run, methods.len())));
        stats.push((NCO_FREQUENCY, method_stats(&per_run, methods.len() + 1)));
    }
    let worst = |s: &MethodStats| s.rmse_over_crlb.iter().fold(0.0f64, |a, &b| a.max(b));
    // The first method within 1e-6 of the smallest worst axis (RLS with λ = 1
    // equals the batch to rounding); the loop-free row is a measurement, not a method.
    let valid = || stats[..methods.len()].iter().filter(|(_, s)| s.runs > 0 && worst(s).is_finite());
    let min_worst = valid().map(|(_, s)| worst(s)).fold(f64::INFINITY, f64::min);
    let best_method = valid().find(|(_, s)| worst(s) <= min_worst * (1.0 + 1e-6)).map(|(n, _)| n.to_string());
    Ok(MonteCarlo {
        runs,
        seed,
        scenario: scenario_name.to_string(),
        wall_s,
        threads: rayon::current_num_threads(),
        stated_bn_scale: stated_bn_scale(scenario, methods),
        best_method,
        methods: stats,
        per_run,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn no_run_with_an_estimate_gives_no_statistics_not_zeros() {
        let failed = |seed| Run {
            seed,
            gamma_hz_per_mps2: [0.09, 0.08, -0.08],
            gamma_imu_axes_hz_per_mps2: [0.09, 0.08, -0.08],
            methods: vec![MethodOutcome { method: "batch", result: None, error: Some("too short".into()) }],
        };
        let st = method_stats(&[failed(1), failed(2)], 0);
        assert_eq!((st.runs, st.failures), (0, 2));
        for v in [st.bias, st.rmse, st.crlb, st.rmse_over_crlb, st.within_1sigma, st.z_rms, st.rmse_body] {
            assert!(v.iter().all(|x| x.is_nan()), "{v:?}");
        }
        assert!(st.untrustworthy.is_nan());
        let json = serde_json::to_value(&st).unwrap();
        assert_eq!(json["bias"], serde_json::json!([null, null, null]));
    }
}
