//! Session preparation: the epoch grid, the selection, the averaging and the
//! IMU interpolation (documented at the crate root).

use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;
use std::borrow::Cow;
use std::path::Path;

use serde::{Deserialize, Serialize};

use gsens_core::average_phase_rad;
use gsens_core::units::Decimal;
use gsens_io::{ImuSeries, TrackingLog, read_imu_file, read_tracking_file};

use crate::error::SessionError;
use crate::screening::{self, ExcludedSpan, Rows, Screened, ScreeningConfig, TrackScreening};

/// The most epochs (gaps included) a prepared session may hold.
pub const MAX_EPOCHS: u64 = 1 << 25;

/// Relative tolerance of a time stamp around the epoch grid (fraction of the log interval).
pub const GRID_TOLERANCE: f64 = 0.1;

/// How the phase errors of the selected channels are weighted in the per-epoch
/// average. The phases are averaged on L1's scale (each scaled by
/// s = f_L1/f_c, [`gsens_io::Carrier::scale_to_l1`]), which scales their
/// thermal noise by s too: both weightings divide by s², so the weight stays
/// the inverse of the scaled variance (for an all-L1 log s = 1 and nothing
/// changes).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Weighting {
    /// Equal weights on one carrier (the paper): `w = 1/s²`, channels assumed
    /// to have equal raw noise.
    #[default]
    Equal,
    /// Weights ∝ C/N0 as a ratio over s², `10^(cn0_dbhz/10)/s²`: the inverse of
    /// the scaled thermal phase variance `s²·Bn/(C/N0)` (squaring loss
    /// neglected), per row.
    Cn0,
}

/// Below this spread of the candidates' mean C/N0 \[dB\] C/N0 does not rank
/// them: it is the resolution receivers log C/N0 at (PocketSDR's `$CH`
/// lines carry one decimal), so a smaller spread is a constant column or
/// the logging's rounding, not a difference in signal strength.
pub const CN0_RANKING_RESOLUTION_DB: f64 = 0.1;

/// How the tracks were ranked for [`SelectionConfig::max_channels`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ChannelRanking {
    /// By mean C/N0 over the rows kept, highest first (the paper's choice).
    Cn0,
    /// By measured noise, lowest first: the screening's robust σ of each
    /// track's deviation from the others ([`TrackScreening::deviation_sigma_rad`]),
    /// because the candidates' mean C/N0 spread less than
    /// [`CN0_RANKING_RESOLUTION_DB`] (a constant C/N0 column ranks nothing).
    Noise,
}

/// Which channels enter the average, and how.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct SelectionConfig {
    /// Use at most this many tracks, those with the highest mean C/N0 (after
    /// the masks), or the least noisy where C/N0 does not vary
    /// ([`ChannelRanking`]); `None`: all that pass the masks. Default
    /// `Some(DEFAULT_CHANNELS)`.
    pub max_channels: Option<usize>,
    /// Drop the rows whose C/N0 is below this [dB-Hz]. Default `None`.
    pub min_cn0_dbhz: Option<f64>,
    /// Drop the rows whose elevation is below this \[deg\]; rows of unknown
    /// elevation pass. Default `None`.
    pub elevation_mask_deg: Option<f64>,
    /// The weights of the per-epoch average. Default [`Weighting::Equal`].
    pub weighting: Weighting,
    /// Estimate and remove a constant phase offset per track before averaging,
    /// so that channels coming and going do not step the average (see the
    /// [crate documentation](crate#averaging)). Default `true`.
    pub remove_channel_offsets: bool,
    /// Per-track screening for cycle slips, losses of lock, C/N0 drops and
    /// rows beyond the discriminator's linear range, before the ranking and
    /// the averaging (see the [crate documentation](crate#screening)). Default on.
    pub screening: ScreeningConfig,
}

/// How many channels enter the average by default: 4, the paper's.
pub const DEFAULT_CHANNELS: usize = 4;

impl Default for SelectionConfig {
    fn default() -> Self {
        SelectionConfig {
            max_channels: Some(DEFAULT_CHANNELS),
            min_cn0_dbhz: None,
            elevation_mask_deg: None,
            weighting: Weighting::Equal,
            remove_channel_offsets: true,
            screening: ScreeningConfig::default(),
        }
    }
}

/// What became of one track (one channel, one PRN) of the tracking log.
///
/// Exhaustive (no `#[non_exhaustive]`): callers outside the crate build it
/// with struct literals (e.g. the report's test fixtures).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ChannelSummary {
    /// Receiver channel number.
    pub channel: u32,
    /// Satellite PRN.
    pub prn: u32,
    /// Mean C/N0 [dB-Hz] over the rows counted in `epochs`; when none is, over
    /// the rows in the usable span, or else over all the track's rows.
    pub mean_cn0_dbhz: f64,
    /// Number of rows in the usable span that pass the masks and the
    /// screening (the epochs the track contributes to when used).
    pub epochs: usize,
    /// Whether the track enters the average.
    pub used: bool,
    /// `"used"`, or why the track is excluded.
    pub reason: String,
    /// The constant phase offset removed from the track \[rad\] (used tracks with
    /// [`SelectionConfig::remove_channel_offsets`]), else `None`. For a track
    /// split at a step by the screening: the offset of its first segment (all
    /// of them in `screening.segment_offsets_rad`).
    pub phase_offset_rad: Option<f64>,
    /// What the screening excluded from the track's rows that pass the masks, and why.
    pub screening: TrackScreening,
    /// The track's signal, [`gsens_io::Carrier::label`]: `L1CA`, `G1:+3`, or the
    /// carrier in MHz where the log does not name it (`1575.42 MHz` for a log
    /// without carrier columns).
    pub signal: String,
    /// The track's carrier \[Hz\]: its phase error enters the screening and the
    /// average scaled by f_L1/carrier_hz.
    pub carrier_hz: f64,
}

/// The tracks of one signal (one carrier) in a session.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SignalSummary {
    /// The signal, as in [`ChannelSummary::signal`].
    pub signal: String,
    /// Its carrier \[Hz\].
    pub carrier_hz: f64,
    /// The factor its phase errors are scaled by, f_L1/carrier_hz.
    pub scale_to_l1: f64,
    /// Tracks of the log on this signal.
    pub tracks: usize,
    /// Of them, those in the average.
    pub tracks_used: usize,
}

/// The inputs of the estimator, on a uniform epoch grid.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct PreparedSession {
    /// The log interval `T` \[s\]: the slope of the epoch grid (for a log without
    /// jitter, the spacing of the tracking time stamps).
    pub log_interval_s: f64,
    /// Epoch times \[s\]: the logged time stamp, or the grid time `t0 + k·T` in
    /// gaps. Consecutive epochs are one log interval apart (up to the time
    /// stamps' jitter, at most 10% of the interval).
    pub t_s: Vec<f64>,
    /// Averaged phase error of the selected channels \[rad\]; `None` where no
    /// selected channel is present.
    pub phase_err_rad: Vec<Option<f64>>,
    /// Specific force [m/s²] interpolated at each epoch, IMU body frame.
    pub accel_mps2: Vec<[f64; 3]>,
    /// Every track of the log, sorted by channel then PRN, with whether it is used.
    pub channels: Vec<ChannelSummary>,
    /// The signals of the log's tracks, in order of carrier (highest first) then
    /// name: which took part in the average, with how many tracks.
    pub signals: Vec<SignalSummary>,
    /// The selection settings used.
    pub selection: SelectionConfig,
    /// How the tracks were ranked for the `max_channels` cut.
    pub channel_ranking: ChannelRanking,
    /// The IMU time offset used \[s\] (IMU time stamp minus true time).
    pub imu_time_offset_s: f64,
}

impl PreparedSession {
    /// Number of epochs.
    pub fn len(&self) -> usize {
        self.t_s.len()
    }

    /// `true` when there is no epoch (never the case for a session from [`prepare_session`]).
    pub fn is_empty(&self) -> bool {
        self.t_s.is_empty()
    }

    /// Number of epochs that have a phase error.
    pub fn epochs_with_phase(&self) -> usize {
        self.phase_err_rad.iter().filter(|p| p.is_some()).count()
    }
}

/// The uniform epoch grid of a tracking log.
struct Grid {
    t0_s: f64,
    log_interval_s: f64,
    /// Grid index of each distinct time stamp.
    k_of_stamp: Vec<u64>,
}

impl Grid {
    /// Epoch time of grid index `k`: the logged stamp if any, else `t0 + k·T`.
    fn time(&self, stamps: &[f64], k: u64) -> f64 {
        match self.k_of_stamp.binary_search(&k) {
            Ok(i) => stamps[i],
            Err(_) => self.t0_s + k as f64 * self.log_interval_s,
        }
    }

    /// Grid indices of the rows of a track whose time stamps are all stamps
    /// of the log, into `ks` (one track's worth, reused from track to track:
    /// all of them at once would be 8 bytes a row of the log).
    fn track_ks(&self, stamps: &[f64], t_s: &[f64], ks: &mut Vec<u64>) {
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
    fn new(log: &TrackingLog) -> Result<Self, SessionError> {
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

/// Per-track bookkeeping of the selection.
struct TrackStats {
    in_span: usize,
    above_mask: usize,
    passing: usize,
    cn0_sum_passing: f64,
    cn0_sum_span: f64,
}

/// Reads both files and prepares the session: [`read_tracking_file`],
/// [`read_imu_file`], then [`prepare_session`].
pub fn prepare_session_files(
    tracking_path: impl AsRef<Path>,
    imu_path: impl AsRef<Path>,
    selection: &SelectionConfig,
    imu_time_offset_s: f64,
) -> Result<PreparedSession, SessionError> {
    let tracking = read_tracking_file(tracking_path)?;
    let imu = read_imu_file(imu_path.as_ref())?;
    prepare_session(&tracking, &imu, &imu_path.as_ref().display().to_string(), selection, imu_time_offset_s)
}

/// Builds the estimator's inputs from a tracking log and an IMU series (see the
/// [crate documentation](crate) for the epoch grid, the selection, the averaging and
/// the interpolation).
///
/// `imu_name` names the IMU source in errors; `imu_time_offset_s` is the IMU
/// time stamp minus true time \[s\] (0 when the clocks agree).
///
/// Errors: fewer than two tracking epochs, a time stamp off the grid, an
/// invalid IMU series, invalid settings, logs that do not overlap in time, or no
/// channel passing the selection (naming the criterion that excluded each one).
pub fn prepare_session(
    tracking: &TrackingLog,
    imu: &ImuSeries,
    imu_name: &str,
    selection: &SelectionConfig,
    imu_time_offset_s: f64,
) -> Result<PreparedSession, SessionError> {
    prepare_session_from(Cow::Borrowed(tracking), imu, imu_name, selection, imu_time_offset_s)
}

/// What the selection needs of a track once its rows are copied out.
struct TrackMeta {
    channel: u32,
    prn: u32,
    carrier: gsens_io::Carrier,
    mean_cn0_dbhz: f64,
}

/// One track's part of the row table: its epochs, phases and C/N0.
type RowSlices<'a> = (&'a mut [u32], &'a mut [f64], &'a mut [f64]);

/// [`prepare_session`] on a log lent or given: a given log is freed once the
/// rows that pass the masks are copied out, before the screening, so that the
/// log and the screening's per-row arrays are never held at once (the peak
/// memory of an estimate).
pub fn prepare_session_from(
    tracking: Cow<'_, TrackingLog>,
    imu: &ImuSeries,
    imu_name: &str,
    selection: &SelectionConfig,
    imu_time_offset_s: f64,
) -> Result<PreparedSession, SessionError> {
    let file_name = tracking.source_name().to_owned();
    let file = file_name.as_str();
    check_settings(file, selection, imu_time_offset_s)?;
    imu.validate(imu_name)?;
    // The epoch stamps outlive the log (1 % of its size).
    let stamps_of_log = tracking.epoch_t_s().to_vec();
    let stamps = stamps_of_log.as_slice();
    let grid = Grid::new(&tracking)?;
    let k_last = *grid.k_of_stamp.last().expect("at least two stamps");

    // Usable span: the grid epochs whose IMU read time lies in the IMU's span.
    let imu_first = imu.t_s[0];
    let imu_last = *imu.t_s.last().expect("validated non-empty");
    let read_time = |k: u64| grid.time(stamps, k) + imu_time_offset_s;
    let k_first = partition_point(0, k_last + 1, |k| read_time(k) < imu_first);
    let k_end = partition_point(0, k_last + 1, |k| read_time(k) <= imu_last); // one past the last
    if k_first >= k_end {
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
    }
    let n_epochs = k_end - k_first;
    if n_epochs > MAX_EPOCHS {
        return Err(SessionError::GridTooLarge {
            file: file.to_owned(),
            epochs: n_epochs,
            log_interval_s: grid.log_interval_s,
            limit: MAX_EPOCHS,
        });
    }
    let n_epochs = n_epochs as usize;
    let span = (grid.time(stamps, k_first), grid.time(stamps, k_end - 1));

    // Row filter shared by the statistics and the averaging.
    let in_span = |k: u64| k >= k_first && k < k_end;
    let above_mask = |elev: f64| selection.elevation_mask_deg.is_none_or(|m| elev.is_nan() || elev >= m);
    let above_cn0 = |cn0: f64| selection.min_cn0_dbhz.is_none_or(|m| cn0 >= m);

    // Each track on its own, in parallel, each worker with its own buffer of
    // grid indices.
    let stats: Vec<TrackStats> = tracking
        .tracks()
        .par_iter()
        .map_init(Vec::new, |ks, tr| {
            grid.track_ks(stamps, &tr.t_s, ks);
            let mut s = TrackStats { in_span: 0, above_mask: 0, passing: 0, cn0_sum_passing: 0.0, cn0_sum_span: 0.0 };
            for (j, &k) in ks.iter().enumerate() {
                if !in_span(k) {
                    continue;
                }
                let cn0 = tr.cn0_dbhz[j];
                s.in_span += 1;
                s.cn0_sum_span += cn0;
                if !above_mask(tr.elev_deg[j]) {
                    continue;
                }
                s.above_mask += 1;
                if !above_cn0(cn0) {
                    continue;
                }
                s.passing += 1;
                s.cn0_sum_passing += cn0;
            }
            s
        })
        .collect();
    let tracks: Vec<TrackMeta> = tracking
        .tracks()
        .iter()
        .map(|t| TrackMeta { channel: t.channel, prn: t.prn, carrier: t.carrier, mean_cn0_dbhz: t.mean_cn0_dbhz() })
        .collect();

    // The rows passing the masks of every track that has some (the
    // candidates), in one table sized by the masks' counts, each candidate's
    // rows filled on either core.
    let mut candidate_of: Vec<Option<usize>> = vec![None; tracks.len()];
    let mut rows = Rows { track_start: vec![0], ..Rows::default() };
    for (i, s) in stats.iter().enumerate().filter(|(_, s)| s.passing > 0) {
        candidate_of[i] = Some(rows.tracks());
        rows.track_start.push(rows.track_start.last().copied().unwrap_or(0) + s.passing);
        rows.to_l1.push(tracks[i].carrier.scale_to_l1());
    }
    let n_rows = *rows.track_start.last().expect("starts at 0");
    // Zeroed by the allocator (untouched pages), each written once below.
    (rows.epoch, rows.phase, rows.cn0) = (vec![0; n_rows], vec![0.0; n_rows], vec![0.0; n_rows]);
    let mut into: Vec<Option<RowSlices>> = (0..tracks.len()).map(|_| None).collect();
    let candidates = candidate_of.iter().enumerate().filter_map(|(i, c)| c.map(|_| i));
    let starts = &rows.track_start;
    let (epoch, phase) = (screening::per_track(&mut rows.epoch, starts), screening::per_track(&mut rows.phase, starts));
    let cn0 = screening::per_track(&mut rows.cn0, starts);
    for (i, ((epoch, phase), cn0)) in candidates.zip(epoch.into_iter().zip(phase).zip(cn0)) {
        into[i] = Some((epoch, phase, cn0));
    }
    // The start-up ends startup_s after a track's first row in the log
    // (which may precede the usable span).
    let startup_epochs = (selection.screening.startup_s / grid.log_interval_s).round() as u64;
    let take_rows = |ks: &mut Vec<u64>, tr: &gsens_io::ChannelTrack, to: RowSlices| {
        grid.track_ks(stamps, &tr.t_s, ks);
        let to_l1 = tr.carrier.scale_to_l1();
        let mut r = 0;
        for (j, &k) in ks.iter().enumerate() {
            if in_span(k) && above_mask(tr.elev_deg[j]) && above_cn0(tr.cn0_dbhz[j]) {
                to.0[r] = (k - k_first) as u32;
                to.1[r] = tr.phase_err_rad[j] * to_l1;
                to.2[r] = tr.cn0_dbhz[j];
                r += 1;
            }
        }
        (ks[0] + startup_epochs).saturating_sub(k_first).min(u32::MAX as u64) as u32
    };
    let startup_end: Vec<Option<u32>> = match tracking {
        // An owned log is freed track by track as its rows are taken, so that
        // the log and the row table are never both whole in memory.
        Cow::Owned(log) => log
            .into_tracks()
            .into_par_iter()
            .zip(into)
            .map_init(Vec::new, |ks, (tr, to)| to.map(|to| take_rows(ks, &tr, to)))
            .collect(),
        // A borrowed one stays with its owner.
        Cow::Borrowed(log) => log
            .tracks()
            .par_iter()
            .zip(into)
            .map_init(Vec::new, |ks, (tr, to)| to.map(|to| take_rows(ks, tr, to)))
            .collect(),
    };
    rows.startup_end = startup_end.into_iter().flatten().collect();
    let screened = if selection.screening.enabled {
        screening::screen(&rows, n_epochs, grid.log_interval_s, &selection.screening)
    } else {
        Screened::none(&rows)
    };
    // Per candidate: rows kept by the screening and their C/N0 sum.
    let kept: Vec<(usize, f64)> = (0..rows.tracks())
        .map(|c| {
            (rows.track_start[c]..rows.track_start[c + 1])
                .filter(|&r| screened.flags[r] == 0)
                .fold((0, 0.0), |(n, sum), r| (n + 1, sum + rows.cn0[r]))
        })
        .collect();
    let kept_of = |i: usize| candidate_of[i].map_or((0, 0.0), |c| kept[c]);

    // Rank the candidates by mean C/N0 over the rows they keep (ties: channel, PRN).
    let mean_cn0 = |i: usize| {
        let s = &stats[i];
        let (n_kept, cn0_kept) = kept_of(i);
        if n_kept > 0 {
            cn0_kept / n_kept as f64
        } else if s.passing > 0 {
            s.cn0_sum_passing / s.passing as f64
        } else if s.in_span > 0 {
            s.cn0_sum_span / s.in_span as f64
        } else {
            tracks[i].mean_cn0_dbhz
        }
    };
    let mut ranked: Vec<usize> = (0..tracks.len()).filter(|&i| kept_of(i).0 > 0).collect();
    // Where C/N0 does not vary between the candidates, their measured noise
    // ranks them (a track without a σ, never compared with two others, last).
    let noise_of =
        |i: usize| candidate_of[i].and_then(|c| screened.summaries[c].deviation_sigma_rad).unwrap_or(f64::INFINITY);
    let spread_db = ranked
        .iter()
        .map(|&i| mean_cn0(i))
        .fold(None, |r: Option<(f64, f64)>, v| Some(r.map_or((v, v), |(lo, hi)| (lo.min(v), hi.max(v)))));
    let noise_known = ranked.iter().any(|&i| noise_of(i).is_finite());
    let channel_ranking = match spread_db {
        Some((lo, hi)) if ranked.len() > 1 && hi - lo < CN0_RANKING_RESOLUTION_DB && noise_known => {
            ChannelRanking::Noise
        }
        _ => ChannelRanking::Cn0,
    };
    ranked.sort_by(|&a, &b| {
        match channel_ranking {
            ChannelRanking::Cn0 => mean_cn0(b).total_cmp(&mean_cn0(a)),
            ChannelRanking::Noise => noise_of(a).total_cmp(&noise_of(b)),
        }
        .then(tracks[a].channel.cmp(&tracks[b].channel))
        .then(tracks[a].prn.cmp(&tracks[b].prn))
    });
    let n_used = selection.max_channels.map_or(ranked.len(), |n| n.min(ranked.len()));
    let mut reasons: Vec<String> = vec![String::new(); tracks.len()];
    let mut used = vec![false; tracks.len()];
    for (rank, &i) in ranked.iter().enumerate() {
        if rank < n_used {
            used[i] = true;
            reasons[i] = "used".to_owned();
        } else {
            reasons[i] = match channel_ranking {
                ChannelRanking::Cn0 => format!(
                    "not among the {} strongest (mean C/N0 {:.1} dB-Hz, rank {})",
                    n_used,
                    mean_cn0(i),
                    rank + 1
                ),
                ChannelRanking::Noise => format!(
                    "not among the {} least noisy (C/N0 does not vary between the tracks; deviation σ {:.4} rad, \
                     rank {})",
                    n_used,
                    noise_of(i),
                    rank + 1
                ),
            };
        }
    }
    for (i, s) in stats.iter().enumerate() {
        if s.in_span == 0 {
            reasons[i] = format!(
                "no rows in the usable span [{}, {}] s (overlap with the IMU)",
                Decimal(span.0),
                Decimal(span.1)
            );
        } else if s.above_mask == 0 {
            reasons[i] = format!(
                "all {} rows in the usable span below the elevation mask of {} deg",
                s.in_span,
                selection.elevation_mask_deg.unwrap_or(f64::NAN)
            );
        } else if s.passing == 0 {
            reasons[i] = format!(
                "all {} rows in the usable span (above the elevation mask) below the C/N0 threshold of {} dB-Hz",
                s.above_mask,
                selection.min_cn0_dbhz.unwrap_or(f64::NAN)
            );
        } else if kept_of(i).0 == 0 {
            reasons[i] = format!("all {} rows passing the masks excluded by the screening", s.passing);
        }
    }
    if n_used == 0 {
        let mut order: Vec<usize> = (0..tracks.len()).collect();
        order.sort_by_key(|&i| (tracks[i].channel, tracks[i].prn, i));
        let detail: Vec<String> = order
            .iter()
            .map(|&i| format!("channel {} (PRN {}): {}", tracks[i].channel, tracks[i].prn, reasons[i]))
            .collect();
        return Err(SessionError::NoChannelSelected { file: file.to_owned(), reason: detail.join("; ") });
    }

    // Gather the kept rows of the used tracks by epoch (compressed rows: slot,
    // weight, phase). A slot is one segment of a track (the screening splits
    // tracks at steps), each with its own offset.
    let selected: Vec<usize> = ranked[..n_used].to_vec();
    // Inverse of the scaled variance: s = f_L1/f_c scales the noise by s.
    let weight = |cn0_dbhz: f64, to_l1: f64| match selection.weighting {
        Weighting::Equal => 1.0 / (to_l1 * to_l1),
        Weighting::Cn0 => gsens_core::units::cn0_dbhz_to_ratio_hz(cn0_dbhz) / (to_l1 * to_l1),
    };
    let selected_candidates: Vec<usize> =
        selected.iter().map(|&i| candidate_of[i].expect("a ranked track is a candidate")).collect();
    let mut slot_base = Vec::with_capacity(selected.len() + 1);
    slot_base.push(0usize);
    for &c in &selected_candidates {
        slot_base.push(slot_base.last().copied().unwrap_or(0) + screened.segments[c]);
    }
    let n_slots = *slot_base.last().expect("non-empty");
    // The epochs in blocks of EPOCH_BLOCK, the blocks at once: a track's rows
    // in a run of epochs are a run of its rows (in epoch order), and every
    // epoch's entries come out in the order of one pass over the tracks, so
    // the result does not depend on how the blocks are shared out.
    let blocks: Vec<std::ops::Range<usize>> =
        (0..n_epochs).step_by(EPOCH_BLOCK).map(|e0| e0..(e0 + EPOCH_BLOCK).min(n_epochs)).collect();
    let for_each_used_row = |epochs: std::ops::Range<usize>, f: &mut dyn FnMut(usize, usize, f64)| {
        for (sel, &c) in selected_candidates.iter().enumerate() {
            let range = rows.range(c);
            let ep = &rows.epoch[range.clone()];
            let first = range.start + ep.partition_point(|&x| (x as usize) < epochs.start);
            let end = range.start + ep.partition_point(|&x| (x as usize) < epochs.end);
            for r in first..end {
                if screened.flags[r] == 0 {
                    f(slot_base[sel] + screened.segment[r] as usize, r, rows.to_l1[c]);
                }
            }
        }
    };
    let mut start = vec![0usize; n_epochs + 1];
    start[1..].par_chunks_mut(EPOCH_BLOCK).zip(&blocks).for_each(|(counts, epochs)| {
        let e0 = epochs.start;
        for_each_used_row(epochs.clone(), &mut |_, r, _| counts[rows.epoch[r] as usize - e0] += 1);
    });
    for e in 0..n_epochs {
        start[e + 1] += start[e];
    }
    let mut entries = vec![(0usize, 0f64, 0f64); start[n_epochs]];
    {
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
            for_each_used_row(epochs.clone(), &mut |slot, r, to_l1| {
                let e = rows.epoch[r] as usize - e0;
                out[fill[e]] = (slot, weight(rows.cn0[r], to_l1), rows.phase[r]);
                fill[e] += 1;
            });
        });
    }

    let offsets_rad = if selection.remove_channel_offsets && n_slots > 1 {
        let first_segment: Vec<bool> = (0..n_slots).map(|slot| slot_base.contains(&slot)).collect();
        channel_offsets(n_slots, &start, &entries, &first_segment)
    } else {
        vec![0.0; n_slots]
    };

    // Average, interpolate: each epoch on its own, the blocks at once.
    let average = |epochs: std::ops::Range<usize>| {
        let n = epochs.len();
        let (mut t_s, mut phase_err_rad, mut accel_mps2) =
            (Vec::with_capacity(n), Vec::with_capacity(n), Vec::with_capacity(n));
        let mut stamp_idx = grid.k_of_stamp.partition_point(|&k| k < k_first + epochs.start as u64);
        // The IMU sample at or before the first read time (the cursor a
        // pass from the first epoch would have reached).
        let first_read = grid.time(stamps, k_first + epochs.start as u64) + imu_time_offset_s;
        let mut cursor = imu.t_s.partition_point(|&x| x <= first_read).saturating_sub(1);
        let (mut phases, mut weights) = (Vec::new(), Vec::new());
        for e in epochs {
            let k = k_first + e as u64;
            let t = if grid.k_of_stamp.get(stamp_idx) == Some(&k) {
                stamp_idx += 1;
                stamps[stamp_idx - 1]
            } else {
                grid.t0_s + k as f64 * grid.log_interval_s
            };
            t_s.push(t);
            let rows = &entries[start[e]..start[e + 1]];
            phases.clear();
            weights.clear();
            for &(slot, w, p) in rows {
                phases.push(p - offsets_rad[slot]);
                weights.push(w);
            }
            phase_err_rad.push(average_phase_rad(&phases, &weights));
            accel_mps2.push(imu.interpolate_at(t + imu_time_offset_s, &mut cursor));
        }
        (t_s, phase_err_rad, accel_mps2)
    };
    let averaged: Vec<_> = blocks.par_iter().map(|epochs| average(epochs.clone())).collect();
    let (mut t_s, mut phase_err_rad, mut accel_mps2) =
        (Vec::with_capacity(n_epochs), Vec::with_capacity(n_epochs), Vec::with_capacity(n_epochs));
    for (t, phase, accel) in averaged {
        t_s.extend(t);
        phase_err_rad.extend(phase);
        accel_mps2.extend(accel);
    }

    let mut summaries = screened.summaries;
    let mut channels: Vec<ChannelSummary> = (0..tracks.len())
        .map(|i| {
            let sel = selected.iter().position(|&s| s == i).filter(|_| selection.remove_channel_offsets);
            let mut screening = candidate_of[i].map(|c| std::mem::take(&mut summaries[c])).unwrap_or_default();
            if let Some(c) = candidate_of[i] {
                screening.spans = screened.spans[c]
                    .iter()
                    .map(|sp| ExcludedSpan {
                        start_s: t_s[sp.first_epoch as usize],
                        end_s: t_s[sp.last_epoch as usize],
                        rows: sp.rows,
                        reasons: screening::flag::NAMES
                            .iter()
                            .filter(|(bit, _)| sp.flags & bit != 0)
                            .map(|(_, name)| (*name).to_owned())
                            .collect(),
                    })
                    .collect();
            }
            if let Some(s) = sel
                && slot_base[s + 1] - slot_base[s] > 1
            {
                screening.segment_offsets_rad = offsets_rad[slot_base[s]..slot_base[s + 1]].to_vec();
            }
            ChannelSummary {
                channel: tracks[i].channel,
                prn: tracks[i].prn,
                mean_cn0_dbhz: mean_cn0(i),
                epochs: kept_of(i).0,
                used: used[i],
                reason: std::mem::take(&mut reasons[i]),
                phase_offset_rad: sel.map(|s| offsets_rad[slot_base[s]]),
                screening,
                signal: tracks[i].carrier.label(),
                carrier_hz: tracks[i].carrier.carrier_hz,
            }
        })
        .collect();
    channels.sort_by_key(|c| (c.channel, c.prn));
    let signals = signal_summaries(&channels);

    // The session runs from the first to the last epoch with a phase: the
    // epochs outside hold no measurement (e.g. every used track's start-up
    // screened out), and a leading stretch without one would be a gap to the
    // estimator, which then leaves out up to three time constants of its
    // high-pass after it (9.5 s at 0.05 Hz), where its own warm-up suffices.
    let first = phase_err_rad.iter().position(Option::is_some).expect("a used track keeps a row");
    let end = phase_err_rad.iter().rposition(Option::is_some).expect("a used track keeps a row") + 1;
    t_s.truncate(end);
    t_s.drain(..first);
    phase_err_rad.truncate(end);
    phase_err_rad.drain(..first);
    accel_mps2.truncate(end);
    accel_mps2.drain(..first);

    Ok(PreparedSession {
        log_interval_s: grid.log_interval_s,
        t_s,
        phase_err_rad,
        accel_mps2,
        channels,
        signals,
        selection: selection.clone(),
        channel_ranking,
        imu_time_offset_s,
    })
}

/// The tracks per signal: highest carrier first, then by name.
fn signal_summaries(channels: &[ChannelSummary]) -> Vec<SignalSummary> {
    let mut out: Vec<SignalSummary> = Vec::new();
    for c in channels {
        match out.iter_mut().find(|s| s.signal == c.signal && s.carrier_hz == c.carrier_hz) {
            Some(s) => {
                s.tracks += 1;
                s.tracks_used += usize::from(c.used);
            }
            None => out.push(SignalSummary {
                signal: c.signal.clone(),
                carrier_hz: c.carrier_hz,
                scale_to_l1: gsens_core::units::GPS_L1_HZ / c.carrier_hz,
                tracks: 1,
                tracks_used: usize::from(c.used),
            }),
        }
    }
    out.sort_by(|a, b| b.carrier_hz.total_cmp(&a.carrier_hz).then_with(|| a.signal.cmp(&b.signal)));
    out
}

/// Re-interpolates the IMU onto the session's epochs for another IMU time
/// offset (IMU time stamp minus true time) \[s\], keeping the selection and the
/// averaged phases: the average does not depend on the offset, so a search
/// over offsets needs the logs prepared once. Epochs whose IMU read time falls
/// outside the IMU's span get no phase (the specific force is held at the
/// nearest sample so the loop models keep running).
pub fn reinterpolate_imu(session: &mut PreparedSession, imu: &ImuSeries, imu_time_offset_s: f64) {
    let (first, last) = (imu.t_s[0], *imu.t_s.last().expect("a prepared session has IMU samples"));
    let mut cursor = 0;
    for k in 0..session.t_s.len() {
        let tau = session.t_s[k] + imu_time_offset_s;
        if tau < first || tau > last {
            session.phase_err_rad[k] = None;
        }
        session.accel_mps2[k] = imu.interpolate_at(tau.clamp(first, last), &mut cursor);
    }
    session.imu_time_offset_s = imu_time_offset_s;
}

fn check_settings(file: &str, selection: &SelectionConfig, imu_time_offset_s: f64) -> Result<(), SessionError> {
    let fail = |reason: String| Err(SessionError::InvalidSelection { file: file.to_owned(), reason });
    if selection.max_channels == Some(0) {
        return fail("max_channels is 0".to_owned());
    }
    if let Some(v) = selection.min_cn0_dbhz.filter(|v| !v.is_finite()) {
        return fail(format!("min_cn0_dbhz = {v} is not finite"));
    }
    if let Some(v) = selection.elevation_mask_deg.filter(|v| !v.is_finite()) {
        return fail(format!("elevation_mask_deg = {v} is not finite"));
    }
    if !imu_time_offset_s.is_finite() {
        return fail(format!("imu_time_offset_s = {imu_time_offset_s} is not finite"));
    }
    if let Err(error) = selection.screening.validate() {
        return Err(SessionError::InvalidScreening { file: file.to_owned(), error });
    }
    Ok(())
}

/// Unix time minus GPS time at the GPS epoch \[s\]: 1980-01-06 is 3 657 days
/// after 1970-01-01 (GPS time has no leap seconds, UTC has had 18 more since).
const UNIX_MINUS_GPS_S: f64 = 315_964_800.0;

/// Epochs gathered and averaged as one block: the blocks run in parallel,
/// each long enough (minutes of a 40 Hz log) that its per-track searches
/// and hand-out cost little beside its rows.
const EPOCH_BLOCK: usize = 1 << 13;

/// Seconds in a GPS week.
const WEEK_S: f64 = 604_800.0;

/// What clock a log's time stamps `[start, end]` \[s\] look like, from their
/// magnitude: Unix time is ≈ 1.5–2.2·10⁹ s in 2017–2039, GPS time (since
/// 1980-01-06) ≈ 0.9–1.5·10⁹ s in 2008–2027, seconds of the GPS week lie in
/// [0, 604 800), an absolute clock in milliseconds is beyond 10¹¹.
fn clock_base(start: f64, end: f64) -> &'static str {
    match start {
        s if s >= 1e11 => "an absolute clock in milliseconds or finer (Unix time in seconds is about 1.7e9)",
        s if (1.5e9..2.2e9).contains(&s) => "Unix time (seconds since 1970-01-01)",
        s if (0.9e9..1.5e9).contains(&s) => "GPS time (seconds since 1980-01-06)",
        s if s >= 0.0 && end <= 1.01 * WEEK_S => "GPS seconds of the week or seconds since power-on",
        s if s >= 0.0 => "seconds since power-on, or milliseconds",
        _ => "a clock of unknown base (negative time stamps)",
    }
}

/// Why two logs of one session may not overlap in time, read from their
/// spans `[start, end]` \[s\] (IMU in true time, tracking), and the fix, for
/// [`SessionError::NoOverlap`]: a log in milliseconds (its span 300–3000× the
/// other's, as one session logged in both would be 1000×), clocks on
/// different bases (the magnitudes of the stamps differ: Unix time ≈ 1.7·10⁹ s,
/// GPS time ≈ 1.4·10⁹ s, seconds of the week below 604 800; Unix
/// and GPS time 315 964 800 s less the leap seconds apart), or logs of
/// different sessions.
pub fn overlap_hint(imu: (f64, f64), tracking: (f64, f64)) -> String {
    let (imu_len, trk_len) = (imu.1 - imu.0, tracking.1 - tracking.0);
    let ratio = imu_len / trk_len;
    let delta = imu.0 - tracking.0;
    let fix = format!(
        "Both logs must be stamped by one clock, in seconds: convert one log's t_s (if they started \
         together, the IMU starts {delta:.3} s after the tracking); a time offset is for a small delay \
         between the clocks, not for a clock base"
    );
    let (imu_base, trk_base) = (clock_base(imu.0, imu.1), clock_base(tracking.0, tracking.1));
    let cause = if trk_len > 0.0 && (300.0..3000.0).contains(&ratio) {
        format!(
            "Likely cause: the IMU's t_s are in milliseconds (its span is {ratio:.0}× the tracking's); \
             divide them by 1000"
        )
    } else if imu_len > 0.0 && (300.0..3000.0).contains(&(1.0 / ratio)) {
        format!(
            "Likely cause: the tracking's t_s are in milliseconds (its span is {:.0}× the IMU's); \
             divide them by 1000",
            1.0 / ratio
        )
    } else if (delta.abs() - UNIX_MINUS_GPS_S).abs() < 60.0 {
        format!(
            "Likely cause: one log is in Unix time and the other in GPS time: they are {delta:.0} s apart, \
             the {UNIX_MINUS_GPS_S:.0} s between the two epochs less the leap seconds (18 since 2017)"
        )
    } else if imu_base != trk_base {
        format!(
            "Likely cause: the clocks have different bases: the IMU's t_s look like {imu_base}, the tracking's like {trk_base}"
        )
    } else {
        format!(
            "Both look like {imu_base}: are they logs of the same session? If so, the clocks differ by \
             {delta:.3} s"
        )
    };
    format!("{cause}. {fix}.")
}

/// The first `k` in `[lo, hi)` where `pred` is false (`pred` monotone: true then false); `hi` if none.
fn partition_point(mut lo: u64, mut hi: u64, pred: impl Fn(u64) -> bool) -> u64 {
    while lo < hi {
        let mid = lo + (hi - lo) / 2;
        if pred(mid) { lo = mid + 1 } else { hi = mid }
    }
    lo
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
    let mut m = DMatrix::<f64>::zeros(n, n);
    let mut b = DVector::<f64>::zeros(n);
    let mut parent: Vec<usize> = (0..n).collect();
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    let (mut phases, mut weights) = (Vec::new(), Vec::new());
    for e in 0..start.len() - 1 {
        let rows = &entries[start[e]..start[e + 1]];
        phases.clear();
        weights.clear();
        phases.extend(rows.iter().map(|&(_, _, p)| p));
        weights.extend(rows.iter().map(|&(_, w, _)| w));
        let Some(mean) = average_phase_rad(&phases, &weights) else {
            continue;
        };
        let sw = weights.iter().fold(0.0, |sw, w| sw + w);
        for (r, &(i, wi, pi)) in rows.iter().enumerate() {
            b[i] += wi * (pi - mean);
            m[(i, i)] += wi - wi * wi / sw;
            for &(j, wj, _) in &rows[r + 1..] {
                let x = wi * wj / sw;
                m[(i, j)] -= x;
                m[(j, i)] -= x;
            }
            let (ri, r0) = (root(&mut parent, i), root(&mut parent, rows[0].0));
            parent[ri] = r0;
        }
    }
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

#[cfg(test)]
mod tests;
