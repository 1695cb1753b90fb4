//! The symbolic context [`Ctx`]: the arena (graph.rs) and, beside it, the
//! memo tables of what the canonical-form and derivative passes remember
//! about its nodes. The arena knows nothing of the tables or of canonical
//! forms, so graph.rs depends on neither canon.rs nor this module; the passes
//! (canon, diff, lower, ...) reach the arena through `Ctx`, which derefs to it.

use crate::budget::{self, Limit};
use crate::graph::{Arena, Id};
use crate::poly::Var;
use crate::ratfun::RatFun;
use rustc_hash::FxHashMap;
use std::fmt;
use std::ops::{Deref, DerefMut};

/// The symbolic context: the arena of nodes and leaves, and memo tables.
#[derive(Default, Clone)]
pub struct Ctx {
    pub(crate) arena: Arena,
    pub(crate) memo: Memo,
}

impl Deref for Ctx {
    type Target = Arena;
    fn deref(&self) -> &Arena {
        &self.arena
    }
}

impl DerefMut for Ctx {
    fn deref_mut(&mut self) -> &mut Arena {
        &mut self.arena
    }
}

impl fmt::Debug for Ctx {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "Ctx({} nodes, {} leaves)",
            self.nodes.len(),
            self.leaves.len()
        )
    }
}

#[derive(Default, Clone)]
pub(crate) struct Memo {
    /// The canonical form of each node canonicalised so far (canon.rs).
    pub canon: FxHashMap<Id, RatFun>,
    /// The derivative of a node by a leaf (diff.rs).
    pub diff: FxHashMap<(Id, Var), Id>,
    /// The canonical radicand of each `sqrt` leaf: its relation `r^2 = radicand`.
    pub radicands: FxHashMap<Var, RatFun>,
    /// An equal, smaller form of a node built from a canonical form
    /// (written.rs).
    pub written: FxHashMap<Id, Id>,
}

impl Ctx {
    pub fn new() -> Ctx {
        Ctx::default()
    }

    /// Run `f` under the context's budget. When a limit is hit, `f`'s value
    /// (built from placeholders) is dropped and the limit is returned; the
    /// context stays valid, since no placeholder reaches its memo tables or
    /// leaves. Nested calls share the outermost budget.
    pub fn within_budget<T>(&mut self, f: impl FnOnce(&mut Ctx) -> T) -> Result<T, Limit> {
        match self.budgeted(f) {
            (r, None) => Ok(r),
            (_, Some(l)) => Err(l),
        }
    }

    /// As [`Ctx::within_budget`], keeping `f`'s value (a placeholder when
    /// the limit is `Some`, but it may hold a located error worth reporting).
    pub(crate) fn budgeted<T>(&mut self, f: impl FnOnce(&mut Ctx) -> T) -> (T, Option<Limit>) {
        let b = self.arena.budget;
        let outer_cap = self.arena.cell_cap;
        self.arena.cell_cap = Some(outer_cap.map_or(b.max_nodes, |c| c.min(b.max_nodes)));
        // Memo tables and leaves are only written while nothing has tripped
        // (canon, diff, from_canonical and the lowering check), so nothing
        // needs undoing here.
        let (r, lim) = budget::scope(&b, || f(self));
        self.arena.cell_cap = outer_cap;
        (r, lim)
    }

    /// The canonical radicand of a `sqrt` leaf (`None` for any other leaf).
    pub(crate) fn radicand(&self, v: Var) -> Option<&RatFun> {
        self.memo.radicands.get(&v)
    }
}
