//! A u-blox module's UBX stream through `gsens_live::Runtime` on an injected
//! clock and injected events: the fixture script's log (tests/fixtures/README.md)
//! arriving in pieces cut inside frames, with a frame corrupted on the way.
//! No test waits on the wall clock.

use std::sync::Arc;
use std::sync::mpsc;

use gsens_calib::{ObservationRecord, PipelineSettings};
use gsens_inputs::{ObservationFile, ObservationInputs};
use gsens_live::{Display, Ending, Inputs, ManualClock, Runtime, RuntimeConfig, Source, SourceEvent, UbxOptions};

const FIXTURE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fixtures/shaken.ubx");

/// The offsets of the RXM-RAWX frames (class 0x02, id 0x15), walked by hand
/// from the frames' lengths.
fn rawx_offsets(bytes: &[u8]) -> Vec<usize> {
    let mut out = Vec::new();
    let mut i = 0;
    while i + 8 <= bytes.len() {
        assert_eq!(&bytes[i..i + 2], [0xB5, 0x62], "a frame at byte {i}");
        if bytes[i + 2..i + 4] == [0x02, 0x15] {
            out.push(i);
        }
        i += 8 + usize::from(u16::from_le_bytes([bytes[i + 4], bytes[i + 5]]));
    }
    out
}

/// Pieces of 1 to 3000 bytes, their sizes from a fixed sequence: most cut a
/// frame somewhere inside.
fn pieces(bytes: &[u8]) -> Vec<&[u8]> {
    let mut out = Vec::new();
    let (mut at, mut k) = (0usize, 0usize);
    while at < bytes.len() {
        let size = (k * 7919) % 3000 + 1;
        let end = (at + size).min(bytes.len());
        out.push(&bytes[at..end]);
        (at, k) = (end, k + 1);
    }
    out
}

/// The log arrives in pieces with one RXM-RAWX's payload damaged (its
/// checksum fails): the plain lines show batch estimates with the loop
/// identified and the dropped frame counted, the bytes are kept as they
/// came, and the final estimate is, to the last digit, the one
/// `gsens estimate --ubx` makes of the whole file (the observation route it
/// runs, on a copy of the damaged log).
#[test]
fn a_stream_in_pieces_ends_with_the_estimate_of_the_whole_log() {
    let scratch = tempfile::Builder::new().prefix("gsens-live-ubx-").tempdir().unwrap();
    let mut bytes = std::fs::read(FIXTURE).unwrap();
    let rawx = rawx_offsets(&bytes);
    assert_eq!(rawx.len(), 399);
    bytes[rawx[200] + 6 + 40] ^= 0x10;
    let damaged = scratch.path().join("damaged.ubx");
    std::fs::write(&damaged, &bytes).unwrap();
    let pieces = pieces(&bytes);
    assert!(pieces.len() > 100);

    let (tx, rx) = mpsc::channel();
    for piece in &pieces {
        tx.send(SourceEvent::Bytes { source: 0, bytes: piece.to_vec() }).unwrap();
    }
    tx.send(SourceEvent::Ended { source: 0, why: None }).unwrap();
    drop(tx);
    let options = UbxOptions::default();
    let sources = vec![Source { name: "module".into(), format: None }];
    let out = scratch.path().join("live");
    let config = RuntimeConfig {
        inputs: Inputs::UbxEvents { sources, events: rx, options },
        out_dir: out.clone(),
        settings: PipelineSettings::default(),
        target_sigma_hz_per_mps2: 1e-4,
        batch_every_s: 5.0,
        idle_timeout_s: 0.0,
    };
    let mut runtime = Runtime::start(config, Arc::new(ManualClock::new())).unwrap();
    assert!(runtime.opening().contains("the receiver's loop is identified from the module's carrier phase"));
    let mut lines = Vec::new();
    let ending = runtime.run(Display::Plain(&mut lines)).unwrap();
    let text = String::from_utf8(lines).unwrap();
    assert_eq!(ending, Ending::InputEnded, "{text}");
    let batches: Vec<&str> = text.lines().filter(|l| l.contains("Γ̂ [Hz/(m/s²)]")).collect();
    // 40 s of data, the first estimate at 15 s, then every 5 s.
    assert!(batches.len() >= 4, "{text}");
    assert!(batches.iter().all(|l| l.contains("| 7 tracks, ") && l.contains("| loop: order 2, Bn ")), "{text}");
    assert!(batches.last().unwrap().contains(", 1 bad checksums, 1 skipped"), "{text}");
    assert_eq!(text.matches("notice: module: a UBX frame with a bad checksum was dropped").count(), 1, "{text}");
    // The shaking guidance comes from the module's own accelerometer.
    assert!(text.lines().any(|l| l.starts_with('[') && l.contains("] shake x")), "{text}");

    let view = runtime.session().view();
    let ubx = view.ubx.clone().unwrap();
    assert_eq!((ubx.bytes, ubx.checksum_failures, ubx.epochs), (bytes.len() as u64, 1, 398));
    assert!(ubx.identified_loop.is_some());
    // Every ESF-RAW sample, on the times the reader gives the whole log.
    let read = gsens_ublox::read_ubx_file(&damaged, &Default::default()).unwrap();
    assert_eq!(view.received.0, read.imu.len() as u64);

    let finished = runtime.finish().unwrap();
    assert_eq!(std::fs::read(out.join("received.ubx")).unwrap(), bytes);
    let kept = gsens_io::read_imu_file(out.join("imu.csv")).unwrap();
    assert_eq!(kept.len(), read.imu.len());
    let gsens_inputs::Estimated::Observations(live) = &finished.estimate else { panic!("an estimate of the UBX log") };
    let whole =
        ObservationInputs::new(ObservationFile::Ubx(damaged, Default::default()), None, ObservationRecord::Auto)
            .calibrate(&PipelineSettings::default())
            .unwrap();
    let (a, b) = (&live.calibration, &whole.calibration);
    assert_eq!(a.gamma_hz_per_mps2, b.gamma_hz_per_mps2);
    assert_eq!(a.sigma_hz_per_mps2, b.sigma_hz_per_mps2);
    assert_eq!(live.identified.identified.bn_hz, whole.identified.identified.bn_hz);
    assert_eq!(live.skipped, whole.skipped);
    assert!(a.gamma_hz_per_mps2[0].is_some(), "x is shaken: {:?}", a.gamma_hz_per_mps2);
}
