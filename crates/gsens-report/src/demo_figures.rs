//! The figures of a demo ([`gsens_montecarlo::Demo`]): its calibration's
//! figure set with the true Γ drawn, plus the Allan deviation of the
//! scenario's simulated oscillator against its model.

use crate::{Figure, FigureInputs, WriteError, write_figures};
use gsens_calib::{CalibError, Outcome};
use gsens_io::FormatError;
use gsens_montecarlo::{Demo, DemoError};
use std::path::Path;

/// Why a demo's figures could not be written.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum DemoFiguresError {
    /// The demo's tracking log could not be read back.
    #[error(transparent)]
    Read(#[from] FormatError),
    /// The calibration's series could not be computed.
    #[error(transparent)]
    Series(#[from] CalibError),
    /// The oscillator's Allan deviation could not be simulated.
    #[error(transparent)]
    Oscillator(#[from] DemoError),
    /// A figure could not be drawn or written.
    #[error(transparent)]
    Write(#[from] WriteError),
}

/// Writes the figures of `demo`'s calibration `outcome` into `dir` as PNG
/// and SVG (`on_figure` is told each figure's id before it is drawn): the
/// calibration's set ([`FigureInputs`]) with the truth, then the
/// oscillator's Allan deviation when it has noise. Returns the ids written.
pub fn write_demo_figures(
    dir: &Path,
    demo: &Demo,
    outcome: &Outcome,
    on_figure: impl FnMut(&str),
) -> Result<Vec<&'static str>, DemoFiguresError> {
    let log = gsens_io::read_tracking_file(&demo.tracking)?;
    let inputs = FigureInputs::new(outcome, Some(&log), Some(demo.truth.sensitivity.gamma_hz_per_mps2))?;
    let mut figs = inputs.figures();
    if let Some(a) = demo.oscillator_allan()? {
        figs.push(Figure::allan(a.taus_s, a.simulated, a.theory, a.duration_s, demo.oscillator_label()));
    }
    write_figures(&figs, dir, on_figure)?;
    Ok(figs.iter().map(|f| f.id).collect())
}
