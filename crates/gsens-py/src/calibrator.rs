//! `gsens.Calibrator`: the streaming calibrator, one epoch at a time.

use crate::convert::options;
use crate::{GsensError, error};
use gsens_calib::{EstimateSettings, MethodName};
use gsens_core::{BatchLeastSquares, PrefilteredCalibrator, solve_in_observable_axes};
use numpy::{PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// The streaming calibrator (`gsens_calib::streaming_calibrator`): the batch
/// pass's regressor model, warm-up, high-pass and least squares, fed one
/// epoch of channel-averaged phase error and specific force at a time. Fed
/// an estimate's whole epoch series (`Estimate.epochs()`) and finished, it
/// ends at that estimate's least-squares Γ̂; its covariance is the
/// white-noise one (what a receiver's firmware computes).
///
/// `log_interval_s` is the epochs' spacing; the keyword options are
/// `estimate`'s (the loop, `warmup_s`, `highpass_hz`, …).
#[pyclass(module = "gsens._gsens")]
pub(crate) struct Calibrator {
    inner: PrefilteredCalibrator<BatchLeastSquares>,
    settings: EstimateSettings,
    finished: bool,
}

#[pymethods]
impl Calibrator {
    #[new]
    #[pyo3(signature = (log_interval_s, **settings))]
    fn new(log_interval_s: f64, settings: Option<&Bound<'_, PyDict>>) -> PyResult<Self> {
        let options = options(settings)?;
        if options.method != MethodName::Batch {
            return Err(GsensError::new_err("the streaming calibrator is least squares: leave method out"));
        }
        if !(log_interval_s.is_finite() && log_interval_s > 0.0) {
            return Err(GsensError::new_err(format!("log_interval_s must be finite and > 0, got {log_interval_s}")));
        }
        let settings = options.estimate_settings();
        let inner = gsens_calib::streaming_calibrator(&settings, log_interval_s).map_err(error)?;
        Ok(Calibrator { inner, settings, finished: false })
    }

    /// One epoch: the specific force [m/s²] (3 values) and the phase error
    /// [rad] (None or NaN: no measurement, the models still run).
    #[pyo3(signature = (accel_mps2, phase_err_rad=None))]
    fn feed(&mut self, accel_mps2: [f64; 3], phase_err_rad: Option<f64>) -> PyResult<()> {
        self.check_open()?;
        self.inner.feed(&accel_mps2, phase_err_rad.filter(|p| !p.is_nan()));
        Ok(())
    }

    /// Many epochs: `accel_mps2` N×3, `phase_err_rad` N (NaN: no measurement).
    fn feed_many(
        &mut self,
        py: Python<'_>,
        accel_mps2: PyReadonlyArray2<'_, f64>,
        phase_err_rad: PyReadonlyArray1<'_, f64>,
    ) -> PyResult<()> {
        self.check_open()?;
        let a = accel_mps2.as_array();
        let p = phase_err_rad.as_array();
        if a.ncols() != 3 || a.nrows() != p.len() {
            return Err(GsensError::new_err(format!(
                "feed_many: accel_mps2 is {}×{} and phase_err_rad has {} values: expected N×3 and N",
                a.nrows(),
                a.ncols(),
                p.len()
            )));
        }
        let epochs: Vec<([f64; 3], Option<f64>)> = a
            .rows()
            .into_iter()
            .zip(p.iter())
            .map(|(r, &p)| ([r[0], r[1], r[2]], Some(p).filter(|p| !p.is_nan())))
            .collect();
        let inner = &mut self.inner;
        py.detach(|| {
            for (a, p) in &epochs {
                inner.feed(a, *p);
            }
        });
        Ok(())
    }

    /// The end of the log: the last epoch is processed (the interpolation
    /// prefilter holds one back); no epoch may follow.
    fn finish(&mut self) {
        if !self.finished {
            self.inner.flush();
            self.finished = true;
        }
    }

    /// The estimate so far over the axes the batch path keeps in its solve:
    /// a dict with `gamma_hz_per_mps2` (NaN: not in the solve),
    /// `sigma_hz_per_mps2`, `covariance_hz_per_mps2_sq` (white-noise),
    /// `observable` and `epochs`.
    fn estimate<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let normal = self.inner.calibrator().estimator().normal_equations();
        let (e, kept) = solve_in_observable_axes(normal, &self.settings.criteria);
        let nan_unless = |i: usize, x: f64| if kept[i] { x } else { f64::NAN };
        let sigma = e.sigma_hz_per_mps2();
        let d = PyDict::new(py);
        d.set_item(
            "gamma_hz_per_mps2",
            PyArray1::from_iter(py, (0..3).map(|i| nan_unless(i, e.gamma_hz_per_mps2[i]))),
        )?;
        d.set_item("sigma_hz_per_mps2", PyArray1::from_iter(py, (0..3).map(|i| nan_unless(i, sigma[i]))))?;
        let cov: Vec<Vec<f64>> = (0..3)
            .map(|i| (0..3).map(|j| if kept[i] && kept[j] { e.covariance[i][j] } else { f64::NAN }).collect())
            .collect();
        d.set_item(
            "covariance_hz_per_mps2_sq",
            PyArray2::from_vec2(py, &cov).map_err(|e| GsensError::new_err(e.to_string()))?,
        )?;
        d.set_item("observable", kept)?;
        d.set_item("epochs", e.epochs)?;
        Ok(d)
    }
}

impl Calibrator {
    fn check_open(&self) -> PyResult<()> {
        if self.finished { Err(GsensError::new_err("the calibrator is finished: no epoch may follow")) } else { Ok(()) }
    }
}
