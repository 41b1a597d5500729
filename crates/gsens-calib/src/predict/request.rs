//! A prediction as a caller requests it: Γ̂ from a result document or stated
//! per axis, the vibration from a spectrum file or as written tones, the
//! levels, the oscillator, the signal, the loop and the feed-forward; read,
//! checked and swept in that order ([`PredictRequest::sweep`]).

use super::{
    FeedForward, FrequencyNoise, PredictionInput, StatedGammaError, Sweep, SweepError, SweepSettings, ToneError,
    Vibration, parse_tone, stated_gamma,
};
#[cfg(feature = "clap")]
use crate::option_values::{finite_non_negative, positive};
use crate::{DocumentError, ResultDocument};
#[cfg(feature = "clap")]
use core::f64::consts::FRAC_1_SQRT_2;
use std::path::PathBuf;

/// Where Γ̂ and its covariance come from.
#[derive(Debug, Clone, PartialEq)]
pub enum EstimateSource {
    /// A result document (`report.json`): its Γ̂ and covariance
    /// ([`ResultDocument::read_gamma_file`]).
    Document(PathBuf),
    /// Γ̂ and its 1σ per axis as x, y, z, the axes uncorrelated ([`stated_gamma`]).
    Stated {
        /// Γ̂ \[Hz/(m/s²)\].
        gamma: Vec<f64>,
        /// Its 1σ \[Hz/(m/s²)\].
        sigma: Vec<f64>,
    },
}

/// Where the vibration comes from.
#[derive(Debug, Clone, PartialEq)]
pub enum VibrationSource {
    /// A spectrum file (`vibration.csv`, [`gsens_io::read_vibration_psd_file`]).
    Spectrum(PathBuf),
    /// Sine tones, each written `F_HZ:AX,AY,AZ` ([`parse_tone`]).
    Tones(Vec<String>),
}

/// A prediction as a caller requests it.
#[derive(Debug, Clone, PartialEq)]
pub struct PredictRequest {
    /// Γ̂ and its covariance.
    pub estimate: EstimateSource,
    /// The vibration at level 1.
    pub vibration: VibrationSource,
    /// The levels, factors on the amplitudes (finite, ≥ 0).
    pub levels: Vec<f64>,
    /// The oscillator's frequency noise (`None`: none).
    pub oscillator: Option<FrequencyNoise>,
    /// The signal, the loop and the feed-forward.
    pub receiver: ReceiverConditions,
}

/// The receiver a prediction is made for: the signal's C/N0, the
/// 2nd-order loop, the feed-forward, the IMU's noise and the Doppler rate
/// the loop follows.
///
/// With the `clap` feature these are a command line's options, with a
/// static GPS L1 receiver's values as their defaults; the fields' doc
/// comments are their help, where a unit reads `[Hz]`, not a link.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
#[allow(rustdoc::broken_intra_doc_links)]
pub struct ReceiverConditions {
    /// C/N0 for the thermal noise [dB-Hz].
    #[cfg_attr(feature = "clap", arg(long, default_value = "45", allow_negative_numbers = true, value_parser = finite_non_negative))]
    pub cn0_dbhz: Option<f64>,
    /// The loop (2nd order): noise bandwidth [Hz].
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 3.0, allow_negative_numbers = true, value_parser = positive))]
    pub bn_hz: f64,
    /// Damping ratio ζ.
    #[cfg_attr(feature = "clap", arg(long, default_value_t = FRAC_1_SQRT_2, allow_negative_numbers = true, value_parser = positive))]
    pub zeta: f64,
    /// Loop update interval [s].
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 0.001, allow_negative_numbers = true, value_parser = positive))]
    pub loop_interval_s: f64,
    /// The feed-forward's timing.
    #[cfg_attr(feature = "clap", command(flatten))]
    pub feed_forward: FeedForward,
    /// The IMU's white noise density [m/s²/√Hz].
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 0.0, allow_negative_numbers = true, value_parser = finite_non_negative))]
    pub imu_noise_mps2_per_rthz: f64,
    /// The line-of-sight Doppler rate the loop must follow [Hz/s] (its dynamic stress
    /// error enters the lock rule; a static receiver sees up to about 0.9 Hz/s at L1).
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 0.9, allow_negative_numbers = true, value_parser = finite_non_negative))]
    pub doppler_rate_hz_per_s: f64,
}

/// Why a request could not be predicted.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PredictError {
    /// The result document could not be read or has an axis without an estimate.
    #[error(transparent)]
    Document(#[from] DocumentError),
    /// The stated Γ̂ or σ are not three finite values each.
    #[error(transparent)]
    Stated(#[from] StatedGammaError),
    /// The spectrum file could not be read.
    #[error(transparent)]
    Vibration(#[from] gsens_io::FormatError),
    /// A tone is not written `F_HZ:AX,AY,AZ`.
    #[error("tone {tone}: {error}")]
    Tone {
        /// The tone as written.
        tone: String,
        /// Why.
        error: ToneError,
    },
    /// A level is negative or not finite.
    #[error("levels {0}: must be finite and ≥ 0")]
    Level(f64),
    /// The loop is not stable or not valid at its interval.
    #[error(transparent)]
    Sweep(SweepError),
}

impl PredictError {
    /// The request's field the error is about, when its message begins
    /// with that field's name (`tone`: one of [`VibrationSource::Tones`];
    /// `levels`), so that a caller can name it its own way.
    pub fn setting(&self) -> Option<&'static str> {
        match self {
            PredictError::Tone { .. } => Some("tone"),
            PredictError::Level(_) => Some("levels"),
            _ => None,
        }
    }
}

impl PredictRequest {
    /// The sweep's settings and the sweep: Γ̂ read or checked, then the
    /// vibration read or parsed, then the loop and each level checked as
    /// the sweep runs ([`SweepSettings::sweep`]).
    pub fn sweep(&self) -> Result<(SweepSettings, Sweep), PredictError> {
        let (gamma, covariance) = match &self.estimate {
            EstimateSource::Document(path) => ResultDocument::read_gamma_file(path)?,
            EstimateSource::Stated { gamma, sigma } => stated_gamma(gamma, sigma)?,
        };
        let vibration = match &self.vibration {
            VibrationSource::Spectrum(path) => Vibration::Spectrum(gsens_io::read_vibration_psd_file(path)?),
            VibrationSource::Tones(tones) => Vibration::Tones(
                tones
                    .iter()
                    .map(|t| parse_tone(t).map_err(|error| PredictError::Tone { tone: t.clone(), error }))
                    .collect::<Result<_, _>>()?,
            ),
        };
        let r = &self.receiver;
        let settings = SweepSettings {
            base: PredictionInput {
                gamma_hz_per_mps2: gamma,
                covariance,
                vibration,
                oscillator: self.oscillator,
                cn0_dbhz: r.cn0_dbhz,
                delay_s: r.feed_forward.delay_s(),
                imu_noise_mps2_per_rthz: r.imu_noise_mps2_per_rthz,
                doppler_rate_hz_per_s: r.doppler_rate_hz_per_s,
            },
            levels: self.levels.clone(),
            bn_hz: r.bn_hz,
            zeta: r.zeta,
            loop_interval_s: r.loop_interval_s,
        };
        let sweep = settings.sweep().map_err(|e| match e {
            SweepError::Level(level) => PredictError::Level(level),
            e => PredictError::Sweep(e),
        })?;
        Ok((settings, sweep))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn request(tones: &[&str], levels: &[f64]) -> PredictRequest {
        PredictRequest {
            estimate: EstimateSource::Stated { gamma: vec![0.09, 0.08, -0.08], sigma: vec![1e-3; 3] },
            vibration: VibrationSource::Tones(tones.iter().map(|t| t.to_string()).collect()),
            levels: levels.to_vec(),
            oscillator: None,
            receiver: receiver(),
        }
    }

    fn receiver() -> ReceiverConditions {
        ReceiverConditions {
            cn0_dbhz: Some(45.0),
            bn_hz: 3.0,
            zeta: std::f64::consts::FRAC_1_SQRT_2,
            loop_interval_s: 0.001,
            feed_forward: FeedForward { imu_rate_hz: 40.0, latency_s: 0.0 },
            imu_noise_mps2_per_rthz: 0.0,
            doppler_rate_hz_per_s: 0.9,
        }
    }

    /// A request sweeps what its parts state: the tone parsed, Γ̂ and its
    /// covariance as stated, the delay the feed-forward's, one row a level.
    #[test]
    fn a_request_sweeps_what_it_states() {
        let (settings, sweep) = request(&["0.91:3,0,0"], &[1.0, 2.0]).sweep().unwrap();
        assert_eq!(settings.base.vibration, Vibration::Tones(vec![(0.91, [3.0, 0.0, 0.0])]));
        assert_eq!(settings.base.delay_s, 0.0125);
        assert_eq!(sweep.gamma_hz_per_mps2, [0.09, 0.08, -0.08]);
        assert_eq!(sweep.covariance_hz_per_mps2_sq[1], [0.0, 1e-6, 0.0]);
        assert_eq!(sweep.predictions.len(), 2);
        // Twice the shaking, twice the g-induced jitter.
        let [one, two] = [0, 1].map(|k| sweep.predictions[k].vibration_rad[0]);
        assert!((two / one - 2.0).abs() < 1e-9, "{one} {two}");
    }

    /// Each error names what it is about: a tone and a level by their
    /// field, a stated Γ̂ and an unstable loop as their owners say.
    #[test]
    fn errors_name_the_tone_the_level_or_the_loop() {
        let e = request(&["0.9:3,0"], &[1.0]).sweep().unwrap_err();
        assert_eq!((e.to_string(), e.setting()), (format!("tone 0.9:3,0: {ToneError}"), Some("tone")));
        let e = request(&["0.9:3,0,0"], &[1.0, -2.0]).sweep().unwrap_err();
        assert_eq!((e.to_string().as_str(), e.setting()), ("levels -2: must be finite and ≥ 0", Some("levels")));
        let stated = PredictRequest {
            estimate: EstimateSource::Stated { gamma: vec![1.0], sigma: vec![1.0; 3] },
            ..request(&["0.9:3,0,0"], &[1.0])
        };
        assert!(matches!(stated.sweep(), Err(PredictError::Stated(StatedGammaError::Count))));
        // An unstable loop is said before any level is checked.
        let receiver = ReceiverConditions { bn_hz: 20.0, loop_interval_s: 0.1, ..receiver() };
        let unstable = PredictRequest { receiver, ..request(&["0.9:3,0,0"], &[-1.0]) };
        let e = unstable.sweep().unwrap_err();
        assert!(matches!(e, PredictError::Sweep(SweepError::Loop { .. })) && e.setting().is_none(), "{e}");
    }
}
