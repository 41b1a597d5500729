//! IF sample generator: complex baseband GPS L1 C/A samples of the scenario's
//! satellites, as a front end with the scenario's oscillator would record them,
//! for software receivers such as GNSS-SDR.
//!
//! # Signal model
//!
//! Sample n is taken at receiver time τ = n/fs (the sample clock, like the
//! local oscillator, is derived from the crystal). Each satellite contributes
//!
//! ```text
//! s(τ) = A·d(τ)·c(τ)·e^{j2πθ(τ)},   A = σ·√(2·(C/N0)/fs)
//! ```
//!
//! with c the C/A code ([`ca_code`]), d the LNAV data ([`lnav`], valid
//! subframes with preamble, HOW, parity and the satellite's ephemeris), θ the baseband carrier phase
//! \[cycles\] and σ the thermal noise per I and Q component, so that the
//! carrier-to-noise density is C/N0 (complex noise of power 2σ² over fs).
//! The noise is white Gaussian, the sum is quantized to the output format
//! ([`IqFormat`]).
//!
//! Time advances in blocks of 1 ms of receiver time. During block b
//! (τ ∈ \[b·1ms, (b+1)·1ms)) the oscillator's fractional frequency error is
//! y_b = ȳ_b + a(τ_mid)ᵀΓ/f_L1 (the scenario's [`crate::oscillator::Oscillator`] noise averaged
//! over the block plus Filler's g-sensitivity at the block's centre, exactly
//! the Δf_b = f_L1·y_b of docs/conventions.md), and each satellite's Doppler f_D
//! is −ρ̇/λ at the block centre, ρ its pseudorange as received
//! ([`crate::satellites::ReceivedSignal`]: light time, Earth rotation and the
//! satellite clock's relativistic term; evaluated every second and
//! interpolated linearly, as in [`crate::session`]). The crystal drives the whole chain: the local
//! oscillator runs at f_L1·(1 + y) and the sample clock at fs·(1 + y), so per
//! second of receiver time the carrier and code advance by
//!
//! ```text
//! f_bb = (f_D − Δf)/(1 + y)          [cycles/s]   (docs/conventions.md: Δf adds to the NCO, i.e. subtracts from the signal)
//! r    = 1.023e6·(1 + f_D/f_L1)/(1 + y)   [chips/s]
//! ```
//!
//! Phases are continuous across blocks (accumulated in f64 at block
//! boundaries; within a block the carrier and code run on 32-bit fixed-point
//! accumulators, error < 1e-6 cycle per block). The code phase starts from the
//! pseudorange (the satellite clock's time t_sv = GPS time − ρ/c) and the data bits and
//! subframes follow it, so bit edges and subframe boundaries
//! are where a receiver expects them. The carrier phase starts uniform.
//!
//! # Orbits and ephemeris
//!
//! Each satellite sends the broadcast ephemeris ([`lnav::Ephemeris`]) of its
//! almanac orbit with t_oe the even hour (a multiple of 2 h, where the
//! control segment puts them) nearest the file's middle, and the file's
//! ranges follow that broadcast orbit (the almanac's quantized to the
//! message's scale factors, a few cm from it): a receiver that solves
//! for its position from the message finds the antenna's, to the noise
//! (no ionosphere or troposphere is simulated: switch a receiver's
//! corrections off). The pseudorange's light time, Earth rotation and
//! relativistic terms are what makes the fix: with the geometric range at
//! the receive instant in their place (up to 73 m from the pseudorange)
//! GNSS-SDR 0.0.17's RTKLIB solver refuses every epoch of
//! `scripts/gnss-sdr-rinex-e2e.sh`'s session (chi-square test: vv ≈ 200
//! against 16.3 for 10 observations).
//!
//! The motion and the satellite geometry are evaluated at receiver time (the
//! clock's time error, below a microsecond over a session, is neglected there).
//!
//! # Satellites
//!
//! The satellites above the elevation mask at the start, highest first, at
//! most `max_satellites` (PRN 1–32: those with a C/A code); they are kept for
//! the whole file. C/N0 follows the scenario's elevation model, updated every
//! second.
//!
//! # Reproducibility
//!
//! The oscillator, motion, IMU errors and noise and C/N0 offsets use the same
//! random streams as [`crate::session::simulate`] (so a session simulated with
//! a 1 ms loop interval and the same seed has the same oscillator, motion and
//! IMU log); the thermal noise and the carrier phases have their own streams.

pub mod ca_code;
pub mod lnav;

use statrs::distribution::{ContinuousCDF, Normal};
use std::f64::consts::TAU;
use std::io::Write;

use gsens_core::units::SPEED_OF_LIGHT_MPS;
use rand::{Rng, RngExt};
use serde::{Deserialize, Serialize};

use crate::imu::ImuErrors;
use crate::rng::{Xoshiro256PlusPlus, substream};
use crate::satellites::{AlmanacEntry, LineOfSight, Site};
use crate::scenario::Scenario;
use crate::session::{SessionSink, SimError};
use crate::world::{ImuUntil, World};

use ca_code::{CA_CHIP_RATE_HZ, CA_CODE_LENGTH, MAX_CA_PRN, ca_code_bipolar};
use lnav::{Ephemeris, EphemerisError, SUBFRAME_BITS, subframe_bits};

/// Length of a generator block \[s\]: Δf, Doppler and code rate are constant over it.
pub const BLOCK_S: f64 = 0.001;
/// Code periods per data bit (20 ms).
const PERIODS_PER_BIT: i64 = 20;
/// Code periods per subframe (6 s).
const PERIODS_PER_SUBFRAME: i64 = 6000;
/// Interval of the satellite geometry updates \[s\].
const GEOMETRY_STEP_S: f64 = 1.0;
/// Stream ids of the generator's own random draws.
const STREAM_IQ_NOISE: u64 = 0x1B_0000_0001;
const STREAM_IQ_PHASES: u64 = 0x1B_0000_0002;
/// log2 of the carrier lookup table size (1024 entries: phase steps of 0.35°).
const LUT_BITS: u32 = 10;

/// Why the generator cannot make a file: its settings ([`IqConfig`]) or the
/// sky at the start.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum IqError {
    /// [`IqConfig::fs_hz`] outside \[1.1, 100\] MHz.
    #[error("IQ sampling rate must be within [1.1, 100] MHz (got {fs_hz} Hz)")]
    SamplingRate {
        /// The rate given \[Hz\].
        fs_hz: f64,
    },
    /// [`IqConfig::noise_sigma`] not finite and positive.
    #[error("IQ noise sigma must be > 0 (got {noise_sigma})")]
    NoiseSigma {
        /// The σ given.
        noise_sigma: f64,
    },
    /// [`IqConfig::max_satellites`] is 0.
    #[error("IQ generator needs at least one satellite")]
    NoSatellites,
    /// No satellite with a C/A code is above the scenario's elevation mask at
    /// the start.
    #[error("no GPS satellite above the elevation mask at the start")]
    NoneInView,
    /// The scenario puts channels on other signals (`satellites.signals`):
    /// the IF generator makes GPS L1 C/A only.
    #[error(
        "the IF generator makes GPS L1 C/A samples only: remove satellites.signals ({0}) to generate IQ, or \
         simulate the mixed-signal session's logs without IF samples"
    )]
    SignalsNotSupported(String),
    /// A satellite's almanac orbit has no broadcast ephemeris.
    #[error("the almanac's orbit cannot be broadcast: {0}")]
    Ephemeris(#[from] EphemerisError),
}

/// Sample format of the output file, as GNSS-SDR's `File_Signal_Source` names it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum IqFormat {
    /// Interleaved signed 8-bit I/Q.
    Ibyte,
    /// Interleaved signed 16-bit I/Q.
    ///
    /// Little-endian.
    Ishort,
    /// Interleaved 32-bit float I/Q.
    ///
    /// Little-endian (GNU Radio's `gr_complex`).
    GrComplex,
}

impl IqFormat {
    /// Bytes per complex sample.
    pub fn bytes_per_sample(self) -> usize {
        match self {
            IqFormat::Ibyte => 2,
            IqFormat::Ishort => 4,
            IqFormat::GrComplex => 8,
        }
    }

    /// GNSS-SDR's `SignalSource.item_type` for this format.
    pub fn gnss_sdr_item_type(self) -> &'static str {
        match self {
            IqFormat::Ibyte => "ibyte",
            IqFormat::Ishort => "ishort",
            IqFormat::GrComplex => "gr_complex",
        }
    }

    /// Default thermal-noise σ per component in output units: 8 LSB for
    /// `ibyte` (quantization loss < 0.01 dB, no clipping), 1024 LSB for
    /// `ishort`, 1 for `gr_complex`.
    pub fn default_noise_sigma(self) -> f64 {
        match self {
            IqFormat::Ibyte => 8.0,
            IqFormat::Ishort => 1024.0,
            IqFormat::GrComplex => 1.0,
        }
    }

    /// Parses `ibyte`, `ishort` or `gr_complex`.
    pub fn parse(s: &str) -> Option<IqFormat> {
        match s {
            "ibyte" => Some(IqFormat::Ibyte),
            "ishort" => Some(IqFormat::Ishort),
            "gr_complex" => Some(IqFormat::GrComplex),
            _ => None,
        }
    }
}

/// Settings of the sample generator (the rest comes from the scenario).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct IqConfig {
    /// Sampling rate \[Hz\] (complex samples per second), at least 1.1 MHz.
    pub fs_hz: f64,
    /// Output sample format.
    pub format: IqFormat,
    /// Thermal noise σ per I and Q component, in output units (LSB for the integer formats).
    pub noise_sigma: f64,
    /// At most this many satellites (the highest at the start).
    pub max_satellites: u32,
    /// Modulate the LNAV data (`true`, the default); `false` sends the bare
    /// C/A code, d ≡ +1, as a simulator with its navigation message switched
    /// off does: a receiver then never synchronizes to bits or frames nor
    /// decodes a time (what `pocket_trk` needs to keep logging at `epoch`
    /// below 0.07 s, docs/conventions.md), while its PLL sees the same carrier.
    pub navigation_data: bool,
}

impl IqConfig {
    /// `fs_hz` and `format` with the format's default noise level and at most
    /// the scenario's `satellites.max_channels` satellites.
    pub fn new(fs_hz: f64, format: IqFormat, scenario: &Scenario) -> Self {
        IqConfig {
            fs_hz,
            format,
            noise_sigma: format.default_noise_sigma(),
            max_satellites: scenario.satellites.max_channels,
            navigation_data: true,
        }
    }

    fn validate(&self) -> Result<(), IqError> {
        if !(self.fs_hz.is_finite() && (1.1e6..=100e6).contains(&self.fs_hz)) {
            return Err(IqError::SamplingRate { fs_hz: self.fs_hz });
        }
        if !(self.noise_sigma.is_finite() && self.noise_sigma > 0.0) {
            return Err(IqError::NoiseSigma { noise_sigma: self.noise_sigma });
        }
        if self.max_satellites == 0 {
            return Err(IqError::NoSatellites);
        }
        Ok(())
    }
}

/// What the generator applied during one 1 ms block (for truth files and tests).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IqBlock<'a> {
    /// Centre of the block, receiver time \[s\].
    pub t_mid_s: f64,
    /// Δf = f_L1·y \[Hz\] over the block (oscillator noise + aᵀΓ).
    pub delta_f_hz: f64,
    /// The part aᵀΓ \[Hz\].
    pub g_induced_hz: f64,
    /// True specific force at the block centre, body axes \[m/s²\].
    pub accel_true_mps2: [f64; 3],
    /// Each satellite's baseband carrier frequency f_bb over the block \[Hz\],
    /// in the order of [`IqTruth::satellites`].
    pub carrier_hz: &'a [f64],
    /// The satellites' PRNs, in the same order.
    pub prns: &'a [u32],
}

/// One satellite of the file.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct IqSatelliteTruth {
    /// PRN.
    pub prn: u32,
    /// Elevation at the start \[deg\].
    pub start_elev_deg: f64,
    /// C/N0 at the start \[dB-Hz\].
    pub start_cn0_dbhz: f64,
    /// Doppler −ρ̇/λ at the start \[Hz\] (the signal's is this minus Δf).
    pub start_doppler_hz: f64,
    /// Pseudorange ρ at the start \[m\] ([`crate::satellites::ReceivedSignal`]).
    pub start_pseudorange_m: f64,
    /// t_oe of the ephemeris the satellite sends (GPS seconds since the GPS epoch).
    pub toe_gps_s: f64,
    /// Code phase at the first sample \[chips\].
    pub start_code_phase_chips: f64,
    /// Carrier phase at the first sample \[cycles\].
    pub start_carrier_phase_cycles: f64,
}

/// The truth of a generated file (`truth.json` of `gsens simulate --iq`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct IqTruth {
    /// The g-sensitivity simulated (flattened: its keys are truth.json's).
    #[serde(flatten)]
    pub sensitivity: crate::session::SensitivityTruth,
    /// Seed.
    pub seed: u64,
    /// Generator name and version.
    pub generator: String,
    /// GPS seconds at the first sample.
    pub start_gps_s: f64,
    /// Duration \[s\].
    pub duration_s: f64,
    /// Sampling rate \[Hz\].
    pub fs_hz: f64,
    /// Sample format.
    pub format: IqFormat,
    /// Noise σ per component \[output units\].
    pub noise_sigma: f64,
    /// Number of complex samples written.
    pub samples: u64,
    /// Block length \[s\] over which Δf and the Dopplers are constant.
    pub block_s: f64,
    /// Time convention of the file.
    pub sample_time: String,
    /// The satellites in the file.
    pub satellites: Vec<IqSatelliteTruth>,
    /// IMU time stamp minus true time \[s\].
    pub imu_time_offset_s: f64,
    /// The IMU's realized errors.
    pub imu_errors: ImuErrors,
    /// The scenario as run.
    pub scenario: Scenario,
}

/// Per-satellite generator state.
struct Sat {
    prn: u32,
    code: [f32; CA_CODE_LENGTH],
    /// Amplitude A in output units.
    amp: f32,
    /// Carrier phase at the start of the current block \[cycles\], in [0, 1).
    carrier_cycles: f64,
    /// Satellite clock time at the start of the current block: whole code periods
    /// since the GPS epoch and the chip within the period, in [0, 1023).
    period: i64,
    chip: f64,
    /// Doppler at the start of the current geometry second \[Hz\] and its slope \[Hz/s\].
    doppler0_hz: f64,
    doppler_slope_hz_per_s: f64,
    seg_t0_s: f64,
    next: LineOfSight,
    /// The broadcast orbit, whose ephemeris `eph` subframes 1–3 carry.
    orbit: AlmanacEntry,
    eph: Ephemeris,
    /// The subframe whose bits are cached.
    subframe: i64,
    bits: [u8; SUBFRAME_BITS],
    /// Whether `bits` modulate the code ([`IqConfig::navigation_data`]).
    data: bool,
    /// Chip table of the current block (amplitude · code · data).
    table: Vec<f32>,
}

impl Sat {
    /// Fills the chip table with `count` chips from chip `first` (relative to
    /// the current period's chip 0): amplitude · code · data, period by period.
    fn fill_table(&mut self, first: i64, count: usize) {
        let n = CA_CODE_LENGTH as i64;
        let mut period = self.period + first.div_euclid(n);
        let mut c = first.rem_euclid(n) as usize;
        self.table.clear();
        while self.table.len() < count {
            let v = self.amp * self.data_sign(period);
            let run = (CA_CODE_LENGTH - c).min(count - self.table.len());
            let code = &self.code[c..c + run];
            self.table.extend(code.iter().map(|&x| v * x));
            c = 0;
            period += 1;
        }
    }

    /// Adds the satellite to a block's samples `bi`, `bq` at `fs` \[Hz\],
    /// the first `lead_s` \[s\] from the block's start, with the baseband
    /// carrier `f_bb` \[Hz\] and the code `rate` \[chips/s\] constant over
    /// it, and advances its phases to the next block's start.
    fn mix(
        &mut self,
        bi: &mut [f32],
        bq: &mut [f32],
        lut: &[[f32; 2]],
        (f_bb, rate, fs): (f64, f64, f64),
        lead_s: f64,
    ) {
        let two32 = 4_294_967_296.0f64;
        // Phases at the first sample.
        let theta = self.carrier_cycles + f_bb * lead_s;
        let chip0 = self.chip + rate * lead_s;
        let first = chip0.floor();
        let frac = chip0 - first;
        let first = first as i64;
        // Chip table: the chips this block touches (with a margin), amplitude and data applied.
        let chips_needed = (rate * bi.len() as f64 / fs).ceil() as i64 + 3;
        self.fill_table(first, chips_needed as usize);
        let acc = Accumulators {
            code: (frac * two32) as u64,
            code_step: (rate / fs * two32).round() as u64,
            carrier: (theta.rem_euclid(1.0) * two32) as u64 as u32,
            carrier_step: (f_bb / fs * two32).round() as i64 as u32,
        };
        mix_satellite(bi, bq, &self.table, lut, acc);
        // Advance to the next block start.
        self.carrier_cycles = (self.carrier_cycles + f_bb * BLOCK_S).rem_euclid(1.0);
        self.chip += rate * BLOCK_S;
        let wraps = (self.chip / CA_CODE_LENGTH as f64).floor();
        self.chip -= wraps * CA_CODE_LENGTH as f64;
        self.period += wraps as i64;
    }

    fn data_sign(&mut self, period: i64) -> f32 {
        if !self.data {
            return 1.0;
        }
        let sf = period.div_euclid(PERIODS_PER_SUBFRAME);
        if sf != self.subframe {
            self.subframe = sf;
            self.bits = subframe_bits(sf, Some(&self.eph));
        }
        let bit = period.rem_euclid(PERIODS_PER_SUBFRAME) / PERIODS_PER_BIT;
        if self.bits[bit as usize] == 0 { 1.0 } else { -1.0 }
    }
}

/// Carrier lookup table: (cos, sin) of 2π·k/2^LUT_BITS, sampled at the
/// centre of each phase bin.
fn carrier_lut() -> Vec<[f32; 2]> {
    let n = 1usize << LUT_BITS;
    (0..n)
        .map(|k| {
            let a = TAU * (k as f64 + 0.5) / n as f64;
            [a.cos() as f32, a.sin() as f32]
        })
        .collect()
}

/// The fixed-point replica accumulators of one satellite over a block:
/// code position (32.32 chips) and carrier phase (2³² = one cycle), with
/// their per-sample steps.
#[derive(Debug, Clone, Copy)]
struct Accumulators {
    code: u64,
    code_step: u64,
    carrier: u32,
    carrier_step: u32,
}

/// Adds one satellite to the block: for each sample, chip value
/// `table[code >> 32]` times the carrier phasor `lut[carrier >> (32 − LUT_BITS)]`.
#[inline(never)]
fn mix_satellite(buf_i: &mut [f32], buf_q: &mut [f32], table: &[f32], lut: &[[f32; 2]], acc: Accumulators) {
    let lut: &[[f32; 2]; 1 << LUT_BITS] = lut.try_into().expect("LUT size");
    let (mut code, mut carrier) = (acc.code, acc.carrier);
    for (bi, bq) in buf_i.iter_mut().zip(buf_q.iter_mut()) {
        let c = table[(code >> 32) as usize];
        let [cs, sn] = lut[(carrier >> (32 - LUT_BITS)) as usize];
        *bi += c * cs;
        *bq += c * sn;
        code += acc.code_step;
        carrier = carrier.wrapping_add(acc.carrier_step);
    }
}

/// Quantizes the block into `out` (resized to the block's bytes) in `format`.
fn quantize(format: IqFormat, buf_i: &[f32], buf_q: &[f32], out: &mut Vec<u8>) {
    // Round half to even by adding and subtracting 1.5·2²³ (exact for |x| < 2²²;
    // larger values clip anyway), which vectorizes unlike `f32::round`.
    const MAGIC: f32 = 12_582_912.0;
    out.resize(buf_i.len() * format.bytes_per_sample(), 0);
    let samples = buf_i.iter().zip(buf_q);
    match format {
        IqFormat::Ibyte => {
            let q8 = |x: f32| ((x.clamp(-128.0, 127.0) + MAGIC) - MAGIC) as i8 as u8;
            for (o, (i, q)) in out.chunks_exact_mut(2).zip(samples) {
                o[0] = q8(*i);
                o[1] = q8(*q);
            }
        }
        IqFormat::Ishort => {
            let q16 = |x: f32| (((x.clamp(-32768.0, 32767.0) + MAGIC) - MAGIC) as i16).to_le_bytes();
            for (o, (i, q)) in out.chunks_exact_mut(4).zip(samples) {
                o[..2].copy_from_slice(&q16(*i));
                o[2..].copy_from_slice(&q16(*q));
            }
        }
        IqFormat::GrComplex => {
            for (o, (i, q)) in out.chunks_exact_mut(8).zip(samples) {
                o[..4].copy_from_slice(&i.to_le_bytes());
                o[4..].copy_from_slice(&q.to_le_bytes());
            }
        }
    }
}

/// Quantile function of the standard normal distribution, Φ⁻¹(p) for p in
/// (0, 1) (statrs: Φ⁻¹(p) = −√2·erfc⁻¹(2p)).
pub fn normal_quantile(p: f64) -> f64 {
    Normal::standard().inverse_cdf(p)
}

/// Thermal noise source: 2¹⁶ equiprobable quantiles of N(0, 1),
/// Φ⁻¹((k + ½)/2¹⁶), rescaled to unit variance, indexed by 16-bit slices of
/// the generator's output (four deviates per 64-bit draw). The distribution
/// is the normal one discretized to 65 536 equally likely values (tails cut
/// at ±4.3σ, one value in 65 536 beyond): after correlation over thousands of
/// samples it is indistinguishable from Gaussian noise, at a fifth of a
/// ziggurat's cost.
struct NoiseTable {
    values: Vec<f32>,
}

impl NoiseTable {
    const BITS: u32 = 16;

    fn new(sigma: f64) -> Self {
        let n = 1usize << Self::BITS;
        let raw: Vec<f64> = (0..n).map(|k| normal_quantile((k as f64 + 0.5) / n as f64)).collect();
        let var = raw.iter().map(|x| x * x).sum::<f64>() / n as f64;
        let scale = sigma / var.sqrt();
        NoiseTable { values: raw.iter().map(|x| (x * scale) as f32).collect() }
    }

    /// Fills `buf` with independent deviates.
    #[inline(never)]
    fn fill(&self, rng: &mut Xoshiro256PlusPlus, buf: &mut [f32]) {
        let v: &[f32; 1 << 16] = self.values.as_slice().try_into().expect("table size");
        let mut chunks = buf.chunks_exact_mut(4);
        for c in &mut chunks {
            let r = rng.next_u64();
            c[0] = v[(r & 0xFFFF) as usize];
            c[1] = v[((r >> 16) & 0xFFFF) as usize];
            c[2] = v[((r >> 32) & 0xFFFF) as usize];
            c[3] = v[(r >> 48) as usize];
        }
        let rest = chunks.into_remainder();
        if !rest.is_empty() {
            let mut r = rng.next_u64();
            for x in rest {
                *x = v[(r & 0xFFFF) as usize];
                r >>= 16;
            }
        }
    }
}

fn set_segment(sat: &mut Sat, now: &LineOfSight, next: &LineOfSight, t: f64, carrier_hz: f64) {
    let d0 = now.doppler_at_hz(carrier_hz);
    sat.doppler0_hz = d0;
    sat.doppler_slope_hz_per_s = (next.doppler_at_hz(carrier_hz) - d0) / GEOMETRY_STEP_S;
    sat.seg_t0_s = t;
    sat.next = *next;
}

fn amplitude(noise_sigma: f64, cn0_dbhz: f64, fs_hz: f64) -> f32 {
    (noise_sigma * (2.0 * gsens_core::units::cn0_dbhz_to_ratio_hz(cn0_dbhz) / fs_hz).sqrt()) as f32
}

/// First sample index of block `b`: ⌈b·fs·1ms⌉ (samples at or after the block start).
fn block_start_sample(b: u64, fs_hz: f64) -> u64 {
    let x = b as f64 * fs_hz * BLOCK_S;
    let r = x.round();
    // Integer products (fs a multiple of 1 kHz) are exact; otherwise round up.
    if (x - r).abs() < 1e-6 { r as u64 } else { x.ceil() as u64 }
}

/// Generates the scenario's IF samples into `out` (`cfg.format`), the IMU log
/// into `sink` (its `tracking` is not called), reports each block's Δf to
/// `on_block` and the fraction done to `progress` about once per second of
/// signal. Returns the truth.
pub fn generate_iq<W: Write, S: SessionSink + ?Sized>(
    scenario: &Scenario,
    seed: u64,
    cfg: &IqConfig,
    mut out: W,
    sink: &mut S,
    mut on_block: impl FnMut(&IqBlock<'_>),
    mut progress: impl FnMut(f64),
) -> Result<IqTruth, SimError> {
    scenario.validate()?;
    cfg.validate()?;
    if !scenario.satellites.signals.is_empty() {
        return Err(IqError::SignalsNotSupported(scenario.satellites.signals.join(", ")).into());
    }
    let mut world = World::new(scenario, seed, BLOCK_S)?;
    let n_blocks = (world.duration_s / BLOCK_S + 1e-6).floor() as u64;
    let blocks_per_geo = (GEOMETRY_STEP_S / BLOCK_S).round() as u64;
    let mut noise_rng = substream(seed, STREAM_IQ_NOISE);
    let (mut sats, truth_sats) = start_satellites(&world, scenario, cfg, &mut substream(seed, STREAM_IQ_PHASES))?;
    let site = Site::new(&scenario.antenna);
    let mut mixer = Mixer::new(cfg);
    let mut carrier_hz_now = vec![0.0; sats.len()];
    let prns: Vec<u32> = sats.iter().map(|s| s.prn).collect();
    let io_err = |e: std::io::Error| SimError::Sink(Box::new(e));
    let mut samples = 0u64;

    for b in 0..n_blocks {
        let t0 = b as f64 * BLOCK_S;
        let tm = t0 + 0.5 * BLOCK_S;
        let y = world.osc.next_y();
        let a = world.specific_force(tm);
        let g_induced_hz = world.g_induced_hz(&a);
        let delta_f_hz = world.carrier_hz * y + g_induced_hz;
        if b % blocks_per_geo == 0 {
            update_geometry(&mut sats, &world, &site, cfg, (b, t0));
            progress((t0 / world.duration_s).min(1.0));
        }
        let bytes = mixer.block(b, &mut sats, (delta_f_hz, world.carrier_hz), &mut noise_rng, &mut carrier_hz_now);
        out.write_all(bytes).map_err(io_err)?;
        samples += (bytes.len() / cfg.format.bytes_per_sample()) as u64;
        on_block(&IqBlock {
            t_mid_s: tm,
            delta_f_hz,
            g_induced_hz,
            accel_true_mps2: a,
            carrier_hz: &carrier_hz_now,
            prns: &prns,
        });
        // IMU samples stamped within this block (and the duration).
        world.log_imu(ImuUntil::Before(t0 + BLOCK_S), sink, |_, _| {})?;
    }
    // IMU stamps at the very end of the duration.
    world.log_imu(ImuUntil::End, sink, |_, _| {})?;
    out.flush().map_err(io_err)?;
    progress(1.0);
    Ok(IqTruth {
        sensitivity: world.sensitivity(),
        seed,
        generator: format!("{} {} (iq)", env!("CARGO_PKG_NAME"), env!("CARGO_PKG_VERSION")),
        start_gps_s: world.start_gps_s,
        duration_s: n_blocks as f64 * BLOCK_S,
        fs_hz: cfg.fs_hz,
        format: cfg.format,
        noise_sigma: cfg.noise_sigma,
        samples,
        block_s: BLOCK_S,
        sample_time: "sample n at receiver time n/fs_hz; Δf and Dopplers constant over 1 ms blocks \
                      [b·1ms, (b+1)·1ms) of receiver time, evaluated at the block centre"
            .into(),
        satellites: truth_sats,
        imu_time_offset_s: world.imu.time_offset_s,
        imu_errors: world.imu,
        scenario: scenario.clone(),
    })
}

/// The satellites of the file: those with a C/A code above the elevation
/// mask at the start, highest first, at most `cfg.max_satellites`; each
/// with its code phase from the geometric range, a carrier phase drawn
/// uniform from `phase_rng` and its geometry for the first second; and
/// their truth.
fn start_satellites(
    world: &World,
    sc: &Scenario,
    cfg: &IqConfig,
    phase_rng: &mut Xoshiro256PlusPlus,
) -> Result<(Vec<Sat>, Vec<IqSatelliteTruth>), SimError> {
    let (start_gps_s, carrier_hz, antenna) = (world.start_gps_s, world.carrier_hz, sc.antenna);
    let site = Site::new(&antenna);
    let toe_gps_s = ((start_gps_s + 0.5 * world.duration_s) / 7200.0).round() * 7200.0;
    let visible: Vec<LineOfSight> = world
        .constellation
        .visible_lines_of_sight(&antenna, start_gps_s, sc.satellites.elevation_mask_deg)
        .into_iter()
        .filter(|l| (1..=MAX_CA_PRN).contains(&l.prn))
        .take(cfg.max_satellites as usize)
        .collect();
    if visible.is_empty() {
        return Err(IqError::NoneInView.into());
    }
    // Milliseconds of GPS time at the start, split exactly.
    let start_ms_f = start_gps_s * 1000.0;
    let start_ms = start_ms_f.floor() as i64;
    let start_ms_frac = start_ms_f - start_ms as f64;
    let mut sats: Vec<Sat> = Vec::with_capacity(visible.len());
    let mut truth_sats = Vec::with_capacity(visible.len());
    for geometric in &visible {
        let almanac = world.constellation.get(geometric.prn).expect("visible PRN");
        let eph = Ephemeris::of_orbit(almanac, toe_gps_s).map_err(IqError::from)?;
        let orbit = eph.orbit();
        let los = &orbit.received_line_of_sight(&site, start_gps_s);
        let next = orbit.received_line_of_sight(&site, start_gps_s + GEOMETRY_STEP_S);
        let code = ca_code_bipolar(los.prn).expect("PRN with a C/A code").map(f32::from);
        // The satellite clock's time t_sv = GPS time − ρ/c, in code periods (ms) and chips.
        let tx_ms = start_ms_frac - los.range_m / SPEED_OF_LIGHT_MPS * 1000.0;
        let whole = tx_ms.floor();
        let chip = (tx_ms - whole) * CA_CODE_LENGTH as f64;
        let u: f64 = phase_rng.random();
        let cn0_dbhz = world.cn0.cn0_dbhz(los.prn, los.elevation_deg);
        let mut sat = Sat {
            prn: los.prn,
            code,
            amp: amplitude(cfg.noise_sigma, cn0_dbhz, cfg.fs_hz),
            carrier_cycles: u,
            period: start_ms + whole as i64,
            chip,
            doppler0_hz: 0.0,
            doppler_slope_hz_per_s: 0.0,
            seg_t0_s: 0.0,
            next,
            orbit,
            eph,
            subframe: i64::MIN,
            bits: [0; SUBFRAME_BITS],
            data: cfg.navigation_data,
            table: Vec::with_capacity(2 * CA_CODE_LENGTH),
        };
        set_segment(&mut sat, los, &next, 0.0, carrier_hz);
        truth_sats.push(IqSatelliteTruth {
            prn: los.prn,
            start_elev_deg: los.elevation_deg,
            start_cn0_dbhz: cn0_dbhz,
            start_doppler_hz: los.doppler_at_hz(carrier_hz),
            start_pseudorange_m: los.range_m,
            toe_gps_s: eph.toe_gps_s(),
            start_code_phase_chips: chip,
            start_carrier_phase_cycles: u,
        });
        sats.push(sat);
    }
    Ok((sats, truth_sats))
}

/// The satellites' geometry for the second from block `b` at `t0` \[s\]
/// (the first block's is set at the start) and their amplitudes from the
/// C/N0 at their elevation now.
fn update_geometry(sats: &mut [Sat], world: &World, site: &Site, cfg: &IqConfig, (b, t0): (u64, f64)) {
    let t_next_gps = world.start_gps_s + t0 + GEOMETRY_STEP_S;
    for sat in sats.iter_mut() {
        let now = sat.next;
        let next = sat.orbit.received_line_of_sight(site, t_next_gps);
        if b > 0 {
            set_segment(sat, &now, &next, t0, world.carrier_hz);
        }
        sat.amp = amplitude(cfg.noise_sigma, world.cn0.cn0_dbhz(sat.prn, now.elevation_deg), cfg.fs_hz);
    }
}

/// What turns the satellites into a block of samples: the noise, the
/// carrier table, the buffers of I and Q and of the block's bytes.
struct Mixer {
    fs_hz: f64,
    format: IqFormat,
    lut: Vec<[f32; 2]>,
    noise: NoiseTable,
    buf_i: Vec<f32>,
    buf_q: Vec<f32>,
    bytes: Vec<u8>,
}

impl Mixer {
    fn new(cfg: &IqConfig) -> Self {
        let max_block = (cfg.fs_hz * BLOCK_S).ceil() as usize + 1;
        Mixer {
            fs_hz: cfg.fs_hz,
            format: cfg.format,
            lut: carrier_lut(),
            noise: NoiseTable::new(cfg.noise_sigma),
            buf_i: vec![0f32; max_block],
            buf_q: vec![0f32; max_block],
            bytes: Vec::with_capacity(max_block * cfg.format.bytes_per_sample()),
        }
    }

    /// Block `b`'s samples in the output format: the thermal noise plus
    /// every satellite under the oscillator's error Δf (`delta_f_hz` at the
    /// carrier `carrier_hz`), each satellite's phases advanced to the next
    /// block and its baseband carrier written to `carrier_hz_now`.
    fn block(
        &mut self,
        b: u64,
        sats: &mut [Sat],
        (delta_f_hz, carrier_hz): (f64, f64),
        noise_rng: &mut Xoshiro256PlusPlus,
        carrier_hz_now: &mut [f64],
    ) -> &[u8] {
        let fs = self.fs_hz;
        let (t0, n0) = (b as f64 * BLOCK_S, block_start_sample(b, fs));
        let len = (block_start_sample(b + 1, fs) - n0) as usize;
        let (bi, bq) = (&mut self.buf_i[..len], &mut self.buf_q[..len]);
        self.noise.fill(noise_rng, bi);
        self.noise.fill(noise_rng, bq);
        let scale = 1.0 / (1.0 + delta_f_hz / carrier_hz);
        // Receiver time of the first sample minus the block start (≤ 0, above −1/fs).
        let lead_s = n0 as f64 / fs - t0;
        let tm = t0 + 0.5 * BLOCK_S;
        for (sat, f_now) in sats.iter_mut().zip(carrier_hz_now.iter_mut()) {
            let f_d = sat.doppler0_hz + sat.doppler_slope_hz_per_s * (tm - sat.seg_t0_s);
            let f_bb = (f_d - delta_f_hz) * scale;
            *f_now = f_bb;
            let rate = CA_CHIP_RATE_HZ * (1.0 + f_d / carrier_hz) * scale;
            sat.mix(bi, bq, &self.lut, (f_bb, rate, fs), lead_s);
        }
        quantize(self.format, bi, bq, &mut self.bytes);
        &self.bytes
    }
}

/// A [`SessionSink`] that ignores tracking rows and forwards IMU samples to a closure.
pub struct ImuOnlySink<F: FnMut(f64, [f64; 3]) -> Result<(), crate::session::SinkError>>(pub F);

impl<F: FnMut(f64, [f64; 3]) -> Result<(), crate::session::SinkError>> SessionSink for ImuOnlySink<F> {
    fn imu(&mut self, t_s: f64, f_mps2: [f64; 3]) -> Result<(), crate::session::SinkError> {
        (self.0)(t_s, f_mps2)
    }
    fn tracking(&mut self, _row: &crate::session::SimulatedRow) -> Result<(), crate::session::SinkError> {
        Ok(())
    }
}

/// Correlates `samples` (complex baseband, interleaved f32 pairs as produced by
/// `gr_complex`) with a replica of `prn` at code phase `code_phase_chips`,
/// code rate `chip_rate_hz` and carrier `carrier_hz` starting at phase
/// `carrier_cycles`, over the whole slice: returns the complex prompt
/// correlation normalized by the number of samples. A test helper for
/// checking generated files.
pub fn correlate(
    samples: &[[f32; 2]],
    fs_hz: f64,
    prn: u32,
    code_phase_chips: f64,
    chip_rate_hz: f64,
    carrier_hz: f64,
    carrier_cycles: f64,
) -> Option<(f64, f64)> {
    let code = ca_code_bipolar(prn)?;
    let (mut si, mut sq) = (0.0, 0.0);
    for (n, s) in samples.iter().enumerate() {
        let t = n as f64 / fs_hz;
        let chip = (code_phase_chips + chip_rate_hz * t).rem_euclid(CA_CODE_LENGTH as f64) as usize;
        let c = f64::from(code[chip.min(CA_CODE_LENGTH - 1)]);
        let ph = -TAU * (carrier_cycles + carrier_hz * t);
        let (sn, cs) = ph.sin_cos();
        let (i, q) = (f64::from(s[0]), f64::from(s[1]));
        si += c * (i * cs - q * sn);
        sq += c * (i * sn + q * cs);
    }
    let n = samples.len().max(1) as f64;
    Some((si / n, sq / n))
}

#[cfg(test)]
mod tests;
