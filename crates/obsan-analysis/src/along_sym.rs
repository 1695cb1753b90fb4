//! Naming what a degenerate window loses: the linear relations its recorded
//! inputs satisfy, the model restricted to the fields those inputs span, the
//! exact symmetries of that restricted model (obsan's own `symmetries`)
//! evaluated at the window's state, and their subspace angles to the
//! window's numerical kernel.
//!
//! The inputs of a window span an affine set; the vectors `(1, u_j)` span a
//! subspace `V` of R^{m+1}, and by multilinearity the Lie derivatives along
//! the fields `f(u_j) = f0 + sum_i f_i u_{j,i}` span what the words over the
//! fields `g = c_0 f0 + sum c_i f_i`, c in a basis of V, span (the
//! codistribution of eq. 16 for the restricted system). A circle of eq. 17
//! (`wL = q wR`) gives `V = span{(1, 0, 0), (0, 1, q)}`, a standstill
//! `V = span{(1, 0, ..., 0)}`: the drift alone.

use crate::along::AlongWindow;
use crate::along_linalg::{max_principal_angle, orthonormal, rationalise, svd};
use crate::rank::{rank, AnalysisError, RankOptions};
use crate::symmetry::{symmetries_with, Route, SymmetryOptions};
use obsan_expr::{Id, Tape, Q};
use obsan_model::NormalForm;
use std::collections::HashMap;
use std::time::Instant;

/// Relative level below which a singular value of the column-scaled input
/// samples `(1, u)` is a relation: recorded inputs are decimal text with
/// at least ten significant digits (or exact, like MRCLAM's zeros), so a
/// relation that holds to 1e-9 of the inputs' scale is one of the record.
pub const INPUT_REL_TOL: f64 = 1e-9;

/// The inputs' linear structure in one window.
#[derive(Clone, Debug, PartialEq)]
pub struct InputSpan {
    /// Relations `c_0 + sum c_i u_i = 0` the window's inputs satisfy, each
    /// over `(1, u_1, ..., u_m)`, reduced (the last input with a non-zero
    /// coefficient has coefficient 1 and appears in no other relation).
    pub relations: Vec<Vec<f64>>,
    /// A basis of V in reduced echelon form, rationalised: the restricted
    /// system's fields are `sum_i c_i F_i` (F_0 = f0).
    pub basis: Vec<Vec<Q>>,
}

/// The relations and span of input rows `(1, u)`.
pub fn input_span(rows: &[Vec<f64>], m: usize) -> InputSpan {
    let w = m + 1;
    let scale: Vec<f64> = (0..w)
        .map(|j| {
            let s = rows.iter().map(|r| r[j].abs()).fold(0.0, f64::max);
            if s > 0.0 {
                s
            } else {
                1.0
            }
        })
        .collect();
    let scaled: Vec<Vec<f64>> = rows
        .iter()
        .map(|r| r.iter().zip(&scale).map(|(x, s)| x / s).collect())
        .collect();
    let (s, v) = svd(&scaled, w);
    let s1 = s.first().copied().unwrap_or(0.0);
    let keep = s.iter().filter(|&&x| x > INPUT_REL_TOL * s1).count();
    let span: Vec<Vec<f64>> = v[..keep]
        .iter()
        .map(|x| x.iter().zip(&scale).map(|(a, s)| a * s).collect())
        .collect();
    let rels: Vec<Vec<f64>> = v[keep..]
        .iter()
        .map(|x| x.iter().zip(&scale).map(|(a, s)| a / s).collect())
        .collect();
    let order_rel: Vec<usize> = (0..w).rev().collect();
    let order_span: Vec<usize> = (0..w).collect();
    let relations = rref(rels, &order_rel);
    let basis = rref(span, &order_span)
        .iter()
        .map(|r| {
            r.iter()
                .map(|&x| rationalise(x, 1e-9 * x.abs().max(1.0)).unwrap_or_else(Q::zero))
                .collect()
        })
        .collect();
    InputSpan { relations, basis }
}

/// Reduced row echelon form, pivots sought in the column order `order`.
fn rref(mut rows: Vec<Vec<f64>>, order: &[usize]) -> Vec<Vec<f64>> {
    let mut r = 0;
    for &c in order {
        if r == rows.len() {
            break;
        }
        let Some(p) =
            (r..rows.len()).max_by(|&a, &b| rows[a][c].abs().total_cmp(&rows[b][c].abs()))
        else {
            break;
        };
        if rows[p][c].abs() < 1e-12 {
            continue;
        }
        rows.swap(r, p);
        let piv = rows[r][c];
        for x in rows[r].iter_mut() {
            *x /= piv;
        }
        rows[r][c] = 1.0;
        for i in 0..rows.len() {
            if i != r {
                let f = rows[i][c];
                if f != 0.0 {
                    let pr = rows[r].clone();
                    for (x, y) in rows[i].iter_mut().zip(&pr) {
                        *x -= f * y;
                    }
                    rows[i][c] = 0.0;
                }
            }
        }
        r += 1;
    }
    for row in rows.iter_mut() {
        for x in row.iter_mut() {
            if x.abs() < 1e-12 {
                *x = 0.0;
            }
        }
    }
    rows
}

/// The exact symmetries of the restricted model, compiled for evaluation at
/// any state.
pub(crate) struct Restricted {
    /// Generic rank of the restricted model (the rank test's).
    pub rank: usize,
    /// Symmetry vectors as tapes over the state (one output per component),
    /// and the unreached variables (each `d/dx` a symmetry).
    tape: Option<Tape>,
    vectors: usize,
    free: Vec<usize>,
    n: usize,
    /// The symmetry basis was proved exactly (else: with its random bound).
    pub exact: bool,
}

impl Restricted {
    /// The symmetry basis at `x` (state order), one vector each.
    pub fn at(&self, x: &[f64]) -> Vec<Vec<f64>> {
        let mut out = Vec::new();
        if let Some(t) = &self.tape {
            let v = t.eval(x);
            for k in 0..self.vectors {
                out.push(v[k * self.n..(k + 1) * self.n].to_vec());
            }
        }
        for &j in &self.free {
            let mut e = vec![0.0; self.n];
            e[j] = 1.0;
            out.push(e);
        }
        out
    }
}

/// The model restricted to the fields of `span` and the outputs `seen`.
fn restrict(nf: &NormalForm, span: &InputSpan, seen: &[bool]) -> NormalForm {
    let mut r = nf.clone();
    r.outputs = nf
        .outputs
        .iter()
        .zip(seen)
        .filter(|(_, &s)| s)
        .map(|(o, _)| o.clone())
        .collect();
    let m = nf.inputs.len();
    if span.basis.len() > m {
        return r; // the inputs span every field: no restriction
    }
    let nd = nf.n_dynamic;
    let mut all: Vec<Vec<Id>> = vec![nf.f0.clone()];
    all.extend(nf.fields.iter().cloned());
    let mut fields = Vec::new();
    for c in &span.basis {
        let mut g = Vec::with_capacity(nf.f0.len());
        for k in 0..nf.f0.len() {
            let mut terms = Vec::new();
            for (ci, f) in c.iter().zip(&all) {
                if !ci.is_zero() && k < nd {
                    let q = r.ctx.num(ci.clone());
                    terms.push(r.ctx.mul(&[q, f[k]]));
                }
            }
            let s = if terms.is_empty() {
                r.ctx.zero()
            } else {
                r.ctx.add(&terms)
            };
            g.push(s);
        }
        fields.push(g);
    }
    let zero = r.ctx.zero();
    r.f0 = vec![zero; nf.f0.len()];
    r.inputs = (1..=fields.len()).map(|i| format!("nu{i}")).collect();
    r.input_vars = nf.input_vars[..fields.len()].to_vec();
    r.fields = fields;
    r.restriction = Some("the window's inputs".into());
    r
}

/// The restricted model's rank and symmetries, cached by span and outputs.
#[derive(Default)]
pub(crate) struct Cache {
    map: HashMap<String, Restricted>,
}

impl Cache {
    pub fn get(
        &mut self,
        nf: &NormalForm,
        span: &InputSpan,
        seen: &[bool],
        deadline: Option<Instant>,
    ) -> Result<&Restricted, AnalysisError> {
        let key = format!("{:?}|{:?}", span.basis, seen);
        if !self.map.contains_key(&key) {
            let value = solve(nf, span, seen, deadline)?;
            self.map.insert(key.clone(), value);
        }
        self.map
            .get(&key)
            .ok_or_else(|| AnalysisError::Invalid("symmetry cache".into()))
    }
}

fn solve(
    nf: &NormalForm,
    span: &InputSpan,
    seen: &[bool],
    deadline: Option<Instant>,
) -> Result<Restricted, AnalysisError> {
    let n = nf.state.len();
    let mut r = restrict(nf, span, seen);
    if r.outputs.is_empty() {
        return Ok(Restricted {
            rank: 0,
            tape: None,
            vectors: 0,
            free: (0..n).collect(),
            n,
            exact: true,
        });
    }
    let rep = rank(
        &mut r,
        RankOptions {
            seed: 1,
            deadline,
            progress: None,
        },
    )?;
    let sym = symmetries_with(
        &mut r,
        &rep,
        &SymmetryOptions {
            deadline,
            route: Route::default(),
        },
    )?;
    let mut roots = Vec::new();
    for v in &sym.vectors {
        for c in v {
            roots.push(r.ctx.from_canonical(c));
        }
    }
    let tape = if roots.is_empty() {
        None
    } else {
        Some(
            Tape::compile(&r.ctx, &roots, &crate::along::tape_vars(&r)).map_err(|e| {
                AnalysisError::Invalid(format!("symmetry evaluation: '{}' unbound", e.0))
            })?,
        )
    };
    Ok(Restricted {
        rank: rep.rank,
        tape,
        vectors: sym.vectors.len(),
        free: sym.free.clone(),
        n,
        exact: sym.exact,
    })
}

/// How a window's kernel compares with the restricted model's symmetries.
#[derive(Clone, Debug)]
pub struct SymmetryMatch {
    /// Generic rank of the model restricted to the window's inputs and outputs.
    pub restricted_rank: usize,
    /// The symmetry basis at the window's state.
    pub vectors: Vec<Vec<f64>>,
    /// Per symmetry vector: its angle (radians) to the window's kernel.
    pub angles: Vec<f64>,
    /// Largest principal angle of the kernel into the symmetries' span, and
    /// of the symmetries into the kernel.
    pub kernel_to_symmetries: f64,
    pub symmetries_to_kernel: f64,
    /// Wedin's bound on the computed kernel's angle to the exact one:
    /// asin(tolerance / sigma_rank).
    pub angle_bound: f64,
    /// Both angles within the bound: the lost directions are exactly the
    /// restricted model's symmetries.
    pub matches: bool,
    pub exact: bool,
}

/// Compare a window's kernel with the symmetries.
pub(crate) fn compare(w: &AlongWindow, consts: &[f64], sym: &Restricted) -> SymmetryMatch {
    let mut point = w.state.clone();
    point.extend(consts);
    let vectors = sym.at(&point);
    let k = orthonormal(&w.kernel, 1e-12);
    let s = orthonormal(&vectors, 1e-9);
    let angles = vectors
        .iter()
        .map(|v| max_principal_angle(&orthonormal(std::slice::from_ref(v), 0.0), &k))
        .collect();
    let kernel_to_symmetries = max_principal_angle(&k, &s);
    let symmetries_to_kernel = max_principal_angle(&s, &k);
    let srank = if w.rank == 0 {
        f64::INFINITY
    } else {
        w.singular_values[w.rank - 1]
    };
    let angle_bound = (w.tolerance / srank).min(1.0).asin();
    // A floor for rounding in the angle computation itself.
    let lim = angle_bound.max(1e-7);
    SymmetryMatch {
        restricted_rank: sym.rank,
        matches: kernel_to_symmetries <= lim && symmetries_to_kernel <= lim,
        vectors,
        angles,
        kernel_to_symmetries,
        symmetries_to_kernel,
        angle_bound,
        exact: sym.exact,
    }
}
