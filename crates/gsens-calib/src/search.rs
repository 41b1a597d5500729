//! Systematic errors estimated jointly with Γ: the IMU/tracking time offset
//! and the receiver loop's natural frequency and damping.
//!
//! Both minimize the residual sum of squares of the batch fit,
//! RSS(p) = min_Γ Σ (φ_k − φ_a,k(p)ᵀΓ)², over the nuisance parameter p (a
//! variable-projection estimate: Γ is eliminated in closed form for each p).
//!
//! - Time offset τ (IMU stamp minus true time): the loop model and the
//!   high-pass are time-invariant, so φ_a for an offset τ is the φ_a series at
//!   τ = 0 shifted by τ. The shift is evaluated by cubic (Catmull–Rom)
//!   interpolation of that series (φ_a is band-limited by the loop to a few Hz,
//!   far below the log rate), so the search costs one loop-model pass.
//! - Loop: every candidate (ωn, ζ) reruns the triad over the log.
//!
//! 1σ of a parameter comes from the curvature of the RSS at its minimum:
//! σ_p² = 2σ̂²/RSS''(p̂), σ̂² = RSS(p̂)/(n − 3) (Gaussian-noise Fisher
//! information; coloured residuals make it optimistic, as it is stated).

use crate::estimate::{build_model, model_input};
use crate::{CalibError, EpochSeries, EstimateSettings};
use gsens_core::Calibrator;
use gsens_core::FedEpoch;
use gsens_core::LoopModel;
use gsens_core::LoopSpec;
use gsens_core::{BatchLeastSquares, NormalEquations};
use serde::{Deserialize, Serialize};

/// Runs the batch estimator over the series; returns every epoch as fed
/// (high-passed φ and φ_a, used or not) and the normal equations.
pub(crate) fn batch_pass(
    series: &EpochSeries,
    settings: &EstimateSettings,
) -> Result<(Vec<FedEpoch>, NormalEquations), CalibError> {
    let model = build_model(series.log_interval_s, settings)?;
    let accel = model_input(series.accel_mps2, &model);
    let skip = (settings.warmup_s / series.log_interval_s).ceil().max(0.0) as u64;
    let mut cal = Calibrator::new(model, BatchLeastSquares::new(), skip, settings.highpass_hz, series.log_interval_s);
    let fed: Vec<FedEpoch> = accel.iter().zip(series.phase_err_rad).map(|(a, p)| cal.feed(a, *p)).collect();
    Ok((fed, *cal.estimator().normal_equations()))
}

/// RSS of the least-squares fit from normal equations: φᵀφ − bᵀ(AᵀA)⁺b.
fn rss(normal: &NormalEquations) -> f64 {
    normal.rss(&{
        let (pinv, _) = normal.pseudo_inverse(gsens_core::RANK_TOL);
        pinv * normal.atb
    })
}

/// Catmull–Rom interpolation of a uniformly sampled series at fractional index `x`.
fn catmull_rom(y: &[[f64; 3]], x: f64) -> [f64; 3] {
    let n = y.len() as isize;
    let i = x.floor() as isize;
    let u = x - i as f64;
    let at = |k: isize| y[k.clamp(0, n - 1) as usize];
    let (p0, p1, p2, p3) = (at(i - 1), at(i), at(i + 1), at(i + 2));
    let (u2, u3) = (u * u, u * u * u);
    [0, 1, 2].map(|c| {
        0.5 * (2.0 * p1[c]
            + (-p0[c] + p2[c]) * u
            + (2.0 * p0[c] - 5.0 * p1[c] + 4.0 * p2[c] - p3[c]) * u2
            + (-p0[c] + 3.0 * p1[c] - 3.0 * p2[c] + p3[c]) * u3)
    })
}

/// Golden-section minimization of `f` on \[a, b\].
fn golden(mut a: f64, mut b: f64, tol: f64, mut f: impl FnMut(f64) -> f64) -> f64 {
    let r = (5f64.sqrt() - 1.0) / 2.0;
    let mut x1 = b - r * (b - a);
    let mut x2 = a + r * (b - a);
    let (mut f1, mut f2) = (f(x1), f(x2));
    while b - a > tol {
        if f1 < f2 {
            b = x2;
            x2 = x1;
            f2 = f1;
            x1 = b - r * (b - a);
            f1 = f(x1);
        } else {
            a = x1;
            x1 = x2;
            f1 = f2;
            x2 = a + r * (b - a);
            f2 = f(x2);
        }
    }
    0.5 * (a + b)
}

/// Grid search then golden-section refinement of `f` on \[lo, hi\]; returns the
/// minimizer and the curvature f'' there (central differences at step `h`).
fn minimize_1d(lo: f64, hi: f64, grid: usize, tol: f64, h: f64, mut f: impl FnMut(f64) -> f64) -> (f64, f64) {
    let step = (hi - lo) / grid as f64;
    let (mut best_x, mut best_f) = (lo, f64::INFINITY);
    for i in 0..=grid {
        let x = lo + i as f64 * step;
        let v = f(x);
        if v < best_f {
            best_f = v;
            best_x = x;
        }
    }
    let x = golden((best_x - step).max(lo), (best_x + step).min(hi), tol, &mut f);
    let (fm, f0, fp) = (f(x - h), f(x), f(x + h));
    (x, (fp - 2.0 * f0 + fm) / (h * h))
}

/// The estimated IMU time offset.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TimeOffsetEstimate {
    /// IMU time stamp minus true time \[s\], in total (the assumed offset of the
    /// series plus the correction found).
    pub imu_time_offset_s: f64,
    /// 1σ \[s\] from the curvature of the RSS.
    pub sigma_s: f64,
    /// Search range ± \[s\].
    pub max_abs_s: f64,
    /// RSS at the assumed offset over RSS at the estimate (≥ 1).
    pub rss_ratio: f64,
}

/// The profile of the RSS over the time-offset correction δτ for one batch pass.
struct OffsetProfile {
    dtau_s: f64,
    curvature: f64,
    rss_min: f64,
    rss_zero: f64,
    epochs: usize,
}

fn offset_profile(fed: &[FedEpoch], t: f64, max_abs_s: f64) -> Result<OffsetProfile, CalibError> {
    let margin = (max_abs_s / t).ceil() as usize + 2;
    let phi_a: Vec<[f64; 3]> = fed.iter().map(|e| e.phi_a).collect();
    let mut used: Vec<usize> =
        (margin..fed.len().saturating_sub(margin)).filter(|&k| fed[k].used && fed[k].phase_err_rad.is_some()).collect();
    if used.len() < 10 {
        return Err(CalibError::TooShortForOffsetSearch { max_abs_s, epochs: used.len() });
    }
    // Long logs: a regular subset of at most 40 000 epochs pins τ as well.
    let stride = used.len().div_ceil(40_000).max(1);
    if stride > 1 {
        used = used.into_iter().step_by(stride).collect();
    }
    // φ_a at true time t_k comes from the IMU at stamp t_k + τ: a shift of +τ/T samples.
    let rss_at = |dtau: f64| {
        let mut ne = NormalEquations::default();
        for &k in &used {
            let v = catmull_rom(&phi_a, k as f64 + dtau / t);
            ne.add(fed[k].phase_err_rad.unwrap_or(0.0), &v);
        }
        rss(&ne)
    };
    let grid = ((2.0 * max_abs_s / (0.25 * t)).ceil() as usize).max(8);
    let (dtau_s, curvature) = minimize_1d(-max_abs_s, max_abs_s, grid, 1e-5, 0.1 * t, rss_at);
    Ok(OffsetProfile { dtau_s, curvature, rss_min: rss_at(dtau_s), rss_zero: rss_at(0.0), epochs: used.len() })
}

/// Estimates the IMU time offset jointly with Γ within ±`max_abs_s` of the
/// offset the series was built with (`series.imu_time_offset_s`). Epochs within
/// `max_abs_s` of either end are left out of the search (their shifted φ_a
/// would need data outside the log).
pub fn estimate_time_offset(
    series: &EpochSeries,
    settings: &EstimateSettings,
    max_abs_s: f64,
) -> Result<TimeOffsetEstimate, CalibError> {
    let (fed, _) = batch_pass(series, settings)?;
    let p = offset_profile(&fed, series.log_interval_s, max_abs_s)?;
    let s2 = p.rss_min / (p.epochs as f64 - 4.0);
    Ok(TimeOffsetEstimate {
        imu_time_offset_s: series.imu_time_offset_s + p.dtau_s,
        sigma_s: if p.curvature > 0.0 { (2.0 * s2 / p.curvature).sqrt() } else { f64::INFINITY },
        max_abs_s,
        rss_ratio: p.rss_zero / p.rss_min,
    })
}

/// The result of identifying the receiver loop from the data.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct LoopIdentification {
    /// Natural frequency of the assumed loop, ωn/2π \[Hz\].
    pub assumed_natural_frequency_hz: f64,
    /// Damping of the assumed loop (2nd order).
    pub assumed_zeta: Option<f64>,
    /// Identified natural frequency \[Hz\].
    pub natural_frequency_hz: f64,
    /// Its 1σ \[Hz\].
    pub sigma_natural_frequency_hz: f64,
    /// Identified damping (2nd order; 3rd-order loops keep their a3, b3).
    pub zeta: Option<f64>,
    /// Identified noise bandwidth Bn \[Hz\].
    pub bn_hz: f64,
    /// RSS with the assumed loop over RSS with the identified one.
    pub rss_ratio: f64,
    /// The likelihood-ratio statistic (n−3)·ln(RSS_assumed/RSS_identified),
    /// χ²-distributed with 1–2 degrees of freedom when the assumed loop is right.
    pub likelihood_ratio: f64,
    /// Whether the data reject the assumed loop (likelihood ratio above the
    /// 0.1 % point of χ², i.e. > 13.8): then the identified loop is used.
    pub assumed_loop_rejected: bool,
    /// Relative change of each Γ̂ component per +1 % of ωn, at the identified loop
    /// (at a fixed time offset).
    pub gamma_sensitivity_per_percent_wn: [f64; 3],
    /// The IMU time offset found jointly with the identified loop \[s\] (total).
    pub imu_time_offset_s: Option<f64>,
}

/// The loop with natural frequency scaled by `scale` and, for a 2nd-order
/// loop, damping `zeta` (GNSS-SDR's loops: their bandwidth scaled).
fn scaled_loop(model: &LoopModel, scale: f64, zeta: Option<f64>) -> LoopModel {
    match *model {
        LoopModel::Kaplan { spec, interval_s } => LoopModel::kaplan(scaled_spec(&spec, scale, zeta), interval_s),
        LoopModel::GnssSdr(stage) => {
            LoopModel::GnssSdr(gsens_core::gnss_sdr::GnssSdrStage { bw_hz: stage.bw_hz * scale, ..stage })
        }
        other => other,
    }
}

fn scaled_spec(spec: &LoopSpec, scale: f64, zeta: Option<f64>) -> LoopSpec {
    match *spec {
        LoopSpec::SecondOrder { bn_hz, zeta: z0 } => {
            let z = zeta.unwrap_or(z0);
            let wn = gsens_core::second_order_wn_from_bn(bn_hz, z0) * scale;
            LoopSpec::SecondOrder { bn_hz: gsens_core::second_order_bn_from_wn(wn, z), zeta: z }
        }
        LoopSpec::ThirdOrder { bn_hz, a3, b3 } => LoopSpec::ThirdOrder { bn_hz: bn_hz * scale, a3, b3 },
        LoopSpec::Coefficients(c) => LoopSpec::Coefficients(gsens_core::LoopFilterCoeffs {
            c0_per_s: c.c0_per_s * scale,
            c1_per_s2: c.c1_per_s2 * scale * scale,
            c2_per_s3: c.c2_per_s3 * scale * scale * scale,
        }),
    }
}

/// Identifies the loop's natural frequency (and, with `identify_damping`, a
/// 2nd-order loop's damping) jointly with Γ, over ωn within ×/÷ 2 of the
/// assumed one and ζ in 0.3…1.5.
///
/// Shaking near one frequency pins |L| and arg L there, and |L| trades off
/// against |Γ|: ωn is identified by the phase of the response, ζ only weakly
/// (by the spread of shaking frequencies). Receivers set ζ by design (0.707)
/// while their effective bandwidth is what drifts from its nominal value, so
/// ζ is kept unless asked for.
///
/// With `offset_search_s` = Some(max), the IMU time offset is profiled out for
/// every candidate loop (a loop's phase error at the shaking frequency mimics
/// a time offset, so the two must be searched together); the offset found
/// with the identified loop is in [`LoopIdentification::imu_time_offset_s`].
pub fn identify_loop(
    series: &EpochSeries,
    settings: &EstimateSettings,
    identify_damping: bool,
    offset_search_s: Option<f64>,
) -> Result<LoopIdentification, CalibError> {
    let loop0 = settings.receiver_loop;
    let wn0 = loop0.natural_frequency_hz().ok_or(CalibError::NoNaturalFrequency)? * core::f64::consts::TAU;
    let zeta0 = match loop0 {
        LoopModel::Kaplan { spec: LoopSpec::SecondOrder { zeta, .. }, .. } => Some(zeta),
        _ => None,
    };
    let eval = |scale: f64, zeta: Option<f64>| -> Result<(f64, NormalEquations, f64), CalibError> {
        let mut s = *settings;
        s.receiver_loop = scaled_loop(&loop0, scale, zeta);
        let (fed, ne) = batch_pass(series, &s)?;
        match offset_search_s {
            None => Ok((rss(&ne), ne, 0.0)),
            Some(max) => {
                let p = offset_profile(&fed, series.log_interval_s, max)?;
                Ok((p.rss_min, ne, p.dtau_s))
            }
        }
    };
    let cost = |scale: f64, zeta: Option<f64>| eval(scale, zeta).map(|r| r.0).unwrap_or(f64::INFINITY);
    // Alternate 1-D searches over ln(scale) and ζ (the RSS bowl is smooth).
    let mut ln_scale = 0.0f64;
    let mut zeta = zeta0;
    let rounds = if identify_damping && zeta0.is_some() { 3 } else { 1 };
    for _ in 0..rounds {
        let z = zeta;
        let (x, _) = minimize_1d(-0.7, 0.7, 14, 1e-4, 1e-3, |x| cost(x.exp(), z));
        ln_scale = x;
        if zeta.is_some() && identify_damping {
            let s = ln_scale.exp();
            let (zz, _) = minimize_1d(0.3, 1.5, 12, 1e-4, 1e-3, |zz| cost(s, Some(zz)));
            zeta = Some(zz);
        }
    }
    let h = 2e-3;
    let (_, curv) = {
        let z = zeta;
        let f = |x: f64| cost(x.exp(), z);
        let (fm, f0, fp) = (f(ln_scale - h), f(ln_scale), f(ln_scale + h));
        (f0, (fp - 2.0 * f0 + fm) / (h * h))
    };
    let (rss_id, ne_id, dtau_id) = eval(ln_scale.exp(), zeta)?;
    let (rss_assumed, _, _) = eval(1.0, zeta0)?;
    let n = ne_id.n as f64;
    let s2 = rss_id / (n - 5.0).max(1.0);
    let sigma_ln = if curv > 0.0 { (2.0 * s2 / curv).sqrt() } else { f64::INFINITY };
    let wn = wn0 * ln_scale.exp();
    let lr = (n - 3.0) * (rss_assumed / rss_id).ln();
    // Sensitivity of Γ̂ to ωn at the identified loop: ±1 % finite difference.
    let gamma_at = |scale: f64| -> Result<[f64; 3], CalibError> {
        let (_, ne, _) = eval(scale, zeta)?;
        Ok(ne.solve().gamma_hz_per_mps2)
    };
    let (gp, gm) = (gamma_at(ln_scale.exp() * 1.01)?, gamma_at(ln_scale.exp() / 1.01)?);
    let g0 = ne_id.solve().gamma_hz_per_mps2;
    let sens = [0, 1, 2].map(|i| if g0[i] != 0.0 { (gp[i] - gm[i]) / (2.0 * g0[i]) } else { 0.0 });
    let identified = scaled_loop(&loop0, ln_scale.exp(), zeta);
    Ok(LoopIdentification {
        assumed_natural_frequency_hz: wn0 / core::f64::consts::TAU,
        assumed_zeta: zeta0,
        natural_frequency_hz: wn / core::f64::consts::TAU,
        sigma_natural_frequency_hz: wn * sigma_ln / core::f64::consts::TAU,
        zeta,
        bn_hz: identified.bn_hz().unwrap_or(f64::NAN),
        rss_ratio: rss_assumed / rss_id,
        likelihood_ratio: lr,
        assumed_loop_rejected: lr > 13.8,
        gamma_sensitivity_per_percent_wn: sens,
        imu_time_offset_s: offset_search_s.map(|_| series.imu_time_offset_s + dtau_id),
    })
}

impl LoopIdentification {
    /// The identified loop, given the assumed one.
    pub fn identified(&self, assumed: &LoopModel) -> LoopModel {
        let scale = self.natural_frequency_hz / self.assumed_natural_frequency_hz;
        scaled_loop(assumed, scale, self.zeta)
    }
}
