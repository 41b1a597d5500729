//! The crate documentation's section "The log" describes this module.

use std::collections::BTreeMap;
use std::path::Path;

use serde::Serialize;

use crate::error::PocketSdrError;

/// Fields of a `$CH` line of PocketSDR 0.17, the type included.
pub(crate) const CH_FIELDS_V017: usize = 27;
/// The fewest fields a `$CH` line must have: up to `err_code` (older
/// versions write fewer after it).
pub(crate) const CH_FIELDS_MIN: usize = 19;
/// The names of the `$CH` fields by index (0 = the type).
pub(crate) const CH_FIELD_NAMES: [&str; CH_FIELDS_V017] = [
    "type", "time", "ch", "rfch", "sat", "sig", "prn", "lock", "cn0", "coff", "dop", "adr", "ssync", "bsync", "fsync",
    "rev", "srev", "err_phas", "err_code", "tow_v", "tow", "week", "type", "nnav", "nerr", "nlol", "nfec",
];

/// One `$CH` line.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ChRecord {
    /// 1-based line in the log.
    pub line: u64,
    /// `time`: receiver time of the start of the logged 1 ms block \[s\].
    pub time_s: f64,
    /// `ch`: receiver channel number.
    pub ch: u32,
    /// `sat`: satellite ID (e.g. `G31`).
    pub sat: String,
    /// `sig`: signal ID (`L1CA` for GPS L1 C/A).
    pub sig: String,
    /// `prn`.
    pub prn: u32,
    /// `lock`: time since acquisition \[s\].
    pub lock_s: f64,
    /// `cn0` \[dB-Hz\].
    pub cn0_dbhz: f64,
    /// `dop`: the NCO's Doppler frequency \[Hz\].
    pub dop_hz: f64,
    /// `adr`: the accumulated Doppler range, ∫`dop` dt \[cycles\]: the
    /// replica's phase less the IF's.
    pub adr_cyc: f64,
    /// `err_phas`: the discriminator output of the block \[cycles\].
    pub err_phas_cyc: f64,
    /// `nlol`: the channel's losses of lock so far (`None` in logs without it).
    pub nlol: Option<u32>,
}

/// A line that was skipped.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Garbled {
    /// 1-based line.
    pub line: u64,
    /// The field (1-based after the type) and its name, when one field is to blame.
    pub field: Option<(usize, &'static str)>,
    /// What is wrong.
    pub reason: String,
}

impl std::fmt::Display for Garbled {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.field {
            Some((i, name)) => write!(f, "line {}: field {i} ({name}): {}", self.line, self.reason),
            None => write!(f, "line {}: {}", self.line, self.reason),
        }
    }
}

/// Garbled lines kept with their details (the rest are counted).
pub(crate) const GARBLED_KEPT: usize = 20;

/// A parsed log.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PocketSdrLog {
    /// The log's name (its path) for messages.
    pub file: String,
    /// Lines in the log.
    pub lines: u64,
    /// The readable `$CH` lines, in log order.
    pub records: Vec<ChRecord>,
    /// Fields of the log's `$CH` lines (the most common count).
    pub ch_fields: usize,
    /// Lines per message type (`$CH`, `$LOG`, …; garbled lines under `garbled`).
    pub messages: BTreeMap<String, u64>,
    /// The first `GARBLED_KEPT` garbled lines.
    pub garbled: Vec<Garbled>,
    /// All garbled lines.
    pub garbled_count: u64,
    /// The sampling rate of the START message (`FS=` in MHz) \[Hz\].
    pub fs_hz: Option<f64>,
    /// The version of the START message (`VER=`).
    pub version: Option<String>,
}

impl PocketSdrLog {
    fn garble(&mut self, g: Garbled) {
        self.garbled_count += 1;
        *self.messages.entry("garbled".into()).or_default() += 1;
        if self.garbled.len() < GARBLED_KEPT {
            self.garbled.push(g);
        }
    }
}

/// Reads and parses a log file ([`parse_log`]).
pub fn read_log(path: &Path) -> Result<PocketSdrLog, PocketSdrError> {
    let name = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|error| PocketSdrError::Io { file: name.clone(), error })?;
    parse_log(&bytes, &name)
}

/// Parses a log held in memory; `file` names it in messages. Errors when it
/// is empty or holds no readable `$CH` line; garbled lines are skipped and
/// reported in [`PocketSdrLog::garbled`].
pub fn parse_log(bytes: &[u8], file: &str) -> Result<PocketSdrLog, PocketSdrError> {
    if bytes.is_empty() {
        return Err(PocketSdrError::EmptyLog { file: file.into() });
    }
    let text = String::from_utf8_lossy(bytes);
    let lines: Vec<&str> = text.split('\n').map(|l| l.strip_suffix('\r').unwrap_or(l)).collect();
    // The log's $CH field count: the most common among lines with one `$`.
    let mut counts: BTreeMap<usize, u64> = BTreeMap::new();
    for l in &lines {
        if l.starts_with("$CH,") && !l[1..].contains('$') {
            *counts.entry(l.split(',').count()).or_default() += 1;
        }
    }
    let ch_fields = counts.iter().max_by_key(|(n, c)| (**c, **n)).map_or(CH_FIELDS_V017, |(n, _)| *n);
    let mut log = PocketSdrLog {
        file: file.into(),
        lines: 0,
        records: Vec::new(),
        ch_fields,
        messages: BTreeMap::new(),
        garbled: Vec::new(),
        garbled_count: 0,
        fs_hz: None,
        version: None,
    };
    for (i, raw) in lines.iter().enumerate() {
        let line = i as u64 + 1;
        if raw.trim().is_empty() {
            continue;
        }
        log.lines = line;
        let l = raw.trim();
        if !l.starts_with('$') {
            log.garble(Garbled { line, field: None, reason: format!("not a $ message: {:?}", shorten(l)) });
            continue;
        }
        if let Some(p) = l[1..].find('$') {
            log.garble(Garbled {
                line,
                field: None,
                reason: format!("two messages on one line (a second `$` at column {})", p + 2),
            });
            continue;
        }
        let kind = l.split(',').next().unwrap_or(l);
        if kind != "$CH" {
            *log.messages.entry(kind.to_string()).or_default() += 1;
            if kind == "$LOG" && l.contains(",START ") {
                read_start(l, &mut log);
            }
            continue;
        }
        match parse_ch(l, line, ch_fields) {
            Ok(r) => {
                *log.messages.entry("$CH".into()).or_default() += 1;
                log.records.push(r);
            }
            Err(g) => log.garble(g),
        }
    }
    if log.records.is_empty() {
        let first = lines.iter().find(|l| !l.trim().is_empty()).map_or("", |l| l.trim());
        return Err(PocketSdrError::NoChannelLines {
            file: file.into(),
            lines: log.lines,
            first: shorten(first),
            garbled: log.garbled.first().map_or(String::new(), |g| format!("; first garbled $CH line: {g}")),
        });
    }
    Ok(log)
}

fn shorten(s: &str) -> String {
    if s.chars().count() > 60 { format!("{}…", s.chars().take(60).collect::<String>()) } else { s.to_string() }
}

/// `FS=2.000` (MHz) and `VER=0.17` of the START message.
fn read_start(l: &str, log: &mut PocketSdrLog) {
    for word in l.split([' ', ',']) {
        if let Some(v) = word.strip_prefix("FS=") {
            log.fs_hz = v.parse::<f64>().ok().filter(|v| v.is_finite() && *v > 0.0).map(|v| v * 1e6);
        } else if let Some(v) = word.strip_prefix("VER=") {
            log.version = Some(v.to_string());
        }
    }
}

fn parse_ch(l: &str, line: u64, ch_fields: usize) -> Result<ChRecord, Garbled> {
    let f: Vec<&str> = l.split(',').collect();
    if f.len() != ch_fields || f.len() < CH_FIELDS_MIN {
        let reason = format!(
            "{} fields where the log's $CH lines have {ch_fields}{}",
            f.len(),
            if f.len() < ch_fields { " (cut short)" } else { "" }
        );
        return Err(Garbled { line, field: None, reason });
    }
    let name = |i: usize| CH_FIELD_NAMES.get(i).copied().unwrap_or("?");
    let bad = |i: usize, what: &str| Garbled { line, field: Some((i, name(i))), reason: format!("{:?} {what}", f[i]) };
    let num = |i: usize| -> Result<f64, Garbled> {
        match f[i].trim().parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            Ok(_) => Err(bad(i, "is not finite")),
            Err(_) => Err(bad(i, "is not a number")),
        }
    };
    let int = |i: usize| -> Result<u32, Garbled> { f[i].trim().parse::<u32>().map_err(|_| bad(i, "is not a count")) };
    let text = |i: usize| -> Result<String, Garbled> {
        let s = f[i].trim();
        if !s.is_empty() && s.chars().all(|c| c.is_ascii_alphanumeric() || "+-_".contains(c)) {
            Ok(s.to_string())
        } else {
            Err(bad(i, "is not an identifier"))
        }
    };
    let time_s = num(1)?;
    if time_s < 0.0 {
        return Err(bad(1, "is negative"));
    }
    let lock_s = num(7)?;
    if lock_s < 0.0 {
        return Err(bad(7, "is negative"));
    }
    let err_phas_cyc = num(17)?;
    // A Costas discriminator lies in ±1/4 cycle.
    if err_phas_cyc.abs() > 0.25 + 1e-3 {
        return Err(bad(17, "is outside the Costas discriminator's ±0.25 cycle"));
    }
    Ok(ChRecord {
        line,
        time_s,
        ch: int(2)?,
        sat: text(4)?,
        sig: text(5)?,
        prn: int(6)?,
        lock_s,
        cn0_dbhz: num(8)?,
        dop_hz: num(10)?,
        adr_cyc: num(11)?,
        err_phas_cyc,
        nlol: if f.len() > 25 { Some(int(25)?) } else { None },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const A: &str =
        "$CH,5.000,1,1,G31,L1CA,31,4.981,44.2,0.358253518,165.638,827.580,0,0,0,0,0,0.033,0.024,0,-1,0,0,0,0,0,0";

    #[test]
    fn reads_a_ch_line_by_its_fields() {
        let log = parse_log(format!("{A}\n").as_bytes(), "t.log").unwrap();
        let r = &log.records[0];
        assert_eq!((r.line, r.ch, r.prn, r.sat.as_str(), r.sig.as_str()), (1, 1, 31, "G31", "L1CA"));
        assert_eq!((r.time_s, r.lock_s, r.cn0_dbhz, r.dop_hz, r.err_phas_cyc), (5.0, 4.981, 44.2, 165.638, 0.033));
        assert_eq!(r.nlol, Some(0));
        assert_eq!(log.ch_fields, CH_FIELDS_V017);
    }

    #[test]
    fn merged_cut_and_damaged_lines_are_reported_not_read() {
        let cut = &A[..60];
        let merged = format!("{}{}", &A[..40], A);
        let damaged = A.replace(",0.033,", ",0.0x3,");
        let text = format!("{A}\n{cut}\n{merged}\n{damaged}\ngarbage\n$LOG,0.1,L1CA,31,SIGNAL FOUND\n{A}\n");
        let log = parse_log(text.as_bytes(), "t.log").unwrap();
        assert_eq!(log.records.len(), 2);
        assert_eq!(log.garbled_count, 4);
        let g: Vec<String> = log.garbled.iter().map(|g| g.to_string()).collect();
        assert!(g[0].starts_with("line 2: ") && g[0].contains("cut short"), "{g:?}");
        assert!(g[1].starts_with("line 3: ") && g[1].contains("two messages"), "{g:?}");
        assert!(g[2].starts_with("line 4: field 17 (err_phas)") && g[2].contains("not a number"), "{g:?}");
        assert!(g[3].starts_with("line 5: ") && g[3].contains("not a $ message"), "{g:?}");
        assert_eq!(log.messages["$LOG"], 1);
    }

    #[test]
    fn empty_and_foreign_files_are_errors_naming_the_file() {
        let e = parse_log(b"", "e.log").unwrap_err().to_string();
        assert!(e.starts_with("e.log: empty log"), "{e}");
        let e = parse_log(b"t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad\n0,1,2,3,,0\n", "t.csv").unwrap_err();
        let e = e.to_string();
        assert!(e.starts_with("t.csv: no readable $CH line in 2 lines") && e.contains("t_s,channel"), "{e}");
    }
}
