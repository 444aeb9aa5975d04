//! Animation: `render --frame K` and `--frames A..B` against static scenes
//! holding the values worked out by hand (the interpolation's oracle), the
//! files they write, and what a failed or interrupted run leaves.

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use crate::support::{komplex, komplex_ok, scene, tempdir, text, write_scene};

/// A scene of a ball moved by `translate`, a box turned by `rotate`
/// (degrees about y) and scaled by `scale`, seen from `eye`: each argument
/// the JSON of a value, plain or keyed. 32×24 pixels.
fn scene_with(translate: &str, rotate: &str, scale: &str, eye: &str) -> String {
    format!(
        r#"{{ "camera": {{ "eye": {eye}, "direction": [0, -0.3, -1], "width": 32, "height": 24 }},
             "lights": [ {{ "position": [3, 5, 4] }} ],
             "materials": {{ "red": {{ "diffuse": [0.8, 0.1, 0.1] }} }},
             "blocks": [
               {{ "name": "ball", "material": "red",
                  "objects": [ {{ "sphere": {{ "radius": 0.5 }}, "transform": [ {{ "translate": {translate} }} ] }} ] }},
               {{ "name": "box", "transform": [ {{ "scale": {scale} }}, {{ "rotate_y": {rotate} }}, {{ "translate": [0.8, 0, -1] }} ],
                  "objects": [ {{ "halfspace": [1, 0, 0, -0.5] }}, {{ "halfspace": [-1, 0, 0, -0.5] }},
                               {{ "halfspace": [0, 1, 0, -0.5] }}, {{ "halfspace": [0, -1, 0, -0.5] }},
                               {{ "halfspace": [0, 0, 1, -0.5] }}, {{ "halfspace": [0, 0, -1, -0.5] }} ] }},
               {{ "name": "floor", "objects": [ {{ "halfspace": [0, 1, 0, 0.5] }} ] }} ] }}"#
    )
}

/// Keys of a value: `(frame, JSON value)`.
fn keys(pairs: &[(u32, &str)]) -> String {
    let keys: Vec<String> = pairs.iter().map(|(f, v)| format!(r#"{{ "frame": {f}, "value": {v} }}"#)).collect();
    format!(r#"{{ "keys": [ {} ] }}"#, keys.join(", "))
}

/// Renders `args` in `dir` and returns the bytes of `file`.
fn render(dir: &Path, args: &[&str], file: &str) -> Vec<u8> {
    komplex_ok(dir, &[&["render"], args].concat());
    std::fs::read(dir.join(file)).unwrap_or_else(|e| panic!("{file}: {e}"))
}

/// The files in `dir`, sorted.
fn files(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> =
        std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    v.sort();
    v
}

#[test]
fn a_keyed_scene_at_a_frame_renders_as_the_static_scene_of_the_values_worked_out_by_hand() {
    let dir = tempdir();
    let d = dir.path();
    // Keys at frames 2 and 6: frame 4 is halfway, frame 3 a quarter of the way.
    let keyed = scene_with(
        &keys(&[(2, "[-1, 0, 0]"), (6, "[1, 0.5, -2]")]),
        &keys(&[(2, "0"), (6, "90")]),
        &keys(&[(2, "1"), (6, "[2, 1, 0.5]")]),
        &keys(&[(2, "[0, 1, 4]"), (6, "[2, 1, 6]")]),
    );
    write_scene(d, "keyed.json", &keyed);
    for (frame, translate, rotate, scale, eye) in [
        // Held before the first key and after the last.
        ("0", "[-1, 0, 0]", "0", "1", "[0, 1, 4]"),
        ("2", "[-1, 0, 0]", "0", "1", "[0, 1, 4]"),
        ("3", "[-0.5, 0.125, -0.5]", "22.5", "[1.25, 1, 0.875]", "[0.5, 1, 4.5]"),
        ("4", "[0, 0.25, -1]", "45", "[1.5, 1, 0.75]", "[1, 1, 5]"),
        ("6", "[1, 0.5, -2]", "90", "[2, 1, 0.5]", "[2, 1, 6]"),
        ("40", "[1, 0.5, -2]", "90", "[2, 1, 0.5]", "[2, 1, 6]"),
    ] {
        write_scene(d, "static.json", &scene_with(translate, rotate, scale, eye));
        let want = render(d, &["static.json", "-o", "static.exr"], "static.exr");
        let name = format!("keyed.{frame:0>4}.exr");
        let got = render(d, &["keyed.json", "-o", "keyed.exr", "--frame", frame], &name);
        assert!(got == want, "frame {frame} differs from the static scene");
    }
    // The frames differ, so the comparison above can fail.
    assert!(std::fs::read(d.join("keyed.0002.exr")).unwrap() != std::fs::read(d.join("keyed.0004.exr")).unwrap());
}

#[test]
fn the_camera_turns_at_a_constant_rate_between_direction_keys() {
    // -z at frame 0 to +x at frame 3: frame 1 looks 30° round, frame 2 60°.
    // A 3×3 pinhole image's centre ray is the view direction.
    let dir = tempdir();
    let json = r#"{ "camera": { "eye": [0, 0, 0], "width": 3, "height": 3,
                                "direction": { "keys": [ { "frame": 0, "value": [0, 0, -1] },
                                                         { "frame": 3, "value": [5, 0, 0] } ] } },
                    "blocks": [ { "objects": [ { "sphere": {} } ] } ] }"#;
    let path = write_scene(dir.path(), "turn.json", json);
    let animation = render::animate::Animation::read(&path).unwrap();
    for (frame, degrees) in [(0, 0.0f64), (1, 30.0), (2, 60.0), (3, 90.0), (4, 90.0)] {
        let world = animation.world_at(frame).unwrap();
        let r = world.camera.ray(1, 1).direction();
        let want = [degrees.to_radians().sin(), 0.0, -degrees.to_radians().cos()];
        assert!((0..3).all(|i| (r[i] - want[i]).abs() < 1e-12), "frame {frame}: {r:?}, want {want:?}");
    }
}

#[test]
fn frames_a_to_b_write_one_file_per_frame_named_by_its_number() {
    let dir = tempdir();
    let d = dir.path();
    let keyed = scene_with(&keys(&[(1, "[-1, 0, 0]"), (3, "[1, 0, 0]")]), "0", "1", "[0, 1, 4]");
    write_scene(d, "walk.json", &keyed);
    std::fs::create_dir(d.join("out")).unwrap();
    let o = komplex_ok(d, &["render", "walk.json", "-o", "out/walk.exr", "--png", "out/walk.png", "--frames", "1..3"]);
    assert_eq!(
        files(&d.join("out")),
        ["walk.0001.exr", "walk.0001.png", "walk.0002.exr", "walk.0002.png", "walk.0003.exr", "walk.0003.png"],
        "{}",
        text(&o)
    );
    // Each is the frame alone.
    let alone = render(d, &["walk.json", "-o", "one.exr", "--frame", "2"], "one.0002.exr");
    assert!(std::fs::read(d.join("out/walk.0002.exr")).unwrap() == alone);
    // Without -o: the scene's stem in the current directory.
    komplex_ok(d, &["render", "walk.json", "--frame", "12345"]);
    assert!(d.join("walk.12345.exr").exists());
}

#[test]
fn frames_without_a_range_render_the_scene_animation_frames() {
    let dir = tempdir();
    let d = dir.path();
    let json = scene_with("[0, 0, 0]", &keys(&[(0, "0"), (9, "90")]), "1", "[0, 1, 4]");
    let json = json.replacen('{', r#"{ "animation": { "frames": [4, 5] },"#, 1);
    write_scene(d, "a.json", &json);
    komplex_ok(d, &["render", "a.json", "--frames"]);
    assert_eq!(files(d), ["a.0004.exr", "a.0005.exr", "a.json"]);
}

#[test]
fn a_static_scene_renders_unchanged_at_any_frame() {
    let dir = tempdir();
    let d = dir.path();
    let s = scene("csg.json");
    let s = s.to_str().unwrap();
    let plain = render(d, &[s, "-o", "plain.exr", "--width", "24"], "plain.exr");
    let framed = render(d, &[s, "-o", "framed.exr", "--width", "24", "--frame", "5"], "framed.0005.exr");
    assert!(plain == framed);
}

#[test]
fn a_failed_frame_leaves_the_frames_before_it() {
    let dir = tempdir();
    let d = dir.path();
    // The box's scale passes through zero at frame 3: singular there only.
    let json = scene_with("[0, 0, 0]", "0", &keys(&[(1, "1"), (5, "-1")]), "[0, 1, 4]");
    write_scene(d, "s.json", &json);
    let o = komplex(d, &["render", "s.json", "--frames", "1..5"]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("error: s.json: blocks[1].transform[0], line 7, column 48: at frame 3: the transform is singular"),
        "{err}"
    );
    assert_eq!(files(d), ["s.0001.exr", "s.0002.exr", "s.json"]);
}

#[test]
fn commands_without_frames_read_a_keyed_scene_at_its_first_keys() {
    let dir = tempdir();
    let d = dir.path();
    let keyed = scene_with(
        &keys(&[(3, "[0.25, 0, 0]"), (6, "[1, 0.5, -2]")]),
        &keys(&[(5, "30"), (6, "90")]),
        "1",
        &keys(&[(4, "[0, 1, 5]"), (6, "[2, 1, 6]")]),
    );
    write_scene(d, "keyed.json", &keyed);
    write_scene(d, "first.json", &scene_with("[0.25, 0, 0]", "30", "1", "[0, 1, 5]"));
    // From the ball's centre at its first key to the box's.
    let ray = ["--origin", "-1.4", "0.1", "3", "--direction", "0.55", "0", "-1", "--json"];
    let trace = |s: &str| komplex_ok(d, &[&["trace", s][..], &ray].concat()).stdout;
    let first = trace("first.json");
    assert_eq!(trace("keyed.json"), first);
    // The ray meets the ball and the box.
    let report = String::from_utf8_lossy(&first);
    assert!(report.contains("\"ball\"") && report.contains("\"box\""), "{report}");
    let image = |s: &str, out: &str| render(d, &[s, "-o", out], out);
    assert!(image("keyed.json", "k.exr") == image("first.json", "f.exr"));
}

#[test]
fn an_interrupted_run_leaves_the_finished_frames_and_no_partial_file() {
    // Frame 1 looks away from the glass scene (background only, quick);
    // frame 2 looks at it with four rays a pixel (seconds). The signal goes
    // once frame 1's file is there.
    let dir = tempdir();
    let d = dir.path();
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(scene("glass.json")).unwrap()).unwrap();
    v["camera"]["direction"] = serde_json::from_str(&keys(&[(1, "[0, 0.25, 1]"), (2, "[0, -0.25, -1]")])).unwrap();
    v.as_object_mut().unwrap().remove("$schema");
    write_scene(d, "g.json", &v.to_string());
    let args = ["render", "g.json", "--frames", "1..3", "--width", "800", "--samples", "2"];
    let child =
        Command::new(env!("CARGO_BIN_EXE_komplex")).args(args).current_dir(d).stderr(Stdio::piped()).spawn().unwrap();
    let start = Instant::now();
    while !d.join("g.0001.exr").exists() {
        assert!(start.elapsed() < Duration::from_secs(300), "frame 1 never appeared");
        std::thread::sleep(Duration::from_millis(10));
    }
    let kill = Command::new("kill").args(["-INT", &child.id().to_string()]).status().unwrap();
    assert!(kill.success());
    let o = child.wait_with_output().unwrap();
    assert_eq!(o.status.code(), Some(130), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(files(d), ["g.0001.exr", "g.json"]);
}
