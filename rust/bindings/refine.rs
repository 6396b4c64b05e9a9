//! The joint output-error fits of the plain model (7.4): one Levenberg-Marquardt over every
//! experiment, and several starts of it in parallel (`rust/refine.rs`, `rust/multistart.rs`).

use numpy::{IntoPyArray, PyReadonlyArray1};
use pyo3::prelude::*;

use super::convert::{arg, count, per_experiment, slices, square, Matrix, Vector};
use super::detach;
use crate::budget::Work;
use crate::multistart;
use crate::refine::{self, Experiment, Options, Params};

pub(super) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(refine_fit, m)?)?;
    m.add_function(wrap_pyfunction!(refine_many, m)?)?;
    Ok(())
}

/// The experiments of a joint fit, after checking one amplitude and one weight per period.
fn experiments<'a>(
    ybars: &[&'a [f64]],
    amplitudes: &[f64],
    weights: &[f64],
) -> PyResult<Vec<Experiment<'a>>> {
    per_experiment(
        ybars.len(),
        &[("amplitudes", amplitudes.len()), ("weights", weights.len())],
    )?;
    Ok(ybars
        .iter()
        .zip(amplitudes.iter().zip(weights))
        .map(|(y, (&amplitude, &weight))| Experiment {
            ybar: y,
            amplitude,
            weight,
        })
        .collect())
}

/// The options of a joint fit from Python's arguments (counts checked).
fn options(
    (max_iter, substeps): (i64, i64),
    (ftol, xtol): (f64, f64),
    (mu_lo, mu_hi): (f64, f64),
) -> PyResult<Options> {
    Ok(Options {
        max_iter: count("max_iter", max_iter, 1)?,
        substeps: count("substeps", substeps, 1)?,
        ftol,
        xtol,
        mu_lo,
        mu_hi,
        ..Options::default()
    })
}

/// Samples of all experiments together, for the work estimates.
fn total_samples(exps: &[Experiment]) -> u128 {
    exps.iter().map(|e| e.ybar.len() as u128).sum()
}

/// What [`refine_fit`] returns to Python: `(params, cost, iterations, converged, fisher, loops,
/// stop, active)`: `stop` the stopping rule's code (`StopReason::code`), `active` the constraints the
/// fit ends on.
type RefineOut<'py> = (
    Vector<'py>,
    f64,
    usize,
    bool,
    Matrix<'py>,
    Vec<Vector<'py>>,
    &'static str,
    Vec<String>,
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
    let ybars = slices("ybars", &ybars)?;
    let exps = experiments(&ybars, &amplitudes, &weights)?;
    let opts = options((max_iter, substeps), (ftol, xtol), (mu_lo, mu_hi))?;
    let start = Params {
        beta,
        gamma,
        mu,
        gains,
        phases,
    };
    let steps = Work::Refinement {
        samples: total_samples(&exps),
        max_iter: opts.max_iter,
        substeps: opts.substeps,
    }
    .check()?;
    let fit = detach::interruptible(py, steps, || refine::refine(&exps, &start, &opts))?;
    let loops = fit.loops.into_iter().map(|l| l.into_pyarray(py)).collect();
    Ok((
        fit.params.flat().into_pyarray(py),
        fit.cost,
        fit.iterations,
        fit.converged,
        square(py, &fit.fisher),
        loops,
        fit.stop.code(),
        fit.active,
    ))
}

/// One start's outcome for Python: `(params, cost, iterations, converged, abandoned)`, or `None`
/// when `refine` refused that start (e.g. no valid steady loop there).
type StartOut<'py> = Option<(Vector<'py>, f64, usize, bool, bool)>;

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
    #[pyo3(from_py_with = arg)] ybars: Vec<PyReadonlyArray1<'py, f64>>,
    #[pyo3(from_py_with = arg)] amplitudes: Vec<f64>,
    #[pyo3(from_py_with = arg)] weights: Vec<f64>,
    #[pyo3(from_py_with = arg)] starts: Vec<Vec<f64>>,
    #[pyo3(from_py_with = arg)] max_iter: i64,
    #[pyo3(from_py_with = arg)] substeps: i64,
    #[pyo3(from_py_with = arg)] ftol: f64,
    #[pyo3(from_py_with = arg)] xtol: f64,
    #[pyo3(from_py_with = arg)] mu_lo: f64,
    #[pyo3(from_py_with = arg)] mu_hi: f64,
    #[pyo3(from_py_with = arg)] abandon_after: i64,
    #[pyo3(from_py_with = arg)] abandon_ratio: f64,
    #[pyo3(from_py_with = arg)] threads: i64,
) -> PyResult<Vec<StartOut<'py>>> {
    let ybars = slices("ybars", &ybars)?;
    let exps = experiments(&ybars, &amplitudes, &weights)?;
    let params = starts
        .iter()
        .enumerate()
        .map(|(k, v)| Params::from_flat(&format!("starts[{k}]"), v, exps.len()))
        .collect::<Result<Vec<_>, _>>()?;
    let opts = options((max_iter, substeps), (ftol, xtol), (mu_lo, mu_hi))?;
    let abandon = match count("abandon_after", abandon_after, 0)? {
        0 => None,
        first_iter => Some(multistart::Abandon {
            first_iter,
            ratio: abandon_ratio,
        }),
    };
    let threads = count("threads", threads, 0)?;
    // Interruptible like the other long calls (Ctrl-C -> KeyboardInterrupt).
    let steps = Work::Starts {
        starts: params.len(),
        samples: total_samples(&exps),
        max_iter: opts.max_iter,
        substeps: opts.substeps,
    }
    .check()?;
    let outcomes = detach::interruptible(py, steps, || {
        multistart::refine_many(&exps, &params, &opts, abandon, threads)
    })?;
    Ok(outcomes
        .into_iter()
        .map(|r| {
            r.ok().map(|o| {
                let f = o.fit;
                let flat = f.params.flat().into_pyarray(py);
                (flat, f.cost, f.iterations, f.converged, o.abandoned)
            })
        })
        .collect())
}
