//! `gsens report` reads every input route `gsens estimate` reads (GNSS-SDR
//! dumps, rows from a GNSS-SDR run with its configuration, a PocketSDR log,
//! a RINEX observation file)
//! and writes the same result document: report.json is `estimate --json`
//! key for key, with the report's own block (`report`: when, by which tool,
//! the title and the figures) as its one key more.

mod common;

use common::{gsens, gsens_any, json, s, temp_dir};
use std::path::{Path, PathBuf};

fn fixtures(krate: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("../{krate}/tests/fixtures"))
}

/// Runs `estimate --json` and `report` on the same inputs and asserts that
/// their result documents agree key for key; returns report's standard output
/// and the ids of the figures it drew.
fn same_document(name: &str, inputs: &[&str]) -> (String, Vec<String>) {
    let d = temp_dir(&format!("report-route-{name}"));
    let est = d.join("estimate.json");
    let (est_text, est_trusted) = gsens_any(&[&["estimate", "--json", &s(&est)], inputs].concat());
    let out = d.join("report");
    let (text, trusted) = gsens_any(&[&["report", "--out", &s(&out)], inputs].concat());
    assert_eq!(trusted, est_trusted, "{name}: estimate and report disagree on the exit status");
    let e = json(&est);
    let mut r = json(&out.join("report.json"));
    let block = r.as_object_mut().unwrap().remove("report").expect("report.json has its report block");
    let figures: Vec<String> = block["figures"].as_array().unwrap().iter().map(|f| f["id"].to_string()).collect();
    assert!(!figures.is_empty(), "{name}: no figures");
    let (e, r) = (e.as_object().unwrap(), r.as_object().unwrap());
    assert_eq!(e.keys().collect::<Vec<_>>(), r.keys().collect::<Vec<_>>(), "{name}: the keys differ");
    for (k, x) in e {
        assert_eq!(x, &r[k], "{name}: estimate --json and report.json differ in `{k}`");
    }
    for k in ["gamma_hz_per_mps2", "sigma_hz_per_mps2", "covariance_hz_per_mps2_sq", "warnings", "loop_used", "inputs"]
    {
        assert!(e.contains_key(k), "{name}: no `{k}` to compare");
    }
    // Both print the route's loop note (and what became of each track).
    let note = est_text
        .lines()
        .find(|l| (l.contains("loop:") && l.contains("modelled exactly")) || l.starts_with("receiver loop identified"))
        .unwrap();
    assert!(text.contains(note), "{name}: report does not say `{note}`:\n{text}");
    assert!(out.join("report.html").exists() && out.join("figures").is_dir());
    (text, figures)
}

#[test]
fn report_from_gnss_sdr_dumps_is_the_estimate() {
    let f = fixtures("gsens-gnss-sdr");
    let (imu, dumps, conf) = (s(&f.join("imu.csv")), s(&f.join("order2")), s(&f.join("order2/gnss-sdr.conf")));
    let (text, _) = same_document("dumps", &["--imu", &imu, "--gnss-sdr", &dumps, "--gnss-sdr-conf", &conf]);
    assert!(text.contains("GNSS-SDR loop: GNSS-SDR"), "{text}");
}

#[test]
fn report_from_gnss_sdr_rows_is_the_estimate() {
    let f = fixtures("gsens-gnss-sdr");
    let d = temp_dir("report-route-rows-csv");
    let conf = s(&f.join("order2/gnss-sdr.conf"));
    let csv = s(&d.join("rows.csv"));
    gsens(&["import", "gnss-sdr", &s(&f.join("order2")), "--conf", &conf, "--out", &csv]);
    same_document("rows", &["--imu", &s(&f.join("imu.csv")), "--tracking", &csv, "--gnss-sdr-conf", &conf]);
}

#[test]
fn report_from_a_pocketsdr_log_is_the_estimate() {
    let f = fixtures("gsens-pocketsdr");
    let (imu, log, conf) = (s(&f.join("imu.csv")), s(&f.join("trk.log")), s(&f.join("opt.conf")));
    let (text, _) = same_document("pocketsdr", &["--imu", &imu, "--pocketsdr", &log, "--pocketsdr-conf", &conf]);
    assert!(text.contains("PocketSDR loop: PocketSDR"), "{text}");
}

/// GNSS-SDR's RINEX with the loop identified: the identified loop's
/// response and the carrier phase before and after compensation drawn.
#[test]
fn report_from_a_rinex_file_is_the_estimate() {
    let f = fixtures("gsens-rinex").join("gnss-sdr");
    let (imu, rinex) = (s(&f.join("imu.csv")), s(&f.join("gnss-sdr.24O")));
    let (_, figures) = same_document("rinex", &["--imu", &imu, "--rinex", &rinex]);
    assert_eq!(figures, ["\"fig3_response\"", "\"fig5_compensation\""]);
}
