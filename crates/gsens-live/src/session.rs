//! The live session: the data received so far, the batch estimate on it, and
//! the view the screen draws.

use std::collections::{BTreeMap, VecDeque};

use gsens_calib::{
    Calibration, IdentifiedLoop, LoopResolution, Measurement, ObservationOutcome, Outcome, PipelineSettings,
    ResultDocument, Warning, calibrate_logs,
};
use gsens_io::{Carrier, ImuSeries, TrackingLog, TrackingRecord, TrackingRow};
use gsens_ublox::{UbxLog, UbxStream};

use crate::guidance::{Instruction, LoopBand, Protocol, Situation, instruct};
use crate::input::{Input, Notice};
use crate::motion::{MotionWindow, Shaking};
use crate::stream::{Epoch, EpochAverager, StreamEstimate};
use crate::ubx::UbxOptions;

/// The IMU's index in a session's per-stream counts.
const IMU_STREAM: usize = 0;
/// The tracking's index in a session's per-stream counts.
const TRACKING_STREAM: usize = 1;

/// How a live session runs.
#[derive(Debug, Clone)]
pub struct LiveConfig {
    /// The batch pipeline's settings (the same as `gsens estimate`'s).
    pub settings: PipelineSettings,
    /// The session ends when every axis's σ is at most this \[Hz/(m/s²)\].
    pub target_sigma_hz_per_mps2: f64,
    /// Rest wanted at the start \[s\]. Default 5 s: the loop's settling from
    /// acquisition (a few 1/(ζωn), 0.25 s for the paper's loop) and several
    /// shaking periods of at-rest level to compare the shaking with.
    pub rest_s: f64,
    /// The batch estimate is re-run every this many seconds of data \[s\]. Default 5 s.
    pub batch_every_s: f64,
    /// No batch estimate before this much data \[s\]. Default 15 s: the rest
    /// plus about ten periods of shaking on the first axis.
    pub min_batch_data_s: f64,
    /// The motion window: how far back the shaking is judged \[s\]. Default 4 s
    /// (between three and four periods at the paper's 1.1 s).
    pub motion_window_s: f64,
    /// An axis counts as shaken above this RMS \[m/s²\]. Default 0.2 m/s²:
    /// hand shaking for a calibration is 1–3 m/s² peak, a consumer MEMS
    /// accelerometer at rest 0.01–0.05 m/s² RMS at 40 Hz. Guidance only: the
    /// estimate uses every sample.
    pub shake_threshold_mps2: f64,
}

impl LiveConfig {
    /// The defaults with these pipeline settings and target.
    pub fn new(settings: PipelineSettings, target_sigma_hz_per_mps2: f64) -> Self {
        LiveConfig {
            settings,
            target_sigma_hz_per_mps2,
            rest_s: 5.0,
            batch_every_s: 5.0,
            min_batch_data_s: 15.0,
            motion_window_s: 4.0,
            shake_threshold_mps2: 0.2,
        }
    }
}

/// The tracking records received: the six columns of each, and beside them
/// the optional columns of the session's log, those of its first record
/// (each empty where the log lacks it; the session refuses records with
/// other columns).
#[derive(Debug, Clone, Default)]
struct Records {
    rows: Vec<TrackingRow>,
    carriers: Vec<Carrier>,
    nco_phase_cycles: Vec<f64>,
    nco_freq_hz: Vec<f64>,
    /// The columns of the first record ([`TrackingRecord::header`]).
    columns: Option<Vec<&'static str>>,
}

impl Records {
    fn push(&mut self, r: &TrackingRecord) {
        self.columns.get_or_insert_with(|| r.header());
        self.rows.push(r.row);
        self.carriers.extend(r.carrier);
        self.nco_phase_cycles.extend(r.nco_phase_cycles);
        self.nco_freq_hz.extend(r.nco_freq_hz);
    }

    fn record(&self, i: usize) -> TrackingRecord {
        TrackingRecord {
            row: self.rows[i],
            carrier: self.carriers.get(i).copied(),
            nco_phase_cycles: self.nco_phase_cycles.get(i).copied(),
            nco_freq_hz: self.nco_freq_hz.get(i).copied(),
        }
    }

    /// The first `n` records.
    fn first(&self, n: usize) -> Records {
        let cut = |v: &Vec<f64>| v[..n.min(v.len())].to_vec();
        Records {
            rows: self.rows[..n].to_vec(),
            carriers: self.carriers[..n.min(self.carriers.len())].to_vec(),
            nco_phase_cycles: cut(&self.nco_phase_cycles),
            nco_freq_hz: cut(&self.nco_freq_hz),
            columns: self.columns.clone(),
        }
    }
}

/// A batch estimate to run, on a copy of the data received so far (in any
/// thread: the session goes on receiving meanwhile).
#[derive(Debug, Clone)]
pub struct BatchJob {
    /// A UBX stream's log so far (or why none), with how it is calibrated;
    /// `None` for tracking records.
    observed: Option<(Result<Box<UbxLog>, String>, UbxOptions, bool)>,
    records: Records,
    imu: ImuSeries,
    settings: PipelineSettings,
    data_end_s: f64,
    shaken_s: [f64; 3],
    epochs: Vec<Epoch>,
}

impl BatchJob {
    /// Seconds of data the job covers, up to its last IMU sample.
    pub fn data_end_s(&self) -> f64 {
        self.data_end_s
    }

    /// Runs `gsens_calib::calibrate_logs` on the job's data, then streams
    /// the job's epochs again under the loop and IMU time offset the
    /// estimate settled on (the session catches that stream up to its
    /// newest epoch in [`LiveSession::apply`]).
    pub fn run(self) -> BatchResult {
        if let Some((log, options, esf_imu)) = self.observed {
            // The loop identified from the log, as `gsens estimate --ubx` calibrates it.
            let outcome = log.and_then(|log| {
                let imu = if esf_imu { &log.imu } else { &self.imu };
                gsens_calib::calibrate_observations(&log.observations, imu, &self.settings, options.record)
                    .map(|o| BatchOutcome::Observations(Box::new(o)))
                    .map_err(|e| e.to_string())
            });
            return BatchResult { data_end_s: self.data_end_s, shaken_s: self.shaken_s, outcome, stream: None };
        }
        let records = (0..self.records.rows.len()).map(|i| self.records.record(i));
        let outcome = TrackingLog::from_records("received tracking rows", records)
            .map_err(|e| e.to_string())
            .and_then(|log| {
                calibrate_logs(&log, &self.imu, "received IMU samples", &self.settings).map_err(|e| e.to_string())
            })
            .map(|o| BatchOutcome::Tracking(Box::new(o)));
        let stream = outcome.as_ref().ok().and_then(BatchOutcome::tracking).map(|o| {
            let mut stream = StreamEstimate::new(o.calibration.settings, o.session.imu_time_offset_s);
            stream.advance(&self.epochs, &self.imu);
            stream
        });
        BatchResult { data_end_s: self.data_end_s, shaken_s: self.shaken_s, outcome, stream }
    }
}

/// A batch estimate's result.
#[derive(Debug, Clone)]
pub struct BatchResult {
    /// The data it covers \[s\].
    pub data_end_s: f64,
    /// Seconds each axis had been shaken at that point.
    pub shaken_s: [f64; 3],
    /// The calibration, or why there is none yet.
    pub outcome: Result<BatchOutcome, String>,
    /// The job's epochs streamed under the estimate's loop and time offset.
    pub stream: Option<StreamEstimate>,
}

impl BatchResult {
    /// The result document of the calibration.
    pub fn document(&self) -> Option<ResultDocument> {
        self.outcome.as_ref().ok().map(BatchOutcome::document)
    }
}

/// A batch estimate: of tracking records (`gsens_calib::calibrate_logs`), or
/// of a carrier phase and Doppler log with its loop identified
/// (`gsens_calib::calibrate_observations`).
#[derive(Debug, Clone)]
pub enum BatchOutcome {
    /// From tracking records.
    Tracking(Box<Outcome>),
    /// From a UBX log's RXM-RAWX.
    Observations(Box<ObservationOutcome>),
}

impl BatchOutcome {
    /// The estimate the result document gives.
    pub fn calibration(&self) -> &Calibration {
        match self {
            BatchOutcome::Tracking(o) => &o.calibration,
            BatchOutcome::Observations(o) => &o.calibration,
        }
    }

    /// The result document.
    pub fn document(&self) -> ResultDocument {
        match self {
            BatchOutcome::Tracking(o) => o.document(None),
            BatchOutcome::Observations(o) => o.document(None),
        }
    }

    /// The estimate from tracking records, if it is one.
    pub fn tracking(&self) -> Option<&Outcome> {
        match self {
            BatchOutcome::Tracking(o) => Some(o),
            BatchOutcome::Observations(_) => None,
        }
    }

    /// The receiver's loop identified from a log, if it is one.
    pub fn identified_loop(&self) -> Option<&IdentifiedLoop> {
        match self {
            BatchOutcome::Tracking(_) => None,
            BatchOutcome::Observations(o) => Some(&o.identified.identified),
        }
    }
}

/// What became of a record given to [`LiveSession::push`].
#[derive(Debug, Clone, PartialEq)]
pub struct Pushed {
    /// The record is part of the session's data (else refused).
    pub used: bool,
    /// What to tell the user, if anything.
    pub notice: Option<Notice>,
}

/// One axis's progress.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct AxisProgress {
    /// Seconds the axis has been shaken (alone, above the threshold).
    pub shaken_s: f64,
    /// Γ̂ of the latest batch estimate \[Hz/(m/s²)\] (None: none yet, or unobservable).
    pub gamma_hz_per_mps2: Option<f64>,
    /// Its σ \[Hz/(m/s²)\].
    pub sigma_hz_per_mps2: Option<f64>,
    /// Whether the latest batch found the axis observable.
    pub observable: bool,
    /// Γ̂ of the streamed estimate, at the newest epoch \[Hz/(m/s²)\] (None:
    /// no estimate yet, or the axis not in its solve: not shaken enough).
    pub now_gamma_hz_per_mps2: Option<f64>,
    /// Its σ \[Hz/(m/s²)\]: the stream's white-noise σ scaled by the latest
    /// batch estimate's ratio of its σ to its white-noise σ on the axis (the
    /// residuals' colour, which the stream cannot see), unscaled before.
    pub now_sigma_hz_per_mps2: Option<f64>,
    /// σ at most the target.
    pub meets_target: bool,
    /// Seconds of shaking still needed for the target, from σ ∝ 1/√(shaken time).
    pub more_s: Option<f64>,
}

/// A channel as last received.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChannelStatus {
    /// Receiver channel.
    pub channel: u32,
    /// Satellite PRN.
    pub prn: u32,
    /// Latest C/N0 \[dB-Hz\].
    pub cn0_dbhz: f64,
    /// Latest phase error \[rad\].
    pub phase_err_rad: f64,
    /// Time of its latest row \[s\].
    pub last_t_s: f64,
    /// Rows received.
    pub rows: u64,
    /// A row within the last second of the tracking stream.
    pub tracking: bool,
}

/// Everything the screen shows, at one moment.
#[derive(Debug, Clone, PartialEq)]
pub struct LiveView {
    /// Latest time received on both streams \[s\].
    pub data_t_s: f64,
    /// Seconds of data received.
    pub data_s: f64,
    /// The instruction.
    pub instruction: Instruction,
    /// Per axis.
    pub axes: [AxisProgress; 3],
    /// The target σ \[Hz/(m/s²)\].
    pub target_sigma_hz_per_mps2: f64,
    /// The shaking now.
    pub shaking: Shaking,
    /// The loop's band.
    pub band: LoopBand,
    /// Largest |φ| of the channel average over the motion window \[rad\].
    pub peak_phase_rad: f64,
    /// The discriminator's linear range \[rad\].
    pub range_rad: f64,
    /// The channels.
    pub channels: Vec<ChannelStatus>,
    /// The verdict on the latest batch estimate.
    pub batch: Option<BatchVerdict>,
    /// Why the latest batch estimate failed, if it did.
    pub batch_error: Option<String>,
    /// The latest notices, and how many there were in all.
    pub notices: (Vec<String>, u64),
    /// IMU samples and tracking rows received.
    pub received: (u64, u64),
    /// A UBX stream as read so far; `None` for tracking records.
    pub ubx: Option<UbxStatus>,
}

/// What a UBX stream brought so far, and the loop the latest batch
/// estimate identified from it.
#[derive(Debug, Clone, PartialEq)]
pub struct UbxStatus {
    /// Bytes received.
    pub bytes: u64,
    /// Frames with a valid checksum.
    pub frames: u64,
    /// Frames dropped for a bad checksum.
    pub checksum_failures: u64,
    /// Frames, messages and samples skipped, for any reason.
    pub skipped: u64,
    /// RXM-RAWX epochs.
    pub epochs: u64,
    /// Measurements of the latest epoch with a valid carrier phase.
    pub tracks: u64,
    /// The loop the latest batch estimate identified.
    pub identified_loop: Option<IdentifiedLoop>,
}

impl UbxStatus {
    /// One line of it: the tracks with a carrier phase at the latest
    /// epoch, the frames read, dropped for their checksum and skipped, and
    /// the loop identified (its order and Bn ± its relative σ, or the bound).
    pub fn summary(&self) -> String {
        let identified = match &self.identified_loop {
            Some(l) => {
                let bn = match l.resolution {
                    LoopResolution::Resolved => format!("Bn {:.2} Hz ± {:.0} %", l.bn_hz, 100.0 * l.sigma_ln_bn),
                    LoopResolution::Wide => format!("Bn ≥ {:.1} Hz", l.bn_hz),
                    _ => format!("Bn ≤ {:.2} Hz", l.bn_hz),
                };
                format!(" | loop: order {}, {bn}", l.order)
            }
            None => String::new(),
        };
        format!(
            "{} tracks, {} frames, {} bad checksums, {} skipped{identified}",
            self.tracks, self.frames, self.checksum_failures, self.skipped
        )
    }
}

/// A UBX stream a session reads: the stream, how it is calibrated, and
/// whether its ESF messages are the IMU.
#[derive(Debug, Clone)]
struct Observed {
    stream: UbxStream,
    options: UbxOptions,
    esf_imu: bool,
}

/// What the view shows of the latest batch estimate: (data end, trustworthy, warnings), or its error.
/// What the screen shows of a batch estimate, made once from its result
/// document (which is not cheap).
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct BatchVerdict {
    /// The data it covers, up to \[s\].
    pub data_end_s: f64,
    /// What the estimate is made from.
    pub measurement: Measurement,
    /// Whether it is trustworthy.
    pub trustworthy: bool,
    /// The codes that make it untrustworthy.
    pub untrusted_codes: Vec<&'static str>,
    /// Its warnings.
    pub warnings: Vec<Warning>,
}

impl BatchVerdict {
    /// The verdict on an estimate from `measurement` covering data up to
    /// `data_end_s` \[s\] that raised `warnings` (in the document's order):
    /// trustworthy when none of them counts against it
    /// ([`gsens_calib::untrusted_codes`]).
    pub fn new(data_end_s: f64, measurement: Measurement, warnings: Vec<Warning>) -> Self {
        let untrusted_codes = gsens_calib::untrusted_codes(&warnings, measurement);
        BatchVerdict { data_end_s, measurement, trustworthy: untrusted_codes.is_empty(), untrusted_codes, warnings }
    }
}

type BatchSummary = (Option<BatchVerdict>, Option<String>);

/// The data received so far and what is made of it.
#[derive(Debug, Clone)]
pub struct LiveSession {
    config: LiveConfig,
    band: LoopBand,
    imu: ImuSeries,
    records: Records,
    channels: BTreeMap<u32, ChannelStatus>,
    /// Channels seen at the latest tracking time stamp.
    epoch_channels: Vec<u32>,
    motion: MotionWindow,
    /// Channel average φ over the motion window: (t, sum, n) per epoch.
    phase_window: VecDeque<(f64, f64, u32)>,
    first_t_s: Option<f64>,
    shaken_s: [f64; 3],
    /// Per axis, seconds shaken at the slow and at the fast rate
    /// ([`LoopBand::rate_of`]).
    shaken_by_rate_s: [[f64; 2]; 3],
    rest_s: f64,
    rest_done: bool,
    last_imu_t_s: Option<f64>,
    last_batch_end_s: f64,
    batch: Option<BatchResult>,
    /// The latest batch's data end, trustworthiness and warnings, or its error.
    batch_summary: BatchSummary,
    notices: VecDeque<String>,
    notices_total: u64,
    /// Records refused in a row per stream (`IMU_STREAM`,
    /// `TRACKING_STREAM`): one notice per burst.
    refused: [u64; 2],
    averager: EpochAverager,
    /// The channel average of every completed tracking epoch.
    epochs: Vec<Epoch>,
    stream: StreamEstimate,
    /// The UBX stream, when the session reads one instead of tracking records.
    observed: Option<Box<Observed>>,
}

impl LiveSession {
    /// A session with `config`; errors when its receiver loop is invalid.
    pub fn new(config: LiveConfig) -> Result<Self, gsens_core::LoopError> {
        let band = LoopBand::of(&config.settings.estimate.receiver_loop)?;
        let motion = MotionWindow::new(config.motion_window_s, config.shake_threshold_mps2);
        let selection = &config.settings.selection;
        let averager = EpochAverager::new(selection.max_channels, selection.min_cn0_dbhz);
        let offset_s = match config.settings.time_offset {
            gsens_calib::TimeOffset::Fixed { imu_time_offset_s } => imu_time_offset_s,
            gsens_calib::TimeOffset::Auto { .. } => 0.0,
        };
        let stream = StreamEstimate::new(config.settings.estimate, offset_s);
        Ok(LiveSession {
            config,
            band,
            imu: ImuSeries::default(),
            records: Records::default(),
            channels: BTreeMap::new(),
            epoch_channels: Vec::new(),
            motion,
            phase_window: VecDeque::with_capacity(256),
            first_t_s: None,
            shaken_s: [0.0; 3],
            shaken_by_rate_s: [[0.0; 2]; 3],
            rest_s: 0.0,
            rest_done: false,
            last_imu_t_s: None,
            last_batch_end_s: f64::NEG_INFINITY,
            batch: None,
            batch_summary: (None, None),
            notices: VecDeque::with_capacity(8),
            notices_total: 0,
            refused: [0; 2],
            averager,
            epochs: Vec::with_capacity(4096),
            stream,
            observed: None,
        })
    }

    /// A session of a UBX stream named `source_name` (RXM-RAWX instead of
    /// tracking records, calibrated with the loop identified under
    /// `options`), its IMU the stream's ESF messages when `esf_imu`, else
    /// IMU records pushed beside it.
    pub fn with_ubx(
        config: LiveConfig,
        source_name: &str,
        options: UbxOptions,
        esf_imu: bool,
    ) -> Result<Self, gsens_core::LoopError> {
        let mut session = LiveSession::new(config)?;
        session.observed = Some(Box::new(Observed { stream: UbxStream::new(source_name), options, esf_imu }));
        Ok(session)
    }

    /// Takes bytes of the UBX stream, in the pieces they arrived in;
    /// returns the accelerometer samples they completed (when the stream's
    /// ESF messages are the IMU), to be pushed as IMU records
    /// ([`LiveSession::push`]). Nothing for a session of tracking records.
    pub fn push_ubx(&mut self, bytes: &[u8]) -> Vec<Input> {
        let Some(o) = self.observed.as_mut() else { return Vec::new() };
        o.stream.push(bytes);
        if let Some((t_s, _)) = o.stream.latest_epoch() {
            self.first_t_s.get_or_insert(t_s);
        }
        if !o.esf_imu {
            return Vec::new();
        }
        let imu = o.stream.take_imu(&o.options.settings);
        imu.t_s.iter().zip(&imu.accel_mps2).map(|(&t_s, &accel_mps2)| Input::Imu { t_s, accel_mps2 }).collect()
    }

    /// The UBX stream, when the session reads one.
    pub fn ubx_stream(&self) -> Option<&UbxStream> {
        self.observed.as_ref().map(|o| &o.stream)
    }

    /// How the session's UBX stream is read and calibrated, and whether its
    /// ESF messages are the IMU.
    pub fn ubx_options(&self) -> Option<(UbxOptions, bool)> {
        self.observed.as_ref().map(|o| (o.options, o.esf_imu))
    }

    /// The configuration.
    pub fn config(&self) -> &LiveConfig {
        &self.config
    }

    /// The shaking protocol guided: one rate when the stated loop is taken
    /// as exact (loop check off, or a tolerance of 0), two otherwise.
    pub fn protocol(&self) -> Protocol {
        let s = &self.config.settings;
        let exact = s.loop_identification == gsens_calib::LoopIdentificationMode::Off || s.loop_tolerance == Some(0.0);
        if exact && s.loop_stated { Protocol::OneRate } else { Protocol::TwoRates }
    }

    /// Records a notice (kept: the latest few for the screen, the count of all).
    pub fn notice(&mut self, notice: &Notice) {
        if self.notices.len() == 5 {
            self.notices.pop_front();
        }
        self.notices.push_back(notice.to_string());
        self.notices_total += 1;
    }

    /// Takes one record from `source` (line `line`). A record that cannot be
    /// used (time going back, a channel twice at one time stamp) is refused
    /// with a notice, once per burst of such records; the first record used
    /// after a burst brings the burst's count.
    pub fn push(&mut self, source: &str, line: u64, input: Input) -> Pushed {
        let used_before = (self.imu.len(), self.records.rows.len());
        let notice = self.take(source, line, input);
        Pushed { used: (self.imu.len(), self.records.rows.len()) != used_before, notice }
    }

    fn take(&mut self, source: &str, line: u64, input: Input) -> Option<Notice> {
        let t = input.t_s();
        let (stream, result) = match input {
            Input::Imu { t_s, accel_mps2 } => (IMU_STREAM, self.take_imu(t_s, accel_mps2)),
            Input::Tracking(record) => (TRACKING_STREAM, self.take_tracking(record)),
        };
        let notice = match result {
            Err(message) => self.refuse(stream, source, line, message),
            Ok(()) => {
                self.first_t_s.get_or_insert(t);
                self.end_burst(stream, source, line)
            }
        };
        self.maybe_notice(notice)
    }

    /// A refused record of `stream`: the notice, for the first of a burst only.
    fn refuse(&mut self, stream: usize, source: &str, line: u64, message: String) -> Option<Notice> {
        self.refused[stream] += 1;
        (self.refused[stream] == 1).then(|| Notice { source: source.to_string(), line, message })
    }

    /// A used record of `stream`: the notice of the burst of refused records
    /// it ends, when there were more than the one already named.
    fn end_burst(&mut self, stream: usize, source: &str, line: u64) -> Option<Notice> {
        let n = std::mem::take(&mut self.refused[stream]);
        (n > 1).then(|| Notice {
            source: source.to_string(),
            line,
            message: format!("{} more records refused before this one", n - 1),
        })
    }

    /// Takes an IMU sample, or says why not (its time not after the previous
    /// sample's).
    fn take_imu(&mut self, t_s: f64, accel_mps2: [f64; 3]) -> Result<(), String> {
        if let Some(last) = self.last_imu_t_s.filter(|&l| t_s <= l) {
            return Err(format!(
                "IMU time {t_s} s not after the previous sample's {last} s: not used (kept in the raw \
                 log; a restarted logger needs a new `gsens live`)"
            ));
        }
        let dt = self.last_imu_t_s.map_or(0.0, |l| t_s - l);
        self.last_imu_t_s = Some(t_s);
        self.imu.t_s.push(t_s);
        self.imu.accel_mps2.push(accel_mps2);
        self.motion.push(t_s, accel_mps2);
        self.stream.advance(&self.epochs, &self.imu);
        self.count_motion(dt);
        Ok(())
    }

    /// Adds the `dt` since the previous IMU sample to the shaken time of the
    /// axis (and rate) shaken now, or to the rest, from the motion window's
    /// judgement at this sample; a gap of a second or more counts nowhere.
    fn count_motion(&mut self, dt: f64) {
        let shaking = self.motion.shaking();
        match shaking.axis {
            Some(i) if dt < 1.0 => {
                self.shaken_s[i] += dt;
                if let Some(f_hz) = shaking.frequency_hz {
                    self.shaken_by_rate_s[i][self.band.rate_of(f_hz)] += dt;
                }
                self.rest_done = true;
            }
            None if !shaking.several_axes && dt < 1.0 => self.rest_s += dt,
            _ => {}
        }
    }

    /// Takes a tracking record, or says why not (its time before the
    /// previous row's, its channel already seen at its time stamp, or
    /// columns other than the first record's).
    fn take_tracking(&mut self, record: TrackingRecord) -> Result<(), String> {
        let row = record.row;
        if let Some(first) = &self.records.columns {
            let columns = record.header();
            if columns != *first {
                return Err(format!(
                    "a tracking row with the columns {}, not the first row's {}: not used (kept in the raw log; a \
                     logger restarted with other columns needs a new `gsens live`)",
                    columns.join(","),
                    first.join(",")
                ));
            }
        }
        let last_t = self.records.rows.last().map(|r| r.t_s);
        if let Some(last) = last_t.filter(|&l| row.t_s < l) {
            return Err(format!(
                "tracking time {} s before the previous row's {last} s: not used (kept in the raw log)",
                row.t_s
            ));
        }
        if last_t != Some(row.t_s) {
            self.epoch_channels.clear();
            self.close_phase_epoch(row.t_s);
        }
        if self.epoch_channels.contains(&row.channel) {
            return Err(format!("channel {} twice at {} s: the second row is not used", row.channel, row.t_s));
        }
        self.epoch_channels.push(row.channel);
        if let Some(back) = self.phase_window.back_mut() {
            back.1 += row.phase_err_rad;
            back.2 += 1;
        }
        self.update_channel(&row);
        // The channels' average on L1's scale, as the batch path averages them.
        let on_l1 = TrackingRow { phase_err_rad: row.phase_err_rad * record.carrier_or_l1().scale_to_l1(), ..row };
        if let Some(epoch) = self.averager.row(&on_l1) {
            self.epochs.push(epoch);
            self.stream.advance(&self.epochs, &self.imu);
        }
        self.records.push(&record);
        Ok(())
    }

    /// The channel's status with `row`: its PRN, C/N0 and phase error now,
    /// one row more.
    fn update_channel(&mut self, row: &TrackingRow) {
        let c = self.channels.entry(row.channel).or_insert(ChannelStatus {
            channel: row.channel,
            prn: row.prn,
            cn0_dbhz: row.cn0_dbhz,
            phase_err_rad: row.phase_err_rad,
            last_t_s: row.t_s,
            rows: 0,
            tracking: true,
        });
        c.prn = row.prn;
        c.cn0_dbhz = row.cn0_dbhz;
        c.phase_err_rad = row.phase_err_rad;
        c.last_t_s = row.t_s;
        c.rows += 1;
    }

    fn maybe_notice(&mut self, n: Option<Notice>) -> Option<Notice> {
        if let Some(n) = &n {
            self.notice(n);
        }
        n
    }

    /// Starts the channel average of a new tracking epoch at `t_s`; drops
    /// epochs older than the motion window.
    fn close_phase_epoch(&mut self, t_s: f64) {
        self.phase_window.push_back((t_s, 0.0, 0));
        while let Some(&(t0, _, _)) = self.phase_window.front() {
            if t_s - t0 > self.config.motion_window_s {
                self.phase_window.pop_front();
            } else {
                break;
            }
        }
    }

    /// The latest time both streams reached \[s\].
    pub fn data_t_s(&self) -> f64 {
        let observed = match &self.observed {
            Some(o) => o.stream.latest_epoch().map(|(t_s, _)| t_s),
            None => self.records.rows.last().map(|r| r.t_s),
        };
        match (self.last_imu_t_s, observed) {
            (Some(a), Some(r)) => a.min(r),
            _ => f64::NEG_INFINITY,
        }
    }

    fn data_s(&self) -> f64 {
        self.first_t_s.map_or(0.0, |t0| (self.data_t_s() - t0).max(0.0))
    }

    /// A batch estimate when one is due: `batch_every_s` of data since the
    /// last, and at least `min_batch_data_s` in all.
    pub fn batch_due(&mut self) -> Option<BatchJob> {
        let end = self.data_t_s();
        if self.data_s() < self.config.min_batch_data_s || end - self.last_batch_end_s < self.config.batch_every_s {
            return None;
        }
        self.last_batch_end_s = end;
        Some(self.job())
    }

    /// The batch estimate on everything received (the session's final result).
    pub fn final_job(&self) -> BatchJob {
        self.job()
    }

    fn job(&self) -> BatchJob {
        let end = self.last_imu_t_s.unwrap_or(f64::NEG_INFINITY);
        // Rows come in time order: those up to the end are the first.
        let records = self.records.first(self.records.rows.partition_point(|r| r.t_s <= end));
        let epochs = self.epochs.iter().take_while(|e| e.0 <= end).copied().collect();
        let observed = self.observed.as_ref().map(|o| {
            let log = o.stream.snapshot(&o.options.settings).map(Box::new).map_err(|e| e.to_string());
            (log, o.options, o.esf_imu)
        });
        BatchJob {
            observed,
            epochs,
            records,
            imu: self.imu.clone(),
            settings: self.config.settings.clone(),
            data_end_s: end,
            shaken_s: self.shaken_s,
        }
    }

    /// Takes a batch estimate's result (a newer one replaces an older one).
    pub fn apply(&mut self, result: BatchResult) {
        if self.batch.as_ref().is_some_and(|b| b.data_end_s > result.data_end_s) {
            return;
        }
        if let Ok(o) = &result.outcome
            && let Ok(band) = LoopBand::of(&o.calibration().loop_used)
        {
            self.band = band;
        }
        let mut result = result;
        if let Some(mut stream) = result.stream.take() {
            stream.advance(&self.epochs, &self.imu);
            self.stream = stream;
        }
        // What the screen shows of it, made once (the result document is not cheap).
        self.batch_summary = match &result.outcome {
            Ok(o) => {
                let doc = o.document();
                (Some(BatchVerdict::new(result.data_end_s, doc.measurement, doc.warnings)), None)
            }
            Err(e) => (None, Some(e.clone())),
        };
        self.batch = Some(result);
    }

    /// The latest batch result.
    pub fn batch(&self) -> Option<&BatchResult> {
        self.batch.as_ref()
    }

    /// Every axis meets the target σ in the latest batch estimate.
    pub fn target_met(&self) -> bool {
        self.axes().iter().all(|a| a.meets_target)
    }

    fn axes(&self) -> [AxisProgress; 3] {
        let target = self.config.target_sigma_hz_per_mps2;
        let mut axes = [AxisProgress::default(); 3];
        for i in 0..3 {
            let a = &mut axes[i];
            a.shaken_s = self.shaken_s[i];
            let Some(Ok(o)) = self.batch.as_ref().map(|b| &b.outcome) else { continue };
            let c = o.calibration();
            a.observable = c.observable[i];
            a.gamma_hz_per_mps2 = c.gamma_hz_per_mps2[i];
            a.sigma_hz_per_mps2 = c.sigma_hz_per_mps2[i];
            if let (true, Some(sigma)) = (a.observable, a.sigma_hz_per_mps2) {
                a.meets_target = sigma <= target;
                let then = self.batch.as_ref().map_or(0.0, |b| b.shaken_s[i]);
                // σ ∝ 1/√T: T·(σ/target)² in all, less what was shaken since.
                let needed = then * ((sigma / target).powi(2) - 1.0) - (a.shaken_s - then);
                a.more_s = Some(if a.meets_target { 0.0 } else { needed.max(1.0) });
            }
        }
        if let Some(now) = self.stream.estimate() {
            let sigma_white = now.sigma_hz_per_mps2();
            let calibration = self.batch.as_ref().and_then(|b| b.outcome.as_ref().ok()).map(BatchOutcome::calibration);
            for (i, a) in axes.iter_mut().enumerate() {
                if !sigma_white[i].is_finite() || now.epochs == 0 {
                    continue;
                }
                let colour = calibration
                    .and_then(|c| Some(c.sigma_hz_per_mps2[i]? / c.sigma_white_hz_per_mps2[i]?))
                    .filter(|r| r.is_finite() && *r > 0.0)
                    .unwrap_or(1.0);
                a.now_gamma_hz_per_mps2 = Some(now.gamma_hz_per_mps2[i]);
                a.now_sigma_hz_per_mps2 = Some(sigma_white[i] * colour);
            }
        }
        axes
    }

    /// The screen's view now.
    pub fn view(&self) -> LiveView {
        let shaking = self.motion.shaking();
        let axes = self.axes();
        let peak_phase_rad =
            self.phase_window.iter().filter(|e| e.2 > 0).map(|&(_, s, n)| (s / n as f64).abs()).fold(0.0, f64::max);
        let rest_more_s = if self.rest_done { 0.0 } else { (self.config.rest_s - self.rest_s).max(0.0) };
        // The batch estimate narrows it by the channels' noise; the guidance warns well before either.
        let range_rad = self.config.settings.estimate.discriminator.unambiguous_range_rad();
        let situation = Situation {
            data_s: self.data_s(),
            rest_more_s,
            shaken: shaking.axis.map(|a| (a, shaking.frequency_hz)),
            several_axes: shaking.several_axes,
            peak_phase_rad,
            range_rad,
            axes: axes.map(|a| (a.meets_target, a.more_s)),
            protocol: self.protocol(),
            shaken_by_rate_s: self.shaken_by_rate_s,
        };
        let latest_trk = self.records.rows.last().map_or(f64::NEG_INFINITY, |r| r.t_s);
        let channels =
            self.channels.values().map(|c| ChannelStatus { tracking: latest_trk - c.last_t_s <= 1.0, ..*c }).collect();
        let (batch, batch_error) = self.batch_summary.clone();
        LiveView {
            data_t_s: self.data_t_s(),
            data_s: situation.data_s,
            instruction: instruct(&situation, &self.band),
            axes,
            target_sigma_hz_per_mps2: self.config.target_sigma_hz_per_mps2,
            shaking,
            band: self.band,
            peak_phase_rad,
            range_rad,
            channels,
            batch,
            batch_error,
            notices: (self.notices.iter().cloned().collect(), self.notices_total),
            received: (self.imu.len() as u64, self.records.rows.len() as u64),
            ubx: self.ubx_status(),
        }
    }

    fn ubx_status(&self) -> Option<UbxStatus> {
        let s = &self.observed.as_ref()?.stream;
        let identified_loop = self.batch.as_ref().and_then(|b| b.outcome.as_ref().ok()?.identified_loop().cloned());
        Some(UbxStatus {
            bytes: s.received_bytes() as u64,
            frames: s.frames() as u64,
            checksum_failures: s.checksum_failures() as u64,
            skipped: s.skipped() as u64,
            epochs: s.epochs() as u64,
            tracks: s.latest_epoch().map_or(0, |(_, n)| n as u64),
            identified_loop,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn session() -> LiveSession {
        LiveSession::new(LiveConfig::new(PipelineSettings::default(), 1e-3)).unwrap()
    }

    fn row(t_s: f64, channel: u32, cn0_dbhz: f64) -> TrackingRecord {
        TrackingRecord::plain(TrackingRow {
            t_s,
            channel,
            prn: channel + 1,
            cn0_dbhz,
            elev_deg: None,
            phase_err_rad: 0.01,
        })
    }

    #[test]
    fn a_burst_is_named_by_its_first_record_and_counted_by_the_next_used_one() {
        let mut s = session();
        let first = s.refuse(TRACKING_STREAM, "trk", 7, "why".into()).unwrap();
        assert_eq!((first.source.as_str(), first.line, first.message.as_str()), ("trk", 7, "why"));
        assert!(s.refuse(TRACKING_STREAM, "trk", 8, "why".into()).is_none());
        assert!(s.refuse(TRACKING_STREAM, "trk", 9, "why".into()).is_none());
        // The other stream's burst is its own.
        assert!(s.end_burst(IMU_STREAM, "imu", 10).is_none());
        let count = s.end_burst(TRACKING_STREAM, "trk", 11).unwrap();
        assert_eq!((count.line, count.message.as_str()), (11, "2 more records refused before this one"));
        assert!(s.end_burst(TRACKING_STREAM, "trk", 12).is_none());
        // A burst of one needs no count.
        assert!(s.refuse(IMU_STREAM, "imu", 13, "why".into()).is_some());
        assert!(s.end_burst(IMU_STREAM, "imu", 14).is_none());
    }

    #[test]
    fn taking_records_refuses_what_cannot_be_used_and_keeps_each_channels_latest() {
        let mut s = session();
        assert!(s.take_imu(1.0, [0.0, 0.0, 9.81]).is_ok());
        let e = s.take_imu(1.0, [0.0, 0.0, 9.81]).unwrap_err();
        assert!(e.starts_with("IMU time 1 s not after the previous sample's 1 s"), "{e}");
        assert!(s.take_tracking(row(1.0, 0, 40.0)).is_ok() && s.take_tracking(row(1.0, 1, 41.0)).is_ok());
        assert_eq!(
            s.take_tracking(row(1.0, 1, 42.0)).unwrap_err(),
            "channel 1 twice at 1 s: the second row is not used"
        );
        assert!(s.take_tracking(row(1.025, 0, 43.0)).is_ok());
        let e = s.take_tracking(row(0.5, 0, 44.0)).unwrap_err();
        assert!(e.starts_with("tracking time 0.5 s before the previous row's 1.025 s"), "{e}");
        assert_eq!((s.imu.len(), s.records.rows.len()), (1, 3));
        let c = &s.channels[&0];
        assert_eq!((c.rows, c.cn0_dbhz, c.last_t_s, c.prn), (2, 43.0, 1.025, 1));
        assert_eq!((s.channels[&1].rows, s.channels[&1].cn0_dbhz), (1, 41.0));
    }
}
