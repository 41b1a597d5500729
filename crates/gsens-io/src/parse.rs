//! CSV plumbing shared by the readers: header lookup, cell parsing, error construction.

use std::io::Read;

use crate::columns::{CellFault, Fault, HeaderError};
use crate::error::{Column, FormatError};

/// The bytes of a source as the `csv` reader reads them, kept from the
/// start of the current record on, and the line ends before them: the line
/// a record starts on. `csv`'s own `Position::line` is that of the start of
/// parsing, which is a blank line (or the `\n` of a `\r\n`) before the
/// record when there is one (rust-csv issue 208): an error message would name
/// the line above the row.
struct LineCounter<R> {
    inner: R,
    /// Bytes read from absolute offset `base` on; those before `window[seen]`
    /// are counted in `newlines_before` (and dropped now and then).
    window: Vec<u8>,
    base: u64,
    seen: usize,
    newlines_before: u64,
}

/// Counted bytes kept at most (beyond it they are dropped at the next read).
const COUNTED_BYTES_KEPT: usize = 1 << 16;

impl<R: Read> Read for LineCounter<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        if self.seen > COUNTED_BYTES_KEPT {
            self.window.drain(..self.seen);
            self.base += self.seen as u64;
            self.seen = 0;
        }
        let n = self.inner.read(buf)?;
        self.window.extend_from_slice(&buf[..n]);
        Ok(n)
    }
}

impl<R> LineCounter<R> {
    fn new(inner: R) -> Self {
        LineCounter { inner, window: Vec::new(), base: 0, seen: 0, newlines_before: 0 }
    }

    /// The 1-based line of the record `csv` parsed from absolute offset
    /// `start` on (its first byte that is not a line end); `None` when
    /// `start` lies before a record asked about already.
    fn line_of_record_at(&mut self, start: u64) -> Option<u64> {
        let at = usize::try_from(start.checked_sub(self.base)?).ok()?;
        if at < self.seen || at > self.window.len() {
            return None;
        }
        self.newlines_before += memchr::memchr_iter(b'\n', &self.window[self.seen..at]).count() as u64;
        self.seen = at;
        let blank =
            self.window[at..].iter().take_while(|&&b| b == b'\n' || b == b'\r').filter(|&&b| b == b'\n').count();
        Some(self.newlines_before + blank as u64 + 1)
    }
}

/// The `csv` reader of every source: no header row of its own (the readers
/// check theirs), rows of any length (checked against the header here).
fn csv_reader<R: Read>(input: R) -> csv::Reader<LineCounter<R>> {
    csv::ReaderBuilder::new().has_headers(false).flexible(true).from_reader(LineCounter::new(input))
}

/// A CSV source being read: the `csv` reader, the reused record and what is
/// needed to build error messages.
pub(crate) struct CsvSource<R: Read> {
    reader: csv::Reader<LineCounter<R>>,
    /// The reused record of the current row.
    pub record: csv::ByteRecord,
    /// The line the current record starts on.
    line: u64,
    /// Source name.
    pub file: String,
    /// Header names as found (trimmed).
    pub header: Vec<String>,
}

impl<R: Read> CsvSource<R> {
    /// Reads the header of `input` and locates the `required` columns (in the
    /// order given; any order in the file, extra columns ignored).
    pub(crate) fn open(input: R, file: &str, required: &[&str]) -> Result<(Self, Vec<usize>), FormatError> {
        let reader = csv_reader(input);
        let mut src =
            CsvSource { reader, record: csv::ByteRecord::new(), line: 0, file: file.to_owned(), header: Vec::new() };
        let expected_header = required.join(",");
        if !src.next_record()? {
            return Err(FormatError::EmptyFile { file: src.file, expected_header });
        }
        src.header = src
            .record
            .iter()
            .enumerate()
            .map(|(i, f)| {
                let f = if i == 0 { f.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(f) } else { f };
                String::from_utf8_lossy(f.trim_ascii()).into_owned()
            })
            .collect();
        let mut indices = Vec::with_capacity(required.len());
        for name in required {
            let mut found = src.header.iter().enumerate().filter(|(_, h)| h == name).map(|(i, _)| i);
            match (found.next(), found.next()) {
                (None, _) => {
                    return Err(FormatError::MissingColumn {
                        file: src.file,
                        missing: (*name).to_owned(),
                        header: src.header.join(","),
                        expected_header,
                    });
                }
                (Some(a), Some(b)) => {
                    return Err(FormatError::DuplicateColumn {
                        file: src.file,
                        name: (*name).to_owned(),
                        first_index: a + 1,
                        second_index: b + 1,
                    });
                }
                (Some(i), None) => indices.push(i),
            }
        }
        Ok((src, indices))
    }

    /// The error of a header whose columns gsens cannot read.
    #[cold]
    pub(crate) fn header_error(&self, e: HeaderError) -> FormatError {
        match e {
            HeaderError::Missing { name } => FormatError::MissingColumn {
                file: self.file.clone(),
                missing: name.to_owned(),
                header: self.header.join(","),
                expected_header: crate::tracking::TRACKING_COLUMNS.join(","),
            },
            HeaderError::Duplicate { name, first_index, second_index } => FormatError::DuplicateColumn {
                file: self.file.clone(),
                name: name.to_owned(),
                first_index,
                second_index,
            },
        }
    }

    /// The error of a cell of the current record the row parser refused.
    #[cold]
    pub(crate) fn cell_error(&self, f: CellFault) -> FormatError {
        let index = f.index;
        match f.fault {
            Fault::Cell { bad: BadCell::Empty, expected } => self.empty_cell_error(index, expected),
            Fault::Cell { bad: BadCell::NonFinite, .. } => self.non_finite_error(index),
            Fault::Cell { bad: BadCell::NotANumber, expected } => self.not_a_number_error(index, expected),
            Fault::Carrier(error) => FormatError::InvalidCarrier {
                file: self.file.clone(),
                line: self.line(),
                column: self.column(index),
                error: Box::new(error),
            },
        }
    }

    /// Reads the next record into `self.record`; `false` at the end of the input.
    #[inline]
    pub(crate) fn next_record(&mut self) -> Result<bool, FormatError> {
        let more = self.reader.read_byte_record(&mut self.record).map_err(|e| FormatError::csv(&self.file, e))?;
        if let Some(p) = self.record.position() {
            let (start, csv_line) = (p.byte(), p.line());
            self.line = self.reader.get_mut().line_of_record_at(start).unwrap_or(csv_line);
        }
        Ok(more)
    }

    /// The 1-based line the current record starts on.
    #[inline]
    pub(crate) fn line(&self) -> u64 {
        self.line
    }

    /// Checks that the current record has as many fields as the header.
    #[inline]
    pub(crate) fn check_field_count(&self) -> Result<(), FormatError> {
        if self.record.len() == self.header.len() { Ok(()) } else { Err(self.field_count_error()) }
    }

    #[cold]
    fn field_count_error(&self) -> FormatError {
        FormatError::FieldCount {
            file: self.file.clone(),
            line: self.line(),
            expected: self.header.len(),
            found: self.record.len(),
        }
    }

    /// The column at 0-based position `index`.
    pub(crate) fn column(&self, index: usize) -> Column {
        Column { index: index + 1, name: self.header[index].clone() }
    }

    /// The raw (untrimmed) cell at 0-based column `index` of the current record.
    #[inline]
    pub(crate) fn cell(&self, index: usize) -> &[u8] {
        self.record.get(index).unwrap_or(b"")
    }

    /// Parses the cell at column `index` as a finite `f64`.
    #[inline]
    pub(crate) fn f64_at(&self, index: usize) -> Result<f64, FormatError> {
        match self.opt_f64_at(index)? {
            Some(v) => Ok(v),
            None => Err(self.empty_cell_error(index, "a number")),
        }
    }

    /// Parses the cell at column `index` as a finite `f64`, `None` if the cell is empty.
    #[inline]
    pub(crate) fn opt_f64_at(&self, index: usize) -> Result<Option<f64>, FormatError> {
        match cell_f64(self.cell(index)) {
            Ok(v) => Ok(v),
            Err(BadCell::NonFinite) => Err(self.non_finite_error(index)),
            Err(_) => Err(self.not_a_number_error(index, "a number")),
        }
    }

    #[cold]
    fn empty_cell_error(&self, index: usize, expected: &'static str) -> FormatError {
        FormatError::EmptyCell { file: self.file.clone(), line: self.line(), column: self.column(index), expected }
    }

    #[cold]
    fn not_a_number_error(&self, index: usize, expected: &'static str) -> FormatError {
        FormatError::NotANumber {
            file: self.file.clone(),
            line: self.line(),
            column: self.column(index),
            value: cell_text(self.cell(index)),
            expected,
        }
    }

    #[cold]
    fn non_finite_error(&self, index: usize) -> FormatError {
        FormatError::NonFinite {
            file: self.file.clone(),
            line: self.line(),
            column: self.column(index),
            value: cell_text(self.cell(index)),
        }
    }
}

/// Why a cell does not hold the number it should.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum BadCell {
    /// Nothing but ASCII white space.
    Empty,
    /// Text that is not a number of the kind asked for.
    NotANumber,
    /// A NaN or an infinity.
    NonFinite,
}

/// The cell `raw` as a finite `f64` (ASCII white space around it ignored),
/// `None` when it is empty: the one rule for every reader's numbers.
#[inline]
pub(crate) fn cell_f64(raw: &[u8]) -> Result<Option<f64>, BadCell> {
    let raw = raw.trim_ascii();
    if raw.is_empty() {
        return Ok(None);
    }
    // fast-float2 parses straight from bytes (Eisel–Lemire, correctly rounded
    // like std) and rejects trailing garbage; NaN/inf parse and are refused here.
    match fast_float2::parse::<f64, _>(raw) {
        Ok(v) if v.is_finite() => Ok(Some(v)),
        Ok(_) => Err(BadCell::NonFinite),
        Err(_) => Err(BadCell::NotANumber),
    }
}

/// The cell `raw` as a `u32` (ASCII white space around it ignored; a `+`
/// sign allowed, as `str::parse` allows it).
#[inline]
pub(crate) fn cell_u32(raw: &[u8]) -> Result<u32, BadCell> {
    let raw = raw.trim_ascii();
    if raw.is_empty() {
        return Err(BadCell::Empty);
    }
    // Fast path: plain decimal digits.
    if raw.len() <= 9 && raw.iter().all(u8::is_ascii_digit) {
        return Ok(raw.iter().fold(0u32, |acc, d| acc * 10 + u32::from(d - b'0')));
    }
    std::str::from_utf8(raw).ok().and_then(|s| s.parse::<u32>().ok()).ok_or(BadCell::NotANumber)
}

/// A cell's text for a message: lossily decoded, trimmed, cut at 40 characters.
pub(crate) fn cell_text(raw: &[u8]) -> String {
    let s = String::from_utf8_lossy(raw.trim_ascii());
    if s.chars().count() > 40 { format!("{}…", s.chars().take(40).collect::<String>()) } else { s.into_owned() }
}

/// The display name of a path: the path as given.
pub(crate) fn path_name(path: &std::path::Path) -> String {
    path.display().to_string()
}

#[cfg(test)]
mod tests {
    /// The crate parses with fast-float2; it must give std's bits and accept/refuse the same text.
    #[test]
    fn fast_float2_agrees_with_std() {
        let cases = [
            "0",
            "-0",
            "+0",
            "0.0",
            "-0.0",
            "5.",
            ".5",
            "45.2",
            "-12.375",
            "0.1",
            "0.3",
            "9007199254740993",
            "0.000001",
            "1.7976931348623157",
            "00012.5000",
            "3600.025",
            "1e5",
            "1E-3",
            ".",
            "-",
            "",
            "1.2.3",
            "1,2",
            "0x10",
            " 1",
            "1 ",
            "abc",
        ];
        for c in cases {
            let std = c.parse::<f64>().ok().map(f64::to_bits);
            let fast = fast_float2::parse::<f64, _>(c.as_bytes()).ok().map(f64::to_bits);
            assert_eq!(fast, std, "{c:?}");
        }
        let mut x: u64 = 1;
        for _ in 0..200_000 {
            x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            let w = (x >> 20) % 10_000_000_000_000_000;
            let f = ((x >> 8) % 18) as usize;
            let mut s = format!("{w:0>width$}", width = f + 1);
            s.insert(s.len() - f, '.');
            let std = s.parse::<f64>().unwrap();
            assert_eq!(fast_float2::parse::<f64, _>(s.as_bytes()).unwrap().to_bits(), std.to_bits(), "{s}");
        }
    }
}
