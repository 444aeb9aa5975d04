//! The random-blocks benchmark scene, shared by `benches/cast_ray.rs` and
//! `examples/random_blocks.rs`: N balls, capped tubes and rotated boxes
//! (radius 0.3–0.6) in a cube whose side grows as `N^(1/3)`, so the density
//! stays fixed, and rays from outside the cube at random points inside it.

use complex::{Block, Complex, ComplexOptions, MaterialKey, Opacity};
use quadric::nalgebra::{Point3, Vector3};
use quadric::{HalfSpace, Quadric, Ray, Solid, Transform};

/// xorshift64*: a small deterministic generator, so the bench needs no `rand`.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * self.next()
    }
}

fn hs(a: f64, b: f64, c: f64, d: f64) -> Solid {
    Solid::from(HalfSpace::new(a, b, c, d).expect("valid"))
}

/// The complex and the rays.
pub fn scene(n: usize, transparent: bool) -> (Complex, Vec<Ray>) {
    let (blocks, rays) = blocks_and_rays(n, transparent, 1024);
    (Complex::new(blocks, ComplexOptions::default()).expect("valid"), rays)
}

/// The blocks (every other one transparent if asked) and `rays` rays.
pub fn blocks_and_rays(n: usize, transparent: bool, rays: usize) -> (Vec<Block>, Vec<Ray>) {
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15 ^ n as u64);
    let side = 2.0 * (n as f64).cbrt();
    let mut blocks = Vec::with_capacity(n);
    for _ in 0..n {
        let r = rng.range(0.3, 0.6);
        let m = Transform::scale(r)
            .and_then(|s| Ok(s.then(&Transform::rotate_x_degrees(rng.range(0.0, 360.0))?)))
            .and_then(|s| Ok(s.then(&Transform::rotate_y_degrees(rng.range(0.0, 360.0))?)))
            .and_then(|s| {
                let c = Vector3::new(rng.range(0.0, side), rng.range(0.0, side), rng.range(0.0, side));
                Ok(s.then(&Transform::translate(c)?))
            })
            .expect("finite");
        let unit: Vec<Solid> = match (rng.next() * 3.0) as u32 {
            0 => vec![Solid::from(Quadric::sphere())],
            1 => vec![Solid::from(Quadric::tube_y()), hs(0.0, 1.0, 0.0, -1.0), hs(0.0, -1.0, 0.0, -1.0)],
            _ => vec![
                hs(1.0, 0.0, 0.0, -1.0),
                hs(-1.0, 0.0, 0.0, -1.0),
                hs(0.0, 1.0, 0.0, -1.0),
                hs(0.0, -1.0, 0.0, -1.0),
                hs(0.0, 0.0, 1.0, -1.0),
                hs(0.0, 0.0, -1.0, -1.0),
            ],
        };
        let solids = unit.iter().map(|s| s.transformed(&m)).collect();
        // Every other block transparent, in one of two materials.
        let opacity = if transparent && blocks.len() % 2 == 0 { Opacity::Transparent } else { Opacity::Opaque };
        blocks.push(Block::new("b", solids, opacity, MaterialKey(blocks.len() as u32 / 2 % 2)).expect("valid"));
    }
    let rays = (0..rays)
        .map(|_| {
            let eye = Point3::new(rng.range(-side, 2.0 * side), rng.range(-side, 2.0 * side), -side);
            let target = Point3::new(rng.range(0.0, side), rng.range(0.0, side), rng.range(0.0, side));
            Ray::new(eye, target - eye).expect("valid")
        })
        .collect();
    (blocks, rays)
}

/// Primary rays of a `w`×`w` pinhole camera in scanline order (coherent, as
/// a renderer casts them) for the scene of `n` blocks: from the middle of
/// the cube's front face, one side back, looking along `+z`, the cube's
/// front face filling the view.
pub fn camera_rays(n: usize, w: usize) -> Vec<Ray> {
    let side = 2.0 * (n as f64).cbrt();
    let eye = Point3::new(0.5 * side, 0.5 * side, -side);
    let mut rays = Vec::with_capacity(w * w);
    for j in 0..w {
        for i in 0..w {
            // The front face spans [-side/2, side/2] around the eye's axis at distance `side`.
            let x = ((i as f64 + 0.5) / w as f64 - 0.5) * side;
            let y = ((j as f64 + 0.5) / w as f64 - 0.5) * side;
            rays.push(Ray::new(eye, Vector3::new(x, y, side)).expect("valid"));
        }
    }
    rays
}
