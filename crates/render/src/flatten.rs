//! Groups to blocks: each `blocks` list of a scene (the top one and each
//! definition's) flattened depth-first into `complex::Block`s with their
//! [`BlockInfo`]s and placed definitions ([`Member`]), so block priority is
//! document order. Definitions are flattened once each, in their own frame,
//! after those they place; a cycle of definitions is an error. Transforms compose in list order (the first step acts
//! first); a block's transform acts after its objects' own, and enclosing
//! groups' transforms after that, innermost first.

use std::collections::BTreeMap;

use complex::{Block, MaterialKey, Opacity, ShapeError};
use quadric::nalgebra::{Matrix4, Vector3};
use quadric::{GeometryError, HalfSpace, Quadric, Solid, Transform};

use crate::error::SceneError;
use crate::format::{Axis, Entry, KeyedStep, MaterialSpec, ObjectSpec, Scale, SceneFile, Step};
use crate::limits::{MAX_DEFINITION_DEPTH, MAX_GROUP_DEPTH};
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

/// A member of a flattened block list: a block, or a definition placed
/// once or on a lattice (`Member::Placed`).
#[derive(Clone, Debug)]
pub(crate) enum Member {
    /// A block, in the frame of the list it belongs to.
    Block(Block),
    /// A placed definition.
    Placed(Placed),
}

/// A definition placed by an `instance` or `lattice` entry.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Placed {
    /// The definition's index (`SceneFile::definitions` in key order).
    pub definition: usize,
    /// The definition's frame to the list's frame, after the lattice
    /// offset: the entry's transform, then its groups', innermost first.
    pub transform: Transform,
    /// The lattice's step along x, y and z (zero for an instance).
    pub pitch: Vector3<f64>,
    /// Elements along x, y and z (`[1, 1, 1]` for an instance).
    pub count: [u32; 3],
    /// The entry's JSON path, for an error the kernel finds.
    pub place: String,
}

/// A block list flattened: its members in document order, the infos of its
/// own blocks (`Member::Block`s) in order, and how many blocks its
/// expansion has.
#[derive(Clone, Debug, Default)]
pub(crate) struct Flat {
    pub members: Vec<Member>,
    pub infos: Vec<BlockInfo>,
    pub len: u64,
}

impl Flat {
    /// Whether it holds blocks only (no instances or lattices).
    pub fn is_plain(&self) -> bool {
        self.members.iter().all(|m| matches!(m, Member::Block(_)))
    }
}

/// The most blocks the expansion of a scene may have: a block id numbers
/// them in a `u32` whose largest value stands for none.
pub(crate) const MAX_BLOCKS: u64 = u32::MAX as u64 - 1;

/// The most elements of a lattice placed one by one (a lattice with a pitch
/// <= 0 on an axis of several elements).
pub(crate) const MAX_ELEMENTS_PLACED_ONE_BY_ONE: u64 = 1 << 16;

/// The flattened scene: the top list and every definition's.
#[derive(Debug, Default)]
pub(crate) struct Flattened {
    /// The top `blocks` list.
    pub top: Flat,
    /// Per definition (in key order), its list; definitions are built in
    /// `order`, each after those it places.
    pub definitions: Vec<Flat>,
    /// The definitions' indices, each after every definition it places.
    pub order: Vec<usize>,
}

#[cfg(test)]
impl Flattened {
    /// The explicit expansion: every placed definition's blocks moved to
    /// each of its places, in document order, `i` fastest, then `j`, then
    /// `k`; each block's info with its frame composed. The blocks of a
    /// placed definition keep their names and paths. The oracle of the
    /// world's placed blocks (`convert`'s tests).
    pub(crate) fn expanded(&self) -> (Vec<Block>, Vec<BlockInfo>) {
        let mut out = (vec![], vec![]);
        self.expand_into(&self.top, &Transform::identity(), &mut out);
        out
    }

    /// Appends the blocks of `list` moved by `to` (its frame to the world).
    fn expand_into(&self, list: &Flat, to: &Transform, out: &mut (Vec<Block>, Vec<BlockInfo>)) {
        let mut infos = list.infos.iter();
        for m in &list.members {
            match m {
                Member::Block(b) => {
                    let solids = b.solids().iter().map(|s| s.transformed(to)).collect();
                    let block = Block::new(b.name(), solids, b.opacity(), b.material())
                        .unwrap_or_else(|e| unreachable!("a valid block stays valid: {e}"));
                    let mut info = infos.next().cloned().unwrap_or_else(|| unreachable!("an info per block"));
                    info.frame = info.frame.map(|f| Box::new(to.inverse().then(&f)));
                    out.0.push(block);
                    out.1.push(info);
                }
                Member::Placed(p) => {
                    let [nx, ny, nz] = p.count;
                    for k in 0..nz {
                        for j in 0..ny {
                            for i in 0..nx {
                                let offset = Vector3::new(
                                    f64::from(i) * p.pitch.x,
                                    f64::from(j) * p.pitch.y,
                                    f64::from(k) * p.pitch.z,
                                );
                                let at = Transform::translate(offset)
                                    .unwrap_or_else(|_| unreachable!("a finite offset"))
                                    .then(&p.transform)
                                    .then(to);
                                self.expand_into(&self.definitions[p.definition], &at, out);
                            }
                        }
                    }
                }
            }
        }
    }
}

impl SceneFile {
    /// The definitions in an order where each comes after those it places;
    /// a reference to an unknown definition or a cycle is an error at the
    /// entry that makes it.
    fn definition_order(&self) -> Result<Vec<usize>, SceneError> {
        let names: Vec<&str> = self.definitions.keys().map(String::as_str).collect();
        let mut refs: Vec<Vec<(usize, String)>> = Vec::with_capacity(names.len());
        for (name, d) in &self.definitions {
            let place = format!("definitions{}.blocks", crate::locate::key_step(name));
            let mut out = vec![];
            references(&d.blocks, &place, &names, 0, &mut out)?;
            refs.push(out);
        }
        // Depth-first with an explicit stack: a chain of definitions as
        // long as the file allows must not overflow the thread's stack.
        #[derive(Clone, Copy, PartialEq)]
        enum State {
            New,
            Open,
            Done,
        }
        let mut state = vec![State::New; names.len()];
        let mut order = Vec::with_capacity(names.len());
        for root in 0..names.len() {
            if state[root] != State::New {
                continue;
            }
            state[root] = State::Open;
            let mut stack = vec![(root, 0)];
            while let Some((d, next)) = stack.last_mut() {
                let d = *d;
                let Some((t, place)) = refs[d].get(*next) else {
                    state[d] = State::Done;
                    order.push(d);
                    stack.pop();
                    continue;
                };
                *next += 1;
                match state[*t] {
                    State::New => {
                        state[*t] = State::Open;
                        stack.push((*t, 0));
                    }
                    State::Open => {
                        let from = stack.iter().position(|(s, _)| s == t).unwrap_or(0);
                        let cycle: Vec<String> = stack[from..]
                            .iter()
                            .map(|(s, _)| *s)
                            .chain([*t])
                            .map(|s| format!("definitions{}", crate::locate::key_step(names[s])))
                            .collect();
                        return Err(SceneError::semantic(
                            place,
                            format!("a definition places itself: {}", cycle.join(" → ")),
                        ));
                    }
                    State::Done => {}
                }
            }
        }
        // Levels of placement below each definition, settled in `order`.
        let mut depth = vec![0; names.len()];
        for &d in &order {
            for (t, place) in &refs[d] {
                depth[d] = depth[d].max(depth[*t] + 1);
                if depth[d] >= MAX_DEFINITION_DEPTH {
                    let msg = format!("definitions place each other deeper than {MAX_DEFINITION_DEPTH} levels");
                    return Err(SceneError::semantic(place, msg));
                }
            }
        }
        Ok(order)
    }

    /// The blocks and their infos, groups flattened depth-first, and the
    /// definitions, each flattened once in its own frame.
    pub(crate) fn flattened(&self, default_material: usize) -> Result<Flattened, SceneError> {
        // Per material index (the default last), whether its blocks keep their frame.
        let textured: Vec<bool> = self.materials.values().map(MaterialSpec::is_textured).chain([false]).collect();
        let order = self.definition_order()?;
        let names: Vec<&str> = self.definitions.keys().map(String::as_str).collect();
        let mut lens: Vec<Option<u64>> = vec![None; names.len()];
        let mut definitions: Vec<Flat> = vec![Flat::default(); names.len()];
        let lists = Lists { materials: &self.materials, textured: &textured, default_material, names: &names };
        for &d in &order {
            let (name, spec) = self.definitions.iter().nth(d).unwrap_or_else(|| unreachable!("a definition's index"));
            let place = format!("definitions{}", crate::locate::key_step(name));
            if spec.blocks.is_empty() {
                return Err(SceneError::semantic(&place, format!("definition \"{name}\" has no blocks")));
            }
            let flat = lists.flatten(&spec.blocks, &format!("{place}.blocks"), Some(name), &lens)?;
            lens[d] = Some(flat.len);
            definitions[d] = flat;
        }
        let top = lists.flatten(&self.blocks, "blocks", None, &lens)?;
        Ok(Flattened { top, definitions, order })
    }
}

/// The definitions `entries` place (at `place`), in document order, with
/// the place of the entry that places each; an unknown name is an error.
/// Groups deeper than flattening allows are not searched: flattening stops
/// there with its own error.
fn references(
    entries: &[Entry],
    place: &str,
    names: &[&str],
    depth: usize,
    out: &mut Vec<(usize, String)>,
) -> Result<(), SceneError> {
    for (i, e) in entries.iter().enumerate() {
        let here = format!("{place}[{i}]");
        if let Some(name) = e.instance.as_deref().or(e.lattice.as_deref()) {
            let key = if e.instance.is_some() { "instance" } else { "lattice" };
            out.push((definition_index(name, names, &format!("{here}.{key}"))?, here));
        } else if let (Some(children), true) = (&e.blocks, depth < MAX_GROUP_DEPTH) {
            references(children, &format!("{here}.blocks"), names, depth + 1, out)?;
        }
    }
    Ok(())
}

/// The index of definition `name`, or an error at `place` with the nearest name.
fn definition_index(name: &str, names: &[&str], place: &str) -> Result<usize, SceneError> {
    names.iter().position(|n| *n == name).ok_or_else(|| {
        let hint = crate::error::nearest(name, names.iter().copied())
            .map(|n| format!(" (did you mean \"{n}\"?)"))
            .unwrap_or_default();
        SceneError::semantic(place, format!("unknown definition \"{name}\"{hint}"))
    })
}

/// What flattening any list reads.
struct Lists<'a> {
    materials: &'a BTreeMap<String, MaterialSpec>,
    /// Per material index, whether it is textured (`MaterialSpec::is_textured`).
    textured: &'a [bool],
    default_material: usize,
    /// The definitions' names, in key order.
    names: &'a [&'a str],
}

impl Lists<'_> {
    /// Flattens the list `entries` at `place` (`definition`: the definition
    /// it is, `None` for the top list); `lens`: the number of blocks of each
    /// definition already flattened.
    ///
    /// A long list is cut into runs flattened in parallel, each knowing
    /// how many blocks of the expansion come before it (for the default
    /// names `block N`); the runs are joined in order and the first error in
    /// document order is returned, so the result is the sequential one.
    fn flatten(
        &self,
        entries: &[Entry],
        place: &str,
        definition: Option<&str>,
        lens: &[Option<u64>],
    ) -> Result<Flat, SceneError> {
        use rayon::prelude::*;
        /// Top-level entries per run (a run takes about a millisecond).
        const RUN: usize = 1024;
        let flattener = |before| Flattener { lists: self, lens, definition, before, flat: Flat::default() };
        if entries.len() < 2 * RUN {
            let mut flat = flattener(0);
            flat.entries(entries, 0, place, &[])?;
            return Ok(flat.flat);
        }
        let mut before = 0u64;
        let runs: Vec<(usize, &[Entry], u64)> = entries
            .chunks(RUN)
            .enumerate()
            .map(|(r, run)| {
                let first = before;
                before = before.saturating_add(
                    run.iter().map(|e| block_count(e, 0, self.names, lens)).fold(0, u64::saturating_add),
                );
                (r * RUN, run, first)
            })
            .collect();
        let runs: Vec<Result<Flattener<'_>, SceneError>> = runs
            .into_par_iter()
            .map(|(first, run, before)| {
                let mut flat = flattener(before);
                flat.entries(run, first, place, &[]).map(|()| flat)
            })
            .collect();
        let mut all = Flat { members: Vec::with_capacity(entries.len()), infos: vec![], len: 0 };
        for run in runs {
            let run = run?.flat;
            all.members.extend(run.members);
            all.infos.extend(run.infos);
            all.len += run.len;
        }
        Ok(all)
    }
}

/// How many blocks flattening `e` yields if it is valid (an invalid entry
/// stops flattening, so what it counts does not matter).
fn block_count(e: &Entry, depth: usize, names: &[&str], lens: &[Option<u64>]) -> u64 {
    if let Some(name) = e.instance.as_deref().or(e.lattice.as_deref()) {
        let len = names.iter().position(|n| *n == name).and_then(|d| lens[d]).unwrap_or(0);
        let count = if e.lattice.is_some() { e.count.unwrap_or([0; 3]) } else { [1; 3] };
        return count.iter().fold(len, |n, &c| n.saturating_mul(u64::from(c)));
    }
    match (&e.objects, &e.blocks) {
        (Some(_), None) => 1,
        (None, Some(children)) if depth < MAX_GROUP_DEPTH => {
            children.iter().map(|c| block_count(c, depth + 1, names, lens)).fold(0, u64::saturating_add)
        }
        _ => 0,
    }
}

struct Flattener<'a> {
    lists: &'a Lists<'a>,
    /// Per definition, its number of blocks once flattened.
    lens: &'a [Option<u64>],
    /// The definition whose list this is (`None`: the top list).
    definition: Option<&'a str>,
    /// Blocks of the expansion that come before this flattener's first (in other runs).
    before: u64,
    flat: Flat,
}

impl Flattener<'_> {
    /// The index of material `name`; `place` and `owner` (`block "x"`) name
    /// the reference in the error.
    fn material(&self, name: &str, place: Place<'_>, owner: &dyn std::fmt::Display) -> Result<usize, SceneError> {
        let materials = self.lists.materials;
        materials.keys().position(|k| k == name).ok_or_else(|| {
            let hint = crate::error::nearest(name, materials.keys().map(String::as_str))
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
            if e.instance.is_some() || e.lattice.is_some() {
                self.placed(e, &here, own, outer)?;
                continue;
            }
            if e.pitch.is_some() || e.count.is_some() {
                let key = if e.pitch.is_some() { "pitch" } else { "count" };
                let msg = format!("`{key}` belongs on a lattice (`\"lattice\": \"NAME\"`), not on a block or group");
                return Err(SceneError::semantic(&format!("{here}.{key}"), msg));
            }
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

    /// An `instance` or `lattice` entry at `here`, its own transform `own`.
    fn placed(&mut self, e: &Entry, here: &str, own: Transform, outer: &[Transform]) -> Result<(), SceneError> {
        let (kind, name) = match (&e.instance, &e.lattice) {
            (Some(name), None) => ("instance", name),
            (None, Some(name)) => ("lattice", name),
            _ => return Err(SceneError::semantic(here, "an entry has either `instance` or `lattice`, not both")),
        };
        let extra = [
            (e.objects.is_some(), "objects"),
            (e.blocks.is_some(), "blocks"),
            (e.group.is_some(), "group"),
            (e.name.is_some(), "name"),
            (e.material.is_some(), "material"),
            (e.transparent.is_some(), "transparent"),
        ];
        if let Some((_, key)) = extra.iter().find(|(set, _)| *set) {
            let article = if kind == "instance" { "an" } else { "a" };
            let msg = format!("{kind} of \"{name}\": `{key}` does not belong on {article} {kind}");
            return Err(SceneError::semantic(&format!("{here}.{key}"), msg));
        }
        let definition = definition_index(name, self.lists.names, &format!("{here}.{kind}"))?;
        let (pitch, count) = match (kind, e.pitch, e.count) {
            ("instance", None, None) => (Vector3::zeros(), [1, 1, 1]),
            ("instance", ..) => {
                let key = if e.pitch.is_some() { "pitch" } else { "count" };
                let msg = format!("instance of \"{name}\": `{key}` belongs on a lattice (`\"lattice\": \"{name}\"`)");
                return Err(SceneError::semantic(&format!("{here}.{key}"), msg));
            }
            (_, Some(pitch), Some(count)) => {
                // The last element's offset too, so that every element's is finite.
                let extent: Triple = std::array::from_fn(|a| pitch[a] * f64::from(count[a].max(1) - 1));
                if !(pitch.iter().chain(&extent).all(|x| x.is_finite())) {
                    let msg = format!("lattice of \"{name}\": the pitch and pitch × (count − 1) must be finite");
                    return Err(SceneError::semantic(&format!("{here}.pitch"), msg));
                }
                if count.contains(&0) {
                    let msg = format!("lattice of \"{name}\": count must be at least 1 on every axis, got {count:?}");
                    return Err(SceneError::semantic(&format!("{here}.count"), msg));
                }
                (vec3(pitch), count)
            }
            (_, pitch, _) => {
                let key = if pitch.is_none() { "pitch" } else { "count" };
                let msg = format!("lattice of \"{name}\" needs `pitch` and `count`");
                return Err(SceneError::semantic(&format!("{here}.{key}"), msg));
            }
        };
        // Definitions are flattened after those they place (`definition_order`).
        let len = self.lens[definition].unwrap_or_else(|| unreachable!("definition \"{name}\" not yet flattened"));
        let elements = count.iter().map(|&n| u64::from(n)).product::<u64>();
        let total = elements.checked_mul(len).and_then(|n| n.checked_add(self.before + self.flat.len));
        match total {
            Some(total) if total <= MAX_BLOCKS => self.flat.len += elements * len,
            _ => {
                let each = if len == 1 { "1 block".to_string() } else { format!("{len} blocks") };
                let msg = format!(
                    "{kind} of \"{name}\": the scene would have more than {MAX_BLOCKS} blocks \
                     (the most a block id can number): {elements} elements of {each} each"
                );
                return Err(SceneError::semantic(here, msg));
            }
        }
        let transform = outer.iter().fold(own, |m, g| m.then(g));
        let place = here.to_string();
        if (0..3).all(|a| count[a] == 1 || pitch[a] > 0.0) {
            self.flat.members.push(Member::Placed(Placed { definition, transform, pitch, count, place }));
            return Ok(());
        }
        // The kernel walks a lattice's cells along increasing coordinates, so
        // a lattice with a pitch <= 0 on an axis of several elements is
        // placed element by element, in the same order.
        if elements > MAX_ELEMENTS_PLACED_ONE_BY_ONE {
            let msg = format!(
                "lattice of \"{name}\": a lattice with a pitch <= 0 on an axis of several elements is placed \
                 element by element, at most {MAX_ELEMENTS_PLACED_ONE_BY_ONE} elements, got {elements} \
                 (a positive pitch and a mirroring transform place any number)"
            );
            return Err(SceneError::semantic(&format!("{here}.pitch"), msg));
        }
        for k in 0..count[2] {
            for j in 0..count[1] {
                for i in 0..count[0] {
                    let offset = Vector3::new(f64::from(i) * pitch.x, f64::from(j) * pitch.y, f64::from(k) * pitch.z);
                    // The offset is finite (the extent was checked above).
                    let step = Transform::translate(offset).map_err(|e| SceneError::semantic(here, e.to_string()))?;
                    let transform = step.then(&transform);
                    let (pitch, count, place) = (Vector3::zeros(), [1, 1, 1], place.clone());
                    self.flat.members.push(Member::Placed(Placed { definition, transform, pitch, count, place }));
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
        let number = self.before + self.flat.len + 1;
        let name = e.name.clone().unwrap_or_else(|| match self.definition {
            None => format!("block {number}"),
            Some(d) => format!("block {number} of {d}"),
        });
        // The owner and object names of error messages, written out only for an error.
        let owner = Owner { block: &name, object: None };
        let who = |j: usize| Owner { block: &name, object: Some(j + 1) };
        if objects.is_empty() {
            return Err(SceneError::semantic(&here, format!("{owner} is empty: a block needs at least one object")));
        }
        let place = Place::Text(&here);
        let material = match &e.material {
            Some(m) => self.material(m, place.key("material"), &owner)?,
            None => self.lists.default_material,
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
        self.flat.members.push(Member::Block(block));
        self.flat.len += 1;
        // Only a textured block keeps its frame: untextured scenes neither
        // store nor read one.
        let textured = |m: usize| self.lists.textured.get(m).copied().unwrap_or(false);
        let frame =
            (textured(material) || solid_materials.iter().any(|&m| textured(m))).then(|| Box::new(placement.inverse()));
        self.flat.infos.push(BlockInfo { material, solid_materials, path: here, frame });
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

/// The kernel solid an object describes, placed by its own transform and
/// complemented if it says so (no block or group transform): for a
/// converter that asks the kernel about solids it writes.
pub(crate) fn object_solid(o: &ObjectSpec) -> Result<Solid, SceneError> {
    let at = Place::Text("object");
    let solid = solid_of(o, at)?;
    let m = steps_transform(&o.transform, at)?;
    let solid = solid.try_transformed(&m).map_err(|e| SceneError::semantic("object", e.to_string()))?;
    Ok(if o.complement { solid.complement() } else { solid })
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
        assert_eq!(w.block_info(complex::BlockId(2)).path, "blocks[1].blocks[1].blocks[0]");
        let id = complex::BlockId(3);
        assert_eq!(w.surface_material(id, 0).name, "a");
        assert_eq!(w.surface_material(id, 1).name, "b");
        assert_eq!(w.block_material(id).name, "b");
        assert_eq!(w.block_material(complex::BlockId(1)).name, "(default)");
        // The table built with the world answers as the block infos do.
        for (i, (_, info)) in w.written_blocks().enumerate() {
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

    /// Flattens `scene`'s top list in one run, as lists shorter than two runs are.
    fn sequential(scene: &SceneFile) -> Result<(Vec<Block>, Vec<BlockInfo>), SceneError> {
        let materials = &scene.materials;
        let textured: Vec<bool> = materials.values().map(MaterialSpec::is_textured).chain([false]).collect();
        let lists = Lists { materials, textured: &textured, default_material: materials.len(), names: &[] };
        let mut flat = Flattener { lists: &lists, lens: &[], definition: None, before: 0, flat: Flat::default() };
        flat.entries(&scene.blocks, 0, "blocks", &[])?;
        Ok(blocks_of(flat.flat))
    }

    /// The blocks and infos of a list without placements.
    fn blocks_of(flat: Flat) -> (Vec<Block>, Vec<BlockInfo>) {
        let blocks = flat.members.into_iter().filter_map(|m| if let Member::Block(b) = m { Some(b) } else { None });
        (blocks.collect(), flat.infos)
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
        let ours = blocks_of(scene.flattened(scene.materials.len()).unwrap().top);
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
