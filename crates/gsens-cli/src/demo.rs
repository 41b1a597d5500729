//! `gsens demo`: the paper's experiment end to end — simulate the session,
//! write the logs, estimate Γ from the files as a user would, and show the
//! estimate next to the truth.

use crate::estimate::{EstimatorArgs, LoggedArg, LoopArgs, SelectionArgs, SystematicArgs, estimate_files};
use crate::simulate::{load_scenario, simulate_to_dir};
use anyhow::{Context, Result};
use clap::Args;
use gsens_calib::EstimateSettings;
use gsens_sim::scenario::{LoggedPhaseMode, Scenario};
use std::path::PathBuf;

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
    #[command(flatten)]
    pub estimator: EstimatorArgs,
    #[command(flatten)]
    pub selection: SelectionArgs,
    #[command(flatten)]
    pub systematic: SystematicArgs,
    /// Write the estimate as JSON here.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Also draw the figures here as PNG and SVG: the paper's Figs. 3–5, C/N0, the
    /// residual spectrum and the Allan deviation of the simulated oscillator.
    #[arg(long)]
    pub figures: Option<PathBuf>,
}

/// The estimator settings for a simulated scenario: the receiver loop the
/// scenario ran, its carrier, and its IMU's datasheet accuracy (where the
/// options leave them at 0), as a user would give them.
pub fn scenario_settings(scenario: &Scenario, estimator: &EstimatorArgs) -> Result<EstimateSettings> {
    let l = &scenario.tracking_loop;
    let loop_args = LoopArgs {
        order: l.order,
        bn_hz: l.bn_hz,
        zeta: l.zeta,
        a3: l.a3,
        b3: l.b3,
        loop_interval_s: Some(l.interval_s),
        logged_phase: match scenario.log.phase {
            LoggedPhaseMode::Last => LoggedArg::Last,
            LoggedPhaseMode::Mean => LoggedArg::Mean,
        },
    };
    let mut settings = estimator.settings(&loop_args)?;
    settings.carrier_hz = scenario.oscillator.carrier_hz;
    let imu = scenario.imu.config();
    if settings.imu_scale_sigma == 0.0 {
        settings.imu_scale_sigma = imu.scale_factor_sigma_ppm * 1e-6;
    }
    if settings.imu_misalignment_sigma_rad == 0.0 {
        settings.imu_misalignment_sigma_rad = imu.misalignment_sigma_rad;
    }
    Ok(settings)
}

pub fn run(args: &DemoArgs) -> Result<()> {
    let scenario = load_scenario(args.scenario.as_deref())?;
    let dir = args.out.clone().unwrap_or_else(|| std::env::temp_dir().join("gsens-demo"));
    println!(
        "simulating {:.0} s of the {} (seed {}) into {} …",
        scenario.duration_s(),
        if args.scenario.is_some() { "given scenario" } else { "paper's experiment" },
        args.seed,
        dir.display()
    );
    let truth = simulate_to_dir(&scenario, args.seed, &dir)?;
    let settings = scenario_settings(&scenario, &args.estimator)?;
    let l = &scenario.tracking_loop;
    let (imu, tracking) = (dir.join("imu.csv"), dir.join("tracking.csv"));
    let (session, calibration) =
        estimate_files(&imu, &tracking, &args.selection.selection(), &args.systematic, &settings)?;
    println!(
        "estimating from {} and {} (the command line: gsens estimate --imu {} --tracking {} --order {} --bn-hz {} --loop-interval-s {} --logged-phase {})\n",
        imu.display(),
        tracking.display(),
        imu.display(),
        tracking.display(),
        l.order,
        l.bn_hz,
        l.interval_s,
        match scenario.log.phase {
            LoggedPhaseMode::Last => "last",
            LoggedPhaseMode::Mean => "mean",
        }
    );
    print!("{}", crate::report::text(&session, &calibration, Some(truth.gamma_hz_per_mps2)));
    if let Some(path) = &args.json {
        crate::report::write_json(
            path,
            &session,
            &calibration,
            Some(truth.gamma_hz_per_mps2),
            &[("imu", &imu), ("tracking", &tracking)],
        )
        .with_context(|| format!("writing {}", path.display()))?;
    }
    if let Some(fig_dir) = &args.figures {
        crate::cmd_report::write_demo_figures(
            fig_dir,
            &session,
            &calibration,
            &tracking,
            truth.gamma_hz_per_mps2,
            &scenario,
            args.seed,
        )?;
    }
    Ok(())
}
