//! The board's accelerometer triad: true specific force from the motion and
//! the sensor's errors.
//!
//! # True specific force
//!
//! f_body = C·(a_level − g_level), C = body_from_level, a_level the kinematic
//! acceleration, g_level = (0, 0, −g₀) in the z-up level frame, g₀ =
//! [`STANDARD_GRAVITY_MPS2`]. At rest and level, f = (0, 0, +g₀)
//! (docs/conventions.md: "at rest, level, z up: a ≈ (0, 0, +9.81)").
//!
//! # Measurement model
//!
//! m = M·f + b + n (then optionally quantized to a step q), with
//!
//! - M = I + diag(s) + N: s the scale-factor errors (per axis, drawn from
//!   N(0, σ_s²), σ_s in ppm) and N the axis misalignment / non-orthogonality,
//!   zero diagonal, each of the six off-diagonal elements drawn from N(0, σ_m²)
//!   \[rad\] (so the x reading picks up N₀₁·f_y + N₀₂·f_z);
//! - b the constant bias per axis, drawn from N(0, σ_b²) once per run;
//! - n white noise, per-sample σ = VRW·√(rate), with the velocity-random-walk
//!   coefficient VRW in (m/s²)/√Hz = √(two-sided PSD) (IEEE Std 952 / 1293
//!   convention: the integrated velocity error grows as VRW·√t). A datasheet
//!   "noise density" ND (one-sided, µg/√Hz) corresponds to VRW = ND/√2 for an
//!   output bandwidth of rate/2; 1 m/s/√h = 1/60 (m/s²)/√Hz.
//!
//! The IMU samples at its own rate; sample k carries the time stamp k/rate and
//! was taken at the true time k/rate − `time_offset_s` (time offset = IMU time
//! stamp minus true time, as in the estimator's output). The sensor's internal
//! anti-alias filter and in-run bias drift are not modelled.

use serde::{Deserialize, Serialize};

use gsens_core::units::STANDARD_GRAVITY_MPS2;
use rand::Rng;

use crate::error::ConfigError;
use crate::motion::{Mat3, MotionState, mat_vec};
use crate::rng::{normal, standard_normal};

/// 1 mg in m/s².
const MG_MPS2: f64 = 1e-3 * STANDARD_GRAVITY_MPS2;
/// 1 µg in m/s².
const UG_MPS2: f64 = 1e-6 * STANDARD_GRAVITY_MPS2;

/// Error-free specific force in the body frame [m/s²]:
/// f = C·(a_level − g_level) with g_level = (0, 0, −g₀).
#[inline]
pub fn specific_force_body(state: &MotionState) -> [f64; 3] {
    let a = state.accel_level_mps2;
    mat_vec(&state.body_from_level, [a[0], a[1], a[2] + STANDARD_GRAVITY_MPS2])
}

/// Accelerometer configuration (error statistics, sampling).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ImuConfig {
    /// Output rate \[Hz\] (the paper logged at 40 Hz; 100–400 Hz typical).
    #[serde(default = "default_rate_hz")]
    pub rate_hz: f64,
    /// IMU time stamp minus true time \[s\].
    #[serde(default)]
    pub time_offset_s: f64,
    /// Velocity random walk VRW [(m/s²)/√Hz]: per-sample noise σ = VRW·√rate.
    #[serde(default)]
    pub vrw_mps2_per_rthz: f64,
    /// σ of the constant bias per axis [m/s²].
    #[serde(default)]
    pub bias_sigma_mps2: f64,
    /// σ of the scale-factor error per axis \[ppm\].
    #[serde(default)]
    pub scale_factor_sigma_ppm: f64,
    /// σ of each off-diagonal misalignment element \[rad\].
    #[serde(default)]
    pub misalignment_sigma_rad: f64,
    /// Output quantization step [m/s²]; 0 = none.
    #[serde(default)]
    pub quantization_mps2: f64,
}

fn default_rate_hz() -> f64 {
    40.0
}

impl Default for ImuConfig {
    /// [`ImuConfig::consumer_mems`].
    fn default() -> Self {
        Self::consumer_mems()
    }
}

/// Named IMU presets (`"ideal"`, `"consumer_mems"`, `"industrial"`,
/// `"tactical"` in a scenario file).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ImuPreset {
    /// [`ImuConfig::ideal`].
    Ideal,
    /// [`ImuConfig::consumer_mems`].
    ConsumerMems,
    /// [`ImuConfig::industrial`].
    Industrial,
    /// [`ImuConfig::tactical`].
    Tactical,
}

impl ImuPreset {
    /// The preset's configuration.
    pub fn config(self) -> ImuConfig {
        match self {
            Self::Ideal => ImuConfig::ideal(),
            Self::ConsumerMems => ImuConfig::consumer_mems(),
            Self::Industrial => ImuConfig::industrial(),
            Self::Tactical => ImuConfig::tactical(),
        }
    }
}

impl ImuConfig {
    /// An error-free accelerometer at 40 Hz.
    pub fn ideal() -> Self {
        Self {
            rate_hz: default_rate_hz(),
            time_offset_s: 0.0,
            vrw_mps2_per_rthz: 0.0,
            bias_sigma_mps2: 0.0,
            scale_factor_sigma_ppm: 0.0,
            misalignment_sigma_rad: 0.0,
            quantization_mps2: 0.0,
        }
    }

    /// Consumer MEMS accelerometer (smartphone / hobby-board class, e.g. the
    /// Bosch BMI160 or TDK InvenSense MPU-6000 families): datasheet noise
    /// density ≈ 150–400 µg/√Hz (here ND = 200 µg/√Hz → VRW = ND/√2 ≈
    /// 1.39e-3 (m/s²)/√Hz), zero-g offset of tens of mg (σ 20 mg), sensitivity
    /// tolerance ≈ 1–3 % (σ 1 % = 10 000 ppm), cross-axis sensitivity ≈ 1–2 %
    /// (σ 10 mrad), 16-bit output at ±4 g (step 8 g/2¹⁶ ≈ 1.2e-3 m/s²). Rounded
    /// values typical of the class, not one part's datasheet.
    pub fn consumer_mems() -> Self {
        Self {
            rate_hz: default_rate_hz(),
            time_offset_s: 0.0,
            vrw_mps2_per_rthz: 200.0 * UG_MPS2 / std::f64::consts::SQRT_2,
            bias_sigma_mps2: 20.0 * MG_MPS2,
            scale_factor_sigma_ppm: 10_000.0,
            misalignment_sigma_rad: 0.01,
            quantization_mps2: 8.0 * STANDARD_GRAVITY_MPS2 / 65_536.0,
        }
    }

    /// Industrial MEMS IMU (e.g. the Analog Devices ADIS1646x/1650x families):
    /// noise density ≈ 15–30 µg/√Hz (ND = 25 µg/√Hz), bias σ 3 mg, scale factor
    /// σ 1 000 ppm, misalignment σ 1 mrad, no visible quantization (32-bit
    /// output). Rounded class values.
    pub fn industrial() -> Self {
        Self {
            rate_hz: default_rate_hz(),
            time_offset_s: 0.0,
            vrw_mps2_per_rthz: 25.0 * UG_MPS2 / std::f64::consts::SQRT_2,
            bias_sigma_mps2: 3.0 * MG_MPS2,
            scale_factor_sigma_ppm: 1_000.0,
            misalignment_sigma_rad: 1e-3,
            quantization_mps2: 0.0,
        }
    }

    /// Tactical-grade IMU (e.g. Honeywell HG1700/HG1900 class; grade ranges as
    /// in P. D. Groves, *Principles of GNSS, Inertial, and Multisensor
    /// Integrated Navigation Systems*, 2nd ed., 2013, §4.4): bias σ 1 mg, scale
    /// factor σ 300 ppm, misalignment σ 0.1 mrad, VRW ≈ 0.03 m/s/√h =
    /// 5e-4 (m/s²)/√Hz. Rounded class values.
    pub fn tactical() -> Self {
        Self {
            rate_hz: default_rate_hz(),
            time_offset_s: 0.0,
            vrw_mps2_per_rthz: 0.03 / 60.0,
            bias_sigma_mps2: MG_MPS2,
            scale_factor_sigma_ppm: 300.0,
            misalignment_sigma_rad: 1e-4,
            quantization_mps2: 0.0,
        }
    }

    /// Per-sample white-noise σ [m/s²] = VRW·√rate.
    pub fn noise_sigma_mps2(&self) -> f64 {
        self.vrw_mps2_per_rthz * self.rate_hz.sqrt()
    }

    /// Checks ranges; the error names the offending key.
    pub fn validate(&self) -> Result<(), ConfigError> {
        if !(self.rate_hz.is_finite() && self.rate_hz >= 1.0 && self.rate_hz <= 10_000.0) {
            return Err(ConfigError::out_of_range("imu.rate_hz", self.rate_hz, "within [1, 10000] Hz"));
        }
        if !(self.time_offset_s.is_finite() && self.time_offset_s.abs() <= 10.0) {
            return Err(ConfigError::out_of_range("imu.time_offset_s", self.time_offset_s, "within ±10 s"));
        }
        let checks = [
            ("vrw_mps2_per_rthz", self.vrw_mps2_per_rthz, 1.0),
            ("bias_sigma_mps2", self.bias_sigma_mps2, 10.0),
            ("scale_factor_sigma_ppm", self.scale_factor_sigma_ppm, 100_000.0),
            ("misalignment_sigma_rad", self.misalignment_sigma_rad, 0.1),
            ("quantization_mps2", self.quantization_mps2, 1.0),
        ];
        for (key, v, max) in checks {
            if !(v.is_finite() && (0.0..=max).contains(&v)) {
                return Err(ConfigError::out_of_range(format!("imu.{key}"), v, format!("within [0, {max}]")));
            }
        }
        Ok(())
    }
}

/// One realization of the IMU's fixed errors (bias, scale factor,
/// misalignment) plus its noise and sampling parameters.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ImuErrors {
    /// Constant bias b per axis [m/s²].
    pub bias_mps2: [f64; 3],
    /// Scale-factor error s per axis \[-\] (fraction, not ppm).
    pub scale_factor: [f64; 3],
    /// Misalignment N \[rad\], zero diagonal: m_i ∋ Σ_j N_ij·f_j.
    pub misalignment_rad: Mat3,
    /// Per-sample white-noise σ [m/s²].
    pub noise_sigma_mps2: f64,
    /// Output quantization step [m/s²] (0 = none).
    pub quantization_mps2: f64,
    /// Output rate \[Hz\].
    pub rate_hz: f64,
    /// IMU time stamp minus true time \[s\].
    pub time_offset_s: f64,
}

impl ImuErrors {
    /// Draws the fixed errors of `cfg` from `rng`, in this order: bias x, y, z;
    /// scale x, y, z; misalignment (0,1), (0,2), (1,0), (1,2), (2,0), (2,1)
    /// (a zero σ draws nothing).
    ///
    /// # Panics
    /// If `cfg.validate()` fails.
    pub fn draw<R: Rng + ?Sized>(cfg: &ImuConfig, rng: &mut R) -> Self {
        if let Err(e) = cfg.validate() {
            panic!("{e}");
        }
        let bias_mps2 = [0, 1, 2].map(|_| normal(rng, cfg.bias_sigma_mps2));
        let scale_factor = [0, 1, 2].map(|_| normal(rng, cfg.scale_factor_sigma_ppm * 1e-6));
        let mut misalignment_rad = [[0.0; 3]; 3];
        for (i, row) in misalignment_rad.iter_mut().enumerate() {
            for (j, v) in row.iter_mut().enumerate() {
                if i != j {
                    *v = normal(rng, cfg.misalignment_sigma_rad);
                }
            }
        }
        Self {
            bias_mps2,
            scale_factor,
            misalignment_rad,
            noise_sigma_mps2: cfg.noise_sigma_mps2(),
            quantization_mps2: cfg.quantization_mps2,
            rate_hz: cfg.rate_hz,
            time_offset_s: cfg.time_offset_s,
        }
    }

    /// The sensing matrix M = I + diag(s) + N.
    pub fn sensing_matrix(&self) -> Mat3 {
        let mut m = self.misalignment_rad;
        for (i, row) in m.iter_mut().enumerate() {
            row[i] = 1.0 + self.scale_factor[i];
        }
        m
    }

    /// One measurement m = M·f + b + n (quantized if configured) of the true
    /// body specific force `f_true_body` [m/s²]; draws three normals from `rng`
    /// when the noise σ is non-zero.
    pub fn measure<R: Rng + ?Sized>(&self, f_true_body: [f64; 3], rng: &mut R) -> [f64; 3] {
        let mut m = mat_vec(&self.sensing_matrix(), f_true_body);
        for (i, v) in m.iter_mut().enumerate() {
            *v += self.bias_mps2[i];
            if self.noise_sigma_mps2 > 0.0 {
                *v += self.noise_sigma_mps2 * standard_normal(rng);
            }
            if self.quantization_mps2 > 0.0 {
                *v = (*v / self.quantization_mps2).round() * self.quantization_mps2;
            }
        }
        m
    }

    /// Time stamp \[s\] of sample k: k/rate.
    pub fn stamp_s(&self, k: u64) -> f64 {
        k as f64 / self.rate_hz
    }

    /// True time \[s\] at which sample k is taken: k/rate − time_offset.
    pub fn true_time_s(&self, k: u64) -> f64 {
        self.stamp_s(k) - self.time_offset_s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::motion::{Axis, Motion, MotionConfig, Segment};
    use crate::rng::seeded;

    #[test]
    fn imu_at_rest_level_reads_plus_g_on_z() {
        let m = Motion::new(&MotionConfig { segments: vec![Segment::rest(5.0)] }, &mut seeded(1));
        let f = specific_force_body(&m.state(2.0));
        assert_eq!(f, [0.0, 0.0, STANDARD_GRAVITY_MPS2]);
        let e = ImuErrors::draw(&ImuConfig::ideal(), &mut seeded(2));
        assert_eq!(e.measure(f, &mut seeded(3)), f);
        // Tipped +90° about x: +g on body y.
        let m = Motion::new(&MotionConfig { segments: vec![Segment::rotate(Axis::X, 90.0, 1.0)] }, &mut seeded(1));
        let f = specific_force_body(&m.state(2.0));
        assert!(f[0].abs() < 1e-12 && (f[1] - STANDARD_GRAVITY_MPS2).abs() < 1e-12 && f[2].abs() < 1e-12);
        // Shaking along z adds the kinematic acceleration to +g.
        let m = Motion::new(&MotionConfig { segments: vec![Segment::shake(Axis::Z, 10.0, 1.0, 2.0)] }, &mut seeded(1));
        let s = m.state(4.3);
        assert!((specific_force_body(&s)[2] - (STANDARD_GRAVITY_MPS2 + s.accel_level_mps2[2])).abs() < 1e-12);
    }

    #[test]
    fn imu_noise_sigma_matches_density_times_sqrt_rate() {
        for (rate, vrw) in [(40.0, 1e-3), (200.0, 2.5e-4)] {
            let cfg = ImuConfig { rate_hz: rate, vrw_mps2_per_rthz: vrw, ..ImuConfig::ideal() };
            let e = ImuErrors::draw(&cfg, &mut seeded(4));
            let mut rng = seeded(5);
            let n = 100_000;
            let mut ss = [0.0; 3];
            for _ in 0..n {
                let m = e.measure([0.0; 3], &mut rng);
                for i in 0..3 {
                    ss[i] += m[i] * m[i];
                }
            }
            let expect = vrw * f64::sqrt(rate);
            for v in ss {
                let sigma = (v / n as f64).sqrt();
                assert!((sigma / expect - 1.0).abs() < 0.05, "rate {rate}: {sigma} vs {expect}");
            }
        }
    }

    #[test]
    fn imu_scale_misalignment_bias_applied_as_documented() {
        let e = ImuErrors {
            bias_mps2: [0.1, -0.2, 0.3],
            scale_factor: [1e-2, -2e-2, 3e-2],
            misalignment_rad: [[0.0, 1e-3, 2e-3], [3e-3, 0.0, 4e-3], [5e-3, 6e-3, 0.0]],
            noise_sigma_mps2: 0.0,
            quantization_mps2: 0.0,
            rate_hz: 100.0,
            time_offset_s: 0.02,
        };
        let f = [1.0, 2.0, 9.0];
        let m = e.measure(f, &mut seeded(6));
        let expect = [
            1.01 * 1.0 + 1e-3 * 2.0 + 2e-3 * 9.0 + 0.1,
            3e-3 * 1.0 + 0.98 * 2.0 + 4e-3 * 9.0 - 0.2,
            5e-3 * 1.0 + 6e-3 * 2.0 + 1.03 * 9.0 + 0.3,
        ];
        for i in 0..3 {
            assert!((m[i] - expect[i]).abs() < 1e-12, "{m:?} vs {expect:?}");
        }
        assert_eq!(e.stamp_s(3), 0.03);
        assert!((e.true_time_s(3) - 0.01).abs() < 1e-15);
        // Quantization.
        let q = ImuErrors { quantization_mps2: 0.5, ..e.clone() };
        let m = q.measure([0.0, 0.0, 9.0], &mut seeded(6));
        assert!(m.iter().all(|v| (v / 0.5 - (v / 0.5).round()).abs() < 1e-12), "{m:?}");
    }

    #[test]
    fn imu_draw_statistics_presets_and_config() {
        // The drawn errors follow their σ (many draws).
        let cfg = ImuConfig::consumer_mems();
        let mut rng = seeded(7);
        let n = 4000;
        let (mut sb, mut ss, mut sm) = (0.0, 0.0, 0.0);
        for _ in 0..n {
            let e = ImuErrors::draw(&cfg, &mut rng);
            sb += e.bias_mps2.iter().map(|v| v * v).sum::<f64>();
            ss += e.scale_factor.iter().map(|v| v * v).sum::<f64>();
            sm += e.misalignment_rad[0][1].powi(2) + e.misalignment_rad[2][0].powi(2);
            assert_eq!(e.misalignment_rad[1][1], 0.0);
        }
        let rel = |sum: f64, count: f64, sigma: f64| (sum / count).sqrt() / sigma - 1.0;
        assert!(rel(sb, 3.0 * n as f64, cfg.bias_sigma_mps2).abs() < 0.05);
        assert!(rel(ss, 3.0 * n as f64, cfg.scale_factor_sigma_ppm * 1e-6).abs() < 0.05);
        assert!(rel(sm, 2.0 * n as f64, cfg.misalignment_sigma_rad).abs() < 0.05);
        for p in [ImuPreset::Ideal, ImuPreset::ConsumerMems, ImuPreset::Industrial, ImuPreset::Tactical] {
            assert!(p.config().validate().is_ok(), "{p:?}");
        }
        assert!(ImuConfig::consumer_mems().noise_sigma_mps2() > ImuConfig::industrial().noise_sigma_mps2());
        let c: ImuConfig = toml::from_str("rate_hz = 100.0\nvrw_mps2_per_rthz = 1e-3\n").unwrap();
        assert_eq!(c.bias_sigma_mps2, 0.0);
        assert!(toml::from_str::<ImuConfig>("rate = 100.0").is_err());
        let bad = ImuConfig { rate_hz: 0.0, ..ImuConfig::ideal() };
        assert!(bad.validate().unwrap_err().to_string().contains("rate_hz"));
    }
}
