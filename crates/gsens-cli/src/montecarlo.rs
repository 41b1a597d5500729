//! `gsens montecarlo`: simulate and estimate many times, in parallel, and
//! compare each method's spread with the Cramér–Rao bound
//! (`gsens_montecarlo`).

use anyhow::Result;
use clap::Args;
use gsens_calib::option_values::positive;
use gsens_calib::{CalibrationOptions, EstimatorOptions, MethodName, SelectionOptions, SystematicOptions};
use gsens_montecarlo::{method_settings, monte_carlo};
use gsens_tui::progress::with_count_bar;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub(crate) struct MonteCarloArgs {
    #[command(flatten)]
    pub scenario: crate::args::ScenarioArgs,
    /// Number of runs.
    #[arg(long, default_value_t = 200)]
    pub runs: u64,
    /// Methods to compare (comma separated).
    #[arg(long, value_enum, value_delimiter = ',', default_value = "batch,rls,gradient,gls")]
    pub methods: Vec<MethodName>,
    /// Write the statistics (and every run's estimates) as JSON here.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// State the receiver loop's bandwidth this many times the true one (1: right), as a user who got it
    /// wrong would: how often the loop check catches the mistake.
    #[arg(long, default_value_t = 1.0, allow_negative_numbers = true, value_parser = positive)]
    pub stated_bn_scale: f64,
    /// State no receiver loop at all: the data choose it, as for a receiver whose loop is not known
    /// (the loop-free estimate needs none).
    #[arg(long, conflicts_with = "stated_bn_scale")]
    pub loop_unstated: bool,
    /// State the loop in words only, not as gsens's own discrete form: the data choose among the forms
    /// the words take in the receivers gsens models, as for a user who names no implementation.
    #[arg(long, conflicts_with = "loop_unstated")]
    pub loop_form_unknown: bool,
    #[command(flatten)]
    pub estimator: EstimatorOptions,
    #[command(flatten)]
    pub selection: SelectionOptions,
    #[command(flatten)]
    pub systematic: SystematicOptions,
}

pub(crate) fn run(args: &MonteCarloArgs, given: &[&str]) -> Result<crate::Status> {
    args.estimator.refuse_unused(given, &args.methods, crate::args::flag)?;
    crate::check_files(&[("--json", args.json.as_deref())], None)?;
    let scenario = args.scenario.load()?;
    let options = CalibrationOptions {
        estimator: args.estimator.clone(),
        selection: args.selection.clone(),
        systematic: args.systematic.clone(),
        ..CalibrationOptions::default()
    };
    let stated = (!args.loop_unstated).then_some(args.stated_bn_scale);
    let mut methods = method_settings(&scenario, &options, &args.methods, stated)?;
    if args.loop_form_unknown {
        methods.iter_mut().for_each(|m| m.loop_form = gsens_calib::LoopForm::Compared);
    }
    let name = args.scenario.scenario.as_ref().map_or("default".into(), |p| p.display().to_string());
    let (runs, seed) = (args.runs, args.scenario.seed);
    let mc =
        with_count_bar("monte carlo", runs, "runs", |tick| monte_carlo(&scenario, &name, runs, seed, &methods, tick))?;
    crate::out(&gsens_report::render_montecarlo_text(&mc))?;
    crate::write_json(args.json.as_deref(), &mc, "\n")?;
    Ok(crate::Status::Done)
}
