//! The registry maps block type names to their documentation and
//! constructors. `graph-core` knows no particular block; the `blocks` crate
//! fills a registry, and the compiler builds blocks through it.

use crate::block::{Block, Interface};
use crate::diag::Diagnostic;
use crate::params::Params;
pub use crate::params::{ParamDefault, ParamDoc, ParamKind};
use std::collections::BTreeMap;

/// A port, as documented.
#[derive(Clone, Copy, Debug)]
pub struct PortDoc {
    pub name: &'static str,
    pub doc: &'static str,
}

/// A constructed block and its ports.
pub struct Built {
    pub block: Box<dyn Block>,
    pub iface: Interface,
}

impl Built {
    pub fn new(block: impl Block + 'static, iface: Interface) -> Self {
        Built { block: Box::new(block), iface }
    }
}

/// Everything the library knows about a block type.
#[derive(Clone, Copy)]
pub struct BlockType {
    pub name: &'static str,
    /// Library section: sources, math, dynamics, discrete, routing, …
    pub category: &'static str,
    /// One line.
    pub summary: &'static str,
    /// Semantics and equations.
    pub doc: &'static str,
    pub inputs: &'static [PortDoc],
    pub outputs: &'static [PortDoc],
    pub params: &'static [ParamDoc],
    pub build: fn(&mut Params) -> Result<Built, Diagnostic>,
}

/// Block types by name.
#[derive(Default, Clone)]
pub struct Registry {
    types: BTreeMap<&'static str, BlockType>,
}

impl Registry {
    pub fn new() -> Self {
        Registry::default()
    }

    /// Adds a type; a later registration of the same name replaces it (so
    /// users can override library blocks).
    pub fn register(&mut self, ty: BlockType) {
        self.types.insert(ty.name, ty);
    }

    pub fn get(&self, name: &str) -> Option<&BlockType> {
        self.types.get(name)
    }

    /// All types, sorted by name.
    pub fn types(&self) -> impl Iterator<Item = &BlockType> {
        self.types.values()
    }

    pub fn names(&self) -> impl Iterator<Item = &'static str> + '_ {
        self.types.keys().copied()
    }
}
