//! The files a live session keeps in its output directory: every line as
//! received (`received/`), and the records used (`imu.csv`, `tracking.csv`),
//! from which the final estimate is made.

use std::fs::File;
use std::io::LineWriter;
use std::path::{Path, PathBuf};

use crate::input::Input;
use crate::runtime::RuntimeError;
use crate::sources::Source;

/// The kept files, written line by line (a session stopped hard keeps what it received).
pub(crate) struct Kept {
    /// Per source, every line as received (none for a source of parsed records).
    received: Vec<Option<LineWriter<File>>>,
    imu: gsens_io::ImuWriter<LineWriter<File>>,
    /// `tracking.csv` before its first record, empty: its header has the
    /// columns of the first record kept (the session refuses records with
    /// other columns after it).
    tracking_file: Option<LineWriter<File>>,
    tracking: Option<gsens_io::TrackingWriter<LineWriter<File>>>,
    imu_path: PathBuf,
    tracking_path: PathBuf,
}

/// Creates the file `path`, the error naming it.
pub(crate) fn create(path: &Path) -> Result<File, RuntimeError> {
    File::create(path).map_err(|error| RuntimeError::Create { path: path.to_path_buf(), error })
}

/// The directory `received/` of `out_dir`, created.
pub(crate) fn received_dir(out_dir: &Path) -> Result<PathBuf, RuntimeError> {
    let dir = out_dir.join("received");
    std::fs::create_dir_all(&dir).map_err(|error| RuntimeError::Create { path: dir.clone(), error })?;
    Ok(dir)
}

impl Kept {
    pub(crate) fn create(out_dir: &Path, sources: &[Source]) -> Result<Self, RuntimeError> {
        let received_dir = received_dir(out_dir)?;
        let file = |p: &Path| create(p).map(LineWriter::new);
        let received = sources
            .iter()
            .map(|s| {
                // The source's name (a path, an address) as one file name.
                let name: String =
                    s.name.chars().map(|c| if c.is_ascii_alphanumeric() || c == '.' { c } else { '_' }).collect();
                s.format.map(|_| file(&received_dir.join(format!("{name}.txt")))).transpose()
            })
            .collect::<Result<_, _>>()?;
        let (imu_path, tracking_path) = (out_dir.join("imu.csv"), out_dir.join("tracking.csv"));
        Ok(Kept {
            received,
            imu: gsens_io::ImuWriter::new(file(&imu_path)?)?,
            tracking_file: Some(file(&tracking_path)?),
            tracking: None,
            imu_path,
            tracking_path,
        })
    }

    /// Keeps a line of `source` as received; `false` for a source of parsed records.
    pub(crate) fn line(&mut self, source: usize, text: &str) -> std::io::Result<bool> {
        use std::io::Write;
        match self.received[source].as_mut() {
            Some(w) => writeln!(w, "{text}").map(|()| true),
            None => Ok(false),
        }
    }

    /// Keeps a record the session used.
    pub(crate) fn record(&mut self, x: &Input) -> std::io::Result<()> {
        match x {
            Input::Imu { t_s, accel_mps2 } => self.imu.write_sample(*t_s, accel_mps2),
            Input::Tracking(r) => {
                let w = match &mut self.tracking {
                    Some(w) => w,
                    None => {
                        let file = self.tracking_file.take().ok_or_else(|| {
                            std::io::Error::other("tracking.csv could not be started (its header failed)")
                        })?;
                        self.tracking.insert(gsens_io::TrackingWriter::for_record(file, r)?)
                    }
                };
                w.write_record(r)
            }
        }
    }

    /// Closes the logs; their paths (`imu.csv`, `tracking.csv`).
    pub(crate) fn finish(self) -> std::io::Result<(PathBuf, PathBuf)> {
        drop(self.imu.finish()?);
        match (self.tracking, self.tracking_file) {
            (Some(w), _) => drop(w.finish()?),
            // No record: the header of the six.
            (None, Some(file)) => drop(gsens_io::TrackingWriter::new(file)?.finish()?),
            (None, None) => {}
        }
        Ok((self.imu_path, self.tracking_path))
    }
}
