//! The `.mat` tracking dumps against the `.dat` of the same run: GNSS-SDR
//! 0.0.17's own two files of one short run (`tests/fixtures/mat`: 1.2 s, one
//! satellite at 50 dB-Hz, `Tracking_1C.dump_mat=true`;
//! `scripts/make-gnss-sdr-fixtures.sh`, ONLY=mat; and `tests/fixtures/kf`,
//! 0.3 s tracked by `GPS_L1_CA_KF_Tracking`, ONLY=kf), read by the crate's own
//! HDF5 reader.

use std::path::{Path, PathBuf};

use gsens_gnss_sdr::{ImportSettings, import_dir};
use gsens_gnss_sdr::{TrackingRecord, find_dumps, read_dump};

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures")
}

/// A scratch folder, removed when dropped; derefs to its path.
struct Scratch(tempfile::TempDir);

impl std::ops::Deref for Scratch {
    type Target = Path;
    fn deref(&self) -> &Path {
        self.0.path()
    }
}

fn tmp(name: &str) -> Scratch {
    Scratch(tempfile::Builder::new().prefix(&format!("gsens-mat-{name}-")).tempdir().unwrap())
}

/// Every field of two records, bit for bit.
fn bits(r: &TrackingRecord) -> Vec<u64> {
    let f = [
        r.abs_ve,
        r.abs_e,
        r.abs_p,
        r.abs_l,
        r.abs_vl,
        r.prompt_i,
        r.prompt_q,
        r.acc_carrier_phase_rad,
        r.carrier_doppler_hz,
        r.carrier_doppler_rate_hz_per_s,
        r.code_freq_chips_per_s,
        r.code_freq_rate_chips_per_s2,
        r.carr_error_cycles,
        r.carr_error_filt_hz,
        r.code_error_chips,
        r.code_error_filt_chips,
        r.cn0_dbhz,
        r.carrier_lock_test,
        r.aux1,
        r.aux2,
    ];
    let mut v: Vec<u64> = f.iter().map(|x| x.to_bits()).collect();
    v.extend([r.prn_start_sample_count, u64::from(r.prn)]);
    v
}

#[test]
fn the_mat_and_the_dat_of_one_run_read_identically() {
    let dir = fixtures().join("mat");
    let dat = read_dump(dir.join("trk_ch_0.dat"), None).unwrap();
    let mat = read_dump(dir.join("trk_ch_0.mat"), None).unwrap();
    // Every byte of the .dat read (a GNSS-SDR run's record count varies from run to run).
    let len = std::fs::metadata(dir.join("trk_ch_0.dat")).unwrap().len();
    assert!(dat.records.len() > 300 && dat.records.len() as u64 * 96 == len, "{len}");
    assert_eq!((mat.layout.as_str(), mat.channel, mat.modelled), ("gnss-sdr-0.0.17", Some(0), true));
    assert_eq!(mat.records.len(), dat.records.len());
    for (k, (a, b)) in mat.records.iter().zip(&dat.records).enumerate() {
        assert_eq!(bits(a), bits(b), "record {k}");
    }
    // The importer gives the same rows from a directory holding only the .mat.
    let only_mat = tmp("only-mat");
    std::fs::copy(dir.join("trk_ch_0.mat"), only_mat.join("trk_ch_0.mat")).unwrap();
    assert!(find_dumps(&only_mat, None).unwrap()[0].1.ends_with("trk_ch_0.mat"));
    let settings = ImportSettings::from_conf(Some(&dir.join("gnss-sdr.conf")), None).unwrap();
    let (a, b) = (import_dir(&only_mat, &settings), import_dir(&dir, &settings));
    // 1.2 s never reaches the 20 ms loop: both say so, in the same words but the file name.
    let (a, b) = (a.unwrap_err().to_string(), b.unwrap_err().to_string());
    assert_eq!(a.replace(&only_mat.display().to_string(), "D"), b.replace(&dir.display().to_string(), "D"));
    assert!(a.contains("never reached the modelled loop"), "{a}");
}

/// The Kalman block's `.mat` (its own variable names) reads as its layout, the `.dat`'s records.
#[test]
fn the_kalman_trackers_mat_reads_as_its_dat() {
    let dir = fixtures().join("kf");
    let dat = read_dump(dir.join("trk_kf_ch_0.dat"), None).unwrap();
    let mat = read_dump(dir.join("trk_kf_ch_0.mat"), None).unwrap();
    assert_eq!((mat.layout.as_str(), mat.modelled), ("gnss-sdr-kf-cc", false));
    assert_eq!(dat.layout, mat.layout);
    assert_eq!(mat.records.len(), dat.records.len());
    for (k, (a, b)) in mat.records.iter().zip(&dat.records).enumerate() {
        assert_eq!(bits(a), bits(b), "record {k}");
    }
}

/// A `.mat` as GNSS-SDR 0.0.21's `save_matfile` names and types its arrays
/// (dll_pll_veml_tracking.cc at tag v0.0.21: 19 float, `PRN_start_sample_count`
/// and `TOW_ms` uint64, `aux2` double, `PRN` uint32, `WN` int32, each 1 × N),
/// made from the real 0.0.17 run's arrays by libhdf5 (h5py) with deflated,
/// contiguous and compact arrays (`scripts/make-mat-v21-fixtures.py`; no 0.0.21
/// runs here): read as the 0.0.21 layout, the same records; a negative week
/// number, which the `.dat`'s uint32 cannot hold, is refused naming record and
/// variable.
#[test]
fn a_0_0_21_mat_reads_as_the_0_0_21_layout() {
    let dat = read_dump(fixtures().join("mat/trk_ch_0.dat"), None).unwrap();
    let n = dat.records.len();
    let m = read_dump(fixtures().join("mat-v21/trk_ch_5.mat"), None).unwrap();
    assert_eq!((m.layout.as_str(), m.channel, m.records.len()), ("gnss-sdr-0.0.21", Some(5), n));
    for (k, (a, b)) in m.records.iter().zip(&dat.records).enumerate() {
        assert_eq!(bits(a), bits(b), "record {k}");
        assert_eq!((a.tow_ms, a.wn), (Some(345_600_000 + k as u64), Some(2391)));
    }
    let e = read_dump(fixtures().join("mat-v21-wn/trk_ch_5.mat"), None).unwrap_err().to_string();
    assert!(e.contains(&format!("trk_ch_5.mat: record {}: variable `WN` does not fit the dump's U32", n - 1)), "{e}");
}

#[test]
fn bad_mat_files_get_clear_errors() {
    let d = tmp("bad");
    let p = d.join("trk_ch_3.mat");
    std::fs::write(&p, b"MATLAB 5.0 MAT-file, not HDF5").unwrap();
    let e = read_dump(&p, None).unwrap_err().to_string();
    assert!(e.starts_with(&format!("{}: not a MATLAB v7.3 (HDF5) file", p.display())), "{e}");
    // A real .mat forced onto the 0.0.21 layout lacks TOW_ms.
    let e = read_dump(fixtures().join("mat/trk_ch_0.mat"), Some(&gsens_gnss_sdr::DumpLayout::v0_0_21()))
        .unwrap_err()
        .to_string();
    assert!(e.contains("trk_ch_0.mat: variable `TOW_ms`"), "{e}");
}

#[test]
fn a_directory_prefers_the_dat_of_a_channel() {
    let found = find_dumps(&fixtures().join("mat"), None).unwrap();
    assert_eq!(found.len(), 1);
    assert!(found[0].1.ends_with("trk_ch_0.dat"), "{found:?}");
}

/// A damaged `.mat` is an error, never a panic: the real file cut at many
/// lengths, and with single bytes changed across its structures (superblock,
/// B-trees, heaps, object headers, deflated chunks).
#[test]
fn damaged_mat_files_are_errors() {
    use gsens_gnss_sdr::mat::parse_mat_dump;
    let good = std::fs::read(fixtures().join("mat/trk_ch_0.mat")).unwrap();
    assert!(parse_mat_dump(&good, "trk_ch_0.mat", None).is_ok());
    // (Cut in its last kilobytes, which hold no array and no index, it still reads.)
    for len in (0..good.len() * 9 / 10).step_by(211) {
        let e = parse_mat_dump(&good[..len], "trk_ch_0.mat", None).map(|_| ()).unwrap_err().to_string();
        assert!(e.starts_with("trk_ch_0.mat: "), "{e}");
    }
    let mut bad = good.clone();
    for at in (512..good.len()).step_by(331) {
        for b in [0x00, 0xff, good[at] ^ 0x10] {
            bad[at] = b;
            let _ = parse_mat_dump(&bad, "trk_ch_0.mat", None);
        }
        bad[at] = good[at];
    }
    // Not HDF5 beyond the user block, and a later superblock version: named.
    let e = parse_mat_dump(&good[..600], "x.mat", None).unwrap_err().to_string();
    assert!(e.starts_with("x.mat: "), "{e}");
    bad[512 + 8] = 2;
    let e = parse_mat_dump(&bad, "x.mat", None).unwrap_err().to_string();
    assert!(e.contains("superblock version 2"), "{e}");
}
