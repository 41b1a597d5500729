//! Correlator-level channel physics against the formulas of docs/conventions.md
//! and the core's loop model.

use core::f64::consts::{FRAC_1_SQRT_2, PI, TAU};

use gsens_core::{LoopFilterCoeffs, LoopSpec};
use gsens_sim::channel::{Channel, ChannelConfig, ChannelStart, Discriminator};
use gsens_sim::rng::substream;

fn start(cn0_dbhz: f64, freq_hz: f64) -> ChannelStart {
    ChannelStart {
        cn0_dbhz,
        preload_freq_hz: freq_hz,
        preload_rate_hz_per_s: 0.0,
        initial_phase_err_rad: 0.0,
        bit_offset: 7,
    }
}

/// Costas tracking jitter σ² = Bn/(C/N0)·(1 + 1/(2T·C/N0)) (docs/conventions.md).
fn costas_sigma_rad(bn_hz: f64, cn0_dbhz: f64, t_s: f64) -> f64 {
    let c = gsens_core::units::cn0_dbhz_to_ratio_hz(cn0_dbhz);
    (bn_hz / c * (1.0 + 1.0 / (2.0 * t_s * c))).sqrt()
}

/// Standard deviation of the *true* phase error (the replica's tracking error,
/// at the integration centres) of a channel without oscillator noise. This is
/// what the formula describes: the loop's phase jitter. The discriminator
/// output would add each integration's raw white noise, of variance
/// 1/(2·C/N0·T) — 25 times the loop jitter at T = 1 ms, Bn = 3 Hz.
fn measured_jitter_rad(bn_hz: f64, cn0_dbhz: f64, t_s: f64, duration_s: f64, seed: u64) -> f64 {
    let coeffs = LoopSpec::SecondOrder { bn_hz, zeta: FRAC_1_SQRT_2 }.coeffs().unwrap();
    let cfg = ChannelConfig::new(coeffs, t_s, Discriminator::Costas);
    let doppler_hz = -1234.5;
    let mut ch = Channel::new(&cfg, &start(cn0_dbhz, doppler_hz), substream(seed, 1));
    let n = (duration_s / t_s) as usize;
    let skip = (2.0 / t_s) as usize;
    let (mut s1, mut s2, mut m) = (0.0, 0.0, 0.0);
    for k in 0..n {
        let out = ch.step(doppler_hz, 0.0);
        if k >= skip {
            s1 += out.true_phase_err_rad;
            s2 += out.true_phase_err_rad * out.true_phase_err_rad;
            m += 1.0;
        }
    }
    assert_eq!(ch.stats().cycle_slips, 0);
    (s2 / m - (s1 / m) * (s1 / m)).sqrt()
}

#[test]
fn costas_thermal_jitter_matches_the_formula_at_35_and_45_dbhz() {
    // Bn = 3 Hz (the paper's loop), T = 1 ms: Bn·T = 0.003 ≪ 1, where the
    // continuous-loop formula holds; 300 s ≈ 1800 loop correlation times, so
    // the std is measured to ~2 %.
    let (bn, t) = (3.0, 0.001);
    for cn0 in [35.0, 45.0] {
        let measured = measured_jitter_rad(bn, cn0, t, 300.0, 11);
        let theory = costas_sigma_rad(bn, cn0, t);
        let ratio = measured / theory;
        println!("C/N0 {cn0} dB-Hz: σφ measured {measured:.5} rad, formula {theory:.5} rad, ratio {ratio:.4}");
        assert!((ratio - 1.0).abs() < 0.10, "C/N0 {cn0}: ratio {ratio}");
    }
}

/// Drives a channel with Δf = A·sin(2πft) and fits the amplitude and phase of
/// its discriminator output at f: returns φ's complex amplitude / A [rad/Hz].
fn fitted_response(coeffs: LoopFilterCoeffs, t_s: f64, f_hz: f64, cn0_dbhz: f64) -> (f64, f64) {
    let a_hz = 0.4;
    let cfg = ChannelConfig::new(coeffs, t_s, Discriminator::Costas);
    let doppler_hz = 2500.0;
    let mut ch = Channel::new(&cfg, &start(cn0_dbhz, doppler_hz), substream(7, 2));
    let settle_s = 4.0;
    let cycles = (40.0 * f_hz).ceil().max(12.0);
    let fit_s = cycles / f_hz;
    let n_settle = (settle_s / t_s).round() as usize;
    let n_fit = (fit_s / t_s).round() as usize;
    let (mut ss, mut sc, mut cc, mut ys, mut yc) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for k in 0..n_settle + n_fit {
        let t = k as f64 * t_s; // integration centre
        let (s, c) = (TAU * f_hz * t).sin_cos();
        let out = ch.step(doppler_hz, a_hz * s);
        if k >= n_settle {
            let y = out.discriminator_rad;
            ss += s * s;
            sc += s * c;
            cc += c * c;
            ys += y * s;
            yc += y * c;
        }
    }
    assert_eq!(ch.stats().cycle_slips, 0);
    // Least squares y ≈ p·sin + q·cos.
    let det = ss * cc - sc * sc;
    let p = (ys * cc - yc * sc) / det;
    let q = (yc * ss - ys * sc) / det;
    // Δf = Im(A e^{jωt}) → φ = Im(L A e^{jωt}) = A|L|(cos∠L·sin + sin∠L·cos).
    ((p * p + q * q).sqrt() / a_hz, q.atan2(p))
}

#[test]
fn phase_response_to_a_sinusoidal_bias_matches_the_core_model() {
    let coeffs = LoopSpec::PAPER.coeffs().unwrap();
    for (t_s, cn0) in [(0.001, 55.0), (0.020, 55.0)] {
        for f in [0.3, 0.9, 3.0] {
            let (mag, arg) = fitted_response(coeffs, t_s, f, cn0);
            let l = coeffs.response_discrete(f, t_s);
            let lc = coeffs.response_continuous(f);
            let rel = mag / l.norm() - 1.0;
            let darg = (arg - l.arg() + PI).rem_euclid(TAU) - PI;
            println!(
                "T {t_s} s, f {f} Hz: |φ|/A {mag:.5} rad/Hz, |L_d| {:.5}, |L| {:.5}, rel {rel:+.5}, Δarg {:+.3}°",
                l.norm(),
                lc.norm(),
                darg.to_degrees()
            );
            assert!(rel.abs() < 0.02, "T {t_s} f {f}: {rel}");
            assert!(darg.abs() < 2f64.to_radians(), "T {t_s} f {f}: {darg}");
        }
    }
}

/// A frequency step too large for the loop makes it slip: the lock point of
/// the true phase error moves by whole multiples of π (Costas) or 2π (pilot),
/// and the slip counter counts exactly those periods.
#[test]
fn cycle_slips_emerge_and_are_counted_in_periods() {
    let coeffs = LoopSpec::PAPER.coeffs().unwrap();
    for disc in [Discriminator::Costas, Discriminator::Pilot] {
        let period = disc.slip_period_rad();
        let cfg = ChannelConfig::new(coeffs, 0.001, disc);
        let mut ch = Channel::new(&cfg, &start(50.0, 0.0), substream(3, 4));
        for _ in 0..3000 {
            ch.step(0.0, 0.0);
        }
        assert!(ch.locked());
        // A 6 Hz bias step: the 2nd-order loop's transient peak 2π·6/(ωn·…)
        // is several radians, far outside the discriminator's range.
        for _ in 0..10_000 {
            ch.step(0.0, 6.0);
        }
        let e = ch.last().true_phase_err_rad;
        let k = (e / period).round();
        let stats = ch.stats();
        println!("{disc:?}: final error {e:.3} rad = {k}·{period:.4}; slips {}", stats.cycle_slips);
        assert!(k != 0.0, "{disc:?}: no slip");
        assert!((e - k * period).abs() < 0.3, "{disc:?}: not at a lock point: {e}");
        assert!(stats.cycle_slips >= k.abs() as u64, "{disc:?}");
        assert!(ch.locked(), "{disc:?}: relocked");
    }
}
