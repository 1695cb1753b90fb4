//! The joint projection of the reduced system along several unknown inputs
//! (docs/engine.md, "Modes with unknown inputs"): with `m'` unknown inputs
//! whose coefficients in some mode's derivative are not functions of the
//! modes, `m'` modes `K` with `B = [L_{g_j} m_k]` non-singular are paired
//! with them, and every field is projected at once: `g~ = G B^-1`, `F' = F -
//! G B^-1 (L_F m_K)`, under the inputs `w~ = B w + (L_F m_K) u_F`. Then
//! `L_{F'} m_K` is 0 and `L_{g~_a} m_{k_b}` is `delta_ab`, and the one-input
//! argument carries over: `[F', xi] = A xi + sum_j b_j g_j` gives `xi(L_{F'}
//! m_{k_b}) = -sum_j b_j L_{g_j} m_{k_b} = 0` for every `b`, so `B b = 0`
//! and `b = 0`: each `L_{F'} m_l` is invariant, a function of the modes.

use crate::derive::{lie_along, Derivation};
use obsan_expr::{Fp, FpEchelon, Id, SplitMix};
use obsan_model::NormalForm;

/// The modes paired with the unknown inputs `slots` (view input indices):
/// the first modes, in order, whose rows of `B` raise its rank at a random
/// point (a non-zero minor there: exact). `None` when fewer than `slots`
/// modes do at two points.
pub(crate) fn pair_modes(
    view: &mut NormalForm,
    d: &Derivation,
    slots: &[usize],
    seed: u64,
) -> Option<Vec<usize>> {
    let r = d.modes.len();
    let mut roots = Vec::with_capacity(r * slots.len());
    for m in &d.modes {
        for &s in slots {
            let g = view.fields[s].clone();
            roots.push(lie_along(view, m.expr, &g));
        }
    }
    for v in values_at_random_points(view, &roots, seed ^ 0x006a_6f69_6e74, 2) {
        let mut taken = FpEchelon::default();
        let mut k = Vec::new();
        for (i, row) in v.chunks(slots.len()).enumerate() {
            if taken.insert(row.to_vec()) {
                k.push(i);
                if k.len() == slots.len() {
                    return Some(k);
                }
            }
        }
    }
    None
}

/// The values of `roots` at `points` random F_p points drawn from `seed`; a
/// point where they cannot be evaluated (a pole) is skipped, so fewer
/// may come back.
pub(crate) fn values_at_random_points(
    nf: &mut NormalForm,
    roots: &[Id],
    seed: u64,
    points: usize,
) -> Vec<Vec<Fp>> {
    let mut rng = SplitMix(seed);
    let mut out = Vec::with_capacity(points);
    for _ in 0..points {
        // A root-free point when the roots have no joint value mod p (the
        // expressions that evaluate there avoid them, exactly).
        let pt = match nf.ctx.random_fp_point(&mut rng, &|_| None) {
            Ok(pt) => pt,
            Err(_) => match nf.ctx.random_fp_point_root_free(&mut rng, &|_| None) {
                Ok(pt) => pt,
                Err(_) => continue,
            },
        };
        if let Ok(v) = nf.ctx.eval_fp(roots, &pt) {
            out.push(v);
        }
    }
    out
}

/// `b` without its row `i` and column `j`.
fn minor(b: &[Vec<Id>], i: usize, j: usize) -> Vec<Vec<Id>> {
    b.iter()
        .enumerate()
        .filter(|(r, _)| *r != i)
        .map(|(_, row)| {
            row.iter()
                .enumerate()
                .filter(|(k, _)| *k != j)
                .map(|(_, &x)| x)
                .collect()
        })
        .collect()
}

/// The determinant of a small square matrix of expressions (Laplace along
/// the first row: `m'` is the number of unknown inputs, a handful).
fn det(view: &mut NormalForm, b: &[Vec<Id>]) -> Id {
    let n = b.len();
    if n == 1 {
        return b[0][0];
    }
    let mut terms = Vec::with_capacity(n);
    for c in 0..n {
        let m = det(view, &minor(b, 0, c));
        let t = view.ctx.mul(&[b[0][c], m]);
        terms.push(if c % 2 == 0 { t } else { view.ctx.neg(t) });
    }
    view.ctx.add(&terms)
}

/// `B^-1` by cofactors, `adj(B) / det(B)`, each entry in canonical form.
pub(crate) fn inverse(view: &mut NormalForm, b: &[Vec<Id>]) -> Vec<Vec<Id>> {
    let n = b.len();
    let dt = det(view, b);
    let mut inv = vec![vec![dt; n]; n];
    for (i, row) in b.iter().enumerate() {
        for (j, _) in row.iter().enumerate() {
            let cof = if n == 1 {
                view.ctx.int(1)
            } else {
                det(view, &minor(b, i, j))
            };
            let cof = if (i + j) % 2 == 0 {
                cof
            } else {
                view.ctx.neg(cof)
            };
            // adj(B)[j][i] = cofactor(i, j)
            let e = view.ctx.div(cof, dt);
            let c = view.ctx.canon(e);
            inv[j][i] = view.ctx.from_canonical(&c);
        }
    }
    inv
}

/// One projected input slot: its new field, the row of `B` (`L_{g_j}
/// m_{k_a}` per paired input) and the moved terms `L_F m_{k_a} u_F`.
pub(crate) struct Joint {
    pub(crate) mode: usize,
    pub(crate) row: Vec<Id>,
    pub(crate) moved: Vec<Id>,
}

/// Projects the view jointly along the inputs in `slots` (view input
/// indices), paired with the modes `k`, for the drift and known fields named
/// in `project` ("f0" or a known input's name). The slots' fields become
/// `G B^-1`; each slot's pieces are returned in order.
pub(crate) fn project(
    view: &mut NormalForm,
    d: &Derivation,
    slots: &[usize],
    k: &[usize],
    project: &[String],
) -> Vec<Joint> {
    let b: Vec<Vec<Id>> = k
        .iter()
        .map(|&ki| {
            slots
                .iter()
                .map(|&s| {
                    let g = view.fields[s].clone();
                    let e = lie_along(view, d.modes[ki].expr, &g);
                    let c = view.ctx.canon(e);
                    view.ctx.from_canonical(&c)
                })
                .collect()
        })
        .collect();
    let inv = inverse(view, &b);
    let gs: Vec<Vec<Id>> = slots.iter().map(|&s| view.fields[s].clone()).collect();
    let n = gs[0].len();
    // g~_a = sum_j g_j inv[j][a]
    let new_g: Vec<Vec<Id>> = (0..slots.len())
        .map(|a| {
            (0..n)
                .map(|i| {
                    let t: Vec<Id> = (0..slots.len())
                        .map(|j| view.ctx.mul(&[gs[j][i], inv[j][a]]))
                        .collect();
                    view.ctx.add(&t)
                })
                .collect()
        })
        .collect();
    let mut moved = vec![Vec::new(); slots.len()];
    for name in project {
        let f = if name == "f0" {
            view.f0.clone()
        } else {
            let Some(q) = view.inputs.iter().position(|x| x == name) else {
                continue;
            };
            view.fields[q].clone()
        };
        let alphas: Vec<Id> = k
            .iter()
            .map(|&ki| lie_along(view, d.modes[ki].expr, &f))
            .collect();
        let new: Vec<Id> = (0..n)
            .map(|i| {
                let mut t = vec![f[i]];
                for (a, &al) in alphas.iter().enumerate() {
                    let p = view.ctx.mul(&[new_g[a][i], al]);
                    t.push(view.ctx.neg(p));
                }
                view.ctx.add(&t)
            })
            .collect();
        let u = (name != "f0").then(|| view.ctx.symbol(name).id);
        for (a, &al) in alphas.iter().enumerate() {
            moved[a].push(match u {
                Some(u) => view.ctx.mul(&[al, u]),
                None => al,
            });
        }
        if name == "f0" {
            view.f0 = new;
        } else if let Some(q) = view.inputs.iter().position(|x| x == name) {
            view.fields[q] = new;
        }
    }
    for (a, &s) in slots.iter().enumerate() {
        view.fields[s] = new_g[a].clone();
    }
    b.into_iter()
        .zip(moved)
        .zip(k)
        .map(|((row, moved), &mode)| Joint { mode, row, moved })
        .collect()
}
