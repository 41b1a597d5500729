//! The synthetic sessions the calibration tests share.
#![allow(dead_code)]

use gsens_calib::EpochSeries;
use gsens_core::{DiscretePll, LoopSpec};
use rand::SeedableRng;
use rand_xoshiro::Xoshiro256PlusPlus;
use std::f64::consts::{PI, TAU};

/// The paper's Γ [Hz/(m/s²)].
pub(crate) const GAMMA: [f64; 3] = [0.09, 0.08, -0.08];
/// Log (and loop) interval [s].
pub(crate) const T: f64 = 0.025;

/// Epoch times k·T.
pub(crate) fn times(n: usize) -> Vec<f64> {
    (0..n).map(|k| k as f64 * T).collect()
}

/// The estimator's view of a series on the grid `t_s`.
pub(crate) fn series<'a>(t_s: &'a [f64], phase: &'a [Option<f64>], accel: &'a [[f64; 3]]) -> EpochSeries<'a> {
    EpochSeries { log_interval_s: T, t_s, phase_err_rad: phase, accel_mps2: accel, imu_time_offset_s: 0.0 }
}

/// A paper-like 80 s session: x, then y, then z (unless `shake_z` is false)
/// shaken for 20 s each at 0.9 Hz with 5 s rests; φ from the paper's discrete
/// loop at T, plus `noise(rng, φ)` (which returns the logged phase, `None`
/// for a gap).
pub(crate) fn paper_session(
    seed: u64,
    shake_z: bool,
    mut noise: impl FnMut(&mut Xoshiro256PlusPlus, usize, f64) -> Option<f64>,
) -> (Vec<Option<f64>>, Vec<[f64; 3]>) {
    let n = (80.0 / T) as usize;
    let mut pll = DiscretePll::new(LoopSpec::PAPER.coeffs().unwrap(), T);
    pll.settle(9.80665 * GAMMA[2]);
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let mut phase = Vec::with_capacity(n);
    let mut accel = Vec::with_capacity(n);
    for k in 0..n {
        let t = k as f64 * T;
        let mut a = [0.0, 0.0, 9.80665];
        let axis = ((t - 5.0) / 25.0).floor();
        let within = (t - 5.0) - 25.0 * axis;
        if (0.0..3.0).contains(&axis) && within < 20.0 && (axis < 2.0 || shake_z) {
            a[axis as usize] += 3.0 * (TAU * 0.9 * within).sin() * (PI * within / 20.0).sin();
        }
        let df: f64 = (0..3).map(|i| a[i] * GAMMA[i]).sum();
        phase.push(noise(&mut rng, k, pll.step(df)));
        accel.push(a);
    }
    (phase, accel)
}
