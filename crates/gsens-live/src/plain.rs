//! The plain screen: lines of text instead of the terminal screen.

use std::io::Write;

use crate::guidance::{Instruction, more_text};
use crate::session::{LiveSession, LiveView};

/// A line when the instruction changes, one per batch estimate (with its
/// verdict and the codes that decide it), each warning with its message the
/// first time a batch raises it. The batch estimate runs in line, so the
/// same input gives the same lines however fast it arrives.
#[derive(Default)]
pub(crate) struct Plain {
    last: Option<(std::mem::Discriminant<Instruction>, Option<usize>)>,
    /// The warning codes already printed with their message.
    warned: Vec<gsens_calib::WarningCode>,
}

impl Plain {
    /// The batch estimate when due (in line), then the instruction.
    pub(crate) fn step(&mut self, session: &mut LiveSession, out: &mut dyn Write) -> std::io::Result<()> {
        if let Some(job) = session.batch_due() {
            session.apply(job.run());
            let view = session.view();
            batch(&view, out)?;
            self.warnings(&view, out)?;
        }
        self.instruction(&session.view(), out)
    }

    fn instruction(&mut self, v: &LiveView, out: &mut dyn Write) -> std::io::Result<()> {
        let key = (std::mem::discriminant(&v.instruction), v.instruction.axis());
        if self.last != Some(key) {
            self.last = Some(key);
            writeln!(out, "[{:7.2} s] {}", v.data_t_s.max(0.0), v.instruction)?;
        }
        Ok(())
    }

    fn warnings(&mut self, v: &LiveView, out: &mut dyn Write) -> std::io::Result<()> {
        for w in v.batch.iter().flat_map(|b| &b.warnings) {
            if !self.warned.contains(&w.code) {
                self.warned.push(w.code);
                writeln!(out, "warning [{}]: {}", w.code, w.message)?;
            }
        }
        Ok(())
    }
}

/// "loop-free: " before the verdict of an estimate from the input phase (the
/// line's estimate is otherwise the one through the loop model).
fn loop_free_label(measurement: gsens_calib::Measurement) -> &'static str {
    if measurement == gsens_calib::Measurement::InputPhase { "loop-free: " } else { "" }
}

/// The line of a batch estimate: Γ̂ ± σ per axis, the channels tracking, the verdict.
fn batch(v: &LiveView, out: &mut dyn Write) -> std::io::Result<()> {
    let axes: Vec<String> = ["x", "y", "z"]
        .iter()
        .zip(&v.axes)
        .map(|(name, a)| match (a.gamma_hz_per_mps2, a.sigma_hz_per_mps2) {
            (Some(g), Some(s)) if a.observable => {
                let state = if a.meets_target { "met".to_string() } else { a.more_s.map_or(String::new(), more_text) };
                format!("{name} {g:+.5} ± {s:.5} {state}")
            }
            _ => format!("{name} unobservable"),
        })
        .collect();
    let trust = match (&v.batch, &v.batch_error) {
        (Some(b), _) if b.trustworthy => format!("{}trustworthy", loop_free_label(b.measurement)),
        (Some(b), _) => format!("{}NOT TRUSTWORTHY ({})", loop_free_label(b.measurement), b.untrusted_codes.join(", ")),
        (None, Some(e)) => format!("no estimate: {e}"),
        (None, None) => String::new(),
    };
    let receiver = match &v.ubx {
        Some(u) => u.summary(),
        None => format!("{} channels", v.channels.iter().filter(|c| c.tracking).count()),
    };
    writeln!(out, "[{:7.2} s] Γ̂ [Hz/(m/s²)] {} | {receiver} | {trust}", v.data_t_s, axes.join(" · "))
}
