//! The camera of docs/model.md §4: the pinhole of §4.2 in pixel units, the
//! thin lens and the orthographic projection of §4.5.

use quadric::nalgebra::{Point3, Vector3};
use quadric::Ray;

use crate::limits::MAX_PIXELS;

/// Why a camera could not be built.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum CameraError {
    /// `direction` is zero (or not finite).
    #[error("the direction is zero or not finite")]
    ZeroDirection,
    /// The eye or up vector is not finite.
    #[error("the eye or up vector is not finite")]
    NonFinite,
    /// `up` is zero or parallel to `direction`.
    #[error("the up vector is zero or parallel to the direction")]
    UpParallel,
    /// Width or height is zero.
    #[error("the image size {0}x{1} is empty")]
    EmptyImage(u32, u32),
    /// More pixels than [`MAX_PIXELS`]; refused before anything is allocated.
    #[error("the image size {0}x{1} is too large: at most {max} pixels (about 16k x 16k) are supported", max = MAX_PIXELS)]
    TooLarge(u32, u32),
    /// The opening angle is outside (0°, 180°).
    #[error("the aperture must lie strictly between 0 and 180 degrees, got {0}")]
    BadAperture(f64),
    /// The lens radius is negative or not finite.
    #[error("the lens radius must be finite and >= 0, got {0}")]
    BadLensRadius(f64),
    /// The focus distance is not positive or not finite.
    #[error("the focus distance must be finite and > 0, got {0}")]
    BadFocusDistance(f64),
    /// The orthographic image diagonal is not positive or not finite.
    #[error("the diagonal must be finite and > 0, got {0}")]
    BadDiagonal(f64),
}

/// How the camera's rays leave the image plane (docs/model.md §4.5).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Projection {
    /// Rays from the eye through the pixels (§4.2): the default.
    Perspective,
    /// Parallel rays along `D`, from the pixels of an image rectangle
    /// through the eye whose diagonal is `diagonal` world units long.
    Orthographic {
        /// The world-space length of the image diagonal.
        diagonal: f64,
    },
}

/// The point of the unit disc for the lens sample `(u, v)` in `[0, 1)²`:
/// Shirley and Chiu's concentric map, which keeps areas (a uniform sample
/// of the square is a uniform sample of the disc) and maps `(½, ½)` to the
/// centre exactly (docs/model.md §4.5).
///
/// ```
/// use render::camera::concentric_disc;
/// assert_eq!(concentric_disc(0.5, 0.5), (0.0, 0.0));
/// let (x, y) = concentric_disc(1.0, 0.5);
/// assert!((x - 1.0).abs() < 1e-15 && y.abs() < 1e-15);
/// ```
pub fn concentric_disc(u: f64, v: f64) -> (f64, f64) {
    use std::f64::consts::FRAC_PI_4;
    let (a, b) = (2.0 * u - 1.0, 2.0 * v - 1.0);
    if a == 0.0 && b == 0.0 {
        return (0.0, 0.0);
    }
    let (r, phi) =
        if a.abs() > b.abs() { (a, FRAC_PI_4 * (b / a)) } else { (b, 2.0 * FRAC_PI_4 - FRAC_PI_4 * (a / b)) };
    (r * phi.cos(), r * phi.sin())
}

/// The camera: an orthonormal frame `D, U, R` at the eye and the distance
/// `f` from the eye to the image plane in pixel units.
///
/// ```
/// use quadric::nalgebra::{Point3, Vector3};
/// use render::camera::Camera;
/// let cam = Camera::new(Point3::origin(), -Vector3::z(), Vector3::y(), 3, 3, 50.0).unwrap();
/// // The centre pixel of an odd-sized image looks straight ahead.
/// assert_eq!(cam.ray(1, 1).direction(), -Vector3::z());
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    eye: Point3<f64>,
    d: Vector3<f64>,
    u: Vector3<f64>,
    r: Vector3<f64>,
    focal: f64,
    width: u32,
    height: u32,
    aperture: f64,
    centre: Ray,
    projection: Projection,
    /// World size of a pixel (orthographic only; 0 for a perspective camera).
    pixel: f64,
    lens_radius: f64,
    focus: f64,
}

impl Camera {
    /// The camera at `eye` looking along `direction` with `up` (only its
    /// part orthogonal to `direction` counts), an image of `width × height`
    /// pixels and the opening angle `aperture_degrees` on the diagonal.
    pub fn new(
        eye: Point3<f64>,
        direction: Vector3<f64>,
        up: Vector3<f64>,
        width: u32,
        height: u32,
        aperture_degrees: f64,
    ) -> Result<Self, CameraError> {
        if width == 0 || height == 0 {
            return Err(CameraError::EmptyImage(width, height));
        }
        if u64::from(width) * u64::from(height) > MAX_PIXELS {
            return Err(CameraError::TooLarge(width, height));
        }
        if !(aperture_degrees > 0.0 && aperture_degrees < 180.0) {
            return Err(CameraError::BadAperture(aperture_degrees));
        }
        let n = direction.norm();
        if !(n > 0.0 && n.is_finite()) {
            return Err(CameraError::ZeroDirection);
        }
        // D := D/|D|;  U := U - (U·D) D;  U := U/|U|;  R := D × U
        let d = direction / n;
        let up_len = up.norm();
        let u = up - up.dot(&d) * d;
        let un = u.norm();
        // Relative test: an up vector within ~1e-9 rad of D gives no usable frame.
        if !up_len.is_finite() {
            return Err(CameraError::NonFinite);
        }
        if !(un > 1e-9 * up_len && un.is_finite()) {
            return Err(CameraError::UpParallel);
        }
        let u = u / un;
        let r = d.cross(&u);
        let (w, h) = (f64::from(width), f64::from(height));
        let centre = Ray::new(eye, d).map_err(|_| CameraError::NonFinite)?;
        let focal = (w * w + h * h).sqrt() / (2.0 * (aperture_degrees.to_radians() / 2.0).tan());
        if !focal.is_finite() {
            return Err(CameraError::BadAperture(aperture_degrees));
        }
        Ok(Camera {
            eye,
            d,
            u,
            r,
            focal,
            width,
            height,
            aperture: aperture_degrees,
            centre,
            projection: Projection::Perspective,
            pixel: 0.0,
            lens_radius: 0.0,
            focus: 1.0,
        })
    }

    /// The same camera with a thin lens of radius `lens_radius` (world
    /// units; 0 is the pinhole) focused at `focus_distance` along `D`
    /// (docs/model.md §4.5).
    pub fn with_lens(&self, lens_radius: f64, focus_distance: f64) -> Result<Self, CameraError> {
        if !(lens_radius.is_finite() && lens_radius >= 0.0) {
            return Err(CameraError::BadLensRadius(lens_radius));
        }
        if !(focus_distance.is_finite() && focus_distance > 0.0) {
            return Err(CameraError::BadFocusDistance(focus_distance));
        }
        Ok(Camera { lens_radius, focus: focus_distance, ..*self })
    }

    /// The same camera with another projection; an orthographic image's
    /// diagonal must be finite and positive.
    pub fn with_projection(&self, projection: Projection) -> Result<Self, CameraError> {
        let pixel = match projection {
            Projection::Perspective => 0.0,
            Projection::Orthographic { diagonal } => {
                let (w, h) = (f64::from(self.width), f64::from(self.height));
                let pixel = diagonal / (w * w + h * h).sqrt();
                if !(diagonal.is_finite() && diagonal > 0.0 && pixel > 0.0) {
                    return Err(CameraError::BadDiagonal(diagonal));
                }
                pixel
            }
        };
        Ok(Camera { projection, pixel, ..*self })
    }

    /// The same camera with another image size (the opening angle, or the
    /// orthographic image's world-space diagonal, stays on the diagonal).
    pub fn with_size(&self, width: u32, height: u32) -> Result<Self, CameraError> {
        Camera::new(self.eye, self.d, self.u, width, height, self.aperture)?
            .with_projection(self.projection)?
            .with_lens(self.lens_radius, self.focus)
    }

    /// The camera with the size overrides of the command line: both given,
    /// that size; one given, the other side keeps this camera's aspect ratio
    /// (rounded, at least 1); none, the camera itself.
    pub fn resized(&self, width: Option<u32>, height: Option<u32>) -> Result<Self, CameraError> {
        let (w0, h0) = (f64::from(self.width), f64::from(self.height));
        let keep = |side: u32, num: f64, den: f64| ((f64::from(side) * num / den).round() as u32).max(1);
        match (width, height) {
            (None, None) => Ok(*self),
            (Some(w), Some(h)) => self.with_size(w, h),
            (Some(w), None) => self.with_size(w, keep(w, h0, w0)),
            (None, Some(h)) => self.with_size(keep(h, w0, h0), h),
        }
    }

    /// Image width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Image height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The eye point `E`.
    pub fn eye(&self) -> Point3<f64> {
        self.eye
    }

    /// The unit viewing direction `D`.
    pub fn direction(&self) -> Vector3<f64> {
        self.d
    }

    /// The unit up vector `U`, orthogonal to `D`.
    pub fn up(&self) -> Vector3<f64> {
        self.u
    }

    /// The unit right vector `R = D × U`.
    pub fn right(&self) -> Vector3<f64> {
        self.r
    }

    /// The projection.
    pub fn projection(&self) -> Projection {
        self.projection
    }

    /// The lens radius in world units (0: a pinhole).
    pub fn lens_radius(&self) -> f64 {
        self.lens_radius
    }

    /// The distance from the eye to the plane of sharp focus along `D`
    /// (only used with a lens).
    pub fn focus_distance(&self) -> f64 {
        self.focus
    }

    /// The world-space size of a pixel of an orthographic camera (0 for a
    /// perspective one).
    pub fn pixel_size(&self) -> f64 {
        self.pixel
    }

    /// `|M - E| = sqrt(DimX² + DimY²) / (2 tan(angle/2))`, in pixels.
    pub fn focal_distance(&self) -> f64 {
        self.focal
    }

    /// `P_ij - E` for row `i` (top first) and column `j`, at pixel offsets
    /// `(i, j)` that may be fractional (`i + 0.5` is the lower edge of row `i`).
    ///
    /// Equal to `P00 - i·U + j·R - E` with `P00 = M - (DimX-1)/2·R + (DimY-1)/2·U`,
    /// but summed relative to the eye: forming `P_ij` first would add `E`
    /// and subtract it again, losing digits when the eye is far from the origin.
    #[inline]
    pub fn offset(&self, i: f64, j: f64) -> Vector3<f64> {
        let (w, h) = (f64::from(self.width), f64::from(self.height));
        self.focal * self.d + (j - (w - 1.0) / 2.0) * self.r + ((h - 1.0) / 2.0 - i) * self.u
    }

    /// The ray through the centre of pixel `(i, j)`: row `i` from the top, column `j`.
    #[inline]
    pub fn ray(&self, i: u32, j: u32) -> Ray {
        self.ray_at(f64::from(i), f64::from(j))
    }

    /// `O_ij - E` of an orthographic camera: the point of pixel `(i, j)` on
    /// the image plane through the eye, relative to the eye (docs/model.md §4.5).
    #[inline]
    fn plane_offset(&self, i: f64, j: f64) -> Vector3<f64> {
        let (w, h) = (f64::from(self.width), f64::from(self.height));
        self.pixel * ((j - (w - 1.0) / 2.0) * self.r + ((h - 1.0) / 2.0 - i) * self.u)
    }

    /// The ray through the (possibly fractional) pixel position `(i, j)`
    /// from the lens centre: the pinhole ray of a lens camera.
    #[inline]
    pub fn ray_at(&self, i: f64, j: f64) -> Ray {
        match self.projection {
            // The offset's D component is `focal > 0` and everything is finite,
            // so this cannot fail; the fallback only keeps the path panic-free.
            Projection::Perspective => Ray::new(self.eye, self.offset(i, j)).unwrap_or(self.centre),
            Projection::Orthographic { .. } => {
                Ray::new(self.eye + self.plane_offset(i, j), self.d).unwrap_or(self.centre)
            }
        }
    }

    /// [`Camera::ray_at`] of four pixel positions `(i, j)`, exactly: the
    /// four directions normalised together ([`Ray::new4`]).
    #[inline]
    pub fn rays4(&self, at: [(f64, f64); 4]) -> [Ray; 4] {
        if let Projection::Orthographic { .. } = self.projection {
            return at.map(|(i, j)| self.ray_at(i, j));
        }
        let rays = Ray::new4(self.eye, &at.map(|(i, j)| self.offset(i, j)));
        rays.map(|r| r.unwrap_or(self.centre))
    }

    /// The ray through pixel position `(i, j)` from the point of the lens
    /// for the lens sample `(u, v)` in `[0, 1)²` ([`concentric_disc`]):
    /// from `E + lens_radius (x R + y U)` through the point at distance
    /// `focus_distance` along `D` that the pinhole ray [`Camera::ray_at`]
    /// passes (docs/model.md §4.5). Without a lens, that pinhole ray, bit
    /// for bit.
    #[inline]
    pub fn lens_ray(&self, i: f64, j: f64, (u, v): (f64, f64)) -> Ray {
        if self.lens_radius == 0.0 {
            return self.ray_at(i, j);
        }
        let (x, y) = concentric_disc(u, v);
        let lens = self.lens_radius * (x * self.r + y * self.u);
        // Both relative to the eye: the focus point and the lens point.
        let (start, focus) = match self.projection {
            Projection::Perspective => (lens, self.offset(i, j) * (self.focus / self.focal)),
            Projection::Orthographic { .. } => {
                let o = self.plane_offset(i, j);
                (o + lens, o + self.focus * self.d)
            }
        };
        Ray::new(self.eye + start, focus - start).unwrap_or(self.centre)
    }

    /// Where the point `x` appears: fractional `(i, j)` of the pixel grid
    /// (centres at integers), or `None` if it is not in front of the eye.
    /// For a lens camera, where the pinhole (the lens centre) sees it.
    pub fn project(&self, x: &Point3<f64>) -> Option<(f64, f64)> {
        let v = x - self.eye;
        let z = v.dot(&self.d);
        if z <= 0.0 {
            return None;
        }
        let s = match self.projection {
            Projection::Perspective => self.focal / z,
            Projection::Orthographic { .. } => 1.0 / self.pixel,
        };
        let (w, h) = (f64::from(self.width), f64::from(self.height));
        let j = v.dot(&self.r) * s + (w - 1.0) / 2.0;
        let i = (h - 1.0) / 2.0 - v.dot(&self.u) * s;
        Some((i, j))
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::too_many_arguments)]
mod tests {
    use super::*;

    /// The formulas of docs/model.md §4.2, literally, as an independent oracle.
    fn model_pixel(
        e: Point3<f64>,
        d: Vector3<f64>,
        u: Vector3<f64>,
        dimx: f64,
        dimy: f64,
        angle: f64,
        i: f64,
        j: f64,
    ) -> Vector3<f64> {
        let d = d / d.norm();
        let u = u - u.dot(&d) * d;
        let u = u / u.norm();
        let r = d.cross(&u);
        let m = e + (dimx * dimx + dimy * dimy).sqrt() / (2.0 * (angle.to_radians() / 2.0).tan()) * d;
        let p00 = m - (dimx - 1.0) / 2.0 * r + (dimy - 1.0) / 2.0 * u;
        let pij = p00 - i * u + j * r;
        let v = pij - e;
        v / v.norm()
    }

    fn check(e: [f64; 3], d: [f64; 3], u: [f64; 3], w: u32, h: u32, angle: f64) {
        let (e, d, u) = (Point3::from(Vector3::from(e)), Vector3::from(d), Vector3::from(u));
        let cam = Camera::new(e, d, u, w, h, angle).unwrap();
        for (i, j) in [(0, 0), (0, w - 1), (h - 1, 0), (h - 1, w - 1), (h / 2, w / 2), (h / 3, w / 5)] {
            let want = model_pixel(e, d, u, f64::from(w), f64::from(h), angle, f64::from(i), f64::from(j));
            let got = cam.ray(i, j);
            assert_eq!(got.origin(), e);
            let err = (got.direction() - want).amax();
            assert!(err <= 4.0 * f64::EPSILON, "pixel ({i},{j}): {got:?} vs {want:?}, error {err:e}");
        }
        // Four at a time: the same rays, bit for bit, whole and sub-pixel positions.
        let (fw, fh) = (f64::from(w), f64::from(h));
        for at in [
            [(0.0, 0.0), (0.0, fw - 1.0), (fh - 1.0, 0.0), (fh - 1.0, fw - 1.0)],
            [(0.25, 0.75), (fh / 3.0, fw / 7.0), (-0.5, fw - 0.5), (fh / 2.0 - 0.125, 0.375)],
        ] {
            let bits = |r: Ray| (r.origin().map(f64::to_bits), r.direction().map(f64::to_bits));
            let four = cam.rays4(at).map(bits);
            assert_eq!(four, at.map(|(i, j)| bits(cam.ray_at(i, j))), "{at:?}");
        }
    }

    #[test]
    fn rays_follow_the_spec_formulas() {
        check([0.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0], 640, 480, 50.0);
        check([0.0, 1.2, 6.0], [0.0, -0.15, -1.0], [0.0, 1.0, 0.0], 640, 480, 50.0);
        check([1.0, -2.0, 3.0], [1.0, 2.0, 3.0], [0.3, 1.0, -0.2], 17, 9, 80.0);
        check([0.0, 0.0, 0.0], [0.0, 0.0, -1.0], [1.0, 0.0, 0.0], 1, 1, 10.0);
        check([5.0, 5.0, 5.0], [-1.0, -1.0, -1.0], [0.0, 0.0, 1.0], 320, 200, 120.0);
    }

    #[test]
    fn the_diagonal_spans_the_aperture() {
        // Corner pixel *edges* (not centres) lie on the cone of half-angle aperture/2.
        let cam = Camera::new(Point3::origin(), -Vector3::z(), Vector3::y(), 400, 300, 60.0).unwrap();
        let corner = cam.offset(-0.5, -0.5);
        let angle = corner.angle(&cam.direction()).to_degrees();
        assert!((angle - 30.0).abs() < 1e-12, "{angle}");
    }

    #[test]
    fn right_is_d_cross_u_and_rows_go_down() {
        let cam = Camera::new(Point3::origin(), -Vector3::z(), Vector3::y(), 4, 2, 50.0).unwrap();
        assert_eq!(cam.right(), Vector3::x());
        assert!(cam.ray(0, 3).direction().x > 0.0 && cam.ray(0, 3).direction().y > 0.0);
        assert!(cam.ray(1, 0).direction().x < 0.0 && cam.ray(1, 0).direction().y < 0.0);
    }

    #[test]
    fn project_inverts_ray() {
        let cam =
            Camera::new(Point3::new(1.0, 2.0, 3.0), Vector3::new(0.2, -0.1, -1.0), Vector3::y(), 64, 48, 50.0).unwrap();
        let p = cam.ray(10, 40).at(7.0);
        let (i, j) = cam.project(&p).unwrap();
        assert!((i - 10.0).abs() < 1e-9 && (j - 40.0).abs() < 1e-9, "{i} {j}");
    }

    /// Distance from the point `p` to the line of `ray`.
    fn off_line(ray: &Ray, p: &Point3<f64>) -> f64 {
        let v = p - ray.origin();
        (v - v.dot(&ray.direction()) * ray.direction()).norm()
    }

    /// Lens samples spread over `[0, 1)²`, the edges and the centre included.
    fn lens_samples() -> Vec<(f64, f64)> {
        let mut s: Vec<(f64, f64)> =
            (0..7).flat_map(|a| (0..7).map(move |b| (a as f64 / 6.0, b as f64 / 6.0))).collect();
        s.iter_mut().for_each(|(u, v)| (*u, *v) = (u.min(0.999_999), v.min(0.999_999)));
        s.push((0.5, 0.5));
        s
    }

    #[test]
    fn thin_lens_rays_meet_on_the_focus_plane() {
        let (e, d, u) = (Point3::new(1.0, -2.0, 3.0), Vector3::new(1.0, 2.0, 3.0), Vector3::new(0.3, 1.0, -0.2));
        let (radius, focus) = (0.35, 7.5);
        let cam = Camera::new(e, d, u, 17, 9, 80.0).unwrap().with_lens(radius, focus).unwrap();
        let dn = d / d.norm();
        for (i, j) in [(0.0, 0.0), (8.0, 16.0), (4.0, 8.0), (2.25, 11.75)] {
            // The focus-plane point of the pinhole ray, from the formulas of §4.2.
            let w = model_pixel(e, d, u, 17.0, 9.0, 80.0, i, j);
            let p = e + w * (focus / w.dot(&dn));
            for s in lens_samples() {
                let ray = cam.lens_ray(i, j, s);
                let o = ray.origin() - e;
                assert!(o.dot(&dn).abs() < 1e-12, "origin off the lens plane: {o:?}");
                assert!(o.norm() <= radius * (1.0 + 1e-12), "origin off the lens disc: {}", o.norm());
                assert!(
                    off_line(&ray, &p) < 1e-12 * focus,
                    "({i},{j}) {s:?}: misses the focus point by {:e}",
                    off_line(&ray, &p)
                );
                assert!(ray.direction().dot(&dn) > 0.0);
            }
        }
    }

    #[test]
    fn lens_origins_cover_the_disc_uniformly() {
        // A uniform map of the square keeps areas: mean r² = 1/2 on the unit disc,
        // a quarter of the points in each quadrant and none outside.
        let n = 200;
        let (mut r2, mut quadrants) = (0.0, [0usize; 4]);
        for a in 0..n {
            for b in 0..n {
                let (x, y) = concentric_disc((a as f64 + 0.5) / n as f64, (b as f64 + 0.5) / n as f64);
                assert!(x * x + y * y <= 1.0 + 1e-12);
                r2 += x * x + y * y;
                quadrants[usize::from(x < 0.0) * 2 + usize::from(y < 0.0)] += 1;
            }
        }
        let r2 = r2 / (n * n) as f64;
        assert!((r2 - 0.5).abs() < 1e-3, "mean r² {r2}");
        assert!(quadrants.iter().all(|q| q.abs_diff(n * n / 4) <= n), "{quadrants:?}");
    }

    #[test]
    fn no_lens_is_the_pinhole_bit_for_bit() {
        let cam = Camera::new(Point3::new(1e3, -2.0, 3.0), Vector3::new(0.2, -0.1, -1.0), Vector3::y(), 64, 48, 50.0)
            .unwrap()
            .with_lens(0.0, 3.0)
            .unwrap();
        let bits = |r: Ray| (r.origin().map(f64::to_bits), r.direction().map(f64::to_bits));
        for (i, j) in [(0.0, 0.0), (47.0, 63.0), (10.25, 40.625)] {
            for s in lens_samples() {
                assert_eq!(bits(cam.lens_ray(i, j, s)), bits(cam.ray_at(i, j)));
            }
        }
    }

    #[test]
    fn orthographic_rays_are_parallel_and_span_the_diagonal() {
        let (e, d) = (Point3::new(0.5, 1.0, 4.0), Vector3::new(0.0, -0.3, -1.0));
        let (w, h, diagonal) = (40, 30, 5.0);
        let cam = Camera::new(e, d, Vector3::y(), w, h, 50.0)
            .unwrap()
            .with_projection(Projection::Orthographic { diagonal })
            .unwrap();
        let dn = d / d.norm();
        for (i, j) in [(0.0, 0.0), (29.0, 39.0), (7.5, 13.25)] {
            let ray = cam.ray_at(i, j);
            assert!((ray.direction() - dn).amax() < 1e-15);
            assert!((ray.origin() - e).dot(&dn).abs() < 1e-12, "origin off the image plane");
        }
        // The outer corners of the corner pixels are `diagonal` apart.
        let (fw, fh) = (f64::from(w), f64::from(h));
        let span = cam.ray_at(-0.5, -0.5).origin() - cam.ray_at(fh - 0.5, fw - 0.5).origin();
        assert!((span.norm() - diagonal).abs() < 1e-12, "{}", span.norm());
        // The image's sides keep the aspect ratio: 4 : 3 of a 3-4-5 triangle.
        let across = cam.ray_at(0.0, -0.5).origin() - cam.ray_at(0.0, fw - 0.5).origin();
        assert!((across.norm() - 4.0).abs() < 1e-12, "{}", across.norm());
        // Four at a time: the same rays.
        let at = [(0.0, 0.0), (1.5, 2.0), (29.0, 0.0), (3.0, 39.0)];
        assert_eq!(cam.rays4(at), at.map(|(i, j)| cam.ray_at(i, j)));
        // Project inverts the ray.
        let (i, j) = cam.project(&cam.ray_at(11.0, 7.0).at(3.0)).unwrap();
        assert!((i - 11.0).abs() < 1e-9 && (j - 7.0).abs() < 1e-9, "{i} {j}");
        // An orthographic lens: rays through one focus point per pixel.
        let lens = cam.with_lens(0.2, 6.0).unwrap();
        let p = cam.ray_at(5.0, 9.0).at(6.0);
        for s in lens_samples() {
            let ray = lens.lens_ray(5.0, 9.0, s);
            assert!(off_line(&ray, &p) < 1e-12, "{s:?}");
            assert!((ray.origin() - cam.ray_at(5.0, 9.0).origin()).norm() <= 0.2 * (1.0 + 1e-12));
        }
    }

    #[test]
    fn resizing_keeps_lens_and_projection() {
        let cam = Camera::new(Point3::origin(), -Vector3::z(), Vector3::y(), 40, 30, 50.0)
            .unwrap()
            .with_projection(Projection::Orthographic { diagonal: 5.0 })
            .unwrap()
            .with_lens(0.1, 4.0)
            .unwrap();
        let big = cam.with_size(80, 60).unwrap();
        assert_eq!(big.projection(), cam.projection());
        assert_eq!((big.lens_radius(), big.focus_distance()), (0.1, 4.0));
        assert!((big.pixel_size() - cam.pixel_size() / 2.0).abs() < 1e-15);
    }

    #[test]
    fn bad_lenses_and_diagonals_are_errors() {
        let cam = Camera::new(Point3::origin(), -Vector3::z(), Vector3::y(), 4, 4, 50.0).unwrap();
        assert_eq!(cam.with_lens(-0.1, 1.0), Err(CameraError::BadLensRadius(-0.1)));
        assert!(matches!(cam.with_lens(f64::NAN, 1.0), Err(CameraError::BadLensRadius(_))));
        assert_eq!(cam.with_lens(0.1, 0.0), Err(CameraError::BadFocusDistance(0.0)));
        assert_eq!(cam.with_lens(0.1, f64::INFINITY), Err(CameraError::BadFocusDistance(f64::INFINITY)));
        let ortho = |diagonal| cam.with_projection(Projection::Orthographic { diagonal });
        assert_eq!(ortho(0.0), Err(CameraError::BadDiagonal(0.0)));
        assert_eq!(ortho(-2.0), Err(CameraError::BadDiagonal(-2.0)));
        assert!(ortho(f64::NAN).is_err() && ortho(f64::INFINITY).is_err());
    }

    #[test]
    fn bad_inputs_are_errors() {
        let e = Point3::origin();
        assert_eq!(Camera::new(e, Vector3::zeros(), Vector3::y(), 4, 4, 50.0), Err(CameraError::ZeroDirection));
        assert_eq!(Camera::new(e, Vector3::y(), Vector3::y() * 3.0, 4, 4, 50.0), Err(CameraError::UpParallel));
        assert_eq!(Camera::new(e, -Vector3::z(), Vector3::y(), 0, 4, 50.0), Err(CameraError::EmptyImage(0, 4)));
        assert_eq!(Camera::new(e, -Vector3::z(), Vector3::y(), 4, 4, 180.0), Err(CameraError::BadAperture(180.0)));
        assert!(Camera::new(e, -Vector3::z(), Vector3::y(), 4, 4, f64::NAN).is_err());
    }
}
