//! Exchanging modes for the functions a reduced system not closed needs
//! (module docs of `derive`: independent invariants need not generate the
//! rational invariants the dynamics are written in).

use super::ansatz::{lie, screen_mode, Indep};
use super::{check_deadline, reduce, DeriveOptions, DerivedMode, ModeKind, ModeSpace, Reduced};
use crate::rank::AnalysisError;
use obsan_expr::{Id, RatFun, SplitMix, Q};
use obsan_model::NormalForm;

/// Most exchanges tried (each one a whole reduced system).
pub(super) const MAX_EXCHANGES: usize = 8;

/// Most functions offered to [`exchange`].
const MAX_CANDIDATES: usize = 6;

/// The functions a reduced system not closed needs, each an invariant
/// rational function of the modes' span when the symmetries are certified:
/// the outputs not written in the modes (as they are), then the missing
/// derivatives `L_f g_k` (the fields commute with the symmetries up to
/// their span; without their rational content: `2 x y c` becomes `x y c`),
/// then the generators of the rank test's codistribution. Projected
/// columns are skipped (`L_g m` along an unknown input is not invariant).
pub(super) fn needed_functions(
    nf: &mut NormalForm,
    gens: &[Id],
    sp: &ModeSpace,
    modes: &[DerivedMode],
    red: &Reduced,
    fnames: &[String],
    opts: &DeriveOptions,
) -> Vec<(Id, ModeKind)> {
    let mut out: Vec<(Id, ModeKind)> = Vec::new();
    for (k, (_, e)) in red.outputs.iter().enumerate() {
        if e.is_none() {
            out.push((nf.outputs[k].1, ModeKind::Output));
        }
    }
    for (k, row) in red.derivatives.iter().enumerate() {
        for (i, d) in row.iter().enumerate() {
            if d.is_none() && !red.variant[k][i] && !opts.projected.contains(&fnames[i]) {
                let t = lie(nf, modes[k].expr, &sp.fields[i]);
                out.push((t, ModeKind::LieDerivative));
            }
        }
    }
    out.extend(gens.iter().map(|&g| (g, ModeKind::LieDerivative)));
    // Each function once (up to a constant factor), constants and angles out.
    let mut seen: Vec<RatFun> = Vec::new();
    let mut cands = Vec::new();
    for (t, kind) in out {
        let c = nf.ctx.canon(t);
        if c.is_zero() || c.as_q().is_some() || nf.ctx.is_angle_valued(t) {
            continue;
        }
        let (pn, pd) = (c.numerator().content(), c.denominator().content());
        let qn = nf.ctx.num(Q::new(pd, pn));
        let g0 = nf.ctx.from_canonical(&c);
        let stripped = nf.ctx.mul(&[qn, g0]);
        let sc = nf.ctx.canon(stripped);
        if seen.contains(&sc) || modes.iter().any(|m| nf.ctx.canon(m.expr) == sc) {
            continue;
        }
        seen.push(sc.clone());
        let g = if kind == ModeKind::Output {
            t
        } else {
            nf.ctx.from_canonical(&sc)
        };
        cands.push((g, kind));
        if cands.len() == MAX_CANDIDATES {
            break;
        }
    }
    cands
}

/// Independent invariants need not generate the rational invariants the
/// dynamics need (`x^2 c`, `y^2 c` leave `x y c` only as `sqrt(z1 z2)`;
/// `x^2 + y^2` and `-x sin(theta) + y cos(theta)` leave `x cos(theta) + y
/// sin(theta)` as a square root). One mode (the last non-variable first) is
/// exchanged for a needed function ([`needed_functions`]) satisfying eq.
/// (11) exactly, when the set stays independent (a non-zero minor at a
/// random point), and the exchange is kept when the reduced system then
/// closes (`open` false).
pub(super) fn exchange(
    nf: &mut NormalForm,
    sp: &ModeSpace,
    modes: &[DerivedMode],
    cands: &[(Id, ModeKind)],
    rng: &mut SplitMix,
    opts: &DeriveOptions,
    open: &dyn Fn(&Reduced) -> bool,
) -> Result<Option<(Vec<DerivedMode>, Reduced)>, AnalysisError> {
    let mut tries = 0;
    for &(g, kind) in cands {
        if !screen_mode(nf, sp.w_ids, g, opts.seed)? || !invariant(nf, sp.w_ids, g) {
            continue;
        }
        let gc = nf.ctx.canon(g);
        for j in (0..modes.len()).rev() {
            if modes[j].kind == ModeKind::Variable || modes[j].angle {
                continue;
            }
            if tries >= MAX_EXCHANGES {
                return Ok(None);
            }
            // Soft, like the reduced system's own deadline: the modes found
            // stand, reported as not closed.
            match check_deadline(opts, "the mode exchange", modes.len()) {
                Err(AnalysisError::Timeout(_)) => return Ok(None),
                r => r?,
            }
            let mut indep = Indep {
                grads: Vec::new(),
                seed: opts.seed ^ 0x6578_6368,
            };
            let mut ok = true;
            for (l, m) in modes.iter().enumerate() {
                if l != j {
                    ok &= indep.raises_rank(nf, m.expr)?;
                }
            }
            if !ok || !indep.raises_rank(nf, g)? {
                continue;
            }
            tries += 1;
            let den = gc.denominator().clone();
            let mut m2 = modes.to_vec();
            m2[j] = DerivedMode {
                name: modes[j].name.clone(),
                expr: g,
                text: nf.ctx.ratfun_text_factored(&gc),
                kind,
                angle: false,
                domain: if den.is_constant() {
                    "everywhere".into()
                } else {
                    format!("where {} != 0", nf.ctx.poly_text(&den))
                },
            };
            let r2 = reduce(nf, sp, &m2, rng, opts)?;
            if !open(&r2) {
                return Ok(Some((m2, r2)));
            }
            if r2.timed_out {
                return Ok(None);
            }
        }
    }
    Ok(None)
}

/// Eq. (11) exactly: `w(g) = 0` in canonical form for every symmetry.
fn invariant(nf: &mut NormalForm, w_ids: &[Vec<Id>], g: Id) -> bool {
    w_ids.iter().all(|w| {
        let t = lie(nf, g, w);
        nf.ctx.canon(t).is_zero()
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::derive::{reduce, ModeSpace};
    use obsan_model::System;

    /// Polynomial modes named and written as given.
    fn polynomial_modes(nf: &mut NormalForm, texts: &[(&str, &str)]) -> Vec<DerivedMode> {
        texts
            .iter()
            .map(|(n, t)| DerivedMode {
                name: n.to_string(),
                expr: nf.parse_expr(t, false).unwrap(),
                text: t.to_string(),
                kind: ModeKind::Polynomial,
                angle: false,
                domain: "everywhere".into(),
            })
            .collect()
    }

    /// `x^2 c` and `y^2 c` are independent invariants of the scaling
    /// `(x, y, c) -> (l x, l y, c / l^2)`, but `L_u (x^2 c) = 2 c x y` is
    /// `±2 sqrt(z1 z2)` in them: no rational form. Exchanging `z2` for that
    /// derivative without its content (`c x y`) closes the system, by hand:
    /// `z1' = 2 u z2`, `z2' = u c (y^2 - x^2) = u (z2^2/z1 - z1)`, `h = z1`.
    #[test]
    fn exchange_replaces_a_mode_the_dynamics_cannot_use() {
        let src = "system t\nstate x, y\nparam c\ninput u\nx' = u*y\ny' = -u*x\noutput h = c*x^2\n";
        let sys = System::parse(src, "t.sys").unwrap();
        let mut nf = sys.normal_form(None, &[]).unwrap();
        let (_, fields) = crate::fields::field_names(&mut nf);
        let w: Vec<Vec<Id>> = vec![["x", "y", "-2*c"]
            .iter()
            .map(|t| nf.parse_expr(t, false).unwrap())
            .collect()];
        let modes = polynomial_modes(&mut nf, &[("z1", "x^2*c"), ("z2", "y^2*c")]);
        let sp = ModeSpace {
            fields: &fields,
            consts: &[],
            used_vars: &[],
            w_ids: &w,
        };
        let opts = DeriveOptions::default();
        let mut rng = SplitMix(5);
        let red = reduce(&mut nf, &sp, &modes, &mut rng, &opts).unwrap();
        let names = vec!["u".to_string()];
        let open = |r: &Reduced| !r.closed_except(&names, &[]);
        assert!(red.derivatives[0][0].is_none() && open(&red));
        let cands = needed_functions(&mut nf, &[], &sp, &modes, &red, &names, &opts);
        let (m2, r2) = exchange(&mut nf, &sp, &modes, &cands, &mut rng, &opts, &open)
            .unwrap()
            .expect("an exchange closes");
        assert!(!open(&r2), "{:?}", r2.derivatives);
        let want = nf.parse_expr("c*x*y", false).unwrap();
        assert_eq!(nf.ctx.canon(m2[1].expr), nf.ctx.canon(want));
        assert_eq!(m2[0].expr, modes[0].expr);
    }

    /// The planar vehicle pushed by an unknown force (vio_planar_force.sys,
    /// wx and wy read as inputs and projected afterwards): `x^2 + y^2`,
    /// `-x vy + y vx`, `x vx + y vy` and `z4 = -x sin(theta) + y cos(theta)`
    /// are independent invariants of the rotation `(-y, x, -vy, vx, 1)`, but
    /// the output `zx = -(x cos(theta) + y sin(theta))` and `L_omega z4 = -zx`
    /// are `+-sqrt(z1 - z4^2)` in them. By hand, with the output in place of
    /// `x^2 + y^2` everything is rational: `p . v` and `p x v` with `R^T p =
    /// -(zx, -z4)` give the body velocity `R^T v` over `zx^2 + z4^2`, and
    /// `zx' = -(R^T v)_x - omega z4`, `z4' = (R^T v)_y + omega zx`. The
    /// output is offered first and taken; the unknown inputs' columns (`L_wx
    /// (x vx + y vy) = x`, not invariant) do not count.
    #[test]
    fn exchange_takes_a_needed_output_first() {
        let src = "system v\nstate x, y, vx, vy, theta\ninput omega, ax, ay, wx, wy\n\
                   x' = vx\ny' = vy\nvx' = cos(theta)*ax - sin(theta)*ay + wx\n\
                   vy' = sin(theta)*ax + cos(theta)*ay + wy\ntheta' = omega\n\
                   output zx = -(cos(theta)*x + sin(theta)*y)\n\
                   output zy = sin(theta)*x - cos(theta)*y\n";
        let sys = System::parse(src, "v.sys").unwrap();
        let mut nf = sys.normal_form(None, &[]).unwrap();
        let (names, fields) = crate::fields::field_names(&mut nf);
        let w: Vec<Vec<Id>> = vec![["-y", "x", "-vy", "vx", "1"]
            .iter()
            .map(|t| nf.parse_expr(t, false).unwrap())
            .collect()];
        let texts = [
            ("z1", "x^2 + y^2"),
            ("z2", "-x*vy + y*vx"),
            ("z3", "x*vx + y*vy"),
            ("z4", "-x*sin(theta) + y*cos(theta)"),
        ];
        let modes = polynomial_modes(&mut nf, &texts);
        let sp = ModeSpace {
            fields: &fields,
            consts: &[],
            used_vars: &[],
            w_ids: &w,
        };
        let opts = DeriveOptions {
            projected: vec!["wx".into(), "wy".into()],
            ..DeriveOptions::default()
        };
        let mut rng = SplitMix(5);
        let open = |r: &Reduced| !r.closed_except(&names, &opts.projected);
        let red = reduce(&mut nf, &sp, &modes, &mut rng, &opts).unwrap();
        assert!(
            red.outputs[0].1.is_none() && open(&red),
            "{:?}",
            red.outputs
        );
        let cands = needed_functions(&mut nf, &[], &sp, &modes, &red, &names, &opts);
        let zx = nf.outputs[0].1;
        assert_eq!(cands[0], (zx, ModeKind::Output));
        let (m2, r2) = exchange(&mut nf, &sp, &modes, &cands, &mut rng, &opts, &open)
            .unwrap()
            .expect("an exchange closes");
        assert!(!open(&r2), "{:?}", r2.derivatives);
        assert_eq!(m2[0].expr, zx, "x^2 + y^2 is the mode exchanged");
        assert_eq!(
            m2[1..].iter().map(|m| m.expr).collect::<Vec<_>>(),
            modes[1..].iter().map(|m| m.expr).collect::<Vec<_>>()
        );
    }
}
