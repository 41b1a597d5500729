//! A live session fed the simulator's default session (the paper's
//! experiment: rest, x, y, z shaken 30 s each) record by record: the
//! guidance asks for x, then y, then z, and ends when every axis meets the
//! target σ, before the data end.

use gsens_live::{Instruction, LiveConfig, LiveSession, read_session_dir};

#[test]
fn asks_for_x_then_y_then_z_and_stops_at_the_target() {
    let dir_scratch = tempfile::Builder::new().prefix("gsens-live-seq-").tempdir().unwrap();
    let dir = dir_scratch.path().to_path_buf();
    let scenario = gsens_sim::scenario::Scenario::default();
    gsens_sim::simulate_to_dir(&scenario, 1, &dir, |_| {}).unwrap();
    let inputs = read_session_dir(&dir).unwrap();
    let settings = gsens_inputs::settings_of_simulated_session(&dir.join("truth.json")).unwrap();
    let mut live = LiveSession::new(LiveConfig::new(settings, 8e-4)).unwrap();
    let mut said: Vec<(f64, Instruction)> = Vec::new();
    let mut stopped_at = None;
    for (k, x) in inputs.iter().enumerate() {
        assert_eq!(live.push("replay", k as u64 + 1, *x), gsens_live::Pushed { used: true, notice: None });
        if let Some(job) = live.batch_due() {
            live.apply(job.run());
            if live.target_met() {
                stopped_at = Some(live.data_t_s());
                break;
            }
        }
        let v = live.view();
        if said.last().is_none_or(|(_, i)| {
            std::mem::discriminant(i) != std::mem::discriminant(&v.instruction) || i.axis() != v.instruction.axis()
        }) {
            said.push((v.data_t_s, v.instruction));
        }
    }
    let text: Vec<String> = said.iter().map(|(t, i)| format!("{t:7.2} s  {i}")).collect();
    eprintln!("{}", text.join("\n"));
    let stopped_at = stopped_at.unwrap_or_else(|| panic!("never met the target:\n{}", text.join("\n")));
    assert!(stopped_at < 125.0, "{stopped_at}");
    // The first time each axis is asked for: x, then y, then z.
    let first = |axis: usize| said.iter().position(|(_, i)| i.axis() == Some(axis));
    let (x, y, z) = (first(0), first(1), first(2));
    assert!(x.is_some() && x < y && y < z, "{}", text.join("\n"));
    // It starts by resting (the scenario's first 10 s), and y is asked for
    // only once x has enough: x's shaking ends at 40 s.
    assert!(matches!(said[1].1, Instruction::Rest { .. }), "{}", text.join("\n"));
    assert!(said[y.unwrap()].0 > 15.0, "{}", text.join("\n"));
    let view = live.view();
    assert!(view.axes.iter().all(|a| a.meets_target && a.sigma_hz_per_mps2.unwrap() <= 8e-4));
    assert_eq!(view.instruction, Instruction::Done);
    std::fs::remove_dir_all(&dir).ok();
}
