//! A validation ([`crate::validate`]) as the text table `gsens validate`
//! prints, one row per loop bandwidth as each trial is done: the setup
//! (the true Γ, the Γ̂ fed forward, the oscillator, the IMU and its latency,
//! the sessions' seed), the table's header, a row per trial, and a note on
//! the runs compared.

use gsens_sim::compensation_trial::{RUNS, Trial};
use gsens_sim::scenario::Scenario;

/// Γ̂ as the validation states it: `Γ̂ [Hz/(m/s²)] = [+x, +y, +z]`.
pub fn render_gamma_hat(gamma_hat: [f64; 3]) -> String {
    let g = gamma_hat;
    format!("Γ̂ [Hz/(m/s²)] = [{:+.5}, {:+.5}, {:+.5}]\n", g[0], g[1], g[2])
}

/// The setup of a validation of `gamma_hat` on `scenario` fed forward with
/// `latency_s` on the sessions of `seed`, and the table's header.
pub fn render_validate_header(scenario: &Scenario, gamma_hat: [f64; 3], latency_s: f64, seed: u64) -> String {
    let g = scenario.oscillator.gamma_hz_per_mps2;
    format!(
        "Γ [Hz/(m/s²)] of the oscillator: [{:+.5}, {:+.5}, {:+.5}]; Γ̂ fed forward: [{:+.5}, {:+.5}, {:+.5}]; {} \
         oscillator; IMU at {} Hz, latency {} s; the validation sessions use seed {}\n\n\
         \x20 Bn [Hz]   g-induced φ RMS under shaking [rad]      logged φ RMS [rad]       cycle slips          losses of lock\n\
         \x20          without    with      reduced by        ref    without with     ref  without with   ref  without with\n",
        g[0],
        g[1],
        g[2],
        gamma_hat[0],
        gamma_hat[1],
        gamma_hat[2],
        scenario.oscillator.preset.name(),
        scenario.imu.rate_hz,
        latency_s,
        seed
    )
}

/// The row of `trial`, run at `bn_hz`.
pub fn render_trial_row(bn_hz: f64, trial: &Trial) -> String {
    let [lr, lu, lc] = trial.logged_rms_rad;
    let [sr, su, sc] = trial.cycle_slips;
    let [or, ou, oc] = trial.losses_of_lock;
    format!(
        "  {bn_hz:6.2}    {:8.4}  {:8.4}    ×{:<8.1}      {lr:6.3} {lu:6.3} {lc:6.3}    {sr:5} {su:6} {sc:5}   {or:4} {ou:6} {oc:5}\n",
        trial.g_rms_rad[0], trial.g_rms_rad[1], trial.suppression
    )
}

/// The note under the table: the runs compared and what the columns count.
pub fn render_validate_footer() -> String {
    format!(
        "\nruns: {}; g-induced = the run's true phase error less the reference's, same noise; slips and losses: \
         the simulator's truth over all channels\n",
        RUNS.join(", ")
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use gsens_sim::compensation::CompensationSection;

    #[test]
    fn the_table_states_the_setup_and_one_row_per_trial() {
        let scenario = Scenario::default();
        let header = render_validate_header(&scenario, [0.1, -0.05, 0.0], 0.01, 2);
        let lines: Vec<&str> = header.lines().collect();
        assert_eq!(
            lines[0],
            "Γ [Hz/(m/s²)] of the oscillator: [+0.09000, +0.08000, -0.08000]; Γ̂ fed forward: [+0.10000, -0.05000, \
             +0.00000]; ocxo oscillator; IMU at 40 Hz, latency 0.01 s; the validation sessions use seed 2"
        );
        assert_eq!((lines.len(), lines[1]), (4, ""));
        assert!(lines[2].starts_with("  Bn [Hz]   g-induced φ RMS") && lines[3].starts_with("           without"));
        let trial = Trial {
            oscillator: "ocxo".into(),
            bn_hz: 3.0,
            gamma_hz_per_mps2: [0.09, 0.08, -0.08],
            compensation: CompensationSection { gamma_hz_per_mps2: [0.1, -0.05, 0.0], latency_s: 0.01 },
            g_rms_rad: [0.1389, 0.0099],
            suppression: 14.03,
            logged_rms_rad: [0.092, 0.167, 0.093],
            cycle_slips: [0, 12, 0],
            losses_of_lock: [0, 1, 0],
            channels: vec![],
            trace: None,
        };
        assert_eq!(
            render_trial_row(3.0, &trial),
            "    3.00      0.1389    0.0099    ×14.0           0.092  0.167  0.093        0     12     0      0      1     0\n"
        );
        assert_eq!(render_gamma_hat([0.08939, 0.07914, -0.0799]), "Γ̂ [Hz/(m/s²)] = [+0.08939, +0.07914, -0.07990]\n");
        assert!(render_validate_footer().starts_with("\nruns: reference (Γ = 0), uncompensated, compensated; "));
    }
}
