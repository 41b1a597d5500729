//! `gsens import gnss-sdr-monitor`: GNSS-SDR's tracking monitor (UDP,
//! protobuf), received live, recorded as `tracking.csv`.

use crate::import::create;
use anyhow::{Context, Result, bail};
use clap::Args;
use gsens_calib::option_values::{finite_non_negative, positive};
use gsens_core::units::Decimal;
use gsens_gnss_sdr::monitor::{MonitorReceiver, MonitorStream, Notice, Recorder};
use gsens_live::{NoticeLimit, SystemClock, monitor_setup, render_recorded_tracks};
use std::io::{BufWriter, Write};
use std::path::PathBuf;
use std::time::Duration;

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
    crate::check_file("--out", Some(&a.out), None)?;
    crate::check_file("--raw", a.raw.as_deref(), None)?;
    let setup = monitor_setup(a.gnss_sdr_conf.as_deref(), a.fs_hz, a.settle_s)?;
    crate::err(setup.note.as_deref().unwrap_or_default());
    let (settle_s, stage) = (setup.import.settle_time_s(), setup.import.stage());
    let idle = Duration::from_secs_f64(a.idle_timeout_s);
    let poll = idle.min(Duration::from_millis(200));
    let mut rx = MonitorReceiver::bind(a.listen.as_str(), MonitorStream::new(setup.fs_hz, setup.decimation), poll)
        .with_context(|| format!("{}: cannot listen", a.listen))?;
    let mut raw = a.raw.as_deref().map(create).transpose()?.map(BufWriter::new);
    crate::err(&format!("listening on {} (stops after {} s without a datagram)\n", rx.local_addr()?, a.idle_timeout_s));
    let mut recorder = Recorder::new(setup.decimation);
    let mut limit = NoticeLimit::default();
    let mut say = |n: &Notice| crate::err(&limit.line(n).unwrap_or_default());
    let raw_out = raw.as_mut().map(|w| w as &mut dyn Write);
    gsens_live::record_monitor(&mut rx, &mut recorder, raw_out, a.idle_timeout_s, &SystemClock::new(), &mut say)?;
    let counts = &rx.stream.counts;
    crate::out(&format!("received {}\n", counts.summary()))?;
    if counts.rows == 0 {
        bail!(
            "no tracking row received on {} in the run ({}): is GNSS-SDR's TrackingMonitor.enable_monitor=true with \
             client_addresses and udp_port pointing here?",
            a.listen,
            counts.summary()
        );
    }
    let (grid, tracks) = (recorder.finish(settle_s), recorder.tracks());
    crate::out(&render_recorded_tracks(&tracks))?;
    gsens_io::write_tracking_csv(BufWriter::new(create(&a.out)?), &grid)?.flush()?;
    crate::out(&format!(
        "wrote {} rows of {} tracks → {} (common {} s grid, the first {:.2} s of each track dropped){}; estimate \
         with the receiver's loop: gsens estimate --tracking {} --order {} --bn-hz {} --loop-interval-s {}\n",
        grid.len(),
        tracks.len(),
        a.out.display(),
        Decimal(recorder.interval_s()),
        settle_s,
        a.raw.as_ref().map_or(String::new(), |p| format!(", datagrams → {}", p.display())),
        a.out.display(),
        stage.order,
        stage.bw_hz,
        Decimal(f64::from(stage.symbols) * 1e-3),
    ))
}
