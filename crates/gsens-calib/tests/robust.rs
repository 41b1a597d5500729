//! Huber's M-estimate (`robust = huber`): against outliers it stays on the
//! truth where least squares is pulled; without them it agrees with least squares.

mod common;

use common::{GAMMA, T, paper_session, series};
use gsens_calib::huber_irls;
use gsens_calib::{EstimateSettings, Method, Robust, calibrate};
use gsens_core::HuberWeights;
use rand::{RngExt, SeedableRng};
use rand_distr::{Distribution, StandardNormal};
use rand_xoshiro::Xoshiro256PlusPlus;
use std::f64::consts::TAU;

/// Regressors and φ = φ_aᵀΓ + white noise of `noise_rad`; with `outliers`,
/// 1 % of the epochs get 2 rad of the sign of their g-induced phase (a
/// saturating, slipping channel pulls the average that way).
fn direct(seed: u64, noise_rad: f64, outliers: bool) -> (Vec<f64>, Vec<[f64; 3]>) {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let n = 8000;
    let mut phase = Vec::with_capacity(n);
    let mut phi_a = Vec::with_capacity(n);
    for k in 0..n {
        let t = k as f64 * T;
        let a = [(TAU * 0.9 * t).sin(), (TAU * 0.7 * t + 1.0).sin(), (TAU * 1.1 * t + 2.0).sin()].map(|v| 0.8 * v);
        let g: f64 = (0..3).map(|i| a[i] * GAMMA[i]).sum();
        let e: f64 = StandardNormal.sample(&mut rng);
        let mut p = g + noise_rad * e;
        if outliers && rng.random::<f64>() < 0.01 {
            p = 2.0 * g.signum();
        }
        phase.push(p);
        phi_a.push(a);
    }
    (phase, phi_a)
}

fn least_squares(phase: &[f64], phi_a: &[[f64; 3]]) -> [f64; 3] {
    let mut ne = gsens_core::NormalEquations::default();
    for (p, a) in phase.iter().zip(phi_a) {
        ne.add(*p, a);
    }
    ne.solve().gamma_hz_per_mps2
}

#[test]
fn huber_resists_one_percent_of_outliers_where_least_squares_is_pulled() {
    let (phase, phi_a) = direct(1, 0.01, true);
    let ls = least_squares(&phase, &phi_a);
    let h = huber_irls(&phase, &phi_a, ls, HuberWeights::K_95, 0).unwrap();
    assert!(h.converged, "{h:?}");
    for i in 0..3 {
        let sigma = h.covariance[i][i].sqrt();
        let (err_h, err_ls) = (h.gamma_hz_per_mps2[i] - GAMMA[i], ls[i] - GAMMA[i]);
        eprintln!("axis {i}: Huber {err_h:+.5} ({:+.2}σ), LS {err_ls:+.5} ({:+.1}σ)", err_h / sigma, err_ls / sigma);
        assert!(err_h.abs() < 3.0 * sigma && err_h.abs() < 0.01 * GAMMA[i].abs(), "axis {i}: Huber off by {err_h}");
        assert!(
            err_ls.abs() > 20.0 * sigma && err_ls.abs() > 0.05 * GAMMA[i].abs(),
            "axis {i}: LS off by only {err_ls}"
        );
    }
    // About 1 % of the epochs are beyond the threshold, plus the Gaussian tail beyond 1.345σ (18 %).
    let frac = h.epochs_downweighted as f64 / h.epochs as f64;
    assert!((0.15..0.25).contains(&frac), "{frac}");
}

#[test]
fn without_outliers_huber_agrees_with_least_squares() {
    for seed in 0..5 {
        let (phase, phi_a) = direct(seed, 0.01, false);
        let ls = least_squares(&phase, &phi_a);
        let h = huber_irls(&phase, &phi_a, ls, HuberWeights::K_95, 0).unwrap();
        for i in 0..3 {
            let sigma = h.covariance[i][i].sqrt();
            // 95 % efficiency: Huber and LS differ by ~0.23σ at most typically.
            assert!((h.gamma_hz_per_mps2[i] - ls[i]).abs() < 0.5 * sigma, "seed {seed} axis {i}");
            // The sandwich σ is the LS σ within a few %.
            let n = phase.len() as f64;
            let s2 = phase
                .iter()
                .zip(&phi_a)
                .map(|(p, a)| (p - (0..3).map(|j| a[j] * ls[j]).sum::<f64>()).powi(2))
                .sum::<f64>()
                / (n - 3.0);
            let ls_sigma = (s2 / (0..phase.len()).map(|k| phi_a[k][i] * phi_a[k][i]).sum::<f64>()).sqrt();
            assert!((sigma / ls_sigma - 1.0).abs() < 0.1, "seed {seed} axis {i}: {sigma} vs {ls_sigma}");
        }
    }
}

/// The paper-like session with white noise of 0.005 rad and, with
/// `outliers`, 1 % of the epochs off by 1.5 rad.
fn session(seed: u64, outliers: bool) -> (Vec<Option<f64>>, Vec<[f64; 3]>) {
    paper_session(seed, true, |rng, _, phi| {
        let e: f64 = StandardNormal.sample(rng);
        let mut p = phi + 0.005 * e;
        if outliers && rng.random::<f64>() < 0.01 {
            p = phi + 1.5 * phi.signum();
        }
        Some(p)
    })
}

#[test]
fn calibrate_with_huber() {
    let times = common::times(3200);
    let run = |outliers: bool, robust: Robust| {
        let (phase, accel) = session(3, outliers);
        let series = series(&times, &phase, &accel);
        calibrate(&series, &EstimateSettings::default().with_robust(robust)).unwrap()
    };
    let (ls, huber) = (run(true, Robust::None), run(true, Robust::Huber));
    let (ls_clean, huber_clean) = (run(false, Robust::None), run(false, Robust::Huber));
    let h = huber.huber.as_ref().expect("the Huber fit is reported");
    assert!(h.converged && h.epochs_downweighted > 0);
    assert!(ls.huber.is_none());
    for i in 0..3 {
        let (g_h, s_h) = (huber.gamma_hz_per_mps2[i].unwrap(), huber.sigma_hz_per_mps2[i].unwrap());
        let g_ls = ls.gamma_hz_per_mps2[i].unwrap();
        eprintln!(
            "axis {i}: Huber {:+.5} ± {s_h:.5}, LS {:+.5} ± {:.5}",
            g_h - GAMMA[i],
            g_ls - GAMMA[i],
            ls.sigma_hz_per_mps2[i].unwrap()
        );
        assert!((g_h - GAMMA[i]).abs() < 3.0 * s_h && (g_h - GAMMA[i]).abs() < 0.02 * GAMMA[i].abs(), "axis {i}");
        assert!((g_ls - GAMMA[i]).abs() > 3.0 * (g_h - GAMMA[i]).abs().max(s_h), "axis {i}: LS not pulled");
        // Without outliers the two agree (well within σ).
        let (a, b) = (huber_clean.gamma_hz_per_mps2[i].unwrap(), ls_clean.gamma_hz_per_mps2[i].unwrap());
        assert!((a - b).abs() < 0.5 * ls_clean.sigma_hz_per_mps2[i].unwrap(), "axis {i}: {a} vs {b}");
    }
    let json = serde_json::to_value(&huber).unwrap();
    assert_eq!(json["settings"]["robust"], "huber");
    assert!(json["huber"]["threshold_rad"].as_f64().unwrap() > 0.0);
}

#[test]
fn huber_needs_the_batch_method() {
    let times = common::times(3200);
    let (phase, accel) = session(3, false);
    let series = series(&times, &phase, &accel);
    for method in [Method::Rls { lambda: 1.0 }, Method::Gradient { gain_k: 0.5 }, Method::Gls] {
        let e = calibrate(&series, &EstimateSettings::default().with_robust(Robust::Huber).with_method(method))
            .unwrap_err()
            .to_string();
        assert!(e.contains("batch method"), "{e}");
    }
}
