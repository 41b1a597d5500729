//! Simulated trials of the estimate from the NCO's frequency with the loop
//! identified from the session ([`gsens_calib::estimate_nco_frequency_identified_from`]),
//! measured against the bound with the loop known.
//!
//! Run i simulates the scenario with seed S + i, makes the rows of the NCO
//! record asked for ([`gsens_calib::nco_rows`]) and fits them twice: with the
//! loop identified among the shapes given (all of
//! [`gsens_calib::identification_shapes`], or those at an update interval
//! known: [`scenario_shapes`]), and through the scenario's own loop stated
//! exactly ([`gsens_calib::estimate_nco_frequency_from`]). The second fit's
//! Cramér–Rao bound (at its fitted AR noise model, τ and loop held) is the
//! bound the identified estimate is measured against: what the same rows
//! give when the loop is known. Errors are Γ̂ − Γ_imu, as in
//! [`crate::monte_carlo`].
//!
//! Per axis: the bias and RMSE of each estimate over the runs, the RMSE's
//! ratio to the RMS over the runs of the known-loop bound, and the RMS of
//! (Γ̂ − Γ_imu)/σ with each estimate's own σ (1 for an honest σ). Of the
//! loop: how often Bn was resolved inside the searched range, the RMS of its
//! relative error and of its z (ln(B̂n/Bn)/σ_ln Bn) over those of them that
//! kept the right order, how often the order was resolved, and resolved
//! right, and how often the kept shape's update interval was the scenario's.

use crate::MonteCarloError;
use gsens_calib::{
    IdentifiedLoop, LoopFreeSettings, LoopResolution, NcoRecord, estimate_nco_frequency_from,
    estimate_nco_frequency_identified_from, identification_shapes, nco_rows,
};
use gsens_core::LoopModel;
use gsens_sim::scenario::{LoopSection, Scenario};
use gsens_sim::simulate_logs;
use rayon::prelude::*;
use serde::Serialize;

/// One run's two estimates.
#[derive(Debug, Clone, Serialize)]
pub struct IdentifiedRun {
    /// Seed of the simulation.
    pub seed: u64,
    /// Γ as seen through the IMU, M⁻ᵀΓ \[Hz/(m/s²)\].
    pub gamma_imu_axes_hz_per_mps2: [f64; 3],
    /// Γ̂ with the loop identified \[Hz/(m/s²)\].
    pub gamma_hz_per_mps2: [f64; 3],
    /// Its 1σ, the loop's uncertainty included \[Hz/(m/s²)\].
    pub sigma_hz_per_mps2: [f64; 3],
    /// Γ̂ through the scenario's loop stated exactly \[Hz/(m/s²)\].
    pub known_gamma_hz_per_mps2: [f64; 3],
    /// Its 1σ \[Hz/(m/s²)\].
    pub known_sigma_hz_per_mps2: [f64; 3],
    /// Its Cramér–Rao bound: the bound with the loop known \[Hz/(m/s²)\].
    pub known_crlb_hz_per_mps2: [f64; 3],
    /// The loop identified.
    pub identified: IdentifiedLoop,
}

/// The statistics over the runs.
#[derive(Debug, Clone, Serialize)]
pub struct IdentifiedStats {
    /// Runs where both estimates were made.
    pub runs: usize,
    /// Mean of Γ̂ − Γ_imu with the loop identified \[Hz/(m/s²)\].
    pub bias: [f64; 3],
    /// RMS of Γ̂ − Γ_imu with the loop identified \[Hz/(m/s²)\].
    pub rmse: [f64; 3],
    /// RMS over the runs of the known-loop Cramér–Rao bound \[Hz/(m/s²)\].
    pub known_crlb: [f64; 3],
    /// `rmse` / `known_crlb`: what identifying the loop costs.
    pub rmse_over_known_crlb: [f64; 3],
    /// RMS of (Γ̂ − Γ_imu)/σ with the loop identified (1: σ honest).
    pub z_rms: [f64; 3],
    /// RMSE of the known-loop estimate over `known_crlb` (the reference: ≈ 1).
    pub known_rmse_over_known_crlb: [f64; 3],
    /// RMS of (Γ̂ − Γ_imu)/σ of the known-loop estimate.
    pub known_z_rms: [f64; 3],
    /// Runs whose Bn was resolved inside the searched range.
    pub bn_resolved: usize,
    /// Of those, the runs whose kept shape has the scenario's order, where
    /// B̂n is compared with Bn (a loop of the other order has another Bn
    /// for the same response).
    pub bn_compared: usize,
    /// RMS of B̂n/Bn − 1 over the runs compared (`None`: none).
    pub bn_relative_error_rms: Option<f64>,
    /// RMS of ln(B̂n/Bn)/σ_ln Bn over the runs compared (1: its σ honest).
    pub bn_z_rms: Option<f64>,
    /// Runs whose order was resolved (the other order's shapes weigh under 5 %).
    pub order_resolved: usize,
    /// Runs whose order was resolved and is the scenario's.
    pub order_right: usize,
    /// Runs whose kept shape is updated at the scenario loop's interval.
    pub interval_right: usize,
}

/// The whole trial.
#[derive(Debug, Clone, Serialize)]
pub struct IdentifiedMonteCarlo {
    /// Number of runs asked for.
    pub runs: u64,
    /// Seed of run 0 (run i: seed + i).
    pub seed: u64,
    /// The record the rows were made of.
    pub record: NcoRecord,
    /// The update intervals of the shapes tried \[s\].
    pub shape_intervals_s: Vec<f64>,
    /// The scenario loop's order.
    pub true_order: u8,
    /// The scenario loop's noise bandwidth \[Hz\].
    pub true_bn_hz: f64,
    /// The statistics.
    pub stats: IdentifiedStats,
    /// Every run with both estimates.
    pub per_run: Vec<IdentifiedRun>,
    /// The runs where an estimate failed: seed and why.
    pub failed: Vec<(u64, String)>,
}

/// The shapes the identification tries on `scenario`'s log
/// ([`gsens_calib::identification_shapes`] of its log interval): all of
/// them, or with `interval_known` only those updated at the scenario loop's
/// interval (the order and Bn still identified).
pub fn scenario_shapes(scenario: &Scenario, interval_known: bool) -> Vec<LoopModel> {
    let interval_s = scenario.tracking_loop.interval_s;
    let at_interval = |m: &LoopModel| m.interval_s().is_some_and(|t| same_interval(t, interval_s));
    identification_shapes(scenario.log.interval_s).into_iter().filter(|m| !interval_known || at_interval(m)).collect()
}

/// Whether two update intervals are the same (within rounding).
fn same_interval(a_s: f64, b_s: f64) -> bool {
    (a_s - b_s).abs() <= 1e-9 * b_s
}

/// One run: `scenario` simulated with `seed`, its `record` fitted with the
/// loop identified among `shapes` and with the scenario's loop stated, under
/// `settings`. `Ok(Err(why))` where an estimate failed.
pub fn identified_run(
    scenario: &Scenario,
    seed: u64,
    record: NcoRecord,
    shapes: &[LoopModel],
    settings: &LoopFreeSettings,
) -> Result<Result<IdentifiedRun, String>, MonteCarloError> {
    let logs = simulate_logs(scenario, seed).map_err(|source| MonteCarloError::Simulation { seed, source })?;
    let known_loop = LoopModel::kaplan(scenario.tracking_loop.spec(), Some(scenario.tracking_loop.interval_s));
    let fits = nco_rows(&logs.tracking, settings, record).and_then(|(rows, quantity)| {
        let identified = estimate_nco_frequency_identified_from(&rows, &logs.imu, settings, shapes, quantity)?;
        let known = estimate_nco_frequency_from(&rows, &logs.imu, settings, &known_loop, quantity)?;
        Ok((identified, known))
    });
    Ok(fits.map_err(|e| e.to_string()).map(|(identified, known)| IdentifiedRun {
        seed,
        gamma_imu_axes_hz_per_mps2: logs.truth.sensitivity.gamma_imu_axes_hz_per_mps2,
        gamma_hz_per_mps2: identified.estimate.gamma_hz_per_mps2,
        sigma_hz_per_mps2: identified.estimate.sigma_hz_per_mps2(),
        known_gamma_hz_per_mps2: known.gamma_hz_per_mps2,
        known_sigma_hz_per_mps2: known.sigma_hz_per_mps2(),
        known_crlb_hz_per_mps2: known.crlb_hz_per_mps2,
        identified: identified.identified,
    }))
}

/// `runs` runs of `scenario` (seeds `seed`, `seed + 1`, …) in parallel, each
/// [`identified_run`]; `progress` is called once per finished run. The
/// same seeds give the same numbers whatever the thread count.
pub fn identified_monte_carlo(
    scenario: &Scenario,
    runs: u64,
    seed: u64,
    record: NcoRecord,
    shapes: &[LoopModel],
    settings: &LoopFreeSettings,
    progress: impl Fn() + Sync,
) -> Result<IdentifiedMonteCarlo, MonteCarloError> {
    if runs == 0 {
        return Err(MonteCarloError::Empty);
    }
    let outcomes: Vec<Result<IdentifiedRun, String>> = (0..runs)
        .into_par_iter()
        .map(|i| {
            let r = identified_run(scenario, seed + i, record, shapes, settings);
            progress();
            r
        })
        .collect::<Result<_, _>>()?;
    let (mut per_run, mut failed) = (Vec::new(), Vec::new());
    for (i, outcome) in (0..runs).zip(outcomes) {
        match outcome {
            Ok(run) => per_run.push(run),
            Err(why) => failed.push((seed + i, why)),
        }
    }
    let stats = identified_stats(&per_run, &scenario.tracking_loop);
    let mut shape_intervals_s: Vec<f64> = shapes.iter().filter_map(LoopModel::interval_s).collect();
    shape_intervals_s.sort_by(f64::total_cmp);
    shape_intervals_s.dedup();
    let (true_order, true_bn_hz) = (scenario.tracking_loop.order, scenario.tracking_loop.bn_hz);
    Ok(IdentifiedMonteCarlo { runs, seed, record, shape_intervals_s, true_order, true_bn_hz, stats, per_run, failed })
}

/// RMS of a sample (`None`: empty).
fn rms(x: impl Iterator<Item = f64>) -> Option<f64> {
    let (n, sum) = x.fold((0usize, 0.0), |(n, s), v| (n + 1, s + v * v));
    (n > 0).then(|| (sum / n as f64).sqrt())
}

/// The statistics of `runs` against the scenario's loop `truth`.
pub fn identified_stats(runs: &[IdentifiedRun], truth: &LoopSection) -> IdentifiedStats {
    let (true_order, true_bn_hz) = (truth.order, truth.bn_hz);
    let per_axis = |f: &dyn Fn(&IdentifiedRun, usize) -> f64| {
        [0, 1, 2].map(|i| rms(runs.iter().map(|r| f(r, i))).unwrap_or(f64::NAN))
    };
    let err = |r: &IdentifiedRun, i: usize| r.gamma_hz_per_mps2[i] - r.gamma_imu_axes_hz_per_mps2[i];
    let known_err = |r: &IdentifiedRun, i: usize| r.known_gamma_hz_per_mps2[i] - r.gamma_imu_axes_hz_per_mps2[i];
    let rmse = per_axis(&err);
    let known_rmse = per_axis(&known_err);
    let known_crlb = per_axis(&|r, i| r.known_crlb_hz_per_mps2[i]);
    let resolved = runs.iter().filter(|r| r.identified.resolution == LoopResolution::Resolved).count();
    let compared: Vec<&IdentifiedLoop> = runs
        .iter()
        .map(|r| &r.identified)
        .filter(|id| id.resolution == LoopResolution::Resolved && id.order == true_order)
        .collect();
    let n = runs.len() as f64;
    IdentifiedStats {
        runs: runs.len(),
        bias: [0, 1, 2].map(|i| runs.iter().map(|r| err(r, i)).sum::<f64>() / n),
        rmse,
        known_crlb,
        rmse_over_known_crlb: [0, 1, 2].map(|i| rmse[i] / known_crlb[i]),
        z_rms: per_axis(&|r, i| err(r, i) / r.sigma_hz_per_mps2[i]),
        known_rmse_over_known_crlb: [0, 1, 2].map(|i| known_rmse[i] / known_crlb[i]),
        known_z_rms: per_axis(&|r, i| known_err(r, i) / r.known_sigma_hz_per_mps2[i]),
        bn_resolved: resolved,
        bn_compared: compared.len(),
        bn_relative_error_rms: rms(compared.iter().map(|id| id.bn_hz / true_bn_hz - 1.0)),
        bn_z_rms: rms(compared.iter().map(|id| (id.bn_hz / true_bn_hz).ln() / id.sigma_ln_bn)),
        order_resolved: runs.iter().filter(|r| r.identified.order_resolved).count(),
        order_right: runs.iter().filter(|r| r.identified.order_resolved && r.identified.order == true_order).count(),
        interval_right: runs.iter().filter(|r| same_interval(r.identified.loop_interval_s, truth.interval_s)).count(),
    }
}
