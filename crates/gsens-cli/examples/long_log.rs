//! Writes a long synthetic calibration log for benchmarking `gsens estimate`:
//! `cargo run --release --example long_log -- DIR [HOURS] [CHANNELS]` writes
//! DIR/imu.csv and DIR/tracking.csv at 40 Hz (default 1 hour, 12 channels).
//!
//! The receiver's loop is the paper's (2nd order, Bn = 3 Hz) updated every
//! 1 ms, 25 updates per 25 ms row, driven by Δf = aᵀΓ (Γ = the paper's value)
//! with the specific force evaluated at each update; each row logs the mean of
//! the 25 discriminator outputs since the previous row, as
//! `gsens_core::LoggedPhase::Mean` defines it (update j of row k centred at
//! t_k − (25 − j)·1 ms, the row stamped at its last), plus white noise per
//! channel. The board is shaken along x, y, z in turn. It is the log of
//! `gsens estimate --order 2 --bn-hz 3 --loop-interval-s 0.001
//! --logged-phase mean`. Enough realism for timing, not for accuracy studies
//! (use `gsens simulate` for those).

use gsens_core::{DiscretePll, LoopSpec};
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};
use rand_xoshiro::Xoshiro256PlusPlus;
use std::io::{BufWriter, Write};

/// Specific force at time `t_s` \[m/s²\]: gravity on z, and a 0.9 Hz,
/// 3 m/s² sinusoid on x, y, z in turn for 20 s each, then 20 s at rest.
fn specific_force_mps2(t_s: f64) -> [f64; 3] {
    let mut a = [0.0, 0.0, 9.80665];
    let axis = ((t_s / 20.0) as usize) % 4;
    if axis < 3 {
        a[axis] += 3.0 * (std::f64::consts::TAU * 0.9 * t_s).sin();
    }
    a
}

fn main() -> std::io::Result<()> {
    let mut args = std::env::args().skip(1);
    let dir = std::path::PathBuf::from(args.next().unwrap_or_else(|| "long_log".into()));
    let hours: f64 = args.next().and_then(|s| s.parse().ok()).unwrap_or(1.0);
    let channels: u32 = args.next().and_then(|s| s.parse().ok()).unwrap_or(12);
    std::fs::create_dir_all(&dir)?;
    let gamma = [0.09, 0.08, -0.08];
    let (t_log_s, t_loop_s, updates_per_row) = (0.025, 0.001, 25u32);
    let n = (hours * 3600.0 / t_log_s) as usize;
    let mut pll = DiscretePll::new(LoopSpec::PAPER.coeffs().expect("valid loop"), t_loop_s);
    pll.settle(9.80665 * gamma[2]);
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(1);
    let noise = Normal::new(0.0, 0.05).expect("valid sigma");
    let mut imu = BufWriter::new(std::fs::File::create(dir.join("imu.csv"))?);
    let mut trk = BufWriter::new(std::fs::File::create(dir.join("tracking.csv"))?);
    writeln!(imu, "t_s,fx_mps2,fy_mps2,fz_mps2")?;
    writeln!(trk, "t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad")?;
    for k in 0..n {
        let t = k as f64 * t_log_s;
        // The row's updates, the first 24 ms before its stamp, the last at it.
        let mut sum_rad = 0.0;
        for j in 1..=updates_per_row {
            let a = specific_force_mps2(t - f64::from(updates_per_row - j) * t_loop_s);
            sum_rad += pll.step((0..3).map(|i| a[i] * gamma[i]).sum());
        }
        let phi = sum_rad * (1.0 / f64::from(updates_per_row));
        let a = specific_force_mps2(t);
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
