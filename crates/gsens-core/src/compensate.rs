use crate::math::dot3;

/// φ − φ_aᵀΓ̂ \[rad\]: the phase error with the g-induced part removed.
#[inline]
pub fn compensated_phase_rad(phase_err_rad: f64, phi_a: &[f64; 3], gamma_hz_per_mps2: &[f64; 3]) -> f64 {
    phase_err_rad - dot3(phi_a, gamma_hz_per_mps2)
}

/// A real-time compensator for receiver firmware.
///
/// Compensation with an estimated Γ̂.
///
/// Post-processing: φ_comp = φ − φ_aᵀΓ̂ (the paper's Fig. 5). In a receiver:
/// the NCO command gets −aᵀΓ̂ added, cancelling the oscillator's Δf = aᵀΓ
/// before it reaches the loop.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Compensator {
    /// Γ̂ \[Hz/(m/s²)\] at the tracked carrier.
    pub gamma_hz_per_mps2: [f64; 3],
}

impl Compensator {
    /// NCO frequency correction \[Hz\] for specific force `accel_mps2`: −aᵀΓ̂.
    /// Add it to every carrier NCO's command; scale by f_other/f_carrier for
    /// another carrier.
    #[inline]
    pub fn nco_correction_hz(&self, accel_mps2: &[f64; 3]) -> f64 {
        -dot3(accel_mps2, &self.gamma_hz_per_mps2)
    }
}
