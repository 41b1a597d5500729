//! Input plausibility checks on a simulated session whose logs were
//! rewritten as a user might have written them.

mod common;

use common::{gsens, gsens_any, json, s, temp_dir};

/// The simulated session's logs, the receiver's loop as truth.json states it.
fn estimate(dir: &std::path::Path, imu: &str, out: &str) -> (String, serde_json::Value) {
    let out_json = dir.join(out);
    let (text, trusted) = gsens_any(&[
        "estimate",
        "--imu",
        &s(&dir.join(imu)),
        "--tracking",
        &s(&dir.join("tracking.csv")),
        "--loop-interval-s",
        "0.001",
        "--logged-phase",
        "mean",
        "--json",
        &s(&out_json),
    ]);
    let v = json(&out_json);
    assert_eq!(v["trustworthy"], trusted, "the exit status says what the document says");
    (text, v)
}

#[test]
fn an_imu_logged_in_g_is_flagged_and_a_correct_one_is_not() {
    let dir = temp_dir("checks-g");
    gsens(&["simulate", "--out", &s(&dir), "--seed", "5"]);
    let (_, clean) = estimate(&dir, "imu.csv", "clean.json");
    assert_eq!(clean["warnings"], serde_json::json!([]), "{}", clean["warnings"]);
    // The same IMU log in g.
    let text = std::fs::read_to_string(dir.join("imu.csv")).unwrap();
    let mut lines = text.lines();
    let mut g = String::from(lines.next().unwrap());
    g.push('\n');
    for l in lines {
        let f: Vec<f64> = l.split(',').map(|v| v.parse().unwrap()).collect();
        g += &format!("{},{},{},{}\n", f[0], f[1] / 9.80665, f[2] / 9.80665, f[3] / 9.80665);
    }
    std::fs::write(dir.join("imu_g.csv"), g).unwrap();
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
