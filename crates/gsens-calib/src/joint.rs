//! The stated loop tested by the data: Γ, the loop's natural frequency (and,
//! when asked, a 2nd-order loop's damping) and the IMU time offset estimated
//! jointly, with one covariance for all of them.
//!
//! The model of the high-passed, channel-averaged phase error is
//! φ_k = φ_a,k(s, ζ, τ)ᵀΓ + n_k, where φ_a,k(s, ζ, τ) is the regressor triad
//! run with the stated loop's natural frequency scaled by s (its damping set
//! to ζ) and the IMU read at true time + τ, and n is coloured noise. It is
//! solved by Gauss–Newton: at θ = (ln s, ζ, τ) the Jacobian of φ_aᵀΓ is
//!
//! - ∂/∂ln s and ∂/∂ζ: central differences of two triad runs at ln s ± h;
//! - ∂/∂τ: the time derivative of φ_aᵀΓ (the series shifted by ±ε by
//!   Catmull–Rom interpolation, as the offset search does);
//!
//! and one least-squares step on [φ_a, ∂θ] updates Γ and θ together.
//!
//! The covariance of (Γ, θ) is the least-squares sandwich
//! (JᵀJ)⁻¹·JᵀΣJ·(JᵀJ)⁻¹ with Σ the autocovariance of an AR model fitted to
//! the joint fit's own residuals ([`crate::gls::covariance_middle_columns`]):
//! a carrier loop's residuals are strongly coloured, and a white-noise
//! likelihood ratio would reject correct loops far more often than it says.
//! The test of the stated loop is then the Wald test z = ln ŝ/σ(ln ŝ),
//! two-sided at [`LOOP_TEST_FALSE_ALARM`]. The Γ block of the covariance is
//! the uncertainty of Γ̂ with the loop and the offset unknown: where they are
//! confounded (a constant shaking rate, whose phase lag a loop error and a
//! delay both explain) it grows, instead of one absorbing the other.

mod forms;
mod params;

use crate::search::{Shift, batch_pass, offset_profile, scaled_loop};
use crate::{CalibError, EpochSeries, EstimateSettings, gls};
pub use forms::{LOOP_FORM_ALIKE, LoopFormFit, LoopForms};
pub(crate) use forms::{compare_loop_forms, form_variance, weighted_spread};
use gsens_core::{FedEpoch, LoopModel, LoopSpec};
use nalgebra::{DMatrix, DVector};
use params::{Fitted, Start, Theta};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::borrow::Cow;

/// False-alarm probability of the test of the stated loop (two-sided).
pub const LOOP_TEST_FALSE_ALARM: f64 = 1e-3;

/// |z| above which the stated loop is rejected: the standard normal's
/// two-sided point for [`LOOP_TEST_FALSE_ALARM`], Φ⁻¹(1 − 0.0005) = 3.2905.
pub const LOOP_TEST_Z: f64 = 3.2905;

/// Which nuisance parameters are estimated with Γ.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointSpec {
    /// Estimate the loop's natural frequency (the stated loop's scaled).
    pub natural_frequency: bool,
    /// Also a 2nd-order loop's damping ζ.
    pub damping: bool,
    /// Estimate the IMU time offset within ± this many seconds of the
    /// series' own offset.
    pub offset_max_abs_s: Option<f64>,
    /// With the natural frequency estimated: the relative 1σ uncertainty of
    /// the stated loop's natural frequency, a Gaussian prior on ln s of this
    /// width (0: the stated loop is exact; `None`: nothing is known of it
    /// beyond its shape, and Γ̂ is given under the fitted loop).
    pub loop_tolerance: Option<f64>,
}

/// The joint estimate of Γ, the loop and the IMU time offset.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[non_exhaustive]
pub struct JointFit {
    /// The loop stated (or assumed), in words.
    pub stated_loop: String,
    /// The loop that fits the data, in words.
    pub fitted_loop: String,
    /// The stated loop's natural frequency ωn/2π \[Hz\] (None: not estimated).
    pub stated_natural_frequency_hz: Option<f64>,
    /// The fitted natural frequency \[Hz\].
    pub natural_frequency_hz: Option<f64>,
    /// Its 1σ \[Hz\].
    pub sigma_natural_frequency_hz: Option<f64>,
    /// The fitted loop's noise bandwidth Bn \[Hz\].
    pub bn_hz: Option<f64>,
    /// The stated damping (2nd order, when estimated).
    pub stated_zeta: Option<f64>,
    /// The fitted damping and its 1σ.
    pub zeta: Option<[f64; 2]>,
    /// z = ln(ωn̂/ωn,stated)/σ: the test statistic of the stated loop.
    pub loop_test_z: Option<f64>,
    /// |z| above which the stated loop is rejected ([`LOOP_TEST_Z`]).
    pub loop_test_threshold_z: f64,
    /// Its false-alarm probability ([`LOOP_TEST_FALSE_ALARM`]).
    pub loop_test_false_alarm: f64,
    /// Whether the data reject the stated loop.
    pub stated_loop_rejected: bool,
    /// The relative 1σ tolerance of the stated loop's natural frequency the
    /// fit combined with the data (`None`: unknown, the loop fitted freely).
    pub loop_tolerance: Option<f64>,
    /// The natural frequency of the loop Γ̂ is given under \[Hz\]: the data's
    /// fit and the stated loop within its tolerance combined (the fitted one
    /// without a tolerance or when the data reject the stated loop).
    pub used_natural_frequency_hz: Option<f64>,
    /// Its 1σ \[Hz\].
    pub sigma_used_natural_frequency_hz: Option<f64>,
    /// IMU time stamp minus true time \[s\] (total), when estimated.
    pub imu_time_offset_s: Option<f64>,
    /// Its 1σ \[s\].
    pub sigma_imu_time_offset_s: Option<f64>,
    /// 1σ of the offset in the fit whose linearization Γ̂ and σ rest on \[s\]:
    /// the free fit's (the data alone) when it was combined with a loop
    /// tolerance through its covariance, the held fit's for an exact loop.
    pub linearization_sigma_imu_time_offset_s: Option<f64>,
    /// The offset's search range ± \[s\] (around the series' own offset).
    pub offset_max_abs_s: Option<f64>,
    /// Whether the offset ended at the edge of its search range.
    pub offset_at_limit: bool,
    /// Correlation of ln ωn̂ with the offset: near ±1 the two are confounded.
    pub correlation_loop_offset: Option<f64>,
    /// Γ̂ of the joint fit \[Hz/(m/s²)\].
    pub gamma_hz_per_mps2: [f64; 3],
    /// Γ̂ under the stated loop (at the fitted offset) \[Hz/(m/s²)\].
    pub gamma_stated_loop_hz_per_mps2: [f64; 3],
    /// Per axis, the variance of Γ̂ with the nuisance parameters estimated
    /// over the variance with them known (≥ 1): how much not knowing the
    /// loop and the offset costs.
    pub variance_inflation: [f64; 3],
    /// Whether Γ̂ is under a loop other than the stated one: the fitted loop,
    /// or the stated one moved within its tolerance (false: under the stated
    /// loop itself, exact or not estimated).
    pub fitted_loop_used: bool,
    /// Residual sum of squares of the joint fit \[rad²\].
    pub rss_rad2: f64,
    /// Epochs in the fit.
    pub epochs: usize,
    /// Covariance of the batch Γ̂ with the loop and the offset estimated
    /// (the Γ block of the joint sandwich) \[(Hz/(m/s²))²\].
    pub gamma_covariance_hz_per_mps2_sq: [[f64; 3]; 3],
    /// Gauss–Newton iterations run.
    pub iterations: u32,
    /// The discrete forms of a loop stated in words, as the data fit them
    /// (`None`: the loop has one form, or it is a receiver's own): the fit is
    /// under the best, and [`JointFit::gamma_covariance_hz_per_mps2_sq`]
    /// takes in [`LoopForms::added_variance_hz_per_mps2_sq`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub loop_forms: Option<LoopForms>,
}

/// The series of φ_a for one loop: every epoch as the estimator fed it.
fn triad_pass(
    series: &EpochSeries,
    settings: &EstimateSettings,
    model: &LoopModel,
) -> Result<Vec<FedEpoch>, CalibError> {
    let mut s = *settings;
    s.receiver_loop = *model;
    Ok(batch_pass(series, &s)?.0)
}

/// φ_a of `fed` at epoch k shifted by `dtau_s` (IMU read later by dtau): `by`,
/// the shift by dtau_s/T samples (φ_a itself at no shift).
fn shifted(fed: &[FedEpoch], k: usize, dtau_s: f64, by: &Shift) -> [f64; 3] {
    if dtau_s == 0.0 { fed[k].phi_a } else { by.at(fed.len(), k, |j| fed[j].phi_a) }
}

fn dot(a: &[f64; 3], g: &[f64; 3]) -> f64 {
    a[0] * g[0] + a[1] * g[1] + a[2] * g[2]
}

/// The damping of a 2nd-order Kaplan loop.
fn zeta_of(model: &LoopModel) -> Option<f64> {
    match model {
        LoopModel::Kaplan { spec: LoopSpec::SecondOrder { zeta, .. }, .. } => Some(*zeta),
        _ => None,
    }
}

/// Estimates Γ jointly with the nuisance parameters `spec` asks for, starting
/// from the stated loop `settings.receiver_loop` and the series' offset.
///
/// Axes the data cannot observe under the stated loop
/// ([`gsens_core::assess`] with `settings.criteria`) are left out of the fit
/// (their Γ̂ reads 0, their variance inflation 1): their small, correlated
/// columns would otherwise inflate the shaken axes' σ.
///
/// With a loop tolerance σ_p ([`JointSpec::loop_tolerance`]) the data's
/// ln ŝ (variance C_ss) and the prior ln s ~ N(0, σ_p²) are combined as two
/// Gaussian measurements of ln s:
///
/// ```text
/// z = ln ŝ / √(C_ss + σ_p²)                      the stated loop's test
/// w = σ_p² / (C_ss + σ_p²),  ln s* = w·ln ŝ,  σ*² = w·C_ss
/// Cov(η) = Cov(η | ln s*) + b·bᵀ·σ*²,  b = C_η,s / C_ss
/// ```
///
/// η is every other parameter (Γ, ζ, τ), Cov(η | ln s*) the sandwich of a
/// second fit with the loop held at ln s*, and b their regression on ln s in
/// the free fit: the Gaussian posterior, linearized (σ_p = 0: the stated loop
/// exact, Cov(η | 0); σ_p → ∞: the free fit). Γ̂ and τ̂ are the second fit's:
/// the model is nonlinear in ln s, so Γ̂ is refitted at ln s* rather than
/// extrapolated there. When the test rejects the stated loop, Γ̂ is the free
/// fit's.
pub fn joint_fit(series: &EpochSeries, settings: &EstimateSettings, spec: JointSpec) -> Result<JointFit, CalibError> {
    joint_fit_from(series, settings, spec, None)
}

/// The data's ln ŝ (variance C_ss) combined with the statement ln s ~ N(0, σ_p²)
/// ([`joint_fit`]): the statement's test z, the posterior ln s* and its variance.
struct StatedCombined {
    z: f64,
    ln_s_post: f64,
    var_post: f64,
}

/// [`StatedCombined`] of ln ŝ = `ln_s`, C_ss = `c_ss` and σ_p = `tol`:
/// z = ln ŝ/√(C_ss + σ_p²), w = σ_p²/(C_ss + σ_p²), ln s* = w·ln ŝ, σ*² = w·C_ss.
fn combine_with_statement(ln_s: f64, c_ss: f64, tol: f64) -> StatedCombined {
    let w = tol * tol / (c_ss + tol * tol);
    StatedCombined { z: ln_s / (c_ss + tol * tol).sqrt(), ln_s_post: w * ln_s, var_post: w * c_ss }
}

/// Where a joint fit may start: the stated loop's pass over the series, the
/// axes fitted and θ where an earlier fit of the same problem ended (the
/// comparison of the stated loop's forms fits the chosen one so).
pub(crate) struct FitStart {
    fed0: Vec<FedEpoch>,
    axes: Vec<usize>,
    theta: Theta,
}

/// [`joint_fit`], from `start` when given (its free fit then confirms the
/// earlier one's end in one Gauss–Newton step rather than searching again).
pub(crate) fn joint_fit_from(
    series: &EpochSeries,
    settings: &EstimateSettings,
    spec: JointSpec,
    start: Option<FitStart>,
) -> Result<JointFit, CalibError> {
    // The stated loop's pass: it decides the axes and starts the fit.
    let (fed0, axes, start) = match start {
        Some(FitStart { fed0, axes, theta }) => (fed0, axes, Start::At(theta)),
        None => {
            let (fed0, ne) = batch_pass(series, settings)?;
            let axes = fit_axes(&ne, settings);
            (fed0, axes, Start::Search)
        }
    };
    let stated = settings.loop_at(series.log_interval_s);
    let fit_loop = spec.natural_frequency && stated.natural_frequency_hz().is_some();
    let tolerance = spec.loop_tolerance.filter(|t| fit_loop && t.is_finite());
    let Some(tol) = tolerance else {
        return free_fit(series, settings, (spec, &axes), fed0, start, true);
    };
    let free = solve(series, settings, spec, &axes, Cow::Borrowed(&fed0), start, true)?;
    let (ln_s, c_ss) = free.ln_s_and_variance().unwrap_or((0.0, 0.0));
    let StatedCombined { z, ln_s_post, var_post } = combine_with_statement(ln_s, c_ss, tol);
    // No variance of ln ŝ (NaN included) or a rejected loop: the free fit.
    if c_ss.is_nan() || c_ss <= 0.0 || z.is_nan() || z.abs() > LOOP_TEST_Z {
        let evidence = LoopEvidence {
            data: Some((ln_s, c_ss)),
            tolerance: Some(tol),
            linearization_sigma_tau_s: free.sigma_tau_s(),
        };
        return Ok(describe(series, &stated, spec, &axes, &free, evidence));
    }
    // The second fit: the loop held at ln s*, everything else free.
    let mut at_post = *settings;
    at_post.receiver_loop = scaled_loop(&stated, ln_s_post.exp(), free.theta.zeta);
    let fed_post = if ln_s_post == 0.0 && free.theta.zeta == zeta_of(&stated) {
        Cow::Owned(fed0)
    } else {
        drop(fed0);
        Cow::Owned(triad_pass(series, settings, &at_post.receiver_loop)?)
    };
    let held = JointSpec { natural_frequency: false, loop_tolerance: None, ..spec };
    let refit = solve(series, &at_post, held, &axes, fed_post, Start::Offset(free.theta.dtau_s), true)?;
    let posterior = free.posterior(&refit, ln_s_post, var_post);
    // Held exact, the free fit's linearization is not used: the held fit's σ_τ is what must hold.
    let linearization_sigma_tau_s = if tol == 0.0 { posterior.sigma_tau_s() } else { free.sigma_tau_s() };
    let evidence = LoopEvidence { data: Some((ln_s, c_ss)), tolerance: Some(tol), linearization_sigma_tau_s };
    Ok(describe(series, &stated, spec, &axes, &posterior, evidence))
}

/// The axes a joint fit solves for: those the stated loop's pass observes
/// (all three when it observes none).
fn fit_axes(ne: &gsens_core::NormalEquations, settings: &EstimateSettings) -> Vec<usize> {
    let in_solve = gsens_core::axes_in_solve(ne, &settings.criteria);
    let axes: Vec<usize> = (0..3).filter(|&i| in_solve[i]).collect();
    if axes.is_empty() { vec![0, 1, 2] } else { axes }
}

/// A solved joint fit: the parameters and their sandwich covariance.
struct Solution {
    /// Γ̂ (0 on the axes left out).
    gamma: [f64; 3],
    /// Γ̂ under the loop the fit started from, at the fitted offset.
    gamma_stated: [f64; 3],
    /// θ: ln s of the loop the fit is under (relative to the starting loop),
    /// its damping and the offset.
    theta: Theta,
    /// Covariance of (Γ on the fit's axes, ln s, ζ, τ: those estimated).
    cov: DMatrix<f64>,
    /// Covariance of Γ̂ with the nuisance parameters known.
    cov3: DMatrix<f64>,
    /// What was fitted: the rows and columns of `cov`.
    fitted: Fitted,
    rss_rad2: f64,
    epochs: usize,
    iterations: u32,
}

impl Solution {
    /// 1σ of the offset, when it was estimated \[s\].
    fn sigma_tau_s(&self) -> Option<f64> {
        self.fitted.tau_index().map(|t| self.cov[(t, t)].max(0.0).sqrt())
    }

    /// ln ŝ and its variance, when the natural frequency was estimated.
    fn ln_s_and_variance(&self) -> Option<(f64, f64)> {
        self.fitted.loop_index().map(|l| (self.theta.ln_s, self.cov[(l, l)]))
    }

    /// This free fit (with covariance) under a loop stated within the relative
    /// tolerance `tol`, linearized as [`joint_fit`] combines them: the
    /// statement's test z = ln ŝ/√(C_ss + σ_p²), and Γ̂ moved to
    /// ln s* = w·ln ŝ (w = σ_p²/(C_ss + σ_p²)) along its regression on ln s,
    /// `Γ̂* = Γ̂ + b·(ln s* − ln ŝ)`, b = C_Γ,s/C_ss: the Γ̂ the joint fit
    /// reports under this loop. `axes`: the fit's axes, in its order. `None`
    /// without a loop variance.
    fn within_tolerance(&self, tol: f64, axes: &[usize]) -> Option<([f64; 3], f64)> {
        let (ln_s, c_ss) = self.ln_s_and_variance()?;
        let l = self.fitted.loop_index()?;
        if !(c_ss > 0.0 && c_ss.is_finite() && tol.is_finite()) {
            return None;
        }
        let StatedCombined { z, ln_s_post, .. } = combine_with_statement(ln_s, c_ss, tol);
        let mut gamma = self.gamma;
        for (m, i) in axes.iter().enumerate() {
            gamma[*i] += self.cov[(m, l)] / c_ss * (ln_s_post - ln_s);
        }
        Some((gamma, z))
    }

    /// The posterior of [`joint_fit`]'s combination: `held`, a fit with the
    /// loop held at `ln_s_post` (no loop column), with the free fit's (self's)
    /// regression on ln s adding the posterior variance `var_post`.
    fn posterior(&self, held: &Solution, ln_s_post: f64, var_post: f64) -> Solution {
        let l = self.fitted.loop_index().expect("a free fit with the natural frequency estimated");
        let c_ss = self.cov[(l, l)];
        let b: Vec<f64> = (0..self.cov.nrows()).map(|m| self.cov[(m, l)] / c_ss).collect();
        // The held fit's index of each of the free fit's parameters (the
        // free fit's columns without ln s, in the same order).
        let map = |m: usize| -> Option<usize> {
            match m.cmp(&l) {
                core::cmp::Ordering::Less => Some(m),
                core::cmp::Ordering::Equal => None,
                core::cmp::Ordering::Greater => Some(m - 1),
            }
        };
        let p = self.cov.nrows();
        let cov = DMatrix::from_fn(p, p, |r, c| {
            let conditional = match (map(r), map(c)) {
                (Some(i), Some(j)) => held.cov[(i, j)],
                _ => 0.0,
            };
            conditional + b[r] * b[c] * var_post
        });
        Solution {
            gamma: held.gamma,
            gamma_stated: self.gamma_stated,
            theta: Theta { ln_s: ln_s_post, ..held.theta },
            cov,
            cov3: held.cov3.clone(),
            fitted: self.fitted,
            rss_rad2: held.rss_rad2,
            epochs: held.epochs,
            iterations: self.iterations + held.iterations,
        }
    }
}

/// The step in ln s and in ζ of the central differences of the Jacobian.
const LOOP_DIFFERENCE_STEP: f64 = 0.01;
/// The step in τ of the offset column's central difference, in log intervals.
const OFFSET_DIFFERENCE_STEP: f64 = 0.1;
/// The most Gauss–Newton iterations.
const MAX_ITERATIONS: u32 = 12;
/// Converged when every nuisance step is below this fraction of its (white-noise) σ.
const CONVERGED_STEP_SIGMAS: f64 = 0.02;

/// What a joint fit runs over: the series, the loop it starts from, what it
/// fits, and the epochs it uses with their phases.
struct Problem<'a> {
    series: &'a EpochSeries<'a>,
    settings: &'a EstimateSettings,
    /// The loop the fit starts from (`settings`' at the log interval).
    stated: LoopModel,
    fitted: Fitted,
    axes: &'a [usize],
    /// The epochs fitted: used by the estimator, with a phase, and clear of
    /// the offset's search margin at both ends.
    used: Vec<usize>,
    /// Their phases \[rad\].
    phi: Vec<f64>,
}

impl<'a> Problem<'a> {
    /// The problem of [`solve`] and its start: the stated loop (or where
    /// `start` says), the offset clamped to its range (0 when not fitted).
    /// Fewer than 20 epochs are an error.
    fn new(
        series: &'a EpochSeries<'a>,
        settings: &'a EstimateSettings,
        (spec, axes): (JointSpec, &'a [usize]),
        fed0: &[FedEpoch],
        start: Start,
    ) -> Result<(Self, Theta), CalibError> {
        let t = series.log_interval_s;
        let stated = settings.loop_at(t);
        let zeta0 = zeta_of(&stated);
        let fitted = Fitted {
            axes: axes.len(),
            natural_frequency: spec.natural_frequency && stated.natural_frequency_hz().is_some(),
            damping: spec.damping && zeta0.is_some(),
            offset_max_abs_s: spec.offset_max_abs_s,
        };
        let margin = spec.offset_max_abs_s.map_or(0, |m| (m / t).ceil() as usize + 2);
        let theta0 = match start {
            Start::At(theta) => theta,
            Start::Search | Start::Offset(_) => Theta { ln_s: 0.0, zeta: zeta0, dtau_s: 0.0 },
        };
        let dtau_s = match (spec.offset_max_abs_s, start) {
            (Some(max), Start::Offset(d)) => d.clamp(-max, max),
            (Some(max), Start::At(theta)) => theta.dtau_s.clamp(-max, max),
            (Some(max), Start::Search) => offset_profile(fed0, t, max)?.dtau_s,
            (None, _) => 0.0,
        };
        let n = fed0.len();
        // The used epochs and their phases, in epoch order (rayon's collect keeps it).
        let used: Vec<usize> = (margin..n.saturating_sub(margin))
            .into_par_iter()
            .filter(|&k| fed0[k].used && fed0[k].phase_err_rad.is_some())
            .collect();
        if used.len() < 20 {
            return Err(CalibError::TooFewEpochs { epochs: used.len() as u64, warmup_s: settings.warmup_s });
        }
        let phi: Vec<f64> = used.par_iter().map(|&k| fed0[k].phase_err_rad.unwrap_or(0.0)).collect();
        let problem = Problem { series, settings, stated, fitted, axes, used, phi };
        Ok((problem, Theta { dtau_s, ..theta0 }))
    }

    /// The stated loop with ln s and ζ of θ.
    fn loop_at(&self, ln_s: f64, zeta: Option<f64>) -> LoopModel {
        scaled_loop(&self.stated, ln_s.exp(), zeta)
    }

    /// Γ̂ of the least squares of the phases on the regressors `a` (one per
    /// used epoch), 0 on the axes left out.
    fn gamma_on_axes(&self, a: impl Iterator<Item = [f64; 3]>) -> [f64; 3] {
        let mut ne = gsens_core::NormalEquations::default();
        for (ak, pk) in a.zip(&self.phi) {
            ne.add(*pk, &ak);
        }
        let mut g = ne.solve().gamma_hz_per_mps2;
        for (i, gi) in g.iter_mut().enumerate() {
            if !self.axes.contains(&i) {
                *gi = 0.0;
            }
        }
        g
    }

    /// The Jacobian of φ_aᵀΓ at θ over the used epochs, one column per
    /// parameter in the solver's order: φ_a on the fit's axes, then the
    /// central differences in ln s and ζ (two more passes each) and the time
    /// derivative in τ, at Γ̂ of θ (`fed0`: the stated loop's pass).
    fn jacobian(&self, fed0: &[FedEpoch], theta: &Theta) -> Result<DMatrix<f64>, CalibError> {
        let t = self.series.log_interval_s;
        let (h, eps, dtau) = (LOOP_DIFFERENCE_STEP, OFFSET_DIFFERENCE_STEP * t, theta.dtau_s);
        let center = if theta.ln_s == 0.0 && theta.zeta == zeta_of(&self.stated) {
            Cow::Borrowed(fed0)
        } else {
            Cow::Owned(triad_pass(self.series, self.settings, &self.loop_at(theta.ln_s, theta.zeta))?)
        };
        let by = Shift::samples(dtau / t);
        let used = &self.used;
        let a: Vec<[f64; 3]> = used.par_iter().map(|&k| shifted(&center, k, dtau, &by)).collect();
        // Γ̂ at the current θ, for the Jacobian of the nuisance parameters.
        let g = self.gamma_on_axes(a.iter().copied());
        // The nuisance parameters' columns, after φ_a's on the fit's axes.
        let mut columns: Vec<Vec<f64>> = Vec::new();
        // φ_aᵀΓ̂ over the used epochs of one more pass (its epochs freed at
        // once), each epoch's on its own (the epochs in parallel).
        let predicted = |model: &LoopModel| -> Result<Vec<f64>, CalibError> {
            let fed = triad_pass(self.series, self.settings, model)?;
            Ok(used.par_iter().map(|&k| dot(&shifted(&fed, k, dtau, &by), &g)).collect())
        };
        let diff = |lo: &LoopModel, hi: &LoopModel, step: f64| -> Result<Vec<f64>, CalibError> {
            // Two independent passes over the log.
            let (pl, ph) = rayon::join(|| predicted(lo), || predicted(hi));
            let (pl, ph) = (pl?, ph?);
            Ok(ph.par_iter().zip(&pl).map(|(h, l)| (h - l) / step).collect())
        };
        let (ln_s, zeta) = (theta.ln_s, theta.zeta);
        if self.fitted.natural_frequency {
            columns.push(diff(&self.loop_at(ln_s - h, zeta), &self.loop_at(ln_s + h, zeta), 2.0 * h)?);
        }
        if self.fitted.damping {
            let z = zeta.unwrap_or(0.707);
            columns.push(diff(&self.loop_at(ln_s, Some(z - h)), &self.loop_at(ln_s, Some(z + h)), 2.0 * h)?);
        }
        if self.fitted.offset_max_abs_s.is_some() {
            let (later, earlier) = (Shift::samples((dtau + eps) / t), Shift::samples((dtau - eps) / t));
            let n_c = center.len();
            columns.push(
                used.par_iter()
                    .map(|&k| {
                        let phi_a = |j: usize| center[j].phi_a;
                        (dot(&later.at(n_c, k, phi_a), &g) - dot(&earlier.at(n_c, k, phi_a), &g)) / (2.0 * eps)
                    })
                    .collect(),
            );
        }
        // Column-major: each column's rows written on their own, in parallel.
        let n = used.len();
        let mut jac = DMatrix::zeros(n, self.fitted.len());
        let (phi_a_part, nuisance_part) = jac.as_mut_slice().split_at_mut(n * self.axes.len());
        phi_a_part.par_chunks_mut(n).zip(self.axes.par_iter()).for_each(|(dst, &i)| {
            for (d, v) in dst.iter_mut().zip(&a) {
                *d = v[i];
            }
        });
        nuisance_part.par_chunks_mut(n).zip(columns).for_each(|(dst, src)| dst.copy_from_slice(&src));
        Ok(jac)
    }
}

/// JᵀJ of `jac`, entry (i, j) the dot product of columns i and j as
/// nalgebra's `tr_mul` computes it (so the same bits), the entries on and
/// above the diagonal computed in parallel and mirrored below it (the dot
/// product is the same either way round).
fn gram(jac: &DMatrix<f64>) -> DMatrix<f64> {
    let p = jac.ncols();
    let pairs: Vec<(usize, usize)> = (0..p).flat_map(|i| (i..p).map(move |j| (i, j))).collect();
    let dots: Vec<f64> = pairs.par_iter().map(|&(i, j)| jac.column(i).dot(&jac.column(j))).collect();
    let mut g = DMatrix::zeros(p, p);
    for (&(i, j), &d) in pairs.iter().zip(&dots) {
        g[(i, j)] = d;
        g[(j, i)] = d;
    }
    g
}

/// Jᵀy of `jac`, entry i the dot product of column i with `y` as nalgebra's
/// `tr_mul` computes it, the columns in parallel.
fn tr_mul_vector(jac: &DMatrix<f64>, y: &DVector<f64>) -> DVector<f64> {
    let dots: Vec<f64> = (0..jac.ncols()).into_par_iter().map(|i| jac.column(i).dot(y)).collect();
    DVector::from_vec(dots)
}

/// One Gauss–Newton step: the least-squares solution on the Jacobian (Γ
/// and the nuisance steps, laid out as the solver's vector), whether
/// every nuisance step, limited, lies within [`CONVERGED_STEP_SIGMAS`] of
/// its white-noise σ, and JᵀJ with its inverse.
fn gauss_newton_step(
    jac: &DMatrix<f64>,
    y: &DVector<f64>,
    fitted: &Fitted,
) -> Result<(DVector<f64>, bool, Normal), CalibError> {
    let jtj = gram(jac);
    let Some(jtj_inv) = jtj.clone().try_inverse() else {
        return Err(CalibError::Unsupported("the joint fit of Γ, the loop and the time offset is singular"));
    };
    let beta = &jtj_inv * tr_mul_vector(jac, y);
    let white_var = {
        let r = y - jac * &beta;
        r.norm_squared() / (jac.nrows() as f64 - fitted.len() as f64).max(1.0)
    };
    let small = |c: usize, d: f64| d.abs() <= CONVERGED_STEP_SIGMAS * (jtj_inv[(c, c)] * white_var).max(0.0).sqrt();
    let step = Theta::limited_step(&fitted.read(beta.as_slice()), fitted.offset_max_abs_s);
    let converged = step.nuisance(fitted).iter().fold(true, |all, &(c, d)| all & small(c, d));
    Ok((beta, converged, Normal { jtj, jtj_inv }))
}

/// A Jacobian's normal matrix JᵀJ and its inverse.
struct Normal {
    jtj: DMatrix<f64>,
    jtj_inv: DMatrix<f64>,
}

/// Gauss–Newton on Γ (on `axes`) and the nuisance parameters `spec` asks
/// for, from `fed0`, the series as `settings`' loop fed it, and the offset
/// as `start` says. Without
/// `covariance` the sandwich is left out (its matrices NaN): the parameters
/// and the RSS are the same.
fn solve(
    series: &EpochSeries,
    settings: &EstimateSettings,
    spec: JointSpec,
    axes: &[usize],
    fed0: Cow<'_, [FedEpoch]>,
    start: Start,
    covariance: bool,
) -> Result<Solution, CalibError> {
    solve_with_residuals(series, settings, (spec, axes), fed0, start, covariance).map(|(sol, _)| sol)
}

/// The residuals of a solved joint fit: the epochs fitted (indices into the
/// series) and φ − Jβ at each \[rad\].
struct Residuals {
    used: Vec<usize>,
    rad: DVector<f64>,
}

/// [`solve`], with the fit's residuals.
fn solve_with_residuals(
    series: &EpochSeries,
    settings: &EstimateSettings,
    (spec, axes): (JointSpec, &[usize]),
    fed0: Cow<'_, [FedEpoch]>,
    start: Start,
    covariance: bool,
) -> Result<(Solution, Residuals), CalibError> {
    let (problem, mut theta) = Problem::new(series, settings, (spec, axes), &fed0, start)?;
    let fitted = problem.fitted;
    let y = DVector::from_column_slice(&problem.phi);
    let mut iterations = 0;
    let (jac, resid, gamma, normal) = loop {
        iterations += 1;
        let jac = problem.jacobian(&fed0, &theta)?;
        let (beta, converged, normal) = gauss_newton_step(&jac, &y, &fitted)?;
        let step = Theta::limited_step(&fitted.read(beta.as_slice()), spec.offset_max_abs_s);
        theta = theta.advanced(&step, spec.offset_max_abs_s);
        // Converged (steps far below any σ) or out of iterations: Γ at the
        // final θ and the Jacobian there give the covariance.
        if converged || iterations >= MAX_ITERATIONS || !fitted.any_nuisance() {
            let resid = &y - &jac * &beta;
            let mut gamma = [0.0; 3];
            for (&i, g) in axes.iter().zip(&step.gamma) {
                gamma[i] = *g;
            }
            break (jac, resid, gamma, normal);
        }
    };
    let gamma_stated = if fitted.natural_frequency || fitted.damping {
        let by = Shift::samples(theta.dtau_s / series.log_interval_s);
        let mut ne = gsens_core::NormalEquations::default();
        for (&k, pk) in problem.used.iter().zip(&problem.phi) {
            ne.add(*pk, &shifted(&fed0, k, theta.dtau_s, &by));
        }
        ne.solve().gamma_hz_per_mps2
    } else {
        gamma
    };
    let (p, na) = (fitted.len(), fitted.axes);
    let (cov, cov3) = if covariance {
        sandwich_covariance(&jac, &normal, &resid, &problem.used, fed0.len(), series.log_interval_s, na)
    } else {
        (DMatrix::from_element(p, p, f64::NAN), DMatrix::from_element(na, na, f64::NAN))
    };
    let solution = Solution {
        gamma,
        gamma_stated,
        theta,
        cov,
        cov3,
        fitted,
        rss_rad2: resid.norm_squared(),
        epochs: problem.used.len(),
        iterations,
    };
    Ok((solution, Residuals { used: problem.used, rad: resid }))
}

/// The least-squares sandwich (JᵀJ)⁻¹·JᵀΣJ·(JᵀJ)⁻¹ of the Jacobian `jac`
/// (rows: the `used` epochs of a series of `n`, log interval `t`; `normal`
/// its JᵀJ and inverse), Σ the autocovariance of an AR model of the
/// residuals `resid` over the used epochs' contiguous runs; and the same
/// sandwich on the first `na` (Γ) columns alone, Γ's covariance with θ known.
fn sandwich_covariance(
    jac: &DMatrix<f64>,
    normal: &Normal,
    resid: &DVector<f64>,
    used: &[usize],
    n: usize,
    t: f64,
    na: usize,
) -> (DMatrix<f64>, DMatrix<f64>) {
    let p = jac.ncols();
    let mut mask = vec![false; n];
    for &k in used {
        mask[k] = true;
    }
    let segments = gls::segments_of(mask.iter().copied());
    let mut full_resid = vec![0.0; n];
    for (r, &k) in used.iter().enumerate() {
        full_resid[k] = resid[r];
    }
    let slices: Vec<&[f64]> = segments.iter().map(|s| &full_resid[s.clone()]).collect();
    let max_order = ((gls::MAX_AR_SPAN_S / t).ceil() as usize).min(used.len() / 20).max(1);
    let full_columns: Vec<Vec<f64>> = (0..p)
        .into_par_iter()
        .map(|c| {
            let mut v = vec![0.0; n];
            for (&x, &k) in jac.column(c).iter().zip(used) {
                v[k] = x;
            }
            v
        })
        .collect();
    // The columns' transforms do not need the noise model: they are computed
    // while it is fitted.
    let (noise, spectra) =
        rayon::join(|| gls::fit_ar(&slices, max_order), || gls::ColumnSpectra::new(&full_columns, &segments));
    let middle = spectra.middle(&noise);
    // A singular normal matrix leaves σ undefined (NaN), never 0: the axes
    // then come out unobservable (`Calibration::include_nuisance`).
    let cov = &normal.jtj_inv * &middle * &normal.jtj_inv;
    // The Γ columns' normal matrix is the leading block of JᵀJ (the same
    // dot products of the same columns).
    let a3_inv = normal
        .jtj
        .view((0, 0), (na, na))
        .into_owned()
        .try_inverse()
        .unwrap_or_else(|| DMatrix::from_element(na, na, f64::NAN));
    // Entry (i, j) of the middle depends on columns i and j alone: the Γ
    // columns' middle is the leading block of the joint one.
    let middle3 = middle.view((0, 0), (na, na)).into_owned();
    let cov3 = &a3_inv * middle3 * &a3_inv;
    (cov, cov3)
}

/// What the loop test and the linearity check of a solution rest on.
struct LoopEvidence {
    /// The free fit's ln ŝ and its variance (the loop test's).
    data: Option<(f64, f64)>,
    /// The prior's width the free fit was combined with.
    tolerance: Option<f64>,
    /// σ of the offset in the fit whose linearization the result rests on.
    linearization_sigma_tau_s: Option<f64>,
}

/// The [`JointFit`] of a solution with its [`LoopEvidence`].
fn describe(
    series: &EpochSeries,
    stated: &LoopModel,
    spec: JointSpec,
    axes: &[usize],
    sol: &Solution,
    evidence: LoopEvidence,
) -> JointFit {
    let LoopEvidence { data, tolerance, linearization_sigma_tau_s } = evidence;
    let cov = &sol.cov;
    let cov3 = &sol.cov3;
    // Row/column of axis i in the fit (None: left out as unobservable).
    let at = |i: usize| axes.iter().position(|&a| a == i);
    let variance_inflation = [0, 1, 2].map(|i| match at(i) {
        Some(k) if cov3[(k, k)] > 0.0 => (cov[(k, k)] / cov3[(k, k)]).max(1.0),
        _ => 1.0,
    });
    // No variance (a singular fit, or rounding below 0) is no σ: NaN, not 0.
    let sd = |i: usize| if cov[(i, i)] > 0.0 { cov[(i, i)].sqrt() } else { f64::NAN };
    let wn_stated = stated.natural_frequency_hz();
    let fitted_free = data.and_then(|(ln_s, _)| scaled_loop(stated, ln_s.exp(), sol.theta.zeta).natural_frequency_hz());
    let sigma_data_ln = data.map(|(_, v)| v.max(0.0).sqrt());
    let z = data.map(|(ln_s, v)| {
        let total = v.max(0.0) + tolerance.unwrap_or(0.0).powi(2);
        if total > 0.0 { ln_s / total.sqrt() } else { 0.0 }
    });
    // Without a tolerance nothing was claimed of the loop: there is nothing to reject.
    let rejected = tolerance.is_some() && z.is_some_and(|z| z.abs() > LOOP_TEST_Z);
    let used = scaled_loop(stated, sol.theta.ln_s.exp(), sol.theta.zeta);
    let fit_loop = sol.fitted.natural_frequency;
    let correlation = match (sol.fitted.loop_index(), sol.fitted.tau_index()) {
        (Some(l), Some(o)) if sd(l) > 0.0 && sd(o) > 0.0 => Some(cov[(l, o)] / (sd(l) * sd(o))),
        _ => None,
    };
    let offset_at_limit = spec.offset_max_abs_s.is_some_and(|m| sol.theta.dtau_s.abs() >= 0.999 * m);
    JointFit {
        stated_loop: stated.to_string(),
        fitted_loop: if fit_loop { used.to_string() } else { stated.to_string() },
        stated_natural_frequency_hz: fit_loop.then_some(wn_stated).flatten(),
        natural_frequency_hz: fitted_free,
        sigma_natural_frequency_hz: sigma_data_ln.zip(fitted_free).map(|(s, f)| s * f),
        bn_hz: used.bn_hz(),
        stated_zeta: sol.fitted.zeta_index().and_then(|_| zeta_of(stated)),
        zeta: sol.fitted.zeta_index().and_then(|i| sol.theta.zeta.map(|z| [z, sd(i)])),
        loop_test_z: z,
        loop_test_threshold_z: LOOP_TEST_Z,
        loop_test_false_alarm: LOOP_TEST_FALSE_ALARM,
        stated_loop_rejected: rejected,
        loop_tolerance: tolerance,
        used_natural_frequency_hz: fit_loop.then(|| used.natural_frequency_hz()).flatten(),
        // 0 for a loop held exact (a tolerance of 0).
        sigma_used_natural_frequency_hz: sol
            .fitted
            .loop_index()
            .zip(used.natural_frequency_hz())
            .map(|(l, f)| cov[(l, l)].max(0.0).sqrt() * f),
        imu_time_offset_s: spec.offset_max_abs_s.map(|_| series.imu_time_offset_s + sol.theta.dtau_s),
        sigma_imu_time_offset_s: sol.fitted.tau_index().map(sd),
        linearization_sigma_imu_time_offset_s: linearization_sigma_tau_s,
        offset_max_abs_s: spec.offset_max_abs_s,
        offset_at_limit,
        correlation_loop_offset: correlation,
        gamma_hz_per_mps2: sol.gamma,
        gamma_stated_loop_hz_per_mps2: sol.gamma_stated,
        variance_inflation,
        fitted_loop_used: fit_loop && (sol.theta.ln_s != 0.0 || sol.theta.zeta != zeta_of(stated)),
        rss_rad2: sol.rss_rad2,
        epochs: sol.epochs,
        gamma_covariance_hz_per_mps2_sq: [0, 1, 2].map(|i| {
            [0, 1, 2].map(|j| match (at(i), at(j)) {
                (Some(k), Some(l)) => cov[(k, l)],
                _ => 0.0,
            })
        }),
        iterations: sol.iterations,
        loop_forms: None,
    }
}

impl JointFit {
    /// Takes in which form of the stated loop the fit is under: Γ̂'s
    /// variance on each axis grows by [`LoopForms::added_variance_hz_per_mps2_sq`]
    /// (its variance inflation with it), so that its σ reaches the Γ̂ of the
    /// forms the data cannot tell apart.
    pub(crate) fn cover_loop_forms(&mut self, forms: LoopForms) {
        for (i, add) in forms.added_variance_hz_per_mps2_sq.iter().enumerate() {
            let var = &mut self.gamma_covariance_hz_per_mps2_sq[i][i];
            if *var > 0.0 && var.is_finite() && *add > 0.0 {
                self.variance_inflation[i] *= (*var + add) / *var;
                *var += add;
            }
        }
        self.loop_forms = Some(forms);
    }

    /// The loop Γ̂ is given under, given the stated one: the stated loop
    /// scaled to [`used_natural_frequency_hz`](Self::used_natural_frequency_hz)
    /// (with the fitted damping), or the stated loop itself when the fit kept it.
    pub fn fitted(&self, stated: &LoopModel) -> LoopModel {
        if !self.fitted_loop_used {
            return *stated;
        }
        match (self.used_natural_frequency_hz, self.stated_natural_frequency_hz) {
            (Some(f), Some(f0)) => scaled_loop(stated, f / f0, self.zeta.map(|z| z[0]).or(zeta_of(stated))),
            _ => *stated,
        }
    }
}

/// The update intervals typical receivers run their carrier loop at \[s\]:
/// the C/A code period and its multiples up to a navigation bit.
pub const TYPICAL_LOOP_INTERVALS_S: [f64; 6] = [0.001, 0.002, 0.004, 0.005, 0.01, 0.02];

/// A loop the data chose among typical receiver loops when none was stated.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ChosenLoop {
    /// The candidate that fits best (its natural frequency then fitted).
    pub model: LoopModel,
    /// What the log holds.
    pub logged_phase: gsens_core::LoggedPhase,
    /// Candidates tried.
    pub candidates: usize,
    /// RSS of the runner-up over the best's (≥ 1): near 1 the data hardly
    /// tell them apart.
    pub runner_up_rss_ratio: f64,
    /// The runner-up, in words.
    pub runner_up: String,
}

/// Chooses the receiver loop when none was stated: every order (2nd with
/// ζ = 1/√2, 3rd with Kaplan's a3, b3), update interval among
/// [`TYPICAL_LOOP_INTERVALS_S`] that divide the log interval (and the log
/// interval itself) and logged phase (last or mean), each with its natural
/// frequency fitted jointly with Γ from `settings.receiver_loop`'s bandwidth;
/// the smallest residual wins. The discrete choices are not tested with a
/// stated false-alarm rate, so the caller must say the loop was chosen, not
/// checked.
///
/// Every candidate is fitted on the whole series, the candidates in
/// parallel and without the covariance (the residual decides). Progress:
/// one step per candidate fitted, to the observer of `crate::progress`.
pub fn choose_loop(
    series: &EpochSeries,
    settings: &EstimateSettings,
    offset_max_abs_s: Option<f64>,
) -> Result<ChosenLoop, CalibError> {
    let t = series.log_interval_s;
    let bn_hz = settings.receiver_loop.bn_hz().unwrap_or(crate::defaults::DEFAULT_BN_HZ);
    let mut intervals: Vec<f64> = TYPICAL_LOOP_INTERVALS_S
        .iter()
        .copied()
        .filter(|&i| i < t * (1.0 - 1e-9) && ((t / i) - (t / i).round()).abs() < 1e-6)
        .collect();
    intervals.push(t);
    let spec = JointSpec { natural_frequency: true, damping: false, offset_max_abs_s, loop_tolerance: None };
    let mut candidates: Vec<EstimateSettings> = Vec::new();
    for order in [2u8, 3] {
        let Ok(loop_spec) = LoopSpec::of_order(
            order,
            bn_hz,
            core::f64::consts::FRAC_1_SQRT_2,
            gsens_core::KAPLAN_A3,
            gsens_core::KAPLAN_B3,
        ) else {
            continue;
        };
        for &interval in &intervals {
            let logged: &[gsens_core::LoggedPhase] = if interval < t {
                &[gsens_core::LoggedPhase::Last, gsens_core::LoggedPhase::Mean]
            } else {
                &[gsens_core::LoggedPhase::Last]
            };
            for &lp in logged {
                let mut s = *settings;
                s.receiver_loop = LoopModel::kaplan(loop_spec, Some(interval));
                s.logged_phase = lp;
                candidates.push(s);
            }
        }
    }
    let progress = crate::progress::current();
    crate::progress::stage("choosing the receiver loop", Some(candidates.len() as u64));
    // Each candidate's RSS and fitted loop (None: not fitted), in the candidates' order.
    let fits: Vec<Option<(f64, LoopModel)>> = candidates
        .par_iter()
        .map(|candidate| {
            let fit = candidate_fit(series, candidate, spec).ok();
            if let Some(p) = &progress {
                p.step();
            }
            fit
        })
        .collect();
    let mut tried: Vec<(f64, LoopModel, gsens_core::LoggedPhase)> =
        candidates.iter().zip(fits).filter_map(|(c, f)| f.map(|(rss, model)| (rss, model, c.logged_phase))).collect();
    let candidates_tried = tried.len();
    tried.sort_by(|a, b| a.0.total_cmp(&b.0));
    let Some(best) = tried.first().cloned() else {
        return Err(CalibError::Unsupported("no typical receiver loop could be fitted to the data"));
    };
    let runner = tried.get(1);
    Ok(ChosenLoop {
        model: best.1,
        logged_phase: best.2,
        candidates: candidates_tried,
        runner_up_rss_ratio: runner.map_or(f64::INFINITY, |r| r.0 / best.0),
        runner_up: runner
            .map(|r| {
                let logged = if r.2 == gsens_core::LoggedPhase::Mean { "the mean" } else { "the last output" };
                format!("{} with the log holding {logged}", r.1)
            })
            .unwrap_or_default(),
    })
}

/// The free joint fit (no tolerance) from the stated loop's pass `fed0`
/// on `axes`; without `covariance` its σ's are NaN (the
/// parameters and the RSS are the same).
fn free_fit(
    series: &EpochSeries,
    settings: &EstimateSettings,
    (spec, axes): (JointSpec, &[usize]),
    fed0: Vec<FedEpoch>,
    start: Start,
    covariance: bool,
) -> Result<JointFit, CalibError> {
    let stated = settings.loop_at(series.log_interval_s);
    let free = solve(series, settings, spec, axes, Cow::Owned(fed0), start, covariance)?;
    let data = free.ln_s_and_variance();
    let evidence = LoopEvidence { data, tolerance: None, linearization_sigma_tau_s: free.sigma_tau_s() };
    Ok(describe(series, &stated, spec, axes, &free, evidence))
}

/// A candidate loop's free joint fit without its covariance: the RSS and the
/// loop fitted, as [`JointFit::rss_rad2`] and [`JointFit::fitted`] of
/// [`joint_fit`] give them.
fn candidate_fit(
    series: &EpochSeries,
    settings: &EstimateSettings,
    spec: JointSpec,
) -> Result<(f64, LoopModel), CalibError> {
    let (fed0, ne) = batch_pass(series, settings)?;
    let fit = free_fit(series, settings, (spec, &fit_axes(&ne, settings)), fed0, Start::Search, false)?;
    Ok((fit.rss_rad2, fit.fitted(&settings.loop_at(series.log_interval_s))))
}

#[cfg(test)]
mod tests {
    use super::*;
    use gsens_core::DiscretePll;
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};

    /// JᵀJ and Jᵀy formed entry by entry in parallel are nalgebra's
    /// products bit for bit, on pools of 1, 2, 4 and 5 threads.
    #[test]
    fn normal_products_are_nalgebras_on_any_pool() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(11);
        let noise = Normal::new(0.0, 1.0).unwrap();
        let (n, p) = (10_007, 5);
        let jac = DMatrix::from_fn(n, p, |_, c| noise.sample(&mut rng) * (c + 1) as f64);
        let y = DVector::from_fn(n, |_, _| noise.sample(&mut rng));
        let bits = |m: &DMatrix<f64>| m.iter().map(|v| v.to_bits()).collect::<Vec<u64>>();
        for threads in [1, 2, 4, 5] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            let (g, b) = pool.install(|| (gram(&jac), tr_mul_vector(&jac, &y)));
            assert_eq!(bits(&g), bits(&jac.tr_mul(&jac)), "{threads} threads");
            assert_eq!(
                b.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
                jac.tr_mul(&y).iter().map(|v| v.to_bits()).collect::<Vec<_>>()
            );
        }
    }

    /// 400 s at 40 Hz of the paper's loop run at the log rate, driven by
    /// Δf = aᵀΓ with x, y, z shaken in turn for 20 s each at 0.9 Hz, white
    /// phase noise: (t, φ, a).
    fn long_session() -> (Vec<f64>, Vec<Option<f64>>, Vec<[f64; 3]>) {
        let t_log = 0.025;
        let gamma = [0.09, 0.08, -0.08];
        let mut pll = DiscretePll::new(LoopSpec::PAPER.coeffs().expect("a valid loop"), t_log);
        pll.settle(9.80665 * gamma[2]);
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(4);
        let noise = Normal::new(0.0, 0.02).expect("a valid σ");
        let (mut t_s, mut phase, mut accel) = (Vec::new(), Vec::new(), Vec::new());
        for k in 0..16_000 {
            let t = k as f64 * t_log;
            let mut a = [0.0, 0.0, 9.80665];
            let axis = ((t / 20.0) as usize) % 4;
            if axis < 3 {
                a[axis] += 3.0 * (core::f64::consts::TAU * 0.9 * t).sin();
            }
            let phi = pll.step((0..3).map(|i| a[i] * gamma[i]).sum());
            t_s.push(t);
            phase.push(Some(phi + noise.sample(&mut rng)));
            accel.push(a);
        }
        (t_s, phase, accel)
    }

    /// The search finds the session's loop (the paper's, run at the log rate)
    /// among the typical ones.
    #[test]
    fn the_search_finds_the_sessions_loop() {
        let (t_s, phase, accel) = long_session();
        let series = EpochSeries::without_offset(0.025, &t_s, &phase, &accel);
        let chosen = choose_loop(&series, &EstimateSettings::default(), Some(0.1)).unwrap();
        assert_eq!(chosen.model.interval_s(), Some(0.025), "{}", chosen.model);
        assert_eq!(chosen.model.order(), 2, "{}", chosen.model);
        assert_eq!(chosen.logged_phase, gsens_core::LoggedPhase::Last);
        assert!(chosen.runner_up_rss_ratio >= 1.0, "{}", chosen.runner_up_rss_ratio);
    }
}
