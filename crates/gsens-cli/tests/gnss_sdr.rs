//! The GNSS-SDR commands on real GNSS-SDR 0.0.17 dumps (the fixtures of
//! `gsens-gnss-sdr`): `gsens import gnss-sdr`, `gsens estimate --gnss-sdr`,
//! errors on bad dumps, and `gsens simulate --iq`.

mod common;

use common::{fails, gsens, gsens_any, json, run, s};

use std::path::{Path, PathBuf};

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../gsens-gnss-sdr/tests/fixtures")
}

fn tmp(name: &str) -> common::TestDir {
    common::temp_dir(&format!("gnss-sdr-{name}"))
}

#[test]
fn import_writes_tracking_csv() {
    let f = fixtures();
    let d = tmp("import");
    let raw = d.join("raw.csv");
    let (dumps, conf) = (s(&f.join("order2")), s(&f.join("order2/gnss-sdr.conf")));
    let import = |out: &Path, extra: &[&str]| {
        gsens(&[&["import", "gnss-sdr", &dumps, "--conf", &conf, "--out", &s(out)], extra].concat())
    };
    let out = import(&raw, &["--record-times", "--tracks-json", &s(&d.join("tracks.json"))]);
    assert!(out.contains("2 tracks, 2 used"), "{out}");
    // Which layout (blocks and versions) each dump was read with.
    for ch in 0..2 {
        assert!(
            out.contains(&format!("trk_ch_{ch}.dat: read as gnss-sdr-0.0.17 (GNSS-SDR 0.0.17 to 0.0.20 dll_pll_veml")),
            "{out}"
        );
    }
    let text = std::fs::read_to_string(&raw).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad,carrier_lock_test"));
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert!(rows.len() > 2500, "{}", rows.len());
    assert!(rows.iter().all(|r| r[4].is_empty() && r[5].parse::<f64>().unwrap().abs() < 0.8));
    // At 55 dB-Hz and 3 m/s² the lock test stays high; no record is dropped for it alone.
    assert!(rows.iter().all(|r| r[6].parse::<f64>().unwrap() >= 0.85));
    // Times at the middle of each 20 ms integration: not on a common grid.
    let t: Vec<f64> = rows.iter().map(|r| r[0].parse().unwrap()).collect();
    assert!(t.iter().any(|v| ((v / 0.02).round() * 0.02 - v).abs() > 1e-4));
    let grid = d.join("grid.csv");
    import(&grid, &[]);
    let g = std::fs::read_to_string(&grid).unwrap();
    for line in g.lines().skip(1) {
        let v: f64 = line.split(',').next().unwrap().parse().unwrap();
        assert!(((v / 0.02).round() * 0.02 - v).abs() < 1e-9, "{v}");
    }
    let tracks: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("tracks.json")).unwrap()).unwrap();
    assert_eq!(tracks["tracks"].as_array().unwrap().len(), 2);
    assert!(tracks["tracks"][0]["layout"].as_str().unwrap().starts_with("gnss-sdr-0.0.17 (GNSS-SDR 0.0.17 to 0.0.20"));
}

#[test]
fn estimate_from_gnss_sdr_dumps_within_2_percent() {
    let f = fixtures();
    let truth: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(f.join("truth.json")).unwrap()).unwrap();
    let d = tmp("estimate");
    for order in ["order2", "order3"] {
        let json = d.join(format!("{order}.json"));
        let text = gsens(&[
            "estimate",
            "--imu",
            &s(&f.join("imu.csv")),
            "--gnss-sdr",
            &s(&f.join(order)),
            "--gnss-sdr-conf",
            &s(&f.join(order).join("gnss-sdr.conf")),
            "--json",
            &s(&json),
        ]);
        assert!(text.contains("modelled exactly"), "{text}");
        assert!(text.contains("trk_ch_0.dat: read as gnss-sdr-0.0.17 (GNSS-SDR 0.0.17 to 0.0.20"), "{text}");
        let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
        for i in 0..3 {
            let g = v["gamma_hz_per_mps2"][i].as_f64().unwrap();
            let t = truth["gamma_hz_per_mps2"][i].as_f64().unwrap();
            assert!(((g - t) / t).abs() < 0.02, "{order} axis {i}: {g} vs {t}");
        }
        // The loop the dumps were made with, modelled exactly, everywhere in the document.
        let l = &v["settings"]["receiver_loop"];
        assert_eq!(l["implementation"], "gnss_sdr");
        assert_eq!(l["order"], if order == "order2" { 2 } else { 3 });
        assert_eq!(l["symbols"], 20);
        assert_eq!(v["loop_used"], *l);
        assert!(v["loop"]["description"].as_str().unwrap().starts_with("GNSS-SDR"), "{}", v["loop"]);
        assert_eq!(v["source"]["receiver"], "gnss-sdr");
        assert!(v["source"]["tracks"].as_array().unwrap().iter().all(|t| t["used"] == true));
        // The result document names each dump's layout.
        let layouts = v["source"]["tracks"].as_array().unwrap().iter().map(|t| t["layout"].as_str().unwrap());
        assert!(layouts.clone().count() > 0 && layouts.clone().all(|l| l.starts_with("gnss-sdr-0.0.17 (GNSS-SDR")));
    }
}

/// GNSS-SDR's default tracking setting, `extend_correlation_symbols=1` (1 ms
/// updates, one record per 20 ms data bit after bit synchronization), with the
/// default options: one track per channel, the estimate trustworthy (exit 0).
#[test]
fn estimate_from_dumps_of_the_default_1_ms_setting() {
    let f = fixtures().join("ext1");
    let d = tmp("ext1");
    let out = d.join("ext1.json");
    let (imu, conf) = (s(&f.join("imu.csv")), s(&f.join("gnss-sdr.conf")));
    let text = gsens(&["estimate", "--imu", &imu, "--gnss-sdr", &s(&f), "--gnss-sdr-conf", &conf, "--json", &s(&out)]);
    assert!(text.contains("2 tracks, 2 used"), "{text}");
    let v = json(&out);
    assert_eq!((v["trustworthy"].as_bool(), v["model_substeps"].as_u64()), (Some(true), Some(20)), "{text}");
    assert_eq!(v["settings"]["receiver_loop"]["symbols"], 1);
}

/// `gsens estimate --gnss-sdr` on the dumps of a board shaken from 3 s on (the
/// lock test down to 0.75 while shaking, the channels switching to the narrow
/// loop mid-shake), with the default options: every track passes GNSS-SDR's own
/// lock rule and Γ̂ is within 2 % on every shaken axis, for both loop orders.
#[test]
fn estimate_from_shaken_dumps_with_low_lock_tests() {
    let f = fixtures().join("shaken");
    let truth: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(f.join("truth.json")).unwrap()).unwrap();
    let d = tmp("shaken");
    for order in ["order2", "order3"] {
        let json = d.join(format!("{order}.json"));
        let dumps = s(&f.join(order));
        let conf = s(&f.join(order).join("gnss-sdr.conf"));
        let imu = s(&f.join("imu.csv"));
        let text =
            gsens(&["estimate", "--imu", &imu, "--gnss-sdr", &dumps, "--gnss-sdr-conf", &conf, "--json", &s(&json)]);
        assert!(text.contains("carrier_lock_th = 0.7 (GNSS-SDR's default)"), "{text}");
        let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
        for i in 0..3 {
            let g = v["gamma_hz_per_mps2"][i].as_f64().unwrap();
            let t = truth["gamma_hz_per_mps2"][i].as_f64().unwrap();
            assert!(((g - t) / t).abs() < 0.02, "{order} axis {i}: {g} vs {t}");
        }
        let tracks = v["source"]["tracks"].as_array().unwrap();
        assert!(tracks.iter().all(|t| t["used"] == true && t["lock"]["loss_of_lock"].is_null()), "{tracks:?}");
        // The lock detector in use is in the document, each value with its source.
        let lock = &v["source"]["conversion"]["tracking"]["lock"];
        assert_eq!(lock["carrier_lock_th"]["value"], 0.7);
        assert_eq!(lock["carrier_lock_th"]["source"], "gnss_sdr_default");
        assert_eq!(lock["max_lock_fail"]["value"], 50);
        // The session starts mid-shake: the warm-up covers the regressor models' start-up
        // error (computed from the IMU through the loop, at most 7.6 s and 15.2 s).
        let w = v["settings"]["warmup_s"].as_f64().unwrap();
        let (lo, hi) = if order == "order2" { (4.0, 7.6) } else { (6.0, 15.2) };
        assert!(w > lo && w <= hi, "{order}: warm-up {w} s");
        // Options override the configuration and are named in the reason.
        if order == "order2" {
            let out = gsens(&[
                "import",
                "gnss-sdr",
                &dumps,
                "--conf",
                &conf,
                "--out",
                &s(&d.join("strict.csv")),
                "--gnss-sdr-min-lock-test",
                "0.85",
                "--gnss-sdr-max-carrier-lock-fail",
                "100",
            ]);
            assert!(
                out.contains("loss of lock") && out.contains("max_carrier_lock_fail = 100 (given as an option)"),
                "{out}"
            );
            assert!(out.contains("carrier_lock_th = 0.85 (given as an option)"), "{out}");
        }
    }
    let e = fails(&[
        "import",
        "gnss-sdr",
        &s(&f.join("order2")),
        "--conf",
        &s(&f.join("order2/gnss-sdr.conf")),
        "--out",
        &s(&d.join("x.csv")),
        "--gnss-sdr-min-lock-test",
        "1.5",
    ]);
    assert!(e.contains("--gnss-sdr-min-lock-test must be in [-1, 1]"), "{e}");
}

#[test]
fn bad_dumps_are_refused_naming_the_file() {
    let f = fixtures();
    let d = tmp("bad");
    let bytes = std::fs::read(f.join("order2/trk_ch_0.dat")).unwrap();
    std::fs::write(d.join("trk_ch_0.dat"), &bytes[..bytes.len() - 10]).unwrap();
    let out = run(&[
        "import",
        "gnss-sdr",
        &s(&d),
        "--conf",
        &s(&f.join("order2/gnss-sdr.conf")),
        "--out",
        &s(&d.join("x.csv")),
    ]);
    assert_eq!(out.status.code(), Some(2));
    let e = String::from_utf8_lossy(&out.stderr);
    assert!(
        e.contains("trk_ch_0.dat: truncated tracking dump") && e.contains("1683 whole records of gnss-sdr-0.0.17"),
        "{e}"
    );
    std::fs::write(d.join("trk_ch_0.dat"), b"").unwrap();
    let conf = s(&f.join("order2/gnss-sdr.conf"));
    let import = |dir: &Path| fails(&["import", "gnss-sdr", &s(dir), "--conf", &conf, "--out", &s(&d.join("x.csv"))]);
    assert!(import(&d).contains("empty tracking dump"));
    assert!(import(&tmp("empty")).contains("no tracking dump"));
    // --gnss-sdr needs its configuration.
    let out = run(&["estimate", "--imu", &s(&f.join("imu.csv")), "--gnss-sdr", &s(&f.join("order2"))]);
    assert!(!out.status.success() && String::from_utf8_lossy(&out.stderr).contains("--gnss-sdr-conf"));
}

#[test]
fn simulate_iq_writes_samples_conf_and_truth() {
    let d = tmp("iq");
    let sc = d.join("sc.toml");
    std::fs::write(&sc, "[session]\nduration_s = 0.5\n[satellites]\nmax_channels = 3\n").unwrap();
    let iq = d.join("x.bin");
    let out = gsens(&[
        "simulate",
        "--scenario",
        &s(&sc),
        "--out",
        &s(&d),
        "--iq",
        &s(&iq),
        "--iq-format",
        "ishort",
        "--fs-hz",
        "2048000",
        "--iq-carrier-truth",
    ]);
    assert!(out.contains("real time"), "{out}");
    assert_eq!(std::fs::metadata(&iq).unwrap().len(), 1_024_000 * 4);
    let conf = std::fs::read_to_string(d.join("gnss-sdr.conf")).unwrap();
    assert!(conf.contains("SignalSource.item_type=ishort") && conf.contains("Channels_1C.count=3"), "{conf}");
    assert!(conf.contains("Tracking_1C.pll_bw_narrow_hz=3") && conf.contains("extend_correlation_symbols=20"));
    let truth: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("truth.json")).unwrap()).unwrap();
    assert_eq!(truth["satellites"].as_array().unwrap().len(), 3);
    assert_eq!(truth["samples"], 1_024_000);
    let carrier = std::fs::read_to_string(d.join("carrier.csv")).unwrap();
    assert!(carrier.starts_with("t_s,prn") && carrier.lines().count() == 501);
    assert_eq!(std::fs::read_to_string(d.join("delta_f.csv")).unwrap().lines().count(), 501);
}

/// A directory holding only a `.mat` dump is read (exit code 2 here: 1.2 s
/// never reaches the 20 ms loop, and the message says so for the `.mat`).
#[test]
fn a_directory_of_mat_dumps_is_read() {
    let f = fixtures();
    let d = tmp("mat");
    std::fs::copy(f.join("mat/trk_ch_0.mat"), d.join("trk_ch_0.mat")).unwrap();
    let out =
        run(&["import", "gnss-sdr", &s(&d), "--conf", &s(&f.join("mat/gnss-sdr.conf")), "--out", &s(&d.join("x.csv"))]);
    assert_eq!(out.status.code(), Some(2));
    let e = String::from_utf8_lossy(&out.stderr);
    let records = std::fs::metadata(f.join("mat/trk_ch_0.dat")).unwrap().len() / 96;
    assert!(e.contains("never reached the modelled loop") && e.contains(&format!("in its {records} records")), "{e}");
}

/// Rows that came from a GNSS-SDR run another way than the estimate's own
/// reading of its dumps (here `gsens import gnss-sdr`; live, its tracking
/// monitor): `--tracking … --gnss-sdr-conf` models the run's loop exactly,
/// within 2 % of the truth; a Kaplan loop stated beside it is refused.
#[test]
fn tracking_rows_with_the_gnss_sdr_loop_of_a_conf() {
    let f = fixtures();
    let truth = json(&f.join("truth.json"));
    let d = tmp("tracking-conf");
    for order in ["order2", "order3"] {
        let conf = f.join(order).join("gnss-sdr.conf");
        let csv = d.join(format!("{order}.csv"));
        gsens(&["import", "gnss-sdr", &s(&f.join(order)), "--conf", &s(&conf), "--out", &s(&csv)]);
        let out = d.join(format!("{order}.json"));
        let imu = f.join("imu.csv");
        let (text, _) = gsens_any(&[
            "estimate",
            "--imu",
            &s(&imu),
            "--tracking",
            &s(&csv),
            "--gnss-sdr-conf",
            &s(&conf),
            "--json",
            &s(&out),
        ]);
        assert!(text.contains("GNSS-SDR loop: GNSS-SDR") && text.contains("modelled exactly"), "{text}");
        let v = json(&out);
        assert_eq!(v["loop_used"]["implementation"], "gnss_sdr");
        for i in 0..3 {
            let g = v["gamma_hz_per_mps2"][i].as_f64().unwrap();
            let t = truth["gamma_hz_per_mps2"][i].as_f64().unwrap();
            assert!(((g - t) / t).abs() < 0.02, "{order} axis {i}: {g} vs {t}");
        }
        let refused =
            run(&["estimate", "--imu", &s(&imu), "--tracking", &s(&csv), "--gnss-sdr-conf", &s(&conf), "--bn-hz", "3"]);
        assert_eq!(refused.status.code(), Some(2));
        assert!(String::from_utf8_lossy(&refused.stderr).contains("--gnss-sdr-conf states the receiver loop"));
    }
}
