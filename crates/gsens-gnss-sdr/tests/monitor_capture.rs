//! The monitor reader against GNSS-SDR 0.0.17's real output: a capture of its
//! tracking monitor (`TrackingMonitor.enable_monitor=true`, decimation 1) for
//! a 2-satellite `gsens simulate --iq` file, the first 2 500 datagrams as
//! received (length-prefixed), and the tracking dumps of the same run cut to
//! the same span (`scripts/make-gnss-sdr-monitor-fixture.sh`).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use gsens_gnss_sdr::monitor::{MonitorEvent, MonitorRow, MonitorStream, decode_datagram, split_capture};
use gsens_gnss_sdr::{TrackingRecord, read_dump};

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/monitor")
}

fn capture() -> Vec<u8> {
    std::fs::read(fixtures().join("monitor.bin")).unwrap()
}

fn rows_of(stream: &mut MonitorStream, datagrams: &[&[u8]]) -> Vec<MonitorRow> {
    let mut rows = Vec::new();
    for d in datagrams {
        for e in stream.push(d) {
            match e {
                MonitorEvent::Row(r) => rows.push(r),
                MonitorEvent::Late(r) => panic!("unexpected late row on a clean capture: {r:?}"),
                MonitorEvent::Notice(n) => panic!("unexpected notice on a clean capture: {n}"),
            }
        }
    }
    rows
}

#[test]
fn every_datagram_of_the_capture_decodes() {
    let bytes = capture();
    let datagrams = split_capture(&bytes).unwrap();
    assert_eq!(datagrams.len(), 2500);
    for d in &datagrams {
        let m = decode_datagram(d).unwrap();
        assert_eq!(m.len(), 1, "0.0.17's monitor sends one GnssSynchro per datagram");
        assert_eq!((m[0].system.as_str(), m[0].signal.as_str(), m[0].fs), ("G", "1C", 2_048_000));
    }
}

#[test]
fn repeats_dropped_rows_every_20_ms() {
    let bytes = capture();
    let datagrams = split_capture(&bytes).unwrap();
    let mut s = MonitorStream::new(None, 1);
    let rows = rows_of(&mut s, &datagrams);
    // GNSS-SDR 0.0.17 re-sends old outputs: most of the capture is repeats.
    assert!(s.counts.repeated > 1000, "{}", s.counts.summary());
    assert_eq!(s.counts.rows as usize, rows.len());
    assert_eq!(s.counts.garbage, 0);
    assert_eq!((s.counts.gaps, s.counts.restarts), (0, 0));
    let mut by_channel: BTreeMap<u32, Vec<&MonitorRow>> = BTreeMap::new();
    for r in &rows {
        by_channel.entry(r.row.channel).or_default().push(r);
    }
    assert_eq!(by_channel.len(), 2);
    for (ch, rs) in &by_channel {
        assert!(rs.len() > 400, "channel {ch}: {} rows", rs.len());
        assert!(rs.iter().all(|r| r.row.prn == rs[0].row.prn));
        for w in rs.windows(2) {
            let dt = w[1].row.t_s - w[0].row.t_s;
            assert!((dt - 0.02).abs() < 2.0 / 2_048_000.0, "channel {ch}: step {dt}");
        }
    }
}

/// The dump record of the same integration: the same sample counter.
fn record_for(recs: &[TrackingRecord], counter: u64) -> Option<usize> {
    recs.binary_search_by_key(&counter, |r| r.prn_start_sample_count).ok()
}

#[test]
fn rows_agree_with_the_dump_of_the_same_run() {
    let bytes = capture();
    let datagrams = split_capture(&bytes).unwrap();
    let rows = rows_of(&mut MonitorStream::new(None, 1), &datagrams);
    let fs = 2_048_000.0;
    let mut compared = 0;
    for ch in 0..2u32 {
        let dump = read_dump(fixtures().join(format!("trk_ch_{ch}.dat")), None).unwrap();
        let recs = &dump.records;
        let mine: Vec<_> = rows.iter().filter(|r| r.row.channel == ch).collect();
        let (mut worst_phase, mut worst_t) = (0.0f64, 0.0f64);
        for r in &mine {
            let k = record_for(recs, r.sample_counter)
                .unwrap_or_else(|| panic!("channel {ch}: no dump record for counter {}", r.sample_counter));
            assert!(k > 0);
            let rec = &recs[k];
            assert_eq!(rec.prn, r.row.prn);
            // The dump reader's time: the middle of the integration ending at the record.
            let dn = (rec.prn_start_sample_count - recs[k - 1].prn_start_sample_count) as f64;
            assert!((dn - 0.02 * fs).abs() < 3.0, "a 20 ms integration, {dn} samples");
            let t_dump = (rec.prn_start_sample_count as f64 - 0.5 * dn) / fs;
            let phase_dump = core::f64::consts::TAU * rec.carr_error_cycles;
            worst_phase = worst_phase.max((r.row.phase_err_rad - phase_dump).abs());
            worst_t = worst_t.max((r.row.t_s - t_dump).abs());
            assert_eq!(r.row.cn0_dbhz as f32, rec.cn0_dbhz as f32);
            compared += 1;
        }
        eprintln!("channel {ch}: {} rows, worst |Δφ| {worst_phase:.2e} rad, |Δt| {worst_t:.2e} s", mine.len());
        // φ: the dump holds atan(Q/I)/2π as f32; t: Δn is the counter step there, 20 ms·fs here.
        assert!(worst_phase < 2e-6, "channel {ch}: φ differs by {worst_phase} rad");
        assert!(worst_t <= 0.5 / fs + 1e-12, "channel {ch}: t differs by {worst_t} s");
        // Every 20 ms record of the dump within the monitor's span has its row.
        let (t0, t1) = (mine[0].sample_counter, mine.last().unwrap().sample_counter);
        let in_span = (1..recs.len())
            .filter(|&k| recs[k].prn_start_sample_count - recs[k - 1].prn_start_sample_count > 30_000)
            .filter(|&k| (t0..=t1).contains(&recs[k].prn_start_sample_count))
            .count();
        assert_eq!(in_span, mine.len(), "channel {ch}");
    }
    assert!(compared > 900);
}

#[test]
fn a_corrupted_capture_gives_notices_not_panics() {
    let bytes = capture();
    let datagrams = split_capture(&bytes).unwrap();
    let mut s = MonitorStream::new(None, 1);
    let mut notices = 0;
    for (i, d) in datagrams.iter().enumerate().take(600) {
        // Every third datagram cut, every fifth bit-flipped, every seventh skipped.
        let mut d = d.to_vec();
        if i % 7 == 3 {
            continue;
        }
        if i % 3 == 1 {
            d.truncate(d.len() / 2);
        }
        if i % 5 == 2 {
            let j = d.len() / 3;
            d[j] ^= 0x5a;
        }
        notices += s.push(&d).iter().filter(|e| matches!(e, MonitorEvent::Notice(_))).count();
    }
    assert!(s.counts.garbage > 100, "{}", s.counts.summary());
    assert!(notices as u64 >= s.counts.garbage);
}
