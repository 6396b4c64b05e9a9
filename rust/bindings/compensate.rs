//! Feedforward compensation kernels (`rust/compensate.rs`): the Bouc-Wen path inverse and the
//! actuator's rate limiter, behind `bouc_wen_id.compensation`.

use numpy::{IntoPyArray, PyReadonlyArray1};
use pyo3::prelude::*;

use super::convert::{arg, slice, Vector};
use super::detach;
use crate::compensate::{self, Element};

pub(super) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(invert_path, m)?)?;
    m.add_function(wrap_pyfunction!(rate_limit, m)?)?;
    Ok(())
}

/// The path `x` whose Bouc-Wen output (with asymmetry `delta`) is `w` at the samples, from the
/// state `(x0, w0)` (`rust/compensate.rs`).
#[pyfunction]
#[pyo3(signature = (w, alpha, beta, gamma, mu, delta, w0, x0))]
#[allow(clippy::too_many_arguments)]
fn invert_path<'py>(
    py: Python<'py>,
    #[pyo3(from_py_with = arg)] w: PyReadonlyArray1<'py, f64>,
    #[pyo3(from_py_with = arg)] alpha: f64,
    #[pyo3(from_py_with = arg)] beta: f64,
    #[pyo3(from_py_with = arg)] gamma: f64,
    #[pyo3(from_py_with = arg)] mu: f64,
    #[pyo3(from_py_with = arg)] delta: f64,
    #[pyo3(from_py_with = arg)] w0: f64,
    #[pyo3(from_py_with = arg)] x0: f64,
) -> PyResult<Vector<'py>> {
    let w = slice("w", &w)?;
    let element = Element {
        alpha,
        beta,
        gamma,
        mu,
        delta,
        w0,
    };
    let x = detach::by_size(py, w.len(), || compensate::invert_path(w, &element, x0))?;
    Ok(x.into_pyarray(py))
}

/// The command moved toward `target` by at most `step` per sample, from `start`.
#[pyfunction]
#[pyo3(signature = (target, step, start))]
fn rate_limit<'py>(
    py: Python<'py>,
    #[pyo3(from_py_with = arg)] target: PyReadonlyArray1<'py, f64>,
    #[pyo3(from_py_with = arg)] step: f64,
    #[pyo3(from_py_with = arg)] start: f64,
) -> PyResult<Vector<'py>> {
    let target = slice("target", &target)?;
    let out = detach::by_size(py, target.len(), || {
        compensate::rate_limit(target, step, start)
    })?;
    Ok(out.into_pyarray(py))
}
