//! The shaking the IMU sees over the last seconds: which axis, how hard, how fast.

use std::collections::VecDeque;

/// The shaking over the window.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Shaking {
    /// RMS of each axis's specific force about its mean over the window \[m/s²\]
    /// (gravity and bias removed with the mean).
    pub rms_mps2: [f64; 3],
    /// The axis shaken (0 = x, 1 = y, 2 = z): the one whose RMS exceeds the
    /// threshold and twice each other axis's RMS. `None` at rest.
    pub axis: Option<usize>,
    /// Two or more axes above the threshold with none dominating.
    pub several_axes: bool,
    /// The shaking frequency of `axis` from its zero crossings \[Hz\].
    pub frequency_hz: Option<f64>,
    /// The window's length actually covered \[s\].
    pub window_s: f64,
}

/// The last `window_s` seconds of IMU samples.
#[derive(Debug, Clone)]
pub struct MotionWindow {
    window_s: f64,
    threshold_mps2: f64,
    samples: VecDeque<(f64, [f64; 3])>,
}

impl MotionWindow {
    /// A window of `window_s` seconds in which an axis counts as shaken when
    /// its RMS exceeds `threshold_mps2`.
    pub fn new(window_s: f64, threshold_mps2: f64) -> Self {
        MotionWindow { window_s, threshold_mps2, samples: VecDeque::with_capacity(1024) }
    }

    /// Adds a sample (time stamps increasing).
    pub fn push(&mut self, t_s: f64, accel_mps2: [f64; 3]) {
        self.samples.push_back((t_s, accel_mps2));
        while let Some(&(t0, _)) = self.samples.front() {
            if t_s - t0 > self.window_s {
                self.samples.pop_front();
            } else {
                break;
            }
        }
    }

    /// The shaking over the window (at rest while it holds fewer than 4 samples).
    pub fn shaking(&self) -> Shaking {
        let n = self.samples.len();
        if n < 4 {
            return Shaking::default();
        }
        let window_s = self.samples[n - 1].0 - self.samples[0].0;
        let mut mean = [0.0; 3];
        for (_, a) in &self.samples {
            for i in 0..3 {
                mean[i] += a[i] / n as f64;
            }
        }
        let mut rms = [0.0; 3];
        for (_, a) in &self.samples {
            for i in 0..3 {
                rms[i] += (a[i] - mean[i]).powi(2) / n as f64;
            }
        }
        let rms_mps2 = rms.map(f64::sqrt);
        let above: Vec<usize> = (0..3).filter(|&i| rms_mps2[i] > self.threshold_mps2).collect();
        let dominant = above.iter().copied().find(|&i| (0..3).all(|j| j == i || rms_mps2[i] > 2.0 * rms_mps2[j]));
        let frequency_hz = dominant.and_then(|i| self.frequency_hz(i, mean[i], rms_mps2[i]));
        Shaking {
            rms_mps2,
            axis: dominant,
            several_axes: dominant.is_none() && above.len() >= 2,
            frequency_hz,
            window_s,
        }
    }

    /// Frequency of axis `i` from its crossings of the mean, with a
    /// hysteresis of half the RMS so that noise does not count: crossings
    /// over the time between the first and the last, halved.
    fn frequency_hz(&self, i: usize, mean: f64, rms: f64) -> Option<f64> {
        let h = 0.5 * rms;
        let mut state = 0i8;
        let (mut first, mut last, mut crossings) = (None, 0.0, 0u32);
        for &(t, a) in &self.samples {
            let x = a[i] - mean;
            let s = if x > h {
                1
            } else if x < -h {
                -1
            } else {
                continue;
            };
            if state != 0 && s != state {
                crossings += 1;
                first.get_or_insert(t);
                last = t;
            }
            state = s;
        }
        let first = first?;
        (crossings >= 3 && last > first).then(|| 0.5 * (crossings - 1) as f64 / (last - first))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::f64::consts::TAU;

    #[test]
    fn finds_the_axis_and_the_frequency() {
        let mut w = MotionWindow::new(4.0, 0.3);
        for k in 0..400 {
            let t = k as f64 * 0.025;
            let a = 3.0 * (TAU * t / 1.1).sin();
            w.push(t, [0.02 * (k % 3) as f64, a, 9.81]);
        }
        let s = w.shaking();
        assert_eq!(s.axis, Some(1));
        assert!((s.frequency_hz.unwrap() - 1.0 / 1.1).abs() < 0.02, "{s:?}");
        assert!((s.rms_mps2[1] - 3.0 / 2f64.sqrt()).abs() < 0.1);
        // At rest: no axis.
        let mut w = MotionWindow::new(4.0, 0.3);
        for k in 0..200 {
            w.push(k as f64 * 0.025, [0.01, -0.01 * (k % 2) as f64, 9.81]);
        }
        assert_eq!(w.shaking().axis, None);
        assert!(!w.shaking().several_axes);
        // Two axes alike: several, none dominating.
        let mut w = MotionWindow::new(4.0, 0.3);
        for k in 0..200 {
            let a = 2.0 * (TAU * k as f64 * 0.025).sin();
            w.push(k as f64 * 0.025, [a, 0.8 * a, 9.81]);
        }
        assert!(w.shaking().several_axes);
    }
}
