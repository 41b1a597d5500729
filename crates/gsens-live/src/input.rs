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

fn number(field: Option<&str>, name: &str, column: usize) -> Result<f64, String> {
    let s = field.ok_or_else(|| format!("column {column} ({name}) missing"))?.trim();
    let v: f64 = s.parse().map_err(|_| format!("column {column} ({name}): {s:?} is not a number"))?;
    if v.is_finite() { Ok(v) } else { Err(format!("column {column} ({name}): {s} is not finite")) }
}

fn integer(field: Option<&str>, name: &str, column: usize) -> Result<u32, String> {
    let s = field.ok_or_else(|| format!("column {column} ({name}) missing"))?.trim();
    s.parse().map_err(|_| format!("column {column} ({name}): {s:?} is not a non-negative integer"))
}

fn skippable(line: &str) -> bool {
    let t = line.trim();
    t.is_empty() || t.starts_with('#')
}

fn no_more(mut fields: core::str::Split<'_, char>, expected: usize) -> Result<(), String> {
    match fields.next() {
        None => Ok(()),
        Some(_) => Err(format!("more than {expected} columns")),
    }
}

/// One line of `imu.csv` (`t_s,fx_mps2,fy_mps2,fz_mps2`); the header is skipped.
/// Errors say which column is wrong (columns counted from 1).
pub fn parse_imu_line(line: &str) -> Result<LineKind, String> {
    parse_imu_fields(line, 0)
}

fn parse_imu_fields(line: &str, offset: usize) -> Result<LineKind, String> {
    if skippable(line) || line.trim() == IMU_COLUMNS.join(",") {
        return Ok(LineKind::Skip);
    }
    let mut f = line.trim_end().split(',');
    for _ in 0..offset {
        f.next();
    }
    let t_s = number(f.next(), IMU_COLUMNS[0], offset + 1)?;
    let mut accel_mps2 = [0.0; 3];
    for (i, a) in accel_mps2.iter_mut().enumerate() {
        *a = number(f.next(), IMU_COLUMNS[i + 1], offset + i + 2)?;
    }
    no_more(f, offset + 4)?;
    Ok(LineKind::Data(Input::Imu { t_s, accel_mps2 }))
}

/// One line of `tracking.csv` (`t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad`,
/// `elev_deg` possibly empty); the header is skipped. Logs with carrier
/// columns are not read live yet: their rows are errors saying so.
pub fn parse_tracking_line(line: &str) -> Result<LineKind, String> {
    parse_tracking_fields(line, 0)
}

fn parse_tracking_fields(line: &str, offset: usize) -> Result<LineKind, String> {
    let header = TRACKING_COLUMNS.join(",");
    if skippable(line) || line.trim() == header {
        return Ok(LineKind::Skip);
    }
    if line.trim().starts_with(&header) {
        return Err("carrier columns (signal, carrier_hz) are not read live yet: log GPS L1 only".into());
    }
    let mut f = line.trim_end().split(',');
    for _ in 0..offset {
        f.next();
    }
    let t_s = number(f.next(), "t_s", offset + 1)?;
    let channel = integer(f.next(), "channel", offset + 2)?;
    let prn = integer(f.next(), "prn", offset + 3)?;
    let cn0_dbhz = number(f.next(), "cn0_dbhz", offset + 4)?;
    let elev = f.next().ok_or_else(|| format!("column {} (elev_deg) missing", offset + 5))?;
    let elev_deg = if elev.trim().is_empty() { None } else { Some(number(Some(elev), "elev_deg", offset + 5)?) };
    let phase_err_rad = number(f.next(), "phase_err_rad", offset + 6)?;
    if f.next().is_some() {
        return Err(format!(
            "more than {} columns (carrier columns are not read live yet: log GPS L1 only)",
            offset + 6
        ));
    }
    Ok(LineKind::Data(Input::Tracking(TrackingRow { t_s, channel, prn, cn0_dbhz, elev_deg, phase_err_rad })))
}

/// One line of the merged stream (module docs): `imu,…` or `trk,…`; the
/// header lines of `imu.csv` and `tracking.csv` are skipped too.
pub fn parse_merged_line(line: &str) -> Result<LineKind, String> {
    if skippable(line) {
        return Ok(LineKind::Skip);
    }
    let tag = line.split(',').next().unwrap_or("").trim();
    match tag {
        "imu" => parse_imu_fields(line, 1),
        "trk" => parse_tracking_fields(line, 1),
        "t_s" => Ok(LineKind::Skip),
        _ => Err(format!("column 1: {tag:?} is neither `imu` nor `trk`")),
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
        assert!(parse_merged_line("gps,1,2").unwrap_err().contains("column 1"));
        assert!(parse_merged_line("imu,1.0,0,x,9.8").unwrap_err().contains("column 4 (fy_mps2)"));
        assert!(parse_merged_line("imu,1.0,0,0").unwrap_err().contains("column 5 (fz_mps2) missing"));
        assert!(parse_merged_line("trk,1.0,1,2,45,,0.1,9").unwrap_err().contains("more than 7 columns"));
        assert!(parse_merged_line("trk,1.0,-1,2,45,,0.1").unwrap_err().contains("column 3 (channel)"));
        assert!(parse_imu_line("1.0,0,NaN,9.8").unwrap_err().contains("not finite"));
        assert_eq!(parse_tracking_line("t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad").unwrap(), LineKind::Skip);
        assert!(parse_tracking_line("t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad,signal,carrier_hz").is_err());
    }
}
