//! `gsens live`: calibrate while the board is shaken, telling the person
//! holding it what to do next. The inputs are read by one thread each; the
//! session (`gsens_live::LiveSession`) and the screen run here.

use crate::estimate::CalibrationArgs;
use anyhow::{Context, Result};
use clap::Args;
use gsens_live::{
    Follower, Input, Instruction, LineKind, LiveConfig, LiveSession, LiveView, Notice, parse_imu_line,
    parse_merged_line, parse_tracking_line,
};
use std::io::{BufRead, IsTerminal, LineWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::{Duration, Instant};

#[derive(Args, Debug)]
pub struct LiveArgs {
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
    /// Follow a growing imu.csv (as `tail -f`), with --follow-tracking or --gnss-sdr-monitor.
    #[arg(long)]
    pub follow_imu: Option<PathBuf>,
    /// Follow a growing tracking.csv, with --follow-imu.
    #[arg(long, requires = "follow_imu")]
    pub follow_tracking: Option<PathBuf>,
    /// With --follow-* and --gnss-sdr-monitor: end when no input has grown for this long [s]
    /// (0: only on a key or the target).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true, value_parser = crate::args::finite_non_negative)]
    pub idle_timeout_s: f64,
    /// Output directory: the records received (imu.csv, tracking.csv; every line as
    /// received in received/), and at the end the report of `gsens report`
    /// (report.html, report.json, gsens_gamma.h as `gsens report` writes it, figures/).
    #[arg(long)]
    pub out: PathBuf,
    /// End when every axis's σ is at most this [Hz/(m/s²)]; ending before (the input ended, a key,
    /// --idle-timeout-s) exits with status 4.
    #[arg(long, default_value_t = 1e-3, allow_negative_numbers = true, value_parser = crate::args::positive)]
    pub target_sigma: f64,
    /// Re-run the estimate every this many seconds of data [s].
    #[arg(long, default_value_t = 5.0, allow_negative_numbers = true, value_parser = crate::args::positive)]
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

/// The screen is redrawn at most this often [ms]: with the followers' 20 ms
/// polls a record reaches the screen within 70 ms (the budget: 100 ms).
const DRAW_EVERY_MS: u64 = 50;

/// With plain lines, the instruction and the batch estimate are looked at
/// every this many seconds of data \[s\] (a tenth of the guidance's 1 s
/// resolution; a view costs microseconds).
const PLAIN_STEP_S: f64 = 0.1;

/// What a reader thread sends.
enum Msg {
    Line {
        source: usize,
        line: u64,
        text: String,
    },
    /// A record already parsed (a monitor row on the grid), numbered by its datagram.
    Record {
        source: usize,
        line: u64,
        input: Input,
    },
    Notice {
        source: usize,
        text: String,
    },
    Restarted {
        source: usize,
    },
    Ended {
        source: usize,
        why: Option<String>,
    },
}

/// How one text line of a source parses into a record.
type LineParser = fn(&str) -> Result<LineKind, String>;

/// One input: its name and how its lines parse.
struct Source {
    name: String,
    /// How its lines parse; `None` for a source that sends records already
    /// parsed (the monitor: its thread keeps the datagrams it received).
    parse: Option<LineParser>,
}

fn spawn_stdin(tx: mpsc::Sender<Msg>, source: usize) {
    std::thread::spawn(move || {
        let stdin = std::io::stdin();
        for (i, text) in stdin.lock().lines().enumerate() {
            let line = i as u64 + 1;
            match text {
                Ok(text) => {
                    if tx.send(Msg::Line { source, line, text }).is_err() {
                        return;
                    }
                }
                Err(e) => {
                    let _ = tx.send(Msg::Ended { source, why: Some(e.to_string()) });
                    return;
                }
            }
        }
        let _ = tx.send(Msg::Ended { source, why: None });
    });
}

/// Polls `path` every 20 ms (well inside the screen's 100 ms budget).
fn spawn_follow(tx: mpsc::Sender<Msg>, source: usize, path: PathBuf, idle_timeout_s: f64) {
    std::thread::spawn(move || {
        let mut f = Follower::new(&path);
        let mut last_growth = Instant::now();
        loop {
            match f.poll() {
                Ok(p) => {
                    if p.restarted && tx.send(Msg::Restarted { source }).is_err() {
                        return;
                    }
                    if !p.lines.is_empty() {
                        last_growth = Instant::now();
                    }
                    for (line, text) in p.lines {
                        if tx.send(Msg::Line { source, line, text }).is_err() {
                            return;
                        }
                    }
                }
                Err(e) => {
                    let _ = tx.send(Msg::Ended { source, why: Some(format!("{}: {e}", path.display())) });
                    return;
                }
            }
            if idle_timeout_s > 0.0 && last_growth.elapsed().as_secs_f64() > idle_timeout_s {
                let why = format!("no new line for {idle_timeout_s} s");
                let _ = tx.send(Msg::Ended { source, why: Some(why) });
                return;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
    });
}

/// Receives GNSS-SDR's tracking monitor: every datagram kept in `raw`
/// (gsens's capture format), its rows put on the 20 ms grid as they arrive.
fn spawn_monitor(
    tx: mpsc::Sender<Msg>,
    source: usize,
    mut rx: gsens_gnss_sdr::monitor::MonitorReceiver,
    mut grid: gsens_gnss_sdr::monitor::LiveGrid,
    mut raw: std::io::BufWriter<std::fs::File>,
    idle_timeout_s: f64,
) {
    use gsens_gnss_sdr::monitor::{MonitorEvent, Received, write_capture_record};
    std::thread::spawn(move || {
        let mut last = Instant::now();
        let mut datagram = 0u64;
        loop {
            let events = match rx.recv() {
                Ok(Received::Datagram(events)) => events,
                Ok(Received::Timeout) => {
                    let _ = raw.flush();
                    if idle_timeout_s > 0.0 && last.elapsed().as_secs_f64() > idle_timeout_s {
                        break;
                    }
                    continue;
                }
                Err(e) => {
                    let _ = tx.send(Msg::Ended { source, why: Some(e.to_string()) });
                    return;
                }
            };
            last = Instant::now();
            datagram += 1;
            // GNSS-SDR's monitor re-sends its outputs many times over: a datagram that brought
            // nothing new (a repeat) is not kept, every other one is.
            if !events.is_empty() {
                let _ = write_capture_record(&mut raw, rx.last_datagram());
            }
            for e in &events {
                if let MonitorEvent::Notice(n) = e
                    && tx.send(Msg::Notice { source, text: n.to_string() }).is_err()
                {
                    return;
                }
                for row in grid.push(e) {
                    if tx.send(Msg::Record { source, line: datagram, input: Input::Tracking(row) }).is_err() {
                        return;
                    }
                }
            }
        }
        for row in grid.flush() {
            let _ = tx.send(Msg::Record { source, line: datagram, input: Input::Tracking(row) });
        }
        let _ = raw.flush();
        let why = format!("no datagram for {idle_timeout_s} s; {} rows came too late for the grid", grid.late());
        let _ = tx.send(Msg::Ended { source, why: Some(why) });
    });
}

/// The files a session keeps: every line as received, and the records used.
struct Kept {
    /// Per source, every line as received (none for a source of parsed records).
    received: Vec<Option<LineWriter<std::fs::File>>>,
    imu: gsens_io::ImuWriter<LineWriter<std::fs::File>>,
    tracking: gsens_io::TrackingWriter<LineWriter<std::fs::File>>,
}

impl Kept {
    fn create(out: &Path, sources: &[Source]) -> Result<Self> {
        let received_dir = out.join("received");
        std::fs::create_dir_all(&received_dir).with_context(|| format!("{}: cannot create", received_dir.display()))?;
        let file = |p: PathBuf| -> Result<LineWriter<std::fs::File>> {
            let f = std::fs::File::create(&p).with_context(|| format!("{}: cannot create", p.display()))?;
            Ok(LineWriter::new(f))
        };
        let received = sources
            .iter()
            .map(|s| {
                let name: String =
                    s.name.chars().map(|c| if c.is_ascii_alphanumeric() || c == '.' { c } else { '_' }).collect();
                s.parse.map(|_| file(received_dir.join(format!("{name}.txt")))).transpose()
            })
            .collect::<Result<_>>()?;
        Ok(Kept {
            received,
            imu: gsens_io::ImuWriter::new(file(out.join("imu.csv"))?)?,
            tracking: gsens_io::TrackingWriter::new(file(out.join("tracking.csv"))?)?,
        })
    }
}

/// The plain screen: a line when the instruction changes, one per batch
/// estimate (with its verdict and the codes that decide it), each warning
/// with its message the first time a batch raises it, each notice.
struct Plain {
    last: Option<(std::mem::Discriminant<Instruction>, Option<usize>)>,
    /// The warning codes already printed with their message.
    warned: Vec<gsens_live::WarningCode>,
}

impl Plain {
    /// The batch estimate when due (in line), then the instruction.
    fn step(&mut self, session: &mut LiveSession) -> Result<()> {
        if let Some(job) = session.batch_due() {
            session.apply(job.run());
            self.batch(&session.view())?;
            self.warnings(&session.view())?;
        }
        self.instruction(&session.view())
    }

    fn instruction(&mut self, v: &LiveView) -> Result<()> {
        let key = (std::mem::discriminant(&v.instruction), v.instruction.axis());
        if self.last != Some(key) {
            self.last = Some(key);
            crate::out(&format!("[{:7.2} s] {}\n", v.data_t_s.max(0.0), v.instruction))?;
        }
        Ok(())
    }

    fn warnings(&mut self, v: &LiveView) -> Result<()> {
        for w in v.batch.iter().flat_map(|b| &b.2) {
            if !self.warned.contains(&w.code) {
                self.warned.push(w.code);
                crate::out(&format!("warning [{}]: {}\n", w.code, w.message))?;
            }
        }
        Ok(())
    }

    fn batch(&self, v: &LiveView) -> Result<()> {
        let axes: Vec<String> = ["x", "y", "z"]
            .iter()
            .zip(&v.axes)
            .map(|(name, a)| match (a.gamma_hz_per_mps2, a.sigma_hz_per_mps2) {
                (Some(g), Some(s)) if a.observable => {
                    let state = if a.meets_target {
                        "met".to_string()
                    } else {
                        a.more_s.map_or(String::new(), gsens_live::guidance::more_text)
                    };
                    format!("{name} {g:+.5} ± {s:.5} {state}")
                }
                _ => format!("{name} unobservable"),
            })
            .collect();
        let trust = match (&v.batch, &v.batch_error) {
            (Some((_, true, _)), _) => "trustworthy".to_string(),
            (Some((_, false, w)), _) => format!("NOT TRUSTWORTHY ({})", gsens_calib::untrusted_codes(w).join(", ")),
            (None, Some(e)) => format!("no estimate: {e}"),
            (None, None) => String::new(),
        };
        let tracking = v.channels.iter().filter(|c| c.tracking).count();
        crate::out(&format!(
            "[{:7.2} s] Γ̂ [Hz/(m/s²)] {} | {tracking} channels | {trust}\n",
            v.data_t_s,
            axes.join(" · ")
        ))
    }
}

/// Checks that the options name one input and that the files followed exist.
fn check_inputs(args: &LiveArgs) -> Result<()> {
    let given = args.stdin
        || (args.follow_imu.is_some() && (args.follow_tracking.is_some() || args.gnss_sdr_monitor.is_some()));
    if !given {
        anyhow::bail!(
            "no input: give --stdin (the merged stream `gsens replay` writes), --follow-imu IMU.CSV with \
             --follow-tracking TRACKING.CSV (growing files), or --follow-imu IMU.CSV with --gnss-sdr-monitor ADDR \
             and --gnss-sdr-conf CONF (GNSS-SDR's tracking monitor)"
        );
    }
    for (flag, path) in [("--follow-imu", &args.follow_imu), ("--follow-tracking", &args.follow_tracking)] {
        if let Some(p) = path.as_ref().filter(|p| !p.is_file()) {
            let what = if p.exists() { "not a file" } else { "no such file (start the logger first)" };
            anyhow::bail!("{flag} {}: {what}", p.display());
        }
    }
    Ok(())
}

pub fn run(args: &LiveArgs) -> Result<crate::Status> {
    check_inputs(args)?;
    let (mut settings, loop_note) = crate::report::settings_and_loop_note(&args.calibration, args.truth.as_deref())?;
    crate::outputs::dir("--out", &args.out)?;
    let monitor_setup =
        args.gnss_sdr_conf.as_deref().map(|conf| crate::monitor::monitor_setup(Some(conf), None, None)).transpose()?;
    if let Some(setup) = &monitor_setup {
        if args.calibration.loop_args.stated() {
            anyhow::bail!("--gnss-sdr-conf states the receiver loop: leave out --order, --bn-hz and the like");
        }
        // The run's own loop, modelled exactly.
        settings = gsens_gnss_sdr::with_gnss_sdr_loop(&settings, &setup.import);
    }
    let truth = args.truth.as_deref().map(gsens_sim::read_truth_gamma).transpose()?;
    let mut config = LiveConfig::new(settings, args.target_sigma);
    config.batch_every_s = args.batch_every_s;
    let mut session = LiveSession::new(config).context("the receiver loop")?;

    let (tx, rx) = mpsc::channel();
    let mut sources = Vec::new();
    if args.stdin {
        sources.push(Source { name: "stdin".into(), parse: Some(parse_merged_line) });
        spawn_stdin(tx.clone(), 0);
    } else if let (Some(imu), Some(addr)) = (&args.follow_imu, &args.gnss_sdr_monitor) {
        sources.push(Source { name: imu.display().to_string(), parse: Some(parse_imu_line) });
        sources.push(Source { name: format!("udp {addr}"), parse: None });
        spawn_follow(tx.clone(), 0, imu.clone(), args.idle_timeout_s);
        let setup = monitor_setup.as_ref().expect("--gnss-sdr-conf comes with --gnss-sdr-monitor");
        let stream = gsens_gnss_sdr::monitor::MonitorStream::new(setup.fs_hz, setup.decimation);
        let rx = gsens_gnss_sdr::monitor::MonitorReceiver::bind(addr.as_str(), stream, Duration::from_millis(100))
            .with_context(|| format!("{addr}: cannot listen"))?;
        let grid =
            gsens_gnss_sdr::monitor::LiveGrid::new(setup.import.record_interval_s(), setup.import.settle_time_s());
        std::fs::create_dir_all(args.out.join("received"))?;
        let raw_path = args.out.join("received").join("monitor-datagrams.bin");
        let raw = std::fs::File::create(&raw_path).with_context(|| format!("{}: cannot create", raw_path.display()))?;
        spawn_monitor(tx.clone(), 1, rx, grid, std::io::BufWriter::new(raw), args.idle_timeout_s);
    } else if let (Some(imu), Some(trk)) = (&args.follow_imu, &args.follow_tracking) {
        sources.push(Source { name: imu.display().to_string(), parse: Some(parse_imu_line) });
        sources.push(Source { name: trk.display().to_string(), parse: Some(parse_tracking_line) });
        spawn_follow(tx.clone(), 0, imu.clone(), args.idle_timeout_s);
        spawn_follow(tx.clone(), 1, trk.clone(), args.idle_timeout_s);
    }
    drop(tx);
    let mut kept = Kept::create(&args.out, &sources)?;
    if let Some(note) = &loop_note {
        crate::out(&format!("{note}\n"))?;
    }
    let band = session.view().band;
    let rates = match session.protocol() {
        gsens_live::Protocol::OneRate => format!("about {:.1} s per cycle", band.period_s()),
        gsens_live::Protocol::TwoRates => {
            let [slow, fast] = band.two_rate_periods_s();
            format!("about {slow:.1} s and {fast:.1} s per cycle, half the time each")
        }
    };
    crate::out(&format!(
        "gsens live: target σ {} Hz/(m/s²) per axis; shake each axis at {rates} (the loop's peak {:.2} Hz, band \
         {:.2}–{:.2} Hz): {}\n",
        args.target_sigma,
        band.peak_hz,
        band.band_hz[0],
        band.band_hz[1],
        session.protocol().why()
    ))?;
    if !session.config().settings.loop_stated {
        crate::out(
            "warning [loop_not_stated]: no receiver loop was stated: the estimates will use the typical loop the \
             data fit best and cannot be trustworthy; state the receiver's loop (--order, --bn-hz, \
             --loop-interval-s, --logged-phase) from its settings\n",
        )?;
    }
    let mut screen = if args.plain || !std::io::stdout().is_terminal() {
        Screen::Plain(Plain { last: None, warned: Vec::new() })
    } else {
        Screen::Tui { terminal: gsens_tui::Terminal::new()?, last_draw: None, worker: None }
    };
    let mut ended = vec![false; sources.len()];
    // Records of several line sources (files followed) are given in time order.
    let mut merger =
        (sources.len() > 1 && sources.iter().all(|s| s.parse.is_some())).then(|| Merger::new(sources.len()));
    let mut next_plain_t_s = f64::NEG_INFINITY;
    let end_reason = loop {
        // Every message waiting (the first waited for up to 20 ms), then the estimate and the screen.
        let mut reason = None;
        let mut first = Some(rx.recv_timeout(Duration::from_millis(20)));
        let mut taken = 0;
        loop {
            let msg = match first.take() {
                Some(Ok(m)) => m,
                Some(Err(mpsc::RecvTimeoutError::Timeout)) => break,
                Some(Err(mpsc::RecvTimeoutError::Disconnected)) => {
                    reason = Some("the input ended".to_string());
                    break;
                }
                None => match rx.try_recv() {
                    Ok(m) => m,
                    Err(_) => break,
                },
            };
            let plain = matches!(screen, Screen::Plain(_));
            if let Some(r) = handle(msg, &mut session, &mut kept, &sources, &mut ended, plain, merger.as_mut())? {
                reason = Some(r);
                break;
            }
            // Plain lines follow the data's time, not the wall clock's: the
            // same input gives the same lines however fast it arrives.
            if let Screen::Plain(plain) = &mut screen
                && session.data_t_s() >= next_plain_t_s
            {
                next_plain_t_s = session.data_t_s() + PLAIN_STEP_S;
                plain.step(&mut session)?;
                if session.target_met() {
                    break;
                }
            }
            taken += 1;
            // Keep the screen within its 100 ms while a burst arrives.
            if taken >= 2000 {
                break;
            }
        }
        if let Some(r) = reason {
            break r;
        }
        match &mut screen {
            Screen::Plain(plain) => plain.step(&mut session)?,
            Screen::Tui { terminal, last_draw, worker } => {
                if worker.as_ref().is_some_and(|w| w.is_finished()) {
                    let result = worker.take().expect("a worker").join().expect("the estimate does not panic");
                    session.apply(result);
                    *last_draw = None;
                }
                if worker.is_none()
                    && let Some(job) = session.batch_due()
                {
                    *worker = Some(std::thread::spawn(move || job.run()));
                }
                if last_draw.is_none_or(|t| t.elapsed() >= Duration::from_millis(DRAW_EVERY_MS)) {
                    terminal.draw(&session.view())?;
                    *last_draw = Some(Instant::now());
                }
                if gsens_tui::poll_quit(Duration::ZERO)? {
                    break "stopped by a key".to_string();
                }
            }
        }
        if session.target_met() {
            break "every axis meets the target σ".to_string();
        }
    };
    drop(screen);
    crate::out(&format!("ended: {end_reason}; the final estimate on everything received:\n"))?;
    finish(session, kept, truth, args)
}

/// The screen: plain lines, or the terminal screen with the estimate re-run in a worker thread.
enum Screen {
    Plain(Plain),
    Tui {
        terminal: gsens_tui::Terminal,
        last_draw: Option<Instant>,
        worker: Option<std::thread::JoinHandle<gsens_live::BatchResult>>,
    },
}

/// Takes one message: the line parsed and pushed (and kept), a notice said
/// (printed when `plain`; the screen shows the session's). Returns why the
/// session ends, if it does.
fn handle(
    msg: Msg,
    session: &mut LiveSession,
    kept: &mut Kept,
    sources: &[Source],
    ended: &mut [bool],
    plain: bool,
    mut merger: Option<&mut Merger>,
) -> Result<Option<String>> {
    let say = |n: &Notice| if plain { crate::out(&format!("notice: {n}\n")) } else { Ok(()) };
    match msg {
        Msg::Line { source, line, text } => {
            // Only line sources send lines.
            let (Some(received), Some(parse)) = (kept.received[source].as_mut(), sources[source].parse) else {
                return Ok(None);
            };
            writeln!(received, "{text}")?;
            let name = &sources[source].name;
            match parse(&text) {
                Ok(LineKind::Data(x)) => match merger.as_deref_mut() {
                    Some(m) => {
                        m.put(source, line, x);
                        for (source, line, x) in m.ready(ended) {
                            push_line_record(session, kept, &sources[source].name, line, x, &say)?;
                        }
                    }
                    None => push_line_record(session, kept, name, line, x, &say)?,
                },
                Ok(LineKind::Skip) => {}
                Err(e) => {
                    let n = Notice { source: name.clone(), line, message: format!("{e}: line not used") };
                    session.notice(&n);
                    say(&n)?;
                }
            }
        }
        Msg::Record { source, line, input } => {
            let pushed = session.push(&sources[source].name, line, input);
            if let Some(n) = &pushed.notice {
                say(n)?;
            }
            if pushed.used
                && let Input::Tracking(r) = input
            {
                kept.tracking.write_row(&r)?;
            }
        }
        Msg::Notice { source, text } => {
            let n = Notice { source: sources[source].name.clone(), line: 0, message: text };
            session.notice(&n);
            say(&n)?;
        }
        Msg::Restarted { source } => {
            let n = Notice {
                source: sources[source].name.clone(),
                line: 0,
                message: "the file became shorter (a logger restarted?): read again from its start".into(),
            };
            session.notice(&n);
            say(&n)?;
        }
        Msg::Ended { source, why } => {
            ended[source] = true;
            if let Some(why) = why {
                let n = Notice { source: sources[source].name.clone(), line: 0, message: why };
                session.notice(&n);
                say(&n)?;
            }
            if let Some(m) = merger {
                for (source, line, x) in m.ready(ended) {
                    push_line_record(session, kept, &sources[source].name, line, x, &say)?;
                }
            }
            if ended.iter().all(|&e| e) {
                return Ok(Some("the input ended".to_string()));
            }
        }
    }
    Ok(None)
}

/// Gives one record of a line source to the session, and keeps it when used.
fn push_line_record(
    session: &mut LiveSession,
    kept: &mut Kept,
    name: &str,
    line: u64,
    x: Input,
    say: &dyn Fn(&Notice) -> Result<()>,
) -> Result<()> {
    let pushed = session.push(name, line, x);
    if let Some(n) = &pushed.notice {
        say(n)?;
    }
    if pushed.used {
        match x {
            Input::Imu { t_s, accel_mps2 } => kept.imu.write_sample(t_s, &accel_mps2)?,
            Input::Tracking(r) => kept.tracking.write_row(&r)?,
        }
    }
    Ok(())
}

/// Records of several sources put in time order. A file followed from its
/// start is read in one go, so without this the session would get all of
/// one file before the other's first line, judge the rest and the shaking on
/// a stream that is all IMU and see the tracking far behind. A record waits
/// until every other source that has not ended has read one at least as
/// late; the earliest waiting record goes first.
struct Merger {
    held: Vec<std::collections::VecDeque<(u64, Input)>>,
    /// Per source, the latest time read.
    seen_t_s: Vec<f64>,
}

impl Merger {
    fn new(sources: usize) -> Self {
        Merger { held: vec![Default::default(); sources], seen_t_s: vec![f64::NEG_INFINITY; sources] }
    }

    fn put(&mut self, source: usize, line: u64, input: Input) {
        self.seen_t_s[source] = self.seen_t_s[source].max(input.t_s());
        self.held[source].push_back((line, input));
    }

    /// The records that may go now, in time order.
    fn ready(&mut self, ended: &[bool]) -> Vec<(usize, u64, Input)> {
        let mut out = Vec::new();
        loop {
            let earliest = (0..self.held.len())
                .filter_map(|s| self.held[s].front().map(|r| (s, r.1.t_s())))
                .min_by(|a, b| a.1.total_cmp(&b.1));
            let Some((s, t)) = earliest else { break };
            let reached = (0..self.held.len()).all(|o| o == s || ended[o] || self.seen_t_s[o] >= t);
            if !reached {
                break;
            }
            let (line, input) = self.held[s].pop_front().expect("a front record");
            out.push((s, line, input));
        }
        out
    }
}

fn finish(session: LiveSession, kept: Kept, truth: Option<[f64; 3]>, args: &LiveArgs) -> Result<crate::Status> {
    let met = session.target_met();
    let (imu_n, trk_n) = session.view().received;
    if imu_n == 0 || trk_n == 0 {
        anyhow::bail!(
            "nothing to estimate from: {imu_n} IMU samples and {trk_n} tracking rows were received (the notices \
             above say why lines were not used)"
        );
    }
    drop(kept.imu.finish()?);
    drop(kept.tracking.finish()?);
    let imu_path = args.out.join("imu.csv");
    let trk_path = args.out.join("tracking.csv");
    // The final estimate is the batch estimate of the logs kept: read back, as `gsens report` would.
    let tracking = gsens_io::read_tracking_file(&trk_path)?;
    let imu = gsens_io::read_imu_file(&imu_path)?;
    let mut outcome =
        gsens_calib::calibrate_logs(&tracking, &imu, &imu_path.display().to_string(), &session.config().settings)?;
    outcome.inputs =
        vec![("imu".into(), imu_path.display().to_string()), ("tracking".into(), trk_path.display().to_string())];
    if let Some(t) = &args.truth {
        outcome.inputs.push(("truth".into(), t.display().to_string()));
    }
    let status = crate::report::write_report(&outcome, &tracking, truth, &args.out, &args.title, args.header)?;
    if !met {
        crate::out(&format!(
            "the target σ ({} Hz/(m/s²)) was not met on every axis: shake longer, or lower the target\n",
            args.target_sigma
        ))?;
        if status == crate::Status::Done {
            return Ok(crate::Status::TargetMissed);
        }
    }
    Ok(status)
}
