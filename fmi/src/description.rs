//! `modelDescription.xml` for FMI 3.0 (FMI 3.0 standard, §2.4) and FMI 2.0
//! (FMI 2.0.4 standard, §2.2), co-simulation only, from the variables of
//! [`crate::table`].
//!
//! Written by hand: a dozen elements with attributes, whose only subtlety
//! is escaping; the FMI crates on crates.io describe a model as a Rust
//! struct fixed at compile time (`fmi-export`) or read descriptions
//! (`fmi-schema`), and a graph's variables are known only at export.

use crate::table::{Causality, Variable, Version};
use ctlgraph_core::Model;
use ctlgraph_solver::Method;
use std::fmt::Write;

/// What names the FMU besides its variables.
pub struct Identity<'a> {
    /// `modelIdentifier`: the binary's file name and a C identifier.
    pub model_identifier: &'a str,
    /// FMI 3's `instantiationToken`, FMI 2's `guid`: checked at instantiation.
    pub token: &'a str,
    pub generation_tool: &'a str,
}

/// The document for `model`'s FMU with `variables` (from [`crate::table::variables`]).
pub fn model_description(model: &Model, variables: &[Variable], id: &Identity, version: Version) -> String {
    let mut x = String::from("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    let name = model.name.clone().unwrap_or_else(|| id.model_identifier.to_string());
    let token_attr = match version {
        Version::Fmi3 => "instantiationToken",
        Version::Fmi2 => "guid",
    };
    let _ = write!(
        x,
        "<fmiModelDescription fmiVersion=\"{}\" modelName=\"{}\" {token_attr}=\"{}\" description=\"{}\" \
         generationTool=\"{}\" variableNamingConvention=\"flat\"",
        version.text(),
        esc(&name),
        esc(id.token),
        esc(&format!("ctlgraph graph `{}`", file_name(&model.file))),
        esc(id.generation_tool),
    );
    if version == Version::Fmi2 {
        x.push_str(" numberOfEventIndicators=\"0\"");
    }
    x.push_str(">\n");
    let state = match version {
        Version::Fmi3 => "canGetAndSetFMUState=\"true\" canSerializeFMUState=\"true\"",
        Version::Fmi2 => {
            "canGetAndSetFMUstate=\"true\" canSerializeFMUstate=\"true\" canNotUseMemoryManagementFunctions=\"true\""
        }
    };
    let _ = writeln!(
        x,
        "  <CoSimulation modelIdentifier=\"{}\" canHandleVariableCommunicationStepSize=\"true\" {state}/>",
        esc(id.model_identifier)
    );
    let mut units: Vec<&str> = variables.iter().filter_map(|v| v.unit.as_deref()).collect();
    units.sort_unstable();
    units.dedup();
    if !units.is_empty() {
        x.push_str("  <UnitDefinitions>\n");
        for u in units {
            let _ = writeln!(x, "    <Unit name=\"{}\"/>", esc(u));
        }
        x.push_str("  </UnitDefinitions>\n");
    }
    x.push_str(&default_experiment(model));
    x.push_str("  <ModelVariables>\n");
    for v in variables {
        match version {
            Version::Fmi3 => fmi3_variable(&mut x, v),
            Version::Fmi2 => fmi2_variable(&mut x, v),
        }
    }
    x.push_str("  </ModelVariables>\n  <ModelStructure>\n");
    let outputs = variables.iter().enumerate().filter(|(_, v)| v.causality == Causality::Output);
    match version {
        Version::Fmi3 => {
            for (_, v) in outputs.clone() {
                let _ = writeln!(x, "    <Output valueReference=\"{}\"/>", v.value_reference);
            }
            for (_, v) in outputs {
                let _ = writeln!(x, "    <InitialUnknown valueReference=\"{}\"/>", v.value_reference);
            }
        }
        Version::Fmi2 => {
            // FMI 2 refers to variables by their 1-based index in ModelVariables.
            let list = |x: &mut String, tag: &str| {
                let _ = writeln!(x, "    <{tag}>");
                for (i, _) in outputs.clone() {
                    let _ = writeln!(x, "      <Unknown index=\"{}\"/>", i + 1);
                }
                let _ = writeln!(x, "    </{tag}>");
            };
            if outputs.clone().next().is_some() {
                list(&mut x, "Outputs");
                list(&mut x, "InitialUnknowns");
            }
        }
    }
    x.push_str("  </ModelStructure>\n</fmiModelDescription>\n");
    x
}

/// The graph file's name, without the folders it was exported from.
fn file_name(path: &str) -> &str {
    path.rsplit(['/', '\\']).next().unwrap_or(path)
}

/// `DefaultExperiment`: the graph's stop time, the fixed step (or the
/// adaptive method's relative tolerance) as ctlgraph would run it.
fn default_experiment(model: &Model) -> String {
    let sim = &model.sim;
    let detail = match sim.method {
        Method::Euler { step } | Method::Heun { step } | Method::Rk4 { step } => {
            format!(" stepSize=\"{}\"", number(step))
        }
        Method::DormandPrince { rtol, .. } | Method::Trbdf2 { rtol, .. } => {
            let step = model.clocks.iter().map(|&(p, _)| p).fold(f64::INFINITY, f64::min);
            let step = if step.is_finite() { format!(" stepSize=\"{}\"", number(step)) } else { String::new() };
            format!(" tolerance=\"{}\"{step}", number(rtol))
        }
    };
    format!("  <DefaultExperiment startTime=\"0\" stopTime=\"{}\"{detail}/>\n", number(sim.stop))
}

fn fmi3_variable(x: &mut String, v: &Variable) {
    let variability = match v.causality {
        Causality::Parameter => "fixed",
        _ => "continuous",
    };
    let _ = write!(
        x,
        "    <Float64 name=\"{}\" valueReference=\"{}\" description=\"{}\" causality=\"{}\" variability=\"{variability}\"",
        esc(&v.name),
        v.value_reference,
        esc(&v.description),
        v.causality.text()
    );
    if matches!(v.causality, Causality::Output | Causality::Local) {
        x.push_str(" initial=\"calculated\"");
    }
    if let Some(unit) = &v.unit {
        let _ = write!(x, " unit=\"{}\"", esc(unit));
    }
    if let Some(start) = &v.start {
        let values: Vec<String> = start.iter().map(|s| number(*s)).collect();
        let _ = write!(x, " start=\"{}\"", values.join(" "));
    }
    match v.dims {
        Some(n) => {
            let _ = write!(x, ">\n      <Dimension start=\"{n}\"/>\n    </Float64>\n");
        }
        None => x.push_str("/>\n"),
    }
}

fn fmi2_variable(x: &mut String, v: &Variable) {
    let (variability, initial) = match v.causality {
        Causality::Parameter => ("fixed", " initial=\"exact\""),
        Causality::Output | Causality::Local => ("continuous", " initial=\"calculated\""),
        _ => ("continuous", ""),
    };
    let _ = write!(
        x,
        "    <ScalarVariable name=\"{}\" valueReference=\"{}\" description=\"{}\" causality=\"{}\" \
         variability=\"{variability}\"{initial}>\n      <Real",
        esc(&v.name),
        v.value_reference,
        esc(&v.description),
        v.causality.text()
    );
    if let Some(unit) = &v.unit {
        let _ = write!(x, " unit=\"{}\"", esc(unit));
    }
    if let Some(start) = v.start.as_ref().and_then(|s| s.first()) {
        let _ = write!(x, " start=\"{}\"", number(*start));
    }
    x.push_str("/>\n    </ScalarVariable>\n");
}

/// A number as XML Schema's `xs:double` reads it back to the same bits.
pub fn number(v: f64) -> String {
    if v == 0.0 || (1e-4..1e15).contains(&v.abs()) { format!("{v}") } else { format!("{v:e}") }
}

/// `text` escaped for an XML attribute.
pub fn esc(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            '\n' => out.push_str("&#10;"),
            c => out.push(c),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::table::variables;

    #[test]
    fn escapes_and_numbers_read_back() {
        assert_eq!(esc("a<b & \"c\""), "a&lt;b &amp; &quot;c&quot;");
        for v in [0.1, 1e-10, 2.5e300, -3.0, 0.0, 1e-4, 123456.789] {
            assert_eq!(number(v).parse::<f64>().unwrap(), v);
        }
    }

    #[test]
    fn both_versions_describe_the_variables_and_the_experiment() {
        let text = "
name: tiny
parameters: { k: 2 }
simulation: { stop: 2, solver: { method: rk4, step: 0.001 } }
blocks:
  u: { type: inport, width: 2 }
  g: { type: gain, k: k }
  y: { type: outport }
wires: [u -> g, g -> y]
";
        let flat = ctlgraph_core::load_str(text, "tiny.yaml".into(), &[]).unwrap();
        let model = ctlgraph_core::compile(&flat, &ctlgraph_blocks::registry()).unwrap();
        let id = Identity { model_identifier: "tiny", token: "{t}", generation_tool: "ctlgraph test" };
        let x3 = model_description(&model, &variables(&model, Version::Fmi3).unwrap(), &id, Version::Fmi3);
        assert!(x3.contains("fmiVersion=\"3.0\" modelName=\"tiny\" instantiationToken=\"{t}\""), "{x3}");
        assert!(x3.contains("<DefaultExperiment startTime=\"0\" stopTime=\"2\" stepSize=\"0.001\"/>"), "{x3}");
        assert!(x3.contains("name=\"u\" valueReference=\"1\""), "{x3}");
        assert!(x3.contains("start=\"0 0\">\n      <Dimension start=\"2\"/>"), "{x3}");
        assert!(x3.contains("name=\"k\" valueReference=\"3\""), "{x3}");
        assert!(x3.contains("causality=\"parameter\" variability=\"fixed\" start=\"2\""), "{x3}");
        assert!(x3.contains("<Output valueReference=\"2\"/>"), "{x3}");
        let x2 = model_description(&model, &variables(&model, Version::Fmi2).unwrap(), &id, Version::Fmi2);
        assert!(x2.contains("fmiVersion=\"2.0\" modelName=\"tiny\" guid=\"{t}\""), "{x2}");
        assert!(x2.contains("name=\"y[2]\" valueReference=\"4\""), "{x2}");
        assert!(x2.contains("<Outputs>\n      <Unknown index=\"3\"/>\n      <Unknown index=\"4\"/>"), "{x2}");
    }
}
