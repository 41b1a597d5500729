//! Options out of their range on the default simulated session: each is an
//! error naming the setting and its range, not a hang or a silent change.
//! Cases found by hand: an absurd offset bound hung (its search grid grew
//! without limit); found by fuzzing: a loop updated every nanosecond ran for
//! minutes, the others were accepted. (A high-pass above the log's Nyquist
//! frequency is not refused: it is what time stamps in milliseconds make of
//! the default, which the `time_units` check names; the estimate is then
//! not trustworthy.)

mod common;

use common::{estimate, message, session};
use gsens_calib::{CalibrationOptions, WarningCode, calibrate_logs};

/// The error of calibrating the default session of seed 1 with `options`:
/// refused as settings, or by the pipeline.
fn error_of(options: &CalibrationOptions) -> String {
    let logs = session(1);
    match options.pipeline_settings() {
        Err(e) => e.to_string(),
        Ok(settings) => match calibrate_logs(&logs.tracking, &logs.imu, "imu", &settings) {
            Err(e) => e.to_string(),
            Ok(_) => panic!("no error"),
        },
    }
}

#[test]
fn out_of_range_options_are_errors_not_hangs_or_silent_changes() {
    let d = CalibrationOptions::default;
    for (options, said) in [
        (
            {
                let mut o = d();
                o.systematic.time_offset_max_s = 1e18;
                o
            },
            "time_offset.max_abs_s",
        ),
        (
            {
                let mut o = d();
                o.receiver_loop.loop_interval_s = Some(1e-9);
                o
            },
            "loop_interval_s = 1e-9 is out of range: expected at least 0.001 s",
        ),
        (CalibrationOptions { carrier_hz: 1e300, ..d() }, "carrier_hz = 1e300 is out of range"),
        (
            {
                let mut o = d();
                o.estimator.imu_scale_sigma_ppm = 1e300;
                o
            },
            "imu_scale_sigma = 1e294 is out of range",
        ),
    ] {
        let e = error_of(&options);
        assert!(e.contains(said), "{said}: {e}");
    }
}

/// A high-pass above the loop's band leaves nothing to estimate: the
/// verdict names it (it was "unobservable: shake harder" and trusted, found
/// by fuzzing).
#[test]
fn a_highpass_above_the_loops_band_is_named_and_not_trusted() {
    let logs = session(1);
    let options = {
        let mut o = CalibrationOptions::default();
        o.receiver_loop.order = Some(2);
        o.receiver_loop.bn_hz = Some(3.0);
        o.receiver_loop.loop_interval_s = Some(0.001);
        o.estimator.highpass_hz = 25.0;
        o
    };
    let doc = estimate(&logs.tracking, &logs.imu, &options);
    assert!(!doc.trustworthy);
    let m = message(&doc, WarningCode::Highpass);
    assert!(m.starts_with("the high-pass at 25 Hz is at or above the top of the loop's half-power band"), "{m}");
}

/// A warm-up as long as the log is named with the setting and the log's
/// length, once.
#[test]
fn a_warm_up_as_long_as_the_log_is_named_once() {
    let options = {
        let mut o = CalibrationOptions::default();
        o.receiver_loop.order = Some(2);
        o.receiver_loop.bn_hz = Some(3.0);
        o.estimator.warmup_s = 500.0;
        o
    };
    let e = error_of(&options);
    let cause = "the warm-up of 500 s (warmup_s) is not shorter than the log (";
    assert!(e.contains(cause), "{e}");
    assert_eq!(e.matches(cause).count(), 1, "{e}");
}
