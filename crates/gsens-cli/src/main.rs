//! `gsens`: calibrate a GNSS receiver oscillator's g-sensitivity from its PLL
//! phase errors and its IMU. A thin shell over the library crates: argument
//! parsing, files, printing.
// clap turns the options' doc comments into `--help`, where a unit reads `[Hz]`, not a link.
#![allow(rustdoc::broken_intra_doc_links)]

mod args;
mod demo;
mod estimate;
mod import;
mod live;
mod monitor;
mod montecarlo;
mod predict;
mod replay;
mod report;
mod response;
mod simulate;
mod validate;

use anyhow::{Result, anyhow};
use clap::parser::ValueSource;
use clap::{ArgMatches, CommandFactory, FromArgMatches, Parser, Subcommand};
pub(crate) use gsens_tui::process::{Status, err, out, say};
use std::path::Path;
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
    /// Estimate Γ from receiver logs (imu.csv + tracking.csv, GNSS-SDR dumps or a PocketSDR log).
    Estimate(estimate::EstimateArgs),
    /// Simulate a calibration session and write imu.csv, tracking.csv, truth.json.
    Simulate(simulate::SimulateArgs),
    /// The loop's response from frequency bias to phase error, its peak and the shaking period to use.
    Response(response::ResponseArgs),
    /// Simulate and estimate many times in parallel: bias, RMSE and Cramér–Rao bound per method and axis.
    Montecarlo(montecarlo::MonteCarloArgs),
    /// Estimate Γ and write a report: one self-contained HTML file, the same as JSON,
    /// a C header for firmware and the figures (PNG, SVG).
    Report(report::ReportArgs),
    /// Convert another receiver's logs to gsens's tracking.csv: GNSS-SDR tracking dumps, GNSS-SDR's
    /// tracking monitor (UDP), PocketSDR pocket_trk logs.
    Import(import::ImportArgs),
    /// Calibrate while the board is shaken: live guidance (which axis, how fast, how long),
    /// Γ̂ converging, the trust checks; ends at the target σ with the report of `gsens report`.
    Live(live::LiveArgs),
    /// Stream a recorded session (imu.csv, tracking.csv) as `gsens live` receives one,
    /// at real time or faster.
    Replay(replay::ReplayArgs),
    /// Compensation proven in the loop: the same session without and with −aᵀΓ̂ fed into the
    /// carrier NCOs, at several loop bandwidths (g-induced phase error, slips, losses of lock).
    Validate(validate::ValidateArgs),
    /// What compensation buys under vibration: the phase jitter without and with −aᵀΓ̂ in the
    /// NCO, the lock margin and the narrowest loop that keeps lock, from Γ̂ and its covariance.
    Predict(predict::PredictArgs),
    /// Print the default scenario as commented TOML (edit it, pass it with --scenario).
    Scenario,
}

/// Checks before any work that the files of options `files` (flag, path) can
/// be written (in `made`, a directory the command creates first, when one lies there).
pub fn check_files(files: &[(&str, Option<&Path>)], made: Option<&Path>) -> Result<()> {
    for &(flag, path) in files {
        path.map_or(Ok(()), |p| gsens_io::check_output_file_in(p, made)).map_err(|e| anyhow!("{flag} {e}"))?;
    }
    Ok(())
}

/// Checks before any work that the directory of option `flag`, when given, exists or can be made, and
/// accepts files.
pub fn check_dir(flag: &str, path: Option<&Path>) -> Result<()> {
    path.map_or(Ok(()), gsens_io::check_output_dir).map_err(|e| anyhow!("{flag} {e}"))
}

/// Writes `value` as pretty JSON followed by `end` to the file `path`, when one is given.
pub fn write_json(path: Option<&Path>, value: &impl serde::Serialize, end: &str) -> Result<()> {
    path.map_or(Ok(()), |p| Ok(gsens_io::write_file(p, serde_json::to_string_pretty(value)? + end)?))
}

/// The options given on the subcommand's command line (not defaulted), by
/// name: the calibration options of these names are refused where the loop
/// or the method ignores them.
fn given(matches: &ArgMatches) -> Vec<String> {
    let Some((_, m)) = matches.subcommand() else { return Vec::new() };
    m.ids()
        .filter(|id| m.value_source(id.as_str()) == Some(ValueSource::CommandLine))
        .map(|id| id.to_string())
        .collect()
}

fn main() -> ExitCode {
    gsens_tui::process::run(|| {
        let matches = Cli::command().get_matches();
        let cli = Cli::from_arg_matches(&matches).unwrap_or_else(|e| e.format(&mut Cli::command()).exit());
        let given = given(&matches);
        let given: Vec<&str> = given.iter().map(String::as_str).collect();
        match cli.command {
            Command::Demo(args) => demo::run(&args, &given),
            Command::Estimate(args) => estimate::run(&args, &given),
            Command::Simulate(args) => simulate::run(&args).map(|()| Status::Done),
            Command::Response(args) => response::run(&args, &given).map(|()| Status::Done),
            Command::Montecarlo(args) => montecarlo::run(&args, &given),
            Command::Report(args) => report::run(&args, &given),
            Command::Import(args) => import::run(&args).map(|()| Status::Done),
            Command::Live(args) => live::run(&args, &given),
            Command::Replay(args) => replay::run(&args).map(|()| Status::Done),
            Command::Validate(args) => validate::run(&args),
            Command::Predict(args) => predict::run(&args),
            Command::Scenario => Ok(out(gsens_sim::scenario::Scenario::default_toml()).map(|()| Status::Done)?),
        }
    })
}
