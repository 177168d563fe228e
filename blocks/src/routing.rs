//! Signal routing: mux, demux, selector, switch, and the structural types
//! the loader handles itself (subsystem, inport, outport), listed here so
//! `ctlgraph blocks` documents them.

use crate::{SAMPLE_TIME_INHERITED, table::*};
use ctlgraph_core::codegen::c::{CBlock, NoCForm};
use ctlgraph_core::registry::{BlockType, Built, PortDoc};
use ctlgraph_core::{Block, Diagnostic, Interface, Io, Kernel, Params, Width};

pub const TYPES: &[BlockType] = &[
    BlockType {
        name: "mux",
        category: "routing",
        summary: "Concatenates inputs into one vector signal.",
        doc: "y = [u1; u2; …; un]. Input widths from `widths` (default: `inputs` scalars).",
        inputs: &[PortDoc { name: "u1 … un", doc: "widths as given" }],
        outputs: &[PortDoc { name: "y", doc: "width = sum of the input widths" }],
        params: &[
            param("inputs", Number(2.0), "number of scalar inputs (when `widths` is not given)"),
            param("widths", Described("1 for each of `inputs`"), "width of each input, e.g. [2, 1]")
                .kind(ParamKind::Numbers),
            SAMPLE_TIME_INHERITED,
        ],
        build: build_mux,
    },
    BlockType {
        name: "demux",
        category: "routing",
        summary: "Splits a vector signal into parts.",
        doc: "[y1; y2; …; yn] = u. Output widths from `widths` (default: `outputs` scalars).",
        inputs: &[PortDoc { name: "u", doc: "width = sum of the output widths" }],
        outputs: &[PortDoc { name: "y1 … yn", doc: "widths as given" }],
        params: &[
            param("outputs", Number(2.0), "number of scalar outputs (when `widths` is not given)"),
            param("widths", Described("1 for each of `outputs`"), "width of each output").kind(ParamKind::Numbers),
            SAMPLE_TIME_INHERITED,
        ],
        build: build_demux,
    },
    BlockType {
        name: "selector",
        category: "routing",
        summary: "Picks elements of a vector by 1-based index.",
        doc: "y[i] = u[indices[i]], indices counted from 1 (as MATLAB); repeats allowed.",
        inputs: &[PortDoc { name: "u", doc: "any width >= the largest index" }],
        outputs: &[PortDoc { name: "y", doc: "width = number of indices" }],
        params: &[
            param("indices", Required, "list of 1-based indices").kind(ParamKind::Numbers),
            SAMPLE_TIME_INHERITED,
        ],
        build: build_selector,
    },
    BlockType {
        name: "switch",
        category: "routing",
        summary: "Passes u1 or u2 depending on a control signal.",
        doc: "y = u1 if control passes the criterion, else u2. Criteria: `>=` (control >= threshold), \
              `>` (control > threshold), `!=0` (control ≠ 0). Ports in Simulink's order: u1, control, u2.\n\
              Modes: the passing input is chosen at major steps and frozen in minor steps; the zero \
              crossing of control − threshold (control for `!=0`) ends the step where it switches.",
        inputs: &[
            PortDoc { name: "u1", doc: "passed when the criterion holds" },
            PortDoc { name: "control", doc: "scalar" },
            PortDoc { name: "u2", doc: "passed otherwise" },
        ],
        outputs: &[PortDoc { name: "y", doc: "width of u1/u2" }],
        params: &[
            param("threshold", Number(0.0), "compared with control"),
            param("criterion", Word(">="), ">= | > | !=0").options(&[">=", ">", "!=0"]),
            SAMPLE_TIME_INHERITED,
        ],
        build: build_switch,
    },
    BlockType {
        name: "subsystem",
        category: "structure",
        summary: "Another graph file used as a block.",
        doc: "Loads `file` (relative to this file) and inlines its blocks as `name/inner` at compile \
              time: no run-time cost. Its `inport` blocks are this block's inputs and its `outport` \
              blocks its outputs, named after them (`ctrl.r`, `ctrl.u`). `parameters` overrides the \
              subsystem's own parameters; values are expressions over this file's parameters.\n\
              With `enable:` it is an enabled subsystem (Simulink's): an input `enable` is added, and its \
              blocks run while it is > 0 (the switches located as zero crossings); while disabled their \
              states are held (derivatives 0) and their outputs hold (`outputs: held`) or read 0 \
              (`reset`); enabled again, the states resume (`states: held`) or restart from their initial \
              values (`reset`). With `trigger:` it is a triggered subsystem: an input `trigger` is added, \
              and its blocks run once per edge of it (rising: from negative to zero or positive, or from \
              zero to positive; falling the mirror image; located as zero crossings of a continuous \
              input), their outputs holding between edges and their memory advancing once per edge (their \
              own sample times give way); no continuous states. Both: an edge runs it only while \
              enabled. An inport wired straight to an outport holds too (a sample-and-hold).",
        inputs: &[PortDoc { name: "(inports)", doc: "one per inport block of the file" }],
        outputs: &[PortDoc { name: "(outports)", doc: "one per outport block of the file" }],
        params: &[
            param("file", Required, "graph file, relative to this one"),
            param("parameters", Described("{}"), "overrides of the subsystem's parameters").kind(ParamKind::Structure),
            param(
                "enable",
                Described("always runs"),
                "{ states: held | reset, outputs: held | reset } (or true: both held): runs while its input `enable` is > 0",
            )
            .kind(ParamKind::Structure),
            param("trigger", Described("always runs"), "rising | falling | either: runs once per edge of its input `trigger`")
                .kind(ParamKind::Word)
                .options(&["rising", "falling", "either"]),
        ],
        build: structural,
    },
    BlockType {
        name: "inport",
        category: "structure",
        summary: "An input of a subsystem, or of the graph itself (the block's name is the port's name).",
        doc: "Inside a subsystem file: the signal wired to the subsystem's port of this name. Resolved \
              at compile time; costs nothing at run time. At the top level of the graph: an input a \
              program driving the graph step by step sets (`Simulator::set_input`); it holds its \
              value between major steps (a zero-order hold) and is \
              `value` until set — so a plain `ctlgraph run` sees `value`.",
        inputs: &[],
        outputs: &[PortDoc { name: "out", doc: "the outer signal (top level: the host's value)" }],
        params: &[
            param("width", Number(1.0), "top level only: the number of elements"),
            param("value", Number(0.0), "top level only: the value before the host sets one"),
        ],
        build: structural,
    },
    BlockType {
        name: "ground",
        category: "routing",
        summary: "Zero (Simulink's Ground): for an input that is to read nothing.",
        doc: "y = 0, of `width` elements, computed once.",
        inputs: &[],
        outputs: &[PortDoc { name: "y", doc: "zeros" }],
        params: &[param("width", Number(1.0), "the number of elements")],
        build: build_ground,
    },
    BlockType {
        name: "terminator",
        category: "routing",
        summary: "Ends a signal that nothing else reads (Simulink's Terminator).",
        doc: "Reads its input and does nothing with it: an output that is not used, said so in the diagram.",
        inputs: &[PortDoc { name: "u", doc: "any width" }],
        outputs: &[],
        params: &[SAMPLE_TIME_INHERITED],
        build: build_terminator,
    },
    BlockType {
        name: "outport",
        category: "structure",
        summary: "An output of a subsystem, or of the graph itself (the block's name is the port's name).",
        doc: "Inside a subsystem file: wire the signal to export into it. Resolved at compile time. At the \
              top level: a signal a program driving the graph reads by this name (`Simulator::output`).",
        inputs: &[PortDoc { name: "in", doc: "the signal to export" }],
        outputs: &[],
        params: &[],
        build: structural,
    },
];

/// Zeros, once.
#[derive(Clone)]
pub struct Ground;

impl Block for Ground {
    rust_type!(Ground);
    fn updates(&self) -> bool {
        false
    }
    fn time_only(&self) -> Option<ctlgraph_core::TimeOnly> {
        Some(ctlgraph_core::TimeOnly::Smooth)
    }
    fn output(&mut self, io: &mut Io) {
        io.output(0).iter_mut().for_each(|v| *v = 0.0);
    }
    fn c_form(&self, c: &mut CBlock) -> Result<(), NoCForm> {
        c.equation("y = 0");
        for k in 0..c.output_width(0) {
            c.output(format!("{} = {};", c.y_at(0, k), c.num(0.0)));
        }
        Ok(())
    }
}

fn build_ground(p: &mut Params) -> Result<Built, Diagnostic> {
    let width = p.count("width", 1_000_000)?.max(1);
    let iface = Interface::new(ctlgraph_core::SampleTime::Constant).output("y", Width::Fixed(width));
    Ok(Built::new(Ground, iface))
}

/// Reads its input, writes nothing.
#[derive(Clone)]
pub struct Terminator;

impl Block for Terminator {
    rust_type!(Terminator);
    fn updates(&self) -> bool {
        false
    }
    fn output(&mut self, _io: &mut Io) {}
    fn c_form(&self, c: &mut CBlock) -> Result<(), NoCForm> {
        c.equation("nothing: the input ends here");
        Ok(())
    }
}

fn build_terminator(p: &mut Params) -> Result<Built, Diagnostic> {
    Ok(Built::new(Terminator, Interface::new(p.sample_time()?).input("u", Width::Common, false)))
}

/// Never called: the loader and compiler handle these types themselves.
fn structural(p: &mut Params) -> Result<Built, Diagnostic> {
    Err(p.block_error("structural block built directly (internal error)"))
}

/// The most ports, and the widest signal, a routing block takes.
const MAX_PORTS: usize = 10_000;
const MAX_WIDTH: f64 = 1e6;

fn widths(p: &mut Params, count_key: &str) -> Result<Vec<usize>, Diagnostic> {
    if let Some(ws) = p.opt_vector("widths")? {
        if ws.is_empty() || ws.len() > MAX_PORTS || ws.iter().any(|w| *w < 1.0 || w.fract() != 0.0 || *w > MAX_WIDTH) {
            return Err(p.error(
                "widths",
                format!("must be 1 to {MAX_PORTS} whole numbers from 1 to {MAX_WIDTH:e} (signal widths)"),
            ));
        }
        return Ok(ws.iter().map(|w| *w as usize).collect());
    }
    Ok(vec![1; p.count(count_key, MAX_PORTS)?])
}

/// Concatenates the inputs in port order.
#[derive(Clone)]
pub struct Concat;

impl Block for Concat {
    rust_type!(Concat);
    fn updates(&self) -> bool {
        false
    }
    fn output(&mut self, io: &mut Io) {
        let mut k = 0;
        for port in 0..io.num_inputs() {
            for j in 0..io.input_width(port) {
                let v = io.input(port)[j];
                io.set_at(0, k, v);
                k += 1;
            }
        }
    }
    fn c_form(&self, c: &mut CBlock) -> Result<(), NoCForm> {
        c.equation("y = [u1, u2, ...]");
        let mut k = 0;
        for port in 0..c.num_inputs() {
            for j in 0..c.input_width(port) {
                c.output(format!("{} = {};", c.y_at(0, k), c.u_at(port, j)));
                k += 1;
            }
        }
        Ok(())
    }
}

fn build_mux(p: &mut Params) -> Result<Built, Diagnostic> {
    let ws = widths(p, "inputs")?;
    let mut iface = Interface::new(p.sample_time()?).piecewise_constant();
    for (i, w) in ws.iter().enumerate() {
        iface = iface.input(&format!("u{}", i + 1), Width::Fixed(*w), true);
    }
    Ok(Built::new(Concat, iface.output("y", Width::Fixed(ws.iter().sum()))))
}

#[derive(Clone)]
pub struct Split(Vec<usize>);

impl Block for Split {
    rust_type!(Split);
    fn updates(&self) -> bool {
        false
    }
    fn kernel(&self) -> Option<Kernel> {
        Some(Kernel::Copy)
    }
    fn output(&mut self, io: &mut Io) {
        let mut k = 0;
        for (port, &w) in self.0.iter().enumerate() {
            for j in 0..w {
                let v = io.input(0)[k];
                io.set_at(port, j, v);
                k += 1;
            }
        }
    }
    fn c_form(&self, c: &mut CBlock) -> Result<(), NoCForm> {
        c.equation("[y1, y2, ...] = u");
        let mut k = 0;
        for (port, &w) in self.0.iter().enumerate() {
            for j in 0..w {
                c.output(format!("{} = {};", c.y_at(port, j), c.u_at(0, k)));
                k += 1;
            }
        }
        Ok(())
    }
}

fn build_demux(p: &mut Params) -> Result<Built, Diagnostic> {
    let ws = widths(p, "outputs")?;
    let mut iface =
        Interface::new(p.sample_time()?).piecewise_constant().input("u", Width::Fixed(ws.iter().sum()), true);
    for (i, w) in ws.iter().enumerate() {
        iface = iface.output(&format!("y{}", i + 1), Width::Fixed(*w));
    }
    Ok(Built::new(Split(ws), iface))
}

#[derive(Clone)]
pub struct Selector(Vec<usize>);

impl Block for Selector {
    rust_type!(Selector);
    fn updates(&self) -> bool {
        false
    }
    fn set_width(&mut self, width: usize) -> Result<(), String> {
        match self.0.iter().find(|&&i| i >= width) {
            Some(i) => Err(format!("index {} is beyond the input's width {width}", i + 1)),
            None => Ok(()),
        }
    }
    fn output(&mut self, io: &mut Io) {
        for (k, &i) in self.0.iter().enumerate() {
            let v = io.input(0)[i];
            io.set_at(0, k, v);
        }
    }
    fn c_form(&self, c: &mut CBlock) -> Result<(), NoCForm> {
        c.equation("y_k = u[index_k]");
        for (k, &i) in self.0.iter().enumerate() {
            c.output(format!("{} = {};", c.y_at(0, k), c.u_at(0, i)));
        }
        Ok(())
    }
}

fn build_selector(p: &mut Params) -> Result<Built, Diagnostic> {
    let idx = p.vector("indices")?;
    if idx.is_empty() || idx.iter().any(|i| *i < 1.0 || i.fract() != 0.0) {
        return Err(p.error("indices", "must be whole numbers >= 1 (indices count from 1)"));
    }
    let idx: Vec<usize> = idx.iter().map(|i| *i as usize - 1).collect();
    let n = idx.len();
    let iface = Interface::new(p.sample_time()?)
        .piecewise_constant()
        .input("u", Width::Common, true)
        .output("y", Width::Fixed(n));
    Ok(Built::new(Selector(idx), iface))
}

#[derive(Clone, Copy)]
enum Criterion {
    AtLeast,
    Above,
    NonZero,
}

#[derive(Clone)]
pub struct Switch {
    threshold: f64,
    criterion: Criterion,
    /// The mode: whether u1 passes.
    first: bool,
}

impl Block for Switch {
    rust_type!(Switch);
    fn updates(&self) -> bool {
        false
    }
    fn output(&mut self, io: &mut Io) {
        if io.may_switch() {
            let c = io.u(1);
            self.first = match self.criterion {
                Criterion::AtLeast => c >= self.threshold,
                Criterion::Above => c > self.threshold,
                Criterion::NonZero => c != 0.0,
            };
        }
        let port = if self.first { 0 } else { 2 };
        for k in 0..io.output_width(0) {
            let v = io.u_at(port, k);
            io.set_at(0, k, v);
        }
    }

    /// The criterion decided afresh at each sample (a major step).
    fn c_form(&self, c: &mut CBlock) -> Result<(), NoCForm> {
        let control = c.u(1).to_string();
        let test = match self.criterion {
            Criterion::AtLeast => format!("{control} >= {}", c.num(self.threshold)),
            Criterion::Above => format!("{control} > {}", c.num(self.threshold)),
            Criterion::NonZero => format!("{control} != {}", c.num(0.0)),
        };
        c.equation("y = control passes the criterion ? u1 : u2");
        for k in 0..c.output_width(0) {
            c.output(format!("{} = ({test}) ? {} : {};", c.y_at(0, k), c.u_at(0, k), c.u_at(2, k)));
        }
        Ok(())
    }

    fn num_zero_crossings(&self) -> usize {
        1
    }

    /// The control input against its threshold (against 0 for `!=0`).
    fn zero_crossings(&self, io: &Io, g: &mut [f64]) {
        g[0] = match self.criterion {
            Criterion::NonZero => io.u(1),
            _ => io.u(1) - self.threshold,
        };
    }
}

fn build_switch(p: &mut Params) -> Result<Built, Diagnostic> {
    let threshold = p.number("threshold")?;
    let criterion = match p.choice("criterion", &[">=", ">", "!=0"])? {
        ">" => Criterion::Above,
        "!=0" => Criterion::NonZero,
        _ => Criterion::AtLeast,
    };
    let iface = Interface::new(p.sample_time()?)
        .piecewise_constant()
        .input("u1", Width::Common, true)
        .input("control", Width::Fixed(1), true)
        .input("u2", Width::Common, true)
        .output("y", Width::Common);
    Ok(Built::new(Switch { threshold, criterion, first: true }, iface))
}
