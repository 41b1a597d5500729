//! The real terminal: raw mode and the alternate screen while the session
//! runs, the user's terminal back afterwards, even after a panic.

use std::io::{self, Stdout};
use std::sync::Once;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use crossterm::event::{self, Event, KeyCode, KeyEvent, KeyEventKind, KeyModifiers};
use crossterm::terminal::{EnterAlternateScreen, LeaveAlternateScreen, disable_raw_mode, enable_raw_mode};
use crossterm::{cursor, execute};
use ratatui::backend::CrosstermBackend;

use gsens_live::LiveView;

/// Whether the terminal is in raw mode on the alternate screen (set by
/// [`Terminal::new`], cleared by [`restore`]), so that restoring twice (the
/// panic hook, then the drop while unwinding) writes nothing the second time.
static ACTIVE: AtomicBool = AtomicBool::new(false);

/// The panic hook is chained once per process, however many terminals are made.
static PANIC_HOOK: Once = Once::new();

/// The terminal `gsens live` draws on: raw mode (keys arrive one by one,
/// unechoed) on the alternate screen (the user's scrollback is left
/// untouched). Dropping it restores the terminal; so does a panic, before
/// the panic's message is printed, so that the message is readable.
pub struct Terminal {
    inner: ratatui::Terminal<CrosstermBackend<Stdout>>,
}

impl Terminal {
    /// Enters raw mode and the alternate screen, hides the cursor and
    /// installs the panic hook that restores them. On an error the terminal
    /// is restored before it is returned.
    pub fn new() -> io::Result<Self> {
        PANIC_HOOK.call_once(|| {
            let previous = std::panic::take_hook();
            std::panic::set_hook(Box::new(move |info| {
                let _ = restore();
                previous(info);
            }));
        });
        let setup = || -> io::Result<Self> {
            enable_raw_mode()?;
            ACTIVE.store(true, Ordering::SeqCst);
            let mut stdout = io::stdout();
            execute!(stdout, EnterAlternateScreen, cursor::Hide)?;
            let mut inner = ratatui::Terminal::new(CrosstermBackend::new(stdout))?;
            inner.clear()?;
            Ok(Terminal { inner })
        };
        setup().inspect_err(|_| {
            let _ = restore();
        })
    }

    /// Draws `view` (see [`crate::draw`]); only the cells that changed are written.
    pub fn draw(&mut self, view: &LiveView) -> io::Result<()> {
        self.inner.draw(|frame| crate::draw(frame, view)).map(|_| ())
    }

    /// The ratatui terminal, to draw something else on it.
    pub fn ratatui(&mut self) -> &mut ratatui::Terminal<CrosstermBackend<Stdout>> {
        &mut self.inner
    }
}

impl Drop for Terminal {
    fn drop(&mut self) {
        let _ = restore();
    }
}

/// Leaves the alternate screen, shows the cursor and leaves raw mode, if
/// [`Terminal::new`] set them up and they have not been restored since (a
/// no-op otherwise). [`Terminal`] calls it on drop and on panic.
pub fn restore() -> io::Result<()> {
    if !ACTIVE.swap(false, Ordering::SeqCst) {
        return Ok(());
    }
    let screen = execute!(io::stdout(), LeaveAlternateScreen, cursor::Show);
    let raw = disable_raw_mode();
    screen.and(raw)
}

/// Whether `key` ends the session: `q`, Esc or Ctrl-C (raw mode turns
/// Ctrl-C into a key, not a signal). Key releases and repeats do not count.
pub fn is_quit_key(key: &KeyEvent) -> bool {
    if key.kind != KeyEventKind::Press {
        return false;
    }
    match key.code {
        KeyCode::Char('q') | KeyCode::Esc => true,
        KeyCode::Char('c') | KeyCode::Char('C') => key.modifiers.contains(KeyModifiers::CONTROL),
        _ => false,
    }
}

/// Waits up to `timeout` for terminal events, then takes every event
/// already waiting (keys typed meanwhile do not queue up), and answers
/// whether one was a quit key ([`is_quit_key`]). Returns `false` at the
/// timeout and on other events (a resize: the caller redraws anyway).
pub fn poll_quit(timeout: Duration) -> io::Result<bool> {
    let mut quit = false;
    let mut wait = timeout;
    while event::poll(wait)? {
        if let Event::Key(key) = event::read()? {
            quit |= is_quit_key(&key);
        }
        wait = Duration::ZERO;
    }
    Ok(quit)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn q_esc_and_ctrl_c_quit_other_keys_do_not() {
        let press = |code, modifiers| KeyEvent::new(code, modifiers);
        assert!(is_quit_key(&press(KeyCode::Char('q'), KeyModifiers::NONE)));
        assert!(is_quit_key(&press(KeyCode::Esc, KeyModifiers::NONE)));
        assert!(is_quit_key(&press(KeyCode::Char('c'), KeyModifiers::CONTROL)));
        assert!(!is_quit_key(&press(KeyCode::Char('c'), KeyModifiers::NONE)));
        assert!(!is_quit_key(&press(KeyCode::Char('x'), KeyModifiers::NONE)));
        assert!(!is_quit_key(&press(KeyCode::Enter, KeyModifiers::NONE)));
        let mut release = press(KeyCode::Char('q'), KeyModifiers::NONE);
        release.kind = KeyEventKind::Release;
        assert!(!is_quit_key(&release));
    }

    #[test]
    fn restore_without_a_terminal_is_a_no_op() {
        // Not set up: nothing is written to stdout (the test harness's), no error.
        assert!(restore().is_ok());
    }
}
