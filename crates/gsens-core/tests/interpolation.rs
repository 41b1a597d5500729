//! The regressor's linear interpolation between log epochs and its compensation.

use gsens_core::{DiscretePll, LoopSpec};
use gsens_core::{LoggedPhase, RegressorModel, compensate_interpolation};
use std::f64::consts::TAU;

/// The mean of `a` over [c − T/2, c + T/2] and its mean weighted by the
/// time left in that window, 2(1 − s/T)/T (s from the start): composite
/// Simpson on 64 panels, exact to rounding for these smooth signals.
fn window_means(a: impl Fn(f64) -> f64, c: f64, t: f64) -> (f64, f64) {
    let panels = 64;
    let h = t / panels as f64;
    let (mut mean, mut weighted) = (0.0, 0.0);
    for i in 0..=panels {
        let w = if i == 0 || i == panels {
            1.0
        } else if i % 2 == 1 {
            4.0
        } else {
            2.0
        };
        let s = i as f64 * h;
        let v = a(c - t / 2.0 + s);
        mean += w * v;
        weighted += w * v * 2.0 * (1.0 - s / t);
    }
    (mean * h / 3.0 / t, weighted * h / 3.0 / t)
}

/// φ_a as a correlator sees it against the model fed the log's samples, raw
/// and compensated: the truth is the loop fed, per update, the specific
/// force's mean over its integration and its mean weighted by the time left
/// in it (`step_varying`: a correlator's mean phase), the model the samples
/// at the log rate. The raw model's gain error is −c·(ωh)² with
/// c = [`RegressorModel::interpolation_compensation`]: the linear
/// interpolation's loss (1 − 1/n²)(ωh)²/12 less the (ωT)²/24 a point value
/// has over an integration's mean; compensated it is gone. A 1 ms loop logged
/// at 40 Hz (mean of 25) and a 20 ms loop logged at its own rate (where the
/// point value was all there is to it).
#[test]
fn compensation_removes_the_interpolation_gain_error() {
    let coeffs = LoopSpec::PAPER.coeffs().unwrap();
    for (t_loop, n, logged) in [(0.001, 25u32, LoggedPhase::Mean), (0.02, 1, LoggedPhase::Last)] {
        let h = t_loop * f64::from(n);
        let nn = f64::from(n * n);
        for f_hz in [0.5, 0.9, 1.5] {
            let a = |t: f64| 3.0 * (TAU * f_hz * t).sin() + 1.0 * (TAU * 0.37 * f_hz * t + 1.0).cos();
            let epochs = (60.0 / h) as usize;
            // Truth: update j of epoch k integrates over [t_j − T/2, t_j + T/2].
            let mut pll = DiscretePll::new(coeffs, t_loop);
            pll.settle(a(0.0));
            let truth: Vec<f64> = (1..epochs)
                .map(|k| {
                    let updates = (1..=n).map(|j| {
                        let (mean, weighted) = window_means(a, (k - 1) as f64 * h + f64::from(j) * t_loop, t_loop);
                        pll.step_varying(mean, weighted)
                    });
                    let phases: Vec<f64> = updates.collect();
                    match logged {
                        LoggedPhase::Mean => phases.iter().sum::<f64>() / f64::from(n),
                        LoggedPhase::Last => phases[phases.len() - 1],
                    }
                })
                .collect();
            let run = |samples: &[[f64; 3]]| {
                let mut m = RegressorModel::new(coeffs, t_loop, h, logged).unwrap();
                m.epoch(&samples[0]);
                samples[1..].iter().map(|s| m.epoch(s)[0]).collect::<Vec<f64>>()
            };
            let raw: Vec<[f64; 3]> = (0..epochs).map(|k| [a(k as f64 * h), 0.0, 0.0]).collect();
            let mut comp = raw.clone();
            let model = RegressorModel::new(coeffs, t_loop, h, logged).unwrap();
            let c = model.interpolation_compensation();
            assert!((c - ((1.0 - 1.0 / nn) / 12.0 - 1.0 / (24.0 * nn))).abs() < 1e-15);
            compensate_interpolation(&mut comp, c);
            // Gain of the model on the truth, past the start-up transient.
            let gain = |y: &[f64]| {
                let s = (10.0 / h) as usize;
                let xy: f64 = y[s..].iter().zip(&truth[s..]).map(|(a, b)| a * b).sum();
                let xx: f64 = truth[s..].iter().map(|b| b * b).sum();
                xy / xx
            };
            let (g_raw, g_comp) = (gain(&run(&raw)), gain(&run(&comp)));
            let predicted = -c * (TAU * f_hz * h).powi(2);
            eprintln!(
                "T {t_loop} s, n {n}, {f_hz} Hz: raw gain − 1 = {:.2e} (predicted {predicted:.2e}), compensated {:.2e}",
                g_raw - 1.0,
                g_comp - 1.0
            );
            assert!((g_raw - 1.0 - predicted).abs() < 0.15 * predicted.abs(), "{f_hz} Hz raw {g_raw}");
            assert!((g_comp - 1.0).abs() < 0.05 * predicted.abs(), "{f_hz} Hz compensated {g_comp}");
        }
    }
}

/// The streamed prefilter (`PrefilteredCalibrator`, one epoch late) gives the
/// batch path's estimate: the same epochs, the same Γ̂ to rounding, whether
/// the series is compensated as a whole and fed to a `Calibrator` or
/// streamed; and Γ̂ is the truth (a correlator's phase, as in the test above)
/// while the raw stream's is 0.17 % too large.
#[test]
fn the_streamed_prefilter_is_the_batch_prefilter() {
    use gsens_core::{BatchLeastSquares, Calibrator, PrefilteredCalibrator};
    let coeffs = LoopSpec::PAPER.coeffs().unwrap();
    let (t_loop, n) = (0.001, 25u32);
    let h = t_loop * f64::from(n);
    let gamma = [0.09, 0.08, -0.08];
    let a =
        |t: f64| [0, 1, 2].map(|i| 3.0 * (TAU * 0.9 * t + i as f64).sin() + (TAU * (0.5 + 0.3 * i as f64) * t).cos());
    let epochs = (90.0 / h) as usize;
    // The receiver's φ: its loop fed aᵀΓ at every update, the mean of the n outputs logged.
    let mut pll = DiscretePll::new(coeffs, t_loop);
    let df = |t: f64| {
        let s = a(t);
        s[0] * gamma[0] + s[1] * gamma[1] + s[2] * gamma[2]
    };
    pll.settle(df(0.0));
    let phase: Vec<f64> = (0..epochs)
        .map(|k| {
            if k == 0 {
                return 0.0;
            }
            (1..=n)
                .map(|j| {
                    let (mean, weighted) = window_means(df, (k - 1) as f64 * h + f64::from(j) * t_loop, t_loop);
                    pll.step_varying(mean, weighted)
                })
                .sum::<f64>()
                / f64::from(n)
        })
        .collect();
    let accel: Vec<[f64; 3]> = (0..epochs).map(|k| a(k as f64 * h)).collect();
    let model = || RegressorModel::new(coeffs, t_loop, h, LoggedPhase::Mean).unwrap();
    let skip = (4.0 / h) as u64;
    let cal = || Calibrator::new(model(), BatchLeastSquares::new(), skip, 0.0, h);
    // Batch: compensate the whole series, then feed.
    let mut comp = accel.clone();
    compensate_interpolation(&mut comp, model().interpolation_compensation());
    let mut batch = cal();
    for (x, p) in comp.iter().zip(&phase) {
        batch.feed(x, Some(*p));
    }
    // Streamed, one epoch late.
    let mut streamed = PrefilteredCalibrator::new(cal());
    let mut out = 0;
    for (x, p) in accel.iter().zip(&phase) {
        out += usize::from(streamed.feed(x, Some(*p)).is_some());
    }
    out += usize::from(streamed.flush().is_some());
    assert_eq!(out, epochs);
    // Raw, as the streaming Calibrator alone would.
    let mut raw = cal();
    for (x, p) in accel.iter().zip(&phase) {
        raw.feed(x, Some(*p));
    }
    let (gb, gs, gr) =
        (batch.estimate().gamma_hz_per_mps2, streamed.estimate().gamma_hz_per_mps2, raw.estimate().gamma_hz_per_mps2);
    let predicted = (TAU * 0.9 * h).powi(2) * model().interpolation_compensation();
    for i in 0..3 {
        assert!((gs[i] - gb[i]).abs() <= 1e-12 * gb[i].abs(), "axis {i}: streamed {} vs batch {}", gs[i], gb[i]);
        assert!((gs[i] / gamma[i] - 1.0).abs() < 0.2 * predicted, "axis {i}: {} vs {}", gs[i], gamma[i]);
        assert!(gr[i] / gamma[i] - 1.0 > 0.5 * predicted, "axis {i}: the raw stream's bias {}", gr[i] / gamma[i] - 1.0);
    }
}
