//! Simulation of the Wiener-Bouc-Wen plant (1a-c, 2a), with the §9.4 terms
//! (`rust/simulate.rs`, `rust/simulate/with_terms.rs`).

use std::collections::BTreeMap;

use numpy::{IntoPyArray, PyReadonlyArray1};
use pyo3::prelude::*;
use pyo3::types::PyTuple;

use super::convert::{arg, count, slice};
use super::detach;
use crate::bouc_wen::BoucWen;
use crate::budget::Work;
use crate::linear::TransferFunction;
use crate::simulate::{self, Input, TermValues};

pub(super) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(simulate_sine, m)?)?;
    m.add_function(wrap_pyfunction!(simulate_sampled, m)?)?;
    Ok(())
}

/// The plant as Python passes it: `G(s) = e^{-delay s} num/den`, then the Bouc-Wen
/// `(alpha, beta, gamma, mu, w0)`.
struct Plant {
    num: Vec<f64>,
    den: Vec<f64>,
    delay: f64,
    bouc_wen: [f64; 5],
}

/// Runs one simulation: `(x, w)`, or `(x, w, y)` with the §9.4 `terms` ({code name: value}, read in
/// the names' sorted order so that an error names the same term on every call; the
/// plain path untouched without them). Checks in the reference's order: G, the hysteresis, dt,
/// substeps, n_samples, then the terms (the input itself was checked by the caller).
fn run<'py>(
    py: Python<'py>,
    plant: Plant,
    terms: Option<BTreeMap<String, f64>>,
    input: Input<'_>,
    dt: f64,
    n_samples: i64,
    substeps: i64,
) -> PyResult<Bound<'py, PyTuple>> {
    let tf = TransferFunction::new(&plant.num, &plant.den, plant.delay)?;
    let [alpha, beta, gamma, mu, w0] = plant.bouc_wen;
    let bw = BoucWen::new(alpha, beta, gamma, mu, w0)?;
    let dt = simulate::check_dt(dt)?;
    let substeps = count("substeps", substeps, 1)?;
    let n_samples = count("n_samples", n_samples, 1)?;
    let terms = terms
        .map(|named| TermValues::from_named(named.iter().map(|(k, v)| (k.as_str(), *v))))
        .transpose()?;
    let steps = Work::Simulation {
        n_samples,
        substeps,
    }
    .check()?;
    match terms {
        None => {
            let sim = detach::interruptible(py, steps, || {
                simulate::simulate(&tf, &bw, input, dt, n_samples, substeps)
            })?;
            (sim.x.into_pyarray(py), sim.w.into_pyarray(py)).into_pyobject(py)
        }
        Some(terms) => {
            let sim = detach::interruptible(py, steps, || {
                simulate::simulate_with_terms(&tf, &bw, &terms, input, dt, n_samples, substeps)
            })?;
            let (x, w, y) = (sim.x, sim.w, sim.y);
            (x.into_pyarray(py), w.into_pyarray(py), y.into_pyarray(py)).into_pyobject(py)
        }
    }
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
    #[pyo3(from_py_with = arg)] terms: Option<BTreeMap<String, f64>>,
) -> PyResult<Bound<'py, PyTuple>> {
    let input = Input::Sine { amplitude, omega };
    input.validate()?;
    let plant = Plant {
        num,
        den,
        delay,
        bouc_wen: [alpha, beta, gamma, mu, w0],
    };
    run(py, plant, terms, input, dt, n_samples, substeps)
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
    #[pyo3(from_py_with = arg)] terms: Option<BTreeMap<String, f64>>,
) -> PyResult<Bound<'py, PyTuple>> {
    let u = slice("u", &u)?;
    let input = Input::Sampled { u };
    input.validate()?;
    // dt before G, as the reference does for a sampled input.
    let dt = simulate::check_dt(dt)?;
    let n_samples = i64::try_from(u.len()).unwrap_or(i64::MAX);
    let plant = Plant {
        num,
        den,
        delay,
        bouc_wen: [alpha, beta, gamma, mu, w0],
    };
    run(py, plant, terms, input, dt, n_samples, substeps)
}
