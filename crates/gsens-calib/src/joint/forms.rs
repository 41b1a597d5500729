//! Which discrete loop a loop stated in words is.
//!
//! "2nd order, Bn 3 Hz, every 20 ms" names a different filter in each
//! receiver ([`LoopModel::discrete_forms`]): Kaplan & Hegarty's as gsens
//! runs it, GNSS-SDR's, PocketSDR's. At a long update interval they differ
//! by a few per cent in the response, which biases Γ̂ by as much while the
//! fitted natural frequency moves only within the loop's tolerance. So every
//! form is fitted (Γ, its natural frequency and the offset, as the joint fit
//! would), the data's likelihood picks the form, and Γ̂'s variance takes in
//! the other forms' Γ̂ by the data's odds for them, reaching every form the
//! data cannot tell from the best.
//!
//! The likelihood is that of coloured noise: each form's residuals are
//! prewhitened by one AR model of the noise (Burg's, fitted to the stated
//! form's residuals) and −2 ln L = n·ln(Σe²) over the n innovations (the
//! conditional likelihood, σ² profiled out). The forms have the same number
//! of parameters, so −2 ln L compares them directly; a white-noise RSS
//! would overstate how well strongly coloured loop residuals tell them
//! apart. With the loop's tolerance σ_p stated, a form whose fitted
//! bandwidth fails the statement's test (the joint fit's z) is not what the
//! words say (it fits only at, say, twice the stated bandwidth) and is left
//! out, and the Γ̂ whose spread σ takes in are the forms' Γ̂ moved to the
//! bandwidth the joint fit would combine with the statement.

use super::{
    FitStart, JointSpec, LOOP_TEST_Z, Residuals, Start, batch_pass, fit_axes, scaled_loop, solve_with_residuals,
};
use crate::{CalibError, EpochSeries, EstimateSettings, gls};
use gsens_core::{FedEpoch, LoopModel};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::borrow::Cow;

/// Δ(−2 ln L) at or below which the data cannot tell a form from the best:
/// the profile likelihood's 1σ region, as for the identified loop's shapes.
pub const LOOP_FORM_ALIKE: f64 = 1.0;

/// The most residuals the noise model of the comparison is fitted to (the
/// first ones, run by run): enough for its spectrum, as in the GLS step
/// ([`gls::GlsSettings::max_fit_samples`]).
const NOISE_FIT_SAMPLES: usize = 40_000;

/// One discrete form of the stated loop, as the data fit it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LoopFormFit {
    /// The form, in words.
    pub form: String,
    /// −2 ln L of its fit over the best form's (0 for the best; negative
    /// for a form that fits better but is not consistent with the statement).
    pub delta_m2lnl: f64,
    /// Whether its fitted bandwidth passes the stated loop's test within its
    /// tolerance (|z| ≤ [`crate::LOOP_TEST_Z`], the joint fit's): a form that
    /// fails it is neither chosen nor covered by σ (unless every form fails).
    #[serde(default = "consistent")]
    pub consistent_with_statement: bool,
    /// Γ̂ of its fit as the joint fit makes it: the offset fitted, the
    /// natural frequency within the stated loop's tolerance (freely without
    /// one) \[Hz/(m/s²)\].
    pub gamma_hz_per_mps2: [f64; 3],
    /// The natural frequency ωn/2π of its free fit, the data's \[Hz\]
    /// (`None`: held at the stated one, or none).
    pub natural_frequency_hz: Option<f64>,
    /// The same for the form at the stated bandwidth \[Hz\].
    pub stated_natural_frequency_hz: Option<f64>,
}

fn consistent() -> bool {
    true
}

/// The discrete forms of a loop stated in words, compared by the data.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LoopForms {
    /// Every form fitted, the stated one (gsens's own) first.
    pub forms: Vec<LoopFormFit>,
    /// The index of the form Γ̂ is given under: the best fit.
    pub chosen: usize,
    /// Δ(−2 ln L) within which a form is covered by σ ([`LOOP_FORM_ALIKE`]).
    pub alike_within: f64,
    /// Per axis, the variance added to Γ̂'s: the forms' spread about the
    /// best's Γ̂ weighted by the data's odds, Σ_k w_k·(Γ̂_k − Γ̂_best)² with
    /// w_k ∝ exp(−Δ_k/2), or, when larger, the largest (Γ̂_k − Γ̂_best)² of
    /// the forms within [`LoopForms::alike_within`] (so that 1σ reaches each);
    /// Γ̂ of the forms' fits within the loop's tolerance \[(Hz/(m/s²))²\].
    pub added_variance_hz_per_mps2_sq: [f64; 3],
}

impl LoopForms {
    /// The chosen form's fit.
    pub fn chosen_form(&self) -> &LoopFormFit {
        &self.forms[self.chosen]
    }

    /// The forms other than the chosen one the data cannot tell from it.
    pub fn alike(&self) -> impl Iterator<Item = &LoopFormFit> {
        let chosen = self.chosen;
        self.forms
            .iter()
            .enumerate()
            .filter(move |(k, f)| *k != chosen && f.consistent_with_statement && f.delta_m2lnl <= self.alike_within)
            .map(|(_, f)| f)
    }
}

/// The form among `forms` (of `settings`' loop, the stated one first) the
/// data fit best, and the comparison. Each form is fitted as `spec` asks
/// but without a tolerance (the data's fit, which the likelihood compares),
/// on the axes the first form's pass observes; with a tolerance stated, with
/// its covariance, which gives the statement's test of the form and its Γ̂
/// at the bandwidth the joint fit would combine ([`Solution::within_tolerance`]).
pub(crate) fn compare_loop_forms(
    series: &EpochSeries,
    settings: &EstimateSettings,
    spec: JointSpec,
    forms: &[LoopModel],
) -> Result<(LoopModel, LoopForms, FitStart), CalibError> {
    let with_form = |form: &LoopModel| EstimateSettings { receiver_loop: *form, ..*settings };
    let mut passes =
        forms.par_iter().map(|form| batch_pass(series, &with_form(form))).collect::<Result<Vec<_>, _>>()?;
    let axes = fit_axes(&passes[0].1, settings);
    let free = JointSpec { loop_tolerance: None, ..spec };
    // With a tolerance the fits' covariances give each form's Γ̂ as the joint
    // fit would report it and the statement's evidence against the form.
    let tolerance = spec.loop_tolerance.filter(|t| t.is_finite() && spec.natural_frequency);
    let fit = |(form, (fed, _)): (&LoopModel, &(Vec<FedEpoch>, _))| {
        let with_cov = tolerance.is_some();
        solve_with_residuals(series, &with_form(form), (free, &axes), Cow::Borrowed(fed), Start::Search, with_cov)
    };
    // With covariances the forms are fitted one after another: each sandwich
    // holds its Jacobian and noise spectra (about 20 MB on an hour of 40 Hz
    // epochs), and their own passes and FFTs run in parallel.
    let fits = match tolerance {
        Some(_) => forms.iter().zip(&passes).map(fit).collect::<Result<Vec<_>, _>>()?,
        None => forms.par_iter().zip(&passes).map(fit).collect::<Result<Vec<_>, _>>()?,
    };
    // Γ̂ under each form as the joint fit gives it, its loop combined with
    // the statement: what not knowing the form changes of the reported Γ̂.
    // The free fits' Γ̂ wander along the flat ωn–τ ridge of one shaking
    // rate, a spread the joint fit's σ already holds. A form whose fitted
    // bandwidth the statement's own test rejects (|z| > LOOP_TEST_Z, as the
    // joint fit would reject the stated loop) is not what the words say: it
    // is neither chosen nor covered, unless no form passes.
    let within: Vec<Option<([f64; 3], f64)>> =
        fits.iter().map(|(sol, _)| tolerance.and_then(|tol| sol.within_tolerance(tol, &axes))).collect();
    let passes_test = |k: usize| within[k].is_none_or(|(_, z)| z.abs() <= LOOP_TEST_Z);
    let any_passes = (0..forms.len()).any(passes_test);
    let considered: Vec<bool> = (0..forms.len()).map(|k| passes_test(k) || !any_passes).collect();
    let n = series.phase_err_rad.len();
    let residuals: Vec<&Residuals> = fits.iter().map(|(_, r)| r).collect();
    let m2lnl = whitened_m2lnl(&residuals, n, series.log_interval_s);
    let best = (0..forms.len()).filter(|&k| considered[k]).map(|k| m2lnl[k]).fold(f64::INFINITY, f64::min);
    let chosen = (0..forms.len()).find(|&k| considered[k] && m2lnl[k] == best).unwrap_or(0);
    let reported = |k: usize| within[k].map_or(fits[k].0.gamma, |(gamma, _)| gamma);
    let gamma_chosen = reported(chosen);
    let models = forms;
    let forms: Vec<LoopFormFit> = models
        .iter()
        .zip(&fits)
        .zip(&m2lnl)
        .enumerate()
        .map(|(k, ((form, (sol, _)), v))| LoopFormFit {
            form: form.to_string(),
            delta_m2lnl: v - best,
            consistent_with_statement: considered[k],
            gamma_hz_per_mps2: reported(k),
            natural_frequency_hz: sol
                .fitted
                .natural_frequency
                .then(|| scaled_loop(form, sol.theta.ln_s.exp(), sol.theta.zeta).natural_frequency_hz())
                .flatten(),
            stated_natural_frequency_hz: form.natural_frequency_hz(),
        })
        .collect();
    let added = form_variance(&forms, gamma_chosen);
    let model = models[chosen];
    // The chosen form's joint fit starts where its fit here ended.
    let start = FitStart { fed0: passes.swap_remove(chosen).0, axes, theta: fits[chosen].0.theta };
    let compared = LoopForms { forms, chosen, alike_within: LOOP_FORM_ALIKE, added_variance_hz_per_mps2_sq: added };
    Ok((model, compared, start))
}

/// The variance per axis the forms add to Γ̂ of the chosen one,
/// `gamma_chosen`: the larger of their spread weighted by the data's odds,
/// Σ_k w_k·(Γ̂_k − Γ̂)² with w_k ∝ exp(−Δ_k/2) (the forms' posterior under
/// equal priors), and the largest (Γ̂_k − Γ̂)² of the forms within
/// [`LOOP_FORM_ALIKE`]. The weighted spread covers a wrong choice: under one
/// shaking rate a receiver's form differs from another's mostly by a gain
/// and a delay, which Γ and the IMU time offset take up, and the data tell
/// them apart only by a Δ of about ten, so the other form wins now and then.
pub(crate) fn form_variance(forms: &[LoopFormFit], gamma_chosen: [f64; 3]) -> [f64; 3] {
    let weights: Vec<f64> =
        forms.iter().map(|f| if f.consistent_with_statement { (-0.5 * f.delta_m2lnl).exp() } else { 0.0 }).collect();
    let gammas: Vec<[f64; 3]> = forms.iter().map(|f| f.gamma_hz_per_mps2).collect();
    let weighted = weighted_spread(&weights, &gammas, gamma_chosen);
    [0, 1, 2].map(|i| {
        let spread = |f: &LoopFormFit| (f.gamma_hz_per_mps2[i] - gamma_chosen[i]).powi(2);
        let alike = forms
            .iter()
            .filter(|f| f.consistent_with_statement && f.delta_m2lnl <= LOOP_FORM_ALIKE)
            .map(spread)
            .fold(0.0, f64::max);
        weighted[i].max(alike)
    })
}

/// The spread of alternative fits' Γ̂ (`gammas`) about the best one's,
/// weighted by `weights` (the data's odds exp(−Δ_k/2) for each), per axis:
/// Σ_k w_k·(Γ̂_k − Γ̂_best)² / Σ_k w_k. What not knowing which alternative
/// holds adds to Γ̂'s variance (a loop's form here, an identified loop's
/// shape in [`crate::nco_loop`]).
pub(crate) fn weighted_spread(weights: &[f64], gammas: &[[f64; 3]], gamma_best: [f64; 3]) -> [f64; 3] {
    let total: f64 = weights.iter().sum();
    [0, 1, 2].map(|i| gammas.iter().zip(weights).map(|(g, w)| w * (g[i] - gamma_best[i]).powi(2)).sum::<f64>() / total)
}

/// −2 ln L (up to a constant) of each fit's residuals under one AR model of
/// the noise: fitted to the first fit's residuals on the epochs every fit
/// used (at most [`NOISE_FIT_SAMPLES`] of them, the longest memory
/// [`gls::MAX_AR_SPAN_S`]), each fit's residuals whitened run by run, and
/// n·ln(Σe²) over the n innovations.
fn whitened_m2lnl(fits: &[&Residuals], n: usize, log_interval_s: f64) -> Vec<f64> {
    // Each fit's residuals on the series' epochs, and the epochs every fit used.
    let mut common = vec![true; n];
    let full: Vec<Vec<f64>> = fits
        .iter()
        .map(|r| {
            let mut v = vec![f64::NAN; n];
            for (&k, &e) in r.used.iter().zip(r.rad.iter()) {
                v[k] = e;
            }
            v
        })
        .collect();
    for v in &full {
        for (c, e) in common.iter_mut().zip(v) {
            *c &= !e.is_nan();
        }
    }
    let segments = gls::segments_of(common.iter().copied());
    let mut noise_slices: Vec<&[f64]> = Vec::new();
    let mut taken = 0;
    for s in &segments {
        if taken >= NOISE_FIT_SAMPLES {
            break;
        }
        let len = s.len().min(NOISE_FIT_SAMPLES - taken);
        noise_slices.push(&full[0][s.start..s.start + len]);
        taken += len;
    }
    let max_order = ((gls::MAX_AR_SPAN_S / log_interval_s).ceil() as usize).min(taken / 20).max(1);
    let noise = gls::fit_ar(&noise_slices, max_order);
    full.par_iter()
        .map(|v| {
            let (mut sum, mut count) = (0.0, 0usize);
            for s in &segments {
                for e in noise.whiten(&v[s.clone()]) {
                    sum += e * e;
                    count += 1;
                }
            }
            count as f64 * (sum / count.max(1) as f64).ln()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn form(delta_m2lnl: f64, gamma_x: f64) -> LoopFormFit {
        LoopFormFit {
            form: String::new(),
            delta_m2lnl,
            consistent_with_statement: true,
            gamma_hz_per_mps2: [gamma_x, 0.0, 0.0],
            natural_frequency_hz: None,
            stated_natural_frequency_hz: None,
        }
    }

    /// The odds-weighted spread in closed form, w = e^{−Δ/2}/(1 + e^{−Δ/2}),
    /// and the whole spread of a form within Δ ≤ 1.
    #[test]
    fn the_forms_add_their_spread_by_the_datas_odds() {
        let d = 0.01;
        let added = form_variance(&[form(0.0, 0.1), form(2.0, 0.1 + d)], [0.1, 0.0, 0.0]);
        let w = (-1.0f64).exp() / (1.0 + (-1.0f64).exp());
        assert!((added[0] - w * d * d).abs() < 1e-15, "{added:?}");
        assert_eq!((added[1], added[2]), (0.0, 0.0));
        let alike = form_variance(&[form(0.0, 0.1), form(0.5, 0.1 + d)], [0.1, 0.0, 0.0]);
        assert!((alike[0] - d * d).abs() < 1e-15, "{alike:?}");
        // A form the data rule out adds (almost) nothing.
        let far = form_variance(&[form(0.0, 0.1), form(60.0, 0.1 + d)], [0.1, 0.0, 0.0]);
        assert!(far[0] < 1e-13 * d * d, "{far:?}");
        // A form the statement's test rejects adds nothing, however well it fits.
        let rejected = LoopFormFit { consistent_with_statement: false, ..form(-5.0, 0.1 + d) };
        assert_eq!(form_variance(&[form(0.0, 0.1), rejected], [0.1, 0.0, 0.0]), [0.0; 3]);
    }
}
