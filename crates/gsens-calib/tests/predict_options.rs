//! A prediction's receiver as a command line's options (the `clap`
//! feature): a static GPS L1 receiver by default.
#![cfg(feature = "clap")]

use clap::Parser;
use gsens_calib::predict::{FeedForward, ReceiverConditions};

#[derive(Parser)]
struct Cli {
    #[command(flatten)]
    receiver: ReceiverConditions,
}

/// No option is a static GPS L1 receiver: C/N0 45 dB-Hz, a 3 Hz loop
/// damped 1/√2 at 1 ms, a 40 Hz IMU without latency or noise, a Doppler
/// rate of 0.9 Hz/s; each option sets its field, and a value out of its
/// range is refused.
#[test]
fn no_option_is_a_static_l1_receiver_and_each_sets_its_field() {
    let defaults = ReceiverConditions {
        cn0_dbhz: Some(45.0),
        bn_hz: 3.0,
        zeta: 0.5f64.sqrt(),
        loop_interval_s: 0.001,
        feed_forward: FeedForward { imu_rate_hz: 40.0, latency_s: 0.0 },
        imu_noise_mps2_per_rthz: 0.0,
        doppler_rate_hz_per_s: 0.9,
    };
    let parsed = Cli::try_parse_from(["gsens"]).unwrap().receiver;
    assert!((parsed.zeta - defaults.zeta).abs() < 1e-15);
    assert_eq!(ReceiverConditions { zeta: defaults.zeta, ..parsed }, defaults);
    let args = ["gsens", "--cn0-dbhz", "38", "--bn-hz", "10", "--imu-rate-hz", "100", "--latency-s", "0.002"];
    let parsed = Cli::try_parse_from(args).unwrap().receiver;
    let feed_forward = FeedForward { imu_rate_hz: 100.0, latency_s: 0.002 };
    assert_eq!((parsed.cn0_dbhz, parsed.bn_hz, parsed.feed_forward), (Some(38.0), 10.0, feed_forward));
    assert!(Cli::try_parse_from(["gsens", "--bn-hz", "-1"]).is_err());
    assert!(Cli::try_parse_from(["gsens", "--latency-s", "-0.1"]).is_err());
}
