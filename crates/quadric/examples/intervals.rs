//! Prints the interval sets of a few rays against a sphere, a capped cylinder
//! and a one-sheet hyperboloid, naming the surface behind every end.
//!
//! ```text
//! cargo run -p quadric --example intervals
//! ```

use nalgebra::{Point3, Vector3};
use quadric::{Bound, GeometryError, HalfSpace, IntervalSet, Quadric, Ray, Transform};

/// Names of the solids, indexed by the tag passed to `intervals`.
const NAMES: [&str; 5] = ["ball", "tube", "top cap", "bottom cap", "hyperboloid"];

fn end(b: Bound) -> String {
    match b.solid() {
        Some(s) => format!("{} ({})", b.t, NAMES.get(s as usize).unwrap_or(&"?")),
        None if b.t.is_infinite() => format!("{}", b.t),
        None => format!("{} (start inside)", b.t),
    }
}

fn show(set: &IntervalSet) -> String {
    if set.is_empty() {
        return "∅".to_owned();
    }
    set.iter().map(|iv| format!("[{}, {}]", end(iv.enter), end(iv.exit))).collect::<Vec<_>>().join(" ∪ ")
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let ray = |p: [f64; 3], d: [f64; 3]| -> Result<Ray, GeometryError> { Ray::new(Point3::from(p), Vector3::from(d)) };

    // A ball of radius 2 centred at (0, 0, -10).
    let ball = Quadric::sphere()
        .transformed(&Transform::scale(2.0)?.then(&Transform::translate(Vector3::new(0.0, 0.0, -10.0))?));
    println!("ball of radius 2 at (0, 0, -10):");
    for (what, r) in [
        ("through the centre", ray([0.0, 0.0, 0.0], [0.0, 0.0, -1.0])?),
        ("off-centre chord", ray([1.0, 0.0, 0.0], [0.0, 0.0, -1.0])?),
        ("tangent (a touching point)", ray([2.0, 0.0, 0.0], [0.0, 0.0, -1.0])?),
        ("from inside", ray([0.0, 0.0, -10.0], [1.0, 1.0, 0.0])?),
        ("pointing away", ray([0.0, 0.0, 0.0], [0.0, 0.0, 1.0])?),
    ] {
        println!("  {what:28} {}", show(&ball.intervals(&r, 0)));
    }

    // A capped cylinder: the unit tube along y between y = 0 and y = 2,
    // intersected by hand from its three solids' interval sets.
    let tube = Quadric::tube_y();
    let top = HalfSpace::new(0.0, 1.0, 0.0, -2.0)?; // y <= 2
    let bottom = HalfSpace::new(0.0, -1.0, 0.0, 0.0)?; // y >= 0
    println!("capped cylinder x² + z² <= 1, 0 <= y <= 2:");
    for (what, r) in [
        ("across the side", ray([-5.0, 1.0, 0.0], [1.0, 0.0, 0.0])?),
        ("up the axis", ray([0.0, -5.0, 0.0], [0.0, 1.0, 0.0])?),
        ("in the side, out the top", ray([-3.0, -0.5, 0.0], [1.0, 1.0, 0.0])?),
        ("above it", ray([-5.0, 3.0, 0.0], [1.0, 0.0, 0.0])?),
        ("from inside, downwards", ray([0.0, 1.0, 0.0], [0.3, -1.0, 0.0])?),
    ] {
        let set = tube.intervals(&r, 1).intersect(&top.intervals(&r, 2))?.intersect(&bottom.intervals(&r, 3))?;
        println!("  {what:28} {}", show(&set));
    }

    // The solid one-sheet hyperboloid x² - y² + z² <= 1 (non-convex: up to two pieces).
    let sheet = Quadric::hyperboloid_one_sheet();
    println!("one-sheet hyperboloid x² - y² + z² <= 1:");
    for (what, r) in [
        ("across the waist", ray([-5.0, 0.0, 0.0], [1.0, 0.0, 0.0])?),
        ("parallel to the axis, x = 2", ray([2.0, -5.0, 0.0], [0.0, 1.0, 0.0])?),
        ("along the axis", ray([0.0, -5.0, 0.0], [0.0, 1.0, 0.0])?),
        ("oblique", ray([-5.0, -5.0, 0.5], [1.0, 0.5, 0.0])?),
    ] {
        println!("  {what:28} {}", show(&sheet.intervals(&r, 4)));
    }
    Ok(())
}
