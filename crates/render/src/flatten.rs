//! Groups to blocks: the `blocks` list of a scene flattened depth-first
//! into `complex::Block`s and their [`BlockInfo`]s, so block priority is
//! document order. Transforms compose in list order (the first step acts
//! first); a block's transform acts after its objects' own, and enclosing
//! groups' transforms after that, innermost first.

use std::collections::BTreeMap;

use complex::{Block, MaterialKey, Opacity, ShapeError};
use quadric::nalgebra::{Matrix4, Vector3};
use quadric::{GeometryError, HalfSpace, Quadric, Solid, Transform};

use crate::error::SceneError;
use crate::format::{Axis, Entry, KeyedStep, MaterialSpec, ObjectSpec, Scale, SceneFile, Step};
use crate::limits::MAX_GROUP_DEPTH;
use crate::world::{BlockInfo, Triple};

/// A triple as a vector.
pub(crate) fn vec3(t: Triple) -> Vector3<f64> {
    Vector3::new(t[0], t[1], t[2])
}

/// Whether every component of `t` is finite; else an error at `place`
/// saying that `what` must be.
pub(crate) fn finite_triple(t: &Triple, place: impl std::fmt::Display, what: &str) -> Result<(), SceneError> {
    if t.iter().all(|c| c.is_finite()) {
        Ok(())
    } else {
        Err(SceneError::semantic(&place.to_string(), format!("{what} must be finite")))
    }
}

/// Composes a list of steps, the first acting first; `place` (the list's
/// owner) is only written out for an error.
fn steps_transform(steps: &[Step], place: Place<'_>) -> Result<Transform, SceneError> {
    let mut m = Transform::identity();
    for (i, step) in steps.iter().enumerate() {
        let t = step_transform(step)
            .map_err(|e| SceneError::semantic(&place.item("transform", i).to_string(), e.to_string()))?;
        m = m.then(&t);
    }
    Ok(m)
}

/// One step's transform.
fn step_transform(step: &Step) -> Result<Transform, GeometryError> {
    match step {
        Step::Translate(v) => Transform::translate(vec3(*v)),
        Step::Scale(s) => scale_transform(s),
        Step::RotateX(d) => Transform::rotate_x_degrees(*d),
        Step::RotateY(d) => Transform::rotate_y_degrees(*d),
        Step::RotateZ(d) => Transform::rotate_z_degrees(*d),
        Step::Matrix(rows) => Transform::from_matrix(&Matrix4::from_fn(|r, c| rows[r][c])),
        Step::Keyed(k) => keyed_transform(k),
    }
}

fn scale_transform(s: &Scale) -> Result<Transform, GeometryError> {
    match s {
        Scale::Uniform(s) => Transform::scale(*s),
        Scale::PerAxis(v) => Transform::scale_xyz(vec3(*v)),
    }
}

/// A keyed step's transform at its first key (a scene resolved at a
/// frame, `SceneFile::at_frame`, has no keyed step). Apart, and not
/// recursive, so that `step_transform` stays inlined for plain steps.
#[cold]
fn keyed_transform(k: &KeyedStep) -> Result<Transform, GeometryError> {
    match k {
        KeyedStep::Translate(k) => Transform::translate(vec3(*k.first())),
        KeyedStep::Scale(k) => scale_transform(k.first()),
        KeyedStep::RotateX(k) => Transform::rotate_x_degrees(*k.first()),
        KeyedStep::RotateY(k) => Transform::rotate_y_degrees(*k.first()),
        KeyedStep::RotateZ(k) => Transform::rotate_z_degrees(*k.first()),
    }
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
    /// The blocks and their infos, groups flattened depth-first.
    ///
    /// A long `blocks` list is cut into runs flattened in parallel, each
    /// knowing how many blocks come before it (for the default names
    /// `block N`); the runs are joined in order and the first error in
    /// document order is returned, so the result is the sequential one.
    pub(crate) fn flattened(&self, default_material: usize) -> Result<(Vec<Block>, Vec<BlockInfo>), SceneError> {
        use rayon::prelude::*;
        /// Top-level entries per run (a run takes about a millisecond).
        const RUN: usize = 1024;
        // Per material index (the default last), whether its blocks keep their frame.
        let textured: Vec<bool> = self.materials.values().map(MaterialSpec::is_textured).chain([false]).collect();
        let flattener = |before| Flattener {
            materials: &self.materials,
            textured: &textured,
            default_material,
            before,
            blocks: vec![],
            infos: vec![],
        };
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
    /// Per material index, whether it is textured (`MaterialSpec::is_textured`).
    textured: &'a [bool],
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
            let solid = solid.try_transformed(&m.then(&placement)).map_err(|e| {
                let msg = match e {
                    GeometryError::Underflow { .. } => {
                        format!("the transforms (the object's, the block's and its groups') underflow: {e}")
                    }
                    _ => "the transforms (the object's, the block's and its groups') overflow: \
                          the placed solid has coefficients that are not finite"
                        .to_string(),
                };
                SceneError::semantic(&at.to_string(), format!("{}: {msg}", who(j)))
            })?;
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
        // Only a textured block keeps its frame: untextured scenes neither
        // store nor read one.
        let textured = |m: usize| self.textured.get(m).copied().unwrap_or(false);
        let frame =
            (textured(material) || solid_materials.iter().any(|&m| textured(m))).then(|| Box::new(placement.inverse()));
        self.infos.push(BlockInfo { material, solid_materials, path: here, frame });
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
    // A radius far from 1 can underflow the unit solid's coefficients; an
    // overflow is left to the check after all the transforms, which names it.
    let sized = |q: Quadric, m: &Transform, what: &str, r: f64| match q.try_transformed(m) {
        Ok(placed) => Ok(Solid::from(placed)),
        Err(e @ GeometryError::Underflow { .. }) => Err(err(format!("{what} {r:e}: {e}"))),
        Err(_) => Ok(Solid::from(q.transformed(m))),
    };
    Ok(if let Some(s) = &o.sphere {
        let r = positive(s.radius, "sphere.radius")?;
        let c = s.center.unwrap_or([0.0; 3]);
        finite_triple(&c, place, "sphere.center")?;
        // The kernel's ball; an overflow is left to the check after all the
        // transforms, as for the other shapes.
        match complex::shapes::sphere(vec3(c).into(), r) {
            Ok(ball) => ball,
            Err(ShapeError::Geometry(e @ GeometryError::Underflow { .. })) => {
                return Err(err(format!("sphere.radius {r:e}: {e}")))
            }
            Err(_) => {
                let m = Transform::scale(r).map_err(geo)?.then(&Transform::translate(vec3(c)).map_err(geo)?);
                Solid::from(Quadric::sphere().transformed(&m))
            }
        }
    } else if let Some(c) = &o.cylinder {
        let r = positive(c.radius, "cylinder.radius")?;
        let tube = match c.axis.unwrap_or_default() {
            Axis::X => Quadric::tube_x(),
            Axis::Y => Quadric::tube_y(),
            Axis::Z => Quadric::tube_z(),
        };
        sized(tube, &Transform::scale(r).map_err(geo)?, "cylinder.radius", r)?
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
    use quadric::nalgebra::Point3;

    use super::*;
    use crate::world::World;

    const CAMERA: &str = r#""camera": { "eye": [0, 0, 50], "direction": [0, 0, -1], "width": 4, "height": 3 }"#;

    fn world(blocks: &str) -> World {
        let text = format!(r#"{{ {CAMERA}, "materials": {{ "a": {{}}, "b": {{}} }}, "blocks": [ {blocks} ] }}"#);
        SceneFile::from_json(&text).unwrap().to_world().unwrap()
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
        let textured: Vec<bool> = materials.values().map(MaterialSpec::is_textured).chain([false]).collect();
        let mut flat = Flattener {
            materials,
            textured: &textured,
            default_material: materials.len(),
            before: 0,
            blocks: vec![],
            infos: vec![],
        };
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
}
