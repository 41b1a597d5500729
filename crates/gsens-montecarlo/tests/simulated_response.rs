//! The measured loop response (`measure_response`) on the simulator's
//! correlator-level channels (`gsens_sim::simulate_logs`), analysed with the
//! loop the scenario ran ([`gsens_montecarlo::scenario_settings`]) and with a
//! wrong one.

use gsens_calib::{EstimateSettings, PipelineSettings, calibrate_logs, measure_response};
use gsens_core::{LoopModel, LoopSpec};
use gsens_montecarlo::scenario_settings;

/// A session from the simulator (correlator-level channels, oscillator
/// noise, IMU errors, the paper's hand motion) analysed with the loop it
/// was simulated with passes; analysed with a loop 20 % wider, it fails.
#[test]
fn simulated_session_passes_with_its_loop() {
    // Seed 1 is `gsens demo`'s default: these are the demo session's numbers.
    // Its single shaking period (1.1 s) probes 0.7–1.2 Hz only, where Γ̂
    // absorbs most of a bandwidth error: Bn 3.6 Hz shows 3.2σ against a 3.0σ
    // threshold there, too close to assert; seed 7's 5.8σ is asserted.
    simulated_session(1, false);
    simulated_session(7, true);
}

fn simulated_session(seed: u64, assert_wrong_fails: bool) {
    let scenario = gsens_sim::scenario::Scenario::default();
    let logs = gsens_sim::simulate_logs(&scenario, seed).unwrap();
    let mut ps = PipelineSettings::default();
    ps.estimate = scenario_settings(&scenario, &EstimateSettings::default()).unwrap();
    // The response is measured against Γ̂ through the loop model.
    ps.measurement = gsens_calib::MeasurementChoice::TrackingError;
    let outcome = calibrate_logs(&logs.tracking, &logs.imu, "imu", &ps).unwrap();
    let c = &outcome.calibration;
    let r = measure_response(&outcome.series(), &c.settings, &c.gamma_raw_hz_per_mps2).unwrap();
    println!("simulated (seed {seed}), right loop: {}", r.summary());
    println!("  K {} n_e {:.1} M {:.1} p {:.3}", r.segments, r.effective_segments, r.independent_tests, r.p_value);
    for b in r.tested() {
        println!(
            "  {:.3} Hz: γ² {:.3}, |Ĥ| {:.4} ± {:.4}, model {:.4}, σ_Δ {:.5}, t_mag {:+.2}, t_phase {:+.2}",
            b.f_hz,
            b.coherence,
            b.measured_magnitude_rad_per_hz,
            b.sigma_magnitude_rad_per_hz,
            b.model_magnitude_rad_per_hz,
            b.sigma_deviation_rad_per_hz,
            b.magnitude_deviation_sigma,
            b.phase_deviation_sigma
        );
    }
    assert!(r.consistent, "{}", r.summary());
    assert!(r.bins_tested >= 2, "{}", r.summary());
    // The shaking period is 1.1 s: the tested band holds 0.91 Hz.
    let [lo, hi] = r.tested_band_hz.unwrap();
    assert!(lo <= 0.91 && hi >= 0.91, "{lo}–{hi} Hz");

    let mut wrong = ps;
    // The stated loop as it is (the pipeline's loop check would fit it).
    wrong.loop_identification = gsens_calib::LoopIdentificationMode::Off;
    wrong.estimate.receiver_loop =
        LoopModel::kaplan(LoopSpec::SecondOrder { bn_hz: 3.6, zeta: std::f64::consts::FRAC_1_SQRT_2 }, Some(0.001));
    let outcome = calibrate_logs(&logs.tracking, &logs.imu, "imu", &wrong).unwrap();
    let c = &outcome.calibration;
    let r = measure_response(&outcome.series(), &c.settings, &c.gamma_raw_hz_per_mps2).unwrap();
    println!("simulated (seed {seed}), Bn 3.6 Hz model: {}", r.summary());
    assert!(!assert_wrong_fails || !r.consistent, "{}", r.summary());
}
