//! Helpers shared by the analysis tests (an independent computation, so
//! the tests do not check the library with itself).

use obsan_expr::Fp;

/// Rank of a matrix over F_p by plain Gaussian elimination.
pub fn rank_fp(mut m: Vec<Vec<Fp>>) -> usize {
    let mut r = 0;
    let cols = m.first().map_or(0, |x| x.len());
    for c in 0..cols {
        let Some(i) = (r..m.len()).find(|&i| !m[i][c].is_zero()) else {
            continue;
        };
        m.swap(r, i);
        let inv = m[r][c].inv().unwrap();
        let pr: Vec<_> = m[r].iter().map(|&x| x * inv).collect();
        for row in m.iter_mut().skip(r + 1) {
            let f = row[c];
            for (x, y) in row.iter_mut().zip(&pr) {
                *x = *x - f * *y;
            }
        }
        r += 1;
    }
    r
}
