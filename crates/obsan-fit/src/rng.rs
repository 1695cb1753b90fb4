//! The estimation side's seeded generator: the engine's SplitMix64
//! ([`obsan_expr::SplitMix`], stepped by obsan-recon's `splitmix64`, the
//! workspace's one) with uniform and normal (Box–Muller: the workspace's one,
//! which the simulating tests use too) deviates. Results depend on the seed
//! only, never on a crate version or on scheduling.

use obsan_expr::SplitMix;

#[derive(Clone, Debug)]
pub struct Rng {
    bits: SplitMix,
    spare: Option<f64>,
}

impl Rng {
    pub fn new(seed: u64) -> Rng {
        Rng {
            bits: SplitMix(seed ^ 0x6a09_e667_f3bc_c909),
            spare: None,
        }
    }
    pub fn next_u64(&mut self) -> u64 {
        self.bits.next_u64()
    }
    /// Uniform in (0, 1).
    pub fn uniform(&mut self) -> f64 {
        ((self.next_u64() >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }
    /// Standard normal.
    pub fn normal(&mut self) -> f64 {
        if let Some(s) = self.spare.take() {
            return s;
        }
        let (z, spare) = box_muller(self.uniform(), self.uniform());
        self.spare = Some(spare);
        z
    }
}

/// Two independent standard normal deviates from two independent uniform
/// deviates `u` in (0, 1] and `v` in [0, 1) (Box & Muller 1958): with
/// `r = sqrt(-2 ln u)`, `(r cos 2 pi v, r sin 2 pi v)`. The workspace's one
/// Box–Muller transform; the simulating tests draw through it too.
pub fn box_muller(u: f64, v: f64) -> (f64, f64) {
    let r = (-2.0 * u.ln()).sqrt();
    let a = 2.0 * std::f64::consts::PI * v;
    (r * a.cos(), r * a.sin())
}
