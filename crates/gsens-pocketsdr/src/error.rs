//! The error type of the crate: every message names the file and, where it
//! applies, the line and the field.

/// What can go wrong reading PocketSDR's files or converting them.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PocketSdrError {
    /// A file could not be read.
    #[error("{file}: cannot read: {error}")]
    Io {
        /// The file.
        file: String,
        /// The underlying error, quoted in the message.
        error: std::io::Error,
    },
    /// The log is empty.
    #[error("{file}: empty log (0 bytes): expected the log of pocket_trk -log FILE ($CH lines)")]
    EmptyLog {
        /// The log.
        file: String,
    },
    /// The log holds no readable `$CH` line.
    #[error(
        "{file}: no readable $CH line in {lines} lines (line 1: {first:?}): expected the log of pocket_trk -log \
         FILE, which writes one $CH line per tracked channel every `epoch` seconds{garbled}"
    )]
    NoChannelLines {
        /// The log.
        file: String,
        /// Its number of lines.
        lines: u64,
        /// Its first line (shortened).
        first: String,
        /// The first garbled `$CH` line, if any, as text.
        garbled: String,
    },
    /// The log holds no GPS L1 C/A channel.
    #[error("{file}: no GPS L1 C/A ($CH … L1CA) line; signals logged: {signals}; only L1CA is estimated")]
    NoL1ca {
        /// The log.
        file: String,
        /// The signals found, with their line counts.
        signals: String,
    },
    /// An options file line that cannot be used.
    #[error("{file}: line {line}: {key}: {reason}")]
    Options {
        /// The options file.
        file: String,
        /// 1-based line.
        line: usize,
        /// The key (or `line` when none could be read).
        key: String,
        /// What is wrong.
        reason: String,
    },
    /// The log's interval does not match the options file's `epoch`.
    #[error(
        "{file}: its $CH lines are {measured_s} s apart (lines {line_a} and {line_b}), but {source_name} gives epoch = \
         {stated_s} s: the log was not made with these options"
    )]
    EpochMismatch {
        /// The log.
        file: String,
        /// The interval measured from the log \[s\].
        measured_s: f64,
        /// Two lines `measured_s` apart.
        line_a: u64,
        /// The second.
        line_b: u64,
        /// The stated `epoch` \[s\].
        stated_s: f64,
        /// Where it was stated.
        source_name: String,
    },
    /// A conversion setting outside its range.
    #[error("{name} must be {expected}, got {value}")]
    Setting {
        /// The setting.
        name: &'static str,
        /// Its value.
        value: f64,
        /// Its range.
        expected: &'static str,
    },
    /// No track is left to estimate from.
    #[error("{file}: no GPS L1 C/A track is left after the FLL pull-in and the settling time ({settle_s} s): {why}")]
    NoTracks {
        /// The log.
        file: String,
        /// The settling time in use \[s\].
        settle_s: f64,
        /// What became of the tracks.
        why: String,
    },
    /// The converted rows or the IMU log do not hold the formats.
    #[error(transparent)]
    Format(#[from] gsens_io::FormatError),
    /// The calibration failed.
    #[error(transparent)]
    Pipeline(#[from] gsens_calib::PipelineError),
}

impl PocketSdrError {
    /// The conversion setting the error is about, when its message begins
    /// with that setting's name ([`crate::ImportSettings::check`]), so that
    /// a caller can name it its own way.
    pub fn setting(&self) -> Option<&'static str> {
        match self {
            PocketSdrError::Setting { name, .. } => Some(name),
            _ => None,
        }
    }
}
