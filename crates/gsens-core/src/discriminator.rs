//! The carrier-phase discriminator: its kind, its thermal noise and the
//! range over which its output follows the phase error.

use crate::math::sqrt;

/// The false-alarm probability behind [`RANGE_MARGIN_SIGMAS`]: the chance
/// that one discriminator output, taken where the g-induced phase error
/// peaks, lies beyond the unambiguous range.
pub const RANGE_FALSE_ALARM: f64 = 1e-3;

/// k = Φ⁻¹(1 − [`RANGE_FALSE_ALARM`]) = 3.090: the thermal σ's of margin
/// between the predicted peak phase error and the unambiguous range
/// ([`Discriminator::linear_range_rad`]).
pub const RANGE_MARGIN_SIGMAS: f64 = 3.090_232_306_167_813_5;

/// A carrier-phase discriminator (I, Q the prompt correlator of one
/// integration).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum Discriminator {
    /// atan(Q/I), the two-quadrant Costas discriminator of GPS L1 C/A receivers: linear within ±π/2.
    ///
    /// The Costas (two-quadrant) arctangent atan(Q/I), insensitive to the
    /// navigation data's 180° transitions: what GPS L1 C/A receivers use
    /// (GNSS-SDR's `pll_cloop_two_quadrant_atan`, PocketSDR's `err_phas`).
    /// Its output follows the phase error within ±π/2.
    #[default]
    AtanCostas,
    /// atan2(Q, I), a four-quadrant PLL discriminator (pilot signals): linear within ±π.
    ///
    /// The four-quadrant arctangent atan2(Q, I) of a pure PLL (a pilot
    /// signal without data, GNSS-SDR's `pll_four_quadrant_atan`): ±π.
    Atan2,
}

impl Discriminator {
    /// The name used in files and on the command line.
    pub const fn name(self) -> &'static str {
        match self {
            Discriminator::AtanCostas => "atan_costas",
            Discriminator::Atan2 => "atan2",
        }
    }

    /// The phase error up to which the noise-free output equals the phase
    /// error \[rad\]: π/2 for atan(Q/I) (beyond it the output jumps by −π),
    /// π for atan2.
    pub const fn unambiguous_range_rad(self) -> f64 {
        match self {
            Discriminator::AtanCostas => core::f64::consts::FRAC_PI_2,
            Discriminator::Atan2 => core::f64::consts::PI,
        }
    }

    /// The largest g-induced phase error \[rad\] the discriminator follows at
    /// C/N0 `cn0_hz` (a ratio, Hz) and integration time `t_s`:
    ///
    /// ```text
    /// R_lin = R − k·σ_d,   σ_d² = (1 + 1/(2·T·C/N0))/(2·T·C/N0),   k = Φ⁻¹(1 − 10⁻³) = 3.09
    /// ```
    ///
    /// R is [`Discriminator::unambiguous_range_rad`], σ_d the thermal σ of
    /// one output ([`discriminator_variance_rad2`]). An output whose phase
    /// error plus noise passes R comes out about π (2π for atan2) off: it
    /// pulls the mean output, and so Γ̂, towards zero, and may start a slip.
    /// With the peak at R_lin at most a fraction 10⁻³ of the outputs at the
    /// peak do so (Gaussian noise); the mean output there is then biased by
    /// about π·10⁻³ = 3 mrad, a 0.3 % loss of gain at a 1 rad peak that
    /// falls off quickly (as the Gaussian tail) below it. At 45 dB-Hz and
    /// T = 1 ms: σ_d = 0.127 rad, R_lin = 1.18 rad for atan(Q/I); at T = 20 ms
    /// and 40 dB-Hz: 0.051 rad and 1.41 rad. Never below 0 (a channel too
    /// weak for any margin).
    pub fn linear_range_rad(self, cn0_hz: f64, t_s: f64) -> f64 {
        let sigma = sqrt(discriminator_variance_rad2(cn0_hz, t_s));
        (self.unambiguous_range_rad() - RANGE_MARGIN_SIGMAS * sigma).max(0.0)
    }
}

impl core::fmt::Display for Discriminator {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(self.name())
    }
}

impl core::str::FromStr for Discriminator {
    type Err = &'static str;

    /// `atan_costas` (also `atan-costas`, `atan`) or `atan2`.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "atan_costas" | "atan-costas" | "atan" => Ok(Discriminator::AtanCostas),
            "atan2" => Ok(Discriminator::Atan2),
            _ => Err("expected atan_costas or atan2"),
        }
    }
}

/// The variance \[rad²\] of one discriminator output from thermal noise alone,
/// for C/N0 `cn0_hz` (a ratio, Hz) and integration time `t_s`:
///
/// ```text
/// σ_d² = 1/(2·T·C/N0)·(1 + 1/(2·T·C/N0))
/// ```
///
/// (the second factor the squaring loss; Kaplan & Hegarty, *Understanding
/// GPS*, 2nd ed., §5.6, whose loop jitter Bn/(C/N0)·(1 + 1/(2·T·C/N0)) is
/// this times 2·Bn·T). With unit-variance noise on I and Q and a signal
/// amplitude √(2·T·C/N0), atan(Q/I) ≈ φ + n_Q/√(2·T·C/N0) near φ = 0.
pub fn discriminator_variance_rad2(cn0_hz: f64, t_s: f64) -> f64 {
    let snr = 2.0 * t_s * cn0_hz;
    (1.0 + 1.0 / snr) / snr
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_margin_is_the_normal_quantile_of_the_false_alarm_rate() {
        // Φ(−k) = erfc(k/√2)/2.
        let tail = 0.5 * libm::erfc(RANGE_MARGIN_SIGMAS / core::f64::consts::SQRT_2);
        assert!((tail / RANGE_FALSE_ALARM - 1.0).abs() < 1e-9, "{tail}");
    }

    #[test]
    fn ranges_follow_the_closed_form() {
        let c = 31_622.776_601_683_792; // 45 dB-Hz
        let snr = 2.0 * 1e-3 * c;
        let sigma = sqrt((1.0 + 1.0 / snr) / snr);
        let r = Discriminator::AtanCostas.linear_range_rad(c, 1e-3);
        assert!((r - (core::f64::consts::FRAC_PI_2 - 3.090_232 * sigma)).abs() < 1e-6);
        assert!((r - 1.1797).abs() < 1e-3, "{r}");
        let r2 = Discriminator::Atan2.linear_range_rad(c, 1e-3);
        assert!((r2 - r - core::f64::consts::FRAC_PI_2).abs() < 1e-12);
        // Noise-free: the unambiguous range itself; hopeless: 0.
        assert_eq!(Discriminator::AtanCostas.linear_range_rad(f64::INFINITY, 1e-3), core::f64::consts::FRAC_PI_2);
        assert_eq!(Discriminator::AtanCostas.linear_range_rad(1.0, 1e-3), 0.0);
        assert_eq!("atan2".parse(), Ok(Discriminator::Atan2));
        assert_eq!("atan-costas".parse(), Ok(Discriminator::AtanCostas));
        assert!("costas".parse::<Discriminator>().is_err());
    }
}
