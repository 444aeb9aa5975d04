//! Bad input: a clear message naming the place, the documented exit status,
//! no panic, and no output written (an existing one left untouched). Every
//! row of docs/errors.md is a case here.

use std::collections::BTreeMap;
use std::path::Path;

use crate::support::{komplex, komplex_env, komplex_ok, scene, tempdir, text, write_scene};

const CAMERA: &str = r#""camera": { "eye": [0, 0, 5], "direction": [0, 0, -1], "width": 8, "height": 6 }"#;

/// A valid scene, `ok.json` in every fixture directory.
const OK: &str = r#"{ "camera": { "eye": [0, 0, 5], "direction": [0, 0, -1], "width": 8, "height": 6 },
                      "blocks": [ { "objects": [ { "sphere": {} } ] } ] }"#;

/// What a case runs.
enum Input<'a> {
    /// A scene text, written to `bad.json` and rendered to `out.exr` and `out.png`.
    Scene(String),
    /// Raw arguments, run in the fixture directory.
    Args(&'a [&'a str]),
}

impl From<&str> for Input<'_> {
    fn from(s: &str) -> Self {
        Input::Scene(s.to_string())
    }
}

impl From<String> for Input<'_> {
    fn from(s: String) -> Self {
        Input::Scene(s)
    }
}

impl<'a, const N: usize> From<&'a [&'a str; N]> for Input<'a> {
    fn from(a: &'a [&'a str; N]) -> Self {
        Input::Args(a)
    }
}

/// Every file under `dir` with its contents (directories as `None`).
fn snapshot(dir: &Path) -> BTreeMap<String, Option<Vec<u8>>> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| {
            let p = e.unwrap().path();
            let name = p.file_name().unwrap().to_string_lossy().into_owned();
            (name, if p.is_dir() { None } else { Some(std::fs::read(&p).unwrap()) })
        })
        .collect()
}

/// Runs `input` in a fixture directory holding `ok.json` (valid), `out.exr`
/// (an earlier render that must survive), `file` (a regular file),
/// `latin1.json` (not UTF-8) and `dir.json/` (a directory). Expects exit
/// status `code`, every `needles` in stderr, no panic, and the directory
/// exactly as before: nothing written, clobbered or left behind.
fn check<'a>(input: impl Into<Input<'a>>, code: i32, needles: &[&str]) {
    check_with(&[], input, code, needles);
}

/// [`check`] with more files in the fixture directory (name, contents).
fn check_with<'a>(files: &[(&str, &[u8])], input: impl Into<Input<'a>>, code: i32, needles: &[&str]) {
    check_env(&[], files, input, code, needles);
}

/// [`check_with`] with environment variables set.
fn check_env<'a>(
    env: &[(&str, &str)],
    files: &[(&str, &[u8])],
    input: impl Into<Input<'a>>,
    code: i32,
    needles: &[&str],
) {
    let dir = tempdir();
    let d = dir.path();
    for (name, contents) in files {
        std::fs::write(d.join(name), contents).unwrap();
    }
    write_scene(d, "ok.json", OK);
    std::fs::write(d.join("out.exr"), b"keep me").unwrap();
    std::fs::write(d.join("file"), b"a regular file").unwrap();
    std::fs::write(d.join("latin1.json"), b"{ \"camera\": \"\xe9t\xe9\" }").unwrap();
    std::fs::create_dir(d.join("dir.json")).unwrap();
    let o = match input.into() {
        Input::Scene(json) => {
            write_scene(d, "bad.json", &json);
            let before = snapshot(d);
            (komplex(d, &["render", "bad.json", "-o", "out.exr", "--png", "out.png"]), before)
        }
        Input::Args(args) => {
            let before = snapshot(d);
            (komplex_env(d, args, env), before)
        }
    };
    let (o, before) = o;
    assert_eq!(o.status.code(), Some(code), "{}", text(&o));
    let err = String::from_utf8_lossy(&o.stderr);
    for n in needles {
        assert!(err.contains(n), "stderr lacks {n:?}:\n{err}");
    }
    assert!(!err.contains("panicked"), "{err}");
    if code != 2 {
        // Our own errors are one line; clap's usage errors have several.
        assert!(err.starts_with("error: ") && err.trim_end().lines().count() == 1, "{err}");
    }
    assert!(snapshot(d) == before, "the directory changed: {:?}", snapshot(d).keys().collect::<Vec<_>>());
}

fn blocks(b: &str) -> String {
    format!(r#"{{ {CAMERA}, "blocks": [ {b} ] }}"#)
}

fn with_camera(cam: &str, settings: &str) -> String {
    format!(r#"{{ "camera": {cam}, "settings": {settings}, "blocks": [ {{ "objects": [ {{ "sphere": {{}} }} ] }} ] }}"#)
}

fn with_material(m: &str) -> String {
    format!(
        r#"{{ {CAMERA}, "materials": {{ "m": {m} }}, "blocks": [ {{ "material": "m", "objects": [ {{ "sphere": {{}} }} ] }} ] }}"#
    )
}

/// `levels` groups nested inside each other around one block.
fn nested(levels: usize) -> String {
    let open = r#"{ "group": "g", "blocks": ["#.repeat(levels);
    let close = "] }".repeat(levels);
    blocks(&format!(r#"{open} {{ "name": "core", "objects": [ {{ "sphere": {{}} }} ] }} {close}"#))
}

#[test]
fn syntax_errors_name_line_and_column() {
    check("{\n  \"camera\": {\n    \"eye\": [0, 0, 5],,\n", 1, &["bad.json: camera, line 3, column 22"]);
    check("", 1, &["line 1, column 0", "EOF"]);
    check(&*blocks(r#"{ "name": "a" "objects": [] }"#), 1, &["blocks[0], line 1, column 111: expected `,` or `}`"]);
}

#[test]
fn unknown_keys_suggest_the_nearest_name() {
    check(
        &*blocks(r#"{ "name": "a", "materail": "x", "objects": [ { "sphere": {} } ] }"#),
        1,
        &["blocks[0].materail", "line 1, column", "unknown field `materail`", "did you mean `material`?"],
    );
    check(
        &*blocks(r#"{ "objects": [ { "sphere": {}, "transform": [ { "rotate_yy": 4 } ] } ] }"#),
        1,
        &["blocks[0].objects[0].transform[0]", "did you mean `rotate_y`?"],
    );
    check(&*format!(r#"{{ {CAMERA}, "setings": {{}}, "blocks": [] }}"#), 1, &["setings", "did you mean `settings`?"]);
    check(
        &*blocks(r#"{ "objects": [ { "sphere": { "raduis": 2 } } ] }"#),
        1,
        &["sphere.raduis", "did you mean `radius`?"],
    );
    check(&*blocks(r#"{ "objects": [ { "matrix_quadric": 1 } ] }"#), 1, &["unknown field `matrix_quadric`"]);
}

#[test]
fn wrong_types_and_missing_keys_name_the_path() {
    check(
        &*blocks(r#"{ "objects": [ { "sphere": { "radius": "big" } } ] }"#),
        1,
        &["blocks[0].objects[0].sphere.radius, line 1", "invalid type: string \"big\", expected f64"],
    );
    check(
        &*blocks(r#"{ "objects": [ { "cone": {}, "transform": [ { "scale": [1, 2] } ] } ] }"#),
        1,
        &[
            "blocks[0].objects[0].transform[0].scale, line 1, column 157",
            "invalid length 2, expected a number or an array [sx, sy, sz]",
        ],
    );
    check(&*format!(r#"{{ {CAMERA} }}"#), 1, &["missing field `blocks`"]);
    check(r#"{ "camera": { "eye": [0, 0, 5] }, "blocks": [] }"#, 1, &["camera, line 1", "missing field `direction`"]);
    check(&*with_camera(r#"{ "eye": [0, 0, 5], "direction": [0, 0, -1], "width": -3 }"#, "{}"), 1, &["camera.width"]);
}

#[test]
fn numbers_overflowing_to_infinity_are_refused() {
    check(
        &*blocks(r#"{ "objects": [ { "sphere": { "radius": 1e999 } } ] }"#),
        1,
        &["blocks[0].objects[0].sphere.radius, line 1, column", "number out of range"],
    );
    check(
        &*with_camera(r#"{ "eye": [0, 0, -1e999], "direction": [0, 0, -1] }"#, "{}"),
        1,
        &["camera.eye", "out of range"],
    );
    // Finite numbers whose composition overflows: caught after the transforms, naming the object.
    check(
        &*blocks(
            r#"{ "name": "far", "objects": [ { "sphere": {}, "transform": [ { "translate": [1e308, 0, 0] }, { "scale": 1e308 } ] } ] }"#,
        ),
        1,
        &["blocks[0].objects[0], line 1", "block \"far\", object 1", "overflow", "not finite"],
    );
}

#[test]
fn transforms_underflowing_are_refused() {
    let underflow = "underflows: it would be stored below the smallest normal number (2.2e-308), \
                     so the solid would not be the one described";
    // A unit ball scaled by 1e170 would be all of space.
    check(
        &*blocks(r#"{ "name": "far", "objects": [ { "sphere": {}, "transform": [ { "scale": 1e170 } ] } ] }"#),
        1,
        &[
            "error: bad.json: blocks[0].objects[0], line 1, column 127: block \"far\", object 1: the transforms \
             (the object's, the block's and its groups') underflow: the placed solid's quadratic part",
            underflow,
        ],
    );
    // One axis only: it would be a tube.
    check(
        &*blocks(r#"{ "name": "far", "objects": [ { "sphere": {}, "transform": [ { "scale": [1e170, 1, 1] } ] } ] }"#),
        1,
        &["blocks[0].objects[0], line 1, column 127", "underflow: the placed solid's quadratic coefficient along x"],
    );
    // Spread over the object's and the block's transforms.
    check(
        &*blocks(
            r#"{ "name": "far", "transform": [ { "scale": 1e100 } ], "objects": [ { "sphere": {}, "transform": [ { "scale": 1e70 } ] } ] }"#,
        ),
        1,
        &["blocks[0].objects[0], line 1, column 164", "block \"far\", object 1", "underflow", underflow],
    );
    // A radius does it alone.
    check(
        &*blocks(r#"{ "name": "far", "objects": [ { "sphere": { "radius": 1e200 } } ] }"#),
        1,
        &["blocks[0].objects[0], line 1, column 127: block \"far\", object 1: sphere.radius 1e200: the placed solid's quadratic part", underflow],
    );
}

/// `komplex check` refuses what `render` refuses, with the same message.
#[test]
fn check_reports_underflow_and_degenerate_quadrics() {
    let dir = tempdir();
    for (b, needle) in [
        (r#"{ "objects": [ { "sphere": {}, "transform": [ { "scale": 1e170 } ] } ] }"#, "underflow"),
        (r#"{ "objects": [ { "quadric": [0, 0, 0, 0, 0, 0, 0, 0, 0, 1] } ] }"#, "the solid is empty"),
    ] {
        write_scene(dir.path(), "bad.json", &blocks(b));
        let o = komplex(dir.path(), &["check", "bad.json"]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{}", text(&o));
        assert!(err.starts_with("error: bad.json: blocks[0].objects[0], line 1") && err.contains(needle), "{err}");
    }
}

#[test]
fn degenerate_quadrics_are_refused() {
    check(
        &*blocks(r#"{ "name": "q", "objects": [ { "quadric": [0, 0, 0, 0, 0, 0, 0, 0, 0, 0] } ] }"#),
        1,
        &["error: bad.json: blocks[0].objects[0], line 1, column 125: block \"q\", object 1: the quadric is degenerate: \
           all ten coefficients are zero (0 <= 0 holds everywhere)"],
    );
    check(
        &*blocks(r#"{ "name": "q", "objects": [ { "quadric": [0, 0, 0, 0, 0, 0, 0, 0, 0, 1] } ] }"#),
        1,
        &["error: bad.json: blocks[0].objects[0], line 1, column 125: block \"q\", object 1: the quadric is degenerate: \
           only the constant k is non-zero and it is positive (k <= 0 holds nowhere: the solid is empty)"],
    );
}

#[test]
fn semantic_errors_name_the_block_and_object() {
    check(
        &*format!(
            r#"{{ {CAMERA}, "materials": {{ "oak": {{}} }}, "blocks": [ {{ "name": "top", "material": "oka", "objects": [ {{ "sphere": {{}} }} ] }} ] }}"#
        ),
        1,
        &["blocks[0].material, line 1, column ", "block \"top\"", "unknown material \"oka\"", "did you mean \"oak\"?"],
    );
    check(
        &*blocks(
            r#"{ "name": "leg", "objects": [ { "sphere": {} }, { "cone": {}, "transform": [ { "scale": [1, 0, 1] } ] } ] }"#,
        ),
        1,
        &["blocks[0].objects[1].transform[0]", "block \"leg\", object 2", "singular"],
    );
    // Semantic errors point at the line and column of the offending value too.
    check(
        "{\n  \"camera\": { \"eye\": [0, 0, 5], \"direction\": [0, 0, -1] },\n  \"blocks\": [\n    { \"name\": \"a\", \"objects\": [ { \"sphere\": {} },\n      { \"cone\": {}, \"transform\": [ { \"scale\": 0 } ] } ] } ] }",
        1,
        &["blocks[0].objects[1].transform[0], line 5, column 36", "block \"a\", object 2", "singular"],
    );
    check(
        &*blocks(
            r#"{ "group": "g", "blocks": [ { "name": "m", "objects": [ { "sphere": {}, "transform": [ { "matrix": [[1,0,0,0],[0,1,0,0],[0,0,0,0],[0,0,0,1]] } ] } ] } ] }"#,
        ),
        1,
        &["blocks[0].blocks[0].objects[0].transform[0]", "block \"m\"", "singular"],
    );
    check(
        &*blocks(r#"{ "name": "two", "objects": [ { "sphere": {}, "cone": {} } ] }"#),
        1,
        &["blocks[0].objects[0]", "exactly one shape key", "sphere, cone"],
    );
    check(&*blocks(r#"{ "name": "none", "objects": [ { "complement": true } ] }"#), 1, &["exactly one shape key"]);
    check(
        &*blocks(r#"{ "name": "h", "objects": [ { "halfspace": [0, 0, 0, 1] } ] }"#),
        1,
        &["block \"h\", object 1", "zero"],
    );
    check(
        &*blocks(r#"{ "name": "hy", "objects": [ { "hyperboloid": { "sheets": 3 } } ] }"#),
        1,
        &["sheets must be 1 or 2"],
    );
    check(&*blocks(r#"{ "group": "g", "objects": [ { "sphere": {} } ] }"#), 1, &["group \"g\"", "blocks[0]"]);
}

#[test]
fn empty_blocks_and_empty_scenes_are_errors() {
    check(&*blocks(r#"{ "name": "void", "objects": [] }"#), 1, &["blocks[0], line 1", "block \"void\" is empty"]);
    check(&*blocks(""), 1, &["blocks, line 1", "the scene has no blocks"]);
    // Groups that hold nothing count as no blocks.
    check(&*blocks(r#"{ "group": "g", "blocks": [] }"#), 1, &["the scene has no blocks"]);
}

#[test]
fn bad_steps_keys_and_frames_name_the_place() {
    let step = |s: &str| blocks(&format!(r#"{{ "objects": [ {{ "sphere": {{}}, "transform": [ {s} ] }} ] }}"#));
    let at = "blocks[0].objects[0].transform[0]";
    check(
        &*step(
            r#"{ "translate": { "keys": [ { "frame": 2, "value": [0, 0, 0] }, { "frame": 1, "value": [1, 0, 0] } ] } }"#,
        ),
        1,
        &[&format!("{at}.translate.keys[1], line 1, column 241: key frames must increase: frame 1 follows frame 2")],
    );
    check(
        &*step(r#"{ "rotate_x": { "keys": [] } }"#),
        1,
        &[&format!("{at}.rotate_x.keys, line 1, column 168: keys must not be empty")],
    );
    check(
        &*step(r#"{ "rotate_x": { "keys": [ { "frame": -1, "value": 5 } ] } }"#),
        1,
        &[&format!(
            "{at}.rotate_x.keys[0], line 1, column 197: a key's frame must be between 0 and 4294967295, got -1"
        )],
    );
    check(
        &*step(r#"{ "matrix": { "keys": [] } }"#),
        1,
        &[&format!("{at}.matrix, line 1, column 156: a `matrix` step cannot be keyed: key `translate`, `scale`")],
    );
    check(
        &*step(r#"{ "rotate_x": { "kyes": [] } }"#),
        1,
        &[&format!("{at}.rotate_x, line 1, column 164: unknown field `kyes`, expected `keys` (did you mean `keys`?)")],
    );
    check(
        &*format!(
            r#"{{ "animation": {{ "frames": [5, 1] }}, {CAMERA}, "blocks": [ {{ "objects": [ {{ "sphere": {{}} }} ] }} ] }}"#
        ),
        1,
        &["animation.frames, line 1, column 28: the first frame comes after the last: [5, 1]"],
    );
    // Errors that depend on the frame: `--frame 2` or `3` on `anim.json`.
    let at_frame = |json: &str, frame: &str, needle: &str| {
        check_with(
            &[("anim.json", json.as_bytes())],
            &["render", "anim.json", "-o", "out.exr", "--frame", frame],
            1,
            &[needle],
        );
    };
    at_frame(
        &step(r#"{ "scale": { "keys": [ { "frame": 1, "value": 1 }, { "frame": 5, "value": -1 } ] } }"#),
        "3",
        "anim.json: blocks[0].objects[0].transform[0], line 1, column 143: at frame 3: block \"block 1\", object 1: the transform is singular",
    );
    let direction = |to: &str| {
        format!(
            r#"{{ "camera": {{ "eye": [0, 0, 5], "direction": {{ "keys": [ {{ "frame": 1, "value": [0, 0, -1] }}, {{ "frame": 3, "value": {to} }} ] }}, "width": 8, "height": 6 }}, "blocks": [ {{ "objects": [ {{ "sphere": {{}} }} ] }} ] }}"#
        )
    };
    at_frame(
        &direction("[0, 0, 1]"),
        "2",
        "anim.json: camera.direction.keys[1], line 1, column 95: at frame 2: keys 0 and 1 point in opposite directions",
    );
    at_frame(
        &direction("[0, 0, 0]"),
        "2",
        "camera.direction.keys[1], line 1, column 95: at frame 2: the direction is zero or not finite",
    );
    // The options.
    check(
        &["render", "ok.json", "-o", "out.exr", "--frame", "1", "--frames", "1..2"],
        2,
        &["the argument '--frame <K>' cannot be used with '--frames [<A..B>]'"],
    );
    check(
        &["render", "ok.json", "-o", "out.exr", "--frames", "1-3"],
        1,
        &["--frames \"1-3\": expected A..B, the first and the last frame (both rendered)"],
    );
    check(
        &["render", "ok.json", "-o", "out.exr", "--frames", "5..1"],
        1,
        &["--frames 5..1: the first frame comes after the last"],
    );
    check(
        &["render", "ok.json", "-o", "out.exr", "--frames"],
        1,
        &["--frames without A..B renders the scene's \"animation\": {\"frames\": [A, B]}, which ok.json lacks"],
    );
}

/// A scene whose camera is at `[0, 0, 5]` with the further members
/// `members` is refused (exit status 1) with each of `needles` in the message.
fn bad_camera(members: &str, needles: &[&str]) {
    check(&*with_camera(&format!(r#"{{ "eye": [0, 0, 5], {members} }}"#), "{}"), 1, needles);
}

#[test]
fn bad_cameras_name_the_field() {
    let d = r#""direction": [0, 0, -1]"#;
    bad_camera(r#""direction": [0, 0, 0]"#, &["camera.direction, line 1, column 46: the direction is zero"]);
    // `up` left out (its default is parallel): named, and located at the camera.
    bad_camera(r#""direction": [0, 2, 0]"#, &["camera.up, line 1, column 13: the up vector is zero or parallel to"]);
    bad_camera(&format!(r#"{d}, "up": [0, 0, 0]"#), &["camera.up, line 1, column 64: the up vector is zero or"]);
    bad_camera(&format!(r#"{d}, "up": [0, 0, 3]"#), &["camera.up, line 1, column 64: the up vector is zero or"]);
    bad_camera(
        &format!(r#"{d}, "up": [1e308, 1e308, 1e308]"#),
        &["camera.up, line 1, column 64: the eye or up vector"],
    );
    for a in ["0", "180", "-5", "400"] {
        let want = format!(
            "camera.aperture, line 1, column 70: the aperture must lie strictly between 0 and 180 degrees, got {a}"
        );
        bad_camera(&format!(r#"{d}, "aperture": {a}"#), &[&want]);
    }
    bad_camera(
        &format!(r#"{d}, "width": 0, "height": 24"#),
        &["camera.width, line 1, column 67: the image size 0x24 is empty"],
    );
    bad_camera(
        &format!(r#"{d}, "width": 32, "height": 0"#),
        &["camera.height, line 1, column 81: the image size 32x0 is"],
    );
    bad_camera(
        &format!(r#"{d}, "width": 0, "height": 0"#),
        &["camera.width, line 1, column 67: the image size 0x0 is empty"],
    );
    // Far beyond memory: refused from the numbers alone, before any allocation.
    let huge = "camera.width, line 1, column 67: the image size 4294967295x4294967295 is too large: at most 268435456";
    bad_camera(&format!(r#"{d}, "width": 4294967295, "height": 4294967295"#), &[huge]);
    bad_camera(
        &format!(r#"{d}, "width": 2, "height": 4294967295"#),
        &["camera.height, line 1, column 80: the image size 2x"],
    );
    bad_camera(&format!(r#"{d}, "width": 4294967296"#), &["camera.width, line 1, column ", "invalid value: integer"]);
}

#[test]
fn bad_lenses_and_projections_name_the_field() {
    let d = r#""direction": [0, 0, -1]"#;
    bad_camera(
        &format!(r#"{d}, "lens_radius": -0.5"#),
        &["camera.lens_radius, line 1, column 73: the lens radius must be finite and >= 0, got -0.5"],
    );
    bad_camera(
        &format!(r#"{d}, "lens_radius": 1e999"#),
        &["camera.lens_radius, line 1, column 77: number out of range"],
    );
    bad_camera(
        &format!(r#"{d}, "lens_radius": 0.1, "focus_distance": 0"#),
        &["camera.focus_distance, line 1, column 96: the focus distance must be finite and > 0, got 0"],
    );
    // Checked without a lens too.
    bad_camera(
        &format!(r#"{d}, "focus_distance": -2"#),
        &["camera.focus_distance, line 1, column 76: the focus distance must be finite and > 0, got -2"],
    );
    bad_camera(
        &format!(r#"{d}, "projection": "fisheye""#),
        &["camera.projection, line 1, column 80: unknown variant `fisheye`, expected `perspective` or `orthographic`"],
    );
    bad_camera(
        &format!(r#"{d}, "projection": "orthographic""#),
        &["camera.projection, line 1, column 72: an orthographic camera needs \"diagonal\", the world-space length"],
    );
    bad_camera(
        &format!(r#"{d}, "projection": "orthographic", "diagonal": 0"#),
        &["camera.diagonal, line 1, column 100: the diagonal must be finite and > 0, got 0"],
    );
    bad_camera(
        &format!(r#"{d}, "diagonal": 3"#),
        &["camera.diagonal, line 1, column 70: only an orthographic camera has a diagonal (set \"projection\": \"orthographic\")"],
    );
}

#[test]
fn bad_settings_and_materials() {
    let cam = r#"{ "eye": [0, 0, 5], "direction": [0, 0, -1] }"#;
    check(&*with_camera(cam, r#"{ "epsilon": -1 }"#), 1, &["settings.epsilon", "must be finite and >= 0"]);
    check(&*with_camera(cam, r#"{ "samples": 0 }"#), 1, &["settings.samples", "between 1 and 16"]);
    check(&*with_camera(cam, r#"{ "spp": 0 }"#), 1, &["settings.spp", "between 1 and 16777216, got 0"]);
    check(&*with_camera(cam, r#"{ "noise": 0 }"#), 1, &["settings.noise", "must be finite and > 0, got 0"]);
    check(&*with_camera(cam, r#"{ "noise": -0.5 }"#), 1, &["settings.noise", "got -0.5"]);
    check(
        &*with_camera(cam, r#"{ "integrator": "bdpt" }"#),
        1,
        &["settings.integrator", "expected `whitted` or `path`"],
    );
    check(
        &*with_material(r#"{ "emission": [1, -1, 0] }"#),
        1,
        &["materials.m.emission, line 1", "must not be negative"],
    );
    check(&*with_camera(cam, r#"{ "max_depth": 1000000 }"#), 1, &["settings.max_depth", "at most 64"]);
    check(&*with_camera(cam, r#"{ "background": [-1, 0, 0] }"#), 1, &["settings.background", "must not be negative"]);
    check(&*with_camera(cam, r#"{ "ambient": [0, -0.1, 0] }"#), 1, &["settings.ambient", "must not be negative"]);
    check(&*with_material(r#"{ "ior": 0 }"#), 1, &["materials.m.ior, line 1", "ior must be finite and > 0, got 0"]);
    check(&*with_material(r#"{ "ior": -1.5 }"#), 1, &["materials.m.ior", "got -1.5"]);
    check(&*with_material(r#"{ "diffuse": [-1, 0, 0] }"#), 1, &["materials.m.diffuse, line 1", "must not be negative"]);
    check(&*with_material(r#"{ "transmit": [0, 0, -0.5] }"#), 1, &["materials.m.transmit", "must not be negative"]);
    // Textures and bump maps (docs/model.md §5.4).
    let texture_cases: [(&str, &[&str]); 12] = [
        (r#"{ "diffuse": { "checker": { "scale": 0 } } }"#, &["materials.m.diffuse.checker.scale, line 1, column 142: scale must be finite and > 0, got 0"]),
        (r#"{ "bump": { "noise": { "scale": -2 } } }"#, &["materials.m.bump.noise.scale, line 1", "got -2"]),
        (r#"{ "diffuse": { "noise": { "octaves": 0 } } }"#, &["materials.m.diffuse.noise.octaves, line 1, column 142: octaves must be between 1 and 16, got 0"]),
        (r#"{ "ambient": { "wood": { "octaves": 17 } } }"#, &["materials.m.ambient.wood.octaves", "got 17"]),
        (r#"{ "bump": { "noise": { "octaves": 17 } } }"#, &["materials.m.bump.noise.octaves", "got 17"]),
        (r#"{ "diffuse": { "marble": { "turbulence": -1 } } }"#, &["materials.m.diffuse.marble.turbulence, line 1, column 146: turbulence must be finite and >= 0, got -1"]),
        (r#"{ "diffuse": { "wood": { "colors": [[1, 1, 1], [0, -1, 0]] } } }"#, &["materials.m.diffuse.wood.colors[1], line 1, column 152: diffuse must not be negative, got [0.0, -1.0, 0.0]"]),
        (r#"{ "bump": { "noise": { "strength": -1 } } }"#, &["materials.m.bump.noise.strength, line 1, column 140: strength must be finite and >= 0, got -1"]),
        (r#"{ "diffuse": { "chequer": { } } }"#, &["materials.m.diffuse, line 1, column 128: unknown variant `chequer`", "(did you mean `checker`?)"]),
        (r#"{ "diffuse": { "checker": { "scale": 1 }, "noise": {} } }"#, &["materials.m.diffuse, line 1, column 153: a texture has one key, got `checker` and `noise`"]),
        (r#"{ "diffuse": {} }"#, &["materials.m.diffuse, line 1, column 119: a texture needs one key"]),
        (r#"{ "diffuse": "red" }"#, &["materials.m.diffuse, line 1, column 122: invalid type: string \"red\", expected a colour [r, g, b] or a texture"]),
    ];
    for (m, want) in texture_cases {
        check(&*with_material(m), 1, want);
    }
    // A name with a dot is written as a quoted step, and still located.
    check(
        &*format!(
            r#"{{ {CAMERA}, "materials": {{ "oak.v2": {{ "diffuse": [-1, 0, 0] }} }}, "blocks": [ {{ "material": "oak.v2", "objects": [ {{ "sphere": {{}} }} ] }} ] }}"#
        ),
        1,
        &[r#"materials["oak.v2"].diffuse, line 1, column 123"#, "must not be negative"],
    );
    check(
        &*with_material(r#"{ "shininess": -2 }"#),
        1,
        &["materials.m.shininess, line 1", "shininess must be finite and >= 0, got -2"],
    );
    check(
        &*format!(
            r#"{{ {CAMERA}, "lights": [ {{ "position": [0, 0, 9], "color": [1, -1, 1] }} ], "blocks": [ {{ "objects": [ {{ "sphere": {{}} }} ] }} ] }}"#
        ),
        1,
        &["lights[0], line 1", "the colour must not be negative"],
    );
}

#[test]
fn deep_nesting_is_refused_without_overflowing_the_stack() {
    // serde_json stops at 128 levels of brackets; the message abbreviates the path.
    check(
        &*nested(10_000),
        1,
        &[
            "bad.json: blocks[0].blocks[0].blocks[0].blocks[0].(… ",
            "more levels …)",
            "line 1, column",
            "nested too deeply",
        ],
    );
    // Within the limit, nesting is fine.
    let dir = tempdir();
    let p = write_scene(dir.path(), "deep.json", &nested(50));
    let o = komplex(dir.path(), &["render", p.to_str().unwrap(), "-o", "deep.exr"]);
    assert!(o.status.success(), "{}", text(&o));
}

#[test]
fn scene_files_that_cannot_be_read_exit_3() {
    check(&["render", "does-not-exist.json"], 3, &["error: does-not-exist.json: No such file or directory"]);
    // Readable but not UTF-8: bad input, located like a syntax error.
    check(
        &["render", "latin1.json", "-o", "out.exr"],
        1,
        &["error: latin1.json: line 1, column 14: the file is not UTF-8 (byte 0xe9)"],
    );
    check(&["render", "dir.json", "-o", "out.exr"], 3, &["dir.json: Is a directory"]);
    check(&["check", "dir.json"], 3, &["dir.json: Is a directory"]);
}

#[test]
fn outputs_that_cannot_be_written_exit_3_before_rendering() {
    check(
        &["render", "ok.json", "-o", "missing/dir/out.exr"],
        3,
        &["missing/dir/out.exr: cannot create a file in directory missing/dir: No such file or directory"],
    );
    // Tests run as root, which may write anywhere: a directory that is a
    // regular file, and /proc, refuse even root.
    check(
        &["render", "ok.json", "-o", "file/out.exr"],
        3,
        &["cannot create a file in directory file: Not a directory"],
    );
    check(
        &["render", "ok.json", "-o", "/proc/out.exr"],
        3,
        &["/proc/out.exr: cannot create a file in directory /proc"],
    );
    check(&["render", "ok.json", "-o", "dir.json"], 3, &["dir.json: is a directory, not a file"]);
    // Renaming over a special file would replace it (think `-o /dev/null`).
    let fifo = tempdir();
    let pipe = fifo.path().join("pipe");
    assert!(std::process::Command::new("mkfifo").arg(&pipe).status().unwrap().success());
    check(&["render", "ok.json", "-o", pipe.to_str().unwrap()], 3, &["pipe: is not a regular file"]);
    assert!(pipe.exists() && !pipe.is_file(), "the pipe was replaced");
    // A bad preview path fails before the EXR is written, not after.
    check(&["render", "ok.json", "-o", "out.exr", "--png", "missing/out.png"], 3, &["missing/out.png: cannot create"]);
}

#[test]
fn failed_generate_and_export_pov_leave_an_existing_output_untouched() {
    // `out.exr` stands for any earlier output; `check` compares the whole
    // directory, so a leftover temporary file fails too.
    check(
        &["export-pov", "latin1.json", "-o", "out.exr"],
        1,
        &["latin1.json: line 1, column 14: the file is not UTF-8"],
    );
    check(&["export-pov", "dir.json", "-o", "out.exr"], 3, &["dir.json: Is a directory"]);
    check(
        &["export-pov", "ok.json", "-o", "out.exr", "--width", "0"],
        1,
        &["--width/--height: the image size 0x1 is empty"],
    );
    check(&["generate", "grid", "--count", "0", "-o", "out.exr"], 2, &["invalid value '0' for '--count <COUNT>'"]);
    // Outputs that cannot be written: refused as the render refuses them.
    check(&["export-pov", "ok.json", "-o", "dir.json"], 3, &["dir.json: is a directory, not a file"]);
    check(
        &["generate", "sphereflake", "-o", "missing/dir/out.json"],
        3,
        &["missing/dir/out.json: cannot create a file in directory missing/dir: No such file or directory"],
    );
    let fifo = tempdir();
    let pipe = fifo.path().join("pipe");
    assert!(std::process::Command::new("mkfifo").arg(&pipe).status().unwrap().success());
    check(&["generate", "sphereflake", "-o", pipe.to_str().unwrap()], 3, &["pipe: is not a regular file"]);
    assert!(pipe.exists() && !pipe.is_file(), "the pipe was replaced");
}

/// A write that fails part way through (past the file-size limit of
/// `ulimit -f`, with SIGXFSZ ignored so that the write returns `EFBIG`
/// instead of killing the process) leaves the earlier file as it was, and
/// no temporary file.
#[test]
fn a_write_that_fails_part_way_leaves_the_earlier_output() {
    let table = scene("table.json");
    let table = table.to_str().unwrap();
    for args in [
        vec!["generate", "sphereflake", "--level", "2", "-o", "out.json"],
        vec!["generate", "grid", "--count", "50", "-o", "out.json"],
        vec!["export-pov", table, "-o", "out.json"],
    ] {
        let dir = tempdir();
        let d = dir.path();
        std::fs::write(d.join("out.json"), b"keep me").unwrap();
        let before = snapshot(d);
        // One 512-byte block; every output here is several kilobytes.
        let o = std::process::Command::new("sh")
            .arg("-c")
            .arg("trap '' XFSZ; ulimit -f 1; exec \"$@\"")
            .arg("sh")
            .arg(env!("CARGO_BIN_EXE_komplex"))
            .args(&args)
            .current_dir(d)
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(3), "{args:?}: {}", text(&o));
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.starts_with("error: out.json: ") && err.contains("File too large"), "{args:?}: {err}");
        assert!(snapshot(d) == before, "{args:?}: the directory changed: {:?}", snapshot(d).keys().collect::<Vec<_>>());
    }
}

#[test]
fn bad_option_values_exit_1() {
    check(&["render", "ok.json", "-o", "out.exr", "--threads", "0"], 1, &["--threads must be at least 1"]);
    check(
        &["render", "ok.json", "-o", "out.exr", "--threads", "100000"],
        1,
        &["--threads must be at most 1024, got 100000"],
    );
    check(
        &["render", "ok.json", "-o", "out.exr", "--width", "0"],
        1,
        &["--width/--height: the image size 0x1 is empty"],
    );
    check(&["render", "ok.json", "-o", "out.exr", "--width", "100000"], 1, &["100000x75000 is too large"]);
    check(&["render", "ok.json", "-o", "out.exr", "--samples", "17"], 1, &["--samples must be between 1 and 16"]);
    check(&["render", "ok.json", "-o", "out.exr", "--spp", "0"], 1, &["--spp must be between 1 and 16777216, got 0"]);
    check(&["render", "ok.json", "-o", "out.exr", "--noise", "0"], 1, &["--noise must be a finite number > 0, got 0"]);
    check(&["bench", "ok.json", "--runs", "0"], 1, &["--runs must be between 1 and 1000, got 0"]);
    check(
        &["render", "ok.json", "-o", "out.exr", "--png", "p.png", "--exposure", "nan"],
        1,
        &["--exposure must be a finite number of stops, got NaN"],
    );
    check(
        &["trace", "ok.json", "--origin", "0", "0", "5", "--direction", "0", "0", "0"],
        1,
        &["--origin/--direction: the ray direction is zero"],
    );
    check(&["check", "bad-file-name.json"], 3, &["bad-file-name.json"]);
    check(&["volume", "ok.json", "--tolerance", "0"], 1, &["--tolerance must be a finite number > 0, got 0"]);
    check(&["volume", "ok.json", "--tolerance", "-1e-3"], 1, &["--tolerance must be a finite number > 0, got -0.001"]);
    check(&["overlaps", "ok.json", "--tolerance", "nan"], 1, &["--tolerance must be a finite number > 0, got NaN"]);
    check(
        &["volume", "ok.json", "--box", "1", "0", "0", "0", "1", "1"],
        1,
        &["--box must be six finite numbers XMIN YMIN ZMIN XMAX YMAX ZMAX with each min <= max, got [1.0, 0.0, 0.0, 0.0, 1.0, 1.0]"],
    );
    check(
        &["volume", "ok.json", "-o", "missing/dir/v.txt"],
        3,
        &["missing/dir/v.txt: cannot create a file in directory"],
    );
}

#[test]
fn usage_errors_exit_2() {
    check(&["render"], 2, &["required arguments were not provided", "<SCENE>"]);
    check(&["render", "ok.json", "--bogus"], 2, &["unexpected argument '--bogus'"]);
    check(&["render", "ok.json", "--threads", "many"], 2, &["invalid value 'many' for '--threads <N>'"]);
    check(
        &["trace", "ok.json", "--origin", "0", "0"],
        2,
        &["3 values required for '--origin <X> <Y> <Z>' but 2 were provided"],
    );
    check(&["paint", "ok.json"], 2, &["unrecognized subcommand 'paint'"]);
    check(&[""; 0], 2, &["Usage: komplex <COMMAND>"]);
}

/// A scene whose only block is a half-space (unbounded).
const HALF: &[u8] = br#"{ "camera": { "eye": [0, 0, 5], "direction": [0, 0, -1] },
                          "blocks": [ { "objects": [ { "halfspace": [0, 1, 0, 0] } ] } ] }"#;

#[test]
fn bad_slices_exit_1_and_name_the_option() {
    let slice = |extra: &[&str], needle: &str| {
        let mut args = vec!["slice", "ok.json", "-o", "s.png"];
        args.extend(extra);
        check(Input::Args(&args), 1, &[needle]);
    };
    slice(&["--plane", "w=1"], r#"--plane "w=1": the axis must be x, y or z, not "w""#);
    slice(&["--plane", "z=abc"], r#"--plane "z=abc": "abc" is not a number"#);
    slice(&["--plane", "z0.5"], r#"--plane "z0.5": expected x=C, y=C or z=C with a number C"#);
    slice(&["--plane", "z=inf"], r#"--plane "z=inf": the coordinate must be finite"#);
    slice(&["--normal", "0", "0", "0"], "--normal: the normal [0.0, 0.0, 0.0] is zero or not finite");
    slice(
        &["--normal", "0", "0", "1", "--up", "0", "0", "2"],
        "--up: the vector [0.0, 0.0, 2.0] is zero or parallel to the normal",
    );
    slice(
        &["--normal", "1", "0", "0", "--origin", "nan", "0", "0"],
        "--origin: the point [NaN, 0.0, 0.0] is not finite",
    );
    slice(&["--plane", "z=0", "--size", "0", "10"], "--size: the image size 0x10 is empty");
    slice(&["--plane", "z=0", "--size", "100000", "100000"], "--size: the image size 100000x100000 is too large");
    slice(&["--plane", "z=0", "--extent", "1", "0", "0", "1"], "--extent 1 0 0 1: needs finite U0 < U1 and V0 < V1");
    slice(&["--plane", "z=5"], "the plane does not cut the scene's bounding box: give --extent U0 U1 V0 V1");
    check(
        &["slice", "ok.json", "--plane", "z=0", "-o", "s.tiff"],
        1,
        &["-o s.tiff: the slice is written as .png or .exr"],
    );
    check_with(
        &[("half.json", HALF)],
        &["slice", "half.json", "--plane", "z=0", "-o", "s.png"],
        1,
        &["the scene is unbounded (or empty), so the slice has no default extent: give --extent U0 U1 V0 V1"],
    );
    check(
        &["slice", "ok.json", "--plane", "z=0", "-o", "missing/s.png"],
        3,
        &["missing/s.png: cannot create a file in directory missing"],
    );
    check(&["slice", "ok.json", "--plane", "z=0"], 2, &["required arguments were not provided", "--output"]);
    check(
        &["slice", "ok.json", "--plane", "z=0", "--normal", "0", "0", "1", "-o", "s.png"],
        2,
        &["cannot be used with"],
    );
}

/// A `.npy` file's bytes: the header dict, padded, then `data`.
fn npy(major: u8, header: &str, data: &[u8]) -> Vec<u8> {
    let mut out = b"\x93NUMPY".to_vec();
    out.extend([major, 0]);
    out.extend_from_slice(&(header.len() as u16).to_le_bytes());
    out.extend_from_slice(header.as_bytes());
    out.extend_from_slice(data);
    out
}

#[test]
fn bad_ray_files_exit_1_and_name_the_place() {
    let rays = |name: &str, contents: &[u8], needle: &str| {
        check_with(&[(name, contents)], &["trace", "ok.json", "--rays", name, "-o", "out.csv"], 1, &[needle]);
    };
    rays(
        "r.csv",
        b"ox,oy,oz,dx,dy,dz\n0,0,5,0,0,-1\n0,0,five,0,0,-1\n",
        r#"r.csv: line 3, column 5: "five" is not a number"#,
    );
    rays("r.csv", b"0,0,5,0,0\n", "r.csv: line 1: expected 6 numbers (ox,oy,oz,dx,dy,dz), found 5 fields");
    rays("r.csv", b"# a comment\n\n0,0,5,0,0,-1\n1,0,5,0,0,0\n", "r.csv: line 4 (ray 1): the ray direction is zero");
    rays("r.csv", b"inf,0,5,0,0,-1\n", "r.csv: line 1 (ray 0): the ray origin is not finite");
    rays("r.csv", b"0,0,5,0,0,-1\n\xff\n", "r.csv: line 2: the file is not UTF-8 text (byte 14)");
    let f8 = |v: &[f64]| v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();
    let one = f8(&[0.0, 0.0, 5.0, 0.0, 0.0, -1.0]);
    rays("r.npy", b"ox,oy,oz,dx,dy,dz\n", r"r.npy: not a .npy file (it does not start with \x93NUMPY)");
    rays("r.npy", &npy(4, "{}", &[]), "r.npy: header: .npy format version 4 is not supported (1, 2 or 3 are)");
    rays(
        "r.npy",
        &npy(1, "{'descr': '>f8', 'fortran_order': False, 'shape': (1, 6), }\n", &one),
        "r.npy: header: the array's type is '>f8'; only little-endian float64 ('<f8') or float32 ('<f4') are read",
    );
    rays(
        "r.npy",
        &npy(1, "{'descr': '<f8', 'fortran_order': False, 'shape': (2, 3), }\n", &one),
        "r.npy: header: the shape is (2, 3); expected (N, 6) or (N, 2, 3)",
    );
    rays(
        "r.npy",
        &npy(1, "{'descr': '<f8', 'fortran_order': False, 'shape': (2, 6), }\n", &one),
        "r.npy: the data holds 48 bytes; the shape (2, 6) of '<f8' needs 96 bytes",
    );
    rays(
        "r.npy",
        &npy(1, "{'descr': '<f8', 'shape': (1, 6), }\n", &one),
        "r.npy: header: no 'fortran_order' in {'descr': '<f8', 'shape': (1, 6), }",
    );
    rays(
        "r.npy",
        &npy(
            1,
            "{'descr': '<f8', 'fortran_order': False, 'shape': (2, 6), }\n",
            &f8(&[0.0, 0.0, 5.0, 0.0, 0.0, -1.0, 1.0, 0.0, 5.0, 0.0, 0.0, 0.0]),
        ),
        "r.npy: ray 1: the ray direction is zero",
    );
    check(&["trace", "ok.json", "--rays", "none.csv"], 3, &["none.csv: No such file or directory"]);
    check(
        &["trace", "ok.json", "--rays", "none.csv", "-o", "missing/out.csv"],
        3,
        &["missing/out.csv: cannot create a file in directory missing"],
    );
    check(
        &["trace", "ok.json", "--rays", "r.csv", "--origin", "0", "0", "5"],
        2,
        &["the argument '--rays <FILE>' cannot be used with '--origin <X> <Y> <Z>'"],
    );
    check(
        &["trace", "ok.json", "-o", "out.csv", "--origin", "0", "0", "5", "--direction", "0", "0", "-1"],
        1,
        &["-o/--output goes with --rays; one ray's report is printed"],
    );
}

/// A scene with these `definitions` (the inside of the object) and top `blocks`.
fn with_definitions(definitions: &str, b: &str) -> String {
    format!(r#"{{ {CAMERA}, "definitions": {{ {definitions} }}, "blocks": [ {b} ] }}"#)
}

const PIN: &str = r#""pin": { "blocks": [ { "name": "rod", "objects": [ { "sphere": {} } ] } ] }"#;

#[test]
fn definitions_that_place_themselves_name_the_cycle() {
    let ball = r#"{ "objects": [ { "sphere": {} } ] }"#;
    check(
        &*with_definitions(&format!(r#""a": {{ "blocks": [ {ball}, {{ "instance": "a" }} ] }}"#), ball),
        1,
        &["definitions.a.blocks[1], line 1, column", "a definition places itself: definitions.a → definitions.a"],
    );
    // Through another definition, from inside a group, by a lattice.
    let defs = r#""a": { "blocks": [ { "instance": "b" } ] },
                  "b": { "blocks": [ { "group": "g", "blocks": [ { "lattice": "a", "pitch": [1, 0, 0], "count": [2, 1, 1] } ] } ] }"#;
    check(
        &*with_definitions(defs, ball),
        1,
        &[
            "definitions.b.blocks[0].blocks[0], line 2, column",
            "a definition places itself: definitions.a → definitions.b → definitions.a",
        ],
    );
}

#[test]
fn instances_and_lattices_are_checked() {
    check(
        &*with_definitions(PIN, r#"{ "instance": "pni" }"#),
        1,
        &["blocks[0].instance, line 1, column", "unknown definition \"pni\" (did you mean \"pin\"?)"],
    );
    check(
        &*with_definitions(PIN, r#"{ "lattice": "pin", "pitch": [1, 0, 0], "count": [3, 0, 1] }"#),
        1,
        &[
            "blocks[0].count, line 1, column",
            "lattice of \"pin\": count must be at least 1 on every axis, got [3, 0, 1]",
        ],
    );
    check(
        &*with_definitions(PIN, r#"{ "lattice": "pin", "pitch": [1e306, 0, 0], "count": [1000, 1, 1] }"#),
        1,
        &["blocks[0].pitch, line 1, column", "lattice of \"pin\": the pitch and pitch × (count − 1) must be finite"],
    );
    check(
        &*with_definitions(PIN, r#"{ "lattice": "pin", "count": [10, 1, 1] }"#),
        1,
        &["blocks[0].pitch, line 1, column", "lattice of \"pin\" needs `pitch` and `count`"],
    );
    check(
        &*with_definitions(PIN, r#"{ "instance": "pin", "count": [10, 1, 1] }"#),
        1,
        &[
            "blocks[0].count, line 1, column",
            "instance of \"pin\": `count` belongs on a lattice (`\"lattice\": \"pin\"`)",
        ],
    );
    check(
        &*with_definitions(PIN, r#"{ "instance": "pin", "material": "x" }"#),
        1,
        &["blocks[0].material, line 1, column", "instance of \"pin\": `material` does not belong on an instance"],
    );
    check(
        &*with_definitions(PIN, r#"{ "instance": "pin", "lattice": "pin" }"#),
        1,
        &["blocks[0], line 1, column", "an entry has either `instance` or `lattice`, not both"],
    );
    check(
        &*blocks(r#"{ "objects": [ { "sphere": {} } ], "pitch": [1, 0, 0] }"#),
        1,
        &[
            "blocks[0].pitch, line 1, column",
            "`pitch` belongs on a lattice (`\"lattice\": \"NAME\"`), not on a block or group",
        ],
    );
    check(
        &*with_definitions(r#""pin": { "blocks": [] }"#, r#"{ "objects": [ { "sphere": {} } ] }"#),
        1,
        &["definitions.pin, line 1, column", "definition \"pin\" has no blocks"],
    );
}

#[test]
fn a_lattice_beyond_the_block_ids_fails_at_once() {
    // 70000 × 70000 elements of a one-block definition: 4.9e9 blocks. Refused
    // from the numbers, before anything is allocated for them.
    check(
        &*with_definitions(PIN, r#"{ "lattice": "pin", "pitch": [1, 1, 0], "count": [70000, 70000, 1] }"#),
        1,
        &[
            "blocks[0], line 1, column",
            "lattice of \"pin\": the scene would have more than 4294967294 blocks (the most a block id can number): \
             4900000000 elements of 1 block each",
        ],
    );
    // The sum of entries each within the limit.
    let half = r#"{ "lattice": "pin", "pitch": [1, 1, 0], "count": [65536, 32768, 1] }"#;
    check(
        &*with_definitions(PIN, &format!("{half}, {half}")),
        1,
        &["blocks[1], line 1, column", "more than 4294967294 blocks"],
    );
}

#[test]
fn lattices_the_kernel_cannot_walk_and_chains_too_deep_are_refused() {
    // A pitch <= 0 is placed element by element, up to 65536 elements.
    check(
        &*with_definitions(PIN, r#"{ "lattice": "pin", "pitch": [-1, 0, 0], "count": [70000, 1, 1] }"#),
        1,
        &[
            "blocks[0].pitch, line 1, column",
            "lattice of \"pin\": a lattice with a pitch <= 0 on an axis of several elements is placed element by \
             element, at most 65536 elements, got 70000",
        ],
    );
    check(
        &*with_definitions(
            r#""floor": { "blocks": [ { "objects": [ { "halfspace": [0, 1, 0, 0] } ] } ] }"#,
            r#"{ "lattice": "floor", "pitch": [1, 0, 0], "count": [2, 1, 1] }"#,
        ),
        1,
        &["blocks[0], line 1, column", "a lattice's definition must be bounded"],
    );
    // d00 places d01, which places d02, ... d40: 41 levels.
    let mut defs: Vec<String> =
        (0..40).map(|i| format!(r#""d{i:02}": {{ "blocks": [ {{ "instance": "d{:02}" }} ] }}"#, i + 1)).collect();
    defs.push(r#""d40": { "blocks": [ { "objects": [ { "sphere": {} } ] } ] }"#.into());
    check(
        &*with_definitions(&defs.join(", "), r#"{ "instance": "d00" }"#),
        1,
        &["definitions.d08.blocks[0], line 1, column", "definitions place each other deeper than 32 levels"],
    );
}

#[test]
fn commands_that_list_every_block_refuse_huge_expansions() {
    let big = with_definitions(PIN, r#"{ "lattice": "pin", "pitch": [3, 3, 3], "count": [128, 128, 128] }"#);
    let files: &[(&str, &[u8])] = &[("big.json", big.as_bytes())];
    let many = "the scene has 2097152 blocks (instances and lattices expanded), more than the";
    check_with(files, &["volume", "big.json"], 1, &["error: volume: ", many, "1048576 it measures one by one"]);
    check_with(files, &["overlaps", "big.json"], 1, &["error: overlaps: ", many, "1048576 it measures one by one"]);
    check_with(
        files,
        &["export-pov", "big.json", "-o", "out.pov"],
        1,
        &["error: export-pov: ", many, "65536 it writes out one by one"],
    );
}

#[test]
fn bad_tiles_exit_1_and_name_the_option() {
    let tile =
        |t: &str, needle: &str| check(Input::Args(&["render", "ok.json", "-o", "out.exr", "--tile", t]), 1, &[needle]);
    tile("1-4", r#"--tile "1-4": expected I/N (part I of N, 0-based, e.g. 2/4) or auto/N, with whole numbers"#);
    tile("4/4", "--tile 4/4: the part index must be below 4 (parts are numbered from 0)");
    tile("0/0", "--tile 0/0: the number of parts must be at least 1");
    tile("0/7", "--tile 0/7: 7 parts of an image 6 rows high; at most 6 (a part is a band of whole rows)");
    tile("auto/4", "--tile auto/4: neither SLURM_ARRAY_TASK_ID nor JOB_COMPLETION_INDEX is set, so there is no task index to render");
    let auto = ["render", "ok.json", "-o", "out.exr", "--tile", "auto/4"];
    for (name, value) in [("SLURM_ARRAY_TASK_ID", "4"), ("SLURM_ARRAY_TASK_ID", "x"), ("JOB_COMPLETION_INDEX", "-1")] {
        check_env(
            &[(name, value)],
            &[],
            &auto,
            1,
            &[&format!("--tile auto/4: {name} is {value:?}, not a part index from 0 to 3 (the index is read from SLURM_ARRAY_TASK_ID, else JOB_COMPLETION_INDEX)")],
        );
    }
    check(
        &["render", "ok.json", "-o", "out.exr", "--tile", "0/2", "--png", "p.png"],
        1,
        &["--png goes with a whole image, not --tile: give it to komplex merge"],
    );
    check(&["render", "ok.json", "--resume"], 2, &["required arguments were not provided", "--tile <I/N>"]);
}

#[test]
fn bad_merges_exit_1_and_name_the_part() {
    // Parts of `ok.json` (the fixture's scene), rendered beforehand.
    let made = tempdir();
    let m = made.path();
    write_scene(m, "ok.json", OK);
    for args in [
        &["-o", "p.exr", "--tile", "0/3"][..],
        &["-o", "p.exr", "--tile", "1/3"],
        &["-o", "p.exr", "--tile", "2/3"],
        &["-o", "q.exr", "--tile", "1/3", "--seed", "1"],
        &["-o", "w.exr", "--tile", "1/2"],
        &["-o", "one.exr"],
    ] {
        komplex_ok(m, &[&["render", "ok.json"], args].concat());
    }
    let read = |name: &str| std::fs::read(m.join(name)).unwrap();
    let p1 = read("p.tile-1-of-3.exr");
    let crafted = |rows, names: &[&str], tags: &[(&str, &str)], layers| {
        crate::tiles::crafted_part((8, 6), rows, names, tags, layers)
    };
    let tags = [("komplex.tile", "0/2"), ("komplex.render", "r")];
    use exr::prelude::Encoding;
    let encoded = |encoding, rows, tags: &[(&str, &str)]| {
        crate::tiles::crafted_encoded(encoding, (8, 6), rows, &["B", "G", "R"], tags, 1)
    };
    let files: Vec<(&str, Vec<u8>)> = vec![
        ("p.tile-0-of-3.exr", read("p.tile-0-of-3.exr")),
        ("p.tile-1-of-3.exr", p1.clone()),
        ("p.tile-2-of-3.exr", read("p.tile-2-of-3.exr")),
        ("q.tile-1-of-3.exr", read("q.tile-1-of-3.exr")),
        ("w.tile-1-of-2.exr", read("w.tile-1-of-2.exr")),
        ("one.exr", read("one.exr")),
        ("cut.exr", p1[..p1.len() - 100].to_vec()),
        ("a.exr", crafted((0, 3), &["B", "G", "R"], &tags, 1)),
        (
            "size.exr",
            crate::tiles::crafted_part(
                (8, 5),
                (2, 5),
                &["B", "G", "R"],
                &[("komplex.tile", "1/2"), ("komplex.render", "r")],
                1,
            ),
        ),
        ("channels.exr", crafted((3, 6), &["G", "R"], &[("komplex.tile", "1/2"), ("komplex.render", "r")], 1)),
        ("window.exr", crafted((2, 6), &["B", "G", "R"], &[("komplex.tile", "1/2"), ("komplex.render", "r")], 1)),
        ("index.exr", crafted((0, 3), &["B", "G", "R"], &[("komplex.tile", "5/4"), ("komplex.render", "r")], 1)),
        ("norender.exr", crafted((0, 3), &["B", "G", "R"], &[("komplex.tile", "0/2")], 1)),
        ("layers.exr", crafted((0, 3), &["B", "G", "R"], &tags, 2)),
        ("depth.exr", crafted((0, 6), &["Z"], &[("komplex.tile", "0/1"), ("komplex.render", "r")], 1)),
        ("zip16.exr", encoded(Encoding::SMALL_LOSSLESS, (3, 6), &[("komplex.tile", "1/2"), ("komplex.render", "r")])),
        ("tiled.exr", encoded(Encoding::FAST_LOSSLESS, (0, 3), &tags)),
    ];
    let files: Vec<(&str, &[u8])> = files.iter().map(|(n, b)| (*n, b.as_slice())).collect();
    let merge = |parts: &[&str], code: i32, needle: &str| {
        let args = [&["merge"], parts, &["-o", "m.exr", "--png", "m.png"]].concat();
        check_with(&files, Input::Args(&args), code, &[needle]);
    };
    let (p0, p1, p2) = ("p.tile-0-of-3.exr", "p.tile-1-of-3.exr", "p.tile-2-of-3.exr");
    merge(&[p0, p2], 1, "tile 1/3 is missing: none of the 2 parts given holds it (tile 1 would be p.tile-1-of-3.exr)");
    merge(&[p0, p1, p1, p2], 1, "p.tile-1-of-3.exr: tile 1/3 again: p.tile-1-of-3.exr holds it too");
    merge(&[p0, "q.tile-1-of-3.exr", p2], 1, "q.tile-1-of-3.exr: a foreign part: it is a tile of another render (another scene or other options: komplex.render ");
    merge(&[p0, "w.tile-1-of-2.exr"], 1, "w.tile-1-of-2.exr: a foreign part: tile 1/2 is one of 2 parts, not 3, unlike p.tile-0-of-3.exr (the first part)");
    merge(
        &["a.exr", "size.exr"],
        1,
        "size.exr: a foreign part: its image is 8x5, not 8x6, unlike a.exr (the first part)",
    );
    merge(&["a.exr", "channels.exr"], 1, "channels.exr: a foreign part: its channels are [G F32, R F32], not [B F32, G F32, R F32], unlike a.exr (the first part)");
    merge(
        &["a.exr", "window.exr"],
        1,
        "window.exr: tile 1/2 of an image 8x6 is rows 3..6 of the full width, but the data window is 8x4 at (0, 2)",
    );
    merge(
        &[p0, p1, p2, "one.exr"],
        1,
        "one.exr: not a tile of a render: the header has no komplex.tile attribute (komplex render --tile writes it)",
    );
    merge(&[p0, "file"], 1, "file: not a readable OpenEXR file: invalid: file identifier missing");
    merge(&[p0, "cut.exr", p2], 1, "cut.exr: not a readable OpenEXR file: invalid: reference to missing bytes");
    merge(&["index.exr"], 1, r#"index.exr: komplex.tile is "5/4", not I/N with I < N"#);
    merge(&["norender.exr"], 1, "norender.exr: tile 0/2 has no komplex.render attribute");
    merge(&["layers.exr"], 1, "layers.exr: holds 2 parts; a tile holds one");
    merge(
        &["a.exr", "zip16.exr"],
        1,
        "zip16.exr: a foreign part: its compression is ZIP16, not Uncompressed, unlike a.exr (the first part)",
    );
    merge(&["tiled.exr"], 1, "tiled.exr: its pixels are stored in tiles or deep samples, not in scanlines as a part's");
    merge(&["zip16.exr"], 1, "zip16.exr: its compression (ZIP16) stores 16 rows a block, and rows 3..6 are not whole blocks of the image; render --tile writes one row a block");
    merge(&["depth.exr"], 1, "--png: the parts have no R, G and B channels");
    merge(&[p0, "none.exr"], 3, "none.exr: No such file or directory (os error 2)");
    check_with(
        &files,
        &["merge", p0, p1, p2, "-o", "missing/m.exr"],
        3,
        &["missing/m.exr: cannot create a file in directory missing"],
    );
    check_with(
        &files,
        &["merge", p0, p1, p2, "-o", "m.exr", "--png", "m.png", "--exposure", "nan"],
        1,
        &["--exposure must be a finite number of stops, got NaN"],
    );
    check(&["merge", "-o", "m.exr"], 2, &["required arguments were not provided", "<PARTS>"]);
}

#[test]
fn bad_openmc_imports_exit_1_and_name_the_place() {
    let cases: &[(&str, &str, &str)] = &[
        ("xml", r#"<geometry><cell id="1" material="1"></geometry>"#, "line 1, column 37: not well-formed XML"),
        ("root", "<materials/>", "line 1, column 1: expected <geometry> or <model>, found <materials>"),
        (
            "attr",
            r#"<geometry><surface id="1" type="sphere" coeffs="0 0 0 1"/><cell id="4" material="1" regoin="-1"/></geometry>"#,
            "line 1, column 59: <cell>: unknown attribute `regoin` (did you mean `region`?)",
        ),
        (
            "type",
            r#"<geometry><surface id="1" type="spere" coeffs="0 0 0 1"/></geometry>"#,
            "line 1, column 11: surface 1: unknown surface type `spere` (did you mean `sphere`?)",
        ),
        (
            "coeffs",
            r#"<geometry><surface id="1" type="sphere" coeffs="0 0 1"/></geometry>"#,
            "line 1, column 11: surface 1: `sphere` takes 4 coefficients, got 3",
        ),
        (
            "undefined",
            r#"<geometry><surface id="10" type="sphere" coeffs="0 0 0 1"/><cell id="4" material="1" region="-11"/></geometry>"#,
            "line 1, column 60: cell 4: region: surface 11 is not defined (did you mean 10?)",
        ),
        (
            "region",
            r#"<geometry><surface id="1" type="sphere" coeffs="0 0 0 1"/><cell id="4" material="1" region="-1 (2"/></geometry>"#,
            "line 1, column 59: cell 4: region `-1 (2`: character 4: `(` is never closed",
        ),
        (
            "torus",
            r#"<geometry><surface id="1" type="x-torus" coeffs="0 0 0 1 1 1"/><cell id="4" material="1" region="-1"/></geometry>"#,
            "line 1, column 64: cell 4: surface 1 is a x-torus, not a quadric: not supported yet",
        ),
        (
            "hex",
            r#"<geometry><hex_lattice id="5"/><cell id="4" fill="5"/></geometry>"#,
            "line 1, column 11: lattice 5: hexagonal lattices are not supported yet (filling cell 4)",
        ),
        (
            "cycle",
            r#"<geometry><surface id="1" type="sphere" coeffs="0 0 0 1"/><cell id="1" fill="2" region="-1"/><cell id="2" universe="2" fill="3"/><cell id="3" universe="3" fill="2"/></geometry>"#,
            "line 1, column 130: cell 3: fills form a cycle: universe 2 → universe 3 → universe 2",
        ),
        (
            "roots",
            r#"<geometry><cell id="1" material="1"/><cell id="2" universe="1" material="2"/></geometry>"#,
            "line 1, column 1: more than one universe fills nothing, so the root is ambiguous: 0, 1",
        ),
        (
            "count",
            r#"<geometry><surface id="1" type="sphere" coeffs="0 0 0 1"/><cell id="1" fill="5" region="-1"/><lattice id="5"><dimension>2 1</dimension><lower_left>0 0</lower_left><pitch>1 1</pitch><universes>2</universes></lattice><cell id="2" universe="2" material="1"/></geometry>"#,
            "line 1, column 182: lattice 5: universes: 1 entries for 2 × 1 × 1 elements",
        ),
        (
            "outer",
            r#"<geometry><surface id="1" type="sphere" coeffs="0 0 0 1"/><cell id="1" fill="5" region="+1"/><cell id="9" material="2" region="-1"/><lattice id="5"><dimension>1 1</dimension><lower_left>0 0</lower_left><pitch>1 1</pitch><outer>3</outer><universes>2</universes></lattice><cell id="2" universe="2" material="1"/><cell id="3" universe="3" material="1" region="-1"/></geometry>"#,
            "line 1, column 133: lattice 5: outer universe 3 has cells with regions, so it is tiled, but the cell the lattice fills is unbounded along x: the tiling would not end",
        ),
        (
            "everything",
            r#"<geometry><cell id="1" material="1"/></geometry>"#,
            "line 1, column 11: cell 1 has no region and nothing around it clips it: it would fill all of space",
        ),
        (
            "empty",
            r#"<geometry><surface id="1" type="x-plane" coeffs="0"/><cell id="3" material="1" region="-1 1"/></geometry>"#,
            "line 1, column 54: root universe 0: no cell with a non-empty region",
        ),
        (
            "rotation",
            r#"<geometry><surface id="1" type="sphere" coeffs="0 0 0 1"/><cell id="1" material="1" region="-1" rotation="0 0 90"/></geometry>"#,
            "line 1, column 59: cell 1: `rotation` needs a `fill` (the cell has a material)",
        ),
        (
            "angles",
            r#"<geometry><surface id="1" type="sphere" coeffs="0 0 0 1"/><cell id="1" fill="2" region="-1" rotation="0 0"/><cell id="2" universe="2" material="1"/></geometry>"#,
            "line 1, column 59: cell 1: rotation: 3 angles or 9 matrix entries expected, got 2 numbers",
        ),
        (
            "distributed",
            r#"<geometry><surface id="1" type="sphere" coeffs="0 0 0 1"/><cell id="1" material="1 2" region="-1"/></geometry>"#,
            "line 1, column 59: cell 1: distributed materials (`1 2`) are not supported",
        ),
    ];
    for (name, xml, message) in cases {
        let file = format!("{name}.xml");
        // `-o out.exr`: an existing file the failed import must not touch.
        check_with(
            &[(file.as_str(), xml.as_bytes())],
            &["import-openmc", file.as_str(), "-o", "out.exr"],
            1,
            &[&format!("error: {file}: {message}")],
        );
    }
    check(&["import-openmc", "none.xml"], 3, &["error: none.xml: No such file or directory (os error 2)"]);
    let good = r#"<geometry><surface id="1" type="sphere" coeffs="0 0 0 1"/><cell id="1" material="1" region="-1"/></geometry>"#;
    check_with(
        &[("good.xml", good.as_bytes())],
        &["import-openmc", "good.xml", "-o", "missing/s.json"],
        3,
        &["error: missing/s.json: cannot create a file in directory missing"],
    );
}
