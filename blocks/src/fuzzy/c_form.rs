//! The fuzzy block's C form: the inference as the block computes it for a
//! rule table over inputs whose terms are triangular partitions (`grid`):
//! each input located between two peaks, the 2ⁿ corner cells' strengths
//! concluded into their terms, then per output the closed-form centroid
//! of a triangular-partition output (`centroid`) or Sugeno's weighted
//! average — the same operations in the same order, so the C gives the
//! block's bits. The per-cell sums the block looks up in tables
//! (`Below`) are computed in C by the expressions that filled them; the
//! peaks and the table's conclusions are `static const` arrays.

use super::centroid::PartitionCentroid;
use super::fis::{Aggregation, Fis, Implication, Mf};
use ctlgraph_core::codegen::c::{CBlock, NoCForm, Real};

/// What the C form covers, for the refusal.
const COVERED: &str = "its C form covers a rule table (an AND of one term of each input per rule) over inputs \
                       whose terms are triangular partitions, with Mamdani outputs that are triangular partitions \
                       defuzzified by centroid (min or product implication with max aggregation, or product with \
                       sum), or Sugeno outputs";

impl Fis {
    pub(super) fn c_form(&self, c: &mut CBlock) -> Result<(), NoCForm> {
        let refuse = || NoCForm::Because(COVERED.into());
        let grid = self.grid.as_ref().ok_or_else(refuse)?;
        let closed_form = self.exact.iter().all(Option::is_some) && self.methods.by_term();
        if !self.sugeno && !closed_form {
            return Err(refuse());
        }
        let real = c.real();
        let n_in = self.inputs.len();
        c.equation(
            "x_i = inputs clipped to their universes; each between two peaks of its partition (memberships a_i, b_i)",
        );
        c.equation(match grid.product {
            true => "cell strength = product of its terms' memberships, over the 2^n cells around x",
            false => "cell strength = min of its terms' memberships, over the 2^n cells around x",
        });
        if self.sugeno {
            c.equation("y = sum(w_r z_r) / sum(w_r) over the fired rules (the universe's middle when none fires)");
        } else {
            c.equation("term strength = max (or sum) of its cells'; y = centroid of the trapezoid-sampled aggregate, in closed form");
        }
        // Where each cell's conclusions are: flat term indices, in rule order.
        let by_cell = grid.terms_by_cell(|r| self.conclusions[self.conclusion_ranges[r].clone()].to_vec());
        let mut at: Vec<String> = by_cell.cells.iter().map(|&(from, _)| from.to_string()).collect();
        at.push(by_cell.terms.len().to_string());
        let cell_at = c.table("cell_at", "int32_t", &at);
        let terms: Vec<String> = by_cell.terms.iter().map(usize::to_string).collect();
        let cell_terms = c.table("cell_terms", "int32_t", &terms);
        let locate = locate_helper(c);
        let clamp = c.clamp();
        let n_terms = self.term_offsets[self.outputs.len()];
        c.output("int32_t j;");
        for (i, v) in self.inputs.iter().enumerate() {
            let peaks: Vec<String> = grid.partitions[i].peaks.iter().map(|&p| c.num(p)).collect();
            let table = c.table(&format!("peaks_{i}"), real, &peaks);
            let x = format!("{clamp}({}, {}, {})", c.u(i), c.num(v.lo), c.num(v.hi));
            c.output(format!(
                "int32_t k{i};\n{real} a{i}, b{i};\n{locate}({table}, {}, {x}, &k{i}, &a{i}, &b{i});",
                peaks.len()
            ));
        }
        // The sugeno sums, or the term strengths.
        let conclude = if self.sugeno {
            let z: Vec<String> = self
                .outputs
                .iter()
                .flat_map(|v| v.terms.iter().map(|(_, mf)| if let Mf::Const(z) = mf { *z } else { 0.0 }))
                .map(|z| c.num(z))
                .collect();
            let consts = c.table("consts", real, &z);
            let owner: Vec<String> = (0..self.outputs.len())
                .flat_map(|o| (self.term_offsets[o]..self.term_offsets[o + 1]).map(move |_| o.to_string()))
                .collect();
            let owner = c.table("term_output", "int32_t", &owner);
            let m = self.outputs.len();
            c.output(format!(
                "{real} num[{m}], den[{m}];\nfor (j = 0; j < {m}; j++) {{\n    num[j] = {0};\n    den[j] = {0};\n}}",
                c.num(0.0)
            ));
            let f = sugeno_helper(c);
            Box::new(move |cell: String, s: String| {
                format!("{f}(num, den, {cell_at}, {cell_terms}, {consts}, {owner}, {cell}, {s});")
            }) as Box<dyn Fn(String, String) -> String>
        } else {
            c.output(format!("{real} w[{n_terms}];\nfor (j = 0; j < {n_terms}; j++) w[j] = {};", c.num(0.0)));
            let sum = i32::from(self.methods.aggregation == Aggregation::Sum);
            let f = conclude_helper(c);
            Box::new(move |cell: String, s: String| format!("{f}(w, {cell_at}, {cell_terms}, {cell}, {s}, {sum});"))
        };
        for corner in 0..1usize << n_in {
            let mu = |i: usize| if corner >> i & 1 == 1 { format!("b{i}") } else { format!("a{i}") };
            let cell: Vec<String> = (0..n_in)
                .map(|i| {
                    let k = if corner >> i & 1 == 1 { format!("(k{i} + 1)") } else { format!("k{i}") };
                    if grid.strides[i] == 1 { k } else { format!("{k} * {}", grid.strides[i]) }
                })
                .collect();
            let strength = if n_in == 2 {
                let (u, v) = (mu(0), mu(1));
                if grid.product { format!("{u} * {v}") } else { format!("{u} < {v} ? {u} : {v}") }
            } else {
                // The fold from 1 (product) or +inf (min), input by input.
                let mut s = if grid.product { c.num(1.0) } else { "INFINITY".into() };
                for i in 0..n_in {
                    s = if grid.product {
                        format!("({s}) * {}", mu(i))
                    } else {
                        format!("({0} < ({s}) ? {0} : ({s}))", mu(i))
                    };
                }
                s
            };
            c.output(conclude(cell.join(" + "), strength));
        }
        for (o, v) in self.outputs.iter().enumerate() {
            let mid = format!("({} + {}) / {}", c.num(v.lo), c.num(v.hi), c.num(2.0));
            let value = match &self.exact[o] {
                Some(exact) if !self.sugeno => centroid(c, exact, o, self.term_offsets[o], &mid),
                _ => format!("den[{o}] > {} ? num[{o}] / den[{o}] : {mid}", c.num(0.0)),
            };
            c.output(format!("{} = {value};", c.y(o)));
        }
        Ok(())
    }
}

/// The closed-form centroid of output `o` from `w[offset…]`: its cells as
/// a constant table, the call, the midpoint when nothing fires.
fn centroid(c: &mut CBlock, e: &PartitionCentroid, o: usize, offset: usize, midpoint: &str) -> String {
    types_helper(c);
    let f = centroid_helper(c);
    let cells: Vec<String> = e
        .cells
        .iter()
        .map(|k| {
            let n = |v: f64| c.num(v);
            format!(
                "{{ {}, {}, {}, {}, {}, {}, {}, {}, {}, {}, {} }}",
                n(k.start),
                n(k.len),
                k.top,
                n(k.offset_less_half),
                n(k.span),
                n(k.per_point),
                n(k.s_first),
                n(k.len_sums.0),
                n(k.len_sums.1),
                n(k.len_sums.2),
                i32::from(k.rises)
            )
        })
        .collect();
    let table = c.table(&format!("cells_{o}"), "ctl_fz_cell", &cells);
    let method = match (e.implication, e.aggregation) {
        (Implication::Min, _) => 0,
        (Implication::Product, Aggregation::Max) => 1,
        (Implication::Product, Aggregation::Sum) => 2,
    };
    let real = c.real();
    c.output(format!("{real} y{o};"));
    format!(
        "{f}({table}, {}, w + {offset}, {method}, {}, {}, {}, {}, {}, {}, {}, &y{o}) ? y{o} : {midpoint}",
        e.cells.len(),
        e.ends[0].0,
        c.num(e.ends[0].1),
        e.ends[1].0,
        c.num(e.ends[1].1),
        c.num(e.last),
        c.num(e.lo),
        c.num(e.dx),
    )
}

/// `Partition::locate` (the cell's k found from below; the same k).
fn locate_helper(c: &mut CBlock) -> &'static str {
    c.helper("ctl_fz_locate", |r: Real| {
        let t = r.c_type();
        format!(
            "/* fuzzy: the k with peak k <= x < peak k+1 (k <= n - 2) and the memberships of terms k, k+1 at x */\n\
             static void ctl_fz_locate(const {t} *p, int32_t n, {t} x, int32_t *k, {t} *a, {t} *b)\n{{\n\
             \x20   int32_t j = 0;\n    {t} width;\n    while (j < n - 2 && x >= p[j + 1]) j++;\n\
             \x20   width = p[j + 1] - p[j];\n    *k = j;\n    *a = (p[j + 1] - x) / width;\n    *b = (x - p[j]) / width;\n}}\n"
        )
    })
}

/// A cell's strength into the terms its rules conclude: the larger, or the sum.
fn conclude_helper(c: &mut CBlock) -> &'static str {
    c.helper("ctl_fz_conclude", |r: Real| {
        let t = r.c_type();
        format!(
            "/* fuzzy: a cell of strength s concludes its rules' terms (max, or sum when `sum`) */\n\
             static void ctl_fz_conclude({t} *w, const int32_t *at, const int32_t *terms, int32_t cell, {t} s, int sum)\n{{\n\
             \x20   int32_t j;\n    for (j = at[cell]; j < at[cell + 1]; j++) {{\n        {t} *v = &w[terms[j]];\n\
             \x20       *v = sum ? *v + s : (s > *v ? s : *v);\n    }}\n}}\n"
        )
    })
}

/// A fired cell's rules into the Sugeno sums of their outputs.
fn sugeno_helper(c: &mut CBlock) -> &'static str {
    c.helper("ctl_fz_sugeno", |r: Real| {
        let (t, zero) = (r.c_type(), r.literal(0.0));
        format!(
            "/* fuzzy, Sugeno: each rule of a fired cell adds s z to its outputs' numerators, s to their denominators */\n\
             static void ctl_fz_sugeno({t} *num, {t} *den, const int32_t *at, const int32_t *terms, const {t} *z,\n\
             \x20                         const int32_t *output, int32_t cell, {t} s)\n{{\n\
             \x20   int32_t j;\n    if (!(s > {zero})) return;\n    for (j = at[cell]; j < at[cell + 1]; j++) {{\n\
             \x20       num[output[terms[j]]] += s * z[terms[j]];\n        den[output[terms[j]]] += s;\n    }}\n}}\n"
        )
    })
}

/// The types of the centroid's tables: a cell between two peaks, and the sums below one of its points.
fn types_helper(c: &mut CBlock) {
    c.helper("ctl_fz_types", |r: Real| {
        let t = r.c_type();
        format!(
            "/* fuzzy: the grid points between two neighbouring peaks of an output's partition */\n\
             typedef struct {{\n    {t} start, len;\n    int32_t top;\n    {t} offset_less_half, span, per_point, s_first;\n\
             \x20   {t} whole0, whole1, whole2;\n    int32_t rises;\n}} ctl_fz_cell;\n\n\
             /* fuzzy: n, sum i, sum i^2 below point n; the rising and falling slopes' sums */\n\
             typedef struct {{\n    {t} n0, n1, n2, rise0, rise1, fall0, fall1;\n}} ctl_fz_below;\n"
        )
    });
}

/// `Cell::below` with `Below::new`'s sums computed (the block looks them up).
fn centroid_helper(c: &mut CBlock) -> &'static str {
    c.helper("ctl_fz_centroid", |r: Real| {
        let t = r.c_type();
        let (l, zero, half, one, two, three, six) =
            (r.math("lrint"), r.literal(0.0), r.literal(0.5), r.literal(1.0), r.literal(2.0), r.literal(3.0), r.literal(6.0));
        format!(
            "/* fuzzy: the first point n of a cell with s >= to, and the sums below it */\n\
             static ctl_fz_below ctl_fz_below_at(const ctl_fz_cell *c, {t} to)\n{{\n\
             \x20   ctl_fz_below b;\n    long n = {l}(to * c->span - c->offset_less_half);\n    {t} p0, p1, p2;\n\
             \x20   if (n < 0) n = 0;\n    if (n > c->top) n = c->top;\n\
             \x20   b.n0 = ({t})n;\n    b.n1 = {half} * b.n0 * (b.n0 - {one});\n    b.n2 = b.n1 * ({two} * b.n0 - {one}) / {three};\n\
             \x20   b.rise0 = c->s_first * b.n0 + c->per_point * b.n1;\n    b.rise1 = c->s_first * b.n1 + c->per_point * b.n2;\n\
             \x20   p0 = c->whole0 - b.n0;\n    p1 = c->whole1 - b.n1;\n    p2 = c->whole2 - b.n2;\n\
             \x20   b.fall0 = ({one} - c->s_first) * p0 + -c->per_point * p1;\n    b.fall1 = ({one} - c->s_first) * p1 + -c->per_point * p2;\n\
             \x20   return b;\n}}\n\n\
             /* fuzzy: a cell's sums of mu and i mu for mu = c0 + c1 s, piece by piece up to s = to */\n\
             static void ctl_fz_pieces(const ctl_fz_cell *c, const {t} *to, const {t} *c0, const {t} *c1, int pieces, {t} *z0, {t} *z1)\n{{\n\
             \x20   {t} f0 = {zero}, f1 = {zero}, f2 = {zero};\n    int p;\n    *z0 = {zero};\n    *z1 = {zero};\n\
             \x20   for (p = 0; p < pieces; p++) {{\n        {t} e0 = c->whole0, e1 = c->whole1, e2 = c->whole2, a, b;\n\
             \x20       if (p + 1 < pieces) {{\n            ctl_fz_below end = ctl_fz_below_at(c, to[p]);\n            e0 = end.n0;\n            e1 = end.n1;\n            e2 = end.n2;\n        }}\n\
             \x20       a = c0[p] + c1[p] * c->s_first;\n        b = c1[p] * c->per_point;\n\
             \x20       *z0 += a * (e0 - f0) + b * (e1 - f1);\n        *z1 += a * (e1 - f1) + b * (e2 - f2);\n\
             \x20       f0 = e0;\n        f1 = e1;\n        f2 = e2;\n    }}\n}}\n\n\
             /* fuzzy: a cell's sums for strengths wa (falling term), wb (rising); method 0 min/max, 1 product/max, 2 product/sum */\n\
             static void ctl_fz_sums(const ctl_fz_cell *c, int method, {t} wa, {t} wb, {t} *z0, {t} *z1)\n{{\n\
             \x20   ctl_fz_below b1, b2;\n    {t} s0, s1;\n\
             \x20   if (method == 1) {{\n        {t} to[2], c0[2], c1[2];\n        to[0] = wa / (wa + wb); c0[0] = wa; c1[0] = -wa;\n        to[1] = {one}; c0[1] = {zero}; c1[1] = wb;\n        ctl_fz_pieces(c, to, c0, c1, 2, z0, z1);\n        return;\n    }}\n\
             \x20   if (method == 2) {{\n        {t} to = {one}, c0 = wa, c1 = wb - wa;\n        ctl_fz_pieces(c, &to, &c0, &c1, 1, z0, z1);\n        return;\n    }}\n\
             \x20   if (wa == {zero}) {{\n        b2 = ctl_fz_below_at(c, wb);\n        *z0 = b2.rise0 + wb * (c->whole0 - b2.n0);\n        *z1 = b2.rise1 + wb * (c->whole1 - b2.n1);\n        return;\n    }}\n\
             \x20   if (wb == {zero}) {{\n        b1 = ctl_fz_below_at(c, {one} - wa);\n        *z0 = wa * b1.n0 + b1.fall0;\n        *z1 = wa * b1.n1 + b1.fall1;\n        return;\n    }}\n\
             \x20   if (wa > {half} && wb > {half}) {{\n        {t} to[4], c0[4], c1[4];\n\
             \x20       to[0] = {one} - wa; c0[0] = wa; c1[0] = {zero};\n        to[1] = {half}; c0[1] = {one}; c1[1] = -{one};\n\
             \x20       to[2] = wb; c0[2] = {zero}; c1[2] = {one};\n        to[3] = {one}; c0[3] = wb; c1[3] = {zero};\n\
             \x20       ctl_fz_pieces(c, to, c0, c1, 4, z0, z1);\n        return;\n    }}\n\
             \x20   if (wa <= wb) {{\n        b1 = ctl_fz_below_at(c, wa);\n        b2 = ctl_fz_below_at(c, wb);\n        s0 = b2.rise0 - b1.rise0;\n        s1 = b2.rise1 - b1.rise1;\n\
             \x20   }} else {{\n        b1 = ctl_fz_below_at(c, {one} - wa);\n        b2 = ctl_fz_below_at(c, {one} - wb);\n        s0 = b1.fall0 - b2.fall0;\n        s1 = b1.fall1 - b2.fall1;\n    }}\n\
             \x20   *z0 = wa * b1.n0 + s0 + wb * (c->whole0 - b2.n0);\n    *z1 = wa * b1.n1 + s1 + wb * (c->whole1 - b2.n1);\n}}\n\n\
             /* fuzzy: the aggregate's value at s in a cell */\n\
             static {t} ctl_fz_at(int method, {t} wa, {t} wb, {t} s)\n{{\n\
             \x20   {t} falling, rising;\n\
             \x20   if (method == 2) return wa * ({one} - s) + wb * s;\n\
             \x20   if (method == 1) {{\n        falling = wa * ({one} - s);\n        rising = wb * s;\n    }} else {{\n\
             \x20       falling = wa < {one} - s ? wa : {one} - s;\n        rising = wb < s ? wb : s;\n    }}\n\
             \x20   return falling > rising ? falling : rising;\n}}\n\n\
             /* fuzzy: the centroid of an output's aggregate from its terms' strengths w (0 when nothing fires) */\n\
             static int ctl_fz_centroid(const ctl_fz_cell *cells, int32_t n, const {t} *w, int method, int32_t k0, {t} s0_end,\n\
             \x20                          int32_t k1, {t} s1_end, {t} last, {t} lo, {t} dx, {t} *y)\n{{\n\
             \x20   {t} s0 = {zero}, s1 = {zero}, first, final_, moment, area;\n    int positive = 0;\n    int32_t k;\n\
             \x20   for (k = 0; k < n; k++) {{\n        {t} wa = w[k], wb = w[k + 1], z0, z1;\n\
             \x20       if (wa > {zero} || wb > {zero}) {{\n\
             \x20           positive |= (wa > {zero} && cells[k].len > {zero}) || (wb > {zero} && cells[k].rises);\n\
             \x20           ctl_fz_sums(&cells[k], method, wa, wb, &z0, &z1);\n            s0 += z0;\n            s1 += cells[k].start * z0 + z1;\n        }}\n    }}\n\
             \x20   first = ctl_fz_at(method, w[k0], w[k0 + 1], s0_end);\n    final_ = ctl_fz_at(method, w[k1], w[k1 + 1], s1_end);\n\
             \x20   if (!(positive || first > {zero} || final_ > {zero})) return 0;\n\
             \x20   s0 = s0 + first + final_;\n    s1 = s1 + last * final_;\n\
             \x20   moment = s1 + first / {six} - final_ * (last / {two} + {one} / {six});\n    area = s0 - {half} * (first + final_);\n\
             \x20   if (!(area > {zero})) return 0;\n    *y = lo + dx * moment / area;\n    return 1;\n}}\n"
        )
    })
}
