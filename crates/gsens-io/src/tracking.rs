//! Reader of `tracking.csv`: one row per channel per epoch (long format), header
//! `t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad`.
//!
//! The columns may come in any order and extra columns are ignored, but the six
//! must all be present. `elev_deg` may be empty (unknown elevation); every other
//! cell must hold a finite number (`channel` and `prn`: non-negative integers).
//! Channels may appear, disappear and reappear.
//!
//! Time stamps must be non-decreasing over the file (the rows of one epoch share
//! one `t_s`) and strictly increasing per channel (a channel appears at most once
//! per epoch).
//!
//! The log is read as a stream and stored column-wise per track, a track being
//! one (channel, PRN) pair: a channel that is re-assigned to another satellite
//! starts a new track.

use std::collections::HashMap;
use std::io::Read;
use std::path::Path;

use crate::error::{Column, FormatError};
use crate::parse::{CsvSource, path_name};

/// The columns of `tracking.csv`, in the order the writer emits them.
pub const TRACKING_COLUMNS: [&str; 6] = ["t_s", "channel", "prn", "cn0_dbhz", "elev_deg", "phase_err_rad"];

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
}

impl ChannelTrack {
    fn new(channel: u32, prn: u32) -> Self {
        ChannelTrack {
            channel,
            prn,
            t_s: Vec::new(),
            phase_err_rad: Vec::new(),
            cn0_dbhz: Vec::new(),
            elev_deg: Vec::new(),
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

    /// The 1-based line of the first row of each distinct time stamp.
    pub(crate) fn epoch_line(&self) -> &[u64] {
        &self.epoch_line
    }

    /// The `t_s` column of the file.
    pub(crate) fn t_column(&self) -> &Column {
        &self.t_column
    }
}

/// Per-channel reader state: the latest row and the current track.
struct ChannelState {
    last_t_s: f64,
    last_line: u64,
    track: usize,
}

/// Reads a `tracking.csv` stream. `source_name` names the source in error
/// messages (typically the file name).
pub fn read_tracking<R: Read>(input: R, source_name: &str) -> Result<TrackingLog, FormatError> {
    let (mut src, cols) = CsvSource::open(input, source_name, &TRACKING_COLUMNS)?;
    let (ct, cch, cprn, ccn0, celev, cphase) = (cols[0], cols[1], cols[2], cols[3], cols[4], cols[5]);
    let mut tracks: Vec<ChannelTrack> = Vec::new();
    let mut track_of: HashMap<(u32, u32), usize> = HashMap::new();
    let mut channels: HashMap<u32, ChannelState> = HashMap::new();
    let mut epoch_t_s: Vec<f64> = Vec::new();
    let mut epoch_line: Vec<u64> = Vec::new();
    let mut rows = 0usize;
    let mut prev: Option<(f64, u64)> = None;
    // The rows of one epoch share the text of their time stamp: parse it once.
    let mut prev_t_text: Vec<u8> = Vec::new();

    let mut track_for = |channel: u32, prn: u32, tracks: &mut Vec<ChannelTrack>| -> usize {
        *track_of.entry((channel, prn)).or_insert_with(|| {
            tracks.push(ChannelTrack::new(channel, prn));
            tracks.len() - 1
        })
    };

    while src.next_record()? {
        src.check_field_count()?;
        let t = match prev {
            Some((prev_t, _)) if src.cell(ct) == prev_t_text.as_slice() => prev_t,
            _ => {
                let t = src.f64_at(ct)?;
                prev_t_text.clear();
                prev_t_text.extend_from_slice(src.cell(ct));
                t
            }
        };
        let channel = src.u32_at(cch)?;
        let prn = src.u32_at(cprn)?;
        let cn0 = src.f64_at(ccn0)?;
        let elev = src.opt_f64_at(celev)?.unwrap_or(f64::NAN);
        let phase = src.f64_at(cphase)?;
        let line = src.line();

        match prev {
            Some((prev_t, prev_line)) if t < prev_t => {
                return Err(FormatError::TimeBackwards {
                    file: src.file.clone(),
                    line,
                    column: src.column(ct),
                    t_s: t,
                    previous_t_s: prev_t,
                    previous_line: prev_line,
                });
            }
            Some((prev_t, _)) if t == prev_t => {}
            _ => {
                epoch_t_s.push(t);
                epoch_line.push(line);
            }
        }
        prev = Some((t, line));

        let track = match channels.get_mut(&channel) {
            Some(state) => {
                // Time stamps are non-decreasing overall, so equality is the only
                // way this channel can fail to be strictly increasing.
                if state.last_t_s == t {
                    return Err(FormatError::RepeatedChannel {
                        file: src.file.clone(),
                        line,
                        column: src.column(cch),
                        channel,
                        t_s: t,
                        previous_line: state.last_line,
                    });
                }
                if tracks[state.track].prn != prn {
                    state.track = track_for(channel, prn, &mut tracks);
                }
                state.last_t_s = t;
                state.last_line = line;
                state.track
            }
            None => {
                let track = track_for(channel, prn, &mut tracks);
                channels.insert(channel, ChannelState { last_t_s: t, last_line: line, track });
                track
            }
        };
        let tr = &mut tracks[track];
        tr.t_s.push(t);
        tr.phase_err_rad.push(phase);
        tr.cn0_dbhz.push(cn0);
        tr.elev_deg.push(elev);
        rows += 1;
    }
    if rows == 0 {
        return Err(FormatError::NoData { file: src.file });
    }
    let t_column = src.column(ct);
    Ok(TrackingLog { source_name: src.file, tracks, epoch_t_s, epoch_line, t_column, rows })
}

/// Opens and reads a `tracking.csv` file; errors name the file by its path.
pub fn read_tracking_file(path: impl AsRef<Path>) -> Result<TrackingLog, FormatError> {
    let path = path.as_ref();
    let name = path_name(path);
    let file = std::fs::File::open(path).map_err(|e| FormatError::io(&name, e))?;
    read_tracking(file, &name)
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
    fn empty_file_and_header_only() {
        let m = err_raw("");
        assert!(m.contains("empty file") && m.contains("t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad"), "{m}");
        let m = err("");
        assert!(m.contains("header only, no data rows"), "{m}");
    }

    #[test]
    fn wrong_field_count() {
        let m = err("0,1,5,45,30,0.01\n0.025,1,5,45,0.01\n");
        assert!(m.contains("line 3") && m.contains("expected 6 fields") && m.contains("found 5"), "{m}");
    }
}
