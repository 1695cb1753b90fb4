//! Cross-section invariants (a moving frame: Hubert & Kogan, "Rational
//! invariants of a group action", J. Symb. Comput. 2007).
//!
//! Functionally independent invariants need not generate the field of
//! rational invariants (vins: `vx^2 + vy^2` and `vx*qw^2 + ...` leave the
//! reduced dynamics without a rational form), while the coordinates of the
//! projection onto a cross-section do: every rational invariant is a
//! rational function of them, so the reduced system closes rationally. Each
//! symmetry is normalised in turn on the current coordinates, when its
//! action on them is recognised exactly (canonical forms):
//! - a translation (`w(c_i) = t_i phi`, `t_i` constant): the pivot `c_k` is
//!   set to 0, the others become `c_i - (t_i/t_k) c_k`;
//! - a rotation (pairs `w(c_i) = -k phi c_j`, `w(c_j) = k phi c_i`, angles
//!   `w(theta) = k phi`): with an angle among them, the angle is set to 0 and
//!   every pair is rotated into its frame, `(c_i + i c_j) e^{-i m theta}`;
//!   without one, the pair `z0` of the slowest rate is turned onto the real
//!   axis (the half-angle view: rational), a pair of `m` times its rate
//!   becoming `z conj(z0)^m / |z0|^(2 ceil(m/2))`, and `|z0|^2` a coordinate
//!   (the paper's eq. 23 normalises `psi` the same way);
//! - a scaling (`w(c_i) = l_i phi c_i`): the pivot is set to 1, the others
//!   become `c_i / c_k^(l_i/l_k)` (integer ratios only).
//!
//! The frame is used only when a rotation was normalised (scalings and
//! translations alone are the monomial and angle-difference steps' cases);
//! a symmetry it cannot recognise leaves it unused. Every coordinate is then
//! screened as a mode like any other candidate and checked exactly after.

use super::*;

#[derive(Clone)]
struct Coord {
    expr: Id,
    text: String,
    /// Enters through cos/sin: defined modulo 2 pi.
    angle: bool,
    /// A plain variable of the system (its own name is its text).
    plain: bool,
}

/// How one symmetry acts on the current coordinates.
enum Action {
    None,
    Translation(Vec<(usize, Q)>),
    /// Pairs `(i, j, rate)` and angles `(i, rate)`, rates relative to one
    /// another; a pair may turn about a centre `(b_i, b_j)` the symmetry fixes.
    Rotation(Vec<(usize, usize, Q, Centre)>, Vec<(usize, Q)>),
    Scaling(Vec<(usize, Q)>),
}

/// The centre of a pair's rotation (`None`: the origin).
type Centre = Option<(Id, Id)>;

/// `q` as a small integer (the exponents and rate multiples of a frame).
fn small_int(q: &Q) -> Option<i64> {
    let x = q.to_f64();
    (q.is_integer() && x.abs() <= 64.0).then_some(x as i64)
}

fn const_ratio(nf: &mut NormalForm, a: &RatFun, b: &RatFun) -> Option<Q> {
    let inv = nf.ctx.rf_inv(b)?;
    nf.ctx.rf_mul(a, &inv).as_q()
}

/// A pair turned about a centre, `w(c_i) = -R (c_j - b_j)`, `w(c_j) = R (c_i - b_i)`
/// with `w(b) = 0` (a bearing from an offset sensor: `lx - x - dx`): then
/// `w(a_i) = -R a_j` gives `R`, and `b` follows. `None` when `a` is not such a pair.
fn affine_pair(
    nf: &mut NormalForm,
    w: &[Id],
    cs: &[RatFun],
    a: &[RatFun],
    (i, j): (usize, usize),
) -> Option<(RatFun, (Id, Id))> {
    let ai = nf.ctx.from_canonical(&a[i]);
    let wai = lie(nf, ai, w);
    let wai = nf.ctx.canon(wai);
    let inv_aj = nf.ctx.rf_inv(&a[j])?;
    let r = nf.ctx.rf_mul(&wai, &inv_aj);
    let r = r.neg();
    let inv_r = nf.ctx.rf_inv(&r)?;
    // b_i = c_i - a_j / R, b_j = c_j + a_i / R.
    let q_j = nf.ctx.rf_mul(&a[j], &inv_r);
    let q_i = nf.ctx.rf_mul(&a[i], &inv_r);
    let bi = nf.ctx.rf_sub(&cs[i], &q_j);
    let bj = nf.ctx.rf_add(&cs[j], &q_i);
    let (bi, bj) = (nf.ctx.from_canonical(&bi), nf.ctx.from_canonical(&bj));
    for b in [bi, bj] {
        let wb = lie(nf, b, w);
        if !nf.ctx.canon(wb).is_zero() {
            return None;
        }
    }
    Some((r, (bi, bj)))
}

fn classify(nf: &mut NormalForm, coords: &[Coord], a: &[RatFun], w: &[Id]) -> Option<Action> {
    let s: Vec<usize> = (0..a.len()).filter(|&i| !a[i].is_zero()).collect();
    let Some(&k) = s.first() else {
        return Some(Action::None);
    };
    // Translation: every component a constant multiple of the first.
    let ts: Option<Vec<(usize, Q)>> = s
        .iter()
        .map(|&i| const_ratio(nf, &a[i], &a[k]).map(|q| (i, q)))
        .collect();
    if let Some(ts) = ts {
        if s.iter().all(|&i| coords[i].angle == coords[k].angle) {
            return Some(Action::Translation(ts));
        }
    }
    // Rotation: angles and pairs, every rate a constant multiple of one.
    let cs: Vec<RatFun> = coords.iter().map(|c| nf.ctx.canon(c.expr)).collect();
    let mut rates: Vec<(usize, Option<usize>, RatFun, Centre)> = Vec::new();
    let mut used = vec![false; a.len()];
    for &i in &s {
        if used[i] {
            continue;
        }
        if coords[i].angle {
            rates.push((i, None, a[i].clone(), None));
            used[i] = true;
            continue;
        }
        let mut found = false;
        for &j in &s {
            if j == i || used[j] || coords[j].angle {
                continue;
            }
            let (Some(ij), Some(ji)) = (nf.ctx.rf_inv(&cs[j]), nf.ctx.rf_inv(&cs[i])) else {
                continue;
            };
            let r1 = nf.ctx.rf_mul(&a[i], &ij);
            let r2 = nf.ctx.rf_mul(&a[j], &ji);
            if nf.ctx.rf_add(&r1, &r2).is_zero() {
                rates.push((i, Some(j), r2, None));
                used[i] = true;
                used[j] = true;
                found = true;
                break;
            }
            if let Some((r, centre)) = affine_pair(nf, w, &cs, a, (i, j)) {
                rates.push((i, Some(j), r, Some(centre)));
                used[i] = true;
                used[j] = true;
                found = true;
                break;
            }
        }
        if !found {
            break;
        }
    }
    if s.iter().all(|&i| used[i]) {
        let base = rates[0].2.clone();
        let mut pairs = Vec::new();
        let mut angles = Vec::new();
        let mut ok = true;
        for (i, j, r, centre) in &rates {
            match const_ratio(nf, r, &base) {
                Some(q) => match j {
                    Some(j) => pairs.push((*i, *j, q, *centre)),
                    None => angles.push((*i, q)),
                },
                None => ok = false,
            }
        }
        if ok && !pairs.is_empty() {
            return Some(Action::Rotation(pairs, angles));
        }
    }
    // Scaling: a[i] / c_i constant multiples of one another.
    if s.iter().any(|&i| coords[i].angle) {
        return None;
    }
    let inv_k = nf.ctx.rf_inv(&cs[k])?;
    let lk = nf.ctx.rf_mul(&a[k], &inv_k);
    let mut ls = Vec::new();
    for &i in &s {
        let inv = nf.ctx.rf_inv(&cs[i])?;
        let li = nf.ctx.rf_mul(&a[i], &inv);
        ls.push((i, const_ratio(nf, &li, &lk)?));
    }
    Some(Action::Scaling(ls))
}

/// A coordinate from a canonical form (its text parses back).
fn coord_from(nf: &mut NormalForm, e: Id, angle: bool) -> Coord {
    let c = nf.ctx.canon(e);
    let text = nf.ctx.ratfun_text_factored(&c);
    let expr = nf.ctx.from_canonical(&c);
    Coord {
        expr,
        text,
        angle,
        plain: false,
    }
}

fn cmul(nf: &mut NormalForm, a: (Id, Id), b: (Id, Id)) -> (Id, Id) {
    let rr = nf.ctx.mul(&[a.0, b.0]);
    let ii = nf.ctx.mul(&[a.1, b.1]);
    let ri = nf.ctx.mul(&[a.0, b.1]);
    let ir = nf.ctx.mul(&[a.1, b.0]);
    (nf.ctx.sub(rr, ii), nf.ctx.add(&[ri, ir]))
}

fn cpow(nf: &mut NormalForm, z: (Id, Id), m: u32) -> (Id, Id) {
    let mut acc = (nf.ctx.one(), nf.ctx.zero());
    for _ in 0..m {
        acc = cmul(nf, acc, z);
    }
    acc
}

/// A pair's coordinates relative to its centre of rotation.
fn about(nf: &mut NormalForm, coords: &[Coord], (i, j): (usize, usize), c: &Centre) -> (Id, Id) {
    match c {
        None => (coords[i].expr, coords[j].expr),
        Some((bi, bj)) => (
            nf.ctx.sub(coords[i].expr, *bi),
            nf.ctx.sub(coords[j].expr, *bj),
        ),
    }
}

/// Apply one recognised action; `None` when a ratio is not an integer.
fn normalise(nf: &mut NormalForm, coords: &[Coord], act: &Action) -> Option<Vec<Coord>> {
    let mut out: Vec<Coord> = Vec::new();
    let moved: Vec<usize> = match act {
        Action::None => return Some(coords.to_vec()),
        Action::Translation(ts) | Action::Scaling(ts) => ts.iter().map(|t| t.0).collect(),
        Action::Rotation(ps, an) => ps
            .iter()
            .flat_map(|p| [p.0, p.1])
            .chain(an.iter().map(|a| a.0))
            .collect(),
    };
    match act {
        Action::None => {}
        Action::Translation(ts) => {
            // Pivot: a plain variable if there is one (r in vins, so pf - r).
            let (k, tk) = ts
                .iter()
                .find(|t| coords[t.0].plain)
                .unwrap_or(&ts[0])
                .clone();
            for (i, ti) in ts {
                if *i == k {
                    continue;
                }
                let q = nf.ctx.num(ti.div(&tk)?);
                let t = nf.ctx.mul(&[q, coords[k].expr]);
                let e = nf.ctx.sub(coords[*i].expr, t);
                out.push(coord_from(nf, e, coords[*i].angle));
            }
        }
        Action::Scaling(ls) => {
            let (k, lk) = ls
                .iter()
                .rev()
                .find(|t| coords[t.0].plain)
                .unwrap_or(&ls[0])
                .clone();
            for (i, li) in ls {
                if *i == k {
                    continue;
                }
                let e = small_int(&li.div(&lk)?)?;
                let p = nf.ctx.pow(coords[k].expr, -e);
                let e = nf.ctx.mul(&[coords[*i].expr, p]);
                out.push(coord_from(nf, e, false));
            }
        }
        Action::Rotation(ps, an) => {
            if let Some((t, kt)) = an.first().cloned() {
                // The angle theta is set to 0: pairs rotated by -m theta.
                for (i, j, k, centre) in ps {
                    let m = small_int(&k.div(&kt)?)?;
                    let th = &coords[t].text;
                    let arg = if m == 1 {
                        format!("({th})")
                    } else {
                        format!("({m}*({th}))")
                    };
                    let c = nf.parse_expr(&format!("cos{arg}"), false).ok()?;
                    let s = nf.parse_expr(&format!("sin{arg}"), false).ok()?;
                    let ns = nf.ctx.neg(s);
                    let z = about(nf, coords, (*i, *j), centre);
                    let (re, im) = cmul(nf, z, (c, ns));
                    out.push(coord_from(nf, re, false));
                    out.push(coord_from(nf, im, false));
                }
                for (i, ki) in an.iter().skip(1) {
                    let q = nf.ctx.num(ki.div(&kt)?);
                    let tt = nf.ctx.mul(&[q, coords[t].expr]);
                    let e = nf.ctx.sub(coords[*i].expr, tt);
                    out.push(coord_from(nf, e, true));
                }
            } else {
                // The slowest pair z0 is turned onto the real axis.
                let r0 = ps
                    .iter()
                    .enumerate()
                    .min_by(|a, b| a.1 .2.to_f64().abs().total_cmp(&b.1 .2.to_f64().abs()))
                    .map(|p| p.0)?;
                let (i0, j0, k0, c0) = ps[r0].clone();
                let (x0, y0) = about(nf, coords, (i0, j0), &c0);
                let ny0 = nf.ctx.neg(y0);
                let x2 = nf.ctx.pow(x0, 2);
                let y2 = nf.ctx.pow(y0, 2);
                let n0 = nf.ctx.add(&[x2, y2]);
                out.push(coord_from(nf, n0, false));
                for (p, (i, j, k, centre)) in ps.iter().enumerate() {
                    if p == r0 {
                        continue;
                    }
                    let mi = small_int(&k.div(&k0)?)?;
                    let (zi, zj) = about(nf, coords, (*i, *j), centre);
                    let z = if mi < 0 { (zj, zi) } else { (zi, zj) };
                    let mu = mi.unsigned_abs() as u32;
                    let zb = cpow(nf, (x0, ny0), mu);
                    let (re, im) = cmul(nf, z, zb);
                    let d = nf.ctx.pow(n0, -i64::from(mu.div_ceil(2)));
                    let re = nf.ctx.mul(&[re, d]);
                    let im = nf.ctx.mul(&[im, d]);
                    out.push(coord_from(nf, re, false));
                    out.push(coord_from(nf, im, false));
                }
            }
        }
    }
    // The coordinates the action leaves alone, in their order, first.
    let mut kept: Vec<Coord> = (0..coords.len())
        .filter(|i| !moved.contains(i))
        .map(|i| coords[i].clone())
        .collect();
    kept.extend(out);
    Some(kept)
}

/// The cross-section coordinates as candidate modes (see the module doc).
#[allow(clippy::too_many_arguments)]
pub(super) fn frame_invariants(
    nf: &mut NormalForm,
    s: &Search,
    angle: &[bool],
    modes: &mut Vec<DerivedMode>,
    indep: &mut Indep,
    fresh: &mut Names,
) -> Result<(), AnalysisError> {
    if modes.len() >= s.rank || s.w_ids.is_empty() {
        return Ok(());
    }
    // Translations, rotations and scalings are affine vector fields: any
    // other symmetry (eq. 16's) is not one this frame normalises, and trying
    // costs canonical forms of large rational functions.
    for w in s.w_ids {
        for &c in w {
            let r = nf.ctx.canon(c);
            if !r.denominator().is_constant() || r.numerator().total_degree() > 1 {
                return Ok(());
            }
        }
    }
    let names = nf.state.clone();
    let mut coords: Vec<Coord> = names
        .iter()
        .enumerate()
        .map(|(i, n)| Coord {
            expr: nf.ctx.symbol(n).id,
            text: n.clone(),
            angle: angle[i],
            plain: true,
        })
        .collect();
    let mut pending: Vec<usize> = (0..s.w_ids.len()).collect();
    let mut rotated = false;
    // Translations first, then rotations, then scalings: each normalised on
    // the coordinates the previous ones left.
    'outer: while !pending.is_empty() {
        check_deadline(s.opts, "the cross-section", modes.len())?;
        let mut acts = Vec::new();
        for &p in &pending {
            let a: Vec<RatFun> = coords
                .iter()
                .map(|c| {
                    let e = lie(nf, c.expr, &s.w_ids[p]);
                    nf.ctx.canon(e)
                })
                .collect();
            acts.push((p, classify(nf, &coords, &a, &s.w_ids[p])));
        }
        for want in 0..4 {
            for (p, act) in &acts {
                let Some(act) = act else { continue };
                let rank = match act {
                    Action::None => 0,
                    Action::Translation(_) => 1,
                    Action::Rotation(..) => 2,
                    Action::Scaling(_) => 3,
                };
                if rank != want {
                    continue;
                }
                let Some(next) = normalise(nf, &coords, act) else {
                    return Ok(());
                };
                rotated |= rank == 2;
                coords = next;
                pending.retain(|q| q != p);
                continue 'outer;
            }
        }
        // A symmetry whose action is not recognised: no frame.
        return Ok(());
    }
    if !rotated {
        return Ok(());
    }
    for c in coords {
        if modes.len() >= s.rank {
            break;
        }
        if c.plain && !c.angle {
            continue; // step 1 took the variables the symmetries leave alone
        }
        if indep.raises_rank(nf, c.expr)? && screen_mode(nf, s.w_ids, c.expr, s.opts.seed)? {
            let den = nf.ctx.canon(c.expr).denominator().clone();
            let domain = if c.angle {
                "everywhere (an angle, modulo 2 pi)".to_string()
            } else if den.is_constant() {
                "everywhere".into()
            } else {
                format!(
                    "where {} != 0 (off the cross-section's singular set)",
                    nf.ctx.poly_text(&den)
                )
            };
            modes.push(DerivedMode {
                name: if c.plain {
                    c.text.clone()
                } else {
                    fresh.next()
                },
                expr: c.expr,
                text: c.text,
                kind: ModeKind::CrossSection,
                angle: c.angle,
                domain,
            });
        }
    }
    Ok(())
}
