//! The options of a calibration by name: the one vocabulary of the command
//! line's flags (`--bn-hz` is `bn_hz`) and of the Python module's keyword
//! arguments, and the one place where those names become
//! [`PipelineSettings`]. With the `clap` feature the option groups are
//! clap's `Args` and the option enums its `ValueEnum`: their doc comments
//! are the command line's help.

use crate::defaults::{
    DEFAULT_BN_HZ, DEFAULT_CHANNELS, DEFAULT_CN0_DROP_DB, DEFAULT_GAIN_K, DEFAULT_HIGHPASS_HZ, DEFAULT_ORDER,
    DEFAULT_TIME_OFFSET_MAX_S, DEFAULT_WARMUP_S,
};
#[cfg(feature = "clap")]
use crate::option_values::{
    elevation_deg, finite, finite_non_negative, forgetting_factor, non_negative_or_inf, positive,
    stated_time_offset_option,
};
use crate::settings::check_range;
use crate::{
    CalibError, EstimateSettings, LoopForm, LoopIdentificationMode, MeasurementChoice, Method, PipelineSettings,
    Robust, TimeOffset,
};
use core::f64::consts::FRAC_1_SQRT_2;
use gsens_core::{Discriminator, KAPLAN_A3, KAPLAN_B3, LoggedPhase, LoopImplementation, LoopModel, LoopSpec};
use gsens_session::{SelectionConfig, Weighting};
use serde::{Deserialize, Serialize};

/// The estimator, by name.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum MethodName {
    /// The paper's gradient observer (constant gain).
    ///
    /// Its gain is [`EstimatorOptions::gain_k`].
    Gradient,
    /// Recursive least squares (Kalman-type gain).
    ///
    /// Its forgetting factor is [`EstimatorOptions::lambda`].
    Rls,
    /// Batch least squares over the whole log.
    #[default]
    Batch,
    /// Generalized least squares: batch prewhitened by an AR model of the residual noise.
    Gls,
}

/// The IMU time offset as the options name it: `"auto"` (searched within
/// ±[`SystematicOptions::time_offset_max_s`]), `"none"` (0) or a number of
/// seconds (IMU time stamp minus true time). Serialized as that word or
/// number; any other word is an error naming `time_offset` and the choices.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[non_exhaustive]
pub enum TimeOffsetOption {
    /// Searched from the data.
    #[default]
    Auto,
    /// None: 0 s.
    None,
    /// A fixed offset \[s\].
    Seconds(f64),
}

impl Serialize for TimeOffsetOption {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            TimeOffsetOption::Auto => s.serialize_str("auto"),
            TimeOffsetOption::None => s.serialize_str("none"),
            TimeOffsetOption::Seconds(v) => s.serialize_f64(*v),
        }
    }
}

impl<'de> Deserialize<'de> for TimeOffsetOption {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Visitor;
        impl serde::de::Visitor<'_> for Visitor {
            type Value = TimeOffsetOption;
            fn expecting(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
                f.write_str("auto, none or a number of seconds")
            }
            fn visit_f64<E: serde::de::Error>(self, v: f64) -> Result<Self::Value, E> {
                Ok(TimeOffsetOption::Seconds(v))
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<Self::Value, E> {
                Ok(TimeOffsetOption::Seconds(v as f64))
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<Self::Value, E> {
                Ok(TimeOffsetOption::Seconds(v as f64))
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<Self::Value, E> {
                match v {
                    "auto" => Ok(TimeOffsetOption::Auto),
                    "none" => Ok(TimeOffsetOption::None),
                    _ => v.parse().map(TimeOffsetOption::Seconds).map_err(|_| {
                        E::custom(format!("time_offset: expected auto, none or a number of seconds, got `{v}`"))
                    }),
                }
            }
        }
        d.deserialize_any(Visitor)
    }
}

/// Every option of a calibration from logs, named as the command line names
/// its flags (with `_` for `-`), with the command line's defaults: the
/// carrier and the method, and the groups of the receiver loop, the
/// estimator, the channels and the systematic errors, whose names are the
/// options' own (serialized flat).
///
/// Deserializes from a map of those names (unknown names are an error that
/// lists the known ones), so that a Python call
/// `estimate(..., bn_hz=3, time_offset="none")` and
/// `gsens estimate --bn-hz 3 --time-offset none` mean the same thing;
/// [`CalibrationOptions::pipeline_settings`] checks the values and builds the
/// library's settings.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CalibrationOptions {
    /// Carrier frequency \[Hz\] for ppb/g (default GPS L1).
    pub carrier_hz: f64,
    /// The receiver's carrier loop.
    #[serde(flatten)]
    pub receiver_loop: LoopOptions,
    /// The estimator.
    pub method: MethodName,
    /// What the result's estimate is made from: the loop's input phase
    /// (loop-free) where the log holds the NCO's phase, else the tracking
    /// error through the loop model.
    pub measurement: MeasurementChoice,
    /// The estimators' parameters and the error model.
    #[serde(flatten)]
    pub estimator: EstimatorOptions,
    /// Which channels enter the average.
    #[serde(flatten)]
    pub selection: SelectionOptions,
    /// The systematic errors estimated jointly with Γ.
    #[serde(flatten)]
    pub systematic: SystematicOptions,
}

impl<'de> Deserialize<'de> for CalibrationOptions {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        use serde::de::Error;
        // serde's flatten cannot name the known options when one is unknown: the names are checked first.
        let given = serde_json::Map::deserialize(d)?;
        let known = serde_json::to_value(CalibrationOptions::default()).map_err(D::Error::custom)?;
        let known: Vec<&String> = known.as_object().map(|o| o.keys().collect()).unwrap_or_default();
        if let Some(name) = given.keys().find(|k| !known.contains(k)) {
            let known: Vec<String> = known.iter().map(|k| format!("`{k}`")).collect();
            return Err(D::Error::custom(format!("unknown field `{name}`, expected one of {}", known.join(", "))));
        }
        let g = Groups::deserialize(serde_json::Value::Object(given)).map_err(D::Error::custom)?;
        Ok(CalibrationOptions {
            carrier_hz: g.carrier_hz,
            receiver_loop: g.receiver_loop,
            method: g.method,
            measurement: g.measurement,
            estimator: g.estimator,
            selection: g.selection,
            systematic: g.systematic,
        })
    }
}

/// [`CalibrationOptions`] as serde derives its reading (every name known).
#[derive(Deserialize)]
#[serde(default)]
struct Groups {
    carrier_hz: f64,
    #[serde(flatten)]
    receiver_loop: LoopOptions,
    method: MethodName,
    measurement: MeasurementChoice,
    #[serde(flatten)]
    estimator: EstimatorOptions,
    #[serde(flatten)]
    selection: SelectionOptions,
    #[serde(flatten)]
    systematic: SystematicOptions,
}

impl Default for Groups {
    fn default() -> Self {
        let o = CalibrationOptions::default();
        Groups {
            carrier_hz: o.carrier_hz,
            receiver_loop: o.receiver_loop,
            method: o.method,
            measurement: o.measurement,
            estimator: o.estimator,
            selection: o.selection,
            systematic: o.systematic,
        }
    }
}

// The groups' doc comments are a command line's help (with the `clap`
// feature), where a unit reads `[Hz]`, not a link.

/// The receiver's carrier loop, as stated: with none of its order,
/// bandwidth, update interval and logged phase given, the data choose it
/// ([`crate::choose_loop`]).
#[allow(rustdoc::broken_intra_doc_links)]
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
#[cfg_attr(feature = "clap", command(next_help_heading = "Receiver loop"))]
pub struct LoopOptions {
    /// Loop order of the receiver's carrier PLL.
    #[cfg_attr(feature = "clap", arg(long, value_parser = clap::value_parser!(u8).range(2..=3)))]
    pub order: Option<u8>,
    /// One-sided noise bandwidth Bn of the receiver's PLL [Hz] (default 3).
    #[cfg_attr(feature = "clap", arg(long, allow_negative_numbers = true, value_parser = positive))]
    pub bn_hz: Option<f64>,
    /// Damping ratio ζ of a 2nd-order loop [default: 1/√2 = 0.707].
    #[cfg_attr(
        feature = "clap",
        arg(long, allow_negative_numbers = true, value_parser = positive, default_value_t = FRAC_1_SQRT_2, hide_default_value = true)
    )]
    pub zeta: f64,
    /// a3 of a 3rd-order loop (with `order` 3) [default: Kaplan's 1.1].
    #[cfg_attr(
        feature = "clap",
        arg(long, allow_negative_numbers = true, value_parser = positive, default_value_t = KAPLAN_A3, hide_default_value = true)
    )]
    pub a3: f64,
    /// b3 of a 3rd-order loop (with `order` 3) [default: Kaplan's 2.4].
    #[cfg_attr(
        feature = "clap",
        arg(long, allow_negative_numbers = true, value_parser = positive, default_value_t = KAPLAN_B3, hide_default_value = true)
    )]
    pub b3: f64,
    /// The receiver's loop update interval [s] (default: the log interval).
    #[cfg_attr(feature = "clap", arg(long, allow_negative_numbers = true, value_parser = positive))]
    pub loop_interval_s: Option<f64>,
    /// What a log row holds when the loop runs faster than the log (default: last).
    #[cfg_attr(feature = "clap", arg(long, value_enum))]
    pub logged_phase: Option<LoggedPhase>,
    /// Which receiver's discrete form the stated loop is (default: the data choose among the forms its order, bandwidth and interval take in the receivers gsens models, and σ takes in the others by the data's odds for them).
    #[cfg_attr(feature = "clap", arg(long, value_enum))]
    pub loop_implementation: Option<LoopImplementation>,
    /// The receiver's carrier-phase discriminator, whose linear range bounds the g-induced phase error (GNSS-SDR and PocketSDR sessions: theirs, atan-costas for GPS L1 C/A).
    #[cfg_attr(feature = "clap", arg(long, value_enum, default_value_t))]
    pub discriminator: Discriminator,
}

impl Default for LoopOptions {
    fn default() -> Self {
        LoopOptions {
            order: None,
            bn_hz: None,
            zeta: FRAC_1_SQRT_2,
            a3: KAPLAN_A3,
            b3: KAPLAN_B3,
            loop_interval_s: None,
            logged_phase: None,
            loop_implementation: None,
            discriminator: Discriminator::AtanCostas,
        }
    }
}

/// The estimators' parameters and the error model.
#[allow(rustdoc::broken_intra_doc_links)]
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
#[cfg_attr(feature = "clap", command(next_help_heading = "Estimator"))]
pub struct EstimatorOptions {
    /// Gain k of the gradient observer (method `gradient` only) [default: 0.5].
    #[cfg_attr(
        feature = "clap",
        arg(long, allow_negative_numbers = true, value_parser = positive, default_value_t = DEFAULT_GAIN_K, hide_default_value = true)
    )]
    pub gain_k: f64,
    /// Forgetting factor λ of the RLS estimator, in (0, 1] (method `rls` only) [default: 1, none].
    #[cfg_attr(
        feature = "clap",
        arg(long, allow_negative_numbers = true, value_parser = forgetting_factor, default_value_t = 1.0, hide_default_value = true)
    )]
    pub lambda: f64,
    /// Seconds at the start that only drive the loop models (their start-up transient).
    #[cfg_attr(
        feature = "clap",
        arg(long, default_value_t = DEFAULT_WARMUP_S, allow_negative_numbers = true, value_parser = finite_non_negative)
    )]
    pub warmup_s: f64,
    /// 1σ scale-factor error of the IMU [ppm] (from its datasheet), added to Γ̂'s uncertainty.
    #[cfg_attr(
        feature = "clap",
        arg(long, default_value_t = 0.0, allow_negative_numbers = true, value_parser = finite_non_negative)
    )]
    pub imu_scale_sigma_ppm: f64,
    /// 1σ axis misalignment of the IMU [mrad], added to Γ̂'s uncertainty.
    #[cfg_attr(
        feature = "clap",
        arg(long, default_value_t = 0.0, allow_negative_numbers = true, value_parser = finite_non_negative)
    )]
    pub imu_misalignment_sigma_mrad: f64,
    /// Corner of the identical high-pass on φ and φ_a [Hz] (0 = off).
    #[cfg_attr(
        feature = "clap",
        arg(long, default_value_t = DEFAULT_HIGHPASS_HZ, allow_negative_numbers = true, value_parser = finite_non_negative)
    )]
    pub highpass_hz: f64,
    /// Robust estimation against outlying epochs: `huber` (IRLS; batch method only) or `none`.
    #[cfg_attr(feature = "clap", arg(long, value_enum, default_value_t))]
    pub robust: Robust,
}

impl Default for EstimatorOptions {
    fn default() -> Self {
        EstimatorOptions {
            gain_k: DEFAULT_GAIN_K,
            lambda: 1.0,
            warmup_s: DEFAULT_WARMUP_S,
            imu_scale_sigma_ppm: 0.0,
            imu_misalignment_sigma_mrad: 0.0,
            highpass_hz: DEFAULT_HIGHPASS_HZ,
            robust: Robust::None,
        }
    }
}

/// Which channels enter the average, and the screening of each.
#[allow(rustdoc::broken_intra_doc_links)]
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
#[cfg_attr(feature = "clap", command(next_help_heading = "Channels"))]
pub struct SelectionOptions {
    /// Average the N channels with the highest mean C/N0, or the least noisy when C/N0 does not vary between them (0 = all that pass the masks).
    #[cfg_attr(feature = "clap", arg(long, default_value_t = DEFAULT_CHANNELS))]
    pub channels: usize,
    /// Drop rows below this C/N0 [dB-Hz].
    #[cfg_attr(feature = "clap", arg(long, allow_negative_numbers = true, value_parser = finite))]
    pub min_cn0_dbhz: Option<f64>,
    /// Drop rows below this elevation [deg] (rows without elevation pass).
    #[cfg_attr(feature = "clap", arg(long, allow_negative_numbers = true, value_parser = elevation_deg))]
    pub elevation_mask_deg: Option<f64>,
    /// Weights of the per-epoch channel average.
    #[cfg_attr(feature = "clap", arg(long, value_enum, default_value_t))]
    pub weights: Weighting,
    /// Per-channel screening before averaging: cycle slips, losses of lock, C/N0 drops, |φ| beyond the linear range.
    #[cfg_attr(
        feature = "clap",
        arg(long, default_value = "on", value_name = "on|off", hide_possible_values = true, value_parser = clap::builder::BoolishValueParser::new(), action = clap::ArgAction::Set)
    )]
    pub screening: bool,
    /// Screening: exclude rows whose C/N0 is more than this below the channel's median [dB] (0 = no test).
    #[cfg_attr(
        feature = "clap",
        arg(long, default_value_t = DEFAULT_CN0_DROP_DB, allow_negative_numbers = true, value_parser = finite_non_negative)
    )]
    pub cn0_drop_db: f64,
    /// Screening: exclude rows whose |phase error| exceeds this [rad] (0 = no limit; default: half the discriminator's unambiguous range, π/4 for atan-costas, π/2 for atan2).
    #[cfg_attr(feature = "clap", arg(long, allow_negative_numbers = true, value_parser = finite_non_negative))]
    pub max_abs_phase_rad: Option<f64>,
}

impl Default for SelectionOptions {
    fn default() -> Self {
        SelectionOptions {
            channels: DEFAULT_CHANNELS,
            min_cn0_dbhz: None,
            elevation_mask_deg: None,
            weights: Weighting::Equal,
            screening: true,
            cn0_drop_db: DEFAULT_CN0_DROP_DB,
            max_abs_phase_rad: None,
        }
    }
}

/// The systematic errors estimated jointly with Γ: the IMU's time offset,
/// the stated loop's error, the IMU's spikes.
#[allow(rustdoc::broken_intra_doc_links)]
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
#[cfg_attr(feature = "clap", command(next_help_heading = "Systematic errors"))]
pub struct SystematicOptions {
    /// IMU time stamp minus true time: `auto` (estimated jointly with Γ), `none` (0) or SECONDS.
    #[cfg_attr(
        feature = "clap",
        arg(long, default_value = "auto", allow_hyphen_values = true, value_parser = stated_time_offset_option)
    )]
    pub time_offset: TimeOffsetOption,
    /// Search range ± of `time_offset` `auto` [s].
    #[cfg_attr(
        feature = "clap",
        arg(long, default_value_t = DEFAULT_TIME_OFFSET_MAX_S, allow_negative_numbers = true, value_parser = finite_non_negative)
    )]
    pub time_offset_max_s: f64,
    /// Test the stated loop against the data: its natural frequency is estimated jointly with Γ and the time offset, a
    /// stated loop the data reject is flagged, and Γ̂ is given under the fitted loop with the loop's uncertainty in its
    /// σ. `off` takes the stated loop as exact.
    #[cfg_attr(
        feature = "clap",
        arg(long, default_value = "on", value_name = "on|off", hide_possible_values = true, value_parser = clap::builder::BoolishValueParser::new(), action = clap::ArgAction::Set)
    )]
    pub loop_check: bool,
    /// With the loop check: fit a 2nd-order loop's damping ζ too (weakly determined by near-sinusoidal shaking).
    #[cfg_attr(feature = "clap", arg(long))]
    pub identify_damping: bool,
    /// How well the stated loop is known: the relative 1σ uncertainty of its natural frequency. The data's fit of the
    /// loop and the stated loop within this tolerance are combined, and what remains uncertain is in σ. `0`: the
    /// receiver implements exactly the stated loop (Γ̂ reaches the known-loop bound, but a loop error below the
    /// test's reach, about 2 % on the paper's session, then biases Γ̂ unseen); `inf`: only the loop's shape is
    /// known. Default: 0 for a loop modelled from the receiver's configuration (GNSS-SDR dumps, PocketSDR logs), 0.02
    /// for a loop stated by `order`/`bn_hz`.
    #[cfg_attr(
        feature = "clap",
        arg(long, value_name = "FRACTION", allow_negative_numbers = true, value_parser = non_negative_or_inf)
    )]
    pub loop_tolerance: Option<f64>,
    /// Replace isolated IMU spikes (single samples no hand motion can produce) by their neighbours' mean.
    #[cfg_attr(
        feature = "clap",
        arg(long, default_value = "on", value_name = "on|off", hide_possible_values = true, value_parser = clap::builder::BoolishValueParser::new(), action = clap::ArgAction::Set)
    )]
    pub imu_despike: bool,
}

impl Default for SystematicOptions {
    fn default() -> Self {
        SystematicOptions {
            time_offset: TimeOffsetOption::Auto,
            time_offset_max_s: DEFAULT_TIME_OFFSET_MAX_S,
            loop_check: true,
            identify_damping: false,
            loop_tolerance: None,
            imu_despike: true,
        }
    }
}

impl Default for CalibrationOptions {
    fn default() -> Self {
        CalibrationOptions {
            carrier_hz: gsens_core::units::GPS_L1_HZ,
            receiver_loop: LoopOptions::default(),
            method: MethodName::Batch,
            measurement: MeasurementChoice::Auto,
            estimator: EstimatorOptions::default(),
            selection: SelectionOptions::default(),
            systematic: SystematicOptions::default(),
        }
    }
}

impl LoopOptions {
    /// The receiver loop: Kaplan's loop of [`order`](Self::order) (2 unless
    /// 3) and [`bn_hz`](Self::bn_hz) (3 Hz unless given).
    pub fn loop_model(&self) -> LoopModel {
        let bn_hz = self.bn_hz.unwrap_or(DEFAULT_BN_HZ);
        // pipeline_settings refuses other orders; unchecked options keep the 2nd order's shape.
        let spec = LoopSpec::of_order(self.order.unwrap_or(DEFAULT_ORDER), bn_hz, self.zeta, self.a3, self.b3)
            .unwrap_or(LoopSpec::SecondOrder { bn_hz, zeta: self.zeta });
        LoopModel::kaplan(spec, self.loop_interval_s)
    }

    /// Whether the loop was stated (its order, bandwidth, update interval or
    /// logged phase given); otherwise the data choose it ([`crate::choose_loop`]).
    pub fn stated(&self) -> bool {
        self.order.is_some() || self.bn_hz.is_some() || self.loop_interval_s.is_some() || self.logged_phase.is_some()
    }

    /// Refuses a shape parameter of the other order's loop among the options
    /// `stated` (by name): ζ shapes a 2nd-order loop only, a3 and b3 a
    /// 3rd-order one. The message names each option by `name` (a command
    /// line's flag, say).
    pub fn refuse_other_shape(&self, stated: &[&str], name: impl Fn(&str) -> String) -> Result<(), CalibError> {
        let third = self.order == Some(3);
        let (zeta, a3, b3, order) = (name("zeta"), name("a3"), name("b3"), name("order"));
        if third && stated.contains(&"zeta") {
            let why =
                format!("{zeta} is the damping of a 2nd-order loop: a 3rd-order loop ({order} 3) takes {a3} and {b3}");
            return Err(CalibError::Ignored(why));
        }
        if !third && (stated.contains(&"a3") || stated.contains(&"b3")) {
            let why =
                format!("{a3} and {b3} shape a 3rd-order loop: they need {order} 3 (a 2nd-order loop takes {zeta})");
            return Err(CalibError::Ignored(why));
        }
        Ok(())
    }
}

impl EstimatorOptions {
    /// Refuses a method's parameter among the options `stated` (by name)
    /// when none of `methods` uses it: `gain_k` is the gradient observer's,
    /// `lambda` the RLS estimator's. The message names each option by `name`.
    pub fn refuse_unused(
        &self,
        stated: &[&str],
        methods: &[MethodName],
        name: impl Fn(&str) -> String,
    ) -> Result<(), CalibError> {
        let names = || methods.iter().map(|m| m.name()).collect::<Vec<_>>().join(", ");
        let method = name("method");
        if stated.contains(&"lambda") && !methods.contains(&MethodName::Rls) {
            let why = format!(
                "{} is the RLS estimator's forgetting factor: it needs {method} rls (the method is {})",
                name("lambda"),
                names()
            );
            return Err(CalibError::Ignored(why));
        }
        if stated.contains(&"gain_k") && !methods.contains(&MethodName::Gradient) {
            let why = format!(
                "{} is the gradient observer's gain: it needs {method} gradient (the method is {})",
                name("gain_k"),
                names()
            );
            return Err(CalibError::Ignored(why));
        }
        Ok(())
    }
}

impl MethodName {
    /// Its name, as serde spells it.
    pub const fn name(self) -> &'static str {
        match self {
            MethodName::Gradient => "gradient",
            MethodName::Rls => "rls",
            MethodName::Batch => "batch",
            MethodName::Gls => "gls",
        }
    }
}

impl CalibrationOptions {
    /// The receiver loop ([`LoopOptions::loop_model`]).
    pub fn loop_model(&self) -> LoopModel {
        self.receiver_loop.loop_model()
    }

    /// Whether the loop was stated ([`LoopOptions::stated`]).
    pub fn loop_stated(&self) -> bool {
        self.receiver_loop.stated()
    }

    /// Refuses options among those `stated` (by name) that the loop's order
    /// or the method ignores ([`LoopOptions::refuse_other_shape`],
    /// [`EstimatorOptions::refuse_unused`]); the message names each option
    /// by `name`.
    pub fn refuse_ignored(&self, stated: &[&str], name: impl Fn(&str) -> String) -> Result<(), CalibError> {
        self.receiver_loop.refuse_other_shape(stated, &name)?;
        self.estimator.refuse_unused(stated, &[self.method], &name)
    }

    /// The estimator with its parameter.
    pub fn method(&self) -> Method {
        match self.method {
            MethodName::Batch => Method::Batch,
            MethodName::Gls => Method::Gls,
            MethodName::Rls => Method::Rls { lambda: self.estimator.lambda },
            MethodName::Gradient => Method::Gradient { gain_k: self.estimator.gain_k },
        }
    }

    /// The estimation stage's settings (the loop included).
    pub fn estimate_settings(&self) -> EstimateSettings {
        EstimateSettings {
            receiver_loop: self.loop_model(),
            logged_phase: self.receiver_loop.logged_phase.unwrap_or(LoggedPhase::Last),
            carrier_hz: self.carrier_hz,
            method: self.method(),
            warmup_s: self.estimator.warmup_s,
            imu_scale_sigma: self.estimator.imu_scale_sigma_ppm * 1e-6,
            imu_misalignment_sigma_rad: self.estimator.imu_misalignment_sigma_mrad * 1e-3,
            highpass_hz: self.estimator.highpass_hz,
            robust: self.estimator.robust,
            discriminator: self.receiver_loop.discriminator,
            ..EstimateSettings::default()
        }
    }

    /// The channel selection (a 0 of `channels`, `cn0_drop_db` or
    /// `max_abs_phase_rad` switches that limit off; `max_abs_phase_rad`
    /// unset is half the discriminator's unambiguous range).
    pub fn selection(&self) -> SelectionConfig {
        let mut s = SelectionConfig {
            max_channels: (self.selection.channels > 0).then_some(self.selection.channels),
            min_cn0_dbhz: self.selection.min_cn0_dbhz,
            elevation_mask_deg: self.selection.elevation_mask_deg,
            weighting: self.selection.weights,
            ..SelectionConfig::default()
        };
        s.screening.enabled = self.selection.screening;
        s.screening.cn0_drop_db = (self.selection.cn0_drop_db > 0.0).then_some(self.selection.cn0_drop_db);
        let limit =
            self.selection.max_abs_phase_rad.unwrap_or(0.5 * self.receiver_loop.discriminator.unambiguous_range_rad());
        s.screening.max_abs_phase_rad = (limit > 0.0).then_some(limit);
        s
    }

    /// The pipeline's settings around `estimate` (the estimation stage's,
    /// which a caller may have adapted: a simulated scenario's loop, say):
    /// selection, time offset, loop identification, despiking. The loop of
    /// `estimate` counts as stated, its implementation included: its form is
    /// not compared with other receivers' ([`PipelineSettings::loop_form`]).
    pub fn pipeline_settings_around(&self, estimate: EstimateSettings) -> Result<PipelineSettings, CalibError> {
        for (name, value) in [
            ("warmup_s", self.estimator.warmup_s),
            ("imu_scale_sigma_ppm", self.estimator.imu_scale_sigma_ppm),
            ("imu_misalignment_sigma_mrad", self.estimator.imu_misalignment_sigma_mrad),
            ("highpass_hz", self.estimator.highpass_hz),
            ("cn0_drop_db", self.selection.cn0_drop_db),
            ("max_abs_phase_rad", self.selection.max_abs_phase_rad.unwrap_or(0.0)),
            ("time_offset_max_s", self.systematic.time_offset_max_s),
        ] {
            check_range(name, value, false)?;
        }
        if let Some(t) = self.systematic.loop_tolerance.filter(|t| t.is_nan() || *t < 0.0) {
            let expected = "at least 0: a relative 1σ (0.02 = 2 %), 0 for a loop known exactly, inf for a loop known only by its shape";
            return Err(CalibError::Setting { name: "loop_tolerance", value: t, expected });
        }
        if let Some(order) = self.receiver_loop.order.filter(|o| !(2..=3).contains(o)) {
            return Err(CalibError::Setting { name: "order", value: f64::from(order), expected: "2 or 3" });
        }
        let time_offset = match &self.systematic.time_offset {
            TimeOffsetOption::Seconds(s) if s.is_finite() => TimeOffset::Fixed { imu_time_offset_s: *s },
            TimeOffsetOption::Seconds(s) => {
                return Err(CalibError::Setting { name: "time_offset", value: *s, expected: "finite" });
            }
            TimeOffsetOption::Auto => TimeOffset::Auto { max_abs_s: self.systematic.time_offset_max_s },
            TimeOffsetOption::None => TimeOffset::Fixed { imu_time_offset_s: 0.0 },
        };
        let loop_identification = match (self.systematic.loop_check, self.systematic.identify_damping) {
            (false, _) => LoopIdentificationMode::Off,
            (true, false) => LoopIdentificationMode::NaturalFrequency,
            (true, true) => LoopIdentificationMode::NaturalFrequencyAndDamping,
        };
        Ok(PipelineSettings {
            estimate,
            selection: self.selection(),
            time_offset,
            despike_imu: self.systematic.imu_despike,
            loop_identification,
            loop_tolerance: self.systematic.loop_tolerance,
            measurement: self.measurement,
            ..PipelineSettings::default()
        })
    }

    /// The whole pipeline's settings, every value checked (the loop stated
    /// when [`loop_stated`](Self::loop_stated)).
    pub fn pipeline_settings(&self) -> Result<PipelineSettings, CalibError> {
        let estimate = self.estimate_settings();
        estimate.validate()?;
        let mut p = self.pipeline_settings_around(estimate)?;
        p.loop_stated = self.loop_stated();
        p.loop_form = match (p.loop_stated, self.receiver_loop.loop_implementation) {
            (true, None) => LoopForm::Compared,
            (true, Some(i)) => LoopForm::Named(i),
            (false, None) => LoopForm::Exact,
            (false, Some(_)) => {
                return Err(CalibError::Unsupported(
                    "a loop implementation names the form of a stated loop: state its order, bandwidth or update \
                     interval too",
                ));
            }
        };
        Ok(p)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The options read by their flat names, the groups' defaults filling in
    /// the rest; an unknown name is an error listing the known ones.
    #[test]
    fn options_read_by_name_and_an_unknown_name_lists_the_known_ones() {
        let json =
            r#"{"bn_hz": 3, "order": 3, "time_offset": "none", "weights": "cn0", "method": "rls", "lambda": 0.99}"#;
        let o: CalibrationOptions = serde_json::from_str(json).unwrap();
        assert_eq!((o.receiver_loop.bn_hz, o.receiver_loop.order), (Some(3.0), Some(3)));
        assert_eq!((o.method, o.estimator.lambda), (MethodName::Rls, 0.99));
        assert_eq!((o.systematic.time_offset, o.selection.weights), (TimeOffsetOption::None, Weighting::Cn0));
        assert_eq!(o.estimator.warmup_s, DEFAULT_WARMUP_S);
        let back: CalibrationOptions = serde_json::from_str(&serde_json::to_string(&o).unwrap()).unwrap();
        assert_eq!(back, o);
        let e = serde_json::from_str::<CalibrationOptions>(r#"{"bn_hertz": 3}"#).unwrap_err().to_string();
        assert!(e.starts_with("unknown field `bn_hertz`, expected one of `a3`, `b3`, `bn_hz`, `carrier_hz`,"), "{e}");
        assert!(e.contains("`imu_despike`"), "{e}");
        let e = serde_json::from_str::<CalibrationOptions>(r#"{"order": "two"}"#).unwrap_err().to_string();
        assert!(e.contains("invalid type: string \"two\""), "{e}");
    }

    /// The time offset reads as a word or a number (also a number in a
    /// string), writes back as it was given, and any other word names the
    /// option and its choices.
    #[test]
    fn time_offset_reads_words_and_numbers_and_names_itself_when_wrong() {
        let read = |json: &str| serde_json::from_str::<TimeOffsetOption>(json);
        assert_eq!(read("\"auto\"").unwrap(), TimeOffsetOption::Auto);
        assert_eq!(read("\"none\"").unwrap(), TimeOffsetOption::None);
        assert_eq!(read("-0.01").unwrap(), TimeOffsetOption::Seconds(-0.01));
        assert_eq!(read("2").unwrap(), TimeOffsetOption::Seconds(2.0));
        assert_eq!(read("\"0.5\"").unwrap(), TimeOffsetOption::Seconds(0.5));
        for o in [TimeOffsetOption::Auto, TimeOffsetOption::None, TimeOffsetOption::Seconds(-0.01)] {
            assert_eq!(read(&serde_json::to_string(&o).unwrap()).unwrap(), o);
        }
        let e = read("\"later\"").unwrap_err().to_string();
        assert!(e.contains("time_offset") && e.contains("auto, none or a number of seconds"), "{e}");
    }
}
