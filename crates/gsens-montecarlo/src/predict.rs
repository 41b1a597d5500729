//! The simulator's oscillator models as the frequency noise of a prediction
//! ([`gsens_calib::predict`]): the same power-law coefficients, so a
//! prediction and a simulated session share one oscillator.

use gsens_calib::predict::FrequencyNoise;
use gsens_sim::oscillator::OscillatorConfig;

/// The frequency noise S_y(f) = h₂f² + h₀ + h₋₁/f + h₋₂/f² of `oscillator`
/// at the carrier `carrier_hz` (the deterministic terms — offset, drift,
/// temperature cycle — are not noise and are left out).
pub fn frequency_noise(oscillator: &OscillatorConfig, carrier_hz: f64) -> FrequencyNoise {
    let o = oscillator;
    FrequencyNoise { h2: o.h2, h0: o.h0, h_neg1: o.h_neg1, h_neg2: o.h_neg2, carrier_hz }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_coefficients_are_the_simulators() {
        let o = OscillatorConfig::tcxo();
        let n = frequency_noise(&o, 1_575.42e6);
        assert_eq!((n.h2, n.h0, n.h_neg1, n.h_neg2, n.carrier_hz), (o.h2, o.h0, o.h_neg1, o.h_neg2, 1_575.42e6));
    }
}
