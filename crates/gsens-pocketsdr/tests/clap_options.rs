//! A log's conversion as a command line's options (the `clap` feature):
//! named with the receiver before them.
#![cfg(feature = "clap")]

use clap::Parser;
use gsens_pocketsdr::ImportOptions;
use std::path::PathBuf;

#[derive(Parser)]
struct Cli {
    #[command(flatten)]
    options: ImportOptions,
}

/// No option names PocketSDR's defaults; each option, named with the
/// receiver before it, sets its own field.
#[test]
fn options_named_with_the_receiver_set_their_fields() {
    assert_eq!(Cli::try_parse_from(["gsens"]).unwrap().options, ImportOptions::default());
    let args = ["gsens", "--pocketsdr-conf", "trk.opt", "--pocketsdr-settle-s", "3", "--pocketsdr-toff-s", "-0.5"];
    let options = ImportOptions { conf: Some(PathBuf::from("trk.opt")), settle_s: Some(3.0), toff_s: -0.5 };
    assert_eq!(Cli::try_parse_from(args).unwrap().options, options);
}
