//! `gsens report` on a simulated session, `gsens response --plot` and
//! `gsens demo --figures`: the files they promise, well formed.

mod common;

use common::{gsens, imu_in_g, json, run, s, temp_dir};

use std::path::Path;
use std::process::Command;

fn assert_png(path: &Path) {
    let b = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert!(b.starts_with(b"\x89PNG\r\n\x1a\n"), "{} is not a PNG", path.display());
    // IHDR: width and height, big-endian, at bytes 16..24.
    let w = u32::from_be_bytes(b[16..20].try_into().unwrap());
    let h = u32::from_be_bytes(b[20..24].try_into().unwrap());
    assert!(w >= 800 && h >= 400 && b.len() > 10_000, "{}: {w}×{h}, {} bytes", path.display(), b.len());
}

fn assert_svg(path: &Path) {
    let s = std::fs::read_to_string(path).unwrap();
    assert!(s.trim_start().starts_with("<svg") && s.trim_end().ends_with("</svg>"), "{}", path.display());
    assert!(s.matches("<text").count() > 10, "{}: too few labels", path.display());
}

#[test]
fn report_writes_html_json_header_and_figures() {
    let dir_scratch = tempfile::Builder::new().prefix("gsens-report-").tempdir().unwrap();
    let dir = dir_scratch.path().to_path_buf();
    let d = dir.to_str().unwrap();
    gsens(&["simulate", "--out", &format!("{d}/sim"), "--seed", "3"]);
    let out = format!("{d}/report");
    let text = gsens(&[
        "report",
        "--imu",
        &format!("{d}/sim/imu.csv"),
        "--tracking",
        &format!("{d}/sim/tracking.csv"),
        "--truth",
        &format!("{d}/sim/truth.json"),
        "--loop-interval-s",
        "0.001",
        "--logged-phase",
        "mean",
        "--loop-implementation",
        "kaplan",
        "--out",
        &out,
    ]);
    assert!(text.contains("report.html"), "{text}");
    let out = Path::new(&out);

    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert_eq!(html.matches("<svg ").count(), 6, "Figs. 3–5, the measured response, C/N0, residual spectrum");
    assert!(html.contains("response measured from the session"), "the measured response figure");
    for needle in [
        "id=\"verdict\"",
        "id=\"estimate-table\"",
        "id=\"rms-before\"",
        "<code>settings.receiver_loop.spec.bn_hz</code>",
    ] {
        assert!(html.contains(needle), "report.html lacks {needle}");
    }
    assert!(!html.contains("<script") && !html.contains("<img"), "the report must be self-contained");

    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    assert_eq!(v["gamma_hz_per_mps2"].as_array().unwrap().len(), 3);
    assert_eq!(v["observable"], serde_json::json!([true, true, true]));
    assert_eq!(v["report"]["figures"].as_array().unwrap().len(), 6);
    assert!(v["truth_gamma_hz_per_mps2"].is_array());
    let g0 = v["gamma_hz_per_mps2"][0].as_f64().unwrap();
    // `estimate --json` writes the same result document: every key but the
    // report's own block agrees, value for value (the loop's form named, as
    // the truth file names it for `report`).
    let est_json = format!("{d}/estimate.json");
    gsens(&[
        "estimate",
        "--imu",
        &format!("{d}/sim/imu.csv"),
        "--tracking",
        &format!("{d}/sim/tracking.csv"),
        "--loop-interval-s",
        "0.001",
        "--logged-phase",
        "mean",
        "--loop-implementation",
        "kaplan",
        "--json",
        &est_json,
    ]);
    let e: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&est_json).unwrap()).unwrap();
    let (mut e, mut r) = (e.as_object().unwrap().clone(), v.as_object().unwrap().clone());
    assert!(r.remove("report").is_some() && r.remove("truth_gamma_hz_per_mps2").is_some());
    let (ei, ri) = (e.remove("inputs").unwrap(), r.remove("inputs").unwrap());
    assert_eq!(ei["imu"], ri["imu"]);
    assert_eq!(e.keys().collect::<Vec<_>>(), r.keys().collect::<Vec<_>>());
    for (k, x) in &e {
        assert_eq!(x, &r[k], "estimate --json and report.json differ in `{k}`");
    }

    let h = std::fs::read_to_string(out.join("gsens_gamma.h")).unwrap();
    assert!(h.contains("#ifndef GSENS_GAMMA_H") && h.contains("GSENS_GAMMA_OBSERVABLE_MASK 7u"));
    let line = h.lines().find(|l| l.starts_with("#define GSENS_GAMMA_X_HZ_PER_MPS2 ")).unwrap();
    let lit = line.rsplit(' ').next().unwrap().trim_matches(|c| c == '(' || c == ')');
    assert_eq!(lit.parse::<f64>().unwrap(), g0, "the header carries the JSON's estimate exactly");

    for f in ["fig3_response", "fig4_estimation", "fig5_compensation", "cn0", "residual_spectrum"] {
        assert_png(&out.join("figures").join(format!("{f}.png")));
        assert_svg(&out.join("figures").join(format!("{f}.svg")));
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn response_plot_and_demo_figures() {
    let dir_scratch = tempfile::Builder::new().prefix("gsens-figs-").tempdir().unwrap();
    let dir = dir_scratch.path().to_path_buf();
    std::fs::create_dir_all(&dir).unwrap();
    let png = dir.join("fig3.png");
    let svg = dir.join("fig3.svg");
    gsens(&["response", "--plot", png.to_str().unwrap()]);
    gsens(&["response", "--plot", svg.to_str().unwrap(), "--order", "3", "--loop-interval-s", "0.005"]);
    assert_png(&png);
    assert_svg(&svg);
    let bad = Command::new(env!("CARGO_BIN_EXE_gsens")).args(["response", "--plot", "x.jpg"]).output().unwrap();
    assert!(!bad.status.success());

    let figs = dir.join("demo");
    gsens(&["demo", "--out", dir.join("logs").to_str().unwrap(), "--figures", figs.to_str().unwrap()]);
    for f in ["fig3_response", "fig4_estimation", "fig5_compensation", "cn0", "residual_spectrum", "allan"] {
        assert_png(&figs.join(format!("{f}.png")));
        assert_svg(&figs.join(format!("{f}.svg")));
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// `gsens report` on an IMU logged in g (the document says `imu_units`):
/// status 3, and every output carries the verdict: the text, report.json,
/// report.html's red banner; no gsens_gamma.h unless asked for, and then one
/// that says GSENS_GAMMA_TRUSTWORTHY 0 with the warning.
#[test]
fn an_untrustworthy_report_says_so_in_every_file_and_writes_no_header() {
    let dir = temp_dir("report-untrusted");
    let sim = dir.join("sim");
    gsens(&["simulate", "--out", &s(&sim), "--seed", "3"]);
    imu_in_g(&sim.join("imu.csv"), &sim.join("imu_g.csv"));
    let out = dir.join("report");
    let (imu, tracking, truth) = (s(&sim.join("imu_g.csv")), s(&sim.join("tracking.csv")), s(&sim.join("truth.json")));
    let args = ["report", "--imu", &imu, "--tracking", &tracking, "--truth", &truth, "--out", &s(&out)];
    let o = run(&args);
    let (text, err) = (String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    assert_eq!(o.status.code(), Some(3), "{text}\n{err}");
    assert!(text.contains("verdict: NOT TRUSTWORTHY (imu_units)"), "{text}");
    assert!(text.contains("(with report.json and figures/ beside it)"), "{text}");
    assert!(err.contains("gsens_gamma.h not written: the estimate is not trustworthy (imu_units)"), "{err}");
    assert!(!out.join("gsens_gamma.h").exists(), "a header for an untrustworthy estimate");
    let v = json(&out.join("report.json"));
    assert_eq!(v["trustworthy"], false);
    assert_eq!(v["warnings"][0]["code"], "imu_units", "{}", v["warnings"]);
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert!(html.contains("id=\"verdict\" role=\"alert\">NOT TRUSTWORTHY (imu_units)"));
    assert!(html.contains("<li><code>imu_units</code>: the specific force at rest"));
    assert!(!html.contains("Γ̂ is complete"), "the green note on an untrustworthy estimate");
    assert_eq!(html.matches("class=\"num untrusted\"").count(), 6);

    let o = run(&[&args[..], &["--write-untrusted-header"]].concat());
    assert_eq!(o.status.code(), Some(3));
    let h = std::fs::read_to_string(out.join("gsens_gamma.h")).unwrap();
    assert!(h.contains("#define GSENS_GAMMA_TRUSTWORTHY 0\n"), "{h}");
    assert!(h.contains(" * VERDICT: NOT TRUSTWORTHY (GSENS_GAMMA_TRUSTWORTHY 0): imu_units."), "{h}");
    assert!(h.contains(" *   imu_units: the specific force at rest"), "{h}");
    std::fs::remove_dir_all(&dir).ok();
}
