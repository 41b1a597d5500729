//! The PocketSDR commands on a real pocket_trk 0.17 log (the fixture of
//! `gsens-pocketsdr`): `gsens import pocketsdr` and `gsens estimate
//! --pocketsdr` write their files, and a PocketSDR option without its log is
//! refused naming the flag. What the log converts to and estimates is tested
//! where it is made: `gsens-pocketsdr`'s and `gsens-inputs`' tests.

mod common;

use common::{fails, gsens, json, s, temp_dir};

use std::path::{Path, PathBuf};

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../gsens-pocketsdr/tests/fixtures")
}

#[test]
fn import_and_estimate_write_their_files() {
    let f = fixtures();
    let d = temp_dir("pocketsdr");
    let (log, conf, imu) = (s(&f.join("trk.log")), s(&f.join("opt.conf")), s(&f.join("imu.csv")));
    let (csv, tracks) = (d.join("tracking.csv"), d.join("tracks.json"));
    let text = gsens(&[
        "import",
        "pocketsdr",
        &log,
        "--pocketsdr-conf",
        &conf,
        "--out",
        &s(&csv),
        "--tracks-json",
        &s(&tracks),
    ]);
    assert!(text.contains("3 GPS L1 C/A tracks, 3 used"), "{text}");
    assert!(std::fs::read_to_string(&csv).unwrap().starts_with("t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad\n"));
    assert_eq!(json(&tracks)["tracks"].as_array().unwrap().len(), 3);
    let out = d.join("est.json");
    let text = gsens(&["estimate", "--imu", &imu, "--pocketsdr", &log, "--pocketsdr-conf", &conf, "--json", &s(&out)]);
    assert!(text.contains("PocketSDR loop: PocketSDR pocket_trk PLL") && text.contains("modelled exactly"), "{text}");
    assert_eq!(json(&out)["source"]["receiver"], "pocketsdr");
}

#[test]
fn a_pocketsdr_option_without_its_log_is_refused() {
    let f = fixtures();
    let imu = s(&f.join("imu.csv"));
    let e = fails(&["estimate", "--imu", &imu, "--tracking", &imu, "--pocketsdr-conf", &s(&f.join("opt.conf"))]);
    assert!(e.contains("need --pocketsdr LOG"), "{e}");
}
