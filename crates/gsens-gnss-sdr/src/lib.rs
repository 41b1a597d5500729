//! # gsens-gnss-sdr
//!
//! Interoperability with GNSS-SDR (<https://gnss-sdr.org>), the open-source
//! software receiver:
//!
//! - [`conf`]: its configuration files — the carrier-loop settings that
//!   produced a dump, and a configuration that tracks `gsens simulate --iq`
//!   files;
//! - [`dump`]: its tracking dumps (`Tracking_1C.dump=true`, `trk_ch_N.dat`),
//!   version-aware, with errors that name the file, record and byte offset;
//! - [`import`]: dumps → the `tracking.csv` schema (φ in rad, time at the
//!   middle of each integration), each track judged by GNSS-SDR's own lock
//!   detector replayed with the configuration's settings, with a reason;
//! - the exact models of its carrier loops live in
//!   [`gsens_core::gnss_sdr`] (no_std, shared with the estimator).
#![deny(missing_docs)]

pub mod conf;
pub mod dump;
pub mod error;
pub mod import;

pub use conf::{GnssSdrConf, TrackingConf};
pub use dump::{DumpLayout, TrackingDump, TrackingRecord, find_dumps, parse_dump, read_dump};
pub use error::{GnssSdrError, LayoutSpecError};
pub use import::{ImportSettings, Imported, import_dir, resample};
