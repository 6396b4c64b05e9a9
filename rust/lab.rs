//! Hot loops of the lab preprocessing (`python/bouc_wen_id/signal/`, issue #8): the harmonic
//! least squares behind the sine analysis, the steady segments and the synchronous average.
//!
//! A fit of `y` on `[1, cos k theta, sin k theta]`, `k = 1..K`, needs the Gram matrix of the basis
//! and its products with `y`. With `z_n = e^{i theta_n}` both follow from the complex moments
//! `mu_q = sum_n z_n^q` (`q = 0..2K`; the Gram matrix is Toeplitz-plus-Hankel in them) and
//! `r_q = sum_n y_n conj(z_n)^q` (`q = 0..K`), in one pass of the phasor recurrence
//! `z^(q+1) = z^q z`: O(n K) work instead of the O(n K^2) of forming the basis and its QR. The
//! NumPy reference of the same recurrence is `signal._harmonic_ls._moment_fit`; [`fit`] does the
//! rest of a fit (Gram matrix, conditioning check, Cholesky factor, solves, explicit residual) and
//! the Gauss-Newton frequency fit of `signal._sine._nls`, so that a fit is one call.
//!
//! The samples are processed in blocks of [`LANES`] held as separate real and imaginary arrays, so
//! that the recurrences of neighbouring samples (independent) fill the vector registers; [`wide`]
//! compiles the kernels for AVX2 when the CPU has it. Each sample's powers are formed as the NumPy
//! reference forms them (`p *= z`, complex multiply without fused operations); the phasors come
//! from [`sincos`] (within 2 ulp of `libm`) and the sums are taken in another order (rounding of
//! order `n eps` relative, far below the noise of any record).
//!
//! Layout: this file holds the checks and the public kernels; `phasors.rs` the phasors and lane
//! blocks, `moments.rs` the moment pass, `series.rs` the series, residual and Gauss-Newton passes,
//! `cholesky.rs` the factor; [`fit`], [`windows`] and [`spectrum`] build on them.

mod cholesky;
pub mod fit;
mod moments;
mod phasors;
mod series;
pub mod sincos;
pub mod spectrum;
mod wide;
pub mod windows;

use wide::wide_fn;

use crate::error::{all_finite, CoreError, Result};

pub(crate) use cholesky::cholesky_of;
pub(crate) use moments::moments_of;
use phasors::{Block, LANES};
pub(crate) use phasors::{Phases, Phasors};
use series::block_series;
pub(crate) use series::{gauss_newton_of, rss_of};

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

/// A fit on `kmax` harmonics has `2 kmax + 1` coefficients: `n` samples must hold at least that many
/// (the check also bounds the `(2 kmax + 1)^2` Gram matrix by the record's own size).
pub(crate) fn check_harmonics(n: usize, kmax: usize) -> Result<()> {
    if kmax.saturating_mul(2).saturating_add(1) > n {
        return Err(CoreError::InsufficientData(format!(
            "{kmax} harmonics need {} samples, the record holds {n}",
            kmax.saturating_mul(2).saturating_add(1)
        )));
    }
    Ok(())
}

fn check_coef(coef: &[f64], min_harmonics: usize) -> Result<()> {
    all_finite("coef", coef)?;
    if coef.len() % 2 == 0 || coef.len() < 2 * min_harmonics + 1 {
        return Err(CoreError::InvalidParameter(format!(
            "coef must hold 2K + 1 values [c, a_1, b_1, ...] with K >= {min_harmonics}, got {}",
            coef.len()
        )));
    }
    Ok(())
}

/// Moments of the harmonic basis at the phases `theta` (rad, length n) against `y` (length n):
/// `mu_q = sum_n e^{i q theta_n}`, `q = 0..=2 kmax`, and `r_q = sum_n y_n e^{-i q theta_n}`,
/// `q = 0..=kmax`, each as `(real parts, imaginary parts)`.
///
/// Errors: non-finite input, unequal lengths, `kmax < 1`, fewer samples than `2 kmax + 1`.
#[allow(clippy::type_complexity)]
pub fn harmonic_moments(
    theta: &[f64],
    y: &[f64],
    kmax: usize,
) -> Result<((Vec<f64>, Vec<f64>), (Vec<f64>, Vec<f64>))> {
    check(theta, y, kmax)?;
    check_harmonics(theta.len(), kmax)?;
    Ok(Phasors::with(|z, _| moments_wide(theta, y, kmax, z)))
}

/// `(mu, r)` moments as (real, imaginary) parts.
type Moments = ((Vec<f64>, Vec<f64>), (Vec<f64>, Vec<f64>));

wide_fn! {
    fn moments_wide(theta: &[f64], y: &[f64], kmax: usize, z: &mut Phasors) -> Moments {
        moments_of(z.fill(Phases::Given(theta)), y, kmax)
    }
}

/// The harmonic series `coef[0] + sum_k coef[2k-1] cos(k theta_n) + coef[2k] sin(k theta_n)` at
/// every phase (length n), by the same phasor recurrence; `coef` has length `2K + 1`, `K >= 0`.
///
/// Errors: non-finite input, an even `coef` length.
pub fn harmonic_series(theta: &[f64], coef: &[f64]) -> Result<Vec<f64>> {
    all_finite("theta", theta)?;
    check_coef(coef, 0)?;
    Ok(Phasors::with(|z, _| series_wide(theta, coef, z)))
}

wide_fn! {
    fn series_wide(theta: &[f64], coef: &[f64], buf: &mut Phasors) -> Vec<f64> {
        let mut out = vec![0.0; theta.len()];
        let z = buf.fill(Phases::Given(theta));
        for start in (0..theta.len()).step_by(LANES) {
            let b = Block::load(z, theta, None, start);
            let s = block_series(&b, coef);
            out[start..start + b.lanes].copy_from_slice(&s[..b.lanes]);
        }
        out
    }
}

/// Residual sum of squares `sum_n (y_n - series(theta_n))^2` (units of `y` squared) of the harmonic
/// series `coef` (as [`harmonic_series`]) against `y` (length n), without the n-vector of the series:
/// the fast path's explicit residual needs no BLAS call (a threaded `ddot` on a long vector costs
/// milliseconds on a loaded machine, more than the fit).
///
/// Errors: non-finite input, unequal lengths, an even `coef` length.
pub fn harmonic_rss(theta: &[f64], y: &[f64], coef: &[f64]) -> Result<f64> {
    harmonic_rss_at(theta, None, y, coef)
}

/// [`harmonic_rss`] at the phases `theta`, or at `omega tau` when `omega` (rad/s) is given and
/// `theta` holds the times `tau` (s): no wrapped phase array is formed (the reduction of [`sincos`]
/// is exact over a record's phases).
///
/// Errors: as [`harmonic_rss`], and a non-finite `omega`.
pub fn harmonic_rss_at(theta: &[f64], omega: Option<f64>, y: &[f64], coef: &[f64]) -> Result<f64> {
    check(theta, y, 1)?;
    check_coef(coef, 0)?;
    check_omega(omega)?;
    Ok(Phasors::with(|z, _| rss_wide(theta, omega, y, coef, z)))
}

/// `a` finite and holding an `m x m` matrix (`m >= 1`).
pub(crate) fn check_square(name: &str, a: &[f64], m: usize) -> Result<()> {
    all_finite(name, a)?;
    if a.len() != m * m || m == 0 {
        return Err(CoreError::InvalidParameter(format!(
            "{name} must hold m * m = {} values (m >= 1), got {}",
            m * m,
            a.len()
        )));
    }
    Ok(())
}

/// `omega`, when given, finite.
pub(crate) fn check_omega(omega: Option<f64>) -> Result<()> {
    match omega {
        Some(w) if !w.is_finite() => {
            Err(CoreError::NonFinite(format!("omega = {w} is not finite")))
        }
        _ => Ok(()),
    }
}

wide_fn! {
    fn rss_wide(theta: &[f64], omega: Option<f64>, y: &[f64], coef: &[f64], z: &mut Phasors) -> f64 {
        rss_of(z.fill(Phases::of(theta, omega)), y, coef)
    }
}

/// Upper Cholesky factor `R` (`R^T R = G`, row-major `m x m`, zeros below the diagonal) of the
/// symmetric positive definite Gram matrix `gram` (row-major `m x m`, only its lower triangle read),
/// as `numpy.linalg.cholesky(gram).T`. The synchronous average's Gram matrix has `m = 2K + 1` up to
/// 401; LAPACK through a threaded OpenBLAS wakes its threads for it, which on a loaded 2-core machine
/// cost hundreds of milliseconds per call (issue #8), against a few here (dot-product form, rows
/// contiguous).
///
/// Errors: non-finite input, `gram.len() != m * m`, a matrix that is not positive definite.
pub fn cholesky_upper(gram: &[f64], m: usize) -> Result<Vec<f64>> {
    check_square("gram", gram, m)?;
    cholesky_wide(gram, m).map_err(|(i, s)| {
        CoreError::InvalidParameter(format!(
            "the Gram matrix is not positive definite (pivot {i}: {s:e})"
        ))
    })
}

wide_fn! {
    fn cholesky_wide(gram: &[f64], m: usize) -> std::result::Result<Vec<f64>, (usize, f64)> {
        cholesky_of(gram, m)
    }
}

/// Gauss-Newton terms of the frequency fit (variable projection, `signal._sine._nls`) at the phases
/// `theta = omega tau` (rad), the times `tau` (s), the record `x` and the harmonic coefficients
/// `coef = [c, a_1, b_1, ...]` (length `2K + 1`, `K >= 1`), in one pass without forming the basis:
/// with the residual `r = x - X coef` and `d = d(X coef)/d omega = tau sum_k k (b_k cos k theta -
/// a_k sin k theta)`, returns `(r.r, r.d, d.d, X^T d)` (`X^T d` of length `2K + 1`, ordered as
/// `coef`). The NumPy reference forms `X` (`_harmonic_ls.harmonic_basis`) and `d`
/// (`_sine._omega_column`) explicitly.
///
/// Errors: non-finite input, unequal lengths, an even `coef` length or `K = 0`.
pub fn harmonic_gauss_newton(
    theta: &[f64],
    tau: &[f64],
    x: &[f64],
    coef: &[f64],
) -> Result<(f64, f64, f64, Vec<f64>)> {
    check(theta, x, 1)?;
    all_finite("tau", tau)?;
    if tau.len() != theta.len() {
        return Err(CoreError::InvalidParameter(format!(
            "theta and tau must have equal lengths, got {} and {}",
            theta.len(),
            tau.len()
        )));
    }
    check_coef(coef, 1)?;
    Ok(Phasors::with(|z, _| {
        gauss_newton_wide(theta, tau, x, coef, z)
    }))
}

wide_fn! {
    fn gauss_newton_wide(
        theta: &[f64],
        tau: &[f64],
        x: &[f64],
        coef: &[f64],
        z: &mut Phasors,
    ) -> (f64, f64, f64, Vec<f64>) {
        gauss_newton_of(z.fill(Phases::Given(theta)), tau, x, coef)
    }
}

#[cfg(test)]
mod tests;
