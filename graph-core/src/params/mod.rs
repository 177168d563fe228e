//! Typed access to a block's parameters, for block constructors.
//!
//! Every accessor turns a wrong value into a positioned diagnostic naming
//! the block and the key; [`Params::finish`] reports keys no accessor asked
//! for, with the closest documented name as a hint.

use crate::block::SampleTime;
use crate::diag::{Diagnostic, Pos};
use crate::expr::{Constants, Expr, ExprError, Scope};
use crate::yaml::{Key, Kind, Yaml};
use std::path::{Path, PathBuf};

mod table;
#[cfg(test)]
mod tests;
pub use table::{ParamDefault, ParamDoc, ParamKind};

/// A block's parameters as written, with the scope their expressions see.
pub struct Params<'a> {
    block: &'a str,
    type_name: &'a str,
    block_pos: &'a Pos,
    entries: &'a [(Key, Yaml)],
    scope: &'a [(String, f64)],
    dir: &'a Path,
    docs: &'static [ParamDoc],
    used: Vec<bool>,
    seed: u64,
}

impl<'a> Params<'a> {
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        block: &'a str,
        type_name: &'a str,
        block_pos: &'a Pos,
        entries: &'a [(Key, Yaml)],
        scope: &'a [(String, f64)],
        dir: &'a Path,
        docs: &'static [ParamDoc],
    ) -> Self {
        let used = entries.iter().map(|(k, _)| k.name == "type").collect();
        Params { block, type_name, block_pos, entries, scope, dir, docs, used, seed: 0 }
    }

    /// Sets the graph's `simulation.seed`, from which random blocks derive
    /// their streams.
    pub fn with_seed(mut self, seed: u64) -> Self {
        self.seed = seed;
        self
    }

    /// A seed for this block's random stream: the graph seed, the block's
    /// full name and `extra` (the block's own `seed` parameter) mixed, so
    /// adding a block elsewhere changes no other block's stream.
    pub fn stream_seed(&self, extra: u64) -> u64 {
        // FNV-1a over the name, then SplitMix64 finalisation of the mix.
        let name =
            self.block.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| (h ^ b as u64).wrapping_mul(0x100_0000_01b3));
        let mut z = self.seed ^ name.rotate_left(17) ^ extra.wrapping_mul(0x9e37_79b9_7f4a_7c15);
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// The block's full name (`outer/inner` inside subsystems).
    pub fn block_name(&self) -> &str {
        self.block
    }

    /// The graph parameters visible to this block, for blocks that compile
    /// expressions of their own (`fcn`).
    pub fn scope(&self) -> &'a [(String, f64)] {
        self.scope
    }

    /// The raw value of `key`, marking it used.
    pub fn raw(&mut self, key: &str) -> Option<&'a Yaml> {
        self.declared(key);
        let i = self.entries.iter().position(|(k, _)| k.name == key)?;
        self.used[i] = true;
        Some(&self.entries[i].1)
    }

    /// Whether `key` is present (without marking it used).
    pub fn has(&self, key: &str) -> bool {
        self.declared(key);
        self.entries.iter().any(|(k, _)| k.name == key)
    }

    /// An error about `key` of this block, at the key's value if present.
    pub fn error(&self, key: &str, message: impl std::fmt::Display) -> Diagnostic {
        let pos = self.entries.iter().find(|(k, _)| k.name == key).map_or(self.block_pos, |(_, v)| &v.pos);
        Diagnostic::at(pos, format!("block `{}` ({}): `{key}`: {message}", self.block, self.type_name))
    }

    /// An error about the block as a whole, at its name.
    pub fn block_error(&self, message: impl std::fmt::Display) -> Diagnostic {
        Diagnostic::at(self.block_pos, format!("block `{}` ({}): {message}", self.block, self.type_name))
    }

    /// The block type's table entry for `key`. A block reading a key its
    /// table does not list is a mistake in the block (its documentation
    /// would not show the parameter): a debug build stops there, so the
    /// tests, which build every type, find it. Blocks without a table
    /// (custom blocks that document nothing) are not checked.
    fn declared(&self, key: &str) -> Option<&'static ParamDoc> {
        let entry = self.docs.iter().find(|d| d.name == key);
        debug_assert!(
            self.docs.is_empty() || entry.is_some(),
            "block type `{}` reads parameter `{key}`, which its parameter table does not list",
            self.type_name
        );
        entry
    }

    /// Checks (in a debug build) that the table declares `key` of one of
    /// `kinds`, the ones the accessor reading it accepts.
    fn expect_kind(&self, key: &str, kinds: &[ParamKind]) {
        if let Some(entry) = self.declared(key) {
            debug_assert!(
                kinds.contains(&entry.kind),
                "block type `{}` reads parameter `{key}` as {:?}, but its table declares it {:?}",
                self.type_name,
                kinds,
                entry.kind
            );
        }
    }

    /// What the table gives `key` when the graph leaves it out (required
    /// for a block without a table).
    fn default_of(&self, key: &str) -> ParamDefault {
        self.declared(key).map_or(ParamDefault::Required, |d| d.default)
    }

    /// The error for a block asking for `key` as `wanted` where its table's
    /// default is of another kind: a mistake in the block, not the graph.
    fn default_mismatch(&self, key: &str, wanted: &str) -> Diagnostic {
        self.block_error(format!(
            "internal error: the block reads `{key}` as {wanted}, but its table's default is `{}`",
            self.default_of(key)
        ))
    }

    fn missing(&self, key: &str) -> Diagnostic {
        self.block_error(format!("missing parameter `{key}`"))
            .with_hint(format!("see `ctlgraph blocks {}`", self.type_name))
    }

    /// Evaluates a number or an expression over the graph parameters.
    pub fn number_value(&self, key: &str, v: &Yaml) -> Result<f64, Diagnostic> {
        let x = match &v.kind {
            Kind::Num(x) => *x,
            Kind::Str(s) => eval_number(s, &v.pos, self.scope).map_err(|d| {
                let message = format!("block `{}` ({}): `{key}`: {}", self.block, self.type_name, d.message);
                Diagnostic { message, ..d }
            })?,
            _ => return Err(self.error(key, format!("expected a number, found {}", v.describe()))),
        };
        if x.is_nan() {
            return Err(Diagnostic::at(
                &v.pos,
                format!("block `{}` ({}): `{key}` is not a number (NaN)", self.block, self.type_name),
            ));
        }
        Ok(x)
    }

    /// A number: the graph's, else the table's default; required when
    /// the table says so.
    pub fn number(&mut self, key: &str) -> Result<f64, Diagnostic> {
        self.opt_number(key)?.ok_or_else(|| self.missing(key))
    }

    /// A number, or `None` when the graph leaves it out (or writes `null`)
    /// and the table gives no number (required, or described in words).
    pub fn opt_number(&mut self, key: &str) -> Result<Option<f64>, Diagnostic> {
        self.expect_kind(key, &[ParamKind::Number]);
        match self.raw(key) {
            Some(v) if v.kind != Kind::Null => self.number_value(key, v).map(Some),
            _ => match self.default_of(key) {
                ParamDefault::Number(x) => Ok(Some(x)),
                ParamDefault::Required | ParamDefault::Described(_) => Ok(None),
                ParamDefault::Numbers(_) | ParamDefault::Flag(_) | ParamDefault::Word(_) => {
                    Err(self.default_mismatch(key, "a number"))
                }
            },
        }
    }

    /// A number with a default the block derives (from another parameter,
    /// the sample time) when neither the graph nor the table gives one.
    pub fn number_or(&mut self, key: &str, default: f64) -> Result<f64, Diagnostic> {
        Ok(self.opt_number(key)?.unwrap_or(default))
    }

    /// A number that must satisfy `ok`, else an error saying `requirement`;
    /// `default` is a derived default ([`Params::number_or`]), `None` for
    /// the table's.
    pub fn number_where(
        &mut self,
        key: &str,
        default: Option<f64>,
        ok: impl Fn(f64) -> bool,
        requirement: &str,
    ) -> Result<f64, Diagnostic> {
        let v = match default {
            Some(d) => self.number_or(key, d)?,
            None => self.number(key)?,
        };
        if ok(v) { Ok(v) } else { Err(self.error(key, format!("must be {requirement}, got {v}"))) }
    }

    /// A required positive, finite number.
    pub fn positive(&mut self, key: &str) -> Result<f64, Diagnostic> {
        self.number_where(key, None, |v| v > 0.0 && v.is_finite(), "a positive number")
    }

    /// The `sample_time` of blocks that exist in a continuous and a
    /// discrete form (default continuous): the sample time and, when
    /// discrete, its period.
    pub fn continuous_or_discrete(&mut self) -> Result<(SampleTime, Option<f64>), Diagnostic> {
        match self.sample_time()? {
            st @ SampleTime::Continuous => Ok((st, None)),
            st @ SampleTime::Discrete { period, .. } => Ok((st, Some(period))),
            other => {
                Err(self.error("sample_time", format!("this block is continuous (0) or discrete (T > 0), not {other}")))
            }
        }
    }

    /// A whole number from 1 to `max` (default: the table's): every
    /// size-like parameter has a stated bound, checked before anything is
    /// allocated.
    pub fn count(&mut self, key: &str, max: usize) -> Result<usize, Diagnostic> {
        let v = self.number(key)?;
        self.checked_count(key, v, max)
    }

    /// [`Params::count`] with a derived default.
    pub fn count_or(&mut self, key: &str, default: usize, max: usize) -> Result<usize, Diagnostic> {
        let v = self.number_or(key, default as f64)?;
        self.checked_count(key, v, max)
    }

    fn checked_count(&self, key: &str, v: f64, max: usize) -> Result<usize, Diagnostic> {
        if v >= 1.0 && v.fract() == 0.0 && v <= max as f64 {
            Ok(v as usize)
        } else {
            Err(self.error(key, format!("must be a whole number from 1 to {max}, got {v}")))
        }
    }

    /// A list of numbers (a single number is a list of one).
    pub fn vector(&mut self, key: &str) -> Result<Vec<f64>, Diagnostic> {
        self.opt_vector(key)?.ok_or_else(|| self.missing(key))
    }

    /// A list of numbers, else the table's default (a number is a list of
    /// one); `None` when the table gives none.
    pub fn opt_vector(&mut self, key: &str) -> Result<Option<Vec<f64>>, Diagnostic> {
        self.expect_kind(key, &[ParamKind::Numbers, ParamKind::Matrix]);
        match self.raw(key) {
            Some(v) if v.kind != Kind::Null => self.vector_value(key, v).map(Some),
            _ => match self.default_of(key) {
                ParamDefault::Number(x) => Ok(Some(vec![x])),
                ParamDefault::Numbers(xs) => Ok(Some(xs.to_vec())),
                ParamDefault::Required | ParamDefault::Described(_) => Ok(None),
                ParamDefault::Flag(_) | ParamDefault::Word(_) => Err(self.default_mismatch(key, "numbers")),
            },
        }
    }

    /// A list of finite numbers (coefficients, gains, initial states).
    fn vector_value(&self, key: &str, v: &Yaml) -> Result<Vec<f64>, Diagnostic> {
        let items = match &v.kind {
            Kind::Seq(items) => items.as_slice(),
            Kind::Num(_) | Kind::Str(_) => std::slice::from_ref(v),
            _ => return Err(self.error(key, format!("expected a list of numbers, found {}", v.describe()))),
        };
        items
            .iter()
            .map(|i| {
                let x = self.number_value(key, i)?;
                if x.is_finite() {
                    Ok(x)
                } else {
                    Err(Diagnostic::at(
                        &i.pos,
                        format!("block `{}` ({}): `{key}`: {x} is not finite", self.block, self.type_name),
                    )
                    .with_hint("coefficients, gains and initial values must be finite numbers"))
                }
            })
            .collect()
    }

    /// A matrix as a list of rows; a list of numbers is one row, a number a 1×1.
    pub fn matrix(&mut self, key: &str) -> Result<Vec<Vec<f64>>, Diagnostic> {
        self.expect_kind(key, &[ParamKind::Matrix]);
        let Some(v) = self.raw(key) else {
            return Err(self.missing(key));
        };
        match &v.kind {
            Kind::Seq(rows) if rows.iter().all(|r| matches!(r.kind, Kind::Seq(_))) && !rows.is_empty() => {
                rows.iter().map(|r| self.vector_value(key, r)).collect()
            }
            Kind::Seq(rows) if rows.is_empty() => Ok(Vec::new()),
            _ => Ok(vec![self.vector_value(key, v)?]),
        }
    }

    /// A polynomial as a list of coefficients, or a product of polynomials
    /// as a list of such lists (one factor each).
    pub fn polynomial_factors(&mut self, key: &str) -> Result<Vec<Vec<f64>>, Diagnostic> {
        self.expect_kind(key, &[ParamKind::Matrix]);
        let Some(v) = self.raw(key) else {
            return Err(self.missing(key));
        };
        match &v.kind {
            Kind::Seq(items) if items.iter().any(|i| matches!(i.kind, Kind::Seq(_))) => {
                items.iter().map(|i| self.vector_value(key, i)).collect()
            }
            _ => Ok(vec![self.vector_value(key, v)?]),
        }
    }

    /// A list whose items are numbers or `[re, im]` pairs (a complex
    /// number, standing for itself and its conjugate).
    pub fn roots(&mut self, key: &str) -> Result<Vec<(f64, f64)>, Diagnostic> {
        self.expect_kind(key, &[ParamKind::Matrix]);
        let Some(v) = self.raw(key) else {
            return Ok(Vec::new());
        };
        let items = match &v.kind {
            Kind::Seq(items) => items.as_slice(),
            Kind::Null => return Ok(Vec::new()),
            _ => std::slice::from_ref(v),
        };
        let mut out = Vec::new();
        let mut written: Vec<(f64, f64)> = Vec::new();
        for item in items {
            match &item.kind {
                Kind::Seq(pair) if pair.len() == 2 => {
                    let (re, im) = (self.number_value(key, &pair[0])?, self.number_value(key, &pair[1])?);
                    // MATLAB lists both conjugates; here one [re, im] stands for the pair.
                    if im != 0.0 && written.contains(&(re, -im)) {
                        return Err(Diagnostic::at(
                            &item.pos,
                            format!(
                                "block `{}`: `{key}`: [{re}, {im}] is the conjugate of [{re}, {}], which already stands for the pair {re} ± {}j",
                                self.block_name(),
                                -im,
                                im.abs()
                            ),
                        )
                        .with_hint("write each conjugate pair once as [re, im]; write it twice for a repeated pair"));
                    }
                    written.push((re, im));
                    out.push((re, im));
                    if im != 0.0 {
                        out.push((re, -im));
                    }
                }
                Kind::Seq(_) => {
                    return Err(Diagnostic::at(&item.pos, "a complex root is written [re, im]".to_string()));
                }
                _ => out.push((self.number_value(key, item)?, 0.0)),
            }
        }
        Ok(out)
    }

    /// A string: the graph's, else the table's word; `None` when the table
    /// gives none (required, or described in words).
    pub fn opt_string(&mut self, key: &str) -> Result<Option<&'a str>, Diagnostic> {
        self.expect_kind(key, &[ParamKind::Word, ParamKind::Text]);
        match self.raw(key) {
            None => match self.default_of(key) {
                ParamDefault::Word(w) => Ok(Some(w)),
                ParamDefault::Required | ParamDefault::Described(_) => Ok(None),
                ParamDefault::Number(_) | ParamDefault::Numbers(_) | ParamDefault::Flag(_) => {
                    Err(self.default_mismatch(key, "a string"))
                }
            },
            Some(v) => match &v.kind {
                Kind::Str(s) => Ok(Some(s)),
                _ => Err(self.error(key, format!("expected a string, found {}", v.describe()))),
            },
        }
    }

    pub fn string(&mut self, key: &str) -> Result<&'a str, Diagnostic> {
        self.opt_string(key)?.ok_or_else(|| self.missing(key))
    }

    /// One of `options`; the default is the table's word (for a block
    /// without a table, the first option).
    pub fn choice(&mut self, key: &str, options: &[&'static str]) -> Result<&'static str, Diagnostic> {
        if let Some(entry) = self.declared(key) {
            debug_assert!(
                entry.options == options,
                "block type `{}` reads `{key}` as one of {options:?}, but its table declares {:?}",
                self.type_name,
                entry.options
            );
        }
        let given = self.has(key);
        let s = match self.opt_string(key)? {
            Some(s) => s,
            None if self.docs.is_empty() => return Ok(options[0]),
            None => return Err(self.missing(key)),
        };
        options.iter().copied().find(|o| *o == s).ok_or_else(|| {
            if given {
                self.error(key, format!("`{s}` is not one of: {}", options.join(", ")))
                    .suggest(s, options.iter().copied())
            } else {
                self.default_mismatch(key, &format!("one of {}", options.join(", ")))
            }
        })
    }

    /// A flag: the graph's, else the table's.
    pub fn flag(&mut self, key: &str) -> Result<bool, Diagnostic> {
        match self.default_of(key) {
            ParamDefault::Flag(default) => self.bool_or(key, default),
            ParamDefault::Required if self.has(key) => self.bool_or(key, false),
            ParamDefault::Required => Err(self.missing(key)),
            _ => Err(self.default_mismatch(key, "a flag")),
        }
    }

    /// A flag with `default` when the graph leaves it out (for blocks
    /// without a table; those with one use [`Params::flag`]).
    pub fn bool_or(&mut self, key: &str, default: bool) -> Result<bool, Diagnostic> {
        self.expect_kind(key, &[ParamKind::Flag]);
        match self.raw(key) {
            None => Ok(default),
            Some(v) => match v.kind {
                Kind::Bool(b) => Ok(b),
                _ => Err(self.error(key, format!("expected true or false, found {}", v.describe()))),
            },
        }
    }

    /// A list of strings (a single string is a list of one).
    pub fn strings(&mut self, key: &str) -> Result<Vec<&'a str>, Diagnostic> {
        self.expect_kind(key, &[ParamKind::Words, ParamKind::Word]);
        let Some(v) = self.raw(key) else {
            return Ok(Vec::new());
        };
        let items = match &v.kind {
            Kind::Seq(items) => items.as_slice(),
            _ => std::slice::from_ref(v),
        };
        items.iter().map(|i| i.expect_str(&format!("`{key}` item"))).collect()
    }

    /// A file path, relative to the graph file's folder.
    pub fn path(&mut self, key: &str) -> Result<PathBuf, Diagnostic> {
        Ok(self.dir.join(self.string(key)?))
    }

    /// The `sample_time` parameter: 0 continuous, -1 inherited, `inf`
    /// constant, T > 0 discrete, or `[T, offset]` with 0 ≤ offset < T.
    /// Left out, it is the table's (inherited for a block without one).
    pub fn sample_time(&mut self) -> Result<SampleTime, Diagnostic> {
        let key = "sample_time";
        self.expect_kind(key, &[ParamKind::SampleTime]);
        let Some(v) = self.raw(key) else {
            return match self.default_of(key) {
                _ if self.docs.is_empty() => Ok(SampleTime::Inherited),
                ParamDefault::Number(period) => self.sample_time_of(period, 0.0),
                ParamDefault::Required => Err(self.missing(key)),
                _ => Err(self.default_mismatch(key, "a sample time")),
            };
        };
        let (period, offset) = match &v.kind {
            Kind::Seq(items) if items.len() == 2 => {
                (self.number_value(key, &items[0])?, self.number_value(key, &items[1])?)
            }
            Kind::Str(s) if s == "inf" => return Ok(SampleTime::Constant),
            Kind::Seq(_) => return Err(self.error(key, "expected a period or [period, offset]")),
            _ => (self.number_value(key, v)?, 0.0),
        };
        self.sample_time_of(period, offset)
    }

    /// [`Params::sample_time`] for a block whose default sample time it
    /// derives (the table describes it in words): `derived` when the graph
    /// leaves it out.
    pub fn sample_time_or(&mut self, derived: SampleTime) -> Result<SampleTime, Diagnostic> {
        match self.default_of("sample_time") {
            ParamDefault::Described(_) if !self.has("sample_time") => Ok(derived),
            _ => self.sample_time(),
        }
    }

    /// The sample time a period and offset stand for.
    fn sample_time_of(&self, period: f64, offset: f64) -> Result<SampleTime, Diagnostic> {
        let key = "sample_time";
        let hint = "0 = continuous, -1 = inherited, T > 0 = every T seconds, [T, offset] with 0 <= offset < T";
        match period {
            p if p == 0.0 && offset == 0.0 => Ok(SampleTime::Continuous),
            p if p == -1.0 && offset == 0.0 => Ok(SampleTime::Inherited),
            p if p == f64::INFINITY => Ok(SampleTime::Constant),
            p if p > 0.0 && p.is_finite() && (0.0..p).contains(&offset) => {
                Ok(SampleTime::Discrete { period: p, offset })
            }
            _ => Err(self.error(key, format!("bad sample time [{period}, {offset}]")).with_hint(hint)),
        }
    }

    /// Like [`Params::sample_time`] for blocks that only exist in discrete
    /// form: the period is required.
    pub fn discrete_sample_time(&mut self) -> Result<SampleTime, Diagnostic> {
        Ok(self.discrete_clock()?.0)
    }

    /// [`Params::discrete_sample_time`] with its period and offset.
    pub fn discrete_clock(&mut self) -> Result<(SampleTime, f64, f64), Diagnostic> {
        if !self.has("sample_time") {
            return Err(self.missing("sample_time"));
        }
        match self.sample_time()? {
            st @ SampleTime::Discrete { period, offset } => Ok((st, period, offset)),
            other => Err(self
                .error("sample_time", format!("this block is discrete: needs a period T > 0, got {other}"))
                .with_hint("write `sample_time: T` or `sample_time: [T, offset]`")),
        }
    }

    /// Reports keys no accessor used (typos, parameters of another type).
    pub fn finish(self) -> Result<(), Diagnostic> {
        let known: Vec<&str> = self.docs.iter().map(|d| d.name).collect();
        for ((key, _), used) in self.entries.iter().zip(&self.used) {
            if !used {
                let message = format!("block `{}` ({}): unknown parameter `{}`", self.block, self.type_name, key.name);
                return Err(Diagnostic::at(&key.pos, message)
                    .suggest(&key.name, known.iter().copied())
                    .or_hint(format!("{} takes: {}", self.type_name, known.join(", "))));
            }
        }
        Ok(())
    }
}

/// Evaluates an expression string to a number; errors point inside it.
pub fn eval_number(src: &str, pos: &Pos, scope: &[(String, f64)]) -> Result<f64, Diagnostic> {
    let expr = Expr::parse(src, &Constants(scope)).map_err(|e| expr_diagnostic(&e, pos))?;
    expr.constant().ok_or_else(|| Diagnostic::at(pos, format!("`{src}` is not a constant")))
}

/// A positioned diagnostic for an error inside an expression written at `pos`.
pub fn expr_diagnostic(e: &ExprError, pos: &Pos) -> Diagnostic {
    let d = Diagnostic::at(&pos.shifted(e.offset), e.message.clone());
    match &e.hint {
        Some(h) => d.with_hint(h.clone()),
        None => d,
    }
}

/// A scope for expressions that also see variables (the `fcn` block).
pub struct VarScope<'a> {
    pub vars: &'a [&'a str],
    pub params: &'a [(String, f64)],
}

impl Scope for VarScope<'_> {
    fn lookup(&self, name: &str) -> Option<crate::expr::Binding> {
        match self.vars.iter().position(|v| *v == name) {
            Some(i) => Some(crate::expr::Binding::Slot(i)),
            None => Constants(self.params).lookup(name),
        }
    }
    fn names(&self) -> Vec<String> {
        self.vars.iter().map(|v| v.to_string()).chain(Constants(self.params).names()).collect()
    }
}
