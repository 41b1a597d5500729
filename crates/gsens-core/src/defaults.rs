//! The defaults of a calibration that the C API needs as well as the
//! library: the loop assumed when none is stated, the warm-up and the
//! high-pass. `gsens_calib::defaults` gathers them with the rest of the
//! command line's defaults.

/// The carrier PLL's order when none is stated: 2, the paper's loop
/// ([`crate::LoopSpec::PAPER`]).
pub const DEFAULT_ORDER: u8 = 2;

/// The carrier loop's one-sided noise bandwidth Bn \[Hz\] when none is
/// stated: 3 Hz, the paper's loop ([`crate::LoopSpec::PAPER`]).
pub const DEFAULT_BN_HZ: f64 = 3.0;

/// Seconds at the start of a log that only drive the loop models \[s\]: 2 s,
/// the start-up transient of the paper's loop (ζωn = 4 s⁻¹, e^(−ζωn·t)
/// below 0.1 % after 2 s).
pub const DEFAULT_WARMUP_S: f64 = 2.0;

/// Corner f_hp of the identical first-order high-pass on φ and φ_a \[Hz\]:
/// y_k = α·(y_{k−1} + x_k − x_{k−1}), α = exp(−2π·f_hp·T_log)
/// (docs/conventions.md), 0.05 Hz, well below hand shaking at about 1 Hz,
/// so that oscillator wander leaves the fit while Γ's signature stays.
pub const DEFAULT_HIGHPASS_HZ: f64 = 0.05;
