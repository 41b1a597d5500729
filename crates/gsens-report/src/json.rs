//! The report as JSON.
//!
//! The shape of `gsens estimate --json` (every key of
//! [`gsens_calib::Calibration`], `channels`, `selection`, `inputs`,
//! `truth_gamma_hz_per_mps2` when known) plus a `report` object:
//! `generated_utc`, `tool`, `title` and the `figures` shown.

use crate::ReportData;
use serde_json::{Map, Value, json};

/// The report as a JSON value.
pub fn report_json(data: &ReportData) -> Result<Value, serde_json::Error> {
    let mut v = serde_json::to_value(data.calibration)?;
    let obj = v.as_object_mut().ok_or_else(|| serde::ser::Error::custom("a calibration serializes to an object"))?;
    obj.insert("channels".into(), serde_json::to_value(&data.channels)?);
    obj.insert("selection".into(), data.selection.clone());
    let inputs: Map<String, Value> =
        data.meta.inputs.iter().map(|(k, p)| (k.clone(), Value::String(p.clone()))).collect();
    obj.insert("inputs".into(), inputs.into());
    if let Some(t) = data.truth {
        obj.insert("truth_gamma_hz_per_mps2".into(), serde_json::to_value(t)?);
    }
    obj.insert(
        "report".into(),
        json!({
            "generated_utc": data.meta.generated_utc,
            "tool": data.meta.tool,
            "title": data.title,
            "figures": data.figures.iter().map(|f| json!({"id": f.id, "title": f.title})).collect::<Vec<_>>(),
        }),
    );
    Ok(v)
}

/// [`report_json`] pretty-printed, with a final newline.
pub fn report_json_string(data: &ReportData) -> Result<String, serde_json::Error> {
    Ok(serde_json::to_string_pretty(&report_json(data)?)? + "\n")
}
