//! The scene file into the world: the camera, settings, lights and
//! materials checked and resolved, the blocks flattened (`flatten`) and the
//! complex built. Every error names its place in the file, with a line and
//! column when the text is at hand.

use std::path::Path;
use std::sync::Arc;
use std::time::{Duration, Instant};

use complex::{Complex, ComplexError, ComplexOptions, Placement};
use quadric::nalgebra::{Point3, Vector3};

use crate::camera::{Camera, CameraError, Projection};
use crate::error::{Error, SceneError};
use crate::flatten::{finite_triple, vec3, Flat, Flattened, Member};
use crate::format::{CameraSpec, ColourSpec, ProjectionSpec, SceneFile, TextureSpec, VeinSpec};
use crate::limits::{MAX_BOUNCES, MAX_SPP};
use crate::texture::{Bump, Texture};
use crate::world::{BlockInfo, Item, Layout, Light, Material, Model, Settings, Textures, Triple, World};

/// Reads and converts a scene file.
pub fn load(path: &Path) -> Result<World, Error> {
    load_timed(path).map(|(world, _)| world)
}

/// How long each stage of [`load`] took (`komplex bench --stages`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LoadTimes {
    /// Reading the file and checking its encoding.
    pub read: Duration,
    /// Parsing the JSON into the scene file's types.
    pub parse: Duration,
    /// Checking the camera, settings, lights and materials and flattening
    /// the blocks (their solids placed).
    pub flatten: Duration,
    /// Building the complex (boxes, BVH, packed solids, point grid) and
    /// the world.
    pub build: Duration,
}

/// A scene file's text at least this long is dropped once parsed (a large
/// scene's text is as big as its blocks); an error found later is located
/// in the file read again. Shorter texts are kept for that.
const KEEP_TEXT_BELOW: usize = 16 << 20;

/// [`load`], with the time each stage took.
pub fn load_timed(path: &Path) -> Result<(World, LoadTimes), Error> {
    load_keeping(path, KEEP_TEXT_BELOW)
}

/// [`load_timed`], keeping the text for errors if it is shorter than `keep_below` bytes.
fn load_keeping(path: &Path, keep_below: usize) -> Result<(World, LoadTimes), Error> {
    let mut times = LoadTimes::default();
    let start = Instant::now();
    let text = read_text(path)?;
    let scene_error = |source| Error::Scene { file: path.to_path_buf(), source };
    times.read = start.elapsed();
    let start = Instant::now();
    let scene = SceneFile::from_json(&text).map_err(scene_error)?;
    times.parse = start.elapsed();
    let text = (text.len() < keep_below).then_some(text);
    // Only an error reads the text again: a file changed since is located
    // as it is now, an unreadable one not at all.
    let located = |e: SceneError| match &text {
        Some(text) => scene_error(e.located(text)),
        None => scene_error(e.located(&std::fs::read_to_string(path).unwrap_or_default())),
    };
    let start = Instant::now();
    let parts = scene.into_world_parts().map_err(located)?;
    times.flatten = start.elapsed();
    let start = Instant::now();
    let world = parts.build().map_err(located)?;
    times.build = start.elapsed();
    Ok((world, times))
}

/// Reads a scene file's text; bad UTF-8 is a scene error with its place.
pub(crate) fn read_text(path: &Path) -> Result<String, Error> {
    let bytes = std::fs::read(path).map_err(|source| Error::Io { path: path.to_path_buf(), source })?;
    let scene_error = |source| Error::Scene { file: path.to_path_buf(), source };
    // Bad encoding is bad input (exit 1), located like a syntax error.
    String::from_utf8(bytes).map_err(|e| {
        let valid = &e.as_bytes()[..e.utf8_error().valid_up_to()];
        let valid = std::str::from_utf8(valid).unwrap_or_default();
        let line = valid.matches('\n').count() + 1;
        let column = valid.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
        let byte = e.as_bytes()[e.utf8_error().valid_up_to()];
        let message = format!("the file is not UTF-8 (byte 0x{byte:02x})");
        scene_error(SceneError::Parse { path: String::new(), line, column, message })
    })
}

/// A colour or reflectance: finite and not negative (negative light or
/// reflectance has no physical meaning and would subtract light).
fn colour(t: &Triple, place: &str, what: &str) -> Result<(), SceneError> {
    finite_triple(t, place, what)?;
    if t.iter().any(|c| *c < 0.0) {
        return Err(SceneError::semantic(place, format!("{what} must not be negative, got {t:?}")));
    }
    Ok(())
}

/// A texture's `scale` (or a bump's): finite and positive.
fn positive(x: f64, place: &str, what: &str) -> Result<(), SceneError> {
    if x.is_finite() && x > 0.0 {
        Ok(())
    } else {
        Err(SceneError::semantic(place, format!("{what} must be finite and > 0, got {x}")))
    }
}

/// A texture's `octaves`: 1 to [`MAX_OCTAVES`].
fn octaves(n: u32, place: &str) -> Result<(), SceneError> {
    if (1..=MAX_OCTAVES).contains(&n) {
        Ok(())
    } else {
        Err(SceneError::semantic(place, format!("octaves must be between 1 and {MAX_OCTAVES}, got {n}")))
    }
}

/// The most octaves a texture sums (the 17th would be below a 65,000th of the first).
const MAX_OCTAVES: u32 = 16;

/// A material colour checked and resolved: its constant colour (the mean
/// of a texture's two colours) and its texture. `place` is the colour's
/// path (`materials.m.diffuse`), `what` its key.
fn resolve_colour(c: &ColourSpec, place: &str, what: &str) -> Result<(Vector3<f64>, Option<Texture>), SceneError> {
    let t = match c {
        ColourSpec::Rgb(t) => {
            colour(t, place, what)?;
            return Ok((vec3(*t), None));
        }
        ColourSpec::Texture(t) => t,
    };
    let (kind, scale, colors) = match &**t {
        TextureSpec::Checker(c) => ("checker", c.scale, &c.colors),
        TextureSpec::Noise(n) => ("noise", n.scale, &n.colors),
        TextureSpec::Marble(v) => ("marble", v.scale, &v.colors),
        TextureSpec::Wood(v) => ("wood", v.scale, &v.colors),
    };
    let at = format!("{place}.{kind}");
    positive(scale, &format!("{at}.scale"), "scale")?;
    for (i, c) in colors.iter().enumerate() {
        colour(c, &format!("{at}.colors[{i}]"), what)?;
    }
    let vein = |v: &VeinSpec| -> Result<(), SceneError> {
        octaves(v.octaves, &format!("{at}.octaves"))?;
        if !(v.turbulence.is_finite() && v.turbulence >= 0.0) {
            let msg = format!("turbulence must be finite and >= 0, got {}", v.turbulence);
            return Err(SceneError::semantic(&format!("{at}.turbulence"), msg));
        }
        Ok(())
    };
    let colors = [vec3(colors[0]), vec3(colors[1])];
    let texture = match &**t {
        TextureSpec::Checker(_) => Texture::Checker { scale, colors },
        TextureSpec::Noise(n) => {
            octaves(n.octaves, &format!("{at}.octaves"))?;
            Texture::Noise { scale, octaves: n.octaves, colors }
        }
        TextureSpec::Marble(v) => {
            vein(v)?;
            Texture::Marble { scale, octaves: v.octaves, turbulence: v.turbulence, colors }
        }
        TextureSpec::Wood(v) => {
            vein(v)?;
            Texture::Wood { scale, octaves: v.octaves, turbulence: v.turbulence, colors }
        }
    };
    Ok(((colors[0] + colors[1]) * 0.5, Some(texture)))
}

/// The member of `camera` a camera error is about, so that the error
/// names it (and its line and column) rather than the whole camera.
fn camera_field(e: &CameraError, c: &CameraSpec) -> &'static str {
    match e {
        CameraError::ZeroDirection => "camera.direction",
        // The eye is finite (checked first); an up vector of finite
        // components can still have a norm that overflows.
        CameraError::NonFinite if vec3(*c.up.first()).norm().is_finite() => "camera.eye",
        CameraError::NonFinite | CameraError::UpParallel => "camera.up",
        CameraError::EmptyImage(0, _) => "camera.width",
        CameraError::EmptyImage(..) => "camera.height",
        // Either side can be cut down; the longer is the likelier mistake.
        CameraError::TooLarge(w, h) if h > w => "camera.height",
        CameraError::TooLarge(..) => "camera.width",
        CameraError::BadAperture(_) => "camera.aperture",
        CameraError::BadLensRadius(_) => "camera.lens_radius",
        CameraError::BadFocusDistance(_) => "camera.focus_distance",
        CameraError::BadDiagonal(_) => "camera.diagonal",
    }
}

/// The camera of `c` (docs/model.md §4): the pinhole, then the projection
/// and the lens. `focus_distance` defaults to `|direction|`, so that
/// `direction = target - eye` focuses on the target. Keyed members are
/// read at their first key (a scene resolved at a frame has none).
fn camera(c: &CameraSpec) -> Result<Camera, SceneError> {
    let (eye, direction, up) = (*c.eye.first(), *c.direction.first(), *c.up.first());
    finite_triple(&eye, "camera.eye", "the eye")?;
    finite_triple(&direction, "camera.direction", "the direction")?;
    finite_triple(&up, "camera.up", "the up vector")?;
    let projection = match (c.projection, c.diagonal) {
        (ProjectionSpec::Perspective, None) => Projection::Perspective,
        (ProjectionSpec::Perspective, Some(_)) => {
            let msg = "only an orthographic camera has a diagonal (set \"projection\": \"orthographic\")";
            return Err(SceneError::semantic("camera.diagonal", msg));
        }
        (ProjectionSpec::Orthographic, Some(diagonal)) => Projection::Orthographic { diagonal },
        (ProjectionSpec::Orthographic, None) => {
            let msg = "an orthographic camera needs \"diagonal\", the world-space length of the image diagonal";
            return Err(SceneError::semantic("camera.projection", msg));
        }
    };
    let focus = c.focus_distance.as_ref().map_or_else(|| vec3(direction).norm(), |f| *f.first());
    Camera::new(Point3::from(vec3(eye)), vec3(direction), vec3(up), c.width, c.height, c.aperture)
        .and_then(|cam| cam.with_projection(projection))
        .and_then(|cam| cam.with_lens(c.lens_radius, focus))
        .map_err(|e| SceneError::semantic(camera_field(&e, c), e.to_string()))
}

impl SceneFile {
    /// Parses and converts a scene; every error carries its place with a
    /// line and column.
    pub fn load_str(text: &str) -> Result<World, SceneError> {
        // The parsed document is dropped before the complex is built, so
        // that the build's allocations can take the memory it frees instead
        // of fresh pages (a 100,000-block scene's parsed entries are about
        // a fifth of the load's memory).
        let scene = Self::from_json(text)?;
        let parts = scene.into_world_parts().map_err(|e| e.located(text))?;
        parts.build().map_err(|e| e.located(text))
    }

    // `world_parts`, dropping the parsed document before it returns (the
    // complex is built after it).
    fn into_world_parts(self) -> Result<WorldParts, SceneError> {
        self.world_parts()
    }

    /// Resolves names, composes transforms and builds the complex.
    pub fn to_world(&self) -> Result<World, SceneError> {
        self.world_parts()?.build()
    }

    // Everything of `to_world` but the complex: checks the camera, settings,
    // lights and materials and flattens the blocks.
    pub(crate) fn world_parts(&self) -> Result<WorldParts, SceneError> {
        let camera = camera(&self.camera)?;
        if let Some(a) = &self.animation {
            if a.frames[0] > a.frames[1] {
                let msg = format!("the first frame comes after the last: {:?}", a.frames);
                return Err(SceneError::semantic("animation.frames", msg));
            }
        }

        let s = &self.settings;
        colour(&s.ambient, "settings.ambient", "the ambient light")?;
        colour(&s.background, "settings.background", "the background")?;
        if s.max_depth > MAX_BOUNCES {
            return Err(SceneError::semantic(
                "settings.max_depth",
                format!("must be at most {MAX_BOUNCES}, got {}", s.max_depth),
            ));
        }
        if let Some(e) = s.epsilon {
            if !(e.is_finite() && e >= 0.0) {
                return Err(SceneError::semantic("settings.epsilon", format!("must be finite and >= 0, got {e}")));
            }
        }

        if let Some(n) = s.spp {
            if !(1..=MAX_SPP).contains(&n) {
                return Err(SceneError::semantic("settings.spp", format!("must be between 1 and {MAX_SPP}, got {n}")));
            }
        }
        if let Some(t) = s.noise {
            if !(t.is_finite() && t > 0.0) {
                return Err(SceneError::semantic("settings.noise", format!("must be finite and > 0, got {t}")));
            }
        }
        if !(1..=16).contains(&s.samples) {
            return Err(SceneError::semantic(
                "settings.samples",
                format!("must be between 1 and 16, got {}", s.samples),
            ));
        }

        let mut lights = Vec::with_capacity(self.lights.len());
        for (i, l) in self.lights.iter().enumerate() {
            let place = format!("lights[{i}]");
            finite_triple(&l.position, &place, "the position")?;
            let base = l.color.unwrap_or([1.0; 3]);
            let diffuse = l.diffuse.unwrap_or(base);
            let specular = l.specular.unwrap_or(base);
            colour(&diffuse, &place, "the colour")?;
            colour(&specular, &place, "the colour")?;
            lights.push(Light {
                position: Point3::from(vec3(l.position)),
                diffuse: vec3(diffuse),
                specular: vec3(specular),
            });
        }

        let mut materials = Vec::with_capacity(self.materials.len() + 1);
        for (name, m) in &self.materials {
            let place = format!("materials{}", crate::locate::key_step(name));
            let mut textures = Textures::default();
            let mut resolve = |c: &ColourSpec, what: &str, slot: fn(&mut Textures) -> &mut Option<Texture>| {
                let (base, texture) = resolve_colour(c, &format!("{place}.{what}"), what)?;
                *slot(&mut textures) = texture;
                Ok::<_, SceneError>(base)
            };
            let ambient = resolve(&m.ambient, "ambient", |t| &mut t.ambient)?;
            let diffuse = resolve(&m.diffuse, "diffuse", |t| &mut t.diffuse)?;
            let specular = resolve(&m.specular, "specular", |t| &mut t.specular)?;
            let reflect = resolve(&m.reflect, "reflect", |t| &mut t.reflect)?;
            let transmit = resolve(&m.transmit, "transmit", |t| &mut t.transmit)?;
            let emission = resolve(&m.emission, "emission", |t| &mut t.emission)?;
            if let Some(b) = &m.bump {
                let at = format!("{place}.bump.noise");
                positive(b.noise.scale, &format!("{at}.scale"), "scale")?;
                if !(b.noise.strength.is_finite() && b.noise.strength >= 0.0) {
                    let msg = format!("strength must be finite and >= 0, got {}", b.noise.strength);
                    return Err(SceneError::semantic(&format!("{at}.strength"), msg));
                }
                octaves(b.noise.octaves, &format!("{at}.octaves"))?;
                textures.bump =
                    Some(Bump { scale: b.noise.scale, strength: b.noise.strength, octaves: b.noise.octaves });
            }
            if !(m.shininess.is_finite() && m.shininess >= 0.0) {
                let msg = format!("shininess must be finite and >= 0, got {}", m.shininess);
                return Err(SceneError::semantic(&format!("{place}.shininess"), msg));
            }
            if !(m.ior.is_finite() && m.ior > 0.0) {
                let msg = format!("ior must be finite and > 0, got {}", m.ior);
                return Err(SceneError::semantic(&format!("{place}.ior"), msg));
            }
            materials.push(Material {
                name: name.clone(),
                ambient,
                diffuse,
                specular,
                shininess: m.shininess,
                model: m.model,
                reflect,
                transmit,
                ior: m.ior,
                emission,
                textures: m.is_textured().then(|| Box::new(textures)),
            });
        }
        // Blocks without a material get a plain grey one, appended last so
        // that the named materials keep their (sorted) indices.
        let default_material = materials.len();
        materials.push(Material {
            name: "(default)".into(),
            ambient: Vector3::repeat(0.8),
            diffuse: Vector3::repeat(0.8),
            specular: Vector3::zeros(),
            shininess: 32.0,
            model: Model::Phong,
            reflect: Vector3::zeros(),
            transmit: Vector3::zeros(),
            ior: 1.0,
            emission: Vector3::zeros(),
            textures: None,
        });

        let flat = self.flattened(default_material)?;
        if flat.top.len == 0 {
            return Err(SceneError::semantic("blocks", "the scene has no blocks"));
        }
        Ok(WorldParts { camera, settings: s.clone(), lights, materials, flat })
    }
}

// A world but for its complex (`SceneFile::world_parts`).
pub(crate) struct WorldParts {
    camera: Camera,
    settings: Settings,
    lights: Vec<Light>,
    materials: Vec<Material>,
    flat: Flattened,
}

impl WorldParts {
    // Builds the complex: the last step of `SceneFile::to_world`.
    pub(crate) fn build(self) -> Result<World, SceneError> {
        let WorldParts { camera, settings, lights, materials, flat } = self;
        let Flattened { top, definitions, order } = flat;
        let options = ComplexOptions { epsilon: settings.epsilon, ..Default::default() };
        if top.is_plain() {
            // No instances: the blocks as they are, the path of every scene before definitions existed.
            let blocks = top.members.into_iter().filter_map(|m| match m {
                Member::Block(b) => Some(b),
                Member::Placed(_) => None,
            });
            let complex =
                Complex::new(blocks.collect(), options).map_err(|e| SceneError::semantic("blocks", e.to_string()))?;
            return Ok(World::new(camera, settings, lights, materials, complex, vec![top.infos], None));
        }
        // Each definition once, after those it places, keyed by its index + 1
        // (the top list is key 0), so that `Complex::resolve` names the table
        // of block infos a block's comes from.
        let mut built: Vec<Option<Arc<Complex>>> = vec![None; definitions.len()];
        let mut tables: Vec<Vec<BlockInfo>> = vec![vec![]; definitions.len() + 1];
        let mut layout = Layout { lists: vec![vec![]; definitions.len() + 1], complexes: vec![None], uniform: false };
        let mut definitions: Vec<Option<Flat>> = definitions.into_iter().map(Some).collect();
        for d in order {
            let Some(list) = definitions[d].take() else { continue };
            let key = u32::try_from(d + 1).map_err(|_| SceneError::semantic("definitions", "too many definitions"))?;
            layout.lists[d + 1] = items(&list.members);
            let complex = assemble(list.members, &built, ComplexOptions { key, ..options })?;
            built[d] = Some(Arc::new(complex));
            tables[d + 1] = list.infos;
        }
        layout.lists[0] = items(&top.members);
        let complex = assemble(top.members, &built, options)?;
        tables[0] = top.infos;
        layout.complexes.extend(built);
        Ok(World::new(camera, settings, lights, materials, complex, tables, Some(layout)))
    }
}

/// A list's entries as its layout holds them.
fn items(members: &[Member]) -> Vec<Item> {
    members
        .iter()
        .map(|m| match m {
            Member::Block(_) => Item::Block,
            Member::Placed(p) => {
                Item::Placed { key: p.definition as u32 + 1, elements: p.count.iter().map(|&n| u64::from(n)).product() }
            }
        })
        .collect()
}

/// `Complex::assemble` of a flattened list whose placed definitions are
/// `built`; a kernel error about a placement names its entry.
fn assemble(
    members: Vec<Member>,
    built: &[Option<Arc<Complex>>],
    options: ComplexOptions,
) -> Result<Complex, SceneError> {
    let mut places = Vec::with_capacity(members.len());
    let members: Vec<complex::Member> = members
        .into_iter()
        .map(|m| match m {
            Member::Block(b) => {
                places.push(None);
                complex::Member::Block(b)
            }
            Member::Placed(p) => {
                let definition = built[p.definition].clone().unwrap_or_else(|| unreachable!("built before its places"));
                places.push(Some(p.place));
                complex::Member::Placed(Placement {
                    definition,
                    transform: p.transform,
                    pitch: p.pitch,
                    count: p.count,
                })
            }
        })
        .collect();
    Complex::assemble(members, options).map_err(|e| match e {
        ComplexError::BadPlacement { index, what } => match places.get(index).cloned().flatten() {
            Some(place) => SceneError::semantic(&place, what),
            None => SceneError::semantic("blocks", what),
        },
        e => SceneError::semantic("blocks", e.to_string()),
    })
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    const CAMERA: &str = r#""camera": { "eye": [0, 0, 50], "direction": [0, 0, -1], "width": 4, "height": 3 }"#;

    #[test]
    fn lights_split_colour_into_diffuse_and_specular() {
        let text = format!(
            r#"{{ {CAMERA}, "lights": [ {{ "position": [0, 0, 0], "color": [0.5, 0.5, 0.5], "specular": [1, 0, 0] }} ],
                 "blocks": [ {{ "objects": [ {{ "sphere": {{}} }} ] }} ] }}"#
        );
        let w = SceneFile::from_json(&text).unwrap().to_world().unwrap();
        assert_eq!(w.lights[0].diffuse, Vector3::repeat(0.5));
        assert_eq!(w.lights[0].specular, Vector3::new(1.0, 0.0, 0.0));
    }

    /// A scene of nested lattices and instances in rotated groups, with a
    /// textured block in a definition.
    const INSTANCED: &str = r#"{ "camera": { "eye": [0, 0, 50], "direction": [0, 0, -1] },
      "materials": { "a": { "diffuse": { "checker": {} } }, "b": {} },
      "definitions": {
        "pin": { "blocks": [ { "name": "rod", "material": "a", "objects": [ { "sphere": { "radius": 0.3 } } ] },
                             { "objects": [ { "sphere": { "radius": 0.2, "center": [0, 0.4, 0] } } ], "material": "b" } ] },
        "row": { "blocks": [ { "group": "g", "transform": [ { "rotate_z": 20 } ], "blocks": [
                   { "lattice": "pin", "pitch": [1, 0, 0], "count": [3, 1, 1], "transform": [ { "scale": 0.8 } ] } ] },
                 { "name": "end", "objects": [ { "sphere": { "radius": 0.25, "center": [3.5, 0, 0] }, "material": "a" },
                                              { "sphere": { "radius": 0.3, "center": [3.5, 0, 0] } } ] } ] } },
      "blocks": [ { "name": "first", "objects": [ { "sphere": { "center": [-4, 0, 0] } } ] },
                  { "group": "h", "transform": [ { "rotate_y": 30 }, { "translate": [0, 1, 0] } ], "blocks": [
                    { "lattice": "row", "pitch": [0, 1.2, 0.7], "count": [1, 3, 2] } ] },
                  { "instance": "pin", "transform": [ { "scale": 2 }, { "translate": [4, -3, 0] } ] } ] }"#;

    #[test]
    fn placed_blocks_have_the_infos_and_frames_of_the_expansion() {
        let world = SceneFile::load_str(INSTANCED).unwrap();
        assert!(world.is_instanced() && world.complex.is_assembled());
        let scene = SceneFile::from_json(INSTANCED).unwrap();
        let (blocks, infos) = scene.flattened(scene.materials.len()).unwrap().expanded();
        // first, 6 rows of (3 pins of 2 blocks and an end), the big pin's 2.
        assert_eq!((world.complex.len(), blocks.len()), (1 + 6 * 7 + 2, 1 + 6 * 7 + 2));
        for (i, (block, info)) in blocks.iter().zip(&infos).enumerate() {
            let id = complex::BlockId(i as u32);
            let got = world.block_info(id);
            assert_eq!(
                (&got.path, got.material, &got.solid_materials),
                (&info.path, info.material, &info.solid_materials)
            );
            assert_eq!(world.complex.block(id).name(), block.name());
            assert!(std::ptr::eq(world.block_material(id), &world.materials()[info.material]), "block {i}");
            for j in 0..block.solids().len() {
                let m = info.solid_materials[j];
                assert!(std::ptr::eq(world.surface_material(id, j as u32), &world.materials()[m]), "block {i}");
            }
            // The frame maps a point of the placed block to the same point of the block's own frame.
            match (world.frame(id), info.frame.as_deref().copied()) {
                (None, None) => {}
                (Some(got), Some(want)) => {
                    for p in [Point3::new(0.3, -1.0, 2.0), Point3::new(-4.0, 5.0, 0.5)] {
                        assert!((got.apply_point(&p) - want.apply_point(&p)).norm() < 1e-12, "block {i}");
                    }
                }
                (got, want) => panic!("block {i}: {got:?} against {want:?}"),
            }
        }
        assert_eq!(world.written_blocks().count(), 1 + 1 + 2, "the top's own block, row's end and pin's 2");
        assert_eq!(world.sum_over_blocks(|b, _| b.solids().len() as u64), 45 + 6);
        let rods = world.select_blocks(|b, _| b.name() == "rod", 100).unwrap();
        let want: Vec<u32> = (0..blocks.len() as u32).filter(|&i| blocks[i as usize].name() == "rod").collect();
        assert_eq!(rods.iter().map(|b| b.0).collect::<Vec<_>>(), want);
        assert_eq!(world.select_blocks(|b, _| b.name() == "rod", 18), None);
        assert_eq!(world.select_blocks(|b, _| b.name() == "first", 1), Some(vec![complex::BlockId(0)]));
    }

    #[test]
    fn errors_are_located_alike_whether_the_text_is_kept_or_read_again() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("s.json");
        let blocks = r#"{ "objects": [ { "sphere": {} } ] },
                 { "objects": [ { "sphere": {} } ], "material": "nope" }"#;
        std::fs::write(&path, format!("{{ {CAMERA},\n \"blocks\": [ {blocks} ] }}")).unwrap();
        let kept = load_keeping(&path, usize::MAX).unwrap_err().to_string();
        assert!(kept.contains("blocks[1].material, line 3, column 65"), "{kept}");
        assert_eq!(load_keeping(&path, 0).unwrap_err().to_string(), kept);
        // Valid, the same world either way.
        std::fs::write(&path, format!(r#"{{ {CAMERA}, "blocks": [ {{ "objects": [ {{ "sphere": {{}} }} ] }} ] }}"#))
            .unwrap();
        let (a, b) = (load_keeping(&path, usize::MAX).unwrap().0, load_keeping(&path, 0).unwrap().0);
        let infos = |w: &World| w.written_blocks().map(|(_, info)| info.clone()).collect::<Vec<_>>();
        assert_eq!(infos(&a), infos(&b));
    }

    #[test]
    fn schema_key_is_allowed() {
        let text =
            format!(r#"{{ "$schema": "x", {CAMERA}, "blocks": [ {{ "objects": [ {{ "sphere": {{}} }} ] }} ] }}"#);
        assert!(SceneFile::from_json(&text).unwrap().to_world().is_ok());
    }
}
