//! The error types of the crate: [`GnssSdrError`] for the files (every
//! message names the file, and for a record of a dump its index and byte
//! offset), [`LayoutSpecError`] for a record layout given as text.

use crate::dump::REQUIRED_FIELDS;

/// What can go wrong reading GNSS-SDR's files or converting them.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum GnssSdrError {
    /// A file or directory could not be read.
    #[error("{file}: cannot read: {error}")]
    Io {
        /// The file.
        file: String,
        /// The underlying error, quoted in the message (so not also a `source`: a printed chain would say it twice).
        error: std::io::Error,
    },
    /// A file or directory could not be written.
    #[error("{file}: cannot write: {error}")]
    Write {
        /// The file.
        file: String,
        /// The underlying error, quoted in the message (so not also a `source`: a printed chain would say it twice).
        error: std::io::Error,
    },
    /// Neither the configuration nor the caller gives the sampling rate.
    #[error(
        "the sampling rate is unknown: the configuration gives neither GNSS-SDR.internal_fs_sps nor \
         SignalSource.sampling_frequency"
    )]
    UnknownSamplingRate,
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
    /// A record layout given as text does not parse.
    #[error("layout: {0}")]
    Layout(LayoutSpecError),
    /// A configuration file is malformed or asks for something not modelled.
    #[error("{file}: line {line}: {reason}")]
    Conf {
        /// The configuration file.
        file: String,
        /// 1-based line (0 when the key is absent).
        line: usize,
        /// What is wrong.
        reason: String,
    },
    /// A tracking dump is empty.
    #[error("{file}: empty tracking dump (0 bytes): no record; expected {expected}")]
    EmptyDump {
        /// The dump.
        file: String,
        /// The layouts the reader knows, with their record sizes.
        expected: String,
    },
    /// No layout explains the dump.
    #[error(
        "{file}: {len} bytes fits no tracking-dump layout (a dump of another GNSS-SDR version or block?); tried: {tried}"
    )]
    NoLayoutFits {
        /// The dump.
        file: String,
        /// File length \[bytes\].
        len: u64,
        /// Every layout tried and why it does not fit (record, byte offset, field).
        tried: String,
    },
    /// The whole records of one layout are plausible and a partial record follows.
    #[error(
        "{file}: truncated tracking dump: {len} bytes is {records} whole records of {layout} and {rest} bytes of a \
         partial one (a run that did not end cleanly, or a cut copy); cut it to {records} records"
    )]
    TruncatedDump {
        /// The dump.
        file: String,
        /// File length \[bytes\].
        len: u64,
        /// The layout whose whole records are plausible.
        layout: String,
        /// Whole records.
        records: u64,
        /// Bytes left over.
        rest: u64,
    },
    /// Records of one layout, then records of another (a file appended to by two versions).
    #[error(
        "{file}: mixed tracking-dump layouts: {first_records} records of {first}, then from byte offset {offset} \
         {second_records} records of {second} (a dump file appended to by two GNSS-SDR versions?); split it there"
    )]
    MixedLayouts {
        /// The dump.
        file: String,
        /// The first layout.
        first: String,
        /// Its records.
        first_records: u64,
        /// Byte offset where the second layout starts.
        offset: u64,
        /// The second layout.
        second: String,
        /// Its records.
        second_records: u64,
    },
    /// The dump's length fits several layouts and the records do not decide.
    #[error(
        "{file}: {len} bytes fits several tracking-dump layouts ({candidates}) and every record is plausible in \
         each; give the layout by name (the conversion's layout setting)"
    )]
    AmbiguousLayout {
        /// The dump.
        file: String,
        /// File length \[bytes\].
        len: u64,
        /// The layouts that fit.
        candidates: String,
    },
    /// A record holds an implausible value for its layout.
    #[error("{file}: record {index} (byte offset {offset}): {reason} (layout {layout})")]
    BadRecord {
        /// The dump.
        file: String,
        /// 0-based record index.
        index: u64,
        /// Byte offset of the record's start.
        offset: u64,
        /// The layout used.
        layout: String,
        /// What is wrong.
        reason: String,
    },
    /// A dump of a layout that only blocks gsens does not model write.
    #[error(
        "{file}: a tracking dump of layout {layout} ({description}): gsens models only the carrier loop of \
         dll_pll_veml_tracking (GPS_L1_CA_DLL_PLL_Tracking), so it cannot convert this one; track with \
         Tracking_1C.implementation=GPS_L1_CA_DLL_PLL_Tracking"
    )]
    NotModelled {
        /// The dump.
        file: String,
        /// The layout's name.
        layout: String,
        /// Its blocks and versions.
        description: String,
    },
    /// A `.mat` tracking dump that cannot be read.
    #[error("{file}: {reason}")]
    Mat {
        /// The `.mat` file.
        file: String,
        /// What is wrong.
        reason: String,
    },
    /// A dump's file name ends in a channel number beyond any receiver's.
    #[error("{file}: the channel number its name ends in ({digits}) is beyond 4294967295: not a tracking dump's name")]
    ChannelNumberOutOfRange {
        /// The dump.
        file: String,
        /// The digits at the end of its name.
        digits: String,
    },
    /// Two dumps track one satellite at the same time: a receiver gives a
    /// signal of a satellite one channel at a time, so one is a copy.
    #[error(
        "{first} and {second} both track PRN {prn} at sample {sample}: a receiver tracks a satellite on one channel \
         at a time (is one a copy of the other?)"
    )]
    SameSatelliteTwice {
        /// The first dump.
        first: String,
        /// The second dump.
        second: String,
        /// The satellite.
        prn: u32,
        /// A sample counter both hold it at.
        sample: u64,
    },
    /// A dump directory holds no `*.dat` dump.
    #[error("{dir}: no tracking dump (files named <prefix><channel>.dat or .mat, e.g. trk_ch_0.dat) found")]
    NoDumps {
        /// The directory.
        dir: String,
    },
    /// No record survives the conversion.
    #[error("{dir}: no usable tracking record: {reason}")]
    NothingUsable {
        /// The dump directory.
        dir: String,
        /// Why each dump was dropped.
        reason: String,
    },
    /// The converted rows or the IMU log do not hold the formats.
    #[error(transparent)]
    Format(#[from] gsens_io::FormatError),
    /// The calibration failed.
    #[error(transparent)]
    Pipeline(#[from] gsens_calib::PipelineError),
}

impl GnssSdrError {
    /// The conversion setting the error is about, when its message begins
    /// with that setting's name ([`crate::ImportSettings::override_with`]'s
    /// errors), so that a caller can name it its own way.
    pub fn setting(&self) -> Option<&'static str> {
        match self {
            GnssSdrError::Setting { name, .. } => Some(name),
            GnssSdrError::Layout(_) => Some("layout"),
            _ => None,
        }
    }
}

/// A record layout spec (`name:type,name:type,…`, see
/// [`DumpLayout::parse_spec`](crate::dump::DumpLayout::parse_spec)) that does not parse.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum LayoutSpecError {
    /// An item without the `:` between name and type.
    #[error("`{item}`: expected name:type")]
    ExpectedNameType {
        /// The item, trimmed.
        item: String,
    },
    /// A type other than f32, f64, u32, u64, i32.
    #[error("`{item}`: unknown type `{ty}` (f32, f64, u32, u64, i32)")]
    UnknownType {
        /// The item, trimmed.
        item: String,
        /// The type given, trimmed.
        ty: String,
    },
    /// One of the `REQUIRED_FIELDS` is missing.
    #[error("the layout lacks the field `{field}` (required: {})", REQUIRED_FIELDS.join(", "))]
    MissingField {
        /// The first required field missing.
        field: &'static str,
    },
}
