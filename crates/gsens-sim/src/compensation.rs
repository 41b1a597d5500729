//! Compensation in the loop: the receiver feeds −aᵀΓ̂ forward into every
//! carrier NCO, `a` the specific force its IMU measured.
//!
//! The feed-forward of Bhaskar, Curran & Lachapelle (IEEE TAES 51(4), 2015):
//! the oscillator's frequency error Δf = aᵀΓ reaches every carrier NCO; a
//! receiver that knows Γ̂ adds −aᵀΓ̂ (scaled to each carrier) to the NCO
//! command, so the loop sees only Δf − aᵀΓ̂ — what Γ̂'s error, the IMU's
//! errors and its latency leave. The simulator takes the IMU's own samples
//! (with their bias, scale factor, misalignment, noise and time offset, as
//! `imu.csv` has them), each applied from `latency_s` after its stamp until
//! the next one is (a zero-order hold: a receiver updates the NCO command
//! once per IMU sample).

use std::collections::VecDeque;

use gsens_core::Compensator;
use serde::{Deserialize, Serialize};

/// `[compensation]`: the feed-forward of Γ̂ into the carrier NCOs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CompensationSection {
    /// Γ̂ fed forward \[Hz/(m/s²)\] at `oscillator.carrier_hz`, IMU axes
    /// (e.g. a calibration's `gamma_hz_per_mps2`).
    pub gamma_hz_per_mps2: [f64; 3],
    /// Time from an IMU sample's stamp to its use in the NCO command \[s\]
    /// (processing and bus delay, on top of the IMU's own time offset and
    /// the hold until the next sample). Default 0.
    #[serde(default)]
    pub latency_s: f64,
}

/// The correction the NCOs get now, from the IMU samples delivered.
#[derive(Debug, Clone)]
pub(crate) struct FeedForward {
    compensator: Compensator,
    latency_s: f64,
    /// Samples delivered, not yet in use: (stamp, specific force).
    queue: VecDeque<(f64, [f64; 3])>,
    /// −aᵀΓ̂ of the sample in use \[Hz\] (0 before the first).
    correction_hz: f64,
}

impl FeedForward {
    pub(crate) fn new(section: &CompensationSection) -> Self {
        FeedForward {
            compensator: Compensator { gamma_hz_per_mps2: section.gamma_hz_per_mps2 },
            latency_s: section.latency_s,
            queue: VecDeque::with_capacity(16),
            correction_hz: 0.0,
        }
    }

    /// An IMU sample as the receiver gets it: when it has it (the later of
    /// its stamp and the instant it measured) and the measured specific force.
    pub(crate) fn sample(&mut self, stamp_s: f64, measured_mps2: [f64; 3]) {
        self.queue.push_back((stamp_s, measured_mps2));
    }

    /// The correction at loop time `t_s` \[Hz, at the reference carrier\]:
    /// −aᵀΓ̂ of the newest sample whose stamp plus the latency has passed.
    pub(crate) fn correction_hz(&mut self, t_s: f64) -> f64 {
        while let Some(&(stamp, a)) = self.queue.front() {
            if stamp + self.latency_s > t_s {
                break;
            }
            self.correction_hz = self.compensator.nco_correction_hz(&a);
            self.queue.pop_front();
        }
        self.correction_hz
    }
}
