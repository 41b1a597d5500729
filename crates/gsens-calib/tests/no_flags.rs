//! No library speaks of command-line flags: the texts of warnings, errors
//! and notes name options as every front end shares them (`order`, `bn_hz`,
//! `loop_interval_s`, …); a shell adds its own spelling. Read from the
//! sources of every crate but the command line's.

use std::path::{Path, PathBuf};

/// Every `.rs` file under `dir`.
fn sources(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            sources(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The `--name` flags on a line of code (its comment cut off): `--`
/// followed by a lowercase letter, not inside a longer dash run.
fn flags(line: &str) -> Vec<&str> {
    let code = line.split("//").next().unwrap_or("");
    let b = code.as_bytes();
    let mut found = Vec::new();
    for i in 0..b.len().saturating_sub(2) {
        let starts = b[i] == b'-' && b[i + 1] == b'-' && b[i + 2].is_ascii_lowercase();
        if starts && (i == 0 || b[i - 1] != b'-') {
            let end = (i + 2..b.len()).find(|&j| !(b[j].is_ascii_alphanumeric() || b[j] == b'-' || b[j] == b'_'));
            found.push(&code[i..end.unwrap_or(b.len())]);
        }
    }
    found
}

#[test]
fn no_library_text_names_a_command_line_flag() {
    let crates = Path::new(env!("CARGO_MANIFEST_DIR")).parent().unwrap();
    let mut named = Vec::new();
    for entry in std::fs::read_dir(crates).unwrap() {
        let dir = entry.unwrap().path();
        if dir.file_name().is_some_and(|n| n == "gsens-cli") {
            continue;
        }
        let mut files = Vec::new();
        if dir.join("src").is_dir() {
            sources(&dir.join("src"), &mut files);
        }
        for file in files {
            // The report's style sheet has custom properties (`--fg`), not flags.
            if file.ends_with("gsens-report/src/html.rs") {
                continue;
            }
            let text = std::fs::read_to_string(&file).unwrap();
            for (k, line) in text.lines().enumerate() {
                let trimmed = line.trim_start();
                if trimmed.starts_with("//") || trimmed.starts_with("#[ignore") {
                    continue;
                }
                // GNSS-SDR's own command line, in the configuration gsens writes for it.
                for flag in flags(line).into_iter().filter(|f| *f != "--config_file") {
                    named.push(format!("{}:{}: {flag}", file.display(), k + 1));
                }
            }
        }
    }
    assert!(named.is_empty(), "library texts naming command-line flags:\n{}", named.join("\n"));
}

#[test]
fn flags_are_found_in_code_not_in_comments() {
    assert_eq!(flags(r#"format!("state it (--bn-hz {bn})") // --order"#), ["--bn-hz"]);
    assert!(flags("let x = a - -b; // ---- rule ----").is_empty());
    assert!(flags("\"bn_hz, loop_interval_s\"").is_empty());
}
