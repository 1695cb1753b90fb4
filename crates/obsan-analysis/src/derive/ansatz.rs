//! The invariant ansatz: polynomial and rational invariants `P/Q` of the
//! symmetries over blocks, solved in F_p and lifted, screened at random points.

use super::*;

/// `sum_m c_m prod_k b_k^{e_k}` as an expression.
pub(super) fn build_poly(
    nf: &mut NormalForm,
    coeffs: &[Q],
    monos: &[Vec<u32>],
    blocks: &[Id],
) -> Id {
    let mut terms = Vec::new();
    for (c, e) in coeffs.iter().zip(monos) {
        if c.is_zero() {
            continue;
        }
        let mut fs = vec![nf.ctx.num(c.clone())];
        for (k, &x) in e.iter().enumerate() {
            if x > 0 {
                let p = nf.ctx.pow(blocks[k], x as i64);
                fs.push(p);
            }
        }
        terms.push(nf.ctx.mul(&fs));
    }
    nf.ctx.add(&terms)
}

/// The same sum as text over block names.
pub(super) fn poly_text(coeffs: &[Q], monos: &[Vec<u32>], names: &[String]) -> String {
    let mut s = String::new();
    for (c, e) in coeffs.iter().zip(monos) {
        if c.is_zero() {
            continue;
        }
        let mut factors: Vec<String> = Vec::new();
        for (k, &x) in e.iter().enumerate() {
            match x {
                0 => {}
                // A product block reads as itself inside a product; a sum or a
                // power of a product needs its parentheses.
                1 if !names[k].contains([' ', '/', '+', '-']) => factors.push(names[k].clone()),
                1 => factors.push(format!("({})", names[k])),
                _ if !names[k].contains([' ', '/', '+', '-', '*', '^']) => {
                    factors.push(format!("{}^{x}", names[k]))
                }
                _ => factors.push(format!("({})^{x}", names[k])),
            }
        }
        let neg = c.is_negative();
        let a = if neg { c.neg() } else { c.clone() };
        let mut body = if a.is_one() && !factors.is_empty() {
            String::new()
        } else if a.is_integer() {
            format!("{}", a.num())
        } else {
            format!("({}/{})", a.num(), a.den())
        };
        if !factors.is_empty() {
            if !body.is_empty() {
                body.push('*');
            }
            body.push_str(&factors.join("*"));
        }
        if s.is_empty() {
            s = if neg { format!("-{body}") } else { body };
        } else {
            s.push_str(if neg { " - " } else { " + " });
            s.push_str(&body);
        }
    }
    if s.is_empty() {
        "0".into()
    } else {
        s
    }
}

pub(super) fn lie(nf: &mut NormalForm, g: Id, field: &[Id]) -> Id {
    let vars = nf.state_vars.clone();
    let mut terms = Vec::new();
    for (i, &x) in vars.iter().enumerate() {
        if nf.ctx.is_zero(field[i]) {
            continue;
        }
        let d = nf.ctx.diff(g, x);
        terms.push(nf.ctx.mul(&[field[i], d]));
    }
    nf.ctx.add(&terms)
}

/// A random point at which every given expression evaluates (retrying poles).
pub(super) fn point_for(
    nf: &mut NormalForm,
    rng: &mut SplitMix,
    roots: &[Id],
) -> Result<(FpPoint, Vec<Fp>), AnalysisError> {
    for _ in 0..64 {
        if let Ok(pt) = nf.ctx.random_fp_point(rng, &|_| None) {
            if let Ok(v) = nf.ctx.eval_fp(roots, &pt) {
                return Ok((pt, v));
            }
        }
    }
    // Roots no point mod p satisfies (BIG's sqrt(7)): expressions that avoid
    // them evaluate exactly at a point where the roots have no value.
    for _ in 0..64 {
        if let Ok(pt) = nf.ctx.random_fp_point_root_free(rng, &|_| None) {
            if let Ok(v) = nf.ctx.eval_fp(roots, &pt) {
                return Ok((pt, v));
            }
        }
    }
    Err(AnalysisError::NoPoint)
}

/// Independence of accepted gradients at one random point (exact when a
/// candidate raises the rank: a non-zero minor).
pub(super) struct Indep {
    pub(super) grads: Vec<Vec<Id>>,
    pub(super) seed: u64,
}

impl Indep {
    pub(super) fn raises_rank(
        &mut self,
        nf: &mut NormalForm,
        g: Id,
    ) -> Result<bool, AnalysisError> {
        let vars = nf.state_vars.clone();
        let grad: Vec<Id> = vars.iter().map(|&x| nf.ctx.diff(g, x)).collect();
        let mut roots: Vec<Id> = self.grads.iter().flatten().copied().collect();
        roots.extend(&grad);
        let n = vars.len();
        self.seed = self.seed.wrapping_add(0x9e37_79b9);
        let mut rng = SplitMix(self.seed);
        let (_, vals) = point_for(nf, &mut rng, &roots)?;
        let rows: Vec<Vec<Fp>> = vals.chunks(n).map(|c| c.to_vec()).collect();
        let before = Fp::matrix_rank(rows[..rows.len() - 1].to_vec());
        let after = Fp::matrix_rank(rows);
        if after > before {
            self.grads.push(grad);
            return Ok(true);
        }
        Ok(false)
    }
}

/// The PDE (11) at two random points in F_p (a screen: the exact check of
/// every accepted mode follows, once, in [`check_modes`]).
pub(super) fn screen_mode(
    nf: &mut NormalForm,
    w_ids: &[Vec<Id>],
    g: Id,
    seed: u64,
) -> Result<bool, AnalysisError> {
    let roots: Vec<Id> = w_ids.iter().map(|w| lie(nf, g, w)).collect();
    let mut rng = SplitMix(seed ^ 0x7363_7265_656e);
    for _ in 0..2 {
        let (_, v) = point_for(nf, &mut rng, &roots)?;
        if v.iter().any(|x| !x.is_zero()) {
            return Ok(false);
        }
    }
    Ok(true)
}

/// Polynomial and rational invariants `P/Q` over the blocks: for each fixed
/// denominator `Q` the PDE (11) `Q w(P) - P w(Q) = 0` is linear in the
/// coefficients of `P`; solved in F_p, lifted by rational reconstruction,
/// screened at random points (the exact check of the accepted modes follows
/// in [`check_modes`]).
#[allow(clippy::too_many_arguments)]
pub(super) fn invariant_ansatz(
    nf: &mut NormalForm,
    s: &Search,
    (blocks, bnames, is_const): (&[Id], &[String], &[bool]),
    dens: &[Id],
    modes: &mut Vec<DerivedMode>,
    indep: &mut Indep,
    fresh: &mut Names,
    rng: &mut SplitMix,
) -> Result<(), AnalysisError> {
    let nsym = s.w_ids.len();
    let nb = blocks.len();
    // w-derivatives of the blocks and of the denominators.
    let mut wb: Vec<Vec<Id>> = Vec::new(); // [sym][block]
    let mut wq: Vec<Vec<Id>> = Vec::new(); // [sym][den]
    for w in s.w_ids {
        let mut row = Vec::new();
        for &b in blocks {
            row.push(lie(nf, b, w));
        }
        wb.push(row);
        let mut rq = Vec::new();
        for &q in dens {
            rq.push(lie(nf, q, w));
        }
        wq.push(rq);
    }
    for (qi, &qd) in dens.iter().enumerate() {
        if modes.len() >= s.rank || nsym == 0 {
            break;
        }
        for d in 1..=s.opts.max_mode_degree {
            if modes.len() >= s.rank {
                break;
            }
            check_deadline(
                s.opts,
                &format!("the invariant ansatz of degree {d}"),
                modes.len(),
            )?;
            let monos = monomials(nb, 0, d);
            let nm = monos.len();
            if nm > MAX_UNKNOWNS {
                break;
            }
            let mut roots: Vec<Id> = blocks.to_vec();
            roots.push(qd);
            for j in 0..nsym {
                roots.extend(&wb[j]);
                roots.push(wq[j][qi]);
            }
            let npts = nm / nsym + 8;
            let mut rows: Vec<Vec<Fp>> = Vec::with_capacity(npts * nsym);
            let mut last_bv: Vec<Fp> = Vec::new();
            for _ in 0..npts {
                let (_, v) = point_for(nf, rng, &roots)?;
                let bv = &v[..nb];
                last_bv = bv.to_vec();
                let qv = v[nb];
                for j in 0..nsym {
                    let off = nb + 1 + j * (nb + 1);
                    let dv = &v[off..off + nb];
                    let dq = v[off + nb];
                    rows.push(
                        monos
                            .iter()
                            .map(|e| qv * mono_deriv(e, bv, dv) - mono_value(e, bv) * dq)
                            .collect(),
                    );
                }
            }
            let mut ns = Fp::null_space(rows, nm);
            ns.sort_by_key(|v| v.iter().filter(|x| !x.is_zero()).count());
            for v in ns {
                if modes.len() >= s.rank {
                    break;
                }
                // Skip constants (only the monomial 1 or constants' monomials).
                let nonconst = v.iter().zip(&monos).any(|(x, e)| {
                    !x.is_zero() && e.iter().enumerate().any(|(k, &p)| p > 0 && !is_const[k])
                });
                if !nonconst {
                    continue;
                }
                // A multiple of a constant, or a relation (cos^2 + sin^2 - 1) that
                // vanishes identically: not a new mode.
                let all_const_factor = v.iter().zip(&monos).all(|(x, e)| {
                    x.is_zero() || e.iter().enumerate().any(|(k, &p)| p > 0 && is_const[k])
                });
                if all_const_factor {
                    continue;
                }
                let val: Fp = v
                    .iter()
                    .zip(&monos)
                    .fold(Fp::ZERO, |a, (&c, e)| a + c * mono_value(e, &last_bv));
                if val.is_zero() {
                    continue;
                }
                let Some(qs) = v.iter().map(|&x| rat_recon(x)).collect::<Option<Vec<Q>>>() else {
                    continue;
                };
                let num = build_poly(nf, &qs, &monos, blocks);
                let g = if qi == 0 { num } else { nf.ctx.div(num, qd) };
                if !indep.raises_rank(nf, g)? || !screen_mode(nf, s.w_ids, g, s.opts.seed)? {
                    continue;
                }
                let c = nf.ctx.canon(g);
                let poly = c.denominator().is_constant();
                // The ansatz's own form usually reads better than the
                // canonical one (which writes sin^2 as 1 - cos^2), but the
                // canonical one has the common factors of P and Q cancelled
                // (x1 k / (x1 s1) is k/s1): the shorter of the two, the same
                // function.
                let ptext = poly_text(&qs, &monos, bnames);
                let ansatz_text = if qi == 0 {
                    ptext
                } else {
                    format!("({ptext})/({})", nf.ctx.to_text(qd))
                };
                let canon_text = nf.ctx.ratfun_text_factored(&c);
                let use_canon = canon_text.len() < ansatz_text.len();
                let text = if use_canon { canon_text } else { ansatz_text };
                let domain = if poly {
                    "everywhere".to_string()
                } else if use_canon {
                    format!("where {} != 0", nf.ctx.poly_text(c.denominator()))
                } else {
                    format!("where {} != 0", nf.ctx.to_text(qd))
                };
                modes.push(DerivedMode {
                    name: fresh.next(),
                    expr: g,
                    text,
                    kind: if poly {
                        ModeKind::Polynomial
                    } else {
                        ModeKind::Rational
                    },
                    angle: false,
                    domain,
                });
            }
        }
    }

    Ok(())
}
