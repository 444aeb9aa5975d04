//! OpenEXR output: one part, scanlines, ZIP compression, with the channels
//! compositing tools expect (`R G B A Z N.X N.Y N.Z id.block id.object`).

use std::path::Path;

use exr::prelude::{
    f16, AnyChannel, AnyChannels, Blocks, Compression, Encoding, FlatSamples, Image, Layer, LayerAttributes, LineOrder,
    SmallVec, WritableImage,
};

use crate::error::Error;
use crate::frame::Frame;
use crate::output::write_atomic;

/// Sample type of the colour channels.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ColorType {
    /// 32-bit float (default).
    #[default]
    F32,
    /// 16-bit half float (`--half`).
    F16,
}

/// Writes `frame` to `path` (atomically: a temporary file renamed into place).
/// The frame's planes become the channels as they are (the colour planes
/// converted for [`ColorType::F16`]), so writing needs no second copy of the
/// image.
///
/// Channels: `R`, `G`, `B`, `A` (f32 or f16), `Z` (f32 distance along the
/// ray, `+∞` on a miss), `N.X`, `N.Y`, `N.Z` (f32 world-space normal facing
/// the camera, 0 on a miss), `id.block`, `id.object` (u32, 1-based, 0 on a miss);
/// under adaptive sampling also `spp` (u32, the samples each pixel took) and
/// `error` (f32, the estimated relative standard error of its mean luminance).
///
/// A colour-only frame ([`Options::colour_only`](crate::frame::Options),
/// whose AOV planes are empty) is written with `R G B A` alone. A frame
/// whose planes do not all hold `width * height` samples otherwise (one
/// built by hand) is an [`Error::Encode`], and nothing is written.
pub fn write_exr(frame: Frame, path: &Path, color: ColorType) -> Result<(), Error> {
    let size = (frame.width as usize, frame.height as usize);
    let n = size.0 * size.1;
    let lengths = frame.plane_lengths();
    let colour_only = n > 0 && lengths[4..].iter().all(|&l| l == 0);
    if lengths.iter().enumerate().any(|(i, &l)| l != if colour_only && i >= 4 { 0 } else { n }) {
        let message = format!(
            "the frame is {}x{}, so every plane needs {n} samples; the planes (R G B A Z N.X N.Y N.Z id.block id.object) hold {lengths:?}",
            size.0, size.1
        );
        return Err(Error::Encode { path: path.to_path_buf(), message });
    }
    let adaptive = frame.has_adaptive();
    let Frame { rgb: [r, g, b], alpha, depth, normal: [nx, ny, nz], block, object, spp, error, .. } = frame;
    let colour = |plane: Vec<f32>| -> FlatSamples {
        match color {
            ColorType::F32 => FlatSamples::F32(plane),
            ColorType::F16 => FlatSamples::F16(plane.into_iter().map(f16::from_f32).collect()),
        }
    };
    let mut list: SmallVec<[AnyChannel<FlatSamples>; 4]> = SmallVec::new();
    list.push(AnyChannel::new("R", colour(r)));
    list.push(AnyChannel::new("G", colour(g)));
    list.push(AnyChannel::new("B", colour(b)));
    list.push(AnyChannel::new("A", colour(alpha)));
    if !colour_only {
        list.push(AnyChannel::new("Z", FlatSamples::F32(depth)));
        list.push(AnyChannel::new("N.X", FlatSamples::F32(nx)));
        list.push(AnyChannel::new("N.Y", FlatSamples::F32(ny)));
        list.push(AnyChannel::new("N.Z", FlatSamples::F32(nz)));
        list.push(AnyChannel::new("id.block", FlatSamples::U32(block)));
        list.push(AnyChannel::new("id.object", FlatSamples::U32(object)));
    }
    if adaptive {
        list.push(AnyChannel::new("spp", FlatSamples::U32(spp)));
        list.push(AnyChannel::new("error", FlatSamples::F32(error)));
    }
    let encoding =
        Encoding { compression: Compression::ZIP16, blocks: Blocks::ScanLines, line_order: LineOrder::Increasing };
    let layer = Layer::new(size, LayerAttributes::default(), encoding, AnyChannels::sort(list));
    let image = Image::from_layer(layer);
    write_atomic(path, |w| image.write().to_buffered(w).map_err(|e| e.to_string()))
}

/// Writes `channels`, each `width * height` u32 samples in rows from the
/// top, as one part with the render's layout (scanlines, ZIP compression),
/// atomically: the id maps of `komplex slice`. Channels of the wrong length
/// are an [`Error::Encode`], and nothing is written.
pub fn write_u32_channels(
    path: &Path,
    (width, height): (u32, u32),
    channels: Vec<(&str, Vec<u32>)>,
) -> Result<(), Error> {
    let size = (width as usize, height as usize);
    if let Some((name, c)) = channels.iter().find(|(_, c)| c.len() != size.0 * size.1) {
        let message = format!("channel {name} holds {} samples, not {}x{}", c.len(), size.0, size.1);
        return Err(Error::Encode { path: path.to_path_buf(), message });
    }
    let list: SmallVec<[AnyChannel<FlatSamples>; 4]> =
        channels.into_iter().map(|(name, c)| AnyChannel::new(name, FlatSamples::U32(c))).collect();
    let encoding =
        Encoding { compression: Compression::ZIP16, blocks: Blocks::ScanLines, line_order: LineOrder::Increasing };
    let layer = Layer::new(size, LayerAttributes::default(), encoding, AnyChannels::sort(list));
    let image = Image::from_layer(layer);
    write_atomic(path, |w| image.write().to_buffered(w).map_err(|e| e.to_string()))
}
