//! σ when the loop is stated in words only: gsens's own sessions with a
//! 20 ms loop logged every 20 ms (where the receivers' forms of the same
//! words differ most: GNSS-SDR's moves Γ̂ by about 15 % on these sessions),
//! the form not named, so that the data choose it. Over 100 seeds the
//! errors against the truth seen through the IMU, in units of each run's
//! own σ, have an RMS within 1.2 (300 axes: about 4 standard errors of an
//! RMS of 1, for the heavy tail of the runs whose data prefer the other
//! form), at least 98 % of them are within 3σ, and at most 2 % of the runs
//! are flagged. Measured: z RMS 1.14, 99.0 % within 3σ, none flagged
//! (400 seeds from 1000 through `gsens montecarlo --loop-form-unknown`: z RMS
//! 0.98–1.02, docs/trust.md).

use gsens_calib::{EstimateSettings, LoopForm, PipelineSettings};
use gsens_core::LoggedPhase;
use gsens_montecarlo::{monte_carlo, scenario_settings};
use gsens_sim::scenario::Scenario;

#[test]
fn sigma_holds_when_the_data_choose_the_loops_form() {
    let mut scenario = Scenario::default();
    scenario.tracking_loop.interval_s = 0.02;
    scenario.log.interval_s = 0.02;
    scenario.log.phase = LoggedPhase::Last;
    let mut settings = PipelineSettings::default();
    settings.estimate = scenario_settings(&scenario, &EstimateSettings::default()).unwrap();
    settings.loop_form = LoopForm::Compared;
    let runs = 100;
    let mc = monte_carlo(&scenario, "20 ms", runs, 2000, &[settings], || {}).unwrap();
    let (mut z, mut flagged) = (Vec::new(), 0);
    for run in &mc.per_run {
        let Some(r) = run.methods[0].result.as_ref() else { continue };
        flagged += usize::from(!r.trustworthy);
        for i in 0..3 {
            if let (Some(g), Some(s)) = (r.gamma_hz_per_mps2[i], r.sigma_statistical_hz_per_mps2[i]) {
                z.push((g - run.gamma_imu_axes_hz_per_mps2[i]) / s);
            }
        }
    }
    let rms = (z.iter().map(|v| v * v).sum::<f64>() / z.len() as f64).sqrt();
    let within = z.iter().filter(|v| v.abs() <= 3.0).count() as f64 / z.len() as f64;
    eprintln!("{} axes: z RMS {rms:.2}, {:.1} % within 3σ, {flagged} of {runs} flagged", z.len(), 100.0 * within);
    assert!(z.len() >= 285, "{} axes estimated", z.len());
    assert!(rms <= 1.2 && within >= 0.98 && flagged <= 2, "z RMS {rms:.2}, {within:.3} within 3σ, {flagged} flagged");
}
