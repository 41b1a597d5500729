//! Scalar math through `libm`, so `std` and `no_std` builds give identical bits.

/// π.
pub(crate) const PI: f64 = core::f64::consts::PI;
/// 2π.
pub(crate) const TAU: f64 = core::f64::consts::TAU;

/// sin(x).
#[inline]
pub(crate) fn sin(x: f64) -> f64 {
    libm::sin(x)
}
/// cos(x).
#[inline]
pub(crate) fn cos(x: f64) -> f64 {
    libm::cos(x)
}
/// √x.
#[inline]
pub(crate) fn sqrt(x: f64) -> f64 {
    libm::sqrt(x)
}
/// eˣ.
#[inline]
pub(crate) fn exp(x: f64) -> f64 {
    libm::exp(x)
}
/// ln x.
#[inline]
pub(crate) fn ln(x: f64) -> f64 {
    libm::log(x)
}
/// 10ˣ (with `std`, `units::cn0_dbhz_to_ratio_hz` uses the platform's pow instead).
#[cfg(not(feature = "std"))]
#[inline]
pub(crate) fn pow10(x: f64) -> f64 {
    libm::pow(10.0, x)
}
/// x rounded half away from zero.
#[inline]
pub(crate) fn round(x: f64) -> f64 {
    libm::round(x)
}
/// |x|.
#[inline]
pub(crate) fn abs(x: f64) -> f64 {
    libm::fabs(x)
}
/// Dot product of two 3-vectors.
#[inline]
pub(crate) fn dot3(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Sweeps of the Schur iteration before giving up: a companion or
/// state-transition matrix of a few states converges in tens; one built from
/// absurd parameters (a bandwidth of 1e200 Hz) may never converge.
const SCHUR_MAX_SWEEPS: usize = 1000;

/// The largest modulus of a matrix's eigenvalues (its spectral radius), or
/// None when an entry is not finite or the Schur iteration does not converge
/// within [`SCHUR_MAX_SWEEPS`] (a loop built from such a matrix is treated as
/// unstable instead of hanging). For the 2×2, 3×3 and 4×4 matrices of the
/// loops ([`SpectralRadius`]).
pub(crate) trait SpectralRadius {
    /// The spectral radius, or None (see the trait).
    fn spectral_radius(self) -> Option<f64>;
}

macro_rules! spectral_radius_for {
    ($($m:ty),*) => {$(
        impl SpectralRadius for $m {
            fn spectral_radius(self) -> Option<f64> {
                if self.iter().any(|x| !x.is_finite()) {
                    return None;
                }
                let schur = nalgebra::linalg::Schur::try_new(self, f64::EPSILON, SCHUR_MAX_SWEEPS)?;
                let rho = schur.complex_eigenvalues().iter().map(|z| sqrt(z.norm_sqr())).fold(0.0, f64::max);
                rho.is_finite().then_some(rho)
            }
        }
    )*};
}

spectral_radius_for!(nalgebra::Matrix2<f64>, nalgebra::Matrix3<f64>, nalgebra::Matrix4<f64>);
