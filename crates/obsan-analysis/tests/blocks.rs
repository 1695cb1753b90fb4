//! Symmetries of stacked systems solved block by block,
//! checked against the copies' own symmetries (by span) and, for copies
//! sharing their params, by invariance with an evaluator written here.

mod common;

use common::rank_fp;
use obsan_analysis::{rank, symmetries, RankOptions};
use obsan_expr::{evaluate::rational_angle, Fp, SplitMix, Var, Q};
use obsan_model::{NormalForm, System};
use std::collections::HashMap;

/// Copies of the paper's calibration system (eq. 16, circular restriction
/// (17)), copy `i` with states mu_i, gamma_i and, unless `shared`, params
/// phi_i .. xi_i; one input nu drives every copy (`--input q`).
fn stack(ids: &[usize], shared: bool) -> String {
    let mut states = Vec::new();
    let mut params = Vec::new();
    let mut inputs = Vec::new();
    let mut body = String::new();
    let mut restrict = Vec::new();
    for &i in ids {
        let p = |s: &str| {
            if shared {
                s.to_string()
            } else {
                format!("{s}{i}")
            }
        };
        let (mu, g) = (format!("mu{i}"), format!("gamma{i}"));
        let (phi, psi, eta, delta, xi) = (p("phi"), p("psi"), p("eta"), p("delta"), p("xi"));
        states.extend([mu.clone(), g.clone()]);
        if !shared {
            params.extend([
                phi.clone(),
                psi.clone(),
                eta.clone(),
                delta.clone(),
                xi.clone(),
            ]);
        }
        inputs.extend([format!("wR{i}"), format!("wL{i}")]);
        body.push_str(&format!(
            "{mu}' = -{mu}^2*{eta}*(wR{i} + {delta}*wL{i})*cos({g} - {phi})\n\
             {g}' = {xi}*(wR{i} - {delta}*wL{i}) - {mu}*{eta}*(wR{i} + {delta}*wL{i})*sin({g} - {phi})\n\
             output beta{i} = atan2(sin({g}), -{mu} - cos({g})) - {psi}\n"
        ));
        restrict.push(format!("wR{i} = nu, wL{i} = q*nu"));
    }
    if shared {
        params = ["phi", "psi", "eta", "delta", "xi"]
            .map(String::from)
            .to_vec();
    }
    format!(
        "system stack\nstate {}\nparam {}\nconst q\ninput {}\n{body}restrict q: {}\n",
        states.join(", "),
        params.join(", "),
        inputs.join(", "),
        restrict.join(", ")
    )
}

fn normal_form(src: &str) -> NormalForm {
    System::parse(src, "stack.sys")
        .unwrap()
        .normal_form(Some("q"), &[])
        .unwrap()
}

#[test]
fn three_independent_copies_have_the_union_of_their_symmetries() {
    let mut nf = normal_form(&stack(&[1, 2, 3], false));
    let r = rank(&mut nf, RankOptions::default()).unwrap();
    let s = symmetries(&mut nf, &r).unwrap();
    assert_eq!(s.blocks, 3);
    // Every copy's own symmetries (a one-copy system: solved whole), moved
    // into the stack by state names through their printed text.
    let mut own: Vec<Vec<obsan_expr::Id>> = Vec::new();
    for i in 1..=3 {
        let mut c = normal_form(&stack(&[i], false));
        let rc = rank(&mut c, RankOptions::default()).unwrap();
        let sc = symmetries(&mut c, &rc).unwrap();
        assert_eq!(sc.blocks, 1);
        for v in &sc.vectors {
            let mut w = vec![nf.parse_expr("0", false).unwrap(); nf.state.len()];
            for (k, e) in v.iter().enumerate() {
                let j = nf.state.iter().position(|x| *x == c.state[k]).unwrap();
                w[j] = nf.parse_expr(&c.ctx.ratfun_text(e), false).unwrap();
            }
            own.push(w);
        }
    }
    // 3 per copy: the paper's three symmetries under the circular restriction.
    assert_eq!(own.len(), 9);
    assert_eq!(s.vectors.len(), 9);
    let mut rng = SplitMix(11);
    for _ in 0..2 {
        let pt = nf.ctx.random_fp_point(&mut rng, &|_| None).unwrap();
        let mut rows: Vec<Vec<Fp>> = Vec::new();
        for v in &s.vectors {
            let ids: Vec<_> = v.iter().map(|e| nf.ctx.from_canonical(e)).collect();
            rows.push(nf.ctx.eval_fp(&ids, &pt).unwrap());
        }
        for w in &own {
            rows.push(nf.ctx.eval_fp(w, &pt).unwrap());
        }
        assert_eq!(rank_fp(rows[..9].to_vec()), 9);
        assert_eq!(rank_fp(rows[9..].to_vec()), 9);
        assert_eq!(rank_fp(rows), 9, "the spans differ");
    }
}

/// Rank of a matrix over Q by Gaussian elimination.
fn rank_q(mut m: Vec<Vec<Q>>) -> usize {
    let mut r = 0;
    let cols = m.first().map_or(0, |x| x.len());
    for c in 0..cols {
        let Some(i) = (r..m.len()).find(|&i| !m[i][c].is_zero()) else {
            continue;
        };
        m.swap(r, i);
        let pr = m[r].clone();
        for row in m.iter_mut().skip(r + 1) {
            let f = row[c].div(&pr[c]).unwrap();
            for (x, y) in row.iter_mut().zip(&pr) {
                *x = x.sub(&f.mul(y));
            }
        }
        r += 1;
    }
    r
}

/// For copies sharing the params: every symmetry w leaves every output
/// invariant (grad beta_i . w = 0) and [w, f] lies in the span of the
/// symmetries, for the one field f of the restricted system, at random
/// rational points. Then L_w L_f h = L_f L_w h + L_[w,f] h = 0 and so on by
/// induction: w annihilates every Lie derivative (Definition 2). The field,
/// its Jacobian and the output gradients are written out here from eq. (16):
/// with c = 1 + delta q, d = 1 - delta q, s = sin(g - phi), k = cos(g - phi),
///   mu' = -mu^2 eta c k,  gamma' = xi d - mu eta c s   (per unit nu),
///   beta = atan2(sin g, -mu - cos g) - psi:
///   d beta/d mu = sin g / r2, d beta/d g = -(mu cos g + 1) / r2,
///   d beta/d psi = -1, with r2 = mu^2 + 2 mu cos g + 1.
#[test]
fn shared_param_stack_symmetries_are_invariances() {
    let copies = 3;
    let mut nf = normal_form(&stack(&[1, 2, 3], true));
    let r = rank(&mut nf, RankOptions::default()).unwrap();
    let s = symmetries(&mut nf, &r).unwrap();
    assert_eq!(s.blocks, copies);
    let n = nf.state.len();
    assert_eq!(n, 2 * copies + 5);
    assert_eq!(s.vectors.len(), n - r.rank);
    assert!(!s.vectors.is_empty());
    let names = nf.state.clone();
    let idx = |name: &str| names.iter().position(|x| x == name).unwrap();
    let (phi, psi, eta, delta, xi) = (idx("phi"), idx("psi"), idx("eta"), idx("delta"), idx("xi"));
    // The leaf variables of symbols and of sin/cos of angles.
    let leaf = |nf: &mut NormalForm, e: &str| -> Var {
        let id = nf.parse_expr(e, false).unwrap();
        nf.ctx.canon(id).numerator().vars()[0]
    };
    let angles: Vec<String> = (1..=copies)
        .map(|i| format!("gamma{i}"))
        .chain(["phi".to_string()])
        .collect();
    let plain: Vec<String> = (1..=copies)
        .map(|i| format!("mu{i}"))
        .chain(["eta", "delta", "xi", "psi", "q"].map(String::from))
        .collect();
    let state_vars = nf.state_vars.clone();
    let mut rng = SplitMix(7);
    let mut rq = || {
        Q::from_i64((rng.next_u64() % 2001) as i64 - 1000)
            .div(&Q::from_i64(1 + (rng.next_u64() % 97) as i64))
            .unwrap()
    };
    for _ in 0..3 {
        let mut vals: HashMap<Var, Q> = HashMap::new();
        let mut x: HashMap<String, Q> = HashMap::new();
        let mut sc: HashMap<String, (Q, Q)> = HashMap::new();
        for a in &angles {
            let (sa, ca) = rational_angle(&rq());
            vals.insert(leaf(&mut nf, &format!("sin({a})")), sa.clone());
            vals.insert(leaf(&mut nf, &format!("cos({a})")), ca.clone());
            sc.insert(a.clone(), (sa, ca));
        }
        for p in &plain {
            let v = rq();
            vals.insert(leaf(&mut nf, p), v.clone());
            x.insert(p.clone(), v);
        }
        let ev = |nf: &mut NormalForm, e: &obsan_expr::RatFun| -> Q {
            let id = nf.ctx.from_canonical(e);
            nf.ctx.eval_q(&[id], &|v| vals.get(&v).cloned()).unwrap()[0].clone()
        };
        // The field f and its Jacobian J (J[a][b] = d f_a / d x_b), by hand.
        let q = x["q"].clone();
        let (et, de, xv) = (x["eta"].clone(), x["delta"].clone(), x["xi"].clone());
        let one = Q::from_i64(1);
        let c = one.add(&de.mul(&q));
        let d = one.sub(&de.mul(&q));
        let (sp, cp) = sc["phi"].clone();
        let mut f = vec![Q::zero(); n];
        let mut jac = vec![vec![Q::zero(); n]; n];
        let mut grads: Vec<Vec<Q>> = Vec::new();
        for i in 1..=copies {
            let (m, g) = (idx(&format!("mu{i}")), idx(&format!("gamma{i}")));
            let mu = x[&format!("mu{i}")].clone();
            let (sg, cg) = sc[&format!("gamma{i}")].clone();
            let s = sg.mul(&cp).sub(&cg.mul(&sp)); // sin(g - phi)
            let k = cg.mul(&cp).add(&sg.mul(&sp)); // cos(g - phi)
            let mu2 = mu.mul(&mu);
            f[m] = mu2.mul(&et).mul(&c).mul(&k).neg();
            f[g] = xv.mul(&d).sub(&mu.mul(&et).mul(&c).mul(&s));
            jac[m][m] = Q::from_i64(-2).mul(&mu).mul(&et).mul(&c).mul(&k);
            jac[m][g] = mu2.mul(&et).mul(&c).mul(&s);
            jac[m][phi] = mu2.mul(&et).mul(&c).mul(&s).neg();
            jac[m][eta] = mu2.mul(&c).mul(&k).neg();
            jac[m][delta] = mu2.mul(&et).mul(&q).mul(&k).neg();
            jac[g][m] = et.mul(&c).mul(&s).neg();
            jac[g][g] = mu.mul(&et).mul(&c).mul(&k).neg();
            jac[g][phi] = mu.mul(&et).mul(&c).mul(&k);
            jac[g][eta] = mu.mul(&c).mul(&s).neg();
            jac[g][delta] = xv.mul(&q).add(&mu.mul(&et).mul(&q).mul(&s)).neg();
            jac[g][xi] = d.clone();
            let r2 = mu2.add(&Q::from_i64(2).mul(&mu).mul(&cg)).add(&one);
            let mut gr = vec![Q::zero(); n];
            gr[m] = sg.div(&r2).unwrap();
            gr[g] = mu.mul(&cg).add(&one).neg().div(&r2).unwrap();
            gr[psi] = one.neg();
            grads.push(gr);
        }
        let mut w_vals: Vec<Vec<Q>> = Vec::new();
        let mut brackets: Vec<Vec<Q>> = Vec::new();
        for w in &s.vectors {
            let wv: Vec<Q> = w.iter().map(|e| ev(&mut nf, e)).collect();
            for gr in &grads {
                let dot = gr
                    .iter()
                    .zip(&wv)
                    .fold(Q::zero(), |a, (p, q)| a.add(&p.mul(q)));
                assert!(dot.is_zero(), "an output is not invariant");
            }
            // [w, f]_a = sum_b (dw_a/dx_b f_b - J[a][b] w_b).
            let mut br = vec![Q::zero(); n];
            for a in 0..n {
                let mut acc = Q::zero();
                for b in 0..n {
                    if !f[b].is_zero() && !w[a].is_zero() {
                        let dw = nf.ctx.rf_diff(&w[a], state_vars[b]);
                        acc = acc.add(&ev(&mut nf, &dw).mul(&f[b]));
                    }
                    acc = acc.sub(&jac[a][b].mul(&wv[b]));
                }
                br[a] = acc;
            }
            w_vals.push(wv);
            brackets.push(br);
        }
        let k = rank_q(w_vals.clone());
        assert_eq!(k, s.vectors.len(), "the symmetries are independent");
        let mut all = w_vals;
        all.extend(brackets);
        assert_eq!(rank_q(all), k, "[w, f] leaves the span of the symmetries");
    }
}

/// An injected deadline that has passed stops every block route at once
/// with a timeout (not a partial answer): the stack's rank by blocks and
/// its symmetries.
#[test]
fn a_passed_deadline_stops_the_blocks() {
    use obsan_analysis::{rank_by_blocks, symmetries_with, AnalysisError, SymmetryOptions};
    let mut nf = normal_form(&stack(&[1, 2], false));
    let past = std::time::Instant::now();
    let r = rank_by_blocks(
        &mut nf,
        RankOptions {
            deadline: Some(past),
            ..RankOptions::default()
        },
    );
    assert!(matches!(r, Err(AnalysisError::Timeout(_))), "{r:?}");
    let r = rank_by_blocks(&mut nf, RankOptions::default()).unwrap();
    assert_eq!((r.n, r.rank), (14, 8));
    let s = symmetries_with(
        &mut nf,
        &r,
        &SymmetryOptions {
            deadline: Some(past),
            ..SymmetryOptions::default()
        },
    );
    assert!(
        matches!(s, Err(AnalysisError::Timeout(_))),
        "{:?}",
        s.map(|s| s.vectors.len())
    );
}
