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
use gsens_inputs::{InputChoice, Inputs, InputsError, ObservationInputs};
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

/// How GNSS-SDR dump records are selected.
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

/// Where a calibration's logs come from (`estimate`, `report`): an IMU log
/// with a tracking log, GNSS-SDR dumps or a PocketSDR log.
#[derive(Args, Debug, Clone)]
pub(crate) struct InputArgs {
    /// IMU log: t_s,fx_mps2,fy_mps2,fz_mps2 (beside a RINEX file: t_s in GPS seconds of the week of
    /// its first epoch; with --ubx, instead of the module's own accelerometer).
    #[arg(long, required_unless_present = "ubx")]
    pub imu: Option<PathBuf>,
    /// Tracking log: t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad (or --gnss-sdr, --pocketsdr,
    /// --rinex, --ubx).
    #[arg(
        long,
        required_unless_present_any = ["gnss_sdr", "pocketsdr", "rinex", "ubx"],
        conflicts_with_all = ["gnss_sdr", "pocketsdr", "rinex", "ubx"]
    )]
    pub tracking: Option<PathBuf>,
    /// Directory of GNSS-SDR tracking dumps (trk_ch_N.dat, Tracking_1C.dump=true) to use instead of --tracking.
    #[arg(long, requires = "gnss_sdr_conf")]
    pub gnss_sdr: Option<PathBuf>,
    /// The GNSS-SDR configuration file the dumps were made with (its loop is modelled exactly).
    /// With --tracking instead of --gnss-sdr: rows that came from that GNSS-SDR run another way
    /// (`gsens import gnss-sdr-monitor`), estimated with its exact loop.
    #[arg(long)]
    pub gnss_sdr_conf: Option<PathBuf>,
    #[command(flatten)]
    pub gnss_sdr_conversion: ConversionArgs,
    /// A pocket_trk log (-log FILE, its $CH lines) to use instead of --tracking; PocketSDR's
    /// carrier loop is modelled exactly.
    #[arg(long, conflicts_with = "gnss_sdr")]
    pub pocketsdr: Option<PathBuf>,
    #[command(flatten)]
    pub pocketsdr_conversion: gsens_pocketsdr::ImportOptions,
    /// A RINEX observation file (3.x, 2.11, Hatanaka) of a receiver that logs carrier phase or
    /// Doppler but no tracking error: its loop is identified from the session.
    #[arg(long, conflicts_with_all = ["gnss_sdr", "pocketsdr", "ubx"], help_heading = "Carrier phase and Doppler logs")]
    pub rinex: Option<PathBuf>,
    /// A u-blox UBX log (RXM-RAWX; the module's accelerometer from ESF-RAW / ESF-MEAS unless
    /// --imu is given): its loop is identified from the session.
    #[arg(long, conflicts_with_all = ["gnss_sdr", "pocketsdr"], help_heading = "Carrier phase and Doppler logs")]
    pub ubx: Option<PathBuf>,
    /// What the estimate from a RINEX or UBX log is made from: the carrier phase differenced, the
    /// Doppler, or auto (the carrier phase where most tracks have one).
    #[arg(long, value_enum, default_value_t, help_heading = "Carrier phase and Doppler logs")]
    pub observable: gsens_calib::ObservationRecord,
    /// How the UBX log's ESF sensor time tags map to GPS time: free-running-ms (a millisecond sensor
    /// clock, tied once to an RXM-RAWX epoch; the rest is the IMU offset searched) or gps-tow-ms
    /// (the tags count GPS time of week in ms, as rcvTow).
    #[arg(long, value_enum, default_value = "free-running-ms", help_heading = "Carrier phase and Doppler logs")]
    pub ubx_sensor_time: gsens_ublox::SensorTime,
}

impl InputArgs {
    /// The inputs the options name, with their conversion settings.
    pub(crate) fn inputs(&self) -> Result<Inputs> {
        self.choice().inputs(flag).map_err(conversion_error)
    }

    /// The carrier phase and Doppler route, where --rinex or --ubx is given.
    pub(crate) fn observations(&self) -> Option<Result<ObservationInputs>> {
        self.choice().observations(flag).map(|r| r.map_err(conversion_error))
    }

    fn choice(&self) -> InputChoice {
        InputChoice {
            imu: self.imu.clone().unwrap_or_default(),
            tracking: self.tracking.clone(),
            gnss_sdr: self.gnss_sdr.clone(),
            gnss_sdr_conf: self.gnss_sdr_conf.clone(),
            gnss_sdr_fs_hz: self.gnss_sdr_conversion.gnss_sdr_fs_hz,
            gnss_sdr_overrides: self.gnss_sdr_conversion.overrides.clone(),
            pocketsdr: self.pocketsdr.clone(),
            pocketsdr_options: self.pocketsdr_conversion.clone(),
            rinex: self.rinex.clone(),
            ubx: self.ubx.clone(),
            ubx_settings: gsens_ublox::UbxSettings { sensor_time: self.ubx_sensor_time },
            observation_record: self.observable,
        }
    }
}
