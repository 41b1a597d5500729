//! `gsens estimate`: Γ̂ from receiver logs.

use crate::args::CalibrationArgs;
use anyhow::{Result, anyhow};
use clap::Args;
use gsens_calib::PipelineSettings;
use gsens_inputs::{Estimated, InputsError, Route};
use gsens_tui::progress::observed;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub(crate) struct EstimateArgs {
    #[command(flatten)]
    pub inputs: gsens_inputs::InputChoice,
    /// Write the result document (JSON) here.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Write the estimator's input here as CSV: per epoch t_s, the channel-averaged
    /// phase_err_rad and the specific force interpolated onto the epoch (what a receiver
    /// feeds the C API's calibrator; examples/c/calibrate.c reads it).
    #[arg(long)]
    pub epochs_out: Option<PathBuf>,
    #[command(flatten)]
    pub calibration: CalibrationArgs,
}

/// Runs the calibration of `route` (keeping the tracking log the estimate
/// was made from when `keep_tracking`), printing what the route did besides
/// the estimate ([`Estimated::notes`]).
pub(crate) fn calibrate(route: Route, settings: &PipelineSettings, keep_tracking: bool) -> Result<Estimated> {
    let estimated = observed(|| route.calibrate(settings, keep_tracking)).map_err(|e| match e {
        InputsError::LoopStatedTwice { .. } => anyhow!(gsens_gnss_sdr::loop_stated_twice(crate::args::flag)),
        e => e.into(),
    })?;
    crate::out(&estimated.notes())?;
    Ok(estimated)
}

pub(crate) fn run(args: &EstimateArgs, given: &[&str]) -> Result<crate::Status> {
    let settings = args.calibration.settings(given)?;
    crate::check_files(&[("--json", args.json.as_deref()), ("--epochs-out", args.epochs_out.as_deref())], None)?;
    let route = crate::args::route(&args.inputs)?;
    if args.epochs_out.is_some() && matches!(route, Route::Observations(_)) {
        return Err(anyhow!("--epochs-out needs a tracking error, which --rinex and --ubx logs do not hold"));
    }
    let estimated = calibrate(route, &settings, false)?;
    let doc = estimated.document(None);
    crate::out(&gsens_report::render_text(&doc))?;
    crate::write_json(args.json.as_deref(), &doc, "\n")?;
    if let (Some(path), Estimated::Tracking(calibrated)) = (&args.epochs_out, &estimated) {
        let s = calibrated.outcome.series();
        gsens_io::write_epochs_file(path, s.t_s, s.phase_err_rad, s.accel_mps2)?;
    }
    Ok(crate::Status::of(&doc))
}

#[cfg(test)]
mod tests {
    use crate::args::CalibrationArgs;
    use clap::Parser;
    use gsens_calib::{CalibrationOptions, TimeOffsetOption};

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        calibration: CalibrationArgs,
    }

    /// The flags' defaults are the library's: one vocabulary for the CLI and Python.
    #[test]
    fn no_flags_give_the_library_defaults() {
        let cli = Cli::try_parse_from(["gsens"]).unwrap();
        assert_eq!(cli.calibration.options(), CalibrationOptions::default());
    }

    #[test]
    fn flags_map_to_the_options_of_the_same_name() {
        let args = ["gsens", "--bn-hz", "2.5", "--order", "3", "--time-offset", "-0.01", "--weights", "cn0"];
        let o = Cli::try_parse_from(args).unwrap().calibration.options();
        assert_eq!(o.receiver_loop.bn_hz, Some(2.5));
        assert_eq!(o.receiver_loop.order, Some(3));
        assert_eq!(o.systematic.time_offset, TimeOffsetOption::Seconds(-0.01));
        assert_eq!(o.selection.weights, gsens_session::Weighting::Cn0);
        assert!(o.loop_stated());
    }
}
