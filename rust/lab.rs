//! Hot loops of the lab preprocessing (`python/bouc_wen_id/signal.py`, issue #8): the harmonic
//! least squares behind the sine analysis and the synchronous average.
//!
//! A fit of `y` on `[1, cos k theta, sin k theta]`, `k = 1..K`, needs the Gram matrix of the basis
//! and its products with `y`. With `z_n = e^{i theta_n}` both follow from the complex moments
//! `mu_q = sum_n z_n^q` (`q = 0..2K`; the Gram matrix is Toeplitz-plus-Hankel in them) and
//! `r_q = sum_n y_n conj(z_n)^q` (`q = 0..K`), in one pass of the phasor recurrence
//! `z^(q+1) = z^q z`: O(n K) work instead of the O(n K^2) of forming the basis and its QR. The
//! NumPy reference of the same recurrence is `signal._moment_fit`; the Gram assembly and the
//! triangular solves stay in Python (they are O(K^2) to O(K^3) on small matrices).
//!
//! The samples are processed in blocks of [`LANES`] so that the recurrences of neighbouring
//! samples (independent) overlap; each sample's powers are formed exactly as the NumPy reference
//! forms them (`p *= z`, complex multiply without fused operations), only the summation order of
//! the moments differs (rounding of order `n eps` relative, far below the noise of any record).

use crate::error::{all_finite, CoreError, Result};

/// Samples advanced together through the phasor recurrence.
const LANES: usize = 8;

/// `(a + ib)(c + id)` as NumPy computes it: `(ac - bd) + i(ad + bc)`.
#[inline(always)]
fn cmul(a: (f64, f64), b: (f64, f64)) -> (f64, f64) {
    (a.0 * b.0 - a.1 * b.1, a.0 * b.1 + a.1 * b.0)
}

fn check(theta: &[f64], y: &[f64], kmax: usize) -> Result<()> {
    all_finite("theta", theta)?;
    all_finite("y", y)?;
    if theta.len() != y.len() {
        return Err(CoreError::InvalidParameter(format!(
            "theta and y must have equal lengths, got {} and {}",
            theta.len(),
            y.len()
        )));
    }
    if kmax < 1 {
        return Err(CoreError::InvalidParameter(format!(
            "kmax = {kmax} must be >= 1"
        )));
    }
    Ok(())
}

/// Moments of the harmonic basis at the phases `theta` (rad, length n) against `y` (length n):
/// `mu_q = sum_n e^{i q theta_n}`, `q = 0..=2 kmax`, and `r_q = sum_n y_n e^{-i q theta_n}`,
/// `q = 0..=kmax`, each as `(real parts, imaginary parts)`.
///
/// Errors: non-finite input, unequal lengths, `kmax < 1`.
#[allow(clippy::type_complexity)]
pub fn harmonic_moments(
    theta: &[f64],
    y: &[f64],
    kmax: usize,
) -> Result<((Vec<f64>, Vec<f64>), (Vec<f64>, Vec<f64>))> {
    check(theta, y, kmax)?;
    let nq = 2 * kmax + 1;
    let (mut mu_re, mut mu_im) = (vec![0.0; nq], vec![0.0; nq]);
    let (mut r_re, mut r_im) = (vec![0.0; kmax + 1], vec![0.0; kmax + 1]);
    for (th, yb) in theta.chunks(LANES).zip(y.chunks(LANES)) {
        let lanes = th.len();
        let mut z = [(0.0, 0.0); LANES];
        let mut p = [(0.0, 0.0); LANES];
        let mut yy = [0.0; LANES];
        for l in 0..lanes {
            z[l] = (th[l].cos(), th[l].sin());
            p[l] = (1.0, 0.0);
            yy[l] = yb[l];
        }
        for q in 0..nq {
            let (mut sr, mut si) = (0.0, 0.0);
            for pl in &p[..lanes] {
                sr += pl.0;
                si += pl.1;
            }
            mu_re[q] += sr;
            mu_im[q] += si;
            if q <= kmax {
                // y conj(p): (y p_re) + i (-y p_im).
                let (mut rr, mut ri) = (0.0, 0.0);
                for l in 0..lanes {
                    rr += yy[l] * p[l].0;
                    ri -= yy[l] * p[l].1;
                }
                r_re[q] += rr;
                r_im[q] += ri;
            }
            for l in 0..lanes {
                p[l] = cmul(p[l], z[l]);
            }
        }
    }
    Ok(((mu_re, mu_im), (r_re, r_im)))
}

/// The harmonic series `coef[0] + sum_k coef[2k-1] cos(k theta_n) + coef[2k] sin(k theta_n)` at
/// every phase (length n), by the same phasor recurrence; `coef` has length `2K + 1`, `K >= 0`.
///
/// Errors: non-finite input, an even `coef` length.
pub fn harmonic_series(theta: &[f64], coef: &[f64]) -> Result<Vec<f64>> {
    all_finite("theta", theta)?;
    all_finite("coef", coef)?;
    if coef.len() % 2 == 0 {
        return Err(CoreError::InvalidParameter(format!(
            "coef must hold 2K + 1 values [c, a_1, b_1, ...], got {}",
            coef.len()
        )));
    }
    let kmax = coef.len() / 2;
    let mut out = vec![coef[0]; theta.len()];
    for (th, ob) in theta.chunks(LANES).zip(out.chunks_mut(LANES)) {
        let lanes = th.len();
        let mut z = [(0.0, 0.0); LANES];
        for l in 0..lanes {
            z[l] = (th[l].cos(), th[l].sin());
        }
        let mut p = z;
        for k in 1..=kmax {
            let (a, b) = (coef[2 * k - 1], coef[2 * k]);
            for l in 0..lanes {
                ob[l] += a * p[l].0 + b * p[l].1;
                p[l] = cmul(p[l], z[l]);
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn moments_match_direct_sums() {
        let n = 37; // not a multiple of LANES: the last block is partial
        let theta: Vec<f64> = (0..n).map(|i| 0.37 * i as f64 + 0.1).collect();
        let y: Vec<f64> = (0..n).map(|i| (i as f64 * 0.7).sin() + 0.2).collect();
        let k = 5;
        let ((mr, mi), (rr, ri)) = harmonic_moments(&theta, &y, k).unwrap();
        for q in 0..=2 * k {
            let (er, ei): (f64, f64) = theta.iter().fold((0.0, 0.0), |acc, t| {
                (acc.0 + (q as f64 * t).cos(), acc.1 + (q as f64 * t).sin())
            });
            assert!(
                (mr[q] - er).abs() < 1e-12 && (mi[q] - ei).abs() < 1e-12,
                "q = {q}"
            );
        }
        for q in 0..=k {
            let (er, ei) = theta.iter().zip(&y).fold((0.0, 0.0), |acc, (t, v)| {
                (
                    acc.0 + v * (q as f64 * t).cos(),
                    acc.1 - v * (q as f64 * t).sin(),
                )
            });
            assert!(
                (rr[q] - er).abs() < 1e-12 && (ri[q] - ei).abs() < 1e-12,
                "q = {q}"
            );
        }
    }

    #[test]
    fn series_matches_direct_sum_and_validates() {
        let theta: Vec<f64> = (0..21).map(|i| 0.3 * i as f64).collect();
        let coef = [0.5, 1.0, -0.3, 0.2, 0.7, -0.1, 0.05];
        let s = harmonic_series(&theta, &coef).unwrap();
        for (t, v) in theta.iter().zip(&s) {
            let mut e = coef[0];
            for k in 1..=3 {
                e += coef[2 * k - 1] * (k as f64 * t).cos() + coef[2 * k] * (k as f64 * t).sin();
            }
            assert!((v - e).abs() < 1e-13);
        }
        assert!(harmonic_series(&theta, &coef[..6]).is_err());
        assert!(harmonic_moments(&theta, &theta[..3], 2).is_err());
        assert!(harmonic_moments(&theta, &theta, 0).is_err());
        let bad = [f64::NAN, 1.0];
        assert!(matches!(
            harmonic_moments(&bad, &bad, 1),
            Err(CoreError::NonFinite(_))
        ));
    }
}
