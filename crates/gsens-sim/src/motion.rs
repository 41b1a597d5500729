//! Hand motion of the receiver board (the antenna is fixed elsewhere): a
//! sequence of segments — rests, shakes along a body axis, smooth rotations
//! (tip-overs) and rotation oscillations — evaluated in O(log n) at any time.
//!
//! # Frames
//!
//! - **Level frame**: x, y horizontal, z up (ENU-like); gravity is
//!   (0, 0, −g₀) in it. The board's kinematic acceleration, velocity and
//!   displacement are given in this frame.
//! - **Body frame**: the board's (IMU's) axes. At t = 0 the body frame
//!   coincides with the level frame (board level, z up).
//! - **Attitude**: the direction-cosine matrix C = `body_from_level`,
//!   v_body = C·v_level.
//!
//! # Segments
//!
//! - [`Segment::Rest`]: nothing moves.
//! - [`Segment::Shake`]: translation along a body axis (fixed during the
//!   segment, since the attitude does not change). The displacement is
//!   x(t) = s(t)·sin φ(t) along that axis, with
//!   s(t) = (A/ω₀²)·e(t)·(1 + ε(t)) and φ(t) = ω₀·(t − t₀) + ψ(t),
//!   ω₀ = 2π/period, A the peak acceleration, e(t) a C² envelope (quintic
//!   smoothstep ramps 10u³ − 15u⁴ + 6u⁵ at both ends), ε(t) the relative
//!   amplitude jitter and ψ(t) the phase wander whose derivative ψ̇ ≈ ω₀·δ(t)
//!   is the relative frequency (≈ period) jitter. ε and ψ are uniform cubic
//!   B-splines with one knot per nominal period; the knot values of ε and δ
//!   are AR(1) ("human-like" mean-reverting random walks) with standard
//!   deviations `amplitude_rel`, `period_rel` and correlation time
//!   `correlation_s`, drawn once in [`Motion::new`]. The acceleration is the
//!   exact second derivative,
//!   ẍ = s̈·sin φ + (2ṡφ̇ + sφ̈)·cos φ − sφ̇²·sin φ,
//!   so the displacement is bounded by construction (≈ A/ω₀², 9 cm for
//!   3 m/s² at 1.1 s) and the board is back at rest, at its starting point,
//!   when the segment ends.
//! - [`Segment::Rotate`]: a rotation by `angle_deg` about a body axis n
//!   (right-handed), angle profile θ(t) = angle·S((t − t₀)/T) with the quintic
//!   smoothstep S (zero rate and angular acceleration at both ends). The
//!   rotation is about the IMU's own position: no kinematic acceleration,
//!   only the projection of gravity changes. C(t) = R(n, θ)ᵀ·C(t₀), with
//!   R(n, θ) the active (Rodrigues) rotation; the body angular rate is n·θ̇.
//!   Example: +90° about body x turns body +y up, so the specific force at
//!   rest moves from (0, 0, +g₀) to (0, +g₀, 0); +90° about body y gives
//!   (−g₀, 0, 0).
//! - [`Segment::Wobble`]: rotation oscillation θ(t) = A_θ·e(t)·sin(2π(t − t₀)/P)
//!   about a body axis, same attitude law; back to the starting attitude at
//!   the end.
//!
//! Before t = 0 and after the last segment the board rests (in the final
//! attitude).

use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

use rand::Rng;

use crate::error::ConfigError;
use crate::rng::standard_normal;

/// A 3×3 matrix, row-major (`m[row][col]`).
pub type Mat3 = [[f64; 3]; 3];

const IDENTITY: Mat3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

/// A body axis by name.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum AxisName {
    /// Body x.
    X,
    /// Body y.
    Y,
    /// Body z.
    Z,
}

/// A direction in the body frame: `"x"`, `"y"`, `"z"` or a vector
/// `[x, y, z]` (normalized on use; must not be zero).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Axis {
    /// A body axis by name.
    Named(AxisName),
    /// Any direction, body-frame components.
    Vector([f64; 3]),
}

impl Axis {
    /// Body x.
    pub const X: Axis = Axis::Named(AxisName::X);
    /// Body y.
    pub const Y: Axis = Axis::Named(AxisName::Y);
    /// Body z.
    pub const Z: Axis = Axis::Named(AxisName::Z);

    /// The unit vector, or an error for a zero or non-finite vector (its key
    /// path is `axis`; a caller that knows where the axis is puts its prefix
    /// before it with [`ConfigError::under`]).
    pub fn unit(&self) -> Result<[f64; 3], ConfigError> {
        match *self {
            Axis::Named(AxisName::X) => Ok([1.0, 0.0, 0.0]),
            Axis::Named(AxisName::Y) => Ok([0.0, 1.0, 0.0]),
            Axis::Named(AxisName::Z) => Ok([0.0, 0.0, 1.0]),
            Axis::Vector(v) => {
                let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
                if n.is_finite() && n > 1e-9 {
                    Ok([v[0] / n, v[1] / n, v[2] / n])
                } else {
                    Err(ConfigError::InvalidAxis { key: "axis".into(), vector: v })
                }
            }
        }
    }
}

/// Random, slowly wandering deviations of a hand shake from its nominal period
/// and amplitude (AR(1) knot values, one knot per nominal period).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Jitter {
    /// σ of the relative frequency (≈ period) deviation δ \[-\], < 0.5.
    pub period_rel: f64,
    /// σ of the relative amplitude deviation ε \[-\], < 0.5.
    pub amplitude_rel: f64,
    /// Correlation time of both deviations \[s\] (AR(1) coefficient
    /// exp(−period/correlation_s) between knots).
    pub correlation_s: f64,
}

impl Default for Jitter {
    /// 7 % on period and amplitude, 3 s correlation time.
    fn default() -> Self {
        Self { period_rel: 0.07, amplitude_rel: 0.07, correlation_s: 3.0 }
    }
}

impl Jitter {
    /// No jitter: a perfectly regular shake.
    pub fn none() -> Self {
        Self { period_rel: 0.0, amplitude_rel: 0.0, correlation_s: 3.0 }
    }
}

/// The board at rest.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RestSegment {
    /// Duration \[s\], ≥ 0.
    pub duration_s: f64,
}

/// Shaking along a body axis (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ShakeSegment {
    /// Direction of the translation in the body frame.
    pub axis: Axis,
    /// Duration \[s\], > 0.
    pub duration_s: f64,
    /// Nominal period \[s\] (the paper: 1–2 s).
    pub period_s: f64,
    /// Nominal peak kinematic acceleration A [m/s²].
    pub amplitude_mps2: f64,
    /// Period and amplitude jitter (default: [`Jitter::default`]).
    #[serde(default)]
    pub jitter: Jitter,
    /// Duration of each smooth start/end ramp \[s\]; default
    /// min(period_s, duration_s/4). At most duration_s/2.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ramp_s: Option<f64>,
}

/// A smooth rotation (e.g. a tip-over) about a body axis.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RotateSegment {
    /// Rotation axis in the body frame (right-handed).
    pub axis: Axis,
    /// Rotation angle \[deg\].
    pub angle_deg: f64,
    /// Duration \[s\], > 0.
    pub duration_s: f64,
}

/// A rotation oscillation about a body axis.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WobbleSegment {
    /// Rotation axis in the body frame (right-handed).
    pub axis: Axis,
    /// Peak rotation angle A_θ \[deg\], < 90.
    pub amplitude_deg: f64,
    /// Period \[s\], > 0.
    pub period_s: f64,
    /// Duration \[s\], > 0.
    pub duration_s: f64,
    /// Duration of each smooth start/end ramp \[s\]; default
    /// min(period_s, duration_s/4). At most duration_s/2.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ramp_s: Option<f64>,
}

/// One motion segment; in TOML, `kind = "rest" | "shake" | "rotate" | "wobble"`
/// plus the variant's keys.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Segment {
    /// [`RestSegment`].
    Rest(RestSegment),
    /// [`ShakeSegment`].
    Shake(ShakeSegment),
    /// [`RotateSegment`] (`kind = "tip_over"` is accepted as an alias).
    #[serde(alias = "tip_over")]
    Rotate(RotateSegment),
    /// [`WobbleSegment`].
    Wobble(WobbleSegment),
}

impl Segment {
    /// A rest of `duration_s`.
    pub fn rest(duration_s: f64) -> Self {
        Segment::Rest(RestSegment { duration_s })
    }

    /// A shake with default jitter and ramps.
    pub fn shake(axis: Axis, duration_s: f64, period_s: f64, amplitude_mps2: f64) -> Self {
        Segment::Shake(ShakeSegment {
            axis,
            duration_s,
            period_s,
            amplitude_mps2,
            jitter: Jitter::default(),
            ramp_s: None,
        })
    }

    /// The one-rate protocol in its shortest form: a rest of `rest_s`, each
    /// axis in turn (x, y, z) shaken for `shake_s` at `period_s` and
    /// `amplitude_mps2` ([`Segment::shake`]), and a rest of `rest_s`.
    pub fn each_axis(rest_s: f64, shake_s: f64, period_s: f64, amplitude_mps2: f64) -> Vec<Segment> {
        let shakes = [Axis::X, Axis::Y, Axis::Z].map(|axis| Segment::shake(axis, shake_s, period_s, amplitude_mps2));
        std::iter::once(Segment::rest(rest_s)).chain(shakes).chain([Segment::rest(rest_s)]).collect()
    }

    /// A smooth rotation by `angle_deg` about `axis` in `duration_s`.
    pub fn rotate(axis: Axis, angle_deg: f64, duration_s: f64) -> Self {
        Segment::Rotate(RotateSegment { axis, angle_deg, duration_s })
    }

    /// The segment's duration \[s\].
    pub fn duration_s(&self) -> f64 {
        match self {
            Segment::Rest(s) => s.duration_s,
            Segment::Shake(s) => s.duration_s,
            Segment::Rotate(s) => s.duration_s,
            Segment::Wobble(s) => s.duration_s,
        }
    }

    fn validate(&self, i: usize) -> Result<(), ConfigError> {
        let key = |k: &str| format!("motion.segments[{i}].{k}");
        let bad = |k: &str, value: f64, allowed: &str| Err(ConfigError::out_of_range(key(k), value, allowed));
        let axis = |a: &Axis| a.unit().map(|_| ()).map_err(|e| e.under(&format!("motion.segments[{i}]")));
        let d = self.duration_s();
        let min_d = if matches!(self, Segment::Rest(_)) { 0.0 } else { f64::MIN_POSITIVE };
        if !(d.is_finite() && d >= min_d && d <= 1e6) {
            return bad("duration_s", d, if min_d > 0.0 { "> 0 and <= 1e6 s" } else { ">= 0 and <= 1e6 s" });
        }
        let ramp_check = |ramp: Option<f64>| -> Result<(), ConfigError> {
            if let Some(r) = ramp
                && !(r.is_finite() && r > 0.0 && r <= 0.5 * d)
            {
                return bad("ramp_s", r, "> 0 and <= duration_s/2");
            }
            Ok(())
        };
        match self {
            Segment::Rest(_) => {}
            Segment::Shake(s) => {
                axis(&s.axis)?;
                if !(s.period_s.is_finite() && s.period_s >= 0.02 && s.period_s <= 100.0) {
                    return bad("period_s", s.period_s, "within [0.02, 100] s");
                }
                if !(s.amplitude_mps2.is_finite() && (0.0..=100.0).contains(&s.amplitude_mps2)) {
                    return bad("amplitude_mps2", s.amplitude_mps2, "within [0, 100] m/s²");
                }
                let j = &s.jitter;
                for (k, v) in [("jitter.period_rel", j.period_rel), ("jitter.amplitude_rel", j.amplitude_rel)] {
                    if !(v.is_finite() && (0.0..0.5).contains(&v)) {
                        return bad(k, v, "within [0, 0.5)");
                    }
                }
                if !(j.correlation_s.is_finite() && j.correlation_s > 0.0) {
                    return bad("jitter.correlation_s", j.correlation_s, "> 0");
                }
                ramp_check(s.ramp_s)?;
            }
            Segment::Rotate(s) => {
                axis(&s.axis)?;
                if !(s.angle_deg.is_finite() && s.angle_deg.abs() <= 3600.0) {
                    return bad("angle_deg", s.angle_deg, "within ±3600°");
                }
            }
            Segment::Wobble(s) => {
                axis(&s.axis)?;
                if !(s.amplitude_deg.is_finite() && s.amplitude_deg.abs() < 90.0) {
                    return bad("amplitude_deg", s.amplitude_deg, "within (-90°, 90°)");
                }
                if !(s.period_s.is_finite() && s.period_s >= 0.02 && s.period_s <= 100.0) {
                    return bad("period_s", s.period_s, "within [0.02, 100] s");
                }
                ramp_check(s.ramp_s)?;
            }
        }
        Ok(())
    }
}

/// The whole motion: segments played one after the other from t = 0.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MotionConfig {
    /// The segments, in order.
    pub segments: Vec<Segment>,
}

impl Default for MotionConfig {
    /// [`MotionConfig::paper_default`].
    fn default() -> Self {
        Self::paper_default()
    }
}

impl MotionConfig {
    /// The paper's experiment (docs/conventions.md: "shaking period 1–2 s in three
    /// orthogonal directions"): rest 10 s, shake x 30 s, rest 10 s, shake y
    /// 30 s, rest 10 s, shake z 30 s, rest 10 s; period 1.1 s (0.91 Hz, at the
    /// Bn = 3 Hz loop's response peak ωn/2π = 0.90 Hz), peak acceleration
    /// 3 m/s², 7 % period and amplitude jitter. 130 s in all.
    pub fn paper_default() -> Self {
        let shake = |axis| Segment::shake(axis, 30.0, 1.1, 3.0);
        Self {
            segments: vec![
                Segment::rest(10.0),
                shake(Axis::X),
                Segment::rest(10.0),
                shake(Axis::Y),
                Segment::rest(10.0),
                shake(Axis::Z),
                Segment::rest(10.0),
            ],
        }
    }

    /// Total duration of the segments \[s\].
    pub fn duration_s(&self) -> f64 {
        self.segments.iter().map(Segment::duration_s).sum()
    }

    /// Checks ranges; the error names the offending key
    /// (`motion.segments[i].key`).
    pub fn validate(&self) -> Result<(), ConfigError> {
        for (i, s) in self.segments.iter().enumerate() {
            s.validate(i)?;
        }
        Ok(())
    }
}

/// The board's kinematic state at one instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MotionState {
    /// Time \[s\].
    pub t_s: f64,
    /// Kinematic acceleration in the level frame [m/s²] (gravity excluded).
    pub accel_level_mps2: [f64; 3],
    /// Velocity in the level frame [m/s].
    pub velocity_level_mps: [f64; 3],
    /// Displacement from the starting point in the level frame \[m\].
    pub position_level_m: [f64; 3],
    /// Attitude C: v_body = C·v_level.
    pub body_from_level: Mat3,
    /// Angular rate of the body relative to the level frame, body axes [rad/s].
    pub angular_rate_body_radps: [f64; 3],
}

/// Uniform cubic B-spline: value, first and second derivative.
#[derive(Debug, Clone)]
struct Spline {
    h_s: f64,
    c: Vec<f64>,
}

impl Spline {
    #[inline]
    fn eval(&self, tau_s: f64) -> (f64, f64, f64) {
        let x = (tau_s / self.h_s).max(0.0);
        let j = (x.floor() as usize).min(self.c.len() - 4);
        let u = x - j as f64;
        let c = &self.c[j..j + 4];
        let (u2, u3) = (u * u, u * u * u);
        let om = 1.0 - u;
        let b = [
            om * om * om / 6.0,
            (3.0 * u3 - 6.0 * u2 + 4.0) / 6.0,
            (-3.0 * u3 + 3.0 * u2 + 3.0 * u + 1.0) / 6.0,
            u3 / 6.0,
        ];
        let d = [-0.5 * om * om, 0.5 * (3.0 * u2 - 4.0 * u), 0.5 * (-3.0 * u2 + 2.0 * u + 1.0), 0.5 * u2];
        let dd = [om, 3.0 * u - 2.0, -3.0 * u + 1.0, u];
        let mut v = [0.0; 3];
        for k in 0..4 {
            v[0] += c[k] * b[k];
            v[1] += c[k] * d[k];
            v[2] += c[k] * dd[k];
        }
        (v[0], v[1] / self.h_s, v[2] / (self.h_s * self.h_s))
    }
}

/// Quintic smoothstep S(u) = 10u³ − 15u⁴ + 6u⁵ on [0, 1] and its first two
/// derivatives (with respect to u).
#[inline]
fn smoothstep5(u: f64) -> (f64, f64, f64) {
    let u = u.clamp(0.0, 1.0);
    let (u2, u3) = (u * u, u * u * u);
    (u3 * (10.0 - 15.0 * u + 6.0 * u2), 30.0 * u2 * (1.0 - u) * (1.0 - u), 60.0 * u * (1.0 - u) * (1.0 - 2.0 * u))
}

/// Envelope 0 → 1 → 0 with quintic ramps of length `ramp` at both ends of
/// [0, dur]: value, first and second time derivative.
#[inline]
fn envelope(tau: f64, dur: f64, ramp: f64) -> (f64, f64, f64) {
    if tau < ramp {
        let (s, ds, dds) = smoothstep5(tau / ramp);
        (s, ds / ramp, dds / (ramp * ramp))
    } else if tau > dur - ramp {
        let (s, ds, dds) = smoothstep5((dur - tau) / ramp);
        (s, -ds / ramp, dds / (ramp * ramp))
    } else {
        (1.0, 0.0, 0.0)
    }
}

#[derive(Debug, Clone)]
enum Kind {
    Rest,
    Shake { dir_level: [f64; 3], omega0_radps: f64, disp_m: f64, ramp_s: f64, amp: Spline, phase: Spline },
    Rotate { axis_body: [f64; 3], angle_rad: f64 },
    Wobble { axis_body: [f64; 3], amp_rad: f64, omega_radps: f64, ramp_s: f64 },
}

#[derive(Debug, Clone)]
struct Piece {
    t0_s: f64,
    dur_s: f64,
    c_start: Mat3,
    kind: Kind,
}

/// A motion realization: the segments with their jitter drawn, evaluable at
/// any time ([`Motion::state`]).
#[derive(Debug, Clone)]
pub struct Motion {
    pieces: Vec<Piece>,
    starts_s: Vec<f64>,
    end_s: f64,
    c_final: Mat3,
}

/// Rodrigues rotation matrix R(n, θ) = I·cosθ + sinθ·\[n\]× + (1 − cosθ)·n nᵀ
/// (active, right-handed, n a unit vector).
pub fn rotation_matrix(axis_unit: [f64; 3], angle_rad: f64) -> Mat3 {
    let (s, c) = angle_rad.sin_cos();
    let [x, y, z] = axis_unit;
    let t = 1.0 - c;
    [
        [c + t * x * x, t * x * y - s * z, t * x * z + s * y],
        [t * x * y + s * z, c + t * y * y, t * y * z - s * x],
        [t * x * z - s * y, t * y * z + s * x, c + t * z * z],
    ]
}

/// Matrix product a·b.
pub fn mat_mul(a: &Mat3, b: &Mat3) -> Mat3 {
    let mut m = [[0.0; 3]; 3];
    for (i, row) in m.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j];
        }
    }
    m
}

/// Matrix–vector product m·v.
#[inline]
pub fn mat_vec(m: &Mat3, v: [f64; 3]) -> [f64; 3] {
    [
        m[0][0] * v[0] + m[0][1] * v[1] + m[0][2] * v[2],
        m[1][0] * v[0] + m[1][1] * v[1] + m[1][2] * v[2],
        m[2][0] * v[0] + m[2][1] * v[1] + m[2][2] * v[2],
    ]
}

/// Transpose.
pub fn transpose(m: &Mat3) -> Mat3 {
    [[m[0][0], m[1][0], m[2][0]], [m[0][1], m[1][1], m[2][1]], [m[0][2], m[1][2], m[2][2]]]
}

/// AR(1) sequence of `n` values with stationary σ `sigma`, coefficient `rho`,
/// each clamped to ±0.45 (keeps 1 + ε and 1 + δ positive).
fn ar1<R: Rng + ?Sized>(rng: &mut R, n: usize, sigma: f64, rho: f64) -> Vec<f64> {
    let mut v = Vec::with_capacity(n);
    if sigma == 0.0 {
        v.resize(n, 0.0);
        return v;
    }
    let innov = (1.0 - rho * rho).sqrt();
    let mut x = sigma * standard_normal(rng);
    for _ in 0..n {
        v.push(x.clamp(-0.45, 0.45));
        x = rho * x + innov * sigma * standard_normal(rng);
    }
    v
}

impl Motion {
    /// Precomputes the motion of `cfg`, drawing the shake jitter from `rng`
    /// (segments in order, amplitude knots then phase knots).
    ///
    /// # Panics
    /// If `cfg.validate()` fails; use [`Motion::try_new`] to get the error.
    pub fn new<R: Rng + ?Sized>(cfg: &MotionConfig, rng: &mut R) -> Self {
        match Self::try_new(cfg, rng) {
            Ok(m) => m,
            Err(e) => panic!("{e}"),
        }
    }

    /// As [`Motion::new`], returning configuration errors.
    pub fn try_new<R: Rng + ?Sized>(cfg: &MotionConfig, rng: &mut R) -> Result<Self, ConfigError> {
        cfg.validate()?;
        let mut pieces = Vec::with_capacity(cfg.segments.len());
        let mut t = 0.0;
        let mut c = IDENTITY;
        for seg in &cfg.segments {
            let dur = seg.duration_s();
            let kind = match *seg {
                Segment::Rest(_) => Kind::Rest,
                Segment::Shake(s) => {
                    let axis = s.axis.unit()?;
                    let dir_level = mat_vec(&transpose(&c), axis);
                    let omega0 = 2.0 * PI / s.period_s;
                    let h = s.period_s;
                    let n = (dur / h).ceil() as usize + 4;
                    let rho = (-h / s.jitter.correlation_s).exp();
                    let amp = Spline { h_s: h, c: ar1(rng, n, s.jitter.amplitude_rel, rho) };
                    let dev = ar1(rng, n, s.jitter.period_rel, rho);
                    // ψ knots: ψ_j − ψ_{j−1} = ω₀·h·δ_j, so ψ̇ is the quadratic spline of ω₀·δ.
                    let mut psi = Vec::with_capacity(n);
                    let mut acc = 0.0;
                    for d in dev {
                        acc += omega0 * h * d;
                        psi.push(acc);
                    }
                    let ramp = s.ramp_s.unwrap_or_else(|| s.period_s.min(0.25 * dur));
                    Kind::Shake {
                        dir_level,
                        omega0_radps: omega0,
                        disp_m: s.amplitude_mps2 / (omega0 * omega0),
                        ramp_s: ramp,
                        amp,
                        phase: Spline { h_s: h, c: psi },
                    }
                }
                Segment::Rotate(s) => Kind::Rotate { axis_body: s.axis.unit()?, angle_rad: s.angle_deg.to_radians() },
                Segment::Wobble(s) => Kind::Wobble {
                    axis_body: s.axis.unit()?,
                    amp_rad: s.amplitude_deg.to_radians(),
                    omega_radps: 2.0 * PI / s.period_s,
                    ramp_s: s.ramp_s.unwrap_or_else(|| s.period_s.min(0.25 * dur)),
                },
            };
            let c_start = c;
            if let Kind::Rotate { axis_body, angle_rad } = kind {
                c = mat_mul(&transpose(&rotation_matrix(axis_body, angle_rad)), &c_start);
            }
            pieces.push(Piece { t0_s: t, dur_s: dur, c_start, kind });
            t += dur;
        }
        let starts_s = pieces.iter().map(|p| p.t0_s).collect();
        Ok(Self { pieces, starts_s, end_s: t, c_final: c })
    }

    /// End of the last segment \[s\].
    pub fn duration_s(&self) -> f64 {
        self.end_s
    }

    /// The board's state at `t_s` (any time: rest before 0 and after the
    /// end). O(log n) in the number of segments, no allocation.
    pub fn state(&self, t_s: f64) -> MotionState {
        let rest = |c: Mat3| MotionState {
            t_s,
            accel_level_mps2: [0.0; 3],
            velocity_level_mps: [0.0; 3],
            position_level_m: [0.0; 3],
            body_from_level: c,
            angular_rate_body_radps: [0.0; 3],
        };
        if t_s.is_nan() || t_s < 0.0 || self.pieces.is_empty() {
            return rest(IDENTITY);
        }
        if t_s >= self.end_s {
            return rest(self.c_final);
        }
        let i = self.starts_s.partition_point(|&s| s <= t_s).saturating_sub(1);
        let p = &self.pieces[i];
        let tau = t_s - p.t0_s;
        match &p.kind {
            Kind::Rest => rest(p.c_start),
            Kind::Shake { dir_level, omega0_radps, disp_m, ramp_s, amp, phase } => {
                let (e, de, dde) = envelope(tau, p.dur_s, *ramp_s);
                let (ea, dea, ddea) = amp.eval(tau);
                let (psi, dpsi, ddpsi) = phase.eval(tau);
                // s = D·e·(1 + ε)
                let g = 1.0 + ea;
                let s = disp_m * e * g;
                let ds = disp_m * (de * g + e * dea);
                let dds = disp_m * (dde * g + 2.0 * de * dea + e * ddea);
                let phi = omega0_radps * tau + psi;
                let dphi = omega0_radps + dpsi;
                let (sp, cp) = phi.sin_cos();
                let x = s * sp;
                let v = ds * sp + s * dphi * cp;
                let a = dds * sp + (2.0 * ds * dphi + s * ddpsi) * cp - s * dphi * dphi * sp;
                MotionState {
                    t_s,
                    accel_level_mps2: [a * dir_level[0], a * dir_level[1], a * dir_level[2]],
                    velocity_level_mps: [v * dir_level[0], v * dir_level[1], v * dir_level[2]],
                    position_level_m: [x * dir_level[0], x * dir_level[1], x * dir_level[2]],
                    body_from_level: p.c_start,
                    angular_rate_body_radps: [0.0; 3],
                }
            }
            Kind::Rotate { axis_body, angle_rad } => {
                let (sv, ds, _) = smoothstep5(tau / p.dur_s);
                let theta = angle_rad * sv;
                let rate = angle_rad * ds / p.dur_s;
                let c = mat_mul(&transpose(&rotation_matrix(*axis_body, theta)), &p.c_start);
                MotionState {
                    body_from_level: c,
                    angular_rate_body_radps: [axis_body[0] * rate, axis_body[1] * rate, axis_body[2] * rate],
                    ..rest(c)
                }
            }
            Kind::Wobble { axis_body, amp_rad, omega_radps, ramp_s } => {
                let (e, de, _) = envelope(tau, p.dur_s, *ramp_s);
                let (sw, cw) = (omega_radps * tau).sin_cos();
                let theta = amp_rad * e * sw;
                let rate = amp_rad * (de * sw + e * omega_radps * cw);
                let c = mat_mul(&transpose(&rotation_matrix(*axis_body, theta)), &p.c_start);
                MotionState {
                    body_from_level: c,
                    angular_rate_body_radps: [axis_body[0] * rate, axis_body[1] * rate, axis_body[2] * rate],
                    ..rest(c)
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::seeded;

    fn norm(v: [f64; 3]) -> f64 {
        (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
    }

    #[test]
    fn each_axis_is_rest_x_y_z_rest() {
        let s = Segment::each_axis(2.0, 5.0, 1.1, 3.0);
        let axes: Vec<Option<Axis>> = s
            .iter()
            .map(|seg| match seg {
                Segment::Shake(k) => Some(k.axis),
                _ => None,
            })
            .collect();
        assert_eq!(axes, [None, Some(Axis::X), Some(Axis::Y), Some(Axis::Z), None]);
        assert_eq!(s[0], Segment::rest(2.0));
        assert_eq!(s[2], Segment::shake(Axis::Y, 5.0, 1.1, 3.0));
    }

    #[test]
    fn motion_rests_have_no_kinematic_acceleration() {
        let m = Motion::new(&MotionConfig::paper_default(), &mut seeded(1));
        assert_eq!(m.duration_s(), 130.0);
        for &t in &[-1.0, 0.0, 5.0, 9.999, 40.0, 45.0, 80.5, 125.0, 130.0, 1e4] {
            let s = m.state(t);
            assert_eq!(s.accel_level_mps2, [0.0; 3], "t {t}");
            assert_eq!(s.velocity_level_mps, [0.0; 3], "t {t}");
            assert_eq!(s.body_from_level, IDENTITY);
        }
        // Shakes are along x, then y, then z (level frame = body frame here).
        let peak = |t0: f64, t1: f64| {
            let mut p = [0.0f64; 3];
            let mut t = t0;
            while t < t1 {
                let a = m.state(t).accel_level_mps2;
                for k in 0..3 {
                    p[k] = p[k].max(a[k].abs());
                }
                t += 0.01;
            }
            p
        };
        let (px, py, pz) = (peak(10.0, 40.0), peak(50.0, 80.0), peak(90.0, 120.0));
        assert!(px[0] > 2.5 && px[0] < 4.5 && px[1] == 0.0 && px[2] == 0.0, "{px:?}");
        assert!(py[1] > 2.5 && py[1] < 4.5 && py[0] == 0.0 && py[2] == 0.0, "{py:?}");
        assert!(pz[2] > 2.5 && pz[2] < 4.5 && pz[0] == 0.0 && pz[1] == 0.0, "{pz:?}");
    }

    /// Power of the x acceleration at `f` over [t0, t1) (a DFT bin at any f).
    fn power_at(m: &Motion, t0: f64, t1: f64, f: f64) -> f64 {
        let dt = 0.01;
        let (mut re, mut im) = (0.0, 0.0);
        let mut t = t0;
        while t < t1 {
            let a = m.state(t).accel_level_mps2[0];
            let (s, c) = (2.0 * PI * f * t).sin_cos();
            re += a * c;
            im += a * s;
            t += dt;
        }
        re * re + im * im
    }

    #[test]
    fn motion_shake_dominant_frequency_is_one_over_period() {
        for (seed, jitter) in [(2, Jitter::none()), (3, Jitter::default()), (4, Jitter::default())] {
            let cfg = MotionConfig {
                segments: vec![Segment::Shake(ShakeSegment {
                    axis: Axis::X,
                    duration_s: 60.0,
                    period_s: 1.1,
                    amplitude_mps2: 3.0,
                    jitter,
                    ramp_s: None,
                })],
            };
            let m = Motion::new(&cfg, &mut seeded(seed));
            let freqs: Vec<f64> = (0..=300).map(|k| 0.1 + 0.01 * f64::from(k)).collect();
            let best = freqs
                .iter()
                .copied()
                .max_by(|a, b| power_at(&m, 0.0, 60.0, *a).total_cmp(&power_at(&m, 0.0, 60.0, *b)))
                .unwrap();
            assert!((best - 1.0 / 1.1).abs() < 0.04, "seed {seed}: peak at {best} Hz");
        }
    }

    #[test]
    fn motion_displacement_bounded_and_consistent() {
        let m = Motion::new(&MotionConfig::paper_default(), &mut seeded(5));
        // Integrate the acceleration twice (trapezoid, 1 kHz) and compare with
        // the analytic velocity and displacement.
        let dt = 1e-3;
        let (mut v, mut x) = ([0.0f64; 3], [0.0f64; 3]);
        let mut a_prev = m.state(0.0).accel_level_mps2;
        let mut max_disp = 0.0f64;
        for k in 1..=140_000 {
            let t = f64::from(k) * dt;
            let s = m.state(t);
            for i in 0..3 {
                let v_new = v[i] + 0.5 * dt * (a_prev[i] + s.accel_level_mps2[i]);
                x[i] += 0.5 * dt * (v[i] + v_new);
                v[i] = v_new;
            }
            a_prev = s.accel_level_mps2;
            max_disp = max_disp.max(norm(x));
            for i in 0..3 {
                assert!((v[i] - s.velocity_level_mps[i]).abs() < 1e-5, "t {t}: v {v:?} vs {:?}", s.velocity_level_mps);
                assert!((x[i] - s.position_level_m[i]).abs() < 1e-5, "t {t}: x {x:?} vs {:?}", s.position_level_m);
            }
        }
        assert!(max_disp > 0.04 && max_disp < 0.2, "max displacement {max_disp} m");
        assert!(norm(x) < 1e-4 && norm(v) < 1e-5, "not back at rest: x {x:?} v {v:?}");
    }

    #[test]
    fn motion_tip_over_moves_gravity_with_documented_sign() {
        let g = [0.0, 0.0, 9.80665]; // specific force at rest in the level frame (−gravity)
        let cfg = MotionConfig {
            segments: vec![Segment::rest(1.0), Segment::rotate(Axis::X, 90.0, 2.0), Segment::rest(1.0)],
        };
        let m = Motion::new(&cfg, &mut seeded(6));
        let f0 = mat_vec(&m.state(0.5).body_from_level, g);
        let f1 = mat_vec(&m.state(3.5).body_from_level, g);
        assert!((f0[2] - 9.80665).abs() < 1e-12);
        assert!(f1[0].abs() < 1e-12 && (f1[1] - 9.80665).abs() < 1e-12 && f1[2].abs() < 1e-12, "{f1:?}");
        // Mid-rotation: 45°, rate about +x.
        let mid = m.state(2.0);
        let f = mat_vec(&mid.body_from_level, g);
        assert!((f[1] - f[2]).abs() < 1e-9 && f[1] > 0.0, "{f:?}");
        assert!(mid.angular_rate_body_radps[0] > 0.0 && mid.angular_rate_body_radps[1] == 0.0);
        // +90° about y: (−g, 0, 0).
        let cfg = MotionConfig { segments: vec![Segment::rotate(Axis::Y, 90.0, 1.0)] };
        let f = mat_vec(&Motion::new(&cfg, &mut seeded(7)).state(2.0).body_from_level, g);
        assert!((f[0] + 9.80665).abs() < 1e-12 && f[1].abs() < 1e-12 && f[2].abs() < 1e-12, "{f:?}");
    }

    #[test]
    fn motion_angular_rate_matches_attitude_derivative() {
        // Ċ = −[ω]×·C for C = body_from_level and ω the body rate.
        let cfg = MotionConfig {
            segments: vec![
                Segment::rotate(Axis::Vector([1.0, 1.0, 0.0]), 60.0, 2.0),
                Segment::Wobble(WobbleSegment {
                    axis: Axis::Z,
                    amplitude_deg: 20.0,
                    period_s: 1.5,
                    duration_s: 6.0,
                    ramp_s: None,
                }),
            ],
        };
        let m = Motion::new(&cfg, &mut seeded(8));
        for &t in &[0.3, 1.0, 1.7, 2.5, 4.0, 7.7] {
            let h = 1e-5;
            let (cp, cm, s) = (m.state(t + h).body_from_level, m.state(t - h).body_from_level, m.state(t));
            let w = s.angular_rate_body_radps;
            let wx = [[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]];
            let expect = mat_mul(&wx, &s.body_from_level);
            for i in 0..3 {
                for j in 0..3 {
                    let num = (cp[i][j] - cm[i][j]) / (2.0 * h);
                    assert!((num + expect[i][j]).abs() < 1e-6, "t {t} ({i},{j}): {num} vs {}", -expect[i][j]);
                }
            }
        }
        // The wobble returns to the attitude it started from.
        let c_end = m.state(9.0).body_from_level;
        let c_mid = m.state(2.0).body_from_level;
        for i in 0..3 {
            for j in 0..3 {
                assert!((c_end[i][j] - c_mid[i][j]).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn motion_shake_after_tip_over_is_along_the_body_axis() {
        let cfg = MotionConfig {
            segments: vec![Segment::rotate(Axis::X, 90.0, 1.0), Segment::shake(Axis::Y, 10.0, 1.1, 3.0)],
        };
        let m = Motion::new(&cfg, &mut seeded(9));
        let s = m.state(5.3);
        // Body y now points up: the shake is vertical in the level frame, along body y.
        assert!(s.accel_level_mps2[0].abs() < 1e-12 && s.accel_level_mps2[1].abs() < 1e-9);
        let a_body = mat_vec(&s.body_from_level, s.accel_level_mps2);
        assert!(a_body[0].abs() < 1e-9 && a_body[2].abs() < 1e-9 && a_body[1].abs() > 0.1, "{a_body:?}");
    }

    #[test]
    fn motion_jitter_is_seeded_and_config_serde() {
        let cfg = MotionConfig::paper_default();
        let (a, b, c) =
            (Motion::new(&cfg, &mut seeded(1)), Motion::new(&cfg, &mut seeded(1)), Motion::new(&cfg, &mut seeded(2)));
        let t = 23.456;
        assert_eq!(a.state(t).accel_level_mps2[0].to_bits(), b.state(t).accel_level_mps2[0].to_bits());
        assert_ne!(a.state(t).accel_level_mps2[0], c.state(t).accel_level_mps2[0]);
        let text = toml::to_string(&cfg).unwrap();
        let back: MotionConfig = toml::from_str(&text).unwrap();
        assert_eq!(back, cfg);
        let custom: MotionConfig = toml::from_str(
            r#"
            [[segments]]
            kind = "rest"
            duration_s = 5.0
            [[segments]]
            kind = "shake"
            axis = [0.0, 1.0, 1.0]
            duration_s = 20.0
            period_s = 1.5
            amplitude_mps2 = 2.0
            jitter = { period_rel = 0.1 }
            [[segments]]
            kind = "tip_over"
            axis = "x"
            angle_deg = -90.0
            duration_s = 2.0
            "#,
        )
        .unwrap();
        assert!(custom.validate().is_ok());
        match custom.segments[1] {
            Segment::Shake(s) => {
                assert_eq!(s.jitter.period_rel, 0.1);
                assert_eq!(s.jitter.amplitude_rel, 0.07);
            }
            _ => panic!(),
        }
        let unknown = "[[segments]]\nkind = \"rest\"\nduration_s = 1.0\nperiod_s = 2.0\n";
        assert!(toml::from_str::<MotionConfig>(unknown).is_err());
        let mut bad = MotionConfig::paper_default();
        if let Segment::Shake(s) = &mut bad.segments[3] {
            s.period_s = 0.0;
        }
        let e = bad.validate().unwrap_err();
        assert_eq!(e.key(), Some("motion.segments[3].period_s"));
        assert!(e.to_string().contains("segments[3].period_s"), "{e}");
    }
}
