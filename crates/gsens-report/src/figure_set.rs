//! The figure set of a calibration: the paper's Figs. 3–5, C/N0 per channel
//! and the residual spectrum, each with its title and caption, computed once
//! from an [`Outcome`] and drawn on demand.

use crate::FigureBlock;
use crate::figures::{
    AllanData, Cn0Track, CompensationData, CompensationKind, DEFAULT_SIZE, EstimationData, Format, Image,
    MeasuredResponseData, RenderError, ResponseData, SpectrumData, fig_allan, fig_cn0, fig_compensation,
    fig_estimation, fig_measured_response, fig_residual_spectrum, fig_response,
};
use gsens_calib::{CalibError, Calibration, ObservationOutcome, Outcome, compensation_series};
use gsens_io::TrackingLog;
use gsens_session::PreparedSession;
use std::path::Path;

/// Why figures could not be written.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum WriteError {
    /// A figure could not be drawn.
    #[error("drawing {id}: {error}")]
    Render {
        /// The figure.
        id: &'static str,
        /// The underlying error, quoted in the message (so not also a `source`: a printed chain would say it twice).
        error: RenderError,
    },
    /// A file or folder could not be written.
    #[error("{path}: cannot write: {error}")]
    Io {
        /// The path.
        path: String,
        /// The underlying error, quoted in the message (so not also a `source`: a printed chain would say it twice).
        error: std::io::Error,
    },
}

/// One figure: file stem, title, caption and its renderer.
pub struct Figure<'a> {
    /// Short identifier, also the file stem.
    pub id: &'static str,
    /// Heading.
    pub title: String,
    /// What the figure shows and how to read it.
    pub caption: String,
    render: Box<dyn Fn(Format) -> Result<Image, RenderError> + 'a>,
}

impl<'a> Figure<'a> {
    /// A figure drawn by `render`.
    pub fn new(
        id: &'static str,
        title: String,
        caption: String,
        render: impl Fn(Format) -> Result<Image, RenderError> + 'a,
    ) -> Self {
        Figure { id, title, caption, render: Box::new(render) }
    }

    /// The Allan deviation of a simulated oscillator (`simulated`, over a
    /// record of `duration_s`) against its power-law model (`theory`) at the
    /// averaging times `taus_s`.
    pub fn allan(taus_s: Vec<f64>, simulated: Vec<f64>, theory: Vec<f64>, duration_s: f64, label: String) -> Self {
        let caption = format!(
            "Overlapping Allan deviation of {:.0} minutes of the simulator's fractional frequency ({label}) against \
             the power-law model of its preset; deterministic terms (offset, drift, temperature cycle) are in the \
             simulation but not in the model.",
            duration_s / 60.0
        );
        Figure::new("allan", "Allan deviation of the simulated oscillator".into(), caption, move |f| {
            let d = AllanData { taus_s: &taus_s, simulated: &simulated, theory: &theory, label: &label };
            fig_allan(&d, f, (900, 600))
        })
    }

    /// Draws the figure.
    pub fn render(&self, format: Format) -> Result<Image, RenderError> {
        (self.render)(format)
    }
}

/// The series the figures of a calibration need, computed once.
pub struct FigureInputs<'a> {
    session: &'a PreparedSession,
    calibration: &'a Calibration,
    measurement: gsens_calib::Measurement,
    tracking: Option<&'a TrackingLog>,
    truth: Option<[f64; 3]>,
    before: Vec<Option<f64>>,
    after: Vec<Option<f64>>,
    spectrum: (Vec<f64>, Vec<f64>),
    measured_response: Option<MeasuredResponseData>,
}

impl<'a> FigureInputs<'a> {
    /// The inputs of the figures of `outcome`; `tracking` (the log it came
    /// from) adds the C/N0 figure, `truth` draws the true Γ.
    pub fn new(
        outcome: &'a Outcome,
        tracking: Option<&'a TrackingLog>,
        truth: Option<[f64; 3]>,
    ) -> Result<Self, CalibError> {
        let (session, calibration) = (&outcome.session, &outcome.calibration);
        let series = outcome.series();
        // φ and φ − φ_aᵀΓ̂ (the estimate of every axis, as the reported RMS
        // after compensation), high-passed exactly as the estimator saw them.
        let (before, after): (Vec<_>, Vec<_>) =
            compensation_series(&series, &calibration.settings, &calibration.gamma_raw_hz_per_mps2)?
                .into_iter()
                .unzip();
        // The spectrum over the longest gap-free run after the warm-up.
        let skip = gsens_calib::warmup_epochs(&calibration.settings, session.log_interval_s) as usize;
        let (mut best, mut start) = (0..0, None);
        for k in skip..=after.len() {
            match (start, after.get(k).copied().flatten()) {
                (None, Some(_)) => start = Some(k),
                (Some(s), None) => {
                    if k - s > best.len() {
                        best = s..k;
                    }
                    start = None;
                }
                _ => {}
            }
        }
        let spec_before: Vec<f64> = best.clone().filter_map(|k| before[k]).collect();
        let resid: Vec<f64> = best.filter_map(|k| after[k]).collect();
        let measured_response = outcome.loop_response.as_ref().ok().map(|check| {
            let model = calibration.settings.loop_at(session.log_interval_s);
            let desc = model.to_string();
            MeasuredResponseData::from_check(
                check,
                &model,
                session.log_interval_s,
                calibration.settings.logged_phase,
                200,
                desc,
            )
        });
        Ok(FigureInputs {
            session,
            calibration,
            measurement: outcome.measurement,
            tracking,
            truth,
            before,
            after,
            spectrum: (spec_before, resid),
            measured_response,
        })
    }

    /// The figures: Figs. 3–5 of the paper, C/N0, the residual spectrum.
    pub fn figures(&self) -> Vec<Figure<'_>> {
        [
            self.response_figure(),
            self.measured_response_figure(),
            Some(self.estimation_figure()),
            Some(self.compensation_figure()),
            self.cn0_figure(),
            self.spectrum_figure(),
        ]
        .into_iter()
        .flatten()
        .collect()
    }

    /// Fig. 3: the modelled loop's response, when it has one.
    fn response_figure(&self) -> Option<Figure<'_>> {
        response_figure(&self.calibration.loop_used, "modelled")
    }

    /// The loop's response measured from the session, when it was.
    fn measured_response_figure(&self) -> Option<Figure<'_>> {
        let m = self.measured_response.as_ref().filter(|m| !m.points.is_empty())?;
        Some(Figure {
            id: "measured_response",
            title: "The loop's response measured from the session".into(),
            caption: "The response of the averaged phase error to the modelled excitation aᵀΓ̂, estimated from \
                      the session (Welch cross-spectrum), beside the model's. Red: the bins the check tests (the \
                      shaken band), each with a bar as long as the deviation the check allows; a red bar that \
                      misses its black dot (the model through the same segments, window leakage included, which \
                      is what Ĥ is compared with, not the smooth curve) means the stated loop is not the \
                      receiver's. Grey: other bins with significant coherence, ±2σ from the coherence; they are \
                      not tested, and with little excitation they scatter about the curve."
                .into(),
            render: Box::new(move |f| fig_measured_response(m, f, (DEFAULT_SIZE.0, 720))),
        })
    }

    /// Fig. 4: the specific force and Γ̂ as the estimator runs.
    fn estimation_figure(&self) -> Figure<'_> {
        let (c, s) = (self.calibration, self.session);
        Figure {
            id: "fig4_estimation",
            title: "Fig. 4: the estimation process".into(),
            caption: format!(
                "Specific force in the IMU frame (top) and the components of Γ̂ as the estimator runs (bottom), with \
                 ±1σ bands assuming white residuals{}. An axis is estimated once it is shaken.{}",
                if self.truth.is_some() { "; the truth dashed" } else { "" },
                match self.measurement {
                    gsens_calib::Measurement::TrackingError => String::new(),
                    m => format!(
                        " The Γ̂ drawn is the estimate through the tracking error as the observer runs; the report's \
                         estimate is made from {}.",
                        m.description()
                    ),
                }
            ),
            render: Box::new(move |f| {
                let d = EstimationData {
                    t_s: &s.t_s,
                    accel_mps2: &s.accel_mps2,
                    history: &c.history,
                    truth: self.truth,
                    observable: c.observable,
                };
                fig_estimation(&d, f, (DEFAULT_SIZE.0, 720))
            }),
        }
    }

    /// Fig. 5: the phase error before and after compensation.
    fn compensation_figure(&self) -> Figure<'_> {
        let (c, s) = (self.calibration, self.session);
        Figure {
            id: "fig5_compensation",
            title: "Fig. 5: phase error before and after compensation".into(),
            caption: format!(
                "The channel-averaged phase tracking error φ and φ − φ_aᵀΓ̂ over the whole log{} (legend RMS \
                 over every plotted epoch; over the {} epochs used: {:.4} rad before, {:.4} rad after). At rest \
                 the two coincide; while shaking, compensation brings the error back to its at-rest level.",
                if c.settings.highpass_hz > 0.0 {
                    format!(
                        ", both high-passed at {} Hz as in the estimator (this removes the slow steady-state \
                         error of the satellites' Doppler rate)",
                        c.settings.highpass_hz
                    )
                } else {
                    String::new()
                },
                c.epochs_used,
                c.rms_before_rad,
                c.rms_after_rad
            ),
            render: Box::new(move |f| {
                let d = CompensationData {
                    t_s: &s.t_s,
                    before_rad: &self.before,
                    after_rad: &self.after,
                    kind: CompensationKind::PostProcessing,
                };
                fig_compensation(&d, f, (DEFAULT_SIZE.0, 520))
            }),
        }
    }

    /// Every track's C/N0, when the tracking log is at hand.
    fn cn0_figure(&self) -> Option<Figure<'_>> {
        let log = self.tracking?;
        let s = self.session;
        let used: Vec<(u32, u32)> = s.channels.iter().filter(|ch| ch.used).map(|ch| (ch.channel, ch.prn)).collect();
        Some(Figure {
            id: "cn0",
            title: "C/N0 per channel".into(),
            caption: format!(
                "Carrier-to-noise density of every track in the log; the {} averaged into φ are drawn bold.",
                used.len()
            ),
            render: Box::new(move |f| {
                let tracks: Vec<Cn0Track> = log
                    .tracks()
                    .iter()
                    .map(|t| Cn0Track {
                        channel: t.channel,
                        prn: t.prn,
                        t_s: &t.t_s,
                        cn0_dbhz: &t.cn0_dbhz,
                        used: used.contains(&(t.channel, t.prn)),
                    })
                    .collect();
                fig_cn0(&tracks, f, (DEFAULT_SIZE.0, 520))
            }),
        })
    }

    /// The residual's spectrum, over a gap-free stretch of at least 64 epochs.
    fn spectrum_figure(&self) -> Option<Figure<'_>> {
        if self.spectrum.1.len() < 64 {
            return None;
        }
        let s = self.session;
        let fn_hz = self.calibration.loop_used.natural_frequency_hz();
        Some(Figure {
            id: "residual_spectrum",
            title: "Residual spectrum".into(),
            caption: format!(
                "Welch power spectral density of φ and of the residual φ − φ_aᵀΓ̂ over the longest gap-free \
                 stretch after the warm-up ({:.0} s). What compensation removes is concentrated around the \
                 loop's natural frequency; a residual peak there would mean a model mismatch.",
                self.spectrum.1.len() as f64 * s.log_interval_s
            ),
            render: Box::new(move |f| {
                let d = SpectrumData {
                    interval_s: s.log_interval_s,
                    residual_rad: &self.spectrum.1,
                    before_rad: Some(&self.spectrum.0),
                    marker_hz: fn_hz,
                };
                fig_residual_spectrum(&d, f, (DEFAULT_SIZE.0, 560))
            }),
        })
    }
}

/// Writes every figure as PNG and SVG into `dir` (`on_figure` is told each
/// figure's id before it is drawn); returns the SVG blocks for the HTML.
pub fn write_figures(
    figs: &[Figure],
    dir: &Path,
    mut on_figure: impl FnMut(&str),
) -> Result<Vec<FigureBlock>, WriteError> {
    std::fs::create_dir_all(dir).map_err(|e| WriteError::Io { path: dir.display().to_string(), error: e })?;
    let mut blocks = Vec::new();
    for fig in figs {
        on_figure(fig.id);
        for format in [Format::Png, Format::Svg] {
            let img = fig.render(format).map_err(|e| WriteError::Render { id: fig.id, error: e })?;
            let path = dir.join(format!("{}.{}", fig.id, format.extension()));
            img.write_to(&path).map_err(|e| WriteError::Io { path: path.display().to_string(), error: e })?;
            if let Image::Svg(svg) = img {
                blocks.push(FigureBlock {
                    id: fig.id.to_string(),
                    title: fig.title.clone(),
                    caption: fig.caption.clone(),
                    svg,
                });
            }
        }
    }
    Ok(blocks)
}

/// What [`write_report_dir`] wrote.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ReportFiles {
    /// `report.html`.
    pub html: std::path::PathBuf,
    /// `gsens_gamma.h`, or `None` when none was written (an untrustworthy
    /// estimate without `write_untrusted_header`).
    pub header: Option<std::path::PathBuf>,
}

/// Writes a whole report into `dir`: `figures/` (PNG and SVG of `figs`),
/// `report.html`, `report.json` and `gsens_gamma.h`, for the result document
/// `document` titled `title`; `on_figure` is told each figure's id before it
/// is drawn. The header carries Γ̂ into firmware, so for an estimate the
/// document calls untrustworthy it is written only when
/// `write_untrusted_header` (and then says `GSENS_GAMMA_TRUSTWORTHY 0`);
/// otherwise a `gsens_gamma.h` of an earlier report in `dir` is removed, so
/// that no header stands beside a report that does not vouch for it.
pub fn write_report_dir(
    dir: &Path,
    title: &str,
    document: &gsens_calib::ResultDocument,
    figs: &[Figure],
    write_untrusted_header: bool,
    on_figure: impl FnMut(&str),
) -> Result<ReportFiles, WriteError> {
    let io = |p: &Path| {
        let path = p.display().to_string();
        move |error| WriteError::Io { path, error }
    };
    std::fs::create_dir_all(dir).map_err(io(dir))?;
    let figures = write_figures(figs, &dir.join("figures"), on_figure)?;
    let inputs: Vec<(&str, &str)> = document.inputs.iter().map(|(k, v)| (k.as_str(), v.as_str())).collect();
    let meta = crate::ReportMeta::now(gsens_calib::tool_version(), &inputs);
    let header =
        (document.trustworthy || write_untrusted_header).then(|| crate::cheader::render_c_header(document, &meta));
    let data = crate::ReportData { title: title.to_string(), document, meta, figures, c_header: header.clone() };
    let json = crate::json::report_json_string(&data).expect("the document serializes");
    for (name, text) in [("report.html", crate::html::render_html(&data)), ("report.json", json)] {
        std::fs::write(dir.join(name), text).map_err(io(&dir.join(name)))?;
    }
    let header_path = dir.join("gsens_gamma.h");
    match header {
        Some(text) => std::fs::write(&header_path, text).map_err(io(&header_path))?,
        None => match std::fs::remove_file(&header_path) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => return Err(io(&header_path)(e)),
            _ => {}
        },
    }
    Ok(ReportFiles { html: dir.join("report.html"), header: data.c_header.is_some().then_some(header_path) })
}

/// Fig. 3 for `loop_model` (`how`: "modelled", "identified from the
/// session"), when it has a response.
fn response_figure(loop_model: &gsens_core::LoopModel, how: &str) -> Option<Figure<'static>> {
    let desc = loop_model.to_string();
    let r = ResponseData::from_loop(loop_model, 0.05, 20.0, 300, desc.clone()).ok()?;
    let period = 1.0 / r.peak_hz;
    Some(Figure {
        id: "fig3_response",
        title: "Fig. 3: the loop's frequency response".into(),
        caption: format!(
            "|L(j2πf)| = |φ/Δf| and its phase for the receiver loop {how} ({desc}). A frequency bias \
             Δf = aᵀΓ leaves the largest phase error when the specific force varies near the peak, \
             {:.3} Hz: shake with a period of about {period:.2} s (shaded: the half-power band).",
            r.peak_hz
        ),
        render: Box::new(move |f| fig_response(&r, f, DEFAULT_SIZE)),
    })
}

/// The figures of a carrier phase and Doppler log's calibration: the
/// identified loop's response (Fig. 3) and the receiver's carrier phase
/// before and after compensation, its time from the first epoch.
pub fn observation_figures(outcome: &ObservationOutcome) -> Vec<Figure<'_>> {
    let phase = &outcome.carrier_phase;
    let t0 = phase.t_s.first().copied().unwrap_or(0.0);
    let t_s: Vec<f64> = phase.t_s.iter().map(|t| t - t0).collect();
    let c = &outcome.calibration;
    let compensation = Figure {
        id: "fig5_compensation",
        title: "Fig. 5: the carrier phase before and after compensation".into(),
        caption: format!(
            "The common mode of the tracks' carrier phase, integrated from the rows (2π·Σ f·Δt over each \
             segment, its linear trend removed), and the same less Γ̂'s part through the identified loop, over \
             the log from its first epoch (legend RMS over every plotted epoch; over the {} epochs used: {:.4} rad \
             before, {:.4} rad after). At rest the two coincide; while shaking, compensation brings the phase back \
             to its at-rest wander.",
            c.epochs_used, c.rms_before_rad, c.rms_after_rad
        ),
        render: Box::new(move |f| {
            let d = CompensationData {
                t_s: &t_s,
                before_rad: &phase.before_rad,
                after_rad: &phase.after_rad,
                kind: CompensationKind::CarrierPhase,
            };
            fig_compensation(&d, f, (DEFAULT_SIZE.0, 520))
        }),
    };
    response_figure(&c.loop_used, "identified from the session").into_iter().chain([compensation]).collect()
}
