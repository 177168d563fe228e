//! A block type's parameter table: each parameter's name, default, unit
//! and doc, written once and read by both the documentation and
//! [`super::Params`].

/// One parameter of a block type, declared once in the type's table: the
/// documentation (`ctlgraph blocks TYPE`, the reference) prints it, and
/// [`Params`] reads its default from it when a graph leaves it out — so a
/// default is written in one place only.
#[derive(Clone, Copy, Debug)]
pub struct ParamDoc {
    pub name: &'static str,
    pub kind: ParamKind,
    pub default: ParamDefault,
    /// The unit of its value ("s", "rad/s", "mm"), or "" for none.
    pub unit: &'static str,
    pub doc: &'static str,
    /// A word's options, empty for other kinds and free words: what
    /// [`super::Params::choice`] accepts (a debug build checks that the
    /// block asks for these), and the schema's enum.
    pub options: &'static [&'static str],
}

impl ParamDoc {
    /// A parameter without a unit, of the kind its default is (text for
    /// one required or described in words, until [`ParamDoc::kind`] says).
    pub const fn new(name: &'static str, default: ParamDefault, doc: &'static str) -> Self {
        let kind = match default {
            ParamDefault::Number(_) => ParamKind::Number,
            ParamDefault::Numbers(_) => ParamKind::Numbers,
            ParamDefault::Flag(_) => ParamKind::Flag,
            ParamDefault::Word(_) => ParamKind::Word,
            ParamDefault::Required | ParamDefault::Described(_) => ParamKind::Text,
        };
        ParamDoc { name, kind, default, unit: "", doc, options: &[] }
    }

    /// The same parameter, of `kind`.
    pub const fn kind(self, kind: ParamKind) -> Self {
        ParamDoc { kind, ..self }
    }

    /// The same parameter, its value in `unit`.
    pub const fn unit(self, unit: &'static str) -> Self {
        ParamDoc { unit, ..self }
    }

    /// The same parameter, a word out of `options`.
    pub const fn options(self, options: &'static [&'static str]) -> Self {
        ParamDoc { options, ..self }
    }
}

/// What a parameter is when a graph leaves it out.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ParamDefault {
    /// The graph must give it.
    Required,
    /// This number (a count, a gain, a time).
    Number(f64),
    /// These numbers (an initial state, a range).
    Numbers(&'static [f64]),
    /// This flag.
    Flag(bool),
    /// This word: an option's name, a string of signs.
    Word(&'static str),
    /// Nothing the parser reads: the block derives the value or gives
    /// absence a meaning, described in words ("always", "2·sample_time").
    Described(&'static str),
}

impl std::fmt::Display for ParamDefault {
    /// As a graph would write it (or the words describing it).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ParamDefault::Required => f.write_str("required"),
            ParamDefault::Number(x) => write!(f, "{x}"),
            ParamDefault::Numbers(xs) => {
                let items: Vec<String> = xs.iter().map(f64::to_string).collect();
                write!(f, "[{}]", items.join(", "))
            }
            ParamDefault::Flag(b) => write!(f, "{b}"),
            ParamDefault::Word(w) | ParamDefault::Described(w) => f.write_str(w),
        }
    }
}

/// What a parameter's value is, as a graph writes it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ParamKind {
    /// A number, or an expression of the graph's parameters.
    Number,
    /// A list of numbers (one number is a list of one).
    Numbers,
    /// A list of rows of numbers (a list is one row, a number a 1×1), or
    /// of numbers and pairs (roots).
    Matrix,
    /// true or false.
    Flag,
    /// One of the block's named options.
    Word,
    /// Free text: a formula in the block's own variables, a file, a column.
    Text,
    /// A list of words or formulas.
    Words,
    /// 0 (continuous), -1 (inherited), T, [T, offset] or inf (constant).
    SampleTime,
    /// A structure the block reads itself (a fuzzy system's variables and
    /// rules, a subsystem's parameter overrides).
    Structure,
}

impl ParamKind {
    /// The kind's name in the documentation.
    pub fn name(self) -> &'static str {
        match self {
            ParamKind::Number => "number",
            ParamKind::Numbers => "numbers",
            ParamKind::Matrix => "matrix",
            ParamKind::Flag => "flag",
            ParamKind::Word => "word",
            ParamKind::Text => "text",
            ParamKind::Words => "words",
            ParamKind::SampleTime => "sample time",
            ParamKind::Structure => "structure",
        }
    }
}
