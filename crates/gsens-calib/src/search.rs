//! The pieces the joint fit ([`crate::joint_fit`]) is built of: the batch
//! pass that feeds every epoch through the loop models, the global search of
//! the IMU time offset that starts it, and the stated loop scaled.
//!
//! The time offset τ (IMU stamp minus true time): the loop model and the
//! high-pass are time-invariant, so φ_a for an offset τ is the φ_a series at
//! τ = 0 shifted by τ. The shift is evaluated by cubic (Catmull–Rom)
//! interpolation of that series (φ_a is band-limited by the loop to a few Hz,
//! far below the log rate), so the search costs one loop-model pass: the
//! residual sum of squares min_Γ Σ (φ_k − φ_a,k(τ)ᵀΓ)² over a grid of τ, refined
//! by golden section (a variable-projection estimate: Γ is eliminated in
//! closed form for each τ).

use crate::estimate::{build_model, model_input};
use crate::{CalibError, EpochSeries, EstimateSettings};
use gsens_core::Calibrator;
use gsens_core::FedEpoch;
use gsens_core::LoopModel;
use gsens_core::LoopSpec;
use gsens_core::{BatchLeastSquares, NormalEquations};

/// Runs the batch estimator over the series; returns every epoch as fed
/// (high-passed φ and φ_a, used or not) and the normal equations.
pub(crate) fn batch_pass(
    series: &EpochSeries,
    settings: &EstimateSettings,
) -> Result<(Vec<FedEpoch>, NormalEquations), CalibError> {
    let model = build_model(series.log_interval_s, settings)?;
    let accel = model_input(series.accel_mps2, &model);
    let skip = crate::estimate::warmup_epochs(settings, series.log_interval_s);
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
pub(crate) fn catmull_rom(y: &[[f64; 3]], x: f64) -> [f64; 3] {
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
/// minimizer. The grid's points are evaluated in parallel (each is a pass
/// over the log); the first smallest wins, as in a sequential scan.
fn minimize_1d(lo: f64, hi: f64, grid: usize, tol: f64, f: impl Fn(f64) -> f64 + Sync) -> f64 {
    use rayon::prelude::*;
    let step = (hi - lo) / grid as f64;
    let values: Vec<f64> = (0..=grid).into_par_iter().map(|i| f(lo + i as f64 * step)).collect();
    let (mut best_x, mut best_f) = (lo, f64::INFINITY);
    for (i, v) in values.into_iter().enumerate() {
        if v < best_f {
            best_f = v;
            best_x = lo + i as f64 * step;
        }
    }
    golden((best_x - step).max(lo), (best_x + step).min(hi), tol, &f)
}

/// The profile of the RSS over the time-offset correction δτ for one batch pass.
pub(crate) struct OffsetProfile {
    pub(crate) dtau_s: f64,
}

pub(crate) fn offset_profile(fed: &[FedEpoch], t: f64, max_abs_s: f64) -> Result<OffsetProfile, CalibError> {
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
    let dtau_s = minimize_1d(-max_abs_s, max_abs_s, grid, 1e-5, rss_at);
    Ok(OffsetProfile { dtau_s })
}

/// The loop with natural frequency scaled by `scale` and, for a 2nd-order
/// loop, damping `zeta` (GNSS-SDR's loops: their bandwidth scaled).
pub(crate) fn scaled_loop(model: &LoopModel, scale: f64, zeta: Option<f64>) -> LoopModel {
    // A new damping at the same ωn first, then every time constant scaled.
    let model = match (*model, zeta) {
        (LoopModel::Kaplan { spec: LoopSpec::SecondOrder { bn_hz, zeta: z0 }, interval_s }, Some(z)) => {
            let wn = gsens_core::second_order_wn_from_bn(bn_hz, z0);
            LoopModel::kaplan(
                LoopSpec::SecondOrder { bn_hz: gsens_core::second_order_bn_from_wn(wn, z), zeta: z },
                interval_s,
            )
        }
        (m, _) => m,
    };
    model.with_bn_scaled(scale)
}
