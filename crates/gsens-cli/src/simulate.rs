//! `gsens simulate`: a calibration session written as receiver logs.

use anyhow::{Context, Result};
use clap::Args;
use gsens_io::{ImuWriter, TrackingRow, TrackingWriter};
use gsens_sim::scenario::Scenario;
use gsens_sim::session::{SessionSink, SinkError, Truth, simulate};
use indicatif::{ProgressBar, ProgressStyle};
use std::fs::File;
use std::path::{Path, PathBuf};

#[derive(Args, Debug)]
pub struct SimulateArgs {
    /// Scenario TOML (default: the embedded paper experiment; see `gsens scenario`).
    #[arg(long)]
    pub scenario: Option<PathBuf>,
    /// Output directory for imu.csv, tracking.csv and truth.json.
    #[arg(long)]
    pub out: PathBuf,
    /// Seed of every random draw (same seed, same bytes).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Write complex baseband GPS L1 C/A IF samples of the scenario's satellites to
    /// this file instead of tracking logs (with imu.csv, truth.json, delta_f.csv
    /// and gnss-sdr.conf in --out; the scenario's [loop] order and bn_hz become
    /// GNSS-SDR's narrow loop).
    #[arg(long)]
    pub iq: Option<PathBuf>,
    /// Sample format of --iq (GNSS-SDR's item_type).
    #[arg(long, value_enum, default_value_t = IqFormatArg::Ibyte, requires = "iq")]
    pub iq_format: IqFormatArg,
    /// Sampling rate of --iq [Hz].
    #[arg(long, default_value_t = 4.0e6, requires = "iq")]
    pub fs_hz: f64,
    /// Also write carrier.csv: each satellite's baseband carrier frequency per 1 ms
    /// block (the truth a receiver's loop tracks; large).
    #[arg(long, requires = "iq")]
    pub iq_carrier_truth: bool,
}

/// IF sample formats on the command line.
#[derive(Clone, Copy, Debug, clap::ValueEnum, PartialEq)]
pub enum IqFormatArg {
    /// Interleaved signed 8-bit I/Q.
    Ibyte,
    /// Interleaved signed 16-bit I/Q.
    Ishort,
    /// Interleaved 32-bit float I/Q.
    GrComplex,
}

/// Streams the simulator's output into the two CSV files.
struct FileSink {
    imu: ImuWriter<File>,
    tracking: TrackingWriter<File>,
}

impl SessionSink for FileSink {
    fn imu(&mut self, t_s: f64, f_mps2: [f64; 3]) -> Result<(), SinkError> {
        Ok(self.imu.write_sample(t_s, &f_mps2)?)
    }
    fn tracking(&mut self, row: &gsens_sim::session::SimulatedRow) -> Result<(), SinkError> {
        Ok(self.tracking.write_row(&TrackingRow {
            t_s: row.t_s,
            channel: row.channel,
            prn: row.prn,
            cn0_dbhz: row.cn0_dbhz,
            elev_deg: Some(row.elev_deg),
            phase_err_rad: row.phase_err_rad,
        })?)
    }
}

/// Reads a scenario file, or the embedded default.
pub fn load_scenario(path: Option<&Path>) -> Result<Scenario> {
    match path {
        None => Ok(Scenario::from_toml_str(Scenario::default_toml())?),
        Some(p) => {
            let text = std::fs::read_to_string(p).with_context(|| format!("{}: cannot read", p.display()))?;
            Scenario::from_toml_str(&text).with_context(|| format!("{}", p.display()))
        }
    }
}

/// Simulates `scenario` into `dir` (imu.csv, tracking.csv, truth.json) with a
/// progress bar on a terminal.
pub fn simulate_to_dir(scenario: &Scenario, seed: u64, dir: &Path) -> Result<Truth> {
    std::fs::create_dir_all(dir).with_context(|| format!("{}: cannot create", dir.display()))?;
    let create = |name: &str| {
        let p = dir.join(name);
        File::create(&p).with_context(|| format!("{}: cannot create", p.display()))
    };
    let mut sink =
        FileSink { imu: ImuWriter::new(create("imu.csv")?)?, tracking: TrackingWriter::new(create("tracking.csv")?)? };
    // indicatif draws nothing when stderr is not a terminal.
    let bar = ProgressBar::new(1000);
    bar.set_style(
        ProgressStyle::with_template("simulating {bar:40} {percent:>3}% {elapsed_precise} (eta {eta})")
            .expect("valid template"),
    );
    let truth = simulate(scenario, seed, &mut sink, |f| bar.set_position((f * 1000.0) as u64))?;
    bar.finish_and_clear();
    sink.imu.finish()?;
    sink.tracking.finish()?;
    let truth_path = dir.join("truth.json");
    std::fs::write(&truth_path, serde_json::to_string_pretty(&truth)? + "\n")
        .with_context(|| format!("{}: cannot write", truth_path.display()))?;
    Ok(truth)
}

pub fn run(args: &SimulateArgs) -> Result<()> {
    let scenario = load_scenario(args.scenario.as_deref())?;
    if let Some(iq) = &args.iq {
        return crate::simulate_iq::run(&scenario, args, iq);
    }
    let truth = simulate_to_dir(&scenario, args.seed, &args.out)?;
    let slips: u64 = truth.channels.iter().map(|c| c.stats.cycle_slips).sum();
    println!(
        "simulated {:.1} s, {} channel passes ({} cycle slips), seed {} → {}",
        truth.duration_s,
        truth.channels.len(),
        slips,
        args.seed,
        args.out.display()
    );
    println!(
        "truth Γ = [{:+.4}, {:+.4}, {:+.4}] Hz/(m/s²); loop interval {} s, log interval {} s, logged phase {:?}",
        truth.gamma_hz_per_mps2[0],
        truth.gamma_hz_per_mps2[1],
        truth.gamma_hz_per_mps2[2],
        truth.loop_interval_s,
        truth.log_interval_s,
        truth.logged_phase
    );
    Ok(())
}
