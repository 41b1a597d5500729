//! The route of a receiver that logs carrier phase and Doppler but no
//! tracking error: a RINEX observation file with an IMU log, or a UBX log
//! (RXM-RAWX) with the module's own accelerometer (ESF-RAW / ESF-MEAS) or
//! an IMU log, calibrated with the receiver's loop identified
//! ([`gsens_calib::calibrate_observations`]).

use crate::InputsError;
use gsens_calib::{ObservationOutcome, ObservationRecord, PipelineSettings};
use gsens_io::ImuSeries;
use std::path::PathBuf;

/// The receiver's log of carrier phase and Doppler.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum ObservationFile {
    /// A RINEX observation file (RINEX 3 or 2.11, Hatanaka-compressed or not).
    Rinex(PathBuf),
    /// A u-blox UBX log, read under its settings (how the sensor time tags
    /// map to GPS time).
    Ubx(PathBuf, gsens_ublox::UbxSettings),
}

/// The inputs of a calibration from a carrier phase and Doppler log.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct ObservationInputs {
    /// The log.
    pub log: ObservationFile,
    /// An IMU log on the log's time (`t_s`: GPS seconds of the week of the
    /// log's first epoch); `None`: the UBX log's own accelerometer.
    pub imu: Option<PathBuf>,
    /// Which observable the rows are made of.
    pub record: ObservationRecord,
    /// The configuration of the GNSS-SDR run that wrote a RINEX file, and
    /// what it says: the receiver's loop is then GNSS-SDR's, modelled
    /// exactly ([`gsens_gnss_sdr::with_gnss_sdr_loop`]; its bandwidth still
    /// fitted), instead of one identified among generic shapes.
    pub gnss_sdr_conf: Option<(PathBuf, gsens_gnss_sdr::ImportSettings)>,
}

impl ObservationInputs {
    /// The inputs of `log` with the IMU log `imu` (`None`: a UBX log's own
    /// accelerometer), the rows made of `record`.
    pub fn new(log: ObservationFile, imu: Option<PathBuf>, record: ObservationRecord) -> Self {
        ObservationInputs { log, imu, record, gnss_sdr_conf: None }
    }

    /// Reads the log and the IMU and calibrates under `settings`, the inputs
    /// list filled in. With a GNSS-SDR configuration the settings must not
    /// state a loop of their own ([`InputsError::LoopStatedTwice`]).
    pub fn calibrate(&self, settings: &PipelineSettings) -> Result<ObservationOutcome, InputsError> {
        let gnss_sdr_settings;
        let settings = match &self.gnss_sdr_conf {
            Some((conf, _)) if settings.loop_stated => {
                return Err(InputsError::LoopStatedTwice { conf: conf.display().to_string() });
            }
            Some((_, import)) => {
                gnss_sdr_settings = gsens_gnss_sdr::with_gnss_sdr_loop(settings, import);
                &gnss_sdr_settings
            }
            None => settings,
        };
        let read_imu = |path: &PathBuf| gsens_io::read_imu_file(path);
        let mut esf_time = String::new();
        let (log, imu, role, path): (gsens_io::ObservationLog, ImuSeries, &str, &PathBuf) = match &self.log {
            ObservationFile::Rinex(path) => {
                let Some(imu_path) = &self.imu else {
                    return Err(InputsError::Choice(format!(
                        "{}: a RINEX file holds no IMU data: name the IMU log",
                        path.display()
                    )));
                };
                let (log, imu) = rayon::join(|| gsens_rinex::read_rinex_file(path), || read_imu(imu_path));
                (log.map_err(|e| InputsError::Observations(e.to_string()))?, imu?, "rinex", path)
            }
            ObservationFile::Ubx(path, ubx_settings) => {
                let ubx = gsens_ublox::read_ubx_file(path, ubx_settings)
                    .map_err(|e| InputsError::Observations(e.to_string()))?;
                let imu = match &self.imu {
                    Some(imu_path) => read_imu(imu_path)?,
                    None if ubx.imu.is_empty() => {
                        return Err(InputsError::Choice(format!(
                            "{}: the UBX log holds no accelerometer sample (ESF-RAW or ESF-MEAS): name an IMU log",
                            path.display()
                        )));
                    }
                    None => {
                        esf_time = match (ubx.sensor_time, ubx.imu_anchor) {
                            (gsens_ublox::SensorTime::GpsTowMs, _) => "sensor time: GPS time of week".into(),
                            (_, Some(a)) => format!(
                                "sensor time: free-running, tied to the RXM-RAWX epoch at t = {} s, GPS − sensor = \
                                 {} s",
                                a.at_t_s, a.gps_minus_sensor_s
                            ),
                            (_, None) => "sensor time: free-running, not tied".into(),
                        };
                        ubx.imu
                    }
                };
                (ubx.observations, imu, "ubx", path)
            }
        };
        let mut outcome = gsens_calib::calibrate_observations(&log, &imu, settings, self.record)?;
        outcome.inputs.push((role.to_string(), path.display().to_string()));
        outcome.inputs.push(match &self.imu {
            Some(p) => ("imu".to_string(), p.display().to_string()),
            None => ("imu".to_string(), format!("{} (ESF; {esf_time})", path.display())),
        });
        if let Some((conf, _)) = &self.gnss_sdr_conf {
            outcome.inputs.push(("gnss_sdr_conf".to_string(), conf.display().to_string()));
        }
        Ok(outcome)
    }
}

/// What became of each track of the log and which loop was identified, as
/// text.
pub fn render_observation_summary(outcome: &ObservationOutcome) -> String {
    let mut out = format!(
        "{}: {} track(s), {} epoch(s) at {:.3} s; rows from the {}\n",
        outcome.format,
        outcome.rows.tracks.len(),
        outcome.rows.rows.epoch_t_s.len(),
        outcome.calibration.log_interval_s,
        match outcome.rows.record {
            ObservationRecord::Doppler => "Doppler",
            _ => "carrier phase, differenced",
        }
    );
    for t in &outcome.rows.tracks {
        let slips = match (t.half_cycle_slips, t.left_out) {
            (n, true) => format!("  left out: {n} unflagged half-cycle slips (false lock or a weak carrier)"),
            (0, false) => String::new(),
            (n, false) => format!("  {n} unflagged half-cycle slip(s)"),
        };
        out += &format!(
            "  {:<24} C/N0 {:5.1} dB-Hz  {:6} epochs  {:6} rows  {:5} left out{slips}\n",
            t.label, t.mean_cn0_dbhz, t.epochs, t.rows, t.rows_left_out
        );
    }
    out
}
