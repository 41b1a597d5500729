//! The options of a calibration by name: the one vocabulary of the command
//! line's flags (`--bn-hz` is `bn_hz`) and of the Python module's keyword
//! arguments, and the one place where those names become
//! [`PipelineSettings`].

use crate::defaults::{
    DEFAULT_BN_HZ, DEFAULT_CHANNELS, DEFAULT_CN0_DROP_DB, DEFAULT_GAIN_K, DEFAULT_HIGHPASS_HZ, DEFAULT_ORDER,
    DEFAULT_TIME_OFFSET_MAX_S, DEFAULT_WARMUP_S,
};
use crate::settings::check_range;
use crate::{CalibError, EstimateSettings, LoopIdentificationMode, Method, PipelineSettings, Robust, TimeOffset};
use gsens_core::{Discriminator, KAPLAN_A3, KAPLAN_B3, LoggedPhase, LoopModel, LoopSpec};
use gsens_session::{SelectionConfig, Weighting};
use serde::{Deserialize, Serialize};

/// The estimator, by name.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum MethodName {
    /// The paper's gradient observer (constant gain [`CalibrationOptions::gain_k`]).
    Gradient,
    /// Recursive least squares (forgetting factor [`CalibrationOptions::lambda`]).
    Rls,
    /// Batch least squares over the whole log.
    #[default]
    Batch,
    /// Batch least squares prewhitened by an AR model of the residual noise.
    Gls,
}

/// The IMU time offset as the options name it: `"auto"` (searched within
/// ±[`CalibrationOptions::time_offset_max_s`]), `"none"` (0) or a number of
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
/// its flags (with `_` for `-`), with the command line's defaults.
///
/// Deserializes from a map of those names (unknown names are an error that
/// lists the known ones), so that a Python call
/// `estimate(..., bn_hz=3, time_offset="none")` and
/// `gsens estimate --bn-hz 3 --time-offset none` mean the same thing;
/// [`CalibrationOptions::pipeline_settings`] checks the values and builds the
/// library's settings.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CalibrationOptions {
    /// Carrier frequency \[Hz\] for ppb/g (default GPS L1).
    pub carrier_hz: f64,
    /// Order of the receiver's carrier PLL (2 or 3; `None`: 2, and the loop not stated).
    pub order: Option<u8>,
    /// One-sided noise bandwidth Bn of the receiver's PLL \[Hz\] (`None`: 3, and the loop not stated).
    pub bn_hz: Option<f64>,
    /// Damping ratio ζ of a 2nd-order loop.
    pub zeta: f64,
    /// a3 of a 3rd-order loop (Kaplan: 1.1).
    pub a3: f64,
    /// b3 of a 3rd-order loop (Kaplan: 2.4).
    pub b3: f64,
    /// The loop's update interval \[s\] (`None`: the log interval).
    pub loop_interval_s: Option<f64>,
    /// What a log row holds when the loop runs faster than the log (`None`: the last output).
    pub logged_phase: Option<LoggedPhase>,
    /// The estimator.
    pub method: MethodName,
    /// Gain k of the gradient observer.
    pub gain_k: f64,
    /// Forgetting factor λ of the RLS estimator (1 = none).
    pub lambda: f64,
    /// Seconds at the start that only drive the loop models.
    pub warmup_s: f64,
    /// 1σ scale-factor error of the IMU \[ppm\], added to Γ̂'s uncertainty.
    pub imu_scale_sigma_ppm: f64,
    /// 1σ axis misalignment of the IMU \[mrad\], added to Γ̂'s uncertainty.
    pub imu_misalignment_sigma_mrad: f64,
    /// Corner of the identical high-pass on φ and φ_a \[Hz\] (0 = off).
    pub highpass_hz: f64,
    /// Robust estimation against outlying epochs.
    pub robust: Robust,
    /// Average the N channels with the highest mean C/N0 (0 = all that pass the masks).
    pub channels: usize,
    /// Drop rows below this C/N0 \[dB-Hz\].
    pub min_cn0_dbhz: Option<f64>,
    /// Drop rows below this elevation \[deg\].
    pub elevation_mask_deg: Option<f64>,
    /// Weights of the per-epoch channel average.
    pub weights: Weighting,
    /// Per-channel screening before averaging.
    pub screening: bool,
    /// Screening: rows more than this below the channel's median C/N0 \[dB\] (0 = no test).
    pub cn0_drop_db: f64,
    /// Screening: rows with |phase error| beyond this \[rad\] (0 = no limit;
    /// `None`: half the discriminator's unambiguous range, π/4 for atan
    /// Costas, π/2 for atan2; see [`gsens_session::ScreeningConfig`]).
    pub max_abs_phase_rad: Option<f64>,
    /// The receiver's carrier-phase discriminator (default atan Costas,
    /// atan(Q/I), what GPS L1 C/A receivers use).
    pub discriminator: Discriminator,
    /// The IMU time offset.
    pub time_offset: TimeOffsetOption,
    /// Search range ± of `time_offset = "auto"` \[s\].
    pub time_offset_max_s: f64,
    /// Test the stated loop against the data (natural frequency fitted jointly with Γ).
    pub loop_check: bool,
    /// With the loop check: fit a 2nd-order loop's damping too.
    pub identify_damping: bool,
    /// The relative 1σ uncertainty of the stated loop's natural frequency
    /// (0: exact; infinite: only its shape is known; `None`: the input's own,
    /// [`crate::DEFAULT_LOOP_TOLERANCE`] for a loop stated by options).
    pub loop_tolerance: Option<f64>,
    /// Replace isolated IMU spikes by their neighbours' mean.
    pub imu_despike: bool,
}

impl Default for CalibrationOptions {
    fn default() -> Self {
        CalibrationOptions {
            carrier_hz: gsens_core::units::GPS_L1_HZ,
            order: None,
            bn_hz: None,
            zeta: core::f64::consts::FRAC_1_SQRT_2,
            a3: KAPLAN_A3,
            b3: KAPLAN_B3,
            loop_interval_s: None,
            logged_phase: None,
            method: MethodName::Batch,
            gain_k: DEFAULT_GAIN_K,
            lambda: 1.0,
            warmup_s: DEFAULT_WARMUP_S,
            imu_scale_sigma_ppm: 0.0,
            imu_misalignment_sigma_mrad: 0.0,
            highpass_hz: DEFAULT_HIGHPASS_HZ,
            robust: Robust::None,
            channels: DEFAULT_CHANNELS,
            min_cn0_dbhz: None,
            elevation_mask_deg: None,
            weights: Weighting::Equal,
            screening: true,
            cn0_drop_db: DEFAULT_CN0_DROP_DB,
            max_abs_phase_rad: None,
            discriminator: Discriminator::AtanCostas,
            time_offset: TimeOffsetOption::Auto,
            time_offset_max_s: DEFAULT_TIME_OFFSET_MAX_S,
            loop_check: true,
            identify_damping: false,
            loop_tolerance: None,
            imu_despike: true,
        }
    }
}

impl CalibrationOptions {
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
    pub fn loop_stated(&self) -> bool {
        self.order.is_some() || self.bn_hz.is_some() || self.loop_interval_s.is_some() || self.logged_phase.is_some()
    }

    /// The estimator with its parameter.
    pub fn method(&self) -> Method {
        match self.method {
            MethodName::Batch => Method::Batch,
            MethodName::Gls => Method::Gls,
            MethodName::Rls => Method::Rls { lambda: self.lambda },
            MethodName::Gradient => Method::Gradient { gain_k: self.gain_k },
        }
    }

    /// The estimation stage's settings (the loop included).
    pub fn estimate_settings(&self) -> EstimateSettings {
        EstimateSettings {
            receiver_loop: self.loop_model(),
            logged_phase: self.logged_phase.unwrap_or(LoggedPhase::Last),
            carrier_hz: self.carrier_hz,
            method: self.method(),
            warmup_s: self.warmup_s,
            imu_scale_sigma: self.imu_scale_sigma_ppm * 1e-6,
            imu_misalignment_sigma_rad: self.imu_misalignment_sigma_mrad * 1e-3,
            highpass_hz: self.highpass_hz,
            robust: self.robust,
            discriminator: self.discriminator,
            ..EstimateSettings::default()
        }
    }

    /// The channel selection (a 0 of `channels`, `cn0_drop_db` or
    /// `max_abs_phase_rad` switches that limit off; `max_abs_phase_rad`
    /// unset is half the discriminator's unambiguous range).
    pub fn selection(&self) -> SelectionConfig {
        let mut s = SelectionConfig {
            max_channels: (self.channels > 0).then_some(self.channels),
            min_cn0_dbhz: self.min_cn0_dbhz,
            elevation_mask_deg: self.elevation_mask_deg,
            weighting: self.weights,
            ..SelectionConfig::default()
        };
        s.screening.enabled = self.screening;
        s.screening.cn0_drop_db = (self.cn0_drop_db > 0.0).then_some(self.cn0_drop_db);
        let limit = self.max_abs_phase_rad.unwrap_or(0.5 * self.discriminator.unambiguous_range_rad());
        s.screening.max_abs_phase_rad = (limit > 0.0).then_some(limit);
        s
    }

    /// The pipeline's settings around `estimate` (the estimation stage's,
    /// which a caller may have adapted: a simulated scenario's loop, say):
    /// selection, time offset, loop identification, despiking. The loop of
    /// `estimate` counts as stated.
    pub fn pipeline_settings_around(&self, estimate: EstimateSettings) -> Result<PipelineSettings, CalibError> {
        for (name, value) in [
            ("warmup_s", self.warmup_s),
            ("imu_scale_sigma_ppm", self.imu_scale_sigma_ppm),
            ("imu_misalignment_sigma_mrad", self.imu_misalignment_sigma_mrad),
            ("highpass_hz", self.highpass_hz),
            ("cn0_drop_db", self.cn0_drop_db),
            ("max_abs_phase_rad", self.max_abs_phase_rad.unwrap_or(0.0)),
            ("time_offset_max_s", self.time_offset_max_s),
        ] {
            check_range(name, value, false)?;
        }
        if let Some(t) = self.loop_tolerance.filter(|t| t.is_nan() || *t < 0.0) {
            let expected = "at least 0: a relative 1σ (0.02 = 2 %), 0 for a loop known exactly, inf for a loop known only by its shape";
            return Err(CalibError::Setting { name: "loop_tolerance", value: t, expected });
        }
        if let Some(order) = self.order.filter(|o| !(2..=3).contains(o)) {
            return Err(CalibError::Setting { name: "order", value: f64::from(order), expected: "2 or 3" });
        }
        let time_offset = match &self.time_offset {
            TimeOffsetOption::Seconds(s) if s.is_finite() => TimeOffset::Fixed { imu_time_offset_s: *s },
            TimeOffsetOption::Seconds(s) => {
                return Err(CalibError::Setting { name: "time_offset", value: *s, expected: "finite" });
            }
            TimeOffsetOption::Auto => TimeOffset::Auto { max_abs_s: self.time_offset_max_s },
            TimeOffsetOption::None => TimeOffset::Fixed { imu_time_offset_s: 0.0 },
        };
        let loop_identification = match (self.loop_check, self.identify_damping) {
            (false, _) => LoopIdentificationMode::Off,
            (true, false) => LoopIdentificationMode::NaturalFrequency,
            (true, true) => LoopIdentificationMode::NaturalFrequencyAndDamping,
        };
        Ok(PipelineSettings {
            estimate,
            selection: self.selection(),
            time_offset,
            despike_imu: self.imu_despike,
            loop_identification,
            loop_tolerance: self.loop_tolerance,
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
        Ok(p)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
