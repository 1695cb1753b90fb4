//! A normal form for `atan` and `atan2` of rational constants, by unique
//! factorisation in the Gaussian integers Z[i].
//!
//! `atan(p/q)` (q > 0) is the principal argument of `z = q + i p`, and
//! `atan2(y, x)` that of `x + i y` (cleared of denominators). Arguments add
//! under multiplication, so factoring `z = unit * (1 + i)^e * prod pi_j^k_j`
//! writes its argument as a multiple of pi/4 plus an integer combination of
//! `theta_l = atan(b/a)`, one per rational prime `l = a^2 + b^2 = 1 (mod 4)`
//! with `a > b > 0` (the Gaussian prime `a + i b`; its conjugate has argument
//! `-theta_l`). These atoms are independent over Q together with pi: a
//! relation `sum n_l theta_l = (m/n) pi` would make `prod pi_l^(4 n n_l)` real,
//! so equal to its conjugate, which unique factorisation forbids unless every
//! `n_l` is 0 (`pi_l` and its conjugate are not associates). The form is
//! therefore canonical: `atan(1/2) + atan(1/3) - pi/4` and Machin's formula
//! are identically zero.
//!
//! Factoring is by trial division below [`TRIAL_MAX`]; a cofactor without
//! such factors becomes one atom `atan(d/c)` (`c > d > 0`, `c + i d` its
//! first-octant associate), which is `theta_l` itself when the cofactor's norm
//! is prime (always when it is below `TRIAL_MAX^2`). A composite cofactor is
//! the one case where relations stay undetected (docs/engine.md).

use crate::num::{int, int_exact_sqrt, int_gcd, Int};
use dashu_int::Sign;
use std::collections::BTreeMap;

/// Trial division bound for the norm of the Gaussian integer.
pub(crate) const TRIAL_MAX: i64 = 1 << 16;

/// `arg = quarters * pi/4 + sum n * atan(d/c)` over `atoms[(c, d)] = n`, with
/// `c > d > 0` coprime.
#[derive(Debug, Default, PartialEq, Eq)]
pub(crate) struct ArgForm {
    pub quarters: i64,
    pub atoms: BTreeMap<(Int, Int), i64>,
}

impl ArgForm {
    fn add_atom(&mut self, c: Int, d: Int, n: i64) {
        let e = self.atoms.entry((c, d)).or_insert(0);
        *e += n;
        if *e == 0 {
            self.atoms.retain(|_, n| *n != 0);
        }
    }
}

fn is_neg(x: &Int) -> bool {
    x.sign() == Sign::Negative && !x.is_zero()
}

/// Whether dividing `z` by a Gaussian integer of argument `theta` in (0, pi)
/// crossed the branch cut, given the quotient `w`: then
/// `arg z = arg w + theta - 2 pi`. (`arg z - theta` lies in (-2 pi, pi); it
/// wrapped iff it fell to -pi or below, which needs `Im z < 0` and puts `w` in
/// the closed upper half plane; without the wrap `Im z < 0` keeps `Im w < 0`.)
fn wrapped_down(z_im: &Int, w_im: &Int) -> bool {
    is_neg(z_im) && !is_neg(w_im)
}

/// As [`wrapped_down`] for a divisor of argument `-theta`: then
/// `arg z = arg w - theta + 2 pi` (`arg z + theta` passed pi: `z` in the
/// upper half plane or on the negative real axis, `w` in the open lower one).
fn wrapped_up(z: &(Int, Int), w_im: &Int) -> bool {
    let z_upper = (!is_neg(&z.1) && !z.1.is_zero()) || (z.1.is_zero() && is_neg(&z.0));
    z_upper && is_neg(w_im)
}

/// `(a, b)` with `a > b > 0` and `a^2 + b^2 = l`, for a prime `l = 1 (mod 4)` below `TRIAL_MAX`.
fn two_squares(l: i64) -> Option<(i64, i64)> {
    let mut b = 1i64;
    while 2 * b * b < l {
        if let Some(a) = int_exact_sqrt(&int(l - b * b)) {
            return i64::try_from(&a).ok().map(|a| (a, b));
        }
        b += 1;
    }
    None
}

/// The principal argument of `x + i y` (not both zero) in normal form.
pub(crate) fn arg(x: &Int, y: &Int) -> Option<ArgForm> {
    if x.is_zero() && y.is_zero() {
        return None;
    }
    let mut out = ArgForm::default();
    // A positive integer factor does not change the argument.
    let g = int_gcd(x, y);
    let mut z = (x / &g, y / &g);
    let norm = |z: &(Int, Int)| &z.0 * &z.0 + &z.1 * &z.1;
    let mut n = norm(&z);
    // z is primitive, so its norm is odd or twice an odd number, and has no
    // prime factor 3 mod 4: only 1 + i (argument pi/4) and split primes divide it.
    if (&n % int(2)).is_zero() {
        // z / (1 + i) = z (1 - i) / 2
        let w = ((&z.0 + &z.1) / int(2), (&z.1 - &z.0) / int(2));
        out.quarters += 1;
        if wrapped_down(&z.1, &w.1) {
            out.quarters -= 8;
        }
        z = w;
        n = norm(&z);
    }
    let mut l = 5i64;
    while l <= TRIAL_MAX && int(l) * int(l) <= n {
        let li = int(l);
        if (&n % &li).is_zero() {
            // l is prime (smaller primes are divided out) and 1 mod 4.
            let (a, b) = two_squares(l)?;
            let (a, b) = (int(a), int(b));
            // a + ib divides z iff z (a - ib) = (xa + yb) + i(ya - xb) is 0 mod l.
            let divides = ((&z.0 * &a + &z.1 * &b) % &li).is_zero()
                && ((&z.1 * &a - &z.0 * &b) % &li).is_zero();
            while (&n % &li).is_zero() {
                if divides {
                    let w = ((&z.0 * &a + &z.1 * &b) / &li, (&z.1 * &a - &z.0 * &b) / &li);
                    out.add_atom(a.clone(), b.clone(), 1);
                    if wrapped_down(&z.1, &w.1) {
                        out.quarters -= 8;
                    }
                    z = w;
                } else {
                    // z / (a - ib) = z (a + ib) / l
                    let w = ((&z.0 * &a - &z.1 * &b) / &li, (&z.0 * &b + &z.1 * &a) / &li);
                    out.add_atom(a.clone(), b.clone(), -1);
                    if wrapped_up(&z, &w.1) {
                        out.quarters += 8;
                    }
                    z = w;
                }
                n = norm(&z);
            }
        }
        l += 4;
    }
    // What is left: a unit, or a cofactor c + id brought to the first
    // quadrant by a unit (its argument then lies in (0, pi/2)).
    let (x, y) = z;
    if n == int(1) {
        out.quarters += if x == int(1) {
            0
        } else if y == int(1) {
            2
        } else if x == int(-1) {
            4
        } else {
            -2
        };
        return Some(out);
    }
    let (c, d) = match (is_neg(&x), is_neg(&y)) {
        (false, false) => (x, y),
        (true, false) => {
            out.quarters += 2;
            (y, -x)
        }
        (true, true) => {
            out.quarters -= 4;
            (-x, -y)
        }
        (false, true) => {
            out.quarters -= 2;
            (-y, x)
        }
    };
    // c, d > 0 and c != d (z is primitive with odd norm > 1).
    if c > d {
        out.add_atom(c, d, 1);
    } else {
        // arg(c + id) = pi/2 - atan(c/d)
        out.quarters += 2;
        out.add_atom(d, c, -1);
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn value(f: &ArgForm) -> f64 {
        let mut v = f.quarters as f64 * std::f64::consts::FRAC_PI_4;
        for ((c, d), n) in &f.atoms {
            let r = crate::num::int_to_f64(d) / crate::num::int_to_f64(c);
            v += *n as f64 * r.atan();
        }
        v
    }

    #[test]
    fn argument_matches_atan2_on_a_grid() {
        for x in -40i64..=40 {
            for y in -40i64..=40 {
                if x == 0 && y == 0 {
                    continue;
                }
                let f = arg(&int(x), &int(y)).unwrap();
                let want = (y as f64).atan2(x as f64);
                assert!((value(&f) - want).abs() < 1e-12, "{x} {y}: {f:?}");
                for (c, d) in f.atoms.keys() {
                    assert!(c > d && d > &int(0), "{x} {y}: {f:?}");
                }
            }
        }
    }

    #[test]
    fn known_relations() {
        // atan(1/2) + atan(1/3) = pi/4; Machin: 4 atan(1/5) - atan(1/239) = pi/4.
        let a = arg(&int(2), &int(1)).unwrap();
        let b = arg(&int(3), &int(1)).unwrap();
        assert_eq!(a.quarters + b.quarters, 1);
        let theta5 = (int(2), int(1));
        assert_eq!(a.atoms[&theta5] + b.atoms[&theta5], 0);
        let c = arg(&int(5), &int(1)).unwrap();
        let d = arg(&int(239), &int(1)).unwrap();
        assert_eq!(4 * c.quarters - d.quarters, 1);
        for (k, n) in &c.atoms {
            assert_eq!(4 * n, d.atoms.get(k).copied().unwrap_or(0), "{k:?}");
        }
    }
}
