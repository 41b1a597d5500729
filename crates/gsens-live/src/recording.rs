//! A recording of GNSS-SDR's tracking monitor into files (what `gsens import
//! gnss-sdr-monitor` does): the datagrams received until the monitor falls
//! silent, put on the common grid as `tracking.csv`, with what was received
//! and how to estimate from it told as it goes.

use crate::monitor::record_monitor;
use crate::monitor_setup::{MonitorSetup, NoticeLimit, render_recorded_tracks};
use crate::{Clock, CreateError};
use gsens_core::units::Decimal;
use gsens_gnss_sdr::monitor::{MonitorReceiver, MonitorStream, Recorder};
use std::io::{BufWriter, Write};
use std::path::Path;
use std::time::Duration;

/// Why a recording failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RecordingError {
    /// The address could not be listened on.
    #[error("{addr}: cannot listen")]
    Listen {
        /// The address.
        addr: String,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// An output file could not be made.
    #[error(transparent)]
    Create(#[from] CreateError),
    /// Receiving or writing failed.
    #[error(transparent)]
    Io(#[from] std::io::Error),
    /// The monitor sent no tracking row.
    #[error(
        "no tracking row received on {addr} in the run ({counts}): is GNSS-SDR's \
         TrackingMonitor.enable_monitor=true with client_addresses and udp_port pointing here?"
    )]
    NothingReceived {
        /// The address listened on.
        addr: String,
        /// What was received ([`gsens_gnss_sdr::monitor::MonitorCounts::summary`]).
        counts: String,
    },
}

/// A recording of the monitor of a run set up as `setup`, received on
/// `listen` until no datagram came for `idle_timeout_s` (counted from the
/// start too), written as `out` (`tracking.csv` on the common grid, each
/// track's first settling time dropped) and every datagram as received to
/// `raw` when given.
#[derive(Debug, Clone)]
pub struct MonitorRecording<'a> {
    /// The address to receive on.
    pub listen: &'a str,
    /// The run's monitor stream ([`crate::monitor_setup`]).
    pub setup: MonitorSetup,
    /// Silence that ends the recording \[s\].
    pub idle_timeout_s: f64,
    /// The tracking log written.
    pub out: &'a Path,
    /// The datagrams' capture, when asked.
    pub raw: Option<&'a Path>,
}

impl MonitorRecording<'_> {
    /// Records, telling `progress` the setup's note, where it listens and
    /// the stream's notices ([`NoticeLimit`]), and `summary` what was
    /// received, the tracks and the files written with the options (spelled
    /// by `option`) that estimate from them with the run's loop.
    pub fn run(
        &self,
        clock: &dyn Clock,
        progress: &mut dyn FnMut(&str),
        summary: &mut dyn FnMut(&str) -> std::io::Result<()>,
        option: impl Fn(&str) -> String,
    ) -> Result<(), RecordingError> {
        let setup = &self.setup;
        progress(setup.note.as_deref().unwrap_or_default());
        let (settle_s, stage) = (setup.import.settle_time_s(), setup.import.stage());
        let poll = Duration::from_secs_f64(self.idle_timeout_s).min(Duration::from_millis(200));
        let stream = MonitorStream::new(setup.fs_hz, setup.decimation);
        let mut rx = MonitorReceiver::bind(self.listen, stream, poll)
            .map_err(|source| RecordingError::Listen { addr: self.listen.to_string(), source })?;
        let mut raw = self.raw.map(create).transpose()?.map(BufWriter::new);
        let listening = rx.local_addr()?;
        progress(&format!("listening on {listening} (stops after {} s without a datagram)\n", self.idle_timeout_s));
        let mut recorder = Recorder::new(setup.decimation);
        let mut limit = NoticeLimit::default();
        let mut say = |n: &_| progress(&limit.line(n).unwrap_or_default());
        let raw_out = raw.as_mut().map(|w| w as &mut dyn Write);
        record_monitor(&mut rx, &mut recorder, raw_out, self.idle_timeout_s, clock, &mut say)?;
        let counts = &rx.stream.counts;
        summary(&format!("received {}\n", counts.summary()))?;
        if counts.rows == 0 {
            return Err(RecordingError::NothingReceived { addr: self.listen.to_string(), counts: counts.summary() });
        }
        let (grid, tracks) = (recorder.finish(settle_s), recorder.tracks());
        summary(&render_recorded_tracks(&tracks))?;
        gsens_io::write_tracking_csv(BufWriter::new(create(self.out)?), &grid)?.flush()?;
        let out = self.out.display();
        summary(&format!(
            "wrote {} rows of {} tracks → {out} (common {} s grid, the first {settle_s:.2} s of each track dropped){}; \
             estimate with the receiver's loop: gsens estimate {} {out} {} {} {} {} {} {}\n",
            grid.len(),
            tracks.len(),
            Decimal(recorder.interval_s()),
            self.raw.map_or(String::new(), |p| format!(", datagrams → {}", p.display())),
            option("tracking"),
            option("order"),
            stage.order,
            option("bn_hz"),
            stage.bw_hz,
            option("loop_interval_s"),
            Decimal(f64::from(stage.symbols) * 1e-3),
        ))?;
        Ok(())
    }
}

/// A new file at `path`.
fn create(path: &Path) -> Result<std::fs::File, CreateError> {
    std::fs::File::create(path).map_err(|source| CreateError { path: path.to_path_buf(), source })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{ManualClock, monitor_setup};

    /// A monitor that sends nothing: the recording says where it listened,
    /// what it received, and ends on the error that says what to check,
    /// writing no tracking log. The manual clock stands still, so an idle
    /// timeout of zero ends it at the first poll.
    #[test]
    fn a_silent_monitor_ends_on_nothing_received() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("tracking.csv");
        let setup = monitor_setup(None, Some(4e6), None).unwrap();
        let recording = MonitorRecording { listen: "127.0.0.1:0", setup, idle_timeout_s: 0.0, out: &out, raw: None };
        let (mut progress, mut summary) = (String::new(), String::new());
        let e = recording
            .run(
                &ManualClock::default(),
                &mut |t| progress.push_str(t),
                &mut |t| {
                    summary.push_str(t);
                    Ok(())
                },
                |n| n.into(),
            )
            .unwrap_err();
        assert!(
            progress.contains("listening on 127.0.0.1:") && progress.ends_with("without a datagram)\n"),
            "{progress}"
        );
        assert!(summary.starts_with("received ") && !out.exists(), "{summary}");
        assert!(matches!(e, RecordingError::NothingReceived { .. }), "{e}");
        assert!(e.to_string().starts_with("no tracking row received on 127.0.0.1:0 in the run ("), "{e}");
    }
}
