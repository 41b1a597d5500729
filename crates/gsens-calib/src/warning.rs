//! The warnings of a result document: their codes as one enum (each with
//! whether it affects trust and where it ranks among the causes), and the
//! ordering of a document's warnings by cause.

use serde::{Deserialize, Serialize};

/// A condition the user should know about before trusting the estimate.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Warning {
    /// Stable identifier, e.g. `discriminator_range`.
    pub code: WarningCode,
    /// What was found, why it matters and what to do.
    pub message: String,
}

/// The stable identifier of a [`Warning`], serialized as its snake-case name
/// (`discriminator_range`). Every check documents its codes where it raises
/// them (`checks.rs`, `document.rs`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
#[non_exhaustive]
pub enum WarningCode {
    /// The IMU log's unit is not m/s² (g, or a scale off).
    ImuUnits,
    /// A log's time stamps are not seconds (milliseconds, microseconds).
    TimeUnits,
    /// The tracking log's phase is not in radians (degrees, cycles).
    PhaseUnits,
    /// The logged phase error has the opposite sign of the convention.
    PhaseSign,
    /// Channels follow the common signal by other carrier ratios than stated.
    CarrierGain,
    /// The predicted phase error leaves the discriminator's linear range.
    DiscriminatorRange,
    /// The tracking log's interval is too coarse for the loop.
    LogRate,
    /// The IMU's rate is too low for the shaking.
    ImuRate,
    /// The high-pass corner is too close to the shaking.
    Highpass,
    /// The IMU time offset search stopped at its limit.
    TimeOffsetAtLimit,
    /// No loop was stated and the data chose one.
    LoopNotStated,
    /// The stated loop is inconsistent with the data.
    LoopRejected,
    /// The loop's measured response disagrees with the model.
    LoopResponse,
    /// The data do not separate the IMU offset, the loop and Γ.
    LoopOffsetUnresolved,
    /// The loop's response could not be measured from the session.
    ResponseUnchecked,
    /// The loop-free estimate from the NCO's phase disagrees with the
    /// estimate through the loop model.
    LoopFreeDisagrees,
    /// No axis is observable.
    NothingObservable,
    /// An estimate came out not finite.
    NotFinite,
    /// Isolated IMU samples were replaced.
    ImuSpikes,
    /// Runs of identical IMU samples (a stuck sensor or logger).
    ImuStuck,
    /// Runs of identical IMU samples at the axis's extreme (clipped).
    ImuClipped,
    /// The receiver's loop identified from its NCO frequency lies at the
    /// narrow end of the range searched: H is extrapolated.
    LoopAtNarrowEnd,
    /// Rows of a carrier phase log were left out at receiver clock jumps.
    ClockJumps,
    /// A receiver's log had records its reader skipped (corrupt, cut off,
    /// event epochs).
    RecordsSkipped,
}

impl WarningCode {
    /// Every code, in the order of the enum.
    pub const ALL: [WarningCode; 24] = [
        WarningCode::ImuUnits,
        WarningCode::TimeUnits,
        WarningCode::PhaseUnits,
        WarningCode::PhaseSign,
        WarningCode::CarrierGain,
        WarningCode::DiscriminatorRange,
        WarningCode::LogRate,
        WarningCode::ImuRate,
        WarningCode::Highpass,
        WarningCode::TimeOffsetAtLimit,
        WarningCode::LoopNotStated,
        WarningCode::LoopRejected,
        WarningCode::LoopResponse,
        WarningCode::LoopOffsetUnresolved,
        WarningCode::ResponseUnchecked,
        WarningCode::LoopFreeDisagrees,
        WarningCode::NothingObservable,
        WarningCode::NotFinite,
        WarningCode::ImuSpikes,
        WarningCode::ImuStuck,
        WarningCode::ImuClipped,
        WarningCode::LoopAtNarrowEnd,
        WarningCode::ClockJumps,
        WarningCode::RecordsSkipped,
    ];

    /// The code as the document writes it.
    pub const fn as_str(self) -> &'static str {
        match self {
            WarningCode::ImuUnits => "imu_units",
            WarningCode::TimeUnits => "time_units",
            WarningCode::PhaseUnits => "phase_units",
            WarningCode::PhaseSign => "phase_sign",
            WarningCode::CarrierGain => "carrier_gain",
            WarningCode::DiscriminatorRange => "discriminator_range",
            WarningCode::LogRate => "log_rate",
            WarningCode::ImuRate => "imu_rate",
            WarningCode::Highpass => "highpass",
            WarningCode::TimeOffsetAtLimit => "time_offset_at_limit",
            WarningCode::LoopNotStated => "loop_not_stated",
            WarningCode::LoopRejected => "loop_rejected",
            WarningCode::LoopResponse => "loop_response",
            WarningCode::LoopOffsetUnresolved => "loop_offset_unresolved",
            WarningCode::ResponseUnchecked => "response_unchecked",
            WarningCode::LoopFreeDisagrees => "loop_free_disagrees",
            WarningCode::NothingObservable => "nothing_observable",
            WarningCode::NotFinite => "not_finite",
            WarningCode::ImuSpikes => "imu_spikes",
            WarningCode::ImuStuck => "imu_stuck",
            WarningCode::ImuClipped => "imu_clipped",
            WarningCode::LoopAtNarrowEnd => "loop_at_narrow_end",
            WarningCode::ClockJumps => "clock_jumps",
            WarningCode::RecordsSkipped => "records_skipped",
        }
    }

    /// Whether a warning of this code makes the estimate untrustworthy: every
    /// code but those reporting something gsens already corrected for
    /// (spikes replaced, stuck or clipped epochs left out, rows at clock
    /// jumps and records a reader skipped left out) or could not check.
    pub const fn affects_trust(self) -> bool {
        !matches!(
            self,
            WarningCode::ImuSpikes
                | WarningCode::ImuStuck
                | WarningCode::ImuClipped
                | WarningCode::ResponseUnchecked
                | WarningCode::ClockJumps
                | WarningCode::RecordsSkipped
        )
    }

    /// Whether the code speaks of the loop model alone: the estimate through
    /// the loop model rests on it, the loop-free estimate
    /// ([`crate::Measurement::InputPhase`]) does not, so under that
    /// measurement it does not make the estimate untrustworthy.
    pub const fn concerns_the_loop_model(self) -> bool {
        matches!(
            self,
            WarningCode::LoopNotStated
                | WarningCode::LoopRejected
                | WarningCode::LoopResponse
                | WarningCode::LoopOffsetUnresolved
                | WarningCode::ResponseUnchecked
                | WarningCode::Highpass
        )
    }

    /// Whether the code is about the logs' units and time base: a wrong unit
    /// or time stamp explains most other findings (a phase in degrees drives
    /// the predicted error past the discriminator's range, an IMU in g or
    /// stamped in milliseconds leaves the axes unobservable), so they come
    /// first and the shaking advice that would follow from them is not given.
    pub const fn is_unit(self) -> bool {
        matches!(self, WarningCode::TimeUnits | WarningCode::ImuUnits | WarningCode::PhaseUnits)
    }

    /// Where a warning comes in the document, by cause: the logs' units and
    /// time base (and what a wrong phase or IMU unit causes in the
    /// discriminator check), then how the logs were sampled and aligned, then
    /// the loop, then the shaking and the estimate, and last what was only
    /// reported.
    fn cause_rank(self, units_flagged: bool) -> u8 {
        use WarningCode::*;
        match self {
            TimeUnits | ImuUnits | PhaseUnits | PhaseSign | CarrierGain => 0,
            DiscriminatorRange if units_flagged => 1,
            LogRate | ImuRate | Highpass | TimeOffsetAtLimit => 2,
            ResponseUnchecked | LoopNotStated | LoopRejected | LoopResponse | LoopOffsetUnresolved
            | LoopFreeDisagrees | LoopAtNarrowEnd => 3,
            c if !c.affects_trust() => 5,
            _ => 4,
        }
    }
}

impl core::fmt::Display for WarningCode {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(self.as_str())
    }
}

impl PartialEq<&str> for WarningCode {
    fn eq(&self, other: &&str) -> bool {
        self.as_str() == *other
    }
}

impl PartialEq<WarningCode> for &str {
    fn eq(&self, other: &WarningCode) -> bool {
        *self == other.as_str()
    }
}

/// The advice of `discriminator_range` (its message ends with it).
pub(crate) const DISCRIMINATOR_ADVICE: &str = "shake more gently or the phase error wraps and biases Γ̂ low (or state \
                                               the receiver's discriminator, discriminator)";

/// The start of the advice that ends `loop_offset_unresolved`'s message.
pub(crate) const LOOP_OFFSET_ADVICE: &str = " State the IMU's latency (time_offset)";

/// Sorts `warnings` by cause ([`WarningCode::cause_rank`]), keeping the
/// order in which they were raised within a cause.
pub(crate) fn sort_by_cause(warnings: &mut [Warning]) {
    let units_flagged = warnings.iter().any(|w| w.code.is_unit());
    warnings.sort_by_key(|w| w.code.cause_rank(units_flagged));
}

/// Replaces the shaking advice of `w` (`discriminator_range`,
/// `nothing_observable`, `loop_offset_unresolved`), which would follow from
/// the wrong unit or time stamp of the warnings `unit_codes`, by a pointer
/// to them.
pub(crate) fn defer_shaking_advice(w: &mut Warning, unit_codes: &str) {
    match w.code {
        WarningCode::DiscriminatorRange => {
            if let Some(finding) = w.message.strip_suffix(DISCRIMINATOR_ADVICE) {
                w.message = format!(
                    "{finding}the unit found above ({unit_codes}) explains it: fix the unit and estimate again before \
                     changing the shaking"
                );
            }
        }
        WarningCode::NothingObservable => {
            w.message = format!(
                "no axis is observable, as the unit or time stamp found above ({unit_codes}) would make it: fix \
                 that and estimate again before changing the shaking"
            );
        }
        WarningCode::LoopOffsetUnresolved => {
            if let Some((finding, _)) = w.message.split_once(LOOP_OFFSET_ADVICE) {
                w.message = format!(
                    "{finding} The unit found above ({unit_codes}) may explain it: fix the unit and estimate again \
                     before changing the shaking"
                );
            }
        }
        _ => {}
    }
}

impl Warning {
    /// Whether this warning makes the estimate untrustworthy
    /// ([`WarningCode::affects_trust`]).
    pub fn affects_trust(&self) -> bool {
        self.code.affects_trust()
    }
}

/// The codes of the `warnings` that make an estimate from `measurement`
/// untrustworthy, in their order. Through the loop model: every code that
/// [`WarningCode::affects_trust`]. From the input phase (loop-free): not the
/// codes that [`WarningCode::concerns_the_loop_model`], and
/// `loop_free_disagrees` only while nothing else finds the loop model at
/// fault (`loop_not_stated`, `loop_rejected`, `loop_response`): a
/// disagreement that the loop's own checks explain is the loop model's, one
/// they do not explain may as well be the NCO phase's bookkeeping.
pub fn untrusted_codes(warnings: &[Warning], measurement: crate::Measurement) -> Vec<&'static str> {
    use WarningCode::*;
    let loop_at_fault = warnings.iter().any(|w| matches!(w.code, LoopNotStated | LoopRejected | LoopResponse));
    let counts = |code: WarningCode| match measurement {
        // The NCO frequency is seen through the loop model as the tracking error is.
        crate::Measurement::TrackingError | crate::Measurement::NcoFrequency => code.affects_trust(),
        crate::Measurement::InputPhase if code == LoopFreeDisagrees => !loop_at_fault,
        crate::Measurement::InputPhase => code.affects_trust() && !code.concerns_the_loop_model(),
    };
    warnings.iter().filter(|w| counts(w.code)).map(|w| w.code.as_str()).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn codes(raised: &[&str]) -> Vec<&'static str> {
        let code = |c: &str| *WarningCode::ALL.iter().find(|w| w.as_str() == c).unwrap();
        let mut w: Vec<Warning> = raised.iter().map(|&c| Warning { code: code(c), message: String::new() }).collect();
        sort_by_cause(&mut w);
        w.iter().map(|w| w.code.as_str()).collect()
    }

    /// Through the loop model every trust code counts; from the input phase
    /// the loop model's own codes do not, and a disagreement between the two
    /// estimates counts only while nothing else finds the loop at fault.
    #[test]
    fn what_counts_against_an_estimate_depends_on_its_measurement() {
        use crate::Measurement::{InputPhase, TrackingError};
        let w = |codes: &[WarningCode]| -> Vec<Warning> {
            codes.iter().map(|&code| Warning { code, message: String::new() }).collect()
        };
        let loop_only = w(&[WarningCode::LoopRejected, WarningCode::Highpass, WarningCode::ImuSpikes]);
        assert_eq!(untrusted_codes(&loop_only, TrackingError), ["loop_rejected", "highpass"]);
        assert!(untrusted_codes(&loop_only, InputPhase).is_empty());
        let explained = w(&[WarningCode::LoopResponse, WarningCode::LoopFreeDisagrees]);
        assert_eq!(untrusted_codes(&explained, TrackingError), ["loop_response", "loop_free_disagrees"]);
        assert!(untrusted_codes(&explained, InputPhase).is_empty());
        let unexplained = w(&[WarningCode::LoopFreeDisagrees, WarningCode::PhaseUnits]);
        assert_eq!(untrusted_codes(&unexplained, InputPhase), ["loop_free_disagrees", "phase_units"]);
    }

    /// The orders the checks raise them in for an IMU stamped in
    /// milliseconds and for both logs so, and a phase in degrees: the unit
    /// first, then the time base and the loop, then the shaking.
    #[test]
    fn warnings_come_by_cause() {
        assert_eq!(
            codes(&["loop_offset_unresolved", "time_units", "nothing_observable"]),
            ["time_units", "loop_offset_unresolved", "nothing_observable"]
        );
        assert_eq!(
            codes(&["time_offset_at_limit", "loop_rejected", "time_units", "imu_spikes", "time_units"]),
            ["time_units", "time_units", "time_offset_at_limit", "loop_rejected", "imu_spikes"]
        );
        // The discriminator's range follows from a wrong phase unit, and is a shaking matter without one.
        assert_eq!(
            codes(&["discriminator_range", "loop_rejected", "phase_units"]),
            ["phase_units", "discriminator_range", "loop_rejected"]
        );
        assert_eq!(codes(&["discriminator_range", "loop_rejected"]), ["loop_rejected", "discriminator_range"]);
    }

    /// Each code's name is its serde name, unique, and reads back.
    #[test]
    fn codes_serialize_as_their_names_and_read_back() {
        for c in WarningCode::ALL {
            let json = serde_json::to_string(&c).unwrap();
            assert_eq!(json, format!("\"{}\"", c.as_str()));
            assert_eq!(serde_json::from_str::<WarningCode>(&json).unwrap(), c);
            assert_eq!(WarningCode::ALL.iter().filter(|d| d.as_str() == c.as_str()).count(), 1);
        }
        let informational: Vec<_> =
            WarningCode::ALL.iter().filter(|c| !c.affects_trust()).map(|c| c.as_str()).collect();
        let want = ["response_unchecked", "imu_spikes", "imu_stuck", "imu_clipped", "clock_jumps", "records_skipped"];
        assert_eq!(informational, want);
    }

    /// Under a unit warning, `loop_offset_unresolved` keeps its finding and
    /// points at the unit instead of advising more shaking.
    #[test]
    fn a_unit_warning_defers_the_offset_warnings_shaking_advice() {
        let finding = "the data do not resolve the IMU time offset and the loop, and Γ̂ moves with them.";
        let mut w = Warning {
            code: WarningCode::LoopOffsetUnresolved,
            message: format!("{finding}{LOOP_OFFSET_ADVICE} if you know it, or shake harder and longer"),
        };
        defer_shaking_advice(&mut w, "time_units");
        assert!(w.message.starts_with(finding), "{}", w.message);
        assert!(w.message.contains("(time_units) may explain it"), "{}", w.message);
        assert!(!w.message.contains("shake"), "{}", w.message);
    }
}
