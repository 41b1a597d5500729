//! GNSS-SDR's `.mat` tracking dumps: at the end of a run with
//! `Tracking_1C.dump=true` and `dump_mat=true` (the default) each tracking
//! block reads its `.dat` dump back and writes `<dump_filename><channel>.mat`,
//! a MATLAB v7.3 file — an HDF5 file with a 512-byte user block — holding one
//! 1 × N array per record field, named as the fields of
//! [`crate::dump::DumpLayout`] (`save_matfile` in
//! `dll_pll_veml_tracking.cc`, through matio: each array chunked and
//! deflated).
//!
//! The file is read by a reader of exactly the part of HDF5 that matio writes
//! for such arrays (superblock 0 or 1, a symbol-table root group, version-1
//! object headers, compact, contiguous or chunked data, deflate), written in
//! Rust here, so no HDF5 library is needed; anything else in the file is
//! refused with an error naming what was found.
//!
//! The reader finds the layout whose field names are exactly the file's
//! variables, packs the arrays back into that layout's little-endian records
//! (each value converted to the field's `.dat` type only when the conversion
//! is exact: 0.0.21 writes `WN` as uint32 to the `.dat` and as int32 to the
//! `.mat`), and decodes them with the `.dat` reader
//! ([`crate::dump::parse_dump`]) with that layout: the same
//! checks, the same conversion, the same records bit for bit as the run's
//! `.dat`.

use std::collections::BTreeMap;
use std::path::Path;

mod h5;

use h5::{Array, ElemType, H5File};

use crate::dump::{DumpLayout, FieldType, TrackingDump, parse_dump};
use crate::error::GnssSdrError;

/// One array of a `.mat` file, as read.
enum Column {
    F32(Vec<f32>),
    F64(Vec<f64>),
    U32(Vec<u32>),
    U64(Vec<u64>),
    I32(Vec<i32>),
}

impl Column {
    /// The elements of `ty` that `bytes` holds, little-endian.
    fn from_le_bytes(ty: ElemType, bytes: &[u8]) -> Column {
        fn each<const N: usize, T>(bytes: &[u8], f: fn([u8; N]) -> T) -> Vec<T> {
            bytes.chunks_exact(N).map(|c| f(c.try_into().expect("chunks of N bytes"))).collect()
        }
        match ty {
            ElemType::F32 => Column::F32(each(bytes, f32::from_le_bytes)),
            ElemType::F64 => Column::F64(each(bytes, f64::from_le_bytes)),
            ElemType::U32 => Column::U32(each(bytes, u32::from_le_bytes)),
            ElemType::U64 => Column::U64(each(bytes, u64::from_le_bytes)),
            ElemType::I32 => Column::I32(each(bytes, i32::from_le_bytes)),
        }
    }

    fn len(&self) -> usize {
        match self {
            Column::F32(v) => v.len(),
            Column::F64(v) => v.len(),
            Column::U32(v) => v.len(),
            Column::U64(v) => v.len(),
            Column::I32(v) => v.len(),
        }
    }

    /// Element `i` as the little-endian bytes of `ty`, if the conversion is exact.
    fn bytes(&self, i: usize, ty: FieldType) -> Option<Vec<u8>> {
        // Every value as an exact i128 or f64 first.
        let int: Option<i128> = match self {
            Column::U32(v) => Some(i128::from(v[i])),
            Column::U64(v) => Some(i128::from(v[i])),
            Column::I32(v) => Some(i128::from(v[i])),
            Column::F32(_) | Column::F64(_) => None,
        };
        let float: Option<f64> = match self {
            Column::F32(v) => Some(f64::from(v[i])),
            Column::F64(v) => Some(v[i]),
            _ => None,
        };
        match ty {
            FieldType::F32 => match self {
                Column::F32(v) => Some(v[i].to_le_bytes().to_vec()),
                _ => {
                    let x = float.or(int.map(|n| n as f64))?;
                    let y = x as f32;
                    (f64::from(y) == x || x.is_nan()).then(|| y.to_le_bytes().to_vec())
                }
            },
            FieldType::F64 => match self {
                Column::F64(v) => Some(v[i].to_le_bytes().to_vec()),
                Column::F32(v) => Some(f64::from(v[i]).to_le_bytes().to_vec()),
                _ => {
                    let n = int?;
                    let x = n as f64;
                    (x as i128 == n).then(|| x.to_le_bytes().to_vec())
                }
            },
            FieldType::U32 => u32::try_from(int?).ok().map(|n| n.to_le_bytes().to_vec()),
            FieldType::U64 => u64::try_from(int?).ok().map(|n| n.to_le_bytes().to_vec()),
            FieldType::I32 => i32::try_from(int?).ok().map(|n| n.to_le_bytes().to_vec()),
        }
    }
}

fn mat_err(file: &str, reason: impl Into<String>) -> GnssSdrError {
    GnssSdrError::Mat { file: file.to_owned(), reason: reason.into() }
}

/// Reads a `.mat` tracking dump (module docs). `layout` forces a layout, else
/// the [`DumpLayout::known`] one whose fields are the file's variables.
pub fn read_mat_dump(path: impl AsRef<Path>, layout: Option<&DumpLayout>) -> Result<TrackingDump, GnssSdrError> {
    let path = path.as_ref();
    let name = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|e| GnssSdrError::Io { file: name.clone(), error: e })?;
    parse_mat_dump(&bytes, &name, layout)
}

/// Decodes the bytes of a `.mat` tracking dump named `name` (see [`read_mat_dump`]).
pub fn parse_mat_dump(bytes: &[u8], name: &str, layout: Option<&DumpLayout>) -> Result<TrackingDump, GnssSdrError> {
    let file = H5File::open(bytes).map_err(|e| mat_err(name, format!("not a MATLAB v7.3 (HDF5) file: {e}")))?;
    let members = file.members().map_err(|e| mat_err(name, format!("cannot list its variables: {e}")))?;
    let mut vars: Vec<String> = members.iter().map(|(n, _)| n.clone()).collect();
    vars.sort();
    let layout = match layout {
        Some(l) => l.clone(),
        None => {
            let fits = |l: &DumpLayout| {
                let mut f: Vec<&str> = l.fields.iter().map(|(n, _)| n.as_str()).collect();
                f.sort_unstable();
                f == vars.iter().map(String::as_str).collect::<Vec<_>>()
            };
            let known = DumpLayout::known();
            let mut fitting: Vec<DumpLayout> = known.iter().filter(|l| fits(l)).cloned().collect();
            match fitting.len() {
                0 => {
                    let tried = known
                        .iter()
                        .map(|l| {
                            let missing: Vec<&str> = l
                                .fields
                                .iter()
                                .map(|(n, _)| n.as_str())
                                .filter(|n| !vars.iter().any(|v| v == n))
                                .collect();
                            let extra: Vec<&str> = vars
                                .iter()
                                .map(String::as_str)
                                .filter(|v| !l.fields.iter().any(|(n, _)| n == v))
                                .collect();
                            format!("{}: lacks [{}], has more [{}]", l.name, missing.join(", "), extra.join(", "))
                        })
                        .collect::<Vec<_>>()
                        .join("; ");
                    return Err(mat_err(
                        name,
                        format!(
                            "its variables [{}] are the fields of no known tracking-dump layout ({tried})",
                            vars.join(", ")
                        ),
                    ));
                }
                1 => fitting.pop().expect("one"),
                // Same names, other meanings (0.0.17 and kf-cc): the records decide, as for a `.dat`.
                _ => return read_fitting(&file, &members, name, &fitting),
            }
        }
    };
    read_fitting(&file, &members, name, std::slice::from_ref(&layout))
}

/// Packs the arrays into the records of each of `layouts` (same field names)
/// and returns the first whose records are plausible.
fn read_fitting(
    file: &H5File<'_>,
    members: &[(String, u64)],
    name: &str,
    layouts: &[DumpLayout],
) -> Result<TrackingDump, GnssSdrError> {
    // Each variable read once, whichever layouts share it.
    let mut columns = BTreeMap::new();
    for (field, _) in layouts.iter().flat_map(|l| &l.fields) {
        if columns.contains_key(field.as_str()) {
            continue;
        }
        let &(_, addr) = members
            .iter()
            .find(|(n, _)| n == field)
            .ok_or_else(|| mat_err(name, format!("variable `{field}` is not in the file")))?;
        let Array { shape, ty, bytes } =
            file.dataset(addr, &format!("variable `{field}`")).map_err(|e| mat_err(name, e))?;
        if shape.iter().filter(|&&d| d != 1).count() > 1 {
            return Err(mat_err(name, format!("variable `{field}` is a {shape:?} array, not a 1 × N row")));
        }
        columns.insert(field.as_str(), Column::from_le_bytes(ty, &bytes));
    }
    let mut last = None;
    for layout in layouts {
        let bytes = pack(&columns, name, layout)?;
        match parse_dump(&bytes, name, Some(layout)) {
            Ok(d) => return Ok(d),
            Err(e) => last = Some(e),
        }
    }
    Err(last.expect("at least one layout"))
}

/// The arrays of the file (by variable name) as the `.dat` records of `layout`.
fn pack(arrays: &BTreeMap<&str, Column>, name: &str, layout: &DumpLayout) -> Result<Vec<u8>, GnssSdrError> {
    let columns: Vec<&Column> = layout.fields.iter().map(|(f, _)| &arrays[f.as_str()]).collect();
    let n = columns.first().map_or(0, |c| c.len());
    if let Some(((field, _), c)) = layout.fields.iter().zip(&columns).find(|(_, c)| c.len() != n) {
        return Err(mat_err(
            name,
            format!("variable `{field}` has {} values, `{}` has {n}", c.len(), layout.fields[0].0),
        ));
    }
    let mut bytes = Vec::with_capacity(n * layout.record_bytes());
    for i in 0..n {
        for ((field, ty), c) in layout.fields.iter().zip(&columns) {
            let b = c.bytes(i, *ty).ok_or_else(|| {
                mat_err(name, format!("record {i}: variable `{field}` does not fit the dump's {ty:?} exactly"))
            })?;
            bytes.extend_from_slice(&b);
        }
    }
    Ok(bytes)
}
