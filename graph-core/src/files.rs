//! Reading the files a user names: only regular files (a device such as
//! /dev/zero or a FIFO never ends, and reading one would exhaust memory or
//! hang) and, when read whole, only up to a size.

use std::cell::RefCell;
use std::io::{Error, ErrorKind, Read};
use std::path::{Path, PathBuf};

thread_local! {
    /// The files read on this thread while [`reading`] runs.
    static READ: RefCell<Option<Vec<PathBuf>>> = const { RefCell::new(None) };
}

/// Runs `f` and returns, with its result, the files it read on this thread
/// ([`read_text`] and those [`note_read`] names: the graph, its subsystem
/// files, data files) in the order first read, each once — what an FMU
/// must carry for the graph to load again elsewhere. Loading and compiling
/// a graph read on the calling thread.
pub fn reading<T>(f: impl FnOnce() -> T) -> (T, Vec<PathBuf>) {
    let outer = READ.with(|r| r.borrow_mut().replace(Vec::new()));
    let value = f();
    let files = READ.with(|r| std::mem::replace(&mut *r.borrow_mut(), outer)).unwrap_or_default();
    (value, files)
}

/// Records that `path` was read, for [`reading`].
pub fn note_read(path: &Path) {
    READ.with(|r| {
        if let Some(files) = r.borrow_mut().as_mut()
            && !files.iter().any(|f| f == path)
        {
            files.push(path.to_path_buf());
        }
    });
}

/// The largest graph file read (a million blocks in flow style are about
/// 50 MiB).
pub const MAX_GRAPH_FILE: u64 = 512 << 20;

/// The cache folder a program set for itself ([`set_cache_base`]).
static CACHE_BASE: std::sync::RwLock<Option<PathBuf>> = std::sync::RwLock::new(None);

/// Sets this process's cache folder, over the environment: for a program
/// (or a test) that must not change its environment while threads run.
pub fn set_cache_base(dir: PathBuf) {
    if let Ok(mut base) = CACHE_BASE.write() {
        *base = Some(dir);
    }
}

/// ctlgraph's cache folder: the one [`set_cache_base`] set, else
/// `$CTLGRAPH_CACHE_DIR`, else `$XDG_CACHE_HOME/ctlgraph`, else
/// `~/.cache/ctlgraph` — the libraries ctlgraph builds, and the FMUs the
/// `fmu` block unpacks.
pub fn cache_base() -> Result<PathBuf, String> {
    if let Some(dir) = CACHE_BASE.read().ok().and_then(|b| b.clone()) {
        return Ok(dir);
    }
    let var = |name: &str| std::env::var_os(name).filter(|v| !v.is_empty()).map(PathBuf::from);
    var("CTLGRAPH_CACHE_DIR")
        .or_else(|| var("XDG_CACHE_HOME").map(|d| d.join("ctlgraph")))
        .or_else(|| var("HOME").map(|d| d.join(".cache").join("ctlgraph")))
        .ok_or_else(|| "no cache folder: set CTLGRAPH_CACHE_DIR (or XDG_CACHE_HOME or HOME)".to_string())
}

/// The size of `path`, an error unless it is a regular file.
pub fn regular_file(path: &Path) -> std::io::Result<u64> {
    let meta = std::fs::metadata(path)?;
    if !meta.is_file() {
        return Err(Error::new(ErrorKind::InvalidInput, "not a regular file (a device, FIFO or folder)"));
    }
    Ok(meta.len())
}

/// The text of the regular file `path`, refused above `limit` bytes (also
/// when it grows past it while being read).
pub fn read_text(path: &Path, limit: u64) -> std::io::Result<String> {
    let too_large = || Error::new(ErrorKind::InvalidData, format!("larger than {} MiB", limit >> 20));
    if regular_file(path)? > limit {
        return Err(too_large());
    }
    let mut text = String::new();
    std::fs::File::open(path)?.take(limit + 1).read_to_string(&mut text)?;
    if text.len() as u64 > limit {
        return Err(too_large());
    }
    note_read(path);
    Ok(text)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reading_names_each_file_read_once_in_order() {
        let dir = std::env::temp_dir().join(format!("ctlgraph-reading-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let (a, b) = (dir.join("a.yaml"), dir.join("b.csv"));
        std::fs::write(&a, "x").unwrap();
        std::fs::write(&b, "y").unwrap();
        note_read(&b); // outside `reading`: not recorded anywhere
        let ((), files) = reading(|| {
            read_text(&a, 10).unwrap();
            note_read(&b);
            read_text(&a, 10).unwrap();
            assert!(read_text(&dir.join("missing"), 10).is_err());
        });
        assert_eq!(files, vec![a.clone(), b.clone()]);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn devices_folders_and_large_files_are_refused() {
        assert!(
            read_text(Path::new("/dev/zero"), MAX_GRAPH_FILE).unwrap_err().to_string().contains("not a regular file")
        );
        assert!(read_text(Path::new("."), MAX_GRAPH_FILE).unwrap_err().to_string().contains("not a regular file"));
        let dir = std::env::temp_dir().join(format!("ctlgraph-files-{}", std::process::id()));
        std::fs::write(&dir, "x".repeat(3 << 20)).unwrap();
        assert_eq!(read_text(&dir, 4 << 20).unwrap().len(), 3 << 20);
        assert_eq!(read_text(&dir, 2 << 20).unwrap_err().to_string(), "larger than 2 MiB");
        std::fs::remove_file(&dir).unwrap();
    }
}
