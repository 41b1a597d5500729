//! The reader and the loop models against GNSS-SDR 0.0.17's real output: the
//! fixtures are dumps it wrote for a gsens IF file whose truth is known
//! (`scripts/make-gnss-sdr-fixtures.sh`; see `tests/fixtures/`).

use std::path::{Path, PathBuf};

use gsens_calib::{EpochSeries, EstimateSettings, calibrate};
use gsens_core::LoopModel;
use gsens_core::gnss_sdr::{GnssSdrPll, GnssSdrStage};
use gsens_core::{LinearLoop, LoopSpec};
use gsens_gnss_sdr::GnssSdrConf;
use gsens_gnss_sdr::{DumpLayout, TrackingRecord, parse_dump, read_dump};
use gsens_gnss_sdr::{ImportSettings, import_dir, resample};
use gsens_io::read_imu_file;
use gsens_session::{SelectionConfig, prepare_session};

const FS_HZ: f64 = 2_048_000.0;

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures")
}

fn dump(order: u8, ch: u32) -> Vec<TrackingRecord> {
    read_dump(fixtures().join(format!("order{order}/trk_ch_{ch}.dat")), None).unwrap().records
}

/// Index of the first 20 ms record.
fn switch_index(r: &[TrackingRecord]) -> usize {
    (1..r.len()).find(|&k| r[k].prn_start_sample_count - r[k - 1].prn_start_sample_count > 30_000).unwrap()
}

#[test]
fn reads_real_dumps() {
    for (order, ch) in [(2u8, 0u32), (2, 1), (3, 0)] {
        let path = fixtures().join(format!("order{order}/trk_ch_{ch}.dat"));
        let len = std::fs::metadata(&path).unwrap().len();
        let d = read_dump(&path, None).unwrap();
        assert_eq!(d.layout, "gnss-sdr-0.0.17");
        assert_eq!(d.channel, Some(ch));
        assert_eq!(d.records.len() as u64 * 96, len);
        let r = &d.records;
        // 100 records of the 1 ms pull-in, then 20 ms integrations to the end.
        let k = switch_index(r);
        assert_eq!(k, 100, "order {order} ch {ch}");
        for w in r[..k].windows(2) {
            let dn = w[1].prn_start_sample_count - w[0].prn_start_sample_count;
            assert!((2047..=2049).contains(&dn), "{dn}");
        }
        for w in r[k..].windows(2) {
            let dn = w[1].prn_start_sample_count - w[0].prn_start_sample_count;
            assert!((40_959..=40_961).contains(&dn), "{dn}");
        }
        // One satellite; what GNSS-SDR writes: filter output = NCO command, aux2 = sample counter.
        assert!(r.iter().all(|x| x.prn == r[0].prn && [28, 31].contains(&x.prn)));
        assert!(r.iter().all(|x| x.carr_error_filt_hz == x.carrier_doppler_hz));
        assert!(r.iter().all(|x| x.aux2 == x.prn_start_sample_count as f64));
        // Locked at 55 dB-Hz: the lock test near 1, C/N0 within 3 dB, φ well inside ±π/4.
        for x in &r[k..] {
            assert!(x.carrier_lock_test > 0.9 && (x.cn0_dbhz - 55.0).abs() < 5.0, "{x:?}");
            assert!(x.carr_error_cycles.abs() < 0.125);
        }
    }
}

#[test]
fn bad_versions_of_real_dumps_get_clear_errors() {
    let path = fixtures().join("order2/trk_ch_0.dat");
    let bytes = std::fs::read(&path).unwrap();
    let name = "trk_ch_0.dat";
    // Truncated in the middle of the last record.
    let e = parse_dump(&bytes[..bytes.len() - 40], name, None).unwrap_err().to_string();
    assert!(e.starts_with("trk_ch_0.dat: truncated tracking dump: 161624 bytes is 1683 whole records"), "{e}");
    assert!(e.contains("of gnss-sdr-0.0.17 (96 bytes per record: GNSS-SDR 0.0.17 to 0.0.20"), "{e}");
    assert!(e.contains("and 56 bytes of a partial one"), "{e}");
    // Empty.
    let e = parse_dump(&[], name, None).unwrap_err().to_string();
    assert!(e.contains("empty tracking dump (0 bytes)"), "{e}");
    // Another version: each record 8 bytes shorter (an f64 less), cut to a multiple of 96 bytes.
    let other: Vec<u8> = bytes.chunks_exact(96).flat_map(|r| r[..88].iter().copied()).collect();
    let other = &other[..other.len() / 96 * 96];
    let e = parse_dump(other, name, None).unwrap_err().to_string();
    assert!(e.starts_with("trk_ch_0.dat: 148128 bytes fits no tracking-dump layout"), "{e}");
    assert!(
        e.contains("gnss-sdr-0.0.17 (96 bytes per record") && e.contains("record 0 (byte offset 0): PRN = "),
        "{e}"
    );
    // A record shifted by 4 bytes (a stray header).
    let mut shifted = vec![0u8; 96];
    shifted.extend_from_slice(&bytes[4..bytes.len() - 4 + 4 - 96]);
    let e = parse_dump(&shifted[..shifted.len() / 96 * 96], name, None).unwrap_err().to_string();
    assert!(e.contains("record 0 (byte offset 0): PRN = 0"), "{e}");
    // Forced onto the other layouts, GNSS-SDR 0.0.17's own bytes are refused.
    for l in [DumpLayout::kf_cc(), DumpLayout::legacy_88(), DumpLayout::v0_0_21()] {
        let cut = &bytes[..bytes.len() / l.record_bytes() * l.record_bytes()];
        let e = parse_dump(cut, name, Some(&l)).unwrap_err().to_string();
        assert!(e.starts_with("trk_ch_0.dat: record ") && e.contains(&format!("(layout {})", l.name)), "{e}");
    }
}

/// The real 0.0.17 records re-packed as 0.0.21 writes them (TOW and WN
/// appended, `dll_pll_veml_tracking.cc` at v0.0.21) read back as the same
/// records; appended to the 0.0.17 file they are a mixed dump.
#[test]
fn real_records_in_the_0_0_21_layout_and_mixed_with_0_0_17() {
    let bytes = std::fs::read(fixtures().join("order2/trk_ch_1.dat")).unwrap();
    let v17 = parse_dump(&bytes, "trk_ch_1.dat", None).unwrap();
    let mut v21 = Vec::new();
    for (k, rec) in bytes.chunks_exact(96).enumerate() {
        v21.extend_from_slice(rec);
        v21.extend_from_slice(&(100_000 + 20 * k as u64).to_le_bytes());
        v21.extend_from_slice(&2300u32.to_le_bytes());
    }
    let d = parse_dump(&v21, "trk_ch_1.dat", None).unwrap();
    assert_eq!(d.layout, "gnss-sdr-0.0.21");
    assert_eq!(d.records.len(), v17.records.len());
    for (a, b) in d.records.iter().zip(&v17.records) {
        assert_eq!(TrackingRecord { tow_ms: None, wn: None, ..*a }, *b);
        assert_eq!(a.wn, Some(2300));
    }
    // The 0.0.17 dump with the last 50 records of the 0.0.21 one appended.
    let mut mixed = bytes.clone();
    mixed.extend_from_slice(&v21[v21.len() - 50 * 108..]);
    let e = parse_dump(&mixed, "trk_ch_1.dat", None).unwrap_err().to_string();
    assert!(e.contains("mixed tracking-dump layouts: 1684 records of gnss-sdr-0.0.17"), "{e}");
    assert!(e.contains("from byte offset 161664 50 records of gnss-sdr-0.0.21"), "{e}");
}

/// Runs GNSS-SDR's filter (the library's) over a real dump's discriminator
/// outputs, bandwidth switch included, from the initial state (unknown: the
/// fixture starts mid pull-in) that fits best; returns the largest and the RMS difference to the dumped
/// filter outputs [Hz].
fn filter_replay(order: u8, r: &[TrackingRecord]) -> (f64, f64) {
    let k = switch_index(r);
    let stage_of = |i: usize| if i < k { (35.0, 0.001) } else { (3.0, 0.02) };
    let run = |w0: f64, x0: f64, zero_input: bool| -> Vec<f64> {
        let mut f = gsens_core::gnss_sdr::GnssSdrFilter::new(order, 35.0, 0.001);
        f.set_state(w0, x0);
        (0..r.len())
            .map(|i| {
                let (bw, t) = stage_of(i);
                f.set_params(bw, t);
                f.update(if zero_input { 0.0 } else { r[i].carr_error_cycles })
            })
            .collect()
    };
    // The output is affine in the initial state: fit (w0, x0) by least squares.
    let base = run(0.0, 0.0, false);
    let rw = run(1.0, 0.0, true);
    let rx = run(0.0, 1.0, true);
    let (mut a11, mut a12, mut a22, mut b1, mut b2) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for i in 0..r.len() {
        let y = r[i].carr_error_filt_hz - base[i];
        a11 += rw[i] * rw[i];
        a12 += rw[i] * rx[i];
        a22 += rx[i] * rx[i];
        b1 += rw[i] * y;
        b2 += rx[i] * y;
    }
    let (w0, x0) = if order == 3 {
        let det = a11 * a22 - a12 * a12;
        ((a22 * b1 - a12 * b2) / det, (a11 * b2 - a12 * b1) / det)
    } else {
        (b1 / a11, 0.0)
    };
    let out = run(w0, x0, false);
    let d: Vec<f64> = out.iter().zip(r).map(|(o, x)| o - x.carr_error_filt_hz).collect();
    let max = d.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let rms = (d.iter().map(|v| v * v).sum::<f64>() / d.len() as f64).sqrt();
    (max, rms)
}

#[test]
fn loop_filters_reproduce_gnss_sdr_through_the_bandwidth_switch() {
    for (order, ch) in [(2u8, 0u32), (2, 1), (3, 0)] {
        let r = dump(order, ch);
        let (max, rms) = filter_replay(order, &r);
        // GNSS-SDR keeps its filter in single precision: agreement to millihertz over 1700 records.
        assert!(max < 0.02 && rms < 0.005, "order {order} ch {ch}: max {max} Hz, rms {rms} Hz");
        // A filter that is not GNSS-SDR's is far off: the other order's equations.
        let (max_other, _) = filter_replay(5 - order, &r);
        eprintln!(
            "order {order} ch {ch}: filter replay max {max:.4} Hz, rms {rms:.4} Hz; other order's max {max_other:.2} Hz"
        );
        assert!(max_other > 50.0 * max, "order {order}: the other order fits too ({max_other} vs {max})");
    }
}

/// The true baseband carrier of the order-3 channel 0 per 1 ms block.
fn carrier_truth() -> (u32, usize, Vec<f64>) {
    let meta: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(fixtures().join("carrier_ch0.json")).unwrap()).unwrap();
    let raw = std::fs::read(fixtures().join("carrier_ch0.f32")).unwrap();
    let off = meta["offset_hz"].as_f64().unwrap();
    let v = raw.chunks_exact(4).map(|c| f64::from(f32::from_le_bytes(c.try_into().unwrap())) + off).collect();
    (meta["prn"].as_u64().unwrap() as u32, meta["first_block"].as_u64().unwrap() as usize, v)
}

#[test]
fn phase_recursion_reproduces_gnss_sdr_discriminator_outputs() {
    let (prn, b0, carrier) = carrier_truth();
    let r = dump(3, 0);
    assert_eq!(r[0].prn, prn);
    // Mean carrier over [a, b) s from the per-millisecond truth.
    let mean = |a: f64, b: f64| {
        let n = 400;
        (0..n).map(|i| carrier[((a + (b - a) * (i as f64 + 0.5) / n as f64) * 1e3) as usize - b0]).sum::<f64>()
            / n as f64
    };
    let t0 = b0 as f64 * 1e-3 + 0.05;
    let t1 = t0 + (carrier.len() as f64) * 1e-3 - 0.1;
    let recs: Vec<&TrackingRecord> = r
        .iter()
        .filter(|x| {
            let t = x.prn_start_sample_count as f64 / FS_HZ;
            t - 0.02 > t0 && t < t1
        })
        .collect();
    assert!(recs.len() > 500, "{}", recs.len());
    let stage = GnssSdrStage { order: 3, bw_hz: 3.0, symbols: 20 };
    // Replay with the dumped NCO commands; N ms of the next command booked per record: 1 (GNSS-SDR), 0 (a
    // continuous NCO, gsens's DiscretePll).
    let replay = |quirk: bool| -> f64 {
        let mut p = GnssSdrPll::new(stage).unwrap();
        let prev = r.iter().position(|x| std::ptr::eq(x, recs[0])).unwrap() - 1;
        p.set_phase_and_nco(0.0, r[prev].carrier_doppler_hz);
        let mut resid = Vec::new();
        for x in &recs {
            let t_end = x.prn_start_sample_count as f64 / FS_HZ;
            let g = mean(t_end - 0.02, t_end);
            let (e, f_prev) = p.phase_and_nco();
            let phi = p.open_loop_step(g, x.carrier_doppler_hz);
            if !quirk {
                // A continuous NCO: the whole record at the previous command.
                p.set_phase_and_nco(e + core::f64::consts::TAU * 0.02 * (g - f_prev), x.carrier_doppler_hz);
            }
            resid.push(core::f64::consts::TAU * x.carr_error_cycles - phi);
        }
        // The initial phase error is unknown: remove the mean.
        let m = resid.iter().sum::<f64>() / resid.len() as f64;
        (resid.iter().map(|v| (v - m) * (v - m)).sum::<f64>() / resid.len() as f64).sqrt()
    };
    let gnss_sdr = replay(true);
    let continuous = replay(false);
    // Thermal noise of a 20 ms atan discriminator at the dump's C/N0.
    let cn0 = recs.iter().map(|x| gsens_core::units::cn0_dbhz_to_ratio_hz(x.cn0_dbhz)).sum::<f64>() / recs.len() as f64;
    let noise = (1.0 / (2.0 * cn0 * 0.02)).sqrt();
    eprintln!(
        "phase replay RMS: GNSS-SDR's booking {gnss_sdr:.4} rad, continuous NCO {continuous:.4} rad, thermal {noise:.4} rad"
    );
    assert!(gnss_sdr < 1.3 * noise, "GNSS-SDR's phase booking leaves {gnss_sdr} rad, thermal noise {noise} rad");
    assert!(gnss_sdr < 0.85 * continuous, "{gnss_sdr} vs a continuous NCO {continuous}");
}

fn estimate(order: u8, exact: bool) -> [f64; 3] {
    let dir = fixtures().join(format!("order{order}"));
    let tc = GnssSdrConf::read(dir.join("gnss-sdr.conf")).unwrap().tracking().unwrap();
    let settings = ImportSettings::new(tc.fs_hz.unwrap(), tc.clone());
    let imported = import_dir(&dir, &settings).unwrap();
    assert!(imported.tracks.iter().all(|t| t.used), "{:?}", imported.tracks);
    let grid = resample(&imported, imported.interval_s);
    let log = gsens_io::TrackingLog::from_rows("grid", &grid).unwrap();
    let imu = read_imu_file(fixtures().join("imu.csv")).unwrap();
    let session = prepare_session(&log, &imu, "imu.csv", &SelectionConfig::default(), 0.0).unwrap();
    let stage = settings.stage();
    let nominal = if order == 3 { LoopSpec::third_order_kaplan(3.0) } else { LoopSpec::PAPER };
    let s = EstimateSettings::default().with_loop(if exact {
        LoopModel::GnssSdr(stage)
    } else {
        LoopModel::kaplan(nominal, Some(0.02))
    });
    let series = EpochSeries {
        log_interval_s: session.log_interval_s,
        t_s: &session.t_s,
        phase_err_rad: &session.phase_err_rad,
        accel_mps2: &session.accel_mps2,
        imu_time_offset_s: 0.0,
    };
    let c = calibrate(&series, &s).unwrap();
    c.gamma_hz_per_mps2.map(|g| g.expect("observable"))
}

#[test]
fn gamma_from_real_dumps_within_2_percent_with_the_exact_loop_model() {
    let truth: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(fixtures().join("truth.json")).unwrap()).unwrap();
    let g: Vec<f64> = truth["gamma_hz_per_mps2"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
    for order in [2u8, 3] {
        let est = estimate(order, true);
        eprintln!("order {order}: Γ̂ {est:?} vs {g:?}");
        for i in 0..3 {
            let err = (est[i] - g[i]) / g[i].abs();
            assert!(err.abs() < 0.02, "order {order} axis {i}: {} vs {} ({:+.2} %)", est[i], g[i], 100.0 * err);
        }
    }
    // Kaplan's 3rd-order loop in place of GNSS-SDR's: far off.
    let est = estimate(3, false);
    eprintln!("order 3 with Kaplan's loop model: Γ̂ {est:?}");
    let err = (est[0] - g[0]) / g[0];
    assert!(err.abs() > 0.1, "Kaplan's model should be off by > 10 %: {:+.1} %", 100.0 * err);
}

#[test]
fn the_exact_model_steps_like_gnss_sdr_on_a_switch() {
    // The pull-in stage, switched to the narrow loop with its state kept, stays stable and settles.
    let mut p = GnssSdrPll::new(GnssSdrStage { order: 3, bw_hz: 35.0, symbols: 1 }).unwrap();
    for _ in 0..2000 {
        p.step(0.4);
    }
    p.switch_stage(3.0, 20).unwrap();
    let mut last = 1.0;
    for _ in 0..2000 {
        last = p.step(0.4);
    }
    assert!(last.abs() < 1e-9, "{last}");
}

/// GNSS-SDR 0.0.17's own dump from `GPS_L1_CA_KF_Tracking`
/// (`gps_l1_ca_kf_tracking_cc`; a 0.3 s run, `tests/fixtures/kf`, ONLY=kf of
/// `scripts/make-gnss-sdr-fixtures.sh`): the
/// reader recognises its layout (same size as dll_pll_veml_tracking's), the
/// dll_pll_veml layout refuses it, and the importer says it cannot model it.
#[test]
fn a_real_kalman_tracker_dump_is_recognised_and_not_modelled() {
    let dir = fixtures().join("kf");
    let path = dir.join("trk_kf_ch_0.dat");
    let d = read_dump(&path, None).unwrap();
    let len = std::fs::metadata(&path).unwrap().len();
    assert_eq!((d.layout.as_str(), d.modelled, d.records.len() as u64 * 96), ("gnss-sdr-kf-cc", false, len));
    // This block writes a record per millisecond even while idle: counter at the start, aux2 one code period on.
    for r in &d.records {
        assert_eq!(r.aux2 - r.prn_start_sample_count as f64, 2048.0);
        assert_eq!(r.code_freq_chips_per_s, 1.023e6);
    }
    let e = read_dump(&path, Some(&DumpLayout::v0_0_17())).unwrap_err().to_string();
    assert!(e.contains("record 0 (byte offset 0): aux2 = 2048 is not the sample counter 0"), "{e}");
    // Its configuration names a tracker gsens does not model; without it, the dump's layout says so.
    let e = GnssSdrConf::read(dir.join("gnss-sdr.conf")).unwrap().tracking().unwrap_err().to_string();
    assert!(e.contains("GPS_L1_CA_KF_Tracking"), "{e}");
    let settings = ImportSettings::from_conf(None, Some(FS_HZ)).unwrap();
    let e = import_dir(&dir, &settings).unwrap_err().to_string();
    assert!(e.contains("trk_kf_ch_0.dat: a tracking dump of layout gnss-sdr-kf-cc"), "{e}");
    assert!(e.contains("gsens models only the carrier loop of dll_pll_veml_tracking"), "{e}");
}

/// A copy of the order-2 fixture directory in the system's temporary directory, removed when dropped.
struct DirCopy(PathBuf);

impl DirCopy {
    fn new(name: &str) -> Self {
        let to = std::env::temp_dir().join(format!("gsens-gnss-sdr-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&to);
        std::fs::create_dir_all(&to).unwrap();
        for f in ["gnss-sdr.conf", "trk_ch_0.dat", "trk_ch_1.dat"] {
            std::fs::copy(fixtures().join("order2").join(f), to.join(f)).unwrap();
        }
        DirCopy(to)
    }
}

impl Drop for DirCopy {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Found by fuzzing: a dump named beyond any channel number was
/// silently skipped, and copies of one dump were taken as as many channels.
#[test]
fn odd_dump_names_and_copies_are_errors() {
    let tc = GnssSdrConf::read(fixtures().join("order2/gnss-sdr.conf")).unwrap().tracking().unwrap();
    let settings = ImportSettings::new(tc.fs_hz.unwrap(), tc);
    let dir = DirCopy::new("big-channel");
    std::fs::copy(dir.0.join("trk_ch_0.dat"), dir.0.join("trk_ch_4294967296.dat")).unwrap();
    let e = import_dir(&dir.0, &settings).unwrap_err().to_string();
    assert!(e.contains("trk_ch_4294967296.dat") && e.contains("(4294967296) is beyond 4294967295"), "{e}");

    let dir = DirCopy::new("copies");
    for ch in [2, 3] {
        std::fs::copy(dir.0.join("trk_ch_0.dat"), dir.0.join(format!("trk_ch_{ch}.dat"))).unwrap();
    }
    let e = import_dir(&dir.0, &settings).unwrap_err().to_string();
    let prn = read_dump(dir.0.join("trk_ch_0.dat"), None).unwrap().records[0].prn;
    assert!(e.contains("trk_ch_0.dat and ") && e.contains("trk_ch_2.dat both track PRN"), "{e}");
    assert!(e.contains(&format!("PRN {prn} at sample")), "{e}");
    // The two real channels (different satellites at the same time) are not copies.
    let dir = DirCopy::new("real");
    assert!(import_dir(&dir.0, &settings).is_ok());
}
