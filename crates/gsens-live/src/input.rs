//! Inputs as they arrive: one line of `imu.csv`, of `tracking.csv`, or of the
//! merged stream `gsens live --stdin` reads.
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

use gsens_io::{IMU_COLUMNS, TRACKING_COLUMNS, TrackingRow};

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
    /// One channel's tracking row.
    Tracking(TrackingRow),
}

impl Input {
    /// The record's time stamp \[s\].
    pub fn t_s(&self) -> f64 {
        match self {
            Input::Imu { t_s, .. } => *t_s,
            Input::Tracking(r) => r.t_s,
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
    /// A tracking row with cells after `phase_err_rad`: carrier columns.
    #[error("more than {columns} columns (carrier columns are not read live yet: log GPS L1 only)")]
    TrackingColumns {
        /// The line's columns up to `phase_err_rad`.
        columns: usize,
    },
    /// The header of a `tracking.csv` with carrier columns.
    #[error("carrier columns (signal, carrier_hz) are not read live yet: log GPS L1 only")]
    CarrierHeader,
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

/// One line of `tracking.csv` (`t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad`,
/// `elev_deg` possibly empty); the header is skipped. Logs with carrier
/// columns are not read live yet: their rows are errors saying so.
pub fn parse_tracking_line(line: &str) -> Result<LineKind, LineError> {
    let header = TRACKING_COLUMNS.join(",");
    if skippable(line) || line.trim() == header {
        return Ok(LineKind::Skip);
    }
    if line.trim().starts_with(&header) {
        return Err(LineError::CarrierHeader);
    }
    tracking_cells(line, 1)
}

/// The tracking record of `cells`, the line's columns from `first_column` on.
fn tracking_cells(cells: &str, first_column: usize) -> Result<LineKind, LineError> {
    match gsens_io::parse_tracking_row(cells, first_column) {
        Ok(row) => Ok(LineKind::Data(Input::Tracking(row))),
        Err(gsens_io::RowError::TooManyColumns { columns }) => Err(LineError::TrackingColumns { columns }),
        Err(e) => Err(LineError::Row(e)),
    }
}

/// One line of the merged stream (module docs): `imu,…` or `trk,…`; the
/// header lines of `imu.csv` and `tracking.csv` are skipped too.
pub fn parse_merged_line(line: &str) -> Result<LineKind, LineError> {
    if skippable(line) {
        return Ok(LineKind::Skip);
    }
    let (tag, rest) = line.split_once(',').unwrap_or((line, ""));
    match tag.trim() {
        "imu" => imu_cells(rest, 2),
        "trk" => tracking_cells(rest, 2),
        "t_s" => Ok(LineKind::Skip),
        tag => Err(LineError::UnknownTag { tag: tag.to_string() }),
    }
}

/// The merged-stream line of a record (module docs), as `gsens replay` writes it.
pub fn merged_line(input: &Input) -> String {
    match input {
        Input::Imu { t_s, accel_mps2: a } => format!("imu,{t_s},{},{},{}", a[0], a[1], a[2]),
        Input::Tracking(r) => {
            let elev = r.elev_deg.map(|e| e.to_string()).unwrap_or_default();
            format!("trk,{},{},{},{},{elev},{}", r.t_s, r.channel, r.prn, r.cn0_dbhz, r.phase_err_rad)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn merged_lines_round_trip_and_errors_name_the_column() {
        let imu = Input::Imu { t_s: 1.025, accel_mps2: [0.1, -0.2, 9.80665] };
        let trk = Input::Tracking(TrackingRow {
            t_s: 1.0125,
            channel: 3,
            prn: 17,
            cn0_dbhz: 44.5,
            elev_deg: None,
            phase_err_rad: -0.012345678901234,
        });
        for x in [imu, trk] {
            assert_eq!(parse_merged_line(&merged_line(&x)).unwrap(), LineKind::Data(x));
        }
        assert_eq!(parse_merged_line("# comment").unwrap(), LineKind::Skip);
        assert_eq!(parse_merged_line("t_s,fx_mps2,fy_mps2,fz_mps2").unwrap(), LineKind::Skip);
        let e = |line: &str| parse_merged_line(line).unwrap_err().to_string();
        assert_eq!(e("gps,1,2"), "column 1: \"gps\" is neither `imu` nor `trk`");
        assert_eq!(e("imu,1.0,0,x,9.8"), "column 4 (`fy_mps2`): `x` is not a number");
        assert_eq!(e("imu,1.0,0,0"), "column 5 (`fz_mps2`) missing");
        assert!(e("trk,1.0,1,2,45,,0.1,9").starts_with("more than 7 columns (carrier columns"));
        assert_eq!(e("trk,1.0,-1,2,45,,0.1"), "column 3 (`channel`): `-1` is not a non-negative integer");
        assert!(parse_imu_line("1.0,0,NaN,9.8").unwrap_err().to_string().contains("not a finite number"));
        assert_eq!(parse_tracking_line("t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad").unwrap(), LineKind::Skip);
        assert!(parse_tracking_line("t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad,signal,carrier_hz").is_err());
    }
}
