//! ODE integrators and linear-time-invariant numerics for ctlgraph.
//!
//! This crate knows differential equations, not block diagrams: the graph
//! simulator in `ctlgraph-core` implements [`OdeSystem`] and drives an
//! [`Integrator`] from one major step to the next.

// Index loops mirror the textbook formulas of the numerical methods.
#![allow(clippy::needless_range_loop)]

pub mod cascade;
#[cfg(feature = "implicit")]
pub mod dense_lu;
#[cfg(feature = "implicit")]
pub mod freq;
pub mod lti;
pub mod ode;
pub mod poly;
pub mod zoh;

pub use cascade::factored_tf2ss;
pub use lti::{StateSpace, tf2ss, zpk2tf};
pub use ode::{Integrator, Method, OdeSystem, SolverError, Stats};
pub use zoh::{Zoh, ZohSingleInput};
