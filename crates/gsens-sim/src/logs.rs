//! A simulated session as receiver logs: written as `imu.csv`,
//! `tracking.csv` and `truth.json` into a folder, or kept in memory as the
//! log types of `gsens-io`, exactly as its readers would return the files.

use crate::scenario::Scenario;
use crate::session::{MemorySink, SessionSink, SimError, SimulatedRow, SinkError, Truth, simulate};
use gsens_core::{LoggedPhase, LoopFilterCoeffs, LoopModel, LoopSpec};
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
        /// The underlying error, quoted in the message (so not also a `source`: a printed chain would say it twice).
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
            let text = gsens_io::read_config_text(p)
                .map_err(|error| LoadError::Io { path: p.display().to_string(), error })?;
            Scenario::from_toml_str(&text).map_err(|error| LoadError::Scenario { path: p.display().to_string(), error })
        }
    }
}

/// The true Γ \[Hz/(m/s²)\] from a simulator's `truth.json` (either layout:
/// a session's or an IF file's).
pub fn read_truth_gamma(path: &Path) -> Result<[f64; 3], LoadError> {
    #[derive(serde::Deserialize)]
    struct Gamma {
        gamma_hz_per_mps2: [f64; 3],
    }
    let text =
        std::fs::read_to_string(path).map_err(|error| LoadError::Io { path: path.display().to_string(), error })?;
    let g: Gamma = serde_json::from_str(&text)
        .map_err(|e| LoadError::Truth { path: path.display().to_string(), reason: e.to_string() })?;
    Ok(g.gamma_hz_per_mps2)
}

/// The receiver loop a simulated session's tracking log was made with, as its
/// `truth.json` states it: what an estimate of that session should model.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct TruthLoop {
    /// The loop: the scenario's `[loop]` spec (order, Bn, ζ or a3/b3) when it
    /// reproduces the written `loop_coeffs` exactly, otherwise those
    /// coefficients; updated every `loop_interval_s`.
    pub receiver_loop: LoopModel,
    /// What a log row holds (`logged_phase`).
    pub logged_phase: LoggedPhase,
    /// The tracking log interval \[s\] (`log_interval_s`).
    pub log_interval_s: f64,
}

/// The receiver loop from a simulator's `truth.json`: `loop_coeffs`
/// {`c0_per_s`, `c1_per_s2`, `c2_per_s3`}, `loop_interval_s`, `logged_phase`,
/// `log_interval_s`, and the `scenario`'s `loop` section for its spec
/// (written by [`simulate_to_dir`]; see [`Truth`]). `None` for a truth file
/// that states no such loop: an IF session's ([`crate::iq::IqTruth`]), whose
/// receiver is GNSS-SDR with the loop of its `gnss-sdr.conf`.
pub fn read_truth_loop(path: &Path) -> Result<Option<TruthLoop>, LoadError> {
    #[derive(serde::Deserialize)]
    struct Spec {
        order: u8,
        bn_hz: f64,
        zeta: f64,
        a3: f64,
        b3: f64,
    }
    #[derive(serde::Deserialize)]
    struct ScenarioLoop {
        #[serde(rename = "loop")]
        tracking_loop: Option<Spec>,
    }
    #[derive(serde::Deserialize)]
    struct Coeffs {
        c0_per_s: f64,
        c1_per_s2: f64,
        c2_per_s3: f64,
    }
    #[derive(serde::Deserialize)]
    struct Stated {
        loop_coeffs: Coeffs,
        loop_interval_s: f64,
        log_interval_s: f64,
        logged_phase: LoggedPhase,
        scenario: Option<ScenarioLoop>,
    }
    let text =
        std::fs::read_to_string(path).map_err(|error| LoadError::Io { path: path.display().to_string(), error })?;
    let bad = |reason: String| LoadError::TruthLoop { path: path.display().to_string(), reason };
    let value: serde_json::Value = serde_json::from_str(&text).map_err(|e| bad(e.to_string()))?;
    if value.get("loop_coeffs").is_none() {
        return Ok(None);
    }
    let s: Stated = serde_json::from_value(value).map_err(|e| bad(e.to_string()))?;
    let Coeffs { c0_per_s, c1_per_s2, c2_per_s3 } = s.loop_coeffs;
    let c = LoopFilterCoeffs { c0_per_s, c1_per_s2, c2_per_s3 };
    let positive = |v: f64| v > 0.0 && v.is_finite();
    if !(positive(s.loop_interval_s) && positive(s.log_interval_s)) {
        return Err(bad(format!(
            "loop_interval_s = {} and log_interval_s = {} must be positive",
            s.loop_interval_s, s.log_interval_s
        )));
    }
    let spec = s
        .scenario
        .and_then(|sc| sc.tracking_loop)
        .and_then(|l| LoopSpec::of_order(l.order, l.bn_hz, l.zeta, l.a3, l.b3).ok())
        .filter(|spec| spec.coeffs().is_ok_and(|k| k == c))
        .unwrap_or(LoopSpec::Coefficients(c));
    Ok(Some(TruthLoop {
        receiver_loop: LoopModel::kaplan(spec, Some(s.loop_interval_s)),
        logged_phase: s.logged_phase,
        log_interval_s: s.log_interval_s,
    }))
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
        /// The underlying error, quoted in the message (so not also a `source`: a printed chain would say it twice).
        error: std::io::Error,
    },
    /// The file is not a valid scenario.
    #[error("{path}: {error}")]
    Scenario {
        /// The file.
        path: String,
        /// Why.
        error: crate::scenario::ScenarioError,
    },
    /// A truth file without `gamma_hz_per_mps2` as 3 numbers.
    #[error("{path}: no `gamma_hz_per_mps2` with 3 numbers: {reason}")]
    Truth {
        /// The file.
        path: String,
        /// What the JSON reader said.
        reason: String,
    },
    /// A truth file whose receiver loop (`loop_coeffs`, `loop_interval_s`,
    /// `log_interval_s`, `logged_phase`) cannot be read.
    #[error("{path}: the receiver loop it states cannot be read: {reason}")]
    TruthLoop {
        /// The file.
        path: String,
        /// What is wrong.
        reason: String,
    },
    /// The embedded default does not parse (a bug).
    #[error(transparent)]
    Default(#[from] crate::scenario::ScenarioError),
}

/// Streams the simulator's output into the two CSV files.
struct FileSink {
    imu: ImuWriter<File>,
    tracking: TrackingWriter<File>,
    /// Whether `tracking.csv` names each row's carrier (channels on named
    /// signals); without, every row is on the oscillator's carrier, which the
    /// estimate is told (`carrier_hz`), as the file's rows carry no carrier.
    carrier_columns: bool,
    /// Whether `tracking.csv` has the NCO columns (`log.nco`).
    nco_columns: bool,
}

impl SessionSink for FileSink {
    fn imu(&mut self, t_s: f64, f_mps2: [f64; 3]) -> Result<(), SinkError> {
        Ok(self.imu.write_sample(t_s, &f_mps2)?)
    }
    fn tracking(&mut self, row: &SimulatedRow) -> Result<(), SinkError> {
        let nco = [row.nco_phase_cycles, row.nco_freq_hz];
        let extra: &[f64] = if self.nco_columns { &nco } else { &[] };
        if self.carrier_columns {
            Ok(self.tracking.write_row_on(&row.tracking_row(), &row.carrier, extra)?)
        } else {
            Ok(self.tracking.write_row_with(&row.tracking_row(), extra)?)
        }
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
    let carrier_columns = !scenario.satellites.signals.is_empty();
    let nco_columns = scenario.log.nco;
    let extra: &[&str] = if nco_columns { &gsens_io::NCO_COLUMNS } else { &[] };
    let mut sink = FileSink {
        imu: ImuWriter::new(imu).map_err(io(&dir.join("imu.csv")))?,
        // Carrier columns only for channels on named signals (the default's file is as it was).
        tracking: if carrier_columns {
            TrackingWriter::with_carriers(tracking, extra)
        } else {
            TrackingWriter::with_extra_columns(tracking, extra)
        }
        .map_err(io(&dir.join("tracking.csv")))?,
        carrier_columns,
        nco_columns,
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
    let name = format!("simulated tracking (seed {seed})");
    let tracking = if scenario.log.nco {
        // Without named signals the rows are on the oscillator's carrier, read as L1 (as the file is).
        let named = !scenario.satellites.signals.is_empty();
        let carrier = |r: &SimulatedRow| if named { r.carrier } else { gsens_io::Carrier::GPS_L1 };
        let rows: Vec<_> = sink.tracking.iter().map(|r| (r.tracking_row(), carrier(r))).collect();
        let nco = sink.tracking.iter().map(|r| [r.nco_phase_cycles, r.nco_freq_hz]);
        TrackingLog::from_rows_with_nco(&name, rows.iter().zip(nco).map(|((r, c), n)| (r, *c, n)))?
    } else if scenario.satellites.signals.is_empty() {
        let rows: Vec<gsens_io::TrackingRow> = sink.tracking.iter().map(SimulatedRow::tracking_row).collect();
        TrackingLog::from_rows(&name, &rows)?
    } else {
        let rows: Vec<_> = sink.tracking.iter().map(SimulatedRow::tracking_row_on).collect();
        TrackingLog::from_rows_on(&name, rows.iter().map(|(r, c)| (r, *c)))?
    };
    let imu =
        ImuSeries { t_s: sink.imu.iter().map(|s| s.0).collect(), accel_mps2: sink.imu.iter().map(|s| s.1).collect() };
    Ok(SimulatedLogs { tracking, imu, truth })
}

/// What [`simulate_iq_to_dir`] wrote and how fast.
#[derive(Debug, Clone)]
#[non_exhaustive]
pub struct IqSession {
    /// The truth (also in `truth.json`).
    pub truth: crate::iq::IqTruth,
    /// Wall time of the generation \[s\].
    pub wall_s: f64,
}

impl core::fmt::Display for IqSession {
    /// What was written, in three lines: duration, format, rate, size and
    /// speed; the satellites; Γ.
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let t = &self.truth;
        let g = t.sensitivity.gamma_hz_per_mps2;
        let prns: Vec<String> =
            t.satellites.iter().map(|s| format!("{} ({:.1} dB-Hz)", s.prn, s.start_cn0_dbhz)).collect();
        writeln!(
            f,
            "wrote {:.1} s of {} samples at {} Hz ({} samples, {:.1} MB) in {:.1} s ({:.1}x real time)",
            t.duration_s,
            t.format.gnss_sdr_item_type(),
            t.fs_hz,
            t.samples,
            (t.samples * t.format.bytes_per_sample() as u64) as f64 / 1e6,
            self.wall_s,
            t.duration_s / self.wall_s
        )?;
        writeln!(f, "satellites: PRN {}", prns.join(", PRN "))?;
        write!(f, "truth Γ = [{:+.4}, {:+.4}, {:+.4}] Hz/(m/s²)", g[0], g[1], g[2])
    }
}

/// Generates the IF samples of `scenario` into `iq_path` and, in `dir`:
/// `imu.csv`, `truth.json`, `delta_f.csv` (`t_s,delta_f_hz,g_induced_hz` per
/// 1 ms block) and, with `carrier_truth`, `carrier.csv` (`t_s,prn<N>_hz,…`:
/// each satellite's baseband carrier per 1 ms block).
pub fn simulate_iq_to_dir(
    scenario: &Scenario,
    seed: u64,
    cfg: &crate::iq::IqConfig,
    iq_path: &Path,
    dir: &Path,
    carrier_truth: bool,
    progress: impl FnMut(f64),
) -> Result<IqSession, LogsError> {
    use crate::iq::{BLOCK_S, ImuOnlySink, generate_iq};
    use std::io::{BufWriter, Write};
    let io = |path: &Path| {
        let path = path.display().to_string();
        move |error| LogsError::Io { path, error }
    };
    std::fs::create_dir_all(dir).map_err(io(dir))?;
    let create = |p: &Path| File::create(p).map_err(io(p));
    let iq_file = BufWriter::with_capacity(1 << 20, create(iq_path)?);
    let imu_path = dir.join("imu.csv");
    let mut imu = ImuWriter::new(create(&imu_path)?).map_err(io(&imu_path))?;
    let df_path = dir.join("delta_f.csv");
    let mut df = BufWriter::new(create(&df_path)?);
    writeln!(df, "t_s,delta_f_hz,g_induced_hz").map_err(io(&df_path))?;
    let carrier_path = dir.join("carrier.csv");
    let mut carrier = if carrier_truth { Some(BufWriter::new(create(&carrier_path)?)) } else { None };
    let mut block_err: Option<LogsError> = None;
    let started = std::time::Instant::now();
    let truth = {
        let mut sink = ImuOnlySink(|t: f64, f: [f64; 3]| imu.write_sample(t, &f).map_err(Into::into));
        let on_block = |b: &crate::iq::IqBlock<'_>| {
            if block_err.is_some() {
                return;
            }
            if let Err(e) = writeln!(df, "{},{},{}", b.t_mid_s, b.delta_f_hz, b.g_induced_hz) {
                block_err = Some(io(&df_path)(e));
                return;
            }
            if let Some(c) = carrier.as_mut() {
                let mut line = String::new();
                if b.t_mid_s < BLOCK_S {
                    line.push_str("t_s");
                    b.prns.iter().for_each(|p| line.push_str(&format!(",prn{p}_hz")));
                    line.push('\n');
                }
                line.push_str(&b.t_mid_s.to_string());
                b.carrier_hz.iter().for_each(|f| line.push_str(&format!(",{f}")));
                line.push('\n');
                if let Err(e) = c.write_all(line.as_bytes()) {
                    block_err = Some(io(&carrier_path)(e));
                }
            }
        };
        generate_iq(scenario, seed, cfg, iq_file, &mut sink, on_block, progress)?
    };
    let wall_s = started.elapsed().as_secs_f64();
    if let Some(e) = block_err {
        return Err(e);
    }
    df.flush().map_err(io(&df_path))?;
    if let Some(mut c) = carrier {
        c.flush().map_err(io(&carrier_path))?;
    }
    imu.finish().map_err(io(&imu_path))?;
    let truth_path = dir.join("truth.json");
    let text = serde_json::to_string_pretty(&truth).expect("the truth serializes") + "\n";
    std::fs::write(&truth_path, text).map_err(io(&truth_path))?;
    Ok(IqSession { truth, wall_s })
}
