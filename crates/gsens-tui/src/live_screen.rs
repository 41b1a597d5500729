//! The terminal as the screen a live session runs on
//! ([`gsens_live::LiveScreen`]): each view drawn, a quit key looked for
//! without waiting.

use crate::terminal::{Terminal, poll_quit};
use gsens_live::{LiveScreen, LiveView};
use std::time::Duration;

impl LiveScreen for Terminal {
    fn draw(&mut self, view: &LiveView) -> std::io::Result<()> {
        Terminal::draw(self, view)
    }

    fn quit_asked(&mut self) -> std::io::Result<bool> {
        poll_quit(Duration::ZERO)
    }
}
