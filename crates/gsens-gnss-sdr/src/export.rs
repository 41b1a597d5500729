//! Imported dumps written as gsens's `tracking.csv`: on the common grid
//! (every channel at t = j·T, T the modelled stage's record interval, what
//! `gsens_io::read_tracking` needs), or each record at the middle of its own
//! integration with its carrier lock test.

use crate::import::{Imported, resample, write_imported_csv};

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
    use crate::import::{ImportSettings, import_dir};
    use std::path::Path;

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
