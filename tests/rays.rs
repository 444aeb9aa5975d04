//! `komplex trace --rays FILE`: every ray of a CSV or `.npy` file gets the
//! partition a single `komplex trace --json` gives it, whatever the file's
//! format (CSV, float64 or float32, C or Fortran order, `(N, 6)` or
//! `(N, 2, 3)`), and the CSV output says the same as the JSON.

use serde_json::Value;

use crate::support::{komplex_ok, python, scene, tempdir};

/// Rays through the example scenes: along axes, aimed at the middle,
/// grazing, from inside, missing.
const RAYS: [[f64; 6]; 8] = [
    [0.0, 3.0, 0.0, 0.0, -1.0, 0.0],
    [0.3, 3.0, 0.2, 0.0, -1.0, 0.0],
    [-4.0, 1.0, 0.0, 1.0, 0.0, 0.0],
    [0.0, 2.2, 6.0, 0.0, -0.3, -1.0],
    [0.75, 0.5, 0.0, 0.0, 1.0, 0.0],
    [5.0, 5.0, 5.0, -1.0, -1.1, -0.9],
    [0.0, 50.0, 0.0, 1.0, 0.0, 0.0],
    [-1.5, 0.9, -0.25, 0.25, 0.1, 0.07],
];

/// `trace --json` of one ray: its segments.
fn single(scene_path: &str, r: &[f64; 6]) -> Value {
    let dir = tempdir();
    let s: Vec<String> = r.iter().map(|v| format!("{v:?}")).collect();
    let mut args = vec!["trace", scene_path, "--json", "--origin"];
    args.extend(s[..3].iter().map(String::as_str));
    args.push("--direction");
    args.extend(s[3..].iter().map(String::as_str));
    let out = komplex_ok(dir.path(), &args);
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    v["segments"].clone()
}

/// A `.npy` file of `values` (little-endian, `descr`), written by hand.
fn npy(descr: &str, fortran: bool, shape: &str, data: &[u8]) -> Vec<u8> {
    let mut header = format!(
        "{{'descr': '{descr}', 'fortran_order': {}, 'shape': {shape}, }}",
        if fortran { "True" } else { "False" }
    );
    // The header is padded with spaces to a multiple of 64 bytes, ending in a newline.
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    let mut out = b"\x93NUMPY\x01\x00".to_vec();
    out.extend_from_slice(&(header.len() as u16).to_le_bytes());
    out.extend_from_slice(header.as_bytes());
    out.extend_from_slice(data);
    out
}

fn f64_bytes(values: impl IntoIterator<Item = f64>) -> Vec<u8> {
    values.into_iter().flat_map(f64::to_le_bytes).collect()
}

/// The rays in Fortran order: component by component (for `(N, 2, 3)`,
/// element `(i, a, b)` at `i + N·a + 2N·b`).
fn fortran(rays: &[[f64; 6]], three: bool) -> Vec<f64> {
    let n = rays.len();
    let mut out = vec![0.0; 6 * n];
    for (i, r) in rays.iter().enumerate() {
        for (k, &x) in r.iter().enumerate() {
            out[if three { i + n * (k / 3) + 2 * n * (k % 3) } else { i + n * k }] = x;
        }
    }
    out
}

#[test]
fn every_ray_of_a_file_gets_the_single_trace_partition() {
    let dir = tempdir();
    let d = dir.path();
    let csv: String = std::iter::once("ox,oy,oz,dx,dy,dz\n# the rays\n\n".to_string())
        .chain(RAYS.iter().map(|r| r.map(|v| format!("{v:?}")).join(", ") + "\n"))
        .collect();
    std::fs::write(d.join("rays.csv"), csv).unwrap();
    let c_order = f64_bytes(RAYS.iter().flatten().copied());
    std::fs::write(d.join("c.npy"), npy("<f8", false, "(8, 6)", &c_order)).unwrap();
    std::fs::write(d.join("c3.npy"), npy("<f8", false, "(8, 2, 3)", &c_order)).unwrap();
    std::fs::write(d.join("f.npy"), npy("<f8", true, "(8, 6)", &f64_bytes(fortran(&RAYS, false)))).unwrap();
    std::fs::write(d.join("f3.NPY"), npy("<f8", true, "(8, 2, 3)", &f64_bytes(fortran(&RAYS, true)))).unwrap();
    for name in ["table.json", "glass.json", "primitives.json"] {
        let s = scene(name);
        let s = s.to_str().unwrap();
        let out = komplex_ok(d, &["trace", s, "--rays", "rays.csv", "--json"]);
        let v: Value = serde_json::from_slice(&out.stdout).unwrap();
        let rays = v["rays"].as_array().unwrap();
        assert_eq!(rays.len(), RAYS.len());
        for (r, got) in RAYS.iter().zip(rays) {
            assert_eq!(got["segments"], single(s, r), "{name}: ray {r:?}");
        }
        // The CSV says what the JSON says.
        let csv = komplex_ok(d, &["trace", s, "--rays", "rays.csv"]).stdout;
        let csv = String::from_utf8(csv).unwrap();
        let mut lines = csv.lines();
        assert_eq!(lines.next(), Some("ray,start,end,block,name"));
        let from_json: Vec<String> = rays
            .iter()
            .enumerate()
            .flat_map(|(i, r)| {
                r["segments"].as_array().unwrap().iter().map(move |seg| {
                    let end = seg["end"].as_f64().map_or("inf".to_string(), |e| format!("{e:?}"));
                    let block = seg["block"].as_u64().unwrap_or(0);
                    // RFC 4180: a name with a comma or quote is quoted, its quotes doubled.
                    let name = seg["name"].as_str().unwrap_or("");
                    let name = if name.contains([',', '"']) {
                        format!("\"{}\"", name.replace('"', "\"\""))
                    } else {
                        name.to_string()
                    };
                    format!("{i},{:?},{end},{block},{name}", seg["start"].as_f64().unwrap())
                })
            })
            .collect();
        assert_eq!(lines.map(str::to_string).collect::<Vec<_>>(), from_json, "{name}");
        // Every .npy layout gives the same bytes as the CSV, to stdout or to a file.
        for npy in ["c.npy", "c3.npy", "f.npy", "f3.NPY"] {
            assert_eq!(komplex_ok(d, &["trace", s, "--rays", npy]).stdout, csv.as_bytes(), "{name}, {npy}");
        }
        komplex_ok(d, &["trace", s, "--rays", "f3.NPY", "-o", "out.csv"]);
        assert_eq!(std::fs::read(d.join("out.csv")).unwrap(), csv.as_bytes());
    }
}

/// float32 rays are widened exactly: the same partition as the CSV of the
/// widened values; a file numpy wrote reads as the one written by hand.
#[test]
fn float32_and_numpy_written_files_read_as_their_values() {
    let dir = tempdir();
    let d = dir.path();
    let narrowed: Vec<[f64; 6]> = RAYS.iter().map(|r| r.map(|v| f64::from(v as f32))).collect();
    let f32s: Vec<u8> = narrowed.iter().flatten().flat_map(|&v| (v as f32).to_le_bytes()).collect();
    std::fs::write(d.join("r32.npy"), npy("<f4", false, "(8, 6)", &f32s)).unwrap();
    let csv: String = narrowed.iter().map(|r| r.map(|v| format!("{v:?}")).join(",") + "\n").collect();
    std::fs::write(d.join("r32.csv"), csv).unwrap();
    let s = scene("table.json");
    let s = s.to_str().unwrap();
    let want = komplex_ok(d, &["trace", s, "--rays", "r32.csv"]).stdout;
    assert_eq!(komplex_ok(d, &["trace", s, "--rays", "r32.npy"]).stdout, want);
    // numpy's own files, when numpy is installed (always under CI).
    let script = d.join("write.py");
    std::fs::write(
        &script,
        "import sys\ntry:\n    import numpy as np\nexcept ImportError:\n    sys.exit(2)\n\
         a = np.loadtxt(sys.argv[1] + '/r32.csv', delimiter=',')\n\
         np.save(sys.argv[1] + '/np32.npy', a.astype('<f4'))\n\
         np.save(sys.argv[1] + '/np3f.npy', np.asfortranarray(a.reshape(-1, 2, 3)))\n",
    )
    .unwrap();
    if python(script.to_str().unwrap(), &[d]).is_some() {
        for f in ["np32.npy", "np3f.npy"] {
            assert_eq!(komplex_ok(d, &["trace", s, "--rays", f]).stdout, want, "{f}");
        }
    }
}
