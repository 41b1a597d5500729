//! Either kind of log a front end may be given: a tracking error (a gsens
//! log, GNSS-SDR's, PocketSDR's; [`Inputs`]) or a carrier phase and Doppler
//! log (RINEX, UBX; [`ObservationInputs`]), and the estimate of either. One
//! rule picks the route ([`InputChoice::route`]), so `estimate`, `report`
//! and a live session's end treat both the same way.

use crate::{Calibrated, InputChoice, Inputs, InputsError, ObservationInputs, render_observation_summary};
use gsens_calib::{ObservationOutcome, Outcome, PipelineSettings, ResultDocument};
use gsens_io::TrackingLog;

/// The route of a calibration: tracking rows, or carrier phase and Doppler.
#[derive(Debug, Clone)]
pub enum Route {
    /// A log of the tracking error.
    Tracking(Box<Inputs>),
    /// A log of carrier phase and Doppler, with the loop identified.
    Observations(Box<ObservationInputs>),
}

/// The estimate of a [`Route`].
#[derive(Debug, Clone)]
pub enum Estimated {
    /// From tracking rows, with what the route converted and (when asked
    /// for) the tracking log.
    Tracking(Box<Calibrated>),
    /// From a carrier phase and Doppler log.
    Observations(Box<ObservationOutcome>),
}

impl InputChoice {
    /// The route the inputs name: a RINEX file or a UBX log
    /// ([`InputChoice::observations`]) where one is named, else the
    /// tracking route ([`InputChoice::inputs`]); options named by `name`.
    pub fn route(&self, name: impl Fn(&str) -> String) -> Result<Route, InputsError> {
        match self.observations(&name) {
            Some(observations) => observations.map(|inputs| Route::Observations(Box::new(inputs))),
            None => self.inputs(name).map(|inputs| Route::Tracking(Box::new(inputs))),
        }
    }
}

impl Route {
    /// Calibrates under `settings`, keeping a tracking route's log when
    /// `keep_tracking` asks for it ([`Inputs::calibrate_keeping_tracking`]).
    pub fn calibrate(self, settings: &PipelineSettings, keep_tracking: bool) -> Result<Estimated, InputsError> {
        Ok(match self {
            Route::Tracking(inputs) if keep_tracking => {
                Estimated::Tracking(Box::new(inputs.calibrate_keeping_tracking(settings)?))
            }
            Route::Tracking(inputs) => Estimated::Tracking(Box::new(inputs.calibrate(settings)?)),
            Route::Observations(inputs) => Estimated::Observations(Box::new(inputs.calibrate(settings)?)),
        })
    }
}

impl Estimated {
    /// What the route did besides the estimate, as lines of text: what
    /// became of each track of a receiver's log and which receiver loop was
    /// modelled ([`Calibrated::track_summary`], [`Calibrated::loop_note`]),
    /// or a carrier phase log's tracks and identified loop
    /// ([`render_observation_summary`]); empty when there is nothing to say.
    pub fn notes(&self) -> String {
        match self {
            Estimated::Tracking(c) => {
                let loop_note = c.loop_note().map(|note| note + "\n");
                c.track_summary().unwrap_or_default() + &loop_note.unwrap_or_default()
            }
            Estimated::Observations(o) => render_observation_summary(o),
        }
    }

    /// The result document, with the true Γ of a simulated session when given.
    pub fn document(&self, truth: Option<[f64; 3]>) -> ResultDocument {
        match self {
            Estimated::Tracking(c) => c.outcome.document(truth),
            Estimated::Observations(o) => o.document(truth),
        }
    }

    /// The estimate from tracking rows with the log it was made from, when
    /// it is one and the log was kept.
    pub fn tracking(&self) -> Option<(&Outcome, &TrackingLog)> {
        match self {
            Estimated::Tracking(c) => c.tracking.as_ref().map(|log| (&c.outcome, log)),
            Estimated::Observations(_) => None,
        }
    }

    /// The inputs named in the result document, as role → path (a caller
    /// adds its own, as `truth`).
    pub fn inputs_mut(&mut self) -> &mut Vec<(String, String)> {
        match self {
            Estimated::Tracking(c) => &mut c.outcome.inputs,
            Estimated::Observations(o) => &mut o.inputs,
        }
    }
}
