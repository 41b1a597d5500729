//! # gsens-inputs
//!
//! Where a calibration's logs come from, as one type: [`Inputs`] names every
//! route gsens reads (an IMU log with a tracking log, the same rows from a
//! GNSS-SDR run with its configuration, GNSS-SDR's tracking dumps, a
//! PocketSDR `pocket_trk` log), and [`Inputs::calibrate`] runs the pipeline
//! of `gsens_calib` for any of them, with the receiver's own loop modelled
//! exactly where the route knows it. What a route has to say besides the
//! estimate (what became of each track, which loop it modelled) comes back
//! in [`Calibrated`].
//!
//! The command line, the Python module and any other front end build an
//! [`Inputs`] from their own words — or name the files in an
//! [`InputChoice`], whose rule picks the route — and share everything after
//! that: a route added here works in all of them. A simulated session's
//! `truth.json` states the loop that made its log, which the settings take
//! when they state none ([`take_truth_loop`]) and the route does not model
//! its receiver's own ([`Route::truth_loop_note`]).
//!
//! The crate sits above `gsens_calib`, `gsens_gnss_sdr` and
//! `gsens_pocketsdr` (the PocketSDR crate itself depends on `gsens_calib`,
//! so the routes cannot all live there).

mod choice;
mod observations;
mod route;
mod truth;

pub use choice::InputChoice;
pub use observations::{ObservationFile, ObservationInputs, render_observation_summary};
pub use route::{Estimated, Route};
pub use truth::{TruthLoopUse, settings_of_simulated_session, take_truth_loop, truth_loop_note};

use gsens_calib::{Outcome, PipelineError, PipelineSettings};
use gsens_io::{FormatError, ImuSeries, TrackingLog};
use gsens_pocketsdr::PocketSdrError;
use std::path::{Path, PathBuf};

/// One log: a file, or a series already in memory.
#[derive(Debug, Clone)]
pub enum Log<T> {
    /// A CSV file in gsens's format (`imu.csv`, `tracking.csv`).
    File(PathBuf),
    /// A log already read or built; `name` is what errors call it.
    Memory {
        /// What errors call the log.
        name: String,
        /// The log.
        log: T,
    },
}

/// What the result document's inputs list says of a log held in memory.
pub const IN_MEMORY: &str = "in memory";

impl<T> Log<T> {
    /// The inputs list's entry of the log under `role`.
    fn input(&self, role: &str) -> (String, String) {
        let value = match self {
            Log::File(p) => p.display().to_string(),
            Log::Memory { .. } => IN_MEMORY.to_string(),
        };
        (role.to_string(), value)
    }
}

impl Log<ImuSeries> {
    /// The series and its name in errors.
    fn read(self) -> Result<(String, ImuSeries), FormatError> {
        match self {
            Log::File(p) => Ok((p.display().to_string(), gsens_io::read_imu_file(&p)?)),
            Log::Memory { name, log } => Ok((name, log)),
        }
    }
}

impl Log<TrackingLog> {
    fn read(self) -> Result<TrackingLog, FormatError> {
        match self {
            Log::File(p) => gsens_io::read_tracking_file(&p),
            Log::Memory { log, .. } => Ok(log),
        }
    }
}

/// The inputs of one calibration: which logs, from which receiver, and how
/// they are converted.
#[derive(Debug, Clone)]
#[non_exhaustive]
pub enum Inputs {
    /// An IMU log and a tracking log in gsens's format; the loop is the
    /// settings' (stated, or chosen by the data).
    Csv {
        /// The IMU log: `t_s,fx_mps2,fy_mps2,fz_mps2`.
        imu: Log<ImuSeries>,
        /// The tracking log: `t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad`.
        tracking: Log<TrackingLog>,
    },
    /// Tracking rows that came from a GNSS-SDR run by another path than its
    /// dumps (its tracking monitor), estimated with that run's loop
    /// ([`gsens_gnss_sdr::with_gnss_sdr_loop`]); the settings must not state a
    /// loop of their own.
    GnssSdrRows {
        /// The IMU log.
        imu: Log<ImuSeries>,
        /// The tracking rows.
        tracking: Log<TrackingLog>,
        /// The run's tracking configuration.
        import: gsens_gnss_sdr::ImportSettings,
        /// The configuration file it was read from (for the inputs list).
        conf: PathBuf,
    },
    /// GNSS-SDR's tracking dumps (`trk_ch_N.dat`) with the loop of the
    /// configuration they were made with ([`gsens_gnss_sdr::calibrate_gnss_sdr`]).
    GnssSdrDumps {
        /// The IMU log file.
        imu: PathBuf,
        /// The directory of the dumps.
        dumps_dir: PathBuf,
        /// How the dumps are converted (the configuration and what overrides it).
        import: gsens_gnss_sdr::ImportSettings,
        /// The configuration file (for the inputs list), when one was read.
        conf: Option<PathBuf>,
    },
    /// A PocketSDR `pocket_trk` log with PocketSDR's loop
    /// ([`gsens_pocketsdr::calibrate_pocketsdr`]).
    PocketSdr {
        /// The IMU log file.
        imu: PathBuf,
        /// The `pocket_trk -log` file.
        log: PathBuf,
        /// How the log is converted (its options file and what overrides it).
        import: gsens_pocketsdr::ImportSettings,
    },
}

/// Why a calibration from [`Inputs`] could not run.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum InputsError {
    /// A log could not be read.
    #[error(transparent)]
    Format(#[from] FormatError),
    /// The pipeline failed.
    #[error(transparent)]
    Pipeline(#[from] PipelineError),
    /// GNSS-SDR's dumps, their conversion or their calibration failed.
    #[error(transparent)]
    GnssSdr(#[from] gsens_gnss_sdr::GnssSdrError),
    /// The PocketSDR log or its conversion failed.
    #[error(transparent)]
    PocketSdr(#[from] PocketSdrError),
    /// A carrier phase and Doppler log (RINEX, UBX) could not be read: the
    /// reader's message, naming the file.
    #[error("{0}")]
    Observations(String),
    /// The inputs named are incomplete or name a conversion without its
    /// log ([`InputChoice::inputs`]; the message names the options).
    #[error("{0}")]
    Choice(String),
    /// A route that models its receiver's loop got settings that state
    /// another one.
    #[error("{conf}: the GNSS-SDR configuration states the receiver loop; the settings must leave it unstated")]
    LoopStatedTwice {
        /// The configuration that states the loop.
        conf: String,
    },
}

/// What a route did besides the estimate.
#[derive(Debug, Clone)]
#[non_exhaustive]
pub enum Conversion {
    /// Logs in gsens's format: nothing converted.
    None,
    /// GNSS-SDR rows (`None`) or dumps and what became of each of their
    /// tracks.
    GnssSdr(Option<Box<gsens_gnss_sdr::Conversion>>),
    /// A PocketSDR log and what became of each of its tracks.
    PocketSdr(Box<gsens_pocketsdr::Imported>),
}

/// A calibration from [`Inputs`]: the pipeline's outcome (with its inputs
/// list), what the route converted, and the tracking log when asked for.
#[derive(Debug, Clone)]
pub struct Calibrated {
    /// The calibration, its inputs list filled in.
    pub outcome: Outcome,
    /// What the route converted.
    pub conversion: Conversion,
    /// The tracking log the estimate was made from (a receiver's log as
    /// converted to gsens's rows), when [`Inputs::calibrate_keeping_tracking`]
    /// asked for it.
    pub tracking: Option<TrackingLog>,
}

impl Calibrated {
    /// What became of each track of a receiver's log (GNSS-SDR dumps,
    /// PocketSDR), as text; `None` for routes with nothing converted.
    pub fn track_summary(&self) -> Option<String> {
        match &self.conversion {
            Conversion::PocketSdr(imported) => Some(gsens_pocketsdr::render_summary(imported)),
            Conversion::GnssSdr(None) => None,
            Conversion::GnssSdr(Some(c)) => {
                Some(gsens_gnss_sdr::render_tracks(&c.tracks, self.outcome.session.log_interval_s))
            }
            Conversion::None => None,
        }
    }

    /// Which receiver's loop the route modelled exactly (`GNSS-SDR loop: …,
    /// modelled exactly`); `None` when the loop is the settings'.
    pub fn loop_note(&self) -> Option<String> {
        let receiver = match self.conversion {
            Conversion::GnssSdr(_) => "GNSS-SDR",
            Conversion::PocketSdr(_) => "PocketSDR",
            Conversion::None => return None,
        };
        Some(format!("{receiver} loop: {}, modelled exactly", self.outcome.calibration.loop_used))
    }
}

impl Inputs {
    /// Whether the route models its receiver's loop itself (from the
    /// receiver's configuration), replacing any loop of the settings.
    pub fn models_the_loop(&self) -> bool {
        !matches!(self, Inputs::Csv { .. })
    }

    /// Calibrates from these inputs under `settings`.
    pub fn calibrate(self, settings: &PipelineSettings) -> Result<Calibrated, InputsError> {
        self.run(settings, false)
    }

    /// [`Inputs::calibrate`], keeping the tracking log the estimate was made
    /// from in [`Calibrated::tracking`] (a report's C/N0 figures need it).
    pub fn calibrate_keeping_tracking(self, settings: &PipelineSettings) -> Result<Calibrated, InputsError> {
        self.run(settings, true)
    }

    fn run(self, settings: &PipelineSettings, keep_tracking: bool) -> Result<Calibrated, InputsError> {
        match self {
            Inputs::Csv { imu, tracking } => {
                let (outcome, tracking) = calibrate_logs(imu, tracking, settings, keep_tracking)?;
                Ok(Calibrated { outcome, conversion: Conversion::None, tracking })
            }
            Inputs::GnssSdrRows { imu, tracking, import, conf } => {
                if settings.loop_stated {
                    return Err(InputsError::LoopStatedTwice { conf: conf.display().to_string() });
                }
                let settings = gsens_gnss_sdr::with_gnss_sdr_loop(settings, &import);
                let (mut outcome, tracking) = calibrate_logs(imu, tracking, &settings, keep_tracking)?;
                outcome.inputs.push(path_input("gnss_sdr_conf", &conf));
                Ok(Calibrated { outcome, conversion: Conversion::GnssSdr(None), tracking })
            }
            Inputs::GnssSdrDumps { imu, dumps_dir, import, conf } => {
                let r = gsens_gnss_sdr::calibrate_gnss_sdr(&dumps_dir, &import, &imu, settings)?;
                let mut outcome = r.outcome;
                if let Some(conf) = &conf {
                    outcome.inputs.push(path_input("gnss_sdr_conf", conf));
                }
                let conversion = Conversion::GnssSdr(Some(Box::new(r.conversion)));
                Ok(Calibrated { outcome, conversion, tracking: keep_tracking.then_some(r.tracking) })
            }
            Inputs::PocketSdr { imu, log, import } => {
                let r = gsens_pocketsdr::calibrate_pocketsdr(&log, &import, &imu, settings)?;
                let tracking =
                    keep_tracking.then(|| gsens_pocketsdr::pocketsdr_tracking_log(&r.imported)).transpose()?;
                Ok(Calibrated { outcome: r.outcome, conversion: Conversion::PocketSdr(Box::new(r.imported)), tracking })
            }
        }
    }
}

fn path_input(role: &str, path: &Path) -> (String, String) {
    (role.to_string(), path.display().to_string())
}

/// The pipeline on an IMU log and a tracking log, the inputs list filled in;
/// with the tracking log when `keep_tracking` (otherwise it is freed as soon
/// as the session has its rows).
fn calibrate_logs(
    imu: Log<ImuSeries>,
    tracking: Log<TrackingLog>,
    settings: &PipelineSettings,
    keep_tracking: bool,
) -> Result<(Outcome, Option<TrackingLog>), InputsError> {
    let inputs = vec![imu.input("imu"), tracking.input("tracking")];
    if let (false, Log::File(imu), Log::File(tracking)) = (keep_tracking, &imu, &tracking) {
        // Both files read at once, the IMU log prepared while the tracking log is read.
        return Ok((gsens_calib::calibrate_files(tracking, imu, settings)?, None));
    }
    // The two logs are independent: each read as its own task, at once.
    let (imu, tracking) = rayon::join(|| imu.read(), || tracking.read());
    let ((imu_name, imu), tracking) = (imu?, tracking?);
    let (mut outcome, tracking) = if keep_tracking {
        (gsens_calib::calibrate_logs(&tracking, &imu, &imu_name, settings)?, Some(tracking))
    } else {
        (gsens_calib::calibrate_owned_logs(tracking, &imu, &imu_name, settings)?, None)
    };
    outcome.inputs = inputs;
    Ok((outcome, tracking))
}
