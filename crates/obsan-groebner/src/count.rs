//! Counting solutions: the dimension of the quotient of a zero-dimensional
//! ideal, minimal polynomials of elements of the quotient (by linear algebra
//! on normal forms of their powers, as in FGLM), elimination, and the number
//! of distinct roots of a univariate polynomial.

use crate::field::Field;
use crate::gb::{Basis, GbBudget};
use crate::mem::{block, mono_bytes, over};
use crate::poly::{Mono, Order, Poly, Ring};
use crate::select::groebner;
use crate::GbError;
use obsan_recon::fp::{Echelon, Zp};
use std::collections::HashMap;
use std::mem::size_of;

impl Basis {
    /// Whether the ideal is zero-dimensional (finitely many common zeros over
    /// the algebraic closure): every variable has a pure power among the
    /// leading monomials. The unit ideal counts as zero-dimensional.
    pub fn is_zero_dimensional(&self) -> bool {
        if self.is_unit() {
            return true;
        }
        let mut seen = vec![false; self.ring.n];
        for p in &self.polys {
            if let Some(v) = p.terms[0].0.pure_power() {
                seen[v] = true;
            }
        }
        seen.iter().all(|&s| s)
    }

    /// The standard monomials (a basis of the quotient), if the ideal is
    /// zero-dimensional and there are at most `cap` of them.
    pub fn standard_monomials(&self, cap: usize) -> Result<Vec<Mono>, GbError> {
        self.standard_monomials_in(&vec![1; self.ring.n], cap)
    }

    /// The standard monomials of the subring `F_p[x_0^s_0, x_1^s_1, ...]`
    /// (`steps[v] = s_v >= 1`), for a basis whose every polynomial lies in
    /// that subring (checked: else `Err(Budget("basis outside the
    /// subring"))`). A basis of the ideal `I'` obtained from `I` by the
    /// substitution `x_v -> x_v^s_v` (the reduced basis of `I'` is the image of
    /// the reduced basis of `I` under the weighted grevlex order, so it lies in
    /// the subring) has these as a basis of the subring's quotient, which is
    /// `R/I` again: dimension `dim R/I`, not `prod s_v` times it.
    pub fn standard_monomials_in(&self, steps: &[u32], cap: usize) -> Result<Vec<Mono>, GbError> {
        let n = self.ring.n;
        if steps.len() != n || steps.contains(&0) {
            return Err(GbError::Budget("one step >= 1 per variable"));
        }
        let in_subring = |m: &Mono| m.exponents().iter().zip(steps).all(|(e, s)| e % s == 0);
        if !self
            .polys
            .iter()
            .all(|p| p.terms.iter().all(|(m, _)| in_subring(m)))
        {
            return Err(GbError::Budget("basis outside the subring"));
        }
        if !self.is_zero_dimensional() {
            return Err(GbError::NotZeroDimensional);
        }
        if self.is_unit() {
            return Ok(Vec::new());
        }
        let lms = self.leading_monomials();
        // Each monomial seen is held in `seen` (a hash slot at 7/8 load),
        // a standard one in `out` too, and up to n children on the stack.
        let per = mono_bytes(n) * (2 + n) + (size_of::<Mono>() + 1) * 8 / 7;
        let mut out: Vec<Mono> = Vec::new();
        let mut stack = vec![Mono::one(n)];
        let mut seen: std::collections::HashSet<Mono> = std::collections::HashSet::new();
        while let Some(m) = stack.pop() {
            if !seen.insert(m.clone()) || lms.iter().any(|l| l.divides(&m)) {
                continue;
            }
            out.push(m.clone());
            if out.len() > cap {
                return Err(GbError::Budget("dimension of the quotient"));
            }
            let need = seen.len() * per;
            if need > self.max_bytes {
                return Err(over(need, self.max_bytes, || {
                    format!(
                        "the count of solutions (the quotient's basis, {} monomials so far)",
                        out.len()
                    )
                }));
            }
            for (v, &st) in steps.iter().enumerate() {
                stack.push(m.mul(&Mono::var(n, v, st))?);
            }
        }
        Ok(out)
    }

    /// The monic minimal polynomial of `f` in the quotient ring (dense
    /// coefficients, constant term first), for a zero-dimensional ideal.
    /// Its distinct roots are the distinct values `f` takes on the zeros.
    pub fn minimal_polynomial(&self, f: &Poly, cap: usize) -> Result<Vec<u64>, GbError> {
        self.minimal_polynomial_in(f, &vec![1; self.ring.n], cap)
    }

    /// [`Basis::minimal_polynomial`] for `f` in the subring of
    /// [`Basis::standard_monomials_in`]: normal forms of its powers stay in
    /// the subring (each reduction step's multiplier is a quotient of two of
    /// its monomials), so the quotient's basis there suffices; a normal form
    /// outside it is an error, never a wrong count.
    pub fn minimal_polynomial_in(
        &self,
        f: &Poly,
        steps: &[u32],
        cap: usize,
    ) -> Result<Vec<u64>, GbError> {
        let std = self.standard_monomials_in(steps, cap)?;
        let r = &self.ring;
        let fld = r.field;
        let col: HashMap<Mono, usize> = std
            .iter()
            .cloned()
            .enumerate()
            .map(|(i, m)| (m, i))
            .collect();
        let dim = std.len();
        // Dense: up to dim + 1 echelon rows [normal form of f^k | e_k] of
        // 2 dim + 1 entries each, beside the quotient's basis and its column
        // map, and the normal forms of m f for the standard monomials m
        // (dim entries each).
        let rows_bytes = (dim + 1) * (size_of::<(usize, Vec<u64>)>() + block(8 * (2 * dim + 1)));
        let times_bytes = dim * (size_of::<Option<Vec<u64>>>() + block(8 * dim));
        let need = rows_bytes + times_bytes + dim * (2 * mono_bytes(r.n) + 2 * size_of::<usize>());
        if need > self.max_bytes {
            return Err(over(need, self.max_bytes, || {
                format!("the count of solutions (a dense {dim} x {dim} matrix over the quotient)")
            }));
        }
        // The one dense elimination keeps both parts of each row, so a power
        // whose normal form reduces to zero leaves in its second part the
        // first linear dependency of the powers.
        let mut ech = Echelon::new(Zp(fld.modulus()));
        let f = self.reduce(f)?;
        let dense = |p: &Poly| -> Result<Vec<u64>, GbError> {
            let mut v = vec![0u64; dim];
            for (m, c) in p.terms() {
                let i = *col
                    .get(m)
                    .ok_or(GbError::Budget("normal form outside the quotient"))?;
                v[i] = *c;
            }
            Ok(v)
        };
        // Multiplication by f on the quotient, one column per standard
        // monomial, each the normal form of `m f` computed once when first
        // needed: the normal form is linear, so `NF(g f) = sum_m g_m NF(m f)`
        // for `g` a normal form, a dense combination where reducing `g f`
        // itself repeated the division for every power (Lincomp1: 95 % of
        // `obsan global` in `Basis::reduce`).
        let mut times: Vec<Option<Vec<u64>>> = vec![None; dim];
        let mut pw = dense(&self.reduce(&r.constant(1))?)?;
        for k in 0..=dim {
            let mut v = vec![0u64; 2 * dim + 1];
            v[..dim].copy_from_slice(&pw);
            v[dim + k] = 1;
            let reduced = ech.reduce(v);
            if reduced[..dim].iter().all(|&x| x == 0) {
                // sum combo[i] f^i = 0 with combo[k] != 0: the first
                // dependency is the minimal polynomial, made monic.
                let combo = &reduced[dim..=dim + k];
                let inv = fld
                    .inv(combo[k])
                    .ok_or(GbError::Budget("zero leading coefficient"))?;
                return Ok(combo.iter().map(|&c| fld.mul(c, inv)).collect());
            }
            ech.insert(reduced);
            if k < dim {
                let mut next = vec![0u64; dim];
                for (i, &c) in pw.iter().enumerate() {
                    if c == 0 {
                        continue;
                    }
                    if times[i].is_none() {
                        let mf = r.mul(&r.from_terms([(std[i].clone(), 1)]), &f)?;
                        times[i] = Some(dense(&self.reduce(&mf)?)?);
                    }
                    if let Some(col) = &times[i] {
                        for (a, &b) in next.iter_mut().zip(col) {
                            *a = fld.add(*a, fld.mul(c, b));
                        }
                    }
                }
                pw = next;
            }
        }
        // dim + 1 vectors in a space of dimension dim are dependent.
        Err(GbError::Budget("minimal polynomial"))
    }
}

/// The generator of the elimination ideal `I ∩ F_p[x_v]` as dense
/// coefficients (constant first), or `None` if it is zero (x_v takes
/// infinitely many values on the zeros). One Gröbner basis under a block order
/// with `x_v` alone in the last block.
pub fn eliminate_to(
    field: Field,
    n: usize,
    gens: &[Poly],
    v: usize,
    budget: GbBudget,
) -> Result<Option<Vec<u64>>, GbError> {
    // Move x_v to the last position.
    let perm = |m: &Mono| -> Result<Mono, GbError> {
        let mut e = m.exponents().to_vec();
        let x = e.remove(v);
        e.push(x);
        Mono::from_exponents(e)
    };
    let ring = Ring::new(field, n, Order::Block(n - 1));
    let mut g2 = Vec::with_capacity(gens.len());
    for p in gens {
        let t: Result<Vec<_>, _> = p.terms().iter().map(|(m, c)| Ok((perm(m)?, *c))).collect();
        g2.push(ring.from_terms(t?));
    }
    let b = groebner(&ring, &g2, budget)?;
    if b.is_unit() {
        return Ok(Some(vec![1]));
    }
    for p in &b.polys {
        if ring.only_in(p, &[n - 1]) {
            let d = p.degree() as usize;
            let mut c = vec![0u64; d + 1];
            for (m, x) in p.terms() {
                c[m.exponents()[n - 1] as usize] = *x;
            }
            return Ok(Some(c));
        }
    }
    Ok(None)
}

/// The number of distinct roots in the algebraic closure of F_p of a
/// univariate polynomial (dense, constant first) of degree below p: the degree
/// of `f / gcd(f, f')`.
pub fn distinct_roots(field: Field, f: &[u64]) -> usize {
    let f = trim(f.to_vec());
    if f.len() <= 1 {
        return 0;
    }
    let df: Vec<u64> = (1..f.len())
        .map(|i| field.mul(f[i], field.reduce(i as u64)))
        .collect();
    let g = upoly_gcd(field, f.clone(), trim(df));
    (f.len() - 1) - (g.len() - 1)
}

fn trim(mut a: Vec<u64>) -> Vec<u64> {
    while a.len() > 1 && *a.last().unwrap_or(&1) == 0 {
        a.pop();
    }
    if a.is_empty() {
        a.push(0);
    }
    a
}

/// Monic gcd of two univariate polynomials (dense, constant first).
pub fn upoly_gcd(field: Field, mut a: Vec<u64>, mut b: Vec<u64>) -> Vec<u64> {
    a = trim(a);
    b = trim(b);
    while !(b.len() == 1 && b[0] == 0) {
        // a mod b
        let lb = b[b.len() - 1];
        let inv = match field.inv(lb) {
            Some(i) => i,
            None => break,
        };
        while a.len() >= b.len() && !(a.len() == 1 && a[0] == 0) {
            let c = field.mul(a[a.len() - 1], inv);
            let shift = a.len() - b.len();
            for (i, &x) in b.iter().enumerate() {
                a[i + shift] = field.sub(a[i + shift], field.mul(c, x));
            }
            a.pop();
            a = trim(a);
            if a.len() < b.len() {
                break;
            }
        }
        std::mem::swap(&mut a, &mut b);
    }
    let l = a[a.len() - 1];
    match field.inv(l) {
        Some(i) => a.iter().map(|&x| field.mul(x, i)).collect(),
        None => a,
    }
}
