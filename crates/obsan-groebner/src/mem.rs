//! What a computation holds, in bytes: counted before each allocation so that
//! a memory budget ([`GbBudget::max_bytes`](crate::GbBudget)) is refused
//! before it is passed, never found out by the operating system.
//!
//! The unit is the allocator's block: glibc malloc hands out, for a request
//! of `r > 0` bytes, a chunk of `r` plus an 8-byte header rounded up to 16,
//! at least 32. A term `(Mono, u64)` is 32 bytes inline in its polynomial's
//! buffer plus one such block for the monomial's `4 n` bytes of exponents
//! (tests/memory.rs checks the count against a counting allocator).
//!
//! F4 (`f4.rs`, `f4mat.rs`) holds each monomial once, in a table
//! (`table.rs`, `table_bytes`: `2 n` bytes of 16-bit
//! exponents, a u32 degree, u64 mask and hash, each vector's capacity
//! counted as it doubles, and 4-byte hash slots at most half full), so a
//! term of its basis is a u32 id and a u64 coefficient in two buffers
//! (`f4state::elem_bytes`: 12 bytes, against 32 + `block(4 n)` above), a pair 16
//! bytes (its lcm an id), a matrix row 4 bytes an entry (its coefficients are
//! its basis element's), a column 33 bytes beside its table entry
//! (`f4mat::col_bytes`). Only the final basis is converted back to `Poly`s,
//! counted by [`poly_bytes`] before it is built.

use crate::poly::{Mono, Poly};
use std::mem::size_of;

/// The allocator's block for a request of `req` bytes (0: no allocation).
pub(crate) fn block(req: usize) -> usize {
    if req == 0 {
        0
    } else {
        (req.saturating_add(8).div_ceil(16) * 16).max(32)
    }
}

/// The heap block of one monomial's exponents in `n` variables.
pub(crate) fn mono_heap(n: usize) -> usize {
    block(4 * n)
}

/// One monomial held by value in a container (inline part and exponents).
pub(crate) fn mono_bytes(n: usize) -> usize {
    size_of::<Mono>() + mono_heap(n)
}

/// One term held in a polynomial's buffer.
pub fn term_bytes(n: usize) -> usize {
    size_of::<(Mono, u64)>() + mono_heap(n)
}

impl Poly {
    /// The bytes this polynomial holds in `n` variables: its term buffer
    /// (sized to its length, as every polynomial a basis keeps is) and the
    /// exponents of each monomial. The `Poly` value itself is not counted
    /// (it lives in its container).
    pub fn stored_bytes(&self, n: usize) -> usize {
        block(self.len() * size_of::<(Mono, u64)>()) + self.len() * mono_heap(n)
    }
}

/// The bytes [`Poly::stored_bytes`] gives a polynomial of `len` terms.
pub(crate) fn poly_bytes(len: usize, n: usize) -> usize {
    block(len * size_of::<(Mono, u64)>()) + len * mono_heap(n)
}

/// Bytes past a budget: the error's fields, `what` naming the stage.
pub(crate) fn over(held: usize, max: usize, what: impl FnOnce() -> String) -> crate::GbError {
    crate::GbError::Memory {
        bytes: held as u128,
        max: max as u128,
        what: what(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{f4, Field, GbBudget, Order, Ring};

    /// glibc's request2size (malloc.c): `(r + 8 + 15) & !15`, at least 32.
    #[test]
    fn blocks_are_glibc_chunks() {
        for (req, chunk) in [
            (0, 0),
            (1, 32),
            (24, 32),
            (25, 48),
            (40, 48),
            (41, 64),
            (4096, 4112),
        ] {
            assert_eq!(block(req), chunk, "{req}");
        }
    }

    /// The count of a basis matches what its polynomials store: each term
    /// buffer has exactly its length (no spare capacity), a term is 32 bytes
    /// inline (a u32 degree padded to 8, a 16-byte boxed slice, a u64) and
    /// its exponents one block of 4 n bytes.
    #[test]
    fn stored_bytes_match_the_stored_terms() {
        let n = 5;
        let f = Field::new((1 << 61) - 1).unwrap();
        let r = Ring::new(f, n, Order::Grevlex);
        // Cyclic-5 (70 solutions).
        let gens: Vec<Poly> = (1..=n)
            .map(|d| {
                let mut t: Vec<(Mono, u64)> = (0..n)
                    .map(|s| {
                        let mut e = vec![0u32; n];
                        for k in 0..d {
                            e[(s + k) % n] = 1;
                        }
                        (Mono::from_exponents(e).unwrap(), 1)
                    })
                    .collect();
                if d == n {
                    t.truncate(1);
                    t.push((Mono::one(n), f.from_i64(-1)));
                }
                r.from_terms(t)
            })
            .collect();
        let b = f4(&r, &gens, GbBudget::default()).unwrap();
        assert_eq!(size_of::<(Mono, u64)>(), 32);
        assert_eq!(term_bytes(n), 32 + 32); // 4 * 5 + 8 = 28 -> 32
        let mut terms = 0;
        for p in &b.polys {
            assert_eq!(p.terms.capacity(), p.len());
            for (m, _) in p.terms() {
                assert_eq!(m.exponents().len(), n);
            }
            terms += p.len();
            assert_eq!(p.stored_bytes(n), block(32 * p.len()) + 32 * p.len());
        }
        assert!(terms > 100, "{terms}");
    }
}
