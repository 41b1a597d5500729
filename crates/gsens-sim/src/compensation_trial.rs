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
use crate::session::{MemorySink, SimError, SimulatedRow, Truth, simulate};

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
    let reference: HashMap<Key, f64> =
        runs[0].0.tracking.iter().map(|row| (key(row), row.true_phase_err_rad)).collect();
    let compensated: HashMap<Key, &SimulatedRow> = runs[2].0.tracking.iter().map(|row| (key(row), row)).collect();
    // Per channel: sums of squares (uncompensated, compensated) and the count.
    let mut per_channel: Vec<(u32, u32, [f64; 2], usize)> = Vec::new();
    // Ordered by channel, so that the trace drawn (the longest; of equals,
    // the highest channel) is the same on every run.
    let mut traces: BTreeMap<u32, PhaseTrace> = BTreeMap::new();
    let mut logged_ss = [0.0; 3];
    let mut logged_n = [0usize; 3];
    for (k, run) in runs.iter().enumerate() {
        for row in run.0.tracking.iter().filter(|r| in_shaking(r.t_s)) {
            logged_ss[k] += row.phase_err_rad * row.phase_err_rad;
            logged_n[k] += 1;
        }
    }
    for row in runs[1].0.tracking.iter().filter(|r| in_shaking(r.t_s)) {
        let (Some(&phi_ref), Some(comp)) = (reference.get(&key(row)), compensated.get(&key(row))) else { continue };
        let du = row.true_phase_err_rad - phi_ref;
        let dc = comp.true_phase_err_rad - phi_ref;
        let entry = match per_channel.iter_mut().find(|e| e.0 == row.channel && e.1 == row.prn) {
            Some(e) => e,
            None => {
                per_channel.push((row.channel, row.prn, [0.0; 2], 0));
                per_channel.last_mut().expect("just pushed")
            }
        };
        entry.2[0] += du * du;
        entry.2[1] += dc * dc;
        entry.3 += 1;
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
    let slips_of = |truth: &Truth, channel: u32, prn: u32| {
        truth
            .channels
            .iter()
            .filter(|c| c.channel == channel && c.prn == prn)
            .fold((0, 0), |(s, l), c| (s + c.stats.cycle_slips, l + c.stats.losses_of_lock))
    };
    let channels: Vec<TrialChannel> = per_channel
        .iter()
        .map(|&(channel, prn, ss, n)| {
            let counts = runs.map(|r| slips_of(&r.1, channel, prn));
            TrialChannel {
                channel,
                prn,
                rows_shaking: n,
                g_rms_rad: ss.map(|s| (s / n.max(1) as f64).sqrt()),
                cycle_slips: counts.map(|c| c.0),
                losses_of_lock: counts.map(|c| c.1),
            }
        })
        .collect();
    let n: usize = per_channel.iter().map(|e| e.3).sum();
    let ss = per_channel.iter().fold([0.0; 2], |acc, e| [acc[0] + e.2[0], acc[1] + e.2[1]]);
    let g_rms_rad = ss.map(|s| (s / n.max(1) as f64).sqrt());
    let totals = runs
        .map(|r| r.1.channels.iter().fold((0, 0), |(s, l), c| (s + c.stats.cycle_slips, l + c.stats.losses_of_lock)));
    let trace = traces.into_values().max_by_key(|t| t.t_s.len());
    Trial {
        oscillator: scenario.oscillator.preset.name().to_string(),
        bn_hz: scenario.tracking_loop.bn_hz,
        gamma_hz_per_mps2: scenario.oscillator.gamma_hz_per_mps2,
        compensation: compensation.clone(),
        g_rms_rad,
        suppression: g_rms_rad[0] / g_rms_rad[1],
        logged_rms_rad: [0, 1, 2].map(|k| (logged_ss[k] / logged_n[k].max(1) as f64).sqrt()),
        cycle_slips: totals.map(|t| t.0),
        losses_of_lock: totals.map(|t| t.1),
        channels,
        trace,
    }
}
