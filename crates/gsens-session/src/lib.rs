//! Session preparation of gsens: what the estimator needs from a tracking log
//! and an IMU log (read with `gsens-io`): the epoch grid, the channel masks and
//! screening, the per-epoch averaged phase error (offset-free, on top of
//! [`gsens_core::average_phase_rad`]) and the specific force interpolated onto
//! the epochs ([`prepare_session`], [`PreparedSession`]).
//!
//! Problems are reported as a [`SessionError`]; reading errors of the logs
//! arrive as its [`SessionError::Format`] variant, unchanged.
//!
//! ```
//! use gsens_io::{read_imu, read_tracking};
//! use gsens_session::{prepare_session, SelectionConfig};
//!
//! let imu = "t_s,fx_mps2,fy_mps2,fz_mps2\n0,0,0,9.81\n0.025,0.1,0,9.81\n0.05,0.2,0,9.81\n";
//! let trk = "t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad\n\
//!            0,1,5,45,30,0.01\n0.025,1,5,45,30,0.02\n0.05,1,5,45,,0.03\n";
//! let imu = read_imu(imu.as_bytes(), "imu.csv")?;
//! let trk = read_tracking(trk.as_bytes(), "tracking.csv")?;
//! let s = prepare_session(&trk, &imu, "imu.csv", &SelectionConfig::default(), 0.0)?;
//! assert_eq!(s.t_s.len(), 3);
//! assert_eq!(s.accel_mps2[1], [0.1, 0.0, 9.81]);
//! assert_eq!(s.phase_err_rad[2], Some(0.03));
//! # Ok::<(), gsens_session::SessionError>(())
//! ```
//!
//! # Epoch grid
//!
//! The tracking time stamps define the epochs. The median spacing of the
//! distinct time stamps gives the log interval, with which each spacing is
//! rounded to a whole number of intervals: that numbers the epochs `k` (a
//! spacing rounding to zero is an error). A least-squares line through the
//! pairs (k, time stamp) then defines the uniform grid `t0 + k·T` (so that
//! jitter in the time stamps or a log interval slightly off its nominal value
//! does not accumulate over a long log); every time stamp must lie within 10%
//! of `T` of its grid time, or it is an error naming the file, line and column.
//! Grid points without any tracking row (gaps) are epochs too, with no phase,
//! so that the estimator's loop models run through the gaps. The epoch time
//! `t_s[k]` is the logged time stamp where the log has one (so an IMU logged at
//! the same instants is used exactly), the grid time `t0 + k·T` in the gaps.
//!
//! # Selection
//!
//! Rows outside the usable span (see below), below the elevation mask (rows of
//! unknown elevation pass) or below the C/N0 threshold are dropped; then the
//! `max_channels` tracks (a track: one channel, one PRN) with the highest mean
//! C/N0 over their remaining rows are used. When C/N0 does not rank them (the
//! candidates' mean C/N0 within [`CN0_RANKING_RESOLUTION_DB`] of each other:
//! a constant column, or rounding), the least noisy are used instead, by the
//! screening's robust σ of each track's deviation from the others
//! ([`ChannelRanking::Noise`]; [`PreparedSession::channel_ranking`] says which).
//!
//! Before the ranking, the rows that pass the masks are screened track by track
//! ([`SelectionConfig::screening`], on by default; see [Screening](#screening)):
//! cycle slips, losses of lock, C/N0 drops and rows beyond the discriminator's
//! linear range are excluded, a track split where it settled on a new level
//! after a slip, and the ranking uses the mean C/N0 over the rows kept.
//!
//! # Averaging
//!
//! At each epoch, the phase errors of the selected tracks present at that epoch
//! are averaged with weights renormalized over the present ones, so a missing
//! channel does not scale the average. Because the average over a changing set
//! of channels would still jump by the channels' constant offsets (a Costas
//! discriminator bias, multipath, ...) whenever a channel comes or goes,
//! [`SelectionConfig::remove_channel_offsets`] (on by default) first estimates
//! a constant offset per track by least squares on the additive model
//! `φ_i(k) = s(k) + c_i` (the common part `s` free at every epoch, the offsets
//! summing to zero over the tracks that share epochs) and averages `φ_i − c_i`.
//! When all selected tracks are present at every epoch, this changes nothing
//! with equal weights. The average itself is the core's,
//! [`gsens_core::average_phase_rad`] of the `φ_i − c_i` present at the epoch
//! (as the receiver-side calibrator averages its channels).
//!
//! Weights: [`Weighting::Equal`], as in the paper, or [`Weighting::Cn0`], the
//! inverse of the thermal phase variance of a Costas loop,
//! `σ_φ² = Bn/(C/N0)·(1 + 1/(2·T·C/N0))`, neglecting the squaring loss (the
//! second term, small above ~30 dB-Hz): `w ∝ C/N0 = 10^(cn0_dbhz/10)` (the ratio
//! in Hz), evaluated with each row's own C/N0.
//!
//! # Carriers
//!
//! Each track's carrier f_c comes from the tracking log (GPS L1 without carrier
//! columns, [`gsens_io::Carrier`]). The oscillator's fractional frequency error
//! y puts Δf_c = f_c·y on every carrier, so a loop on f_c logs (f_c/f_L1) times
//! the phase error the same loop logs on L1: every row's phase error is
//! multiplied by `s = f_L1/f_c` as it is read, and the screening, the offsets
//! and the average all work on L1's scale (Γ̂ is at L1). Its thermal noise is
//! scaled by s as well, so both weightings divide by s²: `w = 1/s²` (equal raw
//! noise) or `w = 10^(cn0_dbhz/10)/s²`, the inverse of the scaled variance. The
//! screening's linear-range test compares the discriminator's own output
//! (φ/s) with its limit. [`PreparedSession::signals`] counts the tracks per
//! signal, and each [`ChannelSummary`] names its signal and carrier.
//!
//! # IMU
//!
//! The specific force is interpolated onto the epochs by a cubic through the
//! IMU's samples ([`gsens_io::ImuSeries::interpolate_at`]: a linear interpolant would
//! attenuate the shaking by ≈ (ωh)²/12 between samples). The IMU sample
//! stamped `t_imu` was taken at true time `t_imu − imu_time_offset_s`, so the
//! epoch at time `t` reads the IMU at stamp `t + imu_time_offset_s`; when that
//! is one of the IMU's stamps the sample is used exactly. Epochs outside the
//! IMU's span are dropped from the ends: the usable span is the overlap of the
//! two logs (logs that do not overlap are an error that names both spans and
//! the likely cause, [`overlap_hint`]: a log in milliseconds, clocks on
//! different bases). The session then runs from the first to the last epoch
//! at which a used track has a kept row: the epochs outside hold no
//! measurement, and a leading stretch without one (every used track's
//! start-up screened out) would be a gap to the estimator.
//!
//! # Screening
//!
//! Per-track screening of the tracking rows before averaging: cycle slips,
//! losses of lock, C/N0 drops and rows outside the discriminator's linear range
//! are detected track by track and the affected stretches left out of the
//! average ([`ScreeningConfig`], on by default; the result per track in
//! [`TrackScreening`]).
//!
//! ## The deviation from the other channels
//!
//! The oscillator's part of the phase error (and so the g-induced part) is
//! common to all channels; what a slip, a loss of lock or a fade does to one
//! channel is not. At each epoch, every track's phase is compared with the
//! median of the other tracks present (all the tracks that pass the masks, not
//! only those averaged, each less its constant offset; rows in a C/N0 drop do
//! not enter the median):
//!
//! `d_i(k) = (φ_i(k) − c_i) − median_{j≠i}(φ_j(k) − c_j)`,
//!
//! where the common signal cancels. The offsets `c_i` are the median of each
//! track's departure from the mean of the tracks present (exact, up to a
//! common constant, while the set of tracks does not change), refined by the
//! median of its `d_i` (which a slip or a step does not move). An epoch with
//! fewer than two other tracks gives no deviation, and the cross-channel tests
//! (1–4 below) skip it. Each track's scale σ_i is the robust σ of its
//! deviation about its local level: 1.4826 × the median of `|d_i − the median
//! of d_i over its window|` in windows of [`ScreeningConfig::noisy_window_s`]
//! (at least [`ScreeningConfig::min_sigma_rad`]), which a step does not
//! inflate as it would the global MAD.
//!
//! It runs in two rounds: the first finds each track's slips and levels
//! (steps) against the others as they are; when it found any, the second
//! compares every track again with the others less their levels and without
//! their slips (so that one track's step or slip does not disturb the others'
//! reference), and its result is the one kept.
//!
//! ## The tests
//!
//! 1. **Slips and excursions.** A track's deviation is followed around a slowly
//!    adapting level ℓ (exponential mean of the in-bound rows, time constant
//!    [`ScreeningConfig::level_tau_s`], so slow per-channel trends such as the
//!    Doppler-rate steady-state error do not trigger). A row with
//!    `|d − ℓ| > k·σ_i` ([`ScreeningConfig::deviation_k`]) starts an event, which
//!    lasts until the deviation has stayed within bounds for
//!    [`ScreeningConfig::settle_s`]; an event with a single row beyond the
//!    bound is the discriminator's noise (an atan output's tail is far heavier
//!    than Gaussian at low C/N0, see [`ScreeningConfig::deviation_k`]) and is
//!    dropped. A Costas loop slipping by π, or a pilot
//!    loop by 2π, logs such a fast excursion: its discriminator wraps, the loop
//!    pulls in to the next stable point, and its filter state needs a loop time
//!    constant to recover. The event and [`ScreeningConfig::guard_s`] on each
//!    side are excluded. An event that settles, after at least
//!    [`ScreeningConfig::step_min_s`], on a new quiet level (a persistent step,
//!    as a log of unwrapped phase shows after a slip) is a *step*: the track is
//!    split there into two segments, each with its own constant offset in the
//!    averaging, and only the transition (plus the guard) is excluded.
//! 2. **Noisy stretches (loss of lock).** In windows of
//!    [`ScreeningConfig::noisy_window_s`], the RMS of `d − ℓ` over the rows not
//!    already excluded; a window above [`ScreeningConfig::noisy_rms_k`]·σ_i is
//!    excluded (with the guard).
//! 3. **Low gain (loss of lock at low C/N0).** A channel that has lost lock, or
//!    whose discriminator has lost gain at a low signal-to-noise ratio, logs a
//!    phase that follows the common signal only partly or not at all; its
//!    deviation can look like plain noise, yet averaging it scales the common
//!    signal down and biases Γ̂ towards zero. In windows of
//!    [`ScreeningConfig::gain_window_s`] each track's phase is regressed on the
//!    median of the others (slope and standard error, inflated for the
//!    residuals' lag-one correlation). The reference's own noise attenuates
//!    every track's slope alike, so the slopes are compared with their median
//!    over the tracks (at least three), and only in windows where that median
//!    is at least 0.8 (the common signal, shaking or oscillator noise,
//!    dominates the reference's noise). A window whose relative gain is below
//!    [`ScreeningConfig::min_gain`] by more than two standard errors is
//!    excluded; a track whose gain pooled over all its tested windows is below
//!    [`ScreeningConfig::min_track_gain`] by more than two standard errors is
//!    excluded entirely. Too large a gain is not tested.
//! 4. **Linear range.** Rows with `|φ|` above
//!    [`ScreeningConfig::max_abs_phase_rad`] (default π/4, half the atan
//!    Costas discriminator's unambiguous range; π/2 for atan2) by more than the track's
//!    noise explains (z·σ, z the normal quantile at a 1 % false-alarm
//!    probability over the track's rows) while the common level at that
//!    epoch (`φ − d`, the others' median plus the track's offset) is within
//!    half of it are excluded with the guard: the channel is on an excursion
//!    of its own (slipping, losing lock), beyond the range where the
//!    discriminator is linear and φ = L\[Δf\]. An excursion of the common
//!    level is the oscillator's own phase error: it is kept (excluding every
//!    channel at once, or each one as its noise crosses the limit, would
//!    fragment the log wherever a noisy oscillator wanders near the limit),
//!    and reported by the calibration's peak-phase check instead. A log of a
//!    single track has no common level: its rows beyond the limit are excluded.
//! 5. **C/N0 drops.** Rows whose C/N0 is more than
//!    [`ScreeningConfig::cn0_drop_db`] below the track's median are excluded
//!    with the guard.
//!
//! **Start-up.** A track begins with the loop pulling in from the
//! acquisition's frequency and phase error, and the receiver's C/N0 estimator
//! averages that pull-in into its first window: the start of a track looks
//! like a slip and a C/N0 drop. An event of test 1 or a drop of test 5 that
//! *begins* within [`ScreeningConfig::startup_s`] of the track's first row in
//! the log is its start-up: it and every row of the track before it are
//! excluded (reason `startup`, [`TrackScreening::rows_startup`]) but it is
//! neither a slip nor a drop, and no step. Later events are what they are.
//!
//! **What cannot be checked.** A track with never two other tracks at its
//! epochs cannot be compared (tests 1–3); the gain test needs a
//! [`ScreeningConfig::gain_window_s`] window with a quarter of it in rows,
//! and its whole-track form two such windows. A test that cannot run does not
//! exclude anything; the track's [`TrackScreening::not_checked`] (and its
//! one-line summary) says which and why, e.g. for a 10 s session.
//!
//! A track of which the cross-channel tests (1–3) flag more than
//! [`ScreeningConfig::max_excluded_fraction`] of the rows is excluded
//! entirely: what is left of it is not to be trusted. (Rows beyond the linear
//! range or in C/N0 drops do not count there: a noisy oscillator takes every
//! channel out of the range at once.) The tracks are ranked for the selection
//! by their mean C/N0 over the rows they keep, so an excluded track makes room
//! for the next one.
//!
//! The cost is linear in the number of rows: a few passes over them, and at
//! each epoch a rank sort of the dozen tracks present (once, twice when the
//! first round found slips); the medians that set offsets and scales run over
//! regular subsamples. About 70–90 ms for 12 tracks over an hour at 40 Hz
//! (1.7 M rows; BENCHMARKS.md gives the machine and the runs).
#![deny(missing_docs)]

mod error;
mod imu_screening;
mod screening;
mod session;

pub use error::{ScreeningConfigError, SessionError};
pub use imu_screening::{
    FLAT_RUN_FALSE_ALARM, FlatRun, FlatRunKind, FlatRuns, ImuSpikes, MIN_FLAT_RUN, SPIKE_SIGMAS, find_flat_runs,
    imu_spikes, mask_flat_runs, replace_imu_spikes,
};
pub use screening::{DEFAULT_CN0_DROP_DB, ExcludedSpan, MAX_SPANS, ScreeningConfig, TrackScreening};
pub use session::{
    CN0_RANKING_RESOLUTION_DB, ChannelRanking, ChannelSummary, DEFAULT_CHANNELS, GRID_TOLERANCE, MAX_EPOCHS,
    PreparedSession, SelectionConfig, SignalSummary, Weighting, overlap_hint, prepare_session, prepare_session_files,
    prepare_session_from, reinterpolate_imu,
};
