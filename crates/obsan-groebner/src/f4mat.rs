//! One F4 matrix: symbolic preprocessing adds, for every monomial of the
//! matrix divisible by a leading monomial of the basis, one multiple of that
//! element as a pivot row; Gaussian elimination of the S-polynomial rows by
//! the pivots (and by each other) leaves rows whose leading monomials are
//! new.
//!
//! The columns are the ids of a table of this matrix's own (`sym`); a row
//! `mult * g` is its column ids only, its coefficients are g's (a basis
//! element is monic, so is every multiple). The new rows' monomials enter
//! the basis table at the end.

use crate::f4state::{Elem, Pair, St};
use crate::mem::{block, over};
use crate::table::{Scratch, Table};
use crate::GbError;
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};
use std::mem::size_of;
use std::time::Instant;

/// The multiplicative hash of rustc (FxHash), for the (element, lcm) keys
/// of the rows entered (ids the program made, no flood to resist).
#[derive(Default)]
struct Fx(u64);

impl Hasher for Fx {
    fn write(&mut self, bytes: &[u8]) {
        for ch in bytes.chunks(8) {
            let mut w = [0u8; 8];
            w[..ch.len()].copy_from_slice(ch);
            self.write_u64(u64::from_le_bytes(w));
        }
    }
    fn write_u32(&mut self, x: u32) {
        self.write_u64(x as u64);
    }
    fn write_u64(&mut self, x: u64) {
        self.0 = (self.0.rotate_left(5) ^ x).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
    fn write_usize(&mut self, x: usize) {
        self.write_u64(x as u64);
    }
    fn finish(&self) -> u64 {
        self.0
    }
}

type FxMap<K, V> = HashMap<K, V, BuildHasherDefault<Fx>>;

const NONE: u32 = u32::MAX;

/// A row `mult * g_poly`: column ids (symbolic ids, then ranks).
struct Row {
    cols: Vec<u32>,
    poly: u32,
}

/// Bytes of one column beside its table entry, from symbolic preprocessing
/// to the end of the elimination: its pivot slot, `by_order`, `rank`, the
/// elimination's pivot slot, the u128 accumulator and a bit of `nz`.
fn col_bytes() -> usize {
    4 + 4 + 4 + 4 + 16 + 1
}

/// Bytes of one row of `len` entries: its column ids (its coefficients are
/// its basis element's).
fn row_bytes(len: usize) -> usize {
    size_of::<Row>() + block(4 * len)
}

/// Bytes of one entry of a new (reduced) row: the transient result, its
/// pivot copy (id and coefficient), its basis-table id.
fn new_entry_bytes() -> usize {
    size_of::<(u32, u64)>() + 4 + 8 + 4
}

/// Symbolic preprocessing's state.
struct Sym<'s, 'a> {
    s: &'s St<'a>,
    sym: Table,
    pivot: Vec<u32>,
    rows: Vec<Row>,
    act: Vec<usize>,
    /// Bytes of the matrix beside its table, and the basis's.
    bytes: usize,
    base: usize,
    prod: Scratch,
}

impl Sym<'_, '_> {
    fn what(&self) -> String {
        format!(
            "the Groebner basis (F4 matrix of {} rows x {} columns)",
            self.rows.len(),
            self.sym.len()
        )
    }

    fn grow(&mut self, extra: usize) -> Result<(), GbError> {
        let need = self.base + self.bytes + self.sym.bytes() + extra;
        let max = self.s.budget.max_bytes;
        if need > max {
            return Err(over(need, max, || self.what()));
        }
        self.bytes += extra;
        Ok(())
    }

    /// Adds the row `q * g_k`; returns its index.
    fn add_row(&mut self, q: &Scratch, k: usize) -> Result<usize, GbError> {
        let s = self.s;
        let g = &s.el[k];
        self.grow(row_bytes(g.ids.len()))?;
        // Each product monomial is one unit of work (its exponents, hash
        // and table lookup cost about a multiply-add's share of time).
        s.work.set(s.work.get() + g.ids.len() as u64);
        let mut cols = Vec::with_capacity(g.ids.len());
        for &id in &g.ids {
            s.t.mul(q, id, &mut self.prod)?;
            let before = self.sym.len();
            let max = s.budget.max_bytes;
            let used = self.base + self.bytes + self.sym.bytes() + col_bytes();
            let (r, c) = (self.rows.len(), before);
            let col = self
                .sym
                .insert(&self.prod.e, self.prod.deg, self.prod.hash, |g| {
                    if used + g > max {
                        return Err(over(used + g, max, || {
                            format!("the Groebner basis (F4 matrix of {r} rows x {c} columns)")
                        }));
                    }
                    Ok(())
                })?;
            if self.sym.len() > before {
                if before >= s.budget.max_terms {
                    return Err(GbError::Budget("columns of the F4 matrix"));
                }
                self.grow(col_bytes())?;
                self.pivot.push(NONE);
            }
            cols.push(col);
        }
        self.rows.push(Row {
            cols,
            poly: k as u32,
        });
        Ok(self.rows.len() - 1)
    }

    /// The active basis element with the fewest terms whose leading monomial
    /// divides column `c`.
    fn reducer(&self, c: u32) -> Option<usize> {
        let s = self.s;
        // One unit of work per divisibility test.
        s.work.set(s.work.get() + self.act.len() as u64);
        self.act
            .iter()
            .copied()
            .filter(|&k| s.t.divides(s.el[k].ids[0], &self.sym, c))
            .min_by_key(|&k| s.el[k].ids.len())
    }
}

/// Reduces the S-polynomials of `sel` together; returns the new basis
/// elements (monic, in the basis table, largest leading monomial first),
/// whose leading monomials no active leading monomial divides.
pub(crate) fn reduce_pairs(st: &mut St, sel: &[Pair]) -> Result<Vec<Elem>, GbError> {
    let s: &St = st;
    let mut m = Sym {
        s,
        sym: Table::new(s.ring.n, s.t.weights().to_vec()),
        pivot: Vec::new(),
        rows: Vec::new(),
        act: (0..s.el.len()).filter(|&k| s.active[k]).collect(),
        bytes: 0,
        base: s.held(),
        prod: Scratch::new(),
    };
    let mut q = Scratch::new();
    // Each pair gives two multiples with the same leading monomial (its lcm):
    // one becomes the pivot of that column (if none is yet), the other a row
    // to reduce. A multiple met twice is entered once.
    let mut seen: FxMap<(u32, u32), ()> = FxMap::default();
    let mut todo: Vec<usize> = Vec::new();
    for p in sel {
        for k in [p.i, p.j] {
            if seen.contains_key(&(k, p.lcm)) {
                continue;
            }
            m.grow((size_of::<(u32, u32)>() + 1) * 8 / 7)?;
            seen.insert((k, p.lcm), ());
            s.t.quotient(s.el[k as usize].ids[0], &s.t, p.lcm, &mut q);
            let r = m.add_row(&q, k as usize)?;
            let lead = m.rows[r].cols[0] as usize;
            if m.pivot[lead] == NONE {
                m.pivot[lead] = r as u32;
            } else {
                todo.push(r);
            }
        }
    }
    // Symbolic preprocessing: a pivot for every reducible column (columns
    // are appended while this runs).
    let mut c = 0usize;
    while c < m.sym.len() {
        if c.is_multiple_of(256) {
            deadline(s)?;
            over_work(s)?;
        }
        if m.pivot[c] == NONE {
            if let Some(k) = m.reducer(c as u32) {
                s.t.quotient(s.el[k].ids[0], &m.sym, c as u32, &mut q);
                let r = m.add_row(&q, k)?;
                m.pivot[c] = r as u32;
            }
        }
        c += 1;
    }
    let (rows, bytes) = eliminate(&mut m, &todo)?;
    let Sym { sym, .. } = m;
    // The new rows' monomials enter the basis table.
    let mut out = Vec::with_capacity(rows.len());
    let matrix = bytes + sym.bytes();
    for (ids, cfs) in rows {
        let mut bids = Vec::with_capacity(ids.len());
        for &c in &ids {
            let e = sym.exps(c);
            let used = st.held() + matrix;
            let max = st.budget.max_bytes;
            bids.push(st.t.insert(e, sym.deg(c), sym.hash(c), |g| {
                if used + g > max {
                    return Err(over(used + g, max, || {
                        "the Groebner basis (the basis table)".to_string()
                    }));
                }
                Ok(())
            })?);
        }
        out.push(Elem { ids: bids, cfs });
    }
    Ok(out)
}

/// Past `GbBudget::max_work` (checked between blocks of work).
fn over_work(s: &St) -> Result<(), GbError> {
    if s.work.get() > s.budget.max_work {
        return Err(GbError::Budget(WORK));
    }
    Ok(())
}

/// The work bound's name in its error (callers match on it, and charge
/// their own work against the same bound under it).
pub const WORK: &str = "work (multiply-adds of the F4 eliminations)";

fn deadline(s: &St) -> Result<(), GbError> {
    if let Some(d) = s.budget.deadline {
        if Instant::now() > d {
            return Err(GbError::Budget("deadline"));
        }
    }
    Ok(())
}

/// Gaussian elimination of the rows `todo` by the pivots, left to right on a
/// dense accumulator; each non-zero result becomes a pivot for the rows after
/// it. Returns the new rows (symbolic column ids and monic coefficients,
/// largest leading monomial first) and the matrix's bytes beside its table.
/// Not obsan-recon's dense `fp::Echelon`: Macaulay rows are sparse over
/// 10^4-10^5 columns and only the new pivots are wanted, so rows are kept
/// sparse and reduced with delayed modular folding (below).
#[allow(clippy::type_complexity)]
fn eliminate(m: &mut Sym, todo: &[usize]) -> Result<(Vec<(Vec<u32>, Vec<u64>)>, usize), GbError> {
    let s = m.s;
    let fld = s.ring.field;
    let p = fld.modulus();
    let order = s.ring.order;
    let ncols = m.sym.len();
    // Columns sorted largest monomial first; rows keep their order (a
    // monomial order is compatible with multiplication).
    let mut by_order: Vec<u32> = (0..ncols as u32).collect();
    by_order.sort_by(|&a, &b| m.sym.cmp(order, b, a));
    let mut rank = vec![0u32; ncols];
    for (i, &c) in by_order.iter().enumerate() {
        rank[c as usize] = i as u32;
    }
    for r in &mut m.rows {
        for c in &mut r.cols {
            *c = rank[*c as usize];
        }
    }
    let nrows = m.rows.len() as u32;
    // The pivot of each rank: a matrix row (< nrows) or a new row.
    let mut piv: Vec<u32> = vec![NONE; ncols];
    for (c, &r) in m.pivot.iter().enumerate() {
        if r != NONE {
            piv[rank[c] as usize] = r;
        }
    }
    let rows = &m.rows;
    let el = &s.el;
    // Delayed reduction: products of residues below p < 2^63 stay below
    // 2^126, so the accumulator is a u128 reduced modulo p only when it
    // passes 2^127 (before two more products could overflow it) and once
    // when its column is read: one remainder per non-zero column instead of
    // one per product, each by Shoup's products (`Rem128`), not a 128-bit
    // division (`__umodti3`, 3% of HIV's time).
    const FOLD: u128 = 1 << 127;
    let rem = obsan_recon::fp::Rem128::new(p);
    let mut acc = vec![0u128; ncols];
    // Bit c of `nz` is set when acc[c] may be non-zero: the scan jumps
    // between set bits instead of reading every column right of the lead
    // (rows are short against the 10^4-10^5 columns of a large matrix).
    let mut nz = vec![0u64; ncols.div_ceil(64)];
    let mut out: Vec<(Vec<u32>, Vec<u64>)> = Vec::new();
    let mut new_bytes = 0usize;
    let mut work = s.work.get();
    for (n, &t) in todo.iter().enumerate() {
        if n % 64 == 0 {
            deadline(s)?;
            s.work.set(work);
            if work > s.budget.max_work {
                return Err(GbError::Budget(WORK));
            }
        }
        let row = &rows[t];
        for (&c, &v) in row.cols.iter().zip(&el[row.poly as usize].cfs) {
            acc[c as usize] = v as u128;
            nz[c as usize / 64] |= 1 << (c % 64);
        }
        let mut res: Vec<(u32, u64)> = Vec::new();
        let mut wi = row.cols[0] as usize / 64;
        while wi < nz.len() {
            let word = nz[wi];
            if word == 0 {
                wi += 1;
                continue;
            }
            // Pivot rows only reach columns right of their lead, so bits
            // set while column c is cleared lie ahead of the scan.
            let b = word.trailing_zeros() as usize;
            nz[wi] &= !(1u64 << b);
            let c = wi * 64 + b;
            let a = rem.reduce(acc[c]);
            acc[c] = 0;
            if a == 0 {
                continue;
            }
            let pr = piv[c];
            if pr == NONE {
                res.push((c as u32, a));
                continue;
            }
            let (pc, pv): (&[u32], &[u64]) = if pr < nrows {
                let r = &rows[pr as usize];
                (&r.cols, &el[r.poly as usize].cfs)
            } else {
                let (c, v) = &out[(pr - nrows) as usize];
                (c, v)
            };
            // Pivots are monic: adding (p - a) * pivot clears column c.
            let mul = (p - a) as u128;
            work += pc.len() as u64;
            for (&x, &y) in pc[1..].iter().zip(&pv[1..]) {
                nz[x as usize / 64] |= 1 << (x % 64);
                let e = &mut acc[x as usize];
                *e += mul * y as u128;
                if *e >= FOLD {
                    *e = u128::from(rem.reduce(*e));
                }
            }
        }
        let Some(&(lead, lc)) = res.first() else {
            continue;
        };
        new_bytes += res.len() * new_entry_bytes();
        let need = m.base + m.bytes + m.sym.bytes() + new_bytes;
        if need > s.budget.max_bytes {
            let (r, c) = (m.rows.len(), ncols);
            return Err(over(need, s.budget.max_bytes, || {
                format!(
                    "the Groebner basis (F4 matrix of {r} rows x {c} columns, {} new rows)",
                    out.len() + 1
                )
            }));
        }
        let inv = fld.inv(lc).ok_or(GbError::Budget("zero pivot"))?;
        let pc: Vec<u32> = res.iter().map(|t| t.0).collect();
        let pv: Vec<u64> = res.iter().map(|t| fld.mul(t.1, inv)).collect();
        piv[lead as usize] = nrows + out.len() as u32;
        out.push((pc, pv));
    }
    s.work.set(work);
    // Largest leading monomial (smallest rank) first, in symbolic ids.
    out.sort_by_key(|(c, _)| c[0]);
    for (c, _) in &mut out {
        for x in c.iter_mut() {
            *x = by_order[*x as usize];
        }
    }
    let bytes = m.bytes + new_bytes;
    Ok((out, bytes))
}
