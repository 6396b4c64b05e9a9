//! Bouc-Wen hysteresis (2a) of the seed paper:
//! `wdot = alpha xdot - beta |xdot| |w|^(mu-1) w - gamma xdot |w|^mu`.
//!
//! Admissible parameters (`docs/design.md` §1, after (2a) in the paper): `alpha > 0`,
//! `beta + gamma > 0` (bounded output), `beta - gamma >= 0`, `mu >= 1`, all finite.
//!
//! ## Reference
//! *Wiener System Identification in Presence of Hysteresis Nonlinearity*, the seed paper whose
//! equation numbers are cited; for the Bouc-Wen properties it relies on (Propositions 1-2):
//! F. Ikhouane and J. Rodellar, *Systems with Hysteresis: Analysis, Identification and Control
//! using the Bouc-Wen Model*, Wiley, 2007.

use crate::error::{finite, CoreError, Result};

/// Validated Bouc-Wen parameters and initial state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoucWen {
    alpha: f64,
    beta: f64,
    gamma: f64,
    mu: f64,
    w0: f64,
}

/// `sgn` with `sgn(0) = 0` (as `numpy.sign`), unlike `f64::signum` which gives `1` at `+0`.
#[inline(always)]
pub(crate) fn sgn(v: f64) -> f64 {
    if v > 0.0 {
        1.0
    } else if v < 0.0 {
        -1.0
    } else {
        0.0
    }
}

impl BoucWen {
    /// Validates the parameters of (2a) (dimensionless `alpha`, `mu`; `beta`, `gamma` in
    /// `1/[w]^mu`) and the initial hysteretic output `w0` (units of `w`).
    ///
    /// Errors: [`CoreError::NonFinite`] for NaN/inf, [`CoreError::InvalidParameter`] when
    /// `alpha <= 0`, `beta + gamma <= 0`, `beta - gamma < 0` or `mu < 1`.
    pub fn new(alpha: f64, beta: f64, gamma: f64, mu: f64, w0: f64) -> Result<Self> {
        for (name, v) in [
            ("alpha", alpha),
            ("beta", beta),
            ("gamma", gamma),
            ("mu", mu),
            ("w0", w0),
        ] {
            finite(name, v)?;
        }
        if alpha <= 0.0 {
            return Err(CoreError::InvalidParameter(format!(
                "alpha = {alpha} must be > 0 (the identified model normalises alpha to 1)"
            )));
        }
        if beta + gamma <= 0.0 {
            return Err(CoreError::InvalidParameter(format!(
                "beta + gamma = {} must be > 0 for a bounded Bouc-Wen output (Proposition 1); \
                 raise beta",
                beta + gamma
            )));
        }
        if beta - gamma < 0.0 {
            return Err(CoreError::InvalidParameter(format!(
                "beta - gamma = {} must be >= 0 (conditions of (2a)); use gamma <= beta",
                beta - gamma
            )));
        }
        if mu < 1.0 {
            return Err(CoreError::InvalidParameter(format!(
                "mu = {mu} must be >= 1"
            )));
        }
        Ok(Self {
            alpha,
            beta,
            gamma,
            mu,
            w0,
        })
    }

    /// Parameters without the admissibility checks, for closed-form tests (e.g. `beta = gamma = 0`
    /// makes `w = x + const`).
    #[cfg(test)]
    pub(crate) fn new_unchecked(alpha: f64, beta: f64, gamma: f64, mu: f64, w0: f64) -> Self {
        Self {
            alpha,
            beta,
            gamma,
            mu,
            w0,
        }
    }

    /// `alpha` of (2a).
    pub fn alpha(&self) -> f64 {
        self.alpha
    }
    /// `beta` of (2a).
    pub fn beta(&self) -> f64 {
        self.beta
    }
    /// `gamma` of (2a).
    pub fn gamma(&self) -> f64 {
        self.gamma
    }
    /// Exponent `mu` of (2a).
    pub fn mu(&self) -> f64 {
        self.mu
    }
    /// Initial output `w(0)`.
    pub fn w0(&self) -> f64 {
        self.w0
    }

    /// Right-hand side of (2a): `wdot` (units of `w` per second) from `xdot` (units of `x` per
    /// second) and `w`.
    ///
    /// `|w|^(mu-1) w` is computed as `sgn(w) |w|^mu`, so one `powf` serves both terms (and
    /// `w = 0` gives 0 without `0^(mu-1)`).
    #[inline(always)]
    pub fn wdot(&self, xdot: f64, w: f64) -> f64 {
        let wmu = w.abs().powf(self.mu);
        self.alpha * xdot - self.beta * xdot.abs() * sgn(w) * wmu - self.gamma * xdot * wmu
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn rhs_matches_2a() {
        let bw = BoucWen::new(1.5, 0.7, 0.2, 2.5, 0.0).unwrap();
        for &(xd, w) in &[
            (0.3, 0.4),
            (-0.3, 0.4),
            (0.3, -0.4),
            (-1.2, -0.05),
            (0.8, 0.0),
        ] {
            let expected: f64 = 1.5 * xd
                - 0.7 * f64::abs(xd) * f64::abs(w).powf(1.5) * w
                - 0.2 * xd * f64::abs(w).powf(2.5);
            assert_relative_eq!(bw.wdot(xd, w), expected, max_relative = 1e-14);
        }
        assert_eq!(sgn(0.0), 0.0);
        assert_eq!(sgn(-0.0), 0.0);
        assert_eq!(sgn(-2.0), -1.0);
    }

    #[test]
    fn constructor_validates() {
        assert!(BoucWen::new(1.0, 0.5, 0.5, 1.0, 0.3).is_ok());
        assert!(BoucWen::new(1.0, 0.5, -0.2, 3.0, 0.0).is_ok());
        let bad = [
            (0.0, 1.0, 0.0, 2.0, "alpha = 0"),
            (1.0, 0.0, 0.0, 2.0, "beta + gamma = 0"),
            (1.0, 0.2, 0.5, 2.0, "beta - gamma = -0.3"),
            (1.0, 1.0, 0.0, 0.5, "mu = 0.5"),
        ];
        for (a, b, g, m, text) in bad {
            let e = BoucWen::new(a, b, g, m, 0.0).unwrap_err();
            assert!(matches!(e, CoreError::InvalidParameter(_)), "{e}");
            assert!(e.to_string().contains(text), "{e}");
        }
        let e = BoucWen::new(1.0, 1.0, 0.0, 2.0, f64::NAN).unwrap_err();
        assert!(matches!(e, CoreError::NonFinite(_)), "{e}");
        assert!(e.to_string().contains("w0"), "{e}");
    }
}
