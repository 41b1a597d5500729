//! `gsens simulate --iq`: IF samples for a software receiver (GNSS-SDR), with
//! the matching IMU log, the truth, Δf per millisecond and a GNSS-SDR
//! configuration that tracks the file.

use anyhow::{Context, Result};
use gsens_gnss_sdr::conf::{IqConfOptions, iq_file_conf};
use gsens_io::ImuWriter;
use gsens_sim::iq::{BLOCK_S, ImuOnlySink, IqConfig, IqFormat, generate_iq};
use gsens_sim::scenario::Scenario;
use indicatif::{ProgressBar, ProgressStyle};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

use crate::simulate::{IqFormatArg, SimulateArgs};

/// Writes `iq` and, in `--out`: imu.csv, truth.json, delta_f.csv (t_s,delta_f_hz,g_induced_hz
/// per 1 ms block), gnss-sdr.conf and, with `--iq-carrier-truth`, carrier.csv
/// (t_s,`prn<N>_hz`,…: each satellite's baseband carrier per 1 ms block).
pub fn run(scenario: &Scenario, args: &SimulateArgs, iq: &Path) -> Result<()> {
    let (seed, fs_hz, out) = (args.seed, args.fs_hz, args.out.as_path());
    std::fs::create_dir_all(out).with_context(|| format!("{}: cannot create", out.display()))?;
    let format = match args.iq_format {
        IqFormatArg::Ibyte => IqFormat::Ibyte,
        IqFormatArg::Ishort => IqFormat::Ishort,
        IqFormatArg::GrComplex => IqFormat::GrComplex,
    };
    let create = |p: &Path| File::create(p).with_context(|| format!("{}: cannot create", p.display()));
    let iq_file = BufWriter::with_capacity(1 << 20, create(iq)?);
    let mut imu = ImuWriter::new(create(&out.join("imu.csv"))?)?;
    let df_path = out.join("delta_f.csv");
    let mut df = BufWriter::new(create(&df_path)?);
    writeln!(df, "t_s,delta_f_hz,g_induced_hz")?;
    let mut carrier = match args.iq_carrier_truth {
        true => Some(BufWriter::new(create(&out.join("carrier.csv"))?)),
        false => None,
    };
    let mut df_err: Option<std::io::Error> = None;
    let cfg = IqConfig::new(fs_hz, format, scenario);
    let bar = ProgressBar::new(1000);
    bar.set_style(
        ProgressStyle::with_template("generating {bar:40} {percent:>3}% {elapsed_precise} (eta {eta})")
            .expect("valid template"),
    );
    let started = std::time::Instant::now();
    let truth = {
        let mut sink = ImuOnlySink(|t: f64, f: [f64; 3]| imu.write_sample(t, &f).map_err(Into::into));
        generate_iq(
            scenario,
            seed,
            &cfg,
            iq_file,
            &mut sink,
            |b| {
                if df_err.is_some() {
                    return;
                }
                let mut r = writeln!(df, "{},{},{}", b.t_mid_s, b.delta_f_hz, b.g_induced_hz);
                if let Some(c) = carrier.as_mut() {
                    if b.t_mid_s < BLOCK_S {
                        r = r.and_then(|_| write!(c, "t_s"));
                        for p in b.prns {
                            r = r.and_then(|_| write!(c, ",prn{p}_hz"));
                        }
                        r = r.and_then(|_| writeln!(c));
                    }
                    r = r.and_then(|_| write!(c, "{}", b.t_mid_s));
                    for f in b.carrier_hz {
                        r = r.and_then(|_| write!(c, ",{f}"));
                    }
                    r = r.and_then(|_| writeln!(c));
                }
                if let Err(e) = r {
                    df_err = Some(e);
                }
            },
            |f| bar.set_position((f * 1000.0) as u64),
        )?
    };
    bar.finish_and_clear();
    let wall_s = started.elapsed().as_secs_f64();
    if let Some(e) = df_err {
        return Err(e).with_context(|| format!("{}: cannot write", df_path.display()));
    }
    df.flush()?;
    if let Some(mut c) = carrier {
        c.flush()?;
    }
    imu.finish()?;
    let truth_path = out.join("truth.json");
    std::fs::write(&truth_path, serde_json::to_string_pretty(&truth)? + "\n")
        .with_context(|| format!("{}: cannot write", truth_path.display()))?;

    // The GNSS-SDR configuration: absolute paths, so it runs from anywhere.
    let abs = |p: &Path| std::fs::canonicalize(p).unwrap_or_else(|_| p.to_path_buf());
    let dumps = out.join("gnss-sdr");
    std::fs::create_dir_all(&dumps).with_context(|| format!("{}: cannot create", dumps.display()))?;
    let l = &scenario.tracking_loop;
    let mut o = IqConfOptions::for_iq_file(
        &abs(iq).display().to_string(),
        format.gnss_sdr_item_type(),
        fs_hz,
        truth.satellites.len() as u32,
        l.order,
        l.bn_hz,
    );
    o.dump_filename = format!("{}/trk_ch_", abs(&dumps).display());
    let conf_path = out.join("gnss-sdr.conf");
    std::fs::write(&conf_path, iq_file_conf(&o)).with_context(|| format!("{}: cannot write", conf_path.display()))?;

    let prns: Vec<String> =
        truth.satellites.iter().map(|s| format!("{} ({:.1} dB-Hz)", s.prn, s.start_cn0_dbhz)).collect();
    println!(
        "wrote {:.1} s of {} samples at {} Hz ({} samples, {:.1} MB) in {:.1} s ({:.1}x real time) → {}",
        truth.duration_s,
        format.gnss_sdr_item_type(),
        fs_hz,
        truth.samples,
        (truth.samples * format.bytes_per_sample() as u64) as f64 / 1e6,
        wall_s,
        truth.duration_s / wall_s,
        iq.display()
    );
    println!("satellites: PRN {}", prns.join(", PRN "));
    println!(
        "truth Γ = [{:+.4}, {:+.4}, {:+.4}] Hz/(m/s²); imu.csv, truth.json, delta_f.csv, gnss-sdr.conf in {}",
        truth.gamma_hz_per_mps2[0],
        truth.gamma_hz_per_mps2[1],
        truth.gamma_hz_per_mps2[2],
        out.display()
    );
    println!("run: gnss-sdr --config_file={}", abs(&conf_path).display());
    Ok(())
}
