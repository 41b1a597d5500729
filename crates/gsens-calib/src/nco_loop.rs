//! The estimate from the NCO's frequency with the receiver's loop
//! identified from the session: for receivers that log the frequency their
//! NCO ran at (or a Doppler) but do not publish their loop.
//!
//! The common mode of the NCO frequency is −H[aᵀΓ] ([`crate::estimate_nco_frequency`]),
//! and H depends on the loop. For each loop shape tried (a 2nd-order loop of
//! ζ = 1/√2, Kaplan's 3rd-order loop) the noise bandwidth is searched: Γ is
//! fitted (offset searched as asked) on a grid of Bn from
//! [`IDENTIFY_BN_RANGE_HZ`]'s low end to its high end, 25 % apart, and the
//! grid point of least innovation variance σ² is refined by Gauss–Newton
//! steps in θ = ln Bn ([`crate::loop_free`]'s scaled fit, which linearizes
//! the regressor in θ). The shape of least σ² is kept (both have one
//! parameter, so −2 ln L = N·ln σ² compares them as it is).
//!
//! Γ̂'s covariance carries the loop's uncertainty: the Γ block of the joint
//! covariance of (Γ, θ), the conditional one plus g·gᵀ·var(θ̂) with
//! g = ∂Γ̂/∂θ. Where the least σ² lies at an end of the grid the
//! linearization does not hold (the likelihood is one-sided: for a wide loop
//! H ≈ 1 in the shaking's band, and every wider loop fits as well): the
//! bandwidth is then reported as a bound, and the spread of Γ̂ over the grid
//! points within Δ(−2 ln L) ≤ 1 of the best is added to its variance.

use crate::loop_free::{
    InputPhases, LoopFreeError, LoopFreeEstimate, LoopFreeSettings, check_settings, fit_rows, fit_rows_scaled,
    median_step,
};
use crate::nco_frequency::{ModelRegressor, frequency_on_epochs};
use gsens_core::{LoopModel, LoopSpec, RegressorModel, RowQuantity};
use gsens_io::{ImuSeries, TrackingLog};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// The noise bandwidths the identification searches \[Hz\]: from loops
/// narrower than receivers run on a moving platform to loops whose H is 1
/// within 0.1 % up to a few hertz of shaking.
pub const IDENTIFY_BN_RANGE_HZ: [f64; 2] = [1.0, 60.0];

/// The model loops' largest Bn·T: the candidates run near their continuous
/// limit, whatever the receiver's (unknown) update interval.
const MAX_BN_T: f64 = 0.02;

/// Gauss–Newton steps of θ = ln Bn after the grid.
const REFINE_STEPS: usize = 4;

/// Where the identified loop lies.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
#[non_exhaustive]
pub enum LoopResolution {
    /// Inside the searched range: Bn with its σ.
    Resolved,
    /// At the wide end: H ≈ 1 in the shaking's band; Bn is a lower bound.
    Wide,
    /// At the narrow end: Bn is an upper bound.
    Narrow,
}

/// One loop shape's best fit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[non_exhaustive]
pub struct ShapeFit {
    /// The loop's order (2 or 3).
    pub order: u8,
    /// Its best noise bandwidth \[Hz\].
    pub bn_hz: f64,
    /// The innovation variance of the fit there \[Hz²\].
    pub innovation_variance_hz2: f64,
}

/// The loop the NCO frequency was seen through, as the session identified it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[non_exhaustive]
pub struct IdentifiedLoop {
    /// The loop kept (its shape scaled to the fitted Bn; model interval
    /// chosen so that Bn·T ≤ 0.02).
    #[serde(skip)]
    pub model: Option<LoopModel>,
    /// Its order.
    pub order: u8,
    /// Whether the other shapes fit clearly worse (Δ(−2 ln L) > 1); where
    /// not, the spread of their Γ̂ is in Γ̂'s variance, and Bn is the kept
    /// shape's.
    pub order_resolved: bool,
    /// Its noise bandwidth Bn \[Hz\] (a bound where not resolved).
    pub bn_hz: f64,
    /// 1σ of ln Bn (the relative 1σ of Bn; infinite where not resolved).
    pub sigma_ln_bn: f64,
    /// Where it lies in the searched range.
    pub resolution: LoopResolution,
    /// Every shape's best fit.
    pub shapes: Vec<ShapeFit>,
}

/// The estimate from the NCO frequency with its loop identified.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct IdentifiedNcoEstimate {
    /// Γ̂ with the loop's uncertainty in its covariance.
    pub estimate: LoopFreeEstimate,
    /// The loop.
    pub identified: IdentifiedLoop,
}

/// The loop shapes the identification tries: a 2nd-order loop of ζ = 1/√2
/// and Kaplan's 3rd-order loop (their Bn is searched).
pub fn identification_shapes() -> [LoopSpec; 2] {
    [LoopSpec::PAPER, LoopSpec::third_order_kaplan(gsens_core::defaults::DEFAULT_BN_HZ)]
}

/// Estimates Γ from the NCO's frequency with the loop identified (see the
/// module documentation) among `shapes` (their Bn is searched).
pub fn estimate_nco_frequency_identified(
    tracking: &TrackingLog,
    imu: &ImuSeries,
    settings: &LoopFreeSettings,
    shapes: &[LoopSpec],
) -> Result<IdentifiedNcoEstimate, LoopFreeError> {
    check_settings(settings)?;
    let epochs = tracking.epoch_t_s();
    let log_interval_s = median_step(epochs);
    let tracks: Vec<_> = tracking.tracks().iter().filter(|t| !t.nco_freq_hz.is_empty()).collect();
    if tracks.is_empty() {
        return Err(LoopFreeError::NoNcoFrequency { source_name: tracking.source_name().to_owned() });
    }
    let rows = InputPhases::of_tracks(epochs, &tracks, |tr| frequency_on_epochs(tr, epochs, settings));
    // Every candidate's model starts this long before the first epoch, so
    // that all are fitted on the same epochs: the narrowest's settling
    // (2nd order: 5τ = 5/(ζωn) ≈ 3.75/Bn).
    let lead_s = settings.warmup_s.max(4.0 / IDENTIFY_BN_RANGE_HZ[0]);
    let (bn_lo, bn_hi) = (IDENTIFY_BN_RANGE_HZ[0], IDENTIFY_BN_RANGE_HZ[1]);
    let grid: Vec<f64> = (0..).map(|k| bn_lo * 1.25f64.powi(k)).take_while(|bn| *bn <= bn_hi * 1.0001).collect();
    // The model interval: Bn·T ≤ MAX_BN_T for the widest loop a step may reach.
    let substeps = ((log_interval_s * bn_hi * 1.5 / MAX_BN_T).ceil() as usize).max(1);
    let loop_interval_s = log_interval_s / substeps as f64;
    let model_at = |shape: &LoopSpec, ln_bn: f64| -> Result<ModelRegressor<'_>, LoopFreeError> {
        let base = LoopModel::Kaplan { spec: *shape, interval_s: Some(loop_interval_s) };
        let bn0 = base.bn_hz().unwrap_or(gsens_core::defaults::DEFAULT_BN_HZ);
        let scaled = base.with_bn_scaled(ln_bn.exp() / bn0);
        let runnable = scaled.runnable().map_err(|e| LoopFreeError::Loop { why: e.to_string() })?;
        let model = RegressorModel::of_quantity(runnable, loop_interval_s, log_interval_s, RowQuantity::NcoFrequency)
            .map_err(|_| LoopFreeError::Intervals { log_interval_s, loop_interval_s })?;
        Ok(ModelRegressor::new(epochs, log_interval_s, imu, model, lead_s))
    };
    let mut candidates = Vec::new();
    let mut shape_fits = Vec::new();
    for shape in shapes {
        let profile: Vec<Result<LoopFreeEstimate, LoopFreeError>> =
            grid.par_iter().map(|bn| fit_rows(&rows, &model_at(shape, bn.ln())?, settings, f64::INFINITY)).collect();
        let profile: Vec<LoopFreeEstimate> = profile.into_iter().collect::<Result<_, _>>()?;
        let candidate = refine(&rows, shape, &grid, &profile, |ln_bn| model_at(shape, ln_bn), settings)?;
        shape_fits.push(ShapeFit {
            order: shape.order(),
            bn_hz: candidate.bn_hz,
            innovation_variance_hz2: candidate.estimate.residual_variance_rad2,
        });
        candidates.push(candidate);
    }
    let score = |c: &Candidate| c.estimate.residual_variance_rad2;
    let Some(k_best) = (0..candidates.len()).min_by(|&a, &b| score(&candidates[a]).total_cmp(&score(&candidates[b])))
    else {
        return Err(LoopFreeError::Loop { why: "no loop shape to identify".into() });
    };
    // Shapes the data cannot tell from the best (Δ(−2 ln L) ≤ 1): their Γ̂
    // are as likely, so their spread joins Γ̂'s variance and the order is
    // not resolved.
    let n = candidates[k_best].estimate.epochs as f64;
    let alike: Vec<usize> = (0..candidates.len())
        .filter(|&k| k != k_best && n * (score(&candidates[k]) / score(&candidates[k_best])).ln() <= 1.0)
        .collect();
    let others: Vec<[f64; 3]> = alike.iter().map(|&k| candidates[k].estimate.gamma_hz_per_mps2).collect();
    let mut c = candidates.swap_remove(k_best);
    for g in &others {
        for i in 0..3 {
            let spread = (g[i] - c.estimate.gamma_hz_per_mps2[i]).powi(2);
            c.estimate.covariance[i][i] += spread;
        }
    }
    let model = LoopModel::Kaplan { spec: c.shape, interval_s: Some(loop_interval_s) };
    let bn0 = model.bn_hz().unwrap_or(gsens_core::defaults::DEFAULT_BN_HZ);
    let mut estimate = c.estimate;
    estimate.loop_interval_s = loop_interval_s;
    Ok(IdentifiedNcoEstimate {
        estimate,
        identified: IdentifiedLoop {
            model: Some(model.with_bn_scaled(c.bn_hz / bn0)),
            order: c.shape.order(),
            order_resolved: others.is_empty(),
            bn_hz: c.bn_hz,
            sigma_ln_bn: c.sigma_ln_bn,
            resolution: c.resolution,
            shapes: shape_fits,
        },
    })
}

/// One shape's identified loop and estimate.
struct Candidate {
    shape: LoopSpec,
    bn_hz: f64,
    sigma_ln_bn: f64,
    resolution: LoopResolution,
    estimate: LoopFreeEstimate,
}

/// The shape's best Bn from its profile over `grid`: Gauss–Newton steps
/// from the best grid point when it is inside the grid, the one-sided
/// bound when it is at an end (module documentation).
fn refine<'a>(
    rows: &InputPhases,
    shape: &LoopSpec,
    grid: &[f64],
    profile: &[LoopFreeEstimate],
    at: impl Fn(f64) -> Result<ModelRegressor<'a>, LoopFreeError> + Sync,
    settings: &LoopFreeSettings,
) -> Result<Candidate, LoopFreeError> {
    let score = |e: &LoopFreeEstimate| e.residual_variance_rad2;
    let k_best = (0..grid.len()).min_by(|&a, &b| score(&profile[a]).total_cmp(&score(&profile[b]))).unwrap_or(0);
    let best = &profile[k_best];
    let n = best.epochs as f64;
    // The grid points the data cannot tell from the best (Δ(−2 ln L) ≤ 1).
    let alike: Vec<usize> = (0..grid.len()).filter(|&k| n * (score(&profile[k]) / score(best)).ln() <= 1.0).collect();
    let step_limit = 1.25f64.ln();
    let h = 0.05;
    let at_an_end = alike.contains(&0) || alike.contains(&(grid.len() - 1));
    if !at_an_end {
        let mut ln_bn = grid[k_best].ln();
        let mut fit = fit_rows_scaled(rows, &at, ln_bn, h, settings)?;
        for _ in 0..REFINE_STEPS {
            let step = fit.step_ln_scale.clamp(-step_limit, step_limit);
            if step.abs() < 1e-3 {
                break;
            }
            let next = fit_rows_scaled(rows, &at, ln_bn + step, h, settings)?;
            // Keep a step only where it lowers the residual.
            if score(&next.estimate) > score(&fit.estimate) {
                break;
            }
            (ln_bn, fit) = (ln_bn + step, next);
        }
        let inside = ln_bn > grid[0].ln() && ln_bn < grid[grid.len() - 1].ln();
        if inside && fit.var_ln_scale.is_finite() {
            return Ok(Candidate {
                shape: *shape,
                bn_hz: ln_bn.exp(),
                sigma_ln_bn: fit.var_ln_scale.sqrt(),
                resolution: LoopResolution::Resolved,
                estimate: fit.estimate,
            });
        }
    }
    // Not resolved: Γ̂ of the best point, its variance widened by the spread
    // of the estimates the data cannot tell from it.
    let mut estimate = best.clone();
    for e in alike.iter().map(|&k| &profile[k]) {
        for i in 0..3 {
            let spread = (e.gamma_hz_per_mps2[i] - best.gamma_hz_per_mps2[i]).powi(2);
            estimate.covariance[i][i] = estimate.covariance[i][i].max(best.covariance[i][i] + spread);
        }
    }
    // The bound: the Bn farthest from the end the data cannot tell apart from the best.
    let alike_bn = alike.iter().map(|&k| grid[k]);
    let (resolution, bn_hz) = if alike.contains(&(grid.len() - 1)) || 2 * k_best >= grid.len() {
        (LoopResolution::Wide, alike_bn.fold(grid[k_best], f64::min))
    } else {
        (LoopResolution::Narrow, alike_bn.fold(grid[k_best], f64::max))
    };
    Ok(Candidate { shape: *shape, bn_hz, sigma_ln_bn: f64::INFINITY, resolution, estimate })
}
