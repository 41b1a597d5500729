//! The crate documentation's sections "Reading" and "Flags and events" describe this module.

use std::collections::{BTreeMap, HashMap};
use std::io::{BufReader, Read};
use std::path::Path;

use gsens_io::{ClockEvent, Observation, ObservationLog, ObservationLogBuilder, obs_flags};
use rinex::prelude::obs::{EpochFlag, LliFlags, SNR};
use rinex::prelude::{Epoch, Observable, ParsingError, Rinex, SV, TimeScale};
use rinex::record::{ParsingDiagnostic, ParsingDiagnosticKind};

use crate::signals::carrier;

/// A change of the epoch line's receiver clock offset larger than this between
/// consecutive epochs is reported as a clock jump \[s\]: receivers that jump
/// do so by whole milliseconds, while a steered clock's offset moves by
/// microseconds per epoch.
pub const CLOCK_JUMP_S: f64 = 1e-4;

/// Why a RINEX file could not be read. Epochs the `rinex` crate cannot
/// decode are not errors: they are skipped and counted with their line
/// ([`ObservationLog::skipped`]).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RinexError {
    /// The file could not be opened or read.
    #[error("{file}: cannot read: {error}")]
    Io {
        /// Source name.
        file: String,
        /// The underlying error.
        error: std::io::Error,
    },
    /// The header (or the whole input) is not RINEX the crate can read.
    #[error("{file}: {where_}not a readable RINEX observation file: {reason}")]
    Parse {
        /// Source name.
        file: String,
        /// `line N: ` where the crate names the line, else empty.
        where_: String,
        /// The crate's reason.
        reason: String,
    },
    /// A RINEX file of another kind (navigation, meteo, clock, …).
    #[error("{file}: a RINEX {kind} file, not an observation file")]
    NotObservation {
        /// Source name.
        file: String,
        /// The kind the header states.
        kind: String,
    },
    /// An observation file without a single epoch read.
    #[error("{file}: no observation epoch could be read ({skipped} skipped{first})")]
    NoData {
        /// Source name.
        file: String,
        /// Epochs and records skipped.
        skipped: usize,
        /// The first reason, as `: 3 × … (first at line 17)`.
        first: String,
    },
}

/// Reads the RINEX observation file at `path` (RINEX 2 or 3, plain or
/// Hatanaka-compressed).
pub fn read_rinex_file(path: impl AsRef<Path>) -> Result<ObservationLog, RinexError> {
    let path = path.as_ref();
    let name = path.display().to_string();
    let file = std::fs::File::open(path).map_err(|error| RinexError::Io { file: name.clone(), error })?;
    read_rinex(file, &name)
}

/// Reads a RINEX observation file from `input`; `source_name` names it in messages.
pub fn read_rinex<R: Read>(mut input: R, source_name: &str) -> Result<ObservationLog, RinexError> {
    let mut bytes = Vec::new();
    input.read_to_end(&mut bytes).map_err(|error| RinexError::Io { file: source_name.to_owned(), error })?;
    read_rinex_bytes(&bytes, source_name)
}

/// Reads a RINEX observation file held in memory.
pub fn read_rinex_bytes(bytes: &[u8], source_name: &str) -> Result<ObservationLog, RinexError> {
    let file = source_name.to_owned();
    let header_lines = header_line_count(bytes);
    // The crate slices some malformed lines without checking their length, and panics: such an
    // input is refused like any other the crate cannot read.
    let parsed = std::panic::catch_unwind(|| Rinex::parse_with_diagnostics(&mut BufReader::new(bytes)));
    let (rinex, diagnostics) = match parsed {
        Ok(parsed) => parsed.map_err(|e| parse_error(&file, &e, header_lines))?,
        Err(_) => {
            let reason = "the rinex crate failed on a malformed line".to_owned();
            return Err(RinexError::Parse { file, where_: String::new(), reason });
        }
    };
    if !rinex.is_observation_rinex() {
        return Err(RinexError::NotObservation { file, kind: format!("{:?}", rinex.header.rinex_type) });
    }
    let version = rinex.header.version;
    let mut b = ObservationLogBuilder::new(source_name, &format!("RINEX {}.{:02}", version.major, version.minor));
    for d in &diagnostics {
        diagnostic(&mut b, d, header_lines);
    }
    let glo_k: HashMap<SV, i8> = rinex.header.glo_channels.clone();
    let mut last_clock_s: Option<f64> = None;
    if let Some(record) = rinex.record.as_obs() {
        for (key, observations) in record {
            let at = || format!("epoch {}", key.epoch);
            match key.flag {
                EpochFlag::Ok | EpochFlag::PowerFailure => {}
                EpochFlag::CycleSlip => {
                    b.skip("epoch flag 6 (cycle slip records)", at);
                    continue;
                }
                _ => {
                    b.skip("epoch flag 2–5 (event)", at);
                    continue;
                }
            }
            let Some((week, tow_s)) = gps_week_tow(key.epoch) else {
                b.skip("epoch before the GPS time origin", at);
                continue;
            };
            let Some(t_s) = b.start_epoch(week, tow_s, at) else { continue };
            if let Some(clock) = &observations.clock {
                if let Some(last) = last_clock_s.filter(|last| (clock.offset_s - last).abs() > CLOCK_JUMP_S) {
                    b.clock_event(ClockEvent {
                        t_s,
                        jump_s: Some(clock.offset_s - last),
                        what: "receiver clock offset (epoch line)".to_owned(),
                    });
                }
                last_clock_s = Some(clock.offset_s);
            }
            let power_failure = key.flag == EpochFlag::PowerFailure;
            epoch(&mut b, t_s, &observations.signals, &glo_k, power_failure, version.major);
        }
    }
    let log = b.finish();
    if log.epochs == 0 {
        let first = log.skipped.first().map(|s| format!(": {s}")).unwrap_or_default();
        return Err(RinexError::NoData { file, skipped: log.skipped_count(), first });
    }
    Ok(log)
}

/// One signal's observables within an epoch, gathered from the file's fields.
#[derive(Default)]
struct Gathered {
    obs: Observation,
    /// The phase's LLI, else none.
    lli: Option<LliFlags>,
    /// The phase's signal strength, else the first other one.
    ssi: Option<SNR>,
    has_phase: bool,
    has_code: bool,
}

fn epoch(
    b: &mut ObservationLogBuilder,
    t_s: f64,
    signals: &[rinex::prelude::obs::SignalObservation],
    glo_k: &HashMap<SV, i8>,
    power_failure: bool,
    major: u8,
) {
    // Ordered by satellite and code, so the tracks come in a stable order.
    let mut gathered: BTreeMap<(String, String), (SV, Gathered)> = BTreeMap::new();
    for s in signals {
        let (kind, code) = match &s.observable {
            Observable::PhaseRange(c) => ('L', c),
            Observable::PseudoRange(c) => ('C', c),
            Observable::Doppler(c) => ('D', c),
            Observable::SSI(c) => ('S', c),
            _ => continue,
        };
        let code = code.get(1..).unwrap_or("").to_owned();
        if major < 3 && code_letter(&s.observable) == Some('P') {
            b.skip("RINEX 2 P-code pseudorange (the C/A code's is kept)", || format!("t = {t_s} s"));
            continue;
        }
        let sv = format!("{:x}", s.sv);
        let (_, g) = gathered.entry((sv, code)).or_insert_with(|| (s.sv, Gathered::default()));
        match kind {
            'L' => {
                g.obs.carrier_phase_cycles = s.value;
                g.has_phase = true;
                g.lli = s.lli;
                g.ssi = s.snr.or(g.ssi);
            }
            'C' => {
                g.obs.pseudorange_m = s.value;
                g.has_code = true;
            }
            'D' => g.obs.doppler_hz = s.value,
            _ => g.obs.cn0_dbhz = s.value,
        }
        if kind != 'L' && g.ssi.is_none() {
            g.ssi = s.snr;
        }
    }
    for ((sv, code), (sv_id, g)) in gathered {
        let system = sv.chars().next().unwrap_or('?');
        let k = glo_k.get(&sv_id).copied();
        let carrier = match carrier(system, &code, k) {
            Ok(c) => c,
            Err(e) => {
                b.skip(&e.reason(system, &code), || format!("{sv} at t = {t_s} s"));
                continue;
            }
        };
        let mut flags = g.lli.map_or(0, |l| l.bits() & 0x07);
        if power_failure {
            flags |= obs_flags::LOSS_OF_LOCK;
        }
        if !g.has_phase {
            flags |= obs_flags::PHASE_INVALID;
        }
        if !g.has_code {
            flags |= obs_flags::PSEUDORANGE_INVALID;
        }
        let obs = Observation { flags, strength: Some(g.ssi.map_or(0, ssi_digit)), lock_time_s: None, ..g.obs };
        b.push(&sv, &code, carrier, t_s, &obs);
    }
}

fn code_letter(o: &Observable) -> Option<char> {
    match o {
        Observable::PseudoRange(c) => c.chars().next(),
        _ => None,
    }
}

/// RINEX 3.04 §5.7's signal strength digit of the crate's [`SNR`] (0: blank).
fn ssi_digit(snr: SNR) -> u8 {
    match snr {
        SNR::DbHz0 => 0,
        SNR::DbHz12 => 1,
        SNR::DbHz12_17 => 2,
        SNR::DbHz18_23 => 3,
        SNR::DbHz24_29 => 4,
        SNR::DbHz30_35 => 5,
        SNR::DbHz36_41 => 6,
        SNR::DbHz42_47 => 7,
        SNR::DbHz48_53 => 8,
        SNR::DbHz54 => 9,
    }
}

/// GPS week and time of week \[s\] of `epoch` (in any time scale the crate reads).
fn gps_week_tow(epoch: Epoch) -> Option<(u32, f64)> {
    let gpst = epoch.to_time_scale(TimeScale::GPST);
    if gpst.duration.total_nanoseconds() < 0 {
        return None;
    }
    let (week, ns) = gpst.to_time_of_week();
    // Whole seconds and the rest apart: exact to the nanosecond for any week.
    Some((week, (ns / 1_000_000_000) as f64 + (ns % 1_000_000_000) as f64 * 1e-9))
}

/// Counts an epoch the crate could not decode, with its line in the file.
fn diagnostic(b: &mut ObservationLogBuilder, d: &ParsingDiagnostic, header_lines: usize) {
    let line = header_lines + d.record_line;
    match &d.kind {
        ParsingDiagnosticKind::ObservationFailure(ParsingError::ObsHardwareEvent) => {
            b.skip("epoch flag 2–5 (event)", || format!("line {line}"))
        }
        ParsingDiagnosticKind::ObservationFailure(e) => {
            b.skip(&format!("epoch the rinex crate cannot decode ({e})"), || format!("line {line}"))
        }
        ParsingDiagnosticKind::DuplicateObservation { .. } => {
            b.skip("epoch repeated (the last kept)", || format!("line {line}"))
        }
        _ => b.skip("record of another kind", || format!("line {line}")),
    }
}

/// The number of header lines (through `END OF HEADER`), 0 if there is none.
fn header_line_count(bytes: &[u8]) -> usize {
    bytes.split(|&c| c == b'\n').position(|l| l.windows(13).any(|w| w == b"END OF HEADER")).map_or(0, |i| i + 1)
}

fn parse_error(file: &str, e: &ParsingError, header_lines: usize) -> RinexError {
    let where_ = match e {
        ParsingError::NonAscii { line, .. } if header_lines == 0 || *line <= header_lines => format!("line {line}: "),
        _ => String::new(),
    };
    RinexError::Parse { file: file.to_owned(), where_, reason: e.to_string() }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn week_and_time_of_week() {
        // 2024-02-08 12:00:18 GPST: week 2300, Thursday noon + 18 s.
        let e = Epoch::from_gregorian(2024, 2, 8, 12, 0, 18, 200_000_000, TimeScale::GPST);
        assert_eq!(gps_week_tow(e), Some((2300, 388_818.2)));
        assert_eq!(gps_week_tow(Epoch::from_gregorian(1970, 1, 1, 0, 0, 0, 0, TimeScale::GPST)), None);
        assert_eq!(header_line_count(b"a\nb END OF HEADER\nc\n"), 2);
    }
}
