//! `komplex volume` and `komplex overlaps`: the kernel's volume and overlap
//! measurements ([`complex::Complex::volumes`], [`complex::Complex::overlaps`])
//! as JSON-ready reports and readable tables. Blocks are numbered from 1,
//! as in the EXR `id.block` channel.

use std::fmt;

use complex::{Aabb, BlockId, Estimate, VolumeOptions};
use quadric::nalgebra::Point3;
use serde::Serialize;

use crate::error::Error;
use crate::world::World;

/// The options both commands share.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MeasureOptions {
    /// The target relative standard error (`--tolerance`).
    pub tolerance: f64,
    /// The seed of the random lines (`--seed`).
    pub seed: u64,
    /// `[xmin, ymin, zmin, xmax, ymax, zmax]`: clip everything to this box (`--box`).
    pub bounds: Option<[f64; 6]>,
}

impl Default for MeasureOptions {
    fn default() -> Self {
        MeasureOptions { tolerance: complex::DEFAULT_VOLUME_TOLERANCE, seed: 0, bounds: None }
    }
}

impl MeasureOptions {
    /// `Error::Options` naming the flag out of range, if any.
    pub fn validate(&self) -> Result<(), Error> {
        self.kernel().map(|_| ())
    }

    /// The kernel's options, or `Error::Options` naming the flag out of range.
    fn kernel(&self) -> Result<VolumeOptions, Error> {
        let t = self.tolerance;
        if !(t.is_finite() && t > 0.0) {
            return Err(Error::Options(format!("--tolerance must be a finite number > 0, got {t}")));
        }
        let bounds = match self.bounds {
            None => None,
            Some(b) => {
                if !(b.iter().all(|c| c.is_finite()) && (0..3).all(|i| b[i] <= b[i + 3])) {
                    return Err(Error::Options(format!(
                        "--box must be six finite numbers XMIN YMIN ZMIN XMAX YMAX ZMAX with each min <= max, got {b:?}"
                    )));
                }
                Some(Aabb { min: Point3::new(b[0], b[1], b[2]), max: Point3::new(b[3], b[4], b[5]) })
            }
        };
        Ok(VolumeOptions { tolerance: t, seed: self.seed, bounds, ..VolumeOptions::default() })
    }
}

/// One block's volumes (`null` in JSON where the block is unbounded and unclipped).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BlockVolumeReport {
    /// 1-based block index (priority order).
    pub index: u32,
    /// The block's name.
    pub name: String,
    /// The volume the block owns under the priority rule.
    pub volume: Option<f64>,
    /// Its standard error.
    pub error: Option<f64>,
    /// The block's own volume, ignoring the others.
    pub own_volume: Option<f64>,
    /// Its standard error.
    pub own_error: Option<f64>,
    /// Whether the block's box is finite (an empty block's counts as finite).
    pub bounded: bool,
}

/// The union's volume (`null` if a block is unbounded and unclipped).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct UnionReport {
    /// The volume of the union of all blocks.
    pub volume: Option<f64>,
    /// Its standard error.
    pub error: Option<f64>,
}

/// Everything `komplex volume` prints.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct VolumeReport {
    /// Every block, in priority order.
    pub blocks: Vec<BlockVolumeReport>,
    /// The union.
    pub union: UnionReport,
    /// The box the lines covered, `[xmin, ymin, zmin, xmax, ymax, zmax]`
    /// (`null` if there is nothing bounded to measure).
    #[serde(rename = "box")]
    pub bounds: Option<[f64; 6]>,
    /// Whether the box was given (`--box`): every volume is then the part inside it.
    pub clipped: bool,
    /// The target relative standard error.
    pub tolerance: f64,
    /// The seed of the random lines.
    pub seed: u64,
    /// Lines of the last round (the one reported).
    pub lines: u64,
    /// Independent replicates per round.
    pub replicates: u32,
    /// Whether every standard error reached the tolerance.
    pub converged: bool,
}

fn split(e: Option<Estimate>) -> (Option<f64>, Option<f64>) {
    (e.map(|e| e.value), e.map(|e| e.error))
}

fn box6(b: &Aabb) -> Option<[f64; 6]> {
    b.is_bounded().then(|| [b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z])
}

/// The most blocks (instances expanded) `volume` and `overlaps` measure:
/// they report every block, or every pair of blocks, one by one.
pub const MAX_BLOCKS_MEASURED: usize = 1 << 20;

/// An error if `world` has more blocks than [`MAX_BLOCKS_MEASURED`].
fn measurable(world: &World, command: &str) -> Result<(), Error> {
    let n = world.complex.len();
    if n <= MAX_BLOCKS_MEASURED {
        return Ok(());
    }
    Err(Error::Options(format!(
        "{command}: the scene has {n} blocks (instances and lattices expanded), more than the \
         {MAX_BLOCKS_MEASURED} it measures one by one"
    )))
}

/// Measures every block's volume, its own and the union's.
pub fn volumes(world: &World, options: &MeasureOptions) -> Result<VolumeReport, Error> {
    let kernel = options.kernel()?;
    measurable(world, "volume")?;
    let complex = &world.complex;
    let v = complex.volumes(&kernel).map_err(|e| Error::Options(e.to_string()))?;
    let blocks = v
        .blocks
        .iter()
        .enumerate()
        .map(|(i, b)| {
            let aabb = complex.block_aabb(BlockId(i as u32));
            let (volume, error) = split(b.owned);
            let (own_volume, own_error) = split(b.own);
            BlockVolumeReport {
                index: i as u32 + 1,
                name: complex.block(BlockId(i as u32)).name().to_string(),
                volume,
                error,
                own_volume,
                own_error,
                bounded: aabb.is_empty() || aabb.is_bounded(),
            }
        })
        .collect();
    let (volume, error) = split(v.union);
    Ok(VolumeReport {
        blocks,
        union: UnionReport { volume, error },
        bounds: box6(&v.bounds),
        clipped: options.bounds.is_some(),
        tolerance: options.tolerance,
        seed: options.seed,
        lines: v.lines,
        replicates: v.replicates,
        converged: v.converged,
    })
}

/// One name's volume: the sum over the blocks of that name (`null` in
/// JSON where one is unbounded and unclipped).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct NameVolumeReport {
    /// The name (an imported OpenMC cell's is `cell <id>`).
    pub name: String,
    /// How many blocks carry it.
    pub blocks: u32,
    /// The volume they own under the priority rule.
    pub volume: Option<f64>,
    /// Its standard error.
    pub error: Option<f64>,
}

/// Everything `komplex volume --by-name` prints.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct NamesReport {
    /// Every name, in order of its first block.
    pub names: Vec<NameVolumeReport>,
    /// The union.
    pub union: UnionReport,
    /// The box the lines covered (as in [`VolumeReport`]).
    #[serde(rename = "box")]
    pub bounds: Option<[f64; 6]>,
    /// Whether the box was given (`--box`).
    pub clipped: bool,
    /// The target relative standard error (of each name's volume and the union's).
    pub tolerance: f64,
    /// The seed of the random lines.
    pub seed: u64,
    /// Lines of the last round.
    pub lines: u64,
    /// Independent replicates per round.
    pub replicates: u32,
    /// Whether every standard error reached the tolerance.
    pub converged: bool,
}

/// The volume the blocks of each name own together
/// ([`complex::Complex::group_volumes`]): only the names' volumes and the
/// union's need reach the tolerance.
pub fn volumes_by_name(world: &World, options: &MeasureOptions) -> Result<NamesReport, Error> {
    let kernel = options.kernel()?;
    measurable(world, "volume --by-name")?;
    let complex = &world.complex;
    let mut names: Vec<NameVolumeReport> = Vec::new();
    let mut index: std::collections::HashMap<&str, u32> = std::collections::HashMap::new();
    let group: Vec<u32> = (0..complex.len() as u32)
        .map(|i| {
            let name = complex.block(BlockId(i)).name();
            let g = *index.entry(name).or_insert_with(|| {
                names.push(NameVolumeReport { name: name.to_string(), blocks: 0, volume: None, error: None });
                names.len() as u32 - 1
            });
            names[g as usize].blocks += 1;
            g
        })
        .collect();
    let v = complex.group_volumes(&kernel, &group, names.len()).map_err(|e| Error::Options(e.to_string()))?;
    for (row, e) in names.iter_mut().zip(&v.groups) {
        (row.volume, row.error) = split(*e);
    }
    let (volume, error) = split(v.union);
    Ok(NamesReport {
        names,
        union: UnionReport { volume, error },
        bounds: box6(&v.bounds),
        clipped: options.bounds.is_some(),
        tolerance: options.tolerance,
        seed: options.seed,
        lines: v.lines,
        replicates: v.replicates,
        converged: v.converged,
    })
}

impl NamesReport {
    /// The report as pretty-printed JSON (`komplex volume --by-name --json`).
    pub fn to_json(&self) -> String {
        json(self)
    }
}

impl fmt::Display for NamesReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let w = self.names.iter().map(|b| b.name.chars().count()).max().unwrap_or(0).max(4);
        writeln!(f, "{:<w$} {:>7} {:>24}", "name", "blocks", "owned volume")?;
        for n in &self.names {
            writeln!(f, "{:<w$} {:>7} {:>24}", n.name, n.blocks, pm(n.volume, n.error))?;
        }
        footer(
            f,
            &self.union,
            self.bounds,
            self.clipped,
            (self.lines, self.replicates, self.seed, self.tolerance),
            self.converged,
        )
    }
}

/// Pretty-printed JSON with a final newline.
fn json<T: Serialize>(value: &T) -> String {
    // Plain structs of numbers, strings and options: serialising cannot fail.
    serde_json::to_string_pretty(value).unwrap_or_default() + "\n"
}

impl VolumeReport {
    /// The report as pretty-printed JSON (`komplex volume --json`).
    pub fn to_json(&self) -> String {
        json(self)
    }
}

impl OverlapsReport {
    /// The report as pretty-printed JSON (`komplex overlaps --json`).
    pub fn to_json(&self) -> String {
        json(self)
    }
}

/// The lines under a volume table: the union, the box, the lines and
/// whether the tolerance was reached.
fn footer(
    f: &mut fmt::Formatter<'_>,
    union: &UnionReport,
    bounds: Option<[f64; 6]>,
    clipped: bool,
    (lines, replicates, seed, tolerance): (u64, u32, u64, f64),
    converged: bool,
) -> fmt::Result {
    writeln!(f, "union: {}", pm(union.volume, union.error))?;
    match (bounds, clipped) {
        (Some(b), true) => writeln!(f, "clipped to the box {:?} .. {:?}", &b[..3], &b[3..])?,
        (Some(b), false) => writeln!(f, "box: {:?} .. {:?}", &b[..3], &b[3..])?,
        (None, _) => {}
    }
    write!(f, "{lines} lines in {replicates} replicates, seed {seed}, tolerance {tolerance:e}")?;
    if converged {
        writeln!(f)
    } else {
        writeln!(f, "\nwarning: the tolerance was not reached within the line cap")
    }
}

/// A number with its standard error, or "unbounded".
fn pm(value: Option<f64>, error: Option<f64>) -> String {
    match (value, error) {
        (Some(v), Some(e)) => format!("{v:.6e} ± {e:.1e}"),
        _ => "unbounded".to_string(),
    }
}

impl fmt::Display for VolumeReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let w = self.blocks.iter().map(|b| b.name.chars().count()).max().unwrap_or(0).max(4);
        writeln!(f, "{:>5}  {:<w$} {:>24} {:>24}", "block", "name", "owned volume", "own volume")?;
        for b in &self.blocks {
            writeln!(
                f,
                "{:>5}  {:<w$} {:>24} {:>24}",
                b.index,
                b.name,
                pm(b.volume, b.error),
                pm(b.own_volume, b.own_error)
            )?;
        }
        footer(
            f,
            &self.union,
            self.bounds,
            self.clipped,
            (self.lines, self.replicates, self.seed, self.tolerance),
            self.converged,
        )
    }
}

/// One overlapping pair.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct OverlapReport {
    /// 1-based index of the first block.
    pub a: u32,
    /// 1-based index of the second block.
    pub b: u32,
    /// The first block's name.
    pub a_name: String,
    /// The second block's name.
    pub b_name: String,
    /// The volume they share.
    pub volume: f64,
    /// Its standard error.
    pub error: f64,
    /// A point inside both.
    pub point: [f64; 3],
}

/// Everything `komplex overlaps` prints.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct OverlapsReport {
    /// The overlapping pairs, by `(a, b)`.
    pub overlaps: Vec<OverlapReport>,
    /// Pairs of blocks whose boxes overlap with positive volume (the candidates).
    pub candidates: usize,
    /// Pairs `[a, b]` whose common box is unbounded, not measured (give `--box`).
    pub unmeasured: Vec<[u32; 2]>,
    /// Whether every measured pair's standard error reached the tolerance.
    pub converged: bool,
    /// The target relative standard error.
    pub tolerance: f64,
    /// The seed of the random lines.
    pub seed: u64,
}

/// Finds every pair of blocks whose own regions share a positive volume.
pub fn overlaps(world: &World, options: &MeasureOptions) -> Result<OverlapsReport, Error> {
    overlaps_among(world, options, |_, _| true)
}

/// [`overlaps`] among the pairs of blocks of different names only (the
/// blocks of one imported OpenMC cell may overlap: they are one region).
pub fn overlaps_between_names(world: &World, options: &MeasureOptions) -> Result<OverlapsReport, Error> {
    let complex = &world.complex;
    overlaps_among(world, options, |a, b| complex.block(a).name() != complex.block(b).name())
}

fn overlaps_among(
    world: &World,
    options: &MeasureOptions,
    include: impl Fn(BlockId, BlockId) -> bool,
) -> Result<OverlapsReport, Error> {
    let kernel = VolumeOptions { max_pairs: usize::MAX - 1, ..options.kernel()? };
    measurable(world, "overlaps")?;
    let complex = &world.complex;
    let found = complex.overlaps_where(&kernel, include).map_err(|e| Error::Options(e.to_string()))?;
    let name = |id: BlockId| complex.block(id).name().to_string();
    Ok(OverlapsReport {
        overlaps: found
            .pairs
            .iter()
            .map(|p| OverlapReport {
                a: p.a.0 + 1,
                b: p.b.0 + 1,
                a_name: name(p.a),
                b_name: name(p.b),
                volume: p.volume.value,
                error: p.volume.error,
                point: [p.point.x, p.point.y, p.point.z],
            })
            .collect(),
        candidates: found.candidates,
        unmeasured: found.unbounded.iter().map(|(a, b)| [a.0 + 1, b.0 + 1]).collect(),
        converged: found.converged,
        tolerance: options.tolerance,
        seed: options.seed,
    })
}

impl fmt::Display for OverlapsReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.overlaps.is_empty() {
            writeln!(f, "no overlaps ({} pairs of blocks with overlapping boxes measured)", self.candidates)?;
        } else {
            let names: Vec<String> =
                self.overlaps.iter().map(|o| format!("\"{}\" & \"{}\"", o.a_name, o.b_name)).collect();
            let w = names.iter().map(|n| n.chars().count()).max().unwrap_or(0).max(5);
            writeln!(f, "{:>5} {:>5}  {:<w$} {:>24}  point", "a", "b", "names", "shared volume")?;
            for (o, names) in self.overlaps.iter().zip(&names) {
                writeln!(
                    f,
                    "{:>5} {:>5}  {:<w$} {:>24}  ({:.6}, {:.6}, {:.6})",
                    o.a,
                    o.b,
                    names,
                    pm(Some(o.volume), Some(o.error)),
                    o.point[0],
                    o.point[1],
                    o.point[2]
                )?;
            }
        }
        for [a, b] in &self.unmeasured {
            writeln!(f, "warning: blocks {a} and {b} share an unbounded box and were not measured (use --box)")?;
        }
        if !self.converged {
            writeln!(f, "warning: the tolerance was not reached within the line cap")?;
        }
        Ok(())
    }
}
