use crate::estimator::{GammaEstimate, NormalEquations, RANK_TOL};
use crate::math::sqrt;
use nalgebra::SymmetricEigen;

/// Thresholds of the observability verdict.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct ObservabilityCriteria {
    /// Minimum unexplained excitation RMS √(S_i/n) \[rad/(Hz/(m/s²))\].
    /// Default 0.05: a 0.06 m/s² oscillation at the loop's peak sensitivity.
    pub min_excitation_rms: f64,
    /// Maximum 1σ of Γ̂_i \[Hz/(m/s²)\]. Default 0.01 (≈ 0.06 ppb/g at L1).
    pub max_sigma_hz_per_mps2: f64,
}

impl Default for ObservabilityCriteria {
    fn default() -> Self {
        ObservabilityCriteria { min_excitation_rms: 0.05, max_sigma_hz_per_mps2: 0.01 }
    }
}

/// The observability of each axis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Observability {
    /// Unexplained excitation RMS per axis √(S_i/n) \[rad/(Hz/(m/s²))\].
    pub excitation_rms: [f64; 3],
    /// Condition number λ_max/λ_min of AᵀA (+∞ when singular).
    pub condition_number: f64,
    /// The verdict per axis.
    pub observable: [bool; 3],
}

/// Judges each axis from the normal equations and the estimate's covariance.
///
/// Which axes of Γ the data can observe.
///
/// From the information matrix AᵀA = Σ φ_aφ_aᵀ: the excitation of axis i that
/// the other two axes cannot explain is the Schur complement
/// S_i = 1/\[(AᵀA)⁻¹\]_ii; its RMS per epoch, √(S_i/n) \[rad per Hz/(m/s²)\], is
/// the phase error a unit Γ_i leaves that no other axis can mimic. An axis is
/// observable when that excitation is above a floor and its 1σ is below a
/// ceiling; both thresholds are settings, reported with the verdict.
pub fn assess(normal: &NormalEquations, estimate: &GammaEstimate, criteria: &ObservabilityCriteria) -> Observability {
    let n = normal.n.max(1) as f64;
    let (pinv, rank) = normal.pseudo_inverse(RANK_TOL);
    let eig = SymmetricEigen::new(normal.ata);
    let max = eig.eigenvalues.iter().fold(0.0f64, |a, &b| a.max(b));
    let min = eig.eigenvalues.iter().fold(f64::INFINITY, |a, &b| a.min(b));
    let condition_number = if rank == 3 && min > 0.0 { max / min } else { f64::INFINITY };
    let sigma = estimate.sigma_hz_per_mps2();
    let mut excitation_rms = [0.0; 3];
    let mut observable = [false; 3];
    for i in 0..3 {
        let schur = if pinv[(i, i)] > 0.0 && sigma[i].is_finite() { 1.0 / pinv[(i, i)] } else { 0.0 };
        excitation_rms[i] = sqrt(schur / n);
        observable[i] = excitation_rms[i] >= criteria.min_excitation_rms
            && sigma[i].is_finite()
            && sigma[i] <= criteria.max_sigma_hz_per_mps2;
    }
    Observability { excitation_rms, condition_number, observable }
}

/// The axes that stay in the solve: first those whose own excitation, the
/// RMS of their φ_a column √(AᵀA_ii/n), reaches the observability floor
/// (an axis never shaken has almost none, and its small column, correlated
/// with a shaken one, would make the shaken one look unobservable too), then
/// of those the ones [`assess`] finds observable with only them
/// in the normal equations.
pub fn axes_in_solve(ne: &NormalEquations, criteria: &ObservabilityCriteria) -> [bool; 3] {
    let n = ne.n.max(1) as f64;
    let excited = [0, 1, 2].map(|i| sqrt((ne.ata[(i, i)] / n).max(0.0)) >= criteria.min_excitation_rms);
    let kept = only_axes(ne, excited);
    let obs = assess(&kept, &kept.solve(), criteria);
    [0, 1, 2].map(|i| excited[i] && obs.observable[i])
}

/// The normal equations with the columns of the axes not `kept` removed
/// (as if their specific force were zero: the model and the high-pass are
/// linear, so a zero input gives a zero column of φ_a).
fn only_axes(ne: &NormalEquations, kept: [bool; 3]) -> NormalEquations {
    let mut out = *ne;
    for i in (0..3).filter(|&i| !kept[i]) {
        for j in 0..3 {
            out.ata[(i, j)] = 0.0;
            out.ata[(j, i)] = 0.0;
        }
        out.atb[i] = 0.0;
    }
    out
}

/// The least-squares estimate from accumulated normal equations over the
/// axes the batch path keeps in its solve ([`axes_in_solve`]; `gsens_calib::calibrate`): an axis not
/// shaken leaves the solve (Γ̂ 0, variance +∞) instead of taking a share of
/// the shaken axes' information through its small, correlated column. The
/// streamed estimate's solve (`gsens_calib::streaming_calibrator`, the C
/// API's calibrator); returns the axes kept.
pub fn solve_in_observable_axes(ne: &NormalEquations, criteria: &ObservabilityCriteria) -> (GammaEstimate, [bool; 3]) {
    let kept = axes_in_solve(ne, criteria);
    let mut estimate = only_axes(ne, kept).solve();
    for i in (0..3).filter(|&i| !kept[i]) {
        estimate.gamma_hz_per_mps2[i] = 0.0;
        for j in 0..3 {
            estimate.covariance[i][j] = if i == j { f64::INFINITY } else { 0.0 };
            estimate.covariance[j][i] = if i == j { f64::INFINITY } else { 0.0 };
        }
    }
    (estimate, kept)
}
