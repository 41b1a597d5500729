//! `gsens validate` prints its table and writes its trials and figure. The
//! trials themselves (the suppression, the slips) are tested where they are
//! made: `gsens-montecarlo`'s tests.

mod common;
use common::*;

#[test]
fn validate_prints_and_writes_its_trials_and_figure() {
    let dir = temp_dir("validate");
    let (out, figure) = (dir.join("trials.json"), dir.join("in_the_loop.png"));
    let (o, f) = (out.to_str().unwrap(), figure.to_str().unwrap());
    let text = gsens(&["validate", "--gamma", "0.09,0.08,-0.08", "--bn-hz", "3", "--json", o, "--figure", f]);
    assert!(text.contains("reduced by"), "{text}");
    assert!(std::fs::metadata(&figure).unwrap().len() > 10_000, "no figure");
    assert_eq!(json(&out).as_array().unwrap().len(), 1);
}
