//! The measured loop response: Ĥ = S_uφ/S_uu from the session with its band
//! against the model's response, magnitude (top) and phase (bottom) versus
//! frequency on a log axis (`gsens_calib::measure_response`).

use super::{
    AFTER_COLOR, BEFORE_COLOR, DrawResult, Format, Frame, Image, Mark, Plot, RenderError, Style, fmt_tick,
    framed_chart, legend_strip, log_axis, render, titled,
};
use gsens_calib::{ResponseCheck, epoch_response};
use gsens_core::{LoggedPhase, LoopModel};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::ops::Range;

/// Standard errors drawn either side of each measured point.
pub const MEASURED_BAND_SIGMA: f64 = 2.0;

/// One measured bin to plot.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct MeasuredPoint {
    /// Frequency \[Hz\].
    pub f_hz: f64,
    /// |Ĥ| \[rad/Hz\].
    pub magnitude_rad_per_hz: f64,
    /// 1σ of |Ĥ| \[rad/Hz\].
    pub sigma_magnitude_rad_per_hz: f64,
    /// arg Ĥ \[deg\], unwrapped onto the model's phase curve.
    pub phase_deg: f64,
    /// 1σ of arg Ĥ \[deg\].
    pub sigma_phase_deg: f64,
    /// |Ĥ_m|, the model through the same segments and window (what the
    /// check compares Ĥ with) \[rad/Hz\].
    pub model_magnitude_rad_per_hz: f64,
    /// arg Ĥ_m \[deg\], unwrapped like `phase_deg`.
    pub model_phase_deg: f64,
    /// Whether the check tested this bin (the shaken band).
    pub tested: bool,
    /// For a tested bin, the largest deviation of Ĥ from Ĥ_m the check
    /// allows, t_max·σ_dev (`ResponseCheck::threshold_sigma` times
    /// `ResponseBin::sigma_deviation_rad_per_hz`) \[rad/Hz\]: a tested point
    /// further than this from its model point fails the check.
    pub allowed_deviation_rad_per_hz: Option<f64>,
}

impl MeasuredPoint {
    /// Half-length of the magnitude bar: for a tested bin the deviation the
    /// check allows, otherwise [`MEASURED_BAND_SIGMA`] standard errors from
    /// the coherence \[rad/Hz\].
    pub fn magnitude_bar_rad_per_hz(&self) -> f64 {
        self.allowed_deviation_rad_per_hz.unwrap_or(MEASURED_BAND_SIGMA * self.sigma_magnitude_rad_per_hz)
    }

    /// Half-length of the phase bar \[deg\], at most 90°: for a tested bin
    /// the allowed deviation across Ĥ_m as an angle, atan(allowed/|Ĥ_m|),
    /// otherwise [`MEASURED_BAND_SIGMA`] standard errors from the coherence.
    pub fn phase_bar_deg(&self) -> f64 {
        let deg = match self.allowed_deviation_rad_per_hz {
            Some(a) => (a / self.model_magnitude_rad_per_hz).atan().to_degrees(),
            None => MEASURED_BAND_SIGMA * self.sigma_phase_deg,
        };
        deg.min(90.0)
    }
}

/// The measured response and the model to plot.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct MeasuredResponseData {
    /// The bins whose coherence is significant, increasing in frequency.
    pub points: Vec<MeasuredPoint>,
    /// Frequencies of the model curve \[Hz\], increasing, positive.
    pub model_frequency_hz: Vec<f64>,
    /// |L| of the model at the log epochs \[rad/Hz\].
    pub model_magnitude_rad_per_hz: Vec<f64>,
    /// Its phase \[deg\], unwrapped along frequency.
    pub model_phase_deg: Vec<f64>,
    /// The loop in words (drawn in the title).
    pub description: String,
    /// The check's verdict in one line.
    pub verdict: String,
    /// Whether the check passed (colours the verdict).
    pub consistent: bool,
}

impl MeasuredResponseData {
    /// The bins of `check` whose coherence exceeds its threshold, and the
    /// model's epoch-level response ([`epoch_response`]: the loop's L times
    /// the logged mean's D) at `points` log-spaced frequencies over them.
    pub fn from_check(
        check: &ResponseCheck,
        model: &LoopModel,
        log_interval_s: f64,
        logged: LoggedPhase,
        points: usize,
        description: impl Into<String>,
    ) -> Self {
        let l = |f: f64| epoch_response(model, log_interval_s, logged, f);
        let shown: Vec<_> = check.bins.iter().filter(|b| b.coherence > check.coherence_threshold).collect();
        let (lo, hi) = match (shown.first(), shown.last()) {
            (Some(a), Some(b)) => (a.f_hz / 1.25, b.f_hz * 1.25),
            _ => (check.resolution_hz, 0.5 / log_interval_s),
        };
        let hi = hi.min(0.999 * 0.5 / log_interval_s).max(lo * 2.0);
        let n = points.max(2);
        let ratio = (hi / lo).powf(1.0 / (n - 1) as f64);
        let model_frequency_hz: Vec<f64> = (0..n).map(|k| lo * ratio.powi(k as i32)).collect();
        let unwrap = |p: f64, prev: f64| if prev.is_finite() { p - 360.0 * ((p - prev) / 360.0).round() } else { p };
        let mut model_phase_deg = Vec::with_capacity(n);
        let mut prev = f64::NAN;
        for &f in &model_frequency_hz {
            prev = unwrap(l(f).arg().to_degrees(), prev);
            model_phase_deg.push(prev);
        }
        // The model's unwrapped phase at f, by interpolation on the log axis.
        let model_phase_at = |f: f64| {
            let i = model_frequency_hz.partition_point(|&x| x < f).clamp(1, n - 1);
            let (f0, f1) = (model_frequency_hz[i - 1].ln(), model_frequency_hz[i].ln());
            let w = ((f.ln() - f0) / (f1 - f0)).clamp(0.0, 1.0);
            model_phase_deg[i - 1] + w * (model_phase_deg[i] - model_phase_deg[i - 1])
        };
        let points = shown
            .iter()
            .map(|b| {
                let reference = model_phase_at(b.f_hz);
                MeasuredPoint {
                    f_hz: b.f_hz,
                    magnitude_rad_per_hz: b.measured_magnitude_rad_per_hz,
                    sigma_magnitude_rad_per_hz: b.sigma_magnitude_rad_per_hz,
                    phase_deg: unwrap(b.measured_phase_rad.to_degrees(), reference),
                    sigma_phase_deg: b.sigma_phase_rad.to_degrees(),
                    model_magnitude_rad_per_hz: b.model_magnitude_rad_per_hz,
                    model_phase_deg: unwrap(b.model_phase_rad.to_degrees(), reference),
                    tested: b.tested,
                    allowed_deviation_rad_per_hz: b
                        .tested
                        .then_some(check.threshold_sigma * b.sigma_deviation_rad_per_hz),
                }
            })
            .collect();
        MeasuredResponseData {
            points,
            model_magnitude_rad_per_hz: model_frequency_hz.iter().map(|&f| l(f).norm()).collect(),
            model_frequency_hz,
            model_phase_deg,
            description: description.into(),
            verdict: verdict(check),
            consistent: check.consistent,
        }
    }
}

/// The verdict in a line short enough for the legend.
fn verdict(check: &ResponseCheck) -> String {
    let (kind, sig, f) = if check.max_magnitude_deviation_sigma.abs() >= check.max_phase_deviation_sigma.abs() {
        ("magnitude", check.max_magnitude_deviation_sigma, check.max_magnitude_f_hz)
    } else {
        ("phase", check.max_phase_deviation_sigma, check.max_phase_f_hz)
    };
    format!(
        "largest deviation {:.1}σ at {f:.2} Hz ({kind}): {} (threshold {:.1}σ, {} % false alarms)",
        sig.abs(),
        if check.consistent { "consistent with the model" } else { "NOT consistent with the model" },
        check.threshold_sigma,
        100.0 * check.settings.false_alarm
    )
}

impl Plot for MeasuredResponseData {
    fn plot<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>, st: &Style) -> DrawResult<DB> {
        let title = format!("Measured loop response: {}", self.description);
        let area = titled(root, &title, st)?;
        let y_area = st.i(70.0);
        let area = legend_strip(&area, &self.legend(), y_area + st.i(10.0), st)?;
        let h = area.dim_in_pixel().1 as i32;
        let (top, bottom) = area.split_vertically(h * 58 / 100);
        self.magnitude_panel(&top, st, y_area)?;
        self.phase_panel(&bottom, st, y_area)
    }
}

/// The measured response figure's colours.
struct Palette {
    model: RGBAColor,
    tested: RGBAColor,
    other: RGBAColor,
    reference: RGBAColor,
}

/// The marks' sizes in pixels: the model's line, a measured dot, the
/// reference's dot, an error bar's width.
struct Marks {
    width: u32,
    dot: i32,
    small: i32,
    bar_w: u32,
}

impl MeasuredResponseData {
    fn palette() -> Palette {
        Palette {
            model: AFTER_COLOR.mix(1.0),
            tested: BEFORE_COLOR.mix(1.0),
            other: RGBColor(127, 127, 127).mix(1.0),
            reference: BLACK.mix(1.0),
        }
    }

    fn marks(st: &Style) -> Marks {
        Marks {
            width: st.i(2.5).max(1) as u32,
            dot: st.i(5.0).max(3),
            small: st.i(2.5).max(2),
            bar_w: st.i(1.5).max(1) as u32,
        }
    }

    /// The legend: the model, the tested and the other bins, the reference
    /// through the same segments, the verdict (green when consistent).
    fn legend(&self) -> Vec<(String, Mark)> {
        let c = Self::palette();
        let verdict_color = if self.consistent { RGBColor(44, 160, 44) } else { BEFORE_COLOR }.mix(1.0);
        let k = MEASURED_BAND_SIGMA;
        let mut entries = vec![
            ("model |L| (loop and logging)".to_string(), Mark::Line(c.model, 3)),
            (
                "measured Ĥ, tested bins (shaken band), bar: the deviation the check allows".to_string(),
                Mark::Dot(c.tested),
            ),
        ];
        if self.points.iter().any(|p| !p.tested) {
            entries.push((
                format!("measured Ĥ ±{k:.0}σ, other bins with significant coherence (not tested)"),
                Mark::Dot(c.other),
            ));
        }
        entries
            .push(("model through the same segments (what Ĥ is tested against)".to_string(), Mark::Dot(c.reference)));
        entries.push((self.verdict.clone(), Mark::Band(verdict_color)));
        entries
    }

    /// The model's frequency range \[Hz\].
    fn f_range(&self) -> Range<f64> {
        let f = &self.model_frequency_hz;
        f[0]..f[f.len() - 1]
    }

    /// The measured bins within the model's frequency range.
    fn points_in_range(&self) -> impl Iterator<Item = &MeasuredPoint> {
        let fr = self.f_range();
        self.points.iter().filter(move |p| p.f_hz >= fr.start && p.f_hz <= fr.end)
    }

    /// The top panel: the model's |L|, each bin's |Ĥ| with its bar and the
    /// reference's dot.
    fn magnitude_panel<DB: DrawingBackend>(
        &self,
        top: &DrawingArea<DB, Shift>,
        st: &Style,
        y_area: i32,
    ) -> DrawResult<DB> {
        let (c, mk) = (Self::palette(), Self::marks(st));
        let f = &self.model_frequency_hz;
        let ymax = self
            .model_magnitude_rad_per_hz
            .iter()
            .cloned()
            .chain(self.points_in_range().map(|p| p.magnitude_rad_per_hz + p.magnitude_bar_rad_per_hz()))
            .filter(|v| v.is_finite())
            .fold(0.0, f64::max)
            * 1.1;
        let ymax = if ymax > 0.0 { ymax } else { 1.0 };
        let fmt_log = |v: &f64| fmt_tick(*v, 0.0);
        let fmt_mag = |v: &f64| fmt_tick(*v, ymax);
        let frame = Frame {
            top: 10.0,
            x_area: 30.0,
            y_area,
            x_desc: None,
            y_desc: "|Ĥ|, |L| [rad/Hz]",
            y_labels: Some(6),
            fmt_x: &fmt_log,
            fmt_y: &fmt_mag,
        };
        let color = |p: &MeasuredPoint| if p.tested { c.tested } else { c.other };
        let mut chart = framed_chart(top, st, &frame, log_axis(self.f_range()), 0.0..ymax)?;
        chart.draw_series(LineSeries::new(
            f.iter().cloned().zip(self.model_magnitude_rad_per_hz.iter().cloned()),
            c.model.stroke_width(mk.width),
        ))?;
        for p in self.points_in_range() {
            let (lo, hi) = (
                (p.magnitude_rad_per_hz - p.magnitude_bar_rad_per_hz()).max(0.0),
                (p.magnitude_rad_per_hz + p.magnitude_bar_rad_per_hz()).min(ymax),
            );
            chart.draw_series(error_bar(p.f_hz, lo, hi, color(p).stroke_width(mk.bar_w)))?;
            chart.draw_series(std::iter::once(Circle::new(
                (p.f_hz, p.magnitude_rad_per_hz),
                mk.dot,
                color(p).filled(),
            )))?;
            chart.draw_series(std::iter::once(Circle::new(
                (p.f_hz, p.model_magnitude_rad_per_hz.min(ymax)),
                mk.small,
                c.reference.filled(),
            )))?;
        }
        Ok(())
    }

    /// The bottom panel: the phases likewise, on whole multiples of 45°.
    fn phase_panel<DB: DrawingBackend>(
        &self,
        bottom: &DrawingArea<DB, Shift>,
        st: &Style,
        y_area: i32,
    ) -> DrawResult<DB> {
        let (c, mk) = (Self::palette(), Self::marks(st));
        let f = &self.model_frequency_hz;
        let phases = self
            .model_phase_deg
            .iter()
            .cloned()
            .chain(
                self.points_in_range().flat_map(|p| [p.phase_deg - p.phase_bar_deg(), p.phase_deg + p.phase_bar_deg()]),
            )
            .filter(|v| v.is_finite());
        let (plo, phi) = phases.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| (a.min(p), b.max(p)));
        let pr = (plo / 45.0).floor() * 45.0..((phi / 45.0).ceil() * 45.0).max((plo / 45.0).floor() * 45.0 + 45.0);
        let fmt_log = |v: &f64| fmt_tick(*v, 0.0);
        let fmt_deg = |v: &f64| format!("{v:.0}");
        let frame = Frame {
            top: 10.0,
            x_area: 48.0,
            y_area,
            x_desc: Some("frequency f [Hz]"),
            y_desc: "phase [deg]",
            y_labels: Some(((pr.end - pr.start) / 45.0) as usize + 1),
            fmt_x: &fmt_log,
            fmt_y: &fmt_deg,
        };
        let color = |p: &MeasuredPoint| if p.tested { c.tested } else { c.other };
        let mut chart = framed_chart(bottom, st, &frame, log_axis(self.f_range()), pr.clone())?;
        chart.draw_series(LineSeries::new(
            f.iter().cloned().zip(self.model_phase_deg.iter().cloned()),
            c.model.stroke_width(mk.width),
        ))?;
        for p in self.points_in_range() {
            let s = p.phase_bar_deg();
            let (lo, hi) = ((p.phase_deg - s).max(pr.start), (p.phase_deg + s).min(pr.end));
            chart.draw_series(error_bar(p.f_hz, lo, hi, color(p).stroke_width(mk.bar_w)))?;
            chart.draw_series(std::iter::once(Circle::new((p.f_hz, p.phase_deg), mk.dot, color(p).filled())))?;
            let m = p.model_phase_deg.clamp(pr.start, pr.end);
            chart.draw_series(std::iter::once(Circle::new((p.f_hz, m), mk.small, c.reference.filled())))?;
        }
        Ok(())
    }
}

/// A vertical error bar from `lo` to `hi` at `f` with caps 3 % of f wide
/// either side (the log axis makes that the same width everywhere).
fn error_bar(f: f64, lo: f64, hi: f64, style: ShapeStyle) -> Vec<PathElement<(f64, f64)>> {
    let (a, b) = (f / 1.03, f * 1.03);
    vec![
        PathElement::new(vec![(f, lo), (f, hi)], style),
        PathElement::new(vec![(a, lo), (b, lo)], style),
        PathElement::new(vec![(a, hi), (b, hi)], style),
    ]
}

/// The measured loop response: |Ĥ| with its ±2σ band from the coherence and
/// the model's |L| (top), their phases (bottom), versus frequency on a log
/// axis; the bins the check tested drawn red, the model through the same
/// segments (what the check compares, window leakage included) as small
/// black dots, the verdict in the legend.
pub fn fig_measured_response(
    data: &MeasuredResponseData,
    format: Format,
    size: (u32, u32),
) -> Result<Image, RenderError> {
    let n = data.model_frequency_hz.len();
    if data.points.is_empty() {
        return Err(RenderError::NoData("no frequency bin with significant coherence".into()));
    }
    let ok = n >= 2
        && data.model_magnitude_rad_per_hz.len() == n
        && data.model_phase_deg.len() == n
        && data.model_frequency_hz.iter().all(|f| f.is_finite() && *f > 0.0)
        && data.model_frequency_hz.windows(2).all(|w| w[1] > w[0])
        && data.model_magnitude_rad_per_hz.iter().chain(&data.model_phase_deg).all(|v| v.is_finite())
        && data.points.iter().all(|p| {
            [p.f_hz, p.magnitude_rad_per_hz, p.sigma_magnitude_rad_per_hz, p.phase_deg, p.sigma_phase_deg]
                .iter()
                .all(|v| v.is_finite())
        });
    if !ok {
        return Err(RenderError::NoData(
            "the measured response needs ≥ 2 increasing positive model frequencies and finite values".into(),
        ));
    }
    render(data, format, size)
}
