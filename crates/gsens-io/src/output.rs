//! Output paths checked before any work is done, so that a long run does
//! not end on a file it cannot write: a file's directory must exist and
//! accept a new file, a directory must exist or be creatable in one that
//! does. Errors name the path as given and what is wrong with it.

use std::path::{Path, PathBuf};

/// Why an output path cannot be written.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum OutputPathError {
    /// The file's directory does not exist.
    #[error("{}: the directory {} does not exist", path.display(), dir.display())]
    NoDirectory {
        /// The path as given.
        path: PathBuf,
        /// Its directory.
        dir: PathBuf,
    },
    /// The file's name is a directory's.
    #[error("{}: is a directory; give a file name", path.display())]
    IsDirectory {
        /// The path as given.
        path: PathBuf,
    },
    /// The (nearest existing) directory accepts no new file.
    #[error("{}: cannot write in {}: {error}", path.display(), dir.display())]
    CannotWrite {
        /// The path as given.
        path: PathBuf,
        /// The directory tried.
        dir: PathBuf,
        /// Why, quoted in the message (so not also a `source`: a printed chain would say it twice).
        error: std::io::Error,
    },
    /// A directory's nearest existing ancestor is a file.
    #[error("{}: {} is a file, not a directory", path.display(), file.display())]
    NotADirectory {
        /// The path as given.
        path: PathBuf,
        /// The file in the way.
        file: PathBuf,
    },
}

/// A file that could not be made or written.
#[derive(Debug, thiserror::Error)]
#[error("{}: cannot {action}", path.display())]
pub struct FileError {
    /// The file.
    pub path: PathBuf,
    /// What was tried: `create` or `write`.
    pub action: &'static str,
    /// Why.
    #[source]
    pub source: std::io::Error,
}

/// Why an export (a converted log, what became of its tracks, the text
/// telling about them) could not be written: one type for every receiver's
/// export, whatever encodes its records.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ExportError {
    /// A file could not be made or written.
    #[error(transparent)]
    File(#[from] FileError),
    /// Writing the rows, or telling about them, failed.
    #[error(transparent)]
    Io(#[from] std::io::Error),
    /// A record could not be encoded (as JSON, say).
    #[error(transparent)]
    Encode(Box<dyn std::error::Error + Send + Sync>),
}

impl ExportError {
    /// The error of the encoder of a record (`serde_json`'s, say), kept as
    /// it is: its message is this error's.
    pub fn encode(error: impl std::error::Error + Send + Sync + 'static) -> Self {
        ExportError::Encode(Box::new(error))
    }
}

/// The file `path`, made afresh (emptied if it exists).
pub fn create_file(path: &Path) -> Result<std::fs::File, FileError> {
    std::fs::File::create(path).map_err(|source| FileError { path: path.to_path_buf(), action: "create", source })
}

/// Writes `bytes` as the whole file `path`.
pub fn write_file(path: &Path, bytes: impl AsRef<[u8]>) -> Result<(), FileError> {
    std::fs::write(path, bytes).map_err(|source| FileError { path: path.to_path_buf(), action: "write", source })
}

/// Whether a new file can be made in `dir` (one is made and removed).
fn accepts_files(dir: &Path) -> std::io::Result<()> {
    let probe = dir.join(format!(".gsens-write-check-{}", std::process::id()));
    std::fs::OpenOptions::new().write(true).create_new(true).open(&probe)?;
    std::fs::remove_file(&probe)
}

/// The directory a relative or bare file name lies in (`.` for a bare name).
pub(crate) fn parent_of(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// Checks that the file `path` can be written: its directory exists and
/// accepts a new file, and `path` is not a directory.
pub fn check_output_file(path: &Path) -> Result<(), OutputPathError> {
    let dir = parent_of(path);
    if !dir.is_dir() {
        return Err(OutputPathError::NoDirectory { path: path.into(), dir: dir.into() });
    }
    if path.is_dir() {
        return Err(OutputPathError::IsDirectory { path: path.into() });
    }
    accepts_files(dir).map_err(|error| OutputPathError::CannotWrite { path: path.into(), dir: dir.into(), error })
}

/// Checks that the directory `path` exists or can be created, and accepts
/// files: its nearest existing ancestor must be a directory that does.
pub fn check_output_dir(path: &Path) -> Result<(), OutputPathError> {
    let mut p = path;
    while !p.exists() {
        p = parent_of(p);
    }
    if !p.is_dir() {
        return Err(OutputPathError::NotADirectory { path: path.into(), file: p.into() });
    }
    accepts_files(p).map_err(|error| OutputPathError::CannotWrite { path: path.into(), dir: p.into(), error })
}

/// Checks the file `path`, which may lie in the directory `made` that the
/// caller creates before writing it (a result file inside an output
/// directory): there its directory is checked as [`check_output_dir`] does,
/// elsewhere the file as [`check_output_file`] does.
pub fn check_output_file_in(path: &Path, made: Option<&Path>) -> Result<(), OutputPathError> {
    match made.filter(|m| parent_of(path).starts_with(m)) {
        Some(_) => check_output_dir(parent_of(path)),
        None => check_output_file(path),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A file that cannot be made or written is named with what was tried,
    /// and why follows as the error's source.
    #[test]
    fn file_errors_name_the_file_and_what_was_tried() {
        let dir = tempfile::tempdir().unwrap();
        let missing = dir.path().join("no/such/dir/f.csv");
        let e = create_file(&missing).unwrap_err();
        assert_eq!(e.to_string(), format!("{}: cannot create", missing.display()));
        let e = write_file(&missing, "x").unwrap_err();
        assert_eq!((e.action, e.source.kind()), ("write", std::io::ErrorKind::NotFound));
        // An export's error says what its cause says.
        let e = ExportError::from(write_file(&missing, "x").unwrap_err());
        assert_eq!(e.to_string(), format!("{}: cannot write", missing.display()));
        let encoded = ExportError::encode(std::fmt::Error);
        assert_eq!(encoded.to_string(), std::fmt::Error.to_string());
        let fine = dir.path().join("f.csv");
        write_file(&fine, "x").unwrap();
        assert_eq!(std::fs::read_to_string(&fine).unwrap(), "x");
    }

    #[test]
    fn a_missing_directory_or_a_file_in_the_way_is_named() {
        let tmp = tempfile::tempdir().unwrap();
        let tmp = tmp.path();
        assert!(check_output_file(&tmp.join("r.json")).is_ok());
        let e = check_output_file(&tmp.join("missing/r.json")).unwrap_err();
        assert!(matches!(&e, OutputPathError::NoDirectory { dir, .. } if dir == &tmp.join("missing")), "{e}");
        let (path, dir) = (tmp.join("missing/r.json"), tmp.join("missing"));
        assert_eq!(e.to_string(), format!("{}: the directory {} does not exist", path.display(), dir.display()));
        let e = check_output_file(tmp).unwrap_err();
        assert!(matches!(e, OutputPathError::IsDirectory { .. }), "{e}");
        assert!(check_output_dir(&tmp.join("a/b/c")).is_ok());
        assert!(!tmp.join("a").exists(), "a check creates nothing");
        // In a directory the caller makes first.
        let made = tmp.join("made");
        assert!(check_output_file_in(&made.join("r.json"), Some(&made)).is_ok());
        assert!(check_output_file_in(&tmp.join("other/r.json"), Some(&made)).is_err());
        std::fs::write(tmp.join("f"), "").unwrap();
        let e = check_output_dir(&tmp.join("f/sub")).unwrap_err();
        assert!(matches!(&e, OutputPathError::NotADirectory { file, .. } if file == &tmp.join("f")), "{e}");
        assert!(e.to_string().ends_with("f is a file, not a directory"), "{e}");
        // The probe file is removed again.
        let names: Vec<_> = std::fs::read_dir(tmp).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert_eq!(names, ["f"]);
    }

    #[test]
    fn a_bare_name_lies_in_the_current_directory() {
        assert_eq!(parent_of(Path::new("r.json")), Path::new("."));
        assert_eq!(parent_of(Path::new("out/r.json")), Path::new("out"));
        assert_eq!(parent_of(Path::new("/")), Path::new("."));
    }
}
