//! The prediction sweep over vibration levels (`SweepSettings::sweep`, what
//! `gsens predict` tabulates): a tone's RMS scales with the level (A·L/√2),
//! level 0 leaves no vibration jitter, the jitter without compensation grows
//! with the level and compensation never makes it worse; bad levels and an
//! unstable loop are errors, not rows.

use gsens_calib::predict::{PredictionInput, SweepError, SweepSettings, Vibration};

fn settings(levels: Vec<f64>) -> SweepSettings {
    SweepSettings {
        base: PredictionInput {
            gamma_hz_per_mps2: [0.09, 0.08, -0.08],
            covariance: [[1e-6, 0.0, 0.0], [0.0, 1e-6, 0.0], [0.0, 0.0, 4e-6]],
            vibration: Vibration::Tones(vec![(0.91, [3.0, 0.0, 0.0])]),
            oscillator: None,
            cn0_dbhz: Some(45.0),
            delay_s: 0.005,
            imu_noise_mps2_per_rthz: 0.0,
            doppler_rate_hz_per_s: 0.0,
        },
        levels,
        bn_hz: 3.0,
        zeta: std::f64::consts::FRAC_1_SQRT_2,
        loop_interval_s: 0.001,
    }
}

#[test]
fn rows_scale_with_the_level_and_compensation_never_hurts() {
    let sweep = settings(vec![0.0, 1.0, 2.0, 4.0]).sweep().unwrap();
    assert_eq!(sweep.predictions.len(), 4);
    let r0 = &sweep.predictions[0];
    assert_eq!(r0.vibration_rad, [0.0, 0.0]);
    for r in &sweep.predictions {
        let expected = 3.0 * r.level / 2f64.sqrt();
        assert!((r.vibration_rms_mps2[0] - expected).abs() < 1e-12, "{r:?}");
        assert!(r.vibration_rad[1] <= r.vibration_rad[0] && r.total_rad[1] <= r.total_rad[0], "{r:?}");
    }
    for w in sweep.predictions.windows(2) {
        assert!(w[1].vibration_rad[0] > w[0].vibration_rad[0]);
        // Without compensation, the jitter is linear in the level.
        if w[0].level > 0.0 {
            let ratio = w[1].vibration_rad[0] / w[0].vibration_rad[0];
            assert!((ratio - w[1].level / w[0].level).abs() < 1e-9, "{ratio}");
        }
    }
}

#[test]
fn bad_levels_and_unstable_loops_are_errors() {
    assert_eq!(settings(vec![1.0, -1.0]).sweep().unwrap_err(), SweepError::Level(-1.0));
    assert!(matches!(settings(vec![f64::NAN]).sweep().unwrap_err(), SweepError::Level(l) if l.is_nan()));
    let mut unstable = settings(vec![1.0]);
    unstable.bn_hz = 200.0;
    unstable.loop_interval_s = 0.02;
    assert!(matches!(unstable.sweep().unwrap_err(), SweepError::Loop { .. }));
}
