//! A logger that stops, restarts, sends garbage or bursts: the session says
//! so once per burst and goes on with what it can use.

use gsens_calib::PipelineSettings;
use gsens_io::{TrackingRecord, TrackingRow};
use gsens_live::{Input, LineFormat, LineKind, LiveConfig, LiveSession};

fn imu(t_s: f64) -> Input {
    Input::Imu { t_s, accel_mps2: [0.0, 0.0, 9.81] }
}

fn trk(t_s: f64, channel: u32) -> Input {
    let row = TrackingRow { t_s, channel, prn: channel + 1, cn0_dbhz: 45.0, elev_deg: None, phase_err_rad: 0.01 };
    Input::Tracking(TrackingRecord::plain(row))
}

#[test]
fn time_going_back_is_one_notice_per_burst_and_the_session_goes_on() {
    let mut s = LiveSession::new(LiveConfig::new(PipelineSettings::default(), 1e-3)).unwrap();
    for k in 0..100 {
        assert!(s.push("stdin", k + 1, imu(k as f64 * 0.025)).notice.is_none());
    }
    // A restarted logger: its clock starts again at 0. One notice, then silence.
    let first = s.push("stdin", 101, imu(0.0)).notice.expect("a notice");
    assert!(first.message.contains("not after the previous"), "{first}");
    assert_eq!(first.to_string().split(':').next(), Some("stdin"));
    for k in 1..50 {
        assert!(s.push("stdin", 101 + k, imu(k as f64 * 0.025)).notice.is_none());
    }
    // Time passes the last good sample: used again, and the burst is counted.
    let summary = s.push("stdin", 200, imu(3.0)).notice.expect("the burst's count");
    assert!(summary.message.contains("49 more records refused"), "{summary}");
    assert_eq!(s.view().received.0, 101);
    // A channel twice at a time stamp, and tracking going back.
    assert!(s.push("stdin", 201, trk(3.0, 0)).notice.is_none());
    assert!(s.push("stdin", 202, trk(3.0, 1)).notice.is_none());
    assert!(s.push("stdin", 203, trk(3.0, 1)).notice.unwrap().message.contains("channel 1 twice"));
    // A single refused record needs no count.
    assert!(s.push("stdin", 204, trk(3.025, 0)).notice.is_none());
    assert!(s.push("stdin", 205, trk(2.0, 0)).notice.unwrap().message.contains("before the previous row"));
    assert_eq!(s.view().received.1, 3);
    assert_eq!(s.view().notices.1, 4);
}

#[test]
fn garbage_lines_are_errors_naming_the_column() {
    for (line, what) in [
        ("imu,1.0,0.0,0.0", "column 5 (`fz_mps2`) missing"),
        ("\u{0}\u{1}binary", "neither `imu` nor `trk`"),
        ("trk,1.0,0,5,45.0,,nan", "column 7 (`phase_err_rad`): `nan` is not a finite number"),
        ("imu,1.0,0.0,0.0,9.8,7", "more than 5 columns"),
    ] {
        let e = LineFormat::Merged.parser().parse(line).unwrap_err().to_string();
        assert!(e.contains(what), "{line:?}: {e}");
    }
    assert_eq!(LineFormat::Merged.parser().parse("").unwrap(), LineKind::Skip);
}
