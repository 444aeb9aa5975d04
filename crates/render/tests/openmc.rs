//! `render::openmc`: imported OpenMC models against the independent point
//! evaluator of `openmc_oracle.rs` (OpenMC's find_cell written out plainly),
//! against the derived values of `tests/openmc/README.md`, and against
//! hand-computed placements.

use std::collections::BTreeMap;

use render::measure::{volumes_by_name, MeasureOptions};
use render::openmc::{import, Imported};
use render::world::World;

use crate::openmc_oracle::Geometry;

fn shared(name: &str) -> String {
    let path = format!("{}/../../tests/openmc/{name}/geometry.xml", env!("CARGO_MANIFEST_DIR"));
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"))
}

fn load(xml: &str) -> (Imported, World) {
    let imported = import(xml).unwrap_or_else(|e| panic!("{e}\n{xml}"));
    let world = imported.scene.to_world().unwrap();
    (imported, world)
}

/// The owner's block name and material name, as the imported scene has it.
fn owner(world: &World, p: [f64; 3]) -> Option<(String, String)> {
    let id = world.complex.contains_point(&p.into())?;
    Some((world.complex.block(id).name().to_string(), world.block_material(id).name.clone()))
}

/// The same from the oracle: `cell <id>` and `material <id>` or `void`.
fn expected(g: &Geometry, p: [f64; 3]) -> Option<(String, String)> {
    let o = g.locate(p)?;
    Some((format!("cell {}", o.cell), o.material.map_or_else(|| "void".to_string(), |m| format!("material {m}"))))
}

/// xorshift64*, uniform in [0, 1).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
    }
    fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }
    fn below(&mut self, n: usize) -> usize {
        ((self.next() * n as f64) as usize).min(n - 1)
    }
    fn point(&mut self, lo: [f64; 3], hi: [f64; 3]) -> [f64; 3] {
        [0, 1, 2].map(|i| self.uniform(lo[i], hi[i]))
    }
}

/// Compares owners at `n` random points of the box; returns how many
/// points some cell owns.
fn agree(xml: &str, lo: [f64; 3], hi: [f64; 3], n: usize, seed: u64) -> usize {
    let (_, world) = load(xml);
    let g = Geometry::parse(xml).unwrap();
    let mut rng = Rng(seed | 1);
    let mut owned = 0;
    for _ in 0..n {
        let p = rng.point(lo, hi);
        let want = expected(&g, p);
        owned += usize::from(want.is_some());
        assert_eq!(owner(&world, p), want, "at {p:?} in\n{xml}");
    }
    owned
}

#[test]
fn shared_models_agree_with_the_oracle_at_random_points() {
    for (name, lo, hi) in [
        ("quadric_surfaces", [-6.0, -6.0, -11.0], [6.0, 6.0, 11.0]),
        ("complex_cell", [-11.0, -11.0, -3.0], [11.0, 11.0, 3.0]),
        ("lattice", [-2.0, -2.0, -32.0], [52.0, 52.0, 112.0]),
    ] {
        let owned = agree(&shared(name), lo, hi, 20_000, 7);
        assert!(owned > 2_000, "{name}: only {owned} points owned: the box misses the model");
    }
}

#[test]
fn lattice_points_of_the_readme() {
    let (_, world) = load(&shared("lattice"));
    for (p, cell) in [
        ([0.01, 0.01, 50.0], 23),
        ([0.7, 0.01, 50.0], 24),
        ([19.558, 0.01, 50.0], 23),
        ([21.336, 0.01, 50.0], 47),
        ([10.668, 19.558, 50.0], 23),
        ([12.446, 19.558, 50.0], 47),
        ([0.72, 0.1, 4.5], 31),
        ([0.01, 0.01, 4.0], 22),
        ([0.01, 0.01, 3.3], 21),
        ([0.01, 0.01, 1.0], 2),
        ([0.01, 0.01, -10.0], 1),
        ([0.01, 0.01, 96.0], 4),
        ([0.01, 0.01, 100.0], 5),
    ] {
        assert_eq!(owner(&world, p).map(|o| o.0), Some(format!("cell {cell}")), "at {p:?}");
    }
    assert_eq!(owner(&world, [-1.0, 1.0, 50.0]), None);
    assert_eq!(owner(&world, [40.0, 40.0, 50.0]), None);
}

#[test]
fn lattice_elements_share_definitions() {
    let (imported, world) = load(&shared("lattice"));
    // 841 elements; those the root cell's cylinder and planes do not cut
    // share one definition per universe.
    assert!(imported.scene.definitions.len() < 300, "{} definitions", imported.scene.definitions.len());
    // Every element that meets the quarter disc r < 50 is placed, no other:
    // 29 × 29 elements of pitch 1.778 from −0.889.
    let meets = (0..29 * 29)
        .filter(|k| {
            let near = |i: usize| (-0.889 + i as f64 * 1.778).max(0.0);
            near(k % 29).hypot(near(k / 29)) < 50.0
        })
        .count();
    let group = imported.scene.blocks.iter().find(|e| e.group.as_deref() == Some("cell 3")).unwrap();
    let placed = group.blocks.as_ref().unwrap().iter().filter(|e| e.instance.is_some()).count();
    assert_eq!(placed, meets);
    assert!(world.complex.len() > placed * 13);
    assert!(imported.bounded);
    let (lo, hi) = imported.frame;
    for i in 0..2 {
        assert!(lo[i].abs() < 1e-6 && (hi[i] - 50.0).abs() < 1e-6, "{lo:?} {hi:?}");
    }
    assert!((lo[2] + 30.0).abs() < 1e-6 && (hi[2] - 110.236).abs() < 1e-6, "{lo:?} {hi:?}");
}

/// The volume each cell owns (its blocks together), with its standard error.
fn cell_volumes(world: &World, bounds: Option<[f64; 6]>) -> BTreeMap<String, (f64, f64)> {
    let report = volumes_by_name(world, &MeasureOptions { tolerance: 2e-3, seed: 3, bounds }).unwrap();
    assert!(report.converged);
    report.names.iter().map(|n| (n.name.clone(), (n.volume.unwrap(), n.error.unwrap()))).collect()
}

#[test]
fn quadric_surfaces_volumes_of_the_readme() {
    let (_, world) = load(&shared("quadric_surfaces"));
    let v = cell_volumes(&world, None);
    // The README's derived values: 74.6167π and 906.80 (to about 0.02 %).
    for (cell, want, known) in [("cell 1", 74.6167 * std::f64::consts::PI, 1e-5), ("cell 2", 906.80, 2e-4)] {
        let (got, error) = v[cell];
        assert!((got - want).abs() < 4.0 * error + known * want, "{cell}: {got} ± {error}, want {want}");
    }
}

#[test]
fn complex_cell_areas_of_the_readme() {
    let (_, world) = load(&shared("complex_cell"));
    // A slab of thickness 1: volumes are the areas per unit length of z.
    let v = cell_volumes(&world, Some([-10.0, -10.0, 0.0, 10.0, 10.0, 1.0]));
    for (cell, want) in [("cell 1", 64.0), ("cell 2", 132.0), ("cell 3", 102.0), ("cell 4", 102.0)] {
        let (got, error) = v[cell];
        assert!((got - want).abs() < 4.0 * error, "{cell}: {got} ± {error}, want {want}");
    }
}

/// A random surface that passes through the box [−2, 2]³.
fn random_surface(rng: &mut Rng, id: usize) -> String {
    let c = |rng: &mut Rng| rng.uniform(-1.0, 1.0);
    let (kind, coeffs): (&str, Vec<f64>) = match rng.below(10) {
        0 => (["x-plane", "y-plane", "z-plane"][rng.below(3)], vec![c(rng)]),
        1 => ("plane", vec![c(rng), c(rng), c(rng), c(rng)]),
        2..=4 => {
            (["x-cylinder", "y-cylinder", "z-cylinder"][rng.below(3)], vec![c(rng), c(rng), rng.uniform(0.5, 2.0)])
        }
        5 => ("sphere", vec![c(rng), c(rng), c(rng), rng.uniform(0.8, 2.5)]),
        6 | 7 => (["x-cone", "y-cone", "z-cone"][rng.below(3)], vec![c(rng), c(rng), c(rng), rng.uniform(0.2, 3.0)]),
        _ => ("quadric", (0..10).map(|_| c(rng)).collect()),
    };
    let coeffs: Vec<String> = coeffs.iter().map(|x| format!("{x}")).collect();
    format!(r#"<surface id="{id}" type="{kind}" coeffs="{}"/>"#, coeffs.join(" "))
}

/// A random region expression over surfaces `ids`.
fn random_region(rng: &mut Rng, ids: &[usize], depth: u32) -> String {
    if depth == 0 || rng.next() < 0.3 {
        return format!("{}{}", ["-", "+", ""][rng.below(3)], ids[rng.below(ids.len())]);
    }
    let a = random_region(rng, ids, depth - 1);
    let b = random_region(rng, ids, depth - 1);
    match rng.below(5) {
        0 | 1 => format!("{a} {b}"),
        2 => format!("{a} | {b}"),
        3 => format!("~({a})"),
        _ => format!("({a} | {b}) {}", random_region(rng, ids, depth - 1)),
    }
}

/// Cells `first..` of `universe` with random regions over `surfaces`,
/// materials and void, ending with a region-less cell when `close`.
fn random_cells(rng: &mut Rng, universe: u64, first: u64, count: u64, surfaces: &[usize], close: bool) -> String {
    let mut out = String::new();
    for id in first..first + count {
        let material = if rng.next() < 0.2 { "void".to_string() } else { format!("{}", 1 + rng.below(4)) };
        let region = random_region(rng, surfaces, 3);
        out.push_str(&format!(r#"<cell id="{id}" universe="{universe}" material="{material}" region="{region}"/>"#));
        out.push('\n');
    }
    if close {
        out.push_str(&format!(r#"<cell id="{}" universe="{universe}" material="void"/>"#, first + count));
        out.push('\n');
    }
    out
}

#[test]
fn every_surface_side_agrees_with_openmc_equations() {
    // One surface, its two sides as two cells: the importer's solids
    // against the oracle's direct evaluation of OpenMC's f.
    let mut rng = Rng(11);
    for model in 0..60 {
        let xml = format!(
            r#"<geometry>{}<cell id="1" material="1" region="-1"/><cell id="2" material="2" region="+1"/></geometry>"#,
            random_surface(&mut rng, 1)
        );
        agree(&xml, [-2.0; 3], [2.0; 3], 400, model + 1);
    }
}

#[test]
fn random_regions_agree_with_first_match() {
    let mut rng = Rng(5);
    for model in 0..60 {
        let surfaces: String = (1..=5).map(|i| random_surface(&mut rng, i)).collect();
        let cells = random_cells(&mut rng, 0, 1, 4, &[1, 2, 3, 4, 5], false);
        let xml = format!("<geometry>\n{surfaces}\n{cells}</geometry>");
        agree(&xml, [-2.0; 3], [2.0; 3], 400, model + 100);
    }
}

/// A random rotation attribute: three angles or nine matrix entries.
fn random_rotation(rng: &mut Rng) -> String {
    let angles = [0, 1, 2].map(|_| rng.uniform(-180.0, 180.0));
    if rng.next() < 0.5 {
        return format!(r#" rotation="{} {} {}""#, angles[0], angles[1], angles[2]);
    }
    // Some rotation matrix, row-major: Rx·Ry·Rz of the angles.
    let [a, b, c] = angles.map(f64::to_radians);
    let rx = [[1.0, 0.0, 0.0], [0.0, a.cos(), -a.sin()], [0.0, a.sin(), a.cos()]];
    let ry = [[b.cos(), 0.0, b.sin()], [0.0, 1.0, 0.0], [-b.sin(), 0.0, b.cos()]];
    let rz = [[c.cos(), -c.sin(), 0.0], [c.sin(), c.cos(), 0.0], [0.0, 0.0, 1.0]];
    let mul = |p: [[f64; 3]; 3], q: [[f64; 3]; 3]| {
        let mut r = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                r[i][j] = (0..3).map(|k| p[i][k] * q[k][j]).sum();
            }
        }
        r
    };
    let m = mul(mul(rx, ry), rz);
    let v: Vec<String> = m.iter().flatten().map(|x| format!("{x}")).collect();
    format!(r#" rotation="{}""#, v.join(" "))
}

fn random_translation(rng: &mut Rng) -> String {
    let t = [0, 1, 2].map(|_| rng.uniform(-1.0, 1.0));
    format!(r#" translation="{} {} {}""#, t[0], t[1], t[2])
}

#[test]
fn random_fills_agree_with_the_oracle() {
    // Root: a ball filled with universe 10 (translated and rotated), the
    // space around it a material. Universe 10 nests universe 20 the same way.
    let mut rng = Rng(17);
    for model in 0..30 {
        let surfaces: String = (1..=5).map(|i| random_surface(&mut rng, i)).collect();
        let inner = random_cells(&mut rng, 20, 200, 3, &[1, 2, 3, 4, 5], true);
        let middle = random_cells(&mut rng, 10, 100, 2, &[1, 2, 3], false);
        let (t1, r1, t2, r2) = (
            random_translation(&mut rng),
            random_rotation(&mut rng),
            random_translation(&mut rng),
            random_rotation(&mut rng),
        );
        let xml = format!(
            r#"<geometry>
{surfaces}
<surface id="90" type="sphere" coeffs="0 0 0 1.7"/>
<surface id="91" type="sphere" coeffs="0.2 0 0 1.2"/>
<cell id="1" fill="10" region="-90"{t1}{r1}/>
<cell id="2" material="9" region="90"/>
{middle}<cell id="150" universe="10" fill="20" region="-91"{t2}{r2}/>
<cell id="151" universe="10" material="8" region="91"/>
{inner}</geometry>"#
        );
        agree(&xml, [-2.0; 3], [2.0; 3], 500, model + 200);
    }
}

#[test]
fn random_lattices_agree_with_the_oracle() {
    let mut rng = Rng(23);
    for model in 0..40 {
        let three_d = model % 2 == 1;
        let surfaces: String = (1..=4).map(|i| random_surface(&mut rng, i)).collect();
        // The lattice's cell is cut by random surfaces too, so that the
        // elements it cuts, holds or misses all occur.
        let clip = random_region(&mut rng, &[1, 2, 3, 4], 2);
        let a = random_cells(&mut rng, 10, 100, 2, &[1, 2, 3, 4], true);
        let b = random_cells(&mut rng, 11, 110, 2, &[1, 2, 3, 4], true);
        let (nx, ny, nz) = (2 + rng.below(3), 2 + rng.below(3), if three_d { 2 } else { 1 });
        let pitch = [0, 1, 2].map(|_| rng.uniform(0.6, 1.3));
        let ll = [0, 1, 2].map(|i| {
            -pitch[i]
                * (if i == 0 {
                    nx
                } else if i == 1 {
                    ny
                } else {
                    nz
                }) as f64
                / 2.0
                + rng.uniform(-0.3, 0.3)
        });
        // The outer universe: one material everywhere (placed once), or
        // cells with regions (tiled over the virtual elements).
        let outer = if model % 4 < 2 {
            r#"<cell id="120" universe="12" material="7"/>"#.to_string() + "\n"
        } else {
            random_cells(&mut rng, 12, 120, 2, &[1, 2, 3, 4], true)
        };
        let mut universes: Vec<&str> = (0..nx * ny * nz).map(|_| ["10", "11"][rng.below(2)]).collect();
        // Both universes placed: an unplaced one would be a second root.
        universes[0] = "10";
        universes[1] = "11";
        let axes = if three_d { 3 } else { 2 };
        let v = |x: [f64; 3]| x[..axes].iter().map(|c| c.to_string()).collect::<Vec<_>>().join(" ");
        let dims = if three_d { format!("{nx} {ny} {nz}") } else { format!("{nx} {ny}") };
        let transform = if model % 3 == 0 {
            format!("{}{}", random_translation(&mut rng), random_rotation(&mut rng))
        } else {
            String::new()
        };
        let xml = format!(
            r#"<geometry>
{surfaces}
<surface id="90" type="sphere" coeffs="0 0 0 2.2"/>
<cell id="1" fill="30" region="-90 ({clip})"{transform}/>
<cell id="2" material="9" region="~(-90 ({clip}))"/>
<lattice id="30"><dimension>{dims}</dimension><lower_left>{}</lower_left><pitch>{}</pitch><outer>12</outer>
<universes>{}</universes></lattice>
{outer}{a}{b}</geometry>"#,
            v(ll),
            v(pitch),
            universes.join(" ")
        );
        agree(&xml, [-2.5; 3], [2.5; 3], 600, model + 300);
    }
}

#[test]
fn a_lattice_cut_by_a_cone_keeps_the_cut() {
    // Every corner of the element [−1, 1]² × [−3, 3] lies inside the double
    // cone x² + y² < 4z², but the element's middle does not: the element
    // must keep the cone (a corner test is right for convex solids only).
    let xml = r#"<geometry>
      <surface id="5" type="z-cone" coeffs="0 0 0 4"/>
      <cell id="1" fill="30" region="-5"/>
      <cell id="2" material="9" region="5"/>
      <lattice id="30"><dimension>1 1 1</dimension><lower_left>-1 -1 -3</lower_left><pitch>2 2 6</pitch>
        <outer>12</outer><universes>10</universes></lattice>
      <cell id="100" universe="10" material="1"/>
      <cell id="120" universe="12" material="7"/>
    </geometry>"#;
    agree(xml, [-1.5, -1.5, -3.5], [1.5, 1.5, 3.5], 2000, 9);
    let (_, world) = load(xml);
    assert_eq!(owner(&world, [0.9, 0.0, 0.1]).map(|o| o.0), Some("cell 2".into()));
    assert_eq!(owner(&world, [0.9, 0.0, 2.0]).map(|o| o.0), Some("cell 100".into()));
}

#[test]
fn a_lattice_around_a_hole_keeps_the_hole() {
    // The lattice fills the outside of a cylinder of radius 1.1: the
    // element [1, 2] × [0, 1] comes within 1 of the axis, so it must keep
    // the cylinder; [1, 2] × [1, 2] (at least √2 away) need not.
    let xml = r#"<geometry>
      <surface id="5" type="z-cylinder" coeffs="0 0 1.1"/>
      <surface id="6" type="sphere" coeffs="0 0 0 2.5"/>
      <cell id="1" fill="30" region="+5 -6"/>
      <cell id="2" material="9" region="-5"/>
      <lattice id="30"><dimension>4 4</dimension><lower_left>-2 -2</lower_left><pitch>1 1</pitch>
        <universes>10 10 10 10 10 10 10 10 10 10 10 10 10 10 10 10</universes></lattice>
      <cell id="100" universe="10" material="1"/>
    </geometry>"#;
    agree(xml, [-2.2, -2.2, -1.0], [2.2, 2.2, 1.0], 3000, 13);
    let (_, world) = load(xml);
    assert_eq!(owner(&world, [1.02, 0.3, 0.0]).map(|o| o.0), Some("cell 2".into()));
    assert_eq!(owner(&world, [1.5, 0.5, 0.0]).map(|o| o.0), Some("cell 100".into()));
}

#[test]
fn a_rotated_fill_lands_where_openmc_puts_it() {
    // rotation="0 0 90": OpenMC's local = M·(global − t) with
    // M = Rz(−90°) = [[0, 1, 0], [−1, 0, 0], [0, 0, 1]], so local = (y, −x, z)
    // for t = 0: the content's box at local x in [2, 3] appears at global
    // y in [2, 3]. With translation (0, 0, 5) it moves up by 5.
    let xml = r#"<geometry>
      <surface id="1" type="x-plane" coeffs="2"/><surface id="2" type="x-plane" coeffs="3"/>
      <surface id="3" type="y-plane" coeffs="-0.5"/><surface id="4" type="y-plane" coeffs="0.5"/>
      <surface id="5" type="z-plane" coeffs="-0.5"/><surface id="6" type="z-plane" coeffs="0.5"/>
      <surface id="9" type="sphere" coeffs="0 0 0 20"/>
      <cell id="1" fill="7" region="-9" rotation="0 0 90" translation="0 0 5"/>
      <cell id="70" universe="7" material="1" region="1 -2 3 -4 5 -6"/>
      <cell id="71" universe="7" material="void" region="~(1 -2 3 -4 5 -6)"/>
    </geometry>"#;
    let (_, world) = load(xml);
    let name = |p| owner(&world, p).map(|o| o.0);
    assert_eq!(name([0.0, 2.5, 5.0]), Some("cell 70".into()));
    assert_eq!(name([0.3, 2.1, 5.3]), Some("cell 70".into()));
    assert_eq!(name([2.5, 0.0, 5.0]), Some("cell 71".into()));
    assert_eq!(name([0.0, -2.5, 5.0]), Some("cell 71".into()));
    assert_eq!(name([0.0, 2.5, 0.0]), Some("cell 71".into()));
}

#[test]
fn errors_name_the_place() {
    let cases: &[(&str, &str)] = &[
        (
            r#"<geometry><surface id="1" type="x-torus" coeffs="0 0 0 1 1 1"/><cell id="4" material="1" region="-1"/></geometry>"#,
            "line 1, column 64: cell 4: surface 1 is a x-torus, not a quadric: not supported yet",
        ),
        (
            r#"<geometry><hex_lattice id="5"/><cell id="4" fill="5"/></geometry>"#,
            "line 1, column 11: lattice 5: hexagonal lattices are not supported yet (filling cell 4)",
        ),
        (
            r#"<geometry><surface id="1" type="sphere" coeffs="0 0 0 1"/><cell id="4" material="1" region="-1 (2"/></geometry>"#,
            "cell 4: region `-1 (2`: character 4: `(` is never closed",
        ),
        (
            r#"<geometry><surface id="10" type="sphere" coeffs="0 0 0 1"/><cell id="4" material="1" region="-11"/></geometry>"#,
            "cell 4: region: surface 11 is not defined (did you mean 10?)",
        ),
        (
            r#"<geometry><surface id="1" type="sphere" coeffs="0 0 0 1"/><cell id="4" material="1" regoin="-1"/></geometry>"#,
            "<cell>: unknown attribute `regoin` (did you mean `region`?)",
        ),
        (
            r#"<geometry><surface id="1" type="sphere" coeffs="0 0 1"/></geometry>"#,
            "surface 1: `sphere` takes 4 coefficients, got 3",
        ),
        (
            r#"<geometry><surface id="1" type="spere" coeffs="0 0 0 1"/></geometry>"#,
            "unknown surface type `spere` (did you mean `sphere`?)",
        ),
        (
            r#"<geometry><cell id="1" material="1"/><cell id="2" universe="1" material="2"/></geometry>"#,
            "more than one universe fills nothing, so the root is ambiguous: 0, 1",
        ),
        (
            r#"<geometry><surface id="1" type="sphere" coeffs="0 0 0 1"/><cell id="1" fill="2" region="-1"/><cell id="2" universe="2" fill="3"/><cell id="3" universe="3" fill="2"/></geometry>"#,
            "fills form a cycle: universe 2 → universe 3 → universe 2",
        ),
        (r#"<geometry><cell id="1" material="1"/></geometry>"#, "cell 1 has no region and nothing around it clips it"),
        (
            r#"<geometry><surface id="1" type="sphere" coeffs="0 0 0 1"/><cell id="1" fill="5" region="+1"/><cell id="9" material="2" region="-1"/>
            <lattice id="5"><dimension>1 1</dimension><lower_left>0 0</lower_left><pitch>1 1</pitch><outer>3</outer><universes>2</universes></lattice>
            <cell id="2" universe="2" material="1"/><cell id="3" universe="3" material="1" region="-1"/></geometry>"#,
            "lattice 5: outer universe 3 has cells with regions, so it is tiled, but the cell the lattice fills is unbounded along x",
        ),
        (
            r#"<geometry><surface id="1" type="sphere" coeffs="0 0 0 1"/><cell id="1" fill="5" region="-1"/>
            <lattice id="5"><dimension>2 1</dimension><lower_left>0 0</lower_left><pitch>1 1</pitch><universes>2</universes></lattice>
            <cell id="2" universe="2" material="1"/></geometry>"#,
            "lattice 5: universes: 1 entries for 2 × 1 × 1 elements",
        ),
        ("<geometry><cell id=\"1\" material=\"1\"></geometry>", "line 1, column 37: not well-formed XML"),
    ];
    for (xml, want) in cases {
        let got = match import(xml) {
            Ok(_) => panic!("imported: {xml}"),
            Err(e) => e.to_string(),
        };
        assert!(got.contains(want), "got: {got}\nwant: {want}");
    }
}

#[test]
fn a_complement_that_openmc_reads_otherwise_is_warned_about() {
    let xml = r#"<geometry><surface id="1" type="x-plane" coeffs="0"/><surface id="2" type="y-plane" coeffs="0"/>
        <surface id="3" type="sphere" coeffs="0 0 0 5"/>
        <cell id="1" material="1" region="-3 ~(1 2 | -1)"/><cell id="2" material="2" region="-3 ~((1 2) | -1)"/></geometry>"#;
    let imported = import(xml).unwrap();
    assert_eq!(imported.warnings.len(), 1, "{:?}", imported.warnings);
    assert!(imported.warnings[0].contains("cell 1"), "{:?}", imported.warnings);
}

#[test]
fn model_xml_and_child_elements_are_read() {
    let xml = r#"<?xml version="1.0"?>
<model><materials/><geometry>
  <surface><id>1</id><type>sphere</type><coeffs>0 0 0 2</coeffs><boundary>vacuum</boundary></surface>
  <cell><id>5</id><material>3</material><region>-1</region></cell>
</geometry><settings/></model>"#;
    let (imported, world) = load(xml);
    assert_eq!(owner(&world, [0.5, 0.5, 0.5]), Some(("cell 5".into(), "material 3".into())));
    assert_eq!(owner(&world, [2.5, 0.0, 0.0]), None);
    let meta = imported.scene.metadata.unwrap();
    assert_eq!(meta["openmc"]["boundaries"]["1"], "vacuum");
}
