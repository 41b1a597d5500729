//! What a new user meets first, on simulated sessions rewritten the way a
//! user might have written them: `gsens report --truth` modelling the loop
//! the simulator states in `truth.json`, a 10 s session, and logs whose
//! clocks have different bases.

mod common;

use common::{fails, gsens, gsens_any, json, s, temp_dir, vec3};

use std::path::Path;

/// A scenario TOML: `extra` sections, then rest 2 s, each axis shaken for
/// `shake_s` at a 1.1 s period and 3 m/s², rest 2 s.
fn scenario(dir: &Path, extra: &str, shake_s: f64) -> String {
    let mut t = format!("{extra}\n[[motion.segments]]\nkind = \"rest\"\nduration_s = 2.0\n");
    for axis in ["x", "y", "z"] {
        t += &format!(
            "[[motion.segments]]\nkind = \"shake\"\naxis = \"{axis}\"\nduration_s = {shake_s}\nperiod_s = 1.1\namplitude_mps2 = 3.0\n"
        );
    }
    t += "[[motion.segments]]\nkind = \"rest\"\nduration_s = 2.0\n";
    let p = dir.join("scenario.toml");
    std::fs::write(&p, t).unwrap();
    s(&p)
}

#[test]
fn report_models_the_loop_truth_json_states() {
    let d = temp_dir("newcomer-report");
    // A 5 Hz loop (the CLI's default is 3 Hz), updated every 1 ms (the
    // default: the 25 ms log interval), logging the mean (default: last).
    let sc = scenario(&d, "[loop]\nbn_hz = 5.0", 10.0);
    let sim = d.join("sim");
    gsens(&["simulate", "--scenario", &sc, "--out", &s(&sim), "--seed", "5"]);
    let (imu, trk, truth) = (s(&sim.join("imu.csv")), s(&sim.join("tracking.csv")), s(&sim.join("truth.json")));
    let report = |out: &str, extra: &[&str]| {
        let out = s(&d.join(out));
        let (text, _) = gsens_any(
            &[&["report", "--imu", &imu, "--tracking", &trk, "--truth", &truth, "--out", &out], extra].concat(),
        );
        (text, json(&Path::new(&out).join("report.json")))
    };
    let (text, v) = report("from-truth", &[]);
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
    let t = json(&sim.join("truth.json"));
    let (g, sig, tr) =
        (vec3(&v["gamma_hz_per_mps2"]), vec3(&v["sigma_hz_per_mps2"]), vec3(&t["gamma_imu_axes_hz_per_mps2"]));
    for i in 0..3 {
        assert!((g[i] - tr[i]).abs() < 4.0 * sig[i], "axis {i}: {} ± {} vs {}", g[i], sig[i], tr[i]);
    }
    // Loop options win, and the note says whether they match the truth's.
    let (text, v) = report("options", &["--bn-hz", "3"]);
    assert!(text.contains("receiver loop: from the options, not the one"), "{text}");
    assert!(v["joint_fit"]["stated_loop"].as_str().unwrap().starts_with("2nd order, Bn 3 Hz"), "{}", v["joint_fit"]);
    // A 3 Hz loop stated for a 5 Hz receiver: rejected, not trusted.
    assert_eq!(v["joint_fit"]["stated_loop_rejected"], true);
    assert_eq!(v["trustworthy"], false);
    let (text, _) = report("same", &["--bn-hz", "5", "--loop-interval-s", "0.001", "--logged-phase", "mean"]);
    assert!(text.contains("receiver loop: from the options, the same as the one"), "{text}");
}

#[test]
fn a_ten_second_session_is_estimated_with_the_screening_on() {
    let d = temp_dir("newcomer-short");
    let sc = scenario(&d, "[session]\nduration_s = 10.0", 2.0);
    let sim = d.join("sim");
    gsens(&["simulate", "--scenario", &sc, "--out", &s(&sim), "--seed", "3"]);
    let est = d.join("est.json");
    let text = gsens(&[
        "estimate",
        "--imu",
        &s(&sim.join("imu.csv")),
        "--tracking",
        &s(&sim.join("tracking.csv")),
        "--loop-interval-s",
        "0.001",
        "--logged-phase",
        "mean",
        "--json",
        &s(&est),
    ]);
    let v = json(&est);
    assert!(v["epochs_used"].as_u64().unwrap() >= 200, "{text}");
    for c in v["channels"].as_array().unwrap() {
        let sc = &c["screening"];
        assert_eq!((sc["slips"].as_u64(), sc["rows_cn0_drop"].as_u64()), (Some(0), Some(0)), "{c}");
    }
    // The gain test's 10 s window fits once: the whole-track test (two windows) is reported as not checked.
    assert!(text.contains("not checked: whole-track gain (one 10 s window tested; needs two)"), "{text}");
    assert!(!text.contains("slip") && !text.contains("C/N0 drop"), "{text}");
}

/// `path`'s CSV with the first column (t_s) mapped by `f`.
fn rewrite_times(path: &Path, f: impl Fn(f64) -> f64) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let mut out = String::from(lines.next().unwrap());
    out.push('\n');
    for line in lines {
        let (t, rest) = line.split_once(',').unwrap();
        out += &format!("{},{rest}\n", f(t.parse().unwrap()));
    }
    std::fs::write(path, out).unwrap();
}

#[test]
fn clocks_on_different_bases_are_named_with_the_fix() {
    let d = temp_dir("newcomer-clocks");
    let sc = scenario(&d, "", 2.0);
    let sim = d.join("sim");
    gsens(&["simulate", "--scenario", &sc, "--out", &s(&sim), "--seed", "2"]);
    let estimate =
        || fails(&["estimate", "--imu", &s(&sim.join("imu.csv")), "--tracking", &s(&sim.join("tracking.csv"))]);
    // The IMU in Unix time (the session's start, 2024-02-08 12:00:00 UTC), the tracking since power-on.
    rewrite_times(&sim.join("imu.csv"), |t| t + 1_707_393_600.0);
    let e = estimate();
    assert!(e.contains("do not overlap in time: the IMU covers [1707393600, 1707393610] s"), "{e}");
    assert!(e.contains("the IMU's t_s look like Unix time (seconds since 1970-01-01)"), "{e}");
    assert!(e.contains("the tracking's like GPS seconds of the week or seconds since power-on"), "{e}");
    assert!(e.contains("Both logs must be stamped by one clock, in seconds"), "{e}");
    // Back to seconds since power-on, the tracking in milliseconds.
    rewrite_times(&sim.join("imu.csv"), |t| t - 1_707_393_600.0);
    rewrite_times(&sim.join("tracking.csv"), |t| t * 1000.0);
    let e = estimate();
    assert!(e.contains("the tracking's t_s are in milliseconds"), "{e}");
    assert!(e.contains("divide them by 1000"), "{e}");
}
