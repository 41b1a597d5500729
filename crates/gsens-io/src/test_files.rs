//! Files for the readers' tests.

/// A file in the system's temporary directory, removed when dropped.
pub(crate) struct TempFile(pub std::path::PathBuf);

impl TempFile {
    /// Writes `text` to a file named after `name` and the process.
    pub(crate) fn new(name: &str, text: &str) -> Self {
        let path = std::env::temp_dir().join(format!("gsens-io-{}-{name}", std::process::id()));
        std::fs::write(&path, text).unwrap();
        TempFile(path)
    }
}

impl Drop for TempFile {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.0);
    }
}
