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

/// C/N0 in dB-Hz → ratio \[Hz\].
pub fn cn0_dbhz_to_ratio_hz(cn0_dbhz: f64) -> f64 {
    crate::math::pow10(cn0_dbhz / 10.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    #[test]
    fn ppb_round_trip_and_paper_value() {
        // docs/conventions.md: 0.09 Hz/(m/s²) at L1 ≈ 0.56 ppb/g.
        let ppb = hz_per_mps2_to_ppb_per_g(0.09, GPS_L1_HZ);
        assert!((ppb - 0.56).abs() < 0.005, "{ppb}");
        assert!((ppb_per_g_to_hz_per_mps2(ppb, GPS_L1_HZ) - 0.09).abs() < 1e-15);
    }
}
