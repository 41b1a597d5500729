//! Whole-session behaviour: reproducibility, time stamps, loop intervals,
//! rising/setting satellites, and consistency with the core's loop model.

use std::collections::HashMap;

use gsens_core::RegressorModel;
use gsens_sim::imu::ImuPreset;
use gsens_sim::motion::{Axis, Segment};
use gsens_sim::satellites::Constellation;
use gsens_sim::scenario::{Cn0Logged, LoggedPhase, Scenario};
use gsens_sim::session::{MemorySink, simulate};

fn bits(s: &MemorySink) -> Vec<u64> {
    let mut v = Vec::new();
    for (t, f) in &s.imu {
        v.push(t.to_bits());
        v.extend(f.iter().map(|x| x.to_bits()));
    }
    for r in &s.tracking {
        v.extend([r.t_s, r.cn0_dbhz, r.elev_deg, r.phase_err_rad, r.true_phase_err_rad].map(f64::to_bits));
        v.extend([u64::from(r.channel), u64::from(r.prn), u64::from(r.locked)]);
    }
    v
}

fn short() -> Scenario {
    let mut sc = Scenario::default();
    sc.motion.segments = vec![Segment::rest(2.0), Segment::shake(Axis::Y, 8.0, 1.1, 3.0), Segment::rest(2.0)];
    sc
}

#[test]
fn same_seed_same_bytes_other_seed_other_bytes() {
    let sc = short();
    let run = |seed| {
        let mut s = MemorySink::default();
        let truth = simulate(&sc, seed, &mut s, |_| {}).unwrap();
        (bits(&s), serde_json::to_string(&truth).unwrap())
    };
    let (a, ta) = run(42);
    let (b, tb) = run(42);
    let (c, _) = run(43);
    assert!(!a.is_empty());
    assert_eq!(a, b);
    assert_eq!(ta, tb);
    assert_ne!(a, c);
    assert!(ta.contains("\"gamma_hz_per_mps2\":[0.09,0.08,-0.08]"), "{ta}");
    assert!(ta.contains("\"seed\":42"));
}

#[test]
fn simulated_rows_are_valid_tracking_rows() {
    let mut s = MemorySink::default();
    simulate(&short(), 5, &mut s, |_| {}).unwrap();
    let rows: Vec<gsens_io::TrackingRow> = s.tracking.iter().map(|r| r.tracking_row()).collect();
    for (r, t) in s.tracking.iter().zip(&rows) {
        assert_eq!((t.t_s, t.channel, t.prn, t.cn0_dbhz), (r.t_s, r.channel, r.prn, r.cn0_dbhz));
        assert_eq!((t.elev_deg, t.phase_err_rad), (Some(r.elev_deg), r.phase_err_rad));
    }
    let log = gsens_io::TrackingLog::from_rows("simulated", &rows).unwrap();
    assert_eq!(log.rows(), s.tracking.len());
}

#[test]
fn rows_are_stamped_at_40_hz_in_step_with_the_imu_and_progress_is_reported() {
    let sc = short();
    let mut s = MemorySink::default();
    let mut fractions = Vec::new();
    let truth = simulate(&sc, 1, &mut s, |f| fractions.push(f)).unwrap();
    assert!(fractions.windows(2).all(|w| w[0] <= w[1]));
    assert_eq!(fractions.last(), Some(&1.0));
    // IMU: stamps k/40 from 0 to the duration inclusive.
    assert_eq!(s.imu.len(), 12 * 40 + 1);
    for (k, (t, _)) in s.imu.iter().enumerate() {
        assert_eq!(*t, k as f64 / 40.0);
    }
    // Tracking: every row time is an IMU time; each channel has a row at
    // every 25 ms once locked, and channels are numbered from 0.
    let imu_times: Vec<u64> = s.imu.iter().map(|(t, _)| t.to_bits()).collect();
    assert!(s.tracking.iter().all(|r| imu_times.contains(&r.t_s.to_bits())));
    assert!(s.tracking.iter().all(|r| r.locked));
    let n_ch = truth.channels.len();
    assert!(n_ch >= 6);
    for c in &truth.channels {
        let rows = s.tracking.iter().filter(|r| r.channel == c.channel && r.prn == c.prn).count();
        assert!(rows as f64 > 0.95 * 12.0 * 40.0, "PRN {}: {rows} rows", c.prn);
        assert!(c.channel < n_ch as u32);
    }
    // C/N0 estimates near the truth after the first second.
    let mut worst: f64 = 0.0;
    for r in s.tracking.iter().filter(|r| r.t_s > 2.0) {
        worst = worst.max((r.cn0_dbhz - r.true_cn0_dbhz).abs());
    }
    assert!(worst < 3.0, "C/N0 estimate off by {worst} dB");
    assert!(truth.loop_interval_s == 0.001 && truth.log_interval_s == 0.025);
}

#[test]
fn loop_intervals_of_5_and_20_ms_work_with_costas_and_pilot() {
    for (t_s, log_s, disc) in [(0.005f64, 0.025f64, "costas"), (0.020, 0.020, "costas"), (0.020, 0.040, "pilot")] {
        let text = format!("[loop]\ninterval_s = {t_s}\ndiscriminator = \"{disc}\"\n[log]\ninterval_s = {log_s}\n");
        let mut sc = Scenario::from_toml_str(&text).unwrap();
        sc.motion = short().motion;
        sc.log.drop_unlocked = false;
        sc.log.cn0 = Cn0Logged::True;
        let mut s = MemorySink::default();
        let truth = simulate(&sc, 9, &mut s, |_| {}).unwrap();
        for c in &truth.channels {
            assert_eq!(c.stats.cycle_slips, 0, "T {t_s}: PRN {}", c.prn);
            assert_eq!(c.stats.losses_of_lock, 0, "T {t_s}: PRN {}", c.prn);
            assert_eq!(c.stats.integrations, (12.0 / t_s) as u64 + 1);
        }
        let per_channel = s.tracking.len() / truth.channels.len();
        assert_eq!(per_channel, (12.0 / log_s).round() as usize, "T {t_s}");
        assert!(s.tracking.iter().all(|r| (r.t_s / log_s - (r.t_s / log_s).round()).abs() < 1e-9));
        let locked_after_1s = s.tracking.iter().filter(|r| r.t_s > 1.0).all(|r| r.locked);
        assert!(locked_after_1s, "T {t_s} {disc}");
    }
}

/// The simulated receiver and the estimator's model agree: the g-induced part
/// of the logged phase (run with Γ minus the same-seed run without) equals the
/// core's `RegressorModel` (same loop, same log convention) fed with the true
/// specific force (an ideal IMU sampled at the row times) times Γ.
#[test]
fn g_induced_phase_matches_the_core_regressor_model() {
    for phase in [LoggedPhase::Mean, LoggedPhase::Last] {
        let mut sc = Scenario::default();
        sc.motion.segments = vec![
            Segment::rest(2.0),
            Segment::shake(Axis::X, 12.0, 1.1, 3.0),
            Segment::shake(Axis::Z, 12.0, 1.6, 3.0),
            Segment::rest(1.0),
        ];
        sc.imu.preset = ImuPreset::Ideal;
        sc.log.drop_unlocked = false;
        sc.log.phase = phase;
        let gamma = sc.oscillator.gamma_hz_per_mps2;
        let mut with = MemorySink::default();
        simulate(&sc, 3, &mut with, |_| {}).unwrap();
        sc.oscillator.gamma_hz_per_mps2 = [0.0; 3];
        let mut without = MemorySink::default();
        simulate(&sc, 3, &mut without, |_| {}).unwrap();

        // The channels started at t = 0 with the NCO preloaded for the
        // apparent frequency there, so the model is fed a − a(0).
        let coeffs = sc.tracking_loop.coeffs().unwrap();
        let mut model = RegressorModel::new(coeffs, 0.001, 0.025, phase).unwrap();
        let a0 = with.imu[0].1;
        let model_at: HashMap<u64, f64> = with
            .imu
            .iter()
            .map(|(t, f)| {
                let p = model.epoch(&[f[0] - a0[0], f[1] - a0[1], f[2] - a0[2]]);
                (t.to_bits(), p[0] * gamma[0] + p[1] * gamma[1] + p[2] * gamma[2])
            })
            .collect();
        let mut per_prn: HashMap<u32, (f64, f64, f64)> = HashMap::new();
        for (a, b) in with.tracking.iter().zip(&without.tracking) {
            assert_eq!((a.t_s, a.prn), (b.t_s, b.prn));
            let m = model_at[&a.t_s.to_bits()];
            let d = a.phase_err_rad - b.phase_err_rad;
            let e = per_prn.entry(a.prn).or_default();
            e.0 += d * m;
            e.1 += m * m;
            e.2 += (d - m) * (d - m);
        }
        for (prn, (dm, mm, rr)) in per_prn {
            let slope = dm / mm;
            let resid = (rr / mm).sqrt();
            println!("{phase:?} PRN {prn}: slope {slope:.4}, residual rms / model rms {resid:.4}");
            // The discriminator is φ + arg(A + n') reduced mod π, with the
            // noise angle independent of φ, so the paired difference is the
            // loop's linear response; what remains is the model's linear
            // interpolation of the 40 Hz specific force (≈ 0.2 %).
            let (max_slope_err, max_resid) = (0.005, 0.02);
            assert!((slope - 1.0).abs() < max_slope_err, "{phase:?} PRN {prn}: slope {slope}");
            assert!(resid < max_resid, "{phase:?} PRN {prn}: residual {resid}");
        }
    }
}

/// Channels start when a satellite rises above the mask and stop when it
/// sets: find instants of the built-in almanac where that happens and run a
/// short session across each.
#[test]
fn channels_follow_rising_and_setting_satellites() {
    let sc0 = Scenario::default();
    let c = Constellation::builtin();
    let t0 = sc0.start_gps_s().unwrap();
    let mask = sc0.satellites.elevation_mask_deg;
    let mut found_rise = None;
    let mut found_set = None;
    let mut prev = c.visible(&sc0.antenna, t0, mask);
    let mut t = t0;
    while t < t0 + 86_400.0 && (found_rise.is_none() || found_set.is_none()) {
        t += 30.0;
        let now = c.visible(&sc0.antenna, t, mask);
        // The crossing instant by bisection on the elevation; the session
        // starts 10 s before it.
        let crossing = |prn: u32| {
            let (mut lo, mut hi) = (t - 30.0, t);
            let above = |x: f64| c.line_of_sight(prn, &sc0.antenna, x).unwrap().elevation_deg >= mask;
            let lo_above = above(lo);
            while hi - lo > 0.01 {
                let mid = 0.5 * (lo + hi);
                if above(mid) == lo_above { lo = mid } else { hi = mid }
            }
            (hi - 10.0).floor()
        };
        if found_rise.is_none()
            && let Some(p) = now.iter().find(|p| !prev.contains(p))
        {
            found_rise = Some((crossing(*p), *p));
        }
        if found_set.is_none()
            && let Some(p) = prev.iter().find(|p| !now.contains(p))
        {
            found_set = Some((crossing(*p), *p));
        }
        prev = now;
    }
    for (what, (start_gps, prn)) in [("rise", found_rise.unwrap()), ("set", found_set.unwrap())] {
        let mut sc = Scenario::default();
        sc.tracking_loop.interval_s = 0.02;
        sc.log.interval_s = 0.02;
        sc.session.duration_s = Some(40.0);
        sc.motion.segments = vec![Segment::rest(40.0)];
        let (y, mo, d, h, mi, s) = utc_from_gps(start_gps);
        sc.session.start_utc = format!("{y:04}-{mo:02}-{d:02}T{h:02}:{mi:02}:{s:02}Z");
        let mut sink = MemorySink::default();
        let truth = simulate(&sc, 1, &mut sink, |_| {}).unwrap();
        let pass = truth.channels.iter().find(|c| c.prn == prn).expect("the PRN got a channel");
        let rows: Vec<f64> = sink.tracking.iter().filter(|r| r.prn == prn).map(|r| r.t_s).collect();
        println!("{what}: PRN {prn} tracked {} s – {} s, rows {:?}…", pass.start_s, pass.stop_s, rows.first());
        match what {
            "rise" => {
                assert!(pass.start_s > 9.0 && pass.start_s < 12.0 && pass.stop_s == 40.0);
                assert!(rows[0] >= pass.start_s);
            }
            _ => {
                assert!(pass.start_s == 0.0 && pass.stop_s > 9.0 && pass.stop_s < 12.0);
                assert!(*rows.last().unwrap() < pass.stop_s);
            }
        }
        assert!(pass.start_elev_deg >= sc.satellites.elevation_mask_deg);
    }
}

/// GPS seconds → UTC calendar (GPS − UTC = 18 s), whole seconds.
fn utc_from_gps(t_gps: f64) -> (i64, i64, i64, i64, i64, i64) {
    let unix = t_gps.round() as i64 + 315_964_800 - 18;
    let days = unix.div_euclid(86_400);
    let sod = unix.rem_euclid(86_400);
    // H. Hinnant's civil_from_days.
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    (y, m, d, sod / 3600, sod % 3600 / 60, sod % 60)
}

/// With `log.nco` the NCO record is written to `tracking.csv` and kept in
/// memory alike: the file reads back as the in-memory log, and every track
/// has one NCO phase and frequency per row.
#[test]
fn nco_columns_round_trip_through_the_file() {
    let mut sc = short();
    sc.log.nco = true;
    let dir = std::env::temp_dir().join(format!("gsens-sim-nco-{}", std::process::id()));
    gsens_sim::simulate_to_dir(&sc, 7, &dir, |_| {}).unwrap();
    let from_file = gsens_io::read_tracking_file(dir.join("tracking.csv")).unwrap();
    let in_memory = gsens_sim::simulate_logs(&sc, 7).unwrap().tracking;
    assert_eq!(from_file.tracks(), in_memory.tracks());
    for tr in in_memory.tracks() {
        assert_eq!((tr.nco_phase_cycles.len(), tr.nco_freq_hz.len()), (tr.len(), tr.len()));
        // The accumulated phase follows the commanded frequency: its steps are
        // the frequency times the log interval, within the change over it.
        for k in 1..tr.len() {
            let step = tr.nco_phase_cycles[k] - tr.nco_phase_cycles[k - 1];
            let mean = 0.5 * (tr.nco_freq_hz[k] + tr.nco_freq_hz[k - 1]) * (tr.t_s[k] - tr.t_s[k - 1]);
            assert!((step - mean).abs() < 0.05, "{step} vs {mean}");
        }
    }
    let header = std::fs::read_to_string(dir.join("tracking.csv")).unwrap();
    assert!(header.starts_with("t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad,nco_phase_cycles,nco_freq_hz\n"));
    sc.log.nco = false;
    assert!(gsens_sim::simulate_logs(&sc, 7).unwrap().tracking.tracks().iter().all(|t| t.nco_phase_cycles.is_empty()));
    std::fs::remove_dir_all(&dir).unwrap();
}
