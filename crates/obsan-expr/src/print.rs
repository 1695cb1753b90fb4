//! Printing canonical forms as plain text (which parses back to the same
//! canonical form) and as LaTeX.

use crate::budget::Limit;
use crate::graph::{Angle, Id, LeafKind};
use crate::memo::Ctx;
use crate::num::Int;
use crate::poly::{Mono, Poly, Var};
use crate::ratfun::RatFun;
use dashu_int::Sign;
use std::cell::{Cell, RefCell};
use std::cmp::Reverse;

// The printed form is a tree over the canonical form's DAG: a leaf is written
// out wherever it occurs, so text can grow exponentially with nesting (fuzz
// timeout-5952913f: 77 characters print as 19.7 MB). `try_ratfun_text` caps
// it, and `within_text_cap` caps every form printed in a scope; once over,
// every printer returns at once, so the work stays bounded too.
thread_local! {
    static TEXT_CAP: Cell<usize> = const { Cell::new(usize::MAX) };
    static TEXT_OVER: Cell<bool> = const { Cell::new(false) };
    /// Passing the cap trips an armed budget (`within_text_cap`), rather than
    /// being reported by the one printer that set it (`try_ratfun_text`).
    static TEXT_TRIPS: Cell<bool> = const { Cell::new(false) };
}

thread_local! {
    /// Printing keys of the leaves met in the current top-level print.
    static KEYS: RefCell<Option<rustc_hash::FxHashMap<Var, LeafKey>>> = const { RefCell::new(None) };
}

/// Where a leaf goes in printed text: by the name of its symbol (the symbol,
/// then its sin, cos and exp), other atoms by their own text. Never by the
/// order leaves were created in, so equal forms print identically in any
/// context and a printed form re-read prints the same.
type LeafKey = (String, u8, u32, String);

/// Run a top-level printer with a cache of leaf keys (a nested call reuses
/// the outer cache).
fn with_keys<T>(f: impl FnOnce() -> T) -> T {
    let outer = KEYS.with(|k| k.borrow().is_some());
    if !outer {
        KEYS.with(|k| *k.borrow_mut() = Some(Default::default()));
    }
    struct Clear(bool);
    impl Drop for Clear {
        fn drop(&mut self) {
            if !self.0 {
                KEYS.with(|k| k.borrow_mut().take());
            }
        }
    }
    let _clear = Clear(outer);
    f()
}

fn text_over() -> bool {
    TEXT_OVER.with(|o| o.get())
}

/// Record that `len` bytes were written; `true` once past the cap.
fn text_check(len: usize) -> bool {
    let cap = TEXT_CAP.with(|c| c.get());
    if len > cap && !text_over() {
        TEXT_OVER.with(|o| o.set(true));
        if TEXT_TRIPS.with(|t| t.get()) && crate::budget::armed() {
            crate::budget::trip(Limit::Text { max: cap });
        }
    }
    text_over()
}

/// A whole printed form, checked against the cap (the parts check as they grow).
fn checked(s: String) -> String {
    text_check(s.len());
    s
}

/// Run `f` with every form printed on this thread (text, factored, LaTeX,
/// leaves) capped at `max_bytes`. A form past the cap is cut short and the
/// result is [`Limit::Text`]; inside an armed budget
/// ([`within_thread_budget`](crate::within_thread_budget)) it also trips the
/// budget, so that caller gets the limit and drops all `f` printed.
pub fn within_text_cap<T>(max_bytes: usize, f: impl FnOnce() -> T) -> Result<T, Limit> {
    struct Restore(usize, bool, bool);
    impl Drop for Restore {
        fn drop(&mut self) {
            TEXT_CAP.with(|c| c.set(self.0));
            TEXT_OVER.with(|o| o.set(self.1));
            TEXT_TRIPS.with(|t| t.set(self.2));
        }
    }
    let _restore = Restore(
        TEXT_CAP.with(|c| c.replace(max_bytes)),
        TEXT_OVER.with(|o| o.replace(false)),
        TEXT_TRIPS.with(|t| t.replace(true)),
    );
    let r = f();
    if text_over() {
        return Err(Limit::Text { max: max_bytes });
    }
    Ok(r)
}

#[derive(Clone, Copy, PartialEq)]
enum Style {
    Text,
    Latex,
}

impl Ctx {
    /// Plain text of the canonical form of `id`.
    pub fn to_text(&mut self, id: Id) -> String {
        let r = self.canon(id);
        self.ratfun_text(&r)
    }

    /// LaTeX of the canonical form of `id`.
    pub fn to_latex(&mut self, id: Id) -> String {
        let r = self.canon(id);
        self.ratfun_latex(&r)
    }

    pub fn ratfun_text(&self, r: &RatFun) -> String {
        with_keys(|| checked(self.fmt_ratfun(r, Style::Text, false)))
    }

    /// [`Ctx::ratfun_text`], refused with [`Limit::Text`] once the text would
    /// pass `max_bytes` (it may be far larger than the form it prints).
    pub fn try_ratfun_text(&self, r: &RatFun, max_bytes: usize) -> Result<String, Limit> {
        let prev = TEXT_CAP.with(|c| c.replace(max_bytes));
        let prev_over = TEXT_OVER.with(|o| o.replace(false));
        let prev_trips = TEXT_TRIPS.with(|t| t.replace(false));
        let s = with_keys(|| self.fmt_ratfun(r, Style::Text, false));
        let over = text_check(s.len());
        TEXT_CAP.with(|c| c.set(prev));
        TEXT_OVER.with(|o| o.set(prev_over));
        TEXT_TRIPS.with(|t| t.set(prev_trips));
        if over {
            return Err(Limit::Text { max: max_bytes });
        }
        Ok(s)
    }

    pub fn ratfun_latex(&self, r: &RatFun) -> String {
        with_keys(|| checked(self.fmt_ratfun(r, Style::Latex, false)))
    }

    /// Plain text of a polynomial over the leaves.
    pub fn poly_text(&self, p: &Poly) -> String {
        with_keys(|| checked(self.fmt_poly(p, Style::Text)))
    }

    /// A fraction, expanded or partially factored. In text, a top-level sum
    /// needs parentheses, and so does any denominator but a single leaf or a
    /// positive constant (a/b*c is (a/b)*c).
    fn fmt_ratfun(&self, r: &RatFun, st: Style, factored: bool) -> String {
        // The canonical form makes the denominator's leading coefficient
        // positive in creation order; printed, it is positive in name order.
        let flipped;
        let r = if !r.den.is_one() && self.name_lc_negative(&r.den) {
            flipped = RatFun {
                num: r.num.neg(),
                den: r.den.neg(),
            };
            &flipped
        } else {
            r
        };
        let part = |p: &Poly| {
            if factored {
                self.fmt_product(p, st)
            } else {
                self.fmt_poly(p, st)
            }
        };
        let num = part(&r.num);
        if r.den.is_one() {
            return num;
        }
        let den = part(&r.den);
        match st {
            Style::Latex => format!("\\frac{{{num}}}{{{den}}}"),
            Style::Text => {
                let sum = r.num.len() > 1 && (!factored || factor_list(&r.num).len() <= 1);
                let n = if sum { format!("({num})") } else { num };
                let simple = r.den.len() == 1 && {
                    let (m, c) = &r.den.terms()[0];
                    (m.is_one() && c.sign() != Sign::Negative)
                        || (c.is_one() && m.iter().count() == 1)
                };
                let d = if simple { den } else { format!("({den})") };
                format!("{n}/{d}")
            }
        }
    }

    fn fmt_poly(&self, p: &Poly, st: Style) -> String {
        if p.is_zero() {
            return "0".into();
        }
        let mut out = String::new();
        for (i, (m, c)) in self.print_order(p).into_iter().enumerate() {
            if text_check(out.len()) {
                return out;
            }
            let neg = c.sign() == Sign::Negative;
            let a: Int = if neg { -c.clone() } else { c.clone() };
            if i == 0 {
                if neg {
                    out.push('-');
                }
            } else {
                out.push_str(if neg { " - " } else { " + " });
            }
            let mono = self.fmt_mono(m, st);
            if mono.is_empty() {
                out.push_str(&a.to_string());
            } else if a.is_one() {
                out.push_str(&mono);
            } else {
                out.push_str(&a.to_string());
                out.push_str(if st == Style::Text { "*" } else { " " });
                out.push_str(&mono);
            }
        }
        out
    }

    fn fmt_mono(&self, m: &Mono, st: Style) -> String {
        let mut vars: Vec<(Var, u32)> = m.iter().collect();
        if vars.len() > 1 {
            let ranks = self.ranks(vars.iter().map(|x| x.0));
            vars.sort_by_key(|(v, _)| ranks.get(v).copied());
        }
        let parts: Vec<String> = vars
            .into_iter()
            .map(|(v, e)| {
                let base = self.fmt_leaf(v, st);
                match (e, st) {
                    (1, _) => base,
                    // A root's text is itself a power: `(x^(1/3))^2`.
                    (_, Style::Text) if self.root_arg(v).is_some_and(|r| r.1 > 2) => {
                        format!("({base})^{e}")
                    }
                    (_, Style::Text) => format!("{base}^{e}"),
                    (_, Style::Latex) => {
                        // \sin^{2}(\gamma) reads better than (\sin(\gamma))^{2}.
                        if let Some(rest) = base.strip_prefix("\\sin") {
                            format!("\\sin^{{{e}}}{rest}")
                        } else if let Some(rest) = base.strip_prefix("\\cos") {
                            format!("\\cos^{{{e}}}{rest}")
                        } else if base.starts_with("e^")
                            || (base.starts_with('\\') && base.contains("\\left("))
                        {
                            format!("\\left({base}\\right)^{{{e}}}")
                        } else {
                            format!("{base}^{{{e}}}")
                        }
                    }
                }
            })
            .collect();
        parts.join(if st == Style::Text { "*" } else { " " })
    }

    /// The printing key of a leaf (cached for the current print).
    fn leaf_key(&self, v: Var) -> LeafKey {
        if let Some(k) = KEYS.with(|k| k.borrow().as_ref().and_then(|m| m.get(&v).cloned())) {
            return k;
        }
        let name = |sym: Var| self.symbol_name(sym).unwrap_or("").to_string();
        let key = match &self.leaves[v as usize].kind {
            LeafKind::Symbol(n) => (n.clone(), 0, 0, String::new()),
            LeafKind::Sin(Angle::Symbol { sym, den }) => (name(*sym), 1, *den, String::new()),
            LeafKind::Cos(Angle::Symbol { sym, den }) => (name(*sym), 2, *den, String::new()),
            LeafKind::Exp(Angle::Symbol { sym, den }) => (name(*sym), 3, *den, String::new()),
            _ => (self.fmt_leaf(v, Style::Text), 4, 0, String::new()),
        };
        KEYS.with(|k| {
            if let Some(m) = k.borrow_mut().as_mut() {
                m.insert(v, key.clone());
            }
        });
        key
    }

    /// Rank of each of `vars` in the printing order.
    fn ranks(&self, vars: impl Iterator<Item = Var>) -> rustc_hash::FxHashMap<Var, u32> {
        let mut keyed: Vec<(LeafKey, Var)> = vars.map(|v| (self.leaf_key(v), v)).collect();
        keyed.sort();
        keyed
            .into_iter()
            .enumerate()
            .map(|(i, (_, v))| (v, i as u32))
            .collect()
    }

    /// The terms of `p` in lex order over the printing order of the leaves
    /// (the first leaf highest), as the canonical order is over creation order.
    fn print_order<'a>(&self, p: &'a Poly) -> Vec<&'a (Mono, Int)> {
        let ranks = self.ranks(p.vars().into_iter());
        let mut keyed: Vec<(Vec<u64>, &(Mono, Int))> = p
            .terms()
            .iter()
            .map(|t| {
                let mut k: Vec<u64> =
                    t.0.iter()
                        .map(|(v, e)| {
                            let r = ranks.get(&v).copied().unwrap_or(u32::MAX);
                            (((u32::MAX - r) as u64) << 32) | e as u64
                        })
                        .collect();
                k.sort_unstable_by(|a, b| b.cmp(a));
                (k, t)
            })
            .collect();
        keyed.sort_by(|a, b| Reverse(&a.0).cmp(&Reverse(&b.0)));
        keyed.into_iter().map(|x| x.1).collect()
    }

    /// Whether the leading coefficient of `p` in the printing order is negative.
    pub(crate) fn name_lc_negative(&self, p: &Poly) -> bool {
        with_keys(|| {
            self.print_order(p)
                .first()
                .is_some_and(|(_, c)| c.sign() == Sign::Negative)
        })
    }

    fn arg(&self, id: Id, st: Style) -> String {
        let r = crate::budget::invariant(
            self.memo.canon.get(&id).cloned(),
            "atom arguments are canonical",
        );
        self.fmt_ratfun(&r, st, false)
    }

    fn fmt_leaf(&self, v: Var, st: Style) -> String {
        if text_over() {
            return String::new();
        }
        let kind = &self.leaves[v as usize].kind;
        let angle = |a: &Angle| -> String {
            match a {
                Angle::Symbol { sym, den } => {
                    let s = self.fmt_leaf(*sym, st);
                    match (den, st) {
                        (1, _) => s,
                        (_, Style::Text) => format!("{s}/{den}"),
                        (_, Style::Latex) => format!("\\frac{{{s}}}{{{den}}}"),
                    }
                }
                Angle::Generic(id) => self.arg(*id, st),
            }
        };
        let simple_angle = |a: &Angle| matches!(a, Angle::Symbol { den: 1, .. });
        match (kind, st) {
            (LeafKind::Symbol(name), Style::Text) => name.clone(),
            (LeafKind::Symbol(name), Style::Latex) => latex_name(name),
            (LeafKind::Pi, Style::Text) => "pi".into(),
            (LeafKind::Pi, Style::Latex) => "\\pi".into(),
            (LeafKind::Sin(a), Style::Text) => format!("sin({})", angle(a)),
            (LeafKind::Cos(a), Style::Text) => format!("cos({})", angle(a)),
            (LeafKind::Exp(a), Style::Text) => format!("exp({})", angle(a)),
            // Arguments always in parentheses: `\cos g \mu` reads as cos(g mu)
            // when pasted into a paper.
            (LeafKind::Sin(a), Style::Latex) if simple_angle(a) => format!("\\sin({})", angle(a)),
            (LeafKind::Cos(a), Style::Latex) if simple_angle(a) => format!("\\cos({})", angle(a)),
            (LeafKind::Sin(a), Style::Latex) => format!("\\sin\\left({}\\right)", angle(a)),
            (LeafKind::Cos(a), Style::Latex) => format!("\\cos\\left({}\\right)", angle(a)),
            (LeafKind::Exp(a), Style::Latex) => format!("e^{{{}}}", angle(a)),
            (LeafKind::Atan(u), Style::Text) => format!("atan({})", self.arg(*u, st)),
            (LeafKind::Atan(u), Style::Latex) => {
                format!("\\arctan\\left({}\\right)", self.arg(*u, st))
            }
            (LeafKind::Atan2(y, x), Style::Text) => {
                format!("atan2({}, {})", self.arg(*y, st), self.arg(*x, st))
            }
            (LeafKind::Atan2(y, x), Style::Latex) => {
                format!(
                    "\\operatorname{{atan2}}\\left({}, {}\\right)",
                    self.arg(*y, st),
                    self.arg(*x, st)
                )
            }
            (LeafKind::Log(u), Style::Text) => format!("log({})", self.arg(*u, st)),
            (LeafKind::Log(u), Style::Latex) => format!("\\log\\left({}\\right)", self.arg(*u, st)),
            (LeafKind::Root(u, 2), Style::Text) => format!("sqrt({})", self.arg(*u, st)),
            (LeafKind::Root(u, 2), Style::Latex) => format!("\\sqrt{{{}}}", self.arg(*u, st)),
            // `x^(1/3)`, `(x + 1)^(1/3)`: reads back as the same root.
            (LeafKind::Root(u, q), Style::Text) => {
                let a = self.arg(*u, st);
                if a.chars().all(|c| c.is_alphanumeric() || c == '_') {
                    format!("{a}^(1/{q})")
                } else {
                    format!("({a})^(1/{q})")
                }
            }
            (LeafKind::Root(u, q), Style::Latex) => {
                format!("\\sqrt[{q}]{{{}}}", self.arg(*u, st))
            }
        }
    }

    /// Plain text of a leaf (a symbol's name, or `sin(gamma)`, ...).
    pub fn leaf_text(&self, v: Var) -> String {
        with_keys(|| checked(self.fmt_leaf(v, Style::Text)))
    }
}

const GREEK: [&str; 40] = [
    "alpha",
    "beta",
    "gamma",
    "delta",
    "epsilon",
    "varepsilon",
    "zeta",
    "eta",
    "theta",
    "vartheta",
    "iota",
    "kappa",
    "lambda",
    "mu",
    "nu",
    "xi",
    "pi",
    "varpi",
    "rho",
    "varrho",
    "sigma",
    "varsigma",
    "tau",
    "upsilon",
    "phi",
    "varphi",
    "chi",
    "psi",
    "omega",
    "Gamma",
    "Delta",
    "Theta",
    "Lambda",
    "Xi",
    "Pi",
    "Sigma",
    "Upsilon",
    "Phi",
    "Psi",
    "Omega",
];

/// LaTeX for a symbol name: Greek names become letters, `a_b` and trailing
/// digits become subscripts, other multi-letter names are upright.
pub fn latex_name(name: &str) -> String {
    let (base, sub) = match name.split_once('_') {
        Some((b, s)) => (b, Some(s.to_string())),
        None => {
            let t = name.trim_end_matches(|c: char| c.is_ascii_digit());
            if t.len() < name.len() && !t.is_empty() {
                (t, Some(name[t.len()..].to_string()))
            } else {
                (name, None)
            }
        }
    };
    let b = if GREEK.contains(&base) {
        format!("\\{base}")
    } else if base.chars().count() == 1 {
        base.to_string()
    } else {
        format!("\\mathrm{{{base}}}")
    };
    match sub {
        Some(s) => format!("{b}_{{{}}}", latex_name(&s)),
        None => b,
    }
}

impl Ctx {
    /// Plain text with numerator and denominator partially factored: monomial
    /// and integer content, then the content with respect to each leaf,
    /// recursively. Parses back to the same canonical form.
    pub fn ratfun_text_factored(&self, r: &RatFun) -> String {
        with_keys(|| checked(self.fmt_ratfun(r, Style::Text, true)))
    }

    /// LaTeX, partially factored as [`Ctx::ratfun_text_factored`].
    pub fn ratfun_latex_factored(&self, r: &RatFun) -> String {
        with_keys(|| checked(self.fmt_ratfun(r, Style::Latex, true)))
    }

    fn fmt_product(&self, p: &Poly, st: Style) -> String {
        let facs = factor_list(p);
        if facs.len() <= 1 {
            return self.fmt_poly(p, st);
        }
        let mut sign = String::new();
        let mut parts = Vec::new();
        // Factors in a context-free order: the constant, single leaves, then
        // sums, each by their text.
        let mut facs: Vec<(u8, String, Poly)> = facs
            .into_iter()
            .map(|f| {
                let kind = if f.as_constant().is_some() {
                    0
                } else if f.len() == 1 {
                    1
                } else {
                    2
                };
                (kind, self.fmt_poly(&f, Style::Text), f)
            })
            .collect();
        facs.sort_by(|a, b| (a.0, &a.1).cmp(&(b.0, &b.1)));
        let facs: Vec<Poly> = facs.into_iter().map(|x| x.2).collect();
        for f in facs {
            if let Some(c) = f.as_constant() {
                if c == crate::num::int(-1) {
                    sign = "-".into();
                    continue;
                }
            }
            let s = self.fmt_poly(&f, st);
            let paren = f.len() > 1 || s.starts_with('-');
            parts.push(match (paren, st) {
                (true, Style::Text) => format!("({s})"),
                (true, Style::Latex) => format!("\\left({s}\\right)"),
                (false, _) => s,
            });
        }
        format!(
            "{sign}{}",
            parts.join(if st == Style::Text { "*" } else { " " })
        )
    }
}

/// Factors whose product is `p`: a constant (possibly -1 only), monomial
/// leaves, and polynomials split by their content in each variable.
fn factor_list(p: &Poly) -> Vec<Poly> {
    if p.is_zero() || p.len() == 1 {
        return vec![p.clone()];
    }
    let mut out = Vec::new();
    let c = p.content();
    let c = if p.lc_is_negative() { -c } else { c };
    if !c.is_one() {
        out.push(Poly::constant(c.clone()));
    }
    let m = p.mono_content();
    for (v, e) in m.iter() {
        out.push(Poly::monomial(
            crate::poly::Mono::var(v, e),
            crate::num::int(1),
        ));
    }
    let mut rest = crate::budget::invariant(
        p.div_mono(&m).div_exact(&Poly::constant(c)),
        "content divides",
    );
    let mut stack = vec![];
    // Split by the content in each variable until nothing splits.
    'outer: loop {
        for v in rest.vars() {
            let mut g = Poly::zero();
            for (_, k) in rest.coeffs_in(v) {
                g = crate::gcd::gcd(&g, &k);
                if g.is_constant() {
                    break;
                }
            }
            if !g.is_constant() {
                let q = crate::budget::invariant(rest.div_exact(&g), "content divides");
                stack.push(g);
                rest = q;
                continue 'outer;
            }
        }
        break;
    }
    for g in stack {
        out.extend(factor_list(&g).into_iter().filter(|f| !f.is_one()));
    }
    if !rest.is_one() {
        out.push(rest);
    }
    out
}
