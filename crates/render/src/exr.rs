//! OpenEXR output: one part, scanlines, ZIP compression, with the channels
//! compositing tools expect (`R G B A Z N.X N.Y N.Z id.block id.object`).

use std::path::Path;

use exr::prelude::{
    f16, AnyChannel, AnyChannels, Blocks, Compression, Encoding, FlatSamples, Image, Layer, LayerAttributes, LineOrder,
    SmallVec, WritableImage,
};

use crate::frame::Frame;
use crate::output::write_atomic;
use crate::Error;

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
///
/// Channels: `R`, `G`, `B`, `A` (f32 or f16), `Z` (f32 distance along the
/// ray, `+∞` on a miss), `N.X`, `N.Y`, `N.Z` (f32 world-space normal facing
/// the camera, 0 on a miss), `id.block`, `id.object` (u32, 1-based, 0 on a miss).
pub fn write_exr(frame: &Frame, path: &Path, color: ColorType) -> Result<(), Error> {
    let px = &frame.pixels;
    let colour = |f: &dyn Fn(&crate::frame::Pixel) -> f32| -> FlatSamples {
        match color {
            ColorType::F32 => FlatSamples::F32(px.iter().map(f).collect()),
            ColorType::F16 => FlatSamples::F16(px.iter().map(|p| f16::from_f32(f(p))).collect()),
        }
    };
    let f32s = |f: &dyn Fn(&crate::frame::Pixel) -> f32| FlatSamples::F32(px.iter().map(f).collect());
    let u32s = |f: &dyn Fn(&crate::frame::Pixel) -> u32| FlatSamples::U32(px.iter().map(f).collect());
    let mut list: SmallVec<[AnyChannel<FlatSamples>; 4]> = SmallVec::new();
    list.push(AnyChannel::new("R", colour(&|p| p.rgb[0])));
    list.push(AnyChannel::new("G", colour(&|p| p.rgb[1])));
    list.push(AnyChannel::new("B", colour(&|p| p.rgb[2])));
    list.push(AnyChannel::new("A", colour(&|p| p.alpha)));
    list.push(AnyChannel::new("Z", f32s(&|p| p.depth)));
    list.push(AnyChannel::new("N.X", f32s(&|p| p.normal[0])));
    list.push(AnyChannel::new("N.Y", f32s(&|p| p.normal[1])));
    list.push(AnyChannel::new("N.Z", f32s(&|p| p.normal[2])));
    list.push(AnyChannel::new("id.block", u32s(&|p| p.block)));
    list.push(AnyChannel::new("id.object", u32s(&|p| p.object)));
    let encoding =
        Encoding { compression: Compression::ZIP16, blocks: Blocks::ScanLines, line_order: LineOrder::Increasing };
    let size = (frame.width as usize, frame.height as usize);
    let layer = Layer::new(size, LayerAttributes::default(), encoding, AnyChannels::sort(list));
    let image = Image::from_layer(layer);
    write_atomic(path, |w| image.write().to_buffered(w).map_err(|e| e.to_string()))
}
