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
//! the regressor in θ). H = 1 (a corrected carrier phase, or a loop wider
//! than the search; [`estimate_nco_frequency_unity`]) competes as a
//! candidate of its own. The candidates are compared under one noise model
//! by N·ln σ² + ln N per fitted bandwidth (Schwarz's criterion), each
//! weighted by exp(−Δ/2): the best is kept, the weighted spread of the
//! others' Γ̂ joins its variance, and that variance reaches the Γ̂ of every
//! candidate within Δ ≤ 1 of the best. At one shaking rate the update
//! interval trades with the bandwidth and the time offset: a 3 Hz loop
//! updated every 20 ms and every 1 ms fit a session alike (Δ of a few
//! tenths) with Γ̂ 3–4 % apart, and only the second rule covers the truth
//! when it lies at the far end of the intervals tried. The kept shape's Γ̂
//! at its bandwidth's ±1σ is covered the same way, where Γ̂ bends over that
//! range more than the linear term below says.
//!
//! Γ̂'s covariance carries the loop's uncertainty: the Γ block of the joint
//! covariance of (Γ, θ), the conditional one plus g·gᵀ·var(θ̂) with
//! g = ∂Γ̂/∂θ. Where the least σ² lies at an end of the grid the
//! linearization does not hold (the likelihood is one-sided: for a wide loop
//! H ≈ 1 in the shaking's band, and every wider loop fits as well): the
//! bandwidth is then reported as a bound, and the spread of Γ̂ over the grid
//! points within Δ(−2 ln L) ≤ 1 of the best is added to its variance.

use crate::loop_free::RowRegressor;
use crate::loop_free::{
    InputPhases, LoopFreeError, LoopFreeEstimate, LoopFreeSettings, check_settings, fit_rows, fit_rows_scaled,
    integrated_phase_rad, median_step, rows_noise, rows_score,
};
use crate::nco_frequency::{ModelRegressor, frequency_on_epochs, loop_regressor, mean_frequency_on_epochs};
use gsens_core::{LoopModel, LoopSpec, RowQuantity};
use gsens_io::{ImuSeries, TrackingLog};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// The noise bandwidths the identification searches \[Hz\]: from loops
/// narrower than receivers run on a moving platform to loops whose H is 1
/// within 0.1 % up to a few hertz of shaking.
pub const IDENTIFY_BN_RANGE_HZ: [f64; 2] = [1.0, 60.0];

/// The update intervals the identification tries \[s\] (those that divide
/// the log interval): receivers update their carrier loops every 1 to 20 ms,
/// and at Bn·T of a few hundredths the discrete loop's response already
/// departs from the continuous one by more than a delay.
pub const IDENTIFY_INTERVALS_S: [f64; 5] = [0.001, 0.002, 0.005, 0.01, 0.02];

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
    /// Its update interval \[s\].
    pub loop_interval_s: f64,
    /// Its best noise bandwidth \[Hz\].
    pub bn_hz: f64,
    /// The innovation variance of the fit there \[Hz²\].
    pub innovation_variance_hz2: f64,
}

/// The loop the NCO frequency was seen through, as the session identified it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[non_exhaustive]
pub struct IdentifiedLoop {
    /// The loop kept (its shape scaled to the fitted Bn).
    #[serde(skip)]
    pub model: Option<LoopModel>,
    /// Its order.
    pub order: u8,
    /// Its update interval \[s\].
    pub loop_interval_s: f64,
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
    /// The update intervals \[s\] of the shapes that fit as well as the kept
    /// one (Δ(−2 ln L) ≤ 1), the kept one's among them, shortest first: more
    /// than one where the session cannot tell the receiver's update interval,
    /// whose Γ̂ are then all within Γ̂'s 1σ.
    #[serde(default)]
    pub alike_intervals_s: Vec<f64>,
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
    /// The fit with H = 1 ([`estimate_nco_frequency_unity`]), where it
    /// competed (not when a single shape was given).
    pub unity: Option<LoopFreeEstimate>,
}

/// The loop shapes the identification tries for a log every
/// `log_interval_s`: a 2nd-order loop of ζ = 1/√2 and Kaplan's 3rd-order
/// loop, each updated at every interval of [`IDENTIFY_INTERVALS_S`] that
/// divides the log interval (their Bn is searched).
pub fn identification_shapes(log_interval_s: f64) -> Vec<LoopModel> {
    let specs = [LoopSpec::PAPER, LoopSpec::third_order_kaplan(gsens_core::defaults::DEFAULT_BN_HZ)];
    specs
        .iter()
        .flat_map(|spec| {
            IDENTIFY_INTERVALS_S
                .iter()
                .filter(|&&t| gsens_core::loop_substeps(t, log_interval_s).is_ok())
                .map(|&t| LoopModel::Kaplan { spec: *spec, interval_s: Some(t) })
        })
        .collect()
}

/// Which of the NCO's records the rows are made of.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
#[non_exhaustive]
pub enum NcoRecord {
    /// `nco_freq_hz`: the command in force during the row's latest update
    /// ([`RowQuantity::NcoFrequency`]).
    Command,
    /// `nco_phase_cycles` differenced between consecutive rows: the mean
    /// command over the log interval ([`RowQuantity::NcoFrequencyMean`]), as
    /// a carrier phase differenced or a Doppler averaged over the interval.
    /// It averages the loop's thermal noise over the interval's updates.
    PhaseDifference,
}

impl NcoRecord {
    /// What a row made of this record holds.
    pub fn quantity(self) -> RowQuantity {
        match self {
            NcoRecord::Command => RowQuantity::NcoFrequency,
            NcoRecord::PhaseDifference => RowQuantity::NcoFrequencyMean,
        }
    }
}

/// Each track's NCO frequency on the log's epochs \[Hz\] from the record
/// `record` names (tracks without it left out; rows in the warm-up or with
/// |φ| past the settings' limit `None`), with what a row holds
/// ([`NcoRecord::quantity`]): the rows [`estimate_nco_frequency_identified_from`]
/// and [`crate::estimate_nco_frequency_from`] fit.
pub fn nco_rows(
    tracking: &TrackingLog,
    settings: &LoopFreeSettings,
    record: NcoRecord,
) -> Result<(InputPhases, RowQuantity), LoopFreeError> {
    check_settings(settings)?;
    let epochs = tracking.epoch_t_s();
    let source_name = tracking.source_name().to_owned();
    let has_record = |t: &&gsens_io::ChannelTrack| match record {
        NcoRecord::Command => !t.nco_freq_hz.is_empty(),
        NcoRecord::PhaseDifference => !t.nco_phase_cycles.is_empty(),
    };
    let tracks: Vec<_> = tracking.tracks().iter().filter(has_record).collect();
    if tracks.is_empty() {
        return Err(match record {
            NcoRecord::Command => LoopFreeError::NoNcoFrequency { source_name },
            NcoRecord::PhaseDifference => LoopFreeError::NoNcoPhase { source_name },
        });
    }
    let rows = InputPhases::of_tracks(epochs, &tracks, |tr| match record {
        NcoRecord::Command => frequency_on_epochs(tr, epochs, settings),
        NcoRecord::PhaseDifference => mean_frequency_on_epochs(tr, epochs, settings),
    });
    Ok((rows, record.quantity()))
}

/// Estimates Γ from the NCO's frequency with the loop identified (see the
/// module documentation) among `shapes` (their Bn is searched), from the
/// rows `record` says.
pub fn estimate_nco_frequency_identified(
    tracking: &TrackingLog,
    imu: &ImuSeries,
    settings: &LoopFreeSettings,
    shapes: &[LoopModel],
    record: NcoRecord,
) -> Result<IdentifiedNcoEstimate, LoopFreeError> {
    let (rows, quantity) = nco_rows(tracking, settings, record)?;
    estimate_nco_frequency_identified_from(&rows, imu, settings, shapes, quantity)
}

/// [`estimate_nco_frequency_identified`] from frequency rows a receiver's
/// adapter made (each track's NCO frequency on the common epochs \[Hz\], in
/// [`InputPhases`]'s value field, with the receiver's sign: the common mode
/// −H\[aᵀΓ\]): `quantity` says what a row holds,
/// [`RowQuantity::NcoFrequency`] or [`RowQuantity::NcoFrequencyMean`].
pub fn estimate_nco_frequency_identified_from(
    rows: &InputPhases,
    imu: &ImuSeries,
    settings: &LoopFreeSettings,
    shapes: &[LoopModel],
    quantity: RowQuantity,
) -> Result<IdentifiedNcoEstimate, LoopFreeError> {
    check_settings(settings)?;
    let epochs = rows.epoch_t_s.as_slice();
    let log_interval_s = median_step(epochs);
    let lead_s = identification_lead_s(settings);
    let (bn_lo, bn_hi) = (IDENTIFY_BN_RANGE_HZ[0], IDENTIFY_BN_RANGE_HZ[1]);
    let grid: Vec<f64> = (0..).map(|k| bn_lo * 1.25f64.powi(k)).take_while(|bn| *bn <= bn_hi * 1.0001).collect();
    let model_at = |shape: &LoopModel, ln_bn: f64| model_regressor(epochs, imu, shape, ln_bn, quantity, lead_s);
    let mut candidates = Vec::new();
    let mut shape_fits = Vec::new();
    for shape in shapes {
        // The bandwidths at which the shape's discrete loop is stable (with room for a refining step).
        let stable = |bn: f64| model_at(shape, (bn * 1.25).ln()).is_ok();
        let grid: Vec<f64> = grid.iter().copied().filter(|&bn| stable(bn)).collect();
        if grid.len() < 3 {
            continue;
        }
        let profile: Vec<Result<LoopFreeEstimate, LoopFreeError>> =
            grid.par_iter().map(|bn| fit_rows(rows, &model_at(shape, bn.ln())?, settings, f64::INFINITY)).collect();
        let profile: Vec<LoopFreeEstimate> = profile.into_iter().collect::<Result<_, _>>()?;
        let candidate = refine(rows, shape, &grid, &profile, |ln_bn| model_at(shape, ln_bn), settings)?;
        shape_fits.push(ShapeFit {
            order: shape.order(),
            loop_interval_s: shape.interval_s().unwrap_or(log_interval_s),
            bn_hz: candidate.bn_hz,
            innovation_variance_hz2: candidate.estimate.residual_variance_rad2,
        });
        candidates.push(candidate);
    }
    // H = 1 (a carrier phase the receiver corrects, or a loop wider than
    // the search) as a candidate of its own, without a bandwidth: a truth at
    // the range's wide end is approached by the shapes from one side only
    // (their |H| > 1 below ωn), so it must compete as itself.
    let mut unity = None;
    if shapes.len() > 1
        && let Some(shape) = unity_shape(log_interval_s)
    {
        let estimate = estimate_nco_frequency_unity(rows, imu, settings, quantity)?;
        unity = Some(estimate.clone());
        candidates.push(Candidate {
            shape,
            bn_hz: bn_hi,
            sigma_ln_bn: f64::INFINITY,
            resolution: LoopResolution::Wide,
            estimate,
            unity: true,
        });
    }
    let own_score = |c: &Candidate| c.estimate.residual_variance_rad2;
    let Some(k_first) =
        (0..candidates.len()).min_by(|&a, &b| own_score(&candidates[a]).total_cmp(&own_score(&candidates[b])))
    else {
        return Err(LoopFreeError::Loop { why: "no loop shape to identify".into() });
    };
    // The shapes compared under one noise model (the provisional best's):
    // each fit's own AR model would move its σ² by the choice of its order.
    let regressor_of = |c: &Candidate| model_at(&c.shape, c.bn_hz.ln());
    let noise = rows_noise(rows, &regressor_of(&candidates[k_first])?, settings)?;
    let scores: Vec<f64> = candidates
        .par_iter()
        .map(|c| rows_score(rows, &regressor_of(c)?, settings, c.estimate.imu_time_offset_s, &noise))
        .collect::<Result<_, _>>()?;
    // −2 ln L + ln N per parameter (Schwarz's criterion, the marginal
    // likelihood's approximation): a shape's bandwidth is one parameter more
    // than H = 1 has. Akaike's 2 per parameter is too little against the
    // best of ten shapes, each fitting the noise with its own bandwidth.
    let n = candidates[k_first].estimate.epochs as f64;
    let totals: Vec<f64> =
        candidates.iter().zip(&scores).map(|(c, s)| n * s.ln() + if c.unity { 0.0 } else { n.ln() }).collect();
    let k_best = (0..candidates.len()).min_by(|&a, &b| totals[a].total_cmp(&totals[b])).unwrap_or(k_first);
    // Each candidate's weight exp(−Δ/2): the spread of the candidates' Γ̂
    // about the best one's, so weighted, joins Γ̂'s variance, and the order
    // is resolved when the other order's shapes (and H = 1) weigh under 5 %.
    let weights: Vec<f64> = totals.iter().map(|t| (-0.5 * (t - totals[k_best])).exp()).collect();
    let total: f64 = weights.iter().sum();
    let gammas: Vec<[f64; 3]> = candidates.iter().map(|c| c.estimate.gamma_hz_per_mps2).collect();
    let spread = crate::joint::weighted_spread(&weights, &gammas, candidates[k_best].estimate.gamma_hz_per_mps2);
    let order_best = candidates[k_best].shape.order();
    let other_order: f64 = candidates
        .iter()
        .zip(&weights)
        .filter(|(c, _)| c.shape.order() != order_best || c.unity)
        .map(|(_, w)| w)
        .sum::<f64>();
    let order_resolved = !candidates[k_best].unity && other_order / total < 0.05;
    // H = 1 best: the loop is at least as wide as the narrowest candidate of
    // any weight (5 % of the total) says.
    let wide_bound_hz = candidates
        .iter()
        .zip(&weights)
        .filter(|(_, w)| **w / total >= 0.05)
        .map(|(c, _)| c.bn_hz)
        .fold(bn_hi, f64::min);
    // Bn trades with the update interval: the spread of ln Bn over the
    // shapes of the same order, so weighted, joins its variance.
    let ln_bn_best = candidates[k_best].bn_hz.ln();
    let same_order = candidates.iter().zip(&weights).filter(|(c, _)| c.shape.order() == order_best && !c.unity);
    let (w_sum, w_spread) =
        same_order.fold((0.0, 0.0), |(ws, sp), (c, w)| (ws + w, sp + w * (c.bn_hz.ln() - ln_bn_best).powi(2)));
    // The candidates the data cannot tell from the best (Δ ≤ 1), each
    // covered by Γ̂'s variance as the grid's points are within a shape
    // ([`cover_alike`]): their weighted spread alone leaves an end of the
    // candidates' range uncovered when the best lies at the other end and
    // the candidates between share their weight (a loop's update interval
    // trades with its bandwidth and the time offset at one shaking rate).
    let is_alike = |t: &f64| *t - totals[k_best] <= 1.0;
    let alike: Vec<[f64; 3]> = candidates
        .iter()
        .zip(&totals)
        .filter(|(_, t)| is_alike(t))
        .map(|(c, _)| c.estimate.gamma_hz_per_mps2)
        .collect();
    let mut alike_intervals_s: Vec<f64> = candidates
        .iter()
        .zip(&totals)
        .filter(|(c, t)| !c.unity && is_alike(t))
        .map(|(c, _)| c.shape.interval_s().unwrap_or(log_interval_s))
        .collect();
    alike_intervals_s.sort_by(f64::total_cmp);
    alike_intervals_s.dedup();
    let mut c = candidates.swap_remove(k_best);
    // The bandwidth's 1σ ends (Δ(−2 ln L) = 1 on its profile): Γ̂ there
    // covered too. The linear term g·gᵀ·var(θ̂) falls short where Γ̂ bends
    // over ±σ of ln Bn, as it does when the rows are the loop's command
    // sampled once per row and Bn is known to 20–30 % only.
    if !c.unity && c.resolution == LoopResolution::Resolved && c.sigma_ln_bn.is_finite() {
        let ln_bn = c.bn_hz.ln();
        let ends: Vec<Option<LoopFreeEstimate>> = [ln_bn - c.sigma_ln_bn, ln_bn + c.sigma_ln_bn]
            .par_iter()
            .map(|&t| model_at(&c.shape, t).and_then(|m| fit_rows(rows, &m, settings, f64::INFINITY)).ok())
            .collect();
        cover_alike(&mut c.estimate, ends.iter().flatten().map(|e| (e.gamma_hz_per_mps2, e.covariance)));
    }
    let own_covariance = c.estimate.covariance;
    if c.unity {
        c.bn_hz = wide_bound_hz;
    } else {
        c.sigma_ln_bn = (c.sigma_ln_bn.powi(2) + w_spread / w_sum).sqrt();
    }
    for (i, s) in spread.iter().enumerate() {
        c.estimate.covariance[i][i] += s;
    }
    cover_alike(&mut c.estimate, alike.iter().map(|g| (*g, own_covariance)));
    let bn0 = c.shape.bn_hz().unwrap_or(gsens_core::defaults::DEFAULT_BN_HZ);
    let loop_interval_s = c.shape.interval_s().unwrap_or(log_interval_s);
    let mut estimate = c.estimate;
    estimate.loop_interval_s = loop_interval_s;
    Ok(IdentifiedNcoEstimate {
        estimate,
        identified: IdentifiedLoop {
            model: Some(if c.unity { c.shape } else { c.shape.with_bn_scaled(c.bn_hz / bn0) }),
            order: c.shape.order(),
            loop_interval_s,
            order_resolved,
            bn_hz: c.bn_hz,
            sigma_ln_bn: c.sigma_ln_bn,
            resolution: c.resolution,
            alike_intervals_s,
            shapes: shape_fits,
        },
        unity,
    })
}

/// How long before the first epoch every candidate's model starts \[s\], so
/// that all are fitted on the same epochs: the narrowest's settling (2nd
/// order: 5τ = 5/(ζωn) ≈ 3.75/Bn).
fn identification_lead_s(settings: &LoopFreeSettings) -> f64 {
    settings.warmup_s.max(4.0 / IDENTIFY_BN_RANGE_HZ[0])
}

/// The regressor of `quantity` on `epochs` through `shape` scaled to the
/// noise bandwidth e^`ln_bn`, its model started `lead_s` before each epoch
/// it is read at.
fn model_regressor<'a>(
    epochs: &[f64],
    imu: &'a ImuSeries,
    shape: &LoopModel,
    ln_bn: f64,
    quantity: RowQuantity,
    lead_s: f64,
) -> Result<ModelRegressor<'a>, LoopFreeError> {
    let bn0 = shape.bn_hz().unwrap_or(gsens_core::defaults::DEFAULT_BN_HZ);
    loop_regressor(epochs, imu, &shape.with_bn_scaled(ln_bn.exp() / bn0), quantity, lead_s)
}

/// The estimate from frequency rows with H = 1 in the shaking's band: the
/// fit under the widest loop of the identification's range
/// ([`IDENTIFY_BN_RANGE_HZ`]'s high end, 2nd order, at the shortest update
/// interval of [`identification_shapes`]), whose |H| departs from 1 by
/// under 0.1 % up to a few hertz. What a receiver's log gives when its
/// carrier phase is corrected by the discriminator, or its loop is wide.
pub fn estimate_nco_frequency_unity(
    rows: &InputPhases,
    imu: &ImuSeries,
    settings: &LoopFreeSettings,
    quantity: RowQuantity,
) -> Result<LoopFreeEstimate, LoopFreeError> {
    check_settings(settings)?;
    let epochs = rows.epoch_t_s.as_slice();
    let Some(shape) = unity_shape(median_step(epochs)) else {
        return Err(LoopFreeError::Loop { why: "no update interval divides the log interval".into() });
    };
    let regressor =
        model_regressor(epochs, imu, &shape, IDENTIFY_BN_RANGE_HZ[1].ln(), quantity, identification_lead_s(settings))?;
    fit_rows(rows, &regressor, settings, f64::INFINITY)
}

/// The loop whose H stands for 1 ([`estimate_nco_frequency_unity`]): the
/// first shape of [`identification_shapes`] (2nd order, the shortest update
/// interval) at the top of [`IDENTIFY_BN_RANGE_HZ`].
fn unity_shape(log_interval_s: f64) -> Option<LoopModel> {
    let shape = *identification_shapes(log_interval_s).first()?;
    let bn0 = shape.bn_hz().unwrap_or(gsens_core::defaults::DEFAULT_BN_HZ);
    Some(shape.with_bn_scaled(IDENTIFY_BN_RANGE_HZ[1] / bn0))
}

/// What compensating with `estimate`'s Γ̂ does, through the `identified`
/// loop: the common mode of the rows integrated to carrier phase before and
/// after ([`crate::loop_free`]'s integrated phase: its RMS, and the series
/// on the rows' epochs), and the largest tracking error |φ_aᵀΓ̂| the loop
/// predicts on the rows' epochs, φ_a the regressor of the discriminator
/// output ([`RowQuantity::PhaseError`]).
pub(crate) fn identified_figures(
    rows: &InputPhases,
    imu: &ImuSeries,
    settings: &LoopFreeSettings,
    identified: &LoopModel,
    estimate: &LoopFreeEstimate,
    quantity: RowQuantity,
) -> Result<(crate::estimate::ResidualFigures, CompensatedCarrierPhase), LoopFreeError> {
    let epochs = rows.epoch_t_s.as_slice();
    let (tau, gamma) = (estimate.imu_time_offset_s, estimate.gamma_hz_per_mps2);
    let ln_bn = identified.bn_hz().unwrap_or(gsens_core::defaults::DEFAULT_BN_HZ).ln();
    let lead_s = identification_lead_s(settings);
    let rows_regressor = model_regressor(epochs, imu, identified, ln_bn, quantity, lead_s)?;
    let series = integrated_phase_rad(rows, &rows_regressor, settings, tau, &gamma)?;
    if series.is_empty() {
        return Err(LoopFreeError::TooFewEpochs { epochs: 0, segment_s: settings.segment_s });
    }
    let rms = |i: usize| (series.iter().map(|(_, v)| v[i] * v[i]).sum::<f64>() / series.len() as f64).sqrt();
    let mut carrier_phase = CompensatedCarrierPhase {
        t_s: epochs.to_vec(),
        before_rad: vec![None; epochs.len()],
        after_rad: vec![None; epochs.len()],
    };
    for (k, v) in &series {
        (carrier_phase.before_rad[*k], carrier_phase.after_rad[*k]) = (Some(v[0]), Some(v[1]));
    }
    let tracking_error = RowQuantity::PhaseError(gsens_core::LoggedPhase::Last);
    let regressor = model_regressor(epochs, imu, identified, ln_bn, tracking_error, lead_s)?;
    let at: Vec<usize> = (0..epochs.len()).filter(|&k| regressor.covers(k, tau)).collect();
    let peak = regressor
        .values(&at, tau)
        .iter()
        .map(|x| (x[0] * gamma[0] + x[1] * gamma[1] + x[2] * gamma[2]).abs())
        .fold(0.0, f64::max);
    let figures = crate::estimate::ResidualFigures {
        rms_before_rad: rms(0),
        rms_after_rad: rms(1),
        rms_g_induced_rad: rms(2),
        peak_phase_err_rad: peak,
    };
    Ok((figures, carrier_phase))
}

/// The receiver's carrier phase as compensation changes it: the common mode
/// of the tracks' rows integrated, 2π·Σ f·Δt, with each segment's linear
/// trend removed, before and after Γ̂'s part is taken out \[rad\], on the
/// rows' epochs (`None` where no row entered the fit).
#[derive(Debug, Clone, PartialEq, Default)]
#[non_exhaustive]
pub struct CompensatedCarrierPhase {
    /// The rows' epochs \[s\] (GPS seconds of the week of the first).
    pub t_s: Vec<f64>,
    /// Before compensation \[rad\].
    pub before_rad: Vec<Option<f64>>,
    /// After it \[rad\].
    pub after_rad: Vec<Option<f64>>,
}

/// One shape's identified loop and estimate.
struct Candidate {
    shape: LoopModel,
    bn_hz: f64,
    sigma_ln_bn: f64,
    resolution: LoopResolution,
    estimate: LoopFreeEstimate,
    /// H = 1: no bandwidth fitted (`shape` is the widest loop searched).
    unity: bool,
}

/// The shape's best Bn from its profile over `grid`: Gauss–Newton steps
/// from the best grid point when it is inside the grid, the one-sided
/// bound when it is at an end (module documentation).
fn refine<'a>(
    rows: &InputPhases,
    shape: &LoopModel,
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
                unity: false,
            });
        }
    }
    // Not resolved: Γ̂ of the best point, its variance widened by the spread
    // of the estimates the data cannot tell from it.
    let mut estimate = best.clone();
    cover_alike(&mut estimate, alike.iter().map(|&k| (profile[k].gamma_hz_per_mps2, best.covariance)));
    // The bound: the Bn farthest from the end the data cannot tell apart from the best.
    let alike_bn = alike.iter().map(|&k| grid[k]);
    let (resolution, bn_hz) = if alike.contains(&(grid.len() - 1)) || 2 * k_best >= grid.len() {
        (LoopResolution::Wide, alike_bn.fold(grid[k_best], f64::min))
    } else {
        (LoopResolution::Narrow, alike_bn.fold(grid[k_best], f64::max))
    };
    Ok(Candidate { shape: *shape, bn_hz, sigma_ln_bn: f64::INFINITY, resolution, estimate, unity: false })
}

/// Widens `estimate`'s variances so that each covers the Γ̂ of every fit in
/// `alike` (those the data cannot tell from it, Δ(−2 ln L) ≤ 1), each given
/// as its Γ̂_k and the covariance V_k it is known to within when the
/// nuisance is fixed: var_i ≥ V_k,ii + (Γ̂_k,i − Γ̂_i)². The set of such fits
/// is the profile likelihood's 1σ region of the nuisance (the bandwidth, or
/// the loop's shape); Γ̂'s 1σ then reaches every estimate in it.
fn cover_alike(estimate: &mut LoopFreeEstimate, alike: impl IntoIterator<Item = ([f64; 3], [[f64; 3]; 3])>) {
    for (g, v) in alike {
        for i in 0..3 {
            let spread = (g[i] - estimate.gamma_hz_per_mps2[i]).powi(2);
            estimate.covariance[i][i] = estimate.covariance[i][i].max(v[i][i] + spread);
        }
    }
}
