//! Plain vector helpers and the camera formulas of docs/model.md §4.2, written out
//! independently of the renderer as test oracles.

pub type V = [f64; 3];

pub fn sub(a: V, b: V) -> V {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
pub fn add(a: V, b: V) -> V {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
pub fn mul(s: f64, a: V) -> V {
    [s * a[0], s * a[1], s * a[2]]
}
pub fn dot(a: V, b: V) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
pub fn unit(a: V) -> V {
    mul(1.0 / dot(a, a).sqrt(), a)
}
pub fn cross(a: V, b: V) -> V {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

pub struct Cam {
    pub e: V,
    pub d: V,
    pub u: V,
    pub w: u32,
    pub h: u32,
    pub angle: f64,
}

impl Cam {
    /// The unit direction of the ray through pixel (i, j), literally as in docs/model.md §4.2.
    pub fn ray(&self, i: u32, j: u32) -> V {
        let d = unit(self.d);
        let u = unit(sub(self.u, mul(dot(self.u, d), d)));
        let r = cross(d, u);
        let (dx, dy) = (f64::from(self.w), f64::from(self.h));
        let m = add(self.e, mul((dx * dx + dy * dy).sqrt() / (2.0 * (self.angle.to_radians() / 2.0).tan()), d));
        let p00 = add(sub(m, mul((dx - 1.0) / 2.0, r)), mul((dy - 1.0) / 2.0, u));
        let pij = add(sub(p00, mul(f64::from(i), u)), mul(f64::from(j), r));
        unit(sub(pij, self.e))
    }

    pub fn json(&self) -> String {
        format!(
            r#""camera": {{ "eye": {:?}, "direction": {:?}, "up": {:?}, "width": {}, "height": {}, "aperture": {} }}"#,
            self.e, self.d, self.u, self.w, self.h, self.angle
        )
    }
}

/// Componentwise product.
pub fn prod(a: V, b: V) -> V {
    [a[0] * b[0], a[1] * b[1], a[2] * b[2]]
}
