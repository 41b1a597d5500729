//! One row of `imu.csv` or `tracking.csv` parsed on its own: for logs read a
//! line at a time as they are written. An IMU row's cells are in the
//! writer's column order ([`IMU_COLUMNS`]); a tracking row's are where its
//! log's header put them ([`TrackingColumns`], the file reader's row parser),
//! or in the writer's order of the six ([`TRACKING_COLUMNS`]) for a log
//! without a header. The cells follow the file readers' rules (the same
//! number parsing, finite values, `elev_deg` possibly empty); errors name
//! the column.

use crate::columns::{CellFault, Fault, RowParser, TrackingColumns};
use crate::error::Column;
use crate::imu::IMU_COLUMNS;
use crate::parse::{BadCell, cell_f64, cell_text};
use crate::signal::Carrier;
use crate::tracking::{CARRIER_COLUMNS, NCO_COLUMNS, TRACKING_COLUMNS};
use crate::writers::TrackingRow;

/// One row of `tracking.csv` with the optional columns its log has (the
/// crate documentation, "Carrier" and "NCO").
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrackingRecord {
    /// The six columns every log has.
    pub row: TrackingRow,
    /// The row's carrier, where the log has carrier columns; `None`: GPS L1,
    /// unnamed ([`Carrier::GPS_L1`]).
    pub carrier: Option<Carrier>,
    /// `nco_phase_cycles` \[cycles\], where the log has the column.
    pub nco_phase_cycles: Option<f64>,
    /// `nco_freq_hz` \[Hz\], where the log has the column.
    pub nco_freq_hz: Option<f64>,
}

impl TrackingRecord {
    /// The record of a log with the six columns only.
    pub fn plain(row: TrackingRow) -> Self {
        TrackingRecord { row, carrier: None, nco_phase_cycles: None, nco_freq_hz: None }
    }

    /// The row's carrier: its own, or GPS L1 in a log without carrier columns.
    pub fn carrier_or_l1(&self) -> Carrier {
        self.carrier.unwrap_or(Carrier::GPS_L1)
    }

    /// The NCO columns the record has, of [`NCO_COLUMNS`], and their values.
    pub fn nco(&self) -> impl Iterator<Item = (&'static str, f64)> {
        let values = [self.nco_phase_cycles, self.nco_freq_hz];
        NCO_COLUMNS.into_iter().zip(values).filter_map(|(name, v)| Some((name, v?)))
    }

    /// The header of a log of such records, as [`crate::TrackingWriter::for_record`]
    /// writes it: the six of [`TRACKING_COLUMNS`], `signal,carrier_hz` with
    /// a carrier, then the NCO columns it has.
    pub fn header(&self) -> Vec<&'static str> {
        let mut names = TRACKING_COLUMNS.to_vec();
        if self.carrier.is_some() {
            names.extend([CARRIER_COLUMNS[0], CARRIER_COLUMNS[2]]);
        }
        names.extend(self.nco().map(|(name, _)| name));
        names
    }

    /// The record's cells as a line of a log with [`TrackingRecord::header`]
    /// (no line end): the numbers as [`crate::TrackingWriter`] writes them.
    pub fn cells(&self) -> String {
        let mut line = Vec::with_capacity(96);
        let nco: Vec<f64> = self.nco().map(|(_, v)| v).collect();
        crate::writers::write_row_cells(&mut line, &self.row, self.carrier.as_ref(), &nco)
            .expect("writing to memory does not fail");
        String::from_utf8(line).expect("numbers and signal names are ASCII")
    }
}

/// What is wrong with a row read on its own.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum RowError {
    /// The row ends before this column.
    #[error("{column} missing")]
    Missing {
        /// The column.
        column: Column,
    },
    /// A required cell is empty.
    #[error("{column}: empty cell, expected {expected}")]
    EmptyCell {
        /// The column.
        column: Column,
        /// What the cell should hold.
        expected: &'static str,
    },
    /// A cell does not hold a number of the expected kind.
    #[error("{column}: `{value}` is not {expected}")]
    NotANumber {
        /// The column.
        column: Column,
        /// The cell's text (truncated).
        value: String,
        /// What the cell should hold.
        expected: &'static str,
    },
    /// A cell holds NaN or an infinity.
    #[error("{column}: `{value}` is not a finite number")]
    NonFinite {
        /// The column.
        column: Column,
        /// The cell's text.
        value: String,
    },
    /// The row's carrier cells name no carrier gsens knows, or disagree.
    #[error("{column}: {message}")]
    InvalidCarrier {
        /// The column.
        column: Column,
        /// What is wrong with the carrier.
        message: String,
    },
    /// The row has cells after its last column.
    #[error("more than {columns} columns")]
    TooManyColumns {
        /// The columns of the line, the last one's number.
        columns: usize,
    },
}

/// The cells of one row, numbered as the line's columns.
struct Cells<'a> {
    cells: std::str::Split<'a, char>,
    /// The line's column number of the next cell (from 1).
    next_column: usize,
}

impl<'a> Cells<'a> {
    fn next(&mut self, name: &str) -> Result<(&'a str, Column), RowError> {
        let column = Column { index: self.next_column, name: name.to_owned() };
        self.next_column += 1;
        match self.cells.next() {
            Some(cell) => Ok((cell, column)),
            None => Err(RowError::Missing { column }),
        }
    }

    fn optional_number(&mut self, name: &str) -> Result<Option<f64>, RowError> {
        let (cell, column) = self.next(name)?;
        cell_f64(cell.as_bytes()).map_err(|bad| bad_cell(bad, cell, column, "a number"))
    }

    fn number(&mut self, name: &str) -> Result<f64, RowError> {
        let column = Column { index: self.next_column, name: name.to_owned() };
        self.optional_number(name)?.ok_or(RowError::EmptyCell { column, expected: "a number" })
    }

    fn end(mut self) -> Result<(), RowError> {
        match self.cells.next() {
            None => Ok(()),
            Some(_) => Err(RowError::TooManyColumns { columns: self.next_column - 1 }),
        }
    }
}

fn bad_cell(bad: BadCell, cell: &str, column: Column, expected: &'static str) -> RowError {
    match bad {
        BadCell::Empty => RowError::EmptyCell { column, expected },
        BadCell::NonFinite => RowError::NonFinite { column, value: cell_text(cell.as_bytes()) },
        BadCell::NotANumber => RowError::NotANumber { column, value: cell_text(cell.as_bytes()), expected },
    }
}

fn cells(row: &str, first_column: usize) -> Cells<'_> {
    Cells { cells: row.trim_end().split(','), next_column: first_column }
}

/// One IMU sample from the cells `t_s,fx_mps2,fy_mps2,fz_mps2` of `row`,
/// whose first cell is the line's column `first_column` (1 for a line of
/// `imu.csv`): its time stamp \[s\] and specific force \[m/s²\].
pub fn parse_imu_row(row: &str, first_column: usize) -> Result<(f64, [f64; 3]), RowError> {
    let mut c = cells(row, first_column);
    let t_s = c.number(IMU_COLUMNS[0])?;
    let accel_mps2 = [c.number(IMU_COLUMNS[1])?, c.number(IMU_COLUMNS[2])?, c.number(IMU_COLUMNS[3])?];
    c.end()?;
    Ok((t_s, accel_mps2))
}

/// One tracking row from the cells `t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad`
/// of `row` (`elev_deg` possibly empty, no other columns), whose first cell
/// is the line's column `first_column` (1 for a line of `tracking.csv`).
pub fn parse_tracking_row(row: &str, first_column: usize) -> Result<TrackingRow, RowError> {
    TrackingColumns::default().parse_row(row, first_column).map(|r| r.row)
}

impl TrackingColumns {
    /// One row of a log with these columns: the cells of `row`, whose first
    /// is the line's column `first_column` (1 for a line of `tracking.csv`),
    /// read by the file reader's row parser. Errors name the column; a row
    /// with fewer or more cells than the header is an error too.
    pub fn parse_row(&self, row: &str, first_column: usize) -> Result<TrackingRecord, RowError> {
        let cells: Vec<&str> = row.trim_end().split(',').collect();
        let names = self.names();
        let column = |i: usize| Column { index: i + first_column, name: names[i].clone() };
        let cell = |i: usize| cells.get(i).map_or(&b""[..], |c| c.as_bytes());
        let record = RowParser::new(self).record(cell);
        // Cells are read in column order: a bad cell before the row's end comes first.
        if cells.len() < names.len() && record.as_ref().err().is_none_or(|f| f.index >= cells.len()) {
            return Err(RowError::Missing { column: column(cells.len()) });
        }
        let record = record.map_err(|CellFault { index, fault }| {
            let (column, text) = (column(index), cells[index]);
            match fault {
                Fault::Cell { bad, expected } => bad_cell(bad, text, column, expected),
                Fault::Carrier(error) => RowError::InvalidCarrier { column, message: error.to_string() },
            }
        })?;
        if cells.len() > names.len() {
            return Err(RowError::TooManyColumns { columns: names.len() + first_column - 1 });
        }
        Ok(record)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_parse_as_written_and_errors_name_the_column() {
        assert_eq!(parse_imu_row("1.5, 0.1 ,-0.2,9.81", 1), Ok((1.5, [0.1, -0.2, 9.81])));
        let r = parse_tracking_row("0.02,3,+17,44.5,,-0.01\r", 1).unwrap();
        assert_eq!((r.channel, r.prn, r.elev_deg, r.phase_err_rad), (3, 17, None, -0.01));
        let e = |r: Result<(f64, [f64; 3]), RowError>| r.unwrap_err().to_string();
        assert_eq!(e(parse_imu_row("1,0,x,9.8", 2)), "column 4 (`fy_mps2`): `x` is not a number");
        assert_eq!(e(parse_imu_row("1,0,0", 1)), "column 4 (`fz_mps2`) missing");
        assert_eq!(e(parse_imu_row("1,0,NaN,9.8", 1)), "column 3 (`fy_mps2`): `NaN` is not a finite number");
        assert_eq!(e(parse_imu_row(",0,0,9.8", 1)), "column 1 (`t_s`): empty cell, expected a number");
        assert_eq!(e(parse_imu_row("1,0,0,9.8,5", 2)), "more than 5 columns");
        let t = parse_tracking_row("1,-1,2,45,,0.1", 2).unwrap_err().to_string();
        assert_eq!(t, "column 3 (`channel`): `-1` is not a non-negative integer");
        let t = parse_tracking_row("1,1,2,45,,", 1).unwrap_err().to_string();
        assert_eq!(t, "column 6 (`phase_err_rad`): empty cell, expected a number");
    }

    /// A tracking row is read where its header put each column, with the
    /// carrier and NCO columns the header names, by the file reader's rules:
    /// the record is the one the file reader keeps of the same line.
    #[test]
    fn tracking_rows_follow_their_header() {
        let header = "nco_freq_hz,t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad,signal,nco_phase_cycles";
        let names: Vec<&str> = header.split(',').collect();
        let columns = TrackingColumns::from_header(&names).unwrap();
        assert!(columns.has_optional() && !TrackingColumns::default().has_optional());
        let line = "1200.5,0.025,3,17,44.5,,-0.01,L5Q,-7.25";
        let r = columns.parse_row(line, 1).unwrap();
        assert_eq!((r.row.channel, r.row.prn, r.row.elev_deg, r.row.phase_err_rad), (3, 17, None, -0.01));
        assert_eq!((r.nco_phase_cycles, r.nco_freq_hz), (Some(-7.25), Some(1200.5)));
        assert_eq!(r.carrier.unwrap().label(), "L5Q");
        let file = crate::read_tracking(format!("{header}\n{line}\n").as_bytes(), "t.csv").unwrap();
        let track = &file.tracks()[0];
        assert_eq!(
            (track.nco_phase_cycles[0], track.nco_freq_hz[0], track.carrier),
            (-7.25, 1200.5, r.carrier_or_l1())
        );
        // Errors name the line's column (the tag of a merged line is column 1).
        let e = |line: &str| columns.parse_row(line, 2).unwrap_err().to_string();
        assert_eq!(
            e("1200.5,0.025,3,17,44.5,,-0.01,L5Q,"),
            "column 10 (`nco_phase_cycles`): empty cell, expected a number"
        );
        assert_eq!(e("inf,0.025,3,17,44.5,,-0.01,L5Q,1"), "column 2 (`nco_freq_hz`): `inf` is not a finite number");
        assert_eq!(e("x,0.025,3,17,44.5,,-0.01,L5Q,1"), "column 2 (`nco_freq_hz`): `x` is not a number");
        assert!(
            e("1,0.025,3,17,44.5,,-0.01,L9,1").starts_with("column 9 (`signal`): `L9` is not a signal gsens knows")
        );
        assert_eq!(e("1,0.025,3,17,44.5,,-0.01,L5Q"), "column 10 (`nco_phase_cycles`) missing");
        assert_eq!(e("1,0.025,3,17,44.5,,-0.01,L5Q,1,2"), "more than 10 columns");
        // Header errors name the column.
        let h = |names: &[&str]| TrackingColumns::from_header(names).unwrap_err().to_string();
        assert_eq!(h(&["t_s", "channel", "prn", "cn0_dbhz", "phase_err_rad"]), "missing column `elev_deg`");
        let twice = ["t_s", "channel", "prn", "cn0_dbhz", "elev_deg", "phase_err_rad", "nco_freq_hz", "nco_freq_hz"];
        assert_eq!(h(&twice), "column `nco_freq_hz` appears twice (columns 7 and 8)");
    }

    /// A record written by its own header's cells reads back the same, and a
    /// log of records keeps their optional columns as the reader does.
    #[test]
    fn records_round_trip_and_make_the_readers_log() {
        let row =
            TrackingRow { t_s: 0.1, channel: 2, prn: 9, cn0_dbhz: 41.25, elev_deg: Some(30.5), phase_err_rad: 0.125 };
        let plain = TrackingRecord::plain(row);
        assert_eq!(plain.cells(), "0.1,2,9,41.25,30.5,0.125");
        let g1 = Carrier::of(crate::Signal::from_label("G1:-7").unwrap());
        let full = TrackingRecord { carrier: Some(g1), nco_phase_cycles: Some(-3.5), nco_freq_hz: Some(1e3), ..plain };
        let nco_only = TrackingRecord { nco_freq_hz: Some(-12.0), ..plain };
        for r in [plain, full, nco_only] {
            let columns = TrackingColumns::of_record(&r);
            assert_eq!(columns.names().join(","), r.header().join(","));
            assert_eq!(columns.parse_row(&r.cells(), 1).unwrap(), r);
            let mut w = crate::TrackingWriter::for_record(Vec::new(), &r).unwrap();
            w.write_record(&r).unwrap();
            let text = String::from_utf8(w.finish().unwrap()).unwrap();
            assert_eq!(text, format!("{}\n{}\n", r.header().join(","), r.cells()));
            let read = crate::read_tracking(text.as_bytes(), "t.csv").unwrap();
            let from_records = crate::TrackingLog::from_records("t.csv", [r]).unwrap();
            assert_eq!(from_records.tracks(), read.tracks());
        }
        // Records of other columns than the first's are errors naming the line and column.
        let e = crate::TrackingLog::from_records("rx", [full, plain]).unwrap_err().to_string();
        assert_eq!(
            e,
            "rx: line 3, column 7 (`signal`): empty cell, expected the row's carrier (a signal name or carrier_hz)"
        );
        let e = crate::TrackingLog::from_records("rx", [nco_only, full]).unwrap_err().to_string();
        assert!(e.starts_with("rx: line 3") && e.contains("expected 7 fields") && e.contains("found 10"), "{e}");
        let bad = TrackingRecord { nco_phase_cycles: Some(f64::NAN), ..full };
        let e = crate::TrackingLog::from_records("rx", [full, bad]).unwrap_err().to_string();
        assert!(e.starts_with("rx: line 3, column 9 (`nco_phase_cycles`)") && e.contains("not a finite number"), "{e}");
    }
}
