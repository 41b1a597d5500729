//! `gsens predict`: what compensation buys under vibration. From Γ̂ and its
//! covariance, a vibration environment, the oscillator and the loop: the
//! carrier phase jitter without and with −aᵀΓ̂ in the NCO, the lock margin by
//! the 3σ rule, and the narrowest loop that keeps lock in each case
//! (`gsens_calib::predict`).

use anyhow::{Context, Result};
use clap::{Args, ValueEnum};
use gsens_calib::predict::{BN_GRID_HZ, FrequencyNoise, PredictionInput, SweepError, SweepSettings, Vibration};
use gsens_report::figures::{DEFAULT_SIZE, Format, LockMarginData, fig_lock_margin};
use gsens_sim::oscillator::OscillatorConfig;
use std::path::PathBuf;

#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum OscillatorArg {
    /// The simulator's OCXO preset (the paper's class).
    Ocxo,
    /// The simulator's TCXO preset.
    Tcxo,
    /// The simulator's low-quality TCXO preset.
    TcxoLowQuality,
    /// No oscillator noise (the vibration and thermal parts alone).
    None,
}

impl std::fmt::Display for OscillatorArg {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            OscillatorArg::Ocxo => "OCXO",
            OscillatorArg::Tcxo => "TCXO",
            OscillatorArg::TcxoLowQuality => "low-quality TCXO",
            OscillatorArg::None => "noise-free",
        })
    }
}

#[derive(Args, Debug)]
pub struct PredictArgs {
    /// Γ̂ and its covariance from a result document (`gsens estimate --json`, `report.json`).
    #[arg(long, required_unless_present = "gamma", conflicts_with_all = ["gamma", "sigma"])]
    pub from: Option<PathBuf>,
    /// Γ̂ [Hz/(m/s²)] as gx,gy,gz (with --sigma).
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true, requires = "sigma")]
    pub gamma: Option<Vec<f64>>,
    /// 1σ of Γ̂ [Hz/(m/s²)] as sx,sy,sz (axes uncorrelated).
    #[arg(long, value_delimiter = ',')]
    pub sigma: Option<Vec<f64>>,
    /// Random vibration: vibration.csv (f_hz,psd_x,psd_y,psd_z in (m/s²)²/Hz).
    #[arg(long, required_unless_present = "tone")]
    pub psd: Option<PathBuf>,
    /// Sine vibration: a tone as F_HZ:AX,AY,AZ (peak m/s² per axis, in phase); repeatable.
    #[arg(long, conflicts_with = "psd")]
    pub tone: Vec<String>,
    /// Vibration levels to predict at, as factors on the amplitudes (PSD × level²).
    #[arg(long, value_delimiter = ',', default_value = "1")]
    pub levels: Vec<f64>,
    /// The oscillator's noise.
    #[arg(long, value_enum, default_value = "ocxo")]
    pub oscillator: OscillatorArg,
    /// Carrier [Hz] (GPS L1 by default).
    #[arg(long, default_value_t = gsens_core::units::GPS_L1_HZ, allow_negative_numbers = true, value_parser = crate::args::positive)]
    pub carrier_hz: f64,
    /// C/N0 for the thermal noise [dB-Hz].
    #[arg(long, default_value_t = 45.0, allow_negative_numbers = true, value_parser = crate::args::finite_non_negative)]
    pub cn0_dbhz: f64,
    /// The loop (2nd order): noise bandwidth [Hz].
    #[arg(long, default_value_t = 3.0, allow_negative_numbers = true, value_parser = crate::args::positive)]
    pub bn_hz: f64,
    /// Damping ratio ζ.
    #[arg(long, default_value_t = std::f64::consts::FRAC_1_SQRT_2, allow_negative_numbers = true, value_parser = crate::args::positive)]
    pub zeta: f64,
    /// Loop update interval [s].
    #[arg(long, default_value_t = 0.001, allow_negative_numbers = true, value_parser = crate::args::positive)]
    pub loop_interval_s: f64,
    /// The feed-forward: IMU sample rate [Hz] (its hold delays by half a sample).
    #[arg(long, default_value_t = 40.0, allow_negative_numbers = true, value_parser = crate::args::positive)]
    pub imu_rate_hz: f64,
    /// The feed-forward: latency on top of the hold [s].
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true, value_parser = crate::args::finite_non_negative)]
    pub latency_s: f64,
    /// The IMU's white noise density [m/s²/√Hz].
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true, value_parser = crate::args::finite_non_negative)]
    pub imu_noise_mps2_per_rthz: f64,
    /// The line-of-sight Doppler rate the loop must follow [Hz/s] (its dynamic stress
    /// error enters the lock rule; a static receiver sees up to about 0.9 Hz/s at L1).
    #[arg(long, default_value_t = 0.9, allow_negative_numbers = true, value_parser = crate::args::finite_non_negative)]
    pub doppler_rate_hz_per_s: f64,
    /// Write the predictions as JSON here.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Draw the lock margin (3σ + θe without and with compensation) over the loop bandwidth
    /// at the last level here (.png or .svg).
    #[arg(long)]
    pub figure: Option<PathBuf>,
}

/// A tone `F:AX,AY,AZ`.
fn parse_tone(text: &str) -> Result<(f64, [f64; 3])> {
    let err = || format!("--tone {text}: expected F_HZ:AX,AY,AZ (e.g. 0.91:3,0,0)");
    let (f, a) = text.split_once(':').with_context(err)?;
    let f: f64 = f.trim().parse().ok().filter(|f: &f64| f.is_finite() && *f > 0.0).with_context(err)?;
    let a: Vec<f64> = a.split(',').map(|x| x.trim().parse::<f64>()).collect::<Result<_, _>>().ok().with_context(err)?;
    if a.len() != 3 || a.iter().any(|x| !x.is_finite()) {
        anyhow::bail!(err());
    }
    Ok((f, [a[0], a[1], a[2]]))
}

pub fn run(args: &PredictArgs) -> Result<crate::Status> {
    crate::outputs::maybe_file("--json", args.json.as_deref())?;
    crate::outputs::maybe_file("--figure", args.figure.as_deref())?;
    let (gamma, covariance) = match (&args.from, &args.gamma, &args.sigma) {
        (Some(path), _, _) => crate::estimate::gamma_of_document(path)?,
        (None, Some(g), Some(s)) => {
            if g.len() != 3 || s.len() != 3 {
                anyhow::bail!("--gamma and --sigma take three values each, as x,y,z");
            }
            if g.iter().chain(s).any(|x| !x.is_finite()) || s.iter().any(|x| *x < 0.0) {
                anyhow::bail!("--gamma and --sigma must be finite, --sigma ≥ 0");
            }
            let mut c = [[0.0; 3]; 3];
            for i in 0..3 {
                c[i][i] = s[i] * s[i];
            }
            ([g[0], g[1], g[2]], c)
        }
        _ => anyhow::bail!("give --from report.json, or --gamma with --sigma"),
    };
    let base = match &args.psd {
        Some(path) => Vibration::Spectrum(gsens_io::read_vibration_psd_file(path)?),
        None => Vibration::Tones(args.tone.iter().map(|t| parse_tone(t)).collect::<Result<_>>()?),
    };
    let oscillator = match args.oscillator {
        OscillatorArg::Ocxo => Some(OscillatorConfig::ocxo()),
        OscillatorArg::Tcxo => Some(OscillatorConfig::tcxo()),
        OscillatorArg::TcxoLowQuality => Some(OscillatorConfig::tcxo_low_quality()),
        OscillatorArg::None => None,
    }
    .map(|o| FrequencyNoise {
        h2: o.h2,
        h0: o.h0,
        h_neg1: o.h_neg1,
        h_neg2: o.h_neg2,
        carrier_hz: args.carrier_hz,
    });
    let delay_s = args.latency_s + 0.5 / args.imu_rate_hz;
    let settings = SweepSettings {
        base: PredictionInput {
            gamma_hz_per_mps2: gamma,
            covariance,
            vibration: base,
            oscillator,
            cn0_dbhz: Some(args.cn0_dbhz),
            delay_s,
            imu_noise_mps2_per_rthz: args.imu_noise_mps2_per_rthz,
            doppler_rate_hz_per_s: args.doppler_rate_hz_per_s,
        },
        levels: args.levels.clone(),
        bn_hz: args.bn_hz,
        zeta: args.zeta,
        loop_interval_s: args.loop_interval_s,
    };
    let sweep = settings.sweep().map_err(|e| match e {
        SweepError::Level(level) => anyhow::anyhow!("--levels {level}: must be finite and ≥ 0"),
        e => e.into(),
    })?;
    crate::out(&format!(
        "loop: 2nd order, Bn {} Hz, ζ {:.3}, T {} s; oscillator {}; C/N0 {} dB-Hz; feed-forward delay {:.4} s \
         (latency {} s + half the IMU's {} Hz sample); lock while 3σ + θe ≤ 45°, θe the dynamic stress of a {} Hz/s \
         Doppler rate\n\n",
        args.bn_hz,
        args.zeta,
        args.loop_interval_s,
        args.oscillator,
        args.cn0_dbhz,
        delay_s,
        args.latency_s,
        args.imu_rate_hz,
        args.doppler_rate_hz_per_s
    ))?;
    crate::out(
        "  level  vibration RMS [m/s²]     1σ [rad]: thermal  oscillator  vibration without → with   total without → with   \
         lock without/with   narrowest Bn without/with [Hz]\n",
    )?;
    let yes = |b: bool| if b { "yes" } else { "NO" };
    let bn = |b: Option<f64>| match b {
        None => format!("none ≤ {}", BN_GRID_HZ[BN_GRID_HZ.len() - 1]),
        Some(b) if b <= BN_GRID_HZ[0] => format!("≤ {b:.1}"),
        Some(b) => format!("{b:.1}"),
    };
    for r in &sweep.predictions {
        crate::out(&format!(
            "  {:5.2}  {:5.2} {:5.2} {:5.2}        {:7.4}     {:7.4}     {:7.4} → {:7.4}       {:6.4} → {:6.4}       \
             {:>3} / {:<3}          {} / {}\n",
            r.level,
            r.vibration_rms_mps2[0],
            r.vibration_rms_mps2[1],
            r.vibration_rms_mps2[2],
            r.thermal_rad,
            r.oscillator_rad,
            r.vibration_rad[0],
            r.vibration_rad[1],
            r.total_rad[0],
            r.total_rad[1],
            yes(r.keeps_lock[0]),
            yes(r.keeps_lock[1]),
            bn(r.narrowest_bn_hz[0]),
            bn(r.narrowest_bn_hz[1]),
        ))?;
    }
    crate::out(
        "\nwithout: Δf = aᵀΓ̂ reaches the loop; with: what Γ̂'s covariance and the feed-forward's delay leave of it \
         (docs: gsens_calib::predict)\n",
    )?;
    if let (Some(path), Some(&level)) = (&args.figure, args.levels.last()) {
        let (bns, without, with) = settings.lock_margin(level);
        let label = format!("vibration level {level}, {} oscillator, C/N0 {} dB-Hz", args.oscillator, args.cn0_dbhz);
        let data = LockMarginData {
            bn_hz: &bns,
            without_rad: &without,
            with_rad: &with,
            threshold_rad: gsens_calib::predict::COSTAS_LOCK_RULE_RAD,
            label: &label,
        };
        fig_lock_margin(&data, Format::of_path(path).unwrap_or(Format::Png), DEFAULT_SIZE)?
            .write_to(path)
            .with_context(|| format!("{}: cannot write", path.display()))?;
    }
    if let Some(path) = &args.json {
        std::fs::write(path, serde_json::to_string_pretty(&sweep)?)
            .with_context(|| format!("{}: cannot write", path.display()))?;
    }
    Ok(crate::Status::Done)
}
