//! The ranking stage of a session's preparation: after the screening, the
//! tracks with rows kept are ranked (by mean C/N0, or by noise where C/N0
//! does not vary), the best `max_channels` used, and every track told why.

use gsens_core::units::Decimal;
use rayon::prelude::*;

use super::rows::{Candidates, TrackMeta, TrackStats};
use super::{CN0_RANKING_RESOLUTION_DB, ChannelRanking, SelectionConfig};
use crate::error::SessionError;
use crate::screening::Screened;

/// What the ranking knows of a track after the screening.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Standing {
    /// Rows kept by the screening (0 for a track that is no candidate).
    pub kept_rows: usize,
    /// Mean C/N0 \[dB-Hz\] over the rows kept; without any, over the rows
    /// passing the masks, or else over the rows in the span, or else over
    /// all the track's rows.
    pub mean_cn0_dbhz: f64,
    /// The screening's deviation σ \[rad\] ([`crate::TrackScreening::deviation_sigma_rad`]);
    /// ∞ where there is none (a track never compared with two others ranks last).
    pub noise_rad: f64,
}

/// The tracks ranked for the `max_channels` cut.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Ranking {
    /// The tracks with rows kept, best first (ties: channel, then PRN).
    pub ranked: Vec<usize>,
    /// What ranked them.
    pub channel_ranking: ChannelRanking,
    /// How many of them, the first, are used.
    pub n_used: usize,
}

impl Ranking {
    /// The tracks used, best first.
    pub(super) fn selected(&self) -> &[usize] {
        &self.ranked[..self.n_used]
    }
}

/// The ranking's outcome for every track of the log.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Selection {
    pub ranking: Ranking,
    pub standings: Vec<Standing>,
    /// Per track: whether it enters the average.
    pub used: Vec<bool>,
    /// Per track: `"used"` or why not ([`verdicts`]).
    pub reasons: Vec<String>,
}

/// The rank stage: each track's [`standings`], their [`rank`] under
/// `selection.max_channels`, and every track's [`verdicts`] (`span_s`: the
/// usable span's first and last epoch times \[s\]).
pub(super) fn select(
    c: &Candidates,
    screened: &Screened,
    span_s: (f64, f64),
    selection: &SelectionConfig,
) -> Selection {
    let standings = standings(c, screened);
    let ranking = rank(&standings, &c.tracks, selection.max_channels);
    let (used, reasons) = verdicts(&ranking, &standings, &c.stats, span_s, selection);
    Selection { ranking, standings, used, reasons }
}

/// Each track's standing from its counts and what the screening kept.
pub(super) fn standings(c: &Candidates, screened: &Screened) -> Vec<Standing> {
    let rows = &c.rows;
    // Per candidate: rows kept by the screening and their C/N0 sum, each
    // track's sum on its own (the tracks in parallel).
    let kept: Vec<(usize, f64)> = (0..rows.tracks())
        .into_par_iter()
        .map(|k| {
            (screened.flags[rows.range(k)].iter().zip(rows.cn0s(k)))
                .filter(|&(&f, _)| f == 0)
                .fold((0, 0.0), |(n, sum), (_, &cn0)| (n + 1, sum + cn0))
        })
        .collect();
    (0..c.tracks.len())
        .map(|i| {
            let s = &c.stats[i];
            let (kept_rows, cn0_kept) = c.candidate_of[i].map_or((0, 0.0), |k| kept[k]);
            let mean_cn0_dbhz = if kept_rows > 0 {
                cn0_kept / kept_rows as f64
            } else if s.passing > 0 {
                s.cn0_sum_passing / s.passing as f64
            } else if s.in_span > 0 {
                s.cn0_sum_span / s.in_span as f64
            } else {
                c.tracks[i].mean_cn0_dbhz
            };
            let noise_rad =
                c.candidate_of[i].and_then(|k| screened.summaries[k].deviation_sigma_rad).unwrap_or(f64::INFINITY);
            Standing { kept_rows, mean_cn0_dbhz, noise_rad }
        })
        .collect()
}

/// Ranks the tracks with rows kept: by mean C/N0, highest first, or, where
/// the candidates' mean C/N0 spread less than [`CN0_RANKING_RESOLUTION_DB`]
/// and some noise is known, by noise, lowest first; ties by channel, then
/// PRN. The first `max_channels` (all: `None`) are used.
pub(super) fn rank(standings: &[Standing], tracks: &[TrackMeta], max_channels: Option<usize>) -> Ranking {
    let mut ranked: Vec<usize> = (0..tracks.len()).filter(|&i| standings[i].kept_rows > 0).collect();
    let spread_db = ranked
        .iter()
        .map(|&i| standings[i].mean_cn0_dbhz)
        .fold(None, |r: Option<(f64, f64)>, v| Some(r.map_or((v, v), |(lo, hi)| (lo.min(v), hi.max(v)))));
    let noise_known = ranked.iter().any(|&i| standings[i].noise_rad.is_finite());
    let channel_ranking = match spread_db {
        Some((lo, hi)) if ranked.len() > 1 && hi - lo < CN0_RANKING_RESOLUTION_DB && noise_known => {
            ChannelRanking::Noise
        }
        _ => ChannelRanking::Cn0,
    };
    ranked.sort_by(|&a, &b| {
        let (sa, sb) = (&standings[a], &standings[b]);
        match channel_ranking {
            ChannelRanking::Cn0 => sb.mean_cn0_dbhz.total_cmp(&sa.mean_cn0_dbhz),
            ChannelRanking::Noise => sa.noise_rad.total_cmp(&sb.noise_rad),
        }
        .then(tracks[a].channel.cmp(&tracks[b].channel))
        .then(tracks[a].prn.cmp(&tracks[b].prn))
    });
    let n_used = max_channels.map_or(ranked.len(), |n| n.min(ranked.len()));
    Ranking { ranked, channel_ranking, n_used }
}

/// Per track: whether it is used, and `"used"` or why not: below the cut
/// (with its rank), or the first of: no rows in the usable span
/// `span_s` \[s\], all below the elevation mask, all below the C/N0
/// threshold, all excluded by the screening.
pub(super) fn verdicts(
    ranking: &Ranking,
    standings: &[Standing],
    stats: &[TrackStats],
    span_s: (f64, f64),
    selection: &SelectionConfig,
) -> (Vec<bool>, Vec<String>) {
    let n_used = ranking.n_used;
    let mut reasons: Vec<String> = vec![String::new(); stats.len()];
    let mut used = vec![false; stats.len()];
    for (rank, &i) in ranking.ranked.iter().enumerate() {
        if rank < n_used {
            used[i] = true;
            reasons[i] = "used".to_owned();
        } else {
            reasons[i] = match ranking.channel_ranking {
                ChannelRanking::Cn0 => format!(
                    "not among the {} strongest (mean C/N0 {:.1} dB-Hz, rank {})",
                    n_used,
                    standings[i].mean_cn0_dbhz,
                    rank + 1
                ),
                ChannelRanking::Noise => format!(
                    "not among the {} least noisy (C/N0 does not vary between the tracks; deviation σ {:.4} rad, \
                     rank {})",
                    n_used,
                    standings[i].noise_rad,
                    rank + 1
                ),
            };
        }
    }
    for (i, s) in stats.iter().enumerate() {
        if s.in_span == 0 {
            reasons[i] = format!(
                "no rows in the usable span [{}, {}] s (overlap with the IMU)",
                Decimal(span_s.0),
                Decimal(span_s.1)
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
        } else if standings[i].kept_rows == 0 {
            reasons[i] = format!("all {} rows passing the masks excluded by the screening", s.passing);
        }
    }
    (used, reasons)
}

/// The error of a selection that keeps no track: every track's reason, by
/// channel then PRN.
pub(super) fn no_channel_selected(file: &str, tracks: &[TrackMeta], reasons: &[String]) -> SessionError {
    let mut order: Vec<usize> = (0..tracks.len()).collect();
    order.sort_by_key(|&i| (tracks[i].channel, tracks[i].prn, i));
    let detail: Vec<String> = order
        .iter()
        .map(|&i| format!("channel {} (PRN {}): {}", tracks[i].channel, tracks[i].prn, reasons[i]))
        .collect();
    SessionError::NoChannelSelected { file: file.to_owned(), reason: detail.join("; ") }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::screening::Rows;

    fn meta(channel: u32) -> TrackMeta {
        TrackMeta { channel, prn: channel + 10, carrier: gsens_io::Carrier::default(), mean_cn0_dbhz: 30.0 }
    }

    fn standing(kept_rows: usize, mean_cn0_dbhz: f64, noise_rad: f64) -> Standing {
        Standing { kept_rows, mean_cn0_dbhz, noise_rad }
    }

    #[test]
    fn the_standing_is_the_mean_over_the_rows_kept_or_else_the_widest_count() {
        // Candidate 0 (track 0) keeps rows 0 and 2 (C/N0 40 and 44); candidate 1 (track 2) keeps none.
        let mut rows = Rows::default();
        rows.push_track(vec![0, 1, 2], vec![0.0; 3], vec![40.0, 99.0, 44.0]);
        rows.push_track(vec![0], vec![0.0], vec![50.0]);
        let mut screened = Screened::none(&rows);
        screened.flags = vec![0, 1, 0, 4];
        screened.summaries[0].deviation_sigma_rad = Some(0.02);
        let stats = [
            TrackStats { in_span: 3, above_mask: 3, passing: 3, cn0_sum_passing: 183.0, cn0_sum_span: 183.0 },
            TrackStats { in_span: 2, above_mask: 0, passing: 0, cn0_sum_passing: 0.0, cn0_sum_span: 70.0 },
            TrackStats { in_span: 1, above_mask: 1, passing: 1, cn0_sum_passing: 50.0, cn0_sum_span: 50.0 },
            TrackStats::default(),
        ];
        let c = Candidates {
            tracks: (0..4).map(meta).collect(),
            stats: stats.to_vec(),
            candidate_of: vec![Some(0), None, Some(1), None],
            rows,
        };
        let s = standings(&c, &screened);
        let inf = f64::INFINITY;
        assert_eq!(
            s,
            [standing(2, 42.0, 0.02), standing(0, 35.0, inf), standing(0, 50.0, inf), standing(0, 30.0, inf)]
        );
    }

    #[test]
    fn the_strongest_are_used_ties_broken_by_channel() {
        let tracks: Vec<TrackMeta> = (0..4).map(meta).collect();
        let s = [standing(5, 40.0, 0.1), standing(5, 45.0, 0.3), standing(0, 50.0, 0.0), standing(5, 45.0, 0.2)];
        let r = rank(&s, &tracks, Some(2));
        assert_eq!(r, Ranking { ranked: vec![1, 3, 0], channel_ranking: ChannelRanking::Cn0, n_used: 2 });
        assert_eq!(r.selected(), [1, 3]);
        assert_eq!(rank(&s, &tracks, None).n_used, 3);
    }

    #[test]
    fn without_a_c_n0_spread_the_least_noisy_are_used() {
        let tracks: Vec<TrackMeta> = (0..3).map(meta).collect();
        let s = [standing(5, 40.0, 0.3), standing(5, 40.05, f64::INFINITY), standing(5, 40.0, 0.1)];
        let r = rank(&s, &tracks, Some(1));
        assert_eq!(r, Ranking { ranked: vec![2, 0, 1], channel_ranking: ChannelRanking::Noise, n_used: 1 });
        // No noise known: C/N0 ranks after all.
        let s = [standing(5, 40.0, f64::INFINITY), standing(5, 40.05, f64::INFINITY)];
        assert_eq!(rank(&s, &tracks[..2], Some(1)).channel_ranking, ChannelRanking::Cn0);
    }

    #[test]
    fn every_track_is_told_why() {
        let s = [standing(5, 45.0, 0.1), standing(5, 40.0, 0.1), standing(0, 0.0, 0.0), standing(0, 0.0, 0.0)];
        let full = TrackStats { in_span: 5, above_mask: 5, passing: 5, ..TrackStats::default() };
        let stats = [full, full, TrackStats { in_span: 4, above_mask: 3, passing: 0, ..full }, TrackStats::default()];
        let ranking = Ranking { ranked: vec![0, 1], channel_ranking: ChannelRanking::Cn0, n_used: 1 };
        let sel = SelectionConfig { min_cn0_dbhz: Some(35.0), ..SelectionConfig::default() };
        let (used, reasons) = verdicts(&ranking, &s, &stats, (1.5, 20.25), &sel);
        assert_eq!(used, [true, false, false, false]);
        assert_eq!(reasons[0], "used");
        assert_eq!(reasons[1], "not among the 1 strongest (mean C/N0 40.0 dB-Hz, rank 2)");
        assert_eq!(
            reasons[2],
            "all 3 rows in the usable span (above the elevation mask) below the C/N0 threshold of 35 dB-Hz"
        );
        assert_eq!(reasons[3], "no rows in the usable span [1.5, 20.25] s (overlap with the IMU)");
        let e = no_channel_selected("t.csv", &[meta(2), meta(1)], &["b".into(), "a".into()]).to_string();
        assert!(e.contains("channel 1 (PRN 11): a; channel 2 (PRN 12): b"), "{e}");
    }
}
