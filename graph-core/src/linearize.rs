//! Linearisation of a compiled graph around an operating point: the
//! continuous model dx = A x + B u, y = C x + D u from an injected input
//! signal to a measured output signal, optionally with the loop cut at a
//! signal (Simulink's loop-opening analysis points).
//!
//! Block by block, in execution order, each signal gets its linear
//! expression in the states and the injected input: continuous LTI blocks
//! contribute their own matrices exactly ([`Block::lti`]); every other
//! block is linearised by central differences of its `output` and
//! `derivatives` in its own inputs and states, a step of 6·10⁻⁶ of the
//! value (at least 6·10⁻⁶), exact to rounding for linear blocks such as
//! gains and sums. Where the one-sided differences disagree the block is
//! not smooth at the operating point: the central difference is used and a
//! warning names the block. Discrete blocks and transport delays on the
//! analysed path are refused with the reason.

use crate::compile::{Model, Rate};
use crate::diag::Diagnostic;
use crate::sim::{SimError, Simulator, io_for};
use ctlgraph_solver::StateSpace;

pub use crate::spec::Selection;

/// A linear model of the selected path, states named by their block.
#[derive(Clone, Debug)]
pub struct Linearization {
    pub system: StateSpace,
    /// `block` for a block's only state, `block.x1`, `block.x2`, … otherwise.
    pub states: Vec<String>,
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
    let (model, signals, x) = sim.operating_point();
    let nx = x.len();
    let mut lin = Propagation::new(model, t, nx);
    lin.outputs(signals, x, u_at, open_at);
    lin.derivatives(signals, x);
    lin.refuse_unlinearizable()?;
    let measured = match y_at {
        Some(y) if Some(y) == open_at => lin.upstream.clone(),
        Some(y) => lin.row(y).to_vec(),
        None => vec![0.0; nx + 1],
    };
    let sign = if loop_transfer { -1.0 } else { 1.0 };
    let system = StateSpace {
        n: nx,
        m: 1,
        p: 1,
        a: lin.dx.iter().flat_map(|r| r[..nx].to_vec()).collect(),
        b: lin.dx.iter().map(|r| r[nx]).collect(),
        c: measured[..nx].iter().map(|v| sign * v).collect(),
        d: vec![sign * measured[nx]],
    };
    let states = state_names(lin.model);
    let on_path = |i: usize| !lin.model.meta[i].states.is_empty() || lin.driven(&lin.elements(i).0);
    let names =
        |list: &[usize]| list.iter().filter(|&&i| on_path(i)).map(|&i| lin.model.meta[i].name.clone()).collect();
    Ok(Linearization {
        system,
        states,
        input,
        output,
        loop_transfer,
        at: t,
        exact: names(&lin.exact),
        perturbed: names(&lin.perturbed),
        warnings: lin.warnings,
    })
}

fn state_names(model: &Model) -> Vec<String> {
    let mut names = vec![String::new(); model.n_states];
    for m in &model.meta {
        for (k, s) in m.states.clone().enumerate() {
            names[s] = if m.states.len() == 1 { m.name.clone() } else { format!("{}.x{}", m.name, k + 1) };
        }
    }
    names
}

/// The perturbation step for a value: 6·10⁻⁶ of it (about the cube root of
/// the machine epsilon, the best for central differences), and no less
/// than 6·10⁻⁶ itself, so that rounding in values of order one stays below
/// 10⁻¹⁰ of the slope.
fn step(v: f64) -> f64 {
    6e-6 * v.abs().max(1.0)
}

/// Linear expressions of every signal in (states, injected input), and of
/// every state derivative, built block by block.
struct Propagation<'m> {
    model: &'m mut Model,
    t: f64,
    /// Variables: the states, then the injected input.
    nv: usize,
    /// Row per signal element.
    expr: Vec<f64>,
    /// Row per state.
    dx: Vec<Vec<f64>>,
    /// The opened signal's upstream expression.
    upstream: Vec<f64>,
    exact: Vec<usize>,
    perturbed: Vec<usize>,
    warnings: Vec<String>,
}

impl<'m> Propagation<'m> {
    fn new(model: &'m mut Model, t: f64, nx: usize) -> Self {
        let nv = nx + 1;
        Propagation {
            expr: vec![0.0; model.signal_len * nv],
            dx: vec![vec![0.0; nv]; nx],
            upstream: vec![0.0; nv],
            exact: Vec::new(),
            perturbed: Vec::new(),
            warnings: Vec::new(),
            model,
            t,
            nv,
        }
    }

    fn row(&self, signal: usize) -> &[f64] {
        &self.expr[signal * self.nv..(signal + 1) * self.nv]
    }

    /// The offsets of block `i`'s input elements, each with whether its
    /// port has direct feedthrough, and of its output elements.
    fn elements(&self, i: usize) -> (Vec<(usize, bool)>, Vec<usize>) {
        let m = &self.model.meta[i];
        let feeds =
            |p: usize| self.model.edges.iter().any(|e| e.dst == i && e.dst_port == p - m.inputs.start && e.feedthrough);
        let inputs = m
            .inputs
            .clone()
            .flat_map(|p| {
                let port = self.model.in_ports[p];
                let f = feeds(p);
                (port.offset..port.offset + port.width).map(move |o| (o, f))
            })
            .collect();
        let outputs = m
            .outputs
            .clone()
            .flat_map(|p| {
                let port = self.model.out_ports[p];
                port.offset..port.offset + port.width
            })
            .collect();
        (inputs, outputs)
    }

    /// Whether any of block `i`'s inputs depends on a state or the input.
    fn driven(&self, inputs: &[(usize, bool)]) -> bool {
        inputs.iter().any(|&(o, _)| self.row(o).iter().any(|v| *v != 0.0))
    }

    /// Output expressions of every block in execution order, the input
    /// injected (or the loop cut) where its signal is produced.
    fn outputs(&mut self, signals: &mut [f64], x: &mut [f64], u_at: Option<usize>, open_at: Option<usize>) {
        let nv = self.nv;
        for i in 0..self.model.meta.len() {
            let (inputs, outputs) = self.elements(i);
            let states = self.model.meta[i].states.clone();
            let rate = self.model.slots[i].rate;
            // Discrete outputs hold between hits; sources are constants here.
            let skip = matches!(rate, Rate::Discrete(_)) || (inputs.is_empty() && states.is_empty());
            if !skip && self.model.blocks[i].not_linearizable().is_none() {
                let rows = if let Some(ss) = self.model.blocks[i].lti().cloned() {
                    self.exact.push(i);
                    let mut rows = vec![vec![0.0; nv]; outputs.len()];
                    for (r, row) in rows.iter_mut().enumerate() {
                        for (k, s) in states.clone().enumerate() {
                            row[s] += ss.c[r * ss.n + k];
                        }
                        for (j, &(o, _)) in inputs.iter().enumerate() {
                            let d = ss.d[r * ss.m + j];
                            for (v, e) in row.iter_mut().zip(&self.expr[o * nv..(o + 1) * nv]) {
                                *v += d * e;
                            }
                        }
                    }
                    rows
                } else {
                    self.perturbed.push(i);
                    let fed: Vec<usize> = inputs.iter().filter(|(_, f)| *f).map(|(o, _)| *o).collect();
                    self.perturb(i, signals, x, &fed, &outputs, Kind::Output)
                };
                for (&o, row) in outputs.iter().zip(rows) {
                    self.expr[o * nv..(o + 1) * nv].copy_from_slice(&row);
                }
            }
            // The cut: downstream of the opening sees nothing of the path
            // (only the injected input, when it enters there).
            if let Some(o) = open_at.filter(|o| outputs.contains(o)) {
                let row = &mut self.expr[o * nv..(o + 1) * nv];
                self.upstream = row.to_vec();
                row.fill(0.0);
            }
            if let Some(u) = u_at.filter(|u| outputs.contains(u)) {
                self.expr[(u + 1) * nv - 1] += 1.0;
            }
        }
    }

    /// State-derivative expressions of every continuous block with states.
    fn derivatives(&mut self, signals: &mut [f64], x: &mut [f64]) {
        let nv = self.nv;
        for i in 0..self.model.meta.len() {
            let states = self.model.meta[i].states.clone();
            if states.is_empty() || self.model.slots[i].rate != Rate::Continuous {
                continue;
            }
            let (inputs, _) = self.elements(i);
            let rows = if let Some(ss) = self.model.blocks[i].lti().cloned() {
                let mut rows = vec![vec![0.0; nv]; states.len()];
                for (r, row) in rows.iter_mut().enumerate() {
                    for (k, s) in states.clone().enumerate() {
                        row[s] += ss.a[r * ss.n + k];
                    }
                    for (j, &(o, _)) in inputs.iter().enumerate() {
                        let b = ss.b[r * ss.m + j];
                        for (v, e) in row.iter_mut().zip(&self.expr[o * nv..(o + 1) * nv]) {
                            *v += b * e;
                        }
                    }
                }
                rows
            } else {
                let all: Vec<usize> = inputs.iter().map(|(o, _)| *o).collect();
                self.perturb(i, signals, x, &all, &states.clone().collect::<Vec<_>>(), Kind::Derivative)
            };
            for (s, row) in states.zip(rows) {
                self.dx[s] = row;
            }
        }
    }

    /// Rows of block `i`'s outputs (or state derivatives) by central
    /// differences in the input elements `inputs` and its own states,
    /// composed with those inputs' expressions.
    fn perturb(
        &mut self,
        i: usize,
        signals: &mut [f64],
        x: &mut [f64],
        inputs: &[usize],
        targets: &[usize],
        kind: Kind,
    ) -> Vec<Vec<f64>> {
        let nv = self.nv;
        let states: Vec<usize> = self.model.meta[i].states.clone().collect();
        let base = self.evaluate(i, signals, x, kind);
        let mut rows = vec![vec![0.0; nv]; targets.len()];
        let mut rough = Vec::new();
        // Each variable: (is it an input element, its index).
        let variables = inputs.iter().map(|&o| (true, o)).chain(states.iter().map(|&s| (false, s)));
        for (is_input, k) in variables {
            let value = if is_input { signals[k] } else { x[k] };
            let h = step(value);
            let mut at = |v: f64, signals: &mut [f64], x: &mut [f64]| {
                if is_input {
                    signals[k] = v
                } else {
                    x[k] = v
                }
                self.evaluate(i, signals, x, kind)
            };
            let plus = at(value + h, signals, x);
            let minus = at(value - h, signals, x);
            at(value, signals, x);
            for (r, row) in rows.iter_mut().enumerate() {
                let slope = (plus[r] - minus[r]) / (2.0 * h);
                let (right, left) = ((plus[r] - base[r]) / h, (base[r] - minus[r]) / h);
                if (right - left).abs() > 1e-3 * right.abs().max(left.abs()) + 1e-9 {
                    rough.push((r, right, left));
                }
                if is_input {
                    for (v, e) in row.iter_mut().zip(&self.expr[k * nv..(k + 1) * nv]) {
                        *v += slope * e;
                    }
                } else {
                    row[k] += slope;
                }
            }
        }
        // Leave the block's outputs as they were at the operating point.
        self.evaluate(i, signals, x, Kind::Output);
        if let Some(&(r, right, left)) = rough.first() {
            let m = &self.model.meta[i];
            let what = match kind {
                Kind::Output => "output",
                Kind::Derivative => "state derivative",
            };
            self.warnings.push(format!(
                "block `{}` ({}) is not smooth at the operating point: {what} {} has slope {right} to the right and {left} \
                 to the left; their mean is used",
                m.name,
                m.type_name,
                r + 1
            ));
        }
        rows
    }

    /// Block `i`'s outputs (or state derivatives) at the given values.
    fn evaluate(&mut self, i: usize, signals: &mut [f64], x: &[f64], kind: Kind) -> Vec<f64> {
        let m = &mut *self.model;
        let slot = &m.slots[i];
        match kind {
            Kind::Output => {
                let mut io = io_for(slot, self.t, false, x, signals, &m.in_ports, &m.out_ports);
                m.blocks[i].output(&mut io);
                m.meta[i]
                    .outputs
                    .clone()
                    .flat_map(|p| {
                        let port = m.out_ports[p];
                        signals[port.offset..port.offset + port.width].to_vec()
                    })
                    .collect()
            }
            Kind::Derivative => {
                let io = io_for(slot, self.t, false, x, signals, &m.in_ports, &m.out_ports);
                let mut dx = vec![0.0; slot.states.len()];
                m.blocks[i].derivatives(&io, &mut dx);
                dx
            }
        }
    }

    /// Refuses a path through a discrete block or one without a linear model.
    fn refuse_unlinearizable(&self) -> Result<(), Diagnostic> {
        for i in 0..self.model.meta.len() {
            let (inputs, _) = self.elements(i);
            if !self.driven(&inputs) {
                continue;
            }
            let m = &self.model.meta[i];
            let at = |why: String| {
                Diagnostic::at(&m.pos, format!("block `{}` ({}) is on the analysed path: {why}", m.name, m.type_name))
            };
            if let Some(why) = self.model.blocks[i].not_linearizable() {
                return Err(at(why.to_string()));
            }
            if let Rate::Discrete(_) = self.model.slots[i].rate {
                return Err(at(format!(
                    "it is discrete (sample time {}); ctlgraph linearises continuous paths only",
                    m.sample_time
                ))
                .with_hint("analyse the continuous design, or open the loop before the discrete block"));
            }
        }
        Ok(())
    }
}

#[derive(Clone, Copy)]
enum Kind {
    Output,
    Derivative,
}
