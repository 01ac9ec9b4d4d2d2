//! Where a command will write, checked before its work: an output in a folder that does not
//! exist, a path that names a folder, or a file that cannot be written fails at once, not after
//! the bake.

use std::path::Path;

use crate::error::{Error, Result};

/// Refuses `path` as the place of the command's `what` (an image, a cache) where it cannot be
/// written: a folder, in a folder that does not exist, or not writable (tried by opening an
/// existing file to append, else by creating the file and removing it again).
pub fn check_writable(path: &Path, what: &str) -> Result<()> {
    let shown = path.display();
    if path.is_dir() {
        return Err(Error::Invalid(format!(
            "{shown}: names a folder; the {what} needs a file name in it"
        )));
    }
    let folder = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    if !folder.is_dir() {
        return Err(Error::Invalid(format!(
            "{shown}: the folder {} does not exist; create it first, the {what} is written \
             after the work",
            folder.display()
        )));
    }
    let tried = match path.exists() {
        true => std::fs::OpenOptions::new()
            .append(true)
            .open(path)
            .map(drop),
        false => std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(path)
            .and_then(|_| std::fs::remove_file(path)),
    };
    tried.map_err(|e| Error::Invalid(format!("{shown}: the {what} cannot be written there: {e}")))
}
