//! Writers of `imu.csv` and `tracking.csv`.
//!
//! Numbers are written with Rust's `Display` for `f64`: the shortest decimal
//! string that parses back to the same value, so the output is deterministic
//! and a write → read round trip gives the same bits. Non-finite values are
//! refused (the readers would reject them) with an
//! [`std::io::ErrorKind::InvalidInput`] error.

use std::io::{self, BufWriter, Write};
use std::path::Path;

use crate::imu::{IMU_COLUMNS, ImuSeries};
use crate::output::FileError;
use crate::row::TrackingRecord;
use crate::signal::Carrier;
use crate::tracking::{CARRIER_COLUMNS, TRACKING_COLUMNS};

fn non_finite(what: &str, value: f64, row: u64) -> io::Error {
    io::Error::new(io::ErrorKind::InvalidInput, format!("cannot write non-finite {what} = {value} (data row {row})"))
}

fn check(what: &str, value: f64, row: u64) -> io::Result<()> {
    if value.is_finite() { Ok(()) } else { Err(non_finite(what, value, row)) }
}

/// Writes `imu` as `imu.csv` (header `t_s,fx_mps2,fy_mps2,fz_mps2`) to `w`
/// (buffered internally, flushed at the end).
///
/// Errors: I/O errors of `w`; `InvalidInput` when a value is not finite or the
/// two vectors of `imu` differ in length.
pub fn write_imu_csv<W: Write>(w: W, imu: &ImuSeries) -> io::Result<()> {
    if imu.t_s.len() != imu.accel_mps2.len() {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("IMU series has {} time stamps but {} samples", imu.t_s.len(), imu.accel_mps2.len()),
        ));
    }
    let mut out = ImuWriter::new(w)?;
    for (t, a) in imu.t_s.iter().zip(&imu.accel_mps2) {
        out.write_sample(*t, a)?;
    }
    out.finish().map(|_| ())
}

/// Writes `rows` as `tracking.csv` to `w` with [`TrackingWriter`] (every
/// number checked finite); returns `w`.
pub fn write_tracking_csv<W: Write>(w: W, rows: &[TrackingRow]) -> io::Result<W> {
    let mut out = TrackingWriter::new(w)?;
    for row in rows {
        out.write_row(row)?;
    }
    out.finish()
}

/// Writes `rows` and their carriers as `tracking.csv` to `w`: with the carrier
/// columns `signal,carrier_hz` ([`TrackingWriter::with_carriers`]) when some
/// row is not on GPS L1 or names a signal other than L1 C/A
/// ([`Carrier::is_default`]), else exactly as [`write_tracking_csv`]; returns `w`.
pub fn write_tracking_csv_on<W: Write>(w: W, rows: &[(TrackingRow, Carrier)]) -> io::Result<W> {
    let mut out = if rows.iter().all(|(_, c)| c.is_default()) {
        TrackingWriter::new(w)?
    } else {
        TrackingWriter::with_carriers(w, &[])?
    };
    for (row, carrier) in rows {
        out.write_row_on(row, carrier, &[])?;
    }
    out.finish()
}

/// The cells of `row` (the empty cell for an unknown elevation), then
/// `signal,carrier_hz` of `carrier` where given, then `extra`, comma-separated,
/// without a line end: the one way a tracking row is written.
pub(crate) fn write_row_cells(
    out: &mut impl Write,
    row: &TrackingRow,
    carrier: Option<&Carrier>,
    extra: &[f64],
) -> io::Result<()> {
    match row.elev_deg {
        Some(e) => write!(out, "{},{},{},{},{},{}", row.t_s, row.channel, row.prn, row.cn0_dbhz, e, row.phase_err_rad)?,
        None => write!(out, "{},{},{},{},,{}", row.t_s, row.channel, row.prn, row.cn0_dbhz, row.phase_err_rad)?,
    }
    if let Some(carrier) = carrier {
        write!(out, ",{},{}", carrier.signal.map_or("", |s| s.name()), carrier.carrier_hz)?;
    }
    for v in extra {
        write!(out, ",{v}")?;
    }
    Ok(())
}

/// A streaming writer of `imu.csv`, one sample at a time (header written by
/// [`ImuWriter::new`]).
#[derive(Debug)]
pub struct ImuWriter<W: Write> {
    out: BufWriter<W>,
    rows: u64,
}

impl<W: Write> ImuWriter<W> {
    /// Starts an `imu.csv` on `w` (buffered internally) by writing the header.
    pub fn new(w: W) -> io::Result<Self> {
        let mut out = BufWriter::new(w);
        writeln!(out, "{}", IMU_COLUMNS.join(","))?;
        Ok(ImuWriter { out, rows: 0 })
    }

    /// Writes one sample: time stamp \[s\] and specific force \[m/s²\].
    /// Errors: I/O errors; `InvalidInput` for a non-finite value.
    pub fn write_sample(&mut self, t_s: f64, accel_mps2: &[f64; 3]) -> io::Result<()> {
        let row = self.rows + 1;
        check("t_s", t_s, row)?;
        for (name, v) in ["fx_mps2", "fy_mps2", "fz_mps2"].iter().zip(accel_mps2) {
            check(name, *v, row)?;
        }
        writeln!(self.out, "{},{},{},{}", t_s, accel_mps2[0], accel_mps2[1], accel_mps2[2])?;
        self.rows = row;
        Ok(())
    }

    /// Flushes the buffer and returns the underlying writer.
    pub fn finish(self) -> io::Result<W> {
        self.out.into_inner().map_err(|e| e.into_error())
    }
}

/// One row of `tracking.csv`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrackingRow {
    /// Time stamp \[s\].
    pub t_s: f64,
    /// Receiver channel number.
    pub channel: u32,
    /// Satellite PRN.
    pub prn: u32,
    /// Carrier-to-noise density ratio [dB-Hz].
    pub cn0_dbhz: f64,
    /// Satellite elevation \[deg\]; `None` writes an empty cell (unknown).
    pub elev_deg: Option<f64>,
    /// Carrier phase tracking error \[rad\].
    pub phase_err_rad: f64,
}

/// A streaming writer of `tracking.csv`, one row at a time.
///
/// The header `t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad` is written by
/// [`TrackingWriter::new`]. Rows must be written in the order the reader
/// requires (non-decreasing `t_s`, each channel at most once per time stamp);
/// the writer does not check it.
///
/// A log may carry extra numeric columns after the six of the format (the
/// readers ignore them): declare them with
/// [`TrackingWriter::with_extra_columns`] and give their values with
/// [`TrackingWriter::write_row_with`]. They are checked finite like the rest.
///
/// A log whose rows are not all on GPS L1 carries the carrier columns
/// `signal,carrier_hz` after the six ([`TrackingWriter::with_carriers`], rows
/// by [`TrackingWriter::write_row_on`]); without them every row is on L1.
#[derive(Debug)]
pub struct TrackingWriter<W: Write> {
    out: BufWriter<W>,
    rows: u64,
    extra_columns: Vec<String>,
    carriers: bool,
}

impl<W: Write> TrackingWriter<W> {
    /// Starts a `tracking.csv` on `w` (buffered internally) by writing the header.
    pub fn new(w: W) -> io::Result<Self> {
        Self::with_extra_columns(w, &[])
    }

    /// Starts a `tracking.csv` on `w` whose header has the columns `extra` after
    /// the six of the format, e.g. `…,phase_err_rad,carrier_lock_test`.
    /// Errors: I/O errors; `InvalidInput` for a name that is empty, holds a
    /// comma, a quote or a line break, or repeats a column of the header.
    pub fn with_extra_columns(w: W, extra: &[&str]) -> io::Result<Self> {
        Self::start(w, extra, false)
    }

    /// Starts a `tracking.csv` on `w` with the carrier columns: the header is
    /// `…,phase_err_rad,signal,carrier_hz` and then the columns `extra`. Every
    /// row gives its carrier ([`TrackingWriter::write_row_on`]; rows written
    /// without one are on GPS L1). Errors as [`TrackingWriter::with_extra_columns`].
    pub fn with_carriers(w: W, extra: &[&str]) -> io::Result<Self> {
        Self::start(w, extra, true)
    }

    fn start(w: W, extra: &[&str], carriers: bool) -> io::Result<Self> {
        for (i, name) in extra.iter().enumerate() {
            let bad_chars = name.is_empty() || name.contains([',', '"', '\n', '\r']);
            let taken = TRACKING_COLUMNS.contains(name) || CARRIER_COLUMNS.contains(name);
            if bad_chars || taken || extra[..i].contains(name) {
                return Err(io::Error::new(
                    io::ErrorKind::InvalidInput,
                    format!("cannot write an extra tracking.csv column named {name:?}"),
                ));
            }
        }
        let mut out = BufWriter::new(w);
        write!(out, "{}", TRACKING_COLUMNS.join(","))?;
        if carriers {
            write!(out, ",{},{}", CARRIER_COLUMNS[0], CARRIER_COLUMNS[2])?;
        }
        for name in extra {
            write!(out, ",{name}")?;
        }
        writeln!(out)?;
        Ok(TrackingWriter { out, rows: 0, extra_columns: extra.iter().map(|s| (*s).to_owned()).collect(), carriers })
    }

    /// Writes one row (of a writer without extra columns).
    /// Errors: I/O errors; `InvalidInput` for a non-finite value, or when the
    /// writer has extra columns (use [`TrackingWriter::write_row_with`]).
    pub fn write_row(&mut self, row: &TrackingRow) -> io::Result<()> {
        self.write_row_with(row, &[])
    }

    /// Writes one row and the values of the extra columns, in the order they
    /// were declared. Errors: I/O errors; `InvalidInput` for a non-finite
    /// value or when `extra` does not hold one value per extra column.
    pub fn write_row_with(&mut self, row: &TrackingRow, extra: &[f64]) -> io::Result<()> {
        self.write_row_on(row, &Carrier::GPS_L1, extra)
    }

    /// Writes one row on `carrier` and the values of the extra columns. On a
    /// writer without carrier columns the carrier must be GPS L1
    /// ([`Carrier::is_default`]). Errors: I/O errors; `InvalidInput` for a
    /// non-finite value, a carrier the columns cannot hold, or a wrong number
    /// of extra values.
    pub fn write_row_on(&mut self, row: &TrackingRow, carrier: &Carrier, extra: &[f64]) -> io::Result<()> {
        let n = self.rows + 1;
        if !self.carriers && !carrier.is_default() {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!(
                    "data row {n} is on {} but the writer has no carrier columns (start it with with_carriers)",
                    carrier.label()
                ),
            ));
        }
        if self.carriers {
            check("carrier_hz", carrier.carrier_hz, n)?;
        }
        if extra.len() != self.extra_columns.len() {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!(
                    "data row {n}: {} extra value(s) for the {} extra column(s) of the header",
                    extra.len(),
                    self.extra_columns.len()
                ),
            ));
        }
        check("t_s", row.t_s, n)?;
        check("cn0_dbhz", row.cn0_dbhz, n)?;
        check("phase_err_rad", row.phase_err_rad, n)?;
        if let Some(e) = row.elev_deg {
            check("elev_deg", e, n)?;
        }
        for (name, v) in self.extra_columns.iter().zip(extra) {
            check(name, *v, n)?;
        }
        write_row_cells(&mut self.out, row, self.carriers.then_some(carrier), extra)?;
        writeln!(self.out)?;
        self.rows = n;
        Ok(())
    }

    /// Starts a `tracking.csv` on `w` for records like `first`: with the
    /// carrier columns where it has a carrier, and its NCO columns
    /// ([`TrackingRecord::header`]); rows by [`TrackingWriter::write_record`].
    /// Errors: I/O errors.
    pub fn for_record(w: W, first: &TrackingRecord) -> io::Result<Self> {
        let nco: Vec<&str> = first.nco().map(|(name, _)| name).collect();
        Self::start(w, &nco, first.carrier.is_some())
    }

    /// Writes `record` on a writer made by [`TrackingWriter::for_record`]
    /// for records with the same columns. Errors as [`TrackingWriter::write_row_on`].
    pub fn write_record(&mut self, record: &TrackingRecord) -> io::Result<()> {
        let nco: Vec<f64> = record.nco().map(|(_, v)| v).collect();
        self.write_row_on(&record.row, &record.carrier_or_l1(), &nco)
    }

    /// Number of data rows written so far.
    pub fn rows(&self) -> u64 {
        self.rows
    }

    /// Flushes the buffer and returns the underlying writer.
    pub fn finish(self) -> io::Result<W> {
        self.out.into_inner().map_err(|e| e.into_error())
    }
}

/// Header of an epoch series file ([`write_epochs_csv`]).
pub const EPOCH_COLUMNS: [&str; 5] = ["t_s", "phase_err_rad", "fx_mps2", "fy_mps2", "fz_mps2"];

/// Writes the estimator's input on the epoch grid to `w`: per epoch its time
/// \[s\], the channel-averaged phase error \[rad\] (empty where no channel had
/// one) and the specific force interpolated onto it \[m/s²\], under the header
/// [`EPOCH_COLUMNS`]. What a receiver would feed its calibrator epoch by
/// epoch (the C example `examples/c/calibrate.c` reads it).
///
/// Errors: I/O errors of `w`; `InvalidInput` when the three series differ in
/// length or a time or specific force is not finite.
pub fn write_epochs_csv<W: Write>(
    w: W,
    t_s: &[f64],
    phase_err_rad: &[Option<f64>],
    accel_mps2: &[[f64; 3]],
) -> io::Result<()> {
    if phase_err_rad.len() != t_s.len() || accel_mps2.len() != t_s.len() {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!(
                "epoch series of {} times, {} phases and {} samples",
                t_s.len(),
                phase_err_rad.len(),
                accel_mps2.len()
            ),
        ));
    }
    let mut w = BufWriter::new(w);
    writeln!(w, "{}", EPOCH_COLUMNS.join(","))?;
    for (k, ((t, p), a)) in t_s.iter().zip(phase_err_rad).zip(accel_mps2).enumerate() {
        let row = k as u64 + 1;
        check("t_s", *t, row)?;
        for (name, x) in ["fx_mps2", "fy_mps2", "fz_mps2"].iter().zip(a) {
            check(name, *x, row)?;
        }
        match p.filter(|p| p.is_finite()) {
            Some(p) => writeln!(w, "{t},{p},{},{},{}", a[0], a[1], a[2])?,
            None => writeln!(w, "{t},,{},{},{}", a[0], a[1], a[2])?,
        }
    }
    w.flush()
}

/// [`write_epochs_csv`] into the file `path`, made afresh: an error making
/// or writing it is the file's ([`FileError`], `cannot write`).
pub fn write_epochs_file(
    path: &Path,
    t_s: &[f64],
    phase_err_rad: &[Option<f64>],
    accel_mps2: &[[f64; 3]],
) -> Result<(), FileError> {
    std::fs::File::create(path)
        .and_then(|f| write_epochs_csv(f, t_s, phase_err_rad, accel_mps2))
        .map_err(|source| FileError { path: path.to_path_buf(), action: "write", source })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The file holds what [`write_epochs_csv`] writes; a series it refuses
    /// and a path that is no file are the file's error, `cannot write`.
    #[test]
    fn an_epochs_file_is_the_csv_or_the_files_error() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("epochs.csv");
        write_epochs_file(&path, &[0.02, 0.04], &[Some(0.5), None], &[[1.0, 2.0, 3.0]; 2]).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert_eq!(text, "t_s,phase_err_rad,fx_mps2,fy_mps2,fz_mps2\n0.02,0.5,1,2,3\n0.04,,1,2,3\n");
        let e = write_epochs_file(&path, &[0.02], &[], &[]).unwrap_err();
        assert_eq!(
            (e.to_string(), e.source.kind()),
            (format!("{}: cannot write", path.display()), io::ErrorKind::InvalidInput)
        );
        let e = write_epochs_file(dir.path(), &[], &[], &[]).unwrap_err();
        assert_eq!(e.to_string(), format!("{}: cannot write", dir.path().display()));
    }
    use crate::imu::read_imu;
    use crate::tracking::read_tracking;

    /// Deterministic awkward values: random bit patterns, tiny and huge magnitudes, -0.
    fn awkward_values(n: usize) -> Vec<f64> {
        let mut x: u64 = 0x9E37_79B9_7F4A_7C15;
        let mut out = vec![0.0, -0.0, 0.1, 1.0 / 3.0, 1e-300, -2.5e300, 5e-324, f64::MAX, f64::MIN_POSITIVE];
        while out.len() < n {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let v = f64::from_bits(x);
            if v.is_finite() {
                out.push(v);
            }
        }
        out
    }

    #[test]
    fn imu_round_trip_is_bit_exact() {
        let vals = awkward_values(300);
        let n = 100;
        let t_s: Vec<f64> = (0..n).map(|k| -3.0 + k as f64 * 0.0123456789).collect();
        let accel_mps2: Vec<[f64; 3]> = (0..n).map(|k| [vals[3 * k], vals[3 * k + 1], vals[3 * k + 2]]).collect();
        let imu = ImuSeries { t_s, accel_mps2 };
        let mut buf = Vec::new();
        write_imu_csv(&mut buf, &imu).unwrap();
        let back = read_imu(buf.as_slice(), "mem").unwrap();
        assert_eq!(back.t_s.len(), n);
        for k in 0..n {
            assert_eq!(back.t_s[k].to_bits(), imu.t_s[k].to_bits());
            for i in 0..3 {
                assert_eq!(back.accel_mps2[k][i].to_bits(), imu.accel_mps2[k][i].to_bits(), "row {k} axis {i}");
            }
        }
        // Deterministic: writing twice gives the same bytes.
        let mut buf2 = Vec::new();
        write_imu_csv(&mut buf2, &back).unwrap();
        assert_eq!(buf, buf2);
    }

    #[test]
    fn tracking_round_trip_is_bit_exact() {
        let vals = awkward_values(400);
        let mut w = TrackingWriter::new(Vec::new()).unwrap();
        let mut rows = Vec::new();
        for k in 0..50 {
            let t_s = 1000.0 + k as f64 * 0.025;
            for ch in 0..4u32 {
                let i = (k * 4 + ch as usize) % 100;
                let row = TrackingRow {
                    t_s,
                    channel: ch,
                    prn: ch + 10,
                    cn0_dbhz: 30.0 + vals[i].abs().fract() * 20.0,
                    elev_deg: if ch == 2 { None } else { Some(vals[i + 100].rem_euclid(90.0)) },
                    phase_err_rad: vals[i + 200],
                };
                w.write_row(&row).unwrap();
                rows.push(row);
            }
        }
        assert_eq!(w.rows(), 200);
        let buf = w.finish().unwrap();
        let log = read_tracking(buf.as_slice(), "mem").unwrap();
        assert_eq!(log.rows(), 200);
        for row in &rows {
            let tr = log.tracks().iter().find(|t| t.channel == row.channel).unwrap();
            assert_eq!(tr.prn, row.prn);
            let j = tr.t_s.iter().position(|&t| t.to_bits() == row.t_s.to_bits()).unwrap();
            assert_eq!(tr.cn0_dbhz[j].to_bits(), row.cn0_dbhz.to_bits());
            assert_eq!(tr.phase_err_rad[j].to_bits(), row.phase_err_rad.to_bits());
            match row.elev_deg {
                Some(e) => assert_eq!(tr.elev_deg[j].to_bits(), e.to_bits()),
                None => assert!(tr.elev_deg[j].is_nan()),
            }
        }
        assert!(
            String::from_utf8(buf).unwrap().starts_with("t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad\n1000,0,10,")
        );
    }

    #[test]
    fn writers_refuse_non_finite() {
        let imu = ImuSeries { t_s: vec![0.0], accel_mps2: vec![[0.0, f64::NAN, 0.0]] };
        let e = write_imu_csv(Vec::new(), &imu).unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::InvalidInput);
        assert!(e.to_string().contains("fy_mps2"), "{e}");
        let mut w = TrackingWriter::new(Vec::new()).unwrap();
        let row = TrackingRow {
            t_s: 0.0,
            channel: 1,
            prn: 1,
            cn0_dbhz: 40.0,
            elev_deg: Some(f64::INFINITY),
            phase_err_rad: 0.0,
        };
        let e = w.write_row(&row).unwrap_err();
        assert!(e.to_string().contains("elev_deg"), "{e}");
    }

    #[test]
    fn extra_columns_are_written_after_the_format_and_checked() {
        let mut w = TrackingWriter::with_extra_columns(Vec::new(), &["carrier_lock_test"]).unwrap();
        let row = TrackingRow { t_s: 0.5, channel: 3, prn: 12, cn0_dbhz: 44.25, elev_deg: None, phase_err_rad: -0.125 };
        w.write_row_with(&row, &[0.9902583956718445]).unwrap();
        w.write_row_with(&TrackingRow { t_s: 0.525, elev_deg: Some(12.5), ..row }, &[1.0]).unwrap();
        // Refused: a missing extra value, a non-finite one.
        assert_eq!(w.write_row(&row).unwrap_err().kind(), io::ErrorKind::InvalidInput);
        let e = w.write_row_with(&row, &[f64::NAN]).unwrap_err();
        assert!(e.to_string().contains("carrier_lock_test") && e.to_string().contains("data row 3"), "{e}");
        assert_eq!(w.rows(), 2);
        let text = String::from_utf8(w.finish().unwrap()).unwrap();
        assert_eq!(
            text,
            "t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad,carrier_lock_test\n\
             0.5,3,12,44.25,,-0.125,0.9902583956718445\n0.525,3,12,44.25,12.5,-0.125,1\n"
        );
        let log = read_tracking(text.as_bytes(), "mem").unwrap();
        assert_eq!(log.rows(), 2);
        for bad in ["", "a,b", "phase_err_rad", "x\ny"] {
            assert!(TrackingWriter::with_extra_columns(Vec::new(), &[bad]).is_err(), "{bad:?}");
        }
        assert!(TrackingWriter::with_extra_columns(Vec::new(), &["x", "x"]).is_err());
    }

    /// The epoch series: header, shortest round-trip numbers, a gap as an empty phase.
    #[test]
    fn epochs_csv_round_trips_and_marks_gaps() {
        let t = [0.025, 0.05];
        let p = [Some(0.1 + 0.2), None];
        let a = [[1.0 / 3.0, -2.5, 9.81], [0.0, 1e-300, -0.0]];
        let mut out = Vec::new();
        write_epochs_csv(&mut out, &t, &p, &a).unwrap();
        let text = String::from_utf8(out).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines[0], "t_s,phase_err_rad,fx_mps2,fy_mps2,fz_mps2");
        let f: Vec<&str> = lines[1].split(',').collect();
        assert_eq!(f[1].parse::<f64>().unwrap(), 0.1 + 0.2);
        assert_eq!(f[2].parse::<f64>().unwrap(), 1.0 / 3.0);
        assert_eq!(lines[2].split(',').nth(1), Some(""));
        assert_eq!(lines[2].split(',').nth(3).unwrap().parse::<f64>().unwrap(), 1e-300);
        let bad = [[f64::NAN, 0.0, 0.0], [0.0; 3]];
        assert_eq!(write_epochs_csv(Vec::new(), &t, &p, &bad).unwrap_err().kind(), io::ErrorKind::InvalidInput);
        assert!(write_epochs_csv(Vec::new(), &t[..1], &p, &a).is_err());
    }
}
