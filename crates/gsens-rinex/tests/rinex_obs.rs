//! The reader against the fixture script's file (tests/fixtures/README.md) and small files
//! written here from the RINEX 3.04 and 2.11 definitions.

use gsens_io::obs_flags;
use gsens_rinex::{RinexError, read_rinex_bytes, read_rinex_file};

const FIXTURE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fixtures/sim.rnx");

fn fixture_text() -> String {
    std::fs::read_to_string(FIXTURE).unwrap()
}

#[test]
fn every_value_the_script_wrote_reads_back() {
    let log = read_rinex_file(FIXTURE).unwrap();
    assert!(log.validate().is_ok());
    assert_eq!((log.format.as_str(), log.gps_week), ("RINEX 3.04", 2300));
    assert!(log.skipped.is_empty() && log.clock_events.is_empty(), "{:?}", log.skipped);
    let text =
        std::fs::read_to_string(format!("{}/tests/fixtures/expected_obs.csv", env!("CARGO_MANIFEST_DIR"))).unwrap();
    let rows: Vec<Vec<&str>> = text.lines().skip(1).map(|l| l.split(',').collect()).collect();
    let mut epochs: Vec<&str> = rows.iter().map(|r| r[1]).collect();
    epochs.dedup();
    assert_eq!(log.epochs, epochs.len());
    let mut seen = 0;
    for track in &log.tracks {
        assert_eq!((track.code.as_str(), track.carrier.label()), ("1C", "L1CA".to_owned()));
        assert!(track.lock_time_s.is_empty());
        let mine: Vec<_> = rows.iter().filter(|r| r[2] == track.sv).collect();
        assert_eq!(track.len(), mine.len(), "{}", track.sv);
        for (i, r) in mine.iter().enumerate() {
            let num = |j: usize| r[j].parse::<f64>().unwrap();
            assert!((track.t_s[i] - num(1)).abs() < 1e-9);
            // F14.3: the value rounded to the thousandth.
            for (got, want) in [
                (track.pseudorange_m[i], num(3)),
                (track.carrier_phase_cycles[i], num(4)),
                (track.doppler_hz[i], num(5)),
                (track.cn0_dbhz[i], num(6)),
            ] {
                assert!((got - want).abs() <= 0.000_5 + 1e-7, "{} row {i}: {got} vs {want}", track.sv);
            }
            let lli = r[7] == "1";
            assert_eq!(track.flags[i], if lli { obs_flags::LOSS_OF_LOCK } else { 0 }, "{} row {i}", track.sv);
            assert_eq!(track.strength[i].to_string(), r[8]);
            seen += 1;
        }
    }
    assert_eq!(seen, rows.len());
    // RINEX's sign: the phase runs against the Doppler (dL/dt = −D).
    let t = &log.tracks[0];
    let (i, j) = (10, 11);
    let rate = (t.carrier_phase_cycles[j] - t.carrier_phase_cycles[i]) / (t.t_s[j] - t.t_s[i]);
    assert!((rate + t.doppler_hz[i]).abs() < 5.0, "{rate} vs {}", t.doppler_hz[i]);
}

/// The 1-based line of the `n`-th epoch line (`>`) of `text`.
fn epoch_line(text: &str, n: usize) -> usize {
    text.lines().enumerate().filter(|(_, l)| l.starts_with('>')).nth(n).unwrap().0 + 1
}

#[test]
fn events_power_failures_and_bad_epochs_are_counted_with_their_line() {
    let text = fixture_text();
    let mut lines: Vec<String> = text.lines().map(str::to_owned).collect();
    // Epoch 3's first observation gets a non-ASCII byte: the crate drops the epoch.
    let bad = epoch_line(&text, 3);
    lines[bad] = lines[bad].replacen(' ', "é", 1);
    // Epoch 5 becomes a power failure (flag 1).
    let pf = epoch_line(&text, 5);
    lines[pf - 1].replace_range(31..32, "1");
    // An external event (flag 5, no special records) after epoch 7.
    let ev = epoch_line(&text, 8);
    lines.insert(ev - 1, "> 2024 02 08 12 00 18.9500000  5  0".to_owned());
    let edited = lines.join("\n") + "\n";
    let log = read_rinex_bytes(edited.as_bytes(), "edited.rnx").unwrap();
    let good = read_rinex_file(FIXTURE).unwrap();
    assert_eq!(log.epochs, good.epochs - 1);
    assert_eq!(log.skipped_count(), 2, "{:?}", log.skipped);
    let s = |reason: &str| log.skipped.iter().find(|s| s.reason.contains(reason)).unwrap();
    assert_eq!(s("cannot decode").first_at.as_deref(), Some(format!("line {bad}").as_str()));
    assert_eq!(s("event").first_at.as_deref(), Some(format!("line {ev}").as_str()));
    // Every signal of the power-failure epoch has lost lock.
    let t_pf = good.tracks.iter().flat_map(|t| t.t_s.iter()).copied().fold(f64::INFINITY, f64::min) + 0.5;
    let mut flagged = 0;
    for t in &log.tracks {
        if let Some(i) = t.t_s.iter().position(|&x| (x - t_pf).abs() < 1e-6) {
            assert!(t.flags[i] & obs_flags::LOSS_OF_LOCK != 0);
            flagged += 1;
        }
    }
    assert!(flagged > 0);
}

#[test]
fn bad_files_are_errors_naming_the_file() {
    let e = read_rinex_bytes(b"not a rinex file\n", "junk.rnx").unwrap_err();
    assert!(matches!(e, RinexError::Parse { .. }), "{e:?}");
    assert!(e.to_string().starts_with("junk.rnx: "), "{e}");
    // Non-ASCII in the header: the line is named.
    let text = fixture_text().replacen("SIM ", "SÏM", 1);
    let e = read_rinex_bytes(text.as_bytes(), "accent.rnx").unwrap_err().to_string();
    assert!(e.starts_with("accent.rnx: line 4: "), "{e}");
    // A header without a single epoch.
    let header: String = fixture_text().lines().take_while(|l| !l.starts_with('>')).map(|l| format!("{l}\n")).collect();
    let e = read_rinex_bytes(header.as_bytes(), "header.rnx").unwrap_err();
    assert!(matches!(e, RinexError::NoData { .. }), "{e:?}");
    let e = read_rinex_file("/nonexistent/x.rnx").unwrap_err().to_string();
    assert!(e.starts_with("/nonexistent/x.rnx: cannot read"), "{e}");
}

fn header_line(content: &str, label: &str) -> String {
    format!("{content:<60}{label:<20}\n")
}

/// The header lines that name the station, the same in every file written here.
fn station_lines() -> String {
    let mut s = String::new();
    s += &header_line("test", "MARKER NAME");
    s += &header_line(&format!("{:<20}{:<40}", "t", "t"), "OBSERVER / AGENCY");
    s += &header_line(&format!("{:<20}{:<20}{:<20}", "1", "R", "1"), "REC # / TYPE / VERS");
    s += &header_line(&format!("{:<20}{:<20}", "1", "A"), "ANT # / TYPE");
    s += &header_line(&format!("{:14.4}{:14.4}{:14.4}", 1.0, 2.0, 3.0), "APPROX POSITION XYZ");
    s += &header_line(&format!("{:14.4}{:14.4}{:14.4}", 0.0, 0.0, 0.0), "ANTENNA: DELTA H/E/N");
    s
}

/// A mixed GPS + GLONASS RINEX 3.04 file written here column by column: R12 at k = −4 in the
/// header, R07 not listed; receiver clock offsets with a 1 ms jump at the second epoch.
fn mixed_file() -> String {
    let mut s = String::new();
    s += &header_line(
        &format!("{:>9}{:11}{:<20}{:<20}", "3.04", "", "OBSERVATION DATA", "M: MIXED"),
        "RINEX VERSION / TYPE",
    );
    s += &station_lines();
    s += &header_line("G    2 L1C D1C", "SYS / # / OBS TYPES");
    s += &header_line("R    3 C1C L1C D1C", "SYS / # / OBS TYPES");
    s += &header_line(&format!("{:6}{:6}{:6}{:6}{:6}{:13.7}     GPS", 2024, 2, 8, 12, 0, 18.0), "TIME OF FIRST OBS");
    s += &header_line("  1 R12 -4", "GLONASS SLOT / FRQ #");
    s += &header_line("", "END OF HEADER");
    for (sec, clock) in [(18.0, 0.000_010_000_000), (19.0, 0.001_010_500_000)] {
        s += &format!("> 2024 02 08 12 00{sec:11.7}  0  3      {clock:15.12}\n");
        s += &format!("G05{:14.3}1 {:14.3}  \n", 1.25e8 + sec, -1234.5);
        s += &format!("R12{:14.3}  {:14.3}  {:14.3}  \n", 2.1e7, 1.1e8 - sec, 500.25);
        s += &format!("R07{:14.3}  {:14.3}  {:14.3}  \n", 2.2e7, 1.2e8, 600.0);
    }
    s
}

#[test]
fn glonass_channels_other_systems_and_clock_jumps() {
    let log = read_rinex_bytes(mixed_file().as_bytes(), "mixed.rnx").unwrap();
    assert_eq!(log.epochs, 2);
    let g = log.track("G05", "1C").unwrap();
    assert_eq!(g.carrier.label(), "L1CA");
    assert_eq!(g.carrier_phase_cycles, [1.25e8 + 18.0, 1.25e8 + 19.0]);
    assert_eq!(g.doppler_hz, [-1234.5, -1234.5]);
    assert_eq!(g.flags[0], obs_flags::LOSS_OF_LOCK | obs_flags::PSEUDORANGE_INVALID);
    assert!(g.pseudorange_m[0].is_nan() && g.cn0_dbhz[0].is_nan());
    let r = log.track("R12", "1C").unwrap();
    assert_eq!(r.carrier.label(), "G1:-4");
    assert_eq!((r.pseudorange_m[1], r.carrier_phase_cycles[1], r.doppler_hz[1]), (2.1e7, 1.1e8 - 19.0, 500.25));
    assert!(log.track("R07", "1C").is_none());
    let skip = &log.skipped[0];
    assert_eq!(skip.count, 2);
    assert!(skip.reason.contains("GLONASS SLOT / FRQ #"), "{}", skip.reason);
    assert_eq!(log.clock_events.len(), 1);
    let jump = log.clock_events[0].jump_s.unwrap();
    assert!((jump - 0.001_000_5).abs() < 1e-12, "{jump}");
    assert_eq!(log.clock_events[0].t_s, 388_819.0);
}

/// A GPS RINEX 2.11 file written here: types of observation L1 C1 P1 D1 S1.
fn v2_file() -> String {
    let mut s = String::new();
    s += &header_line(
        &format!("{:>9}{:11}{:<20}{:<20}", "2.11", "", "OBSERVATION DATA", "G (GPS)"),
        "RINEX VERSION / TYPE",
    );
    s += &station_lines();
    s += &header_line(&format!("{:6}{:6}", 1, 1), "WAVELENGTH FACT L1/2");
    s += &header_line("     5    L1    C1    P1    D1    S1", "# / TYPES OF OBSERV");
    s += &header_line(&format!("{:6}{:6}{:6}{:6}{:6}{:13.7}     GPS", 2024, 2, 8, 12, 0, 18.0), "TIME OF FIRST OBS");
    s += &header_line("", "END OF HEADER");
    for sec in [18.0, 19.0] {
        s += &format!(" 24  2  8 12  0{sec:11.7}  0  1G05\n");
        s += &format!("{:14.3}17{:14.3}  {:14.3}  {:14.3}  {:14.3}  \n", 1.1e8 + sec, 2.1e7, 2.1e7 + 1.0, 900.5, 45.25);
    }
    s
}

#[test]
fn rinex_2_reads_with_band_codes() {
    let log = read_rinex_bytes(v2_file().as_bytes(), "v2.obs").unwrap();
    assert_eq!((log.format.as_str(), log.epochs), ("RINEX 2.11", 2));
    let g = log.track("G05", "1").unwrap();
    assert_eq!(g.carrier.carrier_hz, 1_575.42e6);
    assert_eq!(g.t_s, [388_818.0, 388_819.0]);
    assert_eq!(g.carrier_phase_cycles, [1.1e8 + 18.0, 1.1e8 + 19.0]);
    assert_eq!((g.pseudorange_m[0], g.doppler_hz[0], g.cn0_dbhz[0]), (2.1e7, 900.5, 45.25));
    assert_eq!((g.flags[0], g.strength[0]), (obs_flags::LOSS_OF_LOCK, 7));
    assert_eq!(log.skipped_count(), 2, "{:?}", log.skipped);
}

#[test]
fn hatanaka_compressed_files_read_as_the_plain_file() {
    // The rinex crate's own compressor makes the CRINEX file of the fixture.
    let plain = rinex::prelude::Rinex::from_file(FIXTURE).unwrap();
    let mut crinex = Vec::new();
    plain.rnx2crnx().format(&mut std::io::BufWriter::new(&mut crinex)).unwrap();
    let text = String::from_utf8(crinex.clone()).unwrap();
    assert!(text.contains("COMPACT RINEX FORMAT"), "{}", &text[..200]);
    let a = read_rinex_file(FIXTURE).unwrap();
    let b = read_rinex_bytes(&crinex, "sim.crx").unwrap();
    assert_eq!(a.tracks, b.tracks);
}

#[test]
fn an_input_the_rinex_crate_panics_on_is_refused() {
    // A GLONASS SLOT / FRQ # record cut after its count (found by the fuzz target): the crate
    // slices it unchecked.
    let text = fixture_text().replacen(
        &header_line("", "END OF HEADER"),
        &(header_line("  1 R1", "GLONASS SLOT / FRQ #") + &header_line("", "END OF HEADER")),
        1,
    );
    let e = read_rinex_bytes(text.as_bytes(), "cut.rnx").unwrap_err().to_string();
    assert_eq!(e, "cut.rnx: not a readable RINEX observation file: the rinex crate failed on a malformed line");
}
