//! The one plain instruction for the person holding the board.

use gsens_core::LoopModel;

const AXES: [&str; 3] = ["x", "y", "z"];

/// Where the receiver's loop responds to shaking: its peak and half-power
/// band (`gsens_core::LoopModel::peak`, `half_power_band_hz`), the same
/// numbers `gsens response` prints.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LoopBand {
    /// Frequency of the loop's peak |L| \[Hz\]: the shaking to aim at.
    pub peak_hz: f64,
    /// Where |L| is above peak/√2 \[Hz\].
    pub band_hz: [f64; 2],
}

impl LoopBand {
    /// The band of `receiver_loop`.
    pub fn of(receiver_loop: &LoopModel) -> Result<Self, gsens_core::LoopError> {
        Ok(LoopBand { peak_hz: receiver_loop.peak()?.f_hz, band_hz: receiver_loop.half_power_band_hz()? })
    }

    /// The shaking period to aim at, 1/f_peak \[s\].
    pub fn period_s(&self) -> f64 {
        1.0 / self.peak_hz
    }

    /// Which of the two-rate protocol's rates shaking at `f_hz` counts as (0
    /// slow, 1 fast): the slow one up to the rates' geometric mean,
    /// √(0.7·1.6) = 1.06 times the peak, so that shaking at the peak itself
    /// counts as the slow rate rather than as either by chance.
    pub fn rate_of(&self, f_hz: f64) -> usize {
        let [slow, fast] = gsens_core::TWO_RATE_FACTORS;
        usize::from(f_hz > self.peak_hz * (slow * fast).sqrt())
    }

    /// The two-rate protocol's periods, slow then fast
    /// ([`gsens_core::LoopPeak::two_rate_periods_s`]) \[s\].
    pub fn two_rate_periods_s(&self) -> [f64; 2] {
        gsens_core::LoopPeak { f_hz: self.peak_hz, rad_per_hz: f64::NAN }.two_rate_periods_s()
    }
}

/// Which rates the person is guided to shake at.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Protocol {
    /// Each axis at the loop's peak: the loop is known exactly, so all the
    /// shaking goes where it is most sensitive.
    OneRate,
    /// Each axis half the time below and half above the loop's peak
    /// ([`gsens_core::TWO_RATE_FACTORS`]): the loop is not known exactly, and
    /// at one rate an error of its natural frequency and the IMU's latency
    /// look alike.
    TwoRates,
}

impl Protocol {
    /// Why this protocol, in a sentence for the person shaking.
    pub fn why(&self) -> &'static str {
        match self {
            Protocol::OneRate => "one rate per axis, at the loop's peak: the loop is known exactly",
            Protocol::TwoRates => {
                "two rates per axis, slower and faster than the loop's peak: the loop is not known exactly, and at one \
                 rate its error and the IMU's latency look alike"
            }
        }
    }
}

/// What to do next.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Instruction {
    /// Nothing received yet.
    Waiting,
    /// Hold the board still: the at-rest level and the loop's settling are measured.
    Rest {
        /// Seconds of rest still wanted.
        more_s: f64,
    },
    /// The phase error nears the discriminator's linear range: shake more gently.
    Gentler {
        /// The measured peak phase error \[rad\].
        peak_rad: f64,
        /// The discriminator's linear range \[rad\].
        range_rad: f64,
    },
    /// Several axes move together: shake along one.
    OneAxis {
        /// The axis to shake (0 = x).
        axis: usize,
    },
    /// Shake this axis, at about this period.
    Shake {
        /// The axis (0 = x).
        axis: usize,
        /// The period to aim at \[s\].
        period_s: f64,
        /// Under the two-rate protocol: which of the two (0 slow, 1 fast).
        rate: Option<usize>,
        /// Seconds of shaking still needed for the target σ (None: not known yet).
        more_s: Option<f64>,
    },
    /// Shaking the right axis outside the loop's band: change the pace.
    Pace {
        /// The axis (0 = x).
        axis: usize,
        /// The period to aim at \[s\].
        period_s: f64,
        /// The period shaken now \[s\].
        now_s: f64,
    },
    /// This axis has enough: move on to the next.
    Next {
        /// The axis that is done.
        done: usize,
        /// The axis to shake now.
        axis: usize,
        /// The period to aim at \[s\].
        period_s: f64,
    },
    /// Every axis meets the target σ.
    Done,
}

impl Instruction {
    /// The axis the instruction asks to shake, if any.
    pub fn axis(&self) -> Option<usize> {
        match *self {
            Instruction::OneAxis { axis }
            | Instruction::Shake { axis, .. }
            | Instruction::Pace { axis, .. }
            | Instruction::Next { axis, .. } => Some(axis),
            _ => None,
        }
    }
}

impl core::fmt::Display for Instruction {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            Instruction::Waiting => write!(f, "waiting for data"),
            Instruction::Rest { more_s } => {
                write!(f, "rest: measuring the at-rest level, {:.0} s more", more_s.ceil())
            }
            Instruction::Gentler { peak_rad, range_rad } => write!(
                f,
                "gentler: the phase error ({peak_rad:.2} rad) nears the discriminator's limit ({range_rad:.2} rad)"
            ),
            Instruction::OneAxis { axis } => write!(f, "shake along {} only: several axes move", AXES[axis]),
            Instruction::Shake { axis, period_s, rate, more_s } => {
                write!(f, "shake {}, about {period_s:.1} s per cycle", AXES[axis])?;
                if let Some(r) = rate {
                    write!(f, " (the {} of two rates)", ["slower", "faster"][r.min(1)])?;
                }
                match more_s {
                    Some(s) => write!(f, ", {}", more_text(s)),
                    None => Ok(()),
                }
            }
            Instruction::Pace { axis, period_s, now_s } => {
                let how = if now_s > period_s { "faster" } else { "slower" };
                write!(f, "shake {} {how}: about {period_s:.1} s per cycle (now {now_s:.1} s)", AXES[axis])
            }
            Instruction::Next { done, axis, period_s } => {
                write!(f, "{} has enough: shake {}, about {period_s:.1} s per cycle", AXES[done], AXES[axis])
            }
            Instruction::Done => write!(f, "done: every axis meets the target σ"),
        }
    }
}

/// "N s more", or "over an hour more" past an hour (a target far out of reach).
pub(crate) fn more_text(more_s: f64) -> String {
    if more_s > 3600.0 { "over an hour more".to_string() } else { format!("{:.0} s more", more_s.ceil()) }
}

/// What the instruction is decided from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Situation {
    /// Seconds of data received (IMU and tracking both).
    pub data_s: f64,
    /// Seconds of rest still wanted at the start (0 once measured).
    pub rest_more_s: f64,
    /// The axis shaken now, and its frequency \[Hz\].
    pub shaken: Option<(usize, Option<f64>)>,
    /// Several axes move together.
    pub several_axes: bool,
    /// Largest |φ| of the channel average over the motion window \[rad\].
    pub peak_phase_rad: f64,
    /// The discriminator's linear range \[rad\].
    pub range_rad: f64,
    /// Per axis: whether it meets the target σ, and the seconds of shaking still needed.
    pub axes: [(bool, Option<f64>); 3],
    /// The protocol guided.
    pub protocol: Protocol,
    /// Per axis, the seconds shaken at the slow and at the fast rate ([`LoopBand::rate_of`]).
    pub shaken_by_rate_s: [[f64; 2]; 3],
}

/// Under the two-rate protocol, seconds by which the rate shaken may lead the
/// other before the person is asked to change pace.
pub(crate) const TWO_RATE_LEAD_S: f64 = 5.0;

/// The fraction of the discriminator's linear range at which "gentler" is
/// said: the phase error's peaks then leave less than the 3σ of a Costas
/// loop's rule of thumb for its noise.
pub const GENTLER_FRACTION: f64 = 0.7;

/// The instruction for `s` with the loop's `band`.
pub fn instruct(s: &Situation, band: &LoopBand) -> Instruction {
    if s.data_s <= 0.0 {
        return Instruction::Waiting;
    }
    // The period and rate to ask of `axis`: the peak, or under two rates the
    // one shaken less so far.
    let aim = |axis: usize| -> (f64, Option<usize>) {
        match s.protocol {
            Protocol::OneRate => (band.period_s(), None),
            Protocol::TwoRates => {
                let [slow, fast] = s.shaken_by_rate_s[axis];
                let r = usize::from(fast < slow);
                (band.two_rate_periods_s()[r], Some(r))
            }
        }
    };
    let next = (0..3).find(|&i| !s.axes[i].0);
    let Some(next) = next else { return Instruction::Done };
    if s.shaken.is_none() && s.rest_more_s > 0.0 {
        return Instruction::Rest { more_s: s.rest_more_s };
    }
    if s.peak_phase_rad > GENTLER_FRACTION * s.range_rad {
        return Instruction::Gentler { peak_rad: s.peak_phase_rad, range_rad: s.range_rad };
    }
    if s.several_axes {
        return Instruction::OneAxis { axis: next };
    }
    match s.shaken {
        Some((axis, _)) if s.axes[axis].0 => Instruction::Next { done: axis, axis: next, period_s: aim(next).0 },
        Some((axis, Some(f_hz))) if f_hz < band.band_hz[0] || f_hz > band.band_hz[1] => {
            Instruction::Pace { axis, period_s: aim(axis).0, now_s: 1.0 / f_hz }
        }
        // Two rates: shaking on the side of the peak that already leads.
        Some((axis, Some(f_hz)))
            if aim(axis).1.is_some_and(|r| {
                let now = band.rate_of(f_hz);
                let by_rate = s.shaken_by_rate_s[axis];
                now != r && by_rate[now] - by_rate[r] > TWO_RATE_LEAD_S
            }) =>
        {
            Instruction::Pace { axis, period_s: aim(axis).0, now_s: 1.0 / f_hz }
        }
        Some((axis, _)) => {
            let (period_s, rate) = aim(axis);
            Instruction::Shake { axis, period_s, rate, more_s: s.axes[axis].1 }
        }
        None => {
            let (period_s, rate) = aim(next);
            Instruction::Shake { axis: next, period_s, rate, more_s: s.axes[next].1 }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn band() -> LoopBand {
        LoopBand::of(&LoopModel::kaplan(gsens_core::LoopSpec::PAPER, None)).unwrap()
    }

    fn situation() -> Situation {
        Situation {
            data_s: 20.0,
            rest_more_s: 0.0,
            shaken: None,
            several_axes: false,
            peak_phase_rad: 0.2,
            range_rad: core::f64::consts::FRAC_PI_4,
            axes: [(false, None); 3],
            protocol: Protocol::OneRate,
            shaken_by_rate_s: [[0.0; 2]; 3],
        }
    }

    #[test]
    fn the_paper_loop_asks_for_about_1_1_s_per_cycle() {
        let b = band();
        // Bn = 3 Hz, ζ = 1/√2: ωn/2π = 0.90 Hz.
        assert!((b.period_s() - 1.11).abs() < 0.02, "{b:?}");
        assert!(b.band_hz[0] < b.peak_hz && b.peak_hz < b.band_hz[1]);
        let s = situation();
        assert_eq!(instruct(&s, &b).to_string(), "shake x, about 1.1 s per cycle");
    }

    #[test]
    fn the_sequence_of_instructions() {
        let b = band();
        let mut s = situation();
        assert_eq!(instruct(&Situation { data_s: 0.0, ..s }, &b), Instruction::Waiting);
        assert!(matches!(instruct(&Situation { rest_more_s: 3.0, ..s }, &b), Instruction::Rest { .. }));
        s.shaken = Some((0, Some(0.3)));
        assert!(instruct(&s, &b).to_string().starts_with("shake x faster"), "{}", instruct(&s, &b));
        s.shaken = Some((0, Some(b.peak_hz)));
        s.axes[0] = (false, Some(14.2));
        assert_eq!(instruct(&s, &b).to_string(), "shake x, about 1.1 s per cycle, 15 s more");
        s.peak_phase_rad = 0.6;
        assert!(instruct(&s, &b).to_string().starts_with("gentler"));
        s.peak_phase_rad = 0.2;
        s.axes[0] = (true, Some(0.0));
        assert_eq!(instruct(&s, &b).to_string(), "x has enough: shake y, about 1.1 s per cycle");
        s.shaken = None;
        s.axes[1] = (true, Some(0.0));
        assert_eq!(instruct(&s, &b).axis(), Some(2));
        s.axes[2] = (true, Some(0.0));
        assert_eq!(instruct(&s, &b), Instruction::Done);
    }

    #[test]
    fn two_rates_alternate_below_and_above_the_peak() {
        let b = band();
        // 0.7 and 1.6 times the peak's 0.90 Hz: 1.59 s and 0.69 s.
        let [slow, fast] = b.two_rate_periods_s();
        assert!((slow - 1.0 / (0.7 * b.peak_hz)).abs() < 1e-12 && (fast - 1.0 / (1.6 * b.peak_hz)).abs() < 1e-12);
        let mut s = Situation { protocol: Protocol::TwoRates, ..situation() };
        assert_eq!(instruct(&s, &b).to_string(), "shake x, about 1.6 s per cycle (the slower of two rates)");
        // Shaking slowly, the slow rate leads: the fast one is asked for next.
        s.shaken = Some((0, Some(0.7 * b.peak_hz)));
        s.shaken_by_rate_s[0] = [8.0, 0.0];
        s.axes[0] = (false, Some(12.0));
        assert_eq!(instruct(&s, &b).to_string(), "shake x faster: about 0.7 s per cycle (now 1.6 s)");
        s.shaken_by_rate_s[0] = [4.0, 0.0];
        assert_eq!(instruct(&s, &b).to_string(), "shake x, about 0.7 s per cycle (the faster of two rates), 12 s more");
        // The next axis starts at the slow rate again.
        s.axes[0] = (true, Some(0.0));
        assert_eq!(instruct(&s, &b).to_string(), "x has enough: shake y, about 1.6 s per cycle");
        assert!(Protocol::TwoRates.why().contains("two rates"));
        // Shaking at the peak counts as the slow rate, not as either by chance.
        assert_eq!((b.rate_of(b.peak_hz * 0.99), b.rate_of(b.peak_hz * 1.01)), (0, 0));
        assert_eq!((b.rate_of(1.0 / slow), b.rate_of(1.0 / fast)), (0, 1));
    }
}
