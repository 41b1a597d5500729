//! Γ̂ as a C header that firmware can include.
//!
//! Per axis `A` in `X`, `Y`, `Z`:
//!
//! | macro | meaning |
//! | --- | --- |
//! | `GSENS_GAMMA_A_OBSERVABLE` | 1 when the data observe the axis, else 0 |
//! | `GSENS_GAMMA_A_HZ_PER_MPS2` | Γ̂ at the carrier \[Hz/(m/s²)\]; `0.0` (no compensation) when unobservable |
//! | `GSENS_GAMMA_A_PPB_PER_G` | the same normalized \[ppb/g\]; `0.0` when unobservable |
//! | `GSENS_GAMMA_A_SIGMA_HZ_PER_MPS2`, `..._SIGMA_PPB_PER_G` | 1σ, defined only for observable axes |
//!
//! plus `GSENS_GAMMA_TRUSTWORTHY` (1 or 0: the result document's verdict,
//! [`gsens_calib::ResultDocument::trustworthy`]), `GSENS_GAMMA_HZ_PER_MPS2_INIT` /
//! `GSENS_GAMMA_PPB_PER_G_INIT` (array initializers), `GSENS_GAMMA_OBSERVABLE_MASK`
//! (bit 0 x, bit 1 y, bit 2 z), `GSENS_CARRIER_HZ`, `GSENS_CALIBRATION_DATE` and
//! the source logs. The verdict and every warning (code and message) head the
//! header's comment, so whoever includes it sees why an estimate is not to
//! be trusted. An unobservable axis never gets a made-up number: its value is
//! 0 with a comment saying why, and it has no σ macro.

use crate::ReportMeta;
use gsens_calib::ResultDocument;
use gsens_core::units::STANDARD_GRAVITY_MPS2;
use std::fmt::Write as _;

/// A C double literal that round-trips, in parentheses (macro-safe).
fn c_double(v: f64) -> String {
    let s = format!("{v:e}");
    let s = if s.contains('.') || s.contains('e') { s } else { format!("{s}.0") };
    format!("({s})")
}

/// A C string literal: ASCII printable kept, everything else octal-escaped.
fn c_string(s: &str) -> String {
    let mut out = String::from("\"");
    for b in s.bytes() {
        match b {
            b'"' => out.push_str("\\\""),
            b'\\' => out.push_str("\\\\"),
            b'?' => out.push_str("\\?"), // no trigraphs
            0x20..=0x7e => out.push(b as char),
            _ => {
                let _ = write!(out, "\\{b:03o}");
            }
        }
    }
    out.push('"');
    out
}

/// Text safe inside a C block comment, in ASCII (some firmware toolchains
/// reject other bytes): the symbols gsens uses spelled out, anything else `?`.
fn c_comment(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for ch in s.chars() {
        match ch {
            'ζ' => out.push_str("zeta"),
            'ω' => out.push('w'),
            'π' => out.push_str("pi"),
            'Γ' => out.push_str("Gamma"),
            'φ' => out.push_str("phi"),
            'θ' => out.push_str("theta"),
            'σ' => out.push_str("sigma"),
            'τ' => out.push_str("tau"),
            '\u{302}' => out.push_str("-hat"),
            '±' => out.push_str("+/-"),
            '≤' => out.push_str("<="),
            '≥' => out.push_str(">="),
            '×' => out.push('x'),
            '√' => out.push_str("sqrt"),
            '…' => out.push_str("..."),
            '≈' => out.push('~'),
            '→' => out.push_str("->"),
            '₀' => out.push('0'),
            '⁻' => out.push('-'),
            '¹' => out.push('1'),
            '²' => out.push_str("^2"),
            '³' => out.push_str("^3"),
            '·' => out.push('*'),
            '−' | '–' | '—' => out.push('-'),
            c if c.is_ascii() && (c == '\t' || !c.is_ascii_control()) => out.push(c),
            _ => out.push('?'),
        }
    }
    out.replace("*/", "* /").replace("/*", "/ *")
}

/// `text` cut at spaces into lines of at most `width` characters (a longer
/// word stands alone on its line).
fn wrap(text: &str, width: usize) -> Vec<String> {
    let mut lines = Vec::new();
    let mut line = String::new();
    for word in text.split_whitespace() {
        if !line.is_empty() && line.chars().count() + 1 + word.chars().count() > width {
            lines.push(std::mem::take(&mut line));
        }
        if !line.is_empty() {
            line.push(' ');
        }
        line.push_str(word);
    }
    if !line.is_empty() {
        lines.push(line);
    }
    lines
}

/// The comment block of the verdict: trustworthy or not, then every warning
/// (code and message, wrapped), as [`ResultDocument::trustworthy`] and
/// [`ResultDocument::warnings`] say.
fn verdict_comment(h: &mut String, doc: &ResultDocument) {
    let _ = writeln!(h, " *");
    if doc.trustworthy {
        let _ = writeln!(h, " * VERDICT: TRUSTWORTHY (GSENS_GAMMA_TRUSTWORTHY 1): gsens's checks found nothing");
        let _ = writeln!(h, " * that makes the estimate doubtful beyond its 1-sigma values.");
    } else {
        let codes = doc.untrusted_codes();
        let _ = writeln!(h, " * VERDICT: NOT TRUSTWORTHY (GSENS_GAMMA_TRUSTWORTHY 0): {}.", codes.join(", "));
        let _ = writeln!(h, " * The values below may be wrong beyond their 1-sigma values: do not compile them");
        let _ = writeln!(h, " * into firmware before the warnings are resolved and the calibration repeated.");
    }
    let measured = format!("Estimated from {}.", doc.measurement.description());
    for line in wrap(&c_comment(&measured), 86) {
        let _ = writeln!(h, " * {line}");
    }
    if !doc.warnings.is_empty() {
        let _ = writeln!(h, " *");
        let _ = writeln!(h, " * Warnings:");
    }
    for w in &doc.warnings {
        for (k, line) in wrap(&c_comment(&format!("{}: {}", w.code, w.message)), 84).iter().enumerate() {
            let _ = writeln!(h, " *   {}{line}", if k == 0 { "" } else { "  " });
        }
    }
}

/// The header text of `doc`, named `gsens_gamma.h` by the CLI (include guard `GSENS_GAMMA_H`).
pub fn render_c_header(doc: &ResultDocument, meta: &ReportMeta) -> String {
    let mut h = String::new();
    comment(&mut h, doc, meta);
    defines(&mut h, doc, meta);
    let mut mask = 0u32;
    for i in 0..3 {
        let _ = writeln!(h);
        if axis_defines(&mut h, &doc.calibration, i) {
            mask |= 1 << i;
        }
    }
    mask_and_initializers(&mut h, mask);
    h
}

/// The header's opening comment: where it comes from, the model and its
/// conventions, the estimate and its verdict, and a warning for an axis
/// not observable.
fn comment(h: &mut String, doc: &ResultDocument, meta: &ReportMeta) {
    let c = &doc.calibration;
    let _ = writeln!(h, "/*");
    let _ = writeln!(h, " * gsens_gamma.h - crystal-oscillator g-sensitivity compensation parameters.");
    let _ = writeln!(h, " *");
    let _ = writeln!(h, " * Generated by {} on {} from", c_comment(&meta.tool), c_comment(&meta.generated_utc));
    for (role, path) in &meta.inputs {
        let _ = writeln!(h, " *   {:<9} {}", c_comment(&format!("{role}:")), c_comment(path));
    }
    let _ = writeln!(h, " *");
    let _ = writeln!(h, " * Model (Filler): the oscillator adds the frequency bias");
    let _ = writeln!(h, " *     df [Hz] = GAMMA_X * a_x + GAMMA_Y * a_y + GAMMA_Z * a_z");
    let _ = writeln!(h, " * to the carrier NCO's commanded frequency, with a the specific force in m/s^2");
    let _ = writeln!(h, " * (accelerometer output: at rest it reads +1 g upward) and GAMMA in Hz/(m/s^2)");
    let _ = writeln!(h, " * at the carrier GSENS_CARRIER_HZ. Compensate by subtracting df from the NCO's");
    let _ = writeln!(h, " * frequency command at every loop update. For another carrier f, use the");
    let _ = writeln!(h, " * normalized values: df = GAMMA_PPB_PER_G * 1e-9 * f * a / GSENS_STANDARD_GRAVITY_MPS2.");
    let _ = writeln!(h, " *");
    let _ = writeln!(h, " * Axis convention: the IMU body frame of the input log (columns fx_mps2,");
    let _ = writeln!(h, " * fy_mps2, fz_mps2 of imu.csv); at rest, level, z up: a = (0, 0, +9.81) m/s^2.");
    let _ = writeln!(h, " * Sign: phase error = signal phase - replica phase.");
    let _ = writeln!(h, " *");
    let estimate = format!(
        "Estimate: {} over {} epochs at {:.3} Hz; receiver loop {}.",
        c.settings.method,
        c.epochs_used,
        1.0 / c.log_interval_s,
        c_comment(&c.loop_used.to_string())
    );
    for line in wrap(&estimate, 84) {
        let _ = writeln!(h, " * {line}");
    }
    let _ = writeln!(
        h,
        " * Phase error RMS {:.4} rad before compensation, {:.4} rad after. 1-sigma values are",
        c.rms_before_rad, c.rms_after_rad
    );
    let _ = writeln!(h, " * autocorrelation-robust.");
    verdict_comment(h, doc);
    if c.observable.iter().any(|o| !o) {
        let _ = writeln!(h, " *");
        let _ = writeln!(h, " * WARNING: at least one axis was NOT observable in this log (too little");
        let _ = writeln!(h, " * excitation). Its value is 0 (no compensation), which is not an estimate:");
        let _ = writeln!(h, " * repeat the calibration shaking along that axis.");
    }
    let _ = writeln!(h, " */");
}

/// The include guard, the calibration's date, sources and carrier, and whether it is trustworthy.
fn defines(h: &mut String, doc: &ResultDocument, meta: &ReportMeta) {
    let date = meta.generated_utc.split(' ').next().unwrap_or("").to_string();
    let _ = writeln!(h, "#ifndef GSENS_GAMMA_H");
    let _ = writeln!(h, "#define GSENS_GAMMA_H");
    let _ = writeln!(h);
    let _ = writeln!(h, "#define GSENS_CALIBRATION_DATE {}", c_string(&date));
    let _ = writeln!(h, "#define GSENS_CALIBRATION_GENERATED_UTC {}", c_string(&meta.generated_utc));
    for (role, path) in &meta.inputs {
        let name: String =
            role.chars().map(|ch| if ch.is_ascii_alphanumeric() { ch.to_ascii_uppercase() } else { '_' }).collect();
        let _ = writeln!(h, "#define GSENS_SOURCE_{name}_LOG {}", c_string(path));
    }
    let _ = writeln!(h, "#define GSENS_CARRIER_HZ {}", c_double(doc.calibration.settings.carrier_hz));
    let _ = writeln!(h, "#define GSENS_STANDARD_GRAVITY_MPS2 {}", c_double(STANDARD_GRAVITY_MPS2));
    let _ = writeln!(h);
    let _ =
        writeln!(h, "/* 1 when gsens's checks found the estimate trustworthy, 0 when not (see the warnings above). */");
    let _ = writeln!(h, "#define GSENS_GAMMA_TRUSTWORTHY {}", u8::from(doc.trustworthy));
}

/// Axis `i`'s defines: Γ̂ and its σ in both units when observable (returns
/// true), else 0 with why.
fn axis_defines(h: &mut String, c: &gsens_calib::Calibration, i: usize) -> bool {
    let a = crate::AXES[i].to_ascii_uppercase();
    match (c.gamma_hz_per_mps2[i], c.sigma_hz_per_mps2[i], c.gamma_ppb_per_g[i], c.sigma_ppb_per_g[i]) {
        (Some(g), Some(s), Some(gp), Some(sp)) if c.observable[i] => {
            let _ = writeln!(
                h,
                "/* {} axis: observable. {g:+.6} +/- {s:.6} Hz/(m/s^2) (1 sigma) = {gp:+.4} +/- {sp:.4} ppb/g */",
                crate::AXES[i]
            );
            let _ = writeln!(h, "#define GSENS_GAMMA_{a}_OBSERVABLE 1");
            let _ = writeln!(h, "#define GSENS_GAMMA_{a}_HZ_PER_MPS2 {}", c_double(g));
            let _ = writeln!(h, "#define GSENS_GAMMA_{a}_SIGMA_HZ_PER_MPS2 {}", c_double(s));
            let _ = writeln!(h, "#define GSENS_GAMMA_{a}_PPB_PER_G {}", c_double(gp));
            let _ = writeln!(h, "#define GSENS_GAMMA_{a}_SIGMA_PPB_PER_G {}", c_double(sp));
            true
        }
        _ => {
            let _ = writeln!(
                h,
                "/* {} axis: NOT OBSERVABLE (unexplained excitation RMS {:.4} rad per Hz/(m/s^2),",
                crate::AXES[i],
                c.excitation_rms[i]
            );
            let _ = writeln!(
                h,
                " * floor {}). Set to 0 = no compensation on this axis; not an estimate. No sigma. */",
                c.settings.criteria.min_excitation_rms
            );
            let _ = writeln!(h, "#define GSENS_GAMMA_{a}_OBSERVABLE 0");
            let _ = writeln!(h, "#define GSENS_GAMMA_{a}_HZ_PER_MPS2 (0.0)");
            let _ = writeln!(h, "#define GSENS_GAMMA_{a}_PPB_PER_G (0.0)");
            false
        }
    }
}

/// The mask of the axes compensated and the arrays' initializers; the guard's end.
fn mask_and_initializers(h: &mut String, mask: u32) {
    let _ = writeln!(h);
    let _ = writeln!(h, "/* Bit i set when axis i (0 x, 1 y, 2 z) is observable and compensated. */");
    let _ = writeln!(h, "#define GSENS_GAMMA_OBSERVABLE_MASK {mask}u");
    let _ = writeln!(
        h,
        "#define GSENS_GAMMA_HZ_PER_MPS2_INIT \\\n    {{ GSENS_GAMMA_X_HZ_PER_MPS2, GSENS_GAMMA_Y_HZ_PER_MPS2, GSENS_GAMMA_Z_HZ_PER_MPS2 }}"
    );
    let _ = writeln!(
        h,
        "#define GSENS_GAMMA_PPB_PER_G_INIT \\\n    {{ GSENS_GAMMA_X_PPB_PER_G, GSENS_GAMMA_Y_PPB_PER_G, GSENS_GAMMA_Z_PPB_PER_G }}"
    );
    let _ = writeln!(h);
    let _ = writeln!(h, "#endif /* GSENS_GAMMA_H */");
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn literals() {
        assert_eq!(c_double(0.09), "(9e-2)");
        assert_eq!(c_double(-0.08), "(-8e-2)");
        assert_eq!(c_double(1575.42e6), "(1.57542e9)");
        assert_eq!(c_double(0.0), "(0e0)");
        assert_eq!(c_string("a\"b\\c?é"), "\"a\\\"b\\\\c\\?\\303\\251\"");
        assert_eq!(c_comment("x */ y"), "x * / y");
        assert_eq!(c_comment("ζ 0.707, ωn/2π, m/s², é"), "zeta 0.707, wn/2pi, m/s^2, ?");
        assert_eq!(c_comment("Γ̂ ± 2σ, τ ≤ 1"), "Gamma-hat +/- 2sigma, tau <= 1");
        assert_eq!(wrap("aa bb  cc dddddd e", 5), ["aa bb", "cc", "dddddd", "e"]);
        assert!(wrap(" ", 5).is_empty());
    }
}
