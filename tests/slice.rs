//! `komplex slice` maps a plane exactly: at every pixel centre away from
//! the boundaries its owner, material and overlap count are analytic
//! membership's (two balls) or `contains_point`'s (the example scenes),
//! the EXR read back by an independent reader holds them, and the PNG
//! hatches exactly the overlaps.

use std::collections::BTreeSet;

use quadric::nalgebra::{Point3, Vector3};
use render::slice::{slice, Extent, Plane, Raster};

use crate::support::{komplex_ok, read_exr, scene, tempdir, world, write_scene};

/// Block 1: a transparent ball of material "b" at x = 0.5; block 2: an
/// opaque ball of material "a" at x = −0.5 (it owns the overlap, though
/// later); block 3: a small opaque ball of material "a" apart from both.
const BALLS: &str = r#"{
  "camera": { "eye": [0, 0, 5], "direction": [0, 0, -1] },
  "materials": { "a": { "diffuse": [1, 0, 0] }, "b": { "diffuse": [0, 0, 1], "transmit": [0.5, 0.5, 0.5] } },
  "blocks": [
    { "name": "glass", "material": "b", "transparent": true, "objects": [ { "sphere": { "center": [0.5, 0, 0] } } ] },
    { "name": "stone", "material": "a", "objects": [ { "sphere": { "center": [-0.5, 0, 0] } } ] },
    { "name": "pebble", "material": "a", "objects": [ { "sphere": { "center": [1.6, 1.1, 0], "radius": 0.3 } } ] }
  ]
}"#;

const SIZE: (usize, usize) = (80, 60);
const EXTENT: [f64; 4] = [-2.0, 2.0, -1.5, 1.5];

/// The centre of pixel (column `i`, row `j` from the top), as docs/cli.md
/// defines it, on the plane z = 0.
fn centre(i: usize, j: usize) -> (f64, f64) {
    let [u0, u1, v0, v1] = EXTENT;
    (u0 + (i as f64 + 0.5) * (u1 - u0) / SIZE.0 as f64, v1 - (j as f64 + 0.5) * (v1 - v0) / SIZE.1 as f64)
}

/// For each ball (glass, stone, pebble): whether `(u, v)` is inside, or
/// `None` if it is within `margin` of its circle.
fn membership(u: f64, v: f64, margin: f64) -> Option<[bool; 3]> {
    let balls = [(0.5, 0.0, 1.0), (-0.5, 0.0, 1.0), (1.6, 1.1, 0.3)];
    let mut inside = [false; 3];
    for (k, (x, y, r)) in balls.into_iter().enumerate() {
        let d = ((u - x) * (u - x) + (v - y) * (v - y)).sqrt() - r;
        if d.abs() <= margin {
            return None;
        }
        inside[k] = d < 0.0;
    }
    Some(inside)
}

/// The expected (block, material, overlap) under the priority rule: the
/// opaque balls first, then the glass. Materials: "a" is 1, "b" is 2.
fn expected(inside: [bool; 3]) -> (u32, u32, u32) {
    let overlap = inside.iter().filter(|&&b| b).count() as u32;
    match inside {
        [_, true, _] => (2, 1, overlap),
        [_, _, true] => (3, 1, overlap),
        [true, _, _] => (1, 2, overlap),
        _ => (0, 0, overlap),
    }
}

fn run_slice(dir: &std::path::Path, out: &str, extra: &[&str]) -> std::path::PathBuf {
    let s = write_scene(dir, "balls.json", BALLS);
    let (w, h) = (SIZE.0.to_string(), SIZE.1.to_string());
    let e = EXTENT.map(|x| x.to_string());
    let mut args = vec!["slice", s.to_str().unwrap(), "--plane", "z=0", "--size", &w, &h, "--extent"];
    args.extend(e.iter().map(String::as_str));
    args.extend(["-o", out]);
    args.extend(extra);
    komplex_ok(dir, &args);
    dir.join(out)
}

/// Pixels farther than a pixel's diagonal from every circle, with the
/// balls they lie in.
fn clear_pixels(margin_pixels: f64) -> Vec<(usize, usize, [bool; 3])> {
    let diagonal = (EXTENT[1] - EXTENT[0]) / SIZE.0 as f64 * std::f64::consts::SQRT_2;
    let mut out = Vec::new();
    for j in 0..SIZE.1 {
        for i in 0..SIZE.0 {
            let (u, v) = centre(i, j);
            if let Some(inside) = membership(u, v, margin_pixels * diagonal) {
                out.push((i, j, inside));
            }
        }
    }
    out
}

#[test]
fn the_exr_of_a_slice_holds_the_analytic_owners_materials_and_overlaps() {
    let dir = tempdir();
    let out = run_slice(dir.path(), "s.exr", &[]);
    let Some(exr) = read_exr(&out) else { return };
    assert_eq!((exr.width, exr.height), SIZE);
    let names: Vec<&str> = exr.channels.keys().map(String::as_str).collect();
    assert_eq!(names, ["id.block", "id.material", "overlap"]);
    assert!(exr.channels.values().all(|c| c.kind == "u32"));
    let pixels = clear_pixels(1.0);
    assert!(pixels.len() > SIZE.0 * SIZE.1 * 3 / 4, "{} clear pixels", pixels.len());
    let mut seen = BTreeSet::new();
    for (i, j, inside) in pixels {
        let got = (exr.at("id.block", j, i) as u32, exr.at("id.material", j, i) as u32, exr.at("overlap", j, i) as u32);
        assert_eq!(got, expected(inside), "pixel ({i}, {j}) at {:?}", centre(i, j));
        seen.insert(got);
    }
    // Every case occurs: empty, each ball alone, the overlap.
    assert_eq!(seen, BTreeSet::from([(0, 0, 0), (1, 2, 1), (2, 1, 1), (2, 1, 2), (3, 1, 1)]));
}

#[test]
fn the_png_of_a_slice_hatches_exactly_the_overlaps() {
    let dir = tempdir();
    let by_block = image::open(run_slice(dir.path(), "b.png", &[])).unwrap().to_rgb8();
    let by_material = image::open(run_slice(dir.path(), "m.png", &["--color-by", "material"])).unwrap().to_rgb8();
    assert_eq!(by_block.dimensions(), (SIZE.0 as u32, SIZE.1 as u32));
    // Colours by analytic class, two pixels clear of any boundary (so no
    // boundary line is among them).
    let classes = |img: &image::RgbImage| {
        let mut c: std::collections::BTreeMap<[bool; 3], BTreeSet<[u8; 3]>> = Default::default();
        for (i, j, inside) in clear_pixels(2.0) {
            c.entry(inside).or_default().insert(img.get_pixel(i as u32, j as u32).0);
        }
        c
    };
    let (glass, stone, pebble, both) =
        ([true, false, false], [false, true, false], [false, false, true], [true, true, false]);
    for (img, same_material) in [(&by_block, false), (&by_material, true)] {
        let c = classes(img);
        let one = |k: [bool; 3]| -> [u8; 3] {
            assert_eq!(c[&k].len(), 1, "{k:?}: {:?}", c[&k]);
            *c[&k].first().unwrap()
        };
        assert_eq!(one([false; 3]), [255, 255, 255], "empty space is white");
        let (g, s, p) = (one(glass), one(stone), one(pebble));
        assert!(g != s && g != p && g != [255; 3] && s != [255; 3]);
        assert_eq!(s == p, same_material, "stone and pebble share material \"a\"");
        // The overlap: the owner's colour and a darker hatching, and
        // nowhere else that darker colour.
        let hatch: Vec<[u8; 3]> = c[&both].iter().copied().filter(|&x| x != s).collect();
        assert!(c[&both].contains(&s) && hatch.len() == 1, "{:?}", c[&both]);
        assert!(hatch[0].iter().zip(s).all(|(h, s)| *h < s), "hatching {:?} on {s:?}", hatch[0]);
        for (k, colours) in &c {
            assert!(*k == both || !colours.contains(&hatch[0]), "{k:?} is hatched");
        }
    }
}

/// The owner at a point, if the same at the point and half a pixel away
/// along `u` and `v` either way (away from boundaries).
fn clear_owner(c: &complex::Complex, p: Point3<f64>, du: Vector3<f64>, dv: Vector3<f64>) -> Option<Option<u32>> {
    let owner = c.contains_point(&p).map(|b| b.0 + 1);
    let around = [p + du, p - du, p + dv, p - dv];
    around.iter().all(|q| c.contains_point(q).map(|b| b.0 + 1) == owner).then_some(owner)
}

#[test]
fn slices_of_the_example_scenes_agree_with_contains_point() {
    for (name, normal, up) in [
        ("table.json", [0.0, 0.0, 1.0], None),
        ("table.json", [1.0, 1.0, 1.0], None),
        ("glass.json", [0.0, 1.0, 0.2], Some([1.0, 0.0, 0.0])),
        ("primitives.json", [0.3, -1.0, 0.0], None),
    ] {
        let w = world(&scene(name), None);
        let c = &w.complex;
        let at = Point3::new(0.1, 0.6, 0.2);
        let plane = Plane::new(at.into(), normal, up).unwrap();
        let extent = Extent::new(-3.0, 3.0, -2.0, 2.0).unwrap();
        let (width, height) = (60u32, 40u32);
        let map = slice(&w, &Raster::new(plane, extent, Some((width, height))).unwrap());
        // The frame as docs/cli.md defines it: V the part of `up` across
        // the normal, U = V × N.
        let n = Vector3::from(normal).normalize();
        let up = Vector3::from(up.unwrap_or(if n.z.abs() < 0.9 { [0.0, 0.0, 1.0] } else { [0.0, 1.0, 0.0] }));
        let v = (up - n * up.dot(&n)).normalize();
        let u = v.cross(&n);
        let (du, dv) = (u * (3.0 / f64::from(width)), v * (2.0 / f64::from(height)));
        let mut checked = 0;
        for j in 0..height {
            for i in 0..width {
                let (pu, pv) = (-3.0 + (f64::from(i) + 0.5) * 0.1, 2.0 - (f64::from(j) + 0.5) * 0.1);
                let p = at + u * pu + v * pv;
                if let Some(owner) = clear_owner(c, p, du, dv) {
                    let k = (j * width + i) as usize;
                    assert_eq!(map.block[k], owner.unwrap_or(0), "{name} {normal:?}: pixel ({i}, {j}) at {p:?}");
                    let material = owner.map_or(0, |b| w.block_info(complex::BlockId(b - 1)).material as u32 + 1);
                    assert_eq!(map.material[k], material, "{name} {normal:?}: pixel ({i}, {j})");
                    checked += 1;
                }
            }
        }
        assert!(checked > 1000, "{name}: only {checked} pixels away from boundaries");
        assert!(map.block.iter().any(|&b| b != 0), "{name} {normal:?}: the slice misses the scene");
    }
}

#[test]
fn the_default_extent_frames_where_the_plane_cuts_the_scene() {
    let dir = tempdir();
    let s = write_scene(dir.path(), "balls.json", BALLS);
    let o = komplex_ok(dir.path(), &["slice", s.to_str().unwrap(), "--plane", "z=0", "-o", "d.png"]);
    // The balls' box: x from −1.5 to 1.9, y from −1 to 1.4; a margin of
    // 5 % of the longer side (3.4) on every side.
    let img = image::open(dir.path().join("d.png")).unwrap().to_rgb8();
    assert_eq!(img.dimensions(), (800, 586), "800 on the longer side, (2.4 + 0.34) / (3.4 + 0.34) of it on the other");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("d.png: 800x586, u -1.67"), "{err}");
}

#[test]
fn a_slice_does_not_depend_on_the_thread_count() {
    let dir = tempdir();
    let s = scene("glass.json");
    let s = s.to_str().unwrap();
    for out in ["t.png", "t.exr"] {
        let bytes = |threads: &str| {
            let args =
                ["slice", s, "--normal", "0.2", "1", "0.4", "--size", "300", "200", "--threads", threads, "-o", out];
            komplex_ok(dir.path(), &args);
            std::fs::read(dir.path().join(out)).unwrap()
        };
        assert!(bytes("1") == bytes("2"), "{out}");
    }
}

#[test]
fn coloured_by_name_blocks_of_one_name_are_one_region() {
    // The two balls of BALLS renamed alike (as an imported OpenMC cell's
    // union terms are): by name, their union is one colour with no
    // boundary or hatching inside; by block, the overlap is still hatched.
    let json = BALLS.replace("\"name\": \"stone\"", "\"name\": \"glass\"");
    let w = render::format::SceneFile::from_json(&json).unwrap().to_world().unwrap();
    let plane = Plane::axis("z=0").unwrap();
    let raster = Raster::new(
        plane,
        Extent::new(EXTENT[0], EXTENT[1], EXTENT[2], EXTENT[3]).unwrap(),
        Some((SIZE.0 as u32, SIZE.1 as u32)),
    )
    .unwrap();
    let map = slice(&w, &raster);
    assert_eq!(map.names, ["pebble", "glass"], "in order of first appearance, rows from the top");
    let by_name = map.rgb(render::slice::ColorBy::Name);
    let by_block = map.rgb(render::slice::ColorBy::Block);
    let colour = |rgb: &[u8], i: usize, j: usize| -> [u8; 3] {
        let k = 3 * (j * SIZE.0 + i);
        [rgb[k], rgb[k + 1], rgb[k + 2]]
    };
    let mut union = BTreeSet::new();
    let mut overlap_by_block = BTreeSet::new();
    for (i, j, inside) in clear_pixels(2.0) {
        let k = j * SIZE.0 + i;
        let named = (map.name[k] as usize).checked_sub(1).map_or("", |n| map.names[n].as_str());
        match inside {
            [true, true, false] | [true, false, false] | [false, true, false] => {
                assert_eq!(named, "glass");
                assert_eq!(map.named_overlap[k], 1);
                union.insert(colour(&by_name, i, j));
                if inside == [true, true, false] {
                    assert_eq!(map.overlap[k], 2);
                    overlap_by_block.insert(colour(&by_block, i, j));
                }
            }
            [false, false, true] => assert_eq!(named, "pebble"),
            _ => {}
        }
    }
    assert_eq!(union.len(), 1, "by name the two balls are one colour: {union:?}");
    assert_eq!(overlap_by_block.len(), 2, "by block the overlap is hatched: {overlap_by_block:?}");
}
