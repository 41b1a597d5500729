//! # gsens-calib
//!
//! The calibration pipeline of gsens as a library: from receiver logs (or
//! in-memory series) and settings to one serializable result document.
//!
//! [`calibrate_files`] and [`calibrate_logs`] run the whole job — read,
//! screen, average, model, estimate, judge — under [`PipelineSettings`] and
//! return an [`Outcome`], whose [`Outcome::document`] is the
//! [`ResultDocument`] every output serializes. A receiver's own files reach
//! it through that receiver's adapter crate (`gsens-gnss-sdr`,
//! `gsens-pocketsdr`), which turns them into these logs and settings and
//! records what it converted as a [`SourceConversion`]; this crate knows
//! logs, loops and settings, not where they came from.
//! The stages, each usable on its own:
//!
//! - **session preparation** (`gsens_session`): the epoch grid, channel
//!   screening and the offset-free channel average;
//! - **estimation** ([`calibrate`]): a uniform epoch series of
//!   channel-averaged phase error φ \[rad\] and specific force a \[m/s²\] in,
//!   Γ̂ with its covariance, the Cramér–Rao bound, the observability verdict
//!   per axis and what compensation removes out ([`Calibration`]). The
//!   residuals of a carrier loop are coloured, so the uncertainty is
//!   autocorrelation-robust ([`gsens_core::hac_covariance`]) or
//!   from an AR noise model ([`gls`]);
//! - **systematic errors** ([`joint_fit`], [`choose_loop`]): the
//!   IMU time offset and the loop's natural frequency, jointly with Γ.
//!
//! The method, units and signs are in `docs/conventions.md`.
//!
//! ```
//! use gsens_calib::{EpochSeries, EstimateSettings, calibrate};
//! use gsens_core::RegressorModel;
//! use gsens_core::{LoopModel, LoopSpec};
//!
//! // A synthetic session: x shaken at 0.9 Hz, φ = L[aᵀΓ] through the paper's
//! // loop, fed each integration's mean as the estimate's prefilter takes it.
//! let t = 0.025;
//! let gamma = [0.3, 0.0, 0.0];
//! let accel: Vec<[f64; 3]> =
//!     (0..4000).map(|k| [2.0 * (std::f64::consts::TAU * 0.9 * k as f64 * t).sin(), 0.0, 9.81]).collect();
//! let mut triad = RegressorModel::with_loop(
//!     LoopModel::kaplan(LoopSpec::PAPER, Some(t)).runnable()?, t, t,
//!     gsens_core::LoggedPhase::Last)?;
//! let mut means = accel.clone();
//! gsens_core::compensate_interpolation(&mut means, triad.interpolation_compensation());
//! let phase: Vec<Option<f64>> =
//!     means.iter().map(|a| { let p = triad.epoch(a); Some(p[0] * gamma[0]) }).collect();
//! let t_s: Vec<f64> = (0..accel.len()).map(|k| k as f64 * t).collect();
//! let series = EpochSeries { log_interval_s: t, t_s: &t_s, phase_err_rad: &phase, accel_mps2: &accel,
//!                            imu_time_offset_s: 0.0 };
//! let c = calibrate(&series, &EstimateSettings::default())?;
//! assert!((c.gamma_hz_per_mps2[0].unwrap() - 0.3).abs() < 1e-6);
//! assert_eq!(c.gamma_hz_per_mps2[2], None); // z never shaken: unobservable
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![deny(missing_docs)]

mod checks;
pub mod defaults;
mod document;
mod error;
mod estimate;
mod fft;
pub mod gls;
mod joint;
mod loop_free;
mod measurement;
mod nco_frequency;
mod nco_loop;
mod observation_pipeline;
mod observation_rows;
pub mod option_values;
mod options;
mod pipeline;
pub mod predict;
mod progress;
mod response_check;
mod result;
mod robust;
mod search;
mod settings;
mod verdict;
mod warmup;
mod warning;

pub use document::{
    DocumentError, FigureInfo, LoopSummary, PipelineSummary, ReportInfo, ResultDocument, SourceConversion,
    tool_version, two_rate_advice,
};
pub use error::CalibError;
pub use estimate::{
    CompensatedEpoch, EpochSeries, HISTORY_INTERVAL_S, calibrate, compensation_series, imu_systematic_sigma,
    regressors, streaming_calibrator, warmup_epochs,
};
pub use joint::{
    ChosenLoop, JointFit, JointSpec, LOOP_FORM_ALIKE, LOOP_TEST_FALSE_ALARM, LOOP_TEST_Z, LoopFormFit, LoopForms,
    TYPICAL_LOOP_INTERVALS_S, choose_loop, joint_fit,
};
pub(crate) use joint::{compare_loop_forms, joint_fit_from};
pub use loop_free::{
    CROSS_CHECK_FALSE_ALARM, InputPhases, LoopFreeCheck, LoopFreeError, LoopFreeEstimate, LoopFreeSettings,
    TrackInputPhase, estimate_loop_free, estimate_loop_free_choosing, estimate_loop_free_from,
};
pub use measurement::{Measurement, MeasurementChoice};
pub use nco_frequency::{estimate_nco_frequency, estimate_nco_frequency_from};
pub use nco_loop::{
    CompensatedCarrierPhase, IDENTIFY_BN_RANGE_HZ, IDENTIFY_INTERVALS_S, IdentifiedLoop, IdentifiedNcoEstimate,
    LoopResolution, NcoRecord, ShapeFit, estimate_nco_frequency_identified, estimate_nco_frequency_identified_from,
    estimate_nco_frequency_unity, identification_shapes, nco_rows,
};
pub use observation_pipeline::{LoopIdentification, ObservationOutcome, calibrate_observations};
pub use observation_rows::{
    CLOCK_STEP_HZ, ObservationRecord, ObservationRows, ObservationRowsError, ObservationTrack, SLIPPING_TRACK_SHARE,
    SLIPPING_TRACK_SLIPS, observation_rows,
};
pub use options::{
    CalibrationOptions, EstimatorOptions, LoopOptions, MethodName, SelectionOptions, SystematicOptions,
    TimeOffsetOption,
};
pub use pipeline::{
    DEFAULT_LOOP_TOLERANCE, LoopForm, LoopIdentificationMode, Outcome, ParseTimeOffsetError, PipelineError,
    PipelineSettings, RESPONSE_CHECK_FALSE_ALARM, TimeOffset, calibrate_files, calibrate_logs, calibrate_owned_logs,
    series_of,
};
pub use progress::{Progress, observe};
pub use response_check::{
    ResponseBin, ResponseCheck, ResponseCheckError, ResponseSettings, epoch_response, measure_response,
    measure_response_with, student_t_quantile_two_sided, student_t_two_sided_tail,
};
pub use result::{Calibration, HistoryPoint};
pub use robust::{HuberFit, huber_irls};
pub use settings::{EstimateSettings, Method, Robust};
pub use verdict::{AxisVerdict, session_linear_range_rad};
pub use warmup::{longest_models_warmup_s, models_warmup_s};
pub use warning::{Warning, WarningCode, untrusted_codes};
