//! GNSS-SDR configuration files (gsens_gnss_sdr::conf): any text gives the
//! tracking and lock-detector settings or an error naming the line, never a
//! panic; accepted settings make a loop the importer can model.
#![no_main]
use gsens_gnss_sdr::GnssSdrConf;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    let Ok(conf) = GnssSdrConf::parse(text, "gnss-sdr.conf") else { return };
    let _ = conf.lock_detector();
    if let Ok(t) = conf.tracking() {
        let settings = gsens_gnss_sdr::ImportSettings::new(t.fs_hz.unwrap_or(4e6), t);
        // The importer's start-up analysis of the stage must end (it once did not for 1e200 Hz).
        let _ = gsens_core::gnss_sdr::GnssSdrPll::new(settings.stage()).map(|p| p.settling_time_s(5.0));
    }
});
