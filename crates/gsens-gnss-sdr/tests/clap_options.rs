//! The conversion's overrides as a command line's options (the `clap`
//! feature): named with the receiver before them.
#![cfg(feature = "clap")]

use clap::Parser;
use gsens_gnss_sdr::ImportOverrides;

#[derive(Parser)]
struct Cli {
    #[command(flatten)]
    overrides: ImportOverrides,
}

/// No option keeps every value of the configuration; each option, named
/// with the receiver before it, sets its own field.
#[test]
fn options_named_with_the_receiver_set_their_fields() {
    assert_eq!(Cli::try_parse_from(["gsens"]).unwrap().overrides, ImportOverrides::default());
    let args = [
        "gsens",
        "--gnss-sdr-min-cn0-dbhz",
        "-3",
        "--gnss-sdr-min-lock-test",
        "0.5",
        "--gnss-sdr-max-carrier-lock-fail",
        "7",
        "--gnss-sdr-max-lock-fail",
        "9",
        "--gnss-sdr-settle-s",
        "2.5",
        "--gnss-sdr-layout",
        "gnss-sdr-0.0.21",
    ];
    let overrides = ImportOverrides {
        min_cn0_dbhz: Some(-3.0),
        min_lock_test: Some(0.5),
        max_carrier_lock_fail: Some(7),
        max_lock_fail: Some(9),
        settle_s: Some(2.5),
        layout: Some("gnss-sdr-0.0.21".into()),
    };
    assert_eq!(Cli::try_parse_from(args).unwrap().overrides, overrides);
    assert!(Cli::try_parse_from(["gsens", "--min-cn0-dbhz", "30"]).is_err());
}
