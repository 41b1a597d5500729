//! The inputs of a calibration as a front end names them — the IMU log with
//! a tracking log, GNSS-SDR's dumps or a PocketSDR log, and how each
//! receiver's files are converted — and the one rule that turns them into
//! a route ([`Inputs`]).

use crate::{Inputs, InputsError, Log, ObservationFile, ObservationInputs};
use gsens_gnss_sdr::{ImportOverrides, ImportSettings};
use std::path::{Path, PathBuf};

/// The inputs a caller names (every optional field unset: none). With the
/// `clap` feature it is a command line's options (the fields' doc comments
/// are their help, where a unit reads `[Hz]`, not a link): at least a
/// tracking log, GNSS-SDR dumps, a PocketSDR log, a RINEX file or a UBX log,
/// one at a time, and the IMU log except beside a UBX log.
#[derive(Debug, Clone, Default, PartialEq)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
#[allow(rustdoc::broken_intra_doc_links)]
pub struct InputChoice {
    /// IMU log: t_s,fx_mps2,fy_mps2,fz_mps2 (beside a RINEX file: t_s in GPS seconds of the week of
    /// its first epoch; beside a UBX log, instead of the module's own accelerometer).
    #[cfg_attr(feature = "clap", arg(long, required_unless_present = "ubx"))]
    pub imu: Option<PathBuf>,
    /// Tracking log: t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad (or instead a receiver's own
    /// log: GNSS-SDR dumps, a PocketSDR log, a RINEX file, a UBX log).
    #[cfg_attr(
        feature = "clap",
        arg(
            long,
            required_unless_present_any = ["gnss_sdr", "pocketsdr", "rinex", "ubx"],
            conflicts_with_all = ["gnss_sdr", "pocketsdr", "rinex", "ubx"]
        )
    )]
    pub tracking: Option<PathBuf>,
    /// Directory of GNSS-SDR tracking dumps (trk_ch_N.dat, Tracking_1C.dump=true) to use instead
    /// of a tracking log, with the configuration they were made with.
    #[cfg_attr(feature = "clap", arg(long, requires = "gnss_sdr_conf"))]
    pub gnss_sdr: Option<PathBuf>,
    /// The GNSS-SDR configuration file the dumps were made with (its loop is modelled exactly).
    /// With a tracking log instead of dumps: rows that came from that GNSS-SDR run another way
    /// (`gsens import gnss-sdr-monitor`), estimated with its exact loop. With a RINEX file: the
    /// GNSS-SDR run that wrote it, whose loop is then modelled exactly (its bandwidth fitted)
    /// instead of identified among generic ones.
    #[cfg_attr(feature = "clap", arg(long))]
    pub gnss_sdr_conf: Option<PathBuf>,
    /// Sampling rate of the tracking [Hz] when the configuration does not give it.
    #[cfg_attr(
        feature = "clap",
        arg(
            long,
            allow_negative_numbers = true,
            value_parser = gsens_calib::option_values::positive,
            help_heading = "GNSS-SDR dumps"
        )
    )]
    pub gnss_sdr_fs_hz: Option<f64>,
    /// What is set instead of the configuration's conversion.
    #[cfg_attr(feature = "clap", command(flatten))]
    pub gnss_sdr_overrides: ImportOverrides,
    /// A pocket_trk log (-log FILE, its $CH lines) to use instead of a tracking log; PocketSDR's
    /// carrier loop is modelled exactly.
    #[cfg_attr(feature = "clap", arg(long, conflicts_with = "gnss_sdr"))]
    pub pocketsdr: Option<PathBuf>,
    /// How the PocketSDR log is converted.
    #[cfg_attr(feature = "clap", command(flatten))]
    pub pocketsdr_options: gsens_pocketsdr::ImportOptions,
    /// A RINEX observation file (3.x, 2.11, Hatanaka) of a receiver that logs carrier phase or
    /// Doppler but no tracking error: its loop is identified from the session.
    #[cfg_attr(feature = "clap", arg(long, conflicts_with_all = ["gnss_sdr", "pocketsdr", "ubx"], help_heading = HEADING))]
    pub rinex: Option<PathBuf>,
    /// A u-blox UBX log (RXM-RAWX; the module's accelerometer from ESF-RAW / ESF-MEAS unless an
    /// IMU log is named): its loop is identified from the session.
    #[cfg_attr(feature = "clap", arg(long, conflicts_with_all = ["gnss_sdr", "pocketsdr"], help_heading = HEADING))]
    pub ubx: Option<PathBuf>,
    /// What the estimate from a RINEX or UBX log is made from: the carrier phase differenced, the
    /// Doppler, or auto (the carrier phase where most tracks have one).
    #[cfg_attr(feature = "clap", arg(id = "observable", long = "observable", value_name = "OBSERVABLE", value_enum, default_value_t, help_heading = HEADING))]
    pub observation_record: gsens_calib::ObservationRecord,
    /// How the UBX log is read.
    #[cfg_attr(feature = "clap", command(flatten))]
    pub ubx_settings: gsens_ublox::UbxSettings,
}

/// The help heading of the carrier phase and Doppler logs' options.
#[cfg(feature = "clap")]
const HEADING: &str = "Carrier phase and Doppler logs";

impl InputChoice {
    /// The route of a carrier phase and Doppler log, where a RINEX file or
    /// a UBX log is named (`None` otherwise): the IMU log named, or without
    /// one the UBX log's own accelerometer; with `gnss_sdr_conf`, the RINEX
    /// file is a GNSS-SDR run's and its loop GNSS-SDR's. Both logs named, a
    /// RINEX file without an IMU log, or a GNSS-SDR configuration with a UBX
    /// log is refused, naming the options by `name`; a configuration that
    /// does not read is its receiver's error.
    pub fn observations(&self, name: impl Fn(&str) -> String) -> Option<Result<ObservationInputs, InputsError>> {
        let imu = self.imu.clone();
        let refused = |why: String| Some(Err(InputsError::Choice(why)));
        let log = match (&self.rinex, &self.ubx) {
            (None, None) => return None,
            (Some(_), Some(_)) => return refused(format!("{} and {} exclude each other", name("rinex"), name("ubx"))),
            (Some(_), None) if imu.is_none() => return refused(format!("{} needs {}", name("rinex"), name("imu"))),
            (None, Some(_)) if self.gnss_sdr_conf.is_some() => {
                return refused(format!(
                    "{} goes with a GNSS-SDR run's {}, not {}",
                    name("gnss_sdr_conf"),
                    name("rinex"),
                    name("ubx")
                ));
            }
            (Some(path), None) => ObservationFile::Rinex(path.clone()),
            (None, Some(path)) => ObservationFile::Ubx(path.clone(), self.ubx_settings),
        };
        let gnss_sdr_conf = match &self.gnss_sdr_conf {
            Some(conf) => match self.gnss_sdr_import(Some(conf)) {
                Ok(import) => Some((conf.clone(), import)),
                Err(e) => return Some(Err(e.into())),
            },
            None => None,
        };
        Some(Ok(ObservationInputs { log, imu, record: self.observation_record, gnss_sdr_conf }))
    }

    /// How GNSS-SDR's records of the run configured by `conf` are read:
    /// the configuration with the sampling rate and the overrides named.
    fn gnss_sdr_import(&self, conf: Option<&Path>) -> Result<ImportSettings, gsens_gnss_sdr::GnssSdrError> {
        ImportSettings::from_conf_with(conf, self.gnss_sdr_fs_hz, &self.gnss_sdr_overrides)
    }

    /// The route the inputs name, its conversion settings checked: a
    /// PocketSDR log; else GNSS-SDR dumps; else a tracking log, as rows of
    /// the GNSS-SDR run of `gnss_sdr_conf` when one is named. A PocketSDR
    /// conversion named without its log is refused, as is no IMU log or no tracking input
    /// ([`InputsError::Choice`], its message naming each option by `name`: a
    /// command line's flag, say); a setting's error is its receiver's
    /// ([`gsens_gnss_sdr::GnssSdrError::setting`],
    /// [`gsens_pocketsdr::PocketSdrError::setting`]).
    pub fn inputs(&self, name: impl Fn(&str) -> String) -> Result<Inputs, InputsError> {
        let Some(imu) = self.imu.clone() else {
            return Err(InputsError::Choice(format!("{} is required", name("imu"))));
        };
        if let Some(log) = &self.pocketsdr {
            let import = self.pocketsdr_options.settings()?;
            return Ok(Inputs::PocketSdr { imu, log: log.clone(), import });
        }
        if self.pocketsdr_options.given() {
            let (conf, settle, toff) = (name("pocketsdr_conf"), name("pocketsdr_settle_s"), name("pocketsdr_toff_s"));
            return Err(InputsError::Choice(format!("{conf}, {settle} and {toff} need {} LOG", name("pocketsdr"))));
        }
        let conf = self.gnss_sdr_conf.as_deref();
        let import = |conf| self.gnss_sdr_import(conf);
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
        let plain =
            InputChoice { imu: Some(f.join("imu.csv")), tracking: Some(f.join("t.csv")), ..InputChoice::default() };
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

    /// No IMU log, a PocketSDR conversion without its log, no tracking
    /// input and a setting out of range are refused, each naming its options.
    #[test]
    fn incomplete_or_out_of_range_choices_are_refused() {
        let no_imu = InputChoice { tracking: Some("t.csv".into()), ..InputChoice::default() };
        assert_eq!(no_imu.inputs(flag).unwrap_err().to_string(), "<imu> is required");
        let imu = Some(fixtures().join("imu.csv"));
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
