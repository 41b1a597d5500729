//! `gsens replay`: a recorded session streamed as `gsens live` receives one,
//! at real time or faster, to standard output (the merged stream) or as
//! growing `imu.csv` and `tracking.csv` files.

use anyhow::{Context, Result};
use clap::Args;
use gsens_live::{Input, merged_line, read_session_dir};
use std::io::{LineWriter, Write};
use std::path::PathBuf;
use std::time::{Duration, Instant};

#[derive(Args, Debug)]
pub struct ReplayArgs {
    /// Directory with imu.csv and tracking.csv (e.g. from `gsens simulate`).
    pub dir: PathBuf,
    /// Speed relative to real time (2: twice as fast; 0: as fast as possible).
    #[arg(long, default_value_t = 1.0)]
    pub speed: f64,
    /// Append to growing OUT/imu.csv and OUT/tracking.csv (for `gsens live --follow-imu
    /// --follow-tracking`) instead of writing the merged stream to standard output.
    #[arg(long)]
    pub out: Option<PathBuf>,
}

pub fn run(args: &ReplayArgs) -> Result<()> {
    if !(args.speed.is_finite() && args.speed >= 0.0) {
        anyhow::bail!("--speed {}: must be 0 (as fast as possible) or positive", args.speed);
    }
    if let Some(d) = &args.out {
        crate::outputs::dir("--out", d)?;
    }
    let inputs = read_session_dir(&args.dir).map_err(anyhow::Error::msg)?;
    let Some(first) = inputs.first() else { anyhow::bail!("{}: no records to replay", args.dir.display()) };
    let t0 = first.t_s();
    let start = Instant::now();
    let mut files = match &args.out {
        Some(dir) => {
            std::fs::create_dir_all(dir).with_context(|| format!("{}: cannot create", dir.display()))?;
            let open = |name: &str, header: String| -> Result<LineWriter<std::fs::File>> {
                let path = dir.join(name);
                let f = std::fs::File::create(&path).with_context(|| format!("{}: cannot create", path.display()))?;
                let mut w = LineWriter::new(f);
                writeln!(w, "{header}")?;
                Ok(w)
            };
            Some((
                open("imu.csv", gsens_io::IMU_COLUMNS.join(","))?,
                open("tracking.csv", gsens_io::TRACKING_COLUMNS.join(","))?,
            ))
        }
        None => None,
    };
    let stdout = std::io::stdout();
    let mut out = stdout.lock();
    for x in &inputs {
        if args.speed > 0.0 {
            let due = Duration::from_secs_f64((x.t_s() - t0).max(0.0) / args.speed);
            if let Some(wait) = due.checked_sub(start.elapsed()) {
                out.flush()?;
                std::thread::sleep(wait);
            }
        }
        let line = merged_line(x);
        let r = match &mut files {
            // The files' own format: the merged line without its tag.
            Some((imu, trk)) => {
                let w = if matches!(x, Input::Imu { .. }) { imu } else { trk };
                writeln!(w, "{}", &line[4..])
            }
            None => writeln!(out, "{line}"),
        };
        match r {
            Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => return Ok(()),
            r => r?,
        }
    }
    out.flush().or_else(|e| if e.kind() == std::io::ErrorKind::BrokenPipe { Ok(()) } else { Err(e) })?;
    Ok(())
}
