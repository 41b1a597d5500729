//! `gsens.Loop`: the one loop abstraction (`gsens_core::LoopModel`) from Python.

use crate::{GsensError, error};
use gsens_core::defaults::{DEFAULT_BN_HZ, DEFAULT_ORDER};
use gsens_core::{KAPLAN_A3, KAPLAN_B3, LinearLoop, LoopModel, LoopSpec};
use numpy::{Complex64, PyArray1, PyReadonlyArray1};
use pyo3::prelude::*;

/// A receiver's carrier PLL of Kaplan & Hegarty's form (`docs/conventions.md#loop-models`):
/// order 2 (Bn, ζ) or 3 (Bn, a3, b3), continuous when `interval_s` is None,
/// else the discrete loop updated every `interval_s` seconds.
///
/// The response L = φ/Δf [rad/Hz] is from an oscillator frequency error Δf
/// to the phase tracking error φ: −2π/(s + F(s)) continuous, L_d(e^{j2πfT}) discrete.
#[pyclass(module = "gsens._gsens", frozen)]
pub(crate) struct Loop {
    model: LoopModel,
}

#[pymethods]
impl Loop {
    #[new]
    // Python's inspect cannot show constants' values: the text signature
    // spells them out (stubtest holds the stub to it, the stub test the stub to the constants).
    #[pyo3(
        signature = (order=DEFAULT_ORDER, bn_hz=DEFAULT_BN_HZ, zeta=std::f64::consts::FRAC_1_SQRT_2, a3=KAPLAN_A3, b3=KAPLAN_B3, interval_s=None),
        text_signature = "(order=2, bn_hz=3.0, zeta=..., a3=1.1, b3=2.4, interval_s=None)"
    )]
    fn new(order: u8, bn_hz: f64, zeta: f64, a3: f64, b3: f64, interval_s: Option<f64>) -> PyResult<Self> {
        let spec = LoopSpec::of_order(order, bn_hz, zeta, a3, b3).map_err(|e| GsensError::new_err(e.to_string()))?;
        if let Some(t) = interval_s.filter(|t| !(t.is_finite() && *t > 0.0)) {
            return Err(GsensError::new_err(format!("interval_s must be finite and > 0, got {t}")));
        }
        let model = LoopModel::kaplan(spec, interval_s);
        model.check().map_err(error)?;
        Ok(Loop { model })
    }

    /// The loop's order (2 or 3).
    #[getter]
    fn order(&self) -> u8 {
        self.model.order()
    }

    /// One-sided noise bandwidth Bn [Hz].
    #[getter]
    fn bn_hz(&self) -> Option<f64> {
        self.model.bn_hz()
    }

    /// Natural frequency ωn/2π [Hz].
    #[getter]
    fn natural_frequency_hz(&self) -> Option<f64> {
        self.model.natural_frequency_hz()
    }

    /// Update interval T [s] (None: continuous).
    #[getter]
    fn interval_s(&self) -> Option<f64> {
        self.model.interval_s()
    }

    /// The loop filter's gains: `c0_per_s`, `c1_per_s2`, `c2_per_s3`
    /// (F(s) = c0 + c1/s + c2/s²; Kaplan & Hegarty Table 5.6).
    fn coefficients(&self) -> PyResult<(f64, f64, f64)> {
        let c = self.model.coeffs().map_err(error)?;
        Ok((c.c0_per_s, c.c1_per_s2, c.c2_per_s3))
    }

    /// L(f) [rad/Hz] at each frequency of `f_hz` (an array or a number).
    fn response<'py>(&self, py: Python<'py>, f_hz: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
        if let Ok(f) = f_hz.extract::<f64>() {
            let r = self.model.response(f);
            return Ok(pyo3::types::PyComplex::from_doubles(py, r.re, r.im).into_any());
        }
        let f: PyReadonlyArray1<'py, f64> = f_hz.extract()?;
        let out = PyArray1::from_iter(
            py,
            f.as_array().iter().map(|&f| {
                let r = self.model.response(f);
                Complex64::new(r.re, r.im)
            }),
        );
        Ok(out.into_any())
    }

    /// The peak of |L|: (frequency [Hz], |L| [rad/Hz]); 1/frequency is the shaking period to use.
    fn peak(&self) -> PyResult<(f64, f64)> {
        let p = self.model.peak().map_err(error)?;
        Ok((p.f_hz, p.rad_per_hz))
    }

    /// Where |L| is at least its peak/√2: (low, high) [Hz].
    fn half_power_band_hz(&self) -> PyResult<(f64, f64)> {
        let [lo, hi] = self.model.half_power_band_hz().map_err(error)?;
        Ok((lo, hi))
    }

    /// The discrete loop run over `delta_f_hz` (one value per update, the
    /// mean frequency error over it [Hz]) from rest: the discriminator output
    /// φ [rad] of each update. Needs `interval_s`.
    fn filter<'py>(
        &self,
        py: Python<'py>,
        delta_f_hz: PyReadonlyArray1<'py, f64>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        if self.model.interval_s().is_none() {
            return Err(GsensError::new_err("filter needs a discrete loop: give interval_s"));
        }
        let mut pll = self.model.runnable().map_err(error)?;
        let input: Vec<f64> = delta_f_hz.as_array().iter().copied().collect();
        let out: Vec<f64> = py.detach(|| input.iter().map(|&d| pll.step(d)).collect());
        Ok(PyArray1::from_vec(py, out))
    }

    fn __repr__(&self) -> String {
        format!("<gsens.Loop {}>", self.model)
    }
}
