//! Simulated sessions in memory, changed the way a user might have got their
//! logs or options wrong, and calibrated through the library as every front
//! end calibrates them (`CalibrationOptions` → `calibrate_logs` →
//! `ResultDocument`).

#![allow(dead_code)]

use gsens_calib::{CalibrationOptions, LoopOptions, ResultDocument, WarningCode, calibrate_logs};
use gsens_core::LoggedPhase;
use gsens_io::{ImuSeries, TrackingLog, TrackingRow};
use gsens_sim::scenario::Scenario;
use gsens_sim::{SimulatedLogs, simulate_logs};

/// The default scenario (the paper's experiment) simulated with `seed`, its
/// tracking log as the paper's receiver logs it: the tracking error only (no
/// NCO columns), so that the estimate is the one through the loop model.
pub(crate) fn session(seed: u64) -> SimulatedLogs {
    session_of("[log]\nnco = false", seed)
}

/// The scenario of `toml` (on top of the defaults) simulated with `seed`.
pub(crate) fn session_of(toml: &str, seed: u64) -> SimulatedLogs {
    let scenario = Scenario::from_toml_str(toml).expect("a valid scenario");
    simulate_logs(&scenario, seed).expect("the scenario simulates")
}

/// A second clean session made another way: another seed, the latest
/// discriminator output logged, a consumer MEMS IMU (16-bit over ±4 g) at
/// 100 Hz.
pub(crate) fn other_clean_session() -> SimulatedLogs {
    session_of("[log]\nphase = \"last\"\n[imu]\npreset = \"consumer_mems\"\nrate_hz = 100.0\n", 11)
}

/// The truth as the IMU sees it \[Hz/(m/s²)\].
pub(crate) fn truth(logs: &SimulatedLogs) -> [f64; 3] {
    logs.truth.sensitivity.gamma_imu_axes_hz_per_mps2
}

/// The receiver's loop as the default scenario runs it: 2nd order, 3 Hz,
/// updated every 1 ms, each row the mean of its 25 updates.
pub(crate) fn right_loop() -> CalibrationOptions {
    let receiver_loop = LoopOptions {
        order: Some(2),
        bn_hz: Some(3.0),
        loop_interval_s: Some(0.001),
        logged_phase: Some(LoggedPhase::Mean),
        ..LoopOptions::default()
    };
    CalibrationOptions { receiver_loop, ..CalibrationOptions::default() }
}

/// The tracking log with every row changed by `f`, in the order the
/// simulator wrote them (epoch by epoch).
pub(crate) fn map_tracking(log: &TrackingLog, f: impl Fn(&mut TrackingRow)) -> TrackingLog {
    let mut rows: Vec<(usize, TrackingRow)> = Vec::with_capacity(log.rows());
    for (track, t) in log.tracks().iter().enumerate() {
        for k in 0..t.len() {
            let elev = t.elev_deg[k];
            let mut row = TrackingRow {
                t_s: t.t_s[k],
                channel: t.channel,
                prn: t.prn,
                cn0_dbhz: t.cn0_dbhz[k],
                elev_deg: (!elev.is_nan()).then_some(elev),
                phase_err_rad: t.phase_err_rad[k],
            };
            f(&mut row);
            rows.push((track, row));
        }
    }
    // Epoch by epoch, the channels in their order within each (a stable sort keeps it).
    rows.sort_by(|a, b| a.1.t_s.total_cmp(&b.1.t_s).then(a.0.cmp(&b.0)));
    TrackingLog::from_rows(log.source_name(), rows.iter().map(|(_, r)| r)).expect("a valid tracking log")
}

/// The IMU log with every sample's time stamp changed by `t` and its specific
/// force by `a`.
pub(crate) fn map_imu(imu: &ImuSeries, t: impl Fn(f64) -> f64, a: impl Fn([f64; 3]) -> [f64; 3]) -> ImuSeries {
    ImuSeries {
        t_s: imu.t_s.iter().map(|&x| t(x)).collect(),
        accel_mps2: imu.accel_mps2.iter().map(|&x| a(x)).collect(),
    }
}

/// The result document of `tracking` and `imu` calibrated with `options`.
pub(crate) fn estimate(tracking: &TrackingLog, imu: &ImuSeries, options: &CalibrationOptions) -> ResultDocument {
    let settings = options.pipeline_settings().expect("valid options");
    let outcome = calibrate_logs(tracking, imu, "imu", &settings).expect("the session calibrates");
    outcome.document(None)
}

/// The warning codes of a document, in its order.
pub(crate) fn codes(doc: &ResultDocument) -> Vec<WarningCode> {
    doc.warnings.iter().map(|w| w.code).collect()
}

/// The message of the warning `code`.
pub(crate) fn message(doc: &ResultDocument, code: WarningCode) -> &str {
    let w = doc.warnings.iter().find(|w| w.code == code);
    &w.unwrap_or_else(|| panic!("no {}: {:?}", code.as_str(), codes(doc))).message
}

/// |Γ̂ − Γ|/|Γ| and the largest |Γ̂ − Γ|/σ over the axes (∞ for an axis with
/// no estimate).
pub(crate) fn error_and_z(doc: &ResultDocument, truth: [f64; 3]) -> (f64, f64) {
    let c = &doc.calibration;
    let norm = truth.iter().map(|x| x * x).sum::<f64>().sqrt();
    let mut err2 = 0.0;
    let mut z: f64 = 0.0;
    for i in 0..3 {
        match (c.gamma_hz_per_mps2[i], c.sigma_hz_per_mps2[i]) {
            (Some(g), Some(s)) => {
                err2 += (g - truth[i]).powi(2);
                z = z.max(((g - truth[i]) / s).abs());
            }
            _ => return (f64::INFINITY, f64::INFINITY),
        }
    }
    let err = err2.sqrt() / norm;
    (if err.is_nan() { f64::INFINITY } else { err }, if z.is_nan() { f64::INFINITY } else { z })
}

/// Asserts that every axis's Γ̂ is within 3σ of the truth.
pub(crate) fn assert_within_3_sigma(doc: &ResultDocument, truth: [f64; 3]) {
    let c = &doc.calibration;
    for i in 0..3 {
        let (g, s) = (c.gamma_hz_per_mps2[i].unwrap(), c.sigma_hz_per_mps2[i].unwrap());
        assert!((g - truth[i]).abs() < 3.0 * s, "axis {i}: {g} vs {} ± {s}", truth[i]);
    }
}

/// E[z²] = 1, with standard error √(2/n) for n independent standard normal z.
pub(crate) fn assert_calibrated(z: &[f64]) {
    let mean_z2 = z.iter().map(|z| z * z).sum::<f64>() / z.len() as f64;
    let se = (2.0 / z.len() as f64).sqrt();
    eprintln!("mean z² = {mean_z2:.3} over {} axis estimates (3 SE = {:.3})", z.len(), 3.0 * se);
    assert!((mean_z2 - 1.0).abs() < 3.0 * se, "mean z² = {mean_z2} over {} (3 SE = {}): {z:?}", z.len(), 3.0 * se);
}
