//! Observable modes and the reduced system of a system with unknown inputs
//! (docs/engine.md, "Modes with unknown inputs").
//!
//! The modes are a basis of first integrals of the certified unknown-input
//! symmetries `xi_a` ([`unknown_input_symmetries`]): the derivation of the
//! known-input case (`derive/`, eq. 11 `dm . xi_a = 0`) run on the *view*, the
//! model with the unknown inputs read as inputs, against those vectors (in
//! primitive polynomial form, so a rotation scaled by a function is seen as
//! the rotation) and the unknown-input rank; its closure is judged without
//! the unknown inputs' columns, which are projected afterwards. Their dynamics `dm/dt = dm (f0 + sum f_i u_i + sum g_j w_j)`
//! are then written in the modes, the known inputs and, for each `w_j` some
//! mode's derivative needs:
//! - `w_j` itself when every `L_{g_j} m_k` is a function of the modes; it must
//!   be reconstructable (the rank route's verdict, with its order), else the
//!   reduction is refused;
//! - else (some `L_{g_j} m_k`, or some drift or known-input term of a mode's
//!   derivative, not a function of the modes) a combination: with `m_k` the
//!   first mode whose coefficient is not, `beta = L_{g_j} m_k`, the view's
//!   field becomes `g_j / beta` and each such drift or known field `f`
//!   becomes `f - (L_f m_k / beta) g_j`, the input `w~ = beta w_j + sum
//!   L_f m_k u_f`. With one unknown input every derivative is then a function
//!   of the modes: the certificate gives `[F, xi] = A xi + b g`, so `xi(L_F'
//!   m_l) = -b L_g m_l` for a projected field `F'`, and `L_F' m_k` constant
//!   forces `b = 0`. The combination is reconstructable when the matrix
//!   `C(m)` of the reduced inputs' coefficients has full column rank (the
//!   modes being observable, `dm/dt - F(m, u) = C(m) w~` is a function of the
//!   outputs' derivatives): checked by a non-zero minor at a random point
//!   (exact); else refused. Two or more such inputs are projected jointly
//!   (unknown_input_joint.rs); a form still not found leaves the reduced
//!   system reported not closed, never wrong.

use crate::decided::undecided_atoms_of;
use crate::derive::{derive_modes, reduce_in_modes, Derivation, DeriveOptions, ModeKind};
use crate::rank::{rank, AnalysisError, RankOptions, RankReport};
use crate::sym_report::{Certificate, SymmetryReport};
use crate::unknown_input::UnknownInputOptions;
use crate::unknown_input_feedthrough::unknown_input_symmetries;
use crate::unknown_input_jet_view::{jet_view, show_jets, JetName, JetView};
use crate::unknown_input_joint as joint;
use crate::unknown_input_symmetry::UnknownInputSymmetries;
use obsan_expr::{Fp, FpEchelon, FpField, Id, RatFun};
use obsan_model::NormalForm;

/// How an unknown input enters the reduced system.
#[derive(Clone, Debug)]
pub struct ReducedInput {
    /// Its name in the reduced system.
    pub name: String,
    /// The model's unknown input.
    pub input: String,
    /// `None`: the input itself; else the factor `beta(S)` of the combination
    /// `beta(S) w` (the derivative of `mode` along the input's field).
    pub factor: Option<String>,
    /// The first mode whose derivative needs it; for a combination an output
    /// reads directly (no mode sees the input), that output.
    pub mode: String,
    /// For a combination whose mode's drift or known-input terms are not
    /// functions of the modes: `alpha0 + sum alpha_i u_i`, added to
    /// `factor * w` (those terms of the mode's derivative, moved into the input).
    pub offset: Option<String>,
    /// The output-derivative order it is reconstructable from (the rank
    /// route's, for an input itself; 0 for a combination an output reads
    /// directly); `None` for a combination recovered from the modes' first
    /// derivatives.
    pub order: Option<usize>,
}

impl ReducedInput {
    /// A combination an output reads directly (`mode` names that output).
    pub fn output_held(&self) -> bool {
        self.factor.is_some() && self.order == Some(0)
    }
}

/// The modes and reduced system with unknown inputs.
#[derive(Clone, Debug)]
pub struct UnknownInputModes {
    /// The certified symmetries and the rank test.
    pub symmetries: UnknownInputSymmetries,
    /// The model with the unknown inputs as inputs (a combination's field
    /// divided by its factor, under the combination's name): the reduced
    /// system and its decomposition checks are over it.
    pub view: NormalForm,
    /// The view's rank report with the unknown-input rank.
    pub rank: RankReport,
    /// The certified vectors as the derivation and the checks read them.
    pub sym: SymmetryReport,
    /// `None` at full rank: the modes are the variables and the reduced
    /// system the model itself.
    pub derivation: Option<Derivation>,
    /// The unknown inputs (or combinations) the reduced system needs.
    pub inputs: Vec<ReducedInput>,
    /// The known inputs' jets the view made coordinates, when the symmetries
    /// move with the known inputs (unknown_input_jet_view.rs); empty otherwise.
    pub jets: Vec<JetName>,
}

impl UnknownInputModes {
    /// What is shown: the jets' internal names (`u3_d1`) replaced by their
    /// shown ones (`u3'`) in the modes' texts and forms, the reduced system
    /// and the combinations. The decomposition checks read the internal
    /// names: call this after them.
    pub fn show_input_jets(&mut self) {
        if self.jets.is_empty() {
            return;
        }
        let jets = &self.jets;
        let ctx = &mut self.view.ctx;
        let map: Vec<(obsan_expr::Var, Id)> = jets
            .iter()
            .filter_map(|j| {
                let v = ctx.lookup(&j.internal)?.var;
                Some((v, ctx.symbol(&j.shown).id))
            })
            .collect();
        let show = |t: &mut String| *t = show_jets(t, jets);
        if let Some(d) = &mut self.derivation {
            for m in &mut d.modes {
                show(&mut m.text);
                if let Ok(e) = ctx.substitute(m.expr, &map) {
                    m.expr = e;
                }
            }
            d.field_names.iter_mut().for_each(show);
            d.derivatives.iter_mut().flatten().flatten().for_each(show);
            d.outputs
                .iter_mut()
                .filter_map(|o| o.1.as_mut())
                .for_each(show);
        }
        for ri in &mut self.inputs {
            ri.factor
                .iter_mut()
                .chain(ri.offset.iter_mut())
                .for_each(show);
        }
    }

    /// `text` (a check of the view) with the jets as shown.
    pub fn show(&self, text: &str) -> String {
        show_jets(text, &self.jets)
    }

    /// The known inputs' derivatives the reduced system reads, as shown
    /// (`u3'`, `u3''`; the values `u3` are the model's inputs).
    pub fn input_derivatives(&self) -> Vec<String> {
        self.jets
            .iter()
            .filter(|j| j.shown.ends_with('\''))
            .map(|j| j.shown.clone())
            .collect()
    }
}

/// The view, its rank report and the symmetries as the known-input
/// derivation and checks read them (module docs), for callers that have no
/// names for the inputs' jets: symmetries that move with the known inputs
/// are refused here; `obsan modes` and `obsan verify` read them through
/// [`unknown_input_view_jets`].
pub fn unknown_input_view(
    nf: &mut NormalForm,
    opts: UnknownInputOptions,
) -> Result<
    (
        UnknownInputSymmetries,
        NormalForm,
        RankReport,
        SymmetryReport,
    ),
    AnalysisError,
> {
    let v = unknown_input_view_with_jets(nf, opts)?;
    if !v.jets.is_empty() {
        return Err(AnalysisError::Invalid(
            "the lost directions move with the known inputs (`obsan symmetries` prints them with the inputs' jets): this view has no names for their jets (`obsan modes` and `obsan verify` read them through the jet view)".into(),
        ));
    }
    Ok((v.symmetries, v.view, v.rank, v.sym))
}

/// [`unknown_input_view`] that also accepts symmetries moving with the
/// known inputs: the view then has their jets as states (named by the
/// returned [`JetName`]s), as `obsan verify` reads a decomposition that
/// declares the inputs' derivatives (decomp_jets.rs).
#[allow(clippy::type_complexity)]
pub fn unknown_input_view_jets(
    nf: &mut NormalForm,
    opts: UnknownInputOptions,
) -> Result<
    (
        UnknownInputSymmetries,
        NormalForm,
        RankReport,
        SymmetryReport,
        Vec<JetName>,
    ),
    AnalysisError,
> {
    let v = unknown_input_view_with_jets(nf, opts)?;
    Ok((v.symmetries, v.view, v.rank, v.sym, v.jets))
}

/// The view of [`unknown_input_view_with_jets`].
struct View {
    symmetries: UnknownInputSymmetries,
    view: NormalForm,
    rank: RankReport,
    sym: SymmetryReport,
    jets: Vec<JetName>,
}

/// [`unknown_input_view`], and when the symmetries move with the known
/// inputs the view with their jets made states (unknown_input_jet_view.rs),
/// whose names are returned (empty otherwise).
fn unknown_input_view_with_jets(
    nf: &mut NormalForm,
    opts: UnknownInputOptions,
) -> Result<View, AnalysisError> {
    let deadline = opts.deadline;
    let seed = opts.seed;
    let s = unknown_input_symmetries(nf, opts)?;
    let JetView {
        mut view,
        vectors,
        names: jets,
        rows,
    } = if s.input_dependent() {
        jet_view(nf, &s.input_jets, &s.vectors)?
    } else {
        JetView {
            view: nf.clone(),
            vectors: s.vectors.clone(),
            names: Vec::new(),
            rows: Vec::new(),
        }
    };
    view.inputs.append(&mut view.unknown_inputs);
    view.input_vars.append(&mut view.unknown_input_vars);
    view.fields.append(&mut view.unknown_fields);
    let mut rr = rank(
        &mut view,
        RankOptions {
            seed,
            deadline,
            progress: None,
        },
    )?;
    // The view treats the unknown inputs as known: its rank is an upper bound;
    // the modes are counted by the unknown-input rank (plus the jets, each
    // observable and moved by no symmetry).
    rr.rank = s.report.rank + rows.len();
    rr.observable = s.report.observable.iter().map(Option::is_some).collect();
    for &r in &rows {
        rr.observable.insert(r, true);
    }
    let undecided = undecided_atoms_of(nf, &[]);
    let sym = SymmetryReport {
        n: s.report.n + rows.len(),
        rank: s.report.rank + rows.len(),
        vectors: vectors.iter().map(|v| primitive(&view.ctx, v)).collect(),
        free: vec![],
        exact: true,
        rows_checked: s.identities,
        certificate: Certificate::Invariance(vec![]),
        blocks: 1,
        undecided,
    };
    Ok(View {
        symmetries: s,
        view,
        rank: rr,
        sym,
        jets,
    })
}

/// `v` times a function: polynomial entries without a common factor (the
/// yaw rotation divided by `vy`, as the symmetry search prints it, becomes
/// the rotation itself). The same direction, so the same first integrals
/// (eq. 11), in the affine form the cross-section reads (`derive/frame.rs`).
fn primitive(ctx: &obsan_expr::Ctx, v: &[RatFun]) -> Vec<RatFun> {
    let mut out = v.to_vec();
    // Each pass makes at least one more entry a polynomial.
    for _ in 0..v.len() {
        let Some(d) = out
            .iter()
            .map(RatFun::denominator)
            .find(|d| !d.is_constant())
            .cloned()
        else {
            break;
        };
        let m = RatFun::from_poly(d);
        out = out.iter().map(|c| ctx.rf_mul(c, &m)).collect();
    }
    let mut g: Option<obsan_expr::Poly> = None;
    for c in out.iter().filter(|c| !c.is_zero()) {
        g = Some(match g {
            None => c.numerator().clone(),
            Some(g) => obsan_expr::gcds::gcd(&g, c.numerator()),
        });
    }
    if let Some(inv) = g
        .filter(|g| !g.is_constant())
        .and_then(|g| ctx.rf_inv(&RatFun::from_poly(g)))
    {
        out = out.iter().map(|c| ctx.rf_mul(c, &inv)).collect();
    }
    out
}

/// The modes and reduced system of a model with unknown inputs (module
/// docs). `Err(Invalid)` names the mode and the input when the reduced
/// system would need an input that is not reconstructable.
pub fn unknown_input_modes(
    nf: &mut NormalForm,
    opts: UnknownInputOptions,
    derive: &DeriveOptions,
) -> Result<UnknownInputModes, AnalysisError> {
    let View {
        symmetries: s,
        mut view,
        rank: rr,
        sym,
        jets,
    } = unknown_input_view_with_jets(nf, opts)?;
    let (n, r) = (s.report.n, s.report.rank);
    // The view's known inputs (the jets' top orders in place of the inputs
    // made states), then the unknown ones.
    let known = view.inputs.len() - nf.unknown_inputs.len();
    if r == 0 {
        return Err(AnalysisError::Invalid(
            "nothing is observable with the unknown inputs (rank 0): there is no mode".into(),
        ));
    }
    if r == n {
        // The modes are the variables: w_j drives the first state its field moves.
        let mut inputs = Vec::new();
        for (j, w) in nf.unknown_inputs.iter().enumerate() {
            let Some(i) = (0..n).find(|&i| !view.ctx.is_zero(view.fields[known + j][i])) else {
                continue;
            };
            inputs.push(plain(&s, j, w, &nf.state[i])?);
        }
        return Ok(UnknownInputModes {
            symmetries: s,
            view,
            rank: rr,
            sym,
            derivation: None,
            inputs,
            jets,
        });
    }
    // The unknown inputs' columns are projected below: the derivation's
    // closure (and its exchange of modes) is judged without them.
    let derive = &DeriveOptions {
        projected: nf.unknown_inputs.clone(),
        ..derive.clone()
    };
    let mut d = derive_modes(&mut view, &rr, &sym, derive)?;
    d.jets = jets
        .iter()
        .filter(|j| j.state)
        .map(|j| j.internal.clone())
        .collect();
    d.jet_names = jets
        .iter()
        .map(|j| (j.internal.clone(), j.shown.clone()))
        .collect();
    if let Some(j) = d.jets.iter().find(|j| {
        !d.modes
            .iter()
            .any(|m| m.kind == ModeKind::Variable && &m.name == *j)
    }) {
        return Err(AnalysisError::Invalid(format!(
            "internal: the modes that move with the known inputs lost the input jet {j} as a coordinate: not derived"
        )));
    }
    let mut inputs = Vec::new();
    let mut rescaled = false;
    // The drift and known fields whose derivatives are not functions of the
    // modes: projected along the first combination input (module docs).
    let mut to_project: Vec<usize> = (0..d.field_names.len())
        .filter(|&i| !nf.unknown_inputs.contains(&d.field_names[i]))
        .filter(|&i| d.derivatives.iter().any(|row| row[i].is_none()))
        .collect();
    // Several inputs whose coefficients are not functions of the modes: the
    // joint projection (unknown_input_joint.rs); one at a time does not close.
    let needs: Vec<usize> = (0..nf.unknown_inputs.len())
        .filter(|&j| {
            let w = &nf.unknown_inputs[j];
            d.field_names
                .iter()
                .position(|f| f == w)
                .is_some_and(|idx| d.derivatives.iter().any(|row| row[idx].is_none()))
        })
        .collect();
    let joint = if needs.len() >= 2 {
        joint_inputs(nf, known, &mut view, &d, &needs, &to_project, derive.seed)?
    } else {
        None
    };
    if let Some(joint) = joint {
        inputs = joint;
        rescaled = true;
        to_project.clear();
    }
    for (j, w) in nf.unknown_inputs.iter().enumerate() {
        if rescaled && needs.contains(&j) {
            continue;
        }
        let Some(idx) = d.field_names.iter().position(|f| f == w) else {
            continue;
        };
        let col: Vec<Option<&str>> = d
            .derivatives
            .iter()
            .map(|row| row[idx].as_deref())
            .collect();
        let Some(first) = col.iter().position(|c| *c != Some("0")) else {
            continue; // no mode sees w_j
        };
        // Rows whose derivative along a field still to project is not found.
        let open = |k: usize| to_project.iter().any(|&i| d.derivatives[k][i].is_none());
        let k0 = match col.iter().position(Option::is_none) {
            None if to_project.is_empty() => {
                inputs.push(plain(&s, j, w, &d.modes[first].name)?);
                continue;
            }
            // With several unknown inputs, projecting along one that moves
            // none of the open rows leaves them open (the one-input argument
            // needs the other inputs' terms gone): take a mode it moves that
            // is open, else keep the fields for another input and enter w_j
            // itself when it is reconstructable (`x4' = w1 + x4` beside
            // `z1' = w2 + p u'`).
            None if nf.unknown_inputs.len() >= 2 && !open(first) => {
                match (0..col.len()).find(|&k| col[k] != Some("0") && open(k)) {
                    Some(k) => k,
                    None if s.report.reconstructable[j].is_some() => {
                        inputs.push(plain(&s, j, w, &d.modes[first].name)?);
                        continue;
                    }
                    None => first,
                }
            }
            None => first,
            Some(k0) => k0,
        };
        let mode = d.modes[k0].clone();
        let g = view.fields[known + j].clone();
        let beta = crate::derive::lie_along(&mut view, mode.expr, &g);
        let beta_c = view.ctx.canon(beta);
        let beta = view.ctx.from_canonical(&beta_c);
        let moved = project(
            &mut view,
            &d,
            std::mem::take(&mut to_project),
            mode.expr,
            &g,
            beta,
        );
        view.fields[known + j] = g.iter().map(|&c| view.ctx.div(c, beta)).collect();
        let name = fresh_name(&view, &format!("{w}_{}", mode.name));
        // An output reading w_j (feedthrough, 2dof's y2 = F2/m2 + ...) reads
        // the combination.
        rename_in_outputs(
            &mut view,
            known + j,
            &name,
            moved.as_ref().map(|m| m.1),
            beta,
        )?;
        let offset = moved.map(|m| m.0);
        inputs.push(ReducedInput {
            name,
            input: w.clone(),
            factor: Some(view.ctx.ratfun_text_factored(&beta_c)),
            offset,
            mode: mode.name.clone(),
            order: None,
        });
        rescaled = true;
    }
    rescaled |= output_held(nf, known, &mut view, &mut inputs)?;
    if rescaled {
        d = reduce_in_modes(&mut view, &sym, &d, derive)?;
        independent_inputs(&mut view, &d, &inputs, derive.seed)?;
    }
    Ok(UnknownInputModes {
        symmetries: s,
        view,
        rank: rr,
        sym,
        derivation: Some(d),
        inputs,
        jets,
    })
}

/// An unknown input no mode's derivative needs but an output reads (a
/// feedthrough, 2dof_2ui's `y2 = F2/m2 + ...` with F2 moving only the
/// unobservable `dx2`): no mode sees it, so that output is not a function of
/// the modes and known inputs, and it becomes the combination itself,
/// `w~ = h = beta w + offset` with `beta = dh/dw`, measured (order 0). Its
/// field is divided by `beta` (no mode's derivative changes: `L_g m = 0`),
/// and the outputs read `w = (w~ - offset)/beta`. Returns whether any was.
fn output_held(
    nf: &NormalForm,
    known: usize,
    view: &mut NormalForm,
    inputs: &mut Vec<ReducedInput>,
) -> Result<bool, AnalysisError> {
    let mut any = false;
    for (j, w) in nf.unknown_inputs.iter().enumerate() {
        if inputs.iter().any(|ri| &ri.input == w) {
            continue;
        }
        let slot = known + j;
        let wv = view.input_vars[slot];
        let Some(k) = (0..view.outputs.len())
            .find(|&k| view.ctx.canon(view.outputs[k].1).vars().contains(&wv))
        else {
            continue;
        };
        let h = view.outputs[k].1;
        let beta = view.ctx.diff(h, wv);
        let beta_c = view.ctx.canon(beta);
        if beta_c.is_zero() || beta_c.vars().contains(&wv) {
            continue; // not affine in w: left for the reduction to report
        }
        let wid = view.ctx.symbol(w).id;
        let bw = view.ctx.mul(&[beta, wid]);
        let offset = view.ctx.sub(h, bw);
        let off_c = view.ctx.canon(offset);
        let oname = view.outputs[k].0.clone();
        let name = fresh_name(view, &format!("{w}_{oname}"));
        let g = view.fields[slot].clone();
        view.fields[slot] = g.iter().map(|&c| view.ctx.div(c, beta)).collect();
        rename_in_outputs(view, slot, &name, Some(offset), beta)?;
        inputs.push(ReducedInput {
            name,
            input: w.clone(),
            factor: Some(view.ctx.ratfun_text_factored(&beta_c)),
            offset: (!off_c.is_zero()).then(|| view.ctx.ratfun_text_factored(&off_c)),
            mode: oname,
            order: Some(0),
        });
        any = true;
    }
    Ok(any)
}

/// The view's input `slot`, `w`, renamed to the combination
/// `name = beta w + offset` (offset `None`: 0), and every output that reads
/// `w` rewritten with `w = (name - offset)/beta`.
fn rename_in_outputs(
    view: &mut NormalForm,
    slot: usize,
    name: &str,
    offset: Option<Id>,
    beta: Id,
) -> Result<(), AnalysisError> {
    let old = view.input_vars[slot];
    view.inputs[slot] = name.to_string();
    view.input_vars[slot] = view.ctx.symbol(name).var;
    let wt = view.ctx.symbol(name).id;
    let num = match offset {
        Some(m) => view.ctx.sub(wt, m),
        None => wt,
    };
    let back = view.ctx.div(num, beta);
    for k in 0..view.outputs.len() {
        let h = view.outputs[k].1;
        view.outputs[k].1 = view.ctx.substitute(h, &[(old, back)]).map_err(|e| {
            AnalysisError::Invalid(format!("an output in the combination {name}: {}", e.0))
        })?;
    }
    Ok(())
}

/// The joint projection along the inputs `needs` (module docs of
/// unknown_input_joint.rs), each a combination `w~_a = B_aa w_a + sum_b B_ab
/// w_b + moved terms`; `None` when the modes cannot be paired with them.
fn joint_inputs(
    nf: &NormalForm,
    known: usize,
    view: &mut NormalForm,
    d: &Derivation,
    needs: &[usize],
    to_project: &[usize],
    seed: u64,
) -> Result<Option<Vec<ReducedInput>>, AnalysisError> {
    let slots: Vec<usize> = needs.iter().map(|j| known + j).collect();
    let Some(k) = joint::pair_modes(view, d, &slots, seed) else {
        return Ok(None);
    };
    let names: Vec<String> = to_project
        .iter()
        .map(|&i| d.field_names[i].clone())
        .collect();
    let parts = joint::project(view, d, &slots, &k, &names);
    let mut out = Vec::new();
    for (a, p) in parts.iter().enumerate() {
        let j = needs[a];
        let w = nf.unknown_inputs[j].clone();
        let mode = d.modes[p.mode].name.clone();
        let fc = view.ctx.canon(p.row[a]);
        let mut terms = p.moved.clone();
        for (b, &x) in p.row.iter().enumerate() {
            if b != a {
                let wb = view.ctx.symbol(&nf.unknown_inputs[needs[b]]).id;
                terms.push(view.ctx.mul(&[x, wb]));
            }
        }
        let offset = (!terms.is_empty())
            .then(|| {
                let sum = view.ctx.add(&terms);
                view.ctx.canon(sum)
            })
            .filter(|c| !c.is_zero())
            .map(|c| view.ctx.ratfun_text_factored(&c));
        let name = fresh_name(view, &format!("{w}_{mode}"));
        view.inputs[slots[a]] = name.clone();
        view.input_vars[slots[a]] = view.ctx.symbol(&name).var;
        out.push(ReducedInput {
            name,
            input: w,
            factor: Some(view.ctx.ratfun_text_factored(&fc)),
            offset,
            mode,
            order: None,
        });
    }
    Ok(Some(out))
}

/// `w_j` itself in the reduced system: reconstructable by the rank route, or refused.
fn plain(
    s: &UnknownInputSymmetries,
    j: usize,
    w: &str,
    mode: &str,
) -> Result<ReducedInput, AnalysisError> {
    match s.report.reconstructable[j] {
        Some(order) => Ok(ReducedInput {
            name: w.to_string(),
            input: w.to_string(),
            factor: None,
            offset: None,
            mode: mode.to_string(),
            order: Some(order),
        }),
        None => Err(AnalysisError::Invalid(format!(
            "the derivative of mode {mode} needs the unknown input {w}, which is not reconstructable (obsan rank: no output derivative determines it): no reduced system driven by reconstructable inputs exists in these modes"
        ))),
    }
}

/// The fields `cols` (drift or known inputs, by the derivation's column)
/// projected along `g` onto the kernel of `dm`: `f - (L_f m / beta) g`, `beta
/// = L_g m`. Returns the terms moved into the combination input,
/// `sum L_f m u_f` (`u_f = 1` for the drift), as text and as an expression;
/// `None` when none.
fn project(
    view: &mut NormalForm,
    d: &Derivation,
    cols: Vec<usize>,
    m: Id,
    g: &[Id],
    beta: Id,
) -> Option<(String, Id)> {
    let mut terms = Vec::new();
    for i in cols {
        let name = d.field_names[i].clone();
        let f = if name == "f0" {
            view.f0.clone()
        } else {
            let k = view.inputs.iter().position(|x| *x == name)?;
            view.fields[k].clone()
        };
        let alpha = crate::derive::lie_along(view, m, &f);
        let ratio = view.ctx.div(alpha, beta);
        let new: Vec<Id> = f
            .iter()
            .zip(g)
            .map(|(&fc, &gc)| {
                let t = view.ctx.mul(&[ratio, gc]);
                let t = view.ctx.neg(t);
                view.ctx.add(&[fc, t])
            })
            .collect();
        if name == "f0" {
            view.f0 = new;
            terms.push(alpha);
        } else {
            let k = view.inputs.iter().position(|x| *x == name)?;
            view.fields[k] = new;
            let u = view.ctx.symbol(&name).id;
            terms.push(view.ctx.mul(&[alpha, u]));
        }
    }
    if terms.is_empty() {
        return None;
    }
    let sum = view.ctx.add(&terms);
    let c = view.ctx.canon(sum);
    Some((view.ctx.ratfun_text_factored(&c), sum))
}

/// A name for a combination that the view does not use yet.
fn fresh_name(view: &NormalForm, base: &str) -> String {
    let used = |s: &str| {
        view.state.iter().any(|x| x == s)
            || view.inputs.iter().any(|x| x == s)
            || view.consts.iter().any(|c| c.0 == s)
            || view.outputs.iter().any(|o| o.0 == s)
    };
    let mut name = base.to_string();
    let mut k = 1;
    while used(&name) {
        k += 1;
        name = format!("{base}_{k}");
    }
    name
}

/// The reduced inputs' coefficient matrix `C(m)` (rows: modes, columns: the
/// reduced unknown inputs) has full column rank: each column raising the rank
/// at a random point is a non-zero minor (exact); a column that does not
/// raise it at two points is refused as not reconstructable (a combination
/// of the others could hide it).
fn independent_inputs(
    view: &mut NormalForm,
    d: &Derivation,
    inputs: &[ReducedInput],
    seed: u64,
) -> Result<(), AnalysisError> {
    let mut cols: Vec<(usize, &ReducedInput)> = Vec::new();
    // An output-held combination (`output_held`) drives no mode: it is
    // measured, not recovered from the modes' derivatives.
    for ri in inputs.iter().filter(|ri| !ri.output_held()) {
        if let Some(i) = view.inputs.iter().position(|x| *x == ri.name) {
            cols.push((i, ri));
        }
    }
    if cols.len() < 2 {
        return Ok(()); // one column, non-zero by construction
    }
    let mut roots: Vec<Id> = Vec::new();
    for &(i, _) in &cols {
        let f = view.fields[i].clone();
        for m in &d.modes {
            roots.push(crate::derive::lie_along(view, m.expr, &f));
        }
    }
    let r = d.modes.len();
    let mut ok = vec![false; cols.len()];
    for v in joint::values_at_random_points(view, &roots, seed ^ 0x7569_6d6f_6465_7321, 2) {
        // Columns one by one: does each raise the rank of those before it?
        // (Column rank is row rank: each column is inserted as a row.)
        let mut taken = FpEchelon::default();
        for (c, chunk) in v.chunks(r).enumerate() {
            if taken.insert(chunk.to_vec()) {
                ok[c] = true;
            }
        }
    }
    if let Some(c) = ok.iter().position(|o| !o) {
        let ri = cols[c].1;
        return Err(AnalysisError::Invalid(format!(
            "the derivative of mode {} needs the unknown input {} ({}), which is not reconstructable: its coefficients in the reduced dynamics are a combination of the other unknown inputs' (no full column rank at two random points)",
            ri.mode,
            ri.input,
            ri.name
        )));
    }
    Ok(())
}

/// Which unknown inputs drive a reduced system whose modes are the first
/// integrals of `vectors`: `g_j` outside their span (then `dm(g_j) != 0` for
/// some mode). A rank raised at a random point is exact; not raised at two
/// points is a screen (Schwartz-Zippel).
pub fn inputs_driving_modes(nf: &mut NormalForm, vectors: &[Vec<RatFun>], seed: u64) -> Vec<bool> {
    let n = nf.state.len();
    let mut roots: Vec<Id> = Vec::new();
    for v in vectors {
        for c in v {
            roots.push(nf.ctx.from_canonical(c));
        }
    }
    for g in nf.unknown_fields.clone() {
        roots.extend(g);
    }
    let k = vectors.len();
    let mut out = vec![false; nf.unknown_fields.len()];
    for v in joint::values_at_random_points(nf, &roots, seed ^ 0x6472_6976_6573, 2) {
        let cols: Vec<Vec<Fp>> = v.chunks(n).map(|c| c.to_vec()).collect();
        // The symmetries' span, then whether each g_j raises its rank.
        let span = FpEchelon::of_rows(FpField, cols[..k].to_vec());
        for (j, o) in out.iter_mut().enumerate() {
            *o |= !span.contains(cols[k + j].clone());
        }
    }
    out
}
