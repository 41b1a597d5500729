//! # gsens-core
//!
//! The pure core of gsens: the carrier-loop models, the oscillator
//! g-sensitivity estimators and the compensator. No I/O, no allocation in the
//! per-epoch path, `no_std` when built without the default `std` feature
//! (all transcendental functions come from `libm`, so results are the same
//! bit for bit with and without `std`).
//!
//! The method (see `shared/conventions.md`): the oscillator adds a frequency
//! bias Δf = aᵀΓ \[Hz\] to every carrier NCO, `a` the specific force \[m/s²\] in
//! the IMU body frame and Γ the g-sensitivity vector \[Hz/(m/s²)\]. The carrier
//! loop turns it into a phase tracking error φ = L\[Δf\]. A triad of software
//! loop models gives φ_a = L\[a\], so φ = φ_aᵀΓ + noise, which the estimators in
//! [`estimator`] solve for Γ.
#![cfg_attr(not(feature = "std"), no_std)]
#![deny(missing_docs)]

pub mod calibrator;
pub mod compensate;
pub mod estimator;
pub mod filter;
mod loop_model;
pub mod math;
pub mod observability;
pub mod pll;
pub mod regressor;
pub mod robust;
pub mod units;

pub use calibrator::{Calibrator, average_phase_rad};
pub use estimator::{BatchLeastSquares, GammaEstimate, GammaEstimator, GradientObserver, RecursiveLeastSquares};
pub use loop_model::{LoopModel, LoopPeak};
pub use pll::{CarrierLoop, DiscretePll, LoopFilter, LoopFilterCoeffs, LoopSpec};
pub use regressor::{LoggedPhase, RegressorModel};
