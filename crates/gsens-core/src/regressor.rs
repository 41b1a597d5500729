use crate::pll::{DiscretePll, LinearLoop, LoopFilterCoeffs, ModelLoop};

/// What a tracking-log row reports when the loop runs faster than the log.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "lowercase"))]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum LoggedPhase {
    /// The latest discriminator output.
    Last,
    /// The mean of the discriminator outputs since the previous row.
    Mean,
}

impl LoggedPhase {
    /// Its name in scenarios, result documents and on the command line
    /// (`--logged-phase`): `last` or `mean`, as serde and clap spell it.
    pub const fn name(self) -> &'static str {
        match self {
            LoggedPhase::Last => "last",
            LoggedPhase::Mean => "mean",
        }
    }
}

/// Errors building a [`RegressorModel`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum RegressorError {
    /// The log interval is not an integer multiple of the loop interval.
    NotAMultiple {
        /// Log interval \[s\].
        log_interval_s: f64,
        /// Loop interval \[s\].
        loop_interval_s: f64,
    },
    /// An interval is not finite and positive.
    BadInterval,
}

impl core::fmt::Display for RegressorError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            RegressorError::NotAMultiple { log_interval_s, loop_interval_s } => write!(
                f,
                "the log interval {} s is not an integer multiple of the loop interval {} s",
                Decimal(*log_interval_s),
                Decimal(*loop_interval_s)
            ),
            RegressorError::BadInterval => write!(f, "loop and log intervals must be finite and positive"),
        }
    }
}

impl core::error::Error for RegressorError {}

/// φ_a = L\[a\] epoch by epoch: three identical loop models, one per axis
/// ([`DiscretePll`]s from [`RegressorModel::new`], any [`LinearLoop`] from
/// [`RegressorModel::with_loop`]).
///
/// The triad of software loop models fed by a_x, a_y, a_z: φ_a = L\[a\].
///
/// The model loop runs at the receiver's loop update interval T_loop, which
/// may be shorter than the log interval T_log = n·T_loop. Between two log
/// epochs the specific force is interpolated linearly (the loop is far slower
/// than the log rate, so the interpolation error is second order in the log
/// interval). What a log row holds depends on the receiver:
///
/// - [`LoggedPhase::Last`]: the discriminator output of the integration
///   centred on the row's time stamp (the last one before the row is written);
/// - [`LoggedPhase::Mean`]: the mean of the n discriminator outputs since the
///   previous row, time-stamped like `Last` at the centre of the latest one.
///
/// With n = 1 the two are the same.
///
/// # Interpolation and its compensation
///
/// Linear interpolation of the samples a_k onto the n loop updates between two
/// epochs is a triangular upsampling kernel: a sinusoid of angular frequency ω
/// comes out scaled by ≈ 1 − (1 − 1/n²)·(ωh)²/12 (h the log interval), −0.17 %
/// at 0.9 Hz and 40 Hz. φ_a would be too small by as much and Γ̂ too large
/// (the bias is of the order of the Cramér–Rao bound of a paper-like session).
/// A batch caller can remove it with [`compensate_interpolation`], the
/// three-tap filter a_k + c·(2a_k − a_{k−1} − a_{k+1}), c =
/// [`RegressorModel::interpolation_compensation`], whose gain 1 + 2c·(1 − cos ωh)
/// cancels the kernel's to O((ωh)⁴); it needs the next sample, so the
/// per-epoch path does without it.
#[derive(Debug, Clone, PartialEq)]
pub struct RegressorModel<L = ModelLoop> {
    triad: [L; 3],
    substeps: u32,
    logged: LoggedPhase,
    prev_accel_mps2: Option<[f64; 3]>,
}

impl RegressorModel<ModelLoop> {
    /// A triad at rest for a loop with `coeffs` updated every
    /// `loop_interval_s`, sampled every `log_interval_s` (an integer multiple
    /// of it, within 1e-6 relative).
    pub fn new(
        coeffs: LoopFilterCoeffs,
        loop_interval_s: f64,
        log_interval_s: f64,
        logged: LoggedPhase,
    ) -> Result<Self, RegressorError> {
        Self::with_loop(DiscretePll::new(coeffs, loop_interval_s).into(), loop_interval_s, log_interval_s, logged)
    }
}

impl<L: LinearLoop + Clone> RegressorModel<L> {
    /// A triad of copies of `model_loop` (at rest), a loop updated every
    /// `loop_interval_s`, sampled every `log_interval_s` (an integer multiple
    /// of it, within 1e-6 relative).
    pub fn with_loop(
        model_loop: L,
        loop_interval_s: f64,
        log_interval_s: f64,
        logged: LoggedPhase,
    ) -> Result<Self, RegressorError> {
        let ok = |x: f64| x.is_finite() && x > 0.0;
        if !ok(loop_interval_s) || !ok(log_interval_s) {
            return Err(RegressorError::BadInterval);
        }
        let ratio = log_interval_s / loop_interval_s;
        let n = libm::round(ratio);
        if n < 1.0 || libm::fabs(ratio - n) > 1e-6 * ratio {
            return Err(RegressorError::NotAMultiple { log_interval_s, loop_interval_s });
        }
        let mut l = model_loop;
        l.reset();
        Ok(RegressorModel { triad: [l.clone(), l.clone(), l], substeps: n as u32, logged, prev_accel_mps2: None })
    }

    /// Loop updates per log epoch.
    pub fn substeps(&self) -> u32 {
        self.substeps
    }

    /// The coefficient c = (1 − 1/n²)/12 of [`compensate_interpolation`] for
    /// this model's n substeps (0 when the loop runs at the log rate: nothing
    /// is interpolated).
    pub fn interpolation_compensation(&self) -> f64 {
        let n = f64::from(self.substeps);
        (1.0 - 1.0 / (n * n)) / 12.0
    }

    /// Advances the triad to the next log epoch, whose specific force is
    /// `accel_mps2`, and returns φ_a there \[rad per Hz/(m/s²)·(m/s²)\], i.e. the
    /// phase error each axis would cause with a unit sensitivity.
    #[inline]
    pub fn epoch(&mut self, accel_mps2: &[f64; 3]) -> [f64; 3] {
        let prev = match self.prev_accel_mps2 {
            Some(p) => p,
            None => {
                // The receiver was tracking before the log began: start each
                // model loop in the steady state of the first sample.
                for (pll, a) in self.triad.iter_mut().zip(accel_mps2) {
                    pll.settle(*a);
                }
                *accel_mps2
            }
        };
        self.prev_accel_mps2 = Some(*accel_mps2);
        let n = self.substeps;
        if n == 1 {
            return [
                self.triad[0].step(accel_mps2[0]),
                self.triad[1].step(accel_mps2[1]),
                self.triad[2].step(accel_mps2[2]),
            ];
        }
        let inv_n = 1.0 / n as f64;
        let mut sum = [0.0; 3];
        let mut last = [0.0; 3];
        for j in 1..=n {
            let w = j as f64 * inv_n;
            for axis in 0..3 {
                let a = prev[axis] + w * (accel_mps2[axis] - prev[axis]);
                last[axis] = self.triad[axis].step(a);
                sum[axis] += last[axis];
            }
        }
        match self.logged {
            LoggedPhase::Last => last,
            LoggedPhase::Mean => [sum[0] * inv_n, sum[1] * inv_n, sum[2] * inv_n],
        }
    }

    /// Back to rest.
    pub fn reset(&mut self) {
        for p in &mut self.triad {
            p.reset();
        }
        self.prev_accel_mps2 = None;
    }
}

/// Applies a_k ← a_k + c·(2a_k − a_{k−1} − a_{k+1}) to every sample in place
/// (at the ends the missing neighbour is the sample itself): the compensation
/// of the linear interpolation between epochs (see the module docs).
pub fn compensate_interpolation(accel: &mut [[f64; 3]], c: f64) {
    if c == 0.0 || accel.len() < 2 {
        return;
    }
    let mut prev = accel[0];
    for k in 0..accel.len() {
        let cur = accel[k];
        let next = if k + 1 < accel.len() { accel[k + 1] } else { cur };
        for i in 0..3 {
            accel[k][i] = cur[i] + c * (2.0 * cur[i] - prev[i] - next[i]);
        }
        prev = cur;
    }
}
use crate::units::Decimal;
