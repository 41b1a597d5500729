//! A live session's input as a front end names it: a merged stream on
//! standard input, growing files followed, GNSS-SDR's tracking monitor
//! with a growing IMU log, or a u-blox module's UBX stream; checked, and
//! turned into the runtime's [`Inputs`].

use std::path::PathBuf;

use gsens_gnss_sdr::GnssSdrError;

use crate::monitor_setup::monitor_setup;
use crate::runtime::Inputs;
use crate::ubx::UbxOptions;

/// The inputs a caller names (every field unset: none).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct InputChoice {
    /// One merged stream on standard input (what `replay` writes).
    pub stdin: bool,
    /// A growing IMU log, followed.
    pub follow_imu: Option<PathBuf>,
    /// A growing tracking log, followed (with [`InputChoice::follow_imu`]).
    pub follow_tracking: Option<PathBuf>,
    /// GNSS-SDR's tracking monitor: the address it sends to and the
    /// configuration of its run (with [`InputChoice::follow_imu`]).
    pub gnss_sdr_monitor: Option<(String, PathBuf)>,
    /// A u-blox module's UBX stream: a log being written, its serial port,
    /// a named pipe, or `-` for standard input (with
    /// [`InputChoice::follow_imu`]: that IMU log instead of its ESF
    /// messages).
    pub ubx: Option<PathBuf>,
    /// The serial port's baud rate (`None`: as the port is set).
    pub ubx_baud: Option<u32>,
    /// How the UBX stream is read and calibrated.
    pub ubx_options: UbxOptions,
}

/// Why the inputs named cannot start a session.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum InputChoiceError {
    /// No complete input is named.
    #[error(
        "no input: a merged stream on standard input, a growing IMU log with a growing tracking log, a growing IMU \
         log with GNSS-SDR's tracking monitor, or a UBX stream"
    )]
    NoInput,
    /// A file to follow is missing or not a file (a UBX stream's: nor a
    /// serial device).
    #[error("{option} {}: {}", path.display(), if *exists { "not a file" } else { "no such file (start the logger first)" })]
    NotAFile {
        /// The [`InputChoice`] field that names it (`follow_imu`, `follow_tracking`, `ubx`).
        option: &'static str,
        /// The path.
        path: PathBuf,
        /// Whether something else is there.
        exists: bool,
    },
    /// The settings state a receiver loop, and the monitor's configuration states its own.
    #[error("{}: the GNSS-SDR configuration states the receiver loop; the settings must leave it unstated", conf.display())]
    LoopStatedTwice {
        /// The configuration.
        conf: PathBuf,
    },
    /// The monitor's configuration cannot be read.
    #[error(transparent)]
    Monitor(#[from] GnssSdrError),
}

impl InputChoiceError {
    /// The message with every option it names spelled by `name` (a command
    /// line's flag, say): what to give for an input, a file to follow, the
    /// loop options to leave out; `None` where it names no option (its own
    /// message stands).
    pub fn named(&self, name: impl Fn(&str) -> String) -> Option<String> {
        match self {
            InputChoiceError::NoInput => {
                let (stdin, imu, tracking) = (name("stdin"), name("follow_imu"), name("follow_tracking"));
                let (monitor, conf) = (name("gnss_sdr_monitor"), name("gnss_sdr_conf"));
                Some(format!(
                    "no input: give {stdin} (the merged stream `gsens replay` writes), {imu} IMU.CSV with {tracking} \
                     TRACKING.CSV (growing files), {imu} IMU.CSV with {monitor} ADDR and {conf} CONF (GNSS-SDR's \
                     tracking monitor), or {ubx} LOG.UBX|/dev/ttyACM0 (a u-blox module's UBX stream)",
                    ubx = name("ubx")
                ))
            }
            InputChoiceError::NotAFile { option, .. } => {
                Some(format!("{}{}", name(option), &self.to_string()[option.len()..]))
            }
            InputChoiceError::LoopStatedTwice { .. } => Some(gsens_gnss_sdr::loop_stated_twice(name)),
            InputChoiceError::Monitor(_) => None,
        }
    }
}

impl InputChoice {
    /// Checks that one input is named completely and that the files to
    /// follow exist.
    pub fn check(&self) -> Result<(), InputChoiceError> {
        let follows = self.follow_imu.is_some() && (self.follow_tracking.is_some() || self.gnss_sdr_monitor.is_some());
        if !(self.stdin || follows || self.ubx.is_some()) {
            return Err(InputChoiceError::NoInput);
        }
        let stream = |p: &PathBuf| p.is_file() || crate::ubx::is_device(p) || crate::ubx::is_pipe(p);
        if let Some(p) = self.ubx.as_ref().filter(|p| !stream(p)) {
            return Err(InputChoiceError::NotAFile { option: "ubx", path: p.clone(), exists: p.exists() });
        }
        for (option, path) in [("follow_imu", &self.follow_imu), ("follow_tracking", &self.follow_tracking)] {
            if let Some(p) = path.as_ref().filter(|p| !p.is_file()) {
                return Err(InputChoiceError::NotAFile { option, path: p.clone(), exists: p.exists() });
            }
        }
        Ok(())
    }

    /// The runtime's inputs ([`InputChoice::check`]ed), with the note on the
    /// monitor's configuration ([`crate::MonitorSetup::note`]). A monitor's
    /// loop is its configuration's: `loop_stated` settings are refused.
    pub fn inputs(self, loop_stated: bool) -> Result<(Inputs, Option<String>), InputChoiceError> {
        self.check()?;
        if self.stdin {
            let reader = Box::new(std::io::BufReader::new(std::io::stdin()));
            return Ok((Inputs::Merged { name: "stdin".into(), reader }, None));
        }
        if let Some(log) = self.ubx {
            let (baud, options) = (self.ubx_baud, self.ubx_options);
            return Ok((Inputs::Ubx { log, baud, imu: self.follow_imu, options }, None));
        }
        let (Some(imu), tracking, monitor) = (self.follow_imu, self.follow_tracking, self.gnss_sdr_monitor) else {
            return Err(InputChoiceError::NoInput);
        };
        match (tracking, monitor) {
            (_, Some((addr, conf))) => {
                if loop_stated {
                    return Err(InputChoiceError::LoopStatedTwice { conf });
                }
                let setup = monitor_setup(Some(&conf), None, None)?;
                let note = setup.note.clone();
                Ok((Inputs::Monitor { imu, monitor: Box::new(setup.input(&addr)) }, note))
            }
            (Some(tracking), None) => Ok((Inputs::Files { imu, tracking }, None)),
            (None, None) => Err(InputChoiceError::NoInput),
        }
    }
}

/// The warning of a session whose settings state no receiver loop, naming
/// the options that state one.
pub const LOOP_NOT_STATED: &str = "warning [loop_not_stated]: no receiver loop was stated: the estimates will use the \
     typical loop the data fit best and cannot be trustworthy; state the receiver's loop (order, bn_hz, \
     loop_interval_s, logged_phase) from its settings\n";

#[cfg(test)]
mod tests {
    use super::*;

    /// Nothing, or a followed IMU log alone, is no input; a missing file is
    /// named by its field; files that exist become followed files.
    #[test]
    fn the_choice_needs_a_whole_input_and_existing_files() {
        assert!(matches!(InputChoice::default().check(), Err(InputChoiceError::NoInput)));
        let dir = tempfile::tempdir().unwrap();
        let imu = dir.path().join("imu.csv");
        let only_imu = InputChoice { follow_imu: Some(imu.clone()), ..InputChoice::default() };
        assert!(matches!(only_imu.check(), Err(InputChoiceError::NoInput)));
        let files = InputChoice { follow_tracking: Some(dir.path().to_path_buf()), ..only_imu };
        let e = files.check().unwrap_err();
        assert!(matches!(&e, InputChoiceError::NotAFile { option: "follow_imu", exists: false, .. }), "{e}");
        std::fs::write(&imu, "").unwrap();
        let e = files.check().unwrap_err();
        assert!(matches!(&e, InputChoiceError::NotAFile { option: "follow_tracking", exists: true, .. }), "{e}");
        assert!(e.to_string().ends_with(": not a file"), "{e}");
        let flag = |n: &str| format!("<{n}>");
        let named = format!("<follow_tracking> {}: not a file", dir.path().display());
        assert_eq!(e.named(flag), Some(named));
        let no_input = InputChoiceError::NoInput.named(flag).unwrap();
        assert!(
            no_input.starts_with("no input: give <stdin> (")
                && no_input.ends_with("<ubx> LOG.UBX|/dev/ttyACM0 (a u-blox module's UBX stream)"),
            "{no_input}"
        );
        let tracking = dir.path().join("tracking.csv");
        std::fs::write(&tracking, "").unwrap();
        let files = InputChoice { follow_tracking: Some(tracking.clone()), ..files };
        let (inputs, note) = files.inputs(true).unwrap();
        assert!(matches!(inputs, Inputs::Files { imu: i, tracking: t } if i == imu && t == tracking));
        assert_eq!(note, None);
    }

    /// A monitor brings its configuration's loop: settings that state one are refused.
    #[test]
    fn a_monitor_refuses_a_stated_loop() {
        let dir = tempfile::tempdir().unwrap();
        let imu = dir.path().join("imu.csv");
        std::fs::write(&imu, "").unwrap();
        let conf = dir.path().join("gnss-sdr.conf");
        let choice = InputChoice {
            follow_imu: Some(imu),
            gnss_sdr_monitor: Some(("127.0.0.1:0".into(), conf.clone())),
            ..InputChoice::default()
        };
        let Err(e) = choice.inputs(true) else { panic!("a stated loop with a monitor was accepted") };
        assert!(matches!(&e, InputChoiceError::LoopStatedTwice { conf: c } if *c == conf), "{e}");
        let named = e.named(|n| n.to_string()).unwrap();
        assert_eq!(named, "gnss_sdr_conf states the receiver loop: leave out order, bn_hz and the like");
    }
}
