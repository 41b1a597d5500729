//! CSV plumbing shared by the readers: header lookup, cell parsing, error construction.

use std::io::Read;

use crate::error::{Column, FormatError};

/// A CSV source being read: the `csv` reader, the reused record and what is
/// needed to build error messages.
pub(crate) struct CsvSource<R: Read> {
    reader: csv::Reader<R>,
    /// The reused record of the current row.
    pub record: csv::ByteRecord,
    /// Source name.
    pub file: String,
    /// Header names as found (trimmed).
    pub header: Vec<String>,
}

impl<R: Read> CsvSource<R> {
    /// Reads the header of `input` and locates the `required` columns (in the
    /// order given; any order in the file, extra columns ignored).
    pub fn open(input: R, file: &str, required: &[&str]) -> Result<(Self, Vec<usize>), FormatError> {
        let reader = csv::ReaderBuilder::new().has_headers(false).flexible(true).from_reader(input);
        let mut src = CsvSource { reader, record: csv::ByteRecord::new(), file: file.to_owned(), header: Vec::new() };
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

    /// Reads the next record into `self.record`; `false` at the end of the input.
    #[inline]
    pub fn next_record(&mut self) -> Result<bool, FormatError> {
        self.reader.read_byte_record(&mut self.record).map_err(|e| FormatError::csv(&self.file, e))
    }

    /// The 1-based line of the current record.
    #[inline]
    pub fn line(&self) -> u64 {
        self.record.position().map_or(0, |p| p.line())
    }

    /// Checks that the current record has as many fields as the header.
    #[inline]
    pub fn check_field_count(&self) -> Result<(), FormatError> {
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
    pub fn column(&self, index: usize) -> Column {
        Column { index: index + 1, name: self.header[index].clone() }
    }

    /// The raw (untrimmed) cell at 0-based column `index` of the current record.
    #[inline]
    pub fn cell(&self, index: usize) -> &[u8] {
        self.record.get(index).unwrap_or(b"")
    }

    /// Parses the cell at column `index` as a finite `f64`.
    #[inline]
    pub fn f64_at(&self, index: usize) -> Result<f64, FormatError> {
        match self.opt_f64_at(index)? {
            Some(v) => Ok(v),
            None => Err(self.empty_cell_error(index, "a number")),
        }
    }

    /// Parses the cell at column `index` as a finite `f64`, `None` if the cell is empty.
    #[inline]
    pub fn opt_f64_at(&self, index: usize) -> Result<Option<f64>, FormatError> {
        let raw = self.cell(index).trim_ascii();
        if raw.is_empty() {
            return Ok(None);
        }
        let parsed =
            parse_decimal_fast(raw).or_else(|| std::str::from_utf8(raw).ok().and_then(|s| s.parse::<f64>().ok()));
        match parsed {
            Some(v) if v.is_finite() => Ok(Some(v)),
            Some(_) => Err(self.non_finite_error(index)),
            None => Err(self.not_a_number_error(index, "a number")),
        }
    }

    /// Parses the cell at column `index` as a `u32`.
    #[inline]
    pub fn u32_at(&self, index: usize) -> Result<u32, FormatError> {
        let raw = self.cell(index).trim_ascii();
        if raw.is_empty() {
            return Err(self.empty_cell_error(index, "a non-negative integer"));
        }
        // Fast path: plain decimal digits.
        if raw.len() <= 9 && raw.iter().all(u8::is_ascii_digit) {
            return Ok(raw.iter().fold(0u32, |acc, d| acc * 10 + u32::from(d - b'0')));
        }
        std::str::from_utf8(raw)
            .ok()
            .and_then(|s| s.parse::<u32>().ok())
            .ok_or_else(|| self.not_a_number_error(index, "a non-negative integer"))
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

/// Exact fast path for plain decimals (`[+-]digits[.digits]`, no exponent) of at
/// at most 19 characters whose digit string `w` is at most 2^53 and that have at most
/// 22 fraction digits: `w / 10^f` with both operands exact, so the one division
/// is correctly rounded (Clinger's fast path) and the result is the same as
/// `str::parse::<f64>`. `None` for anything else (the caller falls back to std).
#[inline]
pub(crate) fn parse_decimal_fast(b: &[u8]) -> Option<f64> {
    const POW10: [f64; 23] = [
        1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18, 1e19,
        1e20, 1e21, 1e22,
    ];
    let (neg, digits) = match b.first() {
        Some(b'-') => (true, &b[1..]),
        Some(b'+') => (false, &b[1..]),
        _ => (false, b),
    };
    if digits.is_empty() || digits.len() > 19 {
        return None;
    }
    let mut w: u64 = 0;
    let mut n_digits = 0usize;
    let mut dot: Option<usize> = None;
    for &c in digits {
        if c.is_ascii_digit() {
            w = w * 10 + u64::from(c - b'0');
            n_digits += 1;
        } else if c == b'.' && dot.is_none() {
            dot = Some(n_digits);
        } else {
            return None;
        }
    }
    let frac = n_digits - dot.unwrap_or(n_digits);
    if n_digits == 0 || w > (1u64 << 53) || frac > 22 {
        return None;
    }
    let v = w as f64 / POW10[frac];
    Some(if neg { -v } else { v })
}

/// The text of a cell for an error message: lossily decoded, trimmed, at most 40 characters.
fn cell_text(raw: &[u8]) -> String {
    let s = String::from_utf8_lossy(raw.trim_ascii());
    if s.chars().count() > 40 { format!("{}…", s.chars().take(40).collect::<String>()) } else { s.into_owned() }
}

/// The display name of a path: the path as given.
pub(crate) fn path_name(path: &std::path::Path) -> String {
    path.display().to_string()
}

#[cfg(test)]
mod tests {
    use super::parse_decimal_fast;

    #[test]
    fn fast_path_agrees_with_std() {
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
            "123456789012345",
            "9007199254740992",
            "9007199254740993",
            "0.000001",
            "1.7976931348623157",
            "00012.5000",
            "3600.025",
            "0.0000000000000000000001",
            "0.00000000000000000000001",
            "12345678901234567890",
            "99999999999999999999",
            "9999999999999999999",
            "-999999999999999999",
            "1e5",
            ".",
            "-",
            "",
            "1.2.3",
            "1,2",
            "inf",
            "NaN",
            "0x10",
            " 1",
        ];
        for c in cases {
            let std = c.parse::<f64>().ok();
            if let Some(v) = parse_decimal_fast(c.as_bytes()) {
                assert_eq!(Some(v.to_bits()), std.map(f64::to_bits), "{c}");
            }
        }
        assert_eq!(parse_decimal_fast(b"45.2"), Some(45.2));
        assert_eq!(parse_decimal_fast(b"-0").map(f64::to_bits), Some((-0.0f64).to_bits()));
        assert_eq!(parse_decimal_fast(b"9007199254740993"), None);
        assert_eq!(parse_decimal_fast(b"1e5"), None);
        // Random decimals of up to 16 digits with 0..17 fraction digits.
        let mut x: u64 = 1;
        for _ in 0..200_000 {
            x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            let w = (x >> 20) % 10_000_000_000_000_000;
            let f = ((x >> 8) % 18) as usize;
            let mut s = format!("{w:0>width$}", width = f + 1);
            s.insert(s.len() - f, '.');
            let std = s.parse::<f64>().unwrap();
            if let Some(v) = parse_decimal_fast(s.as_bytes()) {
                assert_eq!(v.to_bits(), std.to_bits(), "{s}");
            }
        }
    }
}
