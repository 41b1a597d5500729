//! The scenario of a simulated calibration session: a TOML file.
//!
//! Every section and key is optional; what is missing takes the default, and
//! the defaults reproduce the paper's experiment (docs/conventions.md): an OCXO with
//! Γ = \[+0.09, +0.08, −0.08\] Hz/(m/s²) at GPS L1, a 2nd-order PLL with
//! Bn = 3 Hz and ζ = 1/√2 updated every 1 ms, logs at 40 Hz, a fixed antenna in
//! Moscow with the satellites of the built-in almanac in view, the board
//! shaken by hand along x, then y, then z with a 1.1 s period and rests
//! between axes. [`Scenario::default_toml`] is that default as a commented
//! TOML file (what `gsens scenario` prints).
//!
//! Unknown keys are errors (`deny_unknown_fields` everywhere; toml's message
//! names the key and its line), and so are out-of-range values
//! ([`Scenario::validate`]: the message names the key path, e.g.
//! `loop.bn_hz must be > 0 (got -1)`, and the error, a [`ConfigError`],
//! carries the key, the value and the allowed range).

use core::f64::consts::FRAC_1_SQRT_2;

/// What a log row holds, re-exported for scenarios' `log.phase`.
pub use gsens_core::LoggedPhase;
use gsens_core::units::{GPS_L1_HZ, L1CA_CODE_PERIOD_S};
use gsens_core::{LoopFilterCoeffs, LoopSpec};
use serde::{Deserialize, Serialize};

use crate::channel::{DATA_BIT_S, Discriminator};
use crate::error::{ConfigError, UtcError};
use crate::imu::{ImuConfig, ImuPreset};
use crate::motion::MotionConfig;
use crate::oscillator::OscillatorConfig;
use crate::satellites::{Cn0Model, Geodetic, gps_seconds_from_utc};

/// The embedded default scenario, with comments (see [`Scenario::default_toml`]).
const DEFAULT_TOML: &str = include_str!("default_scenario.toml");

/// Errors reading or checking a scenario.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ScenarioError {
    /// The TOML does not parse or has an unknown key / a value of the wrong
    /// type (toml's message, which names the key and the line; its
    /// [`span`](toml::de::Error::span) locates it in the text).
    #[error("invalid scenario: {}", .0.to_string().trim_end())]
    Parse(toml::de::Error),
    /// A value out of range or inconsistent with another; the error names
    /// the key path ([`ConfigError::key`]).
    #[error("invalid scenario: {0}")]
    Invalid(ConfigError),
}

impl From<ConfigError> for ScenarioError {
    fn from(e: ConfigError) -> Self {
        ScenarioError::Invalid(e)
    }
}

/// A complete scenario (see the module docs and `default_scenario.toml`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scenario {
    /// `[session]`: start time and duration.
    #[serde(default)]
    pub session: SessionSection,
    /// `[antenna]`: the fixed antenna's WGS-84 position.
    #[serde(default = "default_antenna")]
    pub antenna: Geodetic,
    /// `[oscillator]`: noise, g-sensitivity, carrier.
    #[serde(default)]
    pub oscillator: OscillatorSection,
    /// `[loop]`: the receiver's carrier loops.
    #[serde(default, rename = "loop")]
    pub tracking_loop: LoopSection,
    /// `[log]`: what the receiver logs and how often.
    #[serde(default)]
    pub log: LogSection,
    /// `[imu]`: the accelerometer triad.
    #[serde(default)]
    pub imu: ImuSection,
    /// `[motion]`: the hand motion, `[[motion.segments]]`.
    #[serde(default)]
    pub motion: MotionConfig,
    /// `[satellites]`: mask, channels, C/N0 model.
    #[serde(default)]
    pub satellites: SatellitesSection,
    /// `[compensation]`: Γ̂ fed forward into the carrier NCOs (absent: none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub compensation: Option<crate::compensation::CompensationSection>,
}

impl Default for Scenario {
    fn default() -> Self {
        Scenario {
            session: SessionSection::default(),
            antenna: default_antenna(),
            oscillator: OscillatorSection::default(),
            tracking_loop: LoopSection::default(),
            log: LogSection::default(),
            imu: ImuSection::default(),
            motion: MotionConfig::paper_default(),
            satellites: SatellitesSection::default(),
            compensation: None,
        }
    }
}

/// The default antenna: Moscow (55.75° N, 37.60° E, 200 m), where the seed
/// paper's authors work.
pub fn default_antenna() -> Geodetic {
    Geodetic::new(55.75, 37.60, 200.0)
}

/// `[session]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SessionSection {
    /// Start of the session, UTC, `YYYY-MM-DDTHH:MM:SS[.sss]Z` (GPS − UTC is
    /// taken as 18 s). Default 2024-02-08T12:00:00Z, within a day of the
    /// built-in almanac's epoch.
    pub start_utc: String,
    /// Duration \[s\]; absent: the motion's total duration.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub duration_s: Option<f64>,
}

impl Default for SessionSection {
    fn default() -> Self {
        SessionSection { start_utc: "2024-02-08T12:00:00Z".into(), duration_s: None }
    }
}

/// Oscillator noise presets; see [`OscillatorConfig`]'s constructors.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum OscillatorKind {
    /// [`OscillatorConfig::ocxo`] (the paper's oscillator class).
    Ocxo,
    /// [`OscillatorConfig::tcxo`].
    Tcxo,
    /// [`OscillatorConfig::tcxo_low_quality`].
    TcxoLowQuality,
    /// [`OscillatorConfig::ideal`]: no noise at all (only aᵀΓ).
    Ideal,
}

impl OscillatorKind {
    /// The preset's name in a scenario file, e.g. `tcxo`.
    pub fn name(&self) -> &'static str {
        match self {
            OscillatorKind::Ocxo => "ocxo",
            OscillatorKind::Tcxo => "tcxo",
            OscillatorKind::TcxoLowQuality => "tcxo_low_quality",
            OscillatorKind::Ideal => "ideal",
        }
    }

    /// The preset in words, e.g. `OCXO preset`.
    pub fn description(&self) -> &'static str {
        match self {
            OscillatorKind::Ocxo => "OCXO preset",
            OscillatorKind::Tcxo => "TCXO preset",
            OscillatorKind::TcxoLowQuality => "low-quality TCXO preset",
            OscillatorKind::Ideal => "ideal preset with noise overrides",
        }
    }
}

/// `[oscillator]`: a noise preset, optional overrides of its parameters, the
/// g-sensitivity and the carrier.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct OscillatorSection {
    /// Noise preset (`"ocxo"`, `"tcxo"`, `"tcxo_low_quality"`, `"ideal"`).
    pub preset: OscillatorKind,
    /// Override of h₀ \[s\] (white FM).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub h0: Option<f64>,
    /// Override of h₋₁ \[-\] (flicker FM).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub h_neg1: Option<f64>,
    /// Override of h₋₂ \[Hz\] (random-walk FM).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub h_neg2: Option<f64>,
    /// Override of h₂ \[s³\] (white PM).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub h2: Option<f64>,
    /// Override of the constant fractional frequency offset \[-\].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub offset_frac: Option<f64>,
    /// Override of the linear drift \[1/s\].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub drift_frac_per_s: Option<f64>,
    /// Override of the temperature-cycle amplitude \[-\].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub temp_cycle_amplitude_frac: Option<f64>,
    /// Override of the temperature-cycle period \[s\].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub temp_cycle_period_s: Option<f64>,
    /// Override of the temperature-cycle phase \[rad\].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub temp_cycle_phase_rad: Option<f64>,
    /// Override of the flicker synthesis low cutoff \[Hz\].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub flicker_low_cutoff_hz: Option<f64>,
    /// The g-sensitivity Γ \[Hz/(m/s²)\] at the carrier (docs/conventions.md):
    /// Δf = aᵀΓ is added to every NCO. Default: the paper's calibrated OCXO.
    pub gamma_hz_per_mps2: [f64; 3],
    /// Tracked carrier frequency \[Hz\] (default GPS L1, 1 575.42 MHz).
    pub carrier_hz: f64,
}

impl Default for OscillatorSection {
    fn default() -> Self {
        OscillatorSection {
            preset: OscillatorKind::Ocxo,
            h0: None,
            h_neg1: None,
            h_neg2: None,
            h2: None,
            offset_frac: None,
            drift_frac_per_s: None,
            temp_cycle_amplitude_frac: None,
            temp_cycle_period_s: None,
            temp_cycle_phase_rad: None,
            flicker_low_cutoff_hz: None,
            gamma_hz_per_mps2: [0.09, 0.08, -0.08],
            carrier_hz: GPS_L1_HZ,
        }
    }
}

impl OscillatorSection {
    /// The noise model: the preset with the overrides applied.
    pub fn config(&self) -> OscillatorConfig {
        let mut c = match self.preset {
            OscillatorKind::Ocxo => OscillatorConfig::ocxo(),
            OscillatorKind::Tcxo => OscillatorConfig::tcxo(),
            OscillatorKind::TcxoLowQuality => OscillatorConfig::tcxo_low_quality(),
            OscillatorKind::Ideal => OscillatorConfig::ideal(),
        };
        let set = |dst: &mut f64, v: Option<f64>| {
            if let Some(v) = v {
                *dst = v;
            }
        };
        set(&mut c.h0, self.h0);
        set(&mut c.h_neg1, self.h_neg1);
        set(&mut c.h_neg2, self.h_neg2);
        set(&mut c.h2, self.h2);
        set(&mut c.offset_frac, self.offset_frac);
        set(&mut c.drift_frac_per_s, self.drift_frac_per_s);
        set(&mut c.temp_cycle_amplitude_frac, self.temp_cycle_amplitude_frac);
        set(&mut c.temp_cycle_period_s, self.temp_cycle_period_s);
        set(&mut c.temp_cycle_phase_rad, self.temp_cycle_phase_rad);
        set(&mut c.flicker_low_cutoff_hz, self.flicker_low_cutoff_hz);
        c
    }
}

/// `[loop]`: the carrier loops (all channels alike).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LoopSection {
    /// Loop order, 2 or 3.
    pub order: u8,
    /// One-sided noise bandwidth Bn \[Hz\].
    pub bn_hz: f64,
    /// Damping ratio ζ (order 2).
    pub zeta: f64,
    /// a3 of F(s) = b3·ωn + a3·ωn²/s + ωn³/s² (order 3; Kaplan: 1.1).
    pub a3: f64,
    /// b3 (order 3; Kaplan: 2.4).
    pub b3: f64,
    /// Loop update interval = coherent integration time T \[s\]; 20 ms (a data
    /// bit) must be a whole number of them: 1, 2, 4, 5, 10, 20 ms, …
    pub interval_s: f64,
    /// `"costas"` (atan(Q/I), data channel) or `"pilot"` (atan2(Q, I)).
    pub discriminator: Discriminator,
    /// Aid the NCO with the satellite Doppler predicted from the orbit model
    /// (the antenna is fixed and known), so the loop only tracks the
    /// oscillator; otherwise the loop also tracks the Doppler and its rate.
    pub doppler_aiding: bool,
    /// σ of the frequency error \[Hz\] the loop starts with (what acquisition /
    /// FLL pull-in hands over); the initial phase error is uniform in (−π, π].
    pub initial_freq_err_hz: f64,
    /// Lock indicator threshold on the filtered cos 2φ estimate, in (0, 1).
    pub lock_threshold: f64,
    /// Lock indicator low-pass time constant \[s\].
    pub lock_tau_s: f64,
}

impl Default for LoopSection {
    fn default() -> Self {
        LoopSection {
            order: 2,
            bn_hz: 3.0,
            zeta: FRAC_1_SQRT_2,
            a3: gsens_core::KAPLAN_A3,
            b3: gsens_core::KAPLAN_B3,
            interval_s: 0.001,
            discriminator: Discriminator::Costas,
            doppler_aiding: false,
            initial_freq_err_hz: 0.2,
            lock_threshold: 0.5,
            lock_tau_s: 0.2,
        }
    }
}

impl LoopSection {
    /// The loop specification for the core ([`LoopSpec::of_order`]); validation
    /// refuses orders other than 2 and 3, an unvalidated one keeps the 2nd
    /// order's shape.
    pub fn spec(&self) -> LoopSpec {
        LoopSpec::of_order(self.order, self.bn_hz, self.zeta, self.a3, self.b3)
            .unwrap_or(LoopSpec::SecondOrder { bn_hz: self.bn_hz, zeta: self.zeta })
    }

    /// The loop-filter coefficients (after validation they exist).
    pub fn coeffs(&self) -> Result<LoopFilterCoeffs, ScenarioError> {
        Ok(self.spec().coeffs().map_err(ConfigError::Loop)?)
    }
}

/// Which C/N0 the tracking log reports.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Cn0Logged {
    /// The receiver's estimate (moments method over 1 s of 20 ms sums).
    Estimated,
    /// The simulator's true value.
    True,
}

/// `[log]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LogSection {
    /// Tracking log interval \[s\], a whole number of loop intervals (0.025 = 40 Hz).
    pub interval_s: f64,
    /// `"last"` or `"mean"` discriminator output (see `gsens_core::LoggedPhase`);
    /// rows are time-stamped at the centre of the latest integration.
    pub phase: LoggedPhase,
    /// `"estimated"` or `"true"` C/N0 in the rows.
    pub cn0: Cn0Logged,
    /// Leave out rows of channels whose lock indicator reads unlocked (as
    /// receivers do); the rows always carry the lock state for callers.
    pub drop_unlocked: bool,
    /// Log where each loop put its replica: the columns `nco_phase_cycles`
    /// (at the end of the latest integration) and `nco_freq_hz` (commanded
    /// during it) of `tracking.csv` (default on: the log then gives both the
    /// loop-free estimate and the one through the loop model; off for a
    /// receiver that logs the tracking error only, as the seed paper's).
    pub nco: bool,
}

impl Default for LogSection {
    fn default() -> Self {
        LogSection {
            interval_s: 0.025,
            phase: LoggedPhase::Mean,
            cn0: Cn0Logged::Estimated,
            drop_unlocked: true,
            nco: true,
        }
    }
}

/// `[imu]`: a preset and optional overrides of its parameters.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ImuSection {
    /// Preset (`"ideal"`, `"consumer_mems"`, `"industrial"`, `"tactical"`);
    /// default `"industrial"`, the class of a survey GNSS/IMU receiver such as
    /// the paper's Topcon AGI-4.
    pub preset: ImuPreset,
    /// Output rate \[Hz\] (default 40 Hz, the paper's log rate).
    pub rate_hz: f64,
    /// IMU time stamp minus true time \[s\].
    pub time_offset_s: f64,
    /// Override of the velocity random walk \[(m/s²)/√Hz\].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub vrw_mps2_per_rthz: Option<f64>,
    /// Override of the bias σ \[m/s²\].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bias_sigma_mps2: Option<f64>,
    /// Override of the scale-factor σ \[ppm\].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub scale_factor_sigma_ppm: Option<f64>,
    /// Override of the misalignment σ \[rad\].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub misalignment_sigma_rad: Option<f64>,
    /// Override of the quantization step \[m/s²\].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub quantization_mps2: Option<f64>,
}

impl Default for ImuSection {
    fn default() -> Self {
        ImuSection {
            preset: ImuPreset::Industrial,
            rate_hz: 40.0,
            time_offset_s: 0.0,
            vrw_mps2_per_rthz: None,
            bias_sigma_mps2: None,
            scale_factor_sigma_ppm: None,
            misalignment_sigma_rad: None,
            quantization_mps2: None,
        }
    }
}

impl ImuSection {
    /// The IMU configuration: the preset with rate, offset and overrides applied.
    pub fn config(&self) -> ImuConfig {
        let mut c = self.preset.config();
        c.rate_hz = self.rate_hz;
        c.time_offset_s = self.time_offset_s;
        let set = |dst: &mut f64, v: Option<f64>| {
            if let Some(v) = v {
                *dst = v;
            }
        };
        set(&mut c.vrw_mps2_per_rthz, self.vrw_mps2_per_rthz);
        set(&mut c.bias_sigma_mps2, self.bias_sigma_mps2);
        set(&mut c.scale_factor_sigma_ppm, self.scale_factor_sigma_ppm);
        set(&mut c.misalignment_sigma_rad, self.misalignment_sigma_rad);
        set(&mut c.quantization_mps2, self.quantization_mps2);
        c
    }
}

/// `[satellites]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SatellitesSection {
    /// Elevation mask \[deg\]: channels start when a satellite rises above it
    /// and stop when it sets below it.
    pub elevation_mask_deg: f64,
    /// Number of tracking channels; the highest satellites get them first.
    pub max_channels: u32,
    /// `[satellites.cn0]`: C/N0 versus elevation.
    pub cn0: Cn0Model,
    /// The signal each channel tracks, as [`gsens_io::Signal::label`]s
    /// (`L1CA`, `L5Q`, `B1I`, `E1C`, `G1:+3` for GLONASS G1 on frequency
    /// channel k = +3, …): channel c tracks `signals[c mod len]`. Empty (the
    /// default): every channel on `oscillator.carrier_hz`, and `tracking.csv`
    /// has no carrier columns. A channel on f_c sees Δf_c = f_c·y, y the
    /// oscillator's fractional frequency (noise plus aᵀΓ/`oscillator.carrier_hz`),
    /// and the Doppler of its satellite at f_c; its thermal noise follows its
    /// own C/N0 as on L1. The satellites keep the GPS almanac's orbits and PRNs
    /// whatever the signal (the geometry only sets Doppler and elevation).
    /// Requires `oscillator.carrier_hz` = GPS L1, the carrier the estimate
    /// reports Γ at.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub signals: Vec<String>,
}

impl Default for SatellitesSection {
    fn default() -> Self {
        SatellitesSection { elevation_mask_deg: 10.0, max_channels: 12, cn0: Cn0Model::default(), signals: Vec::new() }
    }
}

impl SatellitesSection {
    /// The carrier of channel `channel`: its signal's from [`Self::signals`],
    /// or `carrier_hz` (unnamed) when the list is empty. Panics on a name
    /// that [`Scenario::validate`] refuses.
    pub fn carrier_of(&self, channel: u32, carrier_hz: f64) -> gsens_io::Carrier {
        if self.signals.is_empty() {
            return gsens_io::Carrier { carrier_hz, signal: None };
        }
        let label = &self.signals[channel as usize % self.signals.len()];
        gsens_io::Carrier::of(gsens_io::Signal::from_label(label).expect("validated signal"))
    }
}

/// Parses `YYYY-MM-DDTHH:MM:SS[.fff][Z]` (UTC; a space may replace the `T`)
/// into GPS seconds.
pub fn parse_utc_to_gps_s(s: &str) -> Result<f64, UtcError> {
    let malformed = || UtcError::Malformed { input: s.to_owned() };
    let t = s.trim().trim_end_matches('Z');
    let (date, time) = t.split_once(['T', ' ']).ok_or_else(malformed)?;
    let d: Vec<&str> = date.split('-').collect();
    let h: Vec<&str> = time.split(':').collect();
    if d.len() != 3 || h.len() != 3 {
        return Err(malformed());
    }
    let year: i32 = d[0].parse().map_err(|_| malformed())?;
    let month: u32 = d[1].parse().map_err(|_| malformed())?;
    let day: u32 = d[2].parse().map_err(|_| malformed())?;
    let hour: u32 = h[0].parse().map_err(|_| malformed())?;
    let minute: u32 = h[1].parse().map_err(|_| malformed())?;
    let second: f64 = h[2].parse().map_err(|_| malformed())?;
    let fields = [
        ("year", (1980..=2200).contains(&year)),
        ("month", (1..=12).contains(&month)),
        ("day", (1..=days_in_month(year, month)).contains(&day)),
        ("hour", hour < 24),
        ("minute", minute < 60),
        ("second", (0.0..61.0).contains(&second)),
    ];
    if let Some(&(field, _)) = fields.iter().find(|(_, ok)| !ok) {
        return Err(UtcError::OutOfRange { input: s.to_owned(), field });
    }
    Ok(gps_seconds_from_utc(year, month, day, hour, minute, second))
}

/// Days in `month` (1–12) of `year` in the Gregorian calendar (0 for a
/// month out of range): February has 29 in years divisible by 4, except
/// centuries not divisible by 400.
fn days_in_month(year: i32, month: u32) -> u32 {
    let leap = (year % 4 == 0 && year % 100 != 0) || year % 400 == 0;
    match month {
        1 | 3 | 5 | 7 | 8 | 10 | 12 => 31,
        4 | 6 | 9 | 11 => 30,
        2 if leap => 29,
        2 => 28,
        _ => 0,
    }
}

/// `Ok` if `ok`, else the error `err` makes.
fn check(ok: bool, err: impl FnOnce() -> ConfigError) -> Result<(), ConfigError> {
    if ok { Ok(()) } else { Err(err()) }
}

/// Each component of a Γ at `key` finite and within ±100 Hz/(m/s²) (far
/// beyond any crystal's: such a value is a typo or a unit mix-up).
fn gamma_in_range(key: &str, gamma: &[f64; 3]) -> Result<(), ConfigError> {
    for (i, g) in gamma.iter().enumerate() {
        range(g.is_finite() && g.abs() <= 100.0, &format!("{key}[{i}]"), *g, "finite and within ±100 Hz/(m/s²)")?;
    }
    Ok(())
}

/// `Ok` if `ok`, else [`ConfigError::OutOfRange`] of `key`.
fn range(ok: bool, key: &str, value: f64, allowed: &str) -> Result<(), ConfigError> {
    check(ok, || ConfigError::out_of_range(key, value, allowed))
}

impl Scenario {
    /// The embedded default scenario as commented TOML (parses to
    /// [`Scenario::default`]).
    pub fn default_toml() -> &'static str {
        DEFAULT_TOML
    }

    /// Parses and validates a scenario.
    pub fn from_toml_str(s: &str) -> Result<Scenario, ScenarioError> {
        let sc: Scenario = toml::from_str(s).map_err(ScenarioError::Parse)?;
        sc.validate()?;
        Ok(sc)
    }

    /// The scenario as TOML (without comments).
    pub fn to_toml_string(&self) -> String {
        toml::to_string(self).unwrap_or_default()
    }

    /// GPS seconds at t = 0.
    pub fn start_gps_s(&self) -> Result<f64, ScenarioError> {
        Ok(self.start_gps_s_checked()?)
    }

    fn start_gps_s_checked(&self) -> Result<f64, ConfigError> {
        parse_utc_to_gps_s(&self.session.start_utc)
            .map_err(|error| ConfigError::Time { key: "session.start_utc".into(), error })
    }

    /// The session's duration \[s\]: `session.duration_s` or the motion's.
    pub fn duration_s(&self) -> f64 {
        self.session.duration_s.unwrap_or_else(|| self.motion.duration_s())
    }

    /// Loop updates per log row, round(log.interval_s / loop.interval_s).
    pub fn integrations_per_row(&self) -> u32 {
        (self.log.interval_s / self.tracking_loop.interval_s).round().max(1.0) as u32
    }

    /// Checks every value; the error names the key path.
    pub fn validate(&self) -> Result<(), ScenarioError> {
        Ok(self.validate_values()?)
    }

    /// Every section's values, in the order of the file; the first error found.
    fn validate_values(&self) -> Result<(), ConfigError> {
        self.validate_session()?;
        self.antenna.validate().map_err(|e| e.under("antenna"))?;
        self.validate_oscillator()?;
        self.validate_loop()?;
        self.validate_log()?;
        self.imu.config().validate()?;
        self.motion.validate()?;
        self.validate_satellites()?;
        self.validate_compensation()
    }

    /// `[session]`: the start and a duration in (0, 1e6\] s.
    fn validate_session(&self) -> Result<(), ConfigError> {
        self.start_gps_s_checked()?;
        if let Some(d) = self.session.duration_s {
            range(d.is_finite() && d > 0.0 && d <= 1e6, "session.duration_s", d, "in (0, 1e6] s")?;
        }
        check(self.duration_s() > 0.0, || ConfigError::EmptySession)?;
        Ok(())
    }

    /// `[oscillator]`: its noise model, Γ and a carrier within \[1e8, 1e11\] Hz.
    fn validate_oscillator(&self) -> Result<(), ConfigError> {
        let o = &self.oscillator;
        self.oscillator.config().validate()?;
        gamma_in_range("oscillator.gamma_hz_per_mps2", &o.gamma_hz_per_mps2)?;
        let c = o.carrier_hz;
        range(c.is_finite() && (1e8..=1e11).contains(&c), "oscillator.carrier_hz", c, "within [1e8, 1e11] Hz")?;
        Ok(())
    }

    /// `[loop]`: order, bandwidth and shape, an interval of whole code periods
    /// in a data bit at which the discrete loop is stable, the initial
    /// frequency error and the lock detector.
    fn validate_loop(&self) -> Result<(), ConfigError> {
        let l = &self.tracking_loop;
        range(l.order == 2 || l.order == 3, "loop.order", f64::from(l.order), "2 or 3")?;
        range(l.bn_hz.is_finite() && l.bn_hz > 0.0, "loop.bn_hz", l.bn_hz, "> 0")?;
        // All three are checked whatever the order: a value the order does
        // not use is still a value the file states.
        range(l.zeta.is_finite() && l.zeta > 0.0, "loop.zeta", l.zeta, "> 0")?;
        range(l.a3.is_finite() && l.a3 > 0.0, "loop.a3", l.a3, "> 0")?;
        range(l.b3.is_finite() && l.b3 > 0.0, "loop.b3", l.b3, "> 0")?;
        if l.order == 3 {
            check(l.a3 * l.b3 > 1.0, || ConfigError::ThirdOrderUnstable { a3: l.a3, b3: l.b3 })?;
        }
        let t = l.interval_s;
        // A carrier loop on C/A code integrates at least one code period.
        let allowed = "in [0.001, 0.02] s (at least one 1 ms C/A code period, at most one 20 ms data bit)";
        let span = L1CA_CODE_PERIOD_S - 1e-12..=DATA_BIT_S + 1e-12;
        range(span.contains(&t), "loop.interval_s", t, allowed)?;
        let per_bit = DATA_BIT_S / t;
        check((per_bit - per_bit.round()).abs() < 1e-6 * per_bit, || ConfigError::LoopIntervalNotInDataBit {
            interval_s: t,
        })?;
        let coeffs = l.spec().coeffs().map_err(ConfigError::Loop)?;
        // coeffs() checked the continuous loop (Routh–Hurwitz); the discrete
        // loop at this interval is checked by its poles.
        check(coeffs.is_stable_at(t), || ConfigError::DiscreteLoopUnstable { bn_hz: l.bn_hz, interval_s: t })?;
        let f = l.initial_freq_err_hz;
        // Beyond ±1/(2T) the loop's phase steps alias: no loop updated every T can pull it in.
        let f_max = 0.5 / t;
        let allowed = format!("within [0, {f_max}] Hz (1/(2·loop.interval_s): a larger error aliases in the loop)");
        range(f.is_finite() && (0.0..=f_max).contains(&f), "loop.initial_freq_err_hz", f, &allowed)?;
        let th = l.lock_threshold;
        range(th > 0.0 && th < 1.0, "loop.lock_threshold", th, "in (0, 1)")?;
        range(l.lock_tau_s.is_finite() && l.lock_tau_s > 0.0, "loop.lock_tau_s", l.lock_tau_s, "> 0")?;
        Ok(())
    }

    /// `[log]`: an interval in (0, 10\] s, a whole number of loop intervals.
    fn validate_log(&self) -> Result<(), ConfigError> {
        let t = self.tracking_loop.interval_s;
        let li = self.log.interval_s;
        range(li.is_finite() && li > 0.0 && li <= 10.0, "log.interval_s", li, "in (0, 10] s")?;
        let r = li / t;
        check(r.round() >= 1.0 && (r - r.round()).abs() < 1e-6 * r, || ConfigError::LogIntervalNotMultiple {
            log_interval_s: li,
            loop_interval_s: t,
        })?;
        Ok(())
    }

    /// `[satellites]`: the mask, the channels, the C/N0 model and the named
    /// signals (at L1's carrier, at most one per channel).
    fn validate_satellites(&self) -> Result<(), ConfigError> {
        let o = &self.oscillator;
        let s = &self.satellites;
        let m = s.elevation_mask_deg;
        range(m.is_finite() && (-5.0..=80.0).contains(&m), "satellites.elevation_mask_deg", m, "within [-5, 80]")?;
        let n = s.max_channels;
        range((1..=64).contains(&n), "satellites.max_channels", f64::from(n), "within [1, 64]")?;
        s.cn0.validate().map_err(|e| e.under("satellites"))?;
        for (i, label) in s.signals.iter().enumerate() {
            let key = format!("satellites.signals[{i}]");
            let signal = gsens_io::Signal::from_label(label).map_err(|e| ConfigError::Signal {
                key: key.clone(),
                message: format!("{e} (a GLONASS FDMA signal is written with its k, e.g. G1:+3)"),
            })?;
            check(o.carrier_hz == gsens_core::units::GPS_L1_HZ, || ConfigError::Signal {
                key: key.clone(),
                message: format!(
                    "channels on named signals ({}) need oscillator.carrier_hz = GPS L1 ({} Hz), the carrier Γ is \
                     given and estimated at (got {} Hz)",
                    signal.label(),
                    gsens_core::units::GPS_L1_HZ,
                    o.carrier_hz
                ),
            })?;
        }
        check(s.signals.len() <= s.max_channels as usize, || ConfigError::Signal {
            key: "satellites.signals".into(),
            message: format!("{} signals for {} channels (one per channel at most)", s.signals.len(), s.max_channels),
        })?;
        Ok(())
    }

    /// `[compensation]`, when given: Γ̂ in range and a latency within \[0, 10\] s.
    fn validate_compensation(&self) -> Result<(), ConfigError> {
        if let Some(c) = &self.compensation {
            gamma_in_range("compensation.gamma_hz_per_mps2", &c.gamma_hz_per_mps2)?;
            let l = c.latency_s;
            range(l.is_finite() && (0.0..=10.0).contains(&l), "compensation.latency_s", l, "within [0, 10] s")?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn embedded_default_parses_and_equals_the_programmatic_default() {
        let parsed = Scenario::from_toml_str(Scenario::default_toml()).unwrap();
        assert_eq!(parsed, Scenario::default());
        // And the serialized form round-trips.
        let again = Scenario::from_toml_str(&Scenario::default().to_toml_string()).unwrap();
        assert_eq!(again, Scenario::default());
    }

    #[test]
    fn empty_file_is_the_default() {
        assert_eq!(Scenario::from_toml_str("").unwrap(), Scenario::default());
    }

    #[test]
    fn unknown_keys_are_errors_naming_the_key() {
        for (toml, key) in [
            ("[loop]\nbn_hz = 3.0\nbandwidth = 2\n", "bandwidth"),
            ("foo = 1\n", "foo"),
            ("[oscillator]\ngama = [0.0, 0.0, 0.0]\n", "gama"),
            ("[satellites.cn0]\nzenith = 40\n", "zenith"),
            ("[[motion.segments]]\nkind = \"rest\"\nduration_s = 1\nperiod_s = 2\n", "period_s"),
            (
                "[[motion.segments]]\nkind = \"shake\"\naxis = \"x\"\nduration_s = 1\nperiod_s = 1\namplitude_mps2 = 1\namp = 2\n",
                "amp",
            ),
        ] {
            let e = Scenario::from_toml_str(toml).unwrap_err().to_string();
            assert!(e.contains(key), "{toml:?}: {e}");
        }
    }

    #[test]
    fn out_of_range_values_name_the_key() {
        for (toml, key) in [
            ("[loop]\nbn_hz = -1.0\n", "loop.bn_hz"),
            ("[loop]\norder = 4\n", "loop.order"),
            ("[loop]\ninterval_s = 0.003\n", "loop.interval_s"),
            ("[loop]\nbn_hz = 600.0\n", "loop.bn_hz"),
            ("[log]\ninterval_s = 0.0255\n", "log.interval_s"),
            ("[antenna]\nlat_deg = 95.0\nlon_deg = 0.0\n", "antenna.lat_deg"),
            ("[oscillator]\nh0 = -1.0\n", "oscillator.h0"),
            ("[oscillator]\ncarrier_hz = 5.0\n", "oscillator.carrier_hz"),
            ("[imu]\nrate_hz = 0.0\n", "imu.rate_hz"),
            ("[satellites]\nmax_channels = 0\n", "satellites.max_channels"),
            ("[satellites.cn0]\nzenith_cn0_dbhz = 99.0\n", "satellites.cn0.zenith_cn0_dbhz"),
            ("[session]\nstart_utc = \"yesterday\"\n", "session.start_utc"),
            // Found by fuzzing: each was accepted, or ran for minutes.
            ("[session]\nstart_utc = \"2024-02-30T12:00:00Z\"\n", "session.start_utc"),
            ("[session]\nstart_utc = \"2023-02-29T12:00:00Z\"\n", "session.start_utc"),
            ("[session]\nstart_utc = \"2024-04-31T12:00:00Z\"\n", "session.start_utc"),
            ("[loop]\ninterval_s = 1e-9\n", "loop.interval_s"),
            ("[loop]\ninterval_s = 0.0005\n", "loop.interval_s"),
            ("[loop]\na3 = nan\n", "loop.a3"),
            ("[loop]\nb3 = nan\n", "loop.b3"),
            ("[loop]\nzeta = nan\n", "loop.zeta"),
            ("[loop]\ninitial_freq_err_hz = 1e308\n", "loop.initial_freq_err_hz"),
            ("[loop]\ninitial_freq_err_hz = 501.0\n", "loop.initial_freq_err_hz"),
            (
                "[[motion.segments]]\nkind = \"shake\"\naxis = \"x\"\nduration_s = 1\nperiod_s = 1\namplitude_mps2 = -1\n",
                "motion.segments[0].amplitude_mps2",
            ),
        ] {
            let e = Scenario::from_toml_str(toml).unwrap_err().to_string();
            assert!(e.contains(key), "{toml:?}: {e}");
        }
    }

    #[test]
    fn signals_are_checked_and_assigned_per_channel() {
        for (toml, want) in [
            ("[satellites]\nsignals = [\"L1CA\", \"GPSL1\"]\n", "satellites.signals[1]: `GPSL1` is not a signal"),
            ("[satellites]\nsignals = [\"G1\"]\n", "satellites.signals[0]: G1 is a GLONASS FDMA signal"),
            ("[satellites]\nsignals = [\"G1:+9\"]\n", "outside the GLONASS frequency channels"),
            (
                "[oscillator]\ncarrier_hz = 1176.45e6\n[satellites]\nsignals = [\"L5Q\"]\n",
                "oscillator.carrier_hz = GPS L1",
            ),
            ("[satellites]\nmax_channels = 2\nsignals = [\"L1CA\", \"L5I\", \"B1I\"]\n", "3 signals for 2 channels"),
        ] {
            let e = Scenario::from_toml_str(toml).unwrap_err().to_string();
            assert!(e.contains(want), "{toml:?}: {e}");
        }
        let sc = Scenario::from_toml_str("[satellites]\nsignals = [\"L5Q\", \"G1:-3\"]\n").unwrap();
        let l1 = gsens_core::units::GPS_L1_HZ;
        assert_eq!(sc.satellites.carrier_of(2, l1).label(), "L5Q");
        assert_eq!(sc.satellites.carrier_of(3, l1).carrier_hz, 1_602e6 - 3.0 * 0.5625e6);
        // The default: every channel on the oscillator's carrier, unnamed; nothing new in its TOML.
        assert_eq!(Scenario::default().satellites.carrier_of(5, l1), gsens_io::Carrier::GPS_L1);
        assert!(!Scenario::default().to_toml_string().contains("signals"));
    }

    #[test]
    fn utc_parsing() {
        let a = parse_utc_to_gps_s("2024-02-08T12:00:00Z").unwrap();
        let b = parse_utc_to_gps_s("2024-02-08T12:00:01.5").unwrap();
        assert!((b - a - 1.5).abs() < 1e-9);
        // GPS week 2300 starts 2024-02-04 00:00:00 GPS = 2024-02-03T23:59:42 UTC.
        let w = parse_utc_to_gps_s("2024-02-03T23:59:42Z").unwrap();
        assert!((w - 2300.0 * 604_800.0).abs() < 1e-6);
        // Leap days: 2024 and 2000 have one, 1900 (not in range) and 2100 do not.
        assert!(parse_utc_to_gps_s("2024-02-29T00:00:00Z").is_ok());
        assert!(parse_utc_to_gps_s("2000-02-29T00:00:00Z").is_ok());
        assert!(parse_utc_to_gps_s("2100-02-29T00:00:00Z").is_err());
        let feb_end = parse_utc_to_gps_s("2024-02-29T00:00:00Z").unwrap();
        let mar_1 = parse_utc_to_gps_s("2024-03-01T00:00:00Z").unwrap();
        assert!((mar_1 - feb_end - 86_400.0).abs() < 1e-9);
    }
}
