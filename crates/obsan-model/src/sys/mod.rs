//! Reading the `.sys` format.
//!
//! A file is a list of statements, one per line; a statement continues on the
//! next line while a parenthesis is open or the line ends with an operator or a
//! comma. `#` starts a comment. Declarations may come in any order: all names
//! are collected first, then every expression is built and checked.

mod build;
mod lex;
mod read;

use crate::error::{normalize_text, ModelError};
use lex::{span_in, split_statements};
use read::{Reader, Statements};

use obsan_expr::{Ast, Ctx, Id, Span, Symbol, Q};

/// Explicit time in right-hand sides and outputs: never declared, a known
/// coordinate with derivative 1 (the normal form appends it as a clock state
/// with its own output, as in Martinelli's treatment of time-varying systems).
pub const TIME: &str = "t";

/// What a declared name is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// A dynamic state (has an equation `x' = ...`).
    State,
    /// An unknown constant parameter: part of the analysed state, derivative 0.
    Param,
    /// A known constant (such as `q`): neither state nor input.
    Const,
    Input,
    /// An unknown input (`unknown input w`, or `varying k` for a time-varying
    /// parameter): an unmeasured function of time entering like an input.
    Unknown,
}

impl Kind {
    pub fn word(self) -> &'static str {
        match self {
            Kind::State => "state",
            Kind::Param => "param",
            Kind::Const => "const",
            Kind::Input => "input",
            Kind::Unknown => "unknown input",
        }
    }
}

/// A declared name.
#[derive(Clone, Debug)]
pub struct Decl {
    pub name: String,
    pub kind: Kind,
    pub sym: Symbol,
    /// For constants declared with a value (`const g = 9.81`).
    pub value: Option<Q>,
    /// For derived inputs (`input dwR = rate(wR)`): the defining text, which
    /// the data layer evaluates from the measured inputs. To the analysis a
    /// derived input is an input like any other.
    pub derived: Option<String>,
    /// A start value for fitting, never used by the analysis: for a param a
    /// number (`param T = 0.2`), for a state an expression of the constants
    /// and the inputs' first row of each trajectory (`state va = v`).
    pub start: Option<Start>,
    /// Byte offset of the name in the source.
    pub(crate) at: usize,
}

/// Where fitting starts a param or a state (`Decl::start`).
#[derive(Clone, Debug, PartialEq)]
pub enum Start {
    /// A param's start value (exact as written).
    Number(Q),
    /// A state's start in each trajectory: an expression of the constants
    /// and of the inputs at the trajectory's first row.
    Inputs(String),
}

impl Start {
    /// The `.sys` text after `=`.
    pub fn text(&self) -> String {
        match self {
            Start::Number(q) => q.to_string(),
            Start::Inputs(t) => t.clone(),
        }
    }
}

/// An expression with the map from its text offsets to source offsets.
#[derive(Clone, Debug)]
pub(crate) struct Located {
    pub ast: Ast,
    pub id: Id,
    pub map: Vec<usize>,
}

impl Located {
    pub(crate) fn src_span(&self, s: Span) -> (usize, usize) {
        span_in(&self.map, s)
    }
}

/// A named input restriction, e.g. `restrict q: wR = nu, wL = q*nu`.
#[derive(Clone, Debug)]
pub struct Restriction {
    pub name: String,
    /// Original input index, and its replacement.
    pub(crate) subs: Vec<(usize, Located)>,
    /// The inputs of the restricted system, in order: the original inputs not
    /// replaced, then the new ones in order of appearance.
    pub inputs: Vec<String>,
}

/// A parsed, checked system description.
#[derive(Clone, Debug)]
pub struct System {
    pub name: String,
    pub description: String,
    pub(crate) ctx: Ctx,
    pub decls: Vec<Decl>,
    /// Right-hand side per dynamic state, in the order of `states()`.
    pub(crate) dynamics: Vec<Located>,
    pub(crate) outputs: Vec<(String, Located)>,
    pub restrictions: Vec<Restriction>,
    /// `delay tau`: the dynamics see the inputs `u(t - tau)`, tau a param
    /// (a clock offset between input and output stamps, or an actuation lag).
    pub delay: Option<String>,
    pub(crate) origin: String,
    pub(crate) src: String,
    /// Source text of each dynamics right-hand side, output expression and
    /// restriction statement (for [`System::to_sys_text`]).
    pub(crate) texts: Texts,
    /// Source offset of the first use of time `t` in the dynamics or outputs.
    pub(crate) time_at: Option<usize>,
    /// Source span of the first known input read by an output.
    pub(crate) input_read_at: Option<(usize, usize)>,
}

#[derive(Clone, Debug, Default)]
pub(crate) struct Texts {
    pub dynamics: Vec<String>,
    pub outputs: Vec<String>,
    pub restrictions: Vec<String>,
}

impl System {
    /// Read a system from `.sys` text; `origin` names the file in messages.
    /// A leading byte-order mark is ignored and CRLF or CR line ends read as
    /// lines ([`crate::normalize_text`]).
    pub fn parse(src: &str, origin: &str) -> Result<System, ModelError> {
        let src = normalize_text(src);
        let src: &str = &src;
        let rd = Reader { src, origin };
        let stmts = split_statements(src, origin)?;
        let mut raw = Statements::default();
        for (si, st) in stmts.iter().enumerate() {
            rd.statement(&mut raw, si, st)?;
        }
        let Some(name) = raw.name.take() else {
            return Err(ModelError::general(
                origin,
                "no 'system NAME' line: every .sys file starts by naming its system",
            ));
        };
        let mut ctx = Ctx::new();
        let decls = rd.declarations(&mut ctx, &raw.pending)?;
        let (dynamics, dyn_text) = rd.dynamics(&mut ctx, &stmts, &raw.equations, &decls)?;
        let outputs = rd.outputs(&mut ctx, &raw.outputs, &decls)?;
        let restrictions = rd.restrictions(&mut ctx, &stmts, &raw.restricts, &decls, &outputs)?;
        if let Some((n, at)) = &raw.delay {
            if !decls.iter().any(|d| &d.name == n && d.kind == Kind::Param) {
                return Err(rd.err_src(
                    *at,
                    at + n.len(),
                    format!("delay '{n}': it must be a declared param (an unknown constant)"),
                ));
            }
        }
        let time_at = dynamics
            .iter()
            .chain(outputs.iter().map(|o| &o.1))
            .flat_map(|l| {
                l.ast
                    .idents()
                    .into_iter()
                    .filter(|(n, _)| *n == TIME)
                    .map(|(_, s)| l.src_span(s).0)
                    .collect::<Vec<_>>()
            })
            .min();
        let input_read_at = outputs
            .iter()
            .flat_map(|(_, l)| {
                l.ast
                    .idents()
                    .into_iter()
                    .filter(|(n, _)| decls.iter().any(|d| d.kind == Kind::Input && d.name == *n))
                    .map(|(_, s)| l.src_span(s))
                    .collect::<Vec<_>>()
            })
            .min();
        Ok(System {
            time_at,
            input_read_at,
            name,
            description: raw.description.join(" ").trim().to_string(),
            ctx,
            decls,
            dynamics,
            outputs,
            restrictions,
            delay: raw.delay.map(|d| d.0),
            origin: origin.to_string(),
            src: src.to_string(),
            texts: Texts {
                dynamics: dyn_text,
                outputs: raw
                    .outputs
                    .iter()
                    .map(|o| o.rhs.trim().to_string())
                    .collect(),
                restrictions: raw
                    .restricts
                    .iter()
                    .filter_map(|r| stmts.get(r.stmt))
                    .map(|s| s.text.trim().to_string())
                    .collect(),
            },
        })
    }
}

impl System {
    /// The system as `.sys` text (declarations, dynamics, outputs,
    /// restrictions; comments dropped): what `obsan diagnose` writes for an
    /// extended model, and what [`System::parse`] reads back.
    pub fn to_sys_text(&self) -> String {
        let mut out = format!("system {}\n", self.name);
        if !self.description.is_empty() {
            out.push_str(&format!("description {}\n", self.description));
        }
        for kind in [
            Kind::State,
            Kind::Param,
            Kind::Const,
            Kind::Input,
            Kind::Unknown,
        ] {
            let items: Vec<String> = self
                .decls_of(kind)
                .map(|d| match (&d.value, &d.derived, &d.start) {
                    (Some(v), _, _) => format!("{} = {}", d.name, v),
                    (_, Some(t), _) => format!("{} = {}", d.name, t),
                    (_, _, Some(s)) => format!("{} = {}", d.name, s.text()),
                    _ => d.name.clone(),
                })
                .collect();
            if items.is_empty() {
                continue;
            }
            // Derived inputs one per line: their definitions contain commas.
            if kind == Kind::Input {
                for it in items {
                    out.push_str(&format!("input {it}\n"));
                }
            } else {
                out.push_str(&format!("{} {}\n", kind.word(), items.join(", ")));
            }
        }
        if let Some(d) = &self.delay {
            out.push_str(&format!("delay {d}\n"));
        }
        out.push('\n');
        for (d, rhs) in self.decls_of(Kind::State).zip(&self.texts.dynamics) {
            out.push_str(&format!("{}' = {}\n", d.name, rhs));
        }
        out.push('\n');
        for ((name, _), rhs) in self.outputs.iter().zip(&self.texts.outputs) {
            out.push_str(&format!("output {name} = {rhs}\n"));
        }
        if !self.texts.restrictions.is_empty() {
            out.push('\n');
            for r in &self.texts.restrictions {
                out.push_str(r);
                out.push('\n');
            }
        }
        out
    }

    /// The source text of a state's right-hand side or an output's expression.
    pub fn rhs_text(&self, name: &str) -> Option<&str> {
        if let Some(i) = self.decls_of(Kind::State).position(|d| d.name == name) {
            return self.texts.dynamics.get(i).map(String::as_str);
        }
        let i = self.outputs.iter().position(|o| o.0 == name)?;
        self.texts.outputs.get(i).map(String::as_str)
    }

    pub fn decls_of(&self, kind: Kind) -> impl Iterator<Item = &Decl> {
        self.decls.iter().filter(move |d| d.kind == kind)
    }

    pub fn origin(&self) -> &str {
        &self.origin
    }

    pub fn restriction(&self, name: &str) -> Option<&Restriction> {
        self.restrictions.iter().find(|r| r.name == name)
    }

    /// `true` if a right-hand side or an output uses time `t` explicitly.
    pub fn uses_time(&self) -> bool {
        self.time_at.is_some()
    }

    /// A located refusal of explicit time by a route that cannot handle it
    /// yet (`what` names it): at the first use of `t`, or `None` when the
    /// system does not use time.
    pub fn time_refusal(&self, what: &str) -> Option<ModelError> {
        let at = self.time_at?;
        Some(ModelError::at(
            &self.origin,
            &self.src,
            at,
            at + TIME.len(),
            format!(
                "explicit time 't' is not supported by {what} yet (`obsan rank`, `obsan symmetries`, `obsan show` and `obsan simulate` handle it)"
            ),
        ))
    }

    /// `true` if an output reads a known input (`output y = x*(1 + k*u)`).
    pub fn outputs_read_inputs(&self) -> bool {
        self.input_read_at.is_some()
    }

    /// A located refusal of outputs that read known inputs by a route that
    /// cannot handle them yet (`what` names it): at the first such input, or
    /// `None` when no output reads one.
    pub fn input_output_refusal(&self, what: &str) -> Option<ModelError> {
        let (a, b) = self.input_read_at?;
        Some(ModelError::at(
            &self.origin,
            &self.src,
            a,
            b,
            format!(
                "an output reads the known input '{}': {what} does not handle outputs that read \
                 known inputs yet",
                &self.src[a..b]
            ),
        ))
    }

    /// Output names in declaration order.
    pub fn output_names(&self) -> Vec<&str> {
        self.outputs.iter().map(|o| o.0.as_str()).collect()
    }
}
