//! An FMU's `modelDescription.xml`, read with roxmltree: what the `fmu`
//! block needs of it — the version, the co-simulation interface's model
//! identifier and flags, the token, the default step, the variables (FMI
//! 3.0 §2.4.7, FMI 2.0.4 §2.2.7).

/// The FMI version of an FMU.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Version {
    Fmi2,
    Fmi3,
}

/// A variable's role, as `causality` names it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Causality {
    Input,
    Output,
    Parameter,
    CalculatedParameter,
    StructuralParameter,
    Local,
    Independent,
}

impl Causality {
    fn parse(s: &str) -> Option<Causality> {
        Some(match s {
            "input" => Causality::Input,
            "output" => Causality::Output,
            "parameter" => Causality::Parameter,
            "calculatedParameter" => Causality::CalculatedParameter,
            "structuralParameter" => Causality::StructuralParameter,
            "local" => Causality::Local,
            "independent" => Causality::Independent,
            _ => return None,
        })
    }

    pub fn name(self) -> &'static str {
        match self {
            Causality::Input => "input",
            Causality::Output => "output",
            Causality::Parameter => "parameter",
            Causality::CalculatedParameter => "calculated parameter",
            Causality::StructuralParameter => "structural parameter",
            Causality::Local => "local",
            Causality::Independent => "independent",
        }
    }
}

/// One variable.
#[derive(Clone, Debug, PartialEq)]
pub struct Variable {
    pub name: String,
    pub value_reference: u32,
    pub causality: Causality,
    pub variability: String,
    /// `Float64`/`Real`, or the other type's element name (`Int32`, `Integer`, `Boolean`, …).
    pub type_name: String,
    /// The number of elements: 1, or an FMI 3 array's fixed size.
    pub size: usize,
    pub start: Option<Vec<f64>>,
    pub unit: Option<String>,
    pub description: Option<String>,
}

impl Variable {
    /// Whether it is a real number (FMI 3 `Float64`/`Float32`, FMI 2 `Real`).
    pub fn is_real(&self) -> bool {
        matches!(self.type_name.as_str(), "Float64" | "Float32" | "Real")
    }
}

/// What the block reads of a model description.
#[derive(Clone, Debug)]
pub struct Description {
    pub version: Version,
    pub model_name: String,
    /// FMI 3's `instantiationToken`, FMI 2's `guid`.
    pub token: String,
    /// The co-simulation interface's `modelIdentifier` (None: the FMU has none).
    pub co_simulation: Option<CoSimulation>,
    /// The model-exchange interface's `modelIdentifier`, and how many
    /// continuous states and event indicators it has.
    pub model_exchange: Option<ModelExchange>,
    pub default_step: Option<f64>,
    pub variables: Vec<Variable>,
    /// The model-exchange interface's state flags (FMI 3 and 2 put them on
    /// each interface's element).
    pub can_get_and_set_state: bool,
    pub can_serialize_state: bool,
}

#[derive(Clone, Debug)]
pub struct ModelExchange {
    pub model_identifier: String,
    pub states: usize,
    pub event_indicators: usize,
}

#[derive(Clone, Debug)]
pub struct CoSimulation {
    pub model_identifier: String,
    pub can_get_and_set_state: bool,
    pub can_serialize_state: bool,
}

/// Parses `text`, the content of `modelDescription.xml`.
pub fn parse(text: &str) -> Result<Description, String> {
    let doc = roxmltree::Document::parse(text).map_err(|e| format!("modelDescription.xml: {e}"))?;
    let root = doc.root_element();
    if root.tag_name().name() != "fmiModelDescription" {
        return Err(format!(
            "modelDescription.xml: the root element is <{}>, not <fmiModelDescription>",
            root.tag_name().name()
        ));
    }
    let fmi_version = root.attribute("fmiVersion").unwrap_or("");
    let version = if fmi_version.starts_with("3.") {
        Version::Fmi3
    } else if fmi_version.starts_with("2.") {
        Version::Fmi2
    } else {
        return Err(format!("FMI version `{fmi_version}`: the fmu block reads FMI 3.0 and 2.0"));
    };
    let token_attr = if version == Version::Fmi3 { "instantiationToken" } else { "guid" };
    let token =
        root.attribute(token_attr).ok_or_else(|| format!("modelDescription.xml: no `{token_attr}`"))?.to_string();
    let child = |name: &str| root.children().find(|n| n.has_tag_name(name));
    let flag = |n: roxmltree::Node, a: &str| n.attribute(a) == Some("true");
    let co_simulation = child("CoSimulation").map(|cs| CoSimulation {
        model_identifier: cs.attribute("modelIdentifier").unwrap_or("").to_string(),
        can_get_and_set_state: flag(
            cs,
            if version == Version::Fmi3 { "canGetAndSetFMUState" } else { "canGetAndSetFMUstate" },
        ),
        can_serialize_state: flag(
            cs,
            if version == Version::Fmi3 { "canSerializeFMUState" } else { "canSerializeFMUstate" },
        ),
    });
    let default_step =
        child("DefaultExperiment").and_then(|d| d.attribute("stepSize")).and_then(|s| s.trim().parse().ok());
    let list = child("ModelVariables").ok_or("modelDescription.xml: no <ModelVariables>")?;
    let mut variables = Vec::new();
    for v in list.children().filter(|n| n.is_element()) {
        let parsed = match version {
            Version::Fmi3 => variable3(v),
            Version::Fmi2 => variable2(v),
        };
        variables.push(
            parsed.map_err(|e| format!("modelDescription.xml, line {}: {e}", doc.text_pos_at(v.range().start).row))?,
        );
    }
    let me_flags = child("ModelExchange").map_or((false, false), |me| {
        let (get_set, serialize) = match version {
            Version::Fmi3 => ("canGetAndSetFMUState", "canSerializeFMUState"),
            Version::Fmi2 => ("canGetAndSetFMUstate", "canSerializeFMUstate"),
        };
        (flag(me, get_set), flag(me, serialize))
    });
    let model_exchange = child("ModelExchange").map(|me| {
        let structure = child("ModelStructure");
        let size_of = |vr: Option<&str>| {
            let vr: Option<u32> = vr.and_then(|r| r.trim().parse().ok());
            variables.iter().find(|v| Some(v.value_reference) == vr).map_or(1, |v| v.size)
        };
        let (states, event_indicators) = match version {
            // Each `<ContinuousStateDerivative>` and `<EventIndicator>` names a variable (an array counts its elements).
            Version::Fmi3 => {
                let count = |tag: &str| {
                    structure
                        .iter()
                        .flat_map(|s| s.children())
                        .filter(|n| n.has_tag_name(tag))
                        .map(|n| size_of(n.attribute("valueReference")))
                        .sum()
                };
                (count("ContinuousStateDerivative"), count("EventIndicator"))
            }
            Version::Fmi2 => {
                let derivatives = structure.and_then(|s| s.children().find(|n| n.has_tag_name("Derivatives")));
                let states = derivatives.map_or(0, |d| d.children().filter(|n| n.has_tag_name("Unknown")).count());
                let indicators =
                    root.attribute("numberOfEventIndicators").and_then(|n| n.trim().parse().ok()).unwrap_or(0);
                (states, indicators)
            }
        };
        ModelExchange {
            model_identifier: me.attribute("modelIdentifier").unwrap_or("").to_string(),
            states,
            event_indicators,
        }
    });
    Ok(Description {
        version,
        model_name: root.attribute("modelName").unwrap_or("").to_string(),
        token,
        co_simulation,
        can_get_and_set_state: me_flags.0,
        can_serialize_state: me_flags.1,
        model_exchange,
        default_step,
        variables,
    })
}

fn common(v: roxmltree::Node) -> Result<(String, u32, Causality, String), String> {
    let name = v.attribute("name").ok_or("a variable without a name")?.to_string();
    let value_reference = v
        .attribute("valueReference")
        .and_then(|r| r.trim().parse().ok())
        .ok_or_else(|| format!("variable `{name}`: no valid valueReference"))?;
    let causality = Causality::parse(v.attribute("causality").unwrap_or("local"))
        .ok_or_else(|| format!("variable `{name}`: unknown causality"))?;
    let variability = v.attribute("variability").unwrap_or("continuous").to_string();
    Ok((name, value_reference, causality, variability))
}

fn numbers(text: &str) -> Option<Vec<f64>> {
    text.split_whitespace().map(|s| s.parse().ok()).collect()
}

/// An FMI 3 variable: the element is its type (`<Float64 …>`); arrays
/// carry `<Dimension start="n"/>` (a dimension set by a structural
/// parameter is refused: the block's ports are fixed when it is built).
fn variable3(v: roxmltree::Node) -> Result<Variable, String> {
    let (name, value_reference, causality, variability) = common(v)?;
    let mut size = 1usize;
    for d in v.children().filter(|n| n.has_tag_name("Dimension")) {
        let n: usize = d.attribute("start").and_then(|s| s.trim().parse().ok()).ok_or_else(|| {
            format!("variable `{name}`: an array whose size a structural parameter sets (the block's ports are fixed)")
        })?;
        size *= n;
    }
    let type_name = v.tag_name().name().to_string();
    let start = v.attribute("start").and_then(numbers);
    let unit = v.attribute("unit").map(str::to_string);
    let description = v.attribute("description").map(str::to_string);
    Ok(Variable { name, value_reference, causality, variability, type_name, size, start, unit, description })
}

/// An FMI 2 variable: `<ScalarVariable …><Real start=… unit=…/></ScalarVariable>`.
fn variable2(v: roxmltree::Node) -> Result<Variable, String> {
    let (name, value_reference, causality, variability) = common(v)?;
    let ty = v.children().find(|n| n.is_element()).ok_or_else(|| format!("variable `{name}`: no type element"))?;
    Ok(Variable {
        start: ty.attribute("start").and_then(numbers),
        unit: ty.attribute("unit").map(str::to_string),
        description: v.attribute("description").map(str::to_string),
        type_name: ty.tag_name().name().to_string(),
        size: 1,
        name,
        value_reference,
        causality,
        variability,
    })
}
