//! The whole calibration from logs: prepare the session (grid, screening,
//! averaging), estimate the systematic errors asked for (time offset, loop),
//! estimate Γ, and describe it all in one [`ResultDocument`].

use crate::document::{ResultDocument, SourceConversion};
use crate::{
    CalibError, Calibration, EpochSeries, EstimateSettings, JointFit, JointSpec, Measurement, MeasurementChoice,
    calibrate, compare_loop_forms, joint_fit_from, session_linear_range_rad,
};
use gsens_core::{Discriminator, LoopModel};
use gsens_io::{FormatError, ImuSeries, TrackingLog};
use gsens_session::{
    FlatRuns, PreparedSession, SelectionConfig, find_flat_runs, imu_spikes, mask_flat_runs, prepare_session_from,
    reinterpolate_imu, replace_imu_spikes,
};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::borrow::Cow;
use std::path::Path;

/// How the IMU/tracking time offset (IMU time stamp minus true time) is handled.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "mode", rename_all = "lowercase")]
pub enum TimeOffset {
    /// Estimated jointly with Γ within ±`max_abs_s`.
    Auto {
        /// Search range ± \[s\].
        max_abs_s: f64,
    },
    /// Taken as given.
    Fixed {
        /// IMU time stamp minus true time \[s\].
        imu_time_offset_s: f64,
    },
}

impl core::str::FromStr for TimeOffset {
    type Err = ParseTimeOffsetError;

    /// `auto` (searched within ±0.25 s), `none` (0) or a number of seconds.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "auto" => Ok(TimeOffset::default()),
            "none" => Ok(TimeOffset::Fixed { imu_time_offset_s: 0.0 }),
            _ => match s.parse::<f64>() {
                Ok(v) if v.is_finite() => Ok(TimeOffset::Fixed { imu_time_offset_s: v }),
                _ => Err(ParseTimeOffsetError(s.to_string())),
            },
        }
    }
}

/// A time offset that is neither `auto`, `none` nor a finite number of seconds.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("expected auto, none or a number of seconds, got `{0}`")]
pub struct ParseTimeOffsetError(pub String);

impl Default for TimeOffset {
    fn default() -> Self {
        TimeOffset::Auto { max_abs_s: crate::defaults::DEFAULT_TIME_OFFSET_MAX_S }
    }
}

/// How the data test the stated loop ([`crate::joint_fit`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LoopIdentificationMode {
    /// The stated loop is taken as exact and not tested (its uncertainty is
    /// not in σ).
    Off,
    /// The loop's natural frequency is estimated jointly with Γ (and the time
    /// offset), the stated one tested against it within its tolerance
    /// ([`PipelineSettings::loop_tolerance`]), and Γ̂ given under the loop the
    /// data and the stated loop agree on, with the remaining uncertainty in σ.
    #[default]
    NaturalFrequency,
    /// The natural frequency and a 2nd-order loop's damping.
    NaturalFrequencyAndDamping,
}

/// How the stated loop's discrete form is known.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LoopForm {
    /// The loop model is the receiver's own, exactly: from a receiver's
    /// configuration, a simulated session's truth, or a caller's model.
    #[default]
    Exact,
    /// A loop given in words (order, bandwidth, update interval): every
    /// receiver's form of them ([`gsens_core::LoopModel::discrete_forms`]) is
    /// fitted, the data choose, and σ takes in the others ([`crate::LoopForms`]).
    Compared,
    /// A loop given in words, in this implementation's form of them.
    Named(gsens_core::LoopImplementation),
}

impl LoopForm {
    /// The forms `stated` (a loop in words, at its update interval) may take
    /// under this rule: itself when exact, every one of
    /// [`gsens_core::LoopModel::discrete_forms`] when compared, the named
    /// implementation's (an error when the words have none).
    pub fn forms_of(self, stated: &LoopModel) -> Result<Vec<LoopModel>, CalibError> {
        let forms: Vec<LoopModel> = match self {
            LoopForm::Exact => return Ok(vec![*stated]),
            LoopForm::Compared => stated.discrete_forms().collect(),
            LoopForm::Named(i) => stated.discrete_forms().filter(|f| f.implementation() == i).collect(),
        };
        match (forms.is_empty(), self) {
            (true, LoopForm::Named(implementation)) => {
                Err(CalibError::NoLoopForm { stated: stated.to_string(), implementation })
            }
            _ => Ok(forms),
        }
    }
}

/// The relative 1σ tolerance of a loop stated by its design (order,
/// bandwidth, update interval) when the user gives none: 2 %. With the
/// order, bandwidth and update interval stated right, an implementation's
/// natural frequency differs from its design's by the constants that turn Bn
/// into ωn (0.53 against 0.5303 for ζ = 1/√2: 0.06 %), by how its integrators
/// are discretized (rectangular against bilinear moves ωn by about ωn·T/2:
/// 0.3 % at 3 Hz and 1 ms, 1.4 % at 5 ms) and by rounding of its gains (under
/// 1 %). A wider tolerance would also take in errors of the loop's shape
/// (a wrong update interval, order or logged phase), which no natural
/// frequency makes right: those the loop test must reject.
pub const DEFAULT_LOOP_TOLERANCE: f64 = 0.02;

/// False-alarm probability of the measured-response check in the pipeline:
/// 0.5 %, so that with the loop test's 0.1 % a clean session is flagged less
/// than 1 % of the time.
pub const RESPONSE_CHECK_FALSE_ALARM: f64 = 0.005;

/// Everything that decides a calibration from logs.
///
/// Start from [`PipelineSettings::default`] and set what differs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
#[non_exhaustive]
pub struct PipelineSettings {
    /// The estimation stage: loop, estimator, error model.
    pub estimate: EstimateSettings,
    /// Which channels enter the average, and how.
    pub selection: SelectionConfig,
    /// The IMU time offset.
    pub time_offset: TimeOffset,
    /// Loop identification.
    pub loop_identification: LoopIdentificationMode,
    /// The relative 1σ uncertainty of the stated loop's natural frequency
    /// (0: the receiver implements exactly the stated loop; infinite: only
    /// its shape is known). `None`: the input's own, 0 for a loop modelled
    /// from a receiver's configuration (GNSS-SDR, PocketSDR), otherwise
    /// [`DEFAULT_LOOP_TOLERANCE`].
    pub loop_tolerance: Option<f64>,
    /// Whether the receiver loop in `estimate` was stated by the user. When
    /// not, the loop is chosen among typical receiver loops by the data
    /// ([`crate::choose_loop`]) and the estimate is flagged until it is stated.
    pub loop_stated: bool,
    /// Whether the loop in `estimate` is the receiver's exactly or a loop
    /// given in words, whose discrete form is then named or chosen by the data.
    pub loop_form: LoopForm,
    /// Replace isolated IMU spikes by the mean of their neighbours before
    /// anything else ([`gsens_session::replace_imu_spikes`]; default on).
    pub despike_imu: bool,
    /// What the result's estimate is made from ([`Outcome::measurement`]).
    pub measurement: MeasurementChoice,
}

impl Default for PipelineSettings {
    fn default() -> Self {
        PipelineSettings {
            estimate: EstimateSettings::default(),
            selection: SelectionConfig::default(),
            time_offset: TimeOffset::default(),
            loop_identification: LoopIdentificationMode::default(),
            loop_tolerance: None,
            loop_stated: true,
            loop_form: LoopForm::Exact,
            despike_imu: true,
            measurement: MeasurementChoice::Auto,
        }
    }
}

impl PipelineSettings {
    /// These settings with a receiver's own loop modelled exactly, as an
    /// adapter that reads the loop from the receiver's configuration states
    /// it: `receiver_loop`, each row the loop's last discriminator output
    /// ([`gsens_core::LoggedPhase::Last`]), `discriminator`, the loop stated,
    /// and exact (a tolerance of 0 unless one was given: tested, not fitted).
    pub fn with_exact_loop(&self, receiver_loop: LoopModel, discriminator: Discriminator) -> PipelineSettings {
        let mut settings = self.clone();
        settings.estimate.receiver_loop = receiver_loop;
        settings.estimate.logged_phase = gsens_core::LoggedPhase::Last;
        settings.set_discriminator(discriminator);
        settings.loop_stated = true;
        settings.loop_tolerance.get_or_insert(0.0);
        settings
    }

    /// States the receiver's discriminator: the estimate's range check uses
    /// it, and the screening's linear-range limit moves with it where it was
    /// half the previous discriminator's unambiguous range, the default (a
    /// limit set otherwise, or none, is kept).
    pub fn set_discriminator(&mut self, discriminator: Discriminator) {
        let limit = &mut self.selection.screening.max_abs_phase_rad;
        if *limit == Some(0.5 * self.estimate.discriminator.unambiguous_range_rad()) {
            *limit = Some(0.5 * discriminator.unambiguous_range_rad());
        }
        self.estimate.discriminator = discriminator;
    }
}

/// Why a calibration from logs could not run.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PipelineError {
    /// A log could not be read or does not hold the format.
    #[error(transparent)]
    Format(#[from] FormatError),
    /// The session could not be prepared from the logs.
    #[error(transparent)]
    Session(#[from] gsens_session::SessionError),
    /// A stage of the estimation failed.
    // The cause is in the message, not a `source` as well: a chain printed in
    // full (anyhow's `{:#}`) would say it twice.
    #[error("{stage}: {error}")]
    Stage {
        /// What was being done.
        stage: &'static str,
        /// Why it failed.
        error: CalibError,
    },
    /// The estimation failed.
    #[error(transparent)]
    Calib(#[from] CalibError),
    /// A carrier phase and Doppler log gives no rows.
    #[error(transparent)]
    ObservationRows(#[from] crate::ObservationRowsError),
    /// A carrier phase and Doppler log (RINEX, UBX) could not be calibrated.
    #[error("{source_name}: {why}")]
    Observations {
        /// The log's name.
        source_name: String,
        /// Why not.
        why: String,
    },
    /// The measurement asked for cannot be made from the log.
    #[error("measurement input_phase: {why}")]
    Measurement {
        /// Why not.
        why: String,
    },
}

/// A calibration from logs: the prepared session it was estimated from and
/// the estimate.
#[derive(Debug, Clone)]
#[non_exhaustive]
pub struct Outcome {
    /// The estimator's inputs on the epoch grid, with every channel's fate.
    pub session: PreparedSession,
    /// The estimate, from [`Outcome::measurement`].
    pub calibration: Calibration,
    /// What `calibration` is made from ([`PipelineSettings::measurement`]
    /// resolved against the log).
    pub measurement: Measurement,
    /// The estimate through the loop model, where `calibration` is made
    /// from another measurement: the cross-check's other side.
    pub tracking_error: Option<Calibration>,
    /// The settings it ran with.
    pub settings: PipelineSettings,
    /// What a receiver's adapter did to turn its files into the logs
    /// (`None` for logs in gsens's format).
    pub source: Option<SourceConversion>,
    /// The loop the data chose when none was stated.
    pub chosen_loop: Option<crate::ChosenLoop>,
    /// The loop's response measured from the session against the model
    /// ([`crate::measure_response_with`], at [`RESPONSE_CHECK_FALSE_ALARM`]),
    /// or why it could not be measured.
    pub loop_response: Result<crate::ResponseCheck, crate::ResponseCheckError>,
    /// Time stamps of the IMU samples replaced as isolated spikes \[s\].
    pub imu_spikes_t_s: Vec<f64>,
    /// Runs of identical IMU samples no noise or motion makes (stuck,
    /// clipped; [`gsens_session::find_flat_runs`]), and the log's sample
    /// interval, step and noise behind the test.
    pub imu_flat_runs: FlatRuns,
    /// Epochs left out of the estimate because their IMU reading touches a
    /// flat run ([`gsens_session::mask_flat_runs`]).
    pub imu_flat_run_epochs: usize,
    /// The inputs as role → path (`imu`, `tracking`, a receiver's files);
    /// empty for logs given in memory. Callers may add their own (`truth`).
    pub inputs: Vec<(String, String)>,
    /// The loop-free estimate from the NCO's phase ([`crate::estimate_loop_free`]),
    /// for a tracking log that holds it; `None` for one that does not.
    pub loop_free: Option<Result<crate::LoopFreeEstimate, crate::LoopFreeError>>,
    /// The estimate from the NCO's frequency through the loop model's closed
    /// loop ([`crate::estimate_nco_frequency`], with the loop the estimate
    /// through the loop model settled on and its σ), for a tracking log that
    /// holds it; `None` for one that does not.
    pub nco_frequency: Option<Result<crate::LoopFreeEstimate, crate::LoopFreeError>>,
}

impl Outcome {
    /// The estimator's view of the prepared session.
    pub fn series(&self) -> EpochSeries<'_> {
        series_of(&self.session)
    }

    /// Makes `calibration` the estimate from the measurement `choice`
    /// resolves to against [`Outcome::loop_free`] (a receiver's adapter that
    /// sets `loop_free` itself calls it again afterwards): for the input
    /// phase, the loop-free Γ̂ and its covariance (statistical, plus the
    /// IMU's systematic part) take the place of the estimate through the loop
    /// model, which moves to [`Outcome::tracking_error`].
    pub fn choose_measurement(&mut self, choice: MeasurementChoice) -> Result<(), PipelineError> {
        self.settings.measurement = choice;
        if let Some(closed) = self.tracking_error.take() {
            self.calibration = closed;
            self.measurement = Measurement::TrackingError;
        }
        let chosen = choice
            .resolve(self.loop_free.as_ref(), self.nco_frequency.as_ref())
            .map_err(|why| PipelineError::Measurement { why })?;
        let direct = match chosen {
            Measurement::InputPhase => self.loop_free.as_ref(),
            Measurement::NcoFrequency => self.nco_frequency.as_ref(),
            _ => None,
        };
        if let Some(Ok(estimate)) = direct {
            let mut adopted = self.calibration.clone();
            let series = series_of(&self.session);
            let figures = crate::estimate::residual_figures(&series, &adopted.settings, &estimate.gamma_hz_per_mps2)?;
            adopted.adopt_direct(chosen, estimate, figures);
            self.tracking_error = Some(std::mem::replace(&mut self.calibration, adopted));
            self.measurement = chosen;
        }
        Ok(())
    }

    /// The estimate through the loop model: [`Outcome::tracking_error`]
    /// where the document's estimate is another, else `calibration`.
    pub fn closed_loop(&self) -> &Calibration {
        self.tracking_error.as_ref().unwrap_or(&self.calibration)
    }

    /// The result document of this calibration (with the true Γ when known).
    pub fn document(&self, truth_gamma_hz_per_mps2: Option<[f64; 3]>) -> ResultDocument {
        let inputs: Vec<(&str, &str)> = self.inputs.iter().map(|(k, v)| (k.as_str(), v.as_str())).collect();
        ResultDocument::new(self, &inputs, truth_gamma_hz_per_mps2)
    }
}

/// The estimator's view of a prepared session.
pub fn series_of(s: &PreparedSession) -> EpochSeries<'_> {
    EpochSeries {
        log_interval_s: s.log_interval_s,
        t_s: &s.t_s,
        phase_err_rad: &s.phase_err_rad,
        accel_mps2: &s.accel_mps2,
        imu_time_offset_s: s.imu_time_offset_s,
    }
}

/// Calibrates from a tracking log and an IMU series in memory (`imu_name`
/// names the IMU source in errors): prepares the session, identifies the loop
/// and estimates the time offset as `settings` ask, and estimates Γ.
pub fn calibrate_logs(
    tracking: &TrackingLog,
    imu: &ImuSeries,
    imu_name: &str,
    settings: &PipelineSettings,
) -> Result<Outcome, PipelineError> {
    calibrate_tracking(Cow::Borrowed(tracking), imu, imu_name, settings)
}

/// [`calibrate_logs`] on a tracking log it frees once the session has its
/// rows (before the screening): the log (tens of MB for an hour of 12
/// channels) is not held through the screening and the estimation.
pub fn calibrate_owned_logs(
    tracking: TrackingLog,
    imu: &ImuSeries,
    imu_name: &str,
    settings: &PipelineSettings,
) -> Result<Outcome, PipelineError> {
    calibrate_tracking(Cow::Owned(tracking), imu, imu_name, settings)
}

/// The IMU log as the pipeline uses it: isolated spikes replaced
/// ([`replace_imu_spikes`], when the settings ask for it) and the runs of identical
/// samples found ([`find_flat_runs`]). It needs nothing of the tracking log,
/// so [`calibrate_files`] prepares it while the tracking log is read.
struct PreparedImu {
    despiked: ImuSeries,
    spikes_t_s: Vec<f64>,
    flat_runs: FlatRuns,
}

impl PreparedImu {
    fn new(imu: &ImuSeries, settings: &PipelineSettings) -> Self {
        Self::of_series(imu.clone(), settings)
    }

    /// [`PreparedImu::new`] of a series no one else needs: despiked in place.
    fn of_series(mut imu: ImuSeries, settings: &PipelineSettings) -> Self {
        // Two independent tasks over the same series, run at once: the
        // spikes found and the flat runs of the series as logged.
        let (spikes, flat_runs) =
            rayon::join(|| settings.despike_imu.then(|| imu_spikes(&imu)), || find_flat_runs(&imu));
        let spikes = spikes.map(|at| replace_imu_spikes(&mut imu, &at)).unwrap_or_default();
        PreparedImu { despiked: imu, spikes_t_s: spikes.t_s, flat_runs }
    }
}

fn calibrate_tracking(
    tracking: Cow<'_, TrackingLog>,
    imu: &ImuSeries,
    imu_name: &str,
    settings: &PipelineSettings,
) -> Result<Outcome, PipelineError> {
    calibrate_prepared(tracking, PreparedImu::new(imu, settings), imu_name, settings)
}

/// The pipeline's stages: the settings' checks, the session, the checks of
/// its span, the flat IMU runs masked, the loop chosen when none was stated,
/// the joint fit of the loop and the offset, then the estimate beside the
/// loop's response check.
fn calibrate_prepared(
    tracking: Cow<'_, TrackingLog>,
    imu: PreparedImu,
    imu_name: &str,
    settings: &PipelineSettings,
) -> Result<Outcome, PipelineError> {
    settings.estimate.validate()?;
    let (assumed, max_abs_s) = time_offset_start(settings.time_offset)?;
    check_carrier(settings, &tracking)?;
    let PreparedImu { despiked, spikes_t_s, flat_runs } = imu;
    let imu = &despiked;
    // A log with the NCO (phase or frequency) is kept for the estimates from it, which read every track's rows.
    let nco_log = tracking
        .tracks()
        .iter()
        .any(|t| !t.nco_phase_cycles.is_empty() || !t.nco_freq_hz.is_empty())
        .then(|| tracking.clone().into_owned());
    // The session holds what the estimate needs of the log; a log given to
    // the pipeline is freed as soon as its rows are taken.
    crate::progress::stage("preparing the session", None);
    let mut session = prepare_session_from(tracking, imu, imu_name, &settings.selection, assumed)?;
    check_span(&session, max_abs_s, settings.estimate.warmup_s)?;
    // A stuck or clipped stretch would enter every regressor: its epochs become gaps before any search.
    let mut flat_run_epochs = mask_flat_runs(&mut session, &flat_runs);
    let mut estimate = settings.estimate;
    let mut spec = joint_spec(settings, max_abs_s)?;
    let mut chosen_loop = None;
    if !settings.loop_stated {
        let chosen = crate::choose_loop(&series_of(&session), &estimate, max_abs_s)
            .map_err(|error| PipelineError::Stage { stage: "choosing the receiver loop", error })?;
        estimate.receiver_loop = chosen.model;
        estimate.logged_phase = chosen.logged_phase;
        chosen_loop = Some(chosen);
        // The data chose the loop: nothing was stated to hold it to.
        spec.loop_tolerance = None;
    }
    let fits_nuisance = spec.natural_frequency || spec.offset_max_abs_s.is_some();
    // A loop stated in words: which receiver's form of it, named or (with
    // the joint fit to cover the rest in σ) the data's choice; without the
    // joint fit the stated loop is taken as exact, its form included.
    let mut forms = Vec::new();
    if settings.loop_stated {
        forms = settings.loop_form.forms_of(&estimate.loop_at(session.log_interval_s))?;
        if forms.len() == 1 || !fits_nuisance {
            estimate.receiver_loop = forms[0];
        }
    }
    estimate.warmup_s = estimate.warmup_s.max(session_models_warmup_s(&session, imu, &estimate));
    let mut joint = None;
    if fits_nuisance {
        let stage = |error| PipelineError::Stage { stage: "fitting the loop and the IMU time offset", error };
        let (mut loop_forms, mut start) = (None, None);
        if forms.len() > 1 {
            crate::progress::stage("comparing the stated loop's forms", None);
            let (form, compared, from) =
                compare_loop_forms(&series_of(&session), &estimate, spec, &forms).map_err(stage)?;
            estimate.receiver_loop = form;
            (loop_forms, start) = (Some(compared), Some(from));
        }
        crate::progress::stage("fitting the loop and the IMU time offset", None);
        let mut fit = joint_fit_from(&series_of(&session), &estimate, spec, start).map_err(stage)?;
        if let Some(forms) = loop_forms {
            fit.cover_loop_forms(forms);
        }
        if let Some(offset_s) = fit.imu_time_offset_s {
            reinterpolate_imu(&mut session, imu, offset_s);
            flat_run_epochs += mask_flat_runs(&mut session, &flat_runs);
        }
        // Γ̂ under the loop the fit settled on: its σ covers what remains
        // uncertain of the loop.
        estimate.receiver_loop = fit.fitted(&estimate.loop_at(session.log_interval_s));
        joint = Some(fit);
    }
    let loop_free_settings = loop_free_settings(settings, &estimate, session.log_interval_s);
    let receiver_loop = estimate.loop_at(session.log_interval_s);
    // What the estimate through the tracking error knows of that loop's
    // time constants: the NCO's frequency depends on them near the loop's
    // bandwidth, so its σ carries their uncertainty.
    let sigma_ln_loop_scale = joint
        .as_ref()
        .and_then(|j| Some(j.sigma_used_natural_frequency_hz? / j.used_natural_frequency_hz?))
        .filter(|s| s.is_finite())
        .unwrap_or(0.0);
    // The stated loop's other forms the tracking error could not rule out,
    // each at the bandwidth its own fit found: the NCO's estimate is made
    // under them too, and their spread joins its σ as it joins the
    // tracking error's.
    let other_forms: Vec<(LoopModel, crate::LoopFormFit)> = joint
        .as_ref()
        .and_then(|j| j.loop_forms.as_ref())
        .map(|compared| {
            (compared.forms.iter().zip(&forms).enumerate())
                .filter(|(k, (fit, _))| *k != compared.chosen && fit.consistent_with_statement)
                .map(|(_, (fit, model))| {
                    let scale =
                        fit.natural_frequency_hz.zip(fit.stated_natural_frequency_hz).map_or(1.0, |(f, f0)| f / f0);
                    (model.with_bn_scaled(scale), fit.clone())
                })
                .collect()
        })
        .unwrap_or_default();
    let (closed_loop, (loop_free, nco_frequency)) = rayon::join(
        || estimate_and_check_response(&session, &estimate, joint),
        || {
            let Some(log) = nco_log.as_ref() else { return (None, None) };
            let has = |column: fn(&gsens_io::ChannelTrack) -> bool| log.tracks().iter().any(column);
            let loop_free = has(|t| !t.nco_phase_cycles.is_empty()).then(|| match settings.loop_stated {
                true => crate::estimate_loop_free(log, imu, &loop_free_settings),
                // Nothing stated of the loop: the rows' bookkeeping is the data's choice too.
                false => {
                    crate::estimate_loop_free_choosing(log, imu, &loop_free_settings, &crate::TYPICAL_LOOP_INTERVALS_S)
                }
            });
            let nco_frequency = has(|t| !t.nco_freq_hz.is_empty()).then(|| {
                let mut estimate =
                    crate::estimate_nco_frequency(log, imu, &loop_free_settings, &receiver_loop, sigma_ln_loop_scale)?;
                cover_other_forms(&mut estimate, &other_forms, |model| {
                    crate::estimate_nco_frequency(log, imu, &loop_free_settings, model, 0.0)
                });
                Ok(estimate)
            });
            (loop_free, nco_frequency)
        },
    );
    let (calibration, loop_response) = closed_loop?;
    let mut outcome = Outcome {
        session,
        calibration,
        measurement: Measurement::TrackingError,
        tracking_error: None,
        settings: settings.clone(),
        source: None,
        chosen_loop,
        loop_response,
        imu_spikes_t_s: spikes_t_s,
        imu_flat_runs: flat_runs,
        imu_flat_run_epochs: flat_run_epochs,
        inputs: Vec::new(),
        loop_free,
        nco_frequency,
    };
    outcome.choose_measurement(settings.measurement)?;
    Ok(outcome)
}

impl PipelineSettings {
    /// The loop-free estimate's settings that go with these (see
    /// [`crate::estimate_loop_free`]), for a log of interval `log_interval_s`:
    /// what the pipeline itself runs it with.
    pub fn loop_free(&self, log_interval_s: f64) -> crate::LoopFreeSettings {
        loop_free_settings(self, &self.estimate, log_interval_s)
    }
}

/// Widens `estimate`'s covariance by the spread of the estimates under the
/// loop's other forms (`other_forms`, each with the tracking error's fit of
/// it: its Δ(−2 ln L) and whether the statement allows it), made by
/// `estimate_under`, as [`crate::LoopForms::added_variance_hz_per_mps2_sq`]
/// does for the tracking error's: the larger of their spread weighted by the
/// data's odds and the largest of the forms the data cannot tell apart. A
/// form whose estimate fails is left out.
fn cover_other_forms(
    estimate: &mut crate::LoopFreeEstimate,
    other_forms: &[(LoopModel, crate::LoopFormFit)],
    estimate_under: impl Fn(&LoopModel) -> Result<crate::LoopFreeEstimate, crate::LoopFreeError> + Sync,
) {
    if other_forms.is_empty() {
        return;
    }
    let gamma = estimate.gamma_hz_per_mps2;
    let chosen = crate::LoopFormFit {
        form: String::new(),
        delta_m2lnl: 0.0,
        consistent_with_statement: true,
        gamma_hz_per_mps2: gamma,
        natural_frequency_hz: None,
        stated_natural_frequency_hz: None,
    };
    let others: Vec<crate::LoopFormFit> = other_forms
        .par_iter()
        .filter_map(|(model, fit)| {
            let under = estimate_under(model).ok()?;
            Some(crate::LoopFormFit { gamma_hz_per_mps2: under.gamma_hz_per_mps2, ..fit.clone() })
        })
        .collect();
    let fits: Vec<crate::LoopFormFit> = std::iter::once(chosen).chain(others).collect();
    let added = crate::joint::form_variance(&fits, gamma);
    for (i, v) in added.iter().enumerate() {
        estimate.covariance[i][i] += v;
    }
}

/// The loop-free estimate's settings from the calibration's: the loop's
/// update interval and what a row holds (stated, configured or chosen), the
/// same offset option, warm-up and channel count, and the screening's phase
/// limit (by default half the discriminator's unambiguous range).
fn loop_free_settings(
    settings: &PipelineSettings,
    estimate: &EstimateSettings,
    log_interval_s: f64,
) -> crate::LoopFreeSettings {
    let loop_interval_s = estimate.loop_at(log_interval_s).interval_s().unwrap_or(log_interval_s);
    let limit = settings.selection.screening.max_abs_phase_rad;
    crate::LoopFreeSettings {
        time_offset: settings.time_offset,
        // No model to start: the settings' own warm-up.
        warmup_s: settings.estimate.warmup_s,
        channels: settings.selection.max_channels.unwrap_or(0),
        max_abs_phase_rad: limit.filter(|v| *v > 0.0).unwrap_or(estimate.discriminator.unambiguous_range_rad() / 2.0),
        ..crate::LoopFreeSettings::new(loop_interval_s, estimate.logged_phase)
    }
}

/// The IMU time offset the session is prepared with, and the range it is
/// searched in when searched: a fixed offset must be finite, a range valid.
fn time_offset_start(time_offset: TimeOffset) -> Result<(f64, Option<f64>), CalibError> {
    match time_offset {
        TimeOffset::Fixed { imu_time_offset_s } => {
            if !imu_time_offset_s.is_finite() {
                let expected = "finite";
                return Err(CalibError::Setting { name: "imu_time_offset_s", value: imu_time_offset_s, expected });
            }
            Ok((imu_time_offset_s, None))
        }
        TimeOffset::Auto { max_abs_s } => {
            crate::settings::check_range("time_offset.max_abs_s", max_abs_s, true)?;
            Ok((0.0, Some(max_abs_s)))
        }
    }
}

/// A log with carriers is scaled to L1 (gsens_session): Γ̂ is at L1, and so
/// must be its ppb/g.
fn check_carrier(settings: &PipelineSettings, tracking: &TrackingLog) -> Result<(), CalibError> {
    let l1 = gsens_core::units::GPS_L1_HZ;
    if settings.estimate.carrier_hz != l1 && tracking.tracks().iter().any(|t| !t.carrier.is_default()) {
        return Err(CalibError::Setting {
            name: "carrier_hz",
            value: settings.estimate.carrier_hz,
            expected: "GPS L1, 1575420000 Hz, for a tracking log with carrier columns: every channel's phase \
                       error is scaled to L1 and Γ̂ is at L1 (leave carrier_hz out)",
        });
    }
    Ok(())
}

/// The warm-up the regressor models' start-up needs in `session`
/// ([`crate::models_warmup_s`] of the loop `estimate` runs, from the
/// session's first epoch), at most half the session: a session that begins
/// mid-shake keeps its other half, and the checks judge what is left of
/// the start-up.
fn session_models_warmup_s(session: &PreparedSession, imu: &ImuSeries, estimate: &EstimateSettings) -> f64 {
    let (Some(&t0), Some(&t1)) = (session.t_s.first(), session.t_s.last()) else { return 0.0 };
    let receiver_loop = estimate.loop_at(session.log_interval_s);
    let start_s = t0 + session.imu_time_offset_s;
    let w = crate::models_warmup_s(&receiver_loop, imu, start_s, session.log_interval_s, estimate.highpass_hz);
    w.min(0.5 * (t1 - t0))
}

/// The session's span against the settings: an offset searched beyond half
/// of it leaves no overlap to compare (and an absurd bound would size the
/// search's grid without limit); a warm-up must end inside it.
fn check_span(session: &PreparedSession, max_abs_s: Option<f64>, warmup_s: f64) -> Result<(), CalibError> {
    if let (Some(max), Some((t0, t1))) = (max_abs_s, session.t_s.first().zip(session.t_s.last()))
        && max > 0.5 * (t1 - t0)
    {
        return Err(CalibError::Setting {
            name: "time_offset.max_abs_s",
            value: max,
            expected: "at most half the log's span (beyond it no overlap of IMU and tracking is left to compare)",
        });
    }
    if let Some((t0, t1)) = session.t_s.first().zip(session.t_s.last())
        && warmup_s >= t1 - t0
    {
        return Err(CalibError::WarmupBeyondLog { warmup_s, log_s: t1 - t0 });
    }
    Ok(())
}

/// What the joint fit estimates with Γ, as the settings ask: the natural
/// frequency (and the damping), the offset within `max_abs_s`, the stated
/// loop within its tolerance (at least 0; infinite: only its shape known).
fn joint_spec(settings: &PipelineSettings, max_abs_s: Option<f64>) -> Result<JointSpec, CalibError> {
    let tolerance = settings.loop_tolerance.unwrap_or(DEFAULT_LOOP_TOLERANCE);
    if tolerance.is_nan() || tolerance < 0.0 {
        return Err(CalibError::Setting {
            name: "loop_tolerance",
            value: tolerance,
            expected: "at least 0 (a relative 1σ; infinite: only the loop's shape is known)",
        });
    }
    Ok(JointSpec {
        natural_frequency: settings.loop_identification != LoopIdentificationMode::Off,
        damping: settings.loop_identification == LoopIdentificationMode::NaturalFrequencyAndDamping,
        offset_max_abs_s: max_abs_s,
        loop_tolerance: tolerance.is_finite().then_some(tolerance),
    })
}

/// The estimate under `estimate`'s loop and offset, and the loop's response
/// check, at once: they need only the loop and the offset, not each other.
/// The response check tests the loop, not the estimator: it is measured
/// against the least-squares Γ̂ (the joint fit's, else the batch pass's; a
/// gradient observer's noisier Γ̂ would show as a loop mismatch). The joint
/// fit's nuisance parameters enter the calibration, and the channels' C/N0
/// (known here, not to the estimator) narrows the discriminator's range.
fn estimate_and_check_response(
    session: &PreparedSession,
    estimate: &EstimateSettings,
    joint: Option<JointFit>,
) -> Result<(Calibration, Result<crate::ResponseCheck, crate::ResponseCheckError>), CalibError> {
    let series = series_of(session);
    let response_check = || -> Result<Result<crate::ResponseCheck, crate::ResponseCheckError>, CalibError> {
        let gamma_ls = match &joint {
            Some(fit) => fit.gamma_hz_per_mps2,
            None => crate::search::batch_pass(&series, estimate)?.1.solve().gamma_hz_per_mps2,
        };
        let response_settings =
            crate::ResponseSettings { false_alarm: RESPONSE_CHECK_FALSE_ALARM, ..Default::default() };
        Ok(crate::measure_response_with(&series, estimate, &gamma_ls, &response_settings)
            .and_then(|c| if c.bins_tested == 0 { Err(crate::ResponseCheckError::NothingCoherent) } else { Ok(c) }))
    };
    crate::progress::stage("estimating Γ and checking the loop's response", None);
    let (calibration, loop_response) = rayon::join(|| calibrate(&series, estimate), response_check);
    let (mut calibration, loop_response) = (calibration?, loop_response?);
    if let Some(fit) = joint {
        calibration.include_nuisance(&fit);
    }
    let interval_s = calibration.loop_used.interval_s().unwrap_or(session.log_interval_s);
    calibration.discriminator_linear_range_rad =
        session_linear_range_rad(&session.channels, estimate.discriminator, interval_s);
    Ok((calibration, loop_response))
}

/// [`calibrate_logs`] on files: `imu.csv` and `tracking.csv`.
pub fn calibrate_files(tracking: &Path, imu: &Path, settings: &PipelineSettings) -> Result<Outcome, PipelineError> {
    // The two files are read at once, and the IMU log prepared while the
    // tracking log is still being read; a bad tracking log is still the
    // error reported first.
    crate::progress::stage("reading the logs", None);
    let (tracking_log, imu_series) = rayon::join(
        || gsens_io::read_tracking_file(tracking),
        || gsens_io::read_imu_file(imu).map(|series| PreparedImu::of_series(series, settings)),
    );
    let (tracking_log, prepared_imu) = (tracking_log?, imu_series?);
    let mut outcome = calibrate_prepared(Cow::Owned(tracking_log), prepared_imu, &imu.display().to_string(), settings)?;
    outcome.inputs = vec![input("imu", imu), input("tracking", tracking)];
    Ok(outcome)
}

fn input(role: &str, path: &Path) -> (String, String) {
    (role.to_string(), path.display().to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn estimate(gamma: [f64; 3]) -> crate::LoopFreeEstimate {
        crate::LoopFreeEstimate {
            gamma_hz_per_mps2: gamma,
            covariance: [[1e-8, 0.0, 0.0], [0.0, 1e-8, 0.0], [0.0, 0.0, 1e-8]],
            crlb_hz_per_mps2: [1e-4; 3],
            epochs: 1000,
            tracks: 4,
            segments: 2,
            imu_time_offset_s: 0.0,
            time_offset_searched: false,
            slipped_segments: 0,
            residual_variance_rad2: 1e-4,
            loop_interval_s: 0.02,
            logged_phase: gsens_core::LoggedPhase::Last,
            bookkeeping_chosen: false,
            excitation_rms: [1.0; 3],
            noise_ar_order: 3,
        }
    }

    fn form(delta_m2lnl: f64) -> crate::LoopFormFit {
        crate::LoopFormFit {
            form: String::new(),
            delta_m2lnl,
            consistent_with_statement: true,
            gamma_hz_per_mps2: [0.0; 3],
            natural_frequency_hz: None,
            stated_natural_frequency_hz: None,
        }
    }

    /// The other forms' estimates widen σ as the tracking error's forms do:
    /// per axis the larger of their spread weighted by the odds exp(−Δ/2)
    /// (the chosen form's included) and the largest of the forms within
    /// Δ ≤ 1; a form whose estimate fails is left out.
    #[test]
    fn other_forms_widen_sigma_by_their_spread() {
        let gamma = [0.09, 0.08, -0.08];
        let mut est = estimate(gamma);
        let loops = [
            gsens_core::LoopModel::kaplan(gsens_core::LoopSpec::PAPER, Some(0.001)),
            gsens_core::LoopModel::kaplan(gsens_core::LoopSpec::PAPER, Some(0.002)),
            gsens_core::LoopModel::kaplan(gsens_core::LoopSpec::PAPER, Some(0.005)),
        ];
        let others = [(loops[0], form(0.5)), (loops[1], form(8.0)), (loops[2], form(0.1))];
        cover_other_forms(&mut est, &others, |model| {
            let mut g = gamma;
            let t = model.interval_s().unwrap_or(0.0);
            if t == 0.001 {
                g[0] += 0.001;
            } else if t == 0.002 {
                g[1] += 0.002;
            } else {
                return Err(crate::LoopFreeError::Loop { why: "fails".into() });
            }
            Ok(estimate(g))
        });
        let total = 1.0 + (-0.25f64).exp() + (-4.0f64).exp();
        let want = [(1e-6f64).max((-0.25f64).exp() * 1e-6 / total), (-4.0f64).exp() * 4e-6 / total, 0.0];
        for i in 0..3 {
            let added = est.covariance[i][i] - 1e-8;
            assert!((added - want[i]).abs() < 1e-15, "axis {i}: {added} against {}", want[i]);
        }
    }
}
