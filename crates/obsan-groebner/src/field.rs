//! The prime field F_p, p < 2^63 (products in u128, never wrapping).

use obsan_recon::fp;
pub use obsan_recon::is_prime;

/// A prime field given by its modulus. Elements are `u64` in `0..p`. The
/// arithmetic is obsan-recon's (`obsan_recon::fp`), the workspace's one
/// implementation; this type only carries the modulus.
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
        fp::add(a, b, self.p)
    }

    #[inline]
    pub fn sub(&self, a: u64, b: u64) -> u64 {
        fp::sub(a, b, self.p)
    }

    #[inline]
    pub fn neg(&self, a: u64) -> u64 {
        fp::sub(0, a, self.p)
    }

    #[inline]
    pub fn mul(&self, a: u64, b: u64) -> u64 {
        fp::mul(a, b, self.p)
    }

    pub fn pow(&self, a: u64, e: u64) -> u64 {
        fp::pow(a % self.p, e, self.p)
    }

    /// The inverse of a non-zero element (`None` for 0).
    pub fn inv(&self, a: u64) -> Option<u64> {
        fp::inv(a % self.p, self.p)
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
