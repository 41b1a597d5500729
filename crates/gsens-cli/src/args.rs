//! The command-line options shared by the commands, and the one place where
//! they become library objects: a calibration's options are
//! `gsens_calib::CalibrationOptions`' groups (the names the Python module
//! takes too, which build `gsens_calib::PipelineSettings`); the converters'
//! are `gsens_gnss_sdr::ImportOverrides` and `gsens_pocketsdr::ImportOptions`;
//! the input options become `gsens_inputs::InputChoice`.

use anyhow::{Result, anyhow};
use clap::Args;
use gsens_calib::option_values::positive;
use gsens_calib::{
    CalibrationOptions, EstimatorOptions, LoopOptions, MeasurementChoice, MethodName, PipelineSettings,
    SelectionOptions, SystematicOptions,
};
use gsens_gnss_sdr::{GnssSdrError, ImportOverrides};
use gsens_inputs::{InputChoice, InputsError, Route};
use std::path::PathBuf;

/// The flag of the option `name` (`bn_hz` is `--bn-hz`).
pub(crate) fn flag(name: &str) -> String {
    format!("--{}", name.replace('_', "-"))
}

/// A library's error about the setting `setting` (its message begins with
/// the setting's name) with the setting given as its flag, `--{prefix}{name}`.
pub(crate) fn flagged<E>(prefix: &str, setting: Option<&str>, e: E) -> anyhow::Error
where
    E: std::error::Error + Send + Sync + 'static,
{
    match setting {
        Some(name) => anyhow!("--{prefix}{}{}", name.replace('_', "-"), &e.to_string()[name.len()..]),
        None => e.into(),
    }
}

/// The simulated scenario and its seed (`demo`, `simulate`, `montecarlo`).
#[derive(Args, Debug, Clone)]
pub(crate) struct ScenarioArgs {
    /// Scenario TOML (default: the embedded paper experiment; see `gsens scenario`).
    #[arg(long)]
    pub scenario: Option<PathBuf>,
    /// Seed of every random draw (same seed, same bytes; Monte Carlo run i uses seed + i).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
}

impl ScenarioArgs {
    /// The scenario: the file's, or the embedded default.
    pub(crate) fn load(&self) -> Result<gsens_sim::scenario::Scenario> {
        Ok(gsens_sim::load_scenario(self.scenario.as_deref())?)
    }
}

/// The options of a single calibration besides its receiver loop (`estimate`,
/// `report`, `live`, `demo`).
#[derive(Args, Debug, Clone)]
pub(crate) struct AnalysisArgs {
    /// Estimator.
    #[arg(long, value_enum, default_value_t, help_heading = "Estimator")]
    pub method: MethodName,
    /// What the estimate is made from: the loop's input phase (loop-free, no loop model) where the log
    /// holds the NCO's phase, else the tracking error through the loop model.
    #[arg(long, value_enum, default_value_t, help_heading = "Estimator")]
    pub measurement: MeasurementChoice,
    #[command(flatten)]
    pub estimator: EstimatorOptions,
    #[command(flatten)]
    pub selection: SelectionOptions,
    #[command(flatten)]
    pub systematic: SystematicOptions,
}

impl AnalysisArgs {
    /// The options of a calibration with the loop at its default.
    pub(crate) fn options(&self) -> CalibrationOptions {
        CalibrationOptions {
            method: self.method,
            measurement: self.measurement,
            estimator: self.estimator.clone(),
            selection: self.selection.clone(),
            systematic: self.systematic.clone(),
            ..CalibrationOptions::default()
        }
    }
}

/// The options that decide a calibration from logs (`estimate`, `report`, `live`).
#[derive(Args, Debug, Clone)]
pub(crate) struct CalibrationArgs {
    /// Carrier frequency [Hz] for ppb/g (default GPS L1).
    #[arg(long, default_value_t = gsens_core::units::GPS_L1_HZ, allow_negative_numbers = true, value_parser = positive)]
    pub carrier_hz: f64,
    #[command(flatten)]
    pub receiver_loop: LoopOptions,
    #[command(flatten)]
    pub analysis: AnalysisArgs,
}

impl CalibrationArgs {
    /// The options by name.
    pub(crate) fn options(&self) -> CalibrationOptions {
        CalibrationOptions {
            carrier_hz: self.carrier_hz,
            receiver_loop: self.receiver_loop.clone(),
            ..self.analysis.options()
        }
    }

    /// The pipeline settings (every value checked; options `given` that the
    /// loop or the method ignores refused).
    pub(crate) fn settings(&self, given: &[&str]) -> Result<PipelineSettings> {
        let options = self.options();
        options.refuse_ignored(given, flag)?;
        Ok(options.pipeline_settings()?)
    }
}

/// How GNSS-SDR dump records are selected (`import gnss-sdr`).
#[derive(Args, Debug, Clone)]
#[command(next_help_heading = "GNSS-SDR dumps")]
pub(crate) struct ConversionArgs {
    /// Sampling rate of the tracking [Hz] when the configuration does not give it.
    #[arg(long, allow_negative_numbers = true, value_parser = positive)]
    pub gnss_sdr_fs_hz: Option<f64>,
    #[command(flatten)]
    pub overrides: ImportOverrides,
}

/// A receiver's conversion error with the setting it is about given as its
/// flag (`--gnss-sdr-…`, `--pocketsdr-…`).
pub(crate) fn conversion_error(e: InputsError) -> anyhow::Error {
    match e {
        InputsError::GnssSdr(GnssSdrError::UnknownSamplingRate) => anyhow!("{e}; give --gnss-sdr-fs-hz"),
        InputsError::GnssSdr(e) => flagged("gnss-sdr-", e.setting(), e),
        InputsError::PocketSdr(e) => flagged("pocketsdr-", e.setting(), e),
        e => e.into(),
    }
}

/// The route of the inputs `choice` names (a RINEX or UBX log, else the
/// tracking route), with its conversion settings.
pub(crate) fn route(choice: &InputChoice) -> Result<Route> {
    choice.route(flag).map_err(conversion_error)
}
