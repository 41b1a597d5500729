//! The loop-free estimate: Γ from the phase each loop was fed, with no model
//! of the loop.
//!
//! A receiver that logs where its loop put the replica (the NCO's
//! accumulated phase, `nco_phase_cycles`) makes the loop's input known
//! exactly: θ_in = θ_NCO + φ (docs/conventions.md, "Tracking log"). Since
//! φ = θ_signal − θ_replica and the replica runs at the commanded frequency
//! plus the oscillator's bias Δf = aᵀΓ,
//!
//! ```text
//! θ_in,i(t) = θ_signal,i(t) − 2π∫Δf dt,     common mode:  −2π∫aᵀΓ dt
//! ```
//!
//! per channel i, whatever the loop's order, bandwidth, gains or latency. The
//! regressor is the integrated specific force ρ = −2π∫a dt (the open-loop
//! limit of L(s) = −2π/(s + F(s))), averaged as the rows average the phase:
//! over the row's latest integration (`last`) or the n integrations since
//! the previous row (`mean`).
//!
//! Each satellite's carrier phase θ_signal,i is smooth (its Doppler changes
//! by under 1 Hz/s, its third derivative by ~10⁻⁸ Hz/s³ for a static
//! receiver) but huge. It is removed by one linear operation applied
//! identically to every channel and to the regressors, so that the model
//! stays exact: the log is cut into segments of equal length on one grid
//! ([`LoopFreeSettings::segment_s`], 30 s by default) and a cubic in time is
//! projected out of each channel's input phase and of each regressor column
//! over each segment. Over 30 s the cubic leaves ~10⁻⁴ rad of a satellite's
//! Doppler, and takes 0.2 % of the energy of a 1 Hz shaking signal (0.8 % at
//! 0.5 Hz): information lost, not a bias, as both sides lose it. A channel
//! enters a segment where it has a row at nearly every epoch of it, and the
//! segment keeps the epochs where every channel in it has one, so that the
//! channels averaged are the same throughout the segment and the average of
//! the projections is the projection of the average.
//!
//! A track's first [`LoopFreeSettings::warmup_s`] (the receiver's pull-in)
//! are left out, and so is a channel's segment where a row's |φ| exceeds
//! [`LoopFreeSettings::max_abs_phase_rad`]: near the discriminator's wrap
//! θ_in may be off by a half cycle, a step no detrending removes.
//!
//! A cycle slip leaves the NCO's phase a half cycle off for good: a channel
//! whose detrended θ_in, less the others' mean, steps by half a slip or more
//! between the means of a second of rows before and after any row is left
//! out of that segment (counted in [`LoopFreeEstimate::slipped_segments`]).
//!
//! The channel average (equal weights, each channel scaled to L1 by
//! f_L1/f_c) is then regressed on the projected regressors by generalized
//! least squares with an AR model of the residual noise (the oscillator's
//! own phase noise, which no loop shapes here, is strongly coloured), the
//! AR filter restarting at each segment ([`crate::gls::gls`]); the 1σ is the
//! larger of the fit's Cramér–Rao bound and its Newey–West covariance.

use crate::Measurement;
use crate::gls::{GlsFit, GlsSettings, gls};
use gsens_core::LoggedPhase;
use gsens_core::interpolate::lagrange;
use gsens_io::{ImuCubic, ImuSeries, TrackingLog};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::f64::consts::TAU;
use std::ops::Range;

/// Settings of [`estimate_loop_free`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LoopFreeSettings {
    /// The receiver's loop update interval T \[s\] (the integration time):
    /// where in an integration a row's stamp and NCO phase fall.
    pub loop_interval_s: f64,
    /// What a row holds when the loop runs faster than the log.
    pub logged_phase: LoggedPhase,
    /// The IMU time offset τ (IMU time stamp minus true time, docs/conventions.md,
    /// "Signs"): given, or searched within ±`max_abs_s` for the least squares
    /// fit (with no loop to confound it with, the only nuisance fitted).
    pub time_offset: crate::TimeOffset,
    /// Length of the segments over which each satellite's phase is
    /// detrended by a cubic \[s\] (a log shorter than this is one segment).
    pub segment_s: f64,
    /// Seconds at the start of each track left out: the receiver's pull-in,
    /// when its discriminator may still wrap.
    pub warmup_s: f64,
    /// A row whose |φ| exceeds this \[rad\] leaves its channel out of the
    /// segment: near the discriminator's wrap (±π/2 for atan Costas) θ_in
    /// may be off by a half cycle (default π/4, half that range).
    pub max_abs_phase_rad: f64,
    /// Average the N tracks with the highest mean C/N0 (0: all): a weak
    /// channel's 1 ms Costas outputs wrap now and then, and each wrap biases
    /// its row by π/n towards zero phase error, against the g-signal.
    pub channels: usize,
}

impl LoopFreeSettings {
    /// The default segment length \[s\]: many shaking periods (1–2 s), and
    /// short enough that a cubic follows a satellite's Doppler to ~10⁻⁴ rad.
    pub const DEFAULT_SEGMENT_S: f64 = 30.0;

    /// Settings for a loop updated every `loop_interval_s` with rows holding
    /// `logged_phase`, an IMU time offset of 0, the default segments, the
    /// calibration's default warm-up (2 s), a limit of π/4 on |φ| and its
    /// default channels (the 4 of highest mean C/N0).
    pub fn new(loop_interval_s: f64, logged_phase: LoggedPhase) -> Self {
        LoopFreeSettings {
            loop_interval_s,
            logged_phase,
            time_offset: crate::TimeOffset::Fixed { imu_time_offset_s: 0.0 },
            segment_s: Self::DEFAULT_SEGMENT_S,
            warmup_s: crate::defaults::DEFAULT_WARMUP_S,
            max_abs_phase_rad: core::f64::consts::FRAC_PI_4,
            channels: crate::defaults::DEFAULT_CHANNELS,
        }
    }
}

/// The loop-free estimate of Γ.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[non_exhaustive]
pub struct LoopFreeEstimate {
    /// Γ̂ \[Hz/(m/s²)\] at L1.
    pub gamma_hz_per_mps2: [f64; 3],
    /// Its covariance \[(Hz/(m/s²))²\]: the larger of the Cramér–Rao bound at
    /// the fitted noise model and the Newey–West covariance, per diagonal.
    pub covariance: [[f64; 3]; 3],
    /// The Cramér–Rao bound at the fitted noise model \[Hz/(m/s²)\].
    pub crlb_hz_per_mps2: [f64; 3],
    /// Epochs in the fit.
    pub epochs: usize,
    /// Channels (tracks) that entered at least one segment.
    pub tracks: usize,
    /// Segments that entered the fit.
    pub segments: usize,
    /// The IMU time offset used \[s\]: the given one, or the search's.
    pub imu_time_offset_s: f64,
    /// Whether the offset was searched.
    pub time_offset_searched: bool,
    /// A channel's segments left out because its input phase stepped by
    /// half a slip or more (a cycle slip: the NCO's phase is off by a half
    /// cycle from then on).
    pub slipped_segments: usize,
    /// The residual variance of the prewhitened fit \[rad²\]: the variance of
    /// what the noise model cannot predict, where a row booked at the wrong
    /// instant shows (the unwhitened residual is dominated by the
    /// oscillator's strongly coloured phase noise).
    pub residual_variance_rad2: f64,
    /// The rows' bookkeeping used: the loop's update interval \[s\] and what
    /// a row holds, given or chosen ([`estimate_loop_free_choosing`]).
    pub loop_interval_s: f64,
    /// What a row holds (see `loop_interval_s`).
    pub logged_phase: LoggedPhase,
    /// Whether the bookkeeping was chosen by the data.
    pub bookkeeping_chosen: bool,
    /// RMS of each detrended regressor column \[rad per Hz/(m/s²)\]: the
    /// phase a unit of Γ along the axis put into the fit, the loop-free
    /// counterpart of the estimate's excitation RMS (the same threshold
    /// decides whether the axis is observable).
    pub excitation_rms: [f64; 3],
    /// Order of the AR model of the residual noise the fit whitened with
    /// (one model, restarted at each segment).
    pub noise_ar_order: usize,
}

impl LoopFreeEstimate {
    /// 1σ of each component \[Hz/(m/s²)\].
    pub fn sigma_hz_per_mps2(&self) -> [f64; 3] {
        [0, 1, 2].map(|i| self.covariance[i][i].max(0.0).sqrt())
    }
}

/// Why a loop-free estimate could not be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum LoopFreeError {
    /// No track of the log has the NCO phase.
    #[error("{source_name}: no track has the NCO phase (column nco_phase_cycles), which the loop-free estimate needs")]
    NoNcoPhase {
        /// The tracking log's name.
        source_name: String,
    },
    /// No track of the log has the NCO frequency.
    #[error("{source_name}: no track has the NCO frequency (column nco_freq_hz), which the estimate from it needs")]
    NoNcoFrequency {
        /// The tracking log's name.
        source_name: String,
    },
    /// The loop model the NCO frequency is seen through cannot run.
    #[error("the loop model cannot run: {why}")]
    Loop {
        /// Why.
        why: String,
    },
    /// The loop interval is not a whole fraction of the log interval.
    #[error(
        "the log interval ({log_interval_s} s) is not a whole number of loop intervals ({loop_interval_s} s) within 1e-6"
    )]
    Intervals {
        /// The log interval \[s\].
        log_interval_s: f64,
        /// The loop interval \[s\].
        loop_interval_s: f64,
    },
    /// A setting out of its range.
    #[error("setting {name} = {value} is out of range: expected {expected}")]
    Setting {
        /// The setting's name.
        name: &'static str,
        /// Its value.
        value: f64,
        /// The range.
        expected: &'static str,
    },
    /// Too little data survived: no channel covers a whole segment inside
    /// the IMU's span, or the fit had too few epochs.
    #[error(
        "too few epochs for the loop-free estimate: {epochs} (channels must cover whole segments of {segment_s} s)"
    )]
    TooFewEpochs {
        /// Epochs that entered.
        epochs: usize,
        /// The segment length \[s\].
        segment_s: f64,
    },
}

/// Estimates Γ from the loop's input phase (see the module documentation).
pub fn estimate_loop_free(
    tracking: &TrackingLog,
    imu: &ImuSeries,
    settings: &LoopFreeSettings,
) -> Result<LoopFreeEstimate, LoopFreeError> {
    estimate_with(tracking, imu, settings, true)
}

/// [`estimate_loop_free`], a `last` row's half-integration step taken with
/// the logged command (`logged_frequency`, where the log has it) or with the
/// NCO phase's mean rate between rows.
fn estimate_with(
    tracking: &TrackingLog,
    imu: &ImuSeries,
    settings: &LoopFreeSettings,
    logged_frequency: bool,
) -> Result<LoopFreeEstimate, LoopFreeError> {
    check_settings(settings)?;
    let epochs = tracking.epoch_t_s();
    let log_interval_s = median_step(epochs);
    let substeps = substeps(log_interval_s, settings.loop_interval_s)?;
    let tracks: Vec<_> = tracking.tracks().iter().filter(|t| !t.nco_phase_cycles.is_empty()).collect();
    if tracks.is_empty() {
        return Err(LoopFreeError::NoNcoPhase { source_name: tracking.source_name().to_owned() });
    }
    let phases = InputPhases::of_tracks(epochs, &tracks, |tr| {
        input_phase_on_epochs(tr, epochs, log_interval_s, substeps, settings, logged_frequency)
    });
    let n_window = if settings.logged_phase == LoggedPhase::Mean { substeps } else { 1 };
    fit(&phases, imu, settings, n_window)
}

/// [`estimate_loop_free`] for a log whose bookkeeping is not known: every
/// update interval of `loop_intervals_s` that divides the log interval (and
/// the log interval itself when it is no longer than the longest of them),
/// each with `last` and `mean` rows, estimated in parallel; the least
/// residual variance of the prewhitened fit wins, and the winner is
/// estimated again as [`estimate_loop_free`] would. A row booked at the
/// wrong instant leaves the loop's own response to the shaking and to the
/// noise in θ_NCO + φ (the combination cancels it only where both are taken
/// at the same instant), which the whitened residual shows; bookkeepings
/// that differ by less than that give the same Γ̂ within its σ.
///
/// The candidates are compared with each `last` row's half-integration step
/// taken at the NCO phase's mean rate between rows, not at the logged
/// command: the command carries the loop's proportional response to the
/// row's own φ (c0·φ/2π), so a step of T/2 at the command cancels part of
/// φ's thermal noise, the more the longer T is, and the residual would
/// reward a wrong T (on a PocketSDR log of 1 ms updates, T = 0.1 s with
/// Γ̂ 25 % low).
pub fn estimate_loop_free_choosing(
    tracking: &TrackingLog,
    imu: &ImuSeries,
    settings: &LoopFreeSettings,
    loop_intervals_s: &[f64],
) -> Result<LoopFreeEstimate, LoopFreeError> {
    let log_interval_s = median_step(tracking.epoch_t_s());
    let longest_s = loop_intervals_s.iter().copied().fold(0.0, f64::max);
    let log_rate = (log_interval_s <= longest_s * (1.0 + 1e-9)).then_some(log_interval_s);
    let mut candidates: Vec<LoopFreeSettings> = Vec::new();
    for &t in loop_intervals_s.iter().chain(&log_rate) {
        let Ok(n) = substeps(log_interval_s, t) else { continue };
        let phases: &[LoggedPhase] = if n > 1 { &[LoggedPhase::Last, LoggedPhase::Mean] } else { &[LoggedPhase::Last] };
        for &logged_phase in phases {
            if !candidates.iter().any(|c| c.logged_phase == logged_phase && (c.loop_interval_s - t).abs() < 1e-9) {
                candidates.push(LoopFreeSettings { loop_interval_s: t, logged_phase, ..*settings });
            }
        }
    }
    let residuals: Vec<Result<f64, LoopFreeError>> = candidates
        .par_iter()
        .map(|c| estimate_with(tracking, imu, c, false).map(|e| e.residual_variance_rad2))
        .collect();
    let best = (0..candidates.len())
        .filter_map(|k| residuals[k].as_ref().ok().map(|&r| (k, r)))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(k, _)| k);
    match best {
        Some(k) => estimate_loop_free(tracking, imu, &candidates[k]).map(|mut chosen| {
            chosen.bookkeeping_chosen = true;
            chosen
        }),
        None => Err(residuals
            .into_iter()
            .find_map(Result::err)
            .unwrap_or(LoopFreeError::Intervals { log_interval_s, loop_interval_s: settings.loop_interval_s })),
    }
}

/// Each track's input phase θ_in on common epochs: what a receiver's adapter
/// hands [`estimate_loop_free_from`] when its bookkeeping of the NCO is its
/// own (GNSS-SDR's records, each at its own instant, brought to a grid).
#[derive(Debug, Clone, PartialEq)]
pub struct InputPhases {
    /// The epochs \[s\], strictly increasing on a uniform grid (missing
    /// grid points allowed).
    pub epoch_t_s: Vec<f64>,
    /// Every track.
    pub tracks: Vec<TrackInputPhase>,
}

impl InputPhases {
    /// Each of `tracks` with its values on `epochs` (`values`), its
    /// carrier's scale to L1 and its mean C/N0.
    pub(crate) fn of_tracks(
        epochs: &[f64],
        tracks: &[&gsens_io::ChannelTrack],
        values: impl Fn(&gsens_io::ChannelTrack) -> Vec<Option<f64>>,
    ) -> Self {
        InputPhases {
            epoch_t_s: epochs.to_vec(),
            tracks: tracks
                .iter()
                .map(|tr| TrackInputPhase {
                    input_phase_rad: values(tr),
                    scale_to_l1: tr.carrier.scale_to_l1(),
                    mean_cn0_dbhz: tr.mean_cn0_dbhz(),
                })
                .collect(),
        }
    }
}

/// The (row, epoch) index pairs of a track's rows, stamped `t_s`, that fall
/// on an epoch of `epochs` (rows of an epoch share its stamp exactly), in
/// order; both ascending.
pub(crate) fn rows_on_epochs<'a>(t_s: &'a [f64], epochs: &'a [f64]) -> impl Iterator<Item = (usize, usize)> + 'a {
    let mut e = 0usize;
    (0..t_s.len()).filter_map(move |k| {
        while e < epochs.len() && epochs[e] < t_s[k] {
            e += 1;
        }
        (e < epochs.len() && epochs[e] == t_s[k]).then_some((k, e))
    })
}

/// One track's input phase on [`InputPhases::epoch_t_s`].
#[derive(Debug, Clone, PartialEq)]
pub struct TrackInputPhase {
    /// θ_in = θ_NCO + φ at each epoch's instant \[rad\] (its own carrier's;
    /// `None` where the track has none or it is not to be used: pull-in,
    /// |φ| near the discriminator's wrap).
    pub input_phase_rad: Vec<Option<f64>>,
    /// f_L1/f_c of its carrier.
    pub scale_to_l1: f64,
    /// Its mean C/N0 \[dB-Hz\], for the choice of channels.
    pub mean_cn0_dbhz: f64,
}

/// [`estimate_loop_free`] from input phases a receiver's adapter made: each
/// a point value at its epoch's instant (the regressor is read there), the
/// settings' loop interval and logged phase unused.
pub fn estimate_loop_free_from(
    phases: &InputPhases,
    imu: &ImuSeries,
    settings: &LoopFreeSettings,
) -> Result<LoopFreeEstimate, LoopFreeError> {
    check_settings(settings)?;
    fit(phases, imu, settings, 1)
}

/// The estimate from input phases whose regressor is the mean over the
/// `n_window` integrations ending at each epoch ([`Regressor`]).
fn fit(
    phases: &InputPhases,
    imu: &ImuSeries,
    settings: &LoopFreeSettings,
    n_window: usize,
) -> Result<LoopFreeEstimate, LoopFreeError> {
    let regressor = Regressor::new(imu, &phases.epoch_t_s, n_window, settings.loop_interval_s);
    // A step of half the smallest slip flags one: the smallest is a half cycle of the discriminator,
    // 4·max|φ| (π for atan Costas at max|φ| = π/4).
    let mut estimate = fit_rows(phases, &regressor, settings, 2.0 * settings.max_abs_phase_rad)?;
    estimate.logged_phase = if n_window > 1 { LoggedPhase::Mean } else { LoggedPhase::Last };
    Ok(estimate)
}

/// The regressor of the rows an estimate from the NCO's record fits, read on
/// the epochs at an IMU time offset τ \[s\].
pub(crate) trait RowRegressor: Sync {
    /// Whether the IMU covers what epoch `k`'s value reads at offset `tau`.
    fn covers(&self, k: usize, tau: f64) -> bool;
    /// The values at the epochs `at` (ascending, each covered).
    fn values(&self, at: &[usize], tau: f64) -> Vec<[f64; 3]>;
}

/// The estimate from per-track values on common epochs (`phases`: the input
/// phase \[rad\], or any other row quantity the regressor models, in its unit),
/// regressed on `regressor`: channels chosen, segments detrended, tracks that
/// step by `slip_step` or more in a segment left out of it (infinite: no
/// slip test), the IMU offset searched where asked, then GLS under the AR
/// noise model.
pub(crate) fn fit_rows(
    phases: &InputPhases,
    regressor: &impl RowRegressor,
    settings: &LoopFreeSettings,
    slip_step: f64,
) -> Result<LoopFreeEstimate, LoopFreeError> {
    fit_rows_kept(phases, regressor, settings, slip_step).map(|fitted| fitted.estimate)
}

/// What [`fit_rows`] fitted, kept for a fit of more parameters on the same rows.
struct RowsFit {
    estimate: LoopFreeEstimate,
    rows: CommonPhase,
    regressors: Vec<[f64; 3]>,
    gls: GlsFit,
}

fn fit_rows_kept(
    phases: &InputPhases,
    regressor: &impl RowRegressor,
    settings: &LoopFreeSettings,
    slip_step: f64,
) -> Result<RowsFit, LoopFreeError> {
    let log_interval_s = median_step(&phases.epoch_t_s);
    let (m, offsets, searched) = assemble_rows(phases, regressor, settings, slip_step)?;
    let too_few = || LoopFreeError::TooFewEpochs { epochs: m.phase.len(), segment_s: settings.segment_s };
    let tau = if searched { m.search_offset(regressor, offsets, log_interval_s) } else { offsets[0] };
    let x = m.regressors(regressor, tau);
    let excitation_rms = [0, 1, 2].map(|i| (x.iter().map(|r| r[i] * r[i]).sum::<f64>() / x.len() as f64).sqrt());
    let ranges = m.ranges();
    let lag = (2.5 / log_interval_s).ceil() as usize;
    let fit = gls(&m.phase, &x, &ranges, &GlsSettings { hac_max_lag: Some(lag), ..GlsSettings::default() })
        .ok_or_else(too_few)?;
    let crlb = fit.estimate.covariance;
    let covariance = match fit.robust_covariance {
        Some(robust) if (0..3).map(|i| robust[i][i]).sum::<f64>() > (0..3).map(|i| crlb[i][i]).sum::<f64>() => robust,
        _ => crlb,
    };
    let estimate = LoopFreeEstimate {
        gamma_hz_per_mps2: fit.estimate.gamma_hz_per_mps2,
        covariance,
        crlb_hz_per_mps2: fit.crlb_hz_per_mps2(),
        epochs: m.phase.len(),
        tracks: m.tracks_used.iter().filter(|&&u| u).count(),
        segments: ranges.len(),
        imu_time_offset_s: tau,
        time_offset_searched: searched,
        slipped_segments: m.slipped,
        residual_variance_rad2: fit.estimate.residual_variance_rad2,
        loop_interval_s: settings.loop_interval_s,
        logged_phase: LoggedPhase::Last,
        bookkeeping_chosen: false,
        excitation_rms,
        noise_ar_order: fit.noise.coeffs.len(),
    };
    Ok(RowsFit { estimate, rows: m, regressors: x, gls: fit })
}

/// The rows [`fit_rows`] fits: the channels chosen, the epochs the
/// regressor covers at every offset tried, detrended and averaged
/// ([`CommonPhase::assemble`]); with the offsets' range and whether it is searched.
fn assemble_rows(
    phases: &InputPhases,
    regressor: &impl RowRegressor,
    settings: &LoopFreeSettings,
    slip_step: f64,
) -> Result<(CommonPhase, [f64; 2], bool), LoopFreeError> {
    let epochs = phases.epoch_t_s.as_slice();
    let log_interval_s = median_step(epochs);
    let mut tracks: Vec<&TrackInputPhase> = phases.tracks.iter().collect();
    if settings.channels > 0 {
        tracks.sort_by(|a, b| b.mean_cn0_dbhz.total_cmp(&a.mean_cn0_dbhz));
        tracks.truncate(settings.channels);
    }
    let (offsets, searched) = match settings.time_offset {
        crate::TimeOffset::Fixed { imu_time_offset_s } => ([imu_time_offset_s; 2], false),
        crate::TimeOffset::Auto { max_abs_s } => ([-max_abs_s, max_abs_s], true),
    };
    // An epoch is usable when the IMU covers every instant its regressor reads at every offset tried.
    let usable: Vec<bool> = (0..epochs.len())
        .map(|k| epochs[k] >= epochs[0] + settings.warmup_s && offsets.iter().all(|&tau| regressor.covers(k, tau)))
        .collect();
    let inputs: Vec<(&[Option<f64>], f64)> =
        tracks.iter().map(|t| (t.input_phase_rad.as_slice(), t.scale_to_l1)).collect();
    // The slip test compares means of a second of rows (at least 3).
    let slip_window = ((1.0 / log_interval_s).round() as usize).max(3);
    let m = CommonPhase::assemble(epochs, &usable, &inputs, settings.segment_s, slip_step, slip_window);
    if m.phase.len() < 10 {
        return Err(LoopFreeError::TooFewEpochs { epochs: m.phase.len(), segment_s: settings.segment_s });
    }
    Ok((m, offsets, searched))
}

/// The AR noise model [`fit_rows`] fits to the rows' residuals under `regressor`.
pub(crate) fn rows_noise(
    phases: &InputPhases,
    regressor: &impl RowRegressor,
    settings: &LoopFreeSettings,
) -> Result<crate::gls::ArModel, LoopFreeError> {
    fit_rows_kept(phases, regressor, settings, f64::INFINITY).map(|fitted| fitted.gls.noise)
}

/// The innovation variance of the rows fitted on `regressor` at the IMU
/// offset `tau`, prewhitened by a given `noise` model: with one noise model
/// for every regressor compared, N·ln of it is −2 ln L up to a constant
/// (each fit's own AR model would move it by its order's choice).
pub(crate) fn rows_score(
    phases: &InputPhases,
    regressor: &impl RowRegressor,
    settings: &LoopFreeSettings,
    tau: f64,
    noise: &crate::gls::ArModel,
) -> Result<f64, LoopFreeError> {
    let (rows, _, _) = assemble_rows(phases, regressor, settings, f64::INFINITY)?;
    let x = rows.regressors(regressor, tau);
    let mut ne = gsens_core::NormalEquations::default();
    for r in rows.ranges() {
        let z: Vec<[f64; 4]> = r.map(|k| [rows.phase[k], x[k][0], x[k][1], x[k][2]]).collect();
        noise.whiten_lanes(&z, false, &mut |e: [f64; 4]| ne.add(e[0], &[e[1], e[2], e[3]]));
    }
    Ok(ne.solve().residual_variance_rad2)
}

/// The common mode of frequency rows \[Hz\] integrated to carrier phase
/// \[rad\], 2π·Σ f·Δt over each segment with its linear trend removed, on
/// the rows [`fit_rows`] fits at the IMU offset `tau`: per row its epoch's
/// index and the phase before compensation, after it (the rows less
/// x·`gamma`) and of the g-induced part x·`gamma` alone. What compensating
/// with Γ̂ removes from the receiver's carrier phase.
pub(crate) fn integrated_phase_rad(
    phases: &InputPhases,
    regressor: &impl RowRegressor,
    settings: &LoopFreeSettings,
    tau: f64,
    gamma: &[f64; 3],
) -> Result<Vec<(usize, [f64; 3])>, LoopFreeError> {
    let (rows, _, _) = assemble_rows(phases, regressor, settings, f64::INFINITY)?;
    let x = rows.regressors(regressor, tau);
    let step_rad = TAU * median_step(&phases.epoch_t_s);
    let mut out = Vec::with_capacity(x.len());
    for (r, (at, _)) in rows.ranges().into_iter().zip(&rows.segments) {
        let mut acc = [0.0; 3];
        let integrated: Vec<[f64; 3]> = r
            .map(|k| {
                let g = x[k][0] * gamma[0] + x[k][1] * gamma[1] + x[k][2] * gamma[2];
                let f = [rows.phase[k], rows.phase[k] - g, g];
                for i in 0..3 {
                    acc[i] += step_rad * f[i];
                }
                acc
            })
            .collect();
        let detrended: [Vec<f64>; 3] =
            [0, 1, 2].map(|i| detrended(&integrated.iter().map(|v| v[i]).collect::<Vec<_>>()));
        out.extend(at.iter().enumerate().map(|(j, &k)| (k, [detrended[0][j], detrended[1][j], detrended[2][j]])));
    }
    Ok(out)
}

/// y less its least-squares line a + b·k (a segment under 3 values: zeros,
/// as no trend can be told from its values).
fn detrended(y: &[f64]) -> Vec<f64> {
    let n = y.len() as f64;
    if y.len() < 3 {
        return vec![0.0; y.len()];
    }
    let k_mean = (n - 1.0) / 2.0;
    let y_mean = y.iter().sum::<f64>() / n;
    let (mut sky, mut skk) = (0.0, 0.0);
    for (k, v) in y.iter().enumerate() {
        let dk = k as f64 - k_mean;
        sky += dk * (v - y_mean);
        skk += dk * dk;
    }
    let b = sky / skk;
    y.iter().enumerate().map(|(k, v)| v - y_mean - b * (k as f64 - k_mean)).collect()
}

/// A fit of Γ with the regressor's loop scaled by s = e^θ as one more
/// parameter (and the IMU offset τ where it is searched).
pub(crate) struct ScaledFit {
    /// The fit at θ, its covariance that of Γ̂ with θ (and τ) unknown.
    pub estimate: LoopFreeEstimate,
    /// The Gauss–Newton step of θ from the fit at θ.
    pub step_ln_scale: f64,
    /// The variance of θ̂.
    pub var_ln_scale: f64,
}

/// Γ and the loop's scale θ = ln s fitted together: `at(θ)` is the
/// regressor of the loop scaled by e^θ (or why that loop cannot run). The
/// rows are fitted at θ as by [`fit_rows`] (offset τ̂ searched where asked);
/// then, under the same AR noise model, the model is linearized in the
/// nuisance parameters ν = (θ, and τ where searched),
///
/// ```text
/// y = X·Γ + D·δν + n,   D = [(X(θ + h) − X(θ − h))·Γ̂/2h, (X(τ̂ + ε) − X(τ̂ − ε))·Γ̂/2ε],
/// ```
///
/// and the prewhitened least squares of y on Z = [X, D] gives the
/// Gauss–Newton step δθ and the joint covariance σ²(Z_wᵀZ_w)⁻¹. Its Γ block,
/// the conditional bound σ²A⁻¹ (A = X_wᵀX_w) plus what the nuisance leaves
/// unknown (the Schur complement), is what θ and τ add to Γ̂'s variance:
/// that difference is added to the fit's own covariance (which may be the
/// larger Newey–West one). Where a shaking at one rate cannot tell a loop's
/// phase lag from a delay, τ's column is what keeps var(θ̂) honest.
pub(crate) fn fit_rows_scaled<R: RowRegressor>(
    phases: &InputPhases,
    at: impl Fn(f64) -> Result<R, LoopFreeError>,
    ln_scale: f64,
    h: f64,
    settings: &LoopFreeSettings,
) -> Result<ScaledFit, LoopFreeError> {
    let Linearized { mut estimate, zz, zy, sigma2 } = linearized(phases, at, ln_scale, h, settings)?;
    let a = zz.view((0, 0), (3, 3)).into_owned();
    let (Some(a_inv), Some(joint)) = (a.try_inverse(), zz.clone().try_inverse()) else {
        return Err(LoopFreeError::TooFewEpochs { epochs: estimate.epochs, segment_s: settings.segment_s });
    };
    for i in 0..3 {
        for j in 0..3 {
            estimate.covariance[i][j] += sigma2 * (joint[(i, j)] - a_inv[(i, j)]);
        }
    }
    estimate.crlb_hz_per_mps2 = [0, 1, 2].map(|i| (sigma2 * joint[(i, i)]).sqrt());
    let var_ln_scale = if joint[(3, 3)] > 0.0 { sigma2 * joint[(3, 3)] } else { f64::INFINITY };
    let step_ln_scale = (&joint * &zy)[3];
    Ok(ScaledFit { estimate, step_ln_scale, var_ln_scale })
}

/// The fit [`fit_rows`] makes under the loop `at(0)`, known only to within a
/// variance `var_ln_scale` of its scale θ = ln s (`at(θ)`: the regressor of
/// the loop scaled by e^θ), with Γ̂ kept and its covariance widened by what
/// the loop's error θ ~ N(0, var) moves it: linearized as in
/// [`fit_rows_scaled`], Γ̂ (with τ̂ where searched, fitted along) moves by
/// J·θ, J = (M⁻¹·Z_νᵀ·d_θ)\[Γ\] with Z_ν = \[X, d_τ\] prewhitened and
/// M = Z_νᵀZ_ν, so
///
/// ```text
/// Cov(Γ̂) = C + σ²·(M⁻¹ − A⁻¹)[Γ] + J·Jᵀ·var
/// ```
///
/// with C the fit's own covariance (the larger of the bound σ²A⁻¹ and the
/// Newey–West one) and σ²(M⁻¹ − A⁻¹) what the searched offset adds. The
/// loop's error comes from elsewhere (a statement, or another fit), so it is
/// propagated, not combined with what these rows say of the loop.
pub(crate) fn fit_rows_loop_uncertain<R: RowRegressor>(
    phases: &InputPhases,
    at: impl Fn(f64) -> Result<R, LoopFreeError>,
    h: f64,
    var_ln_scale: f64,
    settings: &LoopFreeSettings,
) -> Result<LoopFreeEstimate, LoopFreeError> {
    let Linearized { mut estimate, zz, sigma2, .. } = linearized(phases, at, 0.0, h, settings)?;
    // Z = [X, d_θ, d_τ]: the fit's own parameters ν are every column but d_θ's.
    let own: Vec<usize> = (0..zz.nrows()).filter(|&c| c != 3).collect();
    let m = zz.select_rows(&own).select_columns(&own);
    let z_theta = zz.column(3).select_rows(&own);
    let a = zz.view((0, 0), (3, 3)).into_owned();
    let (Some(a_inv), Some(m_inv)) = (a.try_inverse(), m.try_inverse()) else {
        return Err(LoopFreeError::TooFewEpochs { epochs: estimate.epochs, segment_s: settings.segment_s });
    };
    let moved = &m_inv * z_theta;
    for i in 0..3 {
        for j in 0..3 {
            estimate.covariance[i][j] += sigma2 * (m_inv[(i, j)] - a_inv[(i, j)]) + moved[i] * moved[j] * var_ln_scale;
        }
    }
    Ok(estimate)
}

/// The fit of [`fit_rows`] at θ with the prewhitened cross products of
/// Z = \[X, d_θ, d_τ\] (d_τ only where τ is searched) and y: see
/// [`fit_rows_scaled`].
struct Linearized {
    estimate: LoopFreeEstimate,
    zz: nalgebra::DMatrix<f64>,
    zy: nalgebra::DVector<f64>,
    /// The AR model's innovation variance σ².
    sigma2: f64,
}

fn linearized<R: RowRegressor>(
    phases: &InputPhases,
    at: impl Fn(f64) -> Result<R, LoopFreeError>,
    ln_scale: f64,
    h: f64,
    settings: &LoopFreeSettings,
) -> Result<Linearized, LoopFreeError> {
    let RowsFit { estimate, rows, regressors: x, gls: fit } =
        fit_rows_kept(phases, &at(ln_scale)?, settings, f64::INFINITY)?;
    let tau = estimate.imu_time_offset_s;
    let g = estimate.gamma_hz_per_mps2;
    let derivative = |up: Vec<[f64; 3]>, down: Vec<[f64; 3]>, step: f64| -> Vec<f64> {
        up.iter().zip(&down).map(|(u, w)| (0..3).map(|i| (u[i] - w[i]) * g[i]).sum::<f64>() / (2.0 * step)).collect()
    };
    let scaled = at(ln_scale + h)?;
    let d_scale = derivative(rows.regressors(&scaled, tau), rows.regressors(&at(ln_scale - h)?, tau), h);
    let model = at(ln_scale)?;
    let eps = 0.05 * median_step(&phases.epoch_t_s);
    let d_tau = if estimate.time_offset_searched {
        derivative(rows.regressors(&model, tau + eps), rows.regressors(&model, tau - eps), eps)
    } else {
        vec![0.0; x.len()]
    };
    let m = if estimate.time_offset_searched { 5 } else { 4 };
    // Cross products of the prewhitened [y, X, D] over the segments.
    let mut zz = nalgebra::DMatrix::<f64>::zeros(m, m);
    let mut zy = nalgebra::DVector::<f64>::zeros(m);
    for r in rows.ranges() {
        let z: Vec<[f64; 6]> = r.map(|k| [rows.phase[k], x[k][0], x[k][1], x[k][2], d_scale[k], d_tau[k]]).collect();
        fit.noise.whiten_lanes(&z, false, &mut |e: [f64; 6]| {
            let v = nalgebra::DVector::from_column_slice(&e[1..1 + m]);
            zz += &v * v.transpose();
            zy += v * e[0];
        });
    }
    Ok(Linearized { estimate, zz, zy, sigma2: fit.noise.innovation_variance })
}

/// The regressor ρ = −2π∫a dt averaged over the integrations a row holds,
/// on the IMU's clock offset by τ: the latest one, centred on the epoch
/// (`last`), or the n contiguous ones ending with it (`mean`).
///
/// A correlator's discriminator gives the mean of the phase error over its
/// integration, and the NCO's commanded phase is linear within one, so the
/// row's input phase holds the oscillator's phase −2π∫Δf averaged over the
/// window W, not read at its centre: for a sinusoid that is the centre value
/// times sinc(ωW/2), 1 − (ωT)²/24 for one integration of T (0.05 % at 0.9 Hz
/// with 20 ms). The mean is taken by 3-point Gauss–Legendre on panels no
/// longer than half the IMU's median interval: ρ is a quartic between IMU
/// samples, where the rule is exact.
struct Regressor<'a> {
    integral: ForceIntegral<'a>,
    epochs: &'a [f64],
    n_window: usize,
    loop_interval_s: f64,
    /// Panels of the window's Gauss–Legendre rule.
    panels: usize,
}

impl<'a> Regressor<'a> {
    fn new(imu: &'a ImuSeries, epochs: &'a [f64], n_window: usize, loop_interval_s: f64) -> Self {
        let imu_step_s = median_step(&imu.t_s);
        let window_s = n_window as f64 * loop_interval_s;
        let panels = if imu_step_s > 0.0 { (2.0 * window_s / imu_step_s).ceil().max(1.0) as usize } else { 1 };
        Regressor { integral: ForceIntegral::new(imu), epochs, n_window, loop_interval_s, panels }
    }

    /// The window epoch `k`'s row averages over, at offset `tau` \[s\].
    fn window(&self, k: usize, tau: f64) -> (f64, f64) {
        let end = self.epochs[k] + tau + self.loop_interval_s / 2.0;
        (end - self.n_window as f64 * self.loop_interval_s, end)
    }

    fn at(&self, k: usize, tau: f64) -> [f64; 3] {
        // Gauss–Legendre's 3 nodes on [−1, 1] and their weights (which sum to 2).
        const NODES: [f64; 3] = [-0.774_596_669_241_483_4, 0.0, 0.774_596_669_241_483_4];
        const WEIGHTS: [f64; 3] = [5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0];
        let (start, end) = self.window(k, tau);
        let half = (end - start) / (2.0 * self.panels as f64);
        let mut sum = [0.0; 3];
        for p in 0..self.panels {
            let mid = start + (2 * p + 1) as f64 * half;
            for (x, w) in NODES.iter().zip(WEIGHTS) {
                let v = self.integral.at(mid + x * half);
                (0..3).for_each(|i| sum[i] += w * v[i]);
            }
        }
        sum.map(|v| -TAU * v / (2.0 * self.panels as f64))
    }
}

impl RowRegressor for Regressor<'_> {
    fn covers(&self, k: usize, tau: f64) -> bool {
        let (start, end) = self.window(k, tau);
        self.integral.covers(start) && self.integral.covers(end)
    }

    fn values(&self, at: &[usize], tau: f64) -> Vec<[f64; 3]> {
        at.iter().map(|&k| self.at(k, tau)).collect()
    }
}

/// The channel-averaged, detrended input phase and the segments it is on.
struct CommonPhase {
    phase: Vec<f64>,
    /// Each segment's epochs and its cubics.
    segments: Vec<(Vec<usize>, Cubic)>,
    tracks_used: Vec<bool>,
    /// Track segments left out for a step (a cycle slip).
    slipped: usize,
}

/// The share of a segment's epochs a track must have a row at to enter it;
/// the segment then keeps only the epochs where every track it holds has one
/// (the same epochs for every channel and the regressors, so that the
/// average of the projections stays the projection of the average). A lock
/// indicator's few dropped rows then cost those epochs, not the channel.
const MIN_PRESENCE: f64 = 0.9;

/// Whether track `j` of a segment's detrended input phases steps by at least
/// `step_rad` (a half-cycle slip of a Costas loop is π on its own carrier,
/// which leaves the NCO's phase off by as much for good): the largest
/// difference between the means of `window` rows before and after any row,
/// of the track less the mean of the others (the common signal out; the
/// track alone when it is the only one). The means of a second of rows keep
/// the thermal noise far below a half cycle.
fn slipped(residuals: &[(usize, Vec<f64>)], j: usize, window: usize, step_rad: f64) -> bool {
    let own = &residuals[j].1;
    let others = residuals.len() - 1;
    let d: Vec<f64> = (0..own.len())
        .map(|k| {
            let rest = residuals.iter().enumerate().filter(|(o, _)| *o != j).map(|(_, (_, r))| r[k]).sum::<f64>();
            if others > 0 { own[k] - rest / others as f64 } else { own[k] }
        })
        .collect();
    if d.len() < 2 * window {
        return false;
    }
    let mut prefix = Vec::with_capacity(d.len() + 1);
    prefix.push(0.0);
    for v in &d {
        prefix.push(prefix.last().copied().unwrap_or(0.0) + v);
    }
    let mean = |a: usize, b: usize| (prefix[b] - prefix[a]) / (b - a) as f64;
    (window..=d.len() - window).any(|k| (mean(k, k + window) - mean(k - window, k)).abs() >= step_rad)
}

impl CommonPhase {
    /// Each track's θ_in (`inputs`: per track the values on the epochs and
    /// the scale to L1) detrended per segment and averaged over the tracks
    /// that cover the segment's usable epochs and did not slip in it
    /// ([`slipped`], steps of at least `step_rad` between the means of
    /// `slip_window` rows).
    fn assemble(
        epochs: &[f64],
        usable: &[bool],
        inputs: &[(&[Option<f64>], f64)],
        segment_s: f64,
        step_rad: f64,
        slip_window: usize,
    ) -> Self {
        let mut m =
            CommonPhase { phase: Vec::new(), segments: Vec::new(), tracks_used: vec![false; inputs.len()], slipped: 0 };
        let first = usable.iter().position(|&u| u).unwrap_or(epochs.len());
        for seg in segments(&epochs[first..], segment_s) {
            let usable_at: Vec<usize> = (seg.start + first..seg.end + first).filter(|&k| usable[k]).collect();
            // The tracks with a value at nearly every epoch, and the epochs where all of them have one.
            let present = |theta: &[Option<f64>]| usable_at.iter().filter(|&&k| theta[k].is_some()).count();
            let members: Vec<usize> = (0..inputs.len())
                .filter(|&i| present(inputs[i].0) as f64 >= MIN_PRESENCE * usable_at.len() as f64)
                .collect();
            let at: Vec<usize> =
                usable_at.into_iter().filter(|&k| members.iter().all(|&i| inputs[i].0[k].is_some())).collect();
            if at.len() < 10 || members.is_empty() {
                continue;
            }
            let basis = Cubic::on(&at.iter().map(|&k| epochs[k]).collect::<Vec<_>>());
            let residuals: Vec<(usize, Vec<f64>)> = members
                .iter()
                .map(|&i| {
                    let (theta, scale) = &inputs[i];
                    let values: Vec<f64> = at.iter().map(|&k| theta[k].map_or(0.0, |v| v * scale)).collect();
                    (i, basis.residual(&values))
                })
                .collect();
            let kept: Vec<&(usize, Vec<f64>)> = residuals
                .iter()
                .enumerate()
                .filter(|(j, (i, _))| {
                    let slip = slipped(&residuals, *j, slip_window, step_rad * inputs[*i].1);
                    m.slipped += usize::from(slip);
                    !slip
                })
                .map(|(_, r)| r)
                .collect();
            if kept.is_empty() {
                continue;
            }
            let mut sum = vec![0.0; at.len()];
            for (i, r) in &kept {
                sum.iter_mut().zip(r).for_each(|(s, v)| *s += v);
                m.tracks_used[*i] = true;
            }
            m.phase.extend(sum.iter().map(|s| s / kept.len() as f64));
            m.segments.push((at, basis));
        }
        m
    }

    fn ranges(&self) -> Vec<Range<usize>> {
        let mut start = 0;
        self.segments
            .iter()
            .map(|(at, _)| {
                start += at.len();
                start - at.len()..start
            })
            .collect()
    }

    /// The regressors at offset `tau`, detrended on the same segments.
    fn regressors(&self, regressor: &impl RowRegressor, tau: f64) -> Vec<[f64; 3]> {
        let at: Vec<usize> = self.segments.iter().flat_map(|(at, _)| at.iter().copied()).collect();
        let raw = regressor.values(&at, tau);
        let mut out = Vec::with_capacity(self.phase.len());
        let mut start = 0;
        for (at, basis) in &self.segments {
            let raw = &raw[start..start + at.len()];
            start += at.len();
            let columns: [Vec<f64>; 3] =
                [0, 1, 2].map(|i| basis.residual(&raw.iter().map(|r| r[i]).collect::<Vec<_>>()));
            out.extend((0..at.len()).map(|j| [columns[0][j], columns[1][j], columns[2][j]]));
        }
        out
    }

    /// The least-squares residual variance at offset `tau`.
    fn residual_variance(&self, regressor: &impl RowRegressor, tau: f64) -> f64 {
        let mut ne = gsens_core::NormalEquations::default();
        for (row, y) in self.regressors(regressor, tau).iter().zip(&self.phase) {
            ne.add(*y, row);
        }
        ne.solve().residual_variance_rad2
    }

    /// The offset within `range` of least residual: a grid half the log
    /// interval apart, then golden-section refinement between the best
    /// point's neighbours to a thousandth of the log interval (the residual
    /// is smooth in τ: a shaking period spans tens of grid steps).
    fn search_offset(&self, regressor: &impl RowRegressor, range: [f64; 2], log_interval_s: f64) -> f64 {
        let n = ((range[1] - range[0]) / (log_interval_s / 2.0)).ceil().max(1.0) as usize;
        let grid: Vec<f64> = (0..=n).map(|j| range[0] + (range[1] - range[0]) * j as f64 / n as f64).collect();
        let cost = |tau: f64| self.residual_variance(regressor, tau);
        let values: Vec<f64> = grid.par_iter().map(|&tau| cost(tau)).collect();
        let best = (0..grid.len()).min_by(|&a, &b| values[a].total_cmp(&values[b])).unwrap_or(0);
        let (mut lo, mut hi) = (grid[best.saturating_sub(1)], grid[(best + 1).min(n)]);
        let golden = (5f64.sqrt() - 1.0) / 2.0;
        let (mut a, mut b) = (hi - golden * (hi - lo), lo + golden * (hi - lo));
        let (mut fa, mut fb) = (cost(a), cost(b));
        while hi - lo > 1e-3 * log_interval_s {
            if fa < fb {
                (hi, b, fb) = (b, a, fa);
                a = hi - golden * (hi - lo);
                fa = cost(a);
            } else {
                (lo, a, fa) = (a, b, fb);
                b = lo + golden * (hi - lo);
                fb = cost(b);
            }
        }
        (lo + hi) / 2.0
    }
}

pub(crate) fn check_settings(s: &LoopFreeSettings) -> Result<(), LoopFreeError> {
    let positive = |name, value: f64| {
        if value > 0.0 && value.is_finite() {
            Ok(())
        } else {
            Err(LoopFreeError::Setting { name, value, expected: "finite and > 0" })
        }
    };
    positive("loop_interval_s", s.loop_interval_s)?;
    positive("segment_s", s.segment_s)?;
    positive("max_abs_phase_rad", s.max_abs_phase_rad)?;
    if !(s.warmup_s >= 0.0 && s.warmup_s.is_finite()) {
        return Err(LoopFreeError::Setting { name: "warmup_s", value: s.warmup_s, expected: "finite and ≥ 0" });
    }
    match s.time_offset {
        crate::TimeOffset::Fixed { imu_time_offset_s } if !imu_time_offset_s.is_finite() => {
            return Err(LoopFreeError::Setting {
                name: "imu_time_offset_s",
                value: imu_time_offset_s,
                expected: "finite",
            });
        }
        crate::TimeOffset::Auto { max_abs_s } if !(max_abs_s >= 0.0 && max_abs_s.is_finite()) => {
            return Err(LoopFreeError::Setting {
                name: "time_offset.max_abs_s",
                value: max_abs_s,
                expected: "finite and ≥ 0",
            });
        }
        _ => {}
    }
    Ok(())
}

/// The median spacing of the stamps (the high median: one of the spacings;
/// NaN for fewer than two stamps).
pub(crate) fn median_step(t_s: &[f64]) -> f64 {
    let mut steps: Vec<f64> = t_s.windows(2).map(|w| w[1] - w[0]).collect();
    gsens_core::stats::median_high_in_place(&mut steps)
}

/// Loop updates per log interval ([`gsens_core::loop_substeps`]).
fn substeps(log_interval_s: f64, loop_interval_s: f64) -> Result<usize, LoopFreeError> {
    gsens_core::loop_substeps(loop_interval_s, log_interval_s)
        .map(|n| n as usize)
        .map_err(|_| LoopFreeError::Intervals { log_interval_s, loop_interval_s })
}

/// A track's input phase θ_in \[rad\] on the log's epochs (`None` where it
/// has no row, or where its row does not give θ_in).
///
/// `last`: the row's φ is the latest integration's, centred on the stamp, and
/// the NCO phase is the integration's end, so θ_in = 2π(c − f·T/2) + φ with
/// f the commanded frequency (`nco_freq_hz` where `logged_frequency` and the
/// log has it, else the phase's mean rate from the neighbouring row). `mean`: φ is the mean over the n
/// integrations since the previous row, so θ_NCO is averaged over their
/// centres t − iT (i = 0…n−1) on the cubic through the NCO phases of four
/// consecutive rows around it (at their integrations' ends, t_j + T/2): the
/// average of the two end phases alone would be the trapezoid rule, which
/// inflates the NCO's oscillating part by ≈ (ωh)²/12 (0.2 % at 0.9 Hz with
/// 40 Hz rows) and Γ̂ with it.
fn input_phase_on_epochs(
    tr: &gsens_io::ChannelTrack,
    epochs: &[f64],
    log_interval_s: f64,
    substeps: usize,
    settings: &LoopFreeSettings,
    logged_frequency: bool,
) -> Vec<Option<f64>> {
    let mut out = vec![None; epochs.len()];
    let c = &tr.nco_phase_cycles;
    let t_loop = settings.loop_interval_s;
    // Rows j and j + 1 are one log interval apart (no gap between them).
    let next_is_adjacent =
        |j: usize| j + 1 < tr.len() && ((tr.t_s[j + 1] - tr.t_s[j]) - log_interval_s).abs() < 0.1 * log_interval_s;
    for (k, e) in rows_on_epochs(&tr.t_s, epochs) {
        if tr.t_s[k] < tr.t_s[0] + settings.warmup_s || tr.phase_err_rad[k].abs() > settings.max_abs_phase_rad {
            continue;
        }
        out[e] = match settings.logged_phase {
            LoggedPhase::Last => {
                let freq_hz = match tr.nco_freq_hz.get(k).filter(|_| logged_frequency) {
                    Some(&f) => Some(f),
                    None if k >= 1 => Some((c[k] - c[k - 1]) / (tr.t_s[k] - tr.t_s[k - 1])),
                    None if tr.len() > 1 => Some((c[1] - c[0]) / (tr.t_s[1] - tr.t_s[0])),
                    None => None,
                };
                freq_hz.map(|f| TAU * (c[k] - f * t_loop / 2.0) + tr.phase_err_rad[k])
            }
            LoggedPhase::Mean => {
                // Four adjacent rows, centred on k where the track allows.
                let window = [k.wrapping_sub(2), k.wrapping_sub(1), k.wrapping_sub(3), k]
                    .into_iter()
                    .find(|&s| s.checked_add(3).is_some_and(|end| end < tr.len()) && (s..s + 3).all(next_is_adjacent));
                window.map(|s| {
                    let ends: [f64; 4] = [0, 1, 2, 3].map(|m| tr.t_s[s + m] + t_loop / 2.0 - tr.t_s[k]);
                    let centres = (0..substeps).map(|i| -(i as f64) * t_loop);
                    let mean_cycles = centres.map(|y| lagrange(&ends, &c[s..s + 4], y)).sum::<f64>() / substeps as f64;
                    TAU * mean_cycles + tr.phase_err_rad[k]
                })
            }
        };
    }
    out
}

/// The epochs of each segment: the log's span cut into equal segments of
/// about `segment_s` (at least one).
fn segments(epochs: &[f64], segment_s: f64) -> Vec<Range<usize>> {
    let (Some(&t0), Some(&t1)) = (epochs.first(), epochs.last()) else { return Vec::new() };
    let count = ((t1 - t0) / segment_s).floor().max(1.0) as usize;
    let length_s = (t1 - t0) / count as f64;
    let mut out = Vec::with_capacity(count);
    let mut start = 0;
    for j in 1..=count {
        let end = if j == count { epochs.len() } else { epochs.partition_point(|&t| t < t0 + j as f64 * length_s) };
        out.push(start..end);
        start = end;
    }
    out
}

/// An orthonormal basis of the cubics on a segment's instants (modified
/// Gram–Schmidt on 1, x, x², x³ with x the instants scaled to [−1, 1]):
/// projecting one out is a few dot products, and well conditioned.
struct Cubic {
    basis: Vec<Vec<f64>>,
}

impl Cubic {
    fn on(t_s: &[f64]) -> Self {
        let (t0, t1) = (t_s[0], t_s[t_s.len() - 1]);
        let half = ((t1 - t0) / 2.0).max(f64::MIN_POSITIVE);
        let x: Vec<f64> = t_s.iter().map(|t| (t - (t0 + t1) / 2.0) / half).collect();
        let mut basis: Vec<Vec<f64>> = Vec::with_capacity(4);
        for power in 0..4 {
            let mut v: Vec<f64> = x.iter().map(|x| x.powi(power)).collect();
            for b in &basis {
                let d = dot(&v, b);
                v.iter_mut().zip(b).for_each(|(v, b)| *v -= d * b);
            }
            let norm = dot(&v, &v).sqrt();
            if norm > 1e-9 * (x.len() as f64).sqrt() {
                basis.push(v.iter().map(|v| v / norm).collect());
            }
        }
        Cubic { basis }
    }

    /// `values` less their projection on the cubics.
    fn residual(&self, values: &[f64]) -> Vec<f64> {
        // The first value taken out first: what is left is small, so the projection loses no digits.
        let mut r: Vec<f64> = values.iter().map(|v| v - values[0]).collect();
        for b in &self.basis {
            let d = dot(&r, b);
            r.iter_mut().zip(b).for_each(|(r, b)| *r -= d * b);
        }
        r
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(a, b)| a * b).sum()
}

/// ∫a dt of the IMU's specific force on the cubic Hermite (Catmull–Rom)
/// interpolant of its samples ([`ImuSeries::interpolate_at`], its slopes
/// [`ImuSeries::hermite_slope`]): exact for a
/// quadratic a, where the linear interpolant's integral (the trapezoid rule)
/// would shrink a sinusoid's integral by ≈ (ωh)²/12 (0.17 % at 0.9 Hz with a
/// 40 Hz IMU) and inflate Γ̂ by as much. Over one interval of length h:
///
/// ```text
/// ∫ = h(a_j + a_j+1)/2 + h²(m_j − m_j+1)/12
/// ```
struct ForceIntegral<'a> {
    cubic: ImuCubic<'a>,
    at_sample: Vec<[f64; 3]>,
}

impl<'a> ForceIntegral<'a> {
    fn new(imu: &'a ImuSeries) -> Self {
        let (t, a) = (&imu.t_s, &imu.accel_mps2);
        let n = t.len();
        let cubic = ImuCubic::new(imu);
        let slope = cubic.slopes();
        let mut at_sample = Vec::with_capacity(n);
        let mut sum = [0.0; 3];
        for j in 0..n {
            if j > 0 {
                let h = t[j] - t[j - 1];
                for (i, s) in sum.iter_mut().enumerate() {
                    *s += h * (a[j - 1][i] + a[j][i]) / 2.0 + h * h * (slope[j - 1][i] - slope[j][i]) / 12.0;
                }
            }
            at_sample.push(sum);
        }
        ForceIntegral { cubic, at_sample }
    }

    fn covers(&self, t_s: f64) -> bool {
        let t = &self.cubic.series().t_s;
        t.len() >= 2 && t_s >= t[0] && t_s <= t[t.len() - 1]
    }

    /// ∫ from the first sample to `t_s` (within [`Self::covers`]) \[m/s\].
    fn at(&self, t_s: f64) -> [f64; 3] {
        let (t, a) = (&self.cubic.series().t_s, &self.cubic.series().accel_mps2);
        let j = t.partition_point(|&x| x <= t_s).clamp(1, t.len() - 1) - 1;
        let h = t[j + 1] - t[j];
        let u = (t_s - t[j]) / h;
        let (u2, u3, u4) = (u * u, u * u * u, u * u * u * u);
        // The Hermite basis functions integrated from 0 to u.
        let w00 = u - u3 + u4 / 2.0;
        let w10 = u2 / 2.0 - 2.0 * u3 / 3.0 + u4 / 4.0;
        let w01 = u3 - u4 / 2.0;
        let w11 = -u3 / 3.0 + u4 / 4.0;
        let slope = self.cubic.slopes();
        [0, 1, 2].map(|i| {
            self.at_sample[j][i]
                + h * (w00 * a[j][i] + w10 * h * slope[j][i] + w01 * a[j + 1][i] + w11 * h * slope[j + 1][i])
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A row's regressor is ρ = −2π∫a averaged over its integrations, not
    /// read at their centre: for a = A·sin ωt, ρ's oscillating part
    /// 2πA/ω·cos ωt averages to the centre value times sinc(ωW/2) over a
    /// window W. At 0.9 Hz a centre reading of a 20 ms integration would be
    /// off by (ωT)²/24 = 5.3·10⁻⁴ of the amplitude; the cubic through the
    /// 40 Hz IMU costs ~10⁻⁵.
    #[test]
    fn a_rows_regressor_is_the_mean_over_its_integrations() {
        let (amp, w) = (3.0, core::f64::consts::TAU * 0.9);
        let t_s: Vec<f64> = (0..2000).map(|k| k as f64 / 40.0).collect();
        let imu =
            ImuSeries { t_s: t_s.clone(), accel_mps2: t_s.iter().map(|&t| [amp * (w * t).sin(), 0.0, 0.0]).collect() };
        let epochs: Vec<f64> = (100..2000).map(|k| k as f64 / 50.0).filter(|&t| t < 48.0).collect();
        for (n_window, loop_interval_s) in [(1, 0.02), (20, 0.001)] {
            let regressor = Regressor::new(&imu, &epochs, n_window, loop_interval_s);
            let window_s = n_window as f64 * loop_interval_s;
            let sinc = (w * window_s / 2.0).sin() / (w * window_s / 2.0);
            for k in (0..epochs.len()).step_by(37) {
                let centre = epochs[k] + loop_interval_s / 2.0 - window_s / 2.0;
                // −2π·mean of A(1 − cos ωt)/ω over the window.
                let want = -core::f64::consts::TAU * amp / w * (1.0 - (w * centre).cos() * sinc);
                let got = regressor.at(k, 0.0)[0];
                let scale = core::f64::consts::TAU * amp / w;
                assert!((got - want).abs() < 3e-5 * scale, "n {n_window} epoch {k}: {got} against {want}");
            }
        }
    }

    /// Catmull–Rom reproduces a quadratic, so its integral is exact for one
    /// (here on uneven samples, away from the ends' one-sided slopes).
    #[test]
    fn the_integral_is_exact_for_a_quadratic() {
        let t_s: Vec<f64> = (0..40).map(|k| 0.1 * k as f64 + 0.01 * ((k * 7) % 5) as f64).collect();
        let f = |t: f64| [1.0 + 2.0 * t - 0.5 * t * t, 9.81, -t * t];
        let integral = |t: f64| [t + t * t - t * t * t / 6.0, 9.81 * t, -t * t * t / 3.0];
        let imu = ImuSeries { t_s: t_s.clone(), accel_mps2: t_s.iter().map(|&t| f(t)).collect() };
        let fi = ForceIntegral::new(&imu);
        let (from, to) = (t_s[2], t_s[30] + 0.037);
        let (a, b) = (fi.at(from), fi.at(to));
        let (wa, wb) = (integral(from), integral(to));
        for i in 0..3 {
            assert!(((b[i] - a[i]) - (wb[i] - wa[i])).abs() < 1e-12, "axis {i}: {} vs {}", b[i] - a[i], wb[i] - wa[i]);
        }
        assert!(fi.covers(t_s[39]) && !fi.covers(t_s[39] + 0.01) && !fi.covers(-0.1));
    }

    /// The mean of the NCO phase at the integration centres from the cubic
    /// through four rows: exact for a cubic phase (where the two end phases'
    /// mean is not).
    #[test]
    fn the_nco_mean_is_exact_for_a_cubic_phase() {
        let h = 0.025;
        let t_loop = 0.001;
        let phase = |t: f64| 1e5 + 1500.0 * t + 3.0 * t * t - 0.7 * t * t * t;
        let rows: Vec<f64> = (0..8).map(|k| 10.0 + k as f64 * h).collect();
        let mut tr = gsens_io::TrackingLog::from_rows(
            "t",
            rows.iter().map(|&t| gsens_io::TrackingRow {
                t_s: t,
                channel: 1,
                prn: 3,
                cn0_dbhz: 45.0,
                elev_deg: None,
                phase_err_rad: 0.0,
            }),
        )
        .unwrap()
        .into_tracks()
        .remove(0);
        tr.nco_phase_cycles = rows.iter().map(|t| phase(t + t_loop / 2.0)).collect();
        let settings = LoopFreeSettings { warmup_s: 0.0, ..LoopFreeSettings::new(t_loop, LoggedPhase::Mean) };
        let theta = input_phase_on_epochs(&tr, &rows, h, 25, &settings, true);
        for (k, th) in theta.iter().enumerate() {
            let want = TAU * (0..25).map(|i| phase(rows[k] - i as f64 * t_loop)).sum::<f64>() / 25.0;
            let got = th.expect("four adjacent rows around every row");
            assert!((got - want).abs() < 1e-8, "{k}: {got} vs {want}");
        }
    }

    #[test]
    fn a_cubic_projects_to_zero_and_an_orthogonal_signal_is_kept() {
        let t: Vec<f64> = (0..400).map(|k| 100.0 + k as f64 * 0.025).collect();
        let basis = Cubic::on(&t);
        let cubic: Vec<f64> = t.iter().map(|t| 3e6 + 2e4 * t - 0.45 * t * t + 1e-4 * t * t * t).collect();
        let r = basis.residual(&cubic);
        assert!(r.iter().all(|v| v.abs() < 1e-6), "{:?}", r.iter().fold(0.0f64, |m, v| m.max(v.abs())));
        // A 1 Hz sinusoid loses 1.9 % of its energy to the cubics over 10 s,
        // 0.21 % over 30 s (numpy's least squares on the same instants).
        for (seconds, lost) in [(10.0, 0.018925), (30.0, 0.0021424)] {
            let t: Vec<f64> = (0..(seconds / 0.025) as usize).map(|k| k as f64 * 0.025).collect();
            let s: Vec<f64> = t.iter().map(|t| (TAU * t + 0.3).sin()).collect();
            let r = Cubic::on(&t).residual(&s);
            let kept = dot(&r, &r) / dot(&s, &s);
            assert!((1.0 - kept - lost).abs() < 1e-5, "{seconds} s: lost {}", 1.0 - kept);
        }
    }

    #[test]
    fn segments_cover_the_log_in_equal_lengths() {
        let t: Vec<f64> = (0..=4000).map(|k| k as f64 * 0.025).collect();
        let s = segments(&t, 30.0);
        assert_eq!(s.len(), 3);
        assert_eq!((s[0].start, s[2].end), (0, t.len()));
        assert!(s.windows(2).all(|w| w[0].end == w[1].start));
        assert_eq!(segments(&t[..100], 30.0), vec![0..100]);
    }

    #[test]
    fn the_loop_interval_must_divide_the_log_interval() {
        assert_eq!(substeps(0.025, 0.001), Ok(25));
        assert!(substeps(0.025, 0.003).is_err());
    }
}

/// The loop-free estimate beside the estimate through the loop model, as the
/// result document holds it (`loop_free`): the measurement, the estimate or
/// why there is none, and the two estimates' difference per axis.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[non_exhaustive]
pub struct LoopFreeCheck {
    /// What the estimate regresses: the phase the loop was fed (θ_NCO + φ),
    /// where the estimate through the loop model regresses the tracking
    /// error.
    pub measurement: Measurement,
    /// The estimate, when one could be made.
    pub estimate: Option<LoopFreeEstimate>,
    /// Why none could be made.
    pub error: Option<String>,
    /// (Γ̂ − Γ̂_loop-free)/√(σ² + σ_loop-free²) per axis, Γ̂ and σ the
    /// estimate through the loop model's (`null` where either has no
    /// estimate). The two estimates
    /// come from the same data, so their difference varies less than the
    /// sum of their variances says: the test errs towards agreeing.
    pub z_difference: [Option<f64>; 3],
}

/// Two-sided false-alarm probability of the cross-check over the three
/// axes together (Bonferroni: 10⁻³/3 per axis), as the loop's own test.
pub const CROSS_CHECK_FALSE_ALARM: f64 = 1e-3;

impl LoopFreeCheck {
    /// The check of `calibration` (the estimate through the loop model)
    /// against `loop_free`.
    pub fn new(calibration: &crate::Calibration, loop_free: &Result<LoopFreeEstimate, LoopFreeError>) -> Self {
        Self::of(Measurement::InputPhase, calibration, loop_free)
    }

    /// The check of `calibration` against `other`, an estimate from
    /// `measurement` (the NCO's phase or frequency).
    pub fn of(
        measurement: Measurement,
        calibration: &crate::Calibration,
        other: &Result<LoopFreeEstimate, LoopFreeError>,
    ) -> Self {
        let (estimate, error) = match other {
            Ok(e) => (Some(e.clone()), None),
            Err(e) => (None, Some(e.to_string())),
        };
        let z_difference = [0, 1, 2].map(|i| {
            let free = estimate.as_ref()?;
            let (g, s) = (calibration.gamma_hz_per_mps2[i]?, calibration.sigma_hz_per_mps2[i]?);
            let joint = s.hypot(free.sigma_hz_per_mps2()[i]);
            (joint > 0.0 && joint.is_finite()).then(|| (g - free.gamma_hz_per_mps2[i]) / joint)
        });
        LoopFreeCheck { measurement, estimate, error, z_difference }
    }

    /// |z| beyond which the estimates disagree: Φ⁻¹(1 − α/6) = 3.59 for
    /// α = [`CROSS_CHECK_FALSE_ALARM`].
    pub fn z_critical() -> f64 {
        use statrs::distribution::{ContinuousCDF, Normal};
        Normal::standard().inverse_cdf(1.0 - CROSS_CHECK_FALSE_ALARM / 6.0)
    }

    /// The warning `loop_free_disagrees` when an axis's difference passes
    /// [`LoopFreeCheck::z_critical`]: the loop model (stated or from the
    /// receiver's configuration) does not describe the receiver, and the
    /// loop-free estimate, which assumes no loop, is the one to believe.
    pub fn warning(&self) -> Option<crate::Warning> {
        let z_crit = Self::z_critical();
        let free = self.estimate.as_ref()?;
        let axes: Vec<String> = (0..3)
            .filter_map(|i| {
                let z = self.z_difference[i].filter(|z| z.abs() > z_crit)?;
                Some(format!(
                    "{} by {:+.1}σ (loop-free {:.5} ± {:.5} Hz/(m/s²))",
                    ["x", "y", "z"][i],
                    z,
                    free.gamma_hz_per_mps2[i],
                    free.sigma_hz_per_mps2()[i]
                ))
            })
            .collect();
        (!axes.is_empty()).then(|| crate::Warning {
            code: crate::WarningCode::LoopFreeDisagrees,
            message: format!(
                "the estimate through the loop model and the loop-free estimate from the NCO's phase disagree on \
                 {}: either the loop model does not describe the receiver (its order, bandwidth, update interval or \
                 what its log holds) and the loop-free estimate, which assumes no loop, is the one to believe, or the \
                 NCO's phase is not logged as the conventions say (its sign, its instant, its unit); where the \
                 loop's own checks find the loop at fault, believe the loop-free estimate",
                axes.join(", ")
            ),
        })
    }
}
