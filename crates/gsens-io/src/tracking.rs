//! The crate documentation's section "`tracking.csv` in memory" describes this module.

use std::borrow::Borrow;
use std::collections::HashMap;
use std::io::Read;
use std::path::Path;

use crate::columns::{RowParser, TrackingColumns};
use crate::error::{Column, FormatError};
use crate::parse::{CsvSource, path_name};
use crate::row::TrackingRecord;
use crate::signal::Carrier;
use crate::writers::TrackingRow;

/// The columns of `tracking.csv`, in the order the writer emits them.
pub const TRACKING_COLUMNS: [&str; 6] = ["t_s", "channel", "prn", "cn0_dbhz", "elev_deg", "phase_err_rad"];

/// The optional carrier columns of `tracking.csv` (see the crate documentation);
/// the writer emits `signal` and `carrier_hz` after the six of [`TRACKING_COLUMNS`]
/// when some row is not on L1.
pub const CARRIER_COLUMNS: [&str; 3] = ["signal", "glo_k", "carrier_hz"];

/// The optional NCO columns of `tracking.csv` (see the crate documentation):
/// where the loop put its replica, for the loop-free measurement θ_in = θ_NCO + φ.
pub const NCO_COLUMNS: [&str; 2] = ["nco_phase_cycles", "nco_freq_hz"];

/// The rows of one (channel, PRN) pair, stored column-wise, in time order.
#[derive(Debug, Clone, PartialEq)]
pub struct ChannelTrack {
    /// Receiver channel number.
    pub channel: u32,
    /// Satellite PRN tracked by the channel.
    pub prn: u32,
    /// Time stamps \[s\], strictly increasing.
    pub t_s: Vec<f64>,
    /// Carrier phase tracking error \[rad\].
    pub phase_err_rad: Vec<f64>,
    /// Carrier-to-noise density ratio [dB-Hz].
    pub cn0_dbhz: Vec<f64>,
    /// Satellite elevation \[deg\]; NaN where the log leaves it empty (unknown).
    pub elev_deg: Vec<f64>,
    /// The carrier tracked (one per track; GPS L1 for a log without carrier columns).
    pub carrier: Carrier,
    /// The replica's accumulated phase at the end of each row's latest
    /// integration \[cycles\] (φ = θ_signal − θ_replica, θ_replica = 2π·this);
    /// empty when the log has no `nco_phase_cycles` column.
    pub nco_phase_cycles: Vec<f64>,
    /// The frequency the NCO was commanded during each row's latest
    /// integration \[Hz\]; empty when the log has no `nco_freq_hz` column.
    pub nco_freq_hz: Vec<f64>,
}

impl ChannelTrack {
    fn new(channel: u32, prn: u32, carrier: Carrier) -> Self {
        ChannelTrack {
            channel,
            prn,
            carrier,
            t_s: Vec::new(),
            phase_err_rad: Vec::new(),
            cn0_dbhz: Vec::new(),
            elev_deg: Vec::new(),
            nco_phase_cycles: Vec::new(),
            nco_freq_hz: Vec::new(),
        }
    }

    /// Number of rows.
    pub fn len(&self) -> usize {
        self.t_s.len()
    }

    /// `true` when the track has no row (never the case for tracks from a reader).
    pub fn is_empty(&self) -> bool {
        self.t_s.is_empty()
    }

    /// Row `k` as a [`TrackingRow`] (an elevation of NaN, unknown, as `None`).
    pub fn row(&self, k: usize) -> TrackingRow {
        TrackingRow {
            t_s: self.t_s[k],
            channel: self.channel,
            prn: self.prn,
            cn0_dbhz: self.cn0_dbhz[k],
            elev_deg: Some(self.elev_deg[k]).filter(|e| e.is_finite()),
            phase_err_rad: self.phase_err_rad[k],
        }
    }

    /// Mean C/N0 over all rows [dB-Hz] (NaN for an empty track).
    pub fn mean_cn0_dbhz(&self) -> f64 {
        self.cn0_dbhz.iter().sum::<f64>() / self.cn0_dbhz.len() as f64
    }
}

/// A validated tracking log.
///
/// Built by [`read_tracking`] / [`read_tracking_file`], which check its
/// invariants (non-decreasing time stamps, one row per channel per epoch,
/// finite values), so the fields are read-only.
#[derive(Debug, Clone, PartialEq)]
pub struct TrackingLog {
    source_name: String,
    tracks: Vec<ChannelTrack>,
    epoch_t_s: Vec<f64>,
    epoch_line: Vec<u64>,
    t_column: Column,
    rows: usize,
}

impl TrackingLog {
    /// The source name given to the reader (the file name).
    pub fn source_name(&self) -> &str {
        &self.source_name
    }

    /// The tracks, one per (channel, PRN) pair, in order of first appearance.
    pub fn tracks(&self) -> &[ChannelTrack] {
        &self.tracks
    }

    /// The distinct time stamps of the log \[s\], strictly increasing.
    pub fn epoch_t_s(&self) -> &[f64] {
        &self.epoch_t_s
    }

    /// Number of data rows read.
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// The 1-based line of the first row of each distinct time stamp (one per
    /// [`epoch_t_s`](Self::epoch_t_s)), for error messages about the time stamps.
    pub fn epoch_line(&self) -> &[u64] {
        &self.epoch_line
    }

    /// The `t_s` column of the file (its position and name), for error messages.
    pub fn t_column(&self) -> &Column {
        &self.t_column
    }

    /// The tracks, given up by the log (so that a consumer can free each as
    /// it is done with it).
    pub fn into_tracks(self) -> Vec<ChannelTrack> {
        self.tracks
    }
}

/// Per-channel reader state: the latest row and the current track.
struct ChannelState {
    last_t_s: f64,
    last_line: u64,
    track: usize,
}

/// The reader state of every channel seen: receivers number their channels
/// from 0, so the usual numbers index a vector (a hash per row cost more than
/// the row's other bookkeeping); any other number goes to a map.
#[derive(Default)]
struct ChannelTable {
    dense: Vec<Option<ChannelState>>,
    sparse: HashMap<u32, ChannelState>,
}

impl ChannelTable {
    /// Channel numbers below this are indexed directly.
    const DENSE: u32 = 4096;

    #[inline]
    fn get(&self, channel: u32) -> Option<&ChannelState> {
        if channel < Self::DENSE {
            self.dense.get(channel as usize).and_then(Option::as_ref)
        } else {
            self.sparse.get(&channel)
        }
    }

    #[inline]
    fn set(&mut self, channel: u32, state: ChannelState) {
        if channel < Self::DENSE {
            let i = channel as usize;
            if i >= self.dense.len() {
                self.dense.resize_with(i + 1, || None);
            }
            self.dense[i] = Some(state);
        } else {
            self.sparse.insert(channel, state);
        }
    }

    /// Every channel seen, with its state.
    fn entries(&self) -> impl Iterator<Item = (u32, &ChannelState)> {
        let dense = self.dense.iter().enumerate().filter_map(|(c, s)| Some((c as u32, s.as_ref()?)));
        dense.chain(self.sparse.iter().map(|(&c, s)| (c, s)))
    }
}

/// One row's values, as parsed.
#[derive(Clone, Copy)]
struct RowValues {
    t_s: f64,
    channel: u32,
    prn: u32,
    cn0_dbhz: f64,
    elev_deg: f64,
    phase_err_rad: f64,
    carrier: Carrier,
    /// `nco_phase_cycles` and `nco_freq_hz`, when the log has the columns.
    nco: [Option<f64>; 2],
}

impl RowValues {
    /// The values of a parsed record (an unknown elevation as NaN, GPS L1 without a carrier).
    #[inline]
    fn of(r: &TrackingRecord) -> Self {
        RowValues {
            t_s: r.row.t_s,
            channel: r.row.channel,
            prn: r.row.prn,
            cn0_dbhz: r.row.cn0_dbhz,
            elev_deg: r.row.elev_deg.unwrap_or(f64::NAN),
            phase_err_rad: r.row.phase_err_rad,
            carrier: r.carrier_or_l1(),
            nco: [r.nco_phase_cycles, r.nco_freq_hz],
        }
    }
}

/// Assembles a [`TrackingLog`] row by row with the format's checks (time
/// stamps non-decreasing, one row per channel per epoch), shared by the CSV
/// reader and [`TrackingLog::from_rows`].
struct Builder {
    file: String,
    /// The `t_s` and `channel` columns, for errors.
    t_column: Column,
    channel_column: Column,
    /// The column that gives the carrier (for errors), `None` without carrier columns.
    carrier_column: Option<Column>,
    tracks: Vec<ChannelTrack>,
    /// The latest line of each track.
    track_line: Vec<u64>,
    track_of: HashMap<(u32, u32), usize>,
    channels: ChannelTable,
    epoch_t_s: Vec<f64>,
    epoch_line: Vec<u64>,
    rows: usize,
    prev: Option<(f64, u64)>,
}

impl Builder {
    fn new(file: String, t_column: Column, channel_column: Column, carrier_column: Option<Column>) -> Self {
        Builder {
            file,
            t_column,
            channel_column,
            carrier_column,
            tracks: Vec::new(),
            track_line: Vec::new(),
            track_of: HashMap::new(),
            channels: ChannelTable::default(),
            epoch_t_s: Vec::new(),
            epoch_line: Vec::new(),
            rows: 0,
            prev: None,
        }
    }

    fn track_for(&mut self, channel: u32, prn: u32, carrier: Carrier) -> usize {
        let (tracks, lines) = (&mut self.tracks, &mut self.track_line);
        *self.track_of.entry((channel, prn)).or_insert_with(|| {
            tracks.push(ChannelTrack::new(channel, prn, carrier));
            lines.push(0);
            tracks.len() - 1
        })
    }

    /// Adds the row on 1-based `line`.
    #[inline]
    fn push(&mut self, r: &RowValues, line: u64) -> Result<(), FormatError> {
        let t = r.t_s;
        match self.prev {
            Some((prev_t, prev_line)) if t < prev_t => {
                return Err(FormatError::TimeBackwards {
                    file: self.file.clone(),
                    line,
                    column: self.t_column.clone(),
                    t_s: t,
                    previous_t_s: prev_t,
                    previous_line: prev_line,
                });
            }
            Some((prev_t, _)) if t == prev_t => {}
            _ => {
                self.epoch_t_s.push(t);
                self.epoch_line.push(line);
            }
        }
        self.prev = Some((t, line));

        let (channel, prn) = (r.channel, r.prn);
        let track = match self.channels.get(channel) {
            Some(state) => {
                // Time stamps are non-decreasing overall, so equality is the only
                // way this channel can fail to be strictly increasing.
                if state.last_t_s == t {
                    return Err(FormatError::RepeatedChannel {
                        file: self.file.clone(),
                        line,
                        column: self.channel_column.clone(),
                        channel,
                        t_s: t,
                        previous_line: state.last_line,
                    });
                }
                let mut track = state.track;
                if self.tracks[track].prn != prn {
                    track = self.track_for(channel, prn, r.carrier);
                }
                track
            }
            None => self.track_for(channel, prn, r.carrier),
        };
        if self.tracks[track].carrier != r.carrier {
            let previous = self.tracks[track].carrier;
            return Err(FormatError::CarrierChanged {
                file: self.file.clone(),
                line,
                column: self.carrier_column.clone().unwrap_or_else(|| self.channel_column.clone()),
                channel,
                prn,
                carriers: Box::new([previous.label(), r.carrier.label()]),
                previous_line: self.track_line[track],
            });
        }
        self.track_line[track] = line;
        self.channels.set(channel, ChannelState { last_t_s: t, last_line: line, track });
        let tr = &mut self.tracks[track];
        tr.t_s.push(t);
        tr.phase_err_rad.push(r.phase_err_rad);
        tr.cn0_dbhz.push(r.cn0_dbhz);
        tr.elev_deg.push(r.elev_deg);
        if let Some(v) = r.nco[0] {
            tr.nco_phase_cycles.push(v);
        }
        if let Some(v) = r.nco[1] {
            tr.nco_freq_hz.push(v);
        }
        self.rows += 1;
        Ok(())
    }

    /// Reserves every track's columns for the rest of a source of
    /// `total_bytes`, `bytes_read` of it read: each track's share of the rows
    /// so far, of the rows the remaining bytes hold at the average row length
    /// so far (2 % spare). Growing by doubling instead would leave up to half
    /// of each column unused and copy it on every growth.
    fn reserve_for(&mut self, bytes_read: u64, total_bytes: u64) {
        if self.rows == 0 || bytes_read == 0 || total_bytes <= bytes_read {
            return;
        }
        let rows_left = crate::plain::rows_in(total_bytes - bytes_read, self.rows, bytes_read);
        for tr in &mut self.tracks {
            let share = tr.t_s.len() as f64 / self.rows as f64;
            let extra = (1.02 * share * rows_left) as usize + 16;
            tr.t_s.reserve_exact(extra);
            tr.phase_err_rad.reserve_exact(extra);
            tr.cn0_dbhz.reserve_exact(extra);
            tr.elev_deg.reserve_exact(extra);
        }
        let epochs_left = (rows_left * self.epoch_t_s.len() as f64 / self.rows as f64) as usize + 16;
        self.epoch_t_s.reserve_exact(epochs_left);
        self.epoch_line.reserve_exact(epochs_left);
    }

    /// Appends the rows of `next`, the builder of the rows that follow this
    /// one's in the same file (its lines counted from 1 at its first byte,
    /// `line_offset` lines into the file), with the checks that span the
    /// two: `None` when one fails (the `csv` reader then finds it). The
    /// joined builder takes `next`'s per-channel state, so that the rows of
    /// a further chunk can join it in turn.
    fn join(mut self, next: Builder, line_offset: u64) -> Option<Builder> {
        use rayon::prelude::*;
        let (Some((last_t, _)), Some(&next_t)) = (self.prev, next.epoch_t_s.first()) else {
            return if next.rows == 0 { Some(self) } else { None };
        };
        if next_t < last_t {
            return None;
        }
        // A channel's first row in `next` must be at a later epoch than its
        // last one here; each channel's first track in `next` holds it.
        let mut seen = std::collections::HashSet::new();
        for tr in &next.tracks {
            if seen.insert(tr.channel) && self.channels.get(tr.channel).is_some_and(|s| s.last_t_s == tr.t_s[0]) {
                return None;
            }
            if let Some(&k) = self.track_of.get(&(tr.channel, tr.prn))
                && self.tracks[k].carrier != tr.carrier
            {
                return None;
            }
        }
        let skip = usize::from(next_t == last_t);
        self.epoch_t_s.extend_from_slice(&next.epoch_t_s[skip..]);
        self.epoch_line.extend(next.epoch_line[skip..].iter().map(|l| l + line_offset));
        self.rows += next.rows;
        self.prev = next.prev.map(|(t, line)| (t, line + line_offset));
        // Where each of `next`'s tracks is here, its columns to append when it continues one.
        let mut index = Vec::with_capacity(next.tracks.len());
        let mut appended: Vec<Option<ChannelTrack>> = Vec::with_capacity(self.tracks.len());
        appended.resize_with(self.tracks.len(), || None);
        for (tr, line) in next.tracks.into_iter().zip(next.track_line) {
            let k = match self.track_of.get(&(tr.channel, tr.prn)) {
                Some(&k) => {
                    appended[k] = Some(tr);
                    k
                }
                None => {
                    let k = self.tracks.len();
                    self.track_of.insert((tr.channel, tr.prn), k);
                    self.tracks.push(tr);
                    self.track_line.push(0);
                    appended.push(None);
                    k
                }
            };
            self.track_line[k] = line + line_offset;
            index.push(k);
        }
        for (channel, state) in next.channels.entries() {
            let state = ChannelState {
                last_t_s: state.last_t_s,
                last_line: state.last_line + line_offset,
                track: index[state.track],
            };
            self.channels.set(channel, state);
        }
        // Each continued track's columns appended on their own (tens of MB for a long log).
        let append = |(to, tr): (&mut ChannelTrack, ChannelTrack)| {
            to.t_s.extend_from_slice(&tr.t_s);
            to.phase_err_rad.extend_from_slice(&tr.phase_err_rad);
            to.cn0_dbhz.extend_from_slice(&tr.cn0_dbhz);
            to.elev_deg.extend_from_slice(&tr.elev_deg);
            to.nco_phase_cycles.extend_from_slice(&tr.nco_phase_cycles);
            to.nco_freq_hz.extend_from_slice(&tr.nco_freq_hz);
        };
        let pairs = self.tracks.iter_mut().zip(appended).filter_map(|(to, tr)| Some((to, tr?)));
        if next.rows >= JOIN_PARALLEL_ROWS {
            pairs.collect::<Vec<_>>().into_par_iter().for_each(append);
        } else {
            pairs.for_each(append);
        }
        Some(self)
    }

    fn finish(self) -> Result<TrackingLog, FormatError> {
        if self.rows == 0 {
            return Err(FormatError::NoData { file: self.file });
        }
        Ok(TrackingLog {
            source_name: self.file,
            tracks: self.tracks,
            epoch_t_s: self.epoch_t_s,
            epoch_line: self.epoch_line,
            t_column: self.t_column,
            rows: self.rows,
        })
    }
}

impl TrackingLog {
    /// A tracking log from rows in memory (e.g. a simulator's output), checked
    /// exactly as [`read_tracking`] checks a file: finite values (an elevation
    /// of `None` is unknown), non-decreasing time stamps, one row per channel
    /// per epoch. Every row is on GPS L1 ([`TrackingLog::from_rows_on`] for
    /// other carriers). Errors name `source_name` and the line each row would
    /// have in `tracking.csv` as [`crate::TrackingWriter`] writes it (row i on
    /// line i + 2, columns in [`TRACKING_COLUMNS`] order).
    ///
    /// The rows may be borrowed or owned (an iterator that makes them, so that
    /// no row table need exist beside the caller's columns).
    pub fn from_rows<R: Borrow<TrackingRow>>(
        source_name: &str,
        rows: impl IntoIterator<Item = R>,
    ) -> Result<TrackingLog, FormatError> {
        Self::build(source_name, rows.into_iter().map(|r| (r, Carrier::GPS_L1, [None; 2])), false, [None; 2])
    }

    /// [`TrackingLog::from_rows`] with each row's carrier, checked as the reader
    /// checks the carrier columns (within the GNSS bands, one carrier per
    /// track); errors name the `carrier_hz` column as
    /// [`crate::TrackingWriter::with_carriers`] writes it (column 8).
    pub fn from_rows_on<R: Borrow<TrackingRow>>(
        source_name: &str,
        rows: impl IntoIterator<Item = (R, Carrier)>,
    ) -> Result<TrackingLog, FormatError> {
        Self::build(source_name, rows.into_iter().map(|(r, c)| (r, c, [None; 2])), true, [None; 2])
    }

    /// [`TrackingLog::from_rows_on`] with each row's NCO record
    /// `[nco_phase_cycles, nco_freq_hz]` ([`NCO_COLUMNS`]), kept per track as
    /// the reader keeps those columns; a non-finite value is an error naming
    /// its column as a writer with carrier columns and the two NCO columns
    /// writes it (columns 9 and 10).
    pub fn from_rows_with_nco<R: Borrow<TrackingRow>>(
        source_name: &str,
        rows: impl IntoIterator<Item = (R, Carrier, [f64; 2])>,
    ) -> Result<TrackingLog, FormatError> {
        let first_nco = TRACKING_COLUMNS.len() + 3;
        let rows = rows.into_iter().map(|(r, c, [phase, freq])| (r, c, [Some(phase), Some(freq)]));
        Self::build(source_name, rows, true, [Some(first_nco), Some(first_nco + 1)])
    }

    /// A tracking log from records in memory with the columns of the first
    /// ([`TrackingRecord::header`]: the carrier and NCO columns it has),
    /// checked as [`TrackingLog::from_rows`] checks rows and as the reader
    /// checks those columns. Errors name `source_name`, the line and the
    /// column each record would have in the `tracking.csv` that
    /// [`crate::TrackingWriter::for_record`] writes; a record without a
    /// column the first has is an error naming it, one with a column more
    /// an error counting them.
    pub fn from_records<R: Borrow<TrackingRecord>>(
        source_name: &str,
        records: impl IntoIterator<Item = R>,
    ) -> Result<TrackingLog, FormatError> {
        let mut records = records.into_iter().peekable();
        let header = records.peek().map(|r| r.borrow().header()).unwrap_or_else(|| TRACKING_COLUMNS.to_vec());
        let position = |name: &str| header.iter().position(|h| *h == name).map(|i| i + 1);
        let nco_index = [position(NCO_COLUMNS[0]), position(NCO_COLUMNS[1])];
        let carrier_columns = position(CARRIER_COLUMNS[0]).is_some();
        let mut line = 1;
        let mut checked = Vec::new();
        let rows = records.map_while(|r| {
            let r = *r.borrow();
            line += 1;
            let columns = r.header();
            if columns == header {
                return Some((r.row, r.carrier_or_l1(), [r.nco_phase_cycles, r.nco_freq_hz]));
            }
            let file = source_name.to_owned();
            checked.push(match header.iter().position(|h| !columns.contains(h)) {
                Some(i) => FormatError::EmptyCell {
                    file,
                    line,
                    column: Column { index: i + 1, name: header[i].to_owned() },
                    expected: if i < TRACKING_COLUMNS.len() + 2 && carrier_columns {
                        "the row's carrier (a signal name or carrier_hz)"
                    } else {
                        "a number"
                    },
                },
                None => FormatError::FieldCount { file, line, expected: header.len(), found: columns.len() },
            });
            None
        });
        let log = Self::build(source_name, rows, carrier_columns, nco_index);
        match checked.pop() {
            Some(e) => Err(e),
            None => log,
        }
    }

    /// The log of `rows`, each with its carrier and NCO values, written with
    /// the carrier columns (`signal,carrier_hz` after the six) when
    /// `carrier_columns` and the NCO columns at the 1-based `nco_index`
    /// (for errors); a row's NCO value is `None` where its column is absent.
    fn build<R: Borrow<TrackingRow>>(
        source_name: &str,
        rows: impl IntoIterator<Item = (R, Carrier, [Option<f64>; 2])>,
        carrier_columns: bool,
        nco_index: [Option<usize>; 2],
    ) -> Result<TrackingLog, FormatError> {
        let column = |i: usize| Column { index: i + 1, name: TRACKING_COLUMNS[i].to_owned() };
        let carrier_column = Column { index: TRACKING_COLUMNS.len() + 2, name: "carrier_hz".to_owned() };
        let mut b =
            Builder::new(source_name.to_owned(), column(0), column(1), carrier_columns.then(|| carrier_column.clone()));
        for (i, (row, carrier, nco)) in rows.into_iter().enumerate() {
            let row = row.borrow();
            let line = i as u64 + 2;
            let finite = |v: f64, col: usize| {
                if v.is_finite() {
                    Ok(v)
                } else {
                    Err(FormatError::NonFinite {
                        file: source_name.to_owned(),
                        line,
                        column: column(col),
                        value: v.to_string(),
                    })
                }
            };
            let nco_finite = |v: Option<f64>, k: usize| match v {
                Some(v) if !v.is_finite() => {
                    let index = nco_index[k].unwrap_or(TRACKING_COLUMNS.len() + 3 + k);
                    let column = Column { index, name: NCO_COLUMNS[k].to_owned() };
                    Err(FormatError::NonFinite { file: source_name.to_owned(), line, column, value: v.to_string() })
                }
                v => Ok(v),
            };
            let checked = Carrier::from_hz(carrier.carrier_hz).and_then(|_| match carrier.signal {
                Some(s) => s.check_carrier(carrier.carrier_hz),
                None => Ok(()),
            });
            if let Err(error) = checked {
                return Err(FormatError::InvalidCarrier {
                    file: source_name.to_owned(),
                    line,
                    column: carrier_column,
                    error: Box::new(error),
                });
            }
            let values = RowValues {
                t_s: finite(row.t_s, 0)?,
                channel: row.channel,
                prn: row.prn,
                cn0_dbhz: finite(row.cn0_dbhz, 3)?,
                elev_deg: match row.elev_deg {
                    Some(e) => finite(e, 4)?,
                    None => f64::NAN,
                },
                phase_err_rad: finite(row.phase_err_rad, 5)?,
                carrier,
                nco: [nco_finite(nco[0], 0)?, nco_finite(nco[1], 1)?],
            };
            b.push(&values, line)?;
        }
        b.finish()
    }
}

/// Reads a `tracking.csv` stream. `source_name` names the source in error
/// messages (typically the file name).
pub fn read_tracking<R: Read>(input: R, source_name: &str) -> Result<TrackingLog, FormatError> {
    read_tracking_sized(input, source_name, None)
}

/// The time stamp of the previous row: the rows of one epoch share the
/// text of their stamp, which is then parsed once.
#[derive(Default)]
pub(crate) struct StampCache {
    text: Vec<u8>,
    t_s: Option<f64>,
}

impl StampCache {
    /// The stamp of `cell`: the previous row's when the text is the same,
    /// else `parse()`.
    #[inline]
    pub(crate) fn get<E>(&mut self, cell: &[u8], parse: impl FnOnce() -> Result<f64, E>) -> Result<f64, E> {
        match self.t_s {
            Some(t) if cell == self.text.as_slice() => Ok(t),
            _ => {
                let t = parse()?;
                self.text.clear();
                self.text.extend_from_slice(cell);
                self.t_s = Some(t);
                Ok(t)
            }
        }
    }
}

/// Rows read before the columns are reserved for the rest of a source of known size.
const ROWS_BEFORE_RESERVE: usize = 4096;

/// [`read_tracking`] of a source of `total_bytes` (a file's length): the
/// columns are sized for the whole source after its first rows.
fn read_tracking_sized<R: Read>(
    input: R,
    source_name: &str,
    total_bytes: Option<u64>,
) -> Result<TrackingLog, FormatError> {
    let (mut src, _) = CsvSource::open(input, source_name, &TRACKING_COLUMNS)?;
    let columns = columns_of(&src)?;
    let mut b = builder_for(&src, &columns);
    read_rows(&mut src, &columns, &mut b, total_bytes)?;
    b.finish()
}

/// The columns of `src`'s header (read).
fn columns_of<R: Read>(src: &CsvSource<R>) -> Result<TrackingColumns, FormatError> {
    TrackingColumns::from_header(&src.header).map_err(|e| src.header_error(e))
}

/// An empty builder for the rows of `src` (its header read, its `columns`).
fn builder_for<R: Read>(src: &CsvSource<R>, columns: &TrackingColumns) -> Builder {
    let [ct, cch, ..] = columns.required();
    let carrier_column = columns.carrier_column().map(|c| src.column(c));
    Builder::new(src.file.clone(), src.column(ct), src.column(cch), carrier_column)
}

/// Reads every remaining record of `src` into `b` by the row parser of
/// `columns`; `total_bytes` sizes the columns after the first rows (the
/// rest of the source at the average row length so far).
fn read_rows<R: Read>(
    src: &mut CsvSource<R>,
    columns: &TrackingColumns,
    b: &mut Builder,
    total_bytes: Option<u64>,
) -> Result<(), FormatError> {
    let mut parser = RowParser::new(columns);
    while src.next_record()? {
        src.check_field_count()?;
        let record = parser.record(|i| src.cell(i)).map_err(|f| src.cell_error(f))?;
        b.push(&RowValues::of(&record), src.line())?;
        if let Some(total) = total_bytes.filter(|_| b.rows == ROWS_BEFORE_RESERVE) {
            b.reserve_for(src.record.position().map_or(0, |p| p.byte()), total);
        }
    }
    Ok(())
}

/// Tracks appended at least this many rows in all when two chunks are joined
/// are copied in parallel, track by track; fewer are copied sooner than the
/// work is handed out.
const JOIN_PARALLEL_ROWS: usize = 1 << 16;

/// The bytes of rows in one chunk of a file read on the fast path: chunks
/// are parsed at once and joined in file order, so the log does not depend
/// on how many threads parse them. Large enough that a chunk's join costs
/// little beside its parsing; small enough that a chunk's columns (tens of
/// kB each for a dozen channels) are memory the allocator hands out again,
/// not fresh pages mapped and unmapped per chunk (8 MiB chunks cost the
/// 1-hour log 11 000 more page faults; BENCHMARKS.md).
const CHUNK_BYTES: u64 = 2 << 20;

/// Chunks parsed at once, while the wave before them is joined: enough to
/// keep a few threads busy, few enough that their columns beside the joined
/// log's stay small (a fixed number, so the memory does not grow with the
/// threads).
const WAVE_CHUNKS: usize = 4;

/// Opens and reads a `tracking.csv` file; errors name the file by its path.
///
/// A file without quotes or carrier columns is parsed on the fast path (the
/// cells parsed in place) in chunks of a fixed size in bytes, split at line
/// ends, several at once, and the chunks joined with the checks that span them
/// (time stamps non-decreasing, one row per channel per epoch). The result
/// is the log the `csv` reader gives; when anything stops a chunk (an error,
/// a quote character that could hide a line end, a check across chunks
/// failing) the file is read again by the `csv` reader, so the error
/// reported is the first in the file, with its line and column.
pub fn read_tracking_file(path: impl AsRef<Path>) -> Result<TrackingLog, FormatError> {
    let path = path.as_ref();
    let name = path_name(path);
    let file = std::fs::File::open(path).map_err(|e| FormatError::io(&name, e))?;
    let total_bytes = file.metadata().ok().map(|m| m.len());
    if let Some(log) = total_bytes.and_then(|total| read_plain(path, &name, total, CHUNK_BYTES)) {
        return Ok(log);
    }
    read_tracking_sized(file, &name, total_bytes)
}

/// The file read on the quote-free fast path ([`crate::plain`]), `None`
/// where [`read_tracking_file`] reads it with `csv`: for the differential
/// fuzz target (the fast path must give the `csv` reader's log), not for use.
#[doc(hidden)]
pub fn read_tracking_file_plain(path: &Path) -> Option<TrackingLog> {
    let total = std::fs::metadata(path).ok()?.len();
    read_plain(path, &path_name(path), total, CHUNK_BYTES)
}

/// [`read_tracking_file_plain`] with chunks of about `chunk_bytes` (at least
/// 1): for the differential fuzz target, so that short inputs are read in
/// many chunks (the joined chunks must give the `csv` reader's log).
#[doc(hidden)]
pub fn read_tracking_file_in_chunks(path: &Path, chunk_bytes: u64) -> Option<TrackingLog> {
    let total = std::fs::metadata(path).ok()?.len();
    read_plain(path, &path_name(path), total, chunk_bytes.max(1))
}

/// A file without quotes and carrier columns read on the fast path
/// ([`crate::plain`]), in chunks of about `chunk_bytes` parsed at once.
/// `None` (the `csv` path then reads it, and reports the first error in the
/// file) for anything else: a quote, a lone `\r`, blank lines before the
/// header, carrier columns, a row the `csv` path would refuse, chunks that
/// do not join.
fn read_plain(path: &Path, name: &str, total: u64, chunk_bytes: u64) -> Option<TrackingLog> {
    use rayon::prelude::*;
    let crate::plain::PlainFile { mut file, header: src, cols, data_start: start } =
        crate::plain::open_plain(path, name, &TRACKING_COLUMNS, total)?;
    let columns = columns_of(&src).ok()?;
    if columns.has_optional() {
        return None;
    }
    let fields = src.header.len();
    let bounds = crate::plain::chunk_bounds(&mut file, start, total, chunk_bytes)?;
    let chunks: Vec<(usize, (u64, u64))> = bounds.windows(2).map(|w| (w[0], w[1])).enumerate().collect();
    let parse = |&(k, (from, to)): &(usize, (u64, u64))| {
        let mut b = builder_for(&src, &columns);
        // The first chunk's columns are sized for the whole file: the others' rows join them.
        let (first_line, reserve) = if k == 0 { (2, total - start) } else { (1, to - from) };
        let input = crate::plain::byte_range(path, from, to)?;
        let newlines = plain_rows(input, first_line, &cols, fields, &mut b, reserve)?;
        Some((b, newlines))
    };
    // The chunks parsed so far joined in file order, with the lines before the next chunk.
    let join_all = |mut joined: Option<(Builder, u64)>, parsed: Vec<Option<(Builder, u64)>>| {
        for chunk in parsed {
            let (b, newlines) = chunk?;
            joined = Some(match joined {
                // The header's line and the first chunk's precede the next chunk's first byte.
                None => (b, 1 + newlines),
                // A later chunk's lines count from 1 at its first byte.
                Some((log, lines_before)) => (log.join(b, lines_before)?, lines_before + newlines),
            });
        }
        Some(joined)
    };
    // A wave of chunks at a time, parsed while the wave before it is joined
    // (the joins are serial, and fault in the log's own pages): the chunks'
    // own columns held at once stay two waves' worth.
    let mut joined: Option<(Builder, u64)> = None;
    let mut parsed: Vec<Option<(Builder, u64)>> = Vec::new();
    for wave in chunks.chunks(WAVE_CHUNKS).map(Some).chain([None]) {
        let before = std::mem::take(&mut parsed);
        let (next, so_far) = rayon::join(
            || wave.map_or_else(Vec::new, |w| w.par_iter().map(parse).collect()),
            || join_all(joined.take(), before),
        );
        joined = so_far?;
        parsed = next;
    }
    let (log, _) = joined?;
    log.finish().ok()
}

/// The rows of `input` (lines from `first_line` on, `fields` cells each,
/// the columns of [`TRACKING_COLUMNS`] at `cols`) into `b`, on the fast
/// path; the columns are sized after the first rows for `reserve_bytes` of
/// rows. The number of line ends read, `None` at the first row the `csv`
/// path must read (to report it, or to read what this path does not).
fn plain_rows(
    input: impl Read,
    first_line: u64,
    cols: &[usize],
    fields: usize,
    b: &mut Builder,
    reserve_bytes: u64,
) -> Option<u64> {
    use crate::parse::{cell_f64, cell_u32};
    use crate::plain::{Cells, Record, for_each_plain_line, split};
    let (ct, cch, cprn, ccn0, celev, cphase) = (cols[0], cols[1], cols[2], cols[3], cols[4], cols[5]);
    let mut stamp = StampCache::default();
    // What each cell of a row is, for the reading in place.
    #[derive(Clone, Copy)]
    enum Cell {
        Other,
        T,
        Channel,
        Prn,
        Cn0,
        Elev,
        Phase,
    }
    let mut layout = vec![Cell::Other; fields];
    for (at, cell) in [(ct, Cell::T), (cch, Cell::Channel), (cprn, Cell::Prn), (ccn0, Cell::Cn0)]
        .into_iter()
        .chain([(celev, Cell::Elev), (cphase, Cell::Phase)])
    {
        layout[at] = cell;
    }
    let nan = f64::NAN;
    let blank = RowValues {
        t_s: nan,
        channel: 0,
        prn: 0,
        cn0_dbhz: nan,
        elev_deg: nan,
        phase_err_rad: nan,
        carrier: Carrier::GPS_L1,
        nco: [None; 2],
    };
    // The writer's layout (the six columns in their order, nothing else) is
    // read cell after cell without consulting the layout.
    let writers_layout = fields == TRACKING_COLUMNS.len() && cols.iter().enumerate().all(|(i, &c)| c == i);
    let mut values = |text: &[u8]| -> Option<RowValues> {
        if writers_layout {
            let mut cells = Cells::new(text);
            let mut stamp_of = |cells: &mut Cells| match stamp.t_s {
                // The rows of an epoch repeat its stamp's text.
                Some(t) if cells.skip_if(&stamp.text) => Some(t),
                _ => cells.text().and_then(|c| stamp.get(c, || cell_f64(c).ok().flatten().ok_or(())).ok()),
            };
            let row = (|| {
                Some(RowValues {
                    t_s: stamp_of(&mut cells)?,
                    channel: cells.integer()?,
                    prn: cells.integer()?,
                    cn0_dbhz: cells.number()??,
                    elev_deg: cells.number()?.unwrap_or(nan),
                    phase_err_rad: cells.fraction()??,
                    carrier: Carrier::GPS_L1,
                    nco: [None; 2],
                })
            })();
            if let Some(r) = row.filter(|_| cells.finished()) {
                return Some(r);
            }
        }
        // In place first; a row it does not take is split and read by the rules.
        let mut cells = Cells::new(text);
        let mut r = blank;
        let in_place = layout.iter().all(|cell| {
            let got = match cell {
                Cell::Other => cells.text().map(|_| ()),
                Cell::T => match stamp.t_s {
                    // The rows of an epoch repeat its stamp's text.
                    Some(t) if cells.skip_if(&stamp.text) => {
                        r.t_s = t;
                        Some(())
                    }
                    _ => cells
                        .text()
                        .and_then(|c| stamp.get(c, || cell_f64(c).ok().flatten().ok_or(())).ok())
                        .map(|t| r.t_s = t),
                },
                Cell::Channel => cells.integer().map(|v| r.channel = v),
                Cell::Prn => cells.integer().map(|v| r.prn = v),
                Cell::Cn0 => cells.number().flatten().map(|v| r.cn0_dbhz = v),
                Cell::Elev => cells.number().map(|v| r.elev_deg = v.unwrap_or(nan)),
                Cell::Phase => cells.fraction().flatten().map(|v| r.phase_err_rad = v),
            };
            got.is_some()
        });
        if in_place && cells.finished() {
            return Some(r);
        }
        let f = split(text);
        if f.len() != fields {
            return None;
        }
        let t_s = stamp.get(f[ct], || cell_f64(f[ct]).ok().flatten().ok_or(())).ok()?;
        Some(RowValues {
            t_s,
            channel: cell_u32(f[cch]).ok()?,
            prn: cell_u32(f[cprn]).ok()?,
            cn0_dbhz: cell_f64(f[ccn0]).ok()??,
            elev_deg: cell_f64(f[celev]).ok()?.unwrap_or(f64::NAN),
            phase_err_rad: cell_f64(f[cphase]).ok()??,
            carrier: Carrier::GPS_L1,
            nco: [None; 2],
        })
    };
    for_each_plain_line(input, first_line, |line, bytes_before, text| {
        let Some(row) = values(text) else { return Record::Decline };
        if b.push(&row, line).is_err() {
            return Record::Decline;
        }
        if b.rows == ROWS_BEFORE_RESERVE {
            b.reserve_for(bytes_before, reserve_bytes);
        }
        Record::Next
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const HEADER: &str = "t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad\n";

    fn read(body: &str) -> Result<TrackingLog, FormatError> {
        read_tracking(format!("{HEADER}{body}").as_bytes(), "tracking.csv")
    }

    fn err(body: &str) -> String {
        err_raw(&format!("{HEADER}{body}"))
    }

    fn err_raw(text: &str) -> String {
        let msg = read_tracking(text.as_bytes(), "tracking.csv").expect_err("expected an error").to_string();
        assert!(msg.starts_with("tracking.csv"), "message does not name the source: {msg}");
        msg
    }

    /// Errors and epochs name the line a row is on, after blank lines and
    /// with CRLF line ends too (the `csv` crate's own count names the blank
    /// line above; found by the differential fuzz target, whose faster
    /// reading counted right and disagreed).
    #[test]
    fn lines_count_blank_lines_and_crlf() {
        let row1 = "0.15,1,28,47.1,63.1,-0.09";
        let bad = "0.175,1,28,47.1,63.1,abc";
        for (text, line) in [
            (format!("{HEADER}{row1}\n\n{bad}\n"), 4),
            (format!("{HEADER}{row1}\n\n\n\n{bad}\n"), 6),
            (format!("{HEADER}{row1}\n{bad}"), 3),
            (format!("{}\r\n{row1}\r\n{bad}\r\n", HEADER.trim_end()), 3),
            (format!("{}\r\n{row1}\r\n\r\n{bad}\r\n", HEADER.trim_end()), 4),
            (format!("\n\n{HEADER}{row1}\n{bad}\n"), 5),
            // A quoted cell holding a line end: the next row is a line further.
            (format!("{HEADER}0.15,1,28,\"47.1\n\",63.1,-0.09\n{bad}\n"), 4),
        ] {
            let msg = err_raw(&text);
            assert!(msg.contains(&format!("line {line},")), "{text:?}: {msg}");
        }
        let log = read(&format!("{row1}\n\n0.175,1,28,47.1,63.1,-0.12\n\n")).unwrap();
        assert_eq!(log.epoch_line(), &[2, 4]);
    }

    #[test]
    fn reads_channels_appearing_disappearing_reappearing() {
        let log = read(
            "0,1,5,45,30,0.01\n0,2,7,40,,0.02\n\
             0.025,2,7,41,12.5,0.03\n\
             0.05,1,5,46,31,0.04\n0.05,2,7,42,13,0.05\n\
             0.075,2,9,38,20,0.06\n",
        )
        .unwrap();
        assert_eq!(log.source_name(), "tracking.csv");
        assert_eq!(log.rows(), 6);
        assert_eq!(log.epoch_t_s(), &[0.0, 0.025, 0.05, 0.075]);
        assert_eq!(log.epoch_line(), &[2, 4, 5, 7]);
        let tr = log.tracks();
        assert_eq!(tr.len(), 3);
        assert_eq!((tr[0].channel, tr[0].prn), (1, 5));
        assert_eq!(tr[0].t_s, vec![0.0, 0.05]);
        assert_eq!(tr[0].phase_err_rad, vec![0.01, 0.04]);
        assert_eq!(tr[0].cn0_dbhz, vec![45.0, 46.0]);
        assert_eq!((tr[1].channel, tr[1].prn), (2, 7));
        assert_eq!(tr[1].t_s, vec![0.0, 0.025, 0.05]);
        assert!(tr[1].elev_deg[0].is_nan());
        assert_eq!(&tr[1].elev_deg[1..], &[12.5, 13.0]);
        // Channel 2 re-assigned to PRN 9: a new track.
        assert_eq!((tr[2].channel, tr[2].prn), (2, 9));
        assert_eq!(tr[2].t_s, vec![0.075]);
        assert_eq!(tr[1].mean_cn0_dbhz(), 41.0);
    }

    #[test]
    fn columns_in_any_order_extra_ignored() {
        let log = read_tracking(
            "phase_err_rad,elev_deg,foo,prn,cn0_dbhz,channel,t_s\n0.5,10,x,3,44,7,1.0\n".as_bytes(),
            "tracking.csv",
        )
        .unwrap();
        let tr = &log.tracks()[0];
        assert_eq!((tr.channel, tr.prn, tr.t_s[0], tr.cn0_dbhz[0], tr.elev_deg[0]), (7, 3, 1.0, 44.0, 10.0));
        assert_eq!(tr.phase_err_rad[0], 0.5);
    }

    #[test]
    fn missing_column() {
        let m = err_raw("t_s,channel,prn,cn0_dbhz,phase_err_rad\n0,1,2,40,0.1\n");
        assert!(m.contains("line 1") && m.contains("missing column `elev_deg`"), "{m}");
    }

    #[test]
    fn non_numeric_cells() {
        let m = err("0,1,5,45,30,0.01\n0.025,1,5,4x5,30,0.01\n");
        assert!(m.contains("line 3, column 4 (`cn0_dbhz`)") && m.contains("`4x5` is not a number"), "{m}");
        let m = err("0,1.5,5,45,30,0.01\n");
        assert!(m.contains("line 2, column 2 (`channel`)") && m.contains("not a non-negative integer"), "{m}");
        let m = err("0,1,-5,45,30,0.01\n");
        assert!(m.contains("line 2, column 3 (`prn`)") && m.contains("`-5`"), "{m}");
        let m = err("0,1,5,45,30,\n");
        assert!(m.contains("line 2, column 6 (`phase_err_rad`)") && m.contains("empty cell"), "{m}");
    }

    #[test]
    fn nan_and_inf() {
        let m = err("0,1,5,45,30,nan\n");
        assert!(m.contains("line 2, column 6 (`phase_err_rad`)") && m.contains("not a finite number"), "{m}");
        let m = err("0,1,5,inf,30,0.1\n");
        assert!(m.contains("line 2, column 4 (`cn0_dbhz`)") && m.contains("`inf` is not a finite number"), "{m}");
        // An empty elevation is "unknown"; a literal NaN is an error.
        let m = err("0,1,5,45,NaN,0.1\n");
        assert!(m.contains("line 2, column 5 (`elev_deg`)") && m.contains("not a finite number"), "{m}");
    }

    #[test]
    fn time_backwards() {
        let m = err("0,1,5,45,30,0.01\n0.05,1,5,45,30,0.01\n0.025,2,6,45,30,0.01\n");
        assert!(m.contains("line 4, column 1 (`t_s`)") && m.contains("time stamp 0.025 s goes backwards"), "{m}");
        assert!(m.contains("line 3 has 0.05 s"), "{m}");
    }

    #[test]
    fn same_channel_twice_at_same_time() {
        let m = err("0,1,5,45,30,0.01\n0,2,6,45,30,0.01\n0,1,5,45,30,0.02\n");
        assert!(m.contains("line 4, column 2 (`channel`)") && m.contains("channel 1 appears twice at t = 0 s"), "{m}");
        assert!(m.contains("already on line 2"), "{m}");
        // Even with another PRN: a channel tracks one satellite at a time.
        let m = err("0,1,5,45,30,0.01\n0,1,6,45,30,0.01\n");
        assert!(m.contains("channel 1 appears twice"), "{m}");
    }

    #[test]
    fn channel_numbers_beyond_the_dense_table_are_tracked_alike() {
        // 4095 is the dense table's last index, 4096 and u32::MAX go to its map.
        let log =
            read("0,4095,5,45,30,0.01\n0,4096,6,45,30,0.02\n0,4294967295,7,45,30,0.03\n0.025,4096,6,45,30,0.04\n")
                .unwrap();
        let rows: Vec<(u32, usize)> = log.tracks().iter().map(|t| (t.channel, t.t_s.len())).collect();
        assert_eq!(rows, [(4095, 1), (4096, 2), (4294967295, 1)]);
        let m = err("0,4096,5,45,30,0.01\n0,4096,6,45,30,0.01\n");
        assert!(m.contains("line 3, column 2 (`channel`)") && m.contains("channel 4096 appears twice"), "{m}");
    }

    #[test]
    fn empty_file_and_header_only() {
        let m = err_raw("");
        assert!(m.contains("empty file") && m.contains("t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad"), "{m}");
        let m = err("");
        assert!(m.contains("header only, no data rows"), "{m}");
    }

    fn row(t_s: f64, channel: u32, prn: u32, elev_deg: Option<f64>, phase_err_rad: f64) -> TrackingRow {
        TrackingRow { t_s, channel, prn, cn0_dbhz: 44.5, elev_deg, phase_err_rad }
    }

    #[test]
    fn rows_in_memory_give_the_log_their_csv_gives() {
        let rows = [
            row(0.0, 1, 5, Some(30.0), 0.01),
            row(0.0, 2, 7, None, 0.02),
            row(0.025, 2, 7, Some(12.5), -0.03),
            row(0.05, 1, 5, Some(31.0), 0.04),
            row(0.075, 2, 9, Some(20.0), 0.06),
        ];
        let mut w = crate::TrackingWriter::new(Vec::new()).unwrap();
        for r in &rows {
            w.write_row(r).unwrap();
        }
        let csv = w.finish().unwrap();
        let from_file = read_tracking(csv.as_slice(), "sim").unwrap();
        let from_rows = TrackingLog::from_rows("sim", rows).unwrap();
        assert_eq!(from_rows.tracks().len(), 3);
        assert_eq!(from_rows.tracks()[1].elev_deg[0].to_bits(), from_file.tracks()[1].elev_deg[0].to_bits());
        // NaN ≠ NaN: compare with the unknown elevation blanked out.
        let blank = |mut l: TrackingLog| {
            l.tracks[1].elev_deg[0] = -1.0;
            l
        };
        assert_eq!(blank(from_rows), blank(from_file));
    }

    #[test]
    fn rows_in_memory_are_checked_like_a_file() {
        let e = TrackingLog::from_rows("sim", [row(0.0, 1, 5, None, 0.1), row(0.0, 1, 6, None, 0.1)]);
        let m = e.unwrap_err().to_string();
        assert!(m.starts_with("sim: line 3, column 2 (`channel`)") && m.contains("channel 1 appears twice"), "{m}");
        let e = TrackingLog::from_rows("sim", [row(0.05, 1, 5, None, 0.1), row(0.025, 2, 6, None, 0.1)]);
        let m = e.unwrap_err().to_string();
        assert!(m.contains("line 3, column 1 (`t_s`)") && m.contains("goes backwards"), "{m}");
        let e = TrackingLog::from_rows("sim", [row(0.0, 1, 5, Some(f64::NAN), 0.1)]);
        let m = e.unwrap_err().to_string();
        assert!(m.contains("line 2, column 5 (`elev_deg`)") && m.contains("not a finite number"), "{m}");
        let m = TrackingLog::from_rows("sim", [] as [TrackingRow; 0]).unwrap_err().to_string();
        assert!(m.contains("no data rows"), "{m}");
    }

    fn carrier_of(label: &str) -> Carrier {
        Carrier::of(crate::Signal::from_label(label).unwrap())
    }

    #[test]
    fn carriers_round_trip_through_writer_and_reader() {
        let carriers = [
            carrier_of("L1CA"),
            carrier_of("G1:-7"),
            carrier_of("G1:+6"),
            carrier_of("L5Q"),
            carrier_of("B1I"),
            carrier_of("E1C"),
            Carrier::from_hz(1_227.6e6).unwrap(),
        ];
        let rows: Vec<(TrackingRow, Carrier)> = (0..3)
            .flat_map(|k| {
                carriers.iter().enumerate().map(move |(c, &carrier)| {
                    (row(k as f64 * 0.025, c as u32, 3 + c as u32, Some(20.0), 0.01 * c as f64), carrier)
                })
            })
            .collect();
        let csv = crate::write_tracking_csv_on(Vec::new(), &rows).unwrap();
        let text = String::from_utf8(csv.clone()).unwrap();
        assert!(text.starts_with("t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad,signal,carrier_hz\n"), "{text}");
        assert!(text.contains(",G1,1598062500\n") && text.contains(",,1227600000\n"), "{text}");
        let log = read_tracking(csv.as_slice(), "t.csv").unwrap();
        let back: Vec<Carrier> = log.tracks().iter().map(|t| t.carrier).collect();
        assert_eq!(back, carriers);
        assert_eq!(log.tracks()[1].carrier.signal.unwrap().glo_k(), Some(-7));
        let from_rows = TrackingLog::from_rows_on("t.csv", rows.iter().map(|(r, c)| (r, *c))).unwrap();
        assert_eq!(from_rows.tracks().iter().map(|t| t.carrier).collect::<Vec<_>>(), carriers);
    }

    #[test]
    fn all_l1_rows_are_written_without_carrier_columns() {
        let rows: Vec<(TrackingRow, Carrier)> =
            vec![(row(0.0, 1, 5, None, 0.1), Carrier::GPS_L1), (row(0.0, 2, 6, None, 0.2), carrier_of("L1CA"))];
        let on = crate::write_tracking_csv_on(Vec::new(), &rows).unwrap();
        let plain: Vec<TrackingRow> = rows.iter().map(|r| r.0).collect();
        assert_eq!(on, crate::write_tracking_csv(Vec::new(), &plain).unwrap());
        assert!(on.starts_with(HEADER.as_bytes()));
        // A plain writer refuses a row it cannot hold.
        let mut w = crate::TrackingWriter::new(Vec::new()).unwrap();
        assert!(w.write_row_on(&rows[0].0, &carrier_of("L5I"), &[]).is_err());
        // Old files: every track on L1, unnamed.
        let log = read("0,1,5,45,30,0.01\n0,2,7,40,,0.02\n").unwrap();
        assert!(log.tracks().iter().all(|t| t.carrier == Carrier::GPS_L1));
    }

    #[test]
    fn carrier_columns_in_other_forms() {
        let h = "t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad";
        // glo_k beside the name; carrier_hz alone; both agreeing.
        let log = read_tracking(
            format!("{h},signal,glo_k\n0,1,5,45,30,0.01,G1,3\n0,2,6,45,30,0.01,L5I,\n").as_bytes(),
            "t.csv",
        )
        .unwrap();
        assert_eq!(log.tracks()[0].carrier.carrier_hz, 1_602e6 + 3.0 * 0.5625e6);
        assert_eq!(log.tracks()[1].carrier, carrier_of("L5I"));
        let log = read_tracking(format!("{h},carrier_hz\n0,1,5,45,30,0.01,1561098000\n").as_bytes(), "t.csv").unwrap();
        assert_eq!(log.tracks()[0].carrier, Carrier::from_hz(1_561.098e6).unwrap());
        let log = read_tracking(
            format!("{h},glo_k,signal,carrier_hz\n0,1,5,45,30,0.01,-2,G1,1600875000\n").as_bytes(),
            "t.csv",
        )
        .unwrap();
        assert_eq!(log.tracks()[0].carrier, carrier_of("G1:-2"));
    }

    /// The NCO columns are kept per track, in row order, beside the rest;
    /// a log without them has none, and a log with one has only that one.
    #[test]
    fn nco_columns_are_kept_per_track() {
        let h = "nco_freq_hz,t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad,nco_phase_cycles";
        let body =
            "1200.5,0,1,5,45,30,0.01,100.25\n-800,0,2,6,44,,0.02,-7.5\n1200.75,0.025,1,5,45,30,0.03,130.265625\n";
        let log = read_tracking(format!("{h}\n{body}").as_bytes(), "tracking.csv").unwrap();
        let [a, b] = log.tracks() else { panic!("two tracks") };
        assert_eq!(
            (a.nco_phase_cycles.as_slice(), a.nco_freq_hz.as_slice()),
            (&[100.25, 130.265625][..], &[1200.5, 1200.75][..])
        );
        assert_eq!((b.nco_phase_cycles.as_slice(), b.nco_freq_hz.as_slice()), (&[-7.5][..], &[-800.0][..]));
        let only_phase = read_tracking(
            "t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad,nco_phase_cycles\n0,1,5,45,30,0.01,2.5\n".as_bytes(),
            "tracking.csv",
        )
        .unwrap();
        assert_eq!(only_phase.tracks()[0].nco_phase_cycles, [2.5]);
        assert!(only_phase.tracks()[0].nco_freq_hz.is_empty());
        let plain = read("0,1,5,45,30,0.01\n").unwrap();
        assert!(plain.tracks()[0].nco_phase_cycles.is_empty() && plain.tracks()[0].nco_freq_hz.is_empty());
    }

    #[test]
    fn empty_or_bad_nco_cells_are_errors_naming_line_and_column() {
        let h = "t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad,nco_phase_cycles";
        let m = err_raw(&format!("{h}\n0,1,5,45,30,0.01,2.5\n0,2,6,45,30,0.01,\n"));
        assert!(m.contains("line 3, column 7 (`nco_phase_cycles`)"), "{m}");
        let m = err_raw(&format!("{h}\n0,1,5,45,30,0.01,inf\n"));
        assert!(m.contains("line 2, column 7 (`nco_phase_cycles`)"), "{m}");
    }

    /// A file with NCO columns is read by the `csv` path (the fast path
    /// declines it), with the same result.
    #[test]
    fn a_file_with_nco_columns_reads_the_same_from_a_file() {
        let dir = std::env::temp_dir().join(format!("gsens-io-nco-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("tracking.csv");
        let text =
            "t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad,nco_phase_cycles,nco_freq_hz\n0,1,5,45,30,0.01,2.5,10\n";
        std::fs::write(&path, text).unwrap();
        assert!(read_tracking_file_plain(&path).is_none());
        let from_file = read_tracking_file(&path).unwrap();
        assert_eq!(from_file.tracks(), read_tracking(text.as_bytes(), "tracking.csv").unwrap().tracks());
        assert_eq!(from_file.tracks()[0].nco_freq_hz, [10.0]);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn bad_carriers_are_errors_naming_line_and_column() {
        let h = "t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad";
        let m = err_raw(&format!("{h},signal\n0,1,5,45,30,0.01,L1CA\n0,2,6,45,30,0.01,GAL-E1\n"));
        assert!(m.contains("line 3, column 7 (`signal`)") && m.contains("`GAL-E1` is not a signal gsens knows"), "{m}");
        assert!(
            m.contains("known: L1CA, L2C") && m.contains("B1I") && m.contains("G1 (with glo_k or carrier_hz)"),
            "{m}"
        );
        let m = err_raw(&format!("{h},carrier_hz\n0,1,5,45,30,0.01,1575.42\n"));
        assert!(
            m.contains("line 2, column 7 (`carrier_hz`)") && m.contains("outside the GNSS bands, 1.1–1.7 GHz"),
            "{m}"
        );
        let m = err_raw(&format!("{h},signal\n0,1,5,45,30,0.01,G1\n"));
        assert!(m.contains("line 2, column 7 (`signal`)") && m.contains("frequency channel number k"), "{m}");
        let m = err_raw(&format!("{h},signal,glo_k\n0,1,5,45,30,0.01,G1,9\n"));
        assert!(m.contains("column 8 (`glo_k`)") && m.contains("glo_k = 9"), "{m}");
        let m = err_raw(&format!("{h},signal,carrier_hz\n0,1,5,45,30,0.01,B1I,1575420000\n"));
        assert!(m.contains("column 8 (`carrier_hz`)") && m.contains("disagrees with signal B1I"), "{m}");
        let m = err_raw(&format!("{h},signal,carrier_hz\n0,1,5,45,30,0.01,,\n"));
        assert!(m.contains("line 2, column 7 (`signal`)") && m.contains("empty cell"), "{m}");
        let m = err_raw(&format!("{h},signal,signal\n0,1,5,45,30,0.01,L1CA,L1CA\n"));
        assert!(m.contains("`signal` appears twice"), "{m}");
        // A track keeps its carrier.
        let m = err_raw(&format!("{h},signal\n0,1,5,45,30,0.01,L1CA\n0.025,1,5,45,30,0.01,L5I\n"));
        assert!(m.contains("line 3, column 7 (`signal`)") && m.contains("channel 1 (PRN 5) is on L5I"), "{m}");
        assert!(m.contains("was on L1CA (line 2)"), "{m}");
        // ... but a channel re-assigned to another PRN may change signal.
        let log =
            read_tracking(format!("{h},signal\n0,1,5,45,30,0.01,L1CA\n0.025,1,7,45,30,0.01,L5I\n").as_bytes(), "t.csv")
                .unwrap();
        assert_eq!(log.tracks().len(), 2);
        // In memory: the same checks.
        let r = row(0.0, 1, 5, None, 0.1);
        let e = TrackingLog::from_rows_on("sim", [(&r, Carrier { carrier_hz: 4e6, signal: None })]);
        let m = e.unwrap_err().to_string();
        assert!(m.starts_with("sim: line 2, column 8 (`carrier_hz`)") && m.contains("outside the GNSS bands"), "{m}");
    }

    #[test]
    fn wrong_field_count() {
        let m = err("0,1,5,45,30,0.01\n0.025,1,5,45,0.01\n");
        assert!(m.contains("line 3") && m.contains("expected 6 fields") && m.contains("found 5"), "{m}");
    }

    use crate::test_files::TempFile;

    /// A log of `epochs` epochs of channels 0..`channels` (channel 1 moves to
    /// PRN 30 from epoch `reassign_at`; a channel 9 joins at epoch `join_at`).
    fn log_text(header: &str, epochs: usize, channels: u32, reassign_at: usize, join_at: usize) -> String {
        let mut text = String::from(header);
        for k in 0..epochs {
            let t = k as f64 * 0.025;
            let mut chans: Vec<u32> = (0..channels).collect();
            if k >= join_at {
                chans.push(9);
            }
            for c in chans {
                let prn = if c == 1 && k >= reassign_at { 30 } else { c + 1 };
                let phase = ((k as f64) * 0.37 + f64::from(c)).sin() * 0.05;
                text.push_str(&format!(
                    "{t:.3},{c},{prn},{:.1},{:.1},{phase:.6}\n",
                    40.0 + f64::from(c),
                    30.0 + f64::from(c)
                ));
            }
        }
        text
    }

    /// Read in chunks of any size (wherever the bounds fall in an epoch,
    /// an epoch over several chunks), a file gives the log the `csv` reader
    /// gives: tracks, rows, epochs and their lines, a channel re-assigned
    /// and a channel joining in a later chunk.
    #[test]
    fn chunks_give_the_csv_readers_log() {
        for epochs in 40..52 {
            let text = log_text(HEADER, epochs, 3, epochs * 2 / 3, epochs * 3 / 4);
            let f = TempFile::new(&format!("chunks-{epochs}.csv"), &text);
            let serial = read_tracking(text.as_bytes(), &path_name(&f.0)).unwrap();
            let total = text.len() as u64;
            for chunk in [1, 7, 40, 100, 333, total / 2, total] {
                let chunks = read_plain(&f.0, &path_name(&f.0), total, chunk).expect("a clean file is read in chunks");
                assert_eq!(format!("{chunks:?}"), format!("{serial:?}"), "{epochs} epochs, chunks of {chunk} bytes");
            }
        }
        // Blank lines and CRLF line ends around the bounds: the epochs' lines
        // agree (the fuzz target's finding).
        let text = log_text(HEADER, 44, 3, 30, 33);
        for edit in [text.replace("\n0.5", "\n\n\n0.5"), text.replace('\n', "\r\n"), text.replace("\n", "\n\n")] {
            let f = TempFile::new("chunks-blank.csv", &edit);
            let serial = read_tracking(edit.as_bytes(), &path_name(&f.0)).unwrap();
            for chunk in [1, 5, 64, 500] {
                if let Some(chunks) = read_plain(&f.0, &path_name(&f.0), edit.len() as u64, chunk) {
                    assert_eq!(format!("{chunks:?}"), format!("{serial:?}"), "chunks of {chunk} bytes");
                }
            }
        }
        // Large enough for read_tracking_file to read it in several chunks itself.
        let text = log_text(HEADER, 240_000, 3, 200_000, 220_000);
        assert!(text.len() as u64 >= 2 * CHUNK_BYTES);
        let f = TempFile::new("chunks-large.csv", &text);
        assert_eq!(read_tracking_file(&f.0).unwrap(), read_tracking(text.as_bytes(), &path_name(&f.0)).unwrap());
    }

    /// The file's log is the same bit for bit on pools of 1, 2, 4 and 5
    /// threads: the chunks are cut by the bytes alone, and joined in file
    /// order while the next wave is parsed (several waves, in chunks of the
    /// reader's size and in smaller ones).
    #[test]
    fn the_log_does_not_depend_on_the_threads() {
        let text = log_text(HEADER, 120_000, 3, 60_000, 90_000);
        assert!(text.len() as u64 >= 3 * CHUNK_BYTES, "several chunks per wave");
        let f = TempFile::new("chunks-threads.csv", &text);
        let total = text.len() as u64;
        let small = total / (5 * WAVE_CHUNKS as u64 + 1);
        let on = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| {
                (read_tracking_file(&f.0).unwrap(), read_plain(&f.0, &path_name(&f.0), total, small).unwrap())
            })
        };
        let bits = |log: &TrackingLog| -> Vec<u64> {
            let columns = log.tracks().iter().flat_map(|t| [&t.t_s, &t.phase_err_rad, &t.cn0_dbhz, &t.elev_deg]);
            columns.flatten().map(|v| v.to_bits()).collect()
        };
        let serial = read_tracking(text.as_bytes(), &path_name(&f.0)).unwrap();
        for threads in [1, 2, 4, 5] {
            let (whole, waves) = on(threads);
            assert_eq!(bits(&whole), bits(&serial), "{threads} threads");
            assert_eq!(whole, serial, "{threads} threads");
            assert_eq!(waves, serial, "{threads} threads, six waves");
        }
    }

    /// What the chunks cannot decide alone is read again by the `csv`
    /// reader: the error is the first in the file, with its line.
    #[test]
    fn chunks_leave_errors_to_the_csv_reader() {
        let base = log_text(HEADER, 40, 3, 1000, 1000);
        let lines: Vec<&str> = base.lines().collect();
        let mid = lines.len() / 2;
        let cases = [
            // Time backwards just after the middle.
            (mid + 1, "0.000,0,1,40.0,30.0,0.01"),
            // A channel repeated in an epoch that straddles the split.
            (mid + 1, lines[mid]),
            // A bad cell in the second half.
            (lines.len() - 2, "0.975,2,3,40.0,x,0.01"),
            // A quoted field (it could hide a line end).
            (mid + 3, "\"0.500\",7,8,40.0,30.0,0.01"),
        ];
        // A byte-order mark starting the second half (the csv reader would
        // drop it at the start of its input; in the file it is a cell's
        // bytes). Found by the fuzz target when the csv reader read halves.
        let split_of = |text: &str| text.len() / 2 + text[text.len() / 2..].find('\n').unwrap() + 1;
        let at = split_of(&base);
        let text = format!("{}\u{feff}{}", &base[..at], &base[at..]);
        assert_eq!(split_of(&text), at, "the test's mark must start the second half");
        let f = TempFile::new("chunks-bom.csv", &text);
        assert!(read_plain(&f.0, &path_name(&f.0), text.len() as u64, (at / 2) as u64).is_none());
        let one = read_tracking(text.as_bytes(), &path_name(&f.0)).unwrap_err().to_string();
        assert_eq!(read_tracking_file(&f.0).unwrap_err().to_string(), one);
        assert!(one.contains("is not a number"), "{one}");
        for (at, line) in cases {
            let mut edited: Vec<&str> = lines.clone();
            edited.insert(at, line);
            let text = edited.join("\n") + "\n";
            let f = TempFile::new("chunks-bad.csv", &text);
            for chunk in [64, text.len() as u64 / 2, CHUNK_BYTES] {
                assert!(read_plain(&f.0, &path_name(&f.0), text.len() as u64, chunk).is_none(), "{line}");
            }
            let serial = read_tracking(text.as_bytes(), &path_name(&f.0));
            match (read_tracking_file(&f.0), serial) {
                (Err(a), Err(b)) => assert_eq!(a.to_string(), b.to_string()),
                (Ok(a), Ok(b)) => assert_eq!(a, b),
                (a, b) => panic!("{line}: {a:?} vs {b:?}"),
            }
        }
        // A carrier changed near the split, on either side of it or across.
        let h = "t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad,signal\n";
        for change in 15..26 {
            let mut text = String::from(h);
            for k in 0..40 {
                let sig = if k < change { "L1CA" } else { "L5I" };
                text.push_str(&format!("{:.3},1,5,45,30,0.01,{sig}\n", k as f64 * 0.025));
            }
            let f = TempFile::new("chunks-carrier.csv", &text);
            assert!(read_plain(&f.0, &path_name(&f.0), text.len() as u64, 64).is_none());
            let m = read_tracking_file(&f.0).unwrap_err().to_string();
            let (line, previous) = (change + 2, change + 1);
            assert!(
                m.contains(&format!("line {line},")) && m.contains(&format!("was on L1CA (line {previous})")),
                "{m}"
            );
        }
    }

    /// A stamp whose text starts with the previous row's (`0.1` then
    /// `0.12`, `1` then `10`) is a new epoch, read on its own.
    #[test]
    fn stamps_that_extend_the_previous_ones_text_are_new_epochs() {
        let mut text = String::from(HEADER);
        for t in ["0.1", "0.12", "0.125", "1", "10", "10.5", "105"] {
            for c in 0..3 {
                text.push_str(&format!("{t},{c},{},40,30,0.0{c}\n", c + 1));
            }
        }
        let f = TempFile::new("stamp-prefixes.csv", &text);
        let plain = read_plain(&f.0, &path_name(&f.0), text.len() as u64, CHUNK_BYTES).expect("a clean file");
        assert_eq!(plain.epoch_t_s(), [0.1, 0.12, 0.125, 1.0, 10.0, 10.5, 105.0]);
        assert_eq!(plain, read_tracking(text.as_bytes(), &path_name(&f.0)).unwrap());
    }

    /// The quote-free fast path of [`read_tracking_file`] gives the log the
    /// `csv` reader gives on the same bytes, in one chunk or in several,
    /// and leaves to it whatever it does not take (the reader's result is
    /// then the `csv` reader's, error message included).
    #[test]
    fn fast_path_gives_the_csv_readers_log() {
        let base = log_text(HEADER, 60, 3, 40, 45);
        let clean = [
            base.clone(),
            base.replace('\n', "\r\n"),
            base.replace("\n0.5", "\n\n\n0.5"),
            format!("\u{feff}{base}"),
            base.trim_end().to_string(),
            base.replace(",30.0,", ", 30.0 ,").replace(",40.0,", ",+40.0,"),
            base.replace(",30.0,", ",,"),
            base.replace('\n', ",x\n").replacen(",x\n", ",foo\n", 1),
        ];
        for (i, text) in clean.iter().enumerate() {
            let f = TempFile::new(&format!("plain-clean-{i}.csv"), text);
            let plain = read_plain(&f.0, &path_name(&f.0), text.len() as u64, CHUNK_BYTES);
            let plain = plain.unwrap_or_else(|| panic!("case {i}: a clean file takes the fast path"));
            let csv = read_tracking(text.as_bytes(), &path_name(&f.0)).unwrap();
            // Not PartialEq: NaN elevations differ; their bits do not.
            assert_eq!(format!("{plain:?}"), format!("{csv:?}"), "case {i}");
        }
        let lines: Vec<&str> = base.lines().collect();
        let left = [
            // Every error the csv path reports, with its line and column.
            (10, "0.225,1,2,41.0,abc,0.01"),
            (10, "0.225,1,2,41.0,31.0"),
            (10, "0.225,1,2,41.0,31.0,0.01,extra"),
            (10, "0.000,0,1,40.0,30.0,0.01"),
            (10, lines[9]),
            (10, "0.225,-1,2,41.0,31.0,0.01"),
            (10, "0.225,1,2,41.0,31.0,nan"),
            (10, "0.225,1,2,,31.0,0.01"),
            // What only csv reads: quotes, a lone carriage return, blank lines before the header.
            (10, "\"0.230\",1,2,41.0,31.0,0.01"),
            (10, "0.230,1,2,41.0,31.0,0.01\r0.231,0,1,40.0,30.0,0.01"),
            (0, ""),
        ];
        for (at, line) in left {
            let mut edited = lines.clone();
            edited.insert(at, line);
            let text = edited.join("\n") + "\n";
            let f = TempFile::new("plain-left.csv", &text);
            assert!(read_plain(&f.0, &path_name(&f.0), text.len() as u64, CHUNK_BYTES).is_none(), "{line:?}");
            match (read_tracking_file(&f.0), read_tracking(text.as_bytes(), &path_name(&f.0))) {
                (Err(a), Err(b)) => assert_eq!(a.to_string(), b.to_string()),
                (Ok(a), Ok(b)) => assert_eq!(format!("{a:?}"), format!("{b:?}")),
                (a, b) => panic!("{line:?}: {a:?} vs {b:?}"),
            }
        }
        // Carrier columns are read by the csv path (the fast path reads L1 logs).
        let text = "t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad,signal\n0,1,5,45,30,0.01,L1CA\n";
        let f = TempFile::new("plain-carrier.csv", text);
        assert!(read_plain(&f.0, &path_name(&f.0), text.len() as u64, CHUNK_BYTES).is_none());
        assert_eq!(read_tracking_file(&f.0).unwrap().tracks()[0].carrier.label(), "L1CA");
        // Long enough for several chunks, wherever the bounds fall in an
        // epoch, with CRLF line ends and blank lines around a bound too.
        let long = |extra: usize| log_text(HEADER, 120_000 + extra, 3, 100_000, 110_000);
        let blank_lines = {
            let text = long(0);
            let at = text.len() / 2 + text[text.len() / 2..].find('\n').unwrap() + 1;
            format!("{}\n\n{}", &text[..at], &text[at..]).replace("\n0.5", "\n\n0.5")
        };
        for text in [long(0), long(1), long(2), long(1).replace('\n', "\r\n"), blank_lines] {
            assert!(text.len() as u64 >= 4 << 20);
            let f = TempFile::new("plain-chunks.csv", &text);
            let plain = read_plain(&f.0, &path_name(&f.0), text.len() as u64, 1 << 20).expect("a clean file");
            let csv = read_tracking(text.as_bytes(), &path_name(&f.0)).unwrap();
            assert!(plain == csv, "the fast path's chunks differ from the csv reader's log");
        }
    }
}
