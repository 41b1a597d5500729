//! `gsens report`: the calibration as one self-contained HTML file, its
//! result document as JSON, the compensation parameters as a C header, and the
//! figures as PNG and SVG.

use crate::args::CalibrationArgs;
use crate::estimate::calibrate;
use anyhow::{Context, Result};
use clap::Args;
use gsens_inputs::Estimated;
use gsens_report::{ReportSource, write_calibration_report};
use gsens_tui::progress::drawing;
use std::path::{Path, PathBuf};

#[derive(Args, Debug)]
pub(crate) struct ReportArgs {
    #[command(flatten)]
    pub inputs: gsens_inputs::InputChoice,
    /// truth.json of a simulated session: the true Γ is drawn dashed and the errors reported.
    #[arg(long)]
    pub truth: Option<PathBuf>,
    /// Output directory: report.html, report.json, gsens_gamma.h (a trustworthy estimate's,
    /// see --write-untrusted-header) and figures/ (PNG and SVG).
    #[arg(long)]
    pub out: PathBuf,
    /// Heading of the report.
    #[arg(long, default_value = "Oscillator g-sensitivity calibration")]
    pub title: String,
    #[command(flatten)]
    pub header: HeaderArgs,
    #[command(flatten)]
    pub calibration: CalibrationArgs,
}

/// Whether a report writes the C header of an estimate that is not trustworthy.
#[derive(Args, Debug, Clone, Copy)]
pub(crate) struct HeaderArgs {
    /// Write gsens_gamma.h even when the estimate is not trustworthy (it then defines
    /// GSENS_GAMMA_TRUSTWORTHY 0 and lists the warnings); by default none is written.
    #[arg(long)]
    pub write_untrusted_header: bool,
}

pub(crate) fn run(args: &ReportArgs, given: &[&str]) -> Result<crate::Status> {
    let route = crate::args::route(&args.inputs)?;
    let mut settings = args.calibration.settings(given)?;
    let loop_note = route.truth_loop_note(&mut settings, args.truth.as_deref())?;
    crate::check_dir("--out", Some(&args.out))?;
    let truth = args.truth.as_deref().map(gsens_sim::read_truth_gamma).transpose()?;
    if let Some(note) = &loop_note {
        crate::out(&format!("{note}\n"))?;
    }
    let mut estimated = calibrate(route, &settings, true)?;
    if let Some(t) = &args.truth {
        estimated.inputs_mut().push(("truth".into(), t.display().to_string()));
    }
    write_report(&estimated, truth, &args.out, &args.title, args.header)
}

/// Writes the report of `estimated` into `out` and prints its text:
/// report.html, report.json, gsens_gamma.h (for an untrustworthy estimate
/// only as `header` asks; stderr says when it is not written) and figures/.
pub(crate) fn write_report(
    estimated: &Estimated,
    truth: Option<[f64; 3]>,
    out: &Path,
    title: &str,
    header: HeaderArgs,
) -> Result<crate::Status> {
    let source = match estimated {
        Estimated::Tracking(c) => {
            ReportSource::Tracking(&c.outcome, c.tracking.as_ref().context("the calibration kept no tracking log")?)
        }
        Estimated::Observations(outcome) => ReportSource::Observations(outcome),
    };
    let (doc, files) = drawing(|on_figure| {
        write_calibration_report(source, truth, out, title, header.write_untrusted_header, on_figure)
    })?;
    let (text, no_header) = files.render(&doc, crate::args::flag);
    crate::out(&text)?;
    crate::err(no_header.as_deref().unwrap_or_default());
    Ok(crate::Status::of(&doc))
}
