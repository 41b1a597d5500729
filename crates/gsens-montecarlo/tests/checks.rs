//! Input plausibility checks on simulated sessions whose logs were changed as
//! a user might have written them.

mod common;

use common::{
    assert_within_3_sigma, codes, estimate, map_imu, map_tracking, message, other_clean_session, right_loop, session,
    truth,
};
use gsens_calib::{CalibrationOptions, TimeOffsetOption, WarningCode};
use gsens_core::LoggedPhase;
use gsens_io::ImuSeries;
use std::f64::consts::TAU;

/// The loop of [`other_clean_session`]: the default loop, the latest output logged.
fn last_loop() -> CalibrationOptions {
    let mut o = right_loop();
    o.receiver_loop.logged_phase = Some(LoggedPhase::Last);
    o
}

/// Gives samples `first..first + n` of `axes` the value of sample `first − 1`,
/// as a stuck sensor would.
fn hold(imu: &mut ImuSeries, axes: &[usize], first: usize, n: usize) {
    let held = imu.accel_mps2[first - 1];
    for a in &mut imu.accel_mps2[first..first + n] {
        for &axis in axes {
            a[axis] = held[axis];
        }
    }
}

#[test]
fn an_imu_logged_in_g_is_flagged_and_a_correct_one_is_not() {
    let logs = session(5);
    let clean = estimate(&logs.tracking, &logs.imu, &right_loop());
    assert_eq!(codes(&clean), Vec::<WarningCode>::new(), "{:?}", clean.warnings);
    assert!(clean.trustworthy);
    let imu_g = map_imu(&logs.imu, |t| t, |a| a.map(|v| v / 9.80665));
    let doc = estimate(&logs.tracking, &imu_g, &right_loop());
    assert_eq!(codes(&doc), [WarningCode::ImuUnits], "{:?}", doc.warnings);
    assert!(message(&doc, WarningCode::ImuUnits).contains("in g"), "{:?}", doc.warnings);
    assert!(!doc.trustworthy);
}

#[test]
fn isolated_imu_spikes_are_replaced_and_reported() {
    let logs = session(6);
    // Three corrupted samples, one per axis, while the board is shaken.
    let mut imu = logs.imu.clone();
    let n = imu.t_s.len();
    for (j, (axis, v)) in [(0, 1000.0), (1, -400.0), (2, 250.0)].into_iter().enumerate() {
        imu.accel_mps2[n / 5 + j * n / 4][axis] = v;
    }
    let doc = estimate(&logs.tracking, &imu, &right_loop());
    assert_eq!(codes(&doc), [WarningCode::ImuSpikes], "{:?}", doc.warnings);
    assert!(message(&doc, WarningCode::ImuSpikes).starts_with("3 isolated"), "{:?}", doc.warnings);
    assert_within_3_sigma(&doc, truth(&logs));
}

#[test]
fn a_phase_error_in_cycles_or_degrees_is_flagged_and_one_in_radians_is_not() {
    let logs = session(5);
    let cycles = map_tracking(&logs.tracking, |r| r.phase_err_rad /= TAU);
    let degrees = map_tracking(&logs.tracking, |r| r.phase_err_rad = r.phase_err_rad.to_degrees());
    let doc = estimate(&cycles, &logs.imu, &right_loop());
    assert_eq!(codes(&doc), [WarningCode::PhaseUnits], "{:?}", doc.warnings);
    let m = message(&doc, WarningCode::PhaseUnits);
    assert!(m.contains("in cycles; multiply phase_err_rad by 2π"), "{m}");
    let doc = estimate(&degrees, &logs.imu, &right_loop());
    // Γ̂ 57 times too large also overflows the discriminator's range.
    assert!(codes(&doc).contains(&WarningCode::PhaseUnits), "{:?}", doc.warnings);
    let m = message(&doc, WarningCode::PhaseUnits);
    assert!(m.contains("in degrees; multiply phase_err_rad by π/180"), "{m}");

    // Another clean session, logging the latest discriminator output: silent; in cycles: flagged.
    let other = other_clean_session();
    let doc = estimate(&other.tracking, &other.imu, &last_loop());
    assert_eq!(codes(&doc), Vec::<WarningCode>::new(), "{:?}", doc.warnings);
    let cycles = map_tracking(&other.tracking, |r| r.phase_err_rad /= TAU);
    let doc = estimate(&cycles, &other.imu, &last_loop());
    assert_eq!(codes(&doc), [WarningCode::PhaseUnits], "{:?}", doc.warnings);
}

#[test]
fn stuck_and_clipped_imu_samples_are_flagged_and_left_out() {
    let logs = session(6);
    // x held for 0.5 s (20 samples at 40 Hz after the one it holds) while the
    // board is shaken along x (10–40 s).
    let mut stuck = logs.imu.clone();
    hold(&mut stuck, &[0], 20 * 40, 20);
    let doc = estimate(&logs.tracking, &stuck, &right_loop());
    assert_eq!(codes(&doc), [WarningCode::ImuStuck], "{:?}", doc.warnings);
    let m = message(&doc, WarningCode::ImuStuck);
    assert!(m.starts_with("1 run(s)") && m.contains("on axis x (21 samples"), "{m}");
    assert!(m.contains("left out of the estimate"), "{m}");
    assert_within_3_sigma(&doc, truth(&logs));

    // The logger repeating whole samples, 5 times each, every 10 s.
    let mut repeated = logs.imu.clone();
    for first in (599..repeated.t_s.len() - 11).step_by(400) {
        hold(&mut repeated, &[0, 1, 2], first, 5);
    }
    let doc = estimate(&logs.tracking, &repeated, &right_loop());
    assert_eq!(codes(&doc), [WarningCode::ImuStuck], "{:?}", doc.warnings);
    assert!(message(&doc, WarningCode::ImuStuck).contains("axis x, y, z"), "{:?}", doc.warnings);

    // x clipped at ±2 m/s² (the shake's amplitude is 3 m/s²): the x shake is left out, x unobservable.
    let clipped = map_imu(&logs.imu, |t| t, |[x, y, z]| [x.clamp(-2.0, 2.0), y, z]);
    let doc = estimate(&logs.tracking, &clipped, &right_loop());
    assert_eq!(codes(&doc), [WarningCode::ImuClipped], "{:?}", doc.warnings);
    let m = message(&doc, WarningCode::ImuClipped);
    assert!(m.contains("on axis x (") && (m.contains(" at 2 m/s²") || m.contains(" at -2 m/s²")), "{m}");
    assert_eq!(doc.calibration.gamma_hz_per_mps2[0], None);
}

#[test]
fn a_quantized_clean_imu_is_not_flagged_and_a_stuck_one_is() {
    let logs = session(7);
    // 12 bits over ±8 g: a step of 0.038 m/s², 35 times the simulated IMU's
    // noise, so the rests read one value.
    let q = 16.0 * 9.80665 / 4096.0;
    let coarse = map_imu(&logs.imu, |t| t, |a| a.map(|v| (v / q).round() * q));
    let doc = estimate(&logs.tracking, &coarse, &right_loop());
    assert_eq!(codes(&doc), Vec::<WarningCode>::new(), "{:?}", doc.warnings);
    // Stuck for 0.5 s during the x shake: found by its release although the noise cannot tell.
    let mut coarse_stuck = coarse.clone();
    hold(&mut coarse_stuck, &[0], 20 * 40, 20);
    let doc = estimate(&logs.tracking, &coarse_stuck, &right_loop());
    assert_eq!(codes(&doc), [WarningCode::ImuStuck], "{:?}", doc.warnings);
    assert!(message(&doc, WarningCode::ImuStuck).contains("none (noise below the step)"), "{:?}", doc.warnings);
    // The consumer MEMS session (16 bits over ±4 g, at 100 Hz): silent.
    let other = other_clean_session();
    let doc = estimate(&other.tracking, &other.imu, &last_loop());
    assert_eq!(codes(&doc), Vec::<WarningCode>::new(), "{:?}", doc.warnings);
}

#[test]
fn time_stamps_in_milliseconds_are_named() {
    let logs = session(5);
    let imu_ms = map_imu(&logs.imu, |t| t * 1e3, |a| a);
    let tracking_ms = map_tracking(&logs.tracking, |r| r.t_s *= 1e3);
    let doc = estimate(&logs.tracking, &imu_ms, &right_loop());
    // Named as the cause (the other warnings are its consequences), and not trustworthy.
    assert!(codes(&doc).contains(&WarningCode::TimeUnits), "{:?}", doc.warnings);
    assert!(!doc.trustworthy);
    assert!(message(&doc, WarningCode::TimeUnits).contains("IMU's sample interval is 25 s"), "{:?}", doc.warnings);
    // Both in milliseconds: the time-offset search would end at its limit, so the offset is stated.
    let mut none = right_loop();
    none.systematic.time_offset = TimeOffsetOption::None;
    let doc = estimate(&tracking_ms, &imu_ms, &none);
    assert_eq!(codes(&doc).iter().filter(|c| **c == WarningCode::TimeUnits).count(), 2, "{:?}", doc.warnings);
    assert!(!doc.trustworthy);
    assert!(message(&doc, WarningCode::TimeUnits).contains("tracking log's interval is 25 s"), "{:?}", doc.warnings);
}
