//! The carrier-gain check on sessions whose channels follow the common signal
//! by other carrier ratios than the log states (mixed-signal sessions from the
//! simulator: gsens-montecarlo's `mixed_signals` test).

mod common;

use gsens_calib::{PipelineSettings, ResultDocument, calibrate_logs};
use gsens_core::units::GPS_L1_HZ;
use gsens_io::TrackingLog;

/// A session made without the simulator: the paper's discrete loop driven by
/// aᵀΓ (common::paper_session), five channels logging (f_c/f_L1)·φ plus their
/// own white noise. `given[c]` is the carrier the log gives channel c, `true_hz[c]`
/// the one its phase follows.
fn closed_form_session(true_hz: &[f64], given: &[gsens_io::Carrier]) -> ResultDocument {
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};
    let (phase, accel) = common::paper_session(11, true, |_, _, p| Some(p));
    let t_s = common::times(phase.len());
    let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(5);
    let noise = Normal::new(0.0, 0.01).unwrap();
    let mut rows = Vec::new();
    for (k, p) in phase.iter().enumerate() {
        for (c, f) in true_hz.iter().enumerate() {
            let phase_err_rad = f / GPS_L1_HZ * p.unwrap() + noise.sample(&mut rng);
            let row = gsens_io::TrackingRow {
                t_s: t_s[k],
                channel: c as u32,
                prn: 10 + c as u32,
                cn0_dbhz: 45.0,
                elev_deg: None,
                phase_err_rad,
            };
            rows.push((row, given[c]));
        }
    }
    let tracking = TrackingLog::from_rows_on("closed form", rows.iter().map(|(r, c)| (r, *c))).unwrap();
    let imu = gsens_io::ImuSeries { t_s, accel_mps2: accel };
    let mut ps = PipelineSettings::default();
    ps.estimate.receiver_loop = gsens_core::LoopModel::kaplan(gsens_core::LoopSpec::PAPER, Some(common::T));
    ps.selection.max_channels = None;
    ps.loop_stated = true;
    ps.time_offset = gsens_calib::TimeOffset::Fixed { imu_time_offset_s: 0.0 };
    let outcome = calibrate_logs(&tracking, &imu, "imu", &ps).unwrap();
    outcome.document(Some(common::GAMMA))
}

#[test]
fn carrier_gain_check_on_a_closed_form_session() {
    let g1 = gsens_io::Carrier::of(gsens_io::Signal::from_label("G1:+2").unwrap());
    let l1 = gsens_io::Carrier::GPS_L1;
    let hz = [GPS_L1_HZ, GPS_L1_HZ, g1.carrier_hz, GPS_L1_HZ, GPS_L1_HZ];
    // Carriers given right: no warning, Γ̂ within its σ.
    let right = closed_form_session(&hz, &[l1, l1, g1, l1, l1]);
    assert!(!right.warnings.iter().any(|w| w.code == "carrier_gain"), "{:?}", right.warnings);
    for i in 0..3 {
        let (g, s) = (right.calibration.gamma_hz_per_mps2[i].unwrap(), right.calibration.sigma_hz_per_mps2[i].unwrap());
        assert!(((g - common::GAMMA[i]) / s).abs() < 3.3, "axis {i}: {g} ± {s}");
    }
    // The G1 channel given as L1: its gain is (1602 + 2·0.5625) MHz / 1575.42 MHz = 1.0176, caught.
    let wrong = closed_form_session(&hz, &[l1; 5]);
    let w = wrong.warnings.iter().find(|w| w.code == "carrier_gain").expect("carrier_gain");
    println!("{}", w.message);
    assert!(
        w.message.contains("channel 2 (PRN 12, given as 1575.42 MHz)") && w.message.contains("G1:"),
        "{}",
        w.message
    );
    assert!(!wrong.trustworthy);
    // A channel that lost gain (a fade) is no carrier error.
    let faded = [GPS_L1_HZ, GPS_L1_HZ, 0.97 * GPS_L1_HZ, GPS_L1_HZ, GPS_L1_HZ];
    let fade = closed_form_session(&faded, &[l1; 5]);
    assert!(!fade.warnings.iter().any(|w| w.code == "carrier_gain"), "{:?}", fade.warnings);
}
