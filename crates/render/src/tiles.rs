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

use exr::meta::attribute::{AttributeValue, SampleType};
use exr::meta::header::Header;
use exr::meta::MetaData;
use exr::prelude::{AnyChannels, FlatSamples, Image, Layer, ReadChannels, ReadLayers};

use crate::error::Error;
use crate::exr::{write_exr_with, write_layer, ColorType, Window};
use crate::frame::Frame;
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
/// to `path` as [`write_exr`](crate::exr::write_exr) does, with the header
/// attributes that make it a part: [`RENDER_ATTRIBUTE`] (`render`, a
/// [`Fingerprint::hex`]) and [`TILE_ATTRIBUTE`].
pub fn write_part(frame: Frame, path: &Path, color: ColorType, tile: Tile, render: &str) -> Result<(), Error> {
    let tile = tile.to_string();
    write_exr_with(frame, path, color, &[(RENDER_ATTRIBUTE, render)], &[(TILE_ATTRIBUTE, &tile)])
}

/// What a part's header says.
#[derive(Clone, Debug, PartialEq)]
struct PartHeader {
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
    if let Some(e) = header.window_error() {
        return Err(e);
    }
    read_pixels(path).map(drop).map_err(|e| e.to_string())
}

/// The whole image joined from its parts, ready to write.
#[derive(Debug)]
pub struct Merged {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// The number of parts joined.
    pub parts: u32,
    /// Every channel, by name in the parts' order, `width × height`
    /// samples from the top-left.
    pub channels: Vec<(String, FlatSamples)>,
}

/// Joins the parts at `paths` (any order) into the whole image: the parts
/// must be the tiles `0 .. N` of one render, each once. A part that is not
/// a tile, is of another render (another fingerprint, number of parts,
/// image size or channel list than the first part's), repeats a tile or
/// has a data window other than its tile's band is an error that names the
/// file; a missing tile is an error that names its index (and the file
/// name it would have beside the first part). Every header is checked
/// before any pixel is read.
pub fn merge(paths: &[PathBuf]) -> Result<Merged, Error> {
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
        } else {
            first = Some(header.clone());
        }
        if let Some(e) = header.window_error() {
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
    let mut channels: Vec<(String, FlatSamples)> = Vec::new();
    for (path, _) in by_index.values() {
        let part = read_pixels(path)?.layer_data.channel_data.list;
        if channels.is_empty() {
            // The first part's samples, with room for the others'.
            let n = width * height;
            channels = part.into_iter().map(|c| (c.name.to_string(), with_capacity(c.sample_data, n))).collect();
            continue;
        }
        let kinds = |list: &mut dyn Iterator<Item = (String, SampleType)>| list.collect::<Vec<_>>();
        let have = kinds(&mut channels.iter().map(|(n, s)| (n.clone(), sample_type(s))));
        let read = kinds(&mut part.iter().map(|c| (c.name.to_string(), sample_type(&c.sample_data))));
        if read != have {
            let names =
                |c: &[(String, SampleType)]| c.iter().map(|(n, t)| format!("{n} {t:?}")).collect::<Vec<_>>().join(", ");
            return Err(data(
                path,
                format!(
                    "a foreign part: its channels are [{}], not [{}], unlike {} (the first part)",
                    names(&read),
                    names(&have),
                    first_path.display()
                ),
            ));
        }
        for ((_, out), channel) in channels.iter_mut().zip(part) {
            match (out, channel.sample_data) {
                (FlatSamples::F16(o), FlatSamples::F16(s)) => o.extend_from_slice(&s),
                (FlatSamples::F32(o), FlatSamples::F32(s)) => o.extend_from_slice(&s),
                (FlatSamples::U32(o), FlatSamples::U32(s)) => o.extend_from_slice(&s),
                // The types were compared just above.
                _ => {}
            }
        }
    }
    Ok(Merged { width: width as u32, height: height as u32, parts: count, channels })
}

/// The sample type of `samples`.
fn sample_type(samples: &FlatSamples) -> SampleType {
    match samples {
        FlatSamples::F16(_) => SampleType::F16,
        FlatSamples::F32(_) => SampleType::F32,
        FlatSamples::U32(_) => SampleType::U32,
    }
}

/// `samples` with room for `n` in all.
fn with_capacity(samples: FlatSamples, n: usize) -> FlatSamples {
    fn grown<T>(mut v: Vec<T>, n: usize) -> Vec<T> {
        v.reserve(n.saturating_sub(v.len()));
        v
    }
    match samples {
        FlatSamples::F16(v) => FlatSamples::F16(grown(v, n)),
        FlatSamples::F32(v) => FlatSamples::F32(grown(v, n)),
        FlatSamples::U32(v) => FlatSamples::U32(grown(v, n)),
    }
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

impl Merged {
    /// The red, green and blue channels as f32, if the image has them.
    pub fn rgb(&self) -> Option<[Vec<f32>; 3]> {
        let plane = |name: &str| {
            self.channels.iter().find(|(n, _)| n == name).and_then(|(_, s)| match s {
                FlatSamples::F32(v) => Some(v.clone()),
                FlatSamples::F16(v) => Some(v.iter().map(|x| x.to_f32()).collect()),
                FlatSamples::U32(_) => None,
            })
        };
        Some([plane("R")?, plane("G")?, plane("B")?])
    }

    /// Writes the image to `path` as the one-process render writes it
    /// (the same layout, no tile attributes), atomically.
    pub fn write(self, path: &Path) -> Result<(), Error> {
        let window = Window { width: self.width, first_row: 0, rows: self.height, image_height: self.height };
        let channels = self.channels.iter().map(|(n, _)| n.clone()).collect::<Vec<_>>();
        let list = channels.iter().map(String::as_str).zip(self.channels.into_iter().map(|(_, s)| s)).collect();
        write_layer(path, window, list, &[], &[])
    }
}
