//! The one result document: what `gsens estimate --json`, `report.json`, the
//! text report and the bindings all serialize (keys in
//! `docs/conventions.md#result-document`).

use crate::pipeline::{LoopIdentificationMode, Outcome, TimeOffset};
use crate::warning::{
    DISCRIMINATOR_ADVICE, LOOP_OFFSET_ADVICE, Warning, WarningCode, defer_shaking_advice, sort_by_cause,
    untrusted_codes,
};
use crate::{Calibration, Measurement};
use gsens_core::LoopModel;
use gsens_core::units::Decimal;
use gsens_session::{ChannelRanking, ChannelSummary, SelectionConfig, SignalSummary};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// The loop a calibration modelled and what it implies for the shaking.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[non_exhaustive]
pub struct LoopSummary {
    /// The loop in words.
    pub description: String,
    /// Loop order.
    pub order: u8,
    /// Natural frequency ωn/2π \[Hz\].
    pub natural_frequency_hz: Option<f64>,
    /// Frequency of the peak of |L| \[Hz\].
    pub peak_hz: Option<f64>,
    /// |L| at the peak \[rad/Hz\].
    pub peak_rad_per_hz: Option<f64>,
    /// The shaking period that excites the loop most, 1/peak_hz \[s\].
    pub recommended_period_s: Option<f64>,
    /// Where |L| is above peak/√2 \[Hz\].
    pub half_power_band_hz: Option<[f64; 2]>,
}

impl LoopSummary {
    /// The summary of `model` (peak and band `None` for a loop without one).
    pub fn of(model: &LoopModel) -> Self {
        let peak = model.peak().ok();
        LoopSummary {
            description: model.to_string(),
            order: model.order(),
            natural_frequency_hz: model.natural_frequency_hz(),
            peak_hz: peak.map(|p| p.f_hz),
            peak_rad_per_hz: peak.map(|p| p.rad_per_hz),
            recommended_period_s: peak.map(|p| p.period_s()),
            half_power_band_hz: model.half_power_band_hz().ok(),
        }
    }
}

/// The largest step of the joint fit's nuisance parameters, at one σ, that its
/// linearized covariance holds for \[rad\]. The fit linearizes the model in the
/// IMU time offset τ and the loop's scale ln s; a 1σ error of τ turns the
/// shaking's phase by x = 2π·f·σ_τ (f its frequency), and e^{jx} = 1 + jx −
/// x²/2 + …: the term the linearization drops is x/2 of the one it keeps (the
/// loop's scale likewise, x = σ_ln s, as a relative change of the response
/// near its peak). At x = 0.2 that is 10 %; beyond it Γ̂ moves with the
/// nuisance errors in ways σ does not describe.
pub(crate) const JOINT_LINEAR_LIMIT_RAD: f64 = 0.2;

/// The linearity of the joint fit: x = max(2π·f·σ_τ, σ_ln s) (see
/// [`JOINT_LINEAR_LIMIT_RAD`]), f the highest dominant shaking frequency of
/// the observable axes; with it the offset's and the scale's parts. σ_τ and
/// σ_ln s are those of the fit the result rests on: a loop combined with its
/// tolerance rests on the free fit's covariance (the data alone), so its
/// linearization must hold; a loop held exact rests on the held fit (σ_τ
/// alone). `None` when the fit estimated neither or no observable axis has a
/// frequency.
pub(crate) fn joint_nonlinearity(c: &Calibration) -> Option<(f64, Option<f64>, Option<f64>)> {
    let j = c.joint_fit.as_ref()?;
    let f_hz = c
        .axes
        .iter()
        .zip(&c.observable)
        .filter(|(_, o)| **o)
        .filter_map(|(a, _)| a.shaking_frequency_hz)
        .reduce(f64::max)?;
    let offset = j
        .linearization_sigma_imu_time_offset_s
        .or(j.sigma_imu_time_offset_s)
        .map(|s| core::f64::consts::TAU * f_hz * s);
    // The loop's scale in the fit the result rests on: the data's own (free)
    // fit when it was combined with a tolerance, none when held exact.
    let scale = match j.loop_tolerance {
        Some(t) if t == 0.0 && !j.stated_loop_rejected => None,
        _ => j.sigma_natural_frequency_hz.zip(j.natural_frequency_hz).map(|(s, f)| s / f),
    };
    let x = offset.into_iter().chain(scale).reduce(f64::max)?;
    Some((x, offset, scale))
}

/// The two-rate protocol for `loop_used`, in words: each axis half the time
/// at each of [`gsens_core::LoopPeak::two_rate_periods_s`] (empty for a loop
/// without a peak).
pub fn two_rate_advice(loop_used: &LoopModel) -> String {
    match loop_used.peak() {
        Ok(peak) => {
            let [slow, fast] = peak.two_rate_periods_s();
            format!(
                "shake each axis half the time at about {slow:.1} s and half at about {fast:.1} s per cycle ({} and {} \
                 times the loop's peak frequency, {:.2} Hz)",
                gsens_core::TWO_RATE_FACTORS[0],
                gsens_core::TWO_RATE_FACTORS[1],
                peak.f_hz
            )
        }
        Err(_) => "shake each axis at two rates, one slower and one faster than the loop's peak".to_string(),
    }
}

/// What a receiver's adapter did to turn its files into the logs: which
/// receiver, the conversion's settings and every track's fate, each as the
/// adapter serializes them (the calibration does not read them; they are kept
/// for the reader of the document).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SourceConversion {
    /// The receiver whose files were converted (`gnss-sdr`, `pocketsdr`).
    pub receiver: String,
    /// The conversion settings (thresholds, the tracking configuration).
    pub conversion: serde_json::Value,
    /// Every track found and what became of it.
    pub tracks: Vec<serde_json::Value>,
}

/// How the session-level settings were applied.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PipelineSummary {
    /// The IMU time offset setting.
    pub time_offset: TimeOffset,
    /// Loop identification setting.
    pub loop_identification: LoopIdentificationMode,
}

/// Who wrote a report, when and with which figures (`report.json` only).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ReportInfo {
    /// When the report was generated, UTC.
    pub generated_utc: String,
    /// The producing tool and version.
    pub tool: String,
    /// Heading of the report.
    pub title: String,
    /// The figures shown, as (id, title).
    pub figures: Vec<FigureInfo>,
}

/// One figure of a report.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FigureInfo {
    /// Identifier and file stem.
    pub id: String,
    /// Heading.
    pub title: String,
}

/// The result of a calibration, as every output serializes it: the estimate
/// ([`Calibration`], its keys at the top level), the loop, the channels and
/// their screening, the warnings, the inputs and the tool.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[non_exhaustive]
pub struct ResultDocument {
    /// The producing library and version, e.g. `gsens 0.1.0`.
    pub tool: String,
    /// What the estimate is made from: `input_phase` (the loop-free
    /// estimate, wherever the log holds the NCO's phase),
    /// `tracking_error` (through the loop model) or `nco_frequency` (the
    /// NCO's frequency through the loop model's closed loop, on request).
    #[serde(default = "tracking_error")]
    pub measurement: Measurement,
    /// The estimate (flattened: its keys are the document's).
    #[serde(flatten)]
    pub calibration: Calibration,
    /// Whether the estimate can be trusted within its σ: no warning but the
    /// codes that do not [`WarningCode::affects_trust`], and at least one axis observable with a
    /// finite Γ̂ and σ. `gsens` exits with status 3 when it is false.
    pub trustworthy: bool,
    /// The loop modelled, its peak and band.
    #[serde(rename = "loop")]
    pub loop_summary: LoopSummary,
    /// Warnings: conditions under which the estimate may not hold.
    pub warnings: Vec<Warning>,
    /// The loop's response measured from the session against the model
    /// ([`crate::measure_response`]); `null` where it could not be measured.
    pub loop_response: Option<crate::ResponseCheck>,
    /// Every track of the log and what became of it.
    pub channels: Vec<ChannelSummary>,
    /// The signals of the log's tracks and how many of each took part in the
    /// average (their phases scaled by f_L1/f_c; Γ̂ is at L1). Empty for a
    /// document built [`from_parts`](Self::from_parts).
    pub signals: Vec<SignalSummary>,
    /// The channel selection used.
    pub selection: SelectionConfig,
    /// How the tracks were ranked for the selection's `max_channels`: `cn0`
    /// (mean C/N0) or `noise` (C/N0 did not vary between them); `null` for a
    /// document built [`from_parts`](Self::from_parts).
    pub channel_ranking: Option<ChannelRanking>,
    /// The session-level settings.
    pub pipeline: PipelineSummary,
    /// The inputs as role → path.
    pub inputs: BTreeMap<String, String>,
    /// The true Γ \[Hz/(m/s²)\] when known (simulated sessions).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub truth_gamma_hz_per_mps2: Option<[f64; 3]>,
    /// What a receiver's adapter converted, for sessions from a receiver's
    /// own files (GNSS-SDR dumps, a PocketSDR log).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub source: Option<SourceConversion>,
    /// Report metadata (`report.json`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub report: Option<ReportInfo>,
    /// The loop-free estimate from the NCO's phase beside this one, for logs
    /// that hold it (`nco_phase_cycles`; PocketSDR's `adr`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub loop_free: Option<crate::LoopFreeCheck>,
    /// The estimate from the NCO's frequency through the loop model's closed
    /// loop beside this one, for logs that hold it (`nco_freq_hz`), against
    /// the estimate through the tracking error.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub nco_frequency: Option<crate::LoopFreeCheck>,
    /// The estimate through the loop model, where the document's estimate
    /// is made from another measurement: the cross-check's other side.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tracking_error: Option<CrossEstimate>,
    /// The receiver's loop identified from its NCO frequency, for logs of
    /// carrier phase and Doppler (RINEX, UBX).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub identified_loop: Option<crate::LoopIdentification>,
}

/// Another measurement's estimate beside the document's: Γ̂ and its total
/// 1σ per axis (`null` where unobservable).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[non_exhaustive]
pub struct CrossEstimate {
    /// Γ̂ \[Hz/(m/s²)\].
    pub gamma_hz_per_mps2: [Option<f64>; 3],
    /// 1σ \[Hz/(m/s²)\].
    pub sigma_hz_per_mps2: [Option<f64>; 3],
}

impl CrossEstimate {
    fn of(c: &Calibration) -> Self {
        CrossEstimate { gamma_hz_per_mps2: c.gamma_hz_per_mps2, sigma_hz_per_mps2: c.sigma_hz_per_mps2 }
    }
}

/// A document read without `measurement` (written before it existed) was
/// made from the tracking error.
fn tracking_error() -> Measurement {
    Measurement::TrackingError
}

/// This library's name and version.
pub fn tool_version() -> String {
    format!("gsens {}", env!("CARGO_PKG_VERSION"))
}

impl ResultDocument {
    /// The document of `outcome`.
    pub fn new(outcome: &Outcome, inputs: &[(&str, &str)], truth_gamma_hz_per_mps2: Option<[f64; 3]>) -> Self {
        let pipeline = PipelineSummary {
            time_offset: outcome.settings.time_offset,
            loop_identification: outcome.settings.loop_identification,
        };
        let mut doc = Self::from_parts(
            outcome.calibration.clone(),
            outcome.session.channels.clone(),
            outcome.session.selection.clone(),
            pipeline,
            inputs,
            truth_gamma_hz_per_mps2,
        );
        doc.source = outcome.source.clone();
        doc.signals = outcome.session.signals.clone();
        doc.channel_ranking = Some(outcome.session.channel_ranking);
        doc.measurement = outcome.measurement;
        doc.tracking_error = outcome.tracking_error.as_ref().map(CrossEstimate::of);
        if let Some(loop_free) = &outcome.loop_free {
            let check = crate::LoopFreeCheck::new(outcome.closed_loop(), loop_free);
            doc.warnings.extend(check.warning());
            doc.loop_free = Some(check);
        }
        if let Some(nco_frequency) = &outcome.nco_frequency {
            doc.nco_frequency =
                Some(crate::LoopFreeCheck::of(Measurement::NcoFrequency, outcome.closed_loop(), nco_frequency));
        }
        let inputs = crate::checks::input_warnings(outcome, &doc.calibration, &doc.loop_summary);
        doc.warnings.extend(inputs);
        if let Some(first) = outcome.imu_spikes_t_s.first() {
            doc.warnings.push(Warning {
                code: WarningCode::ImuSpikes,
                message: format!(
                    "{} isolated IMU sample(s) no hand motion can produce (the first at {first} s) were replaced by \
                     the mean of their neighbours; check the IMU and its logger",
                    outcome.imu_spikes_t_s.len()
                ),
            });
        }
        match &outcome.loop_response {
            Ok(check) => {
                if !check.consistent {
                    doc.warnings.push(Warning {
                        code: WarningCode::LoopResponse,
                        message: format!(
                            "the loop's response measured from the session does not match the model: {}; check the \
                             receiver loop's order, bandwidth, update interval and what its log holds",
                            check.summary().trim_start_matches("measured loop response: ")
                        ),
                    });
                }
                doc.loop_response = Some(check.clone());
            }
            Err(e) => doc.warnings.push(Warning {
                code: WarningCode::ResponseUnchecked,
                message: format!("the loop's response could not be measured from the session: {e}"),
            }),
        }
        if let Some(ch) = &outcome.chosen_loop {
            let logged = ch.logged_phase.name();
            let mut found = format!("order = {}", ch.model.order());
            if let Some(bn) = ch.model.bn_hz() {
                found += &format!(", bn_hz = {}", Decimal((bn * 100.0).round() / 100.0));
            }
            if let Some(t) = ch.model.interval_s() {
                found += &format!(", loop_interval_s = {}", Decimal(t));
            }
            found += &format!(", logged_phase = {logged}");
            doc.warnings.push(Warning {
                code: WarningCode::LoopNotStated,
                message: format!(
                    "no receiver loop was stated: of {} typical receiver loops the data fit best {} with the log \
                     holding the {} discriminator output (the runner-up, {}, fits with {:.2} times the residual). \
                     Γ̂ is given under it, but a chosen loop is not a checked one: state the receiver's loop (order, \
                     bn_hz, loop_interval_s, logged_phase; the loop found would be {found}) from the receiver's \
                     settings to get a trustworthy estimate",
                    ch.candidates,
                    ch.model,
                    match ch.logged_phase {
                        gsens_core::LoggedPhase::Last => "last",
                        gsens_core::LoggedPhase::Mean => "mean of the",
                    },
                    ch.runner_up,
                    ch.runner_up_rss_ratio
                ),
            });
        }
        doc.judge();
        doc
    }

    /// The codes of the warnings that make the estimate untrustworthy (those
    /// that [`Warning::affects_trust`]), in the order raised: what every
    /// output names beside its verdict.
    pub fn untrusted_codes(&self) -> Vec<&'static str> {
        untrusted_codes(&self.warnings, self.measurement)
    }

    /// Sets [`ResultDocument::trustworthy`] from the warnings and the axes,
    /// and puts the warnings in the order of their causes
    /// ([`ResultDocument::order_by_cause`]).
    pub fn judge(&mut self) {
        let c = &self.calibration;
        let any_axis = (0..3).any(|i| c.gamma_hz_per_mps2[i].is_some() && c.sigma_hz_per_mps2[i].is_some());
        if !any_axis && !self.warnings.iter().any(|w| w.code == WarningCode::NothingObservable) {
            self.warnings.push(Warning {
                code: WarningCode::NothingObservable,
                message: "no axis is observable: the data hold too little g-induced phase error to estimate Γ; \
                          shake the board harder, along each axis in turn, near the loop's peak response"
                    .into(),
            });
        }
        self.order_by_cause();
        self.trustworthy = self.untrusted_codes().is_empty();
    }

    /// Orders the warnings by cause (the logs' units and time base first,
    /// then sampling and alignment, the loop, the shaking; stable within
    /// each), and, when a unit code ([`WarningCode::is_unit`]) is raised, replaces the
    /// shaking advice of the warnings (`discriminator_range`, `nothing_observable`,
    /// `loop_offset_unresolved`) and of the
    /// axes' verdicts, which would follow from the wrong unit, by a pointer
    /// to it.
    pub fn order_by_cause(&mut self) {
        let units: Vec<&'static str> =
            self.warnings.iter().map(|w| w.code).filter(|c| c.is_unit()).map(WarningCode::as_str).collect();
        sort_by_cause(&mut self.warnings);
        if units.is_empty() {
            return;
        }
        let mut codes: Vec<&str> = Vec::new();
        for c in units {
            if !codes.contains(&c) {
                codes.push(c);
            }
        }
        let codes = codes.join(", ");
        for w in &mut self.warnings {
            defer_shaking_advice(w, &codes);
        }
        for a in &mut self.calibration.axes {
            if a.advises_shaking() {
                let state = if a.observable { "observable" } else { "not observable" };
                a.text = format!("{}: {state}; the shaking is not judged while the {codes} warning stands", a.axis);
            }
        }
    }

    /// The document of a calibration estimated from an epoch series the
    /// caller prepared (`channels` and `selection` describe how).
    pub fn from_parts(
        calibration: Calibration,
        channels: Vec<ChannelSummary>,
        selection: SelectionConfig,
        pipeline: PipelineSummary,
        inputs: &[(&str, &str)],
        truth_gamma_hz_per_mps2: Option<[f64; 3]>,
    ) -> Self {
        let mut doc = ResultDocument {
            tool: tool_version(),
            measurement: Measurement::TrackingError,
            trustworthy: true,
            loop_summary: LoopSummary::of(&calibration.loop_used),
            warnings: warnings(&calibration),
            loop_response: None,
            calibration,
            channels,
            signals: Vec::new(),
            channel_ranking: None,
            selection,
            pipeline,
            inputs: inputs.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect(),
            truth_gamma_hz_per_mps2,
            source: None,
            report: None,
            loop_free: None,
            nco_frequency: None,
            tracking_error: None,
            identified_loop: None,
        };
        doc.judge();
        doc
    }

    /// Writes [`ResultDocument::to_json_string`] to `path`.
    pub fn write_json_file(&self, path: &std::path::Path) -> std::io::Result<()> {
        std::fs::write(path, self.to_json_string().map_err(std::io::Error::other)?)
    }

    /// The document as pretty-printed JSON with a final newline.
    pub fn to_json_string(&self) -> Result<String, serde_json::Error> {
        Ok(serde_json::to_string_pretty(self)? + "\n")
    }

    /// A document read back from its JSON ([`ResultDocument::to_json_string`]:
    /// `gsens estimate --json`, `report.json`); numbers written as `null`
    /// because they were not finite read back as NaN, so that the document
    /// writes the same JSON again.
    pub fn from_json_str(json: &str) -> Result<Self, serde_json::Error> {
        serde_json::from_str(json)
    }

    /// [`ResultDocument::from_json_str`] of the file at `path`.
    pub fn read_json_file(path: &std::path::Path) -> Result<Self, DocumentError> {
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|error| DocumentError::Io { file: file.clone(), error })?;
        Self::from_json_str(&text).map_err(|e| DocumentError::Json {
            file,
            line: e.line(),
            column: e.column(),
            message: e.to_string(),
        })
    }

    /// Γ̂ and its covariance ([`Calibration::gamma_with_covariance`]) from
    /// the result document at `path`; an axis without an estimate is an
    /// error naming the file and the entry.
    pub fn read_gamma_file(path: &std::path::Path) -> Result<([f64; 3], [[f64; 3]; 3]), DocumentError> {
        let doc = Self::read_json_file(path)?;
        doc.calibration
            .gamma_with_covariance()
            .map_err(|entry| DocumentError::Unobservable { file: path.display().to_string(), entry })
    }
}

/// Why a result document could not be read back.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum DocumentError {
    /// The file could not be read.
    #[error("{file}: cannot read: {error}")]
    Io {
        /// The file.
        file: String,
        /// The underlying error, quoted in the message.
        error: std::io::Error,
    },
    /// The file is not a result document's JSON.
    #[error("{file}:{line}:{column}: not a gsens result document (the JSON an estimate writes): {message}")]
    Json {
        /// The file.
        file: String,
        /// Line of the error (1-based).
        line: usize,
        /// Column of the error (1-based).
        column: usize,
        /// What serde_json found.
        message: String,
    },
    /// An entry of Γ̂ or its covariance is null: its axis was not observable.
    #[error("{file}: {entry} is null: the axis was not observable")]
    Unobservable {
        /// The file.
        file: String,
        /// The entry, e.g. `gamma_hz_per_mps2[2]`.
        entry: String,
    },
}

/// The warnings a calibration's own numbers raise.
fn warnings(c: &Calibration) -> Vec<Warning> {
    let mut w = Vec::new();
    if c.gamma_raw_hz_per_mps2.iter().any(|g| !g.is_finite()) {
        w.push(Warning {
            code: WarningCode::NotFinite,
            message: format!(
                "the estimator did not give a finite Γ̂ ({}): with the gradient observer, lower its gain (the \
                 paper's k = 0.5) or use the batch estimator",
                c.settings.method
            ),
        });
    }
    // The range is on L1's scale and already narrowed for the weakest channel's noise and the highest carrier.
    let (peak, lin) = (c.predicted_peak_phase_err_rad, c.discriminator_linear_range_rad);
    if peak > lin {
        let d = c.settings.discriminator;
        w.push(Warning {
            code: WarningCode::DiscriminatorRange,
            message: format!(
                "the predicted g-induced phase error reaches {peak:.2} rad, beyond the discriminator's linear range \
                 ({lin:.2} rad: {d}'s ±{:.2} rad less {:.2} σ of thermal noise at the weakest channel's C/N0, on \
                 L1's scale): {DISCRIMINATOR_ADVICE}",
                d.unambiguous_range_rad(),
                gsens_core::RANGE_MARGIN_SIGMAS
            ),
        });
    }
    if let Some(j) = c.joint_fit.as_ref().filter(|j| j.stated_loop_rejected) {
        let (f, f0) = (j.natural_frequency_hz.unwrap_or(f64::NAN), j.stated_natural_frequency_hz.unwrap_or(f64::NAN));
        w.push(Warning {
            code: WarningCode::LoopRejected,
            message: format!(
                "the data reject the stated loop ({}): its natural frequency fits at {f:.4} ± {:.4} Hz instead of \
                 {f0:.4} Hz (z = {:+.1}, beyond ±{:.2}, a {} % false-alarm test). Γ̂ is given under the fitted loop \
                 ({}); under the stated loop it would be {}. Check the receiver's loop settings \
                 (bandwidth, order, update interval, what its log holds) and state them",
                j.stated_loop,
                j.sigma_natural_frequency_hz.unwrap_or(f64::NAN),
                j.loop_test_z.unwrap_or(f64::NAN),
                j.loop_test_threshold_z,
                Decimal(j.loop_test_false_alarm * 100.0),
                j.fitted_loop,
                // Only the observable axes have a number to show.
                (0..3)
                    .map(|i| if c.observable[i] {
                        format!("{:+.5}", j.gamma_stated_loop_hz_per_mps2[i])
                    } else {
                        format!("unobservable ({})", ["x", "y", "z"][i])
                    })
                    .collect::<Vec<_>>()
                    .join(", "),
            ),
        });
    }
    if let Some((x, offset, scale)) = joint_nonlinearity(c).filter(|(x, ..)| *x > JOINT_LINEAR_LIMIT_RAD) {
        let part = |v: Option<f64>| v.map_or("not fitted".to_string(), |v| format!("{v:.2}"));
        w.push(Warning {
            code: WarningCode::LoopOffsetUnresolved,
            message: format!(
                "the data do not resolve the IMU time offset and the loop well enough for σ to hold: one σ of them \
                 moves the shaking's phase by {x:.2} rad (offset {}, loop scale {}), beyond the {JOINT_LINEAR_LIMIT_RAD} \
                 rad the joint fit's linearization holds for, and Γ̂ moves with them.{LOOP_OFFSET_ADVICE} if you \
                 know it, or shake harder and longer, and at two rates: {}",
                part(offset),
                part(scale),
                two_rate_advice(&c.loop_used)
            ),
        });
    }
    if let Some(j) = c.joint_fit.as_ref().filter(|j| j.offset_at_limit) {
        let found = j.imu_time_offset_s.unwrap_or(f64::NAN);
        let max = j.offset_max_abs_s.unwrap_or(f64::NAN);
        w.push(Warning {
            code: WarningCode::TimeOffsetAtLimit,
            message: format!(
                "the IMU time offset search ended at its limit ({found:+.3} s, the search spans ±{max} s): the IMU and tracking clocks \
                 may differ by more; widen the search (time_offset_max_s) or state the offset (time_offset)"
            ),
        });
    }
    w
}
