//! The simulated world every driver runs in ([`crate::session::simulate`]
//! for the logs, [`crate::iq::generate_iq`] for IF samples): the scenario's
//! oscillator, hand motion, IMU, C/N0 offsets and sky, each drawn from its
//! own stream of the one seed, and the IMU log written as the drivers'
//! receiver time advances.

use crate::imu::{ImuErrors, specific_force_body};
use crate::motion::Motion;
use crate::oscillator::Oscillator;
use crate::rng::{Xoshiro256PlusPlus, substream};
use crate::satellites::{Cn0Offsets, Constellation};
use crate::scenario::Scenario;
use crate::session::{SensitivityTruth, SessionSink, SimError};

/// Stream ids of [`crate::rng::substream`] for the world's components (one
/// set for both drivers, so both draw the same oscillator, motion and IMU).
pub(crate) mod stream {
    pub(crate) const OSCILLATOR: u64 = 1;
    pub(crate) const MOTION: u64 = 2;
    pub(crate) const IMU_ERRORS: u64 = 3;
    pub(crate) const IMU_NOISE: u64 = 4;
    pub(crate) const CN0_OFFSETS: u64 = 5;
    /// Channel streams: CHANNEL | prn << 32 | start second.
    pub(crate) const CHANNEL: u64 = 0xC4A7 << 48;
}

/// The world of a scenario and seed.
pub(crate) struct World {
    /// GPS seconds at receiver time 0.
    pub start_gps_s: f64,
    /// The scenario's duration \[s\].
    pub duration_s: f64,
    /// The oscillator's carrier \[Hz\].
    pub carrier_hz: f64,
    /// Γ \[Hz/(m/s²)\] at that carrier, body axes.
    pub gamma: [f64; 3],
    /// The oscillator, averaged over the driver's step.
    pub osc: Oscillator,
    pub motion: Motion,
    /// The IMU's realized errors and time offset.
    pub imu: ImuErrors,
    imu_rng: Xoshiro256PlusPlus,
    /// The next IMU sample to log.
    next_imu: u64,
    pub cn0: Cn0Offsets,
    pub constellation: Constellation,
}

/// Which IMU stamps [`World::log_imu`] logs, besides none beyond the duration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum ImuUntil {
    /// Stamps at or before this time \[s\].
    Through(f64),
    /// Stamps before this time \[s\].
    Before(f64),
    /// Every stamp up to the duration.
    End,
}

impl World {
    /// The world of `scenario` and `seed`, its oscillator averaged over the
    /// driver's step `step_s` \[s\].
    pub(crate) fn new(scenario: &Scenario, seed: u64, step_s: f64) -> Result<World, SimError> {
        let sc = scenario;
        let start_gps_s = sc.start_gps_s()?;
        let osc = Oscillator::try_new(&sc.oscillator.config(), step_s, substream(seed, stream::OSCILLATOR))?;
        let motion = Motion::try_new(&sc.motion, &mut substream(seed, stream::MOTION))?;
        Ok(World {
            start_gps_s,
            duration_s: sc.duration_s(),
            carrier_hz: sc.oscillator.carrier_hz,
            gamma: sc.oscillator.gamma_hz_per_mps2,
            osc,
            motion,
            imu: ImuErrors::draw(&sc.imu.config(), &mut substream(seed, stream::IMU_ERRORS)),
            imu_rng: substream(seed, stream::IMU_NOISE),
            next_imu: 0,
            cn0: sc.satellites.cn0.draw_offsets(&mut substream(seed, stream::CN0_OFFSETS)),
            constellation: Constellation::builtin(),
        })
    }

    /// The true specific force at receiver time `t_s`, body axes \[m/s²\].
    pub(crate) fn specific_force(&self, t_s: f64) -> [f64; 3] {
        specific_force_body(&self.motion.state(t_s))
    }

    /// The frequency error aᵀΓ \[Hz\] the specific force `a` \[m/s²\] puts on the carrier.
    pub(crate) fn g_induced_hz(&self, a: &[f64; 3]) -> f64 {
        a[0] * self.gamma[0] + a[1] * self.gamma[1] + a[2] * self.gamma[2]
    }

    /// Logs the IMU samples not logged yet whose stamps lie within `until`
    /// and the duration, in order, into `sink`, and hands each to `on_sample`
    /// with the time it reaches the receiver (its stamp, or the true time it
    /// was taken when later) and its reading.
    pub(crate) fn log_imu<S: SessionSink + ?Sized>(
        &mut self,
        until: ImuUntil,
        sink: &mut S,
        mut on_sample: impl FnMut(f64, [f64; 3]),
    ) -> Result<(), SimError> {
        loop {
            let stamp = self.imu.stamp_s(self.next_imu);
            let beyond = match until {
                ImuUntil::Through(t) => stamp > t,
                ImuUntil::Before(t) => stamp >= t,
                ImuUntil::End => false,
            };
            if beyond || stamp > self.duration_s + 1e-9 {
                return Ok(());
            }
            let true_time_s = self.imu.true_time_s(self.next_imu);
            let m = self.imu.measure(self.specific_force(true_time_s), &mut self.imu_rng);
            sink.imu(stamp, m).map_err(SimError::Sink)?;
            on_sample(stamp.max(true_time_s), m);
            self.next_imu += 1;
        }
    }

    /// Γ as simulated, at the carrier and through the IMU's sensing matrix.
    pub(crate) fn sensitivity(&self) -> SensitivityTruth {
        SensitivityTruth::new(self.gamma, self.carrier_hz, &self.imu.sensing_matrix())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::session::MemorySink;

    #[test]
    fn the_imu_log_stops_where_asked_and_at_the_duration() {
        let mut sc = Scenario::default();
        sc.imu.rate_hz = 40.0;
        let mut world = World::new(&sc, 7, 0.001).unwrap();
        let mut sink = MemorySink::default();
        let mut handed = Vec::new();
        world.log_imu(ImuUntil::Through(0.05), &mut sink, |t, _| handed.push(t)).unwrap();
        assert_eq!(sink.imu.iter().map(|s| s.0).collect::<Vec<_>>(), [0.0, 0.025, 0.05]);
        world.log_imu(ImuUntil::Before(0.1), &mut sink, |_, _| {}).unwrap();
        assert_eq!(sink.imu.len(), 4);
        world.log_imu(ImuUntil::End, &mut sink, |_, _| {}).unwrap();
        let last = sink.imu.last().unwrap().0;
        assert!(last <= world.duration_s + 1e-9 && last + 0.025 > world.duration_s + 1e-9, "{last}");
        assert_eq!(handed.len(), 3);
        // The same seed gives the same IMU log.
        let mut again = MemorySink::default();
        World::new(&sc, 7, 0.001).unwrap().log_imu(ImuUntil::Through(0.05), &mut again, |_, _| {}).unwrap();
        assert_eq!(again.imu[..], sink.imu[..3]);
    }

    #[test]
    fn the_g_induced_frequency_is_a_dot_gamma() {
        let mut sc = Scenario::default();
        sc.oscillator.gamma_hz_per_mps2 = [0.5, -0.25, 2.0];
        let world = World::new(&sc, 1, 0.02).unwrap();
        assert_eq!(world.g_induced_hz(&[2.0, 4.0, 0.5]), 1.0 - 1.0 + 1.0);
        assert_eq!(world.sensitivity().gamma_hz_per_mps2, [0.5, -0.25, 2.0]);
    }
}
