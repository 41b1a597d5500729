//! The command-line options shared by the commands, and the one place where
//! they become library objects: a calibration's options become
//! `gsens_calib::CalibrationOptions` (the names the Python module takes too,
//! which build `gsens_calib::PipelineSettings`); the converters' become
//! `gsens_gnss_sdr::ImportSettings` and `gsens_pocketsdr::ImportSettings`;
//! the input options become `gsens_inputs::Inputs`.

use anyhow::{Result, bail};
use clap::{Args, ValueEnum};
use gsens_calib::option_values::{
    elevation_deg, finite, finite_non_negative, forgetting_factor, non_negative_or_inf, positive, stated_time_offset,
};
use gsens_calib::{CalibrationOptions, MethodName, Robust, TimeOffset, TimeOffsetOption, defaults};
use gsens_core::LoopModel;
use gsens_gnss_sdr::{DumpLayout, ImportSettings};
use gsens_inputs::{Inputs, Log};
use gsens_session::Weighting;
use std::path::{Path, PathBuf};

/// Estimator choice.
#[derive(Clone, Copy, Debug, ValueEnum, PartialEq)]
pub(crate) enum MethodArg {
    /// The paper's gradient observer (constant gain).
    Gradient,
    /// Recursive least squares (Kalman-type gain).
    Rls,
    /// Batch least squares over the whole log.
    Batch,
    /// Generalized least squares: batch prewhitened by an AR model of the residual noise.
    Gls,
}

impl MethodArg {
    /// The library's name of the method.
    pub(crate) fn name(self) -> MethodName {
        match self {
            MethodArg::Gradient => MethodName::Gradient,
            MethodArg::Rls => MethodName::Rls,
            MethodArg::Batch => MethodName::Batch,
            MethodArg::Gls => MethodName::Gls,
        }
    }
}

/// The simulated scenario and its seed (`demo`, `simulate`, `montecarlo`).
#[derive(Args, Debug, Clone)]
pub(crate) struct ScenarioArgs {
    /// Scenario TOML (default: the embedded paper experiment; see `gsens scenario`).
    #[arg(long)]
    pub scenario: Option<PathBuf>,
    /// Seed of every random draw (same seed, same bytes; Monte Carlo run i uses seed + i).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
}

impl ScenarioArgs {
    /// The scenario: the file's, or the embedded default.
    pub(crate) fn load(&self) -> Result<gsens_sim::scenario::Scenario> {
        Ok(gsens_sim::load_scenario(self.scenario.as_deref())?)
    }
}

/// The receiver's carrier loop.
#[derive(Args, Debug, Clone)]
#[command(next_help_heading = "Receiver loop")]
pub(crate) struct LoopArgs {
    /// Loop order of the receiver's carrier PLL.
    #[arg(long, value_parser = clap::value_parser!(u8).range(2..=3))]
    pub order: Option<u8>,
    /// One-sided noise bandwidth Bn of the receiver's PLL [Hz] (default 3).
    #[arg(long, allow_negative_numbers = true, value_parser = positive)]
    pub bn_hz: Option<f64>,
    /// Damping ratio ζ of a 2nd-order loop [default: 1/√2 = 0.707].
    #[arg(long, allow_negative_numbers = true, value_parser = positive)]
    pub zeta: Option<f64>,
    /// a3 of a 3rd-order loop (with --order 3) [default: Kaplan's 1.1].
    #[arg(long, allow_negative_numbers = true, value_parser = positive)]
    pub a3: Option<f64>,
    /// b3 of a 3rd-order loop (with --order 3) [default: Kaplan's 2.4].
    #[arg(long, allow_negative_numbers = true, value_parser = positive)]
    pub b3: Option<f64>,
    /// The receiver's loop update interval [s] (default: the log interval).
    #[arg(long, allow_negative_numbers = true, value_parser = positive)]
    pub loop_interval_s: Option<f64>,
    /// What a log row holds when the loop runs faster than the log (default: last).
    #[arg(long, value_enum)]
    pub logged_phase: Option<gsens_core::LoggedPhase>,
    /// The receiver's carrier-phase discriminator, whose linear range bounds the g-induced phase error (GNSS-SDR and PocketSDR sessions: theirs, atan-costas for GPS L1 C/A).
    #[arg(long, value_enum, default_value_t = DiscriminatorArg::AtanCostas)]
    pub discriminator: DiscriminatorArg,
}

/// The carrier-phase discriminator.
#[derive(Clone, Copy, Debug, ValueEnum, PartialEq)]
pub(crate) enum DiscriminatorArg {
    /// atan(Q/I), the two-quadrant Costas discriminator of GPS L1 C/A receivers: linear within ±π/2.
    AtanCostas,
    /// atan2(Q, I), a four-quadrant PLL discriminator (pilot signals): linear within ±π.
    Atan2,
}

impl LoopArgs {
    /// Refuses a shape parameter of the other order's loop: ζ shapes a
    /// 2nd-order loop only, a3 and b3 a 3rd-order one.
    pub(crate) fn check(&self) -> Result<()> {
        let third = self.order == Some(3);
        if third && self.zeta.is_some() {
            bail!("--zeta is the damping of a 2nd-order loop: a 3rd-order loop (--order 3) takes --a3 and --b3");
        }
        if !third && (self.a3.is_some() || self.b3.is_some()) {
            bail!("--a3 and --b3 shape a 3rd-order loop: they need --order 3 (a 2nd-order loop takes --zeta)");
        }
        Ok(())
    }

    /// Sets the loop's options.
    pub(crate) fn apply(&self, o: &mut CalibrationOptions) {
        o.order = self.order;
        o.bn_hz = self.bn_hz;
        // Unset shape parameters keep the options' defaults.
        o.zeta = self.zeta.unwrap_or(o.zeta);
        o.a3 = self.a3.unwrap_or(o.a3);
        o.b3 = self.b3.unwrap_or(o.b3);
        o.loop_interval_s = self.loop_interval_s;
        o.logged_phase = self.logged_phase;
        o.discriminator = match self.discriminator {
            DiscriminatorArg::AtanCostas => gsens_core::Discriminator::AtanCostas,
            DiscriminatorArg::Atan2 => gsens_core::Discriminator::Atan2,
        };
    }

    fn options(&self) -> CalibrationOptions {
        let mut o = CalibrationOptions::default();
        self.apply(&mut o);
        o
    }

    /// The loop as the library models it.
    pub(crate) fn loop_model(&self) -> LoopModel {
        self.options().loop_model()
    }

    /// Whether any of the loop's order, bandwidth, update interval or
    /// logged phase was given (otherwise the data choose the loop).
    pub(crate) fn stated(&self) -> bool {
        self.options().loop_stated()
    }
}

/// The estimator of a single calibration (`estimate`, `report`, `demo`).
#[derive(Args, Debug, Clone)]
#[command(next_help_heading = "Estimator")]
pub(crate) struct MethodChoice {
    /// Estimator.
    #[arg(long, value_enum, default_value_t = MethodArg::Batch)]
    pub method: MethodArg,
}

/// The estimators' parameters and the error model.
#[derive(Args, Debug, Clone)]
#[command(next_help_heading = "Estimator")]
pub(crate) struct EstimatorArgs {
    /// Gain k of the gradient observer (--method gradient only) [default: 0.5].
    #[arg(long, allow_negative_numbers = true, value_parser = positive)]
    pub gain_k: Option<f64>,
    /// Forgetting factor λ of the RLS estimator, in (0, 1] (--method rls only) [default: 1, none].
    #[arg(long, allow_negative_numbers = true, value_parser = forgetting_factor)]
    pub lambda: Option<f64>,
    /// Seconds at the start that only drive the loop models (their start-up transient).
    #[arg(long, default_value_t = defaults::DEFAULT_WARMUP_S, allow_negative_numbers = true, value_parser = finite_non_negative)]
    pub warmup_s: f64,
    /// 1σ scale-factor error of the IMU [ppm] (from its datasheet), added to Γ̂'s uncertainty.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true, value_parser = finite_non_negative)]
    pub imu_scale_sigma_ppm: f64,
    /// 1σ axis misalignment of the IMU [mrad], added to Γ̂'s uncertainty.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true, value_parser = finite_non_negative)]
    pub imu_misalignment_sigma_mrad: f64,
    /// Corner of the identical high-pass on φ and φ_a [Hz] (0 = off).
    #[arg(long, default_value_t = defaults::DEFAULT_HIGHPASS_HZ, allow_negative_numbers = true, value_parser = finite_non_negative)]
    pub highpass_hz: f64,
    /// Robust estimation against outlying epochs: `huber` (IRLS; batch method only) or `none`.
    #[arg(long, value_enum, default_value_t = RobustArg::None)]
    pub robust: RobustArg,
}

/// Robust estimation.
#[derive(Clone, Copy, Debug, ValueEnum, PartialEq)]
pub(crate) enum RobustArg {
    /// Plain least squares.
    None,
    /// Huber's M-estimate (iteratively reweighted least squares).
    Huber,
}

impl EstimatorArgs {
    /// Refuses a method's parameter given for methods that do not use it
    /// (`methods`: every method the options will run).
    pub(crate) fn check_methods(&self, methods: &[MethodArg]) -> Result<()> {
        let names = || methods.iter().map(|m| format!("{m:?}").to_lowercase()).collect::<Vec<_>>().join(", ");
        if self.lambda.is_some() && !methods.contains(&MethodArg::Rls) {
            bail!(
                "--lambda is the RLS estimator's forgetting factor: it needs --method rls (the method is {})",
                names()
            );
        }
        if self.gain_k.is_some() && !methods.contains(&MethodArg::Gradient) {
            bail!("--gain-k is the gradient observer's gain: it needs --method gradient (the method is {})", names());
        }
        Ok(())
    }

    /// Sets the estimator's options (the method's parameters, the error model).
    pub(crate) fn apply(&self, o: &mut CalibrationOptions) {
        if let Some(k) = self.gain_k {
            o.gain_k = k;
        }
        if let Some(l) = self.lambda {
            o.lambda = l;
        }
        o.warmup_s = self.warmup_s;
        o.imu_scale_sigma_ppm = self.imu_scale_sigma_ppm;
        o.imu_misalignment_sigma_mrad = self.imu_misalignment_sigma_mrad;
        o.highpass_hz = self.highpass_hz;
        o.robust = match self.robust {
            RobustArg::None => Robust::None,
            RobustArg::Huber => Robust::Huber,
        };
    }
}

/// Which channels enter the average.
#[derive(Args, Debug, Clone)]
#[command(next_help_heading = "Channels")]
pub(crate) struct SelectionArgs {
    /// Average the N channels with the highest mean C/N0, or the least noisy when C/N0 does not vary between them (0 = all that pass the masks).
    #[arg(long, default_value_t = defaults::DEFAULT_CHANNELS)]
    pub channels: usize,
    /// Drop rows below this C/N0 [dB-Hz].
    #[arg(long, allow_negative_numbers = true, value_parser = finite)]
    pub min_cn0_dbhz: Option<f64>,
    /// Drop rows below this elevation [deg] (rows without elevation pass).
    #[arg(long, allow_negative_numbers = true, value_parser = elevation_deg)]
    pub elevation_mask_deg: Option<f64>,
    /// Weights of the per-epoch channel average.
    #[arg(long, value_enum, default_value_t = WeightsArg::Equal)]
    pub weights: WeightsArg,
    /// Per-channel screening before averaging: cycle slips, losses of lock, C/N0 drops, |φ| beyond the linear range.
    #[arg(long, default_value = "on", value_name = "on|off", hide_possible_values = true, value_parser = clap::builder::BoolishValueParser::new(), action = clap::ArgAction::Set)]
    pub screening: bool,
    /// Screening: exclude rows whose C/N0 is more than this below the channel's median [dB] (0 = no test).
    #[arg(long, default_value_t = defaults::DEFAULT_CN0_DROP_DB, allow_negative_numbers = true, value_parser = finite_non_negative)]
    pub cn0_drop_db: f64,
    /// Screening: exclude rows whose |phase error| exceeds this [rad] (0 = no limit; default: half the discriminator's unambiguous range, π/4 for atan-costas, π/2 for atan2).
    #[arg(long, allow_negative_numbers = true, value_parser = finite_non_negative)]
    pub max_abs_phase_rad: Option<f64>,
}

/// Channel weighting.
#[derive(Clone, Copy, Debug, ValueEnum, PartialEq)]
pub(crate) enum WeightsArg {
    /// Equal weights (the paper).
    Equal,
    /// Weights proportional to C/N0 (inverse thermal phase variance).
    Cn0,
}

impl SelectionArgs {
    /// Sets the channel selection's options.
    pub(crate) fn apply(&self, o: &mut CalibrationOptions) {
        o.channels = self.channels;
        o.min_cn0_dbhz = self.min_cn0_dbhz;
        o.elevation_mask_deg = self.elevation_mask_deg;
        o.weights = match self.weights {
            WeightsArg::Equal => Weighting::Equal,
            WeightsArg::Cn0 => Weighting::Cn0,
        };
        o.screening = self.screening;
        o.cn0_drop_db = self.cn0_drop_db;
        o.max_abs_phase_rad = self.max_abs_phase_rad;
    }
}

/// Systematic errors estimated jointly with Γ.
#[derive(Args, Debug, Clone)]
#[command(next_help_heading = "Systematic errors")]
pub(crate) struct SystematicArgs {
    /// IMU time stamp minus true time: `auto` (estimated jointly with Γ), `none` (0) or SECONDS.
    #[arg(long, default_value = "auto", allow_hyphen_values = true, value_parser = stated_time_offset)]
    pub time_offset: TimeOffset,
    /// Search range ± of `--time-offset auto` [s].
    #[arg(long, default_value_t = defaults::DEFAULT_TIME_OFFSET_MAX_S, allow_negative_numbers = true, value_parser = finite_non_negative)]
    pub time_offset_max_s: f64,
    /// Test the stated loop against the data: its natural frequency is estimated jointly with Γ and the time offset, a
    /// stated loop the data reject is flagged, and Γ̂ is given under the fitted loop with the loop's uncertainty in its
    /// σ. `off` takes the stated loop as exact.
    #[arg(long, default_value = "on", value_name = "on|off", hide_possible_values = true, value_parser = clap::builder::BoolishValueParser::new(), action = clap::ArgAction::Set)]
    pub loop_check: bool,
    /// With the loop check: fit a 2nd-order loop's damping ζ too (weakly determined by near-sinusoidal shaking).
    #[arg(long)]
    pub identify_damping: bool,
    /// How well the stated loop is known: the relative 1σ uncertainty of its natural frequency. The data's fit of the
    /// loop and the stated loop within this tolerance are combined, and what remains uncertain is in σ. `0`: the
    /// receiver implements exactly the stated loop (Γ̂ reaches the known-loop bound, but a loop error below the
    /// test's reach, about 2 % on the paper's session, then biases Γ̂ unseen); `inf`: only the loop's shape is
    /// known. Default: 0 for a loop modelled from the receiver's configuration (--gnss-sdr, --pocketsdr), 0.02
    /// for a loop stated by --order/--bn-hz.
    #[arg(long, value_name = "FRACTION", allow_negative_numbers = true, value_parser = non_negative_or_inf)]
    pub loop_tolerance: Option<f64>,
    /// Replace isolated IMU spikes (single samples no hand motion can produce) by their neighbours' mean.
    #[arg(long, default_value = "on", value_name = "on|off", hide_possible_values = true, value_parser = clap::builder::BoolishValueParser::new(), action = clap::ArgAction::Set)]
    pub imu_despike: bool,
}

/// The options of a single calibration besides its receiver loop (`estimate`,
/// `report`, `demo`).
#[derive(Args, Debug, Clone)]
pub(crate) struct AnalysisArgs {
    #[command(flatten)]
    pub method: MethodChoice,
    #[command(flatten)]
    pub estimator: EstimatorArgs,
    #[command(flatten)]
    pub selection: SelectionArgs,
    #[command(flatten)]
    pub systematic: SystematicArgs,
}

impl SystematicArgs {
    /// Sets the options of the systematic errors.
    pub(crate) fn apply(&self, o: &mut CalibrationOptions) {
        o.time_offset = match self.time_offset {
            TimeOffset::Auto { .. } => TimeOffsetOption::Auto,
            TimeOffset::Fixed { imu_time_offset_s } => TimeOffsetOption::Seconds(imu_time_offset_s),
        };
        o.time_offset_max_s = self.time_offset_max_s;
        o.loop_check = self.loop_check;
        o.identify_damping = self.identify_damping;
        o.loop_tolerance = self.loop_tolerance;
        o.imu_despike = self.imu_despike;
    }
}

impl AnalysisArgs {
    /// Refuses options the chosen method ignores.
    pub(crate) fn check(&self) -> Result<()> {
        self.estimator.check_methods(&[self.method.method])
    }

    /// The options of a calibration with the loop at its default.
    pub(crate) fn options(&self) -> CalibrationOptions {
        let mut o = CalibrationOptions { method: self.method.method.name(), ..CalibrationOptions::default() };
        self.estimator.apply(&mut o);
        self.selection.apply(&mut o);
        self.systematic.apply(&mut o);
        o
    }
}

/// How GNSS-SDR dump records are selected.
#[derive(Args, Debug, Clone)]
#[command(next_help_heading = "GNSS-SDR dumps")]
pub(crate) struct ConversionArgs {
    /// Sampling rate of the tracking [Hz] when the configuration does not give it.
    #[arg(long, allow_negative_numbers = true, value_parser = positive)]
    pub gnss_sdr_fs_hz: Option<f64>,
    /// C/N0 threshold of GNSS-SDR's lock detector (Tracking_1C.cn0_min) [dB-Hz]: a record below
    /// it counts as a code-lock failure [default: the conf's cn0_min, GNSS-SDR's 25 when absent].
    #[arg(long, allow_negative_numbers = true)]
    pub gnss_sdr_min_cn0_dbhz: Option<f64>,
    /// Carrier lock test threshold of GNSS-SDR's lock detector (Tracking_1C.carrier_lock_th): a
    /// record below it counts as a carrier-lock failure [default: the conf's carrier_lock_th,
    /// GNSS-SDR's 0.7 when absent].
    #[arg(long, allow_negative_numbers = true)]
    pub gnss_sdr_min_lock_test: Option<f64>,
    /// Carrier-lock failures (net of passes) after which GNSS-SDR's lock detector declares a loss
    /// of lock (Tracking_1C.max_carrier_lock_fail) [default: the conf's, GNSS-SDR's 5000 when absent].
    #[arg(long)]
    pub gnss_sdr_max_carrier_lock_fail: Option<u32>,
    /// Code-lock (C/N0) failures (net of passes) after which GNSS-SDR's lock detector declares a
    /// loss of lock (Tracking_1C.max_lock_fail) [default: the conf's, GNSS-SDR's 50 when absent].
    #[arg(long)]
    pub gnss_sdr_max_lock_fail: Option<u32>,
    /// Seconds dropped after a channel switches to the narrow loop (default: derived from the
    /// narrow loop's slowest mode).
    #[arg(long, allow_negative_numbers = true)]
    pub gnss_sdr_settle_s: Option<f64>,
    /// Record layout of the dumps: a known one's name (gnss-sdr-0.0.17, gnss-sdr-0.0.21,
    /// gnss-sdr-kf-cc, gnss-sdr-legacy-88) to force it, or `name:type,...` for versions the
    /// reader does not know (default: recognised from each file).
    #[arg(long)]
    pub gnss_sdr_layout: Option<String>,
}

impl ConversionArgs {
    /// The conversion settings for dumps made with the configuration `conf`
    /// (GNSS-SDR's defaults when none is given), with the options that
    /// override the configuration's lock detector.
    pub(crate) fn import_settings(&self, conf: Option<&Path>) -> Result<ImportSettings> {
        let mut s = ImportSettings::from_conf(conf, self.gnss_sdr_fs_hz).map_err(|e| match e {
            gsens_gnss_sdr::GnssSdrError::UnknownSamplingRate => anyhow::anyhow!("{e}; give --gnss-sdr-fs-hz"),
            e => e.into(),
        })?;
        if let Some(v) = self.gnss_sdr_settle_s.filter(|v| !(*v >= 0.0 && v.is_finite())) {
            bail!("--gnss-sdr-settle-s must be ≥ 0, got {v}");
        }
        let lock = &mut s.tracking.lock;
        if let Some(v) = self.gnss_sdr_min_cn0_dbhz {
            if !v.is_finite() {
                bail!("--gnss-sdr-min-cn0-dbhz must be finite, got {v}");
            }
            lock.cn0_min_dbhz.set_option(v);
        }
        if let Some(v) = self.gnss_sdr_min_lock_test {
            if !(-1.0..=1.0).contains(&v) {
                bail!("--gnss-sdr-min-lock-test must lie in [-1, 1] (the lock test is cos 2φ), got {v}");
            }
            lock.carrier_lock_th.set_option(v);
        }
        if let Some(v) = self.gnss_sdr_max_carrier_lock_fail {
            lock.max_carrier_lock_fail.set_option(v);
        }
        if let Some(v) = self.gnss_sdr_max_lock_fail {
            lock.max_lock_fail.set_option(v);
        }
        s.settle_s = self.gnss_sdr_settle_s;
        if let Some(spec) = &self.gnss_sdr_layout {
            s.layout = Some(DumpLayout::parse_spec(spec).map_err(|e| anyhow::anyhow!("--gnss-sdr-layout: {e}"))?);
        }
        Ok(s)
    }
}

/// Options of `gsens estimate` and `gsens report` for GNSS-SDR tracking dumps.
#[derive(Args, Debug, Clone)]
pub(crate) struct GnssSdrArgs {
    /// Directory of GNSS-SDR tracking dumps (trk_ch_N.dat, Tracking_1C.dump=true) to use instead of --tracking.
    #[arg(long, requires = "gnss_sdr_conf")]
    pub gnss_sdr: Option<PathBuf>,
    /// The GNSS-SDR configuration file the dumps were made with (its loop is modelled exactly).
    /// With --tracking instead of --gnss-sdr: rows that came from that GNSS-SDR run another way
    /// (`gsens import gnss-sdr-monitor`), estimated with its exact loop.
    #[arg(long)]
    pub gnss_sdr_conf: Option<PathBuf>,
    #[command(flatten)]
    pub conversion: ConversionArgs,
}

/// How a PocketSDR log is converted (`gsens import pocketsdr` and `gsens estimate --pocketsdr`).
#[derive(Args, Debug, Clone)]
#[command(next_help_heading = "PocketSDR logs")]
pub(crate) struct PocketSdrConversionArgs {
    /// The pocket_trk options file (-opt FILE) the log was made with: its b_pll (the PLL
    /// bandwidth) and epoch (the $CH interval) [default: PocketSDR's defaults, b_pll = 5 Hz, and
    /// the log's own interval].
    #[arg(long)]
    pub pocketsdr_conf: Option<PathBuf>,
    /// Seconds dropped after a track's 1 s FLL pull-in [default: five time constants of the
    /// PLL's slowest mode, 5.2 s at 5 Hz].
    #[arg(long, allow_negative_numbers = true)]
    pub pocketsdr_settle_s: Option<f64>,
    /// pocket_trk's -toff: seconds it skipped at the start of the IF file.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub pocketsdr_toff_s: f64,
}

impl PocketSdrConversionArgs {
    /// The conversion settings.
    pub(crate) fn import_settings(&self) -> Result<gsens_pocketsdr::ImportSettings> {
        let mut s = gsens_pocketsdr::ImportSettings::from_options_file(self.pocketsdr_conf.as_deref())?;
        if let Some(v) = self.pocketsdr_settle_s.filter(|v| !(*v >= 0.0 && v.is_finite())) {
            bail!("--pocketsdr-settle-s must be ≥ 0, got {v}");
        }
        if !(self.pocketsdr_toff_s >= 0.0 && self.pocketsdr_toff_s.is_finite()) {
            bail!("--pocketsdr-toff-s must be ≥ 0, got {}", self.pocketsdr_toff_s);
        }
        s.settle_s = self.pocketsdr_settle_s;
        s.toff_s = self.pocketsdr_toff_s;
        Ok(s)
    }

    /// Whether any option differs from its default (they need a log to act on).
    pub(crate) fn given(&self) -> bool {
        self.pocketsdr_conf.is_some() || self.pocketsdr_settle_s.is_some() || self.pocketsdr_toff_s != 0.0
    }
}

/// Options of `gsens estimate` and `gsens report` for PocketSDR logs.
#[derive(Args, Debug, Clone)]
pub(crate) struct PocketSdrArgs {
    /// A pocket_trk log (-log FILE, its $CH lines) to use instead of --tracking; PocketSDR's
    /// carrier loop is modelled exactly.
    #[arg(long, conflicts_with = "gnss_sdr")]
    pub pocketsdr: Option<PathBuf>,
    #[command(flatten)]
    pub conversion: PocketSdrConversionArgs,
}

/// Where a calibration's logs come from (`estimate`, `report`): an IMU log
/// with a tracking log, GNSS-SDR dumps or a PocketSDR log.
#[derive(Args, Debug, Clone)]
pub(crate) struct InputArgs {
    /// IMU log: t_s,fx_mps2,fy_mps2,fz_mps2.
    #[arg(long)]
    pub imu: PathBuf,
    /// Tracking log: t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad (or --gnss-sdr, --pocketsdr).
    #[arg(long, required_unless_present_any = ["gnss_sdr", "pocketsdr"], conflicts_with_all = ["gnss_sdr", "pocketsdr"])]
    pub tracking: Option<PathBuf>,
    #[command(flatten)]
    pub gnss_sdr: GnssSdrArgs,
    #[command(flatten)]
    pub pocketsdr: PocketSdrArgs,
}

impl InputArgs {
    /// The inputs the options name, with their conversion settings.
    pub(crate) fn inputs(&self) -> Result<Inputs> {
        let imu = self.imu.clone();
        if let Some(log) = &self.pocketsdr.pocketsdr {
            let import = self.pocketsdr.conversion.import_settings()?;
            return Ok(Inputs::PocketSdr { imu, log: log.clone(), import });
        }
        if self.pocketsdr.conversion.given() {
            bail!("--pocketsdr-conf, --pocketsdr-settle-s and --pocketsdr-toff-s need --pocketsdr LOG");
        }
        let g = &self.gnss_sdr;
        let conf = g.gnss_sdr_conf.as_deref();
        Ok(match (&g.gnss_sdr, &self.tracking, conf) {
            (Some(dir), _, _) => Inputs::GnssSdrDumps {
                imu,
                dumps_dir: dir.clone(),
                import: g.conversion.import_settings(conf)?,
                conf: conf.map(Path::to_path_buf),
            },
            (None, Some(t), Some(conf)) => Inputs::GnssSdrRows {
                imu: Log::File(imu),
                tracking: Log::File(t.clone()),
                import: g.conversion.import_settings(Some(conf))?,
                conf: conf.to_path_buf(),
            },
            (None, Some(t), None) => Inputs::Csv { imu: Log::File(imu), tracking: Log::File(t.clone()) },
            (None, None, _) => bail!("--tracking is required (or --gnss-sdr, or --pocketsdr)"),
        })
    }
}
