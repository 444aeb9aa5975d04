//! An OpenMC model as Komplex scene entries (docs/openmc.md, "How a model
//! maps"): one transparent block per intersection term of a material
//! cell, in the universe's cell order, so that the priority rule
//! (docs/model.md §3.4) is OpenMC's first match; a filled cell becomes a
//! group moved by the fill's transform whose blocks also carry the cell's
//! term; a lattice element becomes an instance of a definition, shared by
//! every element whose content and clipping are the same in its own frame.

use std::collections::{BTreeMap, HashMap};

use quadric::nalgebra::{Matrix3, Vector3};

use super::model::{err, Fill, ImportError, Lattice, Model};
use super::surface::{Motion, Shape, Side, Surface};
use crate::format::{DefinitionSpec, Entry, Step};

/// What the emission built.
pub struct Emitted {
    /// The root universe's entries.
    pub blocks: Vec<Entry>,
    /// The definitions the lattice elements place.
    pub definitions: BTreeMap<String, DefinitionSpec>,
    /// Material ids used (`None` = void), in first-use order.
    pub materials: Vec<Option<u64>>,
}

/// The material's name in the scene.
pub fn material_name(m: Option<u64>) -> String {
    match m {
        Some(id) => format!("material {id}"),
        None => "void".to_string(),
    }
}

struct Emitter<'m> {
    model: &'m Model,
    definitions: BTreeMap<String, DefinitionSpec>,
    /// Definition by content key: universe and clipping in its frame.
    shared: HashMap<String, Option<String>>,
    materials: Vec<Option<u64>>,
    /// The universes being emitted, outermost first (to name a cycle).
    stack: Vec<u64>,
    /// The cell whose fill is being emitted (to place a cycle).
    via: Option<(u64, super::model::Pos)>,
}

/// Emits the model's root universe.
pub fn emit(model: &Model) -> Result<Emitted, ImportError> {
    let mut e = Emitter {
        model,
        definitions: BTreeMap::new(),
        shared: HashMap::new(),
        materials: Vec::new(),
        stack: vec![],
        via: None,
    };
    let blocks = e.universe(model.root, &[])?;
    if blocks.is_empty() {
        let pos = model.cells_of(model.root).next().map(|c| c.pos);
        return Err(ImportError {
            pos,
            message: format!("root universe {}: no cell with a non-empty region", model.root),
        });
    }
    Ok(Emitted { blocks, definitions: e.definitions, materials: e.materials })
}

impl Emitter<'_> {
    /// The entries of universe `u` clipped by `clip` (in `u`'s frame).
    fn universe(&mut self, u: u64, clip: &[Side]) -> Result<Vec<Entry>, ImportError> {
        if let Some(i) = self.stack.iter().position(|x| *x == u) {
            let cycle: Vec<String> = self.stack[i..].iter().chain([&u]).map(|x| format!("universe {x}")).collect();
            let (pos, by) = match self.via {
                Some((cell, pos)) => (Some(pos), format!("cell {cell}: ")),
                None => (None, String::new()),
            };
            return Err(ImportError { pos, message: format!("{by}fills form a cycle: {}", cycle.join(" → ")) });
        }
        self.stack.push(u);
        let model = self.model;
        let mut out = Vec::new();
        for cell in model.cells_of(u) {
            let what = format!("cell {}", cell.id);
            let terms = match &cell.region {
                None => vec![vec![]],
                Some(e) => e
                    .terms()
                    .map_err(|m| ImportError { pos: Some(cell.pos), message: format!("{what}: region: {m}") })?,
            };
            for term in terms {
                let mut sides = Vec::with_capacity(term.len() + clip.len());
                for (s, positive) in term {
                    let (surface, _) = &model.surfaces[&s];
                    let shape = match surface {
                        Surface::Plane { n, d } => Shape::Plane((*n).into(), *d),
                        Surface::Quadric(f) => Shape::Quadric(*f),
                        Surface::Unsupported(kind) => {
                            return err(
                                cell.pos,
                                format!("{what}: surface {s} is a {kind}, not a quadric: not supported yet"),
                            )
                        }
                    };
                    sides.push(Side { shape, positive });
                }
                sides.extend_from_slice(clip);
                match &cell.fill {
                    Fill::Material(m) => {
                        if sides.is_empty() {
                            return err(
                                cell.pos,
                                format!(
                                    "{what} has no region and nothing around it clips it: it would fill all of space"
                                ),
                            );
                        }
                        // A term the clipping leaves nothing of (the kernel
                        // proves it empty) makes no block.
                        if kernel_box(&sides).is_ok_and(|b| b.is_empty()) {
                            continue;
                        }
                        if !self.materials.contains(m) {
                            self.materials.push(*m);
                        }
                        out.push(Entry {
                            name: Some(what.clone()),
                            material: Some(material_name(*m)),
                            transparent: Some(true),
                            objects: Some(sides.iter().map(Side::object).collect()),
                            ..Entry::default()
                        });
                    }
                    Fill::Fill { id, translation, rotation } => {
                        // OpenMC: local = M·(global − t), so global = Mᵀ·local + t.
                        let r = rotation.map_or_else(Matrix3::identity, |m| Matrix3::from_fn(|i, j| m[j][i]));
                        let motion = Motion { r, t: Vector3::from(*translation) };
                        let inner: Vec<Side> = sides.iter().map(|s| s.in_child(&motion)).collect();
                        self.via = Some((cell.id, cell.pos));
                        let blocks = match model.lattices.get(id) {
                            Some(l) => self.lattice(l, &inner)?,
                            None => self.universe(*id, &inner)?,
                        };
                        if !blocks.is_empty() {
                            out.push(Entry {
                                group: Some(what.clone()),
                                blocks: Some(blocks),
                                transform: steps(&motion),
                                ..Entry::default()
                            });
                        }
                    }
                }
            }
        }
        self.stack.pop();
        Ok(out)
    }

    /// The entries of a lattice clipped by `clip` (in the lattice's frame):
    /// an instance per element that the clipping does not miss, then the
    /// outer universe outside the elements: once, in slabs around the
    /// lattice, when all its cells are region-less material cells (it is
    /// then the same in every virtual element); else tiled, one instance
    /// per virtual element that meets the clipping's bounds.
    fn lattice(&mut self, l: &Lattice, clip: &[Side]) -> Result<Vec<Entry>, ImportError> {
        let model = self.model;
        let axes = if l.three_d { 3 } else { 2 };
        let n = l.dimension.map(|d| d as i64);
        let uniform_outer =
            l.outer.filter(|o| model.cells_of(*o).all(|c| c.region.is_none() && matches!(c.fill, Fill::Material(_))));
        // The index range: the lattice's own, or the virtual elements that
        // the clipping's box meets when a tiled outer universe fills them.
        let mut range = [(0, n[0]), (0, n[1]), (0, n[2])];
        if let (Some(outer), None) = (l.outer, uniform_outer) {
            let (lo, hi) = bounds(clip)
                .map_err(|m| ImportError { pos: Some(l.pos), message: format!("lattice {}: {m}", l.id) })?;
            let empty = (0..3).any(|i| lo[i] > hi[i]);
            let mut count: i64 = 1;
            for i in (0..axes).filter(|_| !empty) {
                if !(lo[i].is_finite() && hi[i].is_finite()) {
                    return err(
                        l.pos,
                        format!(
                            "lattice {}: outer universe {outer} has cells with regions, so it is tiled, but the cell \
                             the lattice fills is unbounded along {}: the tiling would not end",
                            l.id,
                            ["x", "y", "z"][i]
                        ),
                    );
                }
                let first = ((lo[i] - l.lower_left[i]) / l.pitch[i]).floor() as i64;
                let last = ((hi[i] - l.lower_left[i]) / l.pitch[i]).floor() as i64;
                range[i] = (first.min(0), (last + 1).max(n[i]));
                count = count.saturating_mul(range[i].1 - range[i].0);
            }
            if count > MAX_TILED {
                return err(
                    l.pos,
                    format!("lattice {}: tiling outer universe {outer} over the filled cell takes {count} elements, more than {MAX_TILED}", l.id),
                );
            }
        }
        let half = Vector3::from_fn(|i, _| if i == 2 && !l.three_d { f64::INFINITY } else { l.pitch[i] / 2.0 });
        let mut out = Vec::new();
        for iz in range[2].0..range[2].1 {
            for iy in range[1].0..range[1].1 {
                for ix in range[0].0..range[0].1 {
                    let index = [ix, iy, iz];
                    let inside = (0..3).all(|i| (0..n[i]).contains(&index[i]));
                    let u = match (inside, l.outer) {
                        (true, _) => l.universes[(ix + n[0] * (iy + n[1] * iz)) as usize],
                        (false, Some(outer)) => outer,
                        (false, None) => continue,
                    };
                    let centre = Vector3::from_fn(|i, _| {
                        if i == 2 && !l.three_d {
                            0.0
                        } else {
                            l.lower_left[i] + (index[i] as f64 + 0.5) * l.pitch[i]
                        }
                    });
                    let motion = Motion::translation(centre);
                    let mut sides = element_box(&half);
                    let mut missed = false;
                    for s in clip {
                        let s = s.in_child(&motion);
                        if s.misses_box(&half) {
                            missed = true;
                            break;
                        }
                        if !s.holds_box(&half) {
                            sides.push(s);
                        }
                    }
                    if missed {
                        continue;
                    }
                    if let Some(name) = self.definition(u, l.id, &sides)? {
                        out.push(Entry { instance: Some(name), transform: steps(&motion), ..Entry::default() });
                    }
                }
            }
        }
        if let Some(outer) = uniform_outer {
            // The space around the elements, as disjoint slabs, each
            // clipped as the lattice is.
            let lo = Vector3::from(l.lower_left);
            let hi = Vector3::from_fn(|i, _| l.lower_left[i] + l.dimension[i] as f64 * l.pitch[i]);
            for axis in 0..axes {
                for below in [true, false] {
                    let mut sides: Vec<Side> = (0..axis).flat_map(|i| slab(i, lo[i], hi[i])).collect();
                    sides.push(if below { plane(axis, 1.0, -lo[axis]) } else { plane(axis, -1.0, hi[axis]) });
                    sides.extend_from_slice(clip);
                    out.extend(self.universe(outer, &sides)?);
                }
            }
        }
        Ok(out)
    }

    /// The name of the definition holding universe `u` clipped by `clip`
    /// (in `u`'s frame), made on first use; `None` if nothing of it is left.
    fn definition(&mut self, u: u64, lattice: u64, clip: &[Side]) -> Result<Option<String>, ImportError> {
        let key = format!("{u} {clip:?}");
        if let Some(name) = self.shared.get(&key) {
            return Ok(name.clone());
        }
        let blocks = self.universe(u, clip)?;
        let name = (!blocks.is_empty()).then(|| {
            let base = format!("universe {u} in lattice {lattice}");
            let mut name = base.clone();
            let mut n = 1;
            while self.definitions.contains_key(&name) {
                n += 1;
                name = format!("{base} #{n}");
            }
            self.definitions.insert(name.clone(), DefinitionSpec { blocks });
            name
        });
        self.shared.insert(key, name.clone());
        Ok(name)
    }
}

/// Most virtual elements a tiled outer universe may take.
const MAX_TILED: i64 = 1 << 20;

/// The box of the intersection of `sides`, by the kernel
/// (`Complex::block_aabb`): infinite on an unbounded axis, empty when the
/// kernel proves the intersection empty.
fn bounds(sides: &[Side]) -> Result<([f64; 3], [f64; 3]), String> {
    let b = kernel_box(sides)?;
    Ok((b.min.into(), b.max.into()))
}

fn kernel_box(sides: &[Side]) -> Result<complex::Aabb, String> {
    if sides.is_empty() {
        return Ok(complex::Aabb::INFINITE);
    }
    let solids = sides
        .iter()
        .map(|s| crate::flatten::object_solid(&s.object()).map_err(|e| e.to_string()))
        .collect::<Result<Vec<_>, _>>()?;
    let block = complex::Block::new("bounds", solids, complex::Opacity::Transparent, complex::MaterialKey(0))
        .map_err(|e| e.to_string())?;
    let one = complex::Complex::new(vec![block], complex::ComplexOptions::default()).map_err(|e| e.to_string())?;
    Ok(one.block_aabb(complex::BlockId(0)))
}

/// The plane side `s·x_axis + d ≤ 0`.
fn plane(axis: usize, s: f64, d: f64) -> Side {
    let mut n = Vector3::zeros();
    n[axis] = s;
    Side { shape: Shape::Plane(n, d), positive: false }
}

/// `lo ≤ x_axis ≤ hi`.
fn slab(axis: usize, lo: f64, hi: f64) -> [Side; 2] {
    [plane(axis, -1.0, lo), plane(axis, 1.0, -hi)]
}

/// The element box `[−h, h]` on its bounded axes.
fn element_box(h: &Vector3<f64>) -> Vec<Side> {
    (0..3).filter(|i| h[*i].is_finite()).flat_map(|i| slab(i, -h[i], h[i])).collect()
}

/// The scene steps of a motion.
fn steps(m: &Motion) -> Vec<Step> {
    if m.is_translation() {
        if m.t == Vector3::zeros() {
            vec![]
        } else {
            vec![Step::Translate(m.t.into())]
        }
    } else {
        let r = &m.r;
        vec![Step::Matrix(Box::new([
            [r[(0, 0)], r[(0, 1)], r[(0, 2)], m.t[0]],
            [r[(1, 0)], r[(1, 1)], r[(1, 2)], m.t[1]],
            [r[(2, 0)], r[(2, 1)], r[(2, 2)], m.t[2]],
            [0.0, 0.0, 0.0, 1.0],
        ]))]
    }
}
