//! Reading the files a user names: only regular files (a device such as
//! /dev/zero or a FIFO never ends, and reading one would exhaust memory or
//! hang) and, when read whole, only up to a size.

use std::io::{Error, ErrorKind, Read};
use std::path::Path;

/// The largest graph file read (a million blocks in flow style are about
/// 50 MiB).
pub const MAX_GRAPH_FILE: u64 = 512 << 20;

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
    Ok(text)
}

#[cfg(test)]
mod tests {
    use super::*;

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
