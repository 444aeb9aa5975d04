//! Benchmark scene generators: Haines' sphereflake, a grid of random
//! bounded blocks and a nested lattice of balls, as scene documents.
//!
//! ```
//! let flake = render::generate::sphereflake(2);
//! let world = flake.to_world().unwrap();
//! assert_eq!(world.complex.blocks().len(), 91 + 1); // 1 + 9 + 81 spheres and the ground
//! let grid = render::generate::grid(10, 7);
//! assert_eq!(grid.to_world().unwrap().complex.blocks().len(), 10);
//! let field = render::generate::nested_lattice(1000, 30);
//! assert_eq!(field.to_world().unwrap().complex.len(), 1000 * 1000 * 30 * 30 + 1);
//! ```

use std::collections::BTreeMap;
use std::f64::consts::PI;

use quadric::nalgebra::Vector3;

use crate::format::{
    Axis, CameraSpec, ColourSpec, CylinderSpec, Entry, LightSpec, MaterialSpec, ObjectSpec, ProjectionSpec, Scale,
    SceneFile, SphereSpec, Step,
};
use crate::keys::Animated;
use crate::sampling::{mix, GOLDEN};
use crate::world::{Model, Settings};

fn material(diffuse: [f64; 3], specular: f64, shininess: f64, reflect: f64) -> MaterialSpec {
    MaterialSpec {
        ambient: ColourSpec::Rgb(diffuse),
        diffuse: ColourSpec::Rgb(diffuse),
        specular: ColourSpec::Rgb([specular; 3]),
        shininess,
        model: Model::Phong,
        reflect: ColourSpec::Rgb([reflect; 3]),
        transmit: ColourSpec::Rgb([0.0; 3]),
        ior: 1.0,
        emission: ColourSpec::default(),
        bump: None,
    }
}

fn light(position: [f64; 3], c: f64) -> LightSpec {
    LightSpec { position, color: Some([c; 3]), diffuse: None, specular: None }
}

/// A 640 × 480 perspective camera, y up.
pub(crate) fn camera(eye: [f64; 3], direction: [f64; 3], aperture: f64) -> CameraSpec {
    CameraSpec {
        eye: Animated::Fixed(eye),
        direction: Animated::Fixed(direction),
        up: Animated::Fixed([0.0, 1.0, 0.0]),
        width: 640,
        height: 480,
        aperture,
        projection: ProjectionSpec::Perspective,
        diagonal: None,
        lens_radius: 0.0,
        focus_distance: None,
    }
}

fn block(name: String, material: &str, objects: Vec<ObjectSpec>, transform: Vec<Step>) -> Entry {
    Entry { name: Some(name), material: Some(material.into()), objects: Some(objects), transform, ..Entry::default() }
}

fn halfspace(q: [f64; 4]) -> ObjectSpec {
    ObjectSpec { halfspace: Some(q), ..ObjectSpec::default() }
}

/// The number of spheres in a sphereflake of `level`: `1 + 9 + … + 9^level`.
pub fn sphereflake_spheres(level: u32) -> u64 {
    (0..=level).map(|i| 9u64.pow(i)).sum()
}

/// Haines' sphereflake: a reflective unit sphere resting on a ground
/// half-space, each sphere carrying nine children of a third its radius
/// (six around its equator, three above, relative to the direction it grew
/// in), recursively `level` times; three lights. Level 3 has 820 spheres,
/// level 4 7,381.
pub fn sphereflake(level: u32) -> SceneFile {
    let mut blocks = vec![block("ground".into(), "ground", vec![halfspace([0.0, 1.0, 0.0, 0.0])], vec![])];
    let mut stack: Vec<(Vector3<f64>, f64, Vector3<f64>, u32)> =
        vec![(Vector3::new(0.0, 1.0, 0.0), 1.0, Vector3::y(), 0)];
    while let Some((centre, r, axis, depth)) = stack.pop() {
        let sphere = ObjectSpec {
            sphere: Some(Box::new(SphereSpec { radius: Some(r), center: Some([centre.x, centre.y, centre.z]) })),
            ..ObjectSpec::default()
        };
        blocks.push(block(format!("sphere {}", blocks.len()), "flake", vec![sphere], vec![]));
        if depth == level {
            continue;
        }
        // An orthonormal frame (u, v, axis) for the children's directions.
        let helper = if axis.x.abs() < 0.9 { Vector3::x() } else { Vector3::y() };
        let u = axis.cross(&helper).normalize();
        let v = axis.cross(&u);
        let children = (0..6u32)
            .map(|k| (0.0, f64::from(k) * PI / 3.0))
            .chain((0..3u32).map(|k| (PI / 3.0, PI / 6.0 + f64::from(k) * 2.0 * PI / 3.0)));
        for (elevation, azimuth) in children {
            let dir: Vector3<f64> = elevation.cos() * (azimuth.cos() * u + azimuth.sin() * v) + elevation.sin() * axis;
            let child_r = r / 3.0;
            stack.push((centre + (r + child_r) * dir, child_r, dir, depth + 1));
        }
    }
    SceneFile {
        schema: None,
        definitions: BTreeMap::new(),
        camera: camera([4.2, 4.4, 6.8], [-2.1, -1.7, -3.4], 45.0),
        settings: Settings { ambient: [0.1; 3], background: [0.08, 0.1, 0.16], max_depth: 4, ..Settings::default() },
        lights: vec![light([4.0, 6.0, 5.0], 0.6), light([-5.0, 5.0, 2.0], 0.35), light([1.0, 8.0, -4.0], 0.25)],
        materials: BTreeMap::from([
            ("flake".into(), material([0.55, 0.45, 0.35], 0.6, 40.0, 0.5)),
            ("ground".into(), material([0.45, 0.45, 0.5], 0.0, 10.0, 0.0)),
        ]),
        blocks,
        animation: None,
        metadata: None,
    }
}

/// A small deterministic generator (SplitMix64: the sampler's output
/// function over a counter), so the same seed gives the same scene
/// everywhere without a dependency.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(GOLDEN);
        mix(self.0)
    }

    /// Uniform in `[lo, hi)`.
    fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// `count` random bounded blocks on a cubic grid of unit cells (a cube of
/// side `⌈∛count⌉` cells, filled in order): spheres, capped cylinders and
/// boxes of six half-spaces, each randomly rotated and sized to stay in its
/// cell, in four materials, with two lights and the camera looking at the
/// cube across its diagonal. The same `seed` gives the same scene.
pub fn grid(count: u32, seed: u64) -> SceneFile {
    let mut rng = Rng(seed);
    let side = (1..).find(|s: &u32| u64::from(*s).pow(3) >= u64::from(count)).unwrap_or(1);
    let mut blocks = Vec::with_capacity(count as usize);
    let names = ["red", "green", "blue", "white"];
    for n in 0..count {
        let cell = [n % side, (n / side) % side, n / (side * side)].map(|c| f64::from(c) + 0.5);
        // Every shape fits in a ball of radius 0.45 around the cell centre.
        let kind = rng.next() % 3;
        let objects = match kind {
            0 => vec![ObjectSpec {
                sphere: Some(Box::new(SphereSpec { radius: Some(rng.uniform(0.2, 0.45)), center: None })),
                ..ObjectSpec::default()
            }],
            1 => {
                let r = rng.uniform(0.1, 0.25);
                let h = rng.uniform(0.1, 0.35);
                vec![
                    ObjectSpec {
                        cylinder: Some(Box::new(CylinderSpec { radius: Some(r), axis: Some(Axis::Y) })),
                        ..ObjectSpec::default()
                    },
                    halfspace([0.0, 1.0, 0.0, -h]),
                    halfspace([0.0, -1.0, 0.0, -h]),
                ]
            }
            _ => {
                let e = [rng.uniform(0.1, 0.25), rng.uniform(0.1, 0.25), rng.uniform(0.1, 0.25)];
                vec![
                    halfspace([1.0, 0.0, 0.0, -e[0]]),
                    halfspace([-1.0, 0.0, 0.0, -e[0]]),
                    halfspace([0.0, 1.0, 0.0, -e[1]]),
                    halfspace([0.0, -1.0, 0.0, -e[1]]),
                    halfspace([0.0, 0.0, 1.0, -e[2]]),
                    halfspace([0.0, 0.0, -1.0, -e[2]]),
                ]
            }
        };
        let mut transform = vec![];
        if kind != 0 {
            transform.push(Step::RotateX(rng.uniform(0.0, 360.0)));
            transform.push(Step::RotateY(rng.uniform(0.0, 360.0)));
        } else {
            // Squash a few spheres into ellipsoids, so quadrics are not all spheres.
            let sy = rng.uniform(0.6, 1.0);
            transform.push(Step::Scale(Scale::PerAxis([1.0, sy, 1.0])));
        }
        transform.push(Step::Translate(cell));
        let m = names[(rng.next() % 4) as usize];
        blocks.push(block(format!("b{n}"), m, objects, transform));
    }
    let s = f64::from(side);
    SceneFile {
        schema: None,
        definitions: BTreeMap::new(),
        camera: camera([2.2 * s, 1.6 * s, 2.6 * s], [-1.7 * s, -1.1 * s, -2.1 * s], 50.0),
        settings: Settings { ambient: [0.15; 3], background: [0.05, 0.05, 0.08], max_depth: 2, ..Settings::default() },
        lights: vec![light([3.0 * s, 4.0 * s, 2.0 * s], 0.7), light([-s, 2.0 * s, 3.0 * s], 0.3)],
        materials: BTreeMap::from([
            ("red".into(), material([0.7, 0.2, 0.15], 0.3, 30.0, 0.0)),
            ("green".into(), material([0.2, 0.6, 0.25], 0.3, 30.0, 0.0)),
            ("blue".into(), material([0.2, 0.3, 0.7], 0.3, 30.0, 0.0)),
            ("white".into(), material([0.8, 0.8, 0.8], 0.5, 60.0, 0.3)),
        ]),
        blocks,
        animation: None,
        metadata: None,
    }
}

/// A nested lattice over a ground plane: an `outer × outer` lattice of
/// tiles, each an `inner × inner` lattice of a small ball, so
/// `outer² · inner²` balls (a billion at 1000 and 30) and the ground. The
/// camera looks over the field from above one corner's middle.
pub fn nested_lattice(outer: u32, inner: u32) -> SceneFile {
    let ball = Entry {
        name: Some("ball".into()),
        material: Some("ball".into()),
        objects: Some(vec![ObjectSpec {
            sphere: Some(Box::new(SphereSpec { radius: Some(0.35), center: Some([0.0, 0.35, 0.0]) })),
            ..ObjectSpec::default()
        }]),
        ..Entry::default()
    };
    let lattice = |name: &str, pitch: f64, n: u32, transform: Vec<Step>| Entry {
        lattice: Some(name.into()),
        pitch: Some([pitch, 0.0, pitch]),
        count: Some([n, 1, n]),
        transform,
        ..Entry::default()
    };
    let (m, side) = (f64::from(inner), f64::from(outer) * f64::from(inner));
    let definitions = BTreeMap::from([
        ("ball".to_string(), crate::format::DefinitionSpec { blocks: vec![ball] }),
        ("tile".to_string(), crate::format::DefinitionSpec { blocks: vec![lattice("ball", 1.0, inner, vec![])] }),
    ]);
    let centre = Step::Translate([0.5 - side / 2.0, 0.0, 0.5 - side / 2.0]);
    SceneFile {
        schema: None,
        definitions,
        animation: None,
        metadata: None,
        camera: camera([0.0, 14.0, side / 2.0 + 10.0], [0.0, -0.3, -1.0], 60.0),
        settings: Settings { ambient: [0.15; 3], background: [0.35, 0.45, 0.6], max_depth: 2, ..Settings::default() },
        lights: vec![light([side / 4.0, 40.0, side / 2.0], 0.8)],
        materials: BTreeMap::from([
            ("ball".into(), material([0.75, 0.35, 0.2], 0.4, 40.0, 0.0)),
            ("ground".into(), material([0.45, 0.45, 0.5], 0.0, 10.0, 0.0)),
        ]),
        blocks: vec![
            lattice("tile", m, outer, vec![centre]),
            block("ground".into(), "ground", vec![halfspace([0.0, 1.0, 0.0, 0.0])], vec![]),
        ],
    }
}

/// The document as JSON with one block per line: compact for 100,000
/// blocks, still diffable.
pub fn to_json(scene: &SceneFile) -> String {
    let head = SceneFile { blocks: vec![], definitions: BTreeMap::new(), ..scene.clone() };
    // Serialising plain data cannot fail.
    let head = serde_json::to_value(&head).unwrap_or_default();
    let mut out = String::with_capacity(scene.blocks.len() * 200 + 1000);
    out.push_str("{\n");
    for key in ["$schema", "metadata", "camera", "settings", "lights", "materials"] {
        if let Some(v) = head.get(key) {
            out.push_str(&format!("  {}: {},\n", serde_json::Value::from(key), v));
        }
    }
    if !scene.definitions.is_empty() {
        out.push_str("  \"definitions\": {\n");
        for (i, (name, d)) in scene.definitions.iter().enumerate() {
            out.push_str(&format!("    {}: {{ \"blocks\": [\n", serde_json::Value::from(name.as_str())));
            entries(&mut out, &d.blocks, "      ");
            out.push_str(if i + 1 < scene.definitions.len() { "    ] },\n" } else { "    ] }\n" });
        }
        out.push_str("  },\n");
    }
    out.push_str("  \"blocks\": [\n");
    entries(&mut out, &scene.blocks, "    ");
    out.push_str("  ]\n}\n");
    out
}

/// One entry per line, indented.
fn entries(out: &mut String, list: &[Entry], indent: &str) {
    for (i, b) in list.iter().enumerate() {
        out.push_str(indent);
        out.push_str(&serde_json::to_string(b).unwrap_or_default());
        out.push_str(if i + 1 < list.len() { ",\n" } else { "\n" });
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn sphereflake_counts() {
        assert_eq!(sphereflake_spheres(3), 820);
        assert_eq!(sphereflake_spheres(4), 7381);
        assert_eq!(sphereflake(3).blocks.len(), 821);
    }

    #[test]
    fn sphereflake_spheres_are_disjoint_and_above_ground() {
        let world = sphereflake(2).to_world().unwrap();
        let spheres: Vec<(Vector3<f64>, f64)> = sphereflake(2)
            .blocks
            .iter()
            .filter_map(|b| b.objects.as_ref()?[0].sphere.clone())
            .map(|s| (Vector3::from(s.center.unwrap()), s.radius.unwrap()))
            .collect();
        assert_eq!(spheres.len(), 91);
        for (i, (a, ra)) in spheres.iter().enumerate() {
            // The root rests on the ground (tangent); the rest stay above it.
            assert!(a.y - ra >= 0.0, "sphere {i} reaches below the ground");
            for (b, rb) in &spheres[i + 1..] {
                assert!((a - b).norm() >= ra + rb - 1e-12, "spheres overlap");
            }
        }
        assert_eq!(world.complex.blocks().len(), 92);
    }

    /// Equal documents, numbers to within parsing rounding (serde_json's
    /// default float parser may be off by an ulp or so).
    fn same(a: &serde_json::Value, b: &serde_json::Value) {
        use serde_json::Value as V;
        match (a, b) {
            (V::Number(x), V::Number(y)) => {
                let (x, y) = (x.as_f64().unwrap(), y.as_f64().unwrap());
                assert!((x - y).abs() <= 1e-15 * x.abs().max(1.0), "{x} != {y}");
            }
            (V::Array(x), V::Array(y)) => {
                assert_eq!(x.len(), y.len());
                x.iter().zip(y).for_each(|(x, y)| same(x, y));
            }
            (V::Object(x), V::Object(y)) => {
                assert_eq!(x.keys().collect::<Vec<_>>(), y.keys().collect::<Vec<_>>());
                x.values().zip(y.values()).for_each(|(x, y)| same(x, y));
            }
            _ => assert_eq!(a, b),
        }
    }

    #[test]
    fn generated_json_loads_back_identically() {
        for scene in [sphereflake(1), grid(30, 3)] {
            let text = to_json(&scene);
            let back = SceneFile::from_json(&text).unwrap();
            same(&serde_json::to_value(&back).unwrap(), &serde_json::to_value(&scene).unwrap());
        }
    }

    #[test]
    fn grid_blocks_stay_in_their_cells() {
        let world = grid(64, 11).to_world().unwrap();
        assert_eq!(world.complex.blocks().len(), 64);
        for (n, _) in world.complex.blocks().iter().enumerate() {
            let aabb = world.complex.block_aabb(complex::BlockId(n as u32));
            assert!(aabb.is_bounded(), "block {n} is unbounded");
            let n = n as u32;
            let cell = Vector3::new(f64::from(n % 4), f64::from((n / 4) % 4), f64::from(n / 16));
            for k in 0..3 {
                assert!(aabb.min[k] >= cell[k] && aabb.max[k] <= cell[k] + 1.0, "block {n} leaves its cell: {aabb:?}");
            }
        }
        // Same seed, same scene; another seed, another scene.
        assert_eq!(to_json(&grid(20, 5)), to_json(&grid(20, 5)));
        assert_ne!(to_json(&grid(20, 5)), to_json(&grid(20, 6)));
    }
}
