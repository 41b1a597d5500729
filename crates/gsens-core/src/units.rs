//! Unit conversions used across gsens.

/// Standard gravity \[m/s²\] (CGPM 1901), used for ppb/g.
pub const STANDARD_GRAVITY_MPS2: f64 = 9.806_65;

/// GPS L1 carrier frequency \[Hz\] (IS-GPS-200).
pub const GPS_L1_HZ: f64 = 1_575.42e6;

/// GPS L1 C/A code period \[s\] (1023 chips at 1.023 Mchip/s): the
/// shortest coherent integration of a carrier loop on it, and of any GNSS
/// open signal (L5, GLONASS and BeiDou B1I codes are 1 ms too; Galileo E1's
/// is 4 ms).
pub const L1CA_CODE_PERIOD_S: f64 = 1e-3;

/// Speed of light in vacuum \[m/s\].
pub const SPEED_OF_LIGHT_MPS: f64 = 299_792_458.0;

/// Γ \[Hz/(m/s²)\] at the carrier → normalized sensitivity \[ppb/g\]:
/// ppb/g = Γ · g₀ / f_carrier · 1e9 (docs/conventions.md, "Units and signs").
pub fn hz_per_mps2_to_ppb_per_g(gamma_hz_per_mps2: f64, carrier_hz: f64) -> f64 {
    gamma_hz_per_mps2 * STANDARD_GRAVITY_MPS2 / carrier_hz * 1e9
}

/// Inverse of [`hz_per_mps2_to_ppb_per_g`].
pub fn ppb_per_g_to_hz_per_mps2(ppb_per_g: f64, carrier_hz: f64) -> f64 {
    ppb_per_g * carrier_hz / STANDARD_GRAVITY_MPS2 / 1e9
}

/// C/N0 in dB-Hz → ratio \[Hz\]: C/N0 = 10^(C/N0\[dB-Hz\] / 10).
///
/// With the `std` feature this is `f64::powf` (the platform's `pow`), the
/// function the simulator's sessions and the checks' thresholds are computed
/// with, so their numbers keep every bit; without `std` it is libm's `pow`,
/// which differs from the platform's in the last bit for about one argument
/// in ten (far below any C/N0 estimate's precision). The crate's own
/// algorithms do not call it, so they stay bit-identical with and without
/// `std`.
pub fn cn0_dbhz_to_ratio_hz(cn0_dbhz: f64) -> f64 {
    #[cfg(feature = "std")]
    {
        10f64.powf(cn0_dbhz / 10.0)
    }
    #[cfg(not(feature = "std"))]
    {
        crate::math::pow10(cn0_dbhz / 10.0)
    }
}

/// Significant digits a computed number keeps in a message: f64 arithmetic
/// (sums, products, least-squares fits) leaves noise in the last few of its
/// 15–17, which is no part of the value (0.1 + 0.2 is 0.30000000000000004;
/// a 40 Hz log's interval fitted to its time stamps, 0.025000000000000026).
pub const MESSAGE_SIGNIFICANT_DIGITS: i32 = 12;

/// A computed number as a message shows it: rounded to
/// [`MESSAGE_SIGNIFICANT_DIGITS`] significant digits, or to 6 decimals where
/// that keeps more (a GPS time of 1.4e9 s to the µs), and printed in its
/// shortest form (`0.025`, `1`, `3.3`), in exponent form beyond
/// [1e-4, 1e12) (`1e300`, not three hundred digits); zero and non-finite
/// values as they are. For values read from a file or an option, which
/// print as written, plain `{}` is right.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Decimal(pub f64);

impl core::fmt::Display for Decimal {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let x = self.0;
        if x == 0.0 || !x.is_finite() {
            return write!(f, "{x}");
        }
        // Scale by an exact power of ten, so that the integer over (or
        // times) it is the decimal's correctly rounded f64 and Display
        // prints the decimal.
        let exp10 = libm::floor(libm::log10(libm::fabs(x))) as i32;
        let shift = (MESSAGE_SIGNIFICANT_DIGITS - 1 - exp10).max(6);
        let r = if shift >= 0 {
            let p = libm::pow(10.0, f64::from(shift));
            libm::round(x * p) / p
        } else {
            libm::round(x / libm::pow(10.0, f64::from(-shift))) * libm::pow(10.0, f64::from(-shift))
        };
        let r = if r.is_finite() { r } else { x };
        if (1e-4..1e12).contains(&libm::fabs(r)) { write!(f, "{r}") } else { write!(f, "{r:e}") }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decimal_drops_arithmetic_noise_and_keeps_written_digits() {
        // 0.025000000000000026 is what a fitted 40 Hz log interval came out as.
        assert_eq!(format!("{}", Decimal(0.025000000000000026)), "0.025");
        assert_eq!(format!("{}", Decimal(0.1 + 0.2)), "0.3");
        assert_eq!(format!("{}", Decimal(25.0 * 0.001 * 1e3)), "25");
        assert_eq!(format!("{}", Decimal(-2.976367123)), "-2.976367123");
        assert_eq!(format!("{}", Decimal(1391428818.125)), "1391428818.125");
        assert_eq!(format!("{}", Decimal(1391428818.0 + 0.025 * 3.0)), "1391428818.075");
        assert_eq!(format!("{}", Decimal(2.5e13 + 0.1)), "2.50000000000001e13");
        assert_eq!(format!("{}", Decimal(1e300)), "1e300");
        assert_eq!(format!("{}", Decimal(-1.5e-7)), "-1.5e-7");
        assert_eq!(format!("{}", Decimal(0.0)), "0");
        assert_eq!(format!("{}", Decimal(f64::NAN)), "NaN");
    }
    #[test]
    fn ppb_round_trip_and_paper_value() {
        // docs/conventions.md: 0.09 Hz/(m/s²) at L1 ≈ 0.56 ppb/g.
        let ppb = hz_per_mps2_to_ppb_per_g(0.09, GPS_L1_HZ);
        assert!((ppb - 0.56).abs() < 0.005, "{ppb}");
        assert!((ppb_per_g_to_hz_per_mps2(ppb, GPS_L1_HZ) - 0.09).abs() < 1e-15);
    }
}
