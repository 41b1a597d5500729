//! Estimators against synthetic data generated through the same discrete loop.

use gsens_core::*;
use gsens_core::{DiscretePll, LoopSpec};
use gsens_core::{LoggedPhase, RegressorModel};
use gsens_core::{ObservabilityCriteria, assess};
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
/// same linear interpolation of a between log epochs as the model, and the
/// same weighting of Δf by the time left in each integration), plus noise.
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
            let lead: f64 = (0..3).map(|i| (a[i] - prev[i]) / (6.0 * substeps as f64) * GAMMA[i]).sum();
            last = truth.step_varying(df, df - lead);
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

/// Seeds per σ-honesty test: the spread of N independent z-scores has a
/// standard error of ≈ 1/√(2N), and 3 of them must be ≤ 0.05 (N ≥ 1800).
const SIGMA_SEEDS: u64 = 2000;

/// Tolerance on the spread of `n` independent z-scores: 3 standard errors of
/// the sample SD of N(0,1) about its known mean 0, 3/√(2n) (Var z² = 2, and
/// SD = √(mean z²) halves the relative error).
fn three_se_of_spread(n: usize) -> f64 {
    3.0 / (2.0 * n as f64).sqrt()
}

/// Spread √(mean z²) of each axis' z-scores over the seeds. Per axis because
/// the three components of one estimate are correlated in general (through the
/// off-diagonals of AᵀA), so only the seeds are independent samples.
fn spread_per_axis(zs: &[[f64; 3]]) -> [f64; 3] {
    [0, 1, 2].map(|i| (zs.iter().map(|z| z[i] * z[i]).sum::<f64>() / zs.len() as f64).sqrt())
}

fn assert_spread_is_one(zs: &[[f64; 3]], what: &str) {
    let tol = three_se_of_spread(zs.len());
    let sd = spread_per_axis(zs);
    for i in 0..3 {
        assert!(
            (sd[i] - 1.0).abs() < tol,
            "{what}: spread of z on axis {i} = {} (N = {}, 1 ± {tol:.4})",
            sd[i],
            zs.len()
        );
    }
}

#[test]
fn batch_sigma_is_honest_under_white_noise() {
    // z = (Γ̂ − Γ)/σ̂ over many seeds: ~N(0,1) (Student t with n − 3 ≈ 1200
    // degrees of freedom: SD 1 + 1e-3). At most 1% outside 3σ; spread of each
    // axis 1 ± 3/√(2N) = 1 ± 0.047.
    let mut zs = Vec::new();
    for seed in 0..SIGMA_SEEDS {
        let data = synth(30.0, 1, LoggedPhase::Last, [true; 3], 0.02, 1000 + seed);
        let est = run(BatchLeastSquares::new(), &data);
        let s = est.sigma_hz_per_mps2();
        zs.push([0, 1, 2].map(|i| (est.gamma_hz_per_mps2[i] - GAMMA[i]) / s[i]));
    }
    let outside = zs.iter().flatten().filter(|z| z.abs() > 3.0).count() as f64 / (3 * zs.len()) as f64;
    assert!(outside <= 0.01, "{outside}");
    assert_spread_is_one(&zs, "batch");
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

/// z-scores of the gradient observer with gain `gain_k` over `seeds` seeds:
/// with its reported σ, and with its propagated covariance scaled by the true
/// noise variance instead of its σ̂².
fn gradient_z_scores(gain_k: f64, seeds: u64) -> (Vec<[f64; 3]>, Vec<[f64; 3]>) {
    let noise_rad = 0.02;
    let (mut reported, mut known_noise) = (Vec::new(), Vec::new());
    for seed in 0..seeds {
        let data = synth(60.0, 1, LoggedPhase::Last, [true; 3], noise_rad, 5000 + seed);
        let est = run(GradientObserver::new(gain_k, LOG_T), &data);
        let s = est.sigma_hz_per_mps2();
        let to_known = noise_rad / est.residual_variance_rad2.sqrt();
        let err = [0, 1, 2].map(|i| est.gamma_hz_per_mps2[i] - GAMMA[i]);
        reported.push([0, 1, 2].map(|i| err[i] / s[i]));
        known_noise.push([0, 1, 2].map(|i| err[i] / (s[i] * to_known)));
    }
    (reported, known_noise)
}

#[test]
fn gradient_observer_sigma_matches_its_spread() {
    // The propagated covariance must describe the observer's own scatter: with
    // the true noise variance, and as reported (scaled by σ̂²), each axis'
    // spread of z is 1 ± 3/√(2N) = 1 ± 0.047.
    //
    // At this gain the reported σ is ~2.5% pessimistic: σ̂² = RSS(Γ̂)/(n − 3) is
    // taken at the observer's Γ̂, whose excess scatter over least squares (a
    // memory of some tens of epochs) inflates it, by 3.7% on average here
    // (0.6% at k = 0.1). With these fixed seeds the reported-σ check passes,
    // but only just (axis 1: 0.955 against 1 − 0.047); see
    // `gradient_observer_reported_sigma_at_high_gain_large_n`.
    let (reported, known_noise) = gradient_z_scores(0.5, SIGMA_SEEDS);
    assert_spread_is_one(&known_noise, "gradient, known noise σ");
    assert_spread_is_one(&reported, "gradient, reported σ");
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
