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

use std::collections::HashMap;

use numpy::ndarray::Array2;
use std::sync::mpsc::{self, RecvTimeoutError};
use std::sync::Arc;

use numpy::{IntoPyArray, PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::exceptions::{PyKeyboardInterrupt, PyOverflowError, PyTypeError};
use pyo3::prelude::*;
use pyo3::types::PyTuple;

use crate::average;
use crate::bouc_wen::BoucWen;
use crate::error::{self, CoreError};
use crate::estimate;
use crate::linear::TransferFunction;
use crate::simulate::{self, Input, Terms};
use crate::solve::{self, SlsProblem, GOLDEN_MAX_ITER};
use crate::{budget, cancel};
use crate::{lab, multistart, path_loop as pathloop, profile, refine, steady, terms};

pyo3::import_exception!(bouc_wen_id.errors, InvalidParameterError);
pyo3::import_exception!(bouc_wen_id.errors, NonFiniteError);
pyo3::import_exception!(bouc_wen_id.errors, UnstableSystemError);
pyo3::import_exception!(bouc_wen_id.errors, ImproperTransferFunctionError);
pyo3::import_exception!(bouc_wen_id.errors, InsufficientDataError);
pyo3::import_exception!(bouc_wen_id.errors, ZeroAmplitudeError);
pyo3::import_exception!(bouc_wen_id.errors, SingularNormalMatrixError);
pyo3::import_exception!(bouc_wen_id.errors, SearchAtBoundError);
pyo3::import_exception!(bouc_wen_id.errors, NotConvergedError);
pyo3::import_exception!(bouc_wen_id.errors, BudgetExceededError);

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
            CoreError::BudgetExceeded(_) => BudgetExceededError::new_err(msg),
            CoreError::Interrupted(_) => PyKeyboardInterrupt::new_err(msg),
            // The Python class carries the bracket end, so callers can tell mu = 1 from a
            // bracket that is merely too narrow.
            CoreError::SearchAtBound { bound, lower, .. } => {
                SearchAtBoundError::new_err((msg, bound, lower))
            }
            CoreError::NotConverged(_) => NotConvergedError::new_err(msg),
        }
    }
}

/// Extracts an argument, turning pyo3's conversion failures (a `TypeError` for a wrong type or
/// dtype, an `OverflowError` for an integer beyond 64 bits) into the library's
/// [`InvalidParameterError`] (a `ValueError`), as the module promises; pyo3 adds the argument's
/// name as a note. Used as `#[pyo3(from_py_with = arg)]`.
fn arg<'a, 'py, T>(obj: &'a Bound<'py, PyAny>) -> PyResult<T>
where
    T: FromPyObject<'a, 'py>,
{
    obj.extract::<T>().map_err(|e| {
        let e: PyErr = e.into();
        let py = obj.py();
        if !(e.is_instance_of::<PyTypeError>(py) || e.is_instance_of::<PyOverflowError>(py)) {
            return e;
        }
        let got = match (obj.getattr("dtype"), obj.getattr("shape")) {
            (Ok(dtype), Ok(shape)) => format!("an array of dtype {dtype} and shape {shape}"),
            _ => match obj.get_type().name() {
                Ok(name) => format!("an object of type {name}"),
                Err(_) => "an object of unknown type".into(),
            },
        };
        InvalidParameterError::new_err(format!(
            "invalid parameter: got {got}, which cannot be used here ({}); numbers must be \
             float, counts int in [-2^63, 2^63), arrays 1-D C-contiguous float64 (pass \
             numpy.ascontiguousarray(a, dtype=numpy.float64))",
            e.value(py).to_string().replace('\n', " ")
        ))
    })
}

/// Typical golden-section reductions of a search (`0.618^50 ~ 4e-11` of the bracket), for the
/// work estimates.
const GOLDEN_ITER_ESTIMATE: u128 = 50;
/// Typical shooting passes of a steady loop, for the work estimates.
const SHOOT_ITER_ESTIMATE: u128 = 4;

/// Below this many elementary steps a call runs inline: a worker thread (about 20 us) would cost
/// more than the few milliseconds the user waits for Ctrl-C.
const INTERRUPTIBLE_MIN_STEPS: u128 = 1 << 16;

/// Runs `work` with the interpreter released; when `steps` (an estimate of its elementary steps)
/// is large, runs it on a scoped worker thread under a fresh [`cancel::Token`] while this thread
/// polls `Python::check_signals` every [`cancel::POLL_INTERVAL`]. On a signal (Ctrl-C) the token
/// is cancelled, the worker stops at its next checkpoint (nothing of its result is kept), and the
/// signal's exception (`KeyboardInterrupt`) is raised.
fn run_detached<T, F>(py: Python<'_>, steps: u128, work: F) -> PyResult<T>
where
    T: Send,
    F: FnOnce() -> error::Result<T> + Send,
{
    if steps < INTERRUPTIBLE_MIN_STEPS {
        return Ok(py.detach(work)?);
    }
    let token = Arc::new(cancel::Token::new());
    let (outcome, signal) = py.detach(|| {
        std::thread::scope(|scope| {
            let (done, finished) = mpsc::channel::<()>();
            let worker_token = Some(token.clone());
            let spawned = std::thread::Builder::new()
                .name("bouc_wen_id-core".into())
                .spawn_scoped(scope, move || {
                    let out = cancel::with_token(worker_token, work);
                    // The receiver only ends with this scope; a failed send changes nothing.
                    let _ = done.send(());
                    out
                });
            let handle = match spawned {
                Ok(h) => h,
                // No thread to be had (the OS refused one): the work never ran; say so.
                Err(e) => {
                    return (
                        Err(CoreError::InvalidParameter(format!(
                            "could not start a worker thread for an interruptible call: {e}"
                        ))),
                        None,
                    )
                }
            };
            let mut signal: Option<PyErr> = None;
            // Until the worker reports (or drops its end by panicking), poll for signals.
            while let Err(RecvTimeoutError::Timeout) = finished.recv_timeout(cancel::POLL_INTERVAL)
            {
                if signal.is_none() {
                    if let Err(e) = Python::attach(|py| py.check_signals()) {
                        token.cancel();
                        signal = Some(e);
                    }
                }
            }
            let outcome = match handle.join() {
                Ok(out) => out,
                Err(panic) => std::panic::resume_unwind(panic),
            };
            (outcome, signal)
        })
    });
    if let Some(e) = signal {
        return Err(e);
    }
    Ok(outcome?)
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
    budget::check_simulation(n_samples, substeps)?;
    let steps = simulate::rk4_step_count(n_samples, substeps) as u128;
    let sim = run_detached(py, steps, || {
        simulate::simulate(&tf, &bw, input, dt, n_samples, substeps)
    })?;
    Ok((sim.x.into_pyarray(py), sim.w.into_pyarray(py)))
}

/// [`run_simulation`] with the §9.4 terms, `{code name: value}`: `(x, w, y)` when `terms` is
/// given, else the plain `(x, w)` (the plain path untouched).
#[allow(clippy::too_many_arguments)]
fn run_with_terms<'py>(
    py: Python<'py>,
    linear: (Vec<f64>, Vec<f64>, f64),
    bouc_wen: (f64, f64, f64, f64, f64),
    terms: Option<HashMap<String, f64>>,
    input: Input<'_>,
    dt: f64,
    n_samples: i64,
    substeps: i64,
) -> PyResult<Bound<'py, PyTuple>> {
    let Some(named) = terms else {
        let pair = run_simulation(py, linear, bouc_wen, input, dt, n_samples, substeps)?;
        return pair.into_pyobject(py);
    };
    let (num, den, delay) = linear;
    let (alpha, beta, gamma, mu, w0) = bouc_wen;
    // The reference's check order: G, the hysteresis, dt, substeps, n_samples, then the terms.
    let tf = TransferFunction::new(&num, &den, delay)?;
    let bw = BoucWen::new(alpha, beta, gamma, mu, w0)?;
    let dt = simulate::check_dt(dt)?;
    let substeps = count("substeps", substeps, 1)?;
    let n_samples = count("n_samples", n_samples, 1)?;
    let terms = Terms::from_named(named.iter().map(|(k, v)| (k.as_str(), *v)))?;
    budget::check_simulation(n_samples, substeps)?;
    let steps = simulate::rk4_step_count(n_samples, substeps) as u128;
    let sim = run_detached(py, steps, || {
        simulate::simulate_with_terms(&tf, &bw, &terms, input, dt, n_samples, substeps)
    })?;
    (
        sim.x.into_pyarray(py),
        sim.w.into_pyarray(py),
        sim.y.into_pyarray(py),
    )
        .into_pyobject(py)
}

/// RK4 simulation of `G(s) = e^{-delay s} num/den` -> Bouc-Wen driven by
/// `u(t) = amplitude cos(omega t)`; returns `(x, w)` at `t_k = k dt`, k < n_samples, or
/// `(x, w, y)` with the §9.4 `terms` ({code name: value}).
#[pyfunction]
#[pyo3(signature = (num, den, delay, alpha, beta, gamma, mu, w0, amplitude, omega, dt, n_samples, substeps, *, terms=None))]
#[allow(clippy::too_many_arguments)]
fn simulate_sine<'py>(
    py: Python<'py>,
    #[pyo3(from_py_with = arg)] num: Vec<f64>,
    #[pyo3(from_py_with = arg)] den: Vec<f64>,
    #[pyo3(from_py_with = arg)] delay: f64,
    #[pyo3(from_py_with = arg)] alpha: f64,
    #[pyo3(from_py_with = arg)] beta: f64,
    #[pyo3(from_py_with = arg)] gamma: f64,
    #[pyo3(from_py_with = arg)] mu: f64,
    #[pyo3(from_py_with = arg)] w0: f64,
    #[pyo3(from_py_with = arg)] amplitude: f64,
    #[pyo3(from_py_with = arg)] omega: f64,
    #[pyo3(from_py_with = arg)] dt: f64,
    #[pyo3(from_py_with = arg)] n_samples: i64,
    #[pyo3(from_py_with = arg)] substeps: i64,
    #[pyo3(from_py_with = arg)] terms: Option<HashMap<String, f64>>,
) -> PyResult<Bound<'py, PyTuple>> {
    let input = Input::Sine { amplitude, omega };
    input.validate()?;
    run_with_terms(
        py,
        (num, den, delay),
        (alpha, beta, gamma, mu, w0),
        terms,
        input,
        dt,
        n_samples,
        substeps,
    )
}

/// RK4 simulation driven by samples `u` on the grid `k dt` (Catmull-Rom interpolation);
/// returns `(x, w)` of the length of `u`, or `(x, w, y)` with the §9.4 `terms`.
#[pyfunction]
#[pyo3(signature = (num, den, delay, alpha, beta, gamma, mu, w0, u, dt, substeps, *, terms=None))]
#[allow(clippy::too_many_arguments)]
fn simulate_sampled<'py>(
    py: Python<'py>,
    #[pyo3(from_py_with = arg)] num: Vec<f64>,
    #[pyo3(from_py_with = arg)] den: Vec<f64>,
    #[pyo3(from_py_with = arg)] delay: f64,
    #[pyo3(from_py_with = arg)] alpha: f64,
    #[pyo3(from_py_with = arg)] beta: f64,
    #[pyo3(from_py_with = arg)] gamma: f64,
    #[pyo3(from_py_with = arg)] mu: f64,
    #[pyo3(from_py_with = arg)] w0: f64,
    #[pyo3(from_py_with = arg)] u: PyReadonlyArray1<'py, f64>,
    #[pyo3(from_py_with = arg)] dt: f64,
    #[pyo3(from_py_with = arg)] substeps: i64,
    #[pyo3(from_py_with = arg)] terms: Option<HashMap<String, f64>>,
) -> PyResult<Bound<'py, PyTuple>> {
    let u = slice("u", &u)?;
    let input = Input::Sampled { u };
    input.validate()?;
    // dt before G, as the reference does for a sampled input.
    let dt = simulate::check_dt(dt)?;
    let n_samples = i64::try_from(u.len()).unwrap_or(i64::MAX);
    run_with_terms(
        py,
        (num, den, delay),
        (alpha, beta, gamma, mu, w0),
        terms,
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
    #[pyo3(from_py_with = arg)] y: PyReadonlyArray1<'py, f64>,
    #[pyo3(from_py_with = arg)] samples_per_period: i64,
    #[pyo3(from_py_with = arg)] settle_periods: i64,
    #[pyo3(from_py_with = arg)] periods: i64,
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
) -> PyResult<Bound<'py, PyArray1<f64>>> {
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
    #[pyo3(from_py_with = arg)] ybar: PyReadonlyArray1<'py, f64>,
    #[pyo3(from_py_with = arg)] ydot: PyReadonlyArray1<'py, f64>,
    #[pyo3(from_py_with = arg)] amplitude: f64,
    #[pyo3(from_py_with = arg)] omega: f64,
    #[pyo3(from_py_with = arg)] phi: f64,
    #[pyo3(from_py_with = arg)] nu: f64,
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
    #[pyo3(from_py_with = arg)] m: PyReadonlyArray2<'py, f64>,
    #[pyo3(from_py_with = arg)] r: PyReadonlyArray1<'py, f64>,
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
    #[pyo3(from_py_with = arg)] ybar: PyReadonlyArray1<'py, f64>,
    #[pyo3(from_py_with = arg)] ydot: PyReadonlyArray1<'py, f64>,
    #[pyo3(from_py_with = arg)] amplitude: f64,
    #[pyo3(from_py_with = arg)] omega: f64,
    #[pyo3(from_py_with = arg)] phi: f64,
    #[pyo3(from_py_with = arg)] nu: f64,
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
) -> PyResult<(f64, Bound<'py, PyArray1<f64>>, f64, usize)> {
    let (ybar, ydot) = (slice("ybar", &ybar)?, slice("ydot", &ydot)?);
    let max_iter = count("max_iter", max_iter, 1)?;
    budget::check_steps(
        "the mu search",
        (max_iter as u128).saturating_mul(ybar.len() as u128),
    )?;
    let steps = (ybar.len() as u128) * GOLDEN_ITER_ESTIMATE;
    let fit = run_detached(py, steps, || {
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
    #[pyo3(from_py_with = arg)] ybar: PyReadonlyArray1<'_, f64>,
    #[pyo3(from_py_with = arg)] ydot: PyReadonlyArray1<'_, f64>,
    #[pyo3(from_py_with = arg)] amplitude: f64,
    #[pyo3(from_py_with = arg)] omega: f64,
    #[pyo3(from_py_with = arg)] phi: f64,
    #[pyo3(from_py_with = arg)] beta: f64,
    #[pyo3(from_py_with = arg)] gamma: f64,
    #[pyo3(from_py_with = arg)] mu: f64,
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
    #[pyo3(from_py_with = arg)] amplitude: f64,
    #[pyo3(from_py_with = arg)] beta: f64,
    #[pyo3(from_py_with = arg)] gamma: f64,
    #[pyo3(from_py_with = arg)] mu: f64,
    #[pyo3(from_py_with = arg)] phi: f64,
    #[pyo3(from_py_with = arg)] samples_per_period: i64,
    #[pyo3(from_py_with = arg)] substeps: i64,
) -> PyResult<(
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray2<f64>>,
    f64,
    usize,
)> {
    let p = count("samples_per_period", samples_per_period, 0)?;
    let substeps = count("substeps", substeps, 0)?;
    let steps = (p as u128).saturating_mul(substeps as u128) * SHOOT_ITER_ESTIMATE;
    budget::check_steps("the steady loop", steps)?;
    let l = run_detached(py, steps, || {
        steady::steady_loop(amplitude, beta, gamma, mu, phi, p, substeps)
    })?;
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

/// Steady loop of the generalised Bouc-Wen (asymmetry `delta`) behind a play of half-width `play`,
/// under `x = amplitude cos(omega t - phi)` on P samples per period (design.md 9.2):
/// `(w, jac, iterations)` with `jac` of shape (P, 7), `d w/d(beta, gamma, mu, A, phi, delta, b)`.
#[pyfunction]
#[pyo3(signature = (amplitude, beta, gamma, mu, delta, play, phi, samples_per_period, substeps))]
#[allow(clippy::type_complexity, clippy::too_many_arguments)]
fn path_loop<'py>(
    py: Python<'py>,
    amplitude: f64,
    beta: f64,
    gamma: f64,
    mu: f64,
    delta: f64,
    play: f64,
    phi: f64,
    samples_per_period: i64,
    substeps: i64,
) -> PyResult<(Bound<'py, PyArray1<f64>>, Bound<'py, PyArray2<f64>>, usize)> {
    let p = count("samples_per_period", samples_per_period, 0)?;
    let substeps = count("substeps", substeps, 0)?;
    let steps = (p as u128)
        .saturating_mul(substeps as u128)
        .saturating_mul(SHOOT_ITER_ESTIMATE);
    budget::check_steps("the path loop (samples x substeps)", steps)?;
    let l = run_detached(py, steps, || {
        pathloop::path_loop(amplitude, beta, gamma, mu, delta, play, phi, p, substeps)
    })?;
    // The sine path has no distortion column: the first seven.
    let flat: Vec<f64> = l.jac.iter().flat_map(|r| r[..7].to_vec()).collect();
    let jac = Array2::from_shape_vec((l.w.len(), 7), flat)
        .map_err(|e| CoreError::InvalidParameter(e.to_string()))?;
    Ok((l.w.into_pyarray(py), jac.into_pyarray(py), l.iterations))
}

/// [`path_loop`] along a measured waveform `x = A xi(theta - phi)`, `xi = cos + lambda d`,
/// `d = sum_k Re(c_k e^{i k zeta})` with `harmonics = [Re c_2, Im c_2, Re c_3, ...]`
/// (design.md 9.5): `(w, jac, iterations)`, `jac` of shape (P, 8), the last column `d w/d lambda`.
#[pyfunction]
#[pyo3(signature = (amplitude, beta, gamma, mu, delta, play, phi, lam, harmonics, samples_per_period, substeps))]
#[allow(clippy::type_complexity, clippy::too_many_arguments)]
fn path_loop_distorted<'py>(
    py: Python<'py>,
    amplitude: f64,
    beta: f64,
    gamma: f64,
    mu: f64,
    delta: f64,
    play: f64,
    phi: f64,
    lam: f64,
    harmonics: PyReadonlyArray1<'py, f64>,
    samples_per_period: i64,
    substeps: i64,
) -> PyResult<(Bound<'py, PyArray1<f64>>, Bound<'py, PyArray2<f64>>, usize)> {
    let p = count("samples_per_period", samples_per_period, 0)?;
    let substeps = count("substeps", substeps, 0)?;
    let harmonics = slice("harmonics", &harmonics)?;
    let steps = (p as u128)
        .saturating_mul(substeps as u128)
        .saturating_mul(SHOOT_ITER_ESTIMATE);
    budget::check_steps("the path loop (samples x substeps)", steps)?;
    let wf = pathloop::Waveform {
        lambda: lam,
        harmonics,
    };
    let l = run_detached(py, steps, || {
        pathloop::path_loop_distorted(
            amplitude, beta, gamma, mu, delta, play, phi, &wf, p, substeps,
        )
    })?;
    let flat: Vec<f64> = l.jac.iter().flatten().copied().collect();
    let jac = Array2::from_shape_vec((l.w.len(), pathloop::N_PD), flat)
        .map_err(|e| CoreError::InvalidParameter(e.to_string()))?;
    Ok((l.w.into_pyarray(py), jac.into_pyarray(py), l.iterations))
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
    // Each grid point runs a golden search over mu, each step one pass over the period.
    let steps = (grid as u128)
        .saturating_mul(ybar.len() as u128)
        .saturating_mul(GOLDEN_ITER_ESTIMATE);
    budget::check_steps(
        "the phase profile (grid x samples per period x mu search)",
        steps,
    )?;
    let f = run_detached(py, steps, || {
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
    let steps = (grid as u128).saturating_mul(ybar.len() as u128);
    budget::check_steps("the phase profile (grid x samples per period)", steps)?;
    run_detached(py, steps, || {
        profile::profile_phase_gain(ybar, ydot, amplitude, omega, beta, gamma, mu, grid)
    })
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
    #[pyo3(from_py_with = arg)] ybars: Vec<PyReadonlyArray1<'py, f64>>,
    #[pyo3(from_py_with = arg)] amplitudes: Vec<f64>,
    #[pyo3(from_py_with = arg)] weights: Vec<f64>,
    #[pyo3(from_py_with = arg)] beta: f64,
    #[pyo3(from_py_with = arg)] gamma: f64,
    #[pyo3(from_py_with = arg)] mu: f64,
    #[pyo3(from_py_with = arg)] gains: Vec<f64>,
    #[pyo3(from_py_with = arg)] phases: Vec<f64>,
    #[pyo3(from_py_with = arg)] max_iter: i64,
    #[pyo3(from_py_with = arg)] substeps: i64,
    #[pyo3(from_py_with = arg)] ftol: f64,
    #[pyo3(from_py_with = arg)] xtol: f64,
    #[pyo3(from_py_with = arg)] mu_lo: f64,
    #[pyo3(from_py_with = arg)] mu_hi: f64,
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
    // Each iteration evaluates every steady loop (a few shooting passes of P x substeps steps).
    let samples: u128 = slices.iter().map(|y| y.len() as u128).sum();
    let steps = (opts.max_iter as u128)
        .saturating_mul(samples)
        .saturating_mul(opts.substeps as u128)
        .saturating_mul(SHOOT_ITER_ESTIMATE);
    budget::check_steps("the refinement (max_iter x samples x substeps)", steps)?;
    let fit = run_detached(py, steps, || refine::refine(&exps, &start, &opts))?;
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

/// Row-major `(rows, cols)` data as a new 2-D array.
fn matrix<'py>(
    py: Python<'py>,
    rows: usize,
    cols: usize,
    flat: Vec<f64>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let arr = Array2::from_shape_vec((rows, cols), flat)
        .map_err(|e| CoreError::InvalidParameter(format!("internal shape error: {e}")))?;
    Ok(arr.into_pyarray(py))
}

/// `(y, jac_shared, jac_own)` of [`augmented_output`].
type AugOutputPy<'py> = (
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<f64>>,
);

/// The augmented model's output of one experiment (design.md 9.1) on `ybar_len` samples per
/// period: `(y (P,), jac_shared (P, 3 + T), jac_own (P, 2))`, shared columns
/// `[beta, gamma, mu, q_1 .. q_T]` in the order of `terms`, own columns `[g, phi]`.
#[pyfunction]
#[pyo3(signature = (ybar_len, amplitude, frequency, grid_phase, terms, shared, gain, phase, substeps, waveform=None))]
#[allow(clippy::too_many_arguments)]
fn augmented_output<'py>(
    py: Python<'py>,
    ybar_len: i64,
    amplitude: f64,
    frequency: f64,
    grid_phase: f64,
    terms: Vec<String>,
    shared: PyReadonlyArray1<'py, f64>,
    gain: f64,
    phase: f64,
    substeps: i64,
    waveform: Option<PyReadonlyArray1<'py, f64>>,
) -> PyResult<AugOutputPy<'py>> {
    let terms = terms::Terms::parse(&terms)?;
    let shared = slice("shared", &shared)?;
    let waveform = match &waveform {
        Some(a) => slice("waveform", a)?,
        None => &[],
    };
    let exc = terms::Excitation {
        samples: count("ybar_len", ybar_len, 0)?,
        amplitude,
        frequency,
        grid_phase,
    };
    let substeps = count("substeps", substeps, 1)?;
    let out = py.detach(|| {
        terms::augmented_output_with(&exc, waveform, &terms, shared, gain, phase, substeps)
    })?;
    let p = out.y.len();
    let own: Vec<f64> = out.jac_own.iter().flatten().copied().collect();
    Ok((
        out.y.into_pyarray(py),
        matrix(py, p, terms.n_shared(), out.jac_shared)?,
        matrix(py, p, 2, own)?,
    ))
}

/// What [`augmented_refine`] returns to Python:
/// `(shared, gains, phases, cost, iterations, converged, fisher, outputs)`.
type AugRefineOut<'py> = (
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<f64>>,
    f64,
    usize,
    bool,
    Bound<'py, PyArray2<f64>>,
    Vec<Bound<'py, PyArray1<f64>>>,
);

/// Joint Levenberg-Marquardt of the augmented model (design.md 9.3). `fisher` is `J^T W J`
/// ordered `[beta, gamma, mu, q_1 .. q_T, g_0, phi_0, g_1, phi_1, ...]`.
#[pyfunction]
#[pyo3(signature = (ybars, amplitudes, frequencies, grid_phases, weights, terms, shared0, gains0, phases0, *, max_iter=200, substeps=4, mu_lo=1.0, mu_hi=f64::INFINITY, waveforms=None))]
#[allow(clippy::too_many_arguments)]
fn augmented_refine<'py>(
    py: Python<'py>,
    ybars: Vec<PyReadonlyArray1<'py, f64>>,
    amplitudes: Vec<f64>,
    frequencies: Vec<f64>,
    grid_phases: Vec<f64>,
    weights: Vec<f64>,
    terms: Vec<String>,
    shared0: Vec<f64>,
    gains0: Vec<f64>,
    phases0: Vec<f64>,
    max_iter: i64,
    substeps: i64,
    mu_lo: f64,
    mu_hi: f64,
    waveforms: Option<Vec<PyReadonlyArray1<'py, f64>>>,
) -> PyResult<AugRefineOut<'py>> {
    let terms = terms::Terms::parse(&terms)?;
    let waveforms = waveforms.unwrap_or_default();
    let wave_slices = waveforms
        .iter()
        .enumerate()
        .map(|(i, a)| slice(&format!("waveforms[{i}]"), a))
        .collect::<PyResult<Vec<_>>>()?;
    let slices = ybars
        .iter()
        .enumerate()
        .map(|(i, y)| slice(&format!("ybars[{i}]"), y))
        .collect::<PyResult<Vec<_>>>()?;
    let m = slices.len();
    if !(wave_slices.is_empty() || wave_slices.len() == m) {
        return Err(CoreError::InvalidParameter(format!(
            "{m} experiments but {} waveforms (give one per experiment, or none)",
            wave_slices.len()
        ))
        .into());
    }
    if amplitudes.len() != m
        || frequencies.len() != m
        || grid_phases.len() != m
        || weights.len() != m
    {
        return Err(CoreError::InvalidParameter(format!(
            "{m} experiments but {} amplitudes, {} frequencies, {} grid phases and {} weights",
            amplitudes.len(),
            frequencies.len(),
            grid_phases.len(),
            weights.len()
        ))
        .into());
    }
    let opts = terms::AugOptions {
        max_iter: count("max_iter", max_iter, 1)?,
        substeps: count("substeps", substeps, 1)?,
        mu_lo,
        mu_hi,
        ..terms::AugOptions::default()
    };
    let exps: Vec<terms::AugExperiment> = (0..m)
        .map(|i| terms::AugExperiment {
            ybar: slices[i],
            amplitude: amplitudes[i],
            frequency: frequencies[i],
            grid_phase: grid_phases[i],
            weight: weights[i],
            waveform: wave_slices.get(i).copied().unwrap_or(&[]),
        })
        .collect();
    // Each iteration evaluates every steady loop (a few shooting passes of P x substeps steps).
    let samples: u128 = exps.iter().map(|e| e.ybar.len() as u128).sum();
    let steps = (opts.max_iter as u128)
        .saturating_mul(samples)
        .saturating_mul(opts.substeps as u128)
        .saturating_mul(SHOOT_ITER_ESTIMATE);
    budget::check_steps(
        "the augmented refinement (max_iter x samples x substeps)",
        steps,
    )?;
    let fit = run_detached(py, steps, || {
        terms::augmented_refine(&exps, &terms, &shared0, &gains0, &phases0, &opts)
    })?;
    let n = fit.fisher.nrows();
    let fisher = Array2::from_shape_fn((n, n), |(i, j)| fit.fisher[(i, j)]);
    let outputs = fit
        .outputs
        .into_iter()
        .map(|y| y.into_pyarray(py))
        .collect();
    Ok((
        fit.shared.into_pyarray(py),
        fit.gains.into_pyarray(py),
        fit.phases.into_pyarray(py),
        fit.cost,
        fit.iterations,
        fit.converged,
        fisher.into_pyarray(py),
        outputs,
    ))
}

/// The work and memory budgets in force: `(max_samples, max_steps, max_bytes)`
/// (`rust/budget.rs`; set them through `bouc_wen_id.budget`).
#[pyfunction]
fn get_budget() -> (u64, u64, u64) {
    let l = budget::limits();
    (l.max_samples, l.max_steps, l.max_bytes)
}

/// Sets the budgets (each >= 1); returns the previous `(max_samples, max_steps, max_bytes)`.
#[pyfunction]
#[pyo3(signature = (max_samples, max_steps, max_bytes))]
fn set_budget(
    #[pyo3(from_py_with = arg)] max_samples: u64,
    #[pyo3(from_py_with = arg)] max_steps: u64,
    #[pyo3(from_py_with = arg)] max_bytes: u64,
) -> PyResult<(u64, u64, u64)> {
    let old = budget::set_limits(budget::Limits {
        max_samples,
        max_steps,
        max_bytes,
    })?;
    Ok((old.max_samples, old.max_steps, old.max_bytes))
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
    // Interruptible like the other long calls (Ctrl-C -> KeyboardInterrupt): every start is a
    // refinement of up to max_iter iterations, each a few shooting passes over every lattice.
    let samples: u128 = slices.iter().map(|y| y.len() as u128).sum();
    let steps = (params.len() as u128)
        .saturating_mul(opts.max_iter as u128)
        .saturating_mul(samples)
        .saturating_mul(opts.substeps as u128)
        .saturating_mul(SHOOT_ITER_ESTIMATE);
    let outcomes = run_detached(py, steps, || {
        multistart::refine_many(&exps, &params, &opts, abandon, threads)
    })?;
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

/// `coef[0] + sum_k coef[2k-1] cos(k theta) + coef[2k] sin(k theta)` at every phase
/// (`rust/lab.rs`).
#[pyfunction]
fn harmonic_series<'py>(
    py: Python<'py>,
    #[pyo3(from_py_with = arg)] theta: PyReadonlyArray1<'py, f64>,
    #[pyo3(from_py_with = arg)] coef: PyReadonlyArray1<'py, f64>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let (theta, coef) = (slice("theta", &theta)?, slice("coef", &coef)?);
    let out = py.detach(|| lab::harmonic_series(theta, coef))?;
    Ok(out.into_pyarray(py))
}

/// Upper Cholesky factor of the row-major `m x m` Gram matrix `gram` (flat, length `m * m`), flat
/// row-major (`rust/lab.rs`).
#[pyfunction]
fn cholesky_upper<'py>(
    py: Python<'py>,
    #[pyo3(from_py_with = arg)] gram: PyReadonlyArray1<'py, f64>,
    #[pyo3(from_py_with = arg)] m: usize,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let gram = slice("gram", &gram)?;
    let out = py.detach(|| lab::cholesky_upper(gram, m))?;
    Ok(out.into_pyarray(py))
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
    let (theta, y, coef) = (
        slice("theta", &theta)?,
        slice("y", &y)?,
        slice("coef", &coef)?,
    );
    Ok(py.detach(|| lab::harmonic_rss_at(theta, omega, y, coef))?)
}

/// Gauss-Newton terms `(r.r, r.d, d.d, X^T d)` of the frequency fit of `x` on the harmonic series
/// `coef` at phases `theta`, times `tau` (`rust/lab.rs`).
#[pyfunction]
fn harmonic_gauss_newton<'py>(
    py: Python<'py>,
    #[pyo3(from_py_with = arg)] theta: PyReadonlyArray1<'py, f64>,
    #[pyo3(from_py_with = arg)] tau: PyReadonlyArray1<'py, f64>,
    #[pyo3(from_py_with = arg)] x: PyReadonlyArray1<'py, f64>,
    #[pyo3(from_py_with = arg)] coef: PyReadonlyArray1<'py, f64>,
) -> PyResult<(f64, f64, f64, Bound<'py, PyArray1<f64>>)> {
    let (theta, tau) = (slice("theta", &theta)?, slice("tau", &tau)?);
    let (x, coef) = (slice("x", &x)?, slice("coef", &coef)?);
    let (rr, rd, dd, xtd) = py.detach(|| lab::harmonic_gauss_newton(theta, tau, x, coef))?;
    Ok((rr, rd, dd, xtd.into_pyarray(py)))
}

/// `(coef, R, Q^T y, rss)` of one harmonic least-squares fit (`rust/lab/fit.rs`), `R` flat
/// row-major `m x m`; `None` when the Gram matrix is too ill-conditioned for the normal equations.
type HarmonicFitOut<'py> = Option<(
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<f64>>,
    f64,
)>;

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
        (
            f.coef.into_pyarray(py),
            f.r.into_pyarray(py),
            f.qty.into_pyarray(py),
            f.rss,
        )
    }))
}

/// The conditioning check of the fused fit (`rust/lab/fit.rs`): `cond(D^-1/2 G D^-1/2) <= 1e4`
/// and positive definite, `G` flat row-major `m x m`.
#[pyfunction]
fn gram_well_conditioned(
    #[pyo3(from_py_with = arg)] gram: PyReadonlyArray1<'_, f64>,
    #[pyo3(from_py_with = arg)] m: usize,
) -> PyResult<bool> {
    let g = slice("gram", &gram)?;
    Ok(lab::fit::gram_well_conditioned(g, m)?)
}

/// Diagonal of `(R^T R)^-1` for the upper triangular `R` (flat row-major `m x m`,
/// `rust/lab/fit.rs`): the unscaled variances of a fit.
#[pyfunction]
fn unscaled_variances<'py>(
    py: Python<'py>,
    #[pyo3(from_py_with = arg)] r: PyReadonlyArray1<'py, f64>,
    #[pyo3(from_py_with = arg)] m: usize,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let r = slice("r", &r)?;
    let out = py.detach(|| lab::fit::unscaled_variances(r, m))?;
    Ok(out.into_pyarray(py))
}

/// `(coef, rss)` of [`window_fits`].
type WindowFitsOut<'py> = (Bound<'py, PyArray2<f64>>, Bound<'py, PyArray2<f64>>);

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
    let index = |name: &str, v: &[i64]| -> PyResult<Vec<usize>> {
        v.iter().map(|&i| count(name, i, 0)).collect()
    };
    let (starts, stops) = (index("starts", &starts)?, index("stops", &stops)?);
    let f = py.detach(|| lab::windows::window_fits_at(theta, omega, u, y, &starts, &stops, k))?;
    let nw = starts.len();
    let m2 = 2 * (2 * f.harmonics + 1);
    let coef = Array2::from_shape_vec((nw, m2), f.coef)
        .map_err(|e| PyTypeError::new_err(e.to_string()))?;
    let rss =
        Array2::from_shape_vec((nw, 2), f.rss).map_err(|e| PyTypeError::new_err(e.to_string()))?;
    Ok((coef.into_pyarray(py), rss.into_pyarray(py)))
}

/// `|rfft(hann * detrended x, nfft)|` (`rust/lab/spectrum.rs`): the sine analysis's spectrum.
#[pyfunction]
fn padded_spectrum<'py>(
    py: Python<'py>,
    #[pyo3(from_py_with = arg)] x: PyReadonlyArray1<'py, f64>,
    #[pyo3(from_py_with = arg)] nfft: i64,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let x = slice("x", &x)?;
    let nfft = count("nfft", nfft, 2)?;
    let out = py.detach(|| lab::spectrum::padded_spectrum(x, nfft))?;
    Ok(out.into_pyarray(py))
}

/// The bin `dft_peak` takes and its neighbours, `(k, |X_{k-1}|, |X_k|, |X_{k+1}|)`
/// (`rust/lab/spectrum.rs`); `band_lo`/`band_hi` < 0: no band.
#[pyfunction]
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

/// `(omega, coef, rss, se)` of [`harmonic_nls`], or `None`.
type FrequencyFitOut<'py> = Option<(f64, Bound<'py, PyArray1<f64>>, f64, f64)>;

/// The Gauss-Newton frequency fit of `signal._sine._nls` in one call (`rust/lab/fit.rs`):
/// `(omega, coef, rss, se)`, or `None` when a fit is ill-conditioned (run the reference).
#[pyfunction]
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
    m.add_function(wrap_pyfunction!(path_loop, m)?)?;
    m.add_function(wrap_pyfunction!(path_loop_distorted, m)?)?;
    m.add_function(wrap_pyfunction!(profile_phase_sls, m)?)?;
    m.add_function(wrap_pyfunction!(profile_phase_gain, m)?)?;
    m.add_function(wrap_pyfunction!(refine_fit, m)?)?;
    m.add_function(wrap_pyfunction!(augmented_output, m)?)?;
    m.add_function(wrap_pyfunction!(augmented_refine, m)?)?;
    m.add_function(wrap_pyfunction!(get_budget, m)?)?;
    m.add_function(wrap_pyfunction!(set_budget, m)?)?;
    m.add_function(wrap_pyfunction!(refine_many, m)?)?;
    m.add_function(wrap_pyfunction!(harmonic_moments, m)?)?;
    m.add_function(wrap_pyfunction!(harmonic_series, m)?)?;
    m.add_function(wrap_pyfunction!(harmonic_gauss_newton, m)?)?;
    m.add_function(wrap_pyfunction!(harmonic_rss, m)?)?;
    m.add_function(wrap_pyfunction!(cholesky_upper, m)?)?;
    m.add_function(wrap_pyfunction!(harmonic_fit, m)?)?;
    m.add_function(wrap_pyfunction!(harmonic_nls, m)?)?;
    m.add_function(wrap_pyfunction!(gram_well_conditioned, m)?)?;
    m.add_function(wrap_pyfunction!(unscaled_variances, m)?)?;
    m.add_function(wrap_pyfunction!(window_fits, m)?)?;
    m.add_function(wrap_pyfunction!(padded_spectrum, m)?)?;
    m.add_function(wrap_pyfunction!(spectral_peak, m)?)?;
    Ok(())
}
