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

impl TruthLoopUse {
    /// Which loop is modelled and why, for the user: the options', the same
    /// as the one `truth_json` states or not, or the one it states.
    pub fn note(&self, truth_json: &Path) -> String {
        let path = truth_json.display();
        let stated = |t: &TruthLoop| {
            let logged = match t.logged_phase {
                gsens_core::LoggedPhase::Last => "the last discriminator output",
                gsens_core::LoggedPhase::Mean => "the mean of the discriminator outputs",
            };
            format!("{}, logged: {logged}", t.receiver_loop)
        };
        match self {
            TruthLoopUse::NotStated => format!("receiver loop: from the options ({path} states none)"),
            TruthLoopUse::SettingsOwn { truth, same } => {
                let relation = if *same { "the same as" } else { "not" };
                format!("receiver loop: from the options, {relation} the one {path} states ({})", stated(truth))
            }
            TruthLoopUse::Taken { truth } => format!(
                "receiver loop: {} (from {path}, the loop that made the log; loop options such as bn_hz override it)",
                stated(truth)
            ),
        }
    }
}

/// Puts the loop of the simulated session's `truth_json` in `settings`
/// when they state none ([`PipelineSettings::loop_stated`]).
pub fn take_truth_loop(settings: &mut PipelineSettings, truth_json: &Path) -> Result<TruthLoopUse, LoadError> {
    let Some(truth) = gsens_sim::read_truth_loop(truth_json)? else { return Ok(TruthLoopUse::NotStated) };
    if settings.loop_stated {
        let same = settings.estimate.receiver_loop == truth.receiver_loop
            && settings.estimate.logged_phase == truth.logged_phase;
        if same {
            // The words are the simulated session's loop: its form, the simulator's own, is known.
            settings.loop_form = gsens_calib::LoopForm::Exact;
        }
        return Ok(TruthLoopUse::SettingsOwn { truth, same });
    }
    settings.estimate.receiver_loop = truth.receiver_loop;
    settings.estimate.logged_phase = truth.logged_phase;
    settings.loop_stated = true;
    // The simulator's own discrete loop made the log: its form is known.
    settings.loop_form = gsens_calib::LoopForm::Exact;
    Ok(TruthLoopUse::Taken { truth })
}

/// [`take_truth_loop`] of `truth_json` when one is given, with its note
/// ([`TruthLoopUse::note`]); `None` without one.
pub fn truth_loop_note(
    settings: &mut PipelineSettings,
    truth_json: Option<&Path>,
) -> Result<Option<String>, LoadError> {
    truth_json.map(|path| Ok(take_truth_loop(settings, path)?.note(path))).transpose()
}

impl crate::Route {
    /// [`truth_loop_note`] for a calibration by this route. Only a tracking
    /// log in gsens's format takes a simulated session's loop: a receiver's
    /// log comes with its receiver's loop ([`crate::Inputs::models_the_loop`]),
    /// and a carrier phase and Doppler log's loop is identified from the log
    /// (`None`: nothing taken, nothing to say).
    pub fn truth_loop_note(
        &self,
        settings: &mut PipelineSettings,
        truth_json: Option<&Path>,
    ) -> Result<Option<String>, LoadError> {
        let takes = matches!(self, crate::Route::Tracking(inputs) if !inputs.models_the_loop());
        truth_loop_note(settings, truth_json.filter(|_| takes))
    }
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A short simulated session's truth.json: taken when the settings state
    /// no loop, the settings' own otherwise, and the note says which.
    #[test]
    fn the_note_says_which_loop_is_modelled_and_why() {
        let dir = tempfile::tempdir().unwrap();
        let mut scenario = gsens_sim::scenario::Scenario::default();
        scenario.session.duration_s = Some(5.0);
        gsens_sim::simulate_to_dir(&scenario, 1, dir.path(), |_| {}).unwrap();
        let path = dir.path().join("truth.json");
        let shown = path.display();
        let mut settings = PipelineSettings::default();
        settings.loop_stated = false;
        let taken = take_truth_loop(&mut settings, &path).unwrap();
        let TruthLoopUse::Taken { truth } = &taken else { panic!("{taken:?}") };
        let stated = format!("{}, logged: the mean of the discriminator outputs", truth.receiver_loop);
        let note = taken.note(&path);
        assert!(
            note.starts_with(&format!("receiver loop: {stated} (from {shown}, the loop that made the log")),
            "{note}"
        );
        // Now stated, and by the same loop.
        let own = take_truth_loop(&mut settings, &path).unwrap();
        let expected = format!("receiver loop: from the options, the same as the one {shown} states ({stated})");
        assert_eq!(own.note(&path), expected);
        assert_eq!(
            TruthLoopUse::NotStated.note(&path),
            format!("receiver loop: from the options ({shown} states none)")
        );
        // The note of a truth.json given, nothing without one.
        assert_eq!(truth_loop_note(&mut settings, Some(&path)).unwrap(), Some(expected));
        assert_eq!(truth_loop_note(&mut settings, None).unwrap(), None);
    }
}
