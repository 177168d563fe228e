//! A bench for unit tests of blocks: build one from YAML parameters as a
//! graph file would, wire it to its own signal buffer and call the
//! methods the simulator calls, at major or minor steps.

use crate::registry;
use ctlgraph_core::block::Port;
use ctlgraph_core::registry::Built;
use ctlgraph_core::{Diagnostic, Io, Params, Width};

/// Runs `f` on the parameters of a block `b: { type: ty, <params> }`
/// (the inside of a YAML flow mapping).
pub(crate) fn with_params<R>(ty: &str, params: &str, f: impl FnOnce(&mut Params) -> R) -> R {
    let reg = registry();
    let t = reg.get(ty).unwrap_or_else(|| panic!("no block type {ty}"));
    let text = format!("blocks:\n  b: {{ type: {ty}, {params} }}\n");
    let flat = ctlgraph_core::load_str(&text, "t.yaml".into(), &[]).unwrap_or_else(|d| panic!("{d}"));
    let fb = &flat.blocks[0];
    let mut p = Params::new("b", t.name, &fb.spec.pos, &fb.spec.params, &fb.scope, &fb.dir, t.params);
    f(&mut p)
}

pub(crate) fn build(ty: &str, params: &str) -> Result<Built, Diagnostic> {
    let reg = registry();
    let t = reg.get(ty).unwrap_or_else(|| panic!("no block type {ty}"));
    with_params(ty, params, |p| (t.build)(p))
}

/// A built block wired to its own signal buffer: inputs first, then
/// outputs, every port at its fixed width (common width 1).
pub(crate) struct Rig {
    pub(crate) built: Built,
    pub(crate) ins: Vec<Port>,
    pub(crate) outs: Vec<Port>,
    pub(crate) signals: Vec<f64>,
    pub(crate) x: Vec<f64>,
}

impl Rig {
    pub(crate) fn new(built: Built) -> Rig {
        Rig::with_width(built, 1)
    }

    /// A rig whose common-width ports are `common` wide.
    pub(crate) fn with_width(mut built: Built, common: usize) -> Rig {
        if built.iface.has_common_width() {
            built.block.set_width(common).expect("the width");
        }
        let width = |w: &Width| if let Width::Fixed(n) = w { *n } else { common };
        let mut offset = 0;
        let mut port = |n: usize| {
            offset += n;
            Port { offset: offset - n, width: n }
        };
        let ins: Vec<Port> = built.iface.inputs.iter().map(|p| port(width(&p.width))).collect();
        let outs: Vec<Port> = built.iface.outputs.iter().map(|p| port(width(&p.width))).collect();
        let mut x = vec![0.0; built.block.num_states()];
        built.block.initialize(&mut x);
        Rig { built, ins, outs, signals: vec![0.0; offset], x }
    }

    pub(crate) fn input_names(&self) -> Vec<&str> {
        self.built.iface.inputs.iter().map(|p| p.name.as_str()).collect()
    }

    /// Sets every element of input port `i` to `values[i]`.
    pub(crate) fn set(&mut self, values: &[f64]) {
        for (p, &v) in self.ins.iter().zip(values) {
            self.signals[p.offset..p.offset + p.width].fill(v);
        }
    }

    /// Sets the elements of input port `i`.
    pub(crate) fn set_port(&mut self, i: usize, values: &[f64]) {
        let p = self.ins[i];
        self.signals[p.offset..p.offset + p.width].copy_from_slice(values);
    }

    /// All output elements at `t`, after `output` at a major step.
    pub(crate) fn output(&mut self, t: f64) -> Vec<f64> {
        self.output_in(t, false)
    }

    /// The same in a solver stage, modes frozen.
    pub(crate) fn output_minor(&mut self, t: f64) -> Vec<f64> {
        self.output_in(t, true)
    }

    fn output_in(&mut self, t: f64, minor: bool) -> Vec<f64> {
        let mut io = Io::new(t, false, &self.x, &mut self.signals, &self.ins, &self.outs);
        if minor {
            io = io.in_minor_step(true);
        }
        self.built.block.output(&mut io);
        let start = self.outs.first().map_or(0, |p| p.offset);
        self.signals[start..].to_vec()
    }

    pub(crate) fn zero_crossings(&mut self) -> Vec<f64> {
        let mut g = vec![0.0; self.built.block.num_zero_crossings()];
        let io = Io::new(0.0, false, &self.x, &mut self.signals, &self.ins, &self.outs);
        self.built.block.zero_crossings(&io, &mut g);
        g
    }

    /// `major_step` on the rig's states; whether anything changed.
    pub(crate) fn major_step(&mut self) -> bool {
        let mut x = self.x.clone();
        let io = Io::new(0.0, false, &[], &mut self.signals, &self.ins, &self.outs);
        let changed = self.built.block.major_step(&io, &mut x);
        self.x = x;
        changed
    }

    pub(crate) fn update(&mut self, t: f64) {
        let mut io = Io::new(t, false, &self.x, &mut self.signals, &self.ins, &self.outs);
        self.built.block.update(&mut io);
    }

    pub(crate) fn derivatives(&mut self) -> Vec<f64> {
        let mut dx = vec![0.0; self.x.len()];
        let io = Io::new(0.0, false, &self.x, &mut self.signals, &self.ins, &self.outs);
        self.built.block.derivatives(&io, &mut dx);
        dx
    }

    /// The outputs of `n` sample steps with the inputs held at `values`.
    pub(crate) fn steps(&mut self, values: &[f64], n: usize) -> Vec<Vec<f64>> {
        self.set(values);
        (0..n)
            .map(|k| {
                let y = self.output(k as f64);
                self.update(k as f64);
                y
            })
            .collect()
    }
}
