//! Known data for the tests: a synthetic shaking session with a known Γ.
#![allow(dead_code)]

use gsens_calib::{Calibration, EpochSeries, EstimateSettings, calibrate, regressors};

/// The true Γ of the synthetic session \[Hz/(m/s²)\] (the paper's values).
pub(crate) const TRUTH: [f64; 3] = [0.09, 0.08, -0.08];

/// A 40 Hz, 60 s session: rest, then shaking along x, y, z in turn near the
/// loop's natural frequency, then all at once; φ = φ_aᵀΓ + deterministic noise.
pub(crate) struct Session {
    pub t_s: Vec<f64>,
    pub accel_mps2: Vec<[f64; 3]>,
    pub phase_err_rad: Vec<Option<f64>>,
    pub phi_a: Vec<[f64; 3]>,
    pub calibration: Calibration,
}

pub(crate) fn session(shake: [bool; 3]) -> Session {
    session_shaken(shake, 3.0)
}

/// [`session`] with the shaking's amplitude `amplitude_mps2` \[m/s²\] (3 in [`session`]).
pub(crate) fn session_shaken(shake: [bool; 3], amplitude_mps2: f64) -> Session {
    let dt = 0.025;
    let n = 2400;
    let t_s: Vec<f64> = (0..n).map(|k| k as f64 * dt).collect();
    let tau = std::f64::consts::TAU;
    let accel_mps2: Vec<[f64; 3]> = t_s
        .iter()
        .map(|&t| {
            let mut a = [0.0, 0.0, 9.81];
            for i in 0..3 {
                let (lo, hi) = (8.0 + 14.0 * i as f64, 20.0 + 14.0 * i as f64);
                let on = (t >= lo && t < hi) || t >= 50.0;
                if shake[i] && on {
                    a[i] += amplitude_mps2 * (tau * (0.8 + 0.1 * i as f64) * t).sin();
                }
            }
            a
        })
        .collect();
    let settings = EstimateSettings::default();
    let none = vec![None; n];
    let series0 = EpochSeries {
        log_interval_s: dt,
        t_s: &t_s,
        phase_err_rad: &none,
        accel_mps2: &accel_mps2,
        imu_time_offset_s: 0.0,
    };
    let phi_a = regressors(&series0, &settings).unwrap();
    let mut phase_err_rad = vec![None; n];
    let mut s: u64 = 7;
    for k in 0..n {
        s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        let noise = ((s >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 0.02;
        let g: f64 = (0..3).map(|i| phi_a[k][i] * TRUTH[i]).sum();
        // A short gap, as when all channels drop out.
        phase_err_rad[k] = if (1500..1520).contains(&k) { None } else { Some(g + noise) };
    }
    let series = EpochSeries { phase_err_rad: &phase_err_rad, ..series0 };
    let calibration = calibrate(&series, &settings).unwrap();
    Session { t_s, accel_mps2, phase_err_rad, phi_a, calibration }
}

/// PNG facts: (width, height, distinct colours, fraction of non-white pixels).
pub(crate) fn png_facts(bytes: &[u8]) -> (u32, u32, usize, f64) {
    let decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    let mut reader = decoder.read_info().expect("a PNG header");
    let mut buf = vec![0; reader.output_buffer_size().expect("a buffer size")];
    let info = reader.next_frame(&mut buf).expect("a PNG frame");
    assert_eq!(info.color_type, png::ColorType::Rgb);
    let px = &buf[..info.buffer_size()];
    let mut colours = std::collections::HashSet::new();
    let mut ink = 0usize;
    for p in px.chunks_exact(3) {
        colours.insert([p[0], p[1], p[2]]);
        if p != [255, 255, 255] {
            ink += 1;
        }
    }
    (info.width, info.height, colours.len(), ink as f64 / (px.len() / 3) as f64)
}

/// A minimal well-formedness check of an SVG document: one root `<svg>`
/// element, every start tag closed in order, attribute quotes balanced.
pub(crate) fn check_svg(svg: &str, size: (u32, u32)) {
    let body = svg.trim();
    let body = if body.starts_with("<?xml") { body.split_once("?>").unwrap().1.trim() } else { body };
    assert!(body.starts_with("<svg"), "no <svg> root: {}", &body[..body.len().min(80)]);
    assert!(body.ends_with("</svg>"));
    assert!(body.contains(&format!("width=\"{}\"", size.0)) && body.contains(&format!("height=\"{}\"", size.1)));
    let mut stack: Vec<String> = Vec::new();
    let mut rest = body;
    let mut tags = 0;
    while let Some(i) = rest.find('<') {
        let j = rest[i..].find('>').expect("an unterminated tag") + i;
        let tag = &rest[i + 1..j];
        assert_eq!(tag.matches('"').count() % 2, 0, "unbalanced quotes in <{tag}>");
        if let Some(name) = tag.strip_prefix('/') {
            assert_eq!(stack.pop().as_deref(), Some(name.trim()), "mismatched </{name}>");
        } else if !tag.ends_with('/') {
            stack.push(tag.split_whitespace().next().unwrap().to_string());
        }
        tags += 1;
        rest = &rest[j + 1..];
    }
    assert!(stack.is_empty(), "unclosed: {stack:?}");
    assert!(tags > 50, "only {tags} tags");
}

/// Where the tests leave their figures, to be looked at.
pub(crate) fn out_dir() -> std::path::PathBuf {
    let d = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("gsens-report-figures");
    std::fs::create_dir_all(&d).unwrap();
    d
}
