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

use crate::loop_free::{InputPhases, TrackInputPhase};
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
    /// half-cycle change, a clock jump.
    pub rows_left_out: usize,
}

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
    match record {
        ObservationRecord::CarrierPhase if with_phase == 0 => {
            return Err(ObservationRowsError::Missing { source_name, what: "a carrier phase" });
        }
        ObservationRecord::Doppler if with_doppler == 0 => {
            return Err(ObservationRowsError::Missing { source_name, what: "a Doppler" });
        }
        _ => {}
    }
    let epochs = common_epochs(log);
    if epochs.len() < 3 {
        return Err(ObservationRowsError::TooFewEpochs { source_name, epochs: epochs.len() });
    }
    let mut values: Vec<Vec<Option<f64>>> = log
        .tracks
        .iter()
        .map(|t| match record {
            ObservationRecord::Doppler => doppler_rows(t, &epochs),
            _ => phase_rows(t, &epochs),
        })
        .collect();
    let mut jumps = vec![false; epochs.len()];
    if record == ObservationRecord::CarrierPhase {
        for event in &log.clock_events {
            if let Some(k) = epochs.iter().position(|&t| t >= event.t_s) {
                jumps[k] = true;
            }
        }
        let scales: Vec<f64> = log.tracks.iter().map(|t| t.carrier.scale_to_l1()).collect();
        for k in common_steps(&values, &scales) {
            jumps[k] = true;
        }
        for track in &mut values {
            for (v, _) in track.iter_mut().zip(&jumps).filter(|(_, j)| **j) {
                *v = None;
            }
        }
    }
    let tracks = log
        .tracks
        .iter()
        .zip(&values)
        .map(|(t, v)| {
            let rows = v.iter().filter(|v| v.is_some()).count();
            ObservationTrack {
                label: t.label(),
                carrier_hz: t.carrier.carrier_hz,
                mean_cn0_dbhz: mean_finite(&t.cn0_dbhz),
                epochs: t.len(),
                rows,
                rows_left_out: t.len().saturating_sub(rows),
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
    let mut e = 0;
    for (i, &t) in track.t_s.iter().enumerate() {
        while e < epochs.len() && epochs[e] < t {
            e += 1;
        }
        if e < epochs.len() && epochs[e] == t {
            at[e] = Some(i);
        }
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
