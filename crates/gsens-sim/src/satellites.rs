//! GPS satellite geometry seen from a fixed antenna: orbits from an almanac,
//! elevation/azimuth, range, range rate and acceleration, L1 Doppler and its
//! rate, GPS time helpers and an elevation-dependent C/N0 model.
//!
//! # Orbits
//!
//! Satellite positions follow the almanac user algorithm of IS-GPS-200
//! (Table 20-IV, with the almanac's parameters: no harmonic corrections, no
//! Δn, i = i₀ + 0): mean motion n = √(μ/A³), Kepler's equation
//! M = E − e·sin E solved by Newton iteration, true anomaly ν, argument of
//! latitude u = ν + ω, radius r = A(1 − e·cos E), and the corrected longitude
//! of the ascending node Ω = Ω₀ + (Ω̇ − Ω̇ₑ)·t_k − Ω̇ₑ·t_oa, with t_k = t − t_oa
//! in continuous GPS seconds (no week wrap needed). Velocities are the exact
//! time derivatives of these formulas (the velocity equations of
//! IS-GPS-200 Table 20-IV) and accelerations the exact second derivatives
//! (in-plane Kepler acceleration −μ·r/r³ plus the terms of the node rotating
//! at Ω̇ − Ω̇ₑ), so Doppler and Doppler rate are consistent with the positions
//! to rounding.
//!
//! The built-in almanac ([`Constellation::builtin`]) is a **representative
//! constellation, not a specific week's broadcast almanac**: 31 satellites in
//! six planes 60° apart, inclination ≈ 55°, √A ≈ 5153.6 m^½ (A ≈ 26 560 km,
//! period 11 h 58 min), placed at the 24 baseline slots of the GPS SPS
//! Performance Standard (Table 3-1: plane RAANs and in-plane arguments of
//! latitude), with slots B1, D2 and F2 split into fore/aft pairs and four
//! spares in the widest gaps, eccentricities 0.0005–0.02 and small
//! inclination/node scatter within the SPS tolerances. Epoch: GPS week 2300
//! (2024-02-04), t_oa = 319 488 s; it is kept in YUMA format in
//! `satellites/gps_representative.yuma`. Real YUMA almanacs (e.g. from the US
//! Coast Guard NAVCEN) load with [`Constellation::from_yuma`].
//!
//! # Line of sight
//!
//! The antenna is fixed on the Earth (static in ECEF). Range is the geometric
//! distance at the same instant t (no light-time, Sagnac, atmosphere or
//! satellite-clock terms: they change the Doppler by well under 1 Hz and are
//! irrelevant to a g-sensitivity session; the IF generator, whose pseudoranges
//! a receiver solves its position from, uses them: [`ReceivedSignal`]), range rate ρ̇ = û·v_sat, range
//! acceleration ρ̈ = û·a_sat + (|v_sat|² − ρ̇²)/ρ, and the L1 Doppler
//! f_D = −ρ̇/λ with λ = c/f_L1 (positive for an approaching satellite),
//! Doppler rate −ρ̈/λ. The values are smooth: a session running at 1 ms may
//! evaluate them every second or so and use the Taylor expansion
//! ρ(t₀+δ) ≈ ρ + ρ̇δ + ρ̈δ²/2 (error < 1e-5 m over 1 s).

use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

use gsens_core::units::{GPS_L1_HZ, SPEED_OF_LIGHT_MPS};
use rand::Rng;

use crate::error::{AlmanacError, ConfigError};
use crate::rng::normal;

/// Earth's gravitational constant for GPS orbits μ [m³/s²] (IS-GPS-200, 20.3.3.4.3).
pub const GPS_MU_M3PS2: f64 = 3.986_005e14;
/// Earth rotation rate Ω̇ₑ [rad/s] (WGS-84, IS-GPS-200).
pub const EARTH_ROTATION_RADPS: f64 = 7.292_115_146_7e-5;
/// WGS-84 semi-major axis \[m\] (NIMA TR8350.2).
pub const WGS84_A_M: f64 = 6_378_137.0;
/// WGS-84 flattening \[-\] (NIMA TR8350.2).
pub const WGS84_F: f64 = 1.0 / 298.257_223_563;
/// Seconds in a GPS week.
pub const SECONDS_PER_WEEK: f64 = 604_800.0;
/// GPS − UTC \[s\], constant since 2017-01-01 (IERS Bulletin C); earlier leap
/// seconds are ignored by [`gps_seconds_from_utc`].
pub const GPS_MINUS_UTC_S: f64 = 18.0;
/// Days from 1970-01-01 to the GPS epoch 1980-01-06.
const GPS_EPOCH_UNIX_DAYS: i64 = 3657;

/// The built-in almanac text (YUMA format with `#` comments).
pub const BUILTIN_YUMA: &str = include_str!("satellites/gps_representative.yuma");
/// Full GPS week of the built-in almanac.
pub const BUILTIN_WEEK: u32 = 2300;

/// Wavelength of GPS L1 \[m\]: c / f_L1.
pub fn l1_wavelength_m() -> f64 {
    SPEED_OF_LIGHT_MPS / GPS_L1_HZ
}

// ---------------------------------------------------------------------------
// Time
// ---------------------------------------------------------------------------

/// Days since 1970-01-01 of a proleptic Gregorian date (H. Hinnant's
/// `days_from_civil` algorithm).
fn days_from_civil(year: i32, month: u32, day: u32) -> i64 {
    let y = i64::from(year) - i64::from(month <= 2);
    let era = if y >= 0 { y } else { y - 399 } / 400;
    let yoe = y - era * 400;
    let m = i64::from(month);
    let doy = (153 * (if m > 2 { m - 3 } else { m + 9 }) + 2) / 5 + i64::from(day) - 1;
    let doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
    era * 146_097 + doe - 719_468
}

/// GPS seconds since the GPS epoch (1980-01-06 00:00:00 GPS time) of a UTC
/// calendar date and time, with GPS − UTC = [`GPS_MINUS_UTC_S`] (18 s, exact
/// from 2017 on; earlier dates are off by the leap seconds since inserted).
pub fn gps_seconds_from_utc(year: i32, month: u32, day: u32, hour: u32, minute: u32, second: f64) -> f64 {
    let days = days_from_civil(year, month, day) - GPS_EPOCH_UNIX_DAYS;
    days as f64 * 86_400.0 + f64::from(hour) * 3600.0 + f64::from(minute) * 60.0 + second + GPS_MINUS_UTC_S
}

/// A GPS time as full week number and time of week.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GpsTime {
    /// Full GPS week number (no 1024 rollover).
    pub week: u32,
    /// Time of week \[s\], 0 ≤ tow < 604 800.
    pub tow_s: f64,
}

impl GpsTime {
    /// From GPS seconds since the GPS epoch (≥ 0).
    pub fn from_gps_seconds(t_gps_s: f64) -> Self {
        let week = (t_gps_s / SECONDS_PER_WEEK).floor();
        Self { week: week as u32, tow_s: t_gps_s - week * SECONDS_PER_WEEK }
    }

    /// GPS seconds since the GPS epoch: week·604 800 + tow.
    pub fn to_gps_seconds(self) -> f64 {
        f64::from(self.week) * SECONDS_PER_WEEK + self.tow_s
    }
}

// ---------------------------------------------------------------------------
// Geodesy
// ---------------------------------------------------------------------------

/// A WGS-84 geodetic position.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Geodetic {
    /// Geodetic latitude \[deg\], north positive.
    pub lat_deg: f64,
    /// Longitude \[deg\], east positive.
    pub lon_deg: f64,
    /// Height above the ellipsoid \[m\].
    #[serde(default)]
    pub height_m: f64,
}

impl Geodetic {
    /// A position from latitude \[deg\], longitude \[deg\] and ellipsoidal height \[m\].
    pub fn new(lat_deg: f64, lon_deg: f64, height_m: f64) -> Self {
        Self { lat_deg, lon_deg, height_m }
    }

    /// Checks ranges; the error names the offending key (`lat_deg`,
    /// `lon_deg`, `height_m`: a scenario reports them under `antenna.`).
    pub fn validate(&self) -> Result<(), ConfigError> {
        if !(self.lat_deg.is_finite() && self.lat_deg.abs() <= 90.0) {
            return Err(ConfigError::out_of_range("lat_deg", self.lat_deg, "within [-90, 90]"));
        }
        if !(self.lon_deg.is_finite() && self.lon_deg.abs() <= 360.0) {
            return Err(ConfigError::out_of_range("lon_deg", self.lon_deg, "within [-360, 360]"));
        }
        if !(self.height_m.is_finite() && self.height_m > -1.0e4 && self.height_m < 1.0e5) {
            return Err(ConfigError::out_of_range("height_m", self.height_m, "within (-10 km, 100 km)"));
        }
        Ok(())
    }

    /// ECEF position \[m\]: x = (N + h)cosφ cosλ, y = (N + h)cosφ sinλ,
    /// z = (N(1 − e²) + h) sinφ, N = a/√(1 − e² sin²φ) (WGS-84, NIMA TR8350.2 §4).
    pub fn to_ecef_m(&self) -> [f64; 3] {
        let e2 = WGS84_F * (2.0 - WGS84_F);
        let (sp, cp) = self.lat_deg.to_radians().sin_cos();
        let (sl, cl) = self.lon_deg.to_radians().sin_cos();
        let n = WGS84_A_M / (1.0 - e2 * sp * sp).sqrt();
        [(n + self.height_m) * cp * cl, (n + self.height_m) * cp * sl, (n * (1.0 - e2) + self.height_m) * sp]
    }

    /// Geodetic position of an ECEF point \[m\] (iterated to 1e-12 rad; fine
    /// from the Earth's centre region outwards to GPS altitude).
    pub fn from_ecef_m(ecef_m: [f64; 3]) -> Self {
        let e2 = WGS84_F * (2.0 - WGS84_F);
        let [x, y, z] = ecef_m;
        let p = x.hypot(y);
        let lon = y.atan2(x);
        let mut lat = z.atan2(p * (1.0 - e2));
        let mut h = 0.0;
        for _ in 0..20 {
            let (sp, cp) = lat.sin_cos();
            let w = (1.0 - e2 * sp * sp).sqrt();
            let n = WGS84_A_M / w;
            // h = p·cosφ + z·sinφ − a²/N: well conditioned at all latitudes.
            h = p * cp + z * sp - WGS84_A_M * w;
            let next = z.atan2(p * (1.0 - e2 * n / (n + h)));
            let done = (next - lat).abs() < 1e-12;
            lat = next;
            if done {
                break;
            }
        }
        Self { lat_deg: lat.to_degrees(), lon_deg: lon.to_degrees(), height_m: h }
    }

    /// Unit vectors east, north, up [ECEF components] at this position.
    pub fn enu_axes(&self) -> [[f64; 3]; 3] {
        let (sp, cp) = self.lat_deg.to_radians().sin_cos();
        let (sl, cl) = self.lon_deg.to_radians().sin_cos();
        [[-sl, cl, 0.0], [-sp * cl, -sp * sl, cp], [cp * cl, cp * sl, sp]]
    }
}

// ---------------------------------------------------------------------------
// Almanac and orbits
// ---------------------------------------------------------------------------

/// One satellite's almanac (YUMA fields, angles in radians).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AlmanacEntry {
    /// PRN number.
    pub prn: u32,
    /// Health word (0 = healthy).
    pub health: u32,
    /// Eccentricity e \[-\].
    pub eccentricity: f64,
    /// Time of applicability t_oa [s of week].
    pub toa_s: f64,
    /// Inclination i \[rad\].
    pub inclination_rad: f64,
    /// Rate of right ascension Ω̇ [rad/s].
    pub raan_rate_radps: f64,
    /// Square root of the semi-major axis √A [m^½].
    pub sqrt_a_sqrtm: f64,
    /// Longitude of the ascending node at the weekly epoch Ω₀ \[rad\].
    pub raan0_rad: f64,
    /// Argument of perigee ω \[rad\].
    pub arg_perigee_rad: f64,
    /// Mean anomaly at t_oa, M₀ \[rad\].
    pub mean_anomaly_rad: f64,
    /// Clock bias a_f0 \[s\] (not used by the geometry).
    pub af0_s: f64,
    /// Clock drift a_f1 [s/s] (not used by the geometry).
    pub af1_sps: f64,
    /// Full GPS week of t_oa.
    pub week: u32,
}

/// A satellite's ECEF (WGS-84) kinematic state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SatState {
    /// Position \[m\].
    pub pos_m: [f64; 3],
    /// Velocity [m/s] (in the rotating ECEF frame).
    pub vel_mps: [f64; 3],
    /// Acceleration [m/s²] (second derivative of the ECEF position).
    pub accel_mps2: [f64; 3],
}

impl AlmanacEntry {
    /// Semi-major axis A \[m\].
    pub fn semi_major_axis_m(&self) -> f64 {
        self.sqrt_a_sqrtm * self.sqrt_a_sqrtm
    }

    /// Orbital (anomalistic) period 2π·√(A³/μ) \[s\].
    pub fn period_s(&self) -> f64 {
        2.0 * PI / self.mean_motion_radps()
    }

    /// Mean motion n = √(μ/A³) [rad/s].
    pub fn mean_motion_radps(&self) -> f64 {
        (GPS_MU_M3PS2 / self.semi_major_axis_m().powi(3)).sqrt()
    }

    /// t_oa in GPS seconds since the GPS epoch.
    pub fn toa_gps_s(&self) -> f64 {
        f64::from(self.week) * SECONDS_PER_WEEK + self.toa_s
    }

    /// ECEF position, velocity and acceleration at `t_gps_s` (GPS seconds
    /// since the GPS epoch), IS-GPS-200 Table 20-IV with almanac parameters
    /// (see the module documentation).
    pub fn state_ecef(&self, t_gps_s: f64) -> SatState {
        let a = self.semi_major_axis_m();
        let e = self.eccentricity;
        let n = self.mean_motion_radps();
        let tk = t_gps_s - self.toa_gps_s();
        let m = (self.mean_anomaly_rad + n * tk).rem_euclid(2.0 * PI);
        // Kepler: E − e sin E = M (Newton from E = M; e ≤ 0.03 → 3–4 steps).
        let mut ea = m;
        for _ in 0..12 {
            let d = (ea - e * ea.sin() - m) / (1.0 - e * ea.cos());
            ea -= d;
            if d.abs() < 1e-15 {
                break;
            }
        }
        let (se, ce) = ea.sin_cos();
        let one_m_ecos = 1.0 - e * ce;
        let sq = (1.0 - e * e).sqrt();
        let nu = (sq * se).atan2(ce - e);
        let u = nu + self.arg_perigee_rad;
        let r = a * one_m_ecos;
        let edot = n / one_m_ecos;
        let nudot = edot * sq / one_m_ecos;
        let rdot = a * e * se * edot;
        let (su, cu) = u.sin_cos();
        // In-plane position, velocity, acceleration (Kepler: −μ r⃗/r³).
        let (xp, yp) = (r * cu, r * su);
        let (vxp, vyp) = (rdot * cu - r * nudot * su, rdot * su + r * nudot * cu);
        let k = -GPS_MU_M3PS2 / (r * r * r);
        let (axp, ayp) = (k * xp, k * yp);
        // Node rotating at w = Ω̇ − Ω̇ₑ.
        let w = self.raan_rate_radps - EARTH_ROTATION_RADPS;
        let omega = self.raan0_rad + w * tk - EARTH_ROTATION_RADPS * self.toa_s;
        let (so, co) = omega.sin_cos();
        let (si, ci) = self.inclination_rad.sin_cos();
        // x = X cosΩ − Y sinΩ, y = X sinΩ + Y cosΩ, z = y' sin i, with X = x', Y = y' cos i.
        let (bx, by) = (xp, yp * ci);
        let (vbx, vby) = (vxp, vyp * ci);
        let (abx, aby) = (axp, ayp * ci);
        let x = bx * co - by * so;
        let y = bx * so + by * co;
        let z = yp * si;
        let vx = vbx * co - vby * so - w * y;
        let vy = vbx * so + vby * co + w * x;
        let vz = vyp * si;
        let ax = abx * co - aby * so - 2.0 * w * (vbx * so + vby * co) - w * w * x;
        let ay = abx * so + aby * co + 2.0 * w * (vbx * co - vby * so) - w * w * y;
        let az = ayp * si;
        SatState { pos_m: [x, y, z], vel_mps: [vx, vy, vz], accel_mps2: [ax, ay, az] }
    }
}

/// Geometry of one satellite seen from the antenna.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct LineOfSight {
    /// PRN number.
    pub prn: u32,
    /// Elevation above the local (ellipsoid-normal) horizon \[deg\].
    pub elevation_deg: f64,
    /// Azimuth from north towards east \[deg\], in [0, 360).
    pub azimuth_deg: f64,
    /// Geometric range ρ \[m\].
    pub range_m: f64,
    /// Range rate ρ̇ [m/s] (positive when receding).
    pub range_rate_mps: f64,
    /// Range acceleration ρ̈ [m/s²].
    pub range_accel_mps2: f64,
    /// L1 Doppler f_D = −ρ̇/λ_L1 \[Hz\] (positive when approaching).
    pub doppler_hz: f64,
    /// L1 Doppler rate −ρ̈/λ_L1 [Hz/s].
    pub doppler_rate_hz_per_s: f64,
}

impl LineOfSight {
    /// Doppler −ρ̇·f/c \[Hz\] at another carrier frequency `carrier_hz`.
    pub fn doppler_at_hz(&self, carrier_hz: f64) -> f64 {
        -self.range_rate_mps * carrier_hz / SPEED_OF_LIGHT_MPS
    }

    /// L1 Doppler \[Hz\] `dt_s` seconds later by Taylor expansion
    /// f_D + ḟ_D·δt (the Doppler rate changes by < 1e-3 Hz/s² for GPS).
    pub fn doppler_after_hz(&self, dt_s: f64) -> f64 {
        self.doppler_hz + self.doppler_rate_hz_per_s * dt_s
    }
}

/// A fixed antenna with its ECEF position and local axes precomputed (saves
/// the trigonometry of [`Geodetic::to_ecef_m`] on every line-of-sight call).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Site {
    /// The antenna's geodetic position.
    pub geodetic: Geodetic,
    /// Its ECEF position \[m\].
    pub ecef_m: [f64; 3],
    /// Its east, north, up unit vectors [ECEF components].
    pub enu: [[f64; 3]; 3],
}

impl Site {
    /// Precomputes the antenna at `geodetic`.
    pub fn new(geodetic: &Geodetic) -> Self {
        Self { geodetic: *geodetic, ecef_m: geodetic.to_ecef_m(), enu: geodetic.enu_axes() }
    }
}

/// Line of sight from an antenna at ECEF `ant_m` with local axes `enu` to a
/// satellite state.
fn line_of_sight_from(prn: u32, ant_m: &[f64; 3], enu: &[[f64; 3]; 3], s: &SatState) -> LineOfSight {
    let d = [s.pos_m[0] - ant_m[0], s.pos_m[1] - ant_m[1], s.pos_m[2] - ant_m[2]];
    let rho = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    let uv = [d[0] / rho, d[1] / rho, d[2] / rho];
    let dot = |a: &[f64; 3], b: &[f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let rho_dot = dot(&uv, &s.vel_mps);
    let v2 = dot(&s.vel_mps, &s.vel_mps);
    let rho_ddot = dot(&uv, &s.accel_mps2) + (v2 - rho_dot * rho_dot) / rho;
    let (east, north, up) = (dot(&uv, &enu[0]), dot(&uv, &enu[1]), dot(&uv, &enu[2]));
    let mut az = east.atan2(north).to_degrees();
    if az < 0.0 {
        az += 360.0;
    }
    if az >= 360.0 {
        az -= 360.0;
    }
    let lambda = l1_wavelength_m();
    LineOfSight {
        prn,
        elevation_deg: up.clamp(-1.0, 1.0).asin().to_degrees(),
        azimuth_deg: az,
        range_m: rho,
        range_rate_mps: rho_dot,
        range_accel_mps2: rho_ddot,
        doppler_hz: -rho_dot / lambda,
        doppler_rate_hz_per_s: -rho_ddot / lambda,
    }
}

/// A satellite's signal as it reaches a fixed antenna at GPS time t (the
/// receive instant), for a receiver that locates the satellite at the
/// transmit instant and rotates it into the ECEF frame of the receive
/// instant (IS-GPS-200 §20.3.3.4.3.4, §20.3.3.3.3.1):
///
/// ```text
/// τ = |R₃(Ω̇ₑτ)·r_sat(t − τ) − r_ant| / c        (light time, Sagnac by the exact rotation)
/// Δt_r = F·e·√A·sin E = −2·r_sat·v_sat/c²       (the satellite clock's relativistic term at t − τ)
/// ρ = c·(τ − Δt_r)                              (the pseudorange of a receiver clock on GPS time)
/// ```
///
/// with R₃(θ) = [[cos θ, sin θ, 0], [−sin θ, cos θ, 0], [0, 0, 1]] and
/// r·v of the ECEF vectors (equal to the inertial r·v: r·(ω × r) = 0). A
/// satellite clock that keeps GPS time but for the relativistic term (the
/// a_f0 = a_f1 = a_f2 = 0 of a broadcast ephemeris) stamps the signal
/// t_sv = t − τ + Δt_r, so the code and carrier phases a receiver measures
/// follow ρ.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReceivedSignal {
    /// Light time τ \[s\].
    pub light_time_s: f64,
    /// dτ/dt \[s/s\].
    pub light_time_rate: f64,
    /// The satellite clock's relativistic term Δt_r at the transmit instant \[s\].
    pub relativistic_s: f64,
    /// ρ = c·(τ − Δt_r) \[m\].
    pub pseudorange_m: f64,
    /// dρ/dt [m/s] (receive time).
    pub pseudorange_rate_mps: f64,
    /// The satellite at the transmit instant, in the ECEF frame of the receive instant \[m\].
    pub sat_pos_m: [f64; 3],
}

impl AlmanacEntry {
    /// The signal received at the ECEF point `ant_m` at GPS time `t_rx_gps_s`
    /// ([`ReceivedSignal`]): τ by fixed-point iteration (each step gains the
    /// factor |v_sat|/c ≈ 1e-5), and
    ///
    /// ```text
    /// dτ/dt = û·R·v / (c + û·R·v − Ω̇ₑ·û·R′·r)
    /// dρ/dt = c·dτ/dt − c·(dΔt_r/dt)·(1 − dτ/dt),   dΔt_r/dt = −2·(|v|² + r·a)/c²
    /// ```
    ///
    /// (û the unit vector antenna → satellite, R = R₃(Ω̇ₑτ), R′ its
    /// derivative by the angle, r, v, a the ECEF state at t − τ).
    pub fn received_at(&self, ant_m: &[f64; 3], t_rx_gps_s: f64) -> ReceivedSignal {
        let c = SPEED_OF_LIGHT_MPS;
        let dot = |a: &[f64; 3], b: &[f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        let rot = |th: f64, p: &[f64; 3]| {
            let (s, co) = th.sin_cos();
            [co * p[0] + s * p[1], -s * p[0] + co * p[1], p[2]]
        };
        // From τ = 0 (the geometric range): 0.07 s → 1e-6 → 1e-11 → 1e-16 s.
        let mut tau = 0.0;
        let (mut st, mut x);
        let mut steps = 0;
        loop {
            st = self.state_ecef(t_rx_gps_s - tau);
            x = rot(EARTH_ROTATION_RADPS * tau, &st.pos_m);
            let d = [x[0] - ant_m[0], x[1] - ant_m[1], x[2] - ant_m[2]];
            let next = dot(&d, &d).sqrt() / c;
            let change = (next - tau).abs();
            tau = next;
            steps += 1;
            if change < 1e-15 || steps == 8 {
                break;
            }
        }
        let d = [x[0] - ant_m[0], x[1] - ant_m[1], x[2] - ant_m[2]];
        let dist = dot(&d, &d).sqrt();
        let u = [d[0] / dist, d[1] / dist, d[2] / dist];
        let th = EARTH_ROTATION_RADPS * tau;
        let rv = rot(th, &st.vel_mps);
        let (s, co) = th.sin_cos();
        let p = st.pos_m;
        let r_prime_p = [-s * p[0] + co * p[1], -co * p[0] - s * p[1], 0.0];
        let urv = dot(&u, &rv);
        let tau_dot = urv / (c + urv - EARTH_ROTATION_RADPS * dot(&u, &r_prime_p));
        let rel_s = -2.0 * dot(&st.pos_m, &st.vel_mps) / (c * c);
        let rel_rate = -2.0 * (dot(&st.vel_mps, &st.vel_mps) + dot(&st.pos_m, &st.accel_mps2)) / (c * c);
        ReceivedSignal {
            light_time_s: tau,
            light_time_rate: tau_dot,
            relativistic_s: rel_s,
            pseudorange_m: c * (tau - rel_s),
            pseudorange_rate_mps: c * tau_dot - c * rel_rate * (1.0 - tau_dot),
            sat_pos_m: x,
        }
    }
}

impl AlmanacEntry {
    /// The line of sight from `site` at GPS time `t_rx_gps_s` as the signal
    /// arrives: elevation, azimuth, range acceleration and Doppler rate the
    /// geometric ones at that instant, range the pseudorange ρ of
    /// [`ReceivedSignal`], range rate dρ/dt and Doppler −(dρ/dt)/λ_L1.
    pub fn received_line_of_sight(&self, site: &Site, t_rx_gps_s: f64) -> LineOfSight {
        let geometric = line_of_sight_from(self.prn, &site.ecef_m, &site.enu, &self.state_ecef(t_rx_gps_s));
        let r = self.received_at(&site.ecef_m, t_rx_gps_s);
        LineOfSight {
            range_m: r.pseudorange_m,
            range_rate_mps: r.pseudorange_rate_mps,
            doppler_hz: -r.pseudorange_rate_mps / l1_wavelength_m(),
            ..geometric
        }
    }
}

/// A set of GPS satellites with their almanacs, sorted by PRN.
#[derive(Debug, Clone, PartialEq)]
pub struct Constellation {
    sats: Vec<AlmanacEntry>,
}

impl Constellation {
    /// The built-in representative 31-satellite constellation (module docs).
    pub fn builtin() -> Self {
        Self::from_yuma(BUILTIN_YUMA, BUILTIN_WEEK).expect("built-in almanac parses")
    }

    /// A constellation from almanac entries (sorted by PRN; a repeated PRN
    /// keeps its last entry).
    pub fn from_entries(mut sats: Vec<AlmanacEntry>) -> Self {
        sats.sort_by_key(|s| s.prn);
        let mut out: Vec<AlmanacEntry> = Vec::with_capacity(sats.len());
        for s in sats {
            match out.last_mut() {
                Some(last) if last.prn == s.prn => *last = s,
                _ => out.push(s),
            }
        }
        Self { sats: out }
    }

    /// Parses a YUMA almanac (the text format published by the US Coast Guard
    /// NAVCEN: records of `Key: value` lines opened by a `****` header; lines
    /// starting with `#` and text after ` #` are ignored). The 10-bit YUMA week
    /// is resolved to the full week nearest `full_week_near`.
    pub fn from_yuma(text: &str, full_week_near: u32) -> Result<Self, AlmanacError> {
        let mut sats = Vec::new();
        // The current record's fields and the line of its first one.
        let mut cur: Vec<(String, f64)> = Vec::new();
        let mut cur_line = 0;
        let finish =
            |cur: &mut Vec<(String, f64)>, line: usize, sats: &mut Vec<AlmanacEntry>| -> Result<(), AlmanacError> {
                if cur.is_empty() {
                    return Ok(());
                }
                let get = |field: &'static str| {
                    cur.iter()
                        .find(|(k, _)| k.starts_with(field))
                        .map(|(_, v)| *v)
                        .ok_or(AlmanacError::MissingField { line, field })
                };
                let prn = get("id")?;
                let week10 = get("week")? as i64;
                let near = i64::from(full_week_near);
                let mut full = near - (near - week10).rem_euclid(1024);
                if near - full > 512 {
                    full += 1024;
                }
                sats.push(AlmanacEntry {
                    prn: prn as u32,
                    health: get("health")? as u32,
                    eccentricity: get("eccentricity")?,
                    toa_s: get("time of applicability")?,
                    inclination_rad: get("orbital inclination")?,
                    raan_rate_radps: get("rate of right ascen")?,
                    sqrt_a_sqrtm: get("sqrt(a)")?,
                    raan0_rad: get("right ascen at week")?,
                    arg_perigee_rad: get("argument of perigee")?,
                    mean_anomaly_rad: get("mean anom")?,
                    af0_s: get("af0")?,
                    af1_sps: get("af1")?,
                    week: full.max(0) as u32,
                });
                cur.clear();
                Ok(())
            };
        for (lineno, raw) in text.lines().enumerate() {
            let line = lineno + 1;
            let content = raw.split(" #").next().unwrap_or("").trim();
            if content.is_empty() || content.starts_with('#') {
                continue;
            }
            if content.starts_with('*') {
                finish(&mut cur, cur_line, &mut sats)?;
                continue;
            }
            let (key, value) = content.split_once(':').ok_or(AlmanacError::ExpectedKeyValue { line })?;
            let value = value.trim();
            let v: f64 =
                value.parse().map_err(|error| AlmanacError::BadNumber { line, text: value.to_owned(), error })?;
            if cur.is_empty() {
                cur_line = line;
            }
            cur.push((key.trim().to_ascii_lowercase(), v));
        }
        finish(&mut cur, cur_line, &mut sats)?;
        if sats.is_empty() {
            return Err(AlmanacError::Empty);
        }
        Ok(Self::from_entries(sats))
    }

    /// The almanac entries, sorted by PRN.
    pub fn satellites(&self) -> &[AlmanacEntry] {
        &self.sats
    }

    /// The PRN numbers, ascending.
    pub fn prns(&self) -> Vec<u32> {
        self.sats.iter().map(|s| s.prn).collect()
    }

    /// The almanac of `prn`, if present.
    pub fn get(&self, prn: u32) -> Option<&AlmanacEntry> {
        self.sats.binary_search_by_key(&prn, |s| s.prn).ok().map(|i| &self.sats[i])
    }

    /// ECEF state of `prn` at `t_gps_s`, if present.
    pub fn state_ecef(&self, prn: u32, t_gps_s: f64) -> Option<SatState> {
        self.get(prn).map(|s| s.state_ecef(t_gps_s))
    }

    /// Line of sight to `prn` from `antenna` at `t_gps_s` (GPS seconds since
    /// the GPS epoch); None for an unknown PRN.
    pub fn line_of_sight(&self, prn: u32, antenna: &Geodetic, t_gps_s: f64) -> Option<LineOfSight> {
        let sat = self.get(prn)?;
        let ant = antenna.to_ecef_m();
        Some(line_of_sight_from(prn, &ant, &antenna.enu_axes(), &sat.state_ecef(t_gps_s)))
    }

    /// As [`Constellation::line_of_sight`] from a precomputed [`Site`] (about
    /// half the cost).
    pub fn line_of_sight_from_site(&self, prn: u32, site: &Site, t_gps_s: f64) -> Option<LineOfSight> {
        let sat = self.get(prn)?;
        Some(line_of_sight_from(prn, &site.ecef_m, &site.enu, &sat.state_ecef(t_gps_s)))
    }

    /// Lines of sight to all healthy satellites at or above
    /// `elevation_mask_deg`, by decreasing elevation.
    pub fn visible_lines_of_sight(
        &self,
        antenna: &Geodetic,
        t_gps_s: f64,
        elevation_mask_deg: f64,
    ) -> Vec<LineOfSight> {
        let ant = antenna.to_ecef_m();
        let enu = antenna.enu_axes();
        let mut v: Vec<LineOfSight> = self
            .sats
            .iter()
            .filter(|s| s.health == 0)
            .map(|s| line_of_sight_from(s.prn, &ant, &enu, &s.state_ecef(t_gps_s)))
            .filter(|l| l.elevation_deg >= elevation_mask_deg)
            .collect();
        v.sort_by(|a, b| b.elevation_deg.total_cmp(&a.elevation_deg));
        v
    }

    /// PRNs of the healthy satellites at or above `elevation_mask_deg` seen
    /// from `antenna` at `t_gps_s`, ascending.
    pub fn visible(&self, antenna: &Geodetic, t_gps_s: f64, elevation_mask_deg: f64) -> Vec<u32> {
        let mut p: Vec<u32> =
            self.visible_lines_of_sight(antenna, t_gps_s, elevation_mask_deg).iter().map(|l| l.prn).collect();
        p.sort_unstable();
        p
    }
}

// ---------------------------------------------------------------------------
// C/N0
// ---------------------------------------------------------------------------

/// Largest PRN with its own C/N0 offset (GPS PRNs 1–63).
pub const MAX_PRN: u32 = 63;

/// Elevation-dependent carrier-to-noise density of the fixed antenna:
///
/// C/N0(el) = C/N0_horizon + (C/N0_zenith − C/N0_horizon)·sin(max(el, 0))^p + δ_prn
///
/// with δ_prn ~ N(0, σ²) drawn once per PRN ([`Cn0Model::draw_offsets`]). The
/// shape (exponent p = 0.5 by default: 35 dB-Hz at the horizon, ≈ 40 at 10°,
/// ≈ 43.5 at 30°, 47 at the zenith) is an empirical fit typical of a patch
/// antenna in open sky, not a standard.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Cn0Model {
    /// C/N0 at 90° elevation \[dB-Hz\].
    pub zenith_cn0_dbhz: f64,
    /// C/N0 at 0° elevation \[dB-Hz\].
    pub horizon_cn0_dbhz: f64,
    /// Shape exponent p of sin(el)^p \[-\] (1 = linear in sin el).
    pub elevation_exponent: f64,
    /// σ of the per-satellite offset δ_prn \[dB\].
    pub per_satellite_offset_sigma_db: f64,
}

impl Default for Cn0Model {
    fn default() -> Self {
        Self {
            zenith_cn0_dbhz: 47.0,
            horizon_cn0_dbhz: 35.0,
            elevation_exponent: 0.5,
            per_satellite_offset_sigma_db: 1.0,
        }
    }
}

impl Cn0Model {
    /// Checks ranges; the error names the offending key (`cn0.…`: a
    /// scenario reports them under `satellites.`).
    pub fn validate(&self) -> Result<(), ConfigError> {
        for (key, v) in [("zenith_cn0_dbhz", self.zenith_cn0_dbhz), ("horizon_cn0_dbhz", self.horizon_cn0_dbhz)] {
            if !(v.is_finite() && (0.0..=70.0).contains(&v)) {
                return Err(ConfigError::out_of_range(format!("cn0.{key}"), v, "within [0, 70] dB-Hz"));
            }
        }
        if !(self.elevation_exponent.is_finite() && self.elevation_exponent > 0.0) {
            return Err(ConfigError::out_of_range("cn0.elevation_exponent", self.elevation_exponent, "> 0"));
        }
        let s = self.per_satellite_offset_sigma_db;
        if !(s.is_finite() && (0.0..=10.0).contains(&s)) {
            return Err(ConfigError::out_of_range("cn0.per_satellite_offset_sigma_db", s, "within [0, 10] dB"));
        }
        Ok(())
    }

    /// C/N0 \[dB-Hz\] at `elevation_deg` without the per-satellite offset.
    pub fn nominal_cn0_dbhz(&self, elevation_deg: f64) -> f64 {
        let s = elevation_deg.to_radians().sin().max(0.0);
        self.horizon_cn0_dbhz + (self.zenith_cn0_dbhz - self.horizon_cn0_dbhz) * s.powf(self.elevation_exponent)
    }

    /// Draws the per-PRN offsets δ_prn for PRN 1…[`MAX_PRN`], in PRN order
    /// (so the draw does not depend on which satellites are visible).
    pub fn draw_offsets<R: Rng + ?Sized>(&self, rng: &mut R) -> Cn0Offsets {
        let offsets_db =
            (0..=MAX_PRN).map(|p| if p == 0 { 0.0 } else { normal(rng, self.per_satellite_offset_sigma_db) }).collect();
        Cn0Offsets { model: self.clone(), offsets_db }
    }
}

/// A [`Cn0Model`] with its per-PRN offsets drawn.
#[derive(Debug, Clone, PartialEq)]
pub struct Cn0Offsets {
    model: Cn0Model,
    offsets_db: Vec<f64>,
}

impl Cn0Offsets {
    /// The per-PRN offset δ_prn \[dB\] (0 for PRNs above [`MAX_PRN`]).
    pub fn offset_db(&self, prn: u32) -> f64 {
        self.offsets_db.get(prn as usize).copied().unwrap_or(0.0)
    }

    /// C/N0 \[dB-Hz\] of `prn` at `elevation_deg`: nominal + δ_prn.
    pub fn cn0_dbhz(&self, prn: u32, elevation_deg: f64) -> f64 {
        self.model.nominal_cn0_dbhz(elevation_deg) + self.offset_db(prn)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::seeded;

    fn moscow() -> Geodetic {
        Geodetic::new(55.7558, 37.6173, 150.0)
    }

    fn t0() -> f64 {
        gps_seconds_from_utc(2024, 2, 6, 12, 0, 0.0)
    }

    #[test]
    fn sat_time_conversions() {
        // Week 2300 starts on Sunday 2024-02-04 00:00:00 GPS = 23:59:42 UTC on the 3rd.
        let t = gps_seconds_from_utc(2024, 2, 4, 0, 0, 0.0);
        let g = GpsTime::from_gps_seconds(t);
        assert_eq!(g.week, 2300);
        assert!((g.tow_s - 18.0).abs() < 1e-9);
        assert_eq!(GpsTime { week: 2300, tow_s: 18.0 }.to_gps_seconds(), t);
        assert_eq!(gps_seconds_from_utc(1980, 1, 6, 0, 0, 0.0), 18.0);
        // A well-known week: 2019-04-07 started week 2048 (second rollover).
        let g = GpsTime::from_gps_seconds(gps_seconds_from_utc(2019, 4, 7, 0, 0, 0.0) - 18.0);
        assert_eq!((g.week, g.tow_s), (2048, 0.0));
    }

    #[test]
    fn sat_geodetic_round_trip() {
        for &(lat, lon, h) in
            &[(55.7558, 37.6173, 150.0), (-33.9, 151.2, 40.0), (89.9, -120.0, 3000.0), (0.0, 0.0, 0.0)]
        {
            let g = Geodetic::new(lat, lon, h);
            let back = Geodetic::from_ecef_m(g.to_ecef_m());
            assert!((back.lat_deg - lat).abs() < 1e-9 && (back.lon_deg - lon).abs() < 1e-9, "{back:?}");
            assert!((back.height_m - h).abs() < 1e-4, "{back:?}");
        }
    }

    #[test]
    fn sat_builtin_almanac_is_a_gps_constellation() {
        let c = Constellation::builtin();
        assert_eq!(c.satellites().len(), 31);
        let mut planes: Vec<f64> = Vec::new();
        for s in c.satellites() {
            // Period 11 h 58 min (half a sidereal day, 43 082 s) ± 1 min.
            assert!((s.period_s() - (11.0 * 3600.0 + 58.0 * 60.0)).abs() < 60.0, "PRN {} {}", s.prn, s.period_s());
            assert!((s.inclination_rad.to_degrees() - 55.0).abs() < 3.0);
            assert!(s.eccentricity < 0.02);
            // Inertial node longitude at t_oa (Ω₀ − Ω̇ₑ·t_oa + Ω̇ₑ·t_oa cancels): group by plane.
            let node = s.raan0_rad.to_degrees().rem_euclid(360.0);
            if !planes.iter().any(|p| ((p - node + 540.0) % 360.0 - 180.0).abs() < 5.0) {
                planes.push(node);
            }
        }
        planes.sort_by(f64::total_cmp);
        assert_eq!(planes.len(), 6, "{planes:?}");
        for w in planes.windows(2) {
            assert!((w[1] - w[0] - 60.0).abs() < 3.0, "{planes:?}");
        }
    }

    #[test]
    fn sat_orbit_radius_and_period() {
        let c = Constellation::builtin();
        let t = t0();
        for s in c.satellites() {
            let st = s.state_ecef(t);
            let r = st.pos_m.iter().map(|x| x * x).sum::<f64>().sqrt();
            assert!((r - 26_560e3).abs() < 600e3, "PRN {} r = {r}", s.prn);
            let v = st.vel_mps.iter().map(|x| x * x).sum::<f64>().sqrt();
            // ECEF speed: inertial 3.87 km/s minus Earth rotation: 1.9–4.5 km/s.
            assert!((1_500.0..4_500.0).contains(&v), "PRN {} v = {v}", s.prn);
            // One period later the inertial position repeats (up to the node drift
            // Ω̇·T ≈ 3.4e-4 rad ≈ 9 km).
            let inertial = |t: f64| {
                let p = s.state_ecef(t).pos_m;
                let th = EARTH_ROTATION_RADPS * t;
                let (sn, cs) = th.sin_cos();
                [cs * p[0] - sn * p[1], sn * p[0] + cs * p[1], p[2]]
            };
            let (a, b, h) = (inertial(t), inertial(t + s.period_s()), inertial(t + 0.5 * s.period_s()));
            let d = |x: [f64; 3], y: [f64; 3]| {
                ((x[0] - y[0]).powi(2) + (x[1] - y[1]).powi(2) + (x[2] - y[2]).powi(2)).sqrt()
            };
            assert!(d(a, b) < 20e3, "PRN {}: {}", s.prn, d(a, b));
            assert!(d(a, h) > 50_000e3, "PRN {}: {}", s.prn, d(a, h));
        }
    }

    #[test]
    fn sat_visibility_and_doppler_bounds() {
        let c = Constellation::builtin();
        let places = [
            moscow(),
            Geodetic::new(0.0, -60.0, 0.0),
            Geodetic::new(-45.0, 170.0, 0.0),
            Geodetic::new(70.0, 20.0, 0.0),
        ];
        for p in &places {
            for k in 0..48 {
                let t = t0() + f64::from(k) * 1800.0;
                let vis = c.visible_lines_of_sight(p, t, 10.0);
                assert!(vis.len() >= 6, "{p:?} t+{k}·30min: {} visible", vis.len());
                for l in &vis {
                    assert!(l.doppler_hz.abs() < 5_000.0, "{l:?}");
                    assert!(l.doppler_rate_hz_per_s.abs() < 1.0, "{l:?}");
                    assert!((19_000e3..26_000e3).contains(&l.range_m), "{l:?}");
                }
            }
        }
        // Rising and setting: the visible set changes over 6 hours.
        let a = c.visible(&moscow(), t0(), 10.0);
        let b = c.visible(&moscow(), t0() + 6.0 * 3600.0, 10.0);
        let kept = a.iter().filter(|p| b.contains(p)).count();
        assert!(kept < a.len() && b.iter().any(|p| !a.contains(p)), "{a:?} {b:?}");
    }

    #[test]
    fn sat_doppler_is_minus_range_derivative_over_lambda() {
        let c = Constellation::builtin();
        let ant = moscow();
        let lambda = l1_wavelength_m();
        let h = 0.01;
        for prn in c.visible(&ant, t0(), 0.0) {
            let l = c.line_of_sight(prn, &ant, t0()).unwrap();
            let rp = c.line_of_sight(prn, &ant, t0() + h).unwrap();
            let rm = c.line_of_sight(prn, &ant, t0() - h).unwrap();
            let doppler_num = -(rp.range_m - rm.range_m) / (2.0 * h) / lambda;
            assert!((doppler_num - l.doppler_hz).abs() < 0.1, "PRN {prn}: {doppler_num} vs {}", l.doppler_hz);
            let rate_num = (rp.doppler_hz - rm.doppler_hz) / (2.0 * h);
            assert!((rate_num - l.doppler_rate_hz_per_s).abs() < 1e-4, "PRN {prn}: {rate_num} vs {l:?}");
            let accel_num = (rp.range_rate_mps - rm.range_rate_mps) / (2.0 * h);
            assert!((accel_num - l.range_accel_mps2).abs() < 1e-5);
        }
    }

    #[test]
    fn sat_received_signal_matches_an_inertial_frame_solution() {
        // The same pseudorange solved independently: in an inertial frame that turns with the
        // Earth's angle Ω̇ₑ·t, the antenna at the receive instant and the satellite at the
        // transmit instant, τ found by bisection of |p(t − τ) − a| − cτ; the relativistic term
        // F·e·√A·sin E from the orbit's own eccentric anomaly (IS-GPS-200 §20.3.3.3.3.1).
        let c = Constellation::builtin();
        let site = Site::new(&moscow());
        let light = SPEED_OF_LIGHT_MPS;
        let to_inertial = |p: [f64; 3], t: f64| {
            let (s, co) = (EARTH_ROTATION_RADPS * t).sin_cos();
            [co * p[0] - s * p[1], s * p[0] + co * p[1], p[2]]
        };
        let dist =
            |a: [f64; 3], b: [f64; 3]| ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt();
        let mut largest_sagnac_m: f64 = 0.0;
        for prn in c.visible(&moscow(), t0(), 0.0) {
            let sat = c.get(prn).unwrap();
            for dt in [0.0, 600.0, 3000.0] {
                let t = t0() + dt;
                let r = sat.received_at(&site.ecef_m, t);
                let ant = to_inertial(site.ecef_m, t);
                let f = |tau: f64| dist(to_inertial(sat.state_ecef(t - tau).pos_m, t - tau), ant) - light * tau;
                let (mut lo, mut hi) = (0.05, 0.1);
                assert!(f(lo) > 0.0 && f(hi) < 0.0);
                for _ in 0..80 {
                    let mid = 0.5 * (lo + hi);
                    if f(mid) > 0.0 { lo = mid } else { hi = mid }
                }
                let tau = 0.5 * (lo + hi);
                assert!(((r.light_time_s - tau) * light).abs() < 1e-3, "PRN {prn}: τ {} vs {tau}", r.light_time_s);
                // F·e·√A·sin E at the transmit instant.
                let n = sat.mean_motion_radps();
                let m = sat.mean_anomaly_rad + n * (t - tau - sat.toa_gps_s());
                let mut e_anom = m;
                for _ in 0..40 {
                    e_anom = m + sat.eccentricity * e_anom.sin();
                }
                let rel = -4.442_807_633e-10 * sat.eccentricity * sat.sqrt_a_sqrtm * e_anom.sin();
                assert!(((r.relativistic_s - rel) * light).abs() < 1e-4, "PRN {prn}: {} vs {rel}", r.relativistic_s);
                assert!((r.pseudorange_m - light * (tau - rel)).abs() < 1e-3);
                // RTKLIB's linearized Sagnac term (geodist): the same range to a mm.
                let p = sat.state_ecef(t - tau).pos_m;
                let a = site.ecef_m;
                let rtklib = dist(p, a) + EARTH_ROTATION_RADPS * (p[0] * a[1] - p[1] * a[0]) / light;
                assert!((rtklib - light * tau).abs() < 1e-3, "PRN {prn}: {rtklib} vs {}", light * tau);
                largest_sagnac_m = largest_sagnac_m.max((dist(p, a) - light * tau).abs());
                // The rate: a central difference of ρ over ±2 s (the third derivative's part is
                // ~1e-5 m/s; GPS seconds near 1.4e9 s resolve 2.4e-7 s, ~1e-4 m of range).
                let h = 2.0;
                let num = (sat.received_at(&site.ecef_m, t + h).pseudorange_m
                    - sat.received_at(&site.ecef_m, t - h).pseudorange_m)
                    / (2.0 * h);
                assert!((num - r.pseudorange_rate_mps).abs() < 2e-4, "PRN {prn}: {num} vs {}", r.pseudorange_rate_mps);
                // What the light time and Earth rotation change: tens of metres against the
                // geometric range at the receive instant.
                let geometric = c.line_of_sight(prn, &moscow(), t).unwrap();
                let los = sat.received_line_of_sight(&site, t);
                assert_eq!((los.range_m, los.elevation_deg), (r.pseudorange_m, geometric.elevation_deg));
                assert!((los.range_m - geometric.range_m).abs() < 200.0);
            }
        }
        assert!((5.0..50.0).contains(&largest_sagnac_m), "{largest_sagnac_m}");
    }

    #[test]
    fn sat_overhead_elevation_and_azimuth() {
        let c = Constellation::builtin();
        let st = c.state_ecef(7, t0()).unwrap();
        let sub = Geodetic::from_ecef_m(st.pos_m);
        let ant = Geodetic::new(sub.lat_deg, sub.lon_deg, 0.0);
        let l = c.line_of_sight(7, &ant, t0()).unwrap();
        assert!(l.elevation_deg > 89.999, "{l:?}");
        assert!((l.range_m - sub.height_m).abs() < 1e-3, "{l:?} {sub:?}");
        // Same satellite from 10° further south: it is to the north-ish, lower.
        let south = Geodetic::new(sub.lat_deg - 10.0, sub.lon_deg, 0.0);
        let l = c.line_of_sight(7, &south, t0()).unwrap();
        assert!(l.elevation_deg < 80.0 && l.elevation_deg > 50.0, "{l:?}");
        assert!(l.azimuth_deg < 1.0 || l.azimuth_deg > 359.0, "{l:?}");
    }

    #[test]
    fn sat_cn0_model() {
        let m = Cn0Model::default();
        assert!(m.validate().is_ok());
        assert!((m.nominal_cn0_dbhz(90.0) - 47.0).abs() < 1e-12);
        assert!((m.nominal_cn0_dbhz(0.0) - 35.0).abs() < 1e-12);
        assert!((m.nominal_cn0_dbhz(-5.0) - 35.0).abs() < 1e-12);
        assert!(m.nominal_cn0_dbhz(10.0) < m.nominal_cn0_dbhz(30.0));
        let a = m.draw_offsets(&mut seeded(3));
        let b = m.draw_offsets(&mut seeded(3));
        assert_eq!(a, b);
        let offs: Vec<f64> = (1..=32).map(|p| a.offset_db(p)).collect();
        assert!(offs.iter().any(|o| o.abs() > 0.1) && offs.iter().all(|o| o.abs() < 5.0));
        assert!((a.cn0_dbhz(5, 90.0) - 47.0 - a.offset_db(5)).abs() < 1e-12);
        let bad = Cn0Model { elevation_exponent: 0.0, ..Cn0Model::default() };
        assert_eq!(bad.validate().unwrap_err().key(), Some("cn0.elevation_exponent"));
        let parsed: Cn0Model = toml::from_str("zenith_cn0_dbhz = 45.0").unwrap();
        assert_eq!(parsed.horizon_cn0_dbhz, 35.0);
        assert!(toml::from_str::<Cn0Model>("zenith = 45.0").is_err());
    }

    #[test]
    fn sat_yuma_parser_resolves_week_and_rejects_garbage() {
        let c = Constellation::from_yuma(BUILTIN_YUMA, 2290).unwrap();
        assert!(c.satellites().iter().all(|s| s.week == 2300));
        let c = Constellation::from_yuma(BUILTIN_YUMA, 2300 + 500).unwrap();
        assert!(c.satellites().iter().all(|s| s.week == 2300));
        assert!(matches!(
            Constellation::from_yuma("ID: x1\n", 2300),
            Err(AlmanacError::BadNumber { line: 1, ref text, .. }) if text == "x1"
        ));
        assert_eq!(Constellation::from_yuma("", 2300), Err(AlmanacError::Empty));
        assert_eq!(
            Constellation::from_yuma("# header\n****\nID: 1\nHealth: 0\n", 2300),
            Err(AlmanacError::MissingField { line: 3, field: "week" })
        );
        assert!(Constellation::builtin().get(20).is_none());
        let c = Constellation::builtin();
        let a = c.line_of_sight(1, &moscow(), t0()).unwrap();
        assert_eq!(Some(a), c.line_of_sight_from_site(1, &Site::new(&moscow()), t0()));
    }
}
