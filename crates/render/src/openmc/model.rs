//! An OpenMC geometry as read from its XML: surfaces, cells, universes and
//! rectangular lattices, each with its place in the file (docs/openmc.md).
//!
//! Only reading and checking happens here; what the model means in
//! Komplex terms is [`super::emit`]'s job.

use std::collections::{BTreeMap, BTreeSet};

use super::region::{self, Expr};
use super::surface::Surface;

/// A place in the XML file: 1-based line and column.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Pos {
    /// 1-based line.
    pub line: u32,
    /// 1-based column.
    pub column: u32,
}

impl std::fmt::Display for Pos {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        write!(f, "line {}, column {}", self.line, self.column)
    }
}

/// An import error: what is wrong, and where in the file when known.
#[derive(Clone, Debug, PartialEq)]
pub struct ImportError {
    /// The place in the XML file.
    pub pos: Option<Pos>,
    /// What is wrong, naming the element (`cell 3`, `surface 7`, ...).
    pub message: String,
}

impl std::fmt::Display for ImportError {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        match self.pos {
            Some(p) => write!(f, "{p}: {}", self.message),
            None => f.write_str(&self.message),
        }
    }
}

pub(crate) fn err<T>(pos: Pos, message: impl Into<String>) -> Result<T, ImportError> {
    Err(ImportError { pos: Some(pos), message: message.into() })
}

/// What fills a cell.
#[derive(Clone, Debug, PartialEq)]
pub enum Fill {
    /// A material by id; `None` is void.
    Material(Option<u64>),
    /// A universe or a lattice by id (OpenMC shares the id space of the
    /// `fill` attribute between them), with the cell's transform.
    Fill {
        /// The universe or lattice id.
        id: u64,
        /// `translation`: the content's origin in the cell's frame.
        translation: [f64; 3],
        /// `rotation`: the matrix `M` of OpenMC's `local = M·(global − t)`.
        rotation: Option<[[f64; 3]; 3]>,
    },
}

/// A cell: its region and what fills it.
#[derive(Clone, Debug)]
pub struct Cell {
    /// OpenMC's cell id.
    pub id: u64,
    /// The universe it belongs to.
    pub universe: u64,
    /// The region; `None` is the whole universe.
    pub region: Option<Expr>,
    /// The material or the fill.
    pub fill: Fill,
    /// Where the cell is written.
    pub pos: Pos,
}

/// A rectangular lattice.
#[derive(Clone, Debug)]
pub struct Lattice {
    /// OpenMC's lattice id.
    pub id: u64,
    /// Elements along x, y, z (z is 1 for a 2-D lattice).
    pub dimension: [usize; 3],
    /// Whether the lattice is 3-D (a 2-D one leaves z alone).
    pub three_d: bool,
    /// Corner of element (0, 0, 0).
    pub lower_left: [f64; 3],
    /// Element size.
    pub pitch: [f64; 3],
    /// The universe outside the lattice's elements.
    pub outer: Option<u64>,
    /// Universe of element (ix, iy, iz) at `ix + nx·(iy + ny·iz)`, iy
    /// counted from the bottom (the file lists rows from the top).
    pub universes: Vec<u64>,
    /// Where the lattice is written.
    pub pos: Pos,
}

/// The whole geometry.
#[derive(Clone, Debug, Default)]
pub struct Model {
    /// Surfaces by id.
    pub surfaces: BTreeMap<u64, (Surface, Pos)>,
    /// Cells in file order.
    pub cells: Vec<Cell>,
    /// Rectangular lattices by id.
    pub lattices: BTreeMap<u64, Lattice>,
    /// Hexagonal lattices by id (not supported: an error where used).
    pub hex_lattices: BTreeMap<u64, Pos>,
    /// Surfaces with a boundary condition other than transmission.
    pub boundaries: BTreeMap<u64, String>,
    /// The root universe.
    pub root: u64,
    /// Valid input that may not mean what OpenMC makes of it.
    pub warnings: Vec<String>,
}

impl Model {
    /// The cells of `universe`, in file order.
    pub fn cells_of(&self, universe: u64) -> impl Iterator<Item = &Cell> {
        self.cells.iter().filter(move |c| c.universe == universe)
    }

    /// Whether `id` names a universe (has a cell).
    pub fn is_universe(&self, id: u64) -> bool {
        self.cells.iter().any(|c| c.universe == id)
    }
}

/// Attributes OpenMC reads that the import does not need.
const IGNORED: &[&str] = &["name", "temperature", "density", "volume", "albedo", "periodic_surface_id"];

struct Reader<'a> {
    doc: &'a roxmltree::Document<'a>,
}

impl<'a> Reader<'a> {
    fn pos(&self, node: roxmltree::Node) -> Pos {
        let p = self.doc.text_pos_at(node.range().start);
        Pos { line: p.row, column: p.col }
    }

    /// An attribute, or a child element of that name (OpenMC takes both).
    fn get(&self, node: roxmltree::Node<'a, 'a>, key: &str) -> Option<(String, Pos)> {
        if let Some(v) = node.attribute(key) {
            return Some((v.to_string(), self.pos(node)));
        }
        node.children()
            .find(|c| c.is_element() && c.tag_name().name() == key)
            .map(|c| (c.text().unwrap_or("").to_string(), self.pos(c)))
    }

    /// Refuses attributes and child elements the element does not have.
    fn only(&self, node: roxmltree::Node, what: &str, keys: &[&str]) -> Result<(), ImportError> {
        let known = |k: &str| keys.contains(&k) || IGNORED.contains(&k);
        let names = node
            .attributes()
            .map(|a| (a.name().to_string(), self.pos(node)))
            .chain(node.children().filter(|c| c.is_element()).map(|c| (c.tag_name().name().to_string(), self.pos(c))));
        for (name, pos) in names {
            if !known(&name) {
                let hint = crate::error::nearest(&name, keys.iter().copied())
                    .map(|n| format!(" (did you mean `{n}`?)"))
                    .unwrap_or_default();
                return err(pos, format!("{what}: unknown attribute `{name}`{hint}"));
            }
        }
        Ok(())
    }

    fn required(&self, node: roxmltree::Node<'a, 'a>, key: &str, what: &str) -> Result<(String, Pos), ImportError> {
        self.get(node, key)
            .ok_or_else(|| ImportError { pos: Some(self.pos(node)), message: format!("{what}: missing `{key}`") })
    }
}

fn id(text: &str, pos: Pos, what: &str) -> Result<u64, ImportError> {
    text.trim()
        .parse::<u64>()
        .or_else(|_| err(pos, format!("{what}: `{}` is not an id (a whole number ≥ 0)", text.trim())))
}

/// Whitespace-separated finite numbers.
pub(crate) fn numbers(text: &str, pos: Pos, what: &str) -> Result<Vec<f64>, ImportError> {
    text.split_whitespace()
        .map(|t| match t.parse::<f64>() {
            Ok(x) if x.is_finite() => Ok(x),
            _ => err(pos, format!("{what}: `{t}` is not a finite number")),
        })
        .collect()
}

fn numbers_n<const N: usize>(text: &str, pos: Pos, what: &str) -> Result<[f64; N], ImportError> {
    let v = numbers(text, pos, what)?;
    v.as_slice().try_into().or_else(|_| err(pos, format!("{what}: {N} numbers expected, got {}", v.len())))
}

/// Reads a `<geometry>` document, or the `<geometry>` of a `<model>`.
pub fn parse(text: &str) -> Result<Model, ImportError> {
    let doc = roxmltree::Document::parse(text).map_err(|e| {
        let p = e.pos();
        ImportError { pos: Some(Pos { line: p.row, column: p.col }), message: format!("not well-formed XML: {e}") }
    })?;
    let r = Reader { doc: &doc };
    let top = doc.root_element();
    let geometry = match top.tag_name().name() {
        "geometry" => top,
        "model" => top
            .children()
            .find(|c| c.is_element() && c.tag_name().name() == "geometry")
            .ok_or_else(|| ImportError { pos: Some(r.pos(top)), message: "<model> holds no <geometry>".into() })?,
        other => return err(r.pos(top), format!("expected <geometry> or <model>, found <{other}>")),
    };
    let mut model = Model::default();
    for node in geometry.children().filter(|c| c.is_element()) {
        match node.tag_name().name() {
            "surface" => surface(&r, node, &mut model)?,
            "cell" => cell(&r, node, &mut model)?,
            "lattice" => lattice(&r, node, &mut model)?,
            "hex_lattice" => {
                let (text, pos) = r.required(node, "id", "<hex_lattice>")?;
                model.hex_lattices.insert(id(&text, pos, "<hex_lattice> id")?, r.pos(node));
            }
            other => {
                return err(
                    r.pos(node),
                    format!("<geometry>: unknown element <{other}> (expected surface, cell or lattice)"),
                )
            }
        }
    }
    check_references(&mut model, r.pos(geometry))?;
    Ok(model)
}

fn surface(r: &Reader, node: roxmltree::Node, model: &mut Model) -> Result<(), ImportError> {
    r.only(node, "<surface>", &["id", "type", "coeffs", "boundary"])?;
    let (text, pos) = r.required(node, "id", "<surface>")?;
    let sid = id(&text, pos, "<surface> id")?;
    let what = format!("surface {sid}");
    let (kind, kpos) = r.required(node, "type", &what)?;
    let (coeffs, cpos) = r.get(node, "coeffs").unwrap_or_default();
    let coeffs = numbers(&coeffs, cpos, &format!("{what}: coeffs"))?;
    let surface = Surface::new(kind.trim(), &coeffs)
        .map_err(|m| ImportError { pos: Some(kpos), message: format!("{what}: {m}") })?;
    if let Some((b, bpos)) = r.get(node, "boundary") {
        let b = b.trim().to_string();
        const KINDS: &[&str] =
            &["transmission", "transmit", "vacuum", "reflective", "reflect", "reflecting", "white", "periodic"];
        if !KINDS.contains(&b.as_str()) {
            return err(
                bpos,
                format!("{what}: unknown boundary `{b}` (transmission, vacuum, reflective, white or periodic)"),
            );
        }
        if !b.starts_with("transmi") {
            model.boundaries.insert(sid, b);
        }
    }
    if model.surfaces.insert(sid, (surface, pos)).is_some() {
        return err(pos, format!("{what} is defined twice"));
    }
    Ok(())
}

fn cell(r: &Reader, node: roxmltree::Node, model: &mut Model) -> Result<(), ImportError> {
    r.only(node, "<cell>", &["id", "universe", "material", "fill", "region", "rotation", "translation"])?;
    let (text, pos) = r.required(node, "id", "<cell>")?;
    let cid = id(&text, pos, "<cell> id")?;
    let what = format!("cell {cid}");
    if model.cells.iter().any(|c| c.id == cid) {
        return err(pos, format!("{what} is defined twice"));
    }
    let universe = match r.get(node, "universe") {
        Some((t, p)) => id(&t, p, &format!("{what}: universe"))?,
        None => 0,
    };
    let region = match r.get(node, "region") {
        Some((t, p)) if !t.trim().is_empty() => {
            let (e, differs) = region::parse_noting(&t)
                .map_err(|m| ImportError { pos: Some(p), message: format!("{what}: region `{}`: {m}", t.trim()) })?;
            if differs {
                model.warnings.push(format!(
                    "{p}: {what}: region `{}`: OpenMC applies `~` to the tokens of `( … )` before intersection binds, \
                     so it reads this region otherwise than the documented precedence the import follows; \
                     add parentheses inside `~( … )` to make both agree",
                    t.trim()
                ));
            }
            Some(e)
        }
        _ => None,
    };
    let fill = match (r.get(node, "material"), r.get(node, "fill")) {
        (Some(_), Some((_, p))) => return err(p, format!("{what} has both `material` and `fill`")),
        (None, None) => return err(r.pos(node), format!("{what} has neither `material` nor `fill`")),
        (Some((m, p)), None) => {
            let m = m.trim();
            if m == "void" {
                Fill::Material(None)
            } else if m.split_whitespace().count() > 1 {
                return err(p, format!("{what}: distributed materials (`{m}`) are not supported"));
            } else {
                Fill::Material(Some(id(m, p, &format!("{what}: material"))?))
            }
        }
        (None, Some((f, p))) => {
            let translation = match r.get(node, "translation") {
                Some((t, tp)) => numbers_n::<3>(&t, tp, &format!("{what}: translation"))?,
                None => [0.0; 3],
            };
            let rotation = match r.get(node, "rotation") {
                Some((t, rp)) => Some(rotation(&numbers(&t, rp, &format!("{what}: rotation"))?, rp, &what)?),
                None => None,
            };
            Fill::Fill { id: id(&f, p, &format!("{what}: fill"))?, translation, rotation }
        }
    };
    if matches!(fill, Fill::Material(_)) {
        for key in ["translation", "rotation"] {
            if let Some((_, p)) = r.get(node, key) {
                return err(p, format!("{what}: `{key}` needs a `fill` (the cell has a material)"));
            }
        }
    }
    model.cells.push(Cell { id: cid, universe, region, fill, pos: r.pos(node) });
    Ok(())
}

/// OpenMC's rotation matrix `M` (local = M·(global − t)): from three
/// angles φ θ ψ in degrees `M = Rz(−ψ)·Ry(−θ)·Rx(−φ)`, or nine numbers row
/// by row (OpenMC's `Cell::rotation_`, src/cell.cpp).
fn rotation(v: &[f64], pos: Pos, what: &str) -> Result<[[f64; 3]; 3], ImportError> {
    match v.len() {
        3 => {
            let [phi, theta, psi] = [v[0], v[1], v[2]].map(|a| -a.to_radians());
            let (sx, cx) = phi.sin_cos();
            let (sy, cy) = theta.sin_cos();
            let (sz, cz) = psi.sin_cos();
            // Rz(ψ')·Ry(θ')·Rx(φ') with the negated angles, written out as
            // OpenMC's cell.cpp writes it.
            Ok([
                [cy * cz, -cx * sz + sx * sy * cz, sx * sz + cx * sy * cz],
                [cy * sz, cx * cz + sx * sy * sz, -sx * cz + cx * sy * sz],
                [-sy, sx * cy, cx * cy],
            ])
        }
        9 => {
            let m = [[v[0], v[1], v[2]], [v[3], v[4], v[5]], [v[6], v[7], v[8]]];
            let mt = quadric::nalgebra::Matrix3::from_fn(|i, j| m[i][j]);
            let off = (mt.transpose() * mt - quadric::nalgebra::Matrix3::identity()).abs().max();
            if off > 1e-9 {
                return err(
                    pos,
                    format!("{what}: rotation: the nine numbers are not a rotation matrix (MᵀM − I is {off:.2e} off)"),
                );
            }
            Ok(m)
        }
        n => err(pos, format!("{what}: rotation: 3 angles or 9 matrix entries expected, got {n} numbers")),
    }
}

fn lattice(r: &Reader, node: roxmltree::Node, model: &mut Model) -> Result<(), ImportError> {
    r.only(node, "<lattice>", &["id", "dimension", "lower_left", "pitch", "outer", "universes"])?;
    let (text, pos) = r.required(node, "id", "<lattice>")?;
    let lid = id(&text, pos, "<lattice> id")?;
    let what = format!("lattice {lid}");
    let (t, p) = r.required(node, "dimension", &what)?;
    let dims = numbers(&t, p, &format!("{what}: dimension"))?;
    let three_d = match dims.len() {
        2 => false,
        3 => true,
        n => return err(p, format!("{what}: dimension: 2 or 3 numbers expected, got {n}")),
    };
    if dims.iter().any(|d| *d < 1.0 || d.fract() != 0.0 || *d > 1e6) {
        return err(p, format!("{what}: dimension: whole numbers from 1 to 10⁶ expected"));
    }
    let dimension = [dims[0] as usize, dims[1] as usize, if three_d { dims[2] as usize } else { 1 }];
    let axes = if three_d { 3 } else { 2 };
    let vector = |key: &str| -> Result<[f64; 3], ImportError> {
        let (t, p) = r.required(node, key, &what)?;
        let v = numbers(&t, p, &format!("{what}: {key}"))?;
        if v.len() != axes {
            return err(p, format!("{what}: {key}: {axes} numbers expected (as `dimension`), got {}", v.len()));
        }
        Ok([v[0], v[1], if three_d { v[2] } else { 0.0 }])
    };
    let lower_left = vector("lower_left")?;
    let pitch = vector("pitch")?;
    if pitch[..axes].iter().any(|x| *x <= 0.0) {
        let (_, p) = r.required(node, "pitch", &what)?;
        return err(p, format!("{what}: pitch: every entry must be positive"));
    }
    let outer = match r.get(node, "outer") {
        Some((t, p)) => Some(id(&t, p, &format!("{what}: outer"))?),
        None => None,
    };
    let (t, p) = r.required(node, "universes", &what)?;
    let listed: Vec<u64> =
        t.split_whitespace().map(|u| id(u, p, &format!("{what}: universes"))).collect::<Result<_, _>>()?;
    let [nx, ny, nz] = dimension;
    if listed.len() != nx * ny * nz {
        return err(p, format!("{what}: universes: {} entries for {nx} × {ny} × {nz} elements", listed.len()));
    }
    // The file lists x fastest, rows from the top (largest y) down, z
    // layers from the bottom up.
    let mut universes = vec![0; listed.len()];
    for iz in 0..nz {
        for row in 0..ny {
            for ix in 0..nx {
                let iy = ny - 1 - row;
                universes[ix + nx * (iy + ny * iz)] = listed[ix + nx * (row + ny * iz)];
            }
        }
    }
    if model
        .lattices
        .insert(lid, Lattice { id: lid, dimension, three_d, lower_left, pitch, outer, universes, pos: r.pos(node) })
        .is_some()
    {
        return err(pos, format!("{what} is defined twice"));
    }
    Ok(())
}

/// Checks that every surface, universe and lattice referred to exists,
/// that nothing fills itself, and finds the root universe.
fn check_references(model: &mut Model, pos: Pos) -> Result<(), ImportError> {
    if model.cells.is_empty() {
        return err(pos, "<geometry> has no cells");
    }
    let universes: BTreeSet<u64> = model.cells.iter().map(|c| c.universe).collect();
    let mut used = BTreeSet::new();
    for c in &model.cells {
        if let Some(e) = &c.region {
            for s in e.surfaces() {
                if !model.surfaces.contains_key(&s) {
                    let hint = nearest_id(s, model.surfaces.keys().copied());
                    return err(c.pos, format!("cell {}: region: surface {s} is not defined{hint}", c.id));
                }
            }
        }
        if let Fill::Fill { id, .. } = c.fill {
            let is_u = universes.contains(&id);
            let is_l = model.lattices.contains_key(&id) || model.hex_lattices.contains_key(&id);
            match (is_u, is_l) {
                (true, true) => {
                    return err(c.pos, format!("cell {}: fill {id} names both a universe and a lattice", c.id))
                }
                (false, false) => {
                    return err(c.pos, format!("cell {}: fill {id} is neither a universe nor a lattice", c.id))
                }
                _ => {}
            }
            if let Some(p) = model.hex_lattices.get(&id) {
                return err(
                    *p,
                    format!("lattice {id}: hexagonal lattices are not supported yet (filling cell {})", c.id),
                );
            }
            used.insert(id);
        }
    }
    for l in model.lattices.values() {
        for u in l.universes.iter().chain(l.outer.iter()) {
            if !universes.contains(u) {
                return err(l.pos, format!("lattice {}: universe {u} has no cells", l.id));
            }
            used.insert(*u);
        }
    }
    let roots: Vec<u64> = universes.iter().copied().filter(|u| !used.contains(u)).collect();
    model.root = match roots.as_slice() {
        [root] => *root,
        [] => return err(pos, "every universe fills something: no root universe (a cycle of fills?)"),
        many => {
            let list: Vec<String> = many.iter().map(|u| u.to_string()).collect();
            return err(
                pos,
                format!("more than one universe fills nothing, so the root is ambiguous: {}", list.join(", ")),
            );
        }
    };
    Ok(())
}

fn nearest_id(given: u64, ids: impl Iterator<Item = u64>) -> String {
    let ids: Vec<String> = ids.map(|i| i.to_string()).collect();
    let g = given.to_string();
    crate::error::nearest(&g, ids.iter().map(|s| s.as_str()))
        .map(|n| format!(" (did you mean {n}?)"))
        .unwrap_or_default()
}
