//! `gsens validate`: compensation proven in the loop. Calibrates (or takes
//! a Γ̂), then runs the same session without and with −aᵀΓ̂ fed into every
//! carrier NCO at each loop bandwidth asked for, and reports what the
//! feed-forward does to the g-induced phase error, the slips and the lock.

use anyhow::{Context, Result, anyhow, bail};
use clap::Args;
use gsens_calib::ResultDocument;
use gsens_calib::option_values::finite_non_negative;
use gsens_montecarlo::{
    ValidateError, calibrate_scenario, default_bandwidths_hz, render_gamma_hat, render_trial_row,
    render_validate_footer, render_validate_header, validate,
};
use gsens_report::figures::Format;
use gsens_report::studies::fig_in_the_loop;
use gsens_sim::compensation::CompensationSection;
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
    crate::check_file("--json", args.json.as_deref(), None)?;
    crate::check_file("--figure", args.figure.as_deref(), None)?;
    let scenario = args.scenario.load()?;
    let seed = args.scenario.seed;
    let gamma_hat = match (&args.gamma, &args.from) {
        (Some(g), _) => <[f64; 3]>::try_from(&g[..])
            .map_err(|_| anyhow!("--gamma takes three values, as gx,gy,gz (got {})", g.len()))?,
        (None, Some(path)) => ResultDocument::read_gamma_file(path)?.0,
        (None, None) => {
            crate::out(&format!("calibrating on the scenario's session (seed {seed}) …\n"))?;
            let g = match calibrate_scenario(&scenario, seed) {
                Err(ValidateError::Untrustworthy(doc)) => bail!(
                    "the calibration is not trustworthy, so there is no Γ̂ to validate:\n{}",
                    gsens_report::render_text(&doc)
                ),
                g => g?,
            };
            crate::out(&render_gamma_hat(g))?;
            g
        }
    };
    let compensation = CompensationSection { gamma_hz_per_mps2: gamma_hat, latency_s: args.latency_s };
    let bn_list = args.bn_hz.clone().unwrap_or_else(|| default_bandwidths_hz(&scenario));
    // A session other than the calibration's: the same Γ̂ on fresh noise.
    crate::out(&render_validate_header(&scenario, gamma_hat, args.latency_s, seed + 1))?;
    let trials =
        validate(&scenario, seed + 1, &compensation, &bn_list, |bn, trial| crate::out(&render_trial_row(bn, trial)))
            .map_err(|e| match e.downcast::<ValidateError>() {
                Ok(ValidateError::Bandwidth(bn)) => anyhow!("--bn-hz {bn}: must be positive"),
                Ok(e) => e.into(),
                Err(e) => e,
            })?;
    crate::out(&render_validate_footer())?;
    if let Some(path) = &args.json {
        crate::write(path, serde_json::to_string_pretty(&trials)?)?;
    }
    if let Some(path) = &args.figure {
        let trace = trials.first().and_then(|t| t.trace.as_ref()).context("no channel to draw")?;
        let format = Format::of_path(path).unwrap_or(Format::Png);
        fig_in_the_loop(&trace.t_s, &trace.uncompensated_rad, &trace.compensated_rad, format)?
            .write_to(path)
            .with_context(|| format!("{}: cannot write", path.display()))?;
    }
    Ok(crate::Status::Done)
}
