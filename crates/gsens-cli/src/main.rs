//! `gsens`: calibrate a GNSS receiver oscillator's g-sensitivity from its PLL
//! phase errors and its IMU. A thin shell over the library crates: argument
//! parsing, files, printing.

mod cmd_report;
mod demo;
mod estimate;
mod gnss_sdr_cmd;
mod montecarlo;
mod report;
mod response;
mod simulate;
mod simulate_iq;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "gsens",
    version,
    about = "Oscillator g-sensitivity calibration from live GNSS signals, PLLs and an IMU"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Simulate a calibration session (the paper's experiment by default),
    /// estimate Γ from it and show the estimate next to the truth.
    Demo(demo::DemoArgs),
    /// Estimate Γ from receiver logs (imu.csv + tracking.csv).
    Estimate(estimate::EstimateArgs),
    /// Simulate a calibration session and write imu.csv, tracking.csv, truth.json.
    Simulate(simulate::SimulateArgs),
    /// The loop's response from frequency bias to phase error, its peak and the shaking period to use.
    Response(response::ResponseArgs),
    /// Simulate and estimate many times in parallel: bias, RMSE and Cramér–Rao bound per method and axis.
    Montecarlo(montecarlo::MonteCarloArgs),
    /// Estimate Γ and write a report: one self-contained HTML file, the same as JSON,
    /// a C header for firmware and the figures (PNG, SVG).
    Report(cmd_report::ReportArgs),
    /// Convert another receiver's logs to gsens's (GNSS-SDR tracking dumps → tracking.csv).
    Import(gnss_sdr_cmd::ImportArgs),
    /// Print the default scenario as commented TOML (edit it, pass it with --scenario).
    Scenario,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Demo(args) => demo::run(&args),
        Command::Estimate(args) => estimate::run(&args),
        Command::Simulate(args) => simulate::run(&args),
        Command::Response(args) => response::run(&args),
        Command::Montecarlo(args) => montecarlo::run(&args),
        Command::Report(args) => cmd_report::run(&args),
        Command::Import(args) => gnss_sdr_cmd::import(&args),
        Command::Scenario => {
            print!("{}", gsens_sim::scenario::Scenario::default_toml());
            Ok(())
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::from(2)
        }
    }
}
