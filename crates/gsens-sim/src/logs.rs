//! A simulated session as receiver logs: written as `imu.csv`,
//! `tracking.csv` and `truth.json` into a folder, or kept in memory as the
//! log types of `gsens-io`, exactly as its readers would return the files.

use crate::scenario::Scenario;
use crate::session::{MemorySink, SessionSink, SimError, SimulatedRow, SinkError, Truth, simulate};
use gsens_io::{FormatError, ImuSeries, ImuWriter, TrackingLog, TrackingWriter};
use std::fs::File;
use std::path::Path;

/// Why a session could not be simulated into logs.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum LogsError {
    /// The simulation failed.
    #[error(transparent)]
    Sim(#[from] SimError),
    /// A file could not be created or written.
    #[error("{path}: cannot write: {error}")]
    Io {
        /// The file.
        path: String,
        /// Why.
        #[source]
        error: std::io::Error,
    },
    /// The simulated tracking rows did not pass the readers' checks.
    #[error(transparent)]
    Format(#[from] FormatError),
}

/// The scenario in the TOML file at `path`, or the embedded default (the
/// paper's experiment) for `None`.
pub fn load_scenario(path: Option<&Path>) -> Result<Scenario, LoadError> {
    match path {
        None => Ok(Scenario::from_toml_str(Scenario::default_toml())?),
        Some(p) => {
            let text =
                std::fs::read_to_string(p).map_err(|error| LoadError::Io { path: p.display().to_string(), error })?;
            Scenario::from_toml_str(&text).map_err(|error| LoadError::Scenario { path: p.display().to_string(), error })
        }
    }
}

/// Why a scenario could not be loaded.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum LoadError {
    /// The file could not be read.
    #[error("{path}: cannot read: {error}")]
    Io {
        /// The file.
        path: String,
        /// Why.
        #[source]
        error: std::io::Error,
    },
    /// The file is not a valid scenario.
    #[error("{path}: {error}")]
    Scenario {
        /// The file.
        path: String,
        /// Why.
        error: crate::ScenarioError,
    },
    /// The embedded default does not parse (a bug).
    #[error(transparent)]
    Default(#[from] crate::ScenarioError),
}

/// Streams the simulator's output into the two CSV files.
struct FileSink {
    imu: ImuWriter<File>,
    tracking: TrackingWriter<File>,
}

impl SessionSink for FileSink {
    fn imu(&mut self, t_s: f64, f_mps2: [f64; 3]) -> Result<(), SinkError> {
        Ok(self.imu.write_sample(t_s, &f_mps2)?)
    }
    fn tracking(&mut self, row: &SimulatedRow) -> Result<(), SinkError> {
        Ok(self.tracking.write_row(&row.tracking_row())?)
    }
}

/// Simulates `scenario` with `seed` into `dir`: `imu.csv`, `tracking.csv`
/// and `truth.json`; `progress` gets the fraction done.
pub fn simulate_to_dir(
    scenario: &Scenario,
    seed: u64,
    dir: &Path,
    progress: impl FnMut(f64),
) -> Result<Truth, LogsError> {
    let io = |path: &Path| {
        let path = path.display().to_string();
        move |error| LogsError::Io { path, error }
    };
    std::fs::create_dir_all(dir).map_err(io(dir))?;
    let create = |name: &str| {
        let p = dir.join(name);
        File::create(&p).map_err(io(&p))
    };
    let (imu, tracking) = (create("imu.csv")?, create("tracking.csv")?);
    let mut sink = FileSink {
        imu: ImuWriter::new(imu).map_err(io(&dir.join("imu.csv")))?,
        tracking: TrackingWriter::new(tracking).map_err(io(&dir.join("tracking.csv")))?,
    };
    let truth = simulate(scenario, seed, &mut sink, progress)?;
    sink.imu.finish().map_err(io(&dir.join("imu.csv")))?;
    sink.tracking.finish().map_err(io(&dir.join("tracking.csv")))?;
    let truth_path = dir.join("truth.json");
    let text = serde_json::to_string_pretty(&truth).expect("the truth serializes") + "\n";
    std::fs::write(&truth_path, text).map_err(io(&truth_path))?;
    Ok(truth)
}

/// A simulated session in memory, as the readers would return its files.
#[derive(Debug, Clone)]
#[non_exhaustive]
pub struct SimulatedLogs {
    /// The tracking log.
    pub tracking: TrackingLog,
    /// The IMU log.
    pub imu: ImuSeries,
    /// The truth.
    pub truth: Truth,
}

/// Simulates `scenario` with `seed` into memory; the logs are named
/// `simulated tracking (seed N)` and `simulated imu (seed N)` in errors.
pub fn simulate_logs(scenario: &Scenario, seed: u64) -> Result<SimulatedLogs, LogsError> {
    let mut sink = MemorySink::default();
    let truth = simulate(scenario, seed, &mut sink, |_| {})?;
    let rows: Vec<gsens_io::TrackingRow> = sink.tracking.iter().map(SimulatedRow::tracking_row).collect();
    let tracking = TrackingLog::from_rows(&format!("simulated tracking (seed {seed})"), &rows)?;
    let imu =
        ImuSeries { t_s: sink.imu.iter().map(|s| s.0).collect(), accel_mps2: sink.imu.iter().map(|s| s.1).collect() };
    Ok(SimulatedLogs { tracking, imu, truth })
}
