//! Observable modes and the reduced system, derived (Martinelli 2011, eqs.
//! 9–11; the paper's hand derivations 21 → 22 and 23 → 24).
//!
//! Modes are searched from the simplest kind up, each candidate accepted only
//! when its gradient raises the rank at a random point (a non-zero minor:
//! exact) and it satisfies the PDE (11) for every symmetry *exactly*
//! ([`check_modes`]):
//! 1. single variables every symmetry leaves alone, as themselves;
//! 2. integer combinations of angle variables (translations, e.g. thetaR - phiR);
//! 3. polynomial and rational invariants `P/Q` by an ansatz: for a fixed
//!    denominator `Q` (1, then the factors the outputs and first Lie
//!    derivatives show) the PDE `Q w(P) - P w(Q) = 0` is linear in the
//!    coefficients of `P`; solved in F_p at random points, coefficients lifted
//!    to Q by rational reconstruction (then checked exactly) — over two sets
//!    of blocks ([`blocks`]): the variables (with cos/sin of the angles), and
//!    the moving variables with the coefficients the fields show, where eq.
//!    (16)'s invariants are of degree 3 (shortest denominators first);
//! 4. the outputs themselves (an `atan2` output is the angle-valued mode the
//!    paper calls L up to the observable A);
//! 5. the basis Lie derivatives of the rank test.
//!
//! The reduced dynamics `L_f g_k` and each output are then sought as `P(z)/Q(z)`
//! in the modes (and cos/sin of the angle-valued ones) by the same linear
//! ansatz, lifted, and proven by exact substitution in canonical form
//! ([`reduced`]).
//!
//! Layout: `crate::fp_linalg` (F_p null spaces, rational reconstruction, monomials),
//! `ansatz` (the invariant ansatz and its F_p screens), `blocks` (blocks read
//! off the fields), `reduced` (the reduced system, its files and its proof),
//! `exchange` (a mode exchanged for an output, derivative or generator the
//! reduced system needs when it does not close).

mod ansatz;
mod blocks;
mod exchange;
mod files;
mod frame;
mod monomial;

mod free_section;
mod reduced;
mod section;

use crate::fp_linalg::{mono_deriv, mono_value, monomials, rat_recon};
use ansatz::{build_poly, invariant_ansatz, lie, point_for, poly_text, screen_mode, Indep};
use blocks::{coefficient_blocks, push_state_blocks};
use reduced::in_modes;
pub use reduced::{lie_along, reduce_in_modes, verify_derivation};

use crate::decomp::{verify_decomposition_with, Check, Decomposition};
use crate::modes::{check_modes, ModeReport};
use crate::rank::{AnalysisError, RankReport};
use crate::reach::check_symmetry_memory;
use crate::sym_report::SymmetryReport;
use obsan_expr::{evaluate::FpPoint, Fp, Id, Int, Mono, Poly, RatFun, SplitMix, Q};
use obsan_model::NormalForm;
use std::time::Instant;

/// Largest linear system of an ansatz (unknown coefficients).
pub(super) const MAX_UNKNOWNS: usize = 500;

/// Budgets of the search.
#[derive(Clone, Debug)]
pub struct DeriveOptions {
    pub seed: u64,
    pub deadline: Option<Instant>,
    /// Highest total degree of the numerator `P` of an invariant ansatz.
    pub max_mode_degree: usize,
    /// Highest total degree of `P` and `Q` when writing a derivative in the modes.
    pub max_closure_degree: usize,
    /// Inputs whose fields the caller projects afterwards (the unknown
    /// inputs of a view): their columns count neither for the closure that
    /// decides an exchange of modes nor as its candidates.
    pub projected: Vec<String>,
}

impl Default for DeriveOptions {
    fn default() -> Self {
        DeriveOptions {
            seed: 1,
            deadline: None,
            max_mode_degree: 3,
            max_closure_degree: 6,
            projected: Vec::new(),
        }
    }
}

/// How a mode was found (and so how simple it is).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ModeKind {
    Variable,
    Translation,
    Polynomial,
    Rational,
    Output,
    LieDerivative,
    /// A coordinate of a cross-section of the symmetry group (a moving frame).
    CrossSection,
}

impl ModeKind {
    pub fn word(self) -> &'static str {
        match self {
            ModeKind::Variable => "variable",
            ModeKind::Translation => "angle difference",
            ModeKind::Polynomial => "polynomial",
            ModeKind::Rational => "rational",
            ModeKind::Output => "output",
            ModeKind::LieDerivative => "Lie derivative",
            ModeKind::CrossSection => "cross-section",
        }
    }
}

/// One derived observable mode.
#[derive(Clone, Debug)]
pub struct DerivedMode {
    pub name: String,
    pub expr: Id,
    /// The formula in obsan's plain-text syntax (parses back).
    pub text: String,
    pub kind: ModeKind,
    /// An angle (defined modulo 2 pi): the reduced system uses its cos and sin.
    pub angle: bool,
    /// Where the formula holds and which branch it takes.
    pub domain: String,
}

/// The modes and the reduced system.
#[derive(Clone, Debug)]
pub struct Derivation {
    pub n: usize,
    pub rank: usize,
    pub modes: Vec<DerivedMode>,
    /// The exact PDE (11), independence and completeness verdicts.
    pub mode_report: ModeReport,
    /// `f0` (when the drift is not zero), then the inputs.
    pub field_names: Vec<String>,
    /// `derivatives[k][i]`: `L_{f_i} g_k` in the modes, proven; `None` if not found.
    pub derivatives: Vec<Vec<Option<String>>>,
    /// Each output in the modes, proven; `None` if not found.
    pub outputs: Vec<(String, Option<String>)>,
    /// Generic constants of the system the reduced system keeps.
    pub consts: Vec<String>,
    /// The search for the reduced system stopped at the deadline.
    pub reduced_timed_out: bool,
    /// States of the view that are known inputs' jets (modes that move with
    /// the inputs, unknown_input_jet_view.rs): modes and outputs of the
    /// derivation and its checks, hidden from what is shown like the clock.
    pub jets: Vec<String>,
    /// Every jet of the view (its states and the top-order inputs) as
    /// `(name in the view, as shown)`: `("u3_d1", "u3'")`. The files declare
    /// the derivatives by these names (`derivative u3_d1 = u3'`).
    pub jet_names: Vec<(String, String)>,
}

pub(super) fn check_deadline(
    opts: &DeriveOptions,
    stage: &str,
    found: usize,
) -> Result<(), AnalysisError> {
    if obsan_expr::cancel_requested() {
        return Err(AnalysisError::Cancelled);
    }
    match opts.deadline {
        Some(d) if Instant::now() > d => Err(AnalysisError::Timeout(format!(
            "{found} mode(s) found, stopped during {stage}"
        ))),
        _ => Ok(()),
    }
}

/// Builds the modes and the reduced system for any symmetry report: the free
/// directions of `sym` become unit vectors first (the derivation reads every
/// symmetry as a vector), within the memory budget. `obsan modes` derives
/// on the reached subsystem instead, where there are none.
pub fn derive_modes(
    nf: &mut NormalForm,
    report: &RankReport,
    sym: &SymmetryReport,
    opts: &DeriveOptions,
) -> Result<Derivation, AnalysisError> {
    if sym.free.is_empty() {
        return derive_dense(nf, report, sym, opts);
    }
    check_symmetry_memory(sym.n, sym.count())?;
    let mut dense = sym.clone();
    for &j in &sym.free {
        let mut e = vec![RatFun::zero(); sym.n];
        e[j] = RatFun::one();
        dense.vectors.push(e);
    }
    dense.free.clear();
    derive_dense(nf, report, &dense, opts)
}

/// The derivation over a report whose symmetries are all vectors: the
/// steps of the module's documentation, in order, each adding modes until
/// the rank is reached.
fn derive_dense(
    nf: &mut NormalForm,
    report: &RankReport,
    sym: &SymmetryReport,
    opts: &DeriveOptions,
) -> Result<Derivation, AnalysisError> {
    if nf.delay.is_some() {
        return Err(AnalysisError::Invalid(
            "obsan modes does not handle delayed inputs yet".into(),
        ));
    }
    let rank = report.rank;
    let n = report.n;
    let lay = Layout::new(nf);
    // w components as expressions.
    let w_ids: Vec<Vec<Id>> = sym
        .vectors
        .iter()
        .map(|w| w.iter().map(|c| nf.ctx.from_canonical(c)).collect())
        .collect();
    let mut found = Found::new(nf, opts);
    let search = Search {
        w_ids: &w_ids,
        rank,
        opts,
    };

    fixed_variables(nf, sym, &lay, rank, &mut found)?;
    check_deadline(opts, "the variables", found.modes.len())?;
    angle_differences(nf, &lay, &search, &mut found)?;
    check_deadline(opts, "the angle differences", found.modes.len())?;
    // 2a. A cross-section of the group when it has a rotation: a generating
    // set of the rational invariants, so the reduced system closes.
    frame::frame_invariants(
        nf,
        &search,
        &lay.angle,
        &mut found.modes,
        &mut found.indep,
        &mut found.fresh,
    )?;
    // 2b. Monomial invariants of scalings (k1 k2 x2, gamma x2 / x3).
    monomial::monomial_invariants(
        nf,
        &search,
        &lay.fields,
        &mut found.modes,
        &mut found.indep,
        &mut found.fresh,
        &mut found.rng,
    )?;
    let consts = rational_invariants(nf, &lay, &search, &mut found)?;
    // 3b. Products with the sums as written that the symmetries scale.
    monomial::written_sum_invariants(
        nf,
        &search,
        &lay.fields,
        &mut found.modes,
        &mut found.indep,
        &mut found.fresh,
        &mut found.rng,
    )?;
    outputs_and_lie_derivatives(nf, report, &search, &mut found)?;

    let space = ModeSpace {
        fields: &lay.fields,
        consts: &consts,
        used_vars: &lay.used_vars,
        w_ids: &w_ids,
    };
    let Found {
        mut modes, mut rng, ..
    } = found;
    let mut red = reduce(nf, &space, &modes, &mut rng, opts)?;
    // Modes whose dynamics have no rational form (x^2 c and y^2 c, where the
    // fields need x y c = sqrt(z1 z2)): exchange one for a needed function.
    let open = |red: &Reduced| !red.closed_except(&lay.fnames, &opts.projected);
    if open(&red) && !red.timed_out && modes.len() == rank {
        let gens = generators(nf, report);
        let cands = exchange::needed_functions(nf, &gens, &space, &modes, &red, &lay.fnames, opts);
        if let Some((m2, r2)) =
            exchange::exchange(nf, &space, &modes, &cands, &mut rng, opts, &open)?
        {
            modes = m2;
            red = r2;
        }
    }
    let ids: Vec<Id> = modes.iter().map(|m| m.expr).collect();
    let mode_report = check_modes(nf, sym, &ids, opts.seed)?;
    let Reduced {
        derivatives,
        outputs,
        timed_out,
        ..
    } = red;
    Ok(Derivation {
        n,
        rank,
        modes,
        mode_report,
        field_names: lay.fnames,
        derivatives,
        outputs,
        consts,
        reduced_timed_out: timed_out,
        jets: Vec::new(),
        jet_names: Vec::new(),
    })
}

/// How the state variables enter the system: which are angles (through cos
/// and sin), and the fields the search differentiates along.
struct Layout {
    vars: Vec<u32>,
    names: Vec<String>,
    fnames: Vec<String>,
    fields: Vec<Vec<Id>>,
    /// The canonical-form variables the fields and outputs use.
    used_vars: Vec<u32>,
    angle: Vec<bool>,
    /// `(cos x, sin x)` of each angle variable.
    trig: Vec<Option<(Id, Id)>>,
}

impl Layout {
    fn new(nf: &mut NormalForm) -> Layout {
        let n = nf.state.len();
        let vars = nf.state_vars.clone();
        let names = nf.state.clone();
        let (fnames, fields) = crate::fields::field_names(nf);
        let mut used_vars: Vec<u32> = Vec::new();
        let mut all: Vec<Id> = fields.iter().flatten().copied().collect();
        all.extend(nf.outputs.iter().map(|o| o.1));
        for &e in &all {
            let c = nf.ctx.canon(e);
            used_vars.extend(c.vars());
        }
        let mut angle = vec![false; n];
        let mut trig: Vec<Option<(Id, Id)>> = vec![None; n];
        for i in 0..n {
            let Ok(c) = nf.parse_expr(&format!("cos({})", names[i]), false) else {
                continue;
            };
            let Ok(s) = nf.parse_expr(&format!("sin({})", names[i]), false) else {
                continue;
            };
            let cv = nf.ctx.canon(c).vars();
            if cv.iter().any(|v| used_vars.contains(v)) {
                angle[i] = true;
                trig[i] = Some((c, s));
            }
        }
        Layout {
            vars,
            names,
            fnames,
            fields,
            used_vars,
            angle,
            trig,
        }
    }
}

/// The modes found so far and the state every step shares.
struct Found {
    modes: Vec<DerivedMode>,
    indep: Indep,
    fresh: Names,
    rng: SplitMix,
}

impl Found {
    fn new(nf: &NormalForm, opts: &DeriveOptions) -> Found {
        let mut used: Vec<String> = nf.state.clone();
        used.extend(nf.consts.iter().map(|c| c.0.clone()));
        used.extend(nf.inputs.iter().cloned());
        used.extend(nf.outputs.iter().map(|o| o.0.clone()));
        Found {
            modes: Vec::new(),
            indep: Indep {
                grads: Vec::new(),
                seed: opts.seed,
            },
            fresh: Names { used, count: 0 },
            rng: SplitMix(opts.seed ^ 0x6d6f_6465_7321),
        }
    }
}

/// Step 1: variables every symmetry leaves alone, as themselves.
fn fixed_variables(
    nf: &mut NormalForm,
    sym: &SymmetryReport,
    lay: &Layout,
    rank: usize,
    found: &mut Found,
) -> Result<(), AnalysisError> {
    for i in 0..lay.names.len() {
        if found.modes.len() == rank {
            break;
        }
        if sym.vectors.iter().all(|w| w[i].is_zero()) {
            let g = nf.ctx.symbol(&lay.names[i]).id;
            if found.indep.raises_rank(nf, g)? {
                found.modes.push(DerivedMode {
                    name: lay.names[i].clone(),
                    expr: g,
                    text: lay.names[i].clone(),
                    kind: ModeKind::Variable,
                    angle: lay.angle[i],
                    domain: "everywhere".into(),
                });
            }
        }
    }
    Ok(())
}

/// Step 2: integer combinations of angles that every symmetry leaves alone:
/// the integer null vectors of the symmetries' angle components at random points.
fn angle_differences(
    nf: &mut NormalForm,
    lay: &Layout,
    s: &Search,
    found: &mut Found,
) -> Result<(), AnalysisError> {
    let angles: Vec<usize> = (0..lay.names.len()).filter(|&i| lay.angle[i]).collect();
    if found.modes.len() >= s.rank || angles.len() < 2 || s.w_ids.is_empty() {
        return Ok(());
    }
    let roots: Vec<Id> = s
        .w_ids
        .iter()
        .flat_map(|w| angles.iter().map(|&i| w[i]))
        .collect();
    let mut rows = Vec::new();
    for _ in 0..(angles.len() + 2) {
        let (_, v) = point_for(nf, &mut found.rng, &roots)?;
        rows.extend(v.chunks(angles.len()).map(|c| c.to_vec()));
    }
    for v in Fp::null_space(rows, angles.len()) {
        if found.modes.len() == s.rank {
            break;
        }
        let Some(qs) = v.iter().map(|&x| rat_recon(x)).collect::<Option<Vec<Q>>>() else {
            continue;
        };
        if !qs.iter().all(|q| q.is_integer()) || qs.iter().all(|q| q.is_zero()) {
            continue;
        }
        // Leading coefficient positive, for readability.
        let lead_neg = qs
            .iter()
            .rev()
            .find(|q| !q.is_zero())
            .is_some_and(|q| q.is_negative());
        let qs: Vec<Q> = if lead_neg {
            qs.iter().map(|q| q.neg()).collect()
        } else {
            qs
        };
        let blocks: Vec<Id> = angles.iter().map(|&i| vars_id(nf, &lay.names[i])).collect();
        let monos: Vec<Vec<u32>> = (0..angles.len())
            .map(|k| (0..angles.len()).map(|l| u32::from(k == l)).collect())
            .collect();
        let order: Vec<usize> = (0..angles.len()).rev().collect();
        let qs_o: Vec<Q> = order.iter().map(|&k| qs[k].clone()).collect();
        let monos_o: Vec<Vec<u32>> = order.iter().map(|&k| monos[k].clone()).collect();
        let bnames: Vec<String> = angles.iter().map(|&i| lay.names[i].clone()).collect();
        let g = build_poly(nf, &qs_o, &monos_o, &blocks);
        let text = poly_text(&qs_o, &monos_o, &bnames);
        if found.indep.raises_rank(nf, g)? && screen_mode(nf, s.w_ids, g, s.opts.seed)? {
            found.modes.push(DerivedMode {
                name: found.fresh.next(),
                expr: g,
                text,
                kind: ModeKind::Translation,
                angle: true,
                domain: "everywhere (an angle, modulo 2 pi)".into(),
            });
        }
    }
    Ok(())
}

/// Step 3: polynomial and rational invariants `P/Q` by the linear ansatz, over
/// the variable blocks and the coefficient blocks. Returns the generic
/// constants the blocks use (the reduced system keeps them).
fn rational_invariants(
    nf: &mut NormalForm,
    lay: &Layout,
    s: &Search,
    found: &mut Found,
) -> Result<Vec<String>, AnalysisError> {
    let mut blocks: Vec<Id> = Vec::new();
    let mut bnames: Vec<String> = Vec::new();
    for i in 0..lay.names.len() {
        let sym_var = nf.ctx.symbol(&lay.names[i]).id;
        let as_symbol = !lay.angle[i] || lay.used_vars.contains(&lay.vars[i]);
        push_state_blocks(
            &mut blocks,
            &mut bnames,
            &lay.names[i],
            sym_var,
            as_symbol,
            lay.trig[i],
        );
    }
    let mut consts = Vec::new();
    for (name, val) in nf.consts.clone() {
        if val.is_none() {
            if let Some(c) = nf.ctx.lookup(&name) {
                blocks.push(c.id);
                bnames.push(name.clone());
                consts.push(name);
            }
        }
    }
    let dens = denominators(nf, lay, s, found.modes.len());
    let orig_const: Vec<bool> = bnames.iter().map(|b| consts.contains(b)).collect();
    let coef = coefficient_blocks(
        nf,
        &lay.fields,
        &lay.names,
        &lay.angle,
        &lay.trig,
        &lay.used_vars,
        &lay.vars,
    );
    let orig = (blocks, bnames, orig_const);
    // The coefficient blocks first when they are fewer: the same invariants
    // at a lower degree (eq. 16: eta (1 + q delta) cos(phi) is one block).
    let tries: Vec<(Vec<Id>, Vec<String>, Vec<bool>)> = match coef {
        Some(c) if c.0.len() < orig.0.len() => vec![c, orig],
        Some(c) => vec![orig, c],
        None => vec![orig],
    };
    if s.w_ids.is_empty() {
        return Ok(consts);
    }
    for (blocks, bnames, is_const) in &tries {
        if found.modes.len() >= s.rank {
            break;
        }
        invariant_ansatz(
            nf,
            s,
            (blocks, bnames, is_const),
            &dens,
            &mut found.modes,
            &mut found.indep,
            &mut found.fresh,
            &mut found.rng,
        )?;
    }
    Ok(consts)
}

/// Denominator candidates of the ansatz: 1, then the factors of the outputs
/// and of the first-order Lie derivatives as they come out of the canonical
/// form, shortest first: simpler modes, and a reduced system whose exact
/// proof stays small (eq. 39's A_v, V share mu^2 + 2 mu cos(gamma) + 1).
fn denominators(nf: &mut NormalForm, lay: &Layout, s: &Search, found: usize) -> Vec<Id> {
    let mut dens: Vec<(usize, Id)> = vec![(0, nf.ctx.one())];
    if found < s.rank && !s.w_ids.is_empty() {
        let mut seen: Vec<Poly> = Vec::new();
        let mut srcs: Vec<Id> = nf.outputs.iter().map(|o| o.1).collect();
        for o in nf.outputs.clone() {
            for f in &lay.fields {
                srcs.push(lie(nf, o.1, f));
            }
        }
        for e in srcs {
            let c = nf.ctx.canon(e);
            for p in [c.numerator().clone(), c.denominator().clone()] {
                if p.is_constant() || seen.contains(&p) {
                    continue;
                }
                let id = nf.ctx.from_canonical(&RatFun::from_poly(p.clone()));
                if nf.ctx.is_angle_valued(id) {
                    continue;
                }
                seen.push(p.clone());
                dens.push((p.len(), id));
            }
        }
    }
    dens.sort_by_key(|d| d.0);
    dens.into_iter().map(|d| d.1).collect()
}

/// Steps 4 and 5: the outputs themselves, then the basis Lie derivatives of
/// the rank test.
fn outputs_and_lie_derivatives(
    nf: &mut NormalForm,
    report: &RankReport,
    s: &Search,
    found: &mut Found,
) -> Result<(), AnalysisError> {
    for (oname, h) in nf.outputs.clone() {
        if found.modes.len() >= s.rank {
            break;
        }
        if found.indep.raises_rank(nf, h)? && screen_mode(nf, s.w_ids, h, s.opts.seed)? {
            let is_angle = nf.ctx.is_angle_valued(h);
            let text = nf.ctx.to_text(h);
            found.modes.push(DerivedMode {
                name: found.fresh.next(),
                expr: h,
                text,
                kind: ModeKind::Output,
                angle: false,
                domain: if is_angle {
                    format!("the branch of the output {oname} as the system defines it")
                } else {
                    format!("where the output {oname} is defined")
                },
            });
        }
    }
    for w in &report.basis {
        if found.modes.len() >= s.rank {
            break;
        }
        check_deadline(s.opts, "the Lie derivatives", found.modes.len())?;
        let mut g = nf.outputs[w.output].1;
        for &k in &w.fields {
            g = lie(nf, g, &report.fields.vectors[k]);
        }
        if found.indep.raises_rank(nf, g)? && screen_mode(nf, s.w_ids, g, s.opts.seed)? {
            let c = nf.ctx.canon(g);
            let text = nf.ctx.ratfun_text_factored(&c);
            let domain = if c.denominator().is_constant() {
                "everywhere".to_string()
            } else {
                format!("where {} != 0", nf.ctx.poly_text(c.denominator()))
            };
            let g = nf.ctx.from_canonical(&c);
            found.modes.push(DerivedMode {
                name: found.fresh.next(),
                expr: g,
                text,
                kind: ModeKind::LieDerivative,
                angle: false,
                domain,
            });
        }
    }
    Ok(())
}

/// The generators of the rank test's codistribution: the basis Lie
/// derivatives of the outputs.
fn generators(nf: &mut NormalForm, report: &RankReport) -> Vec<Id> {
    let mut out = Vec::new();
    for w in &report.basis {
        let mut g = nf.outputs[w.output].1;
        for &k in &w.fields {
            g = lie(nf, g, &report.fields.vectors[k]);
        }
        out.push(g);
    }
    out
}

/// The names of derived modes: z1, z2, ... skipping names the system uses.
pub(super) struct Names {
    used: Vec<String>,
    count: usize,
}

impl Names {
    fn next(&mut self) -> String {
        loop {
            self.count += 1;
            let s = format!("z{}", self.count);
            if !self.used.contains(&s) {
                self.used.push(s.clone());
                return s;
            }
        }
    }
}

/// What every invariant search needs.
pub(super) struct Search<'a> {
    w_ids: &'a [Vec<Id>],
    rank: usize,
    opts: &'a DeriveOptions,
}

pub(super) fn vars_id(nf: &mut NormalForm, name: &str) -> Id {
    nf.ctx.symbol(name).id
}

/// What the reduced system is written over.
pub(super) struct ModeSpace<'a> {
    pub(super) fields: &'a [Vec<Id>],
    pub(super) consts: &'a [String],
    pub(super) used_vars: &'a [u32],
    pub(super) w_ids: &'a [Vec<Id>],
}

/// The reduced system of one choice of modes (`None`: no form found).
pub(super) struct Reduced {
    pub(super) derivatives: Vec<Vec<Option<String>>>,
    pub(super) outputs: Vec<(String, Option<String>)>,
    pub(super) timed_out: bool,
    /// `variant[k][i]`: `L_{f_i} g_k` proven not invariant (a non-zero
    /// `w(t)` at a point), so a function of no modes; with unknown inputs
    /// the projection, not an exchange, deals with it.
    pub(super) variant: Vec<Vec<bool>>,
}

impl Reduced {
    /// Every output and every derivative that could be a function of
    /// modes found, but along the fields named in `projected` (`fnames`:
    /// the columns' names).
    pub(super) fn closed_except(&self, fnames: &[String], projected: &[String]) -> bool {
        let counted = |i: usize| !projected.contains(&fnames[i]);
        self.derivatives
            .iter()
            .zip(&self.variant)
            .all(|(row, var)| {
                row.iter()
                    .enumerate()
                    .all(|(i, d)| d.is_some() || !counted(i) || var[i])
            })
            && self.outputs.iter().all(|o| o.1.is_some())
    }
}

/// Each `L_f g_k` and each output written in the modes (and cos/sin of the
/// angle-valued ones, log of the variables the system takes the log of, and
/// the generic constants).
pub(super) fn reduce(
    nf: &mut NormalForm,
    sp: &ModeSpace,
    modes: &[DerivedMode],
    rng: &mut SplitMix,
    opts: &DeriveOptions,
) -> Result<Reduced, AnalysisError> {
    let mut zb: Vec<Id> = Vec::new();
    let mut znames: Vec<String> = Vec::new();
    for m in modes {
        if m.angle {
            let c = nf.parse_expr(&format!("cos({})", m.text), false);
            let s = nf.parse_expr(&format!("sin({})", m.text), false);
            if let (Ok(c), Ok(s)) = (c, s) {
                zb.push(c);
                znames.push(format!("cos({})", m.name));
                zb.push(s);
                znames.push(format!("sin({})", m.name));
            }
        } else if !nf.ctx.is_angle_valued(m.expr) {
            zb.push(m.expr);
            znames.push(m.name.clone());
            // A variable the system takes the log of: log(x) is a block too
            // (competition: the model is linear in log x1, log x2).
            if m.kind == ModeKind::Variable {
                if let Ok(l) = nf.parse_expr(&format!("log({})", m.name), false) {
                    let lv = nf.ctx.canon(l).vars();
                    if !lv.is_empty() && lv.iter().all(|v| sp.used_vars.contains(v)) {
                        zb.push(l);
                        znames.push(format!("log({})", m.name));
                    }
                }
            }
        }
    }
    for name in sp.consts {
        if let Some(s) = nf.ctx.lookup(name) {
            zb.push(s.id);
            znames.push(name.clone());
        }
    }
    // The deadline here is soft: the modes stand on their own checks, so a
    // reduced system not closed in time is reported as such (forms not
    // found), never as a failed run.
    let mut timed_out = false;
    let mut soft = |r: Result<Option<String>, AnalysisError>| match r {
        Err(AnalysisError::Timeout(_)) => {
            timed_out = true;
            Ok(None)
        }
        r => r,
    };
    let mut derivatives = Vec::new();
    let mut variant = Vec::new();
    for m in modes {
        let mut row = Vec::new();
        let mut var = Vec::new();
        for f in sp.fields {
            let mut not_invariant = false;
            let e = if check_deadline(opts, "the reduced dynamics", modes.len()).is_err() {
                soft(Err(AnalysisError::Timeout(String::new())))?
            } else {
                let t = lie(nf, m.expr, f);
                // A function of the modes satisfies eq. (11): `w(t)` not zero
                // at a point (exact) rules a form out before any search (the
                // drift of vins with amz unknown carries the lost baz).
                not_invariant = matches!(screen_mode(nf, sp.w_ids, t, opts.seed), Ok(false));
                if not_invariant {
                    None
                } else {
                    soft(in_modes(nf, t, &zb, &znames, modes, rng, opts))?
                }
            };
            row.push(e);
            var.push(not_invariant);
        }
        derivatives.push(row);
        variant.push(var);
    }
    let mut outputs = Vec::new();
    for (oname, h) in nf.outputs.clone() {
        let e = if let Some(m) = modes.iter().find(|m| m.expr == h) {
            Some(m.name.clone())
        } else if let Some((h0, parts)) = reduced::split_inputs(nf, h) {
            // An output reading inputs (an unknown input's feedthrough, or
            // its combination's): `h0 + sum c_u u`, each part in the modes.
            let mut text = match soft(reduced::output_in_modes(
                nf, h0, &zb, &znames, modes, rng, opts,
            ))? {
                Some(t) if t == "0" => String::new(),
                Some(t) => t,
                None => {
                    outputs.push((oname, None));
                    continue;
                }
            };
            let mut found = true;
            for (u, c) in parts {
                match soft(in_modes(nf, c, &zb, &znames, modes, rng, opts))? {
                    Some(ct) => {
                        let term = if ct == "1" { u } else { format!("({ct})*{u}") };
                        if text.is_empty() {
                            text = term;
                        } else {
                            text = format!("{text} + {term}");
                        }
                    }
                    None => found = false,
                }
            }
            found.then_some(text)
        } else {
            soft(reduced::output_in_modes(
                nf, h, &zb, &znames, modes, rng, opts,
            ))?
        };
        outputs.push((oname, e));
    }
    // What the search left: through the cross-section of the scalings
    // (section.rs), computed once, when some invariant derivative is missing.
    let missing = derivatives
        .iter()
        .zip(&variant)
        .any(|(row, var)| row.iter().zip(var).any(|(d, v)| d.is_none() && !v))
        || outputs
            .iter()
            .any(|o: &(String, Option<String>)| o.1.is_none());
    if missing && check_deadline(opts, "the reduced dynamics", modes.len()).is_ok() {
        let sec = match section::scaling_section(nf, sp.w_ids, &zb, &znames, modes, rng, opts) {
            Err(AnalysisError::Timeout(m)) => {
                soft(Err(AnalysisError::Timeout(m)))?;
                None
            }
            r => r?,
        };
        // Symmetries that are not all scalings: the slice of their free
        // columns (free_section.rs).
        let sec = match sec {
            Some(s) => Some(s),
            None => free_section::free_section(nf, sp.w_ids, modes, opts.seed)?,
        };
        if let Some(sec) = sec {
            for (k, m) in modes.iter().enumerate() {
                for (i, f) in sp.fields.iter().enumerate() {
                    if derivatives[k][i].is_none() && !variant[k][i] {
                        let t = lie(nf, m.expr, f);
                        derivatives[k][i] = sec.form(nf, t, &znames);
                    }
                }
            }
            // An output reading no input is an invariant too.
            let hs = nf.outputs.clone();
            for (o, (_, h)) in outputs.iter_mut().zip(hs) {
                if o.1.is_none() && reduced::split_inputs(nf, h).is_none() {
                    o.1 = sec.form(nf, h, &znames);
                }
            }
        }
    }
    Ok(Reduced {
        derivatives,
        outputs,
        timed_out,
        variant,
    })
}
