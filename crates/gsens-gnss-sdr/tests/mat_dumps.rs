//! The `.mat` tracking dumps against the `.dat` of the same run: GNSS-SDR
//! 0.0.17's own two files of one short run (`tests/fixtures/mat`: 1.2 s, one
//! satellite at 50 dB-Hz, `Tracking_1C.dump_mat=true`;
//! `scripts/make-gnss-sdr-fixtures.sh`, ONLY=mat; and `tests/fixtures/kf`,
//! 0.3 s tracked by `GPS_L1_CA_KF_Tracking`, ONLY=kf). With the feature off, a
//! `.mat` file is refused with an error that names the feature.

use std::path::{Path, PathBuf};

use gsens_gnss_sdr::dump::{find_dumps, read_dump};

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

#[cfg(feature = "mat")]
mod with_feature {
    use super::*;
    use gsens_gnss_sdr::dump::TrackingRecord;
    use gsens_gnss_sdr::import::{ImportSettings, import_dir};

    /// One field of a record.
    type Getter = fn(&TrackingRecord) -> f64;

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
    /// built here from the real 0.0.17 run's records (no 0.0.21 runs here):
    /// read as the 0.0.21 layout, the same records; a negative week number,
    /// which the `.dat`'s uint32 cannot hold, is refused naming record and variable.
    #[test]
    fn a_0_0_21_mat_reads_as_the_0_0_21_layout() {
        let dat = read_dump(fixtures().join("mat/trk_ch_0.dat"), None).unwrap();
        let n = dat.records.len();
        let write = |path: &Path, wn_last: i32| {
            let f = hdf5::File::create(path).unwrap();
            let r = &dat.records;
            let floats: [(&str, Getter); 19] = [
                ("abs_VE", |x| x.abs_ve),
                ("abs_E", |x| x.abs_e),
                ("abs_P", |x| x.abs_p),
                ("abs_L", |x| x.abs_l),
                ("abs_VL", |x| x.abs_vl),
                ("Prompt_I", |x| x.prompt_i),
                ("Prompt_Q", |x| x.prompt_q),
                ("acc_carrier_phase_rad", |x| x.acc_carrier_phase_rad),
                ("carrier_doppler_hz", |x| x.carrier_doppler_hz),
                ("carrier_doppler_rate_hz", |x| x.carrier_doppler_rate_hz_per_s),
                ("code_freq_chips", |x| x.code_freq_chips_per_s),
                ("code_freq_rate_chips", |x| x.code_freq_rate_chips_per_s2),
                ("carr_error_hz", |x| x.carr_error_cycles),
                ("carr_error_filt_hz", |x| x.carr_error_filt_hz),
                ("code_error_chips", |x| x.code_error_chips),
                ("code_error_filt_chips", |x| x.code_error_filt_chips),
                ("CN0_SNV_dB_Hz", |x| x.cn0_dbhz),
                ("carrier_lock_test", |x| x.carrier_lock_test),
                ("aux1", |x| x.aux1),
            ];
            for (name, get) in floats {
                let v: Vec<f32> = r.iter().map(|x| get(x) as f32).collect();
                f.new_dataset::<f32>().shape([n, 1]).create(name).unwrap().write_raw(&v).unwrap();
            }
            let counts: Vec<u64> = r.iter().map(|x| x.prn_start_sample_count).collect();
            f.new_dataset::<u64>().shape([n, 1]).create("PRN_start_sample_count").unwrap().write_raw(&counts).unwrap();
            let aux2: Vec<f64> = r.iter().map(|x| x.aux2).collect();
            f.new_dataset::<f64>().shape([n, 1]).create("aux2").unwrap().write_raw(&aux2).unwrap();
            let prn: Vec<u32> = r.iter().map(|x| x.prn).collect();
            f.new_dataset::<u32>().shape([n, 1]).create("PRN").unwrap().write_raw(&prn).unwrap();
            let tow: Vec<u64> = (0..n as u64).map(|k| 345_600_000 + k).collect();
            f.new_dataset::<u64>().shape([n, 1]).create("TOW_ms").unwrap().write_raw(&tow).unwrap();
            let mut wn = vec![2391i32; n];
            wn[n - 1] = wn_last;
            f.new_dataset::<i32>().shape([n, 1]).create("WN").unwrap().write_raw(&wn).unwrap();
        };
        let d = tmp("v21");
        let p = d.join("trk_ch_5.mat");
        write(&p, 2391);
        let m = read_dump(&p, None).unwrap();
        assert_eq!((m.layout.as_str(), m.channel, m.records.len()), ("gnss-sdr-0.0.21", Some(5), n));
        for (k, (a, b)) in m.records.iter().zip(&dat.records).enumerate() {
            assert_eq!(bits(a), bits(b), "record {k}");
            assert_eq!((a.tow_ms, a.wn), (Some(345_600_000 + k as u64), Some(2391)));
        }
        write(&p, -1);
        let e = read_dump(&p, None).unwrap_err().to_string();
        assert!(
            e.contains(&format!("trk_ch_5.mat: record {}: variable `WN` does not fit the dump's U32", n - 1)),
            "{e}"
        );
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
}

#[test]
fn a_directory_prefers_the_dat_of_a_channel() {
    let found = find_dumps(&fixtures().join("mat"), None).unwrap();
    assert_eq!(found.len(), 1);
    assert!(found[0].1.ends_with("trk_ch_0.dat"), "{found:?}");
}

#[cfg(not(feature = "mat"))]
#[test]
fn without_the_feature_a_mat_file_names_the_feature() {
    let p = fixtures().join("mat/trk_ch_0.mat");
    let e = read_dump(&p, None).unwrap_err().to_string();
    assert!(e.starts_with(&format!("{}: a .mat tracking dump", p.display())), "{e}");
    assert!(e.contains("built without the `mat` feature") && e.contains("--features mat"), "{e}");
    let d = tmp("nofeature");
    std::fs::copy(&p, d.join("trk_ch_0.mat")).unwrap();
    assert!(find_dumps(&d, None).unwrap()[0].1.ends_with("trk_ch_0.mat"));
}
