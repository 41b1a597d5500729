//! The crate documentation's section "Tracking dumps" describes this module.

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
pub(crate) const REQUIRED_FIELDS: [&str; 6] =
    ["PRN_start_sample_count", "carr_error_hz", "carrier_doppler_hz", "CN0_SNV_dB_Hz", "carrier_lock_test", "PRN"];

/// What the block writes in `aux2`, checked on every record.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Aux2Rule {
    /// `aux2` = `PRN_start_sample_count` (the counter at the end of the integration).
    SameCounter,
    /// `aux2` = `PRN_start_sample_count` (the start) + the integration length in samples (> 0).
    CounterPlusLength,
    /// Not checked (custom layouts).
    Unchecked,
}

/// A record layout: named, typed fields in file order, the blocks and
/// versions that write it, and the relations between fields the reader checks.
#[derive(Debug, Clone, PartialEq)]
pub struct DumpLayout {
    /// Short name used in messages, e.g. `gnss-sdr-0.0.17`.
    pub name: String,
    /// Which GNSS-SDR versions and blocks write it.
    pub description: String,
    /// (field name, type), in file order.
    pub fields: Vec<(String, FieldType)>,
    /// Largest |`carr_error_hz`| the block can write (0.5 for a discriminator
    /// in cycles); `None`: only finite.
    pub carr_error_max: Option<f64>,
    /// The `aux2` relation.
    pub aux2: Aux2Rule,
    /// Whether `carr_error_filt_hz` = `carrier_doppler_hz` exactly in every record.
    pub filter_is_nco: bool,
    /// Whether the loop that wrote it is the one [`gsens_core::gnss_sdr`]
    /// models (so the importer can use it).
    pub modelled: bool,
}

fn fields(list: &[(&str, FieldType)]) -> Vec<(String, FieldType)> {
    list.iter().map(|(n, t)| ((*n).to_owned(), *t)).collect()
}

impl DumpLayout {
    /// The 96-byte `dll_pll_veml_tracking` record of GNSS-SDR 0.0.17 … 0.0.20 (module docs).
    pub fn v0_0_17() -> Self {
        use FieldType::*;
        DumpLayout {
            name: "gnss-sdr-0.0.17".into(),
            description: "GNSS-SDR 0.0.17 to 0.0.20 dll_pll_veml_tracking (GPS_L1_CA_DLL_PLL_Tracking); also \
                          dll_pll_veml_tracking_fpga 0.0.17 to 0.0.21, kf_vtl_tracking 0.0.17 and kf_tracking 0.0.18 to 0.0.21"
                .into(),
            fields: fields(&[
                ("abs_VE", F32),
                ("abs_E", F32),
                ("abs_P", F32),
                ("abs_L", F32),
                ("abs_VL", F32),
                ("Prompt_I", F32),
                ("Prompt_Q", F32),
                ("PRN_start_sample_count", U64),
                ("acc_carrier_phase_rad", F32),
                ("carrier_doppler_hz", F32),
                ("carrier_doppler_rate_hz", F32),
                ("code_freq_chips", F32),
                ("code_freq_rate_chips", F32),
                ("carr_error_hz", F32),
                ("carr_error_filt_hz", F32),
                ("code_error_chips", F32),
                ("code_error_filt_chips", F32),
                ("CN0_SNV_dB_Hz", F32),
                ("carrier_lock_test", F32),
                ("aux1", F32),
                ("aux2", F64),
                ("PRN", U32),
            ]),
            carr_error_max: Some(0.5),
            aux2: Aux2Rule::SameCounter,
            filter_is_nco: true,
            modelled: true,
        }
    }

    /// The 108-byte `dll_pll_veml_tracking` record from GNSS-SDR 0.0.21 on:
    /// [`DumpLayout::v0_0_17`] then `TOW_ms` (u64) and `WN` (u32) (module docs).
    pub fn v0_0_21() -> Self {
        let mut l = DumpLayout::v0_0_17();
        l.name = "gnss-sdr-0.0.21".into();
        l.description = "GNSS-SDR 0.0.21 and later dll_pll_veml_tracking (GPS_L1_CA_DLL_PLL_Tracking), with TOW_ms \
                         and WN"
            .into();
        l.fields.push(("TOW_ms".into(), FieldType::U64));
        l.fields.push(("WN".into(), FieldType::U32));
        l
    }

    /// The 96-byte record of the Gaussian/Kalman block `gps_l1_ca_kf_tracking_cc`
    /// (0.0.17; `gps_l1_ca_gaussian_tracking_cc` from 0.0.18 on) (module docs).
    pub fn kf_cc() -> Self {
        let mut l = DumpLayout::v0_0_17();
        l.name = "gnss-sdr-kf-cc".into();
        l.description = "GNSS-SDR 0.0.17 gps_l1_ca_kf_tracking_cc (GPS_L1_CA_KF_Tracking), 0.0.18 to 0.0.21 \
                         gps_l1_ca_gaussian_tracking_cc"
            .into();
        // GNSS-SDR's names for its slots (its save_matfile): the Doppler rate, then after
        // code_freq_chips the discriminator, its variance and (under the filter's name) the
        // remnant carrier phase·2π.
        let rename = [
            ("carrier_doppler_rate_hz", "carrier_dopplerrate_hz2"),
            ("code_freq_rate_chips", "carr_error_hz"),
            ("carr_error_hz", "carr_noise_sigma2"),
        ];
        for (n, _) in &mut l.fields {
            if let Some((_, to)) = rename.iter().find(|(from, _)| from == n) {
                *n = (*to).to_owned();
            }
        }
        // The slot after code_freq_chips holds the discriminator (rad·2π): |atan| ≤ π/2.
        l.carr_error_max = Some(core::f64::consts::PI * core::f64::consts::PI + 1e-3);
        l.aux2 = Aux2Rule::CounterPlusLength;
        l.filter_is_nco = false;
        l.modelled = false;
        l
    }

    /// The 88-byte record of the older DLL/PLL blocks (GLONASS, GPU, TCP
    /// connector): [`DumpLayout::v0_0_17`]'s fields without the Doppler rate
    /// and the code-rate rate, the counter at the start (module docs).
    pub fn legacy_88() -> Self {
        let mut l = DumpLayout::v0_0_17();
        l.name = "gnss-sdr-legacy-88".into();
        l.description = "GNSS-SDR 0.0.17 to 0.0.20 glonass_l1/l2_ca_dll_pll(_c_aid)_tracking, 0.0.17 to 0.0.21 \
                         gps_l1_ca_dll_pll_tracking_gpu_cc and the TCP-connector tracking blocks"
            .into();
        l.fields.retain(|(n, _)| n != "carrier_doppler_rate_hz" && n != "code_freq_rate_chips");
        // The GPU block writes 1/(cycles·T) as the discriminator, the TCP blocks 0.
        l.carr_error_max = None;
        l.aux2 = Aux2Rule::CounterPlusLength;
        l.filter_is_nco = false;
        l.modelled = false;
        l
    }

    /// The layouts the reader tries when none is given.
    pub fn known() -> Vec<DumpLayout> {
        vec![DumpLayout::v0_0_17(), DumpLayout::v0_0_21(), DumpLayout::kf_cc(), DumpLayout::legacy_88()]
    }

    /// Record size \[bytes\].
    pub fn record_bytes(&self) -> usize {
        self.fields.iter().map(|(_, t)| t.size()).sum()
    }

    /// A layout from a spec: the name of a [`DumpLayout::known`] one (e.g.
    /// `gnss-sdr-0.0.21`, to force it), or `name:type,name:type,…` (types f32,
    /// f64, u32, u64, i32) for dumps of versions or blocks the reader does not
    /// know. Those must contain the `REQUIRED_FIELDS`; only the generic
    /// plausibility rules are checked, and the importer treats them as the
    /// modelled loop's.
    pub fn parse_spec(spec: &str) -> Result<Self, LayoutSpecError> {
        if let Some(l) = DumpLayout::known().into_iter().find(|l| l.name == spec.trim()) {
            return Ok(l);
        }
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
        Ok(DumpLayout {
            name: "custom".into(),
            description: format!("custom layout `{spec}`"),
            fields,
            carr_error_max: Some(0.5),
            aux2: Aux2Rule::Unchecked,
            filter_is_nco: false,
            modelled: true,
        })
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

    /// `name (N bytes per record: description)`, as messages list it.
    pub fn summary(&self) -> String {
        format!("{} ({} bytes per record: {})", self.name, self.record_bytes(), self.description)
    }
}

/// One record of a tracking dump, whatever its layout (fields the layout lacks are NaN or `None`).
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
    /// Sample counter at the end of the integration (at its start for the
    /// layouts with `Aux2Rule::CounterPlusLength`).
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
    /// PLL discriminator output \[cycles\] (GNSS-SDR calls it `carr_error_hz`;
    /// rad·2π in [`DumpLayout::kf_cc`]).
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
    /// Time of week from the telemetry \[ms\] (0.0.21 on; 0 when not sent to the tracking).
    pub tow_ms: Option<u64>,
    /// Week number from the telemetry (0.0.21 on; 0 when unknown).
    pub wn: Option<u32>,
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
    /// The layout's blocks and versions ([`DumpLayout::description`]).
    pub layout_description: String,
    /// Whether the layout comes from the loop gsens models ([`DumpLayout::modelled`]).
    pub modelled: bool,
    /// The records, in file order.
    pub records: Vec<TrackingRecord>,
}

fn layouts_text(layouts: &[DumpLayout]) -> String {
    layouts.iter().map(DumpLayout::summary).collect::<Vec<_>>().join("; ")
}

/// Why a layout does not explain some bytes: the record, its offset and the field.
#[derive(Debug, Clone, PartialEq)]
struct Misfit {
    index: usize,
    offset: usize,
    reason: String,
}

/// Decodes and checks the whole records of `bytes` with `layout`: the records
/// up to the first implausible one, and why that one is (`None`: all good).
fn decode(bytes: &[u8], layout: &DumpLayout) -> (Vec<TrackingRecord>, Option<Misfit>) {
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
    let (tow, wn) = (get("TOW_ms"), get("WN"));
    let mut out = Vec::with_capacity(bytes.len() / size.max(1));
    let mut prev_count: Option<u64> = None;
    for (i, rec) in bytes.chunks_exact(size).enumerate() {
        let misfit = |reason: String| Some(Misfit { index: i, offset: i * size, reason });
        let v = o.map(|f| fld(rec, f));
        let n = match count.1 {
            FieldType::U64 => u64::from_le_bytes(rec[count.0..count.0 + 8].try_into().expect("8 bytes")),
            t => {
                let x = t.read(&rec[count.0..]);
                if !(x.is_finite() && x >= 0.0) {
                    return (out, misfit(format!("PRN_start_sample_count = {x} is not a sample count")));
                }
                x as u64
            }
        };
        let p = prn.1.read(&rec[prn.0..]);
        if !((1.0..=255.0).contains(&p) && p.fract() == 0.0) {
            return (out, misfit(format!("PRN = {p} is not a satellite number (1…255)")));
        }
        let int = |f: Option<(usize, FieldType)>| f.map(|(off, t)| t.read(&rec[off..]));
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
            tow_ms: tow.map(|(off, _)| u64::from_le_bytes(rec[off..off + 8].try_into().expect("8 bytes"))),
            wn: int(wn).map(|x| x as u32),
        };
        if let Some(reason) = implausible(&r, layout, n) {
            return (out, misfit(reason));
        }
        if let Some(prev) = prev_count
            && n <= prev
        {
            return (out, misfit(format!("PRN_start_sample_count {n} does not increase (previous record: {prev})")));
        }
        prev_count = Some(n);
        out.push(r);
    }
    (out, None)
}

/// The first field of `r` that `layout`'s writer cannot have written, and why.
fn implausible(r: &TrackingRecord, layout: &DumpLayout, n: u64) -> Option<String> {
    let correlators = [
        ("abs_VE", r.abs_ve),
        ("abs_E", r.abs_e),
        ("abs_P", r.abs_p),
        ("abs_L", r.abs_l),
        ("abs_VL", r.abs_vl),
        ("Prompt_I", r.prompt_i),
        ("Prompt_Q", r.prompt_q),
    ];
    for (name, x) in correlators {
        // NaN: the layout lacks the field.
        let magnitude = name.starts_with("abs");
        if !x.is_nan() && !(x.is_finite() && (!magnitude || x >= 0.0)) {
            return Some(format!(
                "{name} = {x} is not a correlator {}",
                if magnitude { "magnitude" } else { "output" }
            ));
        }
    }
    let e = r.carr_error_cycles;
    match layout.carr_error_max {
        Some(max) if !(e.is_finite() && e.abs() <= max + 1e-6) => {
            return Some(format!("carr_error_hz = {e} is not a PLL discriminator output (|x| ≤ {max:.4})"));
        }
        None if !e.is_finite() => return Some(format!("carr_error_hz = {e} is not finite")),
        _ => {}
    }
    if !(r.carrier_lock_test.is_finite() && r.carrier_lock_test.abs() <= 1.0 + 1e-4) {
        return Some(format!("carrier_lock_test = {} is outside [−1, 1]", r.carrier_lock_test));
    }
    if !(r.cn0_dbhz.is_finite() && (-50.0..=150.0).contains(&r.cn0_dbhz)) {
        return Some(format!("CN0_SNV_dB_Hz = {} is not a C/N0 in dB-Hz", r.cn0_dbhz));
    }
    if !(r.carrier_doppler_hz.is_finite() && r.carrier_doppler_hz.abs() < 1e6) {
        return Some(format!("carrier_doppler_hz = {} is not a Doppler", r.carrier_doppler_hz));
    }
    let c = r.code_freq_chips_per_s;
    if !(c.is_nan() || (c > 0.0 && c < 1e8)) {
        return Some(format!("code_freq_chips = {c} is not a code rate in chip/s"));
    }
    if layout.filter_is_nco && r.carr_error_filt_hz != r.carrier_doppler_hz {
        return Some(format!(
            "carr_error_filt_hz = {} differs from carrier_doppler_hz = {} (this block writes the one as the other)",
            r.carr_error_filt_hz, r.carrier_doppler_hz
        ));
    }
    match layout.aux2 {
        Aux2Rule::SameCounter if r.aux2 != n as f64 => {
            return Some(format!("aux2 = {} is not the sample counter {n}", r.aux2));
        }
        Aux2Rule::CounterPlusLength if !(r.aux2 > n as f64 && r.aux2 - (n as f64) < 1e9) => {
            return Some(format!("aux2 = {} is not the sample counter {n} plus an integration length", r.aux2));
        }
        _ => {}
    }
    if let Some(t) = r.tow_ms
        && t >= 604_800_000
    {
        return Some(format!("TOW_ms = {t} is not a time of week in ms (< 604800000)"));
    }
    if let Some(w) = r.wn
        && w > 65_535
    {
        return Some(format!("WN = {w} is not a week number"));
    }
    None
}

/// Decodes a dump held in memory. `file` names it in errors; `layout` forces
/// a layout, else the [`DumpLayout::known`] ones are tried (module docs).
pub fn parse_dump(bytes: &[u8], file: &str, layout: Option<&DumpLayout>) -> Result<TrackingDump, GnssSdrError> {
    let candidates: Vec<DumpLayout> = match layout {
        Some(l) => vec![l.clone()],
        None => DumpLayout::known(),
    };
    if bytes.is_empty() {
        return Err(GnssSdrError::EmptyDump { file: file.to_owned(), expected: layouts_text(&candidates) });
    }
    let len = bytes.len();
    let mut ok = Vec::new();
    let mut why = Vec::new();
    for l in candidates.iter().filter(|l| l.record_bytes() > 0) {
        let size = l.record_bytes();
        if !len.is_multiple_of(size) {
            why.push(format!(
                "{}: {len} bytes is {} records and {} bytes, not a whole number",
                l.summary(),
                len / size,
                len % size
            ));
            continue;
        }
        match decode(bytes, l) {
            (records, None) => ok.push((l, records)),
            (_, Some(m)) => {
                if candidates.len() == 1 {
                    return Err(GnssSdrError::BadRecord {
                        file: file.to_owned(),
                        index: m.index as u64,
                        offset: m.offset as u64,
                        layout: l.name.clone(),
                        reason: m.reason,
                    });
                }
                why.push(format!("{}: record {} (byte offset {}): {}", l.summary(), m.index, m.offset, m.reason))
            }
        }
    }
    let dump = |l: &DumpLayout, records| TrackingDump {
        file: file.to_owned(),
        channel: channel_from_name(file),
        layout: l.name.clone(),
        layout_description: l.description.clone(),
        modelled: l.modelled,
        records,
    };
    match ok.len() {
        1 => {
            let (l, records) = ok.pop().expect("one");
            return Ok(dump(l, records));
        }
        0 => {}
        _ => {
            return Err(GnssSdrError::AmbiguousLayout {
                file: file.to_owned(),
                len: len as u64,
                candidates: ok.iter().map(|(l, _)| l.name.clone()).collect::<Vec<_>>().join(", "),
            });
        }
    }
    if let Some(e) = mixed(bytes, file, &candidates) {
        return Err(e);
    }
    // A truncated dump: the whole records of one layout are good, a partial one follows.
    let truncated: Vec<(&DumpLayout, usize)> = candidates
        .iter()
        .filter(|l| l.record_bytes() > 0 && !len.is_multiple_of(l.record_bytes()) && len > l.record_bytes())
        .filter_map(|l| {
            let whole = len / l.record_bytes() * l.record_bytes();
            matches!(decode(&bytes[..whole], l), (_, None)).then_some((l, len / l.record_bytes()))
        })
        .collect();
    if let [(l, records)] = truncated[..] {
        return Err(GnssSdrError::TruncatedDump {
            file: file.to_owned(),
            len: len as u64,
            layout: l.summary(),
            records: records as u64,
            rest: (len % l.record_bytes()) as u64,
        });
    }
    Err(GnssSdrError::NoLayoutFits { file: file.to_owned(), len: len as u64, tried: why.join("; ") })
}

/// A dump that is records of one layout followed by records of another (a
/// file appended to by two versions): the error that says so, if it is one.
fn mixed(bytes: &[u8], file: &str, candidates: &[DumpLayout]) -> Option<GnssSdrError> {
    for a in candidates {
        let (good, _) = decode(bytes, a);
        // The first record of the second layout may pass as one of the first
        // (0.0.21's first 96 bytes are a 0.0.17 record): try a few boundaries.
        for k in (good.len().saturating_sub(3)..=good.len()).rev() {
            let at = k * a.record_bytes();
            if k == 0 || at >= bytes.len() {
                continue;
            }
            for b in candidates.iter().filter(|b| b.name != a.name) {
                let rest = &bytes[at..];
                if rest.len().is_multiple_of(b.record_bytes()) && matches!(decode(rest, b), (_, None)) {
                    return Some(GnssSdrError::MixedLayouts {
                        file: file.to_owned(),
                        first: a.summary(),
                        first_records: k as u64,
                        offset: at as u64,
                        second: b.summary(),
                        second_records: (rest.len() / b.record_bytes()) as u64,
                    });
                }
            }
        }
    }
    None
}

/// Whether `path` names a `.mat` dump.
pub(crate) fn is_mat(path: &Path) -> bool {
    path.extension().is_some_and(|e| e.eq_ignore_ascii_case("mat"))
}

/// Reads and decodes a dump file (see [`parse_dump`]); a `.mat` file through
/// [`crate::mat`].
pub fn read_dump(path: impl AsRef<Path>, layout: Option<&DumpLayout>) -> Result<TrackingDump, GnssSdrError> {
    let path = path.as_ref();
    let name = path.display().to_string();
    if is_mat(path) {
        return crate::mat::read_mat_dump(path, layout);
    }
    let bytes = std::fs::read(path).map_err(|e| GnssSdrError::Io { file: name.clone(), error: e })?;
    parse_dump(&bytes, &name, layout)
}

/// The channel number at the end of a dump's file stem (`trk_ch_12.dat` → 12).
pub(crate) fn channel_from_name(file: &str) -> Option<u32> {
    trailing_digits(file)?.parse().ok()
}

/// The digits a file's stem ends in (`trk_ch_12.dat` → `12`), `None` without any.
fn trailing_digits(file: &str) -> Option<&str> {
    let stem = Path::new(file).file_stem()?.to_str()?;
    let digits = stem.trim_end_matches(|c: char| c.is_ascii_digit());
    (digits.len() < stem.len()).then(|| &stem[digits.len()..])
}

/// The dumps in `dir`: files `<prefix><channel>.dat` (any prefix when `None`),
/// and `<prefix><channel>.mat` for the channels without a `.dat` (GNSS-SDR
/// writes the `.mat` from the `.dat`), sorted by channel. Errors when there is none.
pub fn find_dumps(dir: &Path, prefix: Option<&str>) -> Result<Vec<(u32, PathBuf)>, GnssSdrError> {
    let name = dir.display().to_string();
    let rd = std::fs::read_dir(dir).map_err(|e| GnssSdrError::Io { file: name.clone(), error: e })?;
    let mut out = Vec::new();
    for entry in rd {
        let entry = entry.map_err(|e| GnssSdrError::Io { file: name.clone(), error: e })?;
        let p = entry.path();
        let Some(fname) = p.file_name().and_then(|f| f.to_str()) else { continue };
        if !(fname.ends_with(".dat") || fname.ends_with(".mat")) || !p.is_file() {
            continue;
        }
        if let Some(pre) = prefix
            && !fname.starts_with(pre)
        {
            continue;
        }
        if let Some(ch) = channel_from_name(fname) {
            out.push((ch, p));
        } else if let Some(digits) = trailing_digits(fname) {
            // Digits beyond u32: no receiver's channel number.
            return Err(GnssSdrError::ChannelNumberOutOfRange { file: p.display().to_string(), digits: digits.into() });
        }
    }
    // A .mat only where its channel has no .dat (the same records, read more slowly).
    let dat_channels: Vec<u32> = out.iter().filter(|(_, p)| !is_mat(p)).map(|(c, _)| *c).collect();
    out.retain(|(c, p)| !is_mat(p) || !dat_channels.contains(c));
    if out.is_empty() {
        return Err(GnssSdrError::NoDumps { dir: name });
    }
    out.sort();
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The frame every GNSS-SDR tracking record shares: five |correlators| and
    /// the prompt I, Q (f32), the sample counter (uint64), the block's own
    /// floats (f32), `aux2` (double), the PRN (uint32).
    fn packed(counter: u64, floats: &[f32], aux2: f64, prn: u32) -> Vec<u8> {
        let mut b = Vec::with_capacity(40 + 4 * floats.len());
        for v in [1.0f32, 2.0, 3.0, 2.0, 1.0, 3.0, 0.1] {
            b.extend_from_slice(&v.to_le_bytes());
        }
        b.extend_from_slice(&counter.to_le_bytes());
        for v in floats {
            b.extend_from_slice(&v.to_le_bytes());
        }
        b.extend_from_slice(&aux2.to_le_bytes());
        b.extend_from_slice(&prn.to_le_bytes());
        b
    }

    /// A record as `dll_pll_veml_tracking::log_data` of GNSS-SDR v0.0.17 writes
    /// it (src/algorithms/tracking/gnuradio_blocks/dll_pll_veml_tracking.cc at
    /// tag v0.0.17): counter at the end; carrier phase, Doppler, Doppler rate,
    /// code rate, code-rate rate, discriminator (cycles), filter output (= the
    /// Doppler), code error and its filtered value, C/N0, lock test, remnant
    /// code phase; `aux2` = the counter.
    pub(crate) fn record_bytes(
        n: u64,
        carr_error_cycles: f32,
        doppler_hz: f32,
        cn0: f32,
        lock: f32,
        prn: u32,
    ) -> Vec<u8> {
        let f = [0.5f32, doppler_hz, 0.0, 1.023e6, 0.0, carr_error_cycles, doppler_hz, 0.01, 0.0, cn0, lock, 0.2];
        packed(n, &f, n as f64, prn)
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

    /// A 0.0.21 record, byte for byte as `dll_pll_veml_tracking::log_data` of
    /// GNSS-SDR v0.0.21 writes it (src/algorithms/tracking/gnuradio_blocks/
    /// dll_pll_veml_tracking.cc at tag v0.0.21): the 0.0.17 record, then the
    /// TOW \[ms\] as uint64 and the week number as uint32.
    pub(crate) fn record_bytes_v21(n: u64, carr_error_cycles: f32, prn: u32, tow_ms: u64, wn: u32) -> Vec<u8> {
        let mut b = record_bytes(n, carr_error_cycles, 1500.0, 45.0, 0.9, prn);
        b.extend_from_slice(&tow_ms.to_le_bytes());
        b.extend_from_slice(&wn.to_le_bytes());
        b
    }

    /// A record of `gps_l1_ca_kf_tracking_cc` as GNSS-SDR v0.0.17 writes it
    /// (src/algorithms/tracking/gnuradio_blocks/gps_l1_ca_kf_tracking_cc.cc at
    /// tag v0.0.17, `gps_l1_ca_gaussian_tracking_cc.cc` from v0.0.18 on): five
    /// |correlators| and the prompt (f32), the sample counter at the start
    /// (uint64), carrier phase, Doppler, Doppler rate, code rate, the
    /// discriminator in rad·2π, its variance, the remnant carrier phase·2π, the
    /// code error and its filtered value, C/N0, lock test, remnant code phase
    /// (f32), start + integration length (double), PRN (uint32).
    pub(crate) fn record_bytes_kf_cc(start: u64, len: u64, disc_rad: f32, prn: u32) -> Vec<u8> {
        let tau = core::f32::consts::TAU;
        let f = [0.5f32, 1500.0, 0.3, 1.023e6, disc_rad * tau, 0.02, 1.2 * tau, 0.01, 0.0, 45.0, 0.9, 0.2];
        packed(start, &f, (start + len) as f64, prn)
    }

    /// A record of `glonass_l1_ca_dll_pll_tracking_cc` as GNSS-SDR v0.0.17
    /// writes it (src/algorithms/tracking/gnuradio_blocks/
    /// glonass_l1_ca_dll_pll_tracking_cc.cc at tag v0.0.17; the GPU and TCP
    /// blocks write the same sizes): five |correlators| and the prompt (f32),
    /// the sample counter at the start (uint64), carrier phase, Doppler, code
    /// rate, the discriminator in cycles, the filter output, code error and
    /// its filtered value, C/N0, lock test, remnant code phase (f32), start +
    /// integration length (double), PRN (uint32) — no rate fields: 88 bytes.
    pub(crate) fn record_bytes_legacy_88(start: u64, len: u64, carr_error_cycles: f32, prn: u32) -> Vec<u8> {
        let f = [0.5f32, 1500.0, 511e3, carr_error_cycles, 3.0, 0.01, 0.0, 45.0, 0.9, 0.2];
        packed(start, &f, (start + len) as f64, prn)
    }

    fn concat(records: impl IntoIterator<Item = Vec<u8>>) -> Vec<u8> {
        records.into_iter().flatten().collect()
    }

    #[test]
    fn every_known_layout_is_recognised_from_constructed_records() {
        assert_eq!(DumpLayout::known().iter().map(DumpLayout::record_bytes).collect::<Vec<_>>(), [96, 108, 96, 88]);
        // 0.0.21: 8 records (864 bytes, also 9 records of 96: the 96-byte layouts must refuse them).
        let b = concat((1..=8u64).map(|k| record_bytes_v21(2048 * k, 0.01, 9, 345_600_000 + k, 2391)));
        assert_eq!(b.len() % 96, 0);
        let d = parse_dump(&b, "trk_ch_0.dat", None).unwrap();
        assert_eq!((d.layout.as_str(), d.records.len(), d.modelled), ("gnss-sdr-0.0.21", 8, true));
        let r = d.records[7];
        assert_eq!((r.tow_ms, r.wn, r.prn, r.prn_start_sample_count), (Some(345_600_008), Some(2391), 9, 16384));
        // kf_cc: same size as 0.0.17; told apart by aux2 = start + length.
        let b = concat((0..5u64).map(|k| record_bytes_kf_cc(2048 * k, 2048, 0.05, 11)));
        let d = parse_dump(&b, "trk_ch_1.dat", None).unwrap();
        assert_eq!((d.layout.as_str(), d.modelled), ("gnss-sdr-kf-cc", false));
        assert!((d.records[4].carr_error_cycles - 0.05 * core::f64::consts::TAU).abs() < 1e-5);
        assert!(d.layout_description.contains("gps_l1_ca_gaussian_tracking_cc"));
        // The 88-byte blocks.
        let b = concat((0..6u64).map(|k| record_bytes_legacy_88(2048 * k, 2048, -0.03, 4)));
        let d = parse_dump(&b, "trk_ch_2.dat", None).unwrap();
        assert_eq!((d.layout.as_str(), d.records.len(), d.modelled), ("gnss-sdr-legacy-88", 6, false));
        assert_eq!(d.records[5].code_freq_chips_per_s, 511e3);
        assert!(d.records[5].carrier_doppler_rate_hz_per_s.is_nan());
    }

    #[test]
    fn wrong_layouts_are_refused_field_by_field() {
        let v17 = concat((1..=9u64).map(|k| record_bytes(2048 * k, 0.01, 1500.0, 45.0, 0.9, 7)));
        let v21 = concat((1..=8u64).map(|k| record_bytes_v21(2048 * k, 0.01, 9, 1000 * k, 2391)));
        let kf = concat((0..9u64).map(|k| record_bytes_kf_cc(2048 * k, 2048, 0.05, 11)));
        // Forced onto another version's bytes (same length), each names record, offset and field.
        let e = parse_dump(&v17, "a.dat", Some(&DumpLayout::v0_0_21())).unwrap_err().to_string();
        assert!(e.starts_with("a.dat: record 0 (byte offset 0): ") && e.contains("layout gnss-sdr-0.0.21"), "{e}");
        let e = parse_dump(&v21, "b.dat", Some(&DumpLayout::v0_0_17())).unwrap_err().to_string();
        assert!(e.starts_with("b.dat: record 1 (byte offset 96): ") && e.contains("layout gnss-sdr-0.0.17"), "{e}");
        let e = parse_dump(&kf, "c.dat", Some(&DumpLayout::v0_0_17())).unwrap_err().to_string();
        assert!(e.contains("record 0 (byte offset 0): carr_error_filt_hz = 7.539") && e.contains("differs"), "{e}");
        let e = parse_dump(&v17, "d.dat", Some(&DumpLayout::kf_cc())).unwrap_err().to_string();
        assert!(e.contains("record 0 (byte offset 0): aux2 = 2048 is not the sample counter 2048 plus"), "{e}");
        // The filter-output = NCO relation of dll_pll_veml_tracking.
        let mut bad = v17.clone();
        bad[96 * 4 + 60..96 * 4 + 64].copy_from_slice(&1499.0f32.to_le_bytes());
        let e = parse_dump(&bad, "e.dat", Some(&DumpLayout::v0_0_17())).unwrap_err().to_string();
        assert!(e.contains("record 4 (byte offset 384): carr_error_filt_hz = 1499 differs"), "{e}");
        // A TOW past the end of the week.
        let bad = concat((1..=2u64).map(|k| record_bytes_v21(2048 * k, 0.01, 9, 604_800_000, 1)));
        let e = parse_dump(&bad, "f.dat", None).unwrap_err().to_string();
        assert!(e.contains("gnss-sdr-0.0.21 (108 bytes per record") && e.contains("TOW_ms = 604800000"), "{e}");
    }

    #[test]
    fn bad_dumps_get_clear_errors() {
        let e = parse_dump(&[], "trk_ch_0.dat", None).unwrap_err().to_string();
        assert!(e.contains("trk_ch_0.dat") && e.contains("empty") && e.contains("96 bytes per record"), "{e}");
        assert!(e.contains("108 bytes per record") && e.contains("88 bytes per record"), "{e}");
        // Truncated: one and a half records.
        let mut b = record_bytes(4000, 0.01, 1500.0, 45.0, 0.9, 7);
        b.extend_from_slice(&record_bytes(8000, 0.01, 1500.0, 45.0, 0.9, 7)[..48]);
        let e = parse_dump(&b, "trk_ch_1.dat", None).unwrap_err().to_string();
        assert!(
            e.contains("trk_ch_1.dat: truncated tracking dump: 144 bytes is 1 whole records of gnss-sdr-0.0.17"),
            "{e}"
        );
        assert!(e.contains("48 bytes of a partial one"), "{e}");
        // Truncated 0.0.21: its whole records name that layout.
        let mut b = concat((1..=3u64).map(|k| record_bytes_v21(2048 * k, 0.01, 9, 0, 0)));
        b.truncate(3 * 108 - 5);
        let e = parse_dump(&b, "t.dat", None).unwrap_err().to_string();
        assert!(e.contains("2 whole records of gnss-sdr-0.0.21") && e.contains("103 bytes of a partial one"), "{e}");
        // Garbage that fills whole 96-byte records: every layout tried, and why.
        let other: Vec<u8> = (0..48).flat_map(|i| (1e5f32 * i as f32 + 3.7).to_le_bytes()).collect();
        let e = parse_dump(&other, "trk_ch_2.dat", None).unwrap_err().to_string();
        assert!(e.starts_with("trk_ch_2.dat: 192 bytes fits no tracking-dump layout"), "{e}");
        for l in DumpLayout::known() {
            assert!(e.contains(&format!("{} ({} bytes per record", l.name, l.record_bytes())), "{e}");
        }
        assert!(
            e.contains("gnss-sdr-0.0.17 (96 bytes per record") && e.contains("record 0 (byte offset 0): PRN ="),
            "{e}"
        );
        assert!(e.contains("192 bytes is 1 records and 84 bytes, not a whole number"), "{e}");
        // A bad value deep in a file names the record and its offset.
        let mut b = Vec::new();
        for k in 0..5u64 {
            b.extend(record_bytes(4000 * (k + 1), if k == 3 { 3.0 } else { 0.01 }, 1500.0, 45.0, 0.9, 7));
        }
        let e = parse_dump(&b, "trk_ch_4.dat", None).unwrap_err().to_string();
        assert!(e.contains("record 3 (byte offset 288): carr_error_hz = 3"), "{e}");
        // The sample counter must increase.
        let mut b = record_bytes(8000, 0.01, 1500.0, 45.0, 0.9, 7);
        b.extend(record_bytes(4000, 0.01, 1500.0, 45.0, 0.9, 7));
        let e = parse_dump(&b, "trk_ch_5.dat", None).unwrap_err().to_string();
        assert!(e.contains("record 1 (byte offset 96): PRN_start_sample_count 4000 does not increase"), "{e}");
    }

    #[test]
    fn a_file_appended_by_two_versions_is_named_mixed() {
        // Three 0.0.17 records, then four 0.0.21 records (a dump_filename reused by an upgraded receiver).
        let mut b = concat((1..=3u64).map(|k| record_bytes(2048 * k, 0.01, 1500.0, 45.0, 0.9, 7)));
        b.extend(concat((10..14u64).map(|k| record_bytes_v21(2048 * k, 0.01, 7, 0, 0))));
        let e = parse_dump(&b, "trk_ch_6.dat", None).unwrap_err().to_string();
        assert!(e.starts_with("trk_ch_6.dat: mixed tracking-dump layouts: 3 records of gnss-sdr-0.0.17"), "{e}");
        assert!(e.contains("from byte offset 288 4 records of gnss-sdr-0.0.21"), "{e}");
        // And the other way round.
        let mut b = concat((1..=2u64).map(|k| record_bytes_v21(2048 * k, 0.01, 7, 0, 0)));
        b.extend(concat((10..15u64).map(|k| record_bytes(2048 * k, 0.01, 1500.0, 45.0, 0.9, 7))));
        let e = parse_dump(&b, "trk_ch_7.dat", None).unwrap_err().to_string();
        assert!(
            e.contains("2 records of gnss-sdr-0.0.21")
                && e.contains("from byte offset 216 5 records of gnss-sdr-0.0.17"),
            "{e}"
        );
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
        assert_eq!(DumpLayout::parse_spec(" gnss-sdr-0.0.21 ").unwrap(), DumpLayout::v0_0_21());
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
