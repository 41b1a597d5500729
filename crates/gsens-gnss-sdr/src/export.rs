//! Imported dumps written as gsens's `tracking.csv`: on the common grid
//! (every channel at t = j·T, T the modelled stage's record interval, what
//! `gsens_io::read_tracking` needs), or each record at the middle of its own
//! integration with its carrier lock test.

use crate::calibrate::Conversion;
use crate::import::{ImportSettings, Imported, render_tracks, resample, write_imported_csv};
use gsens_io::ExportError;
use std::path::Path;

/// Where an import of the dumps in `dump_dir` (made with the configuration
/// `conf`) goes: the tracking log `csv`, on the common grid when
/// `on_common_grid`, and what became of each track as JSON in `tracks_json`.
#[derive(Debug, Clone, Copy)]
pub struct Export<'a> {
    /// The dumps' directory.
    pub dump_dir: &'a Path,
    /// The configuration the dumps were made with.
    pub conf: Option<&'a Path>,
    /// The tracking log written.
    pub csv: &'a Path,
    /// Rows on the common grid t = j·T rather than at their own times.
    pub on_common_grid: bool,
    /// The tracks' JSON ([`Conversion`]), when asked.
    pub tracks_json: Option<&'a Path>,
}

impl Export<'_> {
    /// Writes `imported` (converted with `settings`): tells `say` its tracks
    /// ([`render_tracks`]), then the rows written and how to estimate from
    /// them with the dumps' loop, with the options spelled by `option`.
    pub fn write(
        &self,
        imported: Imported,
        settings: ImportSettings,
        say: &mut dyn FnMut(&str) -> std::io::Result<()>,
        option: impl Fn(&str) -> String,
    ) -> Result<(), ExportError> {
        say(&render_tracks(&imported.tracks, imported.interval_s))?;
        let rows = imported.write_csv(gsens_io::create_file(self.csv)?, self.on_common_grid)?;
        let stage = settings.stage();
        let times = if self.on_common_grid {
            format!(" (common grid, for gsens estimate {})", option("tracking"))
        } else {
            format!(" (times at the middle of each integration; not for gsens estimate {})", option("tracking"))
        };
        say(&format!(
            "wrote {rows} rows → {}{times}; estimate with the GNSS-SDR loop model: gsens estimate {} <imu.csv> {} {} {} {} \
             (order {}, Bn {} Hz, {} ms)\n",
            self.csv.display(),
            option("imu"),
            option("gnss_sdr"),
            self.dump_dir.display(),
            option("gnss_sdr_conf"),
            self.conf.map_or("<conf>".to_string(), |c| c.display().to_string()),
            stage.order,
            stage.bw_hz,
            stage.symbols
        ))?;
        if let Some(path) = self.tracks_json {
            let conversion = Conversion { conversion: settings, tracks: imported.tracks };
            gsens_io::write_file(path, serde_json::to_string_pretty(&conversion).map_err(ExportError::encode)? + "\n")?;
        }
        Ok(())
    }
}

impl Imported {
    /// Writes the rows to `w` on the common grid ([`resample`]) when
    /// `on_common_grid`, else at their own times with the extra column
    /// `carrier_lock_test` (`write_imported_csv`); returns the rows written.
    pub fn write_csv<W: std::io::Write>(&self, w: W, on_common_grid: bool) -> std::io::Result<usize> {
        if on_common_grid {
            let grid = resample(self, self.interval_s);
            gsens_io::write_tracking_csv(w, &grid)?;
            Ok(grid.len())
        } else {
            write_imported_csv(w, &self.rows)?;
            Ok(self.rows.len())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::Export;
    use crate::import::{ImportSettings, import_dir};
    use std::path::Path;

    /// The export writes the rows and the tracks, and says how to estimate
    /// from them with the options spelled as the caller spells them.
    #[test]
    fn the_export_tells_the_rows_written_and_how_to_estimate() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/order2");
        let conf = dir.join("gnss-sdr.conf");
        let settings = ImportSettings::from_conf(Some(&conf), None).unwrap();
        let imported = import_dir(&dir, &settings).unwrap();
        let tracks = imported.tracks.len();
        let out = tempfile::tempdir().unwrap();
        let (csv, json) = (out.path().join("tracking.csv"), out.path().join("tracks.json"));
        let export =
            Export { dump_dir: &dir, conf: Some(&conf), csv: &csv, on_common_grid: true, tracks_json: Some(&json) };
        let mut said = String::new();
        let mut say = |t: &str| {
            said.push_str(t);
            Ok(())
        };
        export.write(imported, settings.clone(), &mut say, |name| format!("<{name}>")).unwrap();
        let rows = std::fs::read_to_string(&csv).unwrap().lines().count() - 1;
        let stage = settings.stage();
        let expected = format!(
            "wrote {rows} rows → {} (common grid, for gsens estimate <tracking>); estimate with the GNSS-SDR loop \
             model: gsens estimate <imu> <imu.csv> <gnss_sdr> {} <gnss_sdr_conf> {} (order {}, Bn {} Hz, {} ms)\n",
            csv.display(),
            dir.display(),
            conf.display(),
            stage.order,
            stage.bw_hz,
            stage.symbols
        );
        assert!(said.starts_with("GNSS-SDR dumps: ") && said.ends_with(&expected), "{said}");
        let written: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
        assert_eq!(written["tracks"].as_array().map(Vec::len), Some(tracks));
    }

    /// The fixture's dumps: on the grid every time is a multiple of 20 ms;
    /// at their own times they are not, and carry the lock test.
    #[test]
    fn the_grid_puts_every_row_on_multiples_of_the_interval() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/order2");
        let settings = ImportSettings::from_conf(Some(&dir.join("gnss-sdr.conf")), None).unwrap();
        let imported = import_dir(&dir, &settings).unwrap();
        let mut grid = Vec::new();
        let n = imported.write_csv(&mut grid, true).unwrap();
        let text = String::from_utf8(grid).unwrap();
        assert_eq!(text.lines().count(), n + 1);
        assert_eq!(text.lines().next(), Some("t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad"));
        for line in text.lines().skip(1) {
            let t: f64 = line.split(',').next().unwrap().parse().unwrap();
            assert!(((t / 0.02).round() * 0.02 - t).abs() < 1e-9, "{t}");
        }
        let mut own = Vec::new();
        assert_eq!(imported.write_csv(&mut own, false).unwrap(), imported.rows.len());
        let text = String::from_utf8(own).unwrap();
        assert!(text.starts_with("t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad,carrier_lock_test\n"));
    }
}
