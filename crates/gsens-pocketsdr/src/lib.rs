//! # gsens-pocketsdr
//!
//! Interoperability with PocketSDR (T. Takasu's open-source software
//! receiver), its tracking program `pocket_trk`:
//!
//! - [`log`]: the log `pocket_trk -log FILE` writes — its `$CH` lines (one
//!   per tracked channel every `epoch` seconds), the other `$` messages
//!   counted, merged or garbled lines reported with their line and field;
//! - [`options`]: its options file (`-opt FILE`, `key = value`): `b_pll`
//!   (the carrier loop's bandwidth) and `epoch` (the log interval);
//! - [`import`]: `$CH` lines → the `tracking.csv` schema (φ in rad, time at
//!   the middle of the logged 1 ms integration, on the IF file's sample time),
//!   cut into tracks, the FLL pull-in and the PLL's settling dropped, every
//!   track reported with what became of it;
//! - [`calibrate_pocketsdr`]: the estimate from a log and an IMU log with
//!   PocketSDR's own loop modelled exactly ([`gsens_core::pocket_sdr`]),
//!   tested rather than fitted.
#![deny(missing_docs)]

pub mod error;
pub mod import;
pub mod log;
pub mod options;
mod pipeline;

pub use error::PocketSdrError;
pub use import::{ImportSettings, Imported, TrackSummary, import_file, import_log, render_summary};
pub use log::{ChRecord, Garbled, PocketSdrLog, parse_log, read_log};
pub use options::{PocketSdrOptions, Setting, SettingSource};
pub use pipeline::{PocketSdrOutcome, calibrate_pocketsdr, pocketsdr_tracking_log};
