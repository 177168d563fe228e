//! Keeping the cache bounded. Every structure of a graph run with
//! `--accelerate` leaves a library in `lib/` (some 4 MB) and as much again
//! of cargo's output for it in `target/`, and a graph edited while it is
//! run (`ctlgraph watch`, a file asking for acceleration) leaves one per
//! change of structure. After each build the libraries beyond the [`KEEP`]
//! used last are removed, with their crate and cargo's output for them;
//! loading a library marks it used ([`mark_used`]). One used within
//! [`RECENT`] is never removed: another process may be about to load it.
//! ctlgraph's own crates, compiled once in `target/`, are left alone.

use std::path::Path;
use std::time::{Duration, SystemTime};

/// How many libraries the cache keeps, the ones used last.
pub const KEEP: usize = 64;
/// How long a library used is safe from removal.
pub const RECENT: Duration = Duration::from_secs(3600);

/// Marks the library at `path` used now (its modification time); a cache
/// that cannot be written is left as it is.
pub fn mark_used(path: &Path) {
    let _ = std::fs::File::options().write(true).open(path).and_then(|f| f.set_modified(SystemTime::now()));
}

/// Removes the libraries of the cache `dir` beyond the [`KEEP`] used last
/// and not used within [`RECENT`] of `now`, with what was built for them;
/// returns how many. Files in `lib/` that are not a library of a key
/// (a copy in progress, anything else) are not touched.
pub fn prune(dir: &Path, now: SystemTime) -> usize {
    let Ok(entries) = std::fs::read_dir(dir.join("lib")) else { return 0 };
    let mut libraries: Vec<(SystemTime, String)> = entries
        .flatten()
        .filter_map(|e| {
            let name = e.file_name().into_string().ok()?;
            let key = name.strip_prefix(std::env::consts::DLL_PREFIX)?.strip_suffix(std::env::consts::DLL_SUFFIX)?;
            let is_key = key.len() == 16 && key.bytes().all(|b| b.is_ascii_hexdigit());
            Some((e.metadata().ok()?.modified().ok()?, key.to_string())).filter(|_| is_key)
        })
        .collect();
    libraries.sort_by(|a, b| b.cmp(a));
    let mut removed = 0;
    for (used, key) in libraries.into_iter().skip(KEEP) {
        let recent = now.duration_since(used).map_or(true, |age| age < RECENT);
        if !recent && std::fs::remove_file(super::library_path(dir, &key)).is_ok() {
            remove_built(dir, &key);
            removed += 1;
        }
    }
    removed
}

/// What was built for the library `key`: its crate, and cargo's output
/// and fingerprints for it (a step's crate or the FMU binary's).
fn remove_built(dir: &Path, key: &str) {
    let _ = std::fs::remove_dir_all(dir.join("crates").join(key));
    let release = dir.join("target").join("release");
    let fingerprints: Vec<_> =
        std::fs::read_dir(release.join(".fingerprint")).into_iter().flatten().flatten().collect();
    for name in [format!("ctlgraph_step_{key}"), format!("ctlgraph_fmu_{key}")] {
        let library = super::dll(&name);
        let prefix = std::env::consts::DLL_PREFIX;
        for file in [
            release.join(&library),
            release.join(format!("{prefix}{name}.d")),
            release.join("deps").join(&library),
            release.join("deps").join(format!("{name}.d")),
        ] {
            let _ = std::fs::remove_file(file);
        }
        let stem = format!("{name}-");
        for f in fingerprints.iter().filter(|f| f.file_name().to_string_lossy().starts_with(&stem)) {
            let _ = std::fs::remove_dir_all(f.path());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fake library for `key` used at `when`, with a crate and cargo's
    /// output as a build leaves them.
    fn library(dir: &Path, key: &str, when: SystemTime) {
        let name = format!("ctlgraph_step_{key}");
        let release = dir.join("target/release");
        for folder in [dir.join("lib"), dir.join("crates").join(key), release.join("deps")] {
            std::fs::create_dir_all(folder).unwrap();
        }
        std::fs::create_dir_all(release.join(".fingerprint").join(format!("{name}-0123456789abcdef"))).unwrap();
        std::fs::write(dir.join("crates").join(key).join("lib.rs"), "").unwrap();
        std::fs::write(release.join("deps").join(super::super::dll(&name)), "").unwrap();
        let path = super::super::library_path(dir, key);
        std::fs::write(&path, "").unwrap();
        std::fs::File::options().write(true).open(&path).unwrap().set_modified(when).unwrap();
    }

    #[test]
    fn the_libraries_used_last_and_recently_stay_the_rest_go_with_their_builds() {
        let dir = tempfile::tempdir().unwrap();
        let dir = dir.path();
        let now = SystemTime::now();
        let hours = |h: u64| now - Duration::from_secs(3600 * h);
        // KEEP + 6 libraries used 2 to 71 hours ago, and 3 used just now.
        let keys: Vec<String> = (0..KEEP + 9).map(|i| format!("{i:016x}")).collect();
        for (i, key) in keys.iter().enumerate() {
            library(dir, key, if i < 3 { now } else { hours(i as u64 - 1) });
        }
        // Not libraries of a key: never touched.
        std::fs::write(dir.join("lib").join(".0000000000000000.42.partial"), "").unwrap();
        std::fs::write(dir.join("lib").join("notes.txt"), "").unwrap();
        assert_eq!(prune(dir, now), 9);
        for (i, key) in keys.iter().enumerate() {
            let kept = i < KEEP;
            assert_eq!(super::super::library_path(dir, key).exists(), kept, "library {i}");
            assert_eq!(dir.join("crates").join(key).exists(), kept, "crate {i}");
            let name = format!("ctlgraph_step_{key}");
            let deps = dir.join("target/release/deps").join(super::super::dll(&name));
            assert_eq!(deps.exists(), kept, "cargo's output {i}");
            let fingerprint = dir.join("target/release/.fingerprint").join(format!("{name}-0123456789abcdef"));
            assert_eq!(fingerprint.exists(), kept, "fingerprint {i}");
        }
        assert!(dir.join("lib").join(".0000000000000000.42.partial").exists() && dir.join("lib/notes.txt").exists());
        assert_eq!(prune(dir, now), 0, "nothing more to remove");
    }

    #[test]
    fn a_library_used_within_the_hour_stays_even_beyond_the_limit() {
        let dir = tempfile::tempdir().unwrap();
        let dir = dir.path();
        let now = SystemTime::now();
        for i in 0..KEEP + 5 {
            library(dir, &format!("{i:016x}"), now - Duration::from_secs(10 * i as u64));
        }
        assert_eq!(prune(dir, now), 0);
        // Two hours on, the oldest beyond the limit are no longer safe.
        assert_eq!(prune(dir, now + RECENT + Duration::from_secs(60 * 60)), 5);
    }

    #[test]
    fn loading_marks_a_library_used() {
        let dir = tempfile::tempdir().unwrap();
        let key = "00000000000000aa";
        library(dir.path(), key, SystemTime::now() - Duration::from_secs(86_400));
        let path = super::super::library_path(dir.path(), key);
        mark_used(&path);
        let age = SystemTime::now().duration_since(std::fs::metadata(&path).unwrap().modified().unwrap());
        assert!(age.as_ref().map_or(true, |a| *a < Duration::from_secs(60)), "{age:?}");
    }
}
