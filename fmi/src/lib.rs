//! ctlgraph graphs as co-simulation FMUs (Functional Mock-up Interface
//! 3.0 and 2.0, <https://fmi-standard.org>).
//!
//! An FMU written by `ctlgraph fmu` carries the graph file (with its
//! subsystem and data files) in `resources/` and one binary, this crate
//! built as a `cdylib` with the `symbols` feature: at instantiation it
//! loads and compiles the graph with ctlgraph's own loader and compiler,
//! and each `doStep` runs ctlgraph's driver to the communication point.
//!
//! - [`table`] derives the FMU's variables from the compiled graph (both
//!   sides derive them the same way);
//! - [`description`] writes `modelDescription.xml`;
//! - [`config`] is what the exporter tells the binary (`resources/ctlgraph.json`);
//! - [`instance`] is an instance and the co-simulation state machine;
//! - [`replay`] saves and serialises FMU states;
//! - [`package`] gathers the FMU's files but its binary;
//! - [`fmi3`] and [`fmi2`] are the C functions of each version, `ffi` what they share.

pub mod config;
pub mod description;
mod ffi;
pub mod fmi2;
pub mod fmi3;
pub mod instance;
pub mod package;
pub mod replay;
pub mod table;
#[cfg(test)]
mod tests;

pub use ffi::Status;
