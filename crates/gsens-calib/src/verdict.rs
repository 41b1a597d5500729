//! The plain verdict per axis: was the shaking good enough?
//!
//! For each axis: the dominant shaking frequency of the specific force (the
//! peak of its periodogram over 0.1–5 Hz, by FFT), the fraction of the loop's peak sensitivity |L| reached
//! there, the unexplained excitation from the information matrix, and whether
//! the predicted g-induced phase error stays in the discriminator's linear
//! range ([`session_linear_range_rad`]).

use gsens_core::{Discriminator, LoopModel};
use gsens_session::ChannelSummary;
use serde::{Deserialize, Serialize};

/// The discriminator's linear range for a session \[rad\], on L1's scale
/// (comparable with the predicted peak |φ_aᵀΓ̂|): the smallest over the used
/// channels of
///
/// ```text
/// R_lin,i · f_L1/f_c,i,   R_lin,i = Discriminator::linear_range_rad(C/N0_i, T)
/// ```
///
/// (R less 3.09 thermal σ of one output at the channel's median C/N0 and the
/// loop's update interval T): the weakest channel, and a channel on a carrier
/// above L1, which logs f_c/f_L1 times L1's phase error, meet the limit
/// first. Without a used channel: the noise-free range R.
pub fn session_linear_range_rad(channels: &[ChannelSummary], discriminator: Discriminator, interval_s: f64) -> f64 {
    let used = channels.iter().filter(|c| c.used);
    weakest_linear_range_rad(
        used.map(|c| (c.screening.median_cn0_dbhz.unwrap_or(c.mean_cn0_dbhz), c.carrier_hz)),
        discriminator,
        interval_s,
    )
}

/// [`session_linear_range_rad`] over tracks given as (C/N0 \[dB-Hz\],
/// carrier \[Hz\]): the smallest R_lin·f_L1/f_c, or the noise-free range
/// without a track.
pub(crate) fn weakest_linear_range_rad(
    tracks: impl Iterator<Item = (f64, f64)>,
    discriminator: Discriminator,
    interval_s: f64,
) -> f64 {
    tracks
        .map(|(cn0_dbhz, carrier_hz)| {
            let to_l1 = gsens_core::units::GPS_L1_HZ / carrier_hz;
            discriminator.linear_range_rad(gsens_core::units::cn0_dbhz_to_ratio_hz(cn0_dbhz), interval_s) * to_l1
        })
        .filter(|r| r.is_finite())
        .reduce(f64::min)
        .unwrap_or(discriminator.unambiguous_range_rad())
}

/// What the data say about one axis.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AxisVerdict {
    /// "x", "y" or "z".
    pub axis: String,
    /// Whether Γ along this axis is observable.
    pub observable: bool,
    /// Dominant frequency of the specific force along the axis \[Hz\] (None if it never moved).
    pub shaking_frequency_hz: Option<f64>,
    /// RMS of the specific force's variation along the axis \[m/s²\].
    pub shaking_rms_mps2: f64,
    /// |L(f_shake)| / max |L|: the fraction of the loop's peak sensitivity reached.
    pub fraction_of_peak_sensitivity: Option<f64>,
    /// The plain-language verdict.
    pub text: String,
}

/// Periodogram peak of `x` (mean removed) over 0.1–5 Hz (or up to 90 % of
/// Nyquist), by FFT of the series zero-padded to at least twice its length.
fn dominant_frequency_hz(x: &[f64], interval_s: f64) -> Option<f64> {
    let n = x.len();
    if n < 16 {
        return None;
    }
    let mean = x.iter().sum::<f64>() / n as f64;
    let len = crate::fft::fast_len(2 * n);
    // A real series: the real-input transform's bins 0 … len/2 are all the
    // periodogram has (half the memory and work of a complex one).
    let fft = crate::fft::real_forward(len);
    let mut input = fft.make_input_vec();
    for (slot, v) in input.iter_mut().zip(x) {
        *slot = v - mean;
    }
    let mut buf = fft.make_output_vec();
    fft.process(&mut input, &mut buf).ok()?;
    drop(input);
    let df = 1.0 / (len as f64 * interval_s);
    let nyquist = 0.5 / interval_s;
    let (lo, hi) = (0.1f64, 5.0f64.min(0.9 * nyquist));
    let (k_lo, k_hi) = ((lo / df).ceil() as usize, ((hi / df).floor() as usize).min(len / 2));
    let k = (k_lo..=k_hi).max_by(|&a, &b| buf[a].norm_sqr().total_cmp(&buf[b].norm_sqr()))?;
    Some(k as f64 * df)
}

/// Below this fraction of the loop's peak sensitivity an observable axis's
/// verdict advises shaking closer to the peak.
pub(crate) const ADVISED_BELOW_FRACTION: f64 = 0.5;

impl AxisVerdict {
    /// Whether the verdict's text advises how to shake (an unobservable
    /// axis, or one shaken below `ADVISED_BELOW_FRACTION` of the peak).
    pub fn advises_shaking(&self) -> bool {
        !self.observable || self.fraction_of_peak_sensitivity.is_some_and(|q| q < ADVISED_BELOW_FRACTION)
    }
}

/// The verdict for every axis.
pub(crate) fn axis_verdicts(
    accel_mps2: &[[f64; 3]],
    interval_s: f64,
    receiver_loop: &LoopModel,
    observable: [bool; 3],
    excitation_rms: [f64; 3],
    min_excitation_rms: f64,
) -> [AxisVerdict; 3] {
    // The loop's peak sensitivity; a loop without one (unstable) gets no fraction.
    let (peak_hz, peak) = receiver_loop.peak().map_or((f64::NAN, f64::NAN), |p| (p.f_hz, p.rad_per_hz));
    let response = |f: f64| receiver_loop.magnitude(f);
    let names = ["x", "y", "z"];
    [0, 1, 2].map(|i| {
        let x: Vec<f64> = accel_mps2.iter().map(|a| a[i]).collect();
        let mean = x.iter().sum::<f64>() / x.len().max(1) as f64;
        let rms = (x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / x.len().max(1) as f64).sqrt();
        let f = if rms > 1e-3 { dominant_frequency_hz(&x, interval_s) } else { None };
        let frac = f.map(|f| response(f) / peak).filter(|q| q.is_finite());
        let text = if observable[i] {
            match (f, frac) {
                (Some(f), Some(q)) if q < ADVISED_BELOW_FRACTION => format!(
                    "{}: observable, but shaken at {f:.2} Hz where the loop has only {:.0} % of its peak sensitivity; \
                     shaking closer to {peak_hz:.2} Hz (period {:.1} s) gives more",
                    names[i],
                    100.0 * q,
                    1.0 / peak_hz
                ),
                (Some(f), Some(q)) => format!(
                    "{}: observable — shaken at {f:.2} Hz ({:.0} % of the loop's peak sensitivity), excitation RMS {:.2}",
                    names[i],
                    100.0 * q,
                    excitation_rms[i]
                ),
                _ => format!("{}: observable, excitation RMS {:.2}", names[i], excitation_rms[i]),
            }
        } else if excitation_rms[i] >= min_excitation_rms {
            // Excited enough, yet σ above the ceiling: the phase error is too noisy for this much shaking.
            format!(
                "{}: too noisy — excitation RMS {:.2} is enough, but σ stays above the observability ceiling: shake \
                 longer along {}, or harder within the discriminator's range",
                names[i], excitation_rms[i], names[i]
            )
        } else {
            format!(
                "{}: too little excitation — shake harder along {} or closer to {peak_hz:.2} Hz (period {:.1} s)",
                names[i],
                names[i],
                1.0 / peak_hz
            )
        };
        AxisVerdict {
            axis: names[i].to_string(),
            observable: observable[i],
            shaking_frequency_hz: f,
            shaking_rms_mps2: rms,
            fraction_of_peak_sensitivity: frac,
            text,
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    #[test]
    fn finds_the_shaking_frequency_and_the_sensitivity_fraction() {
        let t = 0.025;
        let a: Vec<[f64; 3]> = (0..4000)
            .map(|k| {
                let tt = k as f64 * t;
                [2.0 * (core::f64::consts::TAU * 0.9 * tt).sin(), 1.5 * (core::f64::consts::TAU * 0.2 * tt).sin(), 9.8]
            })
            .collect();
        let l = LoopModel::kaplan(gsens_core::LoopSpec::PAPER, Some(t));
        let v = axis_verdicts(&a, t, &l, [true, true, false], [1.0, 0.1, 0.0], 0.05);
        assert!((v[0].shaking_frequency_hz.unwrap() - 0.9).abs() < 0.02, "{:?}", v[0]);
        assert!(v[0].fraction_of_peak_sensitivity.unwrap() > 0.95);
        assert!((v[1].shaking_frequency_hz.unwrap() - 0.2).abs() < 0.01, "{:?}", v[1]);
        // |L(0.2 Hz)|/|L(0.9 Hz)| of the paper loop ≈ 0.32: worth a hint.
        assert!(v[1].fraction_of_peak_sensitivity.unwrap() < 0.5);
        assert!(v[1].text.contains("closer to"), "{}", v[1].text);
        assert!(v[2].shaking_frequency_hz.is_none());
        assert!(v[2].text.starts_with("z: too little excitation"), "{}", v[2].text);
        // Excited above the floor but not observable: σ is the reason, not the shaking's size.
        let v = axis_verdicts(&a, t, &l, [false, true, false], [1.0, 0.1, 0.0], 0.05);
        assert!(v[0].text.starts_with("x: too noisy"), "{}", v[0].text);
    }
}
