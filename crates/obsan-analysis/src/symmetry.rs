//! Continuous symmetries: a basis of the null space of the gradients of the
//! Lie derivatives (Definition 2), in exact form.
//!
//! The rank test gives r independent basis functions and r pivot columns at
//! which their gradients have a non-singular minor. The canonical gradient
//! rows are brought to reduced echelon form on the pivot columns by exact
//! Gauss–Jordan elimination; each free column gives one null vector.
//!
//! Every vector is then checked exactly against the gradients of the basis
//! functions and of all their one-step Lie derivatives. Passing that check
//! proves, without probability, that the codistribution is the span of the
//! basis rows: if d(phi_k) span it and every d(L_f phi_k) lies in that span,
//! then d(L_f psi) does for every psi in it (d L_f = L_f d), by induction.

use crate::rank::{
    lie_jets, random_point, rank, AnalysisError, Fields, LieWord, RankOptions, RankReport,
};
use crate::reach::{check_symmetry_memory, restrict_to_reached, Reached};
use crate::structure::{cheap_symmetries, SymmetryKind};
use crate::sym_blocks::symmetries_by_blocks;
use crate::sym_recon::{certify_symmetries, reconstruct_basis, ReconFail};
use crate::sym_report::{normalize_vector, primitive_vector};
pub use crate::sym_report::{Certificate, Route, SymmetryOptions, SymmetryReport};
use obsan_expr::{Ctx, Fp, FpEchelon, FpField, RatFun, SplitMix};
use obsan_model::NormalForm;
use std::collections::HashMap;

/// From this Lie-derivative order on, reconstructed symmetries are proven by
/// the span certificate before the random one is tried (its closure words
/// are built on the graph, exponentially in the order).
const SPAN_FIRST_ORDER: usize = 10;

/// Canonical Lie derivatives by word, sharing prefixes.
pub struct LieCache {
    fields: Vec<Vec<RatFun>>,
    memo: HashMap<(usize, Vec<usize>), RatFun>,
}

impl LieCache {
    pub fn new(nf: &mut NormalForm, fields: &Fields) -> LieCache {
        let fields = fields
            .vectors
            .iter()
            .map(|f| f.iter().map(|&c| nf.ctx.canon(c)).collect())
            .collect();
        LieCache {
            fields,
            memo: HashMap::new(),
        }
    }

    /// The canonical Lie derivative named by `word`.
    pub fn get(&mut self, nf: &mut NormalForm, word: &LieWord) -> RatFun {
        let key = (word.output, word.fields.clone());
        if let Some(r) = self.memo.get(&key) {
            return r.clone();
        }
        let r = match word.fields.split_last() {
            None => nf.ctx.canon(nf.outputs[word.output].1),
            Some((&last, prefix)) => {
                let inner = self.get(
                    nf,
                    &LieWord {
                        output: word.output,
                        fields: prefix.to_vec(),
                    },
                );
                let vars = nf.state_vars.clone();
                nf.ctx.rf_lie_derivative(&inner, &vars, &self.fields[last])
            }
        };
        self.memo.insert(key, r.clone());
        r
    }
}

/// The canonical form of the Lie derivative named by `word`.
pub fn canonical_lie(nf: &mut NormalForm, fields: &Fields, word: &LieWord) -> RatFun {
    LieCache::new(nf, fields).get(nf, word)
}

fn grad(ctx: &mut Ctx, f: &RatFun, vars: &[obsan_expr::Var]) -> Vec<RatFun> {
    vars.iter().map(|&x| ctx.rf_diff(f, x)).collect()
}

fn dot(ctx: &mut Ctx, a: &[RatFun], b: &[RatFun]) -> RatFun {
    let mut acc = RatFun::zero();
    for (x, y) in a.iter().zip(b) {
        if x.is_zero() || y.is_zero() {
            continue;
        }
        let t = ctx.rf_mul(x, y);
        acc = ctx.rf_add(&acc, &t);
    }
    acc
}

/// Null space of `rows` by intersection, one row at a time: start from the
/// unit vectors; for each row, with c_i = row . b_i and the simplest non-zero
/// c_p, replace b_i by c_p b_i - c_i b_p (i != p) and drop b_p. Each new vector
/// is made primitive at once, so intermediate vectors stay as small as the
/// symmetries themselves (Gauss–Jordan on the rows swells badly instead).
fn null_space(ctx: &mut Ctx, rows: &[Vec<RatFun>], n: usize) -> Vec<Vec<RatFun>> {
    let mut basis: Vec<Vec<RatFun>> = (0..n)
        .map(|i| {
            let mut v = vec![RatFun::zero(); n];
            v[i] = RatFun::one();
            v
        })
        .collect();
    for row in rows {
        let c: Vec<RatFun> = basis.iter().map(|b| dot(ctx, row, b)).collect();
        let candidates: Vec<usize> = (0..basis.len()).filter(|&i| !c[i].is_zero()).collect();
        if candidates.is_empty() {
            continue;
        }
        // Try every pivot and keep the smallest resulting basis: the
        // symmetries are simple, but a careless pivot mixes them with large
        // scalar factors.
        let mut best: Option<(usize, Vec<Vec<RatFun>>)> = None;
        for &p in &candidates {
            let next = eliminate(ctx, &basis, &c, p, n);
            let size: usize = next.iter().flatten().map(|e| e.term_count()).sum();
            if best.as_ref().is_none_or(|b| size < b.0) {
                best = Some((size, next));
            }
        }
        // `candidates` is not empty, so neither is `best`.
        if let Some((_, next)) = best {
            basis = next;
        }
    }
    basis
}

/// The basis after eliminating with pivot vector `p`: c_p b_i - c_i b_p.
fn eliminate(
    ctx: &mut Ctx,
    basis: &[Vec<RatFun>],
    c: &[RatFun],
    p: usize,
    n: usize,
) -> Vec<Vec<RatFun>> {
    let mut next = Vec::with_capacity(basis.len() - 1);
    for i in 0..basis.len() {
        if i == p {
            continue;
        }
        if c[i].is_zero() {
            next.push(basis[i].clone());
            continue;
        }
        let v: Vec<RatFun> = (0..n)
            .map(|j| {
                let a = ctx.rf_mul(&c[p], &basis[i][j]);
                let b = ctx.rf_mul(&c[i], &basis[p][j]);
                ctx.rf_sub(&a, &b)
            })
            .collect();
        next.push(primitive_vector(ctx, &v));
    }
    next
}

/// The free columns whose reduced echelon null basis is sparsest, judged at a
/// random point of F_p (an entry that vanishes there is identically zero
/// except with probability D/p; the choice only affects readability).
fn choose_free_columns(
    nf: &mut NormalForm,
    report: &RankReport,
) -> Result<Vec<usize>, AnalysisError> {
    let n = report.n;
    let k = n - report.rank;
    let report_free: Vec<usize> = (0..n).filter(|j| !report.pivots.contains(j)).collect();
    if k == 0 {
        return Ok(vec![]);
    }
    let mut rng = SplitMix(report.seed ^ 0x5e1ec7);
    let pt = random_point(&mut nf.ctx, &mut rng)?;
    let jets = lie_jets(nf, &report.fields);
    let mut m: Vec<Vec<Fp>> = Vec::new();
    for w in &report.basis {
        let row = jets
            .row(w.output, &w.fields, &pt, false)
            .map_err(|_| AnalysisError::NoPoint)?;
        m.push(row.gradient);
    }
    let mut best: (usize, Vec<usize>) = (0, report_free.clone());
    let mut found = false;
    let mut count = 0;
    for free in subsets(n, k) {
        count += 1;
        if count > 4096 {
            break;
        }
        let piv: Vec<usize> = (0..n).filter(|j| !free.contains(j)).collect();
        let Some(zeros) = echelon_zeros(&m, &piv, &free) else {
            continue;
        };
        // Prefer more zeros; on ties, free columns late in the state (parameters).
        if !found
            || zeros > best.0
            || (zeros == best.0 && free.iter().rev().gt(best.1.iter().rev()))
        {
            best = (zeros, free);
            found = true;
        }
    }
    Ok(best.1)
}

/// Number of zero entries of the reduced echelon null basis for these
/// pivot/free columns, or `None` if the pivot minor is singular.
fn echelon_zeros(m: &[Vec<Fp>], piv: &[usize], free: &[usize]) -> Option<usize> {
    // Augmented system [M_P | M_F] reduced to [I | X]; null vectors are (-X, I).
    let a = m
        .iter()
        .map(|row| piv.iter().chain(free).map(|&c| row[c]).collect());
    let x = FpEchelon::of_rows(FpField, a).solve(piv.len())?;
    Some(x.iter().flatten().filter(|v| v.is_zero()).count())
}

/// All k-subsets of 0..n in lexicographic order.
fn subsets(n: usize, k: usize) -> impl Iterator<Item = Vec<usize>> {
    let mut cur: Option<Vec<usize>> = if k <= n { Some((0..k).collect()) } else { None };
    std::iter::from_fn(move || {
        let out = cur.clone()?;
        let mut c = out.clone();
        let mut i = k;
        loop {
            if i == 0 {
                cur = None;
                break;
            }
            i -= 1;
            if c[i] < n - k + i {
                c[i] += 1;
                for j in i + 1..k {
                    c[j] = c[j - 1] + 1;
                }
                cur = Some(c);
                break;
            }
        }
        Some(out)
    })
}

/// A basis of the continuous symmetries, exact, each vector checked: cheap
/// structure, then exact Gauss–Jordan on canonical rows (can be slow).
pub fn symmetries(
    nf: &mut NormalForm,
    report: &RankReport,
) -> Result<SymmetryReport, AnalysisError> {
    symmetries_with(
        nf,
        report,
        &SymmetryOptions {
            deadline: None,
            route: Route::Exact,
        },
    )
}

/// Whether the exact route is cheap enough to try first: first-order
/// words only over a small state (its canonical forms stay small).
fn exact_is_cheap(report: &RankReport) -> bool {
    report.max_order <= 1 && report.n <= 6
}

/// A basis of the continuous symmetries, in order: cheap structure (exact);
/// the exact route when it is cheap (or asked for, or the system has a
/// square root); otherwise reconstruction from values modulo a prime,
/// certified at random points ([`crate::sym_recon`]).
pub fn symmetries_with(
    nf: &mut NormalForm,
    report: &RankReport,
    opts: &SymmetryOptions,
) -> Result<SymmetryReport, AnalysisError> {
    let mut s = symmetries_inner(nf, report, opts, true)?;
    // The rank and the pivots are nonzero forms over the system's atoms:
    // certified only when those are proven independent.
    s.undecided = crate::decided::undecided_atoms_of(nf, &[]);
    Ok(s)
}

/// [`symmetries_with`]; `by_blocks`: first try solving independent blocks
/// apart (off for a block itself).
pub(crate) fn symmetries_inner(
    nf: &mut NormalForm,
    report: &RankReport,
    opts: &SymmetryOptions,
    by_blocks: bool,
) -> Result<SymmetryReport, AnalysisError> {
    let n = report.n;
    let r = report.rank;
    // A full rank is proven by the rank test itself (a non-zero minor at a
    // point): there is no symmetry to find, and nothing to build.
    if r == n {
        return Ok(SymmetryReport {
            n,
            rank: r,
            vectors: Vec::new(),
            exact: true,
            rows_checked: 0,
            certificate: Certificate::Closure,
            blocks: 1,
            free: Vec::new(),
            undecided: Vec::new(),
        });
    }
    // Variables no output reaches: each is its own symmetry d/dx; the rest
    // is solved on the subsystem of the reached ones (crate::reach), so the
    // dense work below grows with what the outputs reach, not with n.
    if let Some(red) = restrict_to_reached(nf) {
        return symmetries_reached(nf, report, opts, by_blocks, red);
    }
    check_symmetry_memory(n, n - r)?;
    // Parts that see each other only through shared variables (or not at
    // all) are solved one by one, so the cost grows with the number of parts.
    if by_blocks {
        let mut solve =
            |sub: &mut NormalForm, r: &RankReport| symmetries_inner(sub, r, opts, false);
        if let Some(s) = symmetries_by_blocks(nf, report, opts, &mut solve)? {
            return Ok(s);
        }
    }
    // Free variables, translations and scalings first: when they account
    // for the whole deficiency, their certificate proves everything. (No
    // usable point for the candidates: the general route decides.)
    let cheap = match opts.route {
        Route::Reconstruct => None,
        _ => cheap_symmetries(nf, report).ok().flatten(),
    };
    if let Some(c) = cheap {
        return Ok(SymmetryReport {
            n,
            rank: r,
            vectors: c.vectors,
            exact: true,
            rows_checked: c.identities,
            certificate: Certificate::Invariance(c.kinds),
            blocks: 1,
            free: Vec::new(),
            undecided: Vec::new(),
        });
    }
    let recon = match opts.route {
        Route::Auto => !exact_is_cheap(report),
        Route::Exact => false,
        Route::Reconstruct => true,
    };
    if recon {
        let free = choose_free_columns(nf, report)?;
        match reconstruct_basis(nf, report, &free, opts.deadline) {
            Ok(raw) => {
                let vectors: Vec<Vec<RatFun>> = raw
                    .iter()
                    .map(|v| normalize_vector(&mut nf.ctx, v))
                    .collect();
                // Deep bases: the random certificate builds every closure
                // word on the graph, whose size grows exponentially with the
                // order (MSMI, order 25: gigabytes); the span certificate
                // works on the canonical fields and is exact. Tried first
                // there; if it does not apply, the random one decides.
                if report.max_order >= SPAN_FIRST_ORDER {
                    if let Ok(rows) = crate::unknown_input_symmetry::certify_span(nf, &vectors) {
                        return Ok(SymmetryReport {
                            n,
                            rank: r,
                            vectors,
                            exact: true,
                            rows_checked: rows,
                            certificate: Certificate::Span,
                            blocks: 1,
                            free: Vec::new(),
                            undecided: Vec::new(),
                        });
                    }
                }
                return match certify_symmetries(nf, report, &vectors, opts.deadline)? {
                    Some(c) => Ok(SymmetryReport {
                        n,
                        rank: r,
                        vectors,
                        exact: false,
                        rows_checked: c.identities * c.points as usize,
                        certificate: Certificate::Random(c),
                        blocks: 1,
                        free: Vec::new(),
                        undecided: Vec::new(),
                    }),
                    None => Err(AnalysisError::Invalid(
                        "the reconstructed symmetries failed certification (a coefficient too large for one prime, or an unlucky rank test); try --exact or another --seed".into(),
                    )),
                };
            }
            Err(ReconFail::Unsupported) => {}
            Err(ReconFail::Error(e)) => return Err(e),
        }
    }
    exact_route(nf, report)
}

/// The symmetries of `nf` from those of its reached subsystem `red` (which
/// holds `nf`'s context until it is given back): its vectors extended by
/// zeros, and `d/dx` for each unreached variable (module docs of
/// [`crate::reach`]). The subsystem's rank test is the rank test of `nf`
/// on the reached columns (the others are zero).
fn symmetries_reached(
    nf: &mut NormalForm,
    report: &RankReport,
    opts: &SymmetryOptions,
    by_blocks: bool,
    red: Reached,
) -> Result<SymmetryReport, AnalysisError> {
    let Reached {
        nf: mut sub,
        keep,
        unreached,
    } = red;
    let res = (|| {
        let r = rank(
            &mut sub,
            RankOptions {
                seed: report.seed,
                deadline: opts.deadline,
                progress: None,
            },
        )?;
        symmetries_inner(&mut sub, &r, opts, by_blocks)
    })();
    nf.ctx = std::mem::replace(&mut sub.ctx, Ctx::new());
    let s = res?;
    let n = report.n;
    let vectors: Vec<Vec<RatFun>> = s
        .vectors
        .iter()
        .map(|v| {
            let mut w = vec![RatFun::zero(); n];
            for (k, &j) in keep.iter().enumerate() {
                w[j] = v[k].clone();
            }
            w
        })
        .collect();
    // Invariance (`[w, f] = 0`) was checked on the reached components. On
    // an unreached component j, [w, f]_j = L_w f_j (w_j = 0): checked here
    // in canonical form where f_j is not zero (unused params have none).
    // If one fails, the vectors still annihilate every Lie derivative (they
    // live on the reached variables): the closure certificate says that.
    let mut rows_checked = s.rows_checked;
    let certificate = match s.certificate {
        Certificate::Invariance(kinds) => {
            let vars = nf.state_vars.clone();
            let mut still = true;
            'check: for f in &report.fields.vectors {
                for &j in &unreached {
                    if nf.ctx.is_zero(f[j]) {
                        continue;
                    }
                    let g = nf.ctx.canon(f[j]);
                    for w in &vectors {
                        let lw = dot_grad(&mut nf.ctx, &g, w, &keep, &vars);
                        if !lw.is_zero() {
                            still = false;
                            break 'check;
                        }
                        rows_checked += 1;
                    }
                }
            }
            if still {
                Certificate::Invariance(
                    kinds
                        .into_iter()
                        .map(|k| match k {
                            SymmetryKind::Free(i) => SymmetryKind::Free(keep[i]),
                            k => k,
                        })
                        .collect(),
                )
            } else {
                Certificate::Closure
            }
        }
        // The brackets were checked on the reached variables only; the
        // vectors still annihilate every Lie derivative (closure's claim).
        Certificate::Span => Certificate::Closure,
        c => c,
    };
    Ok(SymmetryReport {
        n,
        rank: s.rank,
        vectors,
        exact: s.exact,
        rows_checked,
        certificate,
        blocks: s.blocks,
        free: unreached,
        undecided: Vec::new(),
    })
}

/// `L_w g = sum_k w_k dg/dx_k` over the state indices `on`.
fn dot_grad(
    ctx: &mut Ctx,
    g: &RatFun,
    w: &[RatFun],
    on: &[usize],
    vars: &[obsan_expr::Var],
) -> RatFun {
    let mut acc = RatFun::zero();
    for &k in on {
        if w[k].is_zero() {
            continue;
        }
        let d = ctx.rf_diff(g, vars[k]);
        let t = ctx.rf_mul(&d, &w[k]);
        acc = ctx.rf_add(&acc, &t);
    }
    acc
}

/// Exact Gauss–Jordan over canonical rows, then the exact closure check.
fn exact_route(nf: &mut NormalForm, report: &RankReport) -> Result<SymmetryReport, AnalysisError> {
    let n = report.n;
    let r = report.rank;
    let vars = nf.state_vars.clone();
    let mut cache = LieCache::new(nf, &report.fields);
    let mut rows: Vec<Vec<RatFun>> = Vec::with_capacity(r);
    for w in &report.basis {
        let f = cache.get(nf, w);
        rows.push(grad(&mut nf.ctx, &f, &vars));
    }
    let basis_rows = rows.clone();
    // Linear algebra in the half-angle view, where gcds see every common factor.
    let th = nf.ctx.tan_half();
    let rows: Vec<Vec<RatFun>> = if th.complete(&nf.ctx) {
        rows.iter()
            .map(|row| row.iter().map(|e| nf.ctx.to_tan_half(&th, e)).collect())
            .collect()
    } else {
        rows
    };
    let free = choose_free_columns(nf, report)?;
    let pivots: Vec<usize> = (0..n).filter(|j| !free.contains(j)).collect();
    let mut vectors = Vec::new();
    for &j in &free {
        // The reduced echelon vector for free column j spans the null space
        // of the columns P + {j}: one-dimensional, so its primitive form is unique.
        let mut cols = pivots.clone();
        cols.push(j);
        let sub: Vec<Vec<RatFun>> = rows
            .iter()
            .map(|row| cols.iter().map(|&c| row[c].clone()).collect())
            .collect();
        let ns = null_space(&mut nf.ctx, &sub, cols.len());
        if ns.len() != 1 {
            return Err(AnalysisError::Invalid(
                "internal: the chosen pivot minor is singular".into(),
            ));
        }
        let mut v = vec![RatFun::zero(); n];
        for (k, &c) in cols.iter().enumerate() {
            v[c] = if th.complete(&nf.ctx) {
                nf.ctx.from_tan_half(&th, &ns[0][k])
            } else {
                ns[0][k].clone()
            };
        }
        vectors.push(normalize_vector(&mut nf.ctx, &v));
    }
    // Exact checks: basis rows, then every one-step extension (closure).
    let mut checked = 0;
    for v in &vectors {
        for row in &basis_rows {
            let d = dot(&mut nf.ctx, v, row);
            if !d.is_zero() {
                return Err(AnalysisError::Invalid(
                    "internal: a computed symmetry does not annihilate a basis gradient".into(),
                ));
            }
            checked += 1;
        }
    }
    let mut exact = true;
    if !vectors.is_empty() {
        'outer: for w in &report.basis {
            for k in 0..report.fields.vectors.len() {
                let mut w2 = w.clone();
                w2.fields.push(k);
                let f = cache.get(nf, &w2);
                if f.is_zero() {
                    continue;
                }
                let row = grad(&mut nf.ctx, &f, &vars);
                for v in &vectors {
                    checked += 1;
                    if !dot(&mut nf.ctx, v, &row).is_zero() {
                        exact = false;
                        break 'outer;
                    }
                }
            }
        }
    }
    Ok(SymmetryReport {
        n,
        rank: r,
        vectors,
        exact,
        rows_checked: checked,
        certificate: Certificate::Closure,
        blocks: 1,
        free: Vec::new(),
        undecided: Vec::new(),
    })
}

/// Exact determinant of a square matrix of canonical forms, by elimination
/// in the half-angle view (where every step cancels common factors fully).
pub fn determinant(ctx: &mut Ctx, m: &[Vec<RatFun>]) -> RatFun {
    let th = ctx.tan_half();
    let mut a: Vec<Vec<RatFun>> = m
        .iter()
        .map(|row| row.iter().map(|e| ctx.to_tan_half(&th, e)).collect())
        .collect();
    let n = a.len();
    let mut det = RatFun::one();
    for c in 0..n {
        let Some(p) = (c..n)
            .filter(|&i| !a[i][c].is_zero())
            .min_by_key(|&i| a[i][c].term_count())
        else {
            return RatFun::zero();
        };
        if p != c {
            a.swap(p, c);
            det = det.neg();
        }
        let piv = a[c][c].clone();
        det = ctx.rf_mul(&det, &piv);
        #[allow(clippy::expect_used)] // the pivot was chosen non-zero
        let inv = ctx.rf_inv(&piv).expect("nonzero pivot");
        for i in c + 1..n {
            if a[i][c].is_zero() {
                continue;
            }
            let f = ctx.rf_mul(&a[i][c], &inv);
            let pivot_row = a[c].clone();
            for (x, p) in a[i].iter_mut().zip(&pivot_row).skip(c) {
                let t = ctx.rf_mul(&f, p);
                *x = ctx.rf_sub(x, &t);
            }
        }
    }
    ctx.from_tan_half(&th, &det)
}
