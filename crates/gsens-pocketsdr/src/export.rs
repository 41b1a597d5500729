//! A converted log written as gsens's `tracking.csv` (what `gsens import
//! pocketsdr` does), with what became of each track as JSON when asked.

use crate::import::{Imported, render_summary};
use gsens_io::ExportError;
use std::path::Path;

/// Where an import of the log `log` (made with the options file `conf`)
/// goes: the tracking log `csv`, and the conversion as JSON in `tracks_json`.
#[derive(Debug, Clone, Copy)]
pub struct Export<'a> {
    /// The pocket_trk log.
    pub log: &'a Path,
    /// The options file it was made with.
    pub conf: Option<&'a Path>,
    /// The tracking log written.
    pub csv: &'a Path,
    /// The conversion's JSON ([`Imported`]), when asked.
    pub tracks_json: Option<&'a Path>,
}

impl Export<'_> {
    /// Writes `imported`: tells `say` the conversion ([`render_summary`]),
    /// then the rows written and how to estimate from them with PocketSDR's
    /// loop, with the options spelled by `option`.
    pub fn write(
        &self,
        imported: &Imported,
        say: &mut dyn FnMut(&str) -> std::io::Result<()>,
        option: impl Fn(&str) -> String,
    ) -> Result<(), ExportError> {
        say(&render_summary(imported))?;
        gsens_io::write_tracking_csv(gsens_io::create_file(self.csv)?, &imported.rows)?;
        let conf = self.conf.map_or(String::new(), |c| format!(" {} {}", option("pocketsdr_conf"), c.display()));
        say(&format!(
            "wrote {} rows → {}; estimate with PocketSDR's loop model: gsens estimate {} <imu.csv> {} {}{conf} \
             (b_pll {} Hz, rows = the single 1 ms discriminator output at each epoch)\n",
            imported.rows.len(),
            self.csv.display(),
            option("imu"),
            option("pocketsdr"),
            self.log.display(),
            imported.stage.bw_hz
        ))?;
        if let Some(path) = self.tracks_json {
            gsens_io::write_file(path, serde_json::to_string_pretty(imported).map_err(ExportError::encode)? + "\n")?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::Export;
    use crate::import::{ImportSettings, import_file};
    use std::path::Path;

    /// The export writes the rows and the conversion, and says how to
    /// estimate from them with the options spelled as the caller spells them.
    #[test]
    fn the_export_tells_the_rows_written_and_how_to_estimate() {
        let fixtures = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures");
        let (log, conf) = (fixtures.join("trk.log"), fixtures.join("opt.conf"));
        let imported = import_file(&log, &ImportSettings::from_options_file(Some(&conf)).unwrap()).unwrap();
        let out = tempfile::tempdir().unwrap();
        let (csv, json) = (out.path().join("tracking.csv"), out.path().join("tracks.json"));
        let export = Export { log: &log, conf: Some(&conf), csv: &csv, tracks_json: Some(&json) };
        let mut said = String::new();
        export
            .write(
                &imported,
                &mut |t| {
                    said.push_str(t);
                    Ok(())
                },
                |name| format!("<{name}>"),
            )
            .unwrap();
        let rows = std::fs::read_to_string(&csv).unwrap().lines().count() - 1;
        assert_eq!(rows, imported.rows.len());
        let expected = format!(
            "wrote {rows} rows → {}; estimate with PocketSDR's loop model: gsens estimate <imu> <imu.csv> <pocketsdr> {} \
             <pocketsdr_conf> {} (b_pll {} Hz, rows = the single 1 ms discriminator output at each epoch)\n",
            csv.display(),
            log.display(),
            conf.display(),
            imported.stage.bw_hz
        );
        assert!(said.starts_with("PocketSDR log ") && said.ends_with(&expected), "{said}");
        let written: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
        assert_eq!(written["tracks"].as_array().map(Vec::len), Some(imported.tracks.len()));
    }
}
