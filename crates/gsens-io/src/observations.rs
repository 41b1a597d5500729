//! The crate documentation's section "Carrier phase and Doppler logs" describes this module.

use std::collections::HashMap;
use std::fmt;

use crate::signal::Carrier;

/// Seconds in a GPS week.
pub const GPS_WEEK_S: f64 = 604_800.0;

/// Bits of [`SatelliteSeries::flags`]: what the format says about one
/// observation's lock and phase.
pub mod obs_flags {
    /// Loss of lock since the previous observation of the track: the phase may
    /// have slipped by whole cycles. RINEX: LLI bit 0. UBX RXM-RAWX, which has no
    /// such bit: set where `locktime` fell below its previous value on the track
    /// or the phase turned valid again after an invalid epoch.
    pub const LOSS_OF_LOCK: u8 = 0x01;
    /// The half-cycle ambiguity is unresolved, or a half-cycle slip is possible.
    /// RINEX: LLI bit 1. UBX: `trkStat` bit 2 (`halfCyc`, half cycle valid) clear.
    pub const HALF_CYCLE_AMBIGUOUS: u8 = 0x02;
    /// RINEX: LLI bit 2, the satellite was under anti-spoofing (GPS) or, in
    /// RINEX 3, the observation was made on a BOC-tracking mode.
    pub const ANTI_SPOOFING: u8 = 0x04;
    /// UBX: `trkStat` bit 3 (`subHalfCyc`), a half cycle was subtracted from the phase.
    pub const HALF_CYCLE_SUBTRACTED: u8 = 0x08;
    /// The carrier phase is not valid (UBX: `trkStat` bit 1, `cpValid`, clear);
    /// the phase value is then NaN. RINEX has no such bit: a blank phase field
    /// is NaN with this bit set.
    pub const PHASE_INVALID: u8 = 0x10;
    /// The pseudorange is not valid (UBX: `trkStat` bit 0, `prValid`, clear;
    /// RINEX: a blank field); the value is then NaN.
    pub const PSEUDORANGE_INVALID: u8 = 0x20;
}

/// One signal of one satellite over a log: the observables as the file states
/// them, column-wise, one entry per epoch in which the file holds the signal.
///
/// Units and signs are the format's (docs/conventions.md, "Carrier phase and
/// Doppler logs"): RINEX and UBX RXM-RAWX alike give the Doppler positive for
/// an approaching satellite and a carrier phase that changes like the
/// pseudorange, so that d(phase)/dt ≈ −Doppler for a receiver that keeps
/// time; the reader changes neither.
#[derive(Debug, Clone, PartialEq)]
pub struct SatelliteSeries {
    /// The satellite as RINEX names it: system letter and two-digit number
    /// (`G05`, `R12`, `E11`, `C20`, `J02`, `S23`, `I05`).
    pub sv: String,
    /// The RINEX 3 observation code of the signal: band and attribute (`1C`,
    /// `2L`, `5Q`); a UBX signal is named by its RINEX equivalent.
    pub code: String,
    /// The carrier: the signal of [`crate::SIGNALS`] where it is in the table
    /// (GLONASS with its frequency channel k), else the frequency alone.
    pub carrier: Carrier,
    /// Epoch times \[s\]: GPS time in seconds of the GPS week of the log's
    /// first epoch ([`ObservationLog::gps_week`]), continuing past the week's
    /// end (t = (week − first week)·604800 s + time of week). Strictly
    /// increasing. The receiver's epoch as the file states it (receiver time,
    /// which a receiver steers close to GPS time).
    pub t_s: Vec<f64>,
    /// Pseudorange \[m\]; NaN where absent or invalid.
    pub pseudorange_m: Vec<f64>,
    /// Accumulated carrier phase \[cycles\]; NaN where absent or invalid.
    pub carrier_phase_cycles: Vec<f64>,
    /// Doppler \[Hz\], positive for an approaching satellite; NaN where absent.
    pub doppler_hz: Vec<f64>,
    /// Carrier-to-noise density \[dB-Hz\]; NaN where absent.
    pub cn0_dbhz: Vec<f64>,
    /// Bits of [`obs_flags`] per epoch.
    pub flags: Vec<u8>,
    /// RINEX's signal strength indicator of the phase (1 … 9, 0 where the file
    /// leaves it blank); empty for a format without it.
    pub strength: Vec<u8>,
    /// Time the carrier has been tracked without a slip \[s\] (UBX `locktime`,
    /// capped by the receiver at 64.5 s); empty for a format without it.
    pub lock_time_s: Vec<f64>,
}

impl SatelliteSeries {
    /// An empty series of `sv`'s signal `code` on `carrier`.
    pub fn new(sv: &str, code: &str, carrier: Carrier) -> SatelliteSeries {
        SatelliteSeries {
            sv: sv.to_owned(),
            code: code.to_owned(),
            carrier,
            t_s: Vec::new(),
            pseudorange_m: Vec::new(),
            carrier_phase_cycles: Vec::new(),
            doppler_hz: Vec::new(),
            cn0_dbhz: Vec::new(),
            flags: Vec::new(),
            strength: Vec::new(),
            lock_time_s: Vec::new(),
        }
    }

    /// Number of epochs.
    pub fn len(&self) -> usize {
        self.t_s.len()
    }

    /// `true` when the series holds no epoch.
    pub fn is_empty(&self) -> bool {
        self.t_s.is_empty()
    }

    /// Appends one epoch's observation. `strength` and `lock_time_s` are kept
    /// only by a series whose format has them: pass `None` throughout otherwise.
    pub fn push(&mut self, t_s: f64, obs: &Observation) {
        self.t_s.push(t_s);
        self.pseudorange_m.push(obs.pseudorange_m);
        self.carrier_phase_cycles.push(obs.carrier_phase_cycles);
        self.doppler_hz.push(obs.doppler_hz);
        self.cn0_dbhz.push(obs.cn0_dbhz);
        self.flags.push(obs.flags);
        if let Some(s) = obs.strength {
            self.strength.push(s);
        }
        if let Some(l) = obs.lock_time_s {
            self.lock_time_s.push(l);
        }
    }

    /// The signal's label: `G05 1C (L1CA)`, `R12 1C (G1:-4)`.
    pub fn label(&self) -> String {
        format!("{} {} ({})", self.sv, self.code, self.carrier.label())
    }
}

/// One observation of one signal at one epoch, as [`SatelliteSeries::push`] takes it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Observation {
    /// Pseudorange \[m\] (NaN: absent).
    pub pseudorange_m: f64,
    /// Carrier phase \[cycles\] (NaN: absent).
    pub carrier_phase_cycles: f64,
    /// Doppler \[Hz\] (NaN: absent).
    pub doppler_hz: f64,
    /// C/N0 \[dB-Hz\] (NaN: absent).
    pub cn0_dbhz: f64,
    /// Bits of [`obs_flags`].
    pub flags: u8,
    /// RINEX's signal strength indicator, for formats with one.
    pub strength: Option<u8>,
    /// Lock time \[s\], for formats with one.
    pub lock_time_s: Option<f64>,
}

impl Default for Observation {
    fn default() -> Self {
        Observation {
            pseudorange_m: f64::NAN,
            carrier_phase_cycles: f64::NAN,
            doppler_hz: f64::NAN,
            cn0_dbhz: f64::NAN,
            flags: 0,
            strength: None,
            lock_time_s: None,
        }
    }
}

/// Records of a log a reader left out, by reason: how many, and where the first was.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Skipped {
    /// Why, e.g. `epoch flag 4 (header information follows)` or `bad checksum`.
    pub reason: String,
    /// How many records were left out for it.
    pub count: usize,
    /// Where the first was (`line 112`, `byte 4096`), where the reader knows.
    pub first_at: Option<String>,
}

/// A jump of the receiver's clock that a log shows.
#[derive(Debug, Clone, PartialEq)]
pub struct ClockEvent {
    /// Time of the first epoch after the jump \[s\] (as [`SatelliteSeries::t_s`]).
    pub t_s: f64,
    /// The size of the jump \[s\], where the log gives it (a RINEX receiver
    /// clock offset's step); `None` for a bare flag (UBX `recStat` `clkReset`).
    pub jump_s: Option<f64>,
    /// What showed it.
    pub what: String,
}

/// A log of carrier phase and Doppler observations (RINEX observation file,
/// UBX RXM-RAWX messages): every signal of every satellite as a
/// [`SatelliteSeries`], with what the reader skipped and the receiver clock
/// jumps it saw.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ObservationLog {
    /// The source, as in error messages (typically the file name).
    pub source_name: String,
    /// The format and its version, e.g. `RINEX 3.04`, `UBX`.
    pub format: String,
    /// The GPS week of the first epoch: the origin of every `t_s` is this
    /// week's start (Saturday/Sunday midnight, GPS time).
    pub gps_week: u32,
    /// Number of epochs read (an epoch: one receiver time, all its signals).
    pub epochs: usize,
    /// One series per (satellite, signal), in order of first appearance.
    pub tracks: Vec<SatelliteSeries>,
    /// What was left out and why.
    pub skipped: Vec<Skipped>,
    /// Receiver clock jumps seen.
    pub clock_events: Vec<ClockEvent>,
}

impl ObservationLog {
    /// The series of `sv`'s signal `code`, if the log holds it.
    pub fn track(&self, sv: &str, code: &str) -> Option<&SatelliteSeries> {
        self.tracks.iter().find(|t| t.sv == sv && t.code == code)
    }

    /// How many records were skipped, over all reasons.
    pub fn skipped_count(&self) -> usize {
        self.skipped.iter().map(|s| s.count).sum()
    }

    /// Checks the invariants the readers guarantee: every series' columns of
    /// equal length (`strength`, `lock_time_s`: that or empty), times finite
    /// and strictly increasing per series.
    pub fn validate(&self) -> Result<(), String> {
        for t in &self.tracks {
            let n = t.t_s.len();
            let lens = [t.pseudorange_m.len(), t.carrier_phase_cycles.len(), t.doppler_hz.len(), t.cn0_dbhz.len()];
            if lens.iter().any(|&l| l != n) || t.flags.len() != n {
                return Err(format!("{}: columns of unequal length", t.label()));
            }
            if ![0, n].contains(&t.strength.len()) || ![0, n].contains(&t.lock_time_s.len()) {
                return Err(format!("{}: optional columns of the wrong length", t.label()));
            }
            if let Some(i) = (0..n).find(|&i| !t.t_s[i].is_finite() || (i > 0 && t.t_s[i] <= t.t_s[i - 1])) {
                return Err(format!("{}: time stamps not finite and strictly increasing at epoch {i}", t.label()));
            }
        }
        Ok(())
    }
}

/// Builds an [`ObservationLog`] epoch by epoch: turns GPS week and time of week
/// into `t_s`, keeps one series per (satellite, signal) and counts what is
/// skipped by reason. The readers of the formats share it; a clone finished
/// is the log read so far (a stream read as it arrives).
#[derive(Debug, Clone, Default)]
pub struct ObservationLogBuilder {
    log: ObservationLog,
    week0: Option<u32>,
    index: HashMap<(String, String), usize>,
    last_epoch_s: Option<f64>,
}

impl ObservationLogBuilder {
    /// A builder of the log of `source_name` in `format`.
    pub fn new(source_name: &str, format: &str) -> ObservationLogBuilder {
        let log =
            ObservationLog { source_name: source_name.to_owned(), format: format.to_owned(), ..Default::default() };
        ObservationLogBuilder { log, ..Default::default() }
    }

    /// Starts an epoch at GPS `week` and time of week `tow_s` and returns its
    /// `t_s` (seconds since the start of the first epoch's week), or `None`
    /// (the epoch is skipped and counted) when the time does not increase
    /// past the previous epoch's or is not finite. `at` says where the epoch
    /// is in the file, for the skip report.
    pub fn start_epoch(&mut self, week: u32, tow_s: f64, at: impl FnOnce() -> String) -> Option<f64> {
        let week0 = *self.week0.get_or_insert(week);
        let t_s = (f64::from(week) - f64::from(week0)) * GPS_WEEK_S + tow_s;
        if !t_s.is_finite() {
            self.skip("epoch time not finite", at);
            return None;
        }
        if self.last_epoch_s.is_some_and(|last| t_s <= last) {
            self.skip("epoch time not after the previous epoch's", at);
            return None;
        }
        if self.log.epochs == 0 {
            self.log.gps_week = week0;
        }
        self.last_epoch_s = Some(t_s);
        self.log.epochs += 1;
        Some(t_s)
    }

    /// Appends `obs` at `t_s` (from [`Self::start_epoch`]) to the series of
    /// `sv`'s signal `code`, which starts on `carrier` if new. A signal the
    /// epoch already holds, or one on another carrier than its series' (a
    /// GLONASS satellite whose frequency channel changed), is skipped and counted.
    pub fn push(&mut self, sv: &str, code: &str, carrier: Carrier, t_s: f64, obs: &Observation) {
        let key = (sv.to_owned(), code.to_owned());
        let tracks = &mut self.log.tracks;
        let i = *self.index.entry(key).or_insert_with(|| {
            tracks.push(SatelliteSeries::new(sv, code, carrier));
            tracks.len() - 1
        });
        let track = &mut self.log.tracks[i];
        if track.carrier != carrier {
            let reason = format!("{sv} {code} on another carrier than its first ({})", track.carrier.label());
            self.skip(&reason, || format!("t = {t_s} s"));
            return;
        }
        if track.t_s.last().is_some_and(|&last| last >= t_s) {
            let reason = format!("{sv} {code} twice in one epoch (the first kept)");
            self.skip(&reason, || format!("t = {t_s} s"));
            return;
        }
        track.push(t_s, obs);
    }

    /// The GPS week of the first epoch, once an epoch has started.
    pub fn first_week(&self) -> Option<u32> {
        self.week0
    }

    /// Counts one record skipped for `reason`; `at` (called for the first of
    /// a reason only) says where it was.
    pub fn skip(&mut self, reason: &str, at: impl FnOnce() -> String) {
        match self.log.skipped.iter_mut().find(|s| s.reason == reason) {
            Some(s) => s.count += 1,
            None => self.log.skipped.push(Skipped { reason: reason.to_owned(), count: 1, first_at: Some(at()) }),
        }
    }

    /// Records a receiver clock jump.
    pub fn clock_event(&mut self, event: ClockEvent) {
        self.log.clock_events.push(event);
    }

    /// Number of epochs started so far.
    pub fn epochs(&self) -> usize {
        self.log.epochs
    }

    /// How many records were skipped so far, over all reasons.
    pub fn skipped_count(&self) -> usize {
        self.log.skipped_count()
    }

    /// The log.
    pub fn finish(self) -> ObservationLog {
        self.log
    }
}

impl fmt::Display for Skipped {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} × {}", self.count, self.reason)?;
        if let Some(at) = &self.first_at {
            write!(f, " (first at {at})")?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::signal::Signal;

    #[test]
    fn times_continue_past_the_week_and_repeats_are_counted() {
        let mut b = ObservationLogBuilder::new("x.obs", "RINEX 3.04");
        let l1 = Carrier::of(Signal::L1CA);
        let obs = Observation { carrier_phase_cycles: 1.5, ..Default::default() };
        let t0 = b.start_epoch(2300, 604_799.5, || "line 20".into()).unwrap();
        b.push("G05", "1C", l1, t0, &obs);
        let t1 = b.start_epoch(2301, 0.5, || "line 22".into()).unwrap();
        b.push("G05", "1C", l1, t1, &obs);
        b.push("G05", "1C", l1, t1, &obs);
        b.push("G05", "1C", Carrier::of(Signal::new("L5I", None).unwrap()), t1 + 0.1, &obs);
        assert_eq!((t0, t1), (604_799.5, 604_800.5));
        assert!(b.start_epoch(2301, 0.5, || "line 24".into()).is_none());
        let log = b.finish();
        assert_eq!((log.gps_week, log.epochs, log.tracks[0].len()), (2300, 2, 2));
        assert_eq!(log.skipped_count(), 3);
        assert_eq!(log.skipped[1].reason, "G05 1C on another carrier than its first (L1CA)");
        assert_eq!(log.skipped[2].to_string(), "1 × epoch time not after the previous epoch's (first at line 24)");
        assert!(log.validate().is_ok());
        assert_eq!(log.track("G05", "1C").unwrap().label(), "G05 1C (L1CA)");
    }
}
