//! A recorded session as the stream `gsens live` would have received: the
//! records of `imu.csv` and `tracking.csv` merged in time order.

use std::path::Path;

use crate::input::{Input, LineFormat, LineKind};

/// The records of `dir/imu.csv` and `dir/tracking.csv` in time order (at
/// equal time stamps the IMU first: a receiver's row at t uses the IMU up to
/// t). Errors name the file and line, or the directory when neither file
/// holds a record.
pub fn read_session_dir(dir: &Path) -> Result<Vec<Input>, String> {
    let read = |name: &str, format: LineFormat| -> Result<Vec<Input>, String> {
        let path = dir.join(name);
        let text = std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
        let mut out = Vec::new();
        let mut parser = format.parser();
        for (i, line) in text.lines().enumerate() {
            match parser.parse(line).map_err(|e| format!("{}:{}: {e}", path.display(), i + 1))? {
                LineKind::Data(x) => out.push(x),
                LineKind::Skip => {}
            }
        }
        Ok(out)
    };
    let imu = read("imu.csv", LineFormat::Imu)?;
    let trk = read("tracking.csv", LineFormat::Tracking)?;
    if imu.is_empty() && trk.is_empty() {
        return Err(format!("{}: no records to replay", dir.display()));
    }
    let mut merged = Vec::with_capacity(imu.len() + trk.len());
    let (mut i, mut j) = (0, 0);
    while i < imu.len() || j < trk.len() {
        let take_imu = j >= trk.len() || (i < imu.len() && imu[i].t_s() <= trk[j].t_s());
        if take_imu {
            merged.push(imu[i]);
            i += 1;
        } else {
            merged.push(trk[j]);
            j += 1;
        }
    }
    Ok(merged)
}

#[cfg(test)]
mod tests {
    /// Logs with headers only are no session to replay, and the error names the directory.
    #[test]
    fn a_session_without_records_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("imu.csv"), "t_s,fx_mps2,fy_mps2,fz_mps2\n").unwrap();
        std::fs::write(dir.path().join("tracking.csv"), "t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad\n").unwrap();
        let e = super::read_session_dir(dir.path()).unwrap_err();
        assert_eq!(e, format!("{}: no records to replay", dir.path().display()));
    }
}
