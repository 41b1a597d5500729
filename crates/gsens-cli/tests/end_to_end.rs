//! `gsens simulate` on the default scenario, then `gsens estimate` on its
//! files, as a user would: the truth within the estimate's own 3σ and within
//! 2 % of |Γ|; the same seed gives the same bytes.

mod common;

use common::{fails, gsens, json, vec3};

#[test]
fn simulate_then_estimate_recovers_the_truth() {
    let dir_scratch = tempfile::Builder::new().prefix("gsens-e2e-").tempdir().unwrap();
    let dir = dir_scratch.path().to_path_buf();
    let d = dir.to_str().unwrap();
    gsens(&["simulate", "--out", d, "--seed", "7"]);
    let out = dir.join("estimate.json");
    // The receiver's settings as the simulator wrote them (truth.json) and the
    // industrial IMU's datasheet accuracy (1000 ppm, 1 mrad).
    let text = gsens(&[
        "estimate",
        "--imu",
        &format!("{d}/imu.csv"),
        "--tracking",
        &format!("{d}/tracking.csv"),
        "--loop-interval-s",
        "0.001",
        "--logged-phase",
        "mean",
        "--imu-scale-sigma-ppm",
        "1000",
        "--imu-misalignment-sigma-mrad",
        "1",
        "--json",
        out.to_str().unwrap(),
    ]);
    assert!(text.contains("Γ̂ [Hz/(m/s²)]"), "{text}");
    let est = json(&out);
    let truth = json(&dir.join("truth.json"));
    let g = vec3(&est["gamma_hz_per_mps2"]);
    let s = vec3(&est["sigma_hz_per_mps2"]);
    let t = vec3(&truth["gamma_hz_per_mps2"]);
    assert_eq!(t, [0.09, 0.08, -0.08]);
    assert_eq!(est["observable"], serde_json::json!([true, true, true]));
    let norm = t.iter().map(|x| x * x).sum::<f64>().sqrt();
    let err = (0..3).map(|i| (g[i] - t[i]).powi(2)).sum::<f64>().sqrt();
    assert!(err < 0.02 * norm, "|Γ̂ − Γ| = {err} ({:.2} %)", 100.0 * err / norm);
    for i in 0..3 {
        assert!((g[i] - t[i]).abs() < 3.0 * s[i], "axis {i}: {} ± {} vs {}", g[i], s[i], t[i]);
    }
    // Compensation brings the shaking phase error back to its rest level.
    let before = est["rms_before_rad"].as_f64().unwrap();
    let after = est["rms_after_rad"].as_f64().unwrap();
    assert!(after < 0.3 * before, "{before} → {after}");
    for key in ["gamma_ppb_per_g", "imu_time_offset_s", "settings"] {
        assert!(!est[key].is_null(), "{key} missing");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn same_seed_same_bytes() {
    let base_scratch = tempfile::Builder::new().prefix("gsens-seed-").tempdir().unwrap();
    let base = base_scratch.path().to_path_buf();
    let (a, b, c) = (base.join("a"), base.join("b"), base.join("c"));
    gsens(&["simulate", "--out", a.to_str().unwrap(), "--seed", "3"]);
    gsens(&["simulate", "--out", b.to_str().unwrap(), "--seed", "3"]);
    gsens(&["simulate", "--out", c.to_str().unwrap(), "--seed", "4"]);
    for f in ["imu.csv", "tracking.csv", "truth.json"] {
        let (x, y) = (std::fs::read(a.join(f)).unwrap(), std::fs::read(b.join(f)).unwrap());
        assert!(x == y, "{f} differs between two runs with the same seed");
    }
    assert!(std::fs::read(a.join("tracking.csv")).unwrap() != std::fs::read(c.join("tracking.csv")).unwrap());
    let _ = std::fs::remove_dir_all(&base);
}

#[test]
fn demo_shows_estimate_next_to_truth() {
    let dir_scratch = tempfile::Builder::new().prefix("gsens-demo-test-").tempdir().unwrap();
    let dir = dir_scratch.path().to_path_buf();
    let doc = dir.join("demo.json");
    let text = gsens(&["demo", "--out", dir.to_str().unwrap(), "--json", doc.to_str().unwrap(), "--warmup-s", "3"]);
    let truth = vec3(&json(&dir.join("truth.json"))["gamma_hz_per_mps2"]);
    let v = json(&doc);
    assert_eq!(vec3(&v["truth_gamma_hz_per_mps2"]), truth);
    let gamma = vec3(&v["gamma_hz_per_mps2"]);
    // Each axis line: Γ̂, its 1σ, ppb/g, the truth and the error, as in the document.
    for (i, axis) in ["x", "y", "z"].iter().enumerate() {
        let line = text.lines().find(|l| l.trim_start().starts_with(&format!("{axis}  "))).expect("an axis line");
        let f: Vec<f64> =
            line.split_whitespace().skip(1).filter_map(|w| w.trim_start_matches('±').parse().ok()).collect();
        assert_eq!(f[0], (gamma[i] * 1e5).round() / 1e5, "{line}");
        assert_eq!(f[4], truth[i], "{line}");
        assert!((f[5] - (gamma[i] - truth[i])).abs() <= 5e-6, "{line}");
    }
    // The summary line is the norm of the errors against the truth's norm.
    let norm = |x: [f64; 3]| x.iter().map(|v| v * v).sum::<f64>().sqrt();
    let pct = 100.0 * norm([0, 1, 2].map(|i| gamma[i] - truth[i])) / norm(truth);
    assert!(text.contains(&format!("= {pct:.2} % of |Γ|")), "{pct:.2}: {text}");
    assert!(pct < 2.0, "{pct}");

    // The command line the demo prints gives its estimate: Γ̂, σ and the
    // covariance (which carries the scenario's IMU error model) to 1e-9.
    let command = text.split("(the command line: gsens ").nth(1).and_then(|r| r.split(")\n").next());
    let mut args: Vec<String> =
        command.expect("the demo prints its command line").split(' ').map(String::from).collect();
    let again = dir.join("again.json");
    args.extend(["--json".to_string(), again.to_str().unwrap().to_string()]);
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    assert!(args.contains(&"--warmup-s") && args.contains(&"--imu-scale-sigma-ppm"), "{args:?}");
    let _ = gsens(&args);
    let w = json(&again);
    let flat = |v: &serde_json::Value| -> Vec<f64> {
        let mut out = Vec::new();
        let mut stack = vec![v.clone()];
        while let Some(x) = stack.pop() {
            match x {
                serde_json::Value::Array(a) => stack.extend(a),
                x => out.push(x.as_f64().expect("a number")),
            }
        }
        out
    };
    for key in ["gamma_hz_per_mps2", "sigma_hz_per_mps2", "covariance_hz_per_mps2_sq"] {
        let (a, b) = (flat(&v[key]), flat(&w[key]));
        assert_eq!(a.len(), b.len(), "{key}");
        for (x, y) in a.iter().zip(&b) {
            assert!((x - y).abs() <= 1e-9 * x.abs().max(1e-30), "{key}: demo {x} vs its command {y}");
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn scenario_command_prints_a_parsable_default() {
    let text = gsens(&["scenario"]);
    assert!(text.contains("gamma_hz_per_mps2 = [0.09, 0.08, -0.08]"));
    let dir_scratch = tempfile::Builder::new().prefix("gsens-scn-").tempdir().unwrap();
    let dir = dir_scratch.path().to_path_buf();
    std::fs::create_dir_all(&dir).unwrap();
    let bad = dir.join("bad.toml");
    std::fs::write(&bad, text.replace("bn_hz = 3.0", "bn_hz = -3.0")).unwrap();
    let simulate = ["simulate", "--scenario", bad.to_str().unwrap(), "--out", dir.to_str().unwrap()];
    let err = fails(&simulate);
    assert!(err.contains("bad.toml") && err.contains("bn_hz"), "{err}");
    std::fs::write(&bad, text.replace("bn_hz = 3.0", "bn_hz = 3.0\nbandwidth = 2")).unwrap();
    let err = fails(&simulate);
    assert!(err.contains("bandwidth"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn response_reports_the_paper_loop_peak() {
    let dir_scratch = tempfile::Builder::new().prefix("gsens-resp-").tempdir().unwrap();
    let dir = dir_scratch.path().to_path_buf();
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("r.json");
    gsens(&["response", "--json", out.to_str().unwrap()]);
    let r = json(&out);
    // docs/conventions.md: peak at ωn/2π = 0.900 Hz with π/(ζωn) = 0.785 rad/Hz.
    assert!((r["peak_hz"].as_f64().unwrap() - 0.9003).abs() < 1e-3);
    let wn = 2.0 * 3.0 / (std::f64::consts::FRAC_1_SQRT_2 + 1.0 / (4.0 * std::f64::consts::FRAC_1_SQRT_2));
    let expected = std::f64::consts::PI / (std::f64::consts::FRAC_1_SQRT_2 * wn);
    assert!((r["peak_rad_per_hz"].as_f64().unwrap() - expected).abs() < 1e-3);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn session_shaken_only_along_x_and_y_reports_z_unobservable() {
    let dir_scratch = tempfile::Builder::new().prefix("gsens-xy-").tempdir().unwrap();
    let dir = dir_scratch.path().to_path_buf();
    std::fs::create_dir_all(&dir).unwrap();
    let text = gsens(&["scenario"]);
    // The z segment shaken with 1 mm/s²: nothing the loop can see.
    let (head, tail) = text.split_once("axis = \"z\"").unwrap();
    let scenario = format!("{head}axis = \"z\"{}", tail.replacen("amplitude_mps2 = 3.0", "amplitude_mps2 = 0.001", 1));
    let path = dir.join("xy.toml");
    std::fs::write(&path, scenario).unwrap();
    let out = dir.join("e.json");
    let text = gsens(&[
        "demo",
        "--scenario",
        path.to_str().unwrap(),
        "--out",
        dir.to_str().unwrap(),
        "--json",
        out.to_str().unwrap(),
    ]);
    assert!(text.contains("z: too little excitation"), "{text}");
    assert!(text.contains("unobservable"), "{text}");
    let est = json(&out);
    assert_eq!(est["observable"], serde_json::json!([true, true, false]));
    assert!(est["gamma_hz_per_mps2"][2].is_null());
    assert!(est["sigma_hz_per_mps2"][2].is_null());
    let _ = std::fs::remove_dir_all(&dir);
}
