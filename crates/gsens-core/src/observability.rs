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
