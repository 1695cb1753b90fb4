//! The workspace's one dense elimination over a prime field: a basis of row
//! vectors kept in reduced row echelon form, grown one row at a time.
//!
//! Every rank, null space, membership test and linear solve modulo a prime
//! in obsan is this type (the rank test's codistribution, the symmetry and
//! mode searches, reconstruction's interpolation systems, Gröbner minimal
//! polynomials). It is generic over the field so that the engine's
//! Mersenne-prime `Fp` (shift-and-add reduction) and the residues modulo any
//! prime below 2^63 ([`Zp`]) share it at full speed.
//!
//! Reduced form (each pivot column zero in every other row) makes the
//! result of [`Echelon::reduce`] independent of the rows' order, and the
//! reduced echelon form of a row space is unique, so a null space or a
//! solution does not depend on the order in which rows were inserted.

use std::fmt::Debug;

use crate::field;

/// The arithmetic of a prime field, as the elimination needs it. `self` is
/// the field (its modulus, or nothing for a fixed prime).
pub trait PrimeField: Copy + Send + Sync {
    /// An element, always reduced.
    type Elem: Copy + PartialEq + Debug + Send + Sync;
    fn zero(self) -> Self::Elem;
    fn one(self) -> Self::Elem;
    fn sub(self, a: Self::Elem, b: Self::Elem) -> Self::Elem;
    fn mul(self, a: Self::Elem, b: Self::Elem) -> Self::Elem;
    /// The inverse; `None` for zero.
    fn inv(self, a: Self::Elem) -> Option<Self::Elem>;
    /// `x -= c y` entrywise (the elimination's inner loop; a field may
    /// precompute something per `c`).
    #[inline]
    fn sub_scaled(self, x: &mut [Self::Elem], c: Self::Elem, y: &[Self::Elem]) {
        for (a, b) in x.iter_mut().zip(y) {
            *a = self.sub(*a, self.mul(c, *b));
        }
    }
    /// `x *= c` entrywise.
    #[inline]
    fn scale(self, x: &mut [Self::Elem], c: Self::Elem) {
        for a in x.iter_mut() {
            *a = self.mul(*a, c);
        }
    }
    /// `-(a . b)` (a field may sum the products before reducing them).
    #[inline]
    fn neg_dot(self, a: &[Self::Elem], b: &[Self::Elem]) -> Self::Elem {
        a.iter().zip(b).fold(self.zero(), |s, (&x, &y)| {
            if y == self.zero() {
                s
            } else {
                self.sub(s, self.mul(x, y))
            }
        })
    }
    /// `v` reduced by `rows` in row echelon form, sorted by pivot (each 1
    /// at its pivot and 0 before it): in order, each row times `v`'s entry
    /// at its pivot is subtracted ([`RowEchelon::insert`]).
    fn reduce_sorted(self, v: &mut [Self::Elem], rows: &[(usize, Vec<Self::Elem>)]) {
        for (p, r) in rows {
            let c = v[*p];
            if c != self.zero() {
                self.sub_scaled(&mut v[*p..], c, &r[*p..]);
            }
        }
    }
    /// Each of `vs` reduced by `rows` as [`PrimeField::reduce_sorted`]
    /// does; a field may interleave them so that each row is read once for
    /// the whole block ([`RowEchelon::insert_all`]).
    fn reduce_block(self, vs: &mut [Vec<Self::Elem>], rows: &[(usize, Vec<Self::Elem>)]) {
        for v in vs {
            self.reduce_sorted(v, rows);
        }
    }
}

/// The field of residues `0..p` modulo a prime `p < 2^63`, with this crate's
/// arithmetic ([`crate::fp`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Zp(pub u64);

impl PrimeField for Zp {
    type Elem = u64;
    #[inline]
    fn zero(self) -> u64 {
        0
    }
    #[inline]
    fn one(self) -> u64 {
        1
    }
    #[inline]
    fn sub(self, a: u64, b: u64) -> u64 {
        field::sub(a, b, self.0)
    }
    #[inline]
    fn mul(self, a: u64, b: u64) -> u64 {
        field::mul(a, b, self.0)
    }
    fn inv(self, a: u64) -> Option<u64> {
        field::inv(a, self.0)
    }
    #[inline]
    fn sub_scaled(self, x: &mut [u64], c: u64, y: &[u64]) {
        let s = field::Shoup::new(c, self.0);
        for (a, &b) in x.iter_mut().zip(y) {
            *a = field::sub(*a, s.times(b), self.0);
        }
    }
    #[inline]
    fn scale(self, x: &mut [u64], c: u64) {
        let s = field::Shoup::new(c, self.0);
        for a in x.iter_mut() {
            *a = s.times(*a);
        }
    }
    /// The products summed in `u128`, brought back every `max_adds` of
    /// them (one remainder at the end, not one per product: the null
    /// space's back-substitution was a fifth of a kernel's time).
    fn neg_dot(self, a: &[u64], b: &[u64]) -> u64 {
        let (max_adds, shrink) = Shrink::new(self.0);
        let mut acc = 0u128;
        for (xs, ys) in a.chunks(max_adds).zip(b.chunks(max_adds)) {
            acc = shrink.one(acc);
            for (&x, &y) in xs.iter().zip(ys) {
                acc += u128::from(x) * u128::from(y);
            }
        }
        let s = field::Rem128::new(self.0).reduce(acc);
        if s == 0 {
            0
        } else {
            self.0 - s
        }
    }
    /// Delayed reduction ([`reduce_delayed`], or [`reduce_delayed52`] on
    /// AVX-512 IFMA for a prime below [`IFMA_BOUND`]) of one vector.
    fn reduce_sorted(self, v: &mut [u64], rows: &[(usize, Vec<u64>)]) {
        if self.0 < IFMA_BOUND && obsan_simd::ifma() {
            return reduce_delayed52(&mut [v], rows, self.0);
        }
        let (max_adds, shrink) = Shrink::new(self.0);
        let m = field::Rem128::new(self.0);
        reduce_delayed(
            &mut [v],
            rows,
            self.0,
            max_adds,
            |a| shrink.one(a),
            |a| m.reduce(a),
        );
    }
    /// [`reduce_delayed`], row-major: each row of the basis is read once
    /// and applied to every vector of the block while it sits in cache (one
    /// vector at a time streams the whole basis from memory per vector:
    /// SIWR_orig's 771-column kernels, 4.7 MB). On AVX-512 IFMA, for a
    /// prime below [`IFMA_BOUND`], [`reduce_delayed52`].
    fn reduce_block(self, vs: &mut [Vec<u64>], rows: &[(usize, Vec<u64>)]) {
        if self.0 < IFMA_BOUND && obsan_simd::ifma() {
            return reduce_delayed52(vs, rows, self.0);
        }
        let (max_adds, shrink) = Shrink::new(self.0);
        let m = field::Rem128::new(self.0);
        reduce_delayed(
            vs,
            rows,
            self.0,
            max_adds,
            |a| shrink.one(a),
            |a| m.reduce(a),
        );
    }
}

/// Field elements that are residues `0..p`, `p < 2^63`, for
/// [`reduce_delayed`] (this crate's `u64`, obsan-expr's `Fp`).
pub trait Residue: Copy {
    fn residue(self) -> u64;
    fn of_residue(x: u64) -> Self;
}

impl Residue for u64 {
    #[inline]
    fn residue(self) -> u64 {
        self
    }
    #[inline]
    fn of_residue(x: u64) -> u64 {
        x
    }
}

/// Each of `vs` reduced by `rows` (sorted by pivot, each 1 at its pivot and
/// 0 at the earlier rows' pivots) with delayed reduction: the entries are
/// summed in `u128` (each product below `(p - 1)^2`) and brought back by
/// `shrink` (same residue, below a bound the caller's `max_adds` leaves
/// room above) before `max_adds` products pile up, not reduced once per
/// product; each row's multiplier is reduced (`full`, to `0..p`) when its
/// pivot is reached (the rows before it never touch that column again).
/// Row-major: each row is applied to the whole block while it sits in
/// cache. Rows go [`GROUP`] at a time: their multipliers first (each
/// row's pivot entry as the rows before it in the group leave it, on the
/// pivot columns only; the rows are zero before their pivots), then one
/// pass over the columns adds all their products to each entry, loaded and
/// stored once per group instead of once per row (dense 771- and
/// 1465-column kernels, one thread: 5-13% faster in `cargo bench -p
/// obsan-recon --bench recon`). At a group's pivot
/// columns the pass leaves a multiple of `p` where one row at a time left
/// 0: the same residue, and no later row reads those columns.
pub fn reduce_delayed<E: Residue, V: AsMut<[E]>>(
    vs: &mut [V],
    rows: &[(usize, Vec<E>)],
    p: u64,
    max_adds: usize,
    shrink: impl Fn(u128) -> u128,
    full: impl Fn(u128) -> u64,
) {
    // Per vector its accumulators, the products added since the last
    // reduction, and the first column a product reached: the columns
    // before it keep their residues (a reduction only follows products),
    // so only the others are brought back at the end. A vector that
    // arrives reduced by all but a few rows (`RowEchelon::insert` after
    // `insert_all`'s block pass) paid a remainder per column here, 14% of
    // SEAIJRC's kernels and 8% of SIWR_orig's.
    let mut accs: Vec<(Vec<u128>, usize, usize)> = vs
        .iter_mut()
        .map(|v| {
            let v = v.as_mut();
            (
                v.iter().map(|x| u128::from(x.residue())).collect(),
                0,
                v.len(),
            )
        })
        .collect();
    // With fewer than GROUP products of room the rows go one at a time.
    let group = if max_adds >= 2 * GROUP { GROUP } else { 1 };
    for g in rows.chunks(group) {
        let first = g.iter().map(|(q, _)| *q).min().unwrap_or(0);
        for (acc, adds, from) in accs.iter_mut() {
            if *adds + g.len() > max_adds {
                acc[first..].iter_mut().for_each(|a| *a = shrink(*a));
                *adds = 0;
            }
            let neg: [u64; GROUP] = multipliers(g, |c| acc[c], &full, p);
            let (nc, live, k) = live_rows(g, &neg, first);
            if k == 0 {
                continue;
            }
            add_rows(&mut acc[first..], &nc, &live, k);
            *adds += k;
            *from = (*from).min(first);
        }
    }
    for (v, (acc, _, from)) in vs.iter_mut().zip(&accs) {
        for (x, &a) in v.as_mut()[*from..].iter_mut().zip(&acc[*from..]) {
            *x = E::of_residue(full(a));
        }
    }
}

/// Rows per group of [`reduce_delayed`]'s pass.
const GROUP: usize = 4;

/// A group's negated multipliers, as the rows one at a time would find
/// them: row `i`'s pivot entry (`value` at its column, before the group)
/// after the rows before it in the group, reduced by `full`; products with
/// a zero multiplier skipped, and no remainder for a zero sum (a vector
/// already reduced by the basis, as [`RowEchelon::insert_all`] inserts
/// them, meets zeros at every pivot but a few).
#[inline]
fn multipliers<E: Residue, const G: usize>(
    g: &[(usize, Vec<E>)],
    value: impl Fn(usize) -> u128,
    full: impl Fn(u128) -> u64,
    p: u64,
) -> [u64; G] {
    let mut neg = [0u64; G];
    for (i, (piv, _)) in g.iter().enumerate() {
        let a = (0..i).filter(|&h| neg[h] != 0).fold(value(*piv), |a, h| {
            a + u128::from(neg[h]) * u128::from(g[h].1[*piv].residue())
        });
        let c = if a == 0 { 0 } else { full(a) };
        neg[i] = if c == 0 { 0 } else { p - c };
    }
    neg
}

/// The group's rows with a non-zero multiplier, from column `first` on,
/// and how many there are.
#[inline]
fn live_rows<'a, E, const G: usize>(
    g: &'a [(usize, Vec<E>)],
    neg: &[u64; G],
    first: usize,
) -> ([u64; G], [&'a [E]; G], usize) {
    let mut nc = [0u64; G];
    let mut live: [&[E]; G] = [&[]; G];
    let mut k = 0;
    for (i, (_, r)) in g.iter().enumerate() {
        if neg[i] != 0 {
            nc[k] = neg[i];
            live[k] = &r[first..];
            k += 1;
        }
    }
    (nc, live, k)
}

/// Primes below this bound have residues that fit IFMA's 52-bit operands:
/// [`Zp`]'s eliminations modulo them run [`reduce_delayed52`] where the CPU
/// has AVX-512 IFMA ([`obsan_simd::ifma`]).
pub const IFMA_BOUND: u64 = 1 << obsan_simd::BITS;

/// Products added to an accumulator `lo + 2^52 hi` between two reductions
/// (from `lo < p < 2^52` and `hi = 0`): [`obsan_simd::ROOM`].
const MAX_ADDS52: usize = obsan_simd::ROOM;

/// Rows per group of [`reduce_delayed52`]'s pass: eight products per load
/// and store of an accumulator's halves (four: dense 1465-column kernels
/// 22% slower).
const GROUP52: usize = 8;

/// [`reduce_delayed`] for residues modulo a prime `p <` [`IFMA_BOUND`],
/// each entry held as `lo + 2^52 hi` and the rows' products added by
/// [`obsan_simd::madd52`] (AVX-512 IFMA: eight columns and [`GROUP52`] rows
/// a pass; dense kernels of 771 and 1465 columns 3.5-4x faster than the
/// `u128` pass, `cargo bench -p obsan-recon --bench recon`). Each entry is reduced modulo `p` before
/// [`MAX_ADDS52`] products pile up, and each row's multiplier, as in
/// [`reduce_delayed`], from its pivot entry as the group's earlier rows
/// leave it. Gives the residues [`reduce_delayed`] gives.
pub fn reduce_delayed52<V: AsMut<[u64]>>(vs: &mut [V], rows: &[(usize, Vec<u64>)], p: u64) {
    reduce52_every(vs, rows, p, MAX_ADDS52);
}

/// `out = a b` truncated to `out.len()` terms, for residues modulo a prime
/// `p <` [`IFMA_BOUND`]: the Cauchy product as row operations, eight
/// coefficients `a_i` a pass, each row `b` shifted by `i`, summed as 52-bit
/// halves by [`obsan_simd::madd52`] (AVX-512 IFMA where the CPU has it; the
/// input-output route's series products). Each entry is reduced before
/// [`obsan_simd::ROOM`] products pile up.
pub fn mul_truncated52(a: &[u64], b: &[u64], out: &mut [u64], p: u64) {
    assert!(
        p < IFMA_BOUND,
        "mul_truncated52: a prime of 52 bits or more"
    );
    let n = out.len();
    let m = field::Rem128::new(p);
    let full = |lo: u64, hi: u64| m.reduce(u128::from(lo) + (u128::from(hi) << obsan_simd::BITS));
    // `b` padded with zeros to `n` terms: every shifted row as long as its columns.
    let mut bz = b[..b.len().min(n)].to_vec();
    bz.resize(n, 0);
    let (mut lo, mut hi) = (vec![0u64; n], vec![0u64; n]);
    let mut adds = 0;
    let na = a.len().min(n);
    let mut i0 = 0;
    while i0 < na {
        let i1 = (i0 + GROUP52).min(na);
        if a[i0..i1].iter().all(|&x| x == 0) {
            i0 = i1;
            continue;
        }
        if adds + GROUP52 > MAX_ADDS52 {
            for (l, h) in lo[i0..].iter_mut().zip(&mut hi[i0..]) {
                *l = full(*l, *h);
                *h = 0;
            }
            adds = 0;
        }
        // Columns from `top` on take every row of the group; the triangle
        // before it (row `i` from column `i`), one product at a time.
        let top = i1 - 1;
        for i in i0..top {
            let c = u128::from(a[i]);
            for j in i..top {
                let x = c * u128::from(bz[j - i]);
                lo[j] += x as u64 & obsan_simd::MASK;
                hi[j] += (x >> obsan_simd::BITS) as u64;
            }
        }
        let mut cs = [0u64; GROUP52];
        let mut rows: [&[u64]; GROUP52] = [&[]; GROUP52];
        let mut k = 0;
        for i in i0..i1 {
            if a[i] != 0 {
                cs[k] = a[i];
                rows[k] = &bz[top - i..n - i];
                k += 1;
            }
        }
        obsan_simd::madd52(&mut lo[top..], &mut hi[top..], &cs[..k], &rows[..k]);
        adds += GROUP52;
        i0 = i1;
    }
    for ((o, &l), &h) in out.iter_mut().zip(&lo).zip(&hi) {
        *o = full(l, h);
    }
}

/// [`reduce_delayed52`] reducing the entries once `max_adds` (at least
/// [`GROUP52`], at most [`MAX_ADDS52`]) products piled up.
fn reduce52_every<V: AsMut<[u64]>>(
    vs: &mut [V],
    rows: &[(usize, Vec<u64>)],
    p: u64,
    max_adds: usize,
) {
    assert!(
        p < IFMA_BOUND,
        "reduce_delayed52: a prime of 52 bits or more"
    );
    assert!((GROUP52..=MAX_ADDS52).contains(&max_adds));
    let m = field::Rem128::new(p);
    let full = |lo: u64, hi: u64| m.reduce(u128::from(lo) + (u128::from(hi) << obsan_simd::BITS));
    // Per vector its halves, the products added since the last reduction,
    // and the first column a product reached (as in `reduce_delayed`).
    let mut accs: Vec<(Vec<u64>, Vec<u64>, usize, usize)> = vs
        .iter_mut()
        .map(|v| {
            let v = v.as_mut();
            (v.to_vec(), vec![0; v.len()], 0, v.len())
        })
        .collect();
    for g in rows.chunks(GROUP52) {
        let first = g.iter().map(|(q, _)| *q).min().unwrap_or(0);
        for (lo, hi, adds, from) in accs.iter_mut() {
            if *adds + g.len() > max_adds {
                for (l, h) in lo[first..].iter_mut().zip(&mut hi[first..]) {
                    *l = full(*l, *h);
                    *h = 0;
                }
                *adds = 0;
            }
            let value = |c: usize| u128::from(lo[c]) + (u128::from(hi[c]) << obsan_simd::BITS);
            let neg: [u64; GROUP52] = multipliers(g, value, |a| m.reduce(a), p);
            let (nc, live, k) = live_rows(g, &neg, first);
            if k == 0 {
                continue;
            }
            obsan_simd::madd52(&mut lo[first..], &mut hi[first..], &nc[..k], &live[..k]);
            *adds += k;
            *from = (*from).min(first);
        }
    }
    for (v, (lo, hi, _, from)) in vs.iter_mut().zip(&accs) {
        let v = &mut v.as_mut()[*from..];
        for ((x, &l), &h) in v.iter_mut().zip(&lo[*from..]).zip(&hi[*from..]) {
            *x = full(l, h);
        }
    }
}

/// `acc[j] += sum_k nc[k] rows[k][j]` over the first `k` rows, each entry
/// loaded and stored once (zipped iterators: no bounds checks in the loop).
#[inline]
fn add_rows<E: Residue>(acc: &mut [u128], nc: &[u64; GROUP], rows: &[&[E]; GROUP], k: usize) {
    // Each product a 64 x 64 -> 128 multiply: both factors widened at use.
    let [c0, c1, c2, c3] = *nc;
    let m = |c: u64, x: &E| u128::from(c) * u128::from(x.residue());
    match k {
        1 => {
            for (a, x) in acc.iter_mut().zip(rows[0]) {
                *a += m(c0, x);
            }
        }
        2 => {
            for ((a, x), y) in acc.iter_mut().zip(rows[0]).zip(rows[1]) {
                *a += m(c0, x) + m(c1, y);
            }
        }
        3 => {
            for (((a, x), y), z) in acc.iter_mut().zip(rows[0]).zip(rows[1]).zip(rows[2]) {
                *a += m(c0, x) + m(c1, y) + m(c2, z);
            }
        }
        _ => {
            for ((((a, x), y), z), t) in acc
                .iter_mut()
                .zip(rows[0])
                .zip(rows[1])
                .zip(rows[2])
                .zip(rows[3])
            {
                *a += m(c0, x) + m(c1, y) + m(c2, z) + m(c3, t);
            }
        }
    }
}

/// The delayed reduction's periodic step: entries brought back below
/// [`Fold::BOUND`](field::Fold) by a fold where the prime allows one, else
/// below `p` by a remainder; with how many products (each below `(p -
/// 1)^2`) may be added between two steps so that no entry passes
/// `u128::MAX`.
#[derive(Clone, Copy)]
enum Shrink {
    Fold(field::Fold),
    Rem(field::Rem128),
}

impl Shrink {
    fn new(p: u64) -> (usize, Shrink) {
        let pm = u128::from(p - 1);
        let (start, shrink) = match field::Fold::new(p) {
            Some(f) => (field::Fold::BOUND, Shrink::Fold(f)),
            None => (u128::from(p), Shrink::Rem(field::Rem128::new(p))),
        };
        // Entries stay below start + max_adds (p - 1)^2 <= u128::MAX.
        let max_adds = ((u128::MAX - start) / (pm * pm).max(1)).min(1 << 20) as usize;
        (max_adds, shrink)
    }

    #[inline]
    fn one(self, a: u128) -> u128 {
        match self {
            Shrink::Fold(f) => f.fold(a),
            Shrink::Rem(m) => u128::from(m.reduce(a)),
        }
    }
}

/// Vectors per block of [`RowEchelon::insert_all`]: 16 accumulators of a
/// 771-column kernel (SIWR_orig's) take 200 KB, within a core's L2 cache.
pub const BLOCK: usize = 16;

/// Multiply-adds of one block below which [`RowEchelon::insert_all`] stays
/// on one thread (a thread's start costs tens of microseconds, this work
/// about a millisecond).
pub const PARALLEL_WORK: usize = 1_000_000;

/// Row vectors in reduced row echelon form: each row is 1 at its pivot
/// column (its first non-zero entry) and every pivot column is 0 in the
/// other rows. Rows are kept in insertion order.
#[derive(Clone, Debug, Default)]
pub struct Echelon<F: PrimeField> {
    field: F,
    rows: Vec<(usize, Vec<F::Elem>)>,
}

impl<F: PrimeField> Echelon<F> {
    /// The empty basis.
    pub fn new(field: F) -> Self {
        Echelon {
            field,
            rows: Vec::new(),
        }
    }

    /// The basis of the span of `rows` (all of one length).
    pub fn of_rows(field: F, rows: impl IntoIterator<Item = Vec<F::Elem>>) -> Self {
        let mut e = Echelon::new(field);
        for r in rows {
            e.insert(r);
        }
        e
    }

    /// `v` minus its projection on the rows along the pivot columns: zero
    /// exactly when `v` is in the span.
    pub fn reduce(&self, mut v: Vec<F::Elem>) -> Vec<F::Elem> {
        let f = self.field;
        let zero = f.zero();
        for (p, r) in &self.rows {
            let c = v[*p];
            if c != zero {
                f.sub_scaled(&mut v, c, r);
            }
        }
        v
    }

    /// Adds `v` if it is independent of the rows; whether it was.
    pub fn insert(&mut self, v: Vec<F::Elem>) -> bool {
        let f = self.field;
        let zero = f.zero();
        let mut v = self.reduce(v);
        let Some(p) = v.iter().position(|x| *x != zero) else {
            return false;
        };
        // A non-zero element of a field has an inverse.
        let Some(inv) = f.inv(v[p]) else {
            return false;
        };
        f.scale(&mut v, inv);
        // Keep the form reduced: clear the new pivot column in the others.
        for (_, r) in self.rows.iter_mut() {
            let c = r[p];
            if c != zero {
                f.sub_scaled(r, c, &v);
            }
        }
        self.rows.push((p, v));
        true
    }

    /// Whether `v` is in the span.
    pub fn contains(&self, v: Vec<F::Elem>) -> bool {
        let zero = self.field.zero();
        self.reduce(v).iter().all(|x| *x == zero)
    }

    /// Whether the unit vector `e_col` of length `len` is in the span.
    pub fn contains_unit(&self, col: usize, len: usize) -> bool {
        let mut e = vec![self.field.zero(); len];
        e[col] = self.field.one();
        self.contains(e)
    }

    /// The dimension of the span.
    pub fn rank(&self) -> usize {
        self.rows.len()
    }

    /// The pivot columns, in insertion order.
    pub fn pivots(&self) -> impl Iterator<Item = usize> + '_ {
        self.rows.iter().map(|(p, _)| *p)
    }

    /// The reduced row whose pivot is column `col`.
    pub fn row_at(&self, col: usize) -> Option<&[F::Elem]> {
        self.rows
            .iter()
            .find(|(p, _)| *p == col)
            .map(|(_, r)| r.as_slice())
    }

    /// A basis of the right null space of the rows, for vectors of length
    /// `ncols`: one vector per non-pivot column `j`, 1 at `j` and 0 at the
    /// other non-pivot columns (unique: the null space's reduced form).
    pub fn null_space(&self, ncols: usize) -> Vec<Vec<F::Elem>> {
        let f = self.field;
        let mut is_pivot = vec![false; ncols];
        for (p, _) in &self.rows {
            is_pivot[*p] = true;
        }
        (0..ncols)
            .filter(|&j| !is_pivot[j])
            .map(|j| {
                let mut v = vec![f.zero(); ncols];
                v[j] = f.one();
                for (p, r) in &self.rows {
                    v[*p] = f.sub(f.zero(), r[j]);
                }
                v
            })
            .collect()
    }

    /// For rows `[A | B]` with `unknowns` columns in `A`: the unique `X` with
    /// `A X = B`, as the row of `X` of each unknown in order; `None` unless
    /// every unknown is a pivot and no pivot lies in `B` (`A` of full column
    /// rank and the system consistent).
    pub fn solve(&self, unknowns: usize) -> Option<Vec<Vec<F::Elem>>> {
        if self.rows.len() != unknowns || self.rows.iter().any(|(p, _)| *p >= unknowns) {
            return None;
        }
        let mut x: Vec<Option<Vec<F::Elem>>> = vec![None; unknowns];
        for (p, r) in &self.rows {
            x[*p] = Some(r[unknowns..].to_vec());
        }
        x.into_iter().collect()
    }
}

/// Row vectors in row echelon form, not reduced: each row is 1 at its pivot
/// column and 0 before it, rows sorted by pivot. Inserting costs the
/// columns from each pivot on, about a sixth of [`Echelon`]'s reduced form
/// over a whole elimination, for callers that want only the rank and the
/// null space (the input-output route's kernels). The null space is the
/// same as [`Echelon::null_space`]'s (the pivot columns of a row space do
/// not depend on the form, and the basis is fixed by them).
#[derive(Clone, Debug)]
pub struct RowEchelon<F: PrimeField> {
    field: F,
    rows: Vec<(usize, Vec<F::Elem>)>,
}

/// Adds `v`, already zero at every pivot of `rows` (sorted by pivot), to
/// them unless it is zero: scaled to 1 at its pivot; whether it was added.
fn place<F: PrimeField>(f: F, rows: &mut Vec<(usize, Vec<F::Elem>)>, mut v: Vec<F::Elem>) -> bool {
    let zero = f.zero();
    let Some(p) = v.iter().position(|x| *x != zero) else {
        return false;
    };
    let Some(inv) = f.inv(v[p]) else {
        return false;
    };
    f.scale(&mut v[p..], inv);
    let at = rows.partition_point(|(q, _)| *q < p);
    rows.insert(at, (p, v));
    true
}

impl<F: PrimeField> RowEchelon<F> {
    /// The empty basis.
    pub fn new(field: F) -> Self {
        RowEchelon {
            field,
            rows: Vec::new(),
        }
    }

    /// Adds `v` if it is independent of the rows; whether it was.
    pub fn insert(&mut self, mut v: Vec<F::Elem>) -> bool {
        // In pivot order each row clears its pivot and leaves the earlier
        // pivots cleared (it is zero before its own).
        self.field.reduce_sorted(&mut v, &self.rows);
        place(self.field, &mut self.rows, v)
    }

    /// Adds each of `vs` that is independent of the rows and of the ones
    /// before it; per vector, whether it was ([`RowEchelon::insert`] one by
    /// one, the same row space). Blocks of [`BLOCK`] vectors are reduced by
    /// the basis together, each row read once per block, and split between
    /// `threads` threads when a block's work is large ([`PARALLEL_WORK`]);
    /// then each is inserted, reduced by the block's earlier ones. The
    /// null space depends only on the row space, so it is the one-by-one
    /// insertion's.
    pub fn insert_all(&mut self, vs: Vec<Vec<F::Elem>>, threads: usize) -> Vec<bool> {
        let f = self.field;
        let mut out = Vec::with_capacity(vs.len());
        let mut vs = vs.into_iter().peekable();
        while vs.peek().is_some() {
            let mut block: Vec<Vec<F::Elem>> = vs.by_ref().take(BLOCK).collect();
            let ncols = block.first().map_or(0, Vec::len);
            let work = (self.rows.len() * ncols).saturating_mul(block.len());
            let threads = threads.clamp(1, block.len());
            if threads > 1 && work >= PARALLEL_WORK {
                let per = block.len().div_ceil(threads);
                let rows = &self.rows;
                std::thread::scope(|s| {
                    for part in block.chunks_mut(per) {
                        s.spawn(move || f.reduce_block(part, rows));
                    }
                });
            } else {
                f.reduce_block(&mut block, &self.rows);
            }
            // Zero at every pivot of the basis already: each vector is left
            // to reduce by the block's earlier rows only (zero there too),
            // kept apart until the block ends. The reduced vector is the
            // one-by-one insertion's (the only one of `v + W` zero at every
            // pivot); rescanning the whole basis per vector was 8-10% of
            // SIWR_orig's kernels.
            let mut fresh: Vec<(usize, Vec<F::Elem>)> = Vec::with_capacity(block.len());
            for mut v in block {
                f.reduce_sorted(&mut v, &fresh);
                out.push(place(f, &mut fresh, v));
            }
            for row in fresh {
                let at = self.rows.partition_point(|(q, _)| *q < row.0);
                self.rows.insert(at, row);
            }
        }
        out
    }

    /// The dimension of the span.
    pub fn rank(&self) -> usize {
        self.rows.len()
    }

    /// A basis of the right null space for vectors of length `ncols`: one
    /// vector per non-pivot column `j`, 1 at `j` and 0 at the other
    /// non-pivot columns (back substitution, last pivot first).
    pub fn null_space(&self, ncols: usize) -> Vec<Vec<F::Elem>> {
        let f = self.field;
        let mut is_pivot = vec![false; ncols];
        for (p, _) in &self.rows {
            is_pivot[*p] = true;
        }
        (0..ncols)
            .filter(|&j| !is_pivot[j])
            .map(|j| {
                let mut x = vec![f.zero(); ncols];
                x[j] = f.one();
                for (p, r) in self.rows.iter().rev() {
                    x[*p] = f.neg_dot(&r[p + 1..ncols], &x[p + 1..ncols]);
                }
                x
            })
            .collect()
    }
}

/// The rank of the matrix with these rows.
pub fn rank<F: PrimeField>(field: F, rows: impl IntoIterator<Item = Vec<F::Elem>>) -> usize {
    Echelon::of_rows(field, rows).rank()
}

/// A basis of the right null space of the rows, vectors of length `ncols`
/// ([`Echelon::null_space`]).
pub fn null_space<F: PrimeField>(
    field: F,
    rows: impl IntoIterator<Item = Vec<F::Elem>>,
    ncols: usize,
) -> Vec<Vec<F::Elem>> {
    Echelon::of_rows(field, rows).null_space(ncols)
}

/// The unique solution of `a x = b` for rows `[a | b]` with `unknowns`
/// columns in `a` (as many rows as wanted); `None` unless it has exactly one.
pub fn solve<F: PrimeField>(
    field: F,
    rows: impl IntoIterator<Item = Vec<F::Elem>>,
    unknowns: usize,
) -> Option<Vec<F::Elem>> {
    let x = Echelon::of_rows(field, rows).solve(unknowns)?;
    x.into_iter().map(|r| r.first().copied()).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::{add, PRIMES};
    use crate::rng::Rng;

    const P: u64 = PRIMES[3];
    const F: Zp = Zp(P);

    fn dot(a: &[u64], b: &[u64]) -> u64 {
        a.iter()
            .zip(b)
            .fold(0, |s, (&x, &y)| add(s, field::mul(x, y, P), P))
    }

    /// The `m x n` product of random `m x k` and `k x n` factors (rank at
    /// most `k`); the second's entries are `nonzero - shift` (`shift` 1:
    /// zeros allowed).
    fn planted(rng: &mut Rng, m: usize, n: usize, k: usize, shift: u64) -> Vec<Vec<u64>> {
        let b: Vec<Vec<u64>> = (0..m)
            .map(|_| (0..k).map(|_| rng.nonzero(P)).collect())
            .collect();
        let c: Vec<Vec<u64>> = (0..k)
            .map(|_| (0..n).map(|_| rng.nonzero(P) - shift).collect())
            .collect();
        b.iter()
            .map(|br| {
                (0..n)
                    .map(|j| dot(br, &c.iter().map(|cr| cr[j]).collect::<Vec<_>>()))
                    .collect()
            })
            .collect()
    }

    /// A random solution x and `m` augmented rows `[a | a.x]` in `n` unknowns.
    fn random_system(rng: &mut Rng, m: usize, n: usize) -> (Vec<u64>, Vec<Vec<u64>>) {
        let x: Vec<u64> = (0..n).map(|_| rng.nonzero(P)).collect();
        let rows = (0..m)
            .map(|_| {
                let mut r: Vec<u64> = (0..n).map(|_| rng.nonzero(P)).collect();
                let b = dot(&r, &x);
                r.push(b);
                r
            })
            .collect();
        (x, rows)
    }

    #[test]
    fn solves_square_and_overdetermined_systems() {
        let mut rng = Rng::new(1);
        let (x, rows) = random_system(&mut rng, 7, 7);
        assert_eq!(solve(F, rows, 7).unwrap(), x);
        let (x, mut rows) = random_system(&mut rng, 9, 5);
        assert_eq!(solve(F, rows.clone(), 5).unwrap(), x);
        // One right-hand side off: inconsistent, no solution.
        rows[7][5] = add(rows[7][5], 1, P);
        assert_eq!(solve(F, rows.clone(), 5), None);
        // Fewer independent rows than unknowns: not determined.
        let few: Vec<Vec<u64>> = (0..9).map(|_| rows[0].clone()).collect();
        assert_eq!(solve(F, few, 5), None);
        // Two equal rows of a square system: singular.
        let row = vec![1, 2, 3];
        assert_eq!(solve(F, vec![row.clone(), row], 2), None);
    }

    #[test]
    fn rank_and_null_space_of_a_planted_product() {
        // A (6 x 9) = B (6 x 4) C (4 x 9) with random B, C: rank 4 (a
        // random 4 x 4 minor vanishes with probability about 4/P), so the
        // null space has 5 vectors, each annihilated by every row.
        let mut rng = Rng::new(3);
        let b: Vec<Vec<u64>> = (0..6)
            .map(|_| (0..4).map(|_| rng.nonzero(P)).collect())
            .collect();
        let c: Vec<Vec<u64>> = (0..4)
            .map(|_| (0..9).map(|_| rng.nonzero(P)).collect())
            .collect();
        let a: Vec<Vec<u64>> = b
            .iter()
            .map(|br| {
                (0..9)
                    .map(|j| dot(br, &c.iter().map(|cr| cr[j]).collect::<Vec<_>>()))
                    .collect()
            })
            .collect();
        assert_eq!(rank(F, a.clone()), 4);
        let ns = null_space(F, a.clone(), 9);
        assert_eq!(ns.len(), 5);
        for v in &ns {
            for row in &a {
                assert_eq!(dot(row, v), 0);
            }
        }
        // The null basis does not depend on the rows' order.
        let mut rev = a.clone();
        rev.reverse();
        assert_eq!(null_space(F, rev, 9), ns);
    }

    #[test]
    fn zp_row_operations_agree_with_the_generic_ones() {
        // Zp's Shoup loops against the trait's default (sub, mul per entry).
        #[derive(Clone, Copy)]
        struct Naive(u64);
        impl PrimeField for Naive {
            type Elem = u64;
            fn zero(self) -> u64 {
                0
            }
            fn one(self) -> u64 {
                1
            }
            fn sub(self, a: u64, b: u64) -> u64 {
                field::sub(a, b, self.0)
            }
            fn mul(self, a: u64, b: u64) -> u64 {
                field::mul(a, b, self.0)
            }
            fn inv(self, a: u64) -> Option<u64> {
                field::inv(a, self.0)
            }
        }
        let mut rng = Rng::new(9);
        for _ in 0..50 {
            let n = 1 + (rng.nonzero(P) % 40) as usize;
            let x: Vec<u64> = (0..n).map(|_| rng.nonzero(P) - 1).collect();
            let y: Vec<u64> = (0..n).map(|_| rng.nonzero(P) - 1).collect();
            let c = rng.nonzero(P) - 1;
            let (mut a, mut b) = (x.clone(), x.clone());
            F.sub_scaled(&mut a, c, &y);
            Naive(P).sub_scaled(&mut b, c, &y);
            assert_eq!(a, b);
            F.scale(&mut a, c);
            Naive(P).scale(&mut b, c);
            assert_eq!(a, b);
        }
        // Delayed reduction against the generic loop: more rows than one
        // u128 holds products of (every prime of the list is near 2^62,
        // 15 products per fold), a prime near 2^63 (3 products per fold),
        // and one whose 2^64 mod p passes 2^32 (no fold: remainders, 16).
        assert!(field::Fold::new(0x3fff_feff_ffff_fff9).is_none());
        // The null space's dot products summed late, against the generic
        // fold, past a fold's count of products (3 near 2^63, 15 near 2^62).
        for q in [
            P,
            0x7fff_ffff_ffff_ffe7,
            0x3fff_feff_ffff_fff9,
            0xf_ffff_ffff_ffd1,
        ] {
            for n in [0usize, 1, 3, 4, 16, 70] {
                let x: Vec<u64> = (0..n).map(|_| rng.nonzero(q) - 1).collect();
                let y: Vec<u64> = (0..n).map(|_| rng.nonzero(q) - 1).collect();
                assert_eq!(Zp(q).neg_dot(&x, &y), Naive(q).neg_dot(&x, &y), "{q} {n}");
                let top = vec![q - 1; n];
                assert_eq!(Zp(q).neg_dot(&top, &top), Naive(q).neg_dot(&top, &top));
            }
        }
        // Sparse rows too (two entries in three zero): many multipliers of
        // a group of rows zero, and rows nonzero at later rows' pivots, so
        // the group's multipliers depend on each other.
        for q in [P, 0x7fff_ffff_ffff_ffe7, 0x3fff_feff_ffff_fff9] {
            for n in [1usize, 5, 40, 70] {
                for sparse in [false, true] {
                    let (mut fast, mut slow) = (RowEchelon::new(Zp(q)), RowEchelon::new(Naive(q)));
                    for _ in 0..n + 3 {
                        let row: Vec<u64> = (0..n)
                            .map(|_| {
                                let x = rng.nonzero(q) - 1;
                                if sparse && !x.is_multiple_of(3) {
                                    0
                                } else {
                                    x
                                }
                            })
                            .collect();
                        assert_eq!(fast.insert(row.clone()), slow.insert(row));
                    }
                    assert_eq!(fast.rows, slow.rows);
                }
            }
        }
    }

    #[test]
    fn the_52_bit_pass_gives_the_u128_passs_residues() {
        // reduce_delayed52 (IFMA where the CPU has it, else the portable
        // madd52) against the trait's generic loop and reduce_delayed, on
        // random unit upper-triangular rows (sorted by pivot, 1 there, 0
        // before): primes just below 2^52 (the largest products), below
        // 2^50, and a small one; 4200 rows, so one vector passes
        // MAX_ADDS52 products and is reduced between groups; sparse rows
        // and vectors too (zero multipliers inside a group).
        let naive = |v: &mut [u64], rows: &[(usize, Vec<u64>)], q: u64| {
            for (piv, r) in rows {
                let c = v[*piv];
                for (a, &b) in v[*piv..].iter_mut().zip(&r[*piv..]) {
                    *a = field::sub(*a, field::mul(c, b, q), q);
                }
            }
        };
        let mut rng = Rng::new(42);
        for (q, n, step) in [
            (0xf_ffff_ffff_ffd1, 4201, 1),
            (0x3_ffff_ffff_ffdd, 90, 2),
            (65_521, 37, 1),
        ] {
            assert!(field::is_prime(q) && q < IFMA_BOUND);
            for sparse in [false, true] {
                let entry = |rng: &mut Rng| {
                    let x = rng.nonzero(q) - 1;
                    if sparse && !x.is_multiple_of(3) {
                        0
                    } else {
                        x
                    }
                };
                let rows: Vec<(usize, Vec<u64>)> = (0..n - 1)
                    .step_by(step)
                    .map(|i| {
                        let mut r = vec![0; n];
                        r[i] = 1;
                        for x in &mut r[i + 1..] {
                            *x = entry(&mut rng);
                        }
                        (i, r)
                    })
                    .collect();
                let vs: Vec<Vec<u64>> = (0..3)
                    .map(|_| (0..n).map(|_| entry(&mut rng)).collect())
                    .collect();
                let mut want = vs.clone();
                for v in want.iter_mut() {
                    naive(v, &rows, q);
                }
                let mut got = vs.clone();
                reduce_delayed52(&mut got, &rows, q);
                assert_eq!(got, want, "prime {q}, {n} columns, sparse {sparse}");
                // The reductions between groups (4095 products of 52 bits
                // fit, obsan-simd's test; here their placement).
                for every in [GROUP52, GROUP52 + 3] {
                    let mut got = vs.clone();
                    reduce52_every(&mut got, &rows, q, every);
                    assert_eq!(got, want, "reduced every {every} products");
                }
                let mut wide = vs.clone();
                Zp(q).reduce_block(&mut wide, &rows);
                assert_eq!(wide, want);
                if n < 100 {
                    let (max_adds, shrink) = Shrink::new(q);
                    let m = field::Rem128::new(q);
                    let mut old = vs;
                    reduce_delayed(
                        &mut old,
                        &rows,
                        q,
                        max_adds,
                        |a| shrink.one(a),
                        |a| m.reduce(a),
                    );
                    assert_eq!(old, want);
                }
            }
        }
    }

    #[test]
    fn truncated_products_of_52_bit_residues_are_cauchy_products() {
        // Against the schoolbook sum: lengths around the groups of eight,
        // a `b` shorter than the output, runs of zero coefficients in `a`
        // (whole groups skipped), and 4300 terms (reductions between
        // groups past obsan_simd::ROOM products).
        let mut rng = Rng::new(7);
        for q in [0xf_ffff_ffff_ffd1, 65_521, 3] {
            for (na, nb, n) in [
                (0, 3, 3),
                (1, 1, 1),
                (5, 5, 5),
                (9, 9, 9),
                (17, 6, 20),
                (40, 40, 33),
                (4300, 4300, 4300),
            ] {
                let mut a: Vec<u64> = (0..na).map(|_| rng.nonzero(q) - 1).collect();
                for x in a.iter_mut().skip(3).take(10) {
                    *x = 0;
                }
                let b: Vec<u64> = (0..nb).map(|_| rng.nonzero(q) - 1).collect();
                let mut want = vec![0u64; n];
                for (i, &x) in a.iter().enumerate().take(n) {
                    for (j, &y) in b.iter().enumerate().take(n - i) {
                        want[i + j] = add(want[i + j], field::mul(x, y, q), q);
                    }
                }
                let mut got = vec![1u64; n];
                mul_truncated52(&a, &b, &mut got, q);
                assert_eq!(got, want, "p {q}, lengths {na} {nb} {n}");
            }
        }
    }

    #[test]
    fn row_echelon_has_the_reduced_forms_rank_and_null_space() {
        // Planted ranks (random products B C, some rows repeated and
        // combined) against Echelon, the reduced form.
        let mut rng = Rng::new(11);
        for case in 0..30 {
            let (m, n, k) = (2 + case % 9, 1 + case % 13, 1 + case % 5);
            let mut a = planted(&mut rng, m, n, k, 1);
            // A zero column and a unit row, so that pivots are skipped.
            for r in a.iter_mut() {
                r[n / 2] = 0;
            }
            let mut unit = vec![0; n];
            unit[n - 1] = 1;
            a.push(unit);
            let mut fwd = RowEchelon::new(F);
            let mut red = Echelon::new(F);
            for r in &a {
                assert_eq!(fwd.insert(r.clone()), red.insert(r.clone()));
            }
            assert_eq!(fwd.rank(), red.rank());
            let ns = fwd.null_space(n);
            assert_eq!(ns, red.null_space(n));
            for v in &ns {
                for row in &a {
                    assert_eq!(dot(row, v), 0);
                }
            }
        }
    }

    #[test]
    fn block_insertion_is_one_by_one() {
        // Planted ranks with a repeated row, large enough that blocks
        // run on two threads (PARALLEL_WORK), for Zp's interleaved
        // reduction.
        let mut rng = Rng::new(5);
        for (m, n, k) in [(40, 30, 30), (400, 330, 250), (90, 120, 61)] {
            let mut a = planted(&mut rng, m, n, k, 0);
            a.insert(7, a[3].clone());
            for threads in [1, 2, 3] {
                let mut one = RowEchelon::new(F);
                let flags: Vec<bool> = a.iter().map(|r| one.insert(r.clone())).collect();
                let mut blk = RowEchelon::new(F);
                assert_eq!(blk.insert_all(a.clone(), threads), flags);
                assert_eq!(blk.rank(), k.min(n));
                let ns = blk.null_space(n);
                assert_eq!(ns, one.null_space(n));
                for v in &ns {
                    for row in &a {
                        assert_eq!(dot(row, v), 0);
                    }
                }
            }
        }
    }

    #[test]
    fn membership_and_reduced_form() {
        let mut e = Echelon::new(F);
        assert!(e.insert(vec![0, 2, 4, 6]));
        assert!(e.insert(vec![1, 1, 1, 1]));
        assert!(!e.insert(vec![2, 4, 6, 8])); // (0,2,4,6) + 2 (1,1,1,1)
        assert_eq!(e.rank(), 2);
        assert_eq!(e.pivots().collect::<Vec<_>>(), vec![1, 0]);
        // Reduced: pivot column 1 is zero in the row of pivot 0.
        assert_eq!(e.row_at(0).unwrap(), &[1, 0, P - 1, P - 2]);
        assert_eq!(e.row_at(1).unwrap(), &[0, 1, 2, 3]);
        assert!(!e.contains_unit(3, 4));
        assert!(e.contains(vec![3, 5, 7, 9]));
    }
}
