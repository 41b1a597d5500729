//! `gsens validate`: compensation proven in the loop. Calibrates (or takes
//! a Γ̂), then runs the same session without and with −aᵀΓ̂ fed into every
//! carrier NCO at each loop bandwidth asked for, and reports what the
//! feed-forward does to the g-induced phase error, the slips and the lock.

use anyhow::{Context, Result, anyhow};
use clap::Args;
use gsens_calib::option_values::finite_non_negative;
use gsens_montecarlo::{GammaSource, ValidateError, run_validation};
use gsens_report::figures::Format;
use gsens_report::studies::fig_in_the_loop;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub(crate) struct ValidateArgs {
    #[command(flatten)]
    pub scenario: crate::args::ScenarioArgs,
    /// Γ̂ to feed forward [Hz/(m/s²)], as gx,gy,gz (default: calibrate first on the
    /// scenario's session at --seed, as `gsens demo` does).
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true, conflicts_with = "from")]
    pub gamma: Option<Vec<f64>>,
    /// Take Γ̂ from a result document (`gsens estimate --json`, `report.json`).
    #[arg(long)]
    pub from: Option<PathBuf>,
    /// The loop noise bandwidths to run at [Hz] (default: the scenario's, and narrower).
    #[arg(long, value_delimiter = ',')]
    pub bn_hz: Option<Vec<f64>>,
    /// Delay from an IMU sample to its use in the NCO command [s], on top of the IMU's own
    /// time offset and the hold until its next sample.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true, value_parser = finite_non_negative)]
    pub latency_s: f64,
    /// Write every trial (per channel, and the phase trace) as JSON here.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Draw the g-induced phase error without and with compensation (the first
    /// bandwidth's trial) here (.png or .svg).
    #[arg(long)]
    pub figure: Option<PathBuf>,
}

pub(crate) fn run(args: &ValidateArgs) -> Result<crate::Status> {
    crate::check_files(&[("--json", args.json.as_deref()), ("--figure", args.figure.as_deref())], None)?;
    let scenario = args.scenario.load()?;
    let gamma = match (&args.gamma, &args.from) {
        (Some(g), _) => GammaSource::Stated(g.clone()),
        (None, Some(path)) => GammaSource::Document(path.clone()),
        (None, None) => GammaSource::Calibrate,
    };
    let trials =
        run_validation(&scenario, args.scenario.seed, &gamma, args.bn_hz.as_deref(), args.latency_s, crate::say)
            .map_err(|e| match e {
                ValidateError::Untrustworthy(ref doc) => anyhow!("{e}:\n{}", gsens_report::render_text(doc)),
                e => crate::args::flagged("", e.setting(), e),
            })?;
    crate::write_json(args.json.as_deref(), &trials, "")?;
    if let Some(path) = &args.figure {
        let trace = trials.first().and_then(|t| t.trace.as_ref()).context("no channel to draw")?;
        let format = Format::of_path(path).unwrap_or(Format::Png);
        let image = fig_in_the_loop(&trace.t_s, &trace.uncompensated_rad, &trace.compensated_rad, format)?;
        gsens_io::write_file(path, image.as_bytes())?;
    }
    Ok(crate::Status::Done)
}
