//! How exactly `gsens_core::pocket_sdr` models pocket_trk's carrier loop:
//! the model driven by each satellite's true carrier (the `carrier.csv` of
//! `gsens simulate --iq --iq-carrier-truth`) against the `err_phas` that
//! pocket_trk logged for it. Prints, per satellite, the slope of the logged φ
//! on the model's (1 for an exact model) with its standard error, and the
//! residual's RMS; exits with 1 when a slope is more than 3 standard errors
//! from 1. Run by `scripts/pocketsdr-loop-fidelity.sh`.
//!
//! Usage: loop_fidelity CARRIER_CSV TRK_LOG B_PLL_HZ [FROM_S]

use std::collections::BTreeMap;
use std::path::Path;
use std::process::ExitCode;

use gsens_core::LinearLoop;
use gsens_core::pocket_sdr::{PocketSdrPll, PocketSdrStage};
use gsens_pocketsdr::read_log;

fn main() -> ExitCode {
    match run() {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => ExitCode::from(1),
        Err(e) => {
            eprintln!("loop_fidelity: {e}");
            ExitCode::from(2)
        }
    }
}

fn run() -> Result<bool, Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() < 3 {
        return Err("usage: loop_fidelity CARRIER_CSV TRK_LOG B_PLL_HZ [FROM_S]".into());
    }
    let bw_hz: f64 = args[2].parse()?;
    let from_s: f64 = args.get(3).map(|s| s.parse()).transpose()?.unwrap_or(0.0);
    let stage = PocketSdrStage::l1ca(bw_hz);
    let mut reader = csv::Reader::from_path(&args[0])?;
    let prns: Vec<u32> = reader
        .headers()?
        .iter()
        .skip(1)
        .map(|h| h.trim_start_matches("prn").trim_end_matches("_hz").parse())
        .collect::<Result<_, _>>()?;
    // carrier[j][k]: PRN j's baseband carrier over block k [k·T, (k + 1)·T) [Hz].
    let mut carrier: Vec<Vec<f64>> = vec![Vec::new(); prns.len()];
    for rec in reader.records() {
        let rec = rec?;
        for (j, v) in rec.iter().skip(1).enumerate() {
            carrier[j].push(v.parse()?);
        }
    }
    let log = read_log(Path::new(&args[1]))?;
    // The model starts 2 s into the file (after the FLL pull-in) in the steady
    // state of that block's frequency; compared after six time constants.
    let start = (2.0 / stage.interval_s) as usize;
    let skip_s = 2.0 + 6.0 * stage.settling_time_s(1.0);
    let mut all_ok = true;
    for (j, &prn) in prns.iter().enumerate() {
        let logged: BTreeMap<usize, f64> = log
            .records
            .iter()
            .filter(|r| r.prn == prn && r.time_s >= skip_s.max(from_s))
            .map(|r| ((r.time_s / stage.interval_s).round() as usize, r.err_phas_cyc * std::f64::consts::TAU))
            .collect();
        let g = &carrier[j];
        if g.len() <= start || logged.is_empty() {
            println!("PRN {prn:2}: not logged");
            continue;
        }
        let mut model = PocketSdrPll::new(stage)?;
        model.settle(-g[start]);
        let (mut sxy, mut sxx, mut pairs) = (0.0, 0.0, Vec::new());
        for (k, &gk) in g.iter().enumerate().skip(start) {
            let phi = model.step_signal(gk);
            if let Some(&measured) = logged.get(&k) {
                sxy += phi * measured;
                sxx += phi * phi;
                pairs.push((phi, measured));
            }
        }
        let n = pairs.len() as f64;
        let slope = sxy / sxx;
        let resid_rms = (pairs.iter().map(|(x, y)| (y - slope * x).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
        let model_rms = (sxx / n).sqrt();
        let se = resid_rms / sxx.sqrt();
        let ok = (slope - 1.0).abs() < 3.0 * se;
        all_ok &= ok;
        println!(
            "PRN {prn:2}: {n} lines, slope {slope:.5} ± {se:.5} ({:+.2} SE), model RMS {model_rms:.4} rad, residual RMS {resid_rms:.4} rad{}",
            (slope - 1.0) / se,
            if ok { "" } else { "  FAIL" }
        );
    }
    Ok(all_ok)
}
