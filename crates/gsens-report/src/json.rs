//! The report as JSON: the result document ([`gsens_calib::ResultDocument`],
//! the same as `gsens estimate --json`) with its `report` block filled in:
//! `generated_utc`, `tool`, `title` and the `figures` shown.

use crate::ReportData;
use gsens_calib::{FigureInfo, ReportInfo};

/// The report's result document as a JSON value.
pub fn report_json(data: &ReportData) -> Result<serde_json::Value, serde_json::Error> {
    let mut doc = data.document.clone();
    doc.report = Some(ReportInfo {
        generated_utc: data.meta.generated_utc.clone(),
        tool: data.meta.tool.clone(),
        title: data.title.clone(),
        figures: data.figures.iter().map(|f| FigureInfo { id: f.id.clone(), title: f.title.clone() }).collect(),
    });
    serde_json::to_value(&doc)
}

/// [`report_json`] pretty-printed, with a final newline.
pub fn report_json_string(data: &ReportData) -> Result<String, serde_json::Error> {
    Ok(serde_json::to_string_pretty(&report_json(data)?)? + "\n")
}
