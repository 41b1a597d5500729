//! `gsens demo`: the paper's experiment end to end — simulate the session,
//! write the logs, estimate Γ from the files as a user would, and show the
//! estimate next to the truth.

use crate::args::AnalysisArgs;
use anyhow::Result;
use clap::Args;
use gsens_montecarlo::{DemoFolder, render_demo_start, simulate_demo};
use gsens_report::write_demo_figures;
use gsens_tui::progress::{drawing, observed, with_fraction_bar};
use std::path::PathBuf;

#[derive(Args, Debug)]
pub(crate) struct DemoArgs {
    #[command(flatten)]
    pub scenario: crate::args::ScenarioArgs,
    /// Where the simulated logs go, kept (default: a fresh folder in the system's temporary
    /// directory, removed at the end).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Write the result document (JSON) here.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Also draw the figures here as PNG and SVG: the paper's Figs. 3–5, C/N0, the
    /// residual spectrum and the Allan deviation of the simulated oscillator.
    #[arg(long)]
    pub figures: Option<PathBuf>,
    #[command(flatten)]
    pub analysis: AnalysisArgs,
}

pub(crate) fn run(args: &DemoArgs, given: &[&str]) -> Result<crate::Status> {
    args.analysis.options().refuse_ignored(given, crate::args::flag)?;
    // Without --out the logs go to a folder of this run's own, removed when `folder` drops.
    let folder = DemoFolder::new(args.out.as_deref())?;
    let dir = folder.path();
    crate::check_files(&[("--json", args.json.as_deref())], Some(dir))?;
    crate::check_dir("--out", Some(dir))?;
    crate::check_dir("--figures", args.figures.as_deref())?;
    let scenario = args.scenario.load()?;
    let (named, seed) = (args.scenario.scenario.is_some(), args.scenario.seed);
    crate::out(&render_demo_start(&scenario, named, seed, dir, folder.is_scratch(), crate::args::flag))?;
    let options = args.analysis.options();
    let demo = with_fraction_bar("simulating", |progress| simulate_demo(&scenario, seed, dir, &options, progress))?;
    crate::out(&demo.estimate_line(&analysis_flags_given(), crate::args::flag))?;
    let outcome = observed(|| demo.calibrate())?;
    let doc = demo.document(&outcome);
    crate::out(&gsens_report::render_text(&doc))?;
    crate::write_json(args.json.as_deref(), &doc, "\n")?;
    if let Some(fig_dir) = &args.figures {
        let ids = drawing(|on_figure| write_demo_figures(fig_dir, &demo, &outcome, on_figure))?;
        crate::out(&format!("figures: {} ({})\n", fig_dir.display(), ids.join(", ")))?;
    }
    Ok(crate::Status::of(&doc))
}

/// The demo's own arguments that are estimation options (all but the
/// scenario, the seed and the output paths), as given: what `gsens estimate`
/// needs besides the loop to repeat the demo's estimate.
fn analysis_flags_given() -> Vec<String> {
    const DEMO_ONLY: [&str; 5] = ["--scenario", "--seed", "--out", "--json", "--figures"];
    let mut args = std::env::args().skip_while(|a| a != "demo").skip(1);
    let mut kept = Vec::new();
    while let Some(arg) = args.next() {
        let name = arg.split('=').next().unwrap_or_default();
        if !DEMO_ONLY.contains(&name) {
            kept.push(arg);
        } else if !arg.contains('=') {
            args.next();
        }
    }
    kept
}
