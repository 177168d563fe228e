//! The FMU's variables, derived from the compiled graph in one place for
//! both sides: `ctlgraph fmu` writes them into `modelDescription.xml`, and
//! the FMU's binary, compiling the same graph, maps the value references
//! the importer passes back to the same signals.
//!
//! What maps to what:
//! - the graph's top-level `inport` blocks are inputs, named by the block,
//!   starting from the block's `value`;
//! - its top-level `outport` blocks are outputs; a graph without any has
//!   its recorded signals (`record:`) as outputs instead, so that a closed
//!   loop exported whole (a test bench) still shows its signals;
//! - the graph's `parameters:` are parameters, fixed after initialisation
//!   (they are compiled into the blocks), with the file's values as start;
//! - the recorded signals are local variables when the graph has outports
//!   (but those that are an input or output under the same name);
//! - FMI 3 has the independent variable `time` (value reference 0) and
//!   vectors as arrays; FMI 2 has no array, so a vector `v` of width n is
//!   the scalars `v[1]` … `v[n]` (1-based, as ctlgraph's CSV headers).

use ctlgraph_core::Model;

/// The FMI version written.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Version {
    Fmi2,
    Fmi3,
}

impl Version {
    /// The `fmiVersion` attribute.
    pub fn text(self) -> &'static str {
        match self {
            Version::Fmi2 => "2.0",
            Version::Fmi3 => "3.0",
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Causality {
    Independent,
    Input,
    Output,
    Parameter,
    Local,
}

impl Causality {
    pub fn text(self) -> &'static str {
        match self {
            Causality::Independent => "independent",
            Causality::Input => "input",
            Causality::Output => "output",
            Causality::Parameter => "parameter",
            Causality::Local => "local",
        }
    }
}

/// Where a variable's value lives in a run.
#[derive(Clone, Debug, PartialEq)]
pub enum Place {
    /// The simulation time.
    Time,
    /// Elements `elements` of input `index` (in [`Model::external_inputs`]).
    Input { index: usize, elements: std::ops::Range<usize> },
    /// A span of the signal buffer.
    Signal { offset: usize, width: usize },
    /// Parameter `index` (in [`Model::parameters`]).
    Parameter(usize),
}

/// One FMI variable (an array in FMI 3 when `dims` is given).
#[derive(Clone, Debug, PartialEq)]
pub struct Variable {
    pub name: String,
    pub value_reference: u32,
    pub causality: Causality,
    pub place: Place,
    /// The start values (one per element), for inputs and parameters.
    pub start: Option<Vec<f64>>,
    pub unit: Option<String>,
    pub description: String,
    /// The array's length (FMI 3 vectors only).
    pub dims: Option<usize>,
}

impl Variable {
    /// How many numbers it holds.
    pub fn len(&self) -> usize {
        self.dims.unwrap_or(1)
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// The variables of an FMU of `model`, value references in order from 0 (FMI 3's
/// `time`) or 1; an error names a variable name given twice.
pub fn variables(model: &Model, version: Version) -> Result<Vec<Variable>, String> {
    let mut out: Vec<Variable> = Vec::new();
    let mut push = |name: String, causality, place, start: Option<Vec<f64>>, unit, description: String, width| {
        let value_reference = out.len() as u32 + u32::from(version == Version::Fmi2);
        out.push(Variable { name, value_reference, causality, place, start, unit, description, dims: width });
    };
    if version == Version::Fmi3 {
        push("time".into(), Causality::Independent, Place::Time, None, None, "simulation time [s]".into(), None);
    }
    // One variable per vector (FMI 3) or per element (FMI 2).
    let each = |name: &str, width: usize, make: &mut dyn FnMut(String, std::ops::Range<usize>, Option<usize>)| {
        if version == Version::Fmi3 || width == 1 {
            make(name.to_string(), 0..width, (width != 1).then_some(width));
        } else {
            for k in 0..width {
                make(format!("{name}[{}]", k + 1), k..k + 1, None);
            }
        }
    };
    for (index, (name, block)) in model.external_inputs.iter().enumerate() {
        let value = input_start(model, *block);
        each(name, value.len(), &mut |n, elements, dims| {
            let start = Some(value[elements.clone()].to_vec());
            let place = Place::Input { index, elements };
            push(n, Causality::Input, place, start, None, format!("input: inport block `{name}`"), dims)
        });
    }
    let outputs: Vec<(String, usize, usize, Option<String>, String)> = if model.external_outputs.is_empty() {
        let column = |c: &ctlgraph_core::compile::Column| {
            (c.name.clone(), c.offset, c.width, c.unit.clone(), format!("recorded signal `{}`", c.name))
        };
        model.columns.iter().map(column).collect()
    } else {
        let port = |(n, p): &(String, ctlgraph_core::block::Port)| {
            (n.clone(), p.offset, p.width, None, format!("output: outport block `{n}`"))
        };
        model.external_outputs.iter().map(port).collect()
    };
    for (name, offset, width, unit, description) in outputs {
        each(&name, width, &mut |n, elements, dims| {
            let place = Place::Signal { offset: offset + elements.start, width: elements.len() };
            push(n, Causality::Output, place, None, unit.clone(), description.clone(), dims)
        });
    }
    for (index, (name, value)) in model.parameters.iter().enumerate() {
        let description = format!("graph parameter `{name}` (fixed after initialisation)");
        push(name.clone(), Causality::Parameter, Place::Parameter(index), Some(vec![*value]), None, description, None);
    }
    if !model.external_outputs.is_empty() {
        // A recorded signal that is an input or output under its own name
        // (`record: [y, u: pid]` beside an inport `y` and an outport `u`
        // wired from `pid`) is that variable already.
        let port_of = |name: &str| {
            let input = model.external_inputs.iter().find(|(n, _)| n == name);
            let input = input.and_then(|(_, b)| model.output_ports(*b).first().map(|p| p.offset));
            let output = model.external_outputs.iter().find(|(n, _)| n == name).map(|(_, p)| p.offset);
            input.or(output)
        };
        for c in model.columns.iter().filter(|c| port_of(&c.name) != Some(c.offset)) {
            each(&c.name, c.width, &mut |n, elements, dims| {
                let place = Place::Signal { offset: c.offset + elements.start, width: elements.len() };
                push(n, Causality::Local, place, None, c.unit.clone(), format!("recorded signal `{}`", c.name), dims)
            });
        }
    }
    let mut seen = std::collections::HashMap::new();
    for v in &out {
        if let Some(first) = seen.insert(v.name.as_str(), v.causality) {
            return Err(format!(
                "the FMU would have two variables named `{}` (a {} and a {}): rename the recorded \
                 signal, the parameter or the port so that each name is used once",
                v.name,
                first.text(),
                v.causality.text()
            ));
        }
    }
    Ok(out)
}

/// The value the inport `block` holds until set (its `value`).
pub fn input_start(model: &Model, block: usize) -> Vec<f64> {
    let width = model.output_ports(block).first().map_or(1, |p| p.width);
    let held = model.block_boxed(block).and_then(|mut b| b.external_input().map(|v| v.to_vec()));
    held.filter(|v| v.len() == width).unwrap_or_else(|| vec![0.0; width])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn model(text: &str) -> Model {
        let flat = ctlgraph_core::load_str(text, "t.yaml".into(), &[]).expect("loads");
        ctlgraph_core::compile(&flat, &ctlgraph_blocks::registry()).expect("compiles")
    }

    const WITH_PORTS: &str = "
parameters: { k: 2.5 }
simulation: { stop: 1, solver: { method: rk4, step: 0.01 } }
blocks:
  u: { type: inport, width: 2, value: 0.5 }
  g: { type: gain, k: k }
  y: { type: outport }
wires: [u -> g, g -> y]
record: [{ gy: g, unit: mm }]
";

    #[test]
    fn ports_parameters_and_records_map_to_inputs_outputs_parameters_and_locals() {
        let m = model(WITH_PORTS);
        let v3 = variables(&m, Version::Fmi3).unwrap();
        let names: Vec<(&str, u32, Causality, Option<usize>)> =
            v3.iter().map(|v| (v.name.as_str(), v.value_reference, v.causality, v.dims)).collect();
        assert_eq!(
            names,
            [
                ("time", 0, Causality::Independent, None),
                ("u", 1, Causality::Input, Some(2)),
                ("y", 2, Causality::Output, Some(2)),
                ("k", 3, Causality::Parameter, None),
                ("gy", 4, Causality::Local, Some(2)),
            ]
        );
        assert_eq!(v3[1].start, Some(vec![0.5, 0.5]));
        assert_eq!(v3[3].start, Some(vec![2.5]));
        assert_eq!(v3[4].unit.as_deref(), Some("mm"));
        let v2 = variables(&m, Version::Fmi2).unwrap();
        let names: Vec<(&str, u32)> = v2.iter().map(|v| (v.name.as_str(), v.value_reference)).collect();
        assert_eq!(names, [("u[1]", 1), ("u[2]", 2), ("y[1]", 3), ("y[2]", 4), ("k", 5), ("gy[1]", 6), ("gy[2]", 7)]);
        assert_eq!(v2[1].place, Place::Input { index: 0, elements: 1..2 });
    }

    #[test]
    fn without_outports_the_recorded_signals_are_the_outputs() {
        let m = model(
            "
simulation: { stop: 1 }
blocks:
  s: { type: sine }
record: [s]
",
        );
        let v = variables(&m, Version::Fmi3).unwrap();
        assert_eq!(v[1].name, "s");
        assert_eq!(v[1].causality, Causality::Output);
    }

    #[test]
    fn a_name_used_twice_is_refused_naming_it() {
        let m = model(
            "
parameters: { s: 1 }
simulation: { stop: 1 }
blocks:
  c: { type: constant, value: s }
record: [s: c]
",
        );
        let e = variables(&m, Version::Fmi3).unwrap_err();
        assert!(e.contains("two variables named `s`"), "{e}");
    }
}
