//! Reading a configuration file's text (a scenario TOML, a GNSS-SDR or
//! PocketSDR options file) with a size limit.

use std::path::Path;

/// The largest configuration file gsens reads \[bytes\]: 1 MiB. A scenario
/// or a receiver's options file is a few kilobytes (GNSS-SDR's longest
/// example configurations are under 20 kB); a larger file is something else
/// given in its place (a log, a capture), and reading it whole to find out
/// would hold all of it in memory.
pub const MAX_CONFIG_BYTES: u64 = 1 << 20;

/// The text of the configuration file `path`; a file larger than
/// [`MAX_CONFIG_BYTES`] is an error of kind `InvalidData` saying so (its
/// bytes are not read).
pub fn read_config_text(path: &Path) -> std::io::Result<String> {
    let file = std::fs::File::open(path)?;
    let len = file.metadata()?.len();
    if len > MAX_CONFIG_BYTES {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!(
                "{len} bytes is not a configuration file (at most {MAX_CONFIG_BYTES} bytes; a configuration is a few \
                 kilobytes): is it a log given in its place?"
            ),
        ));
    }
    std::io::read_to_string(file)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_file_beyond_the_limit_is_refused_unread() {
        let dir_scratch = tempfile::Builder::new().prefix("gsens-io-config-").tempdir().unwrap();
        let dir = dir_scratch.path().to_path_buf();
        std::fs::create_dir_all(&dir).unwrap();
        let small = dir.join("small.toml");
        std::fs::write(&small, "[loop]\nbn_hz = 3.0\n").unwrap();
        assert_eq!(read_config_text(&small).unwrap(), "[loop]\nbn_hz = 3.0\n");
        let large = dir.join("large.toml");
        let f = std::fs::File::create(&large).unwrap();
        f.set_len(MAX_CONFIG_BYTES + 1).unwrap();
        let e = read_config_text(&large).unwrap_err();
        assert_eq!(e.kind(), std::io::ErrorKind::InvalidData);
        assert!(e.to_string().contains("1048577 bytes is not a configuration file"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
