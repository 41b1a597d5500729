//! The PocketSDR routes on a real pocket_trk 0.17 log (the fixture of
//! `gsens-pocketsdr`), with the default options every front end starts
//! from: the log imported as `tracking.csv` and estimated with PocketSDR's
//! loop stated, the log with its loop modelled exactly, and errors on bad
//! logs and options files.

mod common;

use common::{defaults, document, json_file};
use gsens_calib::CalibrationOptions;
use gsens_core::LoggedPhase;
use gsens_inputs::{Inputs, Log};
use gsens_pocketsdr::ImportSettings;
use std::path::{Path, PathBuf};

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../gsens-pocketsdr/tests/fixtures")
}

/// The log `log` with the options file `conf`.
fn route(log: &Path, conf: &Path) -> Inputs {
    let import = ImportSettings::from_options_file(Some(conf)).unwrap();
    Inputs::PocketSdr { imu: fixtures().join("imu.csv"), log: log.to_path_buf(), import }
}

#[test]
fn import_writes_tracking_csv_on_the_logs_epochs() {
    let f = fixtures();
    let settings = ImportSettings::from_options_file(Some(&f.join("opt.conf"))).unwrap();
    let imported = gsens_pocketsdr::import_file(&f.join("trk.log"), &settings).unwrap();
    let text = gsens_pocketsdr::render_summary(&imported);
    assert!(
        text.contains("3 GPS L1 C/A tracks, 3 used") && text.contains("b_pll 5 Hz (PocketSDR's default)"),
        "{text}"
    );
    let mut out = Vec::new();
    gsens_io::write_tracking_csv(&mut out, &imported.rows).unwrap();
    let csv = String::from_utf8(out).unwrap();
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
    assert_eq!(imported.tracks.len(), 3);
    assert_eq!(imported.epoch.value, 0.1);
    // The imported file estimates like the log, once the loop is stated as PocketSDR's
    // equivalent (Kaplan's 3rd-order filter at 5 Hz, the last 1 ms output logged).
    let options = {
        let mut o = CalibrationOptions::default();
        o.receiver_loop.order = Some(3);
        o.receiver_loop.bn_hz = Some(5.0);
        o.receiver_loop.loop_interval_s = Some(0.001);
        o.receiver_loop.logged_phase = Some(LoggedPhase::Last);
        o
    };
    let tracking = gsens_io::read_tracking(csv.as_bytes(), "tracking.csv").unwrap();
    let inputs = || Inputs::Csv {
        imu: Log::File(f.join("imu.csv")),
        tracking: Log::Memory { name: "tracking.csv".into(), log: tracking.clone() },
    };
    let c = inputs().calibrate(&options.pipeline_settings().unwrap()).unwrap();
    let v = document(&c);
    assert_eq!(v["epochs_total"], 332);
    // Stated in words, the loop has three forms: gsens's and PocketSDR's fit alike, GNSS-SDR's
    // ("Bn 5 Hz" is ωn/2π 0.64 Hz there, 1.01 Hz in the others) fits only at about twice the
    // stated bandwidth, which the statement's test rejects: it is left out, and σ is what naming
    // the form gives (measured 5.6–6.5 % of Γ against 5.5–6.5 %; with GNSS-SDR's form weighed
    // in by its Δ of 6.2, 20–22 %). Γ̂ within 3σ of the truth, trustworthy.
    let forms = v["joint_fit"]["loop_forms"]["forms"].as_array().unwrap();
    let consistent: Vec<bool> = forms.iter().map(|f| f["consistent_with_statement"].as_bool().unwrap()).collect();
    assert_eq!(consistent, [true, false, true], "{forms:?}");
    assert_eq!(v["trustworthy"], true, "{}", v["warnings"]);
    let named = {
        let mut o = options.clone();
        o.receiver_loop.loop_implementation = Some(gsens_core::LoopImplementation::PocketSdr);
        document(&inputs().calibrate(&o.pipeline_settings().unwrap()).unwrap())
    };
    let truth = json_file(&f.join("truth.json"));
    for i in 0..3 {
        let (g, sd) = (v["gamma_hz_per_mps2"][i].as_f64().unwrap(), v["sigma_hz_per_mps2"][i].as_f64().unwrap());
        let t = truth["gamma_imu_axes_hz_per_mps2"][i].as_f64().unwrap();
        assert!((g - t).abs() < 3.0 * sd, "axis {i}: {g} ± {sd} vs {t}");
        let sd_named = named["sigma_hz_per_mps2"][i].as_f64().unwrap();
        assert!(sd < 1.1 * sd_named, "axis {i}: σ {sd} in words, {sd_named} named");
    }
}

#[test]
fn estimate_from_the_pocketsdr_log_within_its_uncertainty() {
    let f = fixtures();
    let c = route(&f.join("trk.log"), &f.join("opt.conf")).calibrate(&defaults()).unwrap();
    let text = c.loop_note().unwrap();
    assert!(text.contains("PocketSDR loop: PocketSDR pocket_trk PLL") && text.contains("modelled exactly"), "{text}");
    let v = document(&c);
    let truth = json_file(&f.join("truth.json"));
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
    assert_eq!(v["inputs"]["pocketsdr_log"], f.join("trk.log").display().to_string());
    assert_eq!(v["trustworthy"], true);
    // What the conversion did, in the document's per-receiver block.
    assert_eq!(v["source"]["receiver"], "pocketsdr");
    assert_eq!(v["source"]["tracks"].as_array().unwrap().len(), 3);
    assert_eq!(v["source"]["conversion"]["epoch"]["value"], 0.1);
}

#[test]
fn bad_logs_and_options_are_errors_naming_file_line_and_field() {
    let f = fixtures();
    let d = tempfile::Builder::new().prefix("gsens-inputs-pocketsdr-bad-").tempdir().unwrap();
    let empty = d.path().join("empty.log");
    std::fs::write(&empty, "").unwrap();
    let e = route(&empty, &f.join("opt.conf")).calibrate(&defaults()).unwrap_err().to_string();
    assert!(e.contains(&format!("{}: empty log", empty.display())), "{e}");
    let bad_opt = d.path().join("opt.conf");
    std::fs::write(&bad_opt, "epoch = 0.1\nb_pll = ten\n").unwrap();
    let e = ImportSettings::from_options_file(Some(&bad_opt)).unwrap_err().to_string();
    assert!(e.contains(&format!("{}: line 2: b_pll: \"ten\" is not a positive number", bad_opt.display())), "{e}");
    // A stated b_pll the log was not made with: the data reject it.
    let wrong = d.path().join("wrong.conf");
    std::fs::write(&wrong, "epoch = 0.1\nb_pll = 15\n").unwrap();
    let c = route(&f.join("trk.log"), &wrong).calibrate(&defaults()).unwrap();
    let v = document(&c);
    assert_eq!(v["trustworthy"], false);
    assert_eq!(v["joint_fit"]["stated_loop_rejected"], true, "{}", v["joint_fit"]);
}
