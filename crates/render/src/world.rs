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
    /// The block infos of each block list, by the key of the complex built
    /// from it (`Complex::resolve`): the top list's (key 0), then each
    /// definition's (its index in key order + 1), each parallel to that
    /// complex's own blocks. For a scene without instances, the first is
    /// parallel to `complex.blocks()` and the only one.
    tables: Vec<Vec<BlockInfo>>,
    /// Per block of the top list, the material index of all its surfaces,
    /// or `u32::MAX` when its solids' materials differ (then `tables`
    /// answers): four bytes per block, where a `BlockInfo` is 64 and its
    /// solid list a heap buffer of its own, so a shaded hit of a large
    /// scene reads one likely cached word. Built with the world (`materials`
    /// and `tables` are read-only, so it stays true), not per frame: at
    /// 100,000 blocks a per-frame build would read 7 MB of block data the
    /// render itself never needs. Empty for a scene with instances, whose
    /// hits go through `Complex::resolve`.
    surface_materials: Vec<u32>,
    /// How the block lists of a scene with instances place each other
    /// (`None` for a scene without).
    layout: Option<Layout>,
}

/// The structure of a scene with instances: per block list (by key, as
/// `World::tables`), its entries in order, and the complex built from each
/// definition's list. Enough to count or list the blocks of the expansion
/// that satisfy a condition without visiting the others.
#[derive(Clone, Debug, Default)]
pub(crate) struct Layout {
    /// By key: the list's own blocks and placed definitions, in order.
    pub lists: Vec<Vec<Item>>,
    /// By key: the complex of that list (`None` for the top list: `World::complex`).
    pub complexes: Vec<Option<std::sync::Arc<Complex>>>,
    /// Whether every block's surfaces all have the block's material (no
    /// object names a material of its own): then a hit's material is read
    /// off the block, without `Complex::resolve`. Set by `World::new`.
    pub uniform: bool,
}

/// One entry of a block list in a [`Layout`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Item {
    /// The list's next own block.
    Block,
    /// `elements` copies of the list of key `key`.
    Placed {
        /// The placed definition's key.
        key: u32,
        /// Its number of elements (1 for an instance).
        elements: u64,
    },
}

impl World {
    /// A world of these parts; `tables` the block infos of each block list
    /// by key (see the field), their material indices into `materials`.
    pub(crate) fn new(
        camera: Camera,
        settings: Settings,
        lights: Vec<Light>,
        materials: Vec<Material>,
        complex: Complex,
        tables: Vec<Vec<BlockInfo>>,
        layout: Option<Layout>,
    ) -> Self {
        let uniform = |info: &BlockInfo| {
            let same = info.solid_materials.iter().all(|&m| m == info.material);
            u32::try_from(info.material).ok().filter(|&m| same && m != u32::MAX).unwrap_or(u32::MAX)
        };
        let surface_materials =
            if complex.is_assembled() { vec![] } else { tables.iter().flatten().map(uniform).collect() };
        let mut layout = layout;
        if let Some(l) = &mut layout {
            l.uniform = tables.iter().flatten().all(|info| info.solid_materials.iter().all(|&m| m == info.material));
        }
        World { camera, settings, lights, materials, complex, tables, surface_materials, layout }
    }

    /// Whether the scene places definitions (instances or lattices).
    pub fn is_instanced(&self) -> bool {
        self.layout.is_some()
    }

    /// The own blocks of the list of key `key` with their infos.
    fn own_blocks(&self, key: usize) -> impl Iterator<Item = (&complex::Block, &BlockInfo)> {
        let complex = match self.layout.as_ref().and_then(|l| l.complexes.get(key)).and_then(Option::as_ref) {
            Some(c) => &**c,
            None => &self.complex,
        };
        complex.blocks().iter().zip(&self.tables[key])
    }

    /// Over the blocks of the expansion, the sum of `f` of each (of the
    /// block in its list's frame and its info), computed once per block
    /// the file writes and multiplied by how often it is placed, saturating.
    pub fn sum_over_blocks(&self, f: impl Fn(&complex::Block, &BlockInfo) -> u64) -> u64 {
        let Some(layout) = &self.layout else {
            return self.own_blocks(0).map(|(b, i)| f(b, i)).fold(0, u64::saturating_add);
        };
        let mut sums = vec![0u64; layout.lists.len()];
        let mut done = vec![false; layout.lists.len()];
        // Definitions may place definitions of any key; settle them in an
        // order where each comes after those it places.
        let mut stack: Vec<usize> = (0..layout.lists.len()).rev().collect();
        while let Some(&key) = stack.last() {
            if done[key] {
                stack.pop();
                continue;
            }
            let pending: Vec<usize> = layout.lists[key]
                .iter()
                .filter_map(|item| match item {
                    Item::Placed { key: k, .. } if !done[*k as usize] => Some(*k as usize),
                    _ => None,
                })
                .collect();
            if !pending.is_empty() {
                stack.extend(pending);
                continue;
            }
            let own = self.own_blocks(key).map(|(b, i)| f(b, i)).fold(0, u64::saturating_add);
            sums[key] = layout.lists[key].iter().fold(own, |sum, item| match item {
                Item::Block => sum,
                Item::Placed { key: k, elements } => sum.saturating_add(sums[*k as usize].saturating_mul(*elements)),
            });
            done[key] = true;
            stack.pop();
        }
        sums[0]
    }

    /// The ids of the blocks of the expansion for which `keep` holds (of
    /// the block in its list's frame and its info), in id order, if there
    /// are at most `cap` of them; `None` if there are more. Visits only the
    /// placements that hold such a block.
    pub fn select_blocks(
        &self,
        keep: impl Fn(&complex::Block, &BlockInfo) -> bool,
        cap: usize,
    ) -> Option<Vec<complex::BlockId>> {
        let Some(layout) = &self.layout else {
            let ids: Vec<complex::BlockId> = self
                .own_blocks(0)
                .enumerate()
                .filter(|(_, (b, i))| keep(b, i))
                .map(|(n, _)| complex::BlockId(n as u32))
                .collect();
            return (ids.len() <= cap).then_some(ids);
        };
        if self.sum_over_blocks(|b, i| u64::from(keep(b, i))) > cap as u64 {
            return None;
        }
        let len_of = |key: usize| -> u64 {
            // The length of a list's expansion: the length of its complex.
            match layout.complexes.get(key).and_then(Option::as_ref) {
                Some(c) => c.len() as u64,
                None => self.complex.len() as u64,
            }
        };
        let kept: Vec<Vec<bool>> =
            (0..layout.lists.len()).map(|key| self.own_blocks(key).map(|(b, i)| keep(b, i)).collect()).collect();
        let mut any = vec![None::<bool>; layout.lists.len()];
        let mut out = Vec::new();
        fn walk(
            layout: &Layout,
            kept: &[Vec<bool>],
            any: &mut Vec<Option<bool>>,
            len_of: &dyn Fn(usize) -> u64,
            key: usize,
            base: u64,
            out: &mut Vec<complex::BlockId>,
        ) -> bool {
            let mut next = base;
            let mut own = 0;
            let mut found = false;
            for item in &layout.lists[key] {
                match item {
                    Item::Block => {
                        if kept[key][own] {
                            out.push(complex::BlockId(next as u32));
                            found = true;
                        }
                        own += 1;
                        next += 1;
                    }
                    Item::Placed { key: k, elements } => {
                        let k = *k as usize;
                        let stride = len_of(k);
                        if any[k] != Some(false) {
                            for e in 0..*elements {
                                let f = walk(layout, kept, any, len_of, k, next + e * stride, out);
                                any[k] = Some(f);
                                found |= f;
                                if !f {
                                    break;
                                }
                            }
                        }
                        next += elements * stride;
                    }
                }
            }
            found
        }
        walk(layout, &kept, &mut any, &len_of, 0, 0, &mut out);
        Some(out)
    }

    /// The materials; indices are `MaterialKey`s (the last one is the
    /// default of blocks that name none).
    pub fn materials(&self) -> &[Material] {
        &self.materials
    }

    /// The materials and place in the file of block `id` (of the
    /// expansion): the info of the block as the file writes it, which every
    /// placed copy of a definition's block shares.
    ///
    /// # Panics
    /// If `id` is not a block of the complex.
    pub fn block_info(&self, id: complex::BlockId) -> &BlockInfo {
        if !self.complex.is_assembled() {
            return &self.tables[0][id.index()];
        }
        let r = self.complex.resolve(id);
        &self.tables[r.key as usize][r.own as usize]
    }

    /// Every block the file writes, each once with its info: the top
    /// list's, then each definition's (however often it is placed), each in
    /// its list's frame.
    pub fn written_blocks(&self) -> impl Iterator<Item = (&complex::Block, &BlockInfo)> {
        (0..self.tables.len()).flat_map(|key| self.own_blocks(key))
    }

    /// The material of solid `solid` of block `block`.
    pub fn surface_material(&self, block: complex::BlockId, solid: u32) -> &Material {
        if let Some(&m) = self.surface_materials.get(block.index()) {
            if m != u32::MAX {
                return &self.materials[m as usize];
            }
        }
        if self.layout.as_ref().is_some_and(|l| l.uniform) {
            // Every block's surfaces have its material, the block's own key:
            // no need to resolve the placement.
            return self.block_material(block);
        }
        let info = self.block_info(block);
        let m = info.solid_materials.get(solid as usize).copied().unwrap_or(info.material);
        &self.materials[m]
    }

    /// The material of a block (its medium, for transparent blocks).
    pub fn block_material(&self, block: complex::BlockId) -> &Material {
        if self.layout.is_some() {
            // The block's key is its material's index (`flatten`), read
            // without resolving the placement.
            return &self.materials[self.complex.block(block).material().0 as usize];
        }
        &self.materials[self.block_info(block).material]
    }

    /// World to the frame of a block with a textured material: its own
    /// frame's map composed with the inverse of its definition's placement.
    pub fn frame(&self, block: complex::BlockId) -> Option<Transform> {
        if !self.complex.is_assembled() {
            return self.tables[0][block.index()].frame.as_deref().copied();
        }
        let r = self.complex.resolve(block);
        let frame = *self.tables[r.key as usize][r.own as usize].frame.as_deref()?;
        Some(match r.to_world {
            None => frame,
            Some(to_world) => to_world.inverse().then(&frame),
        })
    }
}
