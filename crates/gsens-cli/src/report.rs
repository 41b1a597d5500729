//! `gsens report`: the calibration as one self-contained HTML file, its
//! result document as JSON, the compensation parameters as a C header, and the
//! figures as PNG and SVG.

use crate::estimate::{CalibrationArgs, calibrate};
use anyhow::Result;
use clap::Args;
use gsens_report::{FigureInputs, write_report_dir};
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct ReportArgs {
    /// IMU log: t_s,fx_mps2,fy_mps2,fz_mps2.
    #[arg(long)]
    pub imu: PathBuf,
    /// Tracking log: t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad.
    #[arg(long)]
    pub tracking: PathBuf,
    /// truth.json of a simulated session: the true Γ is drawn dashed and the errors reported.
    #[arg(long)]
    pub truth: Option<PathBuf>,
    /// Output directory: report.html, report.json, gsens_gamma.h and figures/ (PNG and SVG).
    #[arg(long)]
    pub out: PathBuf,
    /// Heading of the report.
    #[arg(long, default_value = "Oscillator g-sensitivity calibration")]
    pub title: String,
    #[command(flatten)]
    pub calibration: CalibrationArgs,
}

pub fn run(args: &ReportArgs) -> Result<crate::Status> {
    let settings = args.calibration.settings();
    let truth = args.truth.as_deref().map(gsens_sim::read_truth_gamma).transpose()?;
    let bar = crate::spinner();
    bar.set_message("reading the logs and estimating Γ");
    let mut outcome = calibrate(&args.imu, Some(&args.tracking), None, &settings)?;
    if let Some(t) = &args.truth {
        outcome.inputs.push(("truth".into(), t.display().to_string()));
    }
    let doc = outcome.document(truth);
    bar.set_message("reading the tracking log for C/N0");
    let tracking = gsens_io::read_tracking_file(&args.tracking)?;
    let figure_inputs = FigureInputs::new(&outcome, Some(&tracking), truth)?;
    let html = write_report_dir(&args.out, &args.title, &doc, &figure_inputs.figures(), |id| {
        bar.set_message(format!("drawing {id}"))
    })?;
    bar.finish_and_clear();
    crate::out(&gsens_report::render_text(&doc))?;
    crate::out(&format!("\nreport: {} (with report.json, gsens_gamma.h and figures/ beside it)\n", html.display()))?;
    Ok(crate::Status::of(&doc))
}
