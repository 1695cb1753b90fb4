//! Claimed local decompositions (eq. 9): new variables as functions of the
//! state, their reduced dynamics and the output, checked exactly.
//!
//! File format (docs/decomposition-format.md):
//! ```text
//! system eq20.sys                  # path relative to this file
//! input q                          # optional: a restriction of the system
//! set q = 9/10                     # optional: constant values
//! let Psi3 = (mu + cos(gamma))/sin(gamma)
//! state Psi1, Psi2, Psi3, xi_q     # the new state: lets or original variables
//! Psi3' = nu*(Psi2 + Psi1*Psi2*Psi3 - xi_q - xi_q*Psi3^2)
//! output y = 1/Psi3                # equal up to a constant
//! ```

use crate::modes::{check_modes, gradient_rank};
use crate::rank::{rank, AnalysisError, RankOptions, RankReport};
use crate::symmetry::{symmetries, SymmetryReport};
use obsan_expr::{line_col, parse_ast, Ast, Ctx, Id, ParseError, RatFun, Span, Var, Q};
use obsan_model::NormalForm;

/// A parsed decomposition file.
#[derive(Clone, Debug)]
pub struct Decomposition {
    pub system: String,
    pub restriction: Option<String>,
    pub set: Vec<(String, Q)>,
    lets: Vec<(String, Ast, usize)>,
    pub new_state: Vec<String>,
    new_state_at: usize,
    pub(crate) dynamics: Vec<(String, Ast, usize)>,
    pub(crate) outputs: Vec<(String, Ast, usize)>,
    /// `derivative NAME = u'`: a known input's time derivative, by name
    /// (input, order, offset); resolved against the model's jets
    /// (decomp_jets.rs).
    pub(crate) derivatives: Vec<(String, String, usize, usize)>,
    /// `combination NAME = EXPR`: an unknown-input combination driving the
    /// claimed dynamics, over the system's variables and unknown inputs.
    pub(crate) combinations: Vec<(String, Ast, usize)>,
    /// Declared derivative name -> the view's name of that jet.
    pub(crate) aliases: Vec<(String, String)>,
    pub(crate) src: String,
    pub(crate) origin: String,
}

/// One line of the verdict.
#[derive(Clone, Debug)]
pub struct Check {
    pub name: String,
    pub pass: bool,
    /// On failure, the residual or the reason.
    pub detail: String,
    /// A verdict that is not decided, with the atoms whose independence the
    /// engine cannot prove: a failure whose every nonzero residual holds
    /// such atoms, or a verdict resting on a nonzero minor or on the rank
    /// (independence, completeness) over such atoms. Empty when the verdict
    /// is certain (a pass by zero residuals always is).
    pub undecided: Vec<String>,
}

/// The atoms that leave a failure undecided: none if one nonzero residual
/// is provably nonzero, else every undecided atom of the residuals.
fn undecided_of(nf: &mut NormalForm, residuals: &[RatFun]) -> Vec<String> {
    let mut all = Vec::new();
    for r in residuals.iter().filter(|r| !r.is_zero()) {
        let atoms = nf.ctx.undecided_atom_texts(r);
        if atoms.is_empty() {
            return Vec::new();
        }
        all.extend(atoms);
    }
    all.sort();
    all.dedup();
    all
}

fn err(origin: &str, src: &str, at: usize, msg: impl Into<String>) -> AnalysisError {
    let (l, c) = line_col(src, at);
    AnalysisError::Invalid(format!("{origin}:{l}:{c}: {}", msg.into()))
}

impl Decomposition {
    /// Read a decomposition file; `origin` names it in messages.
    pub fn parse(src: &str, origin: &str) -> Result<Decomposition, AnalysisError> {
        let mut d = Decomposition {
            system: String::new(),
            restriction: None,
            set: vec![],
            lets: vec![],
            new_state: vec![],
            new_state_at: 0,
            dynamics: vec![],
            outputs: vec![],
            derivatives: vec![],
            combinations: vec![],
            aliases: vec![],
            src: src.to_string(),
            origin: origin.to_string(),
        };
        let mut offset = 0;
        for raw in src.split_inclusive('\n') {
            let start = offset;
            offset += raw.len();
            let code = raw.split('#').next().unwrap_or("").trim_end();
            let lead = code.len() - code.trim_start().len();
            let line = code.trim_start();
            if line.is_empty() {
                continue;
            }
            let at = start + lead;
            let (word, rest) = line.split_once(char::is_whitespace).unwrap_or((line, ""));
            let rest_at = at
                + word.len()
                + (rest.len() - rest.trim_start().len())
                + usize::from(!rest.is_empty());
            let rest = rest.trim();
            let expr = |text: &str, base: usize| -> Result<(Ast, usize), AnalysisError> {
                let lead = text.len() - text.trim_start().len();
                let t = text.trim();
                parse_ast(t)
                    .map(|a| (a, base + lead))
                    .map_err(|e| err(origin, src, base + lead + e.span.start, e.message))
            };
            match word {
                "system" => d.system = rest.to_string(),
                "input" => d.restriction = Some(rest.to_string()),
                "set" | "let" | "output" | "combination" | "derivative" => {
                    let Some(eq) = rest.find('=') else {
                        return Err(err(origin, src, at, format!("'{word}' needs NAME = EXPR")));
                    };
                    let name = rest[..eq].trim().to_string();
                    if name.is_empty()
                        || !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
                    {
                        return Err(err(
                            origin,
                            src,
                            rest_at,
                            format!("'{word}' needs a name before '='"),
                        ));
                    }
                    if word == "derivative" {
                        let rhs = &rest[eq + 1..];
                        let rat = rest_at + eq + 1 + (rhs.len() - rhs.trim_start().len());
                        let rhs = rhs.trim();
                        let base = rhs.trim_end_matches('\'');
                        let order = rhs.len() - base.len();
                        let valid = base.starts_with(|c: char| c.is_ascii_alphabetic() || c == '_')
                            && base.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
                        if order == 0 || !valid {
                            return Err(err(
                                origin,
                                src,
                                rat,
                                "'derivative' needs NAME = INPUT' (an input's name and one quote per order: u', u'')",
                            ));
                        }
                        if d.derivatives.iter().any(|x| x.0 == name) {
                            return Err(err(
                                origin,
                                src,
                                rest_at,
                                format!("'{name}' is defined twice"),
                            ));
                        }
                        d.derivatives.push((name, base.to_string(), order, rat));
                        continue;
                    }
                    let (ast, eat) = expr(&rest[eq + 1..], rest_at + eq + 1)?;
                    match word {
                        "set" => {
                            let mut c = Ctx::new();
                            let q = c
                                .build(&ast, &mut |_, n, s| {
                                    Err(ParseError::new(
                                        format!("a value must be a number, not '{n}'"),
                                        s,
                                    ))
                                })
                                .ok()
                                .map(|id| c.try_canon(id));
                            // The budgeted canonical form: a value past the engine's
                            // number limit (`973347445^0.705...` with a root of index
                            // 200) is an error at its place, never a panic.
                            if let Some(Err(l)) = &q {
                                return Err(err(origin, src, eat, format!("a value: {l}")));
                            }
                            let q = q.and_then(|r| r.ok()).and_then(|r| r.as_q());
                            let Some(q) = q else {
                                return Err(err(
                                    origin,
                                    src,
                                    eat,
                                    "a value must be a rational number",
                                ));
                            };
                            d.set.push((name, q));
                        }
                        "let" => {
                            if d.lets.iter().any(|l| l.0 == name) {
                                return Err(err(
                                    origin,
                                    src,
                                    rest_at,
                                    format!("'{name}' is defined twice"),
                                ));
                            }
                            d.lets.push((name, ast, eat));
                        }
                        "combination" => {
                            if d.combinations.iter().any(|l| l.0 == name) {
                                return Err(err(
                                    origin,
                                    src,
                                    rest_at,
                                    format!("'{name}' is defined twice"),
                                ));
                            }
                            d.combinations.push((name, ast, eat));
                        }
                        _ => d.outputs.push((name, ast, eat)),
                    }
                }
                "state" => {
                    d.new_state = rest.split(',').map(|s| s.trim().to_string()).collect();
                    d.new_state_at = rest_at;
                    if d.new_state.iter().any(|s| s.is_empty()) {
                        return Err(err(
                            origin,
                            src,
                            rest_at,
                            "'state' needs a comma-separated list of names",
                        ));
                    }
                }
                w if w.ends_with('\'') || line.contains("' =") || line.contains("'=") => {
                    #[allow(clippy::expect_used)] // this arm is taken only for lines with a tick
                    let tick = line.find('\'').expect("has a tick");
                    let name = line[..tick].trim().to_string();
                    let Some(eq) = line.find('=') else {
                        return Err(err(origin, src, at, "an equation needs '='"));
                    };
                    let (ast, eat) = expr(&line[eq + 1..], at + eq + 1)?;
                    d.dynamics.push((name, ast, eat));
                }
                _ => {
                    return Err(err(origin, src, at, "expected system, input, set, let, derivative, combination, state, NAME' = EXPR or output NAME = EXPR"));
                }
            }
        }
        if d.system.is_empty() {
            return Err(AnalysisError::Invalid(format!(
                "{origin}: no 'system PATH' line"
            )));
        }
        if d.new_state.is_empty() {
            return Err(AnalysisError::Invalid(format!(
                "{origin}: no 'state' line naming the new state"
            )));
        }
        Ok(d)
    }

    /// Every check passed and every output of `nf` is written in the new
    /// state: then the verdict is exact whatever certified the symmetries.
    /// The span of the new gradients holds every output gradient and is
    /// closed under every field (the dynamics checks), so it contains the
    /// observable codistribution; the rank test's non-zero minor bounds that
    /// from below by the same count (the completeness check); so the two are
    /// equal and each new variable is a mode (eq. 11) with no probability.
    /// The minor proves only over decided atoms: an undecided check proves
    /// nothing.
    pub fn closure_proves(&self, nf: &NormalForm, checks: &[Check]) -> bool {
        !checks.is_empty()
            && checks.iter().all(|c| c.pass && c.undecided.is_empty())
            && nf
                .outputs
                .iter()
                .all(|(n, _)| self.outputs.iter().any(|o| &o.0 == n))
    }

    /// With explicit time the clock `t` (`t' = 1`, observable through its
    /// known output) is a mode of every decomposition, so a file need not
    /// name it (`obsan modes` never writes it, `t` being time, never
    /// declared): it is added, with its equation `t' = 1` appended to the
    /// source so that every offset stays valid.
    fn with_clock(&self) -> Decomposition {
        let t = obsan_model::TIME;
        if self.new_state.iter().any(|s| s == t) {
            return self.clone();
        }
        let mut d = self.clone();
        let line = format!("\n{t}' = 1\n");
        let at = d.src.len() + line.len() - 2;
        d.src.push_str(&line);
        if let Ok(one) = parse_ast("1") {
            d.new_state.push(t.to_string());
            d.dynamics.push((t.to_string(), one, at));
        }
        d
    }

    fn at(&self, offset: usize, msg: impl Into<String>) -> AnalysisError {
        err(&self.origin, &self.src, offset, msg)
    }
}

/// Check a decomposition against the system's normal form (already restricted
/// and with constants set as the file says).
pub fn verify_decomposition(
    nf: &mut NormalForm,
    d: &Decomposition,
    seed: u64,
) -> Result<Vec<Check>, AnalysisError> {
    verify_decomposition_with(nf, d, seed, None)
}

/// [`verify_decomposition`] with the system's rank report and symmetries
/// when the caller has them already (`obsan modes`), so they are not
/// computed twice.
pub fn verify_decomposition_with(
    nf: &mut NormalForm,
    d: &Decomposition,
    seed: u64,
    known: Option<(&RankReport, &SymmetryReport)>,
) -> Result<Vec<Check>, AnalysisError> {
    let with_clock;
    let d = match nf.clock() {
        Some(_) => {
            with_clock = d.with_clock();
            &with_clock
        }
        None => d,
    };
    let new = NewState::build(nf, d)?;
    let mut checks = mode_and_rank_checks(nf, d, &new.g, seed, known)?;
    for (k, s) in d.new_state.iter().enumerate() {
        checks.push(dynamics_check(nf, d, &new, k, s)?);
    }
    for (name, ast, at) in &d.outputs {
        checks.push(output_check(nf, d, &new, name, ast, *at)?);
    }
    Ok(checks)
}

/// Per unknown-input combination the file declares, whether it can be
/// recovered from the claimed dynamics: `z' = F(z, u) + C(z) w~`, and `w~`
/// follows from the modes' derivatives when the column `C` is not zero
/// (exact: canonical forms; one combination, a column of rank one). `C_k`
/// is the claim's coefficient of an unknown input `w` the combination
/// reads divided by the combination's own (`w~ = beta w + offset`).
/// Returns the checks and the unknown inputs the combinations read.
pub fn combination_checks(
    nf: &mut NormalForm,
    d: &Decomposition,
    unknown: &[String],
) -> Result<(Vec<Check>, Vec<String>), AnalysisError> {
    if d.combinations.is_empty() {
        return Ok((Vec::new(), Vec::new()));
    }
    let with_clock;
    let d = match nf.clock() {
        Some(_) => {
            with_clock = d.with_clock();
            &with_clock
        }
        None => d,
    };
    let new = NewState::build(nf, d)?;
    let several = d.combinations.len() > 1;
    let (mut checks, mut covered) = (Vec::new(), Vec::new());
    for (name, _, at) in &d.combinations {
        let Some(&(_, def)) = new.claim_defs.iter().find(|c| &c.0 == name) else {
            continue;
        };
        let mut read = None;
        for w in unknown {
            let Some(wv) = nf.ctx.lookup(w).map(|s| s.var) else {
                continue;
            };
            let b = nf.ctx.diff(def, wv);
            let b = nf.ctx.try_canon(b).map_err(|l| d.at(*at, l.to_string()))?;
            if !b.is_zero() {
                covered.push(w.clone());
                read.get_or_insert((wv, b));
            }
        }
        let mut nonzero = false;
        if let Some((wv, b)) = &read {
            for (_, ast, dat) in &d.dynamics {
                let rhs = new.claim(nf, d, ast, *dat)?;
                let c = nf.ctx.diff(rhs, *wv);
                let c = nf.ctx.try_canon(c).map_err(|l| d.at(*dat, l.to_string()))?;
                nonzero |= !c.is_zero() && !b.is_zero();
            }
        }
        checks.push(Check {
            name: format!("the combination {name} is recovered from the modes' derivatives"),
            pass: nonzero && !several,
            detail: if read.is_none() {
                format!("{name} reads no unknown input")
            } else if several {
                "several combinations: their joint recovery (a minor of their columns) is not checked yet".into()
            } else if !nonzero {
                format!("no claimed dynamics reads {name}")
            } else {
                String::new()
            },
            undecided: Vec::new(),
        });
    }
    covered.sort();
    covered.dedup();
    Ok((checks, covered))
}

/// The new state over the original variables, and the placeholders that stand for the
/// new variables in the claimed expressions.
struct NewState {
    /// Each new variable as an expression in the original variables.
    g: Vec<Id>,
    /// Per new variable: its name, its placeholder symbol and that symbol's variable.
    placeholders: Vec<(String, Id, Var)>,
    /// Each placeholder's variable and the expression it stands for.
    back: Vec<(Var, Id)>,
    /// Names a claim may read besides the new variables: the top-order
    /// input derivatives and the unknown-input combinations.
    claim_defs: Vec<(String, Id)>,
}

impl NewState {
    /// Build the lets (in terms of the original variables, earlier lets usable) and the
    /// new state the file names.
    fn build(nf: &mut NormalForm, d: &Decomposition) -> Result<NewState, AnalysisError> {
        // A declared derivative reads the view's jet (decomp_jets.rs).
        let mut defs: Vec<(String, Id)> = d
            .aliases
            .iter()
            .map(|(a, internal)| (a.clone(), nf.ctx.symbol(internal).id))
            .collect();
        for (name, ast, at) in &d.lets {
            if nf.state.contains(name) || nf.consts.iter().any(|c| &c.0 == name) {
                return Err(d.at(*at, format!("'{name}' is already a variable of the system")));
            }
            let id =
                build_over(nf, ast, &defs, &[]).map_err(|e| d.at(at + e.span.start, e.message))?;
            defs.push((name.clone(), id));
        }
        let mut g: Vec<Id> = Vec::new();
        for s in &d.new_state {
            if let Some((_, id)) = defs.iter().find(|(n, _)| n == s) {
                g.push(*id);
            } else if nf.state.contains(s) {
                g.push(nf.ctx.symbol(s).id);
            } else {
                return Err(d.at(
                    d.new_state_at,
                    format!(
                        "'{s}' in the new state is neither a 'let' nor a variable of the system"
                    ),
                ));
            }
        }
        let mut placeholders: Vec<(String, Id, Var)> = d
            .new_state
            .iter()
            .map(|s| {
                let sym = nf.ctx.symbol(&format!("{s}\u{2032}new"));
                (s.clone(), sym.id, sym.var)
            })
            .collect();
        let back: Vec<(Var, Id)> = placeholders
            .iter()
            .zip(&g)
            .map(|(p, &id)| (p.2, id))
            .collect();
        // In a claim a declared derivative that is a new variable (a jet
        // of the view) is that variable; the top order is an input.
        let mut claim_defs: Vec<(String, Id)> = Vec::new();
        for (a, internal) in &d.aliases {
            match placeholders.iter().find(|p| &p.0 == internal).cloned() {
                Some(p) => placeholders.push((a.clone(), p.1, p.2)),
                None => claim_defs.push((a.clone(), nf.ctx.symbol(internal).id)),
            }
        }
        // A combination stands for its definition over the system's
        // variables: the claim, written back, is then checked field by field.
        for (name, ast, at) in &d.combinations {
            if nf.state.contains(name) || nf.inputs.contains(name) {
                return Err(d.at(*at, format!("'{name}' is already a variable of the system")));
            }
            let id =
                build_over(nf, ast, &defs, &[]).map_err(|e| d.at(at + e.span.start, e.message))?;
            claim_defs.push((name.clone(), id));
        }
        Ok(NewState {
            g,
            placeholders,
            back,
            claim_defs,
        })
    }

    /// A claimed expression over the new variables, written back in the original ones.
    fn claim(
        &self,
        nf: &mut NormalForm,
        d: &Decomposition,
        ast: &Ast,
        at: usize,
    ) -> Result<Id, AnalysisError> {
        let e = build_over(nf, ast, &self.claim_defs, &self.placeholders)
            .map_err(|e| d.at(at + e.span.start, e.message))?;
        nf.ctx.substitute(e, &self.back).map_err(|e| d.at(at, e.0))
    }
}

/// Checks 1 to 3: each new variable an observable mode (eq. 11) of the system's
/// symmetries, the new variables independent, and as many as the system's rank.
fn mode_and_rank_checks(
    nf: &mut NormalForm,
    d: &Decomposition,
    g: &[Id],
    seed: u64,
    known: Option<(&RankReport, &SymmetryReport)>,
) -> Result<Vec<Check>, AnalysisError> {
    let mut checks = Vec::new();
    let computed;
    let (report, sym) = match known {
        Some(k) => k,
        None => {
            let report = rank(
                nf,
                RankOptions {
                    seed,
                    ..Default::default()
                },
            )?;
            let sym = symmetries(nf, &report)?;
            computed = (report, sym);
            (&computed.0, &computed.1)
        }
    };
    let modes = check_modes(nf, sym, g, seed)?;
    for (s, c) in d.new_state.iter().zip(&modes.checks) {
        let detail = match c.residuals.iter().position(|r| !r.is_zero()) {
            None => String::new(),
            Some(k) => format!(
                "grad({s}) . w{} = {}",
                k + 1,
                nf.ctx.ratfun_text(&c.residuals[k])
            ),
        };
        let undecided = undecided_of(nf, &c.residuals);
        checks.push(Check {
            name: format!(
                "{s} is an observable mode (eq. 11, {} symmetries)",
                sym.count()
            ),
            pass: c.is_mode,
            detail,
            undecided,
        });
    }
    // 2. Independent, 3. complete. A rank found at a point is a nonzero
    // minor of the new gradients (their atoms), and the system's rank one
    // over the system's atoms: over undecided atoms, both may be too high.
    // (A rank deficit at a point is only probabilistic, and a formal
    // dependence is a true one: "not independent" needs no atom.)
    let (indep, _) = gradient_rank(nf, g, seed)?;
    let own = crate::decided::undecided_atoms_of_forms(nf, g);
    let atoms = crate::decided::undecided_atoms_of(nf, g);
    checks.push(Check {
        name: format!("the {} new variables are independent", g.len()),
        pass: indep == g.len(),
        detail: if indep == g.len() {
            String::new()
        } else {
            format!("their gradients have rank {indep}")
        },
        undecided: if indep == g.len() { own } else { Vec::new() },
    });
    checks.push(Check {
        name: format!(
            "they are complete (rank of the system is {}{})",
            report.rank,
            if nf.clock().is_some() {
                ", the clock t counted"
            } else {
                ""
            }
        ),
        pass: indep == report.rank,
        detail: if indep == report.rank {
            String::new()
        } else {
            format!("{indep} independent variables for rank {}", report.rank)
        },
        undecided: atoms,
    });
    Ok(checks)
}

/// Check 4 for the `k`-th new variable `s`: `L_{f_i} g_k` equals the claimed coefficient
/// of `u_i` for every input field, and `L_{f0} g_k` the claimed drift.
fn dynamics_check(
    nf: &mut NormalForm,
    d: &Decomposition,
    new: &NewState,
    k: usize,
    s: &str,
) -> Result<Check, AnalysisError> {
    let Some((_, ast, at)) = d.dynamics.iter().find(|x| x.0 == s) else {
        return Ok(Check {
            name: format!("{s}' is given"),
            pass: false,
            detail: format!("no equation {s}' = ... in the file"),
            undecided: Vec::new(),
        });
    };
    let rhs = new.claim(nf, d, ast, *at)?;
    let input_vars = nf.input_vars.clone();
    let state_vars = nf.state_vars.clone();
    // Drift and per-input coefficients of the claim.
    let mut claim_rest = rhs;
    let mut residual_text = Vec::new();
    let mut residuals = Vec::new();
    for (i, &u) in input_vars.iter().enumerate() {
        let ci = nf.ctx.diff(rhs, u);
        let ui = nf.ctx.symbol(&nf.inputs[i].clone()).id;
        let t = nf.ctx.mul(&[ci, ui]);
        claim_rest = nf.ctx.sub(claim_rest, t);
        let field = nf.fields[i].clone();
        let actual = nf.ctx.lie_derivative(new.g[k], &state_vars, &field);
        let diff = nf.ctx.sub(actual, ci);
        let r = nf
            .ctx
            .try_canon(diff)
            .map_err(|l| d.at(*at, l.to_string()))?;
        if !r.is_zero() {
            residual_text.push(format!(
                "coefficient of {}: L_f{} {s} - claimed = {}",
                nf.inputs[i],
                nf.inputs[i],
                nf.ctx.ratfun_text(&r)
            ));
            residuals.push(r);
        }
    }
    let f0 = nf.f0.clone();
    let drift = nf.ctx.lie_derivative(new.g[k], &state_vars, &f0);
    let diff = nf.ctx.sub(drift, claim_rest);
    // Budgeted here, so that a limit names this line (an unbudgeted form
    // would leave it to be reported at the next budgeted step's line).
    let r = nf
        .ctx
        .try_canon(diff)
        .map_err(|l| d.at(*at, l.to_string()))?;
    if !r.is_zero() {
        residual_text.push(format!(
            "drift: L_f0 {s} - claimed = {}",
            nf.ctx.ratfun_text(&r)
        ));
        residuals.push(r);
    }
    let undecided = undecided_of(nf, &residuals);
    Ok(Check {
        name: format!("{s}' = {}", ast_text(&d.src, ast, *at)),
        pass: residual_text.is_empty(),
        detail: residual_text.join("; "),
        undecided,
    })
}

/// Check 5 for output `name`: the system's output equals the claim up to a constant
/// (every state derivative of the difference is zero).
fn output_check(
    nf: &mut NormalForm,
    d: &Decomposition,
    new: &NewState,
    name: &str,
    ast: &Ast,
    at: usize,
) -> Result<Check, AnalysisError> {
    let Some(h) = nf.outputs.iter().find(|o| o.0 == name).map(|o| o.1) else {
        return Err(d.at(at, format!("'{name}' is not an output of the system")));
    };
    let claim = new.claim(nf, d, ast, at)?;
    let diff = nf.ctx.sub(h, claim);
    let c = nf
        .ctx
        .try_canon(diff)
        .map_err(|l| d.at(at, l.to_string()))?;
    let state_vars = nf.state_vars.clone();
    let mut bad = Vec::new();
    let mut residuals = Vec::new();
    for (j, &x) in state_vars.iter().enumerate() {
        let dx = nf.ctx.rf_diff(&c, x);
        if !dx.is_zero() {
            bad.push(format!(
                "d/d{} ({name} - claimed) = {}",
                nf.state[j],
                nf.ctx.ratfun_text(&dx)
            ));
            residuals.push(dx);
        }
    }
    let undecided = undecided_of(nf, &residuals);
    Ok(Check {
        name: format!(
            "output {name} = {} (up to a constant)",
            ast_text(&d.src, ast, at)
        ),
        pass: bad.is_empty(),
        detail: bad.join("; "),
        undecided,
    })
}

fn ast_text(src: &str, ast: &Ast, at: usize) -> String {
    src.get(at + ast.span.start..at + ast.span.end)
        .unwrap_or("?")
        .to_string()
}

/// Build an expression over the system's state, constants and inputs, the
/// given definitions, and placeholders for the new variables.
fn build_over(
    nf: &mut NormalForm,
    ast: &Ast,
    defs: &[(String, Id)],
    placeholders: &[(String, Id, Var)],
) -> Result<Id, ParseError> {
    let state = nf.state.clone();
    let extra = |n: &str, s: Span| -> Option<Result<Id, ParseError>> {
        if let Some(p) = placeholders.iter().find(|p| p.0 == n) {
            return Some(Ok(p.1));
        }
        if let Some((_, id)) = defs.iter().find(|(x, _)| x == n) {
            return Some(Ok(*id));
        }
        if !placeholders.is_empty() && state.iter().any(|x| x == n) {
            return Some(Err(ParseError::new(format!("'{n}' is an original variable, not one of the new state: the claim must use the new variables"), s)));
        }
        None
    };
    nf.build_expr(ast, true, &extra)
}
