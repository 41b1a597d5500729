//! The regressor's linear interpolation between log epochs and its compensation.

use gsens_core::{DiscretePll, LoopSpec};
use gsens_core::{LoggedPhase, RegressorModel, compensate_interpolation};
use std::f64::consts::TAU;

/// φ_a from the exact specific force at every 1 ms loop update (what the
/// receiver's oscillator feels) against the model fed the 40 Hz samples, raw
/// and compensated: the least-squares gain of the model's output on the truth.
#[test]
fn compensation_removes_the_interpolation_gain_error() {
    let coeffs = LoopSpec::PAPER.coeffs().unwrap();
    let (t_loop, n) = (0.001, 25u32);
    let h = t_loop * f64::from(n);
    for f_hz in [0.5, 0.9, 1.5] {
        let a = |t: f64| 3.0 * (TAU * f_hz * t).sin() + 1.0 * (TAU * 0.37 * f_hz * t + 1.0).cos();
        let epochs = (60.0 / h) as usize;
        // Truth: the loop fed a(t) at every update, mean of the n outputs per epoch.
        let mut pll = DiscretePll::new(coeffs, t_loop);
        pll.settle(a(0.0));
        let truth: Vec<f64> = (1..epochs)
            .map(|k| {
                (1..=n).map(|j| pll.step(a((k - 1) as f64 * h + f64::from(j) * t_loop))).sum::<f64>() / f64::from(n)
            })
            .collect();
        let run = |samples: &[[f64; 3]]| {
            let mut m = RegressorModel::new(coeffs, t_loop, h, LoggedPhase::Mean).unwrap();
            m.epoch(&samples[0]);
            samples[1..].iter().map(|s| m.epoch(s)[0]).collect::<Vec<f64>>()
        };
        let raw: Vec<[f64; 3]> = (0..epochs).map(|k| [a(k as f64 * h), 0.0, 0.0]).collect();
        let mut comp = raw.clone();
        let model = RegressorModel::new(coeffs, t_loop, h, LoggedPhase::Mean).unwrap();
        let c = model.interpolation_compensation();
        assert!((c - (1.0 - 1.0 / 625.0) / 12.0).abs() < 1e-15);
        compensate_interpolation(&mut comp, c);
        // Gain of the model on the truth, past the start-up transient.
        let gain = |y: &[f64]| {
            let s = 400;
            let xy: f64 = y[s..].iter().zip(&truth[s..]).map(|(a, b)| a * b).sum();
            let xx: f64 = truth[s..].iter().map(|b| b * b).sum();
            xy / xx
        };
        let (g_raw, g_comp) = (gain(&run(&raw)), gain(&run(&comp)));
        let predicted = (TAU * f_hz * h).powi(2) * (1.0 - 1.0 / 625.0) / 12.0;
        eprintln!(
            "{f_hz} Hz: raw gain − 1 = {:.2e} (predicted −{predicted:.2e}), compensated {:.2e}",
            g_raw - 1.0,
            g_comp - 1.0
        );
        assert!((g_raw - 1.0 + predicted).abs() < 0.15 * predicted, "{f_hz} Hz raw {g_raw}");
        assert!((g_comp - 1.0).abs() < 0.05 * predicted, "{f_hz} Hz compensated {g_comp}");
    }
    // The loop at the log rate interpolates nothing.
    let m = RegressorModel::new(coeffs, 0.025, 0.025, LoggedPhase::Last).unwrap();
    assert_eq!(m.interpolation_compensation(), 0.0);
}
