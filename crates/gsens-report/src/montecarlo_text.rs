//! A Monte Carlo ([`gsens_montecarlo`]) as text.

use crate::AXES;
use gsens_montecarlo::MonteCarlo;
use std::fmt::Write as _;

/// A Monte Carlo as a table: bias, RMSE, Cramér–Rao bound, their ratio, the
/// 3σ coverage and the z RMS per method and axis, then the best method.
pub fn render_montecarlo_text(mc: &MonteCarlo) -> String {
    let stats = &mc.methods;
    let mut s = String::new();
    let s_ = &mut s;
    let _ = writeln!(
        s_,
        "monte carlo: {} runs of the {} scenario (seeds {}…{}), {:.1} s wall on {} threads",
        mc.runs,
        mc.scenario,
        mc.seed,
        mc.seed + mc.runs - 1,
        mc.wall_s,
        mc.threads
    );
    let stated = match mc.stated_bn_scale {
        Some(k) if (k - 1.0).abs() < 1e-12 => "the receiver's loop stated right".to_string(),
        Some(k) => format!("the receiver's loop stated with {k} times its bandwidth"),
        None => "no receiver loop stated (the data choose it)".to_string(),
    };
    let has = |row: &str| stats.iter().any(|(n, _)| *n == row);
    let mut loop_free = String::new();
    if has(gsens_montecarlo::LOOP_FREE) {
        loop_free += &format!("; {}: the input phase θ_NCO + φ, no loop model", gsens_montecarlo::LOOP_FREE);
    }
    if has(gsens_montecarlo::NCO_FREQUENCY) {
        loop_free +=
            &format!("; {}: the NCO frequency through the loop model's closed loop", gsens_montecarlo::NCO_FREQUENCY);
    }
    let _ = writeln!(s_, "methods: the tracking error through the loop model, {stated}{loop_free}");
    let _ = writeln!(
        s_,
        "errors Γ̂ − Γ_imu (Γ through the IMU's scale and misalignment) [Hz/(m/s²)]; CRLB: RMS over runs of each run's bound\n"
    );
    // The name column fits the longest row name (at least the methods' 9).
    let w = stats.iter().map(|(n, _)| n.chars().count()).fold(9, usize::max);
    let _ = writeln!(
        s_,
        "{:<w$} axis      bias        RMSE        CRLB   RMSE/CRLB  |e|≤1σ  |e|≤2σ  |e|≤3σ   z RMS   RMSE vs body Γ",
        "method"
    );
    for (name, st) in stats {
        if st.runs == 0 {
            let _ = writeln!(
                s_,
                "{name:<w$}      no statistics: none of the {} runs gave an estimate of every axis",
                mc.runs
            );
            continue;
        }
        for i in 0..3 {
            let _ = writeln!(
                s_,
                "{:<w$} {:>3}  {:>+10.6}  {:>10.6}  {:>10.6}  {:>9.3}  {:>5.1} %  {:>5.1} %  {:>5.1} %  {:>6.2}   {:>10.6}",
                if i == 0 { *name } else { "" },
                AXES[i],
                st.bias[i],
                st.rmse[i],
                st.crlb[i],
                st.rmse_over_crlb[i],
                100.0 * st.within_1sigma[i],
                100.0 * st.within_2sigma[i],
                100.0 * st.within_3sigma[i],
                st.z_rms[i],
                st.rmse_body[i]
            );
        }
        if st.failures > 0 {
            let _ =
                writeln!(s_, "{:<w$}      {} of {} runs failed or left an axis unobservable", "", st.failures, mc.runs);
        }
    }
    if let Some(b) = &mc.best_method {
        let st = &stats.iter().find(|(n, _)| n == b).expect("best is one of them").1;
        let worst = st.rmse_over_crlb.iter().fold(0.0f64, |a, &x| a.max(x));
        let _ = writeln!(s_, "\nbest: {b} (largest RMSE/CRLB over the axes {worst:.3})");
    }
    for (name, st) in stats.iter().filter(|(_, st)| st.untrustworthy.is_finite()) {
        let codes: Vec<String> = st.warning_counts.iter().map(|(c, n)| format!("{c} ×{n}")).collect();
        let _ = writeln!(
            s_,
            "{name}: flagged not trustworthy in {:.1} % of the runs with an estimate{}",
            100.0 * st.untrustworthy,
            if codes.is_empty() { String::new() } else { format!(" (warnings: {})", codes.join(", ")) }
        );
        if let Some(t) = st.time_offset_error_s {
            let _ =
                writeln!(s_, "{name}: IMU time offset error: bias {:+.3} ms, RMS {:.3} ms", 1e3 * t.mean, 1e3 * t.rms);
        }
        if let Some(f) = st.natural_frequency_error_hz {
            let _ = writeln!(s_, "{name}: loop ωn/2π error: bias {:+.5} Hz, RMS {:.5} Hz", f.mean, f.rms);
        }
    }
    s
}
