//! The GNSS-SDR commands on real GNSS-SDR 0.0.17 dumps (the fixtures of
//! `gsens-gnss-sdr`): `gsens import gnss-sdr` writes its files, the GNSS-SDR
//! options are checked as flags, and `gsens simulate --iq` writes its
//! files. What the dumps convert to and estimate is tested where it is
//! made: `gsens-gnss-sdr`'s and `gsens-inputs`' tests.

mod common;

use common::{fails, gsens, json, run, s};

use std::path::{Path, PathBuf};

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../gsens-gnss-sdr/tests/fixtures")
}

fn tmp(name: &str) -> common::TestDir {
    common::temp_dir(&format!("gnss-sdr-{name}"))
}

#[test]
fn import_writes_tracking_csv_and_the_tracks() {
    let f = fixtures();
    let d = tmp("import");
    let (out, tracks) = (d.join("raw.csv"), d.join("tracks.json"));
    let (dumps, conf) = (s(&f.join("order2")), s(&f.join("order2/gnss-sdr.conf")));
    let text = gsens(&["import", "gnss-sdr", &dumps, "--conf", &conf, "--out", &s(&out), "--tracks-json", &s(&tracks)]);
    assert!(text.contains("2 tracks, 2 used"), "{text}");
    assert!(std::fs::read_to_string(&out).unwrap().lines().count() > 2500);
    assert_eq!(json(&tracks)["tracks"].as_array().unwrap().len(), 2);
}

/// The GNSS-SDR flags are checked, each error naming its flag: a lock-test
/// threshold outside [-1, 1], `--gnss-sdr` without its configuration, and a
/// loop stated beside the configuration's.
#[test]
fn gnss_sdr_flags_are_checked_naming_the_flag() {
    let f = fixtures();
    let d = tmp("flags");
    let (dumps, conf) = (s(&f.join("order2")), s(&f.join("order2/gnss-sdr.conf")));
    let e = fails(&[
        "import",
        "gnss-sdr",
        &dumps,
        "--conf",
        &conf,
        "--out",
        &s(&d.join("x.csv")),
        "--gnss-sdr-min-lock-test",
        "1.5",
    ]);
    assert!(e.contains("--gnss-sdr-min-lock-test must be in [-1, 1]"), "{e}");
    let imu = s(&f.join("imu.csv"));
    let out = run(&["estimate", "--imu", &imu, "--gnss-sdr", &dumps]);
    assert!(!out.status.success() && String::from_utf8_lossy(&out.stderr).contains("--gnss-sdr-conf"));
    let csv = d.join("rows.csv");
    gsens(&["import", "gnss-sdr", &dumps, "--conf", &conf, "--out", &s(&csv)]);
    let refused = run(&["estimate", "--imu", &imu, "--tracking", &s(&csv), "--gnss-sdr-conf", &conf, "--bn-hz", "3"]);
    assert_eq!(refused.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&refused.stderr).contains("--gnss-sdr-conf states the receiver loop"));
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
