//! Builders shared by the topic files.

use complex::{Block, Complex, ComplexOptions, MaterialKey, Opacity};
use quadric::nalgebra::{Point3, Vector3};
use quadric::{HalfSpace, Quadric, Ray, Solid, Transform};

pub const T: Opacity = Opacity::Transparent;
pub const O: Opacity = Opacity::Opaque;

/// `a x + b y + c z + d <= 0`.
pub fn hs(a: f64, b: f64, c: f64, d: f64) -> Solid {
    Solid::from(HalfSpace::new(a, b, c, d).expect("valid half-space"))
}

/// The axis-aligned box `[min, max]` as six half-spaces.
pub fn cuboid(min: [f64; 3], max: [f64; 3]) -> Vec<Solid> {
    vec![
        hs(-1.0, 0.0, 0.0, min[0]),
        hs(1.0, 0.0, 0.0, -max[0]),
        hs(0.0, -1.0, 0.0, min[1]),
        hs(0.0, 1.0, 0.0, -max[1]),
        hs(0.0, 0.0, -1.0, min[2]),
        hs(0.0, 0.0, 1.0, -max[2]),
    ]
}

pub fn translate(x: f64, y: f64, z: f64) -> Transform {
    Transform::translate(Vector3::new(x, y, z)).expect("finite")
}

pub fn moved(solids: &[Solid], m: &Transform) -> Vec<Solid> {
    solids.iter().map(|s| s.transformed(m)).collect()
}

/// A vertical post: the tube `x² + z² <= r²` between `y0` and `y1`, centred at `(x, z)`.
pub fn post(x: f64, z: f64, r: f64, y0: f64, y1: f64) -> Vec<Solid> {
    let m = Transform::scale_xyz(Vector3::new(r, 1.0, r)).expect("finite").then(&translate(x, 0.0, z));
    vec![Solid::from(Quadric::tube_y().transformed(&m)), hs(0.0, -1.0, 0.0, y0), hs(0.0, 1.0, 0.0, -y1)]
}

pub fn block(name: &str, solids: Vec<Solid>, opacity: Opacity, material: u32) -> Block {
    Block::new(name, solids, opacity, MaterialKey(material)).expect("valid block")
}

pub fn complex(blocks: Vec<Block>) -> Complex {
    Complex::new(blocks, ComplexOptions::default()).expect("valid complex")
}

pub fn ray(o: [f64; 3], d: [f64; 3]) -> Ray {
    Ray::new(Point3::new(o[0], o[1], o[2]), Vector3::new(d[0], d[1], d[2])).expect("valid ray")
}

/// The name of a block by id.
pub fn name(c: &Complex, id: complex::BlockId) -> &str {
    c.block(id).name()
}
