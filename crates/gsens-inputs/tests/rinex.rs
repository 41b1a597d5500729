//! GNSS-SDR's own RINEX observation file of a simulated shaken session with a
//! known Γ (crates/gsens-rinex/tests/fixtures/gnss-sdr), calibrated as
//! `gsens estimate --rinex gnss-sdr.24O --imu imu.csv` calibrates it: the
//! receiver's loop identified, not stated.

use gsens_calib::{CalibrationOptions, LoopResolution, ObservationRecord};
use gsens_inputs::{InputChoice, ObservationFile};
use std::path::PathBuf;

fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../gsens-rinex/tests/fixtures/gnss-sdr").join(name)
}

/// The fixture calibrated from `record`'s rows with the loop identified,
/// and the truth (Γ in the IMU's axes).
fn calibrated(record: ObservationRecord) -> (gsens_calib::ResultDocument, Vec<f64>) {
    let (outcome, want) = outcome(record);
    (outcome.document(None), want)
}

/// The fixture's calibration from `record`'s rows, and the truth.
fn outcome(record: ObservationRecord) -> (gsens_calib::ObservationOutcome, Vec<f64>) {
    outcome_with(record, None, &CalibrationOptions::default())
}

/// [`outcome`] with the GNSS-SDR configuration `gnss_sdr_conf` named and
/// the options `options`.
fn outcome_with(
    record: ObservationRecord,
    gnss_sdr_conf: Option<PathBuf>,
    options: &CalibrationOptions,
) -> (gsens_calib::ObservationOutcome, Vec<f64>) {
    let inputs = inputs(record, gnss_sdr_conf).unwrap();
    assert_eq!(inputs.log, ObservationFile::Rinex(fixture("gnss-sdr.24O")));
    let settings = options.pipeline_settings().unwrap();
    let outcome = inputs.calibrate(&settings).expect("the fixture calibrates");
    let truth: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(fixture("truth.json")).unwrap()).unwrap();
    let want = truth["gamma_imu_axes_hz_per_mps2"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
    (outcome, want)
}

/// The fixture's route, as a front end names it.
fn inputs(
    record: ObservationRecord,
    gnss_sdr_conf: Option<PathBuf>,
) -> Result<gsens_inputs::ObservationInputs, gsens_inputs::InputsError> {
    let choice = InputChoice {
        imu: Some(fixture("imu.csv")),
        rinex: Some(fixture("gnss-sdr.24O")),
        gnss_sdr_conf,
        observation_record: record,
        ..InputChoice::default()
    };
    choice.observations(str::to_string).expect("a RINEX route")
}

/// Γ̂ within 3σ of the truth on every axis, σ under `sigma_share` of |Γ|,
/// and the document trustworthy.
fn assert_within_sigma(doc: &gsens_calib::ResultDocument, want: &[f64], sigma_share: f64) {
    let c = &doc.calibration;
    for i in 0..3 {
        let (g, s) = (c.gamma_hz_per_mps2[i].unwrap(), c.sigma_hz_per_mps2[i].unwrap());
        eprintln!("axis {i}: {g:+.5} ± {s:.5} against {:+.5} ({:+.2}σ)", want[i], (g - want[i]) / s);
        assert!(
            (g - want[i]).abs() < 3.0 * s && s < sigma_share * want[i].abs(),
            "axis {i}: {g} ± {s} against {}",
            want[i]
        );
    }
    assert!(doc.trustworthy, "{:?}", doc.warnings);
}

/// From the carrier phase: Γ̂ within 3σ of the truth on every axis with σ
/// useful (under 4 % of |Γ|), trustworthy, and GNSS-SDR's loop (2nd order,
/// 3 Hz, 20 ms updates) identified: the order and the update interval, Bn
/// within 3σ of 3 Hz. Shorter update intervals fit this one-rate session
/// about as well (their Γ̂ up to 3 % higher): they are reported, and σ
/// covers their Γ̂.
#[test]
fn gnss_sdr_rinex_gives_gamma_within_sigma_with_its_loop_identified() {
    let (doc, want) = calibrated(ObservationRecord::CarrierPhase);
    assert_within_sigma(&doc, &want, 0.04);
    let id = &doc.identified_loop.as_ref().unwrap().identified;
    eprintln!(
        "{} order, {} s, Bn {} ± {}; alike {:?}",
        id.order, id.loop_interval_s, id.bn_hz, id.sigma_ln_bn, id.alike_intervals_s
    );
    assert_eq!((id.order, id.loop_interval_s, id.resolution), (2, 0.02, LoopResolution::Resolved), "{id:?}");
    assert!(((id.bn_hz / 3.0).ln() / id.sigma_ln_bn).abs() < 3.0, "{id:?}");
    assert!(id.alike_intervals_s.len() > 1 && id.alike_intervals_s.contains(&0.02), "{id:?}");
}

/// From GNSS-SDR's Doppler (the command of its next 20 ms update): the
/// session fits a 1 ms loop a little better than its own 20 ms one, whose
/// Γ̂ is 3–4 % lower; Γ̂ stays within 3σ of the truth because σ covers
/// every update interval that fits alike, the 20 ms among them.
#[test]
fn gnss_sdr_doppler_gives_gamma_within_sigma() {
    let (doc, want) = calibrated(ObservationRecord::Doppler);
    assert_within_sigma(&doc, &want, 0.05);
    let id = &doc.identified_loop.as_ref().unwrap().identified;
    eprintln!(
        "{} order, {} s, Bn {} ± {}; alike {:?}",
        id.order, id.loop_interval_s, id.bn_hz, id.sigma_ln_bn, id.alike_intervals_s
    );
    assert!(id.alike_intervals_s.contains(&0.02), "{id:?}");
}

/// The carrier phase before and after compensation (the report's figure)
/// is the series whose RMS the document gives, and compensating lowers it.
#[test]
fn the_compensated_carrier_phase_is_the_documents() {
    let (outcome, _) = outcome(ObservationRecord::CarrierPhase);
    let p = &outcome.carrier_phase;
    assert_eq!((p.before_rad.len(), p.after_rad.len()), (p.t_s.len(), p.t_s.len()));
    let rms = |v: &[Option<f64>]| {
        let x: Vec<f64> = v.iter().flatten().copied().collect();
        (x.iter().map(|x| x * x).sum::<f64>() / x.len() as f64).sqrt()
    };
    let c = &outcome.calibration;
    let (before, after) = (rms(&p.before_rad), rms(&p.after_rad));
    eprintln!("carrier phase RMS {before:.4} rad before, {after:.4} rad after");
    assert!((before - c.rms_before_rad).abs() < 1e-12 * before, "{before} against {}", c.rms_before_rad);
    assert!((after - c.rms_after_rad).abs() < 1e-12 * after, "{after} against {}", c.rms_after_rad);
    assert!(after < before);
}

/// With the configuration of the GNSS-SDR run that wrote the file (the
/// fixture's `gnss-sdr.conf`), the loop is GNSS-SDR's own, modelled exactly
/// with its bandwidth fitted: from the carrier phase Γ̂ is within 3σ of the truth
/// with σ under 1 % of |Γ| (the identified loop's σ is 3–4 %), and the
/// document names the configuration. A loop stated besides it, or the
/// configuration with a UBX log, is refused.
#[test]
fn gnss_sdr_rinex_with_its_configuration_is_estimated_with_gnss_sdrs_loop() {
    let conf = fixture("gnss-sdr.conf");
    let (outcome, want) =
        outcome_with(ObservationRecord::CarrierPhase, Some(conf.clone()), &CalibrationOptions::default());
    let doc = outcome.document(None);
    assert_within_sigma(&doc, &want, 0.01);
    let model = outcome.calibration.loop_used.to_string();
    assert!(model.starts_with("GNSS-SDR") && model.contains("20 ms"), "{model}");
    assert!(
        doc.inputs.iter().any(|(k, v)| k == "gnss_sdr_conf" && *v == conf.display().to_string()),
        "{:?}",
        doc.inputs
    );

    let mut stated = CalibrationOptions::default();
    stated.receiver_loop.order = Some(2);
    let settings = stated.pipeline_settings().unwrap();
    let e = inputs(ObservationRecord::CarrierPhase, Some(conf.clone())).unwrap().calibrate(&settings).unwrap_err();
    assert!(matches!(e, gsens_inputs::InputsError::LoopStatedTwice { .. }), "{e}");
    let ubx = InputChoice { ubx: Some("log.ubx".into()), gnss_sdr_conf: Some(conf), ..InputChoice::default() };
    let e = ubx.observations(str::to_string).unwrap().unwrap_err();
    assert_eq!(e.to_string(), "gnss_sdr_conf goes with a GNSS-SDR run's rinex, not ubx");
}
