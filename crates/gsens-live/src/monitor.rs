//! GNSS-SDR's tracking monitor received live: as a source of a live
//! session (every datagram that brings something new kept in gsens's
//! capture format, its rows put on the 20 ms grid as they arrive), or
//! recorded whole until it falls silent.

use std::io::Write;
use std::sync::mpsc::Sender;
use std::time::Duration;

use gsens_gnss_sdr::ImportSettings;
use gsens_gnss_sdr::monitor::{
    LiveGrid, MonitorEvent, MonitorReceiver, Notice, Received, Recorder, write_capture_record,
};
use gsens_io::TrackingRecord;

use crate::clock::Clock;
use crate::input::Input;
use crate::sources::SourceEvent;

/// The monitor a session receives: where, and what the run's configuration says about it.
#[derive(Debug, Clone)]
pub struct MonitorInput {
    /// The address to receive on (GNSS-SDR's `TrackingMonitor.client_addresses` and `udp_port`).
    pub addr: String,
    /// The run's loop (modelled exactly), sampling rate and settling time.
    pub import: ImportSettings,
    /// `TrackingMonitor.decimation_factor`.
    pub decimation: u32,
    /// The sampling rate \[Hz\], `None` to take each message's own.
    pub fs_hz: Option<f64>,
}

/// Waiting for a datagram ends after this long without one [ms], so that
/// the idle timeout is looked at.
pub(crate) const RECEIVE_WAIT_MS: u64 = 100;

/// Where the monitor's datagrams come from: the UDP socket, or datagrams
/// given by a test.
pub trait Datagrams: Send {
    /// Waits for the next datagram (a bounded time) and decodes it.
    fn recv(&mut self) -> std::io::Result<Received>;
    /// The bytes of the datagram [`Datagrams::recv`] last gave.
    fn last_datagram(&self) -> &[u8];
}

impl Datagrams for MonitorReceiver {
    fn recv(&mut self) -> std::io::Result<Received> {
        MonitorReceiver::recv(self)
    }

    fn last_datagram(&self) -> &[u8] {
        MonitorReceiver::last_datagram(self)
    }
}

/// Receives the monitor until no datagram came for `idle_timeout_s` (never
/// when 0) or the session stops listening: the body of the monitor's
/// thread. Each datagram that brought something new is appended to `raw`
/// (GNSS-SDR re-sends its outputs many times over: a repeat is not kept),
/// its notices and rows sent as `source`'s, rows numbered by their datagram.
pub fn receive_monitor(
    tx: &Sender<SourceEvent>,
    source: usize,
    rx: &mut dyn Datagrams,
    grid: &mut LiveGrid,
    raw: &mut dyn Write,
    idle_timeout_s: f64,
    clock: &dyn Clock,
) {
    let mut last = clock.now();
    let mut datagram = 0u64;
    loop {
        let events = match rx.recv() {
            Ok(Received::Datagram(events)) => events,
            Ok(Received::Timeout) => {
                let _ = raw.flush();
                if idle_timeout_s > 0.0 && (clock.now() - last).as_secs_f64() > idle_timeout_s {
                    break;
                }
                continue;
            }
            Err(e) => {
                let _ = tx.send(SourceEvent::Ended { source, why: Some(e.to_string()) });
                return;
            }
        };
        last = clock.now();
        datagram += 1;
        if !events.is_empty() {
            let _ = write_capture_record(&mut &mut *raw, rx.last_datagram());
        }
        for e in &events {
            if let MonitorEvent::Notice(n) = e
                && tx.send(SourceEvent::Notice { source, text: n.to_string() }).is_err()
            {
                return;
            }
            for row in grid.push(e) {
                if tx
                    .send(SourceEvent::Record {
                        source,
                        line: datagram,
                        input: Input::Tracking(TrackingRecord::plain(row)),
                    })
                    .is_err()
                {
                    return;
                }
            }
        }
    }
    for row in grid.flush() {
        let _ =
            tx.send(SourceEvent::Record { source, line: datagram, input: Input::Tracking(TrackingRecord::plain(row)) });
    }
    let _ = raw.flush();
    let why = format!("no datagram for {idle_timeout_s} s; {} rows came too late for the grid", grid.late());
    let _ = tx.send(SourceEvent::Ended { source, why: Some(why) });
}

/// Records the monitor (`gsens import gnss-sdr-monitor`): every datagram
/// appended to `raw` as received (when given), its events taken by
/// `recorder`, its notices given to `notice`; until no datagram came for
/// `idle_timeout_s`, counted from the start too.
pub fn record_monitor(
    rx: &mut dyn Datagrams,
    recorder: &mut Recorder,
    mut raw: Option<&mut dyn Write>,
    idle_timeout_s: f64,
    clock: &dyn Clock,
    notice: &mut dyn FnMut(&Notice),
) -> std::io::Result<()> {
    let idle = Duration::from_secs_f64(idle_timeout_s);
    let mut last = clock.now();
    loop {
        match rx.recv()? {
            Received::Timeout => {
                if clock.now().saturating_sub(last) >= idle {
                    break;
                }
            }
            Received::Datagram(events) => {
                last = clock.now();
                if let Some(w) = raw.as_mut() {
                    write_capture_record(w, rx.last_datagram())?;
                }
                for e in &events {
                    if let MonitorEvent::Notice(n) = e {
                        notice(n);
                    }
                }
                recorder.take(&events);
            }
        }
    }
    match raw {
        Some(w) => w.flush(),
        None => Ok(()),
    }
}
