//! Conversion at the boundary, in one place: every argument of every binding (arrays, numbers,
//! counts, lists, callables), the outputs' arrays, and [`CoreError`] onto the named exceptions of
//! `bouc_wen_id.errors`.
//!
//! Arguments are taken with `#[pyo3(from_py_with = arg)]`: pyo3's own conversion failures (a
//! `TypeError` for a wrong type or dtype, an `OverflowError` for an integer beyond 64 bits) become
//! the library's [`InvalidParameterError`] (a `ValueError`); then [`slice`] borrows an array
//! (non-contiguous: an error, never a panic) and [`count`] turns an integer into a size with its
//! range checked.

use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArray2, PyReadonlyArray1};
use pyo3::exceptions::{PyKeyboardInterrupt, PyOverflowError, PyTypeError};
use pyo3::prelude::*;

use crate::error::CoreError;

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

/// A new 1-D float64 array.
pub(super) type Vector<'py> = Bound<'py, PyArray1<f64>>;
/// A new 2-D float64 array.
pub(super) type Matrix<'py> = Bound<'py, PyArray2<f64>>;

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
/// name as a note. Used as `#[pyo3(from_py_with = arg)]` on every argument of every binding.
pub(super) fn arg<'a, 'py, T>(obj: &'a Bound<'py, PyAny>) -> PyResult<T>
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

/// A callable argument (`#[pyo3(from_py_with = callable)]`); anything else is
/// [`InvalidParameterError`] up front rather than a `TypeError` at the first call.
pub(super) fn callable<'py>(obj: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
    if !obj.is_callable() {
        let name = obj
            .get_type()
            .name()
            .map_or_else(|_| "unknown".to_string(), |n| n.to_string());
        return Err(InvalidParameterError::new_err(format!(
            "invalid parameter: expected a callable f(x) -> float, got an object of type {name}"
        )));
    }
    Ok(obj.clone())
}

/// Borrows a 1-D array as a slice; a non-contiguous array is [`InvalidParameterError`].
pub(super) fn slice<'a>(name: &str, a: &'a PyReadonlyArray1<'_, f64>) -> PyResult<&'a [f64]> {
    a.as_slice().map_err(|_| {
        InvalidParameterError::new_err(format!(
            "invalid parameter: {name} must be a C-contiguous 1-D float64 array; pass \
             numpy.ascontiguousarray({name}, dtype=numpy.float64)"
        ))
    })
}

/// Borrows a list of 1-D arrays, `name[i]` in the errors (see [`slice`]).
pub(super) fn slices<'a>(
    name: &str,
    arrays: &'a [PyReadonlyArray1<'_, f64>],
) -> PyResult<Vec<&'a [f64]>> {
    arrays
        .iter()
        .enumerate()
        .map(|(i, a)| slice(&format!("{name}[{i}]"), a))
        .collect()
}

/// A Python integer as a count `>= min`, else [`InvalidParameterError`].
pub(super) fn count(name: &str, v: i64, min: i64) -> PyResult<usize> {
    if v < min {
        return Err(CoreError::InvalidParameter(format!("{name} = {v} must be >= {min}")).into());
    }
    usize::try_from(v).map_err(|_| {
        CoreError::InvalidParameter(format!("{name} = {v} does not fit this platform")).into()
    })
}

/// A list of Python integers as indices (each a [`count`] `>= 0`).
pub(super) fn indices(name: &str, v: &[i64]) -> PyResult<Vec<usize>> {
    v.iter().map(|&i| count(name, i, 0)).collect()
}

/// Checks that every per-experiment list has one entry per experiment: `m` experiments but
/// `"3 amplitudes and 2 weights"` is [`InvalidParameterError`].
pub(super) fn per_experiment(m: usize, lists: &[(&str, usize)]) -> PyResult<()> {
    if lists.iter().all(|&(_, n)| n == m) {
        return Ok(());
    }
    let parts: Vec<String> = lists
        .iter()
        .map(|(name, n)| format!("{n} {name}"))
        .collect();
    let listed = match parts.split_last() {
        Some((last, [])) => last.clone(),
        Some((last, rest)) => format!("{} and {last}", rest.join(", ")),
        None => String::new(),
    };
    Err(CoreError::InvalidParameter(format!("{m} experiments but {listed}")).into())
}

/// Row-major `(rows, cols)` data as a new 2-D array.
pub(super) fn matrix<'py>(
    py: Python<'py>,
    rows: usize,
    cols: usize,
    flat: Vec<f64>,
) -> PyResult<Matrix<'py>> {
    let arr = Array2::from_shape_vec((rows, cols), flat)
        .map_err(|e| CoreError::InvalidParameter(format!("internal shape error: {e}")))?;
    Ok(arr.into_pyarray(py))
}

/// Fixed-width rows as a new `(rows, N)` array.
pub(super) fn rows<'py, const N: usize>(py: Python<'py>, r: &[[f64; N]]) -> PyResult<Matrix<'py>> {
    matrix(py, r.len(), N, r.iter().flatten().copied().collect())
}

/// A square nalgebra matrix (the Fisher information) as a new 2-D array.
pub(super) fn square<'py>(py: Python<'py>, m: &nalgebra::DMatrix<f64>) -> Matrix<'py> {
    let n = m.nrows();
    Array2::from_shape_fn((n, n), |(i, j)| m[(i, j)]).into_pyarray(py)
}
