//! Compensation proven in the loop: one session (one seed) run three times,
//! every noise the same, so that what differs is the oscillator's g-induced
//! frequency error and what the feed-forward leaves of it.
//!
//! 1. the reference: Γ = 0 (the oscillator has no g-sensitivity);
//! 2. uncompensated: the scenario's Γ;
//! 3. compensated: the scenario's Γ with −aᵀΓ̂ fed into the NCOs
//!    ([`CompensationSection`]: the IMU's own samples, errors and latency).
//!
//! The g-induced phase error of a run is its true phase error less the
//! reference's, row by row (the loops are linear while they hold lock, so
//! the difference is exactly what Δf = aᵀΓ, or aᵀΓ − aᵀΓ̂, makes of it);
//! its RMS is taken over the rows inside the scenario's shaking segments.
//! A cycle slip of one run shows as a 2π step in its difference, and in
//! the channels' slip counters, which are the simulator's truth.

use std::collections::{BTreeMap, HashMap};

use serde::Serialize;

use crate::compensation::CompensationSection;
use crate::motion::Segment;
use crate::scenario::Scenario;
use crate::session::{ChannelSummary, MemorySink, SimError, SimulatedRow, Truth, simulate};

/// Per run: the reference (Γ = 0), uncompensated, compensated.
pub const RUNS: [&str; 3] = ["reference (Γ = 0)", "uncompensated", "compensated"];

/// One channel (one satellite pass) of a trial.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TrialChannel {
    /// Receiver channel.
    pub channel: u32,
    /// Satellite PRN.
    pub prn: u32,
    /// Rows inside the shaking segments.
    pub rows_shaking: usize,
    /// RMS of the g-induced phase error under shaking, uncompensated and
    /// compensated \[rad\].
    pub g_rms_rad: [f64; 2],
    /// Cycle slips per run ([`RUNS`]).
    pub cycle_slips: [u64; 3],
    /// Losses of lock per run ([`RUNS`]).
    pub losses_of_lock: [u64; 3],
}

/// The g-induced phase error of one channel over time, for the figure.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PhaseTrace {
    /// Receiver channel.
    pub channel: u32,
    /// Satellite PRN.
    pub prn: u32,
    /// Row times \[s\].
    pub t_s: Vec<f64>,
    /// g-induced phase error, uncompensated \[rad\].
    pub uncompensated_rad: Vec<f64>,
    /// g-induced phase error, compensated \[rad\].
    pub compensated_rad: Vec<f64>,
}

/// What compensation did in one receiver configuration.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Trial {
    /// The oscillator preset's name.
    pub oscillator: String,
    /// The loop's noise bandwidth \[Hz\].
    pub bn_hz: f64,
    /// Γ of the simulation \[Hz/(m/s²)\].
    pub gamma_hz_per_mps2: [f64; 3],
    /// The feed-forward.
    pub compensation: CompensationSection,
    /// RMS of the g-induced phase error under shaking, all channels pooled,
    /// uncompensated and compensated \[rad\].
    pub g_rms_rad: [f64; 2],
    /// Uncompensated over compensated g-induced RMS.
    pub suppression: f64,
    /// RMS of the logged phase error (what the receiver's discriminator
    /// puts out: noise, oscillator and g-induced parts) under shaking, per
    /// run ([`RUNS`]) \[rad\].
    pub logged_rms_rad: [f64; 3],
    /// Cycle slips, all channels, per run ([`RUNS`]).
    pub cycle_slips: [u64; 3],
    /// Losses of lock, all channels, per run ([`RUNS`]).
    pub losses_of_lock: [u64; 3],
    /// Per channel.
    pub channels: Vec<TrialChannel>,
    /// The channel with the most rows under shaking, over time.
    pub trace: Option<PhaseTrace>,
}

/// The scenario's shaking segments as (start, end) \[s\].
pub fn shaking_intervals_s(scenario: &Scenario) -> Vec<(f64, f64)> {
    let mut t = 0.0;
    let mut out = Vec::new();
    for s in &scenario.motion.segments {
        let d = s.duration_s();
        if matches!(s, Segment::Shake(_)) {
            out.push((t, t + d));
        }
        t += d;
    }
    out
}

/// Runs the three simulations of `scenario` with `seed` (in parallel
/// threads) and compares them.
pub fn run_trial(scenario: &Scenario, seed: u64, compensation: &CompensationSection) -> Result<Trial, SimError> {
    let mut reference = scenario.clone();
    reference.oscillator.gamma_hz_per_mps2 = [0.0; 3];
    reference.compensation = None;
    let mut uncompensated = scenario.clone();
    uncompensated.compensation = None;
    let mut compensated = scenario.clone();
    compensated.compensation = Some(compensation.clone());
    let run = |s: &Scenario| -> Result<(MemorySink, Truth), SimError> {
        let mut sink = MemorySink::default();
        let truth = simulate(s, seed, &mut sink, |_| {})?;
        Ok((sink, truth))
    };
    let (r, (u, c)) = std::thread::scope(|scope| {
        let r = scope.spawn(|| run(&reference));
        let u = scope.spawn(|| run(&uncompensated));
        let c = run(&compensated);
        (r.join().expect("a simulation does not panic"), (u.join().expect("a simulation does not panic"), c))
    });
    let (r, u, c) = (r?, u?, c?);
    Ok(compare(scenario, compensation, [&r, &u, &c]))
}

type Key = (u32, u64);

fn key(row: &SimulatedRow) -> Key {
    (row.channel, row.t_s.to_bits())
}

fn compare(scenario: &Scenario, compensation: &CompensationSection, runs: [&(MemorySink, Truth); 3]) -> Trial {
    let shaking = shaking_intervals_s(scenario);
    let in_shaking = |t: f64| shaking.iter().any(|&(a, b)| t >= a && t < b);
    let tracking = runs.map(|r| r.0.tracking.as_slice());
    let truths = runs.map(|r| &r.1);
    let (per_channel, trace) = g_induced_errors(tracking, in_shaking);
    let channels: Vec<TrialChannel> = per_channel.iter().map(|c| c.trial_channel(truths)).collect();
    let n: usize = per_channel.iter().map(|e| e.rows).sum();
    let ss = per_channel.iter().fold([0.0; 2], |acc, e| [acc[0] + e.ss_rad2[0], acc[1] + e.ss_rad2[1]]);
    let g_rms_rad = ss.map(|s| (s / n.max(1) as f64).sqrt());
    let totals = truths.map(|t| slips_and_losses(t, |_| true));
    Trial {
        oscillator: scenario.oscillator.preset.name().to_string(),
        bn_hz: scenario.tracking_loop.bn_hz,
        gamma_hz_per_mps2: scenario.oscillator.gamma_hz_per_mps2,
        compensation: compensation.clone(),
        g_rms_rad,
        suppression: g_rms_rad[0] / g_rms_rad[1],
        logged_rms_rad: logged_rms_rad(tracking, in_shaking),
        cycle_slips: totals.map(|t| t.0),
        losses_of_lock: totals.map(|t| t.1),
        channels,
        trace,
    }
}

/// The RMS of each run's logged phase error over its rows under shaking
/// (`in_shaking` of the row's time) \[rad\]; 0 for a run with none.
fn logged_rms_rad(tracking: [&[SimulatedRow]; 3], in_shaking: impl Fn(f64) -> bool) -> [f64; 3] {
    tracking.map(|rows| {
        let (mut ss, mut n) = (0.0, 0usize);
        for row in rows.iter().filter(|r| in_shaking(r.t_s)) {
            ss += row.phase_err_rad * row.phase_err_rad;
            n += 1;
        }
        (ss / n.max(1) as f64).sqrt()
    })
}

/// One channel's (one satellite pass's) g-induced phase error under
/// shaking: its sums of squares, uncompensated and compensated \[rad²\],
/// over `rows` rows.
#[derive(Debug, Clone, Copy, PartialEq)]
struct ChannelSums {
    channel: u32,
    prn: u32,
    ss_rad2: [f64; 2],
    rows: usize,
}

impl ChannelSums {
    /// The channel's RMS errors and, from each run's truth ([`RUNS`]), its
    /// cycle slips and losses of lock.
    fn trial_channel(&self, truths: [&Truth; 3]) -> TrialChannel {
        let counts = truths.map(|t| slips_and_losses(t, |c| c.channel == self.channel && c.prn == self.prn));
        TrialChannel {
            channel: self.channel,
            prn: self.prn,
            rows_shaking: self.rows,
            g_rms_rad: self.ss_rad2.map(|s| (s / self.rows.max(1) as f64).sqrt()),
            cycle_slips: counts.map(|c| c.0),
            losses_of_lock: counts.map(|c| c.1),
        }
    }
}

/// The g-induced phase error of the uncompensated and the compensated run
/// (`tracking[1]`, `tracking[2]`): each row's true phase error less the
/// reference's (`tracking[0]`) at the same channel and time, over the rows
/// under shaking that all three runs hold. Per channel in order of first
/// appearance, and the trace of the channel with the most rows (of equals,
/// the highest channel, so that it is the same on every run).
fn g_induced_errors(
    tracking: [&[SimulatedRow]; 3],
    in_shaking: impl Fn(f64) -> bool,
) -> (Vec<ChannelSums>, Option<PhaseTrace>) {
    let reference: HashMap<Key, f64> = tracking[0].iter().map(|row| (key(row), row.true_phase_err_rad)).collect();
    let compensated: HashMap<Key, &SimulatedRow> = tracking[2].iter().map(|row| (key(row), row)).collect();
    let mut per_channel: Vec<ChannelSums> = Vec::new();
    let mut traces: BTreeMap<u32, PhaseTrace> = BTreeMap::new();
    for row in tracking[1].iter().filter(|r| in_shaking(r.t_s)) {
        let (Some(&phi_ref), Some(comp)) = (reference.get(&key(row)), compensated.get(&key(row))) else { continue };
        let du = row.true_phase_err_rad - phi_ref;
        let dc = comp.true_phase_err_rad - phi_ref;
        let entry = match per_channel.iter_mut().position(|e| e.channel == row.channel && e.prn == row.prn) {
            Some(i) => &mut per_channel[i],
            None => {
                per_channel.push(ChannelSums { channel: row.channel, prn: row.prn, ss_rad2: [0.0; 2], rows: 0 });
                per_channel.last_mut().expect("just pushed")
            }
        };
        entry.ss_rad2[0] += du * du;
        entry.ss_rad2[1] += dc * dc;
        entry.rows += 1;
        let trace = traces.entry(row.channel).or_insert_with(|| PhaseTrace {
            channel: row.channel,
            prn: row.prn,
            t_s: Vec::new(),
            uncompensated_rad: Vec::new(),
            compensated_rad: Vec::new(),
        });
        if trace.prn == row.prn {
            trace.t_s.push(row.t_s);
            trace.uncompensated_rad.push(du);
            trace.compensated_rad.push(dc);
        }
    }
    (per_channel, traces.into_values().max_by_key(|t| t.t_s.len()))
}

/// Cycle slips and losses of lock of a run's channels that `keep` keeps.
fn slips_and_losses(truth: &Truth, keep: impl Fn(&ChannelSummary) -> bool) -> (u64, u64) {
    truth
        .channels
        .iter()
        .filter(|c| keep(c))
        .fold((0, 0), |(s, l), c| (s + c.stats.cycle_slips, l + c.stats.losses_of_lock))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A row of channel `channel` (PRN `prn`) at `t_s` with the logged and the true phase error.
    fn row(t_s: f64, channel: u32, prn: u32, logged_rad: f64, true_rad: f64) -> SimulatedRow {
        SimulatedRow {
            t_s,
            channel,
            prn,
            cn0_dbhz: 45.0,
            elev_deg: 30.0,
            phase_err_rad: logged_rad,
            locked: true,
            true_phase_err_rad: true_rad,
            true_cn0_dbhz: 45.0,
            nco_phase_cycles: 0.0,
            nco_freq_hz: 0.0,
            carrier: gsens_io::Carrier::GPS_L1,
        }
    }

    #[test]
    fn logged_rms_is_over_the_rows_under_shaking() {
        let runs = [
            vec![row(0.0, 0, 5, 9.0, 0.0), row(1.0, 0, 5, 3.0, 0.0), row(2.0, 0, 5, 4.0, 0.0)],
            vec![],
            vec![row(1.0, 0, 5, 1.0, 0.0)],
        ];
        let rms = logged_rms_rad([&runs[0], &runs[1], &runs[2]], |t| t >= 0.5);
        assert_eq!(rms, [(12.5f64).sqrt(), 0.0, 1.0]);
    }

    #[test]
    fn g_induced_errors_are_differences_to_the_reference_at_the_same_channel_and_time() {
        let reference = vec![row(1.0, 0, 5, 0.0, 0.5), row(1.0, 1, 7, 0.0, -1.0), row(2.0, 0, 5, 0.0, 0.5)];
        let uncompensated = vec![
            row(0.0, 0, 5, 0.0, 9.0), // before the shaking
            row(1.0, 0, 5, 0.0, 1.5),
            row(1.0, 1, 7, 0.0, 1.0),
            row(2.0, 0, 5, 0.0, 2.5),
            row(3.0, 1, 7, 0.0, 5.0), // no reference row
        ];
        let compensated = vec![row(1.0, 0, 5, 0.0, 0.6), row(1.0, 1, 7, 0.0, -0.9), row(2.0, 0, 5, 0.0, 0.5)];
        let (sums, trace) = g_induced_errors([&reference, &uncompensated, &compensated], |t| t >= 0.5);
        assert_eq!(sums.len(), 2);
        assert_eq!((sums[0].channel, sums[0].prn, sums[0].rows), (0, 5, 2));
        assert!((sums[0].ss_rad2[0] - (1.0 + 4.0)).abs() < 1e-12 && (sums[0].ss_rad2[1] - 0.01).abs() < 1e-12);
        assert_eq!((sums[1].channel, sums[1].rows, sums[1].ss_rad2[0]), (1, 1, 4.0));
        let trace = trace.unwrap();
        assert_eq!((trace.channel, trace.t_s.as_slice()), (0, &[1.0, 2.0][..]));
        assert_eq!(trace.uncompensated_rad, [1.0, 2.0]);
        // Slips and losses of lock from each run's truth, of the channel's pass only.
        let mut truth = short_truth();
        let passes = truth.channels.len();
        for (k, c) in truth.channels.iter_mut().enumerate() {
            (c.channel, c.prn) = if k < 2 { (1, 7) } else { (9, 9) };
            (c.stats.cycle_slips, c.stats.losses_of_lock) = (3, 1);
        }
        let c = sums[1].trial_channel([&truth, &truth, &truth]);
        assert_eq!((c.rows_shaking, c.g_rms_rad[0], c.cycle_slips, c.losses_of_lock), (1, 2.0, [6; 3], [2; 3]));
        assert_eq!(slips_and_losses(&truth, |_| true), (3 * passes as u64, passes as u64));
    }

    /// The truth of a 1 s default session (several channels).
    fn short_truth() -> Truth {
        let scenario = Scenario::from_toml_str("[session]\nduration_s = 1.0\n").unwrap();
        let truth = simulate(&scenario, 1, &mut MemorySink::default(), |_| {}).unwrap();
        assert!(truth.channels.len() > 2);
        truth
    }
}
