//! The terminal screen of `gsens live`.
//!
//! - [`draw`]: one screen of a [`gsens_live::LiveView`] for the person
//!   holding the board: the instruction at the top, then per axis the time
//!   shaken, Γ̂ ± σ and the progress toward the target σ, the shaking now
//!   against the loop's band and the discriminator's range, the channels,
//!   the trust of the latest batch estimate, the notices and the counts
//!   received. Sections that do not fit a small terminal are left out, the
//!   least needed first; nothing panics on any size.
//! - [`Terminal`]: the real terminal (crossterm: raw mode, alternate
//!   screen), restored when it is dropped and when the program panics;
//!   [`poll_quit`] waits for `q`, Esc or Ctrl-C; it is the
//!   [`gsens_live::LiveScreen`] a live session runs on.
//! - [`render_text`]: the screen drawn into a text buffer of a given size
//!   (ratatui's `TestBackend`), for snapshot tests and documentation.
//! - [`progress`]: the bars and spinners of the other commands' long steps,
//!   the calibration pipeline's stages among them ([`progress::observed`]).
//! - [`process`]: a command-line program's process: standard output that
//!   ends quietly on a closed pipe, standard error that never panics, a
//!   command's exit status, the allocator's setup.
#![warn(missing_docs)]

mod live_screen;
pub mod process;
pub mod progress;
mod screen;
mod terminal;

pub use screen::{draw, phase_gauge_is_red, progress_to_target, render_text};
pub use terminal::{Terminal, is_quit_key, poll_quit, restore};

/// The ratatui this crate draws with (for callers that draw around it).
pub use ratatui;

/// The crossterm this crate reads keys with.
pub use crossterm;
