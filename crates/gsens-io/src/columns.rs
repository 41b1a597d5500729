//! Where the columns of `tracking.csv` are, read off its header
//! ([`TrackingColumns`]), and one row's cells read by that map: the one row
//! parser of the file reader and of logs read a line at a time.

use crate::parse::{BadCell, cell_f64, cell_u32};
use crate::row::TrackingRecord;
use crate::signal::{Carrier, SIGNALS, Signal, SignalError};
use crate::tracking::{CARRIER_COLUMNS, NCO_COLUMNS, StampCache, TRACKING_COLUMNS};
use crate::writers::TrackingRow;

/// The columns of a tracking log, found by name in its header: the six of
/// [`TRACKING_COLUMNS`] (required, in any order), the carrier columns
/// ([`CARRIER_COLUMNS`]) and the NCO columns ([`NCO_COLUMNS`]) where the
/// header names them; other columns are ignored. The crate documentation
/// gives what each column holds.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TrackingColumns {
    /// The header's names, trimmed.
    names: Vec<String>,
    /// The 0-based positions of [`TRACKING_COLUMNS`], in its order.
    required: [usize; 6],
    /// Of [`CARRIER_COLUMNS`], where present.
    carrier: [Option<usize>; 3],
    /// Of [`NCO_COLUMNS`], where present.
    nco: [Option<usize>; 2],
}

/// What is wrong with a tracking log's header.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum HeaderError {
    /// A column of [`TRACKING_COLUMNS`] is not in the header.
    #[error("missing column `{name}`")]
    Missing {
        /// The column's name.
        name: &'static str,
    },
    /// A column gsens reads is named twice.
    #[error("column `{name}` appears twice (columns {first_index} and {second_index})")]
    Duplicate {
        /// The column's name.
        name: &'static str,
        /// 1-based position of its first occurrence.
        first_index: usize,
        /// 1-based position of its second occurrence.
        second_index: usize,
    },
}

impl Default for TrackingColumns {
    /// The six columns of [`TRACKING_COLUMNS`] in their order: a log without
    /// a header line, as [`crate::parse_tracking_row`] reads one.
    fn default() -> Self {
        TrackingColumns {
            names: TRACKING_COLUMNS.iter().map(|&n| n.to_owned()).collect(),
            required: [0, 1, 2, 3, 4, 5],
            carrier: [None; 3],
            nco: [None; 2],
        }
    }
}

impl TrackingColumns {
    /// The columns of a log whose header line holds `names` (each trimmed of
    /// ASCII white space, the first of a byte-order mark). Errors: a column of
    /// [`TRACKING_COLUMNS`] missing, or a column gsens reads named twice (in
    /// the order required, carrier, NCO columns).
    pub fn from_header<S: AsRef<str>>(names: &[S]) -> Result<Self, HeaderError> {
        let names: Vec<String> = names
            .iter()
            .enumerate()
            .map(|(i, n)| {
                let n = n.as_ref();
                let n = if i == 0 { n.strip_prefix('\u{feff}').unwrap_or(n) } else { n };
                n.trim_ascii().to_owned()
            })
            .collect();
        let find = |name: &'static str| -> Result<Option<usize>, HeaderError> {
            let mut found = names.iter().enumerate().filter(|(_, n)| *n == name).map(|(i, _)| i);
            match (found.next(), found.next()) {
                (Some(a), Some(b)) => Err(HeaderError::Duplicate { name, first_index: a + 1, second_index: b + 1 }),
                (a, _) => Ok(a),
            }
        };
        let mut required = [0; 6];
        for (at, name) in required.iter_mut().zip(TRACKING_COLUMNS) {
            *at = find(name)?.ok_or(HeaderError::Missing { name })?;
        }
        let carrier = [find(CARRIER_COLUMNS[0])?, find(CARRIER_COLUMNS[1])?, find(CARRIER_COLUMNS[2])?];
        let nco = [find(NCO_COLUMNS[0])?, find(NCO_COLUMNS[1])?];
        Ok(TrackingColumns { names, required, carrier, nco })
    }

    /// The columns of a log that holds `record`, as [`crate::TrackingWriter::for_record`]
    /// writes it: the six of [`TRACKING_COLUMNS`], then `signal,carrier_hz`
    /// where it has a carrier, then its NCO columns.
    pub fn of_record(record: &TrackingRecord) -> Self {
        let names = record.header();
        Self::from_header(&names).expect("a record's columns are a valid header")
    }

    /// The header's names, as found (trimmed).
    pub fn names(&self) -> &[String] {
        &self.names
    }

    /// Whether the header names any of the carrier or NCO columns.
    pub fn has_optional(&self) -> bool {
        self.carrier.iter().chain(&self.nco).any(Option::is_some)
    }

    /// The 0-based positions of [`TRACKING_COLUMNS`], in its order.
    pub(crate) fn required(&self) -> [usize; 6] {
        self.required
    }

    /// The column that names the carrier in errors about a track's carrier
    /// (0-based), `None` without carrier columns.
    pub(crate) fn carrier_column(&self) -> Option<usize> {
        let [signal, glo_k, carrier_hz] = self.carrier;
        signal.or(carrier_hz).or(glo_k)
    }
}

/// A cell that does not hold what its column should: its 0-based position and why.
#[derive(Debug)]
pub(crate) struct CellFault {
    pub(crate) index: usize,
    pub(crate) fault: Fault,
}

/// Why a cell is refused.
#[derive(Debug)]
pub(crate) enum Fault {
    /// Not the number it should be (`expected` says what).
    Cell { bad: BadCell, expected: &'static str },
    /// Not a carrier gsens knows, or not agreeing with the row's other carrier cells.
    Carrier(SignalError),
}

fn at(index: usize, bad: BadCell, expected: &'static str) -> CellFault {
    CellFault { index, fault: Fault::Cell { bad, expected } }
}

/// The row parser: the rows of one log read by its [`TrackingColumns`], a
/// row at a time, with the rules of the crate documentation.
pub(crate) struct RowParser<'c> {
    columns: &'c TrackingColumns,
    /// The rows of one epoch share the text of their stamp.
    stamp: StampCache,
    /// The previous row's raw carrier cells and carrier: the rows of one track repeat them.
    carrier: Option<(Vec<u8>, Carrier)>,
}

impl<'c> RowParser<'c> {
    pub(crate) fn new(columns: &'c TrackingColumns) -> Self {
        RowParser { columns, stamp: StampCache::default(), carrier: None }
    }

    /// The record of the row whose cell at 0-based position `i` is `cell(i)`
    /// (empty beyond the row's end); the first cell refused, in the order
    /// of the required columns, then the carrier, then the NCO columns.
    #[inline]
    pub(crate) fn record<'a>(&mut self, cell: impl Fn(usize) -> &'a [u8]) -> Result<TrackingRecord, CellFault> {
        let [ct, cch, cprn, ccn0, celev, cphase] = self.columns.required;
        let number = |i: usize| match cell_f64(cell(i)) {
            Ok(Some(v)) => Ok(v),
            Ok(None) => Err(at(i, BadCell::Empty, "a number")),
            Err(bad) => Err(at(i, bad, "a number")),
        };
        let count = |i: usize| cell_u32(cell(i)).map_err(|bad| at(i, bad, "a non-negative integer"));
        let row = TrackingRow {
            t_s: self.stamp.get(cell(ct), || number(ct))?,
            channel: count(cch)?,
            prn: count(cprn)?,
            cn0_dbhz: number(ccn0)?,
            elev_deg: cell_f64(cell(celev)).map_err(|bad| at(celev, bad, "a number"))?,
            phase_err_rad: number(cphase)?,
        };
        let carrier = if self.columns.carrier.iter().any(Option::is_some) { Some(self.carrier(&cell)?) } else { None };
        let [nco_phase, nco_freq] = self.columns.nco;
        Ok(TrackingRecord {
            row,
            carrier,
            nco_phase_cycles: nco_phase.map(number).transpose()?,
            nco_freq_hz: nco_freq.map(number).transpose()?,
        })
    }

    /// The carrier of the row (a log with carrier columns).
    fn carrier<'a>(&mut self, cell: &impl Fn(usize) -> &'a [u8]) -> Result<Carrier, CellFault> {
        let mut key = Vec::new();
        for c in self.columns.carrier.into_iter().flatten() {
            key.extend_from_slice(cell(c));
            key.push(b',');
        }
        if let Some((k, carrier)) = &self.carrier
            && *k == key
        {
            return Ok(*carrier);
        }
        let carrier = parse_carrier(self.columns.carrier, cell)?;
        self.carrier = Some((key, carrier));
        Ok(carrier)
    }
}

/// The carrier the cells of the carrier columns at `[signal, glo_k,
/// carrier_hz]` (0-based, where present) give (crate documentation, "Carrier").
fn parse_carrier<'a>(columns: [Option<usize>; 3], cell: &impl Fn(usize) -> &'a [u8]) -> Result<Carrier, CellFault> {
    let [signal_col, glo_k_col, hz_col_opt] = columns;
    let fail = |index: usize, error: SignalError| CellFault { index, fault: Fault::Carrier(error) };
    let name = signal_col.map(|c| String::from_utf8_lossy(cell(c).trim_ascii()).into_owned()).filter(|n| !n.is_empty());
    let glo_k = match glo_k_col {
        Some(c) => {
            let raw = cell(c).trim_ascii();
            if raw.is_empty() {
                None
            } else {
                let k = std::str::from_utf8(raw).ok().and_then(|s| s.trim_start_matches('+').parse::<i64>().ok());
                Some(k.ok_or_else(|| at(c, BadCell::NotANumber, "an integer"))?)
            }
        }
        None => None,
    };
    let hz = match hz_col_opt {
        Some(c) => cell_f64(cell(c)).map_err(|bad| at(c, bad, "a number"))?,
        None => None,
    };
    let hz_col = hz_col_opt.unwrap_or(0);
    if let Some(f) = hz {
        Carrier::from_hz(f).map_err(|e| fail(hz_col, e))?;
    }
    match (name, glo_k, hz) {
        (Some(name), k, hz) => {
            let sig_col = signal_col.expect("a name comes from the signal column");
            let fdma = SIGNALS.iter().any(|s| s.name == name && s.fdma_step_hz.is_some());
            let signal = match (k, hz) {
                (None, Some(f)) if fdma => Signal::with_carrier(&name, f).map_err(|e| fail(hz_col, e))?,
                (k, _) => Signal::new(&name, k).map_err(|e| match e {
                    SignalError::Unknown(_) | SignalError::MissingK(_) => fail(sig_col, e),
                    _ => fail(glo_k_col.unwrap_or(sig_col), e),
                })?,
            };
            if let Some(f) = hz {
                signal.check_carrier(f).map_err(|e| fail(hz_col, e))?;
            }
            Ok(Carrier::of(signal))
        }
        (None, Some(k), _) => {
            let col = signal_col.unwrap_or(glo_k_col.expect("k comes from the glo_k column"));
            Err(fail(col, SignalError::Unknown(format!("(empty signal with glo_k = {k})"))))
        }
        (None, None, Some(f)) => Ok(Carrier { carrier_hz: f, signal: None }),
        (None, None, None) => {
            let col = signal_col.or(hz_col_opt).or(glo_k_col).expect("some carrier column");
            Err(at(col, BadCell::Empty, "the row's carrier (a signal name or carrier_hz)"))
        }
    }
}
