//! The receiver loop of a simulated session: its `truth.json` states the
//! loop that made its log, which an estimate of it should model when no
//! loop is stated otherwise.

use std::path::Path;

use gsens_calib::PipelineSettings;
use gsens_sim::{LoadError, TruthLoop};

/// What became of the loop a `truth.json` states.
#[derive(Debug, Clone)]
pub enum TruthLoopUse {
    /// `truth.json` states no loop: the settings' stands.
    NotStated,
    /// The settings state a loop of their own, which stands.
    SettingsOwn {
        /// The loop `truth.json` states.
        truth: TruthLoop,
        /// Whether the settings' loop (and logged phase) is that one.
        same: bool,
    },
    /// The settings stated none: `truth.json`'s is modelled.
    Taken {
        /// The loop `truth.json` states.
        truth: TruthLoop,
    },
}

/// Puts the loop of the simulated session's `truth_json` in `settings`
/// when they state none ([`PipelineSettings::loop_stated`]).
pub fn take_truth_loop(settings: &mut PipelineSettings, truth_json: &Path) -> Result<TruthLoopUse, LoadError> {
    let Some(truth) = gsens_sim::read_truth_loop(truth_json)? else { return Ok(TruthLoopUse::NotStated) };
    if settings.loop_stated {
        let same = settings.estimate.receiver_loop == truth.receiver_loop
            && settings.estimate.logged_phase == truth.logged_phase;
        return Ok(TruthLoopUse::SettingsOwn { truth, same });
    }
    settings.estimate.receiver_loop = truth.receiver_loop;
    settings.estimate.logged_phase = truth.logged_phase;
    settings.loop_stated = true;
    Ok(TruthLoopUse::Taken { truth })
}

/// The default settings with the loop of the simulated session's
/// `truth_json` (the default's stated loop when it states none).
pub fn settings_of_simulated_session(truth_json: &Path) -> Result<PipelineSettings, LoadError> {
    let mut settings = PipelineSettings::default();
    settings.loop_stated = false;
    if let TruthLoopUse::NotStated = take_truth_loop(&mut settings, truth_json)? {
        settings.loop_stated = true;
    }
    Ok(settings)
}
