//! # gsens-report
//!
//! The presentation layer of gsens: figures, the HTML calibration report, its
//! JSON, and the compensation parameters as a C header for firmware.
//!
//! - [`figures`]: the paper's Fig. 3 (loop response |L|, [`figures::fig_response`]),
//!   Fig. 4 (estimation process, [`figures::fig_estimation`]) and Fig. 5
//!   (phase error before/after compensation, [`figures::fig_compensation`]),
//!   plus per-channel C/N0, the residual spectrum and the Allan deviation of a
//!   simulated oscillator, each as PNG or SVG of a given size. Text uses a
//!   bundled font (DejaVu Sans, `assets/`), so nothing depends on system fonts.
//! - [`spectrum`]: Welch power spectral density (for the residual spectrum).
//! - [`html`]: one self-contained HTML file (inline SVG and CSS, no script, no
//!   external request) with the estimate, uncertainty, observability verdicts,
//!   RMS before and after compensation and every setting used.
//! - [`json`]: the same report as JSON (the shape of `gsens estimate --json`
//!   plus a `report` block).
//! - [`cheader`]: Γ̂ as C preprocessor constants (Hz/(m/s²) and ppb/g).
//!
//! The crate takes plain data (slices and small structs, [`gsens_calib::Calibration`])
//! and does no file reading: the CLI converts its logs.
#![deny(missing_docs)]

pub mod cheader;
pub mod figures;
pub mod html;
pub mod json;
pub mod spectrum;
mod time;

pub use figures::{Format, Image, RenderError};
pub use time::{utc_date_string, utc_now_string, utc_timestamp_string};

/// Names the Cartesian axes in every output.
pub const AXES: [&str; 3] = ["x", "y", "z"];

/// Who produced a report and from what: printed in the HTML, the JSON and the C header.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ReportMeta {
    /// When the report was generated, UTC, e.g. `2025-01-31 12:00:00 UTC`.
    pub generated_utc: String,
    /// The producing tool and version, e.g. `gsens 0.1.0`.
    pub tool: String,
    /// The input logs as (role, path) pairs, e.g. `("imu", "logs/imu.csv")`.
    pub inputs: Vec<(String, String)>,
}

impl ReportMeta {
    /// Metadata stamped now (see [`utc_now_string`]) by `tool` from `inputs`.
    pub fn now(tool: impl Into<String>, inputs: &[(&str, &str)]) -> Self {
        ReportMeta {
            generated_utc: utc_now_string(),
            tool: tool.into(),
            inputs: inputs.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect(),
        }
    }
}

/// Loop description in words, e.g. `2nd order, Bn 3 Hz, ζ 0.707, ωn/2π 0.900 Hz`.
pub fn loop_description(l: &gsens_core::pll::LoopSpec) -> String {
    use gsens_core::pll::LoopSpec;
    let nat = l.wn_rad_per_s().map(|w| format!(", ωn/2π {:.3} Hz", w / core::f64::consts::TAU)).unwrap_or_default();
    match *l {
        LoopSpec::SecondOrder { bn_hz, zeta } => format!("2nd order, Bn {bn_hz} Hz, ζ {zeta:.3}{nat}"),
        LoopSpec::ThirdOrder { bn_hz, a3, b3 } => format!("3rd order, Bn {bn_hz} Hz, a3 {a3}, b3 {b3}{nat}"),
        LoopSpec::Coefficients(c) => {
            format!("filter c0 {} /s, c1 {} /s², c2 {} /s³{nat}", c.c0_per_s, c.c1_per_s2, c.c2_per_s3)
        }
    }
}

/// One track of the tracking log and what became of it (the fields of
/// `gsens_session::ChannelSummary`, which the CLI converts).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ChannelRow {
    /// Receiver channel number.
    pub channel: u32,
    /// Satellite PRN.
    pub prn: u32,
    /// Mean C/N0 [dB-Hz].
    pub mean_cn0_dbhz: f64,
    /// Epochs the track contributes.
    pub epochs: usize,
    /// Whether the track enters the average.
    pub used: bool,
    /// `"used"`, or why the track is excluded.
    pub reason: String,
    /// The constant phase offset removed from the track [rad], if any.
    pub phase_offset_rad: Option<f64>,
}

/// A figure of the report: an inline SVG with its title and caption.
#[derive(Debug, Clone, PartialEq)]
pub struct FigureBlock {
    /// Short identifier, also the file stem when written (e.g. `fig4_estimation`).
    pub id: String,
    /// Heading.
    pub title: String,
    /// What the figure shows and how to read it (plain text).
    pub caption: String,
    /// The SVG document (from [`figures`] with [`Format::Svg`]).
    pub svg: String,
}

/// Everything a calibration report shows.
#[derive(Debug, Clone)]
pub struct ReportData<'a> {
    /// Heading of the report.
    pub title: String,
    /// The calibration.
    pub calibration: &'a gsens_calib::Calibration,
    /// The true Γ [Hz/(m/s²)] when known (simulated logs).
    pub truth: Option<[f64; 3]>,
    /// Every track of the log and whether it was used.
    pub channels: Vec<ChannelRow>,
    /// The channel-selection settings, as the JSON object the CLI reports.
    pub selection: serde_json::Value,
    /// Who made the report, when, from which logs.
    pub meta: ReportMeta,
    /// Figures, in the order shown.
    pub figures: Vec<FigureBlock>,
    /// The C header, shown in the HTML when given.
    pub c_header: Option<String>,
}
