//! Lie derivatives and their gradients at a point of F_p, never built as
//! expressions (reconstruction.md section 1).
//!
//! For a word `(a_1, ..., a_k)` (`a_1` applied first) and the flows `Phi^a_t`
//! of the fields,
//!
//! ```text
//! L_{a_k} ... L_{a_1} h (x) = d^k / dt_1 ... dt_k  h(Phi^{a_1}_{t_1} o ... o Phi^{a_k}_{t_k}(x))  at t = 0
//! ```
//!
//! (`L_b L_a h(x) = d/ds (L_a h)(Phi^b_s x)` and `L_a g(y) = d/dt g(Phi^a_t y)`).
//! A run of one field merges (`Phi^a_s o Phi^a_t = Phi^a_{s+t}`), so a run of
//! length m is one variable truncated at degree m, and the derivative is m!
//! times a coefficient. Each flow is a truncated Taylor series computed by
//! Picard iteration (one order per pass) on the expression DAG: pass c only
//! adds the coefficients of degree c of each op (the lower ones, computed
//! from coefficients of the flow that were already exact, stay in the ops'
//! slots), so a product costs O(m^2) coefficient products per sweep for
//! the whole run, not O(m^3); [`LieJets::run_rows`] reads every shorter run
//! off one sweep. Every
//! coefficient also carries its first-order part in each state variable
//! (dual numbers), which is the gradient. Functions become series by their
//! Taylor expansions at the point (`exp`, `sin`/`cos` from the point's
//! values, `atan`, `atan2` by the angle-difference formulas, `log`, `sqrt` by
//! the binomial series): the same derivative rules as `diff.rs`, so the values
//! are those of the symbolic Lie derivatives at the point, exactly.
//!
//! ## Degree bound (Schwartz–Zippel)
//! Every number computed is a rational function of the random coordinates of
//! [`Ctx::random_fp_point`]. Alongside the values runs an abstract
//! interpretation of the same arithmetic, per grade (total degree in the t's,
//! plus one for a gradient part): a bound `Deg { n, e }` says the coefficient
//! is `P / prod_b B_b^e_b` with `deg P <= n`, where the `B_b` are *bases*:
//! the numerators of everything ever inverted (the value of a node raised to
//! a negative power, the argument of `log` and `sqrt`, `1 + u^2` of `atan u`,
//! `x^2 + y^2` of `atan2(y, x)`) and `1 + t^2` of each angle. Sums take the
//! largest exponent of each base (a common denominator), products add; the
//! inverse of a jet `a0 + N` is `sum_k (-N)^k / a0^(k+1)`, whose `1/a0` is
//! `prod B^e / P` with `P` a new base. Leaves follow [`degree_bounds`]:
//! symbols and atoms 1, sin/cos `2t/(1+t^2)`, a square root its radicand's
//! count. A minor of rows `N_i / D_i` is a polynomial of degree at most
//! `sum n_i` over the product of the `D_i`, which is non-zero at any point
//! where the evaluation succeeded (every base was inverted there), so the
//! minor vanishes at the point only where that numerator does.
//!
//! [`degree_bounds`]: crate::evaluate::degree_bounds

mod bound;
mod compile;
mod coords;
mod series;

pub use coords::{height_bounds, Coord};

use crate::eval::{BadPoint, FpPoint};
use crate::graph::{Id, Node};
use crate::memo::Ctx;
use crate::num::Fp;
use crate::poly::Var;
use bound::{Bounds, DJet};
use compile::{Bases, Compiler, Deg, Program};
use rustc_hash::FxHashMap;
use series::{Fl, Scratch, Shape, Vals};
use std::cell::RefCell;

/// Evaluates Lie derivatives of the outputs along words of fields, with
/// their gradients, at points of F_p.
#[derive(Clone, Debug)]
pub struct LieJets {
    n: usize,
    states: Vec<Var>,
    fields: Vec<Program>,
    outputs: Vec<Program>,
    bases: Bases,
    /// Bounds of inverses, referred to by index from the ops.
    inverses: Vec<Deg>,
    /// State variables each field moves (a structurally non-zero component).
    moves: Vec<Vec<bool>>,
    /// State variables each output and each field component depends on.
    out_support: Vec<Vec<bool>>,
    field_support: Vec<Vec<Vec<bool>>>,
    /// Buffers of the sweeps, kept across points and words.
    scratch: RefCell<Sweep>,
}

/// The gradient of one Lie derivative at a point, its value, and the
/// numerator degree bound of the row (see the module docs) when asked for.
#[derive(Clone, Debug)]
pub struct LieRow {
    pub value: Fp,
    pub gradient: Vec<Fp>,
    pub degree: Option<u64>,
}

impl LieJets {
    /// Compile the outputs `h` and the fields (one node per state variable
    /// each) over the state variables `states`.
    pub fn new(ctx: &Ctx, states: &[Var], fields: &[Vec<Id>], outputs: &[Id]) -> LieJets {
        let mut c = Compiler {
            ctx,
            states,
            bases: Bases::default(),
            inverses: Vec::new(),
            sin_base: FxHashMap::default(),
        };
        // Evaluated in their written forms (written.rs): the same functions,
        // often far fewer ops than the expanded canonical forms. Supports
        // and zero tests below stay on the canonical forms (exact).
        let fields_p: Vec<Program> = fields
            .iter()
            .map(|f| {
                let w: Vec<Id> = f.iter().map(|&x| ctx.written_form(x)).collect();
                c.compile(&w)
            })
            .collect();
        let outputs_p: Vec<Program> = outputs.iter().map(|&h| c.compile(&[h])).collect();
        let support = |id: Id| -> Vec<bool> {
            let mut s = vec![false; states.len()];
            for n in ctx.reachable(&[id]) {
                if let Node::Leaf(v) = ctx.node(n) {
                    if let Some(k) = states.iter().position(|x| x == v) {
                        s[k] = true;
                    }
                }
            }
            s
        };
        let moves = fields
            .iter()
            .map(|f| f.iter().map(|&x| !ctx.is_zero(x)).collect())
            .collect();
        let out_support = outputs.iter().map(|&h| support(h)).collect();
        let field_support = fields
            .iter()
            .map(|f| f.iter().map(|&x| support(x)).collect())
            .collect();
        LieJets {
            n: states.len(),
            states: states.to_vec(),
            fields: fields_p,
            outputs: outputs_p,
            bases: c.bases,
            inverses: c.inverses,
            moves,
            out_support,
            field_support,
            scratch: RefCell::new(Sweep::default()),
        }
    }

    /// The state variables `L_word h_output` may depend on, or `None` if it
    /// is structurally zero (some field of the word moves nothing it depends
    /// on): `supp(L_f g)` lies in `supp(g)` and the supports of the
    /// components `f_i`, `i` in `supp(g)`, that are not zero.
    pub fn support(&self, output: usize, word: &[usize]) -> Option<Vec<bool>> {
        let mut s = self.out_support[output].clone();
        for &a in word {
            let mut next = s.clone();
            let mut any = false;
            for (i, &si) in s.iter().enumerate() {
                if si && self.moves[a][i] {
                    any = true;
                    for (x, &y) in next.iter_mut().zip(&self.field_support[a][i]) {
                        *x |= y;
                    }
                }
            }
            if !any {
                return None;
            }
            s = next;
        }
        Some(s)
    }

    /// Bytes the sweep of `word` holds: the state series, their copy and the
    /// output's (`n` coefficients by `(n + 1)` gradient entries each, dense),
    /// and one slot per op of the largest program. Checked against the
    /// memory budget before a sweep ([`crate::limits::check_memory`]).
    pub fn sweep_bytes(&self, word: &[usize]) -> u128 {
        let mut size: u128 = 1;
        let mut run = 0u128;
        for (i, a) in word.iter().enumerate() {
            run += 1;
            if word.get(i + 1) != Some(a) {
                size = size.saturating_mul(run + 1);
                run = 0;
            }
        }
        let len = size.saturating_mul(self.n as u128 + 1);
        let ops = self
            .fields
            .iter()
            .chain(&self.outputs)
            .map(|p| p.ops.len())
            .max()
            .unwrap_or(0) as u128;
        len.saturating_mul(3 * self.n as u128 + 1 + ops)
            .saturating_mul(8)
    }

    /// `L_{word[k-1]} ... L_{word[0]} h_output` and its gradient at `point`,
    /// with the degree bound of the row if `track` (it does not depend on
    /// the point, and costs about as much as the values).
    pub fn row(
        &self,
        output: usize,
        word: &[usize],
        point: &FpPoint,
        track: bool,
    ) -> Result<LieRow, BadPoint> {
        let pos = self.sweep(output, word, point)?;
        let sw = self.scratch.borrow();
        let (sh, runs) = (&sw.shapes[pos].1, &sw.runs);
        let w = self.n + 1;
        let h = sw.h.as_slice();
        let top = sh.size - 1;
        let mut fact = Fp::ONE;
        for &(_, m) in runs {
            for i in 2..=m {
                fact = fact * Fp::new(i as u64);
            }
        }
        let degree = track.then(|| self.degree(output, runs, sh)).flatten();
        Ok(LieRow {
            value: h[top * w] * fact,
            gradient: h[top * w + 1..top * w + w]
                .iter()
                .map(|&g| g * fact)
                .collect(),
            degree,
        })
    }

    /// The rows of every prefix of `word` (lengths 0 to `word.len()`), from
    /// one jet: with the flows of the later runs at time 0 (the identity),
    /// the coefficient of `t_1^m_1 ... t_j^a` is the derivative along the
    /// prefix (runs 1..j-1 whole, a steps of run j), times `m_1! ... a!`.
    /// Same values as [`LieJets::row`] on each prefix; no degree bounds.
    pub fn prefix_rows(
        &self,
        output: usize,
        word: &[usize],
        point: &FpPoint,
    ) -> Result<Vec<LieRow>, BadPoint> {
        let pos = self.sweep(output, word, point)?;
        let sw = self.scratch.borrow();
        let (sh, runs) = (&sw.shapes[pos].1, &sw.runs);
        let h = sw.h.as_slice();
        let w = self.n + 1;
        let row_at = |idx: usize, fact: Fp| LieRow {
            value: h[idx * w] * fact,
            gradient: h[idx * w + 1..idx * w + w]
                .iter()
                .map(|&g| g * fact)
                .collect(),
            degree: None,
        };
        let mut out = vec![row_at(0, Fp::ONE)];
        let (mut base, mut fact) = (0usize, Fp::ONE);
        for (j, &(_, m)) in runs.iter().enumerate() {
            for a in 1..=m {
                fact = fact * Fp::new(a as u64);
                out.push(row_at(base + a * sh.strides[j], fact));
            }
            base += m * sh.strides[j];
        }
        Ok(out)
    }

    /// The one forward sweep: the series of `h_output` along the flows of
    /// `word`'s runs at `point`, left in the scratch (`h`, `runs`); returns
    /// the index of the word's shape there.
    fn sweep(&self, output: usize, word: &[usize], point: &FpPoint) -> Result<usize, BadPoint> {
        // A root-free point (no value for the roots): the programs read leaf
        // values directly, so refuse it whole rather than check each read.
        if point.has_forbidden() {
            return Err(BadPoint);
        }
        let mut guard = self.scratch.borrow_mut();
        let sw = &mut *guard;
        // Runs of one field, first applied first: (field, length).
        sw.runs.clear();
        for &a in word {
            match sw.runs.last_mut() {
                Some((f, m)) if *f == a => *m += 1,
                _ => sw.runs.push((a, 1)),
            }
        }
        sw.caps.clear();
        sw.caps.extend(sw.runs.iter().map(|r| r.1));
        let pos = match sw.shapes.iter().position(|(c, _)| *c == sw.caps) {
            Some(p) => p,
            None => {
                sw.shapes
                    .push((sw.caps.clone(), Shape::new(self.n, &sw.caps)));
                sw.shapes.len() - 1
            }
        };
        let Sweep {
            shapes,
            runs,
            x,
            x0f,
            xf,
            h,
            vals,
            flow_word,
            flow_point,
            flow_ok,
            ..
        } = sw;
        let sh = &shapes[pos].1;
        let len = sh.size * sh.w;
        let reuse = *flow_ok && flow_word.as_slice() == word && *flow_point == point.values;
        if !reuse {
            // Invalid until this flow is complete (a bad point leaves it so).
            *flow_ok = false;
            Self::flow(self, sh, runs, x, x0f, xf, vals, point)?;
            flow_word.clear();
            flow_word.extend_from_slice(word);
            flow_point.clone_from(&point.values);
            *flow_ok = true;
        }
        let ar = Vals {
            sh,
            v: sh.full(),
            fresh: sh.all(),
            len,
            point,
        };
        let prog = &self.outputs[output];
        ar.run(vals, prog, x, xf)?;
        let (hv, _) = ar.root(vals, prog.roots[0]);
        h.clear();
        h.extend_from_slice(hv);
        Ok(pos)
    }

    /// The flows of the word's runs at `point`, from the last applied
    /// (innermost) outwards, into `x` (series of the states) and `xf`.
    #[allow(clippy::too_many_arguments)]
    fn flow(
        &self,
        sh: &Shape,
        runs: &[(usize, usize)],
        x: &mut Vec<Fp>,
        x0f: &mut Vec<Fl>,
        xf: &mut Vec<Fl>,
        vals: &mut Scratch,
        point: &FpPoint,
    ) -> Result<(), BadPoint> {
        let len = sh.size * sh.w;
        // x + eps, then the flows from the last applied (innermost) outwards.
        x.clear();
        x.resize(self.n * len, Fp::ZERO);
        xf.clear();
        for (k, &v) in self.states.iter().enumerate() {
            x[k * len] = point.value(v);
            x[k * len + 1 + k] = Fp::ONE;
            xf.push(Fl {
                tconst: true,
                eps: true,
            });
        }
        for (j, &(field, m)) in runs.iter().enumerate().rev() {
            x0f.clear();
            x0f.extend_from_slice(xf);
            let prog = &self.fields[field];
            for pass in 0..m {
                // Picard pass `pass` makes the flow exact to t_j-degree
                // pass + 1; it needs the field to degree `pass` only, and
                // the field's coefficients of lower degree are those of the
                // previous pass (computed from the same, already exact,
                // coefficients of the flow), kept in the slots.
                let ar = Vals {
                    sh,
                    v: sh.view(j, pass),
                    fresh: sh.fresh(j, pass),
                    len,
                    point,
                };
                ar.run(vals, prog, x, xf)?;
                // x = x0 + int_0^{t_j} f(x): x0 has no positive t_j-degree.
                for (k, &r) in prog.roots.iter().enumerate() {
                    let (f, ff) = ar.root(vals, r);
                    let out = &mut x[k * len..(k + 1) * len];
                    let fi = ar.integrate_at(out, f, ff, j);
                    xf[k] = fi.join(x0f[k]);
                }
            }
        }
        Ok(())
    }

    /// The rows of `L_field^j h_output` for j = 0 to k (the prefixes of the
    /// word of k times `field`, [`LieJets::prefix_rows`]), with the degree
    /// bound of each when `track`: from one sweep of bounds when the
    /// programs are rational ([`bound`]'s `run_limit`), else one per row.
    pub fn run_rows(
        &self,
        output: usize,
        field: usize,
        k: usize,
        point: &FpPoint,
        track: bool,
    ) -> Result<Vec<LieRow>, BadPoint> {
        let word = vec![field; k];
        let mut rows = self.prefix_rows(output, &word, point)?;
        if track {
            let sh = Shape::new(self.n, &[k]);
            let limit = self
                .bounds(&sh)
                .run_limit(&self.fields[field], &self.outputs[output]);
            for (j, row) in rows.iter_mut().enumerate() {
                row.degree = match &limit {
                    Some(h) if j > 0 => h[j + 1].as_ref().map(|d| d.n),
                    _ => {
                        let runs: Vec<(usize, usize)> =
                            (j > 0).then_some((field, j)).into_iter().collect();
                        let caps: Vec<usize> = runs.iter().map(|r| r.1).collect();
                        self.degree(output, &runs, &Shape::new(self.n, &caps))
                    }
                };
            }
        }
        Ok(rows)
    }

    fn bounds<'s>(&'s self, sh: &'s Shape) -> Bounds<'s> {
        Bounds {
            sh,
            bases: &self.bases,
            inverses: &self.inverses,
        }
    }

    /// The numerator degree bound of the row of `h_output` along `runs`
    /// (structural: the same sweep on bounds, [`bound`]). One run of a
    /// rational field: every grade at its limit, as [`LieJets::run_rows`].
    fn degree(&self, output: usize, runs: &[(usize, usize)], sh: &Shape) -> Option<u64> {
        let b = self.bounds(sh);
        if let [(field, _)] = runs {
            if let Some(h) = b.run_limit(&self.fields[*field], &self.outputs[output]) {
                return h[sh.grades].as_ref().map(|d| d.n);
            }
        }
        let mut x: Vec<DJet> = (0..self.n).map(|_| b.state()).collect();
        for &(field, m) in runs.iter().rev() {
            let x0 = x.clone();
            for _ in 0..m {
                let f = b.run(&self.fields[field], &x);
                x = x0
                    .iter()
                    .zip(&f)
                    .map(|(a, f)| b.add(a, &b.integrate(f)))
                    .collect();
            }
        }
        let h = b.run(&self.outputs[output], &x);
        h[0].d.get(sh.grades).and_then(|d| d.as_ref()).map(|d| d.n)
    }
}

/// The state variables (indices into `states`) that some Lie derivative of
/// the `outputs` along the `fields` may depend on: those the outputs depend
/// on, closed under "component `i` of a field, for `i` reached, depends on
/// `j`". Every other variable has a zero column in every row of the
/// observability codistribution, exactly (the Lie derivative of a function
/// of the reached variables along a field only reads the field's reached
/// components), so it is unobservable with the symmetry `d/dx_j`. One
/// traversal of the graph with a shared visited set: the cost is the size of
/// what the outputs reach, not the number of variables.
pub fn reached_states(ctx: &Ctx, states: &[Var], fields: &[Vec<Id>], outputs: &[Id]) -> Vec<usize> {
    let index: FxHashMap<Var, usize> = states.iter().enumerate().map(|(k, &v)| (v, k)).collect();
    let mut seen: rustc_hash::FxHashSet<Id> = Default::default();
    let mut reached = vec![];
    let mut is_reached: FxHashMap<usize, ()> = FxHashMap::default();
    let mut stack: Vec<Id> = outputs.to_vec();
    while let Some(id) = stack.pop() {
        if !seen.insert(id) {
            continue;
        }
        if let Node::Leaf(v) = ctx.node(id) {
            if let Some(&k) = index.get(v) {
                if is_reached.insert(k, ()).is_none() {
                    reached.push(k);
                    stack.extend(fields.iter().filter_map(|f| f.get(k).copied()));
                }
            }
        }
        stack.extend(ctx.deps(id));
    }
    reached.sort_unstable();
    reached
}

/// The scratch of [`LieJets`]' sweeps.
#[derive(Clone, Debug, Default)]
struct Sweep {
    /// Shapes met so far, by their caps.
    shapes: Vec<(Vec<usize>, Shape)>,
    caps: Vec<usize>,
    runs: Vec<(usize, usize)>,
    x: Vec<Fp>,
    x0f: Vec<Fl>,
    xf: Vec<Fl>,
    /// The series of the output after the last sweep.
    h: Vec<Fp>,
    vals: Scratch,
    /// The word and point whose flow `x`, `xf` hold (`flow_ok`): a sweep of
    /// another output along the same word at the same point reuses it, so
    /// a level of the rank test computes each flow once for all outputs.
    flow_word: Vec<usize>,
    flow_point: Vec<Fp>,
    flow_ok: bool,
}
