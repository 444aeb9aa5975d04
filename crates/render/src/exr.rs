//! OpenEXR output: one part, scanlines, ZIP compression, with the channels
//! compositing tools expect (`R G B A Z N.X N.Y N.Z id.block id.object`).

use std::path::Path;

use exr::prelude::{
    f16, AnyChannel, AnyChannels, AttributeValue, Blocks, Compression, Encoding, FlatSamples, Image, ImageAttributes,
    IntegerBounds, Layer, LayerAttributes, LineOrder, SmallVec, Text, Vec2, WritableImage,
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
///
/// A band of rows ([`Frame::first_row`], [`Frame::image_height`]) is
/// written with a data window of those rows and a display window of the
/// whole image.
pub fn write_exr(frame: Frame, path: &Path, color: ColorType) -> Result<(), Error> {
    write_frame(frame, path, color, Compression::ZIP16, &[], &[])
}

/// [`write_exr`] with another compression and text attributes in the
/// header: `image` among the attributes of the whole image, `layer` among
/// those of its one layer (the `exr` crate keeps each set in a hash map,
/// so one attribute in each gives a header whose bytes do not vary from
/// run to run).
pub(crate) fn write_frame(
    frame: Frame,
    path: &Path,
    color: ColorType,
    compression: Compression,
    image: &[(&str, &str)],
    layer: &[(&str, &str)],
) -> Result<(), Error> {
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
    if u64::from(frame.first_row) + u64::from(frame.height) > u64::from(frame.image_height) {
        let message = format!(
            "the frame holds rows {} to {} of an image {} rows high",
            frame.first_row,
            u64::from(frame.first_row) + u64::from(frame.height),
            frame.image_height
        );
        return Err(Error::Encode { path: path.to_path_buf(), message });
    }
    let adaptive = frame.has_adaptive();
    let window =
        Window { width: frame.width, first_row: frame.first_row, rows: frame.height, image_height: frame.image_height };
    let Frame { rgb: [r, g, b], alpha, depth, normal: [nx, ny, nz], block, object, spp, error, .. } = frame;
    let colour = |plane: Vec<f32>| -> FlatSamples {
        match color {
            ColorType::F32 => FlatSamples::F32(plane),
            ColorType::F16 => FlatSamples::F16(plane.into_iter().map(f16::from_f32).collect()),
        }
    };
    let mut list: Vec<(&str, FlatSamples)> =
        vec![("R", colour(r)), ("G", colour(g)), ("B", colour(b)), ("A", colour(alpha))];
    if !colour_only {
        list.push(("Z", FlatSamples::F32(depth)));
        list.push(("N.X", FlatSamples::F32(nx)));
        list.push(("N.Y", FlatSamples::F32(ny)));
        list.push(("N.Z", FlatSamples::F32(nz)));
        list.push(("id.block", FlatSamples::U32(block)));
        list.push(("id.object", FlatSamples::U32(object)));
    }
    if adaptive {
        list.push(("spp", FlatSamples::U32(spp)));
        list.push(("error", FlatSamples::F32(error)));
    }
    write_layer(path, window, compression, list, image, layer)
}

/// Where a layer's rows sit: rows `first_row .. first_row + rows`, each
/// `width` pixels, of an image `image_height` rows high.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Window {
    width: u32,
    first_row: u32,
    rows: u32,
    image_height: u32,
}

/// Writes `channels` (name, samples: `width * rows` each, rows from the
/// top) as one part with the render's layout (scanlines from the top, the
/// channels sorted by name) and `compression`, its data window the rows of
/// `window` and its display window the whole image, atomically. The caller
/// checks the lengths.
fn write_layer(
    path: &Path,
    window: Window,
    compression: Compression,
    channels: Vec<(&str, FlatSamples)>,
    image: &[(&str, &str)],
    layer: &[(&str, &str)],
) -> Result<(), Error> {
    let list: SmallVec<[AnyChannel<FlatSamples>; 4]> =
        channels.into_iter().map(|(name, c)| AnyChannel::new(name, c)).collect();
    let text = |tags: &[(&str, &str)]| {
        tags.iter().map(|&(k, v)| (Text::from(k), AttributeValue::Text(Text::from(v)))).collect()
    };
    let attributes = LayerAttributes {
        layer_position: Vec2(0, window.first_row as i32),
        other: text(layer),
        ..LayerAttributes::default()
    };
    let size = (window.width as usize, window.rows as usize);
    let encoding = Encoding { compression, ..ENCODING };
    let layer = Layer::new(size, attributes, encoding, AnyChannels::sort(list));
    let display = IntegerBounds::new(Vec2(0, 0), Vec2(window.width as usize, window.image_height as usize));
    let image = Image::new(ImageAttributes { other: text(image), ..ImageAttributes::new(display) }, layer);
    write_atomic(path, |w| image.write().to_buffered(w).map_err(|e| e.to_string()))
}

/// The layout of every image: scanlines in blocks of 16 rows, each
/// ZIP-compressed, top to bottom.
const ENCODING: Encoding =
    Encoding { compression: Compression::ZIP16, blocks: Blocks::ScanLines, line_order: LineOrder::Increasing };

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
    let layer = Layer::new(size, LayerAttributes::default(), ENCODING, AnyChannels::sort(list));
    let image = Image::from_layer(layer);
    write_atomic(path, |w| image.write().to_buffered(w).map_err(|e| e.to_string()))
}
