//! Loading a graph: reading files, evaluating parameters (with `--set`
//! overrides), reading the simulation settings, and expanding subsystems
//! into one flat list of blocks named `outer/inner`.

use crate::diag::{Diagnostic, Pos};
use crate::params::eval_number;
use crate::spec::{BlockSpec, Endpoint, GraphFile};
use crate::yaml::{self, Key, Kind, Yaml};
use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};
use std::sync::Arc;

mod condition;
mod includes;
mod output;
mod simulation;
pub use condition::{Condition, ENABLE_PORT, Edge, Enable, TRIGGER_PORT};
use includes::{IncludeError, Includes};
pub use output::{MAX_REFINE, OutputTimes};
use simulation::sim_config;
pub use simulation::{Accelerate, AlgebraicLoops, METHODS, SIM_KEYS, SOLVER_KEYS, SimConfig, ZeroCrossing};

/// Block types the loader and compiler treat specially.
pub const SUBSYSTEM: &str = "subsystem";
pub const INPORT: &str = "inport";
pub const OUTPORT: &str = "outport";

/// A block after expansion, with the parameters its file defines.
#[derive(Clone, Debug)]
pub struct FlatBlock {
    /// Full name: `name`, or `sub/name` inside subsystem `sub`.
    pub path: String,
    pub spec: Arc<BlockSpec>,
    pub scope: Arc<Vec<(String, f64)>>,
    pub dir: Arc<PathBuf>,
}

/// A wire between flat blocks; positions are where its ends are written.
#[derive(Clone, Debug)]
pub struct FlatWire {
    pub src: Endpoint,
    pub dst: Endpoint,
}

/// The whole diagram, one level deep.
#[derive(Clone, Debug)]
pub struct FlatGraph {
    pub file: Arc<str>,
    pub name: Option<String>,
    pub description: Option<String>,
    /// Top-level parameters after overrides.
    pub parameters: Vec<(String, f64)>,
    pub sim: SimConfig,
    pub blocks: Vec<FlatBlock>,
    pub wires: Vec<FlatWire>,
    pub records: Vec<crate::spec::RecordSpec>,
    pub record_every: usize,
    /// The top-level file's checks (a subsystem's own checks are not run
    /// when it is included).
    pub checks: Vec<crate::checks::CheckSpec>,
    /// The top-level file's plot panels, evaluated.
    pub scopes: Vec<crate::scope::Scope>,
    /// The top-level file's `analysis:` section.
    pub analysis: Option<crate::spec::Selection>,
    /// Subsystem path → its (inports, outports), for resolving records.
    pub subsystems: HashMap<String, (Vec<String>, Vec<String>)>,
    /// The conditionally executed subsystems, outermost first.
    pub conditions: Vec<Condition>,
}

enum Override {
    /// From the command line: an expression over the earlier parameters.
    Text(String),
    /// From a subsystem block, already evaluated in the outer scope.
    Value(f64),
}

/// Reads and expands the graph at `path`. `overrides` are `--set NAME=VALUE`
/// pairs; naming a parameter the graph does not have is an error.
pub fn load(path: &Path, overrides: &[(String, String)]) -> Result<FlatGraph, Diagnostic> {
    let file: Arc<str> = path.display().to_string().into();
    let text = crate::files::read_text(path, crate::files::MAX_GRAPH_FILE)
        .map_err(|e| Diagnostic::in_file(&file, format!("cannot read: {e}")))?;
    load_str(&text, file, overrides)
}

/// Like [`load`] for text already in memory; `file` names it in messages
/// and locates relative paths.
pub fn load_str(text: &str, file: Arc<str>, overrides: &[(String, String)]) -> Result<FlatGraph, Diagnostic> {
    ParsedGraph::parse(text, file)?.flatten(overrides)
}

/// A graph file parsed once, to be expanded with other parameter values
/// (a sweep's cases) without reading and parsing it again.
pub struct ParsedGraph {
    graph: GraphFile,
    file: Arc<str>,
}

impl ParsedGraph {
    /// Parses `text`; `file` names it in messages and locates relative paths.
    pub fn parse(text: &str, file: Arc<str>) -> Result<Self, Diagnostic> {
        Ok(ParsedGraph { graph: GraphFile::parse(text, file.clone())?, file })
    }

    /// Evaluates its parameters with `overrides` (`--set NAME=VALUE`
    /// pairs) and expands it, as [`load_str`] does.
    pub fn flatten(&self, overrides: &[(String, String)]) -> Result<FlatGraph, Diagnostic> {
        flatten(&self.graph, self.file.clone(), overrides)
    }
}

fn flatten(graph: &GraphFile, file: Arc<str>, overrides: &[(String, String)]) -> Result<FlatGraph, Diagnostic> {
    let known: Vec<&str> = graph.parameters.iter().map(|(k, _)| k.name.as_str()).collect();
    for (name, _) in overrides {
        if !known.contains(&name.as_str()) {
            let list = if known.is_empty() { "none".to_string() } else { known.join(", ") };
            return Err(Diagnostic::plain(format!("--set {name}: {file} has no parameter `{name}`"))
                .suggest(name, known.iter().copied())
                .or_hint(format!("its parameters: {list}")));
        }
    }
    let ovr: Vec<(String, Override, Option<Pos>)> =
        overrides.iter().map(|(n, v)| (n.clone(), Override::Text(v.clone()), None)).collect();
    let scope = Arc::new(eval_parameters(&graph.parameters, &ovr)?);
    let sim = sim_config(graph.simulation.as_ref(), &scope)?;
    let dir = Arc::new(Path::new(&*file).parent().map(Path::to_path_buf).unwrap_or_default());
    let mut out = FlatGraph {
        file: file.clone(),
        name: graph.name.clone(),
        description: graph.description.clone(),
        parameters: scope.to_vec(),
        sim,
        blocks: Vec::new(),
        wires: Vec::new(),
        records: Vec::new(),
        record_every: graph.record_every.as_ref().map_or(1, |e| e.0),
        checks: graph.checks.clone(),
        scopes: Vec::new(),
        analysis: graph.analysis.clone(),
        subsystems: HashMap::new(),
        conditions: Vec::new(),
    };
    let number = |v: &Yaml, key: &str| -> Result<f64, Diagnostic> {
        match &v.kind {
            Kind::Num(x) => Ok(*x),
            Kind::Str(s) => eval_number(s, &v.pos, &scope),
            _ => Err(Diagnostic::at(&v.pos, format!("scope `{key}`: expected a number, found {}", v.describe()))),
        }
    };
    out.scopes = graph.scopes.iter().map(|s| s.evaluate(&number)).collect::<Result<_, _>>()?;
    let mut includes = Includes::new(canonical(Path::new(&*file)));
    expand(graph, "", scope, dir, &mut out, &mut includes)?;
    out.records = graph.record.clone();
    Ok(out)
}

fn canonical(p: &Path) -> PathBuf {
    p.canonicalize().unwrap_or_else(|_| p.to_path_buf())
}

fn eval_parameters(
    defs: &[(Key, Yaml)],
    overrides: &[(String, Override, Option<Pos>)],
) -> Result<Vec<(String, f64)>, Diagnostic> {
    let mut scope: Vec<(String, f64)> = Vec::new();
    for (key, value) in defs {
        // `pi` and `inf` are constants of every expression, `t` is time in `fcn`.
        if ["pi", "inf", "t"].contains(&key.name.as_str()) {
            return Err(Diagnostic::at(&key.pos, format!("parameter `{}`: the name is reserved", key.name))
                .with_hint("`pi` and `inf` are built-in constants and `t` is time in `fcn`: choose another name"));
        }
        let v = match overrides.iter().find(|(n, _, _)| *n == key.name) {
            Some((_, Override::Value(v), _)) => *v,
            Some((name, Override::Text(text), _)) => {
                let at = Pos::new(format!("--set {name}=").into(), 1, 1);
                eval_number(text, &at, &scope).map_err(|d| {
                    Diagnostic::plain(format!("--set {name}={text}: {}", d.message))
                        .with_hint(d.hint.unwrap_or_default())
                })?
            }
            None => match &value.kind {
                Kind::Num(v) => *v,
                Kind::Str(s) => eval_number(s, &value.pos, &scope)
                    .map_err(|d| Diagnostic { message: format!("parameter `{}`: {}", key.name, d.message), ..d })?,
                _ => {
                    return Err(Diagnostic::at(
                        &value.pos,
                        format!(
                            "parameter `{}` must be a number or an expression, found {}",
                            key.name,
                            value.describe()
                        ),
                    ));
                }
            },
        };
        if v.is_nan() {
            return Err(Diagnostic::at(&value.pos, format!("parameter `{}` is not a number (NaN)", key.name)));
        }
        scope.push((key.name.clone(), v));
    }
    Ok(scope)
}

fn check_keys(entries: &[(Key, Yaml)], known: &[&str], section: &str) -> Result<(), Diagnostic> {
    for (k, _) in entries {
        if !known.contains(&k.name.as_str()) {
            return Err(Diagnostic::at(&k.pos, format!("unknown key `{}` in `{section}`", k.name))
                .suggest(&k.name, known.iter().copied())
                .or_hint(format!("`{section}` takes: {}", known.join(", "))));
        }
    }
    Ok(())
}

/// A subsystem's ports: the names of its inport and outport blocks, in order.
fn sub_ports(g: &GraphFile) -> (Vec<String>, Vec<String>) {
    let of = |ty: &str| g.blocks.iter().filter(|b| b.type_name == ty).map(|b| b.name.clone()).collect();
    (of(INPORT), of(OUTPORT))
}

/// The most blocks a graph may expand to (subsystems flattened).
pub const MAX_BLOCKS: usize = 1_000_000;

/// The deepest chain of subsystems including subsystems.
pub const MAX_DEPTH: usize = 64;

/// The most fixed steps or sample hits a run may need (1e10: hours of
/// stepping even for a small graph); a finer step or period is refused.
pub const MAX_STEPS: f64 = 1e10;

fn expand(
    g: &GraphFile,
    prefix: &str,
    scope: Arc<Vec<(String, f64)>>,
    dir: Arc<PathBuf>,
    out: &mut FlatGraph,
    includes: &mut Includes,
) -> Result<(), Diagnostic> {
    let mut subs: HashMap<&str, (Vec<String>, Vec<String>)> = HashMap::new();
    for b in &g.blocks {
        let path = format!("{prefix}{}", b.name);
        if b.type_name != SUBSYSTEM {
            // Includes are sized before they expand (`load_subsystem`), so
            // this is reached by blocks written out one by one.
            if out.blocks.len() >= MAX_BLOCKS {
                return Err(Diagnostic::at(
                    &b.pos,
                    format!("the graph expands to more than {MAX_BLOCKS} blocks (here, at `{path}`)"),
                ));
            }
            out.blocks.push(FlatBlock { path, spec: b.clone(), scope: scope.clone(), dir: dir.clone() });
            continue;
        }
        let condition = condition::read(b, &path)?;
        let at = out.conditions.len();
        let mut inner = load_subsystem(b, &path, &scope, &dir, out, includes)?;
        if let Some(c) = condition {
            // Its `enable` and `trigger` ports: inports of its own.
            let ports = [(c.enable.is_some(), ENABLE_PORT), (c.trigger.is_some(), TRIGGER_PORT)];
            for name in ports.iter().filter(|p| p.0).map(|p| p.1) {
                if inner.0.iter().any(|p| p == name) {
                    let message = format!("block `{path}` (subsystem): its file has an inport `{name}` already");
                    return Err(Diagnostic::at(&b.pos, message)
                        .with_hint(format!("`{name}:` adds that port: rename the inport")));
                }
                let spec = Arc::new(condition::port_block(b, name));
                out.blocks.push(FlatBlock {
                    path: format!("{path}/{name}"),
                    spec,
                    scope: scope.clone(),
                    dir: dir.clone(),
                });
                inner.0.push(name.to_string());
            }
            let template = FlatBlock { path: String::new(), spec: b.clone(), scope: scope.clone(), dir: dir.clone() };
            condition::hold_pass_throughs(out, &path, &inner, &template);
            // Outer before inner: the inner ones were pushed while loading.
            out.conditions.insert(at, c);
        }
        subs.insert(&b.name, inner.clone());
        out.subsystems.insert(path, inner);
    }
    let names: HashSet<&str> = g.blocks.iter().map(|b| b.name.as_str()).collect();
    let resolve = |ep: &Endpoint, is_src: bool| -> Result<Endpoint, Diagnostic> {
        if !names.contains(ep.block.as_str()) {
            return Err(Diagnostic::at(&ep.pos, format!("wire: no block named `{}`", ep.block))
                .suggest(&ep.block, g.blocks.iter().map(|b| b.name.as_str())));
        }
        let Some((ins, outs)) = subs.get(ep.block.as_str()) else {
            return Ok(Endpoint { block: format!("{prefix}{}", ep.block), ..ep.clone() });
        };
        let (ports, side) = if is_src { (outs, "outport") } else { (ins, "inport") };
        let port = resolve_sub_port(ep, ports, side)?;
        Ok(Endpoint { block: format!("{prefix}{}/{port}", ep.block), port: None, pos: ep.pos.clone() })
    };
    for w in &g.wires {
        let src = resolve(&w.src, true)?;
        for d in &w.dsts {
            out.wires.push(FlatWire { src: src.clone(), dst: resolve(d, false)? });
        }
    }
    Ok(())
}

/// Which inport/outport block of a subsystem an endpoint means.
pub fn resolve_sub_port<'a>(ep: &Endpoint, ports: &'a [String], side: &str) -> Result<&'a str, Diagnostic> {
    match &ep.port {
        Some(p) => ports.iter().find(|n| *n == p).map(String::as_str).ok_or_else(|| {
            Diagnostic::at(&ep.pos, format!("subsystem `{}` has no {side} `{p}`", ep.block))
                .suggest(p, ports.iter().map(String::as_str))
        }),
        None if ports.len() == 1 => Ok(&ports[0]),
        None => Err(Diagnostic::at(
            &ep.pos,
            format!("subsystem `{}` has {} {side}s: name one as `{}.PORT`", ep.block, ports.len(), ep.block),
        )
        .with_hint(format!("{side}s: {}", ports.join(", ")))),
    }
}

const SUBSYSTEM_KEYS: [&str; 5] = ["type", "file", "parameters", "enable", "trigger"];

fn load_subsystem(
    b: &BlockSpec,
    path: &str,
    scope: &[(String, f64)],
    dir: &Path,
    out: &mut FlatGraph,
    includes: &mut Includes,
) -> Result<(Vec<String>, Vec<String>), Diagnostic> {
    let what = format!("block `{path}` (subsystem)");
    check_keys(&b.params, &SUBSYSTEM_KEYS, &what)?;
    let Some(file_v) = yaml::lookup(&b.params, "file") else {
        return Err(Diagnostic::at(&b.pos, format!("{what}: missing parameter `file`"))
            .with_hint("the graph file to include, relative to this file"));
    };
    let rel = file_v.expect_str(&format!("{what}: `file`"))?;
    let sub_path = dir.join(rel);
    let sub_file: Arc<str> = sub_path.display().to_string().into();
    let canon = canonical(&sub_path);
    if includes.stack.contains(&canon) {
        return Err(Diagnostic::at(&file_v.pos, format!("{what}: `{sub_file}` includes itself")));
    }
    let sub = includes.parse(&sub_path, &canon).map_err(|e| match e {
        IncludeError::Read(e) => Diagnostic::at(&file_v.pos, format!("{what}: cannot read `{sub_file}`: {e}")),
        IncludeError::Parse(d) => d,
    })?;
    if let Some(n) = includes.expanded_size(&sub, &canon, &sub_path)
        && out.blocks.len() + n > MAX_BLOCKS
    {
        return Err(Diagnostic::at(
            &b.pos,
            format!("{what}: `{sub_file}` expands to {n} blocks, past the limit of {MAX_BLOCKS} for the whole graph"),
        )
        .with_hint("subsystems included many times over multiply: look for an include chain that doubles"));
    }
    let known: Vec<&str> = sub.parameters.iter().map(|(k, _)| k.name.as_str()).collect();
    let mut overrides = Vec::new();
    if let Some(p) = yaml::lookup(&b.params, "parameters") {
        for (k, v) in p.expect_map(&format!("{what}: `parameters`"))? {
            if !known.contains(&k.name.as_str()) {
                return Err(Diagnostic::at(&k.pos, format!("{what}: `{sub_file}` has no parameter `{}`", k.name))
                    .suggest(&k.name, known.iter().copied()));
            }
            let value = match &v.kind {
                Kind::Num(x) => *x,
                Kind::Str(s) => eval_number(s, &v.pos, scope)?,
                _ => {
                    return Err(Diagnostic::at(&v.pos, format!("{what}: parameter `{}` must be a number", k.name)));
                }
            };
            overrides.push((k.name.clone(), Override::Value(value), Some(k.pos.clone())));
        }
    }
    let sub_scope = Arc::new(eval_parameters(&sub.parameters, &overrides)?);
    let sub_dir = Arc::new(sub_path.parent().map(Path::to_path_buf).unwrap_or_default());
    if includes.stack.len() >= MAX_DEPTH {
        return Err(Diagnostic::at(&b.pos, format!("{what}: subsystems nested too deeply (limit {MAX_DEPTH})")));
    }
    includes.stack.push(canon);
    expand(&sub, &format!("{path}/"), sub_scope, sub_dir, out, includes)?;
    includes.stack.pop();
    Ok(sub_ports(&sub))
}

/// Splits a command-line `NAME=VALUE`.
pub fn parse_set(arg: &str) -> Result<(String, String), Diagnostic> {
    match arg.split_once('=') {
        Some((n, v)) if !n.trim().is_empty() && !v.trim().is_empty() => {
            Ok((n.trim().to_string(), v.trim().to_string()))
        }
        _ => Err(Diagnostic::plain(format!("--set {arg}: expected NAME=VALUE"))),
    }
}
