//! A directory of real GNSS-SDR 0.0.17 dumps imported as gsens's
//! `tracking.csv` (what `gsens import gnss-sdr` writes): at each record's
//! own time with its lock test, or on the common grid; and the errors of
//! damaged, empty or missing dumps, and of `.mat` dumps too short for the
//! modelled loop.

use gsens_gnss_sdr::{ImportSettings, Imported, import_dir, render_tracks};
use std::path::{Path, PathBuf};

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures")
}

fn settings(conf: &Path) -> ImportSettings {
    ImportSettings::from_conf(Some(conf), None).unwrap()
}

/// The CSV `imported` writes (on the common grid, or at the records' times).
fn csv(imported: &Imported, on_common_grid: bool) -> String {
    let mut out = Vec::new();
    imported.write_csv(&mut out, on_common_grid).unwrap();
    String::from_utf8(out).unwrap()
}

#[test]
fn import_writes_tracking_csv() {
    let f = fixtures();
    let imported = import_dir(&f.join("order2"), &settings(&f.join("order2/gnss-sdr.conf"))).unwrap();
    let out = render_tracks(&imported.tracks, imported.interval_s);
    assert!(out.contains("2 tracks, 2 used"), "{out}");
    // Which layout (blocks and versions) each dump was read with.
    for ch in 0..2 {
        assert!(
            out.contains(&format!("trk_ch_{ch}.dat: read as gnss-sdr-0.0.17 (GNSS-SDR 0.0.17 to 0.0.20 dll_pll_veml")),
            "{out}"
        );
    }
    let text = csv(&imported, false);
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
    let g = csv(&imported, true);
    assert!(g.lines().count() > 2500);
    for line in g.lines().skip(1) {
        let v: f64 = line.split(',').next().unwrap().parse().unwrap();
        assert!(((v / 0.02).round() * 0.02 - v).abs() < 1e-9, "{v}");
    }
    assert_eq!(imported.tracks.len(), 2);
    assert!(imported.tracks[0].layout.starts_with("gnss-sdr-0.0.17 (GNSS-SDR 0.0.17 to 0.0.20"));
}

#[test]
fn bad_dumps_are_refused_naming_the_file() {
    let f = fixtures();
    let d = tempfile::Builder::new().prefix("gsens-gnss-sdr-bad-").tempdir().unwrap();
    let s = settings(&f.join("order2/gnss-sdr.conf"));
    let bytes = std::fs::read(f.join("order2/trk_ch_0.dat")).unwrap();
    std::fs::write(d.path().join("trk_ch_0.dat"), &bytes[..bytes.len() - 10]).unwrap();
    let e = import_dir(d.path(), &s).unwrap_err().to_string();
    assert!(
        e.contains("trk_ch_0.dat: truncated tracking dump") && e.contains("1683 whole records of gnss-sdr-0.0.17"),
        "{e}"
    );
    std::fs::write(d.path().join("trk_ch_0.dat"), b"").unwrap();
    assert!(import_dir(d.path(), &s).unwrap_err().to_string().contains("empty tracking dump"));
    let empty = tempfile::Builder::new().prefix("gsens-gnss-sdr-empty-").tempdir().unwrap();
    assert!(import_dir(empty.path(), &s).unwrap_err().to_string().contains("no tracking dump"));
}

/// A directory holding only a `.mat` dump is read (and refused here: 1.2 s
/// never reaches the 20 ms loop, and the message says so for the `.mat`).
#[test]
fn a_directory_of_mat_dumps_is_read() {
    let f = fixtures();
    let d = tempfile::Builder::new().prefix("gsens-gnss-sdr-mat-").tempdir().unwrap();
    std::fs::copy(f.join("mat/trk_ch_0.mat"), d.path().join("trk_ch_0.mat")).unwrap();
    let e = import_dir(d.path(), &settings(&f.join("mat/gnss-sdr.conf"))).unwrap_err().to_string();
    let records = std::fs::metadata(f.join("mat/trk_ch_0.dat")).unwrap().len() / 96;
    assert!(e.contains("never reached the modelled loop") && e.contains(&format!("in its {records} records")), "{e}");
}

/// A missing directory is named in the error.
#[test]
fn a_missing_dump_directory_is_named() {
    let d = tempfile::Builder::new().prefix("gsens-gnss-sdr-missing-").tempdir().unwrap();
    let dir = d.path().join("no-such-dir");
    let e = gsens_gnss_sdr::find_dumps(&dir, None).unwrap_err().to_string();
    assert!(e.contains(&dir.display().to_string()), "{e}");
    let e = gsens_gnss_sdr::find_dumps(d.path(), None).unwrap_err().to_string();
    assert!(e.contains("no tracking dump"), "{e}");
}

/// A file too large to be a configuration (a log in its place) is refused
/// before it is read, naming it.
#[test]
fn a_configuration_beyond_a_megabyte_is_refused() {
    let d = tempfile::Builder::new().prefix("gsens-gnss-sdr-big-").tempdir().unwrap();
    let big = d.path().join("big.toml");
    std::fs::File::create(&big).unwrap().set_len(2 << 20).unwrap();
    let e = gsens_gnss_sdr::GnssSdrConf::read(&big).unwrap_err().to_string();
    assert!(e.contains("big.toml") && e.contains("2097152 bytes is not a configuration file"), "{e}");
}
