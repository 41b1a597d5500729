//! The PocketSDR commands on a real pocket_trk 0.17 log (the fixture of
//! `gsens-pocketsdr`): `gsens import pocketsdr`, `gsens estimate --pocketsdr`,
//! and errors on bad logs and options.

mod common;

use common::{fails, gsens, json, s, temp_dir};

use std::path::{Path, PathBuf};

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../gsens-pocketsdr/tests/fixtures")
}

#[test]
fn import_writes_tracking_csv_on_the_logs_epochs() {
    let f = fixtures();
    let d = temp_dir("pocketsdr-import");
    let out = d.join("tracking.csv");
    let (log, conf) = (s(&f.join("trk.log")), s(&f.join("opt.conf")));
    let text = gsens(&[
        "import",
        "pocketsdr",
        &log,
        "--pocketsdr-conf",
        &conf,
        "--out",
        &s(&out),
        "--tracks-json",
        &s(&d.join("tracks.json")),
    ]);
    assert!(
        text.contains("3 GPS L1 C/A tracks, 3 used") && text.contains("b_pll 5 Hz (PocketSDR's default)"),
        "{text}"
    );
    let csv = std::fs::read_to_string(&out).unwrap();
    let mut lines = csv.lines();
    assert_eq!(lines.next(), Some("t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad"));
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert!(rows.len() > 900, "{}", rows.len());
    for r in &rows {
        // The middle of the logged 1 ms block, the log's 0.1 s epochs; φ within a Costas ±π/2.
        let t: f64 = r[0].parse().unwrap();
        assert!(((t - 5e-4) / 0.1 - ((t - 5e-4) / 0.1).round()).abs() < 1e-6, "{t}");
        assert!(r[4].is_empty() && r[5].parse::<f64>().unwrap().abs() <= std::f64::consts::FRAC_PI_2 + 1e-2);
    }
    let tracks = json(&d.join("tracks.json"));
    assert_eq!(tracks["tracks"].as_array().unwrap().len(), 3);
    assert_eq!(tracks["epoch"]["value"], 0.1);
    // The imported file estimates like the log, once the loop is stated as PocketSDR's
    // equivalent (Kaplan's 3rd-order filter at 5 Hz, the last 1 ms output logged).
    let est = d.join("est.json");
    let (_, _) = common::gsens_any(&[
        "estimate",
        "--imu",
        &s(&f.join("imu.csv")),
        "--tracking",
        &s(&out),
        "--order",
        "3",
        "--bn-hz",
        "5",
        "--loop-interval-s",
        "0.001",
        "--logged-phase",
        "last",
        "--json",
        &s(&est),
    ]);
    assert_eq!(json(&est)["epochs_total"], 332);
}

#[test]
fn estimate_from_the_pocketsdr_log_within_its_uncertainty() {
    let f = fixtures();
    let d = temp_dir("pocketsdr-estimate");
    let out = d.join("est.json");
    let text = gsens(&[
        "estimate",
        "--imu",
        &s(&f.join("imu.csv")),
        "--pocketsdr",
        &s(&f.join("trk.log")),
        "--pocketsdr-conf",
        &s(&f.join("opt.conf")),
        "--json",
        &s(&out),
    ]);
    assert!(text.contains("PocketSDR loop: PocketSDR pocket_trk PLL") && text.contains("modelled exactly"), "{text}");
    let v = json(&out);
    let truth = json(&f.join("truth.json"));
    for i in 0..3 {
        let g = v["gamma_hz_per_mps2"][i].as_f64().unwrap();
        let sd = v["sigma_hz_per_mps2"][i].as_f64().unwrap();
        let t = truth["gamma_imu_axes_hz_per_mps2"][i].as_f64().unwrap();
        assert!((g - t).abs() < 3.0 * sd, "axis {i}: {g} ± {sd} vs {t}");
    }
    // PocketSDR's loop, exactly, everywhere in the document; tested, not fitted.
    let l = &v["settings"]["receiver_loop"];
    assert_eq!(
        (l["implementation"].as_str(), l["bw_hz"].as_f64(), l["interval_s"].as_f64()),
        (Some("pocket_sdr"), Some(5.0), Some(0.001))
    );
    assert_eq!(v["loop_used"], *l);
    assert_eq!(v["settings"]["logged_phase"], "last");
    assert_eq!(v["joint_fit"]["fitted_loop_used"], false);
    assert_eq!(v["loop_response"]["consistent"], true);
    assert_eq!(v["inputs"]["pocketsdr_log"], s(&f.join("trk.log")));
    assert_eq!(v["trustworthy"], true);
    // What the conversion did, in the document's per-receiver block.
    assert_eq!(v["source"]["receiver"], "pocketsdr");
    assert_eq!(v["source"]["tracks"].as_array().unwrap().len(), 3);
    assert_eq!(v["source"]["conversion"]["epoch"]["value"], 0.1);
}

#[test]
fn bad_logs_and_options_are_errors_naming_file_line_and_field() {
    let f = fixtures();
    let d = temp_dir("pocketsdr-bad");
    let imu = s(&f.join("imu.csv"));
    let empty = d.join("empty.log");
    std::fs::write(&empty, "").unwrap();
    let e = fails(&["estimate", "--imu", &imu, "--pocketsdr", &s(&empty)]);
    assert!(e.contains(&format!("{}: empty log", empty.display())), "{e}");
    let bad_opt = d.join("opt.conf");
    std::fs::write(&bad_opt, "epoch = 0.1\nb_pll = ten\n").unwrap();
    let e = fails(&[
        "import",
        "pocketsdr",
        &s(&f.join("trk.log")),
        "--pocketsdr-conf",
        &s(&bad_opt),
        "--out",
        &s(&d.join("t.csv")),
    ]);
    assert!(e.contains(&format!("{}: line 2: b_pll: \"ten\" is not a positive number", bad_opt.display())), "{e}");
    // A stated b_pll the log was not made with: the data reject it.
    let wrong = d.join("wrong.conf");
    std::fs::write(&wrong, "epoch = 0.1\nb_pll = 15\n").unwrap();
    let out = common::run(&[
        "estimate",
        "--imu",
        &imu,
        "--pocketsdr",
        &s(&f.join("trk.log")),
        "--pocketsdr-conf",
        &s(&wrong),
        "--json",
        &s(&d.join("w.json")),
    ]);
    assert_eq!(out.status.code(), Some(3), "{}", String::from_utf8_lossy(&out.stderr));
    let v = json(&d.join("w.json"));
    assert_eq!(v["joint_fit"]["stated_loop_rejected"], true, "{}", v["joint_fit"]);
    let e = fails(&["estimate", "--imu", &imu, "--tracking", &imu, "--pocketsdr-conf", &s(&wrong)]);
    assert!(e.contains("need --pocketsdr LOG"), "{e}");
}
