//! The calibration from a carrier phase and Doppler log (RINEX, UBX): the
//! NCO's frequency on common epochs ([`crate::observation_rows`]), Γ with
//! the receiver's loop identified from it
//! ([`crate::estimate_nco_frequency_identified_from`]), beside it the
//! estimate with H = 1 ([`crate::estimate_nco_frequency_unity`]), and the
//! result document every output serializes.
//!
//! The document's estimate is the identified loop's, `measurement`
//! `nco_frequency`; its `identified_loop` block says which loop, how well
//! the session resolved it, |H| at each axis's shaking frequency and what
//! H = 1 would have given. Its compensation figures are of the receiver's
//! carrier phase: the tracks' common mode integrated, 2π·Σ f·Δt, before and
//! after Γ̂'s part is removed. The predicted peak phase error is the
//! identified loop's tracking error |φ_aᵀΓ̂|, checked against the
//! discriminator's linear range at the weakest track's C/N0.

use crate::document::{CrossEstimate, PipelineSummary, SourceConversion};
use crate::loop_free::{LoopFreeError, LoopFreeEstimate, median_step};
use crate::nco_loop::{CompensatedCarrierPhase, identification_shapes, identified_figures};
use crate::observation_rows::{ObservationRecord, ObservationRows, observation_rows};
use crate::verdict::weakest_linear_range_rad;
use crate::{
    Calibration, IdentifiedLoop, IdentifiedNcoEstimate, LoopResolution, Measurement, PipelineError, PipelineSettings,
    ResultDocument, Warning, WarningCode, estimate_nco_frequency_identified_from, estimate_nco_frequency_unity,
};
use gsens_core::{Complex, LoopModel};
use gsens_io::{ImuSeries, ObservationLog};
use serde::{Deserialize, Serialize};

/// The calibration of a carrier phase and Doppler log.
#[derive(Debug, Clone)]
#[non_exhaustive]
pub struct ObservationOutcome {
    /// The rows the estimate was made from, and every track's fate.
    pub rows: ObservationRows,
    /// The estimate with the loop identified.
    pub identified: IdentifiedNcoEstimate,
    /// The estimate with H = 1 in the shaking's band (or why none).
    pub unity: Result<LoopFreeEstimate, LoopFreeError>,
    /// The document's estimate: `identified`'s, with the IMU's systematic
    /// σ, the verdicts per axis and the compensation figures.
    pub calibration: Calibration,
    /// The carrier phase before and after compensation, whose RMS the
    /// compensation figures give.
    pub carrier_phase: CompensatedCarrierPhase,
    /// The settings it ran with.
    pub settings: PipelineSettings,
    /// The log's format (`RINEX 3.04`, `UBX`).
    pub format: String,
    /// Records the log's reader skipped, by reason: (reason, count).
    pub skipped: Vec<(String, usize)>,
    /// Receiver clock jumps the log reports.
    pub clock_events: usize,
    /// The inputs as role → path (callers fill it).
    pub inputs: Vec<(String, String)>,
}

/// The identified loop as the result document gives it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[non_exhaustive]
pub struct LoopIdentification {
    /// The observable the rows were made of: `carrier_phase` or `doppler`.
    pub record: ObservationRecord,
    /// The loop.
    #[serde(flatten)]
    pub identified: IdentifiedLoop,
    /// |H| of the identified loop at each axis's dominant shaking frequency
    /// (`null` for an axis not shaken).
    pub h_magnitude_at_shaking: [Option<f64>; 3],
    /// The largest |1 − |H|| over the shaken axes: how far from H = 1 the
    /// session's shaking saw the loop.
    pub h_unity_error: Option<f64>,
    /// The estimate with H = 1 in the shaking's band, as a receiver whose
    /// carrier phase is corrected by its discriminator (or whose loop is
    /// wide) would give it; `null` where it could not be made.
    pub h_unity_estimate: Option<CrossEstimate>,
}

/// Estimates Γ from `log` and the IMU's `imu` (on the log's time: GPS
/// seconds of the week of its first epoch), from the rows of `record`,
/// with the loop identified (module documentation). A loop the settings
/// state narrows the identification to its order and update interval; its
/// bandwidth is still searched. The settings' channel limit does not apply:
/// every track with rows enters.
pub fn calibrate_observations(
    log: &ObservationLog,
    imu: &ImuSeries,
    settings: &PipelineSettings,
    record: ObservationRecord,
) -> Result<ObservationOutcome, PipelineError> {
    settings.estimate.validate()?;
    let source_name = log.source_name.clone();
    let why = |e: &dyn std::fmt::Display| PipelineError::Observations {
        source_name: source_name.clone(),
        why: e.to_string(),
    };
    let rows = observation_rows(log, record)?;
    // The IMU must cover the log's epochs on the same time base (GPS seconds of the week).
    let (Some(&t0), Some(&t1)) = (rows.rows.epoch_t_s.first(), rows.rows.epoch_t_s.last()) else {
        return Err(why(&"no epoch"));
    };
    let (i0, i1) = (imu.t_s.first().copied().unwrap_or(f64::NAN), imu.t_s.last().copied().unwrap_or(f64::NAN));
    let overlap_s = i1.min(t1) - i0.max(t0);
    if overlap_s.is_nan() || overlap_s <= 0.5 * (t1 - t0) {
        return Err(why(&format!(
            "the IMU log covers t = {i0:.3} … {i1:.3} s and the observations t = {t0:.3} … {t1:.3} s \
             (GPS seconds of the week of the first epoch): they overlap by less than half the log; give the \
             IMU's t_s in GPS seconds of the week (for a UBX log's own IMU: the rule its sensor time tags follow)"
        )));
    }
    let log_interval_s = median_step(&rows.rows.epoch_t_s);
    let mut free = settings.loop_free(log_interval_s);
    free.channels = 0;
    let quantity = rows.record.quantity();
    // A loop stated in words may be any receiver's form of those words: the identification compares them.
    let shapes: Vec<LoopModel> = if settings.loop_stated {
        settings.loop_form.forms_of(&settings.estimate.loop_at(log_interval_s))?
    } else {
        identification_shapes(log_interval_s)
    };
    crate::progress::stage("identifying the receiver's loop from its NCO frequency", None);
    let identified =
        estimate_nco_frequency_identified_from(&rows.rows, imu, &free, &shapes, quantity).map_err(|e| why(&e))?;
    let unity = match &identified.unity {
        Some(fit) => Ok(fit.clone()),
        None => estimate_nco_frequency_unity(&rows.rows, imu, &free, quantity),
    };
    let model = identified.identified.model.ok_or_else(|| why(&"the identification kept no loop"))?;
    let (figures, carrier_phase) =
        identified_figures(&rows.rows, imu, &free, &model, &identified.estimate, quantity).map_err(|e| why(&e))?;
    let estimate_settings = settings.estimate.with_loop(model);
    let loop_interval_s = identified.identified.loop_interval_s;
    let mut calibration = Calibration::of_direct(
        estimate_settings,
        &rows.rows.epoch_t_s,
        imu,
        &identified.estimate,
        figures,
        (log_interval_s / loop_interval_s).round() as u32,
    );
    let with_rows = rows.tracks.iter().filter(|t| t.rows > 0);
    calibration.discriminator_linear_range_rad = weakest_linear_range_rad(
        with_rows.map(|t| (t.mean_cn0_dbhz, t.carrier_hz)),
        settings.estimate.discriminator,
        loop_interval_s,
    );
    Ok(ObservationOutcome {
        rows,
        identified,
        unity,
        calibration,
        carrier_phase,
        settings: settings.clone(),
        format: log.format.clone(),
        skipped: log.skipped.iter().map(|s| (s.reason.clone(), s.count)).collect(),
        clock_events: log.clock_events.len(),
        inputs: Vec::new(),
    })
}

impl ObservationOutcome {
    /// The identified loop, |H| at the shaking and the H = 1 estimate.
    pub fn loop_identification(&self) -> LoopIdentification {
        let model = self.calibration.loop_used;
        // The NCO follows Δf through H = 1 − s·(−L)/(2π) = 1 + j·f·L(f), L = φ/Δf the loop's
        // tracking-error response (continuous: L = −2π/(s + F), H = F/(s + F)).
        let h_at = |f: f64| (Complex::new(1.0, 0.0) + Complex::new(0.0, f) * model.response(f)).norm();
        let h_magnitude_at_shaking = self
            .calibration
            .axes
            .each_ref()
            .map(|a| a.shaking_frequency_hz.filter(|_| a.observable).map(h_at).filter(|h| h.is_finite()));
        let h_unity_error = h_magnitude_at_shaking.iter().flatten().map(|h| (1.0 - h).abs()).reduce(f64::max);
        let h_unity_estimate = self.unity.as_ref().ok().map(|u| {
            let s = u.sigma_hz_per_mps2();
            CrossEstimate {
                gamma_hz_per_mps2: u.gamma_hz_per_mps2.map(Some),
                sigma_hz_per_mps2: s.map(|s| Some(s).filter(|s| s.is_finite())),
            }
        });
        LoopIdentification {
            record: self.rows.record,
            identified: self.identified.identified.clone(),
            h_magnitude_at_shaking,
            h_unity_error,
            h_unity_estimate,
        }
    }

    /// The result document (with the true Γ when known).
    pub fn document(&self, truth_gamma_hz_per_mps2: Option<[f64; 3]>) -> ResultDocument {
        let pipeline = PipelineSummary {
            time_offset: self.settings.time_offset,
            loop_identification: self.settings.loop_identification,
        };
        let inputs: Vec<(&str, &str)> = self.inputs.iter().map(|(k, v)| (k.as_str(), v.as_str())).collect();
        let mut doc = ResultDocument::from_parts(
            self.calibration.clone(),
            Vec::new(),
            self.settings.selection.clone(),
            pipeline,
            &inputs,
            truth_gamma_hz_per_mps2,
        );
        doc.measurement = Measurement::NcoFrequency;
        doc.source = Some(SourceConversion {
            receiver: self.format.clone(),
            conversion: serde_json::json!({
                "record": self.rows.record,
                "epochs": self.rows.rows.epoch_t_s.len(),
                "clock_jump_epochs": self.rows.clock_jump_epochs,
                "clock_events": self.clock_events,
                "skipped": self.skipped.iter().map(|(r, n)| serde_json::json!({"reason": r, "count": n})).collect::<Vec<_>>(),
            }),
            tracks: self.rows.tracks.iter().map(|t| serde_json::to_value(t).unwrap_or_default()).collect(),
        });
        let identification = self.loop_identification();
        doc.warnings.extend(self.warnings(&identification));
        doc.identified_loop = Some(identification);
        doc.judge();
        doc
    }

    /// The warnings of the identification and the log.
    fn warnings(&self, id: &LoopIdentification) -> Vec<Warning> {
        let mut w = Vec::new();
        if id.identified.resolution == LoopResolution::Narrow {
            w.push(Warning {
                code: WarningCode::LoopAtNarrowEnd,
                message: format!(
                    "the receiver's loop fits best at the narrow end of the bandwidths searched (Bn ≤ {:.2} Hz of \
                     {:.0}–{:.0} Hz): its H, and Γ̂ with it, is extrapolated; check the log's rate and the \
                     receiver's loop settings",
                    id.identified.bn_hz,
                    crate::IDENTIFY_BN_RANGE_HZ[0],
                    crate::IDENTIFY_BN_RANGE_HZ[1]
                ),
            });
        }
        if self.rows.clock_jump_epochs > 0 {
            w.push(Warning {
                code: WarningCode::ClockJumps,
                message: format!(
                    "{} epoch(s) of carrier phase left out at receiver clock jumps ({} reported by the log)",
                    self.rows.clock_jump_epochs, self.clock_events
                ),
            });
        }
        let skipped: usize = self.skipped.iter().map(|(_, n)| n).sum();
        if skipped > 0 {
            let reasons: Vec<String> = self.skipped.iter().map(|(r, n)| format!("{n} × {r}")).collect();
            w.push(Warning {
                code: WarningCode::RecordsSkipped,
                message: format!("the reader skipped {skipped} record(s) of the log: {}", reasons.join("; ")),
            });
        }
        w
    }
}
