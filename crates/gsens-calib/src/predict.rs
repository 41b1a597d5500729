//! What compensation buys under vibration: the carrier phase jitter of a
//! loop without and with −aᵀΓ̂ fed into its NCO, from Γ̂ and its covariance,
//! a vibration environment, the oscillator's frequency noise and the loop.
//!
//! Every part of the phase tracking error is a frequency error through the
//! loop's response L = φ/Δf \[rad/Hz\] ([`LoopModel::response`]), plus the
//! thermal noise:
//!
//! - vibration, uncompensated: Δf = aᵀΓ; for a spectrum S_a,i(f) per axis
//!   (axes uncorrelated) σ² = ∫ |L(f)|²·Σᵢ Γᵢ²·S_a,i(f) df, for a tone of
//!   peak amplitudes Aᵢ σ² = |L(f)|²·(Σᵢ ΓᵢAᵢ)²/2;
//! - vibration, compensated: Δf = (Γ − Γ̂·e^{−j2πfτ})ᵀa, τ the feed-forward's
//!   delay (latency plus half the IMU's sample interval, the hold), whose
//!   mean square over Γ̂'s error (zero mean, covariance C) is
//!   Σᵢ [Γᵢ²·4·sin²(πfτ) + Cᵢᵢ]·S_a,i(f) (Γ taken as Γ̂), plus the IMU's
//!   white noise density n: Σᵢ Γᵢ²·n²;
//! - the oscillator: Δf = f_c·y with S_y(f) = h₂f² + h₀ + h₋₁/f + h₋₂/f²
//!   (Barnes et al. 1971; the simulator's `OscillatorConfig`);
//! - thermal noise: σ² = Bn/(C/N0)·(1 + 1/(2T·C/N0)) rad² (Kaplan & Hegarty,
//!   *Understanding GPS*, 2nd ed., eq. 5.6).
//!
//! The usual rule of thumb (Kaplan & Hegarty, §5.6.1) keeps lock while
//! 3σ + θₑ ≤ 45° ([`COSTAS_LOCK_RULE_RAD`]: half the two-quadrant
//! arctangent's ±π/2, a margin for the non-Gaussian tails of the loop's
//! jitter over a long track), θₑ the dynamic stress
//! error: for a 2nd-order loop and a line-of-sight Doppler rate ḟ, the
//! steady-state error 2π·ḟ/ωn² (a static receiver sees up to ≈ 0.9 Hz/s at
//! L1 from the satellites' motion alone). With Gaussian φ about θₑ the chance
//! that one sample passes π/4 is 1 − Φ((π/4 − θₑ)/σ) + Φ((−π/4 − θₑ)/σ).
//!
//! The feed-forward is modelled as seeing every frequency of the vibration
//! with its delay: above 1/(6τ) (13 Hz for a 40 Hz IMU's hold) it leaves
//! more than it removes, and above the IMU's Nyquist frequency it could not
//! follow at all — a broadband environment needs a fast IMU.

use gsens_core::{LoopModel, LoopSpec};

mod request;
mod setup;
mod sweep;
mod table;
pub use request::{EstimateSource, PredictError, PredictRequest, ReceiverConditions, VibrationSource};
pub use setup::{FeedForward, StatedGammaError, ToneError, diagonal_covariance, parse_tone, stated_gamma};
use statrs::distribution::{ContinuousCDF, Normal};
pub use sweep::{BN_GRID_HZ, Sweep, SweepError, SweepRow, SweepSettings};
pub use table::{SweepContext, render_sweep_text};

/// Kaplan & Hegarty's rule of thumb for keeping a Costas loop in lock,
/// 3σ + θₑ ≤ 45° \[rad\]: a lock criterion for the loop's whole jitter over a
/// track, not the discriminator's linear range under shaking
/// ([`gsens_core::Discriminator::linear_range_rad`]).
pub const COSTAS_LOCK_RULE_RAD: f64 = core::f64::consts::FRAC_PI_4;

/// A vibration environment.
#[derive(Debug, Clone, PartialEq)]
pub enum Vibration {
    /// Random vibration: a one-sided acceleration PSD per axis at breakpoints
    /// (f \[Hz\], S \[(m/s²)²/Hz\] per axis), log-log interpolated between them
    /// and zero outside (how vibration specifications are written).
    Spectrum(Vec<(f64, [f64; 3])>),
    /// Sine vibration: tones (f \[Hz\], peak amplitude per axis \[m/s²\], in phase).
    Tones(Vec<(f64, [f64; 3])>),
}

impl Vibration {
    /// The spectrum's value at `f_hz` (log-log interpolation; 0 outside).
    fn psd_at(points: &[(f64, [f64; 3])], f_hz: f64) -> [f64; 3] {
        let Some(k) = points.windows(2).position(|w| f_hz >= w[0].0 && f_hz <= w[1].0) else { return [0.0; 3] };
        let ((f0, s0), (f1, s1)) = (points[k], points[k + 1]);
        let u = (f_hz / f0).ln() / (f1 / f0).ln();
        [0, 1, 2].map(|i| if s0[i] > 0.0 && s1[i] > 0.0 { (s0[i].ln() + u * (s1[i] / s0[i]).ln()).exp() } else { 0.0 })
    }

    /// RMS acceleration per axis \[m/s²\].
    pub fn rms_mps2(&self) -> [f64; 3] {
        match self {
            Vibration::Tones(t) => [0, 1, 2].map(|i| t.iter().map(|(_, a)| a[i] * a[i] / 2.0).sum::<f64>().sqrt()),
            Vibration::Spectrum(p) => {
                let (lo, hi) = (p.first().map_or(1.0, |x| x.0), p.last().map_or(1.0, |x| x.0));
                let grid = log_grid(lo, hi, 4000);
                [0, 1, 2].map(|i| integrate(&grid, |f| Self::psd_at(p, f)[i]).sqrt())
            }
        }
    }
}

/// The oscillator's fractional-frequency noise S_y(f) = h₂f² + h₀ + h₋₁/f + h₋₂/f².
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrequencyNoise {
    /// White PM h₂ \[s³\].
    pub h2: f64,
    /// White FM h₀ \[s\].
    pub h0: f64,
    /// Flicker FM h₋₁.
    pub h_neg1: f64,
    /// Random-walk FM h₋₂ \[1/s\].
    pub h_neg2: f64,
    /// The carrier \[Hz\].
    pub carrier_hz: f64,
}

/// What to predict for.
#[derive(Debug, Clone, PartialEq)]
pub struct PredictionInput {
    /// Γ̂ \[Hz/(m/s²)\] at the carrier (also taken as Γ).
    pub gamma_hz_per_mps2: [f64; 3],
    /// Its covariance \[(Hz/(m/s²))²\].
    pub covariance: [[f64; 3]; 3],
    /// The environment.
    pub vibration: Vibration,
    /// The oscillator (None: no oscillator noise).
    pub oscillator: Option<FrequencyNoise>,
    /// C/N0 \[dB-Hz\] for the thermal noise (None: none).
    pub cn0_dbhz: Option<f64>,
    /// The feed-forward's delay τ \[s\] (latency + half the IMU interval).
    pub delay_s: f64,
    /// The IMU's white noise density \[m/s²/√Hz\].
    pub imu_noise_mps2_per_rthz: f64,
    /// The line-of-sight Doppler rate the loop must follow \[Hz/s\].
    pub doppler_rate_hz_per_s: f64,
}

/// The phase jitter of one loop, without and with compensation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Jitter {
    /// Noise bandwidth \[Hz\].
    pub bn_hz: f64,
    /// 1σ of the thermal part \[rad\].
    pub thermal_rad: f64,
    /// 1σ of the oscillator's part \[rad\].
    pub oscillator_rad: f64,
    /// 1σ of the vibration's part, without and with compensation \[rad\].
    pub vibration_rad: [f64; 2],
    /// Total 1σ, without and with \[rad\].
    pub total_rad: [f64; 2],
    /// The dynamic stress error θₑ = 2π·ḟ/ωn² \[rad\].
    pub dynamic_stress_rad: f64,
    /// 3σ + θₑ ≤ π/4, without and with.
    pub keeps_lock: [bool; 2],
    /// P(|φ| > π/4) per sample, without and with.
    pub p_beyond_range: [f64; 2],
}

/// Log-spaced frequencies from `lo` to `hi`.
fn log_grid(lo: f64, hi: f64, n: usize) -> Vec<f64> {
    let (a, b) = (lo.ln(), hi.ln());
    (0..n).map(|k| (a + (b - a) * k as f64 / (n - 1) as f64).exp()).collect()
}

/// Trapezoidal ∫ g(f) df over `grid`.
fn integrate(grid: &[f64], g: impl Fn(f64) -> f64) -> f64 {
    grid.windows(2).map(|w| 0.5 * (g(w[0]) + g(w[1])) * (w[1] - w[0])).sum()
}

/// The jitter of `receiver_loop` (noise bandwidth `bn_hz`, update interval
/// `interval_s`) under `input`. The dynamic stress uses the loop's ωn (the
/// response's peak frequency for a loop without one, e.g. 3rd order, whose
/// steady-state error to a Doppler ramp is 0: then θₑ = 0).
pub fn jitter(receiver_loop: &LoopModel, bn_hz: f64, interval_s: f64, input: &PredictionInput) -> Jitter {
    let nyquist = 0.5 / interval_s;
    let grid = log_grid(1e-3, 0.999 * nyquist, 3000);
    let l2 = |f: f64| receiver_loop.response(f).norm_sqr();
    let g = input.gamma_hz_per_mps2;
    let c = input.covariance;
    let residual_weight = |f: f64, i: usize| {
        let s = (std::f64::consts::PI * f * input.delay_s).sin();
        g[i] * g[i] * 4.0 * s * s + c[i][i].max(0.0)
    };
    let vibration_sq = match &input.vibration {
        Vibration::Spectrum(points) => {
            let (lo, hi) = (points.first().map_or(1.0, |p| p.0), points.last().map_or(1.0, |p| p.0));
            let band = log_grid(lo, hi.min(0.999 * nyquist), 3000);
            let without = integrate(&band, |f| {
                let s = Vibration::psd_at(points, f);
                l2(f) * (0..3).map(|i| g[i] * g[i] * s[i]).sum::<f64>()
            });
            let with = integrate(&band, |f| {
                let s = Vibration::psd_at(points, f);
                l2(f) * (0..3).map(|i| residual_weight(f, i) * s[i]).sum::<f64>()
            });
            [without, with]
        }
        Vibration::Tones(tones) => tones.iter().fold([0.0, 0.0], |acc, &(f, a)| {
            let coherent = (0..3).map(|i| g[i] * a[i]).sum::<f64>();
            let residual: f64 = (0..3).map(|i| residual_weight(f, i) * a[i] * a[i]).sum();
            [acc[0] + l2(f) * coherent * coherent / 2.0, acc[1] + l2(f) * residual / 2.0]
        }),
    };
    // The IMU's white noise enters with the feed-forward only.
    let n2 = input.imu_noise_mps2_per_rthz.powi(2);
    let imu_sq = integrate(&grid, |f| l2(f) * (0..3).map(|i| g[i] * g[i] * n2).sum::<f64>());
    let oscillator_sq = input.oscillator.map_or(0.0, |o| {
        let fc2 = o.carrier_hz * o.carrier_hz;
        integrate(&grid, |f| l2(f) * fc2 * (o.h2 * f * f + o.h0 + o.h_neg1 / f + o.h_neg2 / (f * f)))
    });
    let thermal_sq = input.cn0_dbhz.map_or(0.0, |cn0| {
        let c_n0 = gsens_core::units::cn0_dbhz_to_ratio_hz(cn0);
        bn_hz / c_n0 * (1.0 + 1.0 / (2.0 * interval_s * c_n0))
    });
    let vibration_rad = [vibration_sq[0].sqrt(), (vibration_sq[1] + imu_sq).sqrt()];
    let total_rad = [0, 1].map(|k| (thermal_sq + oscillator_sq + vibration_rad[k].powi(2)).sqrt());
    // A 2nd-order loop's steady-state error to a frequency ramp; a 3rd-order loop has none.
    let dynamic_stress_rad = match receiver_loop {
        LoopModel::Kaplan { spec, .. } if spec.order() == 2 => {
            spec.wn_rad_per_s().map_or(0.0, |wn| std::f64::consts::TAU * input.doppler_rate_hz_per_s.abs() / (wn * wn))
        }
        _ => 0.0,
    };
    let normal = Normal::standard();
    let range = COSTAS_LOCK_RULE_RAD;
    Jitter {
        bn_hz,
        thermal_rad: thermal_sq.sqrt(),
        oscillator_rad: oscillator_sq.sqrt(),
        vibration_rad,
        total_rad,
        dynamic_stress_rad,
        keeps_lock: total_rad.map(|s| 3.0 * s + dynamic_stress_rad <= range),
        p_beyond_range: total_rad.map(|s| {
            let s = s.max(1e-300);
            normal.sf((range - dynamic_stress_rad) / s) + normal.cdf((-range - dynamic_stress_rad) / s)
        }),
    }
}

/// A 2nd-order Kaplan loop of noise bandwidth `bn_hz`, damping `zeta`,
/// updated every `interval_s`.
pub fn second_order_loop(bn_hz: f64, zeta: f64, interval_s: f64) -> LoopModel {
    LoopModel::kaplan(LoopSpec::SecondOrder { bn_hz, zeta }, Some(interval_s))
}

/// The narrowest noise bandwidth on `bn_grid_hz` at which the 2nd-order
/// loop keeps lock (3σ ≤ π/4), without and with compensation (None: none on
/// the grid does; a loop unstable at the interval is skipped).
pub fn narrowest_bn_hz(zeta: f64, interval_s: f64, input: &PredictionInput, bn_grid_hz: &[f64]) -> [Option<f64>; 2] {
    let keeps: Vec<(f64, [bool; 2])> = bn_grid_hz
        .iter()
        .filter_map(|&bn| {
            let l = second_order_loop(bn, zeta, interval_s);
            l.check().ok()?;
            Some((bn, jitter(&l, bn, interval_s, input).keeps_lock))
        })
        .collect();
    [0, 1].map(|k| keeps.iter().filter(|(_, ok)| ok[k]).map(|(bn, _)| *bn).reduce(f64::min))
}
