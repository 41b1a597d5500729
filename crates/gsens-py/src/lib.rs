//! # gsens-py
//!
//! The Python module `gsens._gsens`, wrapped by the package `gsens`
//! (`python/gsens`): a thin shell over the library crates, as the CLI is.
//!
//! - `estimate`: the calibration pipeline
//!   (`gsens_calib::calibrate_logs`) on columns of numpy arrays or on files,
//!   its options named as the CLI's flags (`gsens_calib::CalibrationOptions`);
//!   the result is the one result document (`to_dict()` is its JSON);
//! - `Loop`: the loop abstraction (`gsens_core::LoopModel`):
//!   response, peak, band, coefficients, and the streaming model on an array;
//! - `simulate` and `montecarlo`:
//!   the simulator and the Monte Carlo of `gsens_montecarlo`;
//! - `Calibrator`: the streaming calibrator
//!   (`gsens_calib::streaming_calibrator`).
//!
//! Errors are `gsens.GsensError` with the CLI's messages (the error and its
//! causes, joined by `: `).
#![deny(missing_docs)]

mod calibrator;
mod convert;
mod estimate;
mod loops;
mod simulate;

use pyo3::prelude::*;

pyo3::create_exception!(
    _gsens,
    GsensError,
    pyo3::exceptions::PyValueError,
    "A calibration, a log or a setting gsens cannot use; the message names the file, line and column, or the setting."
);

/// The message of `e` as the CLI prints it: the error, then each cause, joined by `: `.
pub(crate) fn message(e: &dyn std::error::Error) -> String {
    let mut text = e.to_string();
    let mut source = e.source();
    while let Some(s) = source {
        text.push_str(": ");
        text.push_str(&s.to_string());
        source = s.source();
    }
    text
}

/// `e` as a `GsensError`.
pub(crate) fn error(e: impl std::error::Error) -> PyErr {
    GsensError::new_err(message(&e))
}

/// The extension module.
#[pymodule]
fn _gsens(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("GsensError", m.py().get_type::<GsensError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_function(wrap_pyfunction!(estimate::estimate, m)?)?;
    m.add_function(wrap_pyfunction!(estimate::options_defaults, m)?)?;
    m.add_class::<estimate::Estimate>()?;
    m.add_class::<loops::Loop>()?;
    m.add_function(wrap_pyfunction!(simulate::simulate, m)?)?;
    m.add_function(wrap_pyfunction!(simulate::default_scenario, m)?)?;
    m.add_function(wrap_pyfunction!(simulate::montecarlo, m)?)?;
    m.add_class::<calibrator::Calibrator>()?;
    Ok(())
}
