//! Between the protocol's places and ctlgraph's: LSP positions are 0-based
//! lines and UTF-16 code units; ctlgraph's are 1-based lines and
//! characters. And between `file://` URIs and paths.

use lsp_types::{Position, Range, Uri};
use std::path::PathBuf;
use std::str::FromStr;

/// The LSP position of ctlgraph's 1-based `line`, `col` (characters) in `text`.
pub fn position(text: &str, line: u32, col: u32) -> Position {
    let l = line.saturating_sub(1);
    let units = text
        .lines()
        .nth(l as usize)
        .map_or(0, |s| s.chars().take(col.saturating_sub(1) as usize).map(char::len_utf16).sum::<usize>());
    Position { line: l, character: units as u32 }
}

/// ctlgraph's 1-based (line, column in characters) of an LSP position.
pub fn place(text: &str, at: Position) -> (u32, u32) {
    let line = text.lines().nth(at.line as usize).unwrap_or("");
    let (mut units, mut chars) = (0u32, 0u32);
    for c in line.chars() {
        if units >= at.character {
            break;
        }
        units += c.len_utf16() as u32;
        chars += 1;
    }
    (at.line + 1, chars + 1)
}

/// The range of `len` characters from ctlgraph's `line`, `col`.
pub fn span(text: &str, line: u32, col: u32, len: usize) -> Range {
    Range { start: position(text, line, col), end: position(text, line, col + len as u32) }
}

/// The word under 1-based (line, col): letters, digits, `_`, `/` and `.`
/// (a signal `sub/block.port`), with its first column; `None` off a word.
pub fn word_at(text: &str, line: u32, col: u32) -> Option<(String, u32)> {
    let chars: Vec<char> = text.lines().nth(line.saturating_sub(1) as usize)?.chars().collect();
    let is_word = |c: char| c.is_alphanumeric() || c == '_' || c == '/' || c == '.';
    let at = (col.saturating_sub(1) as usize).min(chars.len());
    let mut start = at;
    while start > 0 && is_word(chars[start - 1]) {
        start -= 1;
    }
    let mut end = at;
    while end < chars.len() && is_word(chars[end]) {
        end += 1;
    }
    (end > start).then(|| (chars[start..end].iter().collect(), start as u32 + 1))
}

/// The text of `line` (1-based) before column `col`.
pub fn before(text: &str, line: u32, col: u32) -> String {
    text.lines()
        .nth(line.saturating_sub(1) as usize)
        .unwrap_or("")
        .chars()
        .take(col.saturating_sub(1) as usize)
        .collect()
}

/// The path of a `file://` URI (percent-escapes decoded).
pub fn path_of(uri: &Uri) -> Option<PathBuf> {
    let rest = uri.as_str().strip_prefix("file://")?;
    let bytes = rest.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%'
            && i + 2 < bytes.len()
            && let Ok(b) = u8::from_str_radix(std::str::from_utf8(&bytes[i + 1..i + 3]).ok()?, 16)
        {
            out.push(b);
            i += 3;
            continue;
        }
        out.push(bytes[i]);
        i += 1;
    }
    String::from_utf8(out).ok().map(PathBuf::from)
}

/// The `file://` URI of an absolute path (characters outside the
/// unreserved set and `/` escaped).
pub fn uri_of(path: &std::path::Path) -> Option<Uri> {
    let mut text = String::from("file://");
    for b in path.to_str()?.bytes() {
        if b.is_ascii_alphanumeric() || b"-._~/".contains(&b) {
            text.push(b as char);
        } else {
            text.push_str(&format!("%{b:02X}"));
        }
    }
    Uri::from_str(&text).ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn positions_count_utf16_units_and_characters() {
        let text = "a: 1\n# θ̂ x\n";
        // `x` is the 6th character of line 2: 5 UTF-16 units before it.
        assert_eq!(position(text, 2, 6), Position { line: 1, character: 5 });
        assert_eq!(place(text, Position { line: 1, character: 5 }), (2, 6));
        assert_eq!(word_at("  - ctrl.u -> plant", 1, 8), Some(("ctrl.u".to_string(), 5)));
    }

    #[test]
    fn uris_and_paths_round_trip() {
        let p = std::path::Path::new("/tmp/a graph/ü.yaml");
        let uri = uri_of(p).unwrap();
        assert_eq!(uri.as_str(), "file:///tmp/a%20graph/%C3%BC.yaml");
        assert_eq!(path_of(&uri).unwrap(), p);
    }
}
