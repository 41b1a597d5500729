//! `gsens simulate`: a calibration session written as receiver logs, or (with
//! `--iq`) as IF samples for a software receiver (GNSS-SDR), with the matching
//! IMU log, the truth, Δf per millisecond and a GNSS-SDR configuration that
//! tracks the file.

use anyhow::{Context, Result};
use clap::Args;
use gsens_gnss_sdr::conf::{IqConfOptions, iq_file_conf};
use gsens_sim::iq::{IqConfig, IqFormat};
use gsens_sim::scenario::Scenario;
use gsens_sim::session::Truth;
use indicatif::{ProgressBar, ProgressStyle};
use std::path::{Path, PathBuf};

#[derive(Args, Debug)]
pub struct SimulateArgs {
    #[command(flatten)]
    pub scenario: crate::args::ScenarioArgs,
    /// Output directory for imu.csv, tracking.csv and truth.json.
    #[arg(long)]
    pub out: PathBuf,
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

/// A progress bar on stderr (drawn only on a terminal) for work counted in thousandths.
pub fn progress_bar(verb: &str) -> ProgressBar {
    let bar = ProgressBar::new(1000);
    let template = format!("{verb} {{bar:40}} {{percent:>3}}% {{elapsed_precise}} (eta {{eta}})");
    bar.set_style(ProgressStyle::with_template(&template).expect("valid template"));
    bar
}

/// Simulates `scenario` into `dir` (imu.csv, tracking.csv, truth.json) with a
/// progress bar on a terminal.
pub fn simulate_to_dir(scenario: &Scenario, seed: u64, dir: &Path) -> Result<Truth> {
    let bar = progress_bar("simulating");
    let truth = gsens_sim::simulate_to_dir(scenario, seed, dir, |f| bar.set_position((f * 1000.0) as u64))?;
    bar.finish_and_clear();
    Ok(truth)
}

pub fn run(args: &SimulateArgs) -> Result<()> {
    let scenario = args.scenario.load()?;
    if let Some(iq) = &args.iq {
        return run_iq(&scenario, args, iq);
    }
    let truth = simulate_to_dir(&scenario, args.scenario.seed, &args.out)?;
    crate::out(&format!("{truth}\nlogs: imu.csv, tracking.csv, truth.json in {}\n", args.out.display()))
}

/// Writes `iq` and, in `--out`, the files of `gsens_sim::simulate_iq_to_dir`
/// and gnss-sdr.conf.
fn run_iq(scenario: &Scenario, args: &SimulateArgs, iq: &Path) -> Result<()> {
    let (fs_hz, out) = (args.fs_hz, args.out.as_path());
    let format = match args.iq_format {
        IqFormatArg::Ibyte => IqFormat::Ibyte,
        IqFormatArg::Ishort => IqFormat::Ishort,
        IqFormatArg::GrComplex => IqFormat::GrComplex,
    };
    let bar = progress_bar("generating");
    let cfg = IqConfig::new(fs_hz, format, scenario);
    let session =
        gsens_sim::simulate_iq_to_dir(scenario, args.scenario.seed, &cfg, iq, out, args.iq_carrier_truth, |f| {
            bar.set_position((f * 1000.0) as u64)
        })?;
    bar.finish_and_clear();
    let truth = &session.truth;

    // The GNSS-SDR configuration: absolute paths, so it runs from anywhere.
    let abs = |p: &Path| std::fs::canonicalize(p).unwrap_or_else(|_| p.to_path_buf());
    let dumps = out.join("gnss-sdr");
    std::fs::create_dir_all(&dumps).with_context(|| format!("{}: cannot create", dumps.display()))?;
    let l = &scenario.tracking_loop;
    let sats = truth.satellites.len() as u32;
    let mut o = IqConfOptions::for_iq_file(
        &abs(iq).display().to_string(),
        format.gnss_sdr_item_type(),
        fs_hz,
        sats,
        l.order,
        l.bn_hz,
    );
    o.dump_filename = format!("{}/trk_ch_", abs(&dumps).display());
    let conf_path = out.join("gnss-sdr.conf");
    std::fs::write(&conf_path, iq_file_conf(&o)).with_context(|| format!("{}: cannot write", conf_path.display()))?;

    crate::out(&format!(
        "{session}\nfiles: {} and imu.csv, truth.json, delta_f.csv, gnss-sdr.conf in {}\nrun: gnss-sdr --config_file={}\n",
        iq.display(),
        out.display(),
        abs(&conf_path).display()
    ))
}
