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
                Op::Log(_, u, idx) | Op::Sqrt(_, u, idx) => {
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
