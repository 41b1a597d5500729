//! `gsens demo`: the paper's experiment end to end — simulate the session,
//! write the logs, estimate Γ from the files as a user would, and show the
//! estimate next to the truth.

use crate::args::AnalysisArgs;
use crate::simulate::simulate_to_dir;
use anyhow::{Context, Result};
use clap::Args;
use gsens_calib::{Outcome, calibrate_files};
use gsens_montecarlo::scenario_settings;
use gsens_report::{Figure, FigureInputs, write_figures};
use gsens_sim::scenario::Scenario;
use std::path::{Path, PathBuf};

#[derive(Args, Debug)]
pub struct DemoArgs {
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

pub fn run(args: &DemoArgs) -> Result<crate::Status> {
    args.analysis.check()?;
    // Without --out the logs go to a folder of this run's own, removed when `scratch` drops.
    let (dir, scratch) = match &args.out {
        Some(out) => (out.clone(), None),
        None => {
            let scratch = tempfile::Builder::new()
                .prefix("gsens-demo-")
                .tempdir()
                .context("cannot make a folder in the system's temporary directory for the demo's logs")?;
            (scratch.path().to_path_buf(), Some(scratch))
        }
    };
    crate::outputs::maybe_file_in("--json", args.json.as_deref(), Some(&dir))?;
    crate::outputs::dir("--out", &dir)?;
    if let Some(d) = &args.figures {
        crate::outputs::dir("--figures", d)?;
    }
    let scenario = args.scenario.load()?;
    crate::out(&format!(
        "simulating {:.0} s of the {} (seed {}) into {}{} …\n",
        scenario.duration_s(),
        if args.scenario.scenario.is_some() { "given scenario" } else { "paper's experiment" },
        args.scenario.seed,
        dir.display(),
        if scratch.is_some() { " (removed at the end: --out DIR keeps the logs)" } else { "" }
    ))?;
    let truth = simulate_to_dir(&scenario, args.scenario.seed, &dir)?;
    let options = args.analysis.options();
    let settings = options.pipeline_settings_around(scenario_settings(&scenario, &options.estimate_settings())?)?;
    let l = &scenario.tracking_loop;
    let (imu, tracking) = (dir.join("imu.csv"), dir.join("tracking.csv"));
    let outcome = crate::observed(|| calibrate_files(&tracking, &imu, &settings))?;
    let logged = scenario.log.phase.name();
    let (i, t) = (imu.display(), tracking.display());
    let mut flags =
        format!("--order {} --bn-hz {} --loop-interval-s {} --logged-phase {logged}", l.order, l.bn_hz, l.interval_s);
    let e = &settings.estimate;
    if e.carrier_hz != gsens_core::units::GPS_L1_HZ {
        flags += &format!(" --carrier-hz {}", e.carrier_hz);
    }
    // The scenario's IMU error model enters σ as it would a datasheet's.
    if e.imu_scale_sigma > 0.0 {
        flags += &format!(" --imu-scale-sigma-ppm {}", gsens_core::units::Decimal(e.imu_scale_sigma * 1e6));
    }
    if e.imu_misalignment_sigma_rad > 0.0 {
        flags += &format!(
            " --imu-misalignment-sigma-mrad {}",
            gsens_core::units::Decimal(e.imu_misalignment_sigma_rad * 1e3)
        );
    }
    for arg in analysis_flags_given() {
        flags += &format!(" {arg}");
    }
    crate::out(&format!(
        "estimating from {i} and {t} (the command line: gsens estimate --imu {i} --tracking {t} {flags})\n\n"
    ))?;
    let doc = outcome.document(Some(truth.sensitivity.gamma_hz_per_mps2));
    crate::out(&gsens_report::render_text(&doc))?;
    if let Some(path) = &args.json {
        doc.write_json_file(path).with_context(|| format!("{}: cannot write", path.display()))?;
    }
    if let Some(fig_dir) = &args.figures {
        write_demo_figures(
            fig_dir,
            &outcome,
            &tracking,
            truth.sensitivity.gamma_hz_per_mps2,
            &scenario,
            args.scenario.seed,
        )?;
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
        if DEMO_ONLY.contains(&name) {
            if !arg.contains('=') {
                args.next();
            }
        } else {
            kept.push(arg);
        }
    }
    kept
}

/// The figures of the demo's calibration plus the Allan deviation of the
/// scenario's oscillator, as PNG and SVG.
fn write_demo_figures(
    dir: &Path,
    outcome: &Outcome,
    tracking: &Path,
    truth: [f64; 3],
    scenario: &Scenario,
    seed: u64,
) -> Result<()> {
    let bar = crate::spinner();
    let log = gsens_io::read_tracking_file(tracking)?;
    let inputs = FigureInputs::new(outcome, Some(&log), Some(truth))?;
    let mut figs = inputs.figures();
    let cfg = scenario.oscillator.config();
    if cfg.h0 + cfg.h_neg1 + cfg.h_neg2 + cfg.h2 > 0.0 {
        // 20 minutes at 40 Hz against the model.
        let a = gsens_sim::oscillator::allan_comparison(&cfg, 0.025, 48_000, seed)?;
        let label = scenario.oscillator.preset.description().to_string();
        figs.push(Figure::allan(a.taus_s, a.simulated, a.theory, a.duration_s, label));
    }
    write_figures(&figs, dir, |id| bar.set_message(format!("drawing {id}")))?;
    bar.finish_and_clear();
    let ids: Vec<&str> = figs.iter().map(|f| f.id).collect();
    crate::out(&format!("figures: {} ({})\n", dir.display(), ids.join(", ")))
}
