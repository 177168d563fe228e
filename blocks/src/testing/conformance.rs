//! The promises a block makes through the [`Block`] trait, checked.
//!
//! The simulator trusts several of a block's answers to skip work: a
//! [`Kernel`] is computed in place of calling `output`, `updates() ==
//! false` lets a solver stage reuse the major step's outputs, a time-only
//! block runs once per time, an LTI block may be stepped by its exact
//! transition, a plain integrator is copied, a piecewise-constant block
//! is skipped in minor steps, and a snapshot is a clone. A block whose
//! answer is wrong computes stale or wrong values without an error. This
//! module drives each block of a compiled model on its own — its inputs
//! and states set to pseudo-random values, its memory advanced through a
//! few major steps — and compares what `output`, `update` and
//! `derivatives` compute with what each promise says.
//!
//! ```ignore
//! let model = ctlgraph::compile_file("my_graph.yaml".as_ref(), &[])?;
//! for broken in ctlgraph_blocks::testing::conformance::check_model(&model) {
//!     eprintln!("{broken}");
//! }
//! ```

use ctlgraph_core::block::{Block, Io, Kernel, Port};
use ctlgraph_core::{Model, SampleTime};
use std::panic::{AssertUnwindSafe, catch_unwind};

/// A promise of the [`Block`] trait.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Promise {
    /// `output` called twice at one major step computes the same values.
    IdempotentOutput,
    /// [`Block::kernel`]: the kernel computes what `output` computes.
    Kernel,
    /// [`Block::updates`] `== false`: `update` changes nothing `output` or
    /// `derivatives` read.
    NoUpdate,
    /// [`Block::time_only`]: the outputs ignore the inputs and the block's
    /// past, and it has no states.
    TimeOnly,
    /// [`Block::lti`]: `derivatives` and `output` are A·x + B·u and C·x + D·u.
    Lti,
    /// [`Block::is_plain_integrator`]: y = x, ẋ = u, nothing else.
    PlainIntegrator,
    /// `Interface::piecewise_constant`: the outputs hold between major
    /// steps while the inputs do (no states, no reading of t).
    PiecewiseConstant,
    /// A clone continues exactly as the original (snapshots are clones).
    Clone,
    /// No call panics.
    NoPanic,
}

impl Promise {
    pub fn describe(self) -> &'static str {
        match self {
            Promise::IdempotentOutput => "output is the same when called twice at one major step",
            Promise::Kernel => "kernel() computes what output computes",
            Promise::NoUpdate => "updates() == false: update changes nothing output or derivatives read",
            Promise::TimeOnly => "time_only(): the outputs depend on time alone",
            Promise::Lti => "lti(): derivatives = A·x + B·u and outputs = C·x + D·u",
            Promise::PlainIntegrator => "is_plain_integrator(): y = x and dx = u",
            Promise::PiecewiseConstant => "piecewise_constant: outputs hold between major steps while inputs do",
            Promise::Clone => "a clone continues exactly as the original",
            Promise::NoPanic => "no call panics",
        }
    }
}

/// A promise a block of a model broke, and how.
#[derive(Clone, Debug, PartialEq)]
pub struct Broken {
    pub block: String,
    pub type_name: String,
    pub promise: Promise,
    pub detail: String,
}

impl std::fmt::Display for Broken {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "block `{}` ({}) breaks \"{}\": {}", self.block, self.type_name, self.promise.describe(), self.detail)
    }
}

/// Checks every block of `model` against every promise it makes.
pub fn check_model(model: &Model) -> Vec<Broken> {
    (0..model.meta.len()).flat_map(|i| check_block(model, i)).collect()
}

/// Checks block `i` of `model` against every promise it makes.
pub fn check_block(model: &Model, i: usize) -> Vec<Broken> {
    let meta = &model.meta[i];
    let broken = |promise, detail: String| Broken {
        block: meta.name.clone(),
        type_name: meta.type_name.clone(),
        promise,
        detail,
    };
    let mut found = Vec::new();
    let checks: [(Promise, Check); 8] = [
        (Promise::Clone, clone_continues),
        (Promise::IdempotentOutput, idempotent_output),
        (Promise::Kernel, kernel),
        (Promise::NoUpdate, no_update),
        (Promise::TimeOnly, time_only),
        (Promise::Lti, lti),
        (Promise::PlainIntegrator, plain_integrator),
        (Promise::PiecewiseConstant, piecewise_constant),
    ];
    for (promise, check) in checks {
        let mut bench = Bench::new(model, i);
        match catch_unwind(AssertUnwindSafe(|| check(&mut bench))) {
            Ok(Ok(())) => {}
            Ok(Err(detail)) => found.push(broken(promise, detail)),
            Err(_) => {
                found.push(broken(
                    Promise::NoPanic,
                    format!("a call panicked while checking \"{}\"", promise.describe()),
                ));
                break;
            }
        }
    }
    found
}

/// One promise's check: `Err` says how the block broke it.
type Check = fn(&mut Bench) -> Result<(), String>;

/// One block on a bench: its own signal buffer and states, and the times
/// of its major steps (its sample hits, or every 10 ms).
struct Bench<'m> {
    model: &'m Model,
    i: usize,
    inputs: &'m [Port],
    outputs: &'m [Port],
    signals: Vec<f64>,
    x: Vec<f64>,
    period: f64,
    offset: f64,
}

impl<'m> Bench<'m> {
    fn new(model: &'m Model, i: usize) -> Self {
        let (period, offset) = match model.meta[i].sample_time {
            SampleTime::Discrete { period, offset } => (period, offset),
            _ => (0.01, 0.0),
        };
        Bench {
            model,
            i,
            inputs: model.input_ports(i),
            outputs: model.output_ports(i),
            signals: vec![0.0; model.signal_len],
            x: vec![0.0; model.meta[i].states.len()],
            period,
            offset,
        }
    }

    /// A copy of the model's block, initialised (states into `x`).
    fn fresh(&mut self) -> Box<dyn Block> {
        let mut block = dyn_clone::clone_box(self.model.block(self.i));
        block.initialize(&mut self.x);
        block
    }

    fn time(&self, k: usize) -> f64 {
        self.offset + k as f64 * self.period
    }

    /// Inputs drawn from `seed`: values in [−1, 1] (away from 0).
    fn set_inputs(&mut self, seed: u64) {
        let mut rng = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ (self.i as u64 + 1);
        for p in self.inputs {
            for v in &mut self.signals[p.offset..p.offset + p.width] {
                *v = draw(&mut rng);
            }
        }
    }

    /// States drawn from `seed`.
    fn set_states(&mut self, seed: u64) {
        let mut rng = seed.wrapping_mul(0xD1B5_4A32_D192_ED03) ^ 0x5bd1_e995;
        for v in &mut self.x {
            *v = draw(&mut rng);
        }
    }

    fn input_values(&self) -> Vec<f64> {
        self.inputs.iter().flat_map(|p| self.signals[p.offset..p.offset + p.width].to_vec()).collect()
    }

    /// The block's outputs at `t`, at a major step or in a minor one.
    fn output(&mut self, block: &mut dyn Block, t: f64, major: bool) -> Vec<f64> {
        let io = Io::new(t, false, &self.x, &mut self.signals, self.inputs, self.outputs);
        let mut io = if major { io } else { io.in_minor_step(false) };
        block.output(&mut io);
        self.outputs.iter().flat_map(|p| self.signals[p.offset..p.offset + p.width].to_vec()).collect()
    }

    fn update(&mut self, block: &mut dyn Block, t: f64) {
        let mut io = Io::new(t, false, &self.x, &mut self.signals, self.inputs, self.outputs);
        block.update(&mut io);
    }

    /// The derivatives, for a block with continuous states (the only
    /// ones the simulator asks).
    fn derivatives(&mut self, block: &mut dyn Block, t: f64) -> Vec<f64> {
        if self.x.is_empty() {
            return Vec::new();
        }
        let io = Io::new(t, false, &self.x, &mut self.signals, self.inputs, self.outputs).in_minor_step(false);
        let mut dx = vec![0.0; self.x.len()];
        block.derivatives(&io, &mut dx);
        dx
    }

    /// Major steps `k0 .. k0 + steps` as the simulator takes them (inputs
    /// drawn per step, outputs, mode switches, update, an Euler step of
    /// the states, projection); returns every output and derivative seen.
    fn drive(&mut self, block: &mut dyn Block, k0: usize, steps: usize) -> Vec<f64> {
        let mut seen = Vec::new();
        for k in k0..k0 + steps {
            let t = self.time(k);
            self.set_inputs(k as u64);
            seen.extend(self.output(block, t, true));
            if block.needs_major_step() {
                let io = Io::new(t, false, &[], &mut self.signals, self.inputs, self.outputs);
                if block.major_step(&io, &mut self.x) {
                    seen.extend(self.output(block, t, true));
                }
            }
            self.update(block, t);
            let dx = self.derivatives(block, t);
            for (x, d) in self.x.iter_mut().zip(&dx) {
                *x += self.period * d;
            }
            if !self.x.is_empty() {
                block.clamp_states(&mut self.x);
            }
            seen.extend(dx);
            seen.extend(self.x.iter().copied());
        }
        seen
    }
}

/// A value in [−1, −0.1] ∪ [0.1, 1] from a xorshift generator.
fn draw(state: &mut u64) -> f64 {
    *state ^= *state << 13;
    *state ^= *state >> 7;
    *state ^= *state << 17;
    let unit = (*state >> 11) as f64 / (1u64 << 53) as f64;
    let magnitude = 0.1 + 0.9 * unit;
    if *state & 1 == 0 { magnitude } else { -magnitude }
}

/// Equal to the bit (NaNs from the same computation compare equal).
fn same(a: &[f64], b: &[f64]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits())
}

fn differ(what: &str, a: &[f64], b: &[f64]) -> String {
    format!("{what}: {a:?} vs {b:?}")
}

fn clone_continues(bench: &mut Bench) -> Result<(), String> {
    let mut original = bench.fresh();
    bench.drive(&mut *original, 0, 5);
    let (mut copy, x) = (original.clone(), bench.x.clone());
    let went_on = bench.drive(&mut *original, 5, 5);
    bench.x = x;
    let copy_went_on = bench.drive(&mut *copy, 5, 5);
    if same(&went_on, &copy_went_on) {
        Ok(())
    } else {
        Err(differ("after 5 steps, original then clone", &went_on, &copy_went_on))
    }
}

fn idempotent_output(bench: &mut Bench) -> Result<(), String> {
    let mut block = bench.fresh();
    bench.drive(&mut *block, 0, 3);
    let t = bench.time(3);
    bench.set_inputs(3);
    let first = bench.output(&mut *block, t, true);
    let second = bench.output(&mut *block, t, true);
    if same(&first, &second) { Ok(()) } else { Err(differ("at step 3, first call then second", &first, &second)) }
}

fn kernel(bench: &mut Bench) -> Result<(), String> {
    let Some(kernel) = bench.model.block(bench.i).kernel() else { return Ok(()) };
    if !bench.x.is_empty() {
        return Err(format!("a block with a kernel has {} state(s)", bench.x.len()));
    }
    let scalar = bench.inputs.iter().chain(bench.outputs).all(|p| p.width == 1);
    let mut block = bench.fresh();
    for k in 0..4 {
        bench.set_inputs(100 + k);
        let t = bench.time(k as usize);
        let u = bench.input_values();
        let y = bench.output(&mut *block, t, k % 2 == 0);
        let expected: Vec<f64> = match kernel {
            Kernel::Copy => u.clone(),
            _ if scalar && u.len() == kernel.arity() => vec![kernel.eval(u[0], u.get(1).copied().unwrap_or(0.0))],
            // The scheduler uses a scalar kernel on scalar ports only.
            _ => return Ok(()),
        };
        if !same(&y, &expected) {
            return Err(differ(&format!("{kernel:?} of inputs {u:?}: output then kernel"), &y, &expected));
        }
    }
    Ok(())
}

fn no_update(bench: &mut Bench) -> Result<(), String> {
    if bench.model.block(bench.i).updates() {
        return Ok(());
    }
    let mut updated = bench.fresh();
    bench.drive(&mut *updated, 0, 3);
    let mut skipped = updated.clone();
    let t = bench.time(3);
    bench.set_inputs(3);
    bench.output(&mut *updated, t, true);
    bench.output(&mut *skipped, t, true);
    bench.update(&mut *updated, t);
    // The solver's stage at the next time, with other inputs and states.
    let t = bench.time(4);
    bench.set_inputs(4);
    bench.set_states(4);
    let a = [bench.output(&mut *updated, t, false), bench.derivatives(&mut *updated, t)].concat();
    let b = [bench.output(&mut *skipped, t, false), bench.derivatives(&mut *skipped, t)].concat();
    if same(&a, &b) {
        Ok(())
    } else {
        Err(differ("next stage's outputs and derivatives, with update then without", &a, &b))
    }
}

fn time_only(bench: &mut Bench) -> Result<(), String> {
    if bench.model.block(bench.i).time_only().is_none() {
        return Ok(());
    }
    if !bench.x.is_empty() {
        return Err(format!("a time-only block has {} state(s)", bench.x.len()));
    }
    let mut driven = bench.fresh();
    bench.drive(&mut *driven, 0, 4);
    let mut new = bench.fresh();
    let t = bench.time(4) + 0.3 * bench.period;
    bench.set_inputs(40);
    let a = bench.output(&mut *driven, t, false);
    bench.set_inputs(41);
    let b = bench.output(&mut *new, t, false);
    if same(&a, &b) { Ok(()) } else { Err(differ("at one time, after 4 steps and other inputs, then fresh", &a, &b)) }
}

fn lti(bench: &mut Bench) -> Result<(), String> {
    let Some(ss) = bench.model.block(bench.i).lti().cloned() else { return Ok(()) };
    let (n, m, p) =
        (bench.x.len(), bench.inputs.iter().map(|p| p.width).sum(), bench.outputs.iter().map(|p| p.width).sum());
    if (ss.n, ss.m, ss.p) != (n, m, p) {
        return Err(format!(
            "(n, m, p) = {:?} but the block has {n} states, {m} inputs, {p} outputs",
            (ss.n, ss.m, ss.p)
        ));
    }
    let mut block = bench.fresh();
    for k in 0..3 {
        bench.set_inputs(200 + k);
        bench.set_states(200 + k);
        let t = bench.time(k as usize) + 0.5 * bench.period;
        let (u, x) = (bench.input_values(), bench.x.clone());
        let y = bench.output(&mut *block, t, false);
        let dx = bench.derivatives(&mut *block, t);
        let affine = |mat_x: &[f64], mat_u: &[f64], row: usize| -> (f64, f64) {
            let terms = (0..n).map(|j| mat_x[row * n + j] * x[j]).chain((0..m).map(|j| mat_u[row * m + j] * u[j]));
            terms.fold((0.0, 0.0), |(sum, size), v| (sum + v, size + v.abs()))
        };
        for (what, got, mat_x, mat_u) in [("dx", &dx, &ss.a, &ss.b), ("y", &y, &ss.c, &ss.d)] {
            for (row, &g) in got.iter().enumerate() {
                let (expected, size) = affine(mat_x, mat_u, row);
                if (g - expected).abs() > 1e-12 * (1.0 + size) {
                    return Err(format!("{what}[{row}] = {g} but the matrices give {expected} (x = {x:?}, u = {u:?})"));
                }
            }
        }
    }
    Ok(())
}

fn plain_integrator(bench: &mut Bench) -> Result<(), String> {
    if !bench.model.block(bench.i).is_plain_integrator() {
        return Ok(());
    }
    let mut block = bench.fresh();
    if block.num_zero_crossings() > 0 {
        return Err("it has zero crossings".into());
    }
    bench.set_inputs(300);
    bench.set_states(300);
    let t = bench.time(1);
    let y = bench.output(&mut *block, t, false);
    let dx = bench.derivatives(&mut *block, t);
    let u = bench.input_values();
    let u: Vec<f64> = if u.len() == 1 { vec![u[0]; bench.x.len()] } else { u };
    let mut clamped = bench.x.clone();
    let moved = block.clamp_states(&mut clamped);
    // Each output port is the states (a state port as well as y).
    let states: Vec<f64> = bench.outputs.iter().flat_map(|_| bench.x.iter().copied()).collect();
    if !same(&y, &states) {
        Err(differ("outputs then states", &y, &states))
    } else if !same(&dx, &u) {
        Err(differ("derivatives then inputs", &dx, &u))
    } else if moved || !same(&clamped, &bench.x) {
        Err("clamp_states moved the states".into())
    } else {
        Ok(())
    }
}

fn piecewise_constant(bench: &mut Bench) -> Result<(), String> {
    if !bench.model.meta[bench.i].piecewise_constant {
        return Ok(());
    }
    if !bench.x.is_empty() {
        return Err(format!("a piecewise-constant block has {} state(s)", bench.x.len()));
    }
    let mut block = bench.fresh();
    bench.drive(&mut *block, 0, 3);
    bench.set_inputs(3);
    let (t, later) = (bench.time(3), bench.time(3) + 0.6 * bench.period);
    let at_step = bench.output(&mut *block, t, true);
    if block.next_event(t) <= later {
        return Ok(());
    }
    let in_between = bench.output(&mut *block, later, false);
    if same(&at_step, &in_between) {
        Ok(())
    } else {
        Err(differ("at a major step then 0.6 steps later", &at_step, &in_between))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ctlgraph_core::{BlockType, Built, Diagnostic, Interface, Params, PortDoc, Width};

    /// y = u + (updates so far), but says it has no update.
    #[derive(Clone)]
    struct StaleCounter(f64);

    impl Block for StaleCounter {
        fn output(&mut self, io: &mut Io) {
            let y = io.u(0) + self.0;
            io.output(0)[0] = y;
        }
        fn update(&mut self, _io: &mut Io) {
            self.0 += 1.0;
        }
        fn updates(&self) -> bool {
            false
        }
    }

    /// y = 3u, but its kernel says 2u.
    #[derive(Clone)]
    struct WrongKernel;

    impl Block for WrongKernel {
        fn output(&mut self, io: &mut Io) {
            let y = 3.0 * io.u(0);
            io.output(0)[0] = y;
        }
        fn kernel(&self) -> Option<Kernel> {
            Some(Kernel::Scale(2.0))
        }
        fn updates(&self) -> bool {
            false
        }
    }

    fn scalar_iface() -> Interface {
        Interface::new(ctlgraph_core::SampleTime::Continuous)
            .input("u", Width::Fixed(1), true)
            .output("y", Width::Fixed(1))
    }

    fn planted(name: &'static str, build: fn(&mut Params) -> Result<Built, Diagnostic>) -> BlockType {
        const PORT: &[PortDoc] = &[PortDoc { name: "u", doc: "" }];
        BlockType { name, category: "test", summary: "", doc: "", inputs: PORT, outputs: PORT, params: &[], build }
    }

    #[test]
    fn a_planted_wrong_updates_and_a_wrong_kernel_are_named_and_the_library_blocks_beside_them_pass() {
        let mut registry = crate::registry();
        registry.register(planted("stale_counter", |_| Ok(Built::new(StaleCounter(0.0), scalar_iface()))));
        registry.register(planted("wrong_kernel", |_| Ok(Built::new(WrongKernel, scalar_iface()))));
        let graph = "blocks:\n  u: { type: sine }\n  a: { type: stale_counter }\n  b: { type: wrong_kernel }\n  \
                     g: { type: gain, k: 2 }\n  x: { type: integrator }\nwires: [u -> a, u -> b, u -> g, g -> x]\n";
        let flat = ctlgraph_core::load_str(graph, "planted.yaml".into(), &[]).unwrap();
        let model = ctlgraph_core::compile(&flat, &registry).unwrap();
        let found: Vec<(String, Promise)> = check_model(&model).into_iter().map(|b| (b.block, b.promise)).collect();
        assert_eq!(found, [("a".to_string(), Promise::NoUpdate), ("b".to_string(), Promise::Kernel)]);
        let text = check_model(&model)[1].to_string();
        assert!(
            text.starts_with("block `b` (wrong_kernel) breaks \"kernel() computes what output computes\""),
            "{text}"
        );
    }
}
