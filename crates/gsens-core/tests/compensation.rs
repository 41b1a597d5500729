//! The compensator's sign and size against an independent closed-loop
//! simulation of the carrier loop.
//!
//! The loop under test is written out here from the difference equations of
//! the `pll` module docs (it does not call `DiscretePll`, `CarrierLoop` or
//! `LoopFilter`), extended by the signal's own Doppler so that "the g-induced
//! part" of φ is a non-trivial piece of it:
//!
//! ```text
//! r_k      = f_k + c_k + Δf_k − f_sig,k      replica minus signal frequency over integration k
//! φ_k      = e_k − π·T·r_k
//! e_{k+1}  = e_k − 2π·T·r_k
//! a2_k     = a2_{k−1} + c2·T·φ_k
//! a1_k     = a1_{k−1} + T·(c1·φ_k + a2_k)
//! f_{k+1}  = (c0·φ_k + a1_k) / 2π
//! ```
//!
//! with Δf_k = a_kᵀΓ the oscillator's bias and c_k = `nco_correction_hz(a_k)`
//! the compensator's correction, added to the NCO command (it does not pass
//! through the loop filter). With f_sig = c = Δf = 0 this is exactly the docs'
//! loop.
//!
//! Expected numbers come from linearity alone. The loop is linear in
//! (f_sig, c + Δf, initial state), and the correction is −aᵀΓ̂, so the NCO
//! sees the bias aᵀ(Γ − Γ̂). Writing φ_ref for the run with f_sig only and
//! L\[·\] for the loop's response to a bias (started in the matching steady
//! state), the g-induced part of a run compensated with Γ̂ = s·Γ is
//!
//! ```text
//! φ − φ_ref = L[aᵀ(Γ − sΓ)] = (1 − s)·L[aᵀΓ] = (1 − s)·(φ_uncomp − φ_ref)
//! ```
//!
//! so its RMS relative to the uncompensated one is |1 − s|: 0 for s = 1
//! (the true Γ), 2 for s = −1 (the correction's sign flipped), 0.1 for s = 0.9.
//! And since L\[aᵀΓ\] = Σ_i Γ_i·L\[a_i\] = φ_aᵀΓ with φ_a from a triad of loops
//! fed the three axes, post-processing φ_uncomp − φ_aᵀΓ̂ must equal the closed
//! loop compensated in real time with the same Γ̂.

use gsens_core::{Compensator, compensated_phase_rad};
use gsens_core::{DiscretePll, LoopFilterCoeffs, LoopSpec};
use std::f64::consts::{PI, TAU};

/// Γ \[Hz/(m/s²)\]: ~1e-9/g at L1, different on every axis.
const GAMMA: [f64; 3] = [0.08, -0.05, 0.15];
/// Gravity in the body frame \[m/s²\] (constant: absorbed by the settled loop).
const GRAVITY: [f64; 3] = [0.4, -0.3, 9.79];
/// Vibration near the paper loop's |L| peak: amplitude \[m/s²\], frequency \[Hz\], phase \[rad\].
/// The y axis is not vibrated, so Γ_y only enters through gravity.
const VIBRATION: [(f64, f64, f64); 3] = [(2.0, 0.9, 0.3), (0.0, 0.9, 0.0), (1.5, 0.9, 1.9)];
/// Simulated time \[s\].
const DURATION_S: f64 = 30.0;

/// Mean specific force over integration k, \[kT, (k+1)T\] (exact for the sinusoid).
fn accel_mean(k: usize, t_s: f64) -> [f64; 3] {
    let (t0, t1) = (k as f64 * t_s, (k + 1) as f64 * t_s);
    [0, 1, 2].map(|i| {
        let (amp, f_hz, p) = VIBRATION[i];
        let w = TAU * f_hz;
        GRAVITY[i] + amp * ((w * t0 + p).cos() - (w * t1 + p).cos()) / (w * t_s)
    })
}

/// The signal's own Doppler over integration k \[Hz\]: a constant plus a slow
/// line-of-sight oscillation, the same in every run.
fn signal_doppler_hz(k: usize, t_s: f64) -> f64 {
    let t = (k as f64 + 0.5) * t_s;
    1234.5 + 4.0 * (TAU * 0.13 * t + 0.4).sin()
}

fn dot(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The discrete carrier loop of the module docs, written out independently.
struct Loop {
    c: LoopFilterCoeffs,
    t_s: f64,
    /// Phase error at the start of the current integration \[rad\].
    e: f64,
    /// First and second integrators \[rad/s\], \[rad/s²\].
    a1: f64,
    a2: f64,
    /// NCO command for the current integration (loop filter output) \[Hz\].
    f: f64,
}

impl Loop {
    /// Tracking in the steady state of a constant signal Doppler and NCO bias:
    /// zero phase error, command f = f_sig − bias, held by the first integrator.
    fn settled(c: LoopFilterCoeffs, t_s: f64, signal_hz: f64, bias_hz: f64) -> Self {
        let f = signal_hz - bias_hz;
        Loop { c, t_s, e: 0.0, a1: TAU * f, a2: 0.0, f }
    }

    /// One integration: the NCO runs at f + `nco_extra_hz` (oscillator bias
    /// plus any correction added to the command) against the signal at
    /// `signal_hz`; returns the discriminator output φ_k.
    fn step(&mut self, signal_hz: f64, nco_extra_hz: f64) -> f64 {
        let r = self.f + nco_extra_hz - signal_hz;
        let phi = self.e - PI * self.t_s * r;
        self.e -= TAU * self.t_s * r;
        self.a2 += self.c.c2_per_s3 * self.t_s * phi;
        self.a1 += self.t_s * (self.c.c1_per_s2 * phi + self.a2);
        self.f = (self.c.c0_per_s * phi + self.a1) / TAU;
        phi
    }
}

/// How the NCO command is corrected in a run.
#[derive(Clone, Copy)]
enum Correction {
    /// No g-bias at all (the oscillator is perfect): φ_ref.
    NoBias,
    /// The oscillator's bias aᵀΓ, uncorrected.
    None,
    /// `nco_correction_hz` of a compensator with this Γ̂, added to the command.
    Add([f64; 3]),
    /// The same, subtracted (the wrong sign convention).
    Subtract([f64; 3]),
}

/// The NCO's frequency beyond its loop-filter command at specific force `a`:
/// the oscillator's bias aᵀΓ plus whatever correction the run applies.
fn nco_extra_hz(a: &[f64; 3], corr: Correction) -> f64 {
    let bias = dot(a, &GAMMA);
    match corr {
        Correction::NoBias => 0.0,
        Correction::None => bias,
        Correction::Add(g) => bias + Compensator { gamma_hz_per_mps2: g }.nco_correction_hz(a),
        Correction::Subtract(g) => bias - Compensator { gamma_hz_per_mps2: g }.nco_correction_hz(a),
    }
}

/// φ_k of the closed loop over the whole run.
fn closed_loop(c: LoopFilterCoeffs, t_s: f64, corr: Correction) -> Vec<f64> {
    let n = (DURATION_S / t_s) as usize;
    // The receiver has been tracking for a while: settled on the constant
    // parts (the signal Doppler at t = 0, gravity's bias with its correction),
    // as the triad below is settled on gravity alone.
    let mut lp = Loop::settled(c, t_s, signal_doppler_hz(0, t_s), nco_extra_hz(&GRAVITY, corr));
    (0..n).map(|k| lp.step(signal_doppler_hz(k, t_s), nco_extra_hz(&accel_mean(k, t_s), corr))).collect()
}

/// φ_a = L\[a\] from a triad of `DiscretePll`s, each settled on its axis' gravity.
fn regressor_triad(c: LoopFilterCoeffs, t_s: f64) -> Vec<[f64; 3]> {
    let n = (DURATION_S / t_s) as usize;
    let mut triad = [DiscretePll::new(c, t_s); 3];
    for i in 0..3 {
        triad[i].settle(GRAVITY[i]);
    }
    (0..n)
        .map(|k| {
            let a = accel_mean(k, t_s);
            [0, 1, 2].map(|i| triad[i].step(a[i]))
        })
        .collect()
}

fn rms(x: &[f64]) -> f64 {
    (x.iter().map(|v| v * v).sum::<f64>() / x.len() as f64).sqrt()
}

fn minus(x: &[f64], y: &[f64]) -> Vec<f64> {
    x.iter().zip(y).map(|(a, b)| a - b).collect()
}

fn loops() -> [(&'static str, LoopFilterCoeffs, f64); 2] {
    [
        ("paper 2nd order, Bn 3 Hz, T 5 ms", LoopSpec::PAPER.coeffs().unwrap(), 0.005),
        ("Kaplan 3rd order, Bn 10 Hz, T 2 ms", LoopSpec::third_order_kaplan(10.0).coeffs().unwrap(), 0.002),
    ]
}

fn scaled(s: f64) -> [f64; 3] {
    GAMMA.map(|g| s * g)
}

#[test]
fn the_correction_is_minus_a_dot_gamma() {
    // The convention the closed loop relies on: command + correction cancels aᵀΓ.
    let comp = Compensator { gamma_hz_per_mps2: GAMMA };
    for k in [0, 17, 333] {
        let a = accel_mean(k, 0.005);
        assert_eq!(comp.nco_correction_hz(&a) + dot(&a, &GAMMA), 0.0);
    }
}

#[test]
fn closed_loop_compensation_cancels_doubles_and_scales_linearly() {
    for (name, c, t_s) in loops() {
        assert!(c.is_stable_at(t_s), "{name}");
        let reference = closed_loop(c, t_s, Correction::NoBias);
        let g_induced = |corr| minus(&closed_loop(c, t_s, corr), &reference);
        let uncomp = g_induced(Correction::None);
        let u = rms(&uncomp);
        // Non-trivial: ≈ 0.15 rad RMS in the paper loop at its |L| peak
        // (π/(ζωn) ≈ 0.79 rad/Hz times a 0.27 Hz amplitude of aᵀΓ, over √2),
        // ≈ 0.03 rad in the wider 3rd-order loop; and the reference run has
        // its own tracking error from the signal Doppler to be subtracted.
        assert!(u > 0.01, "{name}: uncompensated g-induced RMS {u}");
        assert!(rms(&reference) > 1e-3, "{name}: the reference run should carry its own dynamics");

        // (a) the true Γ: 1 − s = 0.
        let r = rms(&g_induced(Correction::Add(GAMMA))) / u;
        assert!(r < 1e-9, "{name}: true Γ leaves {r:e} of the g-induced error");
        // (b) sign flipped: |1 − (−1)| = 2, whether the correction is
        // subtracted or the compensator is given −Γ.
        for (how, corr) in [("subtracted", Correction::Subtract(GAMMA)), ("−Γ", Correction::Add(scaled(-1.0)))] {
            let resid = g_induced(corr);
            let r = rms(&resid) / u;
            assert!((r - 2.0).abs() < 1e-6, "{name}: flipped ({how}) ratio {r}");
            // Not only the RMS: the residual is 2·(uncompensated) sample by sample.
            let dev = rms(&minus(&resid, &uncomp.iter().map(|x| 2.0 * x).collect::<Vec<_>>())) / u;
            assert!(dev < 1e-9, "{name}: flipped ({how}) is not 2× the uncompensated: {dev:e}");
        }
        // (c) Γ̂ = 0.9·Γ: 1 − 0.9 = 0.1.
        let resid = g_induced(Correction::Add(scaled(0.9)));
        let r = rms(&resid) / u;
        assert!((r - 0.1).abs() < 1e-6, "{name}: Γ̂ = 0.9Γ ratio {r}");
        let dev = rms(&minus(&resid, &uncomp.iter().map(|x| 0.1 * x).collect::<Vec<_>>())) / u;
        assert!(dev < 1e-9, "{name}: Γ̂ = 0.9Γ is not 0.1× the uncompensated: {dev:e}");
    }
}

#[test]
fn post_processing_with_the_triad_agrees_with_the_compensated_closed_loop() {
    // (d) φ_uncomp − φ_aᵀΓ̂ = φ_ref + L[aᵀ(Γ − Γ̂)] = the closed loop compensated with Γ̂.
    for (name, c, t_s) in loops() {
        let uncomp = closed_loop(c, t_s, Correction::None);
        let reference = closed_loop(c, t_s, Correction::NoBias);
        let u = rms(&minus(&uncomp, &reference));
        let phi_a = regressor_triad(c, t_s);
        assert_eq!(phi_a.len(), uncomp.len());
        for s in [1.0, 0.9, 0.0, -1.0] {
            let g_hat = scaled(s);
            let post: Vec<f64> =
                uncomp.iter().zip(&phi_a).map(|(phi, pa)| compensated_phase_rad(*phi, pa, &g_hat)).collect();
            let real_time = closed_loop(c, t_s, Correction::Add(g_hat));
            let dev = rms(&minus(&post, &real_time)) / u;
            assert!(
                dev < 1e-9,
                "{name}, Γ̂ = {s}·Γ: post-processing vs closed loop differ by {dev:e} of the g-induced RMS"
            );
            let worst = post.iter().zip(&real_time).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
            assert!(worst < 1e-9 * u, "{name}, Γ̂ = {s}·Γ: worst sample differs by {worst:e} rad");
        }
    }
}
