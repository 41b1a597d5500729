//! The live stream's lines (gsens_live::input): IMU, tracking and merged
//! lines, each source read by its own parser (a tracking header sets the
//! columns of the rows after it); any text gives a record, a header, or an
//! error, never a panic; a merged record written back, after the header of
//! its columns, parses to itself.
#![no_main]
use gsens_live::{Input, LineFormat, LineKind, merged_header, merged_line};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    let (mut imu, mut tracking, mut merged) =
        (LineFormat::Imu.parser(), LineFormat::Tracking.parser(), LineFormat::Merged.parser());
    for line in text.lines() {
        let _ = imu.parse(line);
        let _ = tracking.parse(line);
        if let Ok(LineKind::Data(input)) = merged.parse(line) {
            let again = merged_line(&input);
            let mut fresh = LineFormat::Merged.parser();
            if let Input::Tracking(record) = &input {
                let header = merged_header(record);
                assert!(matches!(fresh.parse(&header), Ok(LineKind::Skip)), "{header:?} is no header");
            }
            match fresh.parse(&again) {
                Ok(LineKind::Data(back)) => assert_eq!(merged_line(&back), again),
                other => panic!("{again:?} written back parses as {other:?}"),
            }
        }
    }
});
