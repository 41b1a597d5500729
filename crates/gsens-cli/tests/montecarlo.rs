//! `gsens montecarlo` writes its statistics: the text and the JSON. The
//! statistics themselves are tested where they are made:
//! `gsens-montecarlo`'s tests.

mod common;

use common::{gsens, json, temp_dir};

/// The paper's session cut to 80 s: 20 s of shaking per axis, 5 s rests.
fn short_scenario() -> String {
    let rest = "[[motion.segments]]\nkind = \"rest\"\nduration_s = 5.0\n\n";
    let shake = |axis: &str| {
        format!(
            "[[motion.segments]]\nkind = \"shake\"\naxis = \"{axis}\"\nduration_s = 20.0\nperiod_s = 1.1\n\
             amplitude_mps2 = 3.0\n\n"
        )
    };
    ["x", "y", "z"].iter().map(|a| format!("{rest}{}", shake(a))).collect::<String>() + rest
}

#[test]
fn montecarlo_prints_and_writes_its_statistics() {
    let dir = temp_dir("montecarlo");
    let scenario = dir.join("short.toml");
    std::fs::write(&scenario, short_scenario()).unwrap();
    let out = dir.join("mc.json");
    let text = gsens(&[
        "montecarlo",
        "--scenario",
        scenario.to_str().unwrap(),
        "--runs",
        "2",
        "--methods",
        "batch,gls",
        "--json",
        out.to_str().unwrap(),
    ]);
    assert!(text.contains("RMSE/CRLB") && text.contains("gls"), "{text}");
    let v = json(&out);
    assert_eq!(v["per_run"].as_array().unwrap().len(), 2);
    assert!(v["methods"]["batch"].is_object() && v["methods"]["gls"].is_object(), "{}", v["methods"]);
}
