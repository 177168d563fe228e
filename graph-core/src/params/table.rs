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
    pub default: ParamDefault,
    /// The unit of its value ("s", "rad/s", "mm"), or "" for none.
    pub unit: &'static str,
    pub doc: &'static str,
}

impl ParamDoc {
    /// A parameter without a unit.
    pub const fn new(name: &'static str, default: ParamDefault, doc: &'static str) -> Self {
        ParamDoc { name, default, unit: "", doc }
    }

    /// The same parameter, its value in `unit`.
    pub const fn unit(self, unit: &'static str) -> Self {
        ParamDoc { unit, ..self }
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
