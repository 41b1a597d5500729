//! The one result document: what `gsens estimate --json`, `report.json`, the
//! text report and the bindings all serialize (keys in
//! `docs/conventions.md#result-document`).

use crate::pipeline::{LoopIdentificationMode, Outcome, TimeOffset};
use crate::{Calibration, DISCRIMINATOR_LINEAR_RANGE_RAD};
use gsens_core::LoopModel;
use gsens_gnss_sdr::ImportSettings;
use gsens_gnss_sdr::import::TrackSummary;
use gsens_session::{ChannelSummary, SelectionConfig};
use serde::Serialize;
use std::collections::BTreeMap;

/// The loop a calibration modelled and what it implies for the shaking.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[non_exhaustive]
pub struct LoopSummary {
    /// The loop in words.
    pub description: String,
    /// Loop order.
    pub order: u8,
    /// Natural frequency ωn/2π \[Hz\].
    pub natural_frequency_hz: Option<f64>,
    /// Frequency of the peak of |L| \[Hz\].
    pub peak_hz: Option<f64>,
    /// |L| at the peak \[rad/Hz\].
    pub peak_rad_per_hz: Option<f64>,
    /// The shaking period that excites the loop most, 1/peak_hz \[s\].
    pub recommended_period_s: Option<f64>,
    /// Where |L| is above peak/√2 \[Hz\].
    pub half_power_band_hz: Option<[f64; 2]>,
}

impl LoopSummary {
    /// The summary of `model` (peak and band `None` for a loop without one).
    pub fn of(model: &LoopModel) -> Self {
        let peak = model.peak().ok();
        LoopSummary {
            description: model.to_string(),
            order: model.order(),
            natural_frequency_hz: model.natural_frequency_hz(),
            peak_hz: peak.map(|p| p.f_hz),
            peak_rad_per_hz: peak.map(|p| p.rad_per_hz),
            recommended_period_s: peak.map(|p| p.period_s()),
            half_power_band_hz: model.half_power_band_hz().ok(),
        }
    }
}

/// A condition the user should know about before trusting the estimate.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Warning {
    /// Stable identifier, e.g. `discriminator_range`.
    pub code: &'static str,
    /// What was found, why it matters and what to do.
    pub message: String,
}

/// What the GNSS-SDR conversion did (sessions from GNSS-SDR dumps).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GnssSdrConversion {
    /// The conversion settings (thresholds, the tracking configuration).
    pub conversion: ImportSettings,
    /// Every track found and what became of it.
    pub tracks: Vec<TrackSummary>,
}

/// How the session-level settings were applied.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PipelineSummary {
    /// The IMU time offset setting.
    pub time_offset: TimeOffset,
    /// Loop identification setting.
    pub loop_identification: LoopIdentificationMode,
}

/// Who wrote a report, when and with which figures (`report.json` only).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ReportInfo {
    /// When the report was generated, UTC.
    pub generated_utc: String,
    /// The producing tool and version.
    pub tool: String,
    /// Heading of the report.
    pub title: String,
    /// The figures shown, as (id, title).
    pub figures: Vec<FigureInfo>,
}

/// One figure of a report.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FigureInfo {
    /// Identifier and file stem.
    pub id: String,
    /// Heading.
    pub title: String,
}

/// The result of a calibration, as every output serializes it: the estimate
/// ([`Calibration`], its keys at the top level), the loop, the channels and
/// their screening, the warnings, the inputs and the tool.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[non_exhaustive]
pub struct ResultDocument {
    /// The producing library and version, e.g. `gsens 0.1.0`.
    pub tool: String,
    /// The estimate (flattened: its keys are the document's).
    #[serde(flatten)]
    pub calibration: Calibration,
    /// The loop modelled, its peak and band.
    #[serde(rename = "loop")]
    pub loop_summary: LoopSummary,
    /// Warnings: conditions under which the estimate may not hold.
    pub warnings: Vec<Warning>,
    /// Every track of the log and what became of it.
    pub channels: Vec<ChannelSummary>,
    /// The channel selection used.
    pub selection: SelectionConfig,
    /// The session-level settings.
    pub pipeline: PipelineSummary,
    /// The inputs as role → path.
    pub inputs: BTreeMap<String, String>,
    /// The true Γ \[Hz/(m/s²)\] when known (simulated sessions).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub truth_gamma_hz_per_mps2: Option<[f64; 3]>,
    /// The GNSS-SDR conversion, for sessions from GNSS-SDR dumps.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gnss_sdr: Option<GnssSdrConversion>,
    /// Report metadata (`report.json`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub report: Option<ReportInfo>,
}

/// This library's name and version.
pub fn tool_version() -> String {
    format!("gsens {}", env!("CARGO_PKG_VERSION"))
}

impl ResultDocument {
    /// The document of `outcome`.
    pub fn new(outcome: &Outcome, inputs: &[(&str, &str)], truth_gamma_hz_per_mps2: Option<[f64; 3]>) -> Self {
        let pipeline = PipelineSummary {
            time_offset: outcome.settings.time_offset,
            loop_identification: outcome.settings.loop_identification,
        };
        let mut doc = Self::from_parts(
            outcome.calibration.clone(),
            outcome.session.channels.clone(),
            outcome.session.selection.clone(),
            pipeline,
            inputs,
            truth_gamma_hz_per_mps2,
        );
        doc.gnss_sdr = outcome.gnss_sdr.clone();
        let inputs = crate::checks::input_warnings(outcome, &doc.calibration, &doc.loop_summary);
        doc.warnings.extend(inputs);
        if let Some(first) = outcome.imu_spikes_t_s.first() {
            doc.warnings.push(Warning {
                code: "imu_spikes",
                message: format!(
                    "{} isolated IMU sample(s) no hand motion can produce (the first at {first} s) were replaced by \
                     the mean of their neighbours; check the IMU and its logger",
                    outcome.imu_spikes_t_s.len()
                ),
            });
        }
        doc
    }

    /// The document of a calibration estimated from an epoch series the
    /// caller prepared (`channels` and `selection` describe how).
    pub fn from_parts(
        calibration: Calibration,
        channels: Vec<ChannelSummary>,
        selection: SelectionConfig,
        pipeline: PipelineSummary,
        inputs: &[(&str, &str)],
        truth_gamma_hz_per_mps2: Option<[f64; 3]>,
    ) -> Self {
        ResultDocument {
            tool: tool_version(),
            loop_summary: LoopSummary::of(&calibration.loop_used),
            warnings: warnings(&calibration),
            calibration,
            channels,
            selection,
            pipeline,
            inputs: inputs.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect(),
            truth_gamma_hz_per_mps2,
            gnss_sdr: None,
            report: None,
        }
    }

    /// Writes [`ResultDocument::to_json_string`] to `path`.
    pub fn write_json_file(&self, path: &std::path::Path) -> std::io::Result<()> {
        std::fs::write(path, self.to_json_string().map_err(std::io::Error::other)?)
    }

    /// The document as pretty-printed JSON with a final newline.
    pub fn to_json_string(&self) -> Result<String, serde_json::Error> {
        Ok(serde_json::to_string_pretty(self)? + "\n")
    }
}

/// The warnings a calibration's own numbers raise.
fn warnings(c: &Calibration) -> Vec<Warning> {
    let mut w = Vec::new();
    let (peak, lin) = (c.predicted_peak_phase_err_rad, DISCRIMINATOR_LINEAR_RANGE_RAD);
    if peak > lin {
        w.push(Warning {
            code: "discriminator_range",
            message: format!(
                "the predicted g-induced phase error reaches {peak:.2} rad, beyond the discriminator's linear range \
                 ({lin:.2} rad): shake more gently or the loss of discriminator gain biases Γ̂ low"
            ),
        });
    }
    if let Some(id) = c.loop_identification.filter(|id| id.assumed_loop_rejected) {
        w.push(Warning {
            code: "loop_rejected",
            message: format!(
                "the data reject the stated loop (likelihood ratio {:.1}): the identified loop, ωn/2π = {:.4} Hz \
                 instead of {:.4} Hz, was used; check the receiver's loop settings",
                id.likelihood_ratio, id.natural_frequency_hz, id.assumed_natural_frequency_hz
            ),
        });
    }
    w
}
