//! `gsens report`: the calibration as one self-contained HTML file, its
//! result document as JSON, the compensation parameters as a C header, and the
//! figures as PNG and SVG.

use crate::args::{CalibrationArgs, InputArgs};
use crate::estimate::calibrate;
use anyhow::{Context, Result};
use clap::Args;
use gsens_calib::{ObservationOutcome, Outcome};
use gsens_io::TrackingLog;
use gsens_report::write_calibration_report;
use gsens_tui::progress::drawing;
use std::path::{Path, PathBuf};

#[derive(Args, Debug)]
pub(crate) struct ReportArgs {
    #[command(flatten)]
    pub inputs: InputArgs,
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
    if let Some(observations) = args.inputs.observations() {
        let settings = args.calibration.settings(given)?;
        crate::check_dir("--out", Some(&args.out))?;
        let truth = args.truth.as_deref().map(gsens_sim::read_truth_gamma).transpose()?;
        let mut outcome = crate::estimate::calibrate_observations(observations?, &settings)?;
        if let Some(t) = &args.truth {
            outcome.inputs.push(("truth".into(), t.display().to_string()));
        }
        return write_observation_report(&outcome, truth, &args.out, &args.title, args.header);
    }
    let inputs = args.inputs.inputs()?;
    let mut settings = args.calibration.settings(given)?;
    let loop_note = inputs.truth_loop_note(&mut settings, args.truth.as_deref())?;
    crate::check_dir("--out", Some(&args.out))?;
    let truth = args.truth.as_deref().map(gsens_sim::read_truth_gamma).transpose()?;
    if let Some(note) = &loop_note {
        crate::out(&format!("{note}\n"))?;
    }
    let calibrated = calibrate(inputs, &settings, true)?;
    let mut outcome = calibrated.outcome;
    if let Some(t) = &args.truth {
        outcome.inputs.push(("truth".into(), t.display().to_string()));
    }
    let tracking = calibrated.tracking.context("the calibration kept no tracking log")?;
    write_report(&outcome, &tracking, truth, &args.out, &args.title, args.header)
}

/// Writes the report of a RINEX or UBX log's `outcome` into `out` and prints
/// its text, as [`write_report`], with the figures of such a log (the
/// identified loop's response, the carrier phase before and after
/// compensation).
pub(crate) fn write_observation_report(
    outcome: &ObservationOutcome,
    truth: Option<[f64; 3]>,
    out: &Path,
    title: &str,
    header: HeaderArgs,
) -> Result<crate::Status> {
    let doc = outcome.document(truth);
    let figures = gsens_report::observation_figures(outcome);
    let files = drawing(|on_figure| {
        gsens_report::write_report_dir(out, title, &doc, &figures, header.write_untrusted_header, on_figure)
    })?;
    say_written(&doc, &files)
}

/// Prints the text of a written report (stderr: why no C header was
/// written, if none was); the exit status of its document.
fn say_written(doc: &gsens_calib::ResultDocument, files: &gsens_report::ReportFiles) -> Result<crate::Status> {
    let (text, no_header) = files.render(doc, crate::args::flag);
    crate::out(&text)?;
    crate::err(no_header.as_deref().unwrap_or_default());
    Ok(crate::Status::of(doc))
}

/// Writes the report of `outcome` (estimated from `tracking`) into `out` and
/// prints its text: report.html, report.json, gsens_gamma.h (for an
/// untrustworthy estimate only as `header` asks; stderr says when it is not
/// written) and figures/.
pub(crate) fn write_report(
    outcome: &Outcome,
    tracking: &TrackingLog,
    truth: Option<[f64; 3]>,
    out: &Path,
    title: &str,
    header: HeaderArgs,
) -> Result<crate::Status> {
    let (doc, files) = drawing(|on_figure| {
        write_calibration_report(outcome, tracking, truth, out, title, header.write_untrusted_header, on_figure)
    })?;
    say_written(&doc, &files)
}
