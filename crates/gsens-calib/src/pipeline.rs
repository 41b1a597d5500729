//! The whole calibration from logs: prepare the session (grid, screening,
//! averaging), estimate the systematic errors asked for (time offset, loop),
//! estimate Γ, and describe it all in one [`ResultDocument`].

use crate::document::{GnssSdrConversion, ResultDocument};
use crate::{CalibError, Calibration, EpochSeries, EstimateSettings, calibrate, estimate_time_offset, identify_loop};
use gsens_core::LoopModel;
use gsens_gnss_sdr::{GnssSdrError, ImportSettings, Imported, import_dir, resample};
use gsens_io::{FormatError, ImuSeries, TrackingLog};
use gsens_session::{PreparedSession, SelectionConfig, despike_imu, prepare_session, reinterpolate_imu};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// How the IMU/tracking time offset (IMU time stamp minus true time) is handled.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "mode", rename_all = "lowercase")]
pub enum TimeOffset {
    /// Estimated jointly with Γ within ±`max_abs_s`.
    Auto {
        /// Search range ± \[s\].
        max_abs_s: f64,
    },
    /// Taken as given.
    Fixed {
        /// IMU time stamp minus true time \[s\].
        imu_time_offset_s: f64,
    },
}

impl core::str::FromStr for TimeOffset {
    type Err = ParseTimeOffsetError;

    /// `auto` (searched within ±0.25 s), `none` (0) or a number of seconds.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "auto" => Ok(TimeOffset::default()),
            "none" => Ok(TimeOffset::Fixed { imu_time_offset_s: 0.0 }),
            _ => match s.parse::<f64>() {
                Ok(v) if v.is_finite() => Ok(TimeOffset::Fixed { imu_time_offset_s: v }),
                _ => Err(ParseTimeOffsetError(s.to_string())),
            },
        }
    }
}

/// A time offset that is neither `auto`, `none` nor a finite number of seconds.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("expected auto, none or a number of seconds, got `{0}`")]
pub struct ParseTimeOffsetError(pub String);

impl Default for TimeOffset {
    fn default() -> Self {
        TimeOffset::Auto { max_abs_s: 0.25 }
    }
}

/// Whether the loop's natural frequency (and damping) are identified from the data.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LoopIdentificationMode {
    /// The stated loop is used as it is.
    #[default]
    Off,
    /// The natural frequency is identified jointly with Γ (and the time offset);
    /// the identified loop is used when the data reject the stated one.
    NaturalFrequency,
    /// The natural frequency and a 2nd-order loop's damping.
    NaturalFrequencyAndDamping,
}

/// Everything that decides a calibration from logs.
///
/// Start from [`PipelineSettings::default`] and set what differs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
#[non_exhaustive]
pub struct PipelineSettings {
    /// The estimation stage: loop, estimator, error model.
    pub estimate: EstimateSettings,
    /// Which channels enter the average, and how.
    pub selection: SelectionConfig,
    /// The IMU time offset.
    pub time_offset: TimeOffset,
    /// Loop identification.
    pub loop_identification: LoopIdentificationMode,
    /// Replace isolated IMU spikes by the mean of their neighbours before
    /// anything else ([`gsens_session::despike_imu`]; default on).
    pub despike_imu: bool,
}

impl Default for PipelineSettings {
    fn default() -> Self {
        PipelineSettings {
            estimate: EstimateSettings::default(),
            selection: SelectionConfig::default(),
            time_offset: TimeOffset::default(),
            loop_identification: LoopIdentificationMode::default(),
            despike_imu: true,
        }
    }
}

/// Why a calibration from logs could not run.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PipelineError {
    /// A log could not be read or does not hold the format.
    #[error(transparent)]
    Format(#[from] FormatError),
    /// The session could not be prepared from the logs.
    #[error(transparent)]
    Session(#[from] gsens_session::SessionError),
    /// GNSS-SDR's dumps or configuration could not be read.
    #[error(transparent)]
    GnssSdr(#[from] GnssSdrError),
    /// A stage of the estimation failed.
    #[error("{stage}: {source}")]
    Stage {
        /// What was being done.
        stage: &'static str,
        /// Why it failed.
        source: CalibError,
    },
    /// The estimation failed.
    #[error(transparent)]
    Calib(#[from] CalibError),
    /// The time-offset search ended at its limit.
    #[error(
        "the IMU time offset search ended at its limit ({found_s:+.3} s): the offset may be larger than the search \
         range ±{max_abs_s} s; widen the search or state the offset"
    )]
    TimeOffsetAtLimit {
        /// Where the search ended \[s\].
        found_s: f64,
        /// The search range \[s\].
        max_abs_s: f64,
    },
}

/// A calibration from logs: the prepared session it was estimated from and
/// the estimate.
#[derive(Debug, Clone)]
#[non_exhaustive]
pub struct Outcome {
    /// The estimator's inputs on the epoch grid, with every channel's fate.
    pub session: PreparedSession,
    /// The estimate.
    pub calibration: Calibration,
    /// The settings it ran with.
    pub settings: PipelineSettings,
    /// What the GNSS-SDR conversion did, for sessions from GNSS-SDR dumps.
    pub gnss_sdr: Option<GnssSdrConversion>,
    /// Time stamps of the IMU samples replaced as isolated spikes \[s\].
    pub imu_spikes_t_s: Vec<f64>,
    /// The inputs as role → path (`imu`, `tracking`, `gnss_sdr_dumps`, …);
    /// empty for logs given in memory. Callers may add their own (`truth`).
    pub inputs: Vec<(String, String)>,
}

impl Outcome {
    /// The estimator's view of the prepared session.
    pub fn series(&self) -> EpochSeries<'_> {
        series_of(&self.session)
    }

    /// The result document of this calibration (with the true Γ when known).
    pub fn document(&self, truth_gamma_hz_per_mps2: Option<[f64; 3]>) -> ResultDocument {
        let inputs: Vec<(&str, &str)> = self.inputs.iter().map(|(k, v)| (k.as_str(), v.as_str())).collect();
        ResultDocument::new(self, &inputs, truth_gamma_hz_per_mps2)
    }
}

/// The estimator's view of a prepared session.
pub fn series_of(s: &PreparedSession) -> EpochSeries<'_> {
    EpochSeries {
        log_interval_s: s.log_interval_s,
        t_s: &s.t_s,
        phase_err_rad: &s.phase_err_rad,
        accel_mps2: &s.accel_mps2,
        imu_time_offset_s: s.imu_time_offset_s,
    }
}

/// Calibrates from a tracking log and an IMU series in memory (`imu_name`
/// names the IMU source in errors): prepares the session, identifies the loop
/// and estimates the time offset as `settings` ask, and estimates Γ.
pub fn calibrate_logs(
    tracking: &TrackingLog,
    imu: &ImuSeries,
    imu_name: &str,
    settings: &PipelineSettings,
) -> Result<Outcome, PipelineError> {
    settings.estimate.validate()?;
    let (assumed, max_abs_s) = match settings.time_offset {
        TimeOffset::Fixed { imu_time_offset_s } => {
            if !imu_time_offset_s.is_finite() {
                let expected = "finite";
                return Err(
                    CalibError::Setting { name: "imu_time_offset_s", value: imu_time_offset_s, expected }.into()
                );
            }
            (imu_time_offset_s, None)
        }
        TimeOffset::Auto { max_abs_s } => {
            crate::settings::check_range("time_offset.max_abs_s", max_abs_s, true)?;
            (0.0, Some(max_abs_s))
        }
    };
    let (despiked, spikes) = if settings.despike_imu { despike_imu(imu) } else { (imu.clone(), Default::default()) };
    let imu = &despiked;
    let mut session = prepare_session(tracking, imu, imu_name, &settings.selection, assumed)?;
    let mut estimate = settings.estimate;
    let mut identification = None;
    if settings.loop_identification != LoopIdentificationMode::Off {
        // A loop error mimics a time offset: with `Auto` both are searched together.
        let damping = settings.loop_identification == LoopIdentificationMode::NaturalFrequencyAndDamping;
        let id = identify_loop(&series_of(&session), &estimate, damping, max_abs_s)
            .map_err(|source| PipelineError::Stage { stage: "identifying the loop", source })?;
        if id.assumed_loop_rejected {
            estimate.receiver_loop = id.identified(&estimate.receiver_loop);
        }
        identification = Some(id);
    }
    let mut offset_sigma = None;
    if let Some(max_abs_s) = max_abs_s {
        let found = estimate_time_offset(&series_of(&session), &estimate, max_abs_s)
            .map_err(|source| PipelineError::Stage { stage: "estimating the IMU time offset", source })?;
        if (found.imu_time_offset_s - assumed).abs() >= max_abs_s * 0.999 {
            return Err(PipelineError::TimeOffsetAtLimit { found_s: found.imu_time_offset_s, max_abs_s });
        }
        reinterpolate_imu(&mut session, imu, found.imu_time_offset_s);
        offset_sigma = Some(found.sigma_s);
    }
    let mut calibration = calibrate(&series_of(&session), &estimate)?;
    calibration.imu_time_offset_estimated = offset_sigma.is_some();
    calibration.imu_time_offset_sigma_s = offset_sigma;
    calibration.loop_identification = identification;
    Ok(Outcome {
        session,
        calibration,
        settings: settings.clone(),
        gnss_sdr: None,
        imu_spikes_t_s: spikes.t_s,
        inputs: Vec::new(),
    })
}

/// [`calibrate_logs`] on files: `imu.csv` and `tracking.csv`.
pub fn calibrate_files(tracking: &Path, imu: &Path, settings: &PipelineSettings) -> Result<Outcome, PipelineError> {
    let tracking_log = gsens_io::read_tracking_file(tracking)?;
    let imu_series = gsens_io::read_imu_file(imu)?;
    let mut outcome = calibrate_logs(&tracking_log, &imu_series, &imu.display().to_string(), settings)?;
    outcome.inputs = vec![input("imu", imu), input("tracking", tracking)];
    Ok(outcome)
}

fn input(role: &str, path: &Path) -> (String, String) {
    (role.to_string(), path.display().to_string())
}

/// The tracking log of GNSS-SDR dumps on their common grid (every track
/// resampled at t = j·T, T the modelled stage's integration).
pub fn gnss_sdr_tracking_log(dir: &Path, imported: &Imported) -> Result<TrackingLog, FormatError> {
    let rows = resample(imported, imported.interval_s);
    let name = format!("{} (GNSS-SDR dumps on a {} ms grid)", dir.display(), imported.interval_s * 1e3);
    TrackingLog::from_rows(&name, &rows)
}

/// Calibrates from GNSS-SDR tracking dumps (`Tracking_1C.dump=true`) and an
/// IMU log, with GNSS-SDR's own carrier loop modelled exactly: the loop and
/// logged-phase settings of `settings` are replaced by the ones the dumps
/// were made with, and the warm-up is at least
/// [`ImportSettings::models_warmup_s`] (the regressor models' start-up error).
pub fn calibrate_gnss_sdr(
    dumps_dir: &Path,
    import: &ImportSettings,
    imu: &Path,
    settings: &PipelineSettings,
) -> Result<Outcome, PipelineError> {
    let imported = import_dir(dumps_dir, import)?;
    let tracking_log = gnss_sdr_tracking_log(dumps_dir, &imported)?;
    let imu_series = gsens_io::read_imu_file(imu)?;
    let mut settings = settings.clone();
    settings.estimate.receiver_loop = LoopModel::GnssSdr(import.stage());
    settings.estimate.logged_phase = gsens_core::LoggedPhase::Last;
    // The regressor models start at the first kept record, possibly while
    // the board is shaken: their start-up error, computed from the IMU, is
    // left to the warm-up (ImportSettings::models_warmup_s).
    if let Some(start_s) = tracking_log.epoch_t_s().first() {
        let w = import.models_warmup_s(&imu_series, *start_s, settings.estimate.highpass_hz);
        settings.estimate.warmup_s = settings.estimate.warmup_s.max(w);
    }
    let mut outcome = calibrate_logs(&tracking_log, &imu_series, &imu.display().to_string(), &settings)?;
    outcome.gnss_sdr = Some(GnssSdrConversion { conversion: import.clone(), tracks: imported.tracks });
    outcome.inputs = vec![input("imu", imu), input("gnss_sdr_dumps", dumps_dir)];
    Ok(outcome)
}
