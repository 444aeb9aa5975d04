//! The point-location grid: a uniform grid over the bounded blocks' boxes
//! whose cells list the blocks whose boxes meet them, for
//! [`Complex::contains_point`](crate::Complex::contains_point) and the batch
//! [`Complex::classify`](crate::Complex::classify).
//!
//! A point needs no walk down a tree: its cell is three multiplications
//! away, and the cell's list (about one block, sorted by id) is all there
//! is to test. Blocks whose boxes span too many cells (a floor under small
//! parts, say) are kept in one list tested for every point instead, so the
//! grid stays small whatever the scene: at most [`MAX_SPAN`] entries a block.

use quadric::nalgebra::Point3;

use crate::Aabb;

/// Cells per bounded block the grid aims at (more cells than blocks: a
/// cell then meets about one block's box).
const CELLS_PER_BLOCK: usize = 8;
/// Upper bound on the number of cells (16 MiB of offsets).
const MAX_CELLS: usize = 1 << 22;
/// A block whose box spans more cells than this goes to the list tested for
/// every point.
const MAX_SPAN: usize = 64;

/// Cells of the bounded blocks' boxes; see the module documentation.
#[derive(Clone, Debug)]
pub(crate) struct PointGrid {
    /// The box of all bounded blocks: no point outside it is in one.
    bounds: Aabb,
    /// The corner of cell `(0, 0, 0)`.
    origin: [f64; 3],
    /// Cells per unit length on each axis (0 on an axis of one cell).
    scale: [f64; 3],
    /// Cells on each axis.
    dims: [usize; 3],
    /// The last cell's coordinate on each axis, `dims - 1`.
    last: [f64; 3],
    /// Cell `c`'s blocks are `items[offsets[c]..offsets[c + 1]]`.
    offsets: Vec<u32>,
    /// Block indices, ascending within each cell.
    items: Vec<u32>,
    /// Blocks whose boxes span more than [`MAX_SPAN`] cells, ascending.
    wide: Vec<u32>,
}

impl Default for PointGrid {
    fn default() -> Self {
        PointGrid {
            bounds: Aabb::EMPTY,
            origin: [0.0; 3],
            scale: [0.0; 3],
            dims: [1; 3],
            last: [0.0; 3],
            offsets: Vec::new(),
            items: Vec::new(),
            wide: Vec::new(),
        }
    }
}

impl PointGrid {
    /// The grid over `bounded`: `(block index, box)` of bounded, non-empty
    /// blocks in ascending block order.
    pub(crate) fn new(bounded: &[(u32, Aabb)]) -> Self {
        let scene = bounded.iter().fold(Aabb::EMPTY, |a, (_, b)| a.union(b));
        if !scene.is_bounded() {
            return PointGrid::default();
        }
        let size = scene.size();
        let longest = size.amax();
        let target = (CELLS_PER_BLOCK * bounded.len()).clamp(1, MAX_CELLS) as f64;
        // Near-cubic cells: the side `h` that gives about `target` cells
        // over the axes that have a length (a flat scene is a grid of one
        // layer).
        let long_axes: Vec<f64> = size.iter().copied().filter(|&s| s > 1e-9 * longest).collect();
        let volume: f64 = long_axes.iter().product();
        let h = if long_axes.is_empty() { 1.0 } else { (volume / target).powf(1.0 / long_axes.len() as f64) };
        let mut grid =
            PointGrid { bounds: scene, origin: [scene.min.x, scene.min.y, scene.min.z], ..Default::default() };
        for i in 0..3 {
            let cells = if size[i] > 1e-9 * longest && h > 0.0 { (size[i] / h).ceil().clamp(1.0, 1024.0) } else { 1.0 };
            grid.dims[i] = cells as usize;
            grid.last[i] = cells - 1.0;
            grid.scale[i] = if cells > 1.0 { cells / size[i] } else { 0.0 };
        }
        // Counting sort by cell: count, prefix sums, fill in block order
        // (so each cell's list is ascending).
        let cells = grid.dims.iter().product::<usize>();
        let mut counts = vec![0u32; cells + 1];
        let mut spans = Vec::with_capacity(bounded.len());
        for &(i, b) in bounded {
            let (lo, hi) = (grid.coords(&b.min), grid.coords(&b.max));
            let span = (0..3).map(|k| hi[k] - lo[k] + 1).product::<usize>();
            if span > MAX_SPAN {
                grid.wide.push(i);
                continue;
            }
            for_each_cell(grid.dims, lo, hi, |c| counts[c + 1] += 1);
            spans.push((i, lo, hi));
        }
        for c in 0..cells {
            counts[c + 1] += counts[c];
        }
        let mut next = counts.clone();
        let mut items = vec![0; counts[cells] as usize];
        for (i, lo, hi) in spans {
            for_each_cell(grid.dims, lo, hi, |c| {
                items[next[c] as usize] = i;
                next[c] += 1;
            });
        }
        grid.items = items;
        grid.offsets = counts;
        grid
    }

    /// The cell coordinates of `p`, clamped to the grid: monotone in each
    /// coordinate, so a point of a box lies in a cell of the box's range.
    #[inline(always)]
    fn coords(&self, p: &Point3<f64>) -> [usize; 3] {
        let mut c = [0; 3];
        for i in 0..3 {
            // Clamped first (`max` takes 0 for NaN), so `as usize` floors.
            c[i] = ((p[i] - self.origin[i]) * self.scale[i]).max(0.0).min(self.last[i]) as u32 as usize;
        }
        c
    }

    /// The blocks listed in `p`'s cell, ascending: every bounded block whose
    /// box holds `p` and does not span more than [`MAX_SPAN`] cells is
    /// among them (others too: a cell is bigger than a point).
    #[inline(always)]
    pub(crate) fn cell_blocks(&self, p: &Point3<f64>) -> &[u32] {
        // Also every point of an empty grid, and NaN.
        if !self.bounds.contains_point(p) {
            return &[];
        }
        let [x, y, z] = self.coords(p);
        let c = x + self.dims[0] * (y + self.dims[1] * z);
        &self.items[self.offsets[c] as usize..self.offsets[c + 1] as usize]
    }

    /// The blocks whose boxes span more than [`MAX_SPAN`] cells, ascending.
    #[inline(always)]
    pub(crate) fn wide_blocks(&self) -> &[u32] {
        &self.wide
    }
}

/// Calls `f` with the index of every cell in `[lo, hi]` of a grid of `dims` cells.
fn for_each_cell(dims: [usize; 3], lo: [usize; 3], hi: [usize; 3], mut f: impl FnMut(usize)) {
    for z in lo[2]..=hi[2] {
        for y in lo[1]..=hi[1] {
            for x in lo[0]..=hi[0] {
                f(x + dims[0] * (y + dims[1] * z));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn aabb(min: [f64; 3], max: [f64; 3]) -> Aabb {
        Aabb { min: Point3::from(min), max: Point3::from(max) }
    }

    /// Every box holding a point is listed in its cell (or is wide), on a
    /// grid of random boxes of very different sizes, for points inside,
    /// on the faces of and outside the boxes.
    #[test]
    fn a_point_s_cell_lists_every_box_that_holds_it() {
        let mut s = 0x2545_F491_4F6C_DD1Du64;
        let mut next = move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut boxes = Vec::new();
        for i in 0..300u32 {
            let c = [next() * 50.0 - 10.0, next() * 20.0, next() * 1e-3];
            let r = if i % 50 == 0 { 30.0 } else { 0.1 + next() };
            boxes.push((i, aabb([c[0] - r, c[1] - r, c[2]], [c[0] + r, c[1] + r, c[2] + r * next()])));
        }
        let grid = PointGrid::new(&boxes);
        assert!(!grid.wide_blocks().is_empty() && grid.wide_blocks().len() < 20, "{:?}", grid.wide_blocks());
        for _ in 0..20_000 {
            let (_, b) = boxes[(next() * boxes.len() as f64) as usize];
            let t = [next(), next(), next()];
            // Inside, on a corner, or somewhat outside the box.
            let p = Point3::from(std::array::from_fn::<f64, 3, _>(|k| {
                let u = match (next() * 3.0) as u32 {
                    0 => t[k],
                    1 => t[k].round(),
                    _ => 1.5 * t[k] - 0.25,
                };
                b.min[k] + u * (b.max[k] - b.min[k])
            }));
            let listed: Vec<u32> = grid.cell_blocks(&p).iter().chain(grid.wide_blocks()).copied().collect();
            assert!(grid.cell_blocks(&p).windows(2).all(|w| w[0] < w[1]));
            for (i, b) in &boxes {
                if b.contains_point(&p) {
                    assert!(listed.contains(i), "block {i} holds {p:?} but is not listed");
                }
            }
        }
    }

    #[test]
    fn empty_flat_and_single_point_scenes() {
        let none = PointGrid::new(&[]);
        assert!(none.cell_blocks(&Point3::origin()).is_empty());
        let point = PointGrid::new(&[(3, aabb([1.0; 3], [1.0; 3]))]);
        assert_eq!(point.cell_blocks(&Point3::new(1.0, 1.0, 1.0)), [3]);
        let flat =
            PointGrid::new(&[(0, aabb([0.0, 0.0, 2.0], [1.0, 1.0, 2.0])), (1, aabb([1.0, 0.0, 2.0], [2.0, 1.0, 2.0]))]);
        assert_eq!(flat.cell_blocks(&Point3::new(1.0, 0.5, 2.0)), [0, 1]);
        assert_eq!(flat.cell_blocks(&Point3::new(0.2, 0.5, 2.0)), [0]);
        // Outside the blocks' box, or NaN: nothing to test.
        assert!(flat.cell_blocks(&Point3::new(f64::NAN, 0.5, 2.0)).is_empty());
        assert!(flat.cell_blocks(&Point3::new(0.5, 0.5, 2.5)).is_empty());
    }
}
