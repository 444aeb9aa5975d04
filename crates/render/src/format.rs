//! The scene file: the serde types of the JSON document, the only place
//! that knows JSON, and its JSON Schema. The document converts into a
//! [`World`](crate::world::World) (`SceneFile::to_world`); the settings
//! and specular models are the world's own types, read as they are.

use std::collections::BTreeMap;

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::error::SceneError;
use crate::keys::{Animated, Keyable, Keys};
use crate::world::{Model, Settings, Triple};

/// The whole scene document.
///
/// ```
/// use render::format::SceneFile;
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
    /// The camera (docs/model.md §4).
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
    /// Named lists of blocks, placed by `instance` and `lattice` entries
    /// (docs/scene-format.md, "Definitions, instances and lattices").
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub definitions: BTreeMap<String, DefinitionSpec>,
    /// Blocks and groups in priority order (earlier blocks win where
    /// transparent blocks overlap).
    pub blocks: Vec<Entry>,
    /// The frames of an animation (`komplex render --frames`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub animation: Option<AnimationSpec>,
    /// Any JSON the renderer ignores: where the scene came from and what
    /// it does not model (`komplex import-openmc` keeps OpenMC's boundary
    /// conditions here).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub metadata: Option<serde_json::Value>,
}

/// The animation's default frame range: `{"frames": [A, B]}`, both
/// included, `A <= B`.
#[derive(Clone, Debug, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct AnimationSpec {
    /// The first and the last frame that `komplex render --frames` renders.
    pub frames: [u32; 2],
}

/// A definition: blocks, groups, instances and lattices in their own frame,
/// placed by `instance` and `lattice` entries.
#[derive(Clone, Debug, Default, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct DefinitionSpec {
    /// Blocks, groups, instances and lattices in priority order.
    pub blocks: Vec<Entry>,
}

/// The camera of docs/model.md §4: a pinhole by default, a thin lens with
/// `lens_radius > 0`, orthographic with `projection: "orthographic"`.
#[derive(Clone, Debug, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct CameraSpec {
    /// The eye point `E` (may be keyed).
    pub eye: Animated<Triple>,
    /// The viewing direction `D` (need not be unit length; may be keyed).
    pub direction: Animated<Triple>,
    /// The up vector `U`; only its part orthogonal to `direction` counts
    /// (may be keyed).
    #[serde(default = "default_up")]
    pub up: Animated<Triple>,
    /// Image width in pixels.
    #[serde(default = "default_width")]
    pub width: u32,
    /// Image height in pixels.
    #[serde(default = "default_height")]
    pub height: u32,
    /// Opening angle in degrees, measured on the image diagonal.
    #[serde(default = "default_aperture")]
    pub aperture: f64,
    /// Perspective (default) or orthographic projection.
    #[serde(default, skip_serializing_if = "ProjectionSpec::is_perspective")]
    pub projection: ProjectionSpec,
    /// Orthographic only (and required there): the world-space length of
    /// the image diagonal.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub diagonal: Option<f64>,
    /// Radius of the thin lens in world units; 0 (default) is a pinhole.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub lens_radius: f64,
    /// Distance from the eye to the plane of sharp focus, measured along
    /// `direction` (default: the length of `direction`; may be keyed).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub focus_distance: Option<Animated<f64>>,
}

/// The camera's projection (docs/model.md §4.5).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, Serialize, JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum ProjectionSpec {
    /// Rays from the eye through the pixels.
    #[default]
    Perspective,
    /// Parallel rays along `direction`; needs `diagonal`.
    Orthographic,
}

impl ProjectionSpec {
    fn is_perspective(&self) -> bool {
        *self == ProjectionSpec::Perspective
    }
}

fn is_zero(x: &f64) -> bool {
    *x == 0.0
}

fn default_up() -> Animated<Triple> {
    Animated::Fixed([0.0, 1.0, 0.0])
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

/// A surface material (docs/model.md §5.1). Each colour is a triple or a
/// procedural texture (docs/model.md §5.9).
#[derive(Clone, Debug, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct MaterialSpec {
    /// Ambient reflectance `Ma`.
    #[serde(default)]
    pub ambient: ColourSpec,
    /// Diffuse reflectance `Md`.
    #[serde(default)]
    pub diffuse: ColourSpec,
    /// Specular reflectance `Ms`.
    #[serde(default)]
    pub specular: ColourSpec,
    /// Specular exponent `p`.
    #[serde(default = "default_shininess")]
    pub shininess: f64,
    /// `phong` or `blinn-phong`.
    #[serde(default)]
    pub model: Model,
    /// Mirror reflection weight `kr`.
    #[serde(default)]
    pub reflect: ColourSpec,
    /// Transmission weight `kt` (used on transparent blocks).
    #[serde(default)]
    pub transmit: ColourSpec,
    /// Index of refraction of the medium (transparent blocks).
    #[serde(default = "default_ior")]
    pub ior: f64,
    /// Radiance emitted by the surface towards the outside of its block:
    /// an area light for the path integrator (ignored by Whitted).
    #[serde(default, skip_serializing_if = "ColourSpec::is_black")]
    pub emission: ColourSpec,
    /// A bump map tilting the shading normal (docs/model.md §5.9).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bump: Option<BumpSpec>,
}

impl MaterialSpec {
    /// Whether a colour is a texture or the material has a bump map: its
    /// blocks then keep their frame (`BlockInfo::frame`).
    pub fn is_textured(&self) -> bool {
        self.bump.is_some()
            || [&self.ambient, &self.diffuse, &self.specular, &self.reflect, &self.transmit, &self.emission]
                .iter()
                .any(|c| matches!(c, ColourSpec::Texture(_)))
    }
}

/// A colour of a material: a triple `[r, g, b]`, or a procedural texture
/// `{"checker": {...}}`, `{"noise": {...}}`, `{"marble": {...}}` or
/// `{"wood": {...}}` evaluated in the block's own frame.
#[derive(Clone, Debug, Serialize, JsonSchema)]
#[serde(untagged)]
pub enum ColourSpec {
    /// The same colour everywhere.
    Rgb(Triple),
    /// A procedural texture.
    Texture(Box<TextureSpec>),
}

impl ColourSpec {
    /// Whether it is the constant colour black (the default).
    pub fn is_black(&self) -> bool {
        matches!(self, ColourSpec::Rgb(c) if c.iter().all(|x| *x == 0.0))
    }
}

impl Default for ColourSpec {
    fn default() -> Self {
        ColourSpec::Rgb([0.0; 3])
    }
}

// A visitor of its own rather than `untagged` (which the schema follows):
// an error inside a texture then names its place and what went wrong
// there, not "did not match any variant".
impl<'de> Deserialize<'de> for ColourSpec {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct Colour;
        impl<'de> serde::de::Visitor<'de> for Colour {
            type Value = ColourSpec;

            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a colour [r, g, b] or a texture {\"checker\" | \"noise\" | \"marble\" | \"wood\": {...}}")
            }

            fn visit_seq<A: serde::de::SeqAccess<'de>>(self, seq: A) -> Result<ColourSpec, A::Error> {
                Triple::deserialize(serde::de::value::SeqAccessDeserializer::new(seq)).map(ColourSpec::Rgb)
            }

            // By hand rather than through `TextureSpec`'s own `Deserialize`,
            // which stops after the first key and leaves a second one to be
            // reported as a "trailing comma".
            fn visit_map<A: serde::de::MapAccess<'de>>(self, mut map: A) -> Result<ColourSpec, A::Error> {
                use serde::de::Error;
                const KINDS: &[&str] = &["checker", "noise", "marble", "wood"];
                let Some(kind) = map.next_key::<String>()? else {
                    return Err(A::Error::custom("a texture needs one key: `checker`, `noise`, `marble` or `wood`"));
                };
                let texture = match kind.as_str() {
                    "checker" => TextureSpec::Checker(map.next_value()?),
                    "noise" => TextureSpec::Noise(map.next_value()?),
                    "marble" => TextureSpec::Marble(map.next_value()?),
                    "wood" => TextureSpec::Wood(map.next_value()?),
                    other => return Err(A::Error::unknown_variant(other, KINDS)),
                };
                if let Some(extra) = map.next_key::<String>()? {
                    return Err(A::Error::custom(format!("a texture has one key, got `{kind}` and `{extra}`")));
                }
                Ok(ColourSpec::Texture(Box::new(texture)))
            }
        }
        deserializer.deserialize_any(Colour)
    }
}

/// A procedural texture: exactly one key.
#[derive(Clone, Debug, Deserialize, Serialize, JsonSchema)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum TextureSpec {
    /// Cubes of side `scale` in alternating colours.
    Checker(CheckerSpec),
    /// Fractal Perlin noise blending the two colours.
    Noise(NoiseSpec),
    /// Turbulent stripes across x, one period per `scale`.
    Marble(VeinSpec),
    /// Turbulent rings around the y axis, one per `scale`.
    Wood(VeinSpec),
}

/// Options of a checker texture.
#[derive(Clone, Debug, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct CheckerSpec {
    /// Side of a cell, in units of the block's frame (default 1).
    #[serde(default = "default_one")]
    pub scale: f64,
    /// The two colours (default black and white).
    #[serde(default = "default_colors")]
    pub colors: [Triple; 2],
}

/// Options of a noise texture.
#[derive(Clone, Debug, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct NoiseSpec {
    /// Size of a noise feature, in units of the block's frame (default 1).
    #[serde(default = "default_one")]
    pub scale: f64,
    /// Octaves summed, 1 to 16 (default 4).
    #[serde(default = "default_octaves")]
    pub octaves: u32,
    /// The colours at noise -1 and 1 (default black and white).
    #[serde(default = "default_colors")]
    pub colors: [Triple; 2],
}

/// Options of a marble or wood texture.
#[derive(Clone, Debug, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct VeinSpec {
    /// Stripe period or ring spacing, in units of the block's frame (default 1).
    #[serde(default = "default_one")]
    pub scale: f64,
    /// Octaves of the turbulence, 1 to 16 (default 4).
    #[serde(default = "default_octaves")]
    pub octaves: u32,
    /// How far the turbulence shifts a stripe or ring, in periods (default 1).
    #[serde(default = "default_one")]
    pub turbulence: f64,
    /// The two colours (default black and white).
    #[serde(default = "default_colors")]
    pub colors: [Triple; 2],
}

/// A bump map: `{"noise": {...}}`.
#[derive(Clone, Debug, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct BumpSpec {
    /// Bumps from the gradient of fractal Perlin noise.
    pub noise: BumpNoiseSpec,
}

/// Options of a noise bump map.
#[derive(Clone, Debug, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct BumpNoiseSpec {
    /// Size of a bump, in units of the block's frame (default 1).
    #[serde(default = "default_one")]
    pub scale: f64,
    /// Slope of the bumps: 0 is flat (default 1).
    #[serde(default = "default_one")]
    pub strength: f64,
    /// Octaves summed, 1 to 16 (default 1).
    #[serde(default = "default_one_octave")]
    pub octaves: u32,
}

fn default_one() -> f64 {
    1.0
}
fn default_octaves() -> u32 {
    4
}
fn default_one_octave() -> u32 {
    1
}
fn default_colors() -> [Triple; 2] {
    [[0.0; 3], [1.0; 3]]
}

fn default_shininess() -> f64 {
    32.0
}
fn default_ior() -> f64 {
    1.0
}

/// One step of a transform list. Every step but `matrix` may be keyed,
/// `{"translate": {"keys": [...]}}`: it is then [`Step::Keyed`], which
/// `SceneFile::at_frame` turns into a plain step.
#[derive(Clone, Debug, Serialize)]
#[serde(rename_all = "snake_case")]
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
    /// A step with keys instead of a value (written as the step with its
    /// keys). Boxed: rare, and a step stays 32 bytes.
    #[serde(untagged)]
    Keyed(Box<KeyedStep>),
}

/// A keyed transform step: its kind and its keys.
#[derive(Clone, Debug, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum KeyedStep {
    /// Translation by keyed `[x, y, z]`.
    Translate(Keys<Triple>),
    /// Keyed scaling.
    Scale(Keys<Scale>),
    /// Rotation about x by keyed degrees.
    RotateX(Keys<f64>),
    /// Rotation about y by keyed degrees.
    RotateY(Keys<f64>),
    /// Rotation about z by keyed degrees.
    RotateZ(Keys<f64>),
}

impl KeyedStep {
    /// The plain step at `frame` (docs/model.md §6.1).
    pub fn at(&self, frame: f64) -> Step {
        match self {
            KeyedStep::Translate(k) => Step::Translate(k.at(frame)),
            KeyedStep::Scale(k) => Step::Scale(k.at(frame)),
            KeyedStep::RotateX(k) => Step::RotateX(k.at(frame)),
            KeyedStep::RotateY(k) => Step::RotateY(k.at(frame)),
            KeyedStep::RotateZ(k) => Step::RotateZ(k.at(frame)),
        }
    }
}

// By hand rather than derived: a step's value may be keys, read into
// `Step::Keyed`. Read as serde's derived reader reads an enum (the same
// calls, so a plain step costs what it did), with the same messages and
// places for the same mistakes.
impl<'de> Deserialize<'de> for Step {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        #[derive(Deserialize)]
        #[serde(variant_identifier, rename_all = "snake_case")]
        enum Kind {
            Translate,
            Scale,
            RotateX,
            RotateY,
            RotateZ,
            Matrix,
        }
        const KINDS: &[&str] = &["translate", "scale", "rotate_x", "rotate_y", "rotate_z", "matrix"];

        struct Steps;
        impl<'de> serde::de::Visitor<'de> for Steps {
            type Value = Step;

            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("enum Step")
            }

            fn visit_enum<A: serde::de::EnumAccess<'de>>(self, data: A) -> Result<Step, A::Error> {
                use serde::de::VariantAccess;
                use Animated::{Fixed, Keyed};
                let keyed = |k: KeyedStep| Step::Keyed(Box::new(k));
                let (kind, value) = data.variant::<Kind>()?;
                Ok(match kind {
                    Kind::Translate => match value.newtype_variant()? {
                        Fixed(v) => Step::Translate(v),
                        Keyed(k) => keyed(KeyedStep::Translate(k)),
                    },
                    Kind::Scale => match value.newtype_variant()? {
                        Fixed(v) => Step::Scale(v),
                        Keyed(k) => keyed(KeyedStep::Scale(k)),
                    },
                    Kind::RotateX => match value.newtype_variant()? {
                        Fixed(v) => Step::RotateX(v),
                        Keyed(k) => keyed(KeyedStep::RotateX(k)),
                    },
                    Kind::RotateY => match value.newtype_variant()? {
                        Fixed(v) => Step::RotateY(v),
                        Keyed(k) => keyed(KeyedStep::RotateY(k)),
                    },
                    Kind::RotateZ => match value.newtype_variant()? {
                        Fixed(v) => Step::RotateZ(v),
                        Keyed(k) => keyed(KeyedStep::RotateZ(k)),
                    },
                    Kind::Matrix => Step::Matrix(value.newtype_variant::<PlainMatrix>()?.0),
                })
            }
        }
        deserializer.deserialize_enum("Step", KINDS, Steps)
    }
}

/// A `matrix` step's value: the rows, never keys.
struct PlainMatrix(Box<[[f64; 4]; 4]>);

impl<'de> Deserialize<'de> for PlainMatrix {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct Rows;
        impl<'de> serde::de::Visitor<'de> for Rows {
            type Value = PlainMatrix;

            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("an array of length 4")
            }

            fn visit_seq<A: serde::de::SeqAccess<'de>>(self, seq: A) -> Result<PlainMatrix, A::Error> {
                let rows = <[[f64; 4]; 4]>::deserialize(serde::de::value::SeqAccessDeserializer::new(seq))?;
                Ok(PlainMatrix(Box::new(rows)))
            }

            fn visit_map<A: serde::de::MapAccess<'de>>(self, _: A) -> Result<PlainMatrix, A::Error> {
                Err(serde::de::Error::custom(
                    "a `matrix` step cannot be keyed: key `translate`, `scale` and `rotate_x/y/z` steps instead",
                ))
            }
        }
        deserializer.deserialize_any(Rows)
    }
}

/// The schema of [`Step`]: its JSON form, each value plain or keyed.
#[derive(JsonSchema)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
#[schemars(rename = "Step", description = "One step of a transform list; every step but `matrix` may be keyed.")]
#[allow(dead_code)]
enum StepSchema {
    /// Translation by `[x, y, z]` (may be keyed).
    Translate(Animated<Triple>),
    /// Uniform (`s`) or per-axis (`[sx, sy, sz]`) scaling (may be keyed).
    Scale(Animated<Scale>),
    /// Rotation about x in degrees, y towards z (may be keyed).
    RotateX(Animated<f64>),
    /// Rotation about y in degrees, z towards x (may be keyed).
    RotateY(Animated<f64>),
    /// Rotation about z in degrees, x towards y (may be keyed).
    RotateZ(Animated<f64>),
    /// A general affine 4x4 matrix, row-major, last row `[0, 0, 0, 1]` (never keyed).
    Matrix(Box<[[f64; 4]; 4]>),
}

impl JsonSchema for Step {
    fn schema_name() -> String {
        StepSchema::schema_name()
    }

    fn json_schema(gen: &mut schemars::gen::SchemaGenerator) -> schemars::schema::Schema {
        StepSchema::json_schema(gen)
    }
}

impl Keyable for Scale {
    const EXPECTING: &'static str = "a number or an array [sx, sy, sz]";

    /// Factor by factor; a uniform scale stays uniform between uniform keys.
    fn lerp(a: &Scale, b: &Scale, t: f64) -> Scale {
        match (a, b) {
            (Scale::Uniform(a), Scale::Uniform(b)) => Scale::Uniform(crate::keys::lerp(*a, *b, t)),
            _ => Scale::PerAxis(<Triple as Keyable>::lerp(&a.per_axis(), &b.per_axis(), t)),
        }
    }
}

impl Scale {
    /// The three factors.
    pub fn per_axis(&self) -> Triple {
        match self {
            Scale::Uniform(s) => [*s; 3],
            Scale::PerAxis(v) => *v,
        }
    }
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
// schema and the serialisation still follow): `untagged` buffers every value
// and builds, formats and drops an error for each array it tries as a number
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

/// An entry of a `blocks` list: a block (with `objects`), a group (with
/// `group` and nested `blocks`), an instance of a definition (`instance`)
/// or a lattice of them (`lattice`, `pitch` and `count`).
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
    #[serde(default, skip_serializing_if = "Option::is_none", deserialize_with = "exact_some")]
    pub objects: Option<Vec<ObjectSpec>>,
    /// The group's name (groups only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub group: Option<String>,
    /// Nested blocks and groups (groups only).
    #[serde(default, skip_serializing_if = "Option::is_none", deserialize_with = "exact_some")]
    pub blocks: Option<Vec<Entry>>,
    /// The name of the definition placed once (instances only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub instance: Option<String>,
    /// The name of the definition placed on a lattice (lattices only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lattice: Option<String>,
    /// The lattice's step along x, y and z: element `(i, j, k)` is the
    /// definition moved by `(i·px, j·py, k·pz)`, then by `transform`
    /// (lattices only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pitch: Option<Triple>,
    /// The lattice's number of elements along x, y and z, each at least 1
    /// (lattices only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub count: Option<[u32; 3]>,
    /// Steps applied after the objects' own transforms (blocks), after
    /// everything inside (groups), or after the definition (instances) and
    /// each element's lattice offset (lattices).
    #[serde(default, skip_serializing_if = "Vec::is_empty", deserialize_with = "exact")]
    pub transform: Vec<Step>,
}

/// A list read into a buffer of its own length. serde grows a list as it
/// reads it (4 places, then doubling): a block of one or three objects
/// would keep room for four, one of six for eight, and its transform of
/// two or three steps for four. Shrunk at once, the spare room is what the
/// next values parsed take, and a 10⁶-block scene's parsed document is a
/// third smaller (docs/benchmarks.md, "Load time and peak memory").
fn exact<'de, D: serde::Deserializer<'de>, T: Deserialize<'de>>(d: D) -> Result<Vec<T>, D::Error> {
    let mut v = Vec::<T>::deserialize(d)?;
    v.shrink_to_fit();
    Ok(v)
}

/// [`exact`] for a list that may be `null` or left out.
fn exact_some<'de, D: serde::Deserializer<'de>, T: Deserialize<'de>>(d: D) -> Result<Option<Vec<T>>, D::Error> {
    let mut v = Option::<Vec<T>>::deserialize(d)?;
    if let Some(v) = &mut v {
        v.shrink_to_fit();
    }
    Ok(v)
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
    #[serde(default, skip_serializing_if = "Vec::is_empty", deserialize_with = "exact")]
    pub transform: Vec<Step>,
    /// Whether to take the outside of the solid instead.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub complement: bool,
    /// Material of this surface (default: the block's).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub material: Option<String>,
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
}

/// The JSON Schema (draft-07) of the scene format, pretty-printed.
///
/// Generated from the serde types, plus the two rules the types cannot
/// express: an object has exactly one shape key, and a `blocks` entry is
/// either a block (`objects`), a group (`group` and `blocks`), an instance
/// (`instance`) or a lattice (`lattice`, `pitch` and `count`).
pub fn schema_json() -> String {
    let schema = schemars::schema_for!(SceneFile);
    let mut value = serde_json::to_value(&schema).unwrap_or_default();
    let one_of = |alternatives: &[&[&str]]| {
        serde_json::Value::Array(alternatives.iter().map(|keys| serde_json::json!({ "required": keys })).collect())
    };
    if let Some(defs) = value.get_mut("definitions").and_then(|d| d.as_object_mut()) {
        if let Some(obj) = defs.get_mut("ObjectSpec").and_then(|o| o.as_object_mut()) {
            let shapes: Vec<&[&str]> = vec![
                &["sphere"],
                &["cylinder"],
                &["cone"],
                &["paraboloid"],
                &["hyperboloid"],
                &["quadric"],
                &["halfspace"],
            ];
            obj.insert("oneOf".into(), one_of(&shapes));
        }
        if let Some(entry) = defs.get_mut("Entry").and_then(|o| o.as_object_mut()) {
            entry.insert(
                "oneOf".into(),
                one_of(&[&["objects"], &["group", "blocks"], &["instance"], &["lattice", "pitch", "count"]]),
            );
        }
    }
    // Serialising a JSON value cannot fail.
    let mut s = serde_json::to_string_pretty(&value).unwrap_or_default();
    s.push('\n');
    s
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

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

    #[test]
    fn object_specs_stay_small() {
        // A large scene holds one per solid; see the comment on `ObjectSpec`.
        assert!(std::mem::size_of::<ObjectSpec>() <= 120, "{}", std::mem::size_of::<ObjectSpec>());
        assert!(std::mem::size_of::<Step>() <= 32, "{}", std::mem::size_of::<Step>());
        // One per block, kept with the world; see `BlockInfo::frame`.
        assert!(std::mem::size_of::<crate::world::BlockInfo>() <= 64);
    }

    #[test]
    fn lists_are_read_into_buffers_of_their_own_length() {
        let steps = r#"[ { "translate": [1, 2, 3] }, { "scale": 2 }, { "rotate_x": 90 } ]"#;
        let objects: String = (0..6).map(|_| format!(r#"{{ "sphere": {{}}, "transform": {steps} }},"#)).collect();
        let json = format!(r#"{{ "objects": [ {} ], "transform": {steps} }}"#, objects.trim_end_matches(','));
        let e: Entry = serde_json::from_str(&json).unwrap();
        let objects = e.objects.unwrap();
        assert_eq!((objects.len(), objects.capacity()), (6, 6));
        assert_eq!((e.transform.len(), e.transform.capacity()), (3, 3));
        assert!(objects.iter().all(|o| o.transform.capacity() == 3));
        let group: Entry =
            serde_json::from_str(&format!(r#"{{ "group": "g", "blocks": [ {json}, {json}, {json} ] }}"#)).unwrap();
        assert_eq!(group.blocks.map(|b| b.capacity()), Some(3));
        // `null` is still no list.
        let e: Entry = serde_json::from_str(r#"{ "objects": null }"#).unwrap();
        assert!(e.objects.is_none());
    }
}
