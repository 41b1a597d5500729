//! Output paths checked before any work: a file option's directory must
//! exist and accept a new file, a directory option must be a directory or
//! creatable in one that does. The error names the option.

use anyhow::{Result, bail};
use std::path::Path;

/// Whether a new file can be made in `dir` (one is made and removed).
fn accepts_files(dir: &Path) -> std::io::Result<()> {
    let probe = dir.join(format!(".gsens-write-check-{}", std::process::id()));
    std::fs::OpenOptions::new().write(true).create_new(true).open(&probe)?;
    std::fs::remove_file(&probe)
}

/// The directory a relative or bare file name lies in.
fn parent_of(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// Checks that the file `path` of option `flag` can be written.
pub fn file(flag: &str, path: &Path) -> Result<()> {
    let dir = parent_of(path);
    if !dir.is_dir() {
        bail!("{flag} {}: the directory {} does not exist", path.display(), dir.display());
    }
    if path.is_dir() {
        bail!("{flag} {}: is a directory; give a file name", path.display());
    }
    if let Err(e) = accepts_files(dir) {
        bail!("{flag} {}: cannot write in {}: {e}", path.display(), dir.display());
    }
    Ok(())
}

/// Checks an optional file option.
pub fn maybe_file(flag: &str, path: Option<&Path>) -> Result<()> {
    path.map_or(Ok(()), |p| file(flag, p))
}

/// Checks an optional file option whose file may lie in the directory
/// `made`, which the command creates before writing it (`demo --json` in
/// its `--out`): there the directory is checked as [`dir`] does.
pub fn maybe_file_in(flag: &str, path: Option<&Path>, made: Option<&Path>) -> Result<()> {
    let Some(path) = path else { return Ok(()) };
    match made.filter(|m| parent_of(path).starts_with(m)) {
        Some(_) => dir(flag, parent_of(path)),
        None => file(flag, path),
    }
}

/// Checks that the directory `path` of option `flag` exists or can be
/// created, and accepts files: its nearest existing ancestor must be a
/// directory that does.
pub fn dir(flag: &str, path: &Path) -> Result<()> {
    let mut p = path;
    loop {
        if p.exists() {
            if !p.is_dir() {
                bail!("{flag} {}: {} is a file, not a directory", path.display(), p.display());
            }
            if let Err(e) = accepts_files(p) {
                bail!("{flag} {}: cannot write in {}: {e}", path.display(), p.display());
            }
            return Ok(());
        }
        p = parent_of(p);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_missing_directory_or_a_file_in_the_way_is_named_with_the_option() {
        let tmp = std::env::temp_dir().join(format!("gsens-outputs-{}", std::process::id()));
        std::fs::create_dir_all(&tmp).unwrap();
        assert!(file("--json", &tmp.join("r.json")).is_ok());
        let e = file("--json", &tmp.join("missing/r.json")).unwrap_err().to_string();
        assert!(e.starts_with("--json ") && e.contains("does not exist"), "{e}");
        assert!(dir("--out", &tmp.join("a/b/c")).is_ok());
        // In a directory the command makes first.
        let made = tmp.join("made");
        assert!(maybe_file_in("--json", Some(&made.join("r.json")), Some(&made)).is_ok());
        assert!(maybe_file_in("--json", Some(&tmp.join("other/r.json")), Some(&made)).is_err());
        std::fs::write(tmp.join("f"), "").unwrap();
        let e = dir("--out", &tmp.join("f/sub")).unwrap_err().to_string();
        assert!(e.starts_with("--out ") && e.contains("not a directory"), "{e}");
        std::fs::remove_dir_all(&tmp).unwrap();
    }
}
