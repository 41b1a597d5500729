//! What the route tests share: the result document as JSON, a JSON file,
//! the default options' settings.

#![allow(dead_code)]

use gsens_calib::{CalibrationOptions, PipelineSettings};
use gsens_inputs::Calibrated;
use std::path::Path;

/// The JSON file at `path`.
pub(crate) fn json_file(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// The result document of a calibration, as its JSON.
pub(crate) fn document(c: &Calibrated) -> serde_json::Value {
    serde_json::from_str(&c.outcome.document(None).to_json_string().unwrap()).unwrap()
}

/// The settings of the default options.
pub(crate) fn defaults() -> PipelineSettings {
    CalibrationOptions::default().pipeline_settings().unwrap()
}
