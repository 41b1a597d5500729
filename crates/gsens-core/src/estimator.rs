use crate::math::{dot3, sqrt};
use nalgebra::{Matrix3, SymmetricEigen, Vector3};

/// An estimate of Γ with its covariance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GammaEstimate {
    /// Γ̂ \[Hz/(m/s²)\]. Components along unobservable directions are 0.
    pub gamma_hz_per_mps2: [f64; 3],
    /// Covariance of Γ̂ \[(Hz/(m/s²))²\]; +∞ on the diagonal of unobservable axes.
    pub covariance: [[f64; 3]; 3],
    /// Residual variance σ̂² of φ − φ_aᵀΓ̂ \[rad²\] used in the covariance.
    pub residual_variance_rad2: f64,
    /// Epochs used.
    pub epochs: u64,
}

impl GammaEstimate {
    /// 1σ of each component \[Hz/(m/s²)\].
    pub fn sigma_hz_per_mps2(&self) -> [f64; 3] {
        [0, 1, 2].map(|i| sqrt(self.covariance[i][i].max(0.0)))
    }
}

/// One interface for feeding epochs to every estimator.
///
/// Estimators of Γ from the measured phase error φ and the regressor φ_a.
///
/// All share [`GammaEstimator`]: feed (φ_k, φ_a,k) epoch by epoch, ask for
/// the estimate at any time. The model is φ_k = φ_a,kᵀΓ + n_k.
///
/// - [`GradientObserver`]: the paper's observer dΓ̂/dt = k·φ_a·(φ − φ_aᵀΓ̂),
///   discretized by forward Euler at the log interval T:
///   Γ̂ ← Γ̂ + k·T·φ_a·(φ − φ_aᵀΓ̂). The error obeys
///   Γ̃ ← (I − k·T·φ_aφ_aᵀ)·Γ̃, whose eigenvalues are 1 (orthogonal to φ_a)
///   and 1 − k·T·|φ_a|²: it is stable iff 0 < k·T·|φ_a,k|² < 2 at every epoch
///   (monotone, no overshoot, for k·T·|φ_a|² ≤ 1).
/// - [`RecursiveLeastSquares`]: the Kalman-type gain
///   K = Pφ_a/(λ + φ_aᵀPφ_a), Γ̂ ← Γ̂ + K·e, P ← (P − Kφ_aᵀP)/λ with an
///   optional forgetting factor λ ≤ 1.
/// - [`BatchLeastSquares`]: normal equations accumulated epoch by epoch,
///   solved on request: Γ̂ = (AᵀA)⁻¹Aᵀφ, Cov = σ̂²(AᵀA)⁻¹.
pub trait GammaEstimator {
    /// Feeds one epoch: measured (channel-averaged) phase error \[rad\] and the
    /// regressor φ_a = L\[a\] at the same epoch.
    fn update(&mut self, phase_err_rad: f64, phi_a: &[f64; 3]);
    /// The current estimate.
    fn estimate(&self) -> GammaEstimate;
    /// The current Γ̂ alone \[Hz/(m/s²)\] (cheaper where the estimator can).
    fn gamma_hz_per_mps2(&self) -> [f64; 3] {
        self.estimate().gamma_hz_per_mps2
    }
}

/// Information accumulated from the regressors: AᵀA, Aᵀφ, φᵀφ and the count.
/// Shared by all estimators for covariance and observability.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct NormalEquations {
    /// AᵀA = Σ φ_a φ_aᵀ.
    pub ata: Matrix3<f64>,
    /// Aᵀφ = Σ φ_a φ.
    pub atb: Vector3<f64>,
    /// φᵀφ = Σ φ².
    pub btb: f64,
    /// Number of epochs.
    pub n: u64,
}

impl NormalEquations {
    /// Adds one epoch.
    #[inline]
    pub fn add(&mut self, phase_err_rad: f64, phi_a: &[f64; 3]) {
        let v = Vector3::new(phi_a[0], phi_a[1], phi_a[2]);
        self.ata += v * v.transpose();
        self.atb += v * phase_err_rad;
        self.btb += phase_err_rad * phase_err_rad;
        self.n += 1;
    }

    /// Residual sum of squares at `gamma`: φᵀφ − 2ΓᵀAᵀφ + ΓᵀAᵀAΓ (≥ 0).
    pub fn rss(&self, gamma: &Vector3<f64>) -> f64 {
        (self.btb - 2.0 * gamma.dot(&self.atb) + (gamma.transpose() * self.ata * gamma)[(0, 0)]).max(0.0)
    }

    /// Pseudo-inverse of AᵀA by its eigen-decomposition, dropping directions
    /// whose eigenvalue is below `rel_tol` × the largest; returns it and the rank.
    pub fn pseudo_inverse(&self, rel_tol: f64) -> (Matrix3<f64>, usize) {
        pseudo_inverse_sym(&self.ata, rel_tol)
    }

    /// Least-squares solution and covariance σ̂²(AᵀA)⁺, with σ̂² = RSS/(n − rank).
    /// Unobservable directions (relative eigenvalue below 1e-10) get Γ̂ = 0
    /// along them and +∞ variance on the axes they touch.
    pub fn solve(&self) -> GammaEstimate {
        let (pinv, rank) = self.pseudo_inverse(RANK_TOL);
        let gamma = pinv * self.atb;
        let dof = (self.n as f64 - rank as f64).max(1.0);
        let s2 = self.rss(&gamma) / dof;
        let mut cov = pinv * s2;
        mark_unobservable(&mut cov, &self.ata, rank);
        GammaEstimate {
            gamma_hz_per_mps2: [gamma[0], gamma[1], gamma[2]],
            covariance: to_array(&cov),
            residual_variance_rad2: s2,
            epochs: self.n,
        }
    }
}

/// Relative eigenvalue below which a direction of AᵀA counts as unexcited.
pub const RANK_TOL: f64 = 1e-10;

pub(crate) fn pseudo_inverse_sym(m: &Matrix3<f64>, rel_tol: f64) -> (Matrix3<f64>, usize) {
    let eig = SymmetricEigen::new(*m);
    let max = eig.eigenvalues.iter().fold(0.0f64, |a, &b| a.max(b));
    let mut pinv = Matrix3::zeros();
    let mut rank = 0;
    if max > 0.0 {
        for i in 0..3 {
            let l = eig.eigenvalues[i];
            if l > rel_tol * max {
                let v = eig.eigenvectors.column(i);
                pinv += v * v.transpose() / l;
                rank += 1;
            }
        }
    }
    (pinv, rank)
}

/// Sets +∞ variance on every axis that has a component along a dropped
/// (unexcited) direction of `ata`.
pub(crate) fn mark_unobservable(cov: &mut Matrix3<f64>, ata: &Matrix3<f64>, rank: usize) {
    if rank == 3 {
        return;
    }
    let eig = SymmetricEigen::new(*ata);
    let max = eig.eigenvalues.iter().fold(0.0f64, |a, &b| a.max(b));
    for i in 0..3 {
        let excited = eig.eigenvalues[i] > RANK_TOL * max;
        if !excited {
            let v = eig.eigenvectors.column(i);
            for axis in 0..3 {
                if v[axis].abs() > 1e-6 {
                    cov[(axis, axis)] = f64::INFINITY;
                }
            }
        }
    }
}

/// The estimate of a recursive estimator: its own Γ̂ and covariance, with the
/// axes the accumulated information cannot see marked unobservable.
fn recursive_estimate(gamma: &Vector3<f64>, mut cov: Matrix3<f64>, s2: f64, normal: &NormalEquations) -> GammaEstimate {
    let (_, rank) = normal.pseudo_inverse(RANK_TOL);
    mark_unobservable(&mut cov, &normal.ata, rank);
    GammaEstimate {
        gamma_hz_per_mps2: [gamma[0], gamma[1], gamma[2]],
        covariance: to_array(&cov),
        residual_variance_rad2: s2,
        epochs: normal.n,
    }
}

fn to_array(m: &Matrix3<f64>) -> [[f64; 3]; 3] {
    [[m[(0, 0)], m[(0, 1)], m[(0, 2)]], [m[(1, 0)], m[(1, 1)], m[(1, 2)]], [m[(2, 0)], m[(2, 1)], m[(2, 2)]]]
}

/// Batch least squares over the whole log (normal equations, solved on request).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct BatchLeastSquares {
    normal: NormalEquations,
}

impl BatchLeastSquares {
    /// An empty accumulator.
    pub fn new() -> Self {
        Self::default()
    }
    /// The accumulated normal equations.
    pub fn normal_equations(&self) -> &NormalEquations {
        &self.normal
    }
}

impl GammaEstimator for BatchLeastSquares {
    #[inline]
    fn update(&mut self, phase_err_rad: f64, phi_a: &[f64; 3]) {
        self.normal.add(phase_err_rad, phi_a);
    }
    fn estimate(&self) -> GammaEstimate {
        self.normal.solve()
    }
}

/// The paper's gradient observer with constant gain `k`, discretized at the
/// log interval (see the module docs for the stable range of k).
///
/// Its covariance is propagated alongside: with white residual noise of
/// variance σ², C ← (I − kTφ_aφ_aᵀ)·C·(I − kTφ_aφ_aᵀ)ᵀ + (kT)²σ²·φ_aφ_aᵀ.
/// σ² factors out, so C is propagated for σ² = 1 and scaled on request by
/// σ̂² = RSS(Γ̂)/(n − 3) (the running residuals would include the transient).
/// This is the spread of Γ̂ caused by the noise; the transient from the
/// initial guess is not in it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GradientObserver {
    gain_k: f64,
    interval_s: f64,
    gamma: Vector3<f64>,
    /// Covariance propagated for unit residual variance (σ² factors out).
    cov_unit: Matrix3<f64>,
    normal: NormalEquations,
}

impl GradientObserver {
    /// Observer with gain `gain_k` [1/(s·rad²/Hz²·(m/s²)²)... i.e. per unit
    /// φ_a² per second] for epochs `interval_s` apart, starting at Γ̂ = 0.
    pub fn new(gain_k: f64, interval_s: f64) -> Self {
        GradientObserver {
            gain_k,
            interval_s,
            gamma: Vector3::zeros(),
            cov_unit: Matrix3::zeros(),
            normal: NormalEquations::default(),
        }
    }

    /// Whether the step at regressor `phi_a` is inside the stable range
    /// 0 < k·T·|φ_a|² < 2.
    pub fn step_is_stable(&self, phi_a: &[f64; 3]) -> bool {
        let g = self.gain_k * self.interval_s * dot3(phi_a, phi_a);
        g < 2.0 && self.gain_k > 0.0
    }
}

impl GammaEstimator for GradientObserver {
    #[inline]
    fn update(&mut self, phase_err_rad: f64, phi_a: &[f64; 3]) {
        let v = Vector3::new(phi_a[0], phi_a[1], phi_a[2]);
        let e = phase_err_rad - v.dot(&self.gamma);
        let kt = self.gain_k * self.interval_s;
        self.gamma += v * (kt * e);
        self.normal.add(phase_err_rad, phi_a);
        let vvt = v * v.transpose();
        let m = Matrix3::identity() - vvt * kt;
        self.cov_unit = m * self.cov_unit * m.transpose() + vvt * (kt * kt);
    }
    fn gamma_hz_per_mps2(&self) -> [f64; 3] {
        [self.gamma[0], self.gamma[1], self.gamma[2]]
    }
    fn estimate(&self) -> GammaEstimate {
        let (_, rank) = self.normal.pseudo_inverse(RANK_TOL);
        let s2 = self.normal.rss(&self.gamma) / (self.normal.n as f64 - rank as f64).max(1.0);
        recursive_estimate(&self.gamma, self.cov_unit * s2, s2, &self.normal)
    }
}

/// Recursive least squares (the Kalman-type gain) with forgetting factor λ.
///
/// P starts at `p0`·I (a diffuse prior; its pull on Γ̂ is ~1/(p0·λ_min(AᵀA))).
/// The residual sum of squares is accumulated exactly as
/// RSS ← λ·RSS + e²/(1 + φ_aᵀPφ_a/λ) (e the a-priori residual), which equals
/// the batch RSS when λ = 1; Cov = σ̂²·P with σ̂² = RSS/(n_eff − 3).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RecursiveLeastSquares {
    lambda: f64,
    gamma: Vector3<f64>,
    p: Matrix3<f64>,
    rss: f64,
    n_eff: f64,
    normal: NormalEquations,
}

impl RecursiveLeastSquares {
    /// Default diffuse prior variance of each component \[(Hz/(m/s²))²\].
    pub const DEFAULT_P0: f64 = 1e8;

    /// RLS with forgetting factor `lambda` (1 = none) and prior variance `p0`.
    pub fn new(lambda: f64, p0: f64) -> Self {
        RecursiveLeastSquares {
            lambda,
            gamma: Vector3::zeros(),
            p: Matrix3::identity() * p0,
            rss: 0.0,
            n_eff: 0.0,
            normal: NormalEquations::default(),
        }
    }
}

impl GammaEstimator for RecursiveLeastSquares {
    #[inline]
    fn update(&mut self, phase_err_rad: f64, phi_a: &[f64; 3]) {
        let v = Vector3::new(phi_a[0], phi_a[1], phi_a[2]);
        let pv = self.p * v;
        let denom = self.lambda + v.dot(&pv);
        let k = pv / denom;
        let e = phase_err_rad - v.dot(&self.gamma);
        self.gamma += k * e;
        // Symmetric form of (P − K·vᵀP)/λ.
        self.p = (self.p - k * pv.transpose()) / self.lambda;
        self.p = (self.p + self.p.transpose()) * 0.5;
        self.rss = self.lambda * self.rss + e * e * self.lambda / denom;
        self.n_eff = self.lambda * self.n_eff + 1.0;
        self.normal.add(phase_err_rad, phi_a);
    }
    fn gamma_hz_per_mps2(&self) -> [f64; 3] {
        [self.gamma[0], self.gamma[1], self.gamma[2]]
    }
    fn estimate(&self) -> GammaEstimate {
        let s2 = self.rss / (self.n_eff - 3.0).max(1.0);
        recursive_estimate(&self.gamma, self.p * s2, s2, &self.normal)
    }
}

/// Covariance of a least-squares Γ̂ robust to coloured residuals
/// (Newey–West heteroscedasticity-and-autocorrelation-consistent sandwich):
/// Cov = (AᵀA)⁻¹·S·(AᵀA)⁻¹, S = Σ_ℓ w_ℓ Σ_k e_k e_{k−ℓ}(φ_a,k φ_a,k−ℓᵀ + φ_a,k−ℓ φ_a,kᵀ)/(1+δ_ℓ0),
/// Bartlett weights w_ℓ = 1 − ℓ/(L+1) (Newey & West, Econometrica 55, 1987).
/// The residuals of a carrier loop are coloured (the loop shapes the
/// oscillator noise), so the white-noise σ̂²(AᵀA)⁻¹ is too optimistic.
pub fn hac_covariance(phi_a: &[[f64; 3]], residual_rad: &[f64], max_lag: usize) -> [[f64; 3]; 3] {
    let n = phi_a.len().min(residual_rad.len());
    let mut ata = Matrix3::zeros();
    let mut s = Matrix3::zeros();
    for k in 0..n {
        let v = Vector3::from(phi_a[k]);
        ata += v * v.transpose();
        let g = v * residual_rad[k];
        s += g * g.transpose();
    }
    for lag in 1..=max_lag.min(n.saturating_sub(1)) {
        let w = 1.0 - lag as f64 / (max_lag as f64 + 1.0);
        let mut gamma_l = Matrix3::zeros();
        for k in lag..n {
            let g0 = Vector3::from(phi_a[k]) * residual_rad[k];
            let g1 = Vector3::from(phi_a[k - lag]) * residual_rad[k - lag];
            gamma_l += g0 * g1.transpose();
        }
        s += (gamma_l + gamma_l.transpose()) * w;
    }
    let (pinv, rank) = pseudo_inverse_sym(&ata, RANK_TOL);
    let mut cov = pinv * s * pinv;
    mark_unobservable(&mut cov, &ata, rank);
    to_array(&cov)
}
