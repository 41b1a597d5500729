//! The Monte Carlo and the validation as every front end runs them: the
//! spread of the estimates against the Cramér–Rao bound on a shortened
//! paper session, reproducibility, the in-memory pipeline against the file
//! pipeline, and compensation in the loop with Γ̂ from a calibration.
//!
//! - the default session (the paper's OCXO receiver, Γ̂ from its default
//!   calibration): the g-induced phase error under shaking is cut ≥ 10× at
//!   the calibration's 3 Hz, and at 1 Hz, where the uncompensated receiver
//!   slips, the compensated one slips no more than without g-sensitivity
//!   at all (none);
//! - a TCXO receiver (`examples/scenarios/tcxo.toml`, calibrated at 4 Hz):
//!   at 3 Hz the uncompensated receiver slips, the compensated one does not.

use gsens_calib::{CalibrationOptions, MethodName};
use gsens_montecarlo::{ValidateError, calibrate_scenario, method_settings, monte_carlo, simulate_demo, validate};
use gsens_sim::compensation::CompensationSection;
use gsens_sim::compensation_trial::Trial;
use gsens_sim::scenario::Scenario;

/// A JSON array of three numbers (null → NaN).
fn vec3(v: &serde_json::Value) -> [f64; 3] {
    [0, 1, 2].map(|i| v[i].as_f64().unwrap_or(f64::NAN))
}

/// The paper's session cut to 80 s: 20 s of shaking per axis, 5 s rests.
fn short_scenario() -> String {
    let rest = "[[motion.segments]]\nkind = \"rest\"\nduration_s = 5.0\n\n";
    let shake = |axis: &str| {
        format!(
            "[[motion.segments]]\nkind = \"shake\"\naxis = \"{axis}\"\nduration_s = 20.0\nperiod_s = 1.1\n\
             amplitude_mps2 = 3.0\njitter = {{ period_rel = 0.07, amplitude_rel = 0.07, correlation_s = 3.0 }}\n\n"
        )
    };
    ["x", "y", "z"].iter().map(|a| format!("{rest}{}", shake(a))).collect::<String>() + rest
}

#[test]
fn gls_spread_is_at_the_cramer_rao_bound_and_runs_are_reproducible() {
    let scenario = Scenario::from_toml_str(&short_scenario()).unwrap();
    // The bound assumes the loop known: the loop check off (the offset is still estimated).
    let options = {
        let mut o = CalibrationOptions::default();
        o.systematic.loop_check = false;
        o
    };
    let methods = method_settings(&scenario, &options, &[MethodName::Batch, MethodName::Gls], Some(1.0)).unwrap();
    let run = || serde_json::to_value(monte_carlo(&scenario, "short", 30, 1, &methods, || {}).unwrap()).unwrap();
    let v = run();
    for m in ["batch", "gls"] {
        let s = &v["methods"][m];
        for key in ["bias", "rmse", "crlb", "rmse_over_crlb", "within_3sigma", "z_rms"] {
            assert!(vec3(&s[key]).iter().all(|x| x.is_finite()), "{m}.{key}: {}", s[key]);
        }
        assert_eq!(s["runs"], 30, "{m}: {s}");
    }
    let gls = &v["methods"]["gls"];
    let ratio = vec3(&gls["rmse_over_crlb"]);
    for i in 0..3 {
        assert!(ratio[i] <= 1.3, "axis {i}: GLS RMSE/CRLB {}", ratio[i]);
        // The bound is a bound: the spread is not far below it either.
        assert!(ratio[i] >= 0.7, "axis {i}: GLS RMSE/CRLB {}", ratio[i]);
        let bias = vec3(&gls["bias"])[i];
        let rmse = vec3(&gls["rmse"])[i];
        assert!(bias.abs() < 3.0 * rmse / 30f64.sqrt(), "axis {i}: bias {bias} vs RMSE {rmse}");
        let z = vec3(&gls["z_rms"])[i];
        assert!((0.7..1.3).contains(&z), "axis {i}: z RMS {z}");
    }
    // Same seed, same numbers (whatever the scheduling of the runs).
    let w = run();
    assert_eq!(v["methods"], w["methods"]);
    assert_eq!(v["per_run"], w["per_run"]);
}

#[test]
fn in_memory_runs_estimate_what_the_files_give() {
    let dir = tempfile::Builder::new().prefix("gsens-montecarlo-files-").tempdir().unwrap();
    // The tracking error only: the files' estimate is then the one the `batch` row makes.
    let scenario = Scenario::from_toml_str("[log]\nnco = false").unwrap();
    let options = CalibrationOptions::default();
    let demo = simulate_demo(&scenario, 3, dir.path(), &options, |_| {}).unwrap();
    let d: serde_json::Value =
        serde_json::from_str(&demo.document(&demo.calibrate().unwrap()).to_json_string().unwrap()).unwrap();
    let methods = method_settings(&scenario, &options, &[MethodName::Batch], Some(1.0)).unwrap();
    let m = serde_json::to_value(monte_carlo(&scenario, "default", 1, 3, &methods, || {}).unwrap()).unwrap();
    let run = &m["per_run"][0]["methods"][0];
    assert_eq!(run["method"], "batch");
    // The CSV files hold every digit: the two pipelines agree exactly.
    assert_eq!(run["gamma_hz_per_mps2"], d["gamma_hz_per_mps2"]);
    assert_eq!(run["crlb_hz_per_mps2"], d["crlb_hz_per_mps2"]);
    assert_eq!(run["sigma_statistical_hz_per_mps2"], d["sigma_statistical_hz_per_mps2"]);
}

/// The trials of a validation of `scenario` at `bandwidths_hz` with Γ̂ from
/// its own calibration (seed 1), on the session of seed 2.
fn trials(scenario: &Scenario, bandwidths_hz: &[f64]) -> Vec<Trial> {
    let gamma_hat = calibrate_scenario(scenario, 1).unwrap();
    let compensation = CompensationSection { gamma_hz_per_mps2: gamma_hat, latency_s: 0.0 };
    validate::<ValidateError>(scenario, 2, &compensation, bandwidths_hz, |_, _| Ok(())).unwrap()
}

#[test]
fn compensation_cuts_the_g_induced_error_tenfold_and_stops_the_slips() {
    let t = trials(&Scenario::default(), &[3.0, 1.0]);
    let (at3, at1) = (&t[0], &t[1]);
    assert!(at3.suppression >= 10.0, "×{} at 3 Hz", at3.suppression);
    assert_eq!(at3.cycle_slips, [0, 0, 0]);
    let [reference, without, with] = at1.cycle_slips;
    assert!(without > 0, "the uncompensated receiver at 1 Hz does not slip: {:?}", at1.cycle_slips);
    assert_eq!((reference, with), (0, 0), "{:?}", at1.cycle_slips);
    // The figure's trace: the channel drawn has rows under shaking.
    assert!(at3.trace.as_ref().is_some_and(|t| !t.t_s.is_empty()));
}

#[test]
fn a_tcxo_receiver_slips_at_3_hz_without_compensation_only() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/scenarios/tcxo.toml");
    let mut scenario = gsens_sim::load_scenario(Some(std::path::Path::new(path))).unwrap();
    // Compensated with Γ̂ through the loop model, as the tracking error alone gives it.
    scenario.log.nco = false;
    let t = trials(&scenario, &[3.0]);
    let [reference, without, with] = t[0].cycle_slips;
    assert!(without > 0, "{:?}", t[0].cycle_slips);
    assert_eq!((reference, with), (0, 0), "{:?}", t[0].cycle_slips);
}
