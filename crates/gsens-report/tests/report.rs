//! The HTML report, its JSON and the C header from a known calibration.

mod common;

use common::{TRUTH, out_dir, session, session_shaken};
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
    let doc = document(c, Some(TRUTH));
    assert!(doc.trustworthy && doc.warnings.is_empty(), "{:?}", doc.warnings);
    let header = render_c_header(&doc, &meta());
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
    assert!(html.contains("All three axes observable: Γ̂ is complete."));
    assert!(html.contains("<div class=\"banner ok\" id=\"verdict\">TRUSTWORTHY"));
    assert!(!html.contains("NOT TRUSTWORTHY") && !html.contains("class=\"num untrusted"));
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

    let h = render_c_header(&doc, &meta());
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
    let h = render_c_header(&document(c, None), &meta());
    assert!(h.contains("#ifndef GSENS_GAMMA_H") && h.contains("#endif"));
    assert!(h.contains(" * VERDICT: TRUSTWORTHY (GSENS_GAMMA_TRUSTWORTHY 1)"));
    assert!(h.contains("2025-01-31") && h.contains("logs/tracking.csv"));
    assert!(h.contains("Axis convention"));
    // Lines fit the report's code block: none is wider than 100 characters but
    // those that quote an input's path.
    for line in h.lines().filter(|l| !l.contains("logs/")) {
        assert!(line.chars().count() <= 100, "{} characters: {line}", line.chars().count());
    }
    let Some(text) = compile_and_run(&h, "cheader") else { return };
    let f: Vec<&str> = text.split_whitespace().collect();
    for i in 0..3 {
        assert_eq!(f[i].parse::<f64>().unwrap(), c.gamma_hz_per_mps2[i].unwrap(), "axis {i}");
    }
    assert_eq!(f[3].parse::<f64>().unwrap(), c.gamma_ppb_per_g[2].unwrap());
    assert_eq!(f[4], "7");
    assert_eq!(f[5], "2025-01-31");
    assert_eq!(f[7], "1", "GSENS_GAMMA_TRUSTWORTHY");
}

/// `header` in `out_dir()/name`, included by a C99 program (warnings as
/// errors) that prints Γ̂, the mask, the date, σ_x and the verdict; its
/// output, or `None` where no C compiler is installed.
fn compile_and_run(header: &str, name: &str) -> Option<String> {
    let dir = out_dir().join(name);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("gsens_gamma.h"), header).unwrap();
    let cc = std::env::var("CC").unwrap_or_else(|_| "cc".into());
    if std::process::Command::new(&cc).arg("--version").output().is_err() {
        eprintln!("no C compiler ({cc}): compile check skipped");
        return None;
    }
    std::fs::write(
        dir.join("main.c"),
        "#include <stdio.h>\n#include \"gsens_gamma.h\"\n\
         int main(void) {\n  static const double g[3] = GSENS_GAMMA_HZ_PER_MPS2_INIT;\n\
         static const double p[3] = GSENS_GAMMA_PPB_PER_G_INIT;\n\
         printf(\"%.17g %.17g %.17g %.17g %u %s %g %d\\n\", g[0], g[1], g[2], p[2], GSENS_GAMMA_OBSERVABLE_MASK, GSENS_CALIBRATION_DATE, GSENS_GAMMA_X_SIGMA_HZ_PER_MPS2, GSENS_GAMMA_TRUSTWORTHY);\n\
         #if !GSENS_GAMMA_TRUSTWORTHY\n  puts(\"untrusted\");\n#endif\n  return 0;\n}\n",
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
    Some(String::from_utf8(run.stdout).unwrap())
}

/// A session shaken 6× harder than [`session`]: the predicted g-induced phase
/// error passes the discriminator's linear range, so the document calls the
/// estimate untrustworthy (`discriminator_range`), and every output says so.
fn untrustworthy() -> (common::Session, ResultDocument) {
    let s = session_shaken([true; 3], 18.0);
    let doc = document(&s.calibration, Some(TRUTH));
    assert!(!doc.trustworthy, "{:?}", doc.warnings);
    assert_eq!(doc.untrusted_codes(), ["discriminator_range"], "{:?}", doc.warnings);
    assert_eq!(doc.calibration.observable, [true; 3]);
    (s, doc)
}

#[test]
fn an_untrustworthy_estimate_says_so_in_the_text_and_the_json() {
    let (s, doc) = untrustworthy();
    let text = gsens_report::render_text(&doc);
    let verdict = "verdict: NOT TRUSTWORTHY (discriminator_range): do not use Γ̂ before the warnings are resolved";
    // Before the estimate and again at the end, after the warning itself.
    assert!(
        text.starts_with(&format!("warning [discriminator_range]: {}\n{verdict}\n", doc.warnings[0].message)),
        "{text}"
    );
    assert!(text.trim_end().ends_with(verdict), "{text}");
    let data = ReportData { title: "t".into(), document: &doc, meta: meta(), figures: figures(&s), c_header: None };
    let v = report_json(&data).unwrap();
    assert_eq!(v["trustworthy"], false);
    assert_eq!(v["warnings"][0]["code"], "discriminator_range");
    assert_eq!(v["warnings"][0]["message"].as_str(), Some(doc.warnings[0].message.as_str()));
}

#[test]
fn an_untrustworthy_estimate_has_a_red_banner_and_marked_numbers_in_the_html() {
    let (s, doc) = untrustworthy();
    let c = &doc.calibration;
    let data = ReportData { title: "t".into(), document: &doc, meta: meta(), figures: figures(&s), c_header: None };
    let html = render_html(&data);
    std::fs::write(out_dir().join("report-untrustworthy.html"), &html).unwrap();
    // The red banner above the table, with each warning's code and message (its fix).
    let banner =
        html.find("<div class=\"banner bad\" id=\"verdict\" role=\"alert\">NOT TRUSTWORTHY (discriminator_range)");
    let table = html.find("id=\"estimate-table\"").unwrap();
    assert!(banner.is_some_and(|b| b < table), "no red verdict banner above the table");
    let item =
        format!("<li><code>discriminator_range</code>: {}</li>", gsens_report::html::escape(&doc.warnings[0].message));
    assert!(html[..table].contains(&item), "the warning and its fix in the banner");
    assert!(html.contains("(no gsens_gamma.h was written)"));
    // No green note: every axis observable, but Γ̂ is not complete in any useful sense.
    assert!(
        !html.contains("Γ̂ is complete") && !html.contains("banner ok"),
        "a green note on an untrustworthy estimate"
    );
    assert!(html.contains("All three axes observable, but Γ̂ is not trustworthy"));
    // Each Γ̂ cell (Hz/(m/s²) and ppb/g) is marked, and the numbers are still shown.
    let marked = "<td class=\"num untrusted\" title=\"not trustworthy: discriminator_range\">";
    assert_eq!(html.matches(marked).count(), 6, "{}", &html[table..table + 1500]);
    for i in 0..3 {
        assert!(html.contains(&format!("{marked}{:+.5}</td>", c.gamma_hz_per_mps2[i].unwrap())), "Γ̂{i}");
        assert!(html.contains(&format!("{marked}{:+.4}</td>", c.gamma_ppb_per_g[i].unwrap())), "Γ̂{i} ppb/g");
    }
    assert!(html.contains("<caption class=\"untrusted\">"));
}

#[test]
fn an_untrustworthy_header_says_so_and_compiles() {
    let (_, doc) = untrustworthy();
    let h = render_c_header(&doc, &meta());
    assert!(h.is_ascii(), "the header's text must be ASCII");
    let comment_end = h.find("*/").unwrap();
    let comment = &h[..comment_end];
    assert!(comment.contains(" * VERDICT: NOT TRUSTWORTHY (GSENS_GAMMA_TRUSTWORTHY 0): discriminator_range."), "{h}");
    assert!(comment.contains(" *   discriminator_range: the predicted g-induced phase error reaches"), "{h}");
    // The whole message is there, wrapped, in ASCII.
    let joined: String = comment.lines().map(|l| l.trim_start_matches(" *").trim()).collect::<Vec<_>>().join(" ");
    assert!(joined.contains("shake more gently or the phase error wraps and biases Gamma-hat low"), "{h}");
    let warnings = &comment[comment.find(" * Warnings:").unwrap()..];
    assert!(warnings.lines().all(|l| l.len() <= 92), "{h}");
    assert!(h.contains("#define GSENS_GAMMA_TRUSTWORTHY 0\n"));
    let Some(text) = compile_and_run(&h, "cheader-untrusted") else { return };
    let f: Vec<&str> = text.split_whitespace().collect();
    assert_eq!(f[7], "0", "GSENS_GAMMA_TRUSTWORTHY");
    assert_eq!(f[8], "untrusted", "#if !GSENS_GAMMA_TRUSTWORTHY");
    assert_eq!(f[0].parse::<f64>().unwrap(), doc.calibration.gamma_hz_per_mps2[0].unwrap());
}

/// `write_report_dir` writes no header for an untrustworthy estimate (and
/// removes one an earlier report left), unless asked to.
#[test]
fn no_header_is_written_for_an_untrustworthy_estimate_unless_asked() {
    let (_, doc) = untrustworthy();
    let dir = out_dir().join("untrusted-dir");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("gsens_gamma.h"), "/* an earlier, trusted report's */").unwrap();
    let files = gsens_report::write_report_dir(&dir, "t", &doc, &[], false, |_| {}).unwrap();
    assert_eq!(files.header, None);
    assert!(!dir.join("gsens_gamma.h").exists(), "a header left beside an untrustworthy report");
    assert!(std::fs::read_to_string(&files.html).unwrap().contains("NOT TRUSTWORTHY"));
    let files = gsens_report::write_report_dir(&dir, "t", &doc, &[], true, |_| {}).unwrap();
    let h = std::fs::read_to_string(files.header.unwrap()).unwrap();
    assert!(h.contains("#define GSENS_GAMMA_TRUSTWORTHY 0"));
    assert!(std::fs::read_to_string(&files.html).unwrap().contains("#define GSENS_GAMMA_TRUSTWORTHY 0"));
    // A trustworthy estimate always gets its header.
    let good = document(&session([true; 3]).calibration, None);
    let files = gsens_report::write_report_dir(&dir, "t", &good, &[], false, |_| {}).unwrap();
    assert!(std::fs::read_to_string(files.header.unwrap()).unwrap().contains("#define GSENS_GAMMA_TRUSTWORTHY 1"));
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

/// A written report's text is the document's and where the files are;
/// without a header, a second text says why and names the setting as the
/// caller spells it.
#[test]
fn a_report_without_its_header_says_why() {
    let doc = document(&session([true, true, false]).calibration, None);
    let mut files = gsens_report::ReportFiles { html: "out/report.html".into(), header: None };
    let (text, no_header) = files.render(&doc, |name| format!("<{name}>"));
    assert_eq!(text, format!("{}\n{}\n", gsens_report::render_text(&doc), files.summary()));
    let expected = format!(
        "gsens_gamma.h not written: the estimate is not trustworthy ({}); <write_untrusted_header> writes it \
         anyway, marked GSENS_GAMMA_TRUSTWORTHY 0\n",
        doc.untrusted_codes().join(", ")
    );
    assert_eq!(no_header.as_deref(), Some(expected.as_str()));
    files.header = Some("out/gsens_gamma.h".into());
    assert_eq!(files.render(&doc, |name| name.into()).1, None);
}
