//! The second stage of a session's preparation: the rows of the log that
//! pass the span and the masks, taken track by track into the screening's
//! row table (a log given to the session converted in place).

use rayon::prelude::*;
use std::borrow::Cow;

use gsens_io::{ChannelTrack, TrackingLog};

use super::SelectionConfig;
use super::grid::{Grid, Span};
use crate::screening::Rows;

/// Which rows of the log enter the session: those in the usable span, at or
/// above the elevation mask (unknown elevation passes) and at or above the
/// C/N0 threshold.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct RowFilter {
    pub span: Span,
    pub elevation_mask_deg: Option<f64>,
    pub min_cn0_dbhz: Option<f64>,
}

/// Per-track bookkeeping of the selection: the track's rows in the span, of
/// them those above the elevation mask, of them those above the C/N0
/// threshold (passing), and the C/N0 sums over the first and the last.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(super) struct TrackStats {
    pub in_span: usize,
    pub above_mask: usize,
    pub passing: usize,
    pub cn0_sum_passing: f64,
    pub cn0_sum_span: f64,
}

/// What the selection needs of a track once its rows are copied out.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct TrackMeta {
    pub channel: u32,
    pub prn: u32,
    pub carrier: gsens_io::Carrier,
    pub mean_cn0_dbhz: f64,
}

/// The log's tracks and the rows of those with rows passing the filter (the
/// candidates).
#[derive(Debug)]
pub(super) struct Candidates {
    /// Every track of the log, in the log's order.
    pub tracks: Vec<TrackMeta>,
    /// Per track: its counts under the filter.
    pub stats: Vec<TrackStats>,
    /// Per track: its index among the candidates, if it is one.
    pub candidate_of: Vec<Option<usize>>,
    /// The candidates' passing rows, epochs counted from the span's first.
    pub rows: Rows,
}

/// One track's rows in the row table: its epochs, phases and C/N0, and the
/// epoch where its start-up ends.
type TrackRows = (Vec<u32>, Vec<f64>, Vec<f64>, u32);

impl RowFilter {
    /// The filter of `selection`'s masks over `span`.
    pub(super) fn new(span: Span, selection: &SelectionConfig) -> Self {
        RowFilter { span, elevation_mask_deg: selection.elevation_mask_deg, min_cn0_dbhz: selection.min_cn0_dbhz }
    }

    fn above_mask(&self, elev_deg: f64) -> bool {
        self.elevation_mask_deg.is_none_or(|m| elev_deg.is_nan() || elev_deg >= m)
    }

    fn above_cn0(&self, cn0_dbhz: f64) -> bool {
        self.min_cn0_dbhz.is_none_or(|m| cn0_dbhz >= m)
    }

    /// Whether the row at grid epoch `k` with this elevation and C/N0 passes.
    pub(super) fn passes(&self, k: u64, elev_deg: f64, cn0_dbhz: f64) -> bool {
        self.span.contains(k) && self.above_mask(elev_deg) && self.above_cn0(cn0_dbhz)
    }

    /// The counts of a track whose rows lie at grid epochs `ks`.
    pub(super) fn stats(&self, ks: &[u64], track: &ChannelTrack) -> TrackStats {
        let mut s = TrackStats::default();
        for (j, &k) in ks.iter().enumerate() {
            if !self.span.contains(k) {
                continue;
            }
            let cn0 = track.cn0_dbhz[j];
            s.in_span += 1;
            s.cn0_sum_span += cn0;
            if !self.above_mask(track.elev_deg[j]) {
                continue;
            }
            s.above_mask += 1;
            if !self.above_cn0(cn0) {
                continue;
            }
            s.passing += 1;
            s.cn0_sum_passing += cn0;
        }
        s
    }

    /// The passing rows of `track` (at grid epochs `ks`; `passing` of
    /// them), the phases scaled to L1 (f_L1/f_c), and the epoch, counted
    /// from the span's first, where its start-up ends: `startup_epochs`
    /// after its first row in the log (which may precede the span), 0 when
    /// that lies before the span. A track given is converted in place: its
    /// phase and C/N0 columns become the rows' (a row's index never passes
    /// its index in the log), the rest of it is freed.
    fn take_rows(&self, ks: &[u64], track: Cow<'_, ChannelTrack>, passing: usize, startup_epochs: u64) -> TrackRows {
        let to_l1 = track.carrier.scale_to_l1();
        let startup_end = (ks[0] + startup_epochs).saturating_sub(self.span.k_first).min(u32::MAX as u64) as u32;
        let mut epoch = Vec::with_capacity(passing);
        let (phase, cn0) = match track {
            Cow::Owned(ChannelTrack { phase_err_rad: mut phase, cn0_dbhz: mut cn0, elev_deg, .. }) => {
                for (j, &k) in ks.iter().enumerate() {
                    if self.passes(k, elev_deg[j], cn0[j]) {
                        let r = epoch.len();
                        epoch.push(self.span.epoch_of(k));
                        phase[r] = phase[j] * to_l1;
                        cn0[r] = cn0[j];
                    }
                }
                phase.truncate(epoch.len());
                cn0.truncate(epoch.len());
                (phase, cn0)
            }
            Cow::Borrowed(track) => {
                let (mut phase, mut cn0) = (Vec::with_capacity(passing), Vec::with_capacity(passing));
                for (j, &k) in ks.iter().enumerate() {
                    if self.passes(k, track.elev_deg[j], track.cn0_dbhz[j]) {
                        epoch.push(self.span.epoch_of(k));
                        phase.push(track.phase_err_rad[j] * to_l1);
                        cn0.push(track.cn0_dbhz[j]);
                    }
                }
                (phase, cn0)
            }
        };
        (epoch, phase, cn0, startup_end)
    }
}

/// The candidates of `tracking` under `filter`: every track's counts, then
/// the passing rows of the tracks that have some, the tracks in parallel.
/// A given log is converted track by track into the row table (its phase
/// and C/N0 columns kept, the rest freed), so that no copy of its rows is
/// made. `startup_s`: the start-up's length after a track's first row
/// (`ScreeningConfig::startup_s`).
pub(super) fn candidates(
    tracking: Cow<'_, TrackingLog>,
    grid: &Grid,
    stamps: &[f64],
    filter: &RowFilter,
    startup_s: f64,
) -> Candidates {
    // Each track on its own, in parallel, each worker with its own buffer of
    // grid indices.
    let stats: Vec<TrackStats> = tracking
        .tracks()
        .par_iter()
        .map_init(Vec::new, |ks, tr| {
            grid.track_ks(stamps, &tr.t_s, ks);
            filter.stats(ks, tr)
        })
        .collect();
    // Each track's mean C/N0 on its own, the tracks in parallel.
    let tracks: Vec<TrackMeta> = tracking
        .tracks()
        .par_iter()
        .map(|t| TrackMeta { channel: t.channel, prn: t.prn, carrier: t.carrier, mean_cn0_dbhz: t.mean_cn0_dbhz() })
        .collect();
    let (mut rows, candidate_of) = row_table(&stats, &tracks);
    let startup_epochs = (startup_s / grid.log_interval_s).round() as u64;
    let take = |ks: &mut Vec<u64>, (i, tr): (usize, Cow<'_, ChannelTrack>)| {
        candidate_of[i].is_some().then(|| {
            grid.track_ks(stamps, &tr.t_s, ks);
            filter.take_rows(ks, tr, stats[i].passing, startup_epochs)
        })
    };
    let taken: Vec<Option<TrackRows>> = match tracking {
        Cow::Owned(log) => {
            log.into_tracks().into_par_iter().map(Cow::Owned).enumerate().map_init(Vec::new, take).collect()
        }
        // A borrowed log stays with its owner.
        Cow::Borrowed(log) => log.tracks().par_iter().map(Cow::Borrowed).enumerate().map_init(Vec::new, take).collect(),
    };
    for (epoch, phase, cn0, startup_end) in taken.into_iter().flatten() {
        rows.epoch.push(epoch);
        rows.phase.push(phase);
        rows.cn0.push(cn0);
        rows.startup_end.push(startup_end);
    }
    Candidates { tracks, stats, candidate_of, rows }
}

/// The row table of the candidates, the tracks with passing rows (in the
/// log's order), laid out by their counts (the rows themselves still to be
/// taken), and each track's index among them.
fn row_table(stats: &[TrackStats], tracks: &[TrackMeta]) -> (Rows, Vec<Option<usize>>) {
    let mut candidate_of: Vec<Option<usize>> = vec![None; tracks.len()];
    let mut rows = Rows { track_start: vec![0], ..Rows::default() };
    for (i, s) in stats.iter().enumerate().filter(|(_, s)| s.passing > 0) {
        candidate_of[i] = Some(rows.tracks());
        rows.track_start.push(rows.track_start.last().copied().unwrap_or(0) + s.passing);
        rows.to_l1.push(tracks[i].carrier.scale_to_l1());
    }
    (rows, candidate_of)
}

#[cfg(test)]
mod tests {
    use super::*;
    use gsens_io::{Carrier, TrackingRow, TrackingWriter, read_tracking};

    fn log_from(rows: &[(f64, u32, f64, Option<f64>, f64)]) -> TrackingLog {
        let mut w = TrackingWriter::new(Vec::new()).unwrap();
        for &(t_s, channel, cn0_dbhz, elev_deg, phase_err_rad) in rows {
            w.write_row(&TrackingRow { t_s, channel, prn: channel + 10, cn0_dbhz, elev_deg, phase_err_rad }).unwrap();
        }
        read_tracking(w.finish().unwrap().as_slice(), "tracking.csv").unwrap()
    }

    /// Channel 1 at epochs 0–5 (elevation 10°, 30°, …; C/N0 40, 41, …),
    /// channel 2 at 0–5 below every mask, channel 3 at 4–5 only.
    fn three_channels() -> TrackingLog {
        let mut rows = Vec::new();
        for k in 0..6 {
            let t = k as f64 * 0.5;
            rows.push((t, 1, 40.0 + k as f64, Some(10.0 + 20.0 * k as f64), 0.5 * k as f64));
            rows.push((t, 2, 20.0, Some(1.0), 9.0));
            if k >= 4 {
                rows.push((t, 3, 44.0, None, -1.0));
            }
        }
        log_from(&rows)
    }

    fn filter(span: Span, elevation_mask_deg: Option<f64>, min_cn0_dbhz: Option<f64>) -> RowFilter {
        RowFilter { span, elevation_mask_deg, min_cn0_dbhz }
    }

    #[test]
    fn a_row_passes_in_the_span_above_both_masks_and_unknown_elevation_passes() {
        let f = filter(Span { k_first: 2, k_end: 5 }, Some(15.0), Some(35.0));
        assert!(f.passes(2, 15.0, 35.0));
        assert!(f.passes(4, f64::NAN, 50.0));
        assert!(!f.passes(5, 80.0, 50.0) && !f.passes(1, 80.0, 50.0));
        assert!(!f.passes(3, 14.9, 50.0) && !f.passes(3, 80.0, 34.9));
    }

    #[test]
    fn the_counts_nest_span_mask_threshold() {
        let log = three_channels();
        let f = filter(Span { k_first: 1, k_end: 5 }, Some(45.0), Some(43.0));
        // Channel 1 in the span: k 1–4 (C/N0 41–44), elevation 30, 50, 70, 90: above it k 2–4, of them C/N0 ≥ 43: k 3, 4.
        let s = f.stats(&[0, 1, 2, 3, 4, 5], &log.tracks()[0]);
        let want = TrackStats { in_span: 4, above_mask: 3, passing: 2, cn0_sum_passing: 87.0, cn0_sum_span: 170.0 };
        assert_eq!(s, want);
    }

    #[test]
    fn the_candidates_are_the_tracks_with_passing_rows_counted_from_the_span() {
        let log = three_channels();
        let grid = Grid::new(&log).unwrap();
        let stamps = log.epoch_t_s().to_vec();
        let f = filter(Span { k_first: 1, k_end: 6 }, Some(5.0), None);
        for given in [false, true] {
            let tracking = if given { Cow::Owned(log.clone()) } else { Cow::Borrowed(&log) };
            // A start-up of 1 s: 2 epochs after each track's first row.
            let c = candidates(tracking, &grid, &stamps, &f, 1.0);
            assert_eq!(c.tracks.iter().map(|t| t.channel).collect::<Vec<_>>(), [1, 2, 3]);
            assert_eq!(c.candidate_of, [Some(0), None, Some(1)]);
            assert_eq!(c.stats[1].passing, 0);
            assert_eq!(c.rows.track_start, [0, 5, 7]);
            assert_eq!(c.rows.epoch, [vec![0, 1, 2, 3, 4], vec![3, 4]]);
            assert_eq!(c.rows.phase, [vec![0.5, 1.0, 1.5, 2.0, 2.5], vec![-1.0, -1.0]]);
            assert_eq!(c.rows.cn0, [vec![41.0, 42.0, 43.0, 44.0, 45.0], vec![44.0, 44.0]]);
            assert_eq!(c.rows.to_l1, [1.0, 1.0]);
            // Channel 1 starts at k 0 (before the span): its start-up ends at k 2, epoch 1; channel 3's at k 6, epoch 5.
            assert_eq!(c.rows.startup_end, [1, 5]);
        }
    }

    #[test]
    fn phases_are_scaled_to_l1() {
        let l5 = Carrier::of(gsens_io::Signal::from_label("L5Q").unwrap());
        let meta = |carrier| TrackMeta { channel: 0, prn: 1, carrier, mean_cn0_dbhz: 40.0 };
        let stats = [TrackStats { passing: 2, ..TrackStats::default() }, TrackStats::default()];
        let (rows, of) = row_table(&stats, &[meta(l5), meta(l5)]);
        assert_eq!(rows.len(), 2);
        assert_eq!((rows.track_start, of), (vec![0, 2], vec![Some(0), None]));
        assert_eq!(rows.to_l1, [gsens_core::units::GPS_L1_HZ / l5.carrier_hz]);
    }
}
