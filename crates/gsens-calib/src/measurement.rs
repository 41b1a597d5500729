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
    /// The NCO's frequency, through the loop model's closed loop H: its
    /// common mode is −H\[aᵀΓ\] ([`crate::estimate_nco_frequency`]).
    NcoFrequency,
}

impl Measurement {
    /// Its name in the result document.
    pub const fn name(self) -> &'static str {
        match self {
            Measurement::TrackingError => "tracking_error",
            Measurement::InputPhase => "input_phase",
            Measurement::NcoFrequency => "nco_frequency",
        }
    }

    /// What it is, in words, for the reports.
    pub const fn description(self) -> &'static str {
        match self {
            Measurement::TrackingError => "the tracking error φ through the loop model",
            Measurement::InputPhase => "the loop's input phase θ_NCO + φ (loop-free: no loop model)",
            Measurement::NcoFrequency => "the NCO frequency through the loop model's closed loop H",
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
    /// The NCO frequency through the loop model's closed loop: an error for
    /// a log without it. Never chosen by `auto`: its noise is the loop's
    /// command noise, sampled once per row.
    NcoFrequency,
}

impl MeasurementChoice {
    /// The measurement chosen, given the estimates of the log from the NCO's
    /// phase (`loop_free`) and frequency (`nco_frequency`), each `None` where
    /// the log does not hold it. `Err` for a measurement asked for by name
    /// without its estimate: why there is none.
    pub fn resolve(
        self,
        loop_free: Option<&Result<crate::LoopFreeEstimate, crate::LoopFreeError>>,
        nco_frequency: Option<&Result<crate::LoopFreeEstimate, crate::LoopFreeError>>,
    ) -> Result<Measurement, String> {
        let named = |estimate: Option<&Result<_, crate::LoopFreeError>>, measurement, column: &str| match estimate {
            Some(Ok(_)) => Ok(measurement),
            Some(Err(e)) => Err(e.to_string()),
            None => {
                Err(format!("the tracking log holds no column {column}, which the measurement {measurement} needs"))
            }
        };
        match (self, loop_free) {
            (MeasurementChoice::TrackingError, _) => Ok(Measurement::TrackingError),
            (MeasurementChoice::Auto, Some(Ok(_))) => Ok(Measurement::InputPhase),
            (MeasurementChoice::Auto, _) => Ok(Measurement::TrackingError),
            (MeasurementChoice::InputPhase, _) => named(loop_free, Measurement::InputPhase, "nco_phase_cycles"),
            (MeasurementChoice::NcoFrequency, _) => named(nco_frequency, Measurement::NcoFrequency, "nco_freq_hz"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn auto_takes_the_input_phase_only_where_the_loop_free_estimate_exists() {
        let err = || Err(crate::LoopFreeError::NoNcoPhase { source_name: "t.csv".into() });
        assert_eq!(MeasurementChoice::Auto.resolve(None, None), Ok(Measurement::TrackingError));
        assert_eq!(MeasurementChoice::Auto.resolve(Some(&err()), None), Ok(Measurement::TrackingError));
        assert_eq!(MeasurementChoice::TrackingError.resolve(Some(&err()), None), Ok(Measurement::TrackingError));
        assert!(MeasurementChoice::InputPhase.resolve(None, None).unwrap_err().contains("nco_phase_cycles"));
        assert!(MeasurementChoice::InputPhase.resolve(Some(&err()), None).unwrap_err().contains("t.csv"));
        assert!(MeasurementChoice::NcoFrequency.resolve(None, None).unwrap_err().contains("nco_freq_hz"));
        assert!(MeasurementChoice::NcoFrequency.resolve(None, Some(&err())).unwrap_err().contains("t.csv"));
        let names: Vec<String> = [Measurement::TrackingError, Measurement::InputPhase, Measurement::NcoFrequency]
            .map(|m| serde_json::to_string(&m).unwrap())
            .into();
        assert_eq!(names, ["\"tracking_error\"", "\"input_phase\"", "\"nco_frequency\""]);
        assert_eq!(Measurement::InputPhase.to_string(), "input_phase");
    }
}
