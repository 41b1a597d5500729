//! PocketSDR's carrier loop, exactly: the PLL of `pocket_trk` (T. Takasu's
//! PocketSDR, `src/sdr_ch.c`, version 0.17), as a linear model from the NCO
//! frequency bias Δf to the discriminator output φ, one step per code period.
//!
//! Read from its source and checked on its own logs of files whose truth is
//! known (`gsens simulate --iq`, `tests/` of `gsens-pocketsdr`): driven by the
//! true carrier of each satellite, this model reproduces the `err_phas`
//! column of `pocket_trk`'s `$CH` lines to the thermal noise (residual RMS
//! 0.136 rad against the 0.139 rad that C/N0 = 44.2 dB-Hz predicts for a 1 ms
//! discriminator; with the sign of φ flipped the residual is 0.285 rad).
//!
//! # One update
//!
//! For GPS L1 C/A a channel is updated once per 1 ms block of samples
//! (T, the code period; block k spans receiver time \[k·T, (k + 1)·T)). The
//! replica carrier over block k starts at phase ψ_k and runs at the NCO
//! frequency f_k; the prompt correlation over the block gives the Costas
//! discriminator c_k = atan(Q/I)/2π \[cycles\] (`err_phas`). After the first
//! second of tracking (an FLL pull-in, not modelled: it ends before the loop
//! the estimator uses), each update runs a 3rd-order loop with
//! ω = `b_pll`/0.7845 (b_pll the noise bandwidth, 5 Hz unless set):
//!
//! ```text
//! A_k     = A_{k−1} + ω³·T·c_k                                   frequency-rate accumulator [Hz/s]
//! f_{k+1} = f_k + 2.4·ω·(c_k − c_{k−1}) + 1.1·ω²·T·c_k + T·A_k   NCO frequency for the next block [Hz]
//! ψ_{k+1} = ψ_k + T·f_{k+1}
//! ```
//!
//! The last line is the booking quirk: the phase at the start of the next
//! block advances by the *new* frequency times T, while block k's replica ran
//! at f_k. The replica therefore jumps by T·(f_{k+1} − f_k) at every block
//! boundary, and a new frequency acts on the next block's phase without
//! latency. The filter is Kaplan's 3rd-order F(s) = 2.4·ω + 1.1·ω²/s + ω³/s²
//! with rectangular integrators, in incremental form.
//!
//! # The linear model
//!
//! With e_k = θ_signal − θ_replica at the start of block k \[rad\] and g_k
//! the signal's carrier frequency relative to the replica's nominal over the
//! block (g_k = −Δf_k: the oscillator bias adds to the NCO,
//! docs/conventions.md), the mean phase error over the block and the next
//! start error are
//!
//! ```text
//! φ_k     = e_k + π·T·(g_k − f_k)              (c_k = φ_k/2π)
//! e_{k+1} = e_k + 2π·T·(g_k − f_{k+1})
//! ```
//!
//! and in z (the filter's D(z) = (1 − z⁻¹)·[c0 + c1·T/(1 − z⁻¹) + c2·T²/(1 − z⁻¹)²],
//! c0 = 2.4ω, c1 = 1.1ω², c2 = ω³)
//!
//! ```text
//! L(z) = φ/Δf = −2π·T·(z + 1)·(z − 1) / [2·(z − 1)² + T·(3z − 1)·D(z)]    [rad/Hz]
//! ```
//!
//! which tends to the continuous −2π/(s + F(s)) as T → 0 (z = e^{sT}). A loop
//! booking the phase with the old frequency (a continuous replica) has
//! (z + 1) where this one has (3z − 1): the two differ by O(2πf·T) in phase,
//! below 1 % in the band a calibration shakes.

use nalgebra::{Complex, Matrix4};

use super::{LinearLoop, LoopError, LoopFilterCoeffs, LoopState};
use crate::math::{PI, TAU, cos, sin};

/// `b_pll` when neither the options file nor the command line sets it
/// (PocketSDR's `B_PLL`) \[Hz\].
pub const DEFAULT_BW_HZ: f64 = 5.0;
/// ω = b_pll / this (PocketSDR's Bn/ωn of Kaplan's 3rd-order loop).
pub const BN_OVER_W: f64 = 0.7845;
/// a₃ of PocketSDR's loop (the ω² path).
pub const A3: f64 = 1.1;
/// b₃ of PocketSDR's loop (the proportional path).
pub const B3: f64 = 2.4;
/// Tracking time during which PocketSDR runs its FLL instead of the PLL
/// (`T_FPULLIN`) \[s\].
pub const FLL_PULL_IN_S: f64 = 1.0;
/// GPS L1 C/A code period: PocketSDR's update interval for that signal \[s\].
pub use crate::units::L1CA_CODE_PERIOD_S;

/// PocketSDR's carrier loop for one signal: bandwidth and update interval.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct PocketSdrStage {
    /// The PLL noise bandwidth `b_pll` \[Hz\].
    pub bw_hz: f64,
    /// The update interval T, the signal's code period (1 ms for L1 C/A) \[s\].
    pub interval_s: f64,
}

impl PocketSdrStage {
    /// The GPS L1 C/A loop with bandwidth `bw_hz` (T = 1 ms).
    pub fn l1ca(bw_hz: f64) -> Self {
        PocketSdrStage { bw_hz, interval_s: L1CA_CODE_PERIOD_S }
    }

    /// ω = b_pll/0.7845 \[rad/s\].
    pub fn w_rad_per_s(&self) -> f64 {
        self.bw_hz / BN_OVER_W
    }

    /// The filter as continuous coefficients: c0 = 2.4ω, c1 = 1.1ω², c2 = ω³
    /// (Kaplan's 3rd-order filter, whose discretization is in the module docs).
    pub fn coeffs(&self) -> LoopFilterCoeffs {
        let w = self.w_rad_per_s();
        LoopFilterCoeffs { c0_per_s: B3 * w, c1_per_s2: A3 * w * w, c2_per_s3: w * w * w }
    }

    /// Checks that the bandwidth and interval are finite and positive.
    pub fn check(&self) -> Result<(), LoopError> {
        if !(self.bw_hz.is_finite() && self.bw_hz > 0.0) {
            return Err(LoopError::NonPositiveParameter("bw_hz"));
        }
        if !(self.interval_s.is_finite() && self.interval_s > 0.0) {
            return Err(LoopError::NonPositiveParameter("interval_s"));
        }
        Ok(())
    }

    /// The characteristic polynomial of L(z) (module docs), multiplied out by
    /// z·(z − 1), coefficients of z⁰…z⁴:
    ///
    /// ```text
    /// P(z) = 2z·(z − 1)³ + T·(3z − 1)·[c0·(z − 1)² + c1·T·z·(z − 1) + c2·T²·z²]
    /// ```
    fn characteristic(&self) -> [f64; 5] {
        let c = self.coeffs();
        let t = self.interval_s;
        let q = [c.c0_per_s, -2.0 * c.c0_per_s - c.c1_per_s2 * t, c.c0_per_s + c.c1_per_s2 * t + c.c2_per_s3 * t * t];
        [-t * q[0], -2.0 + t * (3.0 * q[0] - q[1]), 6.0 + t * (3.0 * q[1] - q[2]), -6.0 + 3.0 * t * q[2], 2.0]
    }

    /// The largest modulus of the roots of the characteristic polynomial
    /// (eigenvalues of its companion matrix): the loop is stable below 1.
    pub fn spectral_radius(&self) -> f64 {
        let p = self.characteristic();
        let mut m = Matrix4::zeros();
        for i in 1..4 {
            m[(i, i - 1)] = 1.0;
        }
        for i in 0..4 {
            m[(i, 3)] = -p[i] / p[4];
        }
        // A matrix the Schur iteration cannot handle counts as unstable (radius +∞).
        crate::math::SpectralRadius::spectral_radius(m).unwrap_or(f64::INFINITY)
    }

    /// Whether the loop is stable: every root of its characteristic
    /// polynomial strictly inside the unit circle.
    pub fn is_stable(&self) -> bool {
        self.check().is_ok() && self.spectral_radius() < 1.0 - 1e-12
    }

    /// Time for the slowest natural mode to decay by e⁻ⁿ, n = `time_constants`:
    /// n·T/(−ln ρ), ρ the spectral radius \[s\] (infinite when unstable).
    /// One time constant is 1/(0.1485·ω) in the continuous limit (1.06 s at 5 Hz, 0.53 s at 10 Hz);
    /// at T = 1 ms it is 1.046 s and 0.518 s.
    pub fn settling_time_s(&self, time_constants: f64) -> f64 {
        super::settling_time_s(Some(self.spectral_radius()), self.interval_s, time_constants)
    }

    /// The response L(e^{j2πfT}) = φ/Δf of the module docs \[rad/Hz\], at `f_hz`.
    pub fn response(&self, f_hz: f64) -> Complex<f64> {
        let c = self.coeffs();
        let t = self.interval_s;
        let w = TAU * f_hz * t;
        let z = Complex::new(cos(w), sin(w));
        let one = Complex::new(1.0, 0.0);
        let zm1 = z - one;
        if zm1.norm_sqr() < 1e-300 {
            return Complex::new(0.0, 0.0);
        }
        let acc = z / zm1; // 1/(1 − z⁻¹)
        let d = (zm1 / z)
            * (Complex::new(c.c0_per_s, 0.0)
                + Complex::new(c.c1_per_s2 * t, 0.0) * acc
                + Complex::new(c.c2_per_s3 * t * t, 0.0) * acc * acc);
        let num = Complex::new(-TAU * t, 0.0) * (z + one) * zm1;
        let den = Complex::new(2.0, 0.0) * zm1 * zm1 + Complex::new(t, 0.0) * (Complex::new(3.0, 0.0) * z - one) * d;
        num / den
    }
}

/// PocketSDR's carrier loop as a linear model Δf → φ (module docs): one
/// [`LinearLoop::step`] per code period.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PocketSdrPll {
    stage: PocketSdrStage,
    /// ω \[rad/s\].
    w: f64,
    /// e: phase error at the start of the current block \[rad\].
    err_start_rad: f64,
    /// f: NCO frequency during the current block, relative to nominal \[Hz\].
    nco_hz: f64,
    /// A: the frequency-rate accumulator \[Hz/s\].
    acc_hz_per_s: f64,
    /// c_{k−1}: the previous discriminator output \[cycles\].
    prev_cycles: f64,
}

impl PocketSdrPll {
    /// A loop at rest running `stage`.
    pub fn new(stage: PocketSdrStage) -> Result<Self, LoopError> {
        stage.check()?;
        Ok(PocketSdrPll {
            stage,
            w: stage.w_rad_per_s(),
            err_start_rad: 0.0,
            nco_hz: 0.0,
            acc_hz_per_s: 0.0,
            prev_cycles: 0.0,
        })
    }

    /// The stage it runs.
    pub fn stage(&self) -> PocketSdrStage {
        self.stage
    }

    /// The NCO frequency during the next block, relative to nominal \[Hz\].
    pub fn nco_hz(&self) -> f64 {
        self.nco_hz
    }

    /// One update with the signal's carrier `signal_hz` relative to the
    /// replica's nominal over the block (g = −Δf); returns φ \[rad\].
    #[inline]
    pub fn step_signal(&mut self, signal_hz: f64) -> f64 {
        self.step_signal_varying(signal_hz, signal_hz)
    }

    /// [`PocketSdrPll::step_signal`] for a signal frequency that varies over
    /// the integration: its mean `signal_hz` and its mean weighted by the time
    /// left, `weighted_hz` ([`LinearLoop::step_varying`]).
    pub fn step_signal_varying(&mut self, signal_hz: f64, weighted_hz: f64) -> f64 {
        let t = self.stage.interval_s;
        let w = self.w;
        let phi = self.err_start_rad + PI * t * (weighted_hz - self.nco_hz);
        let c = phi * (0.5 / PI);
        self.acc_hz_per_s += w * w * w * t * c;
        let f_next = self.nco_hz + B3 * w * (c - self.prev_cycles) + A3 * w * w * t * c + t * self.acc_hz_per_s;
        self.prev_cycles = c;
        self.err_start_rad += TAU * t * (signal_hz - f_next);
        self.nco_hz = f_next;
        phi
    }
}

impl LinearLoop for PocketSdrPll {
    #[inline]
    fn step_varying(&mut self, delta_f_hz: f64, weighted_hz: f64) -> f64 {
        self.step_signal_varying(-delta_f_hz, -weighted_hz)
    }

    fn settle(&mut self, delta_f_hz: f64) {
        self.reset();
        self.nco_hz = -delta_f_hz;
    }

    fn reset(&mut self) {
        self.err_start_rad = 0.0;
        self.nco_hz = 0.0;
        self.acc_hz_per_s = 0.0;
        self.prev_cycles = 0.0;
    }

    fn nco_freq_hz(&self) -> f64 {
        self.nco_hz
    }

    /// (e, f, A, c_{k−1}) of the step's recursion.
    fn state(&self) -> LoopState {
        [self.err_start_rad, self.nco_hz, self.acc_hz_per_s, self.prev_cycles]
    }

    fn set_state(&mut self, state: &LoopState) {
        [self.err_start_rad, self.nco_hz, self.acc_hz_per_s, self.prev_cycles] = *state;
    }
}

#[cfg(test)]
mod tests {
    use super::super::sinusoid_response::assert_sinusoid_response;
    use super::*;

    fn pll(bw_hz: f64) -> PocketSdrPll {
        PocketSdrPll::new(PocketSdrStage::l1ca(bw_hz)).unwrap()
    }

    #[test]
    fn the_filter_is_kaplans_rectangular_filter_in_incremental_form() {
        // Open loop, f_{k+1} − f_k must equal the first difference of the
        // core's rectangular-rule filter output for the same inputs.
        let stage = PocketSdrStage::l1ca(5.0);
        let mut core = super::super::LoopFilter::new(stage.coeffs(), stage.interval_s);
        let mut l = pll(5.0);
        let cycles = [0.01, -0.02, 0.005, 0.03, 0.0, -0.011];
        let mut prev_core = 0.0;
        let mut prev_nco = 0.0;
        for (k, &c) in cycles.iter().enumerate() {
            // Drive φ = 2π·c exactly: with e = 0 and g = f the step's φ is its e.
            l.err_start_rad = TAU * c;
            let g = l.nco_hz;
            l.step_signal(g);
            let out = core.update(TAU * c);
            if k > 0 {
                assert!(((l.nco_hz - prev_nco) - (out - prev_core)).abs() < 1e-12, "{k}");
            }
            prev_core = out;
            prev_nco = l.nco_hz;
        }
    }

    #[test]
    fn a_constant_bias_and_a_frequency_ramp_leave_no_steady_error() {
        let mut l = pll(5.0);
        l.settle(0.7);
        for _ in 0..1000 {
            assert!(l.step(0.7).abs() < 1e-12);
        }
        // A third-order loop follows a ramp (a Doppler rate) with zero error
        // (after 60 s, 57 time constants of its slowest mode).
        let mut l = pll(5.0);
        let mut last = 1.0;
        for k in 0..60_000 {
            last = l.step(0.5 + 2.0 * k as f64 * 1e-3);
        }
        assert!(last.abs() < 1e-9, "{last}");
    }

    #[test]
    fn response_matches_a_simulated_sinusoid() {
        for (bw, f_hz) in [(5.0, 0.9), (10.0, 0.9), (5.0, 7.0), (20.0, 30.0)] {
            let mut l0 = pll(bw);
            assert!(l0.stage.is_stable());
            let (t_s, model) = (l0.stage.interval_s, l0.stage.response(f_hz));
            assert_sinusoid_response(|x| l0.step(x), f_hz, t_s, (20.0, 50.0), model, 2e-3, &format!("{bw} Hz"));
        }
    }

    #[test]
    fn tends_to_the_continuous_kaplan_loop() {
        // The continuous limit: −2π/(s + F(s)) with Kaplan's F at ω = Bn/0.7845.
        let bw = 5.0;
        for f_hz in [0.1, 0.9, 3.0] {
            let cont = PocketSdrStage::l1ca(bw).coeffs().response_continuous(f_hz);
            let fine = PocketSdrStage { bw_hz: bw, interval_s: 1e-6 }.response(f_hz);
            assert!((fine - cont).norm() < 1e-4 * cont.norm(), "{f_hz}: {fine} vs {cont}");
            // At 1 ms the difference is O(ωT) (a few 0.1 %), not zero.
            let ms = PocketSdrStage::l1ca(bw).response(f_hz);
            let rel = (ms - cont).norm() / cont.norm();
            assert!(rel > 1e-4 && rel < 3e-2, "{f_hz}: {rel}");
        }
    }

    #[test]
    fn stability_and_settling() {
        // The continuous loop's poles are ω times the roots of x³ + 2.4x² + 1.1x + 1:
        // −2.1031 and the lightly damped pair −0.1485 ± 0.6734j; the discrete loop at 1 ms is close.
        let s = PocketSdrStage::l1ca(5.0);
        let tau = s.settling_time_s(1.0);
        let w = s.w_rad_per_s();
        let tau_cont = 1.0 / (0.1485 * w);
        assert!((tau / tau_cont - 1.0).abs() < 0.02, "{tau} vs {tau_cont}");
        assert!(PocketSdrStage::l1ca(10.0).is_stable());
        // Bn·T far too large: unstable.
        assert!(!PocketSdrStage::l1ca(400.0).is_stable());
        assert_eq!(PocketSdrStage::l1ca(400.0).settling_time_s(5.0), f64::INFINITY);
        assert!(PocketSdrPll::new(PocketSdrStage::l1ca(-1.0)).is_err());
        assert!(PocketSdrPll::new(PocketSdrStage { bw_hz: 5.0, interval_s: 0.0 }).is_err());
    }
}
