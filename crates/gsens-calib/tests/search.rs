//! The joint fit of Γ with the time offset and the loop on synthetic
//! sessions with known truth.

use gsens_calib::{EpochSeries, EstimateSettings, JointSpec, calibrate, joint_fit};
use gsens_core::LoopModel;
use gsens_core::{DiscretePll, LoopSpec};
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};
use rand_xoshiro::Xoshiro256PlusPlus;
use std::f64::consts::{FRAC_1_SQRT_2, PI, TAU};

const GAMMA: [f64; 3] = [0.09, 0.08, -0.08];
const OFFSET_ONLY: JointSpec =
    JointSpec { natural_frequency: false, damping: false, offset_max_abs_s: Some(0.2), loop_tolerance: None };
/// The loop's natural frequency fitted and the stated loop tested as exact.
const LOOP_ONLY: JointSpec =
    JointSpec { natural_frequency: true, damping: false, offset_max_abs_s: None, loop_tolerance: Some(0.0) };
const T: f64 = 0.025;

/// Paper-like motion: x, y, z shaken 20 s each at ~0.9 Hz with rests.
fn accel(t: f64) -> [f64; 3] {
    accel_swept(t, 0.0)
}

/// The same with the shaking rate swept by ±`sweep` (relative) within each
/// axis: f(t) = 0.9·(1 + sweep·(2u − 1)), u the fraction of the segment.
fn accel_swept(t: f64, sweep: f64) -> [f64; 3] {
    let mut a = [0.0, 0.0, 9.80665];
    let axis = ((t - 5.0) / 25.0).floor();
    let within = (t - 5.0) - 25.0 * axis;
    if (0.0..3.0).contains(&axis) && within < 20.0 {
        // Phase of a linear chirp from 0.9(1 − sweep) to 0.9(1 + sweep) Hz over 20 s.
        let f0 = 0.9 * (1.0 - sweep);
        let k = 0.9 * 2.0 * sweep / 20.0;
        let phase = TAU * (f0 * within + 0.5 * k * within * within);
        a[axis as usize] += 3.0 * phase.sin() * (PI * within / 20.0).sin();
    }
    a
}

/// φ from the true loop `truth` at the true times; the IMU series as logged
/// with a time offset (sample stamped t taken at t − offset).
fn session(
    truth: LoopSpec,
    imu_offset_s: f64,
    noise_rad: f64,
    seed: u64,
) -> (Vec<f64>, Vec<Option<f64>>, Vec<[f64; 3]>) {
    session_swept(truth, imu_offset_s, noise_rad, seed, 0.0)
}

fn session_swept(
    truth: LoopSpec,
    imu_offset_s: f64,
    noise_rad: f64,
    seed: u64,
    sweep: f64,
) -> (Vec<f64>, Vec<Option<f64>>, Vec<[f64; 3]>) {
    let accel = |t: f64| accel_swept(t, sweep);
    let n = (80.0 / T) as usize;
    let mut pll = DiscretePll::new(truth.coeffs().unwrap(), T);
    pll.settle(9.80665 * GAMMA[2]);
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let noise = Normal::new(0.0, noise_rad).unwrap();
    let mut t_s = Vec::new();
    let mut phase = Vec::new();
    let mut imu = Vec::new();
    for k in 0..n {
        let t = k as f64 * T;
        let a = accel(t);
        let phi = pll.step((0..3).map(|i| a[i] * GAMMA[i]).sum()) + noise.sample(&mut rng);
        t_s.push(t);
        phase.push(Some(phi));
        imu.push(accel(t - imu_offset_s));
    }
    (t_s, phase, imu)
}

#[test]
fn a_30_ms_imu_offset_is_found_within_2_ms_and_its_bias_removed() {
    let (t_s, phase, imu) = session(LoopSpec::PAPER, 0.030, 0.01, 1);
    let series =
        EpochSeries { log_interval_s: T, t_s: &t_s, phase_err_rad: &phase, accel_mps2: &imu, imu_time_offset_s: 0.0 };
    let settings = EstimateSettings::default();
    let biased = calibrate(&series, &settings).unwrap();
    let fit = joint_fit(&series, &settings, OFFSET_ONLY).unwrap();
    let (offset_s, sigma_s) = (fit.imu_time_offset_s.unwrap(), fit.sigma_imu_time_offset_s.unwrap());
    assert!((offset_s - 0.030).abs() < 3.0 * sigma_s, "{fit:?}");
    assert!(sigma_s < 0.002, "{fit:?}");
    // Re-sample the IMU at the found offset (true time t ↔ IMU stamp t + offset).
    let fixed_imu: Vec<[f64; 3]> = t_s.iter().map(|&t| accel(t + offset_s - 0.030)).collect();
    let series2 = EpochSeries { accel_mps2: &fixed_imu, imu_time_offset_s: offset_s, ..series };
    let fixed = calibrate(&series2, &settings).unwrap();
    let rel = |c: &gsens_calib::Calibration| {
        (0..3).map(|i| (c.gamma_hz_per_mps2[i].unwrap() - GAMMA[i]).powi(2)).sum::<f64>().sqrt() / 0.142
    };
    // cos(2π·0.9·0.03) ≈ 0.984 plus a quadrature part: ~2 % before, ≪ 1 % after.
    let (t2, p2, i2) = session(LoopSpec::PAPER, 0.0, 0.01, 1);
    let clean = calibrate(
        &EpochSeries { log_interval_s: T, t_s: &t2, phase_err_rad: &p2, accel_mps2: &i2, imu_time_offset_s: 0.0 },
        &settings,
    )
    .unwrap();
    eprintln!(
        "rel err: offset ignored {:.4}, estimated {:.4}, no offset {:.4}",
        rel(&biased),
        rel(&fixed),
        rel(&clean)
    );
    assert!(rel(&biased) > 0.01, "{}", rel(&biased));
    assert!((rel(&fixed) - rel(&clean)).abs() < 0.002, "{} vs {}", rel(&fixed), rel(&clean));
}

#[test]
fn no_offset_is_found_where_there_is_none() {
    let (t_s, phase, imu) = session(LoopSpec::PAPER, 0.0, 0.01, 2);
    let series =
        EpochSeries { log_interval_s: T, t_s: &t_s, phase_err_rad: &phase, accel_mps2: &imu, imu_time_offset_s: 0.0 };
    let fit = joint_fit(&series, &EstimateSettings::default(), OFFSET_ONLY).unwrap();
    let (offset_s, sigma_s) = (fit.imu_time_offset_s.unwrap(), fit.sigma_imu_time_offset_s.unwrap());
    assert!(offset_s.abs() < 3.0 * sigma_s && sigma_s < 0.002, "{fit:?}");
}

#[test]
fn a_loop_assumed_10_percent_off_is_detected_and_corrected() {
    let truth = LoopSpec::PAPER;
    let (t_s, phase, imu) = session(truth, 0.0, 0.01, 3);
    let series =
        EpochSeries { log_interval_s: T, t_s: &t_s, phase_err_rad: &phase, accel_mps2: &imu, imu_time_offset_s: 0.0 };
    for bn in [3.3, 2.7] {
        let assumed = EstimateSettings::default()
            .with_loop(LoopModel::kaplan(LoopSpec::SecondOrder { bn_hz: bn, zeta: FRAC_1_SQRT_2 }, None));
        let wrong = calibrate(&series, &assumed).unwrap();
        let id = joint_fit(&series, &assumed, LOOP_ONLY).unwrap();
        assert!(id.stated_loop_rejected, "Bn {bn}: {id:?}");
        let f = id.natural_frequency_hz.unwrap();
        assert!((f - 0.9003).abs() < 3.0 * id.sigma_natural_frequency_hz.unwrap(), "Bn {bn}: {id:?}");
        let fixed = calibrate(&series, &assumed.with_loop(id.fitted(&assumed.loop_at(T)))).unwrap();
        let err = |c: &gsens_calib::Calibration| {
            (0..3).map(|i| (c.gamma_hz_per_mps2[i].unwrap() / GAMMA[i] - 1.0).abs()).fold(0.0, f64::max)
        };
        assert!(err(&wrong) > 0.05, "Bn {bn}: the wrong loop should bias Γ̂ by several %: {}", err(&wrong));
        assert!(err(&fixed) < 0.01, "Bn {bn}: {} after identification", err(&fixed));
    }
    // The right loop is not rejected.
    let id = joint_fit(&series, &EstimateSettings::default(), LOOP_ONLY).unwrap();
    assert!(!id.stated_loop_rejected, "{id:?}");
}

#[test]
fn loop_and_time_offset_identified_together() {
    // 30 ms IMU offset and a loop assumed 10 % too wide: a phase error of the
    // loop mimics a time offset at one shaking frequency, so the two are
    // profiled jointly, and the shaking rate must vary (here swept ±40 %).
    let (t_s, phase, imu) = session_swept(LoopSpec::PAPER, 0.030, 0.01, 4, 0.4);
    let series =
        EpochSeries { log_interval_s: T, t_s: &t_s, phase_err_rad: &phase, accel_mps2: &imu, imu_time_offset_s: 0.0 };
    let assumed = EstimateSettings::default()
        .with_loop(LoopModel::kaplan(LoopSpec::SecondOrder { bn_hz: 3.3, zeta: FRAC_1_SQRT_2 }, None));
    let id = joint_fit(&series, &assumed, JointSpec { offset_max_abs_s: Some(0.2), ..LOOP_ONLY }).unwrap();
    eprintln!("{id:?}");
    assert!(id.stated_loop_rejected, "{id:?}");
    let f = id.natural_frequency_hz.unwrap();
    assert!((f - 0.9003).abs() < 3.0 * id.sigma_natural_frequency_hz.unwrap(), "{id:?}");
    let offset_s = id.imu_time_offset_s.unwrap();
    assert!((offset_s - 0.030).abs() < 3.0 * id.sigma_imu_time_offset_s.unwrap(), "{id:?}");
    // Not knowing the loop and the offset costs σ, and the fit says how much.
    assert!(id.variance_inflation.iter().all(|r| *r > 1.0), "{id:?}");
}

#[test]
fn a_stated_loop_and_its_tolerance_combine_as_two_gaussian_measurements() {
    // One shaking rate, the loop stated 10 % narrow: the data's ln ŝ and the
    // prior ln s ~ N(0, t²) combine in closed form (joint_fit's docs).
    let (t_s, phase, imu) = session(LoopSpec::PAPER, 0.0, 0.01, 5);
    let series =
        EpochSeries { log_interval_s: T, t_s: &t_s, phase_err_rad: &phase, accel_mps2: &imu, imu_time_offset_s: 0.0 };
    let assumed = EstimateSettings::default()
        .with_loop(LoopModel::kaplan(LoopSpec::SecondOrder { bn_hz: 2.7, zeta: FRAC_1_SQRT_2 }, None));
    let spec = |loop_tolerance| JointSpec { offset_max_abs_s: Some(0.2), loop_tolerance, ..LOOP_ONLY };
    let free = joint_fit(&series, &assumed, spec(None)).unwrap();
    let (f, f0, sf) = (
        free.natural_frequency_hz.unwrap(),
        free.stated_natural_frequency_hz.unwrap(),
        free.sigma_natural_frequency_hz.unwrap(),
    );
    let (ln_s, c_ss) = ((f / f0).ln(), (sf / f).powi(2));
    // Nothing claimed of the loop: Γ̂ under the fitted loop, nothing rejected.
    assert!(!free.stated_loop_rejected && free.used_natural_frequency_hz == Some(f), "{free:?}");
    let mut variances = vec![free.gamma_covariance_hz_per_mps2_sq[0][0]];
    for tol in [0.05, 0.02, 0.0] {
        let fit = joint_fit(&series, &assumed, spec(Some(tol))).unwrap();
        let w = tol * tol / (c_ss + tol * tol);
        let z = ln_s / (c_ss + tol * tol).sqrt();
        assert!((fit.loop_test_z.unwrap() - z).abs() < 1e-9, "tolerance {tol}: {fit:?}");
        assert_eq!(fit.stated_loop_rejected, z.abs() > gsens_calib::LOOP_TEST_Z, "tolerance {tol}");
        if fit.stated_loop_rejected {
            // Rejected: Γ̂ is the free fit's, under the fitted loop.
            assert_eq!(fit.gamma_hz_per_mps2, free.gamma_hz_per_mps2);
            continue;
        }
        let used = fit.used_natural_frequency_hz.unwrap();
        assert!((used / (f0 * (w * ln_s).exp()) - 1.0).abs() < 1e-9, "tolerance {tol}: {fit:?}");
        let sigma_used = fit.sigma_used_natural_frequency_hz.unwrap();
        assert!((sigma_used - (w * c_ss).sqrt() * used).abs() < 1e-9 * used, "tolerance {tol}: {fit:?}");
        variances.push(fit.gamma_covariance_hz_per_mps2_sq[0][0]);
    }
    // The tighter the tolerance, the smaller Γ̂'s variance.
    assert!(variances.windows(2).all(|v| v[1] < v[0]), "{variances:?}");
    // 10 % off is within about 2σ of a 5 % tolerance but rejected as exact.
    assert!(!joint_fit(&series, &assumed, spec(Some(0.05))).unwrap().stated_loop_rejected);
    assert!(joint_fit(&series, &assumed, spec(Some(0.0))).unwrap().stated_loop_rejected);
}
