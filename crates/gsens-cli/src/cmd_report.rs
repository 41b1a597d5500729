//! `gsens report`: the calibration as one self-contained HTML file, the same
//! as JSON, the compensation parameters as a C header, and the figures as PNG
//! and SVG. Also the figure set shared by `gsens demo --figures`.

use crate::estimate::{EstimatorArgs, LoopArgs, SelectionArgs, SystematicArgs, estimate_files};
use anyhow::{Context, Result, bail};
use clap::Args;
use gsens_calib::{Calibration, EpochSeries, compensation_series};
use gsens_io::TrackingLog;
use gsens_report::figures::{
    AllanData, Cn0Track, CompensationData, DEFAULT_SIZE, EstimationData, Format, Image, ResponseData, SpectrumData,
    fig_allan, fig_cn0, fig_compensation, fig_estimation, fig_residual_spectrum, fig_response,
};
use gsens_report::{ChannelRow, FigureBlock, ReportData, ReportMeta, loop_description};
use gsens_session::PreparedSession;
use indicatif::{ProgressBar, ProgressStyle};
use std::path::{Path, PathBuf};
use std::time::Duration;

#[derive(Args, Debug)]
pub struct ReportArgs {
    /// IMU log: t_s,fx_mps2,fy_mps2,fz_mps2.
    #[arg(long)]
    pub imu: PathBuf,
    /// Tracking log: t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad.
    #[arg(long)]
    pub tracking: PathBuf,
    /// truth.json of a simulated session: the true Γ is drawn dashed and the errors reported.
    #[arg(long)]
    pub truth: Option<PathBuf>,
    /// Output directory: report.html, report.json, gsens_gamma.h and figures/ (PNG and SVG).
    #[arg(long)]
    pub out: PathBuf,
    /// Heading of the report.
    #[arg(long, default_value = "Oscillator g-sensitivity calibration")]
    pub title: String,
    #[command(flatten)]
    pub loop_args: LoopArgs,
    #[command(flatten)]
    pub estimator: EstimatorArgs,
    #[command(flatten)]
    pub selection: SelectionArgs,
    #[command(flatten)]
    pub systematic: SystematicArgs,
}

/// One figure: file stem, title, caption and its renderer.
pub struct Figure<'a> {
    pub id: &'static str,
    pub title: String,
    pub caption: String,
    render: Box<dyn Fn(Format) -> Result<Image> + 'a>,
}

impl Figure<'_> {
    pub fn render(&self, format: Format) -> Result<Image> {
        (self.render)(format).with_context(|| format!("drawing {}", self.id))
    }
}

/// The series the figures of a calibration need, computed once.
pub struct FigureInputs<'a> {
    pub session: &'a PreparedSession,
    pub calibration: &'a Calibration,
    pub tracking: Option<&'a TrackingLog>,
    pub truth: Option<[f64; 3]>,
    before: Vec<Option<f64>>,
    after: Vec<Option<f64>>,
    spectrum: (Vec<f64>, Vec<f64>),
}

impl<'a> FigureInputs<'a> {
    pub fn new(
        session: &'a PreparedSession,
        calibration: &'a Calibration,
        tracking: Option<&'a TrackingLog>,
        truth: Option<[f64; 3]>,
    ) -> Result<Self> {
        let series = EpochSeries {
            log_interval_s: session.log_interval_s,
            t_s: &session.t_s,
            phase_err_rad: &session.phase_err_rad,
            accel_mps2: &session.accel_mps2,
            imu_time_offset_s: session.imu_time_offset_s,
        };
        // φ and φ − φ_aᵀΓ̂ (the estimate of every axis, as the reported RMS
        // after compensation), high-passed exactly as the estimator saw them.
        let (before, after): (Vec<_>, Vec<_>) =
            compensation_series(&series, &calibration.settings, &calibration.gamma_raw_hz_per_mps2)?
                .into_iter()
                .unzip();
        // The spectrum over the longest gap-free run after the warm-up.
        let skip = (calibration.settings.warmup_s / session.log_interval_s).ceil() as usize;
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
        Ok(FigureInputs { session, calibration, tracking, truth, before, after, spectrum: (spec_before, resid) })
    }

    /// The figures: Figs. 3–5 of the paper, C/N0, the residual spectrum.
    pub fn figures(&self) -> Vec<Figure<'_>> {
        let c = self.calibration;
        let s = self.session;
        let spec = c.settings.loop_spec;
        let loop_t = Some(c.settings.loop_interval_s.unwrap_or(c.log_interval_s));
        let mut desc = loop_description(&spec);
        if let Some(t) = loop_t {
            desc.push_str(&format!(", updated every {t} s"));
        }
        let response =
            spec.coeffs().ok().map(|coeffs| ResponseData::from_loop(&coeffs, loop_t, 0.05, 20.0, 300, desc.clone()));
        let mut figs = Vec::new();
        if let Some(r) = response {
            let period = 1.0 / r.peak_hz;
            figs.push(Figure {
                id: "fig3_response",
                title: "Fig. 3: the loop's frequency response".into(),
                caption: format!(
                    "|L(j2πf)| = |φ/Δf| and its phase for the receiver loop modelled ({desc}). A frequency bias \
                     Δf = aᵀΓ leaves the largest phase error when the specific force varies near the peak, \
                     {:.3} Hz: shake with a period of about {period:.2} s (shaded: the half-power band).",
                    r.peak_hz
                ),
                render: Box::new(move |f| Ok(fig_response(&r, f, DEFAULT_SIZE)?)),
            });
        }
        figs.push(Figure {
            id: "fig4_estimation",
            title: "Fig. 4: the estimation process".into(),
            caption: format!(
                "Specific force in the IMU frame (top) and the components of Γ̂ as the estimator runs (bottom), with \
                 ±1σ bands assuming white residuals{}. An axis is estimated once it is shaken.",
                if self.truth.is_some() { "; the truth dashed" } else { "" }
            ),
            render: Box::new(move |f| {
                let d = EstimationData {
                    t_s: &s.t_s,
                    accel_mps2: &s.accel_mps2,
                    history: &c.history,
                    truth: self.truth,
                    observable: c.observable,
                };
                Ok(fig_estimation(&d, f, (DEFAULT_SIZE.0, 720))?)
            }),
        });
        figs.push(Figure {
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
                let d = CompensationData { t_s: &s.t_s, before_rad: &self.before, after_rad: &self.after };
                Ok(fig_compensation(&d, f, (DEFAULT_SIZE.0, 520))?)
            }),
        });
        if let Some(log) = self.tracking {
            let used: Vec<(u32, u32)> = s.channels.iter().filter(|ch| ch.used).map(|ch| (ch.channel, ch.prn)).collect();
            figs.push(Figure {
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
                    Ok(fig_cn0(&tracks, f, (DEFAULT_SIZE.0, 520))?)
                }),
            });
        }
        if self.spectrum.1.len() >= 64 {
            let fn_hz = spec.wn_rad_per_s().map(|w| w / std::f64::consts::TAU);
            figs.push(Figure {
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
                    Ok(fig_residual_spectrum(&d, f, (DEFAULT_SIZE.0, 560))?)
                }),
            });
        }
        figs
    }
}

/// The Allan deviation of `cfg` simulated for `duration_s` at 40 Hz against
/// its model (the simulator's oscillator, for `gsens demo --figures`).
pub fn allan_figure(cfg: &gsens_sim::oscillator::OscillatorConfig, label: &str, seed: u64) -> Result<Figure<'static>> {
    use gsens_sim::oscillator::{Oscillator, allan_deviation_theory_with_pm, allan_deviations};
    let dt = 0.025;
    let n = 48_000; // 20 minutes
    let mut osc = Oscillator::try_new(cfg, dt, gsens_sim::rng::seeded(seed)).map_err(anyhow::Error::msg)?;
    let mut y = vec![0.0; n];
    osc.fill(&mut y);
    let taus: Vec<f64> = (0..16).map(|k| dt * 2f64.powi(k)).filter(|t| *t <= n as f64 * dt / 4.0).collect();
    let sim = allan_deviations(&y, dt, &taus);
    let theory: Vec<f64> = taus.iter().map(|&t| allan_deviation_theory_with_pm(cfg, t, dt)).collect();
    let label = label.to_string();
    Ok(Figure {
        id: "allan",
        title: "Allan deviation of the simulated oscillator".into(),
        caption: format!(
            "Overlapping Allan deviation of {:.0} minutes of the simulator's fractional frequency ({label}) against \
             the power-law model of its preset; deterministic terms (offset, drift, temperature cycle) are in the \
             simulation but not in the model.",
            n as f64 * dt / 60.0
        ),
        render: Box::new(move |f| {
            let d = AllanData { taus_s: &taus, simulated: &sim, theory: &theory, label: &label };
            Ok(fig_allan(&d, f, (900, 600))?)
        }),
    })
}

/// Writes every figure as PNG and SVG into `dir`; returns the SVG blocks for the HTML.
pub fn write_figures(figs: &[Figure], dir: &Path, bar: Option<&ProgressBar>) -> Result<Vec<FigureBlock>> {
    std::fs::create_dir_all(dir).with_context(|| format!("{}: cannot create", dir.display()))?;
    let mut blocks = Vec::new();
    for fig in figs {
        if let Some(b) = bar {
            b.set_message(format!("drawing {}", fig.id));
        }
        for format in [Format::Png, Format::Svg] {
            let img = fig.render(format)?;
            let path = dir.join(format!("{}.{}", fig.id, format.extension()));
            img.write_to(&path).with_context(|| format!("{}: cannot write", path.display()))?;
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

/// The paper's Fig. 3 for `spec` into `path` (PNG or SVG by its extension),
/// with the peak and half-power band `gsens response` computed.
pub fn write_response_plot(
    path: &Path,
    spec: &gsens_core::pll::LoopSpec,
    loop_interval_s: Option<f64>,
    [f_min_hz, f_max_hz]: [f64; 2],
    (peak_hz, peak_rad_per_hz): (f64, f64),
    band_hz: [f64; 2],
) -> Result<()> {
    let format = match path.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase()).as_deref() {
        Some("png") => Format::Png,
        Some("svg") => Format::Svg,
        _ => bail!("{}: the figure's name must end in .png or .svg", path.display()),
    };
    let mut desc = loop_description(spec);
    desc.push_str(&loop_interval_s.map(|t| format!(", updated every {t} s")).unwrap_or_else(|| ", continuous".into()));
    let mut data = ResponseData::from_loop(&spec.coeffs()?, loop_interval_s, f_min_hz, f_max_hz, 300, desc);
    data.peak_hz = peak_hz;
    data.peak_rad_per_hz = peak_rad_per_hz;
    data.half_power_band_hz = Some(band_hz);
    fig_response(&data, format, DEFAULT_SIZE)?
        .write_to(path)
        .with_context(|| format!("{}: cannot write", path.display()))
}

/// `gsens demo --figures DIR`: the figures of the demo's calibration plus the
/// Allan deviation of the scenario's oscillator, as PNG and SVG.
pub fn write_demo_figures(
    dir: &Path,
    session: &PreparedSession,
    calibration: &Calibration,
    tracking: &Path,
    truth: [f64; 3],
    scenario: &gsens_sim::scenario::Scenario,
    seed: u64,
) -> Result<()> {
    use gsens_sim::scenario::OscillatorKind;
    let bar = spinner();
    let log = gsens_io::read_tracking_file(tracking)?;
    let inputs = FigureInputs::new(session, calibration, Some(&log), Some(truth))?;
    let mut figs = inputs.figures();
    let cfg = scenario.oscillator.config();
    if cfg.h0 + cfg.h_neg1 + cfg.h_neg2 + cfg.h2 > 0.0 {
        let label = match scenario.oscillator.preset {
            OscillatorKind::Ocxo => "OCXO preset",
            OscillatorKind::Tcxo => "TCXO preset",
            OscillatorKind::TcxoLowQuality => "low-quality TCXO preset",
            OscillatorKind::Ideal => "ideal preset with noise overrides",
        };
        figs.push(allan_figure(&cfg, label, seed)?);
    }
    write_figures(&figs, dir, Some(&bar))?;
    bar.finish_and_clear();
    println!("figures: {} ({})", dir.display(), figs.iter().map(|f| f.id).collect::<Vec<_>>().join(", "));
    Ok(())
}

/// The true Γ from a simulator's truth.json (`gamma_hz_per_mps2`).
pub fn read_truth(path: &Path) -> Result<[f64; 3]> {
    let text = std::fs::read_to_string(path).with_context(|| format!("{}: cannot read", path.display()))?;
    let v: serde_json::Value = serde_json::from_str(&text).with_context(|| format!("{}: not JSON", path.display()))?;
    let g = v.get("gamma_hz_per_mps2").and_then(|g| g.as_array());
    match g.map(|a| a.iter().filter_map(|x| x.as_f64()).collect::<Vec<_>>()) {
        Some(a) if a.len() == 3 => Ok([a[0], a[1], a[2]]),
        _ => bail!("{}: no `gamma_hz_per_mps2` with 3 numbers", path.display()),
    }
}

/// A spinner on stderr (drawn only on a terminal).
pub fn spinner() -> ProgressBar {
    let bar = ProgressBar::new_spinner();
    bar.set_style(ProgressStyle::with_template("{spinner} {elapsed} {msg}").expect("valid template"));
    bar.enable_steady_tick(Duration::from_millis(120));
    bar
}

pub fn run(args: &ReportArgs) -> Result<()> {
    let settings = args.estimator.settings(&args.loop_args)?;
    let truth = args.truth.as_deref().map(read_truth).transpose()?;
    let bar = spinner();
    bar.set_message("reading the logs and estimating Γ");
    let (session, calibration) =
        estimate_files(&args.imu, &args.tracking, &args.selection.selection(), &args.systematic, &settings)?;
    bar.set_message("reading the tracking log for C/N0");
    let tracking = gsens_io::read_tracking_file(&args.tracking)?;
    let inputs: Vec<(String, String)> = [("imu", &args.imu), ("tracking", &args.tracking)]
        .into_iter()
        .chain(args.truth.as_ref().map(|t| ("truth", t)))
        .map(|(k, p)| (k.to_string(), p.display().to_string()))
        .collect();
    let meta = ReportMeta {
        generated_utc: gsens_report::utc_now_string(),
        tool: format!("gsens {}", env!("CARGO_PKG_VERSION")),
        inputs,
    };
    let out = &args.out;
    std::fs::create_dir_all(out).with_context(|| format!("{}: cannot create", out.display()))?;
    let inputs_fig = FigureInputs::new(&session, &calibration, Some(&tracking), truth)?;
    let figures = write_figures(&inputs_fig.figures(), &out.join("figures"), Some(&bar))?;
    bar.set_message("writing the report");
    let header = gsens_report::cheader::render_c_header(&calibration, &meta);
    let data = ReportData {
        title: args.title.clone(),
        calibration: &calibration,
        truth,
        channels: session
            .channels
            .iter()
            .map(|ch| ChannelRow {
                channel: ch.channel,
                prn: ch.prn,
                mean_cn0_dbhz: ch.mean_cn0_dbhz,
                epochs: ch.epochs,
                used: ch.used,
                reason: ch.reason.clone(),
                phase_offset_rad: ch.phase_offset_rad,
            })
            .collect(),
        selection: serde_json::to_value(&session.selection)?,
        meta,
        figures,
        c_header: Some(header.clone()),
    };
    let write = |name: &str, text: &str| -> Result<PathBuf> {
        let p = out.join(name);
        std::fs::write(&p, text).with_context(|| format!("{}: cannot write", p.display()))?;
        Ok(p)
    };
    let html = write("report.html", &gsens_report::html::render_html(&data))?;
    write("report.json", &gsens_report::json::report_json_string(&data)?)?;
    write("gsens_gamma.h", &header)?;
    bar.finish_and_clear();
    print!("{}", crate::report::text(&session, &calibration, truth));
    println!("\nreport: {} (with report.json, gsens_gamma.h and figures/ beside it)", html.display());
    Ok(())
}
