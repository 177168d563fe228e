//! A generated step's run with the graph's code inlined into the loop
//! that runs it whole (the step library's `run_rows`, which every
//! accelerated `run`, `sweep`, `test` and Python `run` takes). Everywhere
//! else the sweeps are one out-of-line copy, called once per major step
//! ([`Compiled`]'s `output_sweep`); here the loop carries its own copy: a
//! LADRC sample 26 instructions fewer (the calls, their saved registers
//! and what the loop reloads after them), for the graph's code compiled
//! twice into the library.

use super::driver::{Compiled, GeneratedStep};
use crate::block::Breakpoint;
use crate::compile::BlockMeta;
use crate::sim::{Clockwork, SimError, Sweeps, driver};

/// [`Compiled`] whose sweeps inline into the driver's loop.
pub(super) struct Inlined<'a, G: GeneratedStep>(pub(super) &'a mut Compiled<G>);

/// Forwards [`Sweeps`] methods to the run, inlined: those taking
/// `&self`, then (after `mut:`) those taking `&mut self`.
macro_rules! forward {
    ($(fn $name:ident($($arg:ident: $ty:ty),*) $(-> $ret:ty)?;)* mut: $(fn $mname:ident($($marg:ident: $mty:ty),*) $(-> $mret:ty)?;)*) => {
        $(
            #[inline(always)]
            fn $name(&self $(, $arg: $ty)*) $(-> $ret)? {
                Sweeps::$name(&*self.0 $(, $arg)*)
            }
        )*
        $(
            #[inline(always)]
            fn $mname(&mut self $(, $marg: $mty)*) $(-> $mret)? {
                Sweeps::$mname(&mut *self.0 $(, $marg)*)
            }
        )*
    };
}

impl<G: GeneratedStep> Sweeps for Inlined<'_, G> {
    #[inline(always)]
    fn output_sweep(&mut self) -> Result<(), Box<SimError>> {
        self.0.sweep_outputs()
    }

    #[inline(always)]
    fn update_sweep(&mut self) {
        self.0.sweep_updates();
    }

    forward! {
        fn clockwork() -> &Clockwork;
        fn signals() -> &[f64];
        fn states() -> &[f64];
        fn earliest_event() -> (f64, u32);
        fn block_event(block: usize, t: f64) -> f64;
        fn keeps_history() -> bool;
        fn plain_grid_steps() -> bool;
        fn names() -> &[BlockMeta];
        fn blame_states() -> SimError;
    mut:
        fn clockwork_mut() -> &mut Clockwork;
        fn initialize();
        fn external_input(block: usize) -> Option<&mut [f64]>;
        fn latch_held();
        fn step_held(dt: f64);
        fn integrate(t0: f64, target: f64) -> Result<f64, SimError>;
        fn locate_crossing(t0: f64, t1: f64, target: f64) -> Result<Option<f64>, SimError>;
        fn clamp_states() -> bool;
        fn left_limits(at: Breakpoint);
        fn step_started(t0: f64);
        fn solver_reached(t: f64);
        fn step_ended();
        fn major_row(t: f64) -> Option<f64>;
        fn rows_inside_step(sink: &mut dyn FnMut(f64, &[f64]) -> bool) -> bool;
    }
}

impl<G: GeneratedStep> Compiled<G> {
    /// [`Compiled::run_while`] with the graph's code inlined into the run's
    /// loop (see the module's doc): for the one loop that runs whole runs.
    pub fn run_while_inlined(&mut self, sink: impl FnMut(f64, &[f64]) -> bool) -> Result<bool, SimError> {
        driver::run_while(&mut Inlined(self), sink)
    }
}
