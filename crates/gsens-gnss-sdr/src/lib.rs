//! # gsens-gnss-sdr
//!
//! Interoperability with GNSS-SDR (<https://gnss-sdr.org>), the open-source
//! software receiver:
//!
//! - [`conf`]: its configuration files — the carrier-loop settings that
//!   produced a dump, and a configuration that tracks `gsens simulate --iq`
//!   files;
//! - [`dump`]: its tracking dumps (`Tracking_1C.dump=true`, `trk_ch_N.dat`),
//!   every record layout from 0.0.17 to 0.0.21 (and the Kalman, FPGA, GLONASS,
//!   GPU and TCP blocks), recognised from the file itself, with errors that
//!   name the file, record and byte offset;
//! - [`mat`]: the `.mat` copies of the dumps (MATLAB v7.3 = HDF5,
//!   `dump_mat=true`), read by a built-in reader of the part of HDF5 they use
//!   to exactly the records of the `.dat`;
//! - [`import`]: dumps → the `tracking.csv` schema (φ in rad, time at the
//!   middle of each integration), each track judged by GNSS-SDR's own lock
//!   detector replayed with the configuration's settings, with a reason;
//! - [`calibrate`]: the estimate from the dumps with GNSS-SDR's own loop
//!   modelled exactly (the adapter between these files and `gsens_calib`);
//! - [`monitor`]: its tracking monitor (`TrackingMonitor.enable_monitor`),
//!   protobuf over UDP, received live and converted to the same rows;
//! - the exact models of its carrier loops live in
//!   [`gsens_core::gnss_sdr`] (no_std, shared with the estimator).
#![deny(missing_docs)]

pub mod calibrate;
pub mod conf;
pub mod dump;
pub mod error;
mod export;
pub mod import;
pub mod mat;
pub mod monitor;

pub use calibrate::{Conversion, GnssSdrOutcome, calibrate_gnss_sdr, gnss_sdr_tracking_log, with_gnss_sdr_loop};
pub use conf::{GnssSdrConf, IqConfOptions, TrackingConf, write_iq_conf};
pub use dump::{DumpLayout, TrackingDump, TrackingRecord, find_dumps, parse_dump, read_dump};
pub use error::{GnssSdrError, LayoutSpecError};
pub use import::{ImportSettings, Imported, TrackFate, import_dir, import_dump, render_tracks, resample};
