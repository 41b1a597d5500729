//! The README's promises: the demo block it shows is what `gsens demo` prints.

mod common;

use common::{gsens, s, temp_dir};

#[test]
fn readme_demo_block_is_what_the_demo_prints() {
    let readme = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../README.md")).unwrap();
    let section = readme.split("## What the demo shows").nth(1).expect("the README has the demo section");
    let block = section.split("```").nth(1).expect("a code block in the demo section");
    let dir = temp_dir("readme-demo");
    let out = gsens(&["demo", "--out", &s(&dir)]);
    let lines: Vec<&str> = block.lines().filter(|l| !l.trim().is_empty()).collect();
    assert!(lines.len() >= 6, "{block}");
    for line in lines {
        assert!(out.lines().any(|l| l == line), "README line not printed by `gsens demo`:\n{line}\n---\n{out}");
    }
    std::fs::remove_dir_all(&dir).ok();
}
