//! Isolated IMU spikes: single samples that no motion of a hand-held board
//! can produce, found by their consistency with their neighbours.
//!
//! A sample k is a spike on an axis when its second difference
//! d_k = a_k − (a_{k−1} + a_{k+1})/2 exceeds both [`SPIKE_SIGMAS`] robust
//! standard deviations of all second differences on that axis (1.4826·MAD:
//! the sensor's own noise, from the log itself) and the most a hand can make
//! it — motion of amplitude A at frequency f has |d| ≤ h²·(2πf)²·A/2 for a
//! sample interval h; with [`HAND_MAX_ACCEL_MPS2`] at [`HAND_MAX_FREQ_HZ`]
//! that is 1.5 m/s² at 100 Hz — and its neighbours' second differences do not (a spike makes d_{k±1} about −d_k/2, a real fast motion
//! spreads over several samples). A spike is replaced by the mean of its
//! neighbours and counted: the loop models would otherwise turn one wild
//! sample into a transient that the fit mistakes for Γ's signature.

use gsens_io::ImuSeries;

/// Robust standard deviations of the second difference above which an
/// isolated sample is a spike. Far out in the tails of hand motion and sensor
/// noise alike (a false alarm in a Gaussian log of a million samples has a
/// probability of 10⁻²⁰), near the size of a single corrupted sample.
pub const SPIKE_SIGMAS: f64 = 12.0;

/// The largest specific-force amplitude of a board shaken by hand \[m/s²\] (3 g).
pub const HAND_MAX_ACCEL_MPS2: f64 = 30.0;
/// The highest frequency a hand shakes a board at \[Hz\].
pub const HAND_MAX_FREQ_HZ: f64 = 5.0;

/// What [`despike_imu`] replaced.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ImuSpikes {
    /// Time stamps of the replaced samples \[s\].
    pub t_s: Vec<f64>,
}

/// A copy of `imu` with its isolated spikes replaced by the mean of their
/// neighbours (module docs), and where they were.
pub fn despike_imu(imu: &ImuSeries) -> (ImuSeries, ImuSpikes) {
    let n = imu.accel_mps2.len();
    let mut out = imu.clone();
    let mut spikes = ImuSpikes::default();
    if n < 5 {
        return (out, spikes);
    }
    let a = &imu.accel_mps2;
    let mut dt: Vec<f64> = imu.t_s.windows(2).map(|w| w[1] - w[0]).collect();
    let h = *dt.select_nth_unstable_by(n / 2 - 1, f64::total_cmp).1;
    let w = std::f64::consts::TAU * HAND_MAX_FREQ_HZ;
    let hand_limit = 0.5 * h * h * w * w * HAND_MAX_ACCEL_MPS2;
    let mut spiked = vec![false; n];
    for axis in 0..3 {
        let d: Vec<f64> = (1..n - 1).map(|k| a[k][axis] - 0.5 * (a[k - 1][axis] + a[k + 1][axis])).collect();
        let mut abs: Vec<f64> = d.iter().map(|v| v.abs()).collect();
        let mid = abs.len() / 2;
        let mad = *abs.select_nth_unstable_by(mid, f64::total_cmp).1;
        // A motionless axis of a quantized IMU can have MAD 0: fall back to the mean |d|.
        let scale = if mad > 0.0 { 1.4826 * mad } else { d.iter().map(|v| v.abs()).sum::<f64>() / d.len() as f64 };
        if scale <= 0.0 {
            continue;
        }
        let limit = (SPIKE_SIGMAS * scale).max(hand_limit);
        for j in 0..d.len() {
            // Neighbours of a spike carry about half its second difference, with the other sign.
            let neighbours_follow = (j == 0 || d[j - 1].abs() < 0.75 * d[j].abs())
                && (j + 1 == d.len() || d[j + 1].abs() < 0.75 * d[j].abs());
            if d[j].abs() > limit && neighbours_follow {
                spiked[j + 1] = true;
            }
        }
    }
    for k in 1..n - 1 {
        if spiked[k] && !spiked[k - 1] && !spiked[k + 1] {
            out.accel_mps2[k] = [0, 1, 2].map(|i| 0.5 * (a[k - 1][i] + a[k + 1][i]));
            spikes.t_s.push(imu.t_s[k]);
        }
    }
    (out, spikes)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn shaken(n: usize) -> ImuSeries {
        let t_s: Vec<f64> = (0..n).map(|k| k as f64 * 0.01).collect();
        let accel_mps2 = t_s
            .iter()
            .map(|t| {
                let w = std::f64::consts::TAU * 0.9 * t;
                // A little sensor noise from a fixed sequence.
                let e = ((t * 1e4).sin() * 1e3).fract() * 0.02;
                [3.0 * w.sin() + e, 0.5 * (2.0 * w).cos() - e, 9.81 + e]
            })
            .collect();
        ImuSeries { t_s, accel_mps2 }
    }

    #[test]
    fn finds_and_replaces_isolated_spikes_only() {
        let clean = shaken(4000);
        let (same, none) = despike_imu(&clean);
        assert!(none.t_s.is_empty(), "{:?}", none.t_s);
        assert_eq!(same, clean);
        let mut bad = clean.clone();
        for (k, axis, v) in [(500, 0, 1000.0), (1500, 2, -300.0), (3000, 1, 50.0)] {
            bad.accel_mps2[k][axis] = v;
        }
        let (fixed, found) = despike_imu(&bad);
        assert_eq!(found.t_s, vec![5.0, 15.0, 30.0]);
        for k in [500, 1500, 3000] {
            for i in 0..3 {
                assert!((fixed.accel_mps2[k][i] - clean.accel_mps2[k][i]).abs() < 0.05, "{k} {i}");
            }
        }
    }
}
