//! The estimators of the seed paper on one averaged period, (4a)-(27b): averaging, phase,
//! derivative, the separable least squares and its mu search, the gain, the steady loop and the
//! phase profiles (`rust/average.rs`, `estimate.rs`, `solve.rs`, `steady.rs`, `profile.rs`).

use numpy::{IntoPyArray, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;

use super::convert::{arg, callable, count, rows, slice, Matrix, Vector};
use super::detach;
use crate::budget::Work;
use crate::error::{self, CoreError};
use crate::solve::{self, SlsProblem, GOLDEN_MAX_ITER};
use crate::{average, estimate, profile, steady};

// The Python defaults `max_iter=200` are literals so that `__text_signature__` shows them.
const _: () = assert!(GOLDEN_MAX_ITER == 200);

pub(super) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(periodic_average, m)?)?;
    m.add_function(wrap_pyfunction!(phase_from_max, m)?)?;
    m.add_function(wrap_pyfunction!(spectral_derivative, m)?)?;
    m.add_function(wrap_pyfunction!(sls_regressor, m)?)?;
    m.add_function(wrap_pyfunction!(solve_normal, m)?)?;
    m.add_function(wrap_pyfunction!(sls_theta, m)?)?;
    m.add_function(wrap_pyfunction!(golden_section, m)?)?;
    m.add_function(wrap_pyfunction!(sls_search, m)?)?;
    m.add_function(wrap_pyfunction!(gain_estimate, m)?)?;
    m.add_function(wrap_pyfunction!(steady_loop, m)?)?;
    m.add_function(wrap_pyfunction!(profile_phase_sls, m)?)?;
    m.add_function(wrap_pyfunction!(profile_phase_gain, m)?)?;
    Ok(())
}

/// Periodic average (4a-b) of `y` over `periods` periods after `settle_periods` dropped ones.
#[pyfunction]
#[pyo3(signature = (y, samples_per_period, settle_periods, periods))]
fn periodic_average<'py>(
    py: Python<'py>,
    #[pyo3(from_py_with = arg)] y: PyReadonlyArray1<'py, f64>,
    #[pyo3(from_py_with = arg)] samples_per_period: i64,
    #[pyo3(from_py_with = arg)] settle_periods: i64,
    #[pyo3(from_py_with = arg)] periods: i64,
) -> PyResult<Vector<'py>> {
    let y = slice("y", &y)?;
    let (p, s, n) = match (
        usize::try_from(samples_per_period),
        usize::try_from(settle_periods),
        usize::try_from(periods),
    ) {
        (Ok(p), Ok(s), Ok(n)) => (p, s, n),
        // A negative count: report it as the core would, in the reference's order.
        _ => {
            error::all_finite("y", y)?;
            return Err(if samples_per_period < 0 {
                CoreError::InsufficientData(format!(
                    "samples_per_period = {samples_per_period}: at least 4 samples per period \
                     are needed"
                ))
            } else if periods < 0 {
                CoreError::InsufficientData(format!(
                    "periods = {periods}: at least one period must be averaged"
                ))
            } else {
                CoreError::InvalidParameter(format!(
                    "settle_periods = {settle_periods} must be >= 0"
                ))
            }
            .into());
        }
    };
    let ybar = detach::by_size(py, y.len(), || average::periodic_average(y, p, s, n))?;
    Ok(ybar.into_pyarray(py))
}

/// Phase estimator (9): `2 pi j*/P` (rad) with `j*` the first maximum of `ybar`.
#[pyfunction]
#[pyo3(signature = (ybar))]
fn phase_from_max(#[pyo3(from_py_with = arg)] ybar: PyReadonlyArray1<'_, f64>) -> PyResult<f64> {
    Ok(estimate::phase_from_max(slice("ybar", &ybar)?)?)
}

/// Spectral derivative of one period `ybar` at `omega` (rad/s) from harmonics 1..=harmonics
/// (at most floor((P-1)/2)).
#[pyfunction]
#[pyo3(signature = (ybar, omega, harmonics))]
fn spectral_derivative<'py>(
    py: Python<'py>,
    #[pyo3(from_py_with = arg)] ybar: PyReadonlyArray1<'py, f64>,
    #[pyo3(from_py_with = arg)] omega: f64,
    #[pyo3(from_py_with = arg)] harmonics: i64,
) -> PyResult<Vector<'py>> {
    let ybar = slice("ybar", &ybar)?;
    let Ok(k) = usize::try_from(harmonics) else {
        error::all_finite("ybar", ybar)?;
        error::finite("omega", omega)?;
        return Err(CoreError::InvalidParameter(format!(
            "harmonics = {harmonics} must be in [1, {}] for {} samples per period",
            estimate::max_harmonics(ybar.len()),
            ybar.len()
        ))
        .into());
    };
    let ydot = detach::by_size(py, ybar.len(), || {
        estimate::spectral_derivative(ybar, omega, k)
    })?;
    Ok(ydot.into_pyarray(py))
}

/// The SLS problem of one averaged period: `ybar`, `ydot`, the input amplitude, omega and phi.
fn sls_problem(
    ybar: &PyReadonlyArray1<'_, f64>,
    ydot: &PyReadonlyArray1<'_, f64>,
    (amplitude, omega, phi): (f64, f64, f64),
) -> PyResult<SlsProblem> {
    let (ybar, ydot) = (slice("ybar", ybar)?, slice("ydot", ydot)?);
    Ok(SlsProblem::new(ybar, ydot, amplitude, omega, phi)?)
}

/// Regressor (23) at exponent `nu`, shape (P, 3).
#[pyfunction]
#[pyo3(signature = (ybar, ydot, amplitude, omega, phi, nu))]
fn sls_regressor<'py>(
    py: Python<'py>,
    #[pyo3(from_py_with = arg)] ybar: PyReadonlyArray1<'py, f64>,
    #[pyo3(from_py_with = arg)] ydot: PyReadonlyArray1<'py, f64>,
    #[pyo3(from_py_with = arg)] amplitude: f64,
    #[pyo3(from_py_with = arg)] omega: f64,
    #[pyo3(from_py_with = arg)] phi: f64,
    #[pyo3(from_py_with = arg)] nu: f64,
) -> PyResult<Matrix<'py>> {
    let problem = sls_problem(&ybar, &ydot, (amplitude, omega, phi))?;
    rows(py, &problem.regressor(nu)?)
}

/// Solves the 3x3 normal equations `m theta = r` (Jacobi scaling, Cholesky); returns
/// `(theta, rcond)`.
#[pyfunction]
#[pyo3(signature = (m, r))]
fn solve_normal<'py>(
    py: Python<'py>,
    #[pyo3(from_py_with = arg)] m: PyReadonlyArray2<'py, f64>,
    #[pyo3(from_py_with = arg)] r: PyReadonlyArray1<'py, f64>,
) -> PyResult<(Vector<'py>, f64)> {
    let (mv, rv) = (m.as_array(), r.as_array());
    if mv.shape() != [3, 3] || rv.shape() != [3] {
        return Err(CoreError::InvalidParameter(format!(
            "expected a (3, 3) matrix and a (3,) vector, got {:?}, {:?}",
            mv.shape(),
            rv.shape()
        ))
        .into());
    }
    let mm = nalgebra::Matrix3::from_fn(|i, j| mv[[i, j]]);
    let rr = nalgebra::Vector3::from_fn(|i, _| rv[i]);
    let (theta, rcond) = solve::solve_normal(&mm, &rr)?;
    Ok((theta.as_slice().to_vec().into_pyarray(py), rcond))
}

/// `theta(nu)` (22) and the cost `I_N(nu)` (21).
#[pyfunction]
#[pyo3(signature = (ybar, ydot, amplitude, omega, phi, nu))]
fn sls_theta<'py>(
    py: Python<'py>,
    #[pyo3(from_py_with = arg)] ybar: PyReadonlyArray1<'py, f64>,
    #[pyo3(from_py_with = arg)] ydot: PyReadonlyArray1<'py, f64>,
    #[pyo3(from_py_with = arg)] amplitude: f64,
    #[pyo3(from_py_with = arg)] omega: f64,
    #[pyo3(from_py_with = arg)] phi: f64,
    #[pyo3(from_py_with = arg)] nu: f64,
) -> PyResult<(Vector<'py>, f64)> {
    let problem = sls_problem(&ybar, &ydot, (amplitude, omega, phi))?;
    let (theta, cost) = problem.cost(nu)?;
    Ok((theta.as_slice().to_vec().into_pyarray(py), cost))
}

/// Golden-section minimisation of the Python callable `func` on `[lo, hi]`; returns
/// `(x, func(x), iterations)`. Exceptions raised by `func` propagate unchanged.
#[pyfunction]
#[pyo3(signature = (func, lo, hi, tol, max_iter=200))]
fn golden_section(
    #[pyo3(from_py_with = callable)] func: Bound<'_, PyAny>,
    #[pyo3(from_py_with = arg)] lo: f64,
    #[pyo3(from_py_with = arg)] hi: f64,
    #[pyo3(from_py_with = arg)] tol: f64,
    #[pyo3(from_py_with = arg)] max_iter: i64,
) -> PyResult<(f64, f64, usize)> {
    let max_iter = count("max_iter", max_iter, 1)?;
    let g = solve::golden_section_with::<PyErr, _>(
        |x| func.call1((x,))?.extract::<f64>(),
        lo,
        hi,
        tol,
        max_iter,
    )?;
    Ok((g.x, g.fx, g.iterations))
}

/// Estimator (24a-b) on one averaged period: `(mu, theta, cost, iterations)`.
#[pyfunction]
#[pyo3(signature = (ybar, ydot, amplitude, omega, phi, lo, hi, tol, max_iter=200))]
#[allow(clippy::too_many_arguments)]
fn sls_search<'py>(
    py: Python<'py>,
    #[pyo3(from_py_with = arg)] ybar: PyReadonlyArray1<'py, f64>,
    #[pyo3(from_py_with = arg)] ydot: PyReadonlyArray1<'py, f64>,
    #[pyo3(from_py_with = arg)] amplitude: f64,
    #[pyo3(from_py_with = arg)] omega: f64,
    #[pyo3(from_py_with = arg)] phi: f64,
    #[pyo3(from_py_with = arg)] lo: f64,
    #[pyo3(from_py_with = arg)] hi: f64,
    #[pyo3(from_py_with = arg)] tol: f64,
    #[pyo3(from_py_with = arg)] max_iter: i64,
) -> PyResult<(f64, Vector<'py>, f64, usize)> {
    let (ybar, ydot) = (slice("ybar", &ybar)?, slice("ydot", &ydot)?);
    let max_iter = count("max_iter", max_iter, 1)?;
    let steps = Work::MuSearch {
        samples: ybar.len(),
        max_iter,
    }
    .check()?;
    let fit = detach::interruptible(py, steps, || {
        solve::check_mu_bracket(lo)?;
        let problem = SlsProblem::new(ybar, ydot, amplitude, omega, phi)?;
        solve::sls_search(&problem, lo, hi, tol, max_iter)
    })?;
    let theta = fit.theta.as_slice().to_vec().into_pyarray(py);
    Ok((fit.mu, theta, fit.cost, fit.iterations))
}

/// Gain estimator (27b): `|G(j omega)|` with `beta`, `gamma`, `mu` already estimated.
#[pyfunction]
#[pyo3(signature = (ybar, ydot, amplitude, omega, phi, beta, gamma, mu))]
#[allow(clippy::too_many_arguments)]
fn gain_estimate(
    #[pyo3(from_py_with = arg)] ybar: PyReadonlyArray1<'_, f64>,
    #[pyo3(from_py_with = arg)] ydot: PyReadonlyArray1<'_, f64>,
    #[pyo3(from_py_with = arg)] amplitude: f64,
    #[pyo3(from_py_with = arg)] omega: f64,
    #[pyo3(from_py_with = arg)] phi: f64,
    #[pyo3(from_py_with = arg)] beta: f64,
    #[pyo3(from_py_with = arg)] gamma: f64,
    #[pyo3(from_py_with = arg)] mu: f64,
) -> PyResult<f64> {
    let (ybar, ydot) = (slice("ybar", &ybar)?, slice("ydot", &ydot)?);
    Ok(estimate::gain_estimate(
        ybar, ydot, amplitude, omega, phi, beta, gamma, mu,
    )?)
}

/// Steady loop of (2b) under `x = amplitude cos(omega t - phi)` on P samples per period:
/// `(w, jac, w_top, iterations)` with `jac` of shape (P, 5), `d w/d(beta, gamma, mu, A, phi)`.
#[pyfunction]
#[pyo3(signature = (amplitude, beta, gamma, mu, phi, samples_per_period, substeps))]
#[allow(clippy::too_many_arguments)]
fn steady_loop<'py>(
    py: Python<'py>,
    #[pyo3(from_py_with = arg)] amplitude: f64,
    #[pyo3(from_py_with = arg)] beta: f64,
    #[pyo3(from_py_with = arg)] gamma: f64,
    #[pyo3(from_py_with = arg)] mu: f64,
    #[pyo3(from_py_with = arg)] phi: f64,
    #[pyo3(from_py_with = arg)] samples_per_period: i64,
    #[pyo3(from_py_with = arg)] substeps: i64,
) -> PyResult<(Vector<'py>, Matrix<'py>, f64, usize)> {
    let samples = count("samples_per_period", samples_per_period, 0)?;
    let substeps = count("substeps", substeps, 0)?;
    let steps = Work::SteadyLoop { samples, substeps }.check()?;
    let l = detach::interruptible(py, steps, || {
        steady::steady_loop(amplitude, beta, gamma, mu, phi, samples, substeps)
    })?;
    let jac = rows(py, &l.jac)?;
    Ok((l.w.into_pyarray(py), jac, l.w_top, l.iterations))
}

/// Profile-phase separable least squares (phase as a fit parameter, `sgn(xdot)` from the
/// candidate phase): `(phi, mu, gain, beta, gamma, cost, skipped)`, canonical (`gain > 0`).
#[pyfunction]
#[pyo3(signature = (ybar, ydot, amplitude, omega, lo, hi, tol, grid))]
#[allow(clippy::too_many_arguments)]
fn profile_phase_sls(
    py: Python<'_>,
    #[pyo3(from_py_with = arg)] ybar: PyReadonlyArray1<'_, f64>,
    #[pyo3(from_py_with = arg)] ydot: PyReadonlyArray1<'_, f64>,
    #[pyo3(from_py_with = arg)] amplitude: f64,
    #[pyo3(from_py_with = arg)] omega: f64,
    #[pyo3(from_py_with = arg)] lo: f64,
    #[pyo3(from_py_with = arg)] hi: f64,
    #[pyo3(from_py_with = arg)] tol: f64,
    #[pyo3(from_py_with = arg)] grid: i64,
) -> PyResult<(f64, f64, f64, f64, f64, f64, usize)> {
    let (ybar, ydot) = (slice("ybar", &ybar)?, slice("ydot", &ydot)?);
    let grid = count("grid", grid, 0)?;
    let samples = ybar.len();
    let steps = Work::PhaseProfile { samples, grid }.check()?;
    let f = detach::interruptible(py, steps, || {
        profile::profile_phase_sls(ybar, ydot, amplitude, omega, lo, hi, tol, grid)
    })?;
    Ok((f.phi, f.mu, f.gain, f.beta, f.gamma, f.cost, f.skipped))
}

/// Gain and phase at a further frequency with the hysteresis known: `(gain, phi, cost)`.
#[pyfunction]
#[pyo3(signature = (ybar, ydot, amplitude, omega, beta, gamma, mu, grid))]
#[allow(clippy::too_many_arguments)]
fn profile_phase_gain(
    py: Python<'_>,
    #[pyo3(from_py_with = arg)] ybar: PyReadonlyArray1<'_, f64>,
    #[pyo3(from_py_with = arg)] ydot: PyReadonlyArray1<'_, f64>,
    #[pyo3(from_py_with = arg)] amplitude: f64,
    #[pyo3(from_py_with = arg)] omega: f64,
    #[pyo3(from_py_with = arg)] beta: f64,
    #[pyo3(from_py_with = arg)] gamma: f64,
    #[pyo3(from_py_with = arg)] mu: f64,
    #[pyo3(from_py_with = arg)] grid: i64,
) -> PyResult<(f64, f64, f64)> {
    let (ybar, ydot) = (slice("ybar", &ybar)?, slice("ydot", &ydot)?);
    let grid = count("grid", grid, 0)?;
    let samples = ybar.len();
    let steps = Work::PhaseGain { samples, grid }.check()?;
    detach::interruptible(py, steps, || {
        profile::profile_phase_gain(ybar, ydot, amplitude, omega, beta, gamma, mu, grid)
    })
}
