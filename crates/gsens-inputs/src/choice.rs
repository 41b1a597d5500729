//! The inputs of a calibration as a front end names them — the IMU log with
//! a tracking log, GNSS-SDR's dumps or a PocketSDR log, and how each
//! receiver's files are converted — and the one rule that turns them into
//! a route ([`Inputs`]).

use crate::{Inputs, InputsError, Log, ObservationFile, ObservationInputs};
use gsens_gnss_sdr::{ImportOverrides, ImportSettings};
use std::path::{Path, PathBuf};

/// The inputs a caller names (every optional field unset: none).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct InputChoice {
    /// The IMU log.
    pub imu: PathBuf,
    /// A tracking log in gsens's format; with
    /// [`InputChoice::gnss_sdr_conf`], rows that came from that GNSS-SDR run.
    pub tracking: Option<PathBuf>,
    /// A directory of GNSS-SDR tracking dumps (`trk_ch_N.dat`).
    pub gnss_sdr: Option<PathBuf>,
    /// The configuration of the GNSS-SDR run the dumps or the rows came from.
    pub gnss_sdr_conf: Option<PathBuf>,
    /// The tracking's sampling rate when the configuration gives none \[Hz\].
    pub gnss_sdr_fs_hz: Option<f64>,
    /// What is set instead of the configuration's conversion.
    pub gnss_sdr_overrides: ImportOverrides,
    /// A PocketSDR `pocket_trk` log.
    pub pocketsdr: Option<PathBuf>,
    /// How the PocketSDR log is converted.
    pub pocketsdr_options: gsens_pocketsdr::ImportOptions,
    /// A RINEX observation file.
    pub rinex: Option<PathBuf>,
    /// A u-blox UBX log (RXM-RAWX; its ESF accelerometer where `imu` is empty).
    pub ubx: Option<PathBuf>,
    /// How the UBX log is read.
    pub ubx_settings: gsens_ublox::UbxSettings,
    /// Which observable of a RINEX or UBX log the estimate is made from.
    pub observation_record: gsens_calib::ObservationRecord,
}

impl InputChoice {
    /// The route of a carrier phase and Doppler log, where a RINEX file or
    /// a UBX log is named (`None` otherwise): the IMU log named, or with an
    /// empty `imu` the UBX log's own accelerometer. Both named, or a RINEX
    /// file without an IMU log, is refused, naming the options by `name`.
    pub fn observations(&self, name: impl Fn(&str) -> String) -> Option<Result<ObservationInputs, InputsError>> {
        let imu = (!self.imu.as_os_str().is_empty()).then(|| self.imu.clone());
        let log = match (&self.rinex, &self.ubx) {
            (None, None) => return None,
            (Some(_), Some(_)) => {
                return Some(Err(InputsError::Choice(format!(
                    "{} and {} exclude each other",
                    name("rinex"),
                    name("ubx")
                ))));
            }
            (Some(_), None) if imu.is_none() => {
                return Some(Err(InputsError::Choice(format!("{} needs {}", name("rinex"), name("imu")))));
            }
            (Some(path), None) => ObservationFile::Rinex(path.clone()),
            (None, Some(path)) => ObservationFile::Ubx(path.clone(), self.ubx_settings),
        };
        Some(Ok(ObservationInputs { log, imu, record: self.observation_record }))
    }

    /// The route the inputs name, its conversion settings checked: a
    /// PocketSDR log; else GNSS-SDR dumps; else a tracking log, as rows of
    /// the GNSS-SDR run of `gnss_sdr_conf` when one is named. A PocketSDR
    /// conversion named without its log is refused, as is no tracking input
    /// ([`InputsError::Choice`], its message naming each option by `name`: a
    /// command line's flag, say); a setting's error is its receiver's
    /// ([`gsens_gnss_sdr::GnssSdrError::setting`],
    /// [`gsens_pocketsdr::PocketSdrError::setting`]).
    pub fn inputs(&self, name: impl Fn(&str) -> String) -> Result<Inputs, InputsError> {
        let imu = self.imu.clone();
        if let Some(log) = &self.pocketsdr {
            let import = self.pocketsdr_options.settings()?;
            return Ok(Inputs::PocketSdr { imu, log: log.clone(), import });
        }
        if self.pocketsdr_options.given() {
            let (conf, settle, toff) = (name("pocketsdr_conf"), name("pocketsdr_settle_s"), name("pocketsdr_toff_s"));
            return Err(InputsError::Choice(format!("{conf}, {settle} and {toff} need {} LOG", name("pocketsdr"))));
        }
        let conf = self.gnss_sdr_conf.as_deref();
        let import = |conf| ImportSettings::from_conf_with(conf, self.gnss_sdr_fs_hz, &self.gnss_sdr_overrides);
        Ok(match (&self.gnss_sdr, &self.tracking, conf) {
            (Some(dir), _, _) => Inputs::GnssSdrDumps {
                imu,
                dumps_dir: dir.clone(),
                import: import(conf)?,
                conf: conf.map(Path::to_path_buf),
            },
            (None, Some(t), Some(conf)) => Inputs::GnssSdrRows {
                imu: Log::File(imu),
                tracking: Log::File(t.clone()),
                import: import(Some(conf))?,
                conf: conf.to_path_buf(),
            },
            (None, Some(t), None) => Inputs::Csv { imu: Log::File(imu), tracking: Log::File(t.clone()) },
            (None, None, _) => {
                let (tracking, gnss_sdr, pocketsdr) = (name("tracking"), name("gnss_sdr"), name("pocketsdr"));
                return Err(InputsError::Choice(format!("{tracking} is required (or {gnss_sdr}, or {pocketsdr})")));
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fixtures() -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../gsens-gnss-sdr/tests/fixtures")
    }

    fn flag(name: &str) -> String {
        format!("<{name}>")
    }

    /// Each receiver's log wins over the plain logs in the order PocketSDR,
    /// GNSS-SDR dumps, GNSS-SDR rows, plain logs, each with its conversion.
    #[test]
    fn the_route_is_the_receiver_named() {
        let f = fixtures();
        let conf = f.join("order2/gnss-sdr.conf");
        let plain = InputChoice { imu: f.join("imu.csv"), tracking: Some(f.join("t.csv")), ..InputChoice::default() };
        assert!(matches!(plain.inputs(flag), Ok(Inputs::Csv { imu: Log::File(_), tracking: Log::File(_) })));
        let rows = InputChoice { gnss_sdr_conf: Some(conf.clone()), ..plain.clone() };
        let Ok(Inputs::GnssSdrRows { import, conf: c, .. }) = rows.inputs(flag) else { panic!("not rows") };
        assert_eq!((import, c), (ImportSettings::from_conf(Some(&conf), None).unwrap(), conf.clone()));
        let settle = ImportOverrides { settle_s: Some(0.5), ..ImportOverrides::default() };
        let dumps = InputChoice { gnss_sdr: Some(f.join("order2")), gnss_sdr_overrides: settle, ..rows.clone() };
        let Ok(Inputs::GnssSdrDumps { import, conf: c, .. }) = dumps.inputs(flag) else { panic!("not dumps") };
        assert_eq!((import.settle_s, c), (Some(0.5), Some(conf)));
        let log = Path::new(env!("CARGO_MANIFEST_DIR")).join("../gsens-pocketsdr/tests/fixtures/trk.log");
        let options = gsens_pocketsdr::ImportOptions { toff_s: 1.0, ..Default::default() };
        let pocket = InputChoice { pocketsdr: Some(log), pocketsdr_options: options, ..dumps };
        let Ok(Inputs::PocketSdr { import, .. }) = pocket.inputs(flag) else { panic!("not PocketSDR") };
        assert_eq!(import.toff_s, 1.0);
    }

    /// A PocketSDR conversion without its log, no tracking input and a
    /// setting out of range are refused, each naming its options.
    #[test]
    fn incomplete_or_out_of_range_choices_are_refused() {
        let imu = fixtures().join("imu.csv");
        let none = InputChoice { imu, ..InputChoice::default() };
        let e = none.inputs(flag).unwrap_err();
        assert_eq!(e.to_string(), "<tracking> is required (or <gnss_sdr>, or <pocketsdr>)");
        let options = gsens_pocketsdr::ImportOptions { settle_s: Some(1.0), ..Default::default() };
        let orphan = InputChoice { tracking: Some("t.csv".into()), pocketsdr_options: options, ..none.clone() };
        let e = orphan.inputs(|n: &str| n.to_string()).unwrap_err();
        assert_eq!(e.to_string(), "pocketsdr_conf, pocketsdr_settle_s and pocketsdr_toff_s need pocketsdr LOG");
        let lock = ImportOverrides { min_lock_test: Some(2.0), ..ImportOverrides::default() };
        let dumps =
            InputChoice { gnss_sdr: Some("d".into()), gnss_sdr_fs_hz: Some(4e6), gnss_sdr_overrides: lock, ..none };
        let Err(InputsError::GnssSdr(e)) = dumps.inputs(flag) else { panic!("a lock test of 2 was accepted") };
        assert_eq!(e.setting(), Some("min_lock_test"));
    }
}
