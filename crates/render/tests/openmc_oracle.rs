//! An independent OpenMC point evaluator (a test oracle for `import-openmc`).
//!
//! It answers "which OpenMC cell owns point p?" directly from `geometry.xml`,
//! following OpenMC's find_cell (openmc-dev/openmc 3f06a42a, src/geometry.cpp
//! `find_cell_inner`). Plain code on purpose: readability beats speed.
//!
//! Semantics (checked against OpenMC's C++ source):
//! - surface f(p) from the coefficients as in src/surface.cpp `evaluate`;
//!   `-id` is f < 0, `+id` / `id` is f > 0 (points on a surface: f == 0 is
//!   "outside" both; tests avoid boundaries).
//! - regions: `|` union, whitespace intersection, `~` complement, parentheses;
//!   precedence () > ~ > intersection > union; evaluated by recursive descent
//!   straight to a boolean. No region = everything.
//! - fills: local = M·(global − t), M row-major (src/position.h `rotate`);
//!   for `rotation="φ θ ψ"` (degrees) M = Rz(−ψ)·Ry(−θ)·Rx(−φ)
//!   (src/cell.cpp `Cell::set_rotation`); 9 numbers are M itself, row-major.
//!   The same transform is applied when the fill is a lattice.
//! - rectangular lattices: index = floor((r − lower_left)/pitch), local
//!   position relative to the element centre (also for the `outer` universe
//!   outside the index range); universes are listed x fastest, rows from the
//!   top (largest y) down, z layers from the bottom (src/lattice.cpp).

use std::collections::{HashMap, HashSet};

/// A parsed OpenMC geometry, ready for point queries.
#[derive(Clone, Debug)]
pub struct Geometry {
    surfaces: HashMap<u64, Surface>,
    /// All cells in file order.
    cells: Vec<Cell>,
    /// Universe id -> indices into `cells`, in file order.
    universes: HashMap<u64, Vec<usize>>,
    lattices: HashMap<u64, Lattice>,
    root: u64,
}

/// Where a point is: the leaf cell (the cell with a material, possibly
/// "void") and that cell's material (None = void).
#[derive(Clone, Debug, PartialEq)]
pub struct Owner {
    pub cell: u64,
    pub material: Option<u64>,
}

/// One level of the path from the root universe to the leaf cell.
#[derive(Clone, Debug, PartialEq)]
pub struct Level {
    pub cell: u64,
    /// Indices (ix, iy, iz) in the lattice this cell is filled with, if any
    /// (iz = 0 for a 2D lattice; may be outside the lattice when `outer` is used).
    pub lattice_index: Option<[i64; 3]>,
}

#[derive(Clone, Debug)]
struct Surface {
    kind: String,
    c: Vec<f64>,
}

#[derive(Clone, Debug, PartialEq)]
enum Tok {
    Half(i64),
    Or,
    Not,
    LParen,
    RParen,
}

#[derive(Clone, Debug)]
enum Fill {
    Material(Option<u64>),
    Universe(u64),
    Lattice(u64),
}

#[derive(Clone, Debug)]
struct Cell {
    id: u64,
    universe: u64,
    fill: Fill,
    region: Vec<Tok>,
    translation: [f64; 3],
    /// Row-major M of local = M·(global − translation).
    rotation: Option<[f64; 9]>,
}

#[derive(Clone, Debug)]
struct Lattice {
    n: [i64; 3],
    is_3d: bool,
    lower_left: [f64; 3],
    pitch: [f64; 3],
    outer: Option<u64>,
    /// Universe ids indexed by ix + nx*iy + nx*ny*iz with iy counted from the BOTTOM.
    universes: Vec<u64>,
}

// ---------------------------------------------------------------- surfaces

impl Surface {
    fn new(kind: &str, c: Vec<f64>, id: u64) -> Result<Surface, String> {
        let want = match kind {
            "x-plane" | "y-plane" | "z-plane" => 1,
            "plane" => 4,
            "x-cylinder" | "y-cylinder" | "z-cylinder" => 3,
            "sphere" | "x-cone" | "y-cone" | "z-cone" => 4,
            "quadric" => 10,
            other => return Err(format!("surface {id}: unsupported type {other:?}")),
        };
        if c.len() != want {
            return Err(format!("surface {id}: {kind} needs {want} coefficients, got {}", c.len()));
        }
        Ok(Surface { kind: kind.to_string(), c })
    }

    /// f(p) exactly as OpenMC's `evaluate` (src/surface.cpp).
    fn f(&self, p: [f64; 3]) -> f64 {
        let [x, y, z] = p;
        let c = &self.c;
        match self.kind.as_str() {
            "x-plane" => x - c[0],
            "y-plane" => y - c[0],
            "z-plane" => z - c[0],
            // plane A B C D: Ax + By + Cz - D
            "plane" => c[0] * x + c[1] * y + c[2] * z - c[3],
            // x-cylinder y0 z0 R
            "x-cylinder" => (y - c[0]).powi(2) + (z - c[1]).powi(2) - c[2] * c[2],
            // y-cylinder x0 z0 R
            "y-cylinder" => (x - c[0]).powi(2) + (z - c[1]).powi(2) - c[2] * c[2],
            // z-cylinder x0 y0 R
            "z-cylinder" => (x - c[0]).powi(2) + (y - c[1]).powi(2) - c[2] * c[2],
            // sphere x0 y0 z0 R
            "sphere" => (x - c[0]).powi(2) + (y - c[1]).powi(2) + (z - c[2]).powi(2) - c[3] * c[3],
            // cones x0 y0 z0 R2 (R2 = squared tangent of the half angle; both nappes)
            "x-cone" => (y - c[1]).powi(2) + (z - c[2]).powi(2) - c[3] * (x - c[0]).powi(2),
            "y-cone" => (x - c[0]).powi(2) + (z - c[2]).powi(2) - c[3] * (y - c[1]).powi(2),
            "z-cone" => (x - c[0]).powi(2) + (y - c[1]).powi(2) - c[3] * (z - c[2]).powi(2),
            // quadric A B C D E F G H J K:
            // Ax² + By² + Cz² + Dxy + Eyz + Fxz + Gx + Hy + Jz + K
            "quadric" => {
                c[0] * x * x
                    + c[1] * y * y
                    + c[2] * z * z
                    + c[3] * x * y
                    + c[4] * y * z
                    + c[5] * x * z
                    + c[6] * x
                    + c[7] * y
                    + c[8] * z
                    + c[9]
            }
            _ => f64::NAN, // unreachable: `new` rejects other kinds
        }
    }
}

// ---------------------------------------------------------------- regions

fn tokenize(spec: &str, cell: u64) -> Result<Vec<Tok>, String> {
    let b = spec.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let ch = b[i];
        match ch {
            b'(' => out.push(Tok::LParen),
            b')' => out.push(Tok::RParen),
            b'|' => out.push(Tok::Or),
            b'~' => out.push(Tok::Not),
            b'+' | b'-' | b'0'..=b'9' => {
                let mut j = i + 1;
                while j < b.len() && b[j].is_ascii_digit() {
                    j += 1;
                }
                let text = &spec[i..j];
                let v: i64 =
                    text.trim_start_matches('+').parse().map_err(|_| format!("cell {cell}: bad halfspace {text:?}"))?;
                if v == 0 {
                    return Err(format!("cell {cell}: halfspace 0"));
                }
                out.push(Tok::Half(v));
                i = j;
                continue;
            }
            c if c.is_ascii_whitespace() => {}
            c => return Err(format!("cell {cell}: invalid character {:?} in region", c as char)),
        }
        i += 1;
    }
    Ok(out)
}

/// Recursive-descent evaluation of a region token list straight to a boolean.
/// union := inter ('|' inter)* ; inter := unary unary* ; unary := '~' unary | atom ;
/// atom := halfspace | '(' union ')'.
struct Eval<'a> {
    toks: &'a [Tok],
    pos: usize,
    half: &'a dyn Fn(i64) -> Result<bool, String>,
}

impl Eval<'_> {
    fn union(&mut self) -> Result<bool, String> {
        let mut v = self.inter()?;
        while self.toks.get(self.pos) == Some(&Tok::Or) {
            self.pos += 1;
            let w = self.inter()?; // always evaluate: keeps the parse simple
            v = v || w;
        }
        Ok(v)
    }
    fn inter(&mut self) -> Result<bool, String> {
        let mut v = self.unary()?;
        while matches!(self.toks.get(self.pos), Some(Tok::Half(_) | Tok::Not | Tok::LParen)) {
            let w = self.unary()?;
            v = v && w;
        }
        Ok(v)
    }
    fn unary(&mut self) -> Result<bool, String> {
        match self.toks.get(self.pos) {
            Some(Tok::Not) => {
                self.pos += 1;
                Ok(!self.unary()?)
            }
            Some(Tok::Half(h)) => {
                let h = *h;
                self.pos += 1;
                (self.half)(h)
            }
            Some(Tok::LParen) => {
                self.pos += 1;
                let v = self.union()?;
                if self.toks.get(self.pos) != Some(&Tok::RParen) {
                    return Err("missing ')'".to_string());
                }
                self.pos += 1;
                Ok(v)
            }
            other => Err(format!("unexpected {other:?} in region")),
        }
    }
}

fn eval_region(toks: &[Tok], half: &dyn Fn(i64) -> Result<bool, String>) -> Result<bool, String> {
    if toks.is_empty() {
        return Ok(true);
    }
    let mut e = Eval { toks, pos: 0, half };
    let v = e.union()?;
    if e.pos != toks.len() {
        return Err(format!("trailing {:?} in region", toks[e.pos]));
    }
    Ok(v)
}

// ---------------------------------------------------------------- XML helpers

/// An attribute, or else a child element's text (OpenMC's `get_node_value`:
/// the attribute wins).
fn value<'a>(node: roxmltree::Node<'a, '_>, name: &str) -> Option<&'a str> {
    if let Some(v) = node.attribute(name) {
        return Some(v);
    }
    node.children().find(|c| c.is_element() && c.has_tag_name(name)).map(|c| c.text().unwrap_or(""))
}

fn floats(s: &str, what: &str) -> Result<Vec<f64>, String> {
    s.split_whitespace().map(|w| w.parse::<f64>().map_err(|_| format!("{what}: bad number {w:?}"))).collect()
}

fn int(s: &str, what: &str) -> Result<u64, String> {
    s.trim().parse::<u64>().map_err(|_| format!("{what}: bad integer {s:?}"))
}

fn required<'a>(node: roxmltree::Node<'a, '_>, name: &str, what: &str) -> Result<&'a str, String> {
    value(node, name).ok_or_else(|| format!("{what}: missing {name}"))
}

/// Row-major M for `rotation="φ θ ψ"`, transcribed from src/cell.cpp
/// `Cell::set_rotation` (angles negated there): M = Rz(−ψ)·Ry(−θ)·Rx(−φ).
fn rotation_from_angles(deg: [f64; 3]) -> [f64; 9] {
    let phi = -deg[0].to_radians();
    let theta = -deg[1].to_radians();
    let psi = -deg[2].to_radians();
    let (sf, cf) = phi.sin_cos();
    let (st, ct) = theta.sin_cos();
    let (sp, cp) = psi.sin_cos();
    [
        ct * cp,
        -cf * sp + sf * st * cp,
        sf * sp + cf * st * cp,
        ct * sp,
        cf * cp + sf * st * sp,
        -sf * cp + cf * st * sp,
        -st,
        sf * ct,
        cf * ct,
    ]
}

// ---------------------------------------------------------------- Geometry

impl Geometry {
    /// Parses `<geometry>` or `<model>` (with `<geometry>` inside) text.
    pub fn parse(xml: &str) -> Result<Geometry, String> {
        let doc = roxmltree::Document::parse(xml).map_err(|e| format!("XML: {e}"))?;
        let top = doc.root_element();
        let geo = if top.has_tag_name("geometry") {
            top
        } else if top.has_tag_name("model") {
            top.children().find(|c| c.is_element() && c.has_tag_name("geometry")).ok_or("<model> without <geometry>")?
        } else {
            return Err(format!("root element <{}> is neither <geometry> nor <model>", top.tag_name().name()));
        };

        let mut surfaces = HashMap::new();
        let mut cells = Vec::new();
        let mut lattices = HashMap::new();
        let mut fill_ids = Vec::new(); // (cell index, raw fill id)

        for node in geo.children().filter(|n| n.is_element()) {
            match node.tag_name().name() {
                "surface" => {
                    let id = int(required(node, "id", "surface")?, "surface id")?;
                    let what = format!("surface {id}");
                    let kind = required(node, "type", &what)?.trim().to_string();
                    let c = floats(required(node, "coeffs", &what)?, &what)?;
                    if surfaces.insert(id, Surface::new(&kind, c, id)?).is_some() {
                        return Err(format!("duplicate surface {id}"));
                    }
                }
                "cell" => {
                    let id = int(required(node, "id", "cell")?, "cell id")?;
                    let what = format!("cell {id}");
                    let universe = match value(node, "universe") {
                        Some(u) => int(u, &what)?,
                        None => 0,
                    };
                    let fill = match (value(node, "fill"), value(node, "material")) {
                        (Some(f), None) => {
                            fill_ids.push((cells.len(), int(f, &what)?));
                            Fill::Universe(0) // resolved below
                        }
                        (None, Some(m)) => {
                            let words: Vec<&str> = m.split_whitespace().collect();
                            match words.as_slice() {
                                [w] if w.eq_ignore_ascii_case("void") => Fill::Material(None),
                                [w] => Fill::Material(Some(int(w, &what)?)),
                                _ => {
                                    return Err(format!(
                                        "{what}: material must be one id or void (distributed materials not supported)"
                                    ))
                                }
                            }
                        }
                        _ => return Err(format!("{what}: needs exactly one of fill and material")),
                    };
                    let region = tokenize(value(node, "region").unwrap_or(""), id)?;
                    let translation = match value(node, "translation") {
                        Some(t) => match floats(t, &what)?.as_slice() {
                            [a, b, c] => [*a, *b, *c],
                            _ => return Err(format!("{what}: translation needs 3 numbers")),
                        },
                        None => [0.0; 3],
                    };
                    let rotation = match value(node, "rotation") {
                        Some(r) => {
                            let v = floats(r, &what)?;
                            match v.len() {
                                3 => Some(rotation_from_angles([v[0], v[1], v[2]])),
                                9 => {
                                    let mut m = [0.0; 9];
                                    m.copy_from_slice(&v);
                                    Some(m)
                                }
                                _ => return Err(format!("{what}: rotation needs 3 or 9 numbers")),
                            }
                        }
                        None => None,
                    };
                    if matches!(fill, Fill::Material(_)) && (value(node, "translation").is_some() || rotation.is_some())
                    {
                        return Err(format!("{what}: translation/rotation on a material cell"));
                    }
                    cells.push(Cell { id, universe, fill, region, translation, rotation });
                }
                "lattice" => {
                    let id = int(required(node, "id", "lattice")?, "lattice id")?;
                    let what = format!("lattice {id}");
                    let dim: Vec<i64> = required(node, "dimension", &what)?
                        .split_whitespace()
                        .map(|w| w.parse::<i64>().map_err(|_| format!("{what}: bad dimension {w:?}")))
                        .collect::<Result<_, _>>()?;
                    let nd = dim.len();
                    if !(nd == 2 || nd == 3) || dim.iter().any(|&d| d < 1) {
                        return Err(format!("{what}: dimension must be 2 or 3 positive numbers"));
                    }
                    let ll = floats(required(node, "lower_left", &what)?, &what)?;
                    let pitch = floats(required(node, "pitch", &what)?, &what)?;
                    if ll.len() != nd || pitch.len() != nd {
                        return Err(format!("{what}: lower_left/pitch must have {nd} numbers"));
                    }
                    let outer = match value(node, "outer") {
                        Some(o) => Some(int(o, &what)?),
                        None => None,
                    };
                    let n = [dim[0], dim[1], if nd == 3 { dim[2] } else { 1 }];
                    let listed: Vec<u64> = required(node, "universes", &what)?
                        .split_whitespace()
                        .map(|w| int(w, &what))
                        .collect::<Result<_, _>>()?;
                    if listed.len() as i64 != n[0] * n[1] * n[2] {
                        return Err(format!("{what}: expected {} universes, got {}", n[0] * n[1] * n[2], listed.len()));
                    }
                    // File order: z layers from the bottom; within a layer rows from
                    // the TOP (largest y) down; x fastest. Store with iy from the bottom.
                    let mut universes = vec![0; listed.len()];
                    for iz in 0..n[2] {
                        for row in 0..n[1] {
                            for ix in 0..n[0] {
                                let iy = n[1] - 1 - row;
                                let file = (iz * n[0] * n[1] + row * n[0] + ix) as usize;
                                let ours = (iz * n[0] * n[1] + iy * n[0] + ix) as usize;
                                universes[ours] = listed[file];
                            }
                        }
                    }
                    let lat = Lattice {
                        n,
                        is_3d: nd == 3,
                        lower_left: [ll[0], ll[1], if nd == 3 { ll[2] } else { 0.0 }],
                        pitch: [pitch[0], pitch[1], if nd == 3 { pitch[2] } else { 1.0 }],
                        outer,
                        universes,
                    };
                    if lattices.insert(id, lat).is_some() {
                        return Err(format!("duplicate lattice {id}"));
                    }
                }
                "hex_lattice" => return Err("hex lattice not supported by the oracle".to_string()),
                _ => {}
            }
        }

        let mut universes: HashMap<u64, Vec<usize>> = HashMap::new();
        for (i, c) in cells.iter().enumerate() {
            universes.entry(c.universe).or_default().push(i);
        }
        // Resolve fills like OpenMC's adjust_indices: a universe first, then a lattice.
        for (i, f) in fill_ids {
            cells[i].fill = if universes.contains_key(&f) {
                Fill::Universe(f)
            } else if lattices.contains_key(&f) {
                Fill::Lattice(f)
            } else {
                return Err(format!("cell {}: fill {f} is neither a universe nor a lattice", cells[i].id));
            };
        }
        // Every halfspace must name a known surface; every region must parse.
        for c in &cells {
            let check = |h: i64| -> Result<bool, String> {
                if surfaces.contains_key(&h.unsigned_abs()) {
                    Ok(true)
                } else {
                    Err(format!("unknown surface {}", h.unsigned_abs()))
                }
            };
            eval_region(&c.region, &check).map_err(|e| format!("cell {}: {e}", c.id))?;
        }
        // Root universe: the only universe never used as a fill, lattice entry or outer.
        let mut used = HashSet::new();
        for c in &cells {
            if let Fill::Universe(u) = c.fill {
                used.insert(u);
            }
        }
        for lat in lattices.values() {
            used.extend(lat.universes.iter().copied());
            used.extend(lat.outer);
        }
        let roots: Vec<u64> = universes.keys().copied().filter(|u| !used.contains(u)).collect();
        let root = match roots.as_slice() {
            [r] => *r,
            [] => return Err("no root universe (circular fills?)".to_string()),
            _ => return Err(format!("several candidate root universes: {roots:?}")),
        };
        Ok(Geometry { surfaces, cells, universes, lattices, root })
    }

    /// The root universe id.
    pub fn root_universe(&self) -> u64 {
        self.root
    }

    /// OpenMC's find_cell: the root universe's cells in file order, first whose
    /// region contains p; descend into fills; None if no cell contains p at
    /// some level (a lost particle).
    pub fn locate(&self, p: [f64; 3]) -> Option<Owner> {
        let path = self.locate_path(p)?;
        let leaf = path.last()?;
        let cell = self.cells.iter().find(|c| c.id == leaf.cell)?;
        match cell.fill {
            Fill::Material(m) => Some(Owner { cell: leaf.cell, material: m }),
            _ => None,
        }
    }

    /// The path of cells from the root to the leaf, with the lattice element
    /// indices met on the way.
    pub fn locate_path(&self, p: [f64; 3]) -> Option<Vec<Level>> {
        let mut path = Vec::new();
        let mut universe = self.root;
        let mut r = p;
        // Depth guard against circular fills (OpenMC rejects those at load time).
        for _ in 0..64 {
            let cell = self.find_in_universe(universe, r)?;
            match cell.fill {
                Fill::Material(_) => {
                    path.push(Level { cell: cell.id, lattice_index: None });
                    return Some(path);
                }
                Fill::Universe(u) => {
                    r = cell.to_local(r);
                    universe = u;
                    path.push(Level { cell: cell.id, lattice_index: None });
                }
                Fill::Lattice(l) => {
                    let lat = self.lattices.get(&l)?;
                    let rl = cell.to_local(r);
                    let idx = lat.indices(rl);
                    r = lat.local_position(rl, idx);
                    universe = lat.universe_at(idx)?; // None: outside, no outer -> lost
                    path.push(Level { cell: cell.id, lattice_index: Some(idx) });
                }
            }
        }
        None
    }

    /// First cell of `universe` (file order) whose region contains r.
    fn find_in_universe(&self, universe: u64, r: [f64; 3]) -> Option<&Cell> {
        let members = self.universes.get(&universe)?;
        members.iter().map(|&i| &self.cells[i]).find(|c| {
            let half = |h: i64| -> Result<bool, String> {
                let s = self.surfaces.get(&h.unsigned_abs()).ok_or("unknown surface")?;
                let f = s.f(r);
                Ok(if h < 0 { f < 0.0 } else { f > 0.0 })
            };
            eval_region(&c.region, &half).unwrap_or(false)
        })
    }
}

impl Cell {
    /// local = M·(r − t) (src/geometry.cpp find_cell_inner: `coord.r() -= c.translation_;`
    /// then `coord.rotate(c.rotation_)`).
    fn to_local(&self, r: [f64; 3]) -> [f64; 3] {
        let d = [r[0] - self.translation[0], r[1] - self.translation[1], r[2] - self.translation[2]];
        match &self.rotation {
            None => d,
            Some(m) => [
                m[0] * d[0] + m[1] * d[1] + m[2] * d[2],
                m[3] * d[0] + m[4] * d[1] + m[5] * d[2],
                m[6] * d[0] + m[7] * d[1] + m[8] * d[2],
            ],
        }
    }
}

impl Lattice {
    /// floor((r − lower_left)/pitch); iz = 0 for a 2D lattice. (OpenMC's
    /// get_indices also snaps values within 1e-12 of an integer according to the
    /// direction of flight; ignored here: tests avoid element boundaries.)
    fn indices(&self, r: [f64; 3]) -> [i64; 3] {
        let axis = |a: usize| ((r[a] - self.lower_left[a]) / self.pitch[a]).floor() as i64;
        [axis(0), axis(1), if self.is_3d { axis(2) } else { 0 }]
    }

    /// r − (lower_left + (i + 0.5)·pitch) per axis; z unchanged for a 2D lattice.
    fn local_position(&self, r: [f64; 3], i: [i64; 3]) -> [f64; 3] {
        let axis = |a: usize| r[a] - (self.lower_left[a] + (i[a] as f64 + 0.5) * self.pitch[a]);
        [axis(0), axis(1), if self.is_3d { axis(2) } else { r[2] }]
    }

    /// The element's universe, or `outer` outside the index range.
    fn universe_at(&self, i: [i64; 3]) -> Option<u64> {
        let inside = (0..3).all(|a| i[a] >= 0 && i[a] < self.n[a]);
        if inside {
            let flat = i[0] + self.n[0] * i[1] + self.n[0] * self.n[1] * i[2];
            self.universes.get(flat as usize).copied()
        } else {
            self.outer
        }
    }
}

// ---------------------------------------------------------------- tests

#[cfg(test)]
mod tests {
    use super::*;

    fn owner(g: &Geometry, p: [f64; 3]) -> Option<u64> {
        g.locate(p).map(|o| o.cell)
    }

    fn one_surface(kind: &str, coeffs: &str) -> Geometry {
        let xml = format!(
            r#"<geometry><surface id="1" type="{kind}" coeffs="{coeffs}"/>
               <cell id="1" material="1" region="-1"/><cell id="2" material="void" region="+1"/></geometry>"#
        );
        Geometry::parse(&xml).expect("parse")
    }

    /// Asserts that p is on the -side (cell 1) or the +side (cell 2).
    fn side(g: &Geometry, p: [f64; 3]) -> char {
        match owner(g, p) {
            Some(1) => '-',
            Some(2) => '+',
            other => panic!("{p:?}: {other:?}"),
        }
    }

    #[test]
    fn surface_signs() {
        let g = one_surface("x-plane", "2");
        assert_eq!((side(&g, [1.9, 5., 5.]), side(&g, [2.1, -5., -5.])), ('-', '+'));
        let g = one_surface("y-plane", "-3");
        assert_eq!((side(&g, [9., -3.5, 0.]), side(&g, [9., -2.5, 0.])), ('-', '+'));
        let g = one_surface("z-plane", "1.5");
        assert_eq!((side(&g, [0., 0., 1.]), side(&g, [0., 0., 2.])), ('-', '+'));
        // plane 1 2 3 4: f = x + 2y + 3z - 4; (1,1,0): -1; (0,0,2): 2
        let g = one_surface("plane", "1 2 3 4");
        assert_eq!((side(&g, [1., 1., 0.]), side(&g, [0., 0., 2.])), ('-', '+'));
        // x-cylinder y0=1 z0=2 R=1: (100,1.5,2.5): 0.5 < 1; (0,1,3.5): 2.25 > 1
        let g = one_surface("x-cylinder", "1 2 1");
        assert_eq!((side(&g, [100., 1.5, 2.5]), side(&g, [0., 1., 3.5])), ('-', '+'));
        // y-cylinder x0=1 z0=2 R=1
        let g = one_surface("y-cylinder", "1 2 1");
        assert_eq!((side(&g, [1.5, -50., 2.5]), side(&g, [1., 0., 3.5])), ('-', '+'));
        assert_eq!(side(&g, [2.5, 0., 2.]), '+'); // would be '-' if it were (y, z)
                                                  // z-cylinder x0=1 y0=2 R=1
        let g = one_surface("z-cylinder", "1 2 1");
        assert_eq!((side(&g, [1.5, 2.5, 77.]), side(&g, [1., 3.5, 0.])), ('-', '+'));
        // sphere (1,2,3) R 2: (2,3,4): 3 - 4 < 0; (1,2,5.5): 6.25 - 4 > 0
        let g = one_surface("sphere", "1 2 3 2");
        assert_eq!((side(&g, [2., 3., 4.]), side(&g, [1., 2., 5.5])), ('-', '+'));
        // z-cone (0,0,1) R2=4: f = x² + y² - 4(z-1)²; both nappes
        let g = one_surface("z-cone", "0 0 1 4");
        assert_eq!(side(&g, [1., 0., 3.]), '-'); // 1 - 16
        assert_eq!(side(&g, [1., 0., -1.]), '-'); // lower nappe: 1 - 16
        assert_eq!(side(&g, [3., 0., 2.]), '+'); // 9 - 4
        assert_eq!(side(&g, [0.1, 0., 1.]), '+'); // apex height: 0.01
                                                  // x-cone (1,0,0) R2=1: f = y² + z² - (x-1)²
        let g = one_surface("x-cone", "1 0 0 1");
        assert_eq!((side(&g, [3., 1., 1.]), side(&g, [1.5, 1., 0.])), ('-', '+'));
        assert_eq!(side(&g, [-1., 1., 1.]), '-'); // other nappe: 2 - 4
                                                  // y-cone (0,2,0) R2=0.25: f = x² + z² - 0.25(y-2)²
        let g = one_surface("y-cone", "0 2 0 0.25");
        assert_eq!((side(&g, [1., 6., 0.]), side(&g, [1., 3., 0.])), ('-', '+'));
        // quadric A..K = 1 2 3 4 5 6 7 8 9 10 at (1,1,1): 1+2+3+4+5+6+7+8+9+10 = 55 > 0
        let g = one_surface("quadric", "1 2 3 4 5 6 7 8 9 10");
        assert_eq!(side(&g, [1., 1., 1.]), '+');
        // only D (xy): f = xy - 1; only E (yz); only F (xz): checks the mixed-term order
        let g = one_surface("quadric", "0 0 0 1 0 0 0 0 0 -1");
        assert_eq!((side(&g, [2., 2., 0.]), side(&g, [2., 0., 2.])), ('+', '-'));
        let g = one_surface("quadric", "0 0 0 0 1 0 0 0 0 -1");
        assert_eq!((side(&g, [0., 2., 2.]), side(&g, [2., 2., 0.])), ('+', '-'));
        let g = one_surface("quadric", "0 0 0 0 0 1 0 0 0 -1");
        assert_eq!((side(&g, [2., 0., 2.]), side(&g, [0., 2., 2.])), ('+', '-'));
        // G H J: f = 2x + 3y + 5z - 1 at (0,0,0.1): -0.5; at (0,1,0): 2
        let g = one_surface("quadric", "0 0 0 0 0 0 2 3 5 -1");
        assert_eq!((side(&g, [0., 0., 0.1]), side(&g, [0., 1., 0.])), ('-', '+'));
        // sphere as quadric: x² + y² + z² - 81
        let g = one_surface("quadric", "1. 1. 1. 0. 0. 0. 0. 0. 0. -81.");
        assert_eq!((side(&g, [5., 5., 5.]), side(&g, [5., 5., 6.])), ('-', '+'));
    }

    /// Surfaces 1: x=0, 2: y=0, 3: z=0; cell 1 has `region`, cell 2 is everything else.
    fn region(spec: &str) -> Geometry {
        let xml = format!(
            r#"<geometry>
                 <surface id="1" type="x-plane" coeffs="0"/>
                 <surface id="2" type="y-plane" coeffs="0"/>
                 <surface id="3" type="z-plane" coeffs="0"/>
                 <cell id="1" material="1" region="{spec}"/>
                 <cell id="2" material="2"/>
               </geometry>"#
        );
        Geometry::parse(&xml).expect("parse")
    }

    fn inside(g: &Geometry, x: f64, y: f64, z: f64) -> bool {
        owner(g, [x, y, z]) == Some(1)
    }

    #[test]
    fn region_precedence() {
        // 1 | 2 3 = 1 ∪ (2 ∩ 3)
        let g = region("1 | 2 3");
        assert!(inside(&g, 1., -1., -1.)); // false under (1|2)∩3
        assert!(inside(&g, -1., 1., 1.));
        assert!(!inside(&g, -1., 1., -1.));
        assert!(!inside(&g, -1., -1., 1.));
        // 2 3 | 1 (same, other order)
        let g = region("2 3 | 1");
        assert!(inside(&g, 1., -1., -1.));
        assert!(!inside(&g, -1., 1., -1.));
        // ~1 2 = (~1) ∩ 2
        let g = region("~1 2");
        assert!(inside(&g, -1., 1., 0.5));
        assert!(!inside(&g, 1., 1., 0.5));
        assert!(!inside(&g, -1., -1., 0.5)); // true under ~(1 ∩ 2)
                                             // ~(1 | 2) = ~1 ∩ ~2
        let g = region("~(1 | 2)");
        assert!(inside(&g, -1., -1., 0.5));
        assert!(!inside(&g, 1., -1., 0.5));
        assert!(!inside(&g, -1., 1., 0.5));
        // ~(1 2) = ~1 ∪ ~2; explicit '+' signs
        let g = region("~(+1 +2)");
        assert!(inside(&g, -1., 1., 0.5) && inside(&g, 1., -1., 0.5) && !inside(&g, 1., 1., 0.5));
        // nested parentheses and complement, no spaces: (-1|-2)3 = (x<0 ∪ y<0) ∩ z>0
        let g = region("(-1|-2)3");
        assert!(inside(&g, -1., 5., 1.) && inside(&g, 5., -1., 1.));
        assert!(!inside(&g, 1., 1., 1.) && !inside(&g, -1., -1., -1.));
        // ~(1 2 | 3) = (~1 ∪ ~2) ∩ ~3, mathematically. NOTE: OpenMC's token-level
        // De Morgan (src/cell.cpp Region::Region) turns this into (-1 | -2 -3),
        // i.e. -1 ∪ (-2 ∩ -3): it differs at e.g. (-1, 1, 1). The oracle follows the
        // documented (mathematical) semantics.
        let g = region("~(1 2 | 3)");
        assert!(inside(&g, -1., 1., -1.) && inside(&g, 1., -1., -1.));
        assert!(!inside(&g, 1., 1., -1.));
        assert!(!inside(&g, -1., 1., 1.)); // OpenMC itself would say "inside" here
                                           // empty region: everything; cell order decides overlaps
        let g = region("");
        assert!(inside(&g, -3., 4., -5.));
    }

    #[test]
    fn region_errors() {
        let bad = |spec: &str| {
            let xml = format!(
                r#"<geometry><surface id="1" type="x-plane" coeffs="0"/><cell id="1" material="1" region="{spec}"/></geometry>"#
            );
            Geometry::parse(&xml).is_err()
        };
        assert!(bad("(1"));
        assert!(bad("1)"));
        assert!(bad("2"));
        assert!(bad("1 |"));
        assert!(bad("1 & 1"));
        assert!(!bad("-1"));
    }

    #[test]
    fn child_elements_model_wrapper_and_lost_points() {
        let xml = r#"<model><materials/><geometry>
            <surface><id>1</id><type>sphere</type><coeffs>0 0 0 1</coeffs></surface>
            <surface id="2" type="sphere"><coeffs>0 0 0 2</coeffs></surface>
            <cell><id>7</id><material>3</material><region>-1</region></cell>
            <cell id="8"><material>void</material><region>1 -2</region></cell>
          </geometry><settings/></model>"#;
        let g = Geometry::parse(xml).expect("parse");
        assert_eq!(g.locate([0.5, 0., 0.]), Some(Owner { cell: 7, material: Some(3) }));
        assert_eq!(g.locate([0., 1.5, 0.]), Some(Owner { cell: 8, material: None }));
        assert_eq!(g.locate([0., 0., 2.5]), None);
        assert_eq!(g.locate_path([0., 0., 0.]), Some(vec![Level { cell: 7, lattice_index: None }]));
    }

    #[test]
    fn first_cell_wins() {
        let xml = r#"<geometry><surface id="1" type="x-plane" coeffs="0"/>
            <cell id="5" material="1" region="-1"/><cell id="4" material="2"/><cell id="3" material="3" region="1"/></geometry>"#;
        let g = Geometry::parse(xml).expect("parse");
        assert_eq!(owner(&g, [-1., 0., 0.]), Some(5));
        assert_eq!(owner(&g, [1., 0., 0.]), Some(4));
    }

    /// Universe 1: box cell 11 (2 < x < 3, |y| < 0.5, |z| < 0.5), everything else cell 12.
    /// Root cell 10 fills universe 1 with `attrs`.
    fn filled(attrs: &str) -> Geometry {
        let xml = format!(
            r#"<geometry>
                 <surface id="1" type="x-plane" coeffs="2"/> <surface id="2" type="x-plane" coeffs="3"/>
                 <surface id="3" type="y-plane" coeffs="-0.5"/> <surface id="4" type="y-plane" coeffs="0.5"/>
                 <surface id="5" type="z-plane" coeffs="-0.5"/> <surface id="6" type="z-plane" coeffs="0.5"/>
                 <cell id="10" fill="1" {attrs}/>
                 <cell id="11" universe="1" material="1" region="1 -2 3 -4 5 -6"/>
                 <cell id="12" universe="1" material="2" region="~(1 -2 3 -4 5 -6)"/>
               </geometry>"#
        );
        Geometry::parse(&xml).expect("parse")
    }

    #[test]
    fn translated_fill() {
        let g = filled(r#"translation="5 0 0""#);
        // local = global - t: (7.5, 0, 0) -> (2.5, 0, 0) in the box
        assert_eq!(owner(&g, [7.5, 0., 0.]), Some(11));
        assert_eq!(owner(&g, [2.5, 0., 0.]), Some(12));
        assert_eq!(
            g.locate_path([7.5, 0., 0.]),
            Some(vec![Level { cell: 10, lattice_index: None }, Level { cell: 11, lattice_index: None }])
        );
        let g = filled("");
        assert_eq!(owner(&g, [2.5, 0., 0.]), Some(11));
    }

    #[test]
    fn rotated_fill() {
        // rotation="0 0 90": set_rotation negates the angles, psi = -90°, so
        // M = Rz(-90°) = [[cos(-90), -sin(-90), 0], [sin(-90), cos(-90), 0], [0, 0, 1]]
        //   = [[0, 1, 0], [-1, 0, 0], [0, 0, 1]],  local = M·global = (y, -x, z).
        // Global (0, 2.5, 0) -> local (2.5, 0, 0): the box offset along +x lands along +y.
        let g = filled(r#"rotation="0 0 90""#);
        assert_eq!(owner(&g, [0., 2.5, 0.]), Some(11));
        assert_eq!(owner(&g, [2.5, 0., 0.]), Some(12)); // local (0, -2.5, 0)
        assert_eq!(owner(&g, [0., -2.5, 0.]), Some(12)); // local (-2.5, 0, 0)
                                                         // the same M given as 9 numbers, row-major
        let g = filled(r#"rotation="0 1 0 -1 0 0 0 0 1""#);
        assert_eq!(owner(&g, [0., 2.5, 0.]), Some(11));
        assert_eq!(owner(&g, [2.5, 0., 0.]), Some(12));
        // translation first, then rotation: local = M·(global - t); global (10, 2.5, 0)
        // -> (0, 2.5, 0) -> (2.5, 0, 0).
        let g = filled(r#"translation="10 0 0" rotation="0 0 90""#);
        assert_eq!(owner(&g, [10., 2.5, 0.]), Some(11));
        assert_eq!(owner(&g, [2.5, 10., 0.]), Some(12)); // what rotate-then-translate would give
                                                         // rotation="90 0 90": M = Rz(-90°)·Rx(-90°). Rx(-90°)·(x,y,z) = (x, z, -y), then
                                                         // Rz(-90°)·(a,b,c) = (b, -a, c): local = (z, -x, -y). Global (0, 0, 2.5) -> (2.5, 0, 0):
                                                         // the box. The other order, Rx(-90°)·Rz(-90°), would give local (y, z, x) = (0, 2.5, 0).
        let g = filled(r#"rotation="90 0 90""#);
        assert_eq!(owner(&g, [0., 0., 2.5]), Some(11));
        assert_eq!(owner(&g, [0., 2.5, 0.]), Some(12));
        // rotation="0 90 0": theta = -90°, M = Ry(-90°) = [[0,0,-1],[0,1,0],[1,0,0]],
        // local = (-z, y, x): global (0, 0, -2.5) -> (2.5, 0, 0).
        let g = filled(r#"rotation="0 90 0""#);
        assert_eq!(owner(&g, [0., 0., -2.5]), Some(11));
        assert_eq!(owner(&g, [0., 0., 2.5]), Some(12));
    }

    #[test]
    fn rotation_matrix_matches_hand_values() {
        let m = rotation_from_angles([0., 0., 90.]);
        let want = [0., 1., 0., -1., 0., 0., 0., 0., 1.];
        for (a, b) in m.iter().zip(want) {
            assert!((a - b).abs() < 1e-15, "{m:?}");
        }
    }

    /// 2×2×2 lattice, lower_left 0, pitch 1; element universes 1..8 each with one
    /// cell (id 100+u). File order: layer z=0 rows "1 2" (top, y=1) then "3 4" (y=0);
    /// layer z=1 rows "5 6" then "7 8".
    fn lattice3d(cell_attrs: &str) -> Geometry {
        let mut xml = String::from("<geometry>");
        xml += &format!(r#"<cell id="1" fill="9" {cell_attrs}/>"#);
        for u in 1..=8 {
            xml += &format!(r#"<cell id="{}" universe="{u}" material="{u}"/>"#, 100 + u);
        }
        xml += r#"<lattice id="9"><dimension>2 2 2</dimension><lower_left>0 0 0</lower_left>
                  <pitch>1 1 1</pitch><universes>1 2
                  3 4
                  5 6
                  7 8</universes></lattice></geometry>"#;
        Geometry::parse(&xml).expect("parse")
    }

    #[test]
    fn lattice_3d() {
        let g = lattice3d("");
        assert_eq!(owner(&g, [0.5, 0.5, 0.5]), Some(103));
        assert_eq!(owner(&g, [1.5, 0.5, 0.5]), Some(104));
        assert_eq!(owner(&g, [0.5, 1.5, 0.5]), Some(101));
        assert_eq!(owner(&g, [1.5, 1.5, 0.5]), Some(102));
        assert_eq!(owner(&g, [0.5, 1.5, 1.5]), Some(105));
        assert_eq!(owner(&g, [1.5, 0.5, 1.5]), Some(108));
        assert_eq!(
            g.locate_path([1.5, 0.5, 1.5]),
            Some(vec![Level { cell: 1, lattice_index: Some([1, 0, 1]) }, Level { cell: 108, lattice_index: None }])
        );
        // outside, no outer: lost
        assert_eq!(g.locate([0.5, 0.5, 2.5]), None);
        assert_eq!(g.locate([-0.5, 0.5, 0.5]), None);
        // OpenMC applies the filling cell's translation before a lattice too
        let g = lattice3d(r#"translation="10 0 0""#);
        assert_eq!(owner(&g, [10.5, 0.5, 0.5]), Some(103));
        assert_eq!(g.locate([0.5, 0.5, 0.5]), None);
        // ... and its rotation: "0 0 90" gives local (y, -x, z). Global (-1.5, 0.5, 0.5)
        // -> local (0.5, 1.5, 0.5) -> element (0, 1, 0) = universe 1; global (0.5, -1.5, 0.5)
        // -> local (-1.5, -0.5, 0.5): outside the lattice, no outer: lost.
        let g = lattice3d(r#"rotation="0 0 90""#);
        assert_eq!(owner(&g, [-1.5, 0.5, 0.5]), Some(101));
        assert_eq!(g.locate([0.5, -1.5, 0.5]), None);
    }

    /// 2D 2×2 lattice (lower_left -1 -1, pitch 1 1) of universe 1 (cell 11: |local x| < 0.25,
    /// cell 12 elsewhere), outer universe 2 (cell 21: local sphere r = 0.25; cell 22 elsewhere).
    #[test]
    fn lattice_outer_tiling_and_local_positions() {
        let xml = r#"<geometry>
            <surface id="1" type="x-plane" coeffs="-0.25"/><surface id="2" type="x-plane" coeffs="0.25"/>
            <surface id="5" type="sphere" coeffs="0 0 0 0.25"/>
            <surface id="6" type="z-plane" coeffs="7"/>
            <cell id="1" fill="4"/>
            <cell id="11" universe="1" material="1" region="1 -2"/>
            <cell id="12" universe="1" material="2" region="-1 | 2"/>
            <cell id="21" universe="2" material="3" region="-5"/>
            <cell id="22" universe="2" material="void" region="5 -6"/>
            <lattice id="4" outer="2"><dimension>2 2</dimension><lower_left>-1 -1</lower_left>
              <pitch>1 1</pitch><universes>1 1 1 1</universes></lattice>
          </geometry>"#;
        let g = Geometry::parse(xml).expect("parse");
        // inside: element centres at ±0.5; local x = x ∓ 0.5
        assert_eq!(owner(&g, [0.6, 0.5, 3.]), Some(11));
        assert_eq!(owner(&g, [0.9, 0.5, 3.]), Some(12));
        assert_eq!(owner(&g, [-0.4, -0.9, 3.]), Some(11));
        // outside: ix = floor(4.5) = 4, centre -1 + 4.5 = 3.5; iy = 1, centre 0.5 -> local (0, 0, z)
        let p = [3.5, 0.5, 0.];
        assert_eq!(g.locate(p), Some(Owner { cell: 21, material: Some(3) }));
        assert_eq!(
            g.locate_path(p),
            Some(vec![Level { cell: 1, lattice_index: Some([4, 1, 0]) }, Level { cell: 21, lattice_index: None }])
        );
        assert_eq!(g.locate([3.2, 0.5, 0.]), Some(Owner { cell: 22, material: None }));
        // far away, negative indices: ix = floor(-4.5) = -5 -> centre -5.5; iy = floor(-6.5) = -7 -> centre -7.5
        assert_eq!(owner(&g, [-5.5, -7.5, 0.1]), Some(21));
        assert_eq!(g.locate_path([-5.5, -7.5, 0.1]).map(|p| p[0].lattice_index), Some(Some([-5, -7, 0])));
        // 2D lattice: z is unchanged (sphere at local z = 0 only; z-plane 7 bounds cell 22)
        assert_eq!(owner(&g, [3.5, 0.5, 0.5]), Some(22));
        assert_eq!(g.locate([3.5, 0.5, 8.]), None); // outer universe has no cell there: lost
    }

    #[test]
    fn root_universe_not_zero() {
        // root universe 3 fills universe 0 (translated), which fills universe 7
        let xml = r#"<geometry>
            <surface id="1" type="sphere" coeffs="0 0 0 1"/>
            <surface id="2" type="sphere" coeffs="0 0 10 1"/>
            <cell id="1" universe="3" fill="0" translation="0 0 10" region="-2"/>
            <cell id="2" universe="3" material="1" region="2"/>
            <cell id="3" universe="0" fill="7" translation="0 0 -0.5"/>
            <cell id="4" universe="7" material="2" region="-1"/>
            <cell id="5" universe="7" material="void" region="1"/>
          </geometry>"#;
        let g = Geometry::parse(xml).expect("parse");
        assert_eq!(g.root_universe(), 3);
        // (0,0,10.2) -> universe 0 at (0,0,0.2) -> universe 7 at (0,0,0.7): cell 4
        assert_eq!(g.locate([0., 0., 10.2]), Some(Owner { cell: 4, material: Some(2) }));
        let path: Vec<u64> = g.locate_path([0., 0., 10.2]).unwrap_or_default().iter().map(|l| l.cell).collect();
        assert_eq!(path, vec![1, 3, 4]);
        // (0,0,10.8): universe 0 at 0.8 -> universe 7 at 1.3: outside sphere 1: cell 5 (void)
        assert_eq!(g.locate([0., 0., 10.8]), Some(Owner { cell: 5, material: None }));
        assert_eq!(owner(&g, [0., 0., 0.]), Some(2));
    }

    #[test]
    fn parse_errors() {
        let hex = r#"<geometry><cell id="1" fill="2"/><hex_lattice id="2"/></geometry>"#;
        assert_eq!(Geometry::parse(hex).err(), Some("hex lattice not supported by the oracle".to_string()));
        // two candidate roots
        let two = r#"<geometry><cell id="1" material="1"/><cell id="2" universe="5" material="1"/></geometry>"#;
        assert!(Geometry::parse(two).is_err());
        // fill of nothing
        assert!(Geometry::parse(r#"<geometry><cell id="1" fill="4"/></geometry>"#).is_err());
        // wrong coefficient count
        assert!(Geometry::parse(r#"<geometry><surface id="1" type="sphere" coeffs="1 2 3"/></geometry>"#).is_err());
        assert!(Geometry::parse("<materials/>").is_err());
    }
}
