//! Symmetries block by block: a system made of parts that
//! do not see each other, or that see each other only through shared
//! variables (several experiments with common parameters), is solved one
//! part at a time, so the cost grows with the number of parts instead of
//! with a power of the whole state.
//!
//! Structure. Output `h_o` and all its Lie derivatives depend only on
//! `R_o`, the closure of the variables of `h_o` under "field component
//! `f_v` depends on `u`" for `v` already in the set (`L_f g` involves `f_v`
//! only for `v` in the support of `g`). Variables in every `R_o` are
//! *shared*; outputs are grouped by the connected components of the
//! `R_o` minus the shared ones. Block `B` is the subsystem over
//! `V_B = union of R_o, o in B`, with the fields' components on `V_B` (they
//! depend on `V_B` only) and B's outputs: its Lie derivatives are exactly
//! the full system's Lie derivatives of B's outputs, so the codistribution
//! is the sum of the blocks' codistributions, each living on its own `V_B`.
//! Variables in no `R_o` enter no Lie derivative: each is a symmetry `d/dx`.
//!
//! Without shared variables the symmetries are the blocks' own, extended by
//! zeros (a vector on `V_B` annihilates every other block's gradients, which
//! vanish on `V_B`). With shared variables S, a vector `w` is a symmetry iff
//! its restriction to every `V_B = L_B + S` is one of block B's. Each block's
//! basis is brought to reduced echelon form on the S columns (exact, in the
//! tangent half-angle view): vectors with a zero S part are local symmetries;
//! the others (`lifts`) have unit entries on pivot S columns. When every
//! block has the same pivot columns and the same S parts (exactly equal
//! canonical forms: the usual case of copies of one experiment), the lift
//! `a` of every block glued on S is a global symmetry. The vectors found are
//! independent (unit pivots, disjoint local supports); when they number
//! `n - rank` (the rank test's non-zero minor bounds the rank from below)
//! they are a basis. Otherwise the caller takes the general route.
//!
//! Certificates: every block's basis is certified by its own route; a vector
//! built by exact linear combination of certified block vectors annihilates
//! what they annihilate, so the blocks' certificates together prove the
//! result (random ones: their error bounds add up, a union bound).

use crate::rank::{rank, AnalysisError, Fields, LieWord, RankOptions, RankReport};
use crate::structure::SymmetryKind;
use crate::sym_recon::RandomCheck;
use crate::sym_report::{primitive_vector, Certificate, SymmetryOptions, SymmetryReport};
use obsan_expr::{lie::LieJets, Ctx, Id, RatFun};
use obsan_model::NormalForm;

/// How the state splits into blocks.
#[derive(Debug, PartialEq)]
pub(crate) struct Split {
    /// State indices in every block (empty: independent blocks).
    pub shared: Vec<usize>,
    /// Per block: its state indices (sorted, shared ones included) and outputs.
    pub blocks: Vec<(Vec<usize>, Vec<usize>)>,
    /// State indices no output's Lie derivatives depend on.
    pub unreached: Vec<usize>,
    /// Whether nothing at all (no output, no field component) depends on the unreached ones.
    pub unreached_free: bool,
}

/// The blocks of `nf` for the fields `fields`, or `None` when there is one.
pub(crate) fn split(nf: &NormalForm, fields: &[Vec<Id>]) -> Option<Split> {
    let n = nf.state.len();
    let m = nf.outputs.len();
    if m < 2 || nf.delay.is_some() {
        return None;
    }
    // Supports from the jet compiler (the state variables an expression
    // reaches, through leaf arguments: sin(gamma) depends on gamma).
    let mut roots: Vec<Id> = nf.outputs.iter().map(|o| o.1).collect();
    let mut comp_of: Vec<(usize, usize)> = Vec::new(); // (field, component) per extra root
    for (a, f) in fields.iter().enumerate() {
        for (j, &c) in f.iter().enumerate() {
            if !nf.ctx.is_zero(c) {
                roots.push(c);
                comp_of.push((a, j));
            }
        }
    }
    let jets = LieJets::new(&nf.ctx, &nf.state_vars, &[], &roots);
    let supp = |i: usize| jets.support(i, &[]).unwrap_or_else(|| vec![false; n]);
    // deps[v]: variables some field component f_v depends on (lists, not
    // an n x n table: unused params must cost nothing).
    let mut deps: Vec<Vec<usize>> = vec![Vec::new(); n];
    let mut used = vec![false; n];
    for (k, &(_, j)) in comp_of.iter().enumerate() {
        let s = supp(m + k);
        for u in 0..n {
            if s[u] {
                deps[j].push(u);
                used[u] = true;
            }
        }
    }
    let reach: Vec<Vec<bool>> = (0..m)
        .map(|o| {
            let mut r = supp(o);
            for u in 0..n {
                used[u] |= r[u];
            }
            let mut stack: Vec<usize> = (0..n).filter(|&v| r[v]).collect();
            while let Some(v) = stack.pop() {
                for &u in &deps[v] {
                    if !r[u] {
                        r[u] = true;
                        stack.push(u);
                    }
                }
            }
            r
        })
        .collect();
    // Shared: reached by every output that depends on something.
    let shared: Vec<usize> = (0..n)
        .filter(|&v| reach.iter().all(|r| r[v] || r.iter().all(|x| !x)))
        .collect();
    // Union-find of the outputs over their non-shared variables.
    let mut parent: Vec<usize> = (0..m).collect();
    fn find(p: &mut [usize], mut x: usize) -> usize {
        while p[x] != x {
            p[x] = p[p[x]];
            x = p[x];
        }
        x
    }
    for v in (0..n).filter(|v| !shared.contains(v)) {
        let mut first = None;
        for (o, r) in reach.iter().enumerate() {
            if r[v] {
                match first {
                    None => first = Some(o),
                    Some(f) => {
                        let (a, b) = (find(&mut parent, f), find(&mut parent, o));
                        parent[a] = b;
                    }
                }
            }
        }
    }
    // Outputs that see shared variables only go together (into one block).
    let bare: Vec<usize> = (0..m)
        .filter(|&o| (0..n).all(|v| !reach[o][v] || shared.contains(&v)))
        .collect();
    for w in bare.windows(2) {
        let (a, b) = (find(&mut parent, w[0]), find(&mut parent, w[1]));
        parent[a] = b;
    }
    let mut groups: Vec<(usize, Vec<usize>)> = Vec::new();
    for o in 0..m {
        let root = find(&mut parent, o);
        match groups.iter_mut().find(|g| g.0 == root) {
            Some(g) => g.1.push(o),
            None => groups.push((root, vec![o])),
        }
    }
    // Outputs that depend on no variable (constants) enter no block.
    let blocks: Vec<(Vec<usize>, Vec<usize>)> = groups
        .into_iter()
        .map(|(_, outs)| {
            let vars: Vec<usize> = (0..n)
                .filter(|&v| outs.iter().any(|&o| reach[o][v]))
                .collect();
            (vars, outs)
        })
        .filter(|(vars, _)| !vars.is_empty())
        .collect();
    if blocks.len() < 2 {
        return None;
    }
    let unreached: Vec<usize> = (0..n).filter(|&v| reach.iter().all(|r| !r[v])).collect();
    let unreached_free = unreached.iter().all(|&v| !used[v]);
    Some(Split {
        shared,
        blocks,
        unreached,
        unreached_free,
    })
}

/// The subsystem of one block: its state, its outputs, the fields'
/// components on its state (fields that move nothing there dropped), as
/// input fields of a drift-free system (the rank test treats every field
/// alike). Takes `nf`'s context; [`restore`] gives it back.
/// Also returns, per field of the subsystem, its index in `fields`.
fn sub_system(
    nf: &mut NormalForm,
    fields: &[Vec<Id>],
    names: &[String],
    vars: &[usize],
    outs: &[usize],
) -> (NormalForm, Vec<usize>) {
    let zero = nf.ctx.zero();
    let mut f = Vec::new();
    let mut inputs = Vec::new();
    let mut kept = Vec::new();
    for (a, field) in fields.iter().enumerate() {
        let comp: Vec<Id> = vars.iter().map(|&v| field[v]).collect();
        if comp.iter().any(|&c| !nf.ctx.is_zero(c)) {
            f.push(comp);
            inputs.push(names[a].clone());
            kept.push(a);
        }
    }
    let sub = NormalForm {
        ctx: std::mem::replace(&mut nf.ctx, Ctx::new()),
        name: nf.name.clone(),
        description: String::new(),
        state: vars.iter().map(|&v| nf.state[v].clone()).collect(),
        state_vars: vars.iter().map(|&v| nf.state_vars[v]).collect(),
        n_dynamic: vars.iter().filter(|&&v| v < nf.n_dynamic).count(),
        consts: nf.consts.clone(),
        inputs,
        input_vars: Vec::new(),
        f0: vec![zero; vars.len()],
        fields: f,
        // Symmetries and block ranks are for known inputs only (the commands refuse
        // unknown inputs before they get here).
        unknown_inputs: Vec::new(),
        unknown_input_vars: Vec::new(),
        unknown_fields: Vec::new(),
        outputs: outs.iter().map(|&o| nf.outputs[o].clone()).collect(),
        restriction: nf.restriction.clone(),
        delay: None,
        written: Vec::new(),
        measured_inputs: nf.measured_inputs.clone(),
    };
    (sub, kept)
}

/// The rank test block by block when the system splits into independent
/// blocks (no shared variable; module docs), else [`rank`] itself. The
/// codistribution is then the direct sum of the blocks' (each on its own
/// variables), so the rank is the sum of their ranks, the union of their
/// bases (words renamed to the whole system's outputs and fields) is a basis
/// with the union of their pivots as a non-zero minor, and the error bounds
/// add up (a union bound). Each block's rank test costs what a system of its
/// size costs, so the whole grows linearly with the number of blocks.
pub fn rank_by_blocks(
    nf: &mut NormalForm,
    mut opts: RankOptions,
) -> Result<RankReport, AnalysisError> {
    let fields = Fields::of(nf);
    let sp = match split(nf, &fields.vectors) {
        Some(sp) if sp.shared.is_empty() => sp,
        _ => return rank(nf, opts),
    };
    let n = nf.state.len();
    let mut out = RankReport {
        n,
        rank: 0,
        basis: Vec::new(),
        max_order: 0,
        evaluated: 0,
        observable: vec![false; n],
        pivots: Vec::new(),
        degree_bound: 1,
        error_bound: 0.0,
        fields: fields.clone(),
        seed: opts.seed,
        free_roots: false,
        roots_field: None,
    };
    for (level, (vars, outs)) in sp.blocks.iter().enumerate() {
        let (mut sub, kept) = sub_system(nf, &fields.vectors, &fields.names, vars, outs);
        let r = rank(
            &mut sub,
            RankOptions {
                seed: opts.seed,
                deadline: opts.deadline,
                progress: None,
            },
        );
        nf.ctx = std::mem::replace(&mut sub.ctx, Ctx::new());
        let r = r?;
        out.rank += r.rank;
        out.basis.extend(r.basis.iter().map(|w| LieWord {
            output: outs[w.output],
            fields: w.fields.iter().map(|&f| kept[f]).collect(),
        }));
        out.max_order = out.max_order.max(r.max_order);
        out.evaluated += r.evaluated;
        for (k, &o) in r.observable.iter().enumerate() {
            out.observable[vars[k]] = o;
        }
        out.pivots.extend(r.pivots.iter().map(|&p| vars[p]));
        out.degree_bound = out.degree_bound.max(r.degree_bound);
        out.error_bound = (out.error_bound + r.error_bound).min(1.0);
        if let Some(p) = opts.progress.as_mut() {
            p(level, out.rank, n);
        }
    }
    out.pivots.sort_unstable();
    Ok(out)
}

/// One block's symmetries (on its own state) and its report.
struct Solved {
    vectors: Vec<Vec<RatFun>>,
    rank: usize,
    exact: bool,
    rows: usize,
    cert: Certificate,
}

/// The route that solves one block (the general route, without blocks:
/// `symmetry.rs` passes it in, so this module stays below it).
pub(crate) type SolveBlock<'a> =
    dyn FnMut(&mut NormalForm, &RankReport) -> Result<SymmetryReport, AnalysisError> + 'a;

fn solve_block(
    nf: &mut NormalForm,
    report: &RankReport,
    opts: &SymmetryOptions,
    vars: &[usize],
    outs: &[usize],
    solve: &mut SolveBlock,
) -> Result<Solved, AnalysisError> {
    let (mut sub, _) = sub_system(nf, &report.fields.vectors, &report.fields.names, vars, outs);
    let res = (|| {
        let r = rank(
            &mut sub,
            RankOptions {
                seed: report.seed,
                deadline: opts.deadline,
                progress: None,
            },
        )?;
        solve(&mut sub, &r)
    })();
    nf.ctx = std::mem::replace(&mut sub.ctx, Ctx::new());
    let s = res?;
    Ok(Solved {
        vectors: s.vectors,
        rank: s.rank,
        exact: s.exact,
        rows: s.rows_checked,
        cert: s.certificate,
    })
}

/// The symmetries by blocks, or `Ok(None)` when the system has one block or
/// the shared-variable gluing does not apply (the caller's general route).
pub(crate) fn symmetries_by_blocks(
    nf: &mut NormalForm,
    report: &RankReport,
    opts: &SymmetryOptions,
    solve: &mut SolveBlock,
) -> Result<Option<SymmetryReport>, AnalysisError> {
    let Some(sp) = split(nf, &report.fields.vectors) else {
        return Ok(None);
    };
    // With shared variables, blocks whose bases are all cheap structure give
    // way to the whole system's cheap route (below): when that route alone
    // accounts for the deficiency, solving every block first is wasted (the
    // CHO model's 13 overlapping outputs: a rank test per block, minutes).
    if !sp.shared.is_empty()
        && opts.route != crate::sym_report::Route::Reconstruct
        && crate::structure::cheap_symmetries(nf, report)
            .ok()
            .flatten()
            .is_some()
    {
        return Ok(None);
    }
    let n = report.n;
    let mut solved = Vec::with_capacity(sp.blocks.len());
    for (vars, outs) in &sp.blocks {
        solved.push(solve_block(nf, report, opts, vars, outs, solve)?);
    }
    let mut vectors: Vec<Vec<RatFun>> = Vec::new();
    let mut kinds: Vec<SymmetryKind> = Vec::new();
    // Unreached variables: d/dx, in no Lie derivative at all.
    for &v in &sp.unreached {
        let mut w = vec![RatFun::zero(); n];
        w[v] = RatFun::one();
        vectors.push(w);
        kinds.push(SymmetryKind::Free(v));
    }
    let embed = |vars: &[usize], v: &[RatFun]| {
        let mut w = vec![RatFun::zero(); n];
        for (k, &j) in vars.iter().enumerate() {
            w[j] = v[k].clone();
        }
        w
    };
    let rank = if sp.shared.is_empty() {
        for ((vars, _), s) in sp.blocks.iter().zip(&solved) {
            for v in &s.vectors {
                vectors.push(embed(vars, v));
            }
            if let Certificate::Invariance(k) = &s.cert {
                kinds.extend(k.iter().map(|k| match k {
                    SymmetryKind::Free(i) => SymmetryKind::Free(vars[*i]),
                    k => *k,
                }));
            }
        }
        solved.iter().map(|s| s.rank).sum()
    } else {
        // Cheap structure in every block: the whole system's cheap route
        // proves its vectors by invariance (glued vectors may have lost it).
        if solved
            .iter()
            .all(|s| matches!(s.cert, Certificate::Invariance(_)))
        {
            return Ok(None);
        }
        let Some(glued) = glue(nf, &sp, &solved) else {
            return Ok(None);
        };
        if glued.len() + sp.unreached.len() != n - report.rank {
            return Ok(None);
        }
        vectors.extend(glued);
        report.rank
    };
    let rows: usize = solved.iter().map(|s| s.rows).sum();
    let exact = solved.iter().all(|s| s.exact);
    let certificate = combine(&solved, kinds, sp.unreached_free && sp.shared.is_empty());
    Ok(Some(SymmetryReport {
        n,
        rank,
        vectors,
        exact,
        rows_checked: rows,
        certificate,
        blocks: sp.blocks.len(),
        free: Vec::new(),
        undecided: Vec::new(),
    }))
}

/// The blocks' certificates as one: random if any block's is (error bounds
/// summed, a union bound), else invariance when every block's is and the
/// unreached variables are free, else closure (each vector annihilates every
/// Lie derivative's gradient: invariance implies it, and unreached variables
/// enter none).
fn combine(solved: &[Solved], kinds: Vec<SymmetryKind>, invariance_ok: bool) -> Certificate {
    let randoms: Vec<&RandomCheck> = solved
        .iter()
        .filter_map(|s| match &s.cert {
            Certificate::Random(c) => Some(c),
            _ => None,
        })
        .collect();
    if let Some(first) = randoms.first() {
        let mut c = (*first).clone();
        for r in &randoms[1..] {
            c.identities += r.identities;
            c.degree = c.degree.max(r.degree);
            c.content_bits = c.content_bits.max(r.content_bits);
            c.error_bound = (c.error_bound + r.error_bound).min(1.0);
            c.points = c.points.min(r.points);
            c.primes = c.primes.min(r.primes);
        }
        return Certificate::Random(c);
    }
    if invariance_ok
        && solved
            .iter()
            .all(|s| matches!(s.cert, Certificate::Invariance(_)))
    {
        return Certificate::Invariance(kinds);
    }
    Certificate::Closure
}

/// Global symmetries of blocks sharing the variables `sp.shared`: local
/// vectors of each block and lifts glued on the shared columns (module docs);
/// `None` when the blocks' shared parts differ.
fn glue(nf: &mut NormalForm, sp: &Split, solved: &[Solved]) -> Option<Vec<Vec<RatFun>>> {
    let n = nf.state.len();
    let ctx = &mut nf.ctx;
    let th = ctx.tan_half();
    let half = th.complete(ctx);
    let mut locals: Vec<Vec<RatFun>> = Vec::new();
    // Per block: pivot shared columns and the lifts (global coordinates).
    let mut lifts: Vec<(Vec<usize>, Vec<Vec<RatFun>>)> = Vec::new();
    for ((vars, _), s) in sp.blocks.iter().zip(solved) {
        let mut basis: Vec<Vec<RatFun>> = s
            .vectors
            .iter()
            .map(|v| {
                let mut w = vec![RatFun::zero(); n];
                for (k, &j) in vars.iter().enumerate() {
                    w[j] = if half {
                        ctx.to_tan_half(&th, &v[k])
                    } else {
                        v[k].clone()
                    };
                }
                w
            })
            .collect();
        let mut pivots = Vec::new();
        let mut done: Vec<Vec<RatFun>> = Vec::new();
        for &c in &sp.shared {
            let Some(p) = (0..basis.len())
                .filter(|&i| !basis[i][c].is_zero())
                .min_by_key(|&i| basis[i][c].term_count())
            else {
                continue;
            };
            let mut pv = basis.swap_remove(p);
            let inv = ctx.rf_inv(&pv[c])?;
            for x in pv.iter_mut() {
                if !x.is_zero() {
                    *x = ctx.rf_mul(x, &inv);
                }
            }
            for v in basis.iter_mut().chain(done.iter_mut()) {
                if v[c].is_zero() {
                    continue;
                }
                let f = v[c].clone();
                for (x, y) in v.iter_mut().zip(&pv) {
                    if !y.is_zero() {
                        let t = ctx.rf_mul(&f, y);
                        *x = ctx.rf_sub(x, &t);
                    }
                }
            }
            pivots.push(c);
            done.push(pv);
        }
        locals.extend(basis);
        lifts.push((pivots, done));
    }
    // Every block must agree on the shared parts.
    let (p0, l0) = &lifts[0];
    for (p, l) in &lifts[1..] {
        if p != p0
            || l.iter()
                .zip(l0)
                .any(|(a, b)| sp.shared.iter().any(|&c| a[c] != b[c]))
        {
            return None;
        }
    }
    let mut out = Vec::new();
    for a in 0..l0.len() {
        let mut w = l0[a].clone();
        for (_, l) in &lifts[1..] {
            for (j, x) in l[a].iter().enumerate() {
                if !x.is_zero() && !sp.shared.contains(&j) {
                    w[j] = x.clone();
                }
            }
        }
        out.push(w);
    }
    out.extend(locals);
    Some(
        out.iter()
            .map(|w| {
                let w: Vec<RatFun> = if half {
                    w.iter().map(|e| ctx.from_tan_half(&th, e)).collect()
                } else {
                    w.clone()
                };
                primitive_vector(ctx, &w)
            })
            .collect(),
    )
}

#[cfg(test)]
mod tests {
    use super::{split, Split};
    use crate::rank::Fields;
    use obsan_model::System;

    fn split_of(src: &str) -> Option<Split> {
        let mut nf = System::parse(src, "t.sys")
            .unwrap()
            .normal_form(None, &[])
            .unwrap();
        let f = Fields::of(&mut nf);
        split(&nf, &f.vectors)
    }

    /// State x1, x2, z, p, a: y1 = x1 reaches x1 and, through x1' = a u, a;
    /// y2 = x2 + p reaches x2 and p; z (z' = x1 u) is reached by no output and
    /// nothing depends on it; no variable is in both closures.
    #[test]
    fn independent_blocks_and_an_unreached_variable() {
        let s = split_of(
            "system t\nstate x1, x2, z\nparam p, a\ninput u\nx1' = a*u\nx2' = u\nz' = x1*u\n\
             output y1 = x1\noutput y2 = x2 + p\n",
        )
        .unwrap();
        assert!(s.shared.is_empty());
        assert_eq!(s.blocks, vec![(vec![0, 4], vec![0]), (vec![1, 3], vec![1])]);
        assert_eq!(s.unreached, vec![2]);
        assert!(s.unreached_free);
    }

    /// Two experiments sharing the param k (index 2): blocks over their own
    /// state and k; a constant output enters no block.
    #[test]
    fn shared_params_and_a_constant_output() {
        let s = split_of(
            "system t\nstate x1, x2\nparam k\ninput u\nx1' = k*u\nx2' = k*x2*u\n\
             output y1 = x1\noutput y2 = x2\noutput c = 3\n",
        )
        .unwrap();
        assert_eq!(s.shared, vec![2], "the constant output reaches nothing");
        assert_eq!(s.blocks, vec![(vec![0, 2], vec![0]), (vec![1, 2], vec![1])]);
        let s = split_of(
            "system t\nstate x1, x2\nparam k\ninput u\nx1' = k*u\nx2' = k*x2*u\n\
             output y1 = x1\noutput y2 = x2\n",
        )
        .unwrap();
        assert_eq!(s.shared, vec![2]);
        assert_eq!(s.blocks, vec![(vec![0, 2], vec![0]), (vec![1, 2], vec![1])]);
        // One output: nothing to split.
        assert!(split_of("system t\nstate x\ninput u\nx' = u\noutput y = x\n").is_none());
    }
}
