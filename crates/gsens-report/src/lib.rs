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
//! - [`json`]: the same report as JSON (the result document of
//!   `gsens estimate --json` with its `report` block).
//! - [`cheader`]: Γ̂ as C preprocessor constants (Hz/(m/s²) and ppb/g), with
//!   the verdict (`GSENS_GAMMA_TRUSTWORTHY`) and the warnings;
//! - [`render_text`]: the text report the CLI prints;
//! - [`write_calibration_report`]: a calibration's whole report from its
//!   outcome (tracking rows, or a carrier phase and Doppler log), and [`write_demo_figures`]: a demo's figures with the
//!   simulated oscillator's Allan deviation;
//! - [`studies`]: the outputs of `response`, `predict` and `validate`
//!   besides their text tables;
//! - [`FigureInputs`]: the figure set of a calibration, drawn from its
//!   [`gsens_calib::Outcome`], and [`write_figures`] to write it as PNG and SVG.
//!
//! Every output is rendered from the one [`gsens_calib::ResultDocument`]; the
//! crate reads no file.
#![deny(missing_docs)]

mod calibration_report;
pub mod cheader;
mod demo_figures;
mod figure_set;
pub mod figures;
pub mod html;
pub mod json;
mod montecarlo_text;
pub mod spectrum;
pub mod studies;
mod text;
mod time;

pub use calibration_report::{ReportError, ReportSource, write_calibration_report};
pub use demo_figures::{DemoFiguresError, write_demo_figures};
pub use figure_set::{
    Figure, FigureInputs, ReportFiles, WriteError, observation_figures, write_figures, write_report_dir,
};
pub use montecarlo_text::render_montecarlo_text;
pub use text::{render_response_text, render_text};
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

/// A figure of the report: an inline SVG with its title and caption.
#[derive(Debug, Clone, PartialEq)]
pub struct FigureBlock {
    /// Short identifier, also the file stem when written (e.g. `fig4_estimation`).
    pub id: String,
    /// Heading.
    pub title: String,
    /// What the figure shows and how to read it (plain text).
    pub caption: String,
    /// The SVG document (from [`figures`] with [`figures::Format::Svg`]).
    pub svg: String,
}

/// Everything a calibration report shows.
#[derive(Debug, Clone)]
pub struct ReportData<'a> {
    /// Heading of the report.
    pub title: String,
    /// The result document: the estimate, the channels, the settings, the
    /// inputs and the truth when known.
    pub document: &'a gsens_calib::ResultDocument,
    /// Who made the report, when, from which logs.
    pub meta: ReportMeta,
    /// Figures, in the order shown.
    pub figures: Vec<FigureBlock>,
    /// The C header, shown in the HTML when given; `None` when none was
    /// written (the HTML of an untrustworthy estimate then says so).
    pub c_header: Option<String>,
}
