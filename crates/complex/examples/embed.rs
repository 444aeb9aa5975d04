//! Embedding the kernel: build a complex in code, cast rays, print
//! partitions and test points.
//!
//! `cargo run -p complex --example embed`
//!
//! The scene: a glass of water on a table, built with the priority rule.
//! The table top is opaque. The water (material 2, a capped tube) comes
//! first; a drop of water (material 2, a ball) sits on its surface and
//! bulges above it; the glass (material 1) is a *solid* capped tube inserted
//! last, so it owns only what the water and the drop leave: a hollow glass
//! without any hollow modelling. Where the drop meets the water the medium
//! does not change (same material): that event is not an interface.

use complex::{Block, Complex, ComplexOptions, MaterialKey, Opacity};
use quadric::nalgebra::{Point3, Vector3};
use quadric::{HalfSpace, Quadric, Ray, Solid, Transform};

type Error = Box<dyn std::error::Error>;

/// The tube `x² + z² <= r²` between heights `y0` and `y1`.
fn cylinder(r: f64, y0: f64, y1: f64) -> Result<Vec<Solid>, Error> {
    let m = Transform::scale_xyz(Vector3::new(r, 1.0, r))?;
    Ok(vec![
        Solid::from(Quadric::tube_y().transformed(&m)),
        Solid::from(HalfSpace::new(0.0, -1.0, 0.0, y0)?),
        Solid::from(HalfSpace::new(0.0, 1.0, 0.0, -y1)?),
    ])
}

fn scene() -> Result<Complex, Error> {
    let top = vec![
        Solid::from(HalfSpace::new(0.0, 1.0, 0.0, 0.0)?),    // y <= 0
        Solid::from(HalfSpace::new(0.0, -1.0, 0.0, -0.05)?), // y >= -0.05
        Solid::from(HalfSpace::new(1.0, 0.0, 0.0, -1.0)?),   // x <= 1
        Solid::from(HalfSpace::new(-1.0, 0.0, 0.0, -1.0)?),  // x >= -1
        Solid::from(HalfSpace::new(0.0, 0.0, 1.0, -1.0)?),   // z <= 1
        Solid::from(HalfSpace::new(0.0, 0.0, -1.0, -1.0)?),  // z >= -1
    ];
    let drop = Quadric::sphere()
        .transformed(&Transform::scale(0.05)?.then(&Transform::translate(Vector3::new(0.0, 0.2, 0.0))?));
    let blocks = vec![
        Block::new("table top", top, Opacity::Opaque, MaterialKey(0))?,
        Block::new("water", cylinder(0.09, 0.01, 0.2)?, Opacity::Transparent, MaterialKey(2))?,
        Block::new("drop", vec![Solid::from(drop)], Opacity::Transparent, MaterialKey(2))?,
        Block::new("glass", cylinder(0.1, 0.0, 0.3)?, Opacity::Transparent, MaterialKey(1))?,
    ];
    Ok(Complex::new(blocks, ComplexOptions::default())?)
}

fn main() -> Result<(), Error> {
    let c = scene()?;
    println!("ε = {:e}; scene box {:?} .. {:?}", c.epsilon(), c.aabb().min, c.aabb().max);
    for (i, b) in c.blocks().iter().enumerate() {
        let bx = c.block_aabb(complex::BlockId(i as u32));
        println!("  block {i} {:10} box {:?} .. {:?}", b.name(), bx.min, bx.max);
    }
    let name = |id: Option<complex::BlockId>| id.map_or("(nothing)", |id| c.block(id).name());

    let rays = [
        ("through the drop above the water", Ray::new(Point3::new(-1.0, 0.22, 0.0), Vector3::x())?),
        ("down through the glass", Ray::new(Point3::new(0.0, 1.0, 0.0), -Vector3::y())?),
        ("past the glass", Ray::new(Point3::new(-1.0, 0.2, 0.5), Vector3::x())?),
    ];
    for (what, ray) in &rays {
        println!("\nray {what}: from {:?} along {:?}", ray.origin(), ray.direction());
        match c.cast_ray(ray, f64::INFINITY) {
            Some(h) => println!(
                "  first hit: t = {:.4} on {} (solid {}), {}, normal {:?}",
                h.t,
                c.block(h.block).name(),
                h.solid,
                if h.entering { "entering" } else { "leaving" },
                h.normal
            ),
            None => println!("  no hit"),
        }
        let p = c.partition(ray);
        for s in &p.segments {
            println!("  [{:.4}, {:.4}] {}", s.start, s.end, name(s.owner));
        }
        for e in &p.events {
            println!(
                "  event t = {:.4}: {} -> {} on the surface of {}{}",
                e.t,
                name(e.before),
                name(e.after),
                c.block(e.surface.block).name(),
                if c.is_visible(e) { "" } else { " (no interface: same medium or inside opaque)" }
            );
        }
    }

    println!("\npoints:");
    for p in [[0.0, 0.1, 0.0], [0.095, 0.1, 0.0], [0.0, 0.22, 0.0], [0.0, -0.01, 0.0], [0.5, 0.5, 0.5]] {
        let p = Point3::new(p[0], p[1], p[2]);
        println!("  {p:?} belongs to {}", name(c.contains_point(&p)));
    }
    Ok(())
}
