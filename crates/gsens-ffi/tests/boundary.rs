//! The boundary: null handles and pointers, NaN and infinite inputs, wrong
//! structure sizes, bad configurations and calls in the wrong state all
//! return their status (and leave the calibrator as it was).

use gsens_ffi::*;
use std::ptr::{null, null_mut};

fn config() -> GsensCalibratorConfig {
    let mut c = std::mem::MaybeUninit::<GsensCalibratorConfig>::uninit();
    assert_eq!(gsens_calibrator_config_default(c.as_mut_ptr()), GsensStatus::Ok);
    // SAFETY: filled by the call above.
    unsafe { c.assume_init() }
}

fn estimate(cal: *const GsensCalibrator) -> GsensEstimate {
    let mut e = estimate_template();
    e.observable = [9; 3];
    assert_eq!(gsens_calibrator_estimate(cal, &mut e), GsensStatus::Ok);
    e
}

fn new_calibrator(c: &GsensCalibratorConfig) -> *mut GsensCalibrator {
    let mut cal = null_mut();
    assert_eq!(gsens_calibrator_new(c, &mut cal), GsensStatus::Ok);
    assert!(!cal.is_null());
    cal
}

#[test]
fn null_pointers_are_statuses() {
    let c = config();
    let mut cal = null_mut();
    assert_eq!(gsens_calibrator_config_default(null_mut()), GsensStatus::NullPointer);
    assert_eq!(gsens_calibrator_new(null(), &mut cal), GsensStatus::NullPointer);
    assert_eq!(gsens_calibrator_new(&c, null_mut()), GsensStatus::NullPointer);
    assert_eq!(gsens_calibrator_free(null_mut()), GsensStatus::NullPointer);
    assert_eq!(gsens_calibrator_drop(null_mut()), GsensStatus::NullPointer);
    assert_eq!(gsens_calibrator_feed(null_mut(), [0.0; 3].as_ptr(), 0.0), GsensStatus::NullPointer);
    assert_eq!(gsens_calibrator_finish(null_mut()), GsensStatus::NullPointer);
    let mut e = estimate_template();
    assert_eq!(gsens_calibrator_estimate(null(), &mut e), GsensStatus::NullPointer);
    let cal = new_calibrator(&c);
    assert_eq!(gsens_calibrator_feed(cal, null(), 0.0), GsensStatus::NullPointer);
    assert_eq!(gsens_calibrator_feed_channels(cal, [0.0; 3].as_ptr(), null(), null(), 3), GsensStatus::NullPointer);
    assert_eq!(gsens_calibrator_estimate(cal, null_mut()), GsensStatus::NullPointer);
    let mut comp = GsensCompensator { gamma_hz_per_mps2: [0.0; 3], carrier_ratio: 1.0 };
    assert_eq!(gsens_compensator_init(null(), 1.0, &mut comp), GsensStatus::NullPointer);
    assert_eq!(gsens_compensator_init([0.0; 3].as_ptr(), 1.0, null_mut()), GsensStatus::NullPointer);
    let mut hz = 0.0;
    assert_eq!(gsens_compensator_nco_correction_hz(null(), [0.0; 3].as_ptr(), &mut hz), GsensStatus::NullPointer);
    assert_eq!(gsens_compensator_nco_correction_hz(&comp, null(), &mut hz), GsensStatus::NullPointer);
    assert_eq!(gsens_compensator_nco_correction_hz(&comp, [0.0; 3].as_ptr(), null_mut()), GsensStatus::NullPointer);
    assert_eq!(gsens_calibrator_estimate(cal, &mut e), GsensStatus::Ok);
    assert_eq!(e.epochs_fed, 0);
    assert_eq!(gsens_calibrator_free(cal), GsensStatus::Ok);
}

fn estimate_template() -> GsensEstimate {
    GsensEstimate {
        struct_size: std::mem::size_of::<GsensEstimate>() as u32,
        observable: [0; 3],
        gamma_hz_per_mps2: [0.0; 3],
        sigma_hz_per_mps2: [0.0; 3],
        covariance_hz_per_mps2_sq: [0.0; 9],
        residual_sigma_rad: 0.0,
        epochs_used: 0,
        epochs_fed: 0,
    }
}

#[test]
fn non_finite_inputs_are_refused_and_not_taken() {
    let cal = new_calibrator(&config());
    let a = [0.1, -0.2, 9.8];
    assert_eq!(gsens_calibrator_feed(cal, a.as_ptr(), 0.01), GsensStatus::Ok);
    for bad in [[f64::NAN, 0.0, 9.8], [0.0, f64::INFINITY, 9.8], [0.0, 0.0, f64::NEG_INFINITY]] {
        assert_eq!(gsens_calibrator_feed(cal, bad.as_ptr(), 0.01), GsensStatus::NotFinite);
    }
    assert_eq!(gsens_calibrator_feed(cal, a.as_ptr(), f64::INFINITY), GsensStatus::NotFinite);
    // A NaN phase is an epoch without one: taken.
    assert_eq!(gsens_calibrator_feed(cal, a.as_ptr(), f64::NAN), GsensStatus::Ok);
    let phases = [0.01, f64::NAN, 0.02];
    assert_eq!(gsens_calibrator_feed_channels(cal, a.as_ptr(), phases.as_ptr(), null(), 3), GsensStatus::Ok);
    let inf = [0.01, f64::INFINITY];
    assert_eq!(gsens_calibrator_feed_channels(cal, a.as_ptr(), inf.as_ptr(), null(), 2), GsensStatus::NotFinite);
    let w = [1.0, f64::NAN];
    let p2 = [0.01, 0.02];
    assert_eq!(gsens_calibrator_feed_channels(cal, a.as_ptr(), p2.as_ptr(), w.as_ptr(), 2), GsensStatus::NotFinite);
    assert_eq!(estimate(cal).epochs_fed, 3);
    let mut comp = GsensCompensator { gamma_hz_per_mps2: [0.0; 3], carrier_ratio: 1.0 };
    let g = [0.09, f64::NAN, -0.08];
    assert_eq!(gsens_compensator_init(g.as_ptr(), 1.0, &mut comp), GsensStatus::NotFinite);
    assert_eq!(gsens_compensator_init([0.09, 0.08, -0.08].as_ptr(), f64::NAN, &mut comp), GsensStatus::NotFinite);
    assert_eq!(gsens_compensator_init([0.09, 0.08, -0.08].as_ptr(), 0.0, &mut comp), GsensStatus::InvalidConfig);
    assert_eq!(gsens_calibrator_free(cal), GsensStatus::Ok);
}

#[test]
fn wrong_sizes_are_refused() {
    let mut c = config();
    c.struct_size -= 8;
    let mut cal = null_mut();
    assert_eq!(gsens_calibrator_new(&c, &mut cal), GsensStatus::WrongSize);
    assert!(cal.is_null());
    let cal = new_calibrator(&config());
    let mut e = estimate_template();
    e.struct_size += 1;
    assert_eq!(gsens_calibrator_estimate(cal, &mut e), GsensStatus::WrongSize);
    let p = [0.0; GSENS_MAX_CHANNELS + 1];
    let a = [0.0, 0.0, 9.8];
    assert_eq!(gsens_calibrator_feed_channels(cal, a.as_ptr(), p.as_ptr(), null(), 0), GsensStatus::WrongSize);
    assert_eq!(
        gsens_calibrator_feed_channels(cal, a.as_ptr(), p.as_ptr(), null(), GSENS_MAX_CHANNELS + 1),
        GsensStatus::WrongSize
    );
    assert_eq!(
        gsens_calibrator_feed_channels(cal, a.as_ptr(), p.as_ptr(), null(), GSENS_MAX_CHANNELS),
        GsensStatus::Ok
    );
    // In place: too small, misaligned.
    let mut memory = vec![0u64; gsens_calibrator_size() / 8 + 2];
    let mut placed = null_mut();
    let m = memory.as_mut_ptr().cast();
    assert_eq!(gsens_calibrator_init(m, gsens_calibrator_size() - 1, &config(), &mut placed), GsensStatus::WrongSize);
    let odd = unsafe { m.cast::<u8>().add(1) }.cast();
    assert_eq!(gsens_calibrator_init(odd, gsens_calibrator_size(), &config(), &mut placed), GsensStatus::Misaligned);
    assert_eq!(gsens_calibrator_init(m, gsens_calibrator_size(), &config(), &mut placed), GsensStatus::Ok);
    // Each end of life belongs to its own beginning.
    assert_eq!(gsens_calibrator_free(placed), GsensStatus::NotOwned);
    assert_eq!(gsens_calibrator_drop(cal), GsensStatus::NotOwned);
    assert_eq!(gsens_calibrator_drop(placed), GsensStatus::Ok);
    assert_eq!(gsens_calibrator_free(cal), GsensStatus::Ok);
}

/// A bad configuration: what it is, how it is made, the status it gets.
type BadConfig = (&'static str, fn(&mut GsensCalibratorConfig), GsensStatus);

#[test]
fn bad_configurations_are_refused() {
    let cases: [BadConfig; 12] = [
        ("colour factor < 1", |c| c.sigma_colour_factor = 0.5, GsensStatus::InvalidConfig),
        ("colour factor NaN", |c| c.sigma_colour_factor = f64::NAN, GsensStatus::NotFinite),
        ("logged phase 7", |c| c.logged_phase = 7, GsensStatus::InvalidConfig),
        ("order 4", |c| c.order = 4, GsensStatus::InvalidConfig),
        ("Bn NaN", |c| c.bn_hz = f64::NAN, GsensStatus::NotFinite),
        ("Bn 0", |c| c.bn_hz = 0.0, GsensStatus::InvalidConfig),
        ("ζ < 0", |c| c.zeta = -0.7, GsensStatus::InvalidConfig),
        ("Bn·T too large", |c| c.bn_hz = 600.0, GsensStatus::UnstableLoop),
        ("log not a multiple of the loop", |c| c.log_interval_s = 0.0255, GsensStatus::InvalidConfig),
        ("warm-up < 0", |c| c.warmup_s = -1.0, GsensStatus::InvalidConfig),
        ("high-pass above Nyquist", |c| c.highpass_hz = 30.0, GsensStatus::InvalidConfig),
        ("σ floor 0", |c| c.max_sigma_hz_per_mps2 = 0.0, GsensStatus::InvalidConfig),
    ];
    for (what, change, expected) in cases {
        let mut c = config();
        change(&mut c);
        let mut cal = null_mut();
        assert_eq!(gsens_calibrator_new(&c, &mut cal), expected, "{what}");
        assert!(cal.is_null(), "{what}");
    }
}

#[test]
fn finished_calibrators_take_no_more_epochs() {
    let cal = new_calibrator(&config());
    let a = [0.0, 0.0, 9.8];
    assert_eq!(gsens_calibrator_feed(cal, a.as_ptr(), 0.0), GsensStatus::Ok);
    assert_eq!(gsens_calibrator_finish(cal), GsensStatus::Ok);
    assert_eq!(gsens_calibrator_finish(cal), GsensStatus::Ok);
    assert_eq!(gsens_calibrator_feed(cal, a.as_ptr(), 0.0), GsensStatus::Finished);
    // Nothing shaken: every axis unobservable, Γ̂ NaN, σ +∞.
    let e = estimate(cal);
    assert_eq!(e.observable, [0; 3]);
    assert!(e.gamma_hz_per_mps2.iter().all(|g| g.is_nan()));
    assert!(e.sigma_hz_per_mps2.iter().all(|s| *s == f64::INFINITY));
    assert_eq!(gsens_calibrator_free(cal), GsensStatus::Ok);
}

#[test]
fn every_status_has_a_message() {
    use std::ffi::CStr;
    for s in GsensStatus::all() {
        let m = unsafe { CStr::from_ptr(gsens_status_message(s as i32)) }.to_str().unwrap();
        assert!(!m.is_empty() && m != "unknown status", "{s:?}");
    }
    let m = unsafe { CStr::from_ptr(gsens_status_message(-5)) }.to_str().unwrap();
    assert_eq!(m, "unknown status");
}

/// The compensator: −aᵀΓ̂ times the carrier ratio, against the closed form.
#[test]
fn the_nco_correction_is_minus_a_dot_gamma() {
    let g = [0.089, 0.079, -0.080];
    let mut comp = GsensCompensator { gamma_hz_per_mps2: [0.0; 3], carrier_ratio: 0.0 };
    let ratio = 1176.45 / 1575.42;
    assert_eq!(gsens_compensator_init(g.as_ptr(), ratio, &mut comp), GsensStatus::Ok);
    let a = [1.5, -2.0, 9.81];
    let mut hz = 0.0;
    assert_eq!(gsens_compensator_nco_correction_hz(&comp, a.as_ptr(), &mut hz), GsensStatus::Ok);
    let expected = -(1.5 * 0.089 - 2.0 * 0.079 - 9.81 * 0.080) * ratio;
    assert!((hz - expected).abs() <= 1e-15 * expected.abs(), "{hz} vs {expected}");
}

/// The defaults are those of `gsens estimate`.
#[test]
fn the_defaults_are_the_pipelines() {
    let c = config();
    let s = gsens_calib::EstimateSettings::default();
    assert_eq!(c.warmup_s, s.warmup_s);
    assert_eq!(c.highpass_hz, s.highpass_hz);
    assert_eq!(c.min_excitation_rms, s.criteria.min_excitation_rms);
    assert_eq!(c.max_sigma_hz_per_mps2, s.criteria.max_sigma_hz_per_mps2);
    assert_eq!(c.logged_phase, GsensLoggedPhase::Last as u32);
    match gsens_core::LoopSpec::PAPER {
        gsens_core::LoopSpec::SecondOrder { bn_hz, zeta } => assert_eq!((c.order, c.bn_hz, c.zeta), (2, bn_hz, zeta)),
        other => panic!("{other:?}"),
    }
}
