//! The view of unknown_input_modes.rs when the certified symmetries move with
//! the known inputs (docs/engine.md, "Modes that move with the inputs").
//!
//! A symmetry `xi(S, u, u', ...)` has no component along the inputs' jets.
//! The view makes each jet it reads a coordinate: for input `u` read up to
//! order `L`, dynamic states `u, u^(1), ..., u^(L)` with `u^(l)' = u^(l+1)`,
//! the last driven by a new known input `u^(L+1)`, `f_u u` moved into the
//! drift, and each jet an output (known: the input is measured, so its jets
//! are too). The vectors get zero components there. Why this is the right
//! system: its drift is `F_ext = F + sum_l u^(l+1) d/du^(l)`, so
//! `[F_ext, xi] = [F, xi] + d_t xi`, and the certificate's (b') is exactly
//! the known-input condition on the view; the jets are observable and no
//! symmetry moves them. Hence the first integrals of `xi` on the view are
//! functions `m(S, jets)` with `dm . xi = 0`, the jets among them; the jets
//! stay coordinates of the derivation (hidden from the modes shown), and the
//! view's `L_F_ext m = d_S m . F + sum_l d_{u^(l)} m u^(l+1)` is the modes'
//! dynamics. The rank is the unknown-input rank plus the jets.
//!
//! The jets of order >= 1 get parseable internal names (`u_d1`, ...; a `.sys`
//! name holds no quote, so the decomposition checks read them); [`JetName`]
//! maps them back to `u'`, `u''` for what is shown.

use crate::rank::AnalysisError;
use crate::unknown_input_jets::jet_name;
use obsan_expr::{Id, RatFun, Var};
use obsan_model::NormalForm;

/// A jet coordinate of the view: its name there and as shown (`u3'`).
#[derive(Clone, Debug)]
pub struct JetName {
    pub internal: String,
    pub shown: String,
    /// A state of the view (else the new top-order input).
    pub state: bool,
}

/// The model with the jets made states ([`jet_view`]).
pub(crate) struct JetView {
    pub(crate) view: NormalForm,
    /// The symmetries over the view: zero on the jets.
    pub(crate) vectors: Vec<Vec<RatFun>>,
    pub(crate) names: Vec<JetName>,
    /// The jets' state indices in the view.
    pub(crate) rows: Vec<usize>,
}

/// `nf` (the model, unknown inputs apart) with the jets `jets` (`(input,
/// order)`, as `UnknownInputSymmetries::input_jets`) made states, and the
/// vectors over it (zero on the jets, the jets' symbols renamed).
pub(crate) fn jet_view(
    nf: &NormalForm,
    jets: &[(usize, usize)],
    vectors: &[Vec<RatFun>],
) -> Result<JetView, AnalysisError> {
    if nf.delay.is_some() {
        return Err(AnalysisError::Invalid(
            "modes that move with the known inputs are not derived with `delay`".into(),
        ));
    }
    let mut v = nf.clone();
    let zero = v.ctx.int(0);
    let mut names: Vec<JetName> = Vec::new();
    // The highest order each input is read at.
    let mut top: Vec<(usize, usize)> = Vec::new();
    for &(i, l) in jets {
        match top.iter_mut().find(|t| t.0 == i) {
            Some(t) => t.1 = t.1.max(l),
            None => top.push((i, l)),
        }
    }
    top.sort_unstable();
    // New states go before the clock, if any, else after the dynamic ones.
    let at0 = v.clock().unwrap_or(v.n_dynamic);
    let mut at = at0;
    let mut renames: Vec<(Var, Id)> = Vec::new();
    let mut new_inputs: Vec<(String, Var, usize)> = Vec::new();
    let mut outputs: Vec<(String, Id)> = Vec::new();
    for &(i, l_top) in &top {
        let u = nf.inputs[i].clone();
        let k = v.inputs.iter().position(|x| *x == u).ok_or_else(|| {
            AnalysisError::Invalid(format!("internal: the input {u} is not in the view"))
        })?;
        let f = v.fields.remove(k);
        let uvar = v.input_vars.remove(k);
        v.inputs.remove(k);
        // The drift gains f_u u (u is now a coordinate).
        let uid = v.ctx.symbol(&u).id;
        for (r, &fr) in f.iter().enumerate() {
            if v.ctx.is_zero(fr) {
                continue;
            }
            let t = v.ctx.mul(&[fr, uid]);
            let s = v.ctx.add(&[v.f0[r], t]);
            let c = v.ctx.canon(s);
            v.f0[r] = v.ctx.from_canonical(&c);
        }
        let first = at;
        for l in 0..=l_top {
            let (name, var) = if l == 0 {
                (u.clone(), uvar)
            } else {
                let name = fresh(&v, &format!("{u}_d{l}"));
                let s = v.ctx.symbol(&name);
                // The vectors name u^(l) by its quoted symbol, if they read it.
                if let Some(q) = v.ctx.lookup(&jet_name(&u, l)) {
                    renames.push((q.var, s.id));
                }
                (name, s.var)
            };
            insert_state(&mut v, at, &name, var, zero);
            outputs.push((name.clone(), v.ctx.symbol(&name).id));
            names.push(JetName {
                internal: name,
                shown: jet_name(&u, l),
                state: true,
            });
            at += 1;
        }
        // u^(l)' = u^(l+1): the next state, or the new input for the last.
        for l in 0..l_top {
            let next = v.ctx.symbol(&names[names.len() - l_top + l].internal).id;
            v.f0[first + l] = next;
        }
        let name = fresh(&v, &format!("{u}_d{}", l_top + 1));
        let var = v.ctx.symbol(&name).var;
        new_inputs.push((name.clone(), var, first + l_top));
        names.push(JetName {
            internal: name,
            shown: jet_name(&u, l_top + 1),
            state: false,
        });
    }
    let one = v.ctx.int(1);
    for (name, var, row) in new_inputs {
        let mut e = vec![zero; v.state.len()];
        e[row] = one;
        v.inputs.push(name);
        v.input_vars.push(var);
        v.fields.push(e);
    }
    for (name, id) in outputs {
        let name = if v.outputs.iter().any(|o| o.0 == name) {
            fresh(&v, &name)
        } else {
            name
        };
        v.outputs.push((name, id));
    }
    let rows: Vec<usize> = (at0..at).collect();
    let mut out = Vec::with_capacity(vectors.len());
    for w in vectors {
        let mut e: Vec<RatFun> = Vec::with_capacity(w.len() + rows.len());
        for c in w {
            e.push(if renames.is_empty() {
                c.clone()
            } else {
                let id = v.ctx.from_canonical(c);
                let id = v.ctx.substitute(id, &renames).map_err(|e| {
                    AnalysisError::Invalid(format!("a symmetry over the inputs' jets: {}", e.0))
                })?;
                v.ctx.canon(id)
            });
        }
        for &r in &rows {
            e.insert(r, RatFun::zero());
        }
        out.push(e);
    }
    Ok(JetView {
        view: v,
        vectors: out,
        names,
        rows,
    })
}

/// A state `name` (variable `var`, no drift, moved by no field) at index `at`.
fn insert_state(v: &mut NormalForm, at: usize, name: &str, var: Var, zero: Id) {
    v.state.insert(at, name.to_string());
    v.state_vars.insert(at, var);
    v.f0.insert(at, zero);
    for f in v.fields.iter_mut().chain(v.unknown_fields.iter_mut()) {
        f.insert(at, zero);
    }
    v.n_dynamic += 1;
}

/// `base`, or `base` with underscores appended, unused by the view.
fn fresh(v: &NormalForm, base: &str) -> String {
    let used = |s: &str| {
        v.state.iter().any(|x| x == s)
            || v.inputs.iter().any(|x| x == s)
            || v.unknown_inputs.iter().any(|x| x == s)
            || v.consts.iter().any(|c| c.0 == s)
            || v.outputs.iter().any(|o| o.0 == s)
            || v.ctx.lookup(s).is_some()
    };
    let mut name = base.to_string();
    while used(&name) {
        name.push('_');
    }
    name
}

/// `text` with every identifier that is a jet's internal name replaced by
/// its shown name (`u3_d1` -> `u3'`).
pub fn show_jets(text: &str, jets: &[JetName]) -> String {
    if jets.is_empty() {
        return text.to_string();
    }
    let mut out = String::with_capacity(text.len());
    let mut word = String::new();
    let flush = |word: &mut String, out: &mut String| {
        match jets.iter().find(|j| j.internal == *word) {
            Some(j) => out.push_str(&j.shown),
            None => out.push_str(word),
        }
        word.clear();
    };
    for ch in text.chars() {
        if ch.is_ascii_alphanumeric() || ch == '_' {
            word.push(ch);
        } else {
            flush(&mut word, &mut out);
            out.push(ch);
        }
    }
    flush(&mut word, &mut out);
    out
}
