//! PNG preview: sRGB-encoded, scaled by `2^exposure`, clamped to [0, 1].

use std::path::Path;

use crate::error::Error;
use crate::frame::Frame;
use crate::output::write_atomic;

/// The sRGB transfer function of a linear value in [0, 1].
pub fn srgb(linear: f32) -> f32 {
    if linear <= 0.003_130_8 {
        12.92 * linear
    } else {
        1.055 * linear.powf(1.0 / 2.4) - 0.055
    }
}

/// One linear channel value to an 8-bit sRGB code (NaN becomes 0).
pub fn encode(linear: f32, exposure: f32) -> u8 {
    let v = (linear * exposure.exp2()).clamp(0.0, 1.0);
    let v = if v.is_nan() { 0.0 } else { v };
    (srgb(v) * 255.0).round() as u8
}

/// Writes an 8-bit RGB sRGB preview of `frame` to `path`, atomically.
pub fn write_png(frame: &Frame, path: &Path, exposure: f32) -> Result<(), Error> {
    write_png_planes(path, (frame.width, frame.height), &frame.rgb, exposure)
}

/// Writes the preview of linear `rgb` planes (`width × height` samples
/// each, rows from the top) to `path`, atomically: [`write_png`] of
/// planes not in a [`Frame`] (`komplex merge --png`).
pub fn write_png_planes(
    path: &Path,
    (width, height): (u32, u32),
    rgb: &[Vec<f32>; 3],
    exposure: f32,
) -> Result<(), Error> {
    let [r, g, b] = rgb;
    let bytes: Vec<u8> =
        r.iter().zip(g).zip(b).flat_map(|((&r, &g), &b)| [r, g, b].map(|c| encode(c, exposure))).collect();
    let img = image::RgbImage::from_raw(width, height, bytes)
        .ok_or_else(|| Error::Encode { path: path.to_path_buf(), message: "buffer size mismatch".into() })?;
    write_atomic(path, |w| img.write_to(w, image::ImageFormat::Png).map_err(|e| e.to_string()))
}

/// Writes 8-bit RGB `bytes` (three a pixel, rows from the top) as a PNG,
/// atomically: the maps of `komplex slice`.
pub fn write_rgb8(path: &Path, (width, height): (u32, u32), bytes: Vec<u8>) -> Result<(), Error> {
    let img = image::RgbImage::from_raw(width, height, bytes)
        .ok_or_else(|| Error::Encode { path: path.to_path_buf(), message: "buffer size mismatch".into() })?;
    write_atomic(path, |w| img.write_to(w, image::ImageFormat::Png).map_err(|e| e.to_string()))
}
