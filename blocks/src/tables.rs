//! Tabulated data: 1-D lookup tables and time series read from CSV files,
//! both by linear interpolation.

use crate::{SAMPLE_TIME_CONTINUOUS, SAMPLE_TIME_INHERITED, U_ANY, Y_SAME, Y_SCALAR, table::*};
use ctlgraph_core::codegen::c::{CBlock, NoCForm};
use ctlgraph_core::registry::{BlockType, Built, ParamDoc, PortDoc};
use ctlgraph_core::{Block, Diagnostic, Interface, Io, Params, Width};

pub const TYPES: &[BlockType] = &[
    BlockType {
        name: "lookup_table_1d",
        category: "math",
        summary: "Piecewise-linear map y = f(u) from breakpoints.",
        doc: "Linear interpolation between (x[i], y[i]); x strictly increasing. Outside [x0, xn]: \
              `clamp` holds the end values, `linear` extends the first/last segment. Elementwise.",
        inputs: U_ANY,
        outputs: Y_SAME,
        params: &[
            param("x", Required, "breakpoints, strictly increasing, at least two").kind(ParamKind::Numbers),
            param("y", Required, "table values, one per breakpoint").kind(ParamKind::Numbers),
            param("extrapolation", Word("clamp"), "clamp | linear").options(&["clamp", "linear"]),
            SAMPLE_TIME_INHERITED,
        ],
        build: build_lookup,
    },
    BlockType {
        name: "from_csv",
        category: "sources",
        summary: "A time series read from a CSV file, linearly interpolated.",
        doc: "Reads column `column` against column `time` (header names) from `file`, relative to the \
              graph file. Times must be non-decreasing; a repeated time is a jump. Outside the data: \
              `hold` keeps the end values, `linear` extends the end segments, `zero` outputs 0.",
        inputs: &[],
        outputs: Y_SCALAR,
        params: &[
            param("file", Required, "CSV file with a header row"),
            param("column", Required, "header of the value column"),
            param("time", Word("t"), "header of the time column"),
            param("extrapolation", Word("hold"), "hold | linear | zero").options(&["hold", "linear", "zero"]),
            MAX_FILE_MIB,
            SAMPLE_TIME_CONTINUOUS,
            crate::ACTIVE,
        ],
        build: build_from_csv,
    },
    BlockType {
        name: "lookup_table_2d",
        category: "math",
        summary: "Bilinear interpolation y = f(u1, u2) in a table over two sets of breakpoints.",
        doc: "With row breakpoints r (for u1), column breakpoints c (for u2), both strictly \
              increasing, and table[i][j] the value at (r[i], c[j]) — Simulink's 2-D Lookup Table with \
              linear interpolation: in the cell r[i] <= u1 <= r[i+1], c[j] <= u2 <= c[j+1], with \
              a = (u1 − r[i])/(r[i+1] − r[i]) and b = (u2 − c[j])/(c[j+1] − c[j]),\n\
              \x20 y = (1−a)·[(1−b)·T[i][j] + b·T[i][j+1]] + a·[(1−b)·T[i+1][j] + b·T[i+1][j+1]]\n\
              Outside the breakpoints `clip` (Simulink's name; `clamp` as lookup_table_1d says is the \
              same) holds each input at its end breakpoint, `linear` extends the edge cells. \
              Elementwise over u1 and u2 (a scalar is paired with every element of the other).",
        inputs: &[
            PortDoc { name: "u1", doc: "the row coordinate; any width" },
            PortDoc { name: "u2", doc: "the column coordinate; same width as u1, or scalar" },
        ],
        outputs: &[PortDoc { name: "y", doc: "same width as the inputs" }],
        params: &[
            param("breakpoints1", Required, "r: breakpoints of u1, strictly increasing, at least two")
                .kind(ParamKind::Numbers),
            param("breakpoints2", Required, "c: breakpoints of u2, strictly increasing, at least two")
                .kind(ParamKind::Numbers),
            param("table", Required, "one row per breakpoint of u1, one column per breakpoint of u2")
                .kind(ParamKind::Matrix),
            param("extrapolation", Word("clip"), "clip | clamp | linear").options(&["clip", "clamp", "linear"]),
            SAMPLE_TIME_INHERITED,
        ],
        build: build_lookup_2d,
    },
];

/// Piecewise-linear interpolation over sorted breakpoints.
#[derive(Clone, Debug)]
pub struct Table {
    x: Vec<f64>,
    y: Vec<f64>,
    outside: Outside,
}

/// What a table gives outside its breakpoints.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Outside {
    Clamp,
    Linear,
    Zero,
}

impl Table {
    /// `x` non-decreasing with at least two points, `y` the same length.
    pub fn new(x: Vec<f64>, y: Vec<f64>, outside: Outside) -> Result<Table, String> {
        if x.len() < 2 || x.len() != y.len() {
            return Err(format!(
                "needs at least two points and as many values as breakpoints ({} vs {})",
                x.len(),
                y.len()
            ));
        }
        if let Some(v) = x.iter().chain(&y).find(|v| !v.is_finite()) {
            return Err(format!("{v} in the data: every breakpoint and value must be a finite number"));
        }
        if let Some(i) = x.windows(2).position(|w| w[1] < w[0]) {
            return Err(format!("breakpoints must increase: {} then {}", x[i], x[i + 1]));
        }
        if x[0] == x[x.len() - 1] {
            return Err("breakpoints span no interval".into());
        }
        // Interpolation takes differences: they must stay finite (±1e308 next
        // to each other would give NaN at run time).
        let overflow = |v: &[f64]| v.windows(2).position(|w| !(w[1] - w[0]).is_finite());
        if let Some(i) = overflow(&x).or_else(|| overflow(&y)) {
            return Err(format!(
                "points {} and {} are too far apart to interpolate between (their difference overflows)",
                i + 1,
                i + 2
            ));
        }
        Ok(Table { x, y, outside })
    }

    /// The interpolated value at `u` (binary search; no allocation).
    pub fn eval(&self, u: f64) -> f64 {
        let (x, y, n) = (&self.x, &self.y, self.x.len());
        if u < x[0] || u > x[n - 1] {
            match self.outside {
                Outside::Zero => return 0.0,
                Outside::Clamp => return if u < x[0] { y[0] } else { y[n - 1] },
                Outside::Linear => {}
            }
        }
        // Segment i: x[i] <= u < x[i+1], limited to the first/last segment.
        let i = x.partition_point(|&v| v <= u).clamp(1, n - 1) - 1;
        let (x0, x1) = (x[i], x[i + 1]);
        if x1 == x0 {
            return y[i + 1];
        }
        y[i] + (y[i + 1] - y[i]) * (u - x0) / (x1 - x0)
    }
}

#[derive(Clone)]
pub struct Lookup(Table);

impl Block for Lookup {
    rust_type!(Lookup);
    fn updates(&self) -> bool {
        false
    }
    fn output(&mut self, io: &mut Io) {
        for k in 0..io.output_width(0) {
            let v = self.0.eval(io.u_at(0, k));
            io.set_at(0, k, v);
        }
    }
    /// [`Table::eval`]: the segment found by counting breakpoints (the
    /// same one as the binary search), the same interpolation.
    fn c_form(&self, c: &mut CBlock) -> Result<(), NoCForm> {
        let t = &self.0;
        let x: Vec<String> = t.x.iter().map(|&v| c.num(v)).collect();
        let y: Vec<String> = t.y.iter().map(|&v| c.num(v)).collect();
        let (x, y) = (c.table("x", c.real(), &x), c.table("y", c.real(), &y));
        let outside = match t.outside {
            Outside::Clamp => 0,
            Outside::Linear => 1,
            Outside::Zero => 2,
        };
        let f = c.helper("ctl_lookup", |r| {
            let (ty, zero) = (r.c_type(), r.literal(0.0));
            format!(
                "/* Linear interpolation in breakpoints x (increasing); outside: 0 clamp, 1 extrapolate, 2 zero */\n\
                 static {ty} ctl_lookup(const {ty} *x, const {ty} *y, int32_t n, int outside, {ty} u)\n{{\n\
                 \x20   int32_t i = 0, j;\n\
                 \x20   if (u < x[0] || u > x[n - 1]) {{\n\
                 \x20       if (outside == 2) return {zero};\n        if (outside == 0) return u < x[0] ? y[0] : y[n - 1];\n    }}\n\
                 \x20   for (j = 0; j < n; j++) if (x[j] <= u) i = j + 1;\n\
                 \x20   if (i < 1) i = 1;\n    if (i > n - 1) i = n - 1;\n    i -= 1;\n\
                 \x20   if (x[i + 1] == x[i]) return y[i + 1];\n\
                 \x20   return y[i] + (y[i + 1] - y[i]) * (u - x[i]) / (x[i + 1] - x[i]);\n}}\n"
            )
        });
        c.equation("y = linear interpolation of the table at u");
        for k in 0..c.output_width(0) {
            c.output(format!("{} = {f}({x}, {y}, {}, {outside}, {});", c.y_at(0, k), t.x.len(), c.u_at(0, k)));
        }
        Ok(())
    }
}

fn build_lookup(p: &mut Params) -> Result<Built, Diagnostic> {
    let x = p.vector("x")?;
    if let Some(i) = x.windows(2).position(|w| w[1] <= w[0]) {
        return Err(p.error("x", format!("breakpoints must be strictly increasing: {} then {}", x[i], x[i + 1])));
    }
    let y = p.vector("y")?;
    let outside = match p.choice("extrapolation", &["clamp", "linear"])? {
        "linear" => Outside::Linear,
        _ => Outside::Clamp,
    };
    let table = Table::new(x, y, outside).map_err(|m| p.error("y", m))?;
    let st = p.sample_time()?;
    let iface = Interface::new(st).piecewise_constant().input("u", Width::Common, true).output("y", Width::Common);
    Ok(Built::new(Lookup(table), iface))
}

#[derive(Clone)]
pub struct Series(Table);

impl Block for Series {
    rust_type!(Series);
    fn updates(&self) -> bool {
        false
    }
    fn output(&mut self, io: &mut Io) {
        let v = self.0.eval(io.t);
        io.set(0, v);
    }
}

fn build_from_csv(p: &mut Params) -> Result<Built, Diagnostic> {
    let path = p.path("file")?;
    let column = p.string("column")?;
    let time = p.string("time")?;
    let outside = match p.choice("extrapolation", &["hold", "linear", "zero"])? {
        "linear" => Outside::Linear,
        "zero" => Outside::Zero,
        _ => Outside::Clamp,
    };
    let limit = data_file_limit(p)?;
    let (ts, ys) = read_columns(&path, time, column, limit).map_err(|m| p.error("file", m))?;
    let table = Table::new(ts, ys, outside).map_err(|m| p.error("file", format!("`{}`: {m}", path.display())))?;
    let st = p.sample_time()?;
    crate::sources::windowed(p, Built::new(Series(table), Interface::new(st).output("y", Width::Fixed(1))))
}

/// The `max_file_mib` parameter of the blocks that read a data file: a CSV
/// of 256 MiB holds some ten million rows; anything larger is more likely
/// a wrong path.
pub(crate) const MAX_FILE_MIB: ParamDoc =
    param("max_file_mib", Number(256.0), "largest data file read, in MiB (a larger file is refused)");

/// The size limit of a block's data file in bytes, from `max_file_mib`
/// (at most 1 TiB).
pub(crate) fn data_file_limit(p: &mut Params) -> Result<u64, Diagnostic> {
    Ok((p.count("max_file_mib", 1 << 20)? as u64) << 20)
}

/// Reads two columns by header name, a row at a time; errors name the
/// file, row and column, and the first malformed row ends the reading.
/// Only regular files up to `limit` bytes are read (not a FIFO or a
/// device such as /dev/zero, which never end).
pub(crate) fn read_columns(
    path: &std::path::Path,
    time: &str,
    column: &str,
    limit: u64,
) -> Result<(Vec<f64>, Vec<f64>), String> {
    let shown = path.display();
    let len = ctlgraph_core::files::regular_file(path).map_err(|e| match e.kind() {
        std::io::ErrorKind::InvalidInput => format!("`{shown}` is {e}: give a CSV file"),
        _ => format!("cannot read `{shown}`: {e}"),
    })?;
    if len > limit {
        return Err(format!(
            "`{shown}` is {} MiB, above the limit of {} MiB for data files (raise `max_file_mib` if it is the right file)",
            len.div_ceil(1 << 20),
            limit >> 20
        ));
    }
    let mut reader = csv::Reader::from_path(path).map_err(|e| format!("cannot read `{shown}`: {e}"))?;
    ctlgraph_core::files::note_read(path);
    let headers = reader.headers().map_err(|e| format!("`{shown}`: {e}"))?.clone();
    let find = |name: &str| {
        headers.iter().position(|h| h.trim() == name).ok_or_else(|| {
            let names: Vec<&str> = headers.iter().collect();
            format!("`{shown}` has no column `{name}` (columns: {})", names.join(", "))
        })
    };
    let (ti, yi) = (find(time)?, find(column)?);
    let (mut ts, mut ys) = (Vec::new(), Vec::new());
    for (row, record) in reader.records().enumerate() {
        let record = record.map_err(|e| format!("`{shown}`: {e}"))?;
        let num = |i: usize, name: &str| -> Result<f64, String> {
            let cell = record.get(i).unwrap_or("").trim();
            cell.parse::<f64>().map_err(|_| format!("`{shown}` row {}: `{name}` is `{cell}`, not a number", row + 2))
        };
        ts.push(num(ti, time)?);
        ys.push(num(yi, column)?);
    }
    Ok((ts, ys))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interpolation_and_extrapolation() {
        let t = Table::new(vec![0.0, 1.0, 3.0], vec![0.0, 2.0, 0.0], Outside::Clamp).unwrap();
        assert_eq!([t.eval(-1.0), t.eval(0.5), t.eval(1.0), t.eval(2.0), t.eval(4.0)], [0.0, 1.0, 2.0, 1.0, 0.0]);
        let l = Table { outside: Outside::Linear, ..t.clone() };
        assert_eq!([l.eval(-1.0), l.eval(4.0)], [-2.0, -1.0]);
        let z = Table { outside: Outside::Zero, ..t };
        assert_eq!([z.eval(-0.1), z.eval(3.0), z.eval(3.1)], [0.0, 0.0, 0.0]);
    }

    #[test]
    fn a_repeated_time_is_a_jump() {
        let t = Table::new(vec![0.0, 1.0, 1.0, 2.0], vec![0.0, 0.0, 5.0, 5.0], Outside::Clamp).unwrap();
        assert_eq!([t.eval(0.999), t.eval(1.0), t.eval(1.5)], [0.0, 5.0, 5.0]);
        assert!(Table::new(vec![1.0, 0.0], vec![0.0, 0.0], Outside::Clamp).is_err());
    }
}

/// A 2-D table with bilinear interpolation.
#[derive(Clone, Debug)]
pub struct Lookup2d {
    rows: Vec<f64>,
    cols: Vec<f64>,
    /// Row-major, rows.len() × cols.len().
    table: Vec<f64>,
    linear: bool,
}

/// The cell of `x` holding `u` (limited to the first and last) and the
/// fraction along it: clipped to [0, 1] unless `linear`.
fn cell(x: &[f64], u: f64, linear: bool) -> (usize, f64) {
    let n = x.len();
    let i = x.partition_point(|&v| v <= u).clamp(1, n - 1) - 1;
    let a = (u - x[i]) / (x[i + 1] - x[i]);
    (i, if linear || a.is_nan() { a } else { a.clamp(0.0, 1.0) })
}

impl Lookup2d {
    pub fn eval(&self, u1: f64, u2: f64) -> f64 {
        let (i, a) = cell(&self.rows, u1, self.linear);
        let (j, b) = cell(&self.cols, u2, self.linear);
        let m = self.cols.len();
        let t = |r: usize, c: usize| self.table[r * m + c];
        let near = t(i, j) + (t(i, j + 1) - t(i, j)) * b;
        let far = t(i + 1, j) + (t(i + 1, j + 1) - t(i + 1, j)) * b;
        near + (far - near) * a
    }
}

impl Block for Lookup2d {
    rust_type!(Lookup2d);
    fn updates(&self) -> bool {
        false
    }
    fn output(&mut self, io: &mut Io) {
        for k in 0..io.output_width(0) {
            let v = self.eval(io.u_at(0, k), io.u_at(1, k));
            io.set_at(0, k, v);
        }
    }
}

fn build_lookup_2d(p: &mut Params) -> Result<Built, Diagnostic> {
    let mut axes = Vec::new();
    for key in ["breakpoints1", "breakpoints2"] {
        let x = p.vector(key)?;
        if x.len() < 2 {
            return Err(p.error(key, format!("needs at least two breakpoints, got {}", x.len())));
        }
        if let Some(v) = x.iter().find(|v| !v.is_finite()) {
            return Err(p.error(key, format!("{v} among the breakpoints: each must be a finite number")));
        }
        if let Some(i) = x.windows(2).position(|w| w[1] <= w[0]) {
            return Err(p.error(key, format!("breakpoints must be strictly increasing: {} then {}", x[i], x[i + 1])));
        }
        axes.push(x);
    }
    let cols = axes.pop().unwrap_or_default();
    let rows = axes.pop().unwrap_or_default();
    let table = p.matrix("table")?;
    if table.len() != rows.len() || table.iter().any(|r| r.len() != cols.len()) {
        let shape = format!("{}×{}", table.len(), table.first().map_or(0, Vec::len));
        let message = format!("expected {}×{} (breakpoints1 × breakpoints2), got {shape}", rows.len(), cols.len());
        return Err(p.error("table", message));
    }
    let table: Vec<f64> = table.into_iter().flatten().collect();
    if let Some(v) = table.iter().find(|v| !v.is_finite()) {
        return Err(p.error("table", format!("{v} in the table: every value must be a finite number")));
    }
    let linear = p.choice("extrapolation", &["clip", "clamp", "linear"])? == "linear";
    let iface = Interface::new(p.sample_time()?)
        .piecewise_constant()
        .input("u1", Width::Common, true)
        .input("u2", Width::Common, true)
        .output("y", Width::Common);
    Ok(Built::new(Lookup2d { rows, cols, table, linear }, iface))
}
