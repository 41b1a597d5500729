//! The loop-free estimate's input from GNSS-SDR dumps: each track's input
//! phase θ_in = θ_NCO + φ at its records' own instants (the middle of each
//! integration, [`crate::ImportedRow::input_phase_rad`]) brought to the common
//! grid t = j·T the tracking rows are resampled to.

use gsens_calib::{InputPhases, TrackInputPhase};
use gsens_core::interpolate::lagrange;

use crate::import::{Imported, ImportedRow};

/// Each track's θ_in on the grid t = j·`interval_s` (the grid of
/// [`crate::resample`]): between two consecutive records (a record interval
/// apart) the cubic through them and their neighbours at their own instants
/// (the parabola through three where a neighbour is missing). θ_in is the satellite's
/// carrier phase (its Doppler, smooth) less 2π∫Δf: over 20 ms a cubic leaves
/// of a 1 Hz shaking signal a part in 10⁵. A grid point next to a record whose
/// |φ| exceeds `max_abs_phase_rad` (near the discriminator's wrap, where θ_in
/// may be a half cycle off) has none.
pub fn gnss_sdr_input_phases(imported: &Imported, interval_s: f64, max_abs_phase_rad: f64) -> InputPhases {
    let rows = &imported.rows;
    let n_tracks = rows.iter().map(|r| r.track + 1).max().unwrap_or(0);
    let mut by_track: Vec<Vec<&ImportedRow>> = vec![Vec::new(); n_tracks];
    for r in rows.iter().filter(|r| r.input_phase_rad.is_some()) {
        by_track[r.track].push(r);
    }
    let consecutive = |a: &ImportedRow, b: &ImportedRow| {
        let d = b.t_s - a.t_s;
        d > 0.75 * interval_s && d < 1.25 * interval_s
    };
    // Per track: the grid points (by index j) and θ_in there.
    let on_grid: Vec<Vec<(i64, f64)>> = by_track
        .iter()
        .map(|rows| {
            let mut out = Vec::new();
            for k in 0..rows.len().saturating_sub(1) {
                let (a, b) = (rows[k], rows[k + 1]);
                if !consecutive(a, b) {
                    continue;
                }
                let prev = (k > 0 && consecutive(rows[k - 1], a)).then(|| rows[k - 1]);
                let next = (k + 2 < rows.len() && consecutive(b, rows[k + 2])).then(|| rows[k + 2]);
                let (mut buf, mut n) = ([a; 4], 0);
                for r in [prev, Some(a), Some(b), next].into_iter().flatten() {
                    (buf[n], n) = (r, n + 1);
                }
                let nodes = &buf[..n];
                if nodes.iter().any(|r| r.phase_err_rad.abs() > max_abs_phase_rad) {
                    continue;
                }
                for j in (a.t_s / interval_s).ceil() as i64..(b.t_s / interval_s).ceil() as i64 {
                    out.push((j, interpolate(nodes, j as f64 * interval_s)));
                }
            }
            out
        })
        .collect();
    let mut grid: Vec<i64> = on_grid.iter().flatten().map(|(j, _)| *j).collect();
    grid.sort_unstable();
    grid.dedup();
    let tracks = on_grid
        .iter()
        .zip(&by_track)
        .filter(|(points, _)| !points.is_empty())
        .map(|(points, rows)| {
            let mut input_phase_rad = vec![None; grid.len()];
            for (j, theta) in points {
                if let Ok(e) = grid.binary_search(j) {
                    input_phase_rad[e] = Some(*theta);
                }
            }
            let mean_cn0_dbhz = rows.iter().map(|r| r.cn0_dbhz).sum::<f64>() / rows.len() as f64;
            TrackInputPhase { input_phase_rad, scale_to_l1: 1.0, mean_cn0_dbhz }
        })
        .collect();
    InputPhases { epoch_t_s: grid.iter().map(|&j| j as f64 * interval_s).collect(), tracks }
}

/// The polynomial through the rows' θ_in at their instants, at `t_s`
/// ([`lagrange`]: θ_in holds the Doppler's ramp, ~10⁶ rad after minutes).
fn interpolate(nodes: &[&ImportedRow], t_s: f64) -> f64 {
    // At most four nodes: on the stack, as this runs for every grid point.
    let (mut instants, mut values) = ([0.0; 4], [0.0; 4]);
    for (k, r) in nodes.iter().enumerate() {
        (instants[k], values[k]) = (r.t_s, r.input_phase_rad.unwrap_or(0.0));
    }
    lagrange(&instants[..nodes.len()], &values[..nodes.len()], t_s)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(t_s: f64, track: usize, theta: f64, phi: f64) -> ImportedRow {
        ImportedRow {
            t_s,
            channel: track as u32,
            prn: 3 + track as u32,
            cn0_dbhz: 44.0,
            phase_err_rad: phi,
            lock_test: 1.0,
            symbols: 20,
            track,
            input_phase_rad: Some(theta),
        }
    }

    /// A cubic θ_in sampled at each track's own instants comes out exact on
    /// the grid (to the parabola's 10⁻⁶ rad at a track's ends); a record
    /// beyond the phase limit takes its neighbourhood out.
    #[test]
    fn a_cubic_input_phase_is_exact_on_the_grid() {
        let theta = |t: f64| 2e5 + 1.2e4 * t - 3.0 * t * t + 0.4 * t * t * t;
        let mut rows = Vec::new();
        for (track, offset) in [(0usize, 0.0037), (1, 0.0151)] {
            for k in 0..50 {
                let t = 1.0 + offset + 0.02 * k as f64;
                let phi = if track == 1 && k == 30 { 1.0 } else { 0.01 };
                rows.push(row(t, track, theta(t), phi));
            }
        }
        let imported = Imported { rows, tracks: Vec::new(), interval_s: 0.02 };
        let phases = gnss_sdr_input_phases(&imported, 0.02, core::f64::consts::FRAC_PI_4);
        assert_eq!(phases.tracks.len(), 2);
        let mut missing = 0;
        for (e, t) in phases.epoch_t_s.iter().enumerate() {
            for tr in &phases.tracks {
                match tr.input_phase_rad[e] {
                    Some(v) => assert!((v - theta(*t)).abs() < 1e-5, "{t}: {v} vs {}", theta(*t)),
                    None => missing += 1,
                }
            }
        }
        // Track 1's record 30 spoils the grid points between records 28 and 32; the tracks' ends differ by one.
        assert!((4..=7).contains(&missing), "{missing}");
    }
}
