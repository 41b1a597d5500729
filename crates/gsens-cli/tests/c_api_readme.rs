//! The README's C API walk-through ("The C API, step by step"), run as
//! written: its commands, taken from the README's block, build the static
//! library, export the estimator's input and the result document with
//! `gsens estimate`, compile and link `examples/c/calibrate.c` and run it;
//! the C program's Γ̂ is the pipeline's (the document's `gamma_hz_per_mps2`)
//! to 1e-9 relative.
//!
//! The commands run in a scratch folder (removed at the end) that holds
//! links to the repository's `examples` and `crates` and, as `target`, to
//! the cargo target directory the `cargo` command builds into: cargo runs in
//! the repository with `CARGO_TARGET_DIR` set to a directory beside this
//! test's own (a nested build in this test's target directory would wait for
//! the lock of the `cargo test` that runs it). `gsens` is this test's binary.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

/// The commands of the first `sh` block after `heading` in the README, with
/// continuation lines joined and comments dropped.
fn readme_commands(heading: &str) -> Vec<String> {
    let readme = std::fs::read_to_string(repo().join("README.md")).unwrap();
    let section = readme.split(heading).nth(1).unwrap_or_else(|| panic!("the README has {heading:?}"));
    let block = section.split("```sh\n").nth(1).and_then(|b| b.split("```").next()).expect("an sh block");
    let mut commands = Vec::new();
    let mut current = String::new();
    for line in block.lines() {
        // A comment starts at " #" (none of the commands has a '#' of its own).
        let code = line.split(" #").next().unwrap_or("").trim_end();
        let (code, continued) = match code.strip_suffix('\\') {
            Some(c) => (c.trim_end(), true),
            None => (code, false),
        };
        if !code.trim().is_empty() {
            if !current.is_empty() {
                current.push(' ');
            }
            current += code.trim();
        }
        if !continued && !current.is_empty() {
            commands.push(std::mem::take(&mut current));
        }
    }
    commands
}

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..").canonicalize().unwrap()
}

/// The target directory the README's `cargo build` builds into: beside this
/// test's (target/<profile>/deps/<test> → target/ffi-c-example).
fn ffi_target_dir() -> PathBuf {
    let exe = std::env::current_exe().unwrap();
    let target = exe.parent().and_then(Path::parent).and_then(Path::parent).unwrap();
    target.join("ffi-c-example")
}

#[cfg(unix)]
#[test]
fn the_readmes_c_api_commands_give_the_pipelines_gamma() {
    let commands = readme_commands("### The C API, step by step");
    assert!(commands.len() >= 5, "{commands:?}");
    assert!(commands[0].starts_with("cargo build --release -p gsens-ffi"), "{commands:?}");
    let dir = common::temp_dir("c-api-readme");
    let target = ffi_target_dir();
    std::fs::create_dir_all(&target).unwrap();
    for (link, to) in
        [("examples", repo().join("examples")), ("crates", repo().join("crates")), ("target", target.clone())]
    {
        std::os::unix::fs::symlink(to, dir.join(link)).unwrap();
    }
    let bin_dir = Path::new(env!("CARGO_BIN_EXE_gsens")).parent().unwrap().to_path_buf();
    let path = std::env::join_paths(
        std::iter::once(bin_dir).chain(std::env::split_paths(&std::env::var_os("PATH").unwrap_or_default())),
    )
    .unwrap();
    let mut output = String::new();
    for command in &commands {
        let mut sh = Command::new("sh");
        sh.arg("-c").arg(command).env("PATH", &path);
        if command.starts_with("cargo ") {
            sh.current_dir(repo()).env("CARGO_TARGET_DIR", &target);
        } else {
            sh.current_dir(&*dir);
        }
        let run = sh.output().unwrap_or_else(|e| panic!("{command}: {e}"));
        let code = run.status.code();
        // `gsens estimate` exits 3 for an estimate it does not trust; the README's session is trusted.
        assert_eq!(code, Some(0), "{command}: status {code:?}\n{}", String::from_utf8_lossy(&run.stderr));
        output = String::from_utf8(run.stdout).unwrap();
    }
    // The last command is the C program: its Γ̂ against the document's.
    let doc = common::json(&dir.join("r.json"));
    let pipeline = common::vec3(&doc["gamma_hz_per_mps2"]);
    eprintln!("{output}");
    for (i, axis) in ["x", "y", "z"].iter().enumerate() {
        let line = output.lines().find(|l| l.starts_with(&format!("gamma_{axis} "))).expect("a Γ̂ line per axis");
        let from_c: f64 = line.split_whitespace().nth(1).unwrap().parse().unwrap_or_else(|_| panic!("{line}"));
        let rel = ((from_c - pipeline[i]) / pipeline[i]).abs();
        eprintln!("{axis}: C {from_c:.17e}, pipeline {:.17e}, relative {rel:.1e}", pipeline[i]);
        assert!(rel <= 1e-9, "{axis}: the C program's Γ̂ {from_c} vs the pipeline's {} ({rel:e} relative)", pipeline[i]);
    }
}
