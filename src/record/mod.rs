//! Output files: recorded signals streamed to a CSV file that appears whole
//! or not at all, and atomic writes for plots and reports. (Recording
//! itself lives in `ctlgraph_core::trace`.)

mod number;

pub use ctlgraph_core::trace::{Recorder, Trace};
pub use number::Number;
use number::push_number;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// A CSV file written to a temporary name beside its destination and
/// renamed into place by [`CsvFile::commit`]; dropped uncommitted, it
/// leaves nothing behind.
pub struct CsvFile {
    dest: PathBuf,
    tmp: PathBuf,
    writer: Option<BufWriter<File>>,
    error: Option<std::io::Error>,
    rows: CsvRows,
}

impl CsvFile {
    pub fn create(dest: &Path, headers: &[String]) -> std::io::Result<Self> {
        let dest = &output_target(dest)?;
        let tmp = temp_path(dest)?;
        let mut writer = BufWriter::with_capacity(1 << 16, File::create(&tmp)?);
        let header: Vec<String> = headers.iter().map(|h| quote(h)).collect();
        writeln!(writer, "{}", header.join(","))?;
        Ok(CsvFile { dest: dest.to_path_buf(), tmp, writer: Some(writer), error: None, rows: CsvRows::default() })
    }

    /// Appends a row of numbers in [`Number`] form.
    pub fn write_row(&mut self, row: &[f64]) {
        let (Some(w), None) = (self.writer.as_mut(), &self.error) else {
            return;
        };
        if let Err(e) = w.write_all(self.rows.line(row.iter().copied())) {
            self.error = Some(e);
        }
    }

    /// Flushes and renames into place.
    pub fn commit(mut self) -> std::io::Result<()> {
        if let Some(e) = self.error.take() {
            return Err(e);
        }
        if let Some(w) = self.writer.take() {
            w.into_inner().map_err(|e| e.into_error())?.sync_all()?;
        }
        std::fs::rename(&self.tmp, &self.dest)
    }
}

impl Drop for CsvFile {
    fn drop(&mut self) {
        // After a successful commit the temporary name no longer exists.
        self.writer.take();
        let _ = std::fs::remove_file(&self.tmp);
        forget(&self.tmp);
    }
}

/// Quotes a header cell if CSV needs it.
fn quote(s: &str) -> String {
    if s.contains([',', '"', '\n']) { format!("\"{}\"", s.replace('"', "\"\"")) } else { s.to_string() }
}

/// Temporary files this process is writing, so that a signal handler can
/// remove them ([`remove_temporaries`]).
static LIVE: std::sync::Mutex<Vec<PathBuf>> = std::sync::Mutex::new(Vec::new());

fn forget(tmp: &Path) {
    if let Ok(mut live) = LIVE.lock() {
        live.retain(|p| p != tmp);
    }
}

/// Removes every temporary file this process has not yet renamed into
/// place (on SIGINT or SIGTERM: an interrupted run leaves no debris).
pub fn remove_temporaries() {
    if let Ok(live) = LIVE.lock() {
        for p in live.iter() {
            let _ = std::fs::remove_file(p);
        }
    }
}

/// A hidden temporary name beside `dest` (same folder, so the final
/// rename is atomic), creating the folder if it is missing. Temporaries of
/// the same target left by processes that no longer exist (killed with
/// SIGKILL) are removed first.
fn temp_path(dest: &Path) -> std::io::Result<PathBuf> {
    if let Some(dir) = dest.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)?;
    }
    let name = dest.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    remove_stale(dest, &name);
    let tmp = dest.with_file_name(format!(".{name}.{}.tmp", std::process::id()));
    if let Ok(mut live) = LIVE.lock() {
        live.push(tmp.clone());
    }
    Ok(tmp)
}

/// Removes `.NAME.PID.tmp` beside `dest` whose process is gone (Linux:
/// no /proc/PID; elsewhere nothing is removed).
fn remove_stale(dest: &Path, name: &str) {
    let dir = dest.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
    if !Path::new("/proc/self").exists() {
        return;
    }
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    let prefix = format!(".{name}.");
    for e in entries.flatten() {
        let file = e.file_name().to_string_lossy().into_owned();
        let Some(pid) = file.strip_prefix(&prefix).and_then(|r| r.strip_suffix(".tmp")) else { continue };
        if pid.parse::<u32>().is_ok() && !Path::new("/proc").join(pid).exists() {
            let _ = std::fs::remove_file(e.path());
        }
    }
}

/// Where an output to `dest` really goes: through a symbolic link to its
/// target (the link stays a link, also one whose target does not exist
/// yet); never onto a device, FIFO or folder, nor over a read-only file
/// (those are errors, not replaced).
pub fn output_target(dest: &Path) -> std::io::Result<PathBuf> {
    use std::io::{Error, ErrorKind};
    let target = match std::fs::symlink_metadata(dest) {
        Ok(m) if m.file_type().is_symlink() => match std::fs::canonicalize(dest) {
            Ok(target) => target,
            Err(_) => link_target(dest)?,
        },
        _ => dest.to_path_buf(),
    };
    match std::fs::metadata(&target) {
        Ok(m) if !m.is_file() => {
            Err(Error::new(ErrorKind::InvalidInput, "not a regular file: ctlgraph does not replace it"))
        }
        Ok(m) if m.permissions().readonly() => Err(Error::new(ErrorKind::PermissionDenied, "the file is read-only")),
        _ => Ok(target),
    }
}

/// The path a chain of symbolic links from `link` ends at, which need not
/// exist (a dangling link's target is where the output is created).
fn link_target(link: &Path) -> std::io::Result<PathBuf> {
    let mut path = link.to_path_buf();
    // As the kernel does (ELOOP), give up after 40 links.
    for _ in 0..40 {
        let to = std::fs::read_link(&path)?;
        path = match path.parent() {
            Some(dir) if to.is_relative() => dir.join(to),
            _ => to,
        };
        if !std::fs::symlink_metadata(&path).is_ok_and(|m| m.file_type().is_symlink()) {
            return Ok(path);
        }
    }
    Err(std::io::Error::new(std::io::ErrorKind::InvalidInput, "too many levels of symbolic links"))
}

/// Writes a whole file atomically (temporary name, then rename).
pub fn write_atomic(dest: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let dest = &output_target(dest)?;
    let tmp = temp_path(dest)?;
    let result = std::fs::write(&tmp, bytes).and_then(|_| std::fs::rename(&tmp, dest));
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    forget(&tmp);
    result
}

/// The units of the recorded columns as a two-row CSV aligned with the
/// data's header (`t,y,u` over `s,mm,V`; empty where a record has no
/// unit), or `None` when no record has one.
pub fn units_csv(model: &ctlgraph_core::Model) -> Option<String> {
    if model.columns.iter().all(|c| c.unit.is_none()) {
        return None;
    }
    let units = std::iter::once("s")
        .chain(model.columns.iter().flat_map(|c| std::iter::repeat_n(c.unit.as_deref().unwrap_or(""), c.width)));
    Some(format!("{}\n{}\n", model.headers().join(","), units.collect::<Vec<_>>().join(",")))
}

/// Where the units of the CSV at `data` go: `run.csv` → `run.units.csv`.
pub fn units_path(data: &Path) -> std::path::PathBuf {
    let stem = data.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    data.with_file_name(format!("{stem}.units.csv"))
}

/// A trace as CSV text: the header, then one row per sample in [`Number`] form.
pub fn trace_csv(trace: &Trace) -> String {
    let mut text = trace.headers.join(",");
    text.push('\n');
    let mut rows = CsvRows::default();
    for k in 0..trace.t().len() {
        // Only ASCII is written.
        text.push_str(&String::from_utf8_lossy(rows.line(trace.columns.iter().map(|c| c[k]))));
    }
    text
}

/// Rows of numbers as CSV lines in [`Number`] form. A column whose value
/// repeats the row above's (a reference, a step, a sample held between
/// slower hits) copies that row's text instead of formatting it again.
#[derive(Default)]
struct CsvRows {
    line: Vec<u8>,
    previous: Vec<u8>,
    /// Per column of the previous row: the value's bits and where its text
    /// is in `previous`.
    fields: Vec<(u64, usize, usize)>,
}

impl CsvRows {
    /// `row` as a line of CSV, with its newline.
    fn line(&mut self, row: impl IntoIterator<Item = f64>) -> &[u8] {
        std::mem::swap(&mut self.line, &mut self.previous);
        self.line.clear();
        let mut width = 0;
        for (i, v) in row.into_iter().enumerate() {
            if i > 0 {
                self.line.push(b',');
            }
            let start = self.line.len();
            match self.fields.get(i) {
                Some(&(bits, from, to)) if bits == v.to_bits() => self.line.extend_from_slice(&self.previous[from..to]),
                _ => push_number(&mut self.line, v),
            }
            let field = (v.to_bits(), start, self.line.len());
            match self.fields.get_mut(i) {
                Some(f) => *f = field,
                None => self.fields.push(field),
            }
            width = i + 1;
        }
        self.fields.truncate(width);
        self.line.push(b'\n');
        &self.line
    }
}

#[cfg(test)]
mod tests {
    use super::CsvRows;

    #[test]
    fn a_repeated_value_reads_as_when_it_was_first_written() {
        let mut rows = CsvRows::default();
        let lines: Vec<String> = [[0.0, 1.5, -0.0], [1e-5, 1.5, f64::NAN], [2e-5, 2.5, f64::NAN], [3e-5, 2.5, -0.0]]
            .iter()
            .map(|row| String::from_utf8_lossy(rows.line(row.iter().copied())).into_owned())
            .collect();
        assert_eq!(lines, ["0,1.5,-0\n", "1e-5,1.5,NaN\n", "2e-5,2.5,NaN\n", "3e-5,2.5,-0\n"]);
        assert_eq!(rows.line([7.0]), b"7\n", "a shorter row");
        assert_eq!(rows.line([7.0, 7.0]), b"7,7\n", "a longer row");
    }
}
