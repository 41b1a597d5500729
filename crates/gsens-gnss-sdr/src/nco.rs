//! GNSS-SDR's carrier NCO over one track's records: the replica's phase at
//! the middle of each record's integration, the θ_NCO of the loop-free input
//! phase θ_in = θ_NCO + φ ([`crate::ImportedRow::input_phase_rad`]).
//!
//! How `dll_pll_veml_tracking` books its replica (0.0.17–0.0.21): the
//! samples come in blocks of one code period (T₁ = 1 ms); after each block
//! the block's update (for an integration of N blocks, only the last block's)
//! sets the command f for the next block (the record's `carrier_doppler_hz`),
//! and the replica's start phase for the next block is advanced by f·T₁ at
//! that *new* command, so every block's phase is booked at the command
//! issued at its end, while the correlator runs the block from its start
//! phase at the command in force. With P(t) the integral of the commands in
//! force [cycles], the replica during a block is P(t) + T₁·f_active (one
//! block ahead), and the dump's accumulator `acc_carrier_phase_rad`, written
//! after the update, is the negative of the next block's start phase in rad:
//!
//! ```text
//! A_k  = −acc_k/2π = P(e_k) + T₁·f_k                         e_k the end of record k's last block
//! θ_NCO,k = P(m_k) + T₁·f_p = A_k − T₁·f_k − (N/2 − 1)·T₁·f_p  m_k = e_k − N·T₁/2, f_p the command in force
//! A_k − A_{k−1} = T₁·((N − 1)·f_{k−1} + f_k)                  record k−1 holding the previous update
//! ```
//!
//! Where every update has its record (1 ms before bit synchronization, and
//! `extend_correlation_symbols` = 20) A is summed from the commands in double
//! and f_p is the previous record's command: exact. With 1 or 2 ms updates
//! after bit synchronization the dump keeps one record per 20 ms bit, and A is
//! the accumulator itself: GNSS-SDR sums it in double over every update,
//! logged or not, and rounds it to float32 only when writing, so its error is
//! the rounding alone, at most half a unit in the last place (ulp/√12 RMS,
//! ulp = 2^(⌊log₂|acc|⌋ − 23): 0.009 rad at 5·10⁵ rad, a 1.5 kHz Doppler after
//! 59 s; 0.3 rad at 1.5·10⁷ rad, 4 kHz after 10 min), the same for every record,
//! with nothing accumulated. f_p is then the cubic through the logged commands
//! at the previous update's end (N = 2 needs none: its middle is a block
//! boundary). GNSS-SDR restarts the accumulator once, at the first update
//! after bit synchronization (at minus the replica's phase modulo 2π); the
//! interval holding that restart is summed from the cubic through the logged
//! commands instead (the loop's unresolved high-frequency command content
//! leaves ~0.01 rad there: a step once per track).

use gsens_core::interpolate::lagrange;

/// The code period GNSS-SDR's blocks last \[s\] (GPS L1 C/A).
pub(crate) const BLOCK_S: f64 = 1e-3;

/// What one record says about the NCO.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct NcoRecord {
    /// The end of the record's last block \[s\] (its sample count over the
    /// sampling rate; the next block starts there).
    pub end_s: f64,
    /// Its integration length N \[blocks\].
    pub symbols: u32,
    /// Loop updates since the previous record (1: that record holds the previous update).
    pub updates: u32,
    /// GNSS-SDR's accumulator `acc_carrier_phase_rad` \[rad\].
    pub acc_rad: f64,
    /// The command for the next block, `carrier_doppler_hz` \[Hz\].
    pub command_hz: f64,
}

/// Ways of booking the NCO: the right one, and deliberately wrong ones that
/// the tests show to be far off.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum NcoBookkeeping {
    /// As derived in the module documentation.
    #[default]
    Right,
    /// The replica's phase half a record interval before the φ it is added to.
    HalfEpochShift,
    /// The accumulator taken as the replica's phase (and the commands negated):
    /// θ_NCO with the wrong sign.
    WrongSign,
    /// Each integration booked at its own record's command instead of the
    /// previous record's (the command in force).
    ThisRecordsCommand,
    /// The NCO's phase and φ each brought to the record's instant from their
    /// own stamps, then added: the accumulator's phase (the replica's at the
    /// next block's start) interpolated from the records' ends to their
    /// integrations' middles, with no booking of the block in force.
    CombinedAfterResampling,
}

/// The replica's phase at the middle of each record's integration \[cycles\]
/// (module documentation), up to one constant per track; `reset` is the
/// record whose interval holds the accumulator's restart, if any.
pub(crate) fn replica_mid_cycles(recs: &[NcoRecord], reset: Option<usize>, how: NcoBookkeeping) -> Vec<f64> {
    let sign = if how == NcoBookkeeping::WrongSign { -1.0 } else { 1.0 };
    let command = |k: usize| sign * recs[k].command_hz;
    // The command in force over record k's integration.
    let in_force = |k: usize| match how {
        NcoBookkeeping::ThisRecordsCommand => command(k),
        _ if k > 0 && recs[k].updates == 1 => command(k - 1),
        _ => commands_at(recs, k, recs[k].end_s - f64::from(recs[k].symbols) * BLOCK_S, sign),
    };
    let mut a = vec![0.0; recs.len()];
    for k in 0..recs.len() {
        a[k] = if k == 0 {
            -sign * recs[0].acc_rad / core::f64::consts::TAU
        } else if recs[k].updates == 1 {
            let dt = recs[k].end_s - recs[k - 1].end_s;
            a[k - 1] + in_force(k) * (dt - BLOCK_S) + command(k) * BLOCK_S
        } else if reset == Some(k) {
            a[k - 1] + commands_integral(recs, k, sign)
        } else {
            a[k - 1] - sign * (recs[k].acc_rad - recs[k - 1].acc_rad) / core::f64::consts::TAU
        };
    }
    let mid: Vec<f64> = (0..recs.len())
        .map(|k| {
            let n = f64::from(recs[k].symbols);
            a[k] - BLOCK_S * command(k) - (0.5 * n - 1.0) * BLOCK_S * in_force(k)
        })
        .collect();
    match how {
        NcoBookkeeping::CombinedAfterResampling => (0..mid.len())
            .map(|k| {
                let (lo, hi) = (k.saturating_sub(1), (k + 3).min(recs.len()));
                let t: Vec<f64> = recs[lo..hi].iter().map(|r| r.end_s).collect();
                let m_s = recs[k].end_s - 0.5 * f64::from(recs[k].symbols) * BLOCK_S;
                lagrange(&t, &a[lo..hi], m_s)
            })
            .collect(),
        NcoBookkeeping::HalfEpochShift => {
            (0..mid.len()).map(|k| if k == 0 { mid[0] } else { 0.5 * (mid[k] + mid[k - 1]) }).collect()
        }
        _ => mid,
    }
}

/// The logged commands' cubic (through records k−2…k+1 where they exist) at `t_s` \[Hz\].
fn commands_at(recs: &[NcoRecord], k: usize, t_s: f64, sign: f64) -> f64 {
    let (lo, hi) = (k.saturating_sub(2), (k + 2).min(recs.len()));
    let (mut t, mut f) = ([0.0; 4], [0.0; 4]);
    for (i, r) in recs[lo..hi].iter().enumerate() {
        (t[i], f[i]) = (r.end_s, sign * r.command_hz);
    }
    lagrange(&t[..hi - lo], &f[..hi - lo], t_s)
}

/// A_k − A_{k−1} over an interval whose updates are not logged, from the
/// logged commands: Σ over its updates of N·T₁ times the command in force,
/// plus T₁·(f_k − f_{k−1}) (each block booked at the command issued at its
/// end telescopes to that), the sum by the midpoint rule on the commands' cubic
/// (Simpson's rule on it: exact for a cubic).
fn commands_integral(recs: &[NcoRecord], k: usize, sign: f64) -> f64 {
    let h = f64::from(recs[k].symbols) * BLOCK_S;
    let (t0, t1) = (recs[k - 1].end_s - 0.5 * h, recs[k].end_s - 0.5 * h);
    let f = |t: f64| commands_at(recs, k, t, sign);
    let tm = 0.5 * (t0 + t1);
    (t1 - t0) * (f(t0) + 4.0 * f(tm) + f(t1)) / 6.0 + BLOCK_S * sign * (recs[k].command_hz - recs[k - 1].command_hz)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// GNSS-SDR's booking played block by block: the commands (a Doppler
    /// ramp, a 1 Hz swing and a loop's update noise) issued every N blocks,
    /// each block's start phase advanced at the command issued at its end,
    /// the float32 accumulator logged once per 20 ms; the replica's mean
    /// over each logged integration is what φ is measured against.
    fn played(n: u32, blocks: usize) -> (Vec<NcoRecord>, Vec<f64>) {
        let (mut start, mut active, mut acc) = (0.0, 1500.0, 0.0);
        let (mut recs, mut truth, mut integration) = (Vec::new(), Vec::new(), Vec::new());
        let mut noise = 0x2545_f491_4f6c_dd1d_u64;
        for b in 0..blocks {
            // The replica over block b, from its start phase at the command in force.
            integration.push(start + 0.5 * active * BLOCK_S);
            let end_s = (b + 1) as f64 * BLOCK_S;
            if (b + 1) % n as usize == 0 {
                noise ^= noise << 13;
                noise ^= noise >> 7;
                noise ^= noise << 17;
                let jitter = (noise >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
                active = 1500.0 + 0.8 * end_s + 0.5 * (core::f64::consts::TAU * end_s).sin() + 0.6 * jitter;
                let logged = (b + 1) % 20 == 0;
                if logged {
                    truth.push(integration.iter().sum::<f64>() / integration.len() as f64);
                }
                integration.clear();
                // The next block's start phase, booked at the new command.
                start += active * BLOCK_S;
                acc -= core::f64::consts::TAU * active * BLOCK_S;
                if logged {
                    let updates = if recs.is_empty() { 1 } else { 20 / n };
                    recs.push(NcoRecord {
                        end_s,
                        symbols: n,
                        updates,
                        acc_rad: f64::from(acc as f32),
                        command_hz: active,
                    });
                }
            } else {
                start += active * BLOCK_S;
                acc -= core::f64::consts::TAU * active * BLOCK_S;
            }
        }
        (recs, truth)
    }

    /// The largest deviation of `got` from `want` once their mean difference
    /// (the constant per track) is taken out \[cycles\].
    fn deviation(got: &[f64], want: &[f64]) -> f64 {
        let mean = got.iter().zip(want).map(|(g, w)| g - w).sum::<f64>() / got.len() as f64;
        got.iter().zip(want).map(|(g, w)| (g - w - mean).abs()).fold(0.0, f64::max)
    }

    #[test]
    fn the_booking_gives_the_replicas_phase_over_each_logged_integration() {
        // 20 s at ~1.5 kHz: |acc| < 2^18 rad, ulp 2^-5 rad, rounding ≤ 0.0025 cycles.
        let half_ulp_cycles = 0.5 * 2f64.powi(-5) / core::f64::consts::TAU;
        for (n, bound) in [(20, 1e-9), (2, half_ulp_cycles * 2.0), (1, half_ulp_cycles * 2.0 + 5e-4)] {
            let (recs, truth) = played(n, 20_000);
            // (The first record has no command in force on record: left out.)
            let got = &replica_mid_cycles(&recs, None, NcoBookkeeping::Right)[1..];
            let (recs, truth) = (&recs[1..], &truth[1..]);
            let d = deviation(got, truth);
            assert!(d < bound, "N = {n}: {d} cycles");
            // Booked at the command in force with no lead, the replica is off by T₁·f's swing.
            if n == 20 {
                let plain: Vec<f64> = got.iter().zip(recs).map(|(g, r)| g - BLOCK_S * r.command_hz).collect();
                assert!(deviation(&plain, truth) > 1e-4, "N = {n}");
            }
        }
    }

    /// The `.mat` and the `.dat` of one GNSS-SDR run (its 1 ms records before
    /// bit synchronization) give the same replica phase and θ_in.
    #[test]
    fn the_mat_and_the_dat_give_the_same_input_phase() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/mat");
        let fs_hz = crate::ImportSettings::from_conf(Some(&dir.join("gnss-sdr.conf")), None).unwrap().fs_hz;
        let input_phase = |file: &str| -> Vec<f64> {
            let dump = crate::read_dump(dir.join(file), None).unwrap();
            let recs: Vec<NcoRecord> = dump
                .records
                .iter()
                .map(|r| NcoRecord {
                    end_s: r.prn_start_sample_count as f64 / fs_hz,
                    symbols: 1,
                    updates: 1,
                    acc_rad: r.acc_carrier_phase_rad,
                    command_hz: r.carrier_doppler_hz,
                })
                .collect();
            let replica = replica_mid_cycles(&recs, None, NcoBookkeeping::Right);
            replica.iter().zip(&dump.records).map(|(c, r)| core::f64::consts::TAU * (c + r.carr_error_cycles)).collect()
        };
        let (mat, dat) = (input_phase("trk_ch_0.mat"), input_phase("trk_ch_0.dat"));
        assert!(mat.len() > 300 && mat.len() == dat.len());
        for (k, (m, d)) in mat.iter().zip(&dat).enumerate() {
            assert!((m - d).abs() <= 1e-12 * d.abs().max(1.0), "record {k}: {m} vs {d}");
        }
    }
}
