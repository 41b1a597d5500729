//! Every figure rendered from known data: a valid PNG of the declared size
//! with non-trivial content, and a well-formed SVG with its axis labels.

mod common;

use common::{TRUTH, check_svg, out_dir, png_facts, session};
use gsens_core::LoopModel;
use gsens_core::LoopSpec;
use gsens_report::figures::*;

/// Renders both formats, checks them and leaves them in the test output folder.
fn check(
    name: &str,
    size: (u32, u32),
    labels: &[&str],
    render: impl Fn(Format, (u32, u32)) -> Result<Image, RenderError>,
) {
    let png = render(Format::Png, size).unwrap();
    assert_eq!(png.format(), Format::Png);
    png.write_to(out_dir().join(format!("{name}.png"))).unwrap();
    let (w, h, colours, ink) = png_facts(png.as_bytes());
    assert_eq!((w, h), size, "{name}: size");
    assert!(colours >= 40, "{name}: only {colours} colours");
    assert!((0.02..0.8).contains(&ink), "{name}: {:.1} % of pixels drawn", ink * 100.0);

    let svg = render(Format::Svg, size).unwrap();
    svg.write_to(out_dir().join(format!("{name}.svg"))).unwrap();
    let text = svg.svg().unwrap();
    check_svg(text, size);
    for l in labels {
        assert!(text.contains(l), "{name}: SVG lacks the label {l:?}");
    }
}

#[test]
fn fig3_response() {
    let d = ResponseData::from_loop(
        &LoopModel::kaplan(LoopSpec::PAPER, None),
        0.05,
        20.0,
        200,
        "2nd order, Bn 3 Hz, ζ 0.707",
    )
    .unwrap();
    // The paper's loop: the peak at ωn/2π ≈ 0.900 Hz, |L| = π/(ζωn) ≈ 0.785 rad/Hz.
    assert!((d.peak_hz - 0.9003).abs() < 1e-3, "{}", d.peak_hz);
    // π/(ζωn) with ζωn = ωn/√2 and ωn = 2π·0.9003 Hz.
    let expect = std::f64::consts::PI / (std::f64::consts::FRAC_1_SQRT_2 * 5.6569);
    assert!((d.peak_rad_per_hz - expect).abs() < 1e-3, "{}", d.peak_rad_per_hz);
    // Unwrapped phase: −90° at low frequency, −180° at the peak, −270° far above.
    assert!((d.phase_deg[0] + 90.0).abs() < 5.0 && (d.phase_deg[199] + 270.0).abs() < 10.0, "{:?}", &d.phase_deg[..3]);
    check(
        "fig3_response",
        (1000, 640),
        &["|L| [rad/Hz]", "frequency f [Hz]", "phase of L [deg]", "peak 0.785"],
        |f, s| fig_response(&d, f, s),
    );
    // A discrete loop stops below its Nyquist frequency, and small figures work too.
    let dd =
        ResponseData::from_loop(&LoopModel::kaplan(LoopSpec::PAPER, Some(0.025)), 0.05, 100.0, 50, "discrete").unwrap();
    assert!(*dd.frequency_hz.last().unwrap() < 20.0);
    check("fig3_response_small", (480, 320), &["|L| [rad/Hz]"], |f, s| fig_response(&dd, f, s));
}

#[test]
fn fig4_estimation() {
    let s = session([true; 3]);
    let c = &s.calibration;
    assert_eq!(c.observable, [true; 3]);
    let d = EstimationData {
        t_s: &s.t_s,
        accel_mps2: &s.accel_mps2,
        history: &c.history,
        truth: Some(TRUTH),
        observable: c.observable,
    };
    check(
        "fig4_estimation",
        (1000, 700),
        &["specific force a [m/s²]", "Γ estimate [Hz/(m/s²)]", "time t [s]", "truth (dashed)"],
        |f, sz| fig_estimation(&d, f, sz),
    );
    // An unobservable axis is drawn and labelled as such.
    let s = session([true, true, false]);
    assert!(!s.calibration.observable[2]);
    let d = EstimationData {
        t_s: &s.t_s,
        accel_mps2: &s.accel_mps2,
        history: &s.calibration.history,
        truth: None,
        observable: s.calibration.observable,
    };
    check("fig4_estimation_unobservable", (900, 600), &["(unobservable)"], |f, sz| fig_estimation(&d, f, sz));
}

#[test]
fn fig5_compensation() {
    let s = session([true; 3]);
    let g = s.calibration.gamma_raw_hz_per_mps2;
    let after: Vec<Option<f64>> = s
        .phase_err_rad
        .iter()
        .zip(&s.phi_a)
        .map(|(p, a)| p.map(|p| p - (0..3).map(|i| a[i] * g[i]).sum::<f64>()))
        .collect();
    let d = CompensationData { t_s: &s.t_s, before_rad: &s.phase_err_rad, after_rad: &after, kind: Default::default() };
    check(
        "fig5_compensation",
        (1000, 500),
        &["phase tracking error [rad]", "time t [s]", "before compensation: φ", "after compensation", "RMS"],
        |f, sz| fig_compensation(&d, f, sz),
    );
}

#[test]
fn cn0() {
    let t: Vec<f64> = (0..2400).map(|k| k as f64 * 0.025).collect();
    let cn0: Vec<Vec<f64>> =
        (0..6).map(|c| t.iter().map(|&x| 38.0 + 2.0 * c as f64 + (x * 0.1 + c as f64).sin()).collect()).collect();
    // Channel 5 drops out for 10 s.
    let t5: Vec<f64> = t.iter().cloned().filter(|x| !(20.0..30.0).contains(x)).collect();
    let c5: Vec<f64> = t5.iter().map(|x| 44.0 + (x * 0.2).cos()).collect();
    let mut tracks: Vec<Cn0Track> = (0..5)
        .map(|c| Cn0Track { channel: c as u32, prn: 10 + c as u32, t_s: &t, cn0_dbhz: &cn0[c], used: c >= 2 })
        .collect();
    tracks.push(Cn0Track { channel: 5, prn: 31, t_s: &t5, cn0_dbhz: &c5, used: true });
    check("cn0", (1000, 560), &["C/N0 [dB-Hz]", "ch 5 PRN 31", "not used"], |f, sz| fig_cn0(&tracks, f, sz));
}

#[test]
fn residual_spectrum() {
    let s = session([true; 3]);
    let g = s.calibration.gamma_raw_hz_per_mps2;
    let (mut before, mut after) = (vec![], vec![]);
    for (p, a) in s.phase_err_rad.iter().zip(&s.phi_a).skip(80) {
        if let Some(p) = p {
            before.push(*p);
            after.push(p - (0..3).map(|i| a[i] * g[i]).sum::<f64>());
        }
    }
    let d = SpectrumData { interval_s: 0.025, residual_rad: &after, before_rad: Some(&before), marker_hz: Some(0.9) };
    check(
        "residual_spectrum",
        (1000, 600),
        &["PSD [rad²/Hz]", "frequency f [Hz]", "natural frequency", "before compensation"],
        |f, sz| fig_residual_spectrum(&d, f, sz),
    );
}

#[test]
fn allan() {
    let taus: Vec<f64> = (0..12).map(|k| 0.025 * 2f64.powi(k)).collect();
    let model = |t: f64| (2e-25 / (2.0 * t) + 2.0 * std::f64::consts::LN_2 * 7e-25 + 6.58 * 6e-25 * t).sqrt();
    let theory: Vec<f64> = taus.iter().map(|&t| model(t)).collect();
    let sim: Vec<f64> = taus
        .iter()
        .enumerate()
        .map(|(k, &t)| if k == 11 { f64::NAN } else { model(t) * (1.0 + 0.1 * (k as f64).sin()) })
        .collect();
    let d = AllanData { taus_s: &taus, simulated: &sim, theory: &theory, label: "OCXO preset" };
    check("allan", (900, 600), &["averaging time τ [s]", "Allan deviation", "OCXO preset"], |f, sz| {
        fig_allan(&d, f, sz)
    });
}

#[test]
fn bad_input_is_an_error_not_a_panic() {
    let d = ResponseData::from_loop(&LoopModel::kaplan(LoopSpec::PAPER, None), 0.05, 20.0, 50, "x").unwrap();
    assert!(matches!(fig_response(&d, Format::Png, (10, 10)), Err(RenderError::Size(10, 10))));
    let empty = ResponseData { frequency_hz: vec![], magnitude_rad_per_hz: vec![], phase_deg: vec![], ..d };
    assert!(matches!(fig_response(&empty, Format::Svg, (800, 600)), Err(RenderError::NoData(_))));
    let d = CompensationData {
        t_s: &[0.0, 1.0],
        before_rad: &[None, None],
        after_rad: &[None, None],
        kind: Default::default(),
    };
    assert!(matches!(fig_compensation(&d, Format::Svg, (800, 600)), Err(RenderError::NoData(_))));
    assert!(fig_cn0(&[], Format::Png, (800, 600)).is_err());
    let d = SpectrumData { interval_s: 0.025, residual_rad: &[0.0; 4], before_rad: None, marker_hz: None };
    assert!(fig_residual_spectrum(&d, Format::Png, (800, 600)).is_err());
    let d = AllanData { taus_s: &[1.0], simulated: &[f64::NAN], theory: &[0.0], label: "x" };
    assert!(fig_allan(&d, Format::Png, (800, 600)).is_err());
}
