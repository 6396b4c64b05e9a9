//! Bouc-Wen in feedback (`rust/feedback.rs`): the simulation with forward sensitivities, and the
//! periodic steady state under a sine.

use numpy::{IntoPyArray, PyReadonlyArray1};
use pyo3::prelude::*;
use pyo3::types::PyTuple;

use super::convert::{arg, count, matrix, slice};
use super::detach;
use crate::budget::Work;
use crate::feedback::{self, Feedback, Sampling, N_COLS, N_PARAMS};

pub(super) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(feedback_simulate, m)?)?;
    m.add_function(wrap_pyfunction!(feedback_periodic, m)?)?;
    Ok(())
}

/// RK4 simulation of `m ydd + c yd + k y + z = u`, Bouc-Wen `z` in `yd`, from the state `x0 = [y0,
/// yd0, z0]`, input samples `u` on the grid `dt / upsample`; returns `(y, jacobian, state)`: `y` on
/// the grid `dt`, `d y / d [m, c, k, alpha, bg, bd, nu, y0, yd0, z0]` (`n x 10`, `n x 0` without
/// `sensitivities`) and the final state.
#[pyfunction]
#[pyo3(signature = (theta, x0, u, dt, upsample, substeps, sensitivities=true))]
#[allow(clippy::too_many_arguments)]
fn feedback_simulate<'py>(
    py: Python<'py>,
    #[pyo3(from_py_with = arg)] theta: Vec<f64>,
    #[pyo3(from_py_with = arg)] x0: Vec<f64>,
    #[pyo3(from_py_with = arg)] u: PyReadonlyArray1<'py, f64>,
    #[pyo3(from_py_with = arg)] dt: f64,
    #[pyo3(from_py_with = arg)] upsample: i64,
    #[pyo3(from_py_with = arg)] substeps: i64,
    #[pyo3(from_py_with = arg)] sensitivities: bool,
) -> PyResult<Bound<'py, PyTuple>> {
    let model = Feedback::new(&theta)?;
    let x0: [f64; 3] = x0.as_slice().try_into().map_err(|_| {
        crate::error::CoreError::InvalidParameter(format!(
            "x0 must hold [y0, yd0, z0], got {} values",
            x0.len()
        ))
    })?;
    let u = slice("u", &u)?;
    let sampling = Sampling {
        dt,
        upsample: count("upsample", upsample, 1)?,
        substeps: count("substeps", substeps, 1)?,
    };
    let n_samples = sampling.output_len(u.len())?;
    let mut steps = Work::Simulation {
        n_samples,
        substeps: sampling.substeps,
    }
    .check()?;
    if sensitivities {
        steps = steps.saturating_mul(N_COLS as u128);
    }
    let sim = detach::interruptible(py, steps, || {
        feedback::simulate_feedback(&model, x0, u, sampling, sensitivities)
    })?;
    let cols = if sensitivities { N_COLS } else { 0 };
    let jac = matrix(py, sim.y.len(), cols, sim.jacobian)?;
    (
        sim.y.into_pyarray(py),
        jac,
        sim.state.to_vec().into_pyarray(py),
    )
        .into_pyobject(py)
}

/// Periodic steady state under `u = amplitude cos(omega t)` on `samples` points per period (Newton
/// shooting with the monodromy matrix, `rust/feedback/periodic.rs`); returns `(y, jacobian, x0,
/// iterations)`: one period of `y`, `d y / d theta` of the periodic solution (`samples x 7`), the
/// periodic state at `t = 0` and the Newton iterations.
#[pyfunction]
#[pyo3(signature = (theta, amplitude, omega, samples, substeps, settle_periods=2, max_iter=50, tol=1e-10))]
#[allow(clippy::too_many_arguments)]
fn feedback_periodic<'py>(
    py: Python<'py>,
    #[pyo3(from_py_with = arg)] theta: Vec<f64>,
    #[pyo3(from_py_with = arg)] amplitude: f64,
    #[pyo3(from_py_with = arg)] omega: f64,
    #[pyo3(from_py_with = arg)] samples: i64,
    #[pyo3(from_py_with = arg)] substeps: i64,
    #[pyo3(from_py_with = arg)] settle_periods: i64,
    #[pyo3(from_py_with = arg)] max_iter: i64,
    #[pyo3(from_py_with = arg)] tol: f64,
) -> PyResult<Bound<'py, PyTuple>> {
    let model = Feedback::new(&theta)?;
    let samples = count("samples", samples, 4)?;
    let substeps = count("substeps", substeps, 1)?;
    let settle = count("settle_periods", settle_periods, 0)?;
    let max_iter = count("max_iter", max_iter, 1)?;
    let steps = ((settle + max_iter) as u128) * (samples as u128) * (substeps as u128) * 10;
    let per = detach::interruptible(py, steps, || {
        feedback::periodic_feedback(
            &model, amplitude, omega, samples, substeps, settle, max_iter, tol,
        )
    })?;
    let jac = matrix(py, samples, N_PARAMS, per.jacobian)?;
    (
        per.y.into_pyarray(py),
        jac,
        per.state.to_vec().into_pyarray(py),
        per.iterations,
    )
        .into_pyobject(py)
}
