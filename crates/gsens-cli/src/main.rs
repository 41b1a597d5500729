//! `gsens`: calibrate a GNSS receiver oscillator's g-sensitivity from its PLL
//! phase errors and its IMU. A thin shell over the library crates: argument
//! parsing, files, printing.

mod demo;
mod estimate;
mod report;
mod response;
mod simulate;

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
