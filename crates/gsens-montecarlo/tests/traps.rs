//! The trap suite: the mistakes a calibration engineer makes describing a
//! session, each on a simulated session whose logs (or options) are changed
//! the way a user might have got them wrong. Every one must come out either
//! accurate (within 2 % of |Γ|, and within 3σ) or flagged (not trustworthy);
//! the correctly described session must come out trustworthy.

mod common;

use common::{codes, error_and_z, estimate, map_imu, map_tracking, message, right_loop, session, truth};
use gsens_calib::{CalibrationOptions, LoopOptions, MethodName, TimeOffsetOption, WarningCode};
use gsens_session::ChannelRanking;
use std::f64::consts::TAU;

/// The right loop with `change` applied.
fn right_but(change: impl FnOnce(&mut CalibrationOptions)) -> CalibrationOptions {
    let mut o = right_loop();
    change(&mut o);
    o
}

fn code_list(codes: &[WarningCode]) -> String {
    codes.iter().map(|c| c.as_str()).collect::<Vec<_>>().join(",")
}

#[test]
fn every_mistake_is_accurate_or_flagged_and_the_clean_session_is_trusted() {
    let logs = session(21);
    let truth = truth(&logs);
    let (tracking, imu) = (&logs.tracking, &logs.imu);
    // Logs written wrongly.
    let imu_g = map_imu(imu, |t| t, |a| a.map(|v| v / 9.80665));
    let imu_late = map_imu(imu, |t| t + 0.4, |a| a);
    let imu_ms = map_imu(imu, |t| t * 1e3, |a| a);
    let phase_cycles = map_tracking(tracking, |r| r.phase_err_rad /= TAU);
    let phase_deg = map_tracking(tracking, |r| r.phase_err_rad = r.phase_err_rad.to_degrees());
    let phase_flipped = map_tracking(tracking, |r| r.phase_err_rad = -r.phase_err_rad);
    let cn0_constant = map_tracking(tracking, |r| r.cn0_dbhz = 45.0);

    let clean = estimate(tracking, imu, &right_loop());
    let (err, z) = error_and_z(&clean, truth);
    let clean_codes = code_list(&codes(&clean));
    eprintln!("clean: error {:.2} %, max |z| {z:.2}, warnings [{clean_codes}]", 100.0 * err);
    assert!(clean.trustworthy, "the correctly described session is trustworthy: [{clean_codes}]");
    assert!(err < 0.02 && z < 3.0, "clean: {err} {z}");

    let bn = |bn_hz: f64| right_but(|o| o.receiver_loop.bn_hz = Some(bn_hz));
    let traps = [
        ("loop 10 % too wide", tracking, imu, bn(3.3)),
        ("loop 10 % too narrow", tracking, imu, bn(2.7)),
        ("bn_hz 5 for a 3 Hz loop", tracking, imu, bn(5.0)),
        ("no loop options at all", tracking, imu, CalibrationOptions::default()),
        (
            "loop interval left at the log's",
            tracking,
            imu,
            CalibrationOptions {
                receiver_loop: LoopOptions { bn_hz: Some(3.0), ..LoopOptions::default() },
                ..CalibrationOptions::default()
            },
        ),
        ("3rd order stated for a 2nd", tracking, imu, right_but(|o| o.receiver_loop.order = Some(3))),
        ("logged last, not mean", tracking, imu, right_but(|o| o.receiver_loop.logged_phase = None)),
        ("IMU in g", tracking, &imu_g, right_loop()),
        ("phase in cycles", &phase_cycles, imu, right_loop()),
        ("phase in degrees", &phase_deg, imu, right_loop()),
        ("IMU clock 0.4 s late", tracking, &imu_late, right_loop()),
        ("IMU stamps in ms", tracking, &imu_ms, right_loop()),
        ("phase error of opposite sign", &phase_flipped, imu, right_loop()),
        ("a constant C/N0 column", &cn0_constant, imu, right_loop()),
        (
            "gradient gain 50",
            tracking,
            imu,
            right_but(|o| {
                o.method = MethodName::Gradient;
                o.estimator.gain_k = 50.0;
            }),
        ),
    ];
    let mut failures = Vec::new();
    for (name, tracking, imu, options) in &traps {
        let doc = estimate(tracking, imu, options);
        let (err, z) = error_and_z(&doc, truth);
        let fine = !doc.trustworthy || (err < 0.02 && z < 3.0);
        eprintln!(
            "{name:<34} trusted {:<5}  error {:>8.2} %  max |z| {z:>8.2}  [{}]  {}",
            doc.trustworthy,
            100.0 * err,
            code_list(&codes(&doc)),
            if fine { "ok" } else { "CONFIDENTLY WRONG" }
        );
        if !fine {
            failures.push(*name);
        }
    }
    assert!(failures.is_empty(), "confidently wrong: {failures:?}");
    // The sign is caught by its own check; a constant C/N0 column, ranked by
    // the channels' noise instead, loses nothing.
    let flipped = estimate(&phase_flipped, imu, &right_loop());
    assert_eq!((flipped.trustworthy, codes(&flipped)), (false, vec![WarningCode::PhaseSign]));
    let constant = estimate(&cn0_constant, imu, &right_loop());
    let (err, z) = error_and_z(&constant, truth);
    assert!(constant.trustworthy && err < 0.02 && z < 3.0, "constant C/N0: {err}, |z| {z:.2}");
    assert_eq!(constant.channel_ranking, Some(ChannelRanking::Noise));
}

/// A TCXO shaken gently at one rate, the IMU time offset searched. One σ of
/// the offset turns the shaking's phase by far more than the joint fit's
/// linearization holds for, and Γ̂ moves with it (on this seed by up to 4σ):
/// it must be flagged, for that reason alone, naming the fix. With the offset
/// stated the same session is trustworthy and within 3σ.
#[test]
fn an_offset_the_data_do_not_resolve_is_flagged() {
    let toml = include_str!("../../../examples/scenarios/tcxo-gentle.toml");
    // The joint fit of the loop and the offset: the tracking error only.
    let logs = common::session_of(&format!("{toml}\n[log]\nnco = false"), 1);
    let truth = truth(&logs);
    let (tracking, imu) = (&logs.tracking, &logs.imu);
    // The simulator logs the mean of each epoch's 1 ms discriminator outputs.
    let searched = estimate(tracking, imu, &right_loop());
    let (_, z) = error_and_z(&searched, truth);
    assert_eq!(
        (searched.trustworthy, codes(&searched)),
        (false, vec![WarningCode::LoopOffsetUnresolved]),
        "searched offset: |z| up to {z:.1}"
    );
    // Stated, with the loop fitted freely: with the loop also pinned to its 2 %
    // tolerance this session's σ is too small on x (-3.1σ; an open gap of weak
    // TCXO sessions, docs/trust.md), which this test is not about.
    let stated = estimate(
        tracking,
        imu,
        &right_but(|o| {
            o.systematic.time_offset = TimeOffsetOption::Seconds(0.0);
            o.systematic.loop_tolerance = Some(f64::INFINITY);
        }),
    );
    let (_, z) = error_and_z(&stated, truth);
    assert!(stated.trustworthy && z < 3.0, "stated offset: |z| up to {z:.1}, warnings {:?}", codes(&stated));
    // Described as logging the last update (the default): its scatter is 1/√25
    // of that prediction, which the units check flags, naming both fixes.
    let last = estimate(
        tracking,
        imu,
        &right_but(|o| {
            o.receiver_loop.logged_phase = None;
            o.systematic.time_offset = TimeOffsetOption::Seconds(0.0);
        }),
    );
    assert_eq!((last.trustworthy, codes(&last)), (false, vec![WarningCode::PhaseUnits]));
    let m = message(&last, WarningCode::PhaseUnits);
    assert!(m.contains("2π") && m.contains("mean of the 25 loop updates"), "{m}");
}

/// Warnings come by cause: a unit or time-base problem first (it explains
/// the rest), then the loop, then the shaking; and the shaking advice that a
/// wrong unit would produce ("shake harder" for an IMU stamped in
/// milliseconds, "shake more gently" for a phase in degrees) is not given
/// while the unit is flagged.
#[test]
fn unit_problems_come_first_and_silence_the_shaking_advice() {
    let logs = session(21);
    let (tracking, imu) = (&logs.tracking, &logs.imu);
    let imu_ms = map_imu(imu, |t| t * 1e3, |a| a);
    let tracking_ms = map_tracking(tracking, |r| r.t_s *= 1e3);
    let phase_deg = map_tracking(tracking, |r| r.phase_err_rad = r.phase_err_rad.to_degrees());
    for (name, tracking, imu, first) in [
        ("IMU stamps in ms", tracking, &imu_ms, WarningCode::TimeUnits),
        ("both logs in ms", &tracking_ms, &imu_ms, WarningCode::TimeUnits),
        ("phase in degrees", &phase_deg, imu, WarningCode::PhaseUnits),
    ] {
        let doc = estimate(tracking, imu, &right_loop());
        let found = codes(&doc);
        eprintln!("{name}: trusted {} [{}]", doc.trustworthy, code_list(&found));
        assert_eq!((doc.trustworthy, found[0]), (false, first), "{name}: [{}]", code_list(&found));
        for w in &doc.warnings {
            if matches!(w.code, WarningCode::DiscriminatorRange | WarningCode::NothingObservable) {
                assert!(!w.message.contains("shake"), "{name}: {}: {}", w.code.as_str(), w.message);
                assert!(w.message.contains(first.as_str()), "{name}: {}: {}", w.code.as_str(), w.message);
            }
        }
        for a in &doc.calibration.axes {
            assert!(!a.text.contains("shake") && !a.text.contains("closer to"), "{name}: {}", a.text);
        }
    }
    // No loop stated: the warning gives the loop found as the options that would state it, by
    // the names every front end shares, not a shell's flags.
    let doc = estimate(tracking, imu, &CalibrationOptions::default());
    assert!(!doc.trustworthy && codes(&doc).contains(&WarningCode::LoopNotStated), "{:?}", codes(&doc));
    let m = message(&doc, WarningCode::LoopNotStated);
    assert!(m.contains("state the receiver's loop (order, bn_hz, loop_interval_s, logged_phase;"), "{m}");
    let found = m.split_once("the loop found would be ").map_or("", |(_, f)| f);
    assert!(found.starts_with("order = 2, bn_hz = "), "{m}");
    assert!(found.contains(", loop_interval_s = ") && found.contains(", logged_phase = "), "{m}");
    assert!(!m.contains("--"), "{m}");
}
