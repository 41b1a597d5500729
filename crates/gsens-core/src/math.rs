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
/// 10ˣ.
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
