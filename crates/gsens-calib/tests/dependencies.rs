//! The crate graph's rules, read from the workspace's manifests: the
//! calibration knows logs, loops and settings, not where they came from, so
//! it depends on no receiver's crate, on no shell and not on the simulator;
//! every receiver's crate is an adapter that depends on it; the simulator
//! does not reach into the calibration. `docs/architecture.md` draws the
//! graph.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// Every workspace crate's gsens dependencies (`[dependencies]` only:
/// dev-dependencies do not shape the graph a user builds).
fn graph() -> BTreeMap<String, BTreeSet<String>> {
    let crates = Path::new(env!("CARGO_MANIFEST_DIR")).parent().unwrap();
    let mut graph = BTreeMap::new();
    for entry in std::fs::read_dir(crates).unwrap() {
        let manifest = entry.unwrap().path().join("Cargo.toml");
        let Ok(text) = std::fs::read_to_string(&manifest) else { continue };
        let table: toml::Table = text.parse().unwrap_or_else(|e| panic!("{}: {e}", manifest.display()));
        let name = table["package"]["name"].as_str().unwrap().to_string();
        let deps = table
            .get("dependencies")
            .and_then(|d| d.as_table())
            .map_or_else(BTreeSet::new, |d| d.keys().filter(|k| k.starts_with("gsens-")).cloned().collect());
        graph.insert(name, deps);
    }
    graph
}

/// Everything `name` depends on, directly or not.
fn reach(graph: &BTreeMap<String, BTreeSet<String>>, name: &str) -> BTreeSet<String> {
    let mut seen = BTreeSet::new();
    let mut todo = vec![name.to_string()];
    while let Some(n) = todo.pop() {
        for d in &graph[&n] {
            if seen.insert(d.clone()) {
                todo.push(d.clone());
            }
        }
    }
    seen
}

const RECEIVERS: [&str; 2] = ["gsens-gnss-sdr", "gsens-pocketsdr"];

#[test]
fn calibration_depends_on_no_receiver_no_shell_and_not_on_the_simulator() {
    let graph = graph();
    assert!(graph.len() >= 14, "{:?}", graph.keys());
    let calib = reach(&graph, "gsens-calib");
    let allowed: BTreeSet<String> = ["gsens-core", "gsens-io", "gsens-session"].map(String::from).into();
    assert!(calib.is_subset(&allowed), "gsens-calib reaches {calib:?}");
    assert!(graph["gsens-core"].is_empty(), "{:?}", graph["gsens-core"]);
    let sim = reach(&graph, "gsens-sim");
    assert!(!sim.contains("gsens-calib"), "gsens-sim reaches {sim:?}");
}

#[test]
fn every_receiver_is_an_adapter_over_the_calibration() {
    let graph = graph();
    for receiver in RECEIVERS {
        assert!(graph[receiver].contains("gsens-calib"), "{receiver}: {:?}", graph[receiver]);
        let others: Vec<_> =
            RECEIVERS.iter().filter(|r| **r != receiver && reach(&graph, receiver).contains(**r)).collect();
        assert!(others.is_empty(), "{receiver} reaches {others:?}");
    }
}

/// Format readers many receivers share: they read into the format layer's
/// types, and the calibration of what they read is calib's own.
const READERS: [&str; 2] = ["gsens-rinex", "gsens-ublox"];

#[test]
fn format_readers_read_formats_only() {
    let graph = graph();
    let allowed: BTreeSet<String> = ["gsens-core", "gsens-io"].map(String::from).into();
    for reader in READERS {
        let reached = reach(&graph, reader);
        assert!(reached.is_subset(&allowed), "{reader} reaches {reached:?}");
    }
    for receiver in RECEIVERS {
        let reached = reach(&graph, receiver);
        assert!(READERS.iter().all(|r| !reached.contains(*r)), "{receiver} reaches {reached:?}");
    }
}
