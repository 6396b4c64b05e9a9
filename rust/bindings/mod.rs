//! pyo3 bindings `bouc_wen_id._core`: the only code that knows about Python.
//!
//! One file per domain, each a list of thin functions that convert their arguments, call the
//! numerics of the sibling modules and convert the result; nothing here computes:
//!
//! | file | bindings |
//! |------|----------|
//! | [`convert`] | every argument and error: arrays, counts, lists, `CoreError` -> the exceptions of `bouc_wen_id.errors` |
//! | [`detach`] | releasing the interpreter, interruptible runs on a worker thread |
//! | [`simulate`] | `simulate_sine`, `simulate_sampled` (1a-c, 2a; the §9.4 terms) |
//! | [`paper`] | the estimators of the seed paper on one averaged period, (4a)-(27b) |
//! | [`refine`] | the joint output-error fits of the plain model: `refine`, `refine_many` |
//! | [`augmented`] | the augmented model (design.md 9): path loops, output, joint fit |
//! | [`lab`] | the laboratory kernels behind `bouc_wen_id.signal` |
//! | [`budget`] | `get_budget`, `set_budget` |
//! | [`testing`] | test-only kernels, exposed so that the tests can hold them to their references |
//!
//! Every argument goes through [`convert::arg`] (`#[pyo3(from_py_with = arg)]`), so a wrong type
//! or dtype, an integer beyond 64 bits or a count out of range is the library's
//! `InvalidParameterError` (a `ValueError`), never pyo3's `TypeError` or `OverflowError`; arrays
//! are 1-D float64 C-contiguous (anything else is an error, never a panic). Long calls release the
//! interpreter and are interruptible (Ctrl-C) through [`detach`]; their work is estimated and
//! budgeted in one place, [`crate::budget::Work`].
//!
//! ## Reference
//! *Wiener System Identification in Presence of Hysteresis Nonlinearity*, the seed paper whose
//! equation numbers are cited; for the Bouc-Wen properties it relies on (Propositions 1-2):
//! F. Ikhouane and J. Rodellar, *Systems with Hysteresis: Analysis, Identification and Control
//! using the Bouc-Wen Model*, Wiley, 2007.

use pyo3::prelude::*;

mod augmented;
mod budget;
mod compensate;
mod convert;
mod detach;
mod feedback;
mod lab;
mod paper;
mod refine;
mod simulate;
mod testing;
mod timedomain;

/// Rust core of bouc_wen_id (simulation, averaging, estimators); see docs/design.md.
#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    simulate::register(m)?;
    paper::register(m)?;
    refine::register(m)?;
    augmented::register(m)?;
    feedback::register(m)?;
    budget::register(m)?;
    lab::register(m)?;
    testing::register(m)?;
    compensate::register(m)?;
    timedomain::register(m)?;
    Ok(())
}
