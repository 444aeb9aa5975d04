//! Tiles: a render split into bands of whole rows (`komplex render --tile
//! I/N`), each written as an OpenEXR file whose data window is its band and
//! whose header names its render, and the merge of such parts into the
//! whole image (`komplex merge`), equal channel for channel to the render
//! in one process (docs/cli.md, "Tiles").
//!
//! A part's pixels are the whole image's: the sampler keys a pixel by its
//! place in the whole image (`i · width + j`), so a band renders exactly the
//! pixels the whole render gives those rows.

use std::collections::BTreeMap;
use std::fmt;
use std::path::{Path, PathBuf};

use exr::block::chunk::CompressedBlock;
use exr::block::writer::ChunksWriter;
use exr::meta::attribute::{AttributeValue, SampleType, Text};
use exr::meta::header::Header;
use exr::meta::{compute_chunk_count, BlockDescription, Headers, MetaData};
use exr::prelude::{AnyChannels, Compression, FlatSamples, Image, Layer, ReadChannels, ReadLayers, Vec2};

use crate::error::Error;
use crate::exr::{write_frame, ColorType};
use crate::frame::Frame;
use crate::output::write_atomic;
use crate::sampling::{mix, GOLDEN};
use crate::world::World;

/// The header attribute naming a part's tile, `I/N` (a text attribute of
/// its layer).
pub const TILE_ATTRIBUTE: &str = "komplex.tile";

/// The header attribute naming a part's render: its [`Fingerprint`] in hex
/// (a text attribute of the image).
pub const RENDER_ATTRIBUTE: &str = "komplex.render";

/// The environment variables `--tile auto/N` reads the index from, in this
/// order: a Slurm job array's task id, a Kubernetes Indexed Job's index.
pub const INDEX_VARIABLES: [&str; 2] = ["SLURM_ARRAY_TASK_ID", "JOB_COMPLETION_INDEX"];

/// Part `index` (0-based) of `count`: the band of rows
/// `⌊index·H/count⌋ .. ⌊(index+1)·H/count⌋` of an image `H` rows high.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub struct Tile {
    /// 0-based, below `count`.
    pub index: u32,
    /// The number of parts, at least 1.
    pub count: u32,
}

impl fmt::Display for Tile {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl Tile {
    /// Reads `--tile I/N` or `--tile auto/N`, whose index comes from the
    /// first of [`INDEX_VARIABLES`] that `var` finds set (non-empty).
    /// Errors name the option and, for `auto`, the variables.
    pub fn parse(text: &str, var: impl Fn(&str) -> Option<String>) -> Result<Tile, Error> {
        let malformed = || {
            Error::Options(format!(
                "--tile {text:?}: expected I/N (part I of N, 0-based, e.g. 2/4) or auto/N, with whole numbers"
            ))
        };
        let (index, count) = text.split_once('/').ok_or_else(malformed)?;
        let count: u32 = whole(count).ok_or_else(malformed)?;
        if count == 0 {
            return Err(Error::Options(format!("--tile {text}: the number of parts must be at least 1")));
        }
        let index = if index == "auto" {
            let found = INDEX_VARIABLES.iter().find_map(|&name| var(name).filter(|v| !v.is_empty()).map(|v| (name, v)));
            let [first, second] = INDEX_VARIABLES;
            let Some((name, value)) = found else {
                return Err(Error::Options(format!(
                    "--tile {text}: neither {first} nor {second} is set, so there is no task index to render"
                )));
            };
            match whole(&value) {
                Some(i) if i < count => i,
                _ => {
                    return Err(Error::Options(format!(
                        "--tile {text}: {name} is {value:?}, not a part index from 0 to {} (the index is read from {first}, else {second})",
                        count - 1
                    )))
                }
            }
        } else {
            whole(index).ok_or_else(malformed)?
        };
        if index >= count {
            return Err(Error::Options(format!(
                "--tile {text}: the part index must be below {count} (parts are numbered from 0)"
            )));
        }
        Ok(Tile { index, count })
    }

    /// The tile's rows, `(first, end)`, in an image `height` rows high.
    pub fn rows(self, height: u32) -> (u32, u32) {
        let at = |k: u32| (u64::from(k) * u64::from(height) / u64::from(self.count)) as u32;
        (at(self.index), at(self.index + 1))
    }

    /// Checks that every part of an image `height` rows high has a row
    /// (`count ≤ height`), else an error naming the option.
    pub fn check_height(self, height: u32) -> Result<(), Error> {
        if self.count > height {
            return Err(Error::Options(format!(
                "--tile {self}: {} parts of an image {height} rows high; at most {height} (a part is a band of whole rows)",
                self.count
            )));
        }
        Ok(())
    }
}

/// A whole number in decimal digits alone (no sign, no spaces).
fn whole(text: &str) -> Option<u32> {
    if text.is_empty() || !text.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    text.parse().ok()
}

/// A 64-bit hash of labelled byte strings, shown as 16 hex digits: what
/// identifies a render, so that parts of different renders are not merged.
/// Each byte string is absorbed with its label and length, eight bytes at
/// a time through SplitMix64's output function (not cryptographic: it
/// guards against mistakes, not against forgery).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Fingerprint(u64);

impl Fingerprint {
    /// An empty fingerprint of a kind of thing (`domain`).
    pub fn new(domain: &str) -> Self {
        Fingerprint(GOLDEN).bytes("domain", domain.as_bytes())
    }

    /// Absorbs `label` and `data`.
    #[must_use]
    pub fn bytes(self, label: &str, data: &[u8]) -> Self {
        let mut h = self.0;
        for part in [label.as_bytes(), data] {
            h = absorb(h, part.len() as u64);
            for chunk in part.chunks(8) {
                let mut word = [0u8; 8];
                word[..chunk.len()].copy_from_slice(chunk);
                h = absorb(h, u64::from_le_bytes(word));
            }
        }
        Fingerprint(h)
    }

    /// The fingerprint as 16 lower-case hex digits.
    pub fn hex(self) -> String {
        format!("{:016x}", self.0)
    }
}

/// One more word into a running hash.
fn absorb(h: u64, word: u64) -> u64 {
    mix(h ^ mix(word.wrapping_add(GOLDEN)))
}

/// The fingerprint of a render: the scene file's bytes and everything the
/// command line changes that changes pixels or channels: the image size,
/// the settings as the render uses them (`samples`, `spp`, `noise`, `seed`,
/// the integrator, …), the kernel's precision mode, and `half` colour.
/// A caller with more such options (an animation frame) absorbs them too.
pub fn render_fingerprint(scene_text: &[u8], world: &World, half: bool) -> Fingerprint {
    let settings = serde_json::to_string(&world.settings).unwrap_or_default();
    let camera = &world.camera;
    Fingerprint::new("komplex render")
        .bytes("scene", scene_text)
        .bytes("size", &[camera.width().to_le_bytes(), camera.height().to_le_bytes()].concat())
        .bytes("settings", settings.as_bytes())
        .bytes("precision", format!("{:?}", world.complex.precision()).as_bytes())
        .bytes("half", &[u8::from(half)])
}

/// Writes `frame`, the rows of `tile` ([`Options::rows`](crate::frame::Options)),
/// to `path` as [`write_exr`](crate::exr::write_exr) does, but with ZIPS
/// compression (one row a block, so that [`Merge::write`] copies the
/// compressed blocks as they are, wherever the band starts) and the header
/// attributes that make it a part: [`RENDER_ATTRIBUTE`] (`render`, a
/// [`Fingerprint::hex`]) and [`TILE_ATTRIBUTE`].
pub fn write_part(frame: Frame, path: &Path, color: ColorType, tile: Tile, render: &str) -> Result<(), Error> {
    let tile = tile.to_string();
    write_frame(frame, path, color, PART_COMPRESSION, &[(RENDER_ATTRIBUTE, render)], &[(TILE_ATTRIBUTE, &tile)])
}

/// The compression of parts and of the merged image: ZIP, one row a block
/// (OpenEXR's ZIPS).
pub const PART_COMPRESSION: Compression = Compression::ZIP1;

/// What a part's header says.
#[derive(Clone, Debug, PartialEq)]
struct PartHeader {
    /// The header as read.
    header: Header,
    tile: Tile,
    render: String,
    /// The display window's size.
    image: (usize, usize),
    /// The data window: origin and size.
    data: ((i32, i32), (usize, usize)),
    /// Channel names and sample types, in the file's order.
    channels: Vec<(String, SampleType)>,
}

impl PartHeader {
    /// The header of the one-part file `path`, which must carry the
    /// attributes of a tile.
    fn read(path: &Path) -> Result<Self, Error> {
        let meta = MetaData::read_from_file(path, false).map_err(|e| read_error(path, e))?;
        let [header] = meta.headers.as_slice() else {
            return Err(data(path, format!("holds {} parts; a tile holds one", meta.headers.len())));
        };
        let text = |name: &str| match attribute(header, name) {
            Some(AttributeValue::Text(t)) => Some(t.to_string()),
            _ => None,
        };
        let Some(tile_text) = text(TILE_ATTRIBUTE) else {
            return Err(data(
                path,
                format!("not a tile of a render: the header has no {TILE_ATTRIBUTE} attribute (komplex render --tile writes it)"),
            ));
        };
        let tile = tile_text
            .split_once('/')
            .and_then(|(i, n)| Some(Tile { index: whole(i)?, count: whole(n)? }))
            .filter(|t| t.index < t.count)
            .ok_or_else(|| data(path, format!("{TILE_ATTRIBUTE} is {tile_text:?}, not I/N with I < N")))?;
        let Some(render) = text(RENDER_ATTRIBUTE) else {
            return Err(data(path, format!("tile {tile} has no {RENDER_ATTRIBUTE} attribute")));
        };
        let window = header.data_window();
        let display = header.shared_attributes.display_window;
        Ok(PartHeader {
            header: header.clone(),
            tile,
            render,
            image: (display.size.0, display.size.1),
            data: ((window.position.0, window.position.1), (window.size.0, window.size.1)),
            channels: header.channels.list.iter().map(|c| (c.name.to_string(), c.sample_type)).collect(),
        })
    }

    /// Why the part's data window is not its tile's band of the display
    /// window (or the display window does not start at the origin).
    fn window_error(&self) -> Option<String> {
        let (width, height) = self.image;
        let (first, end) = self.tile.rows(height as u32);
        let want = ((0, first as i32), (width, (end - first) as usize));
        (self.data != want).then(|| {
            let ((x, y), (w, h)) = self.data;
            format!(
                "tile {} of an image {width}x{height} is rows {first}..{end} of the full width, but the data window is {w}x{h} at ({x}, {y})",
                self.tile
            )
        })
    }

    /// Why the part's blocks of rows are not whole blocks of the image
    /// (scanline blocks of `L` rows, the first at a multiple of `L`, the
    /// last full unless it ends the image), so that they cannot be copied
    /// into it as they are. `render --tile` writes one row a block.
    fn block_error(&self) -> Option<String> {
        let h = &self.header;
        if h.blocks != BlockDescription::ScanLines || h.deep {
            return Some("its pixels are stored in tiles or deep samples, not in scanlines as a part's".into());
        }
        let lines = h.compression.scan_lines_per_block();
        let (first, end) = self.tile.rows(self.image.1 as u32);
        let whole = |row: u32| (row as usize).is_multiple_of(lines);
        (!whole(first) || !(whole(end) || end as usize == self.image.1)).then(|| {
            format!(
                "its compression ({:?}) stores {lines} rows a block, and rows {first}..{end} are not whole blocks of the image; render --tile writes one row a block",
                h.compression
            )
        })
    }
}

/// A header attribute by name, among the layer's or the image's own.
fn attribute<'h>(header: &'h Header, name: &str) -> Option<&'h AttributeValue> {
    let own = header.own_attributes.other.iter().chain(&header.shared_attributes.other);
    own.into_iter().find(|(k, _)| **k == *name).map(|(_, v)| v)
}

fn data(path: &Path, message: String) -> Error {
    Error::Data { file: path.to_path_buf(), message }
}

/// An error of the exr crate reading `path`: I/O (a missing file, exit
/// status 3) as [`Error::Io`], anything else (not an EXR, truncated) as a
/// bad input file.
fn read_error(path: &Path, e: exr::error::Error) -> Error {
    match e {
        exr::error::Error::Io(source) if source.kind() != std::io::ErrorKind::UnexpectedEof => {
            Error::Io { path: path.to_path_buf(), source }
        }
        e => data(path, format!("not a readable OpenEXR file: {e}")),
    }
}

/// A part read whole.
type PartImage = Image<Layer<AnyChannels<FlatSamples>>>;

/// Reads every channel of the one-part file `path`.
fn read_pixels(path: &Path) -> Result<PartImage, Error> {
    exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_file(path)
        .map_err(|e| read_error(path, e))
}

/// Whether `path` is already this very part: a readable one-part EXR of
/// tile `tile` of the render `render` (a [`Fingerprint::hex`]) of an image
/// `width × height`, every pixel present. `Err` says why not (the file is
/// missing, unreadable, truncated, or of another render or tile), for
/// `komplex render --resume`.
pub fn check_complete(path: &Path, tile: Tile, render: &str, (width, height): (u32, u32)) -> Result<(), String> {
    let header = PartHeader::read(path).map_err(|e| e.to_string())?;
    if header.tile != tile {
        return Err(format!("it is tile {}, not {tile}", header.tile));
    }
    if header.render != render {
        return Err("it is a tile of another render (another scene or other options)".into());
    }
    if header.image != (width as usize, height as usize) {
        return Err(format!("its image is {}x{}, not {width}x{height}", header.image.0, header.image.1));
    }
    if let Some(e) = header.window_error().or_else(|| header.block_error()) {
        return Err(e);
    }
    read_pixels(path).map(drop).map_err(|e| e.to_string())
}

/// The parts of a whole image, checked and in tile order, ready to be
/// joined ([`merge`]).
#[derive(Debug)]
pub struct Merge {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// The parts, in tile order.
    pub parts: Vec<PathBuf>,
    /// The first part's header, the model of the whole image's.
    header: Header,
}

/// Checks that the parts at `paths` (any order) are the tiles `0 .. N` of
/// one render, each once, reading their headers alone. A part that is not a
/// tile, is of another render (another fingerprint, number of parts, image
/// size, channel list or compression than the first part's), repeats a
/// tile or has a data window other than its tile's band is an error that
/// names the file; a missing tile is an error that names its index (and the
/// file name it would have beside the first part).
pub fn merge(paths: &[PathBuf]) -> Result<Merge, Error> {
    let Some(first_path) = paths.first() else {
        return Err(Error::Options("merge needs at least one part".into()));
    };
    let mut by_index: BTreeMap<u32, (&Path, PartHeader)> = BTreeMap::new();
    let mut first: Option<PartHeader> = None;
    for path in paths {
        let header = PartHeader::read(path)?;
        if let Some(f) = &first {
            let foreign = |what: String| {
                data(path, format!("a foreign part: {what}, unlike {} (the first part)", first_path.display()))
            };
            if header.tile.count != f.tile.count {
                return Err(foreign(format!(
                    "tile {} is one of {} parts, not {}",
                    header.tile, header.tile.count, f.tile.count
                )));
            }
            if header.render != f.render {
                return Err(foreign(format!(
                    "it is a tile of another render (another scene or other options: {RENDER_ATTRIBUTE} {}, not {})",
                    header.render, f.render
                )));
            }
            if header.image != f.image {
                return Err(foreign(format!(
                    "its image is {}x{}, not {}x{}",
                    header.image.0, header.image.1, f.image.0, f.image.1
                )));
            }
            if header.channels != f.channels {
                let names = |c: &[(String, SampleType)]| {
                    c.iter().map(|(n, t)| format!("{n} {t:?}")).collect::<Vec<_>>().join(", ")
                };
                return Err(foreign(format!(
                    "its channels are [{}], not [{}]",
                    names(&header.channels),
                    names(&f.channels)
                )));
            }
            let layout = |h: &Header| (h.compression, h.blocks);
            if layout(&header.header) != layout(&f.header) {
                return Err(foreign(format!(
                    "its compression is {:?}, not {:?}",
                    header.header.compression, f.header.compression
                )));
            }
        } else {
            first = Some(header.clone());
        }
        if let Some(e) = header.window_error() {
            return Err(data(path, e));
        }
        if let Some(e) = header.block_error() {
            return Err(data(path, e));
        }
        if let Some((other, _)) = by_index.get(&header.tile.index) {
            return Err(data(path, format!("tile {} again: {} holds it too", header.tile, other.display())));
        }
        by_index.insert(header.tile.index, (path, header));
    }
    let Some(first) = first else { return Err(Error::Options("merge needs at least one part".into())) };
    let count = first.tile.count;
    let missing: Vec<u32> = (0..count).filter(|i| !by_index.contains_key(i)).collect();
    if let Some(&i) = missing.first() {
        let all = missing.iter().map(u32::to_string).collect::<Vec<_>>().join(", ");
        let which = if missing.len() == 1 {
            format!("tile {i}/{count} is missing")
        } else {
            format!("tiles {all} of {count} are missing")
        };
        let expected = expected_name(first_path, Tile { index: i, count }, first.tile)
            .map(|p| format!(" (tile {i} would be {})", p.display()))
            .unwrap_or_default();
        let given = paths.len();
        return Err(Error::Options(format!("{which}: none of the {given} parts given holds it{expected}")));
    }
    let (width, height) = first.image;
    let parts = by_index.values().map(|(p, _)| p.to_path_buf()).collect();
    Ok(Merge { width: width as u32, height: height as u32, parts, header: first.header })
}

/// The file name tile `want` would have beside `path`, a part named as
/// `render --tile` names tile `have` (`….tile-I-of-N.ext`), if it is.
fn expected_name(path: &Path, want: Tile, have: Tile) -> Option<PathBuf> {
    let name = path.file_name()?.to_str()?;
    let tag = format!(".tile-{}-of-{}", have.index, have.count);
    let at = name.rfind(&tag)?;
    let renamed = format!("{}.tile-{}-of-{}{}", &name[..at], want.index, want.count, &name[at + tag.len()..]);
    Some(path.with_file_name(renamed))
}

impl Merge {
    /// Writes the whole image to `path`, atomically: the first part's
    /// header with the whole image as its data window and no tile
    /// attributes, then every part's blocks of rows as they are, not
    /// decompressed (the parts' blocks are whole blocks of the image:
    /// [`PartHeader::block_error`]). A part that cannot be read to its end
    /// (truncated) is an error that names it, and nothing is written.
    pub fn write(&self, path: &Path) -> Result<(), Error> {
        let mut header = self.header.clone();
        header.own_attributes.layer_position = Vec2(0, 0);
        header.layer_size = Vec2(self.width as usize, self.height as usize);
        header.chunk_count = compute_chunk_count(header.compression, header.layer_size, header.blocks);
        let ours = |name: &Text| name.to_string().starts_with("komplex.");
        header.own_attributes.other.retain(|name, _| !ours(name));
        header.shared_attributes.other.retain(|name, _| !ours(name));
        let lines = header.compression.scan_lines_per_block();
        // An error reading a part, kept to name the part (the writer's own
        // errors name the output).
        let mut failed: Option<Error> = None;
        let (count, height) = (self.parts.len() as u32, self.height);
        let written = write_atomic(path, |w| {
            let headers: Headers = std::iter::once(header).collect();
            exr::block::write(w, headers, true, |_, writer| {
                for (index, part) in (0..count).zip(&self.parts) {
                    let rows = Tile { index, count }.rows(height);
                    if let Err(e) = copy_blocks(part, rows, lines, writer) {
                        let message = e.to_string();
                        failed = Some(e);
                        return Err(exr::error::Error::Invalid(message.into()));
                    }
                }
                Ok(())
            })
            .map_err(|e| e.to_string())
        });
        match failed {
            Some(e) => Err(e),
            None => written,
        }
    }

    /// The red, green and blue channels of the whole image as `f32`
    /// (decompressed from every part), for the preview.
    pub fn rgb(&self) -> Result<[Vec<f32>; 3], Error> {
        let n = self.width as usize * self.height as usize;
        let mut rgb: [Vec<f32>; 3] = std::array::from_fn(|_| Vec::with_capacity(n));
        for part in &self.parts {
            let channels = read_pixels(part)?.layer_data.channel_data.list;
            for (plane, name) in rgb.iter_mut().zip(["R", "G", "B"]) {
                match channels.iter().find(|c| c.name == *name).map(|c| &c.sample_data) {
                    Some(FlatSamples::F32(v)) => plane.extend_from_slice(v),
                    Some(FlatSamples::F16(v)) => plane.extend(v.iter().map(|x| x.to_f32())),
                    // Absent, or integers.
                    _ => return Err(Error::Options("--png: the parts have no R, G and B channels".into())),
                }
            }
        }
        Ok(rgb)
    }
}

/// Writes every block of rows of the part at `path`, whose rows are
/// `rows`, to `writer`, at its place in the whole image (`lines` rows a
/// block).
fn copy_blocks(path: &Path, rows: (u32, u32), lines: usize, writer: &mut impl ChunksWriter) -> Result<(), Error> {
    let unreadable = |what: String| data(path, format!("not a readable OpenEXR file: {what}"));
    let file = std::fs::File::open(path).map_err(|source| Error::Io { path: path.to_path_buf(), source })?;
    let chunks = exr::block::read(std::io::BufReader::new(file), false)
        .and_then(|r| r.all_chunks(false))
        .map_err(|e| read_error(path, e))?;
    for chunk in chunks {
        let chunk = chunk.map_err(|e| read_error(path, e))?;
        let CompressedBlock::ScanLine(block) = &chunk.compressed_block else {
            return Err(unreadable("a block that is not of scanlines".into()));
        };
        let y = block.y_coordinate;
        if !(i64::from(rows.0)..i64::from(rows.1)).contains(&i64::from(y)) {
            return Err(unreadable(format!("a block at row {y}, outside rows {}..{}", rows.0, rows.1)));
        }
        writer.write_chunk(y as usize / lines, chunk).map_err(|e| unreadable(e.to_string()))?;
    }
    Ok(())
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    /// The bands of `N` parts cover rows `0 .. H` in order, each non-empty,
    /// for every `N ≤ H` up to 64 rows.
    #[test]
    fn the_bands_tile_the_image_in_order_and_none_is_empty() {
        for height in 1..=64u32 {
            for count in 1..=height {
                let mut next = 0;
                for index in 0..count {
                    let (first, end) = Tile { index, count }.rows(height);
                    assert_eq!(first, next, "{index}/{count} of {height}");
                    assert!(end > first, "{index}/{count} of {height} is empty");
                    next = end;
                }
                assert_eq!(next, height);
                assert!(Tile { index: 0, count }.check_height(height).is_ok());
            }
            assert!(Tile { index: 0, count: height + 1 }.check_height(height).is_err());
        }
    }

    fn parse(text: &str, env: &[(&str, &str)]) -> Result<Tile, String> {
        Tile::parse(text, |name| env.iter().find(|(n, _)| *n == name).map(|(_, v)| v.to_string()))
            .map_err(|e| e.to_string())
    }

    #[test]
    fn tile_specs_parse_as_documented() {
        let tile = |index, count| Ok(Tile { index, count });
        assert_eq!(parse("2/4", &[]), tile(2, 4));
        assert_eq!(parse("0/1", &[]), tile(0, 1));
        assert_eq!(parse("auto/4", &[("SLURM_ARRAY_TASK_ID", "3")]), tile(3, 4));
        assert_eq!(parse("auto/4", &[("JOB_COMPLETION_INDEX", "1")]), tile(1, 4));
        // Slurm's first; an empty variable counts as unset.
        assert_eq!(parse("auto/4", &[("SLURM_ARRAY_TASK_ID", "0"), ("JOB_COMPLETION_INDEX", "2")]), tile(0, 4));
        assert_eq!(parse("auto/4", &[("SLURM_ARRAY_TASK_ID", ""), ("JOB_COMPLETION_INDEX", "2")]), tile(2, 4));
        for bad in ["", "2", "2/", "/4", "-1/4", "+1/4", " 1/4", "1/4/2", "a/4", "1/x", "1.0/4", "99999999999/4"] {
            assert!(parse(bad, &[]).unwrap_err().contains("expected I/N"), "{bad:?}");
        }
        assert!(parse("4/4", &[]).unwrap_err().contains("must be below 4"));
        assert!(parse("0/0", &[]).unwrap_err().contains("at least 1"));
        assert!(parse("auto/4", &[]).unwrap_err().contains("neither SLURM_ARRAY_TASK_ID nor JOB_COMPLETION_INDEX"));
        for v in ["4", "-1", "x", "1.5"] {
            assert!(parse("auto/4", &[("JOB_COMPLETION_INDEX", v)]).unwrap_err().contains("not a part index"), "{v}");
        }
    }

    /// The fingerprint changes with every labelled part, and with where a
    /// byte string ends (its length is absorbed too).
    #[test]
    fn fingerprints_tell_inputs_apart() {
        let f = |parts: &[(&str, &[u8])]| parts.iter().fold(Fingerprint::new("t"), |f, (l, d)| f.bytes(l, d)).hex();
        let base = f(&[("a", b"12345678x"), ("b", b"")]);
        assert_eq!(base.len(), 16);
        assert_eq!(base, f(&[("a", b"12345678x"), ("b", b"")]));
        for other in [
            f(&[("a", b"12345678y"), ("b", b"")]),
            f(&[("a", b"12345678x\0"), ("b", b"")]),
            f(&[("a", b"12345678"), ("b", b"x")]),
            f(&[("c", b"12345678x"), ("b", b"")]),
            f(&[("a", b"12345678x")]),
        ] {
            assert_ne!(base, other);
        }
    }

    /// A band of rows holds exactly the whole frame's rows, for the Whitted
    /// grid and for the path integrator's random samples, from odd rows too.
    #[test]
    fn a_band_renders_the_whole_frames_rows() {
        for settings in [r#"{ "samples": 2 }"#, r#"{ "integrator": "path", "spp": 3 }"#] {
            let json = format!(
                r#"{{ "camera": {{ "eye": [0, 0, 5], "direction": [0, 0, -1], "width": 9, "height": 23 }},
                    "settings": {settings}, "lights": [ {{ "position": [2, 2, 5] }} ],
                    "materials": {{ "lamp": {{ "emission": [1, 1, 1] }} }},
                    "blocks": [ {{ "objects": [ {{ "sphere": {{}} }} ] }},
                                {{ "material": "lamp", "objects": [ {{ "sphere": {{ "radius": 0.5 }}, "transform": [ {{ "translate": [1, 1, 1] }} ] }} ] }} ] }}"#
            );
            let world = crate::format::SceneFile::from_json(&json).unwrap().to_world().unwrap();
            let render =
                |rows| crate::frame::render(&world, crate::frame::Options { rows, ..Default::default() }, &|| {});
            let (whole, _) = render(None).unwrap();
            for (first, end) in [(0, 23), (3, 4), (5, 18), (17, 23)] {
                let (band, _) = render(Some((first, end))).unwrap();
                assert_eq!((band.first_row, band.height, band.image_height), (first, end - first, 23));
                for i in first..end {
                    for j in 0..9 {
                        assert_eq!(band.at(i - first, j), whole.at(i, j), "{settings} row {i} column {j}");
                    }
                }
            }
            for bad in [(3, 3), (5, 2), (0, 24)] {
                assert!(render(Some(bad)).is_err(), "{bad:?}");
            }
        }
    }
}
