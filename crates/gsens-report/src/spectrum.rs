//! Welch power spectral density.

use rustfft::FftPlanner;
use rustfft::num_complex::Complex;

/// A one-sided power spectral density.
#[derive(Debug, Clone, PartialEq)]
pub struct Psd {
    /// Frequencies \[Hz\], from 0 to the Nyquist frequency.
    pub frequency_hz: Vec<f64>,
    /// Density \[unit²/Hz\] at each frequency.
    pub density: Vec<f64>,
    /// Segments averaged.
    pub segments: usize,
}

/// Welch's estimate of the one-sided PSD of `x` sampled every `interval_s`:
/// Hann-windowed segments of `segment_len` samples (shortened to the record
/// when it is shorter), 50 % overlap, the mean removed per segment, scaled so
/// that Σ density·Δf equals the variance (Parseval). `None` when fewer than 8
/// samples or a non-positive interval.
pub fn welch_psd(x: &[f64], interval_s: f64, segment_len: usize) -> Option<Psd> {
    if x.len() < 8 || !(interval_s > 0.0 && interval_s.is_finite()) {
        return None;
    }
    let n = segment_len.clamp(8, x.len());
    let step = (n / 2).max(1);
    let window: Vec<f64> = (0..n).map(|i| 0.5 - 0.5 * (core::f64::consts::TAU * i as f64 / n as f64).cos()).collect();
    let w2: f64 = window.iter().map(|w| w * w).sum();
    let fs = 1.0 / interval_s;
    let fft = FftPlanner::<f64>::new().plan_fft_forward(n);
    let bins = n / 2 + 1;
    let mut acc = vec![0.0; bins];
    let mut buf = vec![Complex::new(0.0, 0.0); n];
    let mut segments = 0;
    let mut start = 0;
    while start + n <= x.len() {
        let seg = &x[start..start + n];
        let mean = seg.iter().sum::<f64>() / n as f64;
        for ((b, &v), w) in buf.iter_mut().zip(seg).zip(&window) {
            *b = Complex::new((v - mean) * w, 0.0);
        }
        fft.process(&mut buf);
        for (k, a) in acc.iter_mut().enumerate() {
            // One-sided: double every bin but DC and (for even n) Nyquist.
            let two = if k == 0 || 2 * k == n { 1.0 } else { 2.0 };
            *a += two * buf[k].norm_sqr() / (fs * w2);
        }
        segments += 1;
        start += step;
    }
    Some(Psd {
        frequency_hz: (0..bins).map(|k| k as f64 * fs / n as f64).collect(),
        density: acc.into_iter().map(|a| a / segments as f64).collect(),
        segments,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sine_power_and_white_level() {
        // A sine of amplitude 1 at 2 Hz: power 0.5 concentrated near 2 Hz.
        let dt = 0.025;
        let x: Vec<f64> = (0..8192).map(|k| (core::f64::consts::TAU * 2.0 * k as f64 * dt).sin()).collect();
        let p = welch_psd(&x, dt, 1024).unwrap();
        let df = p.frequency_hz[1];
        let total: f64 = p.density.iter().sum::<f64>() * df;
        assert!((total - 0.5).abs() < 0.02, "total power {total}");
        let kmax = p.density.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1)).unwrap().0;
        assert!((p.frequency_hz[kmax] - 2.0).abs() <= df);
        assert_eq!(p.segments, 15);

        // Deterministic "white" sequence (LCG): flat density σ²/(fs/2).
        let mut s: u64 = 12345;
        let y: Vec<f64> = (0..40_000)
            .map(|_| {
                s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
            })
            .collect();
        let p = welch_psd(&y, dt, 256).unwrap();
        let expect = (1.0 / 12.0) / (0.5 / dt);
        let mid: f64 = p.density[20..100].iter().sum::<f64>() / 80.0;
        assert!((mid / expect - 1.0).abs() < 0.1, "{mid} vs {expect}");
    }

    #[test]
    fn too_short() {
        assert!(welch_psd(&[1.0; 5], 0.1, 4).is_none());
        assert!(welch_psd(&[1.0; 50], 0.0, 16).is_none());
    }
}
