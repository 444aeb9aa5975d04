//! `komplex check`: a summary of a valid scene and warnings about things
//! that are allowed but probably not meant.

use std::fmt;

use complex::BlockId;
use quadric::nalgebra::Vector3;

use crate::world::{Integrator, World};

/// What `check` found.
#[derive(Clone, Debug, PartialEq)]
pub struct Report {
    /// Number of blocks (of the expansion: each placed copy counts).
    pub blocks: usize,
    /// Number of solids over all blocks (of the expansion).
    pub solids: u64,
    /// Number of transparent blocks (of the expansion).
    pub transparent: u64,
    /// Number of lights.
    pub lights: usize,
    /// Number of named materials.
    pub materials: usize,
    /// Box of the bounded blocks, `None` if none is bounded; for more than
    /// 2²⁰ blocks (instances expanded), the complex's box if it is bounded.
    pub bounds: Option<([f64; 3], [f64; 3])>,
    /// The fault tolerance ε in use.
    pub epsilon: f64,
    /// Image size.
    pub size: (u32, u32),
    /// Warnings, one line each.
    pub warnings: Vec<String>,
}

/// Summarises `world` and collects warnings.
pub fn check(world: &World) -> Report {
    let complex = &world.complex;
    let mut warnings = Vec::new();
    let mut bounds: Option<([f64; 3], [f64; 3])> = None;
    // A kernel without bounds reports every block as infinite; warning about
    // each block then says nothing, so warn per block only when the kernel
    // bounds at least one.
    if complex.len() <= MAX_BLOCKS_VISITED {
        let kernel_bounds = (0..complex.len()).any(|i| complex.block_aabb(BlockId(i as u32)).is_bounded());
        for i in 0..complex.len() {
            let id = BlockId(i as u32);
            let b = complex.block(id);
            let aabb = complex.block_aabb(id);
            if aabb.is_bounded() {
                let (lo, hi) = bounds.unwrap_or(([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]));
                bounds = Some(([0, 1, 2].map(|k| lo[k].min(aabb.min[k])), [0, 1, 2].map(|k| hi[k].max(aabb.max[k]))));
            } else if aabb.is_empty() {
                let path = &world.block_info(id).path;
                warnings.push(format!("block {} \"{}\" ({path}) is empty: its solids share no point", i + 1, b.name()));
            } else if kernel_bounds {
                let path = &world.block_info(id).path;
                warnings.push(format!("block {} \"{}\" ({path}) may be unbounded", i + 1, b.name()));
            }
            if b.is_transparent() {
                let m = world.block_material(id);
                if m.transmit == Vector3::zeros() {
                    warnings.push(format!(
                        "block {} \"{}\" is transparent but its material \"{}\" has transmit 0",
                        i + 1,
                        b.name(),
                        m.name
                    ));
                }
            }
        }
    } else {
        // Too many blocks to visit: the box of the whole complex, and the
        // warnings once per block the file writes, by name and place.
        let aabb = complex.aabb();
        bounds = aabb.is_bounded().then(|| (aabb.min.into(), aabb.max.into()));
        for (b, info) in world.written_blocks() {
            let m = &world.materials()[info.material];
            if b.is_transparent() && m.transmit == Vector3::zeros() {
                warnings.push(format!(
                    "block \"{}\" ({}) is transparent but its material \"{}\" has transmit 0",
                    b.name(),
                    info.path,
                    m.name
                ));
            }
        }
        warnings.push(format!(
            "{} blocks: more than {MAX_BLOCKS_VISITED}, so the bounds are the complex's box (unknown if it is \
             unbounded) and blocks are not checked one by one",
            complex.len()
        ));
    }
    let eye = world.camera.eye();
    if let Some(id) = complex.contains_point(&eye) {
        let b = complex.block(id);
        let kind = if b.is_transparent() { "transparent" } else { "opaque" };
        warnings.push(format!("the eye lies inside {kind} block {} \"{}\"", id.0 + 1, b.name()));
    }
    for (k, l) in world.lights.iter().enumerate() {
        if let Some(id) = complex.contains_point(&l.position) {
            if !complex.block(id).is_transparent() {
                warnings.push(format!(
                    "light {} lies inside opaque block {} \"{}\" and lights nothing",
                    k + 1,
                    id.0 + 1,
                    complex.block(id).name()
                ));
            }
        }
    }
    if complex.len() <= MAX_BLOCKS_VISITED {
        opaque_overlaps(world, &mut warnings);
    } else {
        warnings.push(format!(
            "overlaps between opaque blocks not checked: more than {MAX_BLOCKS_VISITED} blocks (run komplex overlaps \
             on a part of the scene)"
        ));
    }
    // The path integrator is also lit by emissive blocks and the background.
    let path_lit = world.settings.integrator == Integrator::Path
        && (world.materials().iter().any(|m| m.emission.max() > 0.0)
            || world.settings.background.iter().any(|c| *c > 0.0));
    if world.lights.is_empty() && !path_lit {
        warnings.push("the scene has no lights: only ambient light, reflection and refraction".into());
    }
    let used: Vec<bool> = (0..world.materials().len())
        .map(|m| world.written_blocks().any(|(_, b)| b.material == m || b.solid_materials.contains(&m)))
        .collect();
    // The last material is the built-in default.
    for (m, mat) in world.materials().iter().enumerate().take(world.materials().len() - 1) {
        if !used[m] {
            warnings.push(format!("material \"{}\" is not used", mat.name));
        }
    }
    Report {
        blocks: complex.len(),
        solids: world.sum_over_blocks(|b, _| b.solids().len() as u64),
        transparent: world.sum_over_blocks(|b, _| u64::from(b.is_transparent())),
        lights: world.lights.len(),
        materials: world.materials().len() - 1,
        bounds,
        epsilon: complex.epsilon(),
        size: (world.camera.width(), world.camera.height()),
        warnings,
    }
}

/// The most blocks (of the expansion) `check` visits one by one, for the
/// bounds and the per-block warnings; a scene with more instances gets the
/// complex's box and the warnings once per block the file writes.
const MAX_BLOCKS_VISITED: usize = 1 << 20;

/// Pairs of opaque blocks whose boxes overlap that `check` measures at
/// most; beyond it the check is skipped (and says so).
const MAX_OVERLAP_PAIRS: usize = 2000;

/// Warns about overlapping opaque blocks: the priority rule gives the
/// shared part to the earlier one, so their order decides what is seen.
/// A coarse measurement (`complex::Complex::overlaps_where` with a 1 %
/// tolerance, 2,048 lines a pair to start, at most 65,536 a round) keeps
/// `check` fast; overlaps much smaller than a pair's common box may go
/// unnoticed (`komplex overlaps` measures them finely).
fn opaque_overlaps(world: &World, warnings: &mut Vec<String>) {
    let complex = &world.complex;
    let options = complex::VolumeOptions {
        tolerance: 1e-2,
        replicates: 16,
        initial_lines: 2048,
        max_lines: 1 << 16,
        max_pairs: MAX_OVERLAP_PAIRS,
        ..complex::VolumeOptions::default()
    };
    let opaque = |a: BlockId, b: BlockId| !complex.block(a).is_transparent() && !complex.block(b).is_transparent();
    // The options are valid, so this cannot fail; a failure skips the check.
    let Ok(found) = complex.overlaps_where(&options, opaque) else { return };
    if found.skipped {
        warnings.push(format!(
            "overlaps between opaque blocks not checked: more than {MAX_OVERLAP_PAIRS} pairs have overlapping boxes (run komplex overlaps)"
        ));
    }
    for p in &found.pairs {
        let (a, b) = (complex.block(p.a), complex.block(p.b));
        warnings.push(format!(
            "opaque blocks {} \"{}\" and {} \"{}\" overlap (volume {:.3e} ± {:.1e}, e.g. at ({:.4}, {:.4}, {:.4})): the earlier one owns the overlap",
            p.a.0 + 1,
            a.name(),
            p.b.0 + 1,
            b.name(),
            p.volume.value,
            p.volume.error,
            p.point.x,
            p.point.y,
            p.point.z
        ));
    }
}

impl fmt::Display for Report {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let n = |count: u64, what: &str| format!("{count} {what}{}", if count == 1 { "" } else { "s" });
        writeln!(
            f,
            "{} ({} transparent), {}, {}, {}",
            n(self.blocks as u64, "block"),
            self.transparent,
            n(self.solids, "solid"),
            n(self.lights as u64, "light"),
            n(self.materials as u64, "material")
        )?;
        match self.bounds {
            Some((lo, hi)) => writeln!(f, "bounds: {lo:?} .. {hi:?}")?,
            None => writeln!(f, "bounds: unknown (no block has a finite box, or too many blocks to visit)")?,
        }
        writeln!(f, "image: {}x{}, epsilon {:e}", self.size.0, self.size.1, self.epsilon)?;
        for w in &self.warnings {
            writeln!(f, "warning: {w}")?;
        }
        Ok(())
    }
}
