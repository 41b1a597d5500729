//! The loop response measured from the session: does the receiver's loop
//! behave like the model the estimator assumed?
//!
//! The estimator models the channel-averaged phase error as φ = L\[u\] + n,
//! u = aᵀΓ̂ the g-induced frequency excitation \[Hz\]. Here the response of φ to
//! u is estimated without a model, by Welch's cross-spectral method,
//!
//! ```text
//! Ĥ(f) = S_uφ(f)/S_uu(f),   γ²(f) = |S_uφ|²/(S_uu·S_φφ)
//! ```
//!
//! and compared with the model's response at every frequency where the
//! session shook the board. A mismatch (another bandwidth, damping, order,
//! update interval, a log written differently) shows as a deviation of Ĥ
//! from the model in magnitude or phase, in units of Ĥ's own standard error.
//!
//! # What is compared with what
//!
//! Both φ and u are the estimator's own series: φ high-passed exactly as the
//! estimator was fed it ([`crate::compensation_series`]'s view, the used
//! epochs only) and u = aᵀΓ̂ through the same high-pass (a linear
//! time-invariant filter applied to input and output leaves their ratio
//! unchanged and removes the slow content — Doppler-rate error, oscillator
//! wander — that would otherwise leak into the shaken band through the
//! window's side lobes). The model side is the estimator's prediction
//! φ_m = φ_aᵀΓ̂, the regressor triad run on the same a, taken through the
//! *same* segments and window: Ĥ_m(f) = S_uφm/S_uu. Because φ_m is L\[u\]
//! exactly as the estimator computed it (the discrete loop at its update
//! interval, the linear interpolation between epochs and its compensation,
//! the logged `last`/`mean`), Ĥ − Ĥ_m = S_un/S_uu is pure noise when the model
//! is right: the window's smoothing and leakage, which bias Ĥ against the
//! analytic L(f) by more than its standard error in a well-excited session
//! (a 0.25–3 Hz multisine, 300 s: +4.4 % and −0.12 rad at 0.47 Hz, 6σ),
//! cancel. Ĥ_m agrees with the analytic epoch-level response
//! [`epoch_response`] (L_d(e^{j2πfT})·D(f), D the mean of the logged
//! updates) to O((ωh)⁴); that curve is what the figure draws.
//!
//! # Segments
//!
//! Hann windows with 50 % overlap, inside the contiguous runs of used epochs
//! (a gap ends a run). The segment length T_seg is set by the loop: the Hann
//! window's main lobe is ±2/T_seg wide, so the lower half-power frequency f_lo
//! of |L| is separated from the DC bin's main lobe (where the high-pass and
//! any residual trend live) when 2/T_seg ≤ f_lo, i.e.
//! T_seg = 2/f_lo (rounded up to an even number of epochs). The bins are then
//! 1/T_seg ≤ f_lo/2 apart: the paper's loop (f_lo = 0.466 Hz, f_hi = 1.74 Hz)
//! gets a bin every 0.23 Hz, six across its half-power band.
//!
//! # Uncertainty
//!
//! Conditional on the excitation, the segment spectra obey the complex
//! regression Φ_i = H·U_i + N_i (i = 1…K), so Ĥ − H is circular complex
//! normal with, for its magnitude and phase (Bendat & Piersol, *Random Data*,
//! §9.2.4, with the residual degrees of freedom; n_b the segments corrected
//! for overlap, below),
//!
//! ```text
//! σ_|H|/|Ĥ| = σ_arg H [rad] = √((1 − γ̂²)/(2·(n_b − 1)·γ̂²))
//! ```
//!
//! the band drawn around Ĥ. It counts as noise everything in φ that is not
//! coherent with u within a segment, including the part of L\[u\] that a
//! finite segment cannot attribute to its own bin (the loop's memory across
//! the segment's edges, an excitation that starts and stops): in a
//! well-excited session, γ̂² ≈ 0.99, that dominates the band, yet the
//! model's φ_m carries exactly the same part. The deviation is therefore
//! tested with the σ of the residual r = φ − φ_m itself: Ĥ − Ĥ_m = S_ur/S_uu,
//! and regressing R_i on U_i gives for each of its components along and
//! across Ĥ_m (the magnitude and phase deviations)
//!
//! ```text
//! σ_Δ² = RSS_r/(2·(n_b − 1)·S_uu),   RSS_r = S_rr − |S_ur|²/S_uu
//! ```
//!
//! (S the sums over the segments); under the model, r is noise independent
//! of u and deviation/σ_Δ is Student-t.
//!
//! Overlapping segments share noise: white noise's spectra in segments Δ
//! epochs apart correlate as c = ρ(Δ)·e^{−j2πbΔ/N}, ρ(Δ) = Σ w(n)w(n + Δ)/Σ w²
//! (1/6 for Hann at 50 %), so var(S_un/S_uu) = κ·E|N|²/S_uu with the bin's
//! overlap factor κ = Σ_ij U_i*·U_j·c_ij / Σ|U_i|², computed from the
//! excitation's own segment spectra (1 + 2ρ(K − 1)/K for a steady tone,
//! whose segments are coherent; ≈ 1 for a random one). With n_b = K/κ the
//! segments a bin counts as (n_d of Bendat & Piersol), E\[RSS\] = (K − κ)·E|N|²,
//! which gives both σ above. The t statistics have ν = 2(n_e − 1) degrees of freedom with
//! n_e = K²/Σ_ij ρ_ij² (Welch 1967: the variance of an averaged noise
//! spectrum under overlap). On 2 × 30 synthetic 200 s sessions (the tests:
//! a 0.25–3 Hz multisine through the paper's loop at 1 ms, logged mean,
//! white noise 0.05 and 0.2 rad) 67.6–68.2 % of the deviations fall within
//! ±1σ (nominal 68.3 %) and 94.9 % within the 95 % t-interval; of 2 × 200
//! further sessions none failed the 1 % check, and 4.5 % had p < 0.05.
//!
//! A model error the check detects is as large as the residual noise that
//! sets Γ̂'s own uncertainty, so it is one that matters for Γ̂.
//!
//! # Which bins, and the verdict
//!
//! Tested are the bins of the shaken band: the fewest bins holding
//! [`ResponseSettings::power_fraction`] of the excitation's power (S_uu,
//! DC and Nyquist excluded) and whose coherence is significant — above the
//! level a bin without any response exceeds with probability
//! [`ResponseSettings::coherence_alpha`], γ²_c = 1 − α^{1/(n_e−1)}
//! (Carter, Knapp & Nuttall 1973). The largest |t| over those bins, magnitude
//! and phase, is compared with the Student-t quantile at the per-test level
//! of a Šidák correction, α₁ = 1 − (1 − α)^{1/M}, for M = 2·m/ENBW
//! independent tests (m bins; adjacent Hann bins overlap, ENBW = 1.5 bins;
//! two components per bin), so a right model fails with probability α =
//! [`ResponseSettings::false_alarm`].

use crate::search::batch_pass;
use crate::{CalibError, EpochSeries, EstimateSettings};
use gsens_core::units::Decimal;
use gsens_core::{Complex, HighPass, LoggedPhase, LoopModel};
use rustfft::num_complex::Complex64;
use serde::{Deserialize, Serialize};
use statrs::distribution::{ContinuousCDF, StudentsT};
use std::f64::consts::TAU;

/// Fraction of the segment length by which consecutive segments overlap.
const OVERLAP: f64 = 0.5;
/// Fewest effective segments for which the t statistics are formed (ν ≥ 6).
const MIN_EFFECTIVE_SEGMENTS: f64 = 4.0;

/// The check's settings: the false-alarm rate and the definition of the
/// shaken band (statistical levels, not fitted to any data).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ResponseSettings {
    /// Probability that a session whose loop is the model fails the check.
    pub false_alarm: f64,
    /// Share of the excitation's power the tested bins hold (the shaken band).
    pub power_fraction: f64,
    /// Level of the coherence significance test of each tested bin.
    pub coherence_alpha: f64,
}

impl Default for ResponseSettings {
    /// 1 % false alarms, the bins holding 90 % of the excitation, coherence
    /// significant at 1 %.
    fn default() -> Self {
        ResponseSettings { false_alarm: 0.01, power_fraction: 0.9, coherence_alpha: 0.01 }
    }
}

/// One frequency bin of the measured response.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ResponseBin {
    /// Bin frequency k/T_seg \[Hz\].
    pub f_hz: f64,
    /// Share of the excitation's power in this bin, S_uu(f)/Σ S_uu.
    pub excitation_fraction: f64,
    /// Magnitude-squared coherence γ̂² of u and φ.
    pub coherence: f64,
    /// |Ĥ| = |S_uφ/S_uu| \[rad/Hz\].
    pub measured_magnitude_rad_per_hz: f64,
    /// arg Ĥ \[rad\], in (−π, π\].
    pub measured_phase_rad: f64,
    /// |Ĥ_m| of the estimator's model through the same segments \[rad/Hz\].
    pub model_magnitude_rad_per_hz: f64,
    /// arg Ĥ_m \[rad\], in (−π, π\].
    pub model_phase_rad: f64,
    /// Segments this bin's excitation counts as under overlap, K/κ (module docs).
    pub effective_segments: f64,
    /// 1σ of |Ĥ|, |Ĥ|·√((1 − γ̂²)/(2(n_b − 1)γ̂²)), n_b = [`ResponseBin::effective_segments`] \[rad/Hz\].
    pub sigma_magnitude_rad_per_hz: f64,
    /// 1σ of arg Ĥ, √((1 − γ̂²)/(2(n_b − 1)γ̂²)) \[rad\].
    pub sigma_phase_rad: f64,
    /// 1σ of each component of Ĥ − Ĥ_m, √(RSS_r/(2(n_b − 1)·S_uu)) from the
    /// residual r = φ − φ_m (module docs) \[rad/Hz\].
    pub sigma_deviation_rad_per_hz: f64,
    /// Magnitude deviation, the component of Ĥ − Ĥ_m along Ĥ_m, in units of
    /// [`ResponseBin::sigma_deviation_rad_per_hz`].
    pub magnitude_deviation_sigma: f64,
    /// Phase deviation, the component of Ĥ − Ĥ_m across Ĥ_m, in units of
    /// [`ResponseBin::sigma_deviation_rad_per_hz`] (> 0: Ĥ leads the model).
    pub phase_deviation_sigma: f64,
    /// Whether the bin is in the shaken band and its coherence is significant.
    pub tested: bool,
}

/// The measured loop response and its comparison with the model.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ResponseCheck {
    /// The settings used.
    pub settings: ResponseSettings,
    /// Segment length T_seg = 2/f_lo \[s\].
    pub segment_s: f64,
    /// Bin spacing 1/T_seg \[Hz\].
    pub resolution_hz: f64,
    /// Lower half-power frequency f_lo of the model's |L| that set T_seg \[Hz\].
    pub loop_band_lo_hz: f64,
    /// Number of segments K averaged.
    pub segments: usize,
    /// K corrected for overlap for the noise spectrum, n_e = K²/Σρ_ij²
    /// (the t statistics have ν = 2(n_e − 1)).
    pub effective_segments: f64,
    /// Coherence a bin must exceed to be tested, 1 − α^{1/(n_e − 1)}.
    pub coherence_threshold: f64,
    /// Lowest and highest frequency tested \[Hz\] (`None` when no bin was).
    pub tested_band_hz: Option<[f64; 2]>,
    /// Number of bins tested.
    pub bins_tested: usize,
    /// Independent tests M = 2·bins/ENBW the Šidák correction counts.
    pub independent_tests: f64,
    /// Largest |t| allowed: the Student-t quantile (ν = 2(n_e − 1)) at the
    /// two-sided per-test level 1 − (1 − α)^{1/M}.
    pub threshold_sigma: f64,
    /// Largest magnitude deviation over the tested bins, signed \[σ\] (> 0:
    /// the receiver responds more than the model).
    pub max_magnitude_deviation_sigma: f64,
    /// Where it occurs \[Hz\].
    pub max_magnitude_f_hz: f64,
    /// |Ĥ|/|Ĥ_m| − 1 at that bin (the relative magnitude error).
    pub max_magnitude_relative: f64,
    /// Largest phase deviation over the tested bins, signed \[σ\] (> 0: the
    /// receiver's φ leads the model's).
    pub max_phase_deviation_sigma: f64,
    /// Where it occurs \[Hz\].
    pub max_phase_f_hz: f64,
    /// arg(Ĥ/Ĥ_m) at that bin \[rad\].
    pub max_phase_rad: f64,
    /// Probability that a right model shows a deviation as large as the
    /// largest one, 1 − (1 − p₁)^M (p₁ its two-sided t tail).
    pub p_value: f64,
    /// The verdict: every tested deviation within the threshold (and at
    /// least one bin tested).
    pub consistent: bool,
    /// Every bin from 1/T_seg to below the Nyquist frequency of the log.
    pub bins: Vec<ResponseBin>,
}

impl ResponseCheck {
    /// The bins tested.
    pub fn tested(&self) -> impl Iterator<Item = &ResponseBin> {
        self.bins.iter().filter(|b| b.tested)
    }

    /// One line for the text report, e.g. `measured loop response: largest
    /// deviation 1.3σ at 0.94 Hz (magnitude, +2.1 %), consistent with the
    /// model (threshold 3.6σ at 1 % false alarms, 4 bins 0.70–1.41 Hz)`.
    pub fn summary(&self) -> String {
        let (kind, sig, f, what) = if self.max_magnitude_deviation_sigma.abs() >= self.max_phase_deviation_sigma.abs() {
            (
                "magnitude",
                self.max_magnitude_deviation_sigma,
                self.max_magnitude_f_hz,
                format!("{:+.1} %", 100.0 * self.max_magnitude_relative),
            )
        } else {
            (
                "phase",
                self.max_phase_deviation_sigma,
                self.max_phase_f_hz,
                format!("{:+.1}°", self.max_phase_rad.to_degrees()),
            )
        };
        let band = self.tested_band_hz.map_or(String::new(), |[lo, hi]| format!(" {lo:.2}–{hi:.2} Hz"));
        format!(
            "measured loop response: largest deviation {:.1}σ at {f:.2} Hz ({kind}, {what}), {} (threshold {:.1}σ at {} % false alarms, {} bins{band})",
            sig.abs(),
            if self.consistent { "consistent with the model" } else { "NOT consistent with the model" },
            self.threshold_sigma,
            Decimal(100.0 * self.settings.false_alarm),
            self.bins_tested,
        )
    }
}

/// Why the response could not be measured.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ResponseCheckError {
    /// The estimator's model could not be built.
    #[error(transparent)]
    Calib(#[from] CalibError),
    /// The loop has no half-power band to set the segment length.
    #[error("the loop model has no peak to set the analysis band: {0}")]
    Loop(gsens_core::LoopError),
    /// Γ̂ is zero or not finite: no excitation to measure the response to.
    #[error("Γ̂ is zero or not finite: there is no modelled excitation to measure the loop's response to")]
    NoExcitation,
    /// The runs of used epochs are too short or too few for the statistics.
    #[error(
        "the loop response needs {needed:.0} effective segments of {segment_s:.1} s (2/f_lo of the loop); \
         the used epochs give {effective:.1}: record longer runs without gaps"
    )]
    TooShort {
        /// T_seg \[s\].
        segment_s: f64,
        /// Effective segments found.
        effective: f64,
        /// Effective segments needed.
        needed: f64,
    },
    /// No bin of the shaken band is coherent enough to test.
    #[error("no frequency bin of the shaken band has a significant coherence")]
    NothingCoherent,
}

/// The analytic epoch-level response of a loop from the g-induced frequency
/// u_k at the log epochs to the logged phase error φ_k \[rad/Hz\]: the loop's
/// L(j2πf) ([`LoopModel::response`], L_d(e^{j2πfT}) at its update interval
/// T) times, for a log of the mean of the n = T_log/T updates since the
/// previous row (time-stamped at the latest one),
/// D(f) = (1/n)·Σ_{j=0}^{n−1} e^{−j2πf·jT}.
pub fn epoch_response(model: &LoopModel, log_interval_s: f64, logged: LoggedPhase, f_hz: f64) -> Complex<f64> {
    let l = model.response(f_hz);
    let t = model.interval_s().unwrap_or(log_interval_s);
    let n = (log_interval_s / t).round().max(1.0) as usize;
    match logged {
        LoggedPhase::Mean if n > 1 => {
            let d: Complex<f64> =
                (0..n).map(|j| Complex::from_polar(1.0, -TAU * f_hz * j as f64 * t)).sum::<Complex<f64>>() / n as f64;
            l * d
        }
        _ => l,
    }
}

/// Measures the loop response from a session with the default
/// [`ResponseSettings`]: `series` and `settings` as given to
/// [`crate::calibrate`], `gamma_hz_per_mps2` its estimate
/// (`Calibration::gamma_raw_hz_per_mps2`).
pub fn measure_response(
    series: &EpochSeries,
    settings: &EstimateSettings,
    gamma_hz_per_mps2: &[f64; 3],
) -> Result<ResponseCheck, ResponseCheckError> {
    measure_response_with(series, settings, gamma_hz_per_mps2, &ResponseSettings::default())
}

/// [`measure_response`] with explicit [`ResponseSettings`] (module docs: the
/// method).
pub fn measure_response_with(
    series: &EpochSeries,
    settings: &EstimateSettings,
    gamma_hz_per_mps2: &[f64; 3],
    check: &ResponseSettings,
) -> Result<ResponseCheck, ResponseCheckError> {
    let g = gamma_hz_per_mps2;
    if !g.iter().all(|x| x.is_finite()) || g.iter().all(|x| *x == 0.0) {
        return Err(ResponseCheckError::NoExcitation);
    }
    let h = series.log_interval_s;
    let loop_model = settings.loop_at(h);
    let [f_lo, _] = loop_model.half_power_band_hz().map_err(ResponseCheckError::Loop)?;
    // T_seg = 2/f_lo, an even number of epochs (50 % overlap on whole epochs).
    let n_seg = (((2.0 / (f_lo * h)) / 2.0).ceil() as usize * 2).max(4);
    let segment_s = n_seg as f64 * h;
    let (fed, _) = batch_pass(series, settings)?;

    // The three series through the same high-pass: u = aᵀΓ̂, φ as fed, φ_m = φ_aᵀΓ̂.
    let mut hp = HighPass::new(settings.highpass_hz, h);
    let u: Vec<f64> = series.accel_mps2.iter().map(|a| hp.step(a[0] * g[0] + a[1] * g[1] + a[2] * g[2])).collect();
    let phi: Vec<f64> = fed.iter().map(|e| e.phase_err_rad.unwrap_or(0.0)).collect();
    let phi_m: Vec<f64> = fed.iter().map(|e| e.phi_a[0] * g[0] + e.phi_a[1] * g[1] + e.phi_a[2] * g[2]).collect();

    let window = HannWindow::new(n_seg);
    let (starts, effective) = segment_starts(&fed, &window);
    if effective < MIN_EFFECTIVE_SEGMENTS {
        return Err(ResponseCheckError::TooShort { segment_s, effective, needed: MIN_EFFECTIVE_SEGMENTS });
    }
    let sums = WelchSums::new(&window, &starts, [&u, &phi, &phi_m]);
    let total_u: f64 = sums.suu[1..].iter().sum();
    if total_u.is_nan() || total_u <= 0.0 {
        return Err(ResponseCheckError::NoExcitation);
    }
    let in_band = shaken_band(&sums.suu, check.power_fraction * total_u);
    let dof = effective - 1.0;
    let coherence_threshold = 1.0 - check.coherence_alpha.powf(1.0 / dof);
    let bins = response_bins(&sums, &in_band, (segment_s, total_u), coherence_threshold, starts.len());
    let spectrum = MeasuredSpectrum { segment_s, loop_band_lo_hz: f_lo, segments: starts.len(), effective };
    Ok(verdict(check, &window, spectrum, coherence_threshold, bins))
}

/// The Hann window of a segment of `n` epochs, and its sum of squares.
struct HannWindow {
    w: Vec<f64>,
    w2: f64,
}

impl HannWindow {
    fn new(n_seg: usize) -> Self {
        let w: Vec<f64> = (0..n_seg).map(|n| 0.5 * (1.0 - (TAU * n as f64 / n_seg as f64).cos())).collect();
        let w2 = w.iter().map(|w| w * w).sum();
        HannWindow { w, w2 }
    }

    fn len(&self) -> usize {
        self.w.len()
    }

    /// The correlation of white noise's windowed segments `lag` epochs apart,
    /// ρ(Δ) = Σ w(n)w(n + Δ)/Σ w².
    fn rho(&self, lag: usize) -> f64 {
        let n_seg = self.len();
        if lag >= n_seg {
            return 0.0;
        }
        (0..n_seg - lag).map(|n| self.w[n] * self.w[n + lag]).sum::<f64>() / self.w2
    }

    /// The step between overlapping segments, in epochs.
    fn step(&self) -> usize {
        ((self.len() as f64) * (1.0 - OVERLAP)).round() as usize
    }

    /// The windowed spectrum of `x[s..s + n]` less its mean.
    fn spectrum(&self, fft: &dyn rustfft::Fft<f64>, x: &[f64], s: usize) -> Vec<Complex64> {
        let n_seg = self.len();
        let seg = &x[s..s + n_seg];
        let mean = seg.iter().sum::<f64>() / n_seg as f64;
        let mut buf: Vec<Complex64> =
            seg.iter().zip(&self.w).map(|(v, w)| Complex64::new((v - mean) * w, 0.0)).collect();
        fft.process(&mut buf);
        buf
    }
}

/// The segments' starts inside the runs of used epochs, and their effective
/// number under overlap, K²/Σ_ij ρ_ij² (0 without any).
fn segment_starts(fed: &[gsens_core::FedEpoch], window: &HannWindow) -> (Vec<usize>, f64) {
    let (n_seg, step) = (window.len(), window.step());
    let mut starts = Vec::new();
    let mut overlap_sum = 0.0;
    let mut k = 0;
    while k < fed.len() {
        if !fed[k].used {
            k += 1;
            continue;
        }
        let run_start = k;
        while k < fed.len() && fed[k].used {
            k += 1;
        }
        let run_len = k - run_start;
        if run_len < n_seg {
            continue;
        }
        let kr = (run_len - n_seg) / step + 1;
        starts.extend((0..kr).map(|j| run_start + j * step));
        // Σ_{i,j in the run} ρ_ij² = K_r + 2·Σ_{d≥1} (K_r − d)·ρ(d·D)².
        overlap_sum += kr as f64 + 2.0 * (1..kr).map(|d| (kr - d) as f64 * window.rho(d * step).powi(2)).sum::<f64>();
    }
    let segments = starts.len();
    let effective = if segments == 0 { 0.0 } else { (segments * segments) as f64 / overlap_sum };
    (starts, effective)
}

/// Welch's sums over the segments, bins 1 … below Nyquist (index 0 unused):
/// the auto- and cross-spectra of u, φ, φ_m and the residual r = φ − φ_m,
/// and each bin's overlap factor's cross term.
struct WelchSums {
    suu: Vec<f64>,
    spp: Vec<f64>,
    sup: Vec<Complex64>,
    sum_: Vec<Complex64>,
    sur: Vec<Complex64>,
    srr: Vec<f64>,
    /// Σ_{i<k} U_i*·U_k·c_ik per bin (`cross_terms`).
    cross: Vec<Complex64>,
}

impl WelchSums {
    fn new(window: &HannWindow, starts: &[usize], [u, phi, phi_m]: [&[f64]; 3]) -> Self {
        let n_seg = window.len();
        let n_bins = (n_seg - 1) / 2;
        let fft = crate::fft::forward(n_seg);
        let zero = Complex64::new(0.0, 0.0);
        let (mut suu, mut spp) = (vec![0.0; n_bins + 1], vec![0.0; n_bins + 1]);
        let (mut sup, mut sum_) = (vec![zero; n_bins + 1], vec![zero; n_bins + 1]);
        let (mut sur, mut srr) = (vec![zero; n_bins + 1], vec![0.0; n_bins + 1]);
        let mut u_spectra = Vec::with_capacity(starts.len());
        for &s in starts {
            let spectrum = |x: &[f64]| window.spectrum(&*fft, x, s);
            let (fu, fp, fm) = (spectrum(u), spectrum(phi), spectrum(phi_m));
            for b in 1..=n_bins {
                let r = fp[b] - fm[b];
                suu[b] += fu[b].norm_sqr();
                spp[b] += fp[b].norm_sqr();
                sup[b] += fu[b].conj() * fp[b];
                sum_[b] += fu[b].conj() * fm[b];
                sur[b] += fu[b].conj() * r;
                srr[b] += r.norm_sqr();
            }
            u_spectra.push(fu);
        }
        let cross = cross_terms(window, starts, &u_spectra, n_bins);
        WelchSums { suu, spp, sup, sum_, sur, srr, cross }
    }
}

/// The overlap factor's cross term of each bin, Σ_{i<k} U_i*·U_k·c_ik, c_ik =
/// ρ(Δ)·e^{−j2πbΔ/N} the correlation of white noise's spectra in segments
/// Δ epochs apart: κ = 1 + 2·Re(cross)/S_uu gives var(S_un/S_uu) =
/// κ·E|N|²/S_uu exactly (κ = 1 without overlap, 1 + 2ρ(D)(K − 1)/K for a
/// steady tone).
fn cross_terms(window: &HannWindow, starts: &[usize], u_spectra: &[Vec<Complex64>], n_bins: usize) -> Vec<Complex64> {
    let n_seg = window.len();
    let mut cross = vec![Complex64::new(0.0, 0.0); n_bins + 1];
    // c_ij depends on the lag alone, and the segments take few lags (one
    // step within a run): each lag's factors are made once.
    let mut factors: Vec<Option<Vec<Complex64>>> = vec![None; n_seg];
    for i in 0..starts.len() {
        for k in (i + 1)..starts.len() {
            let lag = starts[k] - starts[i];
            if lag >= n_seg {
                break;
            }
            let c = factors[lag].get_or_insert_with(|| {
                let r = window.rho(lag);
                (0..=n_bins).map(|b| Complex64::from_polar(r, -TAU * (b * lag) as f64 / n_seg as f64)).collect()
            });
            for b in 1..=n_bins {
                cross[b] += u_spectra[i][b].conj() * u_spectra[k][b] * c[b];
            }
        }
    }
    cross
}

/// The shaken band: the fewest bins (largest S_uu first) holding `power` of
/// S_uu, as a flag per bin.
fn shaken_band(suu: &[f64], power: f64) -> Vec<bool> {
    let n_bins = suu.len() - 1;
    let mut order: Vec<usize> = (1..=n_bins).collect();
    order.sort_by(|&a, &b| suu[b].total_cmp(&suu[a]));
    let mut in_band = vec![false; n_bins + 1];
    let mut acc = 0.0;
    for &b in &order {
        if acc >= power {
            break;
        }
        in_band[b] = true;
        acc += suu[b];
    }
    in_band
}

/// Every bin's measured and modelled response, their deviation in σ and
/// whether it is tested (`segment_s`: the segment length \[s\]; `total_u`:
/// S_uu over the bins; `segments`: K).
fn response_bins(
    sums: &WelchSums,
    in_band: &[bool],
    (segment_s, total_u): (f64, f64),
    coherence_threshold: f64,
    segments: usize,
) -> Vec<ResponseBin> {
    let WelchSums { suu, spp, sup, sum_, sur, srr, cross } = sums;
    let n_bins = suu.len() - 1;
    let mut bins = Vec::with_capacity(n_bins);
    for b in 1..=n_bins {
        let hm = sup[b] / suu[b];
        let hmod = sum_[b] / suu[b];
        let coh = if spp[b] > 0.0 { (sup[b].norm_sqr() / (suu[b] * spp[b])).min(1.0) } else { 0.0 };
        let kappa = (1.0 + 2.0 * cross[b].re / suu[b]).clamp(1.0, segments as f64 / 2.0);
        // The segments this bin's excitation counts as, K/κ.
        let n_b = segments as f64 / kappa;
        let rel = ((1.0 - coh) / (2.0 * (n_b - 1.0) * coh)).sqrt();
        let sigma = hm.norm() * rel;
        // Ĥ − Ĥ_m = S_ur/S_uu, r = φ − φ_m, and its σ from the regression of
        // the residual's segment spectra on u's: RSS_r = S_rr − |S_ur|²/S_uu.
        let dev = sur[b] / suu[b];
        let rss = (srr[b] - sur[b].norm_sqr() / suu[b]).max(0.0);
        let sigma_dev = (rss / (2.0 * (n_b - 1.0) * suu[b])).sqrt();
        // Components of Ĥ − Ĥ_m along and across Ĥ_m.
        let dir = if hmod.norm() > 0.0 { hmod.conj() / hmod.norm() } else { Complex64::new(1.0, 0.0) };
        let e = dev * dir;
        // Bin 1 lies in the DC bin's main lobe (the high-pass's start-up,
        // a residual trend): tested are the bins from 2/T_seg up.
        let tested = b >= 2 && in_band[b] && coh > coherence_threshold && sigma_dev > 0.0 && hmod.norm() > 0.0;
        bins.push(ResponseBin {
            f_hz: b as f64 / segment_s,
            excitation_fraction: suu[b] / total_u,
            coherence: coh,
            measured_magnitude_rad_per_hz: hm.norm(),
            measured_phase_rad: hm.arg(),
            model_magnitude_rad_per_hz: hmod.norm(),
            model_phase_rad: hmod.arg(),
            effective_segments: n_b,
            sigma_magnitude_rad_per_hz: sigma,
            sigma_phase_rad: rel,
            sigma_deviation_rad_per_hz: sigma_dev,
            magnitude_deviation_sigma: if sigma_dev > 0.0 { e.re / sigma_dev } else { 0.0 },
            phase_deviation_sigma: if sigma_dev > 0.0 { e.im / sigma_dev } else { 0.0 },
            tested,
        });
    }
    bins
}

/// What the spectra were measured over.
struct MeasuredSpectrum {
    segment_s: f64,
    loop_band_lo_hz: f64,
    segments: usize,
    effective: f64,
}

/// The check's verdict from its bins: the largest deviations, magnitude and
/// phase, over the tested bins against the Student-t quantile of the Šidák
/// correction for the independent tests among them.
fn verdict(
    check: &ResponseSettings,
    window: &HannWindow,
    spectrum: MeasuredSpectrum,
    coherence_threshold: f64,
    bins: Vec<ResponseBin>,
) -> ResponseCheck {
    let MeasuredSpectrum { segment_s, loop_band_lo_hz, segments, effective } = spectrum;
    let tested: Vec<&ResponseBin> = bins.iter().filter(|b| b.tested).collect();
    let worst =
        |f: fn(&ResponseBin) -> f64| tested.iter().copied().max_by(|a, b| f(a).abs().total_cmp(&f(b).abs())).copied();
    let wm = worst(|b| b.magnitude_deviation_sigma);
    let wp = worst(|b| b.phase_deviation_sigma);
    // ENBW of the window in bins, N·Σw²/(Σw)² (1.5 for Hann).
    let enbw = window.len() as f64 * window.w2 / window.w.iter().sum::<f64>().powi(2);
    let m = (2.0 * tested.len() as f64 / enbw).max(1.0);
    let nu = 2.0 * (effective - 1.0);
    let per_test = 1.0 - (1.0 - check.false_alarm).powf(1.0 / m);
    let threshold_sigma = student_t_quantile_two_sided(per_test, nu);
    let max_t =
        wm.map_or(0.0, |b| b.magnitude_deviation_sigma.abs()).max(wp.map_or(0.0, |b| b.phase_deviation_sigma.abs()));
    let p1 = student_t_two_sided_tail(max_t, nu);
    let p_value = if tested.is_empty() { 1.0 } else { 1.0 - (1.0 - p1).powf(m) };
    let ratio = |b: &ResponseBin| {
        Complex64::from_polar(b.measured_magnitude_rad_per_hz, b.measured_phase_rad)
            / Complex64::from_polar(b.model_magnitude_rad_per_hz, b.model_phase_rad)
    };
    ResponseCheck {
        settings: *check,
        segment_s,
        resolution_hz: 1.0 / segment_s,
        loop_band_lo_hz,
        segments,
        effective_segments: effective,
        coherence_threshold,
        tested_band_hz: (!tested.is_empty()).then(|| [tested[0].f_hz, tested[tested.len() - 1].f_hz]),
        bins_tested: tested.len(),
        independent_tests: m,
        threshold_sigma,
        max_magnitude_deviation_sigma: wm.map_or(0.0, |b| b.magnitude_deviation_sigma),
        max_magnitude_f_hz: wm.map_or(f64::NAN, |b| b.f_hz),
        max_magnitude_relative: wm.map_or(0.0, |b| ratio(&b).norm() - 1.0),
        max_phase_deviation_sigma: wp.map_or(0.0, |b| b.phase_deviation_sigma),
        max_phase_f_hz: wp.map_or(f64::NAN, |b| b.f_hz),
        max_phase_rad: wp.map_or(0.0, |b| ratio(&b).arg()),
        p_value,
        consistent: !tested.is_empty() && max_t <= threshold_sigma,
        bins,
    }
}

/// P(|T| > t) for Student's t with ν degrees of freedom: 2·(1 − F_ν(|t|)),
/// F_ν its distribution function (statrs' survival function, accurate in the far tail).
pub fn student_t_two_sided_tail(t: f64, nu: f64) -> f64 {
    match StudentsT::new(0.0, 1.0, nu) {
        Ok(d) => (2.0 * d.sf(t.abs())).min(1.0),
        Err(_) => f64::NAN,
    }
}

/// The t > 0 with P(|T| > t) = `p` for Student's t with ν degrees of freedom:
/// F_ν⁻¹(1 − p/2), from [`student_t_two_sided_tail`] by bisection (statrs' own
/// inverse misses the normal limit at large ν: at ν = 10⁷ it is off by more than
/// 10⁻⁵, which the table test below catches).
pub fn student_t_quantile_two_sided(p: f64, nu: f64) -> f64 {
    let (mut lo, mut hi) = (0.0, 1.0);
    while student_t_two_sided_tail(hi, nu) > p && hi < 1e8 {
        hi *= 2.0;
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if student_t_two_sided_tail(mid, nu) > p {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn student_t_matches_tables() {
        // Two-sided 95 % and 99 % points (any statistics table).
        for (p, nu, t) in
            [(0.05, 10.0, 2.228139), (0.01, 20.0, 2.845340), (0.05, 1.0, 12.706205), (0.002, 30.0, 3.385185)]
        {
            let q = student_t_quantile_two_sided(p, nu);
            assert!((q - t).abs() < 1e-5, "ν {nu}, p {p}: {q} vs {t}");
        }
        // Large ν: the normal distribution, P(|Z| > 1.959964) = 0.05.
        assert!((student_t_quantile_two_sided(0.05, 1e7) - 1.959964).abs() < 1e-5);
        // Cauchy (ν = 1): P(|T| > t) = 1 − 2·atan(t)/π.
        for t in [0.3, 1.0, 4.0] {
            let exact = 1.0 - 2.0 * f64::atan(t) / PI;
            assert!((student_t_two_sided_tail(t, 1.0) - exact).abs() < 1e-12, "{t}");
        }
    }
}
