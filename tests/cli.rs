//! Command-line behaviour: commands, defaults, the schema.

use crate::support::{all_scenes, komplex, komplex_ok, read_exr, root, scene, tempdir, text, write_scene};

#[test]
fn schema_prints_the_committed_schema() {
    let o = komplex_ok(&root(), &["schema"]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("schema is JSON");
    assert_eq!(v["$schema"], "http://json-schema.org/draft-07/schema#");
    let committed = std::fs::read_to_string(root().join("docs/scene.schema.json")).unwrap();
    assert!(
        committed == String::from_utf8_lossy(&o.stdout),
        "docs/scene.schema.json is stale: run `cargo run -- schema > docs/scene.schema.json`"
    );
}

#[test]
fn render_defaults_to_the_scene_stem_in_the_cwd() {
    let dir = tempdir();
    let o = komplex_ok(dir.path(), &["render", scene("csg.json").to_str().unwrap(), "--width", "16"]);
    assert!(dir.path().join("csg.exr").exists(), "{}", text(&o));
    // The summary line: size (height kept in proportion), rays and rate.
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("16x12") && err.contains("rays") && err.contains("Mrays/s"), "{err}");
    // Nothing but the output: no temporary files left behind.
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
}

#[test]
fn threads_option_gives_the_same_image() {
    let dir = tempdir();
    let s = scene("glass.json");
    for (name, threads) in [("one.exr", "1"), ("two.exr", "2")] {
        komplex_ok(
            dir.path(),
            &["render", s.to_str().unwrap(), "-o", name, "--threads", threads, "--width", "24", "--height", "18"],
        );
    }
    let a = std::fs::read(dir.path().join("one.exr")).unwrap();
    let b = std::fs::read(dir.path().join("two.exr")).unwrap();
    assert!(a == b, "thread count changed the output");
    let o = komplex(dir.path(), &["render", s.to_str().unwrap(), "--threads", "0"]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
}

#[test]
fn check_summarises_and_warns() {
    for s in all_scenes() {
        let o = komplex_ok(&root(), &["check", s.to_str().unwrap()]);
        let out = String::from_utf8_lossy(&o.stdout);
        assert!(out.contains("blocks") && out.contains("solids"), "{out}");
    }
    let dir = tempdir();
    let json = r#"{ "camera": { "eye": [0, 0, 0], "direction": [0, 0, -1] },
                    "lights": [ { "position": [0, -5, 0] } ],
                    "materials": { "unused": {} },
                    "blocks": [ { "name": "room", "objects": [ { "sphere": { "radius": 10 } } ] },
                                { "name": "ground", "objects": [ { "halfspace": [0, 1, 0, 3] } ] },
                                { "name": "nothing", "objects": [ { "halfspace": [0, 1, 0, 1] }, { "halfspace": [0, -1, 0, 1] } ] } ] }"#;
    let p = write_scene(dir.path(), "w.json", json);
    let o = komplex_ok(dir.path(), &["check", p.to_str().unwrap()]);
    let out = String::from_utf8_lossy(&o.stdout);
    for needle in [
        "3 blocks",
        "the eye lies inside opaque block 1 \"room\"",
        "block 3 \"nothing\" (blocks[2]) is empty: its solids share no point",
        "light 1 lies inside opaque block",
        "material \"unused\" is not used",
    ] {
        assert!(out.contains(needle), "lacks {needle:?}:\n{out}");
    }
}

#[test]
fn check_warns_of_no_lights_only_when_nothing_lights_the_scene() {
    let dir = tempdir();
    // No point light: Whitted sees only ambient light; the path integrator is lit by an
    // emissive block or by the background, and by nothing when both are black.
    let scene = |integrator: &str, emission: &str, background: &str| {
        format!(
            r#"{{ "camera": {{ "eye": [0, 0, 5], "direction": [0, 0, -1] }},
                 "settings": {{ "integrator": "{integrator}", "background": {background} }},
                 "materials": {{ "lamp": {{ "emission": {emission} }} }},
                 "blocks": [ {{ "material": "lamp", "objects": [ {{ "sphere": {{}} }} ] }} ] }}"#
        )
    };
    for (integrator, emission, background, warns) in [
        ("whitted", "[1, 1, 1]", "[0.5, 0.5, 0.5]", true),
        ("path", "[1, 1, 1]", "[0, 0, 0]", false),
        ("path", "[0, 0, 0]", "[0.5, 0.5, 0.5]", false),
        ("path", "[0, 0, 0]", "[0, 0, 0]", true),
    ] {
        let p = write_scene(dir.path(), "s.json", &scene(integrator, emission, background));
        let o = komplex_ok(dir.path(), &["check", p.to_str().unwrap()]);
        let out = String::from_utf8_lossy(&o.stdout);
        assert_eq!(
            out.contains("no lights"),
            warns,
            "{integrator}, emission {emission}, background {background}:\n{out}"
        );
    }
}

#[test]
fn scenes_validate_against_the_schema_and_bad_ones_do_not() {
    let dir = tempdir();
    let cam = r#""camera": { "eye": [0, 0, 5], "direction": [0, 0, -1] }"#;
    let bad = [
        format!(r#"{{ {cam}, "blocks": [ {{ "objects": [ {{ "sphere": {{}}, "cone": {{}} }} ] }} ] }}"#),
        format!(r#"{{ {cam}, "blocks": [ {{ "objects": [ {{ "complement": true }} ] }} ] }}"#),
        format!(r#"{{ {cam}, "blocks": [ {{ "group": "g" }} ] }}"#),
        format!(r#"{{ {cam}, "blocks": [ {{ "objects": [ {{ "sphere": {{ "raduis": 1 }} }} ] }} ] }}"#),
        format!(
            r#"{{ {cam}, "blocks": [ {{ "objects": [ {{ "sphere": {{}}, "transform": [ {{ "scale": [1, 2] }} ] }} ] }} ] }}"#
        ),
        format!(r#"{{ {cam}, "blocks": [], "lights": [ {{ "color": [1, 1, 1] }} ] }}"#),
    ];
    let bad_paths: Vec<_> =
        bad.iter().enumerate().map(|(i, j)| write_scene(dir.path(), &format!("bad{i}.json"), j)).collect();
    let schema = root().join("docs/scene.schema.json");
    let scenes = all_scenes();
    let mut args: Vec<&std::path::Path> = vec![schema.as_path()];
    args.extend(scenes.iter().map(|p| p.as_path()));
    args.extend(bad_paths.iter().map(|p| p.as_path()));
    let Some(out) = crate::support::python("validate_schema.py", &args) else { return };
    let lines: Vec<String> = String::from_utf8_lossy(&out.stdout).lines().map(str::to_string).collect();
    assert_eq!(lines.len(), scenes.len() + bad.len());
    for (line, scene) in lines.iter().zip(&scenes) {
        assert!(line.starts_with("ok "), "{} does not validate: {line}", scene.display());
    }
    for (line, json) in lines[scenes.len()..].iter().zip(&bad) {
        assert!(line.starts_with("invalid "), "the schema accepts {json}");
    }
}

#[test]
fn complete_examples_in_the_format_docs_load() {
    let doc = std::fs::read_to_string(root().join("docs/scene-format.md")).unwrap();
    let blocks: Vec<&str> = doc.split("```json\n").skip(1).filter_map(|b| b.split("\n```").next()).collect();
    // Whole documents start at the top-level brace; the rest are fragments.
    let complete: Vec<&str> =
        blocks.iter().copied().filter(|b| b.starts_with('{') && b.contains("\"camera\"")).collect();
    assert!(complete.len() >= 6, "found {} complete examples", complete.len());
    let dir = tempdir();
    for (i, json) in complete.iter().enumerate() {
        let p = write_scene(dir.path(), &format!("example{i}.json"), json);
        let o = komplex(dir.path(), &["render", p.to_str().unwrap(), "--width", "16", "--height", "12"]);
        assert!(o.status.success(), "example {i} of docs/scene-format.md:\n{json}\n{}", text(&o));
    }
}

#[test]
fn every_precision_mode_renders_the_same_blocks() {
    let dir = tempdir();
    let s = scene("csg.json");
    let mut ids = Vec::new();
    for mode in ["fast", "accurate", "certified"] {
        let out = format!("{mode}.exr");
        komplex_ok(
            dir.path(),
            &["render", s.to_str().unwrap(), "-o", &out, "--precision", mode, "--width", "32", "--height", "24"],
        );
        let Some(exr) = read_exr(&dir.path().join(&out)) else { return };
        ids.push(exr.channels["id.block"].samples.clone());
    }
    // Near the origin the modes agree on which block each pixel sees, but
    // for a silhouette pixel or two.
    for other in [&ids[0], &ids[2]] {
        let differ = other.iter().zip(&ids[1]).filter(|(a, b)| a != b).count();
        assert!(differ * 100 <= ids[1].len(), "{differ} of {} pixels see another block", ids[1].len());
    }
    // An unknown mode is a usage error that lists the modes.
    let o = komplex(dir.path(), &["render", s.to_str().unwrap(), "--precision", "exact"]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("fast") && err.contains("accurate") && err.contains("certified"), "{err}");
}
