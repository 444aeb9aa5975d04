//! `komplex import-openmc`: an OpenMC `geometry.xml` (or the `<geometry>`
//! of a `model.xml`) as a Komplex scene (docs/openmc.md).
//!
//! [`model`] reads the XML, [`region`] parses region expressions into
//! unions of intersections, [`surface`] turns surfaces into solids and
//! [`emit`] writes the cells, fills and lattices as scene entries. This
//! module adds named materials, a camera that frames the model, and the
//! summary of `--check`.
//!
//! ```
//! let xml = r#"<geometry>
//!   <surface id="1" type="sphere" coeffs="0 0 0 2" boundary="vacuum"/>
//!   <surface id="2" type="z-plane" coeffs="0"/>
//!   <cell id="10" material="1" region="-1 -2"/>
//!   <cell id="11" material="void" region="-1 2"/>
//! </geometry>"#;
//! let imported = render::openmc::import(xml).unwrap();
//! let world = imported.scene.to_world().unwrap();
//! let below = world.complex.contains_point(&[0.0, 0.5, -1.0].into()).unwrap();
//! assert_eq!(world.complex.block(below).name(), "cell 10");
//! ```

pub mod emit;
pub mod model;
pub mod region;
pub mod surface;

use std::collections::BTreeMap;
use std::fmt;

use crate::format::{CameraSpec, ColourSpec, LightSpec, MaterialSpec, SceneFile};
use crate::keys::Animated;
use crate::world::{Model as Specular, Settings, World};

pub use model::{ImportError, Pos};

/// An imported model: the scene and what it came from.
pub struct Imported {
    /// The scene, ready to write or to convert.
    pub scene: SceneFile,
    /// Number of cells in the file.
    pub cells: usize,
    /// Number of universes.
    pub universes: usize,
    /// Number of rectangular lattices.
    pub lattices: usize,
    /// The root universe's id.
    pub root: u64,
    /// The box the camera frames: the model's bounds, with an unbounded
    /// axis replaced by the widest bounded extent (`[min, max]`).
    pub frame: ([f64; 3], [f64; 3]),
    /// Whether every axis of the model is bounded.
    pub bounded: bool,
    /// Things that are valid but may not mean what OpenMC makes of them.
    pub warnings: Vec<String>,
}

/// Imports a `geometry.xml` or `model.xml` file; errors name the file and
/// the line and column.
pub fn import_file(path: &std::path::Path) -> Result<Imported, crate::error::Error> {
    let text =
        std::fs::read_to_string(path).map_err(|source| crate::error::Error::Io { path: path.to_path_buf(), source })?;
    import(&text).map_err(|e| crate::error::Error::Data { file: path.to_path_buf(), message: e.to_string() })
}

/// Imports the text of a `geometry.xml` or `model.xml`.
pub fn import(xml: &str) -> Result<Imported, ImportError> {
    let model = model::parse(xml)?;
    let emitted = emit::emit(&model)?;
    let materials: BTreeMap<String, MaterialSpec> =
        emitted.materials.iter().enumerate().map(|(i, m)| (emit::material_name(*m), material(*m, i))).collect();
    let metadata = serde_json::json!({
        "openmc": {
            "root_universe": model.root,
            "boundaries": model.boundaries.iter().map(|(s, b)| (s.to_string(), serde_json::Value::from(b.as_str()))).collect::<serde_json::Map<_, _>>(),
        }
    });
    let mut scene = SceneFile {
        schema: None,
        camera: camera(&([-1.0; 3], [1.0; 3])),
        settings: Settings::default(),
        lights: vec![],
        materials,
        definitions: emitted.definitions,
        blocks: emitted.blocks,
        animation: None,
        metadata: Some(metadata),
    };
    let world = scene.to_world().map_err(|e| ImportError {
        pos: None,
        message: format!("the imported scene is not valid (a bug of the importer): {e}"),
    })?;
    let (frame, bounded) = framing(&world);
    scene.camera = camera(&frame);
    let (lo, hi) = frame;
    let size = (0..3).map(|i| hi[i] - lo[i]).fold(0.0, f64::max);
    let centre = [0, 1, 2].map(|i| (lo[i] + hi[i]) / 2.0);
    scene.lights = vec![LightSpec {
        position: [centre[0] + 2.0 * size, centre[1] + 1.5 * size, centre[2] + 2.5 * size],
        color: Some([1.0; 3]),
        diffuse: None,
        specular: None,
    }];
    scene.settings.ambient = [0.35; 3];
    let universes: std::collections::BTreeSet<u64> = model.cells.iter().map(|c| c.universe).collect();
    Ok(Imported {
        scene,
        cells: model.cells.len(),
        universes: universes.len(),
        lattices: model.lattices.len(),
        root: model.root,
        frame,
        bounded,
        warnings: model.warnings,
    })
}

/// A material of its own colour (hues a golden angle apart), half
/// transmitting so that the inside of a model shows through its outer
/// cells; void lets everything through. Transparent at index 1: the media
/// are for the priority rule, not for refraction.
fn material(m: Option<u64>, index: usize) -> MaterialSpec {
    let (colour, transmit) = match m {
        None => ([0.0; 3], [1.0; 3]),
        Some(_) => (hue(index as f64 * 0.381_966_011_250_105), [0.45; 3]),
    };
    MaterialSpec {
        ambient: ColourSpec::Rgb(colour.map(|c| 0.4 * c)),
        diffuse: ColourSpec::Rgb(colour.map(|c| 0.6 * c)),
        specular: ColourSpec::Rgb([if m.is_some() { 0.1 } else { 0.0 }; 3]),
        shininess: 20.0,
        model: Specular::Phong,
        reflect: ColourSpec::default(),
        transmit: ColourSpec::Rgb(transmit),
        ior: 1.0,
        emission: ColourSpec::default(),
        bump: None,
    }
}

/// A saturated colour of hue `h` (turns).
fn hue(h: f64) -> [f64; 3] {
    let h = h.fract() * 6.0;
    let x = 1.0 - (h % 2.0 - 1.0).abs();
    let (r, g, b) = match h as u32 {
        0 => (1.0, x, 0.0),
        1 => (x, 1.0, 0.0),
        2 => (0.0, 1.0, x),
        3 => (0.0, x, 1.0),
        4 => (x, 0.0, 1.0),
        _ => (1.0, 0.0, x),
    };
    [0.15 + 0.85 * r, 0.15 + 0.85 * g, 0.15 + 0.85 * b]
}

/// The model's box, an unbounded axis replaced by the widest bounded
/// extent about its centre (or `[−1, 1]` when no axis is bounded), and
/// whether every axis was bounded.
fn framing(world: &World) -> (([f64; 3], [f64; 3]), bool) {
    let b = world.complex.aabb();
    let bounded = (0..3).all(|i| b.min[i].is_finite() && b.max[i].is_finite());
    let widest = (0..3)
        .filter(|i| b.min[*i].is_finite() && b.max[*i].is_finite())
        .map(|i| b.max[i] - b.min[i])
        .fold(0.0, f64::max);
    let half = if widest > 0.0 { widest / 2.0 } else { 1.0 };
    let lo = [0, 1, 2].map(|i| if b.min[i].is_finite() && b.max[i].is_finite() { b.min[i] } else { -half });
    let hi = [0, 1, 2].map(|i| if b.min[i].is_finite() && b.max[i].is_finite() { b.max[i] } else { half });
    ((lo, hi), bounded)
}

/// A perspective camera looking at the box's centre from above its corner
/// of least x and y
/// (z up, as OpenMC models are drawn), far enough for the box's bounding
/// sphere to fit the 40° diagonal opening.
pub(crate) fn camera(frame: &([f64; 3], [f64; 3])) -> CameraSpec {
    let (lo, hi) = frame;
    let centre = [0, 1, 2].map(|i| (lo[i] + hi[i]) / 2.0);
    let radius = ((0..3).map(|i| (hi[i] - lo[i]).powi(2)).sum::<f64>()).sqrt() / 2.0;
    let radius = if radius > 0.0 { radius } else { 1.0 };
    let aperture: f64 = 40.0;
    // The image's shorter side sees about 0.6 of the diagonal's angle.
    let distance = radius / (0.6 * (aperture.to_radians() / 2.0)).tan();
    let dir = [0.55, 0.65, -0.52];
    let norm = (dir.iter().map(|x| x * x).sum::<f64>()).sqrt();
    let eye = [0, 1, 2].map(|i| centre[i] - dir[i] / norm * distance);
    let direction = [0, 1, 2].map(|i| centre[i] - eye[i]);
    CameraSpec { up: Animated::Fixed([0.0, 0.0, 1.0]), ..crate::generate::camera(eye, direction, aperture) }
}

/// Two cells that share space, found by sampling points.
#[derive(Clone, Debug, PartialEq)]
pub struct CellOverlap {
    /// The first cell's name (the earlier one in priority, which owns the space).
    pub a: String,
    /// The second cell's name.
    pub b: String,
    /// How many sample points lie in both.
    pub hits: u64,
    /// The shared volume estimated from the hits.
    pub volume: f64,
    /// Its standard error (binomial).
    pub error: f64,
    /// A sample point inside both.
    pub point: [f64; 3],
}

/// What `komplex import-openmc --check` prints.
pub struct Summary<'a> {
    /// The import.
    pub imported: &'a Imported,
    /// The world built from it.
    pub world: &'a World,
    /// Pairs of different cells that share space.
    pub overlaps: Vec<CellOverlap>,
    /// Points sampled in the framed box.
    pub points: u64,
    /// The framed box's volume.
    pub box_volume: f64,
}

impl fmt::Display for Summary<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let i = self.imported;
        writeln!(
            f,
            "cells: {} in {} universes, {} lattices; root universe {}",
            i.cells, i.universes, i.lattices, i.root
        )?;
        writeln!(
            f,
            "blocks: {} placed ({} definitions, {} materials)",
            self.world.complex.len(),
            i.scene.definitions.len(),
            i.scene.materials.len()
        )?;
        let (lo, hi) = i.frame;
        let b = |v: [f64; 3]| format!("({:.6}, {:.6}, {:.6})", v[0], v[1], v[2]);
        if i.bounded {
            writeln!(f, "bounds: {} to {}", b(lo), b(hi))?;
        } else {
            writeln!(f, "bounds: unbounded; the camera and the overlap check use {} to {}", b(lo), b(hi))?;
        }
        if self.overlaps.is_empty() {
            // With no hit in n points, the shared volume is below 3/n of
            // the box with 95 % confidence (the rule of three).
            writeln!(
                f,
                "overlaps: none between different cells at {} points (any overlap is smaller than {:.3e}, 95 % confidence)",
                self.points,
                3.0 * self.box_volume / self.points as f64
            )?;
        } else {
            writeln!(
                f,
                "overlaps: {} pairs of cells share space ({} points sampled)",
                self.overlaps.len(),
                self.points
            )?;
            for o in &self.overlaps {
                writeln!(
                    f,
                    "  \"{}\" & \"{}\": {:.6e} ± {:.1e} ({} points), e.g. at ({:.6}, {:.6}, {:.6})",
                    o.a, o.b, o.volume, o.error, o.hits, o.point[0], o.point[1], o.point[2]
                )?;
            }
        }
        Ok(())
    }
}

/// The summary of `--check`: overlaps between different cells, found by
/// `points` uniform random points in the framed box (blocks of one cell,
/// the terms of its union, may overlap and are not counted).
pub fn summary<'a>(imported: &'a Imported, world: &'a World, points: u64) -> Summary<'a> {
    use rayon::prelude::*;
    let (lo, hi) = imported.frame;
    let box_volume: f64 = (0..3).map(|i| hi[i] - lo[i]).product();
    const CHUNK: u64 = 1 << 14;
    let chunks = points.div_ceil(CHUNK);
    type Found = BTreeMap<(String, String), (u64, [f64; 3])>;
    let found: Found = (0..chunks)
        .into_par_iter()
        .map(|c| {
            let mut found = Found::new();
            let mut state = crate::sampling::mix(c ^ 0x6f70_656e_6d63);
            let mut next = || {
                state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
                (crate::sampling::mix(state) >> 11) as f64 / (1u64 << 53) as f64
            };
            let mut inside = Vec::new();
            let mut names: Vec<&str> = Vec::new();
            for _ in c * CHUNK..((c + 1) * CHUNK).min(points) {
                let p = [0, 1, 2].map(|i| lo[i] + (hi[i] - lo[i]) * next());
                inside.clear();
                world.complex.blocks_containing(&p.into(), &mut inside);
                inside.sort_unstable();
                if inside.len() < 2 {
                    continue;
                }
                names.clear();
                for id in &inside {
                    let n = world.complex.block(*id).name();
                    if !names.contains(&n) {
                        names.push(n);
                    }
                }
                for (k, a) in names.iter().enumerate() {
                    for b in &names[k + 1..] {
                        found.entry((a.to_string(), b.to_string())).or_insert((0, p)).0 += 1;
                    }
                }
            }
            found
        })
        .reduce(Found::new, |mut x, y| {
            for (k, (n, p)) in y {
                x.entry(k).or_insert((0, p)).0 += n;
            }
            x
        });
    let overlaps = found
        .into_iter()
        .map(|((a, b), (hits, point))| {
            let q = hits as f64 / points as f64;
            CellOverlap {
                a,
                b,
                hits,
                volume: q * box_volume,
                error: (q * (1.0 - q) / points as f64).sqrt() * box_volume,
                point,
            }
        })
        .collect();
    Summary { imported, world, overlaps, points, box_volume }
}
