//! `gsens response`: the loop's response from NCO frequency bias to phase
//! error, |L(j2πf)| and its phase, with the peak and the shaking period to use.

use crate::estimate::LoopArgs;
use anyhow::{Context, Result};
use clap::Args;
use gsens_core::pll::LoopFilterCoeffs;
use serde::Serialize;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct ResponseArgs {
    #[command(flatten)]
    pub loop_args: LoopArgs,
    /// Lowest frequency of the table [Hz].
    #[arg(long, default_value_t = 0.05)]
    pub f_min_hz: f64,
    /// Highest frequency of the table [Hz].
    #[arg(long, default_value_t = 20.0)]
    pub f_max_hz: f64,
    /// Rows of the table (log-spaced).
    #[arg(long, default_value_t = 25)]
    pub points: usize,
    /// Write the response as JSON here.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Draw the response (the paper's Fig. 3) here: FILE.png or FILE.svg.
    #[arg(long)]
    pub plot: Option<PathBuf>,
}

#[derive(Serialize)]
struct ResponseJson {
    loop_interval_s: Option<f64>,
    peak_hz: f64,
    peak_rad_per_hz: f64,
    recommended_period_s: f64,
    half_power_band_hz: [f64; 2],
    frequency_hz: Vec<f64>,
    magnitude_rad_per_hz: Vec<f64>,
    phase_deg: Vec<f64>,
}

/// |L| at `f_hz`, discrete when the loop interval is known.
fn response(c: &LoopFilterCoeffs, loop_interval_s: Option<f64>, f_hz: f64) -> gsens_core::pll::Complex<f64> {
    match loop_interval_s {
        Some(t) => c.response_discrete(f_hz, t),
        None => c.response_continuous(f_hz),
    }
}

/// The peak of |L| by golden-section search on a log-frequency axis
/// (|L| is unimodal for the loops gsens models).
pub fn peak(c: &LoopFilterCoeffs, loop_interval_s: Option<f64>, lo_hz: f64, hi_hz: f64) -> (f64, f64) {
    let mag = |lf: f64| response(c, loop_interval_s, lf.exp()).norm();
    let (mut a, mut b) = (lo_hz.ln(), hi_hz.ln());
    let r = (5f64.sqrt() - 1.0) / 2.0;
    for _ in 0..100 {
        let x1 = b - r * (b - a);
        let x2 = a + r * (b - a);
        if mag(x1) > mag(x2) {
            b = x2;
        } else {
            a = x1;
        }
    }
    let f = (0.5 * (a + b)).exp();
    (f, response(c, loop_interval_s, f).norm())
}

/// Where |L| falls to peak/√2 on either side (bisection).
fn half_power_band(c: &LoopFilterCoeffs, t: Option<f64>, peak_hz: f64, peak_val: f64, lo: f64, hi: f64) -> [f64; 2] {
    let target = peak_val / 2f64.sqrt();
    let find = |mut a: f64, mut b: f64, rising: bool| {
        for _ in 0..100 {
            let m = (a * b).sqrt();
            let above = response(c, t, m).norm() > target;
            if above == rising {
                b = m;
            } else {
                a = m;
            }
        }
        (a * b).sqrt()
    };
    [find(lo, peak_hz, true), find(peak_hz, hi, false)]
}

pub fn run(args: &ResponseArgs) -> Result<()> {
    let spec = args.loop_args.loop_spec();
    let c = spec.coeffs()?;
    let t = args.loop_args.loop_interval_s;
    anyhow::ensure!(
        args.f_min_hz > 0.0 && args.f_max_hz > args.f_min_hz && args.points >= 2,
        "need 0 < --f-min-hz < --f-max-hz and --points ≥ 2"
    );
    let hi = t.map(|t| 0.5 / t).unwrap_or(1e3).min(1e3);
    let (peak_hz, peak_val) = peak(&c, t, 1e-3, hi * 0.999);
    let band = half_power_band(&c, t, peak_hz, peak_val, 1e-4, hi * 0.999);
    let mut out = ResponseJson {
        loop_interval_s: t,
        peak_hz,
        peak_rad_per_hz: peak_val,
        recommended_period_s: 1.0 / peak_hz,
        half_power_band_hz: band,
        frequency_hz: vec![],
        magnitude_rad_per_hz: vec![],
        phase_deg: vec![],
    };
    println!(
        "L(j2πf) = φ/Δf of the {} loop{}",
        match spec.order() {
            3 => "3rd-order",
            _ => "2nd-order",
        },
        t.map(|t| format!(" updated every {t} s")).unwrap_or_else(|| " (continuous time)".into())
    );
    println!("   f [Hz]   |L| [rad/Hz]   phase [deg]");
    let ratio = (args.f_max_hz / args.f_min_hz).powf(1.0 / (args.points - 1) as f64);
    for k in 0..args.points {
        let f = args.f_min_hz * ratio.powi(k as i32);
        if t.is_some_and(|t| f >= 0.5 / t) {
            break;
        }
        let l = response(&c, t, f);
        println!("{f:>9.4}   {:>11.5}   {:>10.1}", l.norm(), l.arg().to_degrees());
        out.frequency_hz.push(f);
        out.magnitude_rad_per_hz.push(l.norm());
        out.phase_deg.push(l.arg().to_degrees());
    }
    println!(
        "peak: |L| = {peak_val:.4} rad/Hz at {peak_hz:.4} Hz → shake with a period of about {:.2} s \
         (half-power band {:.2}–{:.2} Hz, periods {:.2}–{:.2} s)",
        1.0 / peak_hz,
        band[0],
        band[1],
        1.0 / band[1],
        1.0 / band[0]
    );
    if let Some(path) = &args.json {
        std::fs::write(path, serde_json::to_string_pretty(&out)? + "\n")
            .with_context(|| format!("writing {}", path.display()))?;
    }
    if let Some(path) = &args.plot {
        crate::cmd_report::write_response_plot(
            path,
            &spec,
            t,
            [args.f_min_hz, args.f_max_hz],
            (peak_hz, peak_val),
            band,
        )?;
        println!("figure: {}", path.display());
    }
    Ok(())
}
