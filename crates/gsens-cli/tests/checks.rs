//! The input checks through the binary: a smoke test that a flagged session
//! exits with status 3, that the document says the same, and that the warning
//! is printed before the estimate. The checks themselves are tested against
//! the library (`crates/gsens-montecarlo/tests/checks.rs` and `traps.rs`).

mod common;

use common::{gsens, gsens_any, json, s, temp_dir};

/// The simulated session's logs, the receiver's loop as truth.json states it.
fn estimate(dir: &std::path::Path, imu: &str, out: &str) -> (String, serde_json::Value) {
    let out_json = dir.join(out);
    let (imu, tracking, json_path) = (s(&dir.join(imu)), s(&dir.join("tracking.csv")), s(&out_json));
    let (text, trusted) = gsens_any(&[
        "estimate",
        "--imu",
        &imu,
        "--tracking",
        &tracking,
        "--loop-interval-s",
        "0.001",
        "--logged-phase",
        "mean",
        "--json",
        &json_path,
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
