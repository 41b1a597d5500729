//! `gsens montecarlo`: simulate and estimate many times, in parallel, and
//! compare each method's spread with the Cramér–Rao bound.
//!
//! Run i simulates the scenario with seed S + i into memory, prepares the
//! session exactly as `gsens estimate` prepares files (the same readers'
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
//! over that σ. Results are indexed by run, so the same seed gives the same
//! numbers whatever the thread count.

use crate::demo::scenario_settings;
use crate::estimate::{EstimatorArgs, MethodArg, SelectionArgs, SystematicArgs, estimate_logs};
use crate::simulate::load_scenario;
use anyhow::{Context, Result, bail};
use clap::Args;
use gsens_calib::Calibration;
use gsens_io::{ImuSeries, TrackingLog};
use gsens_sim::scenario::Scenario;
use gsens_sim::session::{MemorySink, Truth, simulate};
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;
use serde::Serialize;
use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::Instant;

const AXES: [&str; 3] = ["x", "y", "z"];

#[derive(Args, Debug)]
pub struct MonteCarloArgs {
    /// Scenario TOML (default: the embedded paper experiment).
    #[arg(long)]
    pub scenario: Option<PathBuf>,
    /// Number of runs.
    #[arg(long, default_value_t = 200)]
    pub runs: u64,
    /// Seed of run 0; run i uses seed + i.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Methods to compare (comma separated; replaces --method).
    #[arg(long, value_enum, value_delimiter = ',', default_value = "batch,rls,gradient,gls")]
    pub methods: Vec<MethodArg>,
    #[command(flatten)]
    pub estimator: EstimatorArgs,
    #[command(flatten)]
    pub selection: SelectionArgs,
    #[command(flatten)]
    pub systematic: SystematicArgs,
    /// Write the statistics (and every run's estimates) as JSON here.
    #[arg(long)]
    pub json: Option<PathBuf>,
}

/// One method's result in one run.
#[derive(Debug, Clone, Serialize)]
pub struct MethodRun {
    /// Γ̂ [Hz/(m/s²)] (null: unobservable).
    pub gamma_hz_per_mps2: [Option<f64>; 3],
    /// The method's statistical 1σ [Hz/(m/s²)].
    pub sigma_statistical_hz_per_mps2: [Option<f64>; 3],
    /// The Cramér–Rao bound of the run [Hz/(m/s²)].
    pub crlb_hz_per_mps2: [Option<f64>; 3],
    /// Estimated minus true IMU time offset [s] (when estimated).
    pub time_offset_error_s: Option<f64>,
    /// Identified minus true natural frequency ωn/2π [Hz] (when identified).
    pub natural_frequency_error_hz: Option<f64>,
    /// Order of the AR noise model.
    pub noise_ar_order: usize,
}

/// One run: its seed, truth and each method's result (or why it failed).
#[derive(Debug, Clone, Serialize)]
pub struct Run {
    /// Seed of the simulation.
    pub seed: u64,
    /// Γ in the body frame [Hz/(m/s²)].
    pub gamma_hz_per_mps2: [f64; 3],
    /// Γ as seen through the IMU, M⁻ᵀΓ [Hz/(m/s²)].
    pub gamma_imu_axes_hz_per_mps2: [f64; 3],
    /// Per method, in the order of `--methods`.
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
    /// Mean of Γ̂ − Γ_imu [Hz/(m/s²)].
    pub bias: [f64; 3],
    /// RMS of Γ̂ − Γ_imu [Hz/(m/s²)].
    pub rmse: [f64; 3],
    /// RMS over the runs of the per-run Cramér–Rao bound [Hz/(m/s²)].
    pub crlb: [f64; 3],
    /// rmse / crlb.
    pub rmse_over_crlb: [f64; 3],
    /// Fraction of runs with |Γ̂ − Γ_imu| ≤ 3σ (the method's statistical σ).
    pub within_3sigma: [f64; 3],
    /// RMS of (Γ̂ − Γ_imu)/σ: 1 when the reported σ is honest.
    pub z_rms: [f64; 3],
    /// Mean of Γ̂ − Γ (body frame) [Hz/(m/s²)].
    pub bias_body: [f64; 3],
    /// RMS of Γ̂ − Γ (body frame) [Hz/(m/s²)].
    pub rmse_body: [f64; 3],
    /// Estimated minus true IMU time offset [s] (when estimated).
    pub time_offset_error_s: Option<MeanRms>,
    /// Identified minus true ωn/2π [Hz] (when identified).
    pub natural_frequency_error_hz: Option<MeanRms>,
}

fn method_name(m: MethodArg) -> &'static str {
    match m {
        MethodArg::Batch => "batch",
        MethodArg::Rls => "rls",
        MethodArg::Gradient => "gradient",
        MethodArg::Gls => "gls",
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
    let n = ok.len().max(1) as f64;
    type PerRun<'a> = &'a dyn Fn(&Run, &MethodRun, usize) -> f64;
    let mean = |f: PerRun| [0, 1, 2].map(|i| ok.iter().map(|(r, m)| f(r, m, i)).sum::<f64>() / n);
    let rms = |f: PerRun| [0, 1, 2].map(|i| (ok.iter().map(|(r, m)| f(r, m, i).powi(2)).sum::<f64>() / n).sqrt());
    let err =
        |r: &Run, m: &MethodRun, i: usize| m.gamma_hz_per_mps2[i].unwrap_or(0.0) - r.gamma_imu_axes_hz_per_mps2[i];
    let err_body = |r: &Run, m: &MethodRun, i: usize| m.gamma_hz_per_mps2[i].unwrap_or(0.0) - r.gamma_hz_per_mps2[i];
    let crlb = |_: &Run, m: &MethodRun, i: usize| m.crlb_hz_per_mps2[i].unwrap_or(f64::NAN);
    let z = |r: &Run, m: &MethodRun, i: usize| err(r, m, i) / m.sigma_statistical_hz_per_mps2[i].unwrap_or(f64::NAN);
    let within = |r: &Run, m: &MethodRun, i: usize| if z(r, m, i).abs() <= 3.0 { 1.0 } else { 0.0 };
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
        within_3sigma: mean(&within),
        z_rms: rms(&z),
        bias_body: mean(&err_body),
        rmse_body: rms(&err_body),
        time_offset_error_s: mean_rms(&collect(&|m| m.time_offset_error_s)),
        natural_frequency_error_hz: mean_rms(&collect(&|m| m.natural_frequency_error_hz)),
    }
}

/// Simulates run `seed` into memory and calibrates it with each method.
pub fn run_one(
    scenario: &Scenario,
    seed: u64,
    methods: &[(MethodArg, gsens_calib::EstimateSettings)],
    selection: &gsens_session::SelectionConfig,
    systematic: &SystematicArgs,
) -> Result<Run> {
    let mut sink = MemorySink::default();
    let truth: Truth =
        simulate(scenario, seed, &mut sink, |_| {}).with_context(|| format!("simulating seed {seed}"))?;
    let rows: Vec<gsens_io::TrackingRow> = sink
        .tracking
        .iter()
        .map(|r| gsens_io::TrackingRow {
            t_s: r.t_s,
            channel: r.channel,
            prn: r.prn,
            cn0_dbhz: r.cn0_dbhz,
            elev_deg: Some(r.elev_deg),
            phase_err_rad: r.phase_err_rad,
        })
        .collect();
    let tracking = TrackingLog::from_rows(&format!("simulated tracking (seed {seed})"), &rows)?;
    let imu =
        ImuSeries { t_s: sink.imu.iter().map(|s| s.0).collect(), accel_mps2: sink.imu.iter().map(|s| s.1).collect() };
    drop(sink);
    let imu_name = format!("simulated imu (seed {seed})");
    let true_fn_hz = scenario
        .tracking_loop
        .coeffs()
        .ok()
        .and_then(|c| gsens_core::pll::LoopSpec::Coefficients(c).wn_rad_per_s())
        .map(|wn| wn / std::f64::consts::TAU);
    let results = methods
        .iter()
        .map(|(method, settings)| {
            let c: Calibration = match estimate_logs(&tracking, &imu, &imu_name, selection, systematic, settings) {
                Ok((_, c)) => c,
                Err(e) => {
                    return MethodOutcome { method: method_name(*method), result: None, error: Some(format!("{e:#}")) };
                }
            };
            let result = MethodRun {
                gamma_hz_per_mps2: c.gamma_hz_per_mps2,
                sigma_statistical_hz_per_mps2: c.sigma_statistical_hz_per_mps2,
                crlb_hz_per_mps2: c.crlb_hz_per_mps2,
                time_offset_error_s: c
                    .imu_time_offset_estimated
                    .then_some(c.imu_time_offset_s - truth.imu_time_offset_s),
                natural_frequency_error_hz: c
                    .loop_identification
                    .as_ref()
                    .and_then(|id| true_fn_hz.map(|t| id.natural_frequency_hz - t)),
                noise_ar_order: c.noise_ar_order,
            };
            MethodOutcome { method: method_name(*method), result: Some(result), error: None }
        })
        .collect();
    Ok(Run {
        seed,
        gamma_hz_per_mps2: truth.gamma_hz_per_mps2,
        gamma_imu_axes_hz_per_mps2: truth.gamma_imu_axes_hz_per_mps2,
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
    /// Wall time [s].
    pub wall_s: f64,
    /// Worker threads.
    pub threads: usize,
    /// The method whose largest RMSE/CRLB over the axes is smallest.
    pub best_method: Option<String>,
    /// Statistics per method name.
    pub methods: serde_json::Map<String, serde_json::Value>,
    /// Every run's estimates.
    pub per_run: Vec<Run>,
}

pub fn run(args: &MonteCarloArgs) -> Result<()> {
    if args.runs == 0 {
        bail!("--runs must be at least 1");
    }
    if args.methods.is_empty() {
        bail!("--methods is empty");
    }
    let scenario = load_scenario(args.scenario.as_deref())?;
    let methods = args
        .methods
        .iter()
        .map(|&method| {
            let est = EstimatorArgs { method, ..args.estimator.clone() };
            Ok((method, scenario_settings(&scenario, &est)?))
        })
        .collect::<Result<Vec<_>>>()?;
    let selection = args.selection.selection();
    let bar = ProgressBar::new(args.runs);
    bar.set_style(
        ProgressStyle::with_template("monte carlo {bar:40} {pos}/{len} runs {elapsed_precise} (eta {eta})")
            .expect("valid template"),
    );
    let start = Instant::now();
    let runs: Vec<Run> = (0..args.runs)
        .into_par_iter()
        .map(|i| {
            let r = run_one(&scenario, args.seed + i, &methods, &selection, &args.systematic);
            bar.inc(1);
            r
        })
        .collect::<Result<Vec<_>>>()?;
    bar.finish_and_clear();
    let wall_s = start.elapsed().as_secs_f64();
    let stats: Vec<(&'static str, MethodStats)> =
        methods.iter().enumerate().map(|(j, (m, _))| (method_name(*m), method_stats(&runs, j))).collect();
    let worst = |s: &MethodStats| s.rmse_over_crlb.iter().fold(0.0f64, |a, &b| a.max(b));
    // The first of `--methods` within 1e-6 of the smallest worst axis (RLS with
    // λ = 1 equals the batch to rounding).
    let valid = || stats.iter().filter(|(_, s)| s.runs > 0 && worst(s).is_finite());
    let min_worst = valid().map(|(_, s)| worst(s)).fold(f64::INFINITY, f64::min);
    let best = valid().find(|(_, s)| worst(s) <= min_worst * (1.0 + 1e-6)).map(|(n, _)| n.to_string());
    let mc = MonteCarlo {
        runs: args.runs,
        seed: args.seed,
        scenario: args.scenario.as_ref().map_or("default".into(), |p| p.display().to_string()),
        wall_s,
        threads: rayon::current_num_threads(),
        best_method: best,
        methods: stats.iter().map(|(n, s)| (n.to_string(), serde_json::to_value(s).expect("serializable"))).collect(),
        per_run: runs,
    };
    print!("{}", text(&mc, &stats));
    if let Some(path) = &args.json {
        std::fs::write(path, serde_json::to_string_pretty(&mc)? + "\n")
            .with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}

/// The readable table.
pub fn text(mc: &MonteCarlo, stats: &[(&str, MethodStats)]) -> String {
    let mut s = String::new();
    let s_ = &mut s;
    let _ = writeln!(
        s_,
        "monte carlo: {} runs of the {} scenario (seeds {}…{}), {:.1} s wall on {} threads",
        mc.runs,
        mc.scenario,
        mc.seed,
        mc.seed + mc.runs - 1,
        mc.wall_s,
        mc.threads
    );
    let _ = writeln!(
        s_,
        "errors Γ̂ − Γ_imu (Γ through the IMU's scale and misalignment) [Hz/(m/s²)]; CRLB: RMS over runs of each run's bound\n"
    );
    let _ =
        writeln!(s_, "method    axis      bias        RMSE        CRLB   RMSE/CRLB  |e|≤3σ   z RMS   RMSE vs body Γ");
    for (name, st) in stats {
        for i in 0..3 {
            let _ = writeln!(
                s_,
                "{:<9} {:>3}  {:>+10.6}  {:>10.6}  {:>10.6}  {:>9.3}  {:>5.1} %  {:>6.2}   {:>10.6}",
                if i == 0 { name } else { "" },
                AXES[i],
                st.bias[i],
                st.rmse[i],
                st.crlb[i],
                st.rmse_over_crlb[i],
                100.0 * st.within_3sigma[i],
                st.z_rms[i],
                st.rmse_body[i]
            );
        }
        if st.failures > 0 {
            let _ =
                writeln!(s_, "{:<9}      {} of {} runs failed or left an axis unobservable", "", st.failures, mc.runs);
        }
    }
    if let Some(b) = &mc.best_method {
        let st = &stats.iter().find(|(n, _)| n == b).expect("best is one of them").1;
        let worst = st.rmse_over_crlb.iter().fold(0.0f64, |a, &x| a.max(x));
        let _ = writeln!(s_, "\nbest: {b} (largest RMSE/CRLB over the axes {worst:.3})");
    }
    for (name, st) in stats {
        if let Some(t) = st.time_offset_error_s {
            let _ =
                writeln!(s_, "{name}: IMU time offset error: bias {:+.3} ms, RMS {:.3} ms", 1e3 * t.mean, 1e3 * t.rms);
        }
        if let Some(f) = st.natural_frequency_error_hz {
            let _ = writeln!(s_, "{name}: loop ωn/2π error: bias {:+.5} Hz, RMS {:.5} Hz", f.mean, f.rms);
        }
    }
    s
}
