//! `gsens simulate`: a calibration session written as receiver logs, or (with
//! `--iq`) as IF samples for a software receiver (GNSS-SDR), with the matching
//! IMU log, the truth, Δf per millisecond and a GNSS-SDR configuration that
//! tracks the file.

use anyhow::Result;
use clap::Args;
use gsens_calib::option_values::positive;
use gsens_gnss_sdr::{IqConfOptions, write_iq_conf};
use gsens_sim::iq::{IqConfig, IqFormat};
use gsens_tui::progress::with_fraction_bar;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub(crate) struct SimulateArgs {
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
    #[arg(long, value_enum, default_value_t = IqFormat::Ibyte, requires = "iq")]
    pub iq_format: IqFormat,
    /// Sampling rate of --iq [Hz].
    #[arg(long, default_value_t = 4.0e6, requires = "iq", allow_negative_numbers = true, value_parser = positive)]
    pub fs_hz: f64,
    /// Also write carrier.csv: each satellite's baseband carrier frequency per 1 ms
    /// block (the truth a receiver's loop tracks; large).
    #[arg(long, requires = "iq")]
    pub iq_carrier_truth: bool,
    /// Send the bare C/A code without the LNAV navigation data (as a signal simulator
    /// with its message off): no bit or frame sync, no decoded time in the receiver.
    /// For PocketSDR at `epoch` < 0.07 s, whose $CH lines stop once it decodes the week;
    /// GNSS-SDR needs the data (its bit synchronization starts the 20 ms loop).
    #[arg(long, requires = "iq")]
    pub iq_no_data: bool,
}

pub(crate) fn run(args: &SimulateArgs) -> Result<()> {
    let scenario = args.scenario.load()?;
    crate::check_dir("--out", Some(&args.out))?;
    crate::check_files(&[("--iq", args.iq.as_deref())], Some(&args.out))?;
    let (seed, out) = (args.scenario.seed, args.out.as_path());
    let Some(iq) = &args.iq else {
        let truth =
            with_fraction_bar("simulating", |progress| gsens_sim::simulate_to_dir(&scenario, seed, out, progress))?;
        return Ok(crate::out(&format!("{truth}\nlogs: imu.csv, tracking.csv, truth.json in {}\n", out.display()))?);
    };
    let format = args.iq_format;
    let mut cfg = IqConfig::new(args.fs_hz, format, &scenario);
    cfg.navigation_data = !args.iq_no_data;
    let carrier_truth = args.iq_carrier_truth;
    let session = with_fraction_bar("generating", |progress| {
        gsens_sim::simulate_iq_to_dir(&scenario, seed, &cfg, iq, out, carrier_truth, progress)
    })?;
    let (l, sats) = (&scenario.tracking_loop, session.truth.satellites.len() as u32);
    let item = format.gnss_sdr_item_type();
    let options = IqConfOptions::for_iq_file(&iq.display().to_string(), item, args.fs_hz, sats, l.order, l.bn_hz);
    let conf_path = write_iq_conf(out, options)?;
    Ok(crate::out(&format!(
        "{session}\nfiles: {} and imu.csv, truth.json, delta_f.csv, gnss-sdr.conf in {}\nrun: gnss-sdr --config_file={}\n",
        iq.display(),
        out.display(),
        conf_path.display()
    ))?)
}
