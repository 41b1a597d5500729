//! `gsens.simulate` and `gsens.montecarlo`: the simulator and the Monte Carlo.

use crate::convert::{json_object, options, py_of_json};
use crate::{GsensError, error};
use gsens_sim::scenario::Scenario;
use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;

/// The embedded default scenario (the paper's experiment) as TOML text, with its comments.
#[pyfunction]
pub(crate) fn default_scenario() -> &'static str {
    Scenario::default_toml()
}

/// The scenario of the file `path` (the embedded default for None) with
/// `overrides` merged in: each key a table of the scenario (`oscillator`,
/// `loop`, `log`, `imu`, `motion`, …) whose dict is merged key by key (a
/// non-dict value replaces). Checked as a scenario file is.
fn scenario_with(path: Option<&PathBuf>, overrides: serde_json::Map<String, serde_json::Value>) -> PyResult<Scenario> {
    let (name, text) = match path {
        None => ("the default scenario".to_string(), Scenario::default_toml().to_string()),
        Some(p) => (
            p.display().to_string(),
            gsens_io::read_config_text(p)
                .map_err(|e| GsensError::new_err(format!("{}: cannot read: {e}", p.display())))?,
        ),
    };
    if overrides.is_empty() {
        return Scenario::from_toml_str(&text)
            .map_err(|e| GsensError::new_err(format!("{name}: {}", crate::message(&e))));
    }
    let mut table: toml::Table =
        text.parse().map_err(|e: toml::de::Error| GsensError::new_err(format!("{name}: {e}")))?;
    let overrides: toml::Table = serde_json::from_value(serde_json::Value::Object(overrides)).map_err(|e| {
        GsensError::new_err(format!("scenario overrides: {e} (None has no TOML form: leave the key out)"))
    })?;
    merge(&mut table, overrides);
    let merged = toml::to_string(&table).map_err(error)?;
    Scenario::from_toml_str(&merged)
        .map_err(|e| GsensError::new_err(format!("{name} with the overrides: {}", crate::message(&e))))
}

/// `over` merged into `base`: tables key by key, anything else replaced.
fn merge(base: &mut toml::Table, over: toml::Table) {
    for (k, v) in over {
        match (base.get_mut(&k), v) {
            (Some(toml::Value::Table(b)), toml::Value::Table(o)) => merge(b, o),
            (_, v) => {
                base.insert(k, v);
            }
        }
    }
}

/// Simulates a calibration session (the paper's experiment by default):
/// returns a dict with `imu` and `tracking` (dicts of 1-D arrays named as the
/// CSV columns `gsens simulate` writes), `truth` (truth.json as a dict) and
/// `scenario` (the scenario as run, TOML). The same seed gives the same arrays.
#[pyfunction]
#[pyo3(signature = (scenario=None, seed=1, **overrides))]
pub(crate) fn simulate<'py>(
    py: Python<'py>,
    scenario: Option<PathBuf>,
    seed: u64,
    overrides: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyDict>> {
    let scenario = scenario_with(scenario.as_ref(), json_object(overrides)?)?;
    let logs = py.detach(|| gsens_sim::simulate_logs(&scenario, seed)).map_err(error)?;
    let out = PyDict::new(py);
    let imu = PyDict::new(py);
    imu.set_item("t_s", PyArray1::from_slice(py, &logs.imu.t_s))?;
    for (i, name) in ["fx_mps2", "fy_mps2", "fz_mps2"].into_iter().enumerate() {
        imu.set_item(name, PyArray1::from_iter(py, logs.imu.accel_mps2.iter().map(|a| a[i])))?;
    }
    out.set_item("imu", imu)?;
    // The rows in the order of tracking.csv: by time, then channel.
    let mut rows: Vec<(f64, u32, u32, f64, f64, f64)> = Vec::new();
    for t in logs.tracking.tracks() {
        for k in 0..t.len() {
            rows.push((t.t_s[k], t.channel, t.prn, t.cn0_dbhz[k], t.elev_deg[k], t.phase_err_rad[k]));
        }
    }
    rows.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let tracking = PyDict::new(py);
    tracking.set_item("t_s", PyArray1::from_iter(py, rows.iter().map(|r| r.0)))?;
    tracking.set_item("channel", PyArray1::from_iter(py, rows.iter().map(|r| i64::from(r.1))))?;
    tracking.set_item("prn", PyArray1::from_iter(py, rows.iter().map(|r| i64::from(r.2))))?;
    tracking.set_item("cn0_dbhz", PyArray1::from_iter(py, rows.iter().map(|r| r.3)))?;
    tracking.set_item("elev_deg", PyArray1::from_iter(py, rows.iter().map(|r| r.4)))?;
    tracking.set_item("phase_err_rad", PyArray1::from_iter(py, rows.iter().map(|r| r.5)))?;
    out.set_item("tracking", tracking)?;
    out.set_item("truth", py_of_json(py, &serde_json::to_string(&logs.truth).map_err(error)?)?)?;
    out.set_item("scenario", scenario.to_toml_string())?;
    Ok(out)
}

/// Simulates `runs` sessions (seeds `seed`, `seed + 1`, …) in parallel and
/// estimates each with every method of `methods`, under the scenario's own
/// loop with its bandwidth stated `stated_bn_scale` times the true one
/// (`None`: no loop stated), as `gsens montecarlo`; the loop-free estimate is
/// one more row where the scenario logs the NCO's phase. Returns its JSON
/// document as a dict (statistics per method and every run's estimates).
#[pyfunction]
#[pyo3(signature = (scenario=None, runs=20, seed=1, methods=vec!["batch".to_string()], stated_bn_scale=Some(1.0), overrides=None, **settings))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn montecarlo<'py>(
    py: Python<'py>,
    scenario: Option<PathBuf>,
    runs: u64,
    seed: u64,
    methods: Vec<String>,
    stated_bn_scale: Option<f64>,
    overrides: Option<&Bound<'py, PyDict>>,
    settings: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyAny>> {
    let name = scenario.as_ref().map_or("default".to_string(), |p| p.display().to_string());
    let scenario = scenario_with(scenario.as_ref(), json_object(overrides)?)?;
    let options = options(settings)?;
    if options.loop_stated() {
        return Err(GsensError::new_err(
            "montecarlo models the scenario's own loop: leave out order, bn_hz and the like (stated_bn_scale misstates it)",
        ));
    }
    let mut names = Vec::new();
    for m in &methods {
        names.push(
            serde_json::from_value(serde_json::Value::String(m.clone()))
                .map_err(|e| GsensError::new_err(format!("methods: {e}")))?,
        );
    }
    let pipelines = gsens_montecarlo::method_settings(&scenario, &options, &names, stated_bn_scale).map_err(error)?;
    let mc =
        py.detach(|| gsens_montecarlo::monte_carlo(&scenario, &name, runs, seed, &pipelines, || {})).map_err(error)?;
    py_of_json(py, &serde_json::to_string(&mc).map_err(error)?)
}
