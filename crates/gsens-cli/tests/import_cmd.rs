//! `gsens import gnss-sdr` as a new user meets it: a wrong dump directory is
//! named before anything about the configuration, and what it writes by
//! default (no `--out`) is a `tracking.csv` on the common grid, with a hint
//! that is a whole command. On the real GNSS-SDR 0.0.17 dumps of
//! `gsens-gnss-sdr`'s fixtures (that `gsens estimate --tracking` reads the
//! rows on the grid: `gsens-inputs`' tests).

mod common;

use common::{fails, s, temp_dir};

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
fn the_default_output_is_tracking_csv_on_the_grid() {
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
