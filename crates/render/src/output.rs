//! Atomic file output: write a temporary file beside the target, then
//! rename it over the target, so a failed or interrupted write never leaves
//! a partial file or clobbers an existing one.

use std::fs::File;
use std::io::BufWriter;
use std::path::Path;

use crate::Error;

/// Writes `path` through `write`, atomically.
pub(crate) fn write_atomic(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<&mut File>) -> Result<(), String>,
) -> Result<(), Error> {
    let io = |source| Error::Io { path: path.to_path_buf(), source };
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let mut tmp = tempfile::Builder::new().prefix(".komplex-").suffix(".tmp").tempfile_in(dir).map_err(io)?;
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
