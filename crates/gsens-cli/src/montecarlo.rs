//! `gsens montecarlo`: simulate and estimate many times, in parallel, and
//! compare each method's spread with the Cramér–Rao bound
//! (`gsens_montecarlo`).

use crate::args::{EstimatorArgs, MethodArg, SelectionArgs, SystematicArgs};
use anyhow::{Context, Result};
use clap::Args;
use gsens_montecarlo::{monte_carlo, scenario_settings};
use indicatif::{ProgressBar, ProgressStyle};
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct MonteCarloArgs {
    #[command(flatten)]
    pub scenario: crate::args::ScenarioArgs,
    /// Number of runs.
    #[arg(long, default_value_t = 200)]
    pub runs: u64,
    /// Methods to compare (comma separated).
    #[arg(long, value_enum, value_delimiter = ',', default_value = "batch,rls,gradient,gls")]
    pub methods: Vec<MethodArg>,
    /// Write the statistics (and every run's estimates) as JSON here.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// State the receiver loop's bandwidth this many times the true one (1: right), as a user who got it
    /// wrong would: how often the loop check catches the mistake.
    #[arg(long, default_value_t = 1.0, allow_negative_numbers = true, value_parser = crate::args::positive)]
    pub stated_bn_scale: f64,
    #[command(flatten)]
    pub estimator: EstimatorArgs,
    #[command(flatten)]
    pub selection: SelectionArgs,
    #[command(flatten)]
    pub systematic: SystematicArgs,
}

pub fn run(args: &MonteCarloArgs) -> Result<crate::Status> {
    args.estimator.check_methods(&args.methods)?;
    crate::outputs::maybe_file("--json", args.json.as_deref())?;
    let scenario = args.scenario.load()?;
    let mut options = gsens_calib::CalibrationOptions::default();
    args.estimator.apply(&mut options);
    args.selection.apply(&mut options);
    args.systematic.apply(&mut options);
    let methods = args
        .methods
        .iter()
        .map(|&m| {
            let o = gsens_calib::CalibrationOptions { method: m.name(), ..options.clone() };
            let mut s = scenario_settings(&scenario, &o.estimate_settings())?;
            s.receiver_loop = s.receiver_loop.with_bn_scaled(args.stated_bn_scale);
            Ok(o.pipeline_settings_around(s)?)
        })
        .collect::<Result<Vec<_>>>()?;
    let bar = ProgressBar::new(args.runs);
    bar.set_style(
        ProgressStyle::with_template("monte carlo {bar:40} {pos}/{len} runs {elapsed_precise} (eta {eta})")
            .expect("valid template"),
    );
    let name = args.scenario.scenario.as_ref().map_or("default".into(), |p| p.display().to_string());
    let seed = args.scenario.seed;
    let mc = monte_carlo(&scenario, &name, args.runs, seed, &methods, || bar.inc(1))?;
    bar.finish_and_clear();
    crate::out(&gsens_report::render_montecarlo_text(&mc))?;
    if let Some(path) = &args.json {
        std::fs::write(path, serde_json::to_string_pretty(&mc)? + "\n")
            .with_context(|| format!("{}: cannot write", path.display()))?;
    }
    Ok(crate::Status::Done)
}
