//! `gsens demo`: the paper's experiment end to end — simulate the session,
//! write the logs, estimate Γ from the files as a user would, and show the
//! estimate next to the truth.

use crate::args::{EstimatorArgs, SelectionArgs, SystematicArgs, pipeline_settings};
use crate::simulate::{load_scenario, simulate_to_dir};
use anyhow::Result;
use clap::Args;
use gsens_calib::montecarlo::scenario_settings;
use gsens_calib::{Outcome, calibrate_files};
use gsens_report::{Figure, FigureInputs, write_figures};
use gsens_sim::scenario::{LoggedPhaseMode, OscillatorKind, Scenario};
use std::path::{Path, PathBuf};

#[derive(Args, Debug)]
pub struct DemoArgs {
    /// Scenario TOML (default: the embedded paper experiment).
    #[arg(long)]
    pub scenario: Option<PathBuf>,
    /// Seed of the simulation.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Where the simulated logs go (default: a `gsens-demo` folder in the system's temporary directory).
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
    pub estimator: EstimatorArgs,
    #[command(flatten)]
    pub selection: SelectionArgs,
    #[command(flatten)]
    pub systematic: SystematicArgs,
}

pub fn run(args: &DemoArgs) -> Result<()> {
    let scenario = load_scenario(args.scenario.as_deref())?;
    let dir = args.out.clone().unwrap_or_else(|| std::env::temp_dir().join("gsens-demo"));
    crate::out(&format!(
        "simulating {:.0} s of the {} (seed {}) into {} …\n",
        scenario.duration_s(),
        if args.scenario.is_some() { "given scenario" } else { "paper's experiment" },
        args.seed,
        dir.display()
    ))?;
    let truth = simulate_to_dir(&scenario, args.seed, &dir)?;
    let base = args.estimator.settings();
    let settings = pipeline_settings(scenario_settings(&scenario, &base)?, &args.selection, &args.systematic);
    let l = &scenario.tracking_loop;
    let (imu, tracking) = (dir.join("imu.csv"), dir.join("tracking.csv"));
    let outcome = calibrate_files(&tracking, &imu, &settings)?;
    let logged = match scenario.log.phase {
        LoggedPhaseMode::Last => "last",
        LoggedPhaseMode::Mean => "mean",
    };
    let (i, t) = (imu.display(), tracking.display());
    crate::out(&format!(
        "estimating from {i} and {t} (the command line: gsens estimate --imu {i} --tracking {t} --order {} --bn-hz {} \
         --loop-interval-s {} --logged-phase {logged})\n\n",
        l.order, l.bn_hz, l.interval_s
    ))?;
    let inputs = [("imu", i.to_string()), ("tracking", t.to_string())];
    let doc = outcome.document(&crate::estimate::input_refs(&inputs), Some(truth.gamma_hz_per_mps2));
    crate::out(&gsens_report::render_text(&doc))?;
    if let Some(path) = &args.json {
        crate::estimate::write_json(path, &doc)?;
    }
    if let Some(fig_dir) = &args.figures {
        write_demo_figures(fig_dir, &outcome, &tracking, truth.gamma_hz_per_mps2, &scenario, args.seed)?;
    }
    Ok(())
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
        let label = match scenario.oscillator.preset {
            OscillatorKind::Ocxo => "OCXO preset",
            OscillatorKind::Tcxo => "TCXO preset",
            OscillatorKind::TcxoLowQuality => "low-quality TCXO preset",
            OscillatorKind::Ideal => "ideal preset with noise overrides",
        };
        figs.push(allan_figure(&cfg, label, seed)?);
    }
    write_figures(&figs, dir, |id| bar.set_message(format!("drawing {id}")))?;
    bar.finish_and_clear();
    let ids: Vec<&str> = figs.iter().map(|f| f.id).collect();
    crate::out(&format!("figures: {} ({})\n", dir.display(), ids.join(", ")))
}

/// The Allan deviation of `cfg` simulated for 20 minutes at 40 Hz against its model.
fn allan_figure(cfg: &gsens_sim::oscillator::OscillatorConfig, label: &str, seed: u64) -> Result<Figure<'static>> {
    use gsens_report::figures::{AllanData, fig_allan};
    use gsens_sim::oscillator::{Oscillator, allan_deviation_theory_with_pm, allan_deviations};
    let (dt, n) = (0.025, 48_000);
    let mut osc = Oscillator::try_new(cfg, dt, gsens_sim::rng::seeded(seed)).map_err(anyhow::Error::msg)?;
    let mut y = vec![0.0; n];
    osc.fill(&mut y);
    let taus: Vec<f64> = (0..16).map(|k| dt * 2f64.powi(k)).filter(|t| *t <= n as f64 * dt / 4.0).collect();
    let sim = allan_deviations(&y, dt, &taus);
    let theory: Vec<f64> = taus.iter().map(|&t| allan_deviation_theory_with_pm(cfg, t, dt)).collect();
    let label = label.to_string();
    let caption = format!(
        "Overlapping Allan deviation of {:.0} minutes of the simulator's fractional frequency ({label}) against \
         the power-law model of its preset; deterministic terms (offset, drift, temperature cycle) are in the \
         simulation but not in the model.",
        n as f64 * dt / 60.0
    );
    Ok(Figure::new("allan", "Allan deviation of the simulated oscillator".into(), caption, move |f| {
        let d = AllanData { taus_s: &taus, simulated: &sim, theory: &theory, label: &label };
        fig_allan(&d, f, (900, 600))
    }))
}
