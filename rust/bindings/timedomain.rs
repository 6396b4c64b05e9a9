//! The time-domain Wiener cascade with its exact Jacobian (`rust/timedomain.rs`, issue #20).

use numpy::{IntoPyArray, PyReadonlyArray1};
use pyo3::prelude::*;
use pyo3::types::PyTuple;

use super::convert::{arg, count, matrix, slice};
use super::detach;
use crate::budget::Work;
use crate::timedomain;

pub(super) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(timedomain_sensitivities, m)?)?;
    Ok(())
}

/// `(y, J)`: the alpha-normalised cascade `[b_0..b_m, a_1..a_n, tau, beta, gamma, mu, w0]` driven by
/// the samples `u` (grid `k dt`, Catmull-Rom), from rest, `substeps` RK4 steps per sample; `y = w`
/// on the grid and `J = dy/dtheta` (`(len(u), m + n + 6)`), exact for the discrete RK4 map.
#[pyfunction]
#[pyo3(signature = (m, n, theta, u, dt, substeps))]
fn timedomain_sensitivities<'py>(
    py: Python<'py>,
    #[pyo3(from_py_with = arg)] m: i64,
    #[pyo3(from_py_with = arg)] n: i64,
    #[pyo3(from_py_with = arg)] theta: Vec<f64>,
    #[pyo3(from_py_with = arg)] u: PyReadonlyArray1<'py, f64>,
    #[pyo3(from_py_with = arg)] dt: f64,
    #[pyo3(from_py_with = arg)] substeps: i64,
) -> PyResult<Bound<'py, PyTuple>> {
    let m = count("m", m, 0)?;
    let n = count("n", n, 0)?;
    let substeps = count("substeps", substeps, 1)?;
    let u = slice("u", &u)?;
    let steps = Work::Simulation {
        n_samples: u.len(),
        substeps,
    }
    .check()?;
    // The dual numbers carry MAX_PARAMS directions: about that many times a plain step.
    let steps = steps.saturating_mul(timedomain::MAX_PARAMS as u128);
    let sim = detach::interruptible(py, steps, || {
        timedomain::simulate_sensitivities(m, n, &theta, u, dt, substeps)
    })?;
    let rows = sim.y.len();
    let jac = matrix(py, rows, sim.n_params, sim.jac)?;
    (sim.y.into_pyarray(py), jac).into_pyobject(py)
}
