//! Session preparation: the epoch grid, the selection, the averaging and the
//! IMU interpolation (documented at the crate root).

use std::borrow::Cow;
use std::path::Path;

use serde::{Deserialize, Serialize};

use gsens_io::{ImuSeries, TrackingLog, read_imu_file, read_tracking_file};

use crate::error::SessionError;
use crate::screening::{self, Screened, ScreeningConfig, TrackScreening};

mod average;
mod grid;
mod rank;
mod rows;
mod summaries;

use average::Averaged;
use grid::Grid;
use rows::RowFilter;
use summaries::RemovedOffsets;

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
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum Weighting {
    /// Equal weights (the paper).
    ///
    /// Equal weights on one carrier: `w = 1/s²`, channels assumed to have
    /// equal raw noise.
    #[default]
    Equal,
    /// Weights proportional to C/N0 (inverse thermal phase variance).
    ///
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

/// [`prepare_session`] on a log lent or given: a given log becomes the
/// screening's rows in place (each track's phase and C/N0 columns keep the
/// rows that pass the masks, its other columns are freed), before the
/// screening, so that the log and the screening's per-row arrays are never
/// held at once (the peak memory of an estimate) and its rows are not copied.
///
/// The stages: the grid and its usable span (`grid`), the rows passing
/// the masks (`rows`), the screening, the ranking (`rank`), the used rows
/// gathered by epoch, their offsets and the per-epoch average (`average`),
/// and every track's and signal's summary (`summaries`).
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
    let span = grid::checked_span(&grid, stamps, (imu, imu_name), file, imu_time_offset_s)?;
    let n_epochs = span.epochs() as usize;
    let span_s = (grid.time(stamps, span.k_first), grid.time(stamps, span.k_end - 1));

    let filter = RowFilter::new(span, selection);
    let candidates = rows::candidates(tracking, &grid, stamps, &filter, selection.screening.startup_s);
    let screened = if selection.screening.enabled {
        screening::screen(&candidates.rows, n_epochs, grid.log_interval_s, &selection.screening)
    } else {
        Screened::none(&candidates.rows)
    };
    let chosen = rank::select(&candidates, &screened, span_s, selection);
    if chosen.ranking.n_used == 0 {
        return Err(rank::no_channel_selected(file, &candidates.tracks, &chosen.reasons));
    }
    let channel_ranking = chosen.ranking.channel_ranking;
    let selected: Vec<usize> = (chosen.ranking.selected().iter())
        .map(|&i| candidates.candidate_of[i].expect("a ranked track is a candidate"))
        .collect();
    let gathered = average::gather(&candidates.rows, &screened, &selected, selection.weighting, n_epochs);
    let offsets_rad = average::slot_offsets(&gathered, selection.remove_channel_offsets);
    let mut averaged = average::average(&gathered, &offsets_rad, (&grid, stamps, span), imu, imu_time_offset_s);

    let removed = selection
        .remove_channel_offsets
        .then_some(RemovedOffsets { slot_base: &gathered.slot_base, offsets_rad: &offsets_rad });
    let channels = summaries::channel_summaries(&candidates, screened, chosen, removed, &averaged.t_s);
    let signals = summaries::signal_summaries(&channels);
    averaged.trim_to_phases().ok_or_else(|| SessionError::NoAveragedPhase { file: file.to_owned() })?;
    let Averaged { t_s, phase_err_rad, accel_mps2 } = averaged;
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

#[cfg(test)]
mod tests;
