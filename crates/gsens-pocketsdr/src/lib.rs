//! # gsens-pocketsdr
//!
//! Interoperability with PocketSDR (T. Takasu's open-source software
//! receiver), its tracking program `pocket_trk`:
//!
//! - `log`: the log `pocket_trk -log FILE` writes — its `$CH` lines (one
//!   per tracked channel every `epoch` seconds), the other `$` messages
//!   counted, merged or garbled lines reported with their line and field;
//! - `options`: its options file (`-opt FILE`, `key = value`): `b_pll`
//!   (the carrier loop's bandwidth) and `epoch` (the log interval);
//! - `import`: `$CH` lines → the `tracking.csv` schema (φ in rad, time at
//!   the middle of the logged 1 ms integration, on the IF file's sample time),
//!   cut into tracks, the FLL pull-in and the PLL's settling dropped, every
//!   track reported with what became of it;
//! - [`calibrate_pocketsdr`]: the estimate from a log and an IMU log with
//!   PocketSDR's own loop modelled exactly ([`gsens_core::pocket_sdr`]),
//!   tested rather than fitted.
//!
//! # The log
//!
//! The log of `pocket_trk -log FILE` (PocketSDR 0.17).
//!
//! One message per line, comma-separated, each starting with its type:
//! `$CH` (a tracked channel, every `epoch` seconds), `$LOG` (events: start,
//! signal found or lost, stop), `$TIME`, `$POS`, `$OBS`, `$SAT`, `$EPH`, … .
//! Only `$CH` is read; the others are counted. Its fields (1-based after the
//! type, as PocketSDR's `out_log_ch` writes them):
//!
//! ```text
//! 1 time [s]   2 ch   3 rfch   4 sat   5 sig   6 prn   7 lock [s]   8 cn0 [dB-Hz]   9 coff [ms]
//! 10 dop [Hz]   11 adr [cyc]   12 ssync   13 bsync   14 fsync   15 rev   16 srev
//! 17 err_phas [cyc]   18 err_code [µs]   19 tow_v   20 tow [ms]   21 week   22 type
//! 23 nnav   24 nerr   25 nlol   26 nfec
//! ```
//!
//! `time` is the receiver time of the start of the 1 ms block the channel
//! last processed (its cycle counter × 1 ms, 3 decimals), `lock` the time
//! since acquisition, `err_phas` the Costas discriminator atan(Q/I)/2π of that
//! single block (3 decimals: 1e-3 cycle steps), `nlol` the channel's count of
//! losses of lock.
//!
//! Real logs are not always clean: a line may be cut (the receiver was
//! stopped while writing), two messages may share a line (interleaved
//! writes), bytes may be damaged. A `$CH` line with another number of fields
//! than the log's (the most common among its `$CH` lines), a second `$`, or a
//! field that does not read as its type is *garbled*: it is skipped and
//! reported ([`Garbled`]: line, field, reason), never guessed at.
//!
//! # The options file
//!
//! `pocket_trk`'s options file (`-opt FILE`; PocketSDR's
//! `app/pocket_trk/pocket_trk_default.conf` is one).
//!
//! One `key = value` per line; `#` starts a comment; blank lines are
//! skipped. `pocket_trk` reads every value as a number and ignores lines
//! without `=` and unknown keys (with a message on its standard error); the
//! last of repeated keys wins. Of its keys, the carrier loop gsens models
//! depends on `b_pll` (the PLL's noise bandwidth, 5 Hz by default, PocketSDR's
//! `B_PLL`), and the log on `epoch` (the `$CH` interval, 1 s by default).
//! The FLL's `b_fll_w`/`b_fll_n` only act during the first second of a
//! track, which is not used. A value gsens needs that does not read as a
//! number is an error naming the file, line and key (where `pocket_trk`
//! would have read 0 or a prefix); other keys are kept as text.
//!
//! # From `$CH` lines to tracking rows
//!
//! `pocket_trk` `$CH` lines → gsens's tracking schema
//! (`t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad`, docs/conventions.md).
//!
//! ## Time base
//!
//! `pocket_trk` reads the IF file in cycles of N = fs·1 ms samples (fs a
//! multiple of 1 kHz; `-toff` seconds skipped at the start) and updates each
//! L1 C/A channel once per cycle, with the block of samples that starts at
//! cycle k, receiver time k·1 ms. A `$CH` line at `time` = k·1 ms reports
//! the discriminator output of that single block, whose integration spans
//! \[k·T, (k + 1)·T), T = 1 ms. The IMU log `gsens simulate --iq` writes and
//! the IF file share one clock: sample n of the file is at receiver time
//! n/fs. So each row is stamped at the middle of its integration on the
//! file's sample time:
//!
//! ```text
//! t_s = time + T/2 + toff
//! ```
//!
//! (what `gsens-gnss-sdr` does with GNSS-SDR's sample counter: (n − Δn/2)/fs).
//! Every channel logs at the same cycles (`epoch` apart), so all rows of an
//! epoch share one stamp and no resampling is needed. Until it has decoded
//! the navigation data, `pocket_trk` logs at the cycles that are multiples of
//! `epoch`; afterwards at its PVT epochs, which start on a multiple of 20 ms
//! (and may be moved by multiples of 20 ms to follow the clock). With an
//! `epoch` that divides 0.02 s the two grids coincide; otherwise (0.025 s) the
//! grid moves mid-log, and the lines off the grid of most lines are reported
//! and not used (the tracking schema holds one grid).
//!
//! ## Phase and sign
//!
//! `phase_err_rad` = 2π·`err_phas`: PocketSDR mixes the samples with the
//! conjugate replica, so atan(Q/I) is θ_signal − θ_replica, the sign of
//! docs/conventions.md (checked on real runs: the model of
//! [`gsens_core::pocket_sdr`] driven by the true carrier leaves the thermal
//! noise with this sign, twice as much with the other). With `-fmt CS8` for
//! gsens's interleaved int8 I/Q the receiver's Doppler is the simulator's;
//! `INT8X2` inverts Q (mirrored spectrum, flipped signs).
//!
//! ## Tracks and what is kept
//!
//! A channel's lines form a *track* (one satellite tracked without
//! interruption) until its PRN or signal changes, its lock time falls (it was
//! lost and reacquired: `pocket_trk` writes no line for a channel it does
//! not track) or a line is missing (a gap over 1.5 epochs). Its lines with a
//! lock time up to the FLL pull-in (1 s) plus the PLL's settling time
//! ([`ImportSettings::settle_time_s`]) are dropped: PocketSDR runs an FLL for
//! the first second, and the PLL's start is a transient the estimator does
//! not model. Only GPS L1 C/A (`L1CA`) is estimated; other signals are
//! counted and skipped. Every track is reported with what became of it.
#![deny(missing_docs)]

mod error;
mod export;
mod import;
mod log;
mod options;
mod pipeline;

pub use error::PocketSdrError;
pub use export::Export;
pub use import::{ImportOptions, ImportSettings, Imported, TrackSummary, import_file, import_log, render_summary};
pub use log::{ChRecord, Garbled, PocketSdrLog, parse_log, read_log};
pub use options::{PocketSdrOptions, Setting, SettingSource};
pub use pipeline::{PocketSdrOutcome, calibrate_pocketsdr, pocketsdr_tracking_log};
