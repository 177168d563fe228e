//! C99 for a graph's sampled controller (`ctlgraph codegen --target c`):
//! a header with the controller's input, output and state structs and
//! `NAME_init` / `NAME_step`, and a source file with the blocks' C forms
//! ([`crate::Block::c_form`]) in execution order, the slower rates stepped
//! by counters. No dynamic memory, no globals, no recursion; `<math.h>`
//! and `<stdint.h>` only.
//!
//! One call of `NAME_step` is one base-rate sample, the simulator's major
//! step at that time: every block due computes its outputs in execution
//! order, the outputs are written, then every block due updates its
//! memory (Simulink's order, the interpreter's).

mod form;
mod harness;
mod select;
mod write;

pub use form::{CBlock, Helpers, NoCForm, Real};
pub use harness::harness;
pub use select::{Controller, Member, Terminal, select};

use crate::compile::Model;
use crate::diag::Diagnostic;

/// The generated files' text.
#[derive(Clone, Debug)]
pub struct CFiles {
    /// `NAME.h`
    pub header: String,
    /// `NAME.c`
    pub source: String,
    /// The members of `NAME_in` element by element (`r`, `z[0]`, …), in
    /// the controller's input order; the same of `NAME_out`.
    pub input_elements: Vec<String>,
    pub output_elements: Vec<String>,
}

/// What to generate and what the user should read at the top of the files.
pub struct Options<'a> {
    pub real: Real,
    /// Where the controller came from, for the files' first comment
    /// (`graphs/fladrc/ladrc.yaml, subsystem ctrl`).
    pub origin: &'a str,
    /// The block types that have a C form, for the hint when one is missing.
    pub types_with_c_form: &'a [&'a str],
}

/// The C files for `controller` of `model`; refuses, at the block's
/// position, a block without a C form.
pub fn generate(model: &Model, controller: &Controller, options: &Options) -> Result<CFiles, Diagnostic> {
    write::files(model, controller, options)
}

/// `name` as a C identifier: other characters become `_`, a leading digit
/// or a C keyword gets one more.
pub fn identifier(name: &str) -> String {
    let mut id: String = name.chars().map(|c| if c.is_ascii_alphanumeric() || c == '_' { c } else { '_' }).collect();
    if id.is_empty() || id.starts_with(|c: char| c.is_ascii_digit()) {
        id.insert(0, '_');
    }
    if KEYWORDS.contains(&id.as_str()) {
        id.push('_');
    }
    id
}

const KEYWORDS: &[&str] = &[
    "auto",
    "break",
    "case",
    "char",
    "const",
    "continue",
    "default",
    "do",
    "double",
    "else",
    "enum",
    "extern",
    "float",
    "for",
    "goto",
    "if",
    "inline",
    "int",
    "long",
    "register",
    "restrict",
    "return",
    "short",
    "signed",
    "sizeof",
    "static",
    "struct",
    "switch",
    "typedef",
    "union",
    "unsigned",
    "void",
    "volatile",
    "while",
    "_Bool",
    "_Complex",
    "_Imaginary",
];

#[cfg(test)]
mod tests {
    use super::identifier;

    #[test]
    fn names_become_c_identifiers() {
        assert_eq!(identifier("td"), "td");
        assert_eq!(identifier("ctrl/td"), "ctrl_td");
        assert_eq!(identifier("2nd"), "_2nd");
        assert_eq!(identifier("int"), "int_");
        assert_eq!(identifier("a-b.c"), "a_b_c");
    }
}
