//! Structured inputs for the kernel fuzz targets, and the checks they share.
//!
//! Inputs are decoded from libFuzzer's bytes with [`arbitrary::Unstructured`]
//! by hand-written `read` functions, each paired with a `write` that encodes
//! the same value back. The pairing is what lets `examples/seeds.rs` write a
//! seed corpus of meaningful scenes (unit spheres, capped tubes, rays through
//! them) instead of starting libFuzzer from random bytes; the generator checks
//! that every seed decodes back to itself.
//!
//! Numbers are not raw `f64` bits (nearly all of which are absurdly large or
//! small): a tag byte picks a small integer, a fraction, a decimal `m·10^e`,
//! a special value (0, -0, ±∞, NaN, `f64::MAX`, subnormals, 1e150 …), a value
//! a few ulps from an integer (near-tangencies), or raw bits.

use core::fmt;

use arbitrary::{Arbitrary, Result, Unstructured};
use quadric::nalgebra::{Matrix4, Point3, Vector3, Vector4};
use quadric::{GeometryError, HalfSpace, Quadric, Ray, Solid, Transform};

/// Most solids in one block, blocks in one complex, rays and points per input.
pub const MAX_SOLIDS: usize = 6;
/// See [`MAX_SOLIDS`].
pub const MAX_BLOCKS: usize = 8;
/// See [`MAX_SOLIDS`].
pub const MAX_RAYS: usize = 4;
/// See [`MAX_SOLIDS`].
pub const MAX_POINTS: usize = 4;
/// Most steps in one transform chain.
pub const MAX_STEPS: usize = 4;

/// Special values a [`Num`] can name.
pub const SPECIALS: [f64; 24] = [
    0.0,
    -0.0,
    1.0,
    -1.0,
    0.5,
    1e-300,
    5e-324,
    f64::MIN_POSITIVE,
    1e150,
    -1e150,
    1e300,
    -1e300,
    f64::MAX,
    f64::MIN,
    f64::INFINITY,
    f64::NEG_INFINITY,
    f64::NAN,
    1e-9,
    1e9,
    1e15,
    1e18,
    9007199254740992.0, // 2^53
    1.0 + f64::EPSILON,
    1.0 - f64::EPSILON / 2.0,
];

/// Encoding of a value: the bytes `write` appends are the bytes `read` consumes.
pub trait Wire: Sized {
    /// Decodes a value (missing bytes read as zero, as in `Unstructured`).
    fn read(u: &mut Unstructured<'_>) -> Result<Self>;
    /// Appends the encoding of `self`.
    fn write(&self, out: &mut Vec<u8>);
}

fn byte(u: &mut Unstructured<'_>) -> Result<u8> {
    u8::arbitrary(u)
}

/// A count in `min..=max`, one byte.
fn count(u: &mut Unstructured<'_>, min: usize, max: usize) -> Result<usize> {
    Ok(min + byte(u)? as usize % (max - min + 1))
}

fn write_count(out: &mut Vec<u8>, n: usize, min: usize) {
    out.push((n - min) as u8);
}

/// A fuzzed number; see the module docs.
#[derive(Clone, Copy, PartialEq)]
pub enum Num {
    /// `i` exactly.
    Int(i8),
    /// `i / 64`.
    Frac(i16),
    /// `m · 10^e`.
    Dec(i16, i8),
    /// `SPECIALS[i % SPECIALS.len()]`.
    Special(u8),
    /// `k` ulps away from the integer `base` (by bit pattern).
    Near(i8, i8),
    /// Raw bits.
    Raw(u64),
}

impl Num {
    /// The value.
    pub fn value(self) -> f64 {
        match self {
            Num::Int(i) => i as f64,
            Num::Frac(i) => i as f64 / 64.0,
            Num::Dec(m, e) => m as f64 * 10f64.powi(e as i32),
            Num::Special(i) => SPECIALS[i as usize % SPECIALS.len()],
            Num::Near(base, k) => f64::from_bits((base as f64).to_bits().wrapping_add_signed(k as i64)),
            Num::Raw(bits) => f64::from_bits(bits),
        }
    }
}

impl fmt::Debug for Num {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:?}", self.value())
    }
}

impl Wire for Num {
    fn read(u: &mut Unstructured<'_>) -> Result<Self> {
        Ok(match byte(u)? % 6 {
            0 => Num::Int(i8::arbitrary(u)?),
            1 => Num::Frac(i16::arbitrary(u)?),
            2 => Num::Dec(i16::arbitrary(u)?, i8::arbitrary(u)?),
            3 => Num::Special(byte(u)?),
            4 => Num::Near(i8::arbitrary(u)?, i8::arbitrary(u)?),
            _ => Num::Raw(u64::arbitrary(u)?),
        })
    }

    fn write(&self, out: &mut Vec<u8>) {
        match *self {
            Num::Int(i) => out.extend([0, i as u8]),
            Num::Frac(i) => {
                out.push(1);
                out.extend(i.to_le_bytes());
            }
            Num::Dec(m, e) => {
                out.push(2);
                out.extend(m.to_le_bytes());
                out.push(e as u8);
            }
            Num::Special(i) => out.extend([3, i]),
            Num::Near(b, k) => out.extend([4, b as u8, k as u8]),
            Num::Raw(bits) => {
                out.push(5);
                out.extend(bits.to_le_bytes());
            }
        }
    }
}

impl<const N: usize> Wire for [Num; N] {
    fn read(u: &mut Unstructured<'_>) -> Result<Self> {
        let mut a = [Num::Int(0); N];
        for x in a.iter_mut() {
            *x = Num::read(u)?;
        }
        Ok(a)
    }

    fn write(&self, out: &mut Vec<u8>) {
        for x in self {
            x.write(out);
        }
    }
}

/// The values of an array of numbers.
pub fn values<const N: usize>(a: &[Num; N]) -> [f64; N] {
    a.map(Num::value)
}

fn vector(a: &[Num; 3]) -> Vector3<f64> {
    Vector3::from(values(a))
}

/// One step of a transform chain.
#[derive(Clone, Debug, PartialEq)]
pub enum Step {
    /// `Transform::translate`.
    Translate([Num; 3]),
    /// `Transform::scale`.
    Scale(Num),
    /// `Transform::scale_xyz`.
    ScaleXyz([Num; 3]),
    /// `Transform::rotate_x_degrees`.
    RotateX(Num),
    /// `Transform::rotate_y_degrees`.
    RotateY(Num),
    /// `Transform::rotate_z_degrees`.
    RotateZ(Num),
    /// `Transform::from_matrix` with the top three rows given, row by row.
    Matrix([Num; 12]),
}

impl Wire for Step {
    fn read(u: &mut Unstructured<'_>) -> Result<Self> {
        Ok(match byte(u)? % 7 {
            0 => Step::Translate(Wire::read(u)?),
            1 => Step::Scale(Num::read(u)?),
            2 => Step::ScaleXyz(Wire::read(u)?),
            3 => Step::RotateX(Num::read(u)?),
            4 => Step::RotateY(Num::read(u)?),
            5 => Step::RotateZ(Num::read(u)?),
            _ => Step::Matrix(Wire::read(u)?),
        })
    }

    fn write(&self, out: &mut Vec<u8>) {
        match self {
            Step::Translate(v) => {
                out.push(0);
                v.write(out);
            }
            Step::Scale(s) => {
                out.push(1);
                s.write(out);
            }
            Step::ScaleXyz(v) => {
                out.push(2);
                v.write(out);
            }
            Step::RotateX(a) => {
                out.push(3);
                a.write(out);
            }
            Step::RotateY(a) => {
                out.push(4);
                a.write(out);
            }
            Step::RotateZ(a) => {
                out.push(5);
                a.write(out);
            }
            Step::Matrix(m) => {
                out.push(6);
                m.write(out);
            }
        }
    }
}

impl Step {
    /// Builds the step, checking that it is rejected exactly when it must be.
    pub fn build(&self) -> core::result::Result<Transform, GeometryError> {
        let finite = |v: &[f64]| v.iter().all(|c| c.is_finite());
        let result = match self {
            Step::Translate(v) => {
                let v = vector(v);
                let m = Transform::translate(v);
                assert_eq!(m.is_ok(), finite(v.as_slice()), "translate({v:?})");
                m
            }
            Step::Scale(s) => {
                let s = s.value();
                let m = Transform::scale(s);
                assert_eq!(m.is_ok(), scale_ok(s), "scale({s:?})");
                m
            }
            Step::ScaleXyz(v) => {
                let v = vector(v);
                let m = Transform::scale_xyz(v);
                assert_eq!(m.is_ok(), v.iter().all(|&s| scale_ok(s)), "scale_xyz({v:?})");
                m
            }
            Step::RotateX(a) | Step::RotateY(a) | Step::RotateZ(a) => {
                let a = a.value();
                let m = match self {
                    Step::RotateX(_) => Transform::rotate_x_degrees(a),
                    Step::RotateY(_) => Transform::rotate_y_degrees(a),
                    _ => Transform::rotate_z_degrees(a),
                };
                assert_eq!(m.is_ok(), a.is_finite(), "rotate({a:?})");
                if let Ok(m) = &m {
                    // A rotation is orthogonal: its inverse is its transpose, to rounding.
                    let err = (m.linear() * m.linear().transpose() - quadric::nalgebra::Matrix3::identity()).amax();
                    assert!(err <= 1e-15, "rotation by {a:?} is not orthogonal: {err:e}");
                }
                m
            }
            Step::Matrix(rows) => {
                let r = values(rows);
                let mut m = Matrix4::identity();
                for i in 0..3 {
                    for j in 0..4 {
                        m[(i, j)] = r[4 * i + j];
                    }
                }
                let t = Transform::from_matrix(&m);
                let linear = m.fixed_view::<3, 3>(0, 0).into_owned();
                let zero_row = (0..3).any(|i| linear.row(i).iter().all(|&c| c == 0.0));
                let zero_col = (0..3).any(|j| linear.column(j).iter().all(|&c| c == 0.0));
                let equal_rows = (0..3).any(|i| (i + 1..3).any(|j| linear.row(i) == linear.row(j)));
                if !finite(m.as_slice()) || zero_row || zero_col || equal_rows {
                    assert!(t.is_err(), "singular or non-finite matrix accepted: {m:?}");
                }
                if let Ok(t) = &t {
                    assert!(t.is_finite(), "from_matrix gave a non-finite transform for {m:?}");
                    let residual = (t.linear() * t.linear_inverse() - quadric::nalgebra::Matrix3::identity()).amax();
                    assert!(residual <= 1e-9, "from_matrix inverse is off by {residual:e} for {m:?}");
                }
                t
            }
        };
        result
    }
}

/// Whether `Transform::scale(s)` must succeed: `s` and `1/s` finite and non-zero.
fn scale_ok(s: f64) -> bool {
    s.is_finite() && s != 0.0 && (1.0 / s).is_finite() && 1.0 / s != 0.0
}

fn read_vec<T: Wire>(u: &mut Unstructured<'_>, min: usize, max: usize) -> Result<Vec<T>> {
    let n = count(u, min, max)?;
    (0..n).map(|_| T::read(u)).collect()
}

fn write_vec<T: Wire>(out: &mut Vec<u8>, items: &[T], min: usize) {
    write_count(out, items.len(), min);
    for x in items {
        x.write(out);
    }
}

/// A chain of steps, applied in order.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Chain(pub Vec<Step>);

impl Wire for Chain {
    fn read(u: &mut Unstructured<'_>) -> Result<Self> {
        Ok(Chain(read_vec(u, 0, MAX_STEPS)?))
    }

    fn write(&self, out: &mut Vec<u8>) {
        write_vec(out, &self.0, 0);
    }
}

impl Chain {
    /// The composed transform, or the first step's error.
    pub fn build(&self) -> core::result::Result<Transform, GeometryError> {
        let mut m = Transform::identity();
        for s in &self.0 {
            m = m.then(&s.build()?);
        }
        Ok(m)
    }
}

/// What a solid starts from before it is moved.
#[derive(Clone, Debug, PartialEq)]
pub enum Base {
    /// One of the nine elementary quadrics, by index.
    Elementary(u8),
    /// `Quadric::from_coefficients`.
    Coefficients([Num; 10]),
    /// `Quadric::from_matrix` (symmetric only if the fuzzer makes it so).
    Matrix([Num; 16]),
    /// `HalfSpace::new(a, b, c, d)`.
    HalfSpace([Num; 4]),
}

/// The elementary quadrics [`Base::Elementary`] indexes.
pub const ELEMENTARY: [fn() -> Quadric; 9] = [
    Quadric::sphere,
    Quadric::tube_x,
    Quadric::tube_y,
    Quadric::tube_z,
    Quadric::cone,
    Quadric::paraboloid,
    Quadric::hyperboloid_one_sheet,
    Quadric::hyperboloid_two_sheets,
    Quadric::sphere, // twice: the commonest solid in scenes
];

impl Wire for Base {
    fn read(u: &mut Unstructured<'_>) -> Result<Self> {
        Ok(match byte(u)? % 4 {
            0 => Base::Elementary(byte(u)? % ELEMENTARY.len() as u8),
            1 => Base::Coefficients(Wire::read(u)?),
            2 => Base::Matrix(Wire::read(u)?),
            _ => Base::HalfSpace(Wire::read(u)?),
        })
    }

    fn write(&self, out: &mut Vec<u8>) {
        match self {
            Base::Elementary(i) => out.extend([0, *i]),
            Base::Coefficients(c) => {
                out.push(1);
                c.write(out);
            }
            Base::Matrix(m) => {
                out.push(2);
                m.write(out);
            }
            Base::HalfSpace(h) => {
                out.push(3);
                h.write(out);
            }
        }
    }
}

impl Base {
    /// Builds the solid, checking that bad coefficients are rejected.
    pub fn build(&self) -> core::result::Result<Solid, GeometryError> {
        match self {
            Base::Elementary(i) => Ok(Solid::from(ELEMENTARY[*i as usize % ELEMENTARY.len()]())),
            Base::Coefficients(c) => {
                let c = values(c);
                let q = Quadric::from_coefficients(c);
                // All zero or only `k > 0` is degenerate.
                let constant = c[..9].iter().all(|x| *x == 0.0) && c[9] >= 0.0;
                assert_eq!(q.is_ok(), c.iter().all(|x| x.is_finite()) && !constant, "from_coefficients({c:?})");
                q.map(Solid::from)
            }
            Base::Matrix(m) => {
                let m = Matrix4::from_row_slice(&values(m));
                let q = Quadric::from_matrix(&m);
                let constant = m.iter().take(15).all(|x| *x == 0.0) && m[(3, 3)] >= 0.0;
                let ok = m.iter().all(|x| x.is_finite()) && m == m.transpose() && !constant;
                assert_eq!(q.is_ok(), ok, "from_matrix({m:?})");
                q.map(Solid::from)
            }
            Base::HalfSpace(h) => {
                let v = Vector4::from(values(h));
                let s = HalfSpace::from_vector(&v);
                let ok = v.iter().all(|x| x.is_finite()) && v.xyz() != Vector3::zeros();
                assert_eq!(s.is_ok(), ok, "half-space {v:?}");
                s.map(Solid::from)
            }
        }
    }
}

/// A solid: a base, optionally complemented, then moved by a chain.
#[derive(Clone, Debug, PartialEq)]
pub struct SolidSpec {
    /// The starting solid.
    pub base: Base,
    /// Whether to take the complement before moving it.
    pub complement: bool,
    /// The placement.
    pub chain: Chain,
}

impl Wire for SolidSpec {
    fn read(u: &mut Unstructured<'_>) -> Result<Self> {
        let base = Base::read(u)?;
        let complement = byte(u)? & 1 == 1;
        Ok(SolidSpec { base, complement, chain: Chain::read(u)? })
    }

    fn write(&self, out: &mut Vec<u8>) {
        self.base.write(out);
        out.push(self.complement as u8);
        self.chain.write(out);
    }
}

impl SolidSpec {
    /// Whether every number of the input is [`bound::moderate`]: the inputs
    /// for which accuracy is checked (a coefficient of 1e-320 has a few
    /// significant bits, and the kernel may rescale it to look moderate).
    pub fn moderate(&self) -> bool {
        let ok = |v: &[Num]| v.iter().all(|x| bound::moderate(x.value()));
        let base = match &self.base {
            Base::Elementary(_) => true,
            Base::Coefficients(c) => ok(c),
            Base::Matrix(m) => ok(m),
            Base::HalfSpace(h) => ok(h),
        };
        base && self.chain.0.iter().all(|s| match s {
            Step::Translate(v) | Step::ScaleXyz(v) => ok(v),
            Step::Scale(x) | Step::RotateX(x) | Step::RotateY(x) | Step::RotateZ(x) => ok(&[*x]),
            Step::Matrix(m) => ok(m),
        })
    }

    /// Builds the solid (which may be non-finite if a long chain overflowed).
    pub fn build(&self) -> core::result::Result<Solid, GeometryError> {
        let s = self.base.build()?;
        let s = if self.complement { s.complement() } else { s };
        Ok(s.transformed(&self.chain.build()?))
    }
}

/// A ray, given directly or by a point it passes through.
#[derive(Clone, Debug, PartialEq)]
pub enum RaySpec {
    /// `Ray::new(origin, direction)`.
    Free([Num; 3], [Num; 3]),
    /// From `origin` through `target` (a zero direction if they are equal).
    Through([Num; 3], [Num; 3]),
}

impl Wire for RaySpec {
    fn read(u: &mut Unstructured<'_>) -> Result<Self> {
        let through = byte(u)? & 1 == 1;
        let (a, b) = (Wire::read(u)?, Wire::read(u)?);
        Ok(if through { RaySpec::Through(a, b) } else { RaySpec::Free(a, b) })
    }

    fn write(&self, out: &mut Vec<u8>) {
        let (tag, a, b) = match self {
            RaySpec::Free(a, b) => (0, a, b),
            RaySpec::Through(a, b) => (1, a, b),
        };
        out.push(tag);
        a.write(out);
        b.write(out);
    }
}

impl RaySpec {
    /// Builds the ray, checking that zero and non-finite inputs are rejected
    /// and that accepted rays have a finite unit direction.
    pub fn build(&self) -> core::result::Result<Ray, GeometryError> {
        let (o, d) = match self {
            RaySpec::Free(o, d) => (Point3::from(vector(o)), vector(d)),
            RaySpec::Through(o, t) => (Point3::from(vector(o)), vector(t) - vector(o)),
        };
        let ray = Ray::new(o, d);
        let ok = o.iter().chain(d.iter()).all(|c| c.is_finite()) && d != Vector3::zeros();
        assert_eq!(ray.is_ok(), ok, "Ray::new({o:?}, {d:?})");
        if let Ok(r) = &ray {
            let n = r.direction().norm();
            assert!((n - 1.0).abs() <= 4.0 * f64::EPSILON, "ray direction of length {n} from {d:?}");
            assert_eq!(r.origin(), o);
        }
        ray
    }
}

/// A point.
#[derive(Clone, Debug, PartialEq)]
pub struct PointSpec(pub [Num; 3]);

impl Wire for PointSpec {
    fn read(u: &mut Unstructured<'_>) -> Result<Self> {
        Ok(PointSpec(Wire::read(u)?))
    }

    fn write(&self, out: &mut Vec<u8>) {
        self.0.write(out);
    }
}

impl PointSpec {
    /// The point.
    pub fn point(&self) -> Point3<f64> {
        Point3::from(vector(&self.0))
    }
}

/// The input of `quadric_intervals`: one solid, rays and points.
#[derive(Clone, Debug, PartialEq)]
pub struct QuadricInput {
    /// The solid.
    pub solid: SolidSpec,
    /// 1 to [`MAX_RAYS`] rays.
    pub rays: Vec<RaySpec>,
    /// Up to [`MAX_POINTS`] points.
    pub points: Vec<PointSpec>,
}

impl Wire for QuadricInput {
    fn read(u: &mut Unstructured<'_>) -> Result<Self> {
        Ok(QuadricInput { solid: Wire::read(u)?, rays: read_vec(u, 1, MAX_RAYS)?, points: read_vec(u, 0, MAX_POINTS)? })
    }

    fn write(&self, out: &mut Vec<u8>) {
        self.solid.write(out);
        write_vec(out, &self.rays, 1);
        write_vec(out, &self.points, 0);
    }
}

/// One block of a [`ComplexInput`].
#[derive(Clone, Debug, PartialEq)]
pub struct BlockSpec {
    /// Up to [`MAX_SOLIDS`] solids (none: an empty block, which must be rejected).
    pub solids: Vec<SolidSpec>,
    /// A placement applied to every solid after its own.
    pub chain: Chain,
    /// Opaque or transparent.
    pub transparent: bool,
    /// The material key (small, so that equal keys are common).
    pub material: u8,
}

impl Wire for BlockSpec {
    fn read(u: &mut Unstructured<'_>) -> Result<Self> {
        let solids = read_vec(u, 0, MAX_SOLIDS)?;
        let chain = Chain::read(u)?;
        let flags = byte(u)?;
        Ok(BlockSpec { solids, chain, transparent: flags & 1 == 1, material: (flags >> 1) % 4 })
    }

    fn write(&self, out: &mut Vec<u8>) {
        write_vec(out, &self.solids, 0);
        self.chain.write(out);
        out.push(self.transparent as u8 | self.material << 1);
    }
}

/// A ray with the `max_t` to cast it with.
#[derive(Clone, Debug, PartialEq)]
pub struct CastSpec {
    /// The ray.
    pub ray: RaySpec,
    /// `max_t` for `cast_ray` (any value, NaN included).
    pub max_t: Num,
}

impl Wire for CastSpec {
    fn read(u: &mut Unstructured<'_>) -> Result<Self> {
        Ok(CastSpec { ray: Wire::read(u)?, max_t: Num::read(u)? })
    }

    fn write(&self, out: &mut Vec<u8>) {
        self.ray.write(out);
        self.max_t.write(out);
    }
}

/// The input of `complex_queries`: blocks, an optional ε, rays and points.
#[derive(Clone, Debug, PartialEq)]
pub struct ComplexInput {
    /// 1 to [`MAX_BLOCKS`] blocks.
    pub blocks: Vec<BlockSpec>,
    /// `ComplexOptions::epsilon`.
    pub epsilon: Option<Num>,
    /// 1 to [`MAX_RAYS`] rays.
    pub casts: Vec<CastSpec>,
    /// Up to [`MAX_POINTS`] points.
    pub points: Vec<PointSpec>,
}

impl Wire for ComplexInput {
    fn read(u: &mut Unstructured<'_>) -> Result<Self> {
        let blocks = read_vec(u, 1, MAX_BLOCKS)?;
        let epsilon = if byte(u)? & 1 == 1 { Some(Num::read(u)?) } else { None };
        Ok(ComplexInput { blocks, epsilon, casts: read_vec(u, 1, MAX_RAYS)?, points: read_vec(u, 0, MAX_POINTS)? })
    }

    fn write(&self, out: &mut Vec<u8>) {
        write_vec(out, &self.blocks, 1);
        match &self.epsilon {
            None => out.push(0),
            Some(e) => {
                out.push(1);
                e.write(out);
            }
        }
        write_vec(out, &self.casts, 1);
        write_vec(out, &self.points, 0);
    }
}

macro_rules! arbitrary_via_wire {
    ($($t:ty),*) => {$(
        impl<'a> Arbitrary<'a> for $t {
            fn arbitrary(u: &mut Unstructured<'a>) -> Result<Self> {
                <$t as Wire>::read(u)
            }
        }
    )*};
}

arbitrary_via_wire!(QuadricInput, ComplexInput);

/// Encodes an input (the inverse of `Arbitrary::arbitrary` on these types).
pub fn encode<T: Wire>(x: &T) -> Vec<u8> {
    let mut out = Vec::new();
    x.write(&mut out);
    out
}

/// Decodes bytes as the fuzz target does.
pub fn decode<'a, T: Arbitrary<'a>>(bytes: &'a [u8]) -> Result<T> {
    T::arbitrary_take_rest(Unstructured::new(bytes))
}

/// Error bounds for evaluating a solid's defining function near a point.
pub mod bound {
    use quadric::nalgebra::Point3;
    use quadric::Solid;

    /// `Σ |terms|` of `f(x)`: the scale its rounding error is relative to,
    /// or `None` if it overflows.
    pub fn magnitude(s: &Solid, x: &Point3<f64>) -> Option<f64> {
        let m = match s {
            Solid::Quadric(q) => {
                let (c, a, w, k) = q.local_parts();
                // Every entry of `A` carries an absolute rounding error of
                // about ε·max|A| (from the transforms that built it), so the
                // scale is max|A|·|d|², not Σ|aᵢⱼ dᵢ dⱼ|: a rotated tube's
                // zero entries are ±1e-17, which is 10 at 1e9 along the axis.
                let d = (x - c).abs();
                a.amax() * d.sum() * d.sum() + 2.0 * w.abs().dot(&d) + k.abs()
            }
            Solid::HalfSpace(h) => {
                let v = h.vector();
                let d = (x - h.reference_point()).abs();
                h.normal_vector().abs().dot(&d) + (v.w + h.normal_vector().dot(&h.reference_point().coords)).abs()
            }
        };
        m.is_finite().then_some(m)
    }

    /// An upper bound on `|∇f(x)|₁`, or `None` if it overflows.
    pub fn gradient(s: &Solid, x: &Point3<f64>) -> Option<f64> {
        let g = match s {
            Solid::Quadric(q) => {
                let (c, a, w, _) = q.local_parts();
                2.0 * ((a.abs() * (x - c).abs()).sum() + w.abs().sum())
            }
            Solid::HalfSpace(h) => h.normal_vector().abs().sum(),
        };
        g.is_finite().then_some(g)
    }

    /// `Σ |A_ij|`: how fast the gradient itself can change (0 for a half-space).
    pub fn curvature(s: &Solid) -> f64 {
        match s {
            Solid::Quadric(q) => q.quadratic_part().abs().sum(),
            Solid::HalfSpace(_) => 0.0,
        }
    }

    /// Whether `x` is zero or of moderate size (`1e-80 <= |x| <= 1e80`):
    /// then products of three such numbers neither overflow nor underflow.
    pub fn moderate(x: f64) -> bool {
        x == 0.0 || (1e-80..=1e80).contains(&x.abs())
    }

    /// How far apart in size the non-zero entries of a quadric's `A` may be
    /// for accuracy to be promised: a transform chain that stretches a solid
    /// by more than 10¹⁶ leaves entries that are mostly its rounding (a
    /// cylinder scaled by 10¹⁸ across and 5·10²³ along, then tilted, stored
    /// `A_zz = 1.4e-60` beside `A_xx = 0.08`), and far from the centre the
    /// sign of `f` turns on them: its bounding box (from the stored `A`) and
    /// its computed membership (along the null axis it found) then disagree.
    pub const MAX_SPREAD: f64 = 1e32;

    /// Whether every stored coefficient and the centre are [`moderate`], and
    /// a quadric's `A` spreads over at most [`MAX_SPREAD`]: the range where
    /// accuracy is promised. (Beyond it, subnormal products lose bits,
    /// squares overflow, or rounding residue decides; only "no panic, no
    /// NaN" holds there.)
    pub fn moderate_solid(s: &Solid) -> bool {
        match s {
            Solid::Quadric(q) => {
                let (c, a, w, k) = q.local_parts();
                let sizes = a.iter().map(|x| x.abs()).filter(|x| *x > 0.0);
                let (lo, hi) = sizes.fold((f64::INFINITY, 0.0f64), |(lo, hi), x| (lo.min(x), hi.max(x)));
                c.iter().chain(a.iter()).chain(w.iter()).all(|x| moderate(*x))
                    && moderate(k)
                    && (hi == 0.0 || hi <= MAX_SPREAD * lo)
            }
            Solid::HalfSpace(h) => {
                let v = h.vector();
                h.reference_point().iter().chain(h.normal_vector().iter()).all(|x| moderate(*x)) && moderate(v.w)
            }
        }
    }

    /// The point the solid's coefficients are taken around.
    pub fn centre(s: &Solid) -> Point3<f64> {
        match s {
            Solid::Quadric(q) => q.centre(),
            Solid::HalfSpace(h) => h.reference_point(),
        }
    }
}
