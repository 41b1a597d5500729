//! One row of `imu.csv` or `tracking.csv` parsed on its own, its cells in
//! the writer's column order ([`IMU_COLUMNS`], [`TRACKING_COLUMNS`]): for
//! logs read a line at a time as they are written. The cells follow the
//! file readers' rules (the same number parsing, finite values, `elev_deg`
//! possibly empty); errors name the column.

use crate::error::Column;
use crate::imu::IMU_COLUMNS;
use crate::parse::{BadCell, cell_f64, cell_text, cell_u32};
use crate::tracking::TRACKING_COLUMNS;
use crate::writers::TrackingRow;

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

    fn count(&mut self, name: &str) -> Result<u32, RowError> {
        let (cell, column) = self.next(name)?;
        cell_u32(cell.as_bytes()).map_err(|bad| bad_cell(bad, cell, column, "a non-negative integer"))
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
/// of `row` (`elev_deg` possibly empty, no carrier columns), whose first cell
/// is the line's column `first_column` (1 for a line of `tracking.csv`).
pub fn parse_tracking_row(row: &str, first_column: usize) -> Result<TrackingRow, RowError> {
    let [t, channel, prn, cn0, elev, phase] = TRACKING_COLUMNS;
    let mut c = cells(row, first_column);
    let row = TrackingRow {
        t_s: c.number(t)?,
        channel: c.count(channel)?,
        prn: c.count(prn)?,
        cn0_dbhz: c.number(cn0)?,
        elev_deg: c.optional_number(elev)?,
        phase_err_rad: c.number(phase)?,
    };
    c.end()?;
    Ok(row)
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
}
