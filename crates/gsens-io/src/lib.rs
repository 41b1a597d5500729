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
//!
//! # `tracking.csv` in memory
//!
//! Reader of `tracking.csv`: one row per channel per epoch (long format), header
//! `t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad`, optionally with the
//! carrier of each row in `signal`, `glo_k` and `carrier_hz` ([`CARRIER_COLUMNS`]).
//!
//! The columns may come in any order and extra columns are ignored, but the six
//! must all be present. Where they are is read off the header
//! ([`TrackingColumns`]); the file reader parses each row by that map, and
//! [`TrackingColumns::parse_row`] parses one line by the same row parser for
//! logs read a line at a time (a row with its optional columns: [`TrackingRecord`]). `elev_deg` may be empty (unknown elevation); every other
//! cell must hold a finite number (`channel` and `prn`: non-negative integers).
//! Channels may appear, disappear and reappear.
//!
//! Time stamps must be non-decreasing over the file (the rows of one epoch share
//! one `t_s`) and strictly increasing per channel (a channel appears at most once
//! per epoch).
//!
//! The log is read as a stream and stored column-wise per track, a track being
//! one (channel, PRN) pair: a channel that is re-assigned to another satellite
//! starts a new track.
//!
//! # Carrier
//!
//! Without any of the carrier columns every row is on GPS L1 (1575.42 MHz,
//! [`Carrier::GPS_L1`]), as before they existed. With them, each row's carrier
//! comes from
//!
//! - `signal`: a name of [`crate::SIGNALS`] (`L1CA`, `E1B`, `B1I`, `L5Q`, `G1`, …;
//!   case-sensitive); an unknown name is an error listing the known ones;
//! - `glo_k`: the GLONASS frequency channel number k (−7…+6) of a `G1`/`G2` row
//!   (f = 1602 MHz + k·0.5625 MHz, 1246 MHz + k·0.4375 MHz), empty for the others;
//! - `carrier_hz`: the carrier in Hz, within the GNSS bands 1.1–1.7 GHz. With a
//!   `signal` it must agree with the signal's carrier within 1 Hz (and gives the k
//!   of a `G1`/`G2` row without `glo_k`); alone (empty `signal` cell or no
//!   `signal` column) it is the carrier of an unnamed signal.
//!
//! A row whose carrier cells are all empty is an error (no row is silently put on
//! L1 in a log that names carriers). A track keeps one carrier: a row that puts
//! a (channel, PRN) pair on another carrier is an error naming both lines (a
//! receiver that moves a channel to another signal changes its PRN or channel
//! number, which starts a new track).
//!
//! # NCO
//!
//! Two more optional columns say where the loop put its replica, so that the
//! phase the loop was fed is known with no model of the loop
//! (θ_in = θ_NCO + φ, docs/conventions.md):
//!
//! - `nco_phase_cycles`: the replica's accumulated carrier phase at the end of
//!   the row's latest integration \[cycles\], with the sign of φ = θ_signal −
//!   θ_replica (θ_replica = 2π·`nco_phase_cycles`);
//! - `nco_freq_hz`: the frequency the NCO was commanded during that
//!   integration \[Hz\].
//!
//! Either may come alone ([`NCO_COLUMNS`]); where a column is present every row
//! must hold a finite number in it. Each track keeps them in
//! [`ChannelTrack::nco_phase_cycles`] and [`ChannelTrack::nco_freq_hz`] (empty
//! without the column).
//!
//! # Signals and carriers
//!
//! The GNSS signals gsens knows and their carriers: the one table
//! ([`SIGNALS`]) that the tracking log's `signal` column, the session's
//! scaling and the simulator's channels read.
//!
//! Carrier frequencies from the interface documents: GPS IS-GPS-200 (L1
//! 1575.42 MHz, L2 1227.60 MHz) and IS-GPS-705 (L5 1176.45 MHz); Galileo OS
//! SIS ICD (E1 1575.42, E5a 1176.45, E5b 1207.14 MHz); BeiDou ICDs (B1I
//! 1561.098, B1C 1575.42, B2a 1176.45, B3I 1268.52 MHz); GLONASS ICD 5.1
//! (FDMA: G1 f = 1602 MHz + k·0.5625 MHz, G2 f = 1246 MHz + k·0.4375 MHz,
//! frequency channel number k = −7 … +6).
//!
//! The oscillator's fractional frequency error y moves every carrier by
//! Δf_c = f_c·y, so one loop on f_c sees (f_c/f_L1) times the phase error of
//! the same loop on L1: [`Carrier::scale_to_l1`] = f_L1/f_c brings it onto
//! L1's scale (docs/conventions.md, "Tracking log").
//!
//! # Carrier phase and Doppler logs
//!
//! Receivers that log no tracking error but their measurements (RINEX
//! observation files, u-blox UBX RXM-RAWX) are read into one type,
//! [`ObservationLog`]: one [`SatelliteSeries`] per signal of each satellite
//! (pseudorange, carrier phase, Doppler, C/N0, [`obs_flags`], and the
//! format's signal strength or lock time), with what the reader skipped
//! ([`Skipped`], by reason) and the receiver clock jumps it saw
//! ([`ClockEvent`]). The readers themselves are the receiver crates'
//! (`gsens-rinex`, `gsens-ublox`); they build the log with
//! [`ObservationLogBuilder`].
//!
//! Time: every `t_s` is GPS time in seconds since the start of the GPS week
//! of the log's first epoch ([`ObservationLog::gps_week`]), continuing past
//! the week's end: t = (week − first week)·604800 s + time of week.
//!
//! The observables are kept as the file states them, in its units and with
//! its signs (docs/conventions.md, "Carrier phase and Doppler logs"):
//!
//! - Doppler \[Hz\], positive for an approaching satellite (RINEX 3.04 §3.4;
//!   u-blox RXM-RAWX `doMes` likewise);
//! - carrier phase \[cycles\], changing in the same sense as the range
//!   (RINEX 3.04 §3.3: Φ = ρ/λ + …, so dΦ/dt = −D for a receiver that keeps
//!   time; RXM-RAWX `cpMes` the same, its ambiguity set to bring it near the
//!   pseudorange): a receiver's NCO phase θ, which runs at +D, is −Φ up to a
//!   constant.
#![deny(missing_docs)]

mod columns;
mod config;
mod error;
mod imu;
mod observations;
mod output;
mod parse;
mod plain;
mod row;
mod signal;
#[cfg(test)]
mod test_files;
mod tracking;
mod vibration;
mod writers;

pub use columns::{HeaderError, TrackingColumns};
pub use config::{MAX_CONFIG_BYTES, read_config_text};
pub use error::{Column, FormatError};
pub use imu::{IMU_COLUMNS, ImuCubic, ImuSeries, read_imu, read_imu_file};
pub use observations::{
    ClockEvent, GPS_WEEK_S, Observation, ObservationLog, ObservationLogBuilder, SatelliteSeries, Skipped, obs_flags,
};
pub use output::{
    ExportError, FileError, OutputPathError, check_output_dir, check_output_file, check_output_file_in, create_file,
    write_file,
};
pub use row::{RowError, TrackingRecord, parse_imu_row, parse_tracking_row};
pub use signal::{CARRIER_MATCH_HZ, Carrier, GLONASS_K, GNSS_BAND_HZ, SIGNALS, Signal, SignalError, SignalSpec};
pub use tracking::{
    CARRIER_COLUMNS, ChannelTrack, NCO_COLUMNS, TRACKING_COLUMNS, TrackingLog, read_tracking, read_tracking_file,
    read_tracking_file_in_chunks, read_tracking_file_plain,
};
pub use vibration::{VIBRATION_COLUMNS, read_vibration_psd, read_vibration_psd_file};
pub use writers::{
    EPOCH_COLUMNS, ImuWriter, TrackingRow, TrackingWriter, write_epochs_csv, write_epochs_file, write_imu_csv,
    write_tracking_csv, write_tracking_csv_on,
};
