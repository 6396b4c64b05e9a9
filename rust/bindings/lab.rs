//! The laboratory kernels behind `bouc_wen_id.signal`: harmonic least squares, the frequency
//! fit, per-period window fits and the spectral peak (`rust/lab.rs`, `rust/lab/*.rs`).

use numpy::{IntoPyArray, PyReadonlyArray1};
use pyo3::prelude::*;

use super::convert::{arg, count, indices, matrix, slice, Matrix, Vector};
use crate::lab;

pub(super) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(harmonic_rss, m)?)?;
    m.add_function(wrap_pyfunction!(harmonic_fit, m)?)?;
    m.add_function(wrap_pyfunction!(harmonic_nls, m)?)?;
    m.add_function(wrap_pyfunction!(gram_well_conditioned, m)?)?;
    m.add_function(wrap_pyfunction!(unscaled_variances, m)?)?;
    m.add_function(wrap_pyfunction!(window_fits, m)?)?;
    m.add_function(wrap_pyfunction!(spectral_peak, m)?)?;
    Ok(())
}

/// `sum (y - series(theta))^2` of the harmonic series `coef` against `y` (`rust/lab.rs`).
#[pyfunction]
#[pyo3(signature = (theta, y, coef, omega=None))]
fn harmonic_rss<'py>(
    py: Python<'py>,
    #[pyo3(from_py_with = arg)] theta: PyReadonlyArray1<'py, f64>,
    #[pyo3(from_py_with = arg)] y: PyReadonlyArray1<'py, f64>,
    #[pyo3(from_py_with = arg)] coef: PyReadonlyArray1<'py, f64>,
    #[pyo3(from_py_with = arg)] omega: Option<f64>,
) -> PyResult<f64> {
    let (theta, y) = (slice("theta", &theta)?, slice("y", &y)?);
    let coef = slice("coef", &coef)?;
    Ok(py.detach(|| lab::harmonic_rss_at(theta, omega, y, coef))?)
}

/// `(coef, R, Q^T y, rss)` of one harmonic least-squares fit (`rust/lab/fit.rs`), `R` flat
/// row-major `m x m`; `None` when the Gram matrix is too ill-conditioned for the normal equations.
type HarmonicFitOut<'py> = Option<(Vector<'py>, Vector<'py>, Vector<'py>, f64)>;

/// The whole harmonic least-squares fit of `y` on harmonics `1..=kmax` of `theta` in one call
/// (`rust/lab/fit.rs`): `(coef, R (flat), Q^T y, rss)`, or `None` (ill-conditioned: use QR).
#[pyfunction]
#[pyo3(signature = (theta, y, kmax, omega=None))]
fn harmonic_fit<'py>(
    py: Python<'py>,
    #[pyo3(from_py_with = arg)] theta: PyReadonlyArray1<'py, f64>,
    #[pyo3(from_py_with = arg)] y: PyReadonlyArray1<'py, f64>,
    #[pyo3(from_py_with = arg)] kmax: i64,
    #[pyo3(from_py_with = arg)] omega: Option<f64>,
) -> PyResult<HarmonicFitOut<'py>> {
    let (theta, y) = (slice("theta", &theta)?, slice("y", &y)?);
    let kmax = count("kmax", kmax, 1)?;
    let fit = py.detach(|| lab::fit::harmonic_fit_at(theta, omega, y, kmax))?;
    Ok(fit.map(|f| {
        let (coef, r, qty) = (f.coef, f.r, f.qty);
        (
            coef.into_pyarray(py),
            r.into_pyarray(py),
            qty.into_pyarray(py),
            f.rss,
        )
    }))
}

/// `(omega, coef, rss, se)` of [`harmonic_nls`], or `None`.
type FrequencyFitOut<'py> = Option<(f64, Vector<'py>, f64, f64)>;

/// The Gauss-Newton frequency fit of `signal._sine._nls` in one call (`rust/lab/fit.rs`):
/// `(omega, coef, rss, se)`, or `None` when a fit is ill-conditioned (run the reference).
#[pyfunction]
#[pyo3(signature = (tau, x, omega0, dt, k))]
fn harmonic_nls<'py>(
    py: Python<'py>,
    #[pyo3(from_py_with = arg)] tau: PyReadonlyArray1<'py, f64>,
    #[pyo3(from_py_with = arg)] x: PyReadonlyArray1<'py, f64>,
    #[pyo3(from_py_with = arg)] omega0: f64,
    #[pyo3(from_py_with = arg)] dt: f64,
    #[pyo3(from_py_with = arg)] k: i64,
) -> PyResult<FrequencyFitOut<'py>> {
    let (tau, x) = (slice("tau", &tau)?, slice("x", &x)?);
    let k = count("k", k, 1)?;
    let fit = py.detach(|| lab::fit::harmonic_nls(tau, x, omega0, dt, k))?;
    Ok(fit.map(|f| (f.omega, f.coef.into_pyarray(py), f.rss, f.se)))
}

/// The conditioning check of the fused fit (`rust/lab/fit.rs`): `cond(D^-1/2 G D^-1/2) <= 1e4`
/// and positive definite, `G` flat row-major `m x m`.
#[pyfunction]
#[pyo3(signature = (gram, m))]
fn gram_well_conditioned(
    #[pyo3(from_py_with = arg)] gram: PyReadonlyArray1<'_, f64>,
    #[pyo3(from_py_with = arg)] m: i64,
) -> PyResult<bool> {
    let gram = slice("gram", &gram)?;
    let m = count("m", m, 0)?;
    Ok(lab::fit::gram_well_conditioned(gram, m)?)
}

/// Diagonal of `(R^T R)^-1` for the upper triangular `R` (flat row-major `m x m`,
/// `rust/lab/fit.rs`): the unscaled variances of a fit.
#[pyfunction]
#[pyo3(signature = (r, m))]
fn unscaled_variances<'py>(
    py: Python<'py>,
    #[pyo3(from_py_with = arg)] r: PyReadonlyArray1<'py, f64>,
    #[pyo3(from_py_with = arg)] m: i64,
) -> PyResult<Vector<'py>> {
    let r = slice("r", &r)?;
    let m = count("m", m, 0)?;
    let out = py.detach(|| lab::fit::unscaled_variances(r, m))?;
    Ok(out.into_pyarray(py))
}

/// `(coef, rss)` of [`window_fits`].
type WindowFitsOut<'py> = (Matrix<'py>, Matrix<'py>);

/// The per-period fits of `u` and `y` in the windows `[starts[i], stops[i])` of a block at the
/// phases `theta` (`rust/lab/windows.rs`): `(coef (windows x 2m), rss (windows x 2))`, NaN rows
/// where a window's Gram matrix is ill-conditioned.
#[pyfunction]
#[pyo3(signature = (theta, u, y, starts, stops, k, omega=None))]
#[allow(clippy::too_many_arguments)]
fn window_fits<'py>(
    py: Python<'py>,
    #[pyo3(from_py_with = arg)] theta: PyReadonlyArray1<'py, f64>,
    #[pyo3(from_py_with = arg)] u: PyReadonlyArray1<'py, f64>,
    #[pyo3(from_py_with = arg)] y: PyReadonlyArray1<'py, f64>,
    #[pyo3(from_py_with = arg)] starts: Vec<i64>,
    #[pyo3(from_py_with = arg)] stops: Vec<i64>,
    #[pyo3(from_py_with = arg)] k: i64,
    #[pyo3(from_py_with = arg)] omega: Option<f64>,
) -> PyResult<WindowFitsOut<'py>> {
    let (theta, u, y) = (slice("theta", &theta)?, slice("u", &u)?, slice("y", &y)?);
    let k = count("k", k, 1)?;
    let (starts, stops) = (indices("starts", &starts)?, indices("stops", &stops)?);
    let f = py.detach(|| lab::windows::window_fits_at(theta, omega, u, y, &starts, &stops, k))?;
    let windows = starts.len();
    let columns = 2 * (2 * f.harmonics + 1);
    Ok((
        matrix(py, windows, columns, f.coef)?,
        matrix(py, windows, 2, f.rss)?,
    ))
}

/// The bin `dft_peak` takes and its neighbours, `(k, |X_{k-1}|, |X_k|, |X_{k+1}|)`
/// (`rust/lab/spectrum.rs`); `band_lo`/`band_hi` < 0: no band.
#[pyfunction]
#[pyo3(signature = (x, nfft, lo, hi, band_lo, band_hi, peak_min))]
#[allow(clippy::too_many_arguments)]
fn spectral_peak(
    py: Python<'_>,
    #[pyo3(from_py_with = arg)] x: PyReadonlyArray1<'_, f64>,
    #[pyo3(from_py_with = arg)] nfft: i64,
    #[pyo3(from_py_with = arg)] lo: i64,
    #[pyo3(from_py_with = arg)] hi: i64,
    #[pyo3(from_py_with = arg)] band_lo: i64,
    #[pyo3(from_py_with = arg)] band_hi: i64,
    #[pyo3(from_py_with = arg)] peak_min: f64,
) -> PyResult<(usize, f64, f64, f64)> {
    let x = slice("x", &x)?;
    let nfft = count("nfft", nfft, 2)?;
    let (lo, hi) = (count("lo", lo, 1)?, count("hi", hi, 1)?);
    let (band_lo, band_hi) = if band_lo < 0 || band_hi < 0 {
        (0, 0)
    } else {
        (count("band_lo", band_lo, 0)?, count("band_hi", band_hi, 0)?)
    };
    Ok(py.detach(|| lab::spectrum::spectral_peak(x, nfft, lo, hi, band_lo, band_hi, peak_min))?)
}
