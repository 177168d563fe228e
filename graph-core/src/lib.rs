//! ctlgraph's graph model: loading YAML graph files with positions,
//! evaluating parameters, expanding subsystems, compiling to a sorted
//! dataflow [`Model`] and simulating it with Simulink's semantics.
//!
//! The flow: text → [`spec::GraphFile`] → [`flatten::load`] (parameters,
//! subsystems) → [`compile::compile`] (blocks from a [`Registry`], wiring,
//! widths, rates, execution order) → [`sim::Simulator`].

pub mod algebraic;
pub mod block;
pub mod checks;
pub mod codegen;
pub mod compile;
pub mod composite;
pub mod conditional;
pub mod dense;
pub mod diag;
pub mod expr;
pub mod files;
pub mod flatten;
pub mod linearize;
pub mod params;
pub mod registry;
pub mod scope;
pub mod sim;
pub mod spec;
pub mod trace;
pub mod yaml;

pub use block::Crossing;
pub use block::{Block, Breakpoint, Interface, Io, Kernel, SampleTime, TimeOnly, Width};
pub use compile::{Model, compile, recompile, reuse_structure};
pub use diag::{Diagnostic, Pos};
pub use flatten::{Accelerate, FlatGraph, OutputTimes, ParsedGraph, SimConfig, ZeroCrossing, load, load_str};
pub use params::Params;
pub use registry::{BlockType, Built, ParamDefault, ParamDoc, ParamKind, PortDoc, Registry};
pub use sim::{RunState, RunStats, SimError, Simulator, Snapshot};
