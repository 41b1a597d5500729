//! GNSS-SDR 0.0.17's dumps at the tracking settings other than 20 ms
//! integrations (`tests/fixtures/ext1`, `ext2`, made by
//! `scripts/make-gnss-sdr-fixtures.sh`, ONLY=ext): one shaken session tracked
//! with `extend_correlation_symbols=1` (GNSS-SDR's default: a 3 Hz
//! 2nd-order loop updated every 1 ms after an FLL pull-in, one record per
//! 20 ms data bit after bit synchronization) and with `=2` (no FLL, a
//! 3rd-order 35 Hz loop at 1 ms, then 3 Hz at 2 ms). The truth is the
//! simulator's.

use std::path::{Path, PathBuf};

use gsens_calib::PipelineSettings;
use gsens_gnss_sdr::calibrate_gnss_sdr;
use gsens_gnss_sdr::{GnssSdrError, parse_dump};
use gsens_gnss_sdr::{ImportSettings, TrackFate, import_dir};

fn dir(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures").join(name)
}

fn settings(name: &str) -> ImportSettings {
    ImportSettings::from_conf(Some(&dir(name).join("gnss-sdr.conf")), None).unwrap()
}

fn truth(name: &str, key: &str) -> [f64; 3] {
    let text = std::fs::read_to_string(dir(name).join("truth.json")).unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    std::array::from_fn(|i| v[key][i].as_f64().unwrap())
}

#[test]
fn each_channel_is_one_track_whose_records_hold_the_last_of_twenty_over_n_updates() {
    for (name, symbols) in [("ext1", 1u32), ("ext2", 2)] {
        let s = settings(name);
        assert_eq!(s.stage().symbols, symbols);
        assert_eq!(s.stage().updates_per_record(), Some(20 / symbols));
        let imported = import_dir(&dir(name), &s).unwrap();
        assert_eq!(imported.interval_s, 0.02, "{name}: one record per data bit");
        // Each dump holds 100 records of 1 ms before bit synchronization, then one per bit:
        // a single track per channel.
        assert_eq!(imported.tracks.len(), 2, "{name}: {:#?}", imported.tracks);
        for (k, t) in imported.tracks.iter().enumerate() {
            assert!(t.used && t.fate == TrackFate::Used, "{name} track {k}: {}", t.reason);
            assert!(t.records > 2000, "{name} track {k}: {} records", t.records);
            let rows: Vec<_> = imported.rows.iter().filter(|r| r.track == k).collect();
            // Kept: records one bit apart, each the N ms integration that ends the bit, its
            // middle N/2 ms before the bit's end.
            assert!(rows.iter().all(|r| r.symbols == symbols));
            for w in rows.windows(2) {
                assert!((w[1].t_s - w[0].t_s - 0.02).abs() < 1e-6, "{name}: {} → {}", w[0].t_s, w[1].t_s);
            }
            assert_eq!(rows.len(), t.good_records);
        }
    }
}

#[test]
fn a_track_that_ends_within_the_pull_in_never_reaches_the_1_ms_loop() {
    // The first 100 records of ext1's channel 0 (1 ms apart, before bit synchronization):
    // with N = 1 the loop is modelled from the end of GNSS-SDR's pull-in transitory on,
    // which these 0.1 s never reach.
    let s = settings("ext1");
    let bytes = std::fs::read(dir("ext1").join("trk_ch_0.dat")).unwrap();
    let head = parse_dump(&bytes[..100 * 96], "trk_ch_0.dat", None).unwrap();
    let (rows, tracks) = gsens_gnss_sdr::import_dump(&head, &s, 0);
    assert!(rows.is_empty());
    assert_eq!(tracks.len(), 1);
    assert_eq!(tracks[0].fate, TrackFate::NeverModelled, "{}", tracks[0].reason);
    assert!(tracks[0].reason.contains("pull_in_time_s = 2 s (the FLL)"), "{}", tracks[0].reason);
}

#[test]
fn the_default_setting_and_2_ms_integrations_estimate_within_3_sigma_with_the_default_options() {
    for name in ["ext1", "ext2"] {
        let truth_imu = truth(name, "gamma_imu_axes_hz_per_mps2");
        let o =
            calibrate_gnss_sdr(&dir(name), &settings(name), &dir(name).join("imu.csv"), &PipelineSettings::default())
                .unwrap()
                .outcome;
        let doc = o.document(None);
        let c = &o.calibration;
        let codes: Vec<&str> = doc.warnings.iter().map(|w| w.code.as_str()).collect();
        eprintln!("{name}: trustworthy {}, warnings {codes:?}, {} epochs", doc.trustworthy, c.epochs_used);
        for i in 0..3 {
            let (g, sd) = (c.gamma_hz_per_mps2[i].unwrap(), c.sigma_hz_per_mps2[i].unwrap());
            eprintln!(
                "{name} axis {i}: Γ̂ {g:+.5} ± {sd:.5}, truth {:+.5}, {:+.2}σ",
                truth_imu[i],
                (g - truth_imu[i]) / sd
            );
            assert!((g - truth_imu[i]).abs() < 3.0 * sd, "{name} axis {i}: {g} ± {sd} vs {}", truth_imu[i]);
        }
        assert!(doc.trustworthy, "{name}: {codes:?}");
        // The loop modelled: N ms updates, 20/N of them per 20 ms record, the last logged.
        assert!((c.log_interval_s - 0.02).abs() < 1e-9, "{}", c.log_interval_s);
        assert_eq!(c.model_substeps, if name == "ext1" { 20 } else { 10 });
    }
}

#[test]
fn a_directory_with_no_usable_record_says_so_in_one_line_per_channel_and_reason() {
    // GNSS-SDR's 2 ms dumps with every 7th record dropped, copied over 20 channels (each
    // under its own PRN): every channel is cut into some 400 tracks of a few records, the
    // first ones before bit synchronization, the others shorter than the settling time.
    let tmp_scratch = tempfile::Builder::new().prefix("gsens-no-usable-").tempdir().unwrap();
    let tmp = tmp_scratch.path().to_path_buf();
    std::fs::create_dir_all(&tmp).unwrap();
    std::fs::copy(dir("ext2").join("gnss-sdr.conf"), tmp.join("gnss-sdr.conf")).unwrap();
    for ch in 0..20u32 {
        let src = std::fs::read(dir("ext2").join(format!("trk_ch_{}.dat", ch % 2))).unwrap();
        let mut out = Vec::new();
        for (k, r) in src.chunks(96).enumerate() {
            if k % 7 != 3 {
                let mut r = r.to_vec();
                r[92..96].copy_from_slice(&(ch + 1).to_le_bytes());
                out.extend(r);
            }
        }
        std::fs::write(tmp.join(format!("trk_ch_{ch}.dat")), out).unwrap();
    }
    let s = ImportSettings::from_conf(Some(&tmp.join("gnss-sdr.conf")), None).unwrap();
    let e = import_dir(&tmp, &s).unwrap_err();
    let text = e.to_string();
    std::fs::remove_dir_all(&tmp).unwrap();
    assert!(matches!(e, GnssSdrError::NothingUsable { .. }), "{text}");
    let lines = text.lines().count();
    eprintln!("{lines} lines:\n{text}");
    assert!(lines < 50 && text.len() < 10_000, "{lines} lines, {} bytes", text.len());
    assert!(text.contains("channel 19,") && text.contains("tracks (PRN 20)"), "{text}");
    assert!(text.contains("fewer than"), "{text}");
    assert!(text.contains("no bit synchronization"), "{text}");
}
