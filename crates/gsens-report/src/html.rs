//! The calibration report as one self-contained HTML file.
//!
//! Inline CSS and inline SVG figures; no script, no font, image or style
//! sheet fetched from anywhere, so the file can be mailed or archived as is.
//! Every string that comes from the user (paths, titles, reasons) is escaped.

use crate::{AXES, ReportData};
use gsens_core::units::Decimal;
use gsens_core::units::hz_per_mps2_to_ppb_per_g;
use serde_json::Value;
use std::fmt::Write as _;

/// Escapes `&`, `<`, `>`, `"` and `'` for HTML text and attribute values.
pub fn escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            _ => out.push(c),
        }
    }
    out
}

/// An SVG document from [`crate::figures`] made fit to sit inline: the XML
/// declaration dropped, a `viewBox` added so that CSS can scale it, and a
/// `role="img"` with the title for screen readers.
fn inline_svg(svg: &str, title: &str) -> String {
    let svg = svg.trim_start();
    let svg =
        if svg.starts_with("<?xml") { svg.split_once("?>").map(|x| x.1).unwrap_or(svg).trim_start() } else { svg };
    let Some(end) = svg.find('>') else { return String::new() };
    let (open, rest) = svg.split_at(end);
    let attr = |name: &str| -> Option<String> {
        let key = format!("{name}=\"");
        let i = open.find(&key)? + key.len();
        let j = open[i..].find('"')? + i;
        Some(open[i..j].to_string())
    };
    let mut open = open.to_string();
    if !open.contains("viewBox")
        && let (Some(w), Some(h)) = (attr("width"), attr("height"))
    {
        open.push_str(&format!(" viewBox=\"0 0 {w} {h}\""));
    }
    format!("{open} role=\"img\" aria-label=\"{}\"{rest}", escape(title))
}

/// Flattens a JSON object into (dotted key, value text) rows.
fn flatten(prefix: &str, v: &Value, out: &mut Vec<(String, String)>) {
    match v {
        Value::Object(m) => {
            for (k, x) in m {
                let key = if prefix.is_empty() { k.clone() } else { format!("{prefix}.{k}") };
                flatten(&key, x, out);
            }
        }
        Value::String(s) => out.push((prefix.to_string(), s.clone())),
        Value::Null => out.push((prefix.to_string(), "none".into())),
        other => out.push((prefix.to_string(), other.to_string())),
    }
}

fn num(x: Option<f64>, prec: usize, sign: bool) -> String {
    match x {
        Some(v) if sign => format!("{v:+.prec$}"),
        Some(v) => format!("{v:.prec$}"),
        None => "—".into(),
    }
}

const CSS: &str = r#"
:root { --fg:#1d232a; --muted:#5b6570; --line:#d8dde3; --ok:#1a7f37; --okbg:#e6f4ea; --bad:#b42318; --badbg:#fdecea; --accent:#1f77b4; }
* { box-sizing: border-box; }
body { margin:0; font-family: "DejaVu Sans", "Segoe UI", Helvetica, Arial, sans-serif; color:var(--fg); background:#f6f7f9; line-height:1.45; }
main { max-width: 1100px; margin: 0 auto; padding: 24px 28px 60px; background:#fff; min-height:100vh; }
h1 { font-size: 1.6rem; margin: 0 0 4px; }
h2 { font-size: 1.2rem; margin: 32px 0 10px; padding-bottom: 4px; border-bottom: 2px solid var(--line); }
.sub { color: var(--muted); margin: 0 0 16px; font-size: .92rem; }
table { border-collapse: collapse; width: 100%; font-size: .92rem; margin: 6px 0; }
th, td { padding: 5px 9px; border-bottom: 1px solid var(--line); text-align: left; vertical-align: top; }
th { background: #f1f3f6; font-weight: 600; }
td.num { text-align: right; font-variant-numeric: tabular-nums; font-family: "DejaVu Sans Mono", Consolas, monospace; }
.banner { padding: 12px 16px; border-radius: 6px; margin: 10px 0 6px; font-weight: 600; }
.banner.ok { background: var(--okbg); color: var(--ok); border: 1px solid #b7dfc2; }
.banner.bad { background: var(--badbg); color: var(--bad); border: 1px solid #f3c3bd; }
.banner.note { background: #f1f3f6; color: var(--fg); border: 1px solid var(--line); }
.banner ul { margin: 8px 0 0; padding-left: 22px; font-weight: 400; color: var(--fg); }
.banner li { margin: 4px 0; }
.banner li code { font-weight: 700; color: var(--bad); }
.banner.ok li code { color: var(--ok); }
td.untrusted { color: var(--bad); background: var(--badbg); text-decoration: line-through var(--bad); }
td.untrusted::after { content: " ⚠"; text-decoration: none; display: inline-block; }
caption.untrusted { caption-side: top; text-align: left; color: var(--bad); font-weight: 600; padding: 4px 0; }
.tag { display:inline-block; padding: 1px 8px; border-radius: 10px; font-size: .82rem; font-weight: 600; }
.tag.ok { background: var(--okbg); color: var(--ok); }
.tag.bad { background: var(--badbg); color: var(--bad); }
.kpis { display: flex; gap: 14px; flex-wrap: wrap; margin: 10px 0; }
.kpi { flex: 1 1 200px; border: 1px solid var(--line); border-radius: 6px; padding: 10px 14px; }
.kpi .v { font-size: 1.35rem; font-weight: 700; font-variant-numeric: tabular-nums; }
.kpi .l { color: var(--muted); font-size: .85rem; }
figure { margin: 18px 0 26px; }
figure svg { width: 100%; height: auto; display: block; border: 1px solid var(--line); border-radius: 4px; }
figcaption { color: var(--muted); font-size: .9rem; margin-top: 6px; }
figcaption b { color: var(--fg); }
pre { background: #f6f8fa; border: 1px solid var(--line); border-radius: 6px; padding: 12px; overflow-x: auto; font-size: .8rem; }
details summary { cursor: pointer; font-weight: 600; margin: 8px 0; }
footer { margin-top: 40px; color: var(--muted); font-size: .85rem; }
nav a { margin-right: 14px; color: var(--accent); text-decoration: none; font-size: .92rem; }
"#;

/// The verdict banner (`id="verdict"`): green when the document calls the
/// estimate trustworthy, red when not, each warning listed with its code and
/// message (the message says what to do).
fn verdict_banner(h: &mut String, d: &ReportData) {
    let doc = d.document;
    if doc.trustworthy {
        let _ = writeln!(
            h,
            "<div class=\"banner ok\" id=\"verdict\">TRUSTWORTHY: gsens's checks found nothing that makes Γ̂ \
             doubtful beyond its 1σ.{}",
            if doc.warnings.is_empty() { "" } else { " Noted (these do not affect the verdict):" }
        );
    } else {
        let _ = writeln!(
            h,
            "<div class=\"banner bad\" id=\"verdict\" role=\"alert\">NOT TRUSTWORTHY ({}): Γ̂ may be wrong \
             beyond its 1σ. Do not use it, nor compile it into firmware, before these warnings are resolved{}:",
            escape(&doc.untrusted_codes().join(", ")),
            if d.c_header.is_some() { "" } else { " (no gsens_gamma.h was written)" }
        );
    }
    if !doc.warnings.is_empty() {
        let _ = writeln!(h, "<ul id=\"warnings\">");
        for w in &doc.warnings {
            let _ = writeln!(h, "<li><code>{}</code>: {}</li>", escape(w.code.as_str()), escape(&w.message));
        }
        let _ = writeln!(h, "</ul>");
    }
    let _ = writeln!(h, "</div>");
}

/// The report as one HTML document: the head, then one section after the
/// other (estimate, compensation, figures, channels, settings, all results,
/// the C header) and the footer.
pub fn render_html(d: &ReportData) -> String {
    let mut h = String::with_capacity(64 * 1024 + d.figures.iter().map(|f| f.svg.len()).sum::<usize>());
    head(&mut h, d);
    // Verdict and estimate: the document's verdict and warnings first, then what the shaking observed.
    let _ = writeln!(h, "<h2 id=\"estimate\">Estimate</h2>");
    verdict_banner(&mut h, d);
    let _ = writeln!(h, "<p id=\"measurement\">Estimated from {}.</p>", escape(d.document.measurement.description()));
    observability_banner(&mut h, d);
    estimate_table(&mut h, d);
    estimate_notes(&mut h, d);
    compensation(&mut h, d);
    figures(&mut h, d);
    channels(&mut h, d);
    settings(&mut h, d);
    all_results(&mut h, d);
    c_header_and_footer(&mut h, d);
    let _ = writeln!(h, "</main>\n</body>\n</html>");
    h
}

/// The document's head (title, style sheet), its title, inputs and navigation.
fn head(h: &mut String, d: &ReportData) {
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
         <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n\
         <meta name=\"generator\" content=\"{}\">\n<title>{}</title>\n<style>{CSS}</style>\n</head>\n<body>\n<main>\n",
        escape(&d.meta.tool),
        escape(&d.title)
    );
    let _ = writeln!(h, "<h1>{}</h1>", escape(&d.title));
    let inputs: Vec<String> =
        d.meta.inputs.iter().map(|(k, p)| format!("{}: <code>{}</code>", escape(k), escape(p))).collect();
    let _ = writeln!(
        h,
        "<p class=\"sub\">Generated {} by {} · {}</p>",
        escape(&d.meta.generated_utc),
        escape(&d.meta.tool),
        inputs.join(" · ")
    );
    let _ = writeln!(
        h,
        "<nav><a href=\"#estimate\">Estimate</a><a href=\"#compensation\">Compensation</a><a href=\"#figures\">Figures</a>\
         <a href=\"#channels\">Channels</a><a href=\"#settings\">Settings</a>{}</nav>",
        if d.c_header.is_some() { "<a href=\"#header\">C header</a>" } else { "" }
    );
}

/// Whether every axis was observable (and so Γ̂ complete), or which were not.
fn observability_banner(h: &mut String, d: &ReportData) {
    let c = &d.document.calibration;
    let n_obs = c.observable.iter().filter(|&&o| o).count();
    if n_obs == 3 && d.document.trustworthy {
        let _ = writeln!(
            h,
            "<div class=\"banner ok\" id=\"observability\">All three axes observable: Γ̂ is complete.</div>"
        );
    } else if n_obs == 3 {
        let _ = writeln!(
            h,
            "<div class=\"banner note\" id=\"observability\">All three axes observable, but Γ̂ is not \
             trustworthy: see the warnings above.</div>"
        );
    } else {
        let missing: Vec<&str> = (0..3).filter(|&i| !c.observable[i]).map(|i| AXES[i]).collect();
        let _ = writeln!(
            h,
            "<div class=\"banner bad\" id=\"observability\">Not observable along {}: too little excitation. \
             Those components are not estimated (set to 0 in the C header); repeat the calibration shaking along {}.</div>",
            missing.join(", "),
            if missing.len() == 1 { "that axis" } else { "those axes" }
        );
    }
}

/// Γ̂ per axis with its 1σ, excitation and verdict (beside the truth when
/// known); the Γ̂ cells of an untrustworthy estimate struck through.
fn estimate_table(h: &mut String, d: &ReportData) {
    let c = &d.document.calibration;
    let truth = d.document.truth_gamma_hz_per_mps2;
    let peak_hz = d.document.loop_summary.peak_hz;
    let _ = write!(
        h,
        "<table id=\"estimate-table\">{}<thead><tr><th>axis</th><th>Γ̂ [Hz/(m/s²)]</th><th>1σ</th>\
         <th>Γ̂ [ppb/g]</th><th>1σ</th><th>excitation RMS<br>[rad per Hz/(m/s²)]</th><th>verdict</th>",
        if d.document.trustworthy {
            ""
        } else {
            "<caption class=\"untrusted\">Γ̂ below is NOT TRUSTWORTHY (struck through): see the warnings above</caption>"
        }
    );
    // The Γ̂ cells of an untrustworthy estimate are struck through and flagged.
    let gamma_class = if d.document.trustworthy {
        "num".to_string()
    } else {
        format!("num untrusted\" title=\"not trustworthy: {}", escape(&d.document.untrusted_codes().join(", ")))
    };
    if truth.is_some() {
        let _ = write!(h, "<th>truth [Hz/(m/s²)]</th><th>error</th>");
    }
    let _ = writeln!(h, "</tr></thead><tbody>");
    for i in 0..3 {
        let verdict = if c.observable[i] {
            "<span class=\"tag ok\">observable</span>".to_string()
        } else {
            format!(
                "<span class=\"tag bad\">unobservable</span> excitation below {} or 1σ above {} Hz/(m/s²){}",
                c.settings.criteria.min_excitation_rms,
                c.settings.criteria.max_sigma_hz_per_mps2,
                peak_hz.map(|f| format!(": shake harder along {} or closer to {f:.2} Hz", AXES[i])).unwrap_or_default()
            )
        };
        let _ = write!(
            h,
            "<tr><td>{}</td><td class=\"{gamma_class}\">{}</td><td class=\"num\">±{}</td><td class=\"{gamma_class}\">{}</td>\
             <td class=\"num\">±{}</td><td class=\"num\">{:.3}</td><td>{verdict}</td>",
            AXES[i],
            num(c.gamma_hz_per_mps2[i], 5, true),
            num(c.sigma_hz_per_mps2[i], 5, false),
            num(c.gamma_ppb_per_g[i], 4, true),
            num(c.sigma_ppb_per_g[i], 4, false),
            c.excitation_rms[i],
        );
        if let Some(t) = truth {
            let err = match (c.gamma_hz_per_mps2[i], c.sigma_hz_per_mps2[i]) {
                (Some(g), Some(s)) if s > 0.0 => format!("{:+.5} ({:+.2}σ)", g - t[i], (g - t[i]) / s),
                (Some(g), _) => format!("{:+.5}", g - t[i]),
                _ => "—".into(),
            };
            let _ = write!(h, "<td class=\"num\">{:+.5}</td><td class=\"num\">{err}</td>", t[i]);
        }
        let _ = writeln!(h, "</tr>");
    }
    let _ = writeln!(h, "</tbody></table>");
}

/// |Γ̂ − Γ| against the truth when known, and what the 1σ are.
fn estimate_notes(h: &mut String, d: &ReportData) {
    if let Some(id) = &d.document.identified_loop {
        // The text report's lines on the identified loop, one paragraph.
        let mut lines = String::new();
        crate::text::identified_loop(&mut lines, id, &d.document.calibration.loop_used);
        let lines: Vec<String> = lines.lines().map(|l| escape(l.trim())).collect();
        let _ = writeln!(h, "<p id=\"identified-loop\">{}</p>", lines.join("<br>"));
    }
    let c = &d.document.calibration;
    if let Some(forms) = c.joint_fit.as_ref().and_then(|j| j.loop_forms.as_ref()) {
        // The text report's line on which receiver's form of the stated loop the data chose.
        let mut line = String::new();
        crate::text::loop_forms(&mut line, forms);
        let lines: Vec<String> = line.lines().map(|l| escape(l.trim())).collect();
        let _ = writeln!(h, "<p id=\"loop-forms\">{}</p>", lines.join("<br>"));
    }
    let truth = d.document.truth_gamma_hz_per_mps2;
    if let Some(t) = truth {
        let norm = (t[0] * t[0] + t[1] * t[1] + t[2] * t[2]).sqrt();
        let err: f64 = (0..3).filter_map(|i| c.gamma_hz_per_mps2[i].map(|g| (g - t[i]).powi(2))).sum::<f64>().sqrt();
        let _ = writeln!(
            h,
            "<p>Against the truth: |Γ̂ − Γ| = {err:.5} Hz/(m/s²) (observable axes) = {:.2} % of \
             |Γ| = {norm:.5} Hz/(m/s²) = {:.3} ppb/g.</p>",
            100.0 * err / norm,
            hz_per_mps2_to_ppb_per_g(norm, c.settings.carrier_hz)
        );
    }
    let _ = writeln!(
        h,
        "<p class=\"sub\">1σ are autocorrelation-robust (the residuals of a carrier loop are coloured); \
         assuming white residuals they would be {} Hz/(m/s²). Condition number of the information matrix: {}. \
         ppb/g = Γ·9.80665/f<sub>carrier</sub>·10⁹ at f<sub>carrier</sub> = {} Hz.</p>",
        c.sigma_white_hz_per_mps2
            .iter()
            .map(|s| s.map_or("∞".into(), |s| format!("{s:.5}")))
            .collect::<Vec<_>>()
            .join(" / "),
        c.condition_number.map(|x| format!("{x:.1}")).unwrap_or_else(|| "∞ (singular)".into()),
        c.settings.carrier_hz
    );
}

/// The compensation's figures: the phase error RMS before and after.
fn compensation(h: &mut String, d: &ReportData) {
    let c = &d.document.calibration;
    let reduction = if c.rms_before_rad > 0.0 { 100.0 * (1.0 - c.rms_after_rad / c.rms_before_rad) } else { 0.0 };
    let _ = writeln!(h, "<h2 id=\"compensation\">Compensation</h2>");
    let _ = writeln!(
        h,
        "<div class=\"kpis\">\
         <div class=\"kpi\"><div class=\"v\" id=\"rms-before\">{:.4} rad</div><div class=\"l\">phase error RMS before compensation</div></div>\
         <div class=\"kpi\"><div class=\"v\" id=\"rms-after\">{:.4} rad</div><div class=\"l\">RMS after: φ − φ<sub>a</sub>ᵀΓ̂</div></div>\
         <div class=\"kpi\"><div class=\"v\">{:.4} rad</div><div class=\"l\">RMS of the g-induced part φ<sub>a</sub>ᵀΓ̂</div></div>\
         <div class=\"kpi\"><div class=\"v\">{reduction:.1} %</div><div class=\"l\">RMS reduction</div></div></div>",
        c.rms_before_rad, c.rms_after_rad, c.rms_g_induced_rad
    );
    let _ = writeln!(
        h,
        "<p class=\"sub\">Over the {} epochs used ({} in the log, {:.1} s at {:.3} Hz; the first {} s only drive the loop models).</p>",
        c.epochs_used,
        c.epochs_total,
        c.epochs_total as f64 * c.log_interval_s,
        1.0 / c.log_interval_s,
        c.settings.warmup_s
    );
}

/// Every figure, inline, with its caption.
fn figures(h: &mut String, d: &ReportData) {
    let _ = writeln!(h, "<h2 id=\"figures\">Figures</h2>");
    for f in &d.figures {
        let _ = writeln!(
            h,
            "<figure id=\"{}\">\n{}\n<figcaption><b>{}.</b> {}</figcaption>\n</figure>",
            escape(&f.id),
            inline_svg(&f.svg, &f.title),
            escape(&f.title),
            escape(&f.caption)
        );
    }
}

/// Every track: its C/N0, epochs, whether used, its offset and reason.
fn channels(h: &mut String, d: &ReportData) {
    let _ = writeln!(h, "<h2 id=\"channels\">Channels</h2>");
    let _ = writeln!(
        h,
        "<table><thead><tr><th>channel</th><th>PRN</th><th>mean C/N0 [dB-Hz]</th><th>epochs</th><th>used</th>\
         <th>offset removed [rad]</th><th>reason</th></tr></thead><tbody>"
    );
    for ch in &d.document.channels {
        let _ = writeln!(
            h,
            "<tr><td class=\"num\">{}</td><td class=\"num\">{}</td><td class=\"num\">{:.1}</td><td class=\"num\">{}</td>\
             <td>{}</td><td class=\"num\">{}</td><td>{}</td></tr>",
            ch.channel,
            ch.prn,
            ch.mean_cn0_dbhz,
            ch.epochs,
            if ch.used { "<span class=\"tag ok\">used</span>" } else { "no" },
            num(ch.phase_offset_rad, 4, true),
            escape(&ch.reason)
        );
    }
    let _ = writeln!(h, "</tbody></table>");
}

/// Everything that decided the estimate.
fn settings(h: &mut String, d: &ReportData) {
    let c = &d.document.calibration;
    let _ = writeln!(h, "<h2 id=\"settings\">Settings</h2>");
    let mut rows = vec![
        ("receiver loop".to_string(), c.loop_used.to_string()),
        ("log interval [s]".to_string(), Decimal(c.log_interval_s).to_string()),
        ("loop updates per log epoch (model)".to_string(), c.model_substeps.to_string()),
        (
            "IMU time offset [s]".to_string(),
            match c.imu_time_offset_sigma_s {
                Some(sig) if c.imu_time_offset_estimated => {
                    format!("{:+.4} ± {sig:.4} (estimated jointly with Γ)", c.imu_time_offset_s)
                }
                _ => format!("{} (given)", c.imu_time_offset_s),
            },
        ),
    ];
    if let Ok(v) = serde_json::to_value(c.settings) {
        flatten("settings", &v, &mut rows);
    }
    if let Ok(v) = serde_json::to_value(&d.document.selection) {
        flatten("selection", &v, &mut rows);
    }
    for (k, p) in &d.meta.inputs {
        rows.push((format!("input.{k}"), p.clone()));
    }
    let _ = writeln!(h, "<table id=\"settings-table\"><thead><tr><th>setting</th><th>value</th></tr></thead><tbody>");
    for (k, v) in rows {
        let _ = writeln!(h, "<tr><td><code>{}</code></td><td>{}</td></tr>", escape(&k), escape(&v));
    }
    let _ = writeln!(h, "</tbody></table>");
}

/// Every result of the calibration, including those not discussed above.
fn all_results(h: &mut String, d: &ReportData) {
    let c = &d.document.calibration;
    if let Ok(Value::Object(mut all)) = serde_json::to_value(c) {
        all.remove("settings");
        let mut rows = Vec::new();
        flatten("", &Value::Object(all), &mut rows);
        let _ = writeln!(
            h,
            "<details id=\"all-results\"><summary>All results ({} values, as in the JSON)</summary>\
             <table><thead><tr><th>key</th><th>value</th></tr></thead><tbody>",
            rows.len()
        );
        for (k, v) in rows {
            let _ = writeln!(h, "<tr><td><code>{}</code></td><td class=\"num\">{}</td></tr>", escape(&k), escape(&v));
        }
        let _ = writeln!(h, "</tbody></table></details>");
    }
}

/// The C header when one was written, and the footer with the signs and units.
fn c_header_and_footer(h: &mut String, d: &ReportData) {
    if let Some(header) = &d.c_header {
        let _ = writeln!(h, "<h2 id=\"header\">C header for firmware</h2>");
        let _ = writeln!(
            h,
            "<details open><summary>gsens_gamma.h</summary><pre><code>{}</code></pre></details>",
            escape(header)
        );
    }
    let _ = writeln!(
        h,
        "<footer>Sign and units: φ = θ<sub>signal</sub> − θ<sub>replica</sub> [rad]; Δf = aᵀΓ is added to the NCO's \
         commanded frequency; a is the specific force in the IMU body frame [m/s²]. {}</footer>",
        escape(&d.meta.tool)
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escapes_and_inlines() {
        assert_eq!(escape("<a href='x'>&\"</a>"), "&lt;a href=&#39;x&#39;&gt;&amp;&quot;&lt;/a&gt;");
        let s = inline_svg("<?xml version=\"1.0\"?>\n<svg width=\"10\" height=\"20\" xmlns=\"x\"><g/></svg>", "T<");
        assert!(s.starts_with(
            "<svg width=\"10\" height=\"20\" xmlns=\"x\" viewBox=\"0 0 10 20\" role=\"img\" aria-label=\"T&lt;\">"
        ));
        assert!(s.ends_with("<g/></svg>"));
        let mut rows = vec![];
        flatten("s", &serde_json::json!({"a": {"b": 1}, "c": null, "d": "x"}), &mut rows);
        assert_eq!(rows, vec![("s.a.b".into(), "1".into()), ("s.c".into(), "none".into()), ("s.d".into(), "x".into())]);
    }
}
