//! One circular trajectory: the closed-form observation function (section
//! IV-C), the deterministic method DET (section V-A, Algorithm 1) and the
//! least-squares refinement LS (section V-B).
//!
//! We fit the sign-free form of ERRATA.md instead of eqs. (26)-(29), whose
//! branch signs (Sw, SV, Sy, Sp) flip at nodes and k-nodes:
//! `beta(s) = atan2(eps sin t, 1 - eps cos t) - L + pi/2`, `t = t0 + xi_q s`,
//! with `eps = |OF| / |OC|` (feature and camera distances from the circle's
//! centre) and `L` the exact `L = psi - atan2(xi_q - eta_q sin phi, eta_q cos phi)`
//! (so L is known modulo 2 pi, not pi). The paper's `k` and `c` follow:
//! `k = xi_q / (1 - eps^2)` and, comparing with (29), `A = -tan(alpha)`
//! (`alpha` the atan2 term), hence by (24)
//! `V = xi_q + d(alpha)/ds`, the values `A0`, `V0` at s = 0 and `c` by (31).

use crate::error::CalibError::{self, Degenerate};
use nalgebra::{DMatrix, DVector, Matrix4, SMatrix, SVector};
use obsan_data::wrap;
use obsan_fit::{minimise, LmOptions};
use std::f64::consts::PI;

/// Bearings of one trajectory against the curve length `s = integral of wR dt`
/// (eq. 17: nu = wR), in radians of right-wheel rotation.
#[derive(Clone, Debug)]
pub struct ArcData {
    pub s: Vec<f64>,
    pub beta: Vec<f64>,
    /// The time of each bearing (s).
    pub t: Vec<f64>,
}

/// The parameters of the sign-free observation function.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Closed {
    pub xi_q: f64,
    /// L in (-pi, pi].
    pub l: f64,
    pub t0: f64,
    pub eps: f64,
}

impl Closed {
    /// `(alpha, d alpha / dt, d alpha / d eps)` at curve length s.
    fn alpha(&self, s: f64) -> (f64, f64, f64) {
        let t = self.t0 + self.xi_q * s;
        let (st, ct) = t.sin_cos();
        let e = self.eps;
        let d = 1.0 - 2.0 * e * ct + e * e;
        ((e * st).atan2(1.0 - e * ct), (e * ct - e * e) / d, st / d)
    }

    /// The observation function at curve length s, in (-pi, pi].
    pub fn beta(&self, s: f64) -> f64 {
        wrap(self.alpha(s).0 - self.l + PI / 2.0)
    }

    /// `k = xi_q / (1 - eps^2)` (ERRATA.md; a first integral of eq. 24).
    pub fn k(&self) -> f64 {
        self.xi_q / (1.0 - self.eps * self.eps)
    }

    /// `(A, V)` of eq. (23) at curve length s: `A = -tan(alpha)`,
    /// `V = xi_q (1 - eps cos t) / (1 - 2 eps cos t + eps^2)`.
    pub fn av(&self, s: f64) -> (f64, f64) {
        let t = self.t0 + self.xi_q * s;
        let (st, ct) = t.sin_cos();
        let e = self.eps;
        let a = -(e * st) / (1.0 - e * ct);
        let v = self.xi_q * (1.0 - e * ct) / (1.0 - 2.0 * e * ct + e * e);
        (a, v)
    }

    /// The paper's `c` (eq. 31, sign-general form), in (-pi/2, pi/2].
    pub fn c(&self) -> f64 {
        let (a0, v0) = self.av(0.0);
        let k = self.k();
        let sw = -a0.signum() * v0.signum();
        (sw * ((2.0 * k - self.xi_q) * v0 - self.xi_q * k) / (self.xi_q * a0 * v0)).atan()
    }

    fn to_vec(self) -> SVector<f64, 4> {
        SVector::from([self.xi_q, self.l, self.t0, self.eps])
    }
    fn from_vec(v: &SVector<f64, 4>) -> Closed {
        Closed {
            xi_q: v[0],
            l: wrap(v[1]),
            t0: wrap(v[2]),
            eps: v[3],
        }
    }
}

/// DET's outcome with the intermediate curves (Figures 5-7).
#[derive(Clone, Debug)]
pub struct Det {
    pub closed: Closed,
    /// Period in s (eq. 35).
    pub period: f64,
    /// The node found by Algorithm 1.
    pub node: f64,
    /// The two mirror points used by eq. (38), if inside the data.
    pub mirror: Option<(f64, f64)>,
    /// sigma(s_c) of Algorithm 1: (s_c, sigma).
    pub sigma_curve: Vec<(f64, f64)>,
}

/// Bearing at s by linear interpolation of the unwrapped bearings, read
/// through a uniform table (one lookup per query instead of a search).
struct Interp {
    s0: f64,
    s_last: f64,
    unwrapped: Vec<f64>,
    first: f64,
    last: f64,
    /// Values at `s0 + i h`. Their (cos 2 beta, sin 2 beta) are computed
    /// per query, not tabulated: a table of 8 entries per bearing held 192
    /// bytes a bearing with them (a 10^6-bearing trajectory: 192 MB).
    table: Vec<f64>,
    h: f64,
}

impl Interp {
    fn new(d: &ArcData) -> Interp {
        let n = d.s.len();
        let mut unwrapped: Vec<f64> = Vec::with_capacity(n);
        for (i, &b) in d.beta.iter().enumerate() {
            if i == 0 {
                unwrapped.push(b);
            } else {
                let prev = unwrapped[i - 1];
                unwrapped.push(prev + wrap(b - prev));
            }
        }
        let (s0, s_last) = (d.s[0], d.s[n - 1]);
        let m = (8 * n).max(1024);
        let h = (s_last - s0) / (m - 1) as f64;
        let mut table = Vec::with_capacity(m);
        let slope = |i: usize| -> f64 {
            let (l, r) = (i.saturating_sub(1), (i + 1).min(n - 1));
            let ds = d.s[r] - d.s[l];
            if ds > 0.0 {
                (unwrapped[r] - unwrapped[l]) / ds
            } else {
                0.0
            }
        };
        let mut j = 1usize;
        for i in 0..m {
            let x = s0 + i as f64 * h;
            while j + 1 < n && d.s[j] < x {
                j += 1;
            }
            // Cubic Hermite between samples (slopes by central differences):
            // DET reads beta between sparse bearings (30 on a q = -1 loop).
            let (a, b) = (d.s[j - 1], d.s[j]);
            let w = b - a;
            let f = if w > 0.0 {
                ((x - a) / w).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let (m0, m1) = (slope(j - 1) * w, slope(j) * w);
            let (y0, y1) = (unwrapped[j - 1], unwrapped[j]);
            let (f2, f3) = (f * f, f * f * f);
            table.push(
                (2.0 * f3 - 3.0 * f2 + 1.0) * y0
                    + (f3 - 2.0 * f2 + f) * m0
                    + (-2.0 * f3 + 3.0 * f2) * y1
                    + (f3 - f2) * m1,
            );
        }
        Interp {
            s0,
            s_last,
            first: unwrapped[0],
            last: unwrapped[n - 1],
            unwrapped,
            table,
            h,
        }
    }
    fn at(&self, s: f64) -> Option<f64> {
        if !(s >= self.s0 && s <= self.s_last) || self.h <= 0.0 {
            return None;
        }
        let x = (s - self.s0) / self.h;
        let i = (x as usize).min(self.table.len() - 2);
        let f = x - i as f64;
        Some(self.table[i] + f * (self.table[i + 1] - self.table[i]))
    }
    /// `(cos 2 beta, sin 2 beta)` at s, periodically extended like [`Interp::at_mod`].
    fn at_mod2(&self, s: f64, period: Option<f64>) -> Option<(f64, f64)> {
        let x = match period {
            Some(p) => self.s0 + modulo(s - self.s0, p),
            None => s,
        };
        if x >= self.s0 && x <= self.s_last && self.h > 0.0 {
            let y = (x - self.s0) / self.h;
            let i = (y as usize).min(self.table.len() - 2);
            let f = y - i as f64;
            let doubled = |b: f64| {
                let (s, c) = (2.0 * b).sin_cos();
                (c, s)
            };
            let (a, b) = (doubled(self.table[i]), doubled(self.table[i + 1]));
            return Some((a.0 + f * (b.0 - a.0), a.1 + f * (b.1 - a.1)));
        }
        self.at_mod(s, period).map(|b| {
            let (s2, c2) = (2.0 * b).sin_cos();
            (c2, s2)
        })
    }
    /// Modulo 2 pi, with the data extended periodically with period `period`
    /// when they cover a whole period (Algorithm 1 reflects s about a node
    /// anywhere in the loop).
    fn at_mod(&self, s: f64, period: Option<f64>) -> Option<f64> {
        let Some(p) = period else { return self.at(s) };
        let x = self.s0 + modulo(s - self.s0, p);
        if x <= self.s_last {
            return self.at(x);
        }
        // The gap between the last sample and the first one a period later.
        let f = (x - self.s_last) / (self.s0 + p - self.s_last);
        Some(self.last + f * wrap(self.first - self.last))
    }
}

/// The minimiser of a unimodal `f` on `[a, b]` by golden section, one new
/// evaluation per step (`steps` steps shrink the bracket by 0.618^steps).
///
/// Not the least-squares core: both uses minimise over one variable a
/// function without a Jacobian at hand (the algebraic residual of the
/// implicit observation equation over `xi_q`, the other unknowns eliminated
/// exactly at each value, see [`Implicit`]; Algorithm 1's spread statistic
/// over the node), inside a bracket a grid scan found; the core then
/// refines the whole estimate (LS, section V-B). Not argmin's
/// `GoldenSectionSearch` either: it stops at a tolerance through its
/// executor, while a fixed number of steps here makes the work and the
/// estimate the same for every data set size, in fifteen lines.
fn golden_min(f: impl Fn(f64) -> f64, mut a: f64, mut b: f64, steps: usize) -> f64 {
    let g = (5f64.sqrt() - 1.0) / 2.0;
    let (mut c1, mut c2) = (b - g * (b - a), a + g * (b - a));
    let (mut f1, mut f2) = (f(c1), f(c2));
    for _ in 0..steps {
        if f1 < f2 {
            b = c2;
            (c2, f2) = (c1, f1);
            c1 = b - g * (b - a);
            f1 = f(c1);
        } else {
            a = c1;
            (c1, f1) = (c2, f2);
            c2 = a + g * (b - a);
            f2 = f(c2);
        }
    }
    (a + b) / 2.0
}

/// `x` modulo `p > 0` in `[0, p)`, by one floor: `rem_euclid` goes through
/// `fmod`, which dominated Algorithm 1's inner loop.
fn modulo(x: f64, p: f64) -> f64 {
    let r = x - p * (x / p).floor();
    if r >= p {
        r - p
    } else if r < 0.0 {
        r + p
    } else {
        r
    }
}

/// Mean and standard deviation of angles known modulo pi (doubled-angle circular statistics).
fn circular_mod_pi(angles: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    let (mut c, mut s, mut n) = (0.0, 0.0, 0usize);
    for a in angles {
        c += (2.0 * a).cos();
        s += (2.0 * a).sin();
        n += 1;
    }
    if n < 5 {
        return None;
    }
    let r = ((c * c + s * s).sqrt() / n as f64).clamp(1e-300, 1.0);
    Some((s.atan2(c) / 2.0, (-2.0 * r.ln()).sqrt() / 2.0))
}

/// The algebraic residual of the implicit observation equation for a given
/// `xi_q`: `eps sin(xi_q s + beta + u) = sin(beta + L')` (from the sign-free
/// form, `u = t0 + L'`, `L' = L - pi/2`) is linear and homogeneous in
/// `v = (eps cos u, eps sin u, cos L', sin L')`. With `M` the normal matrix,
/// the minimum of `v^T M v / n` over `v` with `(v3, v4)` a unit vector (the
/// first two eliminated by their Schur complement) measures how well any
/// (eps, t0, L) fits. Returns it with the minimising v.
///
/// Evaluated for many `xi_q` on the same data: the (sin beta, cos beta)
/// block of the normal matrix does not depend on `xi_q`, and
/// `sin^2 + cos^2 = 1` gives the other diagonal block's trace, so each
/// bearing adds six products per `xi_q` instead of a 4x4 outer product.
struct Implicit<'a> {
    d: &'a ArcData,
    sb: Vec<(f64, f64)>,
    c: (f64, f64, f64),
}

impl<'a> Implicit<'a> {
    fn new(d: &'a ArcData) -> Implicit<'a> {
        let sb: Vec<(f64, f64)> = d.beta.iter().map(|b| b.sin_cos()).collect();
        let mut c = (0.0, 0.0, 0.0);
        for &(s, co) in &sb {
            c.0 += s * s;
            c.1 += s * co;
            c.2 += co * co;
        }
        Implicit { d, sb, c }
    }

    /// The normal matrix from `(sin, cos)(xi_q s_i + beta_i)` of each bearing.
    fn normal(&self, rows: impl Iterator<Item = (f64, f64)>) -> Matrix4<f64> {
        let (mut a00, mut a01) = (0.0, 0.0);
        let (mut b02, mut b03, mut b12, mut b13) = (0.0, 0.0, 0.0, 0.0);
        for ((sa, ca), &(sbi, cbi)) in rows.zip(&self.sb) {
            a00 += sa * sa;
            a01 += sa * ca;
            b02 -= sa * sbi;
            b03 -= sa * cbi;
            b12 -= ca * sbi;
            b13 -= ca * cbi;
        }
        let n = self.sb.len() as f64;
        let (c22, c23, c33) = self.c;
        #[rustfmt::skip]
        let m = Matrix4::new(
            a00, a01, b02, b03,
            a01, n - a00, b12, b13,
            b02, b12, c22, c23,
            b03, b13, c23, c33,
        );
        m
    }

    /// Golden section on `[xi_start - h, xi_start + h]`, one new evaluation
    /// per step; 24 steps narrow it to 2e-5 h (LS refines further). Returns
    /// `xi_q` and its algebraic solution.
    fn refine(&self, xi_start: f64, h: f64) -> (f64, SVector<f64, 4>) {
        let xi_q = golden_min(|x| self.at(x).0, xi_start - h, xi_start + h, 24);
        (xi_q, self.at(xi_q).1)
    }

    fn at(&self, xi_q: f64) -> (f64, SVector<f64, 4>) {
        let d = self.d;
        let rows =
            d.s.iter()
                .zip(&d.beta)
                .map(|(&s, &b)| (xi_q * s + b).sin_cos());
        schur_min(&self.normal(rows), d.s.len())
    }

    /// `(residual, xi_q)` at `xi_0 + j dxi`, `j < count`, with the angles
    /// advanced by rotation (no trigonometric call inside the loop).
    fn scan(&self, xi0: f64, dxi: f64, count: usize) -> Vec<(f64, f64)> {
        let d = self.d;
        let rot: Vec<(f64, f64)> = d.s.iter().map(|&s| (dxi * s).sin_cos()).collect();
        let mut cur: Vec<(f64, f64)> =
            d.s.iter()
                .zip(&d.beta)
                .map(|(&s, &b)| (xi0 * s + b).sin_cos())
                .collect();
        let mut out = Vec::with_capacity(count);
        for j in 0..count {
            if j % 64 == 63 {
                // Re-anchor against rounding drift (1e-16 per rotation).
                for ((c, &s), &b) in cur.iter_mut().zip(&d.s).zip(&d.beta) {
                    *c = ((xi0 + j as f64 * dxi) * s + b).sin_cos();
                }
            }
            let m = self.normal(cur.iter().copied());
            out.push((schur_min(&m, d.s.len()).0, xi0 + j as f64 * dxi));
            for (c, r) in cur.iter_mut().zip(&rot) {
                let (s, co) = *c;
                *c = (s * r.1 + co * r.0, co * r.1 - s * r.0);
            }
        }
        out
    }
}

/// See [`Implicit`]: `min over unit w of w^T (C - B^T A^-1 B) w`, where
/// `M = [[A, B], [B^T, C]]` in 2x2 blocks, and the minimiser `(-A^-1 B w, w)`.
fn schur_min(m: &Matrix4<f64>, n: usize) -> (f64, SVector<f64, 4>) {
    let a = m.fixed_view::<2, 2>(0, 0).into_owned();
    let b = m.fixed_view::<2, 2>(0, 2).into_owned();
    let c = m.fixed_view::<2, 2>(2, 2).into_owned();
    let Some(ainv) = a.try_inverse() else {
        return (f64::INFINITY, SVector::zeros());
    };
    let sch = c - b.transpose() * ainv * b;
    // Smallest eigenpair of the symmetric 2x2 matrix.
    let (p, q, r) = (sch[(0, 0)], sch[(0, 1)], sch[(1, 1)]);
    let mean = (p + r) / 2.0;
    let rad = (((p - r) / 2.0).powi(2) + q * q).sqrt();
    let lam = mean - rad;
    let w = if q.abs() > 1e-300 {
        nalgebra::Vector2::new(lam - r, q)
    } else if p <= r {
        nalgebra::Vector2::new(1.0, 0.0)
    } else {
        nalgebra::Vector2::new(0.0, 1.0)
    };
    let w = w / w.norm();
    let top = -(ainv * b * w);
    (lam / n as f64, SVector::from([top[0], top[1], w[0], w[1]]))
}

/// At most `max` samples, evenly spread over the data.
fn subsample(d: &ArcData, max: usize) -> ArcData {
    let n = d.s.len();
    if n <= max {
        return d.clone();
    }
    let idx = (0..max).map(|i| i * (n - 1) / (max - 1));
    ArcData {
        s: idx.clone().map(|i| d.s[i]).collect(),
        beta: idx.clone().map(|i| d.beta[i]).collect(),
        t: idx.map(|i| d.t[i]).collect(),
    }
}

/// Root-mean-square wrapped residual of `c` on the data.
pub(crate) fn rms(c: &Closed, d: &ArcData) -> f64 {
    let ss: f64 =
        d.s.iter()
            .zip(&d.beta)
            .map(|(&s, &b)| wrap(b - c.beta(s)).powi(2))
            .sum();
    (ss / d.s.len().max(1) as f64).sqrt()
}

/// Of the closed forms that differ from `c` only in L (one of `ls`), the one
/// that fits best, with its score: the median absolute residual, so that a
/// few gross errors (a bearing wrapped on the wrong side of +-pi by a scale
/// error, an outlier) do not choose the period or the branch. L only shifts
/// the bearing, so the curve `alpha(s)` is computed once for all of them.
#[allow(clippy::expect_used)] // `ls` is one of the callers' four fixed candidates
fn best_l(c: Closed, ls: &[f64], d: &ArcData) -> (f64, Closed) {
    let resid: Vec<f64> =
        d.s.iter()
            .zip(&d.beta)
            .map(|(&s, &b)| b - c.alpha(s).0 - PI / 2.0)
            .collect();
    let mut abs = vec![0.0; resid.len()];
    ls.iter()
        .map(|&l| {
            for (a, r) in abs.iter_mut().zip(&resid) {
                *a = wrap(r + l).abs();
            }
            let mid = abs.len() / 2;
            let e = if abs.is_empty() {
                f64::INFINITY
            } else {
                *abs.select_nth_unstable_by(mid, f64::total_cmp).1
            };
            (e, Closed { l, ..c })
        })
        .min_by(|a, b| a.0.total_cmp(&b.0))
        .expect("at least one L")
}

/// The deterministic method (section V-A): xi_q from the period of the
/// observation function, a node by Algorithm 1, L by eq. (37), k by eq. (38)
/// from two consecutive mirror points; the discrete ambiguities (L modulo
/// pi/2, which node) are settled by the residual of the closed form.
///
/// The period is found by scanning xi_q (both signs, from half a turn to six
/// turns over the data) for the smallest algebraic residual of the implicit
/// observation equation (see [`Implicit`]), refined by golden section: a
/// non-iterative, initialisation-free reading of the period that also works
/// when the data cover a single loop, where a period cannot be seen by
/// comparing the signal with a shifted copy of itself.
pub fn det(d: &ArcData) -> Result<Det, CalibError> {
    let n = d.s.len();
    if n < 10 {
        return Err(Degenerate(format!(
            "only {n} bearings: at least 10 are needed"
        )));
    }
    let span = d.s[n - 1] - d.s[0];
    if span.is_nan() || span <= 0.0 {
        return Err(Degenerate(
            "the right wheel did not turn: no curve length, nothing to estimate".into(),
        ));
    }
    // Bearing variation: a constant bearing reveals nothing (feature at the
    // circle's centre, or a camera that sees it always in the same direction).
    let interp = Interp::new(d);
    let (_, spread) =
        circular_mod_pi(interp.unwrapped.iter().map(|b| b / 2.0)).unwrap_or((0.0, 0.0));
    if spread < 1e-6 {
        return Err(Degenerate(
            "the bearing is constant: xi_q, L and k cannot be estimated (the feature is at the centre of the circle, or the robot does not turn)".into(),
        ));
    }
    // Scan the total turn over the data, in steps small against a radian, on
    // at most 200 evenly chosen bearings (LS refines on all of them).
    let sub = subsample(d, 200);
    // From 0.7 turn: the implicit equation degenerates as xi_q -> 0 (eps = 1,
    // u = L' fits anything), so shorter turns would win on noise alone; and
    // DET needs about one loop of data anyway (eq. 35).
    let (lo, hi, step) = (1.4 * PI, 12.0 * PI, 0.1);
    let implicit = Implicit::new(&sub);
    let mut grid = Vec::new();
    for sign in [1.0, -1.0] {
        grid.extend(implicit.scan(
            sign * lo / span,
            sign * step / span,
            ((hi - lo) / step) as usize,
        ));
    }
    let mut sorted: Vec<f64> = grid.iter().map(|g| g.0).collect();
    sorted.sort_by(f64::total_cmp);
    let median = sorted[sorted.len() / 2];
    // Noise biases the algebraic residual: keep the three deepest local minima
    // and let the closed form's fit choose (a wrong period fits badly).
    let mut minima: Vec<(f64, f64)> = (0..grid.len())
        .filter(|&i| {
            let same_sign = |j: usize| grid[j].1.signum() == grid[i].1.signum();
            // Interior minima only: an edge of the scan is not a period.
            i > 0
                && i + 1 < grid.len()
                && same_sign(i - 1)
                && same_sign(i + 1)
                && grid[i - 1].0 >= grid[i].0
                && grid[i + 1].0 >= grid[i].0
        })
        .map(|i| grid[i])
        .collect();
    minima.sort_by(|a, b| a.0.total_cmp(&b.0));
    minima.truncate(3);
    // Rank the candidates by how well the closed form that the algebraic
    // solution gives fits the bearings; the rest of DET (Algorithm 1, eqs.
    // 37-38) runs on the best one, on the next only if that one fails.
    let mut ranked: Vec<(f64, f64, SVector<f64, 4>)> = minima
        .into_iter()
        .filter(|m| m.0 <= 0.5 * median)
        .map(|(_, xi0)| {
            let (xi_q, v) = implicit.refine(xi0, step / span);
            let [c, other] = algebraic_closed(xi_q, &v);
            let (e, _) = best_l(c, &[c.l, other.l], d);
            (e, xi_q, v)
        })
        .collect();
    ranked.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut last_err = None;
    for (_, xi_q, v) in ranked {
        match det_from(d, xi_q, &v, span, &interp) {
            Ok(r) => return Ok(r),
            Err(e) => last_err = Some(e),
        }
    }
    Err(last_err.unwrap_or_else(|| {
        Degenerate(format!(
            "no period found in the bearings (best algebraic residual vs median {median:.3e}): xi_q cannot be estimated"
        ))
    }))
}

/// DET with the period known (`xi_q` from the other trajectories, for
/// example): Algorithm 1, eqs. (37) and (38) at that `xi_q`. For a
/// trajectory whose own period reading failed.
pub fn det_at(d: &ArcData, xi_q: f64) -> Result<Det, CalibError> {
    let n = d.s.len();
    if n < 10 || !xi_q.is_finite() || xi_q == 0.0 {
        return Err(Degenerate(format!(
            "DET at a given period needs 10 bearings and a finite, non-zero xi_q (have {n}, {xi_q})"
        )));
    }
    let span = d.s[n - 1] - d.s[0];
    let interp = Interp::new(d);
    let sub = subsample(d, 200);
    let (_, v) = Implicit::new(&sub).at(xi_q);
    det_from(d, xi_q, &v, span, &interp)
}

/// The two closed forms (L and L + pi) of an algebraic solution
/// `v = (eps cos u, eps sin u, cos L', sin L')`, `u = t0 + L'`,
/// `L' = L - pi/2` (see [`Implicit`]; `-v` is the same solution).
fn algebraic_closed(xi_q: f64, v: &SVector<f64, 4>) -> [Closed; 2] {
    let lp = v[3].atan2(v[2]);
    let eps = v[0].hypot(v[1]);
    let t0 = wrap(v[1].atan2(v[0]) - lp);
    let c = |l: f64| Closed {
        xi_q,
        l: wrap(l),
        t0,
        eps,
    };
    [c(lp + PI / 2.0), c(lp + 1.5 * PI)]
}

/// DET from a refined period candidate and its algebraic solution `vec`:
/// Algorithm 1, (37), (38).
fn det_from(
    d: &ArcData,
    xi_q: f64,
    vec: &SVector<f64, 4>,
    span: f64,
    interp: &Interp,
) -> Result<Det, CalibError> {
    let n = d.s.len();
    let period = 2.0 * PI / xi_q.abs();
    // Algorithm 1: sigma(s_c) of beta(s) + beta(2 s_c - s) (mod pi) for s_c
    // over half a period (nodes are half a period apart).
    let s0 = d.s[0];
    // Periodic extension when the data cover a period (less the mean bearing interval).
    let covers = span >= period * (1.0 - 1.5 / n as f64);
    let wrap_period = covers.then_some(period);
    // Algorithm 1's statistic of theta = beta(s) + beta(2 s_c - s) (mod pi),
    // by doubled angles: e^{2i theta} = e^{2i beta(s)} e^{2i beta(s_hat)}.
    let doubled = |data: &ArcData| -> Vec<(f64, f64, f64)> {
        data.s
            .iter()
            .zip(&data.beta)
            .map(|(&s, &b)| {
                let (s2, c2) = (2.0 * b).sin_cos();
                (s, c2, s2)
            })
            .collect()
    };
    let pair_stats = |sc: f64, data: &[(f64, f64, f64)]| -> Option<(f64, f64)> {
        let ns = data.len();
        let min_pairs = if covers { ns / 2 } else { (ns / 3).max(5) };
        let (mut c, mut sn, mut k) = (0.0, 0.0, 0usize);
        for &(s, c2, s2) in data {
            if let Some((ch, sh)) = interp.at_mod2(2.0 * sc - s, wrap_period) {
                c += c2 * ch - s2 * sh;
                sn += s2 * ch + c2 * sh;
                k += 1;
            }
        }
        if k < min_pairs.max(5) {
            return None;
        }
        let r = ((c * c + sn * sn).sqrt() / k as f64).clamp(1e-300, 1.0);
        Some((sn.atan2(c) / 2.0, (-2.0 * r.ln()).sqrt() / 2.0))
    };
    let sigma_at = |sc: f64, data: &[(f64, f64, f64)]| pair_stats(sc, data).map(|p| p.1);
    // Coarse grid on the subsample, then golden section on all bearings.
    let grid = 150;
    let width = (period / 2.0).min(span);
    let coarse = doubled(&subsample(d, 150));
    let all = doubled(d);
    let sigma_curve: Vec<(f64, f64)> = (0..grid)
        .filter_map(|i| {
            let sc = s0 + (i as f64 + 0.5) / grid as f64 * width;
            sigma_at(sc, &coarse).map(|v| (sc, v))
        })
        .collect();
    let Some(imin) =
        (0..sigma_curve.len()).min_by(|&i, &j| sigma_curve[i].1.total_cmp(&sigma_curve[j].1))
    else {
        return Err(Degenerate(
            "too few bearings pairs around any node candidate (Algorithm 1)".into(),
        ));
    };
    let h = width / grid as f64;
    let full = |sc: f64| sigma_at(sc, &all).unwrap_or(f64::INFINITY);
    let node = golden_min(
        full,
        sigma_curve[imin].0 - 1.5 * h,
        sigma_curve[imin].0 + 1.5 * h,
        24,
    );
    // Eq. (37): beta(s) + beta(s_hat) = -2 L (mod pi), at the node.
    let (mean2l, _) = pair_stats(node, &all)
        .ok_or_else(|| Degenerate("no pairs of bearings around the node (Algorithm 1)".into()))?;
    let l37 = -mean2l / 2.0;
    // Eq. (38): k from two consecutive mirror points, a quarter period from the node.
    let mirror = [
        (node + period / 4.0, node + 3.0 * period / 4.0),
        (node - period / 4.0, node + period / 4.0),
    ]
    .into_iter()
    .find_map(|(m1, m2)| {
        Some((
            (m1, m2),
            interp.at_mod(m1, wrap_period)?,
            interp.at_mod(m2, wrap_period)?,
        ))
    });
    let eps_alg = {
        let e = vec.fixed_rows::<2>(0).norm() / vec.fixed_rows::<2>(2).norm().max(1e-300);
        if e.is_finite() {
            e
        } else {
            0.5
        }
    };
    let eps = match mirror {
        Some((_, b1, b2)) => ((b1 - b2) / 2.0).tan().abs(),
        None => eps_alg,
    };
    // Discrete choices: L + j pi/2, the node at t = 0 or t = pi.
    let ls: Vec<f64> = (0..4).map(|j| wrap(l37 + j as f64 * PI / 2.0)).collect();
    #[allow(clippy::expect_used)] // two fixed node choices: the minimum exists
    let (_, closed) = [0.0, PI]
        .into_iter()
        .map(|t_node| {
            let c = Closed {
                xi_q,
                l: 0.0,
                t0: wrap(t_node - xi_q * node),
                eps,
            };
            best_l(c, &ls, d)
        })
        .min_by(|a, b| a.0.total_cmp(&b.0))
        .expect("two candidates");
    Ok(Det {
        closed,
        period,
        node,
        mirror: mirror.map(|m| m.0),
        sigma_curve,
    })
}

/// LS's result: the estimate and its covariance.
#[derive(Clone, Debug)]
pub struct LsFit {
    pub closed: Closed,
    /// Covariance of (xi_q, L, t0, eps).
    pub cov: SMatrix<f64, 4, 4>,
    /// Root-mean-square of the wrapped residuals (rad).
    pub rms: f64,
}

/// Weights of section V-B: `sigma_i^2 = sigma_beta^2 + (d beta/ds)^2 var(s_i)`,
/// with `var(s_i) = encoder_var_per_rad * (s_i - s_0)` (the encoder error
/// model of [10] accumulates along the wheel rotation).
pub fn weights(c: &Closed, d: &ArcData, sigma_beta: f64, encoder_var_per_rad: f64) -> Vec<f64> {
    let s0 = d.s.first().copied().unwrap_or(0.0);
    d.s.iter()
        .map(|&s| {
            let (_, da_dt, _) = c.alpha(s);
            let slope = da_dt * c.xi_q;
            1.0 / (sigma_beta * sigma_beta + slope * slope * encoder_var_per_rad * (s - s0).abs())
        })
        .collect()
}

/// Levenberg-Marquardt on the sign-free closed form (section V-B), from `init`.
/// `w` are the inverse variances of the bearings. Stops when the relative
/// decrease of the cost is below `tol` or after `max_iter` iterations.
pub fn ls(d: &ArcData, init: &Closed, w: &[f64], max_iter: usize, tol: f64) -> LsFit {
    let cost_of = |c: &Closed| -> f64 {
        d.s.iter()
            .zip(&d.beta)
            .zip(w)
            .map(|((&s, &b), &wi)| wi * wrap(b - c.beta(s)).powi(2))
            .sum()
    };
    let normal = |c: &Closed| -> (SMatrix<f64, 4, 4>, SVector<f64, 4>) {
        let mut jtj = SMatrix::<f64, 4, 4>::zeros();
        let mut jtr = SVector::<f64, 4>::zeros();
        for ((&s, &b), &wi) in d.s.iter().zip(&d.beta).zip(w) {
            let (_, da_dt, da_de) = c.alpha(s);
            // d beta / d (xi_q, L, t0, eps).
            let j = SVector::<f64, 4>::from([da_dt * s, -1.0, da_dt, da_de]);
            let r = wrap(b - c.beta(s));
            jtj += wi * j * j.transpose();
            jtr += wi * r * j;
        }
        (jtj, jtr)
    };
    let opts = LmOptions {
        max_iterations: max_iter,
        relative_cost_tolerance: tol,
        ..LmOptions::default()
    };
    let closed = |x: &[f64]| Closed::from_vec(&SVector::<f64, 4>::from_column_slice(x));
    let out = minimise(
        init.to_vec().as_slice(),
        |x| cost_of(&closed(x)),
        |x| {
            let (jtj, jtr) = normal(&closed(x));
            (
                DMatrix::from_column_slice(4, 4, jtj.as_slice()),
                DVector::from_column_slice(jtr.as_slice()),
            )
        },
        // The closed form's own chart (L wrapped), as its steps always were.
        |x| x.copy_from_slice(closed(x).to_vec().as_slice()),
        &opts,
    );
    let mut c = closed(&out.x);
    // eps and -eps with t0 + pi describe the same curve: keep eps > 0.
    if c.eps < 0.0 {
        c.eps = -c.eps;
        c.t0 = wrap(c.t0 + PI);
    }
    let (jtj, _) = normal(&c);
    let cov = jtj
        .try_inverse()
        .unwrap_or_else(|| SMatrix::<f64, 4, 4>::from_element(f64::NAN));
    LsFit {
        closed: c,
        cov,
        rms: rms(&c, d),
    }
}
