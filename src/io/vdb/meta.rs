//! Metadata, as OpenVDB stores it (`io/Archive.cc`, `MetaMap::writeMeta`):
//! a count, then per entry a name, a type name and the value's bytes, each
//! string length-prefixed. The file's and every grid's metadata are such
//! maps.

/// A per-grid metadata value (OpenVDB `TypedMetadata` types).
#[derive(Clone, Debug, PartialEq)]
pub enum MetaValue {
    String(String),
    Int64(i64),
    Float(f32),
    Double(f64),
    Bool(bool),
    Vec3i([i32; 3]),
    Vec3d([f64; 3]),
}

pub(super) fn push_string(out: &mut Vec<u8>, s: &str) {
    out.extend_from_slice(&(s.len() as u32).to_le_bytes());
    out.extend_from_slice(s.as_bytes());
}

pub(super) fn push_dvec3(out: &mut Vec<u8>, v: [f64; 3]) {
    for x in v {
        out.extend_from_slice(&x.to_le_bytes());
    }
}

/// Encodes one metadata entry as (type name, value bytes).
pub(super) fn meta_bytes(v: &MetaValue) -> (&'static str, Vec<u8>) {
    match v {
        MetaValue::String(s) => ("string", s.as_bytes().to_vec()),
        MetaValue::Int64(x) => ("int64", x.to_le_bytes().to_vec()),
        MetaValue::Float(x) => ("float", x.to_le_bytes().to_vec()),
        MetaValue::Double(x) => ("double", x.to_le_bytes().to_vec()),
        MetaValue::Bool(b) => ("bool", vec![*b as u8]),
        MetaValue::Vec3i(v) => ("vec3i", v.iter().flat_map(|x| x.to_le_bytes()).collect()),
        MetaValue::Vec3d(v) => ("vec3d", v.iter().flat_map(|x| x.to_le_bytes()).collect()),
    }
}

/// MetaMap with keys in byte order (OpenVDB's `std::map<Name, ...>`).
pub(super) fn write_meta_map(out: &mut Vec<u8>, mut entries: Vec<(String, MetaValue)>) {
    entries.sort_by(|a, b| a.0.as_bytes().cmp(b.0.as_bytes()));
    out.extend_from_slice(&(entries.len() as u32).to_le_bytes());
    for (k, v) in &entries {
        let (type_name, bytes) = meta_bytes(v);
        push_string(out, k);
        push_string(out, type_name);
        out.extend_from_slice(&(bytes.len() as u32).to_le_bytes());
        out.extend_from_slice(&bytes);
    }
}
