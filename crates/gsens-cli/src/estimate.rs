//! `gsens estimate`: Γ̂ from receiver logs.

use anyhow::{Context, Result, bail};
use clap::{Args, ValueEnum};
use gsens_calib::search::{estimate_time_offset, identify_loop};
use gsens_calib::{Calibration, EpochSeries, EstimateSettings, Method, Robust, calibrate};
use gsens_core::pll::{KAPLAN_A3, KAPLAN_B3, LoopSpec};
use gsens_core::regressor::LoggedPhase;
use gsens_io::{ImuSeries, TrackingLog, read_imu_file, read_tracking_file};
use gsens_session::{PreparedSession, ScreeningConfig, SelectionConfig, Weighting, prepare_session, reinterpolate_imu};
use std::path::{Path, PathBuf};

/// Estimator choice on the command line.
#[derive(Clone, Copy, Debug, ValueEnum, PartialEq)]
pub enum MethodArg {
    /// The paper's gradient observer (constant gain).
    Gradient,
    /// Recursive least squares (Kalman-type gain).
    Rls,
    /// Batch least squares over the whole log.
    Batch,
    /// Generalized least squares: batch prewhitened by an AR model of the residual noise (efficient under coloured noise).
    Gls,
}

/// Robust estimation on the command line.
#[derive(Clone, Copy, Debug, ValueEnum, PartialEq)]
pub enum RobustArg {
    /// Plain least squares.
    None,
    /// Huber's M-estimate (iteratively reweighted least squares).
    Huber,
}

/// Robust estimation options.
#[derive(Args, Debug, Clone)]
pub struct RobustArgs {
    /// Robust estimation against outlying epochs: `huber` (IRLS; batch method only) or `none`.
    #[arg(long, value_enum, default_value_t = RobustArg::None)]
    pub robust: RobustArg,
}

impl RobustArgs {
    /// The setting.
    pub fn robust(&self) -> Robust {
        match self.robust {
            RobustArg::None => Robust::None,
            RobustArg::Huber => Robust::Huber,
        }
    }
}

/// What a log row holds when the loop runs faster than the log.
#[derive(Clone, Copy, Debug, ValueEnum, PartialEq)]
pub enum LoggedArg {
    /// The latest discriminator output.
    Last,
    /// The mean of the discriminator outputs since the previous row.
    Mean,
}

/// Channel weighting on the command line.
#[derive(Clone, Copy, Debug, ValueEnum, PartialEq)]
pub enum WeightsArg {
    /// Equal weights (the paper).
    Equal,
    /// Weights proportional to C/N0 (inverse thermal phase variance).
    Cn0,
}

/// The receiver-loop and estimator options shared by `estimate` and `demo`.
#[derive(Args, Debug, Clone)]
pub struct LoopArgs {
    /// Loop order of the receiver's carrier PLL.
    #[arg(long, default_value_t = 2, value_parser = clap::value_parser!(u8).range(2..=3))]
    pub order: u8,
    /// One-sided noise bandwidth Bn of the receiver's PLL [Hz].
    #[arg(long, default_value_t = 3.0)]
    pub bn_hz: f64,
    /// Damping ratio ζ (2nd-order loop).
    #[arg(long, default_value_t = std::f64::consts::FRAC_1_SQRT_2)]
    pub zeta: f64,
    /// a3 of the 3rd-order loop (Kaplan: 1.1).
    #[arg(long, default_value_t = KAPLAN_A3)]
    pub a3: f64,
    /// b3 of the 3rd-order loop (Kaplan: 2.4).
    #[arg(long, default_value_t = KAPLAN_B3)]
    pub b3: f64,
    /// The receiver's loop update interval [s] (default: the log interval).
    #[arg(long)]
    pub loop_interval_s: Option<f64>,
    /// What a log row holds when the loop runs faster than the log.
    #[arg(long, value_enum, default_value_t = LoggedArg::Last)]
    pub logged_phase: LoggedArg,
}

impl LoopArgs {
    pub fn loop_spec(&self) -> LoopSpec {
        match self.order {
            3 => LoopSpec::ThirdOrder { bn_hz: self.bn_hz, a3: self.a3, b3: self.b3 },
            _ => LoopSpec::SecondOrder { bn_hz: self.bn_hz, zeta: self.zeta },
        }
    }
}

/// Estimator options shared by `estimate` and `demo`.
#[derive(Args, Debug, Clone)]
pub struct EstimatorArgs {
    /// Estimator.
    #[arg(long, value_enum, default_value_t = MethodArg::Batch)]
    pub method: MethodArg,
    /// Gain k of the gradient observer.
    #[arg(long, default_value_t = 0.5)]
    pub gain_k: f64,
    /// Forgetting factor λ of the RLS estimator (1 = none).
    #[arg(long, default_value_t = 1.0)]
    pub lambda: f64,
    /// Seconds at the start that only drive the loop models (their start-up transient).
    #[arg(long, default_value_t = 2.0)]
    pub warmup_s: f64,
    /// Carrier frequency [Hz] for ppb/g (default GPS L1).
    #[arg(long, default_value_t = gsens_core::units::GPS_L1_HZ)]
    pub carrier_hz: f64,
    /// 1σ scale-factor error of the IMU [ppm] (from its datasheet), added to Γ̂'s uncertainty.
    #[arg(long, default_value_t = 0.0)]
    pub imu_scale_sigma_ppm: f64,
    /// 1σ axis misalignment of the IMU [mrad], added to Γ̂'s uncertainty.
    #[arg(long, default_value_t = 0.0)]
    pub imu_misalignment_sigma_mrad: f64,
    /// Corner of the identical high-pass on φ and φ_a [Hz] (0 = off).
    #[arg(long, default_value_t = 0.05)]
    pub highpass_hz: f64,
}

impl EstimatorArgs {
    pub fn settings(&self, loop_args: &LoopArgs) -> Result<EstimateSettings> {
        let method = match self.method {
            MethodArg::Batch => Method::Batch,
            MethodArg::Gls => Method::Gls,
            MethodArg::Rls => {
                if !(self.lambda > 0.0 && self.lambda <= 1.0) {
                    bail!("--lambda must be in (0, 1], got {}", self.lambda);
                }
                Method::Rls { lambda: self.lambda }
            }
            MethodArg::Gradient => {
                if !(self.gain_k > 0.0 && self.gain_k.is_finite()) {
                    bail!("--gain-k must be positive, got {}", self.gain_k);
                }
                Method::Gradient { gain_k: self.gain_k }
            }
        };
        if !(self.warmup_s >= 0.0 && self.warmup_s.is_finite()) {
            bail!("--warmup-s must be ≥ 0, got {}", self.warmup_s);
        }
        for (name, v) in [
            ("--imu-scale-sigma-ppm", self.imu_scale_sigma_ppm),
            ("--imu-misalignment-sigma-mrad", self.imu_misalignment_sigma_mrad),
            ("--highpass-hz", self.highpass_hz),
        ] {
            if !(v >= 0.0 && v.is_finite()) {
                bail!("{name} must be ≥ 0, got {v}");
            }
        }
        if !(self.carrier_hz > 0.0 && self.carrier_hz.is_finite()) {
            bail!("--carrier-hz must be positive, got {}", self.carrier_hz);
        }
        Ok(EstimateSettings {
            loop_spec: loop_args.loop_spec(),
            loop_interval_s: loop_args.loop_interval_s,
            logged_phase: match loop_args.logged_phase {
                LoggedArg::Last => LoggedPhase::Last,
                LoggedArg::Mean => LoggedPhase::Mean,
            },
            method,
            warmup_s: self.warmup_s,
            carrier_hz: self.carrier_hz,
            imu_scale_sigma: self.imu_scale_sigma_ppm * 1e-6,
            imu_misalignment_sigma_rad: self.imu_misalignment_sigma_mrad * 1e-3,
            highpass_hz: self.highpass_hz,
            ..EstimateSettings::default()
        })
    }
}

/// Channel selection options.
#[derive(Args, Debug, Clone)]
pub struct SelectionArgs {
    /// Average the N channels with the highest mean C/N0 (0 = all that pass the masks).
    #[arg(long, default_value_t = 4)]
    pub channels: usize,
    /// Drop rows below this C/N0 [dB-Hz].
    #[arg(long)]
    pub min_cn0_dbhz: Option<f64>,
    /// Drop rows below this elevation [deg] (rows without elevation pass).
    #[arg(long)]
    pub elevation_mask_deg: Option<f64>,
    /// Weights of the per-epoch channel average.
    #[arg(long, value_enum, default_value_t = WeightsArg::Equal)]
    pub weights: WeightsArg,
    /// Per-channel screening before averaging: cycle slips, losses of lock, C/N0 drops, |φ| beyond the linear range.
    #[arg(long, value_enum, default_value_t = OnOff::On)]
    pub screening: OnOff,
    /// Screening: exclude rows whose C/N0 is more than this below the channel's median [dB] (0 = no test).
    #[arg(long, default_value_t = 6.0)]
    pub cn0_drop_db: f64,
    /// Screening: exclude rows whose |phase error| exceeds this [rad] (0 = no limit; default π/4).
    #[arg(long, default_value_t = std::f64::consts::FRAC_PI_4)]
    pub max_abs_phase_rad: f64,
}

/// A switch on the command line.
#[derive(Clone, Copy, Debug, ValueEnum, PartialEq)]
pub enum OnOff {
    /// Enabled.
    On,
    /// Disabled.
    Off,
}

impl SelectionArgs {
    pub fn selection(&self) -> SelectionConfig {
        SelectionConfig {
            max_channels: (self.channels > 0).then_some(self.channels),
            min_cn0_dbhz: self.min_cn0_dbhz,
            elevation_mask_deg: self.elevation_mask_deg,
            weighting: match self.weights {
                WeightsArg::Equal => Weighting::Equal,
                WeightsArg::Cn0 => Weighting::Cn0,
            },
            screening: ScreeningConfig {
                enabled: self.screening == OnOff::On,
                cn0_drop_db: (self.cn0_drop_db > 0.0).then_some(self.cn0_drop_db),
                max_abs_phase_rad: (self.max_abs_phase_rad > 0.0).then_some(self.max_abs_phase_rad),
                ..ScreeningConfig::default()
            },
            ..SelectionConfig::default()
        }
    }
}

/// How the IMU/tracking time offset is handled.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TimeOffset {
    /// Estimated jointly with Γ.
    Auto,
    /// Assumed to be zero.
    None,
    /// Assumed to be this many seconds (IMU time stamp minus true time).
    Seconds(f64),
}

fn parse_time_offset(s: &str) -> Result<TimeOffset, String> {
    match s {
        "auto" => Ok(TimeOffset::Auto),
        "none" => Ok(TimeOffset::None),
        _ => match s.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(TimeOffset::Seconds(v)),
            _ => Err(format!("expected auto, none or a number of seconds, got `{s}`")),
        },
    }
}

/// Systematic errors estimated jointly with Γ.
#[derive(Args, Debug, Clone)]
pub struct SystematicArgs {
    /// IMU time stamp minus true time: `auto` (estimated jointly with Γ), `none` (0) or SECONDS.
    #[arg(long, default_value = "auto", value_parser = parse_time_offset, allow_hyphen_values = true)]
    pub time_offset: TimeOffset,
    /// Search range ± of `--time-offset auto` [s].
    #[arg(long, default_value_t = 0.25)]
    pub time_offset_max_s: f64,
    /// Identify the loop's natural frequency jointly with Γ and use it when the data reject the assumed loop.
    #[arg(long)]
    pub identify_loop: bool,
    /// With --identify-loop: identify the damping ζ too (weakly determined by near-sinusoidal shaking).
    #[arg(long)]
    pub identify_damping: bool,
}

#[derive(Args, Debug)]
pub struct EstimateArgs {
    /// IMU log: t_s,fx_mps2,fy_mps2,fz_mps2.
    #[arg(long)]
    pub imu: PathBuf,
    /// Tracking log: t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad (or --gnss-sdr).
    #[arg(long, required_unless_present = "gnss_sdr", conflicts_with = "gnss_sdr")]
    pub tracking: Option<PathBuf>,
    #[command(flatten)]
    pub gnss_sdr: crate::gnss_sdr_cmd::GnssSdrArgs,
    #[command(flatten)]
    pub loop_args: LoopArgs,
    #[command(flatten)]
    pub estimator: EstimatorArgs,
    #[command(flatten)]
    pub selection: SelectionArgs,
    #[command(flatten)]
    pub systematic: SystematicArgs,
    #[command(flatten)]
    pub robust: RobustArgs,
    /// Write the result as JSON here.
    #[arg(long)]
    pub json: Option<PathBuf>,
}

/// The estimator's view of a prepared session.
fn series_of(s: &PreparedSession) -> EpochSeries<'_> {
    EpochSeries {
        log_interval_s: s.log_interval_s,
        t_s: &s.t_s,
        phase_err_rad: &s.phase_err_rad,
        accel_mps2: &s.accel_mps2,
        imu_time_offset_s: s.imu_time_offset_s,
    }
}

/// Reads the logs, prepares the session, estimates the time offset and the
/// loop when asked, and runs the calibration.
pub fn estimate_files(
    imu: &Path,
    tracking: &Path,
    selection: &SelectionConfig,
    systematic: &SystematicArgs,
    settings: &EstimateSettings,
) -> Result<(PreparedSession, Calibration)> {
    let tracking_log = read_tracking_file(tracking)?;
    let imu_series = read_imu_file(imu)?;
    estimate_logs(&tracking_log, &imu_series, &imu.display().to_string(), selection, systematic, settings)
}

/// [`estimate_files`] on logs already in memory (`imu_name` names the IMU source in errors).
pub fn estimate_logs(
    tracking_log: &TrackingLog,
    imu_series: &ImuSeries,
    imu_name: &str,
    selection: &SelectionConfig,
    systematic: &SystematicArgs,
    settings: &EstimateSettings,
) -> Result<(PreparedSession, Calibration)> {
    let prepare = |offset_s: f64| prepare_session(tracking_log, imu_series, imu_name, selection, offset_s);
    let assumed = match systematic.time_offset {
        TimeOffset::Seconds(v) => v,
        TimeOffset::Auto | TimeOffset::None => 0.0,
    };
    let mut session = prepare(assumed)?;
    let auto = systematic.time_offset == TimeOffset::Auto;
    if auto {
        anyhow::ensure!(
            systematic.time_offset_max_s > 0.0 && systematic.time_offset_max_s.is_finite(),
            "--time-offset-max-s must be positive"
        );
    }
    let mut settings = *settings;
    let mut identification = None;
    if systematic.identify_loop {
        // A loop error mimics a time offset: with `auto` both are searched together.
        let id = identify_loop(
            &series_of(&session),
            &settings,
            systematic.identify_damping,
            auto.then_some(systematic.time_offset_max_s),
        )
        .context("identifying the loop")?;
        if id.assumed_loop_rejected {
            settings.loop_spec = id.spec(&settings.loop_spec);
        }
        identification = Some(id);
    }
    let mut offset_sigma = None;
    if auto {
        let found = estimate_time_offset(&series_of(&session), &settings, systematic.time_offset_max_s)
            .context("estimating the IMU time offset (give --time-offset SECONDS or none to skip)")?;
        if (found.imu_time_offset_s - assumed).abs() >= systematic.time_offset_max_s * 0.999 {
            anyhow::bail!(
                "the IMU time offset search ended at its limit ({:+.3} s): the offset may be larger than \
                 --time-offset-max-s {} s; widen the search or give --time-offset SECONDS",
                found.imu_time_offset_s,
                systematic.time_offset_max_s
            );
        }
        reinterpolate_imu(&mut session, imu_series, found.imu_time_offset_s);
        offset_sigma = Some(found.sigma_s);
    }
    let mut calibration = calibrate(&series_of(&session), &settings)?;
    calibration.imu_time_offset_estimated = offset_sigma.is_some();
    calibration.imu_time_offset_sigma_s = offset_sigma;
    calibration.loop_identification = identification;
    Ok((session, calibration))
}

pub fn run(args: &EstimateArgs) -> Result<()> {
    if let Some(dir) = &args.gnss_sdr.gnss_sdr {
        return crate::gnss_sdr_cmd::estimate(args, dir);
    }
    let tracking = args.tracking.as_ref().context("--tracking is required (or --gnss-sdr)")?;
    let settings = EstimateSettings { robust: args.robust.robust(), ..args.estimator.settings(&args.loop_args)? };
    let (session, calibration) =
        estimate_files(&args.imu, tracking, &args.selection.selection(), &args.systematic, &settings)?;
    print!("{}", crate::report::text(&session, &calibration, None));
    if let Some(path) = &args.json {
        crate::report::write_json(path, &session, &calibration, None, &[("imu", &args.imu), ("tracking", tracking)])
            .with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}
