//! The typed errors of the simulator's configuration: one type per concern.
//!
//! - [`ConfigError`]: a value of a scenario (or of a model's configuration)
//!   that is out of range or inconsistent with another; the variants carry
//!   the key path (e.g. `loop.bn_hz`, `motion.segments[2].period_s`), the
//!   value and what is allowed, so that a caller can point at the TOML key
//!   ([`ConfigError::key`]);
//! - [`UtcError`]: a UTC date and time that does not parse
//!   ([`parse_utc_to_gps_s`](crate::scenario::parse_utc_to_gps_s));
//! - [`AlmanacError`]: a YUMA almanac that does not parse
//!   ([`Constellation::from_yuma`](crate::satellites::Constellation::from_yuma)).
//!
//! The scenario's own error ([`ScenarioError`](crate::scenario::ScenarioError)),
//! the IQ generator's ([`IqError`](crate::iq::IqError)) and the simulation's
//! ([`SimError`](crate::session::SimError)) wrap these.
//!
//! A wrapping error states the wrapped one's message in its own and does not
//! return it as [`source`](std::error::Error::source), so that printing the
//! chain (`anyhow`'s `{:#}`) does not repeat it.

use std::num::ParseFloatError;

use gsens_core::LoopError;

/// An invalid value in a scenario or a model's configuration.
///
/// The messages name the key path, as in `loop.bn_hz must be > 0 (got -1)`.
/// A model validating its own configuration gives the path as it appears in
/// a scenario when it knows it (`oscillator.h0`, `imu.rate_hz`,
/// `motion.segments[i]…`) and a path relative to its section otherwise
/// ([`Geodetic`](crate::satellites::Geodetic): `lat_deg`, which the scenario
/// reports as `antenna.lat_deg`; see [`ConfigError::under`]).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ConfigError {
    /// A number outside its allowed range.
    #[error("{key} must be {allowed} (got {value})")]
    OutOfRange {
        /// Key path, e.g. `loop.bn_hz` or `motion.segments[2].period_s`.
        key: String,
        /// The value given (integers converted exactly).
        value: f64,
        /// What the value must be, as the message states it: `> 0`,
        /// `within [0, 70] dB-Hz`, `finite and >= 0`, …
        allowed: String,
    },
    /// A signal of `satellites.signals` that gsens does not know, or that the
    /// scenario cannot simulate.
    #[error("{key}: {message}")]
    Signal {
        /// Key path, e.g. `satellites.signals[2]`.
        key: String,
        /// What is wrong (for an unknown name: the names known).
        message: String,
    },
    /// A direction given as a vector that is zero or not finite.
    #[error("{key}: axis vector {vector:?} must be finite and non-zero")]
    InvalidAxis {
        /// Key path of the axis, e.g. `motion.segments[1].axis` (`axis` from
        /// [`Axis::unit`](crate::motion::Axis::unit) itself).
        key: String,
        /// The vector given.
        vector: [f64; 3],
    },
    /// A date and time that does not parse.
    #[error("{key} must look like 2024-02-08T12:00:00Z (got {:?})", .error.input())]
    Time {
        /// Key path, e.g. `session.start_utc`.
        key: String,
        /// Why it does not parse (it holds the text given).
        error: UtcError,
    },
    /// `loop.interval_s` is not a whole fraction of the 20 ms data bit.
    #[error("loop.interval_s must divide the 20 ms data bit (1, 2, 4, 5, 10 or 20 ms, …) (got {interval_s})")]
    LoopIntervalNotInDataBit {
        /// `loop.interval_s` \[s\].
        interval_s: f64,
    },
    /// `log.interval_s` is not a whole multiple of `loop.interval_s`.
    #[error("log.interval_s must be a whole multiple of loop.interval_s = {loop_interval_s} (got {log_interval_s})")]
    LogIntervalNotMultiple {
        /// `log.interval_s` \[s\].
        log_interval_s: f64,
        /// `loop.interval_s` \[s\].
        loop_interval_s: f64,
    },
    /// A third-order loop with a3·b3 ≤ 1 (unstable whatever its bandwidth).
    #[error("loop.a3 * loop.b3 must be > 1 for a stable loop (got {})", .a3 * .b3)]
    ThirdOrderUnstable {
        /// `loop.a3`.
        a3: f64,
        /// `loop.b3`.
        b3: f64,
    },
    /// The loop is too wide for its update interval: the discrete loop is
    /// unstable.
    #[error("loop.bn_hz = {bn_hz} is too wide for loop.interval_s = {interval_s}: the discrete loop is unstable")]
    DiscreteLoopUnstable {
        /// `loop.bn_hz` \[Hz\].
        bn_hz: f64,
        /// `loop.interval_s` \[s\].
        interval_s: f64,
    },
    /// The session lasts no time: no motion segment and no `session.duration_s`.
    #[error("the session is empty: give motion.segments or session.duration_s")]
    EmptySession,
    /// The core refused the loop specification.
    #[error("loop: {0}")]
    Loop(LoopError),
    /// An argument of a model's constructor (not a scenario key) out of range.
    #[error("{name} must be {allowed} (got {value})")]
    InvalidArgument {
        /// What the argument is, e.g. `oscillator sample interval`.
        name: String,
        /// The value given.
        value: f64,
        /// What the value must be, e.g. `> 0 s`.
        allowed: String,
    },
}

impl ConfigError {
    /// A value of `key` outside what is `allowed` (see [`ConfigError::OutOfRange`]).
    pub fn out_of_range(key: impl Into<String>, value: f64, allowed: impl Into<String>) -> Self {
        ConfigError::OutOfRange { key: key.into(), value, allowed: allowed.into() }
    }

    /// The key path the error is about (the first one named when a
    /// constraint ties several keys; `loop` for [`ConfigError::Loop`]), or
    /// None when it is not a configuration key.
    pub fn key(&self) -> Option<&str> {
        match self {
            ConfigError::OutOfRange { key, .. }
            | ConfigError::InvalidAxis { key, .. }
            | ConfigError::Time { key, .. }
            | ConfigError::Signal { key, .. } => Some(key),
            ConfigError::LoopIntervalNotInDataBit { .. } => Some("loop.interval_s"),
            ConfigError::LogIntervalNotMultiple { .. } => Some("log.interval_s"),
            ConfigError::ThirdOrderUnstable { .. } => Some("loop.a3"),
            ConfigError::DiscreteLoopUnstable { .. } => Some("loop.bn_hz"),
            ConfigError::Loop(_) => Some("loop"),
            ConfigError::EmptySession | ConfigError::InvalidArgument { .. } => None,
        }
    }

    /// The same error with `prefix.` put before its key path (for a
    /// configuration validated on its own and embedded in a section, e.g.
    /// `lat_deg` → `antenna.lat_deg`). Errors whose message names absolute
    /// scenario keys are returned unchanged.
    pub fn under(self, prefix: &str) -> Self {
        let join = |key: String| format!("{prefix}.{key}");
        match self {
            ConfigError::OutOfRange { key, value, allowed } => {
                ConfigError::OutOfRange { key: join(key), value, allowed }
            }
            ConfigError::InvalidAxis { key, vector } => ConfigError::InvalidAxis { key: join(key), vector },
            ConfigError::Time { key, error } => ConfigError::Time { key: join(key), error },
            other => other,
        }
    }
}

/// A UTC date and time that does not parse as `YYYY-MM-DDTHH:MM:SS[.fff][Z]`.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum UtcError {
    /// Not of the form `YYYY-MM-DDTHH:MM:SS[.fff][Z]`, or a field is not a number.
    #[error("expected a UTC time like 2024-02-08T12:00:00Z, got {input:?}")]
    Malformed {
        /// The text given.
        input: String,
    },
    /// A field out of its range: year 1980–2200, month 1–12, day 1–31, hour
    /// 0–23, minute 0–59, second in [0, 61).
    #[error("the {field} of the UTC time {input:?} is out of range")]
    OutOfRange {
        /// The text given.
        input: String,
        /// `year`, `month`, `day`, `hour`, `minute` or `second`.
        field: &'static str,
    },
}

impl UtcError {
    /// The text that does not parse.
    pub fn input(&self) -> &str {
        match self {
            UtcError::Malformed { input } | UtcError::OutOfRange { input, .. } => input,
        }
    }
}

/// A YUMA almanac that does not parse. Line numbers are 1-based.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum AlmanacError {
    /// A line that is not a record header (`****…`), a comment or `key: value`.
    #[error("YUMA line {line}: expected 'key: value'")]
    ExpectedKeyValue {
        /// The line.
        line: usize,
    },
    /// A value that is not a number.
    #[error("YUMA line {line}: bad number '{text}': {error}")]
    BadNumber {
        /// The line.
        line: usize,
        /// The value's text.
        text: String,
        /// Why it does not parse.
        error: ParseFloatError,
    },
    /// A record without one of the fields the orbit needs.
    #[error("YUMA record lacks '{field}'")]
    MissingField {
        /// The line of the record's first field.
        line: usize,
        /// The start of the missing key, lower case (`id`, `health`, `week`,
        /// `eccentricity`, `sqrt(a)`, …).
        field: &'static str,
    },
    /// No record at all.
    #[error("YUMA almanac holds no satellite")]
    Empty,
}
