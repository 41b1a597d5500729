//! The measured-response figure rendered from a calibrated synthetic session:
//! a valid PNG of the declared size with non-trivial content, and an SVG with
//! its axis labels, legend and verdict.

mod common;

use common::{check_svg, out_dir, png_facts, session};
use gsens_calib::{EpochSeries, EstimateSettings, measure_response};
use gsens_core::LoggedPhase;
use gsens_report::figures::*;

#[test]
fn measured_response_renders() {
    let s = session([true; 3]);
    let c = &s.calibration;
    let series = EpochSeries {
        log_interval_s: 0.025,
        t_s: &s.t_s,
        phase_err_rad: &s.phase_err_rad,
        accel_mps2: &s.accel_mps2,
        imu_time_offset_s: 0.0,
    };
    let settings = EstimateSettings::default();
    let check = measure_response(&series, &settings, &c.gamma_raw_hz_per_mps2).unwrap();
    // φ is the model's own φ_aᵀΓ plus white noise: the model fits.
    assert!(check.consistent, "{}", check.summary());
    let model = settings.loop_at(0.025);
    let d = MeasuredResponseData::from_check(&check, &model, 0.025, LoggedPhase::Last, 200, model.to_string());
    assert!(d.points.iter().any(|p| p.tested));
    // The model curve is the loop's own response (logged `last`): its
    // maximum is the peak LoopModel::peak finds (0.838 rad/Hz for the
    // paper's loop updated at 40 Hz; 0.785 in continuous time).
    let peak = d.model_magnitude_rad_per_hz.iter().cloned().fold(0.0, f64::max);
    let expect = model.peak().unwrap().rad_per_hz;
    assert!((peak - expect).abs() < 2e-3 * expect && (peak - 0.838).abs() < 2e-3, "{peak} vs {expect}");
    // Tested points sit on the model through the same segments within
    // their band (3σ), and their phases are unwrapped onto the model's curve.
    for p in d.points.iter().filter(|p| p.tested) {
        let dm = (p.magnitude_rad_per_hz - p.model_magnitude_rad_per_hz).abs();
        assert!(
            dm < 3.0 * p.sigma_magnitude_rad_per_hz,
            "{} Hz: |Ĥ| {} vs {}",
            p.f_hz,
            p.magnitude_rad_per_hz,
            p.model_magnitude_rad_per_hz
        );
        assert!((p.phase_deg - p.model_phase_deg).abs() < 3.0 * p.sigma_phase_deg, "{} Hz: phase", p.f_hz);
        let i = d.model_frequency_hz.partition_point(|&f| f < p.f_hz).min(d.model_frequency_hz.len() - 1);
        assert!((p.phase_deg - d.model_phase_deg[i]).abs() < 90.0, "{} Hz: not unwrapped", p.f_hz);
    }

    // The red bars are the check's own limits: on a session the model fits,
    // every tested point's bar reaches its model point.
    for p in d.points.iter().filter(|p| p.tested) {
        let miss = (p.magnitude_rad_per_hz - p.model_magnitude_rad_per_hz).abs() / p.magnitude_bar_rad_per_hz();
        assert!(miss < 1.0, "{} Hz: bar misses the model point ({miss:.2} of its length)", p.f_hz);
        assert!((p.phase_deg - p.model_phase_deg).abs() < p.phase_bar_deg(), "{} Hz: phase bar misses", p.f_hz);
    }

    for (size, name) in [((1000, 640), "measured_response"), ((480, 320), "measured_response_small")] {
        let png = fig_measured_response(&d, Format::Png, size).unwrap();
        png.write_to(out_dir().join(format!("{name}.png"))).unwrap();
        let (w, h, colours, ink) = png_facts(png.as_bytes());
        assert_eq!((w, h), size, "{name}: size");
        assert!(colours >= 40, "{name}: only {colours} colours");
        assert!((0.02..0.8).contains(&ink), "{name}: {:.1} % of pixels drawn", ink * 100.0);
        let svg = fig_measured_response(&d, Format::Svg, size).unwrap();
        svg.write_to(out_dir().join(format!("{name}.svg"))).unwrap();
        let text = svg.svg().unwrap();
        check_svg(text, size);
        for label in
            ["|Ĥ|, |L| [rad/Hz]", "phase [deg]", "frequency f [Hz]", "model |L|", "measured Ĥ ±2σ", "same segments"]
        {
            assert!(text.contains(label), "{name}: SVG lacks {label:?}");
        }
        if size.0 >= 1000 {
            assert!(text.contains("consistent with the model"), "{name}: no verdict");
        }
        // Curves present: the model line in both panels and one error bar per point.
        assert!(text.matches("<polyline").count() >= 2, "{name}: model curves missing");
        assert!(text.matches("<circle").count() >= 4 * d.points.len(), "{name}: measured points missing");
    }
}

/// A loop stated 40 % too wide fails the check, and the figure shows it: a
/// tested point whose bar (the deviation the check allows) misses its model
/// point.
#[test]
fn a_wrong_loop_shows_as_a_bar_missing_its_model_point() {
    let s = session([true; 3]);
    let c = &s.calibration;
    let series = EpochSeries {
        log_interval_s: 0.025,
        t_s: &s.t_s,
        phase_err_rad: &s.phase_err_rad,
        accel_mps2: &s.accel_mps2,
        imu_time_offset_s: 0.0,
    };
    let right = EstimateSettings::default();
    let mut wrong = right;
    wrong.receiver_loop = right.receiver_loop.with_bn_scaled(1.4);
    let check = measure_response(&series, &wrong, &c.gamma_raw_hz_per_mps2).unwrap();
    assert!(!check.consistent, "{}", check.summary());
    let model = wrong.loop_at(0.025);
    let d = MeasuredResponseData::from_check(&check, &model, 0.025, LoggedPhase::Last, 200, model.to_string());
    let missed = d.points.iter().filter(|p| p.tested).any(|p| {
        (p.magnitude_rad_per_hz - p.model_magnitude_rad_per_hz).abs() > p.magnitude_bar_rad_per_hz()
            || (p.phase_deg - p.model_phase_deg).abs() > p.phase_bar_deg()
    });
    assert!(missed, "no tested bar misses its model point although the check failed: {}", check.summary());
}

#[test]
fn measured_response_rejects_empty_data() {
    let d = MeasuredResponseData {
        points: vec![],
        model_frequency_hz: vec![0.1, 1.0],
        model_magnitude_rad_per_hz: vec![0.1, 0.7],
        model_phase_deg: vec![-90.0, -180.0],
        description: "x".into(),
        verdict: "v".into(),
        consistent: true,
    };
    assert!(matches!(fig_measured_response(&d, Format::Svg, (800, 600)), Err(RenderError::NoData(_))));
    let p = MeasuredPoint {
        f_hz: 0.5,
        magnitude_rad_per_hz: f64::NAN,
        sigma_magnitude_rad_per_hz: 0.01,
        phase_deg: -120.0,
        sigma_phase_deg: 1.0,
        model_magnitude_rad_per_hz: 0.6,
        model_phase_deg: -121.0,
        tested: true,
        allowed_deviation_rad_per_hz: Some(0.05),
    };
    let bad = MeasuredResponseData { points: vec![p], ..d.clone() };
    assert!(matches!(fig_measured_response(&bad, Format::Png, (800, 600)), Err(RenderError::NoData(_))));
    let ok = MeasuredResponseData { points: vec![MeasuredPoint { magnitude_rad_per_hz: 0.6, ..p }], ..d };
    assert!(matches!(fig_measured_response(&ok, Format::Png, (10, 10)), Err(RenderError::Size(10, 10))));
    assert!(fig_measured_response(&ok, Format::Svg, (800, 600)).is_ok());
}
