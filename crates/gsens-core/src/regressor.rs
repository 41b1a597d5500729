use crate::pll::{DiscretePll, LOOP_STATE_LEN, LinearLoop, LoopFilterCoeffs, LoopState, ModelLoop};

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

/// What the regressor of a log row models: the row's tracking error, or the
/// NCO frequency the loop commanded during the row's latest integration.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RowQuantity {
    /// The discriminator output φ, as the row holds it: φ = L\[Δf\].
    PhaseError(LoggedPhase),
    /// The NCO command in force during the latest integration (centred on
    /// the row's stamp) \[Hz\], without the oscillator's bias
    /// ([`LinearLoop::nco_freq_hz`]): −H\[Δf\], H the closed-loop transfer.
    NcoFrequency,
    /// The mean of the NCO commands in force over the row's updates \[Hz\]:
    /// the NCO's phase advance over the log interval divided by it (a
    /// carrier phase differenced, or a Doppler averaged over the interval).
    NcoFrequencyMean,
}

/// Errors building a [`RegressorModel`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
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
/// # One log interval in one step
///
/// The loop is linear and the input between two epochs is a linear
/// interpolation of a_{k−1} and a_k, so the n updates of one log interval are
/// one affine map of the loop's state s ([`LinearLoop::state`]) and the two
/// samples (a lifted, or block, recursion):
///
/// ```text
/// s_k = Φ·s_{k−1} + b₀·a_{k−1} + b₁·a_k,    φ_k = c·s_{k−1} + d₀·a_{k−1} + d₁·a_k
/// ```
///
/// `LiftedInterval` finds Φ, b₀, b₁, c, d₀, d₁ by running the n updates
/// from each unit state and each unit sample once; each epoch then costs one
/// 4×4 product per axis instead of n loop updates, whatever n is. The result
/// equals the update-by-update recursion up to rounding.
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
///
/// # Within an integration
///
/// A correlator's discriminator gives the phase error's mean over an
/// integration of T: the oscillator's phase enters averaged over it, for a
/// sinusoid sinc(ωT/2) times its centre value. Each update therefore takes
/// Δf's mean over its integration, not its centre value (the same filter's
/// c carries the step, −(ωT)²/24), advances the replica with it, and feeds
/// the discriminator Δf weighted by the time left in the integration, the
/// mean less T/6 of its slope ([`LinearLoop::step_varying`]). Treating Δf as
/// its centre value throughout would put φ_a (ωT)²/24 low of a correlator's
/// (0.05 % at 0.9 Hz with 20 ms integrations, 2·10⁻⁶ at 1 ms).
#[derive(Debug, Clone, PartialEq)]
pub struct RegressorModel<L = ModelLoop> {
    triad: [L; 3],
    substeps: u32,
    quantity: RowQuantity,
    prev_accel_mps2: Option<[f64; 3]>,
    /// The map of one log interval, when it holds more than one update.
    lifted: Option<LiftedInterval>,
    /// The triad's states between epochs on the lifted path, component by
    /// component: `lanes[j][axis]` (a fourth lane kept at zero).
    lanes: TriadLanes,
}

/// One log interval of a linear loop, n updates on the linear interpolation
/// of two samples, as one affine map (see [`RegressorModel`]):
///
/// ```text
/// s' = Φ·s + b₀·a₀ + b₁·a₁,    φ = c·s + d₀·a₀ + d₁·a₁
/// ```
///
/// φ is what the log row holds ([`LoggedPhase`]). By linearity each column
/// is one run of the n updates: from the unit state e_j with a₀ = a₁ = 0
/// (Φ's column j and c_j), and from rest with (a₀, a₁) = (1, 0) and (0, 1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct LiftedInterval {
    phi: [[f64; LOOP_STATE_LEN]; LOOP_STATE_LEN],
    b_prev: LoopState,
    b_cur: LoopState,
    c: LoopState,
    d_prev: f64,
    d_cur: f64,
}

impl LiftedInterval {
    /// The map of `substeps` updates of `model_loop` (its own state is not
    /// used) whose log row holds `quantity`.
    pub(crate) fn of_loop<L: LinearLoop + Clone>(model_loop: &L, substeps: u32, quantity: RowQuantity) -> Self {
        let run = |state: LoopState, a_prev: f64, a_cur: f64| {
            let mut l = model_loop.clone();
            l.set_state(&state);
            let out = interval_updates(&mut l, a_prev, a_cur, substeps, quantity);
            (l.state(), out)
        };
        let mut phi = [[0.0; LOOP_STATE_LEN]; LOOP_STATE_LEN];
        let mut c = [0.0; LOOP_STATE_LEN];
        for j in 0..LOOP_STATE_LEN {
            let mut unit = [0.0; LOOP_STATE_LEN];
            unit[j] = 1.0;
            let (next, out) = run(unit, 0.0, 0.0);
            for i in 0..LOOP_STATE_LEN {
                phi[i][j] = next[i];
            }
            c[j] = out;
        }
        let (b_prev, d_prev) = run([0.0; LOOP_STATE_LEN], 1.0, 0.0);
        let (b_cur, d_cur) = run([0.0; LOOP_STATE_LEN], 0.0, 1.0);
        LiftedInterval { phi, b_prev, b_cur, c, d_prev, d_cur }
    }

    /// Advances `state` over one interval from sample `a_prev` to `a_cur`;
    /// returns what the row holds: one axis of [`LiftedInterval::step_triad`],
    /// the same operations in the same order.
    #[inline]
    pub(crate) fn step(&self, state: &mut LoopState, a_prev: f64, a_cur: f64) -> f64 {
        let s = *state;
        let mut out = self.d_prev * a_prev + self.d_cur * a_cur;
        for j in 0..LOOP_STATE_LEN {
            out += self.c[j] * s[j];
        }
        for i in 0..LOOP_STATE_LEN {
            let row = &self.phi[i];
            let mut v = self.b_prev[i] * a_prev + self.b_cur[i] * a_cur;
            for j in 0..LOOP_STATE_LEN {
                v += row[j] * s[j];
            }
            state[i] = v;
        }
        out
    }

    /// [`LiftedInterval::step`] for the three axes at once, their states
    /// held component by component (`lanes[j][axis]`, the fourth lane
    /// zero): each axis's arithmetic is `step`'s, the same operations in
    /// the same order (no fused multiply-add), so the same bits, with the
    /// axes side by side in the lanes of a vector register.
    #[inline]
    pub(crate) fn step_triad(&self, lanes: &mut TriadLanes, a_prev: &[f64; 3], a_cur: &[f64; 3]) -> [f64; 3] {
        let s = *lanes;
        let ap = [a_prev[0], a_prev[1], a_prev[2], 0.0];
        let ac = [a_cur[0], a_cur[1], a_cur[2], 0.0];
        let mut out: [f64; 4] = core::array::from_fn(|l| self.d_prev * ap[l] + self.d_cur * ac[l]);
        for j in 0..LOOP_STATE_LEN {
            for l in 0..4 {
                out[l] += self.c[j] * s[j][l];
            }
        }
        for i in 0..LOOP_STATE_LEN {
            let row = &self.phi[i];
            let mut v: [f64; 4] = core::array::from_fn(|l| self.b_prev[i] * ap[l] + self.b_cur[i] * ac[l]);
            for j in 0..LOOP_STATE_LEN {
                for l in 0..4 {
                    v[l] += row[j] * s[j][l];
                }
            }
            lanes[i] = v;
        }
        [out[0], out[1], out[2]]
    }
}

/// The states of a triad's three loops component by component:
/// `lanes[j][axis]` is component j of the axis's state, lane 3 is zero.
type TriadLanes = [[f64; 4]; LOOP_STATE_LEN];

/// The n loop updates of one log interval, one at a time, on the linear
/// interpolation a_prev + (j/n)·(a_cur − a_prev), j = 1…n: the recursion
/// `LiftedInterval` condenses (and its probe). Returns what the log row holds.
///
/// Each update takes the interpolant's value at its centre as the mean over
/// its integration and, for the discriminator's mean phase, that mean less a
/// sixth of the interpolant's change over the update
/// ([`LinearLoop::step_varying`]: Δf weighted by the time left in the
/// integration, to O(T²) of its mean).
fn interval_updates<L: LinearLoop>(l: &mut L, a_prev: f64, a_cur: f64, substeps: u32, quantity: RowQuantity) -> f64 {
    let inv_n = 1.0 / f64::from(substeps);
    let lead = (a_cur - a_prev) * inv_n / 6.0;
    let mut sum = 0.0;
    let mut last = 0.0;
    let (mut nco_last_hz, mut nco_sum_hz) = (0.0, 0.0);
    for j in 1..=substeps {
        let w = f64::from(j) * inv_n;
        nco_last_hz = l.nco_freq_hz();
        nco_sum_hz += nco_last_hz;
        let mean = a_prev + w * (a_cur - a_prev);
        last = l.step_varying(mean, mean - lead);
        sum += last;
    }
    match quantity {
        RowQuantity::PhaseError(LoggedPhase::Last) => last,
        RowQuantity::PhaseError(LoggedPhase::Mean) => sum * inv_n,
        RowQuantity::NcoFrequency => nco_last_hz,
        RowQuantity::NcoFrequencyMean => nco_sum_hz * inv_n,
    }
}

/// The loop updates per log interval, n = `log_interval_s`/`loop_interval_s`:
/// an integer within 1e-6 relative (both intervals finite and positive).
pub fn loop_substeps(loop_interval_s: f64, log_interval_s: f64) -> Result<u32, RegressorError> {
    let ok = |x: f64| x.is_finite() && x > 0.0;
    if !ok(loop_interval_s) || !ok(log_interval_s) {
        return Err(RegressorError::BadInterval);
    }
    let ratio = log_interval_s / loop_interval_s;
    let n = libm::round(ratio);
    if n < 1.0 || libm::fabs(ratio - n) > 1e-6 * ratio {
        return Err(RegressorError::NotAMultiple { log_interval_s, loop_interval_s });
    }
    Ok(n as u32)
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
        Self::of_quantity(model_loop, loop_interval_s, log_interval_s, RowQuantity::PhaseError(logged))
    }

    /// [`RegressorModel::with_loop`] for rows holding `quantity`: with
    /// [`RowQuantity::NcoFrequency`] each epoch returns −H\[a\] per axis \[Hz
    /// per Hz/(m/s²)\], the NCO command a unit sensitivity would cause.
    pub fn of_quantity(
        model_loop: L,
        loop_interval_s: f64,
        log_interval_s: f64,
        quantity: RowQuantity,
    ) -> Result<Self, RegressorError> {
        let substeps = loop_substeps(loop_interval_s, log_interval_s)?;
        let mut l = model_loop;
        l.reset();
        let lifted = (substeps > 1).then(|| LiftedInterval::of_loop(&l, substeps, quantity));
        Ok(RegressorModel {
            triad: [l.clone(), l.clone(), l],
            substeps,
            quantity,
            prev_accel_mps2: None,
            lifted,
            lanes: [[0.0; 4]; LOOP_STATE_LEN],
        })
    }

    /// Loop updates per log epoch.
    pub fn substeps(&self) -> u32 {
        self.substeps
    }

    /// What each epoch's output is.
    pub fn quantity(&self) -> RowQuantity {
        self.quantity
    }

    /// The coefficient c = (1 − 1/n²)/12 − 1/(24n²) of
    /// [`compensate_interpolation`] for this model's n substeps: the first
    /// term undoes the linear interpolation's loss, the second takes each
    /// update's input from a point value to the mean over its integration of
    /// T = h/n (a sinusoid's sinc(ωT/2) ≈ 1 − (ωh)²/(24n²)); −1/24 when the
    /// loop runs at the log rate.
    pub fn interpolation_compensation(&self) -> f64 {
        let n = f64::from(self.substeps);
        (1.0 - 1.0 / (n * n)) / 12.0 - 1.0 / (24.0 * n * n)
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
                for (axis, (pll, a)) in self.triad.iter_mut().zip(accel_mps2).enumerate() {
                    pll.settle(*a);
                    for (lane, x) in self.lanes.iter_mut().zip(pll.state()) {
                        lane[axis] = x;
                    }
                }
                *accel_mps2
            }
        };
        self.prev_accel_mps2 = Some(*accel_mps2);
        let Some(lifted) = &self.lifted else {
            let quantity = self.quantity;
            return [0, 1, 2]
                .map(|axis| interval_updates(&mut self.triad[axis], prev[axis], accel_mps2[axis], 1, quantity));
        };
        lifted.step_triad(&mut self.lanes, &prev, accel_mps2)
    }

    /// The triad's three loops as independent recursions, each in this
    /// model's current state: fed axis i's specific force, the i-th
    /// [`AxisRegressor`] returns what [`RegressorModel::epoch`] returns on
    /// axis i, bit for bit (the same operations in the same order), so the
    /// axes can run on different threads.
    pub fn axes(&self) -> [AxisRegressor<L>; 3] {
        core::array::from_fn(|axis| AxisRegressor {
            model_loop: self.triad[axis].clone(),
            quantity: self.quantity,
            lifted: self.lifted,
            state: core::array::from_fn(|j| self.lanes[j][axis]),
            prev_accel_mps2: self.prev_accel_mps2.map(|a| a[axis]),
        })
    }

    /// Back to rest.
    pub fn reset(&mut self) {
        for p in &mut self.triad {
            p.reset();
        }
        self.lanes = [[0.0; 4]; LOOP_STATE_LEN];
        self.prev_accel_mps2 = None;
    }
}

/// One axis of a [`RegressorModel`] ([`RegressorModel::axes`]): the loop
/// model of that axis alone, φ_a,i = L\[a_i\] epoch by epoch, with the same
/// start (the steady state of the first sample), the same lifted map of one
/// log interval and the same arithmetic as the triad's lane.
#[derive(Debug, Clone, PartialEq)]
pub struct AxisRegressor<L = ModelLoop> {
    model_loop: L,
    quantity: RowQuantity,
    lifted: Option<LiftedInterval>,
    /// The loop's state between epochs on the lifted path.
    state: LoopState,
    prev_accel_mps2: Option<f64>,
}

impl<L: LinearLoop> AxisRegressor<L> {
    /// Advances the loop to the next log epoch, whose specific force on this
    /// axis is `accel_mps2`, and returns φ_a there (what
    /// [`RegressorModel::epoch`] returns on this axis).
    #[inline]
    pub fn epoch(&mut self, accel_mps2: f64) -> f64 {
        let prev = match self.prev_accel_mps2 {
            Some(p) => p,
            None => {
                self.model_loop.settle(accel_mps2);
                self.state = self.model_loop.state();
                accel_mps2
            }
        };
        self.prev_accel_mps2 = Some(accel_mps2);
        match &self.lifted {
            Some(lifted) => lifted.step(&mut self.state, prev, accel_mps2),
            None => interval_updates(&mut self.model_loop, prev, accel_mps2, 1, self.quantity),
        }
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
            accel[k][i] = interpolation_compensated(prev[i], cur[i], next[i], c);
        }
        prev = cur;
    }
}

/// One sample of [`compensate_interpolation`]: a_k + c·(2a_k − a_{k−1} −
/// a_{k+1}) from the sample `cur` and its neighbours `prev` and `next`, for
/// a caller that streams the samples.
#[inline]
pub fn interpolation_compensated(prev: f64, cur: f64, next: f64, c: f64) -> f64 {
    cur + c * (2.0 * cur - prev - next)
}
use crate::units::Decimal;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pll::LoopSpec;
    use crate::pll::gnss_sdr::{GnssSdrPll, GnssSdrStage};
    use crate::pll::pocket_sdr::{PocketSdrPll, PocketSdrStage};

    fn spec(order: u8, bn_hz: f64) -> LoopFilterCoeffs {
        let zeta = core::f64::consts::FRAC_1_SQRT_2;
        LoopSpec::of_order(order, bn_hz, zeta, crate::pll::KAPLAN_A3, crate::pll::KAPLAN_B3).unwrap().coeffs().unwrap()
    }

    /// A deterministic, broadband test input: a sum of incommensurate sines
    /// and a slow ramp [m/s²].
    fn accel(k: usize) -> [f64; 3] {
        let t = k as f64 * 0.025;
        [
            2.0 * libm::sin(5.3 * t) + 0.7 * libm::sin(17.1 * t) + 0.01 * t,
            -1.5 * libm::sin(3.1 * t + 0.4) + 0.9 * libm::cos(23.9 * t),
            9.81 + 0.8 * libm::sin(11.7 * t + 1.0),
        ]
    }

    /// The update-by-update reference: three loops settled on the first
    /// sample, then [`interval_updates`] per epoch.
    fn by_updates<L: LinearLoop + Clone>(l: &L, n: u32, logged: RowQuantity, epochs: usize) -> [f64; 3] {
        let mut triad = [l.clone(), l.clone(), l.clone()];
        let first = accel(0);
        for (pll, a) in triad.iter_mut().zip(first) {
            pll.settle(a);
        }
        let mut prev = first;
        let mut sum_sq = [0.0; 3];
        let mut out = [0.0; 3];
        for k in 0..epochs {
            let a = accel(k);
            for axis in 0..3 {
                out[axis] = interval_updates(&mut triad[axis], prev[axis], a[axis], n, logged);
                sum_sq[axis] += out[axis] * out[axis];
            }
            prev = a;
        }
        sum_sq
    }

    fn assert_lifted_equals_updates<L: LinearLoop + Clone>(l: L, loop_interval_s: f64, log_interval_s: f64) {
        let quantities = [
            RowQuantity::PhaseError(LoggedPhase::Last),
            RowQuantity::PhaseError(LoggedPhase::Mean),
            RowQuantity::NcoFrequency,
            RowQuantity::NcoFrequencyMean,
        ];
        for logged in quantities {
            let n = libm::round(log_interval_s / loop_interval_s) as u32;
            let mut model = RegressorModel::of_quantity(l.clone(), loop_interval_s, log_interval_s, logged).unwrap();
            assert_eq!(model.lifted.is_some(), n > 1);
            let epochs = 4000;
            let want_energy = by_updates(&l, n, logged, epochs);
            let mut energy = [0.0; 3];
            let mut max_rel_err: f64 = 0.0;
            let mut triad = [l.clone(), l.clone(), l.clone()];
            let mut prev = accel(0);
            for (pll, a) in triad.iter_mut().zip(prev) {
                pll.settle(a);
            }
            for k in 0..epochs {
                let a = accel(k);
                let got = model.epoch(&a);
                let want = [0, 1, 2].map(|axis| interval_updates(&mut triad[axis], prev[axis], a[axis], n, logged));
                prev = a;
                for axis in 0..3 {
                    energy[axis] += got[axis] * got[axis];
                    let scale = libm::sqrt(want_energy[axis] / epochs as f64);
                    max_rel_err = max_rel_err.max(libm::fabs(got[axis] - want[axis]) / scale);
                }
            }
            // Rounding only: the lifted map and the n updates differ in the
            // order of their sums, not in what they compute.
            assert!(max_rel_err < 1e-11, "{logged:?} n = {n}: {max_rel_err:e} of the RMS");
            for axis in 0..3 {
                assert!(libm::fabs(energy[axis] / want_energy[axis] - 1.0) < 1e-11);
            }
            // After reset the model starts again from the first sample's steady state.
            model.reset();
            let mut fresh = RegressorModel::of_quantity(l.clone(), loop_interval_s, log_interval_s, logged).unwrap();
            for k in 0..3 {
                assert_eq!(model.epoch(&accel(k)), fresh.epoch(&accel(k)));
            }
        }
    }

    #[test]
    fn one_log_interval_in_one_step_equals_its_updates_for_every_loop_kind() {
        let kaplan2 = spec(2, 3.0);
        let kaplan3 = spec(3, 10.0);
        assert_lifted_equals_updates(DiscretePll::new(kaplan2, 0.001), 0.001, 0.025);
        assert_lifted_equals_updates(DiscretePll::new(kaplan3, 0.001), 0.001, 0.025);
        assert_lifted_equals_updates(DiscretePll::new(kaplan2, 0.005), 0.005, 0.1);
        assert_lifted_equals_updates(DiscretePll::new(kaplan2, 0.025), 0.025, 0.025);
        let gnss_sdr = GnssSdrPll::new(GnssSdrStage { order: 3, bw_hz: 15.0, symbols: 1 }).unwrap();
        assert_lifted_equals_updates(ModelLoop::from(gnss_sdr), 0.001, 0.02);
        let pocket = PocketSdrPll::new(PocketSdrStage::l1ca(5.0)).unwrap();
        assert_lifted_equals_updates(ModelLoop::from(pocket), pocket.stage().interval_s, 0.02);
    }

    #[test]
    fn the_triad_step_is_three_single_steps_bit_for_bit() {
        let l = DiscretePll::new(spec(3, 15.0), 0.001);
        let lifted = LiftedInterval::of_loop(&l, 25, RowQuantity::PhaseError(LoggedPhase::Mean));
        let mut states = [[0.0; LOOP_STATE_LEN]; 3];
        let mut lanes: TriadLanes = [[0.0; 4]; LOOP_STATE_LEN];
        // A seeded linear congruential sequence of specific forces [m/s²].
        let mut seed: u64 = 7;
        let mut next = || {
            seed = seed.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 * 20.0 - 10.0
        };
        let mut prev = [0.0; 3];
        for _ in 0..2000 {
            let cur = [next(), next(), next()];
            let single: [f64; 3] = core::array::from_fn(|axis| lifted.step(&mut states[axis], prev[axis], cur[axis]));
            let triad = lifted.step_triad(&mut lanes, &prev, &cur);
            assert_eq!(single.map(f64::to_bits), triad.map(f64::to_bits));
            for j in 0..LOOP_STATE_LEN {
                let axes: [f64; 3] = core::array::from_fn(|axis| states[axis][j]);
                assert_eq!(axes.map(f64::to_bits), [lanes[j][0], lanes[j][1], lanes[j][2]].map(f64::to_bits));
                assert_eq!(lanes[j][3], 0.0);
            }
            prev = cur;
        }
    }

    #[test]
    fn the_lifted_map_is_the_updates_state_space_raised_to_n() {
        // Φ = Aⁿ: the state transition of n updates with no input.
        let l = DiscretePll::new(spec(2, 3.0), 0.001);
        let (a, _, _, _) = crate::pll::loop_state_space(&l);
        let lifted = LiftedInterval::of_loop(&l, 25, RowQuantity::PhaseError(LoggedPhase::Last));
        let a_n = a.pow(25);
        for i in 0..LOOP_STATE_LEN {
            for j in 0..LOOP_STATE_LEN {
                let scale = a_n.abs().max().max(1.0);
                assert!(libm::fabs(lifted.phi[i][j] - a_n[(i, j)]) < 1e-12 * scale, "({i}, {j})");
            }
        }
    }
}
