//! Shared by the unicycle tests (lag.rs, diagb_generated.rs): the files of
//! the workspace, a seeded generator, and systems/mrclam.sys's landmarks
//! placed on a ring of radius 4 m.

use obsan_expr::SplitMix;
use obsan_model::{Kind, System};
use std::collections::BTreeMap;

/// A workspace file.
pub fn read(p: &str) -> String {
    std::fs::read_to_string(format!("{}/../../{p}", env!("CARGO_MANIFEST_DIR"))).unwrap()
}

pub struct Rng(pub SplitMix);
impl Rng {
    pub fn uniform(&mut self) -> f64 {
        (self.0.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
    /// A standard normal deviate by the library's Box–Muller (its first
    /// output only, so the tests' data stay those of their seeds).
    pub fn normal(&mut self) -> f64 {
        let (a, b) = (self.uniform().max(1e-300), self.uniform());
        obsan_fit::box_muller(a, b).0
    }
}

/// A source of uniform and standard normal deviates: the tests' [`Rng`]
/// (Box–Muller's first output only) or the library's whole stream
/// ([`obsan_fit::Rng`], both outputs of each Box–Muller pair).
#[allow(dead_code)]
pub trait Source {
    fn uniform(&mut self) -> f64;
    fn normal(&mut self) -> f64;
}

impl Source for Rng {
    fn uniform(&mut self) -> f64 {
        Rng::uniform(self)
    }
    fn normal(&mut self) -> f64 {
        Rng::normal(self)
    }
}

impl Source for obsan_fit::Rng {
    fn uniform(&mut self) -> f64 {
        obsan_fit::Rng::uniform(self)
    }
    fn normal(&mut self) -> f64 {
        obsan_fit::Rng::normal(self)
    }
}

/// The landmarks of a [`ring`].
pub struct Ring {
    /// The codes of `sys`'s `lxNN` constants.
    pub codes: Vec<String>,
    /// Their positions, evenly on a ring of radius 4 m (read by
    /// diagb_generated.rs, whose simulator is not obsan's predictor).
    #[allow(dead_code)]
    pub marks: Vec<(f64, f64)>,
    /// The trajectories' meta (`lxNN`, `lyNN`).
    pub meta: BTreeMap<String, f64>,
}

/// `sys`'s landmarks on a ring.
pub fn ring(sys: &System) -> Ring {
    let codes: Vec<String> = sys
        .decls_of(Kind::Const)
        .filter_map(|d| d.name.strip_prefix("lx").map(str::to_string))
        .collect();
    let mut meta = BTreeMap::new();
    let mut marks = Vec::new();
    for (i, code) in codes.iter().enumerate() {
        let a = std::f64::consts::TAU * i as f64 / codes.len() as f64;
        meta.insert(format!("lx{code}"), 4.0 * a.cos());
        meta.insert(format!("ly{code}"), 4.0 * a.sin());
        marks.push((4.0 * a.cos(), 4.0 * a.sin()));
    }
    Ring { codes, marks, meta }
}
