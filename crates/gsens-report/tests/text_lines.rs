//! Lines of the text report that simulated sessions call for: the robust
//! fit's line, a whole track excluded by the screening, and an axis shaken
//! too little to observe.

use gsens_calib::{CalibrationOptions, Robust, TimeOffsetOption, calibrate_logs};
use gsens_core::LoggedPhase;
use gsens_report::render_text;
use gsens_sim::scenario::Scenario;
use gsens_sim::simulate_logs;

/// The text report of the session of `toml` (on the defaults) with `seed`,
/// estimated with `options`.
fn text_of(toml: &str, seed: u64, options: &CalibrationOptions) -> String {
    let logs = simulate_logs(&Scenario::from_toml_str(toml).unwrap(), seed).unwrap();
    let settings = options.pipeline_settings().unwrap();
    let outcome = calibrate_logs(&logs.tracking, &logs.imu, "imu", &settings).unwrap();
    render_text(&outcome.document(None))
}

/// The simulated receiver as `truth.json` states it: updated every 1 ms, the mean logged.
fn stated() -> CalibrationOptions {
    let mut o = CalibrationOptions::default();
    o.receiver_loop.loop_interval_s = Some(0.001);
    o.receiver_loop.logged_phase = Some(LoggedPhase::Mean);
    o
}

/// Two satellites too weak to keep lock, their unlocked rows logged: the
/// screening excludes them whole, and Huber's fit has its line.
#[test]
fn a_whole_track_excluded_and_the_robust_fit_are_said() {
    // The screening and the fit of the estimate through the loop model: the tracking error only.
    let toml = "[log]\ndrop_unlocked = false\nnco = false\n[satellites.cn0]\nzenith_cn0_dbhz = 54.0\nhorizon_cn0_dbhz = 14.0\n\
                elevation_exponent = 1.0\n";
    let options = {
        let mut o = stated();
        o.selection.channels = 0;
        o.systematic.time_offset = TimeOffsetOption::None;
        o.estimator.robust = Robust::Huber;
        o
    };
    let text = text_of(toml, 1, &options);
    assert!(text.contains("whole track excluded"), "{text}");
    assert!(text.contains("robust: Huber"), "{text}");
}

/// The z segment of the default session shaken with 1 mm/s²: nothing the loop can see.
#[test]
fn an_axis_shaken_too_little_is_unobservable() {
    let text = Scenario::default_toml();
    let (head, tail) = text.split_once("axis = \"z\"").unwrap();
    let toml = format!("{head}axis = \"z\"{}", tail.replacen("amplitude_mps2 = 3.0", "amplitude_mps2 = 0.001", 1));
    // The observability of the estimate through the loop model: the tracking error only.
    let toml = toml.replacen("nco = true", "nco = false", 1);
    let text = text_of(&toml, 1, &stated());
    assert!(text.contains("z: too little excitation"), "{text}");
    assert!(text.contains("unobservable"), "{text}");
}
