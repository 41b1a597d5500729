//! Estimators against synthetic data generated through the same discrete loop.

use gsens_core::estimator::*;
use gsens_core::observability::{ObservabilityCriteria, assess};
use gsens_core::pll::{DiscretePll, LoopSpec};
use gsens_core::regressor::{LoggedPhase, RegressorModel};
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};
use rand_xoshiro::Xoshiro256PlusPlus;
use std::f64::consts::TAU;

const GAMMA: [f64; 3] = [0.09, 0.08, -0.08];
const LOG_T: f64 = 0.025;

/// Specific force with all three axes excited at different frequencies near
/// the loop's peak (and gravity on z, which the loop rejects).
fn accel(t: f64, excite: [bool; 3]) -> [f64; 3] {
    let s = |on: bool, a: f64, f: f64, p: f64| if on { a * (TAU * f * t + p).sin() } else { 0.0 };
    [s(excite[0], 3.0, 0.7, 0.1), s(excite[1], 2.5, 0.95, 1.0), 9.80665 + s(excite[2], 2.0, 1.3, 2.0)]
}

/// (φ, φ_a) pairs: φ from a loop driven by Δf = aᵀΓ at the loop rate (with the
/// same linear interpolation of a between log epochs as the model), plus noise.
fn synth(
    duration_s: f64,
    substeps: u32,
    logged: LoggedPhase,
    excite: [bool; 3],
    noise_rad: f64,
    seed: u64,
) -> Vec<(f64, [f64; 3])> {
    let c = LoopSpec::PAPER.coeffs().unwrap();
    let loop_t = LOG_T / substeps as f64;
    let mut truth = DiscretePll::new(c, loop_t);
    truth.settle((0..3).map(|i| accel(0.0, excite)[i] * GAMMA[i]).sum());
    let mut model = RegressorModel::new(c, loop_t, LOG_T, logged).unwrap();
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let noise = Normal::new(0.0, noise_rad.max(1e-300)).unwrap();
    let n = (duration_s / LOG_T) as usize;
    let mut prev = accel(0.0, excite);
    let mut out = Vec::with_capacity(n);
    for k in 0..n {
        let a = accel(k as f64 * LOG_T, excite);
        let mut sum = 0.0;
        let mut last = 0.0;
        for j in 1..=substeps {
            let w = j as f64 / substeps as f64;
            let df: f64 = (0..3).map(|i| (prev[i] + w * (a[i] - prev[i])) * GAMMA[i]).sum();
            last = truth.step(df);
            sum += last;
        }
        prev = a;
        let phi = match logged {
            LoggedPhase::Last => last,
            LoggedPhase::Mean => sum / substeps as f64,
        };
        let phi_a = model.epoch(&a);
        let n = if noise_rad > 0.0 { noise.sample(&mut rng) } else { 0.0 };
        out.push((phi + n, phi_a));
    }
    out
}

fn run<E: GammaEstimator>(mut e: E, data: &[(f64, [f64; 3])]) -> GammaEstimate {
    for (phi, phi_a) in data {
        e.update(*phi, phi_a);
    }
    e.estimate()
}

fn rel_err(g: &[f64; 3]) -> f64 {
    let num: f64 = (0..3).map(|i| (g[i] - GAMMA[i]).powi(2)).sum::<f64>().sqrt();
    num / GAMMA.iter().map(|x| x * x).sum::<f64>().sqrt()
}

#[test]
fn every_estimator_recovers_gamma_noiseless() {
    for (substeps, logged) in [(1, LoggedPhase::Last), (25, LoggedPhase::Last), (25, LoggedPhase::Mean)] {
        let data = synth(120.0, substeps, logged, [true; 3], 0.0, 1);
        let batch = run(BatchLeastSquares::new(), &data);
        let rls = run(RecursiveLeastSquares::new(1.0, RecursiveLeastSquares::DEFAULT_P0), &data);
        let grad = run(GradientObserver::new(2.0, LOG_T), &data);
        for (name, est) in [("batch", batch), ("rls", rls), ("gradient", grad)] {
            let e = rel_err(&est.gamma_hz_per_mps2);
            assert!(e < 1e-6, "{name} substeps={substeps} {logged:?}: rel err {e:e} {:?}", est.gamma_hz_per_mps2);
        }
    }
}

#[test]
fn batch_sigma_is_honest_under_white_noise() {
    // z = (Γ̂ − Γ)/σ̂ over many seeds: ~N(0,1). At most 1% outside 3σ; spread 1 ± 0.15.
    let seeds = 300;
    let mut zs = Vec::new();
    for seed in 0..seeds {
        let data = synth(30.0, 1, LoggedPhase::Last, [true; 3], 0.02, 1000 + seed);
        let est = run(BatchLeastSquares::new(), &data);
        let s = est.sigma_hz_per_mps2();
        for i in 0..3 {
            zs.push((est.gamma_hz_per_mps2[i] - GAMMA[i]) / s[i]);
        }
    }
    let outside = zs.iter().filter(|z| z.abs() > 3.0).count() as f64 / zs.len() as f64;
    let sd = (zs.iter().map(|z| z * z).sum::<f64>() / zs.len() as f64).sqrt();
    assert!(outside <= 0.01, "{outside}");
    assert!((sd - 1.0).abs() < 0.15, "spread of z = {sd}");
}

#[test]
fn rls_without_forgetting_equals_batch_and_its_sigma_too() {
    let data = synth(60.0, 1, LoggedPhase::Last, [true; 3], 0.01, 7);
    let b = run(BatchLeastSquares::new(), &data);
    let r = run(RecursiveLeastSquares::new(1.0, RecursiveLeastSquares::DEFAULT_P0), &data);
    for i in 0..3 {
        let sb = b.sigma_hz_per_mps2()[i];
        assert!((b.gamma_hz_per_mps2[i] - r.gamma_hz_per_mps2[i]).abs() < 1e-3 * sb);
        assert!((sb - r.sigma_hz_per_mps2()[i]).abs() < 1e-3 * sb);
    }
}

#[test]
fn gradient_observer_sigma_matches_its_spread() {
    // The propagated covariance must describe the observer's own scatter.
    let mut zs = Vec::new();
    for seed in 0..100 {
        let data = synth(60.0, 1, LoggedPhase::Last, [true; 3], 0.02, 5000 + seed);
        let est = run(GradientObserver::new(0.5, LOG_T), &data);
        let s = est.sigma_hz_per_mps2();
        for i in 0..3 {
            zs.push((est.gamma_hz_per_mps2[i] - GAMMA[i]) / s[i]);
        }
    }
    let sd = (zs.iter().map(|z| z * z).sum::<f64>() / zs.len() as f64).sqrt();
    assert!((sd - 1.0).abs() < 0.2, "spread of z = {sd}");
}

#[test]
fn gradient_gain_stability_boundary() {
    // Constant regressor on one axis: error × (1 − kT|φ_a|²) per step.
    for (k_t_phi2, stable) in [(1.9, true), (2.1, false)] {
        let phi_a = [1.0, 0.0, 0.0];
        let mut g = GradientObserver::new(k_t_phi2 / LOG_T, LOG_T);
        assert_eq!(g.step_is_stable(&phi_a), stable);
        for _ in 0..500 {
            g.update(0.5, &phi_a);
        }
        let err = (g.estimate().gamma_hz_per_mps2[0] - 0.5).abs();
        assert_eq!(err < 1e-6, stable, "kT|φ|² = {k_t_phi2}: err {err}");
    }
}

#[test]
fn unexcited_axis_is_unobservable() {
    let data = synth(120.0, 1, LoggedPhase::Last, [true, true, false], 0.005, 3);
    let mut b = BatchLeastSquares::new();
    for (phi, phi_a) in &data {
        b.update(*phi, phi_a);
    }
    let est = b.estimate();
    let obs = assess(b.normal_equations(), &est, &ObservabilityCriteria::default());
    assert_eq!(obs.observable, [true, true, false], "{obs:?}");
    assert!(est.sigma_hz_per_mps2()[2].is_infinite());
    assert!(obs.condition_number.is_infinite());
    // The excited axes are still estimated.
    assert!((est.gamma_hz_per_mps2[0] - GAMMA[0]).abs() < 5.0 * est.sigma_hz_per_mps2()[0]);
    assert!((est.gamma_hz_per_mps2[1] - GAMMA[1]).abs() < 5.0 * est.sigma_hz_per_mps2()[1]);
}
