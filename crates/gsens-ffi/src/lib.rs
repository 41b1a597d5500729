//! # gsens-ffi: the C API of gsens
//!
//! The streaming calibrator and the compensator of [`gsens_core`] behind a C
//! ABI, for receiver firmware. The header, `include/gsens.h`, is generated
//! from this file by cbindgen (and checked current by the crate's tests).
//!
//! - **Calibrator**: the receiver's carrier loop (2nd or 3rd order from its
//!   noise bandwidth, or its filter coefficients), its update interval, the
//!   log interval; fed one epoch at a time with the specific force and the
//!   selected channels' phase errors (or their average); answers Γ̂, its
//!   covariance and each axis's observability at any time. It is the batch
//!   pipeline's estimator streamed: the regressor triad, the warm-up, the
//!   high-pass, batch least squares and the interpolation prefilter
//!   ([`gsens_core::PrefilteredCalibrator`]), so on the same epoch series it
//!   gives the Γ̂ of `gsens estimate --method batch` (see the crate's tests).
//! - **Compensator**: −aᵀΓ̂ \[Hz\], the frequency to add to every carrier NCO
//!   command ([`gsens_core::Compensator`]).
//!
//! Rules at the boundary: every call returns a [`GsensStatus`]; null
//! pointers, non-finite inputs, structures of another size (`struct_size`)
//! and calls in the wrong state are statuses, never undefined behaviour or a
//! panic (with `std`, a panic would be caught and returned as
//! [`GsensStatus::Panic`]; none is known). Nothing allocates after creation:
//! [`gsens_calibrator_init`] builds a calibrator in memory the caller owns
//! (static, stack), [`gsens_calibrator_new`] (with `std`) on the heap. A
//! handle has no shared state: one handle per thread is thread-safe by
//! construction.
#![cfg_attr(not(feature = "std"), no_std)]
#![deny(missing_docs)]
// The C ABI takes raw pointers; every one is checked for null before use.
#![allow(clippy::not_unsafe_ptr_arg_deref)]

use core::ffi::{c_char, c_void};
use core::mem::{align_of, size_of};

use gsens_core::{
    BatchLeastSquares, Calibrator, Compensator, KAPLAN_A3, KAPLAN_B3, LoggedPhase, LoopError, LoopFilterCoeffs,
    LoopModel, LoopSpec, ModelLoop, ObservabilityCriteria, PrefilteredCalibrator, RegressorModel, defaults,
    solve_in_observable_axes,
};

/// The most channels [`gsens_calibrator_feed_channels`] takes at one epoch.
pub const GSENS_MAX_CHANNELS: usize = 64;

/// What a call did.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GsensStatus {
    /// Done.
    Ok = 0,
    /// A pointer argument was null.
    NullPointer = 1,
    /// A structure's `struct_size` is not this library's (a header of
    /// another version), a buffer is too small, or a channel count is 0 or
    /// above [`GSENS_MAX_CHANNELS`].
    WrongSize = 2,
    /// An input that must be finite was not (a NaN phase is not an error:
    /// it marks a channel or an epoch without a phase).
    NotFinite = 3,
    /// A configuration value is out of range (order, bandwidth, damping,
    /// intervals: the loop interval must divide the log interval).
    InvalidConfig = 4,
    /// The loop is unstable at its update interval (Bn·T too large), or its
    /// filter gives an unstable loop.
    UnstableLoop = 5,
    /// The calibrator was finished ([`gsens_calibrator_finish`]): it takes no more epochs.
    Finished = 6,
    /// The handle was not made by this call's counterpart
    /// ([`gsens_calibrator_free`] on a calibrator from [`gsens_calibrator_init`]).
    NotOwned = 7,
    /// The memory given to [`gsens_calibrator_init`] is not aligned to
    /// [`gsens_calibrator_align`].
    Misaligned = 8,
    /// A panic inside the library was caught (a bug: please report it).
    Panic = 99,
}

impl GsensStatus {
    /// Every status (a function, not a constant: cbindgen would put a
    /// constant in the header).
    pub fn all() -> [GsensStatus; 10] {
        [
            GsensStatus::Ok,
            GsensStatus::NullPointer,
            GsensStatus::WrongSize,
            GsensStatus::NotFinite,
            GsensStatus::InvalidConfig,
            GsensStatus::UnstableLoop,
            GsensStatus::Finished,
            GsensStatus::NotOwned,
            GsensStatus::Misaligned,
            GsensStatus::Panic,
        ]
    }
}

/// What the receiver logs as a row's phase error.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GsensLoggedPhase {
    /// The latest discriminator output at the log epoch.
    Last = 0,
    /// The mean of the discriminator outputs since the previous log epoch.
    Mean = 1,
}

/// The calibrator's configuration: the receiver's carrier loop and the
/// estimator's settings. [`gsens_calibrator_config_default`] fills it with
/// the defaults of `gsens estimate`.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GsensCalibratorConfig {
    /// `sizeof(GsensCalibratorConfig)`: a structure of another version is refused.
    pub struct_size: u32,
    /// Loop order: 2 or 3 (from `bn_hz` and `zeta`, or `bn_hz`, `a3`, `b3`);
    /// 0: the filter's coefficients `c0_per_s`, `c1_per_s2`, `c2_per_s3`.
    pub order: u32,
    /// Noise bandwidth Bn \[Hz\] (orders 2 and 3).
    pub bn_hz: f64,
    /// Damping ratio ζ (order 2).
    pub zeta: f64,
    /// a3 of the 3rd-order filter F(s) = b3·ωn + a3·ωn²/s + ωn³/s² (Kaplan: 1.1).
    pub a3: f64,
    /// b3 (Kaplan: 2.4).
    pub b3: f64,
    /// Proportional gain c0 \[1/s\] (order 0).
    pub c0_per_s: f64,
    /// First-integrator gain c1 \[1/s²\] (order 0).
    pub c1_per_s2: f64,
    /// Second-integrator gain c2 \[1/s³\] (order 0; 0 for a 2nd-order filter).
    pub c2_per_s3: f64,
    /// The loop's update interval T \[s\] (the coherent integration time).
    pub loop_interval_s: f64,
    /// The interval between two epochs fed \[s\]: a whole multiple of `loop_interval_s`.
    pub log_interval_s: f64,
    /// What the phase error fed is: a [`GsensLoggedPhase`] value (an integer
    /// here, so that a value C might pass outside the enum is refused as
    /// [`GsensStatus::InvalidConfig`] rather than undefined).
    pub logged_phase: u32,
    /// Epochs of the first this many seconds are left out while the model's
    /// start-up transient dies out \[s\].
    pub warmup_s: f64,
    /// High-pass corner applied alike to the phase error and the regressors
    /// \[Hz\] (0: off): it removes the phase error's slow wander.
    pub highpass_hz: f64,
    /// An axis is observable when its unexplained excitation RMS reaches
    /// this \[rad/(Hz/(m/s²))\] …
    pub min_excitation_rms: f64,
    /// … and its σ is at most this \[Hz/(m/s²)\].
    pub max_sigma_hz_per_mps2: f64,
    /// σ of the estimate is the least-squares σ under white residuals times
    /// this factor (≥ 1; default 1). The residuals of a real loop are
    /// coloured (loop-filtered thermal noise, oscillator phase noise), which
    /// a streaming estimator cannot measure: set it to σ/σ_white of `gsens
    /// estimate` on a log of the same receiver and shaking (its result
    /// document's `sigma_hz_per_mps2` over `sigma_white_hz_per_mps2`: 2.5 to
    /// 2.8 on the default simulated session) for an honest σ.
    pub sigma_colour_factor: f64,
}

/// The estimate at one moment.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GsensEstimate {
    /// `sizeof(GsensEstimate)`, set by the caller.
    pub struct_size: u32,
    /// Whether each axis is observable (1) or not (0).
    pub observable: [u8; 3],
    /// Γ̂ \[Hz/(m/s²)\] at the tracked carrier; NaN on an unobservable axis.
    pub gamma_hz_per_mps2: [f64; 3],
    /// 1σ of Γ̂ \[Hz/(m/s²)\]: under white residuals, times the
    /// configuration's `sigma_colour_factor`; +∞ on an unobservable axis.
    pub sigma_hz_per_mps2: [f64; 3],
    /// Covariance of Γ̂, row-major \[(Hz/(m/s²))²\] (scaled as σ).
    pub covariance_hz_per_mps2_sq: [f64; 9],
    /// RMS of the residual φ − φ_aᵀΓ̂ \[rad\].
    pub residual_sigma_rad: f64,
    /// Epochs in the estimate.
    pub epochs_used: u64,
    /// Epochs fed so far.
    pub epochs_fed: u64,
}

/// The compensator: Γ̂ at the tracked carrier, and the factor to another
/// carrier's NCO.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GsensCompensator {
    /// Γ̂ \[Hz/(m/s²)\] at the carrier it was estimated on.
    pub gamma_hz_per_mps2: [f64; 3],
    /// f_NCO's carrier / f_estimated carrier (1: the same carrier; L5 from
    /// an L1 estimate: 1176.45/1575.42). Δf of the oscillator scales with
    /// the carrier it is multiplied up to.
    pub carrier_ratio: f64,
}

/// A calibrator (opaque to C).
pub struct GsensCalibrator {
    calibrator: PrefilteredCalibrator<BatchLeastSquares, ModelLoop>,
    criteria: ObservabilityCriteria,
    colour: f64,
    fed: u64,
    finished: bool,
    on_heap: bool,
}

/// Runs `f`, a panic becoming [`GsensStatus::Panic`] (with `std`; without
/// it there is no unwinding to catch).
#[inline]
fn guarded(f: impl FnOnce() -> GsensStatus) -> GsensStatus {
    #[cfg(feature = "std")]
    {
        std::panic::catch_unwind(std::panic::AssertUnwindSafe(f)).unwrap_or(GsensStatus::Panic)
    }
    #[cfg(not(feature = "std"))]
    {
        f()
    }
}

/// A `struct_size` field of this library's size.
fn size_u32<T>() -> u32 {
    size_of::<T>() as u32
}

/// The message of a status (a [`GsensStatus`] value): a static,
/// NUL-terminated string ("unknown status" for a value that is none).
#[unsafe(no_mangle)]
pub extern "C" fn gsens_status_message(status: i32) -> *const c_char {
    let Some(status) = GsensStatus::all().into_iter().find(|s| *s as i32 == status) else {
        return c"unknown status".as_ptr();
    };
    let s: &'static core::ffi::CStr = match status {
        GsensStatus::Ok => c"ok",
        GsensStatus::NullPointer => c"a pointer argument is null",
        GsensStatus::WrongSize => {
            c"a structure of another size (struct_size), a buffer too small, or a channel count out of range"
        }
        GsensStatus::NotFinite => c"an input that must be finite is not",
        GsensStatus::InvalidConfig => {
            c"a configuration value is out of range (the loop interval must divide the log interval)"
        }
        GsensStatus::UnstableLoop => c"the loop is unstable at its update interval, or its filter is unstable",
        GsensStatus::Finished => c"the calibrator is finished: it takes no more epochs",
        GsensStatus::NotOwned => c"the handle was not made by this call's counterpart",
        GsensStatus::Misaligned => c"the memory is not aligned to gsens_calibrator_align()",
        GsensStatus::Panic => c"a panic inside gsens was caught (a bug: please report it)",
    };
    s.as_ptr()
}

/// Fills `config` with the defaults of `gsens estimate`: the paper's loop
/// (2nd order, Bn 3 Hz, ζ 0.707, updated every 1 ms), 40 Hz epochs of the
/// latest discriminator output, a 2 s warm-up, a 0.05 Hz high-pass, the
/// observability floor 0.05 rad/(Hz/(m/s²)) and σ ≤ 0.01 Hz/(m/s²).
#[unsafe(no_mangle)]
pub extern "C" fn gsens_calibrator_config_default(config: *mut GsensCalibratorConfig) -> GsensStatus {
    guarded(|| {
        if config.is_null() {
            return GsensStatus::NullPointer;
        }
        let (bn_hz, zeta) = match LoopSpec::PAPER {
            LoopSpec::SecondOrder { bn_hz, zeta } => (bn_hz, zeta),
            _ => (defaults::DEFAULT_BN_HZ, core::f64::consts::FRAC_1_SQRT_2),
        };
        let criteria = ObservabilityCriteria::default();
        let c = GsensCalibratorConfig {
            struct_size: size_u32::<GsensCalibratorConfig>(),
            order: u32::from(defaults::DEFAULT_ORDER),
            bn_hz,
            zeta,
            a3: KAPLAN_A3,
            b3: KAPLAN_B3,
            c0_per_s: 0.0,
            c1_per_s2: 0.0,
            c2_per_s3: 0.0,
            loop_interval_s: 0.001,
            log_interval_s: 0.025,
            logged_phase: GsensLoggedPhase::Last as u32,
            warmup_s: defaults::DEFAULT_WARMUP_S,
            highpass_hz: defaults::DEFAULT_HIGHPASS_HZ,
            min_excitation_rms: criteria.min_excitation_rms,
            max_sigma_hz_per_mps2: criteria.max_sigma_hz_per_mps2,
            sigma_colour_factor: 1.0,
        };
        // SAFETY: non-null, and the caller gives a GsensCalibratorConfig.
        unsafe { config.write(c) };
        GsensStatus::Ok
    })
}

/// The calibrator `config` describes, or why not.
fn build(config: &GsensCalibratorConfig) -> Result<GsensCalibrator, GsensStatus> {
    if config.struct_size != size_u32::<GsensCalibratorConfig>() {
        return Err(GsensStatus::WrongSize);
    }
    let spec = match config.order {
        0 => LoopSpec::Coefficients(LoopFilterCoeffs {
            c0_per_s: config.c0_per_s,
            c1_per_s2: config.c1_per_s2,
            c2_per_s3: config.c2_per_s3,
        }),
        order => u8::try_from(order)
            .ok()
            .and_then(|order| LoopSpec::of_order(order, config.bn_hz, config.zeta, config.a3, config.b3).ok())
            .ok_or(GsensStatus::InvalidConfig)?,
    };
    let finite = [
        config.bn_hz,
        config.zeta,
        config.a3,
        config.b3,
        config.c0_per_s,
        config.c1_per_s2,
        config.c2_per_s3,
        config.loop_interval_s,
        config.log_interval_s,
        config.warmup_s,
        config.highpass_hz,
        config.min_excitation_rms,
        config.max_sigma_hz_per_mps2,
        config.sigma_colour_factor,
    ];
    if finite.iter().any(|x| !x.is_finite()) {
        return Err(GsensStatus::NotFinite);
    }
    let non_negative = [config.warmup_s, config.highpass_hz, config.min_excitation_rms];
    if non_negative.iter().any(|&x| x < 0.0) || config.max_sigma_hz_per_mps2 <= 0.0 || config.sigma_colour_factor < 1.0
    {
        return Err(GsensStatus::InvalidConfig);
    }
    // A high-pass corner at or above Nyquist has no meaning.
    if config.highpass_hz * config.log_interval_s >= 0.5 {
        return Err(GsensStatus::InvalidConfig);
    }
    let model_loop =
        LoopModel::Kaplan { spec, interval_s: Some(config.loop_interval_s) }.runnable().map_err(|e| match e {
            LoopError::Unstable | LoopError::UnstableAtInterval => GsensStatus::UnstableLoop,
            _ => GsensStatus::InvalidConfig,
        })?;
    let logged = match config.logged_phase {
        x if x == GsensLoggedPhase::Last as u32 => LoggedPhase::Last,
        x if x == GsensLoggedPhase::Mean as u32 => LoggedPhase::Mean,
        _ => return Err(GsensStatus::InvalidConfig),
    };
    let model = RegressorModel::with_loop(model_loop, config.loop_interval_s, config.log_interval_s, logged)
        .map_err(|_| GsensStatus::InvalidConfig)?;
    let skip = gsens_core::warmup_epochs(config.warmup_s, config.log_interval_s);
    let inner = Calibrator::new(model, BatchLeastSquares::new(), skip, config.highpass_hz, config.log_interval_s);
    Ok(GsensCalibrator {
        calibrator: PrefilteredCalibrator::new(inner),
        criteria: ObservabilityCriteria {
            min_excitation_rms: config.min_excitation_rms,
            max_sigma_hz_per_mps2: config.max_sigma_hz_per_mps2,
        },
        colour: config.sigma_colour_factor,
        fed: 0,
        finished: false,
        on_heap: false,
    })
}

/// Bytes of memory a calibrator needs (for [`gsens_calibrator_init`]).
#[unsafe(no_mangle)]
pub extern "C" fn gsens_calibrator_size() -> usize {
    size_of::<GsensCalibrator>()
}

/// The alignment that memory needs \[bytes\].
#[unsafe(no_mangle)]
pub extern "C" fn gsens_calibrator_align() -> usize {
    align_of::<GsensCalibrator>()
}

/// Builds a calibrator in `memory` (`size` bytes, aligned to
/// [`gsens_calibrator_align`], at least [`gsens_calibrator_size`]) and puts
/// its handle in `*out`: no allocation at all. The memory must outlive the
/// handle; end with [`gsens_calibrator_drop`], never [`gsens_calibrator_free`].
#[unsafe(no_mangle)]
pub extern "C" fn gsens_calibrator_init(
    memory: *mut c_void,
    size: usize,
    config: *const GsensCalibratorConfig,
    out: *mut *mut GsensCalibrator,
) -> GsensStatus {
    guarded(|| {
        if memory.is_null() || config.is_null() || out.is_null() {
            return GsensStatus::NullPointer;
        }
        if size < size_of::<GsensCalibrator>() {
            return GsensStatus::WrongSize;
        }
        if !(memory as usize).is_multiple_of(align_of::<GsensCalibrator>()) {
            return GsensStatus::Misaligned;
        }
        // SAFETY: non-null; the caller gives a GsensCalibratorConfig.
        let config = unsafe { &*config };
        match build(config) {
            Ok(c) => {
                let p = memory.cast::<GsensCalibrator>();
                // SAFETY: non-null, large enough and aligned (checked above).
                unsafe {
                    p.write(c);
                    out.write(p);
                }
                GsensStatus::Ok
            }
            Err(s) => s,
        }
    })
}

/// Ends a calibrator made by [`gsens_calibrator_init`] (its memory is the caller's again).
#[unsafe(no_mangle)]
pub extern "C" fn gsens_calibrator_drop(calibrator: *mut GsensCalibrator) -> GsensStatus {
    guarded(|| {
        // SAFETY: a handle from gsens_calibrator_init or null.
        let Some(c) = (unsafe { calibrator.as_mut() }) else { return GsensStatus::NullPointer };
        if c.on_heap {
            return GsensStatus::NotOwned;
        }
        // SAFETY: a live calibrator built in place; not used after this.
        unsafe { core::ptr::drop_in_place(calibrator) };
        GsensStatus::Ok
    })
}

/// Builds a calibrator on the heap and puts its handle in `*out`; end it
/// with [`gsens_calibrator_free`]. (With the `std` feature.)
#[cfg(feature = "std")]
#[unsafe(no_mangle)]
pub extern "C" fn gsens_calibrator_new(
    config: *const GsensCalibratorConfig,
    out: *mut *mut GsensCalibrator,
) -> GsensStatus {
    guarded(|| {
        if config.is_null() || out.is_null() {
            return GsensStatus::NullPointer;
        }
        // SAFETY: non-null; the caller gives a GsensCalibratorConfig.
        match build(unsafe { &*config }) {
            Ok(mut c) => {
                c.on_heap = true;
                // SAFETY: `out` is non-null.
                unsafe { out.write(Box::into_raw(Box::new(c))) };
                GsensStatus::Ok
            }
            Err(s) => s,
        }
    })
}

/// Frees a calibrator made by [`gsens_calibrator_new`]. (With the `std` feature.)
#[cfg(feature = "std")]
#[unsafe(no_mangle)]
pub extern "C" fn gsens_calibrator_free(calibrator: *mut GsensCalibrator) -> GsensStatus {
    guarded(|| {
        // SAFETY: a handle from gsens_calibrator_new/init or null.
        let Some(c) = (unsafe { calibrator.as_ref() }) else { return GsensStatus::NullPointer };
        if !c.on_heap {
            return GsensStatus::NotOwned;
        }
        // SAFETY: made by Box::into_raw in gsens_calibrator_new; not used after this.
        drop(unsafe { Box::from_raw(calibrator) });
        GsensStatus::Ok
    })
}

/// The specific force at `accel_mps2` (3 values), finite.
fn read_accel(accel_mps2: *const f64) -> Result<[f64; 3], GsensStatus> {
    if accel_mps2.is_null() {
        return Err(GsensStatus::NullPointer);
    }
    // SAFETY: non-null; the caller gives 3 doubles.
    let a = unsafe { [*accel_mps2, *accel_mps2.add(1), *accel_mps2.add(2)] };
    if a.iter().all(|x| x.is_finite()) { Ok(a) } else { Err(GsensStatus::NotFinite) }
}

/// Feeds one epoch with an averaged phase, checked.
fn feed(calibrator: *mut GsensCalibrator, accel_mps2: *const f64, phase: Option<f64>) -> GsensStatus {
    // SAFETY: a handle from gsens_calibrator_new/init or null.
    let Some(c) = (unsafe { calibrator.as_mut() }) else { return GsensStatus::NullPointer };
    let a = match read_accel(accel_mps2) {
        Ok(a) => a,
        Err(s) => return s,
    };
    if c.finished {
        return GsensStatus::Finished;
    }
    c.calibrator.feed(&a, phase);
    c.fed += 1;
    GsensStatus::Ok
}

/// Feeds one epoch: the specific force `accel_mps2` (3 values, \[m/s²\], IMU
/// axes) at the epoch and the (channel-averaged) phase error
/// `phase_err_rad` \[rad\]; NaN: no phase at this epoch (the model still
/// advances; the epoch and the settling after it stay out of the estimate).
/// A non-finite specific force or an infinite phase is refused
/// ([`GsensStatus::NotFinite`]) and the epoch not taken. Epochs are
/// `log_interval_s` apart; the prefilter holds each back until the next
/// arrives.
#[unsafe(no_mangle)]
pub extern "C" fn gsens_calibrator_feed(
    calibrator: *mut GsensCalibrator,
    accel_mps2: *const f64,
    phase_err_rad: f64,
) -> GsensStatus {
    guarded(|| {
        if phase_err_rad.is_infinite() {
            return GsensStatus::NotFinite;
        }
        feed(calibrator, accel_mps2, (!phase_err_rad.is_nan()).then_some(phase_err_rad))
    })
}

/// Feeds one epoch from the selected channels' phase errors `phase_err_rad`
/// (`n` of them, NaN: the channel has none at this epoch) and their weights
/// `weights` (`n`, or null for equal weights): the weighted mean over the
/// channels present, Σwᵢφᵢ/Σwᵢ ([`gsens_core::average_phase_rad`]). `n` from
/// 1 to [`GSENS_MAX_CHANNELS`].
#[unsafe(no_mangle)]
pub extern "C" fn gsens_calibrator_feed_channels(
    calibrator: *mut GsensCalibrator,
    accel_mps2: *const f64,
    phase_err_rad: *const f64,
    weights: *const f64,
    n: usize,
) -> GsensStatus {
    guarded(|| {
        if n == 0 || n > GSENS_MAX_CHANNELS {
            return GsensStatus::WrongSize;
        }
        if phase_err_rad.is_null() {
            return GsensStatus::NullPointer;
        }
        // SAFETY: non-null; the caller gives n doubles (n checked above).
        let phases = unsafe { core::slice::from_raw_parts(phase_err_rad, n) };
        let equal = [1.0; GSENS_MAX_CHANNELS];
        // SAFETY: as for the phases, when non-null.
        let w = if weights.is_null() { &equal[..n] } else { unsafe { core::slice::from_raw_parts(weights, n) } };
        if phases.iter().any(|p| p.is_infinite()) || w.iter().any(|x| !x.is_finite() || *x < 0.0) {
            return GsensStatus::NotFinite;
        }
        feed(calibrator, accel_mps2, gsens_core::average_phase_rad(phases, w))
    })
}

/// Ends the epochs: the last one, held back by the prefilter, enters the
/// estimate (as the batch pipeline treats the log's end). Feeding after
/// this is [`GsensStatus::Finished`].
#[unsafe(no_mangle)]
pub extern "C" fn gsens_calibrator_finish(calibrator: *mut GsensCalibrator) -> GsensStatus {
    guarded(|| {
        // SAFETY: a handle or null.
        let Some(c) = (unsafe { calibrator.as_mut() }) else { return GsensStatus::NullPointer };
        if !c.finished {
            c.calibrator.flush();
            c.finished = true;
        }
        GsensStatus::Ok
    })
}

/// The estimate now, in `*out` (its `struct_size` set by the caller): the
/// least squares over the axes that stay in the batch pipeline's solve
/// ([`gsens_core::solve_in_observable_axes`]); an axis not observable has
/// Γ̂ NaN, σ +∞ and `observable` 0.
#[unsafe(no_mangle)]
pub extern "C" fn gsens_calibrator_estimate(
    calibrator: *const GsensCalibrator,
    out: *mut GsensEstimate,
) -> GsensStatus {
    guarded(|| {
        // SAFETY: a handle or null.
        let Some(c) = (unsafe { calibrator.as_ref() }) else { return GsensStatus::NullPointer };
        // SAFETY: null or the caller's GsensEstimate.
        let Some(o) = (unsafe { out.as_mut() }) else { return GsensStatus::NullPointer };
        if o.struct_size != size_u32::<GsensEstimate>() {
            return GsensStatus::WrongSize;
        }
        let normal = c.calibrator.calibrator().estimator().normal_equations();
        let (e, kept) = solve_in_observable_axes(normal, &c.criteria);
        let sigma = e.sigma_hz_per_mps2().map(|s| s * c.colour);
        let mut cov = [0.0; 9];
        for i in 0..3 {
            for j in 0..3 {
                cov[3 * i + j] = e.covariance[i][j] * c.colour * c.colour;
            }
        }
        *o = GsensEstimate {
            struct_size: o.struct_size,
            observable: kept.map(u8::from),
            gamma_hz_per_mps2: [0, 1, 2].map(|i| if kept[i] { e.gamma_hz_per_mps2[i] } else { f64::NAN }),
            sigma_hz_per_mps2: [0, 1, 2].map(|i| if kept[i] { sigma[i] } else { f64::INFINITY }),
            covariance_hz_per_mps2_sq: cov,
            residual_sigma_rad: libm::sqrt(e.residual_variance_rad2.max(0.0)),
            epochs_used: e.epochs,
            epochs_fed: c.fed,
        };
        GsensStatus::Ok
    })
}

/// A compensator for Γ̂ `gamma_hz_per_mps2` (3 values, finite) and
/// `carrier_ratio` (finite, > 0), in `*out`.
#[unsafe(no_mangle)]
pub extern "C" fn gsens_compensator_init(
    gamma_hz_per_mps2: *const f64,
    carrier_ratio: f64,
    out: *mut GsensCompensator,
) -> GsensStatus {
    guarded(|| {
        if out.is_null() {
            return GsensStatus::NullPointer;
        }
        let g = match read_accel(gamma_hz_per_mps2) {
            Ok(g) => g,
            Err(s) => return s,
        };
        if !carrier_ratio.is_finite() {
            return GsensStatus::NotFinite;
        }
        if carrier_ratio <= 0.0 {
            return GsensStatus::InvalidConfig;
        }
        // SAFETY: non-null; the caller's GsensCompensator.
        unsafe { out.write(GsensCompensator { gamma_hz_per_mps2: g, carrier_ratio }) };
        GsensStatus::Ok
    })
}

/// The NCO frequency correction \[Hz\] for specific force `accel_mps2` (3
/// values, \[m/s²\]): −aᵀΓ̂·carrier_ratio, in `*correction_hz`. Add it to the
/// carrier NCO's frequency command at every loop update.
#[unsafe(no_mangle)]
pub extern "C" fn gsens_compensator_nco_correction_hz(
    compensator: *const GsensCompensator,
    accel_mps2: *const f64,
    correction_hz: *mut f64,
) -> GsensStatus {
    guarded(|| {
        // SAFETY: null or the caller's GsensCompensator.
        let Some(c) = (unsafe { compensator.as_ref() }) else { return GsensStatus::NullPointer };
        if correction_hz.is_null() {
            return GsensStatus::NullPointer;
        }
        let a = match read_accel(accel_mps2) {
            Ok(a) => a,
            Err(s) => return s,
        };
        let hz = Compensator { gamma_hz_per_mps2: c.gamma_hz_per_mps2 }.nco_correction_hz(&a) * c.carrier_ratio;
        // SAFETY: non-null.
        unsafe { correction_hz.write(hz) };
        GsensStatus::Ok
    })
}

/// Halts on a panic (bare-metal staticlib only; see the `panic-halt` feature).
#[cfg(all(feature = "panic-halt", not(feature = "std"), not(test)))]
#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    loop {
        core::hint::spin_loop();
    }
}
