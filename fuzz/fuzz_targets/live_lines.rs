//! The live stream's lines (gsens_live::input): IMU, tracking and merged
//! lines; any text gives a record, a header, or an error, never a panic;
//! a merged record written back parses to itself.
#![no_main]
use gsens_live::{LineKind, merged_line, parse_imu_line, parse_merged_line, parse_tracking_line};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    for line in text.lines() {
        let _ = parse_imu_line(line);
        let _ = parse_tracking_line(line);
        if let Ok(LineKind::Data(input)) = parse_merged_line(line) {
            let again = merged_line(&input);
            match parse_merged_line(&again) {
                Ok(LineKind::Data(back)) => assert_eq!(merged_line(&back), again),
                other => panic!("{again:?} written back parses as {other:?}"),
            }
        }
    }
});
