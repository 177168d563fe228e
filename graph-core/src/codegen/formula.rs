//! A block whose output is a formula ([`crate::Block::formula`]: `fcn`),
//! written in place by a generated step: its Rust at generation time
//! ([`Formula`]), its numbers when a run starts ([`formula_constants`]) —
//! the code depends on the formula's shape alone.

use crate::compile::Model;

/// A block whose output is a formula of its inputs and t, written in
/// place: the signals it reads, its constants in `Step::k`.
pub(super) struct Formula {
    /// Where its output goes in the signals.
    pub(super) y: usize,
    /// Its value as Rust ([`crate::expr::Expr::to_rust`]).
    pub(super) code: String,
    /// How many of `Step::k` its constants take (from its visit's
    /// `constants` on).
    pub(super) constants: usize,
}

impl Formula {
    /// Block `i`'s formula, its constants from `Step::k[first]` on.
    pub(super) fn of(model: &Model, i: usize, first: usize) -> Option<Formula> {
        let expr = model.blocks[i].formula()?;
        let slot = &model.slots[i];
        let inputs = &model.in_ports[slot.inputs.clone()];
        let y = model.out_ports[slot.outputs.clone()].first()?;
        if y.width != 1 || inputs.iter().any(|p| p.width != 1) {
            return None;
        }
        let mut vars: Vec<String> = inputs.iter().map(|p| format!("s[{}]", p.offset)).collect();
        vars.push("t".into());
        let code = expr.to_rust(&vars, &|j| format!("self.k[{}]", first + j));
        Some(Formula { y: y.offset, code, constants: expr.constants().len() })
    }
}

/// Block `index`'s formula constants ([`crate::expr::Expr::constants`])
/// into `k`, which has room for exactly as many.
pub fn formula_constants(model: &Model, index: usize, k: &mut [f64]) -> Result<(), String> {
    let constants = model.blocks.get(index).and_then(|b| b.formula()).map(|f| f.constants());
    match constants {
        Some(c) if c.len() == k.len() => {
            k.copy_from_slice(&c);
            Ok(())
        }
        _ => Err(super::mismatch(model, index)),
    }
}
