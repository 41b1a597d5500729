//! Plausibility checks of a session's inputs, from physics alone: each finds
//! a likely mistake in how the logs were written and says how to fix it.

use crate::{Calibration, LoopSummary, Warning};
use gsens_core::units::STANDARD_GRAVITY_MPS2;

/// How far the median specific-force magnitude may stray from g₀ before the
/// IMU's units or scale are doubted: gravity varies by ±0.3 % over the Earth,
/// consumer accelerometers' scale and bias add a few per cent; 10 % is
/// neither.
const GRAVITY_TOLERANCE: f64 = 0.10;

/// Fewer log samples than this per period of the loop's peak response cannot
/// resolve the g-induced phase error (2 is Nyquist; 4 keeps the phase of
/// the response).
const MIN_SAMPLES_PER_PEAK_PERIOD: f64 = 4.0;

/// The warnings about the inputs of `calibration`, whose specific force per
/// epoch was `accel_mps2` and whose loop is summarized by `loop_summary`.
///
/// - `imu_units`: the median |f| over the epochs is gravity, g₀ = 9.80665
///   m/s², within 10 % for any board shaken by hand (the shaking averages
///   out of the median). Near 1 it is in g, otherwise the scale is wrong.
/// - `log_rate`: the log must sample the loop's peak response f_peak at
///   least 4 times per period, T_log ≤ 1/(4·f_peak); a longer interval is
///   most often time stamps in milliseconds.
pub(crate) fn input_warnings(accel_mps2: &[[f64; 3]], c: &Calibration, loop_summary: &LoopSummary) -> Vec<Warning> {
    let mut w = Vec::new();
    let mut norms: Vec<f64> = accel_mps2.iter().map(|a| (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()).collect();
    if !norms.is_empty() {
        let mid = norms.len() / 2;
        let median = *norms.select_nth_unstable_by(mid, f64::total_cmp).1;
        let g0 = STANDARD_GRAVITY_MPS2;
        if (median / g0 - 1.0).abs() > GRAVITY_TOLERANCE {
            let cause = if (median - 1.0).abs() < GRAVITY_TOLERANCE {
                format!("the IMU log looks like it is in g: multiply fx, fy, fz by {g0} to get m/s²")
            } else if (median / (1e3 * g0) - 1.0).abs() < GRAVITY_TOLERANCE {
                format!("the IMU log looks like it is in mg: multiply fx, fy, fz by {} to get m/s²", g0 / 1e3)
            } else {
                "check the IMU log's units and scale factor (imu.csv holds specific force in m/s²)".into()
            };
            w.push(Warning {
                code: "imu_units",
                message: format!(
                    "the specific force's median magnitude is {median:.4} where gravity gives {g0} m/s²: {cause}; \
                     Γ̂ scales inversely with it"
                ),
            });
        }
    }
    if let Some(f_peak) = loop_summary.peak_hz {
        let samples = 1.0 / (f_peak * c.log_interval_s);
        if samples < MIN_SAMPLES_PER_PEAK_PERIOD {
            w.push(Warning {
                code: "log_rate",
                message: format!(
                    "the log interval {} s gives {samples:.1} samples per period of the loop's peak response \
                     ({f_peak:.2} Hz), fewer than {MIN_SAMPLES_PER_PEAK_PERIOD}: the g-induced phase error is not \
                     resolved. If the time stamps are in milliseconds, convert them to seconds; otherwise log at least \
                     every {:.3} s",
                    c.log_interval_s,
                    1.0 / (MIN_SAMPLES_PER_PEAK_PERIOD * f_peak)
                ),
            });
        }
    }
    w
}
