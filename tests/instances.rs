//! Definitions, instances and lattices against their explicit expansion:
//! the oracle rewrites the JSON document, replacing every `instance` by a
//! group holding the definition's blocks and every `lattice` by a group of
//! groups each translated by its element's offset (`i` fastest, then `j`,
//! then `k`), and knows nothing of how the renderer places definitions. An
//! instanced scene must render the same ids, depths and colours, and give
//! the same hits, partitions and point classifications, as its expansion.

use quadric::nalgebra::{Point3, Vector3};
use quadric::Ray;
use serde_json::{json, Value};

use crate::support::{komplex_ok, render_frame, tempdir, write_scene};

/// The document with every instance and lattice written out (the oracle).
fn expanded(doc: &Value) -> Value {
    let defs = doc.get("definitions").cloned().unwrap_or(json!({}));
    let mut out = doc.clone();
    let obj = out.as_object_mut().unwrap();
    obj.remove("definitions");
    obj["blocks"] = Value::Array(expand_list(doc["blocks"].as_array().unwrap(), &defs));
    out
}

fn expand_list(entries: &[Value], defs: &Value) -> Vec<Value> {
    entries.iter().map(|e| expand_entry(e, defs)).collect()
}

fn expand_entry(e: &Value, defs: &Value) -> Value {
    let transform = e.get("transform").cloned().unwrap_or(json!([]));
    let body = |name: &Value| expand_list(defs[name.as_str().unwrap()]["blocks"].as_array().unwrap(), defs);
    if let Some(name) = e.get("instance") {
        json!({ "group": "instance", "transform": transform, "blocks": body(name) })
    } else if let Some(name) = e.get("lattice") {
        let pitch: Vec<f64> = e["pitch"].as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect();
        let count: Vec<u64> = e["count"].as_array().unwrap().iter().map(|x| x.as_u64().unwrap()).collect();
        let mut elements = vec![];
        for k in 0..count[2] {
            for j in 0..count[1] {
                for i in 0..count[0] {
                    let offset = [i as f64 * pitch[0], j as f64 * pitch[1], k as f64 * pitch[2]];
                    let step = json!([{ "translate": offset }]);
                    elements.push(json!({ "group": "element", "transform": step, "blocks": body(name) }));
                }
            }
        }
        json!({ "group": "lattice", "transform": transform, "blocks": elements })
    } else if let Some(children) = e.get("blocks") {
        let mut g = e.clone();
        g["blocks"] = Value::Array(expand_list(children.as_array().unwrap(), defs));
        g
    } else {
        e.clone()
    }
}

/// Pins (a rod and a glass cap) in rows, rows and pins in cells, cells on a
/// lattice inside a rotated group, between plain blocks; a textured bar
/// (its checker in its own frame) and a transparent cap in definitions.
fn scene(integrator: &str) -> Value {
    let halfspaces = json!([ { "halfspace": [0, 1, 0, -1] }, { "halfspace": [0, -1, 0, 0] } ]);
    let rod = json!([ { "cylinder": { "radius": 0.3 } }, halfspaces[0], halfspaces[1] ]);
    json!({
        "camera": { "eye": [1.5, 7, 9], "direction": [0, -0.7, -1], "width": 48, "height": 36, "aperture": 55 },
        "settings": { "integrator": integrator, "spp": 4, "max_depth": 4 },
        "lights": [ { "position": [4, 9, 6] }, { "position": [-5, 6, 2], "color": [0.4, 0.4, 0.5] } ],
        "materials": {
            "red": { "diffuse": [0.8, 0.2, 0.1], "specular": [0.3, 0.3, 0.3], "shininess": 20 },
            "grey": { "diffuse": [0.5, 0.5, 0.5] },
            "glass": { "diffuse": [0.05, 0.05, 0.05], "transmit": [0.8, 0.8, 0.9], "ior": 1.4, "reflect": [0.1, 0.1, 0.1] },
            "checker": { "diffuse": { "checker": { "scale": 0.25, "colors": [[0.9, 0.9, 0.2], [0.1, 0.2, 0.7]] } } },
            "lamp": { "emission": [3, 3, 2.5] }
        },
        "definitions": {
            "pin": { "blocks": [
                { "name": "cap", "material": "glass", "transparent": true,
                  "objects": [ { "sphere": { "radius": 0.35, "center": [0, 1, 0] } } ] },
                { "name": "rod", "material": "red", "objects": rod }
            ] },
            "row": { "blocks": [
                { "lattice": "pin", "pitch": [0.9, 0, 0], "count": [3, 1, 1] },
                { "name": "bar", "material": "checker",
                  "objects": [ { "sphere": {}, "transform": [ { "scale": [1.4, 0.15, 0.2] }, { "translate": [0.9, 0.2, 0.5] } ] } ] }
            ] },
            "cell": { "blocks": [
                { "group": "turned", "transform": [ { "rotate_y": 30 } ], "blocks": [
                    { "instance": "row", "transform": [ { "translate": [0, 0, 0.4] } ] } ] },
                { "lattice": "pin", "pitch": [0.8, 0, 0.8], "count": [2, 1, 2], "transform": [ { "scale": 0.5 } ] },
                { "name": "lamp", "material": "lamp", "objects": [ { "sphere": { "radius": 0.2, "center": [1, 1.8, 1] } } ] }
            ] },
            "unused": { "blocks": [ { "name": "never", "objects": [ { "sphere": {} } ] } ] }
        },
        "blocks": [
            { "name": "ball", "material": "grey", "objects": [ { "sphere": { "radius": 0.6, "center": [-3, 0.6, 2] } } ] },
            { "group": "field", "transform": [ { "rotate_y": 15 }, { "translate": [-2.5, 0, -1] } ], "blocks": [
                { "lattice": "cell", "pitch": [3, 0, -3], "count": [2, 1, 2] } ] },
            { "instance": "pin", "transform": [ { "scale": 1.5 }, { "rotate_z": 10 }, { "translate": [3.5, 0, 2] } ] },
            { "name": "floor", "material": "grey", "objects": [ { "halfspace": [0, 1, 0, 0] } ] }
        ]
    })
}

/// Both scenes loaded: (instanced, expanded).
fn worlds(doc: &Value) -> (render::world::World, render::world::World) {
    let load = |v: &Value| render::format::SceneFile::load_str(&v.to_string()).unwrap();
    (load(doc), load(&expanded(doc)))
}

#[test]
fn the_oracle_writes_every_element_out_in_order() {
    let e = expanded(&scene("whitted"));
    let text = e.to_string();
    assert!(!text.contains("instance\":") && !text.contains("lattice\":") && e.get("definitions").is_none());
    // ball, 4 cells × (3 pins × 2 + bar + 4 pins × 2 + lamp), the big pin's 2, floor.
    let world = render::format::SceneFile::load_str(&text).unwrap();
    assert_eq!(world.complex.len(), 1 + 4 * (7 + 8 + 1) + 2 + 1);
}

#[test]
fn an_instanced_scene_renders_as_its_expansion() {
    for integrator in ["whitted", "path"] {
        let (inst, flat) = worlds(&scene(integrator));
        assert_eq!(inst.complex.len(), flat.complex.len());
        let (a, b) = (render_frame(&inst), render_frame(&flat));
        let (mut ids, mut colours) = (0, 0);
        for (p, q) in a.pixels().zip(b.pixels()) {
            ids += usize::from((p.block, p.object) != (q.block, q.object));
            let close = |x: f32, y: f32| (x - y).abs() <= 1e-4 * (1.0 + x.abs().max(y.abs()));
            colours += usize::from(!(p.rgb.iter().zip(q.rgb).all(|(x, y)| close(*x, y)) && close(p.depth, q.depth)));
        }
        // The placement rounds differently from the composed transform
        // (about 1e-16 of the scene): a pixel centre that close to an
        // outline could change sides, none of these does.
        assert_eq!(ids, 0, "{integrator}: {ids} pixels see another block or solid");
        assert_eq!(colours, 0, "{integrator}: {colours} pixels differ in colour or depth");
        assert!(a.pixels().any(|p| p.block > 2 && p.block < 60), "the lattices are in view");
    }
}

/// Rays through the scene from many origins, and points inside its box.
fn probes() -> (Vec<Ray>, Vec<Point3<f64>>) {
    let mut rays = vec![];
    let mut points = vec![];
    let mut h = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = || {
        h = h.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (h >> 11) as f64 / (1u64 << 53) as f64
    };
    for _ in 0..600 {
        let o = Point3::new(-6.0 + 12.0 * next(), 0.05 + 3.0 * next(), -6.0 + 12.0 * next());
        let d = Vector3::new(next() - 0.5, next() - 0.5, next() - 0.5);
        rays.push(Ray::new(o, d).unwrap());
        points.push(Point3::new(-6.0 + 12.0 * next(), -0.2 + 2.5 * next(), -6.0 + 12.0 * next()));
    }
    (rays, points)
}

/// A partition's segments as (start, end, owner), those shorter than 1e-9
/// dropped and neighbours of one owner joined: where two blocks' faces
/// coincide (a rod standing on the floor), the placement's rounding and the
/// composed transform's can leave a gap of 1e-16 on either side.
fn segments(p: &complex::Partition) -> Vec<(f64, f64, Option<complex::BlockId>)> {
    let mut out: Vec<(f64, f64, Option<complex::BlockId>)> = vec![];
    for s in p.segments.iter().filter(|s| s.end - s.start >= 1e-9) {
        match out.last_mut() {
            Some(last) if last.2 == s.owner => last.1 = s.end,
            _ => out.push((s.start, s.end, s.owner)),
        }
    }
    out
}

#[test]
fn hits_partitions_and_points_are_those_of_the_expansion() {
    let (inst, flat) = worlds(&scene("whitted"));
    let (a, b) = (&inst.complex, &flat.complex);
    let (rays, points) = probes();
    let close = |x: f64, y: f64| x == y || (x - y).abs() <= 1e-9 * (1.0 + x.abs());
    for ray in &rays {
        match (a.cast_ray(ray, f64::INFINITY), b.cast_ray(ray, f64::INFINITY)) {
            (None, None) => {}
            (Some(p), Some(q)) => {
                assert_eq!((p.block, p.solid, p.entering), (q.block, q.solid, q.entering), "{ray:?}");
                assert!(close(p.t, q.t) && (p.normal - q.normal).norm() < 1e-9, "{ray:?}: {p:?} {q:?}");
            }
            (p, q) => panic!("{ray:?}: {p:?} against {q:?}"),
        }
        let (p, q) = (segments(&a.partition(ray)), segments(&b.partition(ray)));
        assert_eq!(p.len(), q.len(), "{ray:?}\n{p:?}\n{q:?}");
        for (s, t) in p.iter().zip(&q) {
            assert_eq!(s.2, t.2, "{ray:?}");
            assert!(close(s.0, t.0) && close(s.1, t.1), "{ray:?}: {s:?} {t:?}");
        }
    }
    let (mut got, mut want) = (vec![None; points.len()], vec![None; points.len()]);
    a.classify(&points, &mut got).unwrap();
    b.classify(&points, &mut want).unwrap();
    assert_eq!(got, want);
    assert!(got.iter().filter(|o| o.is_some_and(|b| b.0 > 0 && b.0 < 60)).count() > 5, "points fall in the lattices");
}

#[test]
fn trace_and_check_print_what_the_expansion_prints() {
    let dir = tempdir();
    let doc = scene("whitted");
    let a = write_scene(dir.path(), "instanced.json", &doc.to_string());
    let b = write_scene(dir.path(), "expanded.json", &expanded(&doc).to_string());
    let run = |args: &[&str]| String::from_utf8(komplex_ok(dir.path(), args).stdout).unwrap();
    for scene in [&a, &b] {
        let out = run(&["check", scene.to_str().unwrap()]);
        assert!(out.starts_with("68 blocks (29 transparent), 126 solids, 2 lights, 5 materials"), "{out}");
    }
    let trace = |s: &std::path::Path| -> Value {
        let args =
            ["trace", s.to_str().unwrap(), "--json", "--origin", "-1", "5", "3", "--direction", "-0.3", "-1", "-0.8"];
        serde_json::from_str(&run(&args)).unwrap()
    };
    let (ta, tb) = (trace(&a), trace(&b));
    assert!(ta["segments"].as_array().unwrap().len() > 2, "{ta}");
    same(&ta, &tb, "trace");
}

/// The same JSON but for numbers, which agree to 1e-9 (the placement rounds
/// differently from the composed transform).
fn same(a: &Value, b: &Value, at: &str) {
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => {
            let (x, y) = (x.as_f64().unwrap(), y.as_f64().unwrap());
            assert!((x - y).abs() <= 1e-9 * (1.0 + x.abs()), "{at}: {x} against {y}");
        }
        (Value::Array(x), Value::Array(y)) => {
            assert_eq!(x.len(), y.len(), "{at}");
            for (i, (x, y)) in x.iter().zip(y).enumerate() {
                same(x, y, &format!("{at}[{i}]"));
            }
        }
        (Value::Object(x), Value::Object(y)) => {
            assert_eq!(x.keys().collect::<Vec<_>>(), y.keys().collect::<Vec<_>>(), "{at}");
            for (k, v) in x {
                same(v, &y[k], &format!("{at}.{k}"));
            }
        }
        _ => assert_eq!(a, b, "{at}"),
    }
}

#[test]
fn a_billion_blocks_load_and_check_in_little_memory() {
    // 1000 x 1000 tiles of 30 x 30 balls: 9e8 blocks, never expanded.
    let dir = tempdir();
    let scene = dir.path().join("lattice.json");
    komplex_ok(dir.path(), &["generate", "lattice", "-o", scene.to_str().unwrap()]);
    let out = String::from_utf8(komplex_ok(dir.path(), &["check", scene.to_str().unwrap()]).stdout).unwrap();
    assert!(out.starts_with("900000001 blocks (0 transparent), 900000001 solids"), "{out}");
    assert!(out.contains("overlaps between opaque blocks not checked: more than 1048576 blocks"), "{out}");
    let world = crate::support::world(&scene, Some((16, 12)));
    let frame = render_frame(&world);
    // Balls have the ids 1 to 9e8 of the expansion, the ground the last.
    assert!(frame.pixels().any(|p| (1..=900_000_000).contains(&p.block)));
    assert!(frame.pixels().all(|p| p.block <= 900_000_001));
}
