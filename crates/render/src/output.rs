//! Atomic file output: write a temporary file beside the target, then
//! rename it over the target, so a failed or interrupted write never leaves
//! a partial file or clobbers an existing one.

use std::ffi::OsString;
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

use crate::error::Error;

/// The directory a file at `path` goes into.
fn directory(path: &Path) -> &Path {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    }
}

/// A temporary file beside `path`. Errors name `path` and the directory,
/// without the temporary file's random name.
fn temporary(path: &Path) -> Result<tempfile::NamedTempFile, Error> {
    let dir = directory(path);
    tempfile::Builder::new().prefix(".komplex-").suffix(".tmp").tempfile_in(dir).map_err(|e| {
        // tempfile appends ` at path "<random temporary name>"`, which means nothing to the user.
        let text = e.to_string();
        let cause = text.rfind(" at path ").map_or(text.as_str(), |i| &text[..i]);
        let source =
            std::io::Error::new(e.kind(), format!("cannot create a file in directory {}: {cause}", dir.display()));
        Error::Io { path: path.to_path_buf(), source }
    })
}

/// Checks, before a long render, that `path` can be written: it is not a
/// directory and a file can be created beside it (the probe is removed at
/// once). A failure here costs nothing; after the render it would waste it.
pub fn check_writable(path: &Path) -> Result<(), Error> {
    if path.is_dir() {
        let source = std::io::Error::other("is a directory, not a file");
        return Err(Error::Io { path: path.to_path_buf(), source });
    }
    // Renaming over a device or pipe (`-o /dev/null`) would replace the
    // special file itself, not write to it.
    if path.exists() && !path.is_file() {
        let source = std::io::Error::other("is not a regular file (a device, pipe or socket); only files are replaced");
        return Err(Error::Io { path: path.to_path_buf(), source });
    }
    temporary(path).map(drop)
}

/// Writes `path` through `write`, atomically: `write` fills a buffered
/// temporary file beside `path`, which is renamed over `path` only once
/// `write` and the flush to disk have succeeded. On any error the temporary
/// file is removed and `path` is left as it was; an error `write` returns
/// is an [`Error::Encode`] with its message. A `path` that exists but is not
/// a regular file (a directory, device or pipe) is refused, as
/// [`check_writable`] refuses it.
pub fn write_atomic(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<&mut File>) -> Result<(), String>,
) -> Result<(), Error> {
    let io = |source| Error::Io { path: path.to_path_buf(), source };
    if path.exists() && !path.is_file() {
        return check_writable(path);
    }
    let mut tmp = temporary(path)?;
    {
        let mut buffered = BufWriter::new(tmp.as_file_mut());
        write(&mut buffered).map_err(|message| Error::Encode { path: path.to_path_buf(), message })?;
        buffered.into_inner().map_err(|e| io(e.into_error()))?;
    }
    // Temporary files are private (0600); give the result the permissions
    // of the file it replaces, or ordinary ones (0644) for a new file.
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        let perms =
            std::fs::metadata(path).map(|m| m.permissions()).unwrap_or_else(|_| std::fs::Permissions::from_mode(0o644));
        tmp.as_file().set_permissions(perms).map_err(io)?;
    }
    tmp.as_file().sync_all().map_err(io)?;
    // On error the temporary file is removed when `tmp` drops.
    tmp.persist(path).map_err(|e| io(e.error))?;
    Ok(())
}

/// The file of one part of a job: `path` with the frame number, four
/// digits at least (`.0007`), and the tile (`.tile-2-of-4`) inserted before
/// the extension: `out/walk.exr`, frame 7, tile 2 of 4 is
/// `out/walk.0007.tile-2-of-4.exr`. Without either, `path` itself; without
/// an extension the tags go at the end.
///
/// ```
/// use std::path::Path;
/// use render::output::part_path;
/// assert_eq!(part_path(Path::new("out/walk.exr"), Some(7), None), Path::new("out/walk.0007.exr"));
/// assert_eq!(part_path(Path::new("walk.exr"), Some(7), Some((2, 4))), Path::new("walk.0007.tile-2-of-4.exr"));
/// ```
pub fn part_path(path: &Path, frame: Option<u32>, tile: Option<(u32, u32)>) -> PathBuf {
    let mut tags = String::new();
    if let Some(k) = frame {
        tags.push_str(&format!(".{k:04}"));
    }
    if let Some((i, n)) = tile {
        tags.push_str(&format!(".tile-{i}-of-{n}"));
    }
    let (Some(stem), false) = (path.file_stem(), tags.is_empty()) else {
        return path.to_path_buf();
    };
    // Built from the stem and extension as they are (not necessarily UTF-8).
    let mut name = OsString::from(stem);
    name.push(&tags);
    if let Some(ext) = path.extension() {
        name.push(".");
        name.push(ext);
    }
    path.with_file_name(name)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn part_paths_insert_the_frame_and_tile_before_the_extension() {
        for (path, frame, tile, want) in [
            ("walk.exr", None, None, "walk.exr"),
            ("walk.exr", Some(0), None, "walk.0000.exr"),
            ("out/walk.exr", Some(7), None, "out/walk.0007.exr"),
            ("walk.exr", Some(24), None, "walk.0024.exr"),
            ("walk.exr", Some(12345), None, "walk.12345.exr"),
            ("walk.exr", Some(u32::MAX), None, "walk.4294967295.exr"),
            ("walk.exr", None, Some((2, 4)), "walk.tile-2-of-4.exr"),
            ("walk.exr", Some(7), Some((0, 16)), "walk.0007.tile-0-of-16.exr"),
            ("a.b/walk.v2.exr", Some(3), None, "a.b/walk.v2.0003.exr"),
            ("walk", Some(3), None, "walk.0003"),
            ("/tmp/.walk", Some(3), None, "/tmp/.walk.0003"),
            ("walk.png", Some(3), None, "walk.0003.png"),
        ] {
            assert_eq!(part_path(Path::new(path), frame, tile), Path::new(want), "{path} {frame:?} {tile:?}");
        }
    }
}
