//! `gsens live`: calibrate while the board is shaken, telling the person
//! holding it what to do next. The session runs in `gsens_live::Runtime`;
//! here are its options, turned into a `gsens_live::RuntimeConfig`, the
//! choice of screen (gsens-tui's, or plain lines) and the report at the end.

use crate::args::CalibrationArgs;
use anyhow::Result;
use clap::Args;
use gsens_calib::option_values::{finite_non_negative, positive};
use gsens_live::{Display, InputChoice, InputChoiceError, Runtime, RuntimeConfig, SystemClock};
use std::io::IsTerminal;
use std::path::PathBuf;
use std::sync::Arc;

#[derive(Args, Debug)]
pub(crate) struct LiveArgs {
    /// Read one merged stream from standard input: lines `imu,t_s,fx_mps2,fy_mps2,fz_mps2`
    /// and `trk,t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad` (`gsens replay` writes it).
    #[arg(long, conflicts_with_all = ["follow_imu", "follow_tracking"])]
    pub stdin: bool,
    /// Receive GNSS-SDR's tracking monitor on this address (its TrackingMonitor.client_addresses
    /// and udp_port, e.g. 127.0.0.1:1234), with --follow-imu and --gnss-sdr-conf.
    #[arg(long, conflicts_with = "follow_tracking", requires_all = ["follow_imu", "gnss_sdr_conf"])]
    pub gnss_sdr_monitor: Option<String>,
    /// The GNSS-SDR configuration of the run sending the monitor: its loop (modelled exactly),
    /// sampling rate, TrackingMonitor.decimation_factor and settling time.
    #[arg(long, requires = "gnss_sdr_monitor")]
    pub gnss_sdr_conf: Option<PathBuf>,
    /// Follow a growing imu.csv (as `tail -f`), with --follow-tracking or --gnss-sdr-monitor, or
    /// with --ubx instead of the module's own accelerometer.
    #[arg(long)]
    pub follow_imu: Option<PathBuf>,
    /// Follow a growing tracking.csv, with --follow-imu.
    #[arg(long, requires = "follow_imu")]
    pub follow_tracking: Option<PathBuf>,
    /// A u-blox module's UBX stream: a log being written (followed as it grows), its serial port
    /// (/dev/ttyACM0, a UART), a named pipe or - for standard input (read until closed), RXM-RAWX with the module's accelerometer (ESF-RAW / ESF-MEAS) unless
    /// --follow-imu is given; its loop is identified from the session. The bytes are kept as
    /// received.ubx in --out.
    #[arg(
        long,
        conflicts_with_all = ["stdin", "follow_tracking", "gnss_sdr_monitor"],
        help_heading = "u-blox UBX stream"
    )]
    pub ubx: Option<PathBuf>,
    /// The serial port's baud rate (a UART: the module's, e.g. 38400 or 115200; a USB port ignores
    /// it); by default the port is left at its rate.
    #[arg(long, requires = "ubx", value_parser = clap::value_parser!(u32).range(1..), help_heading = "u-blox UBX stream")]
    pub ubx_baud: Option<u32>,
    /// How the ESF sensor time tags map to GPS time, as for `gsens estimate --ubx`.
    #[arg(long, value_enum, default_value = "free-running-ms", requires = "ubx", help_heading = "u-blox UBX stream")]
    pub ubx_sensor_time: gsens_ublox::SensorTime,
    /// What the estimate is made from, as for `gsens estimate --ubx`.
    #[arg(long, value_enum, default_value_t, requires = "ubx", help_heading = "u-blox UBX stream")]
    pub observable: gsens_calib::ObservationRecord,
    /// With --follow-*, --gnss-sdr-monitor and --ubx: end when no input has grown for this long [s]
    /// (0: only on a key or the target).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true, value_parser = finite_non_negative)]
    pub idle_timeout_s: f64,
    /// Output directory: the records received (imu.csv, tracking.csv; every line as
    /// received in received/; a UBX stream's bytes as received.ubx), and at the end the report
    /// of `gsens report`
    /// (report.html, report.json, gsens_gamma.h as `gsens report` writes it, figures/).
    #[arg(long)]
    pub out: PathBuf,
    /// End when every axis's σ is at most this [Hz/(m/s²)]; ending before (the input ended, a key,
    /// --idle-timeout-s) exits with status 4.
    #[arg(long, default_value_t = 1e-3, allow_negative_numbers = true, value_parser = positive)]
    pub target_sigma: f64,
    /// Re-run the estimate every this many seconds of data [s].
    #[arg(long, default_value_t = 5.0, allow_negative_numbers = true, value_parser = positive)]
    pub batch_every_s: f64,
    /// Plain lines instead of the terminal screen (also when standard output is not a terminal).
    #[arg(long)]
    pub plain: bool,
    /// truth.json of a simulated session: the true Γ in the report, and its loop when none is stated.
    #[arg(long)]
    pub truth: Option<PathBuf>,
    /// Heading of the report.
    #[arg(long, default_value = "Oscillator g-sensitivity calibration (live)")]
    pub title: String,
    #[command(flatten)]
    pub header: crate::report::HeaderArgs,
    #[command(flatten)]
    pub calibration: CalibrationArgs,
}

/// The input the options name.
fn choice(args: &LiveArgs) -> InputChoice {
    InputChoice {
        stdin: args.stdin,
        follow_imu: args.follow_imu.clone(),
        follow_tracking: args.follow_tracking.clone(),
        gnss_sdr_monitor: args.gnss_sdr_monitor.clone().zip(args.gnss_sdr_conf.clone()),
        ubx: args.ubx.clone(),
        ubx_baud: args.ubx_baud,
        ubx_options: gsens_live::UbxOptions {
            settings: gsens_ublox::UbxSettings { sensor_time: args.ubx_sensor_time },
            record: args.observable,
        },
    }
}

/// An input's error with the options named by their flags.
fn flagged(e: InputChoiceError) -> anyhow::Error {
    match e.named(crate::args::flag) {
        Some(message) => anyhow::Error::msg(message),
        None => e.into(),
    }
}

pub(crate) fn run(args: &LiveArgs, given: &[&str]) -> Result<crate::Status> {
    choice(args).check().map_err(flagged)?;
    let mut settings = args.calibration.settings(given)?;
    let loop_note = gsens_inputs::truth_loop_note(&mut settings, args.truth.as_deref())?;
    crate::check_dir("--out", Some(&args.out))?;
    let (inputs, note) = choice(args).inputs(args.calibration.receiver_loop.stated()).map_err(flagged)?;
    crate::err(note.as_deref().unwrap_or_default());
    let truth = args.truth.as_deref().map(gsens_sim::read_truth_gamma).transpose()?;
    let config = RuntimeConfig {
        inputs,
        out_dir: args.out.clone(),
        settings,
        target_sigma_hz_per_mps2: args.target_sigma,
        batch_every_s: args.batch_every_s,
        idle_timeout_s: args.idle_timeout_s,
    };
    let mut runtime = Runtime::start(config, Arc::new(SystemClock::new()))?;
    if let Some(note) = &loop_note {
        crate::out(&format!("{note}\n"))?;
    }
    crate::out(&runtime.opening())?;
    let ending = if args.plain || !std::io::stdout().is_terminal() {
        runtime.run(Display::Plain(&mut gsens_tui::process::Stdout))?
    } else {
        // The terminal is restored when the screen is dropped, before the final report.
        runtime.run(Display::Screen(&mut gsens_tui::Terminal::new()?))?
    };
    crate::out(&ending.heading())?;
    let mut finished = runtime.finish()?;
    if let Some(t) = &args.truth {
        finished.estimate.inputs_mut().push(("truth".into(), t.display().to_string()));
    }
    crate::out(&finished.estimate.notes())?;
    let status = crate::report::write_report(&finished.estimate, truth, &args.out, &args.title, args.header)?;
    let missed = finished.target_missed(args.target_sigma);
    crate::out(missed.as_deref().unwrap_or_default())?;
    Ok(if missed.is_some() && status == crate::Status::Done { crate::Status::TargetMissed } else { status })
}
