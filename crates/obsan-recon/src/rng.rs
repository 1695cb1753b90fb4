//! SplitMix64 (Steele, Lea & Flood 2014), the workspace's one seeded
//! generator step: reproducible random points without a dependency. The
//! engine's `SplitMix` (obsan-expr) and the estimation side's `Rng`
//! (obsan-fit, over it) step with [`splitmix64`].

/// Advances `state` and returns the next SplitMix64 output.
#[inline]
pub fn splitmix64(state: &mut u64) -> u64 {
    *state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

#[derive(Clone, Debug)]
pub(crate) struct Rng(u64);

impl Rng {
    pub(crate) fn new(seed: u64) -> Self {
        Rng(seed ^ 0x5851_f42d_4c95_7f2d)
    }

    pub(crate) fn next_u64(&mut self) -> u64 {
        splitmix64(&mut self.0)
    }

    /// Uniform in `1..p` (rejection sampling, so no modulo bias).
    pub(crate) fn nonzero(&mut self, p: u64) -> u64 {
        let zone = u64::MAX - u64::MAX % p;
        loop {
            let x = self.next_u64();
            if x < zone {
                let r = x % p;
                if r != 0 {
                    return r;
                }
            }
        }
    }
}
