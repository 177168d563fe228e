//! The interpreter back-end: the sweeps the driver (`driver.rs`) asks
//! for, walking the simulator's visit lists over the model's blocks.

use super::driver::{Clockwork, Sweeps};
use super::events::Watch;
use super::{Blame, Minor, SimError, Simulator, all_finite, io_for, visit};
use crate::block::{Breakpoint, Io};
use crate::compile::{BlockMeta, Rate};

impl Simulator {
    /// Runs `output` of every block due now, in execution order:
    /// continuous blocks always (those that change only at events, only
    /// at events), discrete blocks at their hits, constant blocks on the
    /// first pass only.
    fn sweep(&mut self) {
        let (m, s) = (&*self.model, &mut self.state);
        let c = &s.clockwork;
        let all = c.first || c.at_event || c.inputs_changed;
        let order = if all { &self.every } else { &self.regular };
        for integrator in &self.integrands {
            integrator.output(&s.x, &mut s.signals);
        }
        let (hit, first, t, x, blocks) = (&c.hit[..], c.first, c.t, &s.x, &mut s.blocks);
        let computed_at = &mut self.computed_at;
        visit::sweep(
            order,
            &mut s.signals,
            |v| due(v.rate, hit, first),
            #[inline(always)]
            |v, signals| {
                if computed_at.must_run(v, t, false) {
                    let slot = &m.slots[v.block];
                    let mut io = io_for(slot, t, false, x, signals, &m.in_ports, &m.out_ports);
                    blocks[v.block].output(&mut io);
                }
            },
        );
    }

    /// Blocks with zero crossings may reset their states at a major step;
    /// returns whether any did.
    #[inline(always)]
    fn major_step_events(&mut self) -> bool {
        let (m, s) = (&*self.model, &mut self.state);
        let mut changed = false;
        for &i in &s.watch.blocks {
            let slot = &m.slots[i];
            let (inputs, outputs) = (&m.in_ports[slot.inputs.clone()], &m.out_ports[slot.outputs.clone()]);
            let io = Io::new(s.clockwork.t, false, &[], &mut s.signals, inputs, outputs);
            changed |= s.blocks[i].major_step(&io, &mut s.x[slot.states.clone()]);
        }
        changed
    }

    /// The system the solver integrates between `t` and `t_end`, the
    /// first stage reusing the major step's outputs when `at_start`.
    /// With it, the parts of the run it does not hold: the time keeping,
    /// all states, the zero-crossing watch.
    fn minor_system(&mut self, t_end: f64, at_start: bool) -> (Minor<'_>, &mut Clockwork, &mut [f64], &mut Watch) {
        let s = &mut self.state;
        let sys = Minor {
            model: &self.model,
            blocks: &mut s.blocks,
            signals: &mut s.signals,
            continuous: &self.minor,
            at_start: at_start.then_some(&self.stale_at_start[..]),
            stateful: &self.stateful,
            integrands: &self.integrands,
            computed_at: &mut self.computed_at,
            t_end,
        };
        (sys, &mut s.clockwork, &mut s.x, &mut s.watch)
    }

    /// [`Sweeps::locate_crossing`] with crossings to watch.
    fn locate_watched(&mut self, t0: f64, t1: f64, target: f64) -> Result<Option<f64>, SimError> {
        let (mut sys, clockwork, x, watch) = self.minor_system(target, false);
        let x = &mut x[..clockwork.n_integrated];
        let Some(t) = watch.locate(&mut sys, &mut clockwork.integ, t0, t1, x) else { return Ok(None) };
        let s = &mut self.state;
        for (_, block, k) in s.watch.fired() {
            s.blocks[block].crossing_located(k);
        }
        if let Some((_, block)) = s.watch.count_event(t, &self.model.meta)? {
            s.blocks[block].frozen = false;
        }
        Ok(Some(t))
    }
}

impl Sweeps for Simulator {
    #[inline(always)]
    fn clockwork(&self) -> &Clockwork {
        &self.state.clockwork
    }

    #[inline(always)]
    fn clockwork_mut(&mut self) -> &mut Clockwork {
        &mut self.state.clockwork
    }

    #[inline]
    fn signals(&self) -> &[f64] {
        &self.state.signals
    }

    #[inline]
    fn states(&self) -> &[f64] {
        &self.state.x
    }

    fn initialize(&mut self) {
        self.outputs_current = false;
        self.computed_at.forget();
        let s = &mut self.state;
        s.signals.iter_mut().for_each(|v| *v = 0.0);
        for (b, m) in s.blocks.iter_mut().zip(&self.model.slots) {
            b.initialize(&mut s.x[m.states.clone()]);
        }
        s.watch.reset();
        s.blocks.iter_mut().for_each(|b| b.frozen = false);
        for &i in &s.watch.blocks {
            s.blocks[i].frozen = s.watch.freezes();
        }
        if let Some(dense) = &mut s.dense {
            dense.reset();
        }
    }

    #[inline]
    fn output_sweep(&mut self) -> Result<(), Box<SimError>> {
        self.sweep();
        if self.major_step_events() {
            self.sweep();
        }
        let s = &mut self.state;
        let (m, t, x, signals, blocks) = (&*self.model, s.clockwork.t, &s.x, &mut s.signals, &s.blocks);
        s.watch.record_signs(|_, i, g| {
            blocks[i].zero_crossings(&io_for(&m.slots[i], t, false, x, signals, &m.in_ports, &m.out_ports), g);
        });
        if !all_finite(&s.signals) {
            let s = &self.state;
            return Err(Box::new(Blame::of(&self.model).signal(&s.signals, s.clockwork.t, |i| s.blocks[i].diagnose())));
        }
        self.outputs_current = true;
        Ok(())
    }

    fn external_input(&mut self, block: usize) -> Option<&mut [f64]> {
        self.state.blocks.get_mut(block)?.external_input()
    }

    /// Runs `update` of the blocks that have one (see [`crate::block::Block::updates`])
    /// and are due now: continuous ones always, discrete ones at hits.
    #[inline(always)]
    fn update_sweep(&mut self) {
        let (m, s) = (&*self.model, &mut self.state);
        let (t, hit) = (s.clockwork.t, &s.clockwork.hit[..]);
        for v in &self.updating {
            if due(v.rate, hit, false) {
                let slot = &m.slots[v.block];
                let mut io = io_for(slot, t, false, &s.x, &mut s.signals, &m.in_ports, &m.out_ports);
                s.blocks[v.block].update(&mut io);
            }
        }
    }

    fn earliest_event(&self) -> (f64, u32) {
        self.earliest_event_after(self.state.clockwork.t)
    }

    fn block_event(&self, block: usize, t: f64) -> f64 {
        self.state.blocks[block].next_event(t)
    }

    #[inline(always)]
    fn latch_held(&mut self) {
        let s = &mut self.state;
        for h in &self.held {
            // Element by element: one or two values, where copy_from_slice calls memcpy.
            for (u, &v) in s.held_inputs[h.latched.clone()].iter_mut().zip(&s.signals[h.input.clone()]) {
                *u = v;
            }
        }
    }

    #[inline(always)]
    fn step_held(&mut self, dt: f64) {
        let s = &mut self.state;
        for h in &mut self.held {
            h.zoh.step(dt, &mut s.x[h.states.clone()], &s.held_inputs[h.latched.clone()]);
        }
    }

    #[inline(always)]
    fn integrate(&mut self, t0: f64, target: f64) -> Result<f64, SimError> {
        let current = std::mem::take(&mut self.outputs_current) && !self.state.clockwork.inputs_changed;
        let (mut sys, clockwork, x, _) = self.minor_system(target, current);
        match clockwork.integ.advance(&mut sys, t0, target, &mut x[..clockwork.n_integrated]) {
            Ok(t) => Ok(t),
            Err(error) => Err(Blame::of(sys.model).solver(sys.signals, t0, error)),
        }
    }

    #[inline(always)]
    fn locate_crossing(&mut self, t0: f64, t1: f64, target: f64) -> Result<Option<f64>, SimError> {
        if self.state.watch.blocks.is_empty() { Ok(None) } else { self.locate_watched(t0, t1, target) }
    }

    #[inline(always)]
    fn clamp_states(&mut self) -> bool {
        let s = &mut self.state;
        let mut clamped = false;
        for &i in &self.stateful {
            clamped |= s.blocks[i].clamp_states(&mut s.x[self.model.slots[i].states.clone()]);
        }
        clamped
    }

    #[inline]
    fn keeps_history(&self) -> bool {
        !self.history.is_empty()
    }

    fn left_limits(&mut self, at: Breakpoint) {
        let t = self.state.clockwork.t;
        let (mut sys, _, x, _) = self.minor_system(t, false);
        sys.outputs(t, x);
        self.hand_left_limits(at);
    }

    #[inline]
    fn plain_grid_steps(&self) -> bool {
        self.history.is_empty() && self.state.watch.blocks.is_empty() && self.state.dense.is_none()
    }

    fn names(&self) -> &[BlockMeta] {
        &self.model.meta
    }

    fn blame_states(&self) -> SimError {
        let s = &self.state;
        Blame::of(&self.model).state(&s.signals, s.clockwork.t, &s.x)
    }

    #[inline]
    fn step_started(&mut self, t0: f64) {
        if let Some(dense) = &mut self.state.dense {
            dense.start(t0, &self.state.x);
        }
    }

    #[inline]
    fn solver_reached(&mut self, t: f64) {
        let s = &mut self.state;
        if let Some(dense) = &mut s.dense {
            dense.solver_end(t, &s.x[..s.clockwork.n_integrated]);
        }
    }

    #[inline]
    fn step_ended(&mut self) {
        if let Some(dense) = &mut self.state.dense {
            dense.end(self.state.clockwork.t);
        }
    }

    #[inline]
    fn major_row(&mut self, t: f64) -> Option<f64> {
        self.state.dense.as_mut().map_or(Some(t), |dense| dense.major_row(t))
    }

    #[inline(always)]
    fn rows_inside_step(&mut self, sink: &mut dyn FnMut(f64, &[f64]) -> bool) -> bool {
        self.dense_rows(sink)
    }
}

/// Whether a block of `rate` runs now: continuous ones always, discrete
/// ones at their clock's hits, constant ones when `constant_too`.
#[inline(always)]
fn due(rate: Rate, hit: &[bool], constant_too: bool) -> bool {
    match rate {
        Rate::Continuous => true,
        Rate::Constant => constant_too,
        Rate::Discrete(c) => hit[c],
    }
}
