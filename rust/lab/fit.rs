//! A whole harmonic least-squares fit in one call, and the Gauss-Newton frequency fit built on it
//! (issue #8): the moments ([`super::moments_of`]), the Gram matrix and `X^T y`
//! (Toeplitz-plus-Hankel in the moments), the conditioning check, the Cholesky factor, the two
//! triangular solves and the explicit residual, each the same formula as the NumPy reference
//! (`signal._harmonic_ls._moment_fit`, `_fastlab`), without a round trip through Python between them.
//! [`harmonic_nls`] is `signal._sine._nls` (same step rule, same stopping rule) with every fit
//! from here and the phasors of an accepted trial kept for the next step's Gauss-Newton terms.

use nalgebra::{DMatrix, SymmetricEigen};

use super::wide::wide_fn;
use super::{
    check, check_harmonics, check_omega, check_square, cholesky_of, gauss_newton_of, moments_of,
    rss_of, Phases, Phasors,
};
use crate::error::{all_finite, CoreError, Result};

/// Largest condition number of the scaled Gram matrix for which the normal equations are used
/// (`_fastlab.GRAM_COND_MAX`, `_harmonic_ls._moment_fit`).
pub const GRAM_COND_MAX: f64 = 1e4;

/// A harmonic least-squares fit of `y` on `[1, cos k theta, sin k theta]`, `k = 1..K`.
#[derive(Debug, Clone)]
pub struct HarmonicFit {
    /// `[c, a_1, b_1, ..., a_K, b_K]` (units of `y`).
    pub coef: Vec<f64>,
    /// Upper Cholesky factor `R` of the Gram matrix (`R^T R = X^T X`), row-major `m x m`,
    /// `m = 2K + 1`: the QR factor of the basis up to the signs of its rows.
    pub r: Vec<f64>,
    /// `Q^T y = R^-T X^T y` (length `m`): the nested sub-fits' coefficients and residuals.
    pub qty: Vec<f64>,
    /// Explicit residual sum of squares `|y - X coef|^2`.
    pub rss: f64,
}

/// The real Gram matrix of `[1, c_1, s_1, c_2, s_2, ...]` (row-major) and `X^T y` from the
/// complex moments `mu_q` (`q = 0..2K`) and `r_q` (`q = 0..K`), as `_fastlab.gram_from_moments`:
/// `cos a cos b = (cos(a-b) + cos(a+b))/2`, `sin a sin b = (cos(a-b) - cos(a+b))/2`,
/// `cos a sin b = (sin(a+b) - sin(a-b))/2`.
pub fn gram_from_moments(
    mu: (&[f64], &[f64]),
    r: (&[f64], &[f64]),
    kmax: usize,
) -> (Vec<f64>, Vec<f64>) {
    let m = 2 * kmax + 1;
    // mu at a signed index d: mu_{-d} = conj(mu_d).
    let at = |d: isize| -> (f64, f64) {
        let i = d.unsigned_abs();
        (mu.0[i], if d < 0 { -mu.1[i] } else { mu.1[i] })
    };
    let mut g = vec![0.0; m * m];
    // The constant column is the k = 0 cosine: G[0][0] = Re mu_0, and with harmonic k's cosine
    // and sine, Re mu_k and Im mu_k.
    g[0] = mu.0[0];
    for k in 1..=kmax {
        let (c, s) = (0.5 * (mu.0[k] + mu.0[k]), 0.5 * (mu.1[k] + mu.1[k]));
        g[2 * k - 1] = c;
        g[2 * k] = s;
        g[(2 * k - 1) * m] = c;
        g[2 * k * m] = s;
    }
    // Harmonics a <= b: the 2 x 2 block of (cos a, sin a) x (cos b, sin b) from mu_{a-b} and
    // mu_{a+b}, mirrored (the formulas give the transposed block exactly: a + (-x) = a - x).
    for a in 1..=kmax as isize {
        for b in a..=kmax as isize {
            let (lo, hi) = (at(a - b), at(a + b));
            let (ca, sa, cb, sb) = (
                (2 * a - 1) as usize,
                (2 * a) as usize,
                (2 * b - 1) as usize,
                (2 * b) as usize,
            );
            let cc = 0.5 * (lo.0 + hi.0);
            let ss = 0.5 * (lo.0 - hi.0);
            let sc = 0.5 * (hi.1 + lo.1); // row sin a, column cos b
            let cs = 0.5 * (hi.1 - lo.1); // row cos a, column sin b
            g[ca * m + cb] = cc;
            g[cb * m + ca] = cc;
            g[sa * m + sb] = ss;
            g[sb * m + sa] = ss;
            g[sa * m + cb] = sc;
            g[cb * m + sa] = sc;
            g[ca * m + sb] = cs;
            g[sb * m + ca] = cs;
        }
    }
    let mut xty = vec![0.0; m];
    xty[0] = r.0[0];
    for k in 1..=kmax {
        xty[2 * k - 1] = r.0[k];
        xty[2 * k] = -r.1[k];
    }
    (g, xty)
}

/// `cond(D^-1/2 G D^-1/2) <= GRAM_COND_MAX` and positive definite (`G` row-major `m x m`), as
/// `_fastlab.well_conditioned`: Gershgorin's discs certify it without an eigen-decomposition when
/// the harmonics are nearly orthogonal; otherwise the eigenvalues decide.
pub fn well_conditioned(g: &[f64], m: usize) -> bool {
    let diag: Vec<f64> = (0..m).map(|i| g[i * m + i]).collect();
    if !diag.iter().all(|&d| d > 0.0) {
        return false;
    }
    let scale: Vec<f64> = diag.iter().map(|d| d.sqrt()).collect();
    let scaled = |i: usize, j: usize| g[i * m + j] / (scale[i] * scale[j]);
    // Off-diagonal absolute row sums of the scaled matrix, |g_ij| / (s_i s_j) summed over j != i
    // (a row at a time, contiguous, so that it vectorises).
    let inv: Vec<f64> = scale.iter().map(|s| 1.0 / s).collect();
    let radius = (0..m)
        .map(|i| {
            let row = &g[i * m..(i + 1) * m];
            let total: f64 = row.iter().zip(&inv).map(|(v, w)| v.abs() * w).sum();
            (total - diag[i] * inv[i]) * inv[i]
        })
        .fold(0.0, f64::max);
    if radius < 1.0 && (1.0 + radius) <= GRAM_COND_MAX * (1.0 - radius) {
        return true;
    }
    let eig = SymmetricEigen::new(DMatrix::from_fn(m, m, scaled)).eigenvalues;
    let (lo, hi) = eig
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &e| {
            (a.min(e), b.max(e))
        });
    lo > 0.0 && hi / lo <= GRAM_COND_MAX
}

/// [`well_conditioned`] with its input checked: `gram` finite, of length `m * m`, `m >= 1`.
///
/// Errors: non-finite input, a length other than `m * m`.
pub fn gram_well_conditioned(gram: &[f64], m: usize) -> Result<bool> {
    check_square("gram", gram, m)?;
    Ok(well_conditioned(gram, m))
}

/// `x` with `R^T x = b` (`R` upper, row-major `m x m`).
pub(crate) fn solve_upper_transposed(r: &[f64], b: &[f64]) -> Vec<f64> {
    let m = b.len();
    let mut x = b.to_vec();
    for i in 0..m {
        let mut s = x[i];
        for k in 0..i {
            s -= r[k * m + i] * x[k];
        }
        x[i] = s / r[i * m + i];
    }
    x
}

/// `x` with `R x = b` (`R` upper, row-major `m x m`).
pub(crate) fn solve_upper(r: &[f64], b: &[f64]) -> Vec<f64> {
    let m = b.len();
    let mut x = b.to_vec();
    for i in (0..m).rev() {
        let mut s = x[i];
        for k in i + 1..m {
            s -= r[i * m + k] * x[k];
        }
        x[i] = s / r[i * m + i];
    }
    x
}

/// The diagonal of `(R^T R)^-1` (`R` upper, row-major `m x m`, non-zero diagonal): the unscaled
/// variances of a least-squares fit whose normal matrix is `R^T R`, as the row sums of squares of
/// `R^-1` (`signal._harmonic_ls.HarmonicLS.unscaled_variance`). `R^-1` is formed column by column
/// (`m^3 / 6` multiply-adds, column-oriented back substitution).
///
/// Errors: non-finite input, a length other than `m * m`, a zero on the diagonal.
pub fn unscaled_variances(r: &[f64], m: usize) -> Result<Vec<f64>> {
    check_square("r", r, m)?;
    if let Some(i) = (0..m).find(|&i| r[i * m + i] == 0.0) {
        return Err(CoreError::InvalidParameter(format!(
            "R is singular: zero on its diagonal at {i}"
        )));
    }
    // Column j costs j^2/2: the columns below m / sqrt 2 and those above are equal halves, run on
    // two threads for the synchronous average's large R (a fixed split: the same sums whatever
    // the pool's size).
    if m >= 128 {
        let cut = (m as f64 / std::f64::consts::SQRT_2) as usize;
        let (a, b) = rayon::join(
            || inverse_row_norms(r, m, 0, cut),
            || inverse_row_norms(r, m, cut, m),
        );
        return Ok(a.iter().zip(&b).map(|(u, v)| u + v).collect());
    }
    Ok(inverse_row_norms(r, m, 0, m))
}

wide_fn! {
    /// The contributions of the columns `[from, to)` of `R^-1` to its row sums of squares.
    fn inverse_row_norms(r: &[f64], m: usize, from: usize, to: usize) -> Vec<f64> {
        // R^T row-major (R's columns contiguous): column j of R^-1 by column-oriented back
        // substitution, col[i] /= R[i][i], then col[..i] -= col[i] R[..i][i], an update without the
        // chain of dependent dot products of the row-oriented form.
        let mut rt = vec![0.0; m * m];
        for i in 0..m {
            for k in i..m {
                rt[k * m + i] = r[i * m + k];
            }
        }
        let mut out = vec![0.0; m];
        let mut col = vec![0.0; m];
        for j in from..to {
            col[..j].fill(0.0);
            col[j] = 1.0;
            for i in (0..=j).rev() {
                let c = col[i] / r[i * m + i];
                col[i] = c;
                for (v, a) in col[..i].iter_mut().zip(&rt[i * m..i * m + i]) {
                    *v -= c * a;
                }
            }
            for i in 0..=j {
                out[i] += col[i] * col[i];
            }
        }
        out
    }
}

/// The fit from the record's phasors; `None` when the Gram matrix is too ill-conditioned for the
/// normal equations (the caller then uses its QR path).
#[inline(always)]
pub(crate) fn fit_of(
    phases: Phases<'_>,
    y: &[f64],
    kmax: usize,
    buf: &mut Phasors,
) -> Option<HarmonicFit> {
    // Formed once for the two passes (when not given formed).
    let z = match phases {
        Phases::Cached(..) => phases,
        _ => buf.fill(phases),
    };
    let ((mr, mi), (rr, ri)) = moments_of(z, y, kmax);
    let (g, xty) = gram_from_moments((&mr, &mi), (&rr, &ri), kmax);
    let m = 2 * kmax + 1;
    if !well_conditioned(&g, m) {
        return None;
    }
    let r = cholesky_of(&g, m).ok()?;
    let qty = solve_upper_transposed(&r, &xty);
    let coef = solve_upper(&r, &qty);
    let rss = rss_of(z, y, &coef);
    Some(HarmonicFit { coef, r, qty, rss })
}

/// The least-squares fit of `y` (length n) on harmonics `1..=kmax` of the phases `theta` (rad,
/// length n) and a constant, by the normal equations of the moments (O(n K)); `Ok(None)` when
/// their Gram matrix is too ill-conditioned (`cond > 1e4`: less than about a period, or a harmonic
/// near Nyquist), for the caller's QR path.
///
/// Errors: non-finite input, unequal lengths, `kmax < 1`, fewer samples than `2 kmax + 1`.
pub fn harmonic_fit(theta: &[f64], y: &[f64], kmax: usize) -> Result<Option<HarmonicFit>> {
    harmonic_fit_at(theta, None, y, kmax)
}

/// [`harmonic_fit`] at the phases `theta`, or at `omega tau` when `omega` (rad/s) is given and
/// `theta` holds the times `tau` (s).
///
/// Errors: as [`harmonic_fit`], and a non-finite `omega`.
pub fn harmonic_fit_at(
    theta: &[f64],
    omega: Option<f64>,
    y: &[f64],
    kmax: usize,
) -> Result<Option<HarmonicFit>> {
    check(theta, y, kmax)?;
    check_harmonics(theta.len(), kmax)?;
    check_omega(omega)?;
    Ok(Phasors::with(|z, _| fit_wide(theta, omega, y, kmax, z)))
}

wide_fn! {
    fn fit_wide(
        theta: &[f64],
        omega: Option<f64>,
        y: &[f64],
        kmax: usize,
        z: &mut Phasors,
    ) -> Option<HarmonicFit> {
        fit_of(Phases::of(theta, omega), y, kmax, z)
    }
}

/// The Gauss-Newton frequency fit of [`harmonic_nls`].
#[derive(Debug, Clone)]
pub struct FrequencyFit {
    /// Fitted angular frequency (rad/s).
    pub omega: f64,
    /// Harmonic coefficients at `omega` (as [`HarmonicFit::coef`]).
    pub coef: Vec<f64>,
    /// Residual sum of squares at `omega`.
    pub rss: f64,
    /// Standard error of `omega` (rad/s); infinite when no step was evaluated.
    pub se: f64,
}

/// Gauss-Newton on `omega` and the linear coefficients of a `k`-harmonic model of `x` at the times
/// `tau` (s, centred; sampling step `dt`), from `omega0` (rad/s): `signal._sine._nls`, step for
/// step (variable projection; steps clamped to half a DFT bin and halved until the cost decreases;
/// stop below 1e-4 standard errors or 1e-12 bins). The phases are `omega tau` (unwrapped: the
/// reduction of [`super::sincos`] is exact there). `Ok(None)` when a fit is ill-conditioned (the
/// caller then runs the reference).
///
/// Errors: non-finite input, unequal lengths, `k < 1`, fewer samples than `2 k + 1`, `omega0` or `dt`
/// not finite and positive.
pub fn harmonic_nls(
    tau: &[f64],
    x: &[f64],
    omega0: f64,
    dt: f64,
    k: usize,
) -> Result<Option<FrequencyFit>> {
    check(tau, x, k)?;
    check_harmonics(tau.len(), k)?;
    for (name, v) in [("omega0", omega0), ("dt", dt)] {
        if !(v.is_finite() && v > 0.0) {
            return Err(CoreError::InvalidParameter(format!(
                "{name} = {v} must be finite and > 0"
            )));
        }
    }
    all_finite("x", x)?;
    Ok(Phasors::with(|z, z_trial| {
        nls_wide(tau, x, omega0, dt, k, z, z_trial)
    }))
}

wide_fn! {
    fn nls_wide(
        tau: &[f64],
        x: &[f64],
        omega0: f64,
        dt: f64,
        k: usize,
        z: &mut Phasors,
        z_trial: &mut Phasors,
    ) -> Option<FrequencyFit> {
        nls_of(tau, x, omega0, dt, k, z, z_trial)
    }
}

#[inline(always)]
fn nls_of<'b>(
    tau: &[f64],
    x: &[f64],
    omega0: f64,
    dt: f64,
    k: usize,
    mut z: &'b mut Phasors,
    mut z_trial: &'b mut Phasors,
) -> Option<FrequencyFit> {
    let n = x.len();
    let bin_width = 2.0 * std::f64::consts::PI / (n as f64 * dt);
    let dof = n.saturating_sub(2 * k + 2).max(1) as f64;
    let mut omega = omega0;
    // The phasors of the current fit and of a trial, swapped when the trial is accepted.
    let mut cur = fit_of(Phases::Scaled(omega, tau), x, k, z)?;
    let mut se = f64::INFINITY;
    for _ in 0..60 {
        let (_, r_d, d_d, xtd) = gauss_newton_of(z.phases(), tau, x, &cur.coef);
        let q_t_d = solve_upper_transposed(&cur.r, &xtd);
        let d_perp2 = d_d - q_t_d.iter().map(|v| v * v).sum::<f64>();
        if d_perp2.is_nan() || d_perp2 <= 0.0 {
            break;
        }
        se = (cur.rss / dof / d_perp2).sqrt();
        let mut step = r_d / d_perp2;
        if !step.is_finite() {
            break;
        }
        step = step.clamp(-0.5 * bin_width, 0.5 * bin_width);
        if step.abs() <= (1e-12 * bin_width).max(1e-4 * se) {
            break;
        }
        let previous = cur.rss;
        for _half in 0..10 {
            let trial = omega + step;
            if trial > 0.0 {
                let cand = fit_of(Phases::Scaled(trial, tau), x, k, z_trial)?;
                if cand.rss <= cur.rss {
                    omega = trial;
                    cur = cand;
                    std::mem::swap(&mut z, &mut z_trial);
                    break;
                }
            }
            step *= 0.5;
        }
        if previous - cur.rss <= 1e-14 * previous {
            break;
        }
    }
    Some(FrequencyFit {
        omega,
        coef: cur.coef,
        rss: cur.rss,
        se,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record(n: usize, p: f64) -> (Vec<f64>, Vec<f64>) {
        let theta: Vec<f64> = (0..n)
            .map(|i| {
                (2.0 * std::f64::consts::PI * (i as f64 / p + 0.3))
                    .rem_euclid(std::f64::consts::TAU)
            })
            .collect();
        let y: Vec<f64> = theta
            .iter()
            .enumerate()
            .map(|(i, t)| {
                0.3 + t.cos()
                    + 0.2 * (3.0 * t).sin()
                    + 0.01 * ((i * 7919 % 101) as f64 - 50.0) / 50.0
            })
            .collect();
        (theta, y)
    }

    #[test]
    fn fit_solves_the_normal_equations_of_the_explicit_basis() {
        let (theta, y) = record(1003, 61.7);
        let k = 4;
        let f = harmonic_fit(&theta, &y, k).unwrap().unwrap();
        let m = 2 * k + 1;
        let col = |j: usize, t: f64| {
            let h = j.div_ceil(2) as f64;
            if j == 0 {
                1.0
            } else if j % 2 == 1 {
                (h * t).cos()
            } else {
                (h * t).sin()
            }
        };
        // X^T (y - X coef) = 0 and the residual is the explicit one.
        let mut rss = 0.0;
        let mut grad = vec![0.0; m];
        for (t, v) in theta.iter().zip(&y) {
            let fit: f64 = (0..m).map(|j| f.coef[j] * col(j, *t)).sum();
            rss += (v - fit) * (v - fit);
            for (j, g) in grad.iter_mut().enumerate() {
                *g += col(j, *t) * (v - fit);
            }
        }
        assert!((f.rss - rss).abs() <= 1e-10 * rss);
        assert!(grad.iter().all(|g| g.abs() < 1e-9), "{grad:?}");
        assert!((f.coef[1] - 1.0).abs() < 1e-2 && (f.coef[6] - 0.2).abs() < 1e-2);
    }

    #[test]
    fn ill_conditioned_fits_are_refused_and_bad_input_is_an_error() {
        // A third of a period with 6 harmonics.
        let theta: Vec<f64> = (0..400).map(|i| 2.0 * i as f64 / 399.0).collect();
        let y: Vec<f64> = theta.iter().map(|t| t.cos()).collect();
        assert!(harmonic_fit(&theta, &y, 6).unwrap().is_none());
        assert!(harmonic_fit(&theta, &y[..10], 2).is_err());
        assert!(harmonic_fit(&theta, &y, 0).is_err());
        // More coefficients than samples (and a Gram matrix larger than memory): refused.
        assert!(matches!(
            harmonic_fit(&theta, &y, 200),
            Err(CoreError::InsufficientData(_))
        ));
        assert!(matches!(
            harmonic_fit(&[], &[], 1),
            Err(CoreError::InsufficientData(_))
        ));
        assert!(!well_conditioned(&[1.0, 0.99999, 0.99999, 1.0], 2));
        assert!(well_conditioned(&[1.0, 0.999, 0.999, 1.0], 2));
        assert!(!well_conditioned(&[1.0, 0.0, 0.0, -1.0], 2));
    }

    #[test]
    fn unscaled_variances_are_the_diagonal_of_the_inverse_normal_matrix() {
        // R = [[2, 1, 0.5], [0, 1, -1], [0, 0, 4]]: (R^T R)^-1 = R^-1 R^-T, whose diagonal is the
        // row sums of squares of R^-1 = [[0.5, -0.5, -0.1875], [0, 1, 0.25], [0, 0, 0.25]].
        let r = [2.0, 1.0, 0.5, 0.0, 1.0, -1.0, 0.0, 0.0, 4.0];
        let v = unscaled_variances(&r, 3).unwrap();
        let e = [0.25 + 0.25 + 0.1875 * 0.1875, 1.0 + 0.0625, 0.0625];
        for (a, b) in v.iter().zip(&e) {
            assert!((a - b).abs() < 1e-15, "{v:?}");
        }
        assert!(unscaled_variances(&r[..8], 3).is_err());
        let mut singular = r;
        singular[4] = 0.0;
        assert!(unscaled_variances(&singular, 3).is_err());
    }

    #[test]
    fn avx2_and_baseline_versions_compute_the_same_bits() {
        // No fused multiply-add in either: only the register width differs.
        let (theta, y) = record(2001, 37.9);
        let tau: Vec<f64> = (0..2001).map(|i| (i as f64 - 1000.0) * 1e-3).collect();
        let run = || {
            let f = harmonic_fit(&theta, &y, 9).unwrap().unwrap();
            let g = harmonic_nls(&tau, &y, 2.0 * std::f64::consts::PI * 26.4, 1e-3, 2)
                .unwrap()
                .unwrap();
            let v = unscaled_variances(&f.r, 19).unwrap();
            (f.coef, f.r, f.rss, g.omega, g.coef, v)
        };
        let wide = run();
        super::super::wide::force_baseline(true);
        let base = run();
        super::super::wide::force_baseline(false);
        assert_eq!(format!("{wide:?}"), format!("{base:?}"));
    }

    #[test]
    fn frequency_fit_finds_the_tone() {
        let (n, dt, omega) = (4001, 1e-3, 2.0 * std::f64::consts::PI * 3.3);
        let tau: Vec<f64> = (0..n).map(|i| (i as f64 - 2000.0) * dt).collect();
        let x: Vec<f64> = tau
            .iter()
            .map(|t| 0.1 + 1.3 * (omega * t + 0.7).cos())
            .collect();
        let f = harmonic_nls(&tau, &x, omega * 1.01, dt, 1)
            .unwrap()
            .unwrap();
        assert!((f.omega - omega).abs() < 1e-9 * omega, "{}", f.omega);
        assert!(f.rss < 1e-18);
        assert!(harmonic_nls(&tau, &x, -1.0, dt, 1).is_err());
        assert!(harmonic_nls(&tau, &x, omega, 0.0, 1).is_err());
    }
}
