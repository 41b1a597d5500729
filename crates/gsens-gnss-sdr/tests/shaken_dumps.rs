//! GNSS-SDR 0.0.17's dumps of a board shaken hard from 3 s on, through the
//! channels' switch to the narrow loop (`tests/fixtures/shaken`, made by
//! `scripts/make-gnss-sdr-fixtures.sh`): the carrier lock test falls to
//! 0.75–0.85 while shaking, and in the 3rd-order run channel 1 came out of
//! the switch false-locked (|φ| ≈ 1.2 rad, lock test ≈ 0) until GNSS-SDR's
//! own lock detector dropped it at 59.4 s. The truth is the simulator's.

use std::path::{Path, PathBuf};

use gsens_calib::{
    EpochSeries, EstimateSettings, PipelineSettings, calibrate, longest_models_warmup_s, models_warmup_s,
};
use gsens_core::gnss_sdr::GnssSdrPll;
use gsens_core::{LinearLoop, LoopModel};
use gsens_gnss_sdr::calibrate_gnss_sdr;
use gsens_gnss_sdr::{ImportSettings, Imported, import_dir, resample};
use gsens_io::{ImuSeries, read_imu_file};
use gsens_session::{SelectionConfig, prepare_session};

fn dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/shaken")
}

fn settings(order: u8) -> ImportSettings {
    ImportSettings::from_conf(Some(&dir().join(format!("order{order}/gnss-sdr.conf"))), None).unwrap()
}

fn truth(key: &str) -> [f64; 3] {
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir().join("truth.json")).unwrap()).unwrap();
    std::array::from_fn(|i| v[key][i].as_f64().unwrap())
}

fn imu() -> ImuSeries {
    read_imu_file(dir().join("imu.csv")).unwrap()
}

#[test]
fn the_receivers_lock_rule_keeps_shaken_tracks_and_reproduces_its_own_loss_of_lock() {
    for order in [2u8, 3] {
        let s = settings(order);
        // The dumps' configuration leaves the lock detector's keys out: GNSS-SDR's defaults.
        assert_eq!(s.tracking.lock.carrier_lock_th.value, 0.7);
        let dumps = dir().join(format!("order{order}"));
        let imported = import_dir(&dumps, &s).unwrap();
        for (k, t) in imported.tracks.iter().enumerate() {
            assert!(t.used, "order {order} track {k}: {}", t.reason);
            assert!(t.reason.starts_with("used: GNSS-SDR's lock detector keeps it"), "{}", t.reason);
            assert!(t.reason.contains("carrier_lock_th = 0.7 (GNSS-SDR's default)"), "{}", t.reason);
            assert_eq!(t.lock.loss_of_lock, None, "GNSS-SDR logged no record past a loss of lock");
            // While shaken, most records are below the 0.85 our former rule asked for in 90 % of them.
            let rows: Vec<_> = imported.rows.iter().filter(|r| r.track == k).collect();
            let low = rows.iter().filter(|r| r.lock_test < 0.85).count() as f64 / rows.len() as f64;
            eprintln!("order {order} track {k}: {} rows, {:.0} % with lock test < 0.85", rows.len(), 100.0 * low);
            if rows.len() > 1000 {
                assert!(low > 0.25, "order {order} track {k}: only {:.0} % below 0.85", 100.0 * low);
            }
        }
        // The false-locked track: GNSS-SDR dropped it when its C/N0 fail counter passed
        // max_lock_fail = 50, after its last logged record. The replay stands at exactly 50 there.
        if order == 3 {
            let t = &imported.tracks[1];
            assert_eq!((t.channel, t.end_s < 60.0), (1, true), "{t:?}");
            assert_eq!(t.lock.code_fail_counter_max, 50);
            assert_eq!(t.lock.carrier_lock_failures, t.lock.judged_records, "lock test < 0.7 throughout");
            // Stricter settings than the receiver's end it earlier, and say which value decided.
            let mut strict = s.clone();
            strict.tracking.lock.max_lock_fail.set_option(40);
            let i = import_dir(&dumps, &strict).unwrap();
            let t = &i.tracks[1];
            assert!(t.lock_loss_s.unwrap() < t.end_s, "{t:?}");
            assert!(t.reason.contains("max_lock_fail = 40 (given as an option)"), "{}", t.reason);
            assert_eq!(t.lock.loss_by, Some("code"));
        }
    }
}

/// The regressor of one track for the true Γ: each axis through GNSS-SDR's
/// narrow loop, started `lead_s` before the track's first kept record in the
/// steady state of the specific force there.
fn model_phase(imported: &Imported, track: usize, s: &ImportSettings, lead_s: f64) -> (Vec<f64>, Vec<f64>) {
    let imu = imu();
    let g = truth("gamma_imu_axes_hz_per_mps2");
    let a = |t: f64| -> [f64; 3] {
        let k = imu.t_s.partition_point(|&x| x <= t).clamp(1, imu.t_s.len() - 1);
        let u = (t - imu.t_s[k - 1]) / (imu.t_s[k] - imu.t_s[k - 1]);
        std::array::from_fn(|i| imu.accel_mps2[k - 1][i] + u * (imu.accel_mps2[k][i] - imu.accel_mps2[k - 1][i]))
    };
    let rows: Vec<_> = imported.rows.iter().filter(|r| r.track == track).collect();
    let t_step = s.interval_s();
    let mut loops: Vec<GnssSdrPll> = (0..3).map(|_| GnssSdrPll::new(s.stage()).unwrap()).collect();
    let mut t = rows[0].t_s - (lead_s / t_step).round() * t_step;
    let a0 = a(t);
    for (l, a0) in loops.iter_mut().zip(a0) {
        l.settle(a0);
    }
    while t < rows[0].t_s - 0.5 * t_step {
        let x = a(t);
        for (l, x) in loops.iter_mut().zip(x) {
            l.step(x);
        }
        t += t_step;
    }
    let model =
        rows.iter().map(|r| loops.iter_mut().zip(a(r.t_s)).zip(g).map(|((l, x), g)| g * l.step(x)).sum()).collect();
    (rows.iter().map(|r| r.phase_err_rad).collect(), model)
}

#[test]
fn the_switch_transient_lasts_five_time_constants_of_the_narrow_loop() {
    // Track 0 of the 3rd-order run from its switch on (no settling), against the
    // exact narrow-loop model running since long before: the residual's RMS by
    // time since the switch, against the thermal noise of a 20 ms atan discriminator.
    let mut s = settings(3);
    s.settle_s = Some(0.0);
    let imported = import_dir(&dir().join("order3"), &s).unwrap();
    let (phi, model) = model_phase(&imported, 0, &s, 30.0);
    let rows: Vec<_> = imported.rows.iter().filter(|r| r.track == 0).collect();
    let t0 = rows[0].t_s;
    let resid: Vec<f64> = phi.iter().zip(&model).map(|(p, m)| p - m).collect();
    let tail: Vec<f64> = rows.iter().zip(&resid).filter(|(r, _)| r.t_s > t0 + 30.0).map(|(_, v)| *v).collect();
    let offset = tail.iter().sum::<f64>() / tail.len() as f64;
    let rms = |a: f64, b: f64| {
        let v: Vec<f64> = rows
            .iter()
            .zip(&resid)
            .filter(|(r, _)| r.t_s >= t0 + a && r.t_s < t0 + b)
            .map(|(_, v)| v - offset)
            .collect();
        (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt()
    };
    let cn0 = gsens_core::units::cn0_dbhz_to_ratio_hz(imported.tracks[0].mean_cn0_dbhz);
    let thermal = (1.0 / (2.0 * cn0 * 0.02)).sqrt();
    let settle = settings(3).settle_time_s();
    let (early, late) = (rms(0.0, 2.0), rms(settle, settle + 10.0));
    eprintln!(
        "switch residual RMS: first 2 s {early:.3} rad, from 5τ = {settle:.1} s on {late:.4} rad, thermal {thermal:.4}"
    );
    assert!((12.0..13.5).contains(&settle), "{settle}");
    assert!(early > 5.0 * thermal, "{early} vs {thermal}");
    assert!(late < 1.25 * thermal, "{late} vs {thermal}");
}

fn estimate_with_warmup(order: u8, warmup_s: f64) -> ([f64; 3], [f64; 3], [f64; 3]) {
    let s = settings(order);
    let imported = import_dir(&dir().join(format!("order{order}")), &s).unwrap();
    let grid = resample(&imported, imported.interval_s);
    let log = gsens_io::TrackingLog::from_rows("grid", &grid).unwrap();
    let session = prepare_session(&log, &imu(), "imu.csv", &SelectionConfig::default(), 0.0).unwrap();
    let mut e = EstimateSettings::default().with_loop(LoopModel::GnssSdr(s.stage()));
    e.warmup_s = warmup_s;
    let series = EpochSeries {
        log_interval_s: session.log_interval_s,
        t_s: &session.t_s,
        phase_err_rad: &session.phase_err_rad,
        accel_mps2: &session.accel_mps2,
        imu_time_offset_s: 0.0,
    };
    let c = calibrate(&series, &e).unwrap();
    let get = |v: [Option<f64>; 3]| v.map(|x| x.expect("observable"));
    (get(c.gamma_hz_per_mps2), get(c.sigma_hz_per_mps2), get(c.crlb_hz_per_mps2))
}

#[test]
fn the_models_start_up_transient_needs_the_derived_warm_up() {
    // Order 2: the session starts 1.2 s after the switch, mid-shake; a 2 s warm-up leaves the
    // models' start-up transient in the high-pass's memory, the derived one does not.
    let narrow = |s: &ImportSettings| LoopModel::GnssSdr(s.stage());
    let longest = |order: u8, highpass_hz: f64| longest_models_warmup_s(&narrow(&settings(order)), highpass_hz);
    let w = longest(2, EstimateSettings::default().highpass_hz);
    assert_eq!(w, 7.6);
    assert_eq!(longest(3, 0.05), 15.2);
    let five_tau = settings(3).settle_time_s();
    assert!((longest(3, 0.0) - five_tau).abs() <= 0.1, "no high-pass, no memory: {} vs {five_tau}", longest(3, 0.0));
    // What these sessions need, from the IMU: their first kept record is mid-shake.
    for order in [2u8, 3] {
        let s = settings(order);
        let imported = import_dir(&dir().join(format!("order{order}")), &s).unwrap();
        let start = resample(&imported, imported.interval_s)[0].t_s;
        let need = models_warmup_s(&narrow(&s), &imu(), start, imported.interval_s, 0.05);
        eprintln!(
            "order {order}: session from {start:.2} s, warm-up needed {need} s of at most {}",
            longest(order, 0.05)
        );
        assert!(need > 0.4 * longest(order, 0.05) && need <= longest(order, 0.05), "order {order}: {need}");
    }
    // A board at rest when the session starts needs none (the quiet fixtures: rest until 20 s),
    // nor a session that starts with the IMU log (the loops remember no motion before it).
    let quiet = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures");
    let quiet_imu = read_imu_file(quiet.join("imu.csv")).unwrap();
    let s3 = ImportSettings::from_conf(Some(&quiet.join("order3/gnss-sdr.conf")), None).unwrap();
    let need = models_warmup_s(&narrow(&s3), &quiet_imu, 18.9, s3.interval_s(), 0.05);
    eprintln!("quiet order 3: warm-up needed {need} s");
    assert!(need < 1.0, "{need}");
    assert_eq!(models_warmup_s(&narrow(&s3), &quiet_imu, quiet_imu.t_s[0], s3.interval_s(), 0.05), 0.0);
    let (_, sigma_short, crlb_short) = estimate_with_warmup(2, 2.0);
    let (g, sigma, crlb) = estimate_with_warmup(2, w);
    let truth = truth("gamma_imu_axes_hz_per_mps2");
    for i in 0..3 {
        eprintln!(
            "order 2 axis {i}: σ/CRB {:.2} with a 2 s warm-up, {:.2} with {w} s; error {:+.1}σ",
            sigma_short[i] / crlb_short[i],
            sigma[i] / crlb[i],
            (g[i] - truth[i]) / sigma[i]
        );
        assert!(sigma_short[i] / crlb_short[i] > 1.8, "axis {i}");
        assert!(sigma[i] / crlb[i] < 1.6, "axis {i}");
        assert!((g[i] - truth[i]).abs() < 3.0 * sigma[i], "axis {i}: {} vs {}", g[i], truth[i]);
    }
}

#[test]
fn gamma_within_2_percent_and_3_sigma_for_both_loop_orders_with_the_default_settings() {
    let (truth, truth_imu) = (truth("gamma_hz_per_mps2"), truth("gamma_imu_axes_hz_per_mps2"));
    for order in [2u8, 3] {
        let d = dir().join(format!("order{order}"));
        let o = calibrate_gnss_sdr(&d, &settings(order), &dir().join("imu.csv"), &PipelineSettings::default())
            .unwrap()
            .outcome;
        let c = &o.calibration;
        for i in 0..3 {
            let (g, sd, crlb) =
                (c.gamma_hz_per_mps2[i].unwrap(), c.sigma_hz_per_mps2[i].unwrap(), c.crlb_hz_per_mps2[i].unwrap());
            let err = (g - truth[i]) / truth[i].abs();
            eprintln!(
                "order {order} axis {i}: Γ̂ {g:+.5} ± {sd:.5} (CRB {crlb:.5}), {:+.2} % of the truth, {:+.1}σ in the IMU's axes",
                100.0 * err,
                (g - truth_imu[i]) / sd
            );
            assert!(err.abs() < 0.02, "order {order} axis {i}: {g} vs {}", truth[i]);
            assert!((g - truth_imu[i]).abs() < 3.0 * sd, "order {order} axis {i}");
            assert!(sd / crlb < 1.6, "order {order} axis {i}: σ {sd} vs CRB {crlb}");
        }
        // The false-locked stretch is the session screening's to find (consistency with the other channel).
        if order == 3 {
            let ch1 = o.session.channels.iter().find(|c| c.channel == 1).unwrap();
            eprintln!("order 3 channel 1: {}", ch1.reason);
            assert!(ch1.screening.rows_excluded > 1500, "{ch1:?}");
        }
    }
}
