//! Cheap structure before the general symmetry machinery:
//! variables nothing depends on, translations `sum c_k d/dx_k` (constant c)
//! and scalings `sum l_k x_k d/dx_k` (integer l), as STRIKE-GOLDD's and SIAN's
//! scaling searches look for.
//!
//! Candidates come from linear algebra in F_p at random points: a translation
//! satisfies `grad(g) . c = 0` for every output and every field component g;
//! a scaling satisfies `sum_k l_k x_k dg/dx_k = l_j g` for component j of a
//! field (`0` for an output), i.e. `g(s^l x) = s^(l_j) g(x)`. Kernel vectors
//! are normalised on their pivots and their entries recovered as small
//! rationals. Each candidate is then **certified exactly by invariance**, in
//! canonical form: `L_w h = 0` for every output and `[w, f] = 0` for every
//! field. Then `L_w L_f phi = L_f L_w phi` gives `L_w phi = 0` for every Lie
//! derivative phi by induction on the word, so w annihilates the gradient of
//! every function of the codistribution (a symmetry, Definition 2). The
//! certified vectors are independent (a non-zero minor at a point); when
//! there are `n - rank` of them, the rank test's lower bound (a non-zero minor)
//! and these upper-bound it, so the rank is exact and they span the symmetries.

use crate::rank::{random_point, AnalysisError, RankReport};
use obsan_expr::{evaluate::FpPoint, Ctx, Fp, FpEchelon, Id, RatFun, SplitMix, Var, P, Q};
use obsan_model::NormalForm;

/// What a cheaply found symmetry is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SymmetryKind {
    /// `d/dx_k` for a state variable nothing depends on.
    Free(usize),
    /// A constant vector field.
    Translation,
    /// `sum l_k x_k d/dx_k`.
    Scaling,
}

/// A certified cheap basis: the vectors, their kinds, and the number of
/// exact identities checked.
pub(crate) struct Cheap {
    pub vectors: Vec<Vec<RatFun>>,
    pub kinds: Vec<SymmetryKind>,
    pub identities: usize,
}

enum Candidate {
    Translation(Vec<i64>),
    Scaling(Vec<i64>),
}

/// The components of outputs and fields: (expression, index of the
/// component's state variable for a field, `None` for an output).
fn components(nf: &NormalForm, report: &RankReport) -> Vec<(Id, Option<usize>)> {
    let mut out: Vec<(Id, Option<usize>)> = nf.outputs.iter().map(|o| (o.1, None)).collect();
    for f in &report.fields.vectors {
        for (j, &c) in f.iter().enumerate() {
            if !nf.ctx.is_zero(c) {
                out.push((c, Some(j)));
            }
        }
    }
    out
}

/// Try the cheap structure; `Ok(None)` when it does not account for the
/// whole rank deficiency.
pub(crate) fn cheap_symmetries(
    nf: &mut NormalForm,
    report: &RankReport,
) -> Result<Option<Cheap>, AnalysisError> {
    let n = report.n;
    let k = n - report.rank;
    if k == 0 {
        return Ok(None);
    }
    let comps = components(nf, report);
    let vars = nf.state_vars.clone();
    // Variables nothing depends on (structurally).
    let roots: Vec<Id> = comps.iter().map(|c| c.0).collect();
    let reached: std::collections::HashSet<Id> = nf.ctx.reachable(&roots).into_iter().collect();
    let used: Vec<bool> = nf
        .state
        .iter()
        .map(|name| nf.ctx.lookup(name).is_none_or(|s| reached.contains(&s.id)))
        .collect();
    let mut cands: Vec<(Candidate, SymmetryKind)> = Vec::new();
    for j in (0..n).filter(|&j| !used[j]) {
        let mut c = vec![0; n];
        c[j] = 1;
        cands.push((Candidate::Translation(c), SymmetryKind::Free(j)));
    }
    // Rows at random points.
    let mut rng = SplitMix(report.seed ^ 0x57_2c_7e);
    let grads: Vec<Vec<Id>> = comps
        .iter()
        .map(|&(g, _)| vars.iter().map(|&x| nf.ctx.diff(g, x)).collect())
        .collect();
    // Enough points that each component's gradients can span its support
    // (a component in s variables gives at most one row per point): too
    // few, and the kernel holds spurious vectors that hide the true ones
    // (CHO's rates in up to 30 variables: 39 kernel vectors at 4 points).
    let mut points = 3.max((n + 4).div_ceil(comps.len().max(1)));
    let mut trans_rows: Vec<Vec<Fp>> = Vec::new();
    let mut scale_rows: Vec<Vec<Fp>> = Vec::new();
    let mut taken = 0;
    while taken < points {
        taken += 1;
        let pt = random_point(&mut nf.ctx, &mut rng)?;
        let xs: Vec<Fp> = vars.iter().map(|&v| pt.value(v)).collect();
        for (gi, &(g, j)) in comps.iter().enumerate() {
            let Ok(d) = nf.ctx.eval_fp(&grads[gi], &pt) else {
                continue;
            };
            let Ok(val) = nf.ctx.eval_fp(&[g], &pt) else {
                continue;
            };
            let mut s: Vec<Fp> = d.iter().zip(&xs).map(|(&a, &x)| a * x).collect();
            if let Some(j) = j {
                s[j] = s[j] - val[0];
            }
            if taken == 1 {
                let support = d.iter().filter(|a| **a != Fp::ZERO).count();
                points = points.max((support + 1).min(n + 4));
            }
            trans_rows.push(d);
            scale_rows.push(s);
        }
    }
    for v in Fp::null_space(trans_rows, n) {
        if let Some(c) = integer_vector(&v) {
            cands.push((Candidate::Translation(c), SymmetryKind::Translation));
        }
    }
    for v in Fp::null_space(scale_rows, n) {
        if let Some(l) = integer_vector(&v) {
            cands.push((Candidate::Scaling(l), SymmetryKind::Scaling));
        }
    }
    // Keep independent candidates (at a point) that pass the exact check.
    let pt = random_point(&mut nf.ctx, &mut rng)?;
    let mut span = FpEchelon::default();
    let mut out = Cheap {
        vectors: vec![],
        kinds: vec![],
        identities: 0,
    };
    let outputs: Vec<Id> = nf.outputs.iter().map(|o| o.1).collect();
    let fields: Vec<Vec<Id>> = report.fields.vectors.clone();
    for (cand, kind) in cands {
        if out.vectors.len() == k {
            break;
        }
        let at = at_point(&cand, &vars, &pt);
        if span.contains(at.clone()) {
            continue;
        }
        let w = vector(&cand, &vars);
        if let Some(checked) = certify(&mut nf.ctx, &cand, &w, &vars, &outputs, &fields) {
            span.insert(at);
            out.identities += checked;
            out.vectors.push(w);
            out.kinds.push(kind);
        }
    }
    Ok((out.vectors.len() == k).then_some(out))
}

fn at_point(c: &Candidate, vars: &[Var], pt: &FpPoint) -> Vec<Fp> {
    match c {
        Candidate::Translation(c) => c.iter().map(|&x| Fp::from_i64(x)).collect(),
        Candidate::Scaling(l) => l
            .iter()
            .zip(vars)
            .map(|(&x, &v)| Fp::from_i64(x) * pt.value(v))
            .collect(),
    }
}

fn vector(c: &Candidate, vars: &[Var]) -> Vec<RatFun> {
    match c {
        Candidate::Translation(c) => c.iter().map(|&x| RatFun::from_q(&Q::from_i64(x))).collect(),
        Candidate::Scaling(l) => l
            .iter()
            .zip(vars)
            .map(|(&x, &v)| {
                if x == 0 {
                    RatFun::zero()
                } else {
                    RatFun::from_poly(RatFun::var(v).numerator().scale(&x.into()))
                }
            })
            .collect(),
    }
}

/// The exact invariance check: `L_w h = 0` for each output, `[w, f] = 0`
/// for each field; the number of identities, or `None` if one fails.
fn certify(
    ctx: &mut Ctx,
    cand: &Candidate,
    w: &[RatFun],
    vars: &[Var],
    outputs: &[Id],
    fields: &[Vec<Id>],
) -> Option<usize> {
    let mut checked = 0;
    let lie = |ctx: &mut Ctx, g: &RatFun| -> RatFun {
        let mut acc = RatFun::zero();
        for (&x, wk) in vars.iter().zip(w) {
            if wk.is_zero() {
                continue;
            }
            let d = ctx.rf_diff(g, x);
            if d.is_zero() {
                continue;
            }
            let t = ctx.rf_mul(&d, wk);
            acc = ctx.rf_add(&acc, &t);
        }
        acc
    };
    for &h in outputs {
        let g = ctx.canon(h);
        if !lie(ctx, &g).is_zero() {
            return None;
        }
        checked += 1;
    }
    for f in fields {
        for (j, &c) in f.iter().enumerate() {
            let g = ctx.canon(c);
            // [w, f]_j = L_w f_j - L_f w_j; L_f w_j = l_j f_j for a scaling.
            let mut b = lie(ctx, &g);
            if let Candidate::Scaling(l) = cand {
                let t = ctx.rf_mul(&g, &RatFun::from_q(&Q::from_i64(l[j])));
                b = ctx.rf_sub(&b, &t);
            }
            if !b.is_zero() {
                return None;
            }
            checked += 1;
        }
    }
    Some(checked)
}

/// Small rational `a/b` with `a = b x mod p`, |a|, b below 2^30 (Wang's
/// rational reconstruction), or `None`.
fn rational(x: Fp) -> Option<(i64, i64)> {
    let bound: i128 = 1 << 30;
    let (mut r0, mut r1) = (P as i128, x.0 as i128);
    let (mut t0, mut t1) = (0i128, 1i128);
    while r1 >= bound {
        let q = r0 / r1;
        (r0, r1) = (r1, r0 - q * r1);
        (t0, t1) = (t1, t0 - q * t1);
    }
    if t1 == 0 || t1.abs() >= bound {
        return None;
    }
    let (a, b) = if t1 < 0 { (-r1, -t1) } else { (r1, t1) };
    Some((a as i64, b as i64))
}

/// A kernel vector as a primitive integer vector, first non-zero entry positive.
fn integer_vector(v: &[Fp]) -> Option<Vec<i64>> {
    let qs: Vec<(i64, i64)> = v.iter().map(|&x| rational(x)).collect::<Option<_>>()?;
    let gcd = |mut a: i128, mut b: i128| {
        while b != 0 {
            (a, b) = (b, a % b);
        }
        a.abs()
    };
    let mut l: i128 = 1;
    for &(_, b) in &qs {
        l = l / gcd(l, b as i128) * b as i128;
        if l > 1 << 40 {
            return None;
        }
    }
    let ints: Vec<i128> = qs
        .iter()
        .map(|&(a, b)| a as i128 * (l / b as i128))
        .collect();
    let g = ints.iter().fold(0, |g, &x| gcd(g, x));
    if g == 0 {
        return None;
    }
    let sign = if ints.iter().find(|&&x| x != 0).is_some_and(|&x| x < 0) {
        -1
    } else {
        1
    };
    ints.iter()
        .map(|&x| i64::try_from(sign * x / g).ok())
        .collect()
}
