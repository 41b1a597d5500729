//! The error types of the crate.

use gsens_core::units::Decimal;
use gsens_io::{Column, FormatError};

/// Everything that can be wrong when preparing a session from a tracking log
/// and an IMU log: the epoch grid, the settings, the overlap of the logs, the
/// selection. Problems of the logs themselves (reading them, an inconsistent
/// in-memory IMU series) are the [`SessionError::Format`] variant.
///
/// Like [`FormatError`]'s, the `Display` form starts with the source (the file
/// name, or the display name given to a reader) and, where it applies, names
/// the 1-based line and the column, e.g.
///
/// ```text
/// tracking.csv: line 17, column 1 (`t_s`): time stamp 0.4 s is 0.01 s off the epoch grid t0 + k*T (…)
/// ```
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SessionError {
    /// A log could not be read or is malformed, or an in-memory IMU series is
    /// inconsistent (displayed as the [`FormatError`] itself).
    #[error(transparent)]
    Format(#[from] FormatError),
    /// Fewer than two distinct time stamps: the log interval cannot be found.
    #[error("{file}: only {epochs} distinct time stamp(s): at least 2 are needed to find the log interval")]
    TooFewEpochs {
        /// Source name.
        file: String,
        /// Number of distinct time stamps.
        epochs: usize,
    },
    /// A time stamp is farther than 10% of the log interval from the uniform epoch grid.
    #[error(
        "{file}: line {line}, {column}: time stamp {t_s} s is {} s off the epoch grid t0 + k*T \
         (t0 = {} s, T = {} s, nearest grid time {} s; tolerance 10% of T)",
        Decimal(*offset_s),
        Decimal(*t0_s),
        Decimal(*log_interval_s),
        Decimal(*grid_t_s)
    )]
    OffGrid {
        /// Source name.
        file: String,
        /// 1-based line number (first row with that time stamp).
        line: u64,
        /// The time column.
        column: Column,
        /// The time stamp \[s\].
        t_s: f64,
        /// Its distance from the grid \[s\] (signed).
        offset_s: f64,
        /// Grid origin \[s\].
        t0_s: f64,
        /// Detected log interval \[s\].
        log_interval_s: f64,
        /// Nearest grid time \[s\].
        grid_t_s: f64,
    },
    /// Two distinct time stamps fall on the same grid epoch.
    #[error(
        "{file}: line {line}, {column}: time stamp {t_s} s falls on the same epoch of the grid (T = {} s) \
         as {previous_t_s} s on line {previous_line}",
        Decimal(*log_interval_s)
    )]
    GridCollision {
        /// Source name.
        file: String,
        /// 1-based line number.
        line: u64,
        /// The time column.
        column: Column,
        /// The time stamp \[s\].
        t_s: f64,
        /// The other time stamp on the same epoch \[s\].
        previous_t_s: f64,
        /// Its line.
        previous_line: u64,
        /// Detected log interval \[s\].
        log_interval_s: f64,
    },
    /// The epoch grid (gaps included) would be unreasonably long.
    #[error(
        "{file}: the usable span holds {epochs} epochs of {} s (gaps included): more than the limit of {limit}",
        Decimal(*log_interval_s)
    )]
    GridTooLarge {
        /// Source name.
        file: String,
        /// Number of epochs the grid would have.
        epochs: u64,
        /// Detected log interval \[s\].
        log_interval_s: f64,
        /// The limit.
        limit: u64,
    },
    /// The IMU and tracking logs do not overlap in time.
    #[error(
        "{imu_file} and {tracking_file} do not overlap in time: the IMU covers [{}, {}] s \
         (time stamps minus imu_time_offset_s = {imu_time_offset_s} s), the tracking epochs cover \
         [{tracking_start_s}, {tracking_end_s}] s. {hint}",
        Decimal(*imu_start_s),
        Decimal(*imu_end_s)
    )]
    NoOverlap {
        /// IMU source name.
        imu_file: String,
        /// Tracking source name.
        tracking_file: String,
        /// Start of the IMU span in true time \[s\].
        imu_start_s: f64,
        /// End of the IMU span in true time \[s\].
        imu_end_s: f64,
        /// The IMU time offset applied \[s\].
        imu_time_offset_s: f64,
        /// First tracking epoch \[s\].
        tracking_start_s: f64,
        /// Last tracking epoch \[s\].
        tracking_end_s: f64,
        /// The likely cause read from the two spans (a log in milliseconds,
        /// clocks on different bases: Unix time, GPS time, seconds of the
        /// week or since power-on) and the fix ([`overlap_hint`](crate::overlap_hint)).
        hint: String,
    },
    /// The selection settings are invalid (e.g. a NaN threshold).
    #[error("{file}: invalid selection settings: {reason}")]
    InvalidSelection {
        /// Tracking source name.
        file: String,
        /// What is wrong.
        reason: String,
    },
    /// The screening settings of the selection are invalid
    /// ([`ScreeningConfig::validate`](crate::ScreeningConfig::validate)).
    #[error("{file}: invalid selection settings: {error}")]
    InvalidScreening {
        /// Tracking source name.
        file: String,
        /// What is wrong (displayed as part of this error's message, so not
        /// also given as its `source`).
        error: ScreeningConfigError,
    },
    /// No tracking channel passes the selection.
    #[error("{file}: no channel passes the selection: {reason}")]
    NoChannelSelected {
        /// Tracking source name.
        file: String,
        /// Which criterion excluded the channels, channel by channel.
        reason: String,
    },
    /// The channels passed, but no epoch's average of them is a finite number.
    #[error(
        "{file}: no epoch has a finite channel-averaged phase error: the phases, or the constant offsets \
         between the channels fitted from them, overflow (check the phase_err_rad column's values and units)"
    )]
    NoAveragedPhase {
        /// Tracking source name.
        file: String,
    },
}

/// An invalid value in a [`ScreeningConfig`](crate::ScreeningConfig), naming
/// its key (e.g. `screening.guard_s = -1 must be ≥ 0`).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ScreeningConfigError {
    /// A value that must be positive and finite is not.
    #[error("screening.{key} = {value} must be positive")]
    MustBePositive {
        /// The key, without the `screening.` prefix.
        key: &'static str,
        /// Its value.
        value: f64,
    },
    /// A value that must be non-negative and finite is not.
    #[error("screening.{key} = {value} must be ≥ 0")]
    MustBeNonNegative {
        /// The key, without the `screening.` prefix.
        key: &'static str,
        /// Its value.
        value: f64,
    },
    /// `max_excluded_fraction` is not in \[0, 1\].
    #[error("screening.max_excluded_fraction = {value} must be in [0, 1]")]
    MustBeFraction {
        /// Its value.
        value: f64,
    },
}
