//! The Schwartz–Zippel degree bound of a sweep (module docs of [`super`]):
//! the ops of [`super::series`] on per-grade bounds instead of values. It is
//! structural (the same at every point), so a caller computes it once per
//! word.

use super::compile::{Bases, Deg, Op, Program};
use super::series::{Fl, Shape};

/// Per grade, the bound of the coefficients of that grade (`None`:
/// structurally zero), and the structural flags of the values.
#[derive(Clone, Debug)]
pub(super) struct DJet {
    pub(super) d: Vec<Option<Deg>>,
    fl: Fl,
}

pub(super) struct Bounds<'a> {
    pub(super) sh: &'a Shape,
    pub(super) bases: &'a Bases,
    pub(super) inverses: &'a [Deg],
}

impl Bounds<'_> {
    fn zero(&self) -> DJet {
        DJet {
            d: vec![None; self.sh.grades + 1],
            fl: Fl::CONST,
        }
    }
    /// A state variable plus its first-order part: `x0 + eps`.
    pub(super) fn state(&self) -> DJet {
        let mut j = self.zero();
        j.d[0] = Some(Deg::poly(1));
        j.d[1] = Some(Deg::poly(0));
        j.fl.eps = true;
        j
    }
    fn constant(&self, d: Deg) -> DJet {
        let mut j = self.zero();
        j.d[0] = Some(d);
        j
    }
    fn join(&self, a: &Option<Deg>, b: &Option<Deg>) -> Option<Deg> {
        match (a, b) {
            (None, x) | (x, None) => x.clone(),
            (Some(x), Some(y)) => Some(self.bases.add(x, y)),
        }
    }
    pub(super) fn add(&self, a: &DJet, b: &DJet) -> DJet {
        DJet {
            d: a.d.iter().zip(&b.d).map(|(x, y)| self.join(x, y)).collect(),
            fl: a.fl.join(b.fl),
        }
    }
    fn scale(&self, a: &DJet, sd: &Deg) -> DJet {
        DJet {
            d: a.d
                .iter()
                .map(|x| x.as_ref().map(|x| self.bases.mul(x, sd)))
                .collect(),
            fl: a.fl,
        }
    }
    fn nil(&self, a: &DJet) -> DJet {
        let mut n = a.clone();
        n.d[0] = None;
        n
    }
    fn mul(&self, a: &DJet, b: &DJet) -> DJet {
        let (a, b) = if b.fl.tconst && !a.fl.tconst {
            (b, a)
        } else {
            (a, b)
        };
        let g = self.sh.grades;
        let mut d: Vec<Option<Deg>> = vec![None; g + 1];
        for (i, x) in a.d.iter().enumerate() {
            let Some(x) = x else { continue };
            for (j, y) in b.d.iter().enumerate().take(g + 1 - i) {
                let Some(y) = y else { continue };
                let p = Some(self.bases.mul(x, y));
                d[i + j] = self.join(&d[i + j], &p);
            }
        }
        DJet {
            d,
            fl: a.fl.join(b.fl),
        }
    }
    /// `1 / a`, where `inverses[idx]` bounds `1 / a0`.
    fn inv(&self, a: &DJet, idx: usize) -> DJet {
        let id = &self.inverses[idx];
        let c0 = self.constant(id.clone());
        if a.fl.is_const() {
            return c0;
        }
        let m = self.scale(&self.nil(a), id);
        let one = self.constant(Deg::poly(0));
        let mut acc = one.clone();
        for _ in 0..self.sh.grades {
            acc = self.add(&one, &self.mul(&m, &acc));
        }
        self.mul(&c0, &acc)
    }
    /// `sum_k c_k N^k` for nilpotent N: constant coefficients bound 0.
    fn series(&self, n: &DJet) -> DJet {
        let one = self.constant(Deg::poly(0));
        let mut acc = one.clone();
        for _ in 0..self.sh.grades {
            acc = self.add(&one, &self.mul(n, &acc));
        }
        acc
    }
    /// `int_0^{t_v} a`: one grade up.
    pub(super) fn integrate(&self, a: &DJet) -> DJet {
        let mut d = vec![None; self.sh.grades + 1];
        d[1..].clone_from_slice(&a.d[..self.sh.grades]);
        DJet {
            d,
            fl: Fl {
                tconst: false,
                eps: a.fl.eps,
            },
        }
    }

    /// The bounds of the roots of `prog` on the state series `x`.
    pub(super) fn run(&self, prog: &Program, x: &[DJet]) -> Vec<DJet> {
        let mut vals: Vec<DJet> = Vec::with_capacity(prog.ops.len());
        let p0 = Deg::poly(0);
        for (i, op) in prog.ops.iter().enumerate() {
            let d0 = &prog.deg0[i];
            let at = |k: &u32| &vals[*k as usize];
            let mut j = match op {
                Op::Const(_) | Op::NoValue | Op::Fixed(_) => self.constant(d0.clone()),
                Op::State(k) => x[*k].clone(),
                Op::Add(cs) => cs[1..]
                    .iter()
                    .fold(at(&cs[0]).clone(), |a, c| self.add(&a, at(c))),
                Op::Mul(a, b) => self.mul(at(a), at(b)),
                Op::Inv(b, idx) => self.inv(at(b), *idx),
                Op::Exp(_, arg, _) | Op::Sin(_, _, arg, _) | Op::Cos(_, _, arg, _)
                    if at(arg).fl.is_const() =>
                {
                    self.constant(d0.clone())
                }
                Op::Exp(_, arg, _) => {
                    let n = self.scale(&self.nil(at(arg)), &p0);
                    self.scale(&self.series(&n), d0)
                }
                Op::Sin(_, _, arg, _) | Op::Cos(_, _, arg, _) => {
                    let n = self.scale(&self.nil(at(arg)), &p0);
                    let (cs, sn) = (self.series(&n), self.series(&n));
                    self.add(&self.scale(&cs, d0), &self.scale(&sn, d0))
                }
                Op::Atan(_, u, idx) => {
                    let uj = at(u);
                    if uj.fl.is_const() {
                        self.constant(d0.clone())
                    } else {
                        let u0 = self.constant(prog.deg0[*u as usize].clone());
                        let one = self.constant(p0.clone());
                        let den = self.add(&one, &self.mul(&u0, uj));
                        let z = self.mul(&self.nil(uj), &self.inv(&den, *idx));
                        self.add(&self.constant(d0.clone()), &self.series(&z))
                    }
                }
                Op::Atan2(_, y, xx, idx) => {
                    let (yj, xj) = (at(y), at(xx));
                    if yj.fl.is_const() && xj.fl.is_const() {
                        self.constant(d0.clone())
                    } else {
                        let y0 = self.constant(prog.deg0[*y as usize].clone());
                        let x0 = self.constant(prog.deg0[*xx as usize].clone());
                        let num = self.add(&self.mul(&x0, yj), &self.mul(&y0, xj));
                        let den = self.add(&self.mul(&x0, xj), &self.mul(&y0, yj));
                        let z = self.mul(&self.nil(&num), &self.inv(&den, *idx));
                        self.add(&self.constant(d0.clone()), &self.series(&z))
                    }
                }
                Op::Log(_, u, idx) | Op::Root(_, u, idx, _) => {
                    let uj = at(u);
                    if uj.fl.is_const() {
                        self.constant(d0.clone())
                    } else {
                        let m = self.scale(&self.nil(uj), &self.inverses[*idx]);
                        let s = self.series(&m);
                        if matches!(op, Op::Log(..)) {
                            self.add(&self.constant(d0.clone()), &s)
                        } else {
                            self.scale(&s, d0)
                        }
                    }
                }
            };
            j.d[0] = Some(d0.clone());
            vals.push(j);
        }
        prog.roots
            .iter()
            .map(|&r| vals[r as usize].clone())
            .collect()
    }
}

/// Per op, its bounds by grade (`None`: structurally zero).
type Grades = Vec<Option<Deg>>;

impl Bounds<'_> {
    /// The bounds of `h` along one run of a field, every grade at once
    /// (grades `0..=sh.grades`), or `None` if a program holds an op other
    /// than sums, products and inverses.
    ///
    /// The Picard iteration of [`Bounds::run`] makes grade g of the flow
    /// final after g passes (grade g of an op reads only grades <= g of its
    /// arguments, and integration raises the grade), so the flow is
    /// computed one grade per pass from final lower grades, and each grade
    /// of each op once: O(grades^2) products per op instead of O(grades^3).
    /// Grade j + 1 of `h` is then the bound of every coefficient of that
    /// grade in the sweep of the run of length grades - 1, among them the
    /// gradient of the Lie derivative of order j: one sweep bounds every
    /// prefix of the run. (The per-word [`Bounds::run`] stops after as many
    /// passes as the word is long, where grade j + 1 is not yet final:
    /// another bound of the same coefficients, not always the same number.)
    pub(super) fn run_limit(&self, field: &Program, out: &Program) -> Option<Grades> {
        let supported = |p: &Program| {
            p.ops.iter().all(|op| {
                matches!(
                    op,
                    Op::Const(_)
                        | Op::NoValue
                        | Op::Fixed(_)
                        | Op::State(_)
                        | Op::Add(_)
                        | Op::Mul(..)
                        | Op::Inv(..)
                        | Op::Log(..)
                        | Op::Root(..)
                        | Op::Exp(..)
                        | Op::Sin(..)
                        | Op::Cos(..)
                )
            })
        };
        if !supported(field) || !supported(out) {
            return None;
        }
        let top = self.sh.grades;
        let n = field.roots.len();
        let mut x: Vec<Grades> = (0..n).map(|_| self.state().d).collect();
        let mut fv = Limit::new(field, top);
        for g in 0..top {
            fv.grade(self, &x, g);
            for (xs, &r) in x.iter_mut().zip(&field.roots) {
                // x = x0 + int f: x0 has grades 0 and 1 only.
                let f = &fv.vals[r as usize][g];
                xs[g + 1] = self.join(&xs[g + 1], f);
            }
        }
        let mut hv = Limit::new(out, top);
        for g in 0..=top {
            hv.grade(self, &x, g);
        }
        Some(hv.vals[out.roots[0] as usize].clone())
    }
}

/// The by-grade values of one program's ops ([`Bounds::run_limit`]).
struct Limit<'p> {
    prog: &'p Program,
    vals: Vec<Grades>,
    /// The series `sum_k (-M)^k` of each inverse (see [`Bounds::inv`]).
    aux: Vec<Grades>,
    /// Ops that do not depend on the state.
    konst: Vec<bool>,
}

impl<'p> Limit<'p> {
    fn new(prog: &'p Program, top: usize) -> Limit<'p> {
        let mut konst: Vec<bool> = Vec::with_capacity(prog.ops.len());
        for op in &prog.ops {
            let k = match op {
                Op::State(_) => false,
                Op::Add(cs) => cs.iter().all(|&c| konst[c as usize]),
                Op::Mul(a, b) => konst[*a as usize] && konst[*b as usize],
                Op::Inv(b, _) | Op::Log(_, b, _) | Op::Root(_, b, _, _) => konst[*b as usize],
                Op::Exp(_, a, _) | Op::Sin(_, _, a, _) | Op::Cos(_, _, a, _) => konst[*a as usize],
                Op::Atan(_, a, _) => konst[*a as usize],
                Op::Atan2(_, a, b, _) => konst[*a as usize] && konst[*b as usize],
                _ => true,
            };
            konst.push(k);
        }
        Limit {
            prog,
            vals: vec![vec![None; top + 1]; prog.ops.len()],
            aux: vec![vec![None; top + 1]; prog.ops.len()],
            konst,
        }
    }

    /// Grade `g` of every op, from grades `< g` of the ops and `<= g` of `x`.
    fn grade(&mut self, b: &Bounds, x: &[Grades], g: usize) {
        for (i, op) in self.prog.ops.iter().enumerate() {
            let d0 = &self.prog.deg0[i];
            if g == 0 {
                self.vals[i][0] = Some(d0.clone());
                if let Op::Inv(..)
                | Op::Log(..)
                | Op::Root(..)
                | Op::Exp(..)
                | Op::Sin(..)
                | Op::Cos(..) = op
                {
                    self.aux[i][0] = Some(Deg::poly(0));
                }
                continue;
            }
            let v = match op {
                Op::State(k) => x[*k][g].clone(),
                Op::Add(cs) => cs
                    .iter()
                    .fold(None, |a, &c| b.join(&a, &self.vals[c as usize][g])),
                Op::Mul(p, q) => {
                    let (p, q) = (&self.vals[*p as usize], &self.vals[*q as usize]);
                    (0..=g).fold(None, |acc, j| match (&p[j], &q[g - j]) {
                        (Some(u), Some(v)) => b.join(&acc, &Some(b.bases.mul(u, v))),
                        _ => acc,
                    })
                }
                Op::Inv(a, idx) if !self.konst[*a as usize] => {
                    // A_g = join_{j >= 1} (a_j / a0) A_{g-j}; the inverse is A / a0.
                    let id = &b.inverses[*idx];
                    let a = &self.vals[*a as usize];
                    let aux = &self.aux[i];
                    let s = (1..=g).fold(None, |acc, j| match (&a[j], &aux[g - j]) {
                        (Some(u), Some(v)) => {
                            b.join(&acc, &Some(b.bases.mul(&b.bases.mul(u, id), v)))
                        }
                        _ => acc,
                    });
                    let r = s.as_ref().map(|s| b.bases.mul(id, s));
                    self.aux[i][g] = s;
                    r
                }
                // The series `S = sum_k N^k` of [`Bounds::run`], `S = 1 + N S` by
                // grade as for the inverse: `log u = log u0 + S(N)` and
                // `root_q u = root_q(u0) S(N)` with `N = (u - u0)/u0`; `exp`,
                // `sin`, `cos` of `a`: `d0 S(N)` with `N = a - a0` (the sum of
                // the two series of sin and cos joins equal bounds).
                Op::Log(_, u, idx) | Op::Root(_, u, idx, _) if !self.konst[*u as usize] => {
                    let id = &b.inverses[*idx];
                    let u = &self.vals[*u as usize];
                    let s = Self::series_grade(b, &mut self.aux[i], g, |j| {
                        u[j].as_ref().map(|x| b.bases.mul(x, id))
                    });
                    match op {
                        Op::Log(..) => s,
                        _ => s.map(|s| b.bases.mul(&s, d0)),
                    }
                }
                Op::Exp(_, a, _) | Op::Sin(_, _, a, _) | Op::Cos(_, _, a, _)
                    if !self.konst[*a as usize] =>
                {
                    let a = &self.vals[*a as usize];
                    let s = Self::series_grade(b, &mut self.aux[i], g, |j| a[j].clone());
                    s.map(|s| b.bases.mul(&s, d0))
                }
                _ => None,
            };
            self.vals[i][g] = v;
        }
    }

    /// Grade `g >= 1` of `S = 1 + N S` (kept in `aux`, an op's row), from
    /// the grades `n(j)`, `1 <= j <= g`, of the nilpotent `N`.
    fn series_grade(
        b: &Bounds,
        aux: &mut [Option<Deg>],
        g: usize,
        n: impl Fn(usize) -> Option<Deg>,
    ) -> Option<Deg> {
        let s = (1..=g).fold(None, |acc, j| match (n(j), &aux[g - j]) {
            (Some(u), Some(v)) => b.join(&acc, &Some(b.bases.mul(&u, v))),
            _ => acc,
        });
        aux[g] = s.clone();
        s
    }
}
