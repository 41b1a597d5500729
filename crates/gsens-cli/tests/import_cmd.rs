//! `gsens import gnss-sdr` as a new user meets it: a wrong dump directory is
//! named before anything about the configuration, and what it writes by
//! default (no `--out`) is a `tracking.csv` that
//! `gsens estimate --tracking` reads. On the real GNSS-SDR 0.0.17 dumps of
//! `gsens-gnss-sdr`'s fixtures.

mod common;

use common::{fails, json, s, temp_dir, vec3};

use std::path::{Path, PathBuf};
use std::process::Command;

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../gsens-gnss-sdr/tests/fixtures")
}

#[test]
fn a_missing_dump_directory_is_reported_before_the_configuration() {
    let d = temp_dir("import-order");
    let (dir, conf) = (d.join("no-such-dir"), d.join("no-such.conf"));
    let e = fails(&["import", "gnss-sdr", &s(&dir), "--conf", &s(&conf), "--out", &s(&d.join("x.csv"))]);
    assert!(e.contains(&s(&dir)) && !e.contains("no-such.conf"), "{e}");
    // A directory without dumps: the same, before the (missing) configuration.
    let e = fails(&["import", "gnss-sdr", &s(&d), "--conf", &s(&conf), "--out", &s(&d.join("x.csv"))]);
    assert!(e.contains("no tracking dump") && !e.contains("no-such.conf"), "{e}");
    // With the dumps there, the configuration is the next thing read.
    let e = fails(&["import", "gnss-sdr", &s(&fixtures().join("order2")), "--conf", &s(&conf)]);
    assert!(e.contains("no-such.conf"), "{e}");
}

#[test]
fn the_default_output_is_what_estimate_tracking_reads() {
    let f = fixtures();
    let d = temp_dir("import-default");
    let (dumps, conf) = (f.join("order2"), f.join("order2/gnss-sdr.conf"));
    // No output option at all, run in a scratch folder: tracking.csv there.
    let out = Command::new(env!("CARGO_BIN_EXE_gsens"))
        .current_dir(&d)
        .args(["import", "gnss-sdr", &s(&dumps), "--conf", &s(&conf)])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("tracking.csv (common grid, for gsens estimate --tracking)"), "{text}");
    let tracking = d.join("tracking.csv");
    // Every row on the grid t = j·20 ms.
    let csv = std::fs::read_to_string(&tracking).unwrap();
    assert!(csv.lines().count() > 2500);
    for line in csv.lines().skip(1) {
        let t: f64 = line.split(',').next().unwrap().parse().unwrap();
        assert!(((t / 0.02).round() * 0.02 - t).abs() < 1e-9, "{t}");
    }
    // estimate --tracking takes it. The dumps' loop is GNSS-SDR's 3 Hz
    // order-2 loop over 20 ms records, which the Kaplan model of the options
    // approximates: Γ̂ within 10 % of the truth (the exact model,
    // --gnss-sdr, is within 2 %: tests/gnss_sdr.rs).
    let est = d.join("est.json");
    let imu = f.join("imu.csv");
    let out = common::gsens(&[
        "estimate",
        "--imu",
        &s(&imu),
        "--tracking",
        &s(&tracking),
        "--loop-interval-s",
        "0.02",
        "--json",
        &s(&est),
    ]);
    assert!(out.contains("channels: 2 used"), "{out}");
    let (g, truth) = (vec3(&json(&est)["gamma_hz_per_mps2"]), vec3(&json(&f.join("truth.json"))["gamma_hz_per_mps2"]));
    for i in 0..3 {
        assert!(((g[i] - truth[i]) / truth[i]).abs() < 0.10, "axis {i}: {} vs {}", g[i], truth[i]);
    }
    // --record-times still writes the records at their own times, not for estimate.
    let raw = d.join("raw.csv");
    let out =
        common::gsens(&["import", "gnss-sdr", &s(&dumps), "--conf", &s(&conf), "--record-times", "--out", &s(&raw)]);
    assert!(out.contains("not for gsens estimate --tracking"), "{out}");
    // The hint is a whole command: the IMU log too, and the configuration given.
    let hint = format!("gsens estimate --imu <imu.csv> --gnss-sdr {} --gnss-sdr-conf {}", s(&dumps), s(&conf));
    assert!(out.contains(&hint), "{out}");
    // The help names every source.
    let help = common::gsens(&["import", "--help"]);
    for source in ["gnss-sdr", "pocketsdr", "gnss-sdr-monitor"] {
        assert!(help.contains(source), "{help}");
    }
    let help = common::gsens(&["--help"]);
    assert!(help.contains("PocketSDR") && help.contains("tracking monitor"), "{help}");
    assert!(
        std::fs::read_to_string(&raw)
            .unwrap()
            .starts_with("t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad,carrier_lock_test")
    );
}
