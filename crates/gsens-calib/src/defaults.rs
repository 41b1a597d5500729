//! The defaults of a calibration, in one place: what `gsens estimate` uses
//! without a flag, what [`crate::CalibrationOptions::default`] and
//! [`crate::EstimateSettings::default`] hold and what the Python module's
//! keywords default to. Those the C API needs too are gsens-core's
//! ([`gsens_core::defaults`]), those of the channel selection the session
//! crate's, which applies them; all are re-exported here.

pub use gsens_core::defaults::{DEFAULT_BN_HZ, DEFAULT_HIGHPASS_HZ, DEFAULT_ORDER, DEFAULT_WARMUP_S};
pub use gsens_session::{DEFAULT_CHANNELS, DEFAULT_CN0_DROP_DB};

/// Search range ± of the IMU time offset `auto` \[s\].
pub const DEFAULT_TIME_OFFSET_MAX_S: f64 = 0.25;

/// Gain k of the gradient observer.
pub const DEFAULT_GAIN_K: f64 = 0.5;
