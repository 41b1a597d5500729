//! The process a command-line program runs in: its standard output and
//! standard error, how a command's end becomes the exit status
//! ([`run`]), and its allocator's setup.
//!
//! Output goes to a pipe as often as to a terminal (`gsens response | head`):
//! a closed pipe is the reader having read enough, so it ends the process
//! quietly with status 0 instead of an error (or, with `println!`, a panic).

use std::error::Error;
use std::fmt::Display;
use std::io::{ErrorKind, Write};
use std::process::ExitCode;

/// How a command ended when it did not fail; each is an exit status
/// ([`Status::exit_code`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Status {
    /// Done; any estimate is trustworthy: exit status 0.
    Done,
    /// An estimate was produced (and every file written) but it is not
    /// trustworthy: exit status 3.
    Untrustworthy,
    /// A live session ended (input ended, a key, the idle timeout) before
    /// every axis met the target σ; the estimate is trustworthy: exit
    /// status 4.
    TargetMissed,
}

/// The exit status of a command that failed: 2.
pub const FAILED: u8 = 2;

impl Status {
    /// The status of a result document: [`Status::Untrustworthy`] unless it
    /// is trustworthy.
    pub fn of(doc: &gsens_calib::ResultDocument) -> Self {
        if doc.trustworthy { Status::Done } else { Status::Untrustworthy }
    }

    /// The process's exit status: 0, 3 or 4.
    pub fn exit_code(self) -> u8 {
        match self {
            Status::Done => 0,
            Status::Untrustworthy => 3,
            Status::TargetMissed => 4,
        }
    }
}

/// Runs `command` as the process's work and returns its exit code
/// ([`exit_code`]): the allocator is set up first, before any thread
/// starts ([`one_malloc_arena`]).
pub fn run<E>(command: impl FnOnce() -> Result<Status, E>) -> ExitCode
where
    E: Display + AsRef<dyn Error + Send + Sync + 'static>,
{
    one_malloc_arena();
    exit_code(command())
}

/// glibc's malloc gives each thread that allocates an arena of its own and
/// keeps what is freed in it for that thread: the estimate's stages allocate
/// large buffers on several threads in turn, so with an arena per thread the
/// freed buffers of one thread's stage are not reused by another's and the peak RSS
/// of a 1-hour log grows by some 25 MB over its largest live heap (and every
/// fresh page is a page fault). One arena for the process: its few large
/// allocations do not contend for the lock (BENCHMARKS.md). To be called
/// before any thread starts.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
pub fn one_malloc_arena() {
    // SAFETY: mallopt only sets a malloc parameter; called before any thread starts.
    unsafe {
        libc::mallopt(libc::M_ARENA_MAX, 1);
    }
}

/// Elsewhere the allocator is left as it is.
#[cfg(not(all(target_os = "linux", target_env = "gnu")))]
pub fn one_malloc_arena() {}

/// The exit code of a command's `result`: its status's, or for an error
/// [`FAILED`] after writing `error: ` and the error with its causes
/// (`{:#}`) to standard error. An error that is a closed pipe is the
/// reader having read enough: status 0, nothing written.
pub fn exit_code<E>(result: Result<Status, E>) -> ExitCode
where
    E: Display + AsRef<dyn Error + Send + Sync + 'static>,
{
    let (code, message) = ending(result);
    if let Some(message) = message {
        err(&message);
    }
    ExitCode::from(code)
}

/// The exit status of a command's `result` and what standard error says
/// of it ([`exit_code`]).
fn ending<E>(result: Result<Status, E>) -> (u8, Option<String>)
where
    E: Display + AsRef<dyn Error + Send + Sync + 'static>,
{
    match result {
        Ok(status) => (status.exit_code(), None),
        Err(e) if is_broken_pipe(e.as_ref()) => (0, None),
        Err(e) => (FAILED, Some(format!("error: {e:#}\n"))),
    }
}

/// Whether `e` is an I/O error of a closed pipe.
fn is_broken_pipe(e: &(dyn Error + Send + Sync + 'static)) -> bool {
    e.downcast_ref::<std::io::Error>().is_some_and(|e| e.kind() == ErrorKind::BrokenPipe)
}

/// Writes `text` to standard output; a closed pipe ends the process
/// quietly (status 0).
pub fn out(text: &str) -> std::io::Result<()> {
    out_bytes(text.as_bytes())
}

/// [`out`] as a callback, for a library that tells as it goes.
pub fn say(text: &str) -> std::io::Result<()> {
    out(text)
}

/// [`out`] of bytes.
pub fn out_bytes(bytes: &[u8]) -> std::io::Result<()> {
    match std::io::stdout().lock().write_all(bytes) {
        Err(e) if e.kind() == ErrorKind::BrokenPipe => std::process::exit(0),
        r => r,
    }
}

/// Writes `text` to standard error; a closed pipe (`gsens live 2>&1 | head`)
/// or any other failure to write is ignored (unlike `eprintln!`, which
/// panics).
pub fn err(text: &str) {
    let _ = std::io::stderr().lock().write_all(text.as_bytes());
}

/// Standard output as a [`Write`] that writes with [`out_bytes`] (a closed
/// pipe ends the process quietly): what a live session's plain lines are
/// written to.
pub struct Stdout;

impl Write for Stdout {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        out_bytes(buf)?;
        Ok(buf.len())
    }

    fn flush(&mut self) -> std::io::Result<()> {
        std::io::stdout().flush()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An error type as a command returns it (a boxed error with its chain).
    struct Failure(Box<dyn Error + Send + Sync>);

    impl Display for Failure {
        fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            self.0.fmt(f)
        }
    }

    impl AsRef<dyn Error + Send + Sync + 'static> for Failure {
        fn as_ref(&self) -> &(dyn Error + Send + Sync + 'static) {
            self.0.as_ref()
        }
    }

    /// The statuses are the documented exit codes of `gsens` (README:
    /// 0 done, 2 failed, 3 untrustworthy, 4 target missed).
    #[test]
    fn statuses_are_the_documented_exit_codes() {
        assert_eq!(Status::Done.exit_code(), 0);
        assert_eq!(Status::Untrustworthy.exit_code(), 3);
        assert_eq!(Status::TargetMissed.exit_code(), 4);
        assert_eq!(FAILED, 2);
        assert_eq!(exit_code::<Failure>(Ok(Status::TargetMissed)), ExitCode::from(4));
    }

    #[test]
    fn a_failure_exits_2_and_a_closed_pipe_0() {
        let failed = Failure("no such file".into());
        assert_eq!(ending::<Failure>(Err(failed)), (2, Some("error: no such file\n".into())));
        let pipe = Failure(Box::new(std::io::Error::from(ErrorKind::BrokenPipe)));
        assert_eq!(ending::<Failure>(Err(pipe)), (0, None));
        assert_eq!(ending::<Failure>(Ok(Status::Untrustworthy)), (3, None));
    }
}
