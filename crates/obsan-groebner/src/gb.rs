//! Buchberger's algorithm with the sugar strategy (Giovini, Mora, Niesi,
//! Robbiano, Traverso 1991) and the Gebauer–Möller criteria (Gebauer and
//! Möller 1988, in the form of Becker and Weispfenning, "Gröbner Bases",
//! algorithm UPDATE).

use crate::mem::{block, mono_bytes, mono_heap, over};
use crate::poly::{Mono, Order, Poly, Ring};
use crate::GbError;
use std::cmp::Ordering;
use std::collections::BinaryHeap;
use std::mem::size_of;
use std::time::Instant;

/// Limits of one computation: past any of them it stops with an error.
#[derive(Clone, Copy, Debug)]
pub struct GbBudget {
    /// Elements added to the basis (before interreduction).
    pub max_basis: usize,
    /// Terms of one polynomial.
    pub max_terms: usize,
    /// S-polynomials reduced.
    pub max_pairs: usize,
    /// Bytes held at once (the basis, its pairs, a reduction, an F4
    /// matrix, the counts' dense matrices; `mem.rs` says how they are
    /// counted), refused before an allocation would pass it. `usize::MAX`
    /// (the default): no bound but the others.
    pub max_bytes: usize,
    /// Multiply-adds of F4's eliminations, all matrices together, plus the
    /// product monomials and divisibility tests of its symbolic
    /// preprocessing (one unit each: on cLV2's Taylor system they were most
    /// of the time, 450 ns per multiply-add counted alone): a
    /// deterministic measure of time (`GbError::Budget("work")` past it), for
    /// a first attempt that should give way to another method rather than
    /// grind. `u64::MAX` (the default): no bound.
    pub max_work: u64,
    pub deadline: Option<Instant>,
}

impl Default for GbBudget {
    fn default() -> Self {
        GbBudget {
            max_basis: 20_000,
            max_terms: 2_000_000,
            max_pairs: 2_000_000,
            max_bytes: usize::MAX,
            max_work: u64::MAX,
            deadline: None,
        }
    }
}

/// A reduced Gröbner basis (monic, sorted by leading monomial, smallest first).
#[derive(Clone, Debug)]
pub struct Basis {
    pub ring: Ring,
    pub polys: Vec<Poly>,
    /// The memory budget of the computation, kept for the counts made on
    /// the basis (normal forms, the quotient's dense matrices).
    pub max_bytes: usize,
}

pub(crate) struct Pair {
    pub(crate) i: usize,
    pub(crate) j: usize,
    pub(crate) lcm: Mono,
    /// `lcm.mask()`: screens the divisibility tests of the update.
    pub(crate) mask: u64,
    pub(crate) sugar: u32,
}

/// The state shared by Buchberger's algorithm and F4 (`f4.rs`): the
/// basis so far, its critical pairs, the limits.
pub(crate) struct Work<'a> {
    pub(crate) ring: &'a Ring,
    pub(crate) polys: Vec<Poly>,
    pub(crate) sugar: Vec<u32>,
    /// Leading monomials of `polys` and their masks ([`Mono::mask`]).
    pub(crate) lm: Vec<Mono>,
    pub(crate) masks: Vec<u64>,
    /// Members of the current basis (not superseded by a later element).
    pub(crate) active: Vec<bool>,
    pub(crate) pairs: Vec<Pair>,
    pub(crate) budget: GbBudget,
    /// Bytes held by the elements (`polys` and the per-element vectors);
    /// the pairs are counted by [`Work::held`].
    pub(crate) elem_bytes: usize,
}

/// Bytes of one critical pair in `n` variables (its lcm's exponents too).
pub(crate) fn pair_bytes(n: usize) -> usize {
    size_of::<Pair>() + mono_heap(n)
}

/// Bytes of one basis element's slots beside its polynomial: its `Poly`
/// value, sugar, leading monomial, mask and active flag.
pub(crate) fn elem_slot_bytes(n: usize) -> usize {
    size_of::<Poly>() + size_of::<u32>() + mono_bytes(n) + size_of::<u64>() + 1
}

impl Work<'_> {
    /// Bytes held by the basis and its pairs.
    pub(crate) fn held(&self) -> usize {
        self.elem_bytes + self.pairs.len() * pair_bytes(self.ring.n)
    }

    /// The budget left beside what the basis holds.
    pub(crate) fn bytes_left(&self) -> usize {
        self.budget.max_bytes.saturating_sub(self.held())
    }

    pub(crate) fn check(&self, p: &Poly) -> Result<(), GbError> {
        if p.len() > self.budget.max_terms {
            return Err(GbError::Budget("terms of a polynomial"));
        }
        if let Some(d) = self.budget.deadline {
            if Instant::now() > d {
                return Err(GbError::Budget("deadline"));
            }
        }
        Ok(())
    }

    /// An active element whose leading monomial divides `m`.
    fn reducer(&self, m: &Mono) -> Option<usize> {
        let mm = m.mask();
        (0..self.polys.len())
            .find(|&k| self.active[k] && self.masks[k] & !mm == 0 && self.lm[k].divides(m))
    }

    /// Full reduction of `f` by the active elements.
    pub(crate) fn reduce(&self, f: Poly) -> Result<Poly, GbError> {
        reduce_by(
            self.ring,
            f.terms,
            &self.polys,
            |m| self.reducer(m),
            self.budget.max_terms,
            self.bytes_left(),
            self.budget.deadline,
        )
    }

    /// `f` less multiples of the active elements until no leading monomial
    /// of theirs divides its own (the elements are monic).
    fn reduce_lead(&self, mut f: Poly) -> Result<Poly, GbError> {
        let r = self.ring;
        while let Some((m, c)) = f.terms.first() {
            let Some(k) = self.reducer(m) else { break };
            let q = self.lm[k].quotient(m);
            let c = r.field.neg(*c);
            f = r.axpy(&f, c, &q, &self.polys[k])?;
            self.check(&f)?;
        }
        Ok(f)
    }

    fn spoly(&self, p: &Pair) -> Result<Poly, GbError> {
        let r = self.ring;
        let a = &self.polys[p.i];
        let b = &self.polys[p.j];
        let ma = self.lm[p.i].quotient(&p.lcm);
        let mb = self.lm[p.j].quotient(&p.lcm);
        let t = r.axpy(&Poly::zero(), 1, &ma, a)?;
        r.axpy(&t, r.field.neg(1), &mb, b)
    }

    /// Adds a monic `h` with its sugar: Gebauer–Möller UPDATE.
    pub(crate) fn update(&mut self, h: Poly, sugar: u32) -> Result<(), GbError> {
        if self.polys.len() >= self.budget.max_basis {
            return Err(GbError::Budget("basis size"));
        }
        let hi = self.polys.len();
        let lh = match h.leading() {
            Some((m, _)) => m.clone(),
            None => return Ok(()),
        };
        // At most one new pair per active element, held beside the old
        // pairs until criterion B has run, and the new element itself.
        let n = self.ring.n;
        let grow = h.stored_bytes(n) + elem_slot_bytes(n);
        let need = self.held() + grow + 2 * hi * pair_bytes(n);
        if need > self.budget.max_bytes {
            return Err(over(need, self.budget.max_bytes, || {
                format!(
                    "the Groebner basis ({} elements, {} critical pairs, {} variables)",
                    hi + 1,
                    self.pairs.len() + hi,
                    n
                )
            }));
        }
        // New pairs (h, g) for active g.
        let mut c: Vec<Pair> = Vec::with_capacity(hi);
        for g in 0..hi {
            if !self.active[g] {
                continue;
            }
            let lcm = lh.lcm(&self.lm[g]);
            let s = (sugar + lcm.degree() - lh.degree())
                .max(self.sugar[g] + lcm.degree() - self.lm[g].degree());
            c.push(Pair {
                i: g,
                j: hi,
                mask: lcm.mask(),
                lcm,
                sugar: s,
            });
        }
        // Criterion M/F: drop (h, g) if another new pair's lcm divides its lcm
        // (keeping coprime ones for the product criterion below); a
        // divisor-mask test (a necessary condition) screens each comparison
        // before `divides`. By ascending lcm degree, a pair is compared only with the pairs
        // kept before it: a divisor has no larger degree, and a dropped
        // divisor's own kept divisor divides too (divisibility is transitive),
        // so the minimal lcms survive, one pair each, as before; the kept set
        // is far smaller than all pairs (Fujita: this loop was 36% of the run).
        c.sort_by_key(|p| p.lcm.degree());
        let mut d: Vec<Pair> = Vec::new();
        for p in c {
            let coprime = lh.coprime(&self.lm[p.i]);
            let dominated = d
                .iter()
                .any(|q| q.mask & !p.mask == 0 && q.lcm.divides(&p.lcm));
            if coprime || !dominated {
                d.push(p);
            }
        }
        // Criterion B on old pairs (the lcm tests build no monomial).
        let hm = lh.mask();
        let old = std::mem::take(&mut self.pairs);
        for p in old {
            let dropped = hm & !p.mask == 0
                && lh.divides(&p.lcm)
                && !lh.lcm_is(&self.lm[p.i], &p.lcm)
                && !lh.lcm_is(&self.lm[p.j], &p.lcm);
            if !dropped {
                self.pairs.push(p);
            }
        }
        // Product criterion: coprime leading monomials reduce to zero.
        for p in d {
            if !lh.coprime(&self.lm[p.i]) {
                self.pairs.push(p);
            }
        }
        for g in 0..hi {
            if self.active[g] && lh.divides(&self.lm[g]) {
                self.active[g] = false;
            }
        }
        self.polys.push(h);
        self.sugar.push(sugar);
        self.masks.push(lh.mask());
        self.lm.push(lh);
        self.active.push(true);
        self.elem_bytes += grow;
        Ok(())
    }
}

impl<'a> Work<'a> {
    /// A pair-free work holding the monic `polys` with their sugars, all
    /// active: F4 (`f4.rs`) hands its final elements to [`finish`] so. The
    /// caller has counted their bytes ([`poly_bytes`](crate::mem::poly_bytes)).
    pub(crate) fn assembled(
        ring: &'a Ring,
        budget: GbBudget,
        polys: Vec<Poly>,
        sugar: Vec<u32>,
    ) -> Work<'a> {
        let n = ring.n;
        let lm: Vec<Mono> = polys.iter().map(|p| p.terms[0].0.clone()).collect();
        let elem_bytes = polys
            .iter()
            .map(|p| p.stored_bytes(n) + elem_slot_bytes(n))
            .sum();
        Work {
            ring,
            masks: lm.iter().map(Mono::mask).collect(),
            lm,
            active: vec![true; polys.len()],
            polys,
            sugar,
            pairs: Vec::new(),
            budget,
            elem_bytes,
        }
    }
}

/// How [`start`] reduces each generator by those before it.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(crate) enum Enter {
    /// Every term (Buchberger's algorithm reduces S-polynomials against a
    /// basis whose tails it keeps reduced).
    Full,
    /// The leading term only, until no leading monomial before divides it:
    /// enough for F4, whose matrices reduce the tails, and for the
    /// reduced basis [`finish`] builds. Under an elimination order the full
    /// reduction of the tails was the whole time: TumorHu's input-output
    /// elimination ran past 300 s in it, a microsecond per heap pop.
    Lead,
}

/// The generators entered into a fresh [`Work`] (smallest leading monomial
/// first, each reduced by those before as `enter` says), or the unit
/// ideal's basis.
pub(crate) fn start<'a>(
    ring: &'a Ring,
    gens: &[Poly],
    budget: GbBudget,
    enter: Enter,
) -> Result<Result<Work<'a>, Basis>, GbError> {
    let mut w = Work {
        ring,
        polys: Vec::new(),
        sugar: Vec::new(),
        lm: Vec::new(),
        masks: Vec::new(),
        active: Vec::new(),
        pairs: Vec::new(),
        budget,
        elem_bytes: 0,
    };
    let mut g: Vec<Poly> = gens
        .iter()
        .map(|p| ring.resort(p))
        .filter(|p| !p.is_zero())
        .collect();
    g.sort_by(|a, b| ring.order.cmp(&a.terms[0].0, &b.terms[0].0));
    for p in g {
        let s = p.degree();
        let h = match enter {
            Enter::Full => w.reduce(p)?,
            Enter::Lead => w.reduce_lead(p)?,
        };
        if !h.is_zero() {
            let h = ring.monic(&h);
            if h.terms[0].0.is_one() {
                return Ok(Err(unit(ring, budget.max_bytes)));
            }
            w.update(h, s)?;
        }
    }
    Ok(Ok(w))
}

/// The reduced Gröbner basis of the ideal generated by `gens` in `ring`, by
/// Buchberger's algorithm (normal strategy with sugar).
pub fn buchberger(ring: &Ring, gens: &[Poly], budget: GbBudget) -> Result<Basis, GbError> {
    let mut w = match start(ring, gens, budget, Enter::Full)? {
        Ok(w) => w,
        Err(unit) => return Ok(unit),
    };
    let mut reduced = 0usize;
    while !w.pairs.is_empty() {
        // Normal strategy with sugar: smallest sugar, then smallest lcm.
        let mut best = 0;
        for k in 1..w.pairs.len() {
            let (a, b) = (&w.pairs[k], &w.pairs[best]);
            let o = a
                .sugar
                .cmp(&b.sugar)
                .then_with(|| ring.order.cmp(&a.lcm, &b.lcm));
            if o == Ordering::Less {
                best = k;
            }
        }
        let p = w.pairs.swap_remove(best);
        reduced += 1;
        if reduced > budget.max_pairs {
            return Err(GbError::Budget("pairs reduced"));
        }
        let s = w.spoly(&p)?;
        w.check(&s)?;
        let h = w.reduce(s)?;
        if h.is_zero() {
            continue;
        }
        let h = ring.monic(&h);
        if h.terms[0].0.is_one() {
            return Ok(unit(ring, budget.max_bytes));
        }
        w.update(h, p.sugar)?;
    }
    finish(&w)
}

/// The reduced basis of a completed [`Work`]: the minimal leading monomials,
/// tails fully reduced.
pub(crate) fn finish(w: &Work) -> Result<Basis, GbError> {
    let ring = w.ring;
    let mut keep: Vec<usize> = (0..w.polys.len()).filter(|&k| w.active[k]).collect();
    keep.sort_by(|&a, &b| ring.order.cmp(&w.lm[a], &w.lm[b]));
    let mut out: Vec<Poly> = Vec::with_capacity(keep.len());
    // The reduced basis is built beside the work's.
    let mut out_bytes = block(keep.len() * size_of::<Poly>());
    for &k in &keep {
        let (m, c) = w.polys[k].terms[0].clone();
        let tail = Poly {
            terms: w.polys[k].terms[1..].to_vec(),
        };
        let mut t = reduce_by(
            ring,
            tail.terms,
            &w.polys,
            |m| w.reducer(m),
            w.budget.max_terms,
            w.bytes_left().saturating_sub(out_bytes),
            w.budget.deadline,
        )?;
        t.terms.insert(0, (m, c));
        t.terms.shrink_to_fit();
        out_bytes += t.stored_bytes(ring.n);
        let need = w.held() + out_bytes;
        if need > w.budget.max_bytes {
            return Err(over(need, w.budget.max_bytes, || {
                format!(
                    "the Groebner basis (its reduced form, {} of {} elements)",
                    out.len() + 1,
                    keep.len()
                )
            }));
        }
        out.push(t);
    }
    Ok(Basis {
        ring: ring.clone(),
        polys: out,
        max_bytes: w.budget.max_bytes,
    })
}

/// One term of the heap of [`reduce_by`]: the next term of stream `s`.
struct Head {
    mono: Mono,
    coef: u64,
    s: usize,
    order: Order,
}

impl PartialEq for Head {
    fn eq(&self, o: &Self) -> bool {
        self.cmp(o) == Ordering::Equal
    }
}
impl Eq for Head {}
impl PartialOrd for Head {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Head {
    fn cmp(&self, o: &Self) -> Ordering {
        self.order
            .cmp(&self.mono, &o.mono)
            .then_with(|| self.s.cmp(&o.s))
    }
}

/// A summand of the polynomial being reduced: `c * q * terms[pos..]` of
/// `src` (`None`: the input itself).
struct Stream {
    c: u64,
    q: Mono,
    src: Option<usize>,
    pos: usize,
}

/// Full reduction of `f` by the monic `polys` (`find` names a reducer of a
/// monomial): the pending polynomial is kept as a sum of streams merged by a
/// heap (Johnson; Monagan and Pearce, "Sparse polynomial division using a
/// heap", 2011), so each step costs a logarithm, not a pass over the rest.
/// The streams, their heads and the remainder may hold `max_bytes`.
pub(crate) fn reduce_by(
    ring: &Ring,
    f: Vec<(Mono, u64)>,
    polys: &[Poly],
    find: impl Fn(&Mono) -> Option<usize>,
    max_terms: usize,
    max_bytes: usize,
    deadline: Option<Instant>,
) -> Result<Poly, GbError> {
    let fld = ring.field;
    let order = ring.order;
    // A stream holds its multiplier, the heap its next term; a remainder
    // term its monomial (the remainder's buffer grows by doubling: 2x).
    let per_stream = size_of::<Stream>() + size_of::<Head>() + 2 * mono_heap(ring.n);
    let per_done = 2 * std::mem::size_of::<(Mono, u64)>() + mono_heap(ring.n);
    let held = |streams: usize, done: usize| streams * per_stream + done * per_done;
    let too_big = |streams: usize, done: usize| {
        over(held(streams, done), max_bytes, || {
            format!(
                "the Groebner basis (a reduction of {streams} multiples into {done} remainder terms)"
            )
        })
    };
    let mut streams: Vec<Stream> = vec![Stream {
        c: 1,
        q: Mono::one(ring.n),
        src: None,
        pos: 0,
    }];
    let mut heap: BinaryHeap<Head> = BinaryHeap::new();
    let next = |st: &mut Stream, s: usize, f: &[(Mono, u64)]| -> Result<Option<Head>, GbError> {
        let terms: &[(Mono, u64)] = match st.src {
            None => f,
            Some(k) => &polys[k].terms,
        };
        let Some((m, c)) = terms.get(st.pos) else {
            return Ok(None);
        };
        st.pos += 1;
        let mono = if st.src.is_none() {
            m.clone()
        } else {
            st.q.mul(m)?
        };
        Ok(Some(Head {
            mono,
            coef: fld.mul(st.c, *c),
            s,
            order,
        }))
    };
    if let Some(h) = next(&mut streams[0], 0, &f)? {
        heap.push(h);
    }
    let mut done: Vec<(Mono, u64)> = Vec::new();
    let mut steps = 0usize;
    while let Some(top) = heap.pop() {
        let mono = top.mono;
        let mut coef = top.coef;
        if let Some(h) = next(&mut streams[top.s], top.s, &f)? {
            heap.push(h);
        }
        while heap.peek().is_some_and(|h| h.mono == mono) {
            if let Some(h) = heap.pop() {
                coef = fld.add(coef, h.coef);
                if let Some(n) = next(&mut streams[h.s], h.s, &f)? {
                    heap.push(n);
                }
            }
        }
        if coef == 0 {
            continue;
        }
        match find(&mono) {
            Some(k) => {
                // the reducer is monic: its leading term cancels this one
                let q = polys[k].terms[0].0.quotient(&mono);
                let s = streams.len();
                streams.push(Stream {
                    c: fld.neg(coef),
                    q,
                    src: Some(k),
                    pos: 1,
                });
                if let Some(h) = next(&mut streams[s], s, &f)? {
                    heap.push(h);
                }
                steps += 1;
                if streams.len() > max_terms {
                    return Err(GbError::Budget("terms of a polynomial"));
                }
                if held(streams.len(), done.len()) > max_bytes {
                    return Err(too_big(streams.len(), done.len()));
                }
                if steps.is_multiple_of(1024) {
                    if let Some(d) = deadline {
                        if Instant::now() > d {
                            return Err(GbError::Budget("deadline"));
                        }
                    }
                }
            }
            None => {
                if held(streams.len(), done.len() + 1) > max_bytes {
                    return Err(too_big(streams.len(), done.len() + 1));
                }
                done.push((mono, coef));
                if done.len() > max_terms {
                    return Err(GbError::Budget("terms of a polynomial"));
                }
            }
        }
    }
    Ok(Poly { terms: done })
}

pub(crate) fn unit(ring: &Ring, max_bytes: usize) -> Basis {
    Basis {
        ring: ring.clone(),
        polys: vec![ring.constant(1)],
        max_bytes,
    }
}

impl Basis {
    /// Whether the ideal is the whole ring (no common zero).
    pub fn is_unit(&self) -> bool {
        self.polys.len() == 1 && self.polys[0].terms[0].0.is_one()
    }

    /// The normal form of `f` (its remainder on division by the basis).
    pub fn reduce(&self, f: &Poly) -> Result<Poly, GbError> {
        let masks: Vec<u64> = self.polys.iter().map(|g| g.terms[0].0.mask()).collect();
        reduce_by(
            &self.ring,
            self.ring.resort(f).terms,
            &self.polys,
            |m| {
                let mm = m.mask();
                (0..self.polys.len())
                    .find(|&k| masks[k] & !mm == 0 && self.polys[k].terms[0].0.divides(m))
            },
            usize::MAX,
            self.max_bytes,
            None,
        )
    }

    pub fn contains(&self, f: &Poly) -> Result<bool, GbError> {
        Ok(self.reduce(f)?.is_zero())
    }

    pub fn leading_monomials(&self) -> Vec<&Mono> {
        self.polys.iter().map(|p| &p.terms[0].0).collect()
    }
}
