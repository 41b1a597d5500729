//! Writes a long synthetic calibration log for benchmarking `gsens estimate`:
//! `cargo run --release --example long_log -- DIR [HOURS] [CHANNELS]` writes
//! DIR/imu.csv and DIR/tracking.csv at 40 Hz (default 1 hour, 12 channels).
//!
//! The phase error of every channel is the same discrete loop driven by
//! Δf = aᵀΓ (Γ = the paper's value) plus white noise per channel; the board is
//! shaken along x, y, z in turn. Enough realism for timing, not for accuracy
//! studies (use `gsens simulate` for those).

use gsens_core::{DiscretePll, LoopSpec};
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};
use rand_xoshiro::Xoshiro256PlusPlus;
use std::io::{BufWriter, Write};

fn main() -> std::io::Result<()> {
    let mut args = std::env::args().skip(1);
    let dir = std::path::PathBuf::from(args.next().unwrap_or_else(|| "long_log".into()));
    let hours: f64 = args.next().and_then(|s| s.parse().ok()).unwrap_or(1.0);
    let channels: u32 = args.next().and_then(|s| s.parse().ok()).unwrap_or(12);
    std::fs::create_dir_all(&dir)?;
    let gamma = [0.09, 0.08, -0.08];
    let t_log = 0.025;
    let n = (hours * 3600.0 / t_log) as usize;
    let mut pll = DiscretePll::new(LoopSpec::PAPER.coeffs().expect("valid loop"), t_log);
    pll.settle(9.80665 * gamma[2]);
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(1);
    let noise = Normal::new(0.0, 0.05).expect("valid sigma");
    let mut imu = BufWriter::new(std::fs::File::create(dir.join("imu.csv"))?);
    let mut trk = BufWriter::new(std::fs::File::create(dir.join("tracking.csv"))?);
    writeln!(imu, "t_s,fx_mps2,fy_mps2,fz_mps2")?;
    writeln!(trk, "t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad")?;
    for k in 0..n {
        let t = k as f64 * t_log;
        let mut a = [0.0, 0.0, 9.80665];
        let axis = ((t / 20.0) as usize) % 4;
        if axis < 3 {
            a[axis] += 3.0 * (std::f64::consts::TAU * 0.9 * t).sin();
        }
        let phi = pll.step((0..3).map(|i| a[i] * gamma[i]).sum());
        writeln!(imu, "{t},{},{},{}", a[0], a[1], a[2])?;
        for ch in 0..channels {
            let p = phi + noise.sample(&mut rng);
            writeln!(trk, "{t},{ch},{},{},{},{p}", ch + 1, 40 + ch % 8, 20 + 3 * ch)?;
        }
    }
    imu.flush()?;
    trk.flush()?;
    eprintln!("wrote {} epochs × {channels} channels to {}", n, dir.display());
    Ok(())
}
