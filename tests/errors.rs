//! Bad input: a clear message naming the place, a non-zero exit, and no
//! output file (and an existing one left untouched).

use crate::support::{komplex, tempdir, text, write_scene};

const CAMERA: &str = r#""camera": { "eye": [0, 0, 5], "direction": [0, 0, -1], "width": 8, "height": 6 }"#;

/// Renders `json`; expects exit status 1 with every `needles` in stderr, and
/// that neither the EXR nor the PNG was written or clobbered.
fn check(json: &str, needles: &[&str]) {
    let dir = tempdir();
    let scene = write_scene(dir.path(), "bad.json", json);
    let out = dir.path().join("out.exr");
    std::fs::write(&out, b"keep me").unwrap();
    let o = komplex(dir.path(), &["render", scene.to_str().unwrap(), "-o", "out.exr", "--png", "out.png"]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    let err = String::from_utf8_lossy(&o.stderr);
    for n in needles {
        assert!(err.contains(n), "stderr lacks {n:?}:\n{err}");
    }
    assert!(!err.contains("panicked"), "{err}");
    assert_eq!(std::fs::read(&out).unwrap(), b"keep me", "the existing output was clobbered");
    assert!(!dir.path().join("out.png").exists());
    let leftovers: Vec<_> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(leftovers.len(), 2, "stray files: {leftovers:?}");
}

fn blocks(b: &str) -> String {
    format!(r#"{{ {CAMERA}, "blocks": [ {b} ] }}"#)
}

#[test]
fn syntax_errors_name_line_and_column() {
    check("{\n  \"camera\": {\n    \"eye\": [0, 0, 5],,\n", &["bad.json", "camera, line 3, column 22"]);
    check("", &["line 1, column 0", "EOF"]);
    check(&blocks(r#"{ "name": "a" "objects": [] }"#), &["blocks[0]", "line 1, column"]);
}

#[test]
fn unknown_keys_suggest_the_nearest_name() {
    check(
        &blocks(r#"{ "name": "a", "materail": "x", "objects": [ { "sphere": {} } ] }"#),
        &["blocks[0].materail", "line 1, column", "unknown field `materail`", "did you mean `material`?"],
    );
    check(
        &blocks(r#"{ "objects": [ { "sphere": {}, "transform": [ { "rotate_yy": 4 } ] } ] }"#),
        &["blocks[0].objects[0].transform[0]", "did you mean `rotate_y`?"],
    );
    check(&format!(r#"{{ {CAMERA}, "setings": {{}}, "blocks": [] }}"#), &["setings", "did you mean `settings`?"]);
    check(&blocks(r#"{ "objects": [ { "sphere": { "raduis": 2 } } ] }"#), &["sphere.raduis", "did you mean `radius`?"]);
}

#[test]
fn wrong_types_name_the_path() {
    check(
        &blocks(r#"{ "objects": [ { "sphere": { "radius": "big" } } ] }"#),
        &["blocks[0].objects[0].sphere.radius", "line 1", "invalid type"],
    );
    check(
        &blocks(r#"{ "objects": [ { "cone": {}, "transform": [ { "scale": [1, 2] } ] } ] }"#),
        &["transform[0].scale", "a number or an array [sx, sy, sz]"],
    );
    check(&format!(r#"{{ {CAMERA} }}"#), &["missing field `blocks`"]);
}

#[test]
fn semantic_errors_name_the_block_and_object() {
    check(
        &format!(
            r#"{{ {CAMERA}, "materials": {{ "oak": {{}} }}, "blocks": [ {{ "name": "top", "material": "oka", "objects": [ {{ "sphere": {{}} }} ] }} ] }}"#
        ),
        &["blocks[0].material, line 1, column ", "block \"top\"", "unknown material \"oka\"", "did you mean \"oak\"?"],
    );
    check(
        &blocks(
            r#"{ "name": "leg", "objects": [ { "sphere": {} }, { "cone": {}, "transform": [ { "scale": [1, 0, 1] } ] } ] }"#,
        ),
        &["blocks[0].objects[1].transform[0]", "block \"leg\", object 2", "singular"],
    );
    check(&blocks(r#"{ "name": "void", "objects": [] }"#), &["blocks[0]", "block \"void\" is empty"]);
    // Semantic errors point at the line and column of the offending value too.
    check(
        "{\n  \"camera\": { \"eye\": [0, 0, 5], \"direction\": [0, 0, -1] },\n  \"blocks\": [\n    { \"name\": \"a\", \"objects\": [ { \"sphere\": {} },\n      { \"cone\": {}, \"transform\": [ { \"scale\": 0 } ] } ] } ] }",
        &["blocks[0].objects[1].transform[0], line 5, column 36", "block \"a\", object 2", "singular"],
    );
    check(
        &blocks(r#"{ "name": "two", "objects": [ { "sphere": {}, "cone": {} } ] }"#),
        &["blocks[0].objects[0]", "exactly one shape key", "sphere, cone"],
    );
    check(&blocks(r#"{ "name": "none", "objects": [ { "complement": true } ] }"#), &["exactly one shape key"]);
    check(
        &blocks(
            r#"{ "group": "g", "blocks": [ { "name": "m", "objects": [ { "sphere": {}, "transform": [ { "matrix": [[1,0,0,0],[0,1,0,0],[0,0,0,0],[0,0,0,1]] } ] } ] } ] }"#,
        ),
        &["blocks[0].blocks[0].objects[0].transform[0]", "block \"m\"", "singular"],
    );
    check(&blocks(r#"{ "objects": [ { "matrix_quadric": 1 } ] }"#), &["unknown field `matrix_quadric`"]);
    check(
        &blocks(r#"{ "name": "h", "objects": [ { "halfspace": [0, 0, 0, 1] } ] }"#),
        &["block \"h\", object 1", "zero"],
    );
    check(
        &blocks(r#"{ "name": "hy", "objects": [ { "hyperboloid": { "sheets": 3 } } ] }"#),
        &["sheets must be 1 or 2"],
    );
    check(&blocks(""), &["no blocks"]);
    check(&blocks(r#"{ "group": "g", "objects": [ { "sphere": {} } ] }"#), &["group \"g\"", "blocks[0]"]);
}

#[test]
fn bad_cameras_and_settings() {
    let scene = |cam: &str, settings: &str| {
        format!(
            r#"{{ "camera": {cam}, "settings": {settings}, "blocks": [ {{ "objects": [ {{ "sphere": {{}} }} ] }} ] }}"#
        )
    };
    check(&scene(r#"{ "eye": [0, 0, 5], "direction": [0, 2, 0] }"#, "{}"), &["camera", "parallel"]);
    check(&scene(r#"{ "eye": [0, 0, 5], "direction": [0, 0, 0] }"#, "{}"), &["camera", "zero"]);
    check(&scene(r#"{ "eye": [0, 0, 5], "direction": [0, 0, -1], "aperture": 180 }"#, "{}"), &["aperture"]);
    check(&scene(r#"{ "eye": [0, 0, 5], "direction": [0, 0, -1], "width": 0 }"#, "{}"), &["camera", "empty"]);
    check(&scene(r#"{ "eye": [0, 0, 5], "direction": [0, 0, -1] }"#, r#"{ "epsilon": -1 }"#), &["settings.epsilon"]);
    check(&scene(r#"{ "eye": [0, 0, 5], "direction": [0, 0, -1], "width": -3 }"#, "{}"), &["camera.width", "line 1"]);
    check(
        &scene(r#"{ "eye": [0, 0, 5], "direction": [0, 0, -1], "width": 100000, "height": 100000 }"#, "{}"),
        &["at most"],
    );
    check(&scene(r#"{ "eye": [0, 0, 5], "direction": [0, 0, -1] }"#, r#"{ "samples": 0 }"#), &["settings.samples"]);
}

#[test]
fn environment_errors_exit_3_and_usage_errors_exit_2() {
    let dir = tempdir();
    let o = komplex(dir.path(), &["render", "does-not-exist.json"]);
    assert_eq!(o.status.code(), Some(3), "{}", text(&o));
    assert!(String::from_utf8_lossy(&o.stderr).contains("does-not-exist.json"));
    let o = komplex(dir.path(), &["render"]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    let o = komplex(dir.path(), &["trace", "x.json", "--origin", "0", "0"]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    // An output directory that does not exist: exit 3, nothing written.
    let scene = write_scene(dir.path(), "ok.json", &blocks(r#"{ "objects": [ { "sphere": {} } ] }"#));
    let o = komplex(dir.path(), &["render", scene.to_str().unwrap(), "-o", "missing/dir/out.exr"]);
    assert_eq!(o.status.code(), Some(3), "{}", text(&o));
    assert!(String::from_utf8_lossy(&o.stderr).contains("missing/dir/out.exr"));
}
