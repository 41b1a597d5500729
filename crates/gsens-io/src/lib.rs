//! Log formats of gsens: readers and writers of `imu.csv` and `tracking.csv`
//! (formats in `shared/conventions.md`, section "Log files"), and the assembly
//! of the estimator's inputs from them (epoch grid, channel selection and
//! averaging, IMU interpolation).
//!
//! Every reader streams its input (`impl Read`) and reports problems as a
//! [`FormatError`] naming the source, the line and the column.
//!
//! ```
//! use gsens_io::{read_imu, read_tracking, prepare_session, SelectionConfig};
//!
//! let imu = "t_s,fx_mps2,fy_mps2,fz_mps2\n0,0,0,9.81\n0.025,0.1,0,9.81\n0.05,0.2,0,9.81\n";
//! let trk = "t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad\n\
//!            0,1,5,45,30,0.01\n0.025,1,5,45,30,0.02\n0.05,1,5,45,,0.03\n";
//! let imu = read_imu(imu.as_bytes(), "imu.csv")?;
//! let trk = read_tracking(trk.as_bytes(), "tracking.csv")?;
//! let s = prepare_session(&trk, &imu, "imu.csv", &SelectionConfig::default(), 0.0)?;
//! assert_eq!(s.t_s.len(), 3);
//! assert_eq!(s.accel_mps2[1], [0.1, 0.0, 9.81]);
//! assert_eq!(s.phase_err_rad[2], Some(0.03));
//! # Ok::<(), gsens_io::FormatError>(())
//! ```
#![deny(missing_docs)]

pub mod error;
pub mod imu;
mod parse;
pub mod screening;
pub mod session;
pub mod tracking;
pub mod writers;

pub use error::{Column, FormatError};
pub use imu::{IMU_COLUMNS, ImuSeries, read_imu, read_imu_file};
pub use screening::{ExcludedSpan, ScreeningConfig, TrackScreening};
pub use session::{
    ChannelSummary, PreparedSession, SelectionConfig, Weighting, prepare_session, prepare_session_files,
    reinterpolate_imu,
};
pub use tracking::{ChannelTrack, TRACKING_COLUMNS, TrackingLog, read_tracking, read_tracking_file};
pub use writers::{ImuWriter, TrackingRow, TrackingWriter, write_imu_csv};
