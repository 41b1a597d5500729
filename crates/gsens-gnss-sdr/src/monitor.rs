//! GNSS-SDR's tracking monitor, received over UDP, as gsens tracking rows.
//!
//! With `TrackingMonitor.enable_monitor=true` GNSS-SDR sends every tracking
//! output of every channel to `TrackingMonitor.client_addresses` at
//! `TrackingMonitor.udp_port`, one UDP datagram per output, serialized with
//! protobuf (`TrackingMonitor.enable_protobuf`, on by default). In 0.0.17 a
//! datagram is an `Observables` message (field 1: repeated `GnssSynchro`)
//! holding one `GnssSynchro`; the schema is GNSS-SDR's
//! `docs/protobuf/gnss_synchro.proto` (package `gnss_sdr`, proto3). The
//! structs here mirror its field numbers and types, derived with prost by
//! hand (no protoc).
//!
//! # What a message holds (GPS L1 C/A, `dll_pll_veml_tracking`, 0.0.17)
//!
//! The tracking block emits an output only once it has synchronized to the
//! data bits, one per 20 ms bit (with or without extended integration), and
//! one more with `flag_valid_symbol_output = false` when it loses lock:
//!
//! - `prompt_i`, `prompt_q`: the prompt correlator summed over the 20 ms bit
//!   that just ended. With `Tracking_1C.extend_correlation_symbols=20` this
//!   is exactly the integration the narrow PLL's discriminator used, so
//!   φ = atan(Q/I) is, to float precision, 2π × the `carr_error_hz` of the
//!   tracking dump's record of the same integration. With shorter
//!   integrations it is the phase of the 20 ms sum (close to the mean of
//!   the discriminator outputs over the bit).
//! - `tracking_sample_counter`: the receiver's sample count at the end of
//!   the integration, read after the block consumed its last code period:
//!   the same number as the dump record's `PRN_start_sample_count` (checked
//!   on a real capture, `tests/monitor_capture.rs`).
//! - `fs`, `cn0_db_hz`, `prn`, `channel_id`, `system` ("G"), `signal` ("1C").
//!
//! # Conversion ([`to_row`])
//!
//! ```text
//! t_s           = (n − fs·20 ms/2)/fs              n = tracking_sample_counter: the middle of the 20 ms bit
//! phase_err_rad = atan(prompt_q/prompt_i)          θ_signal − θ_replica, the sign of the dump reader
//! cn0_dbhz      = cn0_db_hz,  channel = channel_id,  prn = prn,  elev_deg empty
//! ```
//!
//! `t_s` matches the dump reader's (n − Δn/2)/fs within half a sample (Δn
//! there is the counter step, which follows the code Doppler: 40 959 or
//! 40 960 samples at 2.048 Msps). Messages that are not GPS
//! L1 C/A, not valid (loss of lock), or hold non-finite or zero correlator
//! values are skipped and counted by reason ([`SkipReason`]).
//!
//! # The stream ([`MonitorStream`], [`MonitorReceiver`])
//!
//! GNSS-SDR 0.0.17's monitor block re-sends outputs it has already sent (a
//! capture of a 26 s run held 221 703 datagrams for 1 969 distinct outputs,
//! each old output repeated up to 239 times, out of order). The stream keeps
//! per channel the last sample counter and drops anything not newer as a
//! repeat (counted). A step larger than the expected one (decimation × 20 ms)
//! is reported as a gap; a new PRN on a channel, or a channel's next output
//! after a loss of lock, as a restart.

use std::collections::BTreeMap;
use std::io::{self, Write};
use std::net::{SocketAddr, ToSocketAddrs, UdpSocket};
use std::time::Duration;

use prost::Message;
use serde::Serialize;

use gsens_io::TrackingRow;

use crate::import::{ImportedRow, resample_rows};

/// Length of the GPS L1 C/A data bit the monitor's prompt spans \[ms\].
pub const BIT_MS: f64 = 20.0;

/// One tracking output of one channel (GNSS-SDR's `gnss_sdr.GnssSynchro`).
#[derive(Clone, PartialEq, Message)]
pub struct GnssSynchro {
    /// Constellation: "G" GPS, "R" GLONASS, "S" SBAS, "E" Galileo, "C" BeiDou.
    #[prost(string, tag = "1")]
    pub system: String,
    /// Signal: "1C" GPS L1 C/A, "1B" Galileo E1, "2S" GPS L2C, "L5", "5X", …
    #[prost(string, tag = "2")]
    pub signal: String,
    /// Satellite PRN.
    #[prost(uint32, tag = "3")]
    pub prn: u32,
    /// Receiver channel.
    #[prost(int32, tag = "4")]
    pub channel_id: i32,
    /// Acquisition's code delay \[samples\].
    #[prost(double, tag = "5")]
    pub acq_delay_samples: f64,
    /// Acquisition's Doppler \[Hz\].
    #[prost(double, tag = "6")]
    pub acq_doppler_hz: f64,
    /// Sample count at the acquisition.
    #[prost(uint64, tag = "7")]
    pub acq_samplestamp_samples: u64,
    /// Acquisition's Doppler bin \[Hz\].
    #[prost(uint32, tag = "8")]
    pub acq_doppler_step: u32,
    /// Whether the acquisition succeeded.
    #[prost(bool, tag = "9")]
    pub flag_valid_acquisition: bool,
    /// Sampling rate \[samples/s\].
    #[prost(int64, tag = "10")]
    pub fs: i64,
    /// Prompt correlator, in-phase.
    #[prost(double, tag = "11")]
    pub prompt_i: f64,
    /// Prompt correlator, quadrature.
    #[prost(double, tag = "12")]
    pub prompt_q: f64,
    /// C/N0 \[dB-Hz\].
    #[prost(double, tag = "13")]
    pub cn0_db_hz: f64,
    /// Carrier Doppler \[Hz\].
    #[prost(double, tag = "14")]
    pub carrier_doppler_hz: f64,
    /// Accumulated carrier phase \[rad\].
    #[prost(double, tag = "15")]
    pub carrier_phase_rads: f64,
    /// Code phase \[samples\].
    #[prost(double, tag = "16")]
    pub code_phase_samples: f64,
    /// Samples processed by the tracking block (see the module docs for which instant).
    #[prost(uint64, tag = "17")]
    pub tracking_sample_counter: u64,
    /// Whether the channel is tracking (false on the output that reports a loss of lock).
    #[prost(bool, tag = "18")]
    pub flag_valid_symbol_output: bool,
    /// Length of one correlation (the code period) \[ms\].
    #[prost(int32, tag = "19")]
    pub correlation_length_ms: i32,
    /// Whether the navigation word is decoded.
    #[prost(bool, tag = "20")]
    pub flag_valid_word: bool,
    /// Time of week of the current symbol \[ms\].
    #[prost(uint32, tag = "21")]
    pub tow_at_current_symbol_ms: u32,
    /// Pseudorange \[m\].
    #[prost(double, tag = "22")]
    pub pseudorange_m: f64,
    /// Receiver time of week \[s\].
    #[prost(double, tag = "23")]
    pub rx_time: f64,
    /// Whether the pseudorange is valid.
    #[prost(bool, tag = "24")]
    pub flag_valid_pseudorange: bool,
    /// Interpolated time of week \[ms\].
    #[prost(double, tag = "25")]
    pub interp_tow_ms: f64,
    /// PLL locked at 180°.
    #[prost(bool, tag = "26")]
    pub flag_pll_180_deg_phase_locked: bool,
}

/// One datagram: GNSS-SDR's `gnss_sdr.Observables`.
#[derive(Clone, PartialEq, Message)]
pub struct Observables {
    /// The tracking outputs (one per datagram from the tracking monitor).
    #[prost(message, repeated, tag = "1")]
    pub observable: Vec<GnssSynchro>,
}

/// Why a datagram is not a monitor message.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum DatagramError {
    /// Zero bytes.
    #[error("empty datagram")]
    Empty,
    /// Not protobuf of the `Observables` schema.
    #[error("{len}-byte datagram is not a GNSS-SDR Observables message: {reason}")]
    Protobuf {
        /// Datagram length \[bytes\].
        len: usize,
        /// prost's description.
        reason: String,
    },
    /// Valid protobuf, but no `GnssSynchro` in it (another stream, or garbage that happens to parse).
    #[error("{len}-byte datagram holds no GnssSynchro (another stream on this port, or boost serialization?)")]
    NoObservable {
        /// Datagram length \[bytes\].
        len: usize,
    },
}

/// Decodes one UDP datagram of the tracking monitor into its messages.
pub fn decode_datagram(bytes: &[u8]) -> Result<Vec<GnssSynchro>, DatagramError> {
    if bytes.is_empty() {
        return Err(DatagramError::Empty);
    }
    let obs =
        Observables::decode(bytes).map_err(|e| DatagramError::Protobuf { len: bytes.len(), reason: e.to_string() })?;
    if obs.observable.is_empty() {
        return Err(DatagramError::NoObservable { len: bytes.len() });
    }
    Ok(obs.observable)
}

/// Serializes messages as the monitor does (for tests and tools).
pub fn encode_datagram(messages: &[GnssSynchro]) -> Vec<u8> {
    Observables { observable: messages.to_vec() }.encode_to_vec()
}

/// Why a message gives no row.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SkipReason {
    /// Another constellation than GPS.
    NotGps,
    /// GPS, but another signal than L1 C/A.
    NotL1Ca,
    /// `flag_valid_symbol_output` false: the output reporting a loss of lock.
    NotValid,
    /// A sampling rate ≤ 0, a negative channel, non-finite or zero prompt, non-finite C/N0.
    BadValue,
}

impl SkipReason {
    /// A short description.
    pub fn describe(self) -> &'static str {
        match self {
            SkipReason::NotGps => "not GPS",
            SkipReason::NotL1Ca => "GPS but not L1 C/A",
            SkipReason::NotValid => "not valid (loss of lock)",
            SkipReason::BadValue => "bad value (fs, channel, prompt or C/N0)",
        }
    }
}

/// A converted message: a tracking row and its sample counter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MonitorRow {
    /// The row of `tracking.csv` (elevation unknown).
    pub row: TrackingRow,
    /// `tracking_sample_counter` of the message.
    pub sample_counter: u64,
    /// The sampling rate used \[Hz\].
    pub fs_hz: f64,
}

/// Converts a message to a tracking row (see the module docs); `fs_hz`
/// overrides the message's own `fs` when given.
pub fn to_row(m: &GnssSynchro, fs_hz: Option<f64>) -> Result<MonitorRow, SkipReason> {
    if m.system != "G" {
        return Err(SkipReason::NotGps);
    }
    if m.signal != "1C" {
        return Err(SkipReason::NotL1Ca);
    }
    if !m.flag_valid_symbol_output {
        return Err(SkipReason::NotValid);
    }
    let fs = fs_hz.unwrap_or(m.fs as f64);
    let (i, q) = (m.prompt_i, m.prompt_q);
    let bad = !(fs.is_finite() && fs > 0.0)
        || m.channel_id < 0
        || !(i.is_finite() && q.is_finite())
        || (i == 0.0 && q == 0.0)
        || !m.cn0_db_hz.is_finite();
    if bad {
        return Err(SkipReason::BadValue);
    }
    // Two-quadrant: the Costas discriminator's atan(Q/I), in (−π/2, π/2]; I = 0 gives ±π/2.
    let phase = if i == 0.0 { core::f64::consts::FRAC_PI_2.copysign(q) } else { (q / i).atan() };
    let t = (m.tracking_sample_counter as f64 - 0.5 * fs * BIT_MS * 1e-3) / fs;
    Ok(MonitorRow {
        row: TrackingRow {
            t_s: t,
            channel: m.channel_id as u32,
            prn: m.prn,
            cn0_dbhz: m.cn0_db_hz,
            elev_deg: None,
            phase_err_rad: phase,
        },
        sample_counter: m.tracking_sample_counter,
        fs_hz: fs,
    })
}

/// Something the stream reports besides rows.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Notice {
    /// A datagram that is not a monitor message.
    Garbage {
        /// 0-based index of the datagram in the stream.
        datagram: u64,
        /// Why.
        error: String,
    },
    /// Outputs missing between two of a channel's (lost datagrams, or a decimation not stated).
    Gap {
        /// Channel.
        channel: u32,
        /// PRN.
        prn: u32,
        /// Time of the last row before the gap \[s\].
        from_s: f64,
        /// Time of the row after it \[s\].
        to_s: f64,
        /// Outputs missing (rounded).
        missing: u64,
    },
    /// A channel tracks again after a loss of lock, or tracks another satellite.
    Restart {
        /// Channel.
        channel: u32,
        /// The PRN tracked before.
        old_prn: u32,
        /// The PRN now.
        new_prn: u32,
        /// Time of its first row \[s\].
        at_s: f64,
        /// Whether the previous output reported a loss of lock.
        after_loss_of_lock: bool,
    },
    /// A channel reports a loss of lock.
    LossOfLock {
        /// Channel.
        channel: u32,
        /// PRN.
        prn: u32,
        /// Sample counter of the report, as time \[s\].
        at_s: f64,
    },
}

impl std::fmt::Display for Notice {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Notice::Garbage { datagram, error } => write!(f, "datagram {datagram}: {error}; skipped"),
            Notice::Gap { channel, prn, from_s, to_s, missing } => {
                write!(
                    f,
                    "channel {channel} (PRN {prn}): {missing} outputs missing between {from_s:.3} s and {to_s:.3} s"
                )
            }
            Notice::Restart { channel, old_prn, new_prn, at_s, after_loss_of_lock } => {
                if *after_loss_of_lock {
                    write!(
                        f,
                        "channel {channel}: tracks PRN {new_prn} again from {at_s:.3} s after a loss of lock of PRN {old_prn}"
                    )
                } else {
                    write!(f, "channel {channel}: PRN {old_prn} → PRN {new_prn} from {at_s:.3} s")
                }
            }
            Notice::LossOfLock { channel, prn, at_s } => {
                write!(f, "channel {channel} (PRN {prn}): GNSS-SDR reports a loss of lock at {at_s:.3} s")
            }
        }
    }
}

/// What one datagram gave.
#[derive(Debug, Clone, PartialEq)]
pub enum MonitorEvent {
    /// A new tracking row.
    Row(MonitorRow),
    /// A row older than its channel's last one, filling a reported gap (GNSS-SDR re-sent it).
    Late(MonitorRow),
    /// A notice.
    Notice(Notice),
}

/// The monitor's rows put on the common grid t = j·T (T the 20 ms output
/// interval) as they arrive, for a live session: each channel's phase error
/// linearly interpolated between its consecutive outputs (as
/// [`crate::import::resample`] does for a whole recording), the first
/// `settle_s` of each track left out (its loop's settling), and each grid
/// epoch released once every channel has had [`LiveGrid::HOLD_EPOCHS`]
/// epochs to arrive, so rows leave in time order. A row for an epoch already
/// released is counted in [`LiveGrid::late`] and dropped; no interpolation
/// spans a gap of more than two outputs.
#[derive(Debug, Clone)]
pub struct LiveGrid {
    interval_s: f64,
    settle_s: f64,
    /// Per channel: its last row and the start of its track.
    last: BTreeMap<u32, (TrackingRow, f64)>,
    pending: BTreeMap<i64, Vec<TrackingRow>>,
    released_to: i64,
    newest: i64,
    late: u64,
}

impl LiveGrid {
    /// Epochs a grid time waits for the channels' rows before it is released
    /// (60 ms at 20 ms: the monitor's outputs of one epoch arrive within one
    /// output interval of each other).
    pub const HOLD_EPOCHS: i64 = 3;

    /// A grid of `interval_s`, leaving out the first `settle_s` of each track.
    pub fn new(interval_s: f64, settle_s: f64) -> Self {
        LiveGrid {
            interval_s,
            settle_s,
            last: BTreeMap::new(),
            pending: BTreeMap::new(),
            released_to: i64::MIN,
            newest: i64::MIN,
            late: 0,
        }
    }

    /// Rows dropped because their epoch had been released.
    pub fn late(&self) -> u64 {
        self.late
    }

    /// Takes one event; returns the grid rows released, in time order (channels in order within an epoch).
    pub fn push(&mut self, event: &MonitorEvent) -> Vec<TrackingRow> {
        match event {
            MonitorEvent::Row(r) => self.row(&r.row),
            MonitorEvent::Late(_) => {}
            MonitorEvent::Notice(Notice::Restart { channel, .. } | Notice::LossOfLock { channel, .. }) => {
                self.last.remove(channel);
            }
            MonitorEvent::Notice(_) => {}
        }
        self.release(self.newest.saturating_sub(Self::HOLD_EPOCHS))
    }

    /// Every epoch still held (the end of the stream).
    pub fn flush(&mut self) -> Vec<TrackingRow> {
        self.release(i64::MAX)
    }

    fn row(&mut self, r: &TrackingRow) {
        let t = self.interval_s;
        let (prev, start) = match self.last.get(&r.channel) {
            Some((p, start)) if p.prn == r.prn && r.t_s > p.t_s => (Some(*p), *start),
            Some((p, _)) if p.prn == r.prn => return,
            _ => (None, r.t_s),
        };
        self.last.insert(r.channel, (*r, start));
        let Some(p) = prev else { return };
        if r.t_s - p.t_s > 2.5 * t {
            return;
        }
        let first = (p.t_s / t).floor() as i64 + 1;
        let last = (r.t_s / t).floor() as i64;
        for j in first..=last {
            let g = j as f64 * t;
            if g - start < self.settle_s {
                continue;
            }
            if j <= self.released_to {
                self.late += 1;
                continue;
            }
            let w = (g - p.t_s) / (r.t_s - p.t_s);
            let phase_err_rad = p.phase_err_rad + w * (r.phase_err_rad - p.phase_err_rad);
            self.pending.entry(j).or_default().push(TrackingRow { t_s: g, phase_err_rad, elev_deg: None, ..*r });
            self.newest = self.newest.max(j);
        }
    }

    fn release(&mut self, up_to: i64) -> Vec<TrackingRow> {
        let mut out = Vec::new();
        while let Some(entry) = self.pending.first_entry() {
            if *entry.key() > up_to {
                break;
            }
            let j = *entry.key();
            let mut rows = entry.remove();
            rows.sort_by_key(|r| r.channel);
            out.extend(rows);
            self.released_to = self.released_to.max(j);
        }
        out
    }
}

/// Counts over a stream, for the summary.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct MonitorCounts {
    /// Datagrams received.
    pub datagrams: u64,
    /// Datagrams that were not monitor messages.
    pub garbage: u64,
    /// Messages decoded.
    pub messages: u64,
    /// Rows produced in order (besides the late ones).
    pub rows: u64,
    /// Messages not newer than their channel's last (GNSS-SDR's re-sends), dropped.
    pub repeated: u64,
    /// Outputs that arrived after newer ones of their channel and fill a gap (taken).
    pub late: u64,
    /// Messages skipped, by reason.
    pub skipped: BTreeMap<SkipReason, u64>,
    /// Gaps reported.
    pub gaps: u64,
    /// Restarts reported.
    pub restarts: u64,
}

impl MonitorCounts {
    /// One line: datagrams, rows and why the rest gave none.
    pub fn summary(&self) -> String {
        let mut s = format!(
            "{} datagrams ({} garbage), {} messages: {} rows ({} of them late, filling gaps), {} repeats of earlier \
             outputs dropped",
            self.datagrams,
            self.garbage,
            self.messages,
            self.rows + self.late,
            self.late,
            self.repeated
        );
        for (r, n) in &self.skipped {
            s += &format!(", {n} {}", r.describe());
        }
        s += &format!("; {} gaps, {} channel restarts", self.gaps, self.restarts);
        s
    }
}

#[derive(Debug, Clone, Copy)]
struct ChannelState {
    prn: u32,
    counter: u64,
    t_s: f64,
    lost: bool,
}

/// A channel's open gaps (counters strictly between) and the late outputs taken in them.
type Holes = (Vec<(u64, u64)>, std::collections::BTreeSet<u64>);

/// Gaps kept per channel for outputs that arrive late (re-sent after newer ones).
const HOLES_KEPT: usize = 256;

/// The monitor stream's state: turns datagrams into new rows and notices
/// (see the module docs); no socket, so it runs on captures too.
#[derive(Debug, Clone, Default)]
pub struct MonitorStream {
    /// Overrides the messages' sampling rate \[Hz\].
    pub fs_hz: Option<f64>,
    /// `TrackingMonitor.decimation_factor` (one output sent per this many; 1 when unknown).
    pub decimation: u32,
    channels: BTreeMap<u32, ChannelState>,
    /// Per channel, the open gaps (counters strictly between) and the late outputs already taken.
    holes: BTreeMap<u32, Holes>,
    /// The counts so far.
    pub counts: MonitorCounts,
}

impl MonitorStream {
    /// A stream at the messages' own sampling rate, or `fs_hz`, with the monitor's decimation.
    pub fn new(fs_hz: Option<f64>, decimation: u32) -> Self {
        MonitorStream { fs_hz, decimation: decimation.max(1), ..Default::default() }
    }

    /// Takes one datagram.
    pub fn push(&mut self, bytes: &[u8]) -> Vec<MonitorEvent> {
        let index = self.counts.datagrams;
        self.counts.datagrams += 1;
        let messages = match decode_datagram(bytes) {
            Ok(m) => m,
            Err(e) => {
                self.counts.garbage += 1;
                return vec![MonitorEvent::Notice(Notice::Garbage { datagram: index, error: e.to_string() })];
            }
        };
        let mut out = Vec::new();
        for m in &messages {
            self.push_message(m, &mut out);
        }
        out
    }

    fn push_message(&mut self, m: &GnssSynchro, out: &mut Vec<MonitorEvent>) {
        self.counts.messages += 1;
        let channel = u32::try_from(m.channel_id).ok();
        // A re-send of an output already seen (or older): the counter is the receiver's, global.
        if let Some(c) = channel
            && let Some(state) = self.channels.get(&c)
            && m.tracking_sample_counter <= state.counter
        {
            // GNSS-SDR re-sends old outputs: one that fills a gap is taken late, once.
            let n = m.tracking_sample_counter;
            if let Some((holes, taken)) = self.holes.get_mut(&c)
                && holes.iter().any(|&(lo, hi)| lo < n && n < hi)
                && !taken.contains(&n)
                && let Ok(row) = to_row(m, self.fs_hz)
            {
                taken.insert(n);
                self.counts.late += 1;
                out.push(MonitorEvent::Late(row));
                return;
            }
            self.counts.repeated += 1;
            return;
        }
        let row = match to_row(m, self.fs_hz) {
            Ok(r) => r,
            Err(reason) => {
                *self.counts.skipped.entry(reason).or_default() += 1;
                if reason == SkipReason::NotValid
                    && let Some(c) = channel
                {
                    let fs = self.fs_hz.unwrap_or(m.fs as f64);
                    let at_s = m.tracking_sample_counter as f64 / fs;
                    let prev = self.channels.get(&c).copied();
                    self.channels.insert(
                        c,
                        ChannelState {
                            prn: m.prn,
                            counter: m.tracking_sample_counter,
                            t_s: prev.map_or(at_s, |p| p.t_s),
                            lost: true,
                        },
                    );
                    out.push(MonitorEvent::Notice(Notice::LossOfLock { channel: c, prn: m.prn, at_s }));
                }
                return;
            }
        };
        let c = row.row.channel;
        if let Some(prev) = self.channels.get(&c).copied() {
            if prev.lost || prev.prn != row.row.prn {
                self.counts.restarts += 1;
                out.push(MonitorEvent::Notice(Notice::Restart {
                    channel: c,
                    old_prn: prev.prn,
                    new_prn: row.row.prn,
                    at_s: row.row.t_s,
                    after_loss_of_lock: prev.lost,
                }));
            } else {
                let step = row.fs_hz * BIT_MS * 1e-3 * f64::from(self.decimation);
                let steps = (row.sample_counter - prev.counter) as f64 / step;
                if steps > 1.5 {
                    self.counts.gaps += 1;
                    let (holes, _) = self.holes.entry(c).or_default();
                    holes.push((prev.counter, row.sample_counter));
                    if holes.len() > HOLES_KEPT {
                        holes.remove(0);
                    }
                    out.push(MonitorEvent::Notice(Notice::Gap {
                        channel: c,
                        prn: row.row.prn,
                        from_s: prev.t_s,
                        to_s: row.row.t_s,
                        missing: (steps.round() as u64).saturating_sub(1),
                    }));
                }
            }
        }
        self.channels
            .insert(c, ChannelState { prn: row.row.prn, counter: row.sample_counter, t_s: row.row.t_s, lost: false });
        self.counts.rows += 1;
        out.push(MonitorEvent::Row(row));
    }
}

/// Collects a stream's rows for `tracking.csv`. [`Recorder::finish`] cuts
/// each channel's rows (in time, late ones included) into tracks where the
/// PRN changes, a loss of lock lies between, or outputs are still missing;
/// drops each track's first seconds (the narrow loop's settling); and puts
/// every track on the common grid of the outputs (20 ms × decimation) by
/// the dump importer's interpolation.
#[derive(Debug, Clone, Default)]
pub struct Recorder {
    decimation: u32,
    rows: Vec<TrackingRow>,
    losses: Vec<(u32, f64)>,
}

impl Recorder {
    /// An empty recording of a monitor that sends one output per `decimation`.
    pub fn new(decimation: u32) -> Self {
        Recorder { decimation: decimation.max(1), ..Default::default() }
    }

    /// Takes one datagram's events.
    pub fn take(&mut self, events: &[MonitorEvent]) {
        for e in events {
            match e {
                MonitorEvent::Notice(Notice::LossOfLock { channel, at_s, .. }) => self.losses.push((*channel, *at_s)),
                MonitorEvent::Notice(_) => {}
                MonitorEvent::Row(r) | MonitorEvent::Late(r) => self.rows.push(r.row),
            }
        }
    }

    /// Rows taken so far.
    pub fn rows(&self) -> &[TrackingRow] {
        &self.rows
    }

    /// The grid interval \[s\]: 20 ms × decimation.
    pub fn interval_s(&self) -> f64 {
        BIT_MS * 1e-3 * f64::from(self.decimation)
    }

    /// The tracks: (channel, PRN, first and last time \[s\], rows).
    pub fn tracks(&self) -> Vec<(u32, u32, f64, f64, usize)> {
        let mut out = Vec::new();
        for r in self.segment() {
            match out.last_mut() {
                Some((_, _, _, last, n, track)) if *track == r.track => {
                    *last = r.t_s;
                    *n += 1;
                }
                _ => out.push((r.channel, r.prn, r.t_s, r.t_s, 1usize, r.track)),
            }
        }
        out.into_iter().map(|(c, p, a, b, n, _)| (c, p, a, b, n)).collect()
    }

    /// The rows by channel then time, each with its track.
    fn segment(&self) -> Vec<ImportedRow> {
        let mut rows = self.rows.clone();
        rows.sort_by(|a, b| a.channel.cmp(&b.channel).then(a.t_s.total_cmp(&b.t_s)));
        rows.dedup_by(|b, a| a.channel == b.channel && a.t_s == b.t_s);
        let step = self.interval_s();
        let mut out: Vec<ImportedRow> = Vec::with_capacity(rows.len());
        let mut track = 0usize;
        for (k, r) in rows.iter().enumerate() {
            if k > 0 {
                let p = &rows[k - 1];
                let lost = self.losses.iter().any(|&(c, t)| c == r.channel && t > p.t_s && t < r.t_s + 0.5 * step);
                if p.channel != r.channel || p.prn != r.prn || r.t_s - p.t_s > 1.5 * step || lost {
                    track += 1;
                }
            }
            out.push(ImportedRow {
                t_s: r.t_s,
                channel: r.channel,
                prn: r.prn,
                cn0_dbhz: r.cn0_dbhz,
                phase_err_rad: r.phase_err_rad,
                lock_test: f64::NAN,
                symbols: BIT_MS as u32,
                track,
                input_phase_rad: None,
            });
        }
        out
    }

    /// The rows of every track from `settle_s` after its first on, on the
    /// grid t = j·[`interval_s`](Self::interval_s) (by time, then channel).
    pub fn finish(&self, settle_s: f64) -> Vec<TrackingRow> {
        let rows = self.segment();
        let n_tracks = rows.last().map_or(0, |r| r.track + 1);
        let mut start = vec![f64::INFINITY; n_tracks];
        for r in &rows {
            start[r.track] = start[r.track].min(r.t_s);
        }
        let kept: Vec<ImportedRow> =
            rows.iter().filter(|r| r.t_s >= start[r.track] + settle_s - 1e-9).copied().collect();
        resample_rows(&kept, self.interval_s())
    }
}

/// A blocking receiver of the tracking monitor on a UDP socket.
#[derive(Debug)]
pub struct MonitorReceiver {
    socket: UdpSocket,
    buf: Vec<u8>,
    len: usize,
    /// The stream's state and counts.
    pub stream: MonitorStream,
}

/// What one [`MonitorReceiver::recv`] gave.
#[derive(Debug, Clone, PartialEq)]
pub enum Received {
    /// A datagram arrived; its events (possibly none: a repeat).
    Datagram(Vec<MonitorEvent>),
    /// Nothing arrived within the read timeout.
    Timeout,
}

impl MonitorReceiver {
    /// Binds to `addr` (e.g. `127.0.0.1:1234`); each [`recv`](Self::recv)
    /// waits at most `read_timeout` so the caller can stop.
    pub fn bind(addr: impl ToSocketAddrs, stream: MonitorStream, read_timeout: Duration) -> io::Result<Self> {
        let socket = UdpSocket::bind(addr)?;
        socket.set_read_timeout(Some(read_timeout.max(Duration::from_millis(1))))?;
        Ok(MonitorReceiver { socket, buf: vec![0; 65_536], len: 0, stream })
    }

    /// The address bound.
    pub fn local_addr(&self) -> io::Result<SocketAddr> {
        self.socket.local_addr()
    }

    /// Waits for one datagram (at most the read timeout).
    pub fn recv(&mut self) -> io::Result<Received> {
        match self.socket.recv(&mut self.buf) {
            Ok(n) => {
                self.len = n;
                Ok(Received::Datagram(self.stream.push(&self.buf[..n])))
            }
            Err(e) if matches!(e.kind(), io::ErrorKind::WouldBlock | io::ErrorKind::TimedOut) => {
                self.len = 0;
                Ok(Received::Timeout)
            }
            Err(e) => Err(e),
        }
    }

    /// The bytes of the last datagram received (empty after a timeout).
    pub fn last_datagram(&self) -> &[u8] {
        &self.buf[..self.len]
    }
}

/// Appends a datagram to a capture: its length (u32, little endian), then its bytes.
pub fn write_capture_record<W: Write>(w: &mut W, datagram: &[u8]) -> io::Result<()> {
    let len = u32::try_from(datagram.len()).map_err(|_| io::Error::other("datagram longer than 4 GiB"))?;
    w.write_all(&len.to_le_bytes())?;
    w.write_all(datagram)
}

/// A capture file that does not split into datagrams.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("capture truncated at byte offset {offset}: datagram {index} needs {needed} bytes, {left} left")]
pub struct CaptureError {
    /// 0-based index of the datagram.
    pub index: usize,
    /// Byte offset of its length prefix.
    pub offset: usize,
    /// Bytes it needs (prefix and body).
    pub needed: usize,
    /// Bytes left from the offset.
    pub left: usize,
}

/// Splits a capture (length-prefixed datagrams, [`write_capture_record`]) into its datagrams.
pub fn split_capture(bytes: &[u8]) -> Result<Vec<&[u8]>, CaptureError> {
    let mut out = Vec::new();
    let mut at = 0;
    while at < bytes.len() {
        let left = bytes.len() - at;
        let len = bytes.get(at..at + 4).map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize);
        match len {
            Some(len) if len <= left - 4 => {
                out.push(&bytes[at + 4..at + 4 + len]);
                at += 4 + len;
            }
            _ => {
                return Err(CaptureError { index: out.len(), offset: at, needed: 4 + len.unwrap_or(0), left });
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn msg(channel: i32, prn: u32, counter: u64, i: f64, q: f64) -> GnssSynchro {
        GnssSynchro {
            system: "G".into(),
            signal: "1C".into(),
            prn,
            channel_id: channel,
            fs: 2_048_000,
            prompt_i: i,
            prompt_q: q,
            cn0_db_hz: 45.5,
            tracking_sample_counter: counter,
            flag_valid_symbol_output: true,
            correlation_length_ms: 1,
            ..Default::default()
        }
    }

    #[test]
    fn round_trip() {
        let m = vec![msg(3, 17, 123_456_789, 1e5, -2.5e3), msg(0, 5, 1, -1.0, 0.5)];
        let b = encode_datagram(&m);
        assert_eq!(decode_datagram(&b).unwrap(), m);
    }

    #[test]
    fn conversion_time_and_sign() {
        let fs = 2_048_000.0;
        let n = 40_960_000u64;
        let r = to_row(&msg(1, 9, n, 1000.0, 100.0), None).unwrap();
        assert_eq!(r.row.channel, 1);
        assert_eq!(r.row.prn, 9);
        assert!((r.row.phase_err_rad - 0.1f64.atan()).abs() < 1e-15);
        assert!((r.row.t_s - (n as f64 - fs * 1e-2) / fs).abs() < 1e-12);
        // Sign kept: a negative Q/I gives a negative φ, I < 0 is folded (Costas).
        assert!(to_row(&msg(1, 9, n, -1000.0, 100.0), None).unwrap().row.phase_err_rad < 0.0);
    }

    #[test]
    fn skips_with_reasons() {
        let mut m = msg(0, 1, 10, 1.0, 0.0);
        m.system = "E".into();
        assert_eq!(to_row(&m, None), Err(SkipReason::NotGps));
        let mut m = msg(0, 1, 10, 1.0, 0.0);
        m.signal = "2S".into();
        assert_eq!(to_row(&m, None), Err(SkipReason::NotL1Ca));
        let mut m = msg(0, 1, 10, 1.0, 0.0);
        m.flag_valid_symbol_output = false;
        assert_eq!(to_row(&m, None), Err(SkipReason::NotValid));
        assert_eq!(to_row(&msg(0, 1, 10, f64::NAN, 0.0), None), Err(SkipReason::BadValue));
        assert_eq!(to_row(&msg(0, 1, 10, 0.0, 0.0), None), Err(SkipReason::BadValue));
        let mut m = msg(0, 1, 10, 1.0, 0.0);
        m.fs = 0;
        assert_eq!(to_row(&m, None), Err(SkipReason::BadValue));
    }

    #[test]
    fn garbage_is_an_error_never_a_panic() {
        assert_eq!(decode_datagram(&[]), Err(DatagramError::Empty));
        assert!(matches!(decode_datagram(&[0xff; 7]), Err(DatagramError::Protobuf { .. })));
        // Truncated: a good datagram cut short.
        let b = encode_datagram(&[msg(0, 1, 99, 1.0, 2.0)]);
        for cut in 1..b.len() {
            let _ = decode_datagram(&b[..cut]);
        }
        assert!(decode_datagram(&b[..b.len() - 3]).is_err());
        // Pseudo-random bytes: decode or fail, never panic.
        let mut x = 0x9e37_79b9_7f4a_7c15u64;
        for len in 0..2000 {
            let bytes: Vec<u8> = (0..len % 300)
                .map(|_| {
                    x ^= x << 13;
                    x ^= x >> 7;
                    x ^= x << 17;
                    x as u8
                })
                .collect();
            let mut s = MonitorStream::new(None, 1);
            let _ = s.push(&bytes);
        }
        // A text datagram that happens to parse as unknown fields holds no GnssSynchro.
        assert!(decode_datagram(b"\x08\x01").is_err());
    }

    #[test]
    fn stream_drops_repeats_and_reports_gaps_restarts() {
        let step = 40_960u64; // 20 ms at 2.048 Msps
        let mut s = MonitorStream::new(None, 1);
        let rows = |ev: Vec<MonitorEvent>| ev.iter().filter(|e| matches!(e, MonitorEvent::Row(_))).count();
        assert_eq!(rows(s.push(&encode_datagram(&[msg(0, 7, 10 * step, 1.0, 0.1)]))), 1);
        assert_eq!(rows(s.push(&encode_datagram(&[msg(0, 7, 11 * step, 1.0, 0.1)]))), 1);
        // A re-send of older outputs.
        assert_eq!(rows(s.push(&encode_datagram(&[msg(0, 7, 10 * step, 1.0, 0.1)]))), 0);
        assert_eq!(rows(s.push(&encode_datagram(&[msg(0, 7, 11 * step, 1.0, 0.1)]))), 0);
        assert_eq!(s.counts.repeated, 2);
        // Three outputs lost.
        let ev = s.push(&encode_datagram(&[msg(0, 7, 15 * step, 1.0, 0.1)]));
        assert!(matches!(ev[0], MonitorEvent::Notice(Notice::Gap { missing: 3, .. })), "{ev:?}");
        // One of the three arrives late (re-sent), once; the others stay missing.
        let ev = s.push(&encode_datagram(&[msg(0, 7, 13 * step, 1.0, 0.1)]));
        assert!(matches!(ev[0], MonitorEvent::Late(r) if r.sample_counter == 13 * step), "{ev:?}");
        assert!(s.push(&encode_datagram(&[msg(0, 7, 13 * step, 1.0, 0.1)])).is_empty());
        assert_eq!((s.counts.late, s.counts.repeated), (1, 3));
        // Loss of lock, then another satellite.
        let mut lost = msg(0, 7, 16 * step, 0.0, 0.0);
        lost.flag_valid_symbol_output = false;
        let ev = s.push(&encode_datagram(&[lost]));
        assert!(matches!(ev[0], MonitorEvent::Notice(Notice::LossOfLock { prn: 7, .. })));
        let ev = s.push(&encode_datagram(&[msg(0, 12, 100 * step, 1.0, 0.1)]));
        assert!(
            matches!(
                ev[0],
                MonitorEvent::Notice(Notice::Restart { old_prn: 7, new_prn: 12, after_loss_of_lock: true, .. })
            ),
            "{ev:?}"
        );
        let ev = s.push(b"");
        assert!(matches!(ev[0], MonitorEvent::Notice(Notice::Garbage { datagram: 9, .. })));
        assert_eq!(s.counts.rows, 4);
        assert_eq!(s.counts.skipped[&SkipReason::NotValid], 1);
        assert_eq!((s.counts.gaps, s.counts.restarts, s.counts.garbage), (1, 1, 1));
    }

    #[test]
    fn recorder_tracks_settle_and_grid() {
        let step = 40_960u64;
        let mut s = MonitorStream::new(None, 1);
        let mut r = Recorder::new(1);
        for k in 100..200u64 {
            r.take(&s.push(&encode_datagram(&[msg(0, 7, k * step + 17, 1.0, 0.01 * k as f64)])));
        }
        // A gap: a second track on the same channel.
        for k in 300..400u64 {
            r.take(&s.push(&encode_datagram(&[msg(0, 7, k * step + 17, 1.0, 0.0)])));
        }
        assert_eq!(r.tracks().len(), 2);
        let g = r.finish(1.0);
        // 99 intervals per track, less 1 s = 50 rows of settling.
        assert!(g.iter().all(|x| (x.t_s / 0.02 - (x.t_s / 0.02).round()).abs() < 1e-9));
        assert_eq!(g.len(), 2 * 49, "{}", g.len());
        assert!(g[0].t_s >= 100.0 * 0.02 + 1.0 - 0.02);
    }

    #[test]
    fn capture_split() {
        let mut v = Vec::new();
        write_capture_record(&mut v, b"abc").unwrap();
        write_capture_record(&mut v, b"").unwrap();
        write_capture_record(&mut v, b"de").unwrap();
        assert_eq!(split_capture(&v).unwrap(), vec![&b"abc"[..], b"", b"de"]);
        assert_eq!(split_capture(&v[..v.len() - 1]).unwrap_err().index, 2);
        assert_eq!(split_capture(&v[..2]).unwrap_err().needed, 4);
    }

    #[test]
    fn receiver_over_loopback() {
        let mut rx =
            MonitorReceiver::bind("127.0.0.1:0", MonitorStream::new(None, 1), Duration::from_millis(50)).expect("bind");
        let to = rx.local_addr().unwrap();
        let tx = UdpSocket::bind("127.0.0.1:0").unwrap();
        tx.send_to(&encode_datagram(&[msg(2, 3, 81_920, 5.0, 1.0)]), to).unwrap();
        tx.send_to(&[1, 2, 3], to).unwrap();
        let mut got = Vec::new();
        for _ in 0..20 {
            match rx.recv().unwrap() {
                Received::Datagram(ev) => got.extend(ev),
                Received::Timeout => break,
            }
        }
        assert!(matches!(got[0], MonitorEvent::Row(r) if r.row.channel == 2 && r.row.prn == 3));
        assert!(matches!(got[1], MonitorEvent::Notice(Notice::Garbage { .. })));
        assert_eq!(rx.recv().unwrap(), Received::Timeout);
        assert!(rx.last_datagram().is_empty());
    }

    #[test]
    fn the_live_grid_interpolates_holds_and_releases_in_time_order() {
        let row = |t_s: f64, channel: u32, phase_err_rad: f64| {
            MonitorEvent::Row(MonitorRow {
                row: TrackingRow { t_s, channel, prn: channel + 10, cn0_dbhz: 45.0, elev_deg: None, phase_err_rad },
                sample_counter: 0,
                fs_hz: 1.0,
            })
        };
        let mut g = LiveGrid::new(0.02, 0.05);
        let mut out = Vec::new();
        // Two channels at their own phases of the 20 ms outputs, φ = t (so the interpolation is exact).
        for k in 0..40 {
            let t0 = 0.013 + 0.02 * k as f64;
            let t1 = 0.007 + 0.02 * k as f64;
            out.extend(g.push(&row(t0, 0, t0)));
            out.extend(g.push(&row(t1, 1, t1)));
        }
        out.extend(g.flush());
        assert!(out.windows(2).all(|w| w[0].t_s <= w[1].t_s), "time order");
        for r in &out {
            assert!((r.phase_err_rad - r.t_s).abs() < 1e-12, "{r:?}");
            assert!(((r.t_s / 0.02).round() * 0.02 - r.t_s).abs() < 1e-12);
        }
        // Each track's first 50 ms are its settling: channel 0 starts at 0.013 s, its first row at 0.08 s.
        assert_eq!(out.iter().find(|r| r.channel == 0).unwrap().t_s, 0.08);
        assert_eq!(g.late(), 0);
        // A row for an epoch already released is late.
        let mut g = LiveGrid::new(0.02, 0.0);
        for k in 0..10 {
            g.push(&row(0.013 + 0.02 * k as f64, 0, 0.0));
        }
        g.push(&row(0.007, 1, 0.0));
        g.push(&row(0.027, 1, 0.0));
        assert_eq!(g.late(), 1);
    }
}
