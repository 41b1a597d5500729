//! `gsens.estimate`: the calibration pipeline on arrays or files, and its result.

use crate::convert::{ColumnData, LogSource, imu_series, options, py_of_json, tracking_log};
use crate::{GsensError, error};
use gsens_calib::{CalibrationOptions, Outcome, ResultDocument};
use gsens_inputs::{Inputs, InputsError, Log};
use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::collections::HashMap;
use std::path::PathBuf;

/// Estimates Γ from an IMU log and a tracking log (or GNSS-SDR dumps, a
/// PocketSDR log, a RINEX file or a UBX log), as `gsens estimate` does.
///
/// `imu` and `tracking` are file paths or dicts of 1-D float arrays named as
/// the CSV columns (`t_s, fx_mps2, fy_mps2, fz_mps2`;
/// `t_s, channel, prn, cn0_dbhz, elev_deg, phase_err_rad`); the keyword
/// options are the CLI's flags with `_` for `-` (`bn_hz=3`, `order=2`,
/// `time_offset="none"`, `method="gls"`, …).
// One argument per Python keyword: the signature is the Python API.
#[allow(clippy::too_many_arguments)]
#[pyfunction]
#[pyo3(signature = (imu=None, tracking=None, *, gnss_sdr=None, gnss_sdr_conf=None, pocketsdr=None, pocketsdr_conf=None, rinex=None, ubx=None, observable=None, **settings))]
pub(crate) fn estimate(
    py: Python<'_>,
    imu: Option<&Bound<'_, PyAny>>,
    tracking: Option<&Bound<'_, PyAny>>,
    gnss_sdr: Option<PathBuf>,
    gnss_sdr_conf: Option<PathBuf>,
    pocketsdr: Option<PathBuf>,
    pocketsdr_conf: Option<PathBuf>,
    rinex: Option<PathBuf>,
    ubx: Option<PathBuf>,
    observable: Option<String>,
    settings: Option<&Bound<'_, PyDict>>,
) -> PyResult<Estimate> {
    let options = options(settings)?;
    let pipeline = options.pipeline_settings().map_err(error)?;
    if rinex.is_some() || ubx.is_some() {
        if tracking.is_some() || gnss_sdr.is_some() || pocketsdr.is_some() {
            return Err(GsensError::new_err("give one of tracking, gnss_sdr, pocketsdr, rinex and ubx"));
        }
        let imu = match imu.map(|i| LogSource::extract(i, "imu")).transpose()? {
            Some(LogSource::Path(p)) => Some(p),
            Some(LogSource::Columns(_)) => {
                return Err(GsensError::new_err("imu: give the IMU log as a file with rinex or ubx"));
            }
            None => None,
        };
        // The names are the record's serde names, as the command line's.
        let record = match observable {
            None => gsens_calib::ObservationRecord::Auto,
            Some(name) => serde_json::from_value(serde_json::Value::String(name))
                .map_err(|e| GsensError::new_err(format!("observable: {e}")))?,
        };
        let choice = gsens_inputs::InputChoice {
            imu,
            rinex,
            ubx,
            gnss_sdr_conf: gnss_sdr_conf.clone(),
            observation_record: record,
            ..Default::default()
        };
        let Some(inputs) = choice.observations(|n| n.to_string()) else { unreachable!("rinex or ubx is given") };
        let inputs = inputs.map_err(error)?;
        let outcome = py.detach(|| inputs.calibrate(&pipeline)).map_err(error)?;
        return Ok(Estimate::of_document(outcome.document(None)));
    }
    let Some(imu) = imu else { return Err(GsensError::new_err("imu is required (except with ubx)")) };
    let imu = LogSource::extract(imu, "imu")?;
    let imu_path = |why: &str| match &imu {
        LogSource::Path(p) => Ok(p.clone()),
        LogSource::Columns(_) => Err(GsensError::new_err(format!("imu: give the IMU log as a file with {why}"))),
    };
    let inputs = match (tracking, gnss_sdr, pocketsdr) {
        (Some(_), Some(_), _) | (Some(_), _, Some(_)) | (None, Some(_), Some(_)) => {
            return Err(GsensError::new_err("give one of tracking, gnss_sdr and pocketsdr"));
        }
        (None, Some(dumps_dir), None) => {
            let Some(conf) = gnss_sdr_conf else {
                return Err(GsensError::new_err(
                    "gnss_sdr needs gnss_sdr_conf (the configuration the dumps were made with)",
                ));
            };
            let imu = imu_path("gnss_sdr")?;
            let import = gsens_gnss_sdr::ImportSettings::from_conf(Some(&conf), None).map_err(error)?;
            Inputs::GnssSdrDumps { imu, dumps_dir, import, conf: Some(conf) }
        }
        (None, None, Some(log)) => {
            let imu = imu_path("pocketsdr")?;
            let import =
                gsens_pocketsdr::ImportSettings::from_options_file(pocketsdr_conf.as_deref()).map_err(error)?;
            Inputs::PocketSdr { imu, log, import }
        }
        (Some(t), None, None) => {
            let tracking = log_of(LogSource::extract(t, "tracking")?, "tracking", tracking_log)?;
            let imu = log_of(imu, "imu", imu_series)?;
            match gnss_sdr_conf {
                // Rows from a GNSS-SDR run: its loop, from its configuration.
                Some(conf) => {
                    let import = gsens_gnss_sdr::ImportSettings::from_conf(Some(&conf), None).map_err(error)?;
                    Inputs::GnssSdrRows { imu, tracking, import, conf }
                }
                None => Inputs::Csv { imu, tracking },
            }
        }
        (None, None, None) => return Err(GsensError::new_err("tracking is required (or gnss_sdr, or pocketsdr)")),
    };
    let calibrated = py.detach(|| inputs.calibrate(&pipeline)).map_err(|e| match e {
        InputsError::LoopStatedTwice { .. } => {
            GsensError::new_err("gnss_sdr_conf states the receiver loop: leave out order, bn_hz and the like")
        }
        e => error(e),
    })?;
    Ok(Estimate::of(calibrated.outcome))
}

/// A log as the library takes it: a file as it is, columns as the series
/// they name (`name` in errors).
fn log_of<T>(
    source: LogSource<'_>,
    name: &str,
    convert: impl FnOnce(&HashMap<String, ColumnData<'_>>, &str) -> PyResult<T>,
) -> PyResult<Log<T>> {
    Ok(match source {
        LogSource::Path(p) => Log::File(p),
        LogSource::Columns(c) => Log::Memory { name: name.to_string(), log: convert(&c, name)? },
    })
}

/// The options' defaults, by name (what `estimate` takes as keywords).
#[pyfunction]
pub(crate) fn options_defaults(py: Python<'_>) -> PyResult<Bound<'_, PyAny>> {
    let json = serde_json::to_string(&CalibrationOptions::default()).map_err(error)?;
    py_of_json(py, &json)
}

/// The result of a calibration: the result document, and the epoch series
/// the estimator saw.
#[pyclass(module = "gsens._gsens", frozen)]
pub(crate) struct Estimate {
    doc: ResultDocument,
    json: String,
    text: String,
    t_s: Vec<f64>,
    phase_err_rad: Vec<f64>,
    accel_mps2: Vec<[f64; 3]>,
}

impl Estimate {
    /// A document without an epoch series of the tracking error (a carrier
    /// phase and Doppler log): the series are empty.
    fn of_document(doc: ResultDocument) -> Self {
        let json = doc.to_json_string().unwrap_or_default();
        let text = gsens_report::render_text(&doc);
        Estimate { t_s: Vec::new(), phase_err_rad: Vec::new(), accel_mps2: Vec::new(), doc, json, text }
    }

    fn of(outcome: Outcome) -> Self {
        let doc = outcome.document(None);
        let json = doc.to_json_string().unwrap_or_default();
        let text = gsens_report::render_text(&doc);
        let s = outcome.series();
        Estimate {
            t_s: s.t_s.to_vec(),
            phase_err_rad: s.phase_err_rad.iter().map(|p| p.unwrap_or(f64::NAN)).collect(),
            accel_mps2: s.accel_mps2.to_vec(),
            doc,
            json,
            text,
        }
    }
}

/// Three options as an array, NaN for None (an axis without an estimate).
fn axes<'py>(py: Python<'py>, v: &[Option<f64>; 3]) -> Bound<'py, PyArray1<f64>> {
    PyArray1::from_iter(py, v.iter().map(|x| x.unwrap_or(f64::NAN)))
}

#[pymethods]
impl Estimate {
    /// Γ̂ [Hz/(m/s²)] per axis (x, y, z); NaN where the axis is unobservable.
    #[getter]
    fn gamma_hz_per_mps2<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        axes(py, &self.doc.calibration.gamma_hz_per_mps2)
    }

    /// 1σ of Γ̂ [Hz/(m/s²)] (statistical, loop and offset uncertainty, IMU errors).
    #[getter]
    fn sigma_hz_per_mps2<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        axes(py, &self.doc.calibration.sigma_hz_per_mps2)
    }

    /// Γ̂ [ppb/g].
    #[getter]
    fn gamma_ppb_per_g<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        axes(py, &self.doc.calibration.gamma_ppb_per_g)
    }

    /// 1σ of Γ̂ [ppb/g].
    #[getter]
    fn sigma_ppb_per_g<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        axes(py, &self.doc.calibration.sigma_ppb_per_g)
    }

    /// Covariance of Γ̂ [(Hz/(m/s²))²], 3×3; NaN in the rows and columns of unobservable axes.
    #[getter]
    fn covariance_hz_per_mps2_sq<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let c = &self.doc.calibration.covariance_hz_per_mps2_sq;
        let rows: Vec<Vec<f64>> = c.iter().map(|r| r.iter().map(|x| x.unwrap_or(f64::NAN)).collect()).collect();
        PyArray2::from_vec2(py, &rows).map_err(|e| GsensError::new_err(e.to_string()))
    }

    /// The Cramér–Rao bound of the session [Hz/(m/s²)].
    #[getter]
    fn crlb_hz_per_mps2<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        axes(py, &self.doc.calibration.crlb_hz_per_mps2)
    }

    /// Whether each axis has an estimate.
    #[getter]
    fn observable(&self) -> [bool; 3] {
        self.doc.calibration.observable
    }

    /// IMU time stamp minus true time [s] (estimated or as given).
    #[getter]
    fn imu_time_offset_s(&self) -> f64 {
        self.doc.calibration.imu_time_offset_s
    }

    /// 1σ of the estimated IMU time offset [s] (None when it was given).
    #[getter]
    fn imu_time_offset_sigma_s(&self) -> Option<f64> {
        self.doc.calibration.imu_time_offset_sigma_s
    }

    /// Whether gsens's checks found nothing that makes Γ̂ doubtful beyond its σ.
    #[getter]
    fn trustworthy(&self) -> bool {
        self.doc.trustworthy
    }

    /// The warnings: dicts with `code` and `message` (what was found, why it matters, what to do).
    #[getter]
    fn warnings<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let json = serde_json::to_string(&self.doc.warnings).map_err(error)?;
        py_of_json(py, &json)
    }

    /// Per axis, the verdict on the shaking (frequency found, share of the
    /// loop's peak sensitivity, observability), as in the result document.
    #[getter]
    fn verdicts<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let json = serde_json::to_string(&self.doc.calibration.axes).map_err(error)?;
        py_of_json(py, &json)
    }

    /// The receiver loop Γ̂ is given under (the stated, fitted or chosen
    /// one), as the result document's `loop_used`.
    #[getter]
    fn loop_used<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let json = serde_json::to_string(&self.doc.calibration.loop_used).map_err(error)?;
        py_of_json(py, &json)
    }

    /// The receiver loop Γ̂ is given under, in words (as `gsens estimate` prints it).
    #[getter]
    fn loop_description(&self) -> String {
        self.doc.calibration.loop_used.to_string()
    }

    /// The epochs the estimator saw: `t_s` [s], the channel-averaged
    /// `phase_err_rad` [rad] (NaN: no channel) and `accel_mps2` (N×3, the
    /// specific force interpolated onto the epochs, offset applied).
    fn epochs<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        d.set_item("t_s", PyArray1::from_slice(py, &self.t_s))?;
        d.set_item("phase_err_rad", PyArray1::from_slice(py, &self.phase_err_rad))?;
        let rows: Vec<Vec<f64>> = self.accel_mps2.iter().map(|a| a.to_vec()).collect();
        d.set_item("accel_mps2", PyArray2::from_vec2(py, &rows).map_err(|e| GsensError::new_err(e.to_string()))?)?;
        Ok(d)
    }

    /// The result document as a dict: equal to the JSON `gsens estimate --json` writes.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        py_of_json(py, &self.json)
    }

    /// The result document as JSON text.
    fn to_json(&self) -> String {
        self.json.clone()
    }

    /// The text report `gsens estimate` prints.
    fn report(&self) -> String {
        self.text.clone()
    }

    fn __str__(&self) -> String {
        self.text.clone()
    }

    fn __repr__(&self) -> String {
        let c = &self.doc.calibration;
        let axis = |i: usize| match (c.gamma_hz_per_mps2[i], c.sigma_hz_per_mps2[i]) {
            (Some(g), Some(s)) => format!("{g:+.5} ± {s:.5}"),
            _ => "unobservable".to_string(),
        };
        let verdict = if self.doc.trustworthy {
            "trustworthy".to_string()
        } else {
            format!("NOT trustworthy ({})", self.doc.untrusted_codes().join(", "))
        };
        format!("<gsens.Estimate Γ̂ [Hz/(m/s²)] x {}, y {}, z {}; {verdict}>", axis(0), axis(1), axis(2))
    }
}
