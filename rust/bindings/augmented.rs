//! The augmented model (design.md 9): the loop along the input path, the model's output of one
//! experiment with its Jacobian, and its joint fit (`rust/path_loop.rs`, `rust/terms.rs`).

use numpy::{IntoPyArray, PyReadonlyArray1};
use pyo3::prelude::*;

use super::convert::{arg, count, matrix, per_experiment, rows, slice, slices, square};
use super::convert::{Matrix, Vector};
use super::detach;
use crate::augmented::{self as model, AugExperiment, Excitation, MeasuredInput};
use crate::budget::Work;
use crate::error::CoreError;
use crate::path_loop::{self as pathloop, PathLoop, Waveform};
use crate::refine::Options;
use crate::terms::{Terms, COULOMB_SMOOTHING};

pub(super) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(path_loop, m)?)?;
    m.add_function(wrap_pyfunction!(path_loop_distorted, m)?)?;
    m.add_function(wrap_pyfunction!(augmented_output, m)?)?;
    m.add_function(wrap_pyfunction!(augmented_refine, m)?)?;
    Ok(())
}

/// `(w, jac, iterations)` of the path loops.
type PathLoopOut<'py> = (Vector<'py>, Matrix<'py>, usize);

/// Runs a path loop of `samples` samples per period with `substeps` steps per segment, budgeted
/// and interruptible; `jac` keeps its first `columns` columns.
fn run_path_loop<'py, F>(
    py: Python<'py>,
    (samples, substeps): (usize, usize),
    columns: usize,
    solve: F,
) -> PyResult<PathLoopOut<'py>>
where
    F: FnOnce() -> crate::error::Result<PathLoop> + Send,
{
    let steps = Work::PathLoop { samples, substeps }.check()?;
    let l = detach::interruptible(py, steps, solve)?;
    let flat: Vec<f64> = l.jac.iter().flat_map(|r| r[..columns].to_vec()).collect();
    let jac = matrix(py, l.w.len(), columns, flat)?;
    Ok((l.w.into_pyarray(py), jac, l.iterations))
}

/// Steady loop of the generalised Bouc-Wen (asymmetry `delta`) behind a play of half-width `play`,
/// under `x = amplitude cos(omega t - phi)` on P samples per period (design.md 9.2):
/// `(w, jac, iterations)` with `jac` of shape (P, 7), `d w/d(beta, gamma, mu, A, phi, delta, b)`.
#[pyfunction]
#[pyo3(signature = (amplitude, beta, gamma, mu, delta, play, phi, samples_per_period, substeps))]
#[allow(clippy::too_many_arguments)]
fn path_loop<'py>(
    py: Python<'py>,
    #[pyo3(from_py_with = arg)] amplitude: f64,
    #[pyo3(from_py_with = arg)] beta: f64,
    #[pyo3(from_py_with = arg)] gamma: f64,
    #[pyo3(from_py_with = arg)] mu: f64,
    #[pyo3(from_py_with = arg)] delta: f64,
    #[pyo3(from_py_with = arg)] play: f64,
    #[pyo3(from_py_with = arg)] phi: f64,
    #[pyo3(from_py_with = arg)] samples_per_period: i64,
    #[pyo3(from_py_with = arg)] substeps: i64,
) -> PyResult<PathLoopOut<'py>> {
    let p = count("samples_per_period", samples_per_period, 0)?;
    let sub = count("substeps", substeps, 0)?;
    // The sine path has no distortion column: the first seven.
    run_path_loop(py, (p, sub), 7, || {
        pathloop::path_loop(amplitude, beta, gamma, mu, delta, play, phi, p, sub)
    })
}

/// [`path_loop`] along a measured waveform `x = A xi(theta - phi)`, `xi = cos + lambda d`,
/// `d = sum_k Re(c_k e^{i k zeta})` with `harmonics = [Re c_2, Im c_2, Re c_3, ...]`
/// (design.md 9.5): `(w, jac, iterations)`, `jac` of shape (P, 8), the last column `d w/d lambda`.
#[pyfunction]
#[pyo3(signature = (amplitude, beta, gamma, mu, delta, play, phi, lam, harmonics, samples_per_period, substeps))]
#[allow(clippy::too_many_arguments)]
fn path_loop_distorted<'py>(
    py: Python<'py>,
    #[pyo3(from_py_with = arg)] amplitude: f64,
    #[pyo3(from_py_with = arg)] beta: f64,
    #[pyo3(from_py_with = arg)] gamma: f64,
    #[pyo3(from_py_with = arg)] mu: f64,
    #[pyo3(from_py_with = arg)] delta: f64,
    #[pyo3(from_py_with = arg)] play: f64,
    #[pyo3(from_py_with = arg)] phi: f64,
    #[pyo3(from_py_with = arg)] lam: f64,
    #[pyo3(from_py_with = arg)] harmonics: PyReadonlyArray1<'py, f64>,
    #[pyo3(from_py_with = arg)] samples_per_period: i64,
    #[pyo3(from_py_with = arg)] substeps: i64,
) -> PyResult<PathLoopOut<'py>> {
    let p = count("samples_per_period", samples_per_period, 0)?;
    let sub = count("substeps", substeps, 0)?;
    let harmonics = slice("harmonics", &harmonics)?;
    let wf = Waveform {
        lambda: lam,
        harmonics,
    };
    // The distortion's column is the last one this binding hands back (not the pinching's).
    run_path_loop(py, (p, sub), pathloop::PD_DISTORT + 1, || {
        pathloop::path_loop_distorted(amplitude, beta, gamma, mu, delta, play, phi, &wf, p, sub)
    })
}

/// `(y, jac_shared, jac_own)` of [`augmented_output`].
type AugOutputPy<'py> = (Vector<'py>, Matrix<'py>, Matrix<'py>);

/// The augmented model's output of one experiment (design.md 9.1) on `ybar_len` samples per
/// period: `(y (P,), jac_shared (P, 3 + T), jac_own (P, 2))`, shared columns
/// `[beta, gamma, mu, q_1 .. q_T]` in the order of `terms`, own columns `[g, phi]`.
#[pyfunction]
#[pyo3(signature = (ybar_len, amplitude, frequency, grid_phase, terms, shared, gain, phase, substeps, waveform=None, input_shape=None, coulomb_smoothing=COULOMB_SMOOTHING))]
#[allow(clippy::too_many_arguments)]
fn augmented_output<'py>(
    py: Python<'py>,
    #[pyo3(from_py_with = arg)] ybar_len: i64,
    #[pyo3(from_py_with = arg)] amplitude: f64,
    #[pyo3(from_py_with = arg)] frequency: f64,
    #[pyo3(from_py_with = arg)] grid_phase: f64,
    #[pyo3(from_py_with = arg)] terms: Vec<String>,
    #[pyo3(from_py_with = arg)] shared: PyReadonlyArray1<'py, f64>,
    #[pyo3(from_py_with = arg)] gain: f64,
    #[pyo3(from_py_with = arg)] phase: f64,
    #[pyo3(from_py_with = arg)] substeps: i64,
    #[pyo3(from_py_with = arg)] waveform: Option<PyReadonlyArray1<'py, f64>>,
    #[pyo3(from_py_with = arg)] input_shape: Option<PyReadonlyArray1<'py, f64>>,
    #[pyo3(from_py_with = arg)] coulomb_smoothing: f64,
) -> PyResult<AugOutputPy<'py>> {
    let terms = Terms::parse(&terms)?.with_smoothing(coulomb_smoothing)?;
    let shared = slice("shared", &shared)?;
    let waveform = match &waveform {
        Some(a) => slice("waveform", a)?,
        None => &[],
    };
    let input = match &input_shape {
        Some(a) => measured_input(slice("input_shape", a)?)?,
        None => MeasuredInput::default(),
    };
    let exc = Excitation {
        samples: count("ybar_len", ybar_len, 0)?,
        amplitude,
        frequency,
        grid_phase,
    };
    let substeps = count("substeps", substeps, 1)?;
    let out = py.detach(|| {
        model::augmented_output_with(&exc, waveform, input, &terms, shared, gain, phase, substeps)
    })?;
    let p = out.y.len();
    Ok((
        out.y.into_pyarray(py),
        matrix(py, p, terms.n_shared(), out.jac_shared)?,
        rows(py, &out.jac_own)?,
    ))
}

/// What [`augmented_refine`] returns to Python:
/// `(shared, gains, phases, cost, iterations, converged, fisher, outputs, stop, active)`: `stop` the
/// stopping rule's code (`rust/refine.rs` `StopReason::code`), `active` the constraints the fit
/// ends on.
type AugRefineOut<'py> = (
    Vector<'py>,
    Vector<'py>,
    Vector<'py>,
    f64,
    usize,
    bool,
    Matrix<'py>,
    Vec<Vector<'py>>,
    &'static str,
    Vec<String>,
);

/// A stall rule's relative decrease (`Options::stall_rtol`, `step_rtol`): finite and not negative.
fn checked_stall_rtol(v: f64) -> PyResult<f64> {
    if v.is_finite() && v >= 0.0 {
        return Ok(v);
    }
    Err(CoreError::InvalidParameter(format!(
        "the stall rules' rtol must be finite and >= 0; got {v}"
    ))
    .into())
}

/// The measured input as the terms on u see it from `[dc, Re c_2, Im c_2, ...]` (the input's mean
/// relative to U, then its harmonics as `waveform`'s); empty: the pure sine.
fn measured_input(a: &[f64]) -> PyResult<MeasuredInput<'_>> {
    if a.is_empty() {
        return Ok(MeasuredInput::default());
    }
    if a.len() % 2 == 0 || a.iter().any(|v| !v.is_finite()) {
        return Err(CoreError::InvalidParameter(format!(
            "input_shape must hold the input's finite mean relative to U, then (re, im) pairs of its \
             harmonics 2, 3, ... (an odd length); got {} values",
            a.len()
        ))
        .into());
    }
    Ok(MeasuredInput {
        dc: a[0],
        harmonics: &a[1..],
    })
}

/// The experiments of the augmented fit: one amplitude, frequency, grid phase and weight per
/// averaged period, and one waveform and one input shape each or none.
fn aug_experiments<'a>(
    ybars: &[&'a [f64]],
    (amplitudes, frequencies): (&[f64], &[f64]),
    (grid_phases, weights): (&[f64], &[f64]),
    (waveforms, shapes): (&[&'a [f64]], &[&'a [f64]]),
    substeps: &[Option<usize>],
) -> PyResult<Vec<AugExperiment<'a>>> {
    let m = ybars.len();
    if !(shapes.is_empty() || shapes.len() == m) {
        return Err(CoreError::InvalidParameter(format!(
            "{m} experiments but {} input shapes (give one per experiment, or none)",
            shapes.len()
        ))
        .into());
    }
    let inputs = shapes
        .iter()
        .map(|a| measured_input(a))
        .collect::<PyResult<Vec<_>>>()?;
    if !(substeps.is_empty() || substeps.len() == m) {
        return Err(CoreError::InvalidParameter(format!(
            "{m} experiments but {} substep counts (give one per experiment, or none)",
            substeps.len()
        ))
        .into());
    }
    if !(waveforms.is_empty() || waveforms.len() == m) {
        return Err(CoreError::InvalidParameter(format!(
            "{m} experiments but {} waveforms (give one per experiment, or none)",
            waveforms.len()
        ))
        .into());
    }
    per_experiment(
        m,
        &[
            ("amplitudes", amplitudes.len()),
            ("frequencies", frequencies.len()),
            ("grid phases", grid_phases.len()),
            ("weights", weights.len()),
        ],
    )?;
    Ok((0..m)
        .map(|i| AugExperiment {
            ybar: ybars[i],
            amplitude: amplitudes[i],
            frequency: frequencies[i],
            grid_phase: grid_phases[i],
            weight: weights[i],
            waveform: waveforms.get(i).copied().unwrap_or(&[]),
            input: inputs.get(i).copied().unwrap_or_default(),
            substeps: substeps.get(i).copied().flatten(),
        })
        .collect())
}

/// Joint Levenberg-Marquardt of the augmented model (design.md 9.3). `fisher` is `J^T W J`
/// ordered `[beta, gamma, mu, q_1 .. q_T, g_0, phi_0, g_1, phi_1, ...]`; `stop` says which rule
/// ended the search and `active` on which constraints it ended. `experiment_substeps`, one count
/// per experiment, overrides `substeps` for each (the budget charges the largest). `stall_window`,
/// `stall_rtol`, `step_rtol`: the stall rules (`Options::stall_window`, `Options::step_rtol`; 0, off).
#[pyfunction]
#[pyo3(signature = (ybars, amplitudes, frequencies, grid_phases, weights, terms, shared0, gains0, phases0, *, max_iter=200, substeps=4, mu_lo=1.0, mu_hi=f64::INFINITY, waveforms=None, experiment_substeps=None, input_shapes=None, coulomb_smoothing=COULOMB_SMOOTHING, stall_window=0, stall_rtol=0.0, step_rtol=0.0))]
#[allow(clippy::too_many_arguments)]
fn augmented_refine<'py>(
    py: Python<'py>,
    #[pyo3(from_py_with = arg)] ybars: Vec<PyReadonlyArray1<'py, f64>>,
    #[pyo3(from_py_with = arg)] amplitudes: Vec<f64>,
    #[pyo3(from_py_with = arg)] frequencies: Vec<f64>,
    #[pyo3(from_py_with = arg)] grid_phases: Vec<f64>,
    #[pyo3(from_py_with = arg)] weights: Vec<f64>,
    #[pyo3(from_py_with = arg)] terms: Vec<String>,
    #[pyo3(from_py_with = arg)] shared0: Vec<f64>,
    #[pyo3(from_py_with = arg)] gains0: Vec<f64>,
    #[pyo3(from_py_with = arg)] phases0: Vec<f64>,
    #[pyo3(from_py_with = arg)] max_iter: i64,
    #[pyo3(from_py_with = arg)] substeps: i64,
    #[pyo3(from_py_with = arg)] mu_lo: f64,
    #[pyo3(from_py_with = arg)] mu_hi: f64,
    #[pyo3(from_py_with = arg)] waveforms: Option<Vec<PyReadonlyArray1<'py, f64>>>,
    #[pyo3(from_py_with = arg)] experiment_substeps: Option<Vec<i64>>,
    #[pyo3(from_py_with = arg)] input_shapes: Option<Vec<PyReadonlyArray1<'py, f64>>>,
    #[pyo3(from_py_with = arg)] coulomb_smoothing: f64,
    #[pyo3(from_py_with = arg)] stall_window: i64,
    #[pyo3(from_py_with = arg)] stall_rtol: f64,
    #[pyo3(from_py_with = arg)] step_rtol: f64,
) -> PyResult<AugRefineOut<'py>> {
    let terms = Terms::parse(&terms)?.with_smoothing(coulomb_smoothing)?;
    let waveforms = waveforms.unwrap_or_default();
    let waveforms = slices("waveforms", &waveforms)?;
    let input_shapes = input_shapes.unwrap_or_default();
    let input_shapes = slices("input_shapes", &input_shapes)?;
    let ybars = slices("ybars", &ybars)?;
    let exps = aug_experiments(
        &ybars,
        (&amplitudes, &frequencies),
        (&grid_phases, &weights),
        (&waveforms, &input_shapes),
        &experiment_substeps
            .unwrap_or_default()
            .into_iter()
            .map(|v| count("experiment_substeps", v, 1).map(Some))
            .collect::<PyResult<Vec<_>>>()?,
    )?;
    let opts = Options {
        max_iter: count("max_iter", max_iter, 1)?,
        substeps: count("substeps", substeps, 1)?,
        mu_lo,
        mu_hi,
        stall_window: count("stall_window", stall_window, 0)?,
        stall_rtol: checked_stall_rtol(stall_rtol)?,
        step_rtol: checked_stall_rtol(step_rtol)?,
        ..Options::default()
    };
    let steps = Work::AugmentedRefinement {
        samples: exps.iter().map(|e| e.ybar.len() as u128).sum(),
        max_iter: opts.max_iter,
        substeps: exps
            .iter()
            .map(|e| e.substeps.unwrap_or(opts.substeps))
            .max()
            .unwrap_or(opts.substeps),
    }
    .check()?;
    let fit = detach::interruptible(py, steps, || {
        model::augmented_refine(&exps, &terms, &shared0, &gains0, &phases0, &opts)
    })?;
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
        square(py, &fit.fisher),
        outputs,
        fit.stop.code(),
        fit.active,
    ))
}
