//! The canonical form's value type: a fraction of leaf polynomials (built by
//! canon.rs, which documents its invariants).

use crate::num::Q;
use crate::poly::{Poly, Var};

/// A canonical rational function (see the module documentation).
#[derive(Clone, PartialEq, Eq, Hash, Debug)]
pub struct RatFun {
    pub(crate) num: Poly,
    pub(crate) den: Poly,
}

impl Default for RatFun {
    /// Zero (`0/1`).
    fn default() -> RatFun {
        RatFun::zero()
    }
}

impl RatFun {
    pub fn zero() -> RatFun {
        RatFun {
            num: Poly::zero(),
            den: Poly::one(),
        }
    }
    pub fn one() -> RatFun {
        RatFun {
            num: Poly::one(),
            den: Poly::one(),
        }
    }
    pub fn from_q(q: &Q) -> RatFun {
        RatFun {
            num: Poly::constant(q.num().clone()),
            den: Poly::constant(q.den().clone()),
        }
    }
    pub fn from_poly(p: Poly) -> RatFun {
        RatFun {
            num: p,
            den: Poly::one(),
        }
    }
    pub fn var(v: Var) -> RatFun {
        RatFun {
            num: Poly::var(v),
            den: Poly::one(),
        }
    }
    pub fn is_zero(&self) -> bool {
        self.num.is_zero()
    }
    pub fn is_one(&self) -> bool {
        self.num.is_one() && self.den.is_one()
    }
    /// The rational value if the form is constant.
    pub fn as_q(&self) -> Option<Q> {
        Some(Q::new(self.num.as_constant()?, self.den.as_constant()?))
    }
    pub fn numerator(&self) -> &Poly {
        &self.num
    }
    pub fn denominator(&self) -> &Poly {
        &self.den
    }
    /// Leaves that occur.
    pub fn vars(&self) -> Vec<Var> {
        let mut v = self.num.vars();
        v.extend(self.den.vars());
        v.sort_unstable();
        v.dedup();
        v
    }
    pub fn neg(&self) -> RatFun {
        RatFun {
            num: self.num.neg(),
            den: self.den.clone(),
        }
    }
    /// Number of terms in numerator and denominator (a size measure).
    pub fn term_count(&self) -> usize {
        self.num.len() + self.den.len()
    }
}

impl RatFun {
    pub(crate) fn fix_zero(self) -> RatFun {
        if self.num.is_zero() {
            RatFun::zero()
        } else {
            self
        }
    }
}
