//! The pinhole camera of docs/model.md §4.2, in pixel units.

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
        Ok(Camera { eye, d, u, r, focal, width, height, aperture: aperture_degrees, centre })
    }

    /// The same camera with another image size (the opening angle stays on the diagonal).
    pub fn with_size(&self, width: u32, height: u32) -> Result<Self, CameraError> {
        Camera::new(self.eye, self.d, self.u, width, height, self.aperture)
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

    /// The ray through the (possibly fractional) pixel position `(i, j)`.
    #[inline]
    pub fn ray_at(&self, i: f64, j: f64) -> Ray {
        // The offset's D component is `focal > 0` and everything is finite,
        // so this cannot fail; the fallback only keeps the path panic-free.
        Ray::new(self.eye, self.offset(i, j)).unwrap_or(self.centre)
    }

    /// [`Camera::ray_at`] of four pixel positions `(i, j)`, exactly: the
    /// four directions normalised together ([`Ray::new4`]).
    #[inline]
    pub fn rays4(&self, at: [(f64, f64); 4]) -> [Ray; 4] {
        let rays = Ray::new4(self.eye, &at.map(|(i, j)| self.offset(i, j)));
        rays.map(|r| r.unwrap_or(self.centre))
    }

    /// Where the point `x` appears: fractional `(i, j)` of the pixel grid
    /// (centres at integers), or `None` if it is not in front of the eye.
    pub fn project(&self, x: &Point3<f64>) -> Option<(f64, f64)> {
        let v = x - self.eye;
        let z = v.dot(&self.d);
        if z <= 0.0 {
            return None;
        }
        let s = self.focal / z;
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
