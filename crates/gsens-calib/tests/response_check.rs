//! The measured loop response (`measure_response`) on sessions made outside
//! the estimator: φ from a receiver loop stepped at 1 ms on the continuous
//! excitation and logged as the mean of 25 updates (synthetic). The
//! simulator's sessions are checked in gsens-montecarlo's `simulated_response`.

use gsens_calib::{
    EpochSeries, EstimateSettings, ResponseCheck, calibrate, epoch_response, measure_response,
    student_t_quantile_two_sided,
};
use gsens_core::{Complex, DiscretePll, LoggedPhase, LoopModel, LoopSpec};
use rand::{RngExt, SeedableRng};
use rand_distr::{Distribution, Normal};
use rand_xoshiro::Xoshiro256PlusPlus;
use std::f64::consts::TAU;

/// Γ of the synthetic sessions \[Hz/(m/s²)\].
const GAMMA: [f64; 3] = [0.09, 0.08, -0.08];
/// The receiver's loop update interval and the log interval \[s\].
const T_LOOP: f64 = 0.001;
const T_LOG: f64 = 0.025;

/// A multisine per axis (x, y): `components` tones at frequencies drawn
/// uniformly in \[0.25, 3\] Hz with random phases, 1.5 m/s² RMS per axis; z
/// holds gravity.
struct Excitation {
    tones: [Vec<(f64, f64, f64)>; 2],
}

impl Excitation {
    fn new(rng: &mut Xoshiro256PlusPlus, components: usize) -> Self {
        let amp = 1.5 * (2.0 / components as f64).sqrt();
        let mut axis = || -> Vec<(f64, f64, f64)> {
            (0..components).map(|_| (rng.random_range(0.25..3.0), amp, rng.random_range(0.0..TAU))).collect()
        };
        let x = axis();
        Excitation { tones: [x, axis()] }
    }
    fn accel(&self, t: f64) -> [f64; 3] {
        let s = |tones: &[(f64, f64, f64)]| tones.iter().map(|(f, a, p)| a * (TAU * f * t + p).sin()).sum::<f64>();
        [s(&self.tones[0]), s(&self.tones[1]), 9.80665]
    }
}

/// A session of `duration_s`: the receiver's loop `spec` stepped every 1 ms
/// on Δf = a(t)ᵀΓ, the log the mean of the 25 updates up to each row (stamped
/// at the latest), white noise of `noise_rad` added; a sampled at the rows.
fn synthetic(
    seed: u64,
    spec: LoopSpec,
    noise_rad: f64,
    duration_s: f64,
) -> (Vec<f64>, Vec<Option<f64>>, Vec<[f64; 3]>) {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let ex = Excitation::new(&mut rng, 40);
    let noise = Normal::new(0.0, noise_rad).unwrap();
    let df = |t: f64| {
        let a = ex.accel(t);
        a[0] * GAMMA[0] + a[1] * GAMMA[1] + a[2] * GAMMA[2]
    };
    let mut pll = DiscretePll::new(spec.coeffs().unwrap(), T_LOOP);
    pll.settle(df(0.0));
    let n = (T_LOG / T_LOOP).round() as usize;
    let rows = (duration_s / T_LOG) as usize;
    let (mut t_s, mut phase, mut accel) = (Vec::new(), Vec::new(), Vec::new());
    for m in 1..=rows {
        let mut sum = 0.0;
        for j in ((m - 1) * n + 1)..=(m * n) {
            sum += pll.step(df(j as f64 * T_LOOP));
        }
        let t = (m * n) as f64 * T_LOOP;
        t_s.push(t);
        phase.push(Some(sum / n as f64 + noise.sample(&mut rng)));
        accel.push(ex.accel(t));
    }
    (t_s, phase, accel)
}

/// The estimator's settings for the synthetic sessions: the paper's loop
/// (or `spec`) at 1 ms, logged mean.
fn settings(spec: LoopSpec) -> EstimateSettings {
    let mut s = EstimateSettings::default();
    s.receiver_loop = LoopModel::kaplan(spec, Some(T_LOOP));
    s.logged_phase = LoggedPhase::Mean;
    s
}

/// Γ̂ and the response check of a synthetic session analysed with the paper's loop.
fn check_synthetic(seed: u64, receiver: LoopSpec, noise_rad: f64) -> ResponseCheck {
    let (t_s, phase, accel) = synthetic(seed, receiver, noise_rad, 200.0);
    let series = EpochSeries {
        log_interval_s: T_LOG,
        t_s: &t_s,
        phase_err_rad: &phase,
        accel_mps2: &accel,
        imu_time_offset_s: 0.0,
    };
    let s = settings(LoopSpec::PAPER);
    let c = calibrate(&series, &s).unwrap();
    measure_response(&series, &s, &c.gamma_raw_hz_per_mps2).unwrap()
}

/// (a) φ = L[u] + white noise through the model's own loop: over 30 seeds and
/// two noise levels the deviations of Ĥ from the model, in units of their
/// stated σ, fall within ±1σ (t-quantile) and within the 95 % t-interval as
/// often as the t distribution says, and the check passes as often as its
/// false-alarm rate allows.
#[test]
fn right_loop_gives_the_stated_coverage_and_passes() {
    for noise_rad in [0.05, 0.2] {
        let (mut inside_1, mut inside_95, mut total, mut failed, mut bins) = (0usize, 0usize, 0usize, 0usize, 0usize);
        let mut nu = 0.0;
        let seeds = 30;
        for seed in 0..seeds {
            let r = check_synthetic(1000 + seed, LoopSpec::PAPER, noise_rad);
            nu = 2.0 * (r.effective_segments - 1.0);
            let (q1, q95) =
                (student_t_quantile_two_sided(1.0 - 0.682_689_5, nu), student_t_quantile_two_sided(0.05, nu));
            for b in r.tested() {
                for t in [b.magnitude_deviation_sigma, b.phase_deviation_sigma] {
                    inside_1 += (t.abs() <= q1) as usize;
                    inside_95 += (t.abs() <= q95) as usize;
                    total += 1;
                }
            }
            bins += r.bins_tested;
            failed += (!r.consistent) as usize;
            // The band is the shaken one: the multisine spans 0.25–3 Hz.
            let [lo, hi] = r.tested_band_hz.unwrap();
            assert!(lo < 1.0 && hi > 2.0, "tested band {lo}–{hi} Hz");
        }
        // Adjacent Hann bins are correlated (ENBW 1.5 bins): count the
        // independent ones for the binomial standard error.
        let n_indep = total as f64 / 1.5;
        for (inside, nominal) in [(inside_1, 0.682_689_5), (inside_95, 0.95)] {
            let frac = inside as f64 / total as f64;
            let se = (nominal * (1.0 - nominal) / n_indep).sqrt();
            println!(
                "noise {noise_rad} rad: {inside}/{total} within the {nominal} interval ({frac:.3}, ±3 SE {:.3}), ν {nu:.0}",
                3.0 * se
            );
            assert!(
                (frac - nominal).abs() < 3.0 * se,
                "noise {noise_rad}: coverage {frac:.3} vs {nominal} ± {:.3}",
                3.0 * se
            );
        }
        // At a 1 % false-alarm rate, 3 or more failures in 30 have probability 0.4 %.
        println!("noise {noise_rad} rad: {failed} of {seeds} sessions failed the check, {bins} bins tested");
        assert!(failed <= 2, "{failed} of {seeds} right-loop sessions failed");
    }
}

/// (b) The receiver's loop 20 % narrower or wider (Bn 2.4 or 3.6 Hz) than the
/// model's 3 Hz: Γ̂ absorbs the overall scale, the shape does not fit, and
/// the check fails every time.
#[test]
fn a_loop_20_percent_off_fails() {
    for bn_hz in [2.4, 3.6] {
        for seed in 1..=3 {
            let spec = LoopSpec::SecondOrder { bn_hz, zeta: std::f64::consts::FRAC_1_SQRT_2 };
            let r = check_synthetic(seed, spec, 0.05);
            println!("Bn {bn_hz} Hz, seed {seed}: {}", r.summary());
            assert!(!r.consistent, "Bn {bn_hz} Hz, seed {seed}: {}", r.summary());
            assert!(r.p_value < 1e-6, "p {}", r.p_value);
        }
    }
}

/// The analytic epoch-level response drawn in the figure, checked against
/// the receiver loop stepped at 1 ms on a pure tone and logged as the mean
/// of 25 updates (least-squares sine fit after the transient).
#[test]
fn epoch_response_matches_a_stepped_loop() {
    let model = LoopModel::kaplan(LoopSpec::PAPER, Some(T_LOOP));
    for f_hz in [0.3, 0.9, 2.5, 7.0] {
        let mut pll = DiscretePll::new(LoopSpec::PAPER.coeffs().unwrap(), T_LOOP);
        let n = 25;
        let (mut sc, mut ss, mut cc, mut ssn, mut cs) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for m in 1..=(200.0 / T_LOG) as usize {
            let mut sum = 0.0;
            for j in ((m - 1) * n + 1)..=(m * n) {
                sum += pll.step((TAU * f_hz * j as f64 * T_LOOP).cos());
            }
            let t = (m * n) as f64 * T_LOOP;
            if t > 20.0 {
                let (c, s) = ((TAU * f_hz * t).cos(), (TAU * f_hz * t).sin());
                let y = sum / n as f64;
                cc += c * c;
                ssn += s * s;
                cs += c * s;
                sc += y * c;
                ss += y * s;
            }
        }
        // y = A cos + B sin ⇒ response A − jB for an input cos(ωt).
        let det = cc * ssn - cs * cs;
        let (a, b) = ((sc * ssn - ss * cs) / det, (ss * cc - sc * cs) / det);
        let measured = Complex::new(a, -b);
        let l = epoch_response(&model, T_LOG, LoggedPhase::Mean, f_hz);
        assert!((measured - l).norm() < 1e-4 * l.norm().max(0.1), "{f_hz} Hz: {measured} vs {l}");
        // Without the mean the logged phase is the loop's own L_d.
        assert_eq!(epoch_response(&model, T_LOG, LoggedPhase::Last, f_hz), model.response(f_hz));
    }
}

/// A session too short for the statistics, or without excitation, is an
/// error that says why, not a verdict.
#[test]
fn too_short_or_unexcited_sessions_are_reported() {
    let (t_s, phase, accel) = synthetic(5, LoopSpec::PAPER, 0.05, 12.0);
    let series = EpochSeries {
        log_interval_s: T_LOG,
        t_s: &t_s,
        phase_err_rad: &phase,
        accel_mps2: &accel,
        imu_time_offset_s: 0.0,
    };
    let s = settings(LoopSpec::PAPER);
    let e = measure_response(&series, &s, &GAMMA).unwrap_err();
    let msg = e.to_string();
    assert!(msg.contains("effective segments of 4.3 s") && msg.contains("record longer runs"), "{msg}");
    let e = measure_response(&series, &s, &[0.0; 3]).unwrap_err();
    assert!(e.to_string().contains("Γ̂ is zero"), "{e}");
}
