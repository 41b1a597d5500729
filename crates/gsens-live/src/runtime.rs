//! A live session run from its inputs to its final estimate: the reader
//! threads started ([`crate::sources`], [`crate::monitor`]), the event loop
//! that gives their records to the [`LiveSession`] and keeps them, the
//! screen kept up to date, and the final estimate on the logs kept.
//!
//! Wall time is read only through the [`Clock`] given to
//! [`Runtime::start`]; the records and lines can come from an injected
//! channel ([`Inputs::Events`]), so a whole session runs in a test without
//! waiting.

use std::fs::File;
use std::io::{BufRead, BufWriter, Write};
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::mpsc::{self, Receiver, RecvTimeoutError};
use std::thread::JoinHandle;
use std::time::Duration;

use gsens_calib::PipelineSettings;
use gsens_gnss_sdr::monitor::{LiveGrid, MonitorReceiver, MonitorStream};
use gsens_inputs::{Calibrated, Conversion, Estimated, ObservationFile, ObservationInputs};

use crate::clock::Clock;
use crate::guidance::Protocol;
use crate::input::{Input, LineFormat, LineKind, LineParser, Notice};
use crate::kept::{Kept, create, received_dir};
use crate::merge::Merger;
use crate::monitor::{MonitorInput, RECEIVE_WAIT_MS, receive_monitor};
use crate::plain::Plain;
use crate::session::{BatchResult, LiveConfig, LiveSession, LiveView};
use crate::sources::{Source, SourceEvent, spawn_follow, spawn_lines};
use crate::ubx::{UbxOptions, spawn_bytes, stream_name};

/// The screen is redrawn at most this often [ms]: with the followers' 20 ms
/// polls a record reaches the screen within 70 ms, inside a 100 ms budget.
const DRAW_EVERY_MS: u64 = 50;

/// With plain lines, the instruction and the batch estimate are looked at
/// every this many seconds of data \[s\] (a tenth of the guidance's 1 s
/// resolution; a view costs microseconds).
const PLAIN_STEP_S: f64 = 0.1;

/// The event loop waits at most this long for an event before it looks at
/// the screen [ms].
const EVENT_WAIT_MS: u64 = 20;

/// Events taken before the screen is looked at again: the screen keeps its
/// 100 ms while a burst arrives.
const EVENTS_PER_ROUND: usize = 2000;

/// The inputs of a session.
pub enum Inputs {
    /// One merged stream (`imu,…` and `trk,…` lines, [`crate::LineParser`]), read to its end.
    Merged {
        /// Its name in notices and in `received/` (`stdin`).
        name: String,
        /// The stream.
        reader: Box<dyn BufRead + Send>,
    },
    /// A growing `imu.csv` and a growing `tracking.csv`, followed as they grow.
    Files {
        /// The IMU log.
        imu: PathBuf,
        /// The tracking log.
        tracking: PathBuf,
    },
    /// A growing `imu.csv` and GNSS-SDR's tracking monitor.
    Monitor {
        /// The IMU log.
        imu: PathBuf,
        /// The monitor (boxed: its settings are large beside the other inputs).
        monitor: Box<MonitorInput>,
    },
    /// A u-blox module's UBX stream: a log being written, followed as it
    /// grows, or its serial port; its RXM-RAWX calibrated with the loop
    /// identified, its IMU the stream's ESF messages or a growing IMU log.
    Ubx {
        /// The log, the serial device (a character device: read as a serial
        /// port), a named pipe, or `-`: standard input.
        log: PathBuf,
        /// The serial port's baud rate; `None`: as the port is set (a USB
        /// port ignores it).
        baud: Option<u32>,
        /// A growing IMU log instead of the stream's ESF messages (`t_s`
        /// on the log's time, as `gsens estimate --ubx` reads it).
        imu: Option<PathBuf>,
        /// How the stream is read and calibrated.
        options: UbxOptions,
    },
    /// A UBX stream whose events are sent on a channel by the caller, as
    /// [`Inputs::Events`]: source 0 sends the stream's bytes
    /// ([`SourceEvent::Bytes`]), a source 1 (with the format of IMU lines),
    /// if any, the IMU instead of the stream's ESF messages.
    UbxEvents {
        /// The sources the events' `source` indexes.
        sources: Vec<Source>,
        /// The events.
        events: Receiver<SourceEvent>,
        /// How the stream is read and calibrated.
        options: UbxOptions,
    },
    /// Sources whose events are sent on a channel by the caller (a test,
    /// another front end); the session ends when every source has ended or
    /// the channel closes.
    Events {
        /// The sources the events' `source` indexes.
        sources: Vec<Source>,
        /// The events.
        events: Receiver<SourceEvent>,
    },
}

/// What a live session is given.
pub struct RuntimeConfig {
    /// Its inputs.
    pub inputs: Inputs,
    /// The directory of the kept files (`received/`, `imu.csv`,
    /// `tracking.csv`; a UBX stream's bytes as `received.ubx`).
    pub out_dir: PathBuf,
    /// The batch pipeline's settings. With the monitor, its loop is the run's own.
    pub settings: PipelineSettings,
    /// The session ends when every axis's σ is at most this \[Hz/(m/s²)\].
    pub target_sigma_hz_per_mps2: f64,
    /// The batch estimate is re-run every this many seconds of data \[s\].
    pub batch_every_s: f64,
    /// A followed file or the monitor ends when it brought nothing for this
    /// long \[s\]; 0: never.
    pub idle_timeout_s: f64,
}

/// A terminal screen the session is drawn on.
pub trait LiveScreen {
    /// Draws the session as it is.
    fn draw(&mut self, view: &LiveView) -> std::io::Result<()>;
    /// Whether the person asked to stop (a key), looked at without waiting.
    fn quit_asked(&mut self) -> std::io::Result<bool>;
}

/// How the session is shown while it runs.
pub enum Display<'a> {
    /// Plain lines of text (the instruction when it changes, each batch
    /// estimate, warnings and notices), the batch estimate run in line so
    /// that the same input gives the same lines.
    Plain(&'a mut dyn Write),
    /// A screen redrawn as data arrive, the batch estimate run in a worker thread.
    Screen(&'a mut dyn LiveScreen),
}

/// Why a session ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Ending {
    /// Every input ended (its end, an error, its idle timeout).
    InputEnded,
    /// A key on the screen.
    Key,
    /// Every axis meets the target σ.
    TargetMet,
}

impl core::fmt::Display for Ending {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Ending::InputEnded => "the input ended",
            Ending::Key => "stopped by a key",
            Ending::TargetMet => "every axis meets the target σ",
        })
    }
}

impl Ending {
    /// The line that leads the final report: why the session ended.
    pub fn heading(&self) -> String {
        format!("ended: {self}; the final estimate on everything received:\n")
    }
}

/// What can stop a live session.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RuntimeError {
    /// The receiver loop of the settings cannot be modelled.
    #[error("the receiver loop")]
    Loop(#[source] gsens_core::LoopError),
    /// A kept file or directory cannot be created.
    #[error("{}: cannot create", path.display())]
    Create {
        /// The file or directory.
        path: PathBuf,
        /// Why.
        #[source]
        error: std::io::Error,
    },
    /// The monitor's address cannot be listened on.
    #[error("{addr}: cannot listen")]
    Listen {
        /// The address.
        addr: String,
        /// Why.
        #[source]
        error: std::io::Error,
    },
    /// Writing a kept file or the screen failed.
    #[error(transparent)]
    Io(#[from] std::io::Error),
    /// The session ended without both kinds of record.
    #[error(
        "nothing to estimate from: {imu_samples} IMU samples and {tracking_rows} tracking rows were received (the \
         notices above say why lines were not used)"
    )]
    NothingReceived {
        /// IMU samples received.
        imu_samples: u64,
        /// Tracking rows received.
        tracking_rows: u64,
    },
    /// The kept logs do not read back.
    #[error(transparent)]
    Format(#[from] gsens_io::FormatError),
    /// The final estimate failed.
    #[error(transparent)]
    Estimate(#[from] gsens_calib::PipelineError),
    /// The final estimate of the kept UBX log failed.
    #[error(transparent)]
    Observations(#[from] gsens_inputs::InputsError),
}

/// The end of a session: the final estimate, the batch estimate of the logs kept.
pub struct Finished {
    /// The final estimate, as `gsens report` makes it from the kept logs
    /// (its inputs those logs): from `imu.csv` and `tracking.csv` with the
    /// tracking log read back, or from `received.ubx` with its loop identified.
    pub estimate: Estimated,
    /// Whether every axis met the target σ.
    pub target_met: bool,
}

impl Finished {
    /// What to do when the session ended before every axis met the target
    /// σ `target_sigma_hz_per_mps2`; `None` when it met it.
    pub fn target_missed(&self, target_sigma_hz_per_mps2: f64) -> Option<String> {
        (!self.target_met).then(|| {
            format!(
                "the target σ ({target_sigma_hz_per_mps2} Hz/(m/s²)) was not met on every axis: shake longer, or \
                 lower the target\n"
            )
        })
    }
}

/// A live session running: its inputs' threads started, its files kept.
pub struct Runtime {
    session: LiveSession,
    kept: Kept,
    sources: Vec<Source>,
    /// Per line source, the parser of its lines (its tracking columns).
    parsers: Vec<Option<LineParser>>,
    events: Receiver<SourceEvent>,
    /// Per source, whether it ended.
    ended: Vec<bool>,
    /// Records of several line sources (files followed) are given in time order.
    merger: Option<Merger>,
    clock: Arc<dyn Clock>,
    /// The UBX stream's bytes as received (`received.ubx`), and its path.
    ubx_log: Option<(File, PathBuf)>,
}

/// The opening's line for a UBX stream.
const UBX_LOOP_IDENTIFIED: &str = "the receiver's loop is identified from the module's carrier phase as data arrive \
     (a stated loop narrows it to its order and update interval)\n";

/// The kept UBX log's name in the output directory.
const KEPT_UBX: &str = "received.ubx";

impl Runtime {
    /// Starts the session: its inputs opened and read by one thread each, the
    /// kept files created in `config.out_dir`.
    pub fn start(config: RuntimeConfig, clock: Arc<dyn Clock>) -> Result<Self, RuntimeError> {
        let RuntimeConfig { inputs, out_dir, mut settings, target_sigma_hz_per_mps2, batch_every_s, idle_timeout_s } =
            config;
        if let Inputs::Monitor { monitor, .. } = &inputs {
            // The run's own loop, modelled exactly.
            settings = gsens_gnss_sdr::with_gnss_sdr_loop(&settings, &monitor.import);
        }
        let mut live = LiveConfig::new(settings, target_sigma_hz_per_mps2);
        live.batch_every_s = batch_every_s;
        let session = match &inputs {
            Inputs::Ubx { log, imu, options, .. } => {
                LiveSession::with_ubx(live, &stream_name(log), *options, imu.is_none())
            }
            Inputs::UbxEvents { sources, options, .. } => {
                let name = sources.first().map_or(String::new(), |s| s.name.clone());
                LiveSession::with_ubx(live, &name, *options, sources.len() < 2)
            }
            _ => LiveSession::new(live),
        }
        .map_err(RuntimeError::Loop)?;
        let (tx, rx) = mpsc::channel();
        let line_source = |name: String, format| Source { name, format: Some(format) };
        let (sources, events) = match inputs {
            Inputs::Merged { name, reader } => {
                spawn_lines(tx.clone(), 0, reader);
                (vec![line_source(name, LineFormat::Merged)], rx)
            }
            Inputs::Files { imu, tracking } => {
                let sources = vec![
                    line_source(imu.display().to_string(), LineFormat::Imu),
                    line_source(tracking.display().to_string(), LineFormat::Tracking),
                ];
                spawn_follow(tx.clone(), 0, imu, idle_timeout_s, clock.clone());
                spawn_follow(tx.clone(), 1, tracking, idle_timeout_s, clock.clone());
                (sources, rx)
            }
            Inputs::Monitor { imu, monitor } => {
                let stream = MonitorStream::new(monitor.fs_hz, monitor.decimation);
                let wait = Duration::from_millis(RECEIVE_WAIT_MS);
                let mut receiver = MonitorReceiver::bind(monitor.addr.as_str(), stream, wait)
                    .map_err(|error| RuntimeError::Listen { addr: monitor.addr.clone(), error })?;
                let mut grid = LiveGrid::new(monitor.import.record_interval_s(), monitor.import.settle_time_s());
                let mut raw = BufWriter::new(create(&received_dir(&out_dir)?.join("monitor-datagrams.bin"))?);
                let sources = vec![
                    line_source(imu.display().to_string(), LineFormat::Imu),
                    Source { name: format!("udp {}", monitor.addr), format: None },
                ];
                spawn_follow(tx.clone(), 0, imu, idle_timeout_s, clock.clone());
                let (tx, clock) = (tx.clone(), clock.clone());
                std::thread::spawn(move || {
                    receive_monitor(&tx, 1, &mut receiver, &mut grid, &mut raw, idle_timeout_s, &*clock);
                });
                (sources, rx)
            }
            Inputs::Ubx { log, baud, imu, .. } => {
                let mut sources = vec![Source { name: stream_name(&log), format: None }];
                spawn_bytes(tx.clone(), 0, log, baud, idle_timeout_s, clock.clone());
                if let Some(imu) = imu {
                    sources.push(line_source(imu.display().to_string(), LineFormat::Imu));
                    spawn_follow(tx.clone(), 1, imu, idle_timeout_s, clock.clone());
                }
                (sources, rx)
            }
            Inputs::UbxEvents { sources, events, .. } | Inputs::Events { sources, events } => (sources, events),
        };
        drop(tx);
        let kept = Kept::create(&out_dir, &sources)?;
        let ubx_log = match session.ubx_stream() {
            Some(_) => {
                let path = out_dir.join(KEPT_UBX);
                Some((create(&path)?, path))
            }
            None => None,
        };
        let merger =
            (sources.len() > 1 && sources.iter().all(|s| s.format.is_some())).then(|| Merger::new(sources.len()));
        let parsers = sources.iter().map(|s| s.format.map(LineFormat::parser)).collect();
        Ok(Runtime {
            session,
            kept,
            ended: vec![false; sources.len()],
            sources,
            parsers,
            events,
            merger,
            clock,
            ubx_log,
        })
    }

    /// The session.
    pub fn session(&self) -> &LiveSession {
        &self.session
    }

    /// What to shake and how fast, for the start: the target, the shaking
    /// periods of the protocol, the loop's band and why.
    pub fn shaking_advice(&self) -> String {
        let band = self.session.view().band;
        let rates = match self.session.protocol() {
            Protocol::OneRate => format!("about {:.1} s per cycle", band.period_s()),
            Protocol::TwoRates => {
                let [slow, fast] = band.two_rate_periods_s();
                format!("about {slow:.1} s and {fast:.1} s per cycle, half the time each")
            }
        };
        format!(
            "target σ {} Hz/(m/s²) per axis; shake each axis at {rates} (the loop's peak {:.2} Hz, band {:.2}–{:.2} \
             Hz): {}",
            self.session.config().target_sigma_hz_per_mps2,
            band.peak_hz,
            band.band_hz[0],
            band.band_hz[1],
            self.session.protocol().why()
        )
    }

    /// The lines that open the session: the shaking advice
    /// ([`Runtime::shaking_advice`]), and the warning of settings that state
    /// no receiver loop ([`crate::LOOP_NOT_STATED`]), or for a UBX stream
    /// that its loop is identified.
    pub fn opening(&self) -> String {
        let unstated = match (self.session.ubx_stream(), self.session.config().settings.loop_stated) {
            // A UBX stream's loop is identified from the session, stated or not.
            (Some(_), _) => UBX_LOOP_IDENTIFIED,
            (None, true) => "",
            (None, false) => crate::LOOP_NOT_STATED,
        };
        format!("gsens live: {}\n{unstated}", self.shaking_advice())
    }

    /// Runs the session until every input ended, a key, or the target σ on every axis.
    pub fn run(&mut self, mut display: Display<'_>) -> Result<Ending, RuntimeError> {
        let mut plain = Plain::default();
        let mut next_plain_t_s = f64::NEG_INFINITY;
        let mut last_draw: Option<Duration> = None;
        let mut worker: Option<JoinHandle<BatchResult>> = None;
        let ending = loop {
            // Every event waiting (the first waited for), then the estimate and the screen.
            let mut ending = None;
            let mut first = Some(self.events.recv_timeout(Duration::from_millis(EVENT_WAIT_MS)));
            let mut taken = 0;
            loop {
                let event = match first.take() {
                    Some(Ok(e)) => e,
                    Some(Err(RecvTimeoutError::Timeout)) => break,
                    Some(Err(RecvTimeoutError::Disconnected)) => {
                        ending = Some(Ending::InputEnded);
                        break;
                    }
                    None => match self.events.try_recv() {
                        Ok(e) => e,
                        Err(_) => break,
                    },
                };
                let plain_out = match &mut display {
                    Display::Plain(out) => Some(&mut **out as &mut dyn Write),
                    Display::Screen(_) => None,
                };
                if let Some(e) = self.handle(event, plain_out)? {
                    ending = Some(e);
                    break;
                }
                // Plain lines follow the data's time, not the wall clock's: the
                // same input gives the same lines however fast it arrives.
                if let Display::Plain(out) = &mut display
                    && self.session.data_t_s() >= next_plain_t_s
                {
                    next_plain_t_s = self.session.data_t_s() + PLAIN_STEP_S;
                    plain.step(&mut self.session, *out)?;
                    if self.session.target_met() {
                        break;
                    }
                }
                taken += 1;
                if taken >= EVENTS_PER_ROUND {
                    break;
                }
            }
            if let Some(e) = ending {
                break e;
            }
            match &mut display {
                Display::Plain(out) => plain.step(&mut self.session, *out)?,
                Display::Screen(screen) => {
                    if worker.as_ref().is_some_and(|w| w.is_finished()) {
                        let result = worker.take().expect("a worker").join().expect("the estimate does not panic");
                        self.session.apply(result);
                        last_draw = None;
                    }
                    if worker.is_none()
                        && let Some(job) = self.session.batch_due()
                    {
                        worker = Some(std::thread::spawn(move || job.run()));
                    }
                    let due = Duration::from_millis(DRAW_EVERY_MS);
                    if last_draw.is_none_or(|t| self.clock.now().saturating_sub(t) >= due) {
                        screen.draw(&self.session.view())?;
                        last_draw = Some(self.clock.now());
                    }
                    if screen.quit_asked()? {
                        break Ending::Key;
                    }
                }
            }
            if self.session.target_met() {
                break Ending::TargetMet;
            }
        };
        Ok(ending)
    }

    /// Takes one event: a line parsed, given to the session and kept; a
    /// notice said (on `out`, the plain screen; the session keeps it for the
    /// other). Returns the ending when every source ended.
    fn handle(&mut self, event: SourceEvent, mut out: Option<&mut dyn Write>) -> Result<Option<Ending>, RuntimeError> {
        match event {
            SourceEvent::Line { source, line, text } => {
                let Some(parser) = self.parsers[source].as_mut() else { return Ok(None) };
                let parsed = parser.parse(&text);
                self.kept.line(source, &text)?;
                match parsed {
                    Ok(LineKind::Data(x)) => match self.merger.as_mut() {
                        Some(m) => {
                            m.put(source, line, x);
                            self.push_ready(&mut out)?;
                        }
                        None => self.push_line_record(source, line, x, &mut out)?,
                    },
                    Ok(LineKind::Skip) => {}
                    Err(e) => self.notice(source, line, format!("{e}: line not used"), &mut out)?,
                }
            }
            SourceEvent::Record { source, line, input } => {
                let pushed = self.session.push(&self.sources[source].name, line, input);
                if let Some(n) = &pushed.notice {
                    say(&mut out, n)?;
                }
                if pushed.used {
                    self.kept.record(&input)?;
                }
            }
            SourceEvent::Bytes { source, bytes } => {
                if let Some((file, _)) = self.ubx_log.as_mut() {
                    file.write_all(&bytes)?;
                }
                let failures = self.session.ubx_stream().map_or(0, |s| s.checksum_failures());
                for x in self.session.push_ubx(&bytes) {
                    self.push_line_record(source, 0, x, &mut out)?;
                }
                if failures == 0 && self.session.ubx_stream().is_some_and(|s| s.checksum_failures() > 0) {
                    let text = "a UBX frame with a bad checksum was dropped (the screen counts them; a serial port \
                                at the wrong baud rate drops most)";
                    self.notice(source, 0, text.into(), &mut out)?;
                }
            }
            SourceEvent::Notice { source, text } => self.notice(source, 0, text, &mut out)?,
            SourceEvent::Restarted { source } => {
                // Read again from its start: its header comes again.
                self.parsers[source] = self.sources[source].format.map(LineFormat::parser);
                let text = "the file became shorter (a logger restarted?): read again from its start";
                self.notice(source, 0, text.into(), &mut out)?;
            }
            SourceEvent::Ended { source, why } => {
                self.ended[source] = true;
                if let Some(why) = why {
                    self.notice(source, 0, why, &mut out)?;
                }
                if self.merger.is_some() {
                    self.push_ready(&mut out)?;
                }
                if self.ended.iter().all(|&e| e) {
                    return Ok(Some(Ending::InputEnded));
                }
            }
        }
        Ok(None)
    }

    /// A notice of `source` about its `line` (0: not about a line), kept by the session and said.
    fn notice(
        &mut self,
        source: usize,
        line: u64,
        message: String,
        out: &mut Option<&mut dyn Write>,
    ) -> Result<(), RuntimeError> {
        let n = Notice { source: self.sources[source].name.clone(), line, message };
        self.session.notice(&n);
        Ok(say(out, &n)?)
    }

    /// Gives the session the merged records that may go now.
    fn push_ready(&mut self, out: &mut Option<&mut dyn Write>) -> Result<(), RuntimeError> {
        let ready = self.merger.as_mut().map(|m| m.ready(&self.ended)).unwrap_or_default();
        for (source, line, x) in ready {
            self.push_line_record(source, line, x, out)?;
        }
        Ok(())
    }

    /// Gives one record of a line source to the session, and keeps it when used.
    fn push_line_record(
        &mut self,
        source: usize,
        line: u64,
        x: Input,
        out: &mut Option<&mut dyn Write>,
    ) -> Result<(), RuntimeError> {
        let pushed = self.session.push(&self.sources[source].name, line, x);
        if let Some(n) = &pushed.notice {
            say(out, n)?;
        }
        if pushed.used {
            self.kept.record(&x)?;
        }
        Ok(())
    }

    /// The final estimate: the batch estimate of the logs kept, read back
    /// as `gsens report` would read them.
    pub fn finish(self) -> Result<Finished, RuntimeError> {
        let target_met = self.session.target_met();
        if let (Some((file, ubx_path)), Some((options, esf_imu))) = (&self.ubx_log, self.session.ubx_options()) {
            file.sync_all()?;
            let (imu_path, _) = self.kept.finish()?;
            let log = ObservationFile::Ubx(ubx_path.clone(), options.settings);
            let inputs = ObservationInputs::new(log, (!esf_imu).then_some(imu_path), options.record);
            let outcome = inputs.calibrate(&self.session.config().settings)?;
            return Ok(Finished { estimate: Estimated::Observations(Box::new(outcome)), target_met });
        }
        let (imu_samples, tracking_rows) = self.session.view().received;
        if imu_samples == 0 || tracking_rows == 0 {
            return Err(RuntimeError::NothingReceived { imu_samples, tracking_rows });
        }
        let (imu_path, tracking_path) = self.kept.finish()?;
        let tracking = gsens_io::read_tracking_file(&tracking_path)?;
        let imu = gsens_io::read_imu_file(&imu_path)?;
        let imu_name = imu_path.display().to_string();
        let mut outcome = gsens_calib::calibrate_logs(&tracking, &imu, &imu_name, &self.session.config().settings)?;
        outcome.inputs = vec![("imu".into(), imu_name), ("tracking".into(), tracking_path.display().to_string())];
        let calibrated = Calibrated { outcome, conversion: Conversion::None, tracking: Some(tracking) };
        Ok(Finished { estimate: Estimated::Tracking(Box::new(calibrated)), target_met })
    }
}

/// Prints a notice on the plain screen (the terminal screen shows the session's).
fn say(out: &mut Option<&mut dyn Write>, n: &Notice) -> std::io::Result<()> {
    match out {
        Some(out) => writeln!(out, "notice: {n}"),
        None => Ok(()),
    }
}
