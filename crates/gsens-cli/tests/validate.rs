//! `gsens validate`: compensation in the loop, with Γ̂ from a calibration.
//!
//! - the default session (the paper's OCXO receiver, Γ̂ from its default
//!   calibration): the g-induced phase error under shaking is cut ≥ 10× at
//!   the calibration's 3 Hz, and at 1 Hz, where the uncompensated receiver
//!   slips, the compensated one slips no more than without g-sensitivity
//!   at all (none);
//! - a TCXO receiver (`examples/scenarios/tcxo.toml`, calibrated at 4 Hz):
//!   at 3 Hz the uncompensated receiver slips, the compensated one does not.
//!
//! The README's tables are these runs.

mod common;
use common::*;

/// The trials of `gsens validate` with `args`, written to a directory of
/// their own (`name`: the tests run at once in one process).
fn trials(name: &str, args: &[&str]) -> Vec<serde_json::Value> {
    let dir = temp_dir(&format!("validate-{name}"));
    let out = dir.join("trials.json");
    let figure = dir.join("in_the_loop.png");
    let mut all: Vec<&str> = args.to_vec();
    let (o, f) = (out.to_str().unwrap().to_string(), figure.to_str().unwrap().to_string());
    all.extend(["--json", &o, "--figure", &f]);
    let text = gsens(&all);
    assert!(text.contains("reduced by"), "{text}");
    assert!(std::fs::metadata(&figure).unwrap().len() > 10_000, "no figure");
    json(&out).as_array().unwrap().clone()
}

fn slips(t: &serde_json::Value) -> [u64; 3] {
    let s = t["cycle_slips"].as_array().unwrap();
    [0, 1, 2].map(|i| s[i].as_u64().unwrap())
}

#[test]
fn compensation_cuts_the_g_induced_error_tenfold_and_stops_the_slips() {
    let t = trials("default", &["validate", "--bn-hz", "3,1"]);
    let (at3, at1) = (&t[0], &t[1]);
    let suppression = at3["suppression"].as_f64().unwrap();
    assert!(suppression >= 10.0, "×{suppression} at 3 Hz");
    assert_eq!(slips(at3), [0, 0, 0]);
    let [reference, without, with] = slips(at1);
    assert!(without > 0, "the uncompensated receiver at 1 Hz does not slip: {:?}", slips(at1));
    assert_eq!((reference, with), (0, 0), "{:?}", slips(at1));
}

#[test]
fn a_tcxo_receiver_slips_at_3_hz_without_compensation_only() {
    let scenario = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/scenarios/tcxo.toml");
    let t = trials("tcxo", &["validate", "--scenario", scenario, "--bn-hz", "3"]);
    let [reference, without, with] = slips(&t[0]);
    assert!(without > 0, "{:?}", slips(&t[0]));
    assert_eq!((reference, with), (0, 0), "{:?}", slips(&t[0]));
}
