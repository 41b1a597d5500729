//! `gsens response`: the loop's response from NCO frequency bias to phase
//! error, |L(j2πf)| and its phase, with the peak and the shaking period to use.

use anyhow::{Context, Result};
use clap::Args;
use gsens_report::figures::Format;
use gsens_report::figures::{DEFAULT_SIZE, ResponseData, fig_response};
use gsens_report::studies::response_json;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub(crate) struct ResponseArgs {
    #[command(flatten)]
    pub receiver_loop: gsens_calib::LoopOptions,
    /// Lowest frequency of the table [Hz].
    #[arg(long, default_value_t = 0.05)]
    pub f_min_hz: f64,
    /// Highest frequency of the table [Hz].
    #[arg(long, default_value_t = 20.0)]
    pub f_max_hz: f64,
    /// Rows of the table (log-spaced).
    #[arg(long, default_value_t = 25)]
    pub points: usize,
    /// Write the response as JSON here.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Draw the response (the paper's Fig. 3) here: FILE.png or FILE.svg.
    #[arg(long)]
    pub plot: Option<PathBuf>,
}

pub(crate) fn run(args: &ResponseArgs, given: &[&str]) -> Result<()> {
    ResponseData::check_range(args.f_min_hz, args.f_max_hz, args.points, crate::args::flag)?;
    args.receiver_loop.refuse_other_shape(given, crate::args::flag)?;
    crate::check_files(&[("--json", args.json.as_deref()), ("--plot", args.plot.as_deref())], None)?;
    let model = args.receiver_loop.loop_model();
    let table = ResponseData::from_loop(&model, args.f_min_hz, args.f_max_hz, args.points, model.to_string())
        .with_context(|| format!("the loop ({model})"))?;
    crate::out(&gsens_report::render_response_text(&table))?;
    if let Some(path) = &args.json {
        gsens_io::write_file(path, response_json(&model, &table)?)?;
    }
    if let Some(path) = &args.plot {
        let Some(format) = Format::of_path(path) else {
            anyhow::bail!("{}: the figure's name must end in .png or .svg", path.display())
        };
        let plot = ResponseData::from_loop(&model, args.f_min_hz, args.f_max_hz, 300, model.to_string())?;
        gsens_io::write_file(path, fig_response(&plot, format, DEFAULT_SIZE)?.as_bytes())?;
        crate::out(&format!("figure: {}\n", path.display()))?;
    }
    Ok(())
}
