//! `vibration.csv`: a random-vibration environment as an acceleration PSD per
//! axis at breakpoints, the way vibration specifications are tabulated.
//!
//! Header `f_hz,psd_x,psd_y,psd_z` (any order, other columns ignored): the
//! frequency \[Hz\], strictly increasing and positive, and the one-sided PSD
//! of the specific force along each IMU axis \[(m/s²)²/Hz\], ≥ 0 (a
//! specification in g²/Hz times 9.80665² = 96.17). Between breakpoints the
//! spectrum is log-log interpolated (straight lines in dB per octave).

use std::io::Read;
use std::path::Path;

use crate::error::FormatError;
use crate::parse::{CsvSource, path_name};

/// The columns of `vibration.csv`.
pub const VIBRATION_COLUMNS: [&str; 4] = ["f_hz", "psd_x", "psd_y", "psd_z"];

/// Reads a `vibration.csv` stream: (f \[Hz\], PSD per axis \[(m/s²)²/Hz\]) per breakpoint.
pub fn read_vibration_psd<R: Read>(input: R, source_name: &str) -> Result<Vec<(f64, [f64; 3])>, FormatError> {
    let (mut src, cols) = CsvSource::open(input, source_name, &VIBRATION_COLUMNS)?;
    let mut out: Vec<(f64, [f64; 3])> = Vec::new();
    while src.next_record()? {
        src.check_field_count()?;
        let f = src.f64_at(cols[0])?;
        let bad = |src: &CsvSource<R>, k: usize, value: f64, expected: &'static str| FormatError::OutOfRange {
            file: src.file.clone(),
            line: src.line(),
            column: src.column(cols[k]),
            value,
            expected,
        };
        if f <= 0.0 {
            return Err(bad(&src, 0, f, "a frequency > 0 Hz"));
        }
        if out.last().is_some_and(|p| f <= p.0) {
            return Err(bad(&src, 0, f, "a frequency above the previous row's (breakpoints in increasing order)"));
        }
        let mut psd = [0.0; 3];
        for i in 0..3 {
            psd[i] = src.f64_at(cols[1 + i])?;
            if psd[i] < 0.0 {
                return Err(bad(&src, 1 + i, psd[i], "a PSD ≥ 0 (m/s²)²/Hz"));
            }
        }
        out.push((f, psd));
    }
    if out.len() < 2 {
        return Err(FormatError::NoData { file: src.file });
    }
    Ok(out)
}

/// Opens and reads a `vibration.csv` file; errors name the file by its path.
pub fn read_vibration_psd_file(path: impl AsRef<Path>) -> Result<Vec<(f64, [f64; 3])>, FormatError> {
    let path = path.as_ref();
    let name = path_name(path);
    let file = std::fs::File::open(path).map_err(|e| FormatError::io(&name, e))?;
    read_vibration_psd(file, &name)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_breakpoints_and_names_the_bad_cell() {
        let ok = read_vibration_psd("f_hz,psd_x,psd_y,psd_z\n10,0.1,0.2,0.3\n100,0.1,0,0.3\n".as_bytes(), "v.csv");
        assert_eq!(ok.unwrap(), vec![(10.0, [0.1, 0.2, 0.3]), (100.0, [0.1, 0.0, 0.3])]);
        let e = read_vibration_psd("f_hz,psd_x,psd_y,psd_z\n10,0.1,0.2,0.3\n5,0.1,0,0.3\n".as_bytes(), "v.csv");
        let text = e.unwrap_err().to_string();
        assert!(text.contains("v.csv: line 3") && text.contains("increasing"), "{text}");
        let e = read_vibration_psd("f_hz,psd_x,psd_y,psd_z\n10,0.1,-0.2,0.3\n20,1,1,1\n".as_bytes(), "v.csv");
        let text = e.unwrap_err().to_string();
        assert!(text.contains("line 2") && text.contains("psd_y"), "{text}");
        assert!(read_vibration_psd("f_hz,psd_x,psd_y,psd_z\n10,0.1,0.2,0.3\n".as_bytes(), "v.csv").is_err());
    }
}
