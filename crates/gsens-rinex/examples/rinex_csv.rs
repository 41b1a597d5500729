//! Reads a RINEX observation file with gsens's reader and writes what it read:
//! a summary on standard error (format, GPS week, epochs, skipped records,
//! clock jumps, one line per signal) and every observation as CSV on standard
//! output (`sv,code,t_s,pseudorange_m,carrier_phase_cycles,doppler_hz,cn0_dbhz,flags`;
//! `t_s` in seconds of the first epoch's GPS week, NaN where absent).
//!
//! ```sh
//! cargo run -p gsens-rinex --example rinex_csv -- obs.26O > obs.csv
//! ```

use std::io::Write;

fn main() -> std::process::ExitCode {
    let Some(path) = std::env::args().nth(1) else {
        eprintln!("usage: rinex_csv FILE   (a RINEX observation file; CSV on standard output)");
        return std::process::ExitCode::from(2);
    };
    let log = match gsens_rinex::read_rinex_file(&path) {
        Ok(log) => log,
        Err(e) => {
            eprintln!("error: {e}");
            return std::process::ExitCode::FAILURE;
        }
    };
    eprintln!(
        "{}: {}, GPS week {}, {} epochs, {} records skipped, {} clock jumps",
        log.source_name,
        log.format,
        log.gps_week,
        log.epochs,
        log.skipped_count(),
        log.clock_events.len()
    );
    for s in &log.skipped {
        eprintln!("  skipped {} × {} (first at {})", s.count, s.reason, s.first_at.as_deref().unwrap_or("?"));
    }
    for track in &log.tracks {
        let valid = |v: &[f64]| v.iter().filter(|x| x.is_finite()).count();
        eprintln!(
            "  {}: {} epochs, t {:.3} … {:.3} s, phase {}, Doppler {}, pseudorange {}",
            track.label(),
            track.len(),
            track.t_s.first().copied().unwrap_or(f64::NAN),
            track.t_s.last().copied().unwrap_or(f64::NAN),
            valid(&track.carrier_phase_cycles),
            valid(&track.doppler_hz),
            valid(&track.pseudorange_m)
        );
    }
    let mut out = std::io::BufWriter::new(std::io::stdout().lock());
    let mut write = || -> std::io::Result<()> {
        writeln!(out, "sv,code,t_s,pseudorange_m,carrier_phase_cycles,doppler_hz,cn0_dbhz,flags")?;
        for t in &log.tracks {
            for i in 0..t.len() {
                writeln!(
                    out,
                    "{},{},{},{},{},{},{},{}",
                    t.sv,
                    t.code,
                    t.t_s[i],
                    t.pseudorange_m[i],
                    t.carrier_phase_cycles[i],
                    t.doppler_hz[i],
                    t.cn0_dbhz[i],
                    t.flags[i]
                )?;
            }
        }
        out.flush()
    };
    match write() {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: writing the CSV: {e}");
            std::process::ExitCode::FAILURE
        }
    }
}
