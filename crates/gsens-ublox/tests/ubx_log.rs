//! The reader against the fixture script's log (tests/fixtures/README.md) and against frames
//! written here byte by byte from the u-blox interface description.

use std::collections::BTreeSet;

use gsens_io::obs_flags;
use gsens_ublox::{SensorTime, UbxError, UbxSettings, UbxStream, read_ubx_bytes, read_ubx_file};

const FIXTURE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fixtures/sim.ubx");

fn fixture_csv(name: &str) -> Vec<Vec<String>> {
    let path = format!("{}/tests/fixtures/{name}", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(path).unwrap();
    text.lines().skip(1).map(|l| l.split(',').map(str::to_owned).collect()).collect()
}

/// The offsets of the frames in a UBX byte stream (sync, class, id, length), walked by hand.
fn frame_offsets(bytes: &[u8]) -> Vec<(usize, u8, u8, usize)> {
    let mut out = Vec::new();
    let mut i = 0;
    while i + 8 <= bytes.len() {
        assert_eq!(&bytes[i..i + 2], [0xB5, 0x62], "a frame at byte {i}");
        let len = usize::from(u16::from_le_bytes([bytes[i + 4], bytes[i + 5]]));
        out.push((i, bytes[i + 2], bytes[i + 3], len));
        i += 8 + len;
    }
    out
}

#[test]
fn every_value_the_script_wrote_reads_back() {
    let log = read_ubx_file(FIXTURE, &UbxSettings::default()).unwrap();
    let obs = &log.observations;
    assert!(obs.validate().is_ok());
    assert_eq!((obs.format.as_str(), obs.gps_week), ("UBX", 2300));
    assert!(obs.skipped.is_empty(), "{:?}", obs.skipped);
    assert_eq!(log.bytes_outside_frames, 0);
    let rows = fixture_csv("expected_obs.csv");
    let epochs: BTreeSet<&str> = rows.iter().map(|r| r[1].as_str()).collect();
    assert_eq!(obs.epochs, epochs.len());
    let mut seen = 0;
    let mut slips = 0;
    for track in &obs.tracks {
        assert_eq!((track.code.as_str(), track.carrier.label()), ("1C", "L1CA".to_owned()));
        let mine: Vec<_> = rows.iter().filter(|r| r[2] == track.sv).collect();
        assert_eq!(track.len(), mine.len(), "{}", track.sv);
        for (i, r) in mine.iter().enumerate() {
            let num = |j: usize| r[j].parse::<f64>().unwrap();
            assert_eq!(r[0], "2300");
            // One week: t_s is the time of week itself, exactly as written (R8).
            assert_eq!(track.t_s[i], num(1));
            assert_eq!(track.pseudorange_m[i], num(3));
            assert_eq!(track.carrier_phase_cycles[i], num(4));
            // doMes is R4: the value rounded to single precision.
            assert_eq!(track.doppler_hz[i], f64::from(num(5) as f32));
            assert_eq!(track.cn0_dbhz[i], num(10));
            assert_eq!(track.lock_time_s[i], num(9) * 1e-3);
            // trkStat 0x07 throughout; loss of lock exactly where the script restarted the lock.
            let lli = r[7] == "1";
            assert_eq!(track.flags[i], if lli { obs_flags::LOSS_OF_LOCK } else { 0 }, "{} row {i}", track.sv);
            slips += usize::from(lli);
            seen += 1;
        }
        assert!(track.strength.is_empty());
    }
    assert_eq!(seen, rows.len());
    assert!(slips > 0, "the fixture holds gaps");
}

#[test]
fn the_imu_and_its_time_mapping_read_back() {
    let log = read_ubx_file(FIXTURE, &UbxSettings::default()).unwrap();
    let rows = fixture_csv("expected_imu.csv");
    assert_eq!(log.imu.len(), rows.len());
    assert!(log.imu.validate("imu").is_ok());
    // The script puts the last sample of each ESF-RAW at its RXM-RAWX epoch, so the anchor is exact.
    let anchor = log.imu_anchor.unwrap();
    assert_eq!(anchor.at_t_s, 388_818.2);
    let sttag0: f64 = rows[0][1].parse().unwrap();
    assert!((anchor.gps_minus_sensor_s - (388_818.0 - sttag0 * 1e-3)).abs() < 1e-6);
    let lsb = |s: &str| {
        let f: i64 = s.parse().unwrap();
        (if f >= 1 << 23 { f - (1 << 24) } else { f }) as f64 / 1024.0
    };
    let mut wrapped = false;
    for (i, r) in rows.iter().enumerate() {
        let tow: f64 = r[0].parse().unwrap();
        assert!((log.imu.t_s[i] - tow).abs() < 1e-6, "sample {i}: {} vs {tow}", log.imu.t_s[i]);
        assert_eq!(log.imu.accel_mps2[i], [lsb(&r[2]), lsb(&r[3]), lsb(&r[4])]);
        wrapped |= i > 0 && r[1].parse::<u64>().unwrap() < rows[i - 1][1].parse::<u64>().unwrap();
    }
    assert!(wrapped, "the fixture's sensor clock wraps");
    // Resting on z: about +9.8 m/s².
    assert!((log.imu.accel_mps2[0][2] - 9.8).abs() < 0.2);
}

#[test]
fn corrupt_truncated_and_foreign_frames_are_skipped_and_counted() {
    let clean = std::fs::read(FIXTURE).unwrap();
    let frames = frame_offsets(&clean);
    let good = read_ubx_bytes(&clean, "sim.ubx", &UbxSettings::default()).unwrap();
    // Corrupt the payload of the 5th RXM-RAWX (one byte of its first prMes).
    let rawx: Vec<_> = frames.iter().filter(|f| (f.1, f.2) == (0x02, 0x15)).collect();
    let (at, ..) = *rawx[4];
    let mut bytes = clean.clone();
    bytes[at + 6 + 16] ^= 0x40;
    // A frame of a message no crate knows (class 0x7F) and 5 garbage bytes between two frames.
    let foreign = frame(0x7F, 0x01, &[1, 2]);
    let (next, ..) = *rawx[6];
    let mut spliced = bytes[..next].to_vec();
    spliced.extend_from_slice(&[0x00, 0x11, 0x22, 0x33, 0x44]);
    spliced.extend_from_slice(&foreign);
    spliced.extend_from_slice(&bytes[next..]);
    // Cut the log inside its last frame.
    spliced.truncate(spliced.len() - 10);
    let log = read_ubx_bytes(&spliced, "bad.ubx", &UbxSettings::default()).unwrap();
    let count = |reason: &str| log.observations.skipped.iter().find(|s| s.reason == reason).map_or(0, |s| s.count);
    assert_eq!(count("bad checksum (frame dropped)"), 1, "{:?}", log.observations.skipped);
    assert_eq!(count("message 0x7F 0x01 (not read)"), 1);
    assert_eq!(count("incomplete frame at the end of the log"), 1);
    assert_eq!(log.frames, good.frames - 2 + 1);
    let last_len = frames.last().unwrap().3 + 8;
    assert_eq!(log.bytes_outside_frames, (rawx[4].3 + 8) + 5 + (last_len - 10));
    // The corrupt RXM-RAWX is one epoch fewer; an ESF-RAW cut off is its samples fewer.
    assert_eq!(log.observations.epochs, good.observations.epochs - usize::from(frames.last().unwrap().1 == 0x02) - 1);
    assert!(log.imu.len() < good.imu.len());
}

#[test]
fn a_log_without_data_is_an_error_naming_the_file() {
    let err = read_ubx_bytes(&[0xB5, 0x62, 0x02], "empty.ubx", &UbxSettings::default()).unwrap_err();
    assert!(matches!(err, UbxError::NoData { .. }));
    let m = err.to_string();
    assert!(m.starts_with("empty.ubx: no UBX-RXM-RAWX") && m.contains("incomplete frame"), "{m}");
    let err = read_ubx_file("/nonexistent/x.ubx", &UbxSettings::default()).unwrap_err();
    assert!(err.to_string().starts_with("/nonexistent/x.ubx: cannot read"), "{err}");
}

/// A UBX frame: sync, class, id, length, payload, 8-bit Fletcher checksum (interface description).
fn frame(class: u8, id: u8, payload: &[u8]) -> Vec<u8> {
    let mut body = vec![class, id];
    body.extend_from_slice(&(payload.len() as u16).to_le_bytes());
    body.extend_from_slice(payload);
    let (mut a, mut b) = (0u8, 0u8);
    for &x in &body {
        a = a.wrapping_add(x);
        b = b.wrapping_add(a);
    }
    let mut out = vec![0xB5, 0x62];
    out.extend(body);
    out.extend([a, b]);
    out
}

/// One RXM-RAWX frame (version 1, one GLONASS measurement) and one ESF-MEAS frame, written out
/// byte by byte from the interface description, checksums included.
#[rustfmt::skip]
const HAND_WRITTEN: [u8; 84] = [
    // RXM-RAWX: sync, class 0x02, id 0x15, length 48
    0xB5, 0x62, 0x02, 0x15, 0x30, 0x00,
    // rcvTow R8 = 100.5 s, week U2 = 2300, leapS I1 = 18, numMeas 1, recStat 0x03 (leapSec, clkReset),
    // version 1, reserved
    0x00, 0x00, 0x00, 0x00, 0x00, 0x20, 0x59, 0x40, 0xFC, 0x08, 0x12, 0x01, 0x03, 0x01, 0x00, 0x00,
    // prMes R8 = 2.0e7 m
    0x00, 0x00, 0x00, 0x00, 0xD0, 0x12, 0x73, 0x41,
    // cpMes R8 = 105100000.25 cycles
    0x00, 0x00, 0x00, 0x81, 0xCB, 0x0E, 0x99, 0x41,
    // doMes R4 = -1234.5 Hz
    0x00, 0x50, 0x9A, 0xC4,
    // gnssId 6 (GLONASS), svId 12, sigId 0 (L1OF), freqId 3 (k = -4), locktime U2 = 1500 ms,
    // cno 42 dB-Hz, prStdev, cpStdev, doStdev, trkStat 0x03 (prValid, cpValid; halfCyc clear), reserved
    0x06, 0x0C, 0x00, 0x03, 0xDC, 0x05, 0x2A, 0x05, 0x03, 0x04, 0x03, 0x00,
    // CK_A, CK_B
    0xC2, 0x91,
    // ESF-MEAS: sync, class 0x10, id 0x02, length 20; timeTag U4 = 5000 ms, flags X2 = numMeas 3 << 11,
    // id U2 = 0
    0xB5, 0x62, 0x10, 0x02, 0x14, 0x00, 0x88, 0x13, 0x00, 0x00, 0x00, 0x18, 0x00, 0x00,
    // data: type 16 (acc x) field 0xFFFC00 = -1024 LSB; type 17 field 2048; type 18 field 10048
    0x00, 0xFC, 0xFF, 0x10, 0x00, 0x08, 0x00, 0x11, 0x40, 0x27, 0x00, 0x12,
    // CK_A, CK_B
    0x76, 0x45,
];

#[test]
fn frames_written_from_the_interface_description_decode_to_their_fields() {
    assert_eq!(HAND_WRITTEN[..56], frame(0x02, 0x15, &HAND_WRITTEN[6..54])[..]);
    let log = read_ubx_bytes(&HAND_WRITTEN, "hand.ubx", &UbxSettings::default()).unwrap();
    assert_eq!((log.frames, log.bytes_outside_frames), (2, 0));
    let obs = &log.observations;
    assert_eq!((obs.gps_week, obs.epochs, obs.tracks.len()), (2300, 1, 1));
    let r = &obs.tracks[0];
    assert_eq!((r.sv.as_str(), r.code.as_str(), r.carrier.label()), ("R12", "1C", "G1:-4".to_owned()));
    assert_eq!(r.carrier.carrier_hz, 1_602e6 - 4.0 * 562.5e3);
    assert_eq!((r.t_s[0], r.pseudorange_m[0], r.carrier_phase_cycles[0]), (100.5, 2.0e7, 105_100_000.25));
    assert_eq!((r.doppler_hz[0], r.cn0_dbhz[0], r.lock_time_s[0]), (-1234.5, 42.0, 1.5));
    assert_eq!(r.flags[0], obs_flags::HALF_CYCLE_AMBIGUOUS);
    assert_eq!(obs.clock_events.len(), 1);
    assert_eq!((obs.clock_events[0].t_s, obs.clock_events[0].jump_s), (100.5, None));
    // ESF-MEAS after the RXM-RAWX: its sample is tied to rcvTow.
    assert_eq!(log.imu.accel_mps2, [[-1.0, 2.0, 9.8125]]);
    assert_eq!(log.imu.t_s, [100.5]);
    assert_eq!(log.imu_anchor.unwrap().gps_minus_sensor_s, 100.5 - 5.0);
    // Read as GPS time of week, the tag is 5 s.
    let tow = UbxSettings { sensor_time: SensorTime::GpsTowMs };
    assert_eq!(read_ubx_bytes(&HAND_WRITTEN, "hand.ubx", &tow).unwrap().imu.t_s, [5.0]);
}

/// The log with one RXM-RAWX's checksum broken (a payload byte flipped) and
/// 5 garbage bytes before the 8th.
fn corrupted() -> Vec<u8> {
    let clean = std::fs::read(FIXTURE).unwrap();
    let frames = frame_offsets(&clean);
    let rawx: Vec<_> = frames.iter().filter(|f| (f.1, f.2) == (0x02, 0x15)).collect();
    let mut bytes = clean.clone();
    bytes[rawx[4].0 + 6 + 16] ^= 0x40;
    let at = rawx[7].0;
    let mut spliced = bytes[..at].to_vec();
    spliced.extend_from_slice(&[0xB5, 0x00, 0x62, 0x11, 0x22]);
    spliced.extend_from_slice(&bytes[at..]);
    spliced
}

/// A stream fed in pieces of every size from 1 to 97 bytes (cut inside
/// frames, inside the sync and the length) reads the log
/// `read_ubx_bytes` reads from the whole: every value, every count. Its
/// snapshot part way is the log of the complete frames so far, and a clone
/// made there, fed the rest, reads the same log.
#[test]
fn a_stream_read_in_pieces_is_the_log_read_whole() {
    let bytes = corrupted();
    let settings = UbxSettings::default();
    let whole = read_ubx_bytes(&bytes, "s.ubx", &settings).unwrap();
    assert_eq!(whole.observations.skipped.iter().map(|s| s.count).sum::<usize>(), 1);
    for (sizes, cut) in [(1..=97usize, 40_001usize), (7..=7, 20_003), (4096..=4096, 60_000)] {
        let mut stream = UbxStream::new("s.ubx");
        let mut clone: Option<UbxStream> = None;
        let (mut at, mut snapshot_checked) = (0, false);
        for size in sizes.cycle() {
            if at >= bytes.len() {
                break;
            }
            let end = (at + size).min(bytes.len());
            stream.push(&bytes[at..end]);
            if let Some(c) = clone.as_mut() {
                c.push(&bytes[at..end]);
            }
            at = end;
            if !snapshot_checked && at >= cut {
                snapshot_checked = true;
                let complete = at - stream.waiting_bytes();
                assert!(stream.waiting_bytes() < 8 + 16 + 32 * 40, "{}", stream.waiting_bytes());
                let part = stream.snapshot(&settings).unwrap();
                let read = read_ubx_bytes(&bytes[..complete], "s.ubx", &settings).unwrap();
                assert_eq!(part, read);
                clone = Some(stream.clone());
            }
        }
        assert_eq!(stream.received_bytes(), bytes.len());
        assert_eq!((stream.checksum_failures(), stream.skipped()), (1, 1));
        assert_eq!((stream.frames(), stream.epochs()), (whole.frames, whole.observations.epochs));
        assert_eq!(stream.finish(&settings).unwrap(), whole);
        assert_eq!(clone.unwrap().finish(&settings).unwrap(), whole);
    }
}

/// The accelerometer samples handed out as frames arrive are, together,
/// the IMU of the log read whole: none before the sensor clock is tied to
/// an RXM-RAWX epoch, each once.
#[test]
fn the_stream_hands_out_each_imu_sample_once_on_the_logs_time() {
    let bytes = std::fs::read(FIXTURE).unwrap();
    for settings in [UbxSettings::default(), UbxSettings { sensor_time: SensorTime::GpsTowMs }] {
        let whole = read_ubx_bytes(&bytes, "s.ubx", &settings).unwrap();
        let mut stream = UbxStream::new("s.ubx");
        let mut taken = gsens_io::ImuSeries::default();
        for piece in bytes.chunks(333) {
            stream.push(piece);
            let new = stream.take_imu(&settings);
            taken.t_s.extend(new.t_s);
            taken.accel_mps2.extend(new.accel_mps2);
        }
        assert_eq!(taken, whole.imu, "{settings:?}");
    }
}
