//! A simulated session's `truth.json` states the loop that made its log: an
//! estimate with no loop stated models it; loop options win, and the note
//! says whether they match it.

use gsens_calib::{CalibrationOptions, calibrate_files};
use gsens_core::LoggedPhase;
use gsens_inputs::take_truth_loop;
use gsens_sim::motion::Segment;
use gsens_sim::scenario::Scenario;
use std::path::Path;

/// The scenario of the TOML `extra`, then rest 2 s, each axis shaken for
/// `shake_s` at a 1.1 s period and 3 m/s², rest 2 s.
fn scenario(extra: &str, shake_s: f64) -> Scenario {
    let mut sc = Scenario::from_toml_str(extra).unwrap();
    sc.motion.segments = Segment::each_axis(2.0, shake_s, 1.1, 3.0);
    // The loop modelled is what this is about: the estimate through it, from the tracking error only.
    sc.log.nco = false;
    sc
}

fn vec3(v: &serde_json::Value) -> [f64; 3] {
    [0, 1, 2].map(|i| v[i].as_f64().unwrap_or(f64::NAN))
}

/// The note and the result document of the session in `dir` estimated with
/// `options` and the loop of its `truth.json` when they state none.
fn estimate(dir: &Path, options: CalibrationOptions) -> (String, serde_json::Value) {
    let mut settings = options.pipeline_settings().unwrap();
    let truth = dir.join("truth.json");
    let note = take_truth_loop(&mut settings, &truth).unwrap().note(&truth);
    let outcome = calibrate_files(&dir.join("tracking.csv"), &dir.join("imu.csv"), &settings).unwrap();
    (note, serde_json::from_str(&outcome.document(None).to_json_string().unwrap()).unwrap())
}

#[test]
fn the_loop_truth_json_states_is_modelled() {
    let d = tempfile::Builder::new().prefix("gsens-live-truth-loop-").tempdir().unwrap();
    // A 5 Hz loop (the options' default is 3 Hz), updated every 1 ms (the
    // default: the 25 ms log interval), logging the mean (default: last).
    let sc = scenario("[loop]\nbn_hz = 5.0", 10.0);
    gsens_sim::simulate_to_dir(&sc, 5, d.path(), |_| {}).unwrap();
    let truth = d.path().join("truth.json").display().to_string();
    let (text, v) = estimate(d.path(), CalibrationOptions::default());
    assert!(
        text.contains(&format!(
            "receiver loop: 2nd order, Bn 5 Hz, ζ 0.707, ωn/2π 1.501 Hz, updated every 0.001 s, logged: the mean of \
             the discriminator outputs (from {truth}"
        )),
        "{text}"
    );
    let l = &v["settings"]["receiver_loop"];
    // The stated loop is truth.json's; the loop check fits its ωn and finds it consistent.
    assert_eq!(l["spec"]["kind"].as_str(), Some("second_order"), "{l}");
    let j = &v["joint_fit"];
    assert!(j["stated_loop"].as_str().unwrap().starts_with("2nd order, Bn 5 Hz"), "{j}");
    assert_eq!(j["stated_loop_rejected"], false, "{j}");
    assert_eq!(l["interval_s"].as_f64(), Some(0.001), "{l}");
    assert_eq!(v["settings"]["logged_phase"], "mean");
    // The estimate of the right loop agrees with the truth (in the IMU's axes) within 4σ.
    let t: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&truth).unwrap()).unwrap();
    let (g, sig, tr) =
        (vec3(&v["gamma_hz_per_mps2"]), vec3(&v["sigma_hz_per_mps2"]), vec3(&t["gamma_imu_axes_hz_per_mps2"]));
    for i in 0..3 {
        assert!((g[i] - tr[i]).abs() < 4.0 * sig[i], "axis {i}: {} ± {} vs {}", g[i], sig[i], tr[i]);
    }
    // Loop options win, and the note says whether they match the truth's.
    let (text, v) = estimate(d.path(), {
        let mut o = CalibrationOptions::default();
        o.receiver_loop.bn_hz = Some(3.0);
        o
    });
    assert!(text.contains("receiver loop: from the options, not the one"), "{text}");
    assert!(v["joint_fit"]["stated_loop"].as_str().unwrap().starts_with("2nd order, Bn 3 Hz"), "{}", v["joint_fit"]);
    // A 3 Hz loop stated for a 5 Hz receiver: rejected, not trusted.
    assert_eq!(v["joint_fit"]["stated_loop_rejected"], true);
    assert_eq!(v["trustworthy"], false);
    let same = {
        let mut o = CalibrationOptions::default();
        o.receiver_loop.bn_hz = Some(5.0);
        o.receiver_loop.loop_interval_s = Some(0.001);
        o.receiver_loop.logged_phase = Some(LoggedPhase::Mean);
        o
    };
    let (text, _) = estimate(d.path(), same);
    assert!(text.contains("receiver loop: from the options, the same as the one"), "{text}");
}
