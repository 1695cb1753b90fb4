//! One integration step of [`Predictor`]'s prediction: classical RK4, or
//! exponential time differencing RK4 where a self-linear state is stiff over
//! the step. A child module of predict.rs, moved out to keep that file short;
//! it reads the predictor's private tapes as its own.

use super::{Predictor, Work};

impl Predictor {
    /// One classical RK4 step of length `h` from `z`, whose derivative is `k1`.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn rk4_step(
        &self,
        z: &mut [f64],
        k1: &[f64],
        u: &[f64],
        (sens, dd): (bool, Option<&[f64]>),
        w: &mut Work,
        h: f64,
        rk: &mut Rk4,
    ) {
        let Rk4 { k2, k3, k4, tmp } = rk;
        let nz = z.len();
        for i in 0..nz {
            tmp[i] = z[i] + h / 2.0 * k1[i];
        }
        self.derivative(tmp, u, sens, dd, w, k2);
        for i in 0..nz {
            tmp[i] = z[i] + h / 2.0 * k2[i];
        }
        self.derivative(tmp, u, sens, dd, w, k3);
        for i in 0..nz {
            tmp[i] = z[i] + h * k3[i];
        }
        self.derivative(tmp, u, sens, dd, w, k4);
        for i in 0..nz {
            z[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
        }
    }

    /// One step of exponential time differencing RK4 (ETDRK4, Cox and
    /// Matthews 2002) from `z`, whose derivative is `k1`: each component
    /// of dynamic state k (its value and its sensitivity row) takes
    /// `lam[k]` as its linear part, integrated exactly; a component with
    /// `lam` 0 takes the classical RK4 stages (the method's limit).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn etd_step(
        &self,
        z: &mut [f64],
        k1: &[f64],
        u: &[f64],
        (sens, dd): (bool, Option<&[f64]>),
        w: &mut Work,
        h: f64,
        lam: &[f64],
        st: &mut Stages,
    ) {
        let (nd, n) = (self.n_dynamic, self.state.len());
        for (c, &l) in st.co.iter_mut().zip(lam) {
            if l == 0.0 {
                continue;
            }
            let x = l * h;
            let (e2, e) = ((x / 2.0).exp(), x.exp());
            let d = h * h * l * l * l;
            *c = [
                e2,
                e,
                (e2 - 1.0) / l,
                (-4.0 - x + e * (4.0 - 3.0 * x + x * x)) / d,
                (2.0 + x + e * (-2.0 + x)) / d,
                (-4.0 - 3.0 * x - x * x + e * (4.0 - x)) / d,
            ];
        }
        // Each dynamic state's components (its value, then its sensitivity
        // row when carried) share its lambda and coefficients: visited by
        // state, the per-component row lookup (a division) and branch are
        // hoisted; the arithmetic per component is unchanged.
        let sens_rows = z.len() > nd;
        let comps = |k: usize| {
            let r = if sens_rows {
                nd + k * n..nd + (k + 1) * n
            } else {
                0..0
            };
            std::iter::once(k).chain(r)
        };
        for (k, (&l, &c)) in lam.iter().zip(&st.co).enumerate() {
            if l == 0.0 {
                for i in comps(k) {
                    st.a[i] = z[i] + h / 2.0 * k1[i];
                }
            } else {
                for i in comps(k) {
                    st.a[i] = c[0] * z[i] + c[2] * (k1[i] - l * z[i]);
                }
            }
        }
        self.derivative(&st.a, u, sens, dd, w, &mut st.k2);
        for (k, (&l, &c)) in lam.iter().zip(&st.co).enumerate() {
            if l == 0.0 {
                for i in comps(k) {
                    st.b[i] = z[i] + h / 2.0 * st.k2[i];
                }
            } else {
                for i in comps(k) {
                    st.b[i] = c[0] * z[i] + c[2] * (st.k2[i] - l * st.a[i]);
                }
            }
        }
        self.derivative(&st.b, u, sens, dd, w, &mut st.k3);
        for (k, (&l, &c)) in lam.iter().zip(&st.co).enumerate() {
            if l == 0.0 {
                for i in comps(k) {
                    st.c[i] = z[i] + h * st.k3[i];
                }
            } else {
                for i in comps(k) {
                    let (n1, n3) = (k1[i] - l * z[i], st.k3[i] - l * st.b[i]);
                    st.c[i] = c[0] * st.a[i] + c[2] * (2.0 * n3 - n1);
                }
            }
        }
        self.derivative(&st.c, u, sens, dd, w, &mut st.k4);
        for (k, (&l, &c)) in lam.iter().zip(&st.co).enumerate() {
            if l == 0.0 {
                for i in comps(k) {
                    z[i] += h / 6.0 * (k1[i] + 2.0 * st.k2[i] + 2.0 * st.k3[i] + st.k4[i]);
                }
            } else {
                for i in comps(k) {
                    let n1 = k1[i] - l * z[i];
                    let n2 = st.k2[i] - l * st.a[i];
                    let n3 = st.k3[i] - l * st.b[i];
                    let n4 = st.k4[i] - l * st.c[i];
                    z[i] = c[1] * z[i] + c[3] * n1 + 2.0 * c[4] * (n2 + n3) + c[5] * n4;
                }
            }
        }
    }
}

/// The classical RK4 stages' buffers, reused over a prediction.
pub(super) struct Rk4 {
    pub(super) k2: Vec<f64>,
    pub(super) k3: Vec<f64>,
    pub(super) k4: Vec<f64>,
    pub(super) tmp: Vec<f64>,
}

/// The stages of [`Predictor::etd_step`].
pub(super) struct Stages {
    /// Per dynamic state: e^{lh/2}, e^{lh}, (e^{lh/2} - 1)/l, f1, f2, f3.
    co: Vec<[f64; 6]>,
    a: Vec<f64>,
    b: Vec<f64>,
    c: Vec<f64>,
    k2: Vec<f64>,
    k3: Vec<f64>,
    k4: Vec<f64>,
}

impl Stages {
    pub(super) fn new(nd: usize, nz: usize) -> Stages {
        let v = || vec![0.0; nz];
        Stages {
            co: vec![[0.0; 6]; nd],
            a: v(),
            b: v(),
            c: v(),
            k2: v(),
            k3: v(),
            k4: v(),
        }
    }
}
