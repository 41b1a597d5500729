//! Python values in: logs as columns of arrays or as files, options as
//! keyword arguments; arrays out.

use crate::GsensError;
use gsens_calib::CalibrationOptions;
use gsens_io::{IMU_COLUMNS, ImuSeries, TRACKING_COLUMNS, TrackingLog, TrackingRow};
use numpy::PyReadonlyArray1;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyString};
use std::collections::HashMap;
use std::path::PathBuf;

/// A log as the caller gave it: a file, or named columns.
pub(crate) enum LogSource<'py> {
    /// A CSV file (`imu.csv`, `tracking.csv`).
    Path(PathBuf),
    /// Columns by name (the CSV header's names), each a 1-D array of float64.
    Columns(HashMap<String, ColumnData<'py>>),
}

/// One column: the caller's contiguous float64 array, read in place, or a
/// copy of anything else (a strided view, a list).
pub(crate) enum ColumnData<'py> {
    /// A contiguous numpy array, borrowed read-only.
    Borrowed(PyReadonlyArray1<'py, f64>),
    /// The values copied.
    Owned(Vec<f64>),
}

impl ColumnData<'_> {
    fn as_slice(&self) -> &[f64] {
        match self {
            // Contiguity was checked when the column was taken.
            ColumnData::Borrowed(a) => a.as_slice().unwrap_or_default(),
            ColumnData::Owned(v) => v,
        }
    }
}

impl<'py> LogSource<'py> {
    /// A path (str or os.PathLike) or a dict of 1-D arrays.
    pub(crate) fn extract(obj: &Bound<'py, PyAny>, role: &str) -> PyResult<Self> {
        if let Ok(dict) = obj.cast::<PyDict>() {
            let mut columns = HashMap::new();
            for (k, v) in dict.iter() {
                let name: String = k.extract()?;
                let values = array_1d(&v).map_err(|_| {
                    GsensError::new_err(format!("{role}: column `{name}` is not a 1-D array of numbers"))
                })?;
                columns.insert(name, values);
            }
            return Ok(LogSource::Columns(columns));
        }
        obj.extract::<PathBuf>().map(LogSource::Path).map_err(|_| {
            pyo3::exceptions::PyTypeError::new_err(format!(
                "{role}: expected a file path, a dict of 1-D arrays or a pandas DataFrame"
            ))
        })
    }
}

/// A 1-D float array (a float64 numpy array, read in place when contiguous,
/// or a sequence of numbers).
fn array_1d<'py>(v: &Bound<'py, PyAny>) -> PyResult<ColumnData<'py>> {
    if let Ok(a) = v.extract::<PyReadonlyArray1<'py, f64>>() {
        if a.as_slice().is_ok() {
            return Ok(ColumnData::Borrowed(a));
        }
        return Ok(ColumnData::Owned(a.as_array().iter().copied().collect()));
    }
    v.extract::<Vec<f64>>().map(ColumnData::Owned)
}

/// The columns `names` of `columns`, all of one length; a missing one is an
/// error naming it and the columns the log needs.
fn take<'a>(
    columns: &'a HashMap<String, ColumnData<'_>>,
    role: &str,
    names: &[&str],
    required: &[&str],
) -> PyResult<Vec<Option<&'a [f64]>>> {
    let mut out = Vec::new();
    let mut len = None;
    for &name in names {
        let col = columns.get(name).map(ColumnData::as_slice);
        if col.is_none() && required.contains(&name) {
            return Err(GsensError::new_err(format!(
                "{role}: missing column `{name}` (the columns are {})",
                names.join(", ")
            )));
        }
        if let Some(c) = col {
            match len {
                Some(n) if n != c.len() => {
                    return Err(GsensError::new_err(format!(
                        "{role}: column `{name}` has {} rows, `{}` has {n}",
                        c.len(),
                        names[0]
                    )));
                }
                _ => len = Some(c.len()),
            }
        }
        out.push(col);
    }
    Ok(out)
}

/// The IMU series of columns `t_s, fx_mps2, fy_mps2, fz_mps2`, checked as the reader checks a file.
pub(crate) fn imu_series(columns: &HashMap<String, ColumnData<'_>>, name: &str) -> PyResult<ImuSeries> {
    let c = take(columns, name, &IMU_COLUMNS, &IMU_COLUMNS)?;
    let [t, x, y, z] = [0, 1, 2, 3].map(|i| c[i].unwrap_or_default());
    let imu =
        ImuSeries { t_s: t.to_vec(), accel_mps2: x.iter().zip(y).zip(z).map(|((x, y), z)| [*x, *y, *z]).collect() };
    imu.validate(name).map_err(crate::error)?;
    Ok(imu)
}

/// The tracking log of columns `t_s, channel, prn, cn0_dbhz, elev_deg,
/// phase_err_rad` (`elev_deg` may be left out: unknown), checked as the
/// reader checks a file; errors name row i as line i + 2, as in the
/// `tracking.csv` these columns would make.
pub(crate) fn tracking_log(columns: &HashMap<String, ColumnData<'_>>, name: &str) -> PyResult<TrackingLog> {
    let required = ["t_s", "channel", "prn", "cn0_dbhz", "phase_err_rad"];
    let c = take(columns, name, &TRACKING_COLUMNS, &required)?;
    let n = c[0].map_or(0, <[f64]>::len);
    let integer = |col: usize, i: usize| -> PyResult<u32> {
        let v = c[col].unwrap_or_default()[i];
        if v.fract() == 0.0 && (0.0..=f64::from(u32::MAX)).contains(&v) {
            Ok(v as u32)
        } else {
            Err(GsensError::new_err(format!(
                "{name}: line {}, column {} ({}): expected a non-negative integer, got {v}",
                i + 2,
                col + 1,
                TRACKING_COLUMNS[col]
            )))
        }
    };
    // Rows stream into the log's builder: no row table beside the columns.
    let mut bad = None;
    let rows = (0..n).map_while(|i| {
        let (channel, prn) = match (integer(1, i), integer(2, i)) {
            (Ok(c), Ok(p)) => (c, p),
            (Err(e), _) | (_, Err(e)) => {
                bad = Some(e);
                return None;
            }
        };
        Some(TrackingRow {
            t_s: c[0].unwrap_or_default()[i],
            channel,
            prn,
            cn0_dbhz: c[3].unwrap_or_default()[i],
            elev_deg: c[4].map(|e| e[i]).filter(|e| !e.is_nan()),
            phase_err_rad: c[5].unwrap_or_default()[i],
        })
    });
    let log = TrackingLog::from_rows(name, rows).map_err(crate::error);
    match bad {
        Some(e) => Err(e),
        None => log,
    }
}

/// A keyword argument's value as JSON (None, bool, int, float, str, or a
/// list of them), so that the options deserialize by name.
pub(crate) fn json_of(v: &Bound<'_, PyAny>, name: &str) -> PyResult<serde_json::Value> {
    use serde_json::Value;
    if v.is_none() {
        return Ok(Value::Null);
    }
    if v.is_instance_of::<PyBool>() {
        return Ok(Value::Bool(v.extract()?));
    }
    if v.is_instance_of::<PyString>() {
        return Ok(Value::String(v.extract()?));
    }
    if v.is_instance_of::<PyInt>() {
        if let Ok(i) = v.extract::<i64>() {
            return Ok(Value::from(i));
        }
    }
    if v.is_instance_of::<PyFloat>() || v.hasattr("__float__")? {
        if let Ok(x) = v.extract::<f64>() {
            return serde_json::Number::from_f64(x)
                .map(Value::Number)
                .ok_or_else(|| GsensError::new_err(format!("setting {name} = {x} is not a finite number")));
        }
    }
    if let Ok(table) = v.cast::<PyDict>() {
        let mut map = serde_json::Map::new();
        for (key, x) in table.iter() {
            let key: String = key.extract()?;
            let value = json_of(&x, &format!("{name}.{key}"))?;
            map.insert(key, value);
        }
        return Ok(Value::Object(map));
    }
    if let Ok(items) = v.extract::<Vec<Bound<'_, PyAny>>>() {
        return items.iter().map(|x| json_of(x, name)).collect::<PyResult<Vec<_>>>().map(Value::Array);
    }
    Err(pyo3::exceptions::PyTypeError::new_err(format!(
        "setting {name}: {} is not a number, a string, a bool, a list, a dict or None",
        v.get_type().name()?
    )))
}

/// Keyword arguments as a JSON object.
pub(crate) fn json_object(kwargs: Option<&Bound<'_, PyDict>>) -> PyResult<serde_json::Map<String, serde_json::Value>> {
    let mut map = serde_json::Map::new();
    if let Some(k) = kwargs {
        for (key, v) in k.iter() {
            let key: String = key.extract()?;
            let value = json_of(&v, &key)?;
            map.insert(key, value);
        }
    }
    Ok(map)
}

/// The calibration options of keyword arguments named as the CLI's flags
/// (`bn_hz=3` for `--bn-hz 3`); an unknown name is an error listing the known ones.
pub(crate) fn options(kwargs: Option<&Bound<'_, PyDict>>) -> PyResult<CalibrationOptions> {
    let map = json_object(kwargs)?;
    serde_json::from_value(serde_json::Value::Object(map)).map_err(|e| GsensError::new_err(format!("settings: {e}")))
}

/// A Python object from its JSON (`json.loads`): the result documents cross as dicts.
pub(crate) fn py_of_json<'py>(py: Python<'py>, json: &str) -> PyResult<Bound<'py, PyAny>> {
    py.import("json")?.call_method1("loads", (json,))
}
