//! `komplex slice`: the exact ownership map of a plane. Each pixel's centre
//! is one point of the plane; its owner is the kernel's answer
//! ([`Complex::classify`](complex::Complex::classify), the priority rule of
//! docs/model.md §3.4) and its overlap count the number of blocks whose own
//! solids hold it
//! ([`Complex::blocks_containing`](complex::Complex::blocks_containing)).
//! The map goes to a PNG (colours by block or material, boundaries drawn,
//! overlaps hatched) or to an EXR of ids.

use std::path::Path;

use complex::{Aabb, BlockId};
use quadric::nalgebra::{Point3, Vector3};
use rayon::prelude::*;

use crate::error::Error;
use crate::limits::MAX_PIXELS;
use crate::world::World;

/// A plane with an orthonormal frame: the point `origin + u·U + v·V` has
/// plane coordinates `(u, v)`; `U` points right in the image, `V` up, and
/// `U × V` is the normal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plane {
    origin: Point3<f64>,
    u: Vector3<f64>,
    v: Vector3<f64>,
    normal: Vector3<f64>,
}

impl Plane {
    /// An axis-aligned plane from `x=C`, `y=C` or `z=C` (spaces allowed):
    /// `x=C` shows `y` to the right and `z` up, `y=C` `x` and `z`, `z=C`
    /// `x` and `y`; the plane coordinates are those world coordinates
    /// exactly. Errors name `--plane` and the text.
    ///
    /// ```
    /// use render::slice::Plane;
    /// let p = Plane::axis("z = 0.5").unwrap();
    /// assert_eq!(p.at(1.0, 2.0), [1.0, 2.0, 0.5].into());
    /// let p = Plane::axis("y=-1").unwrap();
    /// assert_eq!(p.at(3.0, 4.0), [3.0, -1.0, 4.0].into());
    /// assert!(Plane::axis("w=1").is_err() && Plane::axis("x=").is_err());
    /// ```
    pub fn axis(text: &str) -> Result<Plane, Error> {
        let bad = |why: &str| Error::Options(format!("--plane \"{text}\": {why}"));
        let Some((axis, value)) = text.split_once('=') else {
            return Err(bad("expected x=C, y=C or z=C with a number C"));
        };
        let c: f64 = value.trim().parse().map_err(|_| bad(&format!("\"{}\" is not a number", value.trim())))?;
        if !c.is_finite() {
            return Err(bad("the coordinate must be finite"));
        }
        let (x, y, z) = (Vector3::x(), Vector3::y(), Vector3::z());
        // Frames of `Plane::new` with these normals and ups: `U = V × N`.
        let (origin, u, v, normal) = match axis.trim() {
            "x" | "X" => (Point3::new(c, 0.0, 0.0), y, z, x),
            "y" | "Y" => (Point3::new(0.0, c, 0.0), x, z, -y),
            "z" | "Z" => (Point3::new(0.0, 0.0, c), x, y, z),
            other => return Err(bad(&format!("the axis must be x, y or z, not \"{other}\""))),
        };
        Ok(Plane { origin, u, v, normal })
    }

    /// The plane through `origin` with normal `normal` (any length), `V`
    /// the part of `up` orthogonal to it (default: `z`, or `y` for a normal
    /// within about 25° of `z`), `U = V × N`. A zero or non-finite vector,
    /// or an `up` parallel to the normal, is an error naming the option.
    ///
    /// ```
    /// use render::slice::Plane;
    /// // The plane x + y = 2, seen from the side its normal points to.
    /// let p = Plane::new([1.0, 1.0, 0.0], [1.0, 1.0, 0.0], None).unwrap();
    /// let q = p.at(1.0, 0.5);
    /// assert!((q.x + q.y - 2.0).abs() < 1e-15 && (q.z - 0.5).abs() < 1e-15);
    /// assert!(Plane::new([0.0; 3], [0.0; 3], None).is_err());
    /// assert!(Plane::new([0.0; 3], [0.0, 0.0, 1.0], Some([0.0, 0.0, 2.0])).is_err());
    /// ```
    pub fn new(origin: [f64; 3], normal: [f64; 3], up: Option<[f64; 3]>) -> Result<Plane, Error> {
        let finite = |v: &[f64; 3]| v.iter().all(|c| c.is_finite());
        if !finite(&origin) {
            return Err(Error::Options(format!("--origin: the point {origin:?} is not finite")));
        }
        let n = Vector3::from(normal);
        if !finite(&normal) || n.amax() == 0.0 {
            return Err(Error::Options(format!("--normal: the normal {normal:?} is zero or not finite")));
        }
        let n = (n / n.amax()).normalize();
        let up = match up {
            Some(up) if !finite(&up) => {
                return Err(Error::Options(format!("--up: the vector {up:?} is not finite")));
            }
            Some(up) => Vector3::from(up),
            None if n.z.abs() < 0.9 => Vector3::z(),
            None => Vector3::y(),
        };
        let v = up - n * up.dot(&n);
        // Parallel (or zero) to within rounding: no direction is left.
        if v.norm() <= 1e-9 * up.norm() || v.norm() == 0.0 {
            return Err(Error::Options(format!(
                "--up: the vector {:?} is zero or parallel to the normal",
                up.as_slice()
            )));
        }
        let v = v.normalize();
        Ok(Plane { origin: Point3::from(origin), u: v.cross(&n), v, normal: n })
    }

    /// The point with plane coordinates `(u, v)`.
    pub fn at(&self, u: f64, v: f64) -> Point3<f64> {
        self.origin + self.u * u + self.v * v
    }

    /// The unit normal (`U × V`).
    pub fn normal(&self) -> Vector3<f64> {
        self.normal
    }

    /// The rectangle of plane coordinates that holds where the plane cuts
    /// `aabb`, with a margin of 5 % of its longer side on every side. An
    /// unbounded or empty box, or one the plane misses, is an error that
    /// asks for `--extent`.
    ///
    /// ```
    /// use complex::Aabb;
    /// use render::slice::Plane;
    /// let cube = Aabb { min: [-1.0, -1.0, -1.0].into(), max: [1.0, 1.0, 3.0].into() };
    /// let e = Plane::axis("x=0").unwrap().extent_of(&cube).unwrap();
    /// assert_eq!([e.u0, e.u1, e.v0, e.v1], [-1.2, 1.2, -1.2, 3.2]);
    /// assert!(Plane::axis("x=5").unwrap().extent_of(&cube).is_err());
    /// ```
    pub fn extent_of(&self, aabb: &Aabb) -> Result<Extent, Error> {
        if aabb.is_empty() || !aabb.is_bounded() {
            return Err(Error::Options(
                "the scene is unbounded (or empty), so the slice has no default extent: give --extent U0 U1 V0 V1"
                    .into(),
            ));
        }
        let corner = |k: usize| {
            Point3::new(
                if k & 1 == 0 { aabb.min.x } else { aabb.max.x },
                if k & 2 == 0 { aabb.min.y } else { aabb.max.y },
                if k & 4 == 0 { aabb.min.z } else { aabb.max.z },
            )
        };
        let side = |p: &Point3<f64>| (p - self.origin).dot(&self.normal);
        // The polygon's vertices: corners on the plane, and the crossings of
        // the edges whose ends lie on opposite sides.
        let mut cut = Vec::new();
        for a in 0..8 {
            let (pa, da) = (corner(a), side(&corner(a)));
            if da == 0.0 {
                cut.push(pa);
            }
            for bit in [1, 2, 4] {
                let b = a | bit;
                let (pb, db) = (corner(b), side(&corner(b)));
                if b != a && da * db < 0.0 {
                    cut.push(pa + (pb - pa) * (da / (da - db)));
                }
            }
        }
        let (mut u0, mut u1, mut v0, mut v1) = (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
        for p in &cut {
            let (u, v) = ((p - self.origin).dot(&self.u), (p - self.origin).dot(&self.v));
            (u0, u1, v0, v1) = (u0.min(u), u1.max(u), v0.min(v), v1.max(v));
        }
        let margin = 0.05 * (u1 - u0).max(v1 - v0);
        if margin > 0.0 {
            Ok(Extent { u0: u0 - margin, u1: u1 + margin, v0: v0 - margin, v1: v1 + margin })
        } else {
            // No vertex (the margin is -∞), or a single point of the box.
            Err(Error::Options("the plane does not cut the scene's bounding box: give --extent U0 U1 V0 V1".into()))
        }
    }
}

/// A rectangle of plane coordinates: `u` from `u0` (the image's left edge)
/// to `u1`, `v` from `v0` (its bottom edge) to `v1`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Extent {
    /// Left edge.
    pub u0: f64,
    /// Right edge.
    pub u1: f64,
    /// Bottom edge.
    pub v0: f64,
    /// Top edge.
    pub v1: f64,
}

impl Extent {
    /// `--extent U0 U1 V0 V1`: finite, `U0 < U1` and `V0 < V1`.
    pub fn new(u0: f64, u1: f64, v0: f64, v1: f64) -> Result<Extent, Error> {
        let ok = [u0, u1, v0, v1].iter().all(|c| c.is_finite()) && u0 < u1 && v0 < v1 && (u1 - u0).is_finite();
        if !ok || !(v1 - v0).is_finite() {
            return Err(Error::Options(format!(
                "--extent {u0} {u1} {v0} {v1}: needs finite U0 < U1 and V0 < V1 (and a finite width and height)"
            )));
        }
        Ok(Extent { u0, u1, v0, v1 })
    }
}

/// The longer side of the image when `--size` is not given.
pub const DEFAULT_LONG_SIDE: u32 = 800;

/// The image: a plane, the rectangle of it shown, and its pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Raster {
    /// The plane.
    pub plane: Plane,
    /// The rectangle shown.
    pub extent: Extent,
    /// Pixels across.
    pub width: u32,
    /// Pixels down.
    pub height: u32,
}

impl Raster {
    /// `size` in pixels, or by default [`DEFAULT_LONG_SIDE`] on the
    /// extent's longer side and the other from its aspect ratio (at least
    /// one pixel). A size with a zero side or more than
    /// [`MAX_PIXELS`] pixels is an error naming `--size`.
    pub fn new(plane: Plane, extent: Extent, size: Option<(u32, u32)>) -> Result<Raster, Error> {
        let (width, height) = size.unwrap_or_else(|| {
            let aspect = (extent.v1 - extent.v0) / (extent.u1 - extent.u0);
            let long = f64::from(DEFAULT_LONG_SIDE);
            let short = |r: f64| (long * r).round().clamp(1.0, long) as u32;
            if aspect <= 1.0 {
                (DEFAULT_LONG_SIDE, short(aspect))
            } else {
                (short(1.0 / aspect), DEFAULT_LONG_SIDE)
            }
        });
        if width == 0 || height == 0 {
            return Err(Error::Options(format!("--size: the image size {width}x{height} is empty")));
        }
        if u64::from(width) * u64::from(height) > MAX_PIXELS {
            return Err(Error::Options(format!(
                "--size: the image size {width}x{height} is too large: at most {MAX_PIXELS} pixels are supported"
            )));
        }
        Ok(Raster { plane, extent, width, height })
    }

    /// The plane coordinates of the centre of pixel `(i, j)` (column `i`
    /// from the left, row `j` from the top):
    /// `u = u0 + (i + ½)(u1 − u0)/W`, `v = v1 − (j + ½)(v1 − v0)/H`.
    pub fn centre(&self, i: u32, j: u32) -> (f64, f64) {
        let Extent { u0, u1, v0, v1 } = self.extent;
        let u = u0 + (f64::from(i) + 0.5) * (u1 - u0) / f64::from(self.width);
        let v = v1 - (f64::from(j) + 0.5) * (v1 - v0) / f64::from(self.height);
        (u, v)
    }

    /// The world point at the centre of pixel `(i, j)`.
    pub fn point(&self, i: u32, j: u32) -> Point3<f64> {
        let (u, v) = self.centre(i, j);
        self.plane.at(u, v)
    }
}

/// What colours a PNG slice.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ColorBy {
    /// One colour per block (the default).
    #[default]
    Block,
    /// One colour per material.
    Material,
    /// One colour per block name: the blocks of one name (an imported
    /// OpenMC cell's terms) are one region, drawn without boundaries or
    /// hatching between them.
    Name,
}

/// The ownership map of a raster: per pixel (rows from the top), the
/// owner's 1-based block index (0: empty space), its material's 1-based
/// index into [`World::materials`] (0: empty space), its name's, and how
/// many blocks (and how many distinct names) hold the pixel's centre (two
/// or more: an overlap).
#[derive(Clone, Debug, PartialEq)]
pub struct Slice {
    /// Pixels across.
    pub width: u32,
    /// Pixels down.
    pub height: u32,
    /// 1-based owner block, 0 for none.
    pub block: Vec<u32>,
    /// 1-based material of the owner, 0 for none.
    pub material: Vec<u32>,
    /// Blocks whose own solids hold the pixel's centre.
    pub overlap: Vec<u32>,
    /// 1-based index of the owner's name in [`Slice::names`], 0 for none.
    pub name: Vec<u32>,
    /// Distinct names among the blocks holding the pixel's centre.
    pub named_overlap: Vec<u32>,
    /// The owners' names, in order of first appearance (row by row).
    pub names: Vec<String>,
}

/// Rows classified at a time: bounds the memory of the points.
const BAND_ROWS: u32 = 64;

/// Points per parallel task of the overlap count.
const OVERLAP_CHUNK: usize = 1024;

/// The ownership map of `raster` in `world`, in parallel on rayon's current
/// pool; the same for any number of threads.
///
/// ```
/// use render::slice::{slice, Plane, Raster};
/// let text = r#"{
///   "camera": { "eye": [0, 0, 5], "direction": [0, 0, -1] },
///   "materials": { "red": { "diffuse": [1, 0, 0] } },
///   "blocks": [ { "name": "ball", "material": "red", "objects": [ { "sphere": {} } ] } ]
/// }"#;
/// let world = render::format::SceneFile::from_json(text).unwrap().to_world().unwrap();
/// let plane = Plane::axis("z=0").unwrap();
/// let extent = plane.extent_of(&world.complex.aabb()).unwrap();
/// let raster = Raster::new(plane, extent, Some((11, 11))).unwrap();
/// let map = slice(&world, &raster);
/// assert_eq!((map.block[5 * 11 + 5], map.material[5 * 11 + 5]), (1, 1)); // the centre: the ball, red
/// assert_eq!((map.block[0], map.overlap[0]), (0, 0)); // a corner: empty
/// ```
pub fn slice(world: &World, raster: &Raster) -> Slice {
    let complex = &world.complex;
    let (w, h) = (raster.width, raster.height);
    let n = w as usize * h as usize;
    let mut owners = vec![None; n];
    let mut overlap = vec![0u32; n];
    let mut named_overlap = vec![0u32; n];
    let mut points = Vec::with_capacity(w as usize * BAND_ROWS.min(h) as usize);
    for band in (0..h).step_by(BAND_ROWS as usize) {
        let rows = band..(band + BAND_ROWS).min(h);
        points.clear();
        points.extend(rows.clone().flat_map(|j| (0..w).map(move |i| raster.point(i, j))));
        let at = band as usize * w as usize..rows.end as usize * w as usize;
        // The lengths match by construction.
        let _ = complex.classify(&points, &mut owners[at.clone()]);
        let counts =
            overlap[at.clone()].par_chunks_mut(OVERLAP_CHUNK).zip(named_overlap[at].par_chunks_mut(OVERLAP_CHUNK));
        points.par_chunks(OVERLAP_CHUNK).zip(counts).for_each(|(p, (o, named))| {
            let mut inside = Vec::new();
            let mut seen: Vec<&str> = Vec::new();
            for ((p, o), named) in p.iter().zip(o).zip(named) {
                complex.blocks_containing(p, &mut inside);
                *o = inside.len() as u32;
                // One block or none is one name or none: names are looked
                // up only where blocks overlap.
                *named = *o;
                if inside.len() >= 2 {
                    seen.clear();
                    for b in &inside {
                        let n = complex.block(*b).name();
                        if !seen.contains(&n) {
                            seen.push(n);
                        }
                    }
                    *named = seen.len() as u32;
                }
            }
        });
    }
    let material = owners.iter().map(|o| o.map_or(0, |b| material_id(world, b))).collect();
    let block = owners.iter().map(|o| o.map_or(0, |b| b.0 + 1)).collect();
    let mut names: Vec<String> = Vec::new();
    let mut index: std::collections::HashMap<&str, u32> = std::collections::HashMap::new();
    let name = owners
        .iter()
        .map(|o| {
            o.map_or(0, |b| {
                let n = complex.block(b).name();
                *index.entry(n).or_insert_with(|| {
                    names.push(n.to_string());
                    names.len() as u32
                })
            })
        })
        .collect();
    Slice { width: w, height: h, block, material, overlap, name, named_overlap, names }
}

/// The 1-based index of a block's material.
fn material_id(world: &World, b: BlockId) -> u32 {
    world.block_info(b).material as u32 + 1
}

/// Empty space in a PNG slice: white.
pub const EMPTY: [u8; 3] = [255, 255, 255];

/// Boundaries in a PNG slice: black.
pub const BOUNDARY: [u8; 3] = [0, 0, 0];

/// The hatching of overlaps: diagonal stripes, two pixels of every six.
const HATCH_PERIOD: u32 = 6;

/// Colour `k` (0-based) of a deterministic palette whose neighbours are far
/// apart: hues stepped by the golden angle, three levels of saturation and
/// value, never white, black or grey.
///
/// ```
/// use render::slice::palette;
/// let colours: Vec<_> = (0..8).map(palette).collect();
/// assert!(colours.iter().enumerate().all(|(i, c)| !colours[..i].contains(c)));
/// ```
pub fn palette(k: u32) -> [u8; 3] {
    let hue = (f64::from(k) * 0.618_033_988_749_895).fract() * 6.0;
    let (s, v) = [(0.55, 0.95), (0.75, 0.80), (0.40, 0.85)][(k % 3) as usize];
    let f = hue.fract();
    let (p, q, t) = (v * (1.0 - s), v * (1.0 - s * f), v * (1.0 - s * (1.0 - f)));
    let rgb = match hue as u32 {
        0 => [v, t, p],
        1 => [q, v, p],
        2 => [p, v, t],
        3 => [p, q, v],
        4 => [t, p, v],
        _ => [v, p, q],
    };
    rgb.map(|c| (c * 255.0).round() as u8)
}

impl Slice {
    /// Whether pixel `(i, j)` lies on a boundary: a pixel beside it (left,
    /// right, above or below) has another owner.
    pub fn is_boundary(&self, i: u32, j: u32) -> bool {
        self.is_boundary_of(&self.block, i, j)
    }

    /// [`Slice::is_boundary`] between the owners `ids` names (blocks, or names).
    fn is_boundary_of(&self, ids: &[u32], i: u32, j: u32) -> bool {
        let at = |i: u32, j: u32| ids[j as usize * self.width as usize + i as usize];
        let me = at(i, j);
        (i > 0 && at(i - 1, j) != me)
            || (i + 1 < self.width && at(i + 1, j) != me)
            || (j > 0 && at(i, j - 1) != me)
            || (j + 1 < self.height && at(i, j + 1) != me)
    }

    /// Whether pixel `(i, j)` is drawn as hatching: its centre lies in two
    /// or more blocks and it is on one of the diagonal stripes.
    pub fn is_hatched(&self, i: u32, j: u32) -> bool {
        self.overlap[j as usize * self.width as usize + i as usize] >= 2 && (i + j) % HATCH_PERIOD < 2
    }

    /// The 8-bit RGB image (rows from the top): each owner in its colour
    /// ([`palette`] of the 0-based block, material or name index), empty space
    /// [`EMPTY`], boundaries [`BOUNDARY`], and overlaps hatched with
    /// stripes of the owner's colour at half its value.
    pub fn rgb(&self, by: ColorBy) -> Vec<u8> {
        let mut out = Vec::with_capacity(3 * self.block.len());
        for j in 0..self.height {
            for i in 0..self.width {
                let k = j as usize * self.width as usize + i as usize;
                let id = match by {
                    ColorBy::Block => self.block[k],
                    ColorBy::Material => self.material[k],
                    ColorBy::Name => self.name[k],
                };
                let (edges, hatched) = match by {
                    ColorBy::Name => (
                        self.is_boundary_of(&self.name, i, j),
                        self.named_overlap[k] >= 2 && (i + j) % HATCH_PERIOD < 2,
                    ),
                    _ => (self.is_boundary(i, j), self.is_hatched(i, j)),
                };
                let colour = if edges {
                    BOUNDARY
                } else if id == 0 {
                    EMPTY
                } else if hatched {
                    palette(id - 1).map(|c| c / 2)
                } else {
                    palette(id - 1)
                };
                out.extend_from_slice(&colour);
            }
        }
        out
    }
}

/// The image type of a slice's output, from its extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageType {
    /// `.png`: the coloured map.
    Png,
    /// `.exr`: the id channels.
    Exr,
}

impl ImageType {
    /// `.png` or `.exr` (any case); anything else is an error naming `-o`.
    pub fn of(path: &Path) -> Result<ImageType, Error> {
        match path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref() {
            Some("png") => Ok(ImageType::Png),
            Some("exr") => Ok(ImageType::Exr),
            _ => Err(Error::Options(format!(
                "-o {}: the slice is written as .png or .exr, by the file's extension",
                path.display()
            ))),
        }
    }
}

/// Writes the slice to `path` (atomically), as its extension says: a PNG
/// coloured `by` blocks or materials, or an EXR with the u32 channels
/// `id.block`, `id.material` and `overlap`.
pub fn write(map: Slice, path: &Path, by: ColorBy) -> Result<(), Error> {
    let size = (map.width, map.height);
    match ImageType::of(path)? {
        ImageType::Png => crate::png::write_rgb8(path, size, map.rgb(by)),
        ImageType::Exr => crate::exr::write_u32_channels(
            path,
            size,
            vec![("id.block", map.block), ("id.material", map.material), ("overlap", map.overlap)],
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Normals along the axes, both ways, near `z`, and oblique.
    const NORMALS: [[f64; 3]; 9] = [
        [1.0, 0.0, 0.0],
        [0.0, -1.0, 0.0],
        [0.0, 0.0, 1.0],
        [0.0, 0.0, -3.0],
        [0.1, 0.2, 1.0],
        [1.0, 1.0, 1.0],
        [-2.0, 0.5, 0.3],
        [1e-200, 1e-200, 3e-200],
        [1e200, -1e200, 0.0],
    ];

    #[test]
    fn frames_are_orthonormal_right_handed_and_keep_up_upwards() {
        for normal in NORMALS {
            for up in [None, Some([0.3, 1.0, 0.2]), Some([-1.0, 0.0, 0.5])] {
                let Ok(p) = Plane::new([1.0, 2.0, 3.0], normal, up) else {
                    panic!("{normal:?} {up:?}");
                };
                let n = Vector3::from(normal);
                let close = |a: f64, b: f64| (a - b).abs() < 1e-12;
                assert!(close(p.u.norm(), 1.0) && close(p.v.norm(), 1.0) && close(p.normal.norm(), 1.0));
                assert!(close(p.u.dot(&p.v), 0.0) && close(p.u.dot(&p.normal), 0.0) && close(p.v.dot(&p.normal), 0.0));
                assert!((p.u.cross(&p.v) - p.normal).norm() < 1e-12, "{normal:?} {up:?}");
                assert!(close(p.normal.dot(&(n / n.amax()).normalize()), 1.0), "{normal:?}");
                let up =
                    Vector3::from(up.unwrap_or(if p.normal.z.abs() < 0.9 { [0.0, 0.0, 1.0] } else { [0.0, 1.0, 0.0] }));
                assert!(p.v.dot(&up) > 0.0, "{normal:?}: V {:?} points away from up {up:?}", p.v);
                // (u, v) is a point of the plane, at distance (u, v) from the origin.
                let q = p.at(0.7, -1.3);
                assert!(close((q - p.origin).dot(&p.normal), 0.0) && close((q - p.origin).norm(), 0.7f64.hypot(1.3)));
            }
        }
    }

    #[test]
    fn axis_planes_are_their_normal_and_up_planes() {
        for (text, normal, up) in [
            ("x=0", [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]),
            ("y=0", [0.0, -1.0, 0.0], [0.0, 0.0, 1.0]),
            ("z=0", [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]),
        ] {
            assert_eq!(Plane::axis(text).ok(), Plane::new([0.0; 3], normal, Some(up)).ok(), "{text}");
        }
    }

    /// Every point of the plane inside the box lies in the default extent,
    /// inside its margin (sampled on a grid of plane coordinates).
    #[test]
    fn the_default_extent_holds_where_the_plane_cuts_the_box() {
        let boxes = [
            Aabb { min: Point3::new(-1.0, -2.0, 0.5), max: Point3::new(3.0, 1.0, 2.0) },
            Aabb { min: Point3::new(-0.1, -0.1, -0.1), max: Point3::new(0.1, 0.1, 0.1) },
        ];
        for b in boxes {
            for normal in NORMALS {
                let p = Plane::new(b.center().map_or([0.0; 3], |c| c.into()), normal, None).expect("a valid plane");
                let e = p.extent_of(&b).expect("the plane cuts the box");
                let margin = 0.05 / 1.1 * (e.u1 - e.u0).max(e.v1 - e.v0);
                let span = 2.0 * b.size().norm();
                let steps = 200;
                let mut inside = 0;
                for a in 0..=steps {
                    for c in 0..=steps {
                        let (u, v) = (
                            span * (f64::from(a) / f64::from(steps) - 0.5),
                            span * (f64::from(c) / f64::from(steps) - 0.5),
                        );
                        if b.contains_point(&p.at(u, v)) {
                            inside += 1;
                            let eps = 1e-12 * span;
                            assert!(
                                u >= e.u0 + margin - eps && u <= e.u1 - margin + eps,
                                "{normal:?}: u {u} outside {e:?}"
                            );
                            assert!(
                                v >= e.v0 + margin - eps && v <= e.v1 - margin + eps,
                                "{normal:?}: v {v} outside {e:?}"
                            );
                        }
                    }
                }
                assert!(inside > 100, "{normal:?}: {inside} samples in the box");
            }
        }
    }
}
