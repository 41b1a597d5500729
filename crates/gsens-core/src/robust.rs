use crate::estimator::{NormalEquations, RANK_TOL, mark_unobservable, pseudo_inverse_sym};
use crate::math::abs;
use nalgebra::{Matrix3, Vector3};

/// Huber's ψ with threshold `c = k·scale`.
///
/// Huber's M-estimator pieces for a batch fit of φ = φ_aᵀΓ + n robust to
/// outliers: the weights of iteratively reweighted least squares and the
/// sandwich covariance (autocorrelation-robust, as
/// [`crate::estimator::hac_covariance`]).
///
/// Huber's estimator minimizes Σ ρ(r_k) with ρ(r) = r²/2 for |r| ≤ c and
/// c·|r| − c²/2 beyond: quadratic (least squares) for the bulk of the
/// residuals, linear for the outliers, so a few wild epochs pull Γ̂ by a
/// bounded amount. With c = 1.345·σ (σ the residuals' scale) it keeps 95 % of
/// the efficiency of least squares under Gaussian noise (Huber, *Robust
/// Statistics*, 1981). Its influence function ψ = ρ′ = clip(r, ±c) gives the
/// IRLS weights w = ψ(r)/r = min(1, c/|r|) and the sandwich covariance
/// `B⁻¹·S·B⁻¹`, `B = Σ ψ′(r_k)·φ_a,k φ_a,kᵀ`, `S` the (Bartlett-weighted)
/// autocovariance sum of the scores `ψ(r_k)·φ_a,k`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HuberWeights {
    /// The threshold c in the residuals' unit (rad): residuals beyond it count linearly.
    pub threshold: f64,
}

impl HuberWeights {
    /// The usual tuning constant: 95 % efficiency under Gaussian noise.
    pub const K_95: f64 = 1.345;

    /// Weights for residuals of scale `scale` (e.g. 1.4826·MAD) with tuning constant `k`.
    pub fn new(k: f64, scale: f64) -> Self {
        HuberWeights { threshold: k * scale }
    }

    /// ψ(r) = clip(r, ±c).
    #[inline]
    pub fn psi(&self, r: f64) -> f64 {
        r.clamp(-self.threshold, self.threshold)
    }

    /// ψ′(r): 1 inside the threshold, 0 beyond.
    #[inline]
    pub fn psi_prime(&self, r: f64) -> f64 {
        if abs(r) <= self.threshold { 1.0 } else { 0.0 }
    }

    /// The IRLS weight ψ(r)/r = min(1, c/|r|).
    #[inline]
    pub fn weight(&self, r: f64) -> f64 {
        let a = abs(r);
        if a <= self.threshold { 1.0 } else { self.threshold / a }
    }

    /// Adds an epoch to weighted normal equations (weight from the residual
    /// `residual_rad` of the current estimate).
    #[inline]
    pub fn add(&self, normal: &mut NormalEquations, phase_err_rad: f64, phi_a: &[f64; 3], residual_rad: f64) {
        let w = self.weight(residual_rad);
        let v = Vector3::new(phi_a[0], phi_a[1], phi_a[2]);
        normal.ata += v * v.transpose() * w;
        normal.atb += v * (w * phase_err_rad);
        normal.btb += w * phase_err_rad * phase_err_rad;
        normal.n += 1;
    }
}

/// Sandwich covariance `B⁺·S·B⁺` of an M-estimate: `bread` = B = Σ ψ′(r)·φ_aφ_aᵀ,
/// `scores[k]` = ψ(r_k), S = Σ_ℓ w_ℓ Σ_k (ψ_kφ_a,k)(ψ_{k−ℓ}φ_a,k−ℓ)ᵀ + transpose
/// (Bartlett weights w_ℓ = 1 − ℓ/(L+1), `max_lag` = L; L = 0: heteroscedasticity-robust only).
/// Axes along which `bread` is singular get +∞ variance.
pub fn sandwich_covariance(bread: &[[f64; 3]; 3], phi_a: &[[f64; 3]], scores: &[f64], max_lag: usize) -> [[f64; 3]; 3] {
    let n = phi_a.len().min(scores.len());
    let g = |k: usize| Vector3::from(phi_a[k]) * scores[k];
    let mut s = Matrix3::zeros();
    for k in 0..n {
        let gk = g(k);
        s += gk * gk.transpose();
    }
    for lag in 1..=max_lag.min(n.saturating_sub(1)) {
        let w = 1.0 - lag as f64 / (max_lag as f64 + 1.0);
        let mut gamma_l = Matrix3::zeros();
        for k in lag..n {
            gamma_l += g(k) * g(k - lag).transpose();
        }
        s += (gamma_l + gamma_l.transpose()) * w;
    }
    let bread = Matrix3::from_fn(|i, j| bread[i][j]);
    let (pinv, rank) = pseudo_inverse_sym(&bread, RANK_TOL);
    let mut cov = pinv * s * pinv;
    mark_unobservable(&mut cov, &bread, rank);
    [0, 1, 2].map(|i| [0, 1, 2].map(|j| cov[(i, j)]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn psi_weight_and_derivative() {
        let h = HuberWeights::new(HuberWeights::K_95, 2.0);
        assert_eq!(h.threshold, 2.69);
        assert_eq!(h.psi(1.0), 1.0);
        assert_eq!(h.psi(-10.0), -2.69);
        assert_eq!(h.weight(0.5), 1.0);
        assert!((h.weight(5.38) - 0.5).abs() < 1e-15);
        assert_eq!(h.psi_prime(3.0), 0.0);
        assert_eq!(h.psi_prime(-2.0), 1.0);
    }

    #[test]
    fn sandwich_with_unit_scores_is_the_least_squares_covariance_for_white_noise() {
        // ψ = r, ψ′ = 1: the sandwich is (AᵀA)⁻¹·Σ r²aaᵀ·(AᵀA)⁻¹; with |r| = 1 it is (AᵀA)⁻¹.
        let phi_a: Vec<[f64; 3]> = (0..300).map(|k| [(k as f64 * 0.3).sin(), (k as f64 * 0.7).cos(), 0.5]).collect();
        let scores: Vec<f64> = (0..300).map(|k| if k % 2 == 0 { 1.0 } else { -1.0 }).collect();
        let mut bread = Matrix3::zeros();
        for a in &phi_a {
            let v = Vector3::from(*a);
            bread += v * v.transpose();
        }
        let b = [0, 1, 2].map(|i| [0, 1, 2].map(|j| bread[(i, j)]));
        let cov = sandwich_covariance(&b, &phi_a, &scores, 0);
        let inv = bread.try_inverse().unwrap();
        for i in 0..3 {
            for j in 0..3 {
                assert!((cov[i][j] - inv[(i, j)]).abs() < 1e-12 * inv[(i, i)].abs(), "{i} {j}");
            }
        }
    }
}
