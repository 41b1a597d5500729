//! Records of CSV text that holds no quote character: the fast path of the
//! file readers.
//!
//! Without a `"` the `csv` crate's reading (RFC 4180 with `\r`, `\n` or
//! `\r\n` ending a record, blank lines skipped, no header of its own) comes
//! down to this: a record is a line, its cells are the bytes between
//! commas. So such text is cut into lines with `memchr` over large blocks,
//! and each line's cells are parsed in place as they are reached
//! ([`Cells`]), without `csv`'s per-byte state machine, its record copies or
//! a second pass to count lines. Whatever would need that state machine (a
//! quote, a `\r` that does not end a line) makes [`for_each_plain_line`]
//! decline, and the caller reads the text with `csv` instead; the readers
//! also leave every error to their `csv` path, so the messages are that
//! path's. Tests compare the two on the same bytes (the `tracking_chunks`
//! fuzz target too).

use std::io::{Cursor, Read, Seek, SeekFrom};
use std::path::Path;

use crate::parse::CsvSource;

/// Bytes read at a time (a line longer than this grows the buffer).
const BLOCK_BYTES: usize = 1 << 18;

/// Header lines longer than this are left to the `csv` path.
const HEADER_BYTES: usize = 1 << 16;

/// A file opened for the fast path: positioned at its first row, its header
/// read by `csv` (the same checks and names as the `csv` path).
pub(crate) struct PlainFile {
    /// The file, at the first byte after the header line.
    pub file: std::fs::File,
    /// The header, as a source of no rows (for its names and columns).
    pub header: CsvSource<Cursor<Vec<u8>>>,
    /// The positions of the required columns, in the order asked for.
    pub cols: Vec<usize>,
    /// The offset of the first byte after the header line.
    pub data_start: u64,
}

/// Opens the file at `path` (`total` bytes long, `name` in messages) for the
/// fast path with the columns `required`; `None` where the `csv` path must
/// read it: blank lines before the header, a quote or a lone `\r` in it, a
/// header `csv` refuses (that path then reports it), no row after it.
pub(crate) fn open_plain(path: &Path, name: &str, required: &[&str], total: u64) -> Option<PlainFile> {
    let mut file = std::fs::File::open(path).ok()?;
    let mut head = vec![0u8; HEADER_BYTES.min(usize::try_from(total).ok()?)];
    file.read_exact(&mut head).ok()?;
    let header_end = memchr::memchr(b'\n', &head)? + 1;
    head.truncate(header_end);
    let line = head.strip_suffix(b"\n").map(|l| l.strip_suffix(b"\r").unwrap_or(l))?;
    if line.is_empty() || matches!(line[0], b'\r') || memchr::memchr2(b'"', b'\r', line).is_some() {
        return None;
    }
    let (header, cols) = CsvSource::open(Cursor::new(head), name, required).ok()?;
    let data_start = header_end as u64;
    file.seek(SeekFrom::Start(data_start)).ok()?;
    Some(PlainFile { file, header, cols, data_start })
}

/// The rows `rest_bytes` more of a file hold at the average row length of
/// the first `rows` rows, `bytes_read` long: what a reader reserves its
/// columns for (so that they are neither grown by doubling nor copied).
pub(crate) fn rows_in(rest_bytes: u64, rows: usize, bytes_read: u64) -> f64 {
    rest_bytes as f64 * rows as f64 / bytes_read as f64
}

/// The bounds of the chunks the bytes `from..to` of `file` are read in:
/// `from`, then just after the first line end at or past each
/// `chunk_bytes` (at least 1) from the previous bound, then `to`. The
/// chunks hold whole lines and depend only on the bytes, so a log read in
/// them is the same however many threads read it.
pub(crate) fn chunk_bounds(file: &mut std::fs::File, from: u64, to: u64, chunk_bytes: u64) -> Option<Vec<u64>> {
    let mut bounds = vec![from];
    let mut window = vec![0u8; 1 << 16];
    let mut at = from;
    while to - at > chunk_bytes {
        let mut look = at + chunk_bytes;
        file.seek(SeekFrom::Start(look)).ok()?;
        // The first line end from `look` on, read a window at a time.
        at = loop {
            let got = file.read(&mut window).ok()?;
            if got == 0 {
                break to;
            }
            if let Some(i) = memchr::memchr(b'\n', &window[..got]) {
                break (look + i as u64 + 1).min(to);
            }
            look += got as u64;
        };
        if at >= to {
            break;
        }
        bounds.push(at);
    }
    bounds.push(to);
    Some(bounds)
}

/// The bytes `from..to` of the file at `path`, opened on their own.
pub(crate) fn byte_range(path: &Path, from: u64, to: u64) -> Option<std::io::Take<std::fs::File>> {
    let mut f = std::fs::File::open(path).ok()?;
    f.seek(SeekFrom::Start(from)).ok()?;
    Some(f.take(to - from))
}

/// What the caller makes of one record.
pub(crate) enum Record {
    /// Go on with the next record.
    Next,
    /// Stop reading: the record cannot be taken on the fast path.
    Decline,
}

/// Calls `row(line, bytes_before, text)` for every record of `input` in
/// order: `line` is the 1-based line the record is on counting from
/// `first_line` at the first byte of `input`, `bytes_before` the bytes of
/// `input` before the record's line, `text` the line without its end (not
/// empty: blank lines are skipped, as `csv` skips them). Its cells are the
/// bytes between commas ([`split`], or read in place with [`Cells`]).
///
/// Returns the number of line ends read (`\n`), or `None` when the text
/// holds a quote or a lone `\r`, when reading fails, or when `row` declined.
pub(crate) fn for_each_plain_line<R: Read>(
    mut input: R,
    first_line: u64,
    mut row: impl FnMut(u64, u64, &[u8]) -> Record,
) -> Option<u64> {
    let mut buf = vec![0u8; BLOCK_BYTES];
    // Bytes of `buf` filled (an unfinished line of the last block first), bytes of `input` before `buf`.
    let mut filled = 0usize;
    let mut consumed: u64 = 0;
    let mut line = first_line;
    let mut at_end = false;
    while !at_end {
        while filled < buf.len() {
            let n = match input.read(&mut buf[filled..]) {
                Ok(0) => {
                    at_end = true;
                    break;
                }
                Ok(n) => n,
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                Err(_) => return None,
            };
            filled += n;
        }
        // The whole lines of the block (all of it at the end of the input).
        let whole = if at_end {
            filled
        } else {
            match memchr::memrchr(b'\n', &buf[..filled]) {
                Some(i) => i + 1,
                None => {
                    // One line longer than the buffer: read on into a larger one.
                    let len = buf.len();
                    buf.resize(2 * len, 0);
                    continue;
                }
            }
        };
        let block = &buf[..whole];
        if memchr::memchr(b'"', block).is_some() {
            return None;
        }
        let crs = memchr::memchr(b'\r', block).is_some();
        let mut line_start = 0usize;
        let ends = memchr::memchr_iter(b'\n', block).chain((whole > 0 && block[whole - 1] != b'\n').then_some(whole));
        for at in ends {
            let mut text = &block[line_start..at];
            if crs {
                if let [rest @ .., b'\r'] = text {
                    text = rest;
                }
                if memchr::memchr(b'\r', text).is_some() {
                    return None;
                }
            }
            if !text.is_empty() && matches!(row(line, consumed + line_start as u64, text), Record::Decline) {
                return None;
            }
            if at < whole {
                line += 1;
            }
            line_start = at + 1;
        }
        consumed += whole as u64;
        buf.copy_within(whole..filled, 0);
        filled -= whole;
    }
    Some(line - first_line)
}

/// The cells of a record's `text`: the bytes between its commas (untrimmed).
pub(crate) fn split(text: &[u8]) -> Vec<&[u8]> {
    text.split(|&b| b == b',').collect()
}

/// The value of the decimal digits that start `text` (at most `max` of
/// them, `max` ≤ 19 so that the value fits) and their count.
#[inline]
fn leading_digits(text: &[u8], max: usize) -> (u64, usize) {
    let mut v = 0u64;
    let mut len = 0;
    for &b in text.iter().take(max) {
        let d = b.wrapping_sub(b'0');
        if d > 9 {
            break;
        }
        v = v * 10 + u64::from(d);
        len += 1;
    }
    (v, len)
}

/// The cells of a record read in place, left to right, each parsed as it is
/// reached: no pass to find the commas first. A cell is taken only when it
/// is exactly what [`crate::parse`]'s rules would make of it without
/// trimming (a number straight up to the next comma or the line's end);
/// anything else (white space, a sign or text after a number, a non-finite
/// value, a missing cell) gives `None`, and the caller reads the record
/// again by [`split`] and the rules themselves, which decide.
pub(crate) struct Cells<'a> {
    /// The text from the next cell on; `None` once the last cell is read.
    rest: Option<&'a [u8]>,
}

impl<'a> Cells<'a> {
    /// The cells of `text`, a record's line without its end.
    pub(crate) fn new(text: &'a [u8]) -> Self {
        Cells { rest: Some(text) }
    }

    /// Moves past a cell of `len` bytes at the start of `rest`: `false` when
    /// neither a comma nor the line's end follows it.
    #[inline]
    fn past(&mut self, rest: &'a [u8], len: usize) -> bool {
        match rest.get(len) {
            None => {
                self.rest = None;
                true
            }
            Some(b',') => {
                self.rest = Some(&rest[len + 1..]);
                true
            }
            Some(_) => false,
        }
    }

    /// The next cell's bytes, whatever they are.
    #[inline]
    pub(crate) fn text(&mut self) -> Option<&'a [u8]> {
        let rest = self.rest?;
        let len = memchr::memchr(b',', rest).unwrap_or(rest.len());
        self.past(rest, len);
        Some(&rest[..len])
    }

    /// The next cell as [`crate::parse::cell_f64`] reads it (`Some(None)`: empty).
    #[inline]
    pub(crate) fn number(&mut self) -> Option<Option<f64>> {
        let rest = self.rest?;
        // A whole number of up to 15 digits (C/N0 and elevation as many
        // receivers log them) is below 2⁵³, so exact as an f64: the value
        // the float parser would give, read without it.
        let (v, len) = leading_digits(rest, 15);
        if len > 0 && matches!(rest.get(len), None | Some(b',')) {
            self.past(rest, len);
            return Some(Some(v as f64));
        }
        self.fraction()
    }

    /// [`Cells::number`] for a cell seldom written as a whole number (a
    /// phase): straight to the float parser, which reads a whole number as
    /// the same value, without first trying it as one.
    #[inline]
    pub(crate) fn fraction(&mut self) -> Option<Option<f64>> {
        let rest = self.rest?;
        if matches!(rest.first(), None | Some(b',')) {
            self.past(rest, 0);
            return Some(None);
        }
        // fast-float2's full parse is this partial one with every byte used:
        // the same number, read without first finding where the cell ends.
        let (v, len) = fast_float2::parse_partial::<f64, _>(rest).ok()?;
        (v.is_finite() && self.past(rest, len)).then_some(Some(v))
    }

    /// The next cell as [`crate::parse::cell_u32`] reads it, when it is one to
    /// nine decimal digits.
    #[inline]
    pub(crate) fn integer(&mut self) -> Option<u32> {
        let rest = self.rest?;
        let (v, len) = leading_digits(rest, 10);
        if len == 0 || len > 9 {
            return None;
        }
        self.past(rest, len).then_some(v as u32)
    }

    /// Moves past the next cell when it is exactly `text` (followed by a
    /// comma or the line's end): the common case of a cell that repeats
    /// the previous row's, recognized without searching for its end.
    #[inline]
    pub(crate) fn skip_if(&mut self, text: &[u8]) -> bool {
        match self.rest {
            Some(rest) if rest.starts_with(text) => self.past(rest, text.len()),
            _ => false,
        }
    }

    /// Whether every cell has been read.
    pub(crate) fn finished(&self) -> bool {
        self.rest.is_none()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Records as (line, fields).
    type Records = Vec<(u64, Vec<Vec<u8>>)>;

    /// Every record from the fast path and the line ends read, or `None` where it declines.
    fn plain(text: &[u8], block: usize) -> Option<(Records, u64)> {
        // A reader that hands out `block` bytes at a time, to cross block ends anywhere.
        struct Trickle<'a>(&'a [u8], usize);
        impl Read for Trickle<'_> {
            fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
                let n = self.0.len().min(self.1).min(buf.len());
                buf[..n].copy_from_slice(&self.0[..n]);
                self.0 = &self.0[n..];
                Ok(n)
            }
        }
        let mut out = Vec::new();
        let newlines = for_each_plain_line(Trickle(text, block), 1, |line, _, text| {
            out.push((line, split(text).iter().map(|c| c.to_vec()).collect()));
            Record::Next
        })?;
        Some((out, newlines))
    }

    /// The `csv` crate's records of the same text (lines counted from the
    /// bytes, as the readers' `csv` path counts them).
    fn csv_records(text: &[u8]) -> Records {
        let mut rdr = csv::ReaderBuilder::new().has_headers(false).flexible(true).from_reader(text);
        let mut rec = csv::ByteRecord::new();
        let mut out = Vec::new();
        while rdr.read_byte_record(&mut rec).unwrap() {
            let start = rec.position().unwrap().byte() as usize;
            let blank_after = text[start..].iter().take_while(|&&b| b == b'\n' || b == b'\r').count();
            let s = start + blank_after;
            let line = text[..s].iter().filter(|&&b| b == b'\n').count() as u64 + 1;
            out.push((line, rec.iter().map(<[u8]>::to_vec).collect()));
        }
        out
    }

    /// On quote-free text with `\n` or `\r\n` line ends, blank lines, empty
    /// cells, rows of any length and a last line without its end, the fast
    /// path gives `csv`'s records on the same lines, whatever the blocks.
    #[test]
    fn records_are_csvs_records() {
        let texts: [&[u8]; 8] = [
            b"a,b,c\n1,2,3\n4,5,6\n",
            b"a,b,c\n1,2,3\n4,5,6",
            b"a,b\r\n1,2\r\n\r\n3,4\r\n",
            b"\n\na,b\n\n\n1,,2\n,\n",
            b"x\n",
            b"",
            b"1,2\n3\n4,5,6,7\n \n",
            b"t_s,channel\n0.025,1\n\n0.05,1\r\n0.075,1",
        ];
        for text in texts {
            for block in [1, 2, 3, 7, 64, 1 << 20] {
                let (records, newlines) = plain(text, block).expect("quote-free text");
                assert_eq!(records, csv_records(text), "{:?} in blocks of {block}", String::from_utf8_lossy(text));
                assert_eq!(newlines, text.iter().filter(|&&b| b == b'\n').count() as u64);
            }
        }
        // A line longer than the buffer.
        let long = format!("{}\n1,2\n", "x,".repeat(BLOCK_BYTES));
        let (records, _) = plain(long.as_bytes(), 1 << 20).unwrap();
        assert_eq!(records, csv_records(long.as_bytes()));
    }

    /// A quote or a lone carriage return is left to `csv`.
    #[test]
    fn declines_quotes_and_lone_carriage_returns() {
        for text in [&b"a,b\n\"1\",2\n"[..], b"a,b\r1,2\n", b"a,b\n1,2\r\r\n", b"a\n1\n\""] {
            assert!(plain(text, 1 << 20).is_none(), "{:?}", String::from_utf8_lossy(text));
        }
    }

    /// Wherever [`Cells`] takes a cell it reads what [`split`] and the
    /// number rules read (the rules decide the rest); it takes every plainly
    /// written number; it counts the cells.
    #[test]
    fn cells_read_what_the_rules_read() {
        use crate::parse::{cell_f64, cell_u32};
        let plain_numbers = [
            "0",
            "12",
            "007",
            "123456789",
            "999999999999999",
            "9007199254740993",
            "1234567890123456789012",
            "0.042199930681108805",
            "-3.5e-7",
            "1.",
            ".5",
            "-.5e3",
            "9.80665",
            "1e-400",
            "",
        ];
        let others = [
            "1234567890",
            "4294967296",
            "+5",
            " 1",
            "1 ",
            " ",
            "1e",
            "1e+",
            "1e400",
            "inf",
            "NaN",
            "-infinity",
            "0x10",
            "1,5",
            "1.2.3",
            "abc",
            "1_0",
            "\u{663}",
            "1e5x",
        ];
        let all: Vec<&str> = plain_numbers.iter().chain(&others).copied().collect();
        for a in &all {
            for b in &all {
                let text = format!("{a},{b}");
                let cut = split(text.as_bytes());
                let plain = plain_numbers.contains(a) && plain_numbers.contains(b);
                let mut c = Cells::new(text.as_bytes());
                match c.number().zip(c.number()).filter(|_| c.finished()) {
                    Some((x, y)) => assert_eq!((Ok(x), Ok(y)), (cell_f64(cut[0]), cell_f64(cut[1])), "{text:?}"),
                    None => assert!(!plain, "{text:?} not taken"),
                }
                let (mut c, mut f) = (Cells::new(text.as_bytes()), Cells::new(text.as_bytes()));
                let by_number = c.number().zip(c.number()).filter(|_| c.finished());
                let by_fraction = f.fraction().zip(f.fraction()).filter(|_| f.finished());
                assert_eq!(by_fraction, by_number, "{text:?}");
                let digits = |v: &str| (1..=9).contains(&v.len()) && v.bytes().all(|b| b.is_ascii_digit());
                let mut c = Cells::new(text.as_bytes());
                match c.integer().zip(c.integer()).filter(|_| c.finished()) {
                    Some((x, y)) => assert_eq!((Ok(x), Ok(y)), (cell_u32(cut[0]), cell_u32(cut[1])), "{text:?}"),
                    None => assert!(!(digits(a) && digits(b)), "{text:?} not taken"),
                }
                let mut c = Cells::new(text.as_bytes());
                let two = [c.text(), c.text()];
                assert_eq!(two, [Some(cut[0]), Some(cut[1])], "{text:?}");
                assert_eq!(c.finished(), cut.len() == 2, "{text:?}");
                assert_eq!(c.text(), cut.get(2).copied(), "{text:?}");
            }
        }
        // A last cell left empty by a trailing comma is a cell; a missing one is not.
        let mut c = Cells::new(b"1,");
        assert_eq!((c.number(), c.number(), c.finished()), (Some(Some(1.0)), Some(None), true));
        let mut c = Cells::new(b"1");
        assert_eq!((c.number(), c.number()), (Some(Some(1.0)), None));
    }
}
