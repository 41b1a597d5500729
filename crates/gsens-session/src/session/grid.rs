//! The first stage of a session's preparation: the uniform epoch grid of a
//! tracking log and the span of it the IMU covers.

use gsens_io::{ImuSeries, TrackingLog};

use super::{GRID_TOLERANCE, MAX_EPOCHS, overlap_hint};
use crate::error::SessionError;

/// The uniform epoch grid of a tracking log.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Grid {
    pub t0_s: f64,
    pub log_interval_s: f64,
    /// Grid index of each distinct time stamp.
    pub k_of_stamp: Vec<u64>,
}

impl Grid {
    /// Epoch time of grid index `k`: the logged stamp if any, else `t0 + k·T`.
    pub(super) fn time(&self, stamps: &[f64], k: u64) -> f64 {
        match self.k_of_stamp.binary_search(&k) {
            Ok(i) => stamps[i],
            Err(_) => self.t0_s + k as f64 * self.log_interval_s,
        }
    }

    /// Grid indices of the rows of a track whose time stamps are all stamps
    /// of the log, into `ks` (one track's worth, reused from track to track:
    /// all of them at once would be 8 bytes a row of the log).
    pub(super) fn track_ks(&self, stamps: &[f64], t_s: &[f64], ks: &mut Vec<u64>) {
        let mut p = 0usize;
        ks.clear();
        ks.extend(t_s.iter().map(|&t| {
            while stamps[p] < t {
                p += 1;
            }
            debug_assert_eq!(stamps[p], t);
            self.k_of_stamp[p]
        }));
    }

    /// The grid of a log. The median spacing assigns the grid indices (each
    /// spacing rounded to a whole number of intervals, so a slightly wrong
    /// median does not accumulate); a least-squares line through (index, time
    /// stamp) then gives the grid `t0 + k·T`, around which every time stamp must
    /// lie within [`GRID_TOLERANCE`]·T.
    pub(super) fn new(log: &TrackingLog) -> Result<Self, SessionError> {
        let stamps = log.epoch_t_s();
        let lines = log.epoch_line();
        let file = log.source_name();
        let n = stamps.len();
        if n < 2 {
            return Err(SessionError::TooFewEpochs { file: file.to_owned(), epochs: n });
        }
        let mut d: Vec<f64> = stamps.windows(2).map(|w| w[1] - w[0]).collect();
        let median_s = gsens_core::stats::median_in_place(&mut d);
        drop(d);

        let mut k_of_stamp = Vec::with_capacity(n);
        k_of_stamp.push(0u64);
        for i in 1..n {
            let steps = ((stamps[i] - stamps[i - 1]) / median_s).round();
            if steps < 1.0 {
                return Err(SessionError::GridCollision {
                    file: file.to_owned(),
                    line: lines[i],
                    column: log.t_column().clone(),
                    t_s: stamps[i],
                    previous_t_s: stamps[i - 1],
                    previous_line: lines[i - 1],
                    log_interval_s: median_s,
                });
            }
            k_of_stamp.push(k_of_stamp[i - 1] + steps as u64);
        }

        // Least-squares line t = t0 + T·k (times relative to the first stamp).
        let nf = n as f64;
        let k_mean = k_of_stamp.iter().map(|&k| k as f64).sum::<f64>() / nf;
        let y_mean = stamps.iter().map(|&t| t - stamps[0]).sum::<f64>() / nf;
        let (mut sxx, mut sxy) = (0.0, 0.0);
        for (&k, &t) in k_of_stamp.iter().zip(stamps) {
            let dk = k as f64 - k_mean;
            sxx += dk * dk;
            sxy += dk * (t - stamps[0] - y_mean);
        }
        let log_interval_s = sxy / sxx;
        let t0_s = stamps[0] + (y_mean - log_interval_s * k_mean);
        let grid = Grid { t0_s, log_interval_s, k_of_stamp };
        for (i, &t) in stamps.iter().enumerate() {
            let grid_t_s = t0_s + grid.k_of_stamp[i] as f64 * log_interval_s;
            let offset_s = t - grid_t_s;
            if offset_s.abs() > GRID_TOLERANCE * log_interval_s {
                return Err(SessionError::OffGrid {
                    file: file.to_owned(),
                    line: lines[i],
                    column: log.t_column().clone(),
                    t_s: t,
                    offset_s,
                    t0_s,
                    log_interval_s,
                    grid_t_s,
                });
            }
        }
        Ok(grid)
    }
}

/// The grid epochs `k_first ≤ k < k_end` a session covers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Span {
    pub k_first: u64,
    pub k_end: u64,
}

impl Span {
    /// Whether grid epoch `k` lies in the span.
    pub(super) fn contains(&self, k: u64) -> bool {
        k >= self.k_first && k < self.k_end
    }

    /// The number of epochs, `k_end − k_first`.
    pub(super) fn epochs(&self) -> u64 {
        self.k_end - self.k_first
    }

    /// The session's epoch index of grid epoch `k` (in the span).
    pub(super) fn epoch_of(&self, k: u64) -> u32 {
        (k - self.k_first) as u32
    }
}

/// The usable span: the grid epochs (up to the last stamp's) whose IMU read
/// time, epoch time + `imu_time_offset_s`, lies in the IMU's span
/// `[imu_t_s[0], imu_t_s[last]]` (the epoch times are increasing, so it is
/// one run, found by bisection); `None` when there is none.
pub(super) fn usable_span(grid: &Grid, stamps: &[f64], imu_t_s: &[f64], imu_time_offset_s: f64) -> Option<Span> {
    let k_last = *grid.k_of_stamp.last().expect("at least two stamps");
    let imu_first = imu_t_s[0];
    let imu_last = *imu_t_s.last().expect("validated non-empty");
    let read_time = |k: u64| grid.time(stamps, k) + imu_time_offset_s;
    let k_first = partition_point(0, k_last + 1, |k| read_time(k) < imu_first);
    let k_end = partition_point(0, k_last + 1, |k| read_time(k) <= imu_last); // one past the last
    (k_first < k_end).then_some(Span { k_first, k_end })
}

/// [`usable_span`], or the error for logs that do not overlap or a span of
/// more than [`MAX_EPOCHS`] epochs.
pub(super) fn checked_span(
    grid: &Grid,
    stamps: &[f64],
    (imu, imu_name): (&ImuSeries, &str),
    file: &str,
    imu_time_offset_s: f64,
) -> Result<Span, SessionError> {
    let Some(span) = usable_span(grid, stamps, &imu.t_s, imu_time_offset_s) else {
        let imu_first = imu.t_s[0];
        let imu_last = *imu.t_s.last().expect("validated non-empty");
        return Err(SessionError::NoOverlap {
            imu_file: imu_name.to_owned(),
            tracking_file: file.to_owned(),
            imu_start_s: imu_first - imu_time_offset_s,
            imu_end_s: imu_last - imu_time_offset_s,
            imu_time_offset_s,
            tracking_start_s: stamps[0],
            tracking_end_s: *stamps.last().expect("non-empty"),
            hint: overlap_hint(
                (imu_first - imu_time_offset_s, imu_last - imu_time_offset_s),
                (stamps[0], *stamps.last().expect("non-empty")),
            ),
        });
    };
    if span.epochs() > MAX_EPOCHS {
        return Err(SessionError::GridTooLarge {
            file: file.to_owned(),
            epochs: span.epochs(),
            log_interval_s: grid.log_interval_s,
            limit: MAX_EPOCHS,
        });
    }
    Ok(span)
}

/// The first `k` in `[lo, hi)` where `pred` is false (`pred` monotone: true then false); `hi` if none.
fn partition_point(mut lo: u64, mut hi: u64, pred: impl Fn(u64) -> bool) -> u64 {
    while lo < hi {
        let mid = lo + (hi - lo) / 2;
        if pred(mid) { lo = mid + 1 } else { hi = mid }
    }
    lo
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Stamps every 0.25 s (exact in binary) at grid epochs 0–3 and 5–9 (4 is a gap).
    fn quarter_grid() -> (Grid, Vec<f64>) {
        let ks: Vec<u64> = (0..10).filter(|&k| k != 4).collect();
        let stamps = ks.iter().map(|&k| k as f64 * 0.25).collect();
        (Grid { t0_s: 0.0, log_interval_s: 0.25, k_of_stamp: ks }, stamps)
    }

    #[test]
    fn an_epoch_time_is_its_stamp_or_the_grid_time_in_a_gap() {
        let (mut grid, mut stamps) = quarter_grid();
        stamps[2] = 0.5 + 0.01; // a jittered stamp is kept as logged
        grid.t0_s = 0.001;
        assert_eq!(grid.time(&stamps, 2), 0.51);
        assert_eq!(grid.time(&stamps, 4), 0.001 + 4.0 * 0.25);
        let mut ks = Vec::new();
        grid.track_ks(&stamps, &[0.25, 1.25, 2.25], &mut ks);
        assert_eq!(ks, [1, 5, 9]);
    }

    #[test]
    fn the_span_is_the_epochs_whose_imu_read_time_lies_in_the_imus_span() {
        let (grid, stamps) = quarter_grid();
        // IMU over [0.6, 1.9] s: epochs 0.75 … 1.75 s, grid indices 3 … 7.
        let imu = [0.6, 1.0, 1.9];
        assert_eq!(usable_span(&grid, &stamps, &imu, 0.0), Some(Span { k_first: 3, k_end: 8 }));
        // The IMU stamps 0.5 s late: read at t + 0.5 ∈ [0.6, 1.9], t ∈ [0.1, 1.4] → k 1 … 5.
        assert_eq!(usable_span(&grid, &stamps, &imu, 0.5), Some(Span { k_first: 1, k_end: 6 }));
        // Bounds included: [0.75, 1.75] exactly.
        assert_eq!(usable_span(&grid, &stamps, &[0.75, 1.75], 0.0), Some(Span { k_first: 3, k_end: 8 }));
        assert_eq!(usable_span(&grid, &stamps, &[3.0, 4.0], 0.0), None);
        let span = Span { k_first: 3, k_end: 8 };
        assert_eq!((span.epochs(), span.epoch_of(5)), (5, 2));
        assert!(span.contains(3) && span.contains(7) && !span.contains(8) && !span.contains(2));
    }

    #[test]
    fn partition_point_finds_the_first_false() {
        assert_eq!(partition_point(0, 10, |k| k < 4), 4);
        assert_eq!(partition_point(0, 10, |_| true), 10);
        assert_eq!(partition_point(3, 10, |_| false), 3);
    }
}
