//! The HTML report, its JSON and the C header from a known calibration.

mod common;

use common::{TRUTH, out_dir, session};
use gsens_calib::{LoopIdentificationMode, PipelineSummary, ResultDocument, TimeOffset};
use gsens_core::LoopModel;
use gsens_core::LoopSpec;
use gsens_report::cheader::render_c_header;
use gsens_report::figures::*;
use gsens_report::html::render_html;
use gsens_report::json::report_json;
use gsens_report::{FigureBlock, ReportData, ReportMeta};
use gsens_session::{ChannelSummary, SelectionConfig};

fn meta() -> ReportMeta {
    ReportMeta {
        generated_utc: "2025-01-31 12:34:56 UTC".into(),
        tool: "gsens 0.1.0".into(),
        inputs: vec![("imu".into(), "logs/imu <1>.csv".into()), ("tracking".into(), "logs/tracking.csv".into())],
    }
}

fn channels() -> Vec<ChannelSummary> {
    (0..5)
        .map(|k| ChannelSummary {
            channel: k,
            prn: 3 + k,
            mean_cn0_dbhz: 40.0 + k as f64,
            epochs: 2400,
            used: k > 0,
            reason: if k > 0 { "used".into() } else { "not among the 4 strongest".into() },
            phase_offset_rad: (k > 0).then_some(0.01 * k as f64),
            screening: Default::default(),
            signal: "L1CA".into(),
            carrier_hz: gsens_core::units::GPS_L1_HZ,
        })
        .collect()
}

/// The result document of the synthetic session, as the pipeline would write it.
fn document(c: &gsens_calib::Calibration, truth: Option<[f64; 3]>) -> ResultDocument {
    let pipeline = PipelineSummary {
        time_offset: TimeOffset::Fixed { imu_time_offset_s: 0.0 },
        loop_identification: LoopIdentificationMode::Off,
    };
    let inputs = [("imu", "logs/imu <1>.csv"), ("tracking", "logs/tracking.csv")];
    ResultDocument::from_parts(c.clone(), channels(), SelectionConfig::default(), pipeline, &inputs, truth)
}

fn figures(s: &common::Session) -> Vec<FigureBlock> {
    let c = &s.calibration;
    let resp =
        ResponseData::from_loop(&LoopModel::kaplan(LoopSpec::PAPER, None), 0.05, 20.0, 100, "paper loop").unwrap();
    let est = EstimationData {
        t_s: &s.t_s,
        accel_mps2: &s.accel_mps2,
        history: &c.history,
        truth: Some(TRUTH),
        observable: c.observable,
    };
    let svg = |i: Image| i.svg().unwrap().to_string();
    vec![
        FigureBlock {
            id: "fig3_response".into(),
            title: "Loop response".into(),
            caption: "|L| & phase <b>".into(),
            svg: svg(fig_response(&resp, Format::Svg, DEFAULT_SIZE).unwrap()),
        },
        FigureBlock {
            id: "fig4_estimation".into(),
            title: "Estimation process".into(),
            caption: "Γ̂ converging".into(),
            svg: svg(fig_estimation(&est, Format::Svg, DEFAULT_SIZE).unwrap()),
        },
    ]
}

#[test]
fn html_report_is_self_contained_and_complete() {
    let s = session([true; 3]);
    let c = &s.calibration;
    let header = render_c_header(c, &meta());
    let doc = document(c, Some(TRUTH));
    let data = ReportData {
        title: "g-sensitivity calibration".into(),
        document: &doc,
        meta: meta(),
        figures: figures(&s),
        c_header: Some(header),
    };
    let html = render_html(&data);
    std::fs::write(out_dir().join("report.html"), &html).unwrap();
    assert!(html.starts_with("<!DOCTYPE html>") && html.trim_end().ends_with("</html>"));
    // The estimate, its uncertainty, the verdicts, the RMS.
    for i in 0..3 {
        let g = c.gamma_hz_per_mps2[i].unwrap();
        assert!(html.contains(&format!("{g:+.5}")), "Γ̂{i} missing");
        assert!(html.contains(&format!("±{:.5}", c.sigma_hz_per_mps2[i].unwrap())));
        assert!(html.contains(&format!("{:+.4}", c.gamma_ppb_per_g[i].unwrap())));
    }
    assert_eq!(html.matches("<span class=\"tag ok\">observable</span>").count(), 3);
    assert!(html.contains("All three axes observable"));
    assert!(
        html.contains(&format!("{:.4} rad", c.rms_before_rad)) && html.contains(&format!("{:.4} rad", c.rms_after_rad))
    );
    // Every setting.
    for key in [
        "settings.method.name",
        "settings.receiver_loop.spec.bn_hz",
        "settings.warmup_s",
        "settings.carrier_hz",
        "selection.max_channels",
        "settings.criteria.min_excitation_rms",
    ] {
        assert!(html.contains(&format!("<code>{key}</code>")), "setting {key} missing");
    }
    // Inline SVG figures with a viewBox, nothing fetched from outside, user text escaped.
    assert_eq!(html.matches("<svg ").count(), 2);
    assert!(html.contains("viewBox=\"0 0 1000 640\""));
    for bad in ["<script", "src=\"http", "href=\"http", "@import", "url("] {
        assert!(!html.contains(bad), "found {bad}");
    }
    assert!(html.contains("logs/imu &lt;1&gt;.csv") && !html.contains("imu <1>"));
    assert!(html.contains("&amp; phase &lt;b&gt;"));
    assert!(html.contains("#define GSENS_GAMMA_X_HZ_PER_MPS2"));
    // The truth and the error.
    assert!(html.contains("|Γ̂ − Γ|"));
}

#[test]
fn unobservable_axis_is_reported_not_invented() {
    let s = session([true, true, false]);
    let c = &s.calibration;
    assert_eq!(c.observable, [true, true, false]);
    let doc = document(c, None);
    let data = ReportData { title: "t".into(), document: &doc, meta: meta(), figures: vec![], c_header: None };
    let html = render_html(&data);
    assert!(html.contains("Not observable along z"));
    assert_eq!(html.matches("<span class=\"tag bad\">unobservable</span>").count(), 1);

    let h = render_c_header(c, &meta());
    assert!(h.contains("#define GSENS_GAMMA_Z_OBSERVABLE 0"));
    assert!(h.contains("#define GSENS_GAMMA_Z_HZ_PER_MPS2 (0.0)"));
    assert!(!h.contains("GSENS_GAMMA_Z_SIGMA"));
    assert!(h.contains("NOT OBSERVABLE"));
    assert!(h.contains("#define GSENS_GAMMA_OBSERVABLE_MASK 3u"));
}

#[test]
fn json_has_the_estimate_shape() {
    let s = session([true; 3]);
    let c = &s.calibration;
    let doc = document(c, Some(TRUTH));
    let data = ReportData { title: "t".into(), document: &doc, meta: meta(), figures: figures(&s), c_header: None };
    let v = report_json(&data).unwrap();
    for key in [
        "gamma_hz_per_mps2",
        "sigma_hz_per_mps2",
        "gamma_ppb_per_g",
        "observable",
        "imu_time_offset_s",
        "settings",
        "rms_before_rad",
        "rms_after_rad",
        "channels",
        "selection",
        "inputs",
        "truth_gamma_hz_per_mps2",
        "report",
    ] {
        assert!(v.get(key).is_some(), "{key} missing");
    }
    assert_eq!(v["gamma_hz_per_mps2"][0].as_f64(), c.gamma_hz_per_mps2[0]);
    assert_eq!(v["inputs"]["tracking"], "logs/tracking.csv");
    assert_eq!(v["channels"].as_array().unwrap().len(), 5);
    assert_eq!(v["report"]["figures"][1]["id"], "fig4_estimation");
    assert_eq!(v["report"]["generated_utc"], "2025-01-31 12:34:56 UTC");
}

/// The header compiles as C99 with warnings as errors and carries the
/// estimate exactly (skipped where no C compiler is installed).
#[test]
fn c_header_compiles_and_round_trips() {
    let s = session([true; 3]);
    let c = &s.calibration;
    let h = render_c_header(c, &meta());
    assert!(h.contains("#ifndef GSENS_GAMMA_H") && h.contains("#endif"));
    assert!(h.contains("2025-01-31") && h.contains("logs/tracking.csv"));
    assert!(h.contains("Axis convention"));
    let dir = out_dir().join("cheader");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("gsens_gamma.h"), &h).unwrap();
    let cc = std::env::var("CC").unwrap_or_else(|_| "cc".into());
    if std::process::Command::new(&cc).arg("--version").output().is_err() {
        eprintln!("no C compiler ({cc}): compile check skipped");
        return;
    }
    std::fs::write(
        dir.join("main.c"),
        "#include <stdio.h>\n#include \"gsens_gamma.h\"\n\
         int main(void) {\n  static const double g[3] = GSENS_GAMMA_HZ_PER_MPS2_INIT;\n\
         static const double p[3] = GSENS_GAMMA_PPB_PER_G_INIT;\n\
         printf(\"%.17g %.17g %.17g %.17g %u %s %g\\n\", g[0], g[1], g[2], p[2], GSENS_GAMMA_OBSERVABLE_MASK, GSENS_CALIBRATION_DATE, GSENS_GAMMA_X_SIGMA_HZ_PER_MPS2);\n  return 0;\n}\n",
    )
    .unwrap();
    let exe = dir.join("main");
    let out = std::process::Command::new(&cc)
        .args(["-std=c99", "-Wall", "-Wextra", "-pedantic", "-Werror", "-o"])
        .arg(&exe)
        .arg(dir.join("main.c"))
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let run = std::process::Command::new(&exe).output().unwrap();
    let text = String::from_utf8(run.stdout).unwrap();
    let f: Vec<&str> = text.split_whitespace().collect();
    for i in 0..3 {
        assert_eq!(f[i].parse::<f64>().unwrap(), c.gamma_hz_per_mps2[i].unwrap(), "axis {i}");
    }
    assert_eq!(f[3].parse::<f64>().unwrap(), c.gamma_ppb_per_g[2].unwrap());
    assert_eq!(f[4], "7");
    assert_eq!(f[5], "2025-01-31");
}

/// The text names each channel's signal and each signal's scaling to L1 when
/// the log holds carriers other than GPS L1 C/A, and neither for an L1-only log.
#[test]
fn text_lists_signals_only_for_mixed_logs() {
    let c = session([true, true, true]).calibration;
    let plain = gsens_report::render_text(&document(&c, None));
    assert!(!plain.contains("signals (") && !plain.contains("L1CA"), "{plain}");
    // A log without carrier columns: GPS L1, unnamed (one signal summary).
    let mut unnamed = document(&c, None);
    let l1 = gsens_core::units::GPS_L1_HZ;
    unnamed.signals = vec![gsens_session::SignalSummary {
        signal: "1575.42 MHz".into(),
        carrier_hz: l1,
        scale_to_l1: 1.0,
        tracks: 5,
        tracks_used: 4,
    }];
    for ch in &mut unnamed.channels {
        ch.signal = "1575.42 MHz".into();
    }
    let text = gsens_report::render_text(&unnamed);
    assert!(!text.contains("signals (") && !text.contains("MHz"), "{text}");
    let mut doc = document(&c, None);
    let g1 = 1_602.562_5e6;
    doc.channels[2].signal = "G1:+1".into();
    doc.channels[2].carrier_hz = g1;
    doc.signals = vec![
        gsens_session::SignalSummary {
            signal: "L1CA".into(),
            carrier_hz: gsens_core::units::GPS_L1_HZ,
            scale_to_l1: 1.0,
            tracks: 4,
            tracks_used: 3,
        },
        gsens_session::SignalSummary {
            signal: "G1:+1".into(),
            carrier_hz: g1,
            scale_to_l1: gsens_core::units::GPS_L1_HZ / g1,
            tracks: 1,
            tracks_used: 1,
        },
    ];
    let text = gsens_report::render_text(&doc);
    assert!(
        text.contains("signals (phase × f_L1/f_c, averaged on L1): L1CA 1575.4200 MHz ×1.00000, 3 of 4 tracks; G1:+1 1602.5625 MHz ×0.98306, 1 of 1 tracks"),
        "{text}"
    );
    assert!(text.lines().any(|l| l.contains("PRN   5  G1:+1")), "{text}");
    assert!(text.lines().any(|l| l.contains("PRN   4  L1CA")), "{text}");
}
