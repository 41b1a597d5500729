//! What shaking at two rates buys the estimate from the NCO's frequency
//! when the receiver's loop is identified from the session
//! (`gsens_montecarlo::identified_monte_carlo`): the paper's one-rate
//! protocol and the two-rate protocol (`examples/scenarios/two-rate.toml`),
//! each for a 2nd-order 3 Hz loop updated every 1 ms and a 3rd-order 10 Hz
//! loop every 5 ms, from the NCO's phase differenced at 20 Hz and its
//! command logged at 10 Hz. Prints one Markdown row per case (the table of
//! docs/trust.md, "The two-rate protocol with the loop identified").
//!
//! Usage: `identified_loop [--runs N] [--seed S] [--case K] [--interval-known] [--json PATH]`

use clap::Parser;
use gsens_calib::{LoopFreeSettings, NcoRecord, TimeOffset};
use gsens_core::LoggedPhase;
use gsens_montecarlo::{IdentifiedMonteCarlo, identified_monte_carlo, scenario_shapes};
use gsens_sim::scenario::Scenario;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Parser, Debug)]
#[command(about = "Monte Carlo of the NCO-frequency estimate with the loop identified, one and two rates")]
struct Args {
    /// Runs per case.
    #[arg(long, default_value_t = 200)]
    runs: u64,
    /// Seed of each case's first run (run i: seed + i).
    #[arg(long, default_value_t = 1000)]
    seed: u64,
    /// Run only this case (1–8, in the table's order).
    #[arg(long, value_parser = clap::value_parser!(u8).range(1..=8))]
    case: Option<u8>,
    /// Try only the loop shapes updated at the scenario loop's interval (the
    /// order and Bn still identified), as for a receiver whose update
    /// interval is known.
    #[arg(long)]
    interval_known: bool,
    /// Write every case's statistics and runs as JSON here.
    #[arg(long)]
    json: Option<PathBuf>,
}

/// The two-rate protocol's motion.
const TWO_RATE: &str = include_str!("../../../examples/scenarios/two-rate.toml");

/// One case: its protocol, loop and record, and its scenario's TOML.
struct Case {
    protocol: &'static str,
    loop_name: &'static str,
    record: NcoRecord,
    toml: String,
}

fn cases() -> Vec<Case> {
    let protocols = [("one rate", ""), ("two rates", TWO_RATE)];
    let loops = [
        ("2nd order, 3 Hz, 1 ms", "[loop]\norder = 2\nbn_hz = 3.0\ninterval_s = 0.001\n"),
        ("3rd order, 10 Hz, 5 ms", "[loop]\norder = 3\nbn_hz = 10.0\ninterval_s = 0.005\n"),
    ];
    let records = [(NcoRecord::PhaseDifference, 0.05), (NcoRecord::Command, 0.1)];
    let mut out = Vec::new();
    for (protocol, motion) in protocols {
        for (loop_name, loop_toml) in loops {
            for (record, interval_s) in records {
                let toml = format!("{motion}\n{loop_toml}[log]\nnco = true\ninterval_s = {interval_s}\n");
                out.push(Case { protocol, loop_name, record, toml });
            }
        }
    }
    out
}

/// The settings of the identification: as the library's tests state them,
/// the IMU time offset searched within ±0.1 s.
fn settings() -> LoopFreeSettings {
    let mut s = LoopFreeSettings::new(0.001, LoggedPhase::Last);
    s.time_offset = TimeOffset::Auto { max_abs_s: 0.1 };
    s
}

fn record_name(record: NcoRecord) -> &'static str {
    match record {
        NcoRecord::Command => "command, 10 Hz",
        _ => "phase differenced, 20 Hz",
    }
}

fn triple(x: [f64; 3], digits: usize) -> String {
    x.map(|v| format!("{v:.digits$}")).join(" / ")
}

/// The case's row of the estimate's table.
fn gamma_row(k: usize, case: &Case, mc: &IdentifiedMonteCarlo) -> String {
    let s = &mc.stats;
    format!(
        "| {} | {}; {} | {} | {} | {} | {} | {} | {} |",
        k + 1,
        case.loop_name,
        record_name(case.record),
        case.protocol,
        triple(s.rmse_over_known_crlb, 2),
        triple(s.z_rms, 2),
        triple(s.bias.map(|v| 1e4 * v), 1),
        triple(s.known_crlb.map(|v| 1e4 * v), 2),
        triple(s.known_rmse_over_known_crlb, 2),
    )
}

/// The case's row of the loop's table.
fn loop_row(k: usize, case: &Case, mc: &IdentifiedMonteCarlo) -> String {
    let s = &mc.stats;
    let n = s.runs;
    let bn_error = s.bn_relative_error_rms.map_or("–".into(), |e| format!("{:.2} %", 100.0 * e));
    let bn_z = s.bn_z_rms.map_or("–".into(), |z| format!("{z:.2}"));
    format!(
        "| {} | {}; {} | {} | {} of {n} | {bn_error} | {bn_z} | {} | {} ({} right) of {n} | {} of {n} |",
        k + 1,
        case.loop_name,
        record_name(case.record),
        case.protocol,
        s.bn_resolved,
        s.bn_compared,
        s.order_resolved,
        s.order_right,
        s.interval_right,
    )
}

fn main() -> ExitCode {
    let args = Args::parse();
    match run(&args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("identified_loop: {e}");
            ExitCode::from(2)
        }
    }
}

fn run(args: &Args) -> Result<(), Box<dyn std::error::Error>> {
    let (mut all, mut rows) = (Vec::new(), Vec::new());
    for (k, case) in cases().iter().enumerate().filter(|(k, _)| args.case.is_none_or(|c| usize::from(c) == k + 1)) {
        let scenario = Scenario::from_toml_str(&case.toml)?;
        let start = std::time::Instant::now();
        let shapes = scenario_shapes(&scenario, args.interval_known);
        let mc = identified_monte_carlo(&scenario, args.runs, args.seed, case.record, &shapes, &settings(), || {})?;
        eprintln!(
            "case {}: {:.1} s wall, {} failed {:?}",
            k + 1,
            start.elapsed().as_secs_f64(),
            mc.failed.len(),
            mc.failed
        );
        rows.push((gamma_row(k, case, &mc), loop_row(k, case, &mc)));
        all.push(mc);
    }
    println!(
        "| case | loop; NCO record | protocol | RMSE/CRLB x / y / z | z RMS | bias [10⁻⁴ Hz/(m/s²)] | CRLB, loop known [10⁻⁴ Hz/(m/s²)] | loop known: RMSE/CRLB |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- | --- |");
    for (gamma, _) in &rows {
        println!("{gamma}");
    }
    println!(
        "\n| case | loop; NCO record | protocol | Bn resolved | Bn RMS error | Bn z RMS | runs compared (order right) | order resolved | interval kept right |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- | --- | --- |");
    for (_, bn) in &rows {
        println!("{bn}");
    }
    if let Some(path) = &args.json {
        std::fs::write(path, serde_json::to_string_pretty(&all)?)
            .map_err(|e| format!("writing {}: {e}", path.display()))?;
    }
    Ok(())
}
