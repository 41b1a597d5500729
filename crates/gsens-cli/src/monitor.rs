//! `gsens import gnss-sdr-monitor`: GNSS-SDR's tracking monitor (UDP,
//! protobuf), received live, recorded as `tracking.csv`.

use anyhow::{Context, Result, bail};
use clap::Args;
use gsens_core::units::Decimal;
use gsens_gnss_sdr::conf::{GnssSdrConf, TrackingConf};
use gsens_gnss_sdr::import::ImportSettings;
use gsens_gnss_sdr::monitor::{MonitorReceiver, MonitorStream, Notice, Recorder};
use gsens_live::SystemClock;
use std::io::{BufWriter, Write};
use std::path::PathBuf;
use std::time::Duration;

/// `gsens import gnss-sdr-monitor`.
#[derive(Args, Debug)]
pub struct ImportMonitorArgs {
    /// Address to receive on: GNSS-SDR's TrackingMonitor.client_addresses and udp_port.
    #[arg(long, default_value = "127.0.0.1:1234")]
    pub listen: String,
    /// Sampling rate [Hz] (default: the configuration's, else each message's own `fs`).
    #[arg(long, allow_negative_numbers = true, value_parser = crate::args::positive)]
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
    #[arg(long, default_value_t = 10.0, allow_negative_numbers = true, value_parser = crate::args::positive)]
    pub idle_timeout_s: f64,
    /// Seconds dropped from each track's start (default: the narrow loop's settling time).
    #[arg(long, allow_negative_numbers = true, value_parser = crate::args::finite_non_negative)]
    pub settle_s: Option<f64>,
}

/// Notices of one kind printed before the rest are only counted.
const NOTICES_SHOWN: usize = 10;

pub fn run(a: &ImportMonitorArgs) -> Result<()> {
    if !(a.idle_timeout_s.is_finite() && a.idle_timeout_s > 0.0) {
        bail!("--idle-timeout-s must be positive, got {}", a.idle_timeout_s);
    }
    if let Some(fs) = a.fs_hz.filter(|f| !(f.is_finite() && *f > 0.0)) {
        bail!("--fs-hz must be positive, got {fs}");
    }
    crate::outputs::file("--out", &a.out)?;
    crate::outputs::maybe_file("--raw", a.raw.as_deref())?;
    let MonitorSetup { import: settings, decimation, fs_hz } =
        monitor_setup(a.gnss_sdr_conf.as_deref(), a.fs_hz, a.settle_s)?;
    let settle_s = settings.settle_time_s();
    let stage = settings.stage();

    let idle = Duration::from_secs_f64(a.idle_timeout_s);
    let poll = idle.min(Duration::from_millis(200));
    let mut rx = MonitorReceiver::bind(a.listen.as_str(), MonitorStream::new(fs_hz, decimation), poll)
        .with_context(|| format!("{}: cannot listen", a.listen))?;
    let mut raw = match &a.raw {
        Some(p) => {
            Some(BufWriter::new(std::fs::File::create(p).with_context(|| format!("{}: cannot create", p.display()))?))
        }
        None => None,
    };
    crate::err(&format!("listening on {} (stops after {} s without a datagram)\n", rx.local_addr()?, a.idle_timeout_s));
    let mut recorder = Recorder::new(decimation);
    let mut shown = [0usize; 4];
    let mut say = |n: &Notice| {
        let kind = match n {
            Notice::Garbage { .. } => 0,
            Notice::Gap { .. } => 1,
            Notice::Restart { .. } => 2,
            Notice::LossOfLock { .. } => 3,
        };
        shown[kind] += 1;
        if shown[kind] <= NOTICES_SHOWN {
            crate::err(&format!("{n}\n"));
        } else if shown[kind] == NOTICES_SHOWN + 1 {
            crate::err("(further notices of this kind are only counted)\n");
        }
    };
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
    let grid = recorder.finish(settle_s);
    let tracks = recorder.tracks();
    for (channel, prn, from, to, n) in &tracks {
        crate::out(&format!("  channel {channel}: PRN {prn} {from:.2}–{to:.2} s, {n} outputs\n"))?;
    }
    let file = std::fs::File::create(&a.out).with_context(|| format!("{}: cannot create", a.out.display()))?;
    gsens_io::write_tracking_csv(BufWriter::new(file), &grid)?.flush()?;
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
    ))?;
    Ok(())
}

/// What a GNSS-SDR run's configuration says about its monitor stream.
pub struct MonitorSetup {
    /// The conversion settings: its loop, sampling rate and settling time.
    pub import: ImportSettings,
    /// `TrackingMonitor.decimation_factor`.
    pub decimation: u32,
    /// The sampling rate: `fs_hz`, else the configuration's (else each message's own).
    pub fs_hz: Option<f64>,
}

/// The monitor setup of the configuration `conf` (GNSS-SDR's defaults without one).
pub fn monitor_setup(
    conf: Option<&std::path::Path>,
    fs_hz: Option<f64>,
    settle_s: Option<f64>,
) -> Result<MonitorSetup> {
    let (tracking, decimation) = match conf {
        Some(p) => {
            let conf = GnssSdrConf::read(p)?;
            (conf.tracking()?, conf.get_count("TrackingMonitor.decimation_factor")?.unwrap_or(1))
        }
        None => (TrackingConf::defaults(), 1),
    };
    let fs_hz = fs_hz.or(tracking.fs_hz);
    if tracking.extend_correlation_symbols != 20 {
        crate::err(&format!(
            "note: Tracking_1C.extend_correlation_symbols = {}: the monitor's prompt is the 20 ms data bit's, so φ is \
             the phase of that sum, not the {} ms discriminator output\n",
            tracking.extend_correlation_symbols, tracking.extend_correlation_symbols
        ));
    }
    let mut import = ImportSettings::new(fs_hz.unwrap_or(1.0), tracking);
    import.settle_s = settle_s;
    Ok(MonitorSetup { import, decimation, fs_hz })
}
