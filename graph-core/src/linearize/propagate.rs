//! The block-by-block part of linearisation: every signal's linear
//! expression ("row") in the model's variables, built in execution order,
//! and the rows of the state derivatives and discrete updates.

use crate::compile::{Model, Rate};
use crate::diag::Diagnostic;
use crate::sim::RunBlock;
use crate::sim::io_for;
use ctlgraph_solver::StateSpace;

/// The perturbation step for a value: 6·10⁻⁶ of it (about the cube root of
/// the machine epsilon, the best for central differences), and no less
/// than 6·10⁻⁶ itself, so that rounding in values of order one stays below
/// 10⁻¹⁰ of the slope.
fn step(v: f64) -> f64 {
    6e-6 * v.abs().max(1.0)
}

/// What discrete blocks stand for in the rows.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(super) enum Mode {
    /// At a sample hit: a discrete block's output is its linear model in
    /// its own discrete states (variables after the continuous states).
    Instant,
    /// Between hits: a discrete block's output is held, each element a
    /// variable of its own.
    Interval,
}

/// Rows over the variables [continuous states | extra | injected input],
/// where extra are the discrete states (Instant) or the held discrete
/// outputs (Interval).
pub(super) struct Propagation<'m> {
    pub model: &'m Model,
    /// The run's blocks (their memory is read, and put back after a trial update).
    pub blocks: &'m mut [RunBlock],
    t: f64,
    mode: Mode,
    pub nx: usize,
    pub nv: usize,
    /// Row per signal element.
    expr: Vec<f64>,
    /// Row per continuous state derivative.
    pub dx: Vec<Vec<f64>>,
    /// Row per discrete state's next value (Instant).
    pub next: Vec<Vec<f64>>,
    /// The opened signal's upstream row.
    pub upstream: Vec<f64>,
    /// Per block: its discrete model (Instant), how many numbers of
    /// discrete memory it lets be perturbed instead (Instant), and where
    /// its extra variables start.
    discrete: Vec<Option<StateSpace>>,
    memory: Vec<usize>,
    pub extra_start: Vec<usize>,
    /// Names of the discrete states (Instant): `block.z1`, … (`block` for one).
    pub extra_names: Vec<String>,
    pub exact: Vec<usize>,
    pub perturbed: Vec<usize>,
    pub warnings: Vec<String>,
}

impl<'m> Propagation<'m> {
    pub fn new(model: &'m Model, blocks: &'m mut [RunBlock], t: f64, mode: Mode) -> Self {
        let nx = model.n_states;
        let n_blocks = model.meta.len();
        let mut discrete = vec![None; n_blocks];
        let mut memory = vec![0; n_blocks];
        let mut extra_start = vec![0; n_blocks];
        let mut extra_names = Vec::new();
        let mut ne = 0;
        for i in 0..n_blocks {
            if !matches!(model.slots[i].rate, Rate::Discrete(_)) {
                continue;
            }
            extra_start[i] = ne;
            let own = match mode {
                Mode::Instant => {
                    discrete[i] = blocks[i].discrete_lti();
                    if discrete[i].is_none() {
                        memory[i] = blocks[i].discrete_state().map_or(0, |z| z.len());
                    }
                    discrete[i].as_ref().map_or(memory[i], |ss| ss.n)
                }
                Mode::Interval => model.meta[i].outputs.clone().map(|p| model.out_ports[p].width).sum(),
            };
            if mode == Mode::Instant {
                let name = &model.meta[i].name;
                extra_names.extend((1..=own).map(|k| if own == 1 { name.clone() } else { format!("{name}.z{k}") }));
            }
            ne += own;
        }
        let nv = nx + ne + 1;
        Propagation {
            expr: vec![0.0; model.signal_len * nv],
            dx: vec![vec![0.0; nv]; nx],
            next: vec![vec![0.0; nv]; if mode == Mode::Instant { ne } else { 0 }],
            upstream: vec![0.0; nv],
            discrete,
            memory,
            extra_start,
            extra_names,
            exact: Vec::new(),
            perturbed: Vec::new(),
            warnings: Vec::new(),
            model,
            blocks,
            t,
            mode,
            nx,
            nv,
        }
    }

    pub fn row(&self, signal: usize) -> &[f64] {
        &self.expr[signal * self.nv..(signal + 1) * self.nv]
    }

    /// The rows of every discrete block's output elements, in block,
    /// port and element order (the Interval mode's held variables).
    pub fn discrete_output_rows(&self) -> Vec<Vec<f64>> {
        let m = self.model;
        (0..m.meta.len())
            .filter(|&i| matches!(m.slots[i].rate, Rate::Discrete(_)))
            .flat_map(|i| m.meta[i].outputs.clone())
            .flat_map(|p| {
                let port = m.out_ports[p];
                port.offset..port.offset + port.width
            })
            .map(|o| self.row(o).to_vec())
            .collect()
    }

    /// The offsets of block `i`'s input elements, each with whether its
    /// port has direct feedthrough, and of its output elements.
    pub fn elements(&self, i: usize) -> (Vec<(usize, bool)>, Vec<usize>) {
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

    /// Whether any of these inputs depends on a variable.
    pub fn driven(&self, inputs: &[(usize, bool)]) -> bool {
        inputs.iter().any(|&(o, _)| self.row(o).iter().any(|v| *v != 0.0))
    }

    /// Rows `C·own + D·inputs` of a linear model whose own variables start
    /// at `own` (states or discrete states), `inputs` the input elements.
    fn linear_rows(
        &self,
        c: &[f64],
        d: &[f64],
        n: usize,
        own: usize,
        inputs: &[(usize, bool)],
        rows: usize,
    ) -> Vec<Vec<f64>> {
        let (nv, m) = (self.nv, inputs.len());
        let mut out = vec![vec![0.0; nv]; rows];
        for (r, row) in out.iter_mut().enumerate() {
            for k in 0..n {
                row[own + k] += c[r * n + k];
            }
            for (j, &(o, _)) in inputs.iter().enumerate() {
                let g = d[r * m + j];
                if g != 0.0 {
                    for (v, e) in row.iter_mut().zip(&self.expr[o * nv..(o + 1) * nv]) {
                        *v += g * e;
                    }
                }
            }
        }
        out
    }

    /// Output rows of every block in execution order, the input injected
    /// (and the loop cut) where its signal is produced.
    pub fn outputs(&mut self, signals: &mut [f64], x: &mut [f64], u_at: Option<usize>, open_at: Option<usize>) {
        let nv = self.nv;
        for i in 0..self.model.meta.len() {
            let (inputs, outputs) = self.elements(i);
            let states = self.model.meta[i].states.clone();
            let rows = match self.model.slots[i].rate {
                Rate::Discrete(_) => match (self.mode, self.discrete[i].clone()) {
                    (Mode::Interval, _) => {
                        let start = self.nx + self.extra_start[i];
                        Some((0..outputs.len()).map(|k| unit(nv, start + k)).collect())
                    }
                    (Mode::Instant, Some(ss)) => {
                        self.exact.push(i);
                        let own = self.nx + self.extra_start[i];
                        Some(self.linear_rows(&ss.c, &ss.d, ss.n, own, &inputs, outputs.len()))
                    }
                    // Memoryless at its hits, or with memory to perturb.
                    (Mode::Instant, None) if !self.blocks[i].updates() || self.memory[i] > 0 => {
                        self.perturbed.push(i);
                        let fed: Vec<usize> = inputs.iter().filter(|(_, f)| *f).map(|(o, _)| *o).collect();
                        Some(self.perturb(i, signals, x, &fed, Kind::Output))
                    }
                    (Mode::Instant, None) => None,
                },
                // Sources are constants around the operating point.
                _ if inputs.is_empty() && states.is_empty() => None,
                _ if self.blocks[i].not_linearizable().is_some() => None,
                _ => match self.blocks[i].lti().cloned() {
                    Some(ss) => {
                        self.exact.push(i);
                        Some(self.linear_rows(&ss.c, &ss.d, ss.n, states.start, &inputs, outputs.len()))
                    }
                    None => {
                        self.perturbed.push(i);
                        let fed: Vec<usize> = inputs.iter().filter(|(_, f)| *f).map(|(o, _)| *o).collect();
                        Some(self.perturb(i, signals, x, &fed, Kind::Output))
                    }
                },
            };
            if let Some(rows) = rows {
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

    /// Rows of the continuous state derivatives and (Instant) of the
    /// discrete states' next values.
    pub fn dynamics(&mut self, signals: &mut [f64], x: &mut [f64]) {
        for i in 0..self.model.meta.len() {
            let states = self.model.meta[i].states.clone();
            let (inputs, _) = self.elements(i);
            if let Some(ss) = self.discrete[i].clone() {
                let own = self.nx + self.extra_start[i];
                let rows = self.linear_rows(&ss.a, &ss.b, ss.n, own, &inputs, ss.n);
                for (k, row) in rows.into_iter().enumerate() {
                    self.next[self.extra_start[i] + k] = row;
                }
                continue;
            }
            if self.memory[i] > 0 {
                let all: Vec<usize> = inputs.iter().map(|(o, _)| *o).collect();
                let rows = self.perturb(i, signals, x, &all, Kind::Update);
                for (k, row) in rows.into_iter().enumerate() {
                    self.next[self.extra_start[i] + k] = row;
                }
                continue;
            }
            if states.is_empty() || self.model.slots[i].rate != Rate::Continuous {
                continue;
            }
            let rows = match self.blocks[i].lti().cloned() {
                Some(ss) => self.linear_rows(&ss.a, &ss.b, ss.n, states.start, &inputs, ss.n),
                None => {
                    let all: Vec<usize> = inputs.iter().map(|(o, _)| *o).collect();
                    self.perturb(i, signals, x, &all, Kind::Derivative)
                }
            };
            for (s, row) in states.zip(rows) {
                self.dx[s] = row;
            }
        }
    }

    /// Rows of block `i`'s outputs (or state derivatives) by central
    /// differences in the input elements `inputs` and its own states,
    /// composed with those inputs' rows.
    fn perturb(&mut self, i: usize, signals: &mut [f64], x: &mut [f64], inputs: &[usize], kind: Kind) -> Vec<Vec<f64>> {
        let nv = self.nv;
        let states = self.model.meta[i].states.clone();
        let base = self.evaluate(i, signals, x, kind);
        let mut rows = vec![vec![0.0; nv]; base.len()];
        let mut rough = Vec::new();
        let own = self.nx + self.extra_start[i];
        let variables = inputs
            .iter()
            .map(|&o| Var::Input(o))
            .chain(states.map(Var::State))
            .chain((0..self.memory[i]).map(Var::Memory));
        for var in variables {
            let value = match var {
                Var::Input(o) => signals[o],
                Var::State(k) => x[k],
                Var::Memory(j) => self.blocks[i].discrete_state().map_or(0.0, |z| z[j]),
            };
            let h = step(value);
            let mut at = |v: f64, signals: &mut [f64], x: &mut [f64]| {
                match var {
                    Var::Input(o) => signals[o] = v,
                    Var::State(k) => x[k] = v,
                    Var::Memory(j) => {
                        if let Some(z) = self.blocks[i].discrete_state() {
                            z[j] = v;
                        }
                    }
                }
                self.evaluate(i, signals, x, kind)
            };
            let plus = at(value + h, signals, x);
            let minus = at(value - h, signals, x);
            at(value, signals, x);
            for (r, row) in rows.iter_mut().enumerate() {
                let slope = (plus[r] - minus[r]) / (2.0 * h);
                let (right, left) = ((plus[r] - base[r]) / h, (base[r] - minus[r]) / h);
                // Curvature moves the one-sided slopes by O(h); a kink by O(1).
                // Jumps in slope below 10⁻⁴ are taken for rounding (a block's
                // own numeric derivative differenced again gives ~10⁻⁶).
                if (right - left).abs() > 0.1 * right.abs().max(left.abs()) + 1e-4 {
                    rough.push((r, var, right, left));
                }
                match var {
                    Var::Input(o) => {
                        for (v, e) in row.iter_mut().zip(&self.expr[o * nv..(o + 1) * nv]) {
                            *v += slope * e;
                        }
                    }
                    Var::State(k) => row[k] += slope,
                    Var::Memory(j) => row[own + j] += slope,
                }
            }
        }
        // Leave the block's outputs as they were at the operating point.
        self.evaluate(i, signals, x, Kind::Output);
        if let Some(&(r, var, right, left)) = rough.first() {
            let m = &self.model.meta[i];
            let what = match kind {
                Kind::Output => "output",
                Kind::Derivative => "state derivative",
                Kind::Update => "discrete update",
            };
            let along = match var {
                Var::Input(o) => format!("input `{}`", self.input_name(i, o)),
                Var::State(k) => format!("state {}", k + 1 - m.states.start),
                Var::Memory(j) => format!("discrete state {}", j + 1),
            };
            let warning = format!(
                "block `{}` ({}) is not smooth at the operating point: {what} {} has slope {right} to the right and \
                 {left} to the left in {along}; their mean is used",
                m.name,
                m.type_name,
                r + 1
            );
            if !self.warnings.contains(&warning) {
                self.warnings.push(warning);
            }
        }
        rows
    }

    /// The name of block `i`'s input port that holds signal element `o`.
    fn input_name(&self, i: usize, o: usize) -> String {
        let m = &self.model.meta[i];
        m.inputs
            .clone()
            .zip(&m.input_names)
            .find(|(p, _)| {
                let port = self.model.in_ports[*p];
                (port.offset..port.offset + port.width).contains(&o)
            })
            .map_or_else(|| "?".to_string(), |(_, n)| n.clone())
    }

    /// Block `i`'s outputs (or state derivatives) at the given values.
    fn evaluate(&mut self, i: usize, signals: &mut [f64], x: &[f64], kind: Kind) -> Vec<f64> {
        let (m, blocks) = (self.model, &mut *self.blocks);
        let slot = &m.slots[i];
        match kind {
            Kind::Output => {
                let mut io = io_for(slot, self.t, false, x, signals, &m.in_ports, &m.out_ports);
                blocks[i].output(&mut io);
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
                blocks[i].derivatives(&io, &mut dx);
                dx
            }
            // The next discrete state; the block's memory is put back.
            Kind::Update => {
                let before = blocks[i].discrete_state().map(|z| z.to_vec()).unwrap_or_default();
                let mut io = io_for(slot, self.t, false, x, signals, &m.in_ports, &m.out_ports);
                blocks[i].update(&mut io);
                let z = blocks[i].discrete_state().map_or(&mut [][..], |z| z);
                let after = z.to_vec();
                z.copy_from_slice(&before);
                after
            }
        }
    }

    /// The sample rates (period, offset) of the discrete blocks on the path.
    pub fn driven_rates(&self) -> Vec<(f64, f64)> {
        let mut rates: Vec<(f64, f64)> = (0..self.model.meta.len())
            .filter(|&i| self.driven(&self.elements(i).0))
            .filter_map(|i| match self.model.slots[i].rate {
                Rate::Discrete(c) => Some(self.model.clocks[c]),
                _ => None,
            })
            .collect();
        rates.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
        rates.dedup();
        rates
    }

    /// Refuses a path through a block without a linear model.
    pub fn refuse_unlinearizable(&self) -> Result<(), Diagnostic> {
        for i in 0..self.model.meta.len() {
            if !self.driven(&self.elements(i).0) {
                continue;
            }
            let m = &self.model.meta[i];
            let at = |why: String| {
                Diagnostic::at(&m.pos, format!("block `{}` ({}) is on the analysed path: {why}", m.name, m.type_name))
            };
            if let Some(why) = self.blocks[i].not_linearizable() {
                return Err(at(why.to_string()));
            }
            let discrete = matches!(self.model.slots[i].rate, Rate::Discrete(_));
            let opaque = self.discrete[i].is_none() && self.memory[i] == 0 && self.blocks[i].updates();
            if discrete && self.mode == Mode::Instant && opaque {
                return Err(at(format!(
                    "it is discrete (sample time {}) with memory, and has no linear model",
                    m.sample_time
                ))
                .with_hint("open the loop before it, or linearise a variant of the graph without it"));
            }
        }
        Ok(())
    }
}

fn unit(n: usize, k: usize) -> Vec<f64> {
    let mut v = vec![0.0; n];
    v[k] = 1.0;
    v
}

#[derive(Clone, Copy)]
enum Kind {
    Output,
    Derivative,
    Update,
}

/// A variable a block is perturbed in: an input element (signal offset),
/// one of its continuous states (index in x), one of its discrete states.
#[derive(Clone, Copy)]
enum Var {
    Input(usize),
    State(usize),
    Memory(usize),
}
