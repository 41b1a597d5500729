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
use gsens_io::{ImuCubic, ImuSeries, TrackingLog};
use std::sync::OnceLock;

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
/// model started `lead_s` before each epoch it is read at, and fed the IMU
/// as finely as the IMU samples it ([`model_steps_per_epoch`]).
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
    let intervals_error = LoopFreeError::Intervals { log_interval_s, loop_interval_s };
    let updates = gsens_core::loop_substeps(loop_interval_s, log_interval_s).map_err(|_| intervals_error.clone())?;
    let steps = model_steps_per_epoch(updates, log_interval_s, median_step(&imu.t_s));
    let model = RegressorModel::of_quantity(runnable, loop_interval_s, log_interval_s / steps as f64, quantity)
        .map_err(|_| intervals_error)?;
    Ok(ModelRegressor::new(epochs, log_interval_s, steps, imu, model, lead_s))
}

/// Model steps per log epoch m: the least divisor of the loop's `updates`
/// per log interval h with h/m no longer than the IMU's interval (all
/// `updates` where none is).
///
/// The model interpolates its input linearly between its steps. A linear
/// interpolant of a sinusoid at ω sampled every h also holds images at
/// 2πk/h ± ω, of relative size sinc²((2π/h − ω)h/2) ≈ (ωh/2π)²; the loop
/// passes them (|H| ≈ 1 up to its bandwidth) and the rows, read every h,
/// alias them back onto ω. For a 10 Hz record of a 10 Hz loop's command
/// and 0.9 Hz shaking Γ̂ reads 0.11 % large (the test below), growing as ω²
/// for the harmonics of a hand's motion. Stepping the model as often as the
/// IMU has samples (the force read between them by
/// [`ImuSeries::interpolate_at`]'s cubic) leaves only the IMU's own images.
pub(crate) fn model_steps_per_epoch(updates: u32, log_interval_s: f64, imu_interval_s: f64) -> u32 {
    if !(imu_interval_s > 0.0 && imu_interval_s.is_finite()) {
        return 1;
    }
    // The tolerance keeps a 100 Hz IMU under a 10 Hz log at 10 steps despite rounding.
    let wanted = (log_interval_s / imu_interval_s * (1.0 - 1e-6)).ceil().max(1.0);
    (1..=updates).find(|m| updates.is_multiple_of(*m) && f64::from(*m) >= wanted).unwrap_or(updates)
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

/// The loop model's output (the rows' quantity) for a unit Γ per axis at
/// the log's epochs plus an IMU offset τ.
///
/// The model steps every h/m ([`model_steps_per_epoch`]: as often as the IMU
/// has samples, up to the loop's own updates) over the IMU's whole span,
/// from rest at its first step, fed the specific force there
/// ([`ImuCubic::at`]; the model's own linear interpolation between its steps
/// compensated as for the tracking error's regressors); a row holding a mean
/// over its log interval takes the mean of its interval's m steps. That is
/// computed once, at the first use. The model is linear and time-invariant,
/// so its output for the force read at t + τ is its output at t + τ: a row's
/// value at offset τ is the stepped output at t_k + τ, interpolated by the
/// cubic through the four steps around it (its error is of fourth order in
/// ω·h/m, under 10⁻⁶ of a 1 Hz shaking's regressor for a 100 Hz IMU). A row
/// is covered when the IMU starts `lead_s` before it (the model's start-up
/// transient has died out there) and has not ended.
pub(crate) struct ModelRegressor<'a> {
    /// Each epoch's index on the grid t₀ + j·h.
    grid: Vec<usize>,
    t0_s: f64,
    log_interval_s: f64,
    /// Model steps per log interval, m.
    steps: usize,
    imu: &'a ImuSeries,
    /// The model at the step h/m, at rest.
    model: RegressorModel,
    lead_s: f64,
    stepped: OnceLock<Stepped>,
}

/// The model's output at the instants `t_first_s + i·step_s`.
struct Stepped {
    t_first_s: f64,
    step_s: f64,
    values: Vec<[f64; 3]>,
}

impl Stepped {
    /// The output at `t_s`, by the Lagrange cubic through the four steps
    /// around it (the nearest four at the ends).
    fn at(&self, t_s: f64) -> [f64; 3] {
        let v = &self.values;
        if v.len() < 4 {
            let i = ((t_s - self.t_first_s) / self.step_s).round().clamp(0.0, v.len().saturating_sub(1) as f64);
            return v.get(i as usize).copied().unwrap_or([0.0; 3]);
        }
        let u = (t_s - self.t_first_s) / self.step_s;
        let j = (u.floor() as isize).clamp(1, v.len() as isize - 3) as usize;
        let s = u - j as f64;
        let w = [
            -s * (s - 1.0) * (s - 2.0) / 6.0,
            (s + 1.0) * (s - 1.0) * (s - 2.0) / 2.0,
            -(s + 1.0) * s * (s - 2.0) / 2.0,
            (s + 1.0) * s * (s - 1.0) / 6.0,
        ];
        core::array::from_fn(|i| w[0] * v[j - 1][i] + w[1] * v[j][i] + w[2] * v[j + 1][i] + w[3] * v[j + 2][i])
    }
}

impl<'a> ModelRegressor<'a> {
    pub(crate) fn new(
        epochs: &[f64],
        log_interval_s: f64,
        steps: u32,
        imu: &'a ImuSeries,
        model: RegressorModel,
        lead_s: f64,
    ) -> Self {
        let t0_s = epochs.first().copied().unwrap_or(0.0);
        let grid = epochs.iter().map(|t| ((t - t0_s) / log_interval_s).round().max(0.0) as usize).collect();
        let steps = steps.max(1) as usize;
        ModelRegressor { grid, t0_s, log_interval_s, steps, imu, model, lead_s, stepped: OnceLock::new() }
    }

    fn imu_span(&self) -> (f64, f64) {
        let t = &self.imu.t_s;
        (t.first().copied().unwrap_or(f64::NAN), t.last().copied().unwrap_or(f64::NAN))
    }

    fn grid_t_s(&self, j: usize) -> f64 {
        self.t0_s + j as f64 * self.log_interval_s
    }

    /// Whether a row holds its quantity's mean over the log interval (then
    /// the mean of the model's m steps), not its value at the epoch.
    fn averaged(&self) -> bool {
        matches!(
            self.model.quantity(),
            RowQuantity::NcoFrequencyMean | RowQuantity::PhaseError(gsens_core::LoggedPhase::Mean)
        )
    }

    /// The model stepped over the IMU's span on the instants t₀ + i·h/m.
    fn step_over_imu(&self) -> Stepped {
        let (imu_first, imu_last) = self.imu_span();
        let m = self.steps;
        let step_s = self.log_interval_s / m as f64;
        let (i_first, i_last) = (((imu_first - self.t0_s) / step_s).ceil(), ((imu_last - self.t0_s) / step_s).floor());
        let t_first_s = self.t0_s + i_first * step_s;
        let count = if i_last >= i_first { (i_last - i_first) as usize + 1 } else { 0 };
        let (cubic, mut cursor) = (ImuCubic::new(self.imu), 0);
        let accel: Vec<[f64; 3]> =
            (0..count).map(|i| cubic.at((t_first_s + i as f64 * step_s).min(imu_last), &mut cursor)).collect();
        let mut model = self.model.clone();
        model.reset();
        let input = crate::estimate::model_input(&accel, &model);
        let mut values: Vec<[f64; 3]> = input.iter().map(|a| model.epoch(a)).collect();
        if self.averaged() && m > 1 {
            // The mean of the m steps ending at each instant (of those there are at the start).
            let raw = values.clone();
            for (i, out) in values.iter_mut().enumerate() {
                let window = &raw[(i + 1).saturating_sub(m)..=i];
                *out = core::array::from_fn(|axis| window.iter().map(|v| v[axis]).sum::<f64>() / window.len() as f64);
            }
        }
        Stepped { t_first_s, step_s, values }
    }
}

impl RowRegressor for ModelRegressor<'_> {
    fn covers(&self, k: usize, tau: f64) -> bool {
        let (first, last) = self.imu_span();
        let t = self.grid_t_s(self.grid[k]) + tau;
        t - self.lead_s >= first && t <= last
    }

    fn values(&self, at: &[usize], tau: f64) -> Vec<[f64; 3]> {
        let stepped = self.stepped.get_or_init(|| self.step_over_imu());
        at.iter().map(|&k| stepped.at(self.grid_t_s(self.grid[k]) + tau)).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::loop_free::RowRegressor;
    use gsens_core::{LinearLoop, LoopSpec};

    const F_HZ: f64 = 0.9;

    fn force(t_s: f64) -> f64 {
        (2.0 * core::f64::consts::PI * F_HZ * t_s).cos()
    }

    /// Mean of `g` over [a, b] by composite Simpson on 64 panels.
    fn simpson(g: impl Fn(f64) -> f64, a: f64, b: f64) -> f64 {
        let n = 64;
        let h = (b - a) / n as f64;
        let inner: f64 = (1..n).map(|i| g(a + i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 }).sum();
        (g(a) + g(b) + inner) * h / 3.0 / (b - a)
    }

    /// The command a loop updated every `loop_s` gives its NCO, read before
    /// the update whose integration is centred on each of `epochs`, the loop
    /// fed the force's exact mean over each integration and its mean weighted
    /// by the time left (the correlator's view), from 20 s before.
    fn brute_force_commands(l: &LoopModel, loop_s: f64, epochs: &[f64]) -> Vec<f64> {
        let mut pll = l.runnable().expect("a stable loop");
        pll.reset();
        let first = ((epochs[0] - 20.0) / loop_s).round() as i64;
        let mut out = Vec::new();
        let mut next = 0;
        for u in first.. {
            let centre = u as f64 * loop_s;
            while next < epochs.len() && (epochs[next] - centre).abs() < 1e-9 {
                out.push(pll.nco_freq_hz());
                next += 1;
            }
            if next == epochs.len() {
                break;
            }
            let start = centre - loop_s / 2.0;
            let mean = simpson(force, start, start + loop_s);
            let weighted = simpson(|t| force(t) * 2.0 * (1.0 - (t - start) / loop_s), start, start + loop_s);
            pll.step_varying(mean, weighted);
        }
        out
    }

    /// Least-squares gain of the data `truth` on the regressor `model`: the
    /// Γ̂/Γ a fit through `model` gives.
    fn fitted_gain(model: &[f64], truth: &[f64]) -> f64 {
        let num: f64 = model.iter().zip(truth).map(|(m, t)| m * t).sum();
        num / model.iter().map(|m| m * m).sum::<f64>()
    }

    /// A 10 Hz record of the latest command of a 3rd-order 10 Hz loop at
    /// 5 ms, 0.9 Hz shaking read by a 100 Hz IMU: through the model stepped
    /// at the IMU's rate Γ̂ is right within 0.01 % (measured 5·10⁻⁶); stepped
    /// once per row (the force interpolated linearly between rows) it reads
    /// 0.11 % large, the interpolant's image at 10 − 0.9 Hz passed by the loop
    /// and aliased back by the rows.
    #[test]
    fn the_command_regressor_steps_at_the_imu_rate() {
        let loop_s = 0.005;
        let l = LoopModel::Kaplan { spec: LoopSpec::third_order_kaplan(10.0), interval_s: Some(loop_s) };
        let imu_t: Vec<f64> = (0..=4000).map(|i| i as f64 * 0.01).collect();
        let imu = ImuSeries { accel_mps2: imu_t.iter().map(|&t| [force(t), 0.0, 0.0]).collect(), t_s: imu_t };
        let epochs: Vec<f64> = (120..=300).map(|k| k as f64 * 0.1).collect();
        let at: Vec<usize> = (0..epochs.len()).collect();
        let truth = brute_force_commands(&l, loop_s, &epochs);
        let x = |v: Vec<[f64; 3]>| v.iter().map(|r| r[0]).collect::<Vec<_>>();

        let regressor = loop_regressor(&epochs, &imu, &l, RowQuantity::NcoFrequency, 10.0).expect("a regressor");
        assert_eq!(regressor.steps, 10);
        let gain = fitted_gain(&x(regressor.values(&at, 0.0)), &truth);
        assert!((gain - 1.0).abs() < 1e-4, "stepped at the IMU's rate: Γ̂/Γ = {gain}");

        let per_row = RegressorModel::of_quantity(l.runnable().unwrap(), loop_s, 0.1, RowQuantity::NcoFrequency);
        let per_row = ModelRegressor::new(&epochs, 0.1, 1, &imu, per_row.unwrap(), 10.0);
        let gain = fitted_gain(&x(per_row.values(&at, 0.0)), &truth);
        assert!(gain - 1.0 > 5e-4, "stepped once per row: Γ̂/Γ = {gain}");
    }

    /// The mean command over each row's interval (a phase differenced): the
    /// model's steps averaged, against the updates' commands averaged.
    #[test]
    fn the_mean_command_averages_the_steps_of_a_row() {
        let loop_s = 0.001;
        let l = LoopModel::Kaplan {
            spec: LoopSpec::SecondOrder { bn_hz: 3.0, zeta: core::f64::consts::FRAC_1_SQRT_2 },
            interval_s: Some(loop_s),
        };
        let imu_t: Vec<f64> = (0..=4000).map(|i| i as f64 * 0.01).collect();
        let imu = ImuSeries { accel_mps2: imu_t.iter().map(|&t| [0.0, force(t), 0.0]).collect(), t_s: imu_t };
        let epochs: Vec<f64> = (240..=600).map(|k| k as f64 * 0.05).collect();
        // Each row's mean over its 50 updates: the brute-force commands at every update, averaged.
        let updates: Vec<f64> = (240 * 50 - 49..=600 * 50).map(|u| u as f64 * loop_s).collect();
        let each = brute_force_commands(&l, loop_s, &updates);
        let truth: Vec<f64> = each.chunks(50).map(|c| c.iter().sum::<f64>() / 50.0).collect();
        let regressor = loop_regressor(&epochs, &imu, &l, RowQuantity::NcoFrequencyMean, 10.0).expect("a regressor");
        assert_eq!(regressor.steps, 5);
        let at: Vec<usize> = (0..epochs.len()).collect();
        let model: Vec<f64> = regressor.values(&at, 0.0).iter().map(|r| r[1]).collect();
        let gain = fitted_gain(&model, &truth);
        assert!((gain - 1.0).abs() < 1e-5, "Γ̂/Γ = {gain}");
    }

    #[test]
    fn model_steps_divide_the_updates_and_reach_the_imu_rate() {
        assert_eq!(model_steps_per_epoch(100, 0.1, 0.01), 10);
        assert_eq!(model_steps_per_epoch(20, 0.1, 0.01), 10);
        assert_eq!(model_steps_per_epoch(25, 0.025, 0.01), 5);
        assert_eq!(model_steps_per_epoch(25, 0.025, 0.025), 1);
        assert_eq!(model_steps_per_epoch(4, 0.02, 0.001), 4);
        assert_eq!(model_steps_per_epoch(1, 0.02, 0.01), 1);
        assert_eq!(model_steps_per_epoch(10, 0.1, f64::NAN), 1);
    }
}
