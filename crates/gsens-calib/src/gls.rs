//! Generalized least squares under coloured noise, and the Cramér–Rao bound.
//!
//! The residual n_k of φ_k = φ_a,kᵀΓ + n_k is coloured: thermal noise shaped
//! by the loop and the logging, oscillator noise shaped by the loop (a band
//! around ωn), what the high-pass leaves of the slow content. Ordinary least
//! squares stays unbiased but is not efficient when the noise spectrum S(f)
//! varies over the band the regressors occupy, and its white-noise covariance
//! is wrong.
//!
//! # The estimator
//!
//! The noise is modelled as an autoregressive process of order p,
//! A(z)·n = e with A(z) = 1 + Σ_{j=1..p} a_j z^{−j} and e white of variance σ²
//! (an AR model approximates any continuous spectrum as p grows). Then
//! filtering φ and φ_a by the same A(z) leaves the model exact,
//! A\[φ\] = A\[φ_a\]ᵀΓ + e, with white noise: least squares on the filtered
//! ("prewhitened") series is the generalized least-squares estimate and, for
//! Gaussian noise, the maximum-likelihood one (conditional on the first p
//! samples of each segment, which only start the filter). The steps:
//!
//! 1. least squares on the series as they are (the batch estimate);
//! 2. its residuals → AR model by Burg's method, the order p ≤ `max_order`
//!    chosen by Akaike's criterion N·ln σ̂_p² + 2p;
//! 3. φ and φ_a prewhitened by that A(z), least squares again;
//! 4. steps 2–3 once more from the new residuals.
//!
//! The series may have gaps: it comes as contiguous segments, each filtered on
//! its own (the first p epochs of a segment only prime the filter), and Burg's
//! sums run over all segments.
//!
//! # The bound
//!
//! For Gaussian noise of spectrum S(f) the Fisher information on Γ is (Whittle)
//! J = Σ_f X(f)ᴴ S(f)⁻¹ X(f), X the regressors' transform; for AR noise this is
//! exactly J = X_wᵀX_w/σ², X_w the prewhitened regressors (conditional
//! likelihood; the first p epochs of a segment are a vanishing correction). The
//! Cramér–Rao bound on each component is √(J⁻¹)_ii, reported by
//! [`GlsFit::crlb_hz_per_mps2`]. It depends on the data and the noise, not on
//! the method: an unbiased estimator's spread cannot be below it, and
//! the GLS estimate reaches it when the AR model captures the noise.

use core::ops::Range;
use gsens_core::estimator::{GammaEstimate, NormalEquations, hac_covariance};
use serde::Serialize;

/// Default highest AR order tried by the order selection (0.75 s at 40 Hz).
pub const DEFAULT_MAX_AR_ORDER: usize = 30;

/// An autoregressive noise model: e_k = x_k + Σ_{j=1..p} a_j·x_{k−j} is white
/// with variance σ² (the whitening filter A(z) = 1 + Σ a_j z^{−j}).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ArModel {
    /// a_1 … a_p.
    pub coeffs: Vec<f64>,
    /// Innovation variance σ² (in the series' unit squared).
    pub innovation_variance: f64,
}

impl ArModel {
    /// White noise of variance `variance` (order 0).
    pub fn white(variance: f64) -> Self {
        ArModel { coeffs: Vec::new(), innovation_variance: variance }
    }

    /// The order p.
    pub fn order(&self) -> usize {
        self.coeffs.len()
    }

    /// The innovations e_k = x_k + Σ a_j x_{k−j} of one contiguous segment, for
    /// k = p … len−1 (empty when the segment is not longer than p).
    pub fn whiten(&self, x: &[f64]) -> Vec<f64> {
        let p = self.order();
        (p..x.len().max(p))
            .map(|k| x[k] + self.coeffs.iter().enumerate().map(|(j, a)| a * x[k - 1 - j]).sum::<f64>())
            .collect()
    }

    /// One-sided power spectral density at `f_hz` for samples `interval_s`
    /// apart: 2·σ²·T/|A(e^{j2πfT})|² [unit²/Hz].
    pub fn psd_one_sided(&self, f_hz: f64, interval_s: f64) -> f64 {
        let w = core::f64::consts::TAU * f_hz * interval_s;
        let (mut re, mut im) = (1.0, 0.0);
        for (j, a) in self.coeffs.iter().enumerate() {
            let ph = w * (j + 1) as f64;
            re += a * ph.cos();
            im -= a * ph.sin();
        }
        2.0 * self.innovation_variance * interval_s / (re * re + im * im)
    }
}

/// Burg's method over several segments of one process: the AR models of every
/// order 0 … `max_order` (fewer if the data run out).
///
/// Order m's reflection coefficient minimizes the summed energy of the forward
/// and backward prediction errors of all segments,
/// κ_m = −2·Σ f_k b_{k−1} / Σ (f_k² + b_{k−1}²), the coefficients follow
/// Levinson's update a_j ← a_j + κ_m·a_{m−j}, a_m = κ_m, and
/// σ_m² = σ_{m−1}²·(1 − κ_m²), σ_0² the mean square. |κ_m| ≤ 1, so every model
/// is stable.
pub fn burg(segments: &[&[f64]], max_order: usize) -> Vec<ArModel> {
    let total: usize = segments.iter().map(|s| s.len()).sum();
    let energy: f64 = segments.iter().flat_map(|s| s.iter()).map(|x| x * x).sum();
    let mut models = vec![ArModel::white(if total > 0 { energy / total as f64 } else { 0.0 })];
    let mut fwd: Vec<Vec<f64>> = segments.iter().map(|s| s.to_vec()).collect();
    let mut bwd = fwd.clone();
    let mut a: Vec<f64> = Vec::new();
    let mut var = models[0].innovation_variance;
    for m in 1..=max_order {
        let (mut num, mut den) = (0.0, 0.0);
        for (f, b) in fwd.iter().zip(&bwd) {
            for k in m..f.len() {
                num += f[k] * b[k - 1];
                den += f[k] * f[k] + b[k - 1] * b[k - 1];
            }
        }
        if den <= 0.0 || !den.is_finite() {
            break;
        }
        let kappa = -2.0 * num / den;
        let prev = a.clone();
        for j in 0..prev.len() {
            a[j] = prev[j] + kappa * prev[prev.len() - 1 - j];
        }
        a.push(kappa);
        for (f, b) in fwd.iter_mut().zip(bwd.iter_mut()) {
            // Downwards, so that b[k − 1] still holds order m − 1 when read.
            for k in (m..f.len()).rev() {
                let (fk, bk1) = (f[k], b[k - 1]);
                f[k] = fk + kappa * bk1;
                b[k] = bk1 + kappa * fk;
            }
        }
        var *= 1.0 - kappa * kappa;
        models.push(ArModel { coeffs: a.clone(), innovation_variance: var });
    }
    models
}

/// The AR model of the segments by Burg's method, its order (≤ `max_order`)
/// chosen by Akaike's criterion N·ln σ_p² + 2p, N the number of samples.
pub fn fit_ar(segments: &[&[f64]], max_order: usize) -> ArModel {
    let n = segments.iter().map(|s| s.len()).sum::<usize>() as f64;
    let aic = |m: &ArModel| n * m.innovation_variance.max(f64::MIN_POSITIVE).ln() + 2.0 * m.order() as f64;
    burg(segments, max_order)
        .into_iter()
        .min_by(|x, y| aic(x).total_cmp(&aic(y)))
        .expect("burg returns at least the order-0 model")
}

/// Settings of [`gls`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct GlsSettings {
    /// Highest AR order tried.
    pub max_ar_order: usize,
    /// Fit-noise-then-refit rounds after the first least-squares pass (≥ 1).
    pub iterations: usize,
    /// Longest lag of the autocorrelation-robust covariance of the
    /// prewhitened fit, in epochs (what colour the AR model missed).
    pub hac_max_lag: usize,
}

impl Default for GlsSettings {
    fn default() -> Self {
        GlsSettings { max_ar_order: DEFAULT_MAX_AR_ORDER, iterations: 2, hac_max_lag: 100 }
    }
}

/// The result of [`gls`].
#[derive(Debug, Clone, PartialEq)]
pub struct GlsFit {
    /// Γ̂ from the prewhitened least squares; its covariance σ̂_w²(X_wᵀX_w)⁺ is
    /// J⁻¹, the Cramér–Rao bound at the fitted noise model (+∞ on the diagonal
    /// of unobservable axes).
    pub estimate: GammaEstimate,
    /// Autocorrelation-robust (Newey–West) covariance of the prewhitened fit.
    pub robust_covariance: [[f64; 3]; 3],
    /// The noise model of the residuals (the last one fitted).
    pub noise: ArModel,
    /// Normal equations of the prewhitened series.
    pub whitened_normal: NormalEquations,
}

impl GlsFit {
    /// Cramér–Rao bound on each component, √(J⁻¹)_ii [Hz/(m/s²)] (+∞ when unobservable).
    pub fn crlb_hz_per_mps2(&self) -> [f64; 3] {
        self.estimate.sigma_hz_per_mps2()
    }
}

/// The contiguous runs of `true` in `used`, as index ranges.
pub fn segments_of(used: impl IntoIterator<Item = bool>) -> Vec<Range<usize>> {
    let mut out = Vec::new();
    let mut start = None;
    let mut k = 0;
    for u in used {
        match (u, start) {
            (true, None) => start = Some(k),
            (false, Some(s)) => {
                out.push(s..k);
                start = None;
            }
            _ => {}
        }
        k += 1;
    }
    if let Some(s) = start {
        out.push(s..k);
    }
    out
}

/// Normal equations of the series over the segments, each prewhitened by `ar`;
/// also returns the prewhitened regressors and measurements.
fn whitened(
    phase: &[f64],
    phi_a: &[[f64; 3]],
    segments: &[Range<usize>],
    ar: &ArModel,
) -> (NormalEquations, Vec<[f64; 3]>, Vec<f64>) {
    let mut ne = NormalEquations::default();
    let (mut xw, mut yw) = (Vec::new(), Vec::new());
    let p = ar.order();
    for r in segments {
        if r.len() <= p {
            continue;
        }
        let y = ar.whiten(&phase[r.clone()]);
        let cols: [Vec<f64>; 3] =
            [0, 1, 2].map(|i| ar.whiten(&phi_a[r.clone()].iter().map(|v| v[i]).collect::<Vec<_>>()));
        for k in 0..y.len() {
            let v = [cols[0][k], cols[1][k], cols[2][k]];
            ne.add(y[k], &v);
            xw.push(v);
            yw.push(y[k]);
        }
    }
    (ne, xw, yw)
}

/// Residuals φ − φ_aᵀΓ over each segment.
fn residuals(phase: &[f64], phi_a: &[[f64; 3]], segments: &[Range<usize>], gamma: &[f64; 3]) -> Vec<Vec<f64>> {
    segments
        .iter()
        .map(|r| r.clone().map(|k| phase[k] - (0..3).map(|i| phi_a[k][i] * gamma[i]).sum::<f64>()).collect())
        .collect()
}

/// Generalized least squares of φ = φ_aᵀΓ + n with AR noise over the given
/// segments of the series (see the module documentation). `None` when fewer
/// than 10 prewhitened epochs remain.
pub fn gls(phase: &[f64], phi_a: &[[f64; 3]], segments: &[Range<usize>], settings: &GlsSettings) -> Option<GlsFit> {
    let mut ar = ArModel::white(1.0);
    let (mut ne, mut xw, mut yw) = whitened(phase, phi_a, segments, &ar);
    if ne.n < 10 {
        return None;
    }
    let mut est = ne.solve();
    for _ in 0..settings.iterations.max(1) {
        let res = residuals(phase, phi_a, segments, &est.gamma_hz_per_mps2);
        let refs: Vec<&[f64]> = res.iter().map(|r| r.as_slice()).collect();
        // Keep at least ~20 samples per AR coefficient.
        let n: usize = refs.iter().map(|r| r.len()).sum();
        let candidate = fit_ar(&refs, settings.max_ar_order.min(n / 20));
        let (ne_c, xw_c, yw_c) = whitened(phase, phi_a, segments, &candidate);
        if ne_c.n < 10 {
            break;
        }
        (ar, ne, xw, yw) = (candidate, ne_c, xw_c, yw_c);
        est = ne.solve();
    }
    let resid: Vec<f64> =
        yw.iter().zip(&xw).map(|(y, x)| y - (0..3).map(|i| x[i] * est.gamma_hz_per_mps2[i]).sum::<f64>()).collect();
    let robust_covariance = hac_covariance(&xw, &resid, settings.hac_max_lag);
    ar.innovation_variance = est.residual_variance_rad2;
    Some(GlsFit { estimate: est, robust_covariance, noise: ar, whitened_normal: ne })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, StandardNormal};
    use rand_xoshiro::Xoshiro256PlusPlus;

    fn ar_series(coeffs: &[f64], n: usize, seed: u64) -> Vec<f64> {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
        let mut x = vec![0.0; n + 500];
        for k in 0..x.len() {
            let e: f64 = StandardNormal.sample(&mut rng);
            x[k] = e - coeffs.iter().enumerate().filter(|(j, _)| k > *j).map(|(j, a)| a * x[k - 1 - j]).sum::<f64>();
        }
        x.split_off(500)
    }

    /// Burg's recursion from its definition: at each order, filter the data
    /// with the order m−1 forward and backward predictors from scratch and
    /// minimize the summed error energy in closed form.
    fn naive_burg(segments: &[&[f64]], max_order: usize) -> Vec<Vec<f64>> {
        let mut a: Vec<f64> = Vec::new();
        let mut out = vec![Vec::new()];
        for m in 1..=max_order {
            // Filter with taps [1, a_1 … a_{m−1}].
            let taps: Vec<f64> = core::iter::once(1.0).chain(a.iter().copied()).collect();
            let (mut num, mut den) = (0.0, 0.0);
            for s in segments {
                for k in m..s.len() {
                    let f: f64 = (0..m).map(|j| taps[j] * s[k - j]).sum();
                    // Backward error of order m−1 at k−1: Σ_j taps[j]·x[k−1−(m−1)+j].
                    let b: f64 = (0..m).map(|j| taps[j] * s[k - m + j]).sum();
                    num += f * b;
                    den += f * f + b * b;
                }
            }
            let kappa = -2.0 * num / den;
            let prev = a.clone();
            a = (0..m).map(|j| if j + 1 == m { kappa } else { prev[j] + kappa * prev[m - 2 - j] }).collect();
            out.push(a.clone());
        }
        out
    }

    #[test]
    fn burg_matches_its_definition_over_segments() {
        let x = ar_series(&[-1.6, 0.8], 3000, 1);
        let segs: Vec<&[f64]> = vec![&x[..700], &x[710..715], &x[720..2500], &x[2600..]];
        let fast = burg(&segs, 12);
        let slow = naive_burg(&segs, 12);
        assert_eq!(fast.len(), 13);
        for (m, (f, s)) in fast.iter().zip(&slow).enumerate() {
            assert_eq!(f.order(), m);
            for (a, b) in f.coeffs.iter().zip(s) {
                assert!((a - b).abs() < 1e-10, "order {m}: {:?} vs {:?}", f.coeffs, s);
            }
        }
    }

    #[test]
    fn recovers_a_known_ar2_and_its_order() {
        // x_k − 1.6 x_{k−1} + 0.8 x_{k−2} = e_k: a resonance, like the loop's.
        let x = ar_series(&[-1.6, 0.8], 40_000, 2);
        let m = fit_ar(&[&x], 30);
        assert!(m.order() >= 2 && m.order() <= 6, "order {}", m.order());
        assert!((m.coeffs[0] + 1.6).abs() < 0.02 && (m.coeffs[1] - 0.8).abs() < 0.02, "{:?}", m.coeffs);
        assert!((m.innovation_variance - 1.0).abs() < 0.03, "{}", m.innovation_variance);
        // Whitening with the true filter gives back the innovations: white, unit variance.
        let e = ArModel { coeffs: vec![-1.6, 0.8], innovation_variance: 1.0 }.whiten(&x);
        let var = e.iter().map(|v| v * v).sum::<f64>() / e.len() as f64;
        let r1 = e.windows(2).map(|w| w[0] * w[1]).sum::<f64>() / e.len() as f64 / var;
        assert!((var - 1.0).abs() < 0.03 && r1.abs() < 0.03, "{var} {r1}");
        // White noise gets a low order.
        let w = ar_series(&[], 20_000, 3);
        assert!(fit_ar(&[&w], 30).order() <= 3);
    }

    #[test]
    fn psd_of_ar1_matches_closed_form() {
        let m = ArModel { coeffs: vec![-0.9], innovation_variance: 2.0 };
        let (f, t) = (3.0, 0.025);
        let w = core::f64::consts::TAU * f * t;
        let expect = 2.0 * 2.0 * t / (1.0 + 0.81 - 1.8 * w.cos());
        assert!((m.psd_one_sided(f, t) / expect - 1.0).abs() < 1e-12);
    }

    #[test]
    fn segments_of_used_flags() {
        let u = [false, true, true, false, true, false, false, true, true, true];
        assert_eq!(segments_of(u), vec![1..3, 4..5, 7..10]);
        assert!(segments_of([false; 3]).is_empty());
    }

    /// The information of the prewhitened regression equals the exact Gaussian
    /// Fisher information XᵀΣ⁻¹X/… of AR(1) noise (dense Σ, no approximation)
    /// up to the first-sample correction.
    #[test]
    fn whitened_information_is_the_exact_fisher_information() {
        let n = 600;
        let (rho, s2) = (0.9f64, 0.3f64);
        let x: Vec<[f64; 3]> = (0..n)
            .map(|k| {
                let t = k as f64 * 0.025;
                [(6.0 * t).sin(), (2.0 * t).cos() + 0.3 * (11.0 * t).sin(), (0.7 * t).sin() * (4.0 * t).cos()]
            })
            .collect();
        let ar = ArModel { coeffs: vec![-rho], innovation_variance: s2 };
        let (ne, _, _) = whitened(&vec![0.0; n], &x, &[0..n], &ar);
        let j_fast = ne.ata / s2;
        let sigma =
            nalgebra::DMatrix::from_fn(n, n, |i, j| s2 * rho.powi((i as i32 - j as i32).abs()) / (1.0 - rho * rho));
        let xm = nalgebra::DMatrix::from_fn(n, 3, |k, i| x[k][i]);
        let j_exact = xm.transpose() * sigma.cholesky().unwrap().solve(&xm);
        for i in 0..3 {
            for k in 0..3 {
                let scale = (j_exact[(i, i)] * j_exact[(k, k)]).sqrt();
                assert!((j_fast[(i, k)] - j_exact[(i, k)]).abs() < 0.01 * scale, "{i}{k}: {j_fast} vs {j_exact}");
            }
        }
    }
}
