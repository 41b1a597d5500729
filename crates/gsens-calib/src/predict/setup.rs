//! A prediction's inputs as a user states them: Γ̂'s 1σ per axis without
//! correlations, a sine tone written `F_HZ:AX,AY,AZ`, and the feed-forward's
//! timing (the IMU's sample rate and the latency on top of its hold), from
//! which [`super::PredictionInput`]'s covariance, tones and delay follow.

/// The feed-forward's timing.
///
/// With the `clap` feature these are a command line's options, a 40 Hz IMU
/// and no latency by default; the fields' doc comments are their help,
/// where a unit reads `[Hz]`, not a link.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
#[allow(rustdoc::broken_intra_doc_links)]
pub struct FeedForward {
    /// The feed-forward: IMU sample rate [Hz] (its hold delays by half a sample).
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 40.0, allow_negative_numbers = true, value_parser = crate::option_values::positive))]
    pub imu_rate_hz: f64,
    /// The feed-forward: latency on top of the hold [s].
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 0.0, allow_negative_numbers = true, value_parser = crate::option_values::finite_non_negative))]
    pub latency_s: f64,
}

impl FeedForward {
    /// The delay τ = latency + 1/(2·f_IMU) \[s\] (a zero-order hold of
    /// interval T delays by T/2 on average).
    pub fn delay_s(&self) -> f64 {
        self.latency_s + 0.5 / self.imu_rate_hz
    }
}

/// The covariance of uncorrelated axes of 1σ `sigma`: diag(σ²).
pub fn diagonal_covariance(sigma: [f64; 3]) -> [[f64; 3]; 3] {
    let mut c = [[0.0; 3]; 3];
    for i in 0..3 {
        c[i][i] = sigma[i] * sigma[i];
    }
    c
}

/// Γ̂ and its 1σ stated per axis that are not three finite values each
/// with σ ≥ 0 ([`stated_gamma`]).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum StatedGammaError {
    /// Not three values each.
    #[error("gamma and sigma take three values each, as x,y,z")]
    Count,
    /// A value not finite, or a σ below 0.
    #[error("gamma and sigma must be finite, sigma ≥ 0")]
    Value,
}

/// Γ̂ \[Hz/(m/s²)\] and its covariance from Γ̂ and its 1σ stated per axis as
/// x, y, z, the axes uncorrelated ([`diagonal_covariance`]).
pub fn stated_gamma(gamma: &[f64], sigma: &[f64]) -> Result<([f64; 3], [[f64; 3]; 3]), StatedGammaError> {
    let (Ok(g), Ok(s)) = (<[f64; 3]>::try_from(gamma), <[f64; 3]>::try_from(sigma)) else {
        return Err(StatedGammaError::Count);
    };
    if g.iter().chain(&s).any(|x| !x.is_finite()) || s.iter().any(|x| *x < 0.0) {
        return Err(StatedGammaError::Value);
    }
    Ok((g, diagonal_covariance(s)))
}

/// A tone that is not written `F_HZ:AX,AY,AZ` with F > 0 and finite amplitudes.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("expected F_HZ:AX,AY,AZ (e.g. 0.91:3,0,0)")]
pub struct ToneError;

/// A sine tone from `F_HZ:AX,AY,AZ`: its frequency \[Hz\] (finite, > 0) and
/// its peak amplitude per axis \[m/s²\] (finite), as
/// [`super::Vibration::Tones`] holds it.
pub fn parse_tone(text: &str) -> Result<(f64, [f64; 3]), ToneError> {
    let (f, a) = text.split_once(':').ok_or(ToneError)?;
    let f: f64 = f.trim().parse().ok().filter(|f: &f64| f.is_finite() && *f > 0.0).ok_or(ToneError)?;
    let a: Vec<f64> = a.split(',').map(|x| x.trim().parse::<f64>()).collect::<Result<_, _>>().map_err(|_| ToneError)?;
    match a[..] {
        [x, y, z] if a.iter().all(|v| v.is_finite()) => Ok((f, [x, y, z])),
        _ => Err(ToneError),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stated_gamma_needs_three_finite_values_and_sigmas_of_at_least_0() {
        let (g, c) = stated_gamma(&[1e-3, -2e-3, 0.0], &[0.5, 0.0, 2.0]).unwrap();
        assert_eq!(g, [1e-3, -2e-3, 0.0]);
        assert_eq!(c, [[0.25, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 4.0]]);
        assert_eq!(stated_gamma(&[1.0, 2.0], &[1.0, 2.0, 3.0]), Err(StatedGammaError::Count));
        assert_eq!(stated_gamma(&[1.0, 2.0, 3.0], &[1.0, -2.0, 3.0]), Err(StatedGammaError::Value));
        assert_eq!(stated_gamma(&[1.0, f64::NAN, 3.0], &[1.0, 2.0, 3.0]), Err(StatedGammaError::Value));
    }

    #[test]
    fn tones_read_as_written_and_anything_else_is_refused() {
        assert_eq!(parse_tone("0.91:3,0,0"), Ok((0.91, [3.0, 0.0, 0.0])));
        assert_eq!(parse_tone(" 20 : -1, 2.5 ,0"), Ok((20.0, [-1.0, 2.5, 0.0])));
        for bad in ["0.9:3,0", "0.9:3,0,0,1", "0:1,1,1", "-1:1,1,1", "x:1,1,1", "0.9:1,inf,1", "0.9", "nan:1,1,1"] {
            assert_eq!(parse_tone(bad), Err(ToneError), "{bad}");
        }
    }

    #[test]
    fn the_delay_is_the_latency_and_half_a_sample() {
        let f = FeedForward { imu_rate_hz: 40.0, latency_s: 0.01 };
        assert_eq!(f.delay_s(), 0.01 + 0.0125);
        let c = diagonal_covariance([1.0, 2.0, 3.0]);
        assert_eq!(c, [[1.0, 0.0, 0.0], [0.0, 4.0, 0.0], [0.0, 0.0, 9.0]]);
    }
}
