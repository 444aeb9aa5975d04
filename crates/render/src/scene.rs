//! The scene file: serde types for the JSON document (the only place that
//! knows JSON) and their conversion into kernel types.
//!
//! Conversion flattens groups depth-first, so block priority is document
//! order. Transforms compose in list order (the first step acts first); a
//! block's transform acts after its objects' own, and enclosing groups'
//! transforms after that, innermost first.

use std::collections::BTreeMap;

use complex::{Block, Complex, ComplexOptions, MaterialKey, Opacity};
use quadric::nalgebra::{Matrix4, Point3, Vector3};
use quadric::{HalfSpace, Quadric, Solid, Transform};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::camera::Camera;
use crate::error::SceneError;

/// A colour or vector triple.
pub type Triple = [f64; 3];

/// The whole scene document.
///
/// ```
/// use render::scene::SceneFile;
/// let text = r#"{ "camera": { "eye": [0, 0, 4], "direction": [0, 0, -1] },
///                 "blocks": [ { "name": "ball", "objects": [ { "sphere": {} } ] } ] }"#;
/// let world = SceneFile::load_str(text).unwrap();
/// assert_eq!(world.complex.blocks()[0].name(), "ball");
///
/// let typo = text.replace("\"sphere\"", "\"spehre\"");
/// let err = SceneFile::load_str(&typo).unwrap_err().to_string();
/// assert!(err.contains("blocks[0].objects[0].spehre") && err.contains("did you mean `sphere`?"), "{err}");
/// ```
#[derive(Clone, Debug, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
// The doc comment's example must not end up in the JSON Schema.
#[schemars(description = "The whole scene document.")]
pub struct SceneFile {
    /// Optional URL or path of the JSON Schema, for editors. Ignored.
    #[serde(rename = "$schema", default, skip_serializing_if = "Option::is_none")]
    pub schema: Option<String>,
    /// The camera (SPEC §4).
    pub camera: CameraSpec,
    /// Global rendering settings.
    #[serde(default)]
    pub settings: Settings,
    /// Point lights.
    #[serde(default)]
    pub lights: Vec<LightSpec>,
    /// Named materials, referenced by blocks and objects.
    #[serde(default)]
    pub materials: BTreeMap<String, MaterialSpec>,
    /// Blocks and groups in priority order (earlier blocks win where
    /// transparent blocks overlap).
    pub blocks: Vec<Entry>,
}

/// The pinhole camera of SPEC §4.
#[derive(Clone, Debug, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct CameraSpec {
    /// The eye point `E`.
    pub eye: Triple,
    /// The viewing direction `D` (need not be unit length).
    pub direction: Triple,
    /// The up vector `U`; only its part orthogonal to `direction` counts.
    #[serde(default = "default_up")]
    pub up: Triple,
    /// Image width in pixels.
    #[serde(default = "default_width")]
    pub width: u32,
    /// Image height in pixels.
    #[serde(default = "default_height")]
    pub height: u32,
    /// Opening angle in degrees, measured on the image diagonal.
    #[serde(default = "default_aperture")]
    pub aperture: f64,
}

fn default_up() -> Triple {
    [0.0, 1.0, 0.0]
}
fn default_width() -> u32 {
    640
}
fn default_height() -> u32 {
    480
}
fn default_aperture() -> f64 {
    50.0
}

/// Global settings.
#[derive(Clone, Debug, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Settings {
    /// The scene's ambient light `Sa`, multiplied by each material's `ambient`.
    #[serde(default = "default_ambient")]
    pub ambient: Triple,
    /// Colour of rays that hit nothing.
    #[serde(default)]
    pub background: Triple,
    /// Maximum number of reflection/refraction bounces after the primary ray.
    #[serde(default = "default_max_depth")]
    pub max_depth: u32,
    /// Fault tolerance ε (a distance): intervals inside `[0, ε]` are no hit.
    /// Default: chosen by the kernel relative to the scene's size.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub epsilon: Option<f64>,
    /// Whether lights cast shadows.
    #[serde(default = "default_true")]
    pub shadows: bool,
    /// Anti-aliasing: `n` gives an `n × n` grid of rays per pixel whose
    /// colours are averaged (default 1: one ray through the pixel centre).
    #[serde(default = "default_samples")]
    pub samples: u32,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            ambient: default_ambient(),
            background: [0.0; 3],
            max_depth: default_max_depth(),
            epsilon: None,
            shadows: true,
            samples: default_samples(),
        }
    }
}

fn default_ambient() -> Triple {
    [0.1, 0.1, 0.1]
}
fn default_max_depth() -> u32 {
    5
}
fn default_samples() -> u32 {
    1
}
fn default_true() -> bool {
    true
}

/// A point light.
#[derive(Clone, Debug, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct LightSpec {
    /// Where the light is.
    pub position: Triple,
    /// Sets both the diffuse and the specular colour (default white).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub color: Option<Triple>,
    /// Diffuse colour `Ld`; overrides `color`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub diffuse: Option<Triple>,
    /// Specular colour `Ls`; overrides `color`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub specular: Option<Triple>,
}

/// The specular model of a material.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, Serialize, JsonSchema)]
#[serde(rename_all = "kebab-case")]
pub enum Model {
    /// `max(0, r·v)^p`, `r` the reflected light direction.
    #[default]
    Phong,
    /// `max(0, n·h)^p`, `h` the halfway vector.
    BlinnPhong,
}

/// A surface material (SPEC §5).
#[derive(Clone, Debug, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct MaterialSpec {
    /// Ambient reflectance `Ma`.
    #[serde(default)]
    pub ambient: Triple,
    /// Diffuse reflectance `Md`.
    #[serde(default)]
    pub diffuse: Triple,
    /// Specular reflectance `Ms`.
    #[serde(default)]
    pub specular: Triple,
    /// Specular exponent `p`.
    #[serde(default = "default_shininess")]
    pub shininess: f64,
    /// `phong` or `blinn-phong`.
    #[serde(default)]
    pub model: Model,
    /// Mirror reflection weight `kr`.
    #[serde(default)]
    pub reflect: Triple,
    /// Transmission weight `kt` (used on transparent blocks).
    #[serde(default)]
    pub transmit: Triple,
    /// Index of refraction of the medium (transparent blocks).
    #[serde(default = "default_ior")]
    pub ior: f64,
}

fn default_shininess() -> f64 {
    32.0
}
fn default_ior() -> f64 {
    1.0
}

/// One step of a transform list.
#[derive(Clone, Debug, Deserialize, Serialize, JsonSchema)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum Step {
    /// Translation by `[x, y, z]`.
    Translate(Triple),
    /// Uniform (`s`) or per-axis (`[sx, sy, sz]`) scaling.
    Scale(Scale),
    /// Rotation about x in degrees (y towards z).
    RotateX(f64),
    /// Rotation about y in degrees (z towards x).
    RotateY(f64),
    /// Rotation about z in degrees (x towards y).
    RotateZ(f64),
    /// A general affine 4x4 matrix, row-major, last row `[0, 0, 0, 1]`.
    // Boxed: inline, it would make every step 136 bytes instead of 32.
    Matrix(Box<[[f64; 4]; 4]>),
}

/// A scale factor: one number or one per axis.
#[derive(Clone, Debug, Serialize, JsonSchema)]
#[serde(untagged)]
pub enum Scale {
    /// The same factor on every axis.
    Uniform(f64),
    /// One factor per axis.
    PerAxis(Triple),
}

// Read by a visitor of its own rather than serde's `untagged` (which the
// schema and the serialisation still follow): that buffered every value and
// built, formatted and dropped an error for each array it tried as a number
// first (33,000 per-axis scales in the 100,000-block grid: 1.2 % of its
// load's instructions). Errors name what `scale` takes.
impl<'de> Deserialize<'de> for Scale {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct Factors;
        impl<'de> serde::de::Visitor<'de> for Factors {
            type Value = Scale;

            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a number or an array [sx, sy, sz]")
            }

            fn visit_f64<E: serde::de::Error>(self, v: f64) -> Result<Scale, E> {
                Ok(Scale::Uniform(v))
            }

            // JSON integers arrive as these; converted as serde's `f64` does.
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<Scale, E> {
                Ok(Scale::Uniform(v as f64))
            }

            fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<Scale, E> {
                Ok(Scale::Uniform(v as f64))
            }

            fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut seq: A) -> Result<Scale, A::Error> {
                let mut v = [0.0; 3];
                for (i, x) in v.iter_mut().enumerate() {
                    *x = seq.next_element()?.ok_or_else(|| serde::de::Error::invalid_length(i, &self))?;
                }
                let mut more = 0;
                while seq.next_element::<serde::de::IgnoredAny>()?.is_some() {
                    more += 1;
                }
                if more > 0 {
                    return Err(serde::de::Error::invalid_length(3 + more, &self));
                }
                Ok(Scale::PerAxis(v))
            }
        }
        deserializer.deserialize_any(Factors)
    }
}

/// An entry of a `blocks` list: a block (with `objects`) or a group (with
/// `group` and nested `blocks`).
#[derive(Clone, Debug, Default, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Entry {
    /// The block's name (blocks only; default `block N`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// The block's material name (blocks only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub material: Option<String>,
    /// Whether the block is transparent (blocks only; default false).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub transparent: Option<bool>,
    /// The solids whose intersection is the block (blocks only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub objects: Option<Vec<ObjectSpec>>,
    /// The group's name (groups only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub group: Option<String>,
    /// Nested blocks and groups (groups only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub blocks: Option<Vec<Entry>>,
    /// Steps applied after the objects' own transforms (blocks) or after
    /// everything inside (groups).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub transform: Vec<Step>,
}

/// Options of a sphere; `{}` is the unit ball.
#[derive(Clone, Debug, Default, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SphereSpec {
    /// Radius (default 1), applied before `transform`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radius: Option<f64>,
    /// Centre (default origin), applied before `transform`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub center: Option<Triple>,
}

/// The axis of a cylinder.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, Serialize, JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum Axis {
    /// Along x.
    X,
    /// Along y.
    #[default]
    Y,
    /// Along z.
    Z,
}

/// Options of a cylinder; `{}` is the infinite unit tube along y.
#[derive(Clone, Debug, Default, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct CylinderSpec {
    /// Radius (default 1), applied before `transform`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radius: Option<f64>,
    /// Axis (default `y`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub axis: Option<Axis>,
}

/// Options of shapes without parameters (`{}`).
#[derive(Clone, Debug, Default, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Empty {}

/// Options of a hyperboloid.
#[derive(Clone, Debug, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct HyperboloidSpec {
    /// 1: `x² − y² + z² ≤ 1` (waisted tube); 2: `x² − y² + z² ≤ −1` (two bowls).
    pub sheets: u8,
}

/// One solid of a block: exactly one shape key plus options.
#[derive(Clone, Debug, Default, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
// Scenes hold hundreds of thousands of these, so the larger, rarer shape
// options are boxed: 120 bytes instead of 256 (the JSON is the same).
pub struct ObjectSpec {
    /// The unit sphere `x² + y² + z² ≤ 1`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sphere: Option<Box<SphereSpec>>,
    /// The infinite unit tube along y, `x² + z² ≤ 1`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cylinder: Option<Box<CylinderSpec>>,
    /// The double cone `x² − y² + z² ≤ 0`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cone: Option<Empty>,
    /// The paraboloid `x² + z² − y ≤ 0`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub paraboloid: Option<Empty>,
    /// A hyperboloid of one or two sheets around y.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hyperboloid: Option<HyperboloidSpec>,
    /// Raw coefficients `[a, b, c, d, e, f, g, h, j, k]` of
    /// `a x² + b y² + c z² + 2d xy + 2e xz + 2f yz + 2g x + 2h y + 2j z + k ≤ 0`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub quadric: Option<Box<[f64; 10]>>,
    /// The half-space `a x + b y + c z + d ≤ 0`, given as `[a, b, c, d]`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub halfspace: Option<[f64; 4]>,
    /// Steps placing the solid, applied in list order.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub transform: Vec<Step>,
    /// Whether to take the outside of the solid instead.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub complement: bool,
    /// Material of this surface (default: the block's).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub material: Option<String>,
}

/// A resolved material.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// The name in the scene file.
    pub name: String,
    /// Ambient reflectance.
    pub ambient: Vector3<f64>,
    /// Diffuse reflectance.
    pub diffuse: Vector3<f64>,
    /// Specular reflectance.
    pub specular: Vector3<f64>,
    /// Specular exponent.
    pub shininess: f64,
    /// Specular model.
    pub model: Model,
    /// Reflection weight.
    pub reflect: Vector3<f64>,
    /// Transmission weight.
    pub transmit: Vector3<f64>,
    /// Index of refraction.
    pub ior: f64,
}

/// A resolved point light.
#[derive(Clone, Debug, PartialEq)]
pub struct Light {
    /// Position.
    pub position: Point3<f64>,
    /// Diffuse colour.
    pub diffuse: Vector3<f64>,
    /// Specular colour.
    pub specular: Vector3<f64>,
}

/// Per-block data the kernel does not keep: the material of each solid.
#[derive(Clone, Debug, PartialEq)]
pub struct BlockInfo {
    /// The material index of the block.
    pub material: usize,
    /// The material index of each solid's surface.
    pub solid_materials: Vec<usize>,
    /// Where the block is in the file (e.g. `blocks[2].blocks[0]`).
    pub path: String,
}

/// A scene ready to render.
#[derive(Clone, Debug)]
pub struct World {
    /// The camera.
    pub camera: Camera,
    /// Settings from the file.
    pub settings: Settings,
    /// The lights.
    pub lights: Vec<Light>,
    /// Materials; indices are `MaterialKey`s.
    materials: Vec<Material>,
    /// The blocks.
    pub complex: Complex,
    /// Per block, parallel to `complex.blocks()`.
    blocks: Vec<BlockInfo>,
    /// Per block, the material index of all its surfaces, or `u32::MAX`
    /// when its solids' materials differ (then `blocks` answers): four
    /// bytes per block, where a `BlockInfo` is 56 and its solid list a heap
    /// buffer of its own, so a shaded hit of a large scene reads one likely
    /// cached word. Built with the world (`materials` and `blocks` are
    /// read-only, so it stays true), not per frame: at 100,000 blocks a
    /// per-frame build read 7 MB of block data the render itself never
    /// needs.
    surface_materials: Vec<u32>,
}

impl World {
    /// A world of these parts; `blocks` parallel to `complex.blocks()`,
    /// their material indices into `materials`.
    fn new(
        camera: Camera,
        settings: Settings,
        lights: Vec<Light>,
        materials: Vec<Material>,
        complex: Complex,
        blocks: Vec<BlockInfo>,
    ) -> Self {
        let uniform = |info: &BlockInfo| {
            let same = info.solid_materials.iter().all(|&m| m == info.material);
            u32::try_from(info.material).ok().filter(|&m| same && m != u32::MAX).unwrap_or(u32::MAX)
        };
        let surface_materials = blocks.iter().map(uniform).collect();
        World { camera, settings, lights, materials, complex, blocks, surface_materials }
    }

    /// The materials; indices are `MaterialKey`s (the last one is the
    /// default of blocks that name none).
    pub fn materials(&self) -> &[Material] {
        &self.materials
    }

    /// Per block, parallel to `complex.blocks()`: its materials and place
    /// in the file.
    pub fn blocks(&self) -> &[BlockInfo] {
        &self.blocks
    }

    /// The material of solid `solid` of block `block`.
    pub fn surface_material(&self, block: complex::BlockId, solid: u32) -> &Material {
        if let Some(&m) = self.surface_materials.get(block.index()) {
            if m != u32::MAX {
                return &self.materials[m as usize];
            }
        }
        let info = &self.blocks[block.index()];
        let m = info.solid_materials.get(solid as usize).copied().unwrap_or(info.material);
        &self.materials[m]
    }

    /// The material of a block (its medium, for transparent blocks).
    pub fn block_material(&self, block: complex::BlockId) -> &Material {
        &self.materials[self.blocks[block.index()].material]
    }
}

/// The deepest nesting of groups. JSON files cannot get near it (serde_json
/// stops at 128 levels of brackets, about 60 groups) but a `SceneFile` built
/// in code could, and flattening recurses once per level.
pub const MAX_GROUP_DEPTH: usize = 100;

/// The largest `settings.max_depth`: shading recurses once per bounce, so an
/// unbounded depth could overflow a worker thread's stack.
pub const MAX_BOUNCES: u32 = 64;

fn vec3(t: Triple) -> Vector3<f64> {
    Vector3::new(t[0], t[1], t[2])
}

fn finite_triple(t: &Triple, place: impl std::fmt::Display, what: &str) -> Result<(), SceneError> {
    if t.iter().all(|c| c.is_finite()) {
        Ok(())
    } else {
        Err(SceneError::semantic(&place.to_string(), format!("{what} must be finite")))
    }
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

/// Composes a list of steps, the first acting first.
pub fn transform_of(steps: &[Step], place: &str) -> Result<Transform, SceneError> {
    steps_transform(steps, Place::Text(place))
}

/// [`transform_of`] with a lazy place: the path is only written out for an error.
fn steps_transform(steps: &[Step], place: Place<'_>) -> Result<Transform, SceneError> {
    let mut m = Transform::identity();
    for (i, step) in steps.iter().enumerate() {
        let t = match step {
            Step::Translate(v) => Transform::translate(vec3(*v)),
            Step::Scale(Scale::Uniform(s)) => Transform::scale(*s),
            Step::Scale(Scale::PerAxis(v)) => Transform::scale_xyz(vec3(*v)),
            Step::RotateX(d) => Transform::rotate_x_degrees(*d),
            Step::RotateY(d) => Transform::rotate_y_degrees(*d),
            Step::RotateZ(d) => Transform::rotate_z_degrees(*d),
            Step::Matrix(rows) => Transform::from_matrix(&Matrix4::from_fn(|r, c| rows[r][c])),
        }
        .map_err(|e| SceneError::semantic(&place.item("transform", i).to_string(), e.to_string()))?;
        m = m.then(&t);
    }
    Ok(m)
}

/// A JSON path (`blocks[2].objects[0].transform[1]`) not yet written out:
/// flattening a large scene names a place for every block, object and step,
/// and only an error needs the text.
#[derive(Clone, Copy)]
enum Place<'a> {
    /// A path already written out.
    Text(&'a str),
    /// `{parent}.{key}`.
    Key(&'a Place<'a>, &'static str),
    /// `{parent}.{key}[{index}]`.
    Item(&'a Place<'a>, &'static str, usize),
}

impl<'a> Place<'a> {
    fn key(&'a self, key: &'static str) -> Place<'a> {
        Place::Key(self, key)
    }

    fn item(&'a self, key: &'static str, index: usize) -> Place<'a> {
        Place::Item(self, key, index)
    }
}

impl std::fmt::Display for Place<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Place::Text(s) => f.write_str(s),
            Place::Key(parent, key) => write!(f, "{parent}.{key}"),
            Place::Item(parent, key, index) => write!(f, "{parent}.{key}[{index}]"),
        }
    }
}

impl SceneFile {
    /// Parses a scene from JSON text. Errors carry the JSON path and the
    /// line and column.
    pub fn from_json(text: &str) -> Result<Self, SceneError> {
        // Tracking the path costs about a third of the parse, and only an
        // error needs it: a failed parse is run again with the tracker, which
        // stops at the same place with the same error.
        if let Ok(scene) = SceneFile::deserialize(&mut serde_json::Deserializer::from_str(text)) {
            return Ok(scene);
        }
        let de = &mut serde_json::Deserializer::from_str(text);
        let scene: SceneFile = serde_path_to_error::deserialize(de).map_err(SceneError::from_json)?;
        Ok(scene)
    }

    /// Parses and converts a scene; every error carries its place with a
    /// line and column.
    pub fn load_str(text: &str) -> Result<World, SceneError> {
        // The parsed document is dropped before the complex is built, so
        // that the build's allocations can take the memory it frees instead
        // of fresh pages (a 100,000-block scene's parsed entries are about
        // a fifth of the load's memory).
        let scene = Self::from_json(text)?;
        let parts = scene.world_parts().map_err(|e| e.located(text))?;
        drop(scene);
        parts.build().map_err(|e| e.located(text))
    }

    /// Resolves names, composes transforms and builds the complex.
    pub fn to_world(&self) -> Result<World, SceneError> {
        self.world_parts()?.build()
    }

    // Everything of `to_world` but the complex: checks the camera, settings,
    // lights and materials and flattens the blocks.
    fn world_parts(&self) -> Result<WorldParts, SceneError> {
        let c = &self.camera;
        finite_triple(&c.eye, "camera.eye", "the eye")?;
        finite_triple(&c.direction, "camera.direction", "the direction")?;
        finite_triple(&c.up, "camera.up", "the up vector")?;
        let camera =
            Camera::new(Point3::from(vec3(c.eye)), vec3(c.direction), vec3(c.up), c.width, c.height, c.aperture)
                .map_err(|e| SceneError::semantic("camera", e.to_string()))?;

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
            for (t, what) in [
                (&m.ambient, "ambient"),
                (&m.diffuse, "diffuse"),
                (&m.specular, "specular"),
                (&m.reflect, "reflect"),
                (&m.transmit, "transmit"),
            ] {
                colour(t, &format!("{place}.{what}"), what)?;
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
                ambient: vec3(m.ambient),
                diffuse: vec3(m.diffuse),
                specular: vec3(m.specular),
                shininess: m.shininess,
                model: m.model,
                reflect: vec3(m.reflect),
                transmit: vec3(m.transmit),
                ior: m.ior,
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
        });

        let (blocks, infos) = self.flattened(default_material)?;
        if blocks.is_empty() {
            return Err(SceneError::semantic("blocks", "the scene has no blocks"));
        }
        Ok(WorldParts { camera, settings: s.clone(), lights, materials, blocks, infos })
    }

    /// The blocks and their infos, groups flattened depth-first.
    ///
    /// A long `blocks` list is cut into runs flattened in parallel, each
    /// knowing how many blocks come before it (for the default names
    /// `block N`); the runs are joined in order and the first error in
    /// document order is returned, so the result is the sequential one.
    fn flattened(&self, default_material: usize) -> Result<(Vec<Block>, Vec<BlockInfo>), SceneError> {
        use rayon::prelude::*;
        /// Top-level entries per run (a run takes about a millisecond).
        const RUN: usize = 1024;
        let flattener =
            |before| Flattener { materials: &self.materials, default_material, before, blocks: vec![], infos: vec![] };
        if self.blocks.len() < 2 * RUN {
            let mut flat = flattener(0);
            flat.entries(&self.blocks, 0, "blocks", &[])?;
            return Ok((flat.blocks, flat.infos));
        }
        let mut before = 0;
        let runs: Vec<(usize, &[Entry], usize)> = self
            .blocks
            .chunks(RUN)
            .enumerate()
            .map(|(r, run)| {
                let first = before;
                before += run.iter().map(|e| block_count(e, 0)).sum::<usize>();
                (r * RUN, run, first)
            })
            .collect();
        let runs: Vec<Result<Flattener<'_>, SceneError>> = runs
            .into_par_iter()
            .map(|(first, run, before)| {
                let mut flat = flattener(before);
                flat.entries(run, first, "blocks", &[]).map(|()| flat)
            })
            .collect();
        let (mut blocks, mut infos) = (Vec::with_capacity(before), Vec::with_capacity(before));
        for run in runs {
            let run = run?;
            blocks.extend(run.blocks);
            infos.extend(run.infos);
        }
        Ok((blocks, infos))
    }
}

// A world but for its complex (`SceneFile::world_parts`).
struct WorldParts {
    camera: Camera,
    settings: Settings,
    lights: Vec<Light>,
    materials: Vec<Material>,
    blocks: Vec<Block>,
    infos: Vec<BlockInfo>,
}

impl WorldParts {
    // Builds the complex: the last step of `SceneFile::to_world`.
    fn build(self) -> Result<World, SceneError> {
        let WorldParts { camera, settings, lights, materials, blocks, infos } = self;
        let complex = Complex::new(blocks, ComplexOptions { epsilon: settings.epsilon })
            .map_err(|e| SceneError::semantic("blocks", e.to_string()))?;
        Ok(World::new(camera, settings, lights, materials, complex, infos))
    }
}

/// How many blocks flattening `e` yields if it is valid (an invalid entry
/// stops flattening, so what it counts does not matter).
fn block_count(e: &Entry, depth: usize) -> usize {
    match (&e.objects, &e.blocks) {
        (Some(_), None) => 1,
        (None, Some(children)) if depth < MAX_GROUP_DEPTH => children.iter().map(|c| block_count(c, depth + 1)).sum(),
        _ => 0,
    }
}

struct Flattener<'a> {
    materials: &'a BTreeMap<String, MaterialSpec>,
    default_material: usize,
    /// Blocks that come before this flattener's first (in other runs).
    before: usize,
    blocks: Vec<Block>,
    infos: Vec<BlockInfo>,
}

impl Flattener<'_> {
    /// The index of material `name`; `place` and `owner` (`block "x"`) name
    /// the reference in the error.
    fn material(&self, name: &str, place: Place<'_>, owner: &dyn std::fmt::Display) -> Result<usize, SceneError> {
        self.materials.keys().position(|k| k == name).ok_or_else(|| {
            let hint = crate::error::nearest(name, self.materials.keys().map(String::as_str))
                .map(|n| format!(" (did you mean \"{n}\"?)"))
                .unwrap_or_default();
            SceneError::semantic(&place.to_string(), format!("{owner}: unknown material \"{name}\"{hint}"))
        })
    }

    /// `entries` are those at `place[first..]`; `outer`: the enclosing
    /// groups' transforms, innermost first.
    fn entries(&mut self, entries: &[Entry], first: usize, place: &str, outer: &[Transform]) -> Result<(), SceneError> {
        if outer.len() > MAX_GROUP_DEPTH {
            return Err(SceneError::semantic(place, format!("groups nest deeper than {MAX_GROUP_DEPTH} levels")));
        }
        for (i, e) in (first..).zip(entries) {
            // Every block keeps its path (`BlockInfo::path`), so it is written out here, once.
            let here = format!("{place}[{i}]");
            let own = steps_transform(&e.transform, Place::Text(&here))?;
            match (&e.objects, &e.blocks) {
                (Some(_), Some(_)) => {
                    return Err(SceneError::semantic(
                        &here,
                        "an entry has either `objects` (a block) or `blocks` (a group), not both",
                    ))
                }
                (None, Some(children)) => {
                    if e.name.is_some() || e.material.is_some() || e.transparent.is_some() {
                        let name = e.group.as_deref().unwrap_or("?");
                        return Err(SceneError::semantic(
                            &here,
                            format!(
                                "group \"{name}\": `name`, `material` and `transparent` belong on blocks, not groups"
                            ),
                        ));
                    }
                    let mut stack = vec![own];
                    stack.extend_from_slice(outer);
                    self.entries(children, 0, &format!("{here}.blocks"), &stack)?;
                }
                (Some(objects), None) => {
                    if let Some(g) = &e.group {
                        return Err(SceneError::semantic(
                            &here,
                            format!("group \"{g}\" has `objects`; a group holds `blocks`"),
                        ));
                    }
                    self.block(e, objects, here, own, outer)?;
                }
                (None, None) => {
                    let what = match (&e.group, &e.name) {
                        (Some(g), _) => format!("group \"{g}\" has no `blocks`"),
                        (None, Some(n)) => format!("block \"{n}\" has no `objects`"),
                        (None, None) => "an entry needs `objects` (a block) or `group` and `blocks` (a group)".into(),
                    };
                    return Err(SceneError::semantic(&here, what));
                }
            }
        }
        Ok(())
    }

    /// `here`: the block's path, kept in its [`BlockInfo`].
    fn block(
        &mut self,
        e: &Entry,
        objects: &[ObjectSpec],
        here: String,
        own: Transform,
        outer: &[Transform],
    ) -> Result<(), SceneError> {
        let name = e.name.clone().unwrap_or_else(|| format!("block {}", self.before + self.blocks.len() + 1));
        // The owner and object names of error messages, written out only for an error.
        let owner = Owner { block: &name, object: None };
        let who = |j: usize| Owner { block: &name, object: Some(j + 1) };
        if objects.is_empty() {
            return Err(SceneError::semantic(&here, format!("{owner} is empty: a block needs at least one object")));
        }
        let place = Place::Text(&here);
        let material = match &e.material {
            Some(m) => self.material(m, place.key("material"), &owner)?,
            None => self.default_material,
        };
        let placement = outer.iter().fold(own, |m, g| m.then(g));
        let mut solids = Vec::with_capacity(objects.len());
        let mut solid_materials = Vec::with_capacity(objects.len());
        for (j, o) in objects.iter().enumerate() {
            let at = place.item("objects", j);
            let solid = solid_of(o, at).map_err(|err| err.with_owner(&who(j).to_string()))?;
            let m = steps_transform(&o.transform, at).map_err(|err| err.with_owner(&who(j).to_string()))?;
            let solid = solid.transformed(&m.then(&placement));
            let finite = match &solid {
                Solid::Quadric(q) => q.is_finite(),
                Solid::HalfSpace(h) => h.is_finite(),
            };
            if !finite {
                let msg = "the transforms (the object's, the block's and its groups') overflow: \
                           the placed solid has coefficients that are not finite";
                return Err(SceneError::semantic(&at.to_string(), format!("{}: {msg}", who(j))));
            }
            solids.push(if o.complement { solid.complement() } else { solid });
            solid_materials.push(match &o.material {
                Some(mat) => self.material(mat, at.key("material"), &who(j))?,
                None => material,
            });
        }
        let opacity = if e.transparent.unwrap_or(false) { Opacity::Transparent } else { Opacity::Opaque };
        let block = Block::new(name, solids, opacity, MaterialKey(material as u32))
            .map_err(|err| SceneError::semantic(&here, err.to_string()))?;
        self.blocks.push(block);
        self.infos.push(BlockInfo { material, solid_materials, path: here });
        Ok(())
    }
}

/// `block "x"` or `block "x", object 2` (1-based), as error messages name them.
struct Owner<'a> {
    block: &'a str,
    object: Option<usize>,
}

impl std::fmt::Display for Owner<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "block \"{}\"", self.block)?;
        match self.object {
            Some(j) => write!(f, ", object {j}"),
            None => Ok(()),
        }
    }
}

/// The solid an object describes, before its transform.
fn solid_of(o: &ObjectSpec, place: Place<'_>) -> Result<Solid, SceneError> {
    let keys = [
        (o.sphere.is_some(), "sphere"),
        (o.cylinder.is_some(), "cylinder"),
        (o.cone.is_some(), "cone"),
        (o.paraboloid.is_some(), "paraboloid"),
        (o.hyperboloid.is_some(), "hyperboloid"),
        (o.quadric.is_some(), "quadric"),
        (o.halfspace.is_some(), "halfspace"),
    ];
    if keys.iter().filter(|(set, _)| *set).count() != 1 {
        let keys: Vec<&str> = keys.into_iter().filter_map(|(set, k)| set.then_some(k)).collect();
        let msg = if keys.is_empty() {
            "an object needs exactly one shape key (sphere, cylinder, cone, paraboloid, hyperboloid, quadric, halfspace)"
                .to_string()
        } else {
            format!("an object has exactly one shape key, found {}", keys.join(", "))
        };
        return Err(SceneError::semantic(&place.to_string(), msg));
    }
    let err = |message: String| SceneError::semantic(&place.to_string(), message);
    let geo = |e: quadric::GeometryError| err(e.to_string());
    let positive = |r: Option<f64>, what: &str| -> Result<f64, SceneError> {
        match r {
            None => Ok(1.0),
            Some(r) if r.is_finite() && r > 0.0 => Ok(r),
            Some(r) => Err(err(format!("{what} must be finite and > 0, got {r}"))),
        }
    };
    Ok(if let Some(s) = &o.sphere {
        let r = positive(s.radius, "sphere.radius")?;
        let c = s.center.unwrap_or([0.0; 3]);
        finite_triple(&c, place, "sphere.center")?;
        let m = Transform::scale(r).map_err(geo)?.then(&Transform::translate(vec3(c)).map_err(geo)?);
        Solid::from(Quadric::sphere().transformed(&m))
    } else if let Some(c) = &o.cylinder {
        let r = positive(c.radius, "cylinder.radius")?;
        let tube = match c.axis.unwrap_or_default() {
            Axis::X => Quadric::tube_x(),
            Axis::Y => Quadric::tube_y(),
            Axis::Z => Quadric::tube_z(),
        };
        Solid::from(tube.transformed(&Transform::scale(r).map_err(geo)?))
    } else if o.cone.is_some() {
        Solid::from(Quadric::cone())
    } else if o.paraboloid.is_some() {
        Solid::from(Quadric::paraboloid())
    } else if let Some(h) = &o.hyperboloid {
        match h.sheets {
            1 => Solid::from(Quadric::hyperboloid_one_sheet()),
            2 => Solid::from(Quadric::hyperboloid_two_sheets()),
            n => return Err(err(format!("hyperboloid.sheets must be 1 or 2, got {n}"))),
        }
    } else if let Some(q) = &o.quadric {
        Solid::from(Quadric::from_coefficients(**q).map_err(geo)?)
    } else if let Some([a, b, c, d]) = o.halfspace {
        Solid::from(HalfSpace::new(a, b, c, d).map_err(geo)?)
    } else {
        unreachable!("exactly one shape key was checked above")
    })
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    const CAMERA: &str = r#""camera": { "eye": [0, 0, 50], "direction": [0, 0, -1], "width": 4, "height": 3 }"#;

    fn world(blocks: &str) -> World {
        let text = format!(r#"{{ {CAMERA}, "materials": {{ "a": {{}}, "b": {{}} }}, "blocks": [ {blocks} ] }}"#);
        SceneFile::from_json(&text).unwrap().to_world().unwrap()
    }

    #[test]
    fn scale_reads_a_number_or_three_and_refuses_the_rest() {
        let read = |json: &str| serde_json::from_str::<Scale>(json).map_err(|e| e.to_string());
        assert!(matches!(read("2"), Ok(Scale::Uniform(s)) if s == 2.0));
        assert!(matches!(read("-0.5"), Ok(Scale::Uniform(s)) if s == -0.5));
        assert!(matches!(read("18446744073709551615"), Ok(Scale::Uniform(s)) if s == u64::MAX as f64));
        assert!(matches!(read("[1, 2.5, -3]"), Ok(Scale::PerAxis(v)) if v == [1.0, 2.5, -3.0]));
        for (json, want) in [
            ("[]", "invalid length 0, expected a number or an array [sx, sy, sz]"),
            ("[1, 2]", "invalid length 2, expected a number or an array [sx, sy, sz]"),
            ("[1, 2, 3, 4]", "invalid length 4, expected a number or an array [sx, sy, sz]"),
            ("[1, 2, 3, 4, [5], {}]", "invalid length 6, expected a number or an array [sx, sy, sz]"),
            ("\"x\"", "invalid type: string \"x\", expected a number or an array [sx, sy, sz]"),
            ("{}", "invalid type: map, expected a number or an array [sx, sy, sz]"),
            ("[1, true, 3]", "invalid type: boolean `true`, expected f64"),
        ] {
            let got = read(json).err().unwrap_or_default();
            assert!(got.starts_with(want), "{json}: {got}");
        }
        // Written back as it is read.
        for json in ["2.0", "[1.0,2.5,-3.0]"] {
            assert_eq!(serde_json::to_string(&read(json).unwrap()).unwrap(), json);
        }
    }

    /// The first block of `blocks` contains exactly the points `inside` and none of `outside`.
    fn check(blocks: &str, inside: &[[f64; 3]], outside: &[[f64; 3]]) {
        let w = world(blocks);
        let b = &w.complex.blocks()[0];
        for p in inside {
            assert!(b.contains_point(&Point3::from(*p)), "{p:?} should be inside {blocks}");
        }
        for p in outside {
            assert!(!b.contains_point(&Point3::from(*p)), "{p:?} should be outside {blocks}");
        }
    }

    #[test]
    fn transform_steps_apply_in_list_order() {
        // Scale first, then translate: radius 0.5 around (0, 1.5, 0).
        let b =
            r#"{ "objects": [ { "sphere": {}, "transform": [ { "scale": 0.5 }, { "translate": [0, 1.5, 0] } ] } ] }"#;
        check(b, &[[0.0, 1.9, 0.0], [0.0, 1.1, 0.0]], &[[0.0, 0.9, 0.0], [0.0, 2.1, 0.0]]);
        // Translate first, then scale: radius 0.5 around (0, 0.75, 0).
        let b =
            r#"{ "objects": [ { "sphere": {}, "transform": [ { "translate": [0, 1.5, 0] }, { "scale": 0.5 } ] } ] }"#;
        check(b, &[[0.0, 1.2, 0.0], [0.0, 0.3, 0.0]], &[[0.0, 1.3, 0.0], [0.0, 0.2, 0.0]]);
        // Rotate an ellipsoid stretched along x by 90° about z: it now stretches along y.
        let b =
            r#"{ "objects": [ { "sphere": {}, "transform": [ { "scale": [2, 0.5, 0.5] }, { "rotate_z": 90 } ] } ] }"#;
        check(b, &[[0.0, 1.9, 0.0]], &[[1.9, 0.0, 0.0]]);
        // A general matrix (row-major, x' = M x): translation in the last column.
        let b = r#"{ "objects": [ { "sphere": {}, "transform": [ { "matrix": [[1,0,0,5],[0,1,0,0],[0,0,1,0],[0,0,0,1]] } ] } ] }"#;
        check(b, &[[5.9, 0.0, 0.0]], &[[0.5, 0.0, 0.0]]);
    }

    #[test]
    fn block_transform_follows_object_transform_and_groups_follow_blocks() {
        // Object: scale 0.5 about the origin; block: translate by 2 along x;
        // inner group: scale 2 (doubles both radius and offset); outer group: translate y by 10.
        let b = r#"{ "group": "outer", "transform": [ { "translate": [0, 10, 0] } ], "blocks": [
                     { "group": "inner", "transform": [ { "scale": 2 } ], "blocks": [
                       { "name": "x", "transform": [ { "translate": [2, 0, 0] } ],
                         "objects": [ { "sphere": {}, "transform": [ { "scale": 0.5 } ] } ] } ] } ] }"#;
        check(
            b,
            &[[4.0, 10.0, 0.0], [4.9, 10.0, 0.0], [3.1, 10.0, 0.0]],
            &[[5.1, 10.0, 0.0], [4.0, 0.0, 0.0], [2.0, 10.0, 0.0]],
        );
    }

    #[test]
    fn shapes_and_complements() {
        check(
            r#"{ "objects": [ { "cylinder": { "radius": 2, "axis": "z" } } ] }"#,
            &[[1.9, 0.0, 100.0]],
            &[[2.1, 0.0, 0.0]],
        );
        check(r#"{ "objects": [ { "cone": {} } ] }"#, &[[0.0, 2.0, 1.0], [0.0, -2.0, 1.0]], &[[2.0, 1.0, 0.0]]);
        check(r#"{ "objects": [ { "paraboloid": {} } ] }"#, &[[0.0, 1.0, 0.9]], &[[0.0, 1.0, 1.1], [0.0, -0.1, 0.0]]);
        check(
            r#"{ "objects": [ { "hyperboloid": { "sheets": 1 } } ] }"#,
            &[[0.0, 0.0, 0.9], [2.0, 2.0, 0.0]],
            &[[1.1, 0.0, 0.0]],
        );
        check(
            r#"{ "objects": [ { "hyperboloid": { "sheets": 2 } } ] }"#,
            &[[0.0, 1.1, 0.0], [0.0, -1.1, 0.0]],
            &[[0.0, 0.0, 0.0]],
        );
        check(
            r#"{ "objects": [ { "quadric": [1, 1, 1, 0, 0, 0, -1, 0, 0, 0] } ] }"#,
            &[[1.9, 0.0, 0.0]],
            &[[-0.1, 0.0, 0.0]],
        );
        check(r#"{ "objects": [ { "halfspace": [0, 1, 0, -1] } ] }"#, &[[0.0, 0.9, 0.0]], &[[0.0, 1.1, 0.0]]);
        check(
            r#"{ "objects": [ { "sphere": {} }, { "sphere": { "radius": 0.5 }, "complement": true } ] }"#,
            &[[0.0, 0.75, 0.0]],
            &[[0.0, 0.25, 0.0], [0.0, 1.25, 0.0]],
        );
    }

    #[test]
    fn groups_flatten_depth_first_and_materials_resolve() {
        let w = world(
            r#"{ "name": "one", "material": "b", "objects": [ { "sphere": {} } ] },
               { "group": "g", "blocks": [ { "name": "two", "objects": [ { "sphere": {} } ] },
                                            { "group": "h", "blocks": [ { "name": "three", "objects": [ { "sphere": {} } ] } ] } ] },
               { "objects": [ { "sphere": {}, "material": "a" }, { "sphere": {} } ], "material": "b" }"#,
        );
        let names: Vec<&str> = w.complex.blocks().iter().map(|b| b.name()).collect();
        assert_eq!(names, ["one", "two", "three", "block 4"]);
        assert_eq!(w.blocks()[2].path, "blocks[1].blocks[1].blocks[0]");
        let id = complex::BlockId(3);
        assert_eq!(w.surface_material(id, 0).name, "a");
        assert_eq!(w.surface_material(id, 1).name, "b");
        assert_eq!(w.block_material(id).name, "b");
        assert_eq!(w.block_material(complex::BlockId(1)).name, "(default)");
        // The table built with the world answers as the block infos do.
        for (i, info) in w.blocks().iter().enumerate() {
            for j in 0..info.solid_materials.len() + 1 {
                let m = info.solid_materials.get(j).copied().unwrap_or(info.material);
                let got = w.surface_material(complex::BlockId(i as u32), j as u32);
                assert!(core::ptr::eq(got, &w.materials()[m]), "block {i} solid {j}");
            }
        }
    }

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

    #[test]
    fn group_nesting_built_in_code_is_bounded() {
        // JSON cannot nest this deep (serde_json stops at 128 levels), code can.
        let mut entry = Entry {
            objects: Some(vec![ObjectSpec { sphere: Some(Box::default()), ..Default::default() }]),
            ..Default::default()
        };
        for _ in 0..MAX_GROUP_DEPTH + 5 {
            entry = Entry { group: Some("g".into()), blocks: Some(vec![entry]), ..Default::default() };
        }
        let text = format!(r#"{{ {CAMERA}, "blocks": [] }}"#);
        let mut scene = SceneFile::from_json(&text).unwrap();
        scene.blocks = vec![entry];
        let err = scene.to_world().unwrap_err().to_string();
        assert!(err.contains("groups nest deeper than 100 levels") && err.starts_with("blocks[0].blocks[0]"), "{err}");
    }

    /// Flattens `scene` in one run, as scenes shorter than two runs are.
    fn sequential(scene: &SceneFile) -> Result<(Vec<Block>, Vec<BlockInfo>), SceneError> {
        let materials = &scene.materials;
        let mut flat =
            Flattener { materials, default_material: materials.len(), before: 0, blocks: vec![], infos: vec![] };
        flat.entries(&scene.blocks, 0, "blocks", &[])?;
        Ok((flat.blocks, flat.infos))
    }

    #[test]
    fn long_scenes_flatten_in_runs_as_in_one() {
        let ball = || ObjectSpec { sphere: Some(Box::default()), ..Default::default() };
        let block = |name: Option<String>| Entry { name, objects: Some(vec![ball()]), ..Default::default() };
        let group = |blocks| Entry { group: Some("g".into()), blocks: Some(blocks), ..Default::default() };
        // Unnamed blocks (named by their number) and groups of 0 to 3 blocks.
        let entries: Vec<Entry> = (0..5001)
            .map(|i| match i % 7 {
                0 => group((0..i % 4).map(|_| block(None)).collect()),
                1 => block(Some(format!("n{i}"))),
                _ => block(None),
            })
            .collect();
        let text = format!(r#"{{ {CAMERA}, "materials": {{ "a": {{}} }}, "blocks": [] }}"#);
        let mut scene = SceneFile::from_json(&text).unwrap();
        scene.blocks = entries;
        let ours = scene.flattened(scene.materials.len()).unwrap();
        let one = sequential(&scene).unwrap();
        let names = |b: &[Block]| b.iter().map(|b| b.name().to_string()).collect::<Vec<_>>();
        assert_eq!(names(&ours.0), names(&one.0));
        assert_eq!(ours.1, one.1);
        assert_eq!(ours.0.last().unwrap().name(), format!("block {}", one.0.len()));
        // The first error in document order wins, whichever run finds it first.
        scene.blocks[4100].objects = Some(vec![]);
        scene.blocks[3000].material = Some("b".into());
        scene.blocks[3006].objects = Some(vec![]);
        let err = scene.flattened(scene.materials.len()).unwrap_err();
        assert_eq!(err, sequential(&scene).unwrap_err());
        assert!(err.to_string().starts_with("blocks[3000].material: block \"block "), "{err}");
        scene.blocks[3000].material = None;
        let err = scene.flattened(scene.materials.len()).unwrap_err();
        assert_eq!(err, sequential(&scene).unwrap_err());
        assert!(err.to_string().contains("is empty"), "{err}");
    }

    #[test]
    fn object_specs_stay_small() {
        // A large scene holds one per solid; see the comment on `ObjectSpec`.
        assert!(std::mem::size_of::<ObjectSpec>() <= 120, "{}", std::mem::size_of::<ObjectSpec>());
        assert!(std::mem::size_of::<Step>() <= 32, "{}", std::mem::size_of::<Step>());
    }

    #[test]
    fn schema_key_is_allowed() {
        let text =
            format!(r#"{{ "$schema": "x", {CAMERA}, "blocks": [ {{ "objects": [ {{ "sphere": {{}} }} ] }} ] }}"#);
        assert!(SceneFile::from_json(&text).unwrap().to_world().is_ok());
    }
}
