//! `gsens predict`: the table from a result document and a tone, the same
//! numbers as `gsens_calib::predict` (which `crates/gsens-calib/tests/
//! predict.rs` checks against the simulator), and errors naming the input.

mod common;
use common::*;

#[test]
fn predicts_from_a_result_document_and_refuses_bad_input() {
    let dir = temp_dir("predict");
    let sim = dir.join("sim");
    gsens(&["simulate", "--out", sim.to_str().unwrap(), "--seed", "1"]);
    let doc = dir.join("r.json");
    let (imu, trk) = (sim.join("imu.csv"), sim.join("tracking.csv"));
    gsens_any(&[
        "estimate",
        "--imu",
        imu.to_str().unwrap(),
        "--tracking",
        trk.to_str().unwrap(),
        "--order",
        "2",
        "--bn-hz",
        "3",
        "--loop-interval-s",
        "0.001",
        "--logged-phase",
        "mean",
        "--json",
        doc.to_str().unwrap(),
    ]);
    let out = dir.join("p.json");
    let text = gsens(&[
        "predict",
        "--from",
        doc.to_str().unwrap(),
        "--tone",
        "0.91:3,0,0",
        "--levels",
        "1,2",
        "--json",
        out.to_str().unwrap(),
    ]);
    let p = json(&out);
    let rows = p["predictions"].as_array().unwrap();
    // Twice the shaking, twice the g-induced jitter; compensated far below.
    let v1 = rows[0]["vibration_rad"].as_array().unwrap();
    let v2 = rows[1]["vibration_rad"].as_array().unwrap();
    let (u1, c1, u2) = (v1[0].as_f64().unwrap(), v1[1].as_f64().unwrap(), v2[0].as_f64().unwrap());
    assert!((u2 / u1 - 2.0).abs() < 1e-9, "{u1} {u2}");
    assert!(c1 < u1 / 10.0, "{c1} vs {u1}");
    // At level 2 (3σ of 0.9 rad) the uncompensated loop fails the 3σ rule, the compensated one keeps lock.
    assert_eq!(rows[1]["keeps_lock"], serde_json::json!([false, true]), "{text}");
    assert!(text.contains("NO / yes"), "{text}");
    assert!(text.contains("oscillator OCXO;"), "{text}");

    let psd = dir.join("v.csv");
    std::fs::write(&psd, "f_hz,psd_x,psd_y,psd_z\n5,0.01,0.01,0.04\n2,0.2,0.2,0.8\n").unwrap();
    let e = fails(&["predict", "--from", doc.to_str().unwrap(), "--psd", psd.to_str().unwrap()]);
    assert!(e.contains("v.csv: line 3") && e.contains("f_hz"), "{e}");
    let e = fails(&["predict", "--gamma", "0.09,0.08,-0.08", "--sigma", "0.001,0.001,0.001", "--tone", "0.9:3,0"]);
    assert!(e.contains("--tone 0.9:3,0"), "{e}");
    // Ranges are checked as the options are parsed, before the vibration file is read.
    let missing = dir.join("missing-vibration.csv");
    for (flag, value, said) in [
        ("--bn-hz", "-3", "'--bn-hz <BN_HZ>': -3 is not a finite number > 0"),
        ("--loop-interval-s", "0", "'--loop-interval-s <LOOP_INTERVAL_S>': 0 is not a finite number > 0"),
        ("--latency-s", "-0.01", "'--latency-s <LATENCY_S>'"),
    ] {
        let e = fails(&["predict", "--from", doc.to_str().unwrap(), "--psd", missing.to_str().unwrap(), flag, value]);
        assert!(e.contains(said) && !e.contains("missing-vibration.csv"), "{flag} {value}: {e}");
    }
}
