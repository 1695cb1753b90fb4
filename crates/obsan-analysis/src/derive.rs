//! Observable modes and the reduced system, derived (Martinelli 2011, eqs.
//! 9–11; the paper's hand derivations 21 → 22 and 23 → 24).
//!
//! Modes are searched from the simplest kind up, each candidate accepted only
//! when its gradient raises the rank at a random point (a non-zero minor:
//! exact) and it satisfies the PDE (11) for every symmetry *exactly*
//! ([`check_modes`]):
//! 1. single variables every symmetry leaves alone, as themselves;
//! 2. integer combinations of angle variables (translations, e.g. thetaR - phiR);
//! 3. polynomial and rational invariants `P/Q` by an ansatz: for a fixed
//!    denominator `Q` (1, then the factors the outputs and first Lie
//!    derivatives show) the PDE `Q w(P) - P w(Q) = 0` is linear in the
//!    coefficients of `P`; solved in F_p at random points, coefficients lifted
//!    to Q by rational reconstruction (then checked exactly);
//! 4. the outputs themselves (an `atan2` output is the angle-valued mode the
//!    paper calls L up to the observable A);
//! 5. the basis Lie derivatives of the rank test.
//!
//! The reduced dynamics `L_f g_k` and each output are then sought as `P(z)/Q(z)`
//! in the modes (and cos/sin of the angle-valued ones) by the same linear
//! ansatz, lifted, and proven by exact substitution in canonical form.

use crate::decomp::{verify_decomposition_with, Check, Decomposition};
use crate::modes::{check_modes, ModeReport};
use crate::rank::{AnalysisError, RankReport};
use crate::symmetry::SymmetryReport;
use obsan_expr::{Fp, FpPoint, Id, Int, Mono, Poly, RatFun, SplitMix, P, Q};
use obsan_model::NormalForm;
use std::time::Instant;

/// Largest linear system of an ansatz (unknown coefficients).
const MAX_UNKNOWNS: usize = 500;

/// Budgets of the search.
#[derive(Clone, Debug)]
pub struct DeriveOptions {
    pub seed: u64,
    pub deadline: Option<Instant>,
    /// Highest total degree of the numerator `P` of an invariant ansatz.
    pub max_mode_degree: usize,
    /// Highest total degree of `P` and `Q` when writing a derivative in the modes.
    pub max_closure_degree: usize,
}

impl Default for DeriveOptions {
    fn default() -> Self {
        DeriveOptions {
            seed: 1,
            deadline: None,
            max_mode_degree: 3,
            max_closure_degree: 6,
        }
    }
}

/// How a mode was found (and so how simple it is).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ModeKind {
    Variable,
    Translation,
    Polynomial,
    Rational,
    Output,
    LieDerivative,
}

impl ModeKind {
    pub fn word(self) -> &'static str {
        match self {
            ModeKind::Variable => "variable",
            ModeKind::Translation => "angle difference",
            ModeKind::Polynomial => "polynomial",
            ModeKind::Rational => "rational",
            ModeKind::Output => "output",
            ModeKind::LieDerivative => "Lie derivative",
        }
    }
}

/// One derived observable mode.
#[derive(Clone, Debug)]
pub struct DerivedMode {
    pub name: String,
    pub expr: Id,
    /// The formula in obsan's plain-text syntax (parses back).
    pub text: String,
    pub kind: ModeKind,
    /// An angle (defined modulo 2 pi): the reduced system uses its cos and sin.
    pub angle: bool,
    /// Where the formula holds and which branch it takes.
    pub domain: String,
}

/// The modes and the reduced system.
#[derive(Clone, Debug)]
pub struct Derivation {
    pub n: usize,
    pub rank: usize,
    pub modes: Vec<DerivedMode>,
    /// The exact PDE (11), independence and completeness verdicts.
    pub mode_report: ModeReport,
    /// `f0` (when the drift is not zero), then the inputs.
    pub field_names: Vec<String>,
    /// `derivatives[k][i]`: `L_{f_i} g_k` in the modes, proven; `None` if not found.
    pub derivatives: Vec<Vec<Option<String>>>,
    /// Each output in the modes, proven; `None` if not found.
    pub outputs: Vec<(String, Option<String>)>,
    /// Generic constants of the system the reduced system keeps.
    pub consts: Vec<String>,
}

impl Derivation {
    /// Every derivative and every output was written in the modes.
    pub fn closed(&self) -> bool {
        self.derivatives.iter().flatten().all(|d| d.is_some())
            && self.outputs.iter().all(|o| o.1.is_some())
    }

    /// What could not be written in the modes.
    pub fn missing(&self) -> Vec<String> {
        let mut v = Vec::new();
        for (k, ds) in self.derivatives.iter().enumerate() {
            for (i, d) in ds.iter().enumerate() {
                if d.is_none() {
                    v.push(format!("L_{} {}", self.field_names[i], self.modes[k].name));
                }
            }
        }
        for (name, o) in &self.outputs {
            if o.is_none() {
                v.push(format!("output {name}"));
            }
        }
        v
    }

    /// `z_k' = F_k(z, u)`, or `None` when a part is missing.
    pub fn dynamics(&self, k: usize) -> Option<String> {
        let mut parts = Vec::new();
        for (i, d) in self.derivatives[k].iter().enumerate() {
            let d = d.as_deref()?;
            if d == "0" {
                continue;
            }
            let simple = !d.contains([' ', '/']);
            if !self.has_input(i) {
                parts.push(if simple {
                    d.to_string()
                } else {
                    format!("({d})")
                });
            } else if d == "1" {
                parts.push(self.field_names[i].clone());
            } else if simple && !d.starts_with('-') {
                parts.push(format!("{}*{d}", self.field_names[i]));
            } else {
                parts.push(format!("{}*({d})", self.field_names[i]));
            }
        }
        Some(if parts.is_empty() {
            "0".into()
        } else {
            parts.join(" + ")
        })
    }

    fn has_input(&self, i: usize) -> bool {
        self.field_names[i] != "f0"
    }

    /// The inputs of the reduced system.
    pub fn inputs(&self) -> Vec<String> {
        self.field_names
            .iter()
            .filter(|n| *n != "f0")
            .cloned()
            .collect()
    }

    /// Modes whose dynamics are zero are constant (params of the reduced system).
    pub fn is_constant(&self, k: usize) -> bool {
        self.derivatives[k]
            .iter()
            .all(|d| d.as_deref() == Some("0"))
    }

    /// A decomposition file (docs/decomposition-format.md) stating the result.
    pub fn decomposition_text(
        &self,
        system_path: &str,
        restriction: Option<&str>,
        set: &[(String, String)],
    ) -> Option<String> {
        let mut o =
            String::from("# Observable modes and reduced dynamics derived by `obsan modes`.\n");
        o.push_str(&format!("system {system_path}\n"));
        if let Some(r) = restriction {
            o.push_str(&format!("input {r}\n"));
        }
        for (k, v) in set {
            o.push_str(&format!("set {k} = {v}\n"));
        }
        for m in &self.modes {
            if m.kind != ModeKind::Variable {
                o.push_str(&format!("let {} = {}\n", m.name, m.text));
            }
        }
        let names: Vec<&str> = self.modes.iter().map(|m| m.name.as_str()).collect();
        o.push_str(&format!("state {}\n", names.join(", ")));
        for k in 0..self.modes.len() {
            o.push_str(&format!(
                "{}' = {}\n",
                self.modes[k].name,
                self.dynamics(k)?
            ));
        }
        for (name, e) in &self.outputs {
            o.push_str(&format!("output {name} = {}\n", e.as_deref()?));
        }
        Some(o)
    }

    /// A `.sys` file of the reduced system.
    pub fn sys_text(&self, name: &str, description: &str) -> Option<String> {
        let mut o = format!(
            "# The reduced system of {name} in its observable modes (derived by `obsan modes`).\n"
        );
        o.push_str(&format!("system {name}_modes\n"));
        o.push_str(&format!("description {description}\n"));
        for m in &self.modes {
            o.push_str(&format!("# {} = {}\n", m.name, m.text));
        }
        let states: Vec<&str> = (0..self.modes.len())
            .filter(|&k| !self.is_constant(k))
            .map(|k| self.modes[k].name.as_str())
            .collect();
        let params: Vec<&str> = (0..self.modes.len())
            .filter(|&k| self.is_constant(k))
            .map(|k| self.modes[k].name.as_str())
            .collect();
        if !states.is_empty() {
            o.push_str(&format!("state {}\n", states.join(", ")));
        }
        if !params.is_empty() {
            o.push_str(&format!("param {}\n", params.join(", ")));
        }
        if !self.consts.is_empty() {
            o.push_str(&format!("const {}\n", self.consts.join(", ")));
        }
        let inputs = self.inputs();
        if !inputs.is_empty() {
            o.push_str(&format!("input {}\n", inputs.join(", ")));
        }
        for k in 0..self.modes.len() {
            if !self.is_constant(k) {
                o.push_str(&format!(
                    "{}' = {}\n",
                    self.modes[k].name,
                    self.dynamics(k)?
                ));
            }
        }
        for (name, e) in &self.outputs {
            o.push_str(&format!("output {name} = {}\n", e.as_deref()?));
        }
        Some(o)
    }
}

/// Check a derived decomposition with the exact checks of `obsan verify`.
/// The rank report and symmetries are the ones the derivation used.
pub fn verify_derivation(
    nf: &mut NormalForm,
    dec_text: &str,
    origin: &str,
    seed: u64,
    known: (&RankReport, &SymmetryReport),
) -> Result<Vec<Check>, AnalysisError> {
    let d = Decomposition::parse(dec_text, origin)?;
    verify_decomposition_with(nf, &d, seed, Some(known))
}

fn check_deadline(opts: &DeriveOptions, stage: &str, found: usize) -> Result<(), AnalysisError> {
    match opts.deadline {
        Some(d) if Instant::now() > d => Err(AnalysisError::Timeout(format!(
            "{found} mode(s) found, stopped during {stage}"
        ))),
        _ => Ok(()),
    }
}

// ---------- linear algebra in F_p ----------

/// A basis of the right null space, in reduced echelon form (each vector has
/// a 1 at its free column and 0 at the other free columns).
fn null_space(mut m: Vec<Vec<Fp>>, ncols: usize) -> Vec<Vec<Fp>> {
    let mut pivots: Vec<usize> = Vec::new();
    let mut r = 0;
    for c in 0..ncols {
        let Some(i) = (r..m.len()).find(|&i| !m[i][c].is_zero()) else {
            continue;
        };
        m.swap(r, i);
        let Some(inv) = m[r][c].inv() else { continue };
        for x in m[r].iter_mut() {
            *x = *x * inv;
        }
        let pivot = m[r].clone();
        for (i, row) in m.iter_mut().enumerate() {
            if i != r && !row[c].is_zero() {
                let f = row[c];
                for (x, y) in row.iter_mut().zip(&pivot) {
                    *x = *x - f * *y;
                }
            }
        }
        pivots.push(c);
        r += 1;
        if r == m.len() {
            break;
        }
    }
    let mut out = Vec::new();
    for f in (0..ncols).filter(|c| !pivots.contains(c)) {
        let mut v = vec![Fp::ZERO; ncols];
        v[f] = Fp::ONE;
        for (k, &pc) in pivots.iter().enumerate() {
            v[pc] = Fp::ZERO - m[k][f];
        }
        out.push(v);
    }
    out
}

/// Rational number reconstruction (Wang): `a/b = u mod p` with |a|, |b| < sqrt(p/2).
fn rat_recon(u: Fp) -> Option<Q> {
    let p = P as i128;
    let bound = ((P / 2) as f64).sqrt() as i128;
    let (mut r0, mut r1) = (p, u.0 as i128);
    let (mut t0, mut t1) = (0i128, 1i128);
    while r1 > bound {
        let q = r0 / r1;
        (r0, r1) = (r1, r0 - q * r1);
        (t0, t1) = (t1, t0 - q * t1);
    }
    if t1 == 0 || t1.abs() > bound {
        return None;
    }
    let (a, b) = if t1 < 0 { (-r1, -t1) } else { (r1, t1) };
    let a = i64::try_from(a).ok()?;
    let b = i64::try_from(b).ok()?;
    Q::from_i64(a).div(&Q::from_i64(b))
}

/// Exponent vectors of total degree `lo..=hi` over `nb` blocks, by degree.
fn monomials(nb: usize, lo: usize, hi: usize) -> Vec<Vec<u32>> {
    fn rec(nb: usize, left: usize, cur: &mut Vec<u32>, out: &mut Vec<Vec<u32>>) {
        if cur.len() == nb {
            if left == 0 {
                out.push(cur.clone());
            }
            return;
        }
        for e in (0..=left).rev() {
            cur.push(e as u32);
            rec(nb, left - e, cur, out);
            cur.pop();
        }
    }
    let mut out = Vec::new();
    for d in lo..=hi {
        rec(nb, d, &mut Vec::new(), &mut out);
    }
    out
}

fn mono_value(e: &[u32], v: &[Fp]) -> Fp {
    e.iter()
        .zip(v)
        .fold(Fp::ONE, |a, (&k, &x)| a * x.pow(k as u64))
}

/// `w(m)` for a monomial from the block values and the blocks' `w`-derivatives.
fn mono_deriv(e: &[u32], v: &[Fp], dv: &[Fp]) -> Fp {
    let mut acc = Fp::ZERO;
    for k in 0..e.len() {
        if e[k] == 0 || dv[k].is_zero() {
            continue;
        }
        let mut t = Fp::from_i64(e[k] as i64) * dv[k];
        for l in 0..e.len() {
            let ex = if l == k { e[l] - 1 } else { e[l] };
            t = t * v[l].pow(ex as u64);
        }
        acc = acc + t;
    }
    acc
}

// ---------- expressions ----------

/// `sum_m c_m prod_k b_k^{e_k}` as an expression.
fn build_poly(nf: &mut NormalForm, coeffs: &[Q], monos: &[Vec<u32>], blocks: &[Id]) -> Id {
    let mut terms = Vec::new();
    for (c, e) in coeffs.iter().zip(monos) {
        if c.is_zero() {
            continue;
        }
        let mut fs = vec![nf.ctx.num(c.clone())];
        for (k, &x) in e.iter().enumerate() {
            if x > 0 {
                let p = nf.ctx.pow(blocks[k], x as i64);
                fs.push(p);
            }
        }
        terms.push(nf.ctx.mul(&fs));
    }
    nf.ctx.add(&terms)
}

/// The same sum as text over block names.
fn poly_text(coeffs: &[Q], monos: &[Vec<u32>], names: &[String]) -> String {
    let mut s = String::new();
    for (c, e) in coeffs.iter().zip(monos) {
        if c.is_zero() {
            continue;
        }
        let mut factors: Vec<String> = Vec::new();
        for (k, &x) in e.iter().enumerate() {
            match x {
                0 => {}
                1 => factors.push(names[k].clone()),
                _ => factors.push(format!("{}^{x}", names[k])),
            }
        }
        let neg = c.is_negative();
        let a = if neg { c.neg() } else { c.clone() };
        let mut body = if a.is_one() && !factors.is_empty() {
            String::new()
        } else if a.is_integer() {
            format!("{}", a.num())
        } else {
            format!("({}/{})", a.num(), a.den())
        };
        if !factors.is_empty() {
            if !body.is_empty() {
                body.push('*');
            }
            body.push_str(&factors.join("*"));
        }
        if s.is_empty() {
            s = if neg { format!("-{body}") } else { body };
        } else {
            s.push_str(if neg { " - " } else { " + " });
            s.push_str(&body);
        }
    }
    if s.is_empty() {
        "0".into()
    } else {
        s
    }
}

fn lie(nf: &mut NormalForm, g: Id, field: &[Id]) -> Id {
    let vars = nf.state_vars.clone();
    let mut terms = Vec::new();
    for (i, &x) in vars.iter().enumerate() {
        if nf.ctx.is_zero(field[i]) {
            continue;
        }
        let d = nf.ctx.diff(g, x);
        terms.push(nf.ctx.mul(&[field[i], d]));
    }
    nf.ctx.add(&terms)
}

/// A random point at which every given expression evaluates (retrying poles).
fn point_for(
    nf: &mut NormalForm,
    rng: &mut SplitMix,
    roots: &[Id],
) -> Result<(FpPoint, Vec<Fp>), AnalysisError> {
    for _ in 0..64 {
        if let Ok(pt) = nf.ctx.random_fp_point(rng, &|_| None) {
            if let Ok(v) = nf.ctx.eval_fp(roots, &pt) {
                return Ok((pt, v));
            }
        }
    }
    Err(AnalysisError::NoPoint)
}

/// Independence of accepted gradients at one random point (exact when a
/// candidate raises the rank: a non-zero minor).
struct Indep {
    grads: Vec<Vec<Id>>,
    seed: u64,
}

impl Indep {
    fn raises_rank(&mut self, nf: &mut NormalForm, g: Id) -> Result<bool, AnalysisError> {
        let vars = nf.state_vars.clone();
        let grad: Vec<Id> = vars.iter().map(|&x| nf.ctx.diff(g, x)).collect();
        let mut roots: Vec<Id> = self.grads.iter().flatten().copied().collect();
        roots.extend(&grad);
        let n = vars.len();
        self.seed = self.seed.wrapping_add(0x9e37_79b9);
        let mut rng = SplitMix(self.seed);
        let (_, vals) = point_for(nf, &mut rng, &roots)?;
        let rows: Vec<Vec<Fp>> = vals.chunks(n).map(|c| c.to_vec()).collect();
        let before = crate::modes::fp_rank(rows[..rows.len() - 1].to_vec(), n);
        let after = crate::modes::fp_rank(rows, n);
        if after > before {
            self.grads.push(grad);
            return Ok(true);
        }
        Ok(false)
    }
}

/// The PDE (11) at two random points in F_p (a screen: the exact check of
/// every accepted mode follows, once, in [`check_modes`]).
fn screen_mode(
    nf: &mut NormalForm,
    w_ids: &[Vec<Id>],
    g: Id,
    seed: u64,
) -> Result<bool, AnalysisError> {
    let roots: Vec<Id> = w_ids.iter().map(|w| lie(nf, g, w)).collect();
    let mut rng = SplitMix(seed ^ 0x7363_7265_656e);
    for _ in 0..2 {
        let (_, v) = point_for(nf, &mut rng, &roots)?;
        if v.iter().any(|x| !x.is_zero()) {
            return Ok(false);
        }
    }
    Ok(true)
}

/// Builds the modes and the reduced system.
pub fn derive_modes(
    nf: &mut NormalForm,
    report: &RankReport,
    sym: &SymmetryReport,
    opts: &DeriveOptions,
) -> Result<Derivation, AnalysisError> {
    if nf.delay.is_some() {
        return Err(AnalysisError::Invalid(
            "obsan modes does not handle delayed inputs yet".into(),
        ));
    }
    let rank = report.rank;
    let n = report.n;
    let vars = nf.state_vars.clone();
    let names = nf.state.clone();
    let mut modes: Vec<DerivedMode> = Vec::new();
    let mut indep = Indep {
        grads: Vec::new(),
        seed: opts.seed,
    };
    let mut used_names: Vec<String> = names.clone();
    used_names.extend(nf.consts.iter().map(|c| c.0.clone()));
    used_names.extend(nf.inputs.iter().cloned());
    used_names.extend(nf.outputs.iter().map(|o| o.0.clone()));
    let mut fresh = Names {
        used: used_names,
        count: 0,
    };

    // Which variables enter through cos/sin (angles) and which polynomially.
    let (fnames, fields) = crate::field_names(nf);
    let mut used_vars: Vec<u32> = Vec::new();
    let mut all: Vec<Id> = fields.iter().flatten().copied().collect();
    all.extend(nf.outputs.iter().map(|o| o.1));
    for &e in &all {
        let c = nf.ctx.canon(e);
        used_vars.extend(c.vars());
    }
    let mut angle = vec![false; n];
    let mut trig: Vec<Option<(Id, Id)>> = vec![None; n];
    for i in 0..n {
        let Ok(c) = nf.parse_expr(&format!("cos({})", names[i]), false) else {
            continue;
        };
        let Ok(s) = nf.parse_expr(&format!("sin({})", names[i]), false) else {
            continue;
        };
        let cv = nf.ctx.canon(c).vars();
        if cv.iter().any(|v| used_vars.contains(v)) {
            angle[i] = true;
            trig[i] = Some((c, s));
        }
    }

    // w components as expressions.
    let w_ids: Vec<Vec<Id>> = sym
        .vectors
        .iter()
        .map(|w| w.iter().map(|c| nf.ctx.from_canonical(c)).collect())
        .collect();
    // 1. Variables the symmetries leave alone.
    for i in 0..n {
        if modes.len() == rank {
            break;
        }
        if sym.vectors.iter().all(|w| w[i].is_zero()) {
            let g = nf.ctx.symbol(&names[i]).id;
            if indep.raises_rank(nf, g)? {
                modes.push(DerivedMode {
                    name: names[i].clone(),
                    expr: g,
                    text: names[i].clone(),
                    kind: ModeKind::Variable,
                    angle: angle[i],
                    domain: "everywhere".into(),
                });
            }
        }
    }
    check_deadline(opts, "the variables", modes.len())?;

    let nsym = w_ids.len();
    let mut rng = SplitMix(opts.seed ^ 0x6d6f_6465_7321);

    // 2. Integer combinations of angles that every symmetry leaves alone.
    let angles: Vec<usize> = (0..n).filter(|&i| angle[i]).collect();
    if modes.len() < rank && angles.len() >= 2 && nsym > 0 {
        let roots: Vec<Id> = w_ids
            .iter()
            .flat_map(|w| angles.iter().map(|&i| w[i]))
            .collect();
        let mut rows = Vec::new();
        for _ in 0..(angles.len() + 2) {
            let (_, v) = point_for(nf, &mut rng, &roots)?;
            rows.extend(v.chunks(angles.len()).map(|c| c.to_vec()));
        }
        for v in null_space(rows, angles.len()) {
            if modes.len() == rank {
                break;
            }
            let Some(qs) = v.iter().map(|&x| rat_recon(x)).collect::<Option<Vec<Q>>>() else {
                continue;
            };
            if !qs.iter().all(|q| q.is_integer()) || qs.iter().all(|q| q.is_zero()) {
                continue;
            }
            // Leading coefficient positive, for readability.
            let lead_neg = qs
                .iter()
                .rev()
                .find(|q| !q.is_zero())
                .is_some_and(|q| q.is_negative());
            let qs: Vec<Q> = if lead_neg {
                qs.iter().map(|q| q.neg()).collect()
            } else {
                qs
            };
            let blocks: Vec<Id> = angles.iter().map(|&i| vars_id(nf, &names[i])).collect();
            let monos: Vec<Vec<u32>> = (0..angles.len())
                .map(|k| (0..angles.len()).map(|l| u32::from(k == l)).collect())
                .collect();
            let order: Vec<usize> = (0..angles.len()).rev().collect();
            let qs_o: Vec<Q> = order.iter().map(|&k| qs[k].clone()).collect();
            let monos_o: Vec<Vec<u32>> = order.iter().map(|&k| monos[k].clone()).collect();
            let bnames: Vec<String> = angles.iter().map(|&i| names[i].clone()).collect();
            let g = build_poly(nf, &qs_o, &monos_o, &blocks);
            let text = poly_text(&qs_o, &monos_o, &bnames);
            if indep.raises_rank(nf, g)? && screen_mode(nf, &w_ids, g, opts.seed)? {
                modes.push(DerivedMode {
                    name: fresh.next(),
                    expr: g,
                    text,
                    kind: ModeKind::Translation,
                    angle: true,
                    domain: "everywhere (an angle, modulo 2 pi)".into(),
                });
            }
        }
    }
    check_deadline(opts, "the angle differences", modes.len())?;

    // 3. Polynomial and rational invariants.
    let mut blocks: Vec<Id> = Vec::new();
    let mut bnames: Vec<String> = Vec::new();
    for i in 0..n {
        let sym_var = nf.ctx.symbol(&names[i]).id;
        if !angle[i] || used_vars.contains(&vars[i]) {
            blocks.push(sym_var);
            bnames.push(names[i].clone());
        }
        if let Some((c, s)) = trig[i] {
            blocks.push(c);
            bnames.push(format!("cos({})", names[i]));
            blocks.push(s);
            bnames.push(format!("sin({})", names[i]));
        }
    }
    let mut consts = Vec::new();
    for (name, val) in nf.consts.clone() {
        if val.is_none() {
            if let Some(s) = nf.ctx.lookup(&name) {
                blocks.push(s.id);
                bnames.push(name.clone());
                consts.push(name);
            }
        }
    }
    // Denominator candidates: 1, then the factors of the outputs and of the
    // first-order Lie derivatives as they come out of the canonical form.
    let mut dens: Vec<(usize, Id)> = vec![(0, nf.ctx.one())];
    if modes.len() < rank && nsym > 0 {
        let mut seen: Vec<Poly> = Vec::new();
        let mut srcs: Vec<Id> = nf.outputs.iter().map(|o| o.1).collect();
        for o in nf.outputs.clone() {
            for f in &fields {
                srcs.push(lie(nf, o.1, f));
            }
        }
        for e in srcs {
            let c = nf.ctx.canon(e);
            for p in [c.numerator().clone(), c.denominator().clone()] {
                if p.is_constant() || seen.contains(&p) {
                    continue;
                }
                let id = nf.ctx.from_canonical(&RatFun::from_poly(p.clone()));
                if nf.ctx.is_angle_valued(id) {
                    continue;
                }
                seen.push(p.clone());
                dens.push((p.len(), id));
            }
        }
    }
    // Shortest denominators first: simpler modes, and a reduced system whose
    // exact proof stays small (eq. 39's A_v, V share mu^2 + 2 mu cos(gamma) + 1).
    dens.sort_by_key(|d| d.0);
    let dens: Vec<Id> = dens.into_iter().map(|d| d.1).collect();
    let search = Search {
        w_ids: &w_ids,
        rank,
        opts,
    };
    let orig_const: Vec<bool> = bnames.iter().map(|b| consts.contains(b)).collect();
    let coef = coefficient_blocks(nf, &fields, &names, &angle, &trig, &used_vars, &vars);
    let orig = (blocks, bnames, orig_const);
    // The coefficient blocks first when they are fewer: the same invariants
    // at a lower degree (eq. 16: eta (1 + q delta) cos(phi) is one block).
    let tries: Vec<(Vec<Id>, Vec<String>, Vec<bool>)> = match coef {
        Some(c) if c.0.len() < orig.0.len() => vec![c, orig],
        Some(c) => vec![orig, c],
        None => vec![orig],
    };
    if nsym > 0 {
        for (blocks, bnames, is_const) in &tries {
            if modes.len() >= rank {
                break;
            }
            invariant_ansatz(
                nf,
                &search,
                (blocks, bnames, is_const),
                &dens,
                &mut modes,
                &mut indep,
                &mut fresh,
                &mut rng,
            )?;
        }
    }

    // 4. The outputs, 5. the basis Lie derivatives.
    for (oname, h) in nf.outputs.clone() {
        if modes.len() >= rank {
            break;
        }
        if indep.raises_rank(nf, h)? && screen_mode(nf, &w_ids, h, opts.seed)? {
            let is_angle = nf.ctx.is_angle_valued(h);
            let text = nf.ctx.to_text(h);
            modes.push(DerivedMode {
                name: fresh.next(),
                expr: h,
                text,
                kind: ModeKind::Output,
                angle: false,
                domain: if is_angle {
                    format!("the branch of the output {oname} as the system defines it")
                } else {
                    format!("where the output {oname} is defined")
                },
            });
        }
    }
    for w in &report.basis {
        if modes.len() >= rank {
            break;
        }
        check_deadline(opts, "the Lie derivatives", modes.len())?;
        let mut g = nf.outputs[w.output].1;
        for &k in &w.fields {
            g = lie(nf, g, &report.fields.vectors[k]);
        }
        if indep.raises_rank(nf, g)? && screen_mode(nf, &w_ids, g, opts.seed)? {
            let c = nf.ctx.canon(g);
            let text = nf.ctx.ratfun_text_factored(&c);
            let domain = if c.denominator().is_constant() {
                "everywhere".to_string()
            } else {
                format!("where {} != 0", nf.ctx.poly_text(c.denominator()))
            };
            let g = nf.ctx.from_canonical(&c);
            modes.push(DerivedMode {
                name: fresh.next(),
                expr: g,
                text,
                kind: ModeKind::LieDerivative,
                angle: false,
                domain,
            });
        }
    }
    let ids: Vec<Id> = modes.iter().map(|m| m.expr).collect();
    let mode_report = check_modes(nf, sym, &ids, opts.seed)?;

    // The reduced system: each L_f g_k and each output in the modes.
    let mut zb: Vec<Id> = Vec::new();
    let mut znames: Vec<String> = Vec::new();
    for m in &modes {
        if m.angle {
            let c = nf.parse_expr(&format!("cos({})", m.text), false);
            let s = nf.parse_expr(&format!("sin({})", m.text), false);
            if let (Ok(c), Ok(s)) = (c, s) {
                zb.push(c);
                znames.push(format!("cos({})", m.name));
                zb.push(s);
                znames.push(format!("sin({})", m.name));
            }
        } else if !nf.ctx.is_angle_valued(m.expr) {
            zb.push(m.expr);
            znames.push(m.name.clone());
        }
    }
    for name in &consts {
        if let Some(s) = nf.ctx.lookup(name) {
            zb.push(s.id);
            znames.push(name.clone());
        }
    }
    let mut derivatives = Vec::new();
    for k in 0..modes.len() {
        let mut row = Vec::new();
        for f in &fields {
            check_deadline(opts, "the reduced dynamics", modes.len())?;
            let t = lie(nf, modes[k].expr, f);
            row.push(in_modes(nf, t, &zb, &znames, &modes, &mut rng, opts)?);
        }
        derivatives.push(row);
    }
    let mut outputs = Vec::new();
    for (oname, h) in nf.outputs.clone() {
        let e = if let Some(m) = modes.iter().find(|m| m.expr == h) {
            Some(m.name.clone())
        } else {
            in_modes(nf, h, &zb, &znames, &modes, &mut rng, opts)?
        };
        outputs.push((oname, e));
    }
    Ok(Derivation {
        n,
        rank,
        modes,
        mode_report,
        field_names: fnames,
        derivatives,
        outputs,
        consts,
    })
}

/// The names of derived modes: z1, z2, ... skipping names the system uses.
struct Names {
    used: Vec<String>,
    count: usize,
}

impl Names {
    fn next(&mut self) -> String {
        loop {
            self.count += 1;
            let s = format!("z{}", self.count);
            if !self.used.contains(&s) {
                self.used.push(s.clone());
                return s;
            }
        }
    }
}

/// What every invariant search needs.
struct Search<'a> {
    w_ids: &'a [Vec<Id>],
    rank: usize,
    opts: &'a DeriveOptions,
}

/// The coefficients of the fields as polynomials in the moving variables
/// (those some field changes, with cos/sin of the moving angles): the
/// combinations of the constant variables the dynamics see, such as
/// `eta (1 + q delta) cos(phi)` of eq. (16). An invariant of degree 5 in the
/// variables (eq. 23's V) is of degree 3 in these blocks, which a
/// cross-section of the symmetry group would also give. `None` when a
/// coefficient holds anything but constant variables (an atom of a moving one).
#[allow(clippy::type_complexity)]
fn coefficient_blocks(
    nf: &mut NormalForm,
    fields: &[Vec<Id>],
    names: &[String],
    angle: &[bool],
    trig: &[Option<(Id, Id)>],
    used_vars: &[u32],
    vars: &[u32],
) -> Option<(Vec<Id>, Vec<String>, Vec<bool>)> {
    let n = names.len();
    let mut blocks = Vec::new();
    let mut bnames = Vec::new();
    let mut moving: Vec<u32> = Vec::new();
    let mut fixed: Vec<u32> = Vec::new();
    for i in 0..n {
        let sym_var = nf.ctx.symbol(&names[i]).id;
        let mut vs = nf.ctx.canon(sym_var).vars();
        if let Some((c, s)) = trig[i] {
            vs.extend(nf.ctx.canon(c).vars());
            vs.extend(nf.ctx.canon(s).vars());
        }
        if fields.iter().all(|f| nf.ctx.is_zero(f[i])) {
            fixed.extend(vs);
            continue;
        }
        moving.extend(vs);
        if !angle[i] || used_vars.contains(&vars[i]) {
            blocks.push(sym_var);
            bnames.push(names[i].clone());
        }
        if let Some((c, s)) = trig[i] {
            blocks.push(c);
            bnames.push(format!("cos({})", names[i]));
            blocks.push(s);
            bnames.push(format!("sin({})", names[i]));
        }
    }
    let mut const_vars: Vec<u32> = Vec::new();
    for (name, val) in nf.consts.clone() {
        if val.is_none() {
            if let Some(s) = nf.ctx.lookup(&name) {
                const_vars.extend(nf.ctx.canon(s.id).vars());
            }
        }
    }
    fixed.extend(&const_vars);
    let nmoving = blocks.len();
    let mut seen: Vec<Poly> = Vec::new();
    for f in fields {
        for &e in f {
            let c = nf.ctx.canon(e);
            for p in [c.numerator(), c.denominator()] {
                // Group the terms by their monomial in the moving variables.
                let mut groups: Vec<(Mono, Vec<(Mono, Int)>)> = Vec::new();
                for (m, k) in p.terms() {
                    let mv = Mono::from_pairs(m.iter().filter(|(v, _)| moving.contains(v)));
                    let rest = Mono::from_pairs(m.iter().filter(|(v, _)| !moving.contains(v)));
                    match groups.iter_mut().find(|g| g.0 == mv) {
                        Some(g) => g.1.push((rest, k.clone())),
                        None => groups.push((mv, vec![(rest, k.clone())])),
                    }
                }
                for (_, ts) in groups {
                    let q = Poly::from_terms(ts);
                    if q.is_constant() {
                        continue;
                    }
                    if q.vars().iter().any(|v| !fixed.contains(v)) {
                        return None;
                    }
                    let content = q.content();
                    let q = q.div_exact(&Poly::constant(content))?.normalize_sign();
                    if !seen.contains(&q) {
                        seen.push(q);
                    }
                }
            }
        }
    }
    let mut is_const = vec![false; nmoving];
    for q in seen {
        is_const.push(q.vars().iter().all(|v| const_vars.contains(v)));
        let text = nf.ctx.poly_text(&q);
        bnames.push(if text.contains([' ', '*', '^', '/', '-', '+']) {
            format!("({text})")
        } else {
            text
        });
        blocks.push(nf.ctx.from_canonical(&RatFun::from_poly(q)));
    }
    Some((blocks, bnames, is_const))
}

/// Polynomial and rational invariants `P/Q` over the blocks: for each fixed
/// denominator `Q` the PDE (11) `Q w(P) - P w(Q) = 0` is linear in the
/// coefficients of `P`; solved in F_p, lifted by rational reconstruction,
/// screened at random points (the exact check of the accepted modes follows
/// in [`check_modes`]).
#[allow(clippy::too_many_arguments)]
fn invariant_ansatz(
    nf: &mut NormalForm,
    s: &Search,
    (blocks, bnames, is_const): (&[Id], &[String], &[bool]),
    dens: &[Id],
    modes: &mut Vec<DerivedMode>,
    indep: &mut Indep,
    fresh: &mut Names,
    rng: &mut SplitMix,
) -> Result<(), AnalysisError> {
    let nsym = s.w_ids.len();
    let nb = blocks.len();
    // w-derivatives of the blocks and of the denominators.
    let mut wb: Vec<Vec<Id>> = Vec::new(); // [sym][block]
    let mut wq: Vec<Vec<Id>> = Vec::new(); // [sym][den]
    for w in s.w_ids {
        let mut row = Vec::new();
        for &b in blocks {
            row.push(lie(nf, b, w));
        }
        wb.push(row);
        let mut rq = Vec::new();
        for &q in dens {
            rq.push(lie(nf, q, w));
        }
        wq.push(rq);
    }
    for (qi, &qd) in dens.iter().enumerate() {
        if modes.len() >= s.rank || nsym == 0 {
            break;
        }
        for d in 1..=s.opts.max_mode_degree {
            if modes.len() >= s.rank {
                break;
            }
            check_deadline(
                s.opts,
                &format!("the invariant ansatz of degree {d}"),
                modes.len(),
            )?;
            let monos = monomials(nb, 0, d);
            let nm = monos.len();
            if nm > MAX_UNKNOWNS {
                break;
            }
            let mut roots: Vec<Id> = blocks.to_vec();
            roots.push(qd);
            for j in 0..nsym {
                roots.extend(&wb[j]);
                roots.push(wq[j][qi]);
            }
            let npts = nm / nsym + 8;
            let mut rows: Vec<Vec<Fp>> = Vec::with_capacity(npts * nsym);
            let mut last_bv: Vec<Fp> = Vec::new();
            for _ in 0..npts {
                let (_, v) = point_for(nf, rng, &roots)?;
                let bv = &v[..nb];
                last_bv = bv.to_vec();
                let qv = v[nb];
                for j in 0..nsym {
                    let off = nb + 1 + j * (nb + 1);
                    let dv = &v[off..off + nb];
                    let dq = v[off + nb];
                    rows.push(
                        monos
                            .iter()
                            .map(|e| qv * mono_deriv(e, bv, dv) - mono_value(e, bv) * dq)
                            .collect(),
                    );
                }
            }
            let mut ns = null_space(rows, nm);
            ns.sort_by_key(|v| v.iter().filter(|x| !x.is_zero()).count());
            for v in ns {
                if modes.len() >= s.rank {
                    break;
                }
                // Skip constants (only the monomial 1 or constants' monomials).
                let nonconst = v.iter().zip(&monos).any(|(x, e)| {
                    !x.is_zero() && e.iter().enumerate().any(|(k, &p)| p > 0 && !is_const[k])
                });
                if !nonconst {
                    continue;
                }
                // A multiple of a constant, or a relation (cos^2 + sin^2 - 1) that
                // vanishes identically: not a new mode.
                let all_const_factor = v.iter().zip(&monos).all(|(x, e)| {
                    x.is_zero() || e.iter().enumerate().any(|(k, &p)| p > 0 && is_const[k])
                });
                if all_const_factor {
                    continue;
                }
                let val: Fp = v
                    .iter()
                    .zip(&monos)
                    .fold(Fp::ZERO, |a, (&c, e)| a + c * mono_value(e, &last_bv));
                if val.is_zero() {
                    continue;
                }
                let Some(qs) = v.iter().map(|&x| rat_recon(x)).collect::<Option<Vec<Q>>>() else {
                    continue;
                };
                let num = build_poly(nf, &qs, &monos, &blocks);
                let g = if qi == 0 { num } else { nf.ctx.div(num, qd) };
                if !indep.raises_rank(nf, g)? || !screen_mode(nf, s.w_ids, g, s.opts.seed)? {
                    continue;
                }
                let c = nf.ctx.canon(g);
                let poly = c.denominator().is_constant();
                // The ansatz's own form reads better than the canonical one
                // (which writes sin^2 as 1 - cos^2); both are the same function.
                let ptext = poly_text(&qs, &monos, &bnames);
                let text = if qi == 0 {
                    ptext
                } else {
                    format!("({ptext})/({})", nf.ctx.to_text(qd))
                };
                let domain = if poly {
                    "everywhere".to_string()
                } else {
                    format!("where {} != 0", nf.ctx.to_text(qd))
                };
                modes.push(DerivedMode {
                    name: fresh.next(),
                    expr: g,
                    text,
                    kind: if poly {
                        ModeKind::Polynomial
                    } else {
                        ModeKind::Rational
                    },
                    angle: false,
                    domain,
                });
            }
        }
    }

    Ok(())
}

fn vars_id(nf: &mut NormalForm, name: &str) -> Id {
    nf.ctx.symbol(name).id
}

/// `t` written as `P(z)/Q(z)` in the mode blocks, proven exactly; `None` when
/// no such form of degree up to the budget exists.
fn in_modes(
    nf: &mut NormalForm,
    t: Id,
    zb: &[Id],
    znames: &[String],
    modes: &[DerivedMode],
    rng: &mut SplitMix,
    opts: &DeriveOptions,
) -> Result<Option<String>, AnalysisError> {
    if nf.ctx.is_zero(t) {
        return Ok(Some("0".into()));
    }
    if nf.ctx.is_angle_valued(t) {
        return Ok(None);
    }
    let nb = zb.len();
    let mut roots: Vec<Id> = zb.to_vec();
    roots.push(t);
    for d in 0..=opts.max_closure_degree {
        check_deadline(
            opts,
            &format!("the reduced dynamics (degree {d})"),
            modes.len(),
        )?;
        let monos = monomials(nb, 0, d);
        let nm = monos.len();
        // A dense F_p elimination of 2 nm unknowns: keep it well under a second.
        if 2 * nm > MAX_UNKNOWNS {
            break;
        }
        let npts = 2 * nm + 8;
        let mut rows = Vec::with_capacity(npts);
        for _ in 0..npts {
            let (_, v) = point_for(nf, rng, &roots)?;
            let tv = v[nb];
            let mut row: Vec<Fp> = monos.iter().map(|e| mono_value(e, &v[..nb])).collect();
            let qpart: Vec<Fp> = row.iter().map(|&m| Fp::ZERO - tv * m).collect();
            row.extend(qpart);
            rows.push(row);
        }
        let mut ns = null_space(rows, 2 * nm);
        ns.sort_by_key(|v| v.iter().filter(|x| !x.is_zero()).count());
        for v in ns {
            if v[nm..].iter().all(|x| x.is_zero()) {
                continue;
            }
            // Normalise: the first non-zero denominator coefficient is 1.
            let Some(lead) = v[nm..].iter().find(|x| !x.is_zero()).and_then(|x| x.inv()) else {
                continue;
            };
            let Some(qs) = v
                .iter()
                .map(|&x| rat_recon(x * lead))
                .collect::<Option<Vec<Q>>>()
            else {
                continue;
            };
            let (pc, qc) = qs.split_at(nm);
            let pn = build_poly(nf, pc, &monos, zb);
            let qn = build_poly(nf, qc, &monos, zb);
            // Screened at fresh points here; proven exactly by the decomposition
            // checks (verify_derivation) of the whole reduced system.
            let r = nf.ctx.div(pn, qn);
            let diff = nf.ctx.sub(r, t);
            let mut fresh = SplitMix(rng.next_u64());
            let mut ok = true;
            for _ in 0..2 {
                let (_, v) = point_for(nf, &mut fresh, &[diff])?;
                ok &= v[0].is_zero();
            }
            if !ok {
                continue;
            }
            let ptext = poly_text(pc, &monos, znames);
            let qtext = poly_text(qc, &monos, znames);
            return Ok(Some(if qtext == "1" {
                ptext
            } else {
                format!("({ptext})/({qtext})")
            }));
        }
    }
    Ok(None)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rational_reconstruction_inverts_reduction_mod_p() {
        for (a, b) in [(1i64, 1i64), (-3, 7), (22, 7), (-1, 2), (123_456, 789)] {
            let u = Fp::from_i64(a) * Fp::from_i64(b).inv().unwrap();
            let q = rat_recon(u).unwrap();
            assert_eq!(q, Q::from_i64(a).div(&Q::from_i64(b)).unwrap());
        }
    }

    #[test]
    fn null_space_vectors_annihilate_the_rows() {
        let f = Fp::from_i64;
        let m = vec![vec![f(1), f(2), f(3), f(4)], vec![f(2), f(4), f(7), f(1)]];
        let ns = null_space(m.clone(), 4);
        assert_eq!(ns.len(), 2); // rank 2 of 4 columns
        for v in &ns {
            for row in &m {
                let dot = row.iter().zip(v).fold(Fp::ZERO, |a, (&x, &y)| a + x * y);
                assert!(dot.is_zero());
            }
        }
    }

    #[test]
    fn monomials_count_as_binomials() {
        // C(nb + d, d) exponent vectors of degree <= d.
        assert_eq!(monomials(3, 0, 2).len(), 10);
        assert_eq!(monomials(4, 0, 3).len(), 35);
    }
}
