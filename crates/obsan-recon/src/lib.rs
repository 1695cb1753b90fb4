//! Exact reconstruction of rational functions from values modulo primes.
//!
//! A *black box* evaluates one or several rational functions with rational
//! coefficients at a point of F_p^n (for any prime p < 2^63 it is given).
//! [`reconstruct`] and [`reconstruct_vec`] recover them exactly, in the
//! style of FiniteFlow (Peraro 2019) and FireFly (Klappert & Lange 2020):
//!
//! 1. degrees along a random shifted line by Thiele interpolation with early
//!    termination ([`Thiele`]);
//! 2. per prime, `x = t z + s` with a random shift `s` so the denominator's
//!    constant term is non-zero (Cuyt & Lee 2011); the coefficients in `t`
//!    are homogeneous pieces in `z`, each interpolated as a sparse polynomial
//!    (Zippel, variable by variable) after subtracting the shift's
//!    contribution of the higher pieces; later primes reuse the monomials
//!    found by the first and solve one Vandermonde system per piece;
//! 3. the images are normalised (lowest denominator term = 1), combined by
//!    Chinese remaindering and lifted to Q by rational reconstruction (Wang),
//!    stopping when one more prime changes nothing;
//! 4. the result is **verified** at fresh random points modulo a prime never
//!    used for reconstruction, and the Schwartz–Zippel bound of that check
//!    is reported in the [`Certificate`].
//!
//! Budgets (degree, terms, primes, points, deadline) end the run with an
//! error value saying how far it got, never with a truncated answer.
//!
//! ```
//! use obsan_recon::{reconstruct, Options};
//! // f(x, y) = (x^2 - 3 y) / (2 x y + 5), evaluated modulo p.
//! let mut bb = |pt: &[u64], p: u64| -> Result<Option<u64>, ()> {
//!     let (x, y, p) = (pt[0] as u128, pt[1] as u128, p as u128);
//!     let num = (x * x % p + 3 * (p - y)) % p;
//!     let den = (2 * x % p * y + 5) % p;
//!     if den == 0 { return Ok(None); } // a pole: a bad point
//!     let (mut b, mut e, mut inv) = (den, p - 2, 1u128);
//!     while e > 0 { if e & 1 == 1 { inv = inv * b % p; } b = b * b % p; e >>= 1; }
//!     Ok(Some((num * inv % p) as u64))
//! };
//! let r = reconstruct(2, &mut bb, &Options::default()).unwrap();
//! assert_eq!(r.functions[0].display(&["x", "y"]).to_string(), "(x^2 - 3*y)/(2*x*y + 5)");
//! assert!(r.certificate.error_bound < 1e-60);
//! ```
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]

mod echelon;
mod field;
mod linalg;
mod multi;
mod rational;
mod rng;
mod sparse;
mod thiele;
mod univariate;

use std::collections::BTreeMap;
use std::fmt;
use std::time::Instant;

use dashu_int::ops::{Gcd, UnsignedAbs};
use dashu_int::{IBig, UBig};

pub use field::{is_prime, MAX_RECON_PRIMES, PRIMES, PRIMES52, VERIFY_PRIMES};

/// Arithmetic modulo a prime `p < 2^63` on residues in `0..p` (products in
/// u128): the workspace's one implementation; obsan-groebner's `Field` wraps it.
/// With it the workspace's one dense elimination over a prime field
/// ([`Echelon`](fp::Echelon): rank, null space, solve), generic over
/// [`PrimeField`](fp::PrimeField) so the engine's own `Fp` uses it too.
pub mod fp {
    pub use crate::echelon::{
        mul_truncated52, null_space, rank, reduce_delayed, reduce_delayed52, solve, Echelon,
        PrimeField, Residue, RowEchelon, Zp, BLOCK, IFMA_BOUND, PARALLEL_WORK,
    };
    pub use crate::field::{add, inv, mul, pow, sub, Fold, Rem128, Shoup};
    pub use obsan_simd::ifma;
}
pub use rational::{Poly, Rational, Term};
pub use rng::splitmix64;
pub use sparse::{interpolate_polys_vec, DegreeBounds, EARLY_TERMINATION};
pub use thiele::{Thiele, ThieleStep};
pub use univariate::Univariate;

use field::{inv, mul};
use multi::{Budget, Fail, Image, PrimeRun, Skeleton};
use rational::{rat_recon, Crt};
use rng::Rng;

/// Budgets and knobs of a reconstruction.
#[derive(Clone, Debug)]
pub struct Options {
    /// Largest total degree of a numerator or denominator.
    pub max_degree: u32,
    /// Largest number of terms of one homogeneous piece.
    pub max_terms: usize,
    /// Largest number of primes, in `2..=`[`MAX_RECON_PRIMES`].
    pub max_primes: usize,
    /// Largest number of black-box calls.
    pub max_points: u64,
    /// Stop with [`Limit::Deadline`] once this instant has passed.
    pub deadline: Option<Instant>,
    /// Early termination: consecutive agreeing points that end Thiele
    /// interpolation (at least 1).
    pub agree: usize,
    /// Verification points modulo the fresh prime (at least 1).
    pub checks: u32,
    /// Seed of the random points; equal seeds give equal runs.
    pub seed: u64,
    /// The caller's own primes (each a prime below 2^63, at most
    /// [`MAX_RECON_PRIMES`]) in place of [`PRIMES`], for a black box that
    /// only works modulo some primes. No check prime is then known, so the
    /// result is a *candidate*: the fresh-prime check is skipped (the
    /// certificate says `checks: 0`, bound 1) and the caller must certify it.
    /// With a single prime the first complete lift is returned.
    pub primes: Option<Vec<u64>>,
    /// Which fixed list the primes (and the check prime) come from when
    /// `primes` is `None`.
    pub prime_list: PrimeList,
}

/// The fixed lists of primes reconstruction draws from, each of
/// [`PRIMES`]'s length with its last [`VERIFY_PRIMES`] kept for the check.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PrimeList {
    /// [`PRIMES`], just below 2^62: the most bits per prime.
    #[default]
    Bits62,
    /// [`PRIMES52`], just below 2^52: a black box whose work is dense
    /// eliminations modulo the prime ([`fp::RowEchelon`]) runs them on
    /// AVX-512 IFMA where the CPU has it (3.5-4x), at 10 bits less per
    /// prime (more primes for large coefficients, and sparse
    /// interpolation's `q^e < p` holds for fewer supports).
    Bits52,
}

impl PrimeList {
    /// The list, largest first.
    pub fn primes(self) -> &'static [u64; PRIMES.len()] {
        match self {
            PrimeList::Bits62 => &PRIMES,
            PrimeList::Bits52 => &PRIMES52,
        }
    }
}

impl Default for Options {
    fn default() -> Self {
        Options {
            max_degree: 50,
            max_terms: 10_000,
            max_primes: MAX_RECON_PRIMES,
            max_points: u64::MAX,
            deadline: None,
            agree: 2,
            checks: 4,
            seed: 0x0b5a_4ec0,
            primes: None,
            prime_list: PrimeList::Bits62,
        }
    }
}

/// Which budget ran out.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Limit {
    /// A degree above [`Options::max_degree`].
    Degree(u32),
    /// A piece with more than [`Options::max_terms`] terms.
    Terms(usize),
    /// Rational reconstruction not stable within [`Options::max_primes`].
    Primes(usize),
    /// More than [`Options::max_points`] black-box calls.
    Points(u64),
    /// [`Options::deadline`] passed.
    Deadline,
}

/// How far a run got.
#[derive(Clone, Debug, PartialEq, Eq, Default)]
pub struct Progress {
    /// Black-box calls made.
    pub points: u64,
    /// Primes whose image was complete.
    pub primes: usize,
    /// Per function, (numerator, denominator) total degrees once known.
    pub degrees: Vec<(u32, u32)>,
    /// What the run was doing.
    pub stage: &'static str,
}

/// Why a reconstruction gave no answer.
#[derive(Clone, Debug, PartialEq)]
pub enum ReconError<E> {
    /// The black box failed.
    BlackBox(E),
    /// A budget ran out.
    Budget {
        /// The budget.
        limit: Limit,
        /// How far the run got.
        progress: Progress,
    },
    /// The black box returned a vector of the wrong length.
    WrongLength {
        /// Functions announced.
        expected: usize,
        /// Values returned.
        got: usize,
    },
    /// The black box kept answering "bad point".
    NoGoodPoints {
        /// How far the run got.
        progress: Progress,
    },
    /// Random choices kept failing (the black box is likely not a fixed
    /// rational function, e.g. its degrees differ between primes).
    Unlucky {
        /// How far the run got.
        progress: Progress,
    },
    /// The reconstructed function disagrees with the black box at a fresh
    /// point modulo a fresh prime.
    VerificationFailed {
        /// The verification prime.
        prime: u64,
        /// The function that disagreed.
        component: usize,
        /// How far the run got.
        progress: Progress,
    },
    /// An option out of range.
    InvalidOptions(&'static str),
}

impl<E: fmt::Display> fmt::Display for ReconError<E> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let prog = |f: &mut fmt::Formatter<'_>, p: &Progress| {
            write!(
                f,
                " (while {}; {} points, {} primes",
                p.stage, p.points, p.primes
            )?;
            if !p.degrees.is_empty() {
                let d: Vec<String> = p.degrees.iter().map(|(a, b)| format!("{a}/{b}")).collect();
                write!(f, ", degrees {}", d.join(", "))?;
            }
            f.write_str(")")
        };
        match self {
            ReconError::BlackBox(e) => write!(f, "black box failed: {e}"),
            ReconError::Budget { limit, progress } => {
                match limit {
                    Limit::Degree(d) => write!(f, "degree above the limit {d}")?,
                    Limit::Terms(t) => write!(f, "more than {t} terms")?,
                    Limit::Primes(k) => write!(f, "coefficients not determined by {k} primes")?,
                    Limit::Points(k) => write!(f, "more than {k} black-box points")?,
                    Limit::Deadline => write!(f, "deadline passed")?,
                }
                prog(f, progress)
            }
            ReconError::WrongLength { expected, got } => {
                write!(f, "black box returned {got} values, expected {expected}")
            }
            ReconError::NoGoodPoints { progress } => {
                f.write_str("black box answered no point")?;
                prog(f, progress)
            }
            ReconError::Unlucky { progress } => {
                f.write_str(
                    "random choices kept failing; is the black box a fixed rational function?",
                )?;
                prog(f, progress)
            }
            ReconError::VerificationFailed {
                prime,
                component,
                progress,
            } => {
                write!(f, "function {component} failed verification modulo {prime}")?;
                prog(f, progress)
            }
            ReconError::InvalidOptions(what) => write!(f, "invalid options: {what}"),
        }
    }
}

impl<E: fmt::Debug + fmt::Display> std::error::Error for ReconError<E> {}

/// The probabilistic check of a result.
#[derive(Clone, Debug, PartialEq)]
pub struct Certificate {
    /// The fresh prime of the check (never used for reconstruction).
    pub prime: u64,
    /// Independent random points at which every function agreed.
    pub checks: u32,
    /// Largest `deg num + deg den` of the results: the degree of
    /// `A D - N B` for a black box `A/B` of at most these degrees.
    pub degree: u32,
    /// Schwartz–Zippel bound on the probability that a wrong result passes
    /// every check: `m (degree / (q - 1 - 2 deg den))^checks` for m
    /// functions, assuming the black box's degrees are those found.
    pub error_bound: f64,
}

/// Reconstructed functions with their certificate.
#[derive(Clone, Debug, PartialEq)]
pub struct Reconstruction {
    /// The functions, in the black box's order.
    pub functions: Vec<Rational>,
    /// The verification at fresh points.
    pub certificate: Certificate,
    /// Points, primes and degrees used.
    pub stats: Progress,
}

/// Reconstructs one rational function of `nvars` variables from a black box
/// `(point, p) -> value mod p`, `Ok(None)` marking a bad point (a pole, a
/// degenerate null vector). See the crate documentation.
pub fn reconstruct<F, E>(
    nvars: usize,
    blackbox: &mut F,
    opts: &Options,
) -> Result<Reconstruction, ReconError<E>>
where
    F: FnMut(&[u64], u64) -> Result<Option<u64>, E>,
{
    let mut vb = |x: &[u64], p: u64| blackbox(x, p).map(|o| o.map(|v| vec![v]));
    reconstruct_vec(nvars, 1, &mut vb, opts)
}

/// Reconstructs `m` rational functions sharing one black-box call per point
/// (e.g. the components of a normalised null vector); the black box returns
/// all `m` values, or `Ok(None)` for a bad point.
pub fn reconstruct_vec<F, E>(
    nvars: usize,
    m: usize,
    blackbox: &mut F,
    opts: &Options,
) -> Result<Reconstruction, ReconError<E>>
where
    F: FnMut(&[u64], u64) -> Result<Option<Vec<u64>>, E>,
{
    if let Some(ps) = &opts.primes {
        if ps.is_empty() || ps.len() > MAX_RECON_PRIMES {
            return Err(ReconError::InvalidOptions("primes: 1..=20 of them"));
        }
        if ps.iter().any(|&p| p >= 1 << 63 || !is_prime(p)) {
            return Err(ReconError::InvalidOptions(
                "primes: each a prime below 2^63",
            ));
        }
    } else if opts.max_primes < 2 || opts.max_primes > MAX_RECON_PRIMES {
        // Two primes at least: the lift stops when one more prime changes nothing.
        return Err(ReconError::InvalidOptions("max_primes must be in 2..=20"));
    }
    if m == 0 {
        return Err(ReconError::InvalidOptions("no function to reconstruct"));
    }
    if nvars == 0 {
        // A constant: reconstruct it as a function of one ignored variable.
        let mut wrapped = |_: &[u64], p: u64| blackbox(&[], p);
        let mut r = run(1, m, &mut wrapped, opts)?;
        for f in &mut r.functions {
            let strip = |q: &Poly| {
                Poly::from_terms(q.terms().iter().map(|t| Term {
                    exps: Vec::new(),
                    coeff: t.coeff.clone(),
                }))
            };
            *f = Rational::from_parts(strip(f.num()), strip(f.den()));
        }
        return Ok(r);
    }
    run(nvars, m, blackbox, opts)
}

/// Retries of one prime after unlucky random choices.
const RETRIES: usize = 4;

/// Order in which the canonical denominator term is the smallest.
fn low_key(e: &[u32]) -> (u32, &[u32]) {
    (e.iter().sum(), e)
}

fn run<F, E>(
    n: usize,
    m: usize,
    bb: &mut F,
    opts: &Options,
) -> Result<Reconstruction, ReconError<E>>
where
    F: FnMut(&[u64], u64) -> Result<Option<Vec<u64>>, E>,
{
    let mut rng = Rng::new(opts.seed);
    let mut budget = Budget::from_options(opts, "finding degrees");
    let mut degs: Option<Vec<(usize, usize)>> = None;
    let mut skeleton: Option<Skeleton> = None;
    let mut acc: Option<Acc> = None;
    let mut prev: Option<Vec<Rational>> = None;
    let mut result = None;
    let (primes, single) = match &opts.primes {
        Some(ps) => (ps.as_slice(), ps.len() == 1),
        None => (&opts.prime_list.primes()[..opts.max_primes], false),
    };
    'primes: for &p in primes {
        let mut tries = 0;
        let image = loop {
            tries += 1;
            if tries > RETRIES {
                return Err(ReconError::Unlucky {
                    progress: budget.progress(),
                });
            }
            match one_prime(
                p,
                n,
                m,
                bb,
                &mut rng,
                &mut budget,
                &mut degs,
                skeleton.as_ref(),
            ) {
                Ok(x) => break x,
                Err(Fail::Unlucky) => continue,
                Err(Fail::Stale) => {
                    // Start the lift again from full interpolation.
                    skeleton = None;
                    acc = None;
                    prev = None;
                    continue;
                }
                Err(Fail::Degrees(d)) => {
                    let higher = degs.as_ref().is_some_and(|old| {
                        old.iter().zip(&d).all(|(o, n)| n.0 >= o.0 && n.1 >= o.1)
                    });
                    if !higher {
                        // Lower degrees than before: this prime (or its
                        // line) is the unlucky one.
                        continue 'primes;
                    }
                    // Higher: the earlier primes lost terms; start again.
                    degs = None;
                    skeleton = None;
                    acc = None;
                    prev = None;
                    continue;
                }
                Err(Fail::Hard(e)) => return Err(e),
            }
        };
        let (image, sk) = image;
        if skeleton.is_none() {
            skeleton = Some(sk);
        }
        budget.primes += 1;
        budget.stage = "lifting to Q";
        let a = acc.get_or_insert_with(|| Acc::new(&image));
        if !a.push(&image, p) {
            continue;
        }
        let cand = a.lift();
        if single && cand.is_some() {
            result = cand;
            break;
        }
        if let (Some(c), Some(pv)) = (&cand, &prev) {
            if c == pv {
                result = cand;
                break;
            }
        }
        prev = cand;
    }
    let Some(functions) = result else {
        return Err(budget.limit(Limit::Primes(primes.len())));
    };
    if opts.primes.is_some() {
        // A candidate: no prime is known to be fresh for this black box.
        budget.stage = "done";
        return Ok(Reconstruction {
            functions,
            certificate: Certificate {
                prime: 0,
                checks: 0,
                degree: 0,
                error_bound: 1.0,
            },
            stats: budget.progress(),
        });
    }
    let certificate = verify(n, m, bb, &functions, opts, &mut rng, &mut budget)?;
    budget.stage = "done";
    Ok(Reconstruction {
        functions,
        certificate,
        stats: budget.progress(),
    })
}

#[allow(clippy::too_many_arguments)]
fn one_prime<F, E>(
    p: u64,
    n: usize,
    m: usize,
    bb: &mut F,
    rng: &mut Rng,
    budget: &mut Budget,
    degs: &mut Option<Vec<(usize, usize)>>,
    skeleton: Option<&Skeleton>,
) -> Result<(Image, Skeleton), Fail<E>>
where
    F: FnMut(&[u64], u64) -> Result<Option<Vec<u64>>, E>,
{
    let mut run = PrimeRun::new(p, n, m, bb, rng);
    budget.stage = "finding degrees";
    // Every prime re-checks the degrees along a line through its own shift,
    // which also proves D(s) != 0 for that shift.
    let d = run.degrees(budget)?;
    match degs {
        None => {
            budget.degrees = d.iter().map(|&(a, b)| (a as u32, b as u32)).collect();
            *degs = Some(d.clone());
        }
        Some(known) if *known != d => return Err(Fail::Degrees(d)),
        Some(_) => {}
    }
    run.set_degrees(d);
    if skeleton.is_none() {
        budget.stage = "finding degrees per variable";
        run.var_degrees(budget)?;
    }
    budget.stage = if skeleton.is_none() {
        "interpolating (first prime)"
    } else {
        "interpolating on the known monomials"
    };
    run.image(skeleton, budget)
}

/// Chinese-remainder accumulation of normalised images.
pub(crate) struct Acc {
    /// Per function, the denominator monomial normalised to 1.
    canon: Vec<Vec<u32>>,
    modulus: UBig,
    /// Per function, numerator and denominator residues by monomial.
    coeffs: Vec<[BTreeMap<Vec<u32>, Crt>; 2]>,
}

impl Acc {
    pub(crate) fn new(image: &Image) -> Acc {
        Acc {
            canon: image.iter().map(|(_, den)| lowest(den)).collect(),
            modulus: UBig::ONE,
            coeffs: image
                .iter()
                .map(|_| [BTreeMap::new(), BTreeMap::new()])
                .collect(),
        }
    }

    /// Adds one image; false when it was skipped (an unlucky prime that
    /// kills the canonical term).
    pub(crate) fn push(&mut self, image: &Image, p: u64) -> bool {
        // A lower denominator term than the chosen one means the chosen
        // term was an artefact of an earlier prime: start again from here.
        let lower = image
            .iter()
            .zip(&self.canon)
            .any(|((_, den), c)| low_key(&lowest(den)) < low_key(c));
        if lower {
            *self = Acc::new(image);
        }
        let mut scaled = Vec::with_capacity(image.len());
        for ((num, den), c) in image.iter().zip(&self.canon) {
            let Some(k) = den
                .iter()
                .find(|(e, _)| e == c)
                .and_then(|(_, a)| inv(*a, p))
            else {
                return false;
            };
            let sc = |t: &multi::Terms| -> BTreeMap<Vec<u32>, u64> {
                t.iter().map(|(e, a)| (e.clone(), mul(*a, k, p))).collect()
            };
            scaled.push([sc(num), sc(den)]);
        }
        for (slots, img) in self.coeffs.iter_mut().zip(&scaled) {
            for (slot, im) in slots.iter_mut().zip(img) {
                for e in im.keys() {
                    slot.entry(e.clone()).or_insert(Crt { value: UBig::ZERO });
                }
                for (e, crt) in slot.iter_mut() {
                    let b = im.get(e).copied().unwrap_or(0);
                    if crt.push(&self.modulus, b, p).is_none() {
                        return false;
                    }
                }
            }
        }
        self.modulus *= UBig::from(p);
        true
    }

    /// Rational reconstruction of every coefficient, as canonical integer
    /// forms; `None` while some coefficient is not determined.
    pub(crate) fn lift(&self) -> Option<Vec<Rational>> {
        let mut out = Vec::with_capacity(self.coeffs.len());
        for slots in &self.coeffs {
            let mut rats: [Vec<(Vec<u32>, IBig, UBig)>; 2] = [Vec::new(), Vec::new()];
            for (slot, r) in slots.iter().zip(rats.iter_mut()) {
                for (e, crt) in slot {
                    let (nq, dq) = rat_recon(&crt.value, &self.modulus)?;
                    if nq != IBig::ZERO {
                        r.push((e.clone(), nq, dq));
                    }
                }
            }
            let mut l = UBig::ONE;
            for (_, _, d) in rats.iter().flatten() {
                let g = (&l).gcd(d);
                l = &l / &g * d;
            }
            let ints: Vec<Vec<(Vec<u32>, IBig)>> = rats
                .iter()
                .map(|v| {
                    v.iter()
                        .map(|(e, nq, dq)| (e.clone(), nq * IBig::from(&l / dq)))
                        .collect()
                })
                .collect();
            let mut g = UBig::ZERO;
            for (_, c) in ints.iter().flatten() {
                g = (&g).gcd(c.unsigned_abs());
            }
            if g == UBig::ZERO {
                return None;
            }
            // Sign: the leading denominator term (first as printed) positive.
            let lead_negative = {
                let den = &ints[1];
                den.iter()
                    .max_by(|a, b| low_key(&a.0).cmp(&low_key(&b.0)))
                    .is_some_and(|(_, c)| *c < IBig::ZERO)
            };
            let gi = if lead_negative {
                -IBig::from(g)
            } else {
                IBig::from(g)
            };
            let poly = |v: &Vec<(Vec<u32>, IBig)>| {
                Poly::from_terms(v.iter().map(|(e, c)| Term {
                    exps: e.clone(),
                    coeff: c / &gi,
                }))
            };
            out.push(Rational::from_parts(poly(&ints[0]), poly(&ints[1])));
        }
        Some(out)
    }
}

fn lowest(den: &multi::Terms) -> Vec<u32> {
    den.iter()
        .map(|(e, _)| e)
        .min_by(|a, b| low_key(a).cmp(&low_key(b)))
        .cloned()
        .unwrap_or_default()
}

pub(crate) fn verify<F, E>(
    n: usize,
    m: usize,
    bb: &mut F,
    functions: &[Rational],
    opts: &Options,
    rng: &mut Rng,
    budget: &mut Budget,
) -> Result<Certificate, ReconError<E>>
where
    F: FnMut(&[u64], u64) -> Result<Option<Vec<u64>>, E>,
{
    budget.stage = "verifying";
    let q = opts.prime_list.primes()[MAX_RECON_PRIMES];
    let checks = opts.checks.max(1);
    let mut done = 0;
    let mut bad = 0;
    while done < checks {
        let x: Vec<u64> = (0..n).map(|_| rng.nonzero(q)).collect();
        let vals = multi::call(bb, budget, m, &x, q)?;
        let cand: Option<Vec<u64>> = functions.iter().map(|f| f.eval_mod(&x, q)).collect();
        let (Some(vals), Some(cand)) = (vals, cand) else {
            bad += 1;
            if bad > 200 {
                return Err(ReconError::NoGoodPoints {
                    progress: budget.progress(),
                });
            }
            continue;
        };
        if let Some(c) = (0..m).find(|&c| vals[c] != cand[c]) {
            return Err(ReconError::VerificationFailed {
                prime: q,
                component: c,
                progress: budget.progress(),
            });
        }
        done += 1;
    }
    let degree = functions
        .iter()
        .map(|f| f.num().degree() + f.den().degree())
        .max()
        .unwrap_or(0);
    let dd = functions
        .iter()
        .map(|f| f.den().degree())
        .max()
        .unwrap_or(0);
    let beta = if degree == 0 {
        0.0
    } else {
        degree as f64 / (q as f64 - 1.0 - 2.0 * dd as f64)
    };
    Ok(Certificate {
        prime: q,
        checks,
        degree,
        error_bound: m as f64 * beta.powi(checks as i32),
    })
}
