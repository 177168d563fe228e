//! Unpacking an FMU (a zip archive, FMI 3.0 §2.5) into ctlgraph's cache,
//! in a folder named by a hash of its bytes: a second graph (or run) of
//! the same FMU finds it unpacked; a changed FMU gets a folder of its own.

use sha2::{Digest, Sha256};
use std::io::Read;
use std::path::{Path, PathBuf};

/// The folder holding `fmu` unpacked (unpacking it first if needed).
pub fn unpacked(fmu: &Path) -> Result<PathBuf, String> {
    let bytes = std::fs::read(fmu).map_err(|e| format!("cannot read: {e}"))?;
    ctlgraph_core::files::note_read(fmu);
    let hash: String = Sha256::digest(&bytes).iter().take(12).map(|b| format!("{b:02x}")).collect();
    let dir = ctlgraph_core::files::cache_base()?.join("fmus").join(hash);
    if dir.join("modelDescription.xml").is_file() {
        return Ok(dir);
    }
    let parent = dir.parent().ok_or("no cache folder")?;
    std::fs::create_dir_all(parent).map_err(|e| format!("cannot create {}: {e}", parent.display()))?;
    // Into a temporary folder, renamed into place: a folder in the cache is
    // always whole, also for another ctlgraph unpacking the same FMU.
    let partial = parent.join(format!(
        ".{}.{}.partial",
        dir.file_name().unwrap_or_default().to_string_lossy(),
        std::process::id()
    ));
    let result = extract(&bytes, &partial).and_then(|()| match std::fs::rename(&partial, &dir) {
        Ok(()) => Ok(()),
        // Another process unpacked it meanwhile.
        Err(_) if dir.join("modelDescription.xml").is_file() => Ok(()),
        Err(e) => Err(format!("cannot move the unpacked FMU to {}: {e}", dir.display())),
    });
    let _ = std::fs::remove_dir_all(&partial);
    result.map(|()| dir)
}

/// Writes the archive's files under `dir`; an entry whose name would
/// leave `dir` (`../`, an absolute path) is refused.
fn extract(bytes: &[u8], dir: &Path) -> Result<(), String> {
    let mut archive =
        zip::ZipArchive::new(std::io::Cursor::new(bytes)).map_err(|e| format!("not an FMU (zip archive): {e}"))?;
    for i in 0..archive.len() {
        let mut entry = archive.by_index(i).map_err(|e| format!("the archive: {e}"))?;
        let Some(name) = entry.enclosed_name() else {
            return Err(format!("the archive's entry `{}` points outside it", entry.name().unwrap_or_default()));
        };
        let path = dir.join(&name);
        if entry.is_dir() {
            std::fs::create_dir_all(&path).map_err(|e| format!("cannot create {}: {e}", path.display()))?;
            continue;
        }
        if let Some(parent) = path.parent() {
            std::fs::create_dir_all(parent).map_err(|e| format!("cannot create {}: {e}", parent.display()))?;
        }
        let mut data = Vec::new();
        entry.read_to_end(&mut data).map_err(|e| format!("the archive's `{}`: {e}", name.display()))?;
        std::fs::write(&path, data).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    }
    if !dir.join("modelDescription.xml").is_file() {
        return Err("the archive has no modelDescription.xml: not an FMU".to_string());
    }
    Ok(())
}
