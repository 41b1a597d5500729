//! The estimate that follows every epoch: the batch path's least squares
//! streamed ([`gsens_calib::streaming_calibrator`]) on the channel average of
//! each tracking epoch as it completes.
//!
//! The screen shows it at every epoch; the batch estimate, re-run every few
//! seconds on everything received, brings what needs the whole record (the
//! screening, the time-offset search, the loop test, the noise model) and
//! hands its loop and offset back: [`BatchJob::run`](crate::BatchJob::run)
//! re-streams the epochs under them, and the session catches that stream up
//! to the newest epoch ([`StreamEstimate::advance`]). The difference to the
//! batch estimate on the same data is measured in the crate's tests.

use gsens_calib::{EstimateSettings, streaming_calibrator};
use gsens_core::solve_in_observable_axes;
use gsens_core::{BatchLeastSquares, GammaEstimate, PrefilteredCalibrator};
use gsens_io::{ImuSeries, TrackingRow};

/// One completed tracking epoch: its time \[s\] and the channel average of
/// the phase error \[rad\] (`None`: not every channel of the set present).
pub type Epoch = (f64, Option<f64>);

/// The epochs needed to read the log interval off the stream (the median of
/// their spacings: robust to a missing epoch).
const INTERVAL_EPOCHS: usize = 9;

/// Channel average per tracking epoch over a fixed set of channels, so that
/// a channel coming or going does not step the average.
///
/// The set is the `max_channels` channels in view (passing the C/N0 mask)
/// of highest mean C/N0 so far (the batch path's ranking, by the mean over
/// the session), chosen once the channels in view have not changed for a
/// second (acquisition over); the epochs before are gaps. An epoch with a
/// member missing is a gap (`None`, as the batch path's absent epochs). The
/// set is chosen again when a member has been absent for a second, or when
/// the ranking's top channels differ from it and the channels in view have
/// not changed for a second. The new set's average is shifted to continue
/// the old one's (the channels' constant offsets differ): at the same epoch
/// when the old set is complete there (the common, oscillator part is the
/// same in both: nothing of it steps); else from the old members still
/// present, each less its mean deviation from the average while in the set
/// (the splice errs by that mean's noise); else from the average's last value.
#[derive(Debug, Clone)]
pub struct EpochAverager {
    max_channels: usize,
    min_cn0_dbhz: Option<f64>,
    set: Vec<u32>,
    /// Latest time each member was seen \[s\].
    seen_t_s: Vec<f64>,
    /// Per member: Σ(φ − average) and the count, over the complete epochs.
    deviation: Vec<(f64, u64)>,
    /// The channels in view (passing the mask) at the last epoch, sorted,
    /// and since when they have been the same \[s\].
    in_view: Vec<u32>,
    in_view_since_t_s: f64,
    scratch: Vec<u32>,
    /// Per channel ever seen: (channel, ΣC/N0, rows) for the mean C/N0.
    cn0_sums: Vec<(u32, f64, u64)>,
    /// The open epoch: time and its rows (channel, C/N0, φ).
    open_t_s: Option<f64>,
    open: Vec<(u32, f64, f64)>,
    /// Added to the set's average so it continues across a change of set.
    level_rad: f64,
    last_average_rad: Option<f64>,
}

/// How long the channels in view must stay the same, or a member stay
/// absent, before the set is chosen again \[s\].
const SETTLE_S: f64 = 1.0;

impl EpochAverager {
    /// An averager over at most `max_channels` channels (`None`: all in
    /// view) with C/N0 at least `min_cn0_dbhz`.
    pub fn new(max_channels: Option<usize>, min_cn0_dbhz: Option<f64>) -> Self {
        EpochAverager {
            max_channels: max_channels.unwrap_or(usize::MAX).max(1),
            min_cn0_dbhz,
            set: Vec::with_capacity(16),
            seen_t_s: Vec::with_capacity(16),
            deviation: Vec::with_capacity(16),
            in_view: Vec::with_capacity(32),
            in_view_since_t_s: f64::NEG_INFINITY,
            scratch: Vec::with_capacity(32),
            cn0_sums: Vec::with_capacity(32),
            open_t_s: None,
            open: Vec::with_capacity(32),
            level_rad: 0.0,
            last_average_rad: None,
        }
    }

    /// The channels averaged now.
    pub fn channels(&self) -> &[u32] {
        &self.set
    }

    /// Takes one row (rows come in time order, an epoch's rows together);
    /// returns the previous epoch when this row opens a new one.
    pub fn row(&mut self, row: &TrackingRow) -> Option<Epoch> {
        let closed = match self.open_t_s {
            Some(t) if t != row.t_s => self.close(),
            _ => None,
        };
        self.open_t_s = Some(row.t_s);
        match self.cn0_sums.iter_mut().find(|c| c.0 == row.channel) {
            Some(c) => {
                c.1 += row.cn0_dbhz;
                c.2 += 1;
            }
            None => self.cn0_sums.push((row.channel, row.cn0_dbhz, 1)),
        }
        self.open.push((row.channel, row.cn0_dbhz, row.phase_err_rad));
        closed
    }

    /// Closes the open epoch (at the end of a stream).
    pub fn flush(&mut self) -> Option<Epoch> {
        self.close()
    }

    fn close(&mut self) -> Option<Epoch> {
        let t = self.open_t_s.take()?;
        let mask = self.min_cn0_dbhz;
        self.scratch.clear();
        self.scratch.extend(self.open.iter().filter(|r| mask.is_none_or(|m| r.1 >= m) && r.2.is_finite()).map(|r| r.0));
        self.scratch.sort_unstable();
        if self.scratch != self.in_view {
            std::mem::swap(&mut self.scratch, &mut self.in_view);
            self.in_view_since_t_s = t;
        }
        for (k, c) in self.set.iter().enumerate() {
            if self.open.iter().any(|r| r.0 == *c) {
                self.seen_t_s[k] = t;
            }
        }
        let settled = t - self.in_view_since_t_s >= SETTLE_S;
        let lost = self.seen_t_s.iter().any(|&s| t - s > SETTLE_S);
        // The ranking's top channels (in `scratch`, sorted).
        let mean_cn0 = |c: u32, sums: &[(u32, f64, u64)]| {
            sums.iter().find(|s| s.0 == c).map_or(f64::NEG_INFINITY, |s| s.1 / s.2 as f64)
        };
        self.scratch.clear();
        self.scratch.extend_from_slice(&self.in_view);
        let sums = &self.cn0_sums;
        self.scratch.sort_by(|&a, &b| mean_cn0(b, sums).total_cmp(&mean_cn0(a, sums)));
        self.scratch.truncate(self.max_channels);
        self.scratch.sort_unstable();
        // (The set is kept sorted.)
        let better = settled && self.scratch != self.set;
        if lost || better {
            let old = self.raw_average().map(|o| o + self.level_rad).or_else(|| self.estimated_average());
            self.set.clear();
            self.set.extend_from_slice(&self.scratch);
            self.seen_t_s.clear();
            self.seen_t_s.resize(self.set.len(), t);
            self.deviation.clear();
            self.deviation.resize(self.set.len(), (0.0, 0));
            // The new set continues the old one's level.
            if let (Some(level), Some(new)) = (old.or(self.last_average_rad), self.raw_average()) {
                self.level_rad = level - new;
            }
        }
        let average = self.raw_average().map(|a| a + self.level_rad);
        if let Some(a) = average {
            self.last_average_rad = average;
            for (k, c) in self.set.iter().enumerate() {
                if let Some(r) = self.open.iter().find(|r| r.0 == *c) {
                    self.deviation[k].0 += r.2 - a;
                    self.deviation[k].1 += 1;
                }
            }
        }
        self.open.clear();
        Some((t, average))
    }

    /// The set's (continued) average at the open epoch from the members
    /// present, each less its mean deviation from it.
    fn estimated_average(&self) -> Option<f64> {
        let (mut sum, mut n) = (0.0, 0);
        for (k, c) in self.set.iter().enumerate() {
            let (dev_sum, dev_n) = self.deviation[k];
            if let Some(r) = self.open.iter().find(|r| r.0 == *c && r.2.is_finite())
                && dev_n > 0
            {
                sum += r.2 - dev_sum / dev_n as f64;
                n += 1;
            }
        }
        (n > 0).then(|| sum / n as f64)
    }

    /// The equal-weight mean over the set, when every member is in the open epoch.
    fn raw_average(&self) -> Option<f64> {
        let mut sum = 0.0;
        for c in &self.set {
            let r = self.open.iter().find(|r| r.0 == *c)?;
            if !r.2.is_finite() {
                return None;
            }
            sum += r.2;
        }
        (!self.set.is_empty()).then(|| sum / self.set.len() as f64)
    }
}

/// The streamed least-squares estimate over the epochs so far.
#[derive(Debug, Clone)]
pub struct StreamEstimate {
    settings: EstimateSettings,
    imu_time_offset_s: f64,
    calibrator: Option<PrefilteredCalibrator<BatchLeastSquares>>,
    log_interval_s: Option<f64>,
    /// Why there is no calibrator (a loop the interval cannot run).
    error: Option<String>,
    /// Epochs fed so far (an index into the session's epochs).
    next: usize,
    last_fed_t_s: Option<f64>,
    imu_cursor: usize,
}

impl StreamEstimate {
    /// A stream under `settings` (its loop), reading the IMU at epoch time
    /// plus `imu_time_offset_s`.
    pub fn new(settings: EstimateSettings, imu_time_offset_s: f64) -> Self {
        StreamEstimate {
            settings,
            imu_time_offset_s,
            calibrator: None,
            log_interval_s: None,
            error: None,
            next: 0,
            last_fed_t_s: None,
            imu_cursor: 0,
        }
    }

    /// Feeds the epochs of `epochs` not fed yet whose IMU reading is in
    /// `imu` (the IMU has passed the epoch's time). The log interval is read
    /// off the first epochs; a missing epoch is fed as a gap.
    pub fn advance(&mut self, epochs: &[Epoch], imu: &ImuSeries) {
        if self.error.is_some() {
            return;
        }
        let Some(&imu_end) = imu.t_s.last() else { return };
        if self.calibrator.is_none() {
            if epochs.len() < INTERVAL_EPOCHS {
                return;
            }
            let mut d: Vec<f64> = epochs[..INTERVAL_EPOCHS].windows(2).map(|w| w[1].0 - w[0].0).collect();
            let h = gsens_core::stats::median_high_in_place(&mut d);
            match streaming_calibrator(&self.settings, h) {
                Ok(c) => {
                    self.calibrator = Some(c);
                    self.log_interval_s = Some(h);
                }
                Err(e) => {
                    self.error = Some(e.to_string());
                    return;
                }
            }
        }
        let h = self.log_interval_s.expect("set with the calibrator");
        while let Some(&(t, phase)) = epochs.get(self.next) {
            if t + self.imu_time_offset_s > imu_end {
                break;
            }
            // Epochs missing from the stream are gaps of the model's grid.
            if let Some(last) = self.last_fed_t_s {
                let missing = ((t - last) / h).round() as i64 - 1;
                for k in 1..=missing.clamp(0, 1 << 20) {
                    self.feed(last + k as f64 * h, None, imu);
                }
            }
            self.feed(t, phase, imu);
            self.last_fed_t_s = Some(t);
            self.next += 1;
        }
    }

    fn feed(&mut self, t_s: f64, phase_err_rad: Option<f64>, imu: &ImuSeries) {
        // Within the IMU's span: an epoch before its first sample takes that sample.
        let tau = (t_s + self.imu_time_offset_s).max(imu.t_s[0]);
        let a = imu.interpolate_at(tau, &mut self.imu_cursor);
        if let Some(c) = &mut self.calibrator {
            c.feed(&a, phase_err_rad);
        }
    }

    /// The estimate so far over the axes the batch path would keep in its
    /// solve (None before the first epochs, or when the loop cannot run at
    /// the log's interval).
    pub fn estimate(&self) -> Option<GammaEstimate> {
        let c = self.calibrator.as_ref()?;
        let normal = c.calibrator().estimator().normal_equations();
        Some(solve_in_observable_axes(normal, &self.settings.criteria).0)
    }

    /// Why there is no estimate, if the loop cannot run at the log's interval.
    pub fn error(&self) -> Option<&str> {
        self.error.as_deref()
    }

    /// Epochs fed so far.
    pub fn epochs_fed(&self) -> usize {
        self.next
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(t_s: f64, channel: u32, cn0_dbhz: f64, phase_err_rad: f64) -> TrackingRow {
        TrackingRow { t_s, channel, prn: channel + 1, cn0_dbhz, elev_deg: None, phase_err_rad }
    }

    /// Channels with different constant offsets, one of them acquired late,
    /// one lost for 2 s: the average is the common part plus one constant
    /// throughout (no step at any change of set), gaps while the set is
    /// incomplete.
    #[test]
    fn a_change_of_channels_does_not_step_the_average() {
        let mut avg = EpochAverager::new(Some(2), None);
        let common = |t: f64| 0.1 * (2.0 * std::f64::consts::PI * 0.9 * t).sin();
        let mut out = Vec::new();
        for k in 0..800 {
            let t = k as f64 * 0.025;
            // Channel 0 (strongest) from 5 s on, channel 1 lost between 10 s and 12 s.
            let rows = [(0, 48.0, 0.3, t >= 5.0), (1, 45.0, -0.2, !(10.0..12.0).contains(&t)), (2, 42.0, 0.05, true)];
            for (c, cn0, offset, present) in rows {
                if present {
                    out.extend(avg.row(&row(t, c, cn0, common(t) + offset)));
                }
            }
        }
        out.extend(avg.flush());
        let level: Vec<f64> = out.iter().filter_map(|&(t, p)| p.map(|p| p - common(t))).collect();
        assert!(level.len() > 700, "{}", level.len());
        for l in &level {
            assert!((l - level[0]).abs() < 1e-12, "the average stepped: {l} vs {}", level[0]);
        }
        assert_eq!(avg.channels(), &[0, 1]);
        // The first second is acquisition: gaps.
        assert!(out[..40].iter().all(|e| e.1.is_none()));
    }
}
