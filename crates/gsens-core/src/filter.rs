use crate::math::{TAU, exp};

/// First-order high-pass y_k = α·(y_{k−1} + x_k − x_{k−1}), α = e^{−2π·f_c·T}
/// (the "DC blocker"; H(z) = α(1 − z⁻¹)/(1 − αz⁻¹), gain ≈ 0.994 at 0.9 Hz
/// for f_c = 0.05 Hz at 40 Hz).
/// Primed with the first sample, so a constant input gives 0 from the start.
///
/// The identical high-pass applied to φ and φ_a before estimation.
///
/// The averaged phase error carries slow content the regressors do not model:
/// the steady-state error of the satellite's Doppler rate (−2π·ḟ/ωn² for a
/// 2nd-order loop, ~0.1 rad for 0.5 Hz/s at Bn = 3 Hz), oscillator wander,
/// multipath. A linear filter H applied to both sides keeps the model exact,
/// H\[φ\] = H\[φ_a\]ᵀΓ + H\[n\], so Γ̂ stays unbiased while the slow content goes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HighPass {
    alpha: f64,
    x_prev: f64,
    y: f64,
    primed: bool,
}

impl HighPass {
    /// A high-pass with corner `cutoff_hz` for samples `interval_s` apart;
    /// `cutoff_hz = 0` passes everything through.
    pub fn new(cutoff_hz: f64, interval_s: f64) -> Self {
        let alpha = if cutoff_hz > 0.0 { exp(-TAU * cutoff_hz * interval_s) } else { 1.0 };
        HighPass { alpha, x_prev: 0.0, y: 0.0, primed: false }
    }

    /// Filters one sample.
    #[inline]
    pub fn step(&mut self, x: f64) -> f64 {
        if self.alpha == 1.0 {
            return x;
        }
        if !self.primed {
            self.x_prev = x;
            self.primed = true;
        }
        self.y = self.alpha * (self.y + x - self.x_prev);
        self.x_prev = x;
        self.y
    }

    /// Time constant 1/(2π·f_c) in samples (0 when disabled).
    pub fn time_constant_samples(&self) -> f64 {
        if self.alpha >= 1.0 { 0.0 } else { -1.0 / crate::math::ln(self.alpha) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    #[test]
    fn blocks_dc_and_passes_the_shaking_band() {
        let t = 0.025;
        let mut h = HighPass::new(0.05, t);
        for _ in 0..10 {
            assert_eq!(h.step(0.3), 0.0);
        }
        // Gain at 0.9 Hz: |H(e^{jω})| of H(z) = α(1 − z⁻¹)/(1 − αz⁻¹), ≈ 0.994.
        let (a, w) = (exp(-TAU * 0.05 * t), TAU * 0.9 * t);
        let expect = a * 2.0 * libm::sin(w / 2.0) / libm::hypot(1.0 - a * libm::cos(w), a * libm::sin(w));
        let mut h = HighPass::new(0.05, t);
        let mut peak = 0.0f64;
        for k in 0..40_000 {
            let y = h.step(0.1 + libm::sin(TAU * 0.9 * k as f64 * t));
            if k > 30_000 {
                peak = peak.max(y.abs());
            }
        }
        assert!((peak - expect).abs() < 1e-4, "{peak} vs {expect}");
        assert!(expect > 0.99);
    }
}
