//! TEST-ONLY bindings: kernels that no module of the package calls. They are exported so that
//! `tests/test_fastlab.py` can hold each one to its NumPy reference on its own (the production
//! bindings in [`super::lab`] fuse them); `_core.pyi` lists them under a "test-only" block. Do not
//! build on them: they may change or go without notice.

use numpy::{IntoPyArray, PyReadonlyArray1};
use pyo3::prelude::*;

use super::convert::{arg, count, slice, Vector};
use crate::lab;

pub(super) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(harmonic_moments, m)?)?;
    m.add_function(wrap_pyfunction!(harmonic_series, m)?)?;
    m.add_function(wrap_pyfunction!(harmonic_gauss_newton, m)?)?;
    m.add_function(wrap_pyfunction!(cholesky_upper, m)?)?;
    m.add_function(wrap_pyfunction!(padded_spectrum, m)?)?;
    Ok(())
}

/// `(mu_re, mu_im, r_re, r_im)` of [`harmonic_moments`].
type Moments<'py> = (Vector<'py>, Vector<'py>, Vector<'py>, Vector<'py>);

/// Test-only. Complex moments of the harmonic basis (`rust/lab.rs`): `(mu_re, mu_im, r_re, r_im)`
/// with `mu_q = sum e^{i q theta}`, `q <= 2 kmax`, and `r_q = sum y e^{-i q theta}`, `q <= kmax`.
#[pyfunction]
#[pyo3(signature = (theta, y, kmax))]
fn harmonic_moments<'py>(
    py: Python<'py>,
    #[pyo3(from_py_with = arg)] theta: PyReadonlyArray1<'py, f64>,
    #[pyo3(from_py_with = arg)] y: PyReadonlyArray1<'py, f64>,
    #[pyo3(from_py_with = arg)] kmax: i64,
) -> PyResult<Moments<'py>> {
    let (theta, y) = (slice("theta", &theta)?, slice("y", &y)?);
    let kmax = count("kmax", kmax, 1)?;
    let ((mr, mi), (rr, ri)) = py.detach(|| lab::harmonic_moments(theta, y, kmax))?;
    Ok((
        mr.into_pyarray(py),
        mi.into_pyarray(py),
        rr.into_pyarray(py),
        ri.into_pyarray(py),
    ))
}

/// Test-only. `coef[0] + sum_k coef[2k-1] cos(k theta) + coef[2k] sin(k theta)` at every phase
/// (`rust/lab.rs`).
#[pyfunction]
#[pyo3(signature = (theta, coef))]
fn harmonic_series<'py>(
    py: Python<'py>,
    #[pyo3(from_py_with = arg)] theta: PyReadonlyArray1<'py, f64>,
    #[pyo3(from_py_with = arg)] coef: PyReadonlyArray1<'py, f64>,
) -> PyResult<Vector<'py>> {
    let (theta, coef) = (slice("theta", &theta)?, slice("coef", &coef)?);
    let out = py.detach(|| lab::harmonic_series(theta, coef))?;
    Ok(out.into_pyarray(py))
}

/// Test-only. Gauss-Newton terms `(r.r, r.d, d.d, X^T d)` of the frequency fit of `x` on the
/// harmonic series `coef` at phases `theta`, times `tau` (`rust/lab.rs`).
#[pyfunction]
#[pyo3(signature = (theta, tau, x, coef))]
fn harmonic_gauss_newton<'py>(
    py: Python<'py>,
    #[pyo3(from_py_with = arg)] theta: PyReadonlyArray1<'py, f64>,
    #[pyo3(from_py_with = arg)] tau: PyReadonlyArray1<'py, f64>,
    #[pyo3(from_py_with = arg)] x: PyReadonlyArray1<'py, f64>,
    #[pyo3(from_py_with = arg)] coef: PyReadonlyArray1<'py, f64>,
) -> PyResult<(f64, f64, f64, Vector<'py>)> {
    let (theta, tau) = (slice("theta", &theta)?, slice("tau", &tau)?);
    let (x, coef) = (slice("x", &x)?, slice("coef", &coef)?);
    let (rr, rd, dd, xtd) = py.detach(|| lab::harmonic_gauss_newton(theta, tau, x, coef))?;
    Ok((rr, rd, dd, xtd.into_pyarray(py)))
}

/// Test-only. Upper Cholesky factor of the row-major `m x m` Gram matrix `gram` (flat, length
/// `m * m`), flat row-major (`rust/lab.rs`).
#[pyfunction]
#[pyo3(signature = (gram, m))]
fn cholesky_upper<'py>(
    py: Python<'py>,
    #[pyo3(from_py_with = arg)] gram: PyReadonlyArray1<'py, f64>,
    #[pyo3(from_py_with = arg)] m: i64,
) -> PyResult<Vector<'py>> {
    let gram = slice("gram", &gram)?;
    let m = count("m", m, 0)?;
    let out = py.detach(|| lab::cholesky_upper(gram, m))?;
    Ok(out.into_pyarray(py))
}

/// Test-only. `|rfft(hann * detrended x, nfft)|` (`rust/lab/spectrum.rs`): the sine analysis's
/// spectrum, which `spectral_peak` computes inside.
#[pyfunction]
#[pyo3(signature = (x, nfft))]
fn padded_spectrum<'py>(
    py: Python<'py>,
    #[pyo3(from_py_with = arg)] x: PyReadonlyArray1<'py, f64>,
    #[pyo3(from_py_with = arg)] nfft: i64,
) -> PyResult<Vector<'py>> {
    let x = slice("x", &x)?;
    let nfft = count("nfft", nfft, 2)?;
    let out = py.detach(|| lab::spectrum::padded_spectrum(x, nfft))?;
    Ok(out.into_pyarray(py))
}
