//! Arithmetic in the prime field F_p for any prime p < 2^63.
//!
//! Residues are `u64` in `0..p`; products go through `u128`, so sums of two
//! residues never overflow (p < 2^63).

/// Primes just below 2^62, largest first. Reconstruction uses them in order;
/// the last [`VERIFY_PRIMES`] are never used for reconstruction and serve
/// the final check at fresh points. Every entry is proven prime by the
/// deterministic Miller–Rabin test in this module's tests.
pub const PRIMES: [u64; 24] = [
    0x3fff_ffff_ffff_ffc7,
    0x3fff_ffff_ffff_ffa9,
    0x3fff_ffff_ffff_ff8b,
    0x3fff_ffff_ffff_ff71,
    0x3fff_ffff_ffff_ff67,
    0x3fff_ffff_ffff_ff59,
    0x3fff_ffff_ffff_ff55,
    0x3fff_ffff_ffff_ff3d,
    0x3fff_ffff_ffff_ff35,
    0x3fff_ffff_ffff_feef,
    0x3fff_ffff_ffff_fee1,
    0x3fff_ffff_ffff_fec3,
    0x3fff_ffff_ffff_fe45,
    0x3fff_ffff_ffff_fe1d,
    0x3fff_ffff_ffff_fe11,
    0x3fff_ffff_ffff_fdc1,
    0x3fff_ffff_ffff_fdbb,
    0x3fff_ffff_ffff_fda5,
    0x3fff_ffff_ffff_fd87,
    0x3fff_ffff_ffff_fd69,
    0x3fff_ffff_ffff_fd03,
    0x3fff_ffff_ffff_fcfb,
    0x3fff_ffff_ffff_fcf7,
    0x3fff_ffff_ffff_fce9,
];

/// Primes just below 2^52, largest first, as many as [`PRIMES`] and used
/// the same way: residues modulo them fit AVX-512 IFMA's 52-bit operands,
/// so dense eliminations modulo them run 3.5-4x faster where the CPU has it
/// (`fp::reduce_delayed52`), at 10 bits less per prime. Proven prime as
/// [`PRIMES`] is.
pub const PRIMES52: [u64; 24] = [
    0xf_ffff_ffff_ffd1,
    0xf_ffff_ffff_ff71,
    0xf_ffff_ffff_ff53,
    0xf_ffff_ffff_ff49,
    0xf_ffff_ffff_ff3b,
    0xf_ffff_ffff_ff2f,
    0xf_ffff_ffff_fef3,
    0xf_ffff_ffff_fee3,
    0xf_ffff_ffff_feb1,
    0xf_ffff_ffff_fe75,
    0xf_ffff_ffff_fe63,
    0xf_ffff_ffff_fe27,
    0xf_ffff_ffff_fe11,
    0xf_ffff_ffff_fdd3,
    0xf_ffff_ffff_fd87,
    0xf_ffff_ffff_fd85,
    0xf_ffff_ffff_fd6d,
    0xf_ffff_ffff_fd63,
    0xf_ffff_ffff_fd45,
    0xf_ffff_ffff_fd0d,
    0xf_ffff_ffff_fce3,
    0xf_ffff_ffff_fccd,
    0xf_ffff_ffff_fcb9,
    0xf_ffff_ffff_fc9d,
];

/// How many entries at the end of [`PRIMES`] are reserved for verification.
pub const VERIFY_PRIMES: usize = 4;

/// How many primes reconstruction may use at most.
pub const MAX_RECON_PRIMES: usize = PRIMES.len() - VERIFY_PRIMES;

#[inline]
pub fn add(a: u64, b: u64, p: u64) -> u64 {
    let s = a + b;
    if s >= p {
        s - p
    } else {
        s
    }
}

#[inline]
pub fn sub(a: u64, b: u64, p: u64) -> u64 {
    if a >= b {
        a - b
    } else {
        a + (p - b)
    }
}

#[cfg(test)]
pub(crate) fn neg(a: u64, p: u64) -> u64 {
    if a == 0 {
        0
    } else {
        p - a
    }
}

#[inline]
pub fn mul(a: u64, b: u64, p: u64) -> u64 {
    ((a as u128 * b as u128) % p as u128) as u64
}

/// Products by one fixed residue `c` without a division (Shoup's method,
/// V. Shoup, NTL): with `c' = floor(c 2^64 / p)` precomputed, `q =
/// floor(c' y / 2^64)` is `floor(c y / p)` or one less, so `c y - q p` lies
/// in `0..2p` (p < 2^63) and one subtraction reduces it. For loops that
/// multiply many values by one scalar (elimination rows, Cauchy products).
#[derive(Clone, Copy, Debug)]
pub struct Shoup {
    c: u64,
    pre: u64,
    p: u64,
}

impl Shoup {
    /// For `c` in `0..p`, `p < 2^63`.
    #[inline]
    pub fn new(c: u64, p: u64) -> Shoup {
        Shoup {
            c,
            pre: (((c as u128) << 64) / p as u128) as u64,
            p,
        }
    }

    /// `c y mod p` for any `y < 2^64`.
    #[inline]
    pub fn times(self, y: u64) -> u64 {
        let q = ((self.pre as u128 * y as u128) >> 64) as u64;
        let r = self.c.wrapping_mul(y).wrapping_sub(q.wrapping_mul(self.p));
        if r >= self.p {
            r - self.p
        } else {
            r
        }
    }
}

/// Sums of products made small again without a remainder: `x = x_1 2^64 +
/// x_0` becomes `x_1 (2^64 mod p) + x_0`, below 2^97 and of the same
/// residue, when `2^64 mod p < 2^32` ([`PRIMES`], each `2^62 - c` with `c`
/// small, have `2^64 mod p = 4 c`). One product per entry where
/// [`Rem128::reduce`] takes two and their corrections: the dense
/// elimination's periodic reductions (echelon.rs) were 43% of its time on
/// SIWR_orig's kernels.
#[derive(Clone, Copy, Debug)]
pub struct Fold {
    c: u64,
}

impl Fold {
    /// Every fold's result is below this.
    pub const BOUND: u128 = 1 << 97;

    /// The fold modulo `p`, if `2^64 mod p < 2^32`.
    pub fn new(p: u64) -> Option<Fold> {
        let c = ((1u128 << 64) % u128::from(p.max(1))) as u64;
        (c < 1 << 32).then_some(Fold { c })
    }

    #[inline]
    pub fn fold(self, x: u128) -> u128 {
        u128::from(x as u64) + (x >> 64) * u128::from(self.c)
    }
}

/// Remainders of any `u128` modulo `p < 2^63` without a division: `x =
/// x_1 2^64 + x_0` is `x_1 (2^64 mod p) + x_0` modulo p, each term one
/// [`Shoup`] product (`x_0 = 1 * x_0`; Shoup's bound holds for any
/// multiplicand below 2^64). For sums of products reduced late.
#[derive(Clone, Copy, Debug)]
pub struct Rem128 {
    hi: Shoup,
    lo: Shoup,
}

impl Rem128 {
    pub fn new(p: u64) -> Rem128 {
        let r = (u64::MAX % p + 1) % p;
        Rem128 {
            hi: Shoup::new(r, p),
            lo: Shoup::new(1 % p, p),
        }
    }

    #[inline]
    pub fn reduce(self, x: u128) -> u64 {
        add(
            self.hi.times((x >> 64) as u64),
            self.lo.times(x as u64),
            self.hi.p,
        )
    }
}

pub fn pow(mut a: u64, mut e: u64, p: u64) -> u64 {
    let mut r = 1 % p;
    while e > 0 {
        if e & 1 == 1 {
            r = mul(r, a, p);
        }
        a = mul(a, a, p);
        e >>= 1;
    }
    r
}

/// Inverse modulo p (extended Euclid); `None` for zero. The remainders
/// are `u64` (64-bit divisions); only the Bezout coefficient, bounded by
/// `p` in size, is kept in `i128`.
pub fn inv(a: u64, p: u64) -> Option<u64> {
    if a == 0 {
        return None;
    }
    let (mut r0, mut r1) = (p, a % p);
    let (mut s0, mut s1) = (0i128, 1i128);
    while r1 != 0 {
        let q = r0 / r1;
        (r0, r1) = (r1, r0 - q * r1);
        (s0, s1) = (s1, s0 - q as i128 * s1);
    }
    // r0 = gcd(p, a); 1 for a prime p and 0 < a < p.
    if r0 != 1 {
        return None;
    }
    Some(s0.rem_euclid(p as i128) as u64)
}

/// Deterministic Miller–Rabin for every `u64`: the first twelve primes as
/// bases suffice below 3.3e24 (Sorenson & Webster 2015).
pub fn is_prime(n: u64) -> bool {
    const BASES: [u64; 12] = [2, 3, 5, 7, 11, 13, 17, 19, 23, 29, 31, 37];
    if n < 2 {
        return false;
    }
    for &b in &BASES {
        if n.is_multiple_of(b) {
            return n == b;
        }
    }
    let mut d = n - 1;
    let mut s = 0;
    while d.is_multiple_of(2) {
        d /= 2;
        s += 1;
    }
    'base: for &a in &BASES {
        let mut x = pow(a, d, n);
        if x == 1 || x == n - 1 {
            continue;
        }
        for _ in 1..s {
            x = mul(x, x, n);
            if x == n - 1 {
                continue 'base;
            }
        }
        return false;
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn folds_keep_the_residue_below_their_bound() {
        for (k, &p) in PRIMES.iter().enumerate() {
            let f = Fold::new(p).expect("the list's primes are 2^62 - c, c small");
            let m = Rem128::new(p);
            let mut st = k as u64;
            for _ in 0..200 {
                let x = (u128::from(crate::rng::splitmix64(&mut st)) << 64)
                    | u128::from(crate::rng::splitmix64(&mut st));
                for x in [x, u128::MAX, 0, u128::from(p) * u128::from(p - 1)] {
                    let y = f.fold(x);
                    assert!(y < Fold::BOUND);
                    assert_eq!(m.reduce(y), (x % u128::from(p)) as u64);
                }
            }
        }
    }

    #[test]
    fn the_prime_lists_are_the_largest_primes_below_2_62_and_2_52() {
        for (list, bits) in [(&PRIMES, 62), (&PRIMES52, 52)] {
            for (i, &p) in list.iter().enumerate() {
                assert!(is_prime(p), "{p:#x}");
                assert!(p < 1 << bits);
                if i > 0 {
                    assert!(p < list[i - 1]);
                }
            }
            // Nothing between consecutive entries (and above the first) is
            // prime: the list is the largest primes below 2^bits.
            let mut n = (1u64 << bits) - 1;
            for &p in list {
                while n > p {
                    assert!(!is_prime(n), "{n:#x} is prime but missing");
                    n -= 1;
                }
                n = p - 1;
            }
        }
    }

    #[test]
    fn miller_rabin_agrees_with_trial_division() {
        let trial = |n: u64| {
            n >= 2
                && (2..)
                    .take_while(|d| d * d <= n)
                    .all(|d| !n.is_multiple_of(d))
        };
        for n in 0..20_000 {
            assert_eq!(is_prime(n), trial(n), "{n}");
        }
        // Strong pseudoprimes to several bases, and a Carmichael number.
        for n in [3_215_031_751u64, 2_152_302_898_747, 3_474_749_660_383, 561] {
            assert!(!is_prime(n));
        }
        assert!(is_prime(18_446_744_073_709_551_557)); // largest u64 prime
    }

    #[test]
    fn shoup_products_agree_with_u128_remainders() {
        // Against the naive `(c y) % p` in u128, at the edges (0, 1, p - 1,
        // y up to 2^64 - 1) and at random residues, for the list's primes,
        // the Mersenne prime 2^61 - 1, a small prime and one just below 2^63.
        let mut st = 0x5eed_u64;
        let mut next = || crate::rng::splitmix64(&mut st);
        for p in [
            PRIMES[0],
            PRIMES[23],
            (1 << 61) - 1,
            65_537,
            0x7fff_ffff_ffff_ffe7,
        ] {
            assert!(is_prime(p));
            let mut cs = vec![0, 1, 2, p - 1, p / 2];
            cs.extend((0..40).map(|_| next() % p));
            let mut ys = vec![0, 1, p - 1, p, u64::MAX, u64::MAX - 1];
            ys.extend((0..40).map(|_| next() % p));
            ys.extend((0..10).map(|_| next()));
            for &c in &cs {
                let s = Shoup::new(c, p);
                for &y in &ys {
                    assert_eq!(
                        s.times(y),
                        ((c as u128 * y as u128) % p as u128) as u64,
                        "{c} {y} {p}"
                    );
                }
            }
        }
    }

    #[test]
    fn u128_remainders_without_division_agree_with_the_naive_ones() {
        let mut st = 0x12_u64;
        let mut next = || crate::rng::splitmix64(&mut st);
        for p in [
            PRIMES[0],
            PRIMES[17],
            (1 << 61) - 1,
            65_537,
            3,
            0x7fff_ffff_ffff_ffe7,
        ] {
            let r = Rem128::new(p);
            let mut xs: Vec<u128> = vec![
                0,
                1,
                p as u128,
                u128::MAX,
                u128::MAX - 1,
                (p as u128) * (p as u128) - 1,
                1 << 64,
                (1 << 64) - 1,
            ];
            xs.extend((0..200).map(|_| ((next() as u128) << 64) | next() as u128));
            xs.extend((0..50).map(|_| (next() % p) as u128 * (next() % p) as u128 * 15));
            for &x in &xs {
                assert_eq!(r.reduce(x), (x % p as u128) as u64, "{x} mod {p}");
            }
        }
    }

    #[test]
    fn inverse_and_power_identities() {
        let p = PRIMES[0];
        let mut a = 12345u64;
        for _ in 0..200 {
            let ia = inv(a, p).unwrap();
            assert_eq!(mul(a, ia, p), 1);
            // Fermat: a^(p-1) = 1.
            assert_eq!(pow(a, p - 1, p), 1);
            assert_eq!(add(a, neg(a, p), p), 0);
            assert_eq!(sub(add(a, 7, p), 7, p), a);
            a = mul(a, 0x9e37_79b9_7f4a_7c15 % p, p);
        }
        assert_eq!(inv(0, p), None);
        // Against Fermat's a^(p-2) at random residues of several primes.
        let mut st = 3u64;
        for q in [PRIMES[5], (1 << 61) - 1, 65_537, 0x7fff_ffff_ffff_ffe7] {
            for _ in 0..200 {
                let x = crate::rng::splitmix64(&mut st) % q;
                if x != 0 {
                    assert_eq!(inv(x, q), Some(pow(x, q - 2, q)));
                }
            }
            assert_eq!(inv(1, q), Some(1));
        }
        assert_eq!(inv(p - 1, p), Some(p - 1));
    }
}
