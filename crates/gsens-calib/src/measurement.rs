//! What an estimate regresses on the IMU's specific force, and which of the
//! measurements a log offers the result document's estimate is made from.

use serde::{Deserialize, Serialize};

/// What an estimate regresses on the integrated specific force, as the
/// result document names it (`measurement`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
#[non_exhaustive]
pub enum Measurement {
    /// The tracking error φ, through the loop model L: φ ≈ L\[aᵀΓ\] (the
    /// seed paper's observer).
    TrackingError,
    /// The phase the loop was fed, θ_in = θ_NCO + φ, whose common mode is the
    /// oscillator's phase 2π∫aᵀΓ dt: no loop model
    /// ([`crate::estimate_loop_free`]).
    InputPhase,
}

impl Measurement {
    /// Its name in the result document.
    pub const fn name(self) -> &'static str {
        match self {
            Measurement::TrackingError => "tracking_error",
            Measurement::InputPhase => "input_phase",
        }
    }

    /// What it is, in words, for the reports.
    pub const fn description(self) -> &'static str {
        match self {
            Measurement::TrackingError => "the tracking error φ through the loop model",
            Measurement::InputPhase => "the loop's input phase θ_NCO + φ (loop-free: no loop model)",
        }
    }
}

impl std::fmt::Display for Measurement {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Which measurement the result document's estimate is made from.
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[cfg_attr(feature = "clap", value(rename_all = "snake_case"))]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
#[non_exhaustive]
pub enum MeasurementChoice {
    /// The loop's input phase wherever the log holds the NCO's phase and
    /// the loop-free estimate could be made (it needs no loop model), the
    /// tracking error through the loop model otherwise; the other estimate
    /// is kept beside it as the cross-check.
    #[default]
    Auto,
    /// The tracking error through the loop model, the loop-free estimate
    /// (where the log allows) only as the cross-check.
    TrackingError,
    /// The loop's input phase: an error for a log without the NCO's phase.
    InputPhase,
}

impl MeasurementChoice {
    /// The measurement chosen, given the loop-free estimate of the log
    /// (`None`: the log holds no NCO phase). `Err` for
    /// [`MeasurementChoice::InputPhase`] without a loop-free estimate: why
    /// there is none.
    pub fn resolve(
        self,
        loop_free: Option<&Result<crate::LoopFreeEstimate, crate::LoopFreeError>>,
    ) -> Result<Measurement, String> {
        match (self, loop_free) {
            (MeasurementChoice::TrackingError, _) => Ok(Measurement::TrackingError),
            (MeasurementChoice::Auto, Some(Ok(_))) => Ok(Measurement::InputPhase),
            (MeasurementChoice::Auto, _) => Ok(Measurement::TrackingError),
            (MeasurementChoice::InputPhase, Some(Ok(_))) => Ok(Measurement::InputPhase),
            (MeasurementChoice::InputPhase, Some(Err(e))) => Err(e.to_string()),
            (MeasurementChoice::InputPhase, None) => {
                Err("the tracking log holds no NCO phase (column nco_phase_cycles), which the input phase needs".into())
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn auto_takes_the_input_phase_only_where_the_loop_free_estimate_exists() {
        let err = || Err(crate::LoopFreeError::NoNcoPhase { source_name: "t.csv".into() });
        assert_eq!(MeasurementChoice::Auto.resolve(None), Ok(Measurement::TrackingError));
        assert_eq!(MeasurementChoice::Auto.resolve(Some(&err())), Ok(Measurement::TrackingError));
        assert_eq!(MeasurementChoice::TrackingError.resolve(Some(&err())), Ok(Measurement::TrackingError));
        assert!(MeasurementChoice::InputPhase.resolve(None).unwrap_err().contains("nco_phase_cycles"));
        assert!(MeasurementChoice::InputPhase.resolve(Some(&err())).unwrap_err().contains("t.csv"));
        let names: Vec<String> =
            [Measurement::TrackingError, Measurement::InputPhase].map(|m| serde_json::to_string(&m).unwrap()).into();
        assert_eq!(names, ["\"tracking_error\"", "\"input_phase\""]);
        assert_eq!(Measurement::InputPhase.to_string(), "input_phase");
    }
}
