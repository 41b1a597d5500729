//! Input plausibility checks on a simulated session whose logs were
//! rewritten as a user might have written them.

mod common;

use common::{gsens, gsens_any, json, s, temp_dir};
use std::path::Path;

/// The simulated session's logs, the receiver's loop as truth.json states it.
fn estimate(dir: &std::path::Path, imu: &str, out: &str) -> (String, serde_json::Value) {
    estimate_with(dir, imu, "tracking.csv", out, &["--logged-phase", "mean"])
}

/// [`estimate`] with another tracking log and options.
fn estimate_with(dir: &Path, imu: &str, tracking: &str, out: &str, extra: &[&str]) -> (String, serde_json::Value) {
    let out_json = dir.join(out);
    let (imu, tracking, json_path) = (s(&dir.join(imu)), s(&dir.join(tracking)), s(&out_json));
    let mut args = vec!["estimate", "--imu", &imu, "--tracking", &tracking, "--loop-interval-s", "0.001"];
    args.extend_from_slice(extra);
    args.extend_from_slice(&["--json", &json_path]);
    let (text, trusted) = gsens_any(&args);
    let v = json(&out_json);
    assert_eq!(v["trustworthy"], trusted, "the exit status says what the document says");
    (text, v)
}

/// The warning codes of a result document.
fn codes(v: &serde_json::Value) -> Vec<String> {
    v["warnings"].as_array().unwrap().iter().map(|w| w["code"].as_str().unwrap().to_owned()).collect()
}

/// The message of the warning `code`.
fn message(v: &serde_json::Value, code: &str) -> String {
    let w = v["warnings"].as_array().unwrap().iter().find(|w| w["code"] == code);
    w.unwrap_or_else(|| panic!("no {code}: {}", v["warnings"]))["message"].as_str().unwrap().to_owned()
}

/// Rewrites column `col` of the CSV `src` in `dir` into `dst` with `f`.
fn rewrite(dir: &Path, src: &str, dst: &str, col: &str, f: impl Fn(f64) -> f64) {
    rewrite_rows(dir, src, dst, |row, header| {
        let i = header.iter().position(|h| *h == col).unwrap();
        row[i] = f(row[i]);
    });
}

/// Rewrites the rows of the CSV `src` in `dir` into `dst` with `f(row, header)`
/// (fields that are not numbers, NaN in `row`, are written back as they were).
fn rewrite_rows(dir: &Path, src: &str, dst: &str, f: impl Fn(&mut [f64], &[&str])) {
    let text = std::fs::read_to_string(dir.join(src)).unwrap();
    let mut lines = text.lines();
    let header_line = lines.next().unwrap();
    let header: Vec<&str> = header_line.split(',').collect();
    let mut out = format!("{header_line}\n");
    for l in lines {
        let fields: Vec<&str> = l.split(',').collect();
        // Tracking logs have an empty elevation now and then: keep non-numeric fields as they are.
        let mut row: Vec<f64> = fields.iter().map(|v| v.parse().unwrap_or(f64::NAN)).collect();
        f(&mut row, &header);
        let printed: Vec<String> =
            row.iter().zip(&fields).map(|(v, raw)| if v.is_nan() { raw.to_string() } else { v.to_string() }).collect();
        out += &printed.join(",");
        out.push('\n');
    }
    std::fs::write(dir.join(dst), out).unwrap();
}

#[test]
fn an_imu_logged_in_g_is_flagged_and_a_correct_one_is_not() {
    let dir = temp_dir("checks-g");
    gsens(&["simulate", "--out", &s(&dir), "--seed", "5"]);
    let (_, clean) = estimate(&dir, "imu.csv", "clean.json");
    assert_eq!(clean["warnings"], serde_json::json!([]), "{}", clean["warnings"]);
    // The same IMU log in g.
    common::imu_in_g(&dir.join("imu.csv"), &dir.join("imu_g.csv"));
    let (text, v) = estimate(&dir, "imu_g.csv", "g.json");
    let codes: Vec<&str> = v["warnings"].as_array().unwrap().iter().map(|w| w["code"].as_str().unwrap()).collect();
    assert_eq!(codes, ["imu_units"], "{}", v["warnings"]);
    assert!(v["warnings"][0]["message"].as_str().unwrap().contains("in g"), "{}", v["warnings"]);
    // Printed before the estimate.
    let (w, est) = (text.find("warning [imu_units]").unwrap(), text.find("Γ̂ [Hz/(m/s²)]").unwrap());
    assert!(w < est, "{text}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn isolated_imu_spikes_are_replaced_and_reported() {
    let dir = temp_dir("checks-spikes");
    gsens(&["simulate", "--out", &s(&dir), "--seed", "6"]);
    let truth = common::vec3(&json(&dir.join("truth.json"))["gamma_imu_axes_hz_per_mps2"]);
    // Three corrupted samples, one per axis, while the board is shaken.
    let text = std::fs::read_to_string(dir.join("imu.csv")).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let n = lines.len();
    for (j, (axis, v)) in [(1, 1000.0), (2, -400.0), (3, 250.0)].into_iter().enumerate() {
        let k = n / 5 + j * n / 4;
        let mut f: Vec<String> = lines[k].split(',').map(String::from).collect();
        f[axis] = v.to_string();
        lines[k] = f.join(",");
    }
    std::fs::write(dir.join("imu_spiked.csv"), lines.join("\n") + "\n").unwrap();
    let (_, v) = estimate(&dir, "imu_spiked.csv", "spiked.json");
    let codes: Vec<&str> = v["warnings"].as_array().unwrap().iter().map(|w| w["code"].as_str().unwrap()).collect();
    assert_eq!(codes, ["imu_spikes"], "{}", v["warnings"]);
    assert!(v["warnings"][0]["message"].as_str().unwrap().starts_with("3 isolated"), "{}", v["warnings"]);
    let g = common::vec3(&v["gamma_hz_per_mps2"]);
    let sigma = common::vec3(&v["sigma_hz_per_mps2"]);
    for i in 0..3 {
        assert!((g[i] - truth[i]).abs() < 3.0 * sigma[i], "axis {i}: {} vs {} ± {}", g[i], truth[i], sigma[i]);
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// Rewrites the lines of `src` in `dir` (header first) into `dst` with `f`.
fn edit_lines(dir: &Path, src: &str, dst: &str, f: impl FnOnce(&mut Vec<String>)) {
    let mut lines: Vec<String> = std::fs::read_to_string(dir.join(src)).unwrap().lines().map(String::from).collect();
    f(&mut lines);
    std::fs::write(dir.join(dst), lines.join("\n") + "\n").unwrap();
}

/// Gives data rows `first..first + n` (0-based, after the header) the values of
/// row `first − 1` in the columns `cols`, as a stuck sensor would.
fn hold(lines: &mut [String], cols: &[usize], first: usize, n: usize) {
    let held: Vec<String> = lines[first].split(',').map(String::from).collect();
    for line in &mut lines[first + 1..first + 1 + n] {
        let mut f: Vec<String> = line.split(',').map(String::from).collect();
        for &c in cols {
            f[c] = held[c].clone();
        }
        *line = f.join(",");
    }
}

/// A second clean session made another way: another seed, the `last`
/// discriminator output logged, a consumer MEMS IMU (16-bit over ±4 g) at
/// 100 Hz.
fn other_clean_session(name: &str) -> common::TestDir {
    let dir = temp_dir(name);
    let scenario = dir.join("scenario.toml");
    std::fs::write(&scenario, "[log]\nphase = \"last\"\n[imu]\npreset = \"consumer_mems\"\nrate_hz = 100.0\n").unwrap();
    gsens(&["simulate", "--out", &s(&dir), "--seed", "11", "--scenario", &s(&scenario)]);
    dir
}

#[test]
fn a_phase_error_in_cycles_or_degrees_is_flagged_and_one_in_radians_is_not() {
    let dir = temp_dir("checks-phase");
    gsens(&["simulate", "--out", &s(&dir), "--seed", "5"]);
    rewrite(&dir, "tracking.csv", "cycles.csv", "phase_err_rad", |v| v / std::f64::consts::TAU);
    rewrite(&dir, "tracking.csv", "degrees.csv", "phase_err_rad", f64::to_degrees);
    let mean = ["--logged-phase", "mean"];
    let (_, v) = estimate_with(&dir, "imu.csv", "cycles.csv", "cycles.json", &mean);
    assert_eq!(codes(&v), ["phase_units"], "{}", v["warnings"]);
    assert!(message(&v, "phase_units").contains("in cycles; multiply phase_err_rad by 2π"), "{}", v["warnings"]);
    let (_, v) = estimate_with(&dir, "imu.csv", "degrees.csv", "degrees.json", &mean);
    // Γ̂ 57 times too large also overflows the discriminator's range.
    assert!(codes(&v).contains(&"phase_units".to_owned()), "{}", v["warnings"]);
    assert!(message(&v, "phase_units").contains("in degrees; multiply phase_err_rad by π/180"), "{}", v["warnings"]);
    std::fs::remove_dir_all(&dir).ok();

    // Another clean session, logging the latest discriminator output: silent; in cycles: flagged.
    let dir = other_clean_session("checks-phase-last");
    let last = ["--logged-phase", "last"];
    let (_, v) = estimate_with(&dir, "imu.csv", "tracking.csv", "clean.json", &last);
    assert_eq!(v["warnings"], serde_json::json!([]), "{}", v["warnings"]);
    rewrite(&dir, "tracking.csv", "cycles.csv", "phase_err_rad", |v| v / std::f64::consts::TAU);
    let (_, v) = estimate_with(&dir, "imu.csv", "cycles.csv", "cycles.json", &last);
    assert_eq!(codes(&v), ["phase_units"], "{}", v["warnings"]);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn stuck_and_clipped_imu_samples_are_flagged_and_left_out() {
    let dir = temp_dir("checks-stuck");
    gsens(&["simulate", "--out", &s(&dir), "--seed", "6"]);
    let truth = common::vec3(&json(&dir.join("truth.json"))["gamma_imu_axes_hz_per_mps2"]);
    // x held for 0.5 s (20 samples at 40 Hz) while the board is shaken along x (10–40 s).
    edit_lines(&dir, "imu.csv", "stuck.csv", |lines| hold(lines, &[1], 20 * 40, 20));
    let (_, v) = estimate(&dir, "stuck.csv", "stuck.json");
    assert_eq!(codes(&v), ["imu_stuck"], "{}", v["warnings"]);
    let m = message(&v, "imu_stuck");
    assert!(m.starts_with("1 run(s)") && m.contains("on axis x (21 samples"), "{m}");
    assert!(m.contains("left out of the estimate"), "{m}");
    let (g, sigma) = (common::vec3(&v["gamma_hz_per_mps2"]), common::vec3(&v["sigma_hz_per_mps2"]));
    for i in 0..3 {
        assert!((g[i] - truth[i]).abs() < 3.0 * sigma[i], "axis {i}: {} vs {} ± {}", g[i], truth[i], sigma[i]);
    }

    // The logger repeating whole samples, 5 times each, every 10 s.
    edit_lines(&dir, "imu.csv", "repeated.csv", |lines| {
        for first in (600..lines.len() - 10).step_by(400) {
            hold(lines, &[1, 2, 3], first, 5);
        }
    });
    let (_, v) = estimate(&dir, "repeated.csv", "repeated.json");
    assert_eq!(codes(&v), ["imu_stuck"], "{}", v["warnings"]);
    assert!(message(&v, "imu_stuck").contains("axis x, y, z"), "{}", v["warnings"]);

    // x clipped at ±2 m/s² (the shake's amplitude is 3 m/s²): the x shake is left out, x unobservable.
    rewrite(&dir, "imu.csv", "clipped.csv", "fx_mps2", |v| v.clamp(-2.0, 2.0));
    let (_, v) = estimate(&dir, "clipped.csv", "clipped.json");
    assert_eq!(codes(&v), ["imu_clipped"], "{}", v["warnings"]);
    let m = message(&v, "imu_clipped");
    assert!(m.contains("on axis x (") && (m.contains(" at 2 m/s²") || m.contains(" at -2 m/s²")), "{m}");
    assert!(v["gamma_hz_per_mps2"][0].is_null(), "{}", v["gamma_hz_per_mps2"]);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_quantized_clean_imu_is_not_flagged_and_a_stuck_one_is() {
    let dir = temp_dir("checks-quantized");
    gsens(&["simulate", "--out", &s(&dir), "--seed", "7"]);
    // 12 bits over ±8 g: a step of 0.038 m/s², 35 times the simulated IMU's noise, so the rests read one value.
    let q = 16.0 * 9.80665 / 4096.0;
    rewrite_rows(&dir, "imu.csv", "coarse.csv", |row, _| {
        for v in &mut row[1..] {
            *v = (*v / q).round() * q;
        }
    });
    let (_, v) = estimate(&dir, "coarse.csv", "coarse.json");
    assert_eq!(v["warnings"], serde_json::json!([]), "{}", v["warnings"]);
    // Stuck for 0.5 s during the x shake: found by its release although the noise cannot tell.
    edit_lines(&dir, "coarse.csv", "coarse_stuck.csv", |lines| hold(lines, &[1], 20 * 40, 20));
    let (_, v) = estimate(&dir, "coarse_stuck.csv", "coarse_stuck.json");
    assert_eq!(codes(&v), ["imu_stuck"], "{}", v["warnings"]);
    assert!(message(&v, "imu_stuck").contains("none (noise below the step)"), "{}", v["warnings"]);
    std::fs::remove_dir_all(&dir).ok();
    // The consumer MEMS session (16 bits over ±4 g, at 100 Hz): silent.
    let dir = other_clean_session("checks-quantized-mems");
    let (_, v) = estimate_with(&dir, "imu.csv", "tracking.csv", "clean.json", &["--logged-phase", "last"]);
    assert_eq!(v["warnings"], serde_json::json!([]), "{}", v["warnings"]);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn time_stamps_in_milliseconds_are_named() {
    let dir = temp_dir("checks-ms");
    gsens(&["simulate", "--out", &s(&dir), "--seed", "5"]);
    rewrite(&dir, "imu.csv", "imu_ms.csv", "t_s", |t| t * 1e3);
    rewrite(&dir, "tracking.csv", "tracking_ms.csv", "t_s", |t| t * 1e3);
    let (_, v) = estimate(&dir, "imu_ms.csv", "imu_ms.json");
    // Named as the cause (the other warnings are its consequences), and not trustworthy.
    assert!(codes(&v).contains(&"time_units".to_string()), "{}", v["warnings"]);
    assert_eq!(v["trustworthy"], false);
    assert!(message(&v, "time_units").contains("IMU's sample interval is 25 s"), "{}", v["warnings"]);
    // Both in milliseconds: the time-offset search would end at its limit, so the offset is stated.
    let (_, v) = estimate_with(
        &dir,
        "imu_ms.csv",
        "tracking_ms.csv",
        "both_ms.json",
        &["--logged-phase", "mean", "--time-offset", "none"],
    );
    assert_eq!(codes(&v).iter().filter(|c| *c == "time_units").count(), 2, "{}", v["warnings"]);
    assert_eq!(v["trustworthy"], false);
    assert!(message(&v, "time_units").contains("tracking log's interval is 25 s"), "{}", v["warnings"]);
    std::fs::remove_dir_all(&dir).ok();
}
