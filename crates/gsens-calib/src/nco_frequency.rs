//! The estimate from the NCO's frequency: Γ from the command each loop gave
//! its NCO, through the closed loop.
//!
//! A receiver that logs the frequency its NCO ran at (`nco_freq_hz`: the
//! command in force during the row's latest integration, without the
//! oscillator's bias) logs the loop's answer to everything its input holds.
//! The replica runs at the command plus the bias Δf = aᵀΓ, and the loop
//! steers the replica onto the signal, so per channel i
//!
//! ```text
//! f_NCO,i = H[f_signal,i] − H[aᵀΓ],     common mode −H[aᵀΓ]
//! ```
//!
//! with H = F/(s + F) the closed-loop transfer (in discrete time
//! −1 − L_d/G, [`gsens_core::LoopFilterCoeffs::nco_response_discrete`]).
//! The regressor is the loop model's NCO command for a unit Γ along each
//! axis ([`gsens_core::RowQuantity::NcoFrequency`]), read at each row's
//! latest integration: the same loop model as the tracking error's, where
//! L = φ/Δf becomes −H. H is 1 at low frequencies for any loop, so a loop
//! stated a little wrong moves the NCO's answer to a shaking well below the
//! loop's bandwidth much less than the tracking error's: 1 − H ≈ (f/fn)² for a
//! 2nd-order loop, where L's relative error follows the loop's whole error.
//!
//! Everything else is the loop-free estimate's ([`crate::estimate_loop_free`]):
//! each satellite's Doppler is smooth, so a cubic in time is projected out of
//! each channel's frequency and of each regressor column over segments of
//! equal length, the channels of highest C/N0 are averaged (scaled to L1),
//! and the average is fitted by GLS under an AR noise model, the IMU offset
//! searched where asked. A cycle slip leaves the frequency as it was (only the
//! phase keeps the half cycle), so no slip test applies.

use crate::loop_free::{
    InputPhases, LoopFreeError, LoopFreeEstimate, LoopFreeSettings, RowRegressor, check_settings, fit_rows,
    fit_rows_loop_uncertain, median_step, rows_on_epochs,
};
use gsens_core::{LoopModel, RegressorModel, RowQuantity};
use gsens_io::{ImuSeries, TrackingLog};

/// Estimates Γ from the NCO's frequency through the closed loop of
/// `receiver_loop` (see the module documentation); `settings` as for the
/// loop-free estimate (its loop interval unused: the loop model's is).
///
/// `sigma_ln_scale` is the relative 1σ of the loop's time constants (ωn and
/// the bandwidth, all scaled together) as known from elsewhere: the stated
/// loop's tolerance, or the σ of the loop a fit of the tracking error settled
/// on. Near the loop's bandwidth H, and Γ̂ with it, depends on ωn, so Γ̂'s
/// covariance takes what that error moves it by (propagated, not combined
/// with what the rows say of the loop); 0 takes the loop as exact.
pub fn estimate_nco_frequency(
    tracking: &TrackingLog,
    imu: &ImuSeries,
    settings: &LoopFreeSettings,
    receiver_loop: &LoopModel,
    sigma_ln_scale: f64,
) -> Result<LoopFreeEstimate, LoopFreeError> {
    let (rows, quantity) = crate::nco_rows(tracking, settings, crate::NcoRecord::Command)?;
    if !(sigma_ln_scale > 0.0 && sigma_ln_scale.is_finite()) {
        return estimate_nco_frequency_from(&rows, imu, settings, receiver_loop, quantity);
    }
    check_settings(settings)?;
    let log_interval_s = median_step(&rows.epoch_t_s);
    let receiver_loop = receiver_loop.with_default_interval(log_interval_s);
    // A central difference over ±5 % of the time constants: H is smooth in them.
    let step_ln_scale = 0.05;
    let at = |ln_scale: f64| {
        let scaled = receiver_loop.with_bn_scaled(ln_scale.exp());
        loop_regressor(&rows.epoch_t_s, imu, &scaled, quantity, settings.warmup_s)
    };
    let mut estimate = fit_rows_loop_uncertain(&rows, at, step_ln_scale, sigma_ln_scale.powi(2), settings)?;
    estimate.loop_interval_s = receiver_loop.interval_s().unwrap_or(log_interval_s);
    Ok(estimate)
}

/// [`estimate_nco_frequency`] from frequency rows a receiver's adapter made
/// (each track's NCO frequency on the common epochs \[Hz\], the common mode
/// −H\[aᵀΓ\]; [`crate::nco_rows`] makes them from a tracking log), the loop
/// taken as exact: `quantity` says what a row holds,
/// [`RowQuantity::NcoFrequency`] (the command of the row's latest update) or
/// [`RowQuantity::NcoFrequencyMean`] (the mean command over the log
/// interval, a phase differenced). With the true loop stated its
/// `crlb_hz_per_mps2` is the bound with the loop known that an estimate
/// identifying the loop from the same rows
/// ([`crate::estimate_nco_frequency_identified_from`]) is measured against.
pub fn estimate_nco_frequency_from(
    rows: &InputPhases,
    imu: &ImuSeries,
    settings: &LoopFreeSettings,
    receiver_loop: &LoopModel,
    quantity: RowQuantity,
) -> Result<LoopFreeEstimate, LoopFreeError> {
    check_settings(settings)?;
    let log_interval_s = median_step(&rows.epoch_t_s);
    let receiver_loop = receiver_loop.with_default_interval(log_interval_s);
    let regressor = loop_regressor(&rows.epoch_t_s, imu, &receiver_loop, quantity, settings.warmup_s)?;
    let mut estimate = fit_rows(rows, &regressor, settings, f64::INFINITY)?;
    estimate.loop_interval_s = receiver_loop.interval_s().unwrap_or(log_interval_s);
    Ok(estimate)
}

/// The regressor of `quantity` through `receiver_loop` on `epochs`, its
/// model started `lead_s` before each epoch it is read at.
pub(crate) fn loop_regressor<'a>(
    epochs: &[f64],
    imu: &'a ImuSeries,
    receiver_loop: &LoopModel,
    quantity: RowQuantity,
    lead_s: f64,
) -> Result<ModelRegressor<'a>, LoopFreeError> {
    let log_interval_s = median_step(epochs);
    let loop_interval_s = receiver_loop.interval_s().unwrap_or(log_interval_s);
    let runnable = receiver_loop.runnable().map_err(|e| LoopFreeError::Loop { why: e.to_string() })?;
    let model = RegressorModel::of_quantity(runnable, loop_interval_s, log_interval_s, quantity)
        .map_err(|_| LoopFreeError::Intervals { log_interval_s, loop_interval_s })?;
    Ok(ModelRegressor::new(epochs, log_interval_s, imu, model, lead_s))
}

/// A track's NCO frequency \[Hz\] on the log's epochs: `None` where it has no
/// row, during its warm-up, and where |φ| passes the settings' limit (near the
/// discriminator's wrap the loop is pulled by a half cycle).
pub(crate) fn frequency_on_epochs(
    tr: &gsens_io::ChannelTrack,
    epochs: &[f64],
    settings: &LoopFreeSettings,
) -> Vec<Option<f64>> {
    let mut out = vec![None; epochs.len()];
    for (k, e) in rows_on_epochs(&tr.t_s, epochs) {
        if usable_row(tr, k, settings) {
            out[e] = Some(tr.nco_freq_hz[k]);
        }
    }
    out
}

/// A track's mean NCO frequency over each log interval \[Hz\]: the NCO
/// phase's advance from the previous epoch's row, over the interval (the
/// mean of the commands in force over the interval's updates). `None`
/// where either row is missing or not usable ([`frequency_on_epochs`]).
pub(crate) fn mean_frequency_on_epochs(
    tr: &gsens_io::ChannelTrack,
    epochs: &[f64],
    settings: &LoopFreeSettings,
) -> Vec<Option<f64>> {
    let mut out = vec![None; epochs.len()];
    let mut previous: Option<(usize, usize)> = None;
    for (k, e) in rows_on_epochs(&tr.t_s, epochs) {
        if let Some((k0, e0)) = previous.filter(|&(k0, e0)| e0 + 1 == e && usable_row(tr, k0, settings))
            && usable_row(tr, k, settings)
        {
            out[e] = Some((tr.nco_phase_cycles[k] - tr.nco_phase_cycles[k0]) / (epochs[e] - epochs[e0]));
        }
        previous = Some((k, e));
    }
    out
}

/// Whether row `k` is past the track's warm-up and its |φ| within the
/// settings' limit (near the discriminator's wrap the loop is pulled by a
/// half cycle); a track without φ has no such test.
fn usable_row(tr: &gsens_io::ChannelTrack, k: usize, settings: &LoopFreeSettings) -> bool {
    let warm = tr.t_s[k] >= tr.t_s[0] + settings.warmup_s;
    warm && tr.phase_err_rad.get(k).is_none_or(|p| p.abs() <= settings.max_abs_phase_rad)
}

/// The loop model's NCO command for a unit Γ per axis, on the log's uniform
/// grid: the model runs from `lead_s` before the first epoch asked for (its
/// start-up transient dies out there), fed the IMU's specific force at each
/// grid instant plus τ ([`ImuSeries::interpolate_at`]; the model's own linear
/// interpolation between epochs compensated as for the tracking error's regressors).
pub(crate) struct ModelRegressor<'a> {
    /// Each epoch's index on the grid t₀ + j·h.
    grid: Vec<usize>,
    t0_s: f64,
    log_interval_s: f64,
    imu: &'a ImuSeries,
    model: RegressorModel,
    lead_s: f64,
}

impl<'a> ModelRegressor<'a> {
    pub(crate) fn new(
        epochs: &[f64],
        log_interval_s: f64,
        imu: &'a ImuSeries,
        model: RegressorModel,
        lead_s: f64,
    ) -> Self {
        let t0_s = epochs.first().copied().unwrap_or(0.0);
        let grid = epochs.iter().map(|t| ((t - t0_s) / log_interval_s).round().max(0.0) as usize).collect();
        ModelRegressor { grid, t0_s, log_interval_s, imu, model, lead_s }
    }

    fn imu_span(&self) -> (f64, f64) {
        (self.imu.t_s.first().copied().unwrap_or(f64::NAN), self.imu.t_s.last().copied().unwrap_or(f64::NAN))
    }

    fn grid_t_s(&self, j: usize) -> f64 {
        self.t0_s + j as f64 * self.log_interval_s
    }
}

impl RowRegressor for ModelRegressor<'_> {
    fn covers(&self, k: usize, tau: f64) -> bool {
        let (first, last) = self.imu_span();
        let t = self.grid_t_s(self.grid[k]) + tau;
        t - self.lead_s >= first && t <= last
    }

    fn values(&self, at: &[usize], tau: f64) -> Vec<[f64; 3]> {
        let (Some(&first), Some(&last)) = (at.first(), at.last()) else { return Vec::new() };
        let (imu_first, imu_last) = self.imu_span();
        let lead = (self.lead_s / self.log_interval_s).ceil() as usize;
        let j_last = self.grid[last];
        let mut j_start = self.grid[first].saturating_sub(lead);
        while j_start < self.grid[first] && self.grid_t_s(j_start) + tau < imu_first {
            j_start += 1;
        }
        let mut cursor = 0;
        let accel: Vec<[f64; 3]> = (j_start..=j_last)
            .map(|j| self.imu.interpolate_at((self.grid_t_s(j) + tau).clamp(imu_first, imu_last), &mut cursor))
            .collect();
        let mut model = self.model.clone();
        model.reset();
        let input = crate::estimate::model_input(&accel, &model);
        let mut out = Vec::with_capacity(at.len());
        let mut next = 0;
        for (i, a) in input.iter().enumerate() {
            let value = model.epoch(a);
            while next < at.len() && self.grid[at[next]] == j_start + i {
                out.push(value);
                next += 1;
            }
        }
        out
    }
}
