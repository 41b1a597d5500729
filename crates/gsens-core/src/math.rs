//! Scalar math through `libm`, so `std` and `no_std` builds give identical bits.

/// π.
pub const PI: f64 = core::f64::consts::PI;
/// 2π.
pub const TAU: f64 = core::f64::consts::TAU;

/// sin(x).
#[inline]
pub fn sin(x: f64) -> f64 {
    libm::sin(x)
}
/// cos(x).
#[inline]
pub fn cos(x: f64) -> f64 {
    libm::cos(x)
}
/// √x.
#[inline]
pub fn sqrt(x: f64) -> f64 {
    libm::sqrt(x)
}
/// atan(x).
#[inline]
pub fn atan(x: f64) -> f64 {
    libm::atan(x)
}
/// atan2(y, x).
#[inline]
pub fn atan2(y: f64, x: f64) -> f64 {
    libm::atan2(y, x)
}
/// eˣ.
#[inline]
pub fn exp(x: f64) -> f64 {
    libm::exp(x)
}
/// ln x.
#[inline]
pub fn ln(x: f64) -> f64 {
    libm::log(x)
}
/// 10ˣ.
#[inline]
pub fn pow10(x: f64) -> f64 {
    libm::pow(10.0, x)
}
/// |x|.
#[inline]
pub fn abs(x: f64) -> f64 {
    libm::fabs(x)
}
/// Rounds half away from zero.
#[inline]
pub fn round(x: f64) -> f64 {
    libm::round(x)
}
/// Dot product of two 3-vectors.
#[inline]
pub fn dot3(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
