//! Per-track screening of the tracking rows before averaging (documented at
//! the crate root, section "Screening").

use gsens_core::stats::median_in_place;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::error::ScreeningConfigError;

/// The settings of the per-track screening (see the [crate documentation](crate#screening)).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ScreeningConfig {
    /// Screen the tracks at all. Default `true`.
    pub enabled: bool,
    /// A row whose deviation from the other channels is more than this many σ
    /// from the track's level starts a slip / excursion event, which is one
    /// when a second row of it (before it settles) is beyond the bound too.
    /// Default 6. A Gaussian deviation exceeds 6σ once in 5·10⁸ rows, but an
    /// atan discriminator's output of one short integration is not Gaussian:
    /// its phase passes x when the noise across the signal exceeds the
    /// amplitude times sin x, P ≈ erfc(√(C·T)·sin x) against the Gaussian
    /// erfc(x·√(C·T)), so at 40 dB-Hz and 1 ms (C·T = 10; 6σ = 1.34 rad) a
    /// lone row is beyond it 10⁴ times as often (measured: 2 rows in 6·10⁵
    /// clean ones of an independent simulator's 40–48.7 dB-Hz channels). A
    /// slip's excursion lasts a loop time constant (~1/(ζωn), 0.25 s for a 3
    /// Hz loop), several rows at any log rate that resolves the loop, and two
    /// independent tail rows within one event are again rarer than the
    /// Gaussian promise.
    pub deviation_k: f64,
    /// Excluded on each side of every detected stretch \[s\]. Default 0.5 s.
    pub guard_s: f64,
    /// An event ends once the deviation has been back within bounds this long \[s\]. Default 0.25 s.
    pub settle_s: f64,
    /// An event lasting at least this long that settles on a new quiet level is
    /// a step: the track is split there \[s\]. Default 1 s.
    pub step_min_s: f64,
    /// Time constant of the track's adapting deviation level \[s\]. Default 10 s.
    pub level_tau_s: f64,
    /// Window of the noisy-stretch test \[s\]. Default 1 s.
    pub noisy_window_s: f64,
    /// A window whose deviation RMS exceeds this many σ is excluded. Default 3.
    pub noisy_rms_k: f64,
    /// Window of the gain test \[s\]. Default 10 s.
    pub gain_window_s: f64,
    /// A window whose gain on the common signal (relative to the typical
    /// track's) is significantly below this is excluded. Default 0.8.
    pub min_gain: f64,
    /// A track whose gain pooled over all its tested windows is significantly
    /// below this is excluded entirely. Default 0.9.
    pub min_track_gain: f64,
    /// Rows with |φ| above this, plus the track's noise margin, are excluded
    /// \[rad\]; `None`: no limit. Default π/4, half the unambiguous range of
    /// the atan(Q/I) Costas discriminator of GPS L1 C/A receivers: a channel
    /// alone beyond half the range is leaving it (a channel out of lock
    /// logs outputs spread over the whole range, beyond half of it half the
    /// time). For an atan2 discriminator, π/2 (a calibration pipeline sets
    /// it from its discriminator). The margin is z·σ (σ the
    /// track's deviation σ, z the normal quantile at a 1 % false-alarm
    /// probability over its rows): a noisy track's rows are not excluded for
    /// noise that crosses the limit.
    pub max_abs_phase_rad: Option<f64>,
    /// Rows whose C/N0 is more than this below the track's median are excluded
    /// \[dB\]; `None`: no test. Default [`DEFAULT_CN0_DROP_DB`].
    pub cn0_drop_db: Option<f64>,
    /// A track of which the cross-channel tests (slips, noisy stretches, low
    /// gain) flag more than this fraction of the rows is excluded entirely. Default 0.5.
    pub max_excluded_fraction: f64,
    /// Floor of a track's deviation σ \[rad\] (noise-free logs). Default 0.005 rad.
    pub min_sigma_rad: f64,
    /// The start-up of a track: its first `startup_s` seconds in the log \[s\].
    /// A slip / excursion event or a C/N0 drop that *begins* in it is the
    /// track's pull-in, not a slip or a drop: the loop settles from the
    /// acquisition's frequency and phase error, and the receiver's C/N0
    /// estimator averages that pull-in into its first window(s). Its rows are
    /// excluded (reason `startup`) and counted in
    /// [`TrackScreening::rows_startup`], not as slips or drops. Default 2 s:
    /// an acquisition error decays as e^(−ζωn·t) in a 2nd-order loop, ζωn =
    /// 4 s⁻¹ for the paper's Bn = 3 Hz, ζ = 1/√2 (to e⁻⁴ ≈ 2 % in 1 s), plus
    /// one window of a 1 s C/N0 estimator; a narrower loop (settling ≈ 4/(ζωn))
    /// or a longer C/N0 window needs more. 0: no start-up allowance.
    pub startup_s: f64,
}

/// The C/N0 drop below a track's median that excludes a row by default
/// \[dB\]: 6 dB, a quarter of the track's typical signal power.
pub const DEFAULT_CN0_DROP_DB: f64 = 6.0;

impl Default for ScreeningConfig {
    fn default() -> Self {
        ScreeningConfig {
            enabled: true,
            deviation_k: 6.0,
            guard_s: 0.5,
            settle_s: 0.25,
            step_min_s: 1.0,
            level_tau_s: 10.0,
            noisy_window_s: 1.0,
            noisy_rms_k: 3.0,
            gain_window_s: 10.0,
            min_gain: 0.8,
            min_track_gain: 0.9,
            max_abs_phase_rad: Some(core::f64::consts::FRAC_PI_4),
            cn0_drop_db: Some(DEFAULT_CN0_DROP_DB),
            max_excluded_fraction: 0.5,
            min_sigma_rad: 0.005,
            startup_s: 2.0,
        }
    }
}

impl ScreeningConfig {
    /// No screening at all.
    pub fn off() -> Self {
        ScreeningConfig { enabled: false, ..ScreeningConfig::default() }
    }

    /// Checks the values; the error names the offending key.
    pub fn validate(&self) -> Result<(), ScreeningConfigError> {
        let positive = [
            ("deviation_k", self.deviation_k),
            ("settle_s", self.settle_s),
            ("step_min_s", self.step_min_s),
            ("level_tau_s", self.level_tau_s),
            ("noisy_window_s", self.noisy_window_s),
            ("noisy_rms_k", self.noisy_rms_k),
            ("gain_window_s", self.gain_window_s),
        ];
        for (key, value) in positive {
            if !(value > 0.0 && value.is_finite()) {
                return Err(ScreeningConfigError::MustBePositive { key, value });
            }
        }
        let non_negative = [
            ("guard_s", self.guard_s),
            ("min_gain", self.min_gain),
            ("min_sigma_rad", self.min_sigma_rad),
            ("min_track_gain", self.min_track_gain),
            ("startup_s", self.startup_s),
        ];
        for (key, value) in non_negative {
            if !(value >= 0.0 && value.is_finite()) {
                return Err(ScreeningConfigError::MustBeNonNegative { key, value });
            }
        }
        if let Some(value) = self.max_abs_phase_rad.filter(|v| !(*v > 0.0 && v.is_finite())) {
            return Err(ScreeningConfigError::MustBePositive { key: "max_abs_phase_rad", value });
        }
        if let Some(value) = self.cn0_drop_db.filter(|v| !(*v > 0.0 && v.is_finite())) {
            return Err(ScreeningConfigError::MustBePositive { key: "cn0_drop_db", value });
        }
        if !(self.max_excluded_fraction >= 0.0 && self.max_excluded_fraction <= 1.0) {
            return Err(ScreeningConfigError::MustBeFraction { value: self.max_excluded_fraction });
        }
        Ok(())
    }
}

/// A stretch of a track excluded by the screening.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[non_exhaustive]
pub struct ExcludedSpan {
    /// Time of the first excluded row \[s\].
    pub start_s: f64,
    /// Time of the last excluded row \[s\].
    pub end_s: f64,
    /// Excluded rows in the stretch.
    pub rows: usize,
    /// Why: any of `slip`, `noisy`, `low_gain`, `phase_range`, `cn0_drop`,
    /// `track`, `startup` (the track's pull-in, [`ScreeningConfig::startup_s`]).
    pub reasons: Vec<String>,
}

/// The most [`ExcludedSpan`]s listed per track (the counts are always complete).
pub const MAX_SPANS: usize = 100;

/// What the screening did to one track.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[non_exhaustive]
pub struct TrackScreening {
    /// Rows (passing the masks) excluded.
    pub rows_excluded: usize,
    /// The track's gain on the common signal relative to the other tracks'
    /// (test 3, its tested windows pooled; 1 for a track on the carrier the log
    /// gives it, f_true/f_given for one whose carrier is wrong); `None` where
    /// fewer than two windows were tested.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub relative_gain: Option<f64>,
    /// The standard error of [`relative_gain`](Self::relative_gain).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub relative_gain_se: Option<f64>,
    /// Slip / excursion events detected.
    pub slips: usize,
    /// Of the events, those that settled on a new level (the track is split into `steps + 1` segments).
    pub steps: usize,
    /// Rows flagged by the slip / excursion test (a row may be flagged by several tests).
    pub rows_slip: usize,
    /// Rows flagged by the noisy-stretch test.
    pub rows_noisy: usize,
    /// Rows flagged by the gain test.
    pub rows_low_gain: usize,
    /// Rows flagged for |φ| beyond the linear range.
    pub rows_phase_range: usize,
    /// Rows flagged for a C/N0 drop.
    pub rows_cn0_drop: usize,
    /// Rows of the track's start-up transient (pull-in; [`ScreeningConfig::startup_s`]):
    /// excluded, but neither slips nor C/N0 drops.
    pub rows_startup: usize,
    /// Whether the whole track is excluded (too large a fraction flagged).
    pub track_excluded: bool,
    /// Robust σ of the track's deviation from the other channels \[rad\], on
    /// L1's scale (the track's phases times f_L1/f_c, as averaged); `None`
    /// where it never had two others to compare with.
    pub deviation_sigma_rad: Option<f64>,
    /// Median C/N0 of the track's rows \[dB-Hz\] (the reference of the C/N0-drop test).
    pub median_cn0_dbhz: Option<f64>,
    /// The excluded stretches, in time order (at most [`MAX_SPANS`]).
    pub spans: Vec<ExcludedSpan>,
    /// The constant offset of each segment \[rad\], when the track was split
    /// (steps > 0) and is averaged with offsets removed; else empty.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub segment_offsets_rad: Vec<f64>,
    /// The tests that could not be applied to the track, each with why (e.g.
    /// `low gain: no 10 s window with enough rows …`): the track passed them
    /// untested. Empty when every test ran.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub not_checked: Vec<String>,
}

impl TrackScreening {
    /// A one-line summary, e.g. `screened out 312 rows: 2 slips (1 step), 40 noisy`,
    /// followed by what could not be checked (`not checked: low gain (…)`);
    /// `None` when nothing was excluded and every test ran.
    pub fn brief(&self) -> Option<String> {
        let unchecked = if self.not_checked.is_empty() {
            String::new()
        } else {
            format!("not checked: {}", self.not_checked.join("; "))
        };
        if self.rows_excluded == 0 && self.steps == 0 {
            return (!unchecked.is_empty()).then_some(unchecked);
        }
        let mut parts = Vec::new();
        if self.slips > 0 {
            let steps =
                if self.steps > 0 { format!(" ({} step{})", self.steps, plural(self.steps)) } else { "".into() };
            parts.push(format!("{} slip{}{steps}", self.slips, plural(self.slips)));
        }
        for (n, what) in [
            (self.rows_noisy, "noisy"),
            (self.rows_low_gain, "low gain"),
            (self.rows_phase_range, "|φ| range"),
            (self.rows_cn0_drop, "C/N0 drop"),
            (self.rows_startup, "start-up"),
        ] {
            if n > 0 {
                parts.push(format!("{n} {what}"));
            }
        }
        let whole = if self.track_excluded { ", whole track excluded" } else { "" };
        let unchecked = if unchecked.is_empty() { unchecked } else { format!("; {unchecked}") };
        Some(format!("screened out {} rows: {}{whole}{unchecked}", self.rows_excluded, parts.join(", ")))
    }
}

fn plural(n: usize) -> &'static str {
    if n == 1 { "" } else { "s" }
}

/// Bit flags of why a row is excluded.
pub(crate) mod flag {
    pub(crate) const SLIP: u8 = 1;
    pub(crate) const NOISY: u8 = 2;
    pub(crate) const LOW_GAIN: u8 = 4;
    pub(crate) const PHASE_RANGE: u8 = 8;
    pub(crate) const CN0_DROP: u8 = 16;
    pub(crate) const TRACK: u8 = 32;
    /// The start-up transient, as the slip test sees it (reset with SLIP in its second round).
    pub(crate) const STARTUP: u8 = 64;
    /// The start-up transient, as the C/N0 test sees it.
    pub(crate) const STARTUP_CN0: u8 = 128;
    /// Either start-up flag.
    pub(crate) const ANY_STARTUP: u8 = STARTUP | STARTUP_CN0;
    /// The names in `ExcludedSpan::reasons` (a mask of several bits: one name for any of them).
    pub(crate) const NAMES: [(u8, &str); 7] = [
        (SLIP, "slip"),
        (NOISY, "noisy"),
        (LOW_GAIN, "low_gain"),
        (PHASE_RANGE, "phase_range"),
        (CN0_DROP, "cn0_drop"),
        (TRACK, "track"),
        (ANY_STARTUP, "startup"),
    ];
}

/// The rows of the candidate tracks, each track's in time order in columns
/// of its own (a log given to the session lends its own columns, converted
/// in place). A row's index r counts across the tracks, track after track:
/// the screening's per-row arrays are flat in it.
#[derive(Debug, Default)]
pub(crate) struct Rows {
    /// The rows of track `i` are `track_start[i]..track_start[i + 1]`.
    pub track_start: Vec<usize>,
    /// Per track: the epoch index of each row (strictly increasing).
    pub epoch: Vec<Vec<u32>>,
    /// Per track: the phase error of each row \[rad\].
    pub phase: Vec<Vec<f64>>,
    /// Per track: the C/N0 of each row \[dB-Hz\].
    pub cn0: Vec<Vec<f64>>,
    /// Per track: the factor f_L1/f_c its phases were scaled by onto L1's scale
    /// (missing: 1). The linear-range test compares the discriminator's own
    /// output, phase/to_l1, with the limit.
    pub to_l1: Vec<f64>,
    /// Per track: the epoch (exclusive) where its start-up ends
    /// ([`ScreeningConfig::startup_s`] after its first row in the log; 0 when
    /// that lies before the first epoch). Missing: no start-up.
    pub startup_end: Vec<u32>,
}

impl Rows {
    pub(crate) fn tracks(&self) -> usize {
        self.track_start.len().saturating_sub(1)
    }

    pub(crate) fn range(&self, i: usize) -> core::ops::Range<usize> {
        self.track_start[i]..self.track_start[i + 1]
    }

    /// The number of rows of all the tracks.
    pub(crate) fn len(&self) -> usize {
        self.track_start.last().copied().unwrap_or(0)
    }

    /// Track `i`'s epochs.
    pub(crate) fn epochs(&self, i: usize) -> &[u32] {
        &self.epoch[i]
    }

    /// Track `i`'s phases \[rad\].
    pub(crate) fn phases(&self, i: usize) -> &[f64] {
        &self.phase[i]
    }

    /// Track `i`'s C/N0 \[dB-Hz\].
    pub(crate) fn cn0s(&self, i: usize) -> &[f64] {
        &self.cn0[i]
    }

    /// Appends a track of these rows (test fixtures).
    #[cfg(test)]
    pub(crate) fn push_track(&mut self, epoch: Vec<u32>, phase: Vec<f64>, cn0: Vec<f64>) {
        if self.track_start.is_empty() {
            self.track_start.push(0);
        }
        self.track_start.push(self.len() + epoch.len());
        self.epoch.push(epoch);
        self.phase.push(phase);
        self.cn0.push(cn0);
    }

    /// The factor track `i`'s phases were scaled by (f_L1/f_c).
    fn to_l1(&self, i: usize) -> f64 {
        self.to_l1.get(i).copied().unwrap_or(1.0)
    }

    /// The epoch (exclusive) where track `i`'s start-up ends.
    fn startup_end(&self, i: usize) -> u32 {
        self.startup_end.get(i).copied().unwrap_or(0)
    }
}

/// A stretch of excluded rows of one track, in epochs (inclusive).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct EpochSpan {
    pub first_epoch: u32,
    pub last_epoch: u32,
    pub rows: usize,
    pub flags: u8,
}

/// The outcome of [`screen`].
#[derive(Debug, Default)]
pub(crate) struct Screened {
    /// Per row: why it is excluded (0: kept).
    pub flags: Vec<u8>,
    /// Per row: its segment within its track (0, 1, … split at steps).
    pub segment: Vec<u16>,
    /// Per track: the number of segments.
    pub segments: Vec<usize>,
    /// Per track: the summary (spans without times; see `spans`).
    pub summaries: Vec<TrackScreening>,
    /// Per track: the excluded stretches in epochs (at most [`MAX_SPANS`]).
    pub spans: Vec<Vec<EpochSpan>>,
}

impl Screened {
    /// Nothing excluded, one segment per track.
    pub(crate) fn none(rows: &Rows) -> Self {
        let n = rows.len();
        Screened {
            flags: vec![0; n],
            segment: vec![0; n],
            segments: vec![1; rows.tracks()],
            summaries: vec![TrackScreening::default(); rows.tracks()],
            spans: vec![Vec::new(); rows.tracks()],
        }
    }
}

/// `v`, a value per row, split into the rows of each track (`track_start`
/// as in [`Rows`]: track i holds rows `track_start[i]..track_start[i + 1]`),
/// so that the tracks can be worked on at once.
pub(crate) fn per_track<'a, T>(v: &'a mut [T], track_start: &[usize]) -> Vec<&'a mut [T]> {
    let mut out = Vec::with_capacity(track_start.len().saturating_sub(1));
    let mut rest = &mut v[track_start.first().copied().unwrap_or(0)..];
    for w in track_start.windows(2) {
        let (head, tail) = std::mem::take(&mut rest).split_at_mut(w[1] - w[0]);
        out.push(head);
        rest = tail;
    }
    out
}

/// An integer key with the order of the (finite) float, at single precision:
/// the sign-magnitude bits of `v as f32` turned into two's complement.
#[inline]
fn order_key(v: f64) -> i32 {
    let b = (v as f32).to_bits() as i32;
    b ^ (((b >> 31) as u32) >> 1) as i32
}

/// The most tracks at one epoch the median computation handles on the stack.
const MAX_AT_EPOCH: usize = 64;

/// The deviations of every row from the median of the other tracks at its
/// epoch (NaN where fewer than two others), with the tracks' offsets `c`
/// removed; rows with `flags & mask != 0` do not enter the medians, and the
/// values entering them are less `shift` (the tracks' levels, steps
/// included), if given.
///
/// Each epoch's medians need only that epoch's rows: spans of epochs are
/// computed in parallel, each writing its rows' deviations straight into
/// its own parts of `d` (a span's rows of one track are contiguous), so no
/// span holds a buffer of its own.
fn deviations(rows: &Rows, n_epochs: usize, flags: &[u8], mask: u8, c: &[f64], shift: Option<&[f64]>, d: &mut [f64]) {
    const SPAN_EPOCHS: usize = 1 << 14;
    let n_tracks = rows.tracks();
    // The first row of each track at or after epoch `e`.
    let first_at = |e: usize| -> Vec<usize> {
        (0..n_tracks)
            .map(|i| {
                let range = rows.range(i);
                range.start + rows.epochs(i).partition_point(|&ep| (ep as usize) < e)
            })
            .collect()
    };
    let bounds: Vec<usize> = (0..n_epochs).step_by(SPAN_EPOCHS).chain([n_epochs]).collect();
    let firsts: Vec<Vec<usize>> = bounds.iter().map(|&e| first_at(e)).collect();
    // Per span, per track: the part of `d` that holds its rows there.
    let mut parts: Vec<Vec<&mut [f64]>> = (1..bounds.len()).map(|_| Vec::with_capacity(n_tracks)).collect();
    for (i, mut rest) in per_track(d, &rows.track_start).into_iter().enumerate() {
        for (s, part) in parts.iter_mut().enumerate() {
            let (head, tail) = std::mem::take(&mut rest).split_at_mut(firsts[s + 1][i] - firsts[s][i]);
            part.push(head);
            rest = tail;
        }
        // Rows at or beyond `n_epochs`, if any, have no others to compare with.
        rest.fill(f64::NAN);
    }
    let spans: Vec<_> = bounds.windows(2).zip(&firsts).zip(parts).collect();
    spans.into_par_iter().for_each(|((e, first), mut part)| {
        for p in part.iter_mut() {
            p.fill(f64::NAN);
        }
        deviations_span(rows, (e[0], e[1]), first, flags, mask, c, shift, &mut |i, r, v| part[i][r - first[i]] = v);
    });
}

/// [`deviations`] over the epochs `e0..e1` of `span`, whose rows start at
/// `first` (per track); each row's deviation goes to `out(track, row, d)`.
#[allow(clippy::too_many_arguments)]
fn deviations_span(
    rows: &Rows,
    span: (usize, usize),
    first: &[usize],
    flags: &[u8],
    mask: u8,
    c: &[f64],
    shift: Option<&[f64]>,
    out: &mut dyn FnMut(usize, usize, f64),
) {
    // Blocks of epochs copied into dense [epoch][track] buffers (each track's
    // rows of a block are contiguous), so that the per-epoch work reads and
    // writes sequentially.
    const BLOCK: usize = 256;
    let n_tracks = rows.tracks();
    let (span_start, span_end) = span;
    let mut cursor: Vec<usize> = first.to_vec();
    let mut block_start = vec![0usize; n_tracks];
    let cells = BLOCK * n_tracks;
    let (mut present, mut value) = (vec![f64::NAN; cells], vec![f64::NAN; cells]);
    let mut dev = vec![f64::NAN; cells];
    let mut scratch = MedianScratch::new(n_tracks);
    for e0 in (span_start..span_end).step_by(BLOCK) {
        let e1 = (e0 + BLOCK).min(span_end);
        present.fill(f64::NAN);
        value.fill(f64::NAN);
        block_start.copy_from_slice(&cursor);
        for i in 0..n_tracks {
            // The track's own rows, indexed from its first.
            let (range, ep, ph) = (rows.range(i), rows.epochs(i), rows.phases(i));
            let (s0, fl, sh) = (range.start, &flags[range.clone()], shift.map(|s| &s[range]));
            let mut j = cursor[i] - s0;
            while j < ep.len() && (ep[j] as usize) < e1 {
                let k = (ep[j] as usize - e0) * n_tracks + i;
                let p = ph[j] - c[i];
                present[k] = p;
                if fl[j] & mask == 0 {
                    value[k] = p - sh.map_or(0.0, |s| s[j]);
                }
                j += 1;
            }
            cursor[i] = s0 + j;
        }
        for e in 0..e1 - e0 {
            let (p_row, v_row) = (&present[e * n_tracks..][..n_tracks], &value[e * n_tracks..][..n_tracks]);
            scratch.deviations(p_row, v_row, &mut dev[e * n_tracks..][..n_tracks]);
        }
        for i in 0..n_tracks {
            let (s0, ep) = (rows.track_start[i], rows.epochs(i));
            for r in block_start[i]..cursor[i] {
                let k = (ep[r - s0] as usize - e0) * n_tracks + i;
                out(i, r, dev[k]);
            }
        }
    }
}

/// The buffers of one epoch's medians of the others (at most
/// [`MAX_AT_EPOCH`] values enter them).
struct MedianScratch {
    vals: [f64; MAX_AT_EPOCH],
    sorted: [f64; MAX_AT_EPOCH],
    rank_of: [usize; MAX_AT_EPOCH],
    keys: [i32; MAX_AT_EPOCH],
    /// Per track: the index of its value in `vals`, `usize::MAX` when none.
    slot: Vec<usize>,
}

impl MedianScratch {
    fn new(n_tracks: usize) -> Self {
        MedianScratch {
            vals: [0.0; MAX_AT_EPOCH],
            sorted: [0.0; MAX_AT_EPOCH],
            rank_of: [0; MAX_AT_EPOCH],
            keys: [0; MAX_AT_EPOCH],
            slot: vec![usize::MAX; n_tracks],
        }
    }

    /// One epoch: per track present (`p_row` finite) its value less the
    /// median of the other tracks' values `v_row` (those finite), into
    /// `d_row`; NaN where fewer than two others.
    #[inline]
    fn deviations(&mut self, p_row: &[f64], v_row: &[f64], d_row: &mut [f64]) {
        let MedianScratch { vals, sorted, rank_of, keys, slot } = self;
        // The values entering the median (at most MAX_AT_EPOCH of them).
        let mut m = 0;
        for (i, &v) in v_row.iter().enumerate() {
            slot[i] = usize::MAX;
            if v.is_finite() && m < MAX_AT_EPOCH {
                vals[m] = v;
                slot[i] = m;
                m += 1;
            }
        }
        // Rank sort of a dozen values: branch-free integer comparisons of
        // order-preserving single-precision keys, their 6 low bits replaced
        // by the index (distinct keys; values within ~1e-5 of each other may
        // come out of order, which moves a median by as little).
        for a in 0..m {
            keys[a] = (order_key(vals[a]) & !63) | a as i32;
        }
        rank_keys(&keys[..m], &mut rank_of[..m]);
        for a in 0..m {
            sorted[rank_of[a]] = vals[a];
        }
        // The median of the others is one of four values: of all m (a track
        // without a value among them), or of the m − 1 left without the
        // track's own value of rank r, whose middle positions j_lo, j_hi
        // then read sorted[j + (j ≥ r)]: both shifted (r ≤ j_lo), the upper
        // one only (j_lo < r ≤ j_hi) or neither.
        let median = |lo: usize, hi: usize| 0.5 * (sorted[lo] + sorted[hi]);
        let outside = if m >= 2 { median((m - 1) / 2, m / 2) } else { f64::NAN };
        let (j_lo, j_hi) = (m.saturating_sub(2) / 2, m.saturating_sub(1) / 2);
        let [below, between, above] = if m >= 3 {
            [median(j_lo + 1, j_hi + 1), median(j_lo, j_hi + 1), median(j_lo, j_hi)]
        } else {
            [f64::NAN; 3]
        };
        for i in 0..p_row.len() {
            if !p_row[i].is_finite() {
                continue;
            }
            let md = match slot[i] {
                usize::MAX => outside,
                a if rank_of[a] <= j_lo => below,
                a if rank_of[a] <= j_hi => between,
                _ => above,
            };
            d_row[i] = p_row[i] - md;
        }
    }
}

/// The rank of each of `keys` (distinct) among them, the number of keys
/// below it, into `rank_of`.
///
/// Up to 16 keys on x86-64 are compared four at a time in SSE2 registers
/// (part of every x86-64 CPU): each key against all four lanes' keys at once,
/// the lanes' counts summed, instead of one comparison per pair.
#[inline]
fn rank_keys(keys: &[i32], rank_of: &mut [usize]) {
    #[cfg(target_arch = "x86_64")]
    if keys.len() <= 16 {
        use std::arch::x86_64::{_mm_cmpgt_epi32, _mm_set1_epi32, _mm_setr_epi32, _mm_setzero_si128};
        use std::arch::x86_64::{_mm_storeu_si128, _mm_sub_epi32};
        // Beyond the keys, the largest value: never below a key.
        let mut padded = [i32::MAX; 16];
        padded[..keys.len()].copy_from_slice(keys);
        let mut ranks = [0i32; 16];
        // SAFETY: SSE2 is part of the x86-64 baseline; each store writes four
        // i32 into four of `ranks`' sixteen.
        unsafe {
            let lanes = [0, 4, 8, 12].map(|g| _mm_setr_epi32(padded[g], padded[g + 1], padded[g + 2], padded[g + 3]));
            let mut counts = [_mm_setzero_si128(); 4];
            for &kb in keys {
                let b = _mm_set1_epi32(kb);
                for g in 0..4 {
                    // A lane whose key is above kb has one more key below it (the mask is −1).
                    counts[g] = _mm_sub_epi32(counts[g], _mm_cmpgt_epi32(lanes[g], b));
                }
            }
            for (g, c) in counts.iter().enumerate() {
                _mm_storeu_si128(ranks[4 * g..].as_mut_ptr().cast(), *c);
            }
        }
        for (r, &n) in rank_of.iter_mut().zip(&ranks[..keys.len()]) {
            *r = n as usize;
        }
        return;
    }
    rank_keys_pairwise(keys, rank_of);
}

/// [`rank_keys`] one pair at a time: for more than 16 keys, other targets,
/// and the reference its tests hold the registers' version to.
fn rank_keys_pairwise(keys: &[i32], rank_of: &mut [usize]) {
    for (&ka, r) in keys.iter().zip(rank_of.iter_mut()) {
        *r = keys.iter().map(|&kb| usize::from(kb < ka)).sum::<usize>();
    }
}

/// The robust scale of a track's deviation about its local level: 1.4826 ×
/// the median of |d − the median of its window| over windows of `window`
/// epochs (a regular subsample of at most 512 windows). A step or an
/// excursion moves few windows' medians, unlike the track's global median.
fn local_sigma(epoch: &[u32], d: &[f64], window: u32, scratch: &mut Vec<f64>) -> f64 {
    let n = epoch.len();
    if n == 0 {
        return f64::NAN;
    }
    let windows = (epoch[n - 1] / window - epoch[0] / window) as usize + 1;
    let stride = windows.div_ceil(512).max(1) as u32;
    let mut block: Vec<f64> = Vec::new();
    scratch.clear();
    let mut j = 0;
    while j < n {
        let w = epoch[j] / window;
        let first = j;
        while j < n && epoch[j] / window == w {
            j += 1;
        }
        if !(w - epoch[0] / window).is_multiple_of(stride) {
            continue;
        }
        block.clear();
        block.extend(d[first..j].iter().copied().filter(|v| v.is_finite()));
        if block.len() < 3 {
            continue;
        }
        let m = median_in_place(&mut block);
        scratch.extend(d[first..j].iter().filter(|v| v.is_finite()).map(|v| (v - m).abs()));
    }
    1.4826 * median_in_place(scratch)
}

/// The median over a regular subsample of the epochs (at most
/// [`MEDIAN_SAMPLE`]) of each track's departure from the mean of the tracks
/// present (at least two; rows in C/N0 drops, start-up ones included, left out of the mean).
fn initial_offsets(rows: &Rows, n_epochs: usize, flags: &[u8]) -> Vec<f64> {
    let n_tracks = rows.tracks();
    let stride = n_epochs.div_ceil(MEDIAN_SAMPLE).max(1);
    let sampled: Vec<usize> = (0..n_epochs).step_by(stride).collect();
    // The departures of a run of sampled epochs, per track.
    let departures = |epochs: &[usize]| -> Vec<Vec<f64>> {
        // Per track: the index of its next row among its own.
        let mut cursor: Vec<usize> = vec![0; n_tracks];
        let mut dep: Vec<Vec<f64>> = vec![Vec::new(); n_tracks];
        let mut at: Vec<(usize, usize)> = Vec::with_capacity(n_tracks);
        for &e in epochs {
            at.clear();
            let (mut sum, mut n) = (0.0, 0usize);
            for i in 0..n_tracks {
                let (ep, start) = (rows.epochs(i), rows.track_start[i]);
                let end = ep.len();
                // The track's row at epoch e, if any (its rows are in epoch order).
                let c = &mut cursor[i];
                if *c < end && (ep[*c] as usize) < e {
                    // Rows are mostly consecutive epochs: jump, then adjust.
                    let guess = (*c + (e - ep[*c] as usize)).min(end - 1);
                    *c = if ep[guess] as usize >= e {
                        *c + ep[*c..=guess].partition_point(|&x| (x as usize) < e)
                    } else {
                        guess + ep[guess..end].partition_point(|&x| (x as usize) < e)
                    };
                }
                if *c < end && ep[*c] as usize == e {
                    at.push((i, *c));
                    if flags[start + *c] & (flag::CN0_DROP | flag::STARTUP_CN0) == 0 {
                        sum += rows.phases(i)[*c];
                        n += 1;
                    }
                }
            }
            if n >= 2 {
                for &(i, r) in &at {
                    dep[i].push(rows.phases(i)[r] - sum / n as f64);
                }
            }
        }
        dep
    };
    // Runs of sampled epochs in parallel, their departures joined in epoch
    // order (the medians are of the same values however the runs fall).
    const RUN_EPOCHS: usize = 1024;
    let parts: Vec<Vec<Vec<f64>>> = sampled.par_chunks(RUN_EPOCHS).map(departures).collect();
    (0..n_tracks)
        .map(|i| {
            let mut v: Vec<f64> = parts.iter().flat_map(|p| p[i].iter().copied()).collect();
            if v.is_empty() { 0.0 } else { median_in_place(&mut v) }
        })
        .collect()
}

/// The most values a median of a track's rows is taken over (a regular
/// subsample beyond: the medians set offsets and scales, not row decisions).
const MEDIAN_SAMPLE: usize = 16_384;

/// Median of the finite values among `values` (a regular subsample of at most
/// [`MEDIAN_SAMPLE`]), each mapped by `f`; NaN when there is none.
fn sampled_median(values: &[f64], scratch: &mut Vec<f64>, f: impl Fn(f64) -> f64) -> f64 {
    let stride = values.len().div_ceil(MEDIAN_SAMPLE).max(1);
    scratch.clear();
    scratch.extend(values.iter().step_by(stride).copied().filter(|v| v.is_finite()).map(f));
    median_in_place(scratch)
}

/// Screens the rows (see the crate documentation, section "Screening"). `n_epochs`: the epoch
/// indices are below it; `log_interval_s`: the epoch spacing.
///
/// The stages: C/N0 drops (test 5), the deviations from the other tracks
/// with each track's offset and σ and its slips and levels (test 1, two
/// rounds), the linear range (test 4), noisy stretches (test 2), low gain
/// (test 3), what could not be checked, and each track's outcome.
pub(crate) fn screen(rows: &Rows, n_epochs: usize, log_interval_s: f64, cfg: &ScreeningConfig) -> Screened {
    let mut out = Screened::none(rows);
    if !cfg.enabled || rows.len() == 0 {
        return out;
    }
    let windows = Windows::new(log_interval_s, cfg);
    let cn0_medians = cn0_drops(rows, cfg, windows.guard, &mut out.flags);
    for (sum, median_cn0) in out.summaries.iter_mut().zip(cn0_medians) {
        sum.median_cn0_dbhz = Some(median_cn0).filter(|v| v.is_finite());
    }
    let dev = deviations_and_slips(rows, n_epochs, log_interval_s, cfg, &windows, &mut out);
    if let Some(limit) = cfg.max_abs_phase_rad {
        phase_range(rows, &dev, limit, windows.guard, &mut out.flags);
    }
    for (sum, s) in out.summaries.iter_mut().zip(&dev.sigma) {
        sum.deviation_sigma_rad = Some(*s).filter(|v| v.is_finite());
    }
    per_track(&mut out.flags, &rows.track_start).into_par_iter().enumerate().for_each(|(i, fl)| {
        if dev.sigma[i].is_finite() {
            let range = rows.range(i);
            let (ep, d, lvl) = (rows.epochs(i), &dev.d[range.clone()], &dev.level[range]);
            noisy_windows(ep, d, lvl, dev.sigma[i], windows.noisy, cfg.noisy_rms_k, windows.guard, fl);
        }
    });
    let (tested, pooled) = low_gain(rows, &dev, cfg, &windows, &mut out.flags);
    for (sum, p) in out.summaries.iter_mut().zip(pooled) {
        (sum.relative_gain, sum.relative_gain_se) = (p.map(|p| p.0), p.map(|p| p.1));
    }
    note_not_checked(rows, &dev.sigma, &tested, cfg, windows.gain, &mut out.summaries);
    track_outcomes(rows, cfg, &mut out);
    out
}

/// The screening's windows in epochs: the guard around every exclusion,
/// the noisy-stretch and the gain test's windows.
struct Windows {
    guard: u32,
    noisy: u32,
    gain: u32,
}

impl Windows {
    fn new(log_interval_s: f64, cfg: &ScreeningConfig) -> Self {
        let epochs_of = |s: f64| (s / log_interval_s).round().max(0.0) as u32;
        Windows {
            guard: epochs_of(cfg.guard_s),
            noisy: epochs_of(cfg.noisy_window_s).max(1),
            gain: epochs_of(cfg.gain_window_s).max(2),
        }
    }
}

/// Test 5, C/N0 drops: rows more than `cfg.cn0_drop_db` below their track's
/// median C/N0, with the guard; a drop whose first low row lies in the
/// track's start-up is the start-up, and so is every row before it. Each
/// track on its own, the tracks in parallel; returns their median C/N0.
fn cn0_drops(rows: &Rows, cfg: &ScreeningConfig, guard: u32, flags: &mut [u8]) -> Vec<f64> {
    per_track(flags, &rows.track_start)
        .into_par_iter()
        .enumerate()
        .map_init(Vec::new, |scratch, (i, fl)| {
            let median_cn0 = sampled_median(rows.cn0s(i), scratch, |v| v);
            if let Some(x) = cfg.cn0_drop_db {
                let (ep, cn0) = (rows.epochs(i), rows.cn0s(i));
                let low: Vec<bool> = cn0.iter().map(|&v| v < median_cn0 - x).collect();
                let mut drop: Vec<u8> = low.iter().map(|&l| if l { flag::CN0_DROP } else { 0 }).collect();
                spread_with_guard(ep, &mut drop, flag::CN0_DROP, guard);
                mark_drops(ep, &low, &drop, rows.startup_end(i), fl);
            }
            median_cn0
        })
        .collect()
}

/// Flags each stretch of `drop` (drops closer than two guards merged) in
/// `fl`: the start-up when its first `low` row lies before `startup_end`
/// (then so is every row before it: the estimator averaged them, the
/// pull-in, into that low C/N0), else a C/N0 drop.
fn mark_drops(ep: &[u32], low: &[bool], drop: &[u8], startup_end: u32, fl: &mut [u8]) {
    let mut j = 0;
    while j < drop.len() {
        if drop[j] == 0 {
            j += 1;
            continue;
        }
        let a = j;
        while j < drop.len() && drop[j] != 0 {
            j += 1;
        }
        let first_low = (a..j).find(|&r| low[r]).unwrap_or(a);
        let (bit, from) = if ep[first_low] < startup_end { (flag::STARTUP_CN0, 0) } else { (flag::CN0_DROP, a) };
        for f in &mut fl[from..j] {
            *f |= bit;
        }
    }
}

/// What the comparison with the other tracks gives (tests 1–4 use it).
struct Deviation {
    /// Per track: its offset.
    c: Vec<f64>,
    /// Per row: its deviation from the other tracks' median, less its track's offset refinement.
    d: Vec<f64>,
    /// Per row: its track's level there (steps included).
    level: Vec<f64>,
    /// Per track: its deviation's robust σ (NaN: never compared with two others).
    sigma: Vec<f64>,
}

/// Test 1 and the deviations it rests on, in two rounds: the first finds
/// each track's levels (steps) and slips against the others as they are;
/// the second (when the first found any) compares every track with the
/// others less their levels and without their slips, and is the one kept.
/// Sets the slips' flags, the segments, and the summaries' slips and steps.
fn deviations_and_slips(
    rows: &Rows,
    n_epochs: usize,
    log_interval_s: f64,
    cfg: &ScreeningConfig,
    windows: &Windows,
    out: &mut Screened,
) -> Deviation {
    let n_tracks = rows.tracks();
    // Initial offsets: the median of each track's departure from the mean of
    // the tracks present (exact up to a common constant while the set of
    // tracks does not change), over a regular subsample of the epochs.
    let mut dev = Deviation {
        c: initial_offsets(rows, n_epochs, &out.flags),
        // Zeroed pages, filled with NaN by `deviations` span by span.
        d: vec![0.0; rows.len()],
        level: vec![0.0; rows.len()],
        sigma: vec![f64::NAN; n_tracks],
    };
    let mut startup_events = vec![0usize; n_tracks];
    for round in 0..2 {
        // The rows kept out of the medians: C/N0 drops, and the first round's
        // slips; start-up transients as either.
        let cn0_mask = flag::CN0_DROP | flag::STARTUP_CN0;
        let (mask, shift) = if round == 0 {
            (cn0_mask, None)
        } else {
            (cn0_mask | flag::SLIP | flag::STARTUP, Some(dev.level.as_slice()))
        };
        deviations(rows, n_epochs, &out.flags, mask, &dev.c, shift, &mut dev.d);
        refine_offsets(rows, windows.noisy, cfg, &mut dev);
        let events = slip_round(rows, round, &mut dev, (log_interval_s, cfg, windows.guard), out);
        for (i, ev) in events.into_iter().enumerate() {
            if let Some(ev) = ev {
                out.summaries[i].slips = ev.slips;
                out.summaries[i].steps = ev.steps;
                out.segments[i] = ev.steps + 1;
                startup_events[i] = ev.startup;
            }
        }
        // Nothing found: the second round would find the same.
        if round == 0 && out.summaries.iter().zip(&startup_events).all(|(s, &st)| s.slips == 0 && st == 0) {
            break;
        }
    }
    dev
}

/// Each track's own offset refined by the median of its deviations (the
/// others' medians are robust to their small errors), which leaves them;
/// σ from the local MAD over windows of `noisy_window` epochs. Each track on
/// its own, the tracks in parallel.
fn refine_offsets(rows: &Rows, noisy_window: u32, cfg: &ScreeningConfig, dev: &mut Deviation) {
    let refined: Vec<Option<(f64, f64)>> = per_track(&mut dev.d, &rows.track_start)
        .into_par_iter()
        .enumerate()
        .map_init(Vec::new, |scratch, (i, d)| {
            let m = sampled_median(d, scratch, |v| v);
            m.is_finite().then(|| {
                for v in d.iter_mut() {
                    *v -= m;
                }
                (m, local_sigma(rows.epochs(i), d, noisy_window, scratch).max(cfg.min_sigma_rad))
            })
        })
        .collect();
    for (i, r) in refined.into_iter().enumerate() {
        if let Some((m, s)) = r {
            dev.c[i] += m;
            dev.sigma[i] = s;
        }
    }
}

/// One round of test 1 (slips, steps, levels), track by track in parallel
/// (the second round first clears the first's flags, levels and segments);
/// a track without a σ is not tested (`None`).
fn slip_round(
    rows: &Rows,
    round: usize,
    dev: &mut Deviation,
    (log_interval_s, cfg, guard): (f64, &ScreeningConfig, u32),
    out: &mut Screened,
) -> Vec<Option<SlipEvents>> {
    let per_row = per_track(&mut dev.level, &rows.track_start)
        .into_iter()
        .zip(per_track(&mut out.flags, &rows.track_start))
        .zip(per_track(&mut out.segment, &rows.track_start))
        .collect::<Vec<_>>();
    let (d, sigma) = (&dev.d, &dev.sigma);
    per_row
        .into_par_iter()
        .enumerate()
        .map_init(Vec::new, |buf, (i, ((lvl, fl), seg))| {
            if round == 1 {
                seg.fill(0);
                lvl.fill(0.0);
                for f in fl.iter_mut() {
                    *f &= !(flag::SLIP | flag::STARTUP);
                }
            }
            if !sigma[i].is_finite() {
                return None;
            }
            let range = rows.range(i);
            let (ep, dv) = (rows.epochs(i), &d[range]);
            let startup_end = rows.startup_end(i);
            Some(slip_events(ep, dv, sigma[i], log_interval_s, cfg, guard, startup_end, lvl, fl, seg, buf))
        })
        .collect()
}

/// Test 4, beyond the linear range on its own: |φ| above the limit by more
/// than the track's noise explains, while the common level (the others'
/// median plus the track's offset, φ − d) is well within it; a log of a
/// single track has no common level (and no σ) to compare with. The tracks
/// in parallel.
fn phase_range(rows: &Rows, dev: &Deviation, limit: f64, guard: u32, flags: &mut [u8]) {
    per_track(flags, &rows.track_start).into_par_iter().enumerate().for_each(|(i, fl)| {
        let range = rows.range(i);
        // In the discriminator's own units: the phase on L1's scale over f_L1/f_c,
        // plus the noise margin (docs of `phase_range_margin_rad`).
        let limit = limit * rows.to_l1(i) + phase_range_margin_rad(dev.sigma[i], range.len());
        for (f, r) in fl.iter_mut().zip(range.clone()) {
            let (p, d) = (rows.phases(i)[r - range.start], dev.d[r]);
            // A start-up row is excluded already, as the pull-in it is.
            if *f & flag::ANY_STARTUP != 0 {
                continue;
            }
            if p.abs() > limit && (!d.is_finite() || (p - d).abs() < 0.5 * limit) {
                *f |= flag::PHASE_RANGE;
            }
        }
        spread_with_guard(rows.epochs(i), fl, flag::PHASE_RANGE, guard);
    });
}

/// Test 3, low gain: each track's windows fitted on either core, gathered
/// in track order, then tested ([`low_gain_windows`]). Returns per track
/// the windows tested and the pooled gain with its standard error.
fn low_gain(
    rows: &Rows,
    dev: &Deviation,
    cfg: &ScreeningConfig,
    windows: &Windows,
    flags: &mut [u8],
) -> (Vec<usize>, Vec<Option<(f64, f64)>>) {
    let inputs: Vec<Option<GainInput>> = (0..rows.tracks())
        .map(|i| {
            let range = rows.range(i);
            dev.sigma[i].is_finite().then(|| GainInput {
                epoch: rows.epochs(i),
                phase: rows.phases(i),
                dev: &dev.d[range.clone()],
                level: &dev.level[range],
                offset: dev.c[i],
            })
        })
        .collect();
    let per_track_fits: Vec<Vec<GainFit>> = inputs
        .par_iter()
        .enumerate()
        .map(|(i, g)| {
            let mut track_fits = Vec::new();
            if let Some(g) = g {
                gain_fits(g, i, windows.gain, &flags[rows.range(i)], &mut track_fits);
            }
            track_fits
        })
        .collect();
    let fits: Vec<GainFit> = per_track_fits.into_iter().flatten().collect();
    low_gain_windows(&inputs, rows, &fits, cfg, windows.guard, flags)
}

/// What could not be checked, track by track: everything without a σ;
/// the gain test without a window tested, the whole-track gain with one.
fn note_not_checked(
    rows: &Rows,
    sigma: &[f64],
    tested: &[usize],
    cfg: &ScreeningConfig,
    gain_window: u32,
    summaries: &mut [TrackScreening],
) {
    for i in 0..rows.tracks() {
        let not_checked = &mut summaries[i].not_checked;
        if !sigma[i].is_finite() {
            not_checked
                .push("slips, noisy stretches, low gain (never two other tracks at its epochs to compare with)".into());
            continue;
        }
        let rows_i = rows.range(i).len();
        let min_rows = (gain_window as usize / 4).max(10);
        match tested[i] {
            0 if rows_i < min_rows => not_checked.push(format!(
                "low gain (needs {min_rows} rows in one {} s window; the track has {rows_i})",
                cfg.gain_window_s
            )),
            0 => not_checked.push(format!(
                "low gain (no {} s window with {min_rows} of its rows in which three tracks follow a common signal)",
                cfg.gain_window_s
            )),
            1 => not_checked.push(format!("whole-track gain (one {} s window tested; needs two)", cfg.gain_window_s)),
            _ => {}
        }
    }
}

/// Each track's outcome: excluded whole when the cross-channel tests flag
/// more than `cfg.max_excluded_fraction` of its rows; its counts per reason
/// and its excluded spans (at most [`MAX_SPANS`]). The tracks in parallel.
fn track_outcomes(rows: &Rows, cfg: &ScreeningConfig, out: &mut Screened) {
    let per_row = per_track(&mut out.flags, &rows.track_start);
    let each = per_row.into_par_iter().zip(out.summaries.par_iter_mut()).zip(out.spans.par_iter_mut());
    each.enumerate().for_each(|(i, ((fl, sum), spans))| {
        let range = rows.range(i);
        let n = range.len();
        let excluded = fl.iter().filter(|&&f| f & (flag::SLIP | flag::NOISY | flag::LOW_GAIN) != 0).count();
        if n > 0 && excluded as f64 > cfg.max_excluded_fraction * n as f64 {
            sum.track_excluded = true;
            for f in fl.iter_mut() {
                *f |= flag::TRACK;
            }
        }
        count_rows(fl, sum);
        *spans = excluded_spans(rows.epochs(i), fl);
    });
}

/// A track's excluded rows in `sum`: in all, and per reason.
fn count_rows(fl: &[u8], sum: &mut TrackScreening) {
    let mut counts = [0usize; 8];
    let mut excluded_rows = 0;
    for &f in fl {
        excluded_rows += usize::from(f != 0);
        for (b, n) in counts.iter_mut().enumerate() {
            *n += usize::from(f >> b & 1 != 0);
        }
    }
    let count = |bit: u8| counts[bit.trailing_zeros() as usize];
    sum.rows_excluded = excluded_rows;
    sum.rows_slip = count(flag::SLIP);
    sum.rows_noisy = count(flag::NOISY);
    sum.rows_low_gain = count(flag::LOW_GAIN);
    sum.rows_phase_range = count(flag::PHASE_RANGE);
    sum.rows_cn0_drop = count(flag::CN0_DROP);
    sum.rows_startup = fl.iter().filter(|&&f| f & flag::ANY_STARTUP != 0).count();
}

/// The runs of a track's flagged rows (epochs `ep`), at most [`MAX_SPANS`].
fn excluded_spans(ep: &[u32], fl: &[u8]) -> Vec<EpochSpan> {
    let n = fl.len();
    let mut spans = Vec::new();
    let mut j = 0;
    while j < n && spans.len() < MAX_SPANS {
        if fl[j] == 0 {
            j += 1;
            continue;
        }
        let mut span = EpochSpan { first_epoch: ep[j], last_epoch: ep[j], rows: 0, flags: 0 };
        while j < n && fl[j] != 0 {
            span.last_epoch = ep[j];
            span.rows += 1;
            span.flags |= fl[j];
            j += 1;
        }
        spans.push(span);
    }
    spans
}

/// The noise margin of the linear-range test \[rad\]: z·σ, σ the track's
/// deviation σ (its noise, from the comparison with the other tracks) and z
/// the two-sided normal quantile at [`PHASE_RANGE_FALSE_ALARM`] over the
/// track's `rows`, z = Φ⁻¹(1 − α/(2n)) (Bonferroni). A single 1 ms Costas
/// output at 39 dB-Hz has σ ≈ 0.25 rad (1/√(2·C/N0·T)): noise alone would
/// cross π/4 in one row of 500, and excluding those rows (with their guard)
/// would select on the noise and on the signal riding under it, biasing Γ̂
/// towards zero. 0 when σ is unknown (a single track).
fn phase_range_margin_rad(sigma_rad: f64, rows: usize) -> f64 {
    use statrs::distribution::{ContinuousCDF, Normal};
    if !sigma_rad.is_finite() || rows == 0 {
        return 0.0;
    }
    let z = Normal::standard().inverse_cdf(1.0 - PHASE_RANGE_FALSE_ALARM / (2.0 * rows as f64));
    z * sigma_rad
}

/// Probability that noise alone flags any row of a track in the linear-range
/// test (test 4): 1 %.
pub(crate) const PHASE_RANGE_FALSE_ALARM: f64 = 0.01;

/// Extends the rows carrying any of `bits` by `guard` epochs on each side
/// (within the track), setting the same bits there.
fn spread_with_guard(epoch: &[u32], flags: &mut [u8], bits: u8, guard: u32) {
    if guard == 0 || !flags.iter().any(|&f| f & bits != 0) {
        return;
    }
    let n = epoch.len();
    let mut add = vec![0u8; n];
    for bit in (0..8).map(|b| 1u8 << b).filter(|b| bits & b != 0) {
        // Forward: rows up to `guard` epochs after a flagged one; then backward.
        let mut last: Option<u32> = None;
        for j in 0..n {
            if flags[j] & bit != 0 {
                last = Some(epoch[j]);
            } else if last.is_some_and(|e| epoch[j] - e <= guard) {
                add[j] |= bit;
            }
        }
        let mut next: Option<u32> = None;
        for j in (0..n).rev() {
            if flags[j] & bit != 0 {
                next = Some(epoch[j]);
            } else if next.is_some_and(|e| e - epoch[j] <= guard) {
                add[j] |= bit;
            }
        }
    }
    for (f, a) in flags.iter_mut().zip(add) {
        *f |= a;
    }
}

/// Sets `bit` on the rows whose epoch lies in `[first, last]` (epochs, saturating).
fn flag_epochs(epoch: &[u32], flags: &mut [u8], first: u32, last: u32, bit: u8) {
    let a = epoch.partition_point(|&e| e < first);
    let b = epoch.partition_point(|&e| e <= last);
    for f in &mut flags[a..b] {
        *f |= bit;
    }
}

/// What test 1 found on one track.
#[derive(Debug, Clone, Copy, Default)]
struct SlipEvents {
    /// Slip / excursion events (start-up ones not included).
    slips: usize,
    /// Of them, those that settled on a new level.
    steps: usize,
    /// Events that began in the track's start-up (its pull-in).
    startup: usize,
}

/// Test 1 on one track: sets the SLIP flags (STARTUP for an event beginning
/// before epoch `startup_end`: the pull-in, neither a slip nor a step), the
/// level of every row and the segment of every row.
///
/// The deviation is followed around a level that adapts to the in-bound
/// rows; a row out of bounds starts an event, which ends when the
/// deviation has stayed in bounds for `settle_s` (a lone row out of bounds
/// is noise, not a slip) or, after `step_min_s`, has settled on a new level
/// (a step); one never settled is excluded to the end of the track.
#[allow(clippy::too_many_arguments)]
fn slip_events(
    epoch: &[u32],
    d: &[f64],
    sigma: f64,
    log_interval_s: f64,
    cfg: &ScreeningConfig,
    guard: u32,
    startup_end: u32,
    level: &mut [f64],
    flags: &mut [u8],
    segment: &mut [u16],
    ev: &mut Vec<usize>,
) -> SlipEvents {
    let Some(first_valid) = d.iter().position(|v| v.is_finite()) else {
        return SlipEvents::default();
    };
    let mut scan = SlipScan::new((epoch, d), sigma, log_interval_s, cfg, (guard, startup_end));
    let alpha = (log_interval_s / cfg.level_tau_s).min(1.0);
    let thr = scan.thr;
    // The offset makes the track's median deviation zero: the level of its bulk.
    let mut l = 0.0;
    let mut seg: u16 = 0;
    // The event: its rows with a deviation (`ev`), the latest out of bounds.
    ev.clear();
    let mut last_out = 0usize;
    // Rows of the event beyond the bounds: a lone one is the discriminator's
    // noise, not a slip (see `ScreeningConfig::deviation_k`).
    let mut n_out = 0usize;
    let mut window: Vec<f64> = Vec::new();
    for j in 0..epoch.len() {
        segment[j] = seg;
        level[j] = l;
        let x = d[j] - l;
        if !x.is_finite() {
            continue;
        }
        if ev.is_empty() {
            if x.abs() <= thr {
                l += alpha * x;
                level[j] = l;
            } else {
                ev.push(j);
                (last_out, n_out) = (j, 1);
            }
            continue;
        }
        ev.push(j);
        if x.abs() > thr {
            last_out = j;
            n_out += 1;
        } else if epoch[j] - epoch[last_out] >= scan.settle {
            // Back within bounds long enough: the event ends.
            if n_out >= 2 {
                scan.flag_event(ev[0], epoch[last_out] + guard, flags);
            }
            ev.clear();
            continue;
        }
        let Some((b, m)) = scan.settled_level(ev, j, &mut window) else { continue };
        let rb = ev[b];
        if rb != first_valid && scan.end_at_step(ev[0], epoch[rb], m - l, flags) {
            seg = seg.saturating_add(1);
        }
        l = m;
        level[rb..=j].fill(l);
        segment[rb..=j].fill(seg);
        ev.clear();
    }
    if n_out >= 2 && !ev.is_empty() {
        // Never settled: excluded to the end of the track.
        scan.flag_event(ev[0], u32::MAX, flags);
    }
    scan.found
}

/// What test 1 follows one track with: its rows' epochs and deviations, the
/// bound, the settings in epochs, and the events found so far.
struct SlipScan<'a> {
    epoch: &'a [u32],
    d: &'a [f64],
    /// The bound k·σ \[rad\].
    thr: f64,
    guard: u32,
    startup_end: u32,
    /// `settle_s`, `step_min_s` and half of it, in epochs (at least 1).
    settle: u32,
    step_min: u32,
    step_win: u32,
    found: SlipEvents,
}

impl<'a> SlipScan<'a> {
    fn new(
        (epoch, d): (&'a [u32], &'a [f64]),
        sigma: f64,
        log_interval_s: f64,
        cfg: &ScreeningConfig,
        (guard, startup_end): (u32, u32),
    ) -> Self {
        let to_epochs = |s: f64| ((s / log_interval_s).round() as u32).max(1);
        SlipScan {
            epoch,
            d,
            thr: cfg.deviation_k * sigma,
            guard,
            startup_end,
            settle: to_epochs(cfg.settle_s),
            step_min: to_epochs(cfg.step_min_s),
            step_win: to_epochs(cfg.step_min_s / 2.0),
            found: SlipEvents::default(),
        }
    }

    /// Counts an event beginning at row `first`: one that began in the
    /// start-up is the pull-in, flagged as such and not counted as a slip.
    /// Returns its flag.
    fn close(&mut self, first: usize) -> u8 {
        if self.epoch[first] < self.startup_end {
            self.found.startup += 1;
            flag::STARTUP
        } else {
            self.found.slips += 1;
            flag::SLIP
        }
    }

    /// Where an event's exclusion starts: the guard before its first row, or
    /// the track's first row for the start-up (what precedes the pull-in's
    /// excursion is the pull-in too).
    fn excluded_from(&self, bit: u8, first: usize) -> u32 {
        if bit == flag::STARTUP { self.epoch[0] } else { self.epoch[first].saturating_sub(self.guard) }
    }

    /// Counts the event beginning at row `first` and flags it up to epoch `last` (inclusive).
    fn flag_event(&mut self, first: usize, last: u32, flags: &mut [u8]) {
        let bit = self.close(first);
        flag_epochs(self.epoch, flags, self.excluded_from(bit, first), last, bit);
    }

    /// The event of rows `ev` at row `j`: after `step_min`, the last
    /// `step_win` epochs quiet around a new level m; then the index in `ev`
    /// of the earliest row fitting it, and m.
    fn settled_level(&self, ev: &[usize], j: usize, window: &mut Vec<f64>) -> Option<(usize, f64)> {
        let (epoch, d, thr) = (self.epoch, self.d, self.thr);
        if epoch[j] - epoch[ev[0]] < self.step_min {
            return None;
        }
        let from = epoch[j].saturating_sub(self.step_win - 1);
        let first = ev.partition_point(|&k| epoch[k] < from);
        if ev.len() - first < (self.step_win as usize / 2).max(2) {
            return None;
        }
        window.clear();
        window.extend(ev[first..].iter().map(|&k| d[k]));
        let m = median_in_place(window);
        if !ev[first..].iter().all(|&k| (d[k] - m).abs() <= thr) {
            return None;
        }
        // Settled on the level m: the event ends at the earliest row fitting it.
        let mut b = first;
        while b > 0 && (d[ev[b - 1]] - m).abs() <= thr {
            b -= 1;
        }
        Some((b, m))
    }

    /// Ends the event beginning at row `first` on a level reached at epoch
    /// `eb`, `jump` \[rad\] from the old one: flags it up to `eb` and the guard
    /// after it. Returns whether it is a step: a new level beyond the bounds
    /// of the old one (not the level a pull-in settles on), which begins a
    /// new segment.
    fn end_at_step(&mut self, first: usize, eb: u32, jump: f64, flags: &mut [u8]) -> bool {
        let bit = self.close(first);
        let lo = self.excluded_from(bit, first);
        flag_epochs(self.epoch, flags, lo, eb.saturating_sub(1).max(lo), bit);
        flag_epochs(self.epoch, flags, eb, eb + self.guard, bit);
        let step = bit == flag::SLIP && jump.abs() > self.thr;
        if step {
            self.found.steps += 1;
        }
        step
    }
}

/// Test 2 on one track: windows whose deviation RMS (about the level, over the
/// rows not yet excluded) exceeds `k·σ`.
#[allow(clippy::too_many_arguments)]
fn noisy_windows(
    epoch: &[u32],
    d: &[f64],
    level: &[f64],
    sigma: f64,
    window: u32,
    k: f64,
    guard: u32,
    flags: &mut [u8],
) {
    let n = epoch.len();
    let limit = (k * sigma).powi(2);
    let min_rows = (window as usize / 4).max(3);
    let mut j = 0;
    while j < n {
        let w = epoch[j] / window;
        let mut end = j;
        let (mut ss, mut m) = (0.0, 0usize);
        while end < n && epoch[end] / window == w {
            if d[end].is_finite() && flags[end] == 0 {
                ss += (d[end] - level[end]).powi(2);
                m += 1;
            }
            end += 1;
        }
        if m >= min_rows && ss / m as f64 > limit {
            flag_epochs(epoch, flags, (w * window).saturating_sub(guard), (w + 1) * window - 1 + guard, flag::NOISY);
        }
        j = end;
    }
}

/// One track's inputs of the gain test (row-major slices of the track).
struct GainInput<'a> {
    epoch: &'a [u32],
    phase: &'a [f64],
    dev: &'a [f64],
    level: &'a [f64],
    offset: f64,
}

impl GainInput<'_> {
    /// The row enters the fit (a deviation, not excluded yet).
    #[inline]
    fn usable(&self, flags: &[u8], j: usize) -> bool {
        flags[j] == 0 && self.dev[j].is_finite()
    }

    /// The reference the track is regressed on: the median of the others at
    /// the row's epoch, which is the phase less the offset and the deviation
    /// (d = φ − c − median; not stored: a row table's worth of memory).
    #[inline]
    fn x(&self, j: usize) -> f64 {
        self.phase[j] - self.offset - self.dev[j]
    }

    /// The track's phase less its offset and level (steps removed).
    #[inline]
    fn y(&self, j: usize) -> f64 {
        self.phase[j] - self.offset - self.level[j]
    }
}

/// The regression of one track's phase on the median of the others over one window.
#[derive(Debug, Clone, Copy)]
struct GainFit {
    window: u32,
    track: usize,
    /// The track's rows `first..=last` (relative to the track) span the window.
    first: usize,
    last: usize,
    /// Slope (attenuated by the reference's own noise, as every track's in the window).
    slope: f64,
    /// Its standard error, inflated for the residuals' lag-one correlation ρ by √((1 + ρ)/(1 − ρ)).
    se: f64,
}

/// Sums over pairs of consecutive rows (x, y) and (x₋, y₋) of a window.
#[derive(Debug, Clone, Copy, Default)]
struct Lagged {
    n: f64,
    xx: f64,
    yy: f64,
    xy_: f64,
    x_y: f64,
    x: f64,
    y: f64,
    x_: f64,
    y_: f64,
}

impl Lagged {
    #[inline]
    fn add(&mut self, x: f64, y: f64, xp: f64, yp: f64) {
        self.n += 1.0;
        self.xx += x * xp;
        self.yy += y * yp;
        self.xy_ += x * yp;
        self.x_y += xp * y;
        self.x += x;
        self.y += y;
        self.x_ += xp;
        self.y_ += yp;
    }

    /// Σ (u_k − ū)(u_{k−1} − ū) over the pairs, u = y − b·x, ū its mean over the window.
    fn residual_lag1(&self, b: f64, u_mean: f64) -> f64 {
        let uu = self.yy - b * (self.xy_ + self.x_y) + b * b * self.xx;
        let (u, u_) = (self.y - b * self.x, self.y_ - b * self.x_);
        uu - u_mean * (u + u_) + self.n * u_mean * u_mean
    }
}

/// Test 3, first half: the sums of each window of one track (rows not yet
/// excluded), in one pass.
fn gain_fits(g: &GainInput, track: usize, window: u32, flags: &[u8], fits: &mut Vec<GainFit>) {
    let n = g.epoch.len();
    let min_rows = (window as usize / 4).max(10);
    let mut j = 0;
    while j < n {
        let w = g.epoch[j] / window;
        let first = j;
        let (mut m, mut sx, mut sy, mut sxx, mut sxy, mut syy) = (0usize, 0.0, 0.0, 0.0, 0.0, 0.0);
        // Lagged sums over consecutive usable rows (for the residuals' lag-one correlation).
        let mut lag = Lagged::default();
        let mut prev: Option<(f64, f64)> = None;
        // Shifted sums (by the window's first values) for accuracy; the
        // reference of the first usable row (a row without a deviation has none).
        let y0 = g.y(j);
        let mut x0 = None;
        while j < n && g.epoch[j] / window == w {
            if g.usable(flags, j) {
                let x0 = *x0.get_or_insert_with(|| g.x(j));
                let (x, y) = (g.x(j) - x0, g.y(j) - y0);
                m += 1;
                sx += x;
                sy += y;
                sxx += x * x;
                sxy += x * y;
                syy += y * y;
                if let Some((xp, yp)) = prev {
                    lag.add(x, y, xp, yp);
                }
                prev = Some((x, y));
            }
            j += 1;
        }
        if m < min_rows {
            continue;
        }
        let mf = m as f64;
        let (cxx, cxy, cyy) = (sxx - sx * sx / mf, sxy - sx * sy / mf, syy - sy * sy / mf);
        if cxx <= 0.0 {
            continue;
        }
        let slope = cxy / cxx;
        let see = (cyy - slope * cxy).max(0.0);
        let rho =
            if see > 0.0 { (lag.residual_lag1(slope, (sy - slope * sx) / mf) / see).clamp(0.0, 0.99) } else { 0.0 };
        let se = (see / (mf - 2.0).max(1.0) / cxx).sqrt() * ((1.0 + rho) / (1.0 - rho)).sqrt();
        fits.push(GainFit { window: w, track, first, last: j - 1, slope, se });
    }
}

/// Test 3, second half: in each window fitted for at least three tracks, the
/// median slope stands for a track that follows the common signal (the
/// reference's noise attenuates every slope alike); where it is at least 0.8
/// (the common signal dominates the reference's noise), a track whose slope
/// relative to it is below `min_gain` by more than two standard errors is
/// flagged; so is a whole track whose tested windows pooled are below
/// `min_track_gain` by more than two standard errors. Returns the number of
/// windows tested per track and, for those with two or more, the pooled gain
/// and its standard error.
fn low_gain_windows(
    inputs: &[Option<GainInput>],
    rows: &Rows,
    fits: &[GainFit],
    cfg: &ScreeningConfig,
    guard: u32,
    flags: &mut [u8],
) -> (Vec<usize>, Vec<Option<(f64, f64)>>) {
    // Per track: the tested windows' gains and standard errors (for the pooled test).
    let mut tested: Vec<Vec<(f64, f64)>> = vec![Vec::new(); rows.tracks()];
    let mut low: Vec<(usize, u32, u32)> = Vec::new();
    let mut order: Vec<usize> = (0..fits.len()).collect();
    order.sort_by_key(|&f| (fits[f].window, fits[f].track));
    let mut slopes: Vec<f64> = Vec::new();
    let mut a = 0;
    while a < order.len() {
        let w = fits[order[a]].window;
        let b = a + order[a..].partition_point(|&f| fits[f].window == w);
        let group = &order[a..b];
        a = b;
        if group.len() < 3 {
            continue;
        }
        slopes.clear();
        slopes.extend(group.iter().map(|&f| fits[f].slope));
        let typical = median_in_place(&mut slopes);
        if typical.is_nan() || typical < 0.8 {
            continue;
        }
        for &f in group {
            let fit = &fits[f];
            let Some(g) = &inputs[fit.track] else { continue };
            let (gain, se) = (fit.slope / typical, fit.se / typical);
            tested[fit.track].push((gain, se));
            if gain + 2.0 * se < cfg.min_gain {
                low.push((fit.track, g.epoch[fit.first], g.epoch[fit.last]));
            }
        }
    }
    for (track, first, last) in low {
        let range = rows.range(track);
        let (ep, fl) = (rows.epochs(track), &mut flags[range]);
        flag_epochs(ep, fl, first.saturating_sub(guard), last + guard, flag::LOW_GAIN);
    }
    // The whole track: its windows pooled (inverse-variance weights; the
    // spread of the windows' gains bounds the standard error from below).
    let mut pooled_of = vec![None; tested.len()];
    for (i, t) in tested.iter().enumerate() {
        if t.len() < 2 {
            continue;
        }
        let wsum: f64 = t.iter().map(|&(_, se)| 1.0 / (se * se).max(1e-12)).sum();
        let pooled = t.iter().map(|&(g, se)| g / (se * se).max(1e-12)).sum::<f64>() / wsum;
        let nf = t.len() as f64;
        let mean = t.iter().map(|&(g, _)| g).sum::<f64>() / nf;
        let spread = (t.iter().map(|&(g, _)| (g - mean).powi(2)).sum::<f64>() / (nf - 1.0) / nf).sqrt();
        let se = (1.0 / wsum).sqrt().max(spread);
        pooled_of[i] = Some((pooled, se));
        if pooled + 2.0 * se < cfg.min_track_gain {
            for f in &mut flags[rows.range(i)] {
                *f |= flag::LOW_GAIN;
            }
        }
    }
    (tested.iter().map(Vec::len).collect(), pooled_of)
}

#[cfg(test)]
mod tests;
