//! The simulator's commands as a user meets them: `gsens simulate` then
//! `gsens estimate` on its files, `gsens demo` printing its estimate next to
//! the truth and the command line that gives it, `gsens scenario` printing a
//! default that `gsens simulate` reads, `gsens response`. What the estimate
//! recovers and what the simulator writes are tested where they are made:
//! `gsens-montecarlo`'s tests (`simulated_sessions.rs`) and `gsens-sim`'s.

mod common;

use common::{fails, gsens, json, vec3};

#[test]
fn simulate_then_estimate_write_their_files() {
    let dir_scratch = tempfile::Builder::new().prefix("gsens-e2e-").tempdir().unwrap();
    let dir = dir_scratch.path();
    let d = dir.to_str().unwrap();
    gsens(&["simulate", "--out", d, "--seed", "7"]);
    let out = dir.join("estimate.json");
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
        "--json",
        out.to_str().unwrap(),
    ]);
    assert!(text.contains("Γ̂ [Hz/(m/s²)]"), "{text}");
    assert_eq!(json(&out)["observable"], serde_json::json!([true, true, true]));
    assert_eq!(vec3(&json(&dir.join("truth.json"))["gamma_hz_per_mps2"]), [0.09, 0.08, -0.08]);
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
fn scenario_command_prints_a_default_that_simulate_reads() {
    let text = gsens(&["scenario"]);
    assert!(text.contains("gamma_hz_per_mps2 = [0.09, 0.08, -0.08]"));
    let dir_scratch = tempfile::Builder::new().prefix("gsens-scn-").tempdir().unwrap();
    let dir = dir_scratch.path();
    let bad = dir.join("bad.toml");
    std::fs::write(&bad, text.replace("bn_hz = 3.0", "bn_hz = -3.0")).unwrap();
    let err = fails(&["simulate", "--scenario", bad.to_str().unwrap(), "--out", dir.to_str().unwrap()]);
    assert!(err.contains("bad.toml") && err.contains("bn_hz"), "{err}");
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
