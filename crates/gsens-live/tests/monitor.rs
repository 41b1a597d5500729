//! The monitor's receiving loops (`gsens_live::receive_monitor` of a live
//! session, `gsens_live::record_monitor` of `gsens import
//! gnss-sdr-monitor`) on the datagrams of a real GNSS-SDR 0.0.17 monitor
//! capture (gsens-gnss-sdr's fixture) and a garbage datagram, given in order
//! without a socket, on an injected clock: their idle timeouts, notices,
//! rows on the 20 ms grid and the datagrams they keep do not depend on the
//! machine's speed.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::mpsc;
use std::time::Duration;

use gsens_gnss_sdr::monitor::{
    LiveGrid, MonitorStream, Notice, Received, Recorder, split_capture, write_capture_record,
};
use gsens_gnss_sdr::{GnssSdrConf, ImportSettings};
use gsens_live::{Clock, Datagrams, Input, ManualClock, SourceEvent, receive_monitor, record_monitor};

fn fixture() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../gsens-gnss-sdr/tests/fixtures/monitor")
}

/// Datagrams given in order, then nothing: each empty wait moves the clock
/// by a socket's read timeout.
struct Replayed {
    datagrams: Vec<Vec<u8>>,
    next: usize,
    stream: MonitorStream,
    clock: Arc<ManualClock>,
}

impl Datagrams for Replayed {
    fn recv(&mut self) -> std::io::Result<Received> {
        match self.datagrams.get(self.next) {
            Some(d) => {
                self.next += 1;
                Ok(Received::Datagram(self.stream.push(d)))
            }
            None => {
                self.clock.advance(Duration::from_millis(100));
                Ok(Received::Timeout)
            }
        }
    }

    fn last_datagram(&self) -> &[u8] {
        self.next.checked_sub(1).and_then(|i| self.datagrams.get(i)).map_or(&[], Vec::as_slice)
    }
}

/// The fixture's run: its import settings and decimation, and its first
/// 1 200 datagrams with a garbage one before the 101st.
fn fixture_run() -> (ImportSettings, u32, Vec<Vec<u8>>) {
    let conf = GnssSdrConf::read(fixture().join("gnss-sdr.conf")).unwrap();
    let tracking = conf.tracking().unwrap();
    let decimation = conf.get_count("TrackingMonitor.decimation_factor").unwrap().unwrap_or(1);
    let import = ImportSettings::new(tracking.fs_hz.unwrap_or(1.0), tracking);
    let bytes = std::fs::read(fixture().join("monitor.bin")).unwrap();
    let mut datagrams: Vec<Vec<u8>> = split_capture(&bytes).unwrap().iter().take(1200).map(|d| d.to_vec()).collect();
    datagrams.insert(100, b"not protobuf \xff\xff".to_vec());
    (import, decimation, datagrams)
}

#[test]
fn the_monitor_loop_grids_rows_keeps_new_datagrams_and_ends_when_idle() {
    let (import, decimation, datagrams) = fixture_run();
    let fs_hz = import.tracking.fs_hz;
    let clock = Arc::new(ManualClock::new());
    let mut rx = Replayed {
        datagrams: datagrams.clone(),
        next: 0,
        stream: MonitorStream::new(fs_hz, decimation),
        clock: clock.clone(),
    };
    let mut grid = LiveGrid::new(import.record_interval_s(), import.settle_time_s());
    let (tx, events) = mpsc::channel();
    let mut raw = Vec::new();
    receive_monitor(&tx, 1, &mut rx, &mut grid, &mut raw, 1.5, &*clock);
    drop(tx);
    let events: Vec<SourceEvent> = events.into_iter().collect();

    // Ended on the injected clock, just past the idle timeout.
    let idle_s = clock.now().as_secs_f64();
    assert!((1.5..1.7).contains(&idle_s), "{idle_s} s");
    let Some(SourceEvent::Ended { source: 1, why: Some(why) }) = events.last() else { panic!("{:?}", events.last()) };
    assert!(why.starts_with("no datagram for 1.5 s; ") && why.ends_with("rows came too late for the grid"), "{why}");

    let notices: Vec<&str> = events
        .iter()
        .filter_map(|e| match e {
            SourceEvent::Notice { text, .. } => Some(text.as_str()),
            _ => None,
        })
        .collect();
    assert!(notices.iter().any(|n| n.starts_with("datagram 100: ") && n.contains("not a GNSS-SDR Observables")));

    // Rows on the 20 ms grid, numbered by the datagram that brought them.
    let rows: Vec<(u64, f64)> = events
        .iter()
        .filter_map(|e| match e {
            SourceEvent::Record { source: 1, line, input: Input::Tracking(r) } => Some((*line, r.row.t_s)),
            _ => None,
        })
        .collect();
    assert!(rows.len() > 800, "{} rows", rows.len());
    assert!(rows.windows(2).all(|w| w[0].0 <= w[1].0 && w[1].0 <= 1201));
    for (_, t) in &rows {
        assert!((t / 0.02 - (t / 0.02).round()).abs() < 1e-6, "{t}");
    }

    // Kept: every datagram that brought something (the garbage too), not the repeats.
    let mut stream = MonitorStream::new(fs_hz, decimation);
    let mut expected = Vec::new();
    for d in &datagrams {
        if !stream.push(d).is_empty() {
            write_capture_record(&mut expected, d).unwrap();
        }
    }
    assert_eq!(raw, expected);
    let kept = split_capture(&raw).unwrap().len();
    assert!(kept > 100 && kept < datagrams.len(), "{kept} of {} datagrams kept", datagrams.len());
}

/// Recording the monitor (`gsens import gnss-sdr-monitor`): every datagram
/// kept as received, each counted, the garbage one said, the rows on the
/// 20 ms grid; it stops after the idle time on the injected clock.
#[test]
fn recording_keeps_and_counts_every_datagram_until_idle() {
    let (import, decimation, datagrams) = fixture_run();
    let fs_hz = import.tracking.fs_hz;
    let clock = Arc::new(ManualClock::new());
    let stream = MonitorStream::new(fs_hz, decimation);
    let mut rx = Replayed { datagrams: datagrams.clone(), next: 0, stream, clock: clock.clone() };
    let mut recorder = Recorder::new(decimation);
    let (mut raw, mut notices) = (Vec::new(), Vec::new());
    let mut say = |n: &Notice| notices.push(n.to_string());
    record_monitor(&mut rx, &mut recorder, Some(&mut raw), 1.5, &*clock, &mut say).unwrap();
    let idle_s = clock.now().as_secs_f64();
    assert!((1.5..1.7).contains(&idle_s), "{idle_s} s");
    assert!(rx.stream.counts.summary().starts_with("1201 datagrams (1 garbage)"), "{}", rx.stream.counts.summary());
    assert!(notices.iter().any(|n| n.starts_with("datagram 100: ") && n.contains("not a GNSS-SDR Observables")));
    let mut sent = Vec::new();
    for d in &datagrams {
        write_capture_record(&mut sent, d).unwrap();
    }
    assert_eq!(raw, sent, "the raw capture holds every datagram as received");
    let rows = recorder.finish(import.settle_time_s());
    assert!(rows.len() > 800, "{} rows", rows.len());
    assert!(rows.iter().all(|r| (r.t_s / 0.02 - (r.t_s / 0.02).round()).abs() < 1e-6));
}
