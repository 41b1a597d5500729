//! Inputs as they arrive: one line of `imu.csv`, of `tracking.csv`, or of the
//! merged stream `gsens live --stdin` reads, each source's lines read by its
//! own [`LineParser`].
//!
//! # Tracking columns
//!
//! A `tracking.csv` read a line at a time has the columns of its header
//! line, as the file reader reads them (gsens-io's `TrackingColumns`: the
//! six of the format in any order, the carrier columns `signal`, `glo_k`,
//! `carrier_hz` and the NCO columns `nco_phase_cycles`, `nco_freq_hz` where
//! the header names them, other columns ignored). Before any header line
//! the rows hold the six, in the writer's order. A header line is a line
//! that names `t_s`; it sets the columns of the rows after it.
//!
//! # The merged stream
//!
//! One record per line, comma-separated, tagged by its first field:
//!
//! ```text
//! imu,t_s,fx_mps2,fy_mps2,fz_mps2
//! trk,t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad
//! ```
//!
//! with the units and conventions of `imu.csv` and `tracking.csv`
//! (docs/conventions.md; `elev_deg` may be empty). Blank lines, lines
//! starting with `#` and the files' own header lines are skipped. Each
//! stream's time stamps must not decrease; IMU and tracking records may
//! interleave in any order (`gsens replay` writes them in time order).
//!
//! `trk` records with other columns declare them first: the header line of
//! their `tracking.csv` with the tag, e.g.
//!
//! ```text
//! trk,t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad,nco_phase_cycles,nco_freq_hz
//! trk,0.025,3,17,44.5,,-0.012,1.5,0.25
//! ```
//!
//! sets the columns of the `trk` records after it, as a header line sets a
//! `tracking.csv`'s ([`merged_header`]; `gsens replay` writes it before the
//! first record that needs it).

use gsens_io::{HeaderError, IMU_COLUMNS, TrackingColumns, TrackingRecord};

/// One received record.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Input {
    /// An IMU sample: specific force in the body frame \[m/s²\] at `t_s` (IMU clock) \[s\].
    Imu {
        /// Time stamp \[s\].
        t_s: f64,
        /// Specific force `[fx, fy, fz]` \[m/s²\].
        accel_mps2: [f64; 3],
    },
    /// One channel's tracking row, with the optional columns of its log.
    Tracking(TrackingRecord),
}

impl Input {
    /// The record's time stamp \[s\].
    pub fn t_s(&self) -> f64 {
        match self {
            Input::Imu { t_s, .. } => *t_s,
            Input::Tracking(r) => r.row.t_s,
        }
    }
}

/// What a line held.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LineKind {
    /// A record.
    Data(Input),
    /// A header, comment or blank line: nothing to use, nothing wrong.
    Skip,
}

/// Something received that is not used, and why: shown on the screen and
/// kept in the session's notices (the line itself stays in the raw log).
#[derive(Debug, Clone, PartialEq)]
pub struct Notice {
    /// The source: a file name, `stdin`, a UDP address.
    pub source: String,
    /// The source's line (or datagram) number, from 1; 0 when not about a line.
    pub line: u64,
    /// What was wrong and what gsens did about it.
    pub message: String,
}

impl core::fmt::Display for Notice {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        if self.line > 0 {
            write!(f, "{}:{}: {}", self.source, self.line, self.message)
        } else {
            write!(f, "{}: {}", self.source, self.message)
        }
    }
}

/// Why a received line is not a record.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum LineError {
    /// A cell of the row (gsens-io's row parser: the column is named).
    #[error(transparent)]
    Row(gsens_io::RowError),
    /// A tracking row with cells after the last column of its log's header
    /// (or of the six, without one).
    #[error("more than {columns} columns (a log's other columns are read where its header line names them)")]
    TrackingColumns {
        /// The line's columns up to the header's last.
        columns: usize,
    },
    /// A tracking header line gsens cannot read.
    #[error("header: {0}")]
    Header(HeaderError),
    /// A merged-stream line whose first column is no tag.
    #[error("column 1: {tag:?} is neither `imu` nor `trk`")]
    UnknownTag {
        /// The first column.
        tag: String,
    },
}

fn skippable(line: &str) -> bool {
    let t = line.trim();
    t.is_empty() || t.starts_with('#')
}

/// One line of `imu.csv` (`t_s,fx_mps2,fy_mps2,fz_mps2`); the header is skipped.
/// Errors say which column is wrong (columns counted from 1).
pub fn parse_imu_line(line: &str) -> Result<LineKind, LineError> {
    if skippable(line) || line.trim() == IMU_COLUMNS.join(",") {
        return Ok(LineKind::Skip);
    }
    imu_cells(line, 1)
}

/// The IMU record of `cells`, the line's columns from `first_column` on.
fn imu_cells(cells: &str, first_column: usize) -> Result<LineKind, LineError> {
    let (t_s, accel_mps2) = gsens_io::parse_imu_row(cells, first_column).map_err(LineError::Row)?;
    Ok(LineKind::Data(Input::Imu { t_s, accel_mps2 }))
}

/// The format of a source's text lines.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LineFormat {
    /// Lines of `imu.csv`.
    Imu,
    /// Lines of `tracking.csv`.
    Tracking,
    /// The merged stream (`imu,…` and `trk,…`, module docs).
    Merged,
}

impl LineFormat {
    /// A parser of a source of this format, from its first line.
    pub fn parser(self) -> LineParser {
        LineParser { format: self, tracking: TrackingColumns::default() }
    }
}

/// The lines of one source, read in order: a tracking header line sets the
/// columns of the tracking rows after it (module docs).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LineParser {
    format: LineFormat,
    /// The columns of the tracking rows now.
    tracking: TrackingColumns,
}

impl LineParser {
    /// The next line of the source. Errors say which column is wrong
    /// (columns counted from 1, a merged line's tag being column 1).
    pub fn parse(&mut self, line: &str) -> Result<LineKind, LineError> {
        if skippable(line) {
            return Ok(LineKind::Skip);
        }
        match self.format {
            LineFormat::Imu => parse_imu_line(line),
            LineFormat::Tracking => self.tracking_cells(line, 1),
            LineFormat::Merged => {
                let (tag, rest) = line.split_once(',').unwrap_or((line, ""));
                match tag.trim() {
                    "imu" => imu_cells(rest, 2),
                    "trk" => self.tracking_cells(rest, 2),
                    "t_s" => Ok(LineKind::Skip),
                    tag => Err(LineError::UnknownTag { tag: tag.to_string() }),
                }
            }
        }
    }

    /// The tracking columns the source's rows have now.
    pub fn tracking_columns(&self) -> &TrackingColumns {
        &self.tracking
    }

    /// The tracking record or header of `cells`, the line's columns from `first_column` on.
    fn tracking_cells(&mut self, cells: &str, first_column: usize) -> Result<LineKind, LineError> {
        let names: Vec<&str> = cells.trim_end().split(',').collect();
        if names.iter().any(|n| n.trim_start_matches('\u{feff}').trim() == "t_s") {
            self.tracking = TrackingColumns::from_header(&names).map_err(LineError::Header)?;
            return Ok(LineKind::Skip);
        }
        match self.tracking.parse_row(cells, first_column) {
            Ok(record) => Ok(LineKind::Data(Input::Tracking(record))),
            Err(gsens_io::RowError::TooManyColumns { columns }) => Err(LineError::TrackingColumns { columns }),
            Err(e) => Err(LineError::Row(e)),
        }
    }
}

/// The merged-stream line of a record (module docs), as `gsens replay` writes it.
pub fn merged_line(input: &Input) -> String {
    match input {
        Input::Imu { t_s, accel_mps2: a } => format!("imu,{t_s},{},{},{}", a[0], a[1], a[2]),
        Input::Tracking(r) => format!("trk,{}", r.cells()),
    }
}

/// The merged-stream line that declares the columns of the `trk` records
/// like `record` (module docs): the header of their `tracking.csv` with the tag.
pub fn merged_header(record: &TrackingRecord) -> String {
    format!("trk,{}", record.header().join(","))
}

#[cfg(test)]
mod tests {
    use super::*;
    use gsens_io::TrackingRow;

    fn parse(format: LineFormat, lines: &[&str]) -> Vec<Result<LineKind, String>> {
        let mut p = format.parser();
        lines.iter().map(|l| p.parse(l).map_err(|e| e.to_string())).collect()
    }

    #[test]
    fn merged_lines_round_trip_and_errors_name_the_column() {
        let imu = Input::Imu { t_s: 1.025, accel_mps2: [0.1, -0.2, 9.80665] };
        let row = TrackingRow {
            t_s: 1.0125,
            channel: 3,
            prn: 17,
            cn0_dbhz: 44.5,
            elev_deg: None,
            phase_err_rad: -0.012345678901234,
        };
        let trk = Input::Tracking(TrackingRecord::plain(row));
        let mut p = LineFormat::Merged.parser();
        for x in [imu, trk] {
            assert_eq!(p.parse(&merged_line(&x)).unwrap(), LineKind::Data(x));
        }
        assert_eq!(p.parse("# comment").unwrap(), LineKind::Skip);
        assert_eq!(p.parse("t_s,fx_mps2,fy_mps2,fz_mps2").unwrap(), LineKind::Skip);
        let e = |line: &str| LineFormat::Merged.parser().parse(line).unwrap_err().to_string();
        assert_eq!(e("gps,1,2"), "column 1: \"gps\" is neither `imu` nor `trk`");
        assert_eq!(e("imu,1.0,0,x,9.8"), "column 4 (`fy_mps2`): `x` is not a number");
        assert_eq!(e("imu,1.0,0,0"), "column 5 (`fz_mps2`) missing");
        assert!(e("trk,1.0,1,2,45,,0.1,9").starts_with("more than 7 columns (a log's other columns"));
        assert_eq!(e("trk,1.0,-1,2,45,,0.1"), "column 3 (`channel`): `-1` is not a non-negative integer");
        assert!(parse_imu_line("1.0,0,NaN,9.8").unwrap_err().to_string().contains("not a finite number"));
        let header = "t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad";
        assert_eq!(LineFormat::Tracking.parser().parse(header).unwrap(), LineKind::Skip);
    }

    /// A header line sets the columns of the rows after it: the NCO and
    /// carrier columns are read where it names them, in a file's lines and
    /// in the merged stream (declared by the tagged header), and the merged
    /// lines of such records, after their header, read back the same.
    #[test]
    fn a_header_line_sets_the_columns_of_the_rows_after_it() {
        let header = "t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad,signal,carrier_hz,nco_phase_cycles,nco_freq_hz";
        let row = "0.025,3,17,44.5,30,-0.012,L5Q,1176450000,1.5,-0.25";
        let got = parse(LineFormat::Tracking, &[header, row]);
        let Ok(LineKind::Data(Input::Tracking(r))) = got[1] else { panic!("{got:?}") };
        assert_eq!((r.nco_phase_cycles, r.nco_freq_hz), (Some(1.5), Some(-0.25)));
        assert_eq!(r.carrier.unwrap().label(), "L5Q");
        assert_eq!(r.header().join(","), header);
        let mut p = LineFormat::Merged.parser();
        assert_eq!(p.parse(&merged_header(&r)).unwrap(), LineKind::Skip);
        assert_eq!(p.parse(&merged_line(&Input::Tracking(r))).unwrap(), LineKind::Data(Input::Tracking(r)));
        assert_eq!(p.tracking_columns().names().join(","), header);
        // Without the header, the same row has too many columns; bad cells are named by line column.
        let e = |format: LineFormat, lines: &[&str]| parse(format, lines).pop().unwrap().unwrap_err();
        assert!(e(LineFormat::Tracking, &[row]).starts_with("more than 6 columns"));
        let bad = "0.025,3,17,44.5,30,-0.012,L5Q,1176450000,nan,-0.25";
        assert_eq!(
            e(LineFormat::Tracking, &[header, bad]),
            "column 9 (`nco_phase_cycles`): `nan` is not a finite number"
        );
        let merged = [format!("trk,{header}"), format!("trk,{}", row.replace(",-0.25", ","))];
        let merged: Vec<&str> = merged.iter().map(String::as_str).collect();
        assert_eq!(e(LineFormat::Merged, &merged), "column 11 (`nco_freq_hz`): empty cell, expected a number");
        assert_eq!(
            e(LineFormat::Tracking, &["t_s,channel,prn,cn0_dbhz,phase_err_rad"]),
            "header: missing column `elev_deg`"
        );
    }
}
