//! The ctlgraph block library, one module per block family.
//!
//! Every block type documents its ports, parameters (with defaults) and
//! equations in its `BlockType` entry; `ctlgraph blocks TYPE` prints them.

use ctlgraph_core::ParamDefault::{Described, Number, Required};
use ctlgraph_core::registry::{ParamDefault, ParamDoc, ParamKind, PortDoc, Registry};

/// A block's [`Block::rust_type`](ctlgraph_core::Block::rust_type): its
/// path as generated code names it, from the module that defines it.
macro_rules! rust_type {
    ($ty:ident) => {
        fn rust_type(&self) -> Option<&'static str> {
            let path = concat!(module_path!(), "::", stringify!($ty));
            // The type must be defined where its `impl Block` is.
            debug_assert_eq!(std::any::type_name::<Self>(), path);
            Some(path)
        }
    };
}

pub mod adrc;
pub mod backlash;
#[cfg(test)]
mod block_tests;
#[cfg(all(test, feature = "implicit"))]
mod build_tests;
pub mod continuous;
pub mod delay;
pub mod discrete;
pub mod discrete_integrator;
pub mod estimation;
pub mod events;
pub mod fmu;
pub mod force;
pub mod fuzzy;
pub mod integrator;
pub mod kalman;
pub mod logic;
pub mod math;
pub mod milling;
pub mod motion;
pub mod noise;
pub mod nonlinear;
pub mod pid;
pub mod routing;
pub mod signals;
pub mod smc;
pub mod sources;
pub mod tables;
#[cfg(test)]
mod test_rig;
#[cfg(feature = "testing")]
pub mod testing;

/// The block types with a C form (`ctlgraph codegen --target c`,
/// [`ctlgraph_core::Block::c_form`]); `inport` and `outport` are the
/// controller's inputs and outputs. Each has a property test against its
/// Rust form (`c_forms` in the root crate's tests).
pub const TYPES_WITH_C_FORM: &[&str] = &[
    "abs",
    "backlash",
    "constant",
    "coulomb_viscous_friction",
    "dead_zone",
    "delay",
    "demux",
    "discrete_fir",
    "discrete_integrator",
    "discrete_transfer_function",
    "divide",
    "fcn",
    "fuzzy",
    "gain",
    "ground",
    "inport",
    "leso",
    "logical_operator",
    "lookup_table_1d",
    "lsef",
    "max",
    "memory",
    "min",
    "moving_average",
    "mux",
    "outport",
    "pid",
    "product",
    "quantizer",
    "rate_limiter",
    "relational_operator",
    "relay",
    "saturation",
    "selector",
    "sign",
    "sliding_mode",
    "smc",
    "sum",
    "switch",
    "terminator",
    "tracking_differentiator",
    "unit_delay",
    "zero_order_hold",
];

/// A registry holding every block type of the library.
pub fn registry() -> Registry {
    let mut reg = Registry::new();
    for family in [
        sources::TYPES,
        signals::TYPES,
        tables::TYPES,
        noise::TYPES,
        math::TYPES,
        nonlinear::TYPES,
        backlash::TYPES,
        continuous::TYPES,
        integrator::TYPES,
        delay::TYPES,
        events::TYPES,
        logic::TYPES,
        discrete::TYPES,
        discrete_integrator::TYPES,
        pid::TYPES,
        adrc::TYPES,
        fuzzy::TYPES,
        force::TYPES,
        milling::TYPES,
        motion::TYPES,
        smc::TYPES,
        estimation::TYPES,
        kalman::TYPES,
        fmu::TYPES,
        routing::TYPES,
    ] {
        for ty in family {
            reg.register(*ty);
        }
    }
    reg
}

/// The `gain_inputs` parameter: gains (out of `names`) that come from
/// input ports. Adds one scalar port per listed gain to `iface`, in the
/// order listed, and returns each name's port index (`None`: the
/// parameter's value is used).
pub(crate) fn gain_inputs<const N: usize>(
    p: &mut ctlgraph_core::Params,
    names: [&'static str; N],
    iface: &mut ctlgraph_core::Interface,
) -> Result<[Option<usize>; N], ctlgraph_core::Diagnostic> {
    let mut ports = [None; N];
    for name in p.strings("gain_inputs")? {
        let Some(i) = names.iter().position(|g| *g == name) else {
            return Err(p
                .error("gain_inputs", format!("`{name}` is not a gain here: use {}", names.join(", ")))
                .suggest(name, names));
        };
        if ports[i].is_some() {
            return Err(p.error("gain_inputs", format!("`{name}` is listed twice")));
        }
        ports[i] = Some(iface.inputs.len());
        iface.inputs.push(ctlgraph_core::block::InputPort {
            name: name.to_string(),
            width: ctlgraph_core::Width::Fixed(1),
            feedthrough: true,
        });
    }
    Ok(ports)
}

/// Shorthand for parameter tables.
pub(crate) const fn param(name: &'static str, default: ParamDefault, doc: &'static str) -> ParamDoc {
    ParamDoc::new(name, default, doc)
}

/// What a parameter table is written with: [`param`] and the defaults.
pub(crate) mod table {
    pub(crate) use super::param;
    pub(crate) use ctlgraph_core::ParamDefault::{Described, Flag, Number, Numbers, Required, Word};
    pub(crate) use ctlgraph_core::ParamKind;
}

/// An input of any width, and an output of the same width.
pub(crate) const U_ANY: &[PortDoc] = &[PortDoc { name: "u", doc: "any width" }];
pub(crate) const Y_SAME: &[PortDoc] = &[PortDoc { name: "y", doc: "same width as u" }];
/// Scalar input and output.
pub(crate) const U_SCALAR: &[PortDoc] = &[PortDoc { name: "u", doc: "scalar" }];
pub(crate) const Y_SCALAR: &[PortDoc] = &[PortDoc { name: "y", doc: "scalar" }];

/// The `sample_time` parameter of blocks that inherit their rate by default.
pub(crate) const SAMPLE_TIME_INHERITED: ParamDoc =
    param("sample_time", Number(-1.0), "-1 inherit from inputs, 0 continuous, T > 0 every T seconds, [T, offset]")
        .kind(ParamKind::SampleTime);

/// The optional active window of every source.
pub(crate) const ACTIVE: ParamDoc =
    param("active", Described("always"), "[t_on, t_off]: the source outputs zero before t_on and from t_off on")
        .kind(ParamKind::Numbers);

/// The `sample_time` parameter of sources, continuous by default.
pub(crate) const SAMPLE_TIME_CONTINUOUS: ParamDoc =
    param("sample_time", Number(0.0), "0 continuous, T > 0 sampled every T seconds and held, [T, offset]")
        .kind(ParamKind::SampleTime);

/// The `sample_time` parameter of blocks that only exist in discrete form.
pub(crate) const SAMPLE_TIME_REQUIRED: ParamDoc =
    param("sample_time", Required, "period T > 0 in seconds, or [T, offset] with 0 <= offset < T")
        .kind(ParamKind::SampleTime);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_type_is_documented() {
        let reg = registry();
        for ty in reg.types() {
            assert!(!ty.summary.is_empty() && !ty.doc.is_empty(), "{} lacks docs", ty.name);
            assert!(!ty.category.is_empty(), "{} lacks a category", ty.name);
        }
        let required = [
            "constant",
            "step",
            "ramp",
            "sine",
            "pulse",
            "clock",
            "lookup_table_1d",
            "from_csv",
            "gain",
            "sum",
            "product",
            "divide",
            "abs",
            "sign",
            "min",
            "max",
            "saturation",
            "dead_zone",
            "rate_limiter",
            "fcn",
            "integrator",
            "derivative",
            "transfer_function",
            "zpk",
            "state_space",
            "discrete_transfer_function",
            "unit_delay",
            "delay",
            "zero_order_hold",
            "transport_delay",
            "variable_transport_delay",
            "relay",
            "hit_crossing",
            "pid",
            "mux",
            "demux",
            "selector",
            "switch",
            "subsystem",
            "inport",
            "outport",
        ];
        for name in required {
            assert!(reg.get(name).is_some(), "{name} is missing");
        }
    }
}
