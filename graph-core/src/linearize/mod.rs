//! Linearisation of a compiled graph around an operating point: the
//! model dx = A x + B u, y = C x + D u from an injected input signal to a
//! measured output signal, optionally with the loop cut at a signal
//! (Simulink's loop-opening analysis points).
//!
//! Block by block, in execution order, each signal gets its linear
//! expression in the states and the injected input: continuous LTI blocks
//! contribute their own matrices exactly ([`Block::lti`]); every other
//! block is linearised by central differences of its `output` and
//! `derivatives` in its own inputs and states, a step of 6·10⁻⁶ of the
//! value (at least 6·10⁻⁶), exact to rounding for linear blocks such as
//! gains and sums. Where the one-sided differences disagree the block is
//! not smooth at the operating point: the central difference is used and a
//! warning names the block. Transport delays on the path are refused.
//!
//! A path through discrete blocks gives the exact sampled-data model at
//! their sample time T (one rate; mixed rates are refused): states are the
//! continuous states and the discrete blocks' own ([`Block::discrete_lti`];
//! memoryless discrete blocks are perturbed), the continuous part is
//! advanced over a period by its zero-order-hold transition under the held
//! discrete outputs and the held injected input, and the output is read at
//! the sample instants.

mod propagate;

use crate::compile::Model;
use crate::diag::Diagnostic;
use crate::sim::{SimError, Simulator};
use ctlgraph_solver::{StateSpace, Zoh};
use propagate::{Mode, Propagation};

pub use crate::spec::Selection;

/// A linear model of the selected path, states named by their block.
#[derive(Clone, Debug)]
pub struct Linearization {
    pub system: StateSpace,
    /// `block` for a block's only state, `block.x1`, `block.x2`, … otherwise
    /// (`block.z1`, … for a discrete block's own states).
    pub states: Vec<String>,
    /// `Some(T)`: the model is discrete, at sample time T.
    pub sample_time: Option<f64>,
    pub input: String,
    pub output: String,
    /// The model is the loop transfer L = −(measured / injected) at the
    /// opening (negative-feedback convention: margins read as usual).
    pub loop_transfer: bool,
    pub at: f64,
    /// Blocks on the path taken from their own matrices, and those
    /// linearised by perturbation.
    pub exact: Vec<String>,
    pub perturbed: Vec<String>,
    pub warnings: Vec<String>,
}

/// Why a linearisation could not be made.
#[derive(Clone, Debug)]
pub enum AnalysisError {
    /// A selection names no signal, or the path cannot be linearised.
    Invalid(Diagnostic),
    /// The run to the operating point failed.
    Run(SimError),
}

impl std::fmt::Display for AnalysisError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            AnalysisError::Invalid(d) => write!(f, "{d}"),
            AnalysisError::Run(e) => write!(f, "reaching the operating point: {e}"),
        }
    }
}

impl std::error::Error for AnalysisError {}

impl From<Diagnostic> for AnalysisError {
    fn from(d: Diagnostic) -> Self {
        AnalysisError::Invalid(d)
    }
}

/// Linearises `model` as `sel` says (see the module documentation).
pub fn linearize(model: Model, sel: &Selection) -> Result<Linearization, AnalysisError> {
    let (input, output, loop_transfer) = match (&sel.input, &sel.output, &sel.open) {
        (Some(i), Some(o), _) => (i.clone(), o.clone(), false),
        (None, None, Some(p)) => (p.clone(), p.clone(), true),
        // No signals: the states alone (A for the poles; B, C, D zero).
        (None, None, None) => (String::new(), String::new(), false),
        _ => {
            return Err(Diagnostic::plain(
                "say what to analyse: an input and an output signal, or a loop opening alone",
            )
            .with_hint("--input ctrl.u --output plant.y [--open ctrl.u], or --open ctrl.u for the loop transfer there")
            .into());
        }
    };
    let signal = |name: &str| (!name.is_empty()).then(|| model.signal_offset(name)).transpose();
    let (u_at, y_at) = (signal(&input)?, signal(&output)?);
    let open_at = sel.open.as_deref().map(|s| model.signal_offset(s)).transpose()?;
    if !(sel.at >= 0.0 && sel.at.is_finite()) {
        return Err(Diagnostic::plain(format!("--at {}: a time from 0", sel.at)).into());
    }
    // The run stops exactly at the operating point.
    let stop = if sel.at > 0.0 { sel.at } else { model.sim.stop };
    let mut sim = Simulator::new(model, Some(stop));
    sim.outputs().map_err(AnalysisError::Run)?;
    while sim.time() < sel.at && !sim.finished() {
        sim.advance().map_err(AnalysisError::Run)?;
        sim.outputs().map_err(AnalysisError::Run)?;
    }
    let t = sim.time();
    let point = sim.operating_point();
    let (signals, x) = (point.signals, point.x);
    let mut at_hit = Propagation::new(point.model, point.blocks, t, Mode::Instant);
    at_hit.outputs(signals, x, u_at, open_at);
    at_hit.dynamics(signals, x);
    at_hit.refuse_unlinearizable()?;
    let measured = match y_at {
        Some(y) if Some(y) == open_at => at_hit.upstream.clone(),
        Some(y) => at_hit.row(y).to_vec(),
        None => vec![0.0; at_hit.nv],
    };
    let rates = at_hit.driven_rates();
    let (exact, perturbed) = named_on_path(&at_hit);
    let mut warnings = std::mem::take(&mut at_hit.warnings);
    let (mut system, states, sample_time) = match rates.as_slice() {
        [] => (continuous(&at_hit, &measured), state_names(at_hit.model), None),
        &[(period, _)] => {
            let (system, states, more) = sampled(at_hit, &measured, (signals, x), (u_at, open_at), (t, period));
            for w in more {
                if !warnings.contains(&w) {
                    warnings.push(w);
                }
            }
            (system, states, Some(period))
        }
        _ => {
            let list: Vec<String> =
                rates.iter().map(|(p, o)| if *o > 0.0 { format!("{p} (offset {o})") } else { p.to_string() }).collect();
            return Err(Diagnostic::plain(format!(
                "the analysed path has discrete blocks at several sample times ({} s): ctlgraph builds a sampled-data model at one rate",
                list.join(", ")
            ))
            .with_hint("give the discrete blocks on the loop one sample time")
            .into());
        }
    };
    if loop_transfer {
        system.c.iter_mut().chain(system.d.iter_mut()).for_each(|v| *v = -*v);
    }
    Ok(Linearization { system, states, input, output, loop_transfer, sample_time, at: t, exact, perturbed, warnings })
}

/// The blocks on the path taken exactly and by perturbation, by name.
fn named_on_path(p: &Propagation) -> (Vec<String>, Vec<String>) {
    let on_path = |i: usize| !p.model.meta[i].states.is_empty() || p.driven(&p.elements(i).0);
    let names = |list: &[usize]| {
        let mut v: Vec<String> = list.iter().filter(|&&i| on_path(i)).map(|&i| p.model.meta[i].name.clone()).collect();
        v.dedup();
        v
    };
    (names(&p.exact), names(&p.perturbed))
}

/// The continuous model: the rows' state and input columns (discrete
/// outputs off the path are constants).
fn continuous(p: &Propagation, measured: &[f64]) -> StateSpace {
    let (nx, u) = (p.nx, p.nv - 1);
    StateSpace {
        n: nx,
        m: 1,
        p: 1,
        a: p.dx.iter().flat_map(|r| r[..nx].to_vec()).collect(),
        b: p.dx.iter().map(|r| r[u]).collect(),
        c: measured[..nx].to_vec(),
        d: vec![measured[u]],
    }
}

/// The sampled-data model at period T: state [x; z], from the rows at a
/// hit (`at_hit`: outputs w of the discrete blocks and their next states,
/// in x, z and u) and the continuous dynamics between hits under held w
/// and u, discretised exactly: x⁺ = Φ x + Γ_w w + Γ_u u. Returns the
/// model, its state names and the warnings of the pass between hits.
fn sampled(
    mut at_hit: Propagation,
    measured: &[f64],
    (signals, x): (&mut [f64], &mut [f64]),
    (u_at, open_at): (Option<usize>, Option<usize>),
    (t, period): (f64, f64),
) -> (StateSpace, Vec<String>, Vec<String>) {
    let (nx, nz) = (at_hit.nx, at_hit.nv - at_hit.nx - 1);
    let ns = nx + nz;
    // The held discrete outputs' rows at the hit, in Interval order.
    let w_rows = at_hit.discrete_output_rows();
    let next = std::mem::take(&mut at_hit.next);
    let discrete_names = std::mem::take(&mut at_hit.extra_names);
    let mut between = Propagation::new(at_hit.model, at_hit.blocks, t, Mode::Interval);
    between.outputs(signals, x, u_at, open_at);
    between.dynamics(signals, x);
    let nw = w_rows.len();
    // Continuous part between hits: dx = Ac x + E [w; u].
    let ac: Vec<f64> = between.dx.iter().flat_map(|r| r[..nx].to_vec()).collect();
    let e: Vec<f64> = between.dx.iter().flat_map(|r| r[nx..].to_vec()).collect();
    let mut zoh = Zoh::new(StateSpace { n: nx, m: nw + 1, p: 0, a: ac, b: e, c: vec![], d: vec![] });
    let (phi, gamma) = zoh.matrices(period);
    let (phi, gamma) = (phi.to_vec(), gamma.to_vec());
    // Assemble rows over [x, z, u] for x⁺ and z⁺.
    let mut a = vec![0.0; ns * ns];
    let mut b = vec![0.0; ns];
    for r in 0..nx {
        let mut row = vec![0.0; ns + 1];
        row[..nx].copy_from_slice(&phi[r * nx..(r + 1) * nx]);
        for (j, w) in w_rows.iter().enumerate() {
            let g = gamma[r * (nw + 1) + j];
            if g != 0.0 {
                row.iter_mut().zip(w).for_each(|(v, wv)| *v += g * wv);
            }
        }
        row[ns] += gamma[r * (nw + 1) + nw];
        a[r * ns..(r + 1) * ns].copy_from_slice(&row[..ns]);
        b[r] = row[ns];
    }
    for k in 0..nz {
        a[(nx + k) * ns..(nx + k + 1) * ns].copy_from_slice(&next[k][..ns]);
        b[nx + k] = next[k][ns];
    }
    let system = StateSpace { n: ns, m: 1, p: 1, a, b, c: measured[..ns].to_vec(), d: vec![measured[ns]] };
    let states = state_names(between.model).into_iter().chain(discrete_names).collect();
    (system, states, between.warnings)
}

/// Names of the continuous states.
fn state_names(model: &Model) -> Vec<String> {
    let mut names = vec![String::new(); model.n_states];
    for m in &model.meta {
        for (k, s) in m.states.clone().enumerate() {
            names[s] = if m.states.len() == 1 { m.name.clone() } else { format!("{}.x{}", m.name, k + 1) };
        }
    }
    names
}
