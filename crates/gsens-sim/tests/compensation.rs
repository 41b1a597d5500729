//! Compensation in the loop against closed forms: with Γ̂ = Γ and an ideal
//! IMU, what the feed-forward leaves of the g-induced phase error is its
//! delay alone. A tone at f delayed by τ leaves |1 − e^{−j2πfτ}| =
//! 2·sin(πfτ) of itself, so the suppression is 1/(2·sin(πfτ)), τ being the
//! latency plus half the IMU's sample interval (the hold).

use gsens_sim::compensation::CompensationSection;
use gsens_sim::compensation_trial::run_trial;
use gsens_sim::imu::ImuPreset;
use gsens_sim::scenario::Scenario;

fn ideal_imu_scenario(rate_hz: f64) -> Scenario {
    let mut s = Scenario::default();
    s.imu.preset = ImuPreset::Ideal;
    s.imu.rate_hz = rate_hz;
    s.imu.time_offset_s = 0.0;
    s
}

#[test]
fn the_residual_of_an_exact_gamma_is_the_feed_forwards_delay() {
    // The paper's shaking: 1.1 s period (7 % jitter).
    let f_hz = 1.0 / 1.1;
    for (rate_hz, latency_s) in [(1000.0, 0.02), (1000.0, 0.005), (40.0, 0.0)] {
        let s = ideal_imu_scenario(rate_hz);
        let c = CompensationSection { gamma_hz_per_mps2: s.oscillator.gamma_hz_per_mps2, latency_s };
        let trial = run_trial(&s, 3, &c).unwrap();
        let tau_s = latency_s + 0.5 / rate_hz;
        let expected = 1.0 / (2.0 * (std::f64::consts::PI * f_hz * tau_s).sin());
        let ratio = trial.suppression / expected;
        eprintln!("IMU {rate_hz} Hz, latency {latency_s} s: ×{:.1}, closed form ×{expected:.1}", trial.suppression);
        // The jitter spreads the tone over ±7 %; the loop's 1 ms steps add their own half-step.
        assert!((ratio - 1.0).abs() < 0.15, "×{} vs ×{expected}", trial.suppression);
        assert_eq!(trial.cycle_slips, [0, 0, 0]);
    }
}

#[test]
fn no_compensation_section_leaves_the_session_as_it_was() {
    let s = Scenario::default();
    assert!(s.compensation.is_none());
    let a = gsens_sim::simulate_logs(&s, 5).unwrap();
    let mut zero = s.clone();
    zero.compensation = Some(CompensationSection { gamma_hz_per_mps2: [0.0; 3], latency_s: 0.0 });
    let b = gsens_sim::simulate_logs(&zero, 5).unwrap();
    // A zero Γ̂ corrects nothing: the same logs to the bit.
    assert_eq!(a.imu, b.imu);
    assert_eq!(a.tracking, b.tracking);
}

/// Same seed, same trial: the trace drawn (the longest channel's) does not
/// depend on a hash map's order.
#[test]
fn a_trial_is_the_same_on_every_run() {
    let s = Scenario::default();
    let c = CompensationSection { gamma_hz_per_mps2: s.oscillator.gamma_hz_per_mps2, latency_s: 0.0 };
    let (a, b) = (run_trial(&s, 2, &c).unwrap(), run_trial(&s, 2, &c).unwrap());
    let trace = |t: &gsens_sim::compensation_trial::Trial| t.trace.as_ref().map(|t| (t.channel, t.prn));
    assert_eq!(trace(&a), trace(&b));
    assert_eq!(a, b);
}
