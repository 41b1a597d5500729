//! `gsens_calib::predict` against the simulator: the g-induced phase jitter
//! of the paper's loop under sine vibration at three levels (and periods),
//! without and with compensation, predicted and simulated within 10 %.
//!
//! The simulated jitter is a run's true phase error less that of the same
//! session without g-sensitivity (`gsens_sim::compensation_trial`), over the
//! inside of each shaking segment (its ramps left out); the IMU is ideal at
//! 40 Hz, so the feed-forward's delay is the hold's half sample, 12.5 ms.

use gsens_calib::predict::{PredictionInput, Vibration, jitter, second_order_loop};
use gsens_sim::compensation::CompensationSection;
use gsens_sim::compensation_trial::run_trial;
use gsens_sim::imu::ImuPreset;
use gsens_sim::motion::{Axis, MotionConfig, Segment};
use gsens_sim::scenario::Scenario;

fn rms(v: impl Iterator<Item = f64>) -> f64 {
    let (s, n) = v.fold((0.0, 0usize), |(s, n), x| (s + x * x, n + 1));
    (s / n as f64).sqrt()
}

#[test]
fn predicted_and_simulated_jitter_agree_at_three_vibration_levels() {
    for (amplitude_mps2, period_s) in [(1.0, 2.0), (2.0, 1.1), (3.0, 0.7)] {
        let mut s = Scenario::default();
        s.imu.preset = ImuPreset::Ideal;
        s.imu.time_offset_s = 0.0;
        let mut shake = Segment::shake(Axis::X, 40.0, period_s, amplitude_mps2);
        if let Segment::Shake(sh) = &mut shake {
            sh.jitter.period_rel = 0.0;
            sh.jitter.amplitude_rel = 0.0;
        }
        s.motion = MotionConfig { segments: vec![Segment::rest(10.0), shake, Segment::rest(5.0)] };
        let gamma = s.oscillator.gamma_hz_per_mps2;
        // Γ̂ 5 % off on x, as a calibration might leave it.
        let gamma_hat = [gamma[0] * 1.05, gamma[1], gamma[2]];
        let trial = run_trial(&s, 4, &CompensationSection { gamma_hz_per_mps2: gamma_hat, latency_s: 0.0 }).unwrap();
        let trace = trial.trace.as_ref().unwrap();
        // Inside the shaking (10–50 s), its ramps (one period each side) and the loop's settling left out.
        let inside = |t: f64| t > 10.0 + period_s + 2.0 && t < 50.0 - period_s;
        let pick = |v: &[f64]| rms(trace.t_s.iter().zip(v).filter(|(t, _)| inside(**t)).map(|(_, x)| *x));
        let simulated = [pick(&trace.uncompensated_rad), pick(&trace.compensated_rad)];

        let l = &s.tracking_loop;
        let receiver_loop = second_order_loop(l.bn_hz, l.zeta, l.interval_s);
        let sigma_x = 0.05 * gamma[0];
        let input = PredictionInput {
            gamma_hz_per_mps2: gamma_hat,
            covariance: [[sigma_x * sigma_x, 0.0, 0.0], [0.0; 3], [0.0; 3]],
            vibration: Vibration::Tones(vec![(1.0 / period_s, [amplitude_mps2, 0.0, 0.0])]),
            oscillator: None,
            cn0_dbhz: None,
            delay_s: 0.5 / s.imu.rate_hz,
            imu_noise_mps2_per_rthz: 0.0,
            doppler_rate_hz_per_s: 0.0,
        };
        let predicted = jitter(&receiver_loop, l.bn_hz, l.interval_s, &input).vibration_rad;
        // The prediction takes Γ as Γ̂ (5 % larger): scale its uncompensated part back to the true Γ.
        let predicted = [predicted[0] / 1.05, predicted[1]];
        for k in 0..2 {
            let ratio = predicted[k] / simulated[k];
            eprintln!(
                "A {amplitude_mps2} m/s², period {period_s} s, {}: predicted {:.5} rad, simulated {:.5} rad (×{ratio:.3})",
                ["without", "with"][k],
                predicted[k],
                simulated[k]
            );
            assert!((ratio - 1.0).abs() <= 0.10, "{amplitude_mps2} m/s², {period_s} s, case {k}: ×{ratio}");
        }
    }
}

/// Without vibration: the thermal and oscillator parts against the simulator's
/// true phase error (its mean removed: the loop's initial ambiguity), channel
/// by channel (each at its own C/N0), OCXO and TCXO. Measured: ×0.96 to ×1.04
/// (OCXO, thermal noise dominates), ×1.04 to ×1.06 (TCXO, its phase noise).
#[test]
fn predicted_and_simulated_noise_jitter_agree() {
    use gsens_sim::scenario::OscillatorKind;
    use gsens_sim::session::{MemorySink, simulate};
    for kind in [OscillatorKind::Ocxo, OscillatorKind::Tcxo] {
        let mut s = Scenario::default();
        s.oscillator.preset = kind;
        s.oscillator.gamma_hz_per_mps2 = [0.0; 3];
        s.motion = MotionConfig { segments: vec![Segment::rest(60.0)] };
        let mut sink = MemorySink::default();
        simulate(&s, 6, &mut sink, |_| {}).unwrap();
        let o = s.oscillator.config();
        let l = &s.tracking_loop;
        let receiver_loop = second_order_loop(l.bn_hz, l.zeta, l.interval_s);
        let mut channels: Vec<u32> = sink.tracking.iter().map(|r| r.channel).collect();
        channels.sort_unstable();
        channels.dedup();
        for c in channels {
            let rows: Vec<_> = sink.tracking.iter().filter(|r| r.channel == c && r.t_s > 5.0).collect();
            let mean = rows.iter().map(|r| r.true_phase_err_rad).sum::<f64>() / rows.len() as f64;
            let simulated = rms(rows.iter().map(|r| r.true_phase_err_rad - mean));
            let cn0 = rows.iter().map(|r| r.true_cn0_dbhz).sum::<f64>() / rows.len() as f64;
            let input = PredictionInput {
                gamma_hz_per_mps2: [0.0; 3],
                covariance: [[0.0; 3]; 3],
                vibration: Vibration::Tones(vec![]),
                oscillator: Some(gsens_montecarlo::frequency_noise(&o, s.oscillator.carrier_hz)),
                cn0_dbhz: Some(cn0),
                delay_s: 0.0,
                imu_noise_mps2_per_rthz: 0.0,
                doppler_rate_hz_per_s: 0.0,
            };
            let j = jitter(&receiver_loop, l.bn_hz, l.interval_s, &input);
            let ratio = j.total_rad[0] / simulated;
            eprintln!(
                "{kind:?} ch {c} C/N0 {cn0:.1}: thermal {:.4}, oscillator {:.4}, total {:.4} rad; simulated {simulated:.4} (×{ratio:.3})",
                j.thermal_rad, j.oscillator_rad, j.total_rad[0]
            );
            // ≈ 550 loop-correlation times in 55 s: 3 standard errors of an RMS are ≈ 9 %.
            assert!((ratio - 1.0).abs() <= 0.10, "{kind:?} channel {c}: ×{ratio}");
        }
    }
}
