//! `gsens estimate`: Γ̂ from receiver logs.

use crate::args::{CalibrationArgs, InputArgs};
use anyhow::{Result, anyhow};
use clap::Args;
use gsens_calib::{ObservationOutcome, PipelineSettings};
use gsens_inputs::{Calibrated, Inputs, InputsError, ObservationInputs};
use gsens_tui::progress::observed;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub(crate) struct EstimateArgs {
    #[command(flatten)]
    pub inputs: InputArgs,
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

/// Runs the calibration of `inputs` (keeping the tracking log the estimate
/// was made from when `keep_tracking`), printing what became of each track of
/// a receiver's log and which receiver loop was modelled.
pub(crate) fn calibrate(inputs: Inputs, settings: &PipelineSettings, keep_tracking: bool) -> Result<Calibrated> {
    let run = || if keep_tracking { inputs.calibrate_keeping_tracking(settings) } else { inputs.calibrate(settings) };
    let calibrated = observed(run).map_err(|e| match e {
        InputsError::LoopStatedTwice { .. } => anyhow!(gsens_gnss_sdr::loop_stated_twice(crate::args::flag)),
        e => e.into(),
    })?;
    let loop_note = calibrated.loop_note().map(|note| note + "\n");
    crate::out(&(calibrated.track_summary().unwrap_or_default() + &loop_note.unwrap_or_default()))?;
    Ok(calibrated)
}

/// Runs the calibration of a RINEX or UBX log, printing what became of its
/// tracks.
pub(crate) fn calibrate_observations(
    inputs: ObservationInputs,
    settings: &PipelineSettings,
) -> Result<ObservationOutcome> {
    let outcome = observed(|| inputs.calibrate(settings))?;
    crate::out(&gsens_inputs::render_observation_summary(&outcome))?;
    Ok(outcome)
}

pub(crate) fn run(args: &EstimateArgs, given: &[&str]) -> Result<crate::Status> {
    let settings = args.calibration.settings(given)?;
    crate::check_files(&[("--json", args.json.as_deref()), ("--epochs-out", args.epochs_out.as_deref())], None)?;
    if let Some(observations) = args.inputs.observations() {
        if args.epochs_out.is_some() {
            return Err(anyhow!("--epochs-out needs a tracking error, which --rinex and --ubx logs do not hold"));
        }
        let outcome = calibrate_observations(observations?, &settings)?;
        let doc = outcome.document(None);
        crate::out(&gsens_report::render_text(&doc))?;
        crate::write_json(args.json.as_deref(), &doc, "\n")?;
        return Ok(crate::Status::of(&doc));
    }
    let outcome = calibrate(args.inputs.inputs()?, &settings, false)?.outcome;
    let doc = outcome.document(None);
    crate::out(&gsens_report::render_text(&doc))?;
    crate::write_json(args.json.as_deref(), &doc, "\n")?;
    if let Some(path) = &args.epochs_out {
        let s = outcome.series();
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
