//! # gsens-core
//!
//! The pure core of gsens: the carrier-loop models, the oscillator
//! g-sensitivity estimators and the compensator. No I/O, no allocation in the
//! per-epoch path, `no_std` when built without the default `std` feature
//! (all transcendental functions come from `libm`, so results are the same
//! bit for bit with and without `std`; the one exception,
//! [`units::cn0_dbhz_to_ratio_hz`], is a conversion for callers that the
//! crate's algorithms do not use).
//!
//! The method (see `docs/conventions.md`): the oscillator adds a frequency
//! bias Δf = aᵀΓ \[Hz\] to every carrier NCO, `a` the specific force \[m/s²\] in
//! the IMU body frame and Γ the g-sensitivity vector \[Hz/(m/s²)\]. The carrier
//! loop turns it into a phase tracking error φ = L\[Δf\]. A triad of software
//! loop models gives φ_a = L\[a\], so φ = φ_aᵀΓ + noise, which the estimators in
//! [`GammaEstimator`]s solve for Γ. The loop models and their signs are on
//! [`DiscretePll`] and [`LoopModel`]; everything in `docs/conventions.md`.
#![cfg_attr(not(feature = "std"), no_std)]
#![deny(missing_docs)]

mod calibrator;
mod compensate;
pub mod defaults;
mod discriminator;
mod estimator;
mod filter;
pub mod interpolate;
mod loop_model;
mod math;
mod observability;
mod pll;
mod regressor;
mod robust;
pub mod stats;
pub mod units;

pub use pll::gnss_sdr;
pub use pll::pocket_sdr;

pub use calibrator::{AxisStage, Calibrator, FedEpoch, PrefilteredCalibrator, average_phase_rad, warmup_epochs};
pub use compensate::{Compensator, compensated_phase_rad};
pub use discriminator::{Discriminator, RANGE_FALSE_ALARM, RANGE_MARGIN_SIGMAS, discriminator_variance_rad2};
pub use estimator::{
    BatchLeastSquares, GammaEstimate, GammaEstimator, GradientObserver, NormalEquations, RANK_TOL,
    RecursiveLeastSquares, hac_covariance,
};
pub use filter::HighPass;
pub use loop_model::{LoopImplementation, LoopModel, LoopPeak, TWO_RATE_FACTORS};
pub use observability::{Observability, ObservabilityCriteria, assess, axes_in_solve, solve_in_observable_axes};
pub use pll::{
    CarrierLoop, Complex, DiscretePll, KAPLAN_A3, KAPLAN_B3, LOOP_STATE_LEN, LinearLoop, LoopError, LoopFilter,
    LoopFilterCoeffs, LoopOrderError, LoopSpec, LoopState, ModelLoop, loop_state_space, second_order_bn_from_wn,
    second_order_wn_from_bn, third_order_bn_over_wn,
};
pub use regressor::{
    AxisRegressor, LoggedPhase, RegressorError, RegressorModel, RowQuantity, compensate_interpolation,
    interpolation_compensated, loop_substeps,
};
pub use robust::{HuberWeights, sandwich_covariance};
