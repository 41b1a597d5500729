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
//! Gaussian noise, the maximum-likelihood one. The steps:
//!
//! 1. least squares on the series as they are (the batch estimate);
//! 2. its residuals → AR model by Burg's method, the order p (within
//!    `min_ar_order` … `max_ar_order`)
//!    chosen by Akaike's criterion N·ln σ̂_p² + 2p;
//! 3. φ and φ_a prewhitened by that A(z), least squares again;
//! 4. with [`GlsSettings::iterations`] > 1, steps 2–3 again from the new
//!    residuals (one round is the default: the batch residuals already give
//!    the noise spectrum).
//!
//! The series may have gaps: it comes as contiguous segments, each filtered on
//! its own, and Burg's sums run over all segments. By default a segment's
//! first p epochs only prime the filter (the conditional likelihood); with
//! [`GlsSettings::exact_start`] they are whitened by the model's lower-order
//! predictors ([`ArModel::ladder`]), the exact Gaussian likelihood when every
//! segment starts in the stationary state.
//!
//! # The bound
//!
//! For Gaussian noise of spectrum S(f) the Fisher information on Γ is (Whittle)
//! J = Σ_f X(f)ᴴ S(f)⁻¹ X(f), X the regressors' transform; for AR noise this is
//! J = X_wᵀX_w/σ², X_w the prewhitened regressors (exact for the conditional
//! likelihood, segments taken as independent). The Cramér–Rao bound on each
//! component is √(J⁻¹)_ii, reported by
//! [`GlsFit::crlb_hz_per_mps2`]. It depends on the data and the noise, not on
//! the method: an unbiased estimator's spread cannot be below it, and
//! the GLS estimate reaches it when the AR model captures the noise.

use core::ops::Range;
use gsens_core::{GammaEstimate, NormalEquations, hac_covariance};
use serde::Serialize;

/// Default highest AR order tried by the order selection.
pub const DEFAULT_MAX_AR_ORDER: usize = 200;

/// The longest memory of the AR noise model the calibration tries \[s\]: the
/// highest order is this span in epochs (200 at 40 Hz). The residual spectrum
/// has features as narrow as the loop's bandwidth (|1 − H|² rising through ωn,
/// the oscillator's loop-shaped band), which an AR model resolves only with a
/// memory of several seconds: with at most 0.75 s (30 epochs at 40 Hz) the
/// fitted spectrum was ~35 % low at 0.9 Hz in the simulated sessions, and the
/// bound ~20 % optimistic.
pub const MAX_AR_SPAN_S: f64 = 5.0;

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

    /// The predictors of every order k = 0 … p that the model implies, by the
    /// step-down (inverse Levinson) recursion κ_k = a_k^{(k)},
    /// a_j^{(k−1)} = (a_j^{(k)} − κ_k·a_{k−j}^{(k)})/(1 − κ_k²), with the scale
    /// √(σ_p²/σ_k²), σ_{k−1}² = σ_k²/(1 − κ_k²), that brings the order-k
    /// prediction error to the innovation variance σ_p². `None` when the model
    /// is not stationary (some |κ_k| ≥ 1).
    pub fn ladder(&self) -> Option<Vec<(Vec<f64>, f64)>> {
        let p = self.order();
        let mut out = vec![(self.coeffs.clone(), 1.0)];
        let mut var_ratio = 1.0; // σ_k²/σ_p²
        for k in (1..=p).rev() {
            let a = &out.last().expect("non-empty").0;
            let kappa = a[k - 1];
            let d = 1.0 - kappa * kappa;
            if d.is_nan() || d <= 0.0 {
                return None;
            }
            let lower: Vec<f64> = (0..k - 1).map(|j| (a[j] - kappa * a[k - 2 - j]) / d).collect();
            var_ratio /= d;
            out.push((lower, 1.0 / var_ratio.sqrt()));
        }
        out.reverse();
        Some(out)
    }

    /// The innovations e_k = x_k + Σ_{j=1..p} a_j x_{k−j} of one contiguous
    /// segment for k = p … len−1: the conditional likelihood, the first p
    /// samples only prime the filter (empty when the segment is not longer
    /// than p).
    pub fn whiten(&self, x: &[f64]) -> Vec<f64> {
        let mut out = Vec::with_capacity(x.len());
        self.whiten_lanes::<1>(&x.iter().map(|v| [*v]).collect::<Vec<_>>(), false, &mut |e| out.push(e[0]));
        out
    }

    /// [`ArModel::whiten`] from the first sample on: before p samples are past,
    /// the order-k prediction error of the model's lower-order predictor,
    /// scaled by √(σ_p²/σ_k²) (see [`ArModel::ladder`]). For stationary
    /// Gaussian noise of this model the e_k are independent with variance σ²:
    /// Σ e_k² is the exact quadratic form xᵀΣ⁻¹x·σ² (the Cholesky factor of the
    /// Toeplitz inverse) and no sample is lost. It assumes each segment starts
    /// in the stationary state; a non-stationary model starts at k = p.
    pub fn whiten_exact(&self, x: &[f64]) -> Vec<f64> {
        let mut out = Vec::with_capacity(x.len());
        self.whiten_lanes::<1>(&x.iter().map(|v| [*v]).collect::<Vec<_>>(), true, &mut |e| out.push(e[0]));
        out
    }

    /// Whitening of N series side by side (N lanes per tap), each innovation
    /// vector handed to `out` in order; `exact_start` as in [`ArModel::whiten_exact`].
    pub(crate) fn whiten_lanes<const N: usize>(
        &self,
        z: &[[f64; N]],
        exact_start: bool,
        out: &mut impl FnMut([f64; N]),
    ) {
        let p = self.order();
        let filter = |a: &[f64], scale: f64, k: usize| {
            let mut e = z[k];
            for (j, aj) in a.iter().enumerate() {
                let past = &z[k - 1 - j];
                for l in 0..N {
                    e[l] += aj * past[l];
                }
            }
            e.map(|v| v * scale)
        };
        let start = match self.ladder().filter(|_| exact_start) {
            Some(ladder) => {
                for (k, (a, scale)) in ladder.iter().enumerate().take(p.min(z.len())) {
                    out(filter(a, *scale, k));
                }
                p
            }
            None => p,
        };
        for k in start..z.len() {
            out(filter(&self.coeffs, 1.0, k));
        }
    }

    /// One-sided power spectral density at `f_hz` for samples `interval_s`
    /// apart: 2·σ²·T/|A(e^{j2πfT})|² \[unit²/Hz\].
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
    let mut bwd_next = fwd.clone();
    // Order 1's sums (forward and backward errors of order 0 are the data).
    let (mut num, mut den) = (0.0, 0.0);
    for s in segments {
        for k in 1..s.len() {
            num += s[k] * s[k - 1];
            den += s[k] * s[k] + s[k - 1] * s[k - 1];
        }
    }
    let mut a: Vec<f64> = Vec::new();
    let mut var = models[0].innovation_variance;
    for m in 1..=max_order {
        if den <= 0.0 || !den.is_finite() {
            break;
        }
        let kappa = -2.0 * num / den;
        let prev = a.clone();
        for j in 0..prev.len() {
            a[j] = prev[j] + kappa * prev[prev.len() - 1 - j];
        }
        a.push(kappa);
        var *= 1.0 - kappa * kappa;
        models.push(ArModel { coeffs: a.clone(), innovation_variance: var });
        // Update the errors to order m (k ≥ m) and sum order m + 1's
        // f_k·b_{k−1} and f_k² + b_{k−1}² (k ≥ m + 1). Each step reads only
        // the previous order's backward errors, so the new ones go to a
        // second buffer, and a long segment is done in chunks of BURG_CHUNK
        // samples in parallel (each chunk's three arrays fit in a cache),
        // summed in chunk order so the sums do not depend on the threads.
        (num, den) = (0.0, 0.0);
        for ((f, b), b_next) in fwd.iter_mut().zip(bwd.iter_mut()).zip(bwd_next.iter_mut()) {
            if f.len() <= m {
                continue;
            }
            let len = f.len();
            let (nu, de) = if len - m >= PARALLEL_BURG_SAMPLES {
                use rayon::prelude::*;
                let parts: Vec<(f64, f64)> = f[m..]
                    .par_chunks_mut(BURG_CHUNK)
                    .zip(b_next[m..len].par_chunks_mut(BURG_CHUNK))
                    .zip(b[m - 1..len - 1].par_chunks(BURG_CHUNK))
                    .map(|((fc, nc), pc)| burg_step(fc, nc, pc, kappa))
                    .collect();
                let (mut nu, mut de) = (0.0, 0.0);
                for (c, &(nu_c, de_c)) in parts.iter().enumerate() {
                    nu += nu_c;
                    de += de_c;
                    if c > 0 {
                        // The pair that straddles this chunk and the one before.
                        let k = m + c * BURG_CHUNK;
                        let (fk, bk) = (f[k], b_next[k - 1]);
                        nu += fk * bk;
                        de += fk * fk + bk * bk;
                    }
                }
                (nu, de)
            } else {
                burg_step(&mut f[m..], &mut b_next[m..], &b[m - 1..len - 1], kappa)
            };
            std::mem::swap(b, b_next);
            num += nu;
            den += de;
        }
    }
    models
}

/// Segments at least this long have each Burg step done in chunks in
/// parallel (below it the hand-off costs more than it saves).
const PARALLEL_BURG_SAMPLES: usize = 32_768;

/// The samples of one chunk of a parallel Burg step: its three arrays
/// (384 KiB) stay in cache through the step.
const BURG_CHUNK: usize = 16_384;

/// One Burg step on a run of samples k = lo … hi − 1: given the previous
/// order's forward errors `f` (updated in place) and backward errors
/// `b_prev` at k − 1, writes f_k + κ·b_{k−1} to `f` and b_{k−1} + κ·f_k to
/// `b_next`; returns Σ f_k·b_{k−1} and Σ f_k² + b_{k−1}² of the new errors
/// over the pairs inside the run (k = lo + 1 … hi − 1), in four lanes (one
/// running total cannot vectorize): pair k + 1 + 4c + l to lane l, a tail of
/// fewer than four to lane 0.
///
/// One pass: each new pair is summed as it is made (the arrays are streamed
/// once per order, not twice), in the lanes and order of [`burg_step_two_passes`],
/// so the sums are the same to the last bit (a test holds it to that).
///
/// Where the CPU has AVX the same code runs compiled for its 256-bit
/// registers: the same operations in the same lanes and order (no fused
/// multiply-add, which would round once instead of twice), so the same bits
/// in fewer instructions.
fn burg_step(f: &mut [f64], b_next: &mut [f64], b_prev: &[f64], kappa: f64) -> (f64, f64) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx") {
        // SAFETY: the CPU supports AVX (checked just above).
        return unsafe { burg_step_avx(f, b_next, b_prev, kappa) };
    }
    burg_step_lanes(f, b_next, b_prev, kappa)
}

/// [`burg_step_lanes`] compiled for AVX.
///
/// # Safety
///
/// The CPU must support AVX.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
unsafe fn burg_step_avx(f: &mut [f64], b_next: &mut [f64], b_prev: &[f64], kappa: f64) -> (f64, f64) {
    burg_step_lanes(f, b_next, b_prev, kappa)
}

/// [`burg_step`]'s body, inlined into each of its compilations.
#[inline(always)]
fn burg_step_lanes(f: &mut [f64], b_next: &mut [f64], b_prev: &[f64], kappa: f64) -> (f64, f64) {
    let n = f.len().min(b_next.len()).min(b_prev.len());
    if n == 0 {
        return (0.0, 0.0);
    }
    let (f, b_next, b_prev) = (&mut f[..n], &mut b_next[..n], &b_prev[..n]);
    let f0 = f[0];
    f[0] = f0 + kappa * b_prev[0];
    b_next[0] = b_prev[0] + kappa * f0;
    let (mut num, mut den) = ([0.0; 4], [0.0; 4]);
    // The backward error of the pair's k − 1, made one sample earlier.
    let mut b_before = b_next[0];
    let body = 1 + (n - 1) / 4 * 4;
    let (fc, nc, pc) =
        (f[1..body].chunks_exact_mut(4), b_next[1..body].chunks_exact_mut(4), b_prev[1..body].chunks_exact(4));
    for ((f4, n4), p4) in fc.zip(nc).zip(pc) {
        let f_old: [f64; 4] = [f4[0], f4[1], f4[2], f4[3]];
        let f_new: [f64; 4] = core::array::from_fn(|l| f_old[l] + kappa * p4[l]);
        let b_new: [f64; 4] = core::array::from_fn(|l| p4[l] + kappa * f_old[l]);
        f4.copy_from_slice(&f_new);
        n4.copy_from_slice(&b_new);
        let b_pair = [b_before, b_new[0], b_new[1], b_new[2]];
        for l in 0..4 {
            num[l] += f_new[l] * b_pair[l];
            den[l] += f_new[l] * f_new[l] + b_pair[l] * b_pair[l];
        }
        b_before = b_new[3];
    }
    for k in body..n {
        let f_old = f[k];
        f[k] = f_old + kappa * b_prev[k];
        b_next[k] = b_prev[k] + kappa * f_old;
        num[0] += f[k] * b_before;
        den[0] += f[k] * f[k] + b_before * b_before;
        b_before = b_next[k];
    }
    ((num[0] + num[1]) + (num[2] + num[3]), (den[0] + den[1]) + (den[2] + den[3]))
}

/// [`burg_step`] as two passes, the update and then the sums: its reference.
#[cfg(test)]
fn burg_step_two_passes(f: &mut [f64], b_next: &mut [f64], b_prev: &[f64], kappa: f64) -> (f64, f64) {
    for ((fk, bn), &bp) in f.iter_mut().zip(b_next.iter_mut()).zip(b_prev) {
        let f_old = *fk;
        *fk = f_old + kappa * bp;
        *bn = bp + kappa * f_old;
    }
    if f.len() < 2 {
        return (0.0, 0.0);
    }
    let (f, b) = (&f[1..], &b_next[..b_next.len() - 1]);
    let (mut num, mut den) = ([0.0; 4], [0.0; 4]);
    let (fc, bc) = (f.chunks_exact(4), b.chunks_exact(4));
    let (fr, br) = (fc.remainder(), bc.remainder());
    for (f4, b4) in fc.zip(bc) {
        for l in 0..4 {
            num[l] += f4[l] * b4[l];
            den[l] += f4[l] * f4[l] + b4[l] * b4[l];
        }
    }
    for (x, y) in fr.iter().zip(br) {
        num[0] += x * y;
        den[0] += x * x + y * y;
    }
    ((num[0] + num[1]) + (num[2] + num[3]), (den[0] + den[1]) + (den[2] + den[3]))
}

/// The AR model of the segments by Burg's method, its order (≤ `max_order`)
/// chosen by Akaike's criterion N·ln σ_p² + 2p, N the number of samples.
pub fn fit_ar(segments: &[&[f64]], max_order: usize) -> ArModel {
    fit_ar_orders(segments, 0, max_order)
}

/// [`fit_ar`] with the order chosen among `min_order` … `max_order` only.
pub fn fit_ar_orders(segments: &[&[f64]], min_order: usize, max_order: usize) -> ArModel {
    let n = segments.iter().map(|s| s.len()).sum::<usize>() as f64;
    let aic = |m: &ArModel| n * m.innovation_variance.max(f64::MIN_POSITIVE).ln() + 2.0 * m.order() as f64;
    let models = burg(segments, max_order);
    let lo = min_order.min(models.len() - 1);
    models
        .into_iter()
        .skip(lo)
        .min_by(|x, y| aic(x).total_cmp(&aic(y)))
        .expect("burg returns at least the order-0 model")
}

/// Settings of [`gls`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct GlsSettings {
    /// Lowest AR order tried (Akaike's criterion chooses within the range).
    pub min_ar_order: usize,
    /// Highest AR order tried (also at most a twentieth of the samples fitted,
    /// which caps the lowest too).
    pub max_ar_order: usize,
    /// Fit-noise-then-refit rounds after the first least-squares pass (≥ 1).
    pub iterations: usize,
    /// The AR model is fitted to at most this many residuals (the first ones,
    /// segment by segment): enough for its spectrum, and a long log costs
    /// only its O(n·p) prewhitening.
    pub max_fit_samples: usize,
    /// Whiten each segment from its first sample ([`ArModel::whiten_exact`])
    /// rather than from its p-th. Exact when every segment starts in the
    /// noise's stationary state; the calibration's segments do not (the
    /// high-pass's start-up, the bridging of gaps), and there the exact start
    /// made the bound ~10 % optimistic on synthetic series, so it is off by
    /// default.
    pub exact_start: bool,
    /// Longest lag of the autocorrelation-robust covariance of the
    /// prewhitened fit, in epochs (what colour the AR model missed); `None`
    /// skips it.
    pub hac_max_lag: Option<usize>,
}

impl Default for GlsSettings {
    fn default() -> Self {
        GlsSettings {
            min_ar_order: 0,
            max_ar_order: DEFAULT_MAX_AR_ORDER,
            iterations: 1,
            max_fit_samples: 40_000,
            exact_start: false,
            hac_max_lag: None,
        }
    }
}

/// The result of [`gls`].
#[derive(Debug, Clone, PartialEq)]
pub struct GlsFit {
    /// Γ̂ from the prewhitened least squares; its covariance σ̂_w²(X_wᵀX_w)⁺ is
    /// J⁻¹, the Cramér–Rao bound at the fitted noise model (+∞ on the diagonal
    /// of unobservable axes).
    pub estimate: GammaEstimate,
    /// Autocorrelation-robust (Newey–West) covariance of the prewhitened fit
    /// (when asked for by [`GlsSettings::hac_max_lag`]).
    pub robust_covariance: Option<[[f64; 3]; 3]>,
    /// The noise model of the residuals (the last one fitted).
    pub noise: ArModel,
    /// Normal equations of the prewhitened series.
    pub whitened_normal: NormalEquations,
}

impl GlsFit {
    /// Cramér–Rao bound on each component, √(J⁻¹)_ii \[Hz/(m/s²)\] (+∞ when unobservable).
    pub fn crlb_hz_per_mps2(&self) -> [f64; 3] {
        self.estimate.sigma_hz_per_mps2()
    }
}

/// Σ_k Σ_l x_k·x_lᵀ·γ(k − l) over each segment of the regressor `columns`
/// (each a series over the same epochs: Γ's three, plus the loop's and the
/// time offset's in the joint fit): the middle of the least-squares sandwich
/// (XᵀX)⁻¹·XᵀΣX·(XᵀX)⁻¹ when the noise has the autocovariance γ of `model`,
/// exactly (no lag truncation or kernel weights).
///
/// In the frequency domain per segment of m samples, zero-padded to N ≥ 2m so
/// that circular correlation is linear: XᵀΣX = (1/N)·Σ_f S(f)·X(f)·X(f)ᴴ with
/// X the DFT of the regressors and S(f) = σ²/|A(e^{−j2πf/N})|² the model's
/// two-sided spectrum per sample (aliasing of γ beyond N samples neglected).
/// O(N log N) per segment; [`ColumnSpectra`] when the transforms are wanted
/// before the model is known.
pub fn covariance_middle_columns(
    model: &ArModel,
    columns: &[Vec<f64>],
    segments: &[Range<usize>],
) -> nalgebra::DMatrix<f64> {
    ColumnSpectra::new(columns, segments).middle(model)
}

/// The transforms of regressor columns over each segment that
/// [`covariance_middle_columns`] weighs by a noise model's spectrum: they do
/// not depend on the model, so they are computed while it is fitted.
pub struct ColumnSpectra<'a> {
    columns: &'a [Vec<f64>],
    segments: &'a [Range<usize>],
    /// Per segment: the transform length N and the columns' bins 0 … N/2.
    spectra: Vec<(usize, Vec<Vec<rustfft::num_complex::Complex<f64>>>)>,
}

impl<'a> ColumnSpectra<'a> {
    /// Every column's transform over each segment, zero-padded to N ≥ 2m
    /// (m the segment's length), the columns in parallel.
    pub fn new(columns: &'a [Vec<f64>], segments: &'a [Range<usize>]) -> Self {
        let spectra = segments.iter().map(|seg| Self::segment(columns, seg, 0)).collect();
        ColumnSpectra { columns, segments, spectra }
    }

    /// The transforms of one segment, at the length that an AR model of
    /// order `order` needs too.
    fn segment(
        columns: &[Vec<f64>],
        seg: &Range<usize>,
        order: usize,
    ) -> (usize, Vec<Vec<rustfft::num_complex::Complex<f64>>>) {
        use rayon::prelude::*;
        let len = seg.len();
        if len == 0 {
            return (0, Vec::new());
        }
        let n = crate::fft::fast_len((2 * len).max(2 * (order + 1)));
        let fft = crate::fft::real_forward(n);
        let x = columns
            .par_iter()
            .map(|c| {
                let mut v = fft.make_input_vec();
                v[..len].copy_from_slice(&c[seg.clone()]);
                let mut out = fft.make_output_vec();
                fft.process(&mut v, &mut out).expect("buffers sized by the plan");
                out
            })
            .collect();
        (n, x)
    }

    /// Σ_k Σ_l x_k·x_lᵀ·γ(k − l) over each segment, γ the autocovariance of
    /// `model` ([`covariance_middle_columns`]'s method).
    pub fn middle(&self, model: &ArModel) -> nalgebra::DMatrix<f64> {
        use rayon::prelude::*;
        let p = self.columns.len();
        let mut m = nalgebra::DMatrix::<f64>::zeros(p, p);
        for (seg, (n0, x0)) in self.segments.iter().zip(&self.spectra) {
            let len = seg.len();
            if len == 0 {
                continue;
            }
            // A model longer than half the padded segment needs a longer transform.
            let redone;
            let (n, x) = if *n0 == crate::fft::fast_len((2 * len).max(2 * (model.order() + 1))) {
                (*n0, x0)
            } else {
                redone = Self::segment(self.columns, seg, model.order());
                (redone.0, &redone.1)
            };
            let fft = crate::fft::real_forward(n);
            let mut a = fft.make_input_vec();
            a[0] = 1.0;
            a[1..=model.order()].copy_from_slice(&model.coeffs);
            let mut af = fft.make_output_vec();
            fft.process(&mut a, &mut af).expect("buffers sized by the plan");
            // Real series: bin n − f is the conjugate of bin f and S(f) is even, so
            // the sum over all n bins is bins 0 and n/2 once and 1 … n/2 − 1 twice.
            let spectrum: Vec<f64> = af
                .iter()
                .enumerate()
                .map(|(f, af)| {
                    let weight = if f == 0 || f == n / 2 { 1.0 } else { 2.0 };
                    weight * model.innovation_variance / af.norm_sqr()
                })
                .collect();
            // Each entry is its own sum over the bins: the entries in parallel.
            let pairs: Vec<(usize, usize)> = (0..p).flat_map(|i| (i..p).map(move |j| (i, j))).collect();
            let sums: Vec<f64> = pairs
                .par_iter()
                .map(|&(i, j)| {
                    let (xi, xj) = (&x[i], &x[j]);
                    spectrum.iter().enumerate().fold(0.0, |acc, (f, s)| acc + s * (xi[f] * xj[f].conj()).re)
                })
                .collect();
            for (&(i, j), sum) in pairs.iter().zip(sums) {
                m[(i, j)] += sum / n as f64;
            }
        }
        for i in 0..p {
            for j in 0..i {
                m[(i, j)] = m[(j, i)];
            }
        }
        m
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
    exact_start: bool,
) -> (NormalEquations, Vec<[f64; 3]>, Vec<f64>) {
    let mut ne = NormalEquations::default();
    let (mut xw, mut yw) = (Vec::new(), Vec::new());
    for r in segments {
        // φ and φ_a side by side, filtered together.
        let z: Vec<[f64; 4]> = r.clone().map(|k| [phase[k], phi_a[k][0], phi_a[k][1], phi_a[k][2]]).collect();
        ar.whiten_lanes(&z, exact_start, &mut |e| {
            let v = [e[1], e[2], e[3]];
            ne.add(e[0], &v);
            xw.push(v);
            yw.push(e[0]);
        });
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
    let (mut ne, mut xw, mut yw) = whitened(phase, phi_a, segments, &ar, settings.exact_start);
    if ne.n < 10 {
        return None;
    }
    let mut est = ne.solve();
    for _ in 0..settings.iterations.max(1) {
        let res = residuals(phase, phi_a, segments, &est.gamma_hz_per_mps2);
        let mut refs: Vec<&[f64]> = Vec::new();
        let mut n = 0;
        for r in &res {
            let take = r.len().min(settings.max_fit_samples - n);
            if take > 0 {
                refs.push(&r[..take]);
                n += take;
            }
        }
        // Keep at least ~20 samples per AR coefficient.
        let max_order = settings.max_ar_order.min(n / 20);
        let candidate = fit_ar_orders(&refs, settings.min_ar_order.min(max_order), max_order);
        let (ne_c, xw_c, yw_c) = whitened(phase, phi_a, segments, &candidate, settings.exact_start);
        if ne_c.n < 10 {
            break;
        }
        (ar, ne, xw, yw) = (candidate, ne_c, xw_c, yw_c);
        est = ne.solve();
    }
    let robust_covariance = settings.hac_max_lag.map(|lag| {
        let g = est.gamma_hz_per_mps2;
        let resid: Vec<f64> = yw.iter().zip(&xw).map(|(y, x)| y - (0..3).map(|i| x[i] * g[i]).sum::<f64>()).collect();
        hac_covariance(&xw, &resid, lag)
    });
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
        // The last segment is long enough for the chunked parallel steps.
        let x = ar_series(&[-1.6, 0.8], 3000 + PARALLEL_BURG_SAMPLES + 7, 1);
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

    /// Burg's chunked steps give the same models to the last bit on one
    /// thread and on several: the chunks are fixed by the samples, and their
    /// sums added in chunk order.
    #[test]
    fn burg_is_the_same_on_any_number_of_threads() {
        let x = ar_series(&[-1.6, 0.8], 3 * PARALLEL_BURG_SAMPLES + 11, 2);
        let segs: Vec<&[f64]> = vec![&x[..500], &x[600..]];
        let on = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| burg(&segs, 10))
        };
        let bits = |models: Vec<ArModel>| -> Vec<u64> {
            models.iter().flat_map(|m| m.coeffs.iter().chain([&m.innovation_variance]).map(|v| v.to_bits())).collect()
        };
        let one = bits(on(1));
        assert_eq!(bits(on(2)), one);
        assert_eq!(bits(on(5)), one);
    }

    /// The one-pass Burg step is its two-pass reference to the last bit, on
    /// runs of every length around the four lanes.
    #[test]
    fn burg_step_is_its_two_pass_reference() {
        let x = ar_series(&[-1.6, 0.8], 300, 3);
        for n in 0..70 {
            for kappa in [-0.93, 0.0, 0.41] {
                let (f, b) = (x[..n].to_vec(), x[7..7 + n].to_vec());
                let (mut f1, mut n1, mut f2, mut n2) = (f.clone(), vec![0.0; n], f.clone(), vec![0.0; n]);
                let one = burg_step(&mut f1, &mut n1, &b, kappa);
                let two = burg_step_two_passes(&mut f2, &mut n2, &b, kappa);
                // The portable compilation too, where `burg_step` took the AVX one.
                let (mut f3, mut n3) = (f.clone(), vec![0.0; n]);
                let lanes = burg_step_lanes(&mut f3, &mut n3, &b, kappa);
                let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!((lanes.0.to_bits(), lanes.1.to_bits()), (two.0.to_bits(), two.1.to_bits()), "n {n}");
                assert_eq!((bits(&f3), bits(&n3)), (bits(&f2), bits(&n2)), "n {n}");
                assert_eq!((one.0.to_bits(), one.1.to_bits()), (two.0.to_bits(), two.1.to_bits()), "n {n}");
                assert_eq!((bits(&f1), bits(&n1)), (bits(&f2), bits(&n2)), "n {n}");
            }
        }
    }

    /// The frequency-domain middle against its definition in the time
    /// domain, Σ_k Σ_l x_k·x_lᵀ·γ_N(k − l) per segment (γ from the model's
    /// impulse response; γ_N(h) = Σ_m γ(h + mN) what N samples of the
    /// spectrum hold, N the segment's transform length), on segments long
    /// and short: one shorter than the model's order takes the longer
    /// transform the model needs.
    #[test]
    fn covariance_middle_is_its_time_domain_definition() {
        let model = ArModel { coeffs: vec![-0.3, 0.1, 0.0, 0.0, 0.05], innovation_variance: 1.7 };
        // ψ_0 = 1, ψ_j = −Σ_i a_i·ψ_{j−i}; γ(h) = σ²·Σ_j ψ_j·ψ_{j+h}.
        let mut psi = vec![1.0];
        for j in 1..400 {
            let v: f64 = (1..=model.order().min(j)).map(|i| -model.coeffs[i - 1] * psi[j - i]).sum();
            psi.push(v);
        }
        let gamma = |h: usize| {
            model.innovation_variance * (0..psi.len().saturating_sub(h)).map(|j| psi[j] * psi[j + h]).sum::<f64>()
        };
        let x = ar_series(&[0.4], 4 * 700, 9);
        let columns: Vec<Vec<f64>> = (0..4).map(|c| x[c * 700..(c + 1) * 700].to_vec()).collect();
        let segments = vec![0..300, 310..313, 320..700];
        let fast = covariance_middle_columns(&model, &columns, &segments);
        for i in 0..4 {
            for j in 0..4 {
                let mut want = 0.0;
                for seg in &segments {
                    let n = crate::fft::fast_len((2 * seg.len()).max(2 * (model.order() + 1)));
                    let periodic = |h: usize| (0..4).map(|m| gamma(h + m * n) + gamma(m * n + n - h)).sum::<f64>();
                    for k in seg.clone() {
                        for l in seg.clone() {
                            want += columns[i][k] * columns[j][l] * periodic(k.abs_diff(l));
                        }
                    }
                }
                assert!(
                    (fast[(i, j)] - want).abs() <= 1e-9 * want.abs().max(1.0),
                    "({i}, {j}): {} vs {want}",
                    fast[(i, j)]
                );
            }
        }
    }

    #[test]
    fn recovers_a_known_ar2_and_its_order() {
        // x_k − 1.6 x_{k−1} + 0.8 x_{k−2} = e_k: a resonance, like the loop's.
        let x = ar_series(&[-1.6, 0.8], 40_000, 2);
        let m = fit_ar(&[&x], 30);
        // Akaike's criterion may overfit by a few orders: the spectrum is what must match.
        assert!(m.order() >= 2 && m.order() <= 16, "order {}", m.order());
        assert!((m.coeffs[0] + 1.6).abs() < 0.03 && (m.coeffs[1] - 0.8).abs() < 0.03, "{:?}", m.coeffs);
        let truth = ArModel { coeffs: vec![-1.6, 0.8], innovation_variance: 1.0 };
        for i in 0..=40 {
            let f = i as f64 * 0.5;
            let r = m.psd_one_sided(f, 0.025) / truth.psd_one_sided(f, 0.025);
            assert!((r - 1.0).abs() < 0.15, "{f} Hz: ratio {r}");
        }
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

    /// The information of the prewhitened regression is the exact Gaussian
    /// Fisher information XᵀΣ⁻¹X of AR noise over segments taken as
    /// independent, Σ the dense Toeplitz covariance built from the model's
    /// impulse response (no recursion shared with the code under test).
    #[test]
    fn whitened_information_is_the_exact_fisher_information() {
        let x: Vec<[f64; 3]> = (0..700)
            .map(|k| {
                let t = k as f64 * 0.025;
                [(6.0 * t).sin(), (2.0 * t).cos() + 0.3 * (11.0 * t).sin(), (0.7 * t).sin() * (4.0 * t).cos()]
            })
            .collect();
        let segments = [0..450, 460..465, 470..700];
        for (coeffs, s2) in [(vec![-0.9], 0.3), (vec![-1.6, 0.8], 2.0), (vec![-0.5, 0.2, -0.3, 0.1], 1.0)] {
            let ar = ArModel { coeffs: coeffs.clone(), innovation_variance: s2 };
            let (ne, _, _) = whitened(&vec![0.0; x.len()], &x, &segments, &ar, true);
            let j_fast = ne.ata / s2;
            // Autocovariance γ(l) = σ² Σ_i h_i h_{i+l}, h the impulse response of 1/A(z).
            let m = 20_000;
            let mut h = vec![0.0; m];
            for i in 0..m {
                h[i] = if i == 0 { 1.0 } else { 0.0 }
                    - coeffs.iter().enumerate().filter(|(j, _)| i > *j).map(|(j, a)| a * h[i - 1 - j]).sum::<f64>();
            }
            let gamma: Vec<f64> = (0..450).map(|l| s2 * (0..m - l).map(|i| h[i] * h[i + l]).sum::<f64>()).collect();
            let mut j_exact = nalgebra::Matrix3::<f64>::zeros();
            for r in &segments {
                let n = r.len();
                let sigma = nalgebra::DMatrix::from_fn(n, n, |i, j| gamma[i.abs_diff(j)]);
                let xm = nalgebra::DMatrix::from_fn(n, 3, |k, i| x[r.start + k][i]);
                let jm = xm.transpose() * sigma.cholesky().unwrap().solve(&xm);
                j_exact += nalgebra::Matrix3::from_fn(|i, k| jm[(i, k)]);
            }
            for i in 0..3 {
                for k in 0..3 {
                    let scale = (j_exact[(i, i)] * j_exact[(k, k)]).sqrt();
                    assert!(
                        (j_fast[(i, k)] - j_exact[(i, k)]).abs() < 1e-8 * scale,
                        "{coeffs:?} {i}{k}: {j_fast} vs {j_exact}"
                    );
                }
            }
        }
    }

    #[test]
    fn ladder_steps_down_to_the_lower_orders_burg_found() {
        let x = ar_series(&[-1.6, 0.8, 0.1], 5000, 4);
        let models = burg(&[&x], 6);
        let ladder = models[6].ladder().unwrap();
        for k in 0..=6 {
            for (a, b) in ladder[k].0.iter().zip(&models[k].coeffs) {
                assert!((a - b).abs() < 1e-9, "order {k}: {:?} vs {:?}", ladder[k].0, models[k].coeffs);
            }
            let scale = (models[6].innovation_variance / models[k].innovation_variance).sqrt();
            assert!((ladder[k].1 - scale).abs() < 1e-9, "order {k}");
        }
        assert!(ArModel { coeffs: vec![-1.0], innovation_variance: 1.0 }.ladder().is_none());
    }
}
