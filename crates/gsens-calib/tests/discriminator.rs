//! The discriminator's linear range and the IMU's units, on sessions from the
//! independent simulator (`scripts/indep_sim.py`, not gsens's own; the
//! commands that made the fixtures are in docs/independent-simulator.md):
//! atan Costas loops of 1 ms whose true phase error never left ±π/2 are
//! trusted at peaks of 0.9 rad (3rd order) and 1.15 rad (2nd order, a
//! 12 m/s² shake), one whose predicted peak passes π/2 is flagged, and the
//! IMU's units are judged where the board rests.

use gsens_calib::{PipelineSettings, ResultDocument, calibrate_files};
use gsens_core::{Discriminator, KAPLAN_A3, KAPLAN_B3, LoopModel, LoopSpec};
use std::path::{Path, PathBuf};

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/indep").join(name)
}

/// The truth.json the simulator wrote.
fn truth(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("truth.json")).unwrap()).unwrap()
}

/// The loop the simulator ran, stated: order and Bn from truth.json, 1 ms updates, last output logged.
fn settings(truth: &serde_json::Value) -> PipelineSettings {
    let bn_hz = truth["bn_hz"].as_f64().unwrap();
    let spec = match truth["order"].as_u64().unwrap() {
        2 => LoopSpec::SecondOrder { bn_hz, zeta: core::f64::consts::FRAC_1_SQRT_2 },
        _ => LoopSpec::ThirdOrder { bn_hz, a3: KAPLAN_A3, b3: KAPLAN_B3 },
    };
    let mut ps = PipelineSettings::default();
    ps.estimate.receiver_loop = LoopModel::kaplan(spec, Some(truth["loop_interval_s"].as_f64().unwrap()));
    ps
}

fn estimate(dir: &Path, imu: &Path, ps: &PipelineSettings) -> ResultDocument {
    calibrate_files(&dir.join("tracking.csv"), imu, ps).unwrap().document(None)
}

fn codes(doc: &ResultDocument) -> Vec<&'static str> {
    doc.warnings.iter().map(|w| w.code.as_str()).collect()
}

/// A clean atan Costas session near `peak_rad` is trusted and Γ̂ lies within 3σ of the truth.
fn trusted_near(name: &str, peak_rad: f64) -> ResultDocument {
    let dir = fixture(name);
    let truth = truth(&dir);
    assert_eq!(truth["discriminator"], "atan");
    // No channel's true phase error ever left ±π/2: no slip was possible.
    for ch in truth["channels"].as_array().unwrap() {
        assert_eq!(ch["discriminator_range_exits"], 0, "{ch}");
    }
    let doc = estimate(&dir, &dir.join("imu.csv"), &settings(&truth));
    let c = &doc.calibration;
    println!(
        "{name}: peak {:.3} rad, range {:.3} rad, Γ̂ {:?} ± {:?}, warnings {:?}",
        c.predicted_peak_phase_err_rad,
        c.discriminator_linear_range_rad,
        c.gamma_hz_per_mps2,
        c.sigma_hz_per_mps2,
        codes(&doc)
    );
    assert!((c.predicted_peak_phase_err_rad - peak_rad).abs() < 0.05, "{}", c.predicted_peak_phase_err_rad);
    assert!(c.predicted_peak_phase_err_rad > core::f64::consts::FRAC_PI_4);
    assert!(doc.trustworthy, "{:?}", doc.warnings);
    assert_eq!(c.settings.discriminator, Discriminator::AtanCostas);
    for i in 0..3 {
        let (g, s) = (c.gamma_hz_per_mps2[i].unwrap(), c.sigma_hz_per_mps2[i].unwrap());
        let t = truth["gamma_hz_per_mps2"][i].as_f64().unwrap();
        assert!((g - t).abs() < 3.0 * s, "axis {i}: {g} vs {t} ± {s}");
    }
    doc
}

#[test]
fn a_third_order_session_peaking_near_0_9_rad_is_trusted() {
    let doc = trusted_near("third-order-0.9rad", 0.9);
    // 45 dB-Hz at 1 ms: π/2 − 3.09·0.127 rad.
    assert!((doc.calibration.discriminator_linear_range_rad - 1.18).abs() < 0.01);
}

#[test]
fn a_second_order_session_peaking_near_1_15_rad_is_trusted_and_its_shake_is_not_imu_units() {
    let doc = trusted_near("second-order-1.15rad", 1.15);
    assert!(!codes(&doc).contains(&"imu_units"));
    // What the median |f| over the epochs would have said: beyond 10 % of g₀ under a 12 m/s² shake.
    let imu = gsens_io::read_imu_file(fixture("second-order-1.15rad").join("imu.csv")).unwrap();
    let mut norms: Vec<f64> = imu.accel_mps2.iter().map(|a| (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()).collect();
    let median = gsens_core::stats::median_in_place(&mut norms);
    assert!(median > 1.1 * gsens_core::units::STANDARD_GRAVITY_MPS2, "{median}");
}

/// A loop whose phase error peaks at 1.8 rad without slipping (an atan2
/// discriminator): stated as atan Costas, whose output wraps at π/2, it is
/// flagged; stated as atan2 (±π), trusted.
#[test]
fn a_session_past_pi_over_2_is_flagged_unless_its_discriminator_is_atan2() {
    let dir = fixture("atan2-1.8rad");
    let truth = truth(&dir);
    assert_eq!(truth["discriminator"], "atan2");
    let mut ps = settings(&truth);
    let doc = estimate(&dir, &dir.join("imu.csv"), &ps);
    let c = &doc.calibration;
    println!(
        "atan costas: peak {} range {} {:?}",
        c.predicted_peak_phase_err_rad,
        c.discriminator_linear_range_rad,
        codes(&doc)
    );
    assert!(c.predicted_peak_phase_err_rad > core::f64::consts::FRAC_PI_2);
    assert_eq!(codes(&doc), ["discriminator_range"]);
    assert!(!doc.trustworthy);
    ps.set_discriminator(Discriminator::Atan2);
    let doc = estimate(&dir, &dir.join("imu.csv"), &ps);
    assert!(doc.trustworthy, "{:?}", doc.warnings);
    assert_eq!(doc.calibration.settings.discriminator, Discriminator::Atan2);
}

/// An atan Costas loop driven past π/2 slips at the peaks (every channel
/// here): Γ̂ collapses with the lost gain, so its predicted peak falls back
/// inside the range and cannot show it; the session is still not trusted.
#[test]
fn an_atan_costas_session_driven_past_pi_over_2_is_not_trusted() {
    let dir = fixture("atan-costas-slipping");
    let truth = truth(&dir);
    assert!(truth["peak_g_induced_phase_err_rad"].as_f64().unwrap() > core::f64::consts::FRAC_PI_2);
    let doc = estimate(&dir, &dir.join("imu.csv"), &settings(&truth));
    let c = &doc.calibration;
    println!("peak {} Γ̂ {:?} warnings {:?}", c.predicted_peak_phase_err_rad, c.gamma_hz_per_mps2, codes(&doc));
    assert!(!doc.trustworthy);
    let gx = c.gamma_hz_per_mps2[0].unwrap();
    assert!(gx < 0.8 * truth["gamma_hz_per_mps2"][0].as_f64().unwrap(), "{gx}");
}

#[test]
fn an_atan2_discriminator_widens_the_range_by_pi_over_2() {
    let dir = fixture("second-order-1.15rad");
    let mut ps = settings(&truth(&dir));
    let costas = estimate(&dir, &dir.join("imu.csv"), &ps).calibration.discriminator_linear_range_rad;
    ps.set_discriminator(Discriminator::Atan2);
    assert_eq!(ps.selection.screening.max_abs_phase_rad, Some(core::f64::consts::FRAC_PI_2));
    let wide = estimate(&dir, &dir.join("imu.csv"), &ps).calibration.discriminator_linear_range_rad;
    assert!((wide - costas - core::f64::consts::FRAC_PI_2).abs() < 1e-9, "{costas} {wide}");
}

#[test]
fn an_imu_log_in_g_is_still_imu_units() {
    let dir = fixture("second-order-1.15rad");
    let imu = gsens_io::read_imu_file(dir.join("imu.csv")).unwrap();
    let scratch = tempfile::Builder::new().prefix("gsens-disc-imu-g-").tempdir().unwrap();
    let tmp = scratch.path().join("imu.csv");
    let mut text = String::from("t_s,fx_mps2,fy_mps2,fz_mps2\n");
    let g0 = gsens_core::units::STANDARD_GRAVITY_MPS2;
    for (t, a) in imu.t_s.iter().zip(&imu.accel_mps2) {
        text += &format!("{t},{},{},{}\n", a[0] / g0, a[1] / g0, a[2] / g0);
    }
    std::fs::write(&tmp, text).unwrap();
    let doc = estimate(&dir, &tmp, &settings(&truth(&dir)));
    std::fs::remove_file(&tmp).ok();
    let w = doc.warnings.iter().find(|w| w.code == "imu_units").expect("imu_units");
    assert!(w.message.contains("in g"), "{}", w.message);
    assert!(w.message.contains("at rest"), "{}", w.message);
}
