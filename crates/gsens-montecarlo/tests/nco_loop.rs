//! The estimate from the NCO frequency with the receiver's loop identified
//! from the session, on simulated sessions logged at a GNSS receiver's
//! measurement rates.

mod common;

use common::{assert_calibrated, session_of, truth};
use gsens_calib::{
    IdentifiedLoop, LoopFreeSettings, LoopResolution, NcoRecord, TimeOffset, estimate_nco_frequency_identified,
    identification_shapes,
};
use gsens_core::LoggedPhase;

/// What the identification gave on `toml` simulated with `seed`: z of Γ̂
/// per axis, and the identified loop.
fn identified(toml: &str, seed: u64, record: NcoRecord) -> ([f64; 3], IdentifiedLoop) {
    let logs = session_of(toml, seed);
    let mut settings = LoopFreeSettings::new(0.001, LoggedPhase::Last);
    settings.time_offset = TimeOffset::Auto { max_abs_s: 0.1 };
    let epochs = logs.tracking.epoch_t_s();
    let shapes = identification_shapes(epochs[1] - epochs[0]);
    let got =
        estimate_nco_frequency_identified(&logs.tracking, &logs.imu, &settings, &shapes, record).expect("an estimate");
    let (g, s, want) = (got.estimate.gamma_hz_per_mps2, got.estimate.sigma_hz_per_mps2(), truth(&logs));
    ([0, 1, 2].map(|i| (g[i] - want[i]) / s[i]), got.identified)
}

/// z of the identified Bn against the truth, where the loop's order and
/// bandwidth were resolved (`None` elsewhere).
fn z_bn(id: &IdentifiedLoop, order: u8, bn_hz: f64) -> Option<f64> {
    (id.order_resolved && id.resolution == LoopResolution::Resolved && id.order == order)
        .then(|| (id.bn_hz / bn_hz).ln() / id.sigma_ln_bn)
}

/// The identification on `toml` from `record` over 12 seeds: Γ̂ within its
/// σ (mean z²), and where the order and bandwidth were resolved (at least
/// `resolved` of the 12) Bn within 3σ of `bn_hz` (order 0: no bandwidth
/// checked). Returns the identified loops.
fn assert_identified(toml: &str, record: NcoRecord, order: u8, bn_hz: f64, resolved: usize) -> Vec<IdentifiedLoop> {
    let runs: Vec<([f64; 3], IdentifiedLoop)> = (1..=12).map(|seed| identified(toml, seed, record)).collect();
    let z: Vec<f64> = runs.iter().flat_map(|(z, _)| *z).collect();
    assert_calibrated(&z);
    let loops: Vec<IdentifiedLoop> = runs.into_iter().map(|(_, id)| id).collect();
    let z_bn: Vec<f64> = loops.iter().filter_map(|id| z_bn(id, order, bn_hz)).collect();
    eprintln!("z of ln Bn: {z_bn:?}");
    assert!(z_bn.len() >= resolved, "{loops:?}");
    assert!(z_bn.iter().all(|z| z.abs() < 3.0), "{z_bn:?}");
    loops
}

/// The paper's receiver (2nd order, Bn 3 Hz, 1 ms updates) logging its
/// latest NCO command at 10 Hz, the IMU offset searched: Γ̂ within its σ
/// (the loop's uncertainty in it), the order found, Bn within its σ of 3 Hz.
#[test]
fn a_3_hz_loop_logging_its_command_at_10_hz_is_identified() {
    assert_identified("[log]\nnco = true\ninterval_s = 0.1\n", NcoRecord::Command, 2, 3.0, 6);
}

/// The same receiver's NCO phase differenced at 20 Hz (a carrier phase, or
/// a Doppler averaged over the interval): the loop's thermal noise averaged,
/// Bn to about 1 % where the update interval is told apart.
#[test]
fn a_3_hz_loop_logging_its_phase_at_20_hz_is_identified() {
    assert_identified("[log]\nnco = true\ninterval_s = 0.05\n", NcoRecord::PhaseDifference, 2, 3.0, 10);
}

/// A 3rd-order 10 Hz loop at 5 ms, its phase differenced at 20 Hz: Γ̂ within
/// its σ; where the 3rd order is told apart, Bn within its σ of 10 Hz.
#[test]
fn a_10_hz_third_order_loop_logged_at_20_hz_is_identified() {
    let toml = "[loop]\norder = 3\nbn_hz = 10.0\ninterval_s = 0.005\n[log]\nnco = true\ninterval_s = 0.05\n";
    assert_identified(toml, NcoRecord::PhaseDifference, 3, 10.0, 10);
}

/// A wide loop (2nd order, 40 Hz, 1 ms), its phase differenced at 10 Hz: H ≈ 1
/// in the shaking's band, so Γ̂ stays within its σ whatever Bn fits, and
/// the loop is seen as wide (Bn above 10 Hz, or a bound). Its Bn is not
/// within its σ of 40 Hz: where the profile has an inside minimum it lies
/// near 20 Hz (the simulated channel's loop answers a wide loop's shaking
/// with a lag the model's loop lacks: no latency is fitted).
#[test]
fn a_wide_loop_gives_gamma_within_sigma_and_is_seen_wide() {
    let toml = "[loop]\nbn_hz = 40.0\n[log]\nnco = true\ninterval_s = 0.1\n";
    let loops = assert_identified(toml, NcoRecord::PhaseDifference, 0, 40.0, 0);
    let seen: Vec<(f64, LoopResolution)> = loops.iter().map(|id| (id.bn_hz, id.resolution)).collect();
    assert!(loops.iter().all(|id| id.bn_hz > 10.0 && id.resolution != LoopResolution::Narrow), "{seen:?}");
}
