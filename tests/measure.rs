//! `komplex volume` and `komplex overlaps`: the JSON shape, analytic
//! volumes, unbounded blocks, `--box`, `-o`, and `check`'s warning about
//! overlapping opaque blocks.

use std::f64::consts::PI;

use serde_json::Value;

use crate::support::{komplex_ok, tempdir, write_scene};

/// Two unit balls with centres one apart (the second transparent), a cube
/// touching the second ball's box only at a face, and a floor (a half-space).
const SCENE: &str = r#"{
  "camera": { "eye": [0, 0, 9], "direction": [0, 0, -1], "width": 8, "height": 6 },
  "materials": { "glass": { "transmit": [1, 1, 1], "ior": 1.5 } },
  "blocks": [
    { "name": "left", "objects": [ { "sphere": {} } ] },
    { "name": "right", "material": "glass", "transparent": true,
      "objects": [ { "sphere": {}, "transform": [ { "translate": [1, 0, 0] } ] } ] },
    { "name": "cube", "objects": [ { "halfspace": [1, 0, 0, -4] }, { "halfspace": [-1, 0, 0, 2] },
      { "halfspace": [0, 1, 0, -1] }, { "halfspace": [0, -1, 0, -1] },
      { "halfspace": [0, 0, 1, -1] }, { "halfspace": [0, 0, -1, -1] } ] },
    { "name": "floor", "objects": [ { "halfspace": [0, 1, 0, 5] } ] }
  ]
}"#;

const BALL: f64 = 4.0 / 3.0 * PI;
const LENS: f64 = 5.0 / 12.0 * PI;

fn run_json(args: &[&str]) -> Value {
    let dir = tempdir();
    let scene = write_scene(dir.path(), "scene.json", SCENE);
    let mut all = vec![args[0], scene.to_str().unwrap(), "--json"];
    all.extend_from_slice(&args[1..]);
    let out = komplex_ok(dir.path(), &all);
    serde_json::from_slice(&out.stdout).unwrap()
}

/// `v` is a number within four of its standard errors `e` of `exact`.
fn near(v: &Value, e: &Value, exact: f64) {
    let (v, e) = (v.as_f64().unwrap(), e.as_f64().unwrap());
    assert!(e > 0.0 && e <= 2e-3 * exact, "error {e} for {exact}");
    assert!((v - exact).abs() <= 4.0 * e, "{v} ± {e} vs {exact}");
}

#[test]
fn volume_reports_owned_own_and_union_with_nulls_for_unbounded_blocks() {
    let v = run_json(&["volume", "--seed", "3"]);
    let blocks = v["blocks"].as_array().unwrap();
    let fields: Vec<(u64, &str, bool)> = blocks
        .iter()
        .map(|b| (b["index"].as_u64().unwrap(), b["name"].as_str().unwrap(), b["bounded"].as_bool().unwrap()))
        .collect();
    assert_eq!(fields, [(1, "left", true), (2, "right", true), (3, "cube", true), (4, "floor", false)]);
    // The opaque left ball takes the lens from the transparent right one.
    near(&blocks[0]["volume"], &blocks[0]["error"], BALL);
    near(&blocks[1]["volume"], &blocks[1]["error"], BALL - LENS);
    near(&blocks[1]["own_volume"], &blocks[1]["own_error"], BALL);
    near(&blocks[2]["volume"], &blocks[2]["error"], 8.0);
    for key in ["volume", "error", "own_volume", "own_error"] {
        assert!(blocks[3][key].is_null(), "{key}");
    }
    assert!(v["union"]["volume"].is_null() && v["union"]["error"].is_null());
    assert_eq!(v["converged"], Value::Bool(true));
}

#[test]
fn volume_with_a_box_clips_every_block() {
    let v = run_json(&["volume", "--box", "-6", "-6", "-6", "6", "6", "6", "--tolerance", "2e-3"]);
    let blocks = v["blocks"].as_array().unwrap();
    // The floor y <= -5 inside the box: a slab 12 × 1 × 12.
    near(&blocks[3]["volume"], &blocks[3]["error"], 144.0);
    near(&v["union"]["volume"], &v["union"]["error"], 2.0 * BALL - LENS + 8.0 + 144.0);
    assert_eq!(v["clipped"], Value::Bool(true));
    assert_eq!(v["box"], serde_json::json!([-6.0, -6.0, -6.0, 6.0, 6.0, 6.0]));
}

#[test]
fn volume_by_name_sums_the_blocks_of_each_name() {
    // The two balls renamed alike: together they own their union, and the
    // floor, unbounded, has no volume unless a box clips it.
    let dir = tempdir();
    let scene = write_scene(dir.path(), "scene.json", &SCENE.replace("\"name\": \"right\"", "\"name\": \"left\""));
    let out = komplex_ok(dir.path(), &["volume", scene.to_str().unwrap(), "--by-name", "--json", "--seed", "5"]);
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    let names = v["names"].as_array().unwrap();
    let rows: Vec<(&str, u64)> =
        names.iter().map(|n| (n["name"].as_str().unwrap(), n["blocks"].as_u64().unwrap())).collect();
    assert_eq!(rows, [("left", 2), ("cube", 1), ("floor", 1)]);
    near(&names[0]["volume"], &names[0]["error"], 2.0 * BALL - LENS);
    near(&names[1]["volume"], &names[1]["error"], 8.0);
    assert!(names[2]["volume"].is_null() && v["union"]["volume"].is_null());
    let out = komplex_ok(
        dir.path(),
        &["volume", scene.to_str().unwrap(), "--by-name", "--box", "-6", "-6", "-6", "6", "6", "6"],
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.starts_with("name") && text.contains("floor") && text.contains("clipped to the box"), "{text}");
}

#[test]
fn overlaps_lists_the_lens_with_a_point_inside_both_balls() {
    let v = run_json(&["overlaps"]);
    let pairs = v["overlaps"].as_array().unwrap();
    assert_eq!(pairs.len(), 1, "{v}");
    let p = &pairs[0];
    assert_eq!((p["a"].as_u64(), p["b"].as_u64()), (Some(1), Some(2)));
    near(&p["volume"], &p["error"], LENS);
    let x: Vec<f64> = p["point"].as_array().unwrap().iter().map(|c| c.as_f64().unwrap()).collect();
    for centre in [0.0, 1.0] {
        assert!((x[0] - centre).powi(2) + x[1].powi(2) + x[2].powi(2) <= 1.0, "{x:?}");
    }
}

#[test]
fn output_file_and_thread_count_change_nothing() {
    let dir = tempdir();
    let scene = write_scene(dir.path(), "scene.json", SCENE);
    let scene = scene.to_str().unwrap();
    for command in ["volume", "overlaps"] {
        let one = komplex_ok(dir.path(), &[command, scene, "--threads", "1"]).stdout;
        let two = komplex_ok(dir.path(), &[command, scene, "--threads", "2", "-o", "out.txt"]);
        assert!(two.stdout.is_empty());
        assert_eq!(std::fs::read(dir.path().join("out.txt")).unwrap(), one, "{command}");
    }
}

#[test]
fn check_warns_about_overlapping_opaque_blocks_only() {
    let dir = tempdir();
    // As SCENE, with the right ball opaque: now the lens is a warning.
    let opaque = SCENE.replace(r#""transparent": true"#, r#""transparent": false"#);
    for (text, warned) in [(SCENE.to_string(), false), (opaque, true)] {
        let scene = write_scene(dir.path(), "scene.json", &text);
        let out = komplex_ok(dir.path(), &["check", scene.to_str().unwrap()]);
        let stdout = String::from_utf8_lossy(&out.stdout);
        let warning = r#"opaque blocks 1 "left" and 2 "right" overlap"#;
        assert_eq!(stdout.contains(warning), warned, "{stdout}");
        // The cube touches the right ball's box and the floor is apart: no more.
        assert_eq!(stdout.matches("overlap (").count(), usize::from(warned), "{stdout}");
    }
}

#[test]
fn check_skips_the_overlap_test_beyond_its_pair_cap_and_says_so() {
    // 70 balls at one place: 2,415 pairs of opaque blocks with overlapping boxes.
    let balls: Vec<String> =
        (0..70).map(|i| format!(r#"{{ "name": "b{i}", "objects": [ {{ "sphere": {{}} }} ] }}"#)).collect();
    let text = format!(
        r#"{{ "camera": {{ "eye": [0, 0, 9], "direction": [0, 0, -1], "width": 8, "height": 6 }}, "blocks": [ {} ] }}"#,
        balls.join(", ")
    );
    let dir = tempdir();
    let scene = write_scene(dir.path(), "many.json", &text);
    let out = komplex_ok(dir.path(), &["check", scene.to_str().unwrap()]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("overlaps between opaque blocks not checked: more than 2000 pairs"), "{stdout}");
    assert!(!stdout.contains("overlap ("), "{stdout}");
}
