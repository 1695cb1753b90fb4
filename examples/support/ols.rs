//! Least squares with cluster-robust (by window) standard errors, for
//! examples/mrclam_truth.rs: the residuals within a 60 s window are
//! correlated (the odometry drifts), the windows are independent.

/// A least-squares fit with its iid and cluster-robust (by window) covariances.
pub struct Ols {
    pub beta: Vec<f64>,
    pub se: Vec<f64>,
    /// Cluster-robust (CR1, clusters = windows) covariance.
    pub vcr: Vec<Vec<f64>>,
}

impl Ols {
    pub fn cr(&self, j: usize) -> f64 {
        self.vcr[j][j].sqrt()
    }
}

fn invert(mut a: Vec<Vec<f64>>) -> Option<Vec<Vec<f64>>> {
    let p = a.len();
    let mut inv: Vec<Vec<f64>> = (0..p)
        .map(|i| (0..p).map(|j| f64::from(u8::from(i == j))).collect())
        .collect();
    for c in 0..p {
        let piv = (c..p).max_by(|&i, &j| a[i][c].abs().total_cmp(&a[j][c].abs()))?;
        if a[piv][c].abs() < 1e-300 {
            return None;
        }
        a.swap(c, piv);
        inv.swap(c, piv);
        let d = a[c][c];
        for j in 0..p {
            a[c][j] /= d;
            inv[c][j] /= d;
        }
        for i in (0..p).filter(|&i| i != c) {
            let f = a[i][c];
            for j in 0..p {
                a[i][j] -= f * a[c][j];
                inv[i][j] -= f * inv[c][j];
            }
        }
    }
    Some(inv)
}

/// y = X beta by least squares; `g` is each row's window (sorted or not).
pub fn ols(x: &[Vec<f64>], y: &[f64], g: &[usize]) -> Option<Ols> {
    let (n, p) = (y.len(), x.first()?.len());
    let mut xtx = vec![vec![0.0; p]; p];
    let mut xty = vec![0.0; p];
    for (r, yi) in x.iter().zip(y) {
        for i in 0..p {
            xty[i] += r[i] * yi;
            for j in 0..p {
                xtx[i][j] += r[i] * r[j];
            }
        }
    }
    let inv = invert(xtx)?;
    let beta: Vec<f64> = (0..p)
        .map(|i| (0..p).map(|j| inv[i][j] * xty[j]).sum())
        .collect();
    let u: Vec<f64> = x
        .iter()
        .zip(y)
        .map(|(r, yi)| yi - r.iter().zip(&beta).map(|(a, b)| a * b).sum::<f64>())
        .collect();
    let s2 = u.iter().map(|v| v * v).sum::<f64>() / (n - p) as f64;
    let se = (0..p).map(|j| (s2 * inv[j][j]).sqrt()).collect();
    let mut scores: std::collections::BTreeMap<usize, Vec<f64>> = Default::default();
    for ((r, ui), gi) in x.iter().zip(&u).zip(g) {
        let s = scores.entry(*gi).or_insert_with(|| vec![0.0; p]);
        for j in 0..p {
            s[j] += r[j] * ui;
        }
    }
    let ng = scores.len() as f64;
    let mut meat = vec![vec![0.0; p]; p];
    for s in scores.values() {
        for i in 0..p {
            for j in 0..p {
                meat[i][j] += s[i] * s[j];
            }
        }
    }
    let f = ng / (ng - 1.0);
    let vcr = (0..p)
        .map(|i| {
            (0..p)
                .map(|j| {
                    let mut v = 0.0;
                    for k in 0..p {
                        for l in 0..p {
                            v += inv[i][k] * meat[k][l] * inv[l][j];
                        }
                    }
                    f * v
                })
                .collect()
        })
        .collect();
    Some(Ols { beta, se, vcr })
}

/// Subtract each window's mean from every column and from y: the fit then
/// has a free constant per window (its initial heading), by Frisch–Waugh.
pub fn demean(x: &mut [Vec<f64>], y: &mut [f64], g: &[usize]) {
    let p = x.first().map_or(0, Vec::len);
    let mut sums: std::collections::BTreeMap<usize, (Vec<f64>, f64, f64)> = Default::default();
    for ((r, yi), gi) in x.iter().zip(y.iter()).zip(g) {
        let s = sums.entry(*gi).or_insert_with(|| (vec![0.0; p], 0.0, 0.0));
        for (a, v) in s.0.iter_mut().zip(r) {
            *a += v;
        }
        s.1 += yi;
        s.2 += 1.0;
    }
    for ((r, yi), gi) in x.iter_mut().zip(y.iter_mut()).zip(g) {
        let s = &sums[gi];
        for (v, a) in r.iter_mut().zip(&s.0) {
            *v -= a / s.2;
        }
        *yi -= s.1 / s.2;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_exact_line_is_recovered() {
        let x: Vec<Vec<f64>> = (0..10).map(|i| vec![i as f64, 1.0]).collect();
        let y: Vec<f64> = (0..10).map(|i| 2.0 * i as f64 - 3.0).collect();
        let g: Vec<usize> = (0..10).map(|i| i / 3).collect();
        let f = ols(&x, &y, &g).unwrap();
        assert!((f.beta[0] - 2.0).abs() < 1e-12 && (f.beta[1] + 3.0).abs() < 1e-12);
        assert!(f.cr(0) < 1e-9);
    }

    /// Frisch–Waugh: demeaning per window equals a dummy per window.
    #[test]
    fn demeaning_equals_window_dummies() {
        let n = 40;
        let g: Vec<usize> = (0..n).map(|i| i % 4).collect();
        let xv: Vec<f64> = (0..n).map(|i| ((i * 7) % 11) as f64).collect();
        let y: Vec<f64> = (0..n)
            .map(|i| 0.5 * xv[i] + g[i] as f64 + ((i * 13) % 5) as f64 * 0.1)
            .collect();
        let dummies: Vec<Vec<f64>> = (0..n)
            .map(|i| {
                let mut r = vec![xv[i]];
                r.extend((0..4).map(|k| f64::from(u8::from(g[i] == k))));
                r
            })
            .collect();
        let full = ols(&dummies, &y, &g).unwrap();
        let (mut x1, mut y1): (Vec<Vec<f64>>, Vec<f64>) =
            ((0..n).map(|i| vec![xv[i]]).collect(), y.clone());
        demean(&mut x1, &mut y1, &g);
        let within = ols(&x1, &y1, &g).unwrap();
        assert!((full.beta[0] - within.beta[0]).abs() < 1e-10);
    }

    /// One row per cluster: the cluster-robust variance is White's HC1,
    /// sum x^2 u^2 / (sum x^2)^2 * n / (n - 1), for y = b x.
    #[test]
    fn singleton_clusters_give_the_white_variance() {
        let x: Vec<f64> = (1..=8).map(f64::from).collect();
        let y: Vec<f64> = x
            .iter()
            .enumerate()
            .map(|(i, v)| v + [0.3, -0.2][i % 2] * v)
            .collect();
        let rows: Vec<Vec<f64>> = x.iter().map(|v| vec![*v]).collect();
        let f = ols(&rows, &y, &(0..8).collect::<Vec<_>>()).unwrap();
        let sxx: f64 = x.iter().map(|v| v * v).sum();
        let b: f64 = x.iter().zip(&y).map(|(a, c)| a * c).sum::<f64>() / sxx;
        let meat: f64 = x
            .iter()
            .zip(&y)
            .map(|(a, c)| (a * (c - b * a)).powi(2))
            .sum();
        let white = meat / (sxx * sxx) * 8.0 / 7.0;
        assert!((f.vcr[0][0] - white).abs() < 1e-12 * white.max(1.0));
    }
}
