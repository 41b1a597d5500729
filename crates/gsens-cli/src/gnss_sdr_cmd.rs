//! GNSS-SDR in the CLI: `gsens import gnss-sdr` (dumps → tracking.csv) and
//! `gsens estimate --gnss-sdr DIR --gnss-sdr-conf FILE` (dumps → Γ̂ with the
//! exact model of GNSS-SDR's carrier loop).

use anyhow::{Context, Result, bail};
use clap::{Args, Subcommand};
use gsens_calib::EstimateSettings;
use gsens_core::pll::gnss_sdr::{A2, A3, B3, BN_OVER_WN_ORDER2, BN_OVER_WN_ORDER3, GnssSdrStage};
use gsens_core::pll::{LoopFilterCoeffs, LoopSpec};
use gsens_core::regressor::LoggedPhase;
use gsens_gnss_sdr::conf::{GnssSdrConf, TrackingConf};
use gsens_gnss_sdr::dump::DumpLayout;
use gsens_gnss_sdr::import::{
    GridRow, ImportSettings, Imported, import_dir, resample, write_imported_csv, write_tracking_csv,
};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::estimate::EstimateArgs;

/// Options of `gsens estimate` for GNSS-SDR tracking dumps.
#[derive(Args, Debug, Clone)]
pub struct GnssSdrArgs {
    /// Directory of GNSS-SDR tracking dumps (trk_ch_N.dat, Tracking_1C.dump=true) to use instead of --tracking.
    #[arg(long, requires = "gnss_sdr_conf")]
    pub gnss_sdr: Option<PathBuf>,
    /// The GNSS-SDR configuration file the dumps were made with (its loop is modelled exactly).
    #[arg(long, requires = "gnss_sdr")]
    pub gnss_sdr_conf: Option<PathBuf>,
    #[command(flatten)]
    pub conversion: ConversionArgs,
}

/// How dump records are selected.
#[derive(Args, Debug, Clone)]
pub struct ConversionArgs {
    /// Sampling rate of the tracking [Hz] when the configuration does not give it.
    #[arg(long)]
    pub gnss_sdr_fs_hz: Option<f64>,
    /// Records below this C/N0 are dropped [dB-Hz].
    #[arg(long, default_value_t = 25.0)]
    pub gnss_sdr_min_cn0_dbhz: f64,
    /// Records whose carrier lock test is below this are dropped.
    #[arg(long, default_value_t = 0.85)]
    pub gnss_sdr_min_lock_test: f64,
    /// Seconds dropped after a channel switches to the narrow loop (default: five time
    /// constants of the loop's slowest mode, at least 1 s).
    #[arg(long)]
    pub gnss_sdr_settle_s: Option<f64>,
    /// Record layout `name:type,...` for dumps of versions the reader does not know.
    #[arg(long)]
    pub gnss_sdr_layout: Option<String>,
}

impl ConversionArgs {
    fn settings(&self, conf: Option<&Path>) -> Result<ImportSettings> {
        let tracking = match conf {
            Some(p) => GnssSdrConf::read(p)?.tracking()?,
            None => TrackingConf::defaults(),
        };
        let fs_hz = match (self.gnss_sdr_fs_hz, tracking.fs_hz) {
            (Some(f), _) | (None, Some(f)) => f,
            (None, None) => bail!(
                "the sampling rate is unknown: the configuration gives neither GNSS-SDR.internal_fs_sps nor \
                 SignalSource.sampling_frequency; give --gnss-sdr-fs-hz"
            ),
        };
        if !(fs_hz.is_finite() && fs_hz > 0.0) {
            bail!("the sampling rate must be positive, got {fs_hz}");
        }
        let mut s = ImportSettings::new(fs_hz, tracking);
        s.min_cn0_dbhz = self.gnss_sdr_min_cn0_dbhz;
        s.min_lock_test = self.gnss_sdr_min_lock_test;
        if let Some(v) = self.gnss_sdr_settle_s.filter(|v| !(*v >= 0.0 && v.is_finite())) {
            bail!("--gnss-sdr-settle-s must be ≥ 0, got {v}");
        }
        s.settle_s = self.gnss_sdr_settle_s;
        if let Some(spec) = &self.gnss_sdr_layout {
            s.layout = Some(DumpLayout::parse_spec(spec).context("--gnss-sdr-layout")?);
        }
        Ok(s)
    }
}

/// The loop GNSS-SDR runs after bit synchronization, and its continuous
/// equivalent (for the verdicts and the text report).
pub fn loop_of(tc: &TrackingConf) -> (GnssSdrStage, LoopSpec) {
    let stage =
        GnssSdrStage { order: tc.pll_filter_order, bw_hz: tc.narrow_bw_hz(), symbols: tc.extend_correlation_symbols };
    let c = if stage.order == 3 {
        let wn = stage.bw_hz / BN_OVER_WN_ORDER3;
        LoopFilterCoeffs { c0_per_s: B3 * wn, c1_per_s2: 0.5 * A3 * wn * wn, c2_per_s3: 0.25 * wn * wn * wn }
    } else {
        let wn = stage.bw_hz / BN_OVER_WN_ORDER2;
        LoopFilterCoeffs { c0_per_s: A2 * wn, c1_per_s2: wn * wn, c2_per_s3: 0.0 }
    };
    (stage, LoopSpec::Coefficients(c))
}

/// The tracks of an import as text.
pub fn tracks_text(imp: &Imported) -> String {
    let mut s = String::new();
    let used = imp.tracks.iter().filter(|t| t.used).count();
    let _ = writeln!(
        s,
        "GNSS-SDR dumps: {} tracks, {} used, {} records at {} ms kept",
        imp.tracks.len(),
        used,
        imp.rows.len(),
        imp.interval_s * 1e3
    );
    for t in &imp.tracks {
        let _ = writeln!(
            s,
            "  ch {:>3}  PRN {:>3}  {:>7.2}–{:>7.2} s  narrow from {}  C/N0 {:>5.1} dB-Hz  {:>6}/{:<6} good  {}",
            t.channel,
            t.prn,
            t.start_s,
            t.end_s,
            t.switch_s.map(|v| format!("{v:>7.2} s")).unwrap_or_else(|| "      —  ".into()),
            t.mean_cn0_dbhz,
            t.good_records,
            t.modelled_records,
            t.reason
        );
    }
    s
}

fn grid_csv(rows: &[GridRow]) -> Result<Vec<u8>> {
    Ok(write_tracking_csv(Vec::new(), rows.iter().map(|r| (r.t_s, r.channel, r.prn, r.cn0_dbhz, r.phase_err_rad)))?)
}

/// `gsens estimate --gnss-sdr DIR --gnss-sdr-conf FILE`.
pub fn estimate(args: &EstimateArgs, dir: &Path) -> Result<()> {
    let conf = args.gnss_sdr.gnss_sdr_conf.as_deref();
    let import = args.gnss_sdr.conversion.settings(conf)?;
    let imported = import_dir(dir, &import)?;
    print!("{}", tracks_text(&imported));
    let grid = resample(&imported, imported.interval_s);
    let csv = grid_csv(&grid)?;
    let name = format!("{} (GNSS-SDR dumps on a {} ms grid)", dir.display(), imported.interval_s * 1e3);
    let tracking_log = gsens_io::read_tracking(csv.as_slice(), &name)?;
    let imu = gsens_io::read_imu_file(&args.imu)?;
    let (stage, nominal) = loop_of(&import.tracking);
    let settings = EstimateSettings {
        robust: args.robust.robust(),
        loop_spec: nominal,
        loop_interval_s: Some(stage.interval_s()),
        logged_phase: LoggedPhase::Last,
        gnss_sdr_loop: Some(stage),
        ..args.estimator.settings(&args.loop_args)?
    };
    let (session, calibration) = crate::estimate::estimate_logs(
        &tracking_log,
        &imu,
        &args.imu.display().to_string(),
        &args.selection.selection(),
        &args.systematic,
        &settings,
    )?;
    println!(
        "GNSS-SDR loop: order {}, Bn {} Hz, {} ms integrations (pll_bw_narrow_hz, extend_correlation_symbols), \
         modelled exactly",
        stage.order, stage.bw_hz, stage.symbols
    );
    print!("{}", crate::report::text(&session, &calibration, None));
    if let Some(path) = &args.json {
        let conf_path = conf.map(Path::to_path_buf).unwrap_or_default();
        crate::report::write_json(
            path,
            &session,
            &calibration,
            None,
            &[("imu", &args.imu), ("gnss_sdr_dumps", dir), ("gnss_sdr_conf", &conf_path)],
        )
        .with_context(|| format!("writing {}", path.display()))?;
        // Add what the conversion did.
        let text = std::fs::read_to_string(path)?;
        let mut v: serde_json::Value = serde_json::from_str(&text)?;
        if let Some(obj) = v.as_object_mut() {
            obj.insert("gnss_sdr".into(), serde_json::json!({ "conversion": &import, "tracks": &imported.tracks }));
        }
        std::fs::write(path, serde_json::to_string_pretty(&v)? + "\n")
            .with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}

/// `gsens import`: convert another receiver's logs to gsens's.
#[derive(Args, Debug)]
pub struct ImportArgs {
    #[command(subcommand)]
    pub source: ImportSource,
}

/// The receivers `gsens import` reads.
#[derive(Subcommand, Debug)]
pub enum ImportSource {
    /// GNSS-SDR tracking dumps (Tracking_1C.dump=true: trk_ch_N.dat) → tracking.csv.
    GnssSdr(ImportGnssSdrArgs),
}

/// `gsens import gnss-sdr`.
#[derive(Args, Debug)]
pub struct ImportGnssSdrArgs {
    /// Directory of the dumps.
    pub dump_dir: PathBuf,
    /// The GNSS-SDR configuration the dumps were made with (default: GNSS-SDR 0.0.17's defaults).
    #[arg(long)]
    pub conf: Option<PathBuf>,
    /// Output tracking.csv.
    #[arg(long)]
    pub out: PathBuf,
    /// Put all channels on the common grid t = j·T (T the narrow integration) by cubic
    /// interpolation, as `gsens estimate --tracking` needs; default: each record at the
    /// middle of its own integration.
    #[arg(long)]
    pub common_grid: bool,
    /// Also write what became of each track (JSON).
    #[arg(long)]
    pub tracks_json: Option<PathBuf>,
    #[command(flatten)]
    pub conversion: ConversionArgs,
}

/// Runs `gsens import`.
pub fn import(args: &ImportArgs) -> Result<()> {
    let ImportSource::GnssSdr(a) = &args.source;
    let settings = a.conversion.settings(a.conf.as_deref())?;
    let imported = import_dir(&a.dump_dir, &settings)?;
    print!("{}", tracks_text(&imported));
    let file = std::fs::File::create(&a.out).with_context(|| format!("{}: cannot create", a.out.display()))?;
    let rows = if a.common_grid {
        let g = resample(&imported, imported.interval_s);
        let n = g.len();
        write_tracking_csv(file, g.iter().map(|r| (r.t_s, r.channel, r.prn, r.cn0_dbhz, r.phase_err_rad)))?;
        n
    } else {
        write_imported_csv(file, &imported.rows)?;
        imported.rows.len()
    };
    let (stage, _) = loop_of(&settings.tracking);
    println!(
        "wrote {} rows → {}{}; estimate with the GNSS-SDR loop model: gsens estimate --gnss-sdr {} --gnss-sdr-conf \
         <conf> (order {}, Bn {} Hz, {} ms)",
        rows,
        a.out.display(),
        if a.common_grid { " (common grid)" } else { " (times at the middle of each integration)" },
        a.dump_dir.display(),
        stage.order,
        stage.bw_hz,
        stage.symbols
    );
    if let Some(p) = &a.tracks_json {
        std::fs::write(
            p,
            serde_json::to_string_pretty(&serde_json::json!({ "conversion": &settings, "tracks": &imported.tracks }))?
                + "\n",
        )
        .with_context(|| format!("{}: cannot write", p.display()))?;
    }
    Ok(())
}
