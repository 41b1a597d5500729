//! Test harness, shared by the loop models' unit tests and the integration
//! tests (which include this file by path): a loop's response to a sinusoid
//! measured in the time domain, the naive reference, against its closed-form
//! transfer function, the fast kernel. Deterministic (no noise, no seed).

use core::f64::consts::TAU;
use nalgebra::Complex;

/// The response φ/Δf \[rad/Hz\] at `f_hz` of a loop stepped by `step` (one
/// update of `t_s` seconds per call, Δf in, φ out), measured by simulation:
/// driven by Δf_k = cos(2πf·kT) for `settle_s` seconds, then correlated with
/// the input over the whole cycles of `span_s`:
/// L ≈ (2/N)·Σ φ_k·e^(−j2πf·kT).
pub(crate) fn simulated_response(
    mut step: impl FnMut(f64) -> f64,
    f_hz: f64,
    t_s: f64,
    settle_s: f64,
    span_s: f64,
) -> Complex<f64> {
    let k0 = (settle_s / t_s) as usize;
    let cycles = libm::round(span_s * f_hz).max(1.0);
    let n = libm::round(cycles / (f_hz * t_s)) as usize;
    let mut acc = Complex::new(0.0, 0.0);
    for k in 0..k0 + n {
        let x = TAU * f_hz * k as f64 * t_s;
        let (c, s) = (libm::cos(x), libm::sin(x));
        let phi = step(c);
        if k >= k0 {
            acc += Complex::new(c, -s) * phi;
        }
    }
    acc * (2.0 / n as f64)
}

/// Asserts that the loop stepped by `step` answers a sinusoid at `f_hz` as
/// `model` says, within `rel_tol` of |model| ([`simulated_response`]);
/// `what` names the case in the failure message.
pub(crate) fn assert_sinusoid_response(
    step: impl FnMut(f64) -> f64,
    f_hz: f64,
    t_s: f64,
    (settle_s, span_s): (f64, f64),
    model: Complex<f64>,
    rel_tol: f64,
    what: &str,
) {
    let measured = simulated_response(step, f_hz, t_s, settle_s, span_s);
    assert!(
        (measured - model).norm() < rel_tol * model.norm(),
        "{what}, f {f_hz} Hz, T {t_s} s: measured {measured} against the model's {model}"
    );
}
