//! `gsens replay`: a recorded session streamed as `gsens live` receives one,
//! at real time or faster, to standard output (the merged stream) or as
//! growing `imu.csv` and `tracking.csv` files.

use anyhow::Result;
use clap::Args;
use gsens_live::{ReplaySink, SystemClock, check_speed, read_session_dir, replay};
use std::path::PathBuf;

#[derive(Args, Debug)]
pub(crate) struct ReplayArgs {
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

pub(crate) fn run(args: &ReplayArgs) -> Result<()> {
    check_speed(args.speed).map_err(|e| crate::args::flagged("", Some("speed"), e))?;
    crate::check_dir("--out", args.out.as_deref())?;
    let inputs = read_session_dir(&args.dir).map_err(anyhow::Error::msg)?;
    let mut sink = match &args.out {
        Some(dir) => ReplaySink::files_in(dir)?,
        None => ReplaySink::Merged(Box::new(std::io::stdout().lock())),
    };
    Ok(replay(&inputs, args.speed, &SystemClock::new(), &mut sink)?)
}
