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

/// The file a part of a render goes to: `path` with `.FFFF` (the frame,
/// four digits or more) and `.tile-I-of-N` (tile `I` of `N`, 0-based)
/// inserted before its extension, in that order: `out/img.exr` with frame
/// 7 and tile 2 of 4 is `out/img.0007.tile-2-of-4.exr`; without either it
/// is `path` itself. A name without an extension gets them at its end.
///
/// ```
/// use std::path::Path;
/// use render::output::part_path;
/// assert_eq!(part_path(Path::new("out/img.exr"), None, Some((2, 4))), Path::new("out/img.tile-2-of-4.exr"));
/// assert_eq!(part_path(Path::new("img.exr"), Some(7), Some((0, 3))), Path::new("img.0007.tile-0-of-3.exr"));
/// assert_eq!(part_path(Path::new("img"), None, Some((1, 2))), Path::new("img.tile-1-of-2"));
/// ```
pub fn part_path(path: &Path, frame: Option<u32>, tile: Option<(u32, u32)>) -> PathBuf {
    let mut insert = String::new();
    if let Some(k) = frame {
        insert.push_str(&format!(".{k:04}"));
    }
    if let Some((i, n)) = tile {
        insert.push_str(&format!(".tile-{i}-of-{n}"));
    }
    if insert.is_empty() {
        return path.to_path_buf();
    }
    let Some(name) = path.file_name() else { return path.to_path_buf() };
    let name = Path::new(name);
    let mut file: OsString = name.file_stem().unwrap_or(name.as_os_str()).to_os_string();
    file.push(insert);
    if let Some(ext) = name.extension() {
        file.push(".");
        file.push(ext);
    }
    path.with_file_name(file)
}
