//! Huber's M-estimate of Γ by iteratively reweighted least squares (IRLS),
//! for logs with outliers the screening of the channels did not remove
//! (setting `robust = huber`).
//!
//! Over the epochs the batch fit used (φ and φ_a high-passed), starting from
//! the least-squares Γ̂:
//!
//! 1. residuals r_k = φ_k − φ_a,kᵀΓ̂ and their scale σ̂ = 1.4826·median|r_k|
//!    (the MAD about zero, which outliers do not inflate);
//! 2. Huber weights w_k = min(1, c/|r_k|) with c = 1.345·σ̂
//!    ([`HuberWeights::K_95`]: 95 % of the efficiency of least squares for
//!    Gaussian noise), weighted least squares → new Γ̂;
//! 3. repeated until Γ̂ moves by less than 1e-9 of its size (or
//!    [`MAX_ITERATIONS`]).
//!
//! The covariance is the M-estimator's sandwich `B⁻¹·S·B⁻¹`
//! ([`gsens_core::sandwich_covariance`]), with the scores ψ(r_k)·φ_a,k
//! autocorrelation-robust as for least squares (the residuals of a carrier
//! loop are coloured).
//!
//! Without outliers few residuals exceed c and Γ̂ stays close to least
//! squares; an epoch with a wild phase error counts with weight c/|r| instead
//! of pulling the fit quadratically.

use gsens_core::NormalEquations;
use gsens_core::{HuberWeights, sandwich_covariance};
use serde::{Deserialize, Serialize};

/// Most IRLS iterations.
pub(crate) const MAX_ITERATIONS: u32 = 50;

/// A Huber fit of Γ.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HuberFit {
    /// Γ̂ \[Hz/(m/s²)\].
    pub gamma_hz_per_mps2: [f64; 3],
    /// Sandwich covariance, autocorrelation-robust \[(Hz/(m/s²))²\].
    #[serde(skip)]
    pub covariance: [[f64; 3]; 3],
    /// Sandwich covariance without the autocorrelation terms (white residuals).
    #[serde(skip)]
    pub covariance_white: [[f64; 3]; 3],
    /// The residuals' robust scale σ̂ \[rad\].
    pub scale_rad: f64,
    /// The threshold c = 1.345·σ̂ \[rad\].
    pub threshold_rad: f64,
    /// Epochs with |r| > c (down-weighted).
    pub epochs_downweighted: usize,
    /// Epochs in the fit.
    pub epochs: usize,
    /// IRLS iterations run.
    pub iterations: u32,
    /// Whether Γ̂ converged within the iteration limit (50).
    pub converged: bool,
}

/// Median of |x| (of a copy); 0 for an empty slice, so that a fit without
/// residuals has no scale.
fn median_abs(x: &[f64]) -> f64 {
    if x.is_empty() {
        return 0.0;
    }
    let mut a: Vec<f64> = x.iter().map(|v| v.abs()).collect();
    gsens_core::stats::median_in_place(&mut a)
}

fn residuals(phase: &[f64], phi_a: &[[f64; 3]], g: &[f64; 3], out: &mut Vec<f64>) {
    out.clear();
    out.extend(phase.iter().zip(phi_a).map(|(p, a)| p - (a[0] * g[0] + a[1] * g[1] + a[2] * g[2])));
}

/// Huber IRLS over the epochs (`phase[k]`, `phi_a[k]`) from the starting
/// estimate `start` (least squares), tuning constant `k` (1.345), with
/// `max_lag` epochs of autocorrelation in the covariance. `None` when there
/// are fewer than 4 epochs.
pub fn huber_irls(phase: &[f64], phi_a: &[[f64; 3]], start: [f64; 3], k: f64, max_lag: usize) -> Option<HuberFit> {
    let n = phase.len().min(phi_a.len());
    if n < 4 {
        return None;
    }
    let (phase, phi_a) = (&phase[..n], &phi_a[..n]);
    let mut gamma = start;
    let mut r = Vec::with_capacity(n);
    let (mut iterations, mut converged) = (0, false);
    let mut h = HuberWeights::new(k, 0.0);
    while iterations < MAX_ITERATIONS {
        residuals(phase, phi_a, &gamma, &mut r);
        let scale = 1.4826 * median_abs(&r);
        if scale <= 0.0 {
            // More than half the residuals exactly zero: the fit is exact there.
            converged = true;
            break;
        }
        h = HuberWeights::new(k, scale);
        let mut normal = NormalEquations::default();
        for j in 0..n {
            h.add(&mut normal, phase[j], &phi_a[j], r[j]);
        }
        let next = normal.solve().gamma_hz_per_mps2;
        iterations += 1;
        let step = (0..3).map(|i| (next[i] - gamma[i]).powi(2)).sum::<f64>().sqrt();
        let size = next.iter().map(|v| v * v).sum::<f64>().sqrt();
        gamma = next;
        if step <= 1e-9 * size.max(1e-300) {
            converged = true;
            break;
        }
    }
    residuals(phase, phi_a, &gamma, &mut r);
    let scale = 1.4826 * median_abs(&r);
    if scale > 0.0 {
        h = HuberWeights::new(k, scale);
    }
    let mut bread = [[0.0; 3]; 3];
    let mut scores = Vec::with_capacity(n);
    let mut downweighted = 0;
    for j in 0..n {
        let (a, w) = (&phi_a[j], h.psi_prime(r[j]));
        for (row, &ai) in bread.iter_mut().zip(a) {
            for (b, &aj) in row.iter_mut().zip(a) {
                *b += w * ai * aj;
            }
        }
        scores.push(h.psi(r[j]));
        downweighted += usize::from(h.psi_prime(r[j]) == 0.0);
    }
    Some(HuberFit {
        gamma_hz_per_mps2: gamma,
        covariance: sandwich_covariance(&bread, phi_a, &scores, max_lag),
        covariance_white: sandwich_covariance(&bread, phi_a, &scores, 0),
        scale_rad: scale,
        threshold_rad: h.threshold,
        epochs_downweighted: downweighted,
        epochs: n,
        iterations,
        converged,
    })
}
