use crate::math::{PI, TAU, cos, sin, sqrt};
use nalgebra::{Matrix4, Vector4};

pub mod gnss_sdr;
pub mod pocket_sdr;

/// 1/2π: the loop's critical path multiplies rather than divides.
const FRAC_1_TAU: f64 = 1.0 / TAU;
pub use nalgebra::Complex;

/// Loop-filter coefficients of F(s) = c0 + c1/s + c2/s² \[rad/s per rad\].
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct LoopFilterCoeffs {
    /// Proportional gain c0 \[1/s\].
    pub c0_per_s: f64,
    /// First-integrator gain c1 \[1/s²\].
    pub c1_per_s2: f64,
    /// Second-integrator gain c2 \[1/s³\] (0 for a 2nd-order loop).
    pub c2_per_s3: f64,
}

/// Kaplan & Hegarty's 3rd-order loop constant a3 (Table 5.6).
pub const KAPLAN_A3: f64 = 1.1;
/// Kaplan & Hegarty's 3rd-order loop constant b3 (Table 5.6).
pub const KAPLAN_B3: f64 = 2.4;

/// How a carrier loop is specified by a user.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(tag = "kind", rename_all = "snake_case"))]
pub enum LoopSpec {
    /// 2nd-order loop from its one-sided noise bandwidth and damping.
    SecondOrder {
        /// Noise bandwidth Bn \[Hz\].
        bn_hz: f64,
        /// Damping ratio ζ.
        zeta: f64,
    },
    /// 3rd-order loop F(s) = b3·ωn + a3·ωn²/s + ωn³/s² from its noise bandwidth.
    ThirdOrder {
        /// Noise bandwidth Bn \[Hz\].
        bn_hz: f64,
        /// a3 (Kaplan: 1.1).
        a3: f64,
        /// b3 (Kaplan: 2.4).
        b3: f64,
    },
    /// A loop filter given directly by its coefficients.
    Coefficients(LoopFilterCoeffs),
}

/// Errors in a loop specification.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum LoopError {
    /// Bn, ζ, a3, b3 or T not finite and positive.
    NonPositiveParameter(&'static str),
    /// The continuous loop is not stable (Routh–Hurwitz fails).
    Unstable,
    /// The discrete loop at this update interval is not stable.
    UnstableAtInterval,
}

impl core::fmt::Display for LoopError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            LoopError::NonPositiveParameter(p) => write!(f, "loop parameter {p} must be finite and positive"),
            LoopError::Unstable => write!(f, "the loop filter gives an unstable loop"),
            LoopError::UnstableAtInterval => {
                write!(f, "the loop is unstable at this update interval (Bn·T too large)")
            }
        }
    }
}

impl core::error::Error for LoopError {}

/// A loop order [`LoopSpec::of_order`] has no Kaplan & Hegarty loop for
/// (it has 2 and 3).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LoopOrderError {
    /// The order asked for.
    pub order: u8,
}

impl core::fmt::Display for LoopOrderError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "order must be 2 or 3, got {}", self.order)
    }
}

impl core::error::Error for LoopOrderError {}

fn positive(x: f64, name: &'static str) -> Result<f64, LoopError> {
    if x.is_finite() && x > 0.0 { Ok(x) } else { Err(LoopError::NonPositiveParameter(name)) }
}

/// 2nd-order loop: Bn = (ωn/2)·(ζ + 1/(4ζ)) (Kaplan & Hegarty Table 5.6) → ωn \[rad/s\].
pub fn second_order_wn_from_bn(bn_hz: f64, zeta: f64) -> f64 {
    2.0 * bn_hz / (zeta + 1.0 / (4.0 * zeta))
}

/// 2nd-order loop: ωn \[rad/s\] → Bn \[Hz\], Bn = (ωn/2)·(ζ + 1/(4ζ)).
pub fn second_order_bn_from_wn(wn_rad_per_s: f64, zeta: f64) -> f64 {
    0.5 * wn_rad_per_s * (zeta + 1.0 / (4.0 * zeta))
}

/// 3rd-order loop Bn/ωn for F(s) = b3·ωn + a3·ωn²/s + ωn³/s²:
/// Bn/ωn = (a3·b3² + a3² − b3) / (4·(a3·b3 − 1)), the closed-form noise
/// bandwidth of H(s) = (b3·s² + a3·s + 1)/(s³ + b3·s² + a3·s + 1)
/// (0.7845 for Kaplan's a3 = 1.1, b3 = 2.4).
pub fn third_order_bn_over_wn(a3: f64, b3: f64) -> f64 {
    (a3 * b3 * b3 + a3 * a3 - b3) / (4.0 * (a3 * b3 - 1.0))
}

impl LoopSpec {
    /// The paper's loop: 2nd order, Bn = 3 Hz, ζ = 1/√2.
    pub const PAPER: LoopSpec =
        LoopSpec::SecondOrder { bn_hz: crate::defaults::DEFAULT_BN_HZ, zeta: core::f64::consts::FRAC_1_SQRT_2 };

    /// Kaplan & Hegarty's loop (Table 5.6) of `order` as a user states it:
    /// 2 → [`LoopSpec::SecondOrder`] of Bn = `bn_hz` \[Hz\] and damping
    /// `zeta`, F(s) = 2ζωn + ωn²/s; 3 → [`LoopSpec::ThirdOrder`] of Bn and
    /// `a3`, `b3`, F(s) = b3·ωn + a3·ωn²/s + ωn³/s². The shape parameters
    /// of the other order are not used. Any other order is a
    /// [`LoopOrderError`]; the values themselves are checked where the loop
    /// is built ([`LoopSpec::coeffs`], [`LoopError`]).
    pub fn of_order(order: u8, bn_hz: f64, zeta: f64, a3: f64, b3: f64) -> Result<LoopSpec, LoopOrderError> {
        match order {
            2 => Ok(LoopSpec::SecondOrder { bn_hz, zeta }),
            3 => Ok(LoopSpec::ThirdOrder { bn_hz, a3, b3 }),
            _ => Err(LoopOrderError { order }),
        }
    }

    /// Kaplan's 3rd-order loop with bandwidth `bn_hz`.
    pub fn third_order_kaplan(bn_hz: f64) -> LoopSpec {
        LoopSpec::ThirdOrder { bn_hz, a3: KAPLAN_A3, b3: KAPLAN_B3 }
    }

    /// Natural frequency ωn \[rad/s\] (None for raw coefficients of a 3rd-order
    /// filter, where ωn = c2^(1/3)).
    pub fn wn_rad_per_s(&self) -> Option<f64> {
        match *self {
            LoopSpec::SecondOrder { bn_hz, zeta } => Some(second_order_wn_from_bn(bn_hz, zeta)),
            LoopSpec::ThirdOrder { bn_hz, a3, b3 } => Some(bn_hz / third_order_bn_over_wn(a3, b3)),
            LoopSpec::Coefficients(c) => {
                if c.c2_per_s3 > 0.0 {
                    Some(libm::cbrt(c.c2_per_s3))
                } else if c.c1_per_s2 > 0.0 {
                    Some(sqrt(c.c1_per_s2))
                } else {
                    None
                }
            }
        }
    }

    /// Loop order (1, 2 or 3): the number of integrators in the loop.
    pub fn order(&self) -> u8 {
        let c = match self.coeffs() {
            Ok(c) => c,
            Err(_) => return 0,
        };
        if c.c2_per_s3 != 0.0 {
            3
        } else if c.c1_per_s2 != 0.0 {
            2
        } else {
            1
        }
    }

    /// The loop-filter coefficients, checked for stability of the continuous
    /// loop (Routh–Hurwitz on s³ + c0·s² + c1·s + c2: all positive, c0·c1 > c2).
    pub fn coeffs(&self) -> Result<LoopFilterCoeffs, LoopError> {
        let c = match *self {
            LoopSpec::SecondOrder { bn_hz, zeta } => {
                positive(bn_hz, "bn_hz")?;
                positive(zeta, "zeta")?;
                let wn = second_order_wn_from_bn(bn_hz, zeta);
                LoopFilterCoeffs { c0_per_s: 2.0 * zeta * wn, c1_per_s2: wn * wn, c2_per_s3: 0.0 }
            }
            LoopSpec::ThirdOrder { bn_hz, a3, b3 } => {
                positive(bn_hz, "bn_hz")?;
                positive(a3, "a3")?;
                positive(b3, "b3")?;
                if a3 * b3 <= 1.0 {
                    return Err(LoopError::Unstable);
                }
                let wn = bn_hz / third_order_bn_over_wn(a3, b3);
                LoopFilterCoeffs { c0_per_s: b3 * wn, c1_per_s2: a3 * wn * wn, c2_per_s3: wn * wn * wn }
            }
            LoopSpec::Coefficients(c) => c,
        };
        let finite = c.c0_per_s.is_finite() && c.c1_per_s2.is_finite() && c.c2_per_s3.is_finite();
        let hurwitz = c.c0_per_s > 0.0
            && c.c1_per_s2 >= 0.0
            && c.c2_per_s3 >= 0.0
            && (c.c2_per_s3 == 0.0 || (c.c1_per_s2 > 0.0 && c.c0_per_s * c.c1_per_s2 > c.c2_per_s3));
        if finite && hurwitz { Ok(c) } else { Err(LoopError::Unstable) }
    }
}

impl LoopFilterCoeffs {
    /// Continuous response L(j2πf) = −2π/(s + F(s)) at s = j2πf \[rad/Hz\].
    pub fn response_continuous(&self, f_hz: f64) -> Complex<f64> {
        let s = Complex::new(0.0, TAU * f_hz);
        if f_hz == 0.0 {
            // L(0) = 0 for any loop with an integrator; −2π/c0 for a 1st-order loop.
            return if self.c1_per_s2 != 0.0 || self.c2_per_s3 != 0.0 {
                Complex::new(0.0, 0.0)
            } else {
                Complex::new(-TAU / self.c0_per_s, 0.0)
            };
        }
        let f = Complex::new(self.c0_per_s, 0.0)
            + Complex::new(self.c1_per_s2, 0.0) / s
            + Complex::new(self.c2_per_s3, 0.0) / (s * s);
        Complex::new(-TAU, 0.0) / (s + f)
    }

    /// Closed-loop H(j2πf) = F/(s + F): the transfer from signal phase to
    /// replica phase, whose noise bandwidth is Bn = ∫₀^∞ |H(j2πf)|² df.
    pub fn closed_loop_continuous(&self, f_hz: f64) -> Complex<f64> {
        let s = Complex::new(0.0, TAU * f_hz);
        if f_hz == 0.0 {
            return Complex::new(1.0, 0.0);
        }
        let f = Complex::new(self.c0_per_s, 0.0)
            + Complex::new(self.c1_per_s2, 0.0) / s
            + Complex::new(self.c2_per_s3, 0.0) / (s * s);
        f / (s + f)
    }

    /// Discrete response L_d(e^{j2πfT}) from the sequence Δf_k to the sequence
    /// φ_k of the loop of this module's docs, updated every `t_s` seconds.
    pub fn response_discrete(&self, f_hz: f64, t_s: f64) -> Complex<f64> {
        let w = TAU * f_hz * t_s;
        let z = Complex::new(cos(w), sin(w));
        let one = Complex::new(1.0, 0.0);
        if f_hz == 0.0 || (z - one).norm_sqr() < 1e-300 {
            return self.response_continuous(0.0);
        }
        let zi = one / z;
        let g = Complex::new(PI * t_s, 0.0) * (z + one) / (z - one);
        let acc = one / (one - zi);
        let fd = Complex::new(self.c0_per_s, 0.0)
            + Complex::new(self.c1_per_s2 * t_s, 0.0) * acc
            + Complex::new(self.c2_per_s3 * t_s * t_s, 0.0) * acc * acc;
        -g / (one + g * zi * fd / Complex::new(TAU, 0.0))
    }

    /// Discrete response of the NCO command f_k in force during update k to
    /// the sequence Δf_k, for the loop of this module's docs \[Hz/Hz\]. The NCO
    /// accumulates the phase it ran at, so φ = −G(z)·(f + Δf) with
    /// G(z) = π·T·(z+1)/(z−1) (module docs), hence
    ///
    /// ```text
    /// f/Δf = −1 − L_d(z)/G(z) = −H_d(z)
    /// ```
    ///
    /// which tends to −H(s) = −F/(s + F) ([`Self::closed_loop_continuous`])
    /// as T → 0: the NCO follows the oscillator's frequency error through the
    /// closed loop, with the opposite sign.
    pub fn nco_response_discrete(&self, f_hz: f64, t_s: f64) -> Complex<f64> {
        let w = TAU * f_hz * t_s;
        let z = Complex::new(cos(w), sin(w));
        let one = Complex::new(1.0, 0.0);
        if f_hz == 0.0 || (z - one).norm_sqr() < 1e-300 {
            return -self.closed_loop_continuous(0.0);
        }
        let g = Complex::new(PI * t_s, 0.0) * (z + one) / (z - one);
        -one - self.response_discrete(f_hz, t_s) / g
    }

    /// Whether the discrete loop at update interval `t_s` is stable: every
    /// root of the characteristic polynomial of [`DiscretePll`] (the
    /// denominator of L_d(z), multiplied out),
    ///
    /// ```text
    /// P(z) = (2/T)·z·(z−1)³ + (z+1)·[c0·(z−1)² + c1·T·z·(z−1) + c2·T²·z²],
    /// ```
    ///
    /// lies strictly inside the unit circle (eigenvalues of its companion
    /// matrix). Without the second integrator (c2 = 0) both terms share a
    /// factor (z − 1) that cancels in L_d, and without the first (c1 = c2 = 0)
    /// another: they are divided out first.
    pub fn is_stable_at(&self, t_s: f64) -> bool {
        self.spectral_radius_at(t_s).is_some_and(|r| r * r < 1.0 - 1e-12)
    }

    /// The largest modulus of the roots of P(z) ([`LoopFilterCoeffs::is_stable_at`]):
    /// the discrete loop's slowest mode decays as ρᵏ per update. `None` for a
    /// non-positive interval or a matrix the Schur iteration cannot handle.
    pub fn spectral_radius_at(&self, t_s: f64) -> Option<f64> {
        if !(t_s.is_finite() && t_s > 0.0) {
            return None;
        }
        let (c0, c1, c2) = (self.c0_per_s, self.c1_per_s2, self.c2_per_s3);
        let k = 2.0 / t_s;
        if c2 != 0.0 {
            let a = c0 + c1 * t_s + c2 * t_s * t_s;
            let b = -2.0 * c0 - c1 * t_s;
            // k·z(z−1)³ + (z+1)(a z² + b z + c0), divided by k.
            let p = [(-3.0 * k + a) / k, (3.0 * k + a + b) / k, (-k + b + c0) / k, c0 / k];
            let m = nalgebra::Matrix4::new(
                -p[0], -p[1], -p[2], -p[3], //
                1.0, 0.0, 0.0, 0.0, //
                0.0, 1.0, 0.0, 0.0, //
                0.0, 0.0, 1.0, 0.0,
            );
            crate::math::SpectralRadius::spectral_radius(m)
        } else if c1 != 0.0 {
            // k·z(z−1)² + (z+1)((c0 + c1·T) z − c0), divided by k.
            let a = c0 + c1 * t_s;
            let p = [(-2.0 * k + a) / k, (k + a - c0) / k, -c0 / k];
            let m = nalgebra::Matrix3::new(
                -p[0], -p[1], -p[2], //
                1.0, 0.0, 0.0, //
                0.0, 1.0, 0.0,
            );
            crate::math::SpectralRadius::spectral_radius(m)
        } else {
            // k·z(z−1) + c0·(z+1), divided by k.
            let p = [(-k + c0) / k, c0 / k];
            let m = nalgebra::Matrix2::new(-p[0], -p[1], 1.0, 0.0);
            crate::math::SpectralRadius::spectral_radius(m)
        }
    }
}

/// Time for a discrete loop's slowest natural mode to decay by e⁻ⁿ, n =
/// `time_constants` \[s\]: `n·T/(−ln ρ)`, ρ the spectral radius of one
/// update's transition, T = `interval_s`. Infinite when ρ is unknown, NaN
/// or ≥ 1 (an unstable loop never settles); 0 when ρ ≤ 0.
pub(crate) fn settling_time_s(spectral_radius: Option<f64>, interval_s: f64, time_constants: f64) -> f64 {
    match spectral_radius {
        Some(r) if r > 0.0 && r < 1.0 => time_constants * interval_s / -crate::math::ln(r),
        Some(r) if r <= 0.0 => 0.0,
        _ => f64::INFINITY,
    }
}

/// The loop filter as receivers clock it: integrators updated once per update
/// interval T (see the module docs for the difference equations).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LoopFilter {
    coeffs: LoopFilterCoeffs,
    t_s: f64,
    /// First integrator a1 \[rad/s\]: the steady-state NCO frequency (×2π).
    acc1_rad_per_s: f64,
    /// Second integrator a2 \[rad/s²\]: the steady-state frequency rate (×2π).
    acc2_rad_per_s2: f64,
}

impl LoopFilter {
    /// A filter with coefficients `coeffs` updated every `t_s` seconds, integrators at zero.
    pub fn new(coeffs: LoopFilterCoeffs, t_s: f64) -> Self {
        LoopFilter { coeffs, t_s, acc1_rad_per_s: 0.0, acc2_rad_per_s2: 0.0 }
    }

    /// Update interval T \[s\].
    pub fn interval_s(&self) -> f64 {
        self.t_s
    }

    /// The coefficients.
    pub fn coeffs(&self) -> LoopFilterCoeffs {
        self.coeffs
    }

    /// Preloads the integrators with a frequency \[Hz\] and frequency rate \[Hz/s\]
    /// (from acquisition or aiding), as a receiver does when it starts tracking.
    pub fn preload(&mut self, freq_hz: f64, freq_rate_hz_per_s: f64) {
        self.acc1_rad_per_s = TAU * freq_hz;
        self.acc2_rad_per_s2 = if self.coeffs.c2_per_s3 != 0.0 { TAU * freq_rate_hz_per_s } else { 0.0 };
    }

    /// One update with discriminator output `phase_err_rad`; returns the NCO
    /// frequency command \[Hz\] for the next integration:
    /// a2 += c2·T·φ; a1 += T·(c1·φ + a2); f = (c0·φ + a1)/2π.
    #[inline]
    pub fn update(&mut self, phase_err_rad: f64) -> f64 {
        let c = &self.coeffs;
        self.acc2_rad_per_s2 += c.c2_per_s3 * self.t_s * phase_err_rad;
        self.acc1_rad_per_s += self.t_s * (c.c1_per_s2 * phase_err_rad + self.acc2_rad_per_s2);
        (c.c0_per_s * phase_err_rad + self.acc1_rad_per_s) * FRAC_1_TAU
    }
}

/// Loop filter + NCO: the part of a carrier loop shared by the estimator's
/// linear models and the simulator's correlator-level channels. The
/// discriminator is the caller's (a linear one in [`DiscretePll`], atan/atan2
/// on prompt I/Q in the simulator).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CarrierLoop {
    filter: LoopFilter,
    /// NCO commanded frequency for the current integration \[Hz\].
    nco_freq_hz: f64,
}

impl CarrierLoop {
    /// A loop at rest (commanded frequency 0).
    pub fn new(coeffs: LoopFilterCoeffs, t_s: f64) -> Self {
        CarrierLoop { filter: LoopFilter::new(coeffs, t_s), nco_freq_hz: 0.0 }
    }

    /// Starts tracking at `freq_hz` with rate `freq_rate_hz_per_s`.
    pub fn preload(&mut self, freq_hz: f64, freq_rate_hz_per_s: f64) {
        self.filter.preload(freq_hz, freq_rate_hz_per_s);
        self.nco_freq_hz = freq_hz;
    }

    /// The NCO's commanded frequency during the current integration \[Hz\].
    #[inline]
    pub fn nco_freq_hz(&self) -> f64 {
        self.nco_freq_hz
    }

    /// Update interval T \[s\].
    #[inline]
    pub fn interval_s(&self) -> f64 {
        self.filter.interval_s()
    }

    /// Phase advance of the replica over one integration \[rad\] when the NCO
    /// runs at its command plus the oscillator bias `bias_hz`: 2π·T·(f + Δf).
    #[inline]
    pub fn replica_advance_rad(&self, bias_hz: f64) -> f64 {
        TAU * self.filter.interval_s() * (self.nco_freq_hz + bias_hz)
    }

    /// Closes the loop at the end of an integration: feeds the discriminator
    /// output to the filter and commands the next integration's frequency.
    #[inline]
    pub fn close(&mut self, discriminator_rad: f64) {
        self.nco_freq_hz = self.filter.update(discriminator_rad);
    }
}

/// The linear discrete loop: one Δf sample in, one phase error out (the
/// difference equations of the module docs). This is the operator L in
/// discrete time, with an ideal (linear, mean-phase) discriminator.
///
/// Carrier-loop models: loop filter, NCO, the discrete loop as receivers run
/// it, and its frequency response.
///
/// # Signs and the operator L
///
/// φ = θ_signal − θ_replica \[rad\]; the oscillator adds Δf \[Hz\] to the NCO's
/// commanded frequency. For a loop filter
/// F(s) = c0 + c1/s + c2/s² (rad/s of NCO command per rad of phase error) the
/// continuous loop gives
///
/// ```text
/// L(s) = φ(s)/Δf(s) = −2π / (s + F(s)) = −2π·s² / (s³ + c0·s² + c1·s + c2)   [rad/Hz]
/// ```
///
/// which is docs/conventions.md's 2nd-order form with c0 = 2ζωn, c1 = ωn², c2 = 0
/// and Kaplan & Hegarty's 3rd-order form with c0 = b3·ωn, c1 = a3·ωn²,
/// c2 = ωn³ (Kaplan & Hegarty, *Understanding GPS*, 2nd ed., §5.3, Table 5.6).
///
/// # The discrete loop (what receivers run)
///
/// The loop is updated once per coherent integration of length T. Integration
/// k covers \[kT, (k+1)T\]; during it the NCO runs at the constant commanded
/// frequency f_k plus the oscillator bias Δf_k (its mean over the interval).
/// With e_k the phase error at the start of the interval:
///
/// ```text
/// φ_k      = e_k − π·T·(f_k + Δf̃_k)          discriminator: mean phase error over the interval
/// e_{k+1}  = e_k − 2π·T·(f_k + Δf_k)         NCO phase accumulates the frequency it ran at
/// a2_k     = a2_{k−1} + c2·T·φ_k             integrators updated once per T (rectangular rule)
/// a1_k     = a1_{k−1} + T·(c1·φ_k + a2_k)
/// f_{k+1}  = (c0·φ_k + a1_k) / 2π            applied to the next integration (one update of latency)
/// ```
///
/// This is the structure of the digital loop filter of Kaplan & Hegarty
/// (Fig. 5.17 and 5.18: accumulators clocked once per predetection integration,
/// the NCO as a phase accumulator) with the filter output applied to the next
/// integration, as it must be since the correlation of interval k ends at
/// (k+1)T. In z, with G(z) = π·T·(z+1)/(z−1) and
/// F_d(z) = c0 + c1·T/(1−z⁻¹) + c2·T²/(1−z⁻¹)²:
///
/// ```text
/// L_d(z) = −G(z) / (1 + G(z)·z⁻¹·F_d(z)/2π)
/// ```
///
/// which tends to L(s) as T → 0 (z = e^{sT}). Δf̃_k is Δf over the
/// integration weighted by the time left in it, 2(1 − s/T)/T (the mean of
/// the phase accumulated since the integration began): Δf_k for a constant
/// bias, which is what L_d assumes; [`LinearLoop::step_varying`] takes both.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DiscretePll {
    carrier: CarrierLoop,
    /// Phase error at the start of the current integration \[rad\].
    err_start_rad: f64,
}

impl DiscretePll {
    /// A loop at rest with filter `coeffs` updated every `t_s` seconds.
    pub fn new(coeffs: LoopFilterCoeffs, t_s: f64) -> Self {
        DiscretePll { carrier: CarrierLoop::new(coeffs, t_s), err_start_rad: 0.0 }
    }

    /// One integration with mean NCO frequency bias `delta_f_hz` over it;
    /// returns the discriminator output φ_k \[rad\].
    #[inline]
    pub fn step(&mut self, delta_f_hz: f64) -> f64 {
        self.step_varying(delta_f_hz, delta_f_hz)
    }

    /// [`DiscretePll::step`] with a bias that varies over the integration:
    /// its mean `delta_f_hz` advances the replica, its mean weighted by
    /// 2(1 − s/T)/T over the integration, `weighted_hz`, enters the mean
    /// phase error ([`LinearLoop::step_varying`]).
    #[inline]
    pub fn step_varying(&mut self, delta_f_hz: f64, weighted_hz: f64) -> f64 {
        let advance = self.carrier.replica_advance_rad(delta_f_hz);
        let phase_err_rad = self.err_start_rad - 0.5 * self.carrier.replica_advance_rad(weighted_hz);
        self.err_start_rad -= advance;
        self.carrier.close(phase_err_rad);
        phase_err_rad
    }

    /// Back to rest.
    pub fn reset(&mut self) {
        *self = DiscretePll::new(self.carrier.filter.coeffs(), self.carrier.interval_s());
    }

    /// Puts the loop in the steady state of a constant bias `delta_f_hz`: zero
    /// phase error, NCO command −Δf (a receiver that has been tracking for a
    /// while has long absorbed gravity's constant part of aᵀΓ).
    pub fn settle(&mut self, delta_f_hz: f64) {
        self.reset();
        self.carrier.preload(-delta_f_hz, 0.0);
    }
}

/// A linear model of a receiver's carrier loop, from the NCO frequency bias
/// Δf to the discriminator output φ, one loop update at a time: what the
/// estimator's regressor ([`crate::regressor::RegressorModel`]) runs three of.
/// Implemented by [`DiscretePll`] (the loop of this module's docs),
/// [`gnss_sdr::GnssSdrPll`] (GNSS-SDR's loop, exactly),
/// [`pocket_sdr::PocketSdrPll`] (PocketSDR's, exactly) and [`ModelLoop`]
/// (any of them, chosen at run time).
pub trait LinearLoop {
    /// One loop update with mean NCO frequency bias `delta_f_hz` \[Hz\] over
    /// it, constant over the integration; returns the discriminator output
    /// φ \[rad\].
    #[inline]
    fn step(&mut self, delta_f_hz: f64) -> f64 {
        self.step_varying(delta_f_hz, delta_f_hz)
    }
    /// One loop update with a bias that varies over the integration: its mean
    /// `delta_f_hz` \[Hz\] advances the replica, and the discriminator's mean
    /// phase error over the integration takes it weighted by the time left,
    /// 2(1 − s/T)/T with s from the integration's start (the phase
    /// accumulated since the start, averaged): `weighted_hz`, the same as the
    /// mean for a constant bias and Δf_c − (T/6)·Δf′ + O(T²) of the mean for a
    /// smooth one (Δf_c the centre value).
    fn step_varying(&mut self, delta_f_hz: f64, weighted_hz: f64) -> f64;
    /// Puts the loop in the steady state of a constant bias `delta_f_hz`.
    fn settle(&mut self, delta_f_hz: f64);
    /// Back to rest.
    fn reset(&mut self);
    /// The NCO command in force during the next update \[Hz\], without the
    /// oscillator's bias (what a receiver logs as its NCO frequency, less the
    /// satellite's carrier): −Δf in the steady state of a constant bias Δf, so
    /// that the command follows −H\[Δf\], H the closed-loop transfer.
    fn nco_freq_hz(&self) -> f64;
    /// The loop's state between two updates: with it and the next Δf the
    /// next update is determined. At most [`LOOP_STATE_LEN`] numbers in an
    /// order of the implementation's own; entries it does not use are 0.
    /// [`loop_state_space`] and the regressor's lifted recursion probe the loop
    /// through it.
    fn state(&self) -> LoopState;
    /// Sets the state [`LinearLoop::state`] returns (unused entries ignored).
    fn set_state(&mut self, state: &LoopState);
}

/// How many numbers a [`LinearLoop`]'s state holds at most.
pub const LOOP_STATE_LEN: usize = 4;

/// A [`LinearLoop`]'s state ([`LinearLoop::state`]).
pub type LoopState = [f64; LOOP_STATE_LEN];

/// The state-space form of one update of a linear loop, found by probing it
/// (it is linear, so one update from each unit state with Δf = 0 and one from
/// rest with Δf = 1 give every column):
///
/// ```text
/// s' = A·s + b·Δf,    φ = c·s + d·Δf      (s = LinearLoop::state)
/// ```
///
/// Returns (A, b, c, d).
pub fn loop_state_space<L: LinearLoop + Clone>(model_loop: &L) -> (Matrix4<f64>, Vector4<f64>, Vector4<f64>, f64) {
    let probe = |state: LoopState, delta_f_hz: f64| {
        let mut l = model_loop.clone();
        l.set_state(&state);
        let phi = l.step(delta_f_hz);
        (Vector4::from(l.state()), phi)
    };
    let mut a = Matrix4::zeros();
    let mut c = Vector4::zeros();
    for j in 0..LOOP_STATE_LEN {
        let mut s = [0.0; LOOP_STATE_LEN];
        s[j] = 1.0;
        let (next, phi) = probe(s, 0.0);
        a.set_column(j, &next);
        c[j] = phi;
    }
    let (b, d) = probe([0.0; LOOP_STATE_LEN], 1.0);
    (a, b, c, d)
}

impl LinearLoop for DiscretePll {
    #[inline]
    fn step_varying(&mut self, delta_f_hz: f64, weighted_hz: f64) -> f64 {
        DiscretePll::step_varying(self, delta_f_hz, weighted_hz)
    }
    fn settle(&mut self, delta_f_hz: f64) {
        DiscretePll::settle(self, delta_f_hz)
    }
    fn reset(&mut self) {
        DiscretePll::reset(self)
    }
    fn nco_freq_hz(&self) -> f64 {
        self.carrier.nco_freq_hz
    }
    /// (e, f, a1, a2): the phase error at the start of the next integration
    /// \[rad\], the NCO command during it \[Hz\], the filter's integrators.
    fn state(&self) -> LoopState {
        let f = &self.carrier.filter;
        [self.err_start_rad, self.carrier.nco_freq_hz, f.acc1_rad_per_s, f.acc2_rad_per_s2]
    }
    fn set_state(&mut self, state: &LoopState) {
        self.err_start_rad = state[0];
        self.carrier.nco_freq_hz = state[1];
        self.carrier.filter.acc1_rad_per_s = state[2];
        self.carrier.filter.acc2_rad_per_s2 = state[3];
    }
}

/// A loop model chosen at run time: the regressor's default loop type, so
/// that callers pick the receiver's loop implementation without generics.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ModelLoop {
    /// The loop of this module's docs (Kaplan & Hegarty's filter, rectangular integrators).
    Kaplan(DiscretePll),
    /// GNSS-SDR's DLL/PLL carrier loop ([`gnss_sdr`]).
    GnssSdr(gnss_sdr::GnssSdrPll),
    /// PocketSDR's carrier loop ([`pocket_sdr`]).
    PocketSdr(pocket_sdr::PocketSdrPll),
}

impl From<DiscretePll> for ModelLoop {
    fn from(p: DiscretePll) -> Self {
        ModelLoop::Kaplan(p)
    }
}

impl From<gnss_sdr::GnssSdrPll> for ModelLoop {
    fn from(p: gnss_sdr::GnssSdrPll) -> Self {
        ModelLoop::GnssSdr(p)
    }
}

impl From<pocket_sdr::PocketSdrPll> for ModelLoop {
    fn from(p: pocket_sdr::PocketSdrPll) -> Self {
        ModelLoop::PocketSdr(p)
    }
}

impl LinearLoop for ModelLoop {
    #[inline]
    fn step_varying(&mut self, delta_f_hz: f64, weighted_hz: f64) -> f64 {
        match self {
            ModelLoop::Kaplan(p) => p.step_varying(delta_f_hz, weighted_hz),
            ModelLoop::GnssSdr(p) => p.step_varying(delta_f_hz, weighted_hz),
            ModelLoop::PocketSdr(p) => p.step_varying(delta_f_hz, weighted_hz),
        }
    }
    fn settle(&mut self, delta_f_hz: f64) {
        match self {
            ModelLoop::Kaplan(p) => p.settle(delta_f_hz),
            ModelLoop::GnssSdr(p) => p.settle(delta_f_hz),
            ModelLoop::PocketSdr(p) => p.settle(delta_f_hz),
        }
    }
    fn reset(&mut self) {
        match self {
            ModelLoop::Kaplan(p) => p.reset(),
            ModelLoop::GnssSdr(p) => p.reset(),
            ModelLoop::PocketSdr(p) => p.reset(),
        }
    }
    fn nco_freq_hz(&self) -> f64 {
        match self {
            ModelLoop::Kaplan(p) => p.nco_freq_hz(),
            ModelLoop::GnssSdr(p) => p.nco_freq_hz(),
            ModelLoop::PocketSdr(p) => p.nco_freq_hz(),
        }
    }
    fn state(&self) -> LoopState {
        match self {
            ModelLoop::Kaplan(p) => p.state(),
            ModelLoop::GnssSdr(p) => p.state(),
            ModelLoop::PocketSdr(p) => p.state(),
        }
    }
    fn set_state(&mut self, state: &LoopState) {
        match self {
            ModelLoop::Kaplan(p) => p.set_state(state),
            ModelLoop::GnssSdr(p) => p.set_state(state),
            ModelLoop::PocketSdr(p) => p.set_state(state),
        }
    }
}

/// The sinusoid-response harness of the loop models' tests (the integration
/// tests include the same file).
#[cfg(test)]
pub(crate) mod sinusoid_response;
