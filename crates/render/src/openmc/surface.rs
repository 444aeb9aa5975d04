//! OpenMC's surfaces as Komplex solids: each surface `f(x) = 0` gives the
//! solid `f ≤ 0` (its `-` side) and the complement (its `+` side), written
//! about a centre so that a model far from the origin keeps its digits.

use quadric::nalgebra::{Matrix3, Vector3};

use crate::format::{Axis, CylinderSpec, ObjectSpec, SphereSpec, Step};

/// A surface of an OpenMC model, as the quadric function whose negative
/// side is OpenMC's `-id`.
#[derive(Clone, Debug, PartialEq)]
pub enum Surface {
    /// `n·x + d` (the planes).
    Plane {
        /// Normal (not unit in general).
        n: [f64; 3],
        /// Offset.
        d: f64,
    },
    /// `(x − c)ᵀ A (x − c) + 2 bᵀ (x − c) + k` (spheres, cylinders, cones, quadrics).
    Quadric(Form),
    /// A surface kind that is not a quadric (a torus): an error where a
    /// cell uses it.
    Unsupported(String),
}

/// A quadric function written about a centre: `(x − c)ᵀ A (x − c) + 2 bᵀ (x − c) + k`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Form {
    /// The centre `c`.
    pub c: Vector3<f64>,
    /// The symmetric quadratic part `A`.
    pub a: Matrix3<f64>,
    /// Half the linear part about the centre.
    pub b: Vector3<f64>,
    /// The constant.
    pub k: f64,
}

impl Surface {
    /// The surface of OpenMC `type` with its `coeffs` (docs/openmc.md,
    /// "Surfaces"); an error message for a wrong count or kind.
    pub fn new(kind: &str, v: &[f64]) -> Result<Surface, String> {
        let need = |n: usize| {
            if v.len() == n {
                Ok(())
            } else {
                Err(format!("`{kind}` takes {n} coefficients, got {}", v.len()))
            }
        };
        let axis = |i: usize| {
            let mut e = [0.0; 3];
            e[i] = 1.0;
            e
        };
        let form = |c: [f64; 3], diag: [f64; 3], k: f64| {
            Surface::Quadric(Form { c: c.into(), a: Matrix3::from_diagonal(&diag.into()), b: Vector3::zeros(), k })
        };
        Ok(match kind {
            "x-plane" | "y-plane" | "z-plane" => {
                need(1)?;
                let i = (kind.as_bytes()[0] - b'x') as usize;
                Surface::Plane { n: axis(i), d: -v[0] }
            }
            "plane" => {
                need(4)?;
                if v[..3].iter().all(|x| *x == 0.0) {
                    return Err("a plane's normal (A, B, C) must not be zero".into());
                }
                Surface::Plane { n: [v[0], v[1], v[2]], d: -v[3] }
            }
            "x-cylinder" | "y-cylinder" | "z-cylinder" => {
                need(3)?;
                let i = (kind.as_bytes()[0] - b'x') as usize;
                if v[2] <= 0.0 {
                    return Err(format!("the radius must be positive, got {}", v[2]));
                }
                // The two coefficients before R are the other axes' centre, in order.
                let mut c = [0.0; 3];
                let mut diag = [1.0; 3];
                diag[i] = 0.0;
                let others: Vec<usize> = (0..3).filter(|j| *j != i).collect();
                c[others[0]] = v[0];
                c[others[1]] = v[1];
                form(c, diag, -v[2] * v[2])
            }
            "sphere" => {
                need(4)?;
                if v[3] <= 0.0 {
                    return Err(format!("the radius must be positive, got {}", v[3]));
                }
                form([v[0], v[1], v[2]], [1.0; 3], -v[3] * v[3])
            }
            "x-cone" | "y-cone" | "z-cone" => {
                need(4)?;
                let i = (kind.as_bytes()[0] - b'x') as usize;
                if v[3] <= 0.0 {
                    return Err(format!("R2 (the squared slope) must be positive, got {}", v[3]));
                }
                let mut diag = [1.0; 3];
                diag[i] = -v[3];
                form([v[0], v[1], v[2]], diag, 0.0)
            }
            "quadric" => {
                need(10)?;
                // OpenMC: Ax² + By² + Cz² + Dxy + Eyz + Fxz + Gx + Hy + Jz + K.
                let (a, b, c, d, e, f) = (v[0], v[1], v[2], v[3], v[4], v[5]);
                let m = Matrix3::new(a, d / 2.0, f / 2.0, d / 2.0, b, e / 2.0, f / 2.0, e / 2.0, c);
                let lin = Vector3::new(v[6], v[7], v[8]) / 2.0;
                if m == Matrix3::zeros() {
                    if lin == Vector3::zeros() {
                        return Err("all coefficients but K are zero: not a surface".into());
                    }
                    Surface::Plane { n: (lin * 2.0).into(), d: v[9] }
                } else {
                    Surface::Quadric(Form { c: Vector3::zeros(), a: m, b: lin, k: v[9] })
                }
            }
            "x-torus" | "y-torus" | "z-torus" => Surface::Unsupported(kind.to_string()),
            other => {
                const KINDS: &[&str] = &[
                    "plane",
                    "x-plane",
                    "y-plane",
                    "z-plane",
                    "x-cylinder",
                    "y-cylinder",
                    "z-cylinder",
                    "sphere",
                    "x-cone",
                    "y-cone",
                    "z-cone",
                    "quadric",
                    "x-torus",
                    "y-torus",
                    "z-torus",
                ];
                let hint = crate::error::nearest(other, KINDS.iter().copied())
                    .map(|n| format!(" (did you mean `{n}`?)"))
                    .unwrap_or_default();
                return Err(format!("unknown surface type `{other}`{hint}"));
            }
        })
    }
}

/// One side of a surface in some frame: the solid `f ≤ 0`, or its
/// complement `f ≥ 0` (`positive`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Side {
    /// The function.
    pub shape: Shape,
    /// Whether the side is `f > 0` (OpenMC's `+id`).
    pub positive: bool,
}

/// A plane or a quadric function (never unsupported).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Shape {
    /// `n·x + d`.
    Plane(Vector3<f64>, f64),
    /// A quadric about a centre.
    Quadric(Form),
}

/// A rigid motion `x ↦ R x + t` (from a child frame to its parent's).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Motion {
    /// The rotation.
    pub r: Matrix3<f64>,
    /// The translation.
    pub t: Vector3<f64>,
}

impl Motion {
    /// The identity.
    pub fn identity() -> Motion {
        Motion { r: Matrix3::identity(), t: Vector3::zeros() }
    }

    /// A translation.
    pub fn translation(t: Vector3<f64>) -> Motion {
        Motion { r: Matrix3::identity(), t }
    }

    /// Whether the rotation is the identity.
    pub fn is_translation(&self) -> bool {
        self.r == Matrix3::identity()
    }

    /// The parent point of a child point.
    pub fn apply(&self, x: &Vector3<f64>) -> Vector3<f64> {
        self.r * x + self.t
    }
}

impl Side {
    /// The function's value at `x`.
    pub fn value(&self, x: &Vector3<f64>) -> f64 {
        match &self.shape {
            Shape::Plane(n, d) => n.dot(x) + d,
            Shape::Quadric(f) => {
                let y = x - f.c;
                y.dot(&(f.a * y)) + 2.0 * f.b.dot(&y) + f.k
            }
        }
    }

    /// The same side seen from the child frame of `m` (the child's points
    /// go to the parent's by `m`).
    pub fn in_child(&self, m: &Motion) -> Side {
        let shape = match &self.shape {
            // n·(R y + t) + d
            Shape::Plane(n, d) => Shape::Plane(m.r.transpose() * n, n.dot(&m.t) + d),
            // R y + t − c = R (y − Rᵀ(c − t))
            Shape::Quadric(f) => Shape::Quadric(Form {
                c: m.r.transpose() * (f.c - m.t),
                a: m.r.transpose() * f.a * m.r,
                b: m.r.transpose() * f.b,
                k: f.k,
            }),
        };
        Side { shape, positive: self.positive }
    }

    /// Whether the side holds every point of the box `[−h, h]` (per axis;
    /// an infinite `h` is an unbounded axis). `false` where unknown: see
    /// [`Side::range`].
    pub fn holds_box(&self, h: &Vector3<f64>) -> bool {
        let (lo, hi) = self.range(h);
        if self.positive {
            lo.is_some_and(|lo| lo >= 0.0)
        } else {
            hi.is_some_and(|hi| hi <= 0.0)
        }
    }

    /// Whether the side misses the box `[−h, h]` (or touches it only on its
    /// boundary). `false` where unknown.
    pub fn misses_box(&self, h: &Vector3<f64>) -> bool {
        let (lo, hi) = self.range(h);
        if self.positive {
            hi.is_some_and(|hi| hi <= 0.0)
        } else {
            lo.is_some_and(|lo| lo >= 0.0)
        }
    }

    /// The least and the greatest value of the function over the box
    /// `[−h, h]`, where known: exact for planes; for a convex quadric the
    /// greatest is at a corner (the unbounded axes must not change it), and
    /// the least is known when the quadratic part is diagonal and there is
    /// no linear part (spheres, cylinders, axis-aligned ellipsoids): the
    /// sum of `aᵢ · (distance from cᵢ to [−hᵢ, hᵢ])²`, plus `k`.
    fn range(&self, h: &Vector3<f64>) -> (Option<f64>, Option<f64>) {
        match &self.shape {
            Shape::Plane(n, d) => (Some(d - support(n, h)), Some(d + support(n, h))),
            Shape::Quadric(f) => {
                if !is_convex(&f.a) {
                    return (None, None);
                }
                let diagonal = f.a == Matrix3::from_diagonal(&f.a.diagonal()) && f.b == Vector3::zeros();
                let lo = diagonal
                    .then(|| (0..3).map(|i| f.a[(i, i)] * (f.c[i].abs() - h[i]).max(0.0).powi(2)).sum::<f64>() + f.k);
                // Along an unbounded axis the function must not change.
                let flat = (0..3).all(|i| h[i].is_finite() || (f.a.row(i).iter().all(|x| *x == 0.0) && f.b[i] == 0.0));
                let hi = flat.then(|| {
                    let h = h.map(|x| if x.is_infinite() { 0.0 } else { x });
                    (0..8)
                        .map(|corner: u32| {
                            let x = Vector3::from_fn(|i, _| if corner >> i & 1 == 1 { h[i] } else { -h[i] });
                            self.value(&x)
                        })
                        .fold(f64::NEG_INFINITY, f64::max)
                });
                (lo, hi)
            }
        }
    }

    /// The solid as a scene object: `halfspace`, `sphere`, `cylinder`, or
    /// `quadric` moved to its centre.
    pub fn object(&self) -> ObjectSpec {
        match &self.shape {
            Shape::Plane(n, d) => {
                let s = if self.positive { -1.0 } else { 1.0 };
                ObjectSpec { halfspace: Some([s * n[0], s * n[1], s * n[2], s * d]), ..Default::default() }
            }
            Shape::Quadric(f) => {
                let c: [f64; 3] = f.c.into();
                let diag = f.a.diagonal();
                let diagonal = f.a == Matrix3::from_diagonal(&diag) && f.b == Vector3::zeros();
                let mut o = if diagonal && diag == Vector3::new(1.0, 1.0, 1.0) && f.k < 0.0 {
                    let center = (c != [0.0; 3]).then_some(c);
                    ObjectSpec {
                        sphere: Some(Box::new(SphereSpec { radius: Some((-f.k).sqrt()), center })),
                        ..Default::default()
                    }
                } else if let Some(axis) = (0..3)
                    .find(|i| diagonal && f.k < 0.0 && diag[*i] == 0.0 && (0..3).all(|j| j == *i || diag[j] == 1.0))
                {
                    let axis = [Axis::X, Axis::Y, Axis::Z][axis];
                    let mut o = ObjectSpec {
                        cylinder: Some(Box::new(CylinderSpec { radius: Some((-f.k).sqrt()), axis: Some(axis) })),
                        ..Default::default()
                    };
                    if c != [0.0; 3] {
                        o.transform = vec![Step::Translate(c)];
                    }
                    o
                } else {
                    let a = &f.a;
                    let q =
                        [a[(0, 0)], a[(1, 1)], a[(2, 2)], a[(0, 1)], a[(0, 2)], a[(1, 2)], f.b[0], f.b[1], f.b[2], f.k];
                    let mut o = ObjectSpec { quadric: Some(Box::new(q)), ..Default::default() };
                    if c != [0.0; 3] {
                        o.transform = vec![Step::Translate(c)];
                    }
                    o
                };
                o.complement = self.positive;
                o
            }
        }
    }
}

/// `max over the box [−h, h] of n·x`.
fn support(n: &Vector3<f64>, h: &Vector3<f64>) -> f64 {
    (0..3).map(|i| if n[i] == 0.0 { 0.0 } else { n[i].abs() * h[i] }).sum()
}

/// Whether a symmetric matrix is positive semi-definite.
fn is_convex(a: &Matrix3<f64>) -> bool {
    let scale = a.abs().max();
    a.symmetric_eigenvalues().iter().all(|l| *l >= -1e-12 * scale)
}
