//! A carrier phase and Doppler log (RINEX, UBX RXM-RAWX: a
//! [`gsens_io::ObservationLog`]) as rows of the NCO's frequency on common
//! epochs, for the estimate with the receiver's loop identified
//! ([`crate::estimate_nco_frequency_identified_from`]).
//!
//! Signs (docs/conventions.md, "Carrier phase and Doppler logs"): the
//! formats give the Doppler D positive for an approaching satellite and a
//! carrier phase L that changes like the range, d L/dt ≈ −D. A receiver's
//! Doppler is its carrier NCO's frequency, and its carrier phase minus the
//! NCO's accumulated phase, so that
//!
//! ```text
//! f_NCO,k = D_k                                  (Doppler rows)
//! f̄_NCO,k = −(L_k − L_{k−1}) / (t_k − t_{k−1})     (carrier phase rows)
//! ```
//!
//! the second the NCO's mean frequency over the interval
//! ([`gsens_core::RowQuantity::NcoFrequencyMean`]). Either carries the
//! satellite's Doppler, which each track's segments detrend, and the
//! oscillator's frequency error through the loop, −H\[aᵀΓ\], common to every
//! track once scaled to L1 (f_L1/f_c; GLONASS per frequency channel).
//!
//! A carrier phase row is left out where either end is invalid, where the
//! format flags a loss of lock at its end, where a half cycle was
//! subtracted at one end and not the other, or where the receiver's clock
//! jumped within it: at a clock event the log reports, and at a step of
//! the tracks' common mode no oscillator makes (a millisecond clock jump
//! moves every phase by about 1.6·10⁶ cycles).

use crate::loop_free::{InputPhases, TrackInputPhase, rows_on_epochs};
use gsens_core::RowQuantity;
use gsens_io::{ObservationLog, SatelliteSeries, obs_flags};
use serde::{Deserialize, Serialize};

/// Which observable of the log the rows are made of.
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[cfg_attr(feature = "clap", value(rename_all = "snake_case"))]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
#[non_exhaustive]
pub enum ObservationRecord {
    /// The carrier phase where most tracks have one, else the Doppler.
    #[default]
    Auto,
    /// The carrier phase differenced between epochs: the NCO's mean
    /// frequency over each interval, its thermal noise averaged over the
    /// interval's updates.
    CarrierPhase,
    /// The Doppler: the NCO's frequency, read as the command in force at
    /// the epoch's latest loop update.
    Doppler,
}

impl ObservationRecord {
    /// Its name in the result document.
    pub const fn name(self) -> &'static str {
        match self {
            ObservationRecord::Auto => "auto",
            ObservationRecord::CarrierPhase => "carrier_phase",
            ObservationRecord::Doppler => "doppler",
        }
    }

    /// The row quantity a resolved record's rows hold.
    pub const fn quantity(self) -> RowQuantity {
        match self {
            ObservationRecord::Doppler => RowQuantity::NcoFrequency,
            _ => RowQuantity::NcoFrequencyMean,
        }
    }
}

/// A step of the tracks' common mode between consecutive rows above this
/// \[Hz at L1\] is a receiver clock jump, not the oscillator: a
/// g-sensitivity of 1 ppb/g (0.16 Hz/(m/s²) at L1, far above a crystal's) on
/// a 100 m/s² change of specific force moves it by 16 Hz, a clock jump of
/// 1 µs over a 0.1 s interval by 16 kHz.
pub const CLOCK_STEP_HZ: f64 = 1000.0;

/// What became of one track of the log.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[non_exhaustive]
pub struct ObservationTrack {
    /// The signal's label ([`SatelliteSeries::label`]).
    pub label: String,
    /// Its carrier \[Hz\].
    pub carrier_hz: f64,
    /// Its mean C/N0 \[dB-Hz\] (NaN-free: 0 where the log gives none).
    pub mean_cn0_dbhz: f64,
    /// Epochs of the track in the log.
    pub epochs: usize,
    /// Rows it gives (on the common epochs).
    pub rows: usize,
    /// Rows left out: an observable invalid or absent, a loss of lock or a
    /// half-cycle change, a clock jump, a slip no flag marked.
    pub rows_left_out: usize,
    /// Rows at which the track alone stepped by a half cycle or more with
    /// no flag set (a one-row spike of half a cycle against the other
    /// tracks; docs/conventions.md, "Carrier phase and Doppler logs").
    pub half_cycle_slips: usize,
    /// Whether the whole track was left out for slipping again and again
    /// (more than [`SLIPPING_TRACK_SLIPS`] slips and
    /// [`SLIPPING_TRACK_SHARE`] of its rows): a false lock or a carrier too
    /// weak to hold.
    pub left_out: bool,
}

/// A track with more slips than this (and more than
/// [`SLIPPING_TRACK_SHARE`] of its rows) is left out whole.
pub const SLIPPING_TRACK_SLIPS: usize = 3;
/// See [`SLIPPING_TRACK_SLIPS`].
pub const SLIPPING_TRACK_SHARE: f64 = 0.01;

/// The rows of a log and how they were made.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct ObservationRows {
    /// Each track's NCO frequency on the common epochs \[Hz at its carrier\].
    pub rows: InputPhases,
    /// The record the rows are made of (never [`ObservationRecord::Auto`]).
    pub record: ObservationRecord,
    /// Every track, in the log's order.
    pub tracks: Vec<ObservationTrack>,
    /// Epochs whose rows were left out for a receiver clock jump.
    pub clock_jump_epochs: usize,
}

/// Why a log gives no rows.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ObservationRowsError {
    /// No track holds the record asked for.
    #[error("{source_name}: no track has {what}")]
    Missing {
        /// The log's name.
        source_name: String,
        /// What is missing.
        what: &'static str,
    },
    /// Fewer than three epochs on a uniform grid.
    #[error("{source_name}: {epochs} epoch(s): too few for an estimate")]
    TooFewEpochs {
        /// The log's name.
        source_name: String,
        /// Epochs read.
        epochs: usize,
    },
}

/// The rows of `log` from `record` (module documentation).
pub fn observation_rows(
    log: &ObservationLog,
    record: ObservationRecord,
) -> Result<ObservationRows, ObservationRowsError> {
    let has = |t: &SatelliteSeries, phase: bool| {
        let column = if phase { &t.carrier_phase_cycles } else { &t.doppler_hz };
        column.iter().filter(|v| v.is_finite()).count() >= 3
    };
    let with_phase = log.tracks.iter().filter(|t| has(t, true)).count();
    let with_doppler = log.tracks.iter().filter(|t| has(t, false)).count();
    let record = match record {
        ObservationRecord::Auto if 2 * with_phase >= log.tracks.len() && with_phase > 0 => {
            ObservationRecord::CarrierPhase
        }
        ObservationRecord::Auto => ObservationRecord::Doppler,
        r => r,
    };
    let source_name = log.source_name.clone();
    let epochs = common_epochs(log);
    if epochs.len() < 3 {
        return Err(ObservationRowsError::TooFewEpochs { source_name, epochs: epochs.len() });
    }
    match record {
        ObservationRecord::CarrierPhase if with_phase == 0 => {
            return Err(ObservationRowsError::Missing { source_name, what: "a carrier phase" });
        }
        ObservationRecord::Doppler if with_doppler == 0 => {
            return Err(ObservationRowsError::Missing { source_name, what: "a Doppler" });
        }
        _ => {}
    }
    let mut values: Vec<Vec<Option<f64>>> = log
        .tracks
        .iter()
        .map(|t| match record {
            ObservationRecord::Doppler => doppler_rows(t, &epochs),
            _ => phase_rows(t, &epochs),
        })
        .collect();
    let scales: Vec<f64> = log.tracks.iter().map(|t| t.carrier.scale_to_l1()).collect();
    let mut jumps = vec![false; epochs.len()];
    if record == ObservationRecord::CarrierPhase {
        for event in &log.clock_events {
            if let Some(k) = epochs.iter().position(|&t| t >= event.t_s) {
                jumps[k] = true;
            }
        }
        for k in common_steps(&values, &scales) {
            jumps[k] = true;
        }
        for track in &mut values {
            for (v, _) in track.iter_mut().zip(&jumps).filter(|(_, j)| **j) {
                *v = None;
            }
        }
    }
    let mut slips = vec![0usize; values.len()];
    let mut slipping = vec![false; values.len()];
    if record == ObservationRecord::CarrierPhase {
        for (j, flagged) in half_cycle_slips(&values, &scales, &epochs).into_iter().enumerate() {
            slips[j] = flagged.len();
            for k in flagged {
                values[j][k] = None;
            }
            let rows = values[j].iter().filter(|v| v.is_some()).count();
            // A track that slips again and again (a false lock, a weak carrier) is no single slip.
            slipping[j] = slips[j] > SLIPPING_TRACK_SLIPS && slips[j] as f64 > SLIPPING_TRACK_SHARE * rows as f64;
            if slipping[j] {
                values[j].iter_mut().for_each(|v| *v = None);
            }
        }
    }
    let tracks = log
        .tracks
        .iter()
        .zip(&values)
        .enumerate()
        .map(|(j, (t, v))| {
            let rows = v.iter().filter(|v| v.is_some()).count();
            ObservationTrack {
                label: t.label(),
                carrier_hz: t.carrier.carrier_hz,
                mean_cn0_dbhz: mean_finite(&t.cn0_dbhz),
                epochs: t.len(),
                rows,
                rows_left_out: t.len().saturating_sub(rows),
                half_cycle_slips: slips[j],
                left_out: slipping[j],
            }
        })
        .collect::<Vec<_>>();
    let rows = InputPhases {
        epoch_t_s: epochs,
        tracks: log
            .tracks
            .iter()
            .zip(values)
            .zip(&tracks)
            .map(|((t, v), summary)| TrackInputPhase {
                input_phase_rad: v,
                scale_to_l1: t.carrier.scale_to_l1(),
                mean_cn0_dbhz: summary.mean_cn0_dbhz,
            })
            .collect(),
    };
    Ok(ObservationRows { rows, record, tracks, clock_jump_epochs: jumps.iter().filter(|&&j| j).count() })
}

/// Every epoch of the log, ascending (the receiver's epochs are common to
/// its tracks).
fn common_epochs(log: &ObservationLog) -> Vec<f64> {
    let mut t: Vec<f64> = log.tracks.iter().flat_map(|s| s.t_s.iter().copied()).collect();
    t.sort_by(f64::total_cmp);
    t.dedup();
    t
}

/// The mean of the finite values (0 where none is).
fn mean_finite(x: &[f64]) -> f64 {
    let (sum, n) = x.iter().filter(|v| v.is_finite()).fold((0.0, 0usize), |(s, n), v| (s + v, n + 1));
    if n == 0 { 0.0 } else { sum / n as f64 }
}

/// The track's index at each epoch (`None` where it has no observation).
fn on_epochs(track: &SatelliteSeries, epochs: &[f64]) -> Vec<Option<usize>> {
    let mut at = vec![None; epochs.len()];
    for (i, e) in rows_on_epochs(&track.t_s, epochs) {
        at[e] = Some(i);
    }
    at
}

/// The Doppler at each epoch.
fn doppler_rows(track: &SatelliteSeries, epochs: &[f64]) -> Vec<Option<f64>> {
    on_epochs(track, epochs).into_iter().map(|i| i.map(|i| track.doppler_hz[i]).filter(|d| d.is_finite())).collect()
}

/// The carrier phase differenced from the previous epoch, −ΔL/Δt, where
/// both ends are valid and nothing between them broke the phase.
fn phase_rows(track: &SatelliteSeries, epochs: &[f64]) -> Vec<Option<f64>> {
    let at = on_epochs(track, epochs);
    let phase_ok =
        |i: usize| track.carrier_phase_cycles[i].is_finite() && track.flags[i] & obs_flags::PHASE_INVALID == 0;
    let half = |i: usize| track.flags[i] & obs_flags::HALF_CYCLE_SUBTRACTED;
    (0..epochs.len())
        .map(|k| {
            let (Some(i0), Some(i1)) = (k.checked_sub(1).and_then(|k0| at[k0]), at[k]) else { return None };
            let broken = track.flags[i1] & obs_flags::LOSS_OF_LOCK != 0 || half(i0) != half(i1);
            (phase_ok(i0) && phase_ok(i1) && !broken).then(|| {
                -(track.carrier_phase_cycles[i1] - track.carrier_phase_cycles[i0]) / (epochs[k] - epochs[k - 1])
            })
        })
        .collect()
}

/// Each track's rows at which its phase alone stepped by a half cycle or
/// more with no flag set: a slip of the carrier phase is a one-row spike of
/// 1/(2Δt) Hz on the track's own carrier in its differenced phase. The
/// test takes each row less the mean of its two neighbours (the
/// satellite's Doppler is smooth), scaled to L1, less the median of that
/// over the tracks present (the oscillator's common mode), and flags it
/// beyond 0.7 of the slip's spike (a spike's neighbours show half of it).
/// Needs three tracks at the epoch.
fn half_cycle_slips(values: &[Vec<Option<f64>>], scales: &[f64], epochs: &[f64]) -> Vec<Vec<usize>> {
    let n = epochs.len();
    let mut flagged = vec![Vec::new(); values.len()];
    let mut d = vec![None; values.len()];
    for k in 1..n.saturating_sub(1) {
        for (j, v) in values.iter().enumerate() {
            d[j] = match (v[k - 1], v[k], v[k + 1]) {
                (Some(a), Some(b), Some(c)) => Some((b - 0.5 * (a + c)) * scales[j]),
                _ => None,
            };
        }
        let mut present: Vec<f64> = d.iter().flatten().copied().collect();
        if present.len() < 3 {
            continue;
        }
        let common = gsens_core::stats::median_in_place(&mut present);
        let step_s = 0.5 * (epochs[k + 1] - epochs[k - 1]);
        for (j, dj) in d.iter().enumerate() {
            if dj.is_some_and(|dj| (dj - common).abs() > 0.7 * 0.5 / step_s * scales[j]) {
                flagged[j].push(k);
            }
        }
    }
    flagged
}

/// The epochs at which the tracks' common mode steps by more than
/// [`CLOCK_STEP_HZ`]: the median over the tracks present at both epochs of
/// their row's change, scaled to L1.
fn common_steps(values: &[Vec<Option<f64>>], scales: &[f64]) -> Vec<usize> {
    let n = values.first().map_or(0, Vec::len);
    (1..n)
        .filter(|&k| {
            let mut steps: Vec<f64> =
                values.iter().zip(scales).filter_map(|(v, s)| Some((v[k]? - v[k - 1]?) * s)).collect();
            gsens_core::stats::median_in_place(&mut steps).abs() > CLOCK_STEP_HZ
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use gsens_io::{Carrier, ClockEvent, Observation, ObservationLogBuilder, Signal};

    /// A log of `tracks` satellites at 10 Hz for `n` epochs: track j's phase
    /// L = N_j − ∫f dt with f = 1000·j + 2·t Hz (its Doppler D = f), exact.
    fn log(tracks: usize, n: usize, edit: impl Fn(usize, usize, &mut Observation)) -> ObservationLog {
        let mut b = ObservationLogBuilder::new("t.rnx", "RINEX 3.04");
        for k in 0..n {
            let t = b.start_epoch(2300, 1000.0 + k as f64 * 0.1, || format!("epoch {k}")).unwrap();
            for j in 0..tracks {
                let tk = k as f64 * 0.1;
                let f0 = 1000.0 * (j + 1) as f64;
                let mut obs = Observation {
                    carrier_phase_cycles: 2.0e7 - (f0 * tk + tk * tk),
                    doppler_hz: f0 + 2.0 * tk,
                    cn0_dbhz: 40.0 + j as f64,
                    ..Observation::default()
                };
                edit(j, k, &mut obs);
                b.push(&format!("G{:02}", j + 1), "1C", Carrier::of(Signal::L1CA), t, &obs);
            }
        }
        b.finish()
    }

    /// The carrier phase differenced is the mean frequency over the interval
    /// with the NCO's sign (−ΔL/Δt), the Doppler the frequency itself; the
    /// first epoch has no phase row.
    #[test]
    fn rows_are_the_nco_frequency_with_its_sign() {
        let l = log(3, 20, |_, _, _| {});
        let r = observation_rows(&l, ObservationRecord::Auto).unwrap();
        assert_eq!(r.record, ObservationRecord::CarrierPhase);
        assert_eq!(r.record.quantity(), RowQuantity::NcoFrequencyMean);
        let t = &r.rows.epoch_t_s;
        assert_eq!(t.len(), 20);
        assert_eq!(r.rows.tracks[1].input_phase_rad[0], None);
        for k in 1..20 {
            // Mean of 2000 + 2t over [t_{k−1}, t_k].
            let want = 2000.0 + (t[k] + t[k - 1]) - 2.0 * t[0];
            let got = r.rows.tracks[1].input_phase_rad[k].unwrap();
            assert!((got - want).abs() < 1e-6, "{k}: {got} against {want}");
        }
        let d = observation_rows(&l, ObservationRecord::Doppler).unwrap();
        assert_eq!(d.record.quantity(), RowQuantity::NcoFrequency);
        assert!((d.rows.tracks[2].input_phase_rad[5].unwrap() - (3000.0 + 2.0 * 0.5)).abs() < 1e-9);
        assert_eq!((r.tracks[0].rows, r.tracks[0].rows_left_out, r.clock_jump_epochs), (19, 1, 0));
        assert_eq!((r.tracks[2].mean_cn0_dbhz, r.rows.tracks[0].scale_to_l1), (42.0, 1.0));
    }

    /// A loss of lock, a half cycle subtracted at one end only and an
    /// invalid phase break the row they end or start.
    #[test]
    fn slips_and_invalid_phases_leave_their_rows_out() {
        let l = log(2, 30, |j, k, o| {
            if j == 0 && k >= 10 {
                o.flags |= if k == 10 { obs_flags::LOSS_OF_LOCK } else { 0 };
                o.carrier_phase_cycles += 17.0;
            }
            if j == 0 && k >= 20 {
                o.flags |= obs_flags::HALF_CYCLE_SUBTRACTED;
                o.carrier_phase_cycles += 0.5;
            }
            if j == 1 && k == 5 {
                o.flags |= obs_flags::PHASE_INVALID;
                o.carrier_phase_cycles = f64::NAN;
            }
        });
        let r = observation_rows(&l, ObservationRecord::CarrierPhase).unwrap();
        let none =
            |j: usize| -> Vec<usize> { (0..30).filter(|&k| r.rows.tracks[j].input_phase_rad[k].is_none()).collect() };
        assert_eq!(none(0), [0, 10, 20]);
        assert_eq!(none(1), [0, 5, 6]);
        // Every row that is kept is the clean frequency.
        assert!(r.rows.tracks[0].input_phase_rad.iter().flatten().all(|f| (f - 1000.0).abs() < 10.0));
    }

    /// A half-cycle slip no flag marks is found against the other tracks
    /// and its row left out; a track that slips every few seconds (a false
    /// lock) is left out whole.
    #[test]
    fn unflagged_slips_and_slipping_tracks_are_found() {
        let l = log(4, 300, |j, k, o| {
            if j == 1 && k >= 110 {
                o.carrier_phase_cycles += 0.5;
            }
            if j == 3 {
                o.carrier_phase_cycles += 0.5 * (k / 20) as f64;
            }
        });
        let r = observation_rows(&l, ObservationRecord::CarrierPhase).unwrap();
        let slips: Vec<(usize, bool)> = r.tracks.iter().map(|t| (t.half_cycle_slips, t.left_out)).collect();
        assert_eq!(slips, [(0, false), (1, false), (0, false), (14, true)]);
        assert!(r.rows.tracks[1].input_phase_rad[110].is_none() && r.rows.tracks[1].input_phase_rad[111].is_some());
        assert!(r.rows.tracks[3].input_phase_rad.iter().all(Option::is_none));
        assert_eq!(r.tracks[0].rows, 299);
    }

    /// A millisecond jump of the receiver clock moves every phase by
    /// f_L1·1 ms: the common step leaves that epoch's rows out of every track
    /// (and the one after, where the step comes back), reported or not; the
    /// Doppler, a frequency, is kept.
    #[test]
    fn a_receiver_clock_jump_leaves_its_epoch_out() {
        let jump = gsens_core::units::GPS_L1_HZ * 1e-3;
        let l = log(4, 40, |_, k, o| {
            if k >= 25 {
                o.carrier_phase_cycles += jump;
            }
        });
        let r = observation_rows(&l, ObservationRecord::CarrierPhase).unwrap();
        assert_eq!(r.clock_jump_epochs, 2);
        for tr in &r.rows.tracks {
            assert!(tr.input_phase_rad[25].is_none() && tr.input_phase_rad[26].is_none());
            assert!(tr.input_phase_rad.iter().flatten().all(|f| f.abs() < 5000.0));
        }
        let mut reported = l.clone();
        reported.clock_events.push(ClockEvent { t_s: l.tracks[0].t_s[10], jump_s: None, what: "clkReset".into() });
        let r = observation_rows(&reported, ObservationRecord::CarrierPhase).unwrap();
        assert_eq!(r.clock_jump_epochs, 3);
        assert!(r.rows.tracks.iter().all(|tr| tr.input_phase_rad[10].is_none()));
        let d = observation_rows(&reported, ObservationRecord::Doppler).unwrap();
        assert_eq!(d.clock_jump_epochs, 0);
    }

    /// A log without the record asked for, or with too few epochs, is refused by name.
    #[test]
    fn a_log_without_the_record_is_refused() {
        let no_phase = log(2, 10, |_, _, o| o.carrier_phase_cycles = f64::NAN);
        let e = observation_rows(&no_phase, ObservationRecord::CarrierPhase).unwrap_err();
        assert_eq!(e.to_string(), "t.rnx: no track has a carrier phase");
        assert_eq!(observation_rows(&no_phase, ObservationRecord::Auto).unwrap().record, ObservationRecord::Doppler);
        let e = observation_rows(&log(2, 2, |_, _, _| {}), ObservationRecord::Auto).unwrap_err();
        assert_eq!(e.to_string(), "t.rnx: 2 epoch(s): too few for an estimate");
    }
}
