//! The process-wide work and memory budgets (`rust/budget.rs`), read and set by
//! `bouc_wen_id.budget`.

use pyo3::prelude::*;

use super::convert::arg;
use crate::budget;

pub(super) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(get_budget, m)?)?;
    m.add_function(wrap_pyfunction!(set_budget, m)?)?;
    Ok(())
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
