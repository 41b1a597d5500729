//! GNSS-SDR tracking dumps: the `.dat` files its DLL/PLL tracking writes with
//! `Tracking_1C.dump=true`, one per channel (`<dump_filename><channel>.dat`).
//!
//! # Format
//!
//! A dump is a sequence of packed little-endian records, one per loop update
//! (every 1 ms until bit synchronization, then one per extended integration),
//! with no header. The layout is not stored in the file, so the reader knows
//! the layouts of the GNSS-SDR versions it was checked against, picks those
//! whose record size divides the file length, and checks every record for
//! plausibility (PRN, discriminator and lock-test ranges, sample counter
//! increasing), so a dump of another version or block is refused with an
//! error naming the file, the record and its byte offset rather than read as
//! garbage.
//!
//! [`DumpLayout::v0_0_17`], 96 bytes (`dll_pll_veml_tracking`):
//!
//! | field | type | unit |
//! | --- | --- | --- |
//! | `abs_VE`, `abs_E`, `abs_P`, `abs_L`, `abs_VL` | f32 | correlator magnitudes |
//! | `Prompt_I`, `Prompt_Q` | f32 | prompt correlator |
//! | `PRN_start_sample_count` | u64 | sample counter at the end of the integration |
//! | `acc_carrier_phase_rad` | f32 | rad |
//! | `carrier_doppler_hz` | f32 | Hz: the NCO command for the *next* integration |
//! | `carrier_doppler_rate_hz` | f32 | Hz/s |
//! | `code_freq_chips`, `code_freq_rate_chips` | f32 | chip/s, chip/s² |
//! | `carr_error_hz` | f32 | **cycles**: the PLL discriminator atan(Q/I)/2π, θ_signal − θ_replica |
//! | `carr_error_filt_hz` | f32 | Hz: the loop filter output (= `carrier_doppler_hz`) |
//! | `code_error_chips`, `code_error_filt_chips` | f32 | chips |
//! | `CN0_SNV_dB_Hz` | f32 | dB-Hz (0 until the estimator has filled its window) |
//! | `carrier_lock_test` | f32 | cos 2φ estimate, in \[−1, 1\] |
//! | `aux1` | f32 | (the remnant code phase) |
//! | `aux2` | f64 | (the sample counter again) |
//! | `PRN` | u32 | satellite |
//!
//! Checked: GNSS-SDR 0.0.17 (Debian 12) on its own output, and GNSS-SDR 0.0.20
//! (Debian 13): its `dll_pll_veml_tracking` writes the same sequence of field
//! sizes (7 × 4, 8, 12 × 4, 8, 4 bytes), its `.mat` converter divides the file
//! length by 96 and names the same fields in the same order (read from the
//! binary's machine code and strings; 0.0.20 was not run). Other layouts
//! (older versions, other tracking blocks) can be given with
//! [`DumpLayout::parse_spec`].

use std::path::{Path, PathBuf};

use crate::error::{GnssSdrError, LayoutSpecError};

/// The binary type of a dump field (little-endian).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FieldType {
    /// IEEE 754 single.
    F32,
    /// IEEE 754 double.
    F64,
    /// Unsigned 32-bit integer.
    U32,
    /// Unsigned 64-bit integer.
    U64,
    /// Signed 32-bit integer.
    I32,
}

impl FieldType {
    /// Size \[bytes\].
    pub fn size(self) -> usize {
        match self {
            FieldType::F32 | FieldType::U32 | FieldType::I32 => 4,
            FieldType::F64 | FieldType::U64 => 8,
        }
    }

    fn parse(s: &str) -> Option<Self> {
        match s {
            "f32" | "float" => Some(FieldType::F32),
            "f64" | "double" => Some(FieldType::F64),
            "u32" | "uint32" => Some(FieldType::U32),
            "u64" | "uint64" => Some(FieldType::U64),
            "i32" | "int32" => Some(FieldType::I32),
            _ => None,
        }
    }

    fn read(self, b: &[u8]) -> f64 {
        match self {
            FieldType::F32 => f64::from(f32::from_le_bytes(b[..4].try_into().expect("4 bytes"))),
            FieldType::F64 => f64::from_le_bytes(b[..8].try_into().expect("8 bytes")),
            FieldType::U32 => f64::from(u32::from_le_bytes(b[..4].try_into().expect("4 bytes"))),
            FieldType::I32 => f64::from(i32::from_le_bytes(b[..4].try_into().expect("4 bytes"))),
            FieldType::U64 => u64::from_le_bytes(b[..8].try_into().expect("8 bytes")) as f64,
        }
    }
}

/// The fields a layout must have for the conversion.
pub const REQUIRED_FIELDS: [&str; 6] =
    ["PRN_start_sample_count", "carr_error_hz", "carrier_doppler_hz", "CN0_SNV_dB_Hz", "carrier_lock_test", "PRN"];

/// A record layout: named, typed fields in file order.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DumpLayout {
    /// Short name used in messages, e.g. `gnss-sdr-0.0.17`.
    pub name: String,
    /// Which GNSS-SDR versions and blocks write it.
    pub description: String,
    /// (field name, type), in file order.
    pub fields: Vec<(String, FieldType)>,
}

impl DumpLayout {
    /// GNSS-SDR 0.0.17 … 0.0.20 `dll_pll_veml_tracking` (GPS L1 C/A DLL/PLL), 96 bytes (module docs).
    pub fn v0_0_17() -> Self {
        use FieldType::*;
        let f = |n: &str, t| (n.to_owned(), t);
        DumpLayout {
            name: "gnss-sdr-0.0.17".into(),
            description: "GNSS-SDR 0.0.17 to 0.0.20 dll_pll_veml_tracking (GPS_L1_CA_DLL_PLL_Tracking)".into(),
            fields: vec![
                f("abs_VE", F32),
                f("abs_E", F32),
                f("abs_P", F32),
                f("abs_L", F32),
                f("abs_VL", F32),
                f("Prompt_I", F32),
                f("Prompt_Q", F32),
                f("PRN_start_sample_count", U64),
                f("acc_carrier_phase_rad", F32),
                f("carrier_doppler_hz", F32),
                f("carrier_doppler_rate_hz", F32),
                f("code_freq_chips", F32),
                f("code_freq_rate_chips", F32),
                f("carr_error_hz", F32),
                f("carr_error_filt_hz", F32),
                f("code_error_chips", F32),
                f("code_error_filt_chips", F32),
                f("CN0_SNV_dB_Hz", F32),
                f("carrier_lock_test", F32),
                f("aux1", F32),
                f("aux2", F64),
                f("PRN", U32),
            ],
        }
    }

    /// The layouts the reader tries when none is given.
    pub fn known() -> Vec<DumpLayout> {
        vec![DumpLayout::v0_0_17()]
    }

    /// Record size \[bytes\].
    pub fn record_bytes(&self) -> usize {
        self.fields.iter().map(|(_, t)| t.size()).sum()
    }

    /// A layout from a spec `name:type,name:type,…` (types f32, f64, u32, u64,
    /// i32), for dumps of versions or blocks the reader does not know. It must
    /// contain the [`REQUIRED_FIELDS`].
    pub fn parse_spec(spec: &str) -> Result<Self, LayoutSpecError> {
        let mut fields = Vec::new();
        for item in spec.split(',').map(str::trim).filter(|s| !s.is_empty()) {
            let (n, t) =
                item.split_once(':').ok_or_else(|| LayoutSpecError::ExpectedNameType { item: item.to_owned() })?;
            let t = FieldType::parse(t.trim())
                .ok_or_else(|| LayoutSpecError::UnknownType { item: item.to_owned(), ty: t.trim().to_owned() })?;
            fields.push((n.trim().to_owned(), t));
        }
        for field in REQUIRED_FIELDS {
            if !fields.iter().any(|(n, _)| n == field) {
                return Err(LayoutSpecError::MissingField { field });
            }
        }
        Ok(DumpLayout { name: "custom".into(), description: format!("custom layout `{spec}`"), fields })
    }

    fn offset_of(&self, name: &str) -> Option<(usize, FieldType)> {
        let mut off = 0;
        for (n, t) in &self.fields {
            if n == name {
                return Some((off, *t));
            }
            off += t.size();
        }
        None
    }
}

/// One record of a tracking dump, whatever its layout (fields the layout lacks are NaN).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrackingRecord {
    /// Magnitudes of the very early, early, prompt, late and very late correlators.
    pub abs_ve: f64,
    /// Early correlator magnitude.
    pub abs_e: f64,
    /// Prompt correlator magnitude.
    pub abs_p: f64,
    /// Late correlator magnitude.
    pub abs_l: f64,
    /// Very late correlator magnitude.
    pub abs_vl: f64,
    /// Prompt in-phase correlator output.
    pub prompt_i: f64,
    /// Prompt quadrature correlator output.
    pub prompt_q: f64,
    /// Sample counter at the end of the integration.
    pub prn_start_sample_count: u64,
    /// Accumulated carrier phase \[rad\].
    pub acc_carrier_phase_rad: f64,
    /// NCO frequency commanded for the next integration \[Hz\].
    pub carrier_doppler_hz: f64,
    /// Carrier Doppler rate \[Hz/s\].
    pub carrier_doppler_rate_hz_per_s: f64,
    /// Code frequency \[chip/s\].
    pub code_freq_chips_per_s: f64,
    /// Code frequency rate \[chip/s²\].
    pub code_freq_rate_chips_per_s2: f64,
    /// PLL discriminator output \[cycles\] (GNSS-SDR calls it `carr_error_hz`).
    pub carr_error_cycles: f64,
    /// Carrier loop filter output \[Hz\].
    pub carr_error_filt_hz: f64,
    /// DLL discriminator output \[chips\].
    pub code_error_chips: f64,
    /// DLL filter output \[chips\].
    pub code_error_filt_chips: f64,
    /// C/N0 estimate \[dB-Hz\].
    pub cn0_dbhz: f64,
    /// Carrier lock test (cos 2φ estimate).
    pub carrier_lock_test: f64,
    /// Debug value 1.
    pub aux1: f64,
    /// Debug value 2.
    pub aux2: f64,
    /// Satellite PRN.
    pub prn: u32,
}

/// A decoded dump.
#[derive(Debug, Clone, PartialEq)]
pub struct TrackingDump {
    /// The file, as given.
    pub file: String,
    /// The channel number from the file name (`…<channel>.dat`), if any.
    pub channel: Option<u32>,
    /// Name of the layout used.
    pub layout: String,
    /// The records, in file order.
    pub records: Vec<TrackingRecord>,
}

fn layouts_text(layouts: &[DumpLayout]) -> String {
    layouts
        .iter()
        .map(|l| format!("{} ({} bytes per record)", l.description, l.record_bytes()))
        .collect::<Vec<_>>()
        .join("; ")
}

/// Decodes and checks the records of `bytes` with `layout`.
fn decode(bytes: &[u8], file: &str, layout: &DumpLayout) -> Result<Vec<TrackingRecord>, GnssSdrError> {
    let size = layout.record_bytes();
    let get = |name: &str| layout.offset_of(name);
    let fld = |rec: &[u8], f: Option<(usize, FieldType)>| f.map_or(f64::NAN, |(o, t)| t.read(&rec[o..]));
    let o = [
        "abs_VE",
        "abs_E",
        "abs_P",
        "abs_L",
        "abs_VL",
        "Prompt_I",
        "Prompt_Q",
        "acc_carrier_phase_rad",
        "carrier_doppler_hz",
        "carrier_doppler_rate_hz",
        "code_freq_chips",
        "code_freq_rate_chips",
        "carr_error_hz",
        "carr_error_filt_hz",
        "code_error_chips",
        "code_error_filt_chips",
        "CN0_SNV_dB_Hz",
        "carrier_lock_test",
        "aux1",
        "aux2",
    ]
    .map(get);
    let count = get("PRN_start_sample_count").expect("required field");
    let prn = get("PRN").expect("required field");
    let mut out = Vec::with_capacity(bytes.len() / size);
    let mut prev_count: Option<u64> = None;
    for (i, rec) in bytes.chunks_exact(size).enumerate() {
        let bad = |reason: String| GnssSdrError::BadRecord {
            file: file.to_owned(),
            index: i as u64,
            offset: (i * size) as u64,
            layout: layout.name.clone(),
            reason,
        };
        let v = o.map(|f| fld(rec, f));
        let n = match count.1 {
            FieldType::U64 => u64::from_le_bytes(rec[count.0..count.0 + 8].try_into().expect("8 bytes")),
            t => {
                let x = t.read(&rec[count.0..]);
                if !(x.is_finite() && x >= 0.0) {
                    return Err(bad(format!("PRN_start_sample_count = {x} is not a sample count")));
                }
                x as u64
            }
        };
        let p = prn.1.read(&rec[prn.0..]);
        if !((1.0..=255.0).contains(&p) && p.fract() == 0.0) {
            return Err(bad(format!("PRN = {p} is not a satellite number (1…255)")));
        }
        let r = TrackingRecord {
            abs_ve: v[0],
            abs_e: v[1],
            abs_p: v[2],
            abs_l: v[3],
            abs_vl: v[4],
            prompt_i: v[5],
            prompt_q: v[6],
            prn_start_sample_count: n,
            acc_carrier_phase_rad: v[7],
            carrier_doppler_hz: v[8],
            carrier_doppler_rate_hz_per_s: v[9],
            code_freq_chips_per_s: v[10],
            code_freq_rate_chips_per_s2: v[11],
            carr_error_cycles: v[12],
            carr_error_filt_hz: v[13],
            code_error_chips: v[14],
            code_error_filt_chips: v[15],
            cn0_dbhz: v[16],
            carrier_lock_test: v[17],
            aux1: v[18],
            aux2: v[19],
            prn: p as u32,
        };
        if !(r.carr_error_cycles.is_finite() && r.carr_error_cycles.abs() <= 0.5 + 1e-6) {
            return Err(bad(format!(
                "carr_error_hz = {} is not a PLL discriminator output in cycles (|x| ≤ 0.5)",
                r.carr_error_cycles
            )));
        }
        if !(r.carrier_lock_test.is_finite() && r.carrier_lock_test.abs() <= 1.0 + 1e-4) {
            return Err(bad(format!("carrier_lock_test = {} is outside [−1, 1]", r.carrier_lock_test)));
        }
        if !(r.cn0_dbhz.is_finite() && (-50.0..=150.0).contains(&r.cn0_dbhz)) {
            return Err(bad(format!("CN0_SNV_dB_Hz = {} is not a C/N0 in dB-Hz", r.cn0_dbhz)));
        }
        if !(r.carrier_doppler_hz.is_finite() && r.carrier_doppler_hz.abs() < 1e6) {
            return Err(bad(format!("carrier_doppler_hz = {} is not a Doppler", r.carrier_doppler_hz)));
        }
        if let Some(prev) = prev_count
            && n <= prev
        {
            return Err(bad(format!("PRN_start_sample_count {n} does not increase (previous record: {prev})")));
        }
        prev_count = Some(n);
        out.push(r);
    }
    Ok(out)
}

/// Decodes a dump held in memory. `file` names it in errors; `layout` forces
/// a layout, else the [`DumpLayout::known`] ones whose record size divides the
/// length are tried.
pub fn parse_dump(bytes: &[u8], file: &str, layout: Option<&DumpLayout>) -> Result<TrackingDump, GnssSdrError> {
    let candidates: Vec<DumpLayout> = match layout {
        Some(l) => vec![l.clone()],
        None => DumpLayout::known(),
    };
    if bytes.is_empty() {
        return Err(GnssSdrError::EmptyDump { file: file.to_owned(), expected: layouts_text(&candidates) });
    }
    let fitting: Vec<&DumpLayout> =
        candidates.iter().filter(|l| l.record_bytes() > 0 && bytes.len().is_multiple_of(l.record_bytes())).collect();
    if fitting.is_empty() {
        return Err(GnssSdrError::UnknownLayout {
            file: file.to_owned(),
            len: bytes.len() as u64,
            expected: layouts_text(&candidates),
        });
    }
    let mut ok = Vec::new();
    let mut first_err = None;
    for l in &fitting {
        match decode(bytes, file, l) {
            Ok(r) => ok.push((l.name.clone(), r)),
            Err(e) => {
                first_err.get_or_insert(e);
            }
        }
    }
    match ok.len() {
        0 => Err(first_err.expect("at least one layout was tried")),
        1 => {
            let (layout, records) = ok.pop().expect("one");
            Ok(TrackingDump { file: file.to_owned(), channel: channel_from_name(file), layout, records })
        }
        _ => Err(GnssSdrError::AmbiguousLayout {
            file: file.to_owned(),
            len: bytes.len() as u64,
            candidates: ok.iter().map(|(n, _)| n.clone()).collect::<Vec<_>>().join(", "),
        }),
    }
}

/// Reads and decodes a dump file (see [`parse_dump`]).
pub fn read_dump(path: impl AsRef<Path>, layout: Option<&DumpLayout>) -> Result<TrackingDump, GnssSdrError> {
    let path = path.as_ref();
    let name = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|e| GnssSdrError::Io { file: name.clone(), error: e })?;
    parse_dump(&bytes, &name, layout)
}

/// The channel number at the end of a dump's file stem (`trk_ch_12.dat` → 12).
pub fn channel_from_name(file: &str) -> Option<u32> {
    let stem = Path::new(file).file_stem()?.to_str()?;
    let digits: String = stem.chars().rev().take_while(char::is_ascii_digit).collect();
    if digits.is_empty() {
        return None;
    }
    digits.chars().rev().collect::<String>().parse().ok()
}

/// The dumps in `dir`: files `<prefix><channel>.dat` (any prefix when `None`),
/// sorted by channel. Errors when there is none.
pub fn find_dumps(dir: &Path, prefix: Option<&str>) -> Result<Vec<(u32, PathBuf)>, GnssSdrError> {
    let name = dir.display().to_string();
    let rd = std::fs::read_dir(dir).map_err(|e| GnssSdrError::Io { file: name.clone(), error: e })?;
    let mut out = Vec::new();
    for entry in rd {
        let entry = entry.map_err(|e| GnssSdrError::Io { file: name.clone(), error: e })?;
        let p = entry.path();
        let Some(fname) = p.file_name().and_then(|f| f.to_str()) else { continue };
        if !fname.ends_with(".dat") || !p.is_file() {
            continue;
        }
        if let Some(pre) = prefix
            && !fname.starts_with(pre)
        {
            continue;
        }
        if let Some(ch) = channel_from_name(fname) {
            out.push((ch, p));
        }
    }
    if out.is_empty() {
        return Err(GnssSdrError::NoDumps { dir: name });
    }
    out.sort();
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A synthetic record in the 0.0.17 layout.
    pub(crate) fn record_bytes(
        n: u64,
        carr_error_cycles: f32,
        doppler_hz: f32,
        cn0: f32,
        lock: f32,
        prn: u32,
    ) -> Vec<u8> {
        let mut b = Vec::with_capacity(96);
        for v in [1.0f32, 2.0, 3.0, 2.0, 1.0, 3.0, 0.1] {
            b.extend_from_slice(&v.to_le_bytes());
        }
        b.extend_from_slice(&n.to_le_bytes());
        for v in [0.5f32, doppler_hz, 0.0, 1.023e6, 0.0, carr_error_cycles, doppler_hz, 0.01, 0.0, cn0, lock, 0.2] {
            b.extend_from_slice(&v.to_le_bytes());
        }
        b.extend_from_slice(&(n as f64).to_le_bytes());
        b.extend_from_slice(&prn.to_le_bytes());
        b
    }

    #[test]
    fn layout_is_96_bytes_and_round_trips() {
        assert_eq!(DumpLayout::v0_0_17().record_bytes(), 96);
        let mut bytes = record_bytes(4000, 0.01, 1500.0, 45.0, 0.9, 7);
        bytes.extend(record_bytes(8000, -0.02, 1500.5, 45.5, 0.95, 7));
        let d = parse_dump(&bytes, "dir/trk_ch_3.dat", None).unwrap();
        assert_eq!(d.channel, Some(3));
        assert_eq!(d.records.len(), 2);
        let r = d.records[1];
        assert_eq!((r.prn, r.prn_start_sample_count), (7, 8000));
        assert!((r.carr_error_cycles + 0.02).abs() < 1e-7 && r.cn0_dbhz == 45.5 && r.aux2 == 8000.0);
    }

    #[test]
    fn bad_dumps_get_clear_errors() {
        let e = parse_dump(&[], "trk_ch_0.dat", None).unwrap_err().to_string();
        assert!(e.contains("trk_ch_0.dat") && e.contains("empty") && e.contains("96 bytes per record"), "{e}");
        // Truncated: one and a half records.
        let mut b = record_bytes(4000, 0.01, 1500.0, 45.0, 0.9, 7);
        b.extend_from_slice(&record_bytes(8000, 0.01, 1500.0, 45.0, 0.9, 7)[..48]);
        let e = parse_dump(&b, "trk_ch_1.dat", None).unwrap_err().to_string();
        assert!(e.contains("trk_ch_1.dat") && e.contains("144 bytes") && e.contains("truncated"), "{e}");
        assert!(e.contains("GNSS-SDR 0.0.17 to 0.0.20") && e.contains("96 bytes per record"), "{e}");
        // Another version's records that happen to fill whole 96-byte records: 24 f32 of garbage.
        let other: Vec<u8> = (0..48).flat_map(|i| (1e5f32 * i as f32 + 3.7).to_le_bytes()).collect();
        let e = parse_dump(&other, "trk_ch_2.dat", None).unwrap_err().to_string();
        assert!(e.contains("trk_ch_2.dat: record 0 (byte offset 0)"), "{e}");
        // A bad value deep in a file names the record and its offset.
        let mut b = Vec::new();
        for k in 0..5u64 {
            b.extend(record_bytes(4000 * (k + 1), if k == 3 { 3.0 } else { 0.01 }, 1500.0, 45.0, 0.9, 7));
        }
        let e = parse_dump(&b, "trk_ch_4.dat", None).unwrap_err().to_string();
        assert!(e.contains("record 3 (byte offset 288)") && e.contains("carr_error_hz = 3"), "{e}");
        // The sample counter must increase.
        let mut b = record_bytes(8000, 0.01, 1500.0, 45.0, 0.9, 7);
        b.extend(record_bytes(4000, 0.01, 1500.0, 45.0, 0.9, 7));
        let e = parse_dump(&b, "trk_ch_5.dat", None).unwrap_err().to_string();
        assert!(e.contains("record 1 (byte offset 96)") && e.contains("does not increase"), "{e}");
    }

    #[test]
    fn custom_layouts() {
        let l = DumpLayout::parse_spec(
            "PRN_start_sample_count:u64, carr_error_hz:f32, carrier_doppler_hz:f32, CN0_SNV_dB_Hz:f32, \
             carrier_lock_test:f32, PRN:u32",
        )
        .unwrap();
        assert_eq!(l.record_bytes(), 28);
        let mut b = Vec::new();
        b.extend_from_slice(&5000u64.to_le_bytes());
        for v in [0.01f32, -1200.0, 44.0, 0.97] {
            b.extend_from_slice(&v.to_le_bytes());
        }
        b.extend_from_slice(&12u32.to_le_bytes());
        let d = parse_dump(&b, "x7.dat", Some(&l)).unwrap();
        assert_eq!(d.records[0].prn, 12);
        assert!(d.records[0].abs_e.is_nan());
        assert_eq!(
            DumpLayout::parse_spec("PRN:u32"),
            Err(LayoutSpecError::MissingField { field: "PRN_start_sample_count" })
        );
        assert_eq!(
            DumpLayout::parse_spec(" a : f16 ").unwrap_err().to_string(),
            "`a : f16`: unknown type `f16` (f32, f64, u32, u64, i32)"
        );
        assert_eq!(DumpLayout::parse_spec("abs_P f32").unwrap_err().to_string(), "`abs_P f32`: expected name:type");
        assert_eq!(
            DumpLayout::parse_spec("").unwrap_err().to_string(),
            "the layout lacks the field `PRN_start_sample_count` (required: PRN_start_sample_count, carr_error_hz, \
             carrier_doppler_hz, CN0_SNV_dB_Hz, carrier_lock_test, PRN)"
        );
    }

    #[test]
    fn channel_numbers_from_names() {
        assert_eq!(channel_from_name("/x/trk_ch_12.dat"), Some(12));
        assert_eq!(channel_from_name("epl_tracking_ch_0.dat"), Some(0));
        assert_eq!(channel_from_name("trk.dat"), None);
    }
}
