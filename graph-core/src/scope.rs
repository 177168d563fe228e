//! `scopes:`: the plot panels a graph file asks for, as Simulink users
//! configure their scopes in the diagram — which recorded signals share an
//! axis, the title, the y label and unit, y limits, a time window, and a
//! tolerance band to shade.

use crate::diag::{Diagnostic, Pos};
use crate::yaml::{self, Kind, Yaml};

/// One panel as written, numbers still unevaluated (they may be
/// expressions over the parameters).
#[derive(Clone, Debug)]
pub struct ScopeSpec {
    pub pos: Pos,
    pub title: Option<String>,
    /// Recorded names, with where each is written.
    pub signals: Vec<(String, Pos)>,
    pub y_label: Option<String>,
    pub unit: Option<String>,
    pub y_limits: Option<Yaml>,
    pub window: Option<Yaml>,
    pub band: Option<Yaml>,
}

/// One panel, evaluated.
#[derive(Clone, Debug, PartialEq)]
pub struct Scope {
    pub pos: Pos,
    pub title: Option<String>,
    pub signals: Vec<(String, Pos)>,
    pub y_label: Option<String>,
    pub unit: Option<String>,
    pub y_limits: Option<[f64; 2]>,
    pub window: Option<[f64; 2]>,
    /// A band [lo, hi] drawn across the panel (a tolerance, a spec).
    pub band: Option<[f64; 2]>,
}

/// The keys of a scope.
pub const KEYS: [&str; 7] = ["title", "signals", "y_label", "unit", "y_limits", "window", "band"];

/// Parses the `scopes:` list.
pub fn parse(v: &Yaml) -> Result<Vec<ScopeSpec>, Diagnostic> {
    let items = match &v.kind {
        Kind::Seq(items) => items.as_slice(),
        Kind::Null => &[],
        _ => return Err(Diagnostic::at(&v.pos, format!("`scopes` must be a list of panels, found {}", v.describe()))),
    };
    items.iter().map(parse_one).collect()
}

fn parse_one(item: &Yaml) -> Result<ScopeSpec, Diagnostic> {
    let m = item.expect_map("a scope")?;
    for (k, _) in m {
        if !KEYS.contains(&k.name.as_str()) {
            return Err(Diagnostic::at(&k.pos, format!("unknown key `{}` in a scope", k.name))
                .suggest(&k.name, KEYS)
                .or_hint(format!("a scope takes: {}", KEYS.join(", "))));
        }
    }
    let text = |key: &str| -> Result<Option<String>, Diagnostic> {
        yaml::lookup(m, key).map(|v| v.expect_str(&format!("scope `{key}`")).map(str::to_string)).transpose()
    };
    let Some(list) = yaml::lookup(m, "signals") else {
        return Err(Diagnostic::at(&item.pos, "a scope needs `signals: [name, ...]` (recorded names)"));
    };
    let signals = match &list.kind {
        Kind::Seq(s) if !s.is_empty() => s.as_slice(),
        Kind::Str(_) => std::slice::from_ref(list),
        _ => return Err(Diagnostic::at(&list.pos, "`signals` must list at least one recorded name")),
    };
    let signals = signals
        .iter()
        .map(|s| s.expect_str("a recorded name").map(|n| (n.trim().to_string(), s.pos.clone())))
        .collect::<Result<_, _>>()?;
    Ok(ScopeSpec {
        pos: item.pos.clone(),
        title: text("title")?,
        signals,
        y_label: text("y_label")?,
        unit: text("unit")?,
        y_limits: yaml::lookup(m, "y_limits").cloned(),
        window: yaml::lookup(m, "window").cloned(),
        band: yaml::lookup(m, "band").cloned(),
    })
}

impl ScopeSpec {
    /// Evaluates the numbers with `number` (the graph's parameter scope).
    pub fn evaluate(&self, number: &dyn Fn(&Yaml, &str) -> Result<f64, Diagnostic>) -> Result<Scope, Diagnostic> {
        let pair = |v: &Option<Yaml>, key: &str| -> Result<Option<[f64; 2]>, Diagnostic> {
            let Some(v) = v else { return Ok(None) };
            let items = match &v.kind {
                Kind::Seq(items) if items.len() == 2 => items,
                _ => return Err(Diagnostic::at(&v.pos, format!("scope `{key}` must be [low, high]"))),
            };
            let (lo, hi) = (number(&items[0], key)?, number(&items[1], key)?);
            if !(lo < hi && lo.is_finite() && hi.is_finite()) {
                return Err(Diagnostic::at(
                    &v.pos,
                    format!("scope `{key}` must be finite with low < high, got [{lo}, {hi}]"),
                ));
            }
            Ok(Some([lo, hi]))
        };
        Ok(Scope {
            pos: self.pos.clone(),
            title: self.title.clone(),
            signals: self.signals.clone(),
            y_label: self.y_label.clone(),
            unit: self.unit.clone(),
            y_limits: pair(&self.y_limits, "y_limits")?,
            window: pair(&self.window, "window")?,
            band: pair(&self.band, "band")?,
        })
    }
}
