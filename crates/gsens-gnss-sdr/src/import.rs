//! The crate documentation's section "From dumps to tracking rows" describes this module.

use std::path::Path;

use serde::Serialize;

use gsens_core::gnss_sdr::{BIT_SYMBOLS, GnssSdrPll, GnssSdrStage};
use gsens_core::units::Decimal;
use gsens_io::TrackingRow;
use std::fmt::Write as _;

use crate::conf::TrackingConf;
use crate::dump::{DumpLayout, TrackingDump, TrackingRecord, find_dumps, read_dump};
use crate::error::GnssSdrError;
use crate::nco::{BLOCK_S, NcoBookkeeping, NcoRecord, replica_mid_cycles};

/// What a caller sets instead of a configuration's lock detector and of
/// the derived conversion settings ([`ImportSettings::override_with`]);
/// `None` keeps the configuration's or the derived value.
///
/// With the `clap` feature these are a command line's options, named with
/// the receiver before them (`gnss_sdr_min_cn0_dbhz`) as they sit beside
/// other receivers'; the fields' doc comments are their help, where a unit
/// reads `[dB-Hz]`, not a link.
#[derive(Debug, Clone, Default, PartialEq)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
#[cfg_attr(feature = "clap", command(next_help_heading = "GNSS-SDR dumps"))]
#[allow(rustdoc::broken_intra_doc_links)]
pub struct ImportOverrides {
    /// C/N0 threshold of GNSS-SDR's lock detector (Tracking_1C.cn0_min) [dB-Hz]: a record below
    /// it counts as a code-lock failure [default: the conf's cn0_min, GNSS-SDR's 25 when absent].
    #[cfg_attr(
        feature = "clap",
        arg(
            id = "gnss_sdr_min_cn0_dbhz",
            long = "gnss-sdr-min-cn0-dbhz",
            value_name = "GNSS_SDR_MIN_CN0_DBHZ",
            allow_negative_numbers = true
        )
    )]
    pub min_cn0_dbhz: Option<f64>,
    /// Carrier lock test threshold of GNSS-SDR's lock detector (Tracking_1C.carrier_lock_th): a
    /// record below it counts as a carrier-lock failure [default: the conf's carrier_lock_th,
    /// GNSS-SDR's 0.7 when absent].
    #[cfg_attr(
        feature = "clap",
        arg(
            id = "gnss_sdr_min_lock_test",
            long = "gnss-sdr-min-lock-test",
            value_name = "GNSS_SDR_MIN_LOCK_TEST",
            allow_negative_numbers = true
        )
    )]
    pub min_lock_test: Option<f64>,
    /// Carrier-lock failures (net of passes) after which GNSS-SDR's lock detector declares a loss
    /// of lock (Tracking_1C.max_carrier_lock_fail) [default: the conf's, GNSS-SDR's 5000 when absent].
    #[cfg_attr(
        feature = "clap",
        arg(
            id = "gnss_sdr_max_carrier_lock_fail",
            long = "gnss-sdr-max-carrier-lock-fail",
            value_name = "GNSS_SDR_MAX_CARRIER_LOCK_FAIL"
        )
    )]
    pub max_carrier_lock_fail: Option<u32>,
    /// Code-lock (C/N0) failures (net of passes) after which GNSS-SDR's lock detector declares a
    /// loss of lock (Tracking_1C.max_lock_fail) [default: the conf's, GNSS-SDR's 50 when absent].
    #[cfg_attr(
        feature = "clap",
        arg(id = "gnss_sdr_max_lock_fail", long = "gnss-sdr-max-lock-fail", value_name = "GNSS_SDR_MAX_LOCK_FAIL")
    )]
    pub max_lock_fail: Option<u32>,
    /// Seconds dropped after a channel switches to the narrow loop (default: derived from the
    /// narrow loop's slowest mode).
    #[cfg_attr(
        feature = "clap",
        arg(
            id = "gnss_sdr_settle_s",
            long = "gnss-sdr-settle-s",
            value_name = "GNSS_SDR_SETTLE_S",
            allow_negative_numbers = true
        )
    )]
    pub settle_s: Option<f64>,
    /// Record layout of the dumps: a known one's name (gnss-sdr-0.0.17, gnss-sdr-0.0.21,
    /// gnss-sdr-kf-cc, gnss-sdr-legacy-88) to force it, or `name:type,...` for versions the
    /// reader does not know (default: recognised from each file).
    #[cfg_attr(
        feature = "clap",
        arg(id = "gnss_sdr_layout", long = "gnss-sdr-layout", value_name = "GNSS_SDR_LAYOUT")
    )]
    pub layout: Option<String>,
}

/// How dumps are converted.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ImportSettings {
    /// Sampling rate of the tracking \[Hz\].
    pub fs_hz: f64,
    /// The tracking configuration that produced the dumps; its
    /// [`TrackingConf::lock`] is the lock detector whose rule judges every
    /// track (options that override a value are marked so in it).
    pub tracking: TrackingConf,
    /// Time dropped after the switch to the modelled stage \[s\]; `None`:
    /// derived from the modelled loop ([`ImportSettings::settle_time_s`]).
    pub settle_s: Option<f64>,
    /// The dumps' record layout; `None`: detect it.
    #[serde(skip)]
    pub layout: Option<DumpLayout>,
}

impl ImportSettings {
    /// The settings for `tracking` at `fs_hz`: tracks judged by its lock
    /// detector, the settling time derived from its narrow loop.
    pub fn new(fs_hz: f64, tracking: TrackingConf) -> Self {
        ImportSettings { fs_hz, tracking, settle_s: None, layout: None }
    }

    /// The settings for dumps made with the configuration file `conf`
    /// (GNSS-SDR's defaults when `None`), at the sampling rate `fs_hz` or,
    /// when `None`, the configuration's.
    pub fn from_conf(conf: Option<&Path>, fs_hz: Option<f64>) -> Result<Self, GnssSdrError> {
        let tracking = match conf {
            Some(p) => crate::GnssSdrConf::read(p)?.tracking()?,
            None => TrackingConf::defaults(),
        };
        let fs_hz = fs_hz.or(tracking.fs_hz).ok_or(GnssSdrError::UnknownSamplingRate)?;
        if !(fs_hz.is_finite() && fs_hz > 0.0) {
            return Err(GnssSdrError::Setting { name: "the sampling rate", value: fs_hz, expected: "positive" });
        }
        Ok(ImportSettings::new(fs_hz, tracking))
    }

    /// [`ImportSettings::from_conf`] with the values `overrides` gives in
    /// place of the configuration's ([`ImportSettings::override_with`]): the
    /// conversion as a caller names it.
    pub fn from_conf_with(
        conf: Option<&Path>,
        fs_hz: Option<f64>,
        overrides: &ImportOverrides,
    ) -> Result<Self, GnssSdrError> {
        let mut settings = ImportSettings::from_conf(conf, fs_hz)?;
        settings.override_with(overrides)?;
        Ok(settings)
    }

    /// Overrides the configuration's lock detector, the settling time and
    /// the record layout with the values `overrides` gives, each checked
    /// first. Every error names the override: a
    /// [`GnssSdrError::Setting`] or [`GnssSdrError::Layout`] whose message
    /// begins with the name of the [`ImportOverrides`] field
    /// ([`GnssSdrError::setting`]).
    pub fn override_with(&mut self, overrides: &ImportOverrides) -> Result<(), GnssSdrError> {
        let o = overrides;
        let setting = |name, value, expected| GnssSdrError::Setting { name, value, expected };
        if let Some(v) = o.settle_s.filter(|v| !(*v >= 0.0 && v.is_finite())) {
            return Err(setting("settle_s", v, "≥ 0 and finite"));
        }
        if let Some(v) = o.min_cn0_dbhz.filter(|v| !v.is_finite()) {
            return Err(setting("min_cn0_dbhz", v, "finite"));
        }
        // The lock test is cos 2φ: a threshold outside [-1, 1] passes or fails every record.
        if let Some(v) = o.min_lock_test.filter(|v| !(-1.0..=1.0).contains(v)) {
            return Err(setting("min_lock_test", v, "in [-1, 1] (the lock test is cos 2φ)"));
        }
        let layout = o.layout.as_deref().map(DumpLayout::parse_spec).transpose().map_err(GnssSdrError::Layout)?;
        let lock = &mut self.tracking.lock;
        if let Some(v) = o.min_cn0_dbhz {
            lock.cn0_min_dbhz.set_option(v);
        }
        if let Some(v) = o.min_lock_test {
            lock.carrier_lock_th.set_option(v);
        }
        if let Some(v) = o.max_carrier_lock_fail {
            lock.max_carrier_lock_fail.set_option(v);
        }
        if let Some(v) = o.max_lock_fail {
            lock.max_lock_fail.set_option(v);
        }
        self.settle_s = o.settle_s;
        if layout.is_some() {
            self.layout = layout;
        }
        Ok(())
    }

    /// The integration time of the modelled stage, its loop's update interval \[s\].
    pub fn interval_s(&self) -> f64 {
        self.tracking.narrow_interval_s()
    }

    /// The spacing of the modelled stage's records \[s\]: one per 20 ms data
    /// bit after bit synchronization, whatever `extend_correlation_symbols`
    /// ([`GnssSdrStage::record_interval_s`]), each holding the last of its
    /// 20/N loop updates ([`GnssSdrStage::updates_per_record`]).
    pub fn record_interval_s(&self) -> f64 {
        self.stage().record_interval_s()
    }

    /// The modelled stage of GNSS-SDR's loop (after bit synchronization).
    pub fn stage(&self) -> GnssSdrStage {
        let t = &self.tracking;
        GnssSdrStage { order: t.pll_filter_order, bw_hz: t.narrow_bw_hz(), symbols: t.extend_correlation_symbols }
    }

    /// The settling time in use \[s\]: [`ImportSettings::settle_s`], or five
    /// time constants τ of the modelled loop's slowest mode, at least 1 s
    /// (τ = T/(−ln|λ|max) over the eigenvalues λ of its one-record
    /// transition, [`GnssSdrPll::settling_time_s`]). The switch to the narrow
    /// loop starts a transient the regressors do not model: measured on
    /// GNSS-SDR's dumps of a board shaken through the switch, the residual
    /// against the exact narrow-loop model is 0.5 rad RMS in the first 2 s
    /// (3rd order) and back at the thermal level 5τ after the switch (12.6 s for
    /// the lightly damped 3rd-order 3 Hz loop, 1.15 s for the 2nd-order one).
    pub fn settle_time_s(&self) -> f64 {
        self.settle_s.unwrap_or_else(|| match GnssSdrPll::new(self.stage()) {
            Ok(p) => p.settling_time_s(5.0).clamp(1.0, 60.0),
            Err(_) => 2.0,
        })
    }
}

/// One converted record.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ImportedRow {
    /// Middle of the integration \[s\].
    pub t_s: f64,
    /// Channel (from the dump's file name).
    pub channel: u32,
    /// PRN.
    pub prn: u32,
    /// C/N0 \[dB-Hz\].
    pub cn0_dbhz: f64,
    /// Phase error θ_signal − θ_replica \[rad\].
    pub phase_err_rad: f64,
    /// Carrier lock test.
    pub lock_test: f64,
    /// Integration length \[ms\].
    pub symbols: u32,
    /// Index of the track in [`Imported::tracks`].
    pub track: usize,
    /// The phase the loop was fed at the middle of the integration,
    /// θ_in = θ_NCO + φ \[rad\] (the replica's phase booked as GNSS-SDR books
    /// its NCO: from the commands where every update has its record, from the
    /// accumulator where not; `None` for rows not from dumps).
    #[serde(skip)]
    pub input_phase_rad: Option<f64>,
}

impl ImportedRow {
    /// The record as a row of `tracking.csv` (elevation unknown).
    pub fn tracking_row(&self) -> gsens_io::TrackingRow {
        gsens_io::TrackingRow {
            t_s: self.t_s,
            channel: self.channel,
            prn: self.prn,
            cn0_dbhz: self.cn0_dbhz,
            elev_deg: None,
            phase_err_rad: self.phase_err_rad,
        }
    }
}

/// GNSS-SDR's loss-of-lock rule replayed over one track's records
/// (`replay_lock_detector`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LockReplay {
    /// Records judged (from the end of the pull-in transitory and the C/N0 buffer's filling on).
    pub judged_records: usize,
    /// Of those, records whose carrier lock test is below `carrier_lock_th`.
    pub carrier_lock_failures: usize,
    /// Of those, records whose C/N0 is below `cn0_min`.
    pub code_lock_failures: usize,
    /// Highest value the carrier-lock fail counter reached (before a loss of lock).
    pub carrier_fail_counter_max: u32,
    /// Highest value the code-lock (C/N0) fail counter reached (before a loss of lock).
    pub code_fail_counter_max: u32,
    /// Index (within the track) of the record at which GNSS-SDR declares the
    /// loss of lock: it and every later record are not tracking.
    pub loss_of_lock: Option<usize>,
    /// Which counter exceeded its maximum: `"carrier"`, `"code"` (both: `"carrier"`).
    pub loss_by: Option<&'static str>,
}

/// Replays GNSS-SDR's tracking lock detector over a track's records (read in
/// `dll_pll_veml_tracking.cc`, 0.0.17 and 0.0.20, `cn0_and_tracking_lock_status`;
/// the implementation here is ours). Each record is one call of the detector,
/// made before the record is logged, with the values the record holds (the
/// smoothed lock test and C/N0, so the dump alone decides):
///
/// ```text
/// carrier fail counter += 1 if lock_test < carrier_lock_th, else −= 1 (not below 0)
/// code fail counter    += 1 if C/N0 < cn0_min,             else −= 1 (not below 0)
/// loss of lock when carrier counter > max_carrier_lock_fail or code counter > max_lock_fail
/// ```
///
/// The counters start at 0 with the track and count nothing during the
/// pull-in transitory, which lasts until a whole number of seconds since
/// acquisition, floor(Δn/fs), exceeds `pull_in_time_s` (the track's first
/// record stands in for acquisition, which came a little earlier: the
/// transitory may be taken to end a little late, never early), nor while the
/// first `cn0_samples` records fill the C/N0 estimator's buffer. At a loss of
/// lock GNSS-SDR drops the channel without logging the record: the record at
/// which the replay declares it and every later one are not tracking (a
/// GNSS-SDR dump made with these settings holds none; a replay that finds one
/// was given other settings than the dumps', or a dump cut from mid-track).
///
/// `start_sample[k]`: sample count at the start of record k's last
/// millisecond (when its detector call runs); `calls[k]`: the detector calls
/// (loop updates) record k stands for, 1 before bit synchronization and 20/N
/// after it (GNSS-SDR logs one update in 20/N, module docs of
/// [`gsens_core::gnss_sdr`]), each counted with the record's values; `lock`
/// and `cn0` per record.
pub(crate) fn replay_lock_detector(
    start_sample: &[f64],
    calls: &[u32],
    lock_test: &[f64],
    cn0_dbhz: &[f64],
    fs_hz: f64,
    tracking: &TrackingConf,
) -> LockReplay {
    let l = &tracking.lock;
    // GNSS-SDR divides an integer sample count by (int) fs.
    let fs_int = fs_hz.floor().max(1.0);
    let mut r = LockReplay {
        judged_records: 0,
        carrier_lock_failures: 0,
        code_lock_failures: 0,
        carrier_fail_counter_max: 0,
        code_fail_counter_max: 0,
        loss_of_lock: None,
        loss_by: None,
    };
    let Some(&acq) = start_sample.first() else { return r };
    let (mut carrier, mut code) = (0u32, 0u32);
    for k in 0..start_sample.len() {
        let elapsed_s = ((start_sample[k] - acq) / fs_int).floor();
        if elapsed_s <= tracking.pull_in_time_s || k < l.cn0_samples.value as usize {
            continue;
        }
        r.judged_records += 1;
        let (carrier_fails, code_fails) = (lock_test[k] < l.carrier_lock_th.value, cn0_dbhz[k] < l.cn0_min_dbhz.value);
        r.carrier_lock_failures += usize::from(carrier_fails);
        r.code_lock_failures += usize::from(code_fails);
        for _ in 0..calls.get(k).copied().unwrap_or(1).max(1) {
            carrier = if carrier_fails { carrier + 1 } else { carrier.saturating_sub(1) };
            code = if code_fails { code + 1 } else { code.saturating_sub(1) };
            let (by_carrier, by_code) = (carrier > l.max_carrier_lock_fail.value, code > l.max_lock_fail.value);
            if by_carrier || by_code {
                r.loss_of_lock = Some(k);
                r.loss_by = Some(if by_carrier { "carrier" } else { "code" });
                return r;
            }
            r.carrier_fail_counter_max = r.carrier_fail_counter_max.max(carrier);
            r.code_fail_counter_max = r.code_fail_counter_max.max(code);
        }
    }
    r
}

impl LockReplay {
    /// The rule and its values in words, for a track's reason.
    fn describe(&self, t: &TrackingConf) -> String {
        let l = &t.lock;
        format!(
            "carrier lock test < carrier_lock_th = {} ({}) in {} of {} judged records, fail counter at most {} \
             of max_carrier_lock_fail = {} ({}); C/N0 < cn0_min = {} dB-Hz ({}) in {}, counter at most {} of \
             max_lock_fail = {} ({})",
            l.carrier_lock_th.value,
            l.carrier_lock_th.source,
            self.carrier_lock_failures,
            self.judged_records,
            self.carrier_fail_counter_max,
            l.max_carrier_lock_fail.value,
            l.max_carrier_lock_fail.source,
            l.cn0_min_dbhz.value,
            l.cn0_min_dbhz.source,
            self.code_lock_failures,
            self.code_fail_counter_max,
            l.max_lock_fail.value,
            l.max_lock_fail.source,
        )
    }

    /// The loss of lock in words (which counter, which values decided).
    fn describe_loss(&self, t: &TrackingConf, at_s: f64) -> String {
        let l = &t.lock;
        let rule = if self.loss_by == Some("code") {
            format!(
                "the code-lock fail counter exceeded max_lock_fail = {} ({}), C/N0 < cn0_min = {} dB-Hz ({})",
                l.max_lock_fail.value, l.max_lock_fail.source, l.cn0_min_dbhz.value, l.cn0_min_dbhz.source
            )
        } else {
            format!(
                "the carrier-lock fail counter exceeded max_carrier_lock_fail = {} ({}), lock test < \
                 carrier_lock_th = {} ({})",
                l.max_carrier_lock_fail.value,
                l.max_carrier_lock_fail.source,
                l.carrier_lock_th.value,
                l.carrier_lock_th.source
            )
        };
        let own =
            [l.carrier_lock_th.source, l.max_carrier_lock_fail.source, l.cn0_min_dbhz.source, l.max_lock_fail.source]
                .iter()
                .all(|s| *s != crate::conf::ValueSource::Option);
        format!(
            "GNSS-SDR's lock detector declares loss of lock at {at_s:.2} s: {rule}{}",
            if own {
                " (GNSS-SDR itself would have stopped the dump there: were the dumps made with this \
                 configuration, and from the start of the track?)"
            } else {
                ""
            }
        )
    }
}

/// What became of one track.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TrackSummary {
    /// The dump file.
    pub file: String,
    /// The record layout it was read with: name, then the blocks and GNSS-SDR
    /// versions that write it ([`DumpLayout`]).
    pub layout: String,
    /// Channel.
    pub channel: u32,
    /// PRN.
    pub prn: u32,
    /// Time of its first record \[s\].
    pub start_s: f64,
    /// Time of the first record of the modelled stage \[s\] (`None`: never reached).
    pub switch_s: Option<f64>,
    /// Time of its last record \[s\].
    pub end_s: f64,
    /// Records in the track.
    pub records: usize,
    /// Records of the modelled stage after the settling time.
    pub modelled_records: usize,
    /// Of those, the records kept: the ones before a loss of lock.
    pub good_records: usize,
    /// GNSS-SDR's lock detector replayed over the track.
    pub lock: LockReplay,
    /// Time of the record at which the lock detector declares the loss of lock \[s\] (`None`: none).
    pub lock_loss_s: Option<f64>,
    /// Mean C/N0 over the modelled records \[dB-Hz\] (NaN when none).
    pub mean_cn0_dbhz: f64,
    /// Whether its rows are kept.
    pub used: bool,
    /// What became of it: [`TrackSummary::reason`]'s kind.
    pub fate: TrackFate,
    /// `"used: …"` with the rule that kept it, or why not.
    pub reason: String,
}

/// Converted dumps.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Imported {
    /// The kept rows, by time then channel.
    pub rows: Vec<ImportedRow>,
    /// Every track found.
    pub tracks: Vec<TrackSummary>,
    /// Spacing of the modelled stage's records, one per 20 ms data bit
    /// ([`ImportSettings::record_interval_s`]), the grid [`resample`] puts them on \[s\].
    pub interval_s: f64,
}

/// What became of a track, the key by which [`import_dir`] aggregates the
/// reasons of tracks that gave nothing.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum TrackFate {
    /// Kept to its end.
    Used,
    /// Kept up to the record where the replayed lock detector declares a loss of lock.
    UsedToLossOfLock,
    /// The lock detector declares a loss of lock before the modelled loop.
    LostBeforeModelledLoop,
    /// Never reached the modelled loop (no bit synchronization, or ended in the pull-in).
    NeverModelled,
    /// The modelled loop lasted less than its settling time.
    ShorterThanSettling,
    /// The lock detector declares a loss of lock before the modelled loop had settled.
    LostBeforeSettled,
}

/// Converts one decoded dump (see the module docs); `track_base` numbers its tracks.
pub fn import_dump(
    dump: &TrackingDump,
    settings: &ImportSettings,
    track_base: usize,
) -> (Vec<ImportedRow>, Vec<TrackSummary>) {
    import_dump_booked(dump, settings, track_base, NcoBookkeeping::Right)
}

/// [`import_dump`] with the NCO booked as `how` says.
pub(crate) fn import_dump_booked(
    dump: &TrackingDump,
    settings: &ImportSettings,
    track_base: usize,
    how: NcoBookkeeping,
) -> (Vec<ImportedRow>, Vec<TrackSummary>) {
    let samples_per_ms = settings.fs_hz * 1e-3;
    let mut rows = Vec::new();
    let mut tracks = Vec::new();
    let mut i = 0;
    while i < dump.records.len() {
        let (j, synced) = track_span(&dump.records, i, samples_per_ms);
        let track = DumpTrack { records: &dump.records[i..j], synced: synced.map(|s| s - i), settings, how };
        let (track_rows, summary) = track.import(dump, track_base + tracks.len());
        if summary.used {
            rows.extend(track_rows);
        }
        tracks.push(summary);
        i = j;
    }
    (rows, tracks)
}

/// One track of a dump (`track_span`): its records, the index among them of
/// the first after bit synchronization, and how the dumps are converted.
struct DumpTrack<'a> {
    records: &'a [TrackingRecord],
    synced: Option<usize>,
    settings: &'a ImportSettings,
    how: NcoBookkeeping,
}

impl DumpTrack<'_> {
    /// Whether record `k` comes after bit synchronization.
    fn after_sync(&self, k: usize) -> bool {
        self.synced.is_some_and(|s| k >= s)
    }

    /// The integration record `k`'s discriminator output comes from \[ms\]:
    /// 1 before bit synchronization, N after.
    fn symbols(&self, k: usize) -> u32 {
        if self.after_sync(k) { self.settings.stage().symbols.max(1) } else { 1 }
    }

    /// The middle of record `k`'s integration, its time \[s\].
    fn t_mid(&self, k: usize) -> f64 {
        let (fs, samples_per_ms) = (self.settings.fs_hz, self.settings.fs_hz * 1e-3);
        (self.records[k].prn_start_sample_count as f64 - 0.5 * f64::from(self.symbols(k)) * samples_per_ms) / fs
    }

    /// The sample count at which record `k`'s lock-detector call runs: the
    /// start of its last millisecond, not before the track's first record's.
    fn call_sample(&self, k: usize) -> f64 {
        let samples_per_ms = self.settings.fs_hz * 1e-3;
        let first_start = self.records[0].prn_start_sample_count as f64 - samples_per_ms;
        (self.records[k].prn_start_sample_count as f64 - samples_per_ms).max(first_start)
    }

    /// GNSS-SDR's lock detector over the whole track (its counters run
    /// through the stages): called once per loop update, so a record after
    /// bit synchronization stands for 20/N calls (the smoothed lock test and
    /// C/N0 it holds barely move within them).
    fn replay_lock(&self) -> LockReplay {
        let per_record = self.settings.stage().updates_per_record().unwrap_or(1);
        let n = self.records.len();
        let call_sample: Vec<f64> = (0..n).map(|k| self.call_sample(k)).collect();
        let calls: Vec<u32> = (0..n).map(|k| if self.after_sync(k) { per_record } else { 1 }).collect();
        let lock_test: Vec<f64> = self.records.iter().map(|r| r.carrier_lock_test).collect();
        let cn0: Vec<f64> = self.records.iter().map(|r| r.cn0_dbhz).collect();
        let tracking = &self.settings.tracking;
        replay_lock_detector(&call_sample, &calls, &lock_test, &cn0, self.settings.fs_hz, tracking)
    }

    /// The first record of the modelled loop. Extended integration: the
    /// first after bit synchronization (the narrow loop starts there).
    /// Without it the 1 ms loop runs throughout, PLL only once GNSS-SDR's
    /// pull-in transitory (its FLL, if enabled) is over: at the latest
    /// floor(Δn/fs) > pull_in_time_s after the track's first record
    /// (acquisition came a little earlier), and before bit synchronization,
    /// which GNSS-SDR seeks only after the transitory.
    fn first_modelled(&self) -> Option<usize> {
        if self.settings.stage().symbols.max(1) > 1 {
            return self.synced;
        }
        let (fs, samples_per_ms) = (self.settings.fs_hz, self.settings.fs_hz * 1e-3);
        let end_sample = self.call_sample(0) + (self.settings.tracking.pull_in_time_s + 1.0) * fs.floor();
        let after_pull_in = (0..self.records.len())
            .find(|&k| self.records[k].prn_start_sample_count as f64 - samples_per_ms >= end_sample - 0.5);
        match (after_pull_in, self.synced) {
            (Some(a), Some(s)) => Some(a.min(s)),
            (a, s) => a.or(s),
        }
    }

    /// Whether record `k` is on the lattice of one record per data bit.
    /// Without extended integration the 1 ms records before bit
    /// synchronization are thinned to one per data bit, on the lattice of
    /// the records after it (the first of which comes one bit after the last
    /// 1 ms record; without synchronization, the track's last record's):
    /// every record then holds the last of 20 updates, as the stage states.
    fn on_lattice(&self, k: usize) -> bool {
        let anchor = self.synced.map_or(self.records.len() - 1, |s| s - 1);
        self.after_sync(k) || (anchor - k).is_multiple_of(BIT_SYMBOLS as usize)
    }

    /// The rows of the modelled loop from record `k0` on, one per data bit,
    /// once it has settled: the records before `tracking_end` (the loss of
    /// lock) as rows of track `track`; with the count of modelled records
    /// and the sum of their C/N0 \[dB-Hz\].
    /// The replica's phase at the middle of each record's integration
    /// \[cycles\] from the track's first record on, booked as GNSS-SDR books
    /// its NCO ([`crate::nco`]); the accumulator restarts in the interval
    /// that ends at the first record after bit synchronization.
    fn replica_phase_cycles(&self) -> Vec<f64> {
        let fs = self.settings.fs_hz;
        let recs: Vec<NcoRecord> = (0..self.records.len())
            .map(|k| {
                let r = &self.records[k];
                let end_s = r.prn_start_sample_count as f64 / fs;
                let symbols = self.symbols(k);
                let updates = if k == 0 {
                    1
                } else {
                    let dt_s = end_s - self.records[k - 1].prn_start_sample_count as f64 / fs;
                    (dt_s / (f64::from(symbols) * BLOCK_S)).round().max(1.0) as u32
                };
                NcoRecord {
                    end_s,
                    symbols,
                    updates,
                    acc_rad: r.acc_carrier_phase_rad,
                    command_hz: r.carrier_doppler_hz,
                }
            })
            .collect();
        replica_mid_cycles(&recs, self.synced, self.how)
    }

    fn modelled_rows(
        &self,
        channel: u32,
        k0: usize,
        tracking_end: usize,
        track: usize,
    ) -> (Vec<ImportedRow>, usize, f64) {
        let replica_cycles = self.replica_phase_cycles();
        let t0 = self.t_mid(k0);
        let settle_s = self.settings.settle_time_s();
        let (mut modelled, mut cn0_sum) = (0usize, 0.0);
        let mut rows = Vec::new();
        for k in (k0..self.records.len()).filter(|&k| self.on_lattice(k)) {
            let t = self.t_mid(k);
            if t < t0 + settle_s - 1e-9 {
                continue;
            }
            let r = &self.records[k];
            modelled += 1;
            cn0_sum += r.cn0_dbhz;
            if k < tracking_end {
                rows.push(ImportedRow {
                    t_s: t,
                    channel,
                    prn: r.prn,
                    cn0_dbhz: r.cn0_dbhz,
                    phase_err_rad: core::f64::consts::TAU * r.carr_error_cycles,
                    lock_test: r.carrier_lock_test,
                    symbols: self.symbols(k),
                    track,
                    input_phase_rad: Some(core::f64::consts::TAU * (replica_cycles[k] + r.carr_error_cycles)),
                });
            }
        }
        (rows, modelled, cn0_sum)
    }

    /// The track converted: its rows (kept only when some are good) and its
    /// summary, as track `track` of `dump`.
    fn import(&self, dump: &TrackingDump, track: usize) -> (Vec<ImportedRow>, TrackSummary) {
        let (settings, recs) = (self.settings, self.records);
        let channel = dump.channel.unwrap_or(0);
        let lock = self.replay_lock();
        let tracking_end = lock.loss_of_lock.unwrap_or(recs.len());
        let k0 = self.first_modelled();
        let (rows, modelled, cn0_sum) = match k0 {
            Some(k0) => self.modelled_rows(channel, k0, tracking_end, track),
            None => (Vec::new(), 0, 0.0),
        };
        let good = rows.len();
        let lock_loss_s = lock.loss_of_lock.map(|k| self.t_mid(k));
        let loss = lock_loss_s.map(|t| lock.describe_loss(&settings.tracking, t));
        let counts = TrackCounts { records: recs.len(), modelled, good, dropped_after_loss: recs.len() - tracking_end };
        let (fate, reason) = fate_of(settings, &lock, loss, k0.is_none_or(|k| tracking_end <= k), k0.is_some(), counts);
        let summary = TrackSummary {
            file: dump.file.clone(),
            layout: format!("{} ({})", dump.layout, dump.layout_description),
            channel,
            prn: recs[0].prn,
            start_s: self.t_mid(0),
            switch_s: k0.map(|k| self.t_mid(k)),
            end_s: self.t_mid(recs.len() - 1),
            records: recs.len(),
            modelled_records: modelled,
            good_records: good,
            lock,
            lock_loss_s,
            mean_cn0_dbhz: if modelled > 0 { cn0_sum / modelled as f64 } else { f64::NAN },
            used: good > 0,
            fate,
            reason,
        };
        (rows, summary)
    }
}

/// How many records of a track there were, were modelled, were kept, and
/// were dropped after a loss of lock.
#[derive(Debug, Clone, Copy)]
struct TrackCounts {
    records: usize,
    modelled: usize,
    good: usize,
    dropped_after_loss: usize,
}

/// One track's records `i..j` of `recs`, and where bit synchronization came
/// (`synced`): 1 ms apart until then, the first record one data bit after its
/// predecessor, one bit apart from there on; the track ends where the PRN
/// changes or the spacing breaks.
fn track_span(recs: &[TrackingRecord], i: usize, samples_per_ms: f64) -> (usize, Option<usize>) {
    let bit_ms = f64::from(BIT_SYMBOLS);
    let mut j = i + 1;
    let mut synced = None;
    while j < recs.len() {
        let (a, b) = (recs[j - 1].prn_start_sample_count, recs[j].prn_start_sample_count);
        let step_ms = b.checked_sub(a).map_or(f64::NAN, |dn| dn as f64 / samples_per_ms);
        let (one_ms, one_bit) = ((step_ms - 1.0).abs() < 0.5, (step_ms - bit_ms).abs() < 1.0);
        let continues = recs[j].prn == recs[i].prn && if synced.is_some() { one_bit } else { one_ms || one_bit };
        if !continues {
            break;
        }
        if one_bit && synced.is_none() {
            synced = Some(j);
        }
        j += 1;
    }
    (j, synced)
}

/// What became of a track and why (`lock`: GNSS-SDR's lock detector replayed
/// on it, `loss`: its loss of lock described): lost before the modelled loop
/// (`lost_before_model`: the loss of lock came before the first modelled
/// record, or there was none), never modelled (`reached_model` false), too
/// short for the settling time, lost before it settled, used up to a loss of
/// lock, or used to its end.
fn fate_of(
    settings: &ImportSettings,
    lock: &LockReplay,
    loss: Option<String>,
    lost_before_model: bool,
    reached_model: bool,
    counts: TrackCounts,
) -> (TrackFate, String) {
    let (ext, settle_s) = (settings.stage().symbols.max(1), settings.settle_time_s());
    let TrackCounts { records, modelled, good, dropped_after_loss } = counts;
    if let (Some(loss), true) = (&loss, lost_before_model) {
        (TrackFate::LostBeforeModelledLoop, format!("{loss}, before it reached the modelled loop"))
    } else if !reached_model {
        let why = if ext > 1 {
            format!(
                "{ext} ms integrations, pll_bw_narrow_hz = {}): no bit synchronization in its {} records",
                settings.tracking.pll_bw_narrow_hz, records
            )
        } else {
            format!(
                "1 ms loop after the pull-in): its {} records end within pull_in_time_s = {} s{}",
                records,
                settings.tracking.pull_in_time_s,
                if settings.tracking.enable_fll_pull_in { " (the FLL)" } else { "" }
            )
        };
        (TrackFate::NeverModelled, format!("never reached the modelled loop ({why}"))
    } else if modelled == 0 {
        (TrackFate::ShorterThanSettling, format!("fewer than {settle_s:.1} s of the modelled loop (its settling time)"))
    } else if good == 0 {
        (TrackFate::LostBeforeSettled, format!("{}, before the modelled loop had settled", loss.unwrap_or_default()))
    } else if let Some(loss) = loss {
        (
            TrackFate::UsedToLossOfLock,
            format!(
                "used up to the loss of lock: {loss}; the {} records from there on are dropped",
                dropped_after_loss
            ),
        )
    } else {
        (
            TrackFate::Used,
            format!("used: GNSS-SDR's lock detector keeps it to its end ({})", lock.describe(&settings.tracking)),
        )
    }
}

/// Why no track of a dump directory gave a record: one line per channel and
/// fate, with the number of tracks, their PRNs and the first one's reason (a
/// dump cut into thousands of tracks still says it in a few lines).
pub(crate) fn nothing_usable_reason(tracks: &[TrackSummary]) -> String {
    if tracks.is_empty() {
        return "the dumps hold no record".into();
    }
    let mut groups: Vec<(u32, TrackFate, usize, Vec<u32>, &str)> = Vec::new();
    for t in tracks {
        match groups.iter_mut().find(|g| g.0 == t.channel && g.1 == t.fate) {
            Some(g) => {
                g.2 += 1;
                if !g.3.contains(&t.prn) {
                    g.3.push(t.prn);
                }
            }
            None => groups.push((t.channel, t.fate, 1, vec![t.prn], &t.reason)),
        }
    }
    groups.sort_by_key(|g| (g.0, g.1));
    groups
        .iter()
        .map(|(channel, _, n, prns, reason)| {
            let prns = prns.iter().map(u32::to_string).collect::<Vec<_>>().join(", ");
            if *n == 1 {
                format!("\n  channel {channel} (PRN {prns}): {reason}")
            } else {
                format!("\n  channel {channel}, {n} tracks (PRN {prns}), the first: {reason}")
            }
        })
        .collect()
}

/// Reads every dump `<prefix><channel>.dat` in `dir` (the prefix from the
/// configuration's `dump_filename` when it has one) and converts them.
pub fn import_dir(dir: &Path, settings: &ImportSettings) -> Result<Imported, GnssSdrError> {
    import_dir_booked(dir, settings, NcoBookkeeping::Right)
}

/// [`import_dir`] with the NCO booked as `how` says: the tests' hook for
/// the deliberately wrong bookkeepings ([`NcoBookkeeping`]).
#[doc(hidden)]
pub fn import_dir_booked(dir: &Path, settings: &ImportSettings, how: NcoBookkeeping) -> Result<Imported, GnssSdrError> {
    let prefix = settings
        .tracking
        .dump_filename
        .as_deref()
        .and_then(|f| Path::new(f).file_name().and_then(|n| n.to_str()).map(str::to_owned));
    let files = match find_dumps(dir, prefix.as_deref()) {
        Ok(f) => f,
        // A configuration's prefix that matches nothing: take any dump.
        Err(GnssSdrError::NoDumps { .. }) if prefix.is_some() => find_dumps(dir, None)?,
        Err(e) => return Err(e),
    };
    let mut rows = Vec::new();
    let mut tracks = Vec::new();
    // Each dump's runs of one PRN: (PRN, first and last sample counter, file).
    let mut runs: Vec<(u32, u64, u64, String)> = Vec::new();
    for (_, path) in &files {
        let dump = read_dump(path, settings.layout.as_ref())?;
        check_one_channel_per_satellite(&dump, &mut runs)?;
        if !dump.modelled {
            return Err(GnssSdrError::NotModelled {
                file: dump.file,
                layout: dump.layout,
                description: dump.layout_description,
            });
        }
        let (r, t) = import_dump_booked(&dump, settings, tracks.len(), how);
        rows.extend(r);
        tracks.extend(t);
    }
    if rows.is_empty() {
        return Err(GnssSdrError::NothingUsable {
            dir: dir.display().to_string(),
            reason: nothing_usable_reason(&tracks),
        });
    }
    rows.sort_by(|a, b| a.t_s.total_cmp(&b.t_s).then(a.channel.cmp(&b.channel)));
    Ok(Imported { rows, tracks, interval_s: settings.record_interval_s() })
}

/// Adds the runs of one PRN of `dump` to `runs` (those of the dumps read
/// before it), refusing a run that overlaps another dump's run of the same
/// PRN in time: a receiver tracks a satellite's signal on one channel at a
/// time, so two such dumps are copies (or not of one receiver run).
fn check_one_channel_per_satellite(
    dump: &TrackingDump,
    runs: &mut Vec<(u32, u64, u64, String)>,
) -> Result<(), GnssSdrError> {
    let mut own: Vec<(u32, u64, u64)> = Vec::new();
    for r in &dump.records {
        let s = r.prn_start_sample_count;
        match own.last_mut() {
            Some((prn, _, last)) if *prn == r.prn => *last = (*last).max(s),
            _ => own.push((r.prn, s, s)),
        }
    }
    for &(prn, first, last) in &own {
        if let Some((_, f, l, file)) = runs.iter().find(|(p, f, l, _)| *p == prn && first <= *l && *f <= last) {
            return Err(GnssSdrError::SameSatelliteTwice {
                first: file.clone(),
                second: dump.file.clone(),
                prn,
                sample: first.max(*f).min(last.min(*l)),
            });
        }
    }
    runs.extend(own.into_iter().map(|(p, f, l)| (p, f, l, dump.file.clone())));
    Ok(())
}

/// Puts every track on the common grid t = j·`interval_s` (module docs): rows
/// of `tracking.csv` (elevation unknown) by time then channel.
pub fn resample(imported: &Imported, interval_s: f64) -> Vec<TrackingRow> {
    resample_rows(&imported.rows, interval_s)
}

/// [`resample`] of rows alone (their `track` numbers the tracks; the
/// tracking monitor's rows have no [`TrackSummary`]).
pub(crate) fn resample_rows(rows: &[ImportedRow], interval_s: f64) -> Vec<TrackingRow> {
    let n_tracks = rows.iter().map(|r| r.track + 1).max().unwrap_or(0);
    let mut by_track: Vec<Vec<&ImportedRow>> = vec![Vec::new(); n_tracks];
    for r in rows {
        by_track[r.track].push(r);
    }
    let mut out = Vec::new();
    let t = interval_s;
    let consecutive = |a: &ImportedRow, b: &ImportedRow| {
        let d = b.t_s - a.t_s;
        d > 0.75 * t && d < 1.25 * t
    };
    for rows in by_track.iter().filter(|r| r.len() >= 2) {
        for k in 0..rows.len() - 1 {
            let (a, b) = (rows[k], rows[k + 1]);
            if !consecutive(a, b) {
                continue;
            }
            let j0 = (a.t_s / t).ceil() as i64;
            let j1 = (b.t_s / t).ceil() as i64; // grid points in [a, b)
            for jj in j0..j1 {
                let tg = jj as f64 * t;
                let u = (tg - a.t_s) / (b.t_s - a.t_s);
                let prev = (k > 0 && consecutive(rows[k - 1], a)).then(|| rows[k - 1]);
                let next = (k + 2 < rows.len() && consecutive(b, rows[k + 2])).then(|| rows[k + 2]);
                let phase = match (prev, next) {
                    (Some(p), Some(n)) => cubic(p.phase_err_rad, a.phase_err_rad, b.phase_err_rad, n.phase_err_rad, u),
                    _ => a.phase_err_rad + u * (b.phase_err_rad - a.phase_err_rad),
                };
                out.push(TrackingRow {
                    t_s: tg,
                    channel: a.channel,
                    prn: a.prn,
                    cn0_dbhz: a.cn0_dbhz + u * (b.cn0_dbhz - a.cn0_dbhz),
                    elev_deg: None,
                    phase_err_rad: phase,
                });
            }
        }
    }
    out.sort_by(|a, b| a.t_s.total_cmp(&b.t_s).then(a.channel.cmp(&b.channel)));
    // Two tracks of one channel cannot overlap in time, but keep the first if they touch.
    out.dedup_by(|b, a| a.t_s == b.t_s && a.channel == b.channel);
    out
}

/// Four-point Lagrange (cubic) interpolation between p1 (u = 0) and p2
/// (u = 1) of samples at u = −1, 0, 1, 2: exact for cubics.
fn cubic(p0: f64, p1: f64, p2: f64, p3: f64, u: f64) -> f64 {
    let (um, u1, u2) = (u + 1.0, u - 1.0, u - 2.0);
    -p0 * u * u1 * u2 / 6.0 + p1 * um * u1 * u2 / 2.0 - p2 * um * u * u2 / 2.0 + p3 * um * u * u1 / 6.0
}

/// Writes converted records as `tracking.csv` with a seventh column,
/// `carrier_lock_test` (readers of the schema ignore extra columns); the
/// elevation is empty. Written by [`gsens_io::TrackingWriter`]: numbers in
/// the shortest round-trip form, and a non-finite value is refused
/// (`InvalidInput`).
pub(crate) fn write_imported_csv<W: std::io::Write>(w: W, rows: &[ImportedRow]) -> std::io::Result<W> {
    let mut out = gsens_io::TrackingWriter::with_extra_columns(w, &["carrier_lock_test"])?;
    for r in rows {
        out.write_row_with(&r.tracking_row(), &[r.lock_test])?;
    }
    out.finish()
}

/// What became of each track of a GNSS-SDR import, as text.
pub fn render_tracks(tracks: &[TrackSummary], interval_s: f64) -> String {
    let mut s = String::new();
    let used = tracks.iter().filter(|t| t.used).count();
    let _ = writeln!(
        s,
        "GNSS-SDR dumps: {} tracks, {used} used, records at {} ms kept",
        tracks.len(),
        Decimal(interval_s * 1e3)
    );
    // Which record layout (blocks, GNSS-SDR versions) each dump was read with.
    let mut files: Vec<(&str, &str)> = Vec::new();
    for t in tracks {
        if !files.contains(&(t.file.as_str(), t.layout.as_str())) {
            files.push((t.file.as_str(), t.layout.as_str()));
        }
    }
    for (file, layout) in files {
        let _ = writeln!(s, "  {file}: read as {layout}");
    }
    for t in tracks {
        let _ = writeln!(
            s,
            "  ch {:>3}  PRN {:>3}  {:>7.2}–{:>7.2} s  narrow from {}  C/N0 {:>5.1} dB-Hz  {:>6}/{:<6} good  {}",
            t.channel,
            t.prn,
            t.start_s,
            t.end_s,
            t.switch_s.map(|v| format!("{v:>7.2} s")).unwrap_or_else(|| "      —  ".into()),
            t.mean_cn0_dbhz,
            t.good_records,
            t.modelled_records,
            t.reason
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::conf::ValueSource;
    use crate::dump::TrackingRecord;

    fn rec(n: u64, e: f64, cn0: f64, lock: f64, prn: u32) -> TrackingRecord {
        TrackingRecord {
            abs_ve: 0.0,
            abs_e: 0.0,
            abs_p: 0.0,
            abs_l: 0.0,
            abs_vl: 0.0,
            prompt_i: 0.0,
            prompt_q: 0.0,
            prn_start_sample_count: n,
            acc_carrier_phase_rad: 0.0,
            carrier_doppler_hz: 1000.0,
            carrier_doppler_rate_hz_per_s: 0.0,
            code_freq_chips_per_s: 1.023e6,
            code_freq_rate_chips_per_s2: 0.0,
            carr_error_cycles: e,
            carr_error_filt_hz: 1000.0,
            code_error_chips: 0.0,
            code_error_filt_chips: 0.0,
            cn0_dbhz: cn0,
            carrier_lock_test: lock,
            aux1: 0.0,
            aux2: n as f64,
            prn,
            tow_ms: None,
            wn: None,
        }
    }

    fn settings() -> ImportSettings {
        let mut tc = TrackingConf::defaults();
        tc.extend_correlation_symbols = 20;
        tc.pll_bw_narrow_hz = 3.0;
        // Counting starts floor(Δn/fs) > 0 s after a track's first record: at 1 s.
        tc.pull_in_time_s = 0.0;
        let mut s = ImportSettings::new(1.0e6, tc);
        s.settle_s = Some(0.1);
        s
    }

    /// A dump: `pull_in` 1 ms records then `narrow` 20 ms records, starting at sample `start`.
    fn records(start: u64, pull_in: usize, narrow: usize, prn: u32, lock: f64) -> Vec<TrackingRecord> {
        let mut v = Vec::new();
        let mut n = start;
        for _ in 0..pull_in {
            n += 1000;
            v.push(rec(n, 0.01, 45.0, lock, prn));
        }
        for k in 0..narrow {
            n += 20_000;
            v.push(rec(n, 0.02 * (k as f64 * 0.1).sin(), 44.0, lock, prn));
        }
        v
    }

    #[test]
    fn overrides_are_checked_and_named() {
        let mut s = ImportSettings::from_conf(None, Some(4e6)).unwrap();
        let bad = |o: ImportOverrides| s.clone().override_with(&o).unwrap_err();
        let e = bad(ImportOverrides { settle_s: Some(-1.0), ..ImportOverrides::default() });
        assert_eq!(
            (e.to_string().as_str(), e.setting()),
            ("settle_s must be ≥ 0 and finite, got -1", Some("settle_s"))
        );
        let e = bad(ImportOverrides { min_lock_test: Some(1.5), ..ImportOverrides::default() });
        assert!(e.to_string().starts_with("min_lock_test must be in [-1, 1]"), "{e}");
        let e = bad(ImportOverrides { min_cn0_dbhz: Some(f64::INFINITY), ..ImportOverrides::default() });
        assert_eq!(e.to_string(), "min_cn0_dbhz must be finite, got inf");
        let e = bad(ImportOverrides { layout: Some("x:f33".into()), ..ImportOverrides::default() });
        assert_eq!(
            (e.to_string().as_str(), e.setting()),
            ("layout: `x:f33`: unknown type `f33` (f32, f64, u32, u64, i32)", Some("layout"))
        );
        let o = ImportOverrides {
            min_cn0_dbhz: Some(30.0),
            min_lock_test: Some(-0.5),
            max_carrier_lock_fail: Some(7),
            max_lock_fail: Some(9),
            settle_s: Some(0.0),
            layout: Some("gnss-sdr-0.0.21".into()),
        };
        // Named with the configuration (GNSS-SDR's defaults here): the same settings.
        assert_eq!(ImportSettings::from_conf_with(None, Some(4e6), &o).unwrap(), {
            s.override_with(&o).unwrap();
            s.clone()
        });
        let lock = &s.tracking.lock;
        assert_eq!((lock.cn0_min_dbhz.value, lock.carrier_lock_th.value), (30.0, -0.5));
        assert_eq!((lock.max_carrier_lock_fail.value, lock.max_lock_fail.value), (7, 9));
        assert_eq!(s.settle_s, Some(0.0));
        assert!(s.layout.is_some());
        let e = ImportSettings::from_conf_with(None, None, &ImportOverrides::default()).unwrap_err();
        assert!(matches!(e, GnssSdrError::UnknownSamplingRate), "{e}");
    }

    #[test]
    fn a_tracks_times_lattice_and_modelled_rows() {
        // 100 records of 1 ms, then 50 of 20 ms (at fs = 1 MHz, 1000 samples per ms).
        let s = settings();
        let recs = records(0, 100, 50, 5, 0.95);
        assert_eq!(track_span(&recs, 0, 1000.0), (150, Some(100)));
        let track = DumpTrack { records: &recs, synced: Some(100), settings: &s, how: NcoBookkeeping::Right };
        // The middle of each integration: 1 ms before bit synchronization, 20 ms after.
        assert_eq!((track.symbols(99), track.symbols(100)), (1, 20));
        assert!((track.t_mid(0) - 0.0005).abs() < 1e-12 && (track.t_mid(100) - 0.11).abs() < 1e-12);
        assert_eq!((track.call_sample(0), track.call_sample(100)), (0.0, 119_000.0));
        assert_eq!(track.first_modelled(), Some(100));
        // The records before synchronization on the bit lattice end at the last 1 ms one.
        assert!(track.on_lattice(99) && track.on_lattice(79) && !track.on_lattice(98) && track.on_lattice(120));
        // Settled 0.1 s after the switch (record 105 on); lock lost at record 140.
        let (rows, modelled, cn0_sum) = track.modelled_rows(3, 100, 140, 7);
        assert_eq!((rows.len(), modelled, cn0_sum), (35, 45, 45.0 * 44.0));
        assert!((rows[0].t_s - 0.21).abs() < 1e-12 && rows.iter().all(|r| r.channel == 3 && r.track == 7));
        assert!(rows.iter().all(|r| r.symbols == 20 && r.prn == 5));

        // 1 ms updates throughout: the PLL starts at the end of the pull-in,
        // floor(Δn/fs) > 0 s, 1 s after the first record (sample 1 001 000).
        let mut s1 = settings();
        s1.tracking.extend_correlation_symbols = 1;
        let recs = records(0, 2500, 0, 5, 0.95);
        let track = DumpTrack { records: &recs, synced: None, settings: &s1, how: NcoBookkeeping::Right };
        assert_eq!(track.first_modelled(), Some(1000));
        assert!(!track.on_lattice(1000) && track.on_lattice(1019) && track.on_lattice(2499));
    }

    #[test]
    fn stages_times_and_the_receivers_lock_rule() {
        let mut s = settings();
        s.tracking.lock.max_carrier_lock_fail = crate::conf::Sourced { value: 20, source: ValueSource::Conf };
        let mut recs = records(0, 100, 50, 5, 0.95);
        // The channel loses lock and restarts on another satellite, which never syncs.
        recs.extend(records(recs.last().unwrap().prn_start_sample_count + 50_000, 300, 0, 9, 0.95));
        // Then a satellite whose lock test sits at 0.3, below carrier_lock_th = 0.7 (the default):
        // judged from 1 s on (record 20 of the narrow stage), lost when the counter passes 20.
        recs.extend(records(recs.last().unwrap().prn_start_sample_count + 70_000, 50, 80, 11, 0.3));
        let d = TrackingDump {
            file: "trk_ch_2.dat".into(),
            channel: Some(2),
            layout: "x".into(),
            layout_description: "x".into(),
            modelled: true,
            records: recs,
        };
        let (rows, tracks) = import_dump(&d, &s, 0);
        assert_eq!(tracks.len(), 3);
        assert!(
            tracks[0].used && tracks[0].reason.starts_with("used: GNSS-SDR's lock detector"),
            "{}",
            tracks[0].reason
        );
        assert!(tracks[0].reason.contains("carrier_lock_th = 0.7 (GNSS-SDR's default)"), "{}", tracks[0].reason);
        assert!(tracks[0].reason.contains("max_carrier_lock_fail = 20 (from the conf)"), "{}", tracks[0].reason);
        assert_eq!(tracks[0].lock.loss_of_lock, None);
        assert!(tracks[1].reason.contains("no bit synchronization"), "{}", tracks[1].reason);
        // Track 2 starts at its first record's start; a record's detector call runs at the
        // start of its last millisecond, 69 ms + m·20 ms into the track for narrow record m:
        // judged from m = 47 on, the 21st failure is narrow record 67.
        let t2 = &tracks[2];
        assert_eq!(t2.lock.judged_records, 21);
        assert_eq!(t2.lock.loss_of_lock, Some(50 + 67));
        assert_eq!(t2.lock.loss_by, Some("carrier"));
        assert!(t2.used, "{}", t2.reason);
        assert!(t2.reason.starts_with("used up to the loss of lock"), "{}", t2.reason);
        assert!(t2.reason.contains("exceeded max_carrier_lock_fail = 20 (from the conf)"), "{}", t2.reason);
        assert!(t2.reason.contains("the 13 records from there on are dropped"), "{}", t2.reason);
        // Narrow records 0..67, less the first 0.1 s (records 0..4 whose middles are < switch + 0.1 s).
        assert_eq!(t2.good_records, 67 - 5);
        assert_eq!(t2.modelled_records, 80 - 5);
        assert!(t2.lock_loss_s.is_some());
        assert_eq!(rows.iter().filter(|r| r.track == 2).count(), 62);
        // Track 0: first 20 ms record ends at sample 120 000, its middle at 0.110 s; settling 0.1 s.
        assert!((tracks[0].switch_s.unwrap() - 0.110).abs() < 1e-12);
        assert_eq!(tracks[0].modelled_records, 45);
        let r0: Vec<&ImportedRow> = rows.iter().filter(|r| r.track == 0).collect();
        assert_eq!(r0.len(), 45);
        assert!(r0.iter().all(|r| r.channel == 2 && r.prn == 5 && r.symbols == 20));
        assert!((r0[0].t_s - 0.210).abs() < 1e-12, "{}", r0[0].t_s);
        let want = core::f64::consts::TAU * 0.02 * (5.0f64 * 0.1).sin();
        assert!((r0[0].phase_err_rad - want).abs() < 1e-12);
        // A loss before bit synchronization drops the whole track, naming the rule.
        let mut s2 = settings();
        s2.tracking.lock.max_carrier_lock_fail.set_option(3);
        let d = TrackingDump {
            file: "trk_ch_3.dat".into(),
            channel: Some(3),
            layout: "x".into(),
            layout_description: "x".into(),
            modelled: true,
            records: records(0, 1500, 30, 7, 0.1),
        };
        let (rows, tracks) = import_dump(&d, &s2, 0);
        assert!(rows.is_empty() && !tracks[0].used);
        assert!(tracks[0].reason.contains("before it reached the modelled loop"), "{}", tracks[0].reason);
        assert!(tracks[0].reason.contains("max_carrier_lock_fail = 3 (given as an option)"), "{}", tracks[0].reason);
        assert!(!tracks[0].reason.contains("GNSS-SDR itself would have stopped"), "{}", tracks[0].reason);
    }

    #[test]
    fn with_1_ms_updates_the_records_before_bit_synchronization_join_the_bit_lattice() {
        // N = 1: 3000 records of 1 ms, then 50 of one bit each. The 1 ms loop is modelled from
        // the end of the pull-in transitory, floor(Δn/fs) > pull_in_time_s = 0, 1 s after the
        // track's first record; the earlier 1 ms records are thinned to one per bit.
        let mut s = settings();
        s.tracking.extend_correlation_symbols = 1;
        let d = TrackingDump {
            file: "trk_ch_0.dat".into(),
            channel: Some(0),
            layout: "x".into(),
            layout_description: "x".into(),
            modelled: true,
            records: records(0, 3000, 50, 4, 0.95),
        };
        let (rows, tracks) = import_dump(&d, &s, 0);
        assert_eq!(tracks.len(), 1, "{tracks:?}");
        let t = &tracks[0];
        assert_eq!(t.fate, TrackFate::Used, "{}", t.reason);
        // Record k (0-based) ends at (k + 1) ms; its call at k ms reaches 1 s at k = 1000.
        assert!((t.switch_s.unwrap() - 1.0005).abs() < 1e-12, "{:?}", t.switch_s);
        // Kept from 0.1 s later: 1 ms records k ≡ 2999 (mod 20) from k = 1119, i.e. (k + 1 − 0.5) ms,
        // then the 50 records of one bit, all one bit apart.
        assert!((rows[0].t_s - 1.1195).abs() < 1e-12, "{}", rows[0].t_s);
        for w in rows.windows(2) {
            assert!((w[1].t_s - w[0].t_s - 0.02).abs() < 1e-12, "{} → {}", w[0].t_s, w[1].t_s);
        }
        assert_eq!(rows.len(), (2999 - 1119) / 20 + 1 + 50);
        assert!(rows.iter().all(|r| r.symbols == 1));
        // With N = 20 the same records give the 20 ms loop only after bit synchronization.
        let (rows20, t20) = import_dump(&d, &settings(), 0);
        assert_eq!((t20.len(), rows20.len()), (1, 50 - 5));
    }

    #[test]
    fn lock_detector_counts_up_and_down_like_gnss_sdr() {
        let mut tc = TrackingConf::defaults();
        tc.pull_in_time_s = 0.0;
        tc.lock.max_lock_fail.set_option(2);
        tc.lock.cn0_samples.set_option(0);
        let fs = 1000.0;
        // One call per second; the first (the track's start) is in the transitory, floor(0 s) ≤ 0.
        let t: Vec<f64> = (0..9).map(|k| 1000.0 * k as f64).collect();
        let lock = vec![1.0; 9];
        // fail, fail, pass, fail, fail → counter 1, 2, 1, 2, 3 > 2: loss at the 5th judged call.
        let cn0 = [0.0, 20.0, 20.0, 30.0, 20.0, 20.0, 30.0, 30.0, 30.0];
        let r = replay_lock_detector(&t, &[1; 9], &lock, &cn0, fs, &tc);
        assert_eq!(r.loss_of_lock, Some(5));
        assert_eq!(r.loss_by, Some("code"));
        assert_eq!(r.code_fail_counter_max, 2);
        assert_eq!(r.code_lock_failures, 4);
        // The counter never goes below zero: passes first bank nothing.
        let cn0 = [0.0, 30.0, 30.0, 30.0, 20.0, 20.0, 30.0, 20.0, 20.0];
        let r = replay_lock_detector(&t, &[1; 9], &lock, &cn0, fs, &tc);
        assert_eq!(r.loss_of_lock, Some(8), "{r:?}");
        // The pull-in transitory: with pull_in_time_s = 2 nothing is judged before floor(Δt) > 2 s.
        tc.pull_in_time_s = 2.0;
        let r = replay_lock_detector(&t, &[1; 9], &lock, &[20.0; 9], fs, &tc);
        assert_eq!((r.judged_records, r.loss_of_lock), (3, Some(5)));
        // C/N0 exactly at cn0_min and a lock test exactly at carrier_lock_th pass (strict <).
        tc.pull_in_time_s = 0.0;
        let r = replay_lock_detector(&t, &[1; 9], &[0.7; 9], &[25.0; 9], fs, &tc);
        assert_eq!((r.carrier_lock_failures, r.code_lock_failures, r.loss_of_lock), (0, 0, None));
        // A record standing for 20/N = 2 calls counts twice: fail, fail → counter 2, 4 > 2 at the 2nd record.
        let cn0 = [0.0, 20.0, 20.0, 30.0, 30.0, 30.0, 30.0, 30.0, 30.0];
        let r = replay_lock_detector(&t, &[2; 9], &[1.0; 9], &cn0, fs, &tc);
        assert_eq!((r.loss_of_lock, r.code_fail_counter_max, r.code_lock_failures), (Some(2), 2, 2));
        // Passes bank as many: fail ×2, pass ×2 (back to 0), fail ×2 = 2, never above 2.
        let cn0 = [0.0, 20.0, 30.0, 20.0, 30.0, 30.0, 30.0, 30.0, 30.0];
        let r = replay_lock_detector(&t, &[2; 9], &[1.0; 9], &cn0, fs, &tc);
        assert_eq!((r.loss_of_lock, r.code_fail_counter_max), (None, 2));
    }

    #[test]
    fn resampling_is_exact_for_cubics_and_skips_gaps() {
        let s = settings();
        let tracks = vec![TrackSummary {
            file: String::new(),
            layout: String::new(),
            channel: 0,
            prn: 1,
            start_s: 0.0,
            switch_s: Some(0.0),
            end_s: 1.0,
            records: 0,
            modelled_records: 0,
            good_records: 0,
            lock: replay_lock_detector(&[], &[], &[], &[], 1.0, &TrackingConf::defaults()),
            fate: TrackFate::Used,
            lock_loss_s: None,
            mean_cn0_dbhz: 40.0,
            used: true,
            reason: "used".into(),
        }];
        // Records at 0.007 + k·0.02 except one dropped; φ a cubic in t.
        let f = |t: f64| 0.1 + 2.0 * t - 3.0 * t * t + 1.5 * t * t * t;
        let rows: Vec<ImportedRow> = (0..30)
            .filter(|&k| k != 20)
            .map(|k| {
                let t = 0.007 + 0.02 * k as f64;
                ImportedRow {
                    t_s: t,
                    channel: 0,
                    prn: 1,
                    cn0_dbhz: 40.0,
                    phase_err_rad: f(t),
                    lock_test: 1.0,
                    symbols: 20,
                    track: 0,
                    input_phase_rad: None,
                }
            })
            .collect();
        let imp = Imported { rows, tracks, interval_s: s.interval_s() };
        let g = resample(&imp, 0.02);
        // Interior points with two neighbours on each side are exact for a cubic.
        for r in &g {
            let j = (r.t_s / 0.02).round() as i64;
            assert!((r.t_s - j as f64 * 0.02).abs() < 1e-15);
            let near_gap = (18..=22).contains(&j) || j <= 1 || j >= 28;
            if !near_gap {
                assert!((r.phase_err_rad - f(r.t_s)).abs() < 1e-12, "{j}");
            }
        }
        // Grid points 0.40 and 0.42 fall in the gap left by the record at 0.407: none.
        assert!(g.iter().all(|r| (r.t_s - 0.40).abs() > 1e-9));
        assert_eq!(g.len(), 27);
    }

    #[test]
    fn csv_writers_go_through_the_tracking_writer() {
        let row = |t_s: f64, lock_test: f64| ImportedRow {
            t_s,
            channel: 1,
            prn: 31,
            cn0_dbhz: 52.60313415527344,
            phase_err_rad: -0.10144092814183144,
            lock_test,
            symbols: 20,
            track: 0,
            input_phase_rad: None,
        };
        let rows = [row(7.39735791015625, 0.9902583956718445), row(7.41735791015625, 1.0)];
        let text = String::from_utf8(write_imported_csv(Vec::new(), &rows).unwrap()).unwrap();
        // The bytes the former hand-written writer produced.
        let mut want = String::from("t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad,carrier_lock_test\n");
        for r in &rows {
            want += &format!("{},{},{},{},,{},{}\n", r.t_s, r.channel, r.prn, r.cn0_dbhz, r.phase_err_rad, r.lock_test);
        }
        assert_eq!(text, want);
        // Every number is checked finite, the extra column too.
        let e = write_imported_csv(Vec::new(), &[row(7.4, f64::NAN)]).unwrap_err();
        assert_eq!(e.kind(), std::io::ErrorKind::InvalidInput);
        assert!(e.to_string().contains("carrier_lock_test"), "{e}");
        let grid = |cn0_dbhz| gsens_io::TrackingRow {
            t_s: 0.02,
            channel: 0,
            prn: 1,
            cn0_dbhz,
            elev_deg: None,
            phase_err_rad: -0.25,
        };
        let e = gsens_io::write_tracking_csv(Vec::new(), &[grid(f64::INFINITY)]).unwrap_err();
        assert!(e.to_string().contains("cn0_dbhz"), "{e}");
        let text = gsens_io::write_tracking_csv(Vec::new(), &[grid(40.5)]).unwrap();
        assert_eq!(text, b"t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad\n0.02,0,1,40.5,,-0.25\n");
    }
}
