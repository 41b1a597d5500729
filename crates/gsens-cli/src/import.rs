//! `gsens import`: another receiver's logs as gsens's `tracking.csv`.

use crate::args::{ConversionArgs, conversion_error};
use anyhow::Result;
use clap::{Args, Subcommand};
use gsens_gnss_sdr::{ImportSettings, import_dir};
use gsens_tui::progress::with_spinner;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub(crate) struct ImportArgs {
    #[command(subcommand)]
    pub source: ImportSource,
}

/// The receivers `gsens import` reads.
#[derive(Subcommand, Debug)]
pub(crate) enum ImportSource {
    /// GNSS-SDR tracking dumps (Tracking_1C.dump=true: trk_ch_N.dat) → tracking.csv.
    GnssSdr(ImportGnssSdrArgs),
    /// A PocketSDR pocket_trk log (-log FILE: $CH lines) → tracking.csv.
    #[command(name = "pocketsdr")]
    PocketSdr(ImportPocketSdrArgs),
    /// GNSS-SDR's tracking monitor (TrackingMonitor.enable_monitor=true), received over UDP → tracking.csv.
    GnssSdrMonitor(crate::monitor::ImportMonitorArgs),
}

/// `gsens import pocketsdr`.
#[derive(Args, Debug)]
pub(crate) struct ImportPocketSdrArgs {
    /// The pocket_trk log.
    pub log: PathBuf,
    /// Output tracking.csv (`gsens estimate --tracking` reads it as written).
    #[arg(long, default_value = "tracking.csv")]
    pub out: PathBuf,
    /// Also write what became of each track (JSON).
    #[arg(long)]
    pub tracks_json: Option<PathBuf>,
    #[command(flatten)]
    pub conversion: gsens_pocketsdr::ImportOptions,
}

fn run_pocketsdr(a: &ImportPocketSdrArgs) -> Result<()> {
    let settings = a.conversion.settings().map_err(|e| conversion_error(e.into()))?;
    crate::check_files(&[("--out", Some(&a.out)), ("--tracks-json", a.tracks_json.as_deref())], None)?;
    let imported = with_spinner("reading the PocketSDR log", || gsens_pocketsdr::import_file(&a.log, &settings))?;
    let conf = a.conversion.conf.as_deref();
    let export = gsens_pocketsdr::Export { log: &a.log, conf, csv: &a.out, tracks_json: a.tracks_json.as_deref() };
    Ok(export.write(&imported, &mut crate::say, crate::args::flag)?)
}

/// `gsens import gnss-sdr`.
#[derive(Args, Debug)]
pub(crate) struct ImportGnssSdrArgs {
    /// Directory of the dumps.
    pub dump_dir: PathBuf,
    /// The GNSS-SDR configuration the dumps were made with (default: GNSS-SDR 0.0.17's defaults).
    #[arg(long)]
    pub conf: Option<PathBuf>,
    /// Output tracking.csv (`gsens estimate --tracking` reads it as written).
    #[arg(long, default_value = "tracking.csv")]
    pub out: PathBuf,
    /// Write each record at the middle of its own integration, with its carrier lock test,
    /// instead of all channels on the common grid t = j·T (T the narrow integration, by cubic
    /// interpolation) that `gsens estimate --tracking` needs (channels not on one grid: it
    /// refuses them).
    #[arg(long)]
    pub record_times: bool,
    /// Also write what became of each track (JSON).
    #[arg(long)]
    pub tracks_json: Option<PathBuf>,
    #[command(flatten)]
    pub conversion: ConversionArgs,
}

pub(crate) fn run(args: &ImportArgs) -> Result<()> {
    let a = match &args.source {
        ImportSource::GnssSdr(a) => a,
        ImportSource::PocketSdr(a) => return run_pocketsdr(a),
        ImportSource::GnssSdrMonitor(a) => return crate::monitor::run(a),
    };
    // The dumps first: a missing or empty directory is the first thing to fix,
    // whatever the configuration says.
    gsens_gnss_sdr::find_dumps(&a.dump_dir, None)?;
    let c = &a.conversion;
    let settings = ImportSettings::from_conf_with(a.conf.as_deref(), c.gnss_sdr_fs_hz, &c.overrides)
        .map_err(|e| conversion_error(e.into()))?;
    crate::check_files(&[("--out", Some(&a.out)), ("--tracks-json", a.tracks_json.as_deref())], None)?;
    let imported = with_spinner("reading the GNSS-SDR tracking dumps", || import_dir(&a.dump_dir, &settings))?;
    let export = gsens_gnss_sdr::Export {
        dump_dir: &a.dump_dir,
        conf: a.conf.as_deref(),
        csv: &a.out,
        on_common_grid: !a.record_times,
        tracks_json: a.tracks_json.as_deref(),
    };
    Ok(export.write(imported, settings, &mut crate::say, crate::args::flag)?)
}
