//! Conditionally executed subsystems: `enable:` and `trigger:` on a
//! subsystem block (Simulink's Enabled, Triggered and Enabled and
//! Triggered Subsystems), read here; [`crate::conditional`] runs them.

use crate::diag::{Diagnostic, Pos};
use crate::spec::BlockSpec;
use crate::yaml::{self, Kind, Yaml};

/// What a subsystem's `enable:` and `trigger:` ask for.
#[derive(Clone, Debug, PartialEq)]
pub struct Condition {
    /// The subsystem's path (`ctrl`, `outer/ctrl`).
    pub path: String,
    pub pos: Pos,
    pub enable: Option<Enable>,
    pub trigger: Option<Edge>,
}

/// `enable: { states: held | reset, outputs: held | reset }`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Enable {
    /// Re-initialise the states when enabled again (else resume from where they were held).
    pub reset_states: bool,
    /// Outputs 0 while disabled (else the last value).
    pub reset_outputs: bool,
}

/// Which edges of the trigger input run a triggered subsystem.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Edge {
    Rising,
    Falling,
    Either,
}

impl Edge {
    /// Simulink's edges: rising from negative to zero or positive, or from
    /// zero to positive; falling the mirror image.
    pub fn between(self, before: f64, now: f64) -> bool {
        let rising = (before < 0.0 && now >= 0.0) || (before == 0.0 && now > 0.0);
        let falling = (before > 0.0 && now <= 0.0) || (before == 0.0 && now < 0.0);
        match self {
            Edge::Rising => rising,
            Edge::Falling => falling,
            Edge::Either => rising || falling,
        }
    }
}

/// The input ports a conditional subsystem gains.
pub const ENABLE_PORT: &str = "enable";
pub const TRIGGER_PORT: &str = "trigger";

/// The subsystem block's `enable:` and `trigger:`, if it has either.
pub(super) fn read(b: &BlockSpec, path: &str) -> Result<Option<Condition>, Diagnostic> {
    let what = format!("block `{path}` (subsystem)");
    let enable = yaml::lookup(&b.params, "enable").map(|v| enable(v, &what)).transpose()?;
    let trigger = yaml::lookup(&b.params, "trigger").map(|v| edge(v, &what)).transpose()?;
    if enable.is_none() && trigger.is_none() {
        return Ok(None);
    }
    Ok(Some(Condition { path: path.to_string(), pos: b.pos.clone(), enable, trigger }))
}

fn enable(v: &Yaml, what: &str) -> Result<Enable, Diagnostic> {
    let held = Enable { reset_states: false, reset_outputs: false };
    let entries = match &v.kind {
        Kind::Bool(true) => return Ok(held),
        Kind::Map(m) => m,
        _ => {
            return Err(Diagnostic::at(
                &v.pos,
                format!("{what}: `enable` must be true or a mapping, found {}", v.describe()),
            )
            .with_hint("enable: { states: held, outputs: held } (held or reset each)"));
        }
    };
    let mut e = held;
    for (k, value) in entries {
        let reset = match value.expect_str(&format!("{what}: `enable.{}`", k.name))? {
            "held" => false,
            "reset" => true,
            other => {
                return Err(Diagnostic::at(
                    &value.pos,
                    format!("{what}: `enable.{}: {other}`: expected held or reset", k.name),
                )
                .suggest(other, ["held", "reset"]));
            }
        };
        match k.name.as_str() {
            "states" => e.reset_states = reset,
            "outputs" => e.reset_outputs = reset,
            other => {
                return Err(Diagnostic::at(&k.pos, format!("{what}: `enable` has no key `{other}`"))
                    .suggest(other, ["states", "outputs"])
                    .or_hint("enable: { states: held | reset, outputs: held | reset }"));
            }
        }
    }
    Ok(e)
}

fn edge(v: &Yaml, what: &str) -> Result<Edge, Diagnostic> {
    match v.expect_str(&format!("{what}: `trigger`"))? {
        "rising" => Ok(Edge::Rising),
        "falling" => Ok(Edge::Falling),
        "either" => Ok(Edge::Either),
        other => Err(Diagnostic::at(&v.pos, format!("{what}: `trigger: {other}`: expected rising, falling or either"))
            .suggest(other, ["rising", "falling", "either"])),
    }
}

/// The inport block standing for a conditional subsystem's `enable` or
/// `trigger` port inside it, at the key's position.
pub(super) fn port_block(b: &BlockSpec, name: &str) -> BlockSpec {
    let pos = yaml::lookup(&b.params, name).map_or_else(|| b.pos.clone(), |v| v.pos.clone());
    BlockSpec {
        name: name.to_string(),
        pos: pos.clone(),
        type_name: super::INPORT.to_string(),
        type_pos: pos,
        params: Vec::new(),
    }
}

/// A wire from the subsystem's inport straight to its outport passes no
/// block that could hold: a unity `gain` (`PORT~held`) goes between, so the
/// outport holds between runs like every other signal of the subsystem
/// (Simulink's sample-and-hold is such a triggered subsystem).
pub(super) fn hold_pass_throughs(
    out: &mut super::FlatGraph,
    path: &str,
    inner: &(Vec<String>, Vec<String>),
    template: &super::FlatBlock,
) {
    let inport = |block: &str| inner.0.iter().any(|p| format!("{path}/{p}") == block);
    let outport = |block: &str| inner.1.iter().find(|p| format!("{path}/{p}") == block).cloned();
    for k in 0..out.wires.len() {
        let (src, dst) = (&out.wires[k].src, &out.wires[k].dst);
        let Some(port) = outport(&dst.block).filter(|_| inport(&src.block)) else { continue };
        let name = format!("{port}~held");
        let spec = BlockSpec {
            name: name.clone(),
            pos: dst.pos.clone(),
            type_name: "gain".into(),
            type_pos: dst.pos.clone(),
            params: Vec::new(),
        };
        let block = format!("{path}/{name}");
        out.blocks.push(super::FlatBlock { path: block.clone(), spec: std::sync::Arc::new(spec), ..template.clone() });
        let into = super::Endpoint { block: block.clone(), port: None, pos: dst.pos.clone() };
        let from = super::Endpoint { block, port: None, pos: out.wires[k].src.pos.clone() };
        let to = std::mem::replace(&mut out.wires[k].dst, into);
        out.wires.push(super::FlatWire { src: from, dst: to });
    }
}

#[cfg(test)]
mod tests {
    use super::Edge;

    #[test]
    fn edges_as_simulink_counts_them() {
        assert!(Edge::Rising.between(-1.0, 0.0) && Edge::Rising.between(0.0, 1.0) && Edge::Rising.between(-1.0, 2.0));
        assert!(!Edge::Rising.between(0.0, 0.0) && !Edge::Rising.between(1.0, 2.0) && !Edge::Rising.between(1.0, -1.0));
        assert!(
            Edge::Falling.between(1.0, 0.0) && Edge::Falling.between(0.0, -1.0) && !Edge::Falling.between(-1.0, 0.0)
        );
        assert!(
            Edge::Either.between(1.0, -1.0) && Edge::Either.between(-1.0, 1.0) && !Edge::Either.between(f64::NAN, 1.0)
        );
    }
}
