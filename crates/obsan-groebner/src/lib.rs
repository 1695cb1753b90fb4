//! Gröbner bases over prime fields F_p, p < 2^63, on this crate's own sparse
//! polynomials: F4 (Faugère 1999; sparse Macaulay matrices, the normal
//! selection strategy) and, as its oracle, Buchberger's algorithm with the
//! sugar strategy, both with the Gebauer–Möller criteria, under grevlex, lex
//! or a block elimination order;
//! and the counts a zero-dimensional ideal gives (dimension of the quotient,
//! minimal polynomials of elements of the quotient, distinct roots of an
//! elimination polynomial).
//!
//! ```
//! use obsan_groebner::{groebner, Field, GbBudget, Mono, Order, Ring};
//! // x^2 - 4 = 0, y - x = 0 over F_p: two solutions, y takes two values.
//! let f = Field::new((1 << 61) - 1).unwrap();
//! let r = Ring::new(f, 2, Order::Grevlex);
//! let x2 = r.from_terms([(Mono::var(2, 0, 2), 1), (Mono::one(2), f.from_i64(-4))]);
//! let yx = r.sub(&r.var(1), &r.var(0));
//! let b = groebner(&r, &[x2, yx], GbBudget::default()).unwrap();
//! assert_eq!(b.standard_monomials(100).unwrap().len(), 2);
//! let m = b.minimal_polynomial(&r.var(1), 100).unwrap();
//! assert_eq!(obsan_groebner::distinct_roots(f, &m), 2);
//! ```
//!
//! Depends only on obsan-recon (its prime-field arithmetic). Every limit (degree, terms, basis size,
//! bytes held, deadline) is an error, never a truncated basis.

#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]

mod count;
mod f4;
mod f4mat;
mod f4state;
mod field;
mod gb;
mod mem;
mod poly;
mod presolve;
mod select;
mod table;

pub use count::{distinct_roots, eliminate_to, upoly_gcd};
pub use f4mat::WORK as WORK_BUDGET;
pub use field::{is_prime, Field};
pub use gb::{buchberger, Basis, GbBudget};
pub use mem::term_bytes;
pub use poly::{Mono, Order, Poly, Ring, MAX_DEGREE};
pub use presolve::presolve_linear;
pub use select::{f4, groebner};

/// Why a computation stopped.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum GbError {
    /// A monomial's degree passed `MAX_DEGREE`.
    Degree,
    /// A budget was exhausted (which one).
    Budget(&'static str),
    /// A count was asked of an ideal with infinitely many zeros.
    NotZeroDimensional,
    /// The stored data would pass `GbBudget::max_bytes`: `what` names the
    /// stage and its size, `bytes` what it would hold.
    Memory {
        bytes: u128,
        max: u128,
        what: String,
    },
}

impl std::fmt::Display for GbError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            GbError::Degree => write!(f, "a monomial degree passed {MAX_DEGREE}"),
            GbError::Budget(what) => write!(f, "Gröbner basis budget exhausted: {what}"),
            GbError::NotZeroDimensional => write!(f, "the ideal is not zero-dimensional"),
            GbError::Memory { bytes, max, what } => write!(
                f,
                "too large: {what} would need {} MiB, the memory budget is {} MiB",
                bytes.div_ceil(1 << 20),
                max >> 20
            ),
        }
    }
}

impl std::error::Error for GbError {}
