//! Isolated IMU spikes: single samples that no motion of a hand-held board
//! can produce, found by their consistency with their neighbours.
//!
//! A sample k is a spike on an axis when its second difference
//! d_k = a_k − (a_{k−1} + a_{k+1})/2 exceeds both [`SPIKE_SIGMAS`] robust
//! standard deviations of all second differences on that axis (1.4826·MAD:
//! the sensor's own noise, from the log itself) and the most a hand can make
//! it — motion of amplitude A at frequency f has |d| ≤ h²·(2πf)²·A/2 for a
//! sample interval h; with [`HAND_MAX_ACCEL_MPS2`] at [`HAND_MAX_FREQ_HZ`]
//! that is 1.5 m/s² at 100 Hz — and its neighbours' second differences do not (a spike makes d_{k±1} about −d_k/2, a real fast motion
//! spreads over several samples). A spike is replaced by the mean of its
//! neighbours and counted: the loop models would otherwise turn one wild
//! sample into a transient that the fit mistakes for Γ's signature.

use gsens_core::stats::{median_high_in_place, median_low_in_place, quantile_in_place};
use gsens_io::ImuSeries;

/// Robust standard deviations of the second difference above which an
/// isolated sample is a spike. Far out in the tails of hand motion and sensor
/// noise alike (a false alarm in a Gaussian log of a million samples has a
/// probability of 10⁻²⁰), near the size of a single corrupted sample.
pub const SPIKE_SIGMAS: f64 = 12.0;

/// The largest specific-force amplitude of a board shaken by hand \[m/s²\] (3 g).
pub(crate) const HAND_MAX_ACCEL_MPS2: f64 = 30.0;
/// The highest frequency a hand shakes a board at \[Hz\].
pub(crate) const HAND_MAX_FREQ_HZ: f64 = 5.0;

/// What [`replace_imu_spikes`] replaced.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ImuSpikes {
    /// Time stamps of the replaced samples \[s\].
    pub t_s: Vec<f64>,
}

/// The indices of `imu`'s isolated spikes (module docs), in increasing
/// order: samples k whose second difference is beyond the limit on some
/// axis while the samples k − 1 and k + 1 are not spikes themselves.
pub fn imu_spikes(imu: &ImuSeries) -> Vec<usize> {
    let n = imu.accel_mps2.len();
    if n < 5 {
        return Vec::new();
    }
    let a = &imu.accel_mps2;
    let mut dt: Vec<f64> = imu.t_s.windows(2).map(|w| w[1] - w[0]).collect();
    let h = median_low_in_place(&mut dt);
    let w = std::f64::consts::TAU * HAND_MAX_FREQ_HZ;
    let hand_limit = 0.5 * h * h * w * w * HAND_MAX_ACCEL_MPS2;
    let mut spiked = vec![false; n];
    for axis in 0..3 {
        let d: Vec<f64> = (1..n - 1).map(|k| a[k][axis] - 0.5 * (a[k - 1][axis] + a[k + 1][axis])).collect();
        let mut abs: Vec<f64> = d.iter().map(|v| v.abs()).collect();
        let mad = median_high_in_place(&mut abs);
        // A motionless axis of a quantized IMU can have MAD 0: fall back to the mean |d|.
        let scale = if mad > 0.0 { 1.4826 * mad } else { d.iter().map(|v| v.abs()).sum::<f64>() / d.len() as f64 };
        if scale <= 0.0 {
            continue;
        }
        let limit = (SPIKE_SIGMAS * scale).max(hand_limit);
        for j in 0..d.len() {
            // Neighbours of a spike carry about half its second difference, with the other sign.
            let neighbours_follow = (j == 0 || d[j - 1].abs() < 0.75 * d[j].abs())
                && (j + 1 == d.len() || d[j + 1].abs() < 0.75 * d[j].abs());
            if d[j].abs() > limit && neighbours_follow {
                spiked[j + 1] = true;
            }
        }
    }
    (1..n - 1).filter(|&k| spiked[k] && !spiked[k - 1] && !spiked[k + 1]).collect()
}

/// Replaces the samples of `imu` at `at` ([`imu_spikes`] of this series)
/// by the mean of their neighbours, in place, and returns where they were.
/// No two of them are neighbours, so every mean is of samples as logged.
pub fn replace_imu_spikes(imu: &mut ImuSeries, at: &[usize]) -> ImuSpikes {
    let a = &mut imu.accel_mps2;
    for &k in at {
        a[k] = [0, 1, 2].map(|i| 0.5 * (a[k - 1][i] + a[k + 1][i]));
    }
    ImuSpikes { t_s: at.iter().map(|&k| imu.t_s[k]).collect() }
}

/// Chance of a false alarm of the flat-run test per axis and log: a run is
/// called implausible when the expected number of runs at least as long,
/// made by the sensor's noise alone, is below this.
pub const FLAT_RUN_FALSE_ALARM: f64 = 1e-3;

/// The shortest run of identical samples the flat-run test considers: one
/// repeated sample (a run of 2) is what a logger duplicating a row does, one
/// sample's error, and it is not worth a warning.
pub const MIN_FLAT_RUN: usize = 3;

/// Why a run of identical samples was found implausible.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum FlatRunKind {
    /// The axis stopped changing (a stuck sensor, or a logger repeating its
    /// last value) somewhere inside its range.
    Stuck,
    /// The run sits at the axis's largest or smallest value in the log: the
    /// sensor was clipped at its range.
    Clipped,
}

/// One implausible run of identical samples on one axis.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct FlatRun {
    /// 0, 1, 2 for x, y, z.
    pub axis: usize,
    /// Time stamp of its first sample \[s\] (IMU clock).
    pub start_s: f64,
    /// Time stamp of its last sample \[s\] (IMU clock).
    pub end_s: f64,
    /// Number of identical samples.
    pub samples: usize,
    /// The repeated value \[m/s²\].
    pub value_mps2: f64,
    /// Stuck or clipped.
    pub kind: FlatRunKind,
}

/// What [`find_flat_runs`] measured in an IMU log and found implausible.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct FlatRuns {
    /// The median sample interval h \[s\] (0 for fewer than two samples).
    pub sample_interval_s: f64,
    /// The output step q per axis \[m/s²\]: the smallest non-zero change between
    /// consecutive samples (an upper bound on the quantization step).
    pub quantum_mps2: [f64; 3],
    /// The sensor's white noise σ per axis \[m/s²\]: 1.4826·MAD of the second
    /// differences / √1.5, in windows of 1 s, the 10th percentile over the
    /// windows (the quiet ones: motion only adds to it).
    pub noise_sigma_mps2: [f64; 3],
    /// Per axis, the run length (samples) that noise alone makes with a chance
    /// below [`FLAT_RUN_FALSE_ALARM`] in the whole log; `None` when the noise
    /// is below the quantization (σ < q/(2√π)), so that identical samples at
    /// rest are what the sensor gives.
    pub noise_run_limit: [Option<usize>; 3],
    /// The implausible runs, in time order.
    pub runs: Vec<FlatRun>,
}

/// Runs of identical samples on an axis of `imu` that neither its noise nor a
/// continuous motion can produce: a stuck sensor, a logger repeating its last
/// value, or a sensor clipped at its range.
///
/// Consumer accelerometers quantize (16 bits over ±4 g: q = 1.2e-3 m/s²), so
/// identical consecutive samples are normal at rest, and at a coarse step
/// with little noise a board at rest reads one value for seconds. Two tests,
/// each from the log's own numbers, on every run of at least
/// [`MIN_FLAT_RUN`] identical samples:
///
/// 1. **Noise.** With white noise σ and output step q, two consecutive
///    samples of a still board are identical with probability
///    p = E\[(1 − |D|/q)⁺\] ≤ q/(2σ√π) (D ~ N(0, 2σ²), the difference of the
///    continuous values; motion only lowers it). A run of L has probability
///    ≤ p^(L−1) per sample, so over the N samples of the log it is
///    implausible when N·p^(L−1) < [`FLAT_RUN_FALSE_ALARM`]
///    ([`FlatRuns::noise_run_limit`]). σ and q are measured on the log
///    ([`FlatRuns::noise_sigma_mps2`], [`FlatRuns::quantum_mps2`]); when
///    σ < q/(2√π) the bound is 1 and the test says nothing.
/// 2. **Release.** A stuck sensor keeps its last good value, so a run starts
///    continuously; when it is released during motion, the value jumps to
///    where the motion has gone meanwhile. A continuous signal changes by
///    about as much from one sample to the next as its neighbours do, so a
///    jump at the run's end larger than twice the largest one-sample change
///    within 1 s (at least the run's length) before and after the run is
///    implausible. Quantized samples at rest or at a turning point of the
///    motion leave their step by one output step, and pass.
///
/// A run is [`FlatRunKind::Clipped`] when its value is the axis's largest or
/// smallest in the log, else [`FlatRunKind::Stuck`].
pub fn find_flat_runs(imu: &ImuSeries) -> FlatRuns {
    let n = imu.accel_mps2.len();
    let mut out = FlatRuns::default();
    if n < 2 * MIN_FLAT_RUN {
        return out;
    }
    let a = &imu.accel_mps2;
    let mut dt: Vec<f64> = imu.t_s.windows(2).map(|w| w[1] - w[0]).collect();
    let h = median_high_in_place(&mut dt);
    out.sample_interval_s = h;
    let window = if h > 0.0 { ((1.0 / h).round() as usize).clamp(8, n) } else { n };
    for axis in 0..3 {
        let x: Vec<f64> = a.iter().map(|v| v[axis]).collect();
        let q = x.windows(2).map(|w| (w[1] - w[0]).abs()).filter(|d| *d > 0.0).fold(f64::INFINITY, f64::min);
        if !q.is_finite() {
            continue; // a constant axis: nothing to compare a run with
        }
        out.quantum_mps2[axis] = q;
        let d: Vec<f64> = (1..n - 1).map(|k| x[k] - 0.5 * (x[k - 1] + x[k + 1])).collect();
        let mut sigmas: Vec<f64> = d
            .chunks(window)
            .filter(|c| c.len() >= 8)
            .map(|c| {
                let mut abs: Vec<f64> = c.iter().map(|v| v.abs()).collect();
                1.4826 * median_high_in_place(&mut abs) / 1.5f64.sqrt()
            })
            .collect();
        let sigma = if sigmas.is_empty() { 0.0 } else { quantile_in_place(&mut sigmas, 0.1) };
        out.noise_sigma_mps2[axis] = sigma;
        let p = if sigma > 0.0 { q / (2.0 * sigma * std::f64::consts::PI.sqrt()) } else { 1.0 };
        let limit = (p < 1.0).then(|| {
            let l = 1.0 + ((FLAT_RUN_FALSE_ALARM / n as f64).ln() / p.ln()).ceil();
            (l as usize).max(MIN_FLAT_RUN)
        });
        out.noise_run_limit[axis] = limit;
        let (lo, hi) = x.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| (lo.min(v), hi.max(v)));
        let max_step = |from: usize, to: usize| (from..to).map(|j| (x[j + 1] - x[j]).abs()).fold(0.0, f64::max);
        let mut i0 = 0;
        while i0 < n {
            let mut i1 = i0;
            while i1 + 1 < n && x[i1 + 1] == x[i0] {
                i1 += 1;
            }
            let len = i1 - i0 + 1;
            if len >= MIN_FLAT_RUN {
                let by_noise = limit.is_some_and(|l| len >= l);
                let w = window.max(len);
                let released = i1 + 1 < n && i0 > 0 && {
                    let jump = (x[i1 + 1] - x[i1]).abs();
                    let before = max_step(i0.saturating_sub(w), i0);
                    let after = max_step(i1 + 1, (i1 + 1 + w).min(n - 1));
                    jump > 2.0 * before.max(after)
                };
                if by_noise || released {
                    let kind = if x[i0] == lo || x[i0] == hi { FlatRunKind::Clipped } else { FlatRunKind::Stuck };
                    out.runs.push(FlatRun {
                        axis,
                        start_s: imu.t_s[i0],
                        end_s: imu.t_s[i1],
                        samples: len,
                        value_mps2: x[i0],
                        kind,
                    });
                }
            }
            i0 = i1 + 1;
        }
    }
    out.runs.sort_by(|r, s| r.start_s.total_cmp(&s.start_s).then(r.axis.cmp(&s.axis)));
    out
}

/// Leaves out of the estimate the epochs of `session` whose IMU reading
/// touches one of `runs`: their phase becomes `None` (a gap), read at stamp
/// t + τ within two sample intervals of a run (the interpolation between
/// samples reads two on either side, [`ImuSeries::interpolate_at`]). The
/// loop models keep running through them, and the estimator leaves out the
/// epochs after a gap that its high-pass needs to settle. Returns the
/// number of epochs that lost their phase.
pub fn mask_flat_runs(session: &mut crate::PreparedSession, runs: &FlatRuns) -> usize {
    let h = runs.sample_interval_s;
    let mut masked = 0;
    for r in &runs.runs {
        let (from, to) = (r.start_s - 2.0 * h, r.end_s + 2.0 * h);
        let tau = session.imu_time_offset_s;
        let first = session.t_s.partition_point(|&t| t + tau < from);
        for k in first..session.t_s.len() {
            if session.t_s[k] + tau > to {
                break;
            }
            if session.phase_err_rad[k].take().is_some() {
                masked += 1;
            }
        }
    }
    masked
}

#[cfg(test)]
mod tests {
    use super::*;

    fn shaken(n: usize) -> ImuSeries {
        let t_s: Vec<f64> = (0..n).map(|k| k as f64 * 0.01).collect();
        let accel_mps2 = t_s
            .iter()
            .map(|t| {
                let w = std::f64::consts::TAU * 0.9 * t;
                // A little sensor noise from a fixed sequence.
                let e = ((t * 1e4).sin() * 1e3).fract() * 0.02;
                [3.0 * w.sin() + e, 0.5 * (2.0 * w).cos() - e, 9.81 + e]
            })
            .collect();
        ImuSeries { t_s, accel_mps2 }
    }

    /// A copy of `imu` with its isolated spikes replaced, and where they were.
    fn despike_imu(imu: &ImuSeries) -> (ImuSeries, ImuSpikes) {
        let at = imu_spikes(imu);
        let mut out = imu.clone();
        let spikes = replace_imu_spikes(&mut out, &at);
        (out, spikes)
    }

    #[test]
    fn finds_and_replaces_isolated_spikes_only() {
        let clean = shaken(4000);
        let (same, none) = despike_imu(&clean);
        assert!(none.t_s.is_empty(), "{:?}", none.t_s);
        assert_eq!(same, clean);
        let mut bad = clean.clone();
        for (k, axis, v) in [(500, 0, 1000.0), (1500, 2, -300.0), (3000, 1, 50.0)] {
            bad.accel_mps2[k][axis] = v;
        }
        let (fixed, found) = despike_imu(&bad);
        assert_eq!(found.t_s, vec![5.0, 15.0, 30.0]);
        for k in [500, 1500, 3000] {
            for i in 0..3 {
                assert!((fixed.accel_mps2[k][i] - clean.accel_mps2[k][i]).abs() < 0.05, "{k} {i}");
            }
        }
    }

    /// `shaken` with its output rounded to steps of `q`.
    fn quantized(n: usize, q: f64) -> ImuSeries {
        let mut imu = shaken(n);
        for a in &mut imu.accel_mps2 {
            *a = a.map(|v| (v / q).round() * q);
        }
        imu
    }

    #[test]
    fn flat_runs_are_found_where_neither_noise_nor_motion_makes_them() {
        // Unquantized and quantized (the noise, 0.006 m/s² rms, dithers a step of 0.001 but not one of 0.1; z
        // then reads one value throughout): nothing.
        for q in [0.0, 0.001, 0.1] {
            let imu = if q > 0.0 { quantized(4000, q) } else { shaken(4000) };
            let runs = find_flat_runs(&imu);
            assert!(runs.runs.is_empty(), "q = {q}: {:?}", runs.runs);
            assert!((runs.sample_interval_s - 0.01).abs() < 1e-12);
        }
        assert_eq!(find_flat_runs(&quantized(4000, 0.1)).noise_run_limit[2], None);
        // Stuck for 0.3 s while x moves: found at every step size, by the noise or by its release.
        for q in [0.0, 0.001, 0.1] {
            let mut imu = if q > 0.0 { quantized(4000, q) } else { shaken(4000) };
            let held = imu.accel_mps2[1000][0];
            for a in &mut imu.accel_mps2[1001..1030] {
                a[0] = held;
            }
            let runs = find_flat_runs(&imu);
            assert_eq!(runs.runs.len(), 1, "q = {q}: {:?}", runs.runs);
            let r = &runs.runs[0];
            assert_eq!((r.axis, r.samples, r.start_s, r.kind), (0, 30, 10.0, FlatRunKind::Stuck), "q = {q}");
        }
        // Clipped at ±2.5 m/s² (amplitude 3): flat tops at the extremes.
        let mut imu = shaken(4000);
        for a in &mut imu.accel_mps2 {
            a[0] = a[0].clamp(-2.5, 2.5);
        }
        let runs = find_flat_runs(&imu);
        assert!(runs.runs.len() > 50, "{}", runs.runs.len());
        assert!(runs.runs.iter().all(|r| r.axis == 0 && r.kind == FlatRunKind::Clipped && r.value_mps2.abs() == 2.5));
    }
}
