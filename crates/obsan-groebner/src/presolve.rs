//! Linear presolve: generators of degree 1 are put in reduced echelon form
//! (each solved for its leading variable) and every solved variable is
//! substituted into the other generators, repeated while substitution makes
//! new ones linear. The ideal is unchanged (`<x - L, g> = <x - L, g(x = L)>`),
//! so the reduced basis computed afterwards is the same; but F4's matrices no
//! longer carry, for every monomial holding a solved variable, a row of
//! `x - L` times a multiplier (a system where outputs fix many unknowns to
//! numbers, as SIAN's does, has dozens of such variables).

use crate::mem::over;
use crate::poly::{Mono, Poly, Ring};
use crate::GbError;

/// `p` with `x_v := l` (`l` free of `x_v`).
fn substitute(ring: &Ring, p: &Poly, v: usize, l: &Poly) -> Result<Poly, GbError> {
    if p.terms().iter().all(|(m, _)| m.exponents()[v] == 0) {
        return Ok(p.clone());
    }
    // p = sum_e x_v^e p_e; the powers of l are built once each.
    let top = p
        .terms()
        .iter()
        .map(|(m, _)| m.exponents()[v])
        .max()
        .unwrap_or(0);
    let mut parts: Vec<Vec<(Mono, u64)>> = vec![Vec::new(); top as usize + 1];
    for (m, c) in p.terms() {
        let mut e = m.exponents().to_vec();
        let k = std::mem::replace(&mut e[v], 0);
        parts[k as usize].push((Mono::from_exponents(e)?, *c));
    }
    let mut out = Poly::zero();
    let mut pw = ring.constant(1);
    for (k, terms) in parts.into_iter().enumerate() {
        if k > 0 {
            pw = ring.mul(&pw, l)?;
        }
        if !terms.is_empty() {
            out = ring.add(&out, &ring.mul(&ring.from_terms(terms), &pw)?);
        }
    }
    Ok(out)
}

/// The generators with every linear one solved and substituted (module
/// docs): the solved ones come first as `x_v - L`, each `L` free of every
/// solved variable; `[1]` if the ideal is the unit ideal. Every polynomial
/// held is counted against `max_bytes`.
pub fn presolve_linear(ring: &Ring, gens: &[Poly], max_bytes: usize) -> Result<Vec<Poly>, GbError> {
    let n = ring.n;
    let mut rest: Vec<Poly> = gens.iter().filter(|g| !g.is_zero()).cloned().collect();
    // Solved variables: (v, L) with x_v = L.
    let mut solved: Vec<(usize, Poly)> = Vec::new();
    while let Some(i) = rest.iter().position(|g| g.degree() <= 1) {
        let g = ring.monic(&rest.swap_remove(i));
        let Some((lead, _)) = g.leading() else {
            continue;
        };
        if lead.is_one() {
            return Ok(vec![ring.constant(1)]);
        }
        // Degree 1: the leading monomial is a variable.
        let Some(v) = lead.pure_power() else {
            continue;
        };
        let l = ring.sub(&ring.var(v), &g);
        for (_, lw) in solved.iter_mut() {
            *lw = substitute(ring, lw, v, &l)?;
        }
        let mut bytes = 0usize;
        let mut next = Vec::with_capacity(rest.len());
        for p in &rest {
            let q = substitute(ring, p, v, &l)?;
            if !q.is_zero() {
                bytes += q.stored_bytes(n);
                next.push(q);
            }
        }
        if bytes > max_bytes {
            return Err(over(bytes, max_bytes, || {
                format!(
                    "the system after its linear presolve ({} polynomials)",
                    next.len()
                )
            }));
        }
        rest = next;
        solved.push((v, l));
    }
    let mut out: Vec<Poly> = solved
        .into_iter()
        .map(|(v, l)| ring.sub(&ring.var(v), &l))
        .collect();
    out.extend(rest);
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{groebner, Field, GbBudget, Order};

    #[test]
    fn presolve_keeps_the_reduced_basis() {
        // x0 - 3 = 0, x1 + x0 x2 - 1 = 0, x2^2 - x1 = 0, x3 - x1 - x2 = 0:
        // the same ideal before and after, so the same reduced basis.
        let f = Field::new((1 << 61) - 1).unwrap();
        let r = Ring::new(f, 4, Order::Grevlex);
        let v = |i| r.var(i);
        let c = |k: i64| r.constant(f.from_i64(k));
        let gens = vec![
            r.sub(&v(0), &c(3)),
            r.sub(&r.add(&v(1), &r.mul(&v(0), &v(2)).unwrap()), &c(1)),
            r.sub(&r.mul(&v(2), &v(2)).unwrap(), &v(1)),
            r.sub(&r.sub(&v(3), &v(1)), &v(2)),
        ];
        let pre = presolve_linear(&r, &gens, usize::MAX).unwrap();
        let a = groebner(&r, &gens, GbBudget::default()).unwrap();
        let b = groebner(&r, &pre, GbBudget::default()).unwrap();
        assert_eq!(a.polys, b.polys);
        // x0 is solved to 3, and no other generator holds it.
        assert!(pre[1..]
            .iter()
            .all(|p| p.terms().iter().all(|(m, _)| m.exponents()[0] == 0)));
    }

    #[test]
    fn an_inconsistent_linear_system_is_the_unit_ideal() {
        let f = Field::new((1 << 61) - 1).unwrap();
        let r = Ring::new(f, 2, Order::Grevlex);
        let gens = vec![
            r.sub(&r.var(0), &r.constant(1)),
            r.sub(&r.var(0), &r.constant(2)),
        ];
        let pre = presolve_linear(&r, &gens, usize::MAX).unwrap();
        assert_eq!(pre, vec![r.constant(1)]);
    }
}

#[cfg(test)]
mod subring_tests {
    use crate::{groebner, Field, GbBudget, GbError, Mono, Order, Ring};

    #[test]
    fn the_subring_count_is_the_count_before_the_substitution() {
        // I = <x^2 - 4, y - x>: y takes 2 values. Under x -> x^3, y -> y^2
        // the ideal <x^6 - 4, y^2 - x^3> has 12 zeros, but y^2 (the old y)
        // still takes 2 values, counted in the subring of x^3, y^2 in a
        // quotient of dimension 2, not 12.
        let f = Field::new((1 << 61) - 1).unwrap();
        let r = Ring::new(f, 2, Order::Grevlex);
        let g = vec![
            r.from_terms([(Mono::var(2, 0, 6), 1), (Mono::one(2), f.from_i64(-4))]),
            r.from_terms([
                (Mono::var(2, 1, 2), 1),
                (Mono::var(2, 0, 3), f.from_i64(-1)),
            ]),
        ];
        let b = groebner(&r, &g, GbBudget::default()).unwrap();
        assert_eq!(b.standard_monomials(100).unwrap().len(), 12);
        let steps = [3, 2];
        assert_eq!(b.standard_monomials_in(&steps, 100).unwrap().len(), 2);
        let y2 = r.from_terms([(Mono::var(2, 1, 2), 1)]);
        let m = b.minimal_polynomial_in(&y2, &steps, 100).unwrap();
        assert_eq!(crate::distinct_roots(f, &m), 2);
        // The whole y takes 4 values (y^2 = +-2 each has two roots).
        let m = b.minimal_polynomial(&r.var(1), 100).unwrap();
        assert_eq!(crate::distinct_roots(f, &m), 4);
        // A basis outside the subring is refused, never miscounted.
        assert_eq!(
            b.standard_monomials_in(&[2, 2], 100),
            Err(GbError::Budget("basis outside the subring"))
        );
    }
}
