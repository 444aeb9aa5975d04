//! `komplex trace --json` reports what the kernel computes, and its
//! partition agrees with point membership sampled along the ray.

use complex::BlockId;
use quadric::nalgebra::{Point3, Vector3};
use quadric::Ray;
use serde_json::Value;

use crate::support::{komplex_ok, root, scene, world};

fn num(v: &Value) -> Option<f64> {
    v.as_f64()
}

fn trace_json(scene_name: &str, o: [f64; 3], d: [f64; 3]) -> Value {
    let s = scene(scene_name);
    let fmt = |v: f64| format!("{v:?}");
    let args: Vec<String> = ["trace", s.to_str().unwrap(), "--json", "--origin"]
        .iter()
        .map(|x| x.to_string())
        .chain(o.iter().map(|v| fmt(*v)))
        .chain(["--direction".to_string()])
        .chain(d.iter().map(|v| fmt(*v)))
        .collect();
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let out = komplex_ok(&root(), &args);
    serde_json::from_slice(&out.stdout).unwrap()
}

/// The owner of `p` under the priority rule, from point membership alone.
fn owner(w: &render::world::World, p: &Point3<f64>) -> Option<u32> {
    let blocks = w.complex.blocks();
    let inside: Vec<usize> =
        (0..blocks.len()).filter(|i| blocks[*i].solids().iter().all(|s| s.value(p) <= 0.0)).collect();
    inside.iter().find(|i| !blocks[**i].is_transparent()).or(inside.first()).map(|i| *i as u32 + 1)
}

fn check(scene_name: &str, o: [f64; 3], d: [f64; 3], expect_hit: bool) {
    let v = trace_json(scene_name, o, d);
    let w = world(&scene(scene_name), None);
    let c = &w.complex;
    let ray = Ray::new(Point3::from(Vector3::from(o)), Vector3::from(d)).unwrap();

    // Every block, 1-based, with exactly the kernel's interval set.
    let blocks = v["blocks"].as_array().unwrap();
    assert_eq!(blocks.len(), c.blocks().len());
    for (i, b) in blocks.iter().enumerate() {
        assert_eq!(b["index"], i as u64 + 1);
        assert_eq!(b["name"], c.blocks()[i].name());
        let want: Vec<[Option<f64>; 2]> = c
            .block_intervals(BlockId(i as u32), &ray)
            .iter()
            .map(|iv| [iv.enter.t, iv.exit.t].map(|t| t.is_finite().then_some(t)))
            .collect();
        let got: Vec<[Option<f64>; 2]> =
            b["intervals"].as_array().unwrap().iter().map(|p| [num(&p[0]), num(&p[1])]).collect();
        assert_eq!(got, want, "block {}", i + 1);
    }

    // The partition covers [0, ∞) and each segment's owner is the owner of
    // points sampled inside it.
    let segs = v["segments"].as_array().unwrap();
    assert_eq!(segs[0]["start"], 0.0);
    assert!(segs.last().unwrap()["end"].is_null());
    for pair in segs.windows(2) {
        assert_eq!(pair[0]["end"], pair[1]["start"]);
    }
    for s in segs {
        let a = num(&s["start"]).unwrap();
        let b = num(&s["end"]).unwrap_or(a + 50.0);
        if b - a < 1e-6 {
            continue;
        }
        for k in 1..8 {
            let t = a + (b - a) * f64::from(k) / 8.0;
            let got = s["block"].as_u64().map(|x| x as u32);
            assert_eq!(got, owner(&w, &ray.at(t)), "segment [{a}, {b}] at t = {t}");
            if let Some(id) = got {
                assert_eq!(s["name"], c.blocks()[id as usize - 1].name());
            }
        }
    }

    // The hit is the kernel's, 1-based; it lies on the reported surface.
    match (c.cast_ray(&ray, f64::INFINITY), &v["hit"]) {
        (None, Value::Null) => assert!(!expect_hit),
        (Some(h), hit) => {
            assert!(expect_hit);
            assert_eq!(num(&hit["t"]), Some(h.t));
            assert_eq!(hit["block"], h.block.0 as u64 + 1);
            assert_eq!(hit["object"], h.solid as u64 + 1);
            let p: Vec<f64> = hit["point"].as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect();
            assert_eq!(p, vec![h.point.x, h.point.y, h.point.z]);
            let solid = &c.blocks()[h.block.index()].solids()[h.solid as usize];
            // The scenes' solids have unit-scale coefficients, so |f| bounds the distance.
            assert!(solid.value(&h.point).abs() < 1e-9, "hit not on its surface");
            // The hit is the first segment boundary after ε.
            let first = segs.iter().filter_map(|s| num(&s["end"])).find(|t| *t > c.epsilon());
            assert_eq!(first, Some(h.t));
        }
        (None, hit) => panic!("kernel misses but trace reports {hit}"),
    }
}

#[test]
fn trace_agrees_with_the_kernel() {
    // Through the glass ball into the overlapping water box (priority rule).
    check("glass.json", [-3.0, 1.1, 0.3], [1.0, 0.0, 0.0], true);
    // Through both amber lobes (same medium).
    check("glass.json", [0.0, 0.8, 0.4], [1.0, 0.0, -0.1], true);
    // Down through the table top, a leg-free spot, the floor.
    check("table.json", [0.2, 3.0, 0.1], [0.0, -1.0, 0.0], true);
    // Through the drilled box along a bore.
    check("csg.json", [-1.5, 5.0, 0.0], [0.0, -1.0, 0.0], true);
    // Up into the sky: nothing.
    check("primitives.json", [0.0, 20.0, 0.0], [0.1, 1.0, 0.0], false);
}

#[test]
fn trace_text_form_prints_full_precision() {
    let s = scene("table.json");
    let out = komplex_ok(
        &root(),
        &["trace", s.to_str().unwrap(), "--origin", "0", "3", "0", "--direction", "0.1", "-1", "0.05"],
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("blocks:") && text.contains("segments:") && text.contains("hit: t = "), "{text}");
    let v = trace_json("table.json", [0.0, 3.0, 0.0], [0.1, -1.0, 0.05]);
    let t = v["hit"]["t"].as_f64().unwrap();
    assert!(text.contains(&format!("{t:?}")), "{t:?} not in\n{text}");
}

/// `Shader::primary4` (four rays sharing one BVH walk) gives exactly the
/// colours and surfaces of four `primary` calls, and casts as many rays:
/// on every example and benchmark scene (opaque and transparent), for 2×2
/// squares of neighbouring pixels and for four pixels far apart.
#[test]
fn four_primary_rays_at_once_are_four_single_ones() {
    use render::shade::{Scratch, Shader};
    let scenes = crate::support::all_scenes().into_iter().chain(crate::support::bench_scenes());
    for path in scenes {
        let w = world(&path, Some((64, 48)));
        let shader = Shader::new(&w);
        let cam = &w.camera;
        let mut quads: Vec<[(u32, u32); 4]> = Vec::new();
        for i in (0..48).step_by(6) {
            for j in (0..64).step_by(5) {
                quads.push([(i, j), (i, j + 1), (i + 1, j), (i + 1, j + 1)]);
                quads.push([(i, j), (47 - i, 63 - j), (i / 2, 63 - j), (47 - i / 3, j / 2)]);
            }
        }
        for quad in quads {
            let rays = quad.map(|(i, j)| cam.ray(i, j));
            let (mut one, mut four) = (Scratch::default(), Scratch::default());
            let singles = rays.each_ref().map(|r| shader.primary(r, &mut one));
            assert_eq!(shader.primary4(&rays, &mut four), singles, "{} at {quad:?}", path.display());
            assert_eq!(four.rays, one.rays, "{}: rays cast", path.display());
        }
    }
}

/// The render loop puts every pixel where it belongs: each pixel of a frame
/// (rendered in bands of rows and square tiles, with 2×2 packets, 1×4 runs
/// on a last odd row and single rays where a row has pixels left) is
/// exactly `Shader::primary` of that pixel's own camera ray. Sizes with a
/// part band, an odd last row, a part tile and an odd last column. A
/// colour-only frame (`Options::colour_only`) has the same colours and
/// coverage, and no AOV planes.
#[test]
fn every_pixel_of_a_frame_is_its_own_primary_ray() {
    use render::shade::{Scratch, Shader};
    for name in ["table.json", "glass.json"] {
        for (width, height) in [(37, 35), (16, 16), (5, 3), (1, 1), (40, 33)] {
            let w = world(&scene(name), Some((width, height)));
            let frame = crate::support::render_frame(&w);
            // Colour only (`komplex bench`): the same colours, no AOV planes.
            let options = render::frame::Options { threads: Some(2), colour_only: true, ..Default::default() };
            let colour = render::frame::render(&w, options, &|| {}).unwrap().0;
            assert!(frame.has_aovs() && !colour.has_aovs(), "{name} {width}x{height}");
            let n = (width * height) as usize;
            assert_eq!(colour.plane_lengths(), [n, n, n, n, 0, 0, 0, 0, 0, 0], "{name} {width}x{height}");
            let shader = Shader::new(&w);
            let mut scratch = Scratch::default();
            for i in 0..height {
                for j in 0..width {
                    let (c, hit) = shader.primary(&w.camera.ray(i, j), &mut scratch);
                    let p = frame.at(i, j);
                    let at = format!("{name} {width}x{height} pixel ({i}, {j})");
                    assert_eq!(p.rgb, [c.x as f32, c.y as f32, c.z as f32], "{at}");
                    assert_eq!(p.alpha, if hit.is_some() { 1.0 } else { 0.0 }, "{at}");
                    assert_eq!(p.depth, hit.map_or(f32::INFINITY, |s| s.t as f32), "{at}");
                    assert_eq!(p.block, hit.map_or(0, |s| s.block.0 + 1), "{at}");
                    assert_eq!(p.object, hit.map_or(0, |s| s.solid + 1), "{at}");
                    let q = colour.at(i, j);
                    assert_eq!((q.rgb, q.alpha), (p.rgb, p.alpha), "{at}, colour only");
                    assert_eq!((q.depth, q.normal, q.block, q.object), (0.0, [0.0; 3], 0, 0), "{at}, colour only");
                }
            }
        }
    }
}

/// A block with more non-convex solids than an interval set carries (a
/// plate drilled by 12 holes in a row) loads, and `trace` reports all of
/// its intervals along the row: inside the plate between the holes, out
/// of it within them (membership sampled at each interval's middle and in
/// each gap).
#[test]
fn trace_reports_every_interval_of_a_large_block() {
    let holes: Vec<String> = (0..12)
        .map(|k| {
            format!(
                r#"{{ "cylinder": {{ "radius": 0.25, "axis": "y" }}, "complement": true, "transform": [ {{ "translate": [{k}, 0, 0] }} ] }}"#
            )
        })
        .collect();
    let json = format!(
        r#"{{ "camera": {{ "eye": [0, 5, 5], "direction": [0, -1, -1] }},
              "blocks": [ {{ "name": "plate", "objects": [ {{ "halfspace": [0, 1, 0, -1] }}, {{ "halfspace": [0, -1, 0, -1] }}, {} ] }} ] }}"#,
        holes.join(", ")
    );
    let dir = crate::support::tempdir();
    let p = crate::support::write_scene(dir.path(), "plate.json", &json);
    let args = ["trace", p.to_str().unwrap(), "--json", "--origin", "-1", "0", "0", "--direction", "1", "0", "0"];
    let v: Value = serde_json::from_slice(&komplex_ok(dir.path(), &args).stdout).unwrap();
    let intervals = v["blocks"][0]["intervals"].as_array().unwrap();
    assert_eq!(intervals.len(), 13, "{intervals:?}");
    let w = world(&p, None);
    let plate = &w.complex.blocks()[0];
    let at = |t: f64| plate.contains_point(&Point3::new(-1.0 + t, 0.0, 0.0));
    let mut gap_start = 0.0;
    for iv in intervals {
        let (a, b) = (num(&iv[0]).unwrap(), num(&iv[1]).unwrap_or(100.0));
        assert!(at(0.5 * (a + b)), "[{a}, {b}] should be inside");
        if a > gap_start {
            assert!(!at(0.5 * (gap_start + a)), "({gap_start}, {a}) should be outside");
        }
        gap_start = b;
    }
}
