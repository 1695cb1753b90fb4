//! The memo tables of a [`Ctx`]: what the canonical-form and derivative
//! passes remember about the arena's nodes. The arena (graph.rs) owns a
//! [`Memo`] as an opaque field and never reads it, so it does not depend on
//! the canonical forms (canon.rs); the passes that fill the tables do.

use crate::canon::RatFun;
use crate::graph::{Ctx, Id};
use crate::poly::Var;
use rustc_hash::FxHashMap;

#[derive(Default, Clone)]
pub(crate) struct Memo {
    /// The canonical form of each node canonicalised so far (canon.rs).
    pub canon: FxHashMap<Id, RatFun>,
    /// The derivative of a node by a leaf (diff.rs).
    pub diff: FxHashMap<(Id, Var), Id>,
    /// The canonical radicand of each `sqrt` leaf: its relation `r^2 = radicand`.
    pub radicands: FxHashMap<Var, RatFun>,
}

impl Ctx {
    /// The canonical radicand of a `sqrt` leaf (`None` for any other leaf).
    pub(crate) fn radicand(&self, v: Var) -> Option<&RatFun> {
        self.memo.radicands.get(&v)
    }
}
