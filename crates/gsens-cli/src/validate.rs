//! `gsens validate`: compensation proven in the loop. Calibrates (or takes
//! a Γ̂), then runs the same session without and with −aᵀΓ̂ fed into every
//! carrier NCO at each loop bandwidth asked for, and reports what the
//! feed-forward does to the g-induced phase error, the slips and the lock.

use anyhow::{Context, Result};
use clap::Args;
use gsens_montecarlo::{ValidateError, calibrate_scenario, default_bandwidths_hz, validate};
use gsens_report::figures::{CompensationData, CompensationKind, Format, fig_compensation};
use gsens_sim::compensation::CompensationSection;
use gsens_sim::compensation_trial::RUNS;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct ValidateArgs {
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
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true, value_parser = crate::args::finite_non_negative)]
    pub latency_s: f64,
    /// Write every trial (per channel, and the phase trace) as JSON here.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Draw the g-induced phase error without and with compensation (the first
    /// bandwidth's trial) here (.png or .svg).
    #[arg(long)]
    pub figure: Option<PathBuf>,
}

pub fn run(args: &ValidateArgs) -> Result<crate::Status> {
    crate::outputs::maybe_file("--json", args.json.as_deref())?;
    crate::outputs::maybe_file("--figure", args.figure.as_deref())?;
    let scenario = args.scenario.load()?;
    let seed = args.scenario.seed;
    let gamma_hat = match (&args.gamma, &args.from) {
        (Some(g), _) if g.len() == 3 => [g[0], g[1], g[2]],
        (Some(g), _) => anyhow::bail!("--gamma takes three values, as gx,gy,gz (got {})", g.len()),
        (None, Some(path)) => crate::estimate::gamma_of_document(path)?.0,
        (None, None) => {
            crate::out(&format!("calibrating on the scenario's session (seed {seed}) …\n"))?;
            let g = match calibrate_scenario(&scenario, seed) {
                Err(ValidateError::Untrustworthy(doc)) => anyhow::bail!(
                    "the calibration is not trustworthy, so there is no Γ̂ to validate:\n{}",
                    gsens_report::render_text(&doc)
                ),
                g => g?,
            };
            crate::out(&format!("Γ̂ [Hz/(m/s²)] = [{:+.5}, {:+.5}, {:+.5}]\n", g[0], g[1], g[2]))?;
            g
        }
    };
    let compensation = CompensationSection { gamma_hz_per_mps2: gamma_hat, latency_s: args.latency_s };
    let bn_list = args.bn_hz.clone().unwrap_or_else(|| default_bandwidths_hz(&scenario));
    let g = scenario.oscillator.gamma_hz_per_mps2;
    crate::out(&format!(
        "Γ [Hz/(m/s²)] of the oscillator: [{:+.5}, {:+.5}, {:+.5}]; Γ̂ fed forward: [{:+.5}, {:+.5}, {:+.5}]; {} \
         oscillator; IMU at {} Hz, latency {} s; the validation sessions use seed {}\n\n",
        g[0],
        g[1],
        g[2],
        gamma_hat[0],
        gamma_hat[1],
        gamma_hat[2],
        scenario.oscillator.preset.name(),
        scenario.imu.rate_hz,
        args.latency_s,
        seed + 1
    ))?;
    crate::out(
        "  Bn [Hz]   g-induced φ RMS under shaking [rad]      logged φ RMS [rad]       cycle slips          losses of lock\n\
         \x20          without    with      reduced by        ref    without with     ref  without with   ref  without with\n",
    )?;
    // A session other than the calibration's: the same Γ̂ on fresh noise.
    let trials = validate(&scenario, seed + 1, &compensation, &bn_list, |bn, trial| -> Result<()> {
        let [lr, lu, lc] = trial.logged_rms_rad;
        let [sr, su, sc] = trial.cycle_slips;
        let [or, ou, oc] = trial.losses_of_lock;
        crate::out(&format!(
            "  {bn:6.2}    {:8.4}  {:8.4}    ×{:<8.1}      {lr:6.3} {lu:6.3} {lc:6.3}    {sr:5} {su:6} {sc:5}   {or:4} {ou:6} {oc:5}\n",
            trial.g_rms_rad[0], trial.g_rms_rad[1], trial.suppression
        ))
    })
    .map_err(|e| match e.downcast::<ValidateError>() {
        Ok(ValidateError::Bandwidth(bn)) => anyhow::anyhow!("--bn-hz {bn}: must be positive"),
        Ok(e) => e.into(),
        Err(e) => e,
    })?;
    crate::out(&format!(
        "\nruns: {}; g-induced = the run's true phase error less the reference's, same noise; slips and losses: \
         the simulator's truth over all channels\n",
        RUNS.join(", ")
    ))?;
    if let Some(path) = &args.json {
        let text = serde_json::to_string_pretty(&trials)?;
        std::fs::write(path, text).with_context(|| format!("{}: cannot write", path.display()))?;
    }
    if let Some(path) = &args.figure {
        let trace = trials.first().and_then(|t| t.trace.as_ref()).context("no channel to draw")?;
        let before: Vec<Option<f64>> = trace.uncompensated_rad.iter().map(|&v| Some(v)).collect();
        let after: Vec<Option<f64>> = trace.compensated_rad.iter().map(|&v| Some(v)).collect();
        let format = Format::of_path(path).unwrap_or(Format::Png);
        let data = CompensationData {
            t_s: &trace.t_s,
            before_rad: &before,
            after_rad: &after,
            kind: CompensationKind::InTheLoop,
        };
        fig_compensation(&data, format, gsens_report::figures::DEFAULT_SIZE)?
            .write_to(path)
            .with_context(|| format!("{}: cannot write", path.display()))?;
    }
    Ok(crate::Status::Done)
}
