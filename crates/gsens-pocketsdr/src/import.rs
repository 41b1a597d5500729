//! The crate documentation's section "From `$CH` lines to tracking rows" describes this module.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::Serialize;

use gsens_core::pocket_sdr::{FLL_PULL_IN_S, PocketSdrStage};
use gsens_io::TrackingRow;

use crate::error::PocketSdrError;
use crate::log::{ChRecord, Garbled, PocketSdrLog, read_log};
use crate::options::{DEFAULT_EPOCH_S, PocketSdrOptions, Setting, SettingSource};

/// The signal gsens estimates from.
pub(crate) const L1CA: &str = "L1CA";

/// A log's conversion as a caller names it: the options file `pocket_trk`
/// ran with and the values set instead of the derived ones
/// ([`ImportSettings::settle_s`], [`ImportSettings::toff_s`]); every field
/// at its default names PocketSDR's defaults.
///
/// With the `clap` feature these are a command line's options, named with
/// the receiver before them (`pocketsdr_settle_s`) as they sit beside other
/// receivers'; the fields' doc comments are their help.
#[derive(Debug, Clone, Default, PartialEq)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
#[cfg_attr(feature = "clap", command(next_help_heading = "PocketSDR logs"))]
pub struct ImportOptions {
    /// The pocket_trk options file (-opt FILE) the log was made with: its b_pll (the PLL
    /// bandwidth) and epoch (the $CH interval) [default: PocketSDR's defaults, b_pll = 5 Hz, and
    /// the log's own interval].
    #[cfg_attr(feature = "clap", arg(id = "pocketsdr_conf", long = "pocketsdr-conf", value_name = "POCKETSDR_CONF"))]
    pub conf: Option<PathBuf>,
    /// Seconds dropped after a track's 1 s FLL pull-in [default: five time constants of the
    /// PLL's slowest mode, 5.2 s at 5 Hz].
    #[cfg_attr(
        feature = "clap",
        arg(
            id = "pocketsdr_settle_s",
            long = "pocketsdr-settle-s",
            value_name = "POCKETSDR_SETTLE_S",
            allow_negative_numbers = true
        )
    )]
    pub settle_s: Option<f64>,
    /// pocket_trk's -toff: seconds it skipped at the start of the IF file.
    #[cfg_attr(
        feature = "clap",
        arg(
            id = "pocketsdr_toff_s",
            long = "pocketsdr-toff-s",
            value_name = "POCKETSDR_TOFF_S",
            default_value_t = 0.0,
            allow_negative_numbers = true
        )
    )]
    pub toff_s: f64,
}

impl ImportOptions {
    /// The settings they name, checked ([`ImportSettings::check`]).
    pub fn settings(&self) -> Result<ImportSettings, PocketSdrError> {
        let settings = ImportSettings {
            settle_s: self.settle_s,
            toff_s: self.toff_s,
            ..ImportSettings::from_options_file(self.conf.as_deref())?
        };
        settings.check()?;
        Ok(settings)
    }

    /// Whether any option is set (they need a log to act on).
    pub fn given(&self) -> bool {
        *self != ImportOptions::default()
    }
}

/// How a log is converted.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ImportSettings {
    /// The options `pocket_trk` ran with (its defaults when no file was given).
    pub options: PocketSdrOptions,
    /// Time dropped after the FLL pull-in \[s\]; `None`: five time constants
    /// of the loop's slowest mode ([`ImportSettings::settle_time_s`]).
    pub settle_s: Option<f64>,
    /// `pocket_trk`'s `-toff`: seconds of the IF file skipped at its start \[s\].
    pub toff_s: f64,
}

impl ImportSettings {
    /// The settings for a log made with the options file `path` (PocketSDR's
    /// defaults when `None`).
    pub fn from_options_file(path: Option<&Path>) -> Result<Self, PocketSdrError> {
        let options = match path {
            Some(p) => PocketSdrOptions::read(p)?,
            None => PocketSdrOptions::default(),
        };
        Ok(ImportSettings { options, settle_s: None, toff_s: 0.0 })
    }

    /// The settings' own checks: `toff_s` and `settle_s` finite and ≥ 0.
    /// Every error is a [`PocketSdrError::Setting`] whose message begins
    /// with the field's name ([`PocketSdrError::setting`]).
    pub fn check(&self) -> Result<(), PocketSdrError> {
        if !(self.toff_s.is_finite() && self.toff_s >= 0.0) {
            return Err(PocketSdrError::Setting { name: "toff_s", value: self.toff_s, expected: "≥ 0 and finite" });
        }
        if let Some(v) = self.settle_s.filter(|v| !(v.is_finite() && *v >= 0.0)) {
            return Err(PocketSdrError::Setting { name: "settle_s", value: v, expected: "≥ 0 and finite" });
        }
        Ok(())
    }

    /// The modelled loop: GPS L1 C/A at `b_pll`.
    pub fn stage(&self) -> PocketSdrStage {
        PocketSdrStage::l1ca(self.options.b_pll_hz.value)
    }

    /// The settling time after the FLL pull-in \[s\]: [`ImportSettings::settle_s`],
    /// or five time constants τ = T/(−ln ρ) of the loop's slowest mode (ρ the
    /// largest root modulus of its characteristic polynomial): 5.2 s at
    /// b_pll = 5 Hz, 2.6 s at 10 Hz, at least 1 s.
    pub fn settle_time_s(&self) -> f64 {
        self.settle_s.unwrap_or_else(|| self.stage().settling_time_s(5.0).clamp(1.0, 60.0))
    }
}

/// What became of one track.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TrackSummary {
    /// Receiver channel.
    pub channel: u32,
    /// PRN.
    pub prn: u32,
    /// Satellite ID.
    pub sat: String,
    /// Signal ID.
    pub sig: String,
    /// Lines of its first and last `$CH` line.
    pub lines: [u64; 2],
    /// Receiver times of its first and last line \[s\].
    pub time_s: [f64; 2],
    /// Lock time at its first line \[s\].
    pub first_lock_s: f64,
    /// Its `$CH` lines.
    pub records: usize,
    /// Rows kept.
    pub kept: usize,
    /// Mean C/N0 of its lines \[dB-Hz\].
    pub mean_cn0_dbhz: f64,
    /// Whether any row is kept.
    pub used: bool,
    /// Why it ends and why rows were dropped or kept.
    pub reason: String,
}

/// A converted log.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Imported {
    /// The log.
    pub file: String,
    /// `pocket_trk`'s version, from the log's START message.
    pub version: Option<String>,
    /// Sampling rate from the START message \[Hz\].
    pub fs_hz: Option<f64>,
    /// The kept rows, by time then channel.
    #[serde(skip)]
    pub rows: Vec<TrackingRow>,
    /// Each row's NCO record `[nco_phase_cycles, nco_freq_hz]`: `adr` and
    /// `dop` of its line (`adr` at the end of the line's block, `dop` the
    /// Doppler it was mixed with).
    #[serde(skip)]
    pub nco: Vec<[f64; 2]>,
    /// Every GPS L1 C/A track.
    pub tracks: Vec<TrackSummary>,
    /// The log interval (`epoch`) and where it comes from.
    pub epoch: Setting,
    /// The modelled loop.
    pub stage: PocketSdrStage,
    /// The settling time used \[s\].
    pub settle_s: f64,
    /// Lines per message type.
    pub messages: BTreeMap<String, u64>,
    /// `$CH` lines of signals not estimated, per signal.
    pub other_signals: BTreeMap<String, u64>,
    /// The first garbled lines (the log's, and lines repeated or off the epoch grid).
    pub garbled: Vec<Garbled>,
    /// All garbled lines.
    pub garbled_count: u64,
    /// The conversion settings.
    pub settings: ImportSettings,
}

impl Imported {
    /// The log interval \[s\].
    pub fn interval_s(&self) -> f64 {
        self.epoch.value
    }
}

/// Reads and converts a log file.
pub fn import_file(path: &Path, settings: &ImportSettings) -> Result<Imported, PocketSdrError> {
    import_log(read_log(path)?, settings)
}

fn ms(t_s: f64) -> i64 {
    (t_s * 1e3).round() as i64
}

/// Converts a parsed log (module docs): the GPS L1 C/A lines, the log
/// interval and the epoch grid they are on, each channel's lines split into
/// tracks, and the rows of the tracks' settled lines.
pub fn import_log(log: PocketSdrLog, settings: &ImportSettings) -> Result<Imported, PocketSdrError> {
    settings.check()?;
    let stage = settings.stage();
    let PocketSdrLog { file, records, messages, garbled, garbled_count, fs_hz, version, .. } = log;
    let mut garbled = GarbledLines { kept: garbled, count: garbled_count };
    let (l1, other_signals) = split_signals(records);
    if l1.is_empty() {
        let signals = other_signals.iter().map(|(s, n)| format!("{s} ({n})")).collect::<Vec<_>>().join(", ");
        return Err(PocketSdrError::NoL1ca { file, signals });
    }
    let epoch = log_interval(&l1, settings.options.epoch_s.as_ref(), &file)?;
    let grid = EpochGrid::of(&l1, epoch.value);
    let settle_s = settings.settle_time_s();
    let conversion = Conversion {
        keep_after_s: FLL_PULL_IN_S + settle_s,
        settle_s,
        t_block_s: stage.interval_s,
        toff_s: settings.toff_s,
    };
    let mut tracker = Tracker { grid, conversion, open: BTreeMap::new(), done: Vec::new(), rows: Vec::new() };
    for r in &l1 {
        tracker.take(r, &mut garbled);
    }
    let (tracks, rows, nco) = tracker.finish();
    if rows.is_empty() {
        let why = tracks.iter().map(|s| format!("ch {} PRN {}: {}", s.channel, s.prn, s.reason)).collect::<Vec<_>>();
        return Err(PocketSdrError::NoTracks { file, settle_s, why: why.join("; ") });
    }
    Ok(Imported {
        file,
        version,
        fs_hz,
        rows,
        nco,
        tracks,
        epoch,
        stage,
        settle_s,
        messages,
        other_signals,
        garbled: garbled.kept,
        garbled_count: garbled.count,
        settings: settings.clone(),
    })
}

/// The log's garbled lines: the first [`crate::log::GARBLED_KEPT`], and how many.
struct GarbledLines {
    kept: Vec<Garbled>,
    count: u64,
}

impl GarbledLines {
    fn push(&mut self, g: Garbled) {
        self.count += 1;
        if self.kept.len() < crate::log::GARBLED_KEPT {
            self.kept.push(g);
        }
    }
}

/// The GPS L1 C/A lines, in log order, and the count of every other signal's.
fn split_signals(records: Vec<ChRecord>) -> (Vec<ChRecord>, BTreeMap<String, u64>) {
    let mut other_signals: BTreeMap<String, u64> = BTreeMap::new();
    let mut l1: Vec<ChRecord> = Vec::new();
    for r in records {
        if r.sig == L1CA {
            l1.push(r);
        } else {
            *other_signals.entry(r.sig.clone()).or_default() += 1;
        }
    }
    (l1, other_signals)
}

/// The log interval: the most common step between a channel's consecutive
/// lines (ties: the shorter), which must be the `stated` one if the options
/// state one; without lines two apart, the stated one or PocketSDR's default.
fn log_interval(l1: &[ChRecord], stated: Option<&Setting>, file: &str) -> Result<Setting, PocketSdrError> {
    let mut last_by_ch: BTreeMap<u32, (i64, u64)> = BTreeMap::new();
    let mut steps: BTreeMap<i64, (u64, u64, u64)> = BTreeMap::new();
    for r in l1 {
        let t = ms(r.time_s);
        if let Some((t0, line0)) = last_by_ch.insert(r.ch, (t, r.line))
            && t > t0
        {
            steps.entry(t - t0).or_insert((0, line0, r.line)).0 += 1;
        }
    }
    let measured = steps.iter().max_by_key(|(d, (n, _, _))| (*n, -**d)).map(|(d, (_, a, b))| (*d, *a, *b));
    Ok(match (stated, measured) {
        (Some(stated), Some((d, a, b))) => {
            if ms(stated.value) != d {
                return Err(PocketSdrError::EpochMismatch {
                    file: file.to_owned(),
                    measured_s: d as f64 * 1e-3,
                    line_a: a,
                    line_b: b,
                    stated_s: stated.value,
                    source_name: match &stated.source {
                        SettingSource::File { file, line } => format!("{file}:{line}"),
                        _ => "the options".into(),
                    },
                });
            }
            stated.clone()
        }
        (Some(stated), None) => stated.clone(),
        (None, Some((d, _, _))) => Setting { value: d as f64 * 1e-3, source: SettingSource::Log },
        (None, None) => Setting { value: DEFAULT_EPOCH_S, source: SettingSource::Default },
    })
}

/// The epoch grid of most lines: the log interval in whole milliseconds
/// (at least 1) and the grid's phase, the most common time modulo it (ties:
/// the smaller).
#[derive(Debug, Clone, Copy, PartialEq)]
struct EpochGrid {
    epoch_s: f64,
    step_ms: i64,
    phase_ms: i64,
}

impl EpochGrid {
    fn of(l1: &[ChRecord], epoch_s: f64) -> Self {
        let step_ms = ms(epoch_s).max(1);
        let mut phases: BTreeMap<i64, u64> = BTreeMap::new();
        for r in l1 {
            *phases.entry(ms(r.time_s).rem_euclid(step_ms)).or_default() += 1;
        }
        let phase_ms = phases.iter().max_by_key(|(p, n)| (**n, -**p)).map_or(0, |(p, _)| *p);
        EpochGrid { epoch_s, step_ms, phase_ms }
    }

    /// Whether a line at `t_ms` lies on the grid.
    fn holds(&self, t_ms: i64) -> bool {
        t_ms.rem_euclid(self.step_ms) == self.phase_ms
    }
}

/// How a settled line becomes a row: the lock time it must exceed, the
/// loop's update interval, the IF file's `toff`.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Conversion {
    /// The FLL pull-in plus the PLL's settling \[s\].
    keep_after_s: f64,
    /// The settling time \[s\].
    settle_s: f64,
    /// The loop's update interval T \[s\].
    t_block_s: f64,
    /// `-toff` \[s\].
    toff_s: f64,
}

impl Conversion {
    /// Whether a line with lock time `lock_s` is kept.
    fn keeps(&self, lock_s: f64) -> bool {
        lock_s > self.keep_after_s + 1e-9
    }

    /// The row of line `r` at `t_ms`: stamped at the middle of its
    /// integration on the file's sample time, `time + T/2 + toff`, its phase
    /// 2π·`err_phas`.
    fn row(&self, r: &ChRecord, t_ms: i64) -> TrackingRow {
        TrackingRow {
            t_s: (t_ms as f64 + 500.0 * self.t_block_s) * 1e-3 + self.toff_s,
            channel: r.ch,
            prn: r.prn,
            cn0_dbhz: r.cn0_dbhz,
            elev_deg: None,
            phase_err_rad: core::f64::consts::TAU * r.err_phas_cyc,
        }
    }

    /// The NCO record of line `r`: `[adr, dop]`. `pocket_trk` advances
    /// `adr` by `dop`·T as it processes a block, so the line's `adr` is at the
    /// end of its block and `dop` the Doppler the block was mixed with; the
    /// replica's phase is 2π(f_IF·t + `adr`), the IF's ramp the same on every
    /// channel (taken out with each satellite's Doppler). The sign is the
    /// tracking log's: φ = θ_signal − θ_replica (the module documentation,
    /// "Phase and sign").
    fn nco(r: &ChRecord) -> [f64; 2] {
        [r.adr_cyc, r.dop_hz]
    }
}

/// A track being followed: its summary so far and what the next line must continue.
struct Open {
    summary: TrackSummary,
    last_t_ms: i64,
    last_lock_s: f64,
    cn0_sum: f64,
}

/// The channels' lines split into tracks, line by line.
struct Tracker {
    grid: EpochGrid,
    conversion: Conversion,
    /// The track each channel is on.
    open: BTreeMap<u32, Open>,
    done: Vec<TrackSummary>,
    rows: Vec<(TrackingRow, [f64; 2])>,
}

impl Tracker {
    /// Takes the next line: off the grid, or repeated or back in time on its
    /// channel, it is garbled; else it ends its channel's track when that
    /// changes satellite, was reacquired or has a gap, and continues (or
    /// begins) one, with a row when settled.
    fn take(&mut self, r: &ChRecord, garbled: &mut GarbledLines) {
        let t = ms(r.time_s);
        if !self.grid.holds(t) {
            garbled.push(Garbled {
                line: r.line,
                field: Some((1, "time")),
                reason: format!(
                    "{:.3} s is off the {} s epoch grid of most lines (pocket_trk moves its $CH epochs to its PVT \
                     epochs, multiples of 20 ms, once it has decoded the navigation data; an epoch dividing 0.02 s \
                     keeps one grid)",
                    r.time_s, self.grid.epoch_s
                ),
            });
            return;
        }
        if let Some(o) = self.open.get(&r.ch) {
            if t <= o.last_t_ms {
                garbled.push(Garbled {
                    line: r.line,
                    field: Some((1, "time")),
                    reason: format!(
                        "channel {} at {:.3} s again or back in time (its previous line was at {:.3} s)",
                        r.ch,
                        r.time_s,
                        o.last_t_ms as f64 * 1e-3
                    ),
                });
                return;
            }
            if let Some(why) = track_break(o, r, t, self.grid.step_ms) {
                let o = self.open.remove(&r.ch).expect("open track");
                self.close(o, &why);
            }
        }
        let o = self.open.entry(r.ch).or_insert_with(|| open(r, t));
        o.summary.records += 1;
        o.summary.lines[1] = r.line;
        o.summary.time_s[1] = r.time_s;
        o.last_t_ms = t;
        o.last_lock_s = r.lock_s;
        o.cn0_sum += r.cn0_dbhz;
        if self.conversion.keeps(r.lock_s) {
            o.summary.kept += 1;
            self.rows.push((self.conversion.row(r, t), Conversion::nco(r)));
        }
    }

    /// Ends a track for reason `why`: its mean C/N0, whether used, and why.
    fn close(&mut self, o: Open, why: &str) {
        let settle_s = self.conversion.settle_s;
        let mut s = o.summary;
        s.mean_cn0_dbhz = o.cn0_sum / s.records as f64;
        s.used = s.kept > 0;
        let span = s.time_s[1] - s.time_s[0];
        s.reason = if s.used {
            format!(
                "{why}; {} of {} lines kept (lock time over the 1 s FLL pull-in + {settle_s:.1} s settling)",
                s.kept, s.records
            )
        } else {
            format!(
                "{why}; dropped: its lock time never passed the 1 s FLL pull-in + {settle_s:.1} s settling \
                 ({span:.2} s tracked)"
            )
        };
        self.done.push(s);
    }

    /// Ends the tracks still open; every track by its first line, the rows by time then channel.
    fn finish(mut self) -> (Vec<TrackSummary>, Vec<TrackingRow>, Vec<[f64; 2]>) {
        for (_, o) in std::mem::take(&mut self.open) {
            self.close(o, "tracked to the end of the log");
        }
        let (mut done, mut rows) = (self.done, self.rows);
        done.sort_by(|a, b| (a.lines[0]).cmp(&b.lines[0]));
        rows.sort_by(|(a, _), (b, _)| a.t_s.total_cmp(&b.t_s).then(a.channel.cmp(&b.channel)));
        let (rows, nco) = rows.into_iter().unzip();
        (done, rows, nco)
    }
}

/// Why line `r` at `t_ms` does not continue the open track `o` (lines
/// `step_ms` apart): another satellite or signal, a lock time that fell
/// (lost and reacquired), or a gap over 1.5 epochs; `None` when it does.
fn track_break(o: &Open, r: &ChRecord, t_ms: i64, step_ms: i64) -> Option<String> {
    if o.summary.prn != r.prn || o.summary.sig != r.sig {
        Some(format!("the channel turned to {} PRN {} at line {}", r.sig, r.prn, r.line))
    } else if r.lock_s + 1e-9 < o.last_lock_s {
        Some(format!("lost and reacquired (lock time {} s at line {}, after {} s)", r.lock_s, r.line, o.last_lock_s))
    } else if t_ms - o.last_t_ms > step_ms + step_ms / 2 {
        Some(format!(
            "no line from {:.3} s to {:.3} s (line {}): not tracked between",
            o.last_t_ms as f64 * 1e-3,
            r.time_s,
            r.line
        ))
    } else {
        None
    }
}

/// A track begun by line `r` at `t_ms`, with no line counted yet.
fn open(r: &ChRecord, t_ms: i64) -> Open {
    Open {
        summary: TrackSummary {
            channel: r.ch,
            prn: r.prn,
            sat: r.sat.clone(),
            sig: r.sig.clone(),
            lines: [r.line, r.line],
            time_s: [r.time_s, r.time_s],
            first_lock_s: r.lock_s,
            records: 0,
            kept: 0,
            mean_cn0_dbhz: 0.0,
            used: false,
            reason: String::new(),
        },
        last_t_ms: t_ms,
        last_lock_s: r.lock_s,
        cn0_sum: 0.0,
    }
}

/// What the conversion did, as text: the loop, the interval, every track,
/// the skipped signals and the garbled lines.
pub fn render_summary(imported: &Imported) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let used = imported.tracks.iter().filter(|t| t.used).count();
    let _ = writeln!(
        s,
        "PocketSDR log {} ({}): {} GPS L1 C/A tracks, {} used; $CH every {}; PLL b_pll {}",
        imported.file,
        imported.version.as_deref().map_or("version unknown".to_string(), |v| format!("pocket_trk {v}")),
        imported.tracks.len(),
        used,
        imported.epoch.with_unit("s"),
        imported.settings.options.b_pll_hz.with_unit("Hz")
    );
    for t in &imported.tracks {
        let _ = writeln!(
            s,
            "  ch {:>2} {} PRN {:>2}  lines {}–{}  {:.3}–{:.3} s  {:.1} dB-Hz  {}: {}",
            t.channel,
            t.sig,
            t.prn,
            t.lines[0],
            t.lines[1],
            t.time_s[0],
            t.time_s[1],
            t.mean_cn0_dbhz,
            if t.used { "used" } else { "not used" },
            t.reason
        );
    }
    for (sig, n) in &imported.other_signals {
        let _ = writeln!(s, "  {sig}: {n} $CH lines skipped (only GPS L1 C/A is estimated)");
    }
    if imported.garbled_count > 0 {
        let _ = writeln!(s, "  {} garbled lines skipped, e.g.:", imported.garbled_count);
        for g in imported.garbled.iter().take(5) {
            let _ = writeln!(s, "    {}: {g}", imported.file);
        }
    }
    for (line, what) in &imported.settings.options.ignored {
        let file = imported.settings.options.file.as_deref().unwrap_or("options");
        let _ = writeln!(s, "  {file}:{line}: {what}");
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The options name the settings (PocketSDR's defaults when none is
    /// given), are checked as the settings are, and are given when any
    /// differs from its default.
    #[test]
    fn options_name_their_settings_and_say_when_any_is_given() {
        let none = ImportOptions::default();
        assert!(!none.given());
        assert_eq!(none.settings().unwrap(), ImportSettings::from_options_file(None).unwrap());
        let set = ImportOptions { settle_s: Some(2.0), toff_s: 0.5, ..ImportOptions::default() };
        assert!(set.given() && ImportOptions { toff_s: f64::NAN, ..none.clone() }.given());
        let s = set.settings().unwrap();
        assert_eq!((s.settle_s, s.toff_s), (Some(2.0), 0.5));
        let e = ImportOptions { toff_s: -1.0, ..none }.settings().unwrap_err();
        assert_eq!((e.to_string().as_str(), e.setting()), ("toff_s must be ≥ 0 and finite, got -1", Some("toff_s")));
    }

    /// A settling time or `-toff` below 0 (or not finite) is refused, the
    /// message beginning with the field's name.
    #[test]
    fn settings_out_of_range_are_refused_by_name() {
        let ok = ImportSettings::from_options_file(None).unwrap();
        assert!(ok.check().is_ok());
        let e = ImportSettings { settle_s: Some(-2.0), ..ok.clone() }.check().unwrap_err();
        assert_eq!(
            (e.to_string().as_str(), e.setting()),
            ("settle_s must be ≥ 0 and finite, got -2", Some("settle_s"))
        );
        let e = ImportSettings { toff_s: f64::NAN, ..ok }.check().unwrap_err();
        assert_eq!((e.to_string().as_str(), e.setting()), ("toff_s must be ≥ 0 and finite, got NaN", Some("toff_s")));
    }
}
