//! The reduced dynamics through the cross-section of the scalings, when
//! the search of `in_modes` finds no form (KD1999's `L_f0 (Ca Arr k0)`: a
//! quotient of degree 5 in 8 modes, past the dense ansatz).
//!
//! Every symmetry a scaling, `w(x_i) = l_i x_i` (`l_i` numbers), the group
//! they generate acts by `x_i -> x_i prod_s lambda_s^(W_si)`. Pivots `P`
//! (columns of `W` with `W_P` invertible) are moved to 1 by the group
//! element `lambda(x)`, which sends every other variable to
//! `m_j = x_j prod_{k in P} x_k^(a_jk)`, `a_j = -W_P^(-T) W_j`: an invariant
//! Laurent monomial when the `a_jk` are integers (else no rational section,
//! and no form from here). An invariant `t` is constant on the orbits:
//! `t(x) = t(lambda(x) x) = t(x_P := 1, x_j := m_j)` identically. Each `m_j`
//! is written in the modes by the search (a Laurent monomial of monomial
//! modes is of low degree there), and `t` with those forms substituted is
//! the form of `t` in the modes. Nothing here is trusted: the form is
//! proven like any other by the exact decomposition checks.

use super::reduced::in_modes;
use super::*;
use obsan_expr::Var;

/// Per variable (nf.state order): `None` for a pivot (set to 1), else the
/// form of its invariant monomial `m_j` in the modes, as a node over the
/// mode names.
pub(super) struct Section {
    images: Vec<(Var, Id)>,
    names: Vec<String>,
}

/// The cross-section of the scalings, or `None` when some symmetry is not a
/// scaling, no integer section exists, or some `m_j` has no form.
pub(super) fn scaling_section(
    nf: &mut NormalForm,
    w_ids: &[Vec<Id>],
    zb: &[Id],
    znames: &[String],
    modes: &[DerivedMode],
    rng: &mut SplitMix,
    opts: &DeriveOptions,
) -> Result<Option<Section>, AnalysisError> {
    let n = nf.state.len();
    if w_ids.is_empty() {
        return Ok(None);
    }
    let vars = nf.state_vars.clone();
    // The weights: w(x_i) / x_i must be a number.
    let mut weights: Vec<Vec<Q>> = Vec::with_capacity(w_ids.len());
    for w in w_ids {
        let mut row = Vec::with_capacity(n);
        for (i, &c) in w.iter().enumerate() {
            let r = nf.ctx.canon(c);
            let xi = RatFun::var(vars[i]);
            let Some(inv) = nf.ctx.rf_inv(&xi) else {
                return Ok(None);
            };
            let Some(l) = nf.ctx.rf_mul(&r, &inv).as_q() else {
                return Ok(None);
            };
            row.push(l);
        }
        weights.push(row);
    }
    // Pivots: params first (a scale fixed to 1), then states, each taken
    // when its column raises the rank.
    let s = weights.len();
    let n_dyn = nf.n_dynamic;
    let order: Vec<usize> = (n_dyn..n).chain(0..n_dyn).collect();
    let mut pivots: Vec<usize> = Vec::new();
    for &k in &order {
        let mut trial = pivots.clone();
        trial.push(k);
        if rank_of(&weights, &trial) == trial.len() {
            pivots = trial;
        }
        if pivots.len() == s {
            break;
        }
    }
    if pivots.len() != s {
        return Ok(None);
    }
    // a_j solves W_P^T a = -W_j (one equation per symmetry).
    let mut names = Vec::new();
    let mut images = Vec::new();
    let one = nf.ctx.one();
    for j in 0..n {
        if pivots.contains(&j) {
            images.push((vars[j], one));
            continue;
        }
        let rhs: Vec<Q> = (0..s).map(|r| weights[r][j].neg()).collect();
        let cols: Vec<Vec<Q>> = pivots
            .iter()
            .map(|&k| (0..s).map(|r| weights[r][k].clone()).collect())
            .collect();
        let Some(a) = solve_square(&cols, &rhs) else {
            return Ok(None);
        };
        if a.iter().all(|q| q.is_zero()) {
            continue; // invariant as it is: kept
        }
        let mut factors = vec![nf.ctx.symbol(&nf.state[j]).id];
        for (q, &k) in a.iter().zip(&pivots) {
            if q.is_zero() {
                continue;
            }
            // An integer exponent of a sane size (else no rational section).
            let Some(e) = q
                .is_integer()
                .then(|| i64::try_from(q.num()).ok())
                .flatten()
                .filter(|e| e.abs() <= 64)
            else {
                return Ok(None);
            };
            let xk = nf.ctx.symbol(&nf.state[k]).id;
            factors.push(nf.ctx.pow(xk, e));
        }
        let m = nf.ctx.mul(&factors);
        let Some(text) = in_modes(nf, m, zb, znames, modes, rng, opts)? else {
            return Ok(None);
        };
        let Some(form) = mode_node(nf, &text, znames) else {
            return Ok(None);
        };
        names.push(text);
        images.push((vars[j], form));
    }
    Ok(Some(Section { images, names }))
}

impl Section {
    /// A section given by the images of every state variable
    /// (free_section.rs).
    pub(super) fn from_images(images: Vec<(Var, Id)>) -> Section {
        Section {
            images,
            names: Vec::new(),
        }
    }

    /// `t` in the modes through the section, as text; `None` when the
    /// substitution leaves a variable that is not a mode or a constant.
    pub(super) fn form(&self, nf: &mut NormalForm, t: Id, znames: &[String]) -> Option<String> {
        let moved = nf.ctx.substitute(t, &self.images).ok()?;
        let r = nf.ctx.try_canon(moved).ok()?;
        for v in r.vars() {
            let name = nf.ctx.symbol_name(v)?;
            if !znames.iter().any(|z| z == name) {
                return None;
            }
        }
        let _ = &self.names;
        Some(nf.ctx.ratfun_text_factored(&r))
    }
}

/// A form's text over the mode names as a node (each name a symbol).
fn mode_node(nf: &mut NormalForm, text: &str, znames: &[String]) -> Option<Id> {
    let ast = obsan_expr::parse_ast(text).ok()?;
    let names: Vec<String> = znames.to_vec();
    let ids: Vec<Id> = names.iter().map(|z| nf.ctx.symbol(z).id).collect();
    let extra =
        move |name: &str, _s: obsan_expr::Span| -> Option<Result<Id, obsan_expr::ParseError>> {
            names.iter().position(|z| z == name).map(|k| Ok(ids[k]))
        };
    nf.build_expr(&ast, false, &extra).ok()
}

/// Rank over Q of the columns `cols` of `w` (rows: symmetries).
fn rank_of(w: &[Vec<Q>], cols: &[usize]) -> usize {
    let mut m: Vec<Vec<Q>> = w
        .iter()
        .map(|row| cols.iter().map(|&k| row[k].clone()).collect())
        .collect();
    let mut rank = 0;
    for c in 0..cols.len() {
        let Some(p) = (rank..m.len()).find(|&r| !m[r][c].is_zero()) else {
            continue;
        };
        m.swap(rank, p);
        eliminate(&mut m, rank, c, 0);
        rank += 1;
    }
    rank
}

/// Clears column `c` in every row but `p` with row `p` (entries from `from` on).
fn eliminate(m: &mut [Vec<Q>], p: usize, c: usize, from: usize) {
    let pivot = m[p].clone();
    for (r, row) in m.iter_mut().enumerate() {
        if r == p || row[c].is_zero() {
            continue;
        }
        let Some(f) = row[c].div(&pivot[c]) else {
            continue;
        };
        for (x, y) in row.iter_mut().zip(&pivot).skip(from) {
            *x = x.sub(&f.mul(y));
        }
    }
}

/// `x` with `sum_k cols[k] x_k = rhs` (a square, invertible system over Q).
fn solve_square(cols: &[Vec<Q>], rhs: &[Q]) -> Option<Vec<Q>> {
    let n = cols.len();
    // Augmented rows: equation r is sum_k cols[k][r] x_k = rhs[r].
    let mut m: Vec<Vec<Q>> = (0..n)
        .map(|r| {
            let mut row: Vec<Q> = cols.iter().map(|col| col[r].clone()).collect();
            row.push(rhs[r].clone());
            row
        })
        .collect();
    for c in 0..n {
        let p = (c..n).find(|&r| !m[r][c].is_zero())?;
        m.swap(c, p);
        let inv = m[c][c].inv()?;
        for x in m[c].iter_mut().skip(c) {
            *x = x.mul(&inv);
        }
        eliminate(&mut m, c, c, c);
    }
    Some(m.iter().map(|row| row[n].clone()).collect())
}
