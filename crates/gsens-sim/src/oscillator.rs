//! Crystal-oscillator frequency noise: the fractional frequency y(t) that
//! every tracking channel sees as Δf = f_carrier·y (docs/conventions.md).
//!
//! # Model
//!
//! y(t) = y_noise(t) + y_det(t), with
//!
//! - **power-law noise**, one-sided PSD S_y(f) = h₂f² + h₀ + h₋₁/f + h₋₂/f²
//!   (IEEE Std 1139; Barnes et al., "Characterization of frequency
//!   stability", IEEE Trans. IM-20(2), 1971): white PM (h₂), white FM (h₀),
//!   flicker FM (h₋₁), random-walk FM (h₋₂);
//! - **deterministic terms** (aging and temperature):
//!   y_det(t) = y_offset + D·t + A·sin(2π·t/P + φ₀).
//!
//! # Generation
//!
//! [`Oscillator`] produces, for k = 0, 1, 2, …, the value of y *averaged over
//! the interval* [kΔt, (k+1)Δt], so that the phase of a carrier driven by the
//! oscillator is exactly θ_{k+1} − θ_k = 2π·f_c·ȳ_k·Δt.
//!
//! - White FM: ȳ_k = σ·w_k with σ² = h₀/(2Δt) (a one-sided PSD h₀ up to the
//!   Nyquist frequency 1/(2Δt); its Allan variance is exactly h₀/(2τ) for
//!   τ = mΔt).
//! - Random-walk FM: y is a Wiener process with diffusion N = 2π²h₋₂
//!   (two-sided PSD of dy/dt; then S_y = N/(2π²f²) one-sided). It is sampled
//!   exactly at the interval ends, y_{k+1} = y_k + √(NΔt)·w, and the interval
//!   mean is (y_k + y_{k+1})/2 plus the Brownian-bridge term of variance
//!   NΔt/12, which is merged into the white-FM draw.
//! - Flicker FM: white noise through a rational approximation of the
//!   Kasdin–Walter fractional integrator (1 − z⁻¹)^(−1/2) (N. J. Kasdin,
//!   "Discrete simulation of colored noise and stochastic processes and 1/f^α
//!   power law noise generation", Proc. IEEE 83(5), 1995, §IV): a cascade of
//!   first-order pole–zero sections (the method of J. A. Barnes & S. Jarvis,
//!   NBS Tech. Note 604, 1971), two per decade, the poles at
//!   f_p,i = f_lo·10^(i/2) and the zeros half a step above, f_z,i = f_p,i·10^(1/4),
//!   mapped to z = exp(−2πfΔt), from `flicker_low_cutoff_hz` up to the Nyquist
//!   frequency. Each section contributes −20 dB/decade over half of each
//!   decade, so |H|² falls 10 dB/decade with a ripple below ±0.01 dB; the gain
//!   is fitted so that S_y = h₋₁/f over the band. Below f_lo the spectrum
//!   flattens, which changes σ_y(τ) by less than (π·τ·f_lo)² relative: keep
//!   f_lo ≪ 1/(πτ) for the longest τ of interest (the default 10⁻⁵ Hz is
//!   fine to τ ≈ 3 000 s). The filter starts from rest at t = 0 (as the
//!   Kasdin–Walter generator does): flicker noise has no stationary start.
//! - White PM: a white phase (time) error x_k of variance h₂·f_h/(4π²),
//!   f_h = 1/(2Δt), differenced: ȳ_k = (x_{k+1} − x_k)/Δt.
//! - Deterministic terms are averaged over the interval analytically.
//!
//! Cost per sample: one normal draw per enabled noise type plus ~2 FMA per
//! flicker section (about 16 sections at Δt = 1 ms), some 20–40 ns.
//!
//! # Allan variance
//!
//! σ_y²(τ) = h₀/(2τ) + 2·ln2·h₋₁ + (2π²/3)·h₋₂·τ + 3·f_h·h₂/(4π²τ²)
//! (Barnes et al. 1971, Table I; NIST SP 1065, Table 9), see
//! [`allan_deviation_theory`]; a linear drift D adds D²τ²/2 (not included).

use serde::{Deserialize, Serialize};
use std::f64::consts::{LN_2, PI};

use crate::error::ConfigError;
use crate::rng::{Xoshiro256PlusPlus, standard_normal};

/// Flicker filter sections per decade of frequency (the ripple of |H|²·f is
/// below ±0.01 dB with two).
const FLICKER_SECTIONS_PER_DECADE: f64 = 2.0;

/// Power-law noise and deterministic-drift parameters of a crystal oscillator,
/// in fractional-frequency units (y = δf/f₀). The g-sensitivity Γ is not here:
/// the session adds aᵀΓ to f_carrier·y.
///
/// Every key is optional in a scenario file: a missing `h_*` is 0 (no such
/// noise); the other defaults are given per key.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OscillatorConfig {
    /// White FM coefficient h₀ [1/Hz = s]: S_y(f) ∋ h₀.
    #[serde(default)]
    pub h0: f64,
    /// Flicker FM coefficient h₋₁ \[dimensionless\]: S_y(f) ∋ h₋₁/f.
    #[serde(default)]
    pub h_neg1: f64,
    /// Random-walk FM coefficient h₋₂ \[Hz\]: S_y(f) ∋ h₋₂/f².
    #[serde(default)]
    pub h_neg2: f64,
    /// White PM coefficient h₂ [1/Hz³ = s³]: S_y(f) ∋ h₂·f² (up to the Nyquist
    /// frequency of the sample interval).
    #[serde(default)]
    pub h2: f64,
    /// Constant fractional frequency offset y_offset \[-\] (e.g. 3e-7 for a
    /// TCXO 0.3 ppm off; a PLL tracks it as an extra Doppler).
    #[serde(default)]
    pub offset_frac: f64,
    /// Linear frequency drift (aging) D [1/s]: y ∋ D·t (1e-10/day = 1.16e-15/s).
    #[serde(default)]
    pub drift_frac_per_s: f64,
    /// Amplitude A \[-\] of the sinusoidal temperature cycle y ∋ A·sin(2πt/P + φ₀).
    #[serde(default)]
    pub temp_cycle_amplitude_frac: f64,
    /// Period P \[s\] of the temperature cycle (e.g. an oven or air-conditioning
    /// cycle).
    #[serde(default = "default_temp_cycle_period_s")]
    pub temp_cycle_period_s: f64,
    /// Phase φ₀ \[rad\] of the temperature cycle at t = 0.
    #[serde(default)]
    pub temp_cycle_phase_rad: f64,
    /// Lowest corner f_lo \[Hz\] of the flicker-FM synthesis filter: S_y follows
    /// h₋₁/f from here to the Nyquist frequency and is flat below.
    #[serde(default = "default_flicker_low_cutoff_hz")]
    pub flicker_low_cutoff_hz: f64,
}

fn default_temp_cycle_period_s() -> f64 {
    600.0
}

fn default_flicker_low_cutoff_hz() -> f64 {
    1e-5
}

/// Named oscillator presets (`"ocxo"`, `"tcxo"`, `"tcxo_low_quality"` in a
/// scenario file); see the constructors of [`OscillatorConfig`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum OscillatorPreset {
    /// [`OscillatorConfig::ocxo`].
    Ocxo,
    /// [`OscillatorConfig::tcxo`].
    Tcxo,
    /// [`OscillatorConfig::tcxo_low_quality`].
    TcxoLowQuality,
}

impl OscillatorPreset {
    /// The preset's configuration.
    pub fn config(self) -> OscillatorConfig {
        match self {
            Self::Ocxo => OscillatorConfig::ocxo(),
            Self::Tcxo => OscillatorConfig::tcxo(),
            Self::TcxoLowQuality => OscillatorConfig::tcxo_low_quality(),
        }
    }
}

impl Default for OscillatorConfig {
    /// The OCXO preset ([`OscillatorConfig::ocxo`]), the paper's oscillator class.
    fn default() -> Self {
        Self::ocxo()
    }
}

impl OscillatorConfig {
    /// A noise-free oscillator (all coefficients 0): y ≡ 0.
    pub fn ideal() -> Self {
        Self::from_h(0.0, 0.0, 0.0)
    }

    /// Power-law noise only (white, flicker, random-walk FM), no PM noise, no
    /// deterministic terms.
    pub fn from_h(h0: f64, h_neg1: f64, h_neg2: f64) -> Self {
        Self {
            h0,
            h_neg1,
            h_neg2,
            h2: 0.0,
            offset_frac: 0.0,
            drift_frac_per_s: 0.0,
            temp_cycle_amplitude_frac: 0.0,
            temp_cycle_period_s: default_temp_cycle_period_s(),
            temp_cycle_phase_rad: 0.0,
            flicker_low_cutoff_hz: default_flicker_low_cutoff_hz(),
        }
    }

    /// Oven-controlled crystal oscillator: h₀ = 2e-25 s, h₋₁ = 7e-25,
    /// h₋₂ = 6e-25 Hz — the "OCXO" row of the clock-model table in R. G. Brown &
    /// P. Y. C. Hwang, *Introduction to Random Signals and Applied Kalman
    /// Filtering*, 4th ed., Wiley 2012, §9.3 (as also tabulated in open GNSS
    /// receiver code, e.g. the `navtools` clock models).
    ///
    /// σ_y(1 s) ≈ 2.2e-12, σ_y(100 s) ≈ 2.0e-11. Phase jitter it causes in the
    /// paper's loop (2nd order, Bn = 3 Hz, L1): ≈ 0.12° rms — negligible, as
    /// the paper finds for its OCXO. (The 3rd edition's "ovenized crystal" row,
    /// h = 8e-20/2e-21/4e-23, is far noisier — 29° rms in that loop — and does
    /// not fit a modern OCXO.)
    pub fn ocxo() -> Self {
        Self::from_h(2e-25, 7e-25, 6e-25)
    }

    /// Good temperature-compensated crystal oscillator: h₀ = 2e-21 s,
    /// h₋₁ = 1e-22, h₋₂ = 2e-20 Hz — the "high-quality TCXO" row of Brown &
    /// Hwang, 4th ed., §9.3.
    ///
    /// σ_y(1 s) ≈ 3.6e-10 (random-walk FM dominated). Phase jitter in a 2nd-order
    /// L1 loop: ≈ 16° rms at Bn = 3 Hz, ≈ 29° at Bn = 2 Hz (so the 3σ < 45° rule
    /// fails below ~3 Hz — the paper's "Bn < 2 Hz: lock at risk with a TCXO").
    pub fn tcxo() -> Self {
        Self::from_h(2e-21, 1e-22, 2e-20)
    }

    /// Low-quality TCXO: h₀ = 2e-19 s, h₋₁ = 7e-21, h₋₂ = 2e-20 Hz — Brown &
    /// Hwang's "low-quality TCXO" (4th ed., §9.3), identical to the
    /// "compensated crystal" row of the 3rd ed. (1997), Table 11.1, p. 430, from
    /// Van Dierendonck, McGraw & Brown, "Relationship between Allan variances
    /// and Kalman filter parameters", PTTI 1984. Phase jitter in a 2nd-order
    /// L1 loop ≈ 48° rms at Bn = 3 Hz: only wide loops keep lock.
    pub fn tcxo_low_quality() -> Self {
        Self::from_h(2e-19, 7e-21, 2e-20)
    }

    /// Checks ranges; the error names the offending key.
    pub fn validate(&self) -> Result<(), ConfigError> {
        let bad = |key: &str, value: f64, allowed: &str| {
            Err(ConfigError::out_of_range(format!("oscillator.{key}"), value, allowed))
        };
        let nonneg = [("h0", self.h0), ("h_neg1", self.h_neg1), ("h_neg2", self.h_neg2), ("h2", self.h2)];
        for (key, v) in nonneg {
            if !(v.is_finite() && v >= 0.0) {
                return bad(key, v, "finite and >= 0");
            }
        }
        let finite = [
            ("offset_frac", self.offset_frac),
            ("drift_frac_per_s", self.drift_frac_per_s),
            ("temp_cycle_amplitude_frac", self.temp_cycle_amplitude_frac),
            ("temp_cycle_phase_rad", self.temp_cycle_phase_rad),
        ];
        for (key, v) in finite {
            if !v.is_finite() {
                return bad(key, v, "finite");
            }
        }
        if self.offset_frac.abs() > 1e-3 {
            return bad("offset_frac", self.offset_frac, "within ±1e-3");
        }
        if !(self.temp_cycle_period_s.is_finite() && self.temp_cycle_period_s > 0.0) {
            return bad("temp_cycle_period_s", self.temp_cycle_period_s, "> 0");
        }
        if !(self.flicker_low_cutoff_hz.is_finite() && self.flicker_low_cutoff_hz > 0.0) {
            return bad("flicker_low_cutoff_hz", self.flicker_low_cutoff_hz, "> 0");
        }
        Ok(())
    }
}

/// Theoretical Allan deviation σ_y(τ) of the FM noise of `cfg`:
/// σ_y²(τ) = h₀/(2τ) + 2·ln2·h₋₁ + (2π²/3)·h₋₂·τ (Barnes et al. 1971;
/// docs/conventions.md). Deterministic terms and white PM are excluded (see
/// [`allan_deviation_theory_with_pm`]).
pub fn allan_deviation_theory(cfg: &OscillatorConfig, tau_s: f64) -> f64 {
    (cfg.h0 / (2.0 * tau_s) + 2.0 * LN_2 * cfg.h_neg1 + (2.0 * PI * PI / 3.0) * cfg.h_neg2 * tau_s).sqrt()
}

/// [`allan_deviation_theory`] plus the white-PM term 3·f_h·h₂/(4π²τ²), with the
/// measurement bandwidth f_h = 1/(2Δt) of samples taken every
/// `sample_interval_s` (NIST SP 1065, Table 9).
pub fn allan_deviation_theory_with_pm(cfg: &OscillatorConfig, tau_s: f64, sample_interval_s: f64) -> f64 {
    let f_h = 0.5 / sample_interval_s;
    let fm = allan_deviation_theory(cfg, tau_s);
    (fm * fm + 3.0 * f_h * cfg.h2 / (4.0 * PI * PI * tau_s * tau_s)).sqrt()
}

/// Overlapping Allan deviation of fractional-frequency samples, each the mean
/// of y over one `sample_interval_s` (NIST SP 1065, eq. 11):
///
/// σ_y²(τ) = 1/(2τ²(N − 2m)) · Σ_{i=0}^{N−2m} (x_{i+2m} − 2x_{i+m} + x_i)²
///
/// with m = round(τ/Δt), x the phase (time error, x_{i+1} = x_i + ȳ_iΔt) and N
/// the number of phase points (samples + 1). Returns NaN when m < 1 or the
/// record holds fewer than 2m samples.
pub fn allan_deviation(y_samples: &[f64], sample_interval_s: f64, tau_s: f64) -> f64 {
    let x = phase_from_frequency(y_samples, sample_interval_s);
    overlapping_adev_from_phase(&x, sample_interval_s, tau_s)
}

/// Overlapping Allan deviations at several τ (one phase integration shared).
pub fn allan_deviations(y_samples: &[f64], sample_interval_s: f64, taus_s: &[f64]) -> Vec<f64> {
    let x = phase_from_frequency(y_samples, sample_interval_s);
    taus_s.iter().map(|&tau| overlapping_adev_from_phase(&x, sample_interval_s, tau)).collect()
}

/// Phase (time error) \[s\] from frequency samples; the mean frequency is
/// removed first (it does not change the Allan variance and keeps the phase
/// small for accuracy).
fn phase_from_frequency(y: &[f64], dt: f64) -> Vec<f64> {
    let mean = if y.is_empty() { 0.0 } else { y.iter().sum::<f64>() / y.len() as f64 };
    let mut x = Vec::with_capacity(y.len() + 1);
    let mut acc = 0.0;
    x.push(0.0);
    for &yi in y {
        acc += (yi - mean) * dt;
        x.push(acc);
    }
    x
}

fn overlapping_adev_from_phase(x: &[f64], dt: f64, tau_s: f64) -> f64 {
    let m = (tau_s / dt).round();
    if m.is_nan() || m < 1.0 {
        return f64::NAN;
    }
    let m = m as usize;
    if x.len() < 2 * m + 1 {
        return f64::NAN;
    }
    let terms = x.len() - 2 * m;
    let mut sum = 0.0;
    for i in 0..terms {
        let d = x[i + 2 * m] - 2.0 * x[i + m] + x[i];
        sum += d * d;
    }
    let tau = m as f64 * dt;
    (sum / (2.0 * tau * tau * terms as f64)).sqrt()
}

/// The flicker-FM synthesis filter: a cascade of first-order pole–zero
/// sections in transposed direct form II (one state each).
#[derive(Debug, Clone)]
struct FlickerFilter {
    gain: f64,
    pole: Vec<f64>,
    zero: Vec<f64>,
    state: Vec<f64>,
}

impl FlickerFilter {
    /// Design for S_y(f) = h₋₁/f between `f_lo_hz` and the Nyquist frequency
    /// of `dt_s`, fed with unit-variance white noise. None if the band is empty.
    fn design(h_neg1: f64, f_lo_hz: f64, dt_s: f64) -> Option<Self> {
        let f_hi = 0.5 / dt_s;
        if h_neg1 <= 0.0 || f_lo_hz >= f_hi {
            return None;
        }
        let decades = (f_hi / f_lo_hz).log10();
        let n = (decades * FLICKER_SECTIONS_PER_DECADE).ceil().max(1.0) as usize;
        let ratio = 10f64.powf(1.0 / FLICKER_SECTIONS_PER_DECADE);
        let mut pole = Vec::with_capacity(n);
        let mut zero = Vec::with_capacity(n);
        for i in 0..n {
            let fp = f_lo_hz * ratio.powi(i as i32);
            let fz = fp * ratio.sqrt();
            pole.push((-2.0 * PI * fp * dt_s).exp());
            zero.push((-2.0 * PI * fz * dt_s).exp());
        }
        // Fit the gain: mean of 10·log10(f·|H|²) over the band's interior on a
        // log grid (the ripple is tiny, so the mean is the level).
        let (lo, hi) = if decades > 2.0 / FLICKER_SECTIONS_PER_DECADE + 0.5 {
            (f_lo_hz * ratio, f_hi / ratio)
        } else {
            let c = (f_lo_hz * f_hi).sqrt();
            (c, c)
        };
        let points = (((hi / lo).log10() * 64.0).ceil() as usize).max(1);
        let mut mean_db = 0.0;
        for k in 0..=points {
            let f = lo * (hi / lo).powf(k as f64 / points as f64);
            mean_db += 10.0 * (f * Self::mag2(&pole, &zero, f, dt_s)).log10();
        }
        mean_db /= (points + 1) as f64;
        // One-sided PSD of the output: 2Δt·g²·|H|² = h₋₁/f  ⇒  g² = h₋₁ / (2Δt·f|H|²).
        let gain = (h_neg1 / (2.0 * dt_s * 10f64.powf(mean_db / 10.0))).sqrt();
        Some(Self { gain, state: vec![0.0; n], pole, zero })
    }

    /// |H(e^{j2πfΔt})|² of the cascade without the gain.
    fn mag2(pole: &[f64], zero: &[f64], f_hz: f64, dt_s: f64) -> f64 {
        let w = 2.0 * PI * f_hz * dt_s;
        let c = w.cos();
        let mut m2 = 1.0;
        for (&p, &q) in pole.iter().zip(zero) {
            // |1 − q e^{-jw}|² / |1 − p e^{-jw}|²
            let num = 1.0 - 2.0 * q * c + q * q;
            let den = 1.0 - 2.0 * p * c + p * p;
            m2 *= num / den;
        }
        m2
    }

    #[inline]
    fn step(&mut self, w: f64) -> f64 {
        let mut v = w;
        for ((s, &p), &q) in self.state.iter_mut().zip(&self.pole).zip(&self.zero) {
            let out = v + *s;
            *s = p * out - q * v;
            v = out;
        }
        self.gain * v
    }
}

/// Streaming generator of the oscillator's fractional frequency, one value per
/// sample interval (see the module documentation for the model). One
/// generator per session, shared by all channels; same configuration, sample
/// interval and generator state → same output bits.
#[derive(Debug, Clone)]
pub struct Oscillator {
    dt_s: f64,
    k: u64,
    rng: Xoshiro256PlusPlus,
    /// σ of the per-sample white draw: white FM h₀/(2Δt) plus the
    /// random-walk Brownian-bridge term NΔt/12.
    sigma_white: f64,
    /// σ of the random-walk FM step √(2π²h₋₂Δt).
    sigma_rw_step: f64,
    y_rw: f64,
    /// σ of the white-PM time error x \[s\] and its previous value.
    sigma_x_wpm_s: f64,
    x_wpm_prev_s: f64,
    flicker: Option<FlickerFilter>,
    offset_frac: f64,
    drift_frac_per_s: f64,
    /// A·sin(ωΔt/2)/(ωΔt/2): the interval mean of A·sin(θ) is this times sin(θ_mid).
    temp_amp_avg: f64,
    temp_omega_radps: f64,
    temp_phase_rad: f64,
    /// cos/sin of θ at the middle of the current interval, rotated each step.
    temp_cos: f64,
    temp_sin: f64,
    temp_rot_cos: f64,
    temp_rot_sin: f64,
    time_error_s: f64,
}

impl Oscillator {
    /// Generator for samples of length `sample_interval_s` \[s\], drawing from
    /// `rng` (which it owns).
    ///
    /// # Panics
    /// If `cfg.validate()` fails or `sample_interval_s` is not > 0; use
    /// [`Oscillator::try_new`] to get the error instead.
    pub fn new(cfg: &OscillatorConfig, sample_interval_s: f64, rng: Xoshiro256PlusPlus) -> Self {
        match Self::try_new(cfg, sample_interval_s, rng) {
            Ok(o) => o,
            Err(e) => panic!("{e}"),
        }
    }

    /// As [`Oscillator::new`], returning configuration errors.
    pub fn try_new(
        cfg: &OscillatorConfig,
        sample_interval_s: f64,
        rng: Xoshiro256PlusPlus,
    ) -> Result<Self, ConfigError> {
        cfg.validate()?;
        if !(sample_interval_s.is_finite() && sample_interval_s > 0.0) {
            return Err(ConfigError::InvalidArgument {
                name: "oscillator sample interval".into(),
                value: sample_interval_s,
                allowed: "> 0 s".into(),
            });
        }
        let dt = sample_interval_s;
        let diffusion = 2.0 * PI * PI * cfg.h_neg2;
        let sigma_white = (cfg.h0 / (2.0 * dt) + diffusion * dt / 12.0).sqrt();
        let sigma_rw_step = (diffusion * dt).sqrt();
        let sigma_x_wpm_s = (cfg.h2 * (0.5 / dt) / (4.0 * PI * PI)).sqrt();
        let omega = 2.0 * PI / cfg.temp_cycle_period_s;
        let half = 0.5 * omega * dt;
        let sinc = if half == 0.0 { 1.0 } else { half.sin() / half };
        let mut osc = Self {
            dt_s: dt,
            k: 0,
            rng,
            sigma_white,
            sigma_rw_step,
            y_rw: 0.0,
            sigma_x_wpm_s,
            x_wpm_prev_s: 0.0,
            flicker: FlickerFilter::design(cfg.h_neg1, cfg.flicker_low_cutoff_hz, dt),
            offset_frac: cfg.offset_frac,
            drift_frac_per_s: cfg.drift_frac_per_s,
            temp_amp_avg: cfg.temp_cycle_amplitude_frac * sinc,
            temp_omega_radps: omega,
            temp_phase_rad: cfg.temp_cycle_phase_rad,
            temp_cos: 1.0,
            temp_sin: 0.0,
            temp_rot_cos: (omega * dt).cos(),
            temp_rot_sin: (omega * dt).sin(),
            time_error_s: 0.0,
        };
        if osc.sigma_x_wpm_s > 0.0 {
            osc.x_wpm_prev_s = osc.sigma_x_wpm_s * standard_normal(&mut osc.rng);
        }
        osc.resync_temperature_phasor();
        Ok(osc)
    }

    /// Recomputes the temperature phasor at the middle of interval k exactly
    /// (done every 1024 samples to stop rounding drift of the rotation).
    fn resync_temperature_phasor(&mut self) {
        let theta = self.temp_omega_radps * (self.k as f64 + 0.5) * self.dt_s + self.temp_phase_rad;
        let (s, c) = theta.sin_cos();
        self.temp_sin = s;
        self.temp_cos = c;
    }

    /// The sample interval Δt \[s\].
    pub fn sample_interval_s(&self) -> f64 {
        self.dt_s
    }

    /// Start time \[s\] of the next interval, k·Δt (t = 0 at construction).
    pub fn t_s(&self) -> f64 {
        self.k as f64 * self.dt_s
    }

    /// Accumulated time error x(t) = ∫₀ᵗ y dt' \[s\] of all samples produced so
    /// far (the carrier phase error it causes is 2π·f_c·x).
    pub fn time_error_s(&self) -> f64 {
        self.time_error_s
    }

    /// The fractional frequency ȳ_k \[-\] averaged over the next interval
    /// [kΔt, (k+1)Δt], then advances k.
    #[inline]
    pub fn next_y(&mut self) -> f64 {
        let mut y = 0.0;
        if self.sigma_white > 0.0 {
            y += self.sigma_white * standard_normal(&mut self.rng);
        }
        if self.sigma_rw_step > 0.0 {
            let step = self.sigma_rw_step * standard_normal(&mut self.rng);
            y += self.y_rw + 0.5 * step;
            self.y_rw += step;
        }
        if let Some(f) = self.flicker.as_mut() {
            y += f.step(standard_normal(&mut self.rng));
        }
        if self.sigma_x_wpm_s > 0.0 {
            let x = self.sigma_x_wpm_s * standard_normal(&mut self.rng);
            y += (x - self.x_wpm_prev_s) / self.dt_s;
            self.x_wpm_prev_s = x;
        }
        y += self.offset_frac + self.drift_frac_per_s * (self.k as f64 + 0.5) * self.dt_s;
        if self.temp_amp_avg != 0.0 {
            y += self.temp_amp_avg * self.temp_sin;
            let c = self.temp_cos * self.temp_rot_cos - self.temp_sin * self.temp_rot_sin;
            let s = self.temp_sin * self.temp_rot_cos + self.temp_cos * self.temp_rot_sin;
            self.temp_cos = c;
            self.temp_sin = s;
        }
        self.k += 1;
        if self.temp_amp_avg != 0.0 && self.k.is_multiple_of(1024) {
            self.resync_temperature_phasor();
        }
        self.time_error_s += y * self.dt_s;
        y
    }

    /// Fills `out` with the next `out.len()` interval means (as repeated
    /// [`Oscillator::next_y`]).
    pub fn fill(&mut self, out: &mut [f64]) {
        for v in out {
            *v = self.next_y();
        }
    }
}

/// An oscillator's noise by preset, or none (a prediction of the vibration
/// and thermal parts alone).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum NoisePreset {
    /// The simulator's OCXO preset (the paper's class).
    Ocxo,
    /// The simulator's TCXO preset.
    Tcxo,
    /// The simulator's low-quality TCXO preset.
    TcxoLowQuality,
    /// No oscillator noise (the vibration and thermal parts alone).
    None,
}

impl NoisePreset {
    /// The preset's configuration ([`OscillatorConfig::ocxo`] …); `None` for no noise.
    pub fn config(self) -> Option<OscillatorConfig> {
        match self {
            NoisePreset::Ocxo => Some(OscillatorConfig::ocxo()),
            NoisePreset::Tcxo => Some(OscillatorConfig::tcxo()),
            NoisePreset::TcxoLowQuality => Some(OscillatorConfig::tcxo_low_quality()),
            NoisePreset::None => None,
        }
    }
}

impl std::fmt::Display for NoisePreset {
    /// The oscillator as a prediction's text names it: `OCXO`, `TCXO`,
    /// `low-quality TCXO`, `noise-free`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            NoisePreset::Ocxo => "OCXO",
            NoisePreset::Tcxo => "TCXO",
            NoisePreset::TcxoLowQuality => "low-quality TCXO",
            NoisePreset::None => "noise-free",
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each preset is its configuration, none is no noise, and each names
    /// itself as a prediction's text does.
    #[test]
    fn noise_presets_are_the_configurations_and_name_themselves() {
        assert_eq!(NoisePreset::Ocxo.config(), Some(OscillatorConfig::ocxo()));
        assert_eq!(NoisePreset::TcxoLowQuality.config(), Some(OscillatorConfig::tcxo_low_quality()));
        assert_eq!(NoisePreset::None.config(), None);
        let names: Vec<String> = [NoisePreset::Ocxo, NoisePreset::Tcxo, NoisePreset::TcxoLowQuality, NoisePreset::None]
            .iter()
            .map(ToString::to_string)
            .collect();
        assert_eq!(names, ["OCXO", "TCXO", "low-quality TCXO", "noise-free"]);
    }
    use crate::rng::seeded;

    fn simulate(cfg: &OscillatorConfig, dt: f64, n: usize, seed: u64) -> Vec<f64> {
        let mut osc = Oscillator::new(cfg, dt, seeded(seed));
        let mut y = vec![0.0; n];
        osc.fill(&mut y);
        y
    }

    const TAUS: [f64; 5] = [1.0, 3.0, 10.0, 30.0, 100.0];

    /// Simulated ADEV vs theory within 25 % at τ = 1…100 s. 8 h at 10 ms: the
    /// τ = 100 s point has ≈ 280 equivalent degrees of freedom (σ of the ADEV
    /// estimate ≈ 4 %), so 25 % is a > 5σ bound.
    fn check_adev(cfg: &OscillatorConfig, seed: u64) {
        let dt = 0.01;
        let n = (8.0 * 3600.0 / dt) as usize;
        let y = simulate(cfg, dt, n, seed);
        let sim = allan_deviations(&y, dt, &TAUS);
        for (tau, s) in TAUS.iter().zip(sim) {
            let th = allan_deviation_theory(cfg, *tau);
            let rel = s / th - 1.0;
            eprintln!("ADEV tau {tau} s: sim {s:e} theory {th:e} ({:+.1} %)", rel * 100.0);
            assert!(rel.abs() < 0.25, "tau {tau}: sim {s:e} theory {th:e} ({:+.1} %)", rel * 100.0);
        }
    }

    #[test]
    fn oscillator_adev_matches_theory_ocxo() {
        check_adev(&OscillatorConfig::ocxo(), 1);
    }

    #[test]
    fn oscillator_adev_matches_theory_tcxo() {
        check_adev(&OscillatorConfig::tcxo(), 2);
    }

    #[test]
    fn oscillator_flicker_alone_has_flat_adev() {
        let cfg = OscillatorConfig::from_h(0.0, 1e-22, 0.0);
        check_adev(&cfg, 3);
        // And it is flat: the spread over τ is small (relabelled white noise
        // would fall as τ^-1/2, a factor 10 over 1…100 s).
        let dt = 0.01;
        let y = simulate(&cfg, dt, (8.0 * 3600.0 / dt) as usize, 4);
        let a = allan_deviations(&y, dt, &TAUS);
        let (lo, hi) = a.iter().fold((f64::MAX, 0.0f64), |(l, h), &v| (l.min(v), h.max(v)));
        assert!(hi / lo < 1.25, "flicker ADEV not flat: {a:?}");
    }

    #[test]
    fn oscillator_white_fm_and_white_pm_short_tau() {
        // White FM: σ_y² = h0/(2τ) exactly for the interval means.
        let cfg = OscillatorConfig::from_h(1e-20, 0.0, 0.0);
        let dt = 1e-3;
        let y = simulate(&cfg, dt, 2_000_000, 5);
        for tau in [1e-3, 1e-2, 0.1, 1.0] {
            let (s, th) = (allan_deviation(&y, dt, tau), allan_deviation_theory(&cfg, tau));
            assert!((s / th - 1.0).abs() < 0.05, "white FM tau {tau}: {s:e} vs {th:e}");
        }
        // White PM: σ_y² = 3 f_h h2 / (4π²τ²).
        let mut cfg = OscillatorConfig::ideal();
        cfg.h2 = 1e-24;
        let y = simulate(&cfg, dt, 500_000, 6);
        for tau in [1e-3, 1e-2, 0.1] {
            let (s, th) = (allan_deviation(&y, dt, tau), allan_deviation_theory_with_pm(&cfg, tau, dt));
            assert!((s / th - 1.0).abs() < 0.05, "white PM tau {tau}: {s:e} vs {th:e}");
        }
    }

    #[test]
    fn oscillator_deterministic_terms_and_reproducibility() {
        let mut cfg = OscillatorConfig::ideal();
        cfg.offset_frac = 1e-7;
        cfg.drift_frac_per_s = 1e-12;
        cfg.temp_cycle_amplitude_frac = 1e-9;
        cfg.temp_cycle_period_s = 10.0;
        cfg.temp_cycle_phase_rad = 0.3;
        let dt = 0.01;
        let mut osc = Oscillator::new(&cfg, dt, seeded(7));
        let w = 2.0 * PI / 10.0;
        for k in 0..5000u64 {
            let y = osc.next_y();
            let (t0, t1) = (k as f64 * dt, (k + 1) as f64 * dt);
            // Exact interval mean of the deterministic model.
            let expect =
                1e-7 + 1e-12 * 0.5 * (t0 + t1) + 1e-9 * ((w * t0 + 0.3).cos() - (w * t1 + 0.3).cos()) / (w * dt);
            assert!((y - expect).abs() < 1e-18, "k {k}: {y:e} vs {expect:e}");
        }
        // Same seed, same bits; the phase integral is the sum of y·Δt.
        let a = simulate(&OscillatorConfig::tcxo(), 1e-3, 10_000, 9);
        let mut osc = Oscillator::new(&OscillatorConfig::tcxo(), 1e-3, seeded(9));
        let b: Vec<f64> = (0..10_000).map(|_| osc.next_y()).collect();
        assert!(a.iter().zip(&b).all(|(x, y)| x.to_bits() == y.to_bits()));
        let x: f64 = a.iter().map(|v| v * 1e-3).sum();
        assert!((osc.time_error_s() - x).abs() <= 1e-12 * x.abs().max(1e-30));
    }

    #[test]
    fn oscillator_config_validation_and_serde() {
        assert!(OscillatorConfig::ocxo().validate().is_ok());
        let mut c = OscillatorConfig::tcxo();
        c.h_neg1 = -1.0;
        assert!(c.validate().unwrap_err().to_string().contains("h_neg1"));
        let mut c = OscillatorConfig::tcxo();
        c.temp_cycle_period_s = 0.0;
        assert!(c.validate().unwrap_err().to_string().contains("temp_cycle_period_s"));
        let c: OscillatorConfig = toml::from_str("h0 = 2e-21\nh_neg2 = 2e-20\n").unwrap();
        assert_eq!(c.h_neg1, 0.0);
        assert_eq!(c.flicker_low_cutoff_hz, 1e-5);
        assert!(toml::from_str::<OscillatorConfig>("h0 = 1.0\nh_minus1 = 2.0\n").is_err());
        let p: OscillatorPreset =
            toml::from_str::<toml::Table>("p = \"tcxo_low_quality\"").unwrap()["p"].clone().try_into().unwrap();
        assert_eq!(p.config(), OscillatorConfig::tcxo_low_quality());
    }
}

/// The Allan deviation of an oscillator simulated at `sample_interval_s` for
/// `samples` samples next to its power-law model, at τ = T·2^k up to a
/// quarter of the record.
#[derive(Debug, Clone, PartialEq)]
pub struct AllanComparison {
    /// Averaging times τ \[s\].
    pub taus_s: Vec<f64>,
    /// Overlapping Allan deviation of the simulated fractional frequency.
    pub simulated: Vec<f64>,
    /// The model's Allan deviation ([`allan_deviation_theory_with_pm`]).
    pub theory: Vec<f64>,
    /// Length of the record \[s\].
    pub duration_s: f64,
}

/// Simulates `cfg` with `seed` and compares its Allan deviation with the model.
pub fn allan_comparison(
    cfg: &OscillatorConfig,
    sample_interval_s: f64,
    samples: usize,
    seed: u64,
) -> Result<AllanComparison, crate::error::ConfigError> {
    let dt = sample_interval_s;
    let mut osc = Oscillator::try_new(cfg, dt, crate::rng::seeded(seed))?;
    let mut y = vec![0.0; samples];
    osc.fill(&mut y);
    let duration_s = samples as f64 * dt;
    let taus_s: Vec<f64> = (0..16).map(|k| dt * 2f64.powi(k)).filter(|t| *t <= duration_s / 4.0).collect();
    let simulated = allan_deviations(&y, dt, &taus_s);
    let theory = taus_s.iter().map(|&t| allan_deviation_theory_with_pm(cfg, t, dt)).collect();
    Ok(AllanComparison { taus_s, simulated, theory, duration_s })
}
