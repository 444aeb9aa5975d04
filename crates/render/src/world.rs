//! The scene ready to render: the camera, the settings, the resolved
//! lights and materials and the complex of blocks, with what the kernel
//! does not keep of each block (its materials, its place in the file).
//!
//! The scene format (`format`) converts into these types; everything that
//! renders or inspects a scene (shading, the render loop, `trace`, `check`,
//! the POV-Ray export) reads them and knows nothing of JSON. `Settings` and
//! `Model` are the file's own values, unchanged by conversion, so the format
//! reads them as they are defined here.

use complex::Complex;
use quadric::nalgebra::{Point3, Vector3};
use quadric::Transform;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::camera::Camera;
use crate::texture::{Bump, Texture};

/// A colour or vector triple.
pub type Triple = [f64; 3];

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
    /// The light transport algorithm: `whitted` (the default) or `path`
    /// (docs/model.md §5.10).
    #[serde(default, skip_serializing_if = "Integrator::is_whitted")]
    pub integrator: Integrator,
    /// Samples per pixel, each at a random point of the pixel (and of the
    /// lens), for either integrator. Default: the `samples × samples` grid
    /// for Whitted, `samples²` random samples for the path integrator.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub spp: Option<u32>,
    /// Adaptive sampling: a pixel takes samples until the estimated relative
    /// standard error of its mean luminance is below this (at least
    /// [`MIN_ADAPTIVE_SPP`](crate::frame::MIN_ADAPTIVE_SPP) and at most
    /// `spp` samples). Default: every pixel takes `spp` samples.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub noise: Option<f64>,
    /// The seed of the random numbers of sampled pixels: another seed,
    /// another (equally likely) image.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub seed: u64,
}

impl Integrator {
    /// Whether it is the default, Whitted.
    pub fn is_whitted(&self) -> bool {
        *self == Integrator::Whitted
    }
}

/// The light transport algorithm of a render.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, Serialize, JsonSchema)]
#[serde(rename_all = "kebab-case")]
pub enum Integrator {
    /// Whitted ray tracing: point lights, mirrors and glass (docs/model.md §5.2–§5.6).
    #[default]
    Whitted,
    /// Unidirectional path tracing of the rendering equation with next-event
    /// estimation and multiple importance sampling (docs/model.md §5.10).
    Path,
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
            integrator: Integrator::Whitted,
            spp: None,
            noise: None,
            seed: 0,
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
fn is_zero(x: &u64) -> bool {
    *x == 0
}
fn default_true() -> bool {
    true
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
    /// The radiance the surface emits towards the outside of its block
    /// (the path integrator's area lights; Whitted ignores it).
    pub emission: Vector3<f64>,
    /// The textures and bump map, if any: then the colours above are
    /// the textures' mean colours (what `pov` and `check` read), and the
    /// shader reads [`Material::at`].
    pub textures: Option<Box<Textures>>,
}

/// The textured colours of a material (`None`: the constant colour) and
/// its bump map.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Textures {
    /// Ambient reflectance.
    pub ambient: Option<Texture>,
    /// Diffuse reflectance.
    pub diffuse: Option<Texture>,
    /// Specular reflectance.
    pub specular: Option<Texture>,
    /// Reflection weight.
    pub reflect: Option<Texture>,
    /// Transmission weight.
    pub transmit: Option<Texture>,
    /// Emitted radiance.
    pub emission: Option<Texture>,
    /// Bump map.
    pub bump: Option<Bump>,
}

impl Material {
    /// The untextured material of the point `p` of the block's frame:
    /// each textured colour evaluated there (docs/model.md §5.9).
    pub fn at(&self, p: &Point3<f64>) -> Material {
        let pick = |t: &Option<Texture>, c: &Vector3<f64>| t.as_ref().map_or(*c, |t| t.at(p));
        let Some(t) = &self.textures else { return Material { name: String::new(), textures: None, ..self.clone() } };
        Material {
            name: String::new(),
            ambient: pick(&t.ambient, &self.ambient),
            diffuse: pick(&t.diffuse, &self.diffuse),
            specular: pick(&t.specular, &self.specular),
            shininess: self.shininess,
            model: self.model,
            reflect: pick(&t.reflect, &self.reflect),
            transmit: pick(&t.transmit, &self.transmit),
            ior: self.ior,
            emission: pick(&t.emission, &self.emission),
            textures: None,
        }
    }
}

/// A resolved point light.
#[derive(Clone, Debug, PartialEq)]
pub struct Light {
    /// Position.
    pub position: Point3<f64>,
    /// Diffuse colour; for the path integrator, the radiant intensity
    /// (W/sr) of the light.
    pub diffuse: Vector3<f64>,
    /// Specular colour (Whitted only).
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
    /// World to the block's own frame (the inverse of its transform and
    /// its groups'), where its textures are evaluated; only for blocks
    /// with a textured material (docs/model.md §5.9). Boxed: inline, the
    /// `None` of every untextured block would take 176 bytes.
    pub frame: Option<Box<Transform>>,
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
    /// bytes per block, where a `BlockInfo` is 64 and its solid list a heap
    /// buffer of its own, so a shaded hit of a large scene reads one likely
    /// cached word. Built with the world (`materials` and `blocks` are
    /// read-only, so it stays true), not per frame: at 100,000 blocks a
    /// per-frame build would read 7 MB of block data the render itself
    /// never needs.
    surface_materials: Vec<u32>,
}

impl World {
    /// A world of these parts; `blocks` parallel to `complex.blocks()`,
    /// their material indices into `materials`.
    pub(crate) fn new(
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

    /// World to the frame of a block with a textured material.
    pub fn frame(&self, block: complex::BlockId) -> Option<&Transform> {
        self.blocks[block.index()].frame.as_deref()
    }
}
