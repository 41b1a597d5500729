//! Plausibility checks of a session's inputs, from physics alone: each finds
//! a likely mistake in how the logs were written and says how to fix it.

use crate::pipeline::Outcome;
use crate::{Calibration, LoopSummary, Warning, WarningCode};
use gsens_core::LoggedPhase;
use gsens_core::stats::{median_high_in_place, median_in_place};
use gsens_core::units::{Decimal, STANDARD_GRAVITY_MPS2, cn0_dbhz_to_ratio_hz};
use gsens_session::{ChannelSummary, FlatRunKind, FlatRuns};
use statrs::distribution::{ContinuousCDF, Normal};
use std::f64::consts::{PI, TAU};

/// How far the specific force's magnitude at rest may stray from g₀ before
/// the IMU's units or scale are doubted: gravity varies by ±0.3 % over the
/// Earth, consumer accelerometers' scale and bias add a few per cent; 10 % is
/// neither.
const GRAVITY_TOLERANCE: f64 = 0.10;

/// Length of the windows searched for rest \[s\]: about one period of hand
/// shaking (1–2 s), so a shaken window's motion does not pass for rest.
const REST_WINDOW_S: f64 = 1.0;

/// A window is at rest when the RMS of its specific force about the window's
/// mean vector is at most this fraction of the mean's magnitude: a quarter of
/// [`GRAVITY_TOLERANCE`], so motion at rest moves the magnitude by less than
/// the tolerance can notice. A ratio, so the test holds in any unit (m/s², g, mg).
const REST_MAX_RELATIVE_RMS: f64 = GRAVITY_TOLERANCE / 4.0;

/// The specific force's magnitude where the board is at rest, and how it was
/// found: the median of |mean vector| over the [`REST_WINDOW_S`] windows
/// (of consecutive epochs) at rest ([`REST_MAX_RELATIVE_RMS`]); without any,
/// the magnitude of the session's mean vector, in which a hand's
/// acceleration averages out (the board starts and ends at rest, ∫a dt = Δv
/// = 0) while gravity stays. Not the median |f| over all epochs: under strong
/// shaking |g + a| is mostly above g (10.9 m/s² at 12 m/s² amplitude).
fn magnitude_at_rest(accel: &[[f64; 3]], interval_s: f64) -> Option<(f64, String)> {
    let norm = |a: [f64; 3]| (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
    let mean = |w: &[[f64; 3]]| {
        let n = w.len() as f64;
        w.iter().fold([0.0; 3], |s, a| [s[0] + a[0] / n, s[1] + a[1] / n, s[2] + a[2] / n])
    };
    if accel.is_empty() {
        return None;
    }
    let len = ((REST_WINDOW_S / interval_s).round() as usize).max(4);
    let mut rest: Vec<f64> = accel
        .chunks_exact(len)
        .filter_map(|w| {
            let m = mean(w);
            let ms = w.iter().map(|a| norm([a[0] - m[0], a[1] - m[1], a[2] - m[2]]).powi(2)).sum::<f64>() / len as f64;
            (ms.sqrt() <= REST_MAX_RELATIVE_RMS * norm(m)).then(|| norm(m))
        })
        .collect();
    if rest.is_empty() {
        let m = norm(mean(accel));
        return Some((m, "the magnitude of its mean vector over the session (no stretch at rest)".into()));
    }
    let median = median_high_in_place(&mut rest);
    Some((median, format!("its median magnitude over the {} stretches of {REST_WINDOW_S} s at rest", rest.len())))
}

/// Fewer log samples than this per period of the loop's peak response cannot
/// resolve the g-induced phase error (2 is Nyquist; 4 keeps the phase of
/// the response).
const MIN_SAMPLES_PER_PEAK_PERIOD: f64 = 4.0;

/// A log interval this long or longer \[s\] is no GNSS receiver's tracking
/// log and no IMU's sample interval while the board is shaken at about 1 Hz:
/// together with a loop peak that 1/1000 of it would resolve, it is a time
/// stamp in milliseconds.
const MS_SUSPECT_INTERVAL_S: f64 = 1.0;

/// Phase units are doubted when the channels' median ratio of measured to
/// predicted scatter is farther than the geometric midpoint from 1 towards a
/// wrong unit's factor: below 1/√(2π) ≈ 0.40 (cycles give 1/(2π)), above
/// √(180/π) ≈ 7.6 (degrees give 180/π). The prediction holds within a few
/// tens of per cent (C/N0 estimator bias of 1–2 dB, the median of the other
/// channels in the deviation, multipath), far inside both margins (×2.5).
const CYCLES_BELOW: f64 = 0.398_942_280_401_432_7; // 1/√(2π)
const DEGREES_ABOVE: f64 = 7.569_397_566_060_481; // √(180/π)

/// More than this fraction of the epochs with an averaged phase error beyond
/// π — the range of any discriminator (atan2; a Costas atan stops at π/2) —
/// is not a phase error in radians.
const BEYOND_PI_FRACTION: f64 = 0.01;

/// The warnings about the inputs of the calibration `c` of `outcome`, whose
/// loop is summarized by `loop_summary`.
///
/// - `imu_units`: the specific force's magnitude at rest
///   ([`magnitude_at_rest`]) is gravity, g₀ = 9.80665 m/s², within 10 %.
///   Near 1 it is in g, near 1000·g₀ in mg, otherwise the scale is wrong.
/// - `log_rate`: the log must sample the loop's peak response f_peak at
///   least 4 times per period, T_log ≤ 1/(4·f_peak).
/// - `time_units`: a tracking log interval or an IMU sample interval of 1 s
///   or more that would satisfy the same rule if it were in milliseconds
///   (it replaces `log_rate` for the tracking log).
/// - `imu_rate`: the IMU too must sample the loop's peak 4 times a period:
///   its specific force is interpolated linearly onto the epochs.
/// - `highpass`: the high-pass corner at or above the top of the loop's
///   half-power band (or the log's Nyquist frequency, 1/(2T)): nothing of
///   the g-induced phase error is left to estimate from.
/// - `phase_units`: [`phase_units`].
/// - `carrier_gain`: [`carrier_gain`].
/// - `phase_sign`: [`phase_sign`].
/// - `imu_stuck`, `imu_clipped`: the runs of identical IMU samples
///   [`gsens_session::find_flat_runs`] found, and the epochs left out.
pub(crate) fn input_warnings(outcome: &Outcome, c: &Calibration, loop_summary: &LoopSummary) -> Vec<Warning> {
    let mut w = Vec::new();
    w.extend(imu_units(outcome));
    let rates = Rates::new(loop_summary);
    w.extend(rates.tracking_warning(outcome, c));
    w.extend(highpass(outcome, c, loop_summary));
    w.extend(rates.imu_warning(outcome.imu_flat_runs.sample_interval_s));
    w.extend(phase_units(outcome, c));
    w.extend(carrier_gain(&outcome.session.channels));
    w.extend(phase_sign(outcome, c));
    w.extend(flat_run_warnings(&outcome.imu_flat_runs, outcome.imu_flat_run_epochs));
    w
}

/// `imu_units`: the specific force at rest against gravity, with the likely
/// unit (g, mg) when it is one.
fn imu_units(outcome: &Outcome) -> Option<Warning> {
    let (median, how) = magnitude_at_rest(&outcome.session.accel_mps2, outcome.session.log_interval_s)?;
    let g0 = STANDARD_GRAVITY_MPS2;
    if (median / g0 - 1.0).abs() <= GRAVITY_TOLERANCE {
        return None;
    }
    let cause = if (median - 1.0).abs() < GRAVITY_TOLERANCE {
        format!("the IMU log looks like it is in g: multiply fx, fy, fz by {g0} to get m/s²")
    } else if (median / (1e3 * g0) - 1.0).abs() < GRAVITY_TOLERANCE {
        format!("the IMU log looks like it is in mg: multiply fx, fy, fz by {} to get m/s²", Decimal(g0 / 1e3))
    } else {
        "check the IMU log's units and scale factor (imu.csv holds specific force in m/s²)".into()
    };
    Some(Warning {
        code: WarningCode::ImuUnits,
        message: format!(
            "the specific force at rest, {how}, is {median:.4} where gravity gives {g0} m/s²: {cause}; \
             Γ̂ scales inversely with it"
        ),
    })
}

/// What the logs' rates are held to: the loop's peak response and the
/// longest interval that still samples it 4 times a period.
struct Rates {
    peak_hz: Option<f64>,
    longest_s: Option<f64>,
}

impl Rates {
    fn new(loop_summary: &LoopSummary) -> Self {
        let longest_s = loop_summary.peak_hz.map(|f| 1.0 / (MIN_SAMPLES_PER_PEAK_PERIOD * f));
        Rates { peak_hz: loop_summary.peak_hz, longest_s }
    }

    /// Whether an interval of 1 s or more would satisfy the rule in milliseconds.
    fn in_ms(&self, interval_s: f64) -> bool {
        interval_s >= MS_SUSPECT_INTERVAL_S && self.longest_s.is_none_or(|l| interval_s * 1e-3 <= l && interval_s > l)
    }

    /// `time_units` for the tracking log's interval, else `log_rate`.
    fn tracking_warning(&self, outcome: &Outcome, c: &Calibration) -> Option<Warning> {
        let span_s = |t: &[f64]| t.last().zip(t.first()).map_or(0.0, |(b, a)| b - a);
        if self.in_ms(c.log_interval_s) {
            return Some(Warning {
                code: WarningCode::TimeUnits,
                message: format!(
                    "the tracking log's interval is {} s and it lasts {:.0} s ({:.1} h) for a session shaken by hand: \
                     its time stamps look like milliseconds ({} ms would be a usual log interval); divide t_s by 1000 \
                     (and the IMU's if it is in milliseconds too)",
                    Decimal(c.log_interval_s),
                    span_s(&outcome.session.t_s),
                    span_s(&outcome.session.t_s) / 3600.0,
                    Decimal(c.log_interval_s)
                ),
            });
        }
        let (f_peak, longest_s) = (self.peak_hz?, self.longest_s?);
        (c.log_interval_s > longest_s).then(|| {
            let samples = 1.0 / (f_peak * c.log_interval_s);
            Warning {
                code: WarningCode::LogRate,
                message: format!(
                    "the log interval {} s gives {samples:.1} samples per period of the loop's peak response \
                     ({f_peak:.2} Hz), fewer than {MIN_SAMPLES_PER_PEAK_PERIOD}: the g-induced phase error is not \
                     resolved; log at least every {longest_s:.3} s",
                    Decimal(c.log_interval_s),
                ),
            }
        })
    }

    /// `time_units` for the IMU's sample interval `imu_h` \[s\], else `imu_rate`.
    fn imu_warning(&self, imu_h: f64) -> Option<Warning> {
        if imu_h > 0.0 && self.in_ms(imu_h) {
            return Some(Warning {
                code: WarningCode::TimeUnits,
                message: format!(
                    "the IMU's sample interval is {} s: its time stamps look like milliseconds ({} ms would \
                     be a usual IMU interval), so the tracking epochs see the specific force of a few samples \
                     stretched over the session; divide the IMU's t_s by 1000",
                    Decimal(imu_h),
                    Decimal(imu_h)
                ),
            });
        }
        let (f_peak, longest_s) = (self.peak_hz?, self.longest_s?);
        (imu_h > longest_s).then(|| Warning {
            code: WarningCode::ImuRate,
            message: format!(
                "the IMU's sample interval {} s gives {:.1} samples per period of the loop's peak response \
                 ({f_peak:.2} Hz), fewer than {MIN_SAMPLES_PER_PEAK_PERIOD}: the motion that excites the loop is not \
                 resolved; log the IMU at least every {longest_s:.3} s",
                Decimal(imu_h),
                1.0 / (f_peak * imu_h)
            ),
        })
    }
}

/// `highpass`: a high-pass above the loop's band (or the log's Nyquist
/// frequency) removes the g-induced phase error with the drift it is meant for.
fn highpass(outcome: &Outcome, c: &Calibration, loop_summary: &LoopSummary) -> Option<Warning> {
    let highpass_hz = outcome.settings.estimate.highpass_hz;
    let nyquist_hz = 0.5 / c.log_interval_s;
    let band_top_hz = loop_summary.half_power_band_hz.map_or(nyquist_hz, |b| b[1].min(nyquist_hz));
    if highpass_hz < band_top_hz {
        return None;
    }
    let limit = if band_top_hz < nyquist_hz {
        format!("the top of the loop's half-power band, {band_top_hz:.2} Hz")
    } else {
        format!("the log's Nyquist frequency 1/(2T), {nyquist_hz:.2} Hz")
    };
    Some(Warning {
        code: WarningCode::Highpass,
        message: format!(
            "the high-pass at {highpass_hz} Hz is at or above {limit}: it removes the g-induced phase error \
             along with the drift it is meant for; use a corner well below the loop's band (the default is \
             0.05 Hz, highpass_hz)"
        ),
    })
}

/// Largest Doppler rate magnitude a static antenna sees from a GPS satellite
/// at L1 \[Hz/s\]: at zenith, ρ̈ = v²/ρ − g_sat ≈ 0.18 m/s² (Kaplan & Hegarty,
/// *Understanding GPS*, 2nd ed., §3.4: 0.936 Hz/s at L1).
const MAX_STATIC_DOPPLER_RATE_HZ_PER_S: f64 = 0.936;

/// Normal quantile of the `phase_sign` test: a false-alarm probability of
/// 10⁻³ (one-sided) while the sign is right and the oscillator holds.
const PHASE_SIGN_FALSE_ALARM: f64 = 1e-3;

/// Epochs' channel-averaged phase error over the whole session: its mean
/// \[rad\] and the mean's standard error from the means of consecutive blocks
/// of `block_s` (the residuals' correlation span; blocks keep the loop's
/// colour and the shaking's leftovers in the error); `None` with fewer than
/// 8 blocks.
pub(crate) fn mean_phase_level_rad(
    phase_err_rad: &[Option<f64>],
    log_interval_s: f64,
    block_s: f64,
) -> Option<(f64, f64)> {
    let per_block = ((block_s / log_interval_s).round() as usize).max(1);
    let means: Vec<f64> = phase_err_rad
        .chunks(per_block)
        .filter_map(|b| {
            let (n, sum) = b.iter().flatten().fold((0usize, 0.0), |(n, s), v| (n + 1, s + v));
            (2 * n >= b.len() && b.len() == per_block).then(|| sum / n as f64)
        })
        .collect();
    let m = means.len();
    if m < 8 {
        return None;
    }
    let mean = means.iter().sum::<f64>() / m as f64;
    let var = means.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (m - 1) as f64;
    Some((mean, (var / m as f64).sqrt()))
}

/// `phase_sign`: the phase error logged with the opposite sign
/// (θ_replica − θ_signal), which turns Γ̂ into −Γ with nothing else to show.
///
/// With a static antenna every satellite's Doppler rate ḟ is ≤ 0 (the range
/// accelerates away: ρ̈ = (|v|² − ρ̇²)/ρ + û·a_sat > 0 over a GPS pass, at most
/// 0.936 Hz/s at L1), and a loop F = c0 + c1/s (2nd order; one with c2 > 0
/// has no such error and is not tested) tracks a Doppler ramp with the
/// steady-state error φ = 2π·ḟ/c1 (from L(s)·ḟ/s² at s → 0; signal leading
/// the replica is φ > 0). The channel offsets sum to zero, so the mean of the
/// averaged phase is the mean of the tracks' means: ≤ 0. The oscillator's
/// own drift ẏ adds −2π·f_c·ẏ/c1 to every channel alike; the shaking adds
/// only its net change over the session. A mean above zero by more than
/// Φ⁻¹(1 − 10⁻³) standard errors therefore means the sign is flipped, or
/// the oscillator's frequency fell by at least c1·mean/(2π·f_L1) per second
/// (a TCXO warming up; no OCXO), which the message names.
pub(crate) fn phase_sign(outcome: &Outcome, c: &Calibration) -> Option<Warning> {
    let coeffs = c.loop_used.coeffs().ok().filter(|k| k.c2_per_s3 == 0.0 && k.c1_per_s2 > 0.0)?;
    let block_s = outcome.settings.estimate.hac_lag_s;
    let s = &outcome.session;
    let (mean, se) = mean_phase_level_rad(&s.phase_err_rad, s.log_interval_s, block_s)?;
    let z_crit = Normal::standard().inverse_cdf(1.0 - PHASE_SIGN_FALSE_ALARM);
    (mean > z_crit * se).then_some(())?;
    let c1 = coeffs.c1_per_s2;
    let drift_per_s = c1 * mean / (TAU * gsens_core::units::GPS_L1_HZ);
    let lowest = TAU * -MAX_STATIC_DOPPLER_RATE_HZ_PER_S / c1;
    Some(Warning {
        code: WarningCode::PhaseSign,
        message: format!(
            "the channels' mean phase error is {mean:+.3} ± {se:.3} rad (z = {:+.1}, beyond {z_crit:.2}): with a \
             static antenna each satellite's Doppler rate is ≤ 0, so this loop's mean phase error lies between \
             {lowest:.3} and 0 rad; the phase error looks logged with the opposite sign (θ_replica − θ_signal), which \
             makes Γ̂ come out as −Γ: negate phase_err_rad. Only an oscillator whose frequency fell by more than \
             {:.1e} per second during the session (a TCXO warming up) could give this with the right sign",
            mean / se,
            drift_per_s
        ),
    })
}

/// The variance of one logged phase error \[rad²\] that thermal noise alone
/// gives a channel of C/N0 `cn0_hz` (as a ratio, Hz) behind a loop that
/// integrates for `t_s` and logs one value per `n` integrations (`mean`: the
/// mean of the n discriminator outputs; `last`: the latest one).
///
/// One discriminator output has σ_d² ([`gsens_core::discriminator_variance_rad2`]).
/// The logged value is that noise less the part the replica follows: for
/// `last` the variance is σ_d²·(1 + 2·Bn·T) (the replica's jitter is
/// independent of the current integration's noise, the loop having a
/// one-update latency), for `mean` about σ_d²/n (the loop removes only the
/// part below ~Bn of the averaged noise's bandwidth 1/(2·n·T), a fraction
/// Bn·n·T ≈ 8 % at 3 Hz and 25 ms). Both within 10 % of σ_d²·(1 or 1/n),
/// which is what is returned. The loop's jitter alone (Kaplan's formula)
/// would under-predict a `mean` log of 25 × 1 ms by a factor 2.6 in σ,
/// close to the 2π of a log in cycles.
pub(crate) fn logged_phase_variance_rad2(cn0_hz: f64, t_s: f64, n: u32, logged: LoggedPhase) -> f64 {
    let per_output = gsens_core::discriminator_variance_rad2(cn0_hz, t_s);
    match logged {
        LoggedPhase::Last => per_output,
        LoggedPhase::Mean => per_output / f64::from(n.max(1)),
    }
}

/// The ratio of a channel's measured high-frequency phase scatter to the
/// thermal scatter its C/N0 predicts ([`logged_phase_variance_rad2`]), and
/// whether the measured value is only an upper bound (the screening's scale
/// sits at its floor `min_sigma_rad`). Both are on L1's scale (the
/// prediction times f_L1/f_c, like the channel's phases). The measured scatter is the
/// screening's robust σ of the channel's deviation from the median of the
/// other channels, in which the oscillator's (and the g-induced) phase
/// cancels; the others' median adds 20–25 % of the channel's own σ for a
/// handful of channels.
fn scatter_ratio(
    ch: &ChannelSummary,
    t_s: f64,
    n: u32,
    logged: LoggedPhase,
    min_sigma_rad: f64,
) -> Option<(f64, bool)> {
    let measured = ch.screening.deviation_sigma_rad?;
    let cn0_dbhz = ch.screening.median_cn0_dbhz.unwrap_or(ch.mean_cn0_dbhz);
    // The measured σ is on L1's scale (the phases times f_L1/f_c): so is the prediction.
    let to_l1 = gsens_core::units::GPS_L1_HZ / ch.carrier_hz;
    let predicted = logged_phase_variance_rad2(cn0_dbhz_to_ratio_hz(cn0_dbhz), t_s, n, logged).sqrt() * to_l1;
    (predicted.is_finite() && predicted > 0.0).then(|| (measured / predicted, measured <= min_sigma_rad * (1.0 + 1e-9)))
}

/// `phase_units`: a phase error logged in cycles or degrees instead of
/// radians, from two pieces of physics.
///
/// 1. Each channel's measured scatter against its thermal prediction from its
///    own C/N0 ([`scatter_ratio`]): the median ratio over the channels
///    (every track the screening compared with two others or more) is near 1
///    for radians, near 1/(2π) for cycles and 180/π for degrees; the
///    thresholds are the geometric midpoints, [`CYCLES_BELOW`] and
///    [`DEGREES_ABOVE`]. A ratio that is only an upper bound counts for the
///    cycles test, where it is conservative, not for the degrees test.
/// 2. A discriminator's output cannot exceed π (atan2; a Costas atan π/2):
///    more than [`BEYOND_PI_FRACTION`] of the epochs' averaged phase beyond π
///    is degrees when the first test has no channel to go by, and is quoted as
///    evidence when it has.
///
/// The loop-predicted g-induced error cannot tell units apart: Γ̂ absorbs the
/// unit's factor, and nothing else fixes the size of Γ.
///
/// The rows' bookkeeping (update interval, last or mean) is the loop
/// model's, or, for an estimate from the input phase, the loop-free
/// estimate's (which chooses its own where no loop was stated).
fn phase_units(outcome: &Outcome, c: &Calibration) -> Option<Warning> {
    let mut logged = c.settings.logged_phase;
    let mut n = c.model_substeps.max(1);
    let mut t_s = c.loop_used.interval_s().unwrap_or(c.log_interval_s / f64::from(n));
    if let (crate::Measurement::InputPhase, Some(Ok(free))) = (outcome.measurement, &outcome.loop_free) {
        logged = free.logged_phase;
        t_s = free.loop_interval_s;
        n = ((c.log_interval_s / t_s).round() as u32).max(1);
    }
    let floor = outcome.session.selection.screening.min_sigma_rad;
    let ratios: Vec<(f64, bool)> =
        outcome.session.channels.iter().filter_map(|ch| scatter_ratio(ch, t_s, n, logged, floor)).collect();
    let median = |mut v: Vec<f64>| (!v.is_empty()).then(|| median_in_place(&mut v));
    let all = median(ratios.iter().map(|r| r.0).collect());
    let exact = median(ratios.iter().filter(|r| !r.1).map(|r| r.0).collect());
    let phases: Vec<f64> = outcome.session.phase_err_rad.iter().flatten().copied().collect();
    let beyond = phases.iter().filter(|p| p.abs() > PI).count() as f64 / phases.len().max(1) as f64;
    let scatter = |r: f64| {
        format!(
            "the channels' phase errors scatter {r:.3} times (median over {} channels) what their C/N0 predicts for \
             a discriminator's output in radians",
            ratios.len()
        )
    };
    let (unit, factor, evidence) = if let Some(r) = all.filter(|&r| r < CYCLES_BELOW) {
        let mut factor = "multiply phase_err_rad by 2π".to_string();
        if logged == LoggedPhase::Last && n > 1 {
            // The mean of n updates stated as the last scatters 1/√n as much:
            // a description error that looks like a unit.
            factor = format!(
                "{factor}. Or the log holds the mean of the {n} loop updates of each epoch, not the last: that \
                 scatters 1/√{n} = {:.3} times as much; then state the logged phase as the mean (logged_phase = mean)",
                1.0 / f64::from(n).sqrt()
            );
        }
        ("cycles", factor, format!("{}, near 1/(2π) = {:.3}", scatter(r), 1.0 / TAU))
    } else if let Some(r) = exact.filter(|&r| r > DEGREES_ABOVE) {
        let e = format!(
            "{}, near 180/π = {:.1}; {:.0} % of the epochs' phase lies beyond ±π, where no discriminator's output goes",
            scatter(r),
            180.0 / PI,
            beyond * 100.0
        );
        ("degrees", "multiply phase_err_rad by π/180".to_string(), e)
    } else if exact.is_none() && beyond > BEYOND_PI_FRACTION {
        let e = format!(
            "{:.0} % of the epochs' phase lies beyond ±π, where no discriminator's output goes",
            beyond * 100.0
        );
        (
            "degrees",
            "multiply phase_err_rad by π/180 (or, if it is an unwrapped phase, log the discriminator's output)"
                .to_string(),
            e,
        )
    } else {
        return None;
    };
    Some(Warning {
        code: WarningCode::PhaseUnits,
        message: format!(
            "{evidence}: the phase error looks like it is in {unit}; {factor}. Γ̂ scales with the phase's unit"
        ),
    })
}

/// Family-wise false-alarm probability of `carrier_gain` over the channels tested.
const CARRIER_GAIN_FALSE_ALARM: f64 = 1e-3;

/// `carrier_gain`: a channel whose gain on the common signal exceeds the
/// others' (the screening's pooled relative gain, test 3, by more than the
/// one-sided Φ⁻¹(1 − 10⁻³/n) standard errors over the n used channels that
/// have one). The oscillator puts f_c·y on every carrier, so with the
/// phases scaled by f_L1/f_c every channel follows the common signal with
/// gain 1; a fade or a loss of lock can only lower it (the discriminator
/// loses gain), a carrier higher than the log says raises it by
/// f_true/f_given (a GLONASS G1 channel read as L1: +1.4 to +1.9 %; the
/// carrier columns dropped from a mixed-signal log). Γ̂ is then biased by
/// the mean of f_true/f_given over the channels averaged. The candidates
/// named are the table's carriers within 3 standard errors of gain·f_given.
pub(crate) fn carrier_gain(channels: &[ChannelSummary]) -> Option<Warning> {
    let tested: Vec<(&ChannelSummary, f64, f64)> = channels
        .iter()
        .filter(|c| c.used)
        .filter_map(|c| match (c.screening.relative_gain, c.screening.relative_gain_se) {
            (Some(g), Some(se)) if g.is_finite() && se.is_finite() && se > 0.0 => Some((c, g, se)),
            _ => None,
        })
        .collect();
    if tested.len() < 3 {
        return None;
    }
    let z_crit = Normal::standard().inverse_cdf(1.0 - CARRIER_GAIN_FALSE_ALARM / tested.len() as f64);
    let high: Vec<String> = tested
        .iter()
        .filter(|(_, g, se)| (g - 1.0) / se > z_crit)
        .map(|(c, g, se)| {
            let mut candidates: Vec<String> = Vec::new();
            for spec in &gsens_io::SIGNALS {
                let ks: Vec<Option<i64>> = match spec.fdma_step_hz {
                    Some(_) => gsens_io::GLONASS_K.map(|k| Some(i64::from(k))).collect(),
                    None => vec![None],
                };
                for k in ks {
                    let Ok(sig) = gsens_io::Signal::new(spec.name, k) else { continue };
                    if (sig.carrier_hz() / c.carrier_hz - g).abs() <= 3.0 * se && candidates.len() < 4 {
                        candidates.push(sig.label());
                    }
                }
            }
            let like = if candidates.is_empty() {
                String::new()
            } else {
                format!(", as a channel on e.g. {} would", candidates.join(" or "))
            };
            format!(
                "channel {} (PRN {}, given as {}): gain {g:.4} ± {se:.4} (z = {:+.1}{like})",
                c.channel,
                c.prn,
                c.signal,
                (g - 1.0) / se
            )
        })
        .collect();
    if high.is_empty() {
        return None;
    }
    Some(Warning {
        code: WarningCode::CarrierGain,
        message: format!(
            "{} of {} channels follow the common (oscillator's) signal more than fully, beyond {z_crit:.2} standard \
             errors ({} % false alarms): {}. Scaled by f_L1/f_c, every channel's phase follows the common signal \
             with gain 1, and a fade or loss of lock only lowers it; a higher gain is a carrier higher than the log \
             says (or a loop other than the others'). Give tracking.csv each row's carrier (a `signal` or \
             `carrier_hz` column: without them every row is read as GPS L1); Γ̂ is biased by the mean of \
             f_true/f_given over the channels averaged",
            high.len(),
            tested.len(),
            Decimal(CARRIER_GAIN_FALSE_ALARM * 100.0),
            high.join("; ")
        ),
    })
}

/// `imu_stuck` and `imu_clipped`: what [`gsens_session::find_flat_runs`]
/// found, and how many epochs were left out of the estimate for it.
fn flat_run_warnings(runs: &FlatRuns, masked_epochs: usize) -> Vec<Warning> {
    let axis = ["x", "y", "z"];
    let mut w = Vec::new();
    for (kind, code) in [(FlatRunKind::Stuck, WarningCode::ImuStuck), (FlatRunKind::Clipped, WarningCode::ImuClipped)] {
        let of_kind: Vec<_> = runs.runs.iter().filter(|r| r.kind == kind).collect();
        let Some(first) = of_kind.first() else { continue };
        let samples: usize = of_kind.iter().map(|r| r.samples).sum();
        let mut axes: Vec<&str> = of_kind.iter().map(|r| axis[r.axis]).collect();
        axes.dedup();
        axes.sort_unstable();
        axes.dedup();
        let limits: Vec<String> = (0..3)
            .map(|i| match runs.noise_run_limit[i] {
                Some(l) => format!("{} {l}", axis[i]),
                None => format!("{} none (noise below the step)", axis[i]),
            })
            .collect();
        let (what, fix) = match kind {
            FlatRunKind::Stuck => (
                "identical samples that neither the sensor's noise nor a continuous motion makes (a stuck sensor or \
                 a logger repeating its last value)",
                "check the IMU's read-out and the logger",
            ),
            FlatRunKind::Clipped => (
                "identical samples at the axis's extreme value (the sensor clipped at its range)",
                "shake more gently or set the accelerometer to a wider range",
            ),
        };
        let masked = match masked_epochs {
            0 => "No epoch of the estimate reads them".to_owned(),
            m => format!("The {m} epochs that read them (stuck or clipped) were left out of the estimate"),
        };
        w.push(Warning {
            code,
            message: format!(
                "{} run(s) of {what} on axis {} ({samples} samples in all; the first: {} samples from {} s at {} \
                 m/s²). At the log's output steps ({} m/s²) and noise, runs are implausible from (samples per axis) \
                 {} (none: the noise is below the step, identical samples at rest are normal and only a jump at a \
                 run's end tells). {masked}; {fix}",
                of_kind.len(),
                axes.join(", "),
                first.samples,
                first.start_s,
                first.value_mps2,
                runs.quantum_mps2.map(|q| format!("{q:.3e}")).join(", "),
                limits.join(", "),
            ),
        });
    }
    w
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};

    /// The level of a constant plus white noise: the mean within 3 standard
    /// errors, and the standard error σ/√N within the spread of a block
    /// estimate (40 blocks: ±11 % for one σ); gaps and a short tail block are
    /// left out; too few blocks give nothing.
    #[test]
    fn mean_phase_level_is_the_mean_and_its_standard_error() {
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(11);
        let noise = Normal::new(0.0, 0.1).unwrap();
        let n = 4000 + 30;
        let mut phase: Vec<Option<f64>> = (0..n).map(|_| Some(-0.08 + noise.sample(&mut rng))).collect();
        for p in &mut phase[1000..1010] {
            *p = None;
        }
        let (mean, se) = mean_phase_level_rad(&phase, 0.025, 2.5).unwrap();
        let want_se = 0.1 / (4000f64).sqrt();
        assert!((mean + 0.08).abs() < 3.0 * want_se, "{mean}");
        assert!((se / want_se - 1.0).abs() < 0.35, "{se} vs {want_se}");
        assert_eq!(mean_phase_level_rad(&phase[..700], 0.025, 2.5), None);
    }

    /// Level board, z up, shaken along x at 0.9 Hz with `amp` m/s² where `shaking(t)`, 40 Hz epochs.
    fn board(seconds: f64, amp: f64, shaking: impl Fn(f64) -> bool) -> Vec<[f64; 3]> {
        let n = (seconds * 40.0) as usize;
        (0..n)
            .map(|k| {
                let t = k as f64 / 40.0;
                let a = if shaking(t) { amp * (TAU * 0.9 * t).sin() } else { 0.0 };
                [a, 0.0, STANDARD_GRAVITY_MPS2]
            })
            .collect()
    }

    #[test]
    fn rest_stretches_give_gravity_under_a_shake_whose_median_magnitude_is_not() {
        // Shaken at 12 m/s² except for 3 s at each end.
        let accel = board(60.0, 12.0, |t| (3.0..57.0).contains(&t));
        let (m, how) = magnitude_at_rest(&accel, 0.025).unwrap();
        assert!((m - STANDARD_GRAVITY_MPS2).abs() < 1e-9, "{m}");
        assert!(how.contains("6 stretches"), "{how}");
        let mut norms: Vec<f64> = accel.iter().map(|a| (a[0] * a[0] + a[2] * a[2]).sqrt()).collect();
        assert!(median_high_in_place(&mut norms) > 1.1 * STANDARD_GRAVITY_MPS2);
    }

    #[test]
    fn without_rest_the_mean_vector_gives_gravity_and_a_log_in_g_gives_one() {
        // 50 s of shaking, 45 whole cycles at 0.9 Hz: the kinematic part averages out.
        let accel = board(50.0, 12.0, |_| true);
        let (m, how) = magnitude_at_rest(&accel, 0.025).unwrap();
        assert!((m / STANDARD_GRAVITY_MPS2 - 1.0).abs() < 1e-3, "{m}");
        assert!(how.contains("mean vector"), "{how}");
        let in_g: Vec<[f64; 3]> =
            board(60.0, 12.0, |t| t > 5.0).iter().map(|a| a.map(|v| v / STANDARD_GRAVITY_MPS2)).collect();
        let (m, how) = magnitude_at_rest(&in_g, 0.025).unwrap();
        assert!((m - 1.0).abs() < 1e-9 && how.contains("at rest"), "{m} {how}");
    }
}
