//! The prime field F_p, p < 2^63 (products in u128, never wrapping).

/// A prime field given by its modulus. Elements are `u64` in `0..p`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Field {
    p: u64,
}

impl Field {
    /// The field of the odd prime `p < 2^63`; `None` otherwise. Primality is
    /// checked (deterministic Miller–Rabin for 64-bit integers).
    pub fn new(p: u64) -> Option<Field> {
        if !(3..1 << 63).contains(&p) || !is_prime(p) {
            return None;
        }
        Some(Field { p })
    }

    pub fn modulus(&self) -> u64 {
        self.p
    }

    #[inline]
    pub fn add(&self, a: u64, b: u64) -> u64 {
        let s = a + b; // a, b < 2^63: no overflow
        if s >= self.p {
            s - self.p
        } else {
            s
        }
    }

    #[inline]
    pub fn sub(&self, a: u64, b: u64) -> u64 {
        if a >= b {
            a - b
        } else {
            a + self.p - b
        }
    }

    #[inline]
    pub fn neg(&self, a: u64) -> u64 {
        if a == 0 {
            0
        } else {
            self.p - a
        }
    }

    #[inline]
    pub fn mul(&self, a: u64, b: u64) -> u64 {
        ((a as u128 * b as u128) % self.p as u128) as u64
    }

    pub fn pow(&self, mut a: u64, mut e: u64) -> u64 {
        let mut r = 1;
        while e > 0 {
            if e & 1 == 1 {
                r = self.mul(r, a);
            }
            a = self.mul(a, a);
            e >>= 1;
        }
        r
    }

    /// The inverse of a non-zero element (`None` for 0).
    pub fn inv(&self, a: u64) -> Option<u64> {
        if a % self.p == 0 {
            return None;
        }
        Some(self.pow(a % self.p, self.p - 2))
    }

    /// The residue of a signed integer.
    pub fn from_i64(&self, x: i64) -> u64 {
        let r = (x as i128).rem_euclid(self.p as i128);
        r as u64
    }

    /// The residue of an unsigned integer.
    pub fn reduce(&self, x: u64) -> u64 {
        x % self.p
    }
}

fn mul_mod(a: u64, b: u64, m: u64) -> u64 {
    ((a as u128 * b as u128) % m as u128) as u64
}

fn pow_mod(mut a: u64, mut e: u64, m: u64) -> u64 {
    let mut r = 1 % m;
    a %= m;
    while e > 0 {
        if e & 1 == 1 {
            r = mul_mod(r, a, m);
        }
        a = mul_mod(a, a, m);
        e >>= 1;
    }
    r
}

/// Deterministic Miller–Rabin for all 64-bit integers (the first 12 primes
/// as bases suffice below 3.3e24).
pub fn is_prime(n: u64) -> bool {
    if n < 2 {
        return false;
    }
    const BASES: [u64; 12] = [2, 3, 5, 7, 11, 13, 17, 19, 23, 29, 31, 37];
    for &b in &BASES {
        if n % b == 0 {
            return n == b;
        }
    }
    let mut d = n - 1;
    let mut s = 0;
    while d % 2 == 0 {
        d /= 2;
        s += 1;
    }
    'outer: for &a in &BASES {
        let mut x = pow_mod(a, d, n);
        if x == 1 || x == n - 1 {
            continue;
        }
        for _ in 1..s {
            x = mul_mod(x, x, n);
            if x == n - 1 {
                continue 'outer;
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
    fn primes_and_inverses() {
        // 2^61 - 1 is a Mersenne prime; 2^62 - 1 = 3 * 715827883 * 2147483647.
        assert!(Field::new((1 << 61) - 1).is_some());
        assert!(Field::new((1 << 62) - 1).is_none());
        let f = Field::new((1 << 61) - 1).unwrap();
        for a in [1u64, 2, 12345, (1 << 61) - 2] {
            assert_eq!(f.mul(a, f.inv(a).unwrap()), 1);
        }
        assert_eq!(f.inv(0), None);
        assert_eq!(f.from_i64(-1), (1 << 61) - 2);
    }
}
