//! `komplex trace --rays`: many rays read from a CSV or `.npy` file, traced
//! in one batch ([`Complex::trace_many`](complex::Complex::trace_many)),
//! and every ray's partition written as CSV or JSON.

use std::fmt::Write as _;
use std::path::Path;

use complex::Traces;
use quadric::nalgebra::{Point3, Vector3};
use quadric::Ray;
use serde::Serialize;

use crate::error::Error;
use crate::trace::SegmentReport;
use crate::world::World;

/// Reads rays from `path`: a `.npy` file (by its extension, any case) or
/// else CSV. Each ray is an origin and a direction (normalised, as
/// `komplex trace` normalises it).
///
/// CSV: six numbers a line, `ox,oy,oz,dx,dy,dz`; blank lines and lines
/// starting with `#` are skipped, and a first line with no number in it
/// is a header. `.npy`: a little-endian float64 (`<f8`) or float32 (`<f4`)
/// array of shape `(N, 6)` or `(N, 2, 3)`, C or Fortran order.
///
/// Errors name the file and the line and column (CSV), the header's
/// problem or the ray (`.npy`); a zero or non-finite direction, or a
/// non-finite origin, names the ray (0-based, as in the output).
pub fn read(path: &Path) -> Result<Vec<Ray>, Error> {
    let bytes = std::fs::read(path).map_err(|source| Error::Io { path: path.to_path_buf(), source })?;
    let bad = |message: String| Error::Data { file: path.to_path_buf(), message };
    let npy = path.extension().and_then(|e| e.to_str()).is_some_and(|e| e.eq_ignore_ascii_case("npy"));
    if npy {
        parse_npy(&bytes).map_err(bad)
    } else {
        let text = std::str::from_utf8(&bytes).map_err(|e| {
            let line = bytes[..e.valid_up_to()].iter().filter(|&&b| b == b'\n').count() + 1;
            bad(format!("line {line}: the file is not UTF-8 text (byte {})", e.valid_up_to() + 1))
        })?;
        parse_csv(text).map_err(bad)
    }
}

/// A ray from six numbers; `place` names it in an error.
fn ray(v: [f64; 6], place: impl FnOnce() -> String) -> Result<Ray, String> {
    Ray::new(Point3::new(v[0], v[1], v[2]), Vector3::new(v[3], v[4], v[5])).map_err(|e| format!("{}: {e}", place()))
}

/// The rays of a CSV text, or a message naming the line and column.
///
/// ```
/// let rays = render::rays::parse_csv("ox,oy,oz,dx,dy,dz\n# two rays\n0,0,5, 0,0,-1\n\n1,0,5,0,0,-2\n").unwrap();
/// assert_eq!(rays.len(), 2);
/// assert_eq!(rays[1].direction().as_slice(), [0.0, 0.0, -1.0]);
/// let err = render::rays::parse_csv("0,0,5,0,0,-1\n0,0,five,0,0,-1\n").unwrap_err();
/// assert_eq!(err, "line 2, column 5: \"five\" is not a number");
/// ```
pub fn parse_csv(text: &str) -> Result<Vec<Ray>, String> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut rays = Vec::new();
    let mut header_allowed = true;
    for (k, line) in text.lines().enumerate() {
        let n = k + 1;
        let content = line.trim();
        if content.is_empty() || content.starts_with('#') {
            continue;
        }
        // Each field with its 1-based column (of its first character).
        let mut fields = Vec::with_capacity(6);
        let mut start = 0;
        for field in line.split(',') {
            let lead = field.len() - field.trim_start().len();
            fields.push((line[..start + lead].chars().count() + 1, field.trim()));
            start += field.len() + 1;
        }
        let numbers: Vec<Option<f64>> = fields.iter().map(|(_, f)| f.parse::<f64>().ok()).collect();
        let was_header_allowed = std::mem::replace(&mut header_allowed, false);
        if was_header_allowed && numbers.iter().all(Option::is_none) {
            continue;
        }
        if fields.len() != 6 {
            return Err(format!(
                "line {n}: expected 6 numbers (ox,oy,oz,dx,dy,dz), found {} field{}",
                fields.len(),
                if fields.len() == 1 { "" } else { "s" }
            ));
        }
        let mut v = [0.0; 6];
        for ((x, (column, field)), parsed) in v.iter_mut().zip(&fields).zip(&numbers) {
            *x = parsed.ok_or_else(|| format!("line {n}, column {column}: \"{field}\" is not a number"))?;
        }
        let index = rays.len();
        rays.push(ray(v, || format!("line {n} (ray {index})"))?);
    }
    Ok(rays)
}

/// The `.npy` magic string.
const NPY_MAGIC: &[u8] = b"\x93NUMPY";

/// The value of `key` in a `.npy` header (a Python dict literal): the text
/// after `'key':` up to the next top-level comma or the closing brace.
fn header_value<'a>(header: &'a str, key: &str) -> Result<&'a str, String> {
    let quoted = [format!("'{key}'"), format!("\"{key}\"")];
    let at = quoted.iter().find_map(|q| header.find(q.as_str()).map(|i| i + q.len()));
    let rest = at.map(|i| header[i..].trim_start()).and_then(|r| r.strip_prefix(':'));
    let Some(rest) = rest.map(str::trim_start) else {
        return Err(format!("header: no '{key}' in {}", header.trim()));
    };
    let mut depth = 0;
    for (i, c) in rest.char_indices() {
        match c {
            '(' | '[' => depth += 1,
            ')' | ']' => depth -= 1,
            ',' | '}' if depth == 0 => return Ok(rest[..i].trim()),
            _ => {}
        }
    }
    Ok(rest.trim())
}

/// The rays of a `.npy` file's bytes, or a message naming the header's
/// problem or the ray.
///
/// ```
/// // What `numpy.save` writes for `np.array([[0, 0, 5, 0, 0, -2]], dtype="<f4")`.
/// let header = "{'descr': '<f4', 'fortran_order': False, 'shape': (1, 6), }";
/// let mut bytes = b"\x93NUMPY\x01\x00".to_vec();
/// bytes.extend_from_slice(&(header.len() as u16).to_le_bytes());
/// bytes.extend_from_slice(header.as_bytes());
/// bytes.extend([0.0f32, 0.0, 5.0, 0.0, 0.0, -2.0].iter().flat_map(|x| x.to_le_bytes()));
/// let rays = render::rays::parse_npy(&bytes).unwrap();
/// assert_eq!(rays[0].origin(), [0.0, 0.0, 5.0].into());
/// assert_eq!(rays[0].direction().as_slice(), [0.0, 0.0, -1.0]);
/// let wrong = bytes.len() - 4;
/// assert_eq!(
///     render::rays::parse_npy(&bytes[..wrong]).unwrap_err(),
///     "the data holds 20 bytes; the shape (1, 6) of '<f4' needs 24 bytes"
/// );
/// ```
pub fn parse_npy(bytes: &[u8]) -> Result<Vec<Ray>, String> {
    if !bytes.starts_with(NPY_MAGIC) || bytes.len() < 10 {
        return Err("not a .npy file (it does not start with \\x93NUMPY)".into());
    }
    let (len, start) = match bytes[6] {
        1 => (usize::from(u16::from_le_bytes([bytes[8], bytes[9]])), 10),
        2 | 3 if bytes.len() >= 12 => (u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]) as usize, 12),
        v => return Err(format!("header: .npy format version {v} is not supported (1, 2 or 3 are)")),
    };
    let header = bytes.get(start..start + len).ok_or("header: the file ends inside the header")?;
    let header = std::str::from_utf8(header).map_err(|_| "header: not text".to_string())?;
    let descr = header_value(header, "descr")?;
    let size = match descr.trim_matches(|c| c == '\'' || c == '"') {
        "<f8" => 8,
        "<f4" => 4,
        _ => {
            return Err(format!(
                "header: the array's type is {descr}; only little-endian float64 ('<f8') or float32 ('<f4') are read"
            ))
        }
    };
    let fortran = match header_value(header, "fortran_order")? {
        "False" => false,
        "True" => true,
        other => return Err(format!("header: fortran_order is {other}, not True or False")),
    };
    let shape_text = header_value(header, "shape")?;
    let shape: Option<Vec<usize>> = shape_text
        .strip_prefix('(')
        .and_then(|s| s.strip_suffix(')'))
        .map(|s| s.split(',').map(str::trim).filter(|d| !d.is_empty()).map(|d| d.parse().ok()).collect())
        .and_then(|d: Option<Vec<usize>>| d);
    let n = match shape.as_deref() {
        Some(&[n, 6]) | Some(&[n, 2, 3]) => n,
        _ => return Err(format!("header: the shape is {shape_text}; expected (N, 6) or (N, 2, 3)")),
    };
    let data = &bytes[start + len..];
    let needed = n.checked_mul(6 * size);
    if needed != Some(data.len()) {
        let needed = needed.map_or_else(|| "more than fits in memory".to_string(), |b| format!("{b} bytes"));
        return Err(format!("the data holds {} bytes; the shape {shape_text} of {descr} needs {needed}", data.len()));
    }
    let value = |e: usize| -> f64 {
        let b = &data[e * size..(e + 1) * size];
        match b.try_into() {
            Ok(b8) => f64::from_le_bytes(b8),
            // Four bytes: float32, widened exactly.
            Err(_) => f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
        }
    };
    // Component `k` of row `i`: C order puts a row's six together (for
    // `(N, 2, 3)` too); Fortran order puts the rows' first components
    // together, then the second ones, and so on (for `(N, 2, 3)`,
    // component `3a + b` is element `(i, a, b)` at `i + N·a + 2N·b`).
    let three = shape.as_deref().is_some_and(|s| s.len() == 3);
    let element = |i: usize, k: usize| match (fortran, three) {
        (false, _) => 6 * i + k,
        (true, false) => i + n * k,
        (true, true) => i + n * (k / 3) + 2 * n * (k % 3),
    };
    (0..n).map(|i| ray(std::array::from_fn(|k| value(element(i, k))), || format!("ray {i}"))).collect()
}

/// Every ray's segments ([`Complex::trace_many`](complex::Complex::trace_many):
/// parallel on rayon's current pool, each ray's exactly its partition's).
pub fn trace(world: &World, rays: &[Ray]) -> Traces {
    let mut traces = Traces::new();
    world.complex.trace_many(rays, &mut traces);
    traces
}

/// A CSV field, quoted when it holds a comma, quote or line break.
fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// The segments as CSV: a header `ray,start,end,block,name`, then one line
/// a segment: the 0-based ray, its start and end (shortest round-trip
/// decimals, `inf` for the last end), the 1-based owner block (0 for empty
/// space) and its name (empty for empty space; quoted when it holds a
/// comma, quote or line break).
///
/// ```
/// let text = r#"{ "camera": { "eye": [0, 0, 5], "direction": [0, 0, -1] },
///   "blocks": [ { "name": "ball", "objects": [ { "sphere": {} } ] } ] }"#;
/// let world = render::format::SceneFile::from_json(text).unwrap().to_world().unwrap();
/// let rays = render::rays::parse_csv("0,0,5,0,0,-1").unwrap();
/// let csv = render::rays::to_csv(&world, &render::rays::trace(&world, &rays));
/// assert_eq!(csv, "ray,start,end,block,name\n0,0.0,4.0,0,\n0,4.0,6.0,1,ball\n0,6.0,inf,0,\n");
/// ```
pub fn to_csv(world: &World, traces: &Traces) -> String {
    let mut out = String::from("ray,start,end,block,name\n");
    for (i, segments) in traces.iter().enumerate() {
        for s in segments {
            let end = if s.end.is_finite() { format!("{:?}", s.end) } else { "inf".to_string() };
            let (block, name) = match s.owner {
                Some(b) => (b.0 + 1, csv_field(world.complex.block(b).name())),
                None => (0, String::new()),
            };
            // Writing to a String cannot fail.
            let _ = writeln!(out, "{i},{:?},{end},{block},{name}", s.start);
        }
    }
    out
}

/// One ray's segments, as `komplex trace --json` reports them.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RayReport {
    /// The partition of the ray.
    pub segments: Vec<SegmentReport>,
}

/// What `komplex trace --rays FILE --json` prints.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RaysReport {
    /// Each ray's report, in the file's order.
    pub rays: Vec<RayReport>,
}

/// The segments as one JSON document `{"rays": [{"segments": [...]}, ...]}`
/// (and a line break), each segment as in `komplex trace --json`.
///
/// ```
/// let text = r#"{ "camera": { "eye": [0, 0, 5], "direction": [0, 0, -1] },
///   "blocks": [ { "name": "ball", "objects": [ { "sphere": {} } ] } ] }"#;
/// let world = render::format::SceneFile::from_json(text).unwrap().to_world().unwrap();
/// let rays = render::rays::parse_csv("0,0,5,0,0,-1\n0,3,5,0,0,-1").unwrap();
/// let json = render::rays::to_json(&world, &render::rays::trace(&world, &rays)).unwrap();
/// let v: serde_json::Value = serde_json::from_str(&json).unwrap();
/// assert_eq!(v["rays"][0]["segments"][1]["name"], "ball");
/// assert_eq!(v["rays"][1]["segments"].as_array().unwrap().len(), 1); // a miss: empty space to infinity
/// assert!(v["rays"][1]["segments"][0]["end"].is_null());
/// ```
pub fn to_json(world: &World, traces: &Traces) -> Result<String, Error> {
    let rays = traces
        .iter()
        .map(|s| RayReport { segments: s.iter().map(|s| SegmentReport::new(&world.complex, s)).collect() })
        .collect();
    let mut text = serde_json::to_string(&RaysReport { rays }).map_err(|e| Error::Options(e.to_string()))?;
    text.push('\n');
    Ok(text)
}
