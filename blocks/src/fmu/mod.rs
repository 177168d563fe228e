//! The `fmu` block: an FMU (FMI 3.0 or 2.0) inside a graph — a plant from
//! Modelica, Simulink or any FMI exporter. Model exchange is `me.rs`.
//!
//! Co-simulation semantics (as Simulink's FMU block in that mode): a discrete
//! block at `sample_time` T. At each hit t_k it outputs the FMU's outputs
//! at t_k, then (its update) sets the FMU's inputs to their values at t_k
//! and calls `doStep(t_k, T)`: inputs are held over each step, and the
//! block has no direct feedthrough (an output at t_k does not see the
//! input at t_k), so it closes loops without an algebraic loop. The FMU
//! is instantiated, its parameters set and initialised at the run's start,
//! one instance per run; a snapshot of the run copies the FMU's state
//! (FMI's serialised state, where the FMU can give it).

mod archive;
mod binding;
mod binding_me;
mod cs;
mod description;
mod me;

use crate::table::*;
use binding::Binary;
use cs::FmuBlock;
use ctlgraph_core::registry::{BlockType, Built};
use ctlgraph_core::{Diagnostic, Interface, Params, Width};
use description::{Causality, Description, Variable};
use std::path::PathBuf;
use std::sync::Arc;

pub const TYPES: &[BlockType] = &[BlockType {
    name: "fmu",
    category: "co-simulation",
    summary: "An FMU (FMI 3.0 or 2.0, co-simulation or model exchange): a plant or controller from another tool.",
    doc: "Loads `file` (an .fmu, relative to the graph), unpacked once into ctlgraph's cache \
          (`$CTLGRAPH_CACHE_DIR`, …/fmus/<hash>), and runs its binary for this platform. Ports: the \
          FMU's real inputs and outputs (`Float64`, FMI 2 `Real`), named by the variables (characters \
          other than letters, digits and _ become _), arrays as vectors; `inputs`/`outputs` select and \
          order them. `parameters` sets the FMU's parameters before initialisation (values may be \
          expressions of the graph's parameters). `mode: cs`, co-simulation (Simulink's FMU block): a \
          discrete block; at each hit t_k of `sample_time` (default: the FMU's DefaultExperiment \
          stepSize) the outputs are the FMU's at t_k, then the inputs at t_k are set and doStep(t_k, T) \
          runs, inputs held over the step — no direct feedthrough. `mode: me`, model exchange: a \
          continuous block whose states are the FMU's continuous states, integrated by the graph's \
          solver (TR-BDF2's Jacobian by finite differences); its event indicators are zero crossings, \
          located like any block's; its time events are major steps; at each major step \
          completedIntegratorStep is called and, at an event, the discrete states are updated until \
          the FMU needs no more (FMI 3.0 §3.2) and the states it resets taken; inputs feed through. \
          A discarded step, an early return or an error status stops the run, naming the block, with \
          what the FMU logged. `ctlgraph check` lists the FMU's variables.",
    inputs: &[PortDoc { name: "(the FMU's inputs)", doc: "one port per selected input variable" }],
    outputs: &[PortDoc { name: "(the FMU's outputs)", doc: "one port per selected output variable" }],
    params: &[
        param("file", Required, "the FMU, relative to the graph file"),
        param(
            "mode",
            Word("cs"),
            "cs: co-simulation (the FMU's own solver between hits); me: model exchange (ctlgraph's solver)",
        )
        .options(&["cs", "me"]),
        param(
            "sample_time",
            Described("the FMU's DefaultExperiment stepSize"),
            "T > 0, or [T, offset]: the communication step",
        )
        .kind(ParamKind::SampleTime),
        param("parameters", Described("none"), "{ name: value, … }: the FMU's parameters, set before initialisation")
            .kind(ParamKind::Structure),
        param("inputs", Described("every real input"), "the FMU's inputs to connect, in port order")
            .kind(ParamKind::Words),
        param("outputs", Described("every real output"), "the FMU's outputs to connect, in port order")
            .kind(ParamKind::Words),
    ],
    build: build_fmu,
}];

use ctlgraph_core::registry::PortDoc;

/// An FMU loaded for the blocks that use it: its binary, description and
/// resources.
pub(super) struct Loaded {
    binary: Arc<Binary>,
    description: Description,
    resources: PathBuf,
    /// Whether the interface used can get, set and serialise its state
    /// (what copying a run's instance needs).
    can_copy_state: bool,
}

/// A selected port: its name, the variable's value reference and size
/// (an FMI 3 array is one reference for all its elements).
struct Port {
    name: String,
    reference: u32,
    size: usize,
}

fn build_fmu(p: &mut Params) -> Result<Built, Diagnostic> {
    let path = p.path("file")?;
    let me = p.choice("mode", &["cs", "me"])? == "me";
    let loaded = load(&path, me).map_err(|e| {
        let d = p.error("file", format!("`{}`: {e}", path.display()));
        // An FMU exported from a graph beside it (as graphs/fmu's): say how.
        match path.with_extension("yaml") {
            graph if !path.exists() && graph.is_file() => d.with_hint(format!(
                "export it from the graph beside it: ctlgraph fmu {} --out {}",
                graph.display(),
                path.display()
            )),
            _ => d,
        }
    })?;
    let d = &loaded.description;
    let inputs = select(p, d, "inputs", Causality::Input)?;
    let outputs = select(p, d, "outputs", Causality::Output)?;
    let parameters = parameters(p, d)?;
    let common = Common {
        name: p.block_name().to_string(),
        // Where the block is written, for the errors the FMU gives at run time.
        at: p.block_error("").pos.map(|pos| pos.to_string()).unwrap_or_default(),
        token: d.token.clone(),
        can_copy_state: loaded.can_copy_state,
        input_refs: inputs.iter().map(|p| p.reference).collect(),
        input_len: inputs.iter().map(|p| p.size).sum(),
        output_refs: outputs.iter().map(|p| p.reference).collect(),
        output_len: outputs.iter().map(|p| p.size).sum(),
        parameters,
        report: String::new(),
        loaded: Arc::new(loaded),
    };
    let d = &common.loaded.description;
    if me {
        let interface = d.model_exchange.as_ref().ok_or_else(|| no_interface(p, &path, "model exchange"))?;
        let (n_states, n_indicators) = (interface.states, interface.event_indicators);
        let iface = interface_of(ctlgraph_core::SampleTime::Continuous, &inputs, &outputs, true);
        let shared = me::Shared { common: Common { report: report(d, &path, None), ..common }, n_states, n_indicators };
        // Instantiated and initialised once now, so that what fails there
        // (the parameters, the FMU's own checks) is reported at the block.
        if let Err(e) = shared.instantiate(None) {
            return Err(at_initialisation(p, e));
        }
        let block = me::MeBlock { shared, next_time: f64::INFINITY, located: false, run: None };
        return Ok(Built::new(block, iface));
    }
    d.co_simulation.as_ref().ok_or_else(|| no_interface(p, &path, "co-simulation"))?;
    let (st, period, offset) = if p.has("sample_time") {
        p.discrete_clock()?
    } else {
        let step = d
            .default_step
            .ok_or_else(|| p.block_error("the FMU gives no DefaultExperiment stepSize: set `sample_time: T`"))?;
        (ctlgraph_core::SampleTime::Discrete { period: step, offset: 0.0 }, step, 0.0)
    };
    let common = Common { report: report(d, &path, Some(period)), ..common };
    let block = FmuBlock { common, period, offset, run: None };
    if let Err(e) = block.common.instance(offset) {
        return Err(at_initialisation(p, e));
    }
    Ok(Built::new(block, interface_of(st, &inputs, &outputs, false).piecewise_constant()))
}

/// The block's ports: the selected inputs (feeding through or not) and outputs.
fn interface_of(st: ctlgraph_core::SampleTime, inputs: &[Port], outputs: &[Port], feedthrough: bool) -> Interface {
    let mut iface = Interface::new(st);
    for port in inputs {
        iface = iface.input(&port.name, Width::Fixed(port.size), feedthrough);
    }
    for port in outputs {
        iface = iface.output(&port.name, Width::Fixed(port.size));
    }
    iface
}

/// What a block of either mode was built with.
#[derive(Clone)]
pub(super) struct Common {
    pub name: String,
    /// `file:line:col` of the block, for errors at run time.
    pub at: String,
    pub token: String,
    /// Whether the FMU can copy its state (what a snapshot of a run needs).
    pub can_copy_state: bool,
    pub loaded: Arc<Loaded>,
    /// The selected variables' value references, and how many numbers they hold.
    pub input_refs: Vec<u32>,
    pub input_len: usize,
    pub output_refs: Vec<u32>,
    pub output_len: usize,
    pub parameters: Vec<(u32, Vec<f64>)>,
    /// What `ctlgraph check` prints.
    pub report: String,
}

impl Common {
    /// A new instance from `start`, its parameters set and initialised.
    pub fn instance(&self, start: f64) -> Result<binding::Instance, String> {
        let mut i = binding::Instance::new(&self.loaded.binary, &self.name, &self.token, &self.loaded.resources)?;
        i.enter_initialization(start)?;
        for (reference, values) in &self.parameters {
            i.set(&[*reference], values)?;
        }
        i.exit_initialization()?;
        Ok(i)
    }

    /// Why the block's output is NaN, when its instance failed.
    pub fn diagnose(&self, instance: &Result<binding::Instance, String>) -> Option<String> {
        match instance {
            Err(e) if e != NOT_YET_RESTORED => Some(format!("the FMU ({}): {e}", self.at)),
            _ => None,
        }
    }
}

/// An instantiation or initialisation that failed while building: at the
/// block's `parameters` when it has them (they are what initialisation
/// takes from the graph), else at its `file`.
fn at_initialisation(p: &Params, error: String) -> Diagnostic {
    let key = if p.has("parameters") { "parameters" } else { "file" };
    p.error(key, format!("the FMU does not initialise: {error}"))
}

/// The error for an FMU without the interface `mode` asks for.
fn no_interface(p: &Params, path: &std::path::Path, interface: &str) -> Diagnostic {
    let other = if interface == "co-simulation" { "me" } else { "cs" };
    p.error("file", format!("`{}` has no {interface} interface", path.display()))
        .with_hint(format!("its other interface: `mode: {other}`"))
}

/// The FMU at `path`, unpacked, described and its binary loaded for
/// co-simulation or (`me`) model exchange.
fn load(path: &std::path::Path, me: bool) -> Result<Loaded, String> {
    let dir = archive::unpacked(path)?;
    let text =
        std::fs::read_to_string(dir.join("modelDescription.xml")).map_err(|e| format!("modelDescription.xml: {e}"))?;
    let description = description::parse(&text)?;
    let identifier = match (me, &description.co_simulation, &description.model_exchange) {
        (false, Some(cs), _) => cs.model_identifier.clone(),
        (true, _, Some(m)) => m.model_identifier.clone(),
        (false, None, _) => return Err("no co-simulation interface (for model exchange: `mode: me`)".into()),
        (true, _, None) => return Err("no model-exchange interface (for co-simulation: `mode: cs`)".into()),
    };
    let folder = match description.version {
        description::Version::Fmi3 => "x86_64-linux",
        description::Version::Fmi2 => "linux64",
    };
    let binary_path = dir.join("binaries").join(folder).join(format!("{identifier}.so"));
    if !binary_path.is_file() {
        let platforms: Vec<String> = std::fs::read_dir(dir.join("binaries"))
            .map(|r| r.filter_map(|e| e.ok()).map(|e| e.file_name().to_string_lossy().into_owned()).collect())
            .unwrap_or_default();
        return Err(format!(
            "no binary for this platform ({folder}/{identifier}.so); the FMU has binaries for: {}",
            if platforms.is_empty() { "none (a source-only FMU)".to_string() } else { platforms.join(", ") }
        ));
    }
    let can_copy_state = match (me, &description.co_simulation) {
        (false, Some(cs)) => cs.can_get_and_set_state && cs.can_serialize_state,
        _ => description.can_get_and_set_state && description.can_serialize_state,
    };
    let binary = Binary::load(&binary_path, description.version, can_copy_state, me)?;
    Ok(Loaded { binary, description, resources: dir.join("resources"), can_copy_state })
}

/// A port name from a variable name: letters, digits and _ kept.
fn port_name(variable: &str) -> String {
    variable.chars().map(|c| if c.is_ascii_alphanumeric() || c == '_' { c } else { '_' }).collect()
}

/// The ports `key` selects (all the real variables of `causality` when not given).
fn select(p: &mut Params, d: &Description, key: &str, causality: Causality) -> Result<Vec<Port>, Diagnostic> {
    let candidates: Vec<&Variable> = d.variables.iter().filter(|v| v.causality == causality).collect();
    let chosen: Vec<&Variable> = if p.has(key) {
        let mut chosen = Vec::new();
        for name in p.strings(key)? {
            let Some(v) = candidates.iter().find(|v| v.name == name || port_name(&v.name) == name) else {
                let names: Vec<&str> = candidates.iter().map(|v| v.name.as_str()).collect();
                return Err(p
                    .error(key, format!("the FMU has no {} `{name}`", causality.name()))
                    .suggest(name, names.iter().copied())
                    .or_hint(format!(
                        "its {}s: {}",
                        causality.name(),
                        if names.is_empty() { "none".into() } else { names.join(", ") }
                    )));
            };
            if !v.is_real() {
                return Err(
                    p.error(key, format!("`{name}` is {}: the block connects real variables only", v.type_name))
                );
            }
            chosen.push(*v);
        }
        chosen
    } else {
        candidates.into_iter().filter(|v| v.is_real()).collect()
    };
    let mut ports: Vec<Port> = Vec::new();
    for v in chosen {
        let name = port_name(&v.name);
        if ports.iter().any(|q| q.name == name) {
            return Err(p.error(key, format!("two of the FMU's {}s are the port `{name}`", causality.name())));
        }
        ports.push(Port { name, reference: v.value_reference, size: v.size });
    }
    Ok(ports)
}

/// `parameters:`: each name the FMU's (a did-you-mean otherwise), each
/// value a number, expression or list (an array).
fn parameters(p: &mut Params, d: &Description) -> Result<Vec<(u32, Vec<f64>)>, Diagnostic> {
    let Some(map) = p.raw("parameters") else { return Ok(Vec::new()) };
    let entries = map.expect_map("`parameters`")?;
    let settable = |v: &&Variable| matches!(v.causality, Causality::Parameter | Causality::Input) && v.is_real();
    let names: Vec<&str> = d.variables.iter().filter(settable).map(|v| v.name.as_str()).collect();
    let mut out = Vec::new();
    for (key, value) in entries {
        let Some(v) = d.variables.iter().filter(settable).find(|v| v.name == key.name) else {
            let kind = d.variables.iter().find(|v| v.name == key.name).map(|v| {
                format!(
                    " (it is {} {} of type {})",
                    if v.causality == Causality::Input { "an" } else { "a" },
                    v.causality.name(),
                    v.type_name
                )
            });
            return Err(Diagnostic::at(
                &key.pos,
                format!(
                    "block `{}` (fmu): the FMU has no real parameter `{}`{}",
                    p.block_name(),
                    key.name,
                    kind.unwrap_or_default()
                ),
            )
            .suggest(&key.name, names.iter().copied())
            .or_hint(format!("its parameters: {}", names.join(", "))));
        };
        let values = match &value.kind {
            ctlgraph_core::yaml::Kind::Seq(items) => {
                items.iter().map(|item| p.number_value("parameters", item)).collect::<Result<Vec<_>, _>>()?
            }
            _ => vec![p.number_value("parameters", value)?],
        };
        if values.len() != v.size {
            return Err(Diagnostic::at(
                &value.pos,
                format!(
                    "block `{}` (fmu): parameter `{}` holds {} value(s), given {}",
                    p.block_name(),
                    v.name,
                    v.size,
                    values.len()
                ),
            ));
        }
        out.push((v.value_reference, values));
    }
    Ok(out)
}

/// What `ctlgraph check` prints: the FMU and its variables.
fn report(d: &Description, path: &std::path::Path, period: Option<f64>) -> String {
    let version = match d.version {
        description::Version::Fmi3 => "3.0",
        description::Version::Fmi2 => "2.0",
    };
    let how = match period {
        Some(period) => format!("co-simulation, step {period} s"),
        None => match &d.model_exchange {
            Some(me) => format!("model exchange, {} states, {} event indicators", me.states, me.event_indicators),
            None => "model exchange".to_string(),
        },
    };
    let file = path.file_name().map(|f| f.to_string_lossy().into_owned()).unwrap_or_default();
    let mut lines = vec![format!("FMU `{}` (FMI {version}, {how}), `{file}`; variables:", d.model_name)];
    for v in d.variables.iter().filter(|v| v.causality != Causality::Local) {
        let size = if v.size > 1 { format!("[{}]", v.size) } else { String::new() };
        let unit = v.unit.as_ref().map(|u| format!(" [{u}]")).unwrap_or_default();
        let start = v.start.as_ref().map(|s| format!(", start {s:?}")).unwrap_or_default();
        lines.push(format!("    {}{size}: {} {}{unit}{start}", v.name, v.causality.name(), v.type_name));
    }
    lines.join("\n")
}

/// A copy's instance before its first use (never seen: it is made then).
const NOT_YET_RESTORED: &str = "a copy's instance, not yet restored";

/// What a copy of a run's instance starts from (a snapshot of the run, in
/// either mode): no instance yet, and the FMU's state serialised now, to
/// be restored into a new instance when the copy is first used — or why
/// it cannot be copied.
fn copy_of(
    instance: &Result<binding::Instance, String>,
    pending: &Option<Vec<u8>>,
    can_copy_state: bool,
) -> (Result<binding::Instance, String>, Option<Vec<u8>>) {
    let state = match (instance, pending) {
        // A copy not yet used: its state, again.
        (_, Some(bytes)) => Ok(bytes.clone()),
        (Ok(i), None) if can_copy_state => i.serialize(),
        (Ok(_), None) => Err("the FMU cannot save and restore its state (canGetAndSetFMUState or \
                             canSerializeFMUState is false): a snapshot of this run cannot copy it"
            .to_string()),
        (Err(e), None) => Err(e.clone()),
    };
    match state {
        Ok(bytes) => (Err(NOT_YET_RESTORED.to_string()), Some(bytes)),
        Err(e) => (Err(e), None),
    }
}
