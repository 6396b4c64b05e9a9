//! The one error type of the core: every check of `docs/design.md` that can fail ends in a
//! [`CoreError`] variant, mapped one-to-one onto the Python exceptions of `bouc_wen_id.errors`.
//!
//! Messages say what was wrong, the offending value, and what to do about it.

use thiserror::Error;

/// Every failure the numerical core can detect.
#[non_exhaustive]
#[derive(Debug, Clone, PartialEq, Error)]
pub enum CoreError {
    /// A model or method parameter is out of its admissible range (e.g. `mu < 1`, `dt <= 0`).
    #[error("invalid parameter: {0}")]
    InvalidParameter(String),
    /// An input array or parameter holds NaN or infinity.
    #[error("non-finite value: {0}")]
    NonFinite(String),
    /// The transfer function is not asymptotically stable (Routh-Hurwitz).
    #[error("unstable system: {0}")]
    Unstable(String),
    /// The transfer function is improper, or its denominator's leading coefficient is zero.
    #[error("improper transfer function: {0}")]
    Improper(String),
    /// The data are too short for the requested operation.
    #[error("insufficient data: {0}")]
    InsufficientData(String),
    /// The input amplitude is zero or the output is constant: nothing can be identified.
    #[error("zero amplitude: {0}")]
    ZeroAmplitude(String),
    /// The Jacobi-scaled normal matrix is singular or too badly conditioned to be solved.
    #[error(
        "singular normal matrix (rcond = {rcond:.3e} < 1e-12): {context}; the regressor columns are \
         (nearly) collinear, so the data do not excite every term of the model"
    )]
    SingularNormalMatrix {
        /// Reciprocal condition number of the scaled matrix (0 when it could not be formed).
        rcond: f64,
        /// Where the matrix came from and what was wrong with it.
        context: String,
    },
    /// The golden-section search never left one end of its bracket.
    #[error(
        "the minimum lies at the {} end {bound} of the search bracket (tol {tol:e}); widen the \
         bracket past {bound}, or check that the data excite the hysteresis",
        if *lower { "lower" } else { "upper" }
    )]
    SearchAtBound {
        /// The bracket end the search stayed on.
        bound: f64,
        /// `true` for the lower end `lo`, `false` for the upper end `hi`.
        lower: bool,
        /// The requested bracket width.
        tol: f64,
    },
    /// An iteration that must converge did not (the steady-loop shooting).
    #[error("not converged: {0}")]
    NotConverged(String),
}

/// Result alias of the core.
pub type Result<T> = std::result::Result<T, CoreError>;

/// `Ok(v)` when `v` is finite, else a [`CoreError::NonFinite`] naming it.
pub(crate) fn finite(name: &str, v: f64) -> Result<f64> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(CoreError::NonFinite(format!(
            "{name} = {v} is not finite; pass a finite number"
        )))
    }
}

/// `Ok(())` when every element of `values` is finite, else a [`CoreError::NonFinite`] with the
/// first bad index.
pub(crate) fn all_finite(name: &str, values: &[f64]) -> Result<()> {
    // Fast screen first: `v * 0` is 0 for finite v and NaN otherwise, and eight independent lanes
    // let the compiler vectorise a scan that an early-exit search would not.
    const LANES: usize = 8;
    let mut lanes = [0.0f64; LANES];
    let chunks = values.chunks_exact(LANES);
    let tail = chunks.remainder();
    for chunk in chunks {
        for (acc, v) in lanes.iter_mut().zip(chunk) {
            *acc += v * 0.0;
        }
    }
    if lanes.iter().chain(tail).all(|v| v.is_finite()) {
        return Ok(());
    }
    match values.iter().position(|v| !v.is_finite()) {
        None => Ok(()),
        Some(i) => Err(CoreError::NonFinite(format!(
            "{name} holds a non-finite value ({}) at index {i}; clean or drop it first",
            values[i]
        ))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_name_the_value_and_the_remedy() {
        let e = CoreError::SearchAtBound {
            bound: 10.0,
            lower: false,
            tol: 1e-8,
        };
        let msg = e.to_string();
        assert!(msg.contains("upper end 10"), "{msg}");
        assert!(msg.contains("widen the bracket"), "{msg}");

        let e = CoreError::SingularNormalMatrix {
            rcond: 1e-17,
            context: "sls normal equations".into(),
        };
        assert!(e.to_string().contains("1.000e-17"), "{e}");

        let e = finite("dt", f64::NAN).unwrap_err();
        assert!(matches!(e, CoreError::NonFinite(_)));
        assert!(e.to_string().contains("dt = NaN"), "{e}");

        let e = all_finite("y", &[1.0, f64::INFINITY]).unwrap_err();
        assert!(e.to_string().contains("index 1"), "{e}");
        assert!(all_finite("y", &[1.0, 2.0]).is_ok());
        // Both the vectorised screen (first 16) and the tail are searched.
        let mut long = vec![1.0; 21];
        assert!(all_finite("y", &long).is_ok());
        long[11] = f64::NEG_INFINITY;
        assert!(all_finite("y", &long)
            .unwrap_err()
            .to_string()
            .contains("index 11"));
        long[11] = 0.0;
        long[20] = f64::NAN;
        assert!(all_finite("y", &long)
            .unwrap_err()
            .to_string()
            .contains("index 20"));
    }
}
