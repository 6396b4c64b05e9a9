//! pyo3 bindings `bouc_wen_id._core`: the only file that knows about Python.
//!
//! Each function borrows its NumPy arrays (1-D float64, C-contiguous; anything else is a
//! `ValueError`, never a panic), releases the interpreter around long work, calls the numerics of
//! (1a)-(27b) in the sibling modules, and maps [`CoreError`] onto the named exceptions of
//! `bouc_wen_id.errors`.
//!
//! ## Reference
//! *Wiener System Identification in Presence of Hysteresis Nonlinearity*, the seed paper whose
//! equation numbers are cited; for the Bouc-Wen properties it relies on (Propositions 1-2):
//! F. Ikhouane and J. Rodellar, *Systems with Hysteresis: Analysis, Identification and Control
//! using the Bouc-Wen Model*, Wiley, 2007.

use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;

use crate::average;
use crate::bouc_wen::BoucWen;
use crate::error::CoreError;
use crate::estimate;
use crate::linear::TransferFunction;
use crate::simulate::{self, Input};
use crate::solve::{self, SlsProblem, GOLDEN_MAX_ITER};
use crate::{lab, multistart, profile, refine, steady};

pyo3::import_exception!(bouc_wen_id.errors, InvalidParameterError);
pyo3::import_exception!(bouc_wen_id.errors, NonFiniteError);
pyo3::import_exception!(bouc_wen_id.errors, UnstableSystemError);
pyo3::import_exception!(bouc_wen_id.errors, ImproperTransferFunctionError);
pyo3::import_exception!(bouc_wen_id.errors, InsufficientDataError);
pyo3::import_exception!(bouc_wen_id.errors, ZeroAmplitudeError);
pyo3::import_exception!(bouc_wen_id.errors, SingularNormalMatrixError);
pyo3::import_exception!(bouc_wen_id.errors, SearchAtBoundError);
pyo3::import_exception!(bouc_wen_id.errors, ConvergenceError);

// The Python defaults `max_iter=200` are literals so that `__text_signature__` shows them.
const _: () = assert!(GOLDEN_MAX_ITER == 200);

/// Above this many samples, averaging and differentiation release the interpreter: below it the
/// work is shorter than the hand-over.
const DETACH_MIN_SAMPLES: usize = 1 << 14;

impl From<CoreError> for PyErr {
    fn from(e: CoreError) -> PyErr {
        let msg = e.to_string();
        match e {
            CoreError::InvalidParameter(_) => InvalidParameterError::new_err(msg),
            CoreError::NonFinite(_) => NonFiniteError::new_err(msg),
            CoreError::Unstable(_) => UnstableSystemError::new_err(msg),
            CoreError::Improper(_) => ImproperTransferFunctionError::new_err(msg),
            CoreError::InsufficientData(_) => InsufficientDataError::new_err(msg),
            CoreError::ZeroAmplitude(_) => ZeroAmplitudeError::new_err(msg),
            CoreError::SingularNormalMatrix { .. } => SingularNormalMatrixError::new_err(msg),
            // The Python class carries the bracket end, so callers can tell mu = 1 from a
            // bracket that is merely too narrow.
            CoreError::SearchAtBound { bound, lower, .. } => {
                SearchAtBoundError::new_err((msg, bound, lower))
            }
            CoreError::NotConverged(_) => ConvergenceError::new_err(msg),
        }
    }
}

/// Borrows a 1-D array as a slice; a non-contiguous array is a `ValueError`
/// ([`InvalidParameterError`]).
fn slice<'a>(name: &str, a: &'a PyReadonlyArray1<'_, f64>) -> PyResult<&'a [f64]> {
    a.as_slice().map_err(|_| {
        InvalidParameterError::new_err(format!(
            "invalid parameter: {name} must be a C-contiguous 1-D float64 array; pass \
             numpy.ascontiguousarray({name}, dtype=numpy.float64)"
        ))
    })
}

/// A Python integer as a count `>= min`, else [`InvalidParameterError`].
fn count(name: &str, v: i64, min: i64) -> PyResult<usize> {
    if v < min {
        return Err(CoreError::InvalidParameter(format!("{name} = {v} must be >= {min}")).into());
    }
    usize::try_from(v).map_err(|_| {
        CoreError::InvalidParameter(format!("{name} = {v} does not fit this platform")).into()
    })
}

/// `(x, w)` as two new arrays.
type Pair<'py> = (Bound<'py, PyArray1<f64>>, Bound<'py, PyArray1<f64>>);

fn run_simulation<'py>(
    py: Python<'py>,
    (num, den, delay): (Vec<f64>, Vec<f64>, f64),
    (alpha, beta, gamma, mu, w0): (f64, f64, f64, f64, f64),
    input: Input<'_>,
    dt: f64,
    n_samples: i64,
    substeps: i64,
) -> PyResult<Pair<'py>> {
    // The reference's check order: G, the hysteresis, dt, substeps, n_samples (the input itself
    // was checked by the caller).
    let tf = TransferFunction::new(&num, &den, delay)?;
    let bw = BoucWen::new(alpha, beta, gamma, mu, w0)?;
    let dt = simulate::check_dt(dt)?;
    let substeps = count("substeps", substeps, 1)?;
    let n_samples = count("n_samples", n_samples, 1)?;
    let sim = py.detach(|| simulate::simulate(&tf, &bw, input, dt, n_samples, substeps))?;
    Ok((sim.x.into_pyarray(py), sim.w.into_pyarray(py)))
}

/// RK4 simulation of `G(s) = e^{-delay s} num/den` -> Bouc-Wen driven by
/// `u(t) = amplitude cos(omega t)`; returns `(x, w)` at `t_k = k dt`, k < n_samples.
#[pyfunction]
#[pyo3(signature = (num, den, delay, alpha, beta, gamma, mu, w0, amplitude, omega, dt, n_samples, substeps))]
#[allow(clippy::too_many_arguments)]
fn simulate_sine<'py>(
    py: Python<'py>,
    num: Vec<f64>,
    den: Vec<f64>,
    delay: f64,
    alpha: f64,
    beta: f64,
    gamma: f64,
    mu: f64,
    w0: f64,
    amplitude: f64,
    omega: f64,
    dt: f64,
    n_samples: i64,
    substeps: i64,
) -> PyResult<Pair<'py>> {
    let input = Input::Sine { amplitude, omega };
    input.validate()?;
    run_simulation(
        py,
        (num, den, delay),
        (alpha, beta, gamma, mu, w0),
        input,
        dt,
        n_samples,
        substeps,
    )
}

/// RK4 simulation driven by samples `u` on the grid `k dt` (Catmull-Rom interpolation);
/// returns `(x, w)` of the length of `u`.
#[pyfunction]
#[pyo3(signature = (num, den, delay, alpha, beta, gamma, mu, w0, u, dt, substeps))]
#[allow(clippy::too_many_arguments)]
fn simulate_sampled<'py>(
    py: Python<'py>,
    num: Vec<f64>,
    den: Vec<f64>,
    delay: f64,
    alpha: f64,
    beta: f64,
    gamma: f64,
    mu: f64,
    w0: f64,
    u: PyReadonlyArray1<'py, f64>,
    dt: f64,
    substeps: i64,
) -> PyResult<Pair<'py>> {
    let u = slice("u", &u)?;
    let input = Input::Sampled { u };
    input.validate()?;
    // dt before G, as the reference does for a sampled input.
    let dt = simulate::check_dt(dt)?;
    let n_samples = i64::try_from(u.len()).unwrap_or(i64::MAX);
    run_simulation(
        py,
        (num, den, delay),
        (alpha, beta, gamma, mu, w0),
        input,
        dt,
        n_samples,
        substeps,
    )
}

/// Periodic average (4a-b) of `y` over `periods` periods after `settle_periods` dropped ones.
#[pyfunction]
#[pyo3(signature = (y, samples_per_period, settle_periods, periods))]
fn periodic_average<'py>(
    py: Python<'py>,
    y: PyReadonlyArray1<'py, f64>,
    samples_per_period: i64,
    settle_periods: i64,
    periods: i64,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let y = slice("y", &y)?;
    let (p, s, n) = match (
        usize::try_from(samples_per_period),
        usize::try_from(settle_periods),
        usize::try_from(periods),
    ) {
        (Ok(p), Ok(s), Ok(n)) => (p, s, n),
        // A negative count: report it as the core would, in the reference's order.
        _ => {
            crate::error::all_finite("y", y)?;
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
    let run = || average::periodic_average(y, p, s, n);
    let ybar = if y.len() >= DETACH_MIN_SAMPLES {
        py.detach(run)
    } else {
        run()
    }?;
    Ok(ybar.into_pyarray(py))
}

/// Phase estimator (9): `2 pi j*/P` (rad) with `j*` the first maximum of `ybar`.
#[pyfunction]
#[pyo3(signature = (ybar))]
fn phase_from_max(ybar: PyReadonlyArray1<'_, f64>) -> PyResult<f64> {
    Ok(estimate::phase_from_max(slice("ybar", &ybar)?)?)
}

/// Spectral derivative of one period `ybar` at `omega` (rad/s) from harmonics 1..=harmonics
/// (at most floor((P-1)/2)).
#[pyfunction]
#[pyo3(signature = (ybar, omega, harmonics))]
fn spectral_derivative<'py>(
    py: Python<'py>,
    ybar: PyReadonlyArray1<'py, f64>,
    omega: f64,
    harmonics: i64,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let ybar = slice("ybar", &ybar)?;
    let Ok(k) = usize::try_from(harmonics) else {
        crate::error::all_finite("ybar", ybar)?;
        crate::error::finite("omega", omega)?;
        return Err(CoreError::InvalidParameter(format!(
            "harmonics = {harmonics} must be in [1, {}] for {} samples per period",
            estimate::max_harmonics(ybar.len()),
            ybar.len()
        ))
        .into());
    };
    let run = || estimate::spectral_derivative(ybar, omega, k);
    let ydot = if ybar.len() >= DETACH_MIN_SAMPLES {
        py.detach(run)
    } else {
        run()
    }?;
    Ok(ydot.into_pyarray(py))
}

/// Regressor (23) at exponent `nu`, shape (P, 3).
#[pyfunction]
#[pyo3(signature = (ybar, ydot, amplitude, omega, phi, nu))]
fn sls_regressor<'py>(
    py: Python<'py>,
    ybar: PyReadonlyArray1<'py, f64>,
    ydot: PyReadonlyArray1<'py, f64>,
    amplitude: f64,
    omega: f64,
    phi: f64,
    nu: f64,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let problem = SlsProblem::new(
        slice("ybar", &ybar)?,
        slice("ydot", &ydot)?,
        amplitude,
        omega,
        phi,
    )?;
    let rows = problem.regressor(nu)?;
    let p = rows.len();
    let flat: Vec<f64> = rows.into_iter().flatten().collect();
    let arr = Array2::from_shape_vec((p, 3), flat).map_err(|e| {
        CoreError::InvalidParameter(format!("internal shape error building the regressor: {e}"))
    })?;
    Ok(arr.into_pyarray(py))
}

/// Solves the 3x3 normal equations `m theta = r` (Jacobi scaling, Cholesky); returns
/// `(theta, rcond)`.
#[pyfunction]
#[pyo3(signature = (m, r))]
fn solve_normal<'py>(
    py: Python<'py>,
    m: PyReadonlyArray2<'py, f64>,
    r: PyReadonlyArray1<'py, f64>,
) -> PyResult<(Bound<'py, PyArray1<f64>>, f64)> {
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
    ybar: PyReadonlyArray1<'py, f64>,
    ydot: PyReadonlyArray1<'py, f64>,
    amplitude: f64,
    omega: f64,
    phi: f64,
    nu: f64,
) -> PyResult<(Bound<'py, PyArray1<f64>>, f64)> {
    let problem = SlsProblem::new(
        slice("ybar", &ybar)?,
        slice("ydot", &ydot)?,
        amplitude,
        omega,
        phi,
    )?;
    let (theta, cost) = problem.cost(nu)?;
    Ok((theta.as_slice().to_vec().into_pyarray(py), cost))
}

/// Golden-section minimisation of the Python callable `func` on `[lo, hi]`; returns
/// `(x, func(x), iterations)`. Exceptions raised by `func` propagate unchanged.
#[pyfunction]
#[pyo3(signature = (func, lo, hi, tol, max_iter=200))]
fn golden_section(
    func: &Bound<'_, PyAny>,
    lo: f64,
    hi: f64,
    tol: f64,
    max_iter: i64,
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
    ybar: PyReadonlyArray1<'py, f64>,
    ydot: PyReadonlyArray1<'py, f64>,
    amplitude: f64,
    omega: f64,
    phi: f64,
    lo: f64,
    hi: f64,
    tol: f64,
    max_iter: i64,
) -> PyResult<(f64, Bound<'py, PyArray1<f64>>, f64, usize)> {
    let (ybar, ydot) = (slice("ybar", &ybar)?, slice("ydot", &ydot)?);
    let max_iter = count("max_iter", max_iter, 1)?;
    let fit = py.detach(|| {
        solve::check_mu_bracket(lo)?;
        let problem = SlsProblem::new(ybar, ydot, amplitude, omega, phi)?;
        solve::sls_search(&problem, lo, hi, tol, max_iter)
    })?;
    Ok((
        fit.mu,
        fit.theta.as_slice().to_vec().into_pyarray(py),
        fit.cost,
        fit.iterations,
    ))
}

/// Gain estimator (27b): `|G(j omega)|` with `beta`, `gamma`, `mu` already estimated.
#[pyfunction]
#[pyo3(signature = (ybar, ydot, amplitude, omega, phi, beta, gamma, mu))]
#[allow(clippy::too_many_arguments)]
fn gain_estimate(
    ybar: PyReadonlyArray1<'_, f64>,
    ydot: PyReadonlyArray1<'_, f64>,
    amplitude: f64,
    omega: f64,
    phi: f64,
    beta: f64,
    gamma: f64,
    mu: f64,
) -> PyResult<f64> {
    Ok(estimate::gain_estimate(
        slice("ybar", &ybar)?,
        slice("ydot", &ydot)?,
        amplitude,
        omega,
        phi,
        beta,
        gamma,
        mu,
    )?)
}

/// Steady loop of (2b) under `x = amplitude cos(omega t - phi)` on P samples per period:
/// `(w, jac, w_top, iterations)` with `jac` of shape (P, 5), `d w/d(beta, gamma, mu, A, phi)`.
#[pyfunction]
#[pyo3(signature = (amplitude, beta, gamma, mu, phi, samples_per_period, substeps))]
#[allow(clippy::type_complexity, clippy::too_many_arguments)]
fn steady_loop<'py>(
    py: Python<'py>,
    amplitude: f64,
    beta: f64,
    gamma: f64,
    mu: f64,
    phi: f64,
    samples_per_period: i64,
    substeps: i64,
) -> PyResult<(
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray2<f64>>,
    f64,
    usize,
)> {
    let p = count("samples_per_period", samples_per_period, 0)?;
    let substeps = count("substeps", substeps, 0)?;
    let l = py.detach(|| steady::steady_loop(amplitude, beta, gamma, mu, phi, p, substeps))?;
    let flat: Vec<f64> = l.jac.iter().flatten().copied().collect();
    let jac = Array2::from_shape_vec((l.w.len(), 5), flat)
        .map_err(|e| CoreError::InvalidParameter(e.to_string()))?;
    Ok((
        l.w.into_pyarray(py),
        jac.into_pyarray(py),
        l.w_top,
        l.iterations,
    ))
}

/// Profile-phase separable least squares (phase as a fit parameter, `sgn(xdot)` from the
/// candidate phase): `(phi, mu, gain, beta, gamma, cost, skipped)`, canonical (`gain > 0`).
#[pyfunction]
#[pyo3(signature = (ybar, ydot, amplitude, omega, lo, hi, tol, grid))]
#[allow(clippy::too_many_arguments)]
fn profile_phase_sls(
    py: Python<'_>,
    ybar: PyReadonlyArray1<'_, f64>,
    ydot: PyReadonlyArray1<'_, f64>,
    amplitude: f64,
    omega: f64,
    lo: f64,
    hi: f64,
    tol: f64,
    grid: i64,
) -> PyResult<(f64, f64, f64, f64, f64, f64, usize)> {
    let (ybar, ydot) = (slice("ybar", &ybar)?, slice("ydot", &ydot)?);
    let grid = count("grid", grid, 0)?;
    let f =
        py.detach(|| profile::profile_phase_sls(ybar, ydot, amplitude, omega, lo, hi, tol, grid))?;
    Ok((f.phi, f.mu, f.gain, f.beta, f.gamma, f.cost, f.skipped))
}

/// Gain and phase at a further frequency with the hysteresis known: `(gain, phi, cost)`.
#[pyfunction]
#[pyo3(signature = (ybar, ydot, amplitude, omega, beta, gamma, mu, grid))]
#[allow(clippy::too_many_arguments)]
fn profile_phase_gain(
    py: Python<'_>,
    ybar: PyReadonlyArray1<'_, f64>,
    ydot: PyReadonlyArray1<'_, f64>,
    amplitude: f64,
    omega: f64,
    beta: f64,
    gamma: f64,
    mu: f64,
    grid: i64,
) -> PyResult<(f64, f64, f64)> {
    let (ybar, ydot) = (slice("ybar", &ybar)?, slice("ydot", &ydot)?);
    let grid = count("grid", grid, 0)?;
    Ok(py.detach(|| {
        profile::profile_phase_gain(ybar, ydot, amplitude, omega, beta, gamma, mu, grid)
    })?)
}

/// What [`refine_fit`] returns to Python: `(params, cost, iterations, converged, fisher, loops)`.
type RefineOut<'py> = (
    Bound<'py, PyArray1<f64>>,
    f64,
    usize,
    bool,
    Bound<'py, PyArray2<f64>>,
    Vec<Bound<'py, PyArray1<f64>>>,
);

/// Joint output-error Levenberg-Marquardt over every experiment. Parameters are ordered
/// `[beta, gamma, mu, g_0, phi_0, g_1, phi_1, ...]`; `fisher` is `J^T W J` at the minimiser.
#[pyfunction]
#[pyo3(name = "refine", signature = (ybars, amplitudes, weights, beta, gamma, mu, gains, phases, max_iter=200, substeps=4, ftol=1e-12, xtol=1e-10, mu_lo=1.0, mu_hi=f64::INFINITY))]
#[allow(clippy::too_many_arguments)]
fn refine_fit<'py>(
    py: Python<'py>,
    ybars: Vec<PyReadonlyArray1<'py, f64>>,
    amplitudes: Vec<f64>,
    weights: Vec<f64>,
    beta: f64,
    gamma: f64,
    mu: f64,
    gains: Vec<f64>,
    phases: Vec<f64>,
    max_iter: i64,
    substeps: i64,
    ftol: f64,
    xtol: f64,
    mu_lo: f64,
    mu_hi: f64,
) -> PyResult<RefineOut<'py>> {
    let slices = ybars
        .iter()
        .enumerate()
        .map(|(i, y)| slice(&format!("ybars[{i}]"), y))
        .collect::<PyResult<Vec<_>>>()?;
    if amplitudes.len() != slices.len() || weights.len() != slices.len() {
        return Err(CoreError::InvalidParameter(format!(
            "{} experiments but {} amplitudes and {} weights",
            slices.len(),
            amplitudes.len(),
            weights.len()
        ))
        .into());
    }
    let opts = refine::Options {
        max_iter: count("max_iter", max_iter, 1)?,
        substeps: count("substeps", substeps, 1)?,
        ftol,
        xtol,
        mu_lo,
        mu_hi,
    };
    let exps: Vec<refine::Experiment> = slices
        .iter()
        .zip(amplitudes.iter().zip(&weights))
        .map(|(y, (&a, &w))| refine::Experiment {
            ybar: y,
            amplitude: a,
            weight: w,
        })
        .collect();
    let start = refine::Params {
        beta,
        gamma,
        mu,
        gains,
        phases,
    };
    let fit = py.detach(|| refine::refine(&exps, &start, &opts))?;
    let mut params = vec![fit.params.beta, fit.params.gamma, fit.params.mu];
    for (g, p) in fit.params.gains.iter().zip(&fit.params.phases) {
        params.push(*g);
        params.push(*p);
    }
    let n = fit.fisher.nrows();
    let fisher = Array2::from_shape_fn((n, n), |(i, j)| fit.fisher[(i, j)]);
    let loops = fit.loops.into_iter().map(|l| l.into_pyarray(py)).collect();
    Ok((
        params.into_pyarray(py),
        fit.cost,
        fit.iterations,
        fit.converged,
        fisher.into_pyarray(py),
        loops,
    ))
}

/// One start's outcome for Python: `(params, cost, iterations, converged, abandoned)`, or `None`
/// when `refine` refused that start (e.g. no valid steady loop there).
type StartOut<'py> = Option<(Bound<'py, PyArray1<f64>>, f64, usize, bool, bool)>;

/// Several starts of the joint refinement, run in parallel with the interpreter released
/// (`rust/multistart.rs`). `starts` holds one `[beta, gamma, mu, g_0, phi_0, g_1, phi_1, ...]` per
/// start; the outcomes come back in order and do not depend on `threads` (0: one per core).
/// `abandon_after > 0` screens in two rounds: after that many iterations, starts whose cost is over
/// `abandon_ratio` times the best are stopped.
#[pyfunction]
#[pyo3(signature = (ybars, amplitudes, weights, starts, max_iter=200, substeps=4, ftol=1e-12, xtol=1e-10, mu_lo=1.0, mu_hi=f64::INFINITY, abandon_after=0, abandon_ratio=10.0, threads=0))]
#[allow(clippy::too_many_arguments)]
fn refine_many<'py>(
    py: Python<'py>,
    ybars: Vec<PyReadonlyArray1<'py, f64>>,
    amplitudes: Vec<f64>,
    weights: Vec<f64>,
    starts: Vec<Vec<f64>>,
    max_iter: i64,
    substeps: i64,
    ftol: f64,
    xtol: f64,
    mu_lo: f64,
    mu_hi: f64,
    abandon_after: i64,
    abandon_ratio: f64,
    threads: i64,
) -> PyResult<Vec<StartOut<'py>>> {
    let slices = ybars
        .iter()
        .enumerate()
        .map(|(i, y)| slice(&format!("ybars[{i}]"), y))
        .collect::<PyResult<Vec<_>>>()?;
    let m = slices.len();
    if amplitudes.len() != m || weights.len() != m {
        return Err(CoreError::InvalidParameter(format!(
            "{m} experiments but {} amplitudes and {} weights",
            amplitudes.len(),
            weights.len()
        ))
        .into());
    }
    let params = starts
        .iter()
        .enumerate()
        .map(|(k, v)| {
            if v.len() != 3 + 2 * m {
                return Err(CoreError::InvalidParameter(format!(
                    "starts[{k}] has {} values; {m} experiments need 3 + 2 * {m} = {}",
                    v.len(),
                    3 + 2 * m
                )));
            }
            Ok(refine::Params {
                beta: v[0],
                gamma: v[1],
                mu: v[2],
                gains: v[3..].iter().step_by(2).copied().collect(),
                phases: v[4..].iter().step_by(2).copied().collect(),
            })
        })
        .collect::<Result<Vec<_>, CoreError>>()?;
    let opts = refine::Options {
        max_iter: count("max_iter", max_iter, 1)?,
        substeps: count("substeps", substeps, 1)?,
        ftol,
        xtol,
        mu_lo,
        mu_hi,
    };
    let abandon = match count("abandon_after", abandon_after, 0)? {
        0 => None,
        first_iter => Some(multistart::Abandon {
            first_iter,
            ratio: abandon_ratio,
        }),
    };
    let threads = count("threads", threads, 0)?;
    let exps: Vec<refine::Experiment> = slices
        .iter()
        .zip(amplitudes.iter().zip(&weights))
        .map(|(y, (&a, &w))| refine::Experiment {
            ybar: y,
            amplitude: a,
            weight: w,
        })
        .collect();
    let outcomes =
        py.detach(|| multistart::refine_many(&exps, &params, &opts, abandon, threads))?;
    Ok(outcomes
        .into_iter()
        .map(|r| {
            r.ok().map(|o| {
                let p = &o.fit.params;
                let mut flat = vec![p.beta, p.gamma, p.mu];
                for (g, ph) in p.gains.iter().zip(&p.phases) {
                    flat.push(*g);
                    flat.push(*ph);
                }
                (
                    flat.into_pyarray(py),
                    o.fit.cost,
                    o.fit.iterations,
                    o.fit.converged,
                    o.abandoned,
                )
            })
        })
        .collect())
}

/// `(mu_re, mu_im, r_re, r_im)` of [`harmonic_moments`].
type Moments<'py> = (
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<f64>>,
);

/// Complex moments of the harmonic basis (`rust/lab.rs`): `(mu_re, mu_im, r_re, r_im)` with
/// `mu_q = sum e^{i q theta}`, `q <= 2 kmax`, and `r_q = sum y e^{-i q theta}`, `q <= kmax`.
#[pyfunction]
fn harmonic_moments<'py>(
    py: Python<'py>,
    theta: PyReadonlyArray1<'py, f64>,
    y: PyReadonlyArray1<'py, f64>,
    kmax: i64,
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

/// `coef[0] + sum_k coef[2k-1] cos(k theta) + coef[2k] sin(k theta)` at every phase
/// (`rust/lab.rs`).
#[pyfunction]
fn harmonic_series<'py>(
    py: Python<'py>,
    theta: PyReadonlyArray1<'py, f64>,
    coef: PyReadonlyArray1<'py, f64>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let (theta, coef) = (slice("theta", &theta)?, slice("coef", &coef)?);
    let out = py.detach(|| lab::harmonic_series(theta, coef))?;
    Ok(out.into_pyarray(py))
}

/// Rust core of bouc_wen_id (simulation, averaging, estimators); see docs/design.md.
#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_function(wrap_pyfunction!(simulate_sine, m)?)?;
    m.add_function(wrap_pyfunction!(simulate_sampled, m)?)?;
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
    m.add_function(wrap_pyfunction!(refine_fit, m)?)?;
    m.add_function(wrap_pyfunction!(refine_many, m)?)?;
    m.add_function(wrap_pyfunction!(harmonic_moments, m)?)?;
    m.add_function(wrap_pyfunction!(harmonic_series, m)?)?;
    Ok(())
}
