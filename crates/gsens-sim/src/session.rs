//! A whole simulated calibration session: oscillator, hand motion, IMU,
//! satellites, one tracking channel per satellite, and the logs.
//!
//! # Timeline
//!
//! Receiver time t \[s\] starts at 0 (GPS time `start_utc` + t). The loops run
//! at the update interval T: integration k covers \[kT − T/2, kT + T/2\], so its
//! centre is t_k = kT. Every step k, once for all channels:
//!
//! - the oscillator gives ȳ_k, its fractional frequency averaged over the
//!   step ([`crate::oscillator::Oscillator::next_y`]);
//! - the true specific force a(t_k) in the body frame comes from the motion
//!   ([`crate::imu::specific_force_body`]), evaluated exactly on a 5 ms grid and
//!   interpolated linearly in between (error < 1e-4 relative for a 1 s shake);
//! - Δf_k = f_carrier·ȳ_k + a(t_k)ᵀΓ \[Hz\], added to every NCO's command
//!   (docs/conventions.md); a channel on another carrier f_c
//!   (`satellites.signals`) gets (f_c/f_carrier)·Δf_k, i.e. f_c times the same
//!   fractional frequency error.
//!
//! Then each channel integrates against its satellite's carrier, whose Doppler
//! (and rate) come from the orbit model at 1 s intervals and are interpolated
//! linearly in between ([`Channel::step`]).
//!
//! # Logs
//!
//! - IMU: sample i is stamped i/rate and taken at the true time
//!   i/rate − `imu.time_offset_s` (the IMU's errors from [`ImuErrors`]),
//!   for every stamp in \[0, duration\].
//! - Tracking: a row per channel every n = `log.interval_s`/T integrations, after
//!   integration k = m·n (m ≥ 1), time-stamped t_k = kT, the centre of the
//!   latest integration; with `log.phase = "mean"` the phase is the mean of
//!   the n discriminator outputs since the previous row. This is exactly the
//!   convention of `gsens_core::LoggedPhase`. With the default
//!   40 Hz logs and IMU the two streams share their time stamps.
//!
//! # Satellites and channels
//!
//! Every second the satellites above the elevation mask are listed; a
//! satellite that has set stops its channel, and risen satellites take free
//! channels, highest first (at most `satellites.max_channels`). A starting
//! channel is preloaded with the true carrier frequency offset seen through the
//! oscillator (Doppler − Δf) plus a random error of σ = `loop.initial_freq_err_hz`,
//! a uniform phase and a uniform data-bit phase: lock, losses of lock and
//! cycle slips then come from the loop's dynamics alone.
//!
//! # Reproducibility
//!
//! All randomness comes from streams derived from the one seed
//! ([`crate::rng::substream`]): oscillator, motion jitter, IMU errors, IMU
//! noise, C/N0 offsets, and one stream per channel start (identified by PRN
//! and start time), so the same scenario and seed give the same bytes.

use core::f64::consts::PI;

use gsens_core::LoopFilterCoeffs;
use gsens_core::units::hz_per_mps2_to_ppb_per_g;
use rand::RngExt;
use serde::Serialize;

use crate::channel::{Channel, ChannelConfig, ChannelStart, ChannelStats};
use crate::imu::ImuErrors;
use crate::rng::{Xoshiro256PlusPlus, normal, substream};
use crate::satellites::{Cn0Offsets, LineOfSight};
use crate::scenario::{Cn0Logged, Scenario, ScenarioError};
use crate::world::{ImuUntil, World, stream};
use gsens_core::LoggedPhase;

/// Interval of the satellite geometry updates \[s\].
const GEOMETRY_STEP_S: f64 = 1.0;
/// Grid of the exact specific-force evaluations \[s\] (interpolated in between).
const FORCE_GRID_S: f64 = 0.005;

/// One simulated tracking-log row (a channel at a log epoch): what a receiver
/// logs (the columns of `tracking.csv`, [`SimulatedRow::tracking_row`]) and
/// the simulation's truth and lock state beside it, which `tracking.csv` does
/// not hold.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SimulatedRow {
    /// Time stamp \[s\]: the centre of the latest integration.
    pub t_s: f64,
    /// Receiver channel number (0-based; reused after a satellite sets).
    pub channel: u32,
    /// Satellite PRN.
    pub prn: u32,
    /// C/N0 \[dB-Hz\]: the receiver's estimate or the true value, per `log.cn0`.
    pub cn0_dbhz: f64,
    /// Elevation \[deg\].
    pub elev_deg: f64,
    /// The logged phase error \[rad\]: the last discriminator output or the mean
    /// since the previous row, per `log.phase` (what a receiver can log).
    pub phase_err_rad: f64,
    /// The lock indicator's state.
    pub locked: bool,
    /// Truth: the same statistic (last or mean) of the true phase error at the
    /// integration centres, unwrapped (it includes the multiples of π or 2π the
    /// loop has slipped by, and the initial ambiguity) \[rad\].
    pub true_phase_err_rad: f64,
    /// Truth: the channel's true C/N0 \[dB-Hz\].
    pub true_cn0_dbhz: f64,
    /// The replica's accumulated phase the NCO was commanded, at the end of
    /// the latest integration \[cycles\]: `nco_phase_cycles` of
    /// `tracking.csv` (what the receiver knows of its replica; the
    /// oscillator's bias is not in it).
    pub nco_phase_cycles: f64,
    /// The NCO frequency commanded during the latest integration \[Hz\]:
    /// `nco_freq_hz` of `tracking.csv`.
    pub nco_freq_hz: f64,
    /// The carrier the channel tracks (`satellites.signals`; unnamed
    /// `oscillator.carrier_hz` without it).
    #[serde(skip)]
    pub carrier: gsens_io::Carrier,
}

impl SimulatedRow {
    /// The row as logged with its carrier, for `tracking.csv` with carrier columns.
    pub fn tracking_row_on(&self) -> (gsens_io::TrackingRow, gsens_io::Carrier) {
        (self.tracking_row(), self.carrier)
    }

    /// The row as logged, for `tracking.csv` (the elevation is always known).
    pub fn tracking_row(&self) -> gsens_io::TrackingRow {
        gsens_io::TrackingRow {
            t_s: self.t_s,
            channel: self.channel,
            prn: self.prn,
            cn0_dbhz: self.cn0_dbhz,
            elev_deg: Some(self.elev_deg),
            phase_err_rad: self.phase_err_rad,
        }
    }
}

/// Error of a sink (e.g. an I/O error of the CLI's file writers).
pub type SinkError = Box<dyn std::error::Error + Send + Sync>;

/// Where a session's logs go, as they are produced (so that long sessions
/// need not be held in memory).
pub trait SessionSink {
    /// One IMU sample: time stamp \[s\] and measured specific force, body axes \[m/s²\].
    fn imu(&mut self, t_s: f64, f_mps2: [f64; 3]) -> Result<(), SinkError>;
    /// One tracking row.
    fn tracking(&mut self, row: &SimulatedRow) -> Result<(), SinkError>;
}

/// A sink that keeps everything in memory.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MemorySink {
    /// IMU samples (time stamp \[s\], specific force \[m/s²\]).
    pub imu: Vec<(f64, [f64; 3])>,
    /// Tracking rows.
    pub tracking: Vec<SimulatedRow>,
}

impl SessionSink for MemorySink {
    fn imu(&mut self, t_s: f64, f_mps2: [f64; 3]) -> Result<(), SinkError> {
        self.imu.push((t_s, f_mps2));
        Ok(())
    }
    fn tracking(&mut self, row: &SimulatedRow) -> Result<(), SinkError> {
        self.tracking.push(*row);
        Ok(())
    }
}

/// A sink that drops everything (for benchmarks and statistics-only runs).
#[derive(Debug, Clone, Copy, Default)]
pub struct NullSink;

impl SessionSink for NullSink {
    fn imu(&mut self, _t_s: f64, _f_mps2: [f64; 3]) -> Result<(), SinkError> {
        Ok(())
    }
    fn tracking(&mut self, _row: &SimulatedRow) -> Result<(), SinkError> {
        Ok(())
    }
}

/// Errors of a simulation.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SimError {
    /// The scenario is invalid.
    #[error(transparent)]
    Scenario(#[from] ScenarioError),
    /// A model refused its configuration.
    #[error(transparent)]
    Model(#[from] crate::error::ConfigError),
    /// The IQ generator's settings, or no satellite in view for it.
    #[error(transparent)]
    Iq(#[from] crate::iq::IqError),
    /// The sink failed.
    #[error("writing the logs: {0}")]
    Sink(SinkError),
}

/// The loop filter as used, for the truth file.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct LoopCoeffsTruth {
    /// c0 \[1/s\].
    pub c0_per_s: f64,
    /// c1 \[1/s²\].
    pub c1_per_s2: f64,
    /// c2 \[1/s³\].
    pub c2_per_s3: f64,
}

impl From<LoopFilterCoeffs> for LoopCoeffsTruth {
    fn from(c: LoopFilterCoeffs) -> Self {
        LoopCoeffsTruth { c0_per_s: c.c0_per_s, c1_per_s2: c.c1_per_s2, c2_per_s3: c.c2_per_s3 }
    }
}

/// What happened on one channel (one satellite pass within the session).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ChannelSummary {
    /// Channel number.
    pub channel: u32,
    /// PRN.
    pub prn: u32,
    /// Start of tracking \[s\].
    pub start_s: f64,
    /// End of tracking \[s\] (the satellite set, or the session ended).
    pub stop_s: f64,
    /// Elevation at the start \[deg\].
    pub start_elev_deg: f64,
    /// The satellite's C/N0 offset from the elevation model \[dB\].
    pub cn0_offset_db: f64,
    /// True C/N0 at the start \[dB-Hz\].
    pub start_cn0_dbhz: f64,
    /// Counters: integrations, integrations locked, cycle slips, losses of lock.
    pub stats: ChannelStats,
    /// The signal tracked (`satellites.signals`; absent without it).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub signal: Option<String>,
}

/// The g-sensitivity a simulation ran with, in every form a calibration is
/// compared against (the first keys of every `truth.json`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SensitivityTruth {
    /// Γ \[Hz/(m/s²)\] at the carrier, body axes.
    pub gamma_hz_per_mps2: [f64; 3],
    /// Γ in ppb/g: Γ·g₀/f_carrier·1e9.
    pub gamma_ppb_per_g: [f64; 3],
    /// Γ as seen through the IMU's readings, M⁻ᵀΓ \[Hz/(m/s²)\]: the IMU reads
    /// m = M·f + b (M = I + scale factors + misalignment), so
    /// Δf = Γᵀf = (M⁻ᵀΓ)ᵀ(m − b) and the constant b is rejected by the loops.
    /// This is what an estimator fed with the IMU log converges to.
    pub gamma_imu_axes_hz_per_mps2: [f64; 3],
    /// Tracked carrier \[Hz\].
    pub carrier_hz: f64,
}

impl SensitivityTruth {
    /// Γ at `carrier_hz` as seen through an IMU with sensing matrix `m`.
    pub fn new(gamma_hz_per_mps2: [f64; 3], carrier_hz: f64, m: &[[f64; 3]; 3]) -> Self {
        SensitivityTruth {
            gamma_hz_per_mps2,
            gamma_ppb_per_g: gamma_hz_per_mps2.map(|g| hz_per_mps2_to_ppb_per_g(g, carrier_hz)),
            gamma_imu_axes_hz_per_mps2: inverse_transpose_times(m, &gamma_hz_per_mps2),
            carrier_hz,
        }
    }
}

impl core::fmt::Display for Truth {
    /// What was simulated, in two lines: duration, channel passes, cycle
    /// slips and seed; Γ and the loop and log settings.
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let slips: u64 = self.channels.iter().map(|c| c.stats.cycle_slips).sum();
        let g = self.sensitivity.gamma_hz_per_mps2;
        let logged = self.logged_phase.name();
        writeln!(
            f,
            "simulated {:.1} s, {} channel passes ({slips} cycle slips), seed {}",
            self.duration_s,
            self.channels.len(),
            self.seed
        )?;
        write!(
            f,
            "truth Γ = [{:+.4}, {:+.4}, {:+.4}] Hz/(m/s²); loop interval {} s, log interval {} s, logged phase {logged}",
            g[0], g[1], g[2], self.loop_interval_s, self.log_interval_s
        )
    }
}

/// The truth of a run: Γ and everything needed to reproduce it
/// (`truth.json`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Truth {
    /// The g-sensitivity simulated (flattened: its keys are truth.json's).
    #[serde(flatten)]
    pub sensitivity: SensitivityTruth,
    /// The seed.
    pub seed: u64,
    /// The simulator and its version, e.g. `gsens-sim 0.1.0`.
    pub generator: String,
    /// GPS seconds at t = 0.
    pub start_gps_s: f64,
    /// Duration \[s\].
    pub duration_s: f64,
    /// Loop update interval T \[s\].
    pub loop_interval_s: f64,
    /// Tracking log interval \[s\].
    pub log_interval_s: f64,
    /// What `phase_err_rad` is: `last` or `mean`.
    pub logged_phase: LoggedPhase,
    /// The rows' time-stamp convention.
    pub row_time_stamp: String,
    /// The loop filter used by every channel.
    pub loop_coeffs: LoopCoeffsTruth,
    /// IMU time stamp minus true time \[s\].
    pub imu_time_offset_s: f64,
    /// The IMU's realized errors (bias, scale factor, misalignment, noise).
    pub imu_errors: ImuErrors,
    /// Per channel (satellite pass): PRN, times, slips, losses of lock.
    pub channels: Vec<ChannelSummary>,
    /// The scenario as run.
    pub scenario: Scenario,
}

/// One active channel and its satellite's interpolated geometry.
struct Track {
    ch: Channel,
    prn: u32,
    channel: u32,
    /// The carrier tracked, and its ratio to the oscillator's carrier (Δf scales by it).
    carrier: gsens_io::Carrier,
    carrier_ratio: f64,
    start_s: f64,
    start_elev_deg: f64,
    start_cn0_dbhz: f64,
    cn0_offset_db: f64,
    /// Carrier Doppler at the start of the current geometry second \[Hz\] and its slope \[Hz/s\].
    doppler0_hz: f64,
    doppler_slope_hz_per_s: f64,
    /// Elevation at the start of the current geometry second \[deg\] and its slope \[deg/s\].
    elev0_deg: f64,
    elev_slope_deg_per_s: f64,
    /// Start of the current geometry second \[s\].
    seg_t0_s: f64,
    /// Geometry at the end of the current second.
    next: LineOfSight,
}

impl Track {
    fn summary(&self, stop_s: f64) -> ChannelSummary {
        ChannelSummary {
            channel: self.channel,
            prn: self.prn,
            start_s: self.start_s,
            stop_s,
            start_elev_deg: self.start_elev_deg,
            cn0_offset_db: self.cn0_offset_db,
            start_cn0_dbhz: self.start_cn0_dbhz,
            stats: self.ch.stats(),
            signal: self.carrier.signal.map(|s| s.label()),
        }
    }
}

/// Simulates the session of `scenario` with `seed`, streaming the logs into
/// `sink` and reporting the fraction done (0…1) to `progress` about once per
/// simulated second. Returns the truth.
pub fn simulate<S: SessionSink + ?Sized>(
    scenario: &Scenario,
    seed: u64,
    sink: &mut S,
    mut progress: impl FnMut(f64),
) -> Result<Truth, SimError> {
    scenario.validate()?;
    let sc = scenario;
    let t_s = sc.tracking_loop.interval_s;
    let coeffs = sc.tracking_loop.coeffs()?;
    let mut world = World::new(sc, seed, t_s)?;
    let (duration_s, carrier_hz, gamma) = (world.duration_s, world.carrier_hz, world.gamma);
    // 20 ms is a whole number of loop intervals, so 1/T is an integer and
    // t = k/(1/T) is the correctly rounded time stamp.
    let updates_per_s = (1.0 / t_s).round();
    let n_steps = (duration_s * updates_per_s + 1e-6).floor() as u64;
    let per_row = u64::from(sc.integrations_per_row());
    let geo_steps = (GEOMETRY_STEP_S / t_s).round() as u64;
    // The force at the integrations' starts, centres and ends (half steps).
    let mut force = ForceGrid::new(&world, t_s / 2.0);
    let mut a_start: Option<[f64; 3]> = None;
    // The receiver's feed-forward of Γ̂ into its NCOs, from its IMU's samples.
    let mut feed_forward = sc.compensation.as_ref().map(crate::compensation::FeedForward::new);
    let mut receiver = Receiver::new(sc, seed, coeffs, t_s);

    for k in 0..=n_steps {
        let t = k as f64 / updates_per_s;
        // IMU samples whose stamp has been reached (first: the feed-forward
        // uses the newest sample at this very step), in the receiver's hands
        // once both stamped and measured.
        world.log_imu(ImuUntil::Through(t), sink, |at_s, m| {
            if let Some(f) = &mut feed_forward {
                f.sample(at_s, m);
            }
        })?;
        // Shared per-step inputs: oscillator and specific force → Δf.
        let y = world.osc.next_y();
        // Over this step's integration [t − T/2, t + T/2] the force varies: its
        // mean advances the replica, its mean weighted by the time left,
        // 2(1 − s/T)/T, enters the mean phase error (Channel::step_varying).
        // Simpson's rule on the start, centre and end: exact for a quadratic.
        // The first integration starts at the session's start.
        let a_centre = force.at(&world, 2 * k);
        let a_end = force.at(&world, 2 * k + 1);
        let a0 = a_start.unwrap_or(a_centre);
        let a_mean: [f64; 3] = core::array::from_fn(|i| (a0[i] + 4.0 * a_centre[i] + a_end[i]) / 6.0);
        let a_weighted: [f64; 3] = core::array::from_fn(|i| (a0[i] + 2.0 * a_centre[i]) / 3.0);
        a_start = Some(a_end);
        // What reaches the NCOs: the oscillator's error, less the feed-forward's correction.
        let correction_hz = feed_forward.as_mut().map_or(0.0, |f| f.correction_hz(t));
        let delta_f =
            |a: [f64; 3]| carrier_hz * y + a[0] * gamma[0] + a[1] * gamma[1] + a[2] * gamma[2] + correction_hz;
        let (delta_f_hz, weighted_hz) = (delta_f(a_mean), delta_f(a_weighted));
        if k % geo_steps == 0 {
            receiver.update_sky(&world, t, delta_f_hz);
            progress((t / duration_s).min(1.0));
        }
        receiver.integrate(t, delta_f_hz, weighted_hz);
        if k > 0 && k % per_row == 0 {
            receiver.log_rows(t, sink)?;
        }
    }
    // Any IMU stamp after the last integration but within the duration.
    world.log_imu(ImuUntil::End, sink, |_, _| {})?;
    progress(1.0);
    let channels = receiver.finish(n_steps as f64 / updates_per_s);
    Ok(truth(world, sc, seed, (t_s, per_row as f64 * t_s), coeffs, channels))
}

/// The truth of a session: `world`'s, the loop and log intervals
/// `intervals_s` \[s\] and the loop filter `coeffs`, every channel pass.
fn truth(
    world: World,
    sc: &Scenario,
    seed: u64,
    (loop_interval_s, log_interval_s): (f64, f64),
    coeffs: LoopFilterCoeffs,
    channels: Vec<ChannelSummary>,
) -> Truth {
    Truth {
        sensitivity: world.sensitivity(),
        seed,
        generator: format!("{} {}", env!("CARGO_PKG_NAME"), env!("CARGO_PKG_VERSION")),
        start_gps_s: world.start_gps_s,
        duration_s: world.duration_s,
        loop_interval_s,
        log_interval_s,
        logged_phase: sc.log.phase,
        row_time_stamp: "centre of the latest integration (t = k*T, integration k covering [kT - T/2, kT + T/2])"
            .into(),
        loop_coeffs: coeffs.into(),
        imu_time_offset_s: world.imu.time_offset_s,
        imu_errors: world.imu,
        channels,
        scenario: sc.clone(),
    }
}

/// The specific force at steps of a fixed length: exact every [`FORCE_GRID_S`] (a
/// whole number `m` of steps), linear in between.
struct ForceGrid {
    m: u64,
    /// The grid's spacing \[s\].
    h_s: f64,
    /// The grid interval the steps are in, and the force at its two ends.
    j: u64,
    a: [f64; 3],
    b: [f64; 3],
}

impl ForceGrid {
    /// The grid for loop steps of `t_s` \[s\], at its first interval.
    fn new(world: &World, t_s: f64) -> Self {
        let m = ((FORCE_GRID_S / t_s).round() as u64).max(1);
        let h_s = m as f64 * t_s;
        ForceGrid { m, h_s, j: 0, a: world.specific_force(0.0), b: world.specific_force(h_s) }
    }

    /// The specific force at step `k` (steps in increasing order) \[m/s²\].
    fn at(&mut self, world: &World, k: u64) -> [f64; 3] {
        let j = k / self.m;
        if j != self.j {
            if j == self.j + 1 {
                self.a = self.b;
            } else {
                self.a = world.specific_force(j as f64 * self.h_s);
            }
            self.b = world.specific_force((j + 1) as f64 * self.h_s);
            self.j = j;
        }
        let w = (k - j * self.m) as f64 / self.m as f64;
        let (a, b) = (self.a, self.b);
        [a[0] + w * (b[0] - a[0]), a[1] + w * (b[1] - a[1]), a[2] + w * (b[2] - a[2])]
    }
}

/// The simulated receiver's tracking channels: those tracking, and the
/// passes that ended.
struct Receiver<'a> {
    sc: &'a Scenario,
    seed: u64,
    cfg: ChannelConfig,
    tracks: Vec<Track>,
    done: Vec<ChannelSummary>,
}

impl<'a> Receiver<'a> {
    /// No channel tracking yet; channels with the loop filter `coeffs` at `t_s`.
    fn new(sc: &'a Scenario, seed: u64, coeffs: LoopFilterCoeffs, t_s: f64) -> Self {
        let mut cfg = ChannelConfig::new(coeffs, t_s, sc.tracking_loop.discriminator);
        cfg.lock_threshold = sc.tracking_loop.lock_threshold;
        cfg.lock_tau_s = sc.tracking_loop.lock_tau_s;
        let tracks = Vec::with_capacity(sc.satellites.max_channels as usize);
        Receiver { sc, seed, cfg, tracks, done: Vec::new() }
    }

    /// The sky at `t` \[s\], once per geometry step: a track whose satellite
    /// has set stops, the others get their geometry for the next second and
    /// its C/N0; then risen satellites take free channels, highest first
    /// (`delta_f_hz`: Δf now, for the acquisition's hand-over).
    fn update_sky(&mut self, world: &World, t: f64, delta_f_hz: f64) {
        let sc = self.sc;
        let (antenna, mask_deg) = (sc.antenna, sc.satellites.elevation_mask_deg);
        let max_channels = sc.satellites.max_channels as usize;
        let t_gps = world.start_gps_s + t;
        let t_next_gps = t_gps + GEOMETRY_STEP_S;
        let tracks = &mut self.tracks;
        let mut i = 0;
        while i < tracks.len() {
            let tr = &mut tracks[i];
            let now = tr.next;
            if now.elevation_deg < mask_deg {
                self.done.push(tr.summary(t));
                tracks.swap_remove(i);
                continue;
            }
            let next = world.constellation.line_of_sight(tr.prn, &antenna, t_next_gps).expect("tracked PRN exists");
            set_segment(tr, &now, &next, t);
            tr.ch.set_cn0_dbhz(world.cn0.cn0_dbhz(tr.prn, now.elevation_deg));
            i += 1;
        }
        if tracks.len() >= max_channels {
            return;
        }
        for los in world.constellation.visible_lines_of_sight(&antenna, t_gps, mask_deg) {
            if tracks.len() >= max_channels {
                break;
            }
            if tracks.iter().any(|tr| tr.prn == los.prn) {
                continue;
            }
            let channel = (0..).find(|c| !tracks.iter().any(|tr| tr.channel == *c)).unwrap_or(0);
            let next = world.constellation.line_of_sight(los.prn, &antenna, t_next_gps).expect("visible PRN exists");
            let rng = substream(self.seed, stream::CHANNEL | u64::from(los.prn) << 32 | (t as u64 & 0xFFFF_FFFF));
            let carrier = sc.satellites.carrier_of(channel, world.carrier_hz);
            let start = (carrier, t, channel, delta_f_hz);
            let aiding = sc.tracking_loop.doppler_aiding;
            tracks.push(start_track(&self.cfg, &los, &next, start, aiding, sc, &world.cn0, rng));
        }
        tracks.sort_by_key(|tr| tr.channel);
    }

    /// One integration per channel at `t` \[s\], the oscillator's error
    /// on its carrier: its mean `delta_f_hz` over the integration and its mean
    /// weighted by the time left, `weighted_hz` (with Doppler aiding, the NCO
    /// also follows the Doppler).
    fn integrate(&mut self, t: f64, delta_f_hz: f64, weighted_hz: f64) {
        let aiding = self.sc.tracking_loop.doppler_aiding;
        for tr in self.tracks.iter_mut() {
            let f_sig = tr.doppler0_hz + tr.doppler_slope_hz_per_s * (t - tr.seg_t0_s);
            let aided = if aiding { f_sig } else { 0.0 };
            let bias = delta_f_hz * tr.carrier_ratio + aided;
            let bias_weighted = weighted_hz * tr.carrier_ratio + aided;
            tr.ch.step_varying(f_sig, bias, bias_weighted);
        }
    }

    /// Every channel's tracking row at `t` \[s\] into `sink` (not the unlocked
    /// ones with `log.drop_unlocked`).
    fn log_rows<S: SessionSink + ?Sized>(&mut self, t: f64, sink: &mut S) -> Result<(), SimError> {
        let log = &self.sc.log;
        for tr in self.tracks.iter_mut() {
            let snap = tr.ch.take_log();
            if log.drop_unlocked && !snap.locked {
                continue;
            }
            let (phase, truth) = match log.phase {
                LoggedPhase::Last => (snap.last_rad, snap.true_last_rad),
                LoggedPhase::Mean => (snap.mean_rad, snap.true_mean_rad),
            };
            let row = SimulatedRow {
                t_s: t,
                channel: tr.channel,
                prn: tr.prn,
                cn0_dbhz: match log.cn0 {
                    Cn0Logged::Estimated => snap.cn0_est_dbhz,
                    Cn0Logged::True => tr.ch.cn0_true_dbhz(),
                },
                elev_deg: tr.elev0_deg + tr.elev_slope_deg_per_s * (t - tr.seg_t0_s),
                phase_err_rad: phase,
                locked: snap.locked,
                true_phase_err_rad: truth,
                true_cn0_dbhz: tr.ch.cn0_true_dbhz(),
                nco_phase_cycles: snap.nco_phase_cycles,
                nco_freq_hz: snap.nco_freq_hz,
                carrier: tr.carrier,
            };
            sink.tracking(&row).map_err(SimError::Sink)?;
        }
        Ok(())
    }

    /// Every channel pass, those still tracking ending at `end_s` \[s\], by
    /// start then channel.
    fn finish(self, end_s: f64) -> Vec<ChannelSummary> {
        let mut done = self.done;
        done.extend(self.tracks.iter().map(|tr| tr.summary(end_s)));
        done.sort_by(|a, b| a.start_s.total_cmp(&b.start_s).then(a.channel.cmp(&b.channel)));
        done
    }
}

/// M⁻ᵀ·v for a 3×3 matrix M (adjugate / determinant).
pub(crate) fn inverse_transpose_times(m: &[[f64; 3]; 3], v: &[f64; 3]) -> [f64; 3] {
    // Cofactor matrix C: M⁻¹ = Cᵀ/det, so M⁻ᵀ = C/det.
    let c = |i: usize, j: usize| {
        let (r0, r1) = ((i + 1) % 3, (i + 2) % 3);
        let (c0, c1) = ((j + 1) % 3, (j + 2) % 3);
        m[r0][c0] * m[r1][c1] - m[r0][c1] * m[r1][c0]
    };
    let det = m[0][0] * c(0, 0) + m[0][1] * c(0, 1) + m[0][2] * c(0, 2);
    [0, 1, 2].map(|i| (c(i, 0) * v[0] + c(i, 1) * v[1] + c(i, 2) * v[2]) / det)
}

/// Sets a track's linear geometry for the second starting at `t` from the
/// lines of sight at its two ends.
fn set_segment(tr: &mut Track, now: &LineOfSight, next: &LineOfSight, t: f64) {
    let carrier_hz = tr.carrier.carrier_hz;
    let d0 = now.doppler_at_hz(carrier_hz);
    let d1 = next.doppler_at_hz(carrier_hz);
    tr.doppler0_hz = d0;
    tr.doppler_slope_hz_per_s = (d1 - d0) / GEOMETRY_STEP_S;
    tr.elev0_deg = now.elevation_deg;
    tr.elev_slope_deg_per_s = (next.elevation_deg - now.elevation_deg) / GEOMETRY_STEP_S;
    tr.seg_t0_s = t;
    tr.next = *next;
}

#[allow(clippy::too_many_arguments)]
fn start_track(
    cfg: &ChannelConfig,
    now: &LineOfSight,
    next: &LineOfSight,
    (carrier, t, channel, delta_f_hz): (gsens_io::Carrier, f64, u32, f64),
    aiding: bool,
    sc: &Scenario,
    cn0: &Cn0Offsets,
    mut rng: Xoshiro256PlusPlus,
) -> Track {
    // The channel's carrier; Δf on it is f_c·y (ratio exactly 1 on the oscillator's carrier).
    let carrier_hz = carrier.carrier_hz;
    let carrier_ratio = carrier_hz / sc.oscillator.carrier_hz;
    let delta_f_hz = delta_f_hz * carrier_ratio;
    let doppler_hz = now.doppler_at_hz(carrier_hz);
    let rate_hz_per_s = (next.doppler_at_hz(carrier_hz) - doppler_hz) / GEOMETRY_STEP_S;
    let freq_err_hz = normal(&mut rng, sc.tracking_loop.initial_freq_err_hz);
    // Acquisition hands over the apparent carrier frequency: the Doppler seen
    // through the oscillator's offset (the NCO runs at command + Δf).
    let (preload_hz, preload_rate) =
        if aiding { (-delta_f_hz + freq_err_hz, 0.0) } else { (doppler_hz - delta_f_hz + freq_err_hz, rate_hz_per_s) };
    let u: f64 = rng.random();
    let initial_phase_err_rad = PI * (2.0 * u - 1.0);
    let bit_offset = rng.random_range(0..cfg.integrations_per_bit());
    let cn0_dbhz = cn0.cn0_dbhz(now.prn, now.elevation_deg);
    let start = ChannelStart {
        cn0_dbhz,
        preload_freq_hz: preload_hz,
        preload_rate_hz_per_s: preload_rate,
        initial_phase_err_rad,
        bit_offset,
    };
    let mut tr = Track {
        ch: Channel::new(cfg, &start, rng),
        prn: now.prn,
        channel,
        carrier,
        carrier_ratio,
        start_s: t,
        start_elev_deg: now.elevation_deg,
        start_cn0_dbhz: cn0_dbhz,
        cn0_offset_db: cn0.offset_db(now.prn),
        doppler0_hz: 0.0,
        doppler_slope_hz_per_s: 0.0,
        elev0_deg: 0.0,
        elev_slope_deg_per_s: 0.0,
        seg_t0_s: t,
        next: *next,
    };
    set_segment(&mut tr, now, next, t);
    tr
}

#[cfg(test)]
mod tests {
    #[test]
    fn inverse_transpose() {
        let m = [[1.01, 0.002, -0.003], [0.001, 0.99, 0.004], [-0.002, 0.003, 1.005]];
        let g = [0.09, 0.08, -0.08];
        let x = super::inverse_transpose_times(&m, &g);
        // Mᵀx = g.
        for j in 0..3 {
            let mtx: f64 = (0..3).map(|i| m[i][j] * x[i]).sum();
            assert!((mtx - g[j]).abs() < 1e-15, "{j}");
        }
    }
}
