//! Brown's modular multivariate gcd over Z (W. S. Brown, "On Euclid's
//! algorithm and the computation of polynomial greatest common divisors",
//! J. ACM 18, 1971; the MGCD/PGCD pair of Geddes, Czapor and Labahn,
//! *Algorithms for Computer Algebra*, §7.4).
//!
//! - Over Z (`modular_gcd`): images modulo 62-bit primes not dividing either
//!   leading coefficient, each scaled to `gamma = gcd(lc a, lc b)` (the
//!   leading-coefficient correction), combined by CRT in the symmetric range.
//! - Over F_p (`pgcd`): the last variable is evaluated at random points,
//!   the gcd taken recursively, the images scaled to `g(alpha)` where `g` is
//!   the gcd of the leading coefficients in that variable, and rebuilt by
//!   Newton interpolation; the base case is Euclid's algorithm in F_p[x].
//!
//! Unlucky primes and points are detected, never trusted: with the leading
//! coefficients nonzero at the point (or modulo the prime), an image's
//! leading monomial is never below the true gcd's, and it is equal exactly
//! when the image is the true gcd's image. A smaller leading monomial restarts
//! the interpolation, a larger one is skipped. Interpolation stops early when
//! a new point changes nothing, and every candidate is proven by trial
//! division (modulo p inside `pgcd`, over Z at the end), so the answer is
//! exact whatever the random choices; they affect only the time. A budget
//! trip or an unexpected run of failures returns `None` and the caller falls
//! back to the primitive PRS (which stops at once on a tripped budget).

use crate::budget;
use crate::num::{int, int_gcd, int_mod, Int, SplitMix};
use crate::poly::{Mono, Poly, Var};
use dashu_int::ops::Abs;
use obsan_recon::fp;
use smallvec::SmallVec;
use std::cmp::Ordering;
use std::collections::BTreeMap;

/// Exponent vector, one entry per variable of the problem (position 0 is the
/// lex-highest variable). At recursion level `k` only positions `< k` are nonzero.
type Exps = SmallVec<[u32; 8]>;

/// Most primes tried before giving up (a 62-bit prime adds 62 bits, so this
/// is far beyond any coefficient the term budget lets through).
const MAX_PRIMES: usize = 4096;

/// Most unlucky or failed rounds tolerated per interpolation.
const MAX_FAILURES: usize = 8;

// ---------------------------------------------------------------- F_p

/// Arithmetic modulo a prime `p < 2^62`: obsan-recon's `fp`, the
/// workspace's one implementation; this type only carries the modulus.
#[derive(Clone, Copy, Debug)]
struct Field {
    p: u64,
}

impl Field {
    #[inline]
    fn add(self, a: u64, b: u64) -> u64 {
        fp::add(a, b, self.p)
    }
    #[inline]
    fn sub(self, a: u64, b: u64) -> u64 {
        fp::sub(a, b, self.p)
    }
    #[inline]
    fn mul(self, a: u64, b: u64) -> u64 {
        fp::mul(a, b, self.p)
    }
    /// Inverse of a nonzero element; `0` maps to `0`.
    fn inv(self, a: u64) -> u64 {
        fp::inv(a, self.p).unwrap_or(0)
    }
    fn reduce(self, x: &Int) -> u64 {
        int_mod(x, self.p)
    }
}

pub(crate) use obsan_recon::is_prime;

/// The `i`-th prime below 2^62, in decreasing order (cached per thread).
fn prime(i: usize) -> u64 {
    thread_local! {
        static CACHE: std::cell::RefCell<Vec<u64>> = const { std::cell::RefCell::new(Vec::new()) };
    }
    CACHE.with(|c| {
        let mut c = c.borrow_mut();
        while c.len() <= i {
            let from = c.last().map_or((1 << 62) - 1, |&p| p - 2);
            let more = primes_below(from, 32);
            if more.is_empty() {
                break;
            }
            c.extend(more);
        }
        c.get(i).copied().unwrap_or(3)
    })
}

fn primes_below(start: u64, count: usize) -> Vec<u64> {
    let mut out = Vec::with_capacity(count);
    let mut n = start | 1;
    while out.len() < count && n > 3 {
        if is_prime(n) {
            out.push(n);
        }
        n -= 2;
    }
    out
}

// ------------------------------------------------- dense F_p[x], low to high

fn trim(a: &mut Vec<u64>) {
    while a.last() == Some(&0) {
        a.pop();
    }
}

fn uni_eval(f: Field, a: &[u64], x: u64) -> u64 {
    a.iter().rev().fold(0, |acc, &c| f.add(f.mul(acc, x), c))
}

fn uni_deg(a: &[u64]) -> usize {
    a.len().saturating_sub(1)
}

fn uni_is_one(a: &[u64]) -> bool {
    a.len() == 1 && a[0] == 1
}

/// Monic gcd (zero only if both are zero).
fn uni_gcd(f: Field, a: &[u64], b: &[u64]) -> Vec<u64> {
    let (mut a, mut b) = (a.to_vec(), b.to_vec());
    trim(&mut a);
    trim(&mut b);
    while let Some(&lb) = b.last() {
        let inv = f.inv(lb);
        while a.len() >= b.len() {
            let Some(&top) = a.last() else { break };
            let c = f.mul(top, inv);
            let shift = a.len() - b.len();
            for (i, &bi) in b.iter().enumerate() {
                a[shift + i] = f.sub(a[shift + i], f.mul(c, bi));
            }
            trim(&mut a);
        }
        std::mem::swap(&mut a, &mut b);
    }
    if let Some(&la) = a.last() {
        let inv = f.inv(la);
        for c in &mut a {
            *c = f.mul(*c, inv);
        }
    }
    a
}

/// Quotient and remainder by a nonzero divisor.
fn uni_divrem(f: Field, a: &[u64], d: &[u64]) -> (Vec<u64>, Vec<u64>) {
    let mut r = a.to_vec();
    trim(&mut r);
    let Some(&ld) = d.last() else {
        return (Vec::new(), r);
    };
    if r.len() < d.len() {
        return (Vec::new(), r);
    }
    let inv = f.inv(ld);
    let mut q = vec![0; r.len() - d.len() + 1];
    while r.len() >= d.len() {
        let Some(&top) = r.last() else { break };
        let c = f.mul(top, inv);
        let shift = r.len() - d.len();
        q[shift] = c;
        for (i, &di) in d.iter().enumerate() {
            r[shift + i] = f.sub(r[shift + i], f.mul(c, di));
        }
        // The top coefficient is now exactly zero.
        r.pop();
        trim(&mut r);
    }
    trim(&mut q);
    (q, r)
}

fn uni_mul(f: Field, a: &[u64], b: &[u64]) -> Vec<u64> {
    if a.is_empty() || b.is_empty() {
        return Vec::new();
    }
    let mut out = vec![0; a.len() + b.len() - 1];
    for (i, &x) in a.iter().enumerate() {
        if x == 0 {
            continue;
        }
        for (j, &y) in b.iter().enumerate() {
            out[i + j] = f.add(out[i + j], f.mul(x, y));
        }
    }
    trim(&mut out);
    out
}

// ------------------------------------------- sparse F_p[x_0..x_{n-1}]

/// A polynomial modulo p: terms in decreasing lex order, nonzero coefficients.
type MP = Vec<(Exps, u64)>;

/// The terms of `a` grouped by their exponents in `x_0..x_{k-2}`: each group
/// is a dense polynomial in `x_{k-1}`. Terms of one group are contiguous in
/// lex order, so this is one pass; groups come in decreasing order.
fn groups(a: &MP, k: usize) -> Vec<(Exps, Vec<u64>)> {
    let mut out: Vec<(Exps, Vec<u64>)> = Vec::new();
    for (e, c) in a {
        let mut key = e.clone();
        let d = std::mem::take(&mut key[k - 1]) as usize;
        match out.last_mut() {
            Some((k0, u)) if *k0 == key => {
                if u.len() <= d {
                    u.resize(d + 1, 0);
                }
                u[d] = *c;
            }
            _ => {
                let mut u = vec![0; d + 1];
                u[d] = *c;
                out.push((key, u));
            }
        }
    }
    out
}

/// Inverse of `groups`.
fn ungroup(g: &[(Exps, Vec<u64>)], k: usize) -> MP {
    let mut out = Vec::new();
    for (key, u) in g {
        for (d, &c) in u.iter().enumerate().rev() {
            if c != 0 {
                let mut e = key.clone();
                e[k - 1] = d as u32;
                out.push((e, c));
            }
        }
    }
    out
}

/// Value at `x_{k-1} = alpha` (zero coefficients dropped; order kept).
fn eval_groups(f: Field, g: &[(Exps, Vec<u64>)], alpha: u64) -> MP {
    g.iter()
        .filter_map(|(key, u)| {
            let v = uni_eval(f, u, alpha);
            (v != 0).then(|| (key.clone(), v))
        })
        .collect()
}

fn is_const(a: &MP) -> bool {
    a.len() == 1 && a[0].0.iter().all(|&e| e == 0)
}

fn make_monic(f: Field, a: &mut MP) {
    if let Some(&(_, lc)) = a.first() {
        let inv = f.inv(lc);
        for t in a.iter_mut() {
            t.1 = f.mul(t.1, inv);
        }
    }
}

/// Exact quotient `a / d` modulo p, or `None` if `d` does not divide `a`.
fn mp_div_exact(f: Field, a: &MP, d: &MP) -> Option<MP> {
    let (lm, lc) = d.first()?;
    let inv = f.inv(*lc);
    let mut r: BTreeMap<Exps, u64> = a.iter().cloned().collect();
    let mut q = Vec::new();
    while let Some((rm, rc)) = r.pop_last() {
        if !budget::poll() {
            return None;
        }
        let mut m = Exps::with_capacity(rm.len());
        for (x, y) in rm.iter().zip(lm.iter()) {
            m.push(x.checked_sub(*y)?);
        }
        let c = f.mul(rc, inv);
        for (dm, dc) in &d[1..] {
            let key: Exps = dm.iter().zip(m.iter()).map(|(x, y)| x + y).collect();
            let sub = f.mul(*dc, c);
            match r.entry(key) {
                std::collections::btree_map::Entry::Occupied(mut o) => {
                    let v = f.sub(*o.get(), sub);
                    if v == 0 {
                        o.remove();
                    } else {
                        *o.get_mut() = v;
                    }
                }
                std::collections::btree_map::Entry::Vacant(o) => {
                    o.insert(f.sub(0, sub));
                }
            }
        }
        q.push((m, c));
    }
    Some(q)
}

/// The gcd of two univariate polynomials (in `x_0`, the other exponents zero) by the
/// dense Euclidean algorithm, monic.
fn pgcd_univariate(f: Field, a: &MP, b: &MP) -> MP {
    let dense = |p: &MP| {
        let mut u = vec![0; p.first().map_or(0, |t| t.0[0] as usize) + 1];
        for (e, c) in p {
            u[e[0] as usize] = *c;
        }
        u
    };
    let g = uni_gcd(f, &dense(a), &dense(b));
    let n = a.first().map_or(1, |t| t.0.len());
    let mut out = MP::new();
    for (d, &c) in g.iter().enumerate().rev() {
        if c != 0 {
            let mut e: Exps = smallvec::smallvec![0; n];
            e[0] = d as u32;
            out.push((e, c));
        }
    }
    out
}

/// The content in `F_p[x_{k-1}]` of a polynomial grouped by its other monomials: the
/// gcd of its coefficient polynomials.
fn uni_content(f: Field, g: &[(Exps, Vec<u64>)]) -> Vec<u64> {
    let mut c: Vec<u64> = Vec::new();
    for (_, u) in g {
        c = uni_gcd(f, &c, u);
        if uni_is_one(&c) {
            break;
        }
    }
    c
}

/// One Newton interpolation step at `alpha`: `h += (img - h(alpha)) / q(alpha) * q`,
/// per monomial (both sorted the same way, `h`'s coefficients polynomials in
/// `x_{k-1}`). Whether `h` changed.
fn newton_step(
    f: Field,
    h: &mut Vec<(Exps, Vec<u64>)>,
    img: &MP,
    q: &[u64],
    alpha: u64,
) -> Option<bool> {
    let qinv = f.inv(uni_eval(f, q, alpha));
    let mut changed = false;
    let old = std::mem::take(h);
    let mut old = old.into_iter().peekable();
    let mut j = 0;
    while old.peek().is_some() || j < img.len() {
        let ord = match (old.peek(), img.get(j)) {
            (Some(x), Some(y)) => x.0.cmp(&y.0),
            (Some(_), None) => Ordering::Greater,
            _ => Ordering::Less,
        };
        let (key, mut u, v) = match ord {
            Ordering::Greater => {
                let (key, u) = old.next()?;
                (key, u, 0)
            }
            Ordering::Less => {
                j += 1;
                (img[j - 1].0.clone(), Vec::new(), img[j - 1].1)
            }
            Ordering::Equal => {
                let (key, u) = old.next()?;
                j += 1;
                (key, u, img[j - 1].1)
            }
        };
        let d = f.mul(f.sub(v, uni_eval(f, &u, alpha)), qinv);
        if d != 0 {
            changed = true;
            if u.len() < q.len() {
                u.resize(q.len(), 0);
            }
            for (x, &qc) in u.iter_mut().zip(q.iter()) {
                *x = f.add(*x, f.mul(d, qc));
            }
            trim(&mut u);
        }
        if !u.is_empty() {
            h.push((key, u));
        }
    }
    Some(changed)
}

/// Monic gcd of two nonzero polynomials modulo p in `x_0..x_{k-1}` (Brown's
/// PGCD); `None` on a budget trip or an unexpected run of failures.
fn pgcd(f: Field, a: &MP, b: &MP, k: usize, rng: &mut SplitMix) -> Option<MP> {
    if k == 1 {
        return Some(pgcd_univariate(f, a, b));
    }
    let (mut ga, mut gb) = (groups(a, k), groups(b, k));
    // Contents in F_p[x_{k-1}] and primitive parts.
    let content = |g: &[(Exps, Vec<u64>)]| uni_content(f, g);
    let (ca, cb) = (content(&ga), content(&gb));
    let cont = uni_gcd(f, &ca, &cb);
    for (g, c) in [(&mut ga, &ca), (&mut gb, &cb)] {
        if !uni_is_one(c) {
            for (_, u) in g.iter_mut() {
                u.clone_from(&uni_divrem(f, u, c).0);
            }
        }
    }
    let n = a[0].0.len();
    let with_content = |h: MP| -> MP {
        // cont(x_{k-1}) * h, made monic.
        let mut gh = groups(&h, k);
        for (_, u) in gh.iter_mut() {
            *u = uni_mul(f, u, &cont);
        }
        let mut out = ungroup(&gh, k);
        make_monic(f, &mut out);
        out
    };
    let unit: MP = vec![(smallvec::smallvec![0; n], 1)];
    // A primitive part free of x_0..x_{k-2} is 1.
    if ga.len() == 1 && ga[0].0.iter().all(|&e| e == 0)
        || gb.len() == 1 && gb[0].0.iter().all(|&e| e == 0)
    {
        return Some(with_content(unit));
    }
    let deg = |g: &[(Exps, Vec<u64>)]| g.iter().map(|(_, u)| uni_deg(u)).max().unwrap_or(0);
    let (pa, pb) = (ungroup(&ga, k), ungroup(&gb, k));
    if deg(&ga) == 0 && deg(&gb) == 0 {
        // x_{k-1} occurs in neither primitive part.
        return Some(with_content(pgcd(f, &pa, &pb, k - 1, rng)?));
    }
    let (lca, lcb) = (ga[0].1.clone(), gb[0].1.clone());
    let lcg = uni_gcd(f, &lca, &lcb);
    // deg_{x_{k-1}} of the interpolated lcg/lc(G) * G.
    let bound = uni_deg(&lcg) + deg(&ga).min(deg(&gb));

    // Newton interpolant: leading monomial, groups, the product of (x - alpha_i).
    let mut lm: Option<Exps> = None;
    let mut h: Vec<(Exps, Vec<u64>)> = Vec::new();
    let mut q: Vec<u64> = vec![1];
    let mut points = 0usize;
    // Images whose leading monomial is at least this were all unlucky.
    let mut reject: Option<Exps> = None;
    let mut failures = 0usize;
    let mut tries = 0usize;
    loop {
        tries += 1;
        if !budget::poll() || failures > MAX_FAILURES || tries > 4 * bound + 64 {
            return None;
        }
        let alpha = rng.next_u64() % f.p;
        if uni_eval(f, &lcg, alpha) == 0
            || uni_eval(f, &lca, alpha) == 0
            || uni_eval(f, &lcb, alpha) == 0
            || uni_eval(f, &q, alpha) == 0
        {
            continue;
        }
        let (ea, eb) = (eval_groups(f, &ga, alpha), eval_groups(f, &gb, alpha));
        let mut img = pgcd(f, &ea, &eb, k - 1, rng)?;
        if is_const(&img) {
            // The primitive parts are coprime: LM(gcd) <= LM(image) = 1.
            return Some(with_content(unit));
        }
        let s = uni_eval(f, &lcg, alpha);
        for t in img.iter_mut() {
            t.1 = f.mul(t.1, s);
        }
        let ilm = img[0].0.clone();
        if reject.as_ref().is_some_and(|r| ilm >= *r) {
            continue;
        }
        let changed = match lm.as_ref().map(|l| ilm.cmp(l)) {
            Some(Ordering::Greater) => continue,
            Some(Ordering::Equal) => {
                let changed = newton_step(f, &mut h, &img, &q, alpha)?;
                q = uni_mul(f, &q, &[f.sub(0, alpha), 1]);
                points += 1;
                changed
            }
            // First point, or every earlier point was unlucky.
            None | Some(Ordering::Less) => {
                lm = Some(ilm);
                h = img.into_iter().map(|(e, c)| (e, vec![c])).collect();
                q = vec![f.sub(0, alpha), 1];
                points = 1;
                true
            }
        };
        // Stop at the degree bound, or early when a new point changed nothing.
        if changed && points <= bound {
            continue;
        }
        // Candidate: the primitive part of h in x_{k-1}, proven by division.
        let hc = content(&h);
        let mut cand = h.clone();
        if !uni_is_one(&hc) {
            for (_, u) in cand.iter_mut() {
                u.clone_from(&uni_divrem(f, u, &hc).0);
            }
        }
        let cand = ungroup(&cand, k);
        if mp_div_exact(f, &pa, &cand).is_some() && mp_div_exact(f, &pb, &cand).is_some() {
            return Some(with_content(cand));
        }
        if !budget::poll() {
            return None;
        }
        if points > bound {
            // Every image since the last restart was unlucky.
            failures += 1;
            reject = lm.take();
            h.clear();
            q = vec![1];
            points = 0;
        }
    }
}

// ------------------------------------------------------------------ Z

/// Gcd of two non-constant primitive polynomials over Z with the same
/// variables and no monomial content; `None` sends the caller to the PRS.
pub(crate) fn modular_gcd(a: &Poly, b: &Poly) -> Option<Poly> {
    let vars = a.vars();
    if vars.is_empty() || b.vars() != vars {
        return None;
    }
    // The base variable of the recursion is the one of highest degree: the
    // others are interpolated densely, at about (degree + 1) points each.
    let mut order: Vec<Var> = vars.clone();
    order.sort_by_key(|&v| (std::cmp::Reverse(a.degree(v).max(b.degree(v))), v));
    let n = order.len();
    let pos = |v: Var| order.iter().position(|&x| x == v).unwrap_or(0);
    let to_z = |p: &Poly| {
        let mut t: Vec<(Exps, Int)> = p
            .terms()
            .iter()
            .map(|(m, c)| {
                let mut e: Exps = smallvec::smallvec![0; n];
                for (v, x) in m.iter() {
                    e[pos(v)] = x;
                }
                (e, c.clone())
            })
            .collect();
        t.sort_unstable_by(|x, y| y.0.cmp(&x.0));
        t
    };
    let (za, zb) = (to_z(a), to_z(b));
    let (lca, lcb) = (za[0].1.clone(), zb[0].1.clone());
    let gamma = int_gcd(&lca, &lcb);
    let back = |t: &[(Exps, Int)]| {
        Poly::from_terms(t.iter().map(|(e, c)| {
            let m = Mono::from_pairs(
                e.iter()
                    .enumerate()
                    .filter(|(_, &x)| x > 0)
                    .map(|(i, &x)| (order[i], x)),
            );
            (m, c.clone())
        }))
    };
    let mut rng = SplitMix(0x6d6f_6467_6364 ^ ((a.len() as u64) << 32) ^ b.len() as u64);
    // CRT state: leading monomial, residues in [0, m), modulus, last symmetric image.
    let mut lm: Option<Exps> = None;
    let mut h: Vec<(Exps, Int)> = Vec::new();
    let mut modulus = int(1);
    let mut last: Vec<(Exps, Int)> = Vec::new();
    for i in 0..MAX_PRIMES {
        if !budget::poll() {
            return None;
        }
        let f = Field { p: prime(i) };
        if f.reduce(&lca) == 0 || f.reduce(&lcb) == 0 {
            continue;
        }
        let reduce = |t: &[(Exps, Int)]| -> MP {
            t.iter()
                .filter_map(|(e, c)| {
                    let r = f.reduce(c);
                    (r != 0).then(|| (e.clone(), r))
                })
                .collect()
        };
        let Some(mut img) = pgcd(f, &reduce(&za), &reduce(&zb), n, &mut rng) else {
            if budget::tripped() {
                return None;
            }
            continue;
        };
        if is_const(&img) {
            return Some(Poly::one());
        }
        let s = f.reduce(&gamma);
        for t in img.iter_mut() {
            t.1 = f.mul(t.1, s);
        }
        match lm.as_ref().map(|l| img[0].0.cmp(l)) {
            Some(Ordering::Greater) => continue,
            Some(Ordering::Equal) => {
                h = crt(f, &h, &modulus, &img);
                modulus *= Int::from(f.p);
            }
            None | Some(Ordering::Less) => {
                lm = Some(img[0].0.clone());
                h = img
                    .iter()
                    .map(|(e, c)| (e.clone(), Int::from(*c)))
                    .collect();
                modulus = Int::from(f.p);
                last.clear();
            }
        }
        let half: Int = &modulus >> 1;
        let sym: Vec<(Exps, Int)> = h
            .iter()
            .map(|(e, c)| {
                let v = if *c > half { c - &modulus } else { c.clone() };
                (e.clone(), v)
            })
            .collect();
        // Try the proof when the image has stopped changing, or at once when
        // every coefficient is small next to the modulus (a wrong image would
        // look uniformly random, so this is rarely wasted).
        let small: Int = &modulus >> 24;
        let stable = sym == last;
        let tiny = !stable && last.is_empty() && sym.iter().all(|(_, c)| c.clone().abs() < small);
        if stable || tiny {
            let cand = back(&sym);
            let cont = cand.content();
            let cand = cand.div_exact(&Poly::constant(cont))?.normalize_sign();
            if a.div_exact(&cand).is_some() && b.div_exact(&cand).is_some() {
                return Some(cand);
            }
            if budget::tripped() {
                return None;
            }
        }
        last = sym;
    }
    None
}

/// Chinese remaindering of residues `h` modulo `m` with an image modulo `p`
/// (monomials missing on either side are zero there).
fn crt(f: Field, h: &[(Exps, Int)], m: &Int, img: &MP) -> Vec<(Exps, Int)> {
    let minv = f.inv(f.reduce(m));
    let lift = |r: &Int, v: u64| -> Int {
        let t = f.mul(f.sub(v, f.reduce(r)), minv);
        r + m * Int::from(t)
    };
    let mut out = Vec::with_capacity(h.len().max(img.len()));
    let (mut i, mut j) = (0, 0);
    while i < h.len() || j < img.len() {
        let ord = match (h.get(i), img.get(j)) {
            (Some(x), Some(y)) => x.0.cmp(&y.0),
            (Some(_), None) => Ordering::Greater,
            _ => Ordering::Less,
        };
        let (e, r, v) = match ord {
            Ordering::Greater => {
                i += 1;
                (h[i - 1].0.clone(), h[i - 1].1.clone(), 0)
            }
            Ordering::Less => {
                j += 1;
                (img[j - 1].0.clone(), int(0), img[j - 1].1)
            }
            Ordering::Equal => {
                i += 1;
                j += 1;
                (h[i - 1].0.clone(), h[i - 1].1.clone(), img[j - 1].1)
            }
        };
        let x = lift(&r, v);
        if !x.is_zero() {
            out.push((e, x));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn primes_are_prime_and_distinct() {
        let ps: Vec<u64> = (0..70).map(prime).collect();
        for w in ps.windows(2) {
            assert!(w[0] > w[1]);
        }
        assert!(ps
            .iter()
            .all(|&p| is_prime(p) && p < 1 << 62 && p > 1 << 61));
        // Known small cases of the test itself.
        assert!(is_prime(2) && is_prime(97) && !is_prime(91) && !is_prime(3215031751));
        // 2^61 - 1 is a Mersenne prime; 2^62 - 1 = 3 * 715827883 * 2147483647.
        assert!(is_prime((1 << 61) - 1) && !is_prime((1 << 62) - 1));
    }

    fn x(v: Var) -> Poly {
        Poly::var(v)
    }

    /// Cofactors that coincide modulo the first (or second) prime: that
    /// prime's image has a larger leading monomial and must be discarded, by
    /// a restart (first prime) or a skip (second prime, after a lucky one).
    #[test]
    fn unlucky_primes_are_detected() {
        for i in [0, 1] {
            let p = Int::from(prime(i));
            let g = x(0).mul(&x(1)).add(&Poly::constant(int(3)));
            let c1 = x(0).add(&x(1)).add(&Poly::constant(p.clone()));
            let c2 = x(0).add(&x(1));
            let (a, b) = (g.mul(&c1), g.mul(&c2));
            assert_eq!(modular_gcd(&a, &b), Some(g.clone()));
            // With coefficients needing several primes, so that the unlucky one
            // meets an existing interpolation.
            let big = Poly::constant(Int::from(1u8) << 300);
            let gb = g.add(&big.mul(&x(1)));
            let (a, b) = (gb.mul(&c1), gb.mul(&c2));
            assert_eq!(modular_gcd(&a, &b), Some(gb.clone()));
            // And coprime inputs whose images modulo p are not coprime.
            assert_eq!(modular_gcd(&c1, &c2), Some(Poly::one()));
        }
    }

    #[test]
    fn field_inverse_and_univariate_gcd() {
        let f = Field { p: prime(0) };
        for a in [1u64, 2, 3, 12345, f.p - 1] {
            assert_eq!(f.mul(a, f.inv(a)), 1);
        }
        // (x + 1)(x + 2) and (x + 1)(x + 3): gcd x + 1.
        let a = uni_mul(f, &[1, 1], &[2, 1]);
        let b = uni_mul(f, &[1, 1], &[3, 1]);
        assert_eq!(uni_gcd(f, &a, &b), vec![1, 1]);
        let (q, r) = uni_divrem(f, &a, &[1, 1]);
        assert_eq!((q, r), (vec![2, 1], vec![]));
    }
}
