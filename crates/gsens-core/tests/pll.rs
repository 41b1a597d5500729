//! Known answers for the loop models (docs/conventions.md, "PLL parametrization").

use gsens_core::LoopModel;
use gsens_core::*;

#[path = "../src/pll/sinusoid_response.rs"]
mod sinusoid_response;
use sinusoid_response::assert_sinusoid_response;
use std::f64::consts::{FRAC_1_SQRT_2, PI, TAU};

fn paper() -> LoopFilterCoeffs {
    LoopSpec::PAPER.coeffs().unwrap()
}

/// ∫₀^fmax |H(j2πf)|² df by composite Simpson on a log-spaced + linear grid.
fn noise_bandwidth_by_integration(c: &LoopFilterCoeffs) -> f64 {
    // Substitute f = u/(1-u) to map [0, ∞) onto [0, 1): df = du/(1-u)².
    let n = 200_000;
    let h = 1.0 / n as f64;
    let g = |u: f64| {
        if u >= 1.0 {
            return 0.0;
        }
        let f = u / (1.0 - u);
        c.closed_loop_continuous(f).norm_sqr() / ((1.0 - u) * (1.0 - u))
    };
    let mut s = g(0.0) + g(1.0 - 1e-12);
    for i in 1..n {
        let w = if i % 2 == 1 { 4.0 } else { 2.0 };
        s += w * g(i as f64 * h);
    }
    s * h / 3.0
}

#[test]
fn paper_loop_natural_frequency_is_0_9_hz() {
    let wn = second_order_wn_from_bn(3.0, FRAC_1_SQRT_2);
    assert!((wn - 5.657).abs() < 1e-3, "{wn}");
    assert!((wn / TAU - 0.900).abs() < 1e-3);
    assert!((second_order_bn_from_wn(wn, FRAC_1_SQRT_2) - 3.0).abs() < 1e-12);
}

#[test]
fn second_order_response_peaks_at_wn_with_pi_over_zeta_wn() {
    let c = paper();
    let wn = second_order_wn_from_bn(3.0, FRAC_1_SQRT_2);
    // Golden-section search of the peak over 0.1 … 10 Hz (independent of the formula).
    let (mut a, mut b) = (0.1f64, 10.0f64);
    let r = (5f64.sqrt() - 1.0) / 2.0;
    for _ in 0..200 {
        let x1 = b - r * (b - a);
        let x2 = a + r * (b - a);
        if c.response_continuous(x1).norm() > c.response_continuous(x2).norm() {
            b = x2;
        } else {
            a = x1;
        }
    }
    let peak_hz = 0.5 * (a + b);
    assert!((peak_hz - wn / TAU).abs() < 1e-6, "peak at {peak_hz} Hz");
    let peak = c.response_continuous(peak_hz).norm();
    assert!((peak - PI / (FRAC_1_SQRT_2 * wn)).abs() < 1e-9, "{peak}");
    assert!((peak - 0.785).abs() < 1e-3);
    // The one loop abstraction finds the same peak (closed form: ωn, π/(ζωn)).
    let p = gsens_core::LoopModel::kaplan(LoopSpec::PAPER, None).peak().unwrap();
    assert!((p.f_hz - wn / TAU).abs() < 1e-6 && (p.rad_per_hz - PI / (FRAC_1_SQRT_2 * wn)).abs() < 1e-9, "{p:?}");
    // A constant Δf leaves no steady-state phase error; the sign is negative at low f
    // (a positive NCO bias makes the replica lead: φ = θ_s − θ_r < 0).
    assert_eq!(c.response_continuous(0.0).norm(), 0.0);
    let low = c.response_continuous(0.01);
    assert!(low.im < 0.0 && low.norm() < 0.02);
}

#[test]
fn noise_bandwidths_by_numerical_integration() {
    // 2nd order: Bn = 3 Hz by construction; the integral must give it back.
    let bn2 = noise_bandwidth_by_integration(&paper());
    assert!((bn2 - 3.0).abs() < 1e-4, "2nd-order Bn = {bn2}");
    // 3rd order, Kaplan a3 = 1.1, b3 = 2.4, built from ωn = 1 rad/s: Bn/ωn = 0.7845.
    let c3 = LoopFilterCoeffs { c0_per_s: KAPLAN_B3, c1_per_s2: KAPLAN_A3, c2_per_s3: 1.0 };
    let bn3 = noise_bandwidth_by_integration(&c3);
    assert!((bn3 - 0.7845).abs() < 5e-4, "3rd-order Bn/ωn = {bn3}");
    assert!((third_order_bn_over_wn(KAPLAN_A3, KAPLAN_B3) - bn3).abs() < 1e-4);
}

#[test]
fn discrete_response_converges_to_continuous_as_t_shrinks() {
    for c in [paper(), LoopSpec::third_order_kaplan(3.0).coeffs().unwrap()] {
        let mut prev = f64::INFINITY;
        for t_s in [0.02, 0.005, 0.001, 0.0002] {
            let mut worst = 0.0f64;
            for f_hz in [0.1, 0.3, 0.9, 2.0, 5.0] {
                let d = c.response_discrete(f_hz, t_s);
                let k = c.response_continuous(f_hz);
                worst = worst.max((d - k).norm() / k.norm());
            }
            assert!(worst < prev * 0.6, "T = {t_s}: {worst} vs {prev}");
            prev = worst;
        }
        // First order in T (the one-update latency is a delay of about T).
        assert!(prev < 5e-3, "{prev}");
    }
}

/// The z-domain formula must describe the time-domain loop exactly: drive the
/// DiscretePll with a sinusoid and compare the steady-state phasor.
#[test]
fn discrete_response_matches_time_domain_loop() {
    for (c, t_s) in [(paper(), 0.025), (paper(), 0.001), (LoopSpec::third_order_kaplan(5.0).coeffs().unwrap(), 0.02)] {
        for f_hz in [0.3, 0.9, 3.0] {
            let mut pll = DiscretePll::new(c, t_s);
            // 30 s to settle, then 20 cycles.
            let span_s = 20.0 / f_hz;
            let model = c.response_discrete(f_hz, t_s);
            assert_sinusoid_response(|x| pll.step(x), f_hz, t_s, (30.0, span_s), model, 2e-3, "DiscretePll");
        }
    }
}

/// The NCO command of the time-domain loop answers a sinusoidal Δf as the
/// z-domain −1 − L_d/G says, and that tends to the continuous −H(s) = −F/(s + F)
/// as the update interval shrinks.
#[test]
fn nco_command_follows_minus_the_closed_loop() {
    for (c, t_s) in [(paper(), 0.025), (paper(), 0.001), (LoopSpec::third_order_kaplan(5.0).coeffs().unwrap(), 0.02)] {
        for f_hz in [0.3, 0.9, 3.0] {
            let mut pll = DiscretePll::new(c, t_s);
            let span_s = 20.0 / f_hz;
            let model = c.nco_response_discrete(f_hz, t_s);
            let nco_in_force = |x: f64| {
                let f = pll.nco_freq_hz();
                pll.step(x);
                f
            };
            assert_sinusoid_response(nco_in_force, f_hz, t_s, (30.0, span_s), model, 2e-3, "NCO command");
        }
    }
    let c = paper();
    for f_hz in [0.3, 0.9, 2.0] {
        let h = c.closed_loop_continuous(f_hz);
        // One update of latency: a delay of about T, first order in T.
        let rel = (c.nco_response_discrete(f_hz, 0.0002) + h).norm() / h.norm();
        assert!(rel < 5e-3, "{f_hz} Hz: {rel}");
    }
    assert_eq!(c.nco_response_discrete(0.0, 0.001).re, -1.0);
}

#[test]
fn stability_checks() {
    assert!(paper().is_stable_at(0.001));
    assert!(paper().is_stable_at(0.025));
    // Bn·T far beyond any receiver's choice: unstable.
    let wide = LoopSpec::SecondOrder { bn_hz: 60.0, zeta: FRAC_1_SQRT_2 }.coeffs().unwrap();
    assert!(!wide.is_stable_at(0.02));
    // Slow 3rd-order loops at fast updates are stable (their slow poles sit near z = 1).
    assert!(LoopSpec::third_order_kaplan(1.0).coeffs().unwrap().is_stable_at(0.001));
    assert!(LoopSpec::third_order_kaplan(0.2).coeffs().unwrap().is_stable_at(0.001));
    // The root test agrees with the time-domain loop: find the Bn·T where the
    // impulse response starts to grow and check the verdict flips there too.
    for spec in [LoopSpec::PAPER, LoopSpec::third_order_kaplan(3.0)] {
        let t_s = 0.02;
        let verdict = |bn: f64| {
            let c = match spec {
                LoopSpec::SecondOrder { zeta, .. } => LoopSpec::SecondOrder { bn_hz: bn, zeta },
                LoopSpec::ThirdOrder { a3, b3, .. } => LoopSpec::ThirdOrder { bn_hz: bn, a3, b3 },
                other => other,
            }
            .coeffs()
            .unwrap();
            let mut pll = DiscretePll::new(c, t_s);
            pll.step(1.0);
            let mut late = 0.0f64;
            let mut finite = true;
            for k in 0..20_000 {
                let y = pll.step(0.0).abs();
                finite &= y.is_finite();
                if k >= 19_000 {
                    late = late.max(y);
                }
            }
            (c.is_stable_at(t_s), finite && late < 1e-6)
        };
        for bn in [5.0, 10.0, 15.0, 20.0, 25.0, 30.0, 40.0] {
            let (roots, time_domain) = verdict(bn);
            assert_eq!(roots, time_domain, "Bn = {bn} Hz at T = {t_s} s");
        }
    }
    assert_eq!(
        LoopSpec::SecondOrder { bn_hz: -1.0, zeta: 0.7 }.coeffs(),
        Err(LoopError::NonPositiveParameter("bn_hz"))
    );
    assert_eq!(LoopSpec::ThirdOrder { bn_hz: 3.0, a3: 0.3, b3: 2.0 }.coeffs(), Err(LoopError::Unstable));
}

#[test]
fn preloaded_loop_tracks_constant_frequency_with_zero_error() {
    let mut l = CarrierLoop::new(paper(), 0.001);
    l.preload(1234.5, 0.0);
    assert_eq!(l.nco_freq_hz(), 1234.5);
    l.close(0.0);
    assert!((l.nco_freq_hz() - 1234.5).abs() < 1e-9);
}

#[test]
fn half_power_band_of_the_second_order_loop_in_closed_form() {
    // |L|² = 4π²ω²/((ωn² − ω²)² + 4ζ²ωn²ω²) falls to half its peak where
    // |ωn² − ω²| = 2ζωnω, i.e. at ω = ωn·(√(1 + ζ²) ∓ ζ).
    for zeta in [0.5, FRAC_1_SQRT_2, 1.0] {
        let wn = second_order_wn_from_bn(3.0, zeta);
        let m = LoopModel::kaplan(LoopSpec::SecondOrder { bn_hz: 3.0, zeta }, None);
        let [lo, hi] = m.half_power_band_hz().unwrap();
        let want = [wn * ((1.0 + zeta * zeta).sqrt() - zeta) / TAU, wn * ((1.0 + zeta * zeta).sqrt() + zeta) / TAU];
        assert!((lo - want[0]).abs() < 1e-6 * want[0] && (hi - want[1]).abs() < 1e-6 * want[1], "ζ {zeta}: {lo} {hi}");
    }
}

#[test]
fn loop_model_refuses_an_unstable_loop_and_tends_to_the_continuous_one() {
    // Bn = 3 Hz updated every 0.5 s is unstable: no peak, no runnable model.
    let fast = LoopModel::kaplan(LoopSpec::PAPER, Some(0.5));
    assert_eq!(fast.peak(), Err(LoopError::UnstableAtInterval));
    assert!(fast.runnable().is_err());
    // At 1 ms the discrete peak is within 0.5 % of the continuous one.
    let cont = LoopModel::kaplan(LoopSpec::PAPER, None).peak().unwrap();
    let disc = LoopModel::kaplan(LoopSpec::PAPER, Some(1e-3)).peak().unwrap();
    assert!((disc.f_hz / cont.f_hz - 1.0).abs() < 5e-3 && (disc.rad_per_hz / cont.rad_per_hz - 1.0).abs() < 5e-3);
}

#[test]
fn gnss_sdr_loop_equivalent_coefficients_match_its_exact_response_at_low_rate() {
    use gsens_core::gnss_sdr::GnssSdrStage;
    // At 1 ms integrations the exact GNSS-SDR loop is close to its continuous equivalent.
    for order in [2, 3] {
        let m = LoopModel::GnssSdr(GnssSdrStage { order, bw_hz: 3.0, symbols: 1 });
        let c = LoopModel::kaplan(LoopSpec::Coefficients(m.coeffs().unwrap()), None);
        let (pm, pc) = (m.peak().unwrap(), c.peak().unwrap());
        assert!((pm.f_hz / pc.f_hz - 1.0).abs() < 1e-2, "order {order}: {pm:?} {pc:?}");
        assert!((pm.rad_per_hz / pc.rad_per_hz - 1.0).abs() < 1e-2, "order {order}: {pm:?} {pc:?}");
        assert_eq!(m.order(), order);
    }
}

#[test]
fn pocket_sdr_loop_model_answers_every_question_like_kaplans_continuous_loop() {
    use gsens_core::LinearLoop;
    use gsens_core::pocket_sdr::PocketSdrStage;
    // PocketSDR's loop is Kaplan's 3rd-order filter at ω = Bn/0.7845 with its
    // own discretization: at 1 ms its peak and band are within 1 % of the
    // continuous loop of the same filter.
    let m = LoopModel::PocketSdr(PocketSdrStage::l1ca(5.0));
    let c = LoopModel::kaplan(LoopSpec::Coefficients(m.coeffs().unwrap()), None);
    let (pm, pc) = (m.peak().unwrap(), c.peak().unwrap());
    assert!((pm.f_hz / pc.f_hz - 1.0).abs() < 1e-2, "{pm:?} {pc:?}");
    assert!((pm.rad_per_hz / pc.rad_per_hz - 1.0).abs() < 1e-2, "{pm:?} {pc:?}");
    let (bm, bc) = (m.half_power_band_hz().unwrap(), c.half_power_band_hz().unwrap());
    assert!((bm[0] / bc[0] - 1.0).abs() < 1e-2 && (bm[1] / bc[1] - 1.0).abs() < 1e-2, "{bm:?} {bc:?}");
    // The filter is Kaplan's: the same coefficients as LoopSpec::third_order_kaplan up to
    // PocketSDR's rounded Bn/ωn (0.7845 against the closed form's 0.78445).
    let k = LoopSpec::third_order_kaplan(5.0).coeffs().unwrap();
    assert!((m.coeffs().unwrap().c2_per_s3 / k.c2_per_s3 - 1.0).abs() < 3e-4);
    assert_eq!((m.order(), m.bn_hz(), m.interval_s()), (3, Some(5.0), Some(1e-3)));
    // Scaling the bandwidth scales every time constant: the peak moves with it.
    let m2 = m.with_bn_scaled(2.0);
    assert_eq!(m2, LoopModel::PocketSdr(PocketSdrStage::l1ca(10.0)));
    let p2 = m2.peak().unwrap();
    assert!((p2.f_hz / pm.f_hz - 2.0).abs() < 0.02, "{p2:?} {pm:?}");
    // The runnable model is the exact one: its steady sinusoid response is `response`.
    let mut l = m.runnable().unwrap();
    let (f_hz, r) = (pm.f_hz, m.response(pm.f_hz));
    assert_sinusoid_response(|x| l.step(x), f_hz, 1e-3, (30.0, 100.0), r, 2e-3, "PocketSDR runnable");
    assert!(LoopModel::PocketSdr(PocketSdrStage::l1ca(500.0)).check().is_err());
    assert!(m.to_string().contains("PocketSDR") && m.to_string().contains("b_pll 5 Hz"), "{m}");
}

#[test]
fn a_loop_of_order_two_or_three_takes_that_orders_shape_and_no_other_order_is_a_loop() {
    use gsens_core::{LoopOrderError, LoopSpec};
    assert_eq!(LoopSpec::of_order(2, 3.0, 0.7, 1.1, 2.4), Ok(LoopSpec::SecondOrder { bn_hz: 3.0, zeta: 0.7 }));
    assert_eq!(LoopSpec::of_order(3, 5.0, 0.7, 1.1, 2.4), Ok(LoopSpec::ThirdOrder { bn_hz: 5.0, a3: 1.1, b3: 2.4 }));
    for order in [0, 1, 4, 255] {
        let e = LoopSpec::of_order(order, 3.0, 0.7, 1.1, 2.4).unwrap_err();
        assert_eq!(e, LoopOrderError { order });
        assert_eq!(e.to_string(), format!("order must be 2 or 3, got {order}"));
    }
}

/// The forms a loop in words may take: GNSS-SDR's for its own ζ or a₃, b₃
/// and a whole-ms interval dividing the bit, PocketSDR's for the 3rd order,
/// and nothing else for a loop that is already one receiver's or is given
/// otherwise.
#[test]
fn a_loop_in_words_has_each_receivers_form() {
    use gsens_core::{gnss_sdr::GnssSdrStage, pocket_sdr::PocketSdrStage};
    let zeta = core::f64::consts::FRAC_1_SQRT_2;
    let second = |t: Option<f64>| LoopModel::kaplan(LoopSpec::SecondOrder { bn_hz: 3.0, zeta }, t);
    let forms: Vec<LoopModel> = second(Some(0.02)).discrete_forms().collect();
    assert_eq!(forms, vec![second(Some(0.02)), LoopModel::GnssSdr(GnssSdrStage { order: 2, bw_hz: 3.0, symbols: 20 })]);
    let third = LoopModel::kaplan(LoopSpec::ThirdOrder { bn_hz: 10.0, a3: 1.1, b3: 2.4 }, Some(0.001));
    let forms: Vec<LoopModel> = third.discrete_forms().collect();
    assert_eq!(
        forms,
        vec![
            third,
            LoopModel::GnssSdr(GnssSdrStage { order: 3, bw_hz: 10.0, symbols: 1 }),
            LoopModel::PocketSdr(PocketSdrStage { bw_hz: 10.0, interval_s: 0.001 }),
        ]
    );
    // 25 ms and 3 ms do not divide the 20 ms bit; another damping is no GNSS-SDR loop.
    for t in [0.025, 0.003] {
        assert_eq!(second(Some(t)).discrete_forms().count(), 1, "{t}");
    }
    let damped = LoopModel::kaplan(LoopSpec::SecondOrder { bn_hz: 3.0, zeta: 0.9 }, Some(0.02));
    assert_eq!(damped.discrete_forms().collect::<Vec<_>>(), vec![damped]);
    assert_eq!(second(None).discrete_forms().count(), 1);
    let own = LoopModel::GnssSdr(GnssSdrStage { order: 2, bw_hz: 3.0, symbols: 20 });
    assert_eq!(own.discrete_forms().collect::<Vec<_>>(), vec![own]);
    // A form unstable at the interval is left out: GNSS-SDR's 3rd order at 20 ms and Bn 30 Hz.
    let wide = LoopModel::kaplan(LoopSpec::ThirdOrder { bn_hz: 30.0, a3: 1.1, b3: 2.4 }, Some(0.02));
    assert!(wide.discrete_forms().all(|m| m == wide || m.check().is_ok()));
}
