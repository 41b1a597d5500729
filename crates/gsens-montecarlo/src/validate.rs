//! Compensation validated in the loop (what `gsens validate` tabulates): Γ̂
//! fed forward into the simulated receiver's NCO on sessions other than the
//! calibration's, at several loop bandwidths ([`gsens_sim::compensation_trial`]).

use gsens_calib::{DocumentError, EstimateSettings, PipelineSettings, ResultDocument, calibrate_logs};
use gsens_sim::compensation::CompensationSection;
use gsens_sim::compensation_trial::{Trial, run_trial};
use gsens_sim::scenario::Scenario;
use gsens_sim::session::SimError;
use gsens_sim::{LogsError, simulate_logs};

use crate::scenario_settings;
use crate::{MonteCarloError, render_gamma_hat, render_trial_row, render_validate_footer, render_validate_header};
use std::path::PathBuf;

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
    #[error("bn_hz {0}: must be positive")]
    Bandwidth(f64),
    /// A stated Γ̂ does not have three components.
    #[error("gamma takes three values, as gx,gy,gz (got {0})")]
    GammaComponents(usize),
    /// The result document giving Γ̂ could not be read.
    #[error(transparent)]
    Document(#[from] DocumentError),
    /// The table could not be written.
    #[error(transparent)]
    Output(#[from] std::io::Error),
    /// A trial's session could not be simulated.
    #[error("the trial at Bn {bn_hz} Hz: {source}")]
    Trial {
        /// The bandwidth \[Hz\].
        bn_hz: f64,
        /// Why.
        source: SimError,
    },
}

impl ValidateError {
    /// The setting the error is about (its message begins with the name).
    pub fn setting(&self) -> Option<&'static str> {
        match self {
            ValidateError::Bandwidth(_) => Some("bn_hz"),
            ValidateError::GammaComponents(_) => Some("gamma"),
            _ => None,
        }
    }
}

/// Where the Γ̂ a validation feeds forward comes from.
#[derive(Debug, Clone, PartialEq)]
pub enum GammaSource {
    /// Stated \[Hz/(m/s²)\], as gx,gy,gz.
    Stated(Vec<f64>),
    /// A result document's Γ̂ ([`ResultDocument::read_gamma_file`]).
    Document(PathBuf),
    /// Calibrated first on the scenario's own session ([`calibrate_scenario`]).
    Calibrate,
}

/// A validation as `gsens validate` runs it: Γ̂ from `gamma` (calibrating
/// on the session of `seed` when asked, saying so), then the trials of
/// [`validate`] at `bandwidths_hz` (default [`default_bandwidths_hz`]) with
/// `latency_s` on the session of `seed` + 1 — the same Γ̂ on fresh noise —
/// with the table ([`render_validate_header`], a row per trial as it is
/// done, [`render_validate_footer`]) given to `say` as it grows.
pub fn run_validation(
    scenario: &Scenario,
    seed: u64,
    gamma: &GammaSource,
    bandwidths_hz: Option<&[f64]>,
    latency_s: f64,
    mut say: impl FnMut(&str) -> std::io::Result<()>,
) -> Result<Vec<Trial>, ValidateError> {
    let gamma_hat = match gamma {
        GammaSource::Stated(g) => <[f64; 3]>::try_from(&g[..]).map_err(|_| ValidateError::GammaComponents(g.len()))?,
        GammaSource::Document(path) => ResultDocument::read_gamma_file(path)?.0,
        GammaSource::Calibrate => {
            say(&format!("calibrating on the scenario's session (seed {seed}) …\n"))?;
            let g = calibrate_scenario(scenario, seed)?;
            say(&render_gamma_hat(g))?;
            g
        }
    };
    let compensation = CompensationSection { gamma_hz_per_mps2: gamma_hat, latency_s };
    let bandwidths_hz = bandwidths_hz.map_or_else(|| default_bandwidths_hz(scenario), <[f64]>::to_vec);
    say(&render_validate_header(scenario, gamma_hat, latency_s, seed + 1))?;
    let trials = validate(scenario, seed + 1, &compensation, &bandwidths_hz, |bn_hz, trial| {
        say(&render_trial_row(bn_hz, trial)).map_err(ValidateError::from)
    })?;
    say(&render_validate_footer())?;
    Ok(trials)
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A stated Γ̂ of the wrong length and a bandwidth that is not positive
    /// are refused by the setting's name, after the table's header for the
    /// latter; nothing is calibrated for a stated Γ̂.
    #[test]
    fn stated_values_are_checked_by_the_settings_name() {
        let scenario = Scenario::default();
        let mut said = String::new();
        let two = GammaSource::Stated(vec![0.1, 0.2]);
        let e = run_validation(&scenario, 1, &two, None, 0.0, |t| {
            said.push_str(t);
            Ok(())
        })
        .unwrap_err();
        assert_eq!(
            (e.setting(), e.to_string().as_str()),
            (Some("gamma"), "gamma takes three values, as gx,gy,gz (got 2)")
        );
        assert!(said.is_empty());
        let three = GammaSource::Stated(vec![0.1, 0.2, 0.3]);
        let e = run_validation(&scenario, 1, &three, Some(&[-1.0]), 0.0, |t| {
            said.push_str(t);
            Ok(())
        })
        .unwrap_err();
        assert_eq!((e.setting(), e.to_string().as_str()), (Some("bn_hz"), "bn_hz -1: must be positive"));
        assert_eq!(said, render_validate_header(&scenario, [0.1, 0.2, 0.3], 0.0, 2));
    }
}
