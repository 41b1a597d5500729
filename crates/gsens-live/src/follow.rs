//! A growing file read as it grows, like `tail -f`.

use std::fs::File;
use std::io::{Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};

/// What one [`Follower::poll`] found.
#[derive(Debug, Default, Clone, PartialEq)]
pub struct Polled {
    /// The complete new lines with their line numbers (from 1), without the
    /// line break. A last line without its line break is held back until it
    /// is complete (a logger caught mid-write).
    pub lines: Vec<(u64, String)>,
    /// The file became shorter than what was read: a logger restarted and
    /// rewrote it. Reading starts again from its beginning, line 1.
    pub restarted: bool,
}

/// Reads the lines a logger appends to a file. The file need not exist yet.
#[derive(Debug)]
pub struct Follower {
    path: PathBuf,
    offset: u64,
    line: u64,
    partial: Vec<u8>,
}

impl Follower {
    /// Follows `path` from its beginning.
    pub fn new(path: impl AsRef<Path>) -> Self {
        Follower { path: path.as_ref().to_path_buf(), offset: 0, line: 0, partial: Vec::new() }
    }

    /// The followed file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Reads what was appended since the last call. A missing file is no
    /// error (not written yet); a file that cannot be read is.
    pub fn poll(&mut self) -> std::io::Result<Polled> {
        let mut out = Polled::default();
        let mut file = match File::open(&self.path) {
            Ok(f) => f,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(out),
            Err(e) => return Err(e),
        };
        let len = file.metadata()?.len();
        if len < self.offset {
            out.restarted = true;
            self.offset = 0;
            self.line = 0;
            self.partial.clear();
        }
        if len == self.offset {
            return Ok(out);
        }
        file.seek(SeekFrom::Start(self.offset))?;
        let mut buf = Vec::with_capacity((len - self.offset) as usize);
        file.take(len - self.offset).read_to_end(&mut buf)?;
        self.offset += buf.len() as u64;
        self.partial.extend_from_slice(&buf);
        let mut start = 0;
        while let Some(pos) = self.partial[start..].iter().position(|&b| b == b'\n') {
            let end = start + pos;
            let mut text = String::from_utf8_lossy(&self.partial[start..end]).into_owned();
            if text.ends_with('\r') {
                text.pop();
            }
            self.line += 1;
            out.lines.push((self.line, text));
            start = end + 1;
        }
        self.partial.drain(..start);
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    #[test]
    fn partial_lines_wait_and_a_rewritten_file_restarts() {
        let dir_scratch = tempfile::Builder::new().prefix("gsens-follow-").tempdir().unwrap();
        let dir = dir_scratch.path().to_path_buf();
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("imu.csv");
        let _ = std::fs::remove_file(&path);
        let mut f = Follower::new(&path);
        assert_eq!(f.poll().unwrap(), Polled::default());
        let mut w = File::create(&path).unwrap();
        write!(w, "a,1\nb,2\nc,").unwrap();
        w.flush().unwrap();
        let p = f.poll().unwrap();
        assert_eq!(p.lines, vec![(1, "a,1".to_string()), (2, "b,2".to_string())]);
        write!(w, "3\r\n").unwrap();
        w.flush().unwrap();
        assert_eq!(f.poll().unwrap().lines, vec![(3, "c,3".to_string())]);
        drop(w);
        std::fs::write(&path, "x\n").unwrap();
        let p = f.poll().unwrap();
        assert!(p.restarted);
        assert_eq!(p.lines, vec![(1, "x".to_string())]);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
