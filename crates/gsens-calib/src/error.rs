//! Why a calibration could not run.

use gsens_core::LoopError;
use gsens_core::RegressorError;
use gsens_core::units::Decimal;

/// Why a calibration (or one of its searches) could not run.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum CalibError {
    /// The loop specification is invalid.
    #[error("invalid loop: {0}")]
    Loop(LoopError),
    /// Loop and log intervals do not fit together.
    #[error("{0}")]
    Intervals(RegressorError),
    /// The discrete loop at this interval is unstable.
    #[error("the loop (Bn, order) is unstable when updated every {} s; is the loop update interval right?", Decimal(*.0))]
    UnstableAtInterval(f64),
    /// A setting outside its range.
    #[error("setting {name} = {} is out of range: expected {expected}", Decimal(*value))]
    Setting {
        /// The setting's name (as in the result document's `settings`).
        name: &'static str,
        /// Its value.
        value: f64,
        /// The range it must be in.
        expected: &'static str,
    },
    /// An option stated that the loop or the method does not use (the
    /// message names the options as the caller does).
    #[error("{0}")]
    Ignored(String),
    /// A combination of settings gsens does not support.
    #[error("{0}")]
    Unsupported(&'static str),
    /// The loop stated in words has no form of the implementation named
    /// ([`gsens_core::LoopModel::discrete_forms`]).
    #[error(
        "{implementation} has no form of the stated loop ({stated}): GNSS-SDR's needs a 2nd-order loop of ζ 0.707 or a \
         3rd-order one of a3 1.1 and b3 2.4, updated every 1, 2, 4, 5, 10 or 20 ms; PocketSDR's a 3rd-order one of a3 \
         1.1 and b3 2.4"
    )]
    NoLoopForm {
        /// The loop stated, in words.
        stated: String,
        /// The implementation asked for.
        implementation: gsens_core::LoopImplementation,
    },
    /// The series differ in length.
    #[error(
        "the series differ in length: {t_s} epoch times, {phase_err_rad} phase errors, {accel_mps2} specific forces"
    )]
    LengthMismatch {
        /// Epoch times.
        t_s: usize,
        /// Phase errors.
        phase_err_rad: usize,
        /// Specific forces.
        accel_mps2: usize,
    },
    /// Too few epochs to estimate.
    #[error("only {epochs} epochs with a phase measurement after the {warmup_s} s warm-up; need at least 10")]
    TooFewEpochs {
        /// Usable epochs.
        epochs: u64,
        /// The warm-up \[s\].
        warmup_s: f64,
    },
    /// The warm-up leaves no epoch of the log to estimate from.
    #[error(
        "the warm-up of {warmup_s} s (warmup_s) is not shorter than the log ({log_s:.1} s): no epoch is \
         left to estimate from; give a warm-up of a few seconds (the default is 2 s)"
    )]
    WarmupBeyondLog {
        /// The warm-up \[s\].
        warmup_s: f64,
        /// The log's span \[s\].
        log_s: f64,
    },
    /// The log is too short for the time-offset search.
    #[error("the log is too short to search a time offset of ±{max_abs_s} s ({epochs} usable epochs)")]
    TooShortForOffsetSearch {
        /// The search range \[s\].
        max_abs_s: f64,
        /// Usable epochs.
        epochs: usize,
    },
    /// The loop has no natural frequency to identify.
    #[error("the loop has no natural frequency to identify")]
    NoNaturalFrequency,
}
