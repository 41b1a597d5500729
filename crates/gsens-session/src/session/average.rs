//! The averaging stages of a session's preparation: the used tracks' kept
//! rows gathered by epoch, their constant offsets, and the per-epoch
//! average with the IMU interpolated beside it.

use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;
use std::ops::Range;

use gsens_core::average_phase_rad;
use gsens_io::ImuSeries;

use super::Weighting;
use super::grid::{Grid, Span};
use crate::screening::{Rows, Screened};

/// Epochs gathered and averaged as one block: the blocks run in parallel,
/// each long enough (minutes of a 40 Hz log) that its per-track searches
/// and hand-out cost little beside its rows.
const EPOCH_BLOCK: usize = 1 << 13;

/// The kept rows of the used tracks by epoch, as compressed rows.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Gathered {
    /// Per used track (in the order given): its first slot, and after the
    /// last the number of slots. A slot is one segment of a track (the
    /// screening splits tracks at steps), each with its own offset.
    pub slot_base: Vec<usize>,
    /// The entries of epoch `e` are `entries[start[e]..start[e + 1]]`.
    pub start: Vec<usize>,
    /// Every kept row of the used tracks: (slot, weight, phase on L1's scale \[rad\]),
    /// each epoch's in the order of the used tracks.
    pub entries: Vec<(usize, f64, f64)>,
}

impl Gathered {
    /// The number of slots.
    pub(super) fn slots(&self) -> usize {
        *self.slot_base.last().expect("starts at 0")
    }

    /// The number of epochs.
    pub(super) fn epochs(&self) -> usize {
        self.start.len() - 1
    }
}

/// The weight of a row in the per-epoch average: the inverse of its phase
/// variance on L1's scale, where s = f_L1/f_c (`to_l1`) scales the noise by
/// s: `1/s²` ([`Weighting::Equal`]) or `10^(cn0_dbhz/10)/s²` ([`Weighting::Cn0`]).
pub(super) fn row_weight(weighting: Weighting, cn0_dbhz: f64, to_l1: f64) -> f64 {
    match weighting {
        Weighting::Equal => 1.0 / (to_l1 * to_l1),
        Weighting::Cn0 => gsens_core::units::cn0_dbhz_to_ratio_hz(cn0_dbhz) / (to_l1 * to_l1),
    }
}

/// `0..n_epochs` in runs of [`EPOCH_BLOCK`].
fn epoch_blocks(n_epochs: usize) -> Vec<Range<usize>> {
    (0..n_epochs).step_by(EPOCH_BLOCK).map(|e0| e0..(e0 + EPOCH_BLOCK).min(n_epochs)).collect()
}

/// Gathers the rows the screening kept of the candidates `selected` (indices
/// into `rows`, in rank order) by epoch (below `n_epochs`), weighted by
/// [`row_weight`]. The epochs in blocks of [`EPOCH_BLOCK`], the blocks at
/// once: a track's rows in a run of epochs are a run of its rows (in epoch
/// order), and every epoch's entries come out in the order of one pass over
/// the tracks, so the result does not depend on how the blocks are shared out.
pub(super) fn gather(
    rows: &Rows,
    screened: &Screened,
    selected: &[usize],
    weighting: Weighting,
    n_epochs: usize,
) -> Gathered {
    let mut slot_base = Vec::with_capacity(selected.len() + 1);
    slot_base.push(0usize);
    for &c in selected {
        slot_base.push(slot_base.last().copied().unwrap_or(0) + screened.segments[c]);
    }
    let blocks = epoch_blocks(n_epochs);
    // Calls f(slot, epoch, phase, C/N0, to_l1) for each used row at `epochs`.
    let for_each_used_row = |epochs: Range<usize>, f: &mut dyn FnMut(usize, u32, f64, f64, f64)| {
        for (sel, &c) in selected.iter().enumerate() {
            let (ep, phase, cn0) = (rows.epochs(c), rows.phases(c), rows.cn0s(c));
            let range = rows.range(c);
            let (flags, segment) = (&screened.flags[range.clone()], &screened.segment[range]);
            let first = ep.partition_point(|&x| (x as usize) < epochs.start);
            let end = ep.partition_point(|&x| (x as usize) < epochs.end);
            for j in first..end {
                if flags[j] == 0 {
                    f(slot_base[sel] + segment[j] as usize, ep[j], phase[j], cn0[j], rows.to_l1[c]);
                }
            }
        }
    };
    let mut start = vec![0usize; n_epochs + 1];
    start[1..].par_chunks_mut(EPOCH_BLOCK).zip(&blocks).for_each(|(counts, epochs)| {
        let e0 = epochs.start;
        for_each_used_row(epochs.clone(), &mut |_, epoch, _, _, _| counts[epoch as usize - e0] += 1);
    });
    for e in 0..n_epochs {
        start[e + 1] += start[e];
    }
    let mut entries = vec![(0usize, 0f64, 0f64); start[n_epochs]];
    // Each block's entries, a slice of their own.
    let mut outs = Vec::with_capacity(blocks.len());
    let mut rest = entries.as_mut_slice();
    for epochs in &blocks {
        let (out, tail) = rest.split_at_mut(start[epochs.end] - start[epochs.start]);
        outs.push(out);
        rest = tail;
    }
    outs.into_par_iter().zip(&blocks).for_each(|(out, epochs)| {
        // Where each epoch's next entry goes, in `out`.
        let base = start[epochs.start];
        let mut fill: Vec<usize> = start[epochs.clone()].iter().map(|s| s - base).collect();
        let e0 = epochs.start;
        for_each_used_row(epochs.clone(), &mut |slot, epoch, phase, cn0, to_l1| {
            let e = epoch as usize - e0;
            out[fill[e]] = (slot, row_weight(weighting, cn0, to_l1), phase);
            fill[e] += 1;
        });
    });
    Gathered { slot_base, start, entries }
}

/// The constant phase offset of every slot \[rad\]: [`channel_offsets`] with
/// each track's first segment in the gauge, when `remove` and there are two
/// slots or more; else zeros.
pub(super) fn slot_offsets(g: &Gathered, remove: bool) -> Vec<f64> {
    let n_slots = g.slots();
    if remove && n_slots > 1 {
        let first_segment: Vec<bool> = (0..n_slots).map(|slot| g.slot_base.contains(&slot)).collect();
        channel_offsets(n_slots, &g.start, &g.entries, &first_segment)
    } else {
        vec![0.0; n_slots]
    }
}

/// The estimator's inputs per epoch, before the trim to the epochs with a phase.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Averaged {
    pub t_s: Vec<f64>,
    pub phase_err_rad: Vec<Option<f64>>,
    pub accel_mps2: Vec<[f64; 3]>,
}

impl Averaged {
    /// Keeps the epochs from the first to the last with a phase: the epochs
    /// outside hold no measurement (e.g. every used track's start-up
    /// screened out), and a leading stretch without one would be a gap to
    /// the estimator, which then leaves out up to three time constants of
    /// its high-pass after it (9.5 s at 0.05 Hz), where its own warm-up suffices.
    /// Returns `None`, and keeps everything, where no epoch has a phase
    /// (every average not finite).
    pub(super) fn trim_to_phases(&mut self) -> Option<()> {
        let first = self.phase_err_rad.iter().position(Option::is_some)?;
        let end = self.phase_err_rad.iter().rposition(Option::is_some)? + 1;
        self.t_s.truncate(end);
        self.t_s.drain(..first);
        self.phase_err_rad.truncate(end);
        self.phase_err_rad.drain(..first);
        self.accel_mps2.truncate(end);
        self.accel_mps2.drain(..first);
        Some(())
    }
}

/// Per epoch of `span`: its time (the logged stamp, or the grid time in a
/// gap), the weighted average of its entries less their slots' offsets
/// ([`average_phase_rad`]; `None` without an entry), and the specific force
/// interpolated at time + `imu_time_offset_s`. Each epoch on its own, the
/// blocks at once.
pub(super) fn average(
    g: &Gathered,
    offsets_rad: &[f64],
    (grid, stamps, span): (&Grid, &[f64], Span),
    imu: &ImuSeries,
    imu_time_offset_s: f64,
) -> Averaged {
    let k_first = span.k_first;
    let n_epochs = g.epochs();
    // The outputs made whole at once, each block writing its own parts of
    // them (no block's vectors joined on the caller's thread afterwards).
    let (mut t_s, mut phase_err_rad, mut accel_mps2) =
        (vec![0.0; n_epochs], vec![None; n_epochs], vec![[0.0; 3]; n_epochs]);
    let blocks = epoch_blocks(n_epochs);
    let parts = t_s.par_chunks_mut(EPOCH_BLOCK).zip(phase_err_rad.par_chunks_mut(EPOCH_BLOCK));
    parts.zip(accel_mps2.par_chunks_mut(EPOCH_BLOCK)).zip(&blocks).for_each(
        |(((t_out, phase_out), accel_out), epochs)| {
            let mut stamp_idx = grid.k_of_stamp.partition_point(|&k| k < k_first + epochs.start as u64);
            // The IMU sample at or before the first read time (the cursor a
            // pass from the first epoch would have reached).
            let first_read = grid.time(stamps, k_first + epochs.start as u64) + imu_time_offset_s;
            let mut cursor = imu.t_s.partition_point(|&x| x <= first_read).saturating_sub(1);
            let (mut phases, mut weights) = (Vec::new(), Vec::new());
            for (j, e) in epochs.clone().enumerate() {
                let k = k_first + e as u64;
                let t = if grid.k_of_stamp.get(stamp_idx) == Some(&k) {
                    stamp_idx += 1;
                    stamps[stamp_idx - 1]
                } else {
                    grid.t0_s + k as f64 * grid.log_interval_s
                };
                t_out[j] = t;
                let rows = &g.entries[g.start[e]..g.start[e + 1]];
                phases.clear();
                weights.clear();
                for &(slot, w, p) in rows {
                    phases.push(p - offsets_rad[slot]);
                    weights.push(w);
                }
                phase_out[j] = average_phase_rad(&phases, &weights);
                accel_out[j] = imu.interpolate_at(t + imu_time_offset_s, &mut cursor);
            }
        },
    );
    Averaged { t_s, phase_err_rad, accel_mps2 }
}

/// Least-squares constant offsets `c` of the additive model `φ_i(k) = s(k) + c_i`
/// (weights `w_ik`), with `s` eliminated: `M c = b`,
/// `M = Σ_k (diag(w_k) − w_k w_kᵀ / W_k)`, `b_i = Σ_k w_ik (φ_ik − φ̄_k)`, `φ̄_k` the
/// weighted mean at epoch `k`. `M` is singular along the indicator vector of
/// each group of tracks connected by shared epochs; the gauge `Σ c_i = 0` over
/// each group is imposed by adding `λ·1_g 1_gᵀ` (b is orthogonal to these
/// vectors, so the solution satisfies the gauge exactly).
///
/// Only the slots with `gauge[i]` enter the gauge of their group (all of the
/// group's when none of them does): a track split at a step by the screening
/// keeps its later segments out of it, so the step does not shift the level
/// of the average (`1_g·u ≠ 0` for the indicator `u` of the gauge slots keeps
/// `M + λ·u uᵀ` regular, and `1_gᵀb = 0` again gives `uᵀc = 0` exactly).
pub(crate) fn channel_offsets(n: usize, start: &[usize], entries: &[(usize, f64, f64)], gauge: &[bool]) -> Vec<f64> {
    // M row-major in a plain array: the sums run epoch after epoch, one
    // update per entry per epoch, the operations of the formula above in
    // its order.
    let mut sums = vec![0.0; n * n];
    let mut b = DVector::<f64>::zeros(n);
    let mut parent: Vec<usize> = (0..n).collect();
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    for e in 0..start.len() - 1 {
        let rows = &entries[start[e]..start[e + 1]];
        let Some(mean) = weighted_mean(rows) else {
            continue;
        };
        let sw = rows.iter().fold(0.0, |sw, &(_, w, _)| sw + w);
        let first = rows[0].0;
        for (r, &(i, wi, pi)) in rows.iter().enumerate() {
            b[i] += wi * (pi - mean);
            sums[i * n + i] += wi - wi * wi / sw;
            for &(j, wj, _) in &rows[r + 1..] {
                let x = wi * wj / sw;
                sums[i * n + j] -= x;
                sums[j * n + i] -= x;
            }
            if i != first {
                let (ri, r0) = (root(&mut parent, i), root(&mut parent, first));
                parent[ri] = r0;
            }
        }
    }
    let mut m = DMatrix::<f64>::from_row_slice(n, n, &sums);
    let trace: f64 = m.trace();
    let lambda = if trace > 0.0 { trace / n as f64 } else { 1.0 };
    let groups: Vec<usize> = (0..n).map(|i| root(&mut parent, i)).collect();
    let in_gauge: Vec<bool> = (0..n).map(|i| gauge[i] || !(0..n).any(|j| groups[j] == groups[i] && gauge[j])).collect();
    for i in 0..n {
        for j in 0..n {
            if groups[i] == groups[j] && in_gauge[i] && in_gauge[j] {
                m[(i, j)] += lambda;
            }
        }
    }
    // M + λ·(group indicators) is symmetric positive definite by construction.
    match m.clone().cholesky() {
        Some(ch) => ch.solve(&b).iter().copied().collect(),
        None => m.lu().solve(&b).map(|x| x.iter().copied().collect()).unwrap_or_else(|| vec![0.0; n]),
    }
}

/// [`average_phase_rad`] of an epoch's entries (slot, weight, phase), read
/// in place: the same sums in the same order, so the same mean to the bit.
#[inline]
fn weighted_mean(rows: &[(usize, f64, f64)]) -> Option<f64> {
    let (mut sum, mut wsum) = (0.0, 0.0);
    for &(_, w, p) in rows {
        if p.is_finite() {
            sum += w * p;
            wsum += w;
        }
    }
    if wsum > 0.0 { Some(sum / wsum) } else { None }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two candidates: the first with rows at epochs 0, 1, 3 (the one at 1
    /// screened out), two segments (split before epoch 3); the second at 0–3
    /// on L5 (scale s = 2 for the test's arithmetic).
    fn two_tracks() -> (Rows, Screened) {
        let rows = Rows {
            track_start: vec![0, 3, 7],
            epoch: vec![vec![0, 1, 3], vec![0, 1, 2, 3]],
            phase: vec![vec![0.1, 0.2, 0.3], vec![1.0, 1.1, 1.2, 1.3]],
            cn0: vec![vec![40.0, 40.0, 30.0], vec![20.0, 20.0, 20.0, 10.0]],
            to_l1: vec![1.0, 2.0],
            startup_end: vec![],
        };
        let mut screened = Screened::none(&rows);
        screened.flags[1] = 1;
        screened.segment[2] = 1;
        screened.segments[0] = 2;
        (rows, screened)
    }

    #[test]
    fn weights_are_the_inverse_scaled_variance() {
        assert_eq!(row_weight(Weighting::Equal, 45.0, 1.0), 1.0);
        assert_eq!(row_weight(Weighting::Equal, 45.0, 2.0), 0.25);
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b;
        assert!(close(row_weight(Weighting::Cn0, 40.0, 1.0), 1e4));
        assert!(close(row_weight(Weighting::Cn0, 30.0, 2.0), 250.0));
    }

    #[test]
    fn the_kept_rows_are_gathered_by_epoch_in_rank_order() {
        let (rows, screened) = two_tracks();
        // The second candidate ranked first: slots 0 (it), 1 and 2 (the first's two segments).
        let g = gather(&rows, &screened, &[1, 0], Weighting::Equal, 5);
        assert_eq!(g.slot_base, [0, 1, 3]);
        assert_eq!((g.slots(), g.epochs()), (3, 5));
        assert_eq!(g.start, [0, 2, 3, 4, 6, 6]);
        let q = 0.25;
        let want = [(0, q, 1.0), (1, 1.0, 0.1), (0, q, 1.1), (0, q, 1.2), (0, q, 1.3), (2, 1.0, 0.3)];
        assert_eq!(g.entries, want);
        let g = gather(&rows, &screened, &[0], Weighting::Cn0, 4);
        let w = |cn0_dbhz| row_weight(Weighting::Cn0, cn0_dbhz, 1.0);
        assert_eq!((g.start, g.entries), (vec![0, 1, 1, 1, 2], vec![(0, w(40.0), 0.1), (1, w(30.0), 0.3)]));
    }

    #[test]
    fn constant_offsets_are_removed_in_the_gauge_of_the_first_segments() {
        // Slot 0 = s + 0.5, slot 1 = s − 0.5 over epochs 0–2; slot 2 (the
        // second segment of slot 1's track) = s + 1.5 at epochs 3–4 beside slot 0.
        let s = [0.1, -0.2, 0.3, 0.05, 0.0];
        let mut entries = Vec::new();
        let mut start = vec![0];
        for (e, s) in s.iter().enumerate() {
            entries.push((0, 1.0, s + 0.5));
            entries.push(if e < 3 { (1, 1.0, s - 0.5) } else { (2, 1.0, s + 1.5) });
            start.push(entries.len());
        }
        let g = Gathered { slot_base: vec![0, 1, 3], start, entries };
        let c = slot_offsets(&g, true);
        for (c, want) in c.iter().zip([0.5, -0.5, 1.5]) {
            assert!((c - want).abs() < 1e-12, "{c} vs {want}");
        }
        assert_eq!(slot_offsets(&g, false), [0.0; 3]);
    }

    #[test]
    fn each_epoch_is_averaged_and_the_imu_read_at_its_time_plus_the_offset() {
        // Grid epochs 0–4 at 0.5 s, stamps at 0, 1, 3, 4 (epoch 2 a gap); the span from k = 1.
        let grid = Grid { t0_s: 0.0, log_interval_s: 0.5, k_of_stamp: vec![0, 1, 3, 4] };
        let stamps = [0.0, 0.5, 1.5, 2.0];
        let span = Span { k_first: 1, k_end: 5 };
        let g = Gathered {
            slot_base: vec![0, 2],
            start: vec![0, 2, 2, 3, 4],
            entries: vec![(0, 1.0, 0.3), (1, 3.0, 0.7), (1, 1.0, 0.2), (0, 1.0, 0.4)],
        };
        let imu = ImuSeries { t_s: vec![0.0, 4.0], accel_mps2: vec![[0.0, 1.0, 2.0], [4.0, 1.0, -2.0]] };
        let a = average(&g, &[0.1, -0.1], (&grid, &stamps, span), &imu, 0.25);
        assert_eq!(a.t_s, [0.5, 1.0, 1.5, 2.0]);
        // (1·0.2 + 3·0.8)/4 = 0.65; nothing; 0.3; 0.3.
        let p: Vec<f64> = a.phase_err_rad.iter().map(|p| p.unwrap_or(f64::NAN)).collect();
        assert!((p[0] - 0.65).abs() < 1e-15 && p[1].is_nan() && (p[2] - 0.3).abs() < 1e-15, "{p:?}");
        assert_eq!(a.phase_err_rad[1], None);
        // Read at t + 0.25: a_x = t + 0.25, a_z = 2 − (t + 0.25).
        assert_eq!(a.accel_mps2[0], [0.75, 1.0, 1.25]);
        assert_eq!(a.accel_mps2[3], [2.25, 1.0, -0.25]);
        let mut a = a;
        a.phase_err_rad = vec![None, Some(1.0), None, Some(2.0)];
        a.trim_to_phases();
        assert_eq!((a.t_s, a.phase_err_rad), (vec![1.0, 1.5, 2.0], vec![Some(1.0), None, Some(2.0)]));
        assert_eq!(a.accel_mps2.len(), 3);
    }
}
