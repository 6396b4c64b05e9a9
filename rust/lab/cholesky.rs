//! The upper Cholesky factor of a Gram matrix (dot-product form, rows in groups, padded chunks).

/// The factor of [`cholesky_upper`], or the failing pivot `(index, value)`.
#[inline(always)]
pub(crate) fn cholesky_of(gram: &[f64], m: usize) -> Result<Vec<f64>, (usize, f64)> {
    // Lower factor L, row-major with rows padded to whole chunks of CHOL_LANES and zero-filled:
    // L[i][j] = (G[i][j] - L[i][..j] . L[j][..j]) / L[j][j]. Row j is zero beyond its diagonal and
    // L[i][j] is still zero when its own dot product runs, so every dot product can run to the
    // next whole chunk without a scalar tail (the same sum: the extra terms are exact zeros).
    const CHOL_LANES: usize = 8;
    let stride = m.div_ceil(CHOL_LANES) * CHOL_LANES;
    let mut l = vec![0.0; m * stride];
    let dot = |l: &[f64], i: usize, j: usize| -> f64 {
        let len = j.div_ceil(CHOL_LANES) * CHOL_LANES;
        let (ri, rj) = (
            &l[i * stride..i * stride + len],
            &l[j * stride..j * stride + len],
        );
        let mut acc = [0.0; CHOL_LANES];
        for (a, b) in ri.chunks_exact(CHOL_LANES).zip(rj.chunks_exact(CHOL_LANES)) {
            for k in 0..CHOL_LANES {
                acc[k] += a[k] * b[k];
            }
        }
        acc.iter().sum::<f64>()
    };
    // Rows in groups of CHOL_ROWS: each earlier row j is read once per group (not once per row),
    // which keeps the factor of the synchronous average (m = 2K + 1 up to 401, over 1 MB) from
    // being streamed m times through the cache.
    const CHOL_ROWS: usize = 8;
    for i0 in (0..m).step_by(CHOL_ROWS) {
        let i1 = (i0 + CHOL_ROWS).min(m);
        for j in 0..i0 {
            let mut sums = [0.0; CHOL_ROWS];
            for (i, sum) in (i0..i1).zip(sums.iter_mut()) {
                *sum = dot(&l, i, j);
            }
            let d = l[j * stride + j];
            for (i, sum) in (i0..i1).zip(sums) {
                l[i * stride + j] = (gram[i * m + j] - sum) / d;
            }
        }
        for i in i0..i1 {
            for j in i0..=i {
                let s = gram[i * m + j] - dot(&l, i, j);
                if i == j {
                    if s.is_nan() || s <= 0.0 {
                        return Err((i, s));
                    }
                    l[i * stride + i] = s.sqrt();
                } else {
                    l[i * stride + j] = s / l[j * stride + j];
                }
            }
        }
    }
    let mut r = vec![0.0; m * m];
    for i in 0..m {
        for j in 0..=i {
            r[j * m + i] = l[i * stride + j];
        }
    }
    Ok(r)
}
