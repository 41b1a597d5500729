use super::*;
use gsens_io::{TrackingRow, TrackingWriter, read_tracking};

const T: f64 = 0.025;

fn row(t_s: f64, channel: u32, cn0_dbhz: f64, elev_deg: Option<f64>, phase_err_rad: f64) -> TrackingRow {
    TrackingRow { t_s, channel, prn: channel + 100, cn0_dbhz, elev_deg, phase_err_rad }
}

fn log_from(rows: &[TrackingRow]) -> TrackingLog {
    let mut w = TrackingWriter::new(Vec::new()).unwrap();
    for r in rows {
        w.write_row(r).unwrap();
    }
    read_tracking(w.finish().unwrap().as_slice(), "tracking.csv").unwrap()
}

/// Epoch `k` of a 40 Hz log starting at 100 s (awkward binary fractions).
fn tk(k: usize) -> f64 {
    100.0 + k as f64 * T
}

/// A closed-form linear specific force [m/s²].
fn lin(t: f64) -> [f64; 3] {
    [0.5 + 2.0 * t, -1.0 - 0.3 * t, 9.81 + 0.01 * t]
}

/// IMU sampled every `dt_s` over [t0, t1] (true time), stamped with `offset_s`, values `lin`.
fn imu_lin(t0: f64, t1: f64, dt_s: f64, offset_s: f64) -> ImuSeries {
    let n = ((t1 - t0) / dt_s).round() as usize;
    let mut s = ImuSeries::default();
    for j in 0..=n {
        let t_true = t0 + j as f64 * dt_s + 0.2 * dt_s * (j as f64).sin();
        s.t_s.push(t_true + offset_s);
        s.accel_mps2.push(lin(t_true));
    }
    s
}

/// A log with `n` epochs of one channel (phase = k), on the grid `tk`.
fn one_channel(n: usize) -> TrackingLog {
    log_from(&(0..n).map(|k| row(tk(k), 1, 45.0, Some(30.0), k as f64)).collect::<Vec<_>>())
}

fn wide_imu() -> ImuSeries {
    imu_lin(0.0, 1000.0, 0.05, 0.0)
}

fn prep(log: &TrackingLog, imu: &ImuSeries, cfg: &SelectionConfig) -> Result<PreparedSession, SessionError> {
    prepare_session(log, imu, "imu.csv", cfg, 0.0)
}

/// The selection without screening: most tests here use unphysical phases
/// (phase = epoch number, or channel number, far beyond a discriminator's range).
fn base() -> SelectionConfig {
    SelectionConfig { screening: crate::screening::ScreeningConfig::off(), ..SelectionConfig::default() }
}

fn msg(e: SessionError) -> String {
    e.to_string()
}

#[test]
fn imu_at_the_same_instants_is_used_bit_exactly() {
    let n = 400;
    let log = one_channel(n);
    let mut x: u64 = 12345;
    let mut rnd = || {
        x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (x >> 11) as f64 / (1u64 << 53) as f64 * 20.0 - 10.0
    };
    // The IMU has the same instants, plus one more at each end.
    let t_s: Vec<f64> = std::iter::once(tk(0) - T).chain((0..n).map(tk)).chain(std::iter::once(tk(n) + 1e-3)).collect();
    let accel_mps2: Vec<[f64; 3]> = t_s.iter().map(|_| [rnd(), rnd(), rnd()]).collect();
    let imu = ImuSeries { t_s, accel_mps2 };
    let s = prep(&log, &imu, &base()).unwrap();
    assert_eq!(s.len(), n);
    for k in 0..n {
        assert_eq!(s.t_s[k].to_bits(), tk(k).to_bits());
        for i in 0..3 {
            assert_eq!(s.accel_mps2[k][i].to_bits(), imu.accel_mps2[k + 1][i].to_bits(), "epoch {k} axis {i}");
        }
        assert_eq!(s.phase_err_rad[k], Some(k as f64));
    }
    assert!((s.log_interval_s - T).abs() < 1e-12);
}

#[test]
fn interpolation_matches_a_linear_function_with_and_without_time_offset() {
    let n = 200;
    let log = one_channel(n);
    for offset_s in [0.0, 0.0137, -0.4] {
        // 100 Hz jittered IMU covering the whole tracking span.
        let imu = imu_lin(tk(0) - 0.1, tk(n) + 0.1, 0.01, offset_s);
        let s = prepare_session(&log, &imu, "imu.csv", &base(), offset_s).unwrap();
        assert_eq!(s.len(), n);
        assert_eq!(s.imu_time_offset_s, offset_s);
        for k in 0..n {
            for (got, want) in s.accel_mps2[k].iter().zip(lin(s.t_s[k])) {
                assert!(
                    (got - want).abs() < 1e-12 * want.abs().max(1.0),
                    "offset {offset_s}, epoch {k}: {got} vs {want}"
                );
            }
        }
    }
}

#[test]
fn epochs_outside_the_imu_span_are_dropped_from_the_ends() {
    let log = one_channel(400); // 100 .. 109.975 s
    for offset_s in [0.0, 0.5] {
        // True span [102, 103] s.
        let imu = imu_lin(102.0, 103.0, 0.01, offset_s);
        let (first, last) = (imu.t_s[0] - offset_s, imu.t_s[imu.len() - 1] - offset_s);
        let s = prepare_session(&log, &imu, "imu.csv", &base(), offset_s).unwrap();
        assert!(s.t_s[0] >= first && s.t_s[0] - T < first, "{} vs {first}", s.t_s[0]);
        let t_end = *s.t_s.last().unwrap();
        assert!(t_end <= last && t_end + T > last, "{t_end} vs {last}");
        assert_eq!(s.phase_err_rad[0], Some(((s.t_s[0] - 100.0) / T).round()));
        assert_eq!(s.channels[0].epochs, s.len());
    }
}

#[test]
fn logs_not_overlapping_in_time() {
    let log = one_channel(400); // 100 .. 109.975 s
    let imu = ImuSeries { t_s: (0..=20).map(|j| 200.0 + 0.5 * j as f64).collect(), accel_mps2: vec![[0.0; 3]; 21] };
    let m = msg(prep(&log, &imu, &base()).unwrap_err());
    assert!(m.contains("imu.csv and tracking.csv do not overlap in time"), "{m}");
    assert!(m.contains("the IMU covers [200, 210] s"), "{m}");
    assert!(m.contains("tracking epochs cover [100, 109.975] s"), "{m}");
    // The offset moves the IMU span: stamps 200..210 are true time 100..110 with offset 100.
    prepare_session(&log, &imu, "imu.csv", &base(), 100.0).unwrap();
    let m = msg(prepare_session(&log, &imu, "imu.csv", &base(), -5.0).unwrap_err());
    assert!(m.contains("[205, 215] s") && m.contains("imu_time_offset_s = -5 s"), "{m}");
}

#[test]
fn no_overlap_names_the_likely_clock_mix_up() {
    // 10 s of tracking in GPS seconds of the week (Thursday noon).
    let log = log_from(&(0..400).map(|k| row(388_800.0 + k as f64 * T, 1, 45.0, None, 0.0)).collect::<Vec<_>>());
    let imu_at = |t0: f64, scale: f64| ImuSeries {
        t_s: (0..=40).map(|j| (t0 + 0.25 * j as f64) * scale).collect(),
        accel_mps2: vec![[0.0, 0.0, 9.81]; 41],
    };
    // The IMU in Unix time (2024-02-08 12:00:00 UTC).
    let m = msg(prep(&log, &imu_at(1_707_393_600.0, 1.0), &base()).unwrap_err());
    assert!(m.contains("the IMU covers [1707393600, 1707393610] s"), "{m}");
    assert!(m.contains("tracking epochs cover [388800, 388809.975] s"), "{m}");
    assert!(m.contains("the IMU's t_s look like Unix time"), "{m}");
    assert!(m.contains("the tracking's like GPS seconds of the week or seconds since power-on"), "{m}");
    assert!(m.contains("one clock, in seconds"), "{m}");
    // The IMU in milliseconds of the same clock.
    let m = msg(prep(&log, &imu_at(388_800.0, 1000.0), &base()).unwrap_err());
    assert!(m.contains("the IMU's t_s are in milliseconds (its span is 1003× the tracking's)"), "{m}");
    // The IMU in Unix time, the tracking in GPS time (18 leap seconds in 2024).
    let gps = 1_707_393_600.0 - 315_964_800.0 + 18.0;
    let log = log_from(&(0..400).map(|k| row(gps + k as f64 * T, 1, 45.0, None, 0.0)).collect::<Vec<_>>());
    let m = msg(prep(&log, &imu_at(1_707_393_600.0, 1.0), &base()).unwrap_err());
    assert!(m.contains("one log is in Unix time and the other in GPS time: they are 315964782 s apart"), "{m}");
    // One base, different sessions.
    let hint = overlap_hint((200.0, 210.0), (100.0, 110.0));
    assert!(hint.starts_with("Both look like GPS seconds of the week or seconds since power-on"), "{hint}");
    assert!(hint.contains("the IMU starts 100.000 s after the tracking"), "{hint}");
}

#[test]
fn gaps_become_epochs_without_phase() {
    let rows: Vec<TrackingRow> =
        (0..40).filter(|k| !(11..15).contains(k)).map(|k| row(tk(k), 1, 45.0, None, k as f64)).collect();
    let s = prep(&log_from(&rows), &wide_imu(), &base()).unwrap();
    assert_eq!(s.len(), 40);
    assert_eq!(s.epochs_with_phase(), 36);
    for k in 0..40 {
        if (11..15).contains(&k) {
            assert_eq!(s.phase_err_rad[k], None);
            assert!((s.t_s[k] - tk(k)).abs() < 1e-9);
        } else {
            assert_eq!(s.phase_err_rad[k], Some(k as f64));
            assert_eq!(s.t_s[k], tk(k));
        }
    }
}

#[test]
fn jittered_time_stamps_snap_to_the_grid() {
    let rows: Vec<TrackingRow> =
        (0..100).map(|k| row(tk(k) + 0.002 * (k as f64 * 1.7).sin(), 1, 45.0, None, k as f64)).collect();
    let s = prep(&log_from(&rows), &wide_imu(), &base()).unwrap();
    assert_eq!(s.len(), 100);
    assert!((s.log_interval_s - T).abs() < 0.002);
    for (k, r) in rows.iter().enumerate() {
        assert_eq!(s.t_s[k], r.t_s);
        assert_eq!(s.phase_err_rad[k], Some(k as f64));
    }
}

#[test]
fn long_log_with_jitter_and_an_off_nominal_interval_does_not_drift_off_the_grid() {
    // 100 000 epochs, interval 2e-4 off 25 ms, ±5% jitter, gaps of 3 and 100 epochs:
    // with t0 + k·median the stamps would leave the 10% tolerance after ~500 epochs
    // of accumulated median error; the fitted grid does not.
    let true_t = 0.025 * (1.0 + 2e-4);
    let n = 100_000;
    let gap = |k: usize| (5000..5003).contains(&k) || (60_000..60_100).contains(&k);
    let rows: Vec<TrackingRow> = (0..n)
        .filter(|&k| !gap(k))
        .map(|k| row(10.0 + k as f64 * true_t + 0.05 * true_t * (k as f64 * 0.77).sin(), 1, 45.0, None, k as f64))
        .collect();
    let imu = imu_lin(0.0, 3000.0, 0.5, 0.0);
    let s = prep(&log_from(&rows), &imu, &base()).unwrap();
    assert_eq!(s.len(), n);
    assert!((s.log_interval_s / true_t - 1.0).abs() < 1e-7, "{}", s.log_interval_s);
    for k in 0..n {
        assert_eq!(s.phase_err_rad[k], if gap(k) { None } else { Some(k as f64) });
    }
    assert!((s.t_s[60_050] - (10.0 + 60_050.0 * true_t)).abs() < 1e-6);
}

#[test]
fn time_stamp_off_the_grid() {
    let mut rows: Vec<TrackingRow> = (0..20).map(|k| row(tk(k), 1, 45.0, None, 0.0)).collect();
    rows[7].t_s += 0.3 * T; // line 9 (header + 7 rows before it)
    let m = msg(prep(&log_from(&rows), &wide_imu(), &base()).unwrap_err());
    assert!(m.starts_with("tracking.csv: line 9, column 1 (`t_s`)"), "{m}");
    assert!(m.contains("off the epoch grid") && m.contains("tolerance 10% of T"), "{m}");
}

#[test]
fn two_time_stamps_on_one_grid_epoch() {
    let mut rows: Vec<TrackingRow> = (0..20).map(|k| row(tk(k), 1, 45.0, None, 0.0)).collect();
    rows[10].t_s = tk(10) - 0.09 * T;
    rows[11].t_s = tk(10) + 0.09 * T;
    let m = msg(prep(&log_from(&rows), &wide_imu(), &base()).unwrap_err());
    assert!(m.starts_with("tracking.csv: line 13, column 1 (`t_s`)"), "{m}");
    assert!(m.contains("same epoch of the grid") && m.contains("on line 12"), "{m}");
}

#[test]
fn a_single_epoch_is_not_enough() {
    let log = log_from(&[row(1.0, 1, 45.0, None, 0.0), row(1.0, 2, 45.0, None, 0.0)]);
    let m = msg(prep(&log, &wide_imu(), &base()).unwrap_err());
    assert!(m.starts_with("tracking.csv: only 1 distinct time stamp"), "{m}");
}

/// Common signal of the averaging tests \[rad\].
fn common(k: usize) -> f64 {
    0.2 * (0.3 * k as f64).sin() + 0.05
}

/// Four channels carrying `common` plus constant offsets summing to zero; channel 2 is
/// missing at epochs 10..30, channel 0 at 50..60, all of them at 70..73.
fn offsets_log(cn0: impl Fn(u32, usize) -> f64) -> (TrackingLog, [f64; 4]) {
    let offsets = [0.3, -0.1, -0.5, 0.3];
    let mut rows = Vec::new();
    for k in 0..100 {
        for ch in 0..4u32 {
            let missing =
                (ch == 2 && (10..30).contains(&k)) || (ch == 0 && (50..60).contains(&k)) || (70..73).contains(&k);
            if !missing {
                rows.push(row(tk(k), ch, cn0(ch, k), Some(45.0), common(k) + offsets[ch as usize]));
            }
        }
    }
    (log_from(&rows), offsets)
}

#[test]
fn average_is_unbiased_when_a_channel_is_missing() {
    let varying = |ch: u32, k: usize| 38.0 + 2.0 * ch as f64 + (0.1 * k as f64 + ch as f64).sin();
    for weighting in [Weighting::Equal, Weighting::Cn0] {
        let (log, offsets) = offsets_log(varying);
        let cfg = SelectionConfig { weighting, ..SelectionConfig::default() };
        let s = prep(&log, &wide_imu(), &cfg).unwrap();
        assert_eq!(s.len(), 100);
        for k in 0..100 {
            match s.phase_err_rad[k] {
                None => assert!((70..73).contains(&k)),
                Some(p) => assert!((p - common(k)).abs() < 1e-12, "{weighting:?} epoch {k}: {p} vs {}", common(k)),
            }
        }
        for c in &s.channels {
            let off = c.phase_offset_rad.unwrap();
            assert!((off - offsets[c.channel as usize]).abs() < 1e-12, "{c:?}");
        }
    }
}

#[test]
fn plain_average_renormalizes_weights_over_present_channels() {
    // Without offsets, the renormalized mean is exact at every epoch (dividing by
    // the number of selected channels would give 3/4 of the signal where one is missing).
    let (log, _) = {
        let mut rows = Vec::new();
        for k in 0..60 {
            for ch in 0..4u32 {
                if !(ch == 1 && (20..40).contains(&k)) {
                    rows.push(row(tk(k), ch, 40.0 + ch as f64, None, common(k)));
                }
            }
        }
        (log_from(&rows), ())
    };
    for weighting in [Weighting::Equal, Weighting::Cn0] {
        let cfg = SelectionConfig { weighting, remove_channel_offsets: false, ..base() };
        let s = prep(&log, &wide_imu(), &cfg).unwrap();
        for k in 0..60 {
            let p = s.phase_err_rad[k].unwrap();
            assert!((p - common(k)).abs() < 1e-15, "{weighting:?} epoch {k}");
        }
        assert!(s.channels.iter().all(|c| c.phase_offset_rad.is_none()));
    }
    // With offsets and no offset removal, a missing channel shifts the mean by
    // −c_j/(N−1): the reason offset removal is the default.
    let (log, offsets) = offsets_log(|_, _| 45.0);
    let cfg = SelectionConfig { remove_channel_offsets: false, ..base() };
    let s = prep(&log, &wide_imu(), &cfg).unwrap();
    assert!((s.phase_err_rad[0].unwrap() - common(0)).abs() < 1e-15);
    assert!((s.phase_err_rad[15].unwrap() - (common(15) - offsets[2] / 3.0)).abs() < 1e-12);
}

#[test]
fn channels_without_common_epochs_get_offsets_per_group() {
    // Channel 1 only in the first half, channel 2 only in the second: offsets
    // are not identifiable between them, each group sums to zero (no NaN, no panic).
    let mut rows = Vec::new();
    for k in 0..40 {
        let ch = if k < 20 { 1 } else { 2 };
        rows.push(row(tk(k), ch, 45.0, None, common(k) + 0.1 * ch as f64));
    }
    let s = prep(&log_from(&rows), &wide_imu(), &base()).unwrap();
    for k in 0..40 {
        let want = common(k) + if k < 20 { 0.1 } else { 0.2 };
        assert!((s.phase_err_rad[k].unwrap() - want).abs() < 1e-12);
    }
    assert!(s.channels.iter().all(|c| c.phase_offset_rad == Some(0.0)));
}

#[test]
fn cn0_weights_are_the_cn0_ratio() {
    let mut rows = Vec::new();
    for k in 0..10 {
        rows.push(row(tk(k), 1, 40.0, None, 1.0));
        rows.push(row(tk(k), 2, 43.0, None, 0.0));
    }
    let log = log_from(&rows);
    let cfg = SelectionConfig { weighting: Weighting::Cn0, remove_channel_offsets: false, ..base() };
    let s = prep(&log, &wide_imu(), &cfg).unwrap();
    let (w1, w2) = (gsens_core::units::cn0_dbhz_to_ratio_hz(40.0), gsens_core::units::cn0_dbhz_to_ratio_hz(43.0));
    let want = w1 / (w1 + w2);
    assert!((want - 0.3339).abs() < 1e-3); // 3 dB ≈ twice the weight
    for p in &s.phase_err_rad {
        assert!((p.unwrap() - want).abs() < 1e-15);
    }
    let cfg = SelectionConfig { remove_channel_offsets: false, ..base() };
    let s = prep(&log, &wide_imu(), &cfg).unwrap();
    assert!(s.phase_err_rad.iter().all(|p| *p == Some(0.5)));
}

/// Six channels, C/N0 = 30 + 2·channel dB-Hz, phase = channel.
fn six_channels(elev: impl Fn(u32, usize) -> Option<f64>, cn0: impl Fn(u32, usize) -> f64) -> TrackingLog {
    let mut rows = Vec::new();
    for k in 0..50 {
        for ch in 0..6u32 {
            rows.push(row(tk(k), ch, cn0(ch, k), elev(ch, k), ch as f64));
        }
    }
    log_from(&rows)
}

fn used(s: &PreparedSession) -> Vec<u32> {
    s.channels.iter().filter(|c| c.used).map(|c| c.channel).collect()
}

#[test]
fn selection_keeps_the_n_strongest_channels() {
    let log = six_channels(|_, _| Some(40.0), |ch, _| 30.0 + 2.0 * ch as f64);
    let cfg = SelectionConfig { remove_channel_offsets: false, ..base() };
    let s = prep(&log, &wide_imu(), &cfg).unwrap();
    assert_eq!(used(&s), vec![2, 3, 4, 5]);
    assert_eq!(s.phase_err_rad[0], Some(3.5));
    let c0 = &s.channels[0];
    assert_eq!((c0.channel, c0.prn, c0.mean_cn0_dbhz, c0.epochs, c0.used), (0, 100, 30.0, 50, false));
    assert!(c0.reason.contains("not among the 4 strongest") && c0.reason.contains("rank 6"), "{}", c0.reason);
    assert_eq!(s.channels[5].reason, "used");
    assert_eq!(s.selection, cfg);

    let cfg = SelectionConfig { max_channels: Some(2), remove_channel_offsets: false, ..base() };
    assert_eq!(used(&prep(&log, &wide_imu(), &cfg).unwrap()), vec![4, 5]);
    let cfg = SelectionConfig { max_channels: None, remove_channel_offsets: false, ..base() };
    let s = prep(&log, &wide_imu(), &cfg).unwrap();
    assert_eq!(used(&s), vec![0, 1, 2, 3, 4, 5]);
    assert_eq!(s.phase_err_rad[0], Some(2.5));
}

#[test]
fn selection_by_cn0_threshold_drops_rows() {
    // Channel 1 alternates 33 / 37 dB-Hz: half its rows pass a 35 dB-Hz threshold.
    let cn0 = |ch: u32, k: usize| if ch == 1 { if k & 1 == 0 { 33.0 } else { 37.0 } } else { 30.0 + 2.0 * ch as f64 };
    let log = six_channels(|_, _| None, cn0);
    let cfg = SelectionConfig { max_channels: None, min_cn0_dbhz: Some(35.0), remove_channel_offsets: false, ..base() };
    let s = prep(&log, &wide_imu(), &cfg).unwrap();
    assert_eq!(used(&s), vec![1, 3, 4, 5]);
    let c0 = &s.channels[0];
    assert!(c0.reason.contains("below the C/N0 threshold of 35 dB-Hz"), "{}", c0.reason);
    assert_eq!(s.channels[1].epochs, 25);
    assert_eq!(s.channels[1].mean_cn0_dbhz, 37.0);
    assert_eq!(s.phase_err_rad[0], Some(4.0)); // channels 3, 4, 5
    assert_eq!(s.phase_err_rad[1], Some(3.25)); // channels 1, 3, 4, 5
}

#[test]
fn selection_by_elevation_mask() {
    // Channel 0 low, channel 1 unknown elevation, channel 2 rising through the mask.
    let elev = |ch: u32, k: usize| match ch {
        0 => Some(5.0),
        1 => None,
        2 => Some(k as f64 * 0.5),
        _ => Some(60.0),
    };
    let log = six_channels(elev, |ch, _| 30.0 + 2.0 * ch as f64);
    let cfg =
        SelectionConfig { max_channels: None, elevation_mask_deg: Some(10.0), remove_channel_offsets: false, ..base() };
    let s = prep(&log, &wide_imu(), &cfg).unwrap();
    assert_eq!(used(&s), vec![1, 2, 3, 4, 5]);
    assert!(s.channels[0].reason.contains("below the elevation mask of 10 deg"), "{}", s.channels[0].reason);
    assert_eq!(s.channels[1].epochs, 50);
    assert_eq!(s.channels[2].epochs, 30); // k = 20..49
    assert_eq!(s.phase_err_rad[0], Some(13.0 / 4.0));
    assert_eq!(s.phase_err_rad[20], Some(3.0));
}

#[test]
fn no_channel_passing_the_selection() {
    let log = six_channels(|_, _| Some(30.0), |ch, _| 30.0 + 2.0 * ch as f64);
    let cfg = SelectionConfig { elevation_mask_deg: Some(50.0), ..base() };
    let m = msg(prep(&log, &wide_imu(), &cfg).unwrap_err());
    assert!(m.starts_with("tracking.csv: no channel passes the selection"), "{m}");
    assert!(
        m.contains("channel 0 (PRN 100): all 50 rows in the usable span below the elevation mask of 50 deg"),
        "{m}"
    );

    let cfg = SelectionConfig { min_cn0_dbhz: Some(60.0), ..base() };
    let m = msg(prep(&log, &wide_imu(), &cfg).unwrap_err());
    assert!(m.contains("no channel passes the selection") && m.contains("below the C/N0 threshold of 60 dB-Hz"), "{m}");

    // Channel 1 only before the IMU span, channel 2 only after it, a gap in between.
    let mut rows: Vec<TrackingRow> = (0..10).map(|k| row(tk(k), 1, 45.0, None, 0.0)).collect();
    rows.extend((30..40).map(|k| row(tk(k), 2, 45.0, None, 0.0)));
    let imu = imu_lin(tk(15), tk(25), 0.01, 0.0);
    let m = msg(prep(&log_from(&rows), &imu, &base()).unwrap_err());
    assert!(m.contains("channel 1 (PRN 101): no rows in the usable span"), "{m}");
    assert!(m.contains("channel 2 (PRN 102): no rows in the usable span"), "{m}");
}

#[test]
fn invalid_settings() {
    let log = one_channel(10);
    let cfg = SelectionConfig { max_channels: Some(0), ..base() };
    let m = msg(prep(&log, &wide_imu(), &cfg).unwrap_err());
    assert!(m.starts_with("tracking.csv: invalid selection settings: max_channels is 0"), "{m}");
    let cfg = SelectionConfig { min_cn0_dbhz: Some(f64::NAN), ..base() };
    assert!(msg(prep(&log, &wide_imu(), &cfg).unwrap_err()).contains("min_cn0_dbhz = NaN"));
    let m = msg(prepare_session(&log, &wide_imu(), "imu.csv", &base(), f64::NAN).unwrap_err());
    assert!(m.contains("imu_time_offset_s"), "{m}");
    let bad = ImuSeries { t_s: vec![1.0, 0.0], accel_mps2: vec![[0.0; 3]; 2] };
    let e = prep(&log, &bad, &base()).unwrap_err();
    assert!(matches!(e, SessionError::Format(gsens_io::FormatError::InvalidImuSeries { .. })), "{e:?}");
    let m = msg(e);
    assert!(m.starts_with("imu.csv: invalid IMU series"), "{m}");
}

#[test]
fn reading_errors_pass_through_unchanged() {
    let dir = std::env::temp_dir().join(format!("gsens-session-missing-{}", std::process::id()));
    let (trk, imu) = (dir.join("tracking.csv"), dir.join("imu.csv"));
    let e = prepare_session_files(&trk, &imu, &base(), 0.0).unwrap_err();
    let direct = gsens_io::read_tracking_file(&trk).unwrap_err();
    assert!(matches!(e, SessionError::Format(gsens_io::FormatError::Io { .. })), "{e:?}");
    assert_eq!(e.to_string(), direct.to_string());
    assert!(e.to_string().starts_with(&format!("{}: cannot read", trk.display())), "{e}");
}

#[test]
fn reassigned_channel_is_two_tracks() {
    let mut rows: Vec<TrackingRow> = (0..20).map(|k| row(tk(k), 1, 45.0, None, 1.0)).collect();
    for r in rows.iter_mut().skip(10) {
        r.prn = 7;
        r.cn0_dbhz = 40.0;
    }
    let cfg = SelectionConfig { remove_channel_offsets: false, ..base() };
    let s = prep(&log_from(&rows), &wide_imu(), &cfg).unwrap();
    let ids: Vec<(u32, u32, usize, bool)> = s.channels.iter().map(|c| (c.channel, c.prn, c.epochs, c.used)).collect();
    assert_eq!(ids, vec![(1, 7, 10, true), (1, 101, 10, true)]);
    assert_eq!(s.epochs_with_phase(), 20);
}

#[test]
fn selection_config_serde() {
    let cfg: SelectionConfig = serde_json::from_str(r#"{"weighting":"cn0","min_cn0_dbhz":35}"#).unwrap();
    assert_eq!(cfg.weighting, Weighting::Cn0);
    assert_eq!(cfg.max_channels, Some(4));
    assert_eq!(cfg.min_cn0_dbhz, Some(35.0));
    let text = serde_json::to_string(&SelectionConfig::default()).unwrap();
    assert!(text.contains(r#""weighting":"equal""#) && text.contains(r#""max_channels":4"#), "{text}");
}

#[test]
fn reinterpolating_the_imu_matches_a_fresh_preparation_inside_the_span() {
    // IMU at 100 Hz over 0…10 s, a linear-in-time specific force; tracking at 40 Hz.
    let imu = ImuSeries {
        t_s: (0..=1000).map(|k| k as f64 * 0.01).collect(),
        accel_mps2: (0..=1000).map(|k| [k as f64 * 0.01, 1.0 - k as f64 * 0.002, 9.8]).collect(),
    };
    let mut text = String::from("t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad\n");
    for k in 0..400 {
        text.push_str(&format!("{},1,5,45,,{}\n", k as f64 * 0.025, (k as f64 * 0.3).sin() * 0.01));
    }
    let log = read_tracking(text.as_bytes(), "t.csv").unwrap();
    let sel = SelectionConfig::default();
    let mut moved = prepare_session(&log, &imu, "imu.csv", &sel, 0.0).unwrap();
    reinterpolate_imu(&mut moved, &imu, 0.037);
    let fresh = prepare_session(&log, &imu, "imu.csv", &sel, 0.037).unwrap();
    for (k, t) in fresh.t_s.iter().enumerate() {
        let j = moved.t_s.iter().position(|x| x == t).unwrap();
        for i in 0..3 {
            assert!((moved.accel_mps2[j][i] - fresh.accel_mps2[k][i]).abs() < 1e-12);
        }
        assert_eq!(moved.phase_err_rad[j].is_some(), fresh.phase_err_rad[k].is_some());
    }
    // The epoch that reads past the IMU's end has no phase.
    assert!(moved.phase_err_rad.last().unwrap().is_none());
    assert_eq!(moved.imu_time_offset_s, 0.037);
}

fn mixed_log(rows: &[(TrackingRow, gsens_io::Carrier)]) -> TrackingLog {
    let csv = gsens_io::write_tracking_csv_on(Vec::new(), rows).unwrap();
    read_tracking(csv.as_slice(), "tracking.csv").unwrap()
}

fn on(label: &str) -> gsens_io::Carrier {
    gsens_io::Carrier::of(gsens_io::Signal::from_label(label).unwrap())
}

#[test]
fn phases_are_scaled_to_l1_and_weighted_by_the_inverse_scaled_variance() {
    // One common L1-scale signal s(k): a channel on f_c logs (f_c/f_L1)·s plus its own term.
    let l1 = gsens_core::units::GPS_L1_HZ;
    let labels = ["L1CA", "L5Q", "G1:-7", "B1I"];
    let own = [0.01, -0.02, 0.03, 0.005];
    let mut rows = Vec::new();
    for k in 0..20 {
        for (c, label) in labels.iter().enumerate() {
            let f = on(label).carrier_hz;
            rows.push((row(tk(k), c as u32, 40.0 + c as f64, None, f / l1 * common(k) + own[c]), on(label)));
        }
    }
    let log = mixed_log(&rows);
    for weighting in [Weighting::Equal, Weighting::Cn0] {
        let cfg = SelectionConfig { weighting, remove_channel_offsets: false, ..base() };
        let s = prep(&log, &wide_imu(), &cfg).unwrap();
        // Closed form: Σ w_c·(s + own_c·f_L1/f_c) / Σ w_c, w_c = (C/N0 or 1)·(f_c/f_L1)².
        let (mut sw, mut swx) = (0.0, 0.0);
        for (c, label) in labels.iter().enumerate() {
            let r = on(label).carrier_hz / l1;
            let base = if weighting == Weighting::Cn0 {
                gsens_core::units::cn0_dbhz_to_ratio_hz(40.0 + c as f64)
            } else {
                1.0
            };
            sw += base * r * r;
            swx += base * r * r * own[c] / r;
        }
        for (k, p) in s.phase_err_rad.iter().enumerate() {
            assert!((p.unwrap() - (common(k) + swx / sw)).abs() < 1e-12, "{weighting:?} epoch {k}");
        }
        let got: Vec<(&str, usize)> = s.signals.iter().map(|g| (g.signal.as_str(), g.tracks_used)).collect();
        assert_eq!(got, [("G1:-7", 1), ("L1CA", 1), ("B1I", 1), ("L5Q", 1)]);
        assert_eq!(s.channels[1].signal, "L5Q");
        assert_eq!(s.channels[1].carrier_hz, 1_176.45e6);
    }
}

#[test]
fn linear_range_test_uses_each_channels_own_carrier() {
    use gsens_io::Carrier;
    // Four quiet L1 channels and one with an excursion of its own, `logged` rad as logged.
    let flagged = |carrier: Carrier, logged: f64| {
        let mut rows = Vec::new();
        for k in 0..2400 {
            let wiggle = 1e-3 * ((k * 7919) % 13) as f64;
            for c in 0..4u32 {
                rows.push((row(tk(k), c, 45.0, None, wiggle + 1e-3 * c as f64), Carrier::GPS_L1));
            }
            let p = if (1000..1040).contains(&k) { logged } else { wiggle };
            rows.push((row(tk(k), 9, 45.0, None, p), carrier));
        }
        let s = prep(&mixed_log(&rows), &wide_imu(), &SelectionConfig::default()).unwrap();
        s.channels.iter().find(|c| c.channel == 9).unwrap().screening.rows_phase_range
    };
    // 0.7 rad is within π/4 as logged, though 0.7·1575.42/1176.45 = 0.94 rad on L1's scale.
    assert_eq!(flagged(on("L5I"), 0.7), 0);
    assert_eq!(flagged(Carrier::GPS_L1, 0.7), 0);
    // 0.85 rad as logged is beyond it on any carrier (π/4 plus the noise
    // margin, here 4.6 times the σ floor of 0.005 rad: 0.808 rad).
    assert!(flagged(on("L5I"), 0.85) >= 40);
    assert!(flagged(Carrier::GPS_L1, 0.85) >= 40);
}

/// A log given to the session (freed track by track as its rows are taken,
/// the tracks in parallel) gives the session a lent one gives: tracks
/// joining, leaving, below the masks and re-assigned, with the screening on.
#[test]
fn given_and_lent_logs_give_the_same_session() {
    let mut rows = Vec::new();
    for k in 0..4000 {
        for ch in 0..6u32 {
            // Channel 2 leaves for a while, channel 4 is below the C/N0 mask
            // at first, channel 5 joins late.
            if (ch == 2 && (1500..2100).contains(&k)) || (ch == 5 && k < 700) {
                continue;
            }
            let cn0 = if ch == 4 && k < 1000 { 20.0 } else { 40.0 + ch as f64 };
            let phase = 0.05 * (k as f64 * 0.21).sin() + 0.003 * ((k * 7 + ch as usize * 13) % 11) as f64;
            rows.push(row(tk(k), ch, cn0, Some(30.0 + ch as f64), phase));
        }
    }
    let log = log_from(&rows);
    let cfg = SelectionConfig { min_cn0_dbhz: Some(30.0), ..SelectionConfig::default() };
    let imu = wide_imu();
    let lent = prepare_session_from(Cow::Borrowed(&log), &imu, "imu.csv", &cfg, 0.0).unwrap();
    let given = prepare_session_from(Cow::Owned(log.clone()), &imu, "imu.csv", &cfg, 0.0).unwrap();
    assert_eq!(format!("{given:?}"), format!("{lent:?}"));
    assert_eq!(lent.channels.iter().filter(|c| c.epochs > 0).count(), 6);
}

/// The session is the same on one thread and on several, from a log lent
/// or given (converted in place): the epochs go in fixed blocks and spans
/// (several here, one starting mid-gap), the tracks one by one, whatever
/// the pool.
#[test]
fn the_session_is_the_same_on_any_number_of_threads() {
    let mut rows = Vec::new();
    for k in 0..20_000 {
        for ch in 0..5u32 {
            if (ch == 1 && (8000..8500).contains(&k)) || (ch == 4 && k < 9000) {
                continue;
            }
            let phase = 0.05 * (k as f64 * 0.21).sin() + 0.003 * ((k * 7 + ch as usize * 13) % 11) as f64;
            rows.push(row(tk(k), ch, 40.0 + ch as f64, Some(30.0), phase));
        }
    }
    let log = log_from(&rows);
    let (imu, cfg) = (wide_imu(), SelectionConfig::default());
    let on = |threads: usize, given: bool| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        let tracking = if given { Cow::Owned(log.clone()) } else { Cow::Borrowed(&log) };
        format!("{:?}", pool.install(|| prepare_session_from(tracking, &imu, "imu.csv", &cfg, 0.0).unwrap()))
    };
    let one = on(1, false);
    for threads in [2, 4, 5] {
        assert_eq!(on(threads, false), one, "{threads} threads");
    }
    for threads in [1, 4] {
        assert_eq!(on(threads, true), one, "{threads} threads, the log given");
    }
}

/// Standard normal deviates from a splitmix64 stream (Box–Muller).
fn gaussians(seed: u64) -> impl FnMut() -> f64 {
    let mut s = seed;
    let mut uniform = move || {
        s = s.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = s;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    };
    move || (-2.0 * (1.0 - uniform()).ln()).sqrt() * (std::f64::consts::TAU * uniform()).cos()
}

/// Six channels on a common signal, each with its own white noise
/// (`sigma_rad[ch]`), C/N0 from `cn0(ch)`.
fn noisy_log(sigma_rad: [f64; 6], cn0: impl Fn(u32) -> f64) -> TrackingLog {
    let mut noise = gaussians(3);
    let mut rows = Vec::new();
    for k in 0..2000 {
        for ch in 0..6u32 {
            rows.push(row(tk(k), ch, cn0(ch), None, common(k) + sigma_rad[ch as usize] * noise()));
        }
    }
    log_from(&rows)
}

fn used_channels(s: &PreparedSession) -> Vec<u32> {
    s.channels.iter().filter(|c| c.used).map(|c| c.channel).collect()
}

/// A constant C/N0 column ranks nothing: the four tracks with the lowest
/// measured noise are used, and the session says so. A spread of C/N0 below
/// the logging's resolution is no ranking either; above it, C/N0 ranks.
#[test]
fn without_c_n0_differences_the_least_noisy_tracks_are_used() {
    let sigma_rad = [0.03, 0.3, 0.04, 0.25, 0.05, 0.06];
    let imu = wide_imu();
    let cfg = SelectionConfig::default();
    let s = prep(&noisy_log(sigma_rad, |_| 45.0), &imu, &cfg).unwrap();
    assert_eq!(s.channel_ranking, ChannelRanking::Noise);
    assert_eq!(used_channels(&s), [0, 2, 4, 5]);
    let noisy = s.channels.iter().find(|c| c.channel == 1).unwrap();
    assert!(noisy.reason.starts_with("not among the 4 least noisy"), "{}", noisy.reason);
    // Each track's deviation σ measures its own noise (and a share of the others').
    for c in &s.channels {
        let sd = c.screening.deviation_sigma_rad.unwrap();
        let own = sigma_rad[c.channel as usize];
        assert!(sd > 0.85 * own && sd < 1.2 * own + 0.03, "{c:?}");
    }
    let s = prep(&noisy_log(sigma_rad, |ch| 45.0 + 0.01 * ch as f64), &imu, &cfg).unwrap();
    assert_eq!((s.channel_ranking, used_channels(&s)), (ChannelRanking::Noise, vec![0, 2, 4, 5]));
    // C/N0 that differs ranks by C/N0 (here against the noise: the paper's rule).
    let s = prep(&noisy_log(sigma_rad, |ch| 40.0 + ch as f64), &imu, &cfg).unwrap();
    assert_eq!((s.channel_ranking, used_channels(&s)), (ChannelRanking::Cn0, vec![2, 3, 4, 5]));
}

/// Phases so large that the channels' constant offsets overflow leave no
/// epoch with a finite average: an error naming the file, not a panic.
#[test]
fn phases_whose_average_overflows_are_an_error() {
    let rows: Vec<TrackingRow> =
        (0..200).flat_map(|k| [row(tk(k), 1, 45.0, None, 1.7e308), row(tk(k), 2, 45.0, None, -1.7e308)]).collect();
    let e = prep(&log_from(&rows), &wide_imu(), &base()).unwrap_err();
    assert!(matches!(e, SessionError::NoAveragedPhase { .. }), "{e}");
    assert!(msg(e).starts_with("tracking.csv: no epoch has a finite channel-averaged phase error"));
}
