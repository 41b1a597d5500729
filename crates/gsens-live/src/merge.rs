//! Records of several sources put in time order.

use std::collections::VecDeque;

use crate::input::Input;

/// Records of several sources put in time order. A file followed from its
/// start is read in one go, so without this the session would get all of
/// one file before the other's first line, judge the rest and the shaking on
/// a stream that is all IMU and see the tracking far behind. A record waits
/// until every other source that has not ended has read one at least as
/// late; the earliest waiting record goes first.
pub(crate) struct Merger {
    held: Vec<VecDeque<(u64, Input)>>,
    /// Per source, the latest time read.
    seen_t_s: Vec<f64>,
}

impl Merger {
    pub(crate) fn new(sources: usize) -> Self {
        Merger { held: vec![VecDeque::new(); sources], seen_t_s: vec![f64::NEG_INFINITY; sources] }
    }

    pub(crate) fn put(&mut self, source: usize, line: u64, input: Input) {
        self.seen_t_s[source] = self.seen_t_s[source].max(input.t_s());
        self.held[source].push_back((line, input));
    }

    /// The records that may go now, in time order.
    pub(crate) fn ready(&mut self, ended: &[bool]) -> Vec<(usize, u64, Input)> {
        let mut out = Vec::new();
        loop {
            let earliest = (0..self.held.len())
                .filter_map(|s| self.held[s].front().map(|r| (s, r.1.t_s())))
                .min_by(|a, b| a.1.total_cmp(&b.1));
            let Some((s, t)) = earliest else { break };
            let reached = (0..self.held.len()).all(|o| o == s || ended[o] || self.seen_t_s[o] >= t);
            if !reached {
                break;
            }
            let (line, input) = self.held[s].pop_front().expect("a front record");
            out.push((s, line, input));
        }
        out
    }
}
