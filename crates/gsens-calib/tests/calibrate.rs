//! The calibration job on synthetic series: coloured noise, gaps, unobservable axes.

mod common;

use common::{GAMMA, paper_session, series, times};
use gsens_calib::{EstimateSettings, Method, calibrate};
use gsens_core::LoopModel;
use gsens_core::LoopSpec;
use rand_distr::{Distribution, StandardNormal};

/// The paper-like session with AR(1) noise (ρ = 0.97, ~1 s correlation) of
/// `noise_rad` and a gap every 10 s (no channel present).
fn session(seed: u64, noise_rad: f64, shake_z: bool) -> (Vec<Option<f64>>, Vec<[f64; 3]>) {
    let rho: f64 = 0.97;
    let mut ar = 0.0;
    paper_session(seed, shake_z, |rng, k, phi| {
        let e: f64 = StandardNormal.sample(rng);
        ar = rho * ar + (1.0 - rho * rho).sqrt() * e;
        (k % 400 != 399).then_some(phi + noise_rad * ar)
    })
}

#[test]
fn robust_sigma_is_honest_under_coloured_noise_and_white_sigma_is_not() {
    let mut z_robust = Vec::new();
    let mut z_white = Vec::new();
    // 600 seeds × 3 axes: the sample SD of the z-scores has a standard error of
    // 1/√(2·1800) = 0.017, so 3 standard errors are ±0.05.
    for seed in 0..600 {
        let (phase, accel) = session(seed, 0.02, true);
        let t_s = times(phase.len());
        let series = series(&t_s, &phase, &accel);
        let c = calibrate(&series, &EstimateSettings::default()).unwrap();
        for i in 0..3 {
            let err = c.gamma_hz_per_mps2[i].unwrap() - GAMMA[i];
            z_robust.push(err / c.sigma_hz_per_mps2[i].unwrap());
            z_white.push(err / c.sigma_white_hz_per_mps2[i].unwrap());
        }
    }
    let sd = |z: &[f64]| (z.iter().map(|x| x * x).sum::<f64>() / z.len() as f64).sqrt();
    let (r, w) = (sd(&z_robust), sd(&z_white));
    eprintln!("z spread: robust {r:.3}, white {w:.3}");
    assert!((r - 1.0).abs() < 0.05, "robust z spread {r}");
    assert!(w > 1.5, "white z spread {w}: the test noise is not coloured enough to matter");
}

#[test]
fn every_method_recovers_gamma_and_compensation_removes_the_g_part() {
    let (phase, accel) = session(1, 0.002, true);
    let t_s = times(phase.len());
    let series = series(&t_s, &phase, &accel);
    for method in [Method::Batch, Method::Rls { lambda: 1.0 }, Method::Gradient { gain_k: 0.5 }] {
        let settings = EstimateSettings::default().with_method(method);
        let c = calibrate(&series, &settings).unwrap();
        for i in 0..3 {
            let g = c.gamma_hz_per_mps2[i].unwrap();
            assert!((g - GAMMA[i]).abs() < 0.01 * GAMMA[i].abs(), "{method:?} axis {i}: {g}");
        }
        assert!(c.rms_after_rad < 0.3 * c.rms_before_rad, "{method:?}: {} → {}", c.rms_before_rad, c.rms_after_rad);
        assert_eq!(c.observable, [true; 3]);
    }
}

#[test]
fn axis_never_shaken_is_reported_unobservable_not_as_a_number() {
    let (phase, accel) = session(2, 0.005, false);
    let t_s = times(phase.len());
    let series = series(&t_s, &phase, &accel);
    let c = calibrate(&series, &EstimateSettings::default()).unwrap();
    assert_eq!(c.observable, [true, true, false]);
    assert_eq!(c.gamma_hz_per_mps2[2], None);
    assert_eq!(c.sigma_hz_per_mps2[2], None);
    // In the JSON the unobservable axis is null everywhere a number would be
    // read as an estimate, and the document reads back as it was written.
    let v = serde_json::to_value(&c).unwrap();
    for key in ["gamma_hz_per_mps2", "sigma_hz_per_mps2", "gamma_ppb_per_g", "sigma_ppb_per_g", "crlb_hz_per_mps2"] {
        assert!(v[key][2].is_null() && v[key][0].is_number(), "{key}: {}", v[key]);
    }
    let cov = &v["covariance_hz_per_mps2_sq"];
    assert!((0..3).all(|i| cov[2][i].is_null() && cov[i][2].is_null()) && cov[0][1].is_number(), "{cov}");
    assert!((cov[0][0].as_f64().unwrap() / c.sigma_hz_per_mps2[0].unwrap().powi(2) - 1.0).abs() < 1e-12);
    let back: gsens_calib::Calibration = serde_json::from_value(v).unwrap();
    let mut written = c.clone();
    written.history.clear(); // the estimation history is not part of the document
    assert_eq!(back, written);
}

#[test]
fn wrong_loop_interval_is_an_error_not_garbage() {
    let (phase, accel) = session(3, 0.005, true);
    let t_s = times(phase.len());
    let series = series(&t_s, &phase, &accel);
    let settings = EstimateSettings::default().with_loop(LoopModel::kaplan(LoopSpec::PAPER, Some(0.007)));
    let e = calibrate(&series, &settings).unwrap_err().to_string();
    assert!(e.contains("not an integer multiple"), "{e}");
}

#[test]
fn imu_systematic_sigma_matches_monte_carlo_of_the_sensing_matrix() {
    use gsens_calib::imu_systematic_sigma;
    use rand_distr::Normal;
    let (s_sigma, m_sigma) = (2e-3, 1.5e-3);
    let predicted = imu_systematic_sigma(&GAMMA, s_sigma, m_sigma);
    // Draw E = diag(s) + N, form Γ̂ = (I + E)⁻ᵀ·Γ exactly, compare the spread.
    let mut rng = <rand_xoshiro::Xoshiro256PlusPlus as rand::SeedableRng>::seed_from_u64(9);
    let (ns, nm) = (Normal::new(0.0, s_sigma).unwrap(), Normal::new(0.0, m_sigma).unwrap());
    let n = 20_000;
    let mut ss = [0.0; 3];
    for _ in 0..n {
        let mut m = nalgebra::Matrix3::<f64>::identity();
        for i in 0..3 {
            for j in 0..3 {
                m[(i, j)] += if i == j { ns.sample(&mut rng) } else { nm.sample(&mut rng) };
            }
        }
        let g = m.transpose().try_inverse().unwrap() * nalgebra::Vector3::from(GAMMA);
        for i in 0..3 {
            ss[i] += (g[i] - GAMMA[i]).powi(2);
        }
    }
    for i in 0..3 {
        let sd = (ss[i] / n as f64).sqrt();
        // The sample SD of 20 000 draws has a relative standard error of 1/√(2n) = 0.005.
        assert!((sd / predicted[i] - 1.0).abs() < 0.015, "axis {i}: {sd} vs {}", predicted[i]);
    }
}

#[test]
fn an_unobservable_axis_does_not_inflate_the_shaken_axes_sigma() {
    // z never shaken, but a slight tilt couples a little of x's motion into
    // z's reading (the IMU a hand holds is never level): z's column is small
    // and correlated with x's. With z in the solve σ_x would grow; without it
    // σ_x is what an x-and-y-only model gives.
    use rand_distr::{Distribution, Normal};
    let noise = Normal::new(0.0, 0.02).unwrap();
    let (phase, mut accel) = common::paper_session(17, false, |rng, _, phi| Some(phi + noise.sample(rng)));
    for a in &mut accel {
        a[2] += 0.002 * a[0];
    }
    let t_s = common::times(phase.len());
    let c = gsens_calib::calibrate(&common::series(&t_s, &phase, &accel), &gsens_calib::EstimateSettings::default())
        .unwrap();
    assert!(!c.observable[2] && c.observable[0] && c.observable[1], "{:?}", c.observable);
    // The reference: the same session with z's reading removed outright.
    let xy: Vec<[f64; 3]> = accel.iter().map(|a| [a[0], a[1], 0.0]).collect();
    let r =
        gsens_calib::calibrate(&common::series(&t_s, &phase, &xy), &gsens_calib::EstimateSettings::default()).unwrap();
    for i in 0..2 {
        let (s, s_ref) = (c.sigma_hz_per_mps2[i].unwrap(), r.sigma_hz_per_mps2[i].unwrap());
        assert!((s / s_ref - 1.0).abs() < 1e-9, "axis {i}: σ {s} vs {s_ref} without z");
        assert!((c.gamma_hz_per_mps2[i].unwrap() - common::GAMMA[i]).abs() < 3.0 * s, "axis {i}");
    }
    assert_eq!(c.gamma_hz_per_mps2[2], None);
}
