//! Substitution of symbols by expressions, rebuilding every function whose
//! argument changes (so the result is lowered exactly as if written out).

use crate::graph::{Angle, Id, LeafKind, Node};
use crate::lower::EngineError;
use crate::memo::Ctx;
use crate::num::Q;
use crate::poly::Var;
use rustc_hash::FxHashMap;

impl Ctx {
    /// `id` with each symbol `map[i].0` replaced by the node `map[i].1`.
    /// Runs under the context's budget ([`Ctx::set_budget`](Ctx#method.set_budget)).
    pub fn substitute(&mut self, id: Id, map: &[(Var, Id)]) -> Result<Id, EngineError> {
        self.within_budget(|c| c.substitute_raw(id, map))?
    }

    fn substitute_raw(&mut self, id: Id, map: &[(Var, Id)]) -> Result<Id, EngineError> {
        let order = self.reachable(&[id]);
        let mut new: FxHashMap<Id, Id> = FxHashMap::default();
        for n in order {
            let deps = self.deps(n);
            let changed = deps.iter().any(|d| new.get(d).is_some_and(|x| x != d));
            let is_target =
                matches!(self.node(n), Node::Leaf(v) if map.iter().any(|(s, _)| s == v));
            let r = if is_target {
                let v = match *self.node(n) {
                    Node::Leaf(v) => Some(v),
                    _ => None,
                };
                match map.iter().find(|(s, _)| Some(*s) == v) {
                    Some(t) => t.1,
                    None => n,
                }
            } else if !changed {
                n
            } else {
                let get = |x: &Id| new[x];
                match self.node(n).clone() {
                    Node::Num(_) => n,
                    Node::Add(cs) => {
                        let v: Vec<Id> = cs.iter().map(get).collect();
                        self.add(&v)
                    }
                    Node::Mul(cs) => {
                        // Negative powers were checked when they were rebuilt (children first).
                        let v: Vec<Id> = cs.iter().map(get).collect();
                        self.mul(&v)
                    }
                    Node::Pow(b, e) => {
                        let nb = get(&b);
                        if e < 0 && self.canon(nb).is_zero() && !crate::budget::tripped() {
                            return Err(EngineError(
                                "the substitution makes a denominator zero".into(),
                            ));
                        }
                        self.pow(nb, e as i64)
                    }
                    Node::Leaf(v) => self.rebuild_leaf(v, &get)?,
                }
            };
            if crate::budget::tripped() {
                return Err(EngineError("engine limit".into()));
            }
            new.insert(n, r);
        }
        Ok(new.get(&id).copied().unwrap_or(id))
    }

    fn rebuild_leaf(&mut self, v: Var, get: &dyn Fn(&Id) -> Id) -> Result<Id, EngineError> {
        let kind = self.leaves[v as usize].kind.clone();
        let angle_arg = |s: &mut Ctx, a: &Angle| -> Id {
            match a {
                Angle::Symbol { sym, den } => {
                    let x = get(&s.leaf_node(*sym));
                    let k = s.num(Q::new(1.into(), (*den as i64).into()));
                    s.mul(&[k, x])
                }
                Angle::Generic(g) => get(g),
            }
        };
        match kind {
            LeafKind::Symbol(_) | LeafKind::Pi => Ok(self.leaf_node(v)),
            LeafKind::Sin(a) => {
                let x = angle_arg(self, &a);
                self.sin(x)
            }
            LeafKind::Cos(a) => {
                let x = angle_arg(self, &a);
                self.cos(x)
            }
            LeafKind::Exp(a) => {
                let x = angle_arg(self, &a);
                self.exp(x)
            }
            LeafKind::Atan(u) => self.atan(get(&u)),
            LeafKind::Atan2(y, x) => self.atan2(get(&y), get(&x)),
            LeafKind::Log(u) => self.log(get(&u)),
            LeafKind::Root(u, q) => self.root(get(&u), q),
        }
    }
}
