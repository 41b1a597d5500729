//! A calibration's whole report from its outcome: the result document, the
//! figure set and every file of [`write_report_dir`], and the line that
//! says where they are.

use crate::{FigureInputs, ReportFiles, WriteError, observation_figures, write_report_dir};
use gsens_calib::{CalibError, ObservationOutcome, Outcome, ResultDocument};
use gsens_io::TrackingLog;
use std::path::Path;

/// Why a calibration's report could not be written.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ReportError {
    /// The figures' series could not be computed.
    #[error(transparent)]
    Series(#[from] CalibError),
    /// A figure or file could not be drawn or written.
    #[error(transparent)]
    Write(#[from] WriteError),
}

/// What a report is written from: a calibration from tracking rows with the
/// log it was made from (for the figures of its tracks), or one from a
/// carrier phase and Doppler log (its loop identified).
#[derive(Debug, Clone, Copy)]
pub enum ReportSource<'a> {
    /// A calibration and the tracking log it was estimated from.
    Tracking(&'a Outcome, &'a TrackingLog),
    /// A calibration from a RINEX or UBX log.
    Observations(&'a ObservationOutcome),
}

/// Writes the report of `source` (with the true Γ `truth` when known) into
/// `dir` titled `title`: the files of [`write_report_dir`] with the figures
/// of [`FigureInputs`] for tracking rows, of [`observation_figures`] for a
/// carrier phase and Doppler log. Returns the result document and the files
/// written.
pub fn write_calibration_report(
    source: ReportSource<'_>,
    truth: Option<[f64; 3]>,
    dir: &Path,
    title: &str,
    write_untrusted_header: bool,
    on_figure: impl FnMut(&str),
) -> Result<(ResultDocument, ReportFiles), ReportError> {
    let figure_inputs;
    let (doc, figures) = match source {
        ReportSource::Tracking(outcome, tracking) => {
            figure_inputs = FigureInputs::new(outcome, Some(tracking), truth)?;
            (outcome.document(truth), figure_inputs.figures())
        }
        ReportSource::Observations(outcome) => (outcome.document(truth), observation_figures(outcome)),
    };
    let files = write_report_dir(dir, title, &doc, &figures, write_untrusted_header, on_figure)?;
    Ok((doc, files))
}

impl ReportFiles {
    /// Where the report is: `report: DIR/report.html (with report.json,
    /// gsens_gamma.h and figures/ beside it)`, the header named only when
    /// written.
    pub fn summary(&self) -> String {
        let beside = if self.header.is_some() { "report.json, gsens_gamma.h" } else { "report.json" };
        format!("report: {} (with {beside} and figures/ beside it)", self.html.display())
    }

    /// What a report of `doc` written as these files tells: its text
    /// ([`crate::render_text`]) and [`ReportFiles::summary`]; and, when
    /// the header was not written, why and how to have it anyway (the
    /// setting `write_untrusted_header` spelled by `option`).
    pub fn render(&self, doc: &ResultDocument, option: impl Fn(&str) -> String) -> (String, Option<String>) {
        let text = format!("{}\n{}\n", crate::render_text(doc), self.summary());
        let no_header = self.header.is_none().then(|| {
            format!(
                "gsens_gamma.h not written: the estimate is not trustworthy ({}); {} writes it anyway, marked \
                 GSENS_GAMMA_TRUSTWORTHY 0\n",
                doc.untrusted_codes().join(", "),
                option("write_untrusted_header")
            )
        });
        (text, no_header)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    #[test]
    fn the_summary_names_the_header_only_when_written() {
        let mut files =
            ReportFiles { html: PathBuf::from("out/report.html"), header: Some(PathBuf::from("out/gsens_gamma.h")) };
        assert_eq!(files.summary(), "report: out/report.html (with report.json, gsens_gamma.h and figures/ beside it)");
        files.header = None;
        assert_eq!(files.summary(), "report: out/report.html (with report.json and figures/ beside it)");
    }
}
