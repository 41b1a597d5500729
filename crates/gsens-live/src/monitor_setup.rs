//! What a GNSS-SDR run's configuration says about its tracking monitor
//! stream (the loop, the sampling rate, the decimation, the settling time),
//! and how a recording of the stream reports on itself: its notices, a
//! few of each kind and then only counted, and the tracks it recorded.

use crate::monitor::MonitorInput;
use gsens_gnss_sdr::monitor::Notice;
use gsens_gnss_sdr::{GnssSdrConf, GnssSdrError, ImportSettings, TrackingConf};
use std::path::Path;

/// A GNSS-SDR run's monitor stream as its configuration describes it.
#[derive(Debug, Clone)]
pub struct MonitorSetup {
    /// The conversion settings: the loop, sampling rate and settling time.
    pub import: ImportSettings,
    /// `TrackingMonitor.decimation_factor` (1 without a configuration).
    pub decimation: u32,
    /// The sampling rate \[Hz\]: the one given, else the configuration's
    /// (`None`: each message's own).
    pub fs_hz: Option<f64>,
    /// What to tell the user about the stream, if anything: with an
    /// extended integration other than the 20 ms data bit's, the monitor's
    /// prompt is not the discriminator's output.
    pub note: Option<String>,
}

/// The monitor setup of the configuration `conf` (GNSS-SDR's defaults
/// without one), with the sampling rate `fs_hz` and the settling time
/// `settle_s` when given.
pub fn monitor_setup(
    conf: Option<&Path>,
    fs_hz: Option<f64>,
    settle_s: Option<f64>,
) -> Result<MonitorSetup, GnssSdrError> {
    let (tracking, decimation) = match conf {
        Some(p) => {
            let conf = GnssSdrConf::read(p)?;
            (conf.tracking()?, conf.get_count("TrackingMonitor.decimation_factor")?.unwrap_or(1))
        }
        None => (TrackingConf::defaults(), 1),
    };
    let fs_hz = fs_hz.or(tracking.fs_hz);
    let symbols = tracking.extend_correlation_symbols;
    let note = (symbols != 20).then(|| {
        format!(
            "note: Tracking_1C.extend_correlation_symbols = {symbols}: the monitor's prompt is the 20 ms data bit's, \
             so φ is the phase of that sum, not the {symbols} ms discriminator output\n"
        )
    });
    let mut import = ImportSettings::new(fs_hz.unwrap_or(1.0), tracking);
    import.settle_s = settle_s;
    Ok(MonitorSetup { import, decimation, fs_hz, note })
}

impl MonitorSetup {
    /// The monitor a live session receives on `addr` with this setup.
    pub fn input(self, addr: &str) -> MonitorInput {
        MonitorInput { addr: addr.to_string(), import: self.import, decimation: self.decimation, fs_hz: self.fs_hz }
    }
}

/// Notices of one kind shown before the rest are only counted.
pub(crate) const NOTICES_SHOWN: usize = 10;

/// Which notices a recording shows: the first `NOTICES_SHOWN` of each
/// kind, then one line saying the rest are only counted.
#[derive(Debug, Clone, Default)]
pub struct NoticeLimit {
    shown: [usize; 4],
}

impl NoticeLimit {
    /// The line to show for `notice` (with its newline), if any.
    pub fn line(&mut self, notice: &Notice) -> Option<String> {
        let kind = match notice {
            Notice::Garbage { .. } => 0,
            Notice::Gap { .. } => 1,
            Notice::Restart { .. } => 2,
            Notice::LossOfLock { .. } => 3,
        };
        self.shown[kind] += 1;
        match self.shown[kind] {
            n if n <= NOTICES_SHOWN => Some(format!("{notice}\n")),
            n if n == NOTICES_SHOWN + 1 => Some("(further notices of this kind are only counted)\n".into()),
            _ => None,
        }
    }
}

/// The tracks of a recording ([`gsens_gnss_sdr::monitor::Recorder::tracks`]),
/// a line each: channel, PRN, first and last time, outputs.
pub fn render_recorded_tracks(tracks: &[(u32, u32, f64, f64, usize)]) -> String {
    tracks
        .iter()
        .map(|(channel, prn, from, to, n)| format!("  channel {channel}: PRN {prn} {from:.2}–{to:.2} s, {n} outputs\n"))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn without_a_configuration_the_defaults_and_the_given_rate_hold() {
        let s = monitor_setup(None, Some(4e6), Some(1.5)).unwrap();
        assert_eq!((s.decimation, s.fs_hz, s.import.settle_s), (1, Some(4e6), Some(1.5)));
        // GNSS-SDR's default integrates 1 ms, not the 20 ms bit the monitor's prompt sums.
        let note = s.note.clone().expect("a note on the prompt");
        assert!(
            note.starts_with("note: Tracking_1C.extend_correlation_symbols = 1: ")
                && note.ends_with("the 1 ms discriminator output\n"),
            "{note}"
        );
        let input = s.input("127.0.0.1:1234");
        assert_eq!((input.addr.as_str(), input.decimation), ("127.0.0.1:1234", 1));
    }

    #[test]
    fn ten_notices_of_a_kind_are_shown_then_one_line_says_the_rest_are_counted() {
        let mut limit = NoticeLimit::default();
        let gap = Notice::Gap { channel: 1, prn: 5, from_s: 1.0, to_s: 2.0, missing: 49 };
        let lines: Vec<Option<String>> = (0..12).map(|_| limit.line(&gap)).collect();
        assert!(lines[..10].iter().all(|l| l.as_deref() == Some(&format!("{gap}\n"))));
        assert_eq!(lines[10].as_deref(), Some("(further notices of this kind are only counted)\n"));
        assert_eq!(lines[11], None);
        // Another kind has its own count.
        let garbage = Notice::Garbage { datagram: 3, error: "short".into() };
        assert!(limit.line(&garbage).is_some());
    }

    #[test]
    fn tracks_are_listed_a_line_each() {
        let text = render_recorded_tracks(&[(0, 5, 1.0, 61.25, 3000), (1, 12, 2.0, 30.0, 1400)]);
        assert_eq!(
            text,
            "  channel 0: PRN 5 1.00–61.25 s, 3000 outputs\n  channel 1: PRN 12 2.00–30.00 s, 1400 outputs\n"
        );
    }
}
