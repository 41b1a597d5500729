//! The inputs of a live session, one reader thread each, and what they send
//! to the event loop ([`SourceEvent`]).

use std::io::BufRead;
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::mpsc::Sender;
use std::time::Duration;

use crate::clock::Clock;
use crate::follow::Follower;
use crate::input::{Input, LineFormat};

/// What a reader thread sends; `source` indexes the session's [`Source`]s.
#[derive(Debug, Clone, PartialEq)]
pub enum SourceEvent {
    /// A text line, numbered from 1.
    Line {
        /// The source.
        source: usize,
        /// Its line number.
        line: u64,
        /// The line without its line break.
        text: String,
    },
    /// A record already parsed (a monitor row on the grid), numbered by its datagram.
    Record {
        /// The source.
        source: usize,
        /// The datagram that brought it.
        line: u64,
        /// The record.
        input: Input,
    },
    /// Bytes of a byte stream (a UBX log or serial port), in the pieces
    /// they arrived in: a piece may end inside a frame.
    Bytes {
        /// The source.
        source: usize,
        /// The bytes.
        bytes: Vec<u8>,
    },
    /// Something the source noticed that is not about one line.
    Notice {
        /// The source.
        source: usize,
        /// What it noticed.
        text: String,
    },
    /// A followed file became shorter: its logger restarted and it is read again from its start.
    Restarted {
        /// The source.
        source: usize,
    },
    /// The source ended: its end, an error, or its idle timeout (`why`).
    Ended {
        /// The source.
        source: usize,
        /// Why, when not simply the end of its input.
        why: Option<String>,
    },
}

/// One input of a session: its name (in notices and the kept files) and the
/// format of its lines.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Source {
    /// A file name, `stdin`, `udp ADDR`.
    pub name: String,
    /// The format of its lines; `None` for a source that sends records
    /// already parsed (the monitor: its thread keeps the datagrams itself).
    pub format: Option<LineFormat>,
}

/// A followed file is polled this often [ms]: a record reaches the screen
/// within this and the screen's redraw interval.
pub(crate) const FOLLOW_POLL_MS: u64 = 20;

/// Reads `reader` to its end, a line at a time.
pub(crate) fn spawn_lines(tx: Sender<SourceEvent>, source: usize, reader: Box<dyn BufRead + Send>) {
    std::thread::spawn(move || {
        for (i, text) in reader.lines().enumerate() {
            let line = i as u64 + 1;
            match text {
                Ok(text) => {
                    if tx.send(SourceEvent::Line { source, line, text }).is_err() {
                        return;
                    }
                }
                Err(e) => {
                    let _ = tx.send(SourceEvent::Ended { source, why: Some(e.to_string()) });
                    return;
                }
            }
        }
        let _ = tx.send(SourceEvent::Ended { source, why: None });
    });
}

/// Follows the growing file `path`, ending when it has not grown for
/// `idle_timeout_s` (never when 0).
pub(crate) fn spawn_follow(
    tx: Sender<SourceEvent>,
    source: usize,
    path: PathBuf,
    idle_timeout_s: f64,
    clock: Arc<dyn Clock>,
) {
    std::thread::spawn(move || {
        let mut f = Follower::new(&path);
        let mut last_growth = clock.now();
        loop {
            match f.poll() {
                Ok(p) => {
                    if p.restarted && tx.send(SourceEvent::Restarted { source }).is_err() {
                        return;
                    }
                    if !p.lines.is_empty() {
                        last_growth = clock.now();
                    }
                    for (line, text) in p.lines {
                        if tx.send(SourceEvent::Line { source, line, text }).is_err() {
                            return;
                        }
                    }
                }
                Err(e) => {
                    let why = format!("{}: {e}", path.display());
                    let _ = tx.send(SourceEvent::Ended { source, why: Some(why) });
                    return;
                }
            }
            if idle_timeout_s > 0.0 && (clock.now() - last_growth).as_secs_f64() > idle_timeout_s {
                let why = format!("no new line for {idle_timeout_s} s");
                let _ = tx.send(SourceEvent::Ended { source, why: Some(why) });
                return;
            }
            clock.sleep(Duration::from_millis(FOLLOW_POLL_MS));
        }
    });
}
