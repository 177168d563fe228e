//! What happens between major steps, decided once at compile time: which
//! blocks the solver's minor steps must evaluate, which carry continuous
//! states to integrate, and which LTI blocks can instead be advanced by
//! their exact zero-order-hold transition.
//!
//! A signal is *piecewise constant* (Simulink: "fixed in minor step") when
//! it cannot change between two major steps: outputs of constant and
//! discrete blocks (their hits are major steps), and of blocks declaring
//! [`crate::block::Interface::piecewise_constant`] whose inputs all are.
//! Minor steps must evaluate only what a derivative or a watched
//! zero-crossing function reads, through signals that are not piecewise
//! constant. An LTI block whose inputs are all piecewise constant, and whose
//! outputs no minor-step evaluation reads, is *held*: its states leave the
//! integrator and jump exactly from one major step to the next.

use super::{Model, Rate};
use crate::flatten::ZeroCrossing;

/// The plan the simulator follows between major steps.
#[derive(Clone, Debug, Default)]
pub(crate) struct Between {
    /// Blocks whose outputs minor steps recompute, in execution order.
    pub minor: Vec<usize>,
    /// Blocks whose states the solver integrates (their `derivatives`).
    pub integrated: Vec<usize>,
    /// LTI blocks advanced exactly; their states follow the integrated ones.
    pub held: Vec<usize>,
    /// Length of the integrated prefix of the state vector.
    pub n_integrated: usize,
    /// Per block: its outputs change only at block events (a step source, a
    /// sum of steps), so major steps without an event need not run it.
    pub event_only: Vec<bool>,
}

/// Decides the plan and lays the states out: integrated blocks' first, held
/// blocks' after. `exact_lti` enables holding (fixed-step methods only: an
/// adaptive method's steps, and so the recorded samples, would change if
/// the states it controls its error on were taken from it).
pub(super) fn plan(model: &mut Model) {
    let n = model.blocks.len();
    let mut drivers = vec![Vec::new(); n];
    for e in &model.edges {
        drivers[e.dst].push(e.src);
    }
    let is_continuous: Vec<bool> = model.meta.iter().map(|m| m.rate == Rate::Continuous).collect();
    let is_stateful: Vec<bool> = model.blocks.iter().map(|b| b.num_states() > 0).collect();
    let (continuous, has_states) = (|i: usize| is_continuous[i], |i: usize| is_stateful[i]);
    // A block is piecewise constant once all its drivers are.
    let start: Vec<bool> = (0..n).map(|i| !continuous(i)).collect();
    let piecewise: Vec<bool> = model.meta.iter().map(|m| m.piecewise_constant).collect();
    let constant = closure(start, |i, set| piecewise[i] && !has_states(i) && drivers[i].iter().all(|&d| set[d]));
    // Event-only: continuous, piecewise constant, and fed only by constant
    // or event-only blocks (a source without inputs changes at its events).
    let is_constant_rate: Vec<bool> = model.meta.iter().map(|m| m.rate == Rate::Constant).collect();
    let event_only = closure(vec![false; n], |i, set| {
        continuous(i) && constant[i] && drivers[i].iter().all(|&d| is_constant_rate[d] || set[d])
    });
    let exact = model.sim.exact_lti && !model.sim.method.is_adaptive();
    let mut held: Vec<bool> = (0..n)
        .map(|i| {
            exact
                && continuous(i)
                && has_states(i)
                && model.blocks[i].lti().is_some()
                && drivers[i].iter().all(|&d| constant[d])
        })
        .collect();
    let watching = model.sim.zero_crossing != ZeroCrossing::Off;
    let is_watched: Vec<bool> = model.blocks.iter().map(|b| watching && b.needs_major_step()).collect();
    let watched = |i: usize| is_watched[i];
    // Blocks keeping their input's past read it at breakpoints' left limits,
    // which a minor-step evaluation computes.
    let keeps_history: Vec<bool> = model.blocks.iter().map(|b| b.keeps_history()).collect();
    // Minor steps evaluate the integrated and watched blocks and, backwards,
    // every continuous signal they read that may change within a step. A
    // held block reached that way is read there after all: integrate it.
    let minor = loop {
        let mut minor = vec![false; n];
        let mut stack: Vec<usize> = (0..n)
            .filter(|&i| continuous(i) && !held[i] && (has_states(i) || watched(i) || keeps_history[i]))
            .collect();
        for &i in &stack {
            minor[i] = true;
        }
        while let Some(i) = stack.pop() {
            for &d in &drivers[i] {
                if continuous(d) && !constant[d] && !minor[d] {
                    minor[d] = true;
                    stack.push(d);
                }
            }
        }
        let read_in_minor: Vec<usize> = (0..n).filter(|&i| held[i] && minor[i]).collect();
        if read_in_minor.is_empty() {
            break minor;
        }
        for i in read_in_minor {
            held[i] = false;
        }
    };
    let mut between = Between { event_only, ..Between::default() };
    let mut next = 0;
    for i in 0..n {
        if minor[i] {
            between.minor.push(i);
        }
        if continuous(i) && has_states(i) && !held[i] {
            between.integrated.push(i);
        }
        if !held[i] {
            next = relocate(model, i, next);
        }
    }
    between.n_integrated = next;
    for i in (0..n).filter(|&i| held[i]) {
        between.held.push(i);
        model.meta[i].exact_zoh = true;
        next = relocate(model, i, next);
    }
    model.between = between;
}

/// The least set containing `set` and closed under `rule`: adds every `i`
/// for which `rule(i, set)` holds until nothing changes.
fn closure(mut set: Vec<bool>, rule: impl Fn(usize, &[bool]) -> bool) -> Vec<bool> {
    loop {
        let mut changed = false;
        for i in 0..set.len() {
            if !set[i] && rule(i, &set) {
                set[i] = true;
                changed = true;
            }
        }
        if !changed {
            return set;
        }
    }
}

/// Gives block `i` the states from `start` on; returns the next free index.
fn relocate(model: &mut Model, i: usize, start: usize) -> usize {
    let len = model.meta[i].states.len();
    model.meta[i].states = start..start + len;
    model.slots[i].states = start..start + len;
    start + len
}
