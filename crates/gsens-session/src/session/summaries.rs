//! The last stage of a session's preparation: what became of every track
//! and of every signal.

use super::rank::Selection;
use super::rows::Candidates;
use super::{ChannelSummary, SignalSummary};
use crate::screening::{self, ExcludedSpan, Screened};

/// The offsets removed from the used tracks: per used track (in rank order)
/// its first slot (one more at the end, [`super::average::Gathered::slot_base`]),
/// and every slot's offset \[rad\].
#[derive(Debug, Clone, Copy)]
pub(super) struct RemovedOffsets<'a> {
    pub slot_base: &'a [usize],
    pub offsets_rad: &'a [f64],
}

/// Every track's summary, sorted by channel then PRN: its counts and
/// verdict from `sel`, the screening's summary (taken out of `screened`)
/// with its excluded spans timed by the epoch times `t_s`, and, for a used
/// track when `offsets` were removed, its offset (and each segment's, for a
/// track split at a step).
pub(super) fn channel_summaries(
    c: &Candidates,
    screened: Screened,
    sel: Selection,
    offsets: Option<RemovedOffsets>,
    t_s: &[f64],
) -> Vec<ChannelSummary> {
    let Screened { summaries: mut screenings, spans, .. } = screened;
    let Selection { ranking, standings, used, mut reasons } = sel;
    let selected = ranking.selected();
    let mut channels: Vec<ChannelSummary> = (0..c.tracks.len())
        .map(|i| {
            let sel = offsets.and_then(|o| selected.iter().position(|&s| s == i).map(|s| (s, o)));
            let mut screening = c.candidate_of[i].map(|k| std::mem::take(&mut screenings[k])).unwrap_or_default();
            if let Some(k) = c.candidate_of[i] {
                screening.spans = spans[k].iter().map(|sp| excluded_span(sp, t_s)).collect();
            }
            if let Some((s, o)) = sel
                && o.slot_base[s + 1] - o.slot_base[s] > 1
            {
                screening.segment_offsets_rad = o.offsets_rad[o.slot_base[s]..o.slot_base[s + 1]].to_vec();
            }
            let track = &c.tracks[i];
            ChannelSummary {
                channel: track.channel,
                prn: track.prn,
                mean_cn0_dbhz: standings[i].mean_cn0_dbhz,
                epochs: standings[i].kept_rows,
                used: used[i],
                reason: std::mem::take(&mut reasons[i]),
                phase_offset_rad: sel.map(|(s, o)| o.offsets_rad[o.slot_base[s]]),
                screening,
                signal: track.carrier.label(),
                carrier_hz: track.carrier.carrier_hz,
            }
        })
        .collect();
    channels.sort_by_key(|c| (c.channel, c.prn));
    channels
}

/// A stretch the screening excluded, its epochs timed by `t_s` and its
/// flags named.
fn excluded_span(sp: &screening::EpochSpan, t_s: &[f64]) -> ExcludedSpan {
    ExcludedSpan {
        start_s: t_s[sp.first_epoch as usize],
        end_s: t_s[sp.last_epoch as usize],
        rows: sp.rows,
        reasons: screening::flag::NAMES
            .iter()
            .filter(|(bit, _)| sp.flags & bit != 0)
            .map(|(_, name)| (*name).to_owned())
            .collect(),
    }
}

/// The tracks per signal: highest carrier first, then by name.
pub(super) fn signal_summaries(channels: &[ChannelSummary]) -> Vec<SignalSummary> {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::screening::{EpochSpan, Rows, flag};
    use crate::session::ChannelRanking;
    use crate::session::rank::{Ranking, Standing};
    use crate::session::rows::{TrackMeta, TrackStats};

    /// Tracks of channels 3, 1, 2 (log order); 3 and 2 candidates, 2 used
    /// (split in two segments), 3 not.
    fn three() -> (Candidates, Screened, Selection) {
        let meta = |channel| TrackMeta { channel, prn: 7, carrier: gsens_io::Carrier::default(), mean_cn0_dbhz: 30.0 };
        let mut rows = Rows::default();
        rows.push_track(vec![0; 2], vec![0.0; 2], vec![0.0; 2]);
        rows.push_track(vec![0; 3], vec![0.0; 3], vec![0.0; 3]);
        let c = Candidates {
            tracks: vec![meta(3), meta(1), meta(2)],
            stats: vec![TrackStats::default(); 3],
            candidate_of: vec![Some(0), None, Some(1)],
            rows,
        };
        let mut screened = Screened::none(&c.rows);
        screened.summaries[1].rows_slip = 2;
        screened.spans[1] = vec![EpochSpan { first_epoch: 1, last_epoch: 2, rows: 2, flags: flag::SLIP | flag::NOISY }];
        let standing = |kept_rows, mean_cn0_dbhz| Standing { kept_rows, mean_cn0_dbhz, noise_rad: 0.1 };
        let sel = Selection {
            ranking: Ranking { ranked: vec![2, 0], channel_ranking: ChannelRanking::Cn0, n_used: 1 },
            standings: vec![standing(2, 40.0), standing(0, 35.0), standing(3, 45.0)],
            used: vec![false, false, true],
            reasons: vec!["not among".into(), "no rows".into(), "used".into()],
        };
        (c, screened, sel)
    }

    #[test]
    fn every_track_is_summarized_by_channel_with_its_offsets_and_timed_spans() {
        let (c, screened, sel) = three();
        let offsets = RemovedOffsets { slot_base: &[0, 2], offsets_rad: &[0.25, -0.5] };
        let t_s = [10.0, 10.5, 11.0];
        let s = channel_summaries(&c, screened, sel, Some(offsets), &t_s);
        assert_eq!(s.iter().map(|c| c.channel).collect::<Vec<_>>(), [1, 2, 3]);
        let (one, two, last) = (&s[0], &s[1], &s[2]);
        assert_eq!((one.used, one.reason.as_str(), one.epochs, one.mean_cn0_dbhz), (false, "no rows", 0, 35.0));
        assert_eq!((two.used, two.epochs, two.mean_cn0_dbhz, two.phase_offset_rad), (true, 3, 45.0, Some(0.25)));
        assert_eq!(two.screening.segment_offsets_rad, [0.25, -0.5]);
        assert_eq!(two.screening.rows_slip, 2);
        let span = &two.screening.spans[0];
        assert_eq!((span.start_s, span.end_s, span.rows), (10.5, 11.0, 2));
        assert_eq!(span.reasons, ["slip", "noisy"]);
        assert_eq!((last.phase_offset_rad, last.reason.as_str()), (None, "not among"));
        assert_eq!((two.signal.as_str(), two.carrier_hz), ("1575.42 MHz", gsens_core::units::GPS_L1_HZ));
        // Offsets kept: none is reported.
        let (c, screened, sel) = three();
        let s = channel_summaries(&c, screened, sel, None, &t_s);
        assert_eq!((s[1].phase_offset_rad, s[1].screening.segment_offsets_rad.len()), (None, 0));
    }

    #[test]
    fn signals_are_counted_highest_carrier_first() {
        let (c, screened, sel) = three();
        let mut s = channel_summaries(&c, screened, sel, None, &[0.0; 3]);
        s[0].signal = "L5Q".into();
        s[0].carrier_hz = 1176.45e6;
        let g = signal_summaries(&s);
        assert_eq!(
            g.iter().map(|g| (g.signal.as_str(), g.tracks, g.tracks_used)).collect::<Vec<_>>(),
            [("1575.42 MHz", 2, 1), ("L5Q", 1, 0)]
        );
        assert_eq!(g[1].scale_to_l1, 1575.42e6 / 1176.45e6);
    }
}
