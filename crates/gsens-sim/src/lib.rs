//! # gsens-sim
//!
//! A closed-loop simulator of a g-sensitivity calibration session (the
//! experiment of the seed paper): a crystal oscillator whose frequency depends
//! on the specific force it feels drives the carrier-tracking channels of a
//! GNSS receiver with a fixed antenna, while the board with the oscillator and
//! an IMU is shaken by hand. It produces what the receiver would log — IMU
//! specific force and per-channel PLL phase errors — and the truth (Γ and
//! everything needed to reproduce the run).
//!
//! - [`scenario`]: the TOML scenario (with an embedded, commented default
//!   reproducing the paper's experiment) and its validation;
//! - [`channel`]: one tracking channel at the correlator level, using the
//!   core's loop filter and NCO ([`gsens_core::CarrierLoop`]);
//! - [`session`]: the whole session, streamed through a [`session::SessionSink`];
//! - [`iq`]: complex baseband GPS L1 C/A samples of the same scenario, for
//!   software receivers (GNSS-SDR);
//! - [`error`]: the typed errors of the configuration (`ConfigError`,
//!   `UtcError`, `AlmanacError`).
#![deny(missing_docs)]

pub mod channel;
pub mod compensation;
pub mod compensation_trial;
pub mod error;
pub mod imu;
pub mod iq;
mod logs;
pub mod motion;
pub mod oscillator;
pub mod rng;
pub mod satellites;
pub mod scenario;
pub mod session;
mod world;

pub use logs::{
    IqSession, LoadError, LogsError, SimulatedLogs, TruthLoop, load_scenario, read_truth_gamma, read_truth_loop,
    simulate_iq_to_dir, simulate_logs, simulate_to_dir,
};
