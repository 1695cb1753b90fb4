//! Which atoms a certificate built on nonzero forms cannot rest on.
//!
//! A zero canonical form proves zero; a nonzero one proves nonzero only over
//! atoms the engine proves independent (docs/engine.md, "Decided and not
//! decided"). The rank's non-zero minor, the Gauss-Jordan pivots of the
//! symmetries, the independence of modes and "there are no more symmetries"
//! all rest on nonzero forms built from the system's fields and outputs (and
//! the modes' gradients): products and quotients of their atoms and of the
//! atoms' derivatives, which stay in the field those atoms generate.

use obsan_expr::{Id, RatFun};
use obsan_model::NormalForm;

/// The atoms of the system's fields and outputs, and of the forms `extra`
/// (modes, say), whose algebraic independence the engine cannot prove,
/// sorted as text. Empty: every nonzero form built from them (a minor, a
/// pivot, a residual) is a proof of "nonzero". Every product is covered
/// (`linear_ok` false), as a minor multiplies entries.
pub fn undecided_atoms_of(nf: &mut NormalForm, extra: &[Id]) -> Vec<String> {
    let mut ids: Vec<Id> = nf.f0.clone();
    ids.extend(nf.fields.iter().flatten());
    ids.extend(nf.unknown_fields.iter().flatten());
    ids.extend(nf.outputs.iter().map(|o| o.1));
    ids.extend_from_slice(extra);
    undecided_atoms_of_forms(nf, &ids)
}

/// The undecided atoms of the forms `ids` alone (and all their products):
/// what a minor of their gradients rests on.
pub(crate) fn undecided_atoms_of_forms(nf: &mut NormalForm, ids: &[Id]) -> Vec<String> {
    let forms: Vec<RatFun> = ids.iter().map(|&id| nf.ctx.canon(id)).collect();
    let vs = nf.ctx.undecided_atoms_in(&forms, false);
    nf.ctx.atom_texts(&vs)
}
