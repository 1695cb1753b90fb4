//! The workspace's one home of `unsafe` code: rows of residues multiplied
//! and added into split accumulators with AVX-512 IFMA, chosen at run time,
//! and a portable loop with bit-identical results everywhere else.
//!
//! The modular kernels of the input-output route are dense eliminations
//! whose inner loop is `acc[j] += c * row[j]`. In `u128` one core does about
//! 1.2 G such multiply-adds a second; IFMA's `vpmadd52luq`/`vpmadd52huq`
//! multiply eight pairs of 52-bit operands at once and add the low and the
//! high 52 bits of each 104-bit product to two 64-bit accumulators (a row
//! pass alone: 8.6 G a second, session 41's prototype), so that whole dense
//! kernels modulo a prime below 2^52 run 3.5-4x faster (`cargo bench -p
//! obsan-recon --bench recon`; `docs/performance.md`, session 42). An entry
//! is then `lo + 2^52 hi`; the caller reduces it modulo its prime before
//! either half can wrap.
//!
//! The rest of the workspace forbids `unsafe`. Here it is confined to
//! [`madd52`]'s dispatch: the loads and stores of eight lanes, in bounds
//! by the lengths checked on entry, and the call into the
//! `#[target_feature]` pass, made only after the CPU reported the feature.

/// The operand bits the multiply-adds read: each operand is taken modulo
/// 2^52 (its low 52 bits), as the hardware does.
pub const BITS: u32 = 52;

/// `2^52 - 1`.
pub const MASK: u64 = (1 << BITS) - 1;

/// Products of 52-bit operands a pair of halves takes, from `lo < 2^52`
/// and `hi = 0`, before either can wrap: each adds below 2^52 to each
/// half, so after 4095 of them `lo < 2^52 + 4095 (2^52 - 1) < 2^64` and
/// `hi < 2^64` (a test reaches the bound).
pub const ROOM: usize = 4095;

/// Whether [`madd52`] runs on AVX-512 IFMA on this CPU (else the portable
/// loop). The detection is cached by the standard library.
pub fn ifma() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx512f")
            && std::arch::is_x86_feature_detected!("avx512ifma")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// For each column `j < lo.len()` and each row `k`, with the product `x =
/// (cs[k] & MASK) (rows[k][j] & MASK)` (below 2^104): `lo[j] += x mod 2^52`
/// and `hi[j] += x >> 52`, each wrapping modulo 2^64, so that `lo + 2^52 hi` grows by the
/// sum of the products while neither half wraps (the caller's bound: from
/// `lo < 2^52`, 4095 products of 52-bit operands). Runs on AVX-512 IFMA
/// when [`ifma`] says so, else [`madd52_portable`]; both give the same bits.
///
/// # Panics
/// When `hi` is not as long as `lo`, `cs` not as long as `rows`, or a row
/// shorter than `lo`.
pub fn madd52(lo: &mut [u64], hi: &mut [u64], cs: &[u64], rows: &[&[u64]]) {
    check(lo, hi, cs, rows);
    #[cfg(target_arch = "x86_64")]
    if ifma() {
        for (c, r) in cs.chunks(8).zip(rows.chunks(8)) {
            // SAFETY: `ifma()` found avx512f and avx512ifma on this CPU, and
            // `check` found every row at least as long as `lo` and `hi` (the
            // pass reads and writes columns below `lo.len()` only).
            unsafe {
                match c.len() {
                    8 => x86::pass::<8>(lo, hi, arr(c), arr(r)),
                    7 => x86::pass::<7>(lo, hi, arr(c), arr(r)),
                    6 => x86::pass::<6>(lo, hi, arr(c), arr(r)),
                    5 => x86::pass::<5>(lo, hi, arr(c), arr(r)),
                    4 => x86::pass::<4>(lo, hi, arr(c), arr(r)),
                    3 => x86::pass::<3>(lo, hi, arr(c), arr(r)),
                    2 => x86::pass::<2>(lo, hi, arr(c), arr(r)),
                    _ => x86::pass::<1>(lo, hi, arr(c), arr(r)),
                }
            }
        }
        return;
    }
    portable(lo, hi, cs, rows);
}

/// [`madd52`] without the hardware: the definition, and the fallback.
///
/// # Panics
/// As [`madd52`].
pub fn madd52_portable(lo: &mut [u64], hi: &mut [u64], cs: &[u64], rows: &[&[u64]]) {
    check(lo, hi, cs, rows);
    portable(lo, hi, cs, rows);
}

fn check(lo: &[u64], hi: &[u64], cs: &[u64], rows: &[&[u64]]) {
    assert_eq!(lo.len(), hi.len(), "madd52: halves of different lengths");
    assert_eq!(cs.len(), rows.len(), "madd52: one multiplier per row");
    assert!(
        rows.iter().all(|r| r.len() >= lo.len()),
        "madd52: a row shorter than the accumulator"
    );
}

/// A slice of known length as an array (the caller chunked it).
#[cfg(target_arch = "x86_64")]
fn arr<T, const K: usize>(s: &[T]) -> &[T; K] {
    s.try_into().expect("a chunk of K")
}

/// The products, one at a time.
fn portable(lo: &mut [u64], hi: &mut [u64], cs: &[u64], rows: &[&[u64]]) {
    let n = lo.len();
    for (&c, r) in cs.iter().zip(rows) {
        let c = u128::from(c & MASK);
        for ((l, h), &y) in lo.iter_mut().zip(hi.iter_mut()).zip(&r[..n]) {
            let x = c * u128::from(y & MASK);
            *l = l.wrapping_add(x as u64 & MASK);
            *h = h.wrapping_add((x >> BITS) as u64);
        }
    }
}

#[cfg(target_arch = "x86_64")]
mod x86 {
    use std::arch::x86_64::{
        __m512i, __mmask8, _mm512_loadu_epi64, _mm512_madd52hi_epu64, _mm512_madd52lo_epu64,
        _mm512_mask_storeu_epi64, _mm512_maskz_loadu_epi64, _mm512_set1_epi64,
        _mm512_setzero_si512, _mm512_storeu_epi64,
    };

    /// Eight columns at a time, all `K` rows (up to eight) added to each
    /// loaded pair of accumulators before it is stored (one load and store
    /// per `K` products); the last `len % 8` columns under a mask.
    ///
    /// # Safety
    /// The CPU has avx512f and avx512ifma, and every row is at least as
    /// long as `lo`, which is as long as `hi`.
    #[target_feature(enable = "avx512f,avx512ifma")]
    pub(super) unsafe fn pass<const K: usize>(
        lo: &mut [u64],
        hi: &mut [u64],
        cs: &[u64; K],
        rows: &[&[u64]; K],
    ) {
        let n = lo.len();
        let mut c = [_mm512_setzero_si512(); K];
        for k in 0..K {
            c[k] = _mm512_set1_epi64(cs[k] as i64);
        }
        let whole = n / 8 * 8;
        let mut j = 0;
        while j < whole {
            // SAFETY: j + 8 <= n, and lo, hi and every row hold at least n
            // entries (the caller's contract); unaligned loads and stores.
            unsafe {
                let at = |s: &[u64]| s.as_ptr().add(j) as *const i64;
                let mut l: __m512i = _mm512_loadu_epi64(at(lo));
                let mut h: __m512i = _mm512_loadu_epi64(at(hi));
                for k in 0..K {
                    let y = _mm512_loadu_epi64(at(rows[k]));
                    l = _mm512_madd52lo_epu64(l, c[k], y);
                    h = _mm512_madd52hi_epu64(h, c[k], y);
                }
                _mm512_storeu_epi64(lo.as_mut_ptr().add(j) as *mut i64, l);
                _mm512_storeu_epi64(hi.as_mut_ptr().add(j) as *mut i64, h);
            }
            j += 8;
        }
        if whole < n {
            // The last `n % 8` columns under a mask: masked-off lanes are
            // neither read nor written (no fault past the slices' ends).
            let mask: __mmask8 = (1u8 << (n - whole)) - 1;
            // SAFETY: the lanes the mask keeps are columns whole..n, below
            // the length of lo, hi and every row.
            unsafe {
                let at = |s: &[u64]| s.as_ptr().add(whole) as *const i64;
                let mut l = _mm512_maskz_loadu_epi64(mask, at(lo));
                let mut h = _mm512_maskz_loadu_epi64(mask, at(hi));
                for k in 0..K {
                    let y = _mm512_maskz_loadu_epi64(mask, at(rows[k]));
                    l = _mm512_madd52lo_epu64(l, c[k], y);
                    h = _mm512_madd52hi_epu64(h, c[k], y);
                }
                _mm512_mask_storeu_epi64(lo.as_mut_ptr().add(whole) as *mut i64, mask, l);
                _mm512_mask_storeu_epi64(hi.as_mut_ptr().add(whole) as *mut i64, mask, h);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// `lo + 2^52 hi` as one number (no half has wrapped in these tests).
    fn value(lo: u64, hi: u64) -> u128 {
        u128::from(lo) + (u128::from(hi) << BITS)
    }

    #[test]
    fn reports_the_backend() {
        // Not an assertion: which path the equality tests below exercised.
        eprintln!("obsan-simd: AVX-512 IFMA on this CPU: {}", ifma());
    }

    #[test]
    fn the_halves_sum_the_products() {
        // ROOM products of the largest 52-bit operands from lo = 2^52 - 1:
        // reached without a wrap.
        let n = 19;
        let mut lo = vec![MASK; n];
        let mut hi = vec![0; n];
        let row = vec![MASK; n];
        let rows: Vec<&[u64]> = vec![&row; 5];
        let cs = vec![MASK; 5];
        assert_eq!(ROOM % 5, 0);
        for _ in 0..ROOM / 5 {
            madd52(&mut lo, &mut hi, &cs, &rows);
        }
        let x = u128::from(MASK) * u128::from(MASK);
        for j in 0..n {
            assert_eq!(value(lo[j], hi[j]), u128::from(MASK) + ROOM as u128 * x);
        }
    }

    proptest! {
        /// The hardware and the definition agree bit for bit, wrapping
        /// included, for any operands (their bits past 52 ignored) and any
        /// length (the tail past a multiple of eight).
        #[test]
        fn ifma_is_the_portable_loop(
            n in 0usize..41,
            k in 0usize..10,
            seed in any::<u64>(),
        ) {
            let mut s = seed;
            let mut next = || {
                s = s.wrapping_add(0x9e37_79b9_7f4a_7c15);
                let mut z = s;
                z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
                z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
                z ^ (z >> 31)
            };
            let lo: Vec<u64> = (0..n).map(|_| next()).collect();
            let hi: Vec<u64> = (0..n).map(|_| next()).collect();
            let cs: Vec<u64> = (0..k).map(|_| next()).collect();
            // Rows may be longer than the accumulator.
            let rows: Vec<Vec<u64>> = (0..k).map(|i| (0..n + i % 3).map(|_| next()).collect()).collect();
            let refs: Vec<&[u64]> = rows.iter().map(Vec::as_slice).collect();
            let (mut l1, mut h1) = (lo.clone(), hi.clone());
            madd52(&mut l1, &mut h1, &cs, &refs);
            let (mut l2, mut h2) = (lo, hi);
            madd52_portable(&mut l2, &mut h2, &cs, &refs);
            prop_assert_eq!(l1, l2);
            prop_assert_eq!(h1, h2);
        }

        /// Without wraps, `lo + 2^52 hi` grows by exactly the products of
        /// the operands' low 52 bits.
        #[test]
        fn adds_the_products(
            cs in proptest::collection::vec(any::<u64>(), 0..9),
            y in proptest::collection::vec(any::<u64>(), 9..10),
            start in 0u64..(1 << 52),
        ) {
            let n = 11;
            let rows: Vec<Vec<u64>> = (0..cs.len()).map(|i| {
                (0..n).map(|j| y[(i + j) % y.len()].rotate_left(j as u32)).collect()
            }).collect();
            let refs: Vec<&[u64]> = rows.iter().map(Vec::as_slice).collect();
            let mut lo = vec![start; n];
            let mut hi = vec![0; n];
            madd52(&mut lo, &mut hi, &cs, &refs);
            for j in 0..n {
                let want = cs.iter().zip(&rows).fold(u128::from(start), |a, (&c, r)| {
                    a + u128::from(c & MASK) * u128::from(r[j] & MASK)
                });
                prop_assert_eq!(value(lo[j], hi[j]), want);
            }
        }
    }
}
