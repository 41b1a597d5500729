//! One carrier-tracking channel at the correlator level.
//!
//! # What is simulated
//!
//! The channel keeps the *true* carrier phase error e = θ_signal − θ_replica
//! \[rad\] (docs/conventions.md sign: positive when the incoming carrier leads the
//! replica), unwrapped, so that cycle slips stay visible. The replica is
//! driven by the core's [`CarrierLoop`] (loop filter + NCO, the very code the
//! estimator's loop models run: shared, not copied). Integration k lasts T
//! seconds; during it
//!
//! - the signal carrier runs at `signal_freq_hz` (the satellite Doppler at
//!   the integration's centre — the mean over the interval for a linearly
//!   varying Doppler);
//! - the replica runs at the NCO command plus `nco_bias_hz`, the oscillator
//!   bias Δf = f_carrier·y + aᵀΓ (docs/conventions.md: the bias is *added* to the
//!   commanded frequency) plus any Doppler aiding.
//!
//! The phase error is then a linear ramp over the interval,
//! e(t) = φ_k + 2δ·(t − t_mid)/T with
//! δ = π·T·(f_signal − f_nco − Δf) and φ_k its value at the centre. The prompt
//! correlator output is
//!
//! ```text
//! P_k = I + jQ = A·d·(1/T)∫ e^{j e(t)} dt + n = A·d·sinc(δ)·e^{jφ_k} + n,   sinc(δ) = sin δ / δ
//! ```
//!
//! (the mean of e^{jφ} over a linear ramp, computed analytically), with d = ±1
//! the navigation data bit and n complex white Gaussian noise. The noise is
//! drawn in the frame of the signal phasor, n = e^{jφ_k}·n' (the same process:
//! circular Gaussian noise is rotation-invariant), so that
//! arg P_k = φ_k + arg(A·d·sinc δ + n') exactly and the discriminator is that
//! sum reduced modulo π or 2π — off the loop's critical path, which is what
//! makes a channel update ~40 ns.
//!
//! # Normalization of the correlator outputs
//!
//! A = 1 and each of I, Q carries noise of variance σ² = 1/(2·(C/N0)·T), so
//! the coherent SNR per integration is A²/(2σ²) = (C/N0)·T (C/N0 as a ratio,
//! Hz). At high SNR the atan discriminator's noise then has variance
//! σ² = 1/(2·(C/N0)·T) per update, and a loop of noise bandwidth Bn turns it
//! into the phase jitter Bn/(C/N0) — the first term of the Costas formula of
//! docs/conventions.md (Kaplan & Hegarty, *Understanding GPS*, 2nd ed., §5.6.2).
//!
//! # Discriminators
//!
//! - [`Discriminator::Costas`]: atan(Q/I), insensitive to the data bit, stable
//!   points every π rad (a slip is a jump of π of the true error);
//! - [`Discriminator::Pilot`]: atan2(Q, I) on a data-less pilot, stable points
//!   every 2π.
//!
//! The discriminator output is the mean-phase estimate φ_k of
//! the difference equations of `gsens_core::DiscretePll`; the channel then calls
//! [`CarrierLoop::close`], so without noise and within ±π/2 it reproduces
//! [`gsens_core::DiscretePll`] exactly.
//!
//! # Lock indicator, slips, C/N0 estimate
//!
//! Prompt I/Q are summed coherently over each data bit (20 ms, aligned with
//! the bit edges, as after bit synchronization; one integration when T = 20 ms).
//! Per bit block:
//!
//! - phase-lock indicator (Van Dierendonck, in Parkinson & Spilker vol. I
//!   ch. 8): the normalized cos 2φ estimate (I² − Q²)/(I² + Q²), low-pass
//!   filtered with time constant τ; the channel is *locked* while it exceeds a
//!   threshold. Each locked → unlocked transition counts as a loss of lock;
//! - C/N0 (the receiver's estimate): the moments method (Pauluzzi & Beaulieu
//!   2000) over a window of blocks: M2 = ⟨|P|²⟩, M4 = ⟨|P|⁴⟩,
//!   Pd = √(2M2² − M4), Pn = M2 − Pd, C/N0 = Pd/(Pn·T_block).
//!
//! Cycle slips are counted from the true phase error, once the indicator has
//! first declared lock: the lock point is the multiple of the slip period P
//! (π or 2π) the error settled on; whenever the error at an integration centre
//! leaves it by more than 3P/4 the lock point moves to the nearest multiple and
//! the slip count grows by the number of periods jumped. Nothing is scripted:
//! slips and losses of lock come out of the noise and the dynamics.

use core::f64::consts::{FRAC_PI_2, PI, TAU};

use gsens_core::{CarrierLoop, LoopFilterCoeffs};
use rand::{Rng, RngExt};
use rand_distr::StandardNormal;
use rand_xoshiro::Xoshiro256PlusPlus;
use serde::{Deserialize, Serialize};

/// Duration of a GPS L1 C/A navigation data bit \[s\] (50 bit/s).
pub const DATA_BIT_S: f64 = 0.020;

/// The carrier phase discriminator.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Discriminator {
    /// Costas atan(Q/I): data-insensitive, ±π/2 range, slips of π.
    Costas,
    /// Pure PLL atan2(Q, I) on a data-less pilot: ±π range, slips of 2π.
    Pilot,
}

impl Discriminator {
    /// The spacing of the loop's stable points \[rad\]: π (Costas) or 2π (pilot).
    pub fn slip_period_rad(self) -> f64 {
        match self {
            Discriminator::Costas => PI,
            Discriminator::Pilot => TAU,
        }
    }

    /// The discriminator output for prompt I/Q \[rad\].
    #[inline]
    pub fn apply(self, i: f64, q: f64) -> f64 {
        match self {
            Discriminator::Costas => {
                if i != 0.0 {
                    atan(q / i)
                } else if q >= 0.0 {
                    FRAC_PI_2
                } else {
                    -FRAC_PI_2
                }
            }
            Discriminator::Pilot => atan2(q, i),
        }
    }
}

/// Settings of a channel that do not change while it runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChannelConfig {
    /// Loop filter (shared with the core's models).
    pub coeffs: LoopFilterCoeffs,
    /// Loop update interval = coherent integration time T \[s\]; 20 ms must be a
    /// whole number of them.
    pub interval_s: f64,
    /// The discriminator.
    pub discriminator: Discriminator,
    /// Time constant of the lock indicator's low-pass filter \[s\].
    pub lock_tau_s: f64,
    /// The channel is declared locked while the filtered cos 2φ estimate
    /// exceeds this (0.5 ↔ |φ| ≲ 30°).
    pub lock_threshold: f64,
    /// Window of the moments C/N0 estimator \[s\].
    pub cn0_window_s: f64,
}

impl ChannelConfig {
    /// A channel with the default indicator settings (τ = 0.2 s, threshold
    /// 0.5, C/N0 window 1 s).
    pub fn new(coeffs: LoopFilterCoeffs, interval_s: f64, discriminator: Discriminator) -> Self {
        ChannelConfig { coeffs, interval_s, discriminator, lock_tau_s: 0.2, lock_threshold: 0.5, cn0_window_s: 1.0 }
    }

    /// Integrations per data bit, round(20 ms / T) (at least 1).
    pub fn integrations_per_bit(&self) -> u32 {
        ((DATA_BIT_S / self.interval_s).round() as u32).max(1)
    }
}

/// How a channel starts tracking (what acquisition hands over).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChannelStart {
    /// True C/N0 \[dB-Hz\] (may be changed later with [`Channel::set_cn0_dbhz`];
    /// `f64::INFINITY` turns the thermal noise off).
    pub cn0_dbhz: f64,
    /// NCO frequency preloaded into the loop \[Hz\] (acquisition estimate).
    pub preload_freq_hz: f64,
    /// NCO frequency rate preloaded (3rd-order loops only) \[Hz/s\].
    pub preload_rate_hz_per_s: f64,
    /// True phase error at the start of the first integration \[rad\].
    pub initial_phase_err_rad: f64,
    /// Index of the first integration within its data bit (0 ≤ · < integrations per bit).
    pub bit_offset: u32,
}

/// The outputs of one integration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Integration {
    /// Prompt in-phase sum.
    pub i: f64,
    /// Prompt quadrature sum.
    pub q: f64,
    /// Discriminator output \[rad\].
    pub discriminator_rad: f64,
    /// True phase error at the integration's centre, unwrapped \[rad\].
    pub true_phase_err_rad: f64,
}

/// What a channel reports at a log epoch: statistics of the integrations
/// since the previous call of [`Channel::take_log`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LogSnapshot {
    /// The latest discriminator output \[rad\].
    pub last_rad: f64,
    /// The mean of the discriminator outputs since the previous snapshot \[rad\].
    pub mean_rad: f64,
    /// The latest true phase error (integration centre, unwrapped) \[rad\].
    pub true_last_rad: f64,
    /// The mean true phase error since the previous snapshot \[rad\].
    pub true_mean_rad: f64,
    /// Number of integrations in the means.
    pub count: u32,
    /// Lock indicator state.
    pub locked: bool,
    /// The receiver's C/N0 estimate \[dB-Hz\].
    pub cn0_est_dbhz: f64,
    /// The replica's accumulated phase commanded by the NCO at the end of
    /// the latest integration \[cycles\] (what the receiver knows: without
    /// the oscillator's bias).
    pub nco_phase_cycles: f64,
    /// The NCO frequency commanded during the latest integration \[Hz\].
    pub nco_freq_hz: f64,
}

/// Counters of a channel's history.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
pub struct ChannelStats {
    /// Integrations run.
    pub integrations: u64,
    /// Integrations during which the lock indicator read locked.
    pub integrations_locked: u64,
    /// Cycle slips (periods jumped by the true phase error after first lock).
    pub cycle_slips: u64,
    /// Locked → unlocked transitions of the lock indicator.
    pub losses_of_lock: u64,
}

/// A tracking channel: correlator, discriminator, the core's loop filter and
/// NCO, lock indicator and C/N0 estimator (see the module docs).
#[derive(Debug, Clone)]
pub struct Channel {
    carrier: CarrierLoop,
    disc: Discriminator,
    pi_t: f64,
    interval_s: f64,
    /// The NCO's commanded phase at the end of the latest integration \[cycles\].
    nco_phase_cycles: f64,
    /// The NCO's commanded frequency during the latest integration \[Hz\].
    nco_used_hz: f64,
    /// True phase error at the start of the current integration \[rad\], unwrapped.
    err_start_rad: f64,
    noise_sigma: f64,
    cn0_true_dbhz: f64,
    rng: Xoshiro256PlusPlus,
    // data bits
    ints_per_bit: u32,
    int_in_bit: u32,
    data_sign: f64,
    bit_pool: u64,
    bits_left: u32,
    // per-bit coherent sums
    blk_i: f64,
    blk_q: f64,
    block_s: f64,
    // lock indicator
    lock_gain: f64,
    lock_threshold: f64,
    lock_lpf: f64,
    locked: bool,
    ever_locked: bool,
    // slips
    slip_period_rad: f64,
    lock_point_rad: f64,
    // C/N0 moments estimator
    m2_sum: f64,
    m4_sum: f64,
    m_count: u32,
    blocks_per_window: u32,
    cn0_est_dbhz: f64,
    // log accumulators
    disc_sum: f64,
    true_sum: f64,
    log_count: u32,
    last: Integration,
    stats: ChannelStats,
}

/// Noise standard deviation per I/Q component for C/N0 \[dB-Hz\] and T \[s\]:
/// σ = √(1/(2·(C/N0)·T)) with A = 1 (0 for an infinite C/N0).
pub fn noise_sigma(cn0_dbhz: f64, interval_s: f64) -> f64 {
    if cn0_dbhz.is_infinite() && cn0_dbhz > 0.0 {
        0.0
    } else {
        (0.5 / (gsens_core::units::cn0_dbhz_to_ratio_hz(cn0_dbhz) * interval_s)).sqrt()
    }
}

/// π/2 split in two for an exact Cody–Waite range reduction (fdlibm's pio2_1, pio2_1t).
const PIO2_HI: f64 = 1.570_796_326_734_125_6;
const PIO2_LO: f64 = 6.077_100_506_506_192e-11;

/// Round to nearest (ties to even) for |x| < 2⁵¹ without a libm call (the
/// baseline x86-64 target has no `roundsd`): adding and subtracting 1.5·2⁵²
/// leaves the nearest integer.
#[inline]
pub fn round_nearest(x: f64) -> f64 {
    const MAGIC: f64 = 6_755_399_441_055_744.0;
    (x + MAGIC) - MAGIC
}

/// (sin x, cos x) by reduction to |r| ≤ π/4 and Taylor polynomials through
/// r¹¹ / r¹² (truncation < 7e-12 absolute), evaluated by Estrin's scheme for a
/// short dependency chain: about three times faster than the libm pair, which
/// matters at ~10⁸ calls per simulated session. Valid for |x| < 2⁵⁰.
#[inline]
pub fn sin_cos(x: f64) -> (f64, f64) {
    let n = round_nearest(x * core::f64::consts::FRAC_2_PI);
    let r = (x - n * PIO2_HI) - n * PIO2_LO;
    let r2 = r * r;
    let r4 = r2 * r2;
    let r8 = r4 * r4;
    let s_lo = -1.0 / 6.0 + r2 * (1.0 / 120.0);
    let s_hi = -1.0 / 5040.0 + r2 * (1.0 / 362_880.0);
    let s = r + (r * r2) * (s_lo + r4 * s_hi + r8 * (-1.0 / 39_916_800.0));
    let c_lo = 1.0 / 24.0 + r2 * (-1.0 / 720.0);
    let c_hi = 1.0 / 40_320.0 + r2 * (-1.0 / 3_628_800.0);
    let c = (1.0 - 0.5 * r2) + r4 * (c_lo + r4 * c_hi + r8 * (1.0 / 479_001_600.0));
    match (n as i64) & 3 {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
}

/// atan x by the classic reductions (|x| > 1 → π/2 − atan(1/x);
/// |x| > 2 − √3 → π/6 + atan((√3·x − 1)/(√3 + x))) to |r| ≤ 0.268 and an odd
/// Taylor polynomial through r¹⁷ (truncation < 1e-12), Estrin-evaluated.
#[inline]
pub fn atan(x: f64) -> f64 {
    const TAN_PI_12: f64 = 0.267_949_192_431_122_7;
    const SQRT3: f64 = 1.732_050_807_568_877_2;
    let mut a = x.abs();
    let mut off = 0.0;
    let inverted = a > 1.0;
    if inverted {
        a = 1.0 / a;
    }
    if a > TAN_PI_12 {
        a = (SQRT3 * a - 1.0) / (SQRT3 + a);
        off = core::f64::consts::FRAC_PI_6;
    }
    let z = a * a;
    let z2 = z * z;
    let z4 = z2 * z2;
    let z8 = z4 * z4;
    let p01 = 1.0 - z * (1.0 / 3.0);
    let p23 = 1.0 / 5.0 - z * (1.0 / 7.0);
    let p45 = 1.0 / 9.0 - z * (1.0 / 11.0);
    let p67 = 1.0 / 13.0 - z * (1.0 / 15.0);
    let p = (p01 + z2 * p23) + z4 * (p45 + z2 * p67) + z8 * (1.0 / 17.0);
    let mut y = off + a * p;
    if inverted {
        y = FRAC_PI_2 - y;
    }
    y.copysign(x)
}

/// atan2(y, x) from [`atan`]: atan(y/x), shifted by ±π for x < 0
/// (range (−π, π]; ±π/2 on the y axis, 0 at the origin).
#[inline]
pub fn atan2(y: f64, x: f64) -> f64 {
    if x > 0.0 {
        atan(y / x)
    } else if x < 0.0 {
        let a = atan(y / x);
        if y >= 0.0 { a + PI } else { a - PI }
    } else if y == 0.0 {
        0.0
    } else {
        FRAC_PI_2.copysign(y)
    }
}

/// sin(δ)/δ, with a Taylor polynomial for small δ (|error| < 2e-10 there).
#[inline]
fn sinc(delta: f64) -> f64 {
    let d2 = delta * delta;
    if d2 < 0.09 { 1.0 - d2 * (1.0 / 6.0 - d2 * (1.0 / 120.0 - d2 * (1.0 / 5040.0))) } else { delta.sin() / delta }
}

impl Channel {
    /// A channel starting as described by `start`, with its own random
    /// stream `rng` (noise and data bits).
    pub fn new(cfg: &ChannelConfig, start: &ChannelStart, rng: Xoshiro256PlusPlus) -> Self {
        let mut carrier = CarrierLoop::new(cfg.coeffs, cfg.interval_s);
        carrier.preload(start.preload_freq_hz, start.preload_rate_hz_per_s);
        let ints_per_bit = cfg.integrations_per_bit();
        let block_s = cfg.interval_s * ints_per_bit as f64;
        let mut ch = Channel {
            carrier,
            disc: cfg.discriminator,
            pi_t: PI * cfg.interval_s,
            interval_s: cfg.interval_s,
            nco_phase_cycles: 0.0,
            nco_used_hz: 0.0,
            err_start_rad: start.initial_phase_err_rad,
            noise_sigma: noise_sigma(start.cn0_dbhz, cfg.interval_s),
            cn0_true_dbhz: start.cn0_dbhz,
            rng,
            ints_per_bit,
            int_in_bit: start.bit_offset % ints_per_bit,
            data_sign: 1.0,
            bit_pool: 0,
            bits_left: 0,
            blk_i: 0.0,
            blk_q: 0.0,
            block_s,
            lock_gain: (block_s / cfg.lock_tau_s).min(1.0),
            lock_threshold: cfg.lock_threshold,
            lock_lpf: 0.0,
            locked: false,
            ever_locked: false,
            slip_period_rad: cfg.discriminator.slip_period_rad(),
            lock_point_rad: 0.0,
            m2_sum: 0.0,
            m4_sum: 0.0,
            m_count: 0,
            blocks_per_window: ((cfg.cn0_window_s / block_s).round() as u32).max(2),
            cn0_est_dbhz: if start.cn0_dbhz.is_finite() { start.cn0_dbhz } else { 99.0 },
            disc_sum: 0.0,
            true_sum: 0.0,
            log_count: 0,
            last: Integration { i: 0.0, q: 0.0, discriminator_rad: 0.0, true_phase_err_rad: 0.0 },
            stats: ChannelStats::default(),
        };
        ch.draw_bit();
        ch
    }

    /// Sets the true C/N0 \[dB-Hz\] (it changes with elevation).
    pub fn set_cn0_dbhz(&mut self, cn0_dbhz: f64) {
        self.cn0_true_dbhz = cn0_dbhz;
        self.noise_sigma = noise_sigma(cn0_dbhz, self.carrier.interval_s());
    }

    /// The true C/N0 \[dB-Hz\].
    pub fn cn0_true_dbhz(&self) -> f64 {
        self.cn0_true_dbhz
    }

    /// The receiver's C/N0 estimate \[dB-Hz\] (the true value until the first
    /// estimator window has completed: acquisition's estimate, taken as exact).
    pub fn cn0_est_dbhz(&self) -> f64 {
        self.cn0_est_dbhz
    }

    /// The lock indicator's state.
    pub fn locked(&self) -> bool {
        self.locked
    }

    /// The filtered cos 2φ estimate of the lock indicator.
    pub fn lock_indicator(&self) -> f64 {
        self.lock_lpf
    }

    /// Counters since the start.
    pub fn stats(&self) -> ChannelStats {
        self.stats
    }

    /// The NCO's commanded frequency for the next integration \[Hz\].
    pub fn nco_freq_hz(&self) -> f64 {
        self.carrier.nco_freq_hz()
    }

    /// The latest integration's outputs.
    pub fn last(&self) -> Integration {
        self.last
    }

    #[inline]
    fn draw_bit(&mut self) {
        if self.disc == Discriminator::Pilot {
            self.data_sign = 1.0;
            return;
        }
        if self.bits_left == 0 {
            self.bit_pool = self.rng.next_u64();
            self.bits_left = 64;
        }
        self.data_sign = if self.bit_pool & 1 == 1 { 1.0 } else { -1.0 };
        self.bit_pool >>= 1;
        self.bits_left -= 1;
    }

    /// One integration of T seconds: the signal carrier at `signal_freq_hz`,
    /// the replica at the NCO command plus `nco_bias_hz` (both means over the
    /// interval, the bias constant over it) \[Hz\]. Correlates, discriminates,
    /// closes the loop.
    #[inline]
    pub fn step(&mut self, signal_freq_hz: f64, nco_bias_hz: f64) -> Integration {
        self.step_varying(signal_freq_hz, nco_bias_hz, nco_bias_hz)
    }

    /// [`Channel::step`] with a bias that varies over the integration: its
    /// mean `nco_bias_hz` advances the replica, and the correlator's phase
    /// error, the mean of the error's ramp over the integration, takes it
    /// weighted by the time left, 2(1 − s/T)/T with s from the start:
    /// `nco_bias_weighted_hz` (the mean again for a constant bias).
    #[inline]
    pub fn step_varying(&mut self, signal_freq_hz: f64, nco_bias_hz: f64, nco_bias_weighted_hz: f64) -> Integration {
        // Half the phase-error ramp over the interval: δ = πT(f_sig − f_nco − Δf).
        let nco_hz = self.carrier.nco_freq_hz();
        let delta = self.pi_t * (signal_freq_hz - nco_hz - nco_bias_hz);
        // The receiver's own record of its replica: the commanded frequency, without the oscillator's bias.
        self.nco_phase_cycles += nco_hz * self.interval_s;
        self.nco_used_hz = nco_hz;
        let phi_mid = self.err_start_rad + self.pi_t * (signal_freq_hz - nco_hz - nco_bias_weighted_hz);
        self.err_start_rad += 2.0 * delta;
        // The noise is drawn in the frame of the mean signal phasor (complex
        // white Gaussian noise is rotation-invariant, so this is the same
        // process): P = e^{jφ}·z with z = A·d·sinc(δ) + n'. Then
        // arg P = φ + arg z exactly, and the discriminator is φ + arg z
        // reduced modulo π (Costas: atan(Q/I)) or 2π (pilot: atan2(Q, I)).
        // Only that reduction sits on the loop's critical path (NCO →
        // δ → φ → discriminator → filter → NCO); arg z, sin/cos φ and I/Q,
        // which feed the lock indicator and C/N0 estimator, can proceed in
        // parallel — the reason for this form.
        let n_i: f64 = self.rng.sample(StandardNormal);
        let n_q: f64 = self.rng.sample(StandardNormal);
        let zr = self.data_sign * sinc(delta) + self.noise_sigma * n_i;
        let zi = self.noise_sigma * n_q;
        let d = match self.disc {
            Discriminator::Costas => {
                let arg_z = if zr != 0.0 { atan(zi / zr) } else { FRAC_PI_2.copysign(zi) };
                let x = phi_mid + arg_z;
                x - PI * round_nearest(x * (1.0 / PI))
            }
            Discriminator::Pilot => {
                let x = phi_mid + atan2(zi, zr);
                x - TAU * round_nearest(x * (1.0 / TAU))
            }
        };
        let (s, c) = sin_cos(phi_mid);
        let i = zr * c - zi * s;
        let q = zr * s + zi * c;
        self.carrier.close(d);

        // Slips: the true error leaving its lock point by more than 3P/4.
        if self.ever_locked {
            let off = phi_mid - self.lock_point_rad;
            if off.abs() > 0.75 * self.slip_period_rad {
                let n = round_nearest(off / self.slip_period_rad);
                self.lock_point_rad += n * self.slip_period_rad;
                self.stats.cycle_slips += n.abs() as u64;
            }
        }

        self.stats.integrations += 1;
        if self.locked {
            self.stats.integrations_locked += 1;
        }
        self.disc_sum += d;
        self.true_sum += phi_mid;
        self.log_count += 1;
        self.last = Integration { i, q, discriminator_rad: d, true_phase_err_rad: phi_mid };

        // Per-bit block: lock indicator, C/N0 moments, next data bit.
        self.blk_i += i;
        self.blk_q += q;
        self.int_in_bit += 1;
        if self.int_in_bit >= self.ints_per_bit {
            self.end_block(phi_mid);
        }
        self.last
    }

    #[cold]
    fn end_block(&mut self, phi_mid: f64) {
        self.int_in_bit = 0;
        let (bi, bq) = (self.blk_i, self.blk_q);
        self.blk_i = 0.0;
        self.blk_q = 0.0;
        let p2 = bi * bi + bq * bq;
        if p2 > 0.0 {
            let cos2 = (bi * bi - bq * bq) / p2;
            self.lock_lpf += self.lock_gain * (cos2 - self.lock_lpf);
        }
        let now_locked = self.lock_lpf > self.lock_threshold;
        if now_locked && !self.ever_locked {
            self.ever_locked = true;
            self.lock_point_rad = round_nearest(phi_mid / self.slip_period_rad) * self.slip_period_rad;
        }
        if self.locked && !now_locked {
            self.stats.losses_of_lock += 1;
        }
        self.locked = now_locked;

        self.m2_sum += p2;
        self.m4_sum += p2 * p2;
        self.m_count += 1;
        if self.m_count >= self.blocks_per_window {
            let n = self.m_count as f64;
            let m2 = self.m2_sum / n;
            let m4 = self.m4_sum / n;
            let pd = (2.0 * m2 * m2 - m4).max(0.0).sqrt();
            let pn = m2 - pd;
            if pd > 0.0 && pn > 0.0 {
                self.cn0_est_dbhz = 10.0 * (pd / (pn * self.block_s)).log10();
            } else if pd > 0.0 {
                self.cn0_est_dbhz = 99.0;
            }
            self.m2_sum = 0.0;
            self.m4_sum = 0.0;
            self.m_count = 0;
        }
        self.draw_bit();
    }

    /// Statistics since the previous call (the log accumulators are reset).
    pub fn take_log(&mut self) -> LogSnapshot {
        let n = self.log_count.max(1) as f64;
        let snap = LogSnapshot {
            last_rad: self.last.discriminator_rad,
            mean_rad: self.disc_sum / n,
            true_last_rad: self.last.true_phase_err_rad,
            true_mean_rad: self.true_sum / n,
            count: self.log_count,
            locked: self.locked,
            cn0_est_dbhz: self.cn0_est_dbhz,
            nco_phase_cycles: self.nco_phase_cycles,
            nco_freq_hz: self.nco_used_hz,
        };
        self.disc_sum = 0.0;
        self.true_sum = 0.0;
        self.log_count = 0;
        snap
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use gsens_core::{DiscretePll, LoopSpec};

    fn cfg() -> ChannelConfig {
        ChannelConfig::new(LoopSpec::PAPER.coeffs().unwrap(), 0.001, Discriminator::Costas)
    }

    #[test]
    fn noiseless_channel_reproduces_the_core_discrete_loop() {
        let c = cfg();
        let start = ChannelStart {
            cn0_dbhz: f64::INFINITY,
            preload_freq_hz: 1234.5,
            preload_rate_hz_per_s: 0.0,
            initial_phase_err_rad: 0.0,
            bit_offset: 3,
        };
        let mut ch = Channel::new(&c, &start, crate::rng::substream(1, 2));
        let mut pll = DiscretePll::new(c.coeffs, c.interval_s);
        for k in 0..5000 {
            let df = 0.3 * (k as f64 * 0.004).sin();
            let out = ch.step(1234.5, df);
            let want = pll.step(df);
            assert!((out.discriminator_rad - want).abs() < 1e-9, "{k}: {} vs {want}", out.discriminator_rad);
            assert!((out.true_phase_err_rad - want).abs() < 1e-9);
        }
        assert_eq!(ch.stats().cycle_slips, 0);
        assert!(ch.locked());
    }

    /// A channel start with no noise, the NCO preloaded to `preload_freq_hz`
    /// and the phase error at `initial_phase_err_rad`.
    fn noiseless_start(preload_freq_hz: f64, initial_phase_err_rad: f64) -> ChannelStart {
        ChannelStart {
            cn0_dbhz: f64::INFINITY,
            preload_freq_hz,
            preload_rate_hz_per_s: 0.0,
            initial_phase_err_rad,
            bit_offset: 0,
        }
    }

    /// The NCO's record and the true phase error give the phase the loop was
    /// fed, loop or no loop: 2π(c − f·T/2) + φ at an integration's centre is
    /// the signal's phase minus 2π∫Δf (θ_in = θ_NCO + φ).
    #[test]
    fn nco_phase_plus_phase_error_is_the_input_phase() {
        let cfg = cfg();
        let t = cfg.interval_s;
        let mut ch = Channel::new(&cfg, &noiseless_start(480.0, 0.3), crate::rng::substream(3, 1));
        let f_signal_hz = 500.0;
        let bias_hz = |k: usize| 0.4 * (k as f64 * 0.0113).sin();
        let mut bias_sum = 0.0;
        for k in 0..3000 {
            let b = bias_hz(k);
            let out = ch.step(f_signal_hz, b);
            let snap = ch.take_log();
            let n = (k + 1) as f64;
            // The true input phase at this integration's centre.
            let theta_in = 0.3 + core::f64::consts::TAU * (f_signal_hz * (n - 0.5) * t - (bias_sum + 0.5 * b) * t);
            bias_sum += b;
            let from_log =
                core::f64::consts::TAU * (snap.nco_phase_cycles - snap.nco_freq_hz * t / 2.0) + out.true_phase_err_rad;
            assert!((from_log - theta_in).abs() < 1e-9 * theta_in.abs().max(1.0), "{k}: {from_log} vs {theta_in}");
        }
    }

    /// With a bias that varies within each integration the true phase error
    /// is the mean, over the integration, of the continuous error: with the
    /// NCO's record, 2π(c − f·T/2) + φ is the signal's phase less 2π∫Δf
    /// averaged over the integration (here by composite Simpson on 64
    /// panels), where the mean of its end values (a bias constant over the
    /// integration) would be off by 2π·T²·Δf′/12, up to 4.7·10⁻⁴ rad here.
    #[test]
    fn a_varying_bias_enters_the_phase_error_averaged_over_the_integration() {
        let cfg = ChannelConfig::new(LoopSpec::PAPER.coeffs().unwrap(), 0.02, Discriminator::Costas);
        let t = cfg.interval_s;
        let mut ch = Channel::new(&cfg, &noiseless_start(500.0, 0.0), crate::rng::substream(3, 2));
        let f_signal_hz = 500.0;
        let w = core::f64::consts::TAU * 0.9;
        let bias_hz = |x: f64| 0.4 * (w * x).sin();
        // ∫₀ˣ Δf: the oscillator's phase in cycles.
        let cycles = |x: f64| 0.4 * (1.0 - (w * x).cos()) / w;
        let panels = 64;
        let simpson = |f: &dyn Fn(f64) -> f64, a: f64| {
            let h = t / panels as f64;
            let sum: f64 = (0..=panels)
                .map(|i| {
                    let c = if i == 0 || i == panels {
                        1.0
                    } else if i % 2 == 1 {
                        4.0
                    } else {
                        2.0
                    };
                    c * f(a + i as f64 * h)
                })
                .sum();
            sum * h / 3.0 / t
        };
        for k in 0..200 {
            let t0 = k as f64 * t;
            let mean = simpson(&bias_hz, t0);
            let weighted = simpson(&|x: f64| bias_hz(x) * 2.0 * (1.0 - (x - t0) / t), t0);
            let out = ch.step_varying(f_signal_hz, mean, weighted);
            let snap = ch.take_log();
            let centre = t0 + t / 2.0;
            let theta_in = core::f64::consts::TAU * (f_signal_hz * centre - simpson(&cycles, t0));
            let from_log =
                core::f64::consts::TAU * (snap.nco_phase_cycles - snap.nco_freq_hz * t / 2.0) + out.true_phase_err_rad;
            assert!((from_log - theta_in).abs() < 1e-9 * theta_in.abs().max(1.0), "{k}: {from_log} vs {theta_in}");
        }
    }

    #[test]
    fn costas_is_data_insensitive_and_pilot_is_not() {
        assert!((Discriminator::Costas.apply(-1.0, -0.1) - Discriminator::Costas.apply(1.0, 0.1)).abs() < 1e-15);
        assert!((Discriminator::Pilot.apply(-1.0, 0.0) - PI).abs() < 1e-15);
        assert_eq!(Discriminator::Costas.apply(0.0, -1.0), -FRAC_PI_2);
    }

    #[test]
    fn fast_sin_cos_and_atan_match_libm() {
        let mut x = -40.0;
        while x < 40.0 {
            let (s, c) = sin_cos(x);
            assert!((s - x.sin()).abs() < 1e-11 && (c - x.cos()).abs() < 1e-11, "{x}");
            assert!((atan(x) - x.atan()).abs() < 1e-12, "{x}");
            assert!((atan(x * 1e-3) - (x * 1e-3).atan()).abs() < 1e-15, "{x}");
            assert_eq!(round_nearest(x), x.round_ties_even());
            for y in [-2.0, -1e-3, 0.0, 0.5, 3.0] {
                assert!((atan2(y, x) - y.atan2(x)).abs() < 1e-12, "{y} {x}");
            }
            x += 0.0137;
        }
        assert!((atan(1e300) - FRAC_PI_2).abs() < 1e-15);
        assert!((atan(-1e-300) + 1e-300).abs() < 1e-310);
    }

    #[test]
    fn sinc_polynomial_matches() {
        for &d in &[0.0f64, 1e-3, 0.1, 0.29, 0.31, 1.0] {
            let exact = if d == 0.0 { 1.0 } else { d.sin() / d };
            assert!((sinc(d) - exact).abs() < 1e-9);
        }
    }

    #[test]
    fn noise_normalization() {
        // SNR per integration A²/(2σ²) = C/N0·T.
        let s = noise_sigma(40.0, 0.001);
        assert!((1.0 / (2.0 * s * s) - 10.0).abs() < 1e-9);
        assert_eq!(noise_sigma(f64::INFINITY, 0.001), 0.0);
    }
}
