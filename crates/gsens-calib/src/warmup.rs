//! The estimator's warm-up the regressor models' start-up needs.
//!
//! The regressor models start at the session's first epoch in the steady
//! state of the specific force there. When the board is already being shaken
//! (a log that begins mid-shake, GNSS-SDR's rows that begin at its narrow
//! loop's switch), that state is wrong by about the loop's forced response,
//! and the error d(t) ≈ d₀·e^(−t/τ) dies out with the loop's slowest mode τ.
//! The high-pass that the measurement and the regressors both pass through
//! remembers its area d₀·τ: its output afterwards is about
//! d₀·(τ/τ_hp)·e^(−t/τ_hp), τ_hp = 1/(2π·f_hp). [`longest_models_warmup_s`]
//! bounds the warm-up that needs; [`models_warmup_s`] measures it from the
//! IMU log for the session at hand.

use gsens_core::{HighPass, LinearLoop, LoopModel};
use gsens_io::ImuSeries;

/// Time constants of the slowest mode after which a transient counts as
/// gone: e⁻⁵ of its start.
const SETTLED_TIME_CONSTANTS: f64 = 5.0;

/// The longest warm-up a session through `receiver_loop` may need \[s\],
/// with the estimator's high-pass at `highpass_hz` (0 = off):
///
/// ```text
/// W = max(S, τ_hp·(5 + ln(τ/τ_hp)))      S = 5τ, τ_hp = 1/(2π·highpass_hz)
/// ```
///
/// τ the slowest time constant of the loop ([`LoopModel::settling_time_s`]):
/// S for the models' start-up error itself to reach e⁻⁵, the second term
/// for the high-pass's memory of its area d₀·τ to fall below e⁻⁵·d₀. For
/// GNSS-SDR's 3 Hz loops at 20 ms with the default 0.05 Hz high-pass: 7.6 s
/// (2nd order, τ = 0.23 s) and 15.2 s (3rd order, τ = 2.5 s). Rounded up to
/// 0.1 s (a setting that reads back as written); 0 for a loop that cannot run.
pub fn longest_models_warmup_s(receiver_loop: &LoopModel, highpass_hz: f64) -> f64 {
    let tau = receiver_loop.settling_time_s(1.0);
    if !tau.is_finite() {
        return 0.0;
    }
    let s = SETTLED_TIME_CONSTANTS * tau;
    let w = if highpass_hz > 0.0 && tau > 0.0 {
        let tau_hp = 1.0 / (core::f64::consts::TAU * highpass_hz);
        s.max(tau_hp * (SETTLED_TIME_CONSTANTS + (tau / tau_hp).ln()))
    } else {
        s
    };
    up_to_tenth_s(w)
}

/// `t_s` rounded up to 0.1 s: a warm-up that reads back as written.
fn up_to_tenth_s(t_s: f64) -> f64 {
    (t_s * 10.0).ceil() / 10.0
}

/// The warm-up a session whose first epoch is at IMU stamp `start_s` needs
/// \[s\], measured from the IMU log: each axis runs `receiver_loop` twice,
/// once started at `start_s` in the steady state of the specific force there
/// (as the estimator's models are) and once [`longest_models_warmup_s`]
/// earlier (a reference whose own start has died out); both are sampled
/// every `log_interval_s` and high-passed from `start_s` on. The warm-up ends
/// where their difference stays below e⁻⁵ of the reference's peak over the
/// whole log and the three axes, on every axis, looked for over two longest
/// warm-ups: 0 for a board at rest at the start, at most
/// [`longest_models_warmup_s`]. One bound for the three axes: an axis hardly
/// shaken has a peak at the IMU's noise level, which the start-up error from
/// a noisy sample would always pass, and the phase error it adds is Γᵢ times
/// a difference small against the largest axis's regressor.
///
/// The reference starts no earlier than the IMU log, at rest in its first
/// sample's specific force: motion before the log is unknown, and a receiver
/// whose loops started with its IMU log (simulators, PocketSDR with the IMU
/// from the IF file's start, GNSS-SDR's rows that begin at its narrow loop's
/// switch) remembers none. 0 when the loop cannot run.
pub fn models_warmup_s(
    receiver_loop: &LoopModel,
    imu: &ImuSeries,
    start_s: f64,
    log_interval_s: f64,
    highpass_hz: f64,
) -> f64 {
    let w_max = longest_models_warmup_s(receiver_loop, highpass_hz);
    let (Some(&first), Some(&last)) = (imu.t_s.first(), imu.t_s.last()) else { return 0.0 };
    let (Ok(model), Some(t_loop)) = (receiver_loop.runnable(), receiver_loop.interval_s()) else { return 0.0 };
    let t_ref = (start_s - w_max).max(first);
    if w_max <= 0.0 || start_s <= t_ref || log_interval_s.is_nan() || log_interval_s <= 0.0 {
        return 0.0;
    }
    let per_epoch = (log_interval_s / t_loop).round().max(1.0) as usize;
    let n_lead = ((start_s - t_ref) / t_loop).round() as usize;
    let n_after = (2.0 * w_max / log_interval_s).ceil() as usize;
    // Each read with its own cursor: the cursor only moves forward.
    let at = |t: f64| imu.interpolate_at(t.clamp(first, last), &mut 0);
    let (mut reference, mut started) = ([model; 3], [model; 3]);
    for ((r, s), (a_ref, a_start)) in reference.iter_mut().zip(&mut started).zip(at(t_ref).into_iter().zip(at(start_s)))
    {
        r.settle(a_ref);
        s.settle(a_start);
    }
    let hp = HighPass::new(highpass_hz, log_interval_s);
    let (mut hp_ref, mut hp_diff) = ([hp; 3], [hp; 3]);
    let (mut peak, mut diffs) = (0.0f64, Vec::with_capacity(n_after));
    let mut cursor = 0;
    for k in 1.. {
        let t = t_ref + k as f64 * t_loop;
        if t > last {
            break;
        }
        let a = imu.interpolate_at(t, &mut cursor);
        let r: [f64; 3] = core::array::from_fn(|i| reference[i].step(a[i]));
        if k <= n_lead {
            continue;
        }
        // The started models only while their difference is looked at.
        let looking = diffs.len() < n_after;
        let d: [f64; 3] = core::array::from_fn(|i| if looking { started[i].step(a[i]) - r[i] } else { 0.0 });
        if (k - n_lead).is_multiple_of(per_epoch) {
            for i in 0..3 {
                peak = peak.max(hp_ref[i].step(r[i]).abs());
            }
            if looking {
                diffs.push(core::array::from_fn::<f64, 3, _>(|i| hp_diff[i].step(d[i]).abs()));
            }
        }
    }
    // The models' start-up error against the largest regressor (`peak` over the three axes): an
    // axis hardly shaken has its own peak at the IMU's noise, which its noise-driven start-up
    // error would always pass.
    let bound = (-SETTLED_TIME_CONSTANTS).exp() * peak;
    match diffs.iter().rposition(|d| d.iter().any(|&x| x > bound)) {
        None => 0.0,
        Some(j) => up_to_tenth_s((j + 1) as f64 * log_interval_s).min(w_max),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use gsens_core::LoopSpec;

    fn kaplan(order: u8, bn_hz: f64, interval_s: f64) -> LoopModel {
        LoopModel::kaplan(LoopSpec::of_order(order, bn_hz, 0.707, 1.1, 2.4).unwrap(), Some(interval_s))
    }

    /// The bound in closed form: a 2nd-order loop's slowest mode decays as
    /// e^(−ζωn·t) in the continuous limit, so τ = 1/(ζωn) with ωn = 8ζBn/(4ζ² + 1).
    #[test]
    fn the_longest_warm_up_follows_the_loops_slowest_mode() {
        let (bn_hz, zeta) = (3.0, 0.707);
        let wn = 8.0 * zeta * bn_hz / (4.0 * zeta * zeta + 1.0);
        let tau = 1.0 / (zeta * wn);
        let tau_hp = 1.0 / (core::f64::consts::TAU * 0.05);
        let expected = (tau_hp * (5.0 + (tau / tau_hp).ln()) * 10.0).ceil() / 10.0;
        assert_eq!(longest_models_warmup_s(&kaplan(2, bn_hz, 1e-4), 0.05), expected);
        let no_hp = longest_models_warmup_s(&kaplan(2, bn_hz, 1e-4), 0.0);
        assert!((no_hp - 5.0 * tau).abs() <= 0.1, "{no_hp} against {}", 5.0 * tau);
    }

    fn imu(shake_from_s: f64) -> ImuSeries {
        let t_s: Vec<f64> = (0..4000).map(|k| k as f64 * 0.025).collect();
        let w = core::f64::consts::TAU * 0.9;
        let accel_mps2 = t_s
            .iter()
            .map(|&t| {
                let a = if t >= shake_from_s { 3.0 * (w * (t - shake_from_s)).sin() } else { 0.0 };
                // Sensor noise of a few hundredths of m/s² from a fixed sequence; z never shaken.
                let e = |k: f64| ((t * 1e4 + k).sin() * 1e3).fract() * 0.05;
                [a + e(0.0), 0.5 * a + e(1.0), 9.81 + e(2.0)]
            })
            .collect();
        ImuSeries { t_s, accel_mps2 }
    }

    /// A session that starts mid-shake needs a warm-up of the order of the
    /// longest; one that starts at rest no more than the default (the start-up
    /// error of the IMU's noise), one that starts with the IMU log none.
    #[test]
    fn a_session_started_mid_shake_needs_a_warm_up() {
        let l = kaplan(3, 3.0, 0.02);
        let longest = longest_models_warmup_s(&l, 0.05);
        let mid_shake = models_warmup_s(&l, &imu(5.0), 30.0, 0.02, 0.05);
        assert!(mid_shake > 0.4 * longest && mid_shake <= longest, "{mid_shake} of {longest}");
        let at_rest = models_warmup_s(&l, &imu(50.0), 30.0, 0.02, 0.05);
        // The noise's own start-up error: within the default warm-up, so it changes nothing.
        assert!(at_rest <= crate::defaults::DEFAULT_WARMUP_S, "{at_rest} of {longest}");
        assert_eq!(models_warmup_s(&l, &imu(0.0), 0.0, 0.02, 0.05), 0.0);
    }
}
