//! The estimate from the NCO frequency with the receiver's loop identified
//! from the session, on simulated sessions logged at a GNSS receiver's
//! measurement rates.

mod common;

use common::{assert_calibrated, session_of, truth};
use gsens_calib::{
    IdentifiedLoop, LoopFreeSettings, LoopResolution, TimeOffset, estimate_nco_frequency_identified,
    identification_shapes,
};
use gsens_core::LoggedPhase;

/// What the identification gave on `toml` simulated with `seed`: z of Γ̂
/// per axis, and the identified loop.
fn identified(toml: &str, seed: u64) -> ([f64; 3], IdentifiedLoop) {
    let logs = session_of(toml, seed);
    let mut settings = LoopFreeSettings::new(0.001, LoggedPhase::Last);
    settings.time_offset = TimeOffset::Auto { max_abs_s: 0.1 };
    let got = estimate_nco_frequency_identified(&logs.tracking, &logs.imu, &settings, &identification_shapes())
        .expect("an estimate");
    let (g, s, want) = (got.estimate.gamma_hz_per_mps2, got.estimate.sigma_hz_per_mps2(), truth(&logs));
    ([0, 1, 2].map(|i| (g[i] - want[i]) / s[i]), got.identified)
}

/// z of the identified Bn against the truth, where the loop's order and
/// bandwidth were resolved (`None` elsewhere).
fn z_bn(id: &IdentifiedLoop, order: u8, bn_hz: f64) -> Option<f64> {
    (id.order_resolved && id.resolution == LoopResolution::Resolved && id.order == order)
        .then(|| (id.bn_hz / bn_hz).ln() / id.sigma_ln_bn)
}

/// The identification on `toml` over 12 seeds: Γ̂ within its σ (mean z²),
/// and where the order and bandwidth were resolved (at least `resolved` of
/// the 12) Bn within 3σ of `bn_hz`. Returns the identified loops.
fn assert_identified(toml: &str, order: u8, bn_hz: f64, resolved: usize) -> Vec<IdentifiedLoop> {
    let runs: Vec<([f64; 3], IdentifiedLoop)> = (1..=12).map(|seed| identified(toml, seed)).collect();
    let z: Vec<f64> = runs.iter().flat_map(|(z, _)| *z).collect();
    assert_calibrated(&z);
    let loops: Vec<IdentifiedLoop> = runs.into_iter().map(|(_, id)| id).collect();
    let z_bn: Vec<f64> = loops.iter().filter_map(|id| z_bn(id, order, bn_hz)).collect();
    assert!(z_bn.len() >= resolved, "{loops:?}");
    assert!(z_bn.iter().all(|z| z.abs() < 3.0), "{z_bn:?}");
    loops
}

/// The paper's receiver (2nd order, Bn 3 Hz, 1 ms updates) logging the NCO
/// command at 10 Hz, the IMU offset searched: Γ̂ within its σ (the loop's
/// uncertainty in it), the order found, Bn within its σ of 3 Hz, and to a
/// few per cent (what one rate and an unknown offset let the session separate).
#[test]
fn a_3_hz_loop_logged_at_10_hz_is_identified() {
    let loops = assert_identified("[log]\nnco = true\ninterval_s = 0.1\n", 2, 3.0, 10);
    assert!(loops.iter().all(|id| id.sigma_ln_bn < 0.15), "{loops:?}");
}

/// A 3rd-order 10 Hz loop at 5 ms logging at 20 Hz: Γ̂ within its σ; where
/// the 3rd order is told apart, Bn within its σ of 10 Hz.
#[test]
fn a_10_hz_third_order_loop_logged_at_20_hz_is_identified() {
    let toml = "[loop]\norder = 3\nbn_hz = 10.0\ninterval_s = 0.005\n[log]\nnco = true\ninterval_s = 0.05\n";
    assert_identified(toml, 3, 10.0, 8);
}
