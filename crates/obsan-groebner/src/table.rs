//! F4's monomial table: each distinct monomial stored once, its exponents
//! packed in 16 bits beside its degree, divisibility mask and hash, and
//! named by a u32 id (as msolve and Groebner.jl do), so a term of a basis
//! element or a matrix row costs an id and a coefficient instead of a boxed
//! exponent vector (round 6 of docs/performance.md: ~220 bytes a term at
//! 47 variables).
//!
//! The hash is linear in the exponents (`sum e_v w_v`, wrapping, fixed
//! random weights): the hash of a product is the sum of the factors'
//! hashes, so `mult * g` is looked up without rehashing its exponents.
//! An exponent past 16 bits is `GbError::Degree`, never a wrap.

use crate::mem::block;
use crate::poly::{Mono, Order, MAX_DEGREE};
use crate::GbError;
use std::cmp::Ordering;

/// A packed exponent.
pub(crate) type Exp = u16;

/// The hash weights of `n` variables (splitmix64 from a fixed seed: the
/// same run gives the same tables).
pub(crate) fn weights(n: usize) -> Vec<u64> {
    let mut x: u64 = 0x9e37_79b9_7f4a_7c15;
    (0..n)
        .map(|_| {
            x = x.wrapping_add(0x9e37_79b9_7f4a_7c15);
            let mut z = x;
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            z ^ (z >> 31)
        })
        .collect()
}

/// The monomials of one table, by id.
pub(crate) struct Table {
    n: usize,
    exps: Vec<Exp>,
    deg: Vec<u32>,
    mask: Vec<u64>,
    hash: Vec<u64>,
    /// Open addressing, at most half full: 0 is empty, else id + 1.
    slots: Vec<u32>,
    /// Monomials the vectors are allocated for (grown by doubling, exactly).
    cap: usize,
    w: Vec<u64>,
}

/// Bytes of a table in `n` variables with room for `cap` monomials and
/// `slots` hash slots: the exponents (2 n bytes each), degree (4), mask (8)
/// and hash (8) of each, 4 bytes a slot, each vector one allocator block.
pub(crate) fn table_bytes(n: usize, cap: usize, slots: usize) -> usize {
    block(2 * n * cap) + block(4 * cap) + 2 * block(8 * cap) + block(4 * slots) + block(8 * n)
}

/// `a | b` on packed exponents.
#[inline]
fn divides_exps(a: &[Exp], b: &[Exp]) -> bool {
    a.iter().zip(b).all(|(x, y)| x <= y)
}

fn grevlex(a: &[Exp], b: &[Exp]) -> Ordering {
    let da: u64 = a.iter().map(|&x| x as u64).sum();
    let db: u64 = b.iter().map(|&x| x as u64).sum();
    da.cmp(&db).then_with(|| revlex(a, b))
}

/// The smaller exponent in the last differing variable wins.
#[inline]
fn revlex(a: &[Exp], b: &[Exp]) -> Ordering {
    for (x, y) in a.iter().zip(b).rev() {
        if x != y {
            return y.cmp(x);
        }
    }
    Ordering::Equal
}

/// `order` on packed exponents (as [`Order::cmp`] on monomials).
pub(crate) fn cmp_exps(order: Order, a: &[Exp], da: u32, b: &[Exp], db: u32) -> Ordering {
    match order {
        Order::Grevlex => da.cmp(&db).then_with(|| revlex(a, b)),
        Order::Block(k) => grevlex(&a[..k], &b[..k]).then_with(|| grevlex(&a[k..], &b[k..])),
        Order::Lex => a.cmp(b),
    }
}

/// The mask of [`Mono::mask`]: bit `v mod 64` for each variable present.
#[inline]
fn mask_of(e: &[Exp]) -> u64 {
    let mut m = 0u64;
    for (v, &x) in e.iter().enumerate() {
        if x > 0 {
            m |= 1 << (v % 64);
        }
    }
    m
}

/// A packed monomial outside any table: exponents, degree, hash.
pub(crate) struct Scratch {
    pub(crate) e: Vec<Exp>,
    pub(crate) deg: u32,
    pub(crate) hash: u64,
}

impl Table {
    pub(crate) fn new(n: usize, w: Vec<u64>) -> Table {
        Table {
            n,
            exps: Vec::new(),
            deg: Vec::new(),
            mask: Vec::new(),
            hash: Vec::new(),
            slots: Vec::new(),
            cap: 0,
            w,
        }
    }

    pub(crate) fn len(&self) -> usize {
        self.deg.len()
    }

    /// The bytes this table holds.
    pub(crate) fn bytes(&self) -> usize {
        table_bytes(self.n, self.cap, self.slots.len())
    }

    pub(crate) fn weights(&self) -> &[u64] {
        &self.w
    }

    #[inline]
    pub(crate) fn exps(&self, id: u32) -> &[Exp] {
        let i = id as usize * self.n;
        &self.exps[i..i + self.n]
    }

    #[inline]
    pub(crate) fn deg(&self, id: u32) -> u32 {
        self.deg[id as usize]
    }

    #[inline]
    pub(crate) fn mask(&self, id: u32) -> u64 {
        self.mask[id as usize]
    }

    #[inline]
    pub(crate) fn hash(&self, id: u32) -> u64 {
        self.hash[id as usize]
    }

    /// The hash of exponents `e` (as the table computes it).
    pub(crate) fn hash_of(&self, e: &[Exp]) -> u64 {
        e.iter().zip(&self.w).fold(0u64, |h, (&x, &w)| {
            h.wrapping_add((x as u64).wrapping_mul(w))
        })
    }

    #[inline]
    fn home(&self, hash: u64) -> usize {
        ((hash ^ (hash >> 29)) as usize) & (self.slots.len() - 1)
    }

    /// The id of the monomial `e` (degree `deg`, hash `hash`), entered if
    /// new. Before the table grows, `room` is told the bytes it would add
    /// and may refuse.
    pub(crate) fn insert(
        &mut self,
        e: &[Exp],
        deg: u32,
        hash: u64,
        room: impl FnOnce(usize) -> Result<(), GbError>,
    ) -> Result<u32, GbError> {
        if !self.slots.is_empty() {
            let m = self.slots.len() - 1;
            let mut i = self.home(hash);
            loop {
                let s = self.slots[i];
                if s == 0 {
                    break;
                }
                let id = s - 1;
                if self.hash[id as usize] == hash
                    && self.deg[id as usize] == deg
                    && self.exps(id) == e
                {
                    return Ok(id);
                }
                i = (i + 1) & m;
            }
        }
        let id = self.len();
        if id >= u32::MAX as usize - 1 {
            return Err(GbError::Budget("monomials of the F4 table"));
        }
        if id + 1 > self.cap || 2 * (id + 1) > self.slots.len() {
            let cap = (2 * self.cap).max(64);
            let before = self.bytes();
            let after = table_bytes(self.n, cap, 2 * cap);
            room(after.saturating_sub(before))?;
            self.grow(cap);
        }
        self.exps.extend_from_slice(e);
        self.deg.push(deg);
        self.mask.push(mask_of(e));
        self.hash.push(hash);
        let m = self.slots.len() - 1;
        let mut i = self.home(hash);
        while self.slots[i] != 0 {
            i = (i + 1) & m;
        }
        self.slots[i] = id as u32 + 1;
        Ok(id as u32)
    }

    /// Room for `cap` monomials and `2 cap` slots (a power of two), rehashed.
    fn grow(&mut self, cap: usize) {
        let n = self.n;
        self.exps.reserve_exact(cap * n - self.exps.len());
        self.deg.reserve_exact(cap - self.deg.len());
        self.mask.reserve_exact(cap - self.mask.len());
        self.hash.reserve_exact(cap - self.hash.len());
        self.cap = cap;
        self.slots = vec![0; 2 * cap];
        let m = self.slots.len() - 1;
        for id in 0..self.len() {
            let mut i = self.home(self.hash[id]);
            while self.slots[i] != 0 {
                i = (i + 1) & m;
            }
            self.slots[i] = id as u32 + 1;
        }
    }

    /// Enters a monomial of the crate's `Mono` type.
    pub(crate) fn insert_mono(
        &mut self,
        m: &Mono,
        room: impl FnOnce(usize) -> Result<(), GbError>,
    ) -> Result<u32, GbError> {
        let e = pack(m.exponents())?;
        let h = self.hash_of(&e);
        self.insert(&e, m.degree(), h, room)
    }

    /// The monomial `id` as the crate's `Mono`.
    pub(crate) fn mono(&self, id: u32) -> Result<Mono, GbError> {
        Mono::from_exponents(self.exps(id).iter().map(|&x| x as u32).collect())
    }

    /// `a | b` for ids of this table and of `o`.
    #[inline]
    pub(crate) fn divides(&self, a: u32, o: &Table, b: u32) -> bool {
        self.mask(a) & !o.mask(b) == 0
            && self.deg(a) <= o.deg(b)
            && divides_exps(self.exps(a), o.exps(b))
    }

    /// `o.b / self.a` into `q`, assuming `a | b`.
    pub(crate) fn quotient(&self, a: u32, o: &Table, b: u32, q: &mut Scratch) {
        q.e.clear();
        q.e.extend(o.exps(b).iter().zip(self.exps(a)).map(|(y, x)| y - x));
        q.deg = o.deg(b) - self.deg(a);
        q.hash = o.hash(b).wrapping_sub(self.hash(a));
    }

    /// `q * id` into `out`; `GbError::Degree` if an exponent passes 16 bits
    /// or the degree passes `MAX_DEGREE`.
    #[inline]
    pub(crate) fn mul(&self, q: &Scratch, id: u32, out: &mut Scratch) -> Result<(), GbError> {
        out.e.clear();
        let mut hi = 0u32;
        out.e.extend(q.e.iter().zip(self.exps(id)).map(|(&x, &y)| {
            let s = x as u32 + y as u32;
            hi |= s;
            s as Exp
        }));
        out.deg = q.deg + self.deg(id);
        if hi > Exp::MAX as u32 || out.deg > MAX_DEGREE {
            return Err(GbError::Degree);
        }
        out.hash = q.hash.wrapping_add(self.hash(id));
        Ok(())
    }

    /// `order` on two ids of this table.
    #[inline]
    pub(crate) fn cmp(&self, order: Order, a: u32, b: u32) -> Ordering {
        cmp_exps(order, self.exps(a), self.deg(a), self.exps(b), self.deg(b))
    }
}

impl Scratch {
    pub(crate) fn new() -> Scratch {
        Scratch {
            e: Vec::new(),
            deg: 0,
            hash: 0,
        }
    }
}

/// 32-bit exponents packed, `GbError::Degree` past 16 bits.
pub(crate) fn pack(e: &[u32]) -> Result<Vec<Exp>, GbError> {
    e.iter()
        .map(|&x| Exp::try_from(x).map_err(|_| GbError::Degree))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// By hand: the table returns one id per distinct monomial, products
    /// hash as their factors' sum, and 65535 + 1 is refused.
    #[test]
    fn ids_products_and_the_width() {
        let n = 3;
        let mut t = Table::new(n, weights(n));
        let ok = |_| Ok(());
        let mut ids = Vec::new();
        for a in 0..10u16 {
            for b in 0..10u16 {
                let e = [a, b, 1];
                let h = t.hash_of(&e);
                ids.push(t.insert(&e, a as u32 + b as u32 + 1, h, ok).unwrap());
            }
        }
        assert_eq!(t.len(), 100);
        for (k, &id) in ids.iter().enumerate() {
            assert_eq!(id as usize, k);
            let e = t.exps(id).to_vec();
            let h = t.hash_of(&e);
            assert_eq!(t.insert(&e, t.deg(id), h, ok).unwrap(), id);
        }
        let q = Scratch {
            e: vec![1, 2, 3],
            deg: 6,
            hash: t.hash_of(&[1, 2, 3]),
        };
        let mut out = Scratch::new();
        t.mul(&q, ids[23], &mut out).unwrap();
        assert_eq!(out.e, vec![3, 5, 4]);
        assert_eq!(out.deg, 12);
        assert_eq!(out.hash, t.hash_of(&[3, 5, 4]));
        let big = Scratch {
            e: vec![Exp::MAX, 0, 0],
            deg: Exp::MAX as u32,
            hash: 0,
        };
        assert_eq!(t.mul(&big, ids[0], &mut out), Ok(()));
        assert_eq!(t.mul(&big, ids[10], &mut out), Err(GbError::Degree));
        assert_eq!(pack(&[65_536]), Err(GbError::Degree));
        assert!(t.bytes() >= table_bytes(n, 100, 200));
    }
}
