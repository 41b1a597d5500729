//! The trap suite: the mistakes a calibration engineer makes describing a
//! session, each on a simulated session whose logs (or options) are changed
//! the way a user might have got them wrong. Every one must come out either
//! accurate (within 2 % of |Γ|, and within 3σ) or flagged (exit status 3,
//! `trustworthy: false`); the correctly described session must come out
//! trustworthy.

mod common;

use common::{gsens, json, run, s, temp_dir, vec3};
use std::path::Path;

/// The receiver's loop as the simulator ran it (truth.json).
const RIGHT_LOOP: [&str; 6] = ["--order", "2", "--bn-hz", "3", "--loop-interval-s", "0.001"];

/// Rewrites every value of column `col` (0-based) of `src` into `dst`.
fn rewrite(dir: &Path, src: &str, dst: &str, f: impl Fn(usize, f64) -> f64) {
    let text = std::fs::read_to_string(dir.join(src)).unwrap();
    let mut lines = text.lines();
    let mut out = format!("{}\n", lines.next().unwrap());
    for l in lines {
        let fields: Vec<String> = l
            .split(',')
            .enumerate()
            .map(|(i, v)| match v.parse::<f64>() {
                Ok(x) => format!("{}", f(i, x)),
                Err(_) => v.to_string(),
            })
            .collect();
        out += &fields.join(",");
        out.push('\n');
    }
    std::fs::write(dir.join(dst), out).unwrap();
}

/// Outcome of one trap: (exit status, relative error |Γ̂ − Γ|/|Γ|, max |z|).
fn estimate(dir: &Path, imu: &str, tracking: &str, opts: &[&str], truth: [f64; 3]) -> (i32, f64, f64, String) {
    let out = dir.join("out.json");
    let (i, t, o) = (s(&dir.join(imu)), s(&dir.join(tracking)), s(&out));
    let mut args = vec!["estimate", "--imu", &i, "--tracking", &t, "--json", &o];
    args.extend_from_slice(opts);
    let r = run(&args);
    let code = r.status.code().unwrap_or(-1);
    assert!(matches!(code, 0 | 3), "{args:?}: {}", String::from_utf8_lossy(&r.stderr));
    let v = json(&out);
    assert_eq!(v["trustworthy"] == true, code == 0, "exit status and document agree");
    let g = vec3(&v["gamma_hz_per_mps2"]);
    let sg = vec3(&v["sigma_hz_per_mps2"]);
    let norm = truth.iter().map(|x| x * x).sum::<f64>().sqrt();
    let err = (0..3).map(|k| (g[k] - truth[k]).powi(2)).sum::<f64>().sqrt() / norm;
    let z = (0..3).map(|k| ((g[k] - truth[k]) / sg[k]).abs()).fold(0.0, f64::max);
    let codes: Vec<String> =
        v["warnings"].as_array().unwrap().iter().map(|w| w["code"].as_str().unwrap().to_string()).collect();
    (code, if err.is_nan() { f64::INFINITY } else { err }, if z.is_nan() { f64::INFINITY } else { z }, codes.join(","))
}

#[test]
fn every_mistake_is_accurate_or_flagged_and_the_clean_session_is_trusted() {
    let dir = temp_dir("traps");
    gsens(&["simulate", "--out", &s(&dir), "--seed", "21"]);
    let truth = vec3(&json(&dir.join("truth.json"))["gamma_imu_axes_hz_per_mps2"]);
    // Logs written wrongly.
    rewrite(&dir, "imu.csv", "imu_g.csv", |c, x| if c == 0 { x } else { x / 9.80665 });
    rewrite(&dir, "tracking.csv", "phase_cycles.csv", |c, x| if c == 5 { x / std::f64::consts::TAU } else { x });
    rewrite(&dir, "tracking.csv", "phase_deg.csv", |c, x| if c == 5 { x.to_degrees() } else { x });
    rewrite(&dir, "imu.csv", "imu_late.csv", |c, x| if c == 0 { x + 0.4 } else { x });
    rewrite(&dir, "imu.csv", "imu_ms.csv", |c, x| if c == 0 { x * 1e3 } else { x });
    rewrite(&dir, "tracking.csv", "phase_flipped.csv", |c, x| if c == 5 { -x } else { x });
    rewrite(&dir, "tracking.csv", "cn0_constant.csv", |c, x| if c == 3 { 45.0 } else { x });

    let right: Vec<&str> = RIGHT_LOOP.iter().copied().chain(["--logged-phase", "mean"]).collect();
    let with = |extra: &[&'static str]| -> Vec<&'static str> {
        let mut v: Vec<&'static str> = vec!["--order", "2", "--loop-interval-s", "0.001", "--logged-phase", "mean"];
        v.extend_from_slice(extra);
        v
    };
    let (code, err, z, codes) = estimate(&dir, "imu.csv", "tracking.csv", &right, truth);
    eprintln!("clean: exit {code}, error {:.2} %, max |z| {z:.2}, warnings [{codes}]", 100.0 * err);
    assert_eq!(code, 0, "the correctly described session is trustworthy: [{codes}]");
    assert!(err < 0.02 && z < 3.0, "clean: {err} {z}");

    let traps: Vec<(&str, &str, &str, Vec<&str>)> = vec![
        ("loop 10 % too wide", "imu.csv", "tracking.csv", with(&["--bn-hz", "3.3"])),
        ("loop 10 % too narrow", "imu.csv", "tracking.csv", with(&["--bn-hz", "2.7"])),
        ("--bn-hz 5 for a 3 Hz loop", "imu.csv", "tracking.csv", with(&["--bn-hz", "5"])),
        ("no loop options at all", "imu.csv", "tracking.csv", vec![]),
        ("loop interval left at the log's", "imu.csv", "tracking.csv", vec!["--bn-hz", "3"]),
        ("3rd order stated for a 2nd", "imu.csv", "tracking.csv", {
            let mut v = right.clone();
            v[1] = "3";
            v
        }),
        ("logged last, not mean", "imu.csv", "tracking.csv", RIGHT_LOOP.to_vec()),
        ("IMU in g", "imu_g.csv", "tracking.csv", right.clone()),
        ("phase in cycles", "imu.csv", "phase_cycles.csv", right.clone()),
        ("phase in degrees", "imu.csv", "phase_deg.csv", right.clone()),
        ("IMU clock 0.4 s late", "imu_late.csv", "tracking.csv", right.clone()),
        ("IMU stamps in ms", "imu_ms.csv", "tracking.csv", right.clone()),
        ("phase error of opposite sign", "imu.csv", "phase_flipped.csv", right.clone()),
        ("a constant C/N0 column", "imu.csv", "cn0_constant.csv", right.clone()),
        ("gradient gain 50", "imu.csv", "tracking.csv", {
            let mut v = right.clone();
            v.extend_from_slice(&["--method", "gradient", "--gain-k", "50"]);
            v
        }),
    ];
    let mut failures = Vec::new();
    for (name, imu, tracking, opts) in &traps {
        let (code, err, z, codes) = estimate(&dir, imu, tracking, opts, truth);
        let fine = code == 3 || (err < 0.02 && z < 3.0);
        eprintln!(
            "{name:<34} exit {code}  error {:>8.2} %  max |z| {z:>8.2}  [{codes}]  {}",
            100.0 * err,
            if fine { "ok" } else { "CONFIDENTLY WRONG" }
        );
        if !fine {
            failures.push(*name);
        }
    }
    assert!(failures.is_empty(), "confidently wrong: {failures:?}");
    // The sign is caught by its own check; a constant C/N0 column, ranked by
    // the channels' noise instead, loses nothing.
    let (code, _, _, codes) = estimate(&dir, "imu.csv", "phase_flipped.csv", &right, truth);
    assert_eq!((code, codes.as_str()), (3, "phase_sign"));
    let (code, err, z, codes) = estimate(&dir, "imu.csv", "cn0_constant.csv", &right, truth);
    assert!(code == 0 && err < 0.02 && z < 3.0, "constant C/N0: exit {code}, {err}, |z| {z:.2}, [{codes}]");
    assert_eq!(json(&dir.join("out.json"))["channel_ranking"], "noise");
    std::fs::remove_dir_all(&dir).ok();
}

/// README's former known gap: a TCXO shaken gently at one rate, the IMU time
/// offset searched. One σ of the offset turns the shaking's phase by far
/// more than the joint fit's linearization holds for, and Γ̂ moves with it
/// (on this seed by up to 4σ): it must be flagged, for that reason alone,
/// naming the fix. With the offset stated the same session is trustworthy
/// and within 3σ.
#[test]
fn an_offset_the_data_do_not_resolve_is_flagged() {
    let dir = temp_dir("traps-gentle");
    let scenario = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/scenarios/tcxo-gentle.toml");
    gsens(&["simulate", "--scenario", scenario, "--out", &s(&dir), "--seed", "1"]);
    let truth = vec3(&json(&dir.join("truth.json"))["gamma_imu_axes_hz_per_mps2"]);
    // The simulator logs the mean of each epoch's 1 ms discriminator outputs.
    let described = [&RIGHT_LOOP[..], &["--logged-phase", "mean"]].concat();
    let (code, _, z, codes) = estimate(&dir, "imu.csv", "tracking.csv", &described, truth);
    assert_eq!((code, codes.as_str()), (3, "loop_offset_unresolved"), "searched offset: |z| up to {z:.1}");
    // Stated, with the loop fitted freely: with the loop also pinned to its 2 %
    // tolerance this session's σ is too small on x (-3.1σ; an open gap of weak
    // TCXO sessions, docs/trust.md), which this test is not about.
    let stated = [&described[..], &["--time-offset", "0", "--loop-tolerance", "inf"]].concat();
    let (code, _, z, codes) = estimate(&dir, "imu.csv", "tracking.csv", &stated, truth);
    assert!(code == 0 && z < 3.0, "stated offset: exit {code}, |z| up to {z:.1}, warnings {codes}");
    // Described as logging the last update (the default): its scatter is 1/√25
    // of that prediction, which the units check flags, naming both fixes.
    let last = [&RIGHT_LOOP[..], &["--time-offset", "0"]].concat();
    let (code, _, _, codes) = estimate(&dir, "imu.csv", "tracking.csv", &last, truth);
    let message = json(&dir.join("out.json"))["warnings"][0]["message"].as_str().unwrap_or_default().to_string();
    assert_eq!((code, codes.as_str()), (3, "phase_units"), "{message}");
    assert!(message.contains("2π") && message.contains("mean of the 25 loop updates"), "{message}");
}

/// Warnings come by cause: a unit or time-base problem first (it explains
/// the rest), then the loop, then the shaking; and the shaking advice that a
/// wrong unit would produce ("shake harder" for an IMU stamped in
/// milliseconds, "shake more gently" for a phase in degrees) is not given
/// while the unit is flagged.
#[test]
fn unit_problems_come_first_and_silence_the_shaking_advice() {
    let dir = temp_dir("traps-order");
    gsens(&["simulate", "--out", &s(&dir), "--seed", "21"]);
    let truth = vec3(&json(&dir.join("truth.json"))["gamma_imu_axes_hz_per_mps2"]);
    rewrite(&dir, "imu.csv", "imu_ms.csv", |c, x| if c == 0 { x * 1e3 } else { x });
    rewrite(&dir, "tracking.csv", "tracking_ms.csv", |c, x| if c == 0 { x * 1e3 } else { x });
    rewrite(&dir, "tracking.csv", "phase_deg.csv", |c, x| if c == 5 { x.to_degrees() } else { x });
    let right: Vec<&str> = RIGHT_LOOP.iter().copied().chain(["--logged-phase", "mean"]).collect();
    for (name, imu, tracking, first) in [
        ("IMU stamps in ms", "imu_ms.csv", "tracking.csv", "time_units"),
        ("both logs in ms", "imu_ms.csv", "tracking_ms.csv", "time_units"),
        ("phase in degrees", "imu.csv", "phase_deg.csv", "phase_units"),
    ] {
        let (code, _, _, codes) = estimate(&dir, imu, tracking, &right, truth);
        eprintln!("{name}: exit {code} [{codes}]");
        assert_eq!((code, codes.split(',').next().unwrap()), (3, first), "{name}: [{codes}]");
        let doc = json(&dir.join("out.json"));
        for w in doc["warnings"].as_array().unwrap() {
            let (code, message) = (w["code"].as_str().unwrap(), w["message"].as_str().unwrap());
            if matches!(code, "discriminator_range" | "nothing_observable") {
                assert!(!message.contains("shake"), "{name}: {code}: {message}");
                assert!(message.contains(first), "{name}: {code}: {message}");
            }
        }
        for a in doc["axes"].as_array().unwrap() {
            let text = a["text"].as_str().unwrap();
            assert!(!text.contains("shake") && !text.contains("closer to"), "{name}: {text}");
        }
    }
    // No loop stated: the warning gives the loop found as the options that would state it.
    let (code, _, _, codes) = estimate(&dir, "imu.csv", "tracking.csv", &[], truth);
    assert!(code == 3 && codes.contains("loop_not_stated"), "[{codes}]");
    let doc = json(&dir.join("out.json"));
    let w = doc["warnings"].as_array().unwrap().iter().find(|w| w["code"] == "loop_not_stated").unwrap();
    let message = w["message"].as_str().unwrap().to_string();
    let flags = message.split_once("the loop found would be ").map_or("", |(_, f)| f);
    assert!(flags.starts_with("--order 2 --bn-hz "), "{message}");
    assert!(flags.contains(" --loop-interval-s ") && flags.contains(" --logged-phase "), "{message}");
    std::fs::remove_dir_all(&dir).ok();
}
