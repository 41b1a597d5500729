//! `gsens predict`: what compensation buys under vibration. From Γ̂ and its
//! covariance, a vibration environment, the oscillator and the loop: the
//! carrier phase jitter without and with −aᵀΓ̂ in the NCO, the lock margin by
//! the 3σ rule, and the narrowest loop that keeps lock in each case
//! (`gsens_calib::predict`).

use anyhow::{Result, bail};
use clap::Args;
use gsens_calib::option_values::positive;
use gsens_calib::predict::{
    EstimateSource, PredictRequest, ReceiverConditions, SweepContext, VibrationSource, render_sweep_text,
};
use gsens_montecarlo::frequency_noise;
use gsens_report::figures::Format;
use gsens_report::studies::fig_lock_margin_at;
use gsens_sim::oscillator::NoisePreset;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub(crate) struct PredictArgs {
    /// Γ̂ and its covariance from a result document (`gsens estimate --json`, `report.json`).
    #[arg(long, required_unless_present = "gamma", conflicts_with_all = ["gamma", "sigma"])]
    pub from: Option<PathBuf>,
    /// Γ̂ [Hz/(m/s²)] as gx,gy,gz (with --sigma).
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true, requires = "sigma")]
    pub gamma: Option<Vec<f64>>,
    /// 1σ of Γ̂ [Hz/(m/s²)] as sx,sy,sz (axes uncorrelated).
    #[arg(long, value_delimiter = ',')]
    pub sigma: Option<Vec<f64>>,
    /// Random vibration: vibration.csv (f_hz,psd_x,psd_y,psd_z in (m/s²)²/Hz).
    #[arg(long, required_unless_present = "tone")]
    pub psd: Option<PathBuf>,
    /// Sine vibration: a tone as F_HZ:AX,AY,AZ (peak m/s² per axis, in phase); repeatable.
    #[arg(long, conflicts_with = "psd")]
    pub tone: Vec<String>,
    /// Vibration levels to predict at, as factors on the amplitudes (PSD × level²).
    #[arg(long, value_delimiter = ',', default_value = "1")]
    pub levels: Vec<f64>,
    /// The oscillator's noise.
    #[arg(long, value_enum, default_value = "ocxo")]
    pub oscillator: NoisePreset,
    /// Carrier [Hz] (GPS L1 by default).
    #[arg(long, default_value_t = gsens_core::units::GPS_L1_HZ, allow_negative_numbers = true, value_parser = positive)]
    pub carrier_hz: f64,
    #[command(flatten)]
    pub receiver: ReceiverConditions,
    /// Write the predictions as JSON here.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Draw the lock margin (3σ + θe without and with compensation) over the loop bandwidth
    /// at the last level here (.png or .svg).
    #[arg(long)]
    pub figure: Option<PathBuf>,
}

pub(crate) fn run(args: &PredictArgs) -> Result<crate::Status> {
    crate::check_files(&[("--json", args.json.as_deref()), ("--figure", args.figure.as_deref())], None)?;
    let estimate = match (&args.from, &args.gamma, &args.sigma) {
        (Some(path), _, _) => EstimateSource::Document(path.clone()),
        (None, Some(gamma), Some(sigma)) => EstimateSource::Stated { gamma: gamma.clone(), sigma: sigma.clone() },
        _ => bail!("give --from report.json, or --gamma with --sigma"),
    };
    let request = PredictRequest {
        estimate,
        vibration: args
            .psd
            .clone()
            .map_or_else(|| VibrationSource::Tones(args.tone.clone()), VibrationSource::Spectrum),
        levels: args.levels.clone(),
        oscillator: args.oscillator.config().map(|o| frequency_noise(&o, args.carrier_hz)),
        receiver: args.receiver.clone(),
    };
    let (settings, sweep) = request.sweep().map_err(|e| crate::args::flagged("", e.setting(), e))?;
    let oscillator = args.oscillator.to_string();
    let context = SweepContext { oscillator: &oscillator, feed_forward: args.receiver.feed_forward };
    crate::out(&render_sweep_text(&settings, &sweep, &context))?;
    if let (Some(path), Some(&level)) = (&args.figure, args.levels.last()) {
        let format = Format::of_path(path).unwrap_or(Format::Png);
        gsens_io::write_file(path, fig_lock_margin_at(&settings, &context, level, format)?.as_bytes())?;
    }
    crate::write_json(args.json.as_deref(), &sweep, "")?;
    Ok(crate::Status::Done)
}
