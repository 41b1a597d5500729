//! The error type of the crate.

use std::fmt;

/// A column of a CSV file: its 1-based position in the file and its name.
///
/// Displays as ``column 3 (`fy_mps2`)``.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Column {
    /// 1-based position of the column in the file.
    pub index: usize,
    /// The column's name (as the header spells it).
    pub name: String,
}

impl fmt::Display for Column {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "column {} (`{}`)", self.index, self.name)
    }
}

/// Everything that can be wrong with a log file, or with a log held in memory
/// (an [`ImuSeries`](crate::ImuSeries) that breaks the readers' invariants).
///
/// The `Display` form always starts with the source (the file name, or the
/// display name given to a reader) and, where it applies, names the 1-based
/// line (the header is line 1) and the column (1-based, and its name), e.g.
///
/// ```text
/// imu.csv: line 17, column 3 (`fy_mps2`): `abc` is not a number
/// ```
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum FormatError {
    /// The file could not be opened or read.
    #[error("{file}: cannot read: {error}")]
    Io {
        /// Source name.
        file: String,
        /// The underlying error, quoted in the message (so not also a `source`: a printed chain would say it twice).
        error: std::io::Error,
    },
    /// The file holds nothing, not even a header line.
    #[error("{file}: empty file: expected a header line `{expected_header}`")]
    EmptyFile {
        /// Source name.
        file: String,
        /// The header the format expects.
        expected_header: String,
    },
    /// The file holds a header but no data row.
    #[error("{file}: header only, no data rows")]
    NoData {
        /// Source name.
        file: String,
    },
    /// A column the format requires is absent from the header.
    #[error("{file}: line 1: missing column `{missing}` (header: `{header}`; expected columns `{expected_header}`)")]
    MissingColumn {
        /// Source name.
        file: String,
        /// The name of the missing column.
        missing: String,
        /// The header as found.
        header: String,
        /// The header the format expects (columns in any order).
        expected_header: String,
    },
    /// A required column appears twice in the header.
    #[error("{file}: line 1: column `{name}` appears twice (columns {first_index} and {second_index})")]
    DuplicateColumn {
        /// Source name.
        file: String,
        /// The repeated column name.
        name: String,
        /// 1-based position of its first occurrence.
        first_index: usize,
        /// 1-based position of its second occurrence.
        second_index: usize,
    },
    /// A row does not have as many fields as the header.
    #[error("{file}: line {line}: expected {expected} fields (as in the header), found {found}")]
    FieldCount {
        /// Source name.
        file: String,
        /// 1-based line number.
        line: u64,
        /// Number of fields in the header.
        expected: usize,
        /// Number of fields in the row.
        found: usize,
    },
    /// A required cell is empty.
    #[error("{file}: line {line}, {column}: empty cell, expected {expected}")]
    EmptyCell {
        /// Source name.
        file: String,
        /// 1-based line number.
        line: u64,
        /// The column.
        column: Column,
        /// What the cell should hold.
        expected: &'static str,
    },
    /// A cell does not hold a number of the expected kind.
    #[error("{file}: line {line}, {column}: `{value}` is not {expected}")]
    NotANumber {
        /// Source name.
        file: String,
        /// 1-based line number.
        line: u64,
        /// The column.
        column: Column,
        /// The cell's text (lossily decoded, truncated).
        value: String,
        /// What the cell should hold.
        expected: &'static str,
    },
    /// A number outside what the column allows.
    #[error("{file}: line {line}, {column}: {value} is out of range: expected {expected}")]
    OutOfRange {
        /// Source name.
        file: String,
        /// 1-based line number.
        line: u64,
        /// The column.
        column: Column,
        /// The value.
        value: f64,
        /// What the column allows.
        expected: &'static str,
    },
    /// A cell holds NaN or an infinity.
    #[error("{file}: line {line}, {column}: `{value}` is not a finite number (NaN and infinities are not allowed)")]
    NonFinite {
        /// Source name.
        file: String,
        /// 1-based line number.
        line: u64,
        /// The column.
        column: Column,
        /// The cell's text.
        value: String,
    },
    /// A time stamp is smaller than the previous row's.
    #[error(
        "{file}: line {line}, {column}: time stamp {t_s} s goes backwards (line {previous_line} has {previous_t_s} s)"
    )]
    TimeBackwards {
        /// Source name.
        file: String,
        /// 1-based line number.
        line: u64,
        /// The time column.
        column: Column,
        /// The offending time stamp \[s\].
        t_s: f64,
        /// The previous time stamp \[s\].
        previous_t_s: f64,
        /// Line of the previous time stamp.
        previous_line: u64,
    },
    /// An IMU time stamp repeats the previous row's.
    #[error("{file}: line {line}, {column}: repeated time stamp {t_s} s (already on line {previous_line})")]
    RepeatedTime {
        /// Source name.
        file: String,
        /// 1-based line number.
        line: u64,
        /// The time column.
        column: Column,
        /// The repeated time stamp \[s\].
        t_s: f64,
        /// The line that has the same time stamp.
        previous_line: u64,
    },
    /// A tracking channel appears twice at the same time stamp.
    #[error(
        "{file}: line {line}, {column}: channel {channel} appears twice at t = {t_s} s (already on line {previous_line})"
    )]
    RepeatedChannel {
        /// Source name.
        file: String,
        /// 1-based line number.
        line: u64,
        /// The channel column.
        column: Column,
        /// The repeated channel number.
        channel: u32,
        /// The time stamp \[s\].
        t_s: f64,
        /// The line that has the same channel at the same time.
        previous_line: u64,
    },
    /// A tracking row's signal name, GLONASS k or carrier is invalid
    /// (unknown name, k missing or out of range, carrier outside the GNSS bands
    /// or disagreeing with the signal's).
    #[error("{file}: line {line}, {column}: {error}")]
    InvalidCarrier {
        /// Source name.
        file: String,
        /// 1-based line number.
        line: u64,
        /// The column at fault (`signal`, `glo_k` or `carrier_hz`).
        column: Column,
        /// What is wrong.
        error: Box<crate::signal::SignalError>,
    },
    /// A track (one channel, one PRN) changes its carrier.
    #[error(
        "{file}: line {line}, {column}: channel {channel} (PRN {prn}) is on {} here but was on {} \
         (line {previous_line}): a track keeps one carrier; a channel moved to another signal must change its \
         channel number or PRN",
        carriers[1],
        carriers[0]
    )]
    CarrierChanged {
        /// Source name.
        file: String,
        /// 1-based line number.
        line: u64,
        /// The carrier's column (`signal` or `carrier_hz`).
        column: Column,
        /// The channel.
        channel: u32,
        /// The PRN.
        prn: u32,
        /// The track's carrier so far and the row's (labels).
        carriers: Box<[String; 2]>,
        /// The track's latest row before.
        previous_line: u64,
    },
    /// An in-memory IMU series is inconsistent (lengths, order, non-finite values).
    #[error("{file}: invalid IMU series: {reason}")]
    InvalidImuSeries {
        /// Source name.
        file: String,
        /// What is wrong.
        reason: String,
    },
}

impl FormatError {
    /// The I/O error of `file`.
    pub(crate) fn io(file: &str, error: std::io::Error) -> Self {
        FormatError::Io { file: file.to_owned(), error }
    }

    /// A `csv` error of `file` (with `flexible` byte records, only I/O errors can occur).
    pub(crate) fn csv(file: &str, error: csv::Error) -> Self {
        let line = error.position().map(|p| p.line());
        match error.into_kind() {
            csv::ErrorKind::Io(e) => FormatError::io(file, e),
            other => {
                let msg = match line {
                    Some(l) => format!("line {l}: {other:?}"),
                    None => format!("{other:?}"),
                };
                FormatError::io(file, std::io::Error::new(std::io::ErrorKind::InvalidData, msg))
            }
        }
    }
}
