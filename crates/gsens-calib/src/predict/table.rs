//! A sweep ([`Sweep`]) as the text table `gsens predict` prints: a line
//! stating the loop, the oscillator, the signal, the feed-forward and the
//! lock rule, then per level the vibration's RMS, each part of the phase
//! jitter without and with compensation, whether lock holds and the
//! narrowest loop that keeps it, and a note on what "with" means.

use super::{BN_GRID_HZ, FeedForward, Sweep, SweepSettings};
use std::fmt::Write as _;

/// What a sweep was computed with that [`SweepSettings`] does not hold.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SweepContext<'a> {
    /// The oscillator in words, e.g. `OCXO` (`noise-free` without one).
    pub oscillator: &'a str,
    /// The feed-forward's timing, whose delay is the settings'.
    pub feed_forward: FeedForward,
}

/// The narrowest bandwidth as the table writes it: `≤` the grid's first
/// when that one keeps lock, `none ≤` the grid's last when none does.
fn narrowest(bn_hz: Option<f64>) -> String {
    match bn_hz {
        None => format!("none ≤ {}", BN_GRID_HZ[BN_GRID_HZ.len() - 1]),
        Some(b) if b <= BN_GRID_HZ[0] => format!("≤ {b:.1}"),
        Some(b) => format!("{b:.1}"),
    }
}

/// The table of `sweep`, computed with `settings` in `context`.
pub fn render_sweep_text(settings: &SweepSettings, sweep: &Sweep, context: &SweepContext) -> String {
    let b = &settings.base;
    let feed = &context.feed_forward;
    let cn0 = b.cn0_dbhz.map_or("no thermal noise".to_string(), |c| format!("C/N0 {c} dB-Hz"));
    let mut s = format!(
        "loop: 2nd order, Bn {} Hz, ζ {:.3}, T {} s; oscillator {}; {cn0}; feed-forward delay {:.4} s (latency {} s \
         + half the IMU's {} Hz sample); lock while 3σ + θe ≤ 45°, θe the dynamic stress of a {} Hz/s Doppler \
         rate\n\n",
        settings.bn_hz,
        settings.zeta,
        settings.loop_interval_s,
        context.oscillator,
        b.delay_s,
        feed.latency_s,
        feed.imu_rate_hz,
        b.doppler_rate_hz_per_s
    );
    s += "  level  vibration RMS [m/s²]     1σ [rad]: thermal  oscillator  vibration without → with   total without \
          → with   lock without/with   narrowest Bn without/with [Hz]\n";
    let yes = |b: bool| if b { "yes" } else { "NO" };
    for r in &sweep.predictions {
        let _ = writeln!(
            s,
            "  {:5.2}  {:5.2} {:5.2} {:5.2}        {:7.4}     {:7.4}     {:7.4} → {:7.4}       {:6.4} → {:6.4}       \
             {:>3} / {:<3}          {} / {}",
            r.level,
            r.vibration_rms_mps2[0],
            r.vibration_rms_mps2[1],
            r.vibration_rms_mps2[2],
            r.thermal_rad,
            r.oscillator_rad,
            r.vibration_rad[0],
            r.vibration_rad[1],
            r.total_rad[0],
            r.total_rad[1],
            yes(r.keeps_lock[0]),
            yes(r.keeps_lock[1]),
            narrowest(r.narrowest_bn_hz[0]),
            narrowest(r.narrowest_bn_hz[1]),
        );
    }
    s + "\nwithout: Δf = aᵀΓ̂ reaches the loop; with: what Γ̂'s covariance and the feed-forward's delay leave of it \
         (docs: gsens_calib::predict)\n"
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::predict::{PredictionInput, SweepRow, Vibration};

    #[test]
    fn the_table_states_the_setup_and_writes_one_row_per_level() {
        let feed_forward = FeedForward { imu_rate_hz: 40.0, latency_s: 0.0 };
        let settings = SweepSettings {
            base: PredictionInput {
                gamma_hz_per_mps2: [0.09, 0.08, -0.08],
                covariance: [[0.0; 3]; 3],
                vibration: Vibration::Tones(vec![(0.9, [3.0, 0.0, 0.0])]),
                oscillator: None,
                cn0_dbhz: Some(45.0),
                delay_s: feed_forward.delay_s(),
                imu_noise_mps2_per_rthz: 0.0,
                doppler_rate_hz_per_s: 0.9,
            },
            levels: vec![1.0, 2.0],
            bn_hz: 3.0,
            zeta: std::f64::consts::FRAC_1_SQRT_2,
            loop_interval_s: 0.001,
        };
        let row = SweepRow {
            dynamic_stress_rad: 0.1,
            keeps_lock: [false, true],
            level: 2.0,
            narrowest_bn_hz: [None, Some(0.1)],
            oscillator_rad: 0.0,
            p_beyond_linear_range: [0.5, 0.0],
            thermal_rad: 0.05,
            total_rad: [0.4, 0.06],
            vibration_rad: [0.39, 0.03],
            vibration_rms_mps2: [4.24264, 0.0, 0.0],
        };
        let sweep = Sweep {
            bn_hz: 3.0,
            covariance_hz_per_mps2_sq: [[0.0; 3]; 3],
            gamma_hz_per_mps2: [0.09, 0.08, -0.08],
            predictions: vec![SweepRow { level: 1.0, narrowest_bn_hz: [Some(2.5), Some(0.3)], ..row }, row],
        };
        let text = render_sweep_text(&settings, &sweep, &SweepContext { oscillator: "noise-free", feed_forward });
        let lines: Vec<&str> = text.lines().collect();
        assert!(lines[0].starts_with("loop: 2nd order, Bn 3 Hz, ζ 0.707, T 0.001 s; oscillator noise-free; C/N0 45 dB-Hz; feed-forward delay 0.0125 s (latency 0 s + half the IMU's 40 Hz sample)"), "{}", lines[0]);
        assert_eq!(lines.len(), 7, "{text}");
        assert!(
            lines[3].starts_with("   1.00   4.24  0.00  0.00         0.0500      0.0000      0.3900 →  0.0300"),
            "{}",
            lines[3]
        );
        assert!(lines[3].ends_with("  NO / yes          2.5 / 0.3"), "{}", lines[3]);
        assert!(lines[4].ends_with("none ≤ 20 / ≤ 0.1"), "{}", lines[4]);
        assert!(lines[6].starts_with("without: Δf = aᵀΓ̂ reaches the loop"));
    }
}
