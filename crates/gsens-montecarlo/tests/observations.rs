//! Carrier phase and Doppler logs (what a RINEX file or a u-blox RXM-RAWX
//! log holds) of simulated sessions, calibrated through the library as
//! `gsens estimate --rinex` / `--ubx` calibrates them
//! (`calibrate_observations` → `ResultDocument`), with the receiver's loop
//! identified from the log.

mod common;

use common::{assert_calibrated, map_imu, session_of, truth};
use gsens_calib::{
    CalibrationOptions, LoopResolution, ObservationRecord, ResultDocument, WarningCode, calibrate_observations,
};
use gsens_io::{ClockEvent, Observation, ObservationLog, ObservationLogBuilder, obs_flags};
use gsens_sim::SimulatedLogs;
use rayon::prelude::*;

/// Time of week of the session's start \[s\]: the log's and the IMU's time.
const TOW0_S: f64 = 1000.0;

/// What the receiver's carrier phase is.
#[derive(Clone, Copy)]
enum Phase {
    /// Minus the NCO's accumulated phase (most receivers).
    Nco,
    /// Corrected by the discriminator: minus the loop's input phase θ_NCO + φ/2π.
    Corrected,
}

/// The simulated receiver's measurements every 1/`rate_hz` s as such a log
/// holds them (docs/conventions.md, "Carrier phase and Doppler logs"): the
/// Doppler D = f_NCO, the phase L = N − θ(t) with θ(t) the replica's phase at
/// the row's instant (its record at the integration's end less f_NCO·T/2),
/// a loss-of-lock flag after a gap.
fn observation_log(logs: &SimulatedLogs, rate_hz: f64, phase: Phase) -> ObservationLog {
    let half_t = logs.truth.loop_interval_s / 2.0;
    let tracks = logs.tracking.tracks();
    let mut next = vec![0usize; tracks.len()];
    let mut last_t: Vec<Option<f64>> = vec![None; tracks.len()];
    let mut b = ObservationLogBuilder::new("sim.rnx", "RINEX 3.04");
    for &t in logs.tracking.epoch_t_s() {
        if (t * rate_hz - (t * rate_hz).round()).abs() > 1e-6 {
            continue;
        }
        let Some(t_s) = b.start_epoch(2300, TOW0_S + t, || format!("t = {t}")) else { continue };
        for (j, tr) in tracks.iter().enumerate() {
            while next[j] < tr.len() && tr.t_s[next[j]] < t {
                next[j] += 1;
            }
            let i = next[j];
            if i == tr.len() || tr.t_s[i] != t {
                continue;
            }
            let theta = tr.nco_phase_cycles[i] - tr.nco_freq_hz[i] * half_t;
            let theta = match phase {
                Phase::Nco => theta,
                Phase::Corrected => theta + tr.phase_err_rad[i] / std::f64::consts::TAU,
            };
            let gap = last_t[j].is_some_and(|p| t - p > 1.5 / rate_hz);
            last_t[j] = Some(t);
            let obs = Observation {
                carrier_phase_cycles: 2.0e7 - theta,
                doppler_hz: tr.nco_freq_hz[i],
                cn0_dbhz: tr.cn0_dbhz[i],
                flags: if gap { obs_flags::LOSS_OF_LOCK } else { 0 },
                ..Observation::default()
            };
            b.push(&format!("G{:02}", tr.prn), "1C", tr.carrier, t_s, &obs);
        }
    }
    b.finish()
}

/// The document of `log` with the session's IMU on the log's time, the
/// offset searched within ±0.1 s.
fn calibrate(logs: &SimulatedLogs, log: &ObservationLog, record: ObservationRecord) -> ResultDocument {
    let imu = map_imu(&logs.imu, |t| t + TOW0_S, |a| a);
    let settings = CalibrationOptions::default().pipeline_settings().expect("valid options");
    calibrate_observations(log, &imu, &settings, record).expect("the log calibrates").document(None)
}

/// z of Γ̂ per axis.
fn z(doc: &ResultDocument, want: [f64; 3]) -> [f64; 3] {
    let c = &doc.calibration;
    [0, 1, 2].map(|i| (c.gamma_hz_per_mps2[i].unwrap() - want[i]) / c.sigma_hz_per_mps2[i].unwrap())
}

/// The documents of `toml` simulated with seeds 1…`seeds`, logged at
/// `rate_hz` with `phase`, calibrated from `record`: Γ̂ within its σ over
/// them all (mean z²), every one trustworthy. Returns them.
fn documents(toml: &str, rate_hz: f64, phase: Phase, record: ObservationRecord, seeds: u64) -> Vec<ResultDocument> {
    let runs: Vec<([f64; 3], ResultDocument)> = (1..=seeds)
        .into_par_iter()
        .map(|seed| {
            let logs = session_of(toml, seed);
            let doc = calibrate(&logs, &observation_log(&logs, rate_hz, phase), record);
            (z(&doc, truth(&logs)), doc)
        })
        .collect();
    let zs: Vec<f64> = runs.iter().flat_map(|(z, _)| *z).collect();
    assert_calibrated(&zs);
    let docs: Vec<ResultDocument> = runs.into_iter().map(|(_, d)| d).collect();
    for d in &docs {
        assert!(d.trustworthy, "{:?}", d.warnings);
    }
    docs
}

/// The paper's receiver (2nd order, 3 Hz, 1 ms) seen through its carrier
/// phase at 20 Hz: Γ̂ within its σ, the loop's order and Bn found (within
/// 3σ of 3 Hz), and H = 1 flagged: |H| at the shaking is 20 % or more off 1,
/// and the estimate with H = 1 off Γ by as much.
#[test]
fn a_narrow_loop_is_identified_and_h_unity_flagged() {
    let docs = documents("[log]\nnco = true\ninterval_s = 0.05\n", 20.0, Phase::Nco, ObservationRecord::Auto, 8);
    for d in &docs {
        let id = d.identified_loop.as_ref().unwrap();
        assert_eq!(id.record, ObservationRecord::CarrierPhase);
        let l = &id.identified;
        if l.order_resolved && l.resolution == LoopResolution::Resolved {
            assert_eq!(l.order, 2);
            assert!(((l.bn_hz / 3.0).ln() / l.sigma_ln_bn).abs() < 3.0, "{l:?}");
        }
        assert!(id.h_unity_error.unwrap() > 0.15, "{id:?}");
        let unity = id.h_unity_estimate.as_ref().unwrap().gamma_hz_per_mps2;
        let g = d.calibration.gamma_hz_per_mps2;
        assert!((0..3).all(|i| unity[i].unwrap() / g[i].unwrap() > 1.1), "{unity:?} against {g:?}");
    }
}

/// A 3rd-order 10 Hz loop updated every 5 ms, seen through its Doppler at
/// 10 Hz (the command at the epoch's latest update): Γ̂ within its σ, every
/// document trustworthy, and where the order and Bn are resolved, Bn within
/// 3σ of 10 Hz.
#[test]
fn a_10_hz_loop_is_identified_from_its_doppler() {
    let toml = "[loop]\norder = 3\nbn_hz = 10.0\ninterval_s = 0.005\n[log]\nnco = true\ninterval_s = 0.1\n";
    let docs = documents(toml, 10.0, Phase::Nco, ObservationRecord::Doppler, 8);
    for d in &docs {
        let id = d.identified_loop.as_ref().unwrap();
        assert_eq!(id.record, ObservationRecord::Doppler);
        let l = &id.identified;
        if l.order_resolved && l.resolution == LoopResolution::Resolved {
            assert_eq!(l.order, 3, "{l:?}");
            assert!(((l.bn_hz / 10.0).ln() / l.sigma_ln_bn).abs() < 3.0, "{l:?}");
        }
    }
}

/// A carrier phase corrected by the discriminator (θ_NCO + φ/2π, φ the
/// latest output: no loop in the way) at 10 Hz: seen as a wide loop (a
/// bound on Bn only), H ≈ 1 within 1 % at the shaking, Γ̂ within its σ. The satellites are strong
/// (45–50 dB-Hz): a 1 ms Costas output that wraps puts a half cycle into the
/// corrected phase, which a receiver's own correction avoids by smoothing.
#[test]
fn a_corrected_carrier_phase_is_seen_as_h_unity() {
    let toml = "[log]\nnco = true\ninterval_s = 0.1\nphase = \"last\"\n\
                [satellites.cn0]\nzenith_cn0_dbhz = 50.0\nhorizon_cn0_dbhz = 45.0\n";
    let docs = documents(toml, 10.0, Phase::Corrected, ObservationRecord::Auto, 8);
    for d in &docs {
        let id = d.identified_loop.as_ref().unwrap();
        assert_eq!(id.identified.resolution, LoopResolution::Wide, "{id:?}");
        assert!(id.h_unity_error.unwrap() < 0.01, "{id:?}");
    }
}

/// A wide loop (40 Hz) through its carrier phase at 10 Hz: Γ̂ within its σ,
/// the loop seen wide (Bn above 10 Hz, not at the narrow end), H within 5 %
/// of 1 at the shaking even at the narrowest Bn the data allow.
#[test]
fn a_wide_loop_gives_gamma_within_sigma_and_h_near_unity() {
    let toml = "[loop]\nbn_hz = 40.0\n[log]\nnco = true\ninterval_s = 0.1\n";
    let docs = documents(toml, 10.0, Phase::Nco, ObservationRecord::Auto, 8);
    for d in &docs {
        let id = d.identified_loop.as_ref().unwrap();
        let wide = id.identified.resolution != LoopResolution::Narrow && id.identified.bn_hz > 10.0;
        assert!(wide && id.h_unity_error.unwrap() < 0.05, "{id:?}");
    }
}

/// A millisecond jump of the receiver's clock mid-session (every phase
/// moved by f·1 ms, as u-blox clock steering does) and a reported clock
/// reset: the epochs around them are left out and reported (not a reason to
/// distrust), and Γ̂ moves by a small part of its σ.
#[test]
fn receiver_clock_jumps_are_left_out() {
    let logs = session_of("[log]\nnco = true\ninterval_s = 0.05\n", 4);
    let clean = observation_log(&logs, 20.0, Phase::Nco);
    let mut jumped = clean.clone();
    for tr in &mut jumped.tracks {
        let jump = tr.carrier.carrier_hz * 1e-3;
        for (t, l) in tr.t_s.iter().zip(tr.carrier_phase_cycles.iter_mut()) {
            if *t > TOW0_S + 70.0 {
                *l += jump;
            }
        }
    }
    jumped.clock_events.push(ClockEvent { t_s: TOW0_S + 40.0, jump_s: None, what: "clkReset".into() });
    let (a, b) =
        (calibrate(&logs, &clean, ObservationRecord::Auto), calibrate(&logs, &jumped, ObservationRecord::Auto));
    assert!(b.trustworthy, "{:?}", b.warnings);
    assert!(
        b.warnings.iter().any(|w| w.code == WarningCode::ClockJumps && w.message.starts_with("3 epoch(s)")),
        "{:?}",
        b.warnings
    );
    for i in 0..3 {
        let (ga, gb) = (a.calibration.gamma_hz_per_mps2[i].unwrap(), b.calibration.gamma_hz_per_mps2[i].unwrap());
        assert!((ga - gb).abs() < 0.3 * a.calibration.sigma_hz_per_mps2[i].unwrap(), "axis {i}: {ga} against {gb}");
    }
}
