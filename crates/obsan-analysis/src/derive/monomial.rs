//! Monomial invariants of scaling-like symmetries.
//!
//! When a symmetry acts on a block `b` (a variable or an atom such as
//! `x3^sigma`) by `w(b) = lambda b`, a Laurent monomial `prod b_k^{e_k}` has
//! `w(prod b^e) = (sum_k e_k lambda_k) prod b^e`, so it satisfies the PDE (11)
//! exactly when `sum_k e_k lambda_k = 0` as a function. The ratios
//! `lambda_k = w(b_k) / b_k` are evaluated at random points of F_p (rows of a
//! linear system in the integer exponents); a column whose ratio is not
//! constant along the orbits makes no vanishing combination and drops out by
//! itself. Supports are tried from the smallest up, so the monomials are the
//! short ones the literature writes (`k1 k2 x2`, `gamma x2 / x3`). Like every
//! candidate, each is screened in F_p here and proven by the exact checks.

use super::*;

/// Largest support tried, and a cap on the subsets enumerated.
const MAX_SUPPORT: usize = 5;
const MAX_SUBSETS: usize = 60_000;

/// The blocks of the monomial search: every state variable, and the atoms
/// other than sin/cos that the fields and outputs use.
fn monomial_blocks(nf: &mut NormalForm, fields: &[Vec<Id>]) -> Vec<(Id, String)> {
    let mut out: Vec<(Id, String)> = nf
        .state
        .clone()
        .into_iter()
        .map(|s| (nf.ctx.symbol(&s).id, s))
        .collect();
    let mut roots: Vec<Id> = fields.iter().flatten().copied().collect();
    roots.extend(nf.outputs.iter().map(|o| o.1));
    let mut seen: Vec<u32> = Vec::new();
    for e in roots {
        let c = nf.ctx.canon(e);
        for v in c.vars() {
            if seen.contains(&v) || nf.ctx.symbol_name(v).is_some() {
                continue;
            }
            seen.push(v);
            let id = nf.ctx.from_canonical(&RatFun::var(v));
            let text = nf.ctx.to_text(id);
            if text.starts_with("sin(") || text.starts_with("cos(") || nf.ctx.is_angle_valued(id) {
                continue;
            }
            out.push((id, text));
        }
    }
    out
}

/// Subsets of `0..n` of size `k`, in lexicographic order.
fn subsets(n: usize, k: usize, mut f: impl FnMut(&[usize]) -> bool) {
    if k > n {
        return;
    }
    let mut c: Vec<usize> = (0..k).collect();
    loop {
        if !f(&c) {
            return;
        }
        let mut i = k;
        loop {
            if i == 0 {
                return;
            }
            i -= 1;
            if c[i] < n - k + i {
                c[i] += 1;
                for j in i + 1..k {
                    c[j] = c[j - 1] + 1;
                }
                break;
            }
        }
    }
}

fn gcd(a: i64, b: i64) -> i64 {
    if b == 0 {
        a.abs()
    } else {
        gcd(b, a % b)
    }
}

/// The primitive integer vector of a one-dimensional F_p null space, if its
/// entries reconstruct to small rationals.
fn primitive(v: &[Fp]) -> Option<Vec<i64>> {
    let qs: Vec<Q> = v.iter().map(|&x| rat_recon(x)).collect::<Option<_>>()?;
    let mut l: i64 = 1;
    for q in &qs {
        let d = i64::try_from(q.den()).ok()?;
        l = l.checked_mul(d / gcd(l, d))?;
    }
    let mut e: Vec<i64> = Vec::with_capacity(qs.len());
    for q in &qs {
        let n = i64::try_from(q.num()).ok()?;
        let d = i64::try_from(q.den()).ok()?;
        e.push(n.checked_mul(l / d)?);
    }
    let g = e.iter().fold(0, |a, &x| gcd(a, x));
    if g == 0 {
        return None;
    }
    let mut e: Vec<i64> = e.into_iter().map(|x| x / g).collect();
    // More positive exponents than negative ones read better (k12 k21, not 1/(k12 k21)).
    let neg = e.iter().filter(|&&x| x < 0).count();
    if 2 * neg > e.len() || (2 * neg == e.len() && e[0] < 0) {
        for x in e.iter_mut() {
            *x = -*x;
        }
    }
    if e.iter().any(|x| x.abs() > 6) {
        return None;
    }
    Some(e)
}

/// `b1^e1 * ...` as text and expression.
fn monomial(
    nf: &mut NormalForm,
    blocks: &[(Id, String)],
    cols: &[usize],
    e: &[i64],
) -> (Id, String) {
    let mut factors = Vec::new();
    let (mut num, mut den): (Vec<String>, Vec<String>) = (Vec::new(), Vec::new());
    for (&c, &x) in cols.iter().zip(e) {
        let (id, name) = &blocks[c];
        factors.push(nf.ctx.pow(*id, x));
        let base = if name.contains([' ', '+', '-', '*', '/', '^']) && !name.ends_with(')') {
            format!("({name})")
        } else {
            name.clone()
        };
        let t = if x.abs() == 1 {
            base
        } else {
            format!("{base}^{}", x.abs())
        };
        if x > 0 {
            num.push(t);
        } else {
            den.push(t);
        }
    }
    let top = if num.is_empty() {
        "1".to_string()
    } else {
        num.join("*")
    };
    let text = match den.len() {
        0 => top,
        1 => format!("{top}/{}", den[0]),
        _ => format!("{top}/({})", den.join("*")),
    };
    (nf.ctx.mul(&factors), text)
}

/// Whether the rows generate a saturated lattice (`(span_Q rows) ∩ Z^n`):
/// the gcd of their maximal minors is 1, i.e. every pivot of a unimodular
/// diagonalisation (row and column operations) is ±1. Then every monomial
/// invariant over these blocks is a Laurent monomial in the rows' monomials
/// (`x^2 c`, `y^2 c` generate index 2: `x y c` is only a square root; with
/// `y/x` instead, `x y c = x^2 c (y/x)`). `true` when dependent or past i128.
fn saturated(rows: &[Vec<i64>]) -> bool {
    let mut a: Vec<Vec<i128>> = rows
        .iter()
        .map(|r| r.iter().map(|&x| i128::from(x)).collect())
        .collect();
    let (m, n) = (a.len(), a.first().map_or(0, |r| r.len()));
    for t in 0..m {
        loop {
            // The smallest non-zero entry of the remaining block as pivot.
            let mut best: Option<(usize, usize)> = None;
            for i in t..m {
                for j in t..n {
                    if a[i][j] != 0 && best.is_none_or(|(bi, bj)| a[i][j].abs() < a[bi][bj].abs()) {
                        best = Some((i, j));
                    }
                }
            }
            let Some((bi, bj)) = best else {
                return true; // dependent rows: not this test's question
            };
            a.swap(t, bi);
            for r in a.iter_mut() {
                r.swap(t, bj);
            }
            let p = a[t][t];
            let mut clean = true;
            let (top, rest) = a.split_at_mut(t + 1);
            let pivot_row = &top[t];
            for row in rest.iter_mut() {
                let q = row[t] / p;
                for (x, &y) in row.iter_mut().zip(pivot_row).skip(t) {
                    let Some(v) = y.checked_mul(q).and_then(|y| x.checked_sub(y)) else {
                        return true;
                    };
                    *x = v;
                }
                clean &= row[t] == 0;
            }
            for j in t + 1..n {
                let q = a[t][j] / p;
                for row in a.iter_mut().skip(t) {
                    let Some(v) = row[t].checked_mul(q).and_then(|y| row[j].checked_sub(y)) else {
                        return true;
                    };
                    row[j] = v;
                }
                clean &= a[t][j] == 0;
            }
            if clean {
                break;
            }
        }
        if a[t][t].abs() != 1 {
            return false;
        }
    }
    true
}

/// A candidate: support size, negative exponents, total degree, columns, exponents.
type Cand = (usize, usize, i64, Vec<usize>, Vec<i64>);

/// The monomial over `cols` whose ratios vanish in every row, when the null
/// space is one vector with every entry non-zero and small rational exponents.
fn candidate(rows: &[Vec<Fp>], cols: Vec<usize>) -> Option<Cand> {
    let m: Vec<Vec<Fp>> = rows
        .iter()
        .map(|r| cols.iter().map(|&c| r[c]).collect())
        .collect();
    let ns = Fp::null_space(m, cols.len());
    if ns.len() != 1 || ns[0].iter().any(|x| x.is_zero()) {
        return None;
    }
    let e = primitive(&ns[0])?;
    let neg = e.iter().filter(|&&x| x < 0).count();
    let tot: i64 = e.iter().map(|x| x.abs()).sum();
    Some((cols.len(), neg, tot, cols, e))
}

/// Monomial invariants, accepted while they raise the rank.
pub(super) fn monomial_invariants(
    nf: &mut NormalForm,
    s: &Search,
    fields: &[Vec<Id>],
    modes: &mut Vec<DerivedMode>,
    indep: &mut Indep,
    fresh: &mut Names,
    rng: &mut SplitMix,
) -> Result<(), AnalysisError> {
    let nsym = s.w_ids.len();
    if nsym == 0 || modes.len() >= s.rank {
        return Ok(());
    }
    let blocks = monomial_blocks(nf, fields);
    let nb = blocks.len();
    let Some(rows) = ratio_rows(nf, s, &blocks, rng)? else {
        return Ok(());
    };
    // Only blocks some symmetry moves take part.
    let live: Vec<usize> = (0..nb)
        .filter(|&k| rows.iter().any(|r| !r[k].is_zero()))
        .collect();
    let mut cands: Vec<Cand> = Vec::new();
    let mut budget = MAX_SUBSETS;
    // Exponent vectors of the modes over the blocks (the variables already
    // modes as unit vectors): a candidate that would leave them unsaturated
    // waits until every other one was tried.
    let mut lattice: Vec<Vec<i64>> = modes
        .iter()
        .filter_map(|m| blocks.iter().position(|b| b.0 == m.expr))
        .map(|k| (0..nb).map(|j| i64::from(j == k)).collect())
        .collect();
    let mut deferred: Vec<Cand> = Vec::new();
    for size in 2..=MAX_SUPPORT.min(live.len()) {
        check_deadline(s.opts, "the monomial invariants", modes.len())?;
        subsets(live.len(), size, |sub| {
            if budget == 0 {
                return false;
            }
            budget -= 1;
            let cols: Vec<usize> = sub.iter().map(|&i| live[i]).collect();
            cands.extend(candidate(&rows, cols));
            true
        });
        // Smaller supports first; within one, fewer denominators, lower degree.
        cands.sort_by_key(|c| (c.0, c.1, c.2));
        for c in std::mem::take(&mut cands) {
            if modes.len() >= s.rank {
                return Ok(());
            }
            let mut row = vec![0i64; nb];
            for (&k, &x) in c.3.iter().zip(&c.4) {
                row[k] = x;
            }
            lattice.push(row);
            if !saturated(&lattice) {
                lattice.pop();
                deferred.push(c);
                continue;
            }
            if !accept(nf, s, &blocks, &c, modes, indep, fresh)? {
                lattice.pop();
            }
        }
    }
    for c in deferred {
        if modes.len() >= s.rank {
            break;
        }
        accept(nf, s, &blocks, &c, modes, indep, fresh)?;
    }
    Ok(())
}

/// Rows of the ratios `lambda_jk = w_j(b_k) / b_k` at enough random points
/// that a varying column cannot cancel; `None` when no such points were found.
fn ratio_rows(
    nf: &mut NormalForm,
    s: &Search,
    blocks: &[(Id, String)],
    rng: &mut SplitMix,
) -> Result<Option<Vec<Vec<Fp>>>, AnalysisError> {
    let (nb, nsym) = (blocks.len(), s.w_ids.len());
    let mut roots: Vec<Id> = blocks.iter().map(|b| b.0).collect();
    for w in s.w_ids {
        for b in blocks {
            roots.push(lie(nf, b.0, w));
        }
    }
    let npts = nb / nsym + 3;
    let mut rows: Vec<Vec<Fp>> = Vec::with_capacity(npts * nsym);
    let mut tries = 0;
    while rows.len() < npts * nsym {
        tries += 1;
        if tries > 4 * npts + 16 {
            return Ok(None);
        }
        let (_, v) = point_for(nf, rng, &roots)?;
        let Some(inv) = v[..nb].iter().map(|x| x.inv()).collect::<Option<Vec<Fp>>>() else {
            continue;
        };
        for j in 0..nsym {
            let off = nb * (j + 1);
            rows.push((0..nb).map(|k| v[off + k] * inv[k]).collect());
        }
    }
    Ok(Some(rows))
}

/// Most sums as written taken as blocks, and most terms in one.
const MAX_SUMS: usize = 16;
const MAX_SUM_TERMS: usize = 12;

/// Relative invariants among the sums as written (EAIHRD's `N - A - I - H -
/// R - D - E`, the population not yet infected, which the symmetries scale
/// by `a`): a sum `g` with `w(g) = lambda g` enters the lattice search as a
/// block, and `a c1 (N - A - I - H - R - D - E)` is a monomial invariant over
/// `a, c1, g` though no product of variables is. Tried after the other
/// searches, with one sum per monomial, only while modes are missing: a
/// short relative-invariant product in place of a long Lie derivative, whose
/// derivative closes where the Lie derivative's has no form of low degree.
pub(super) fn written_sum_invariants(
    nf: &mut NormalForm,
    s: &Search,
    fields: &[Vec<Id>],
    modes: &mut Vec<DerivedMode>,
    indep: &mut Indep,
    fresh: &mut Names,
    rng: &mut SplitMix,
) -> Result<(), AnalysisError> {
    if s.w_ids.is_empty() || modes.len() >= s.rank || nf.written.is_empty() {
        return Ok(());
    }
    let mut blocks = monomial_blocks(nf, fields);
    let nv = blocks.len();
    let allowed: Vec<u32> = nf
        .state_vars
        .iter()
        .copied()
        .chain(
            nf.consts
                .iter()
                .filter(|c| c.1.is_none())
                .filter_map(|c| nf.ctx.lookup(&c.0).map(|s| s.var)),
        )
        .collect();
    let mut seen: Vec<RatFun> = blocks.iter().map(|b| nf.ctx.canon(b.0)).collect();
    let mut sums: Vec<(usize, Id, String)> = Vec::new();
    let written = nf.written.clone();
    for id in nf.ctx.reachable(&written) {
        if !nf.ctx.is_sum(id) || nf.ctx.is_angle_valued(id) {
            continue;
        }
        let c = nf.ctx.canon(id);
        let terms = c.numerator().len();
        if c.as_q().is_some()
            || !c.denominator().is_constant()
            || !(2..=MAX_SUM_TERMS).contains(&terms)
            || !c.vars().iter().all(|v| allowed.contains(v))
        {
            continue;
        }
        // One block per sum up to a constant factor.
        let unit = nf
            .ctx
            .num(Q::new(c.denominator().content(), c.numerator().content()));
        let g0 = nf.ctx.from_canonical(&c);
        let g = nf.ctx.mul(&[unit, g0]);
        let gc = nf.ctx.canon(g);
        let minus = nf.ctx.neg(g);
        let neg = nf.ctx.canon(minus);
        if seen.contains(&gc) || seen.contains(&neg) {
            continue;
        }
        seen.push(gc.clone());
        let g = nf.ctx.from_canonical(&gc);
        let text = nf.ctx.to_text(g);
        sums.push((terms, g, text));
    }
    sums.sort_by_key(|x| x.0);
    sums.truncate(MAX_SUMS);
    if sums.is_empty() {
        return Ok(());
    }
    blocks.extend(sums.into_iter().map(|(_, g, t)| (g, t)));
    let Some(rows) = ratio_rows(nf, s, &blocks, rng)? else {
        return Ok(());
    };
    let live = |k: usize| rows.iter().any(|r| !r[k].is_zero());
    let vars: Vec<usize> = (0..nv).filter(|&k| live(k)).collect();
    let mut cands: Vec<Cand> = Vec::new();
    let mut budget = MAX_SUBSETS;
    for g in (nv..blocks.len()).filter(|&k| live(k)) {
        for size in 1..MAX_SUPPORT.min(vars.len() + 1) {
            subsets(vars.len(), size, |sub| {
                if budget == 0 {
                    return false;
                }
                budget -= 1;
                let mut cols: Vec<usize> = sub.iter().map(|&i| vars[i]).collect();
                cols.push(g);
                cands.extend(candidate(&rows, cols));
                true
            });
        }
    }
    cands.sort_by_key(|c| (c.0, c.1, c.2));
    for c in &cands {
        if modes.len() >= s.rank {
            break;
        }
        check_deadline(s.opts, "the invariants over written sums", modes.len())?;
        accept(nf, s, &blocks, c, modes, indep, fresh)?;
    }
    Ok(())
}

/// One candidate monomial taken as a mode when it raises the rank and passes
/// the PDE screen.
fn accept(
    nf: &mut NormalForm,
    s: &Search,
    blocks: &[(Id, String)],
    (_, _, _, cols, e): &Cand,
    modes: &mut Vec<DerivedMode>,
    indep: &mut Indep,
    fresh: &mut Names,
) -> Result<bool, AnalysisError> {
    let (g, text) = monomial(nf, blocks, cols, e);
    if !indep.raises_rank(nf, g)? || !screen_mode(nf, s.w_ids, g, s.opts.seed)? {
        return Ok(false);
    }
    let dens: Vec<&str> = cols
        .iter()
        .zip(e.iter())
        .filter(|(_, &x)| x < 0)
        .map(|(&c, _)| blocks[c].1.as_str())
        .collect();
    modes.push(DerivedMode {
        name: fresh.next(),
        expr: g,
        text,
        kind: if dens.is_empty() {
            ModeKind::Polynomial
        } else {
            ModeKind::Rational
        },
        angle: false,
        domain: if dens.is_empty() {
            "everywhere".into()
        } else {
            format!("where {} != 0", dens.join(", "))
        },
    });
    Ok(true)
}
