//! A recorded session played back as `gsens live` would receive it: the
//! records written at real time or a multiple of it, to one merged stream
//! (`gsens live --stdin`) or appended to growing `imu.csv` and
//! `tracking.csv` files (`gsens live --follow-imu --follow-tracking`).

use crate::clock::Clock;
use crate::input::{Input, merged_header, merged_line};
use std::io::{ErrorKind, LineWriter, Write};
use std::path::{Path, PathBuf};
use std::time::Duration;

/// Where a replay writes its records.
pub enum ReplaySink {
    /// One merged stream: a [`merged_line`] per record, and before the
    /// first tracking record whose columns are not the six (and at each
    /// change of columns) the [`merged_header`] that declares them.
    Merged(Box<dyn Write>),
    /// The logs' own lines (the merged line without its tag): IMU records
    /// to `imu`, tracking rows to `tracking`, whose header line (the columns
    /// of the first tracking record) goes before its first row.
    Files {
        /// Receives the IMU records.
        imu: Box<dyn Write>,
        /// Receives the tracking rows.
        tracking: Box<dyn Write>,
    },
}

/// A replay's file that could not be made.
#[derive(Debug, thiserror::Error)]
#[error("{}: cannot create", path.display())]
pub struct CreateError {
    /// The file or folder.
    pub path: PathBuf,
    /// Why.
    #[source]
    pub source: std::io::Error,
}

impl ReplaySink {
    /// `dir/imu.csv` and `dir/tracking.csv` made afresh (the folder too, if
    /// need be), `imu.csv` with its header line, each written a line at a
    /// time so a follower sees whole lines; `tracking.csv` gets its header
    /// line with the first tracking record, which says its columns.
    pub fn files_in(dir: &Path) -> Result<ReplaySink, CreateError> {
        let error = |path: &Path| {
            let path = path.to_path_buf();
            move |source| CreateError { path, source }
        };
        std::fs::create_dir_all(dir).map_err(error(dir))?;
        let open = |name: &str, columns: &[&str]| -> Result<Box<dyn Write>, CreateError> {
            let path = dir.join(name);
            let mut w = LineWriter::new(std::fs::File::create(&path).map_err(error(&path))?);
            if !columns.is_empty() {
                writeln!(w, "{}", columns.join(",")).map_err(error(&path))?;
            }
            Ok(Box::new(w))
        };
        Ok(ReplaySink::Files { imu: open("imu.csv", &gsens_io::IMU_COLUMNS)?, tracking: open("tracking.csv", &[])? })
    }

    fn flush(&mut self) -> std::io::Result<()> {
        match self {
            ReplaySink::Merged(w) => w.flush(),
            ReplaySink::Files { imu, tracking } => imu.flush().and(tracking.flush()),
        }
    }

    /// The columns a merged stream's tracking records have before any header line.
    fn declared_at_start(&self) -> Option<Vec<&'static str>> {
        match self {
            ReplaySink::Merged(_) => Some(gsens_io::TRACKING_COLUMNS.to_vec()),
            ReplaySink::Files { .. } => None,
        }
    }

    /// Declares the columns of the tracking records like `record`.
    fn declare(&mut self, record: &gsens_io::TrackingRecord) -> std::io::Result<()> {
        match self {
            ReplaySink::Merged(w) => writeln!(w, "{}", merged_header(record)),
            ReplaySink::Files { tracking, .. } => writeln!(tracking, "{}", record.header().join(",")),
        }
    }

    fn write(&mut self, x: &Input) -> std::io::Result<()> {
        let line = merged_line(x);
        match self {
            ReplaySink::Merged(w) => writeln!(w, "{line}"),
            // The tags `imu,` and `trk,` are four bytes.
            ReplaySink::Files { imu, .. } if matches!(x, Input::Imu { .. }) => writeln!(imu, "{}", &line[4..]),
            ReplaySink::Files { tracking, .. } => writeln!(tracking, "{}", &line[4..]),
        }
    }
}

/// A replay's speed that is neither 0 (as fast as possible) nor a finite
/// multiple of real time above 0.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[error("speed {0}: must be 0 (as fast as possible) or positive")]
pub struct SpeedError(pub f64);

/// Checks a replay's speed: 0 (as fast as possible) or finite and > 0.
pub fn check_speed(speed: f64) -> Result<(), SpeedError> {
    if speed.is_finite() && speed >= 0.0 { Ok(()) } else { Err(SpeedError(speed)) }
}

/// Writes `inputs` to `sink` at `speed` times real time as `clock` keeps it
/// (0: as fast as possible): the record stamped t goes out once
/// (t − t₀)/speed has passed since the start, t₀ the first record's stamp,
/// the sink flushed before each wait. A reader that goes away (a closed
/// pipe) ends the replay quietly.
pub fn replay(inputs: &[Input], speed: f64, clock: &dyn Clock, sink: &mut ReplaySink) -> std::io::Result<()> {
    let quiet = |r: std::io::Result<()>| match r {
        Err(e) if e.kind() == ErrorKind::BrokenPipe => Ok(true),
        r => r.map(|()| false),
    };
    let Some(t0) = inputs.first().map(Input::t_s) else { return Ok(()) };
    let start = clock.now();
    let mut declared = sink.declared_at_start();
    for x in inputs {
        if speed > 0.0 {
            let due = Duration::from_secs_f64((x.t_s() - t0).max(0.0) / speed);
            if let Some(wait) = due.checked_sub(clock.now().saturating_sub(start)) {
                if quiet(sink.flush())? {
                    return Ok(());
                }
                clock.sleep(wait);
            }
        }
        if let Input::Tracking(r) = x {
            let columns = r.header();
            if declared.as_ref() != Some(&columns) {
                if quiet(sink.declare(r))? {
                    return Ok(());
                }
                declared = Some(columns);
            }
        }
        if quiet(sink.write(x))? {
            return Ok(());
        }
    }
    quiet(sink.flush()).map(|_| ())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::clock::ManualClock;
    use gsens_io::{TrackingRecord, TrackingRow};
    use std::sync::{Arc, Mutex};

    /// 0 and finite speeds above it replay; anything else is refused, named.
    #[test]
    fn a_speed_is_0_or_finite_and_positive() {
        assert!(check_speed(0.0).is_ok() && check_speed(2.5).is_ok());
        for bad in [-1.0, -0.0 - 1e-9, f64::NAN, f64::INFINITY] {
            assert!(check_speed(bad).is_err(), "{bad}");
        }
        assert_eq!(check_speed(-1.0).unwrap_err().to_string(), "speed -1: must be 0 (as fast as possible) or positive");
    }

    /// A writer into a shared buffer; fails with a closed pipe once `limit` bytes are in.
    #[derive(Clone)]
    struct Shared(Arc<Mutex<Vec<u8>>>, usize);

    impl Write for Shared {
        fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
            let mut v = self.0.lock().unwrap();
            if v.len() >= self.1 {
                return Err(ErrorKind::BrokenPipe.into());
            }
            v.extend_from_slice(buf);
            Ok(buf.len())
        }
        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }

    fn session() -> Vec<Input> {
        let row = |t_s| TrackingRow { t_s, channel: 1, prn: 5, cn0_dbhz: 45.0, elev_deg: None, phase_err_rad: 0.01 };
        (0..=10)
            .flat_map(|k| {
                let t_s = f64::from(k);
                [Input::Imu { t_s, accel_mps2: [0.0, 0.0, 9.81] }, Input::Tracking(TrackingRecord::plain(row(t_s)))]
            })
            .collect()
    }

    #[test]
    fn records_go_out_at_their_time_over_the_speed() {
        let buffer = Shared(Arc::new(Mutex::new(Vec::new())), usize::MAX);
        let clock = ManualClock::new();
        let mut sink = ReplaySink::Merged(Box::new(buffer.clone()));
        replay(&session(), 2.0, &clock, &mut sink).unwrap();
        // 10 s of records at twice real time.
        assert_eq!(clock.now(), Duration::from_secs(5));
        let text = String::from_utf8(buffer.0.lock().unwrap().clone()).unwrap();
        let expected: String = session().iter().map(|x| merged_line(x) + "\n").collect();
        assert_eq!(text, expected);
        let clock = ManualClock::new();
        replay(&session(), 0.0, &clock, &mut ReplaySink::Merged(Box::new(std::io::sink()))).unwrap();
        assert_eq!(clock.now(), Duration::ZERO, "speed 0 never waits");
    }

    #[test]
    fn files_get_their_own_lines_and_a_closed_pipe_ends_quietly() {
        let dir = tempfile::tempdir().unwrap();
        let mut sink = ReplaySink::files_in(&dir.path().join("out")).unwrap();
        replay(&session(), 0.0, &ManualClock::new(), &mut sink).unwrap();
        drop(sink);
        let imu = std::fs::read_to_string(dir.path().join("out/imu.csv")).unwrap();
        assert_eq!(imu.lines().next(), Some("t_s,fx_mps2,fy_mps2,fz_mps2"));
        assert_eq!(imu.lines().nth(2), Some("1,0,0,9.81"));
        let tracking = std::fs::read_to_string(dir.path().join("out/tracking.csv")).unwrap();
        assert_eq!(tracking.lines().nth(1), Some("0,1,5,45,,0.01"));
        assert_eq!(tracking.lines().count(), 12);

        let closed = Shared(Arc::new(Mutex::new(Vec::new())), 40);
        replay(&session(), 0.0, &ManualClock::new(), &mut ReplaySink::Merged(Box::new(closed.clone()))).unwrap();
        assert!(closed.0.lock().unwrap().len() < 100);
        let e = ReplaySink::files_in(&dir.path().join("out/imu.csv/sub")).err().unwrap();
        assert!(e.to_string().ends_with("sub: cannot create"), "{e}");
    }
}
