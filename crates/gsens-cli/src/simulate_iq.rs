//! `gsens simulate --iq`: IF samples for a software receiver (GNSS-SDR), with
//! the matching IMU log, the truth, Δf per millisecond and a GNSS-SDR
//! configuration that tracks the file.

use crate::simulate::{IqFormatArg, SimulateArgs, progress_bar};
use anyhow::{Context, Result};
use gsens_gnss_sdr::conf::{IqConfOptions, iq_file_conf};
use gsens_sim::iq::{IqConfig, IqFormat};
use gsens_sim::scenario::Scenario;
use std::path::Path;

/// Writes `iq` and, in `--out`, the files of `gsens_sim::simulate_iq_to_dir`
/// and gnss-sdr.conf.
pub fn run(scenario: &Scenario, args: &SimulateArgs, iq: &Path) -> Result<()> {
    let (fs_hz, out) = (args.fs_hz, args.out.as_path());
    let format = match args.iq_format {
        IqFormatArg::Ibyte => IqFormat::Ibyte,
        IqFormatArg::Ishort => IqFormat::Ishort,
        IqFormatArg::GrComplex => IqFormat::GrComplex,
    };
    let bar = progress_bar("generating");
    let cfg = IqConfig::new(fs_hz, format, scenario);
    let session =
        gsens_sim::simulate_iq_to_dir(scenario, args.scenario.seed, &cfg, iq, out, args.iq_carrier_truth, |f| {
            bar.set_position((f * 1000.0) as u64)
        })?;
    bar.finish_and_clear();
    let (truth, wall_s) = (&session.truth, session.wall_s);

    // The GNSS-SDR configuration: absolute paths, so it runs from anywhere.
    let abs = |p: &Path| std::fs::canonicalize(p).unwrap_or_else(|_| p.to_path_buf());
    let dumps = out.join("gnss-sdr");
    std::fs::create_dir_all(&dumps).with_context(|| format!("{}: cannot create", dumps.display()))?;
    let l = &scenario.tracking_loop;
    let sats = truth.satellites.len() as u32;
    let mut o = IqConfOptions::for_iq_file(
        &abs(iq).display().to_string(),
        format.gnss_sdr_item_type(),
        fs_hz,
        sats,
        l.order,
        l.bn_hz,
    );
    o.dump_filename = format!("{}/trk_ch_", abs(&dumps).display());
    let conf_path = out.join("gnss-sdr.conf");
    std::fs::write(&conf_path, iq_file_conf(&o)).with_context(|| format!("{}: cannot write", conf_path.display()))?;

    let prns: Vec<String> =
        truth.satellites.iter().map(|s| format!("{} ({:.1} dB-Hz)", s.prn, s.start_cn0_dbhz)).collect();
    let g = truth.sensitivity.gamma_hz_per_mps2;
    crate::out(&format!(
        "wrote {:.1} s of {} samples at {} Hz ({} samples, {:.1} MB) in {:.1} s ({:.1}x real time) → {}\n\
         satellites: PRN {}\n\
         truth Γ = [{:+.4}, {:+.4}, {:+.4}] Hz/(m/s²); imu.csv, truth.json, delta_f.csv, gnss-sdr.conf in {}\n\
         run: gnss-sdr --config_file={}\n",
        truth.duration_s,
        format.gnss_sdr_item_type(),
        fs_hz,
        truth.samples,
        (truth.samples * format.bytes_per_sample() as u64) as f64 / 1e6,
        wall_s,
        truth.duration_s / wall_s,
        iq.display(),
        prns.join(", PRN "),
        g[0],
        g[1],
        g[2],
        out.display(),
        abs(&conf_path).display()
    ))
}
