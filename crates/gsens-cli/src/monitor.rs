//! `gsens import gnss-sdr-monitor`: GNSS-SDR's tracking monitor (UDP,
//! protobuf), received live, recorded as `tracking.csv`.

use anyhow::Result;
use clap::Args;
use gsens_calib::option_values::{finite_non_negative, positive};
use gsens_live::{MonitorRecording, SystemClock, monitor_setup};
use std::path::PathBuf;

/// `gsens import gnss-sdr-monitor`.
#[derive(Args, Debug)]
pub(crate) struct ImportMonitorArgs {
    /// Address to receive on: GNSS-SDR's TrackingMonitor.client_addresses and udp_port.
    #[arg(long, default_value = "127.0.0.1:1234")]
    pub listen: String,
    /// Sampling rate [Hz] (default: the configuration's, else each message's own `fs`).
    #[arg(long, allow_negative_numbers = true, value_parser = positive)]
    pub fs_hz: Option<f64>,
    /// The GNSS-SDR configuration of the run: its loop (for the settling time dropped after each
    /// track's start) and TrackingMonitor.decimation_factor.
    #[arg(long)]
    pub gnss_sdr_conf: Option<PathBuf>,
    /// Output tracking.csv, on the common 20 ms grid (`gsens estimate --tracking` reads it as written).
    #[arg(long, default_value = "tracking.csv")]
    pub out: PathBuf,
    /// Also write every datagram as received (u32 little-endian length, then its bytes).
    #[arg(long)]
    pub raw: Option<PathBuf>,
    /// Stop after this many seconds without a datagram (counted from the start too) [s].
    #[arg(long, default_value_t = 10.0, allow_negative_numbers = true, value_parser = positive)]
    pub idle_timeout_s: f64,
    /// Seconds dropped from each track's start (default: the narrow loop's settling time).
    #[arg(long, allow_negative_numbers = true, value_parser = finite_non_negative)]
    pub settle_s: Option<f64>,
}

pub(crate) fn run(a: &ImportMonitorArgs) -> Result<()> {
    crate::check_files(&[("--out", Some(&a.out)), ("--raw", a.raw.as_deref())], None)?;
    let setup = monitor_setup(a.gnss_sdr_conf.as_deref(), a.fs_hz, a.settle_s)?;
    let recording = MonitorRecording {
        listen: &a.listen,
        setup,
        idle_timeout_s: a.idle_timeout_s,
        out: &a.out,
        raw: a.raw.as_deref(),
    };
    Ok(recording.run(&SystemClock::new(), &mut crate::err, &mut crate::say, crate::args::flag)?)
}
