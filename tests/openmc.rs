//! `komplex import-openmc` end to end: the shared OpenMC models become
//! scenes that `check`, `slice`, `volume` and `render` take as they are;
//! `--check` reports cells, blocks, bounds and overlaps, an overlap found
//! where two cells share a known volume.

use crate::support::{komplex_ok, read_exr, root, tempdir};

fn model(name: &str) -> String {
    root().join("tests/openmc").join(name).join("geometry.xml").to_string_lossy().into_owned()
}

#[test]
fn imported_models_work_with_every_command() {
    let dir = tempdir();
    let d = dir.path();
    for name in ["quadric_surfaces", "complex_cell", "lattice"] {
        let out = format!("{name}.json");
        komplex_ok(d, &["import-openmc", &model(name), "-o", &out]);
        let scene: serde_json::Value = serde_json::from_slice(&std::fs::read(d.join(&out)).unwrap()).unwrap();
        assert!(scene["materials"].as_object().is_some_and(|m| !m.is_empty()), "{name}");
        komplex_ok(d, &["check", &out]);
        komplex_ok(
            d,
            &[
                "slice",
                &out,
                "--plane",
                "z=4.5",
                "-o",
                &format!("{name}.png"),
                "--color-by",
                "name",
                "--size",
                "64",
                "64",
                "--extent",
                "-1",
                "11",
                "-1",
                "11",
            ],
        );
        komplex_ok(d, &["render", &out, "-o", &format!("{name}.exr"), "--width", "48", "--height", "36"]);
        if let Some(exr) = read_exr(&d.join(format!("{name}.exr"))) {
            // The framing camera sees the model: some pixel hits a block.
            let hits = (0..36)
                .flat_map(|j| (0..48).map(move |i| (i, j)))
                .filter(|&(i, j)| exr.at("id.block", j, i) > 0.0)
                .count();
            assert!(hits > 48 * 36 / 10, "{name}: the camera sees {hits} pixels of the model");
        }
    }
    // The imported scenes are valid by the JSON Schema too.
    let schema = root().join("docs/scene.schema.json");
    let files: Vec<std::path::PathBuf> =
        ["quadric_surfaces", "complex_cell", "lattice"].iter().map(|n| d.join(format!("{n}.json"))).collect();
    let mut args: Vec<&std::path::Path> = vec![schema.as_path()];
    args.extend(files.iter().map(|p| p.as_path()));
    if let Some(out) = crate::support::python("validate_schema.py", &args) {
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(text.lines().count() == 3 && text.lines().all(|l| l.starts_with("ok ")), "{text}");
    }
    // stdout without -o is the same scene.
    let o = komplex_ok(d, &["import-openmc", &model("complex_cell")]);
    assert_eq!(o.stdout, std::fs::read(d.join("complex_cell.json")).unwrap());
}

#[test]
fn check_reports_cells_blocks_bounds_and_overlaps() {
    let dir = tempdir();
    let d = dir.path();
    let o = komplex_ok(d, &["import-openmc", &model("lattice"), "--check"]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("cells: 36 in 3 universes, 1 lattices; root universe 0"), "{out}");
    assert!(out.contains("overlaps: none between different cells at 1000000 points"), "{out}");
    assert!(!d.join("lattice.json").exists());
    // Two balls of radius 1 whose centres are 1 apart share 5π/12.
    let xml = r#"<geometry>
      <surface id="1" type="sphere" coeffs="0 0 0 1"/><surface id="2" type="sphere" coeffs="1 0 0 1"/>
      <cell id="7" material="1" region="-1"/><cell id="8" material="2" region="-2"/></geometry>"#;
    std::fs::write(d.join("two.xml"), xml).unwrap();
    let o = komplex_ok(d, &["import-openmc", "two.xml", "--check", "--points", "400000"]);
    let out = String::from_utf8_lossy(&o.stdout);
    let line = out.lines().find(|l| l.contains("\"cell 7\" & \"cell 8\"")).unwrap_or_else(|| panic!("{out}"));
    let numbers: Vec<f64> = line.split([' ', '(', ',']).filter_map(|t| t.parse().ok()).collect();
    let (volume, error) = (numbers[0], numbers[1]);
    let want = 5.0 * std::f64::consts::PI / 12.0;
    assert!((volume - want).abs() < 4.0 * error, "{line}: want {want}");
}

#[test]
fn overlaps_by_name_leaves_out_the_terms_of_one_cell() {
    let dir = tempdir();
    let d = dir.path();
    komplex_ok(d, &["import-openmc", &model("complex_cell"), "-o", "cc.json"]);
    let all = komplex_ok(d, &["overlaps", "cc.json", "--box", "-10", "-10", "-1", "10", "10", "1", "--json"]);
    let all: serde_json::Value = serde_json::from_slice(&all.stdout).unwrap();
    let pairs = all["overlaps"].as_array().unwrap();
    // Cell 2's four terms overlap at the corners of its square ring.
    assert!(!pairs.is_empty() && pairs.iter().all(|p| p["a_name"] == p["b_name"]), "{pairs:?}");
    let named =
        komplex_ok(d, &["overlaps", "cc.json", "--box", "-10", "-10", "-1", "10", "10", "1", "--json", "--by-name"]);
    let named: serde_json::Value = serde_json::from_slice(&named.stdout).unwrap();
    assert_eq!(named["overlaps"].as_array().unwrap().len(), 0, "{named}");
    // Two cells that do overlap are still found.
    let xml = r#"<geometry>
      <surface id="1" type="sphere" coeffs="0 0 0 1"/><surface id="2" type="sphere" coeffs="1 0 0 1"/>
      <cell id="7" material="1" region="-1"/><cell id="8" material="2" region="-2"/></geometry>"#;
    std::fs::write(d.join("two.xml"), xml).unwrap();
    komplex_ok(d, &["import-openmc", "two.xml", "-o", "two.json"]);
    let o = komplex_ok(d, &["overlaps", "two.json", "--by-name", "--json"]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let pair = &v["overlaps"][0];
    assert_eq!((pair["a_name"].as_str(), pair["b_name"].as_str()), (Some("cell 7"), Some("cell 8")));
    let (volume, error) = (pair["volume"].as_f64().unwrap(), pair["error"].as_f64().unwrap());
    assert!((volume - 5.0 * std::f64::consts::PI / 12.0).abs() < 4.0 * error, "{pair}");
}
