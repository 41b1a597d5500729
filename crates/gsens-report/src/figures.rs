//! The figures: PNG or SVG of a given size from plain data.
//!
//! | function | figure |
//! | --- | --- |
//! | [`fig_response`] | the paper's Fig. 3: \|L\| and phase of the loop versus frequency, its peak and the shaking period to use |
//! | [`fig_estimation`] | the paper's Fig. 4: specific force (top), Γ̂ with ±1σ bands and the truth dashed (bottom) |
//! | [`fig_compensation`] | the paper's Fig. 5: the averaged phase error before and after compensation over time |
//! | [`fig_cn0`] | C/N0 of every channel, those averaged drawn bold |
//! | [`fig_residual_spectrum`] | Welch PSD of the phase error before and after compensation |
//! | [`fig_allan`] | Allan deviation of a simulated oscillator against its model |
//!
//! Every function checks its data first ([`RenderError::NoData`]) and draws
//! long series decimated to a min/max envelope of a few thousand points, so a
//! figure of a long log stays small and fast. Text is drawn with the bundled
//! DejaVu Sans (registered as `sans-serif`); an SVG names `sans-serif` and the
//! viewer's font draws it.

use crate::spectrum::welch_psd;
use gsens_calib::HistoryPoint;
use gsens_core::LoopModel;
use gsens_core::{Complex, LoopError};
use plotters::coord::Shift;
use plotters::coord::combinators::{LogCoord, WithKeyPoints};
use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::coord::types::RangedCoordf64;
use plotters::drawing::DrawingAreaErrorKind;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use plotters::style::{FontStyle, register_font};
use std::ops::Range;
use std::path::Path;
use std::sync::Once;

mod measured_response;
pub use measured_response::{MEASURED_BAND_SIGMA, MeasuredPoint, MeasuredResponseData, fig_measured_response};

/// The bundled font (DejaVu Sans; license in `assets/DejaVuSans-LICENSE.txt`).
static FONT: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");
static FONT_ONCE: Once = Once::new();

fn ensure_font() {
    FONT_ONCE.call_once(|| {
        for style in [FontStyle::Normal, FontStyle::Bold, FontStyle::Italic, FontStyle::Oblique] {
            // The font is a compile-time constant that parses: a failure is a build defect.
            if register_font("sans-serif", style, FONT).is_err() {
                panic!("the bundled DejaVu Sans font does not parse");
            }
        }
    });
}

/// Image format of a figure.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// PNG, 8-bit RGB.
    Png,
    /// SVG text (UTF-8).
    Svg,
}

impl Format {
    /// The format a file name asks for by its extension (`.png` or `.svg`,
    /// any case); None for another or no extension.
    pub fn of_path(path: &Path) -> Option<Format> {
        match path.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase()).as_deref() {
            Some("png") => Some(Format::Png),
            Some("svg") => Some(Format::Svg),
            _ => None,
        }
    }

    /// The file-name extension: `png` or `svg`.
    pub fn extension(self) -> &'static str {
        match self {
            Format::Png => "png",
            Format::Svg => "svg",
        }
    }
}

/// A rendered figure.
#[derive(Debug, Clone, PartialEq)]
pub enum Image {
    /// An encoded PNG file.
    Png(Vec<u8>),
    /// An SVG document.
    Svg(String),
}

impl Image {
    /// The file's bytes.
    pub fn as_bytes(&self) -> &[u8] {
        match self {
            Image::Png(b) => b,
            Image::Svg(s) => s.as_bytes(),
        }
    }

    /// Its format.
    pub fn format(&self) -> Format {
        match self {
            Image::Png(_) => Format::Png,
            Image::Svg(_) => Format::Svg,
        }
    }

    /// The SVG text (`None` for a PNG).
    pub fn svg(&self) -> Option<&str> {
        match self {
            Image::Svg(s) => Some(s),
            Image::Png(_) => None,
        }
    }

    /// Writes the file.
    pub fn write_to(&self, path: impl AsRef<Path>) -> std::io::Result<()> {
        std::fs::write(path, self.as_bytes())
    }
}

/// Why a figure could not be drawn.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RenderError {
    /// The requested size is unusable.
    #[error("figure size {0}×{1} px is outside {MIN_SIZE:?} … {MAX_SIZE:?}")]
    Size(u32, u32),
    /// The data hold nothing to draw.
    #[error("nothing to plot: {0}")]
    NoData(String),
    /// The drawing backend failed.
    #[error("drawing failed: {0}")]
    Draw(String),
    /// The PNG encoder failed.
    #[error("PNG encoding failed: {0}")]
    Png(String),
}

/// Smallest figure size accepted (width, height) \[px\].
pub const MIN_SIZE: (u32, u32) = (240, 180);
/// Largest figure size accepted (width, height) \[px\].
pub const MAX_SIZE: (u32, u32) = (8000, 8000);
/// The size used by the report and the CLI (width, height) \[px\].
pub const DEFAULT_SIZE: (u32, u32) = (1000, 640);

type DrawResult<DB> = Result<(), DrawingAreaErrorKind<<DB as DrawingBackend>::ErrorType>>;

/// A figure's drawing routine, for any backend.
trait Plot {
    fn plot<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>, st: &Style) -> DrawResult<DB>;
}

/// Font sizes scaled to the figure.
struct Style {
    scale: f64,
}

impl Style {
    fn new((w, h): (u32, u32)) -> Self {
        // 1 at 1000×640; text stays readable on small and large figures alike.
        Style { scale: ((w as f64 / 1000.0).min(h as f64 / 640.0)).clamp(0.55, 4.0) }
    }
    fn px(&self, base: f64) -> f64 {
        (base * self.scale).max(9.0)
    }
    fn font(&self, base: f64) -> TextStyle<'static> {
        ("sans-serif", self.px(base)).into_font().color(&BLACK)
    }
    fn title(&self) -> TextStyle<'static> {
        self.font(20.0)
    }
    fn label(&self) -> TextStyle<'static> {
        self.font(14.0)
    }
    fn desc(&self) -> TextStyle<'static> {
        self.font(16.0)
    }
    fn legend(&self) -> TextStyle<'static> {
        self.font(14.0)
    }
    fn i(&self, base: f64) -> i32 {
        (base * self.scale).round() as i32
    }
}

fn render<P: Plot>(p: &P, format: Format, size: (u32, u32)) -> Result<Image, RenderError> {
    let (w, h) = size;
    if w < MIN_SIZE.0 || h < MIN_SIZE.1 || w > MAX_SIZE.0 || h > MAX_SIZE.1 {
        return Err(RenderError::Size(w, h));
    }
    ensure_font();
    let st = Style::new(size);
    match format {
        Format::Png => {
            // Drawn at twice the size and averaged down 2×2: anti-aliased lines
            // (the bitmap backend draws them aliased) and smooth thick strokes.
            let ss: u32 = if (w as u64) * (h as u64) <= 4_000_000 { 2 } else { 1 };
            let big = (w * ss, h * ss);
            let st = Style::new(big);
            let mut rgb = vec![255u8; big.0 as usize * big.1 as usize * 3];
            {
                paint(&BitMapBackend::with_buffer(&mut rgb, big).into_drawing_area(), p, &st)?;
            }
            let rgb = if ss == 2 { downsample2(&rgb, w as usize, h as usize) } else { rgb };
            encode_png(&rgb, w, h)
        }
        Format::Svg => {
            let mut s = String::new();
            {
                paint(&SVGBackend::with_string(&mut s, size).into_drawing_area(), p, &st)?;
            }
            Ok(Image::Svg(s))
        }
    }
}

/// Fills `root` white, draws `p` on it and presents it.
fn paint<DB: DrawingBackend, P: Plot>(root: &DrawingArea<DB, Shift>, p: &P, st: &Style) -> Result<(), RenderError> {
    let draw_err = |e: DrawingAreaErrorKind<DB::ErrorType>| RenderError::Draw(e.to_string());
    root.fill(&WHITE).map_err(draw_err)?;
    p.plot(root, st).map_err(draw_err)?;
    root.present().map_err(draw_err)
}

/// Averages 2×2 blocks of an RGB image of (2w, 2h) pixels.
fn downsample2(rgb: &[u8], w: usize, h: usize) -> Vec<u8> {
    let mut out = vec![0u8; w * h * 3];
    let row = 2 * w * 3;
    for y in 0..h {
        for x in 0..w {
            for c in 0..3 {
                let i = 2 * y * row + 2 * x * 3 + c;
                let sum = rgb[i] as u32 + rgb[i + 3] as u32 + rgb[i + row] as u32 + rgb[i + row + 3] as u32;
                out[(y * w + x) * 3 + c] = ((sum + 2) / 4) as u8;
            }
        }
    }
    out
}

fn encode_png(rgb: &[u8], w: u32, h: u32) -> Result<Image, RenderError> {
    let mut out = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut out, w, h);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let mut writer = enc.write_header().map_err(|e| RenderError::Png(e.to_string()))?;
        writer.write_image_data(rgb).map_err(|e| RenderError::Png(e.to_string()))?;
        writer.finish().map_err(|e| RenderError::Png(e.to_string()))?;
    }
    Ok(Image::Png(out))
}

// ---------------------------------------------------------------- helpers

/// Colours of the x, y, z components (matplotlib's tab10 blue, orange, green).
const AXIS_COLORS: [RGBColor; 3] = [RGBColor(31, 119, 180), RGBColor(255, 127, 14), RGBColor(44, 160, 44)];
/// Colours for channels (tab10).
const PALETTE: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
    RGBColor(127, 127, 127),
];
const BEFORE_COLOR: RGBColor = RGBColor(214, 39, 40);
const AFTER_COLOR: RGBColor = RGBColor(31, 119, 180);
const GRID_LIGHT: RGBColor = RGBColor(236, 236, 236);
const GRID_BOLD: RGBColor = RGBColor(200, 200, 200);

/// Tick label: up to 4 significant digits, exponent form for very small or large values.
fn fmt_tick(v: f64, span: f64) -> String {
    if !v.is_finite() || v == 0.0 || v.abs() < span.abs() * 1e-9 {
        return "0".into();
    }
    let a = v.abs();
    if !(1e-3..1e5).contains(&a) {
        let e = a.log10().floor() as i32;
        let m = trim_zeros(format!("{:.2}", v / 10f64.powi(e)));
        return format!("{m}e{e}");
    }
    let dec = (3 - a.log10().floor() as i32).clamp(0, 6) as usize;
    trim_zeros(format!("{v:.dec$}"))
}

fn trim_zeros(s: String) -> String {
    if s.contains('.') { s.trim_end_matches('0').trim_end_matches('.').to_string() } else { s }
}

/// \[lo, hi\] of the finite values, padded by `pad` of the span (a flat series gets a unit-scaled span).
fn padded_range(values: impl Iterator<Item = f64>, pad: f64) -> Option<Range<f64>> {
    let (lo, hi) =
        values.filter(|v| v.is_finite()).fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)));
    if lo > hi {
        return None;
    }
    let span = hi - lo;
    let span = if span > 1e-12 * lo.abs().max(hi.abs()) && span > 0.0 { span } else { lo.abs().max(1e-3) * 0.2 };
    Some(lo - pad * span..hi + pad * span)
}

/// Log-axis range covering the positive finite values with a margin of a
/// factor 1.25 on each side.
fn log_range(values: impl Iterator<Item = f64>) -> Option<Range<f64>> {
    let (lo, hi) = values
        .filter(|v| v.is_finite() && *v > 0.0)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)));
    if lo > hi {
        return None;
    }
    let (lo, hi) = (lo / 1.25, hi * 1.25);
    Some(if hi > lo * 2.0 { lo..hi } else { lo / 2.0..hi * 2.0 })
}

/// Tick values of a log axis: 1-2-3-…-9 per decade on short ranges, 1-2-5 on
/// medium ones, decades (thinned) on long ones; the light grid at every 1…9.
fn log_ticks(r: &Range<f64>) -> (Vec<f64>, Vec<f64>) {
    let decades = (r.end / r.start).log10();
    let (mults, every): (&[f64], i32) = if decades < 1.2 {
        (&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0], 1)
    } else if decades < 3.0 {
        (&[1.0, 2.0, 5.0], 1)
    } else {
        (&[1.0], (decades / 8.0).ceil().max(1.0) as i32)
    };
    let (e0, e1) = (r.start.log10().floor() as i32, r.end.log10().ceil() as i32);
    let (mut bold, mut light) = (Vec::new(), Vec::new());
    for e in e0..=e1 {
        let p = 10f64.powi(e);
        for m in 1..10 {
            let v = m as f64 * p;
            if !r.contains(&v) {
                continue;
            }
            if mults.contains(&(m as f64)) && (e - e0) % every == 0 {
                bold.push(v);
            } else if decades < 6.0 {
                light.push(v);
            }
        }
    }
    (bold, light)
}

/// A log axis with chosen bold and light tick points.
type LogAxis = WithKeyPoints<LogCoord<f64>>;

/// A log axis over `r` with [`log_ticks`].
fn log_axis(r: Range<f64>) -> LogAxis {
    let (bold, light) = log_ticks(&r);
    r.log_scale().with_key_points(bold).with_light_points(light)
}

/// Index runs of a series where `present(i)` holds and the time steps stay
/// below `max_gap_s`.
fn runs(t: &[f64], present: impl Fn(usize) -> bool, max_gap_s: f64) -> Vec<Range<usize>> {
    let mut out = Vec::new();
    let mut start: Option<usize> = None;
    for i in 0..t.len() {
        let ok = present(i) && t[i].is_finite();
        let gap = i > 0 && t[i] - t[i - 1] > max_gap_s;
        match (start, ok) {
            (Some(s), true) if gap => {
                out.push(s..i);
                start = Some(i);
            }
            (None, true) => start = Some(i),
            (Some(s), false) => {
                out.push(s..i);
                start = None;
            }
            _ => {}
        }
    }
    if let Some(s) = start {
        out.push(s..t.len());
    }
    out
}

/// Typical time step: the median of the first few thousand steps.
fn typical_step(t: &[f64]) -> f64 {
    let mut d: Vec<f64> = t.windows(2).take(4096).map(|w| w[1] - w[0]).filter(|d| *d > 0.0).collect();
    if d.is_empty() {
        return 1.0;
    }
    gsens_core::stats::median_high_in_place(&mut d)
}

/// Polylines of (t, y) with gaps broken, each decimated to at most `2·buckets`
/// points keeping each bucket's min and max (the visual envelope).
fn polylines(t: &[f64], y: impl Fn(usize) -> Option<f64>, buckets: usize) -> Vec<Vec<(f64, f64)>> {
    let max_gap = 3.0 * typical_step(t);
    let value = |i: usize| y(i).filter(|v| v.is_finite());
    let rs = runs(t, |i| value(i).is_some(), max_gap);
    let total: usize = rs.iter().map(|r| r.len()).sum();
    let per_bucket = total.div_ceil(buckets.max(1)).max(1);
    rs.into_iter()
        .map(|r| {
            if per_bucket <= 2 {
                return r.map(|i| (t[i], value(i).unwrap_or(0.0))).collect();
            }
            let mut line = Vec::with_capacity(2 * r.len() / per_bucket + 2);
            let mut i = r.start;
            while i < r.end {
                let end = (i + per_bucket).min(r.end);
                let (mut imin, mut imax) = (i, i);
                for j in i..end {
                    let v = value(j).unwrap_or(0.0);
                    if v < value(imin).unwrap_or(0.0) {
                        imin = j;
                    }
                    if v > value(imax).unwrap_or(0.0) {
                        imax = j;
                    }
                }
                let (a, b) = if imin <= imax { (imin, imax) } else { (imax, imin) };
                line.push((t[a], value(a).unwrap_or(0.0)));
                if b != a {
                    line.push((t[b], value(b).unwrap_or(0.0)));
                }
                i = end;
            }
            line
        })
        .filter(|l| !l.is_empty())
        .collect()
}

fn clamp_to(v: f64, r: &Range<f64>) -> f64 {
    v.clamp(r.start, r.end)
}

/// How a legend entry is marked.
#[derive(Debug, Clone, Copy)]
enum Mark {
    /// A solid line of a colour and width.
    Line(RGBAColor, u32),
    /// A dashed line.
    Dashed(RGBAColor),
    /// A filled box (a shaded band).
    Band(RGBAColor),
    /// A dot.
    Dot(RGBAColor),
}

/// Draws `entries` as rows of a legend in a strip at the top of `area`,
/// starting at `x0` px, and returns the rest of the area: a legend never hides data.
fn legend_strip<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[(String, Mark)],
    x0: i32,
    st: &Style,
) -> Result<DrawingArea<DB, Shift>, DrawingAreaErrorKind<DB::ErrorType>> {
    if entries.is_empty() {
        return Ok(area.clone());
    }
    let style = st.legend();
    let (w, _) = area.dim_in_pixel();
    let mark_w = st.i(26.0).max(14);
    let gap = st.i(6.0).max(3);
    let spacing = st.i(22.0).max(8);
    let line_h = (st.px(14.0) * 1.55).round() as i32;
    let mut rows: Vec<Vec<(usize, i32)>> = vec![vec![]];
    let mut x = x0;
    for (k, (text, _)) in entries.iter().enumerate() {
        let tw = area.estimate_text_size(text, &style)?.0 as i32;
        let need = mark_w + gap + tw;
        if x > x0 && x + need > w as i32 - st.i(10.0) {
            rows.push(vec![]);
            x = x0;
        }
        if let Some(r) = rows.last_mut() {
            r.push((k, x));
        }
        x += need + spacing;
    }
    let h = rows.len() as i32 * line_h + st.i(6.0);
    let (strip, rest) = area.split_vertically(h);
    for (r, row) in rows.iter().enumerate() {
        let y = st.i(4.0) + r as i32 * line_h + line_h / 2;
        for &(k, x) in row {
            let (text, mark) = &entries[k];
            match *mark {
                Mark::Line(c, width) => {
                    strip.draw(&PathElement::new(vec![(x, y), (x + mark_w, y)], c.stroke_width(width)))?
                }
                Mark::Dashed(c) => {
                    let d = mark_w / 3;
                    strip.draw(&PathElement::new(vec![(x, y), (x + d, y)], c.stroke_width(2)))?;
                    strip.draw(&PathElement::new(vec![(x + 2 * d, y), (x + mark_w, y)], c.stroke_width(2)))?;
                }
                Mark::Band(c) => {
                    strip.draw(&Rectangle::new([(x, y - line_h / 3), (x + mark_w, y + line_h / 3)], c.filled()))?
                }
                Mark::Dot(c) => strip.draw(&Circle::new((x + mark_w / 2, y), st.i(5.0).max(3), c.filled()))?,
            }
            strip.draw(&Text::new(
                text.clone(),
                (x + mark_w + gap, y),
                style.pos(Pos::new(HPos::Left, VPos::Center)),
            ))?;
        }
    }
    Ok(rest)
}

/// The area under a title line (the title drawn with a top margin: the font
/// backend draws glyphs slightly above their nominal box).
fn titled<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    st: &Style,
) -> Result<DrawingArea<DB, Shift>, DrawingAreaErrorKind<DB::ErrorType>> {
    root.margin(st.i(8.0), 0, 0, 0).titled(title, st.title())
}

fn check_size(n: usize, what: &str) -> Result<(), RenderError> {
    if n == 0 { Err(RenderError::NoData(format!("{what} is empty"))) } else { Ok(()) }
}

/// Tick labels for an axis spanning `r` ([`fmt_tick`] with its span).
fn span_fmt(r: &Range<f64>) -> impl Fn(&f64) -> String + use<> {
    let span = r.end - r.start;
    move |v: &f64| fmt_tick(*v, span)
}

/// The layout and mesh of one chart: margins, label areas, axis descriptions and tick labels.
struct Frame<'s> {
    /// Top margin (before scaling).
    top: f64,
    /// Height of the x label area (before scaling).
    x_area: f64,
    /// Width of the y label area \[px\].
    y_area: i32,
    /// The x axis description, if drawn.
    x_desc: Option<&'s str>,
    /// The y axis description.
    y_desc: &'s str,
    /// How many y labels, if not the default.
    y_labels: Option<usize>,
    fmt_x: &'s dyn Fn(&f64) -> String,
    fmt_y: &'s dyn Fn(&f64) -> String,
}

type Chart<'a, DB, X, Y> = ChartContext<'a, DB, Cartesian2d<X, Y>>;
type AreaResult<DB, T> = Result<T, DrawingAreaErrorKind<<DB as DrawingBackend>::ErrorType>>;

/// A chart on `area` over `x` × `y` laid out by `frame`, its mesh (grid, ticks
/// and axis descriptions) already drawn.
fn framed_chart<'a, DB, X, Y>(
    area: &'a DrawingArea<DB, Shift>,
    st: &Style,
    frame: &Frame,
    x: X,
    y: Y,
) -> AreaResult<DB, Chart<'a, DB, X::CoordDescType, Y::CoordDescType>>
where
    DB: DrawingBackend,
    X: AsRangedCoord,
    Y: AsRangedCoord,
    X::CoordDescType: Ranged<ValueType = f64> + ValueFormatter<f64>,
    Y::CoordDescType: Ranged<ValueType = f64> + ValueFormatter<f64>,
{
    let mut chart = ChartBuilder::on(area)
        .margin(st.i(10.0))
        .margin_top(st.i(frame.top))
        .margin_right(st.i(24.0))
        .x_label_area_size(st.i(frame.x_area))
        .y_label_area_size(frame.y_area)
        .build_cartesian_2d(x, y)?;
    let mut mesh = chart.configure_mesh();
    if let Some(d) = frame.x_desc {
        mesh.x_desc(d);
    }
    if let Some(n) = frame.y_labels {
        mesh.y_labels(n);
    }
    mesh.y_desc(frame.y_desc)
        .x_label_formatter(frame.fmt_x)
        .y_label_formatter(frame.fmt_y)
        .max_light_lines(4)
        .label_style(st.label())
        .axis_desc_style(st.desc())
        .light_line_style(GRID_LIGHT)
        .bold_line_style(GRID_BOLD)
        .draw()?;
    Ok(chart)
}

/// A chart of a quantity over time `xr` × `yr` under a legend: the time axis
/// described at the bottom, 8 y labels, ticks formatted to the spans.
fn time_chart<'a, DB: DrawingBackend>(
    area: &'a DrawingArea<DB, Shift>,
    st: &Style,
    y_area: i32,
    y_desc: &str,
    xr: Range<f64>,
    yr: Range<f64>,
) -> AreaResult<DB, Chart<'a, DB, RangedCoordf64, RangedCoordf64>> {
    let (fmt_x, fmt_y) = (span_fmt(&xr), span_fmt(&yr));
    let frame = Frame {
        top: 2.0,
        x_area: 48.0,
        y_area,
        x_desc: Some("time t [s]"),
        y_desc,
        y_labels: Some(8),
        fmt_x: &fmt_x,
        fmt_y: &fmt_y,
    };
    framed_chart(area, st, &frame, xr, yr)
}

/// A log-log chart over `xr` × `yr` ([`log_axis`]) under a legend, its axes
/// described by `(x_desc, y_desc)`.
fn loglog_chart<'a, DB: DrawingBackend>(
    area: &'a DrawingArea<DB, Shift>,
    st: &Style,
    y_area: i32,
    (x_desc, y_desc): (&str, &str),
    xr: Range<f64>,
    yr: Range<f64>,
) -> AreaResult<DB, Chart<'a, DB, LogAxis, LogAxis>> {
    let fmt = |v: &f64| fmt_tick(*v, 0.0);
    let frame = Frame {
        top: 2.0,
        x_area: 48.0,
        y_area,
        x_desc: Some(x_desc),
        y_desc,
        y_labels: None,
        fmt_x: &fmt,
        fmt_y: &fmt,
    };
    framed_chart(area, st, &frame, log_axis(xr), log_axis(yr))
}

/// Draws the series `y` over `t` as [`polylines`] of `buckets`, in `style`.
fn draw_polylines<DB, X, Y>(
    chart: &mut Chart<'_, DB, X, Y>,
    t: &[f64],
    y: impl Fn(usize) -> Option<f64>,
    buckets: usize,
    style: ShapeStyle,
) -> DrawResult<DB>
where
    DB: DrawingBackend,
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
{
    for l in polylines(t, y, buckets) {
        chart.draw_series(LineSeries::new(l, style))?;
    }
    Ok(())
}

// ---------------------------------------------------------------- Fig. 3

/// The loop response to plot (the paper's Fig. 3).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ResponseData {
    /// Frequencies \[Hz\], increasing, positive.
    pub frequency_hz: Vec<f64>,
    /// |L(j2πf)| \[rad/Hz\].
    pub magnitude_rad_per_hz: Vec<f64>,
    /// Phase of L \[deg\], unwrapped along frequency.
    pub phase_deg: Vec<f64>,
    /// Frequency of the peak of |L| \[Hz\].
    pub peak_hz: f64,
    /// |L| at the peak \[rad/Hz\].
    pub peak_rad_per_hz: f64,
    /// Where |L| is above peak/√2 \[Hz\], if known.
    pub half_power_band_hz: Option<[f64; 2]>,
    /// The loop in words (drawn in the title), e.g. [`LoopModel`]'s `Display`.
    pub description: String,
}

/// A response table's range that is not 0 < f_min < f_max with at least
/// two points ([`ResponseData::check_range`]).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct ResponseRangeError(String);

impl ResponseData {
    /// Checks a table's range: 0 < `f_min_hz` < `f_max_hz` and `points` ≥ 2;
    /// the message names the three by `name` (a command line's flag, say).
    pub fn check_range(
        f_min_hz: f64,
        f_max_hz: f64,
        points: usize,
        name: impl Fn(&str) -> String,
    ) -> Result<(), ResponseRangeError> {
        if f_min_hz > 0.0 && f_max_hz > f_min_hz && points >= 2 {
            return Ok(());
        }
        let (min, max, points) = (name("f_min_hz"), name("f_max_hz"), name("points"));
        Err(ResponseRangeError(format!("need 0 < {min} < {max} and {points} ≥ 2")))
    }

    /// Samples the response of `model` at `points` log-spaced frequencies from
    /// `f_min_hz` to `f_max_hz` (below the Nyquist frequency of its update
    /// rate) with its peak and half-power band, all from the loop itself
    /// ([`LoopModel::response`], [`LoopModel::peak`], [`LoopModel::half_power_band_hz`]).
    pub fn from_loop(
        model: &LoopModel,
        f_min_hz: f64,
        f_max_hz: f64,
        points: usize,
        description: impl Into<String>,
    ) -> Result<Self, LoopError> {
        let peak = model.peak()?;
        let band = model.half_power_band_hz()?;
        let nyq = model.nyquist_hz().unwrap_or(f64::INFINITY);
        let hi = f_max_hz.min(0.999 * nyq);
        let n = points.max(2);
        let ratio = (hi / f_min_hz).powf(1.0 / (n - 1) as f64);
        let frequency_hz: Vec<f64> = (0..n).map(|k| f_min_hz * ratio.powi(k as i32)).collect();
        let l: Vec<Complex<f64>> = frequency_hz.iter().map(|&f| model.response(f)).collect();
        let mut phase_deg = Vec::with_capacity(n);
        let mut prev = f64::NAN;
        for z in &l {
            let mut p = z.arg().to_degrees();
            if prev.is_finite() {
                p -= 360.0 * ((p - prev) / 360.0).round();
            }
            phase_deg.push(p);
            prev = p;
        }
        Ok(ResponseData {
            magnitude_rad_per_hz: l.iter().map(|z| z.norm()).collect(),
            frequency_hz,
            phase_deg,
            peak_hz: peak.f_hz,
            peak_rad_per_hz: peak.rad_per_hz,
            half_power_band_hz: Some(band),
            description: description.into(),
        })
    }
}

impl Plot for ResponseData {
    fn plot<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>, st: &Style) -> DrawResult<DB> {
        let title = format!("PLL frequency response L = φ/Δf: {}", self.description);
        let area = titled(root, &title, st)?;
        let f = &self.frequency_hz;
        let (f0, f1) = (f[0], f[f.len() - 1]);
        let band = self.half_power_band_hz.map(|[lo, hi]| (lo.max(f0), hi.min(f1))).filter(|(lo, hi)| hi > lo);
        let y_area = st.i(70.0);
        let area = legend_strip(&area, &self.legend(band.is_some()), y_area + st.i(10.0), st)?;
        let h = area.dim_in_pixel().1 as i32;
        let (top, bottom) = area.split_vertically(h * 60 / 100);
        self.magnitude_panel(&top, st, y_area, band)?;
        self.phase_panel(&bottom, st, y_area, band)
    }
}

impl ResponseData {
    /// Fig. 3's colours: the response's line, the peak's, the half-power band's shade.
    fn colors() -> (RGBAColor, RGBAColor, RGBAColor) {
        (AFTER_COLOR.mix(1.0), BEFORE_COLOR.mix(1.0), RGBColor(255, 200, 120).mix(0.35))
    }

    /// The legend: |L|, its peak with the shaking period it implies, and the
    /// half-power band when it is drawn (`band`).
    fn legend(&self, band: bool) -> Vec<(String, Mark)> {
        let (line, peak_color, shade) = Self::colors();
        let mut entries = vec![
            ("|L(j2πf)|".to_string(), Mark::Line(line, 3)),
            (
                format!(
                    "peak {:.3} rad/Hz at {:.3} Hz: shake with a period of about {:.2} s",
                    self.peak_rad_per_hz,
                    self.peak_hz,
                    1.0 / self.peak_hz
                ),
                Mark::Dot(peak_color),
            ),
        ];
        if let (true, Some([blo, bhi])) = (band, self.half_power_band_hz) {
            entries.push((
                format!("half-power band {blo:.2}–{bhi:.2} Hz (periods {:.2}–{:.2} s)", 1.0 / bhi, 1.0 / blo),
                Mark::Band(shade),
            ));
        }
        entries
    }

    /// The top panel: |L| on a log frequency axis, the peak marked, the band shaded.
    fn magnitude_panel<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        st: &Style,
        y_area: i32,
        band: Option<(f64, f64)>,
    ) -> DrawResult<DB> {
        let (line, peak_color, shade) = Self::colors();
        let f = &self.frequency_hz;
        let ymax = self.magnitude_rad_per_hz.iter().cloned().fold(self.peak_rad_per_hz, f64::max) * 1.1;
        let fmt_log = |v: &f64| fmt_tick(*v, 0.0);
        let fmt_mag = |v: &f64| fmt_tick(*v, ymax);
        let frame = Frame {
            top: 10.0,
            x_area: 30.0,
            y_area,
            x_desc: None,
            y_desc: "|L| [rad/Hz]",
            y_labels: Some(6),
            fmt_x: &fmt_log,
            fmt_y: &fmt_mag,
        };
        let mut chart = framed_chart(area, st, &frame, log_axis(f[0]..f[f.len() - 1]), 0.0..ymax)?;
        if let Some((lo, hi)) = band {
            chart.draw_series(std::iter::once(Rectangle::new([(lo, 0.0), (hi, ymax)], shade.filled())))?;
        }
        chart.draw_series(LineSeries::new(
            f.iter().cloned().zip(self.magnitude_rad_per_hz.iter().cloned()),
            line.stroke_width(st.i(2.5).max(1) as u32),
        ))?;
        chart.draw_series(std::iter::once(Circle::new(
            (self.peak_hz, self.peak_rad_per_hz),
            st.i(6.0).max(3),
            peak_color.filled(),
        )))?;
        Ok(())
    }

    /// The bottom panel: the phase of L in whole multiples of 45°, the peak's
    /// frequency dashed, the band shaded.
    fn phase_panel<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        st: &Style,
        y_area: i32,
        band: Option<(f64, f64)>,
    ) -> DrawResult<DB> {
        let (line, peak_color, shade) = Self::colors();
        let f = &self.frequency_hz;
        let (plo, phi) =
            self.phase_deg.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &p| (a.min(p), b.max(p)));
        let pr = (plo / 45.0).floor() * 45.0..(phi / 45.0).ceil() * 45.0;
        let fmt_log = |v: &f64| fmt_tick(*v, 0.0);
        let fmt_deg = |v: &f64| format!("{v:.0}");
        let frame = Frame {
            top: 10.0,
            x_area: 48.0,
            y_area,
            x_desc: Some("frequency f [Hz]"),
            y_desc: "phase of L [deg]",
            y_labels: Some(((pr.end - pr.start) / 45.0) as usize + 1),
            fmt_x: &fmt_log,
            fmt_y: &fmt_deg,
        };
        let mut chart = framed_chart(area, st, &frame, log_axis(f[0]..f[f.len() - 1]), pr.clone())?;
        if let Some((lo, hi)) = band {
            chart.draw_series(std::iter::once(Rectangle::new([(lo, pr.start), (hi, pr.end)], shade.filled())))?;
        }
        chart.draw_series(LineSeries::new(
            f.iter().cloned().zip(self.phase_deg.iter().cloned()),
            line.stroke_width(st.i(2.5).max(1) as u32),
        ))?;
        chart.draw_series(DashedLineSeries::new(
            vec![(self.peak_hz, pr.start), (self.peak_hz, pr.end)],
            st.i(6.0).max(2),
            st.i(4.0).max(2),
            peak_color.stroke_width(st.i(1.2).max(1) as u32),
        ))?;
        Ok(())
    }
}

/// The paper's Fig. 3: |L| (top) and its phase (bottom) versus frequency on a
/// log axis, the peak marked with the shaking period it suggests, the
/// half-power band shaded.
pub fn fig_response(data: &ResponseData, format: Format, size: (u32, u32)) -> Result<Image, RenderError> {
    check_size(data.frequency_hz.len(), "the frequency axis")?;
    let n = data.frequency_hz.len();
    if data.magnitude_rad_per_hz.len() != n || data.phase_deg.len() != n {
        return Err(RenderError::NoData("frequency, magnitude and phase differ in length".into()));
    }
    let ok = data.frequency_hz.iter().all(|f| f.is_finite() && *f > 0.0)
        && data.frequency_hz.windows(2).all(|w| w[1] > w[0])
        && data.magnitude_rad_per_hz.iter().chain(&data.phase_deg).all(|v| v.is_finite())
        && data.peak_hz > 0.0
        && data.peak_rad_per_hz.is_finite();
    if !ok || n < 2 {
        return Err(RenderError::NoData(
            "the response needs ≥ 2 increasing positive frequencies and finite values".into(),
        ));
    }
    render(data, format, size)
}

// ---------------------------------------------------------------- Fig. 4

/// The estimation process to plot (the paper's Fig. 4).
#[derive(Debug, Clone, Copy)]
pub struct EstimationData<'a> {
    /// Epoch times \[s\].
    pub t_s: &'a [f64],
    /// Specific force per epoch \[m/s²\] (IMU body frame).
    pub accel_mps2: &'a [[f64; 3]],
    /// Γ̂ and its 1σ as they evolved ([`gsens_calib::Calibration::history`]).
    pub history: &'a [HistoryPoint],
    /// The true Γ \[Hz/(m/s²)\] when known (simulation): drawn dashed.
    pub truth: Option<[f64; 3]>,
    /// Which axes the data observe; an unobservable component is drawn faint.
    pub observable: [bool; 3],
}

impl Plot for EstimationData<'_> {
    fn plot<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>, st: &Style) -> DrawResult<DB> {
        let area = titled(root, "Estimation process: specific force (top), g-sensitivity estimate (bottom)", st)?;
        let h = area.dim_in_pixel().1 as i32;
        let (top, bottom) = area.split_vertically(h * 42 / 100);
        let y_area = st.i(78.0);
        let t0 = self.t_s.iter().cloned().fold(f64::INFINITY, f64::min);
        let t1 = self.t_s.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
        let t1 = self.history.iter().map(|p| p.t_s).fold(t1, f64::max);
        let xr = t0..if t1 > t0 { t1 } else { t0 + 1.0 };
        self.accel_panel(&top, st, y_area, xr.clone())?;
        self.gamma_panel(&bottom, st, y_area, xr)
    }
}

impl EstimationData<'_> {
    /// The top panel: the specific force's components over the time range `xr`.
    fn accel_panel<DB: DrawingBackend>(
        &self,
        top: &DrawingArea<DB, Shift>,
        st: &Style,
        y_area: i32,
        xr: Range<f64>,
    ) -> DrawResult<DB> {
        let fmt_x = span_fmt(&xr);
        let buckets = (top.dim_in_pixel().0 as usize).max(200);
        let entries: Vec<(String, Mark)> =
            (0..3).map(|i| (format!("a{}", crate::AXES[i]), Mark::Line(AXIS_COLORS[i].mix(0.9), 3))).collect();
        let top = legend_strip(top, &entries, y_area + st.i(10.0), st)?;
        let ar = padded_range(self.accel_mps2.iter().flat_map(|a| a.iter().cloned()), 0.05).unwrap_or(-1.0..1.0);
        let fmt_a = span_fmt(&ar);
        let frame = Frame {
            top: 2.0,
            x_area: 30.0,
            y_area,
            x_desc: None,
            y_desc: "specific force a [m/s²]",
            y_labels: Some(6),
            fmt_x: &fmt_x,
            fmt_y: &fmt_a,
        };
        let mut chart = framed_chart(&top, st, &frame, xr, ar)?;
        for i in 0..3 {
            let style = AXIS_COLORS[i].mix(0.9).stroke_width(st.i(1.3).max(1) as u32);
            draw_polylines(&mut chart, self.t_s, |k| self.accel_mps2.get(k).map(|a| a[i]), buckets, style)?;
        }
        Ok(())
    }

    /// The Γ̂ panel's view: around the final estimates and the truth (of the
    /// observable axes, or all when none is), wide enough for ±4σ; the early,
    /// undetermined estimates are clipped to its edges.
    fn gamma_view(&self) -> Range<f64> {
        let any_obs = self.observable.iter().any(|&o| o);
        let ranged = |i: usize| self.observable[i] || !any_obs;
        let mut vals: Vec<f64> = vec![0.0];
        let mut sigma_max = 0.0f64;
        for i in (0..3).filter(|&i| ranged(i)) {
            if let Some(p) = self.history.last() {
                vals.push(p.gamma_hz_per_mps2[i]);
                if p.sigma_hz_per_mps2[i].is_finite() {
                    sigma_max = sigma_max.max(p.sigma_hz_per_mps2[i]);
                }
            }
            if let Some(t) = self.truth {
                vals.push(t[i]);
            }
        }
        let (lo, hi) = vals.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| (a.min(v), b.max(v)));
        let span = (hi - lo).max(1e-6);
        let pad = (0.3 * span).max(4.0 * sigma_max);
        lo - pad..hi + pad
    }

    /// The Γ̂ panel's legend: each component with its final value (or
    /// unobservable), the σ band, the truth when known.
    fn gamma_legend(&self) -> Vec<(String, Mark)> {
        let mut entries = Vec::new();
        for i in 0..3 {
            let strong = self.observable[i];
            let color = AXIS_COLORS[i].mix(if strong { 1.0 } else { 0.35 });
            let value = match self.history.last() {
                Some(p) if strong => format!(" → {:+.4}", p.gamma_hz_per_mps2[i]),
                _ => " (unobservable)".to_string(),
            };
            entries.push((format!("Γ{}{value}", crate::AXES[i]), Mark::Line(color, 3)));
        }
        entries.push(("±1σ (white residuals)".to_string(), Mark::Band(RGBColor(120, 120, 120).mix(0.25))));
        if self.truth.is_some() {
            entries.push(("truth (dashed)".to_string(), Mark::Dashed(BLACK.mix(0.8))));
        }
        entries
    }

    /// The bottom panel: Γ̂ with ±1σ bands and the truth, each component
    /// drawn where determined (its σ small against the view).
    fn gamma_panel<DB: DrawingBackend>(
        &self,
        bottom: &DrawingArea<DB, Shift>,
        st: &Style,
        y_area: i32,
        xr: Range<f64>,
    ) -> DrawResult<DB> {
        let gr = self.gamma_view();
        let bottom = legend_strip(bottom, &self.gamma_legend(), y_area + st.i(10.0), st)?;
        let mut chart = time_chart(&bottom, st, y_area, "Γ estimate [Hz/(m/s²)]", xr.clone(), gr.clone())?;
        // An estimate counts as determined once its σ is small against the view.
        let determined = |p: &HistoryPoint, i: usize| p.sigma_hz_per_mps2[i] <= 0.25 * (gr.end - gr.start);
        let hist = self.history;
        for i in 0..3 {
            let strong = self.observable[i];
            let color = AXIS_COLORS[i].mix(if strong { 1.0 } else { 0.35 });
            // ±1σ band, over the determined points.
            let band: Vec<&HistoryPoint> = hist.iter().filter(|p| determined(p, i)).collect();
            if band.len() >= 2 {
                let mut poly: Vec<(f64, f64)> = band
                    .iter()
                    .map(|p| (p.t_s, clamp_to(p.gamma_hz_per_mps2[i] + p.sigma_hz_per_mps2[i], &gr)))
                    .collect();
                poly.extend(
                    band.iter().rev().map(|p| (p.t_s, clamp_to(p.gamma_hz_per_mps2[i] - p.sigma_hz_per_mps2[i], &gr))),
                );
                chart.draw_series(std::iter::once(Polygon::new(
                    poly,
                    AXIS_COLORS[i].mix(if strong { 0.22 } else { 0.08 }).filled(),
                )))?;
            }
            if let Some(t) = self.truth {
                let y = clamp_to(t[i], &gr);
                chart.draw_series(DashedLineSeries::new(
                    vec![(xr.start, y), (xr.end, y)],
                    st.i(10.0).max(3),
                    st.i(6.0).max(2),
                    AXIS_COLORS[i].mix(0.9).stroke_width(st.i(1.5).max(1) as u32),
                ))?;
            }
            // Drawn where determined: before an axis is excited its estimate is
            // arbitrary and would only clutter the view.
            let width = if strong { st.i(2.5).max(1) as u32 } else { st.i(1.2).max(1) as u32 };
            let mut k = 0;
            while k < hist.len() {
                let mut end = k;
                while end < hist.len() && determined(&hist[end], i) {
                    end += 1;
                }
                if end > k {
                    let pts = hist[k..end].iter().map(|p| (p.t_s, clamp_to(p.gamma_hz_per_mps2[i], &gr)));
                    chart.draw_series(LineSeries::new(pts, color.stroke_width(width)))?;
                    k = end;
                } else {
                    k += 1;
                }
            }
        }
        Ok(())
    }
}

/// The paper's Fig. 4: the specific force components over time (top) and the
/// components of Γ̂ as the estimator converges, with ±1σ bands (bottom); the
/// truth dashed when known. The view is centred on the final estimates; a
/// component is drawn once its σ is below a quarter of the view (before its
/// axis is excited the estimate is arbitrary), values outside it clipped to
/// its edge.
pub fn fig_estimation(data: &EstimationData, format: Format, size: (u32, u32)) -> Result<Image, RenderError> {
    check_size(data.t_s.len(), "the epoch series")?;
    if data.accel_mps2.len() != data.t_s.len() {
        return Err(RenderError::NoData("times and specific force differ in length".into()));
    }
    check_size(data.history.len(), "the estimate history")?;
    render(data, format, size)
}

// ---------------------------------------------------------------- Fig. 5

/// Phase error before and after compensation (the paper's Fig. 5).
#[derive(Debug, Clone, Copy)]
pub struct CompensationData<'a> {
    /// Epoch times \[s\].
    pub t_s: &'a [f64],
    /// Averaged phase error φ \[rad\]; `None` in gaps.
    pub before_rad: &'a [Option<f64>],
    /// φ − φ_aᵀΓ̂ \[rad\]; `None` in gaps.
    pub after_rad: &'a [Option<f64>],
    /// Which compensation the two series compare.
    pub kind: CompensationKind,
}

/// What a [`CompensationData`] figure compares.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum CompensationKind {
    /// The paper's Fig. 5: φ and φ − φ_aᵀΓ̂, after the fact.
    #[default]
    PostProcessing,
    /// In the loop: the g-induced phase error of a receiver without and with
    /// −aᵀΓ̂ fed into its NCOs (`gsens validate`).
    InTheLoop,
    /// A carrier phase and Doppler log: the tracks' common-mode carrier
    /// phase integrated from the rows, and the same less Γ̂'s part.
    CarrierPhase,
}

fn rms(v: impl Iterator<Item = f64>) -> f64 {
    let (s, n) = v.filter(|x| x.is_finite()).fold((0.0, 0usize), |(s, n), x| (s + x * x, n + 1));
    if n == 0 { f64::NAN } else { (s / n as f64).sqrt() }
}

impl Plot for CompensationData<'_> {
    fn plot<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>, st: &Style) -> DrawResult<DB> {
        let (title, before, after) = match self.kind {
            CompensationKind::PostProcessing => (
                "Effect of g-sensitivity compensation on the phase tracking error",
                "before compensation: φ",
                "after compensation: φ minus the modelled g-induced part",
            ),
            CompensationKind::InTheLoop => (
                "g-induced phase tracking error without and with compensation in the loop",
                "without compensation",
                "with the IMU's a·Γ estimate fed out of the NCO",
            ),
            CompensationKind::CarrierPhase => (
                "Effect of g-sensitivity compensation on the receiver's carrier phase",
                "before compensation: the tracks' common mode",
                "after compensation: less the modelled g-induced part",
            ),
        };
        let y_label = match self.kind {
            CompensationKind::CarrierPhase => "carrier phase, common mode [rad]",
            _ => "phase tracking error [rad]",
        };
        let area = titled(root, title, st)?;
        let y_area = st.i(78.0);
        let series: [(&[Option<f64>], RGBAColor, &str); 2] =
            [(self.before_rad, BEFORE_COLOR.mix(0.75), before), (self.after_rad, AFTER_COLOR.mix(0.95), after)];
        let entries: Vec<(String, Mark)> = series
            .iter()
            .map(|(d, c, name)| {
                (format!("{name} (RMS {:.4} rad)", rms(d.iter().flatten().cloned())), Mark::Line(*c, 3))
            })
            .collect();
        let area = legend_strip(&area, &entries, y_area + st.i(10.0), st)?;
        let t = self.t_s;
        let xr = t[0]..if t[t.len() - 1] > t[0] { t[t.len() - 1] } else { t[0] + 1.0 };
        let yr =
            padded_range(self.before_rad.iter().chain(self.after_rad).flatten().cloned(), 0.05).unwrap_or(-1.0..1.0);
        let mut chart = time_chart(&area, st, y_area, y_label, xr, yr)?;
        let buckets = (area.dim_in_pixel().0 as usize).max(200);
        for (data, color, _) in series {
            let style = color.stroke_width(st.i(1.3).max(1) as u32);
            draw_polylines(&mut chart, t, |k| data.get(k).copied().flatten(), buckets, style)?;
        }
        Ok(())
    }
}

/// The paper's Fig. 5: the averaged phase tracking error before compensation
/// and after (φ − φ_aᵀΓ̂) over time, with their RMS in the legend.
pub fn fig_compensation(data: &CompensationData, format: Format, size: (u32, u32)) -> Result<Image, RenderError> {
    check_size(data.t_s.len(), "the epoch series")?;
    if data.before_rad.len() != data.t_s.len() || data.after_rad.len() != data.t_s.len() {
        return Err(RenderError::NoData("times, phase before and phase after differ in length".into()));
    }
    if data.before_rad.iter().chain(data.after_rad).flatten().all(|v| !v.is_finite()) {
        return Err(RenderError::NoData("no phase error in the series".into()));
    }
    render(data, format, size)
}

// ---------------------------------------------------------------- C/N0

/// One channel's C/N0 series.
#[derive(Debug, Clone, Copy)]
pub struct Cn0Track<'a> {
    /// Receiver channel number.
    pub channel: u32,
    /// Satellite PRN.
    pub prn: u32,
    /// Time stamps \[s\].
    pub t_s: &'a [f64],
    /// C/N0 \[dB-Hz\].
    pub cn0_dbhz: &'a [f64],
    /// Whether the channel enters the average.
    pub used: bool,
}

struct Cn0Plot<'a, 'b>(&'b [Cn0Track<'a>]);

impl Plot for Cn0Plot<'_, '_> {
    fn plot<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>, st: &Style) -> DrawResult<DB> {
        let n_used = self.0.iter().filter(|c| c.used).count();
        let title = format!("C/N0 per channel: {n_used} of {} averaged (bold)", self.0.len());
        let area = titled(root, &title, st)?;
        let y_area = st.i(70.0);
        let grey = RGBColor(150, 150, 150).mix(0.7);
        // Used channels get the palette in channel order; unused ones are grey.
        let mut colors = vec![(grey, st.i(1.2).max(1) as u32); self.0.len()];
        let mut entries = Vec::new();
        let mut by_channel: Vec<usize> = (0..self.0.len()).collect();
        by_channel.sort_by_key(|&j| (self.0[j].channel, self.0[j].prn));
        let mut k = 0;
        for j in by_channel {
            let c = &self.0[j];
            if c.used {
                let color = PALETTE[k % PALETTE.len()].mix(1.0);
                k += 1;
                colors[j] = (color, st.i(2.5).max(2) as u32);
                entries.push((format!("ch {} PRN {}", c.channel, c.prn), Mark::Line(color, 3)));
            }
        }
        if n_used < self.0.len() {
            entries.push((format!("{} other channels, not used", self.0.len() - n_used), Mark::Line(grey, 1)));
        }
        let area = legend_strip(&area, &entries, y_area + st.i(10.0), st)?;
        let ts = || self.0.iter().flat_map(|c| c.t_s.iter().cloned());
        let xr = padded_range(ts(), 0.0).unwrap_or(0.0..1.0);
        let yr = padded_range(self.0.iter().flat_map(|c| c.cn0_dbhz.iter().cloned()), 0.08).unwrap_or(30.0..50.0);
        let mut chart = time_chart(&area, st, y_area, "C/N0 [dB-Hz]", xr, yr)?;
        let buckets = (area.dim_in_pixel().0 as usize).max(200);
        // Unused first, so that the used ones lie on top.
        for pass_used in [false, true] {
            for (c, &(color, width)) in self.0.iter().zip(&colors).filter(|(c, _)| c.used == pass_used) {
                draw_polylines(&mut chart, c.t_s, |i| c.cn0_dbhz.get(i).copied(), buckets, color.stroke_width(width))?;
            }
        }
        Ok(())
    }
}

/// C/N0 of every channel over time; the channels entering the average are
/// drawn bold and coloured and named in the legend, the others thin grey.
pub fn fig_cn0(tracks: &[Cn0Track], format: Format, size: (u32, u32)) -> Result<Image, RenderError> {
    check_size(tracks.len(), "the channel list")?;
    if tracks.iter().any(|c| c.t_s.len() != c.cn0_dbhz.len()) {
        return Err(RenderError::NoData("a channel's times and C/N0 differ in length".into()));
    }
    if tracks.iter().all(|c| c.t_s.is_empty()) {
        return Err(RenderError::NoData("every channel is empty".into()));
    }
    render(&Cn0Plot(tracks), format, size)
}

// ---------------------------------------------------------------- residual spectrum

/// Phase-error series whose spectra to compare.
#[derive(Debug, Clone, Copy)]
pub struct SpectrumData<'a> {
    /// Sample interval \[s\].
    pub interval_s: f64,
    /// φ − φ_aᵀΓ̂ over contiguous epochs \[rad\].
    pub residual_rad: &'a [f64],
    /// φ over the same epochs \[rad\], if wanted for comparison.
    pub before_rad: Option<&'a [f64]>,
    /// A frequency to mark \[Hz\] (the loop's natural frequency, where the
    /// g-induced error concentrates).
    pub marker_hz: Option<f64>,
}

/// Welch segment length for a record of `n` samples: a power of two giving
/// about 16 half-overlapping segments, between 64 samples and the record.
pub fn welch_segment_len(n: usize) -> usize {
    let target = (n / 8).max(64);
    let p = 1usize << (usize::BITS - 1 - target.leading_zeros());
    p.min(n)
}

/// A named, coloured curve of (frequency, density) points.
type Curve = (String, RGBAColor, Vec<(f64, f64)>);

struct SpectrumPlot {
    curves: Vec<Curve>,
    marker_hz: Option<f64>,
    segments: usize,
}

impl Plot for SpectrumPlot {
    fn plot<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>, st: &Style) -> DrawResult<DB> {
        let title = format!("Phase-error spectrum (Welch, {} Hann segments)", self.segments);
        let area = titled(root, &title, st)?;
        let y_area = st.i(78.0);
        let all = || self.curves.iter().flat_map(|c| c.2.iter());
        let xr = log_range(all().map(|p| p.0)).unwrap_or(0.01..10.0);
        let yr = log_range(all().map(|p| p.1)).unwrap_or(1e-8..1.0);
        let marker = self.marker_hz.filter(|f| xr.contains(f));
        let marker_color = RGBColor(90, 90, 90).mix(0.8);
        let mut entries: Vec<(String, Mark)> =
            self.curves.iter().map(|(name, color, _)| (name.clone(), Mark::Line(*color, 3))).collect();
        if let Some(f) = marker {
            entries.push((format!("loop natural frequency {f:.3} Hz"), Mark::Dashed(marker_color)));
        }
        let area = legend_strip(&area, &entries, y_area + st.i(10.0), st)?;
        let mut chart = loglog_chart(&area, st, y_area, ("frequency f [Hz]", "PSD [rad²/Hz]"), xr, yr.clone())?;
        if let Some(f) = marker {
            chart.draw_series(DashedLineSeries::new(
                vec![(f, yr.start), (f, yr.end)],
                st.i(8.0).max(3),
                st.i(5.0).max(2),
                marker_color.stroke_width(st.i(1.2).max(1) as u32),
            ))?;
        }
        for (_, color, pts) in &self.curves {
            chart.draw_series(LineSeries::new(pts.iter().cloned(), color.stroke_width(st.i(2.0).max(1) as u32)))?;
        }
        Ok(())
    }
}

/// Welch PSD of the residual φ − φ_aᵀΓ̂ (and of φ before compensation when
/// given) on log-log axes, the loop's natural frequency marked: what
/// compensation removed shows as the gap between the curves around it.
pub fn fig_residual_spectrum(data: &SpectrumData, format: Format, size: (u32, u32)) -> Result<Image, RenderError> {
    let n = data.residual_rad.len();
    let seg = welch_segment_len(n);
    let psd = welch_psd(data.residual_rad, data.interval_s, seg)
        .ok_or_else(|| RenderError::NoData("the residual needs ≥ 8 samples and a positive interval".into()))?;
    let pts = |p: &crate::spectrum::Psd| -> Vec<(f64, f64)> {
        p.frequency_hz.iter().cloned().zip(p.density.iter().cloned()).skip(1).filter(|(_, d)| *d > 0.0).collect()
    };
    let mut curves = Vec::new();
    if let Some(b) = data.before_rad
        && let Some(pb) = welch_psd(b, data.interval_s, welch_segment_len(b.len()))
    {
        curves.push(("before compensation".to_string(), BEFORE_COLOR.mix(0.8), pts(&pb)));
    }
    curves.push(("after compensation".to_string(), AFTER_COLOR.mix(1.0), pts(&psd)));
    if curves.iter().all(|c| c.2.is_empty()) {
        return Err(RenderError::NoData("the spectrum is zero everywhere".into()));
    }
    render(&SpectrumPlot { curves, marker_hz: data.marker_hz, segments: psd.segments }, format, size)
}

// ---------------------------------------------------------------- Allan deviation

/// Allan deviation of a simulated oscillator and of its model.
#[derive(Debug, Clone, Copy)]
pub struct AllanData<'a> {
    /// Averaging times τ \[s\].
    pub taus_s: &'a [f64],
    /// σ_y(τ) measured on the simulated fractional frequency (NaN where undefined).
    pub simulated: &'a [f64],
    /// σ_y(τ) of the preset's power-law model.
    pub theory: &'a [f64],
    /// The oscillator's name, e.g. `OCXO preset`.
    pub label: &'a str,
}

impl Plot for AllanData<'_> {
    fn plot<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>, st: &Style) -> DrawResult<DB> {
        let title = format!("Allan deviation of the simulated oscillator ({})", self.label);
        let area = titled(root, &title, st)?;
        let y_area = st.i(78.0);
        let keep = |v: &[f64]| -> Vec<(f64, f64)> {
            self.taus_s
                .iter()
                .cloned()
                .zip(v.iter().cloned())
                .filter(|(t, s)| *t > 0.0 && *s > 0.0 && s.is_finite())
                .collect()
        };
        let (sim, th) = (keep(self.simulated), keep(self.theory));
        let tc = RGBColor(60, 60, 60).mix(1.0);
        let sc = AFTER_COLOR.mix(1.0);
        let entries = vec![
            ("simulated (overlapping Allan deviation)".to_string(), Mark::Dot(sc)),
            ("model: σy² = h₀/(2τ) + 2·ln2·h₋₁ + (2π²/3)·h₋₂·τ".to_string(), Mark::Dashed(tc)),
        ];
        let area = legend_strip(&area, &entries, y_area + st.i(10.0), st)?;
        let xr = log_range(sim.iter().chain(&th).map(|p| p.0)).unwrap_or(0.01..100.0);
        let yr = log_range(sim.iter().chain(&th).map(|p| p.1)).unwrap_or(1e-13..1e-9);
        let descs = ("averaging time τ [s]", "Allan deviation σy(τ)");
        let mut chart = loglog_chart(&area, st, y_area, descs, xr, yr)?;
        chart.draw_series(DashedLineSeries::new(th, st.i(10.0).max(3), st.i(6.0).max(2), tc.stroke_width(2)))?;
        chart.draw_series(LineSeries::new(sim.iter().cloned(), sc.stroke_width(st.i(1.5).max(1) as u32)))?;
        chart.draw_series(sim.iter().map(|&p| Circle::new(p, st.i(4.0).max(2), sc.filled())))?;
        Ok(())
    }
}

/// Allan deviation of a simulated oscillator (points) against its preset's
/// power-law model (dashed), log-log.
pub fn fig_allan(data: &AllanData, format: Format, size: (u32, u32)) -> Result<Image, RenderError> {
    check_size(data.taus_s.len(), "the τ list")?;
    if data.simulated.len() != data.taus_s.len() || data.theory.len() != data.taus_s.len() {
        return Err(RenderError::NoData("τ, simulated and theory differ in length".into()));
    }
    if !data.simulated.iter().chain(data.theory).any(|s| s.is_finite() && *s > 0.0) {
        return Err(RenderError::NoData("no positive Allan deviation".into()));
    }
    render(data, format, size)
}

// ---------------------------------------------------------------- lock margin

/// The lock margin over the loop's bandwidth (`gsens predict --figure`).
#[derive(Debug, Clone, Copy)]
pub struct LockMarginData<'a> {
    /// Noise bandwidths \[Hz\], increasing.
    pub bn_hz: &'a [f64],
    /// 3σ + θₑ without compensation \[rad\].
    pub without_rad: &'a [f64],
    /// 3σ + θₑ with compensation \[rad\].
    pub with_rad: &'a [f64],
    /// The lock threshold \[rad\] (π/4).
    pub threshold_rad: f64,
    /// The case in words (vibration level, oscillator), drawn in the title.
    pub label: &'a str,
}

impl Plot for LockMarginData<'_> {
    fn plot<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>, st: &Style) -> DrawResult<DB> {
        let title = format!("Lock margin over the loop bandwidth ({})", self.label);
        let area = titled(root, &title, st)?;
        let y_area = st.i(78.0);
        let keep = |v: &[f64]| -> Vec<(f64, f64)> {
            self.bn_hz
                .iter()
                .cloned()
                .zip(v.iter().cloned())
                .filter(|(b, s)| *b > 0.0 && *s > 0.0 && s.is_finite())
                .collect()
        };
        let (without, with) = (keep(self.without_rad), keep(self.with_rad));
        let (wc, cc, tc) = (BEFORE_COLOR.mix(0.9), AFTER_COLOR.mix(1.0), RGBColor(60, 60, 60).mix(1.0));
        let entries = vec![
            ("without compensation: 3σ + dynamic stress".to_string(), Mark::Line(wc, 3)),
            ("with compensation".to_string(), Mark::Line(cc, 3)),
            (format!("lock threshold {:.2} rad (45°)", self.threshold_rad), Mark::Dashed(tc)),
        ];
        let area = legend_strip(&area, &entries, y_area + st.i(10.0), st)?;
        let xr = log_range(without.iter().chain(&with).map(|p| p.0)).unwrap_or(0.1..20.0);
        let yr = log_range(without.iter().chain(&with).map(|p| p.1).chain([self.threshold_rad])).unwrap_or(0.01..10.0);
        let descs = ("loop noise bandwidth Bn [Hz]", "3σ + θe [rad]");
        let mut chart = loglog_chart(&area, st, y_area, descs, xr.clone(), yr)?;
        let line = [(xr.start, self.threshold_rad), (xr.end, self.threshold_rad)];
        chart.draw_series(DashedLineSeries::new(line, st.i(10.0).max(3), st.i(6.0).max(2), tc.stroke_width(2)))?;
        chart.draw_series(LineSeries::new(without, wc.stroke_width(st.i(2.0).max(1) as u32)))?;
        chart.draw_series(LineSeries::new(with, cc.stroke_width(st.i(2.0).max(1) as u32)))?;
        Ok(())
    }
}

/// 3σ + θₑ of the phase error over the loop's bandwidth without and with
/// compensation, against the lock threshold, log-log: where each curve lies
/// below the threshold the loop keeps lock.
pub fn fig_lock_margin(data: &LockMarginData, format: Format, size: (u32, u32)) -> Result<Image, RenderError> {
    check_size(data.bn_hz.len(), "the bandwidth list")?;
    if data.without_rad.len() != data.bn_hz.len() || data.with_rad.len() != data.bn_hz.len() {
        return Err(RenderError::NoData("bandwidths, without and with differ in length".into()));
    }
    if !(data.threshold_rad.is_finite() && data.threshold_rad > 0.0) {
        return Err(RenderError::NoData("the lock threshold is not positive".into()));
    }
    render(data, format, size)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A table needs 0 < f_min < f_max and two points; the message names them as the caller does.
    #[test]
    fn a_response_range_is_checked() {
        assert!(ResponseData::check_range(0.05, 20.0, 2, |s: &str| s.to_string()).is_ok());
        for (lo, hi, n) in [(0.0, 20.0, 25), (5.0, 1.0, 25), (0.05, 20.0, 1), (f64::NAN, 20.0, 25)] {
            let e = ResponseData::check_range(lo, hi, n, |s| format!("<{s}>")).unwrap_err();
            assert_eq!(e.to_string(), "need 0 < <f_min_hz> < <f_max_hz> and <points> ≥ 2");
        }
    }

    #[test]
    fn ticks() {
        assert_eq!(fmt_tick(0.085, 0.1), "0.085");
        assert_eq!(fmt_tick(10.0, 100.0), "10");
        assert_eq!(fmt_tick(1e-12, 0.0), "1e-12");
        assert_eq!(fmt_tick(2.5e-7, 0.0), "2.5e-7");
        assert_eq!(fmt_tick(1e-18, 1.0), "0");
        assert_eq!(fmt_tick(-5.0, 20.0), "-5");
    }

    #[test]
    fn decimation_keeps_envelope_and_gaps() {
        let t: Vec<f64> = (0..10_000).map(|k| k as f64 * 0.025).collect();
        let y = |k: usize| if (4000..4100).contains(&k) { None } else { Some((k as f64 * 0.3).sin()) };
        let lines = polylines(&t, y, 100);
        assert_eq!(lines.len(), 2);
        let pts: usize = lines.iter().map(|l| l.len()).sum();
        assert!(pts <= 2 * 100 + 4, "{pts}");
        let max = lines.iter().flatten().map(|p| p.1).fold(f64::MIN, f64::max);
        assert!(max > 0.99);
        // Time gaps break lines too.
        let t2 = [0.0, 1.0, 2.0, 10.0, 11.0];
        assert_eq!(polylines(&t2, |_| Some(1.0), 100).len(), 2);
    }

    #[test]
    fn segment_lengths() {
        assert_eq!(welch_segment_len(24_000), 2048);
        assert_eq!(welch_segment_len(100), 64);
        assert_eq!(welch_segment_len(40), 40);
    }
}
