//! Log formats of gsens: readers and writers of `imu.csv` and `tracking.csv`
//! (formats in `docs/conventions.md`, section "Log files") and the logs they
//! hold in memory ([`ImuSeries`], [`TrackingLog`]).
//!
//! Every reader streams its input (`impl Read`) and reports problems as a
//! [`FormatError`] naming the source, the line and the column. The writers
//! print the shortest decimal that reads back to the same value and refuse
//! non-finite numbers.
//!
//! Turning the logs into the estimator's inputs (epoch grid, channel selection
//! and screening, averaging, IMU interpolation) is the job of `gsens-session`.
//!
//! ```
//! use gsens_io::{TrackingRow, TrackingWriter, read_imu, read_tracking};
//!
//! let imu = "t_s,fx_mps2,fy_mps2,fz_mps2\n0,0,0,9.81\n0.025,0.1,0,9.81\n";
//! let imu = read_imu(imu.as_bytes(), "imu.csv")?;
//! assert_eq!(imu.accel_mps2[1], [0.1, 0.0, 9.81]);
//!
//! let mut w = TrackingWriter::new(Vec::new())?;
//! let row = TrackingRow { t_s: 0.0, channel: 1, prn: 5, cn0_dbhz: 45.0, elev_deg: None, phase_err_rad: 0.01 };
//! w.write_row(&row)?;
//! let text = w.finish()?;
//! assert_eq!(text, b"t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad\n0,1,5,45,,0.01\n");
//! let log = read_tracking(text.as_slice(), "tracking.csv")?;
//! assert_eq!(log.tracks()[0].phase_err_rad, [0.01]);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![deny(missing_docs)]

pub mod config;
pub mod error;
pub mod imu;
pub mod output;
mod parse;
mod plain;
pub mod row;
pub mod signal;
#[cfg(test)]
mod test_files;
pub mod tracking;
pub mod vibration;
pub mod writers;

pub use config::{MAX_CONFIG_BYTES, read_config_text};
pub use error::{Column, FormatError};
pub use imu::{IMU_COLUMNS, ImuSeries, read_imu, read_imu_file};
pub use output::{OutputPathError, check_output_dir, check_output_file, check_output_file_in};
pub use row::{RowError, parse_imu_row, parse_tracking_row};
pub use signal::{Carrier, GNSS_BAND_HZ, SIGNALS, Signal, SignalError, SignalSpec};
pub use tracking::{CARRIER_COLUMNS, ChannelTrack, TRACKING_COLUMNS, TrackingLog, read_tracking, read_tracking_file};
pub use vibration::{VIBRATION_COLUMNS, read_vibration_psd, read_vibration_psd_file};
pub use writers::{
    EPOCH_COLUMNS, ImuWriter, TrackingRow, TrackingWriter, write_epochs_csv, write_imu_csv, write_tracking_csv,
    write_tracking_csv_on,
};
