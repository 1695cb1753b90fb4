//! Truncated Taylor series with first-order parts, evaluated in F_p in
//! place: every op writes one slot of an arena that is kept across points,
//! and temporaries come from a pool, so a sweep allocates nothing once warm.
//! Products accumulate unreduced in u128 and reduce once per coefficient.
//! The polynomial ops compute only the coefficients a Picard pass adds
//! ([`Vals::run`]); the others recompute their sub-box.

use super::compile::{Op, Program};
use crate::eval::{BadPoint, FpPoint};
use crate::num::{Fp, P};

/// The truncation box of a word: one variable per run, truncated at the
/// run's length (mixed radix, the first run fastest), and per coefficient
/// the value and one first-order part per state variable.
#[derive(Clone, Debug)]
pub(super) struct Shape {
    /// State variables + 1.
    pub(super) w: usize,
    pub(super) caps: Vec<usize>,
    pub(super) strides: Vec<usize>,
    pub(super) size: usize,
    /// The largest grade: the sum of the caps, plus one for a gradient part.
    pub(super) grades: usize,
    /// The total t-degree of each index (the grade of its value part).
    degree: Vec<u32>,
    /// The whole box, then per run j and cap c < caps[j] the sub-box with
    /// the runs before j at 0, run j at c and the later runs whole (see
    /// [`Shape::view`]).
    views: Vec<View>,
    /// Index in `views` of run j's first sub-box.
    first: Vec<usize>,
    /// Per view: the indices it adds to the previous sub-box of its run
    /// (all of its members for the whole box and for cap 0), ascending.
    fresh: Vec<Vec<u32>>,
}

/// A sub-box of a shape (a lower set of indices, so the indices outside it
/// span an ideal and truncating to it is a ring homomorphism): arithmetic
/// on it is exact for the coefficients inside and leaves zeros outside.
#[derive(Clone, Debug)]
pub(super) struct View {
    /// Indices inside, ascending (0 first).
    members: Vec<u32>,
    /// For each index i inside: the (j, i + j) with j and i + j inside, j
    /// ascending.
    table: Vec<Vec<(u32, u32)>>,
    /// For each index k inside: the (i, j) inside with i + j = k.
    by_k: Vec<Vec<(u32, u32)>>,
}

impl Shape {
    pub(super) fn new(n: usize, caps: &[usize]) -> Shape {
        let mut strides = Vec::with_capacity(caps.len());
        let mut size = 1;
        for &m in caps {
            strides.push(size);
            size *= m + 1;
        }
        let digits = |i: usize| -> Vec<usize> {
            caps.iter()
                .zip(&strides)
                .map(|(&m, &s)| (i / s) % (m + 1))
                .collect()
        };
        let all: Vec<Vec<usize>> = (0..size).map(digits).collect();
        let view = |sub: &[usize]| -> View {
            let inside = |i: usize| all[i].iter().zip(sub).all(|(a, m)| a <= m);
            let members: Vec<u32> = (0..size).filter(|&i| inside(i)).map(|i| i as u32).collect();
            let mut table = vec![Vec::new(); size];
            let mut by_k = vec![Vec::new(); size];
            for &i in &members {
                let i = i as usize;
                for &j in &members {
                    let j = j as usize;
                    let fits = all[i]
                        .iter()
                        .zip(&all[j])
                        .zip(sub)
                        .all(|((a, b), m)| a + b <= *m);
                    if fits {
                        table[i].push((j as u32, (i + j) as u32));
                        by_k[i + j].push((i as u32, j as u32));
                    }
                }
            }
            View {
                members,
                table,
                by_k,
            }
        };
        let mut views = vec![view(caps)];
        let mut fresh = vec![views[0].members.clone()];
        let mut first = Vec::with_capacity(caps.len());
        for j in 0..caps.len() {
            first.push(views.len());
            for c in 0..caps[j] {
                let mut sub = caps.to_vec();
                sub[..j].fill(0);
                sub[j] = c;
                let v = view(&sub);
                let new = v
                    .members
                    .iter()
                    .copied()
                    .filter(|&i| c == 0 || all[i as usize][j] == c)
                    .collect();
                fresh.push(new);
                views.push(v);
            }
        }
        let degree = all.iter().map(|d| d.iter().sum::<usize>() as u32).collect();
        Shape {
            w: n + 1,
            caps: caps.to_vec(),
            strides,
            size,
            grades: caps.iter().sum::<usize>() + 1,
            degree,
            views,
            first,
            fresh,
        }
    }

    /// The whole box.
    pub(super) fn full(&self) -> &View {
        &self.views[0]
    }

    /// The sub-box of Picard pass c (from 0) of run j: the flow of run j is
    /// computed while the earlier runs' variables are still absent (their
    /// digits 0), and pass c only needs the field's coefficients of t_j-degree
    /// at most c (they make the flow exact to degree c + 1).
    pub(super) fn view(&self, j: usize, c: usize) -> &View {
        &self.views[self.first[j] + c]
    }

    /// The indices of [`Shape::view`]`(j, c)` outside `view(j, c - 1)`:
    /// those of t_j-degree c (every index for c = 0).
    pub(super) fn fresh(&self, j: usize, c: usize) -> &[u32] {
        &self.fresh[self.first[j] + c]
    }

    /// Every index of the whole box, ascending.
    pub(super) fn all(&self) -> &[u32] {
        &self.fresh[0]
    }
}

/// Inverses of small integers, tabulated at compile time: a series
/// coefficient or an integration step would otherwise pay a Fermat inversion
/// (60 squarings) per use.
const SMALL: usize = 64;

const fn mul_p(a: u64, b: u64) -> u64 {
    let w = a as u128 * b as u128;
    let s = ((w as u64) & P) + (w >> 61) as u64;
    if s >= P {
        s - P
    } else {
        s
    }
}

const fn inv_p(a: u64) -> u64 {
    let (mut b, mut e, mut r) = (a, P - 2, 1u64);
    while e > 0 {
        if e & 1 == 1 {
            r = mul_p(r, b);
        }
        b = mul_p(b, b);
        e >>= 1;
    }
    r
}

/// `[0, 1/1, 1/2, ...]` (entry 0 unused).
const fn small_inverses() -> [u64; SMALL] {
    let mut inv = [0u64; SMALL];
    let mut k = 1;
    while k < SMALL {
        inv[k] = inv_p(k as u64);
        k += 1;
    }
    inv
}

static INVERSES: [u64; SMALL] = small_inverses();

pub(super) fn inv_small(k: u64) -> Fp {
    if (1..SMALL as u64).contains(&k) {
        return Fp(INVERSES[k as usize]);
    }
    #[allow(clippy::expect_used)]
    Fp::new(k)
        .inv()
        .expect("small positive integers are invertible mod p")
}

pub(super) fn atan_coeff(k: u64) -> Fp {
    if k.is_multiple_of(2) {
        Fp::ZERO
    } else if (k / 2).is_multiple_of(2) {
        inv_small(k)
    } else {
        -inv_small(k)
    }
}

/// `log(1 + M)`.
pub(super) fn log_coeff(k: u64) -> Fp {
    if k == 0 {
        Fp::ZERO
    } else if k % 2 == 1 {
        inv_small(k)
    } else {
        -inv_small(k)
    }
}

/// `sqrt(1 + M)`: binomial(1/2, k).
pub(super) fn sqrt_coeff(k: u64) -> Fp {
    let half = inv_small(2);
    (0..k).fold(Fp::ONE, |a, i| a * (half - Fp::new(i)) * inv_small(i + 1))
}

/// `(1 + M)^(1/q)`: binomial(1/q, k).
pub(super) fn root_coeff(q: u32, k: u64) -> Fp {
    let inv_q = inv_small(q as u64);
    (0..k).fold(Fp::ONE, |a, i| a * (inv_q - Fp::new(i)) * inv_small(i + 1))
}

/// What is structurally known of a series (the same at every point).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct Fl {
    /// Only monomial 0 may be non-zero.
    pub(super) tconst: bool,
    /// Some first-order part may be non-zero.
    pub(super) eps: bool,
}

impl Fl {
    pub(super) const CONST: Fl = Fl {
        tconst: true,
        eps: false,
    };
    pub(super) fn is_const(self) -> bool {
        self.tconst && !self.eps
    }
    /// Of a sum (or of a product: the same rule).
    pub(super) fn join(self, o: Fl) -> Fl {
        Fl {
            tconst: self.tconst && o.tconst,
            eps: self.eps || o.eps,
        }
    }
}

/// Buffers kept across points.
#[derive(Clone, Debug, Default)]
pub(super) struct Scratch {
    /// One slot per op of the program being run.
    vals: Vec<Fp>,
    flags: Vec<Fl>,
    tmp: Scratch2,
}

/// Temporaries: a pool of slots and the accumulator of products.
#[derive(Clone, Debug, Default)]
pub(super) struct Scratch2 {
    pool: Vec<Vec<Fp>>,
    acc: Vec<u128>,
}

/// Pairs of products summed unreduced between two folds of an accumulator:
/// a product of two values below p = 2^61 - 1 is below 2^122, so a folded
/// accumulator (below 2^68) plus 2 (LAZY - 1) = 62 products stays below
/// 2^128.
const LAZY: usize = 32;

/// `w mod p` up to a multiple of p, below 2^62: products are summed
/// unreduced (2^66 of them fit in a u128).
#[inline(always)]
fn fold(w: u128) -> u128 {
    (w & P as u128) + (w >> 61)
}

#[inline(always)]
fn reduce(y: u128) -> Fp {
    let y = (y & P as u128) + (y >> 61);
    let y = ((y & P as u128) + (y >> 61)) as u64;
    Fp(if y >= P { y - P } else { y })
}

/// The series arithmetic of one shape; slices are `size * w` long, and every
/// entry of a slot is written (zeros where structurally zero).
pub(super) struct Vals<'a> {
    pub(super) sh: &'a Shape,
    /// The sub-box computed (zeros outside).
    pub(super) v: &'a View,
    /// The indices of `v` not computed before: the polynomial ops (sums,
    /// products, inverses) compute only these and keep the rest of their
    /// slot, the others recompute the whole of `v` (see [`Vals::run`]).
    pub(super) fresh: &'a [u32],
    /// `size * w`.
    pub(super) len: usize,
    pub(super) point: &'a FpPoint,
}

impl Vals<'_> {
    fn take(&self, pool: &mut Vec<Vec<Fp>>) -> Vec<Fp> {
        let mut v = pool.pop().unwrap_or_default();
        v.resize(self.len, Fp::ZERO);
        v
    }

    pub(super) fn set_const(out: &mut [Fp], v: Fp) -> Fl {
        out.fill(Fp::ZERO);
        out[0] = v;
        Fl::CONST
    }

    fn scale(out: &mut [Fp], s: Fp) {
        for x in out.iter_mut() {
            *x = *x * s;
        }
    }

    /// `out = a b` (`out` apart from both).
    fn mul(&self, acc: &mut Vec<u128>, out: &mut [Fp], a: &[Fp], fa: Fl, b: &[Fp], fb: Fl) -> Fl {
        let (a, fa, b, fb) = if fb.tconst && !fa.tconst {
            (b, fb, a, fa)
        } else {
            (a, fa, b, fb)
        };
        let w = self.sh.w;
        acc.clear();
        acc.resize(self.len, 0);
        let ilim = if fa.tconst { 1 } else { self.v.members.len() };
        for &i in &self.v.members[..ilim] {
            let i = i as usize;
            let ai = &a[i * w..i * w + w];
            if ai.iter().all(|x| x.is_zero()) {
                continue;
            }
            let av = ai[0].0 as u128;
            for &(j, k) in &self.v.table[i] {
                let (j, k) = (j as usize, k as usize);
                if fb.tconst && j > 0 {
                    break;
                }
                let bj = &b[j * w..j * w + w];
                let bv = bj[0].0 as u128;
                let o = &mut acc[k * w..k * w + w];
                o[0] += fold(av * bv);
                if fb.eps && av != 0 {
                    for (x, y) in o[1..].iter_mut().zip(&bj[1..]) {
                        *x += fold(av * y.0 as u128);
                    }
                }
                if fa.eps && bv != 0 {
                    for (x, y) in o[1..].iter_mut().zip(&ai[1..]) {
                        *x += fold(y.0 as u128 * bv);
                    }
                }
            }
        }
        for (x, &y) in out.iter_mut().zip(acc.iter()) {
            *x = reduce(y);
        }
        fa.join(fb)
    }

    /// `out = 1 / a` coefficient by coefficient: with every coefficient a
    /// dual number (value and first-order parts), `b = 1/a` has `b_0 =
    /// 1/a_0` and `b_k = -b_0 sum_{i + j = k, i != 0} a_i b_j` (j < k).
    fn inv(&self, s: &mut Scratch2, out: &mut [Fp], a: &[Fp], fa: Fl) -> Result<Fl, BadPoint> {
        let i0 = a[0].inv().ok_or(BadPoint)?;
        if fa.is_const() {
            return Ok(Self::set_const(out, i0));
        }
        let w = self.sh.w;
        out.fill(Fp::ZERO);
        out[0] = i0;
        let m0 = -(i0 * i0);
        for q in 1..w {
            out[q] = a[q] * m0;
        }
        let acc = &mut s.acc;
        for &k in &self.v.members[1..] {
            let k = k as usize;
            acc.clear();
            acc.resize(w, 0);
            for &(i, j) in &self.v.by_k[k] {
                let (i, j) = (i as usize, j as usize);
                if i == 0 || fa.tconst {
                    continue;
                }
                let (ai, bj) = (&a[i * w..i * w + w], &out[j * w..j * w + w]);
                let (av, bv) = (ai[0].0 as u128, bj[0].0 as u128);
                acc[0] += fold(av * bv);
                for q in 1..w {
                    acc[q] += fold(av * bj[q].0 as u128) + fold(ai[q].0 as u128 * bv);
                }
            }
            // b_k = -(b_0 t) for the dual numbers b_0 and t.
            let t0 = reduce(acc[0]);
            let (b0, nb0) = (out[0], -out[0]);
            out[k * w] = nb0 * t0;
            for q in 1..w {
                let tq = reduce(acc[q]);
                out[k * w + q] = -(b0 * tq + out[q] * t0);
            }
        }
        Ok(fa)
    }

    /// `out[k] = a[k]` for the fresh k.
    fn copy_at(&self, out: &mut [Fp], a: &[Fp]) {
        let w = self.sh.w;
        for &k in self.fresh {
            let k = k as usize;
            out[k * w..k * w + w].copy_from_slice(&a[k * w..k * w + w]);
        }
    }

    /// The constant `v` at the fresh indices.
    fn const_at(&self, out: &mut [Fp], v: Fp) -> Fl {
        let w = self.sh.w;
        for &k in self.fresh {
            let k = k as usize;
            out[k * w..k * w + w].fill(Fp::ZERO);
            if k == 0 {
                out[0] = v;
            }
        }
        Fl::CONST
    }

    /// `out[k] = sum of the args at k` for the fresh k (`prev` the slots of
    /// the earlier ops, `flags` their flags).
    fn add_at(&self, out: &mut [Fp], cs: &[u32], prev: &[Fp], flags: &[Fl]) -> Fl {
        let (w, len) = (self.sh.w, self.len);
        let slot = |c: u32, k: usize| {
            let at = c as usize * len + k * w;
            &prev[at..at + w]
        };
        for &k in self.fresh {
            let k = k as usize;
            let o = &mut out[k * w..k * w + w];
            o.copy_from_slice(slot(cs[0], k));
            for &c in &cs[1..] {
                if k > 0 && flags[c as usize].tconst {
                    continue;
                }
                for (x, &y) in o.iter_mut().zip(slot(c, k)) {
                    *x = *x + y;
                }
            }
        }
        cs.iter()
            .fold(flags[cs[0] as usize], |a, &c| a.join(flags[c as usize]))
    }

    /// `out[k] = (a b)[k] = sum_{i + j = k} a_i b_j` (dual numbers) for the
    /// fresh k: a Picard pass adds one t-degree, so each coefficient of a
    /// product is computed once per sweep (O(k) for coefficient k, not the
    /// O(k^2) of recomputing the truncated product in every pass).
    fn mul_at(
        &self,
        acc: &mut Vec<u128>,
        out: &mut [Fp],
        a: &[Fp],
        fa: Fl,
        b: &[Fp],
        fb: Fl,
    ) -> Fl {
        let (a, fa, b, fb) = if fb.tconst && !fa.tconst {
            (b, fb, a, fa)
        } else {
            (a, fa, b, fb)
        };
        let w = self.sh.w;
        acc.clear();
        acc.resize(w, 0);
        let by_k = &self.sh.full().by_k;
        for &k in self.fresh {
            let k = k as usize;
            acc.fill(0);
            // With `a` t-constant only the pair (0, k) can be non-zero.
            let pairs: &[(u32, u32)] = if fa.tconst { &by_k[k][..1] } else { &by_k[k] };
            for (n, &(i, j)) in pairs.iter().enumerate() {
                let (i, j) = (i as usize, j as usize);
                if fb.tconst && j > 0 {
                    continue;
                }
                if n % LAZY == LAZY - 1 {
                    acc.iter_mut().for_each(|x| *x = fold(*x));
                }
                let (ai, bj) = (&a[i * w..i * w + w], &b[j * w..j * w + w]);
                let (av, bv) = (ai[0].0 as u128, bj[0].0 as u128);
                acc[0] += av * bv;
                if fb.eps && av != 0 {
                    for (x, y) in acc[1..].iter_mut().zip(&bj[1..]) {
                        *x += av * y.0 as u128;
                    }
                }
                if fa.eps && bv != 0 {
                    for (x, y) in acc[1..].iter_mut().zip(&ai[1..]) {
                        *x += y.0 as u128 * bv;
                    }
                }
            }
            for (x, &y) in out[k * w..k * w + w].iter_mut().zip(acc.iter()) {
                *x = reduce(y);
            }
        }
        fa.join(fb)
    }

    /// `out = 1 / a` at the fresh indices, by the recurrence of
    /// [`Vals::inv`] (index 0 first, then each from lower ones).
    fn inv_at(
        &self,
        acc: &mut Vec<u128>,
        out: &mut [Fp],
        a: &[Fp],
        fa: Fl,
    ) -> Result<Fl, BadPoint> {
        let w = self.sh.w;
        if fa.is_const() {
            let i0 = a[0].inv().ok_or(BadPoint)?;
            return Ok(self.const_at(out, i0));
        }
        let by_k = &self.sh.full().by_k;
        acc.clear();
        acc.resize(w, 0);
        for &k in self.fresh {
            let k = k as usize;
            if k == 0 {
                let i0 = a[0].inv().ok_or(BadPoint)?;
                out[0] = i0;
                let m0 = -(i0 * i0);
                for q in 1..w {
                    out[q] = a[q] * m0;
                }
                continue;
            }
            acc.fill(0);
            if !fa.tconst {
                for &(i, j) in &by_k[k] {
                    let (i, j) = (i as usize, j as usize);
                    if i == 0 {
                        continue;
                    }
                    let (ai, bj) = (&a[i * w..i * w + w], &out[j * w..j * w + w]);
                    let (av, bv) = (ai[0].0 as u128, bj[0].0 as u128);
                    acc[0] += fold(av * bv);
                    for q in 1..w {
                        acc[q] += fold(av * bj[q].0 as u128) + fold(ai[q].0 as u128 * bv);
                    }
                }
            }
            // b_k = -(b_0 t) for the dual numbers b_0 and t.
            let t0 = reduce(acc[0]);
            let b0 = out[0];
            out[k * w] = -(b0 * t0);
            for q in 1..w {
                let tq = reduce(acc[q]);
                out[k * w + q] = -(b0 * tq + out[q] * t0);
            }
        }
        Ok(fa)
    }

    /// `(E f)` for the Euler operator E (multiply each part by its grade:
    /// the t-degree, plus one for a first-order part), into `out`.
    fn euler(&self, out: &mut [Fp], a: &[Fp]) {
        let w = self.sh.w;
        for (k, &d) in self.sh.degree.iter().enumerate() {
            let (dv, dg) = (Fp(d as u64), Fp(d as u64 + 1));
            out[k * w] = a[k * w] * dv;
            for q in 1..w {
                out[k * w + q] = a[k * w + q] * dg;
            }
        }
    }

    /// `exp(n)` (`c` only) or `cos n`, `sin n` (`c` and `s`) for nilpotent
    /// `n`, by the Euler operator, a derivation: `E exp(n) = exp(n) E n`,
    /// `E cos n = -sin(n) E n`, `E sin n = cos(n) E n`. Coefficient by
    /// coefficient in increasing grade (E n has no grade-0 part, so each
    /// right-hand side only uses lower grades), divided by the grade.
    fn by_euler(
        &self,
        tmp: &mut Scratch2,
        c: &mut [Fp],
        mut s: Option<&mut [Fp]>,
        n: &[Fp],
        fnl: Fl,
    ) -> Fl {
        let w = self.sh.w;
        let mut en = self.take(&mut tmp.pool);
        self.euler(&mut en, n);
        c.fill(Fp::ZERO);
        c[0] = Fp::ONE;
        if let Some(s) = s.as_deref_mut() {
            s.fill(Fp::ZERO);
        }
        let trig = s.is_some();
        for &k in &self.v.members {
            let k = k as usize;
            let dk = self.sh.degree[k] as u64;
            // Value part (grade dk), then the first-order parts (dk + 1).
            for q in 0..w {
                let g = if q == 0 { dk } else { dk + 1 };
                if g == 0 {
                    continue;
                }
                let mut accc = [0u128; 2];
                for &(i, j) in &self.v.by_k[k] {
                    let (i, j) = (i as usize, j as usize);
                    if fnl.tconst && j > 0 {
                        continue;
                    }
                    let e = &en[j * w..j * w + w];
                    let (cx, sx) = (
                        &c[i * w..i * w + w],
                        s.as_deref().map(|s| &s[i * w..i * w + w]),
                    );
                    if q == 0 {
                        let ev = e[0].0 as u128;
                        accc[0] += fold(cx[0].0 as u128 * ev);
                        if let Some(sx) = sx {
                            accc[1] += fold(sx[0].0 as u128 * ev);
                        }
                    } else {
                        let (ev, eq) = (e[0].0 as u128, e[q].0 as u128);
                        accc[0] += fold(cx[0].0 as u128 * eq) + fold(cx[q].0 as u128 * ev);
                        if let Some(sx) = sx {
                            accc[1] += fold(sx[0].0 as u128 * eq) + fold(sx[q].0 as u128 * ev);
                        }
                    }
                }
                let ig = inv_small(g);
                if trig {
                    // E cos = -sin E n, E sin = cos E n.
                    c[k * w + q] = -(reduce(accc[1]) * ig);
                    if let Some(s) = s.as_deref_mut() {
                        s[k * w + q] = reduce(accc[0]) * ig;
                    }
                } else {
                    c[k * w + q] = reduce(accc[0]) * ig;
                }
            }
        }
        tmp.pool.push(en);
        fnl
    }

    /// `out = sum_k coeff(k) n^k` for nilpotent `n`, k up to the grades.
    fn series(
        &self,
        s: &mut Scratch2,
        out: &mut [Fp],
        n: &[Fp],
        fnl: Fl,
        coeff: &dyn Fn(u64) -> Fp,
    ) -> Fl {
        let g = self.sh.grades as u64;
        let mut acc = self.take(&mut s.pool);
        let mut fc = Self::set_const(&mut acc, coeff(g));
        for k in (0..g).rev() {
            fc = self.mul(&mut s.acc, out, n, fnl, &acc, fc);
            out[0] = out[0] + coeff(k);
            acc.copy_from_slice(out);
        }
        s.pool.push(acc);
        fc
    }

    /// `out[k + stride_v] = a[k] / (c + 1)` for the fresh k (t_v-degree
    /// c < cap): the new coefficients of `int_0^{t_v} a`. The rest of `out`
    /// is kept (before run v it is zero at every positive t_v-degree).
    pub(super) fn integrate_at(&self, out: &mut [Fp], a: &[Fp], fa: Fl, v: usize) -> Fl {
        let (w, st, m) = (self.sh.w, self.sh.strides[v], self.sh.caps[v]);
        for &k in self.fresh {
            let k = k as usize;
            let digit = (k / st) % (m + 1);
            if digit == m {
                continue;
            }
            let inv = inv_small(digit as u64 + 1);
            let o = &mut out[(k + st) * w..(k + st) * w + w];
            for (x, &y) in o.iter_mut().zip(&a[k * w..k * w + w]) {
                *x = y * inv;
            }
        }
        Fl {
            tconst: false,
            eps: fa.eps,
        }
    }

    /// `out = nil(a) * f`: the nilpotent part of `a` times the scalar `f`.
    fn nil_scaled(out: &mut [Fp], a: &[Fp], f: Fp) {
        for (x, &y) in out.iter_mut().zip(a) {
            *x = y * f;
        }
        out[0] = Fp::ZERO;
    }

    /// Runs `prog` on the state series `x` (`n` slots, flags `xf`); the
    /// values stay in `sc` (see [`Vals::root`]). Sums, products and
    /// inverses write only the `fresh` indices and read their arguments at
    /// lower ones: the caller runs the same program on the sub-boxes of one
    /// run in increasing order, starting with a `fresh` that is the whole
    /// sub-box, and changes `x` only at indices no pass has read yet.
    pub(super) fn run(
        &self,
        sc: &mut Scratch,
        prog: &Program,
        x: &[Fp],
        xf: &[Fl],
    ) -> Result<(), BadPoint> {
        let len = self.len;
        let nops = prog.ops.len();
        let Scratch { vals, flags, tmp } = sc;
        vals.resize(nops * len, Fp::ZERO);
        flags.clear();
        self.run_ops(tmp, vals, flags, prog, x, xf)
    }

    fn run_ops(
        &self,
        s: &mut Scratch2,
        vals: &mut [Fp],
        flags: &mut Vec<Fl>,
        prog: &Program,
        x: &[Fp],
        xf: &[Fl],
    ) -> Result<(), BadPoint> {
        let len = self.len;
        let pv = |v| self.point.value(v);
        for (i, op) in prog.ops.iter().enumerate() {
            let (prev, rest) = vals.split_at_mut(i * len);
            let out = &mut rest[..len];
            let at = |k: &u32| &prev[*k as usize * len..(*k as usize + 1) * len];
            let fat = |k: &u32| flags[*k as usize];
            let f = match op {
                Op::Const(v) => self.const_at(out, *v),
                Op::NoValue => return Err(BadPoint),
                Op::State(k) => {
                    self.copy_at(out, &x[k * len..(k + 1) * len]);
                    xf[*k]
                }
                Op::Fixed(v) => self.const_at(out, pv(*v)),
                Op::Add(cs) => self.add_at(out, cs, prev, flags),
                Op::Mul(a, b) => self.mul_at(&mut s.acc, out, at(a), fat(a), at(b), fat(b)),
                Op::Inv(b, _) => self.inv_at(&mut s.acc, out, at(b), fat(b))?,
                Op::Exp(v, arg, _) | Op::Sin(v, _, arg, _) | Op::Cos(v, _, arg, _)
                    if fat(arg).is_const() =>
                {
                    Self::set_const(out, pv(*v))
                }
                Op::Exp(v, arg, den) => {
                    let mut n = self.take(&mut s.pool);
                    Self::nil_scaled(&mut n, at(arg), inv_small(*den));
                    let fo = self.by_euler(s, out, None, &n, fat(arg));
                    Self::scale(out, pv(*v));
                    s.pool.push(n);
                    fo
                }
                Op::Sin(v, p, arg, den) | Op::Cos(v, p, arg, den) => {
                    let mut n = self.take(&mut s.pool);
                    let mut sn = self.take(&mut s.pool);
                    Self::nil_scaled(&mut n, at(arg), inv_small(*den));
                    let fo = self.by_euler(s, out, Some(&mut sn), &n, fat(arg));
                    let (me, other) = (pv(*v), pv(*p));
                    // sin(a0 + N) = s0 cos N + c0 sin N; cos(a0 + N) = c0 cos N - s0 sin N.
                    let other = if matches!(op, Op::Sin(..)) {
                        other
                    } else {
                        -other
                    };
                    for (x, &y) in out.iter_mut().zip(&sn) {
                        *x = *x * me + y * other;
                    }
                    s.pool.push(n);
                    s.pool.push(sn);
                    fo
                }
                Op::Atan(v, u, _) => {
                    let (uj, fu) = (at(u), fat(u));
                    if fu.is_const() {
                        Self::set_const(out, pv(*v))
                    } else {
                        // atan U - atan u0 = atan((U - u0) / (1 + u0 U)).
                        let mut den = self.take(&mut s.pool);
                        let mut z = self.take(&mut s.pool);
                        let mut t = self.take(&mut s.pool);
                        for (x, &y) in den.iter_mut().zip(uj) {
                            *x = y * uj[0];
                        }
                        den[0] = den[0] + Fp::ONE;
                        let fi = self.inv(s, &mut t, &den, fu)?;
                        den.copy_from_slice(uj);
                        den[0] = Fp::ZERO;
                        let fz = self.mul(&mut s.acc, &mut z, &den, fu, &t, fi);
                        let fo = self.series(s, out, &z, fz, &atan_coeff);
                        out[0] = out[0] + pv(*v);
                        s.pool.extend([den, z, t]);
                        fo
                    }
                }
                Op::Atan2(v, y, xx, _) => {
                    let (yj, xj, fy, fx) = (at(y), at(xx), fat(y), fat(xx));
                    if fy.is_const() && fx.is_const() {
                        Self::set_const(out, pv(*v))
                    } else {
                        // atan2(Y, X) - atan2(y0, x0) = atan((x0 Y - y0 X) / (x0 X + y0 Y)).
                        let (y0, x0) = (yj[0], xj[0]);
                        let mut num = self.take(&mut s.pool);
                        let mut den = self.take(&mut s.pool);
                        let mut t = self.take(&mut s.pool);
                        for (((a, b), &yv), &xv) in
                            num.iter_mut().zip(den.iter_mut()).zip(yj).zip(xj)
                        {
                            *a = x0 * yv - y0 * xv;
                            *b = x0 * xv + y0 * yv;
                        }
                        let fj = fy.join(fx);
                        // The numerator's value is x0 y0 - y0 x0 = 0 exactly.
                        num[0] = Fp::ZERO;
                        let fi = self.inv(s, &mut t, &den, fj)?;
                        let fz = self.mul(&mut s.acc, &mut den, &num, fj, &t, fi);
                        let fo = self.series(s, out, &den, fz, &atan_coeff);
                        out[0] = out[0] + pv(*v);
                        s.pool.extend([num, den, t]);
                        fo
                    }
                }
                Op::Log(v, u, _) | Op::Root(v, u, _, _) => {
                    let (uj, fu) = (at(u), fat(u));
                    if fu.is_const() {
                        Self::set_const(out, pv(*v))
                    } else {
                        let i0 = uj[0].inv().ok_or(BadPoint)?;
                        let mut m = self.take(&mut s.pool);
                        Self::nil_scaled(&mut m, uj, i0);
                        let fo = if matches!(op, Op::Log(..)) {
                            // log U = log u0 + log(1 + M)
                            let fo = self.series(s, out, &m, fu, &log_coeff);
                            out[0] = out[0] + pv(*v);
                            fo
                        } else {
                            // root_q U = r0 (1 + M)^(1/q)
                            let q = match op {
                                Op::Root(.., q) => *q,
                                _ => 2,
                            };
                            let fo = if q == 2 {
                                self.series(s, out, &m, fu, &sqrt_coeff)
                            } else {
                                self.series(s, out, &m, fu, &|k| root_coeff(q, k))
                            };
                            Self::scale(out, pv(*v));
                            fo
                        };
                        s.pool.push(m);
                        fo
                    }
                }
            };
            flags.push(f);
        }
        Ok(())
    }

    /// The values of op `k` after [`Vals::run`], with its flags.
    pub(super) fn root<'s>(&self, sc: &'s Scratch, k: u32) -> (&'s [Fp], Fl) {
        let k = k as usize;
        (&sc.vals[k * self.len..(k + 1) * self.len], sc.flags[k])
    }
}
