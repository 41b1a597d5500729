//! Reader of `imu.csv`: one row per IMU sample, header `t_s,fx_mps2,fy_mps2,fz_mps2`.
//!
//! The columns may come in any order and extra columns are ignored, but the four
//! must all be present. Time stamps must be strictly increasing; every value
//! must be a finite number.

use std::io::Read;
use std::path::Path;

use crate::error::FormatError;
use crate::parse::{CsvSource, path_name};

/// The columns of `imu.csv`, in the order the writer emits them.
pub const IMU_COLUMNS: [&str; 4] = ["t_s", "fx_mps2", "fy_mps2", "fz_mps2"];

/// An IMU log: specific force samples in the IMU body frame.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ImuSeries {
    /// Sample time stamps \[s\], strictly increasing (IMU clock: see `imu_time_offset_s`
    /// in `gsens_session::prepare_session`).
    pub t_s: Vec<f64>,
    /// Specific force `[fx, fy, fz]` [m/s²] at each time stamp, IMU body frame
    /// (at rest, level, z up: ≈ `[0, 0, +9.81]`).
    pub accel_mps2: Vec<[f64; 3]>,
}

impl ImuSeries {
    /// The specific force at stamp `tau_s`, interpolated between the samples
    /// around it by a cubic Hermite polynomial with Catmull–Rom slopes: on
    /// `[t_j, t_j+1]` with `s = (τ − t_j)/h`, `h = t_j+1 − t_j`,
    /// `a(τ) = h00(s)·a_j + h10(s)·h·m_j + h01(s)·a_j+1 + h11(s)·h·m_j+1`, the
    /// slopes m those of [`ImuSeries::hermite_slope`] (exact for a quadratic).
    /// It reads the two samples on either side. Why not linear: a linear
    /// interpolant of a sinusoid of angular frequency ω sampled every h is
    /// low by `(ωh)²·s(1 − s)/2` of its amplitude, `(ωh)²/12` on average over
    /// the interval (0.4 % for 2 Hz shaking read by a 40 Hz IMU), which would
    /// bias Γ̂ by as much whenever epochs fall between the IMU's samples; the
    /// cubic's error is of fourth order in ωh. The sample itself at its own
    /// stamp; the last sample past the end. `tau_s` must lie within the
    /// series' span (no extrapolation is meant); `cursor` keeps the search's
    /// place, so calls with non-decreasing `tau_s` cost O(1) each.
    pub fn interpolate_at(&self, tau_s: f64, cursor: &mut usize) -> [f64; 3] {
        self.cubic_at(tau_s, cursor, |j| self.hermite_slope(j))
    }

    /// [`ImuSeries::interpolate_at`] with the slope at sample j from `slope(j)`.
    fn cubic_at(&self, tau_s: f64, cursor: &mut usize, slope: impl Fn(usize) -> [f64; 3]) -> [f64; 3] {
        let t = &self.t_s;
        let mut j = (*cursor).min(t.len().saturating_sub(1));
        while j + 1 < t.len() && t[j + 1] <= tau_s {
            j += 1;
        }
        *cursor = j;
        if t[j] == tau_s || j + 1 == t.len() {
            return self.accel_mps2[j];
        }
        let h = t[j + 1] - t[j];
        let s = (tau_s - t[j]) / h;
        let a = &self.accel_mps2;
        let (m0, m1) = (slope(j), slope(j + 1));
        let (s2, s3) = (s * s, s * s * s);
        let (h00, h10, h01, h11) = (2.0 * s3 - 3.0 * s2 + 1.0, s3 - 2.0 * s2 + s, -2.0 * s3 + 3.0 * s2, s3 - s2);
        core::array::from_fn(|i| h00 * a[j][i] + h10 * h * m0[i] + h01 * a[j + 1][i] + h11 * h * m1[i])
    }

    /// The slope of the specific force at sample `j` the cubic interpolant
    /// takes \[m/s³\]: the secants s over the intervals on either side
    /// (lengths h₋ and h₊) weighted `m = (h₋·s₊ + h₊·s₋)/(h₋ + h₊)`, the
    /// central difference on even spacing and exact for a quadratic on any;
    /// the one secant at the ends, 0 for a single sample.
    pub fn hermite_slope(&self, j: usize) -> [f64; 3] {
        let (t, a) = (&self.t_s, &self.accel_mps2);
        let secant = |k: usize| -> [f64; 3] { core::array::from_fn(|i| (a[k + 1][i] - a[k][i]) / (t[k + 1] - t[k])) };
        match (j.checked_sub(1), j + 1 < t.len()) {
            (Some(p), true) => {
                let (h0, h1, s0, s1) = (t[j] - t[p], t[j + 1] - t[j], secant(p), secant(j));
                core::array::from_fn(|i| (h0 * s1[i] + h1 * s0[i]) / (h0 + h1))
            }
            (None, true) => secant(j),
            (Some(p), false) => secant(p),
            (None, false) => [0.0; 3],
        }
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.t_s.len()
    }

    /// `true` when the series holds no sample.
    pub fn is_empty(&self) -> bool {
        self.t_s.is_empty()
    }

    /// Checks the invariants the readers guarantee: equal lengths, at least one
    /// sample, finite values, strictly increasing time stamps. `name` names the
    /// series in the error.
    pub fn validate(&self, name: &str) -> Result<(), FormatError> {
        let fail = |reason: String| Err(FormatError::InvalidImuSeries { file: name.to_owned(), reason });
        if self.t_s.len() != self.accel_mps2.len() {
            return fail(format!("{} time stamps but {} acceleration samples", self.t_s.len(), self.accel_mps2.len()));
        }
        if self.t_s.is_empty() {
            return fail("no samples".to_owned());
        }
        for (i, (t, a)) in self.t_s.iter().zip(&self.accel_mps2).enumerate() {
            if !t.is_finite() || !a.iter().all(|x| x.is_finite()) {
                return fail(format!("sample {i} is not finite (t = {t} s, a = {a:?} m/s²)"));
            }
            if i > 0 && *t <= self.t_s[i - 1] {
                return fail(format!(
                    "time stamps not strictly increasing at sample {i} ({} s then {t} s)",
                    self.t_s[i - 1]
                ));
            }
        }
        Ok(())
    }
}

/// [`ImuSeries::interpolate_at`] with every sample's slope
/// ([`ImuSeries::hermite_slope`]) computed once: the same values, bit for
/// bit, at a fraction of the cost where one series is read at many instants
/// (a loop model fed at the IMU's rate for every time offset tried).
#[derive(Debug, Clone)]
pub struct ImuCubic<'a> {
    imu: &'a ImuSeries,
    slopes: Vec<[f64; 3]>,
}

impl<'a> ImuCubic<'a> {
    /// The interpolant of `imu`.
    pub fn new(imu: &'a ImuSeries) -> Self {
        ImuCubic { imu, slopes: (0..imu.len()).map(|j| imu.hermite_slope(j)).collect() }
    }

    /// The series interpolated.
    pub fn series(&self) -> &'a ImuSeries {
        self.imu
    }

    /// Each sample's slope \[m/s³\] ([`ImuSeries::hermite_slope`]).
    pub fn slopes(&self) -> &[[f64; 3]] {
        &self.slopes
    }

    /// The specific force at `tau_s`: [`ImuSeries::interpolate_at`].
    pub fn at(&self, tau_s: f64, cursor: &mut usize) -> [f64; 3] {
        self.imu.cubic_at(tau_s, cursor, |j| self.slopes[j])
    }
}

/// Reads an `imu.csv` stream. `source_name` names the source in error messages
/// (typically the file name).
pub fn read_imu<R: Read>(input: R, source_name: &str) -> Result<ImuSeries, FormatError> {
    let (mut src, cols) = CsvSource::open(input, source_name, &IMU_COLUMNS)?;
    let (ct, cx, cy, cz) = (cols[0], cols[1], cols[2], cols[3]);
    let mut out = ImuSeries::default();
    let mut prev: Option<(f64, u64)> = None;
    while src.next_record()? {
        src.check_field_count()?;
        let t = src.f64_at(ct)?;
        let a = [src.f64_at(cx)?, src.f64_at(cy)?, src.f64_at(cz)?];
        let line = src.line();
        if let Some((prev_t, prev_line)) = prev {
            if t < prev_t {
                return Err(FormatError::TimeBackwards {
                    file: src.file.clone(),
                    line,
                    column: src.column(ct),
                    t_s: t,
                    previous_t_s: prev_t,
                    previous_line: prev_line,
                });
            }
            if t == prev_t {
                return Err(FormatError::RepeatedTime {
                    file: src.file.clone(),
                    line,
                    column: src.column(ct),
                    t_s: t,
                    previous_line: prev_line,
                });
            }
        }
        prev = Some((t, line));
        out.t_s.push(t);
        out.accel_mps2.push(a);
    }
    if out.t_s.is_empty() {
        return Err(FormatError::NoData { file: src.file });
    }
    Ok(out)
}

/// Opens and reads an `imu.csv` file; errors name the file by its path.
pub fn read_imu_file(path: impl AsRef<Path>) -> Result<ImuSeries, FormatError> {
    let path = path.as_ref();
    let name = path_name(path);
    let file = std::fs::File::open(path).map_err(|e| FormatError::io(&name, e))?;
    if let Some(imu) = file.metadata().ok().and_then(|m| read_plain(path, &name, m.len(), CHUNK_BYTES)) {
        return Ok(imu);
    }
    read_imu(file, &name)
}

/// Rows read before the columns are reserved for the rest of the file.
const ROWS_BEFORE_RESERVE: usize = 1024;

/// The bytes of rows in one chunk of a file read on the fast path: the
/// chunks are parsed at once and joined in file order (see
/// [`crate::read_tracking_file`]).
const CHUNK_BYTES: u64 = 8 << 20;

/// The file read on the quote-free fast path ([`crate::plain`]), in chunks
/// of about `chunk_bytes` split at line ends and parsed at once; `None`
/// where [`read_imu_file`] reads it with `csv` (which then reports the first
/// error in the file).
fn read_plain(path: &Path, name: &str, total: u64, chunk_bytes: u64) -> Option<ImuSeries> {
    use crate::parse::cell_f64;
    use crate::plain::{Cells, PlainFile, Record, for_each_plain_line, open_plain, split};
    use rayon::prelude::*;
    let PlainFile { mut file, header, cols, data_start } = open_plain(path, name, &IMU_COLUMNS, total)?;
    let (fields, ct, cx, cy, cz) = (header.header.len(), cols[0], cols[1], cols[2], cols[3]);
    // Which value each cell is (0: time, 1–3: the axes), for the reading in place.
    let mut layout = vec![None; fields];
    for (slot, at) in [ct, cx, cy, cz].into_iter().enumerate() {
        layout[at] = Some(slot);
    }
    let number = |cell: &[u8]| cell_f64(cell).ok().flatten();
    let row = |text: &[u8]| -> Option<(f64, [f64; 3])> {
        // In place first; a row it does not take is split and read by the rules.
        let mut cells = Cells::new(text);
        let mut v = [0.0; 4];
        let in_place = layout.iter().all(|slot| match slot {
            Some(i) => cells.number().flatten().map(|x| v[*i] = x).is_some(),
            None => cells.text().is_some(),
        });
        if in_place && cells.finished() {
            return Some((v[0], [v[1], v[2], v[3]]));
        }
        let f = split(text);
        if f.len() != fields {
            return None;
        }
        Some((number(f[ct])?, [number(f[cx])?, number(f[cy])?, number(f[cz])?]))
    };
    let read_chunk = |from: u64, to: u64| -> Option<ImuSeries> {
        let mut out = ImuSeries::default();
        for_each_plain_line(crate::plain::byte_range(path, from, to)?, 1, |_, bytes_before, text| {
            let Some((t, a)) = row(text) else { return Record::Decline };
            if out.t_s.last().is_some_and(|&prev| t <= prev) {
                return Record::Decline;
            }
            out.t_s.push(t);
            out.accel_mps2.push(a);
            if out.t_s.len() == ROWS_BEFORE_RESERVE && bytes_before > 0 {
                // The rows of the whole chunk (2 % spare).
                let rows = (1.02 * crate::plain::rows_in(to - from, ROWS_BEFORE_RESERVE, bytes_before)) as usize;
                out.t_s.reserve_exact(rows.saturating_sub(out.t_s.len()));
                out.accel_mps2.reserve_exact(rows.saturating_sub(out.accel_mps2.len()));
            }
            Record::Next
        })?;
        Some(out)
    };
    let bounds = crate::plain::chunk_bounds(&mut file, data_start, total, chunk_bytes)?;
    let chunks: Vec<Option<ImuSeries>> = bounds.par_windows(2).map(|w| read_chunk(w[0], w[1])).collect();
    let rows: usize = chunks.iter().map(|c| c.as_ref().map_or(0, |c| c.t_s.len())).sum();
    // The first chunk's columns become the series' (a file of one chunk, as
    // most IMU logs are, is not copied at all), grown once for the others.
    let mut chunks = chunks.into_iter();
    let mut out = chunks.next()??;
    let more = rows - out.t_s.len();
    out.t_s.reserve_exact(more);
    out.accel_mps2.reserve_exact(more);
    for chunk in chunks {
        let chunk = chunk?;
        // Time stamps strictly increasing across the chunks too.
        if let (Some(&last), Some(&first)) = (out.t_s.last(), chunk.t_s.first())
            && first <= last
        {
            return None;
        }
        out.t_s.extend_from_slice(&chunk.t_s);
        out.accel_mps2.extend_from_slice(&chunk.accel_mps2);
    }
    (!out.t_s.is_empty()).then_some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(text: &str) -> Result<ImuSeries, FormatError> {
        read_imu(text.as_bytes(), "imu.csv")
    }

    fn err(text: &str) -> String {
        let e = read(text).expect_err("expected an error");
        let msg = e.to_string();
        assert!(msg.starts_with("imu.csv"), "message does not name the source: {msg}");
        msg
    }

    /// The interpolant reproduces a quadratic on unevenly spaced samples
    /// (away from the ends' one-sided slopes).
    #[test]
    fn interpolation_is_exact_for_a_quadratic() {
        let t_s: Vec<f64> = (0..40).map(|k| 0.1 * k as f64 + 0.01 * ((k * 7) % 5) as f64).collect();
        let f = |t: f64| [1.0 + 2.0 * t - 0.5 * t * t, 9.81, -t * t];
        let imu = ImuSeries { t_s: t_s.clone(), accel_mps2: t_s.iter().map(|&t| f(t)).collect() };
        let mut cursor = 0;
        for k in 0..500 {
            let tau_s = t_s[1] + k as f64 * (t_s[38] - t_s[1]) / 500.0;
            let (got, want) = (imu.interpolate_at(tau_s, &mut cursor), f(tau_s));
            for i in 0..3 {
                assert!((got[i] - want[i]).abs() < 1e-12, "t {tau_s}, axis {i}: {} vs {}", got[i], want[i]);
            }
        }
    }

    /// Read between its samples, a sampled sinusoid keeps its amplitude to
    /// fourth order: over uniformly spread reading instants the in-phase gain
    /// of the cubic is `1 − θ⁴/80` with `θ = ωh` (the integral over s of its
    /// transfer `H(s)·e^(−iθs)`; a linear interpolant's is `1 − θ²/12`), and
    /// it reads the samples themselves exactly.
    #[test]
    fn interpolation_between_samples_keeps_a_sinusoids_amplitude() {
        let (f_hz, h_s) = (2.0, 0.025);
        let w = std::f64::consts::TAU * f_hz;
        let n = 4001;
        let t_s: Vec<f64> = (0..n).map(|k| k as f64 * h_s).collect();
        let accel_mps2 = t_s.iter().map(|t| [(w * t).sin(), (w * t).cos(), 9.81]).collect();
        let imu = ImuSeries { t_s, accel_mps2 };
        let mut cursor = 0;
        for k in (0..n).step_by(97) {
            assert_eq!(imu.interpolate_at(imu.t_s[k], &mut cursor), imu.accel_mps2[k]);
        }
        // Reading instants at an irrational fraction of the interval apart
        // cover every phase of the sinusoid and every place between samples.
        let (mut cursor, mut sin_dot, mut cos_dot, mut sin_norm, mut cos_norm) = (0, 0.0, 0.0, 0.0, 0.0);
        let step_s = h_s * (2f64.sqrt() - 1.0);
        let mut tau_s = 2.0 * h_s;
        while tau_s < (n - 3) as f64 * h_s {
            let a = imu.interpolate_at(tau_s, &mut cursor);
            let (s, c) = (w * tau_s).sin_cos();
            (sin_dot, sin_norm) = (sin_dot + a[0] * s, sin_norm + s * s);
            (cos_dot, cos_norm) = (cos_dot + a[1] * c, cos_norm + c * c);
            assert!((a[2] - 9.81).abs() < 1e-12);
            tau_s += step_s;
        }
        let theta = w * h_s;
        let (expected, linear) = (1.0 - theta.powi(4) / 80.0, 1.0 - theta * theta / 12.0);
        for gain in [sin_dot / sin_norm, cos_dot / cos_norm] {
            assert!(
                (gain - expected).abs() < 0.05 * (1.0 - expected),
                "gain {gain}, expected {expected}, linear {linear}"
            );
        }
    }

    /// [`read_imu_file`]'s quote-free fast path gives the series the `csv`
    /// reader gives on the same bytes, and leaves to it whatever it does not
    /// take (the result, error message included, is then the `csv` reader's).
    #[test]
    fn fast_path_gives_the_csv_readers_series() {
        use crate::test_files::TempFile;
        let h = "t_s,fx_mps2,fy_mps2,fz_mps2\n";
        let rows: String = (0..3000).map(|k| format!("{},{},-1,9.81\n", k as f64 * 0.01, (k as f64).sin())).collect();
        let body = format!("{h}{rows}");
        let clean = [
            body.clone(),
            body.replace('\n', "\r\n"),
            format!("\u{feff}{body}"),
            body.trim_end().to_string(),
            body.replace(",-1,", ", -1 ,"),
            "fz_mps2,extra,t_s,fy_mps2,fx_mps2\n3,x,1.5,2,1\n\n6,y,2.5,5,4\n".to_string(),
        ];
        for (i, text) in clean.iter().enumerate() {
            let f = TempFile::new(&format!("imu-plain-{i}.csv"), text);
            // In one chunk and in many (of any size: the bounds fall at line ends).
            for chunk in [CHUNK_BYTES, 1000, 37, 1] {
                let plain = read_plain(&f.0, &path_name(&f.0), text.len() as u64, chunk);
                let plain = plain.unwrap_or_else(|| panic!("case {i}: a clean file takes the fast path"));
                assert_eq!(plain, read_imu(text.as_bytes(), "x").unwrap(), "case {i}, chunks of {chunk} bytes");
            }
        }
        for bad in [
            "0.04,1,2,3",
            "0.05,1,2",
            "0.05,1,2,3,4",
            "0.03,1,2,3",
            "0.04,1,x,3",
            "0.05,1,,3",
            "0.05,inf,2,3",
            "\"0.05\",1,2,3",
            "0.05,1,2,3\r0.06,1,2,3",
        ] {
            let text = format!("{h}0,1,2,3\n0.01,1,2,3\n0.02,1,2,3\n0.03,1,2,3\n0.04,1,2,3\n{bad}\n0.07,1,2,3\n");
            let f = TempFile::new("imu-plain-left.csv", &text);
            for chunk in [CHUNK_BYTES, 20, 1] {
                assert!(read_plain(&f.0, &path_name(&f.0), text.len() as u64, chunk).is_none(), "{bad:?}");
            }
            match (read_imu_file(&f.0), read_imu(text.as_bytes(), &path_name(&f.0))) {
                (Err(a), Err(b)) => assert_eq!(a.to_string(), b.to_string()),
                (Ok(a), Ok(b)) => assert_eq!(a, b),
                (a, b) => panic!("{bad:?}: {a:?} vs {b:?}"),
            }
        }
    }

    #[test]
    fn reads_plain_file() {
        let s = read("t_s,fx_mps2,fy_mps2,fz_mps2\n0,0.5,-1,9.81\n0.025,1e-3,2,3\n").unwrap();
        assert_eq!(s.t_s, vec![0.0, 0.025]);
        assert_eq!(s.accel_mps2, vec![[0.5, -1.0, 9.81], [1e-3, 2.0, 3.0]]);
        s.validate("imu.csv").unwrap();
    }

    #[test]
    fn columns_in_any_order_extra_ignored_crlf_bom_spaces() {
        let s = read("\u{feff}fz_mps2, extra ,t_s,fy_mps2,fx_mps2\r\n3,x,1.5, 2 ,1\r\n\r\n6,y,2.5,5,4\r\n").unwrap();
        assert_eq!(s.t_s, vec![1.5, 2.5]);
        assert_eq!(s.accel_mps2, vec![[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]);
    }

    #[test]
    fn missing_column() {
        let m = err("t_s,fx_mps2,fz_mps2\n0,1,2\n");
        assert!(m.contains("line 1") && m.contains("missing column `fy_mps2`"), "{m}");
    }

    #[test]
    fn duplicate_column() {
        let m = err("t_s,fx_mps2,fy_mps2,fz_mps2,fx_mps2\n0,1,2,3,4\n");
        assert!(m.contains("`fx_mps2` appears twice") && m.contains("columns 2 and 5"), "{m}");
    }

    #[test]
    fn non_numeric_cell() {
        let m = err("t_s,fx_mps2,fy_mps2,fz_mps2\n0,1,2,3\n0.1,1,abc,3\n");
        assert!(m.contains("line 3, column 3 (`fy_mps2`)") && m.contains("`abc` is not a number"), "{m}");
    }

    #[test]
    fn empty_cell() {
        let m = err("t_s,fx_mps2,fy_mps2,fz_mps2\n0,1,,3\n");
        assert!(m.contains("line 2, column 3 (`fy_mps2`)") && m.contains("empty cell"), "{m}");
    }

    #[test]
    fn nan_and_inf() {
        let m = err("t_s,fx_mps2,fy_mps2,fz_mps2\n0,NaN,2,3\n");
        assert!(m.contains("line 2, column 2 (`fx_mps2`)") && m.contains("`NaN` is not a finite number"), "{m}");
        let m = err("t_s,fx_mps2,fy_mps2,fz_mps2\n0,1,2,3\n1,1,2,-inf\n");
        assert!(m.contains("line 3, column 4 (`fz_mps2`)") && m.contains("`-inf` is not a finite number"), "{m}");
        let m = err("t_s,fx_mps2,fy_mps2,fz_mps2\ninfinity,1,2,3\n");
        assert!(m.contains("line 2, column 1 (`t_s`)") && m.contains("not a finite number"), "{m}");
    }

    #[test]
    fn time_backwards() {
        let m = err("t_s,fx_mps2,fy_mps2,fz_mps2\n0,1,2,3\n0.2,1,2,3\n0.1,1,2,3\n");
        assert!(m.contains("line 4, column 1 (`t_s`)") && m.contains("goes backwards") && m.contains("line 3"), "{m}");
    }

    #[test]
    fn repeated_time() {
        let m = err("t_s,fx_mps2,fy_mps2,fz_mps2\n0,1,2,3\n0.1,1,2,3\n0.1,1,2,3\n");
        assert!(m.contains("line 4, column 1 (`t_s`)") && m.contains("repeated time stamp 0.1 s"), "{m}");
        assert!(m.contains("already on line 3"), "{m}");
    }

    #[test]
    fn empty_file() {
        let m = err("");
        assert!(m.contains("empty file"), "{m}");
        let m = err("\n\n");
        assert!(m.contains("empty file"), "{m}");
    }

    #[test]
    fn header_only() {
        let m = err("t_s,fx_mps2,fy_mps2,fz_mps2\n");
        assert!(m.contains("header only, no data rows"), "{m}");
    }

    #[test]
    fn wrong_field_count() {
        let m = err("t_s,fx_mps2,fy_mps2,fz_mps2\n0,1,2,3\n0.1,1,2\n");
        assert!(m.contains("line 3") && m.contains("expected 4 fields") && m.contains("found 3"), "{m}");
        let m = err("t_s,fx_mps2,fy_mps2,fz_mps2\n0,1,2,3,4\n");
        assert!(m.contains("line 2") && m.contains("found 5"), "{m}");
    }

    #[test]
    fn missing_file() {
        let e = read_imu_file("/nonexistent/dir/imu.csv").unwrap_err();
        let m = e.to_string();
        assert!(m.starts_with("/nonexistent/dir/imu.csv: cannot read"), "{m}");
    }

    #[test]
    fn validate_in_memory_series() {
        let bad = ImuSeries { t_s: vec![0.0, 0.0], accel_mps2: vec![[0.0; 3]; 2] };
        let m = bad.validate("sim").unwrap_err().to_string();
        assert!(m.starts_with("sim: invalid IMU series") && m.contains("not strictly increasing"), "{m}");
        let bad = ImuSeries { t_s: vec![0.0], accel_mps2: vec![] };
        assert!(bad.validate("sim").is_err());
        assert!(ImuSeries::default().validate("sim").is_err());
    }
}
