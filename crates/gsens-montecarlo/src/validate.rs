//! Compensation validated in the loop (what `gsens validate` tabulates): Γ̂
//! fed forward into the simulated receiver's NCO on sessions other than the
//! calibration's, at several loop bandwidths ([`gsens_sim::compensation_trial`]).

use gsens_calib::{EstimateSettings, PipelineSettings, ResultDocument, calibrate_logs};
use gsens_sim::compensation::CompensationSection;
use gsens_sim::compensation_trial::{Trial, run_trial};
use gsens_sim::scenario::Scenario;
use gsens_sim::session::SimError;
use gsens_sim::{LogsError, simulate_logs};

use crate::{MonteCarloError, scenario_settings};

/// Why a validation could not run.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ValidateError {
    /// The calibration session could not be simulated.
    #[error(transparent)]
    Simulation(#[from] LogsError),
    /// The calibration failed.
    #[error(transparent)]
    Calibration(#[from] gsens_calib::PipelineError),
    /// The scenario's settings could not be stated.
    #[error(transparent)]
    Settings(#[from] MonteCarloError),
    /// The calibration is not trustworthy: there is no Γ̂ to validate.
    #[error("the calibration is not trustworthy, so there is no Γ̂ to validate")]
    Untrustworthy(Box<ResultDocument>),
    /// An axis is unobservable: nothing to feed forward on it.
    #[error("an axis is unobservable in the calibration: nothing to feed forward on it")]
    Unobservable,
    /// Γ̂ has a component that is not finite.
    #[error("Γ̂ {0:?}: every component must be finite")]
    NotFinite([f64; 3]),
    /// A bandwidth is not positive.
    #[error("Bn {0} Hz: must be positive")]
    Bandwidth(f64),
    /// A trial's session could not be simulated.
    #[error("the trial at Bn {bn_hz} Hz: {source}")]
    Trial {
        /// The bandwidth \[Hz\].
        bn_hz: f64,
        /// Why.
        source: SimError,
    },
}

/// Γ̂ \[Hz/(m/s²)\] from the scenario's own session at `seed`, calibrated with
/// the scenario's receiver stated ([`scenario_settings`]); an estimate that
/// is not trustworthy or leaves an axis unobservable is an error.
pub fn calibrate_scenario(scenario: &Scenario, seed: u64) -> Result<[f64; 3], ValidateError> {
    let logs = simulate_logs(scenario, seed)?;
    let mut settings = PipelineSettings::default();
    settings.estimate = scenario_settings(scenario, &EstimateSettings::default())?;
    let outcome = calibrate_logs(&logs.tracking, &logs.imu, "simulated imu", &settings)?;
    let doc = outcome.document(Some(logs.truth.sensitivity.gamma_hz_per_mps2));
    if !doc.trustworthy {
        return Err(ValidateError::Untrustworthy(Box::new(doc)));
    }
    let g = outcome.calibration.gamma_hz_per_mps2;
    g[0].zip(g[1]).zip(g[2]).map(|((x, y), z)| [x, y, z]).ok_or(ValidateError::Unobservable)
}

/// The bandwidths a validation runs at when none are given: the scenario's
/// loop and 2/3, 1/2 and 1/3 of it (narrower loops suffer more from g).
pub fn default_bandwidths_hz(scenario: &Scenario) -> Vec<f64> {
    let bn = scenario.tracking_loop.bn_hz;
    vec![bn, bn * 2.0 / 3.0, bn / 2.0, bn / 3.0]
}

/// The compensation trial ([`run_trial`]) of `compensation` at each of
/// `bandwidths_hz`, on the session of `seed` (not the calibration's: the
/// same Γ̂ on fresh noise); `each` sees every trial as it is done, and its
/// error (the caller's output failing) ends the validation.
pub fn validate<E: From<ValidateError>>(
    scenario: &Scenario,
    seed: u64,
    compensation: &CompensationSection,
    bandwidths_hz: &[f64],
    mut each: impl FnMut(f64, &Trial) -> Result<(), E>,
) -> Result<Vec<Trial>, E> {
    if compensation.gamma_hz_per_mps2.iter().any(|g| !g.is_finite()) {
        return Err(ValidateError::NotFinite(compensation.gamma_hz_per_mps2).into());
    }
    let mut trials = Vec::with_capacity(bandwidths_hz.len());
    for &bn_hz in bandwidths_hz {
        if !(bn_hz.is_finite() && bn_hz > 0.0) {
            return Err(ValidateError::Bandwidth(bn_hz).into());
        }
        let mut s = scenario.clone();
        s.tracking_loop.bn_hz = bn_hz;
        let trial = run_trial(&s, seed, compensation).map_err(|source| ValidateError::Trial { bn_hz, source })?;
        each(bn_hz, &trial)?;
        trials.push(trial);
    }
    Ok(trials)
}
