//! Positioned diagnostics: every mistake in a graph file is reported as
//! `file:line:col: message`, with a hint where one helps.

use std::fmt;
use std::sync::Arc;

/// A position in a graph file (1-based line and column, in characters).
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct Pos {
    pub file: Arc<str>,
    pub line: u32,
    pub col: u32,
}

impl Pos {
    pub fn new(file: Arc<str>, line: u32, col: u32) -> Self {
        Pos { file, line, col }
    }

    /// The position `n` characters further along the same line.
    pub fn shifted(&self, n: usize) -> Pos {
        Pos { file: self.file.clone(), line: self.line, col: self.col + n as u32 }
    }
}

impl fmt::Display for Pos {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}:{}", self.file, self.line, self.col)
    }
}

/// An error in the user's input: a graph file, a `--set` value, a CSV file.
#[derive(Clone, Debug, PartialEq)]
pub struct Diagnostic {
    /// Where, if the error has a position; otherwise `file` names the input.
    pub pos: Option<Pos>,
    pub file: Option<Arc<str>>,
    pub message: String,
    pub hint: Option<String>,
}

impl Diagnostic {
    pub fn at(pos: &Pos, message: impl Into<String>) -> Self {
        Diagnostic { pos: Some(pos.clone()), file: None, message: message.into(), hint: None }
    }

    /// An error about a whole file (cannot be read, for example).
    pub fn in_file(file: &str, message: impl Into<String>) -> Self {
        Diagnostic { pos: None, file: Some(file.into()), message: message.into(), hint: None }
    }

    /// An error with no file to point at (a command-line argument).
    pub fn plain(message: impl Into<String>) -> Self {
        Diagnostic { pos: None, file: None, message: message.into(), hint: None }
    }

    pub fn with_hint(mut self, hint: impl Into<String>) -> Self {
        self.hint = Some(hint.into());
        self
    }

    /// Adds a hint unless there is one already.
    pub fn or_hint(self, hint: impl Into<String>) -> Self {
        if self.hint.is_some() { self } else { self.with_hint(hint) }
    }

    /// Adds a "did you mean" hint when a candidate is close enough to `got`.
    pub fn suggest<'a>(self, got: &str, candidates: impl IntoIterator<Item = &'a str>) -> Self {
        match closest(got, candidates) {
            Some(best) => self.with_hint(format!("did you mean `{best}`?")),
            None => self,
        }
    }
}

impl fmt::Display for Diagnostic {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match (&self.pos, &self.file) {
            (Some(pos), _) => write!(f, "{pos}: {}", self.message)?,
            (None, Some(file)) => write!(f, "{file}: {}", self.message)?,
            (None, None) => f.write_str(&self.message)?,
        }
        if let Some(hint) = &self.hint {
            write!(f, "\n  hint: {hint}")?;
        }
        Ok(())
    }
}

impl std::error::Error for Diagnostic {}

/// The candidate closest to `got` by edit distance, if it is plausibly a
/// typo of it (distance at most a third of the length, at least 1), or if
/// one contains the other.
pub fn closest<'a>(got: &str, candidates: impl IntoIterator<Item = &'a str>) -> Option<&'a str> {
    let limit = (got.chars().count() / 3).max(1);
    candidates
        .into_iter()
        .map(|c| {
            let d = strsim::damerau_levenshtein(got, c);
            let contained = got.len() >= 3 && c.len() >= 3 && (c.contains(got) || got.contains(c));
            (if contained { d.min(limit) } else { d }, d, c)
        })
        .filter(|&(d, _, _)| d <= limit)
        .min_by_key(|&(d, real, c)| (d, real, !c.starts_with(got), c.len()))
        .map(|(_, _, c)| c)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn suggestions_catch_typos_only() {
        let types = ["transfer_function", "gain", "sum", "saturation"];
        assert_eq!(closest("tranfer_function", types), Some("transfer_function"));
        assert_eq!(closest("gian", types), Some("gain"));
        assert_eq!(closest("integrator", types), None);
        // A one-letter name inside the word is no suggestion; the near miss is.
        assert_eq!(closest("ctrll", ["r", "e", "ctrl", "plant"]), Some("ctrl"));
    }

    #[test]
    fn display_is_file_line_col() {
        let d = Diagnostic::at(&Pos::new("g.yaml".into(), 3, 7), "bad").with_hint("try this");
        assert_eq!(d.to_string(), "g.yaml:3:7: bad\n  hint: try this");
    }
}
