//! Engine limits: a size and time budget, and the error when it is exceeded.
//!
//! The polynomial kernels (`poly.rs`, `gcd.rs`) cannot return errors without
//! threading `Result` through every ring operation, so a budget is armed per
//! thread for the duration of a fallible entry point ([`crate::Ctx::try_canon`],
//! [`crate::Ctx::within_budget`], parsing). A kernel that exceeds it *trips*
//! the budget: the first reason is recorded, every later operation returns a
//! cheap placeholder at once, and the entry point discards all of it and
//! returns the recorded [`Limit`]. A tripped computation never reaches a memo
//! table or a caller, so no placeholder can be mistaken for a result.
//!
//! Outside an armed scope (the infallible API used by trusted callers) no size
//! or time limit applies, and an exceeded hard limit (an exponent beyond
//! `u32::MAX`, a leaf count beyond `u32::MAX`) or a broken internal invariant
//! panics with its reason instead of returning a wrong answer.

use std::cell::Cell;
use std::fmt;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Instant;

/// Largest exponent of a variable in a polynomial (the packing's hard limit).
pub const EXP_MAX: u32 = u32::MAX;

/// Largest exponent of a power node in the expression graph.
pub const POW_MAX: i64 = i32::MAX as i64;

/// The largest root index (`x^(p/q)` with `q` above it is refused): the F_p
/// root (`Fp::root`) searches a subgroup whose order grows with the primes
/// of `q`, and the relation's reductions grow with `q`.
pub const ROOT_MAX: u32 = 1000;

/// Largest number of bits of a rational power `q^e` of the graph: 65536
/// bits (about 20,000 digits). At 2^24 the fuzzer found
/// `sqrt((lx0 - x/66666666661^66602)^3)`, a 2.4-million-bit number whose
/// canonical form took over 10 s to build and 5 MB to print.
pub const NUM_BITS_MAX: u128 = 1 << 16;

/// Size and time limits of an engine computation (see docs/engine.md, Limits).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Budget {
    /// Most terms of any one polynomial (numerator or denominator).
    pub max_terms: usize,
    /// Most nodes in the expression arena, counted as `1 + children`.
    pub max_nodes: usize,
    /// Largest exponent of any variable in a polynomial.
    pub max_degree: u32,
    /// Wall-clock deadline.
    pub deadline: Option<Instant>,
}

impl Budget {
    /// Default term limit: a product of 16 distinct binomials (65536 terms)
    /// passes, one of 17 or more stops within about a second.
    pub const DEFAULT_MAX_TERMS: usize = 100_000;
    /// Default arena limit: about 1.5 GB of nodes.
    pub const DEFAULT_MAX_NODES: usize = 50_000_000;
    /// Default degree limit: dense univariate images stay below 8 MB.
    pub const DEFAULT_MAX_DEGREE: u32 = 1_000_000;
    /// Dense buffers outside the polynomials (the rank test's jets, which
    /// hold a gradient per coefficient) may use this many bytes per unit of
    /// `max_terms`: about 200 MiB under the default budget.
    pub const BYTES_PER_TERM: u128 = 2048;

    /// No limit beyond the hard ones.
    pub fn unlimited() -> Budget {
        Budget {
            max_terms: usize::MAX,
            max_nodes: usize::MAX,
            max_degree: EXP_MAX,
            deadline: None,
        }
    }
}

impl Default for Budget {
    /// Limits that the shipped systems and the paper's analyses never reach.
    fn default() -> Budget {
        Budget {
            max_terms: Budget::DEFAULT_MAX_TERMS,
            max_nodes: Budget::DEFAULT_MAX_NODES,
            max_degree: Budget::DEFAULT_MAX_DEGREE,
            deadline: None,
        }
    }
}

/// Why a computation was stopped.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Limit {
    /// A polynomial grew past the term budget.
    Terms { terms: usize, max: usize },
    /// The arena grew past the node budget.
    Nodes { nodes: usize, max: usize },
    /// An exponent passed the degree budget or the hard exponent range.
    Degree { degree: u128, max: u128 },
    /// A numeric power would have more bits than the engine stores.
    Number { bits: u128, max: u128 },
    /// A printed form would pass this many bytes.
    Text { max: usize },
    /// A dense buffer (the jets of the rank test) would need this many bytes.
    Memory {
        bytes: u128,
        max: u128,
        what: &'static str,
    },
    /// The deadline passed.
    Timeout,
    /// The caller asked the computation to stop (see [`with_cancel`]).
    Cancelled,
    /// An internal invariant failed (a bug: please report the input).
    Internal(&'static str),
}

impl fmt::Display for Limit {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Limit::Terms { terms, max } => write!(
                f,
                "expression too large: {terms} terms, budget {max}; raise it with --max-terms"
            ),
            Limit::Nodes { nodes, max } => write!(
                f,
                "expression too large: {nodes} graph nodes, budget {max}; raise it with --max-terms"
            ),
            Limit::Degree { degree, max } => {
                write!(f, "exponent too large: {degree}, the limit is {max}")
            }
            Limit::Number { bits, max } => {
                write!(f, "number too large: about {bits} bits, the limit is {max}")
            }
            Limit::Text { max } => write!(f, "printed form longer than {max} bytes"),
            Limit::Memory { bytes, max, what } => write!(
                f,
                "too large: {what} would need {} MiB, the memory budget is {} MiB ({} bytes per --max-terms); raise it with --max-terms",
                bytes.div_ceil(1 << 20),
                max >> 20,
                Budget::BYTES_PER_TERM
            ),
            Limit::Timeout => f.write_str("time limit reached; raise it with --timeout"),
            Limit::Cancelled => f.write_str("interrupted"),
            Limit::Internal(what) => write!(f, "internal error in the symbolic engine: {what}"),
        }
    }
}

impl std::error::Error for Limit {}

#[derive(Clone, Copy)]
struct Armed {
    max_terms: usize,
    max_degree: u32,
    deadline: Option<Instant>,
}

thread_local! {
    static ARMED: Cell<Option<Armed>> = const { Cell::new(None) };
    static TRIPPED: Cell<bool> = const { Cell::new(false) };
    static REASON: std::cell::RefCell<Option<Limit>> = const { std::cell::RefCell::new(None) };
    static TICK: Cell<u32> = const { Cell::new(0) };
    /// A flag another thread may set to stop this thread's armed scope.
    static CANCEL: std::cell::RefCell<Option<Arc<AtomicBool>>> = const { std::cell::RefCell::new(None) };
}

/// Run `f` on this thread with `flag` as its cancel flag: once another
/// thread sets it, an armed scope trips with [`Limit::Cancelled`] where it
/// polls its deadline (so a caller can stop work it no longer wants, e.g. on
/// Ctrl-C). Outside an armed scope the flag is not looked at.
pub fn with_cancel<T>(flag: Arc<AtomicBool>, f: impl FnOnce() -> T) -> T {
    struct Reset(Option<Arc<AtomicBool>>);
    impl Drop for Reset {
        fn drop(&mut self) {
            let old = self.0.take();
            CANCEL.with(|c| *c.borrow_mut() = old);
        }
    }
    let _reset = Reset(CANCEL.with(|c| c.borrow_mut().replace(flag)));
    f()
}

/// Whether this thread's cancel flag is set.
fn cancelled() -> bool {
    CANCEL.with(|c| {
        c.borrow()
            .as_ref()
            .is_some_and(|f| f.load(Ordering::Relaxed))
    })
}

/// Whether the caller of [`with_cancel`] asked this thread's work to stop:
/// long loops outside the engine (the F_p rank test, the estimators, Monte
/// Carlo runs) poll this and return their crate's "cancelled" error. Cheap
/// (a thread-local and an atomic load); `false` outside [`with_cancel`].
pub fn cancel_requested() -> bool {
    cancelled()
}

/// This thread's cancel flag, to hand to worker threads (the flag is
/// thread-local): `with_cancel(cancel_flag(), ..)` on each worker. Outside
/// [`with_cancel`], a fresh flag nobody sets.
pub fn cancel_flag() -> Arc<AtomicBool> {
    CANCEL.with(|c| c.borrow().clone()).unwrap_or_default()
}

/// Run `f` with `b` armed on this thread. A nested scope keeps the outer
/// budget (the outermost caller's limits apply) and reports the outer trip.
/// The value is a placeholder whenever the limit is `Some`.
pub(crate) fn scope<T>(b: &Budget, f: impl FnOnce() -> T) -> (T, Option<Limit>) {
    if ARMED.with(|a| a.get()).is_some() {
        let r = f();
        return (r, reason());
    }
    ARMED.with(|a| {
        a.set(Some(Armed {
            max_terms: b.max_terms,
            max_degree: b.max_degree,
            deadline: b.deadline,
        }))
    });
    // Disarm and clear even if `f` unwinds, so a later scope starts clean.
    struct Reset;
    impl Drop for Reset {
        fn drop(&mut self) {
            ARMED.with(|a| a.set(None));
            TRIPPED.with(|t| t.set(false));
            REASON.with(|r| r.borrow_mut().take());
        }
    }
    let _reset = Reset;
    let r = f();
    (r, reason())
}

/// Run `f` with `b` armed on this thread, for every context `f` uses: the
/// way to put code that calls the infallible API (normal forms, symmetries)
/// under a budget. On a limit, `f`'s value is built from placeholders and is
/// dropped; the caller must discard everything `f` produced (its printed
/// output too) and report the limit.
pub fn within_thread_budget<T>(b: &Budget, f: impl FnOnce() -> T) -> Result<T, Limit> {
    match scope(b, f) {
        (r, None) => Ok(r),
        (_, Some(l)) => Err(l),
    }
}

/// [`within_thread_budget`] that also hands back `f`'s value on a limit,
/// for a caller that can tell a value which already reports the limit (an
/// error located in the input, built by [`ParseError::from_limit`]) from a
/// placeholder; anything else in it must be discarded as there.
///
/// [`ParseError::from_limit`]: crate::ParseError::from_limit
pub fn within_thread_budget_keep<T>(b: &Budget, f: impl FnOnce() -> T) -> (T, Option<Limit>) {
    scope(b, f)
}

/// Whether a budget armed on this thread has been exceeded: from then on,
/// what the engine returns inside the scope is placeholders, and a caller's
/// invariant checks on them may fail (the binary reports the limit instead).
pub fn budget_tripped() -> bool {
    tripped()
}

/// The limit a budget armed on this thread was exceeded by, if any: for a
/// caller that reports it with where it was reached (an error whose text
/// holds the limit's own is kept by the binary over the bare limit).
pub fn budget_reason() -> Option<Limit> {
    reason()
}

/// The limit hit in the current scope, if any.
pub(crate) fn reason() -> Option<Limit> {
    REASON.with(|r| r.borrow().clone())
}

/// Whether a limit has been hit in the current scope (work should stop).
#[inline]
pub(crate) fn tripped() -> bool {
    TRIPPED.with(|t| t.get())
}

/// Record that `l` was hit. Outside a scope this is a broken hard limit or
/// invariant of the infallible API, and panics rather than go on wrongly.
/// Whether a budget is armed on this thread.
pub(crate) fn armed() -> bool {
    ARMED.with(|a| a.get()).is_some()
}

#[cold]
pub(crate) fn trip(l: Limit) {
    if ARMED.with(|a| a.get()).is_none() {
        #[allow(clippy::panic)]
        {
            panic!(
                "obsan-expr: {l} (use the budgeted API, e.g. Ctx::try_canon, for untrusted input)"
            );
        }
    }
    TRIPPED.with(|t| t.set(true));
    REASON.with(|r| {
        let mut r = r.borrow_mut();
        if r.is_none() {
            *r = Some(l);
        }
    });
}

/// Check that a dense buffer of `bytes` bytes fits the memory budget of the
/// armed scope (`max_terms * BYTES_PER_TERM`); outside a scope there is none.
pub fn check_memory(bytes: u128, what: &'static str) -> Result<(), Limit> {
    let Some(a) = ARMED.with(|a| a.get()) else {
        return Ok(());
    };
    let max = (a.max_terms as u128).saturating_mul(Budget::BYTES_PER_TERM);
    if bytes > max {
        return Err(Limit::Memory { bytes, max, what });
    }
    Ok(())
}

/// Check a polynomial's size against the armed term budget.
#[inline]
pub(crate) fn check_terms(n: usize) -> bool {
    let max = ARMED.with(|a| a.get()).map_or(usize::MAX, |a| a.max_terms);
    if n > max {
        trip(Limit::Terms { terms: n, max });
        return false;
    }
    true
}

/// The armed degree limit (`EXP_MAX` outside a scope).
#[inline]
pub(crate) fn max_degree() -> u32 {
    ARMED.with(|a| a.get()).map_or(EXP_MAX, |a| a.max_degree)
}

/// Check an exponent against the armed degree budget and the hard range.
#[inline]
pub(crate) fn check_degree(d: u64) -> bool {
    let max = max_degree();
    if d > max as u64 {
        trip(Limit::Degree {
            degree: d as u128,
            max: max as u128,
        });
        return false;
    }
    true
}

/// Poll the deadline (cheaply: the clock is read every 64th call). Returns
/// `false` once the scope has tripped for any reason.
#[inline]
pub(crate) fn poll() -> bool {
    if tripped() {
        return false;
    }
    let t = TICK.with(|t| {
        let v = t.get().wrapping_add(1);
        t.set(v);
        v
    });
    if t.is_multiple_of(64) {
        if let Some(a) = ARMED.with(|a| a.get()) {
            if a.deadline.is_some_and(|d| Instant::now() >= d) {
                trip(Limit::Timeout);
                return false;
            }
            if cancelled() {
                trip(Limit::Cancelled);
                return false;
            }
        }
    }
    true
}

/// `Some(x)` or, for `None`, a tripped invariant (`what` names it) and a placeholder.
pub(crate) fn invariant<T: Default>(x: Option<T>, what: &'static str) -> T {
    match x {
        Some(v) => v,
        None => {
            if !tripped() {
                trip(Limit::Internal(what));
            }
            T::default()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Ctx;

    /// A set cancel flag stops an armed computation, the flag is this
    /// thread's only for the scope, and an unset flag changes nothing.
    #[test]
    fn a_set_cancel_flag_stops_the_engine() {
        let src: Vec<String> = (0..16).map(|i| format!("(a{i} + b{i})")).collect();
        let mut ctx = Ctx::new();
        let id = ctx.parse(&src.join("*")).unwrap();
        let flag = Arc::new(AtomicBool::new(true));
        let r = with_cancel(flag.clone(), || ctx.try_canon(id));
        assert_eq!(r, Err(Limit::Cancelled));
        assert!(!cancelled());
        let small = ctx.parse("(x + 1)^2").unwrap();
        flag.store(false, Ordering::Relaxed);
        let r = with_cancel(flag, || ctx.try_canon(small)).unwrap();
        assert_eq!(r.numerator().len(), 3);
    }

    /// `cancel_requested` follows the scope's flag, and `cancel_flag` hands
    /// the same flag to another thread (where it was not set before).
    #[test]
    fn the_cancel_flag_reaches_worker_threads() {
        assert!(!cancel_requested());
        assert!(!cancel_flag().load(Ordering::Relaxed));
        let flag = Arc::new(AtomicBool::new(false));
        with_cancel(flag.clone(), || {
            assert!(!cancel_requested());
            let handed = cancel_flag();
            let worker = std::thread::spawn(move || {
                assert!(!cancel_requested());
                with_cancel(handed, || {
                    while !cancel_requested() {
                        std::thread::yield_now();
                    }
                })
            });
            flag.store(true, Ordering::Relaxed);
            assert!(cancel_requested());
            worker.join().unwrap();
        });
        assert!(!cancel_requested());
    }
}
