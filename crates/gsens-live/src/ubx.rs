//! A u-blox module's UBX stream as a live input: a log file being written,
//! followed as it grows (`tail -f`), the module's serial port (USB CDC-ACM
//! such as `/dev/ttyACM0`, or a UART) read as a byte stream, or a pipe
//! (standard input, a named pipe) read until its writer closes it. The bytes go to
//! the event loop in the pieces they arrive in ([`SourceEvent::Bytes`]);
//! [`gsens_ublox::UbxStream`] reads the complete frames among them.

use std::fs::File;
use std::io::{ErrorKind, Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::mpsc::Sender;
use std::time::Duration;

use gsens_calib::ObservationRecord;
use gsens_ublox::UbxSettings;

use crate::clock::Clock;
use crate::sources::{FOLLOW_POLL_MS, SourceEvent};

/// How a UBX stream is read and calibrated: the reader's settings (how the
/// ESF sensor time maps to GPS time) and the observable the estimate is made
/// from, as `gsens estimate --ubx` takes them.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct UbxOptions {
    /// The reader's settings.
    pub settings: UbxSettings,
    /// What the estimate is made from.
    pub record: ObservationRecord,
}

/// Bytes read at most at once.
const READ_CHUNK: usize = 64 * 1024;

/// A serial port's read returns after this long without a byte (termios
/// VTIME, in tenths of a second), so that the idle timeout is looked at.
#[cfg(unix)]
const SERIAL_READ_TIMEOUT_DS: u8 = 1;

/// Whether `path` is a character device (a serial port) rather than a file.
pub(crate) fn is_device(path: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        std::fs::metadata(path).is_ok_and(|m| m.file_type().is_char_device())
    }
    #[cfg(not(unix))]
    {
        let _ = path;
        false
    }
}

/// The path that names standard input as a UBX stream.
pub(crate) const STDIN: &str = "-";

/// The stream's name in notices and messages: its path, `stdin` for [`STDIN`].
pub(crate) fn stream_name(path: &Path) -> String {
    if path == Path::new(STDIN) { "stdin".into() } else { path.display().to_string() }
}

/// Whether `path` is a pipe: standard input ([`STDIN`]) or a named pipe (a
/// FIFO another program writes into, such as `socat` or `str2str` relaying
/// a module), read until its writer closes it.
pub(crate) fn is_pipe(path: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        path == Path::new(STDIN) || std::fs::metadata(path).is_ok_and(|m| m.file_type().is_fifo())
    }
    #[cfg(not(unix))]
    {
        path == Path::new(STDIN)
    }
}

/// Puts the serial port `file` in raw mode (no line editing, no character
/// translation, 8 data bits, receiver on, modem lines ignored), at
/// `baud` where given, its reads returning after
/// [`SERIAL_READ_TIMEOUT_DS`] without a byte. POSIX termios, "Non-canonical
/// mode input processing" (VMIN = 0, VTIME > 0).
#[cfg(unix)]
fn raw_serial(file: &File, baud: Option<u32>) -> std::io::Result<()> {
    use rustix::termios::{ControlModes, OptionalActions, SpecialCodeIndex, tcgetattr, tcsetattr};
    let mut t = tcgetattr(file)?;
    t.make_raw();
    t.control_modes |= ControlModes::CREAD | ControlModes::CLOCAL;
    t.special_codes[SpecialCodeIndex::VMIN] = 0;
    t.special_codes[SpecialCodeIndex::VTIME] = SERIAL_READ_TIMEOUT_DS;
    if let Some(baud) = baud {
        t.set_speed(baud)?;
    }
    tcsetattr(file, OptionalActions::Now, &t)?;
    Ok(())
}

/// Whether the serial port `file` is still there: a port hung up fails
/// its terminal attributes (EIO), where a read only returns nothing.
#[cfg(unix)]
fn port_open(file: &File) -> std::io::Result<()> {
    rustix::termios::tcgetattr(file).map(drop).map_err(std::io::Error::from)
}

#[cfg(not(unix))]
fn port_open(_file: &File) -> std::io::Result<()> {
    Ok(())
}

#[cfg(not(unix))]
fn raw_serial(_file: &File, _baud: Option<u32>) -> std::io::Result<()> {
    Err(std::io::Error::new(ErrorKind::Unsupported, "serial ports are read on Unix only"))
}

/// Reads the UBX stream at `path` in its own thread: a serial port (put in
/// raw mode at `baud`) until it fails, or a file followed as it grows until
/// it shrinks (a logger that restarted writes another log), either until
/// nothing came for `idle_timeout_s` (never when 0); or a pipe ([`is_pipe`])
/// until its writer closes it.
pub(crate) fn spawn_bytes(
    tx: Sender<SourceEvent>,
    source: usize,
    path: PathBuf,
    baud: Option<u32>,
    idle_timeout_s: f64,
    clock: Arc<dyn Clock>,
) {
    std::thread::spawn(move || {
        let why = if is_pipe(&path) {
            read_pipe(&tx, source, &path)
        } else {
            read_bytes(&tx, source, &path, baud, idle_timeout_s, &*clock)
        };
        let _ = tx.send(SourceEvent::Ended { source, why });
    });
}

/// Reads the pipe `path` (standard input for [`STDIN`]) until its writer
/// closes it; why it ended, when not so.
fn read_pipe(tx: &Sender<SourceEvent>, source: usize, path: &Path) -> Option<String> {
    let mut pipe: Box<dyn Read> = if path == Path::new(STDIN) {
        Box::new(std::io::stdin().lock())
    } else {
        match File::open(path) {
            Ok(f) => Box::new(f),
            Err(e) => return Some(format!("{}: {e}", path.display())),
        }
    };
    let mut buf = vec![0u8; READ_CHUNK];
    loop {
        match pipe.read(&mut buf) {
            Ok(0) => return None,
            Ok(n) => {
                if tx.send(SourceEvent::Bytes { source, bytes: buf[..n].to_vec() }).is_err() {
                    return None;
                }
            }
            Err(e) if e.kind() == ErrorKind::Interrupted => {}
            Err(e) => return Some(format!("{}: {e}", path.display())),
        }
    }
}

/// The loop of [`spawn_bytes`]; why it ended (`None`: the receiver hung up).
fn read_bytes(
    tx: &Sender<SourceEvent>,
    source: usize,
    path: &Path,
    baud: Option<u32>,
    idle_timeout_s: f64,
    clock: &dyn Clock,
) -> Option<String> {
    let named = |e: std::io::Error| Some(format!("{}: {e}", path.display()));
    let device = is_device(path);
    let mut file = match File::open(path) {
        Ok(f) => f,
        Err(e) => return named(e),
    };
    if device && let Err(e) = raw_serial(&file, baud) {
        return Some(format!("{}: cannot set the serial port up: {e}", path.display()));
    }
    let mut buf = vec![0u8; READ_CHUNK];
    let mut offset = 0u64;
    let mut last_data = clock.now();
    loop {
        match file.read(&mut buf) {
            Ok(0) => {
                if !device {
                    match file.metadata() {
                        Ok(m) if m.len() < offset => {
                            return Some(format!(
                                "{}: the file became shorter (a logger restarted?): its new log needs a new `gsens \
                                 live`",
                                path.display()
                            ));
                        }
                        Ok(_) => {}
                        Err(e) => return named(e),
                    }
                    // At the end of what was written: read on from here at the next poll.
                    if let Err(e) = file.seek(SeekFrom::Start(offset)) {
                        return named(e);
                    }
                }
                if idle_timeout_s > 0.0 && (clock.now() - last_data).as_secs_f64() > idle_timeout_s {
                    return Some(format!("no new byte for {idle_timeout_s} s"));
                }
                if !device {
                    clock.sleep(Duration::from_millis(FOLLOW_POLL_MS));
                } else if let Err(e) = port_open(&file) {
                    // A port hung up (unplugged, its other end closed) reads nothing at once, for ever.
                    return Some(format!("{}: the port closed: {e}", path.display()));
                }
            }
            Ok(n) => {
                offset += n as u64;
                last_data = clock.now();
                if tx.send(SourceEvent::Bytes { source, bytes: buf[..n].to_vec() }).is_err() {
                    return None;
                }
            }
            Err(e) if e.kind() == ErrorKind::Interrupted => {}
            Err(e) => return named(e),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::clock::ManualClock;
    use std::io::Write;

    /// A file arrives whole, in order, in pieces of at most a read's size,
    /// and its follower ends at the idle timeout, on a clock moved by the
    /// follower's own sleeps.
    #[test]
    fn a_file_arrives_whole_and_ends_at_its_idle_timeout() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("log.ubx");
        let bytes: Vec<u8> = (0..=255u8).cycle().take(200_000).collect();
        File::create(&path).unwrap().write_all(&bytes).unwrap();
        let (tx, rx) = std::sync::mpsc::channel();
        let clock = Arc::new(ManualClock::default());
        spawn_bytes(tx, 3, path.clone(), None, 2.0, clock);
        let mut got = Vec::new();
        let why = loop {
            match rx.recv().unwrap() {
                SourceEvent::Bytes { source: 3, bytes: b } => {
                    assert!(!b.is_empty() && b.len() <= READ_CHUNK);
                    got.extend_from_slice(&b);
                }
                SourceEvent::Ended { source: 3, why } => break why,
                other => panic!("{other:?}"),
            }
        };
        assert_eq!(got, bytes);
        assert_eq!(why.as_deref(), Some("no new byte for 2 s"));
        assert!(!is_device(&path));
    }

    /// A pseudo-terminal on this machine stands in for a module's serial
    /// port: the follower sets it raw, so bytes a terminal would act on (CR,
    /// LF, Ctrl-C, Ctrl-D, XON/XOFF, DEL) arrive as sent, in order; the port
    /// closing ends the source with its error.
    #[cfg(target_os = "linux")]
    #[test]
    fn a_serial_port_is_read_raw() {
        use rustix::pty::{OpenptFlags, grantpt, openpt, ptsname, unlockpt};
        use rustix::termios::{LocalModes, tcgetattr};
        let master = openpt(OpenptFlags::RDWR | OpenptFlags::NOCTTY).unwrap();
        grantpt(&master).unwrap();
        unlockpt(&master).unwrap();
        let port = PathBuf::from(ptsname(&master, Vec::new()).unwrap().into_string().unwrap());
        assert!(is_device(&port));
        let (tx, rx) = std::sync::mpsc::channel();
        spawn_bytes(tx, 0, port, Some(115_200), 0.0, Arc::new(ManualClock::default()));
        // Sent once the follower has put the port in raw mode (no canonical input).
        while tcgetattr(&master).unwrap().local_modes.contains(LocalModes::ICANON) {
            std::thread::yield_now();
        }
        let bytes: Vec<u8> = [0xB5, 0x62, b'\r', b'\n', 0x03, 0x04, 0x11, 0x13, 0x7F, 0x1A, 0xFF]
            .iter()
            .copied()
            .cycle()
            .take(3000)
            .collect();
        let mut master = File::from(master);
        master.write_all(&bytes).unwrap();
        let mut got = Vec::new();
        while got.len() < bytes.len() {
            match rx.recv().unwrap() {
                SourceEvent::Bytes { source: 0, bytes: b } => got.extend_from_slice(&b),
                other => panic!("{other:?} after {} bytes", got.len()),
            }
        }
        assert_eq!(got, bytes);
        drop(master);
        match rx.recv().unwrap() {
            // EIO, from the read or from the port's attributes, whichever sees the hang-up first.
            SourceEvent::Ended { source: 0, why: Some(why) } => assert!(why.starts_with("/dev/pts/"), "{why}"),
            other => panic!("{other:?}"),
        }
    }

    /// A named pipe is read until its writer closes it, every byte in order.
    #[cfg(unix)]
    #[test]
    fn a_named_pipe_is_read_until_its_writer_closes_it() {
        let dir = tempfile::tempdir().unwrap();
        let fifo = dir.path().join("ubx.fifo");
        rustix::fs::mkfifoat(rustix::fs::CWD, &fifo, rustix::fs::Mode::RUSR | rustix::fs::Mode::WUSR).unwrap();
        assert!(is_pipe(&fifo) && !is_device(&fifo) && is_pipe(Path::new(STDIN)));
        let (tx, rx) = std::sync::mpsc::channel();
        spawn_bytes(tx, 1, fifo.clone(), None, 0.0, Arc::new(ManualClock::default()));
        let bytes: Vec<u8> = (0..=255u8).cycle().take(300_000).collect();
        // Opening for writing waits for the reader: the follower has opened it.
        File::options().write(true).open(&fifo).unwrap().write_all(&bytes).unwrap();
        let mut got = Vec::new();
        loop {
            match rx.recv().unwrap() {
                SourceEvent::Bytes { source: 1, bytes: b } => got.extend_from_slice(&b),
                SourceEvent::Ended { source: 1, why: None } => break,
                other => panic!("{other:?}"),
            }
        }
        assert_eq!(got, bytes);
    }
}
