//! Bouc-Wen in feedback (`rust/feedback.rs`): the simulation with forward sensitivities.

use numpy::{IntoPyArray, PyReadonlyArray1};
use pyo3::prelude::*;
use pyo3::types::PyTuple;

use super::convert::{arg, count, matrix, slice};
use super::detach;
use crate::budget::Work;
use crate::feedback::{self, Feedback, Sampling, N_COLS};

pub(super) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(feedback_simulate, m)?)?;
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
