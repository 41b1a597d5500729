//! `gsens estimate`: Γ̂ from receiver logs.

use crate::args::{AnalysisArgs, GnssSdrArgs, LoopArgs, PocketSdrArgs};
use anyhow::{Context, Result};
use clap::Args;
use gsens_calib::{Outcome, PipelineSettings, calibrate_files, calibrate_gnss_sdr};
use std::path::{Path, PathBuf};

#[derive(Args, Debug)]
pub struct EstimateArgs {
    /// IMU log: t_s,fx_mps2,fy_mps2,fz_mps2.
    #[arg(long)]
    pub imu: PathBuf,
    /// Tracking log: t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad (or --gnss-sdr, --pocketsdr).
    #[arg(long, required_unless_present_any = ["gnss_sdr", "pocketsdr"], conflicts_with_all = ["gnss_sdr", "pocketsdr"])]
    pub tracking: Option<PathBuf>,
    /// Write the result document (JSON) here.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Write the estimator's input here as CSV: per epoch t_s, the channel-averaged
    /// phase_err_rad and the specific force interpolated onto the epoch (what a receiver
    /// feeds the C API's calibrator; examples/c/calibrate.c reads it).
    #[arg(long)]
    pub epochs_out: Option<PathBuf>,
    #[command(flatten)]
    pub calibration: CalibrationArgs,
    #[command(flatten)]
    pub gnss_sdr: GnssSdrArgs,
    #[command(flatten)]
    pub pocketsdr: PocketSdrArgs,
}

/// The options that decide a calibration from logs (`estimate` and `report`).
#[derive(Args, Debug, Clone)]
pub struct CalibrationArgs {
    /// Carrier frequency [Hz] for ppb/g (default GPS L1).
    #[arg(long, default_value_t = gsens_core::units::GPS_L1_HZ)]
    pub carrier_hz: f64,
    #[command(flatten)]
    pub loop_args: LoopArgs,
    #[command(flatten)]
    pub analysis: AnalysisArgs,
}

impl CalibrationArgs {
    /// The options by name.
    pub fn options(&self) -> gsens_calib::CalibrationOptions {
        let mut o = self.analysis.options();
        self.loop_args.apply(&mut o);
        o.carrier_hz = self.carrier_hz;
        o
    }

    /// The pipeline settings (every value checked).
    pub fn settings(&self) -> Result<PipelineSettings> {
        Ok(self.options().pipeline_settings()?)
    }
}

/// Runs the calibration the options describe: from tracking.csv, or from
/// GNSS-SDR dumps (printing what became of each track).
pub fn calibrate(
    imu: &Path,
    tracking: Option<&Path>,
    gnss_sdr: Option<&GnssSdrArgs>,
    settings: &PipelineSettings,
) -> Result<Outcome> {
    match (gnss_sdr.and_then(|g| g.gnss_sdr.as_ref().map(|d| (g, d))), tracking) {
        (Some((gnss_sdr, dir)), _) => {
            let conf = gnss_sdr.gnss_sdr_conf.as_deref();
            let import = gnss_sdr.conversion.import_settings(conf)?;
            let mut outcome = crate::observed(|| calibrate_gnss_sdr(dir, &import, imu, settings))?;
            if let Some(g) = &outcome.gnss_sdr {
                crate::out(&gsens_report::render_gnss_sdr_tracks(&g.tracks, outcome.session.log_interval_s))?;
            }
            crate::out(&format!("GNSS-SDR loop: {}, modelled exactly\n", outcome.calibration.loop_used))?;
            let conf = conf.map(|p| p.display().to_string()).unwrap_or_default();
            outcome.inputs.push(("gnss_sdr_conf".into(), conf));
            Ok(outcome)
        }
        (None, Some(t)) => match gnss_sdr.and_then(|g| g.gnss_sdr_conf.as_deref().map(|c| (g, c))) {
            // Rows from a GNSS-SDR run by another path than its dumps: its loop, from its configuration.
            Some((g, conf)) => {
                if settings.loop_stated {
                    anyhow::bail!("--gnss-sdr-conf states the receiver loop: leave out --order, --bn-hz and the like");
                }
                let settings = gsens_calib::with_gnss_sdr_loop(settings, &g.conversion.import_settings(Some(conf))?);
                let mut outcome = crate::observed(|| calibrate_files(t, imu, &settings))?;
                crate::out(&format!("GNSS-SDR loop: {}, modelled exactly\n", outcome.calibration.loop_used))?;
                outcome.inputs.push(("gnss_sdr_conf".into(), conf.display().to_string()));
                Ok(outcome)
            }
            None => Ok(crate::observed(|| calibrate_files(t, imu, settings))?),
        },
        (None, None) => anyhow::bail!("--tracking is required (or --gnss-sdr)"),
    }
}

/// Calibrates from a PocketSDR log with PocketSDR's loop modelled exactly,
/// printing what became of each track.
fn calibrate_pocketsdr(imu: &Path, log: &Path, args: &PocketSdrArgs, settings: &PipelineSettings) -> Result<Outcome> {
    let import = args.conversion.import_settings()?;
    let r = crate::observed(|| gsens_pocketsdr::calibrate_pocketsdr(log, &import, imu, settings))?;
    crate::out(&gsens_pocketsdr::render_summary(&r.imported))?;
    crate::out(&format!("PocketSDR loop: {}, modelled exactly\n", r.outcome.calibration.loop_used))?;
    Ok(r.outcome)
}

pub fn run(args: &EstimateArgs) -> Result<crate::Status> {
    let settings = args.calibration.settings()?;
    let outcome = match &args.pocketsdr.pocketsdr {
        Some(log) => calibrate_pocketsdr(&args.imu, log, &args.pocketsdr, &settings)?,
        None => {
            if args.pocketsdr.conversion.given() {
                anyhow::bail!("--pocketsdr-conf, --pocketsdr-settle-s and --pocketsdr-toff-s need --pocketsdr LOG");
            }
            calibrate(&args.imu, args.tracking.as_deref(), Some(&args.gnss_sdr), &settings)?
        }
    };
    let doc = outcome.document(None);
    crate::out(&gsens_report::render_text(&doc))?;
    if let Some(path) = &args.json {
        doc.write_json_file(path).with_context(|| format!("{}: cannot write", path.display()))?;
    }
    if let Some(path) = &args.epochs_out {
        let s = outcome.series();
        std::fs::File::create(path)
            .and_then(|f| gsens_io::write_epochs_csv(f, s.t_s, s.phase_err_rad, s.accel_mps2))
            .with_context(|| format!("{}: cannot write", path.display()))?;
    }
    Ok(crate::Status::of(&doc))
}

/// Γ̂ and its covariance from a result document (`gsens estimate --json`,
/// `report.json`); an axis without an estimate is an error naming it.
pub fn gamma_of_document(path: &Path) -> Result<([f64; 3], [[f64; 3]; 3])> {
    let text = std::fs::read_to_string(path).with_context(|| format!("{}: cannot read", path.display()))?;
    let doc: serde_json::Value =
        serde_json::from_str(&text).with_context(|| format!("{}: not a JSON result document", path.display()))?;
    let number = |v: &serde_json::Value, what: &str| {
        v.as_f64().with_context(|| format!("{}: {what} is {v}: the axis was not observable", path.display()))
    };
    let g = doc["gamma_hz_per_mps2"]
        .as_array()
        .filter(|g| g.len() == 3)
        .with_context(|| format!("{}: no gamma_hz_per_mps2 (write one with gsens estimate --json)", path.display()))?;
    let c = doc["covariance_hz_per_mps2_sq"]
        .as_array()
        .filter(|c| c.len() == 3)
        .with_context(|| format!("{}: no covariance_hz_per_mps2_sq", path.display()))?;
    let mut gamma = [0.0; 3];
    let mut cov = [[0.0; 3]; 3];
    for i in 0..3 {
        gamma[i] = number(&g[i], &format!("gamma_hz_per_mps2[{i}]"))?;
        for j in 0..3 {
            cov[i][j] = number(&c[i][j], &format!("covariance_hz_per_mps2_sq[{i}][{j}]"))?;
        }
    }
    Ok((gamma, cov))
}

#[cfg(test)]
mod tests {
    use super::CalibrationArgs;
    use clap::Parser;
    use gsens_calib::{CalibrationOptions, TimeOffsetOption};

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        calibration: CalibrationArgs,
    }

    /// The flags' defaults are the library's: one vocabulary for the CLI and Python.
    #[test]
    fn no_flags_give_the_library_defaults() {
        let cli = Cli::try_parse_from(["gsens"]).unwrap();
        assert_eq!(cli.calibration.options(), CalibrationOptions::default());
    }

    #[test]
    fn flags_map_to_the_options_of_the_same_name() {
        let args = ["gsens", "--bn-hz", "2.5", "--order", "3", "--time-offset", "-0.01", "--weights", "cn0"];
        let o = Cli::try_parse_from(args).unwrap().calibration.options();
        assert_eq!(o.bn_hz, Some(2.5));
        assert_eq!(o.order, Some(3));
        assert_eq!(o.time_offset, TimeOffsetOption::Seconds(-0.01));
        assert_eq!(o.weights, gsens_session::Weighting::Cn0);
        assert!(o.loop_stated());
    }
}
