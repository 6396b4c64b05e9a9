//! Separable least squares (18)-(24) of the seed paper (`docs/design.md` §5): for a trial exponent
//! `nu`, the parameters `theta = [|G|, beta |G|, gamma |G|]` enter linearly through the regressor
//! (23) `psi_j(nu) = [-s_j, s_j sgn(ydot_j) sgn(ybar_j) |ybar_j|^nu, s_j |ybar_j|^nu]` with
//! `s_j = U omega sin(omega t_j - phi)`; `theta(nu)` (22) solves the normal equations, and the
//! scalar cost `I_N(nu)` (21) is minimised by golden-section search (24a-b).
//!
//! Integrals over one period are rectangle sums times `dt = T/P` (spectrally accurate for periodic
//! integrands).
//!
//! ## Reference
//! *Wiener System Identification in Presence of Hysteresis Nonlinearity*, the seed paper whose
//! equation numbers are cited; for the Bouc-Wen properties it relies on (Propositions 1-2):
//! F. Ikhouane and J. Rodellar, *Systems with Hysteresis: Analysis, Identification and Control
//! using the Bouc-Wen Model*, Wiley, 2007.

use nalgebra::{Matrix3, SymmetricEigen, Vector3};

use crate::bouc_wen::sgn;
use crate::error::{all_finite, finite, CoreError, Result};

/// Conjugate golden ratio `(sqrt 5 - 1)/2`: the fraction of the bracket kept at each step.
pub const GOLDEN_RATIO_CONJ: f64 = 0.618_033_988_749_894_9;
/// Smallest reciprocal condition number of the Jacobi-scaled normal matrix that is solved; below
/// it, the solution would carry less than ~4 significant digits.
pub const RCOND_MIN: f64 = 1e-12;
/// Default iteration cap of the golden-section search: `0.618^200 ~ 1e-42`, far below any double
/// tolerance, so the cap only guards against a `tol` below rounding.
pub const GOLDEN_MAX_ITER: usize = 200;
/// Fewest samples per period accepted by the estimators.
pub const MIN_SAMPLES: usize = 4;
/// Iteration cap of the 3x3 symmetric eigenvalue solver (converges in a handful).
const EIGEN_MAX_ITER: usize = 1000;

/// One averaged period prepared for repeated evaluations of `I_N(nu)`.
///
/// Everything that does not depend on `nu` is computed once: `s_j`, `sgn(ydot_j) sgn(ybar_j)` and
/// `ln |ybar_j|`, so that `|ybar_j|^nu = exp(nu ln |ybar_j|)` costs one `exp` per sample.
#[derive(Debug, Clone, PartialEq)]
pub struct SlsProblem {
    pub(crate) s: Vec<f64>,
    pub(crate) sign: Vec<f64>,
    /// `ln |ybar_j|`, `-inf` where `ybar_j == 0`.
    ln_abs: Vec<f64>,
    pub(crate) ydot: Vec<f64>,
    dt: f64,
}

/// Minimiser found by [`golden_section`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Golden {
    /// Midpoint of the final bracket.
    pub x: f64,
    /// `f(x)`, evaluated at that midpoint.
    pub fx: f64,
    /// Bracket reductions performed.
    pub iterations: usize,
}

/// Result of [`sls_search`] (24a-b).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SlsFit {
    /// Estimated exponent `mu`.
    pub mu: f64,
    /// `theta(mu) = [|G|, beta |G|, gamma |G|]` as solved (not sign-normalised).
    pub theta: Vector3<f64>,
    /// `I_N(mu)`, units of `ydot^2 s`.
    pub cost: f64,
    /// Golden-section iterations.
    pub iterations: usize,
}

/// Checks the inputs shared by the SLS and gain estimators; returns `(s, dt)`.
fn sls_inputs(
    ybar: &[f64],
    ydot: &[f64],
    amplitude: f64,
    omega: f64,
    phi: f64,
) -> Result<(Vec<f64>, f64)> {
    all_finite("ybar", ybar)?;
    all_finite("ydot", ydot)?;
    if ybar.len() != ydot.len() {
        return Err(CoreError::InvalidParameter(format!(
            "ybar ({}) and ydot ({}) must have the same length (one period each)",
            ybar.len(),
            ydot.len()
        )));
    }
    if ybar.len() < MIN_SAMPLES {
        return Err(CoreError::InsufficientData(format!(
            "ybar needs at least {MIN_SAMPLES} samples per period, got {}",
            ybar.len()
        )));
    }
    let amplitude = finite("amplitude", amplitude)?;
    let omega = finite("omega", omega)?;
    let phi = finite("phi", phi)?;
    if amplitude == 0.0 {
        return Err(CoreError::ZeroAmplitude(
            "the input amplitude U is 0: a zero input identifies nothing; use the amplitude of \
             the applied sine"
                .into(),
        ));
    }
    if omega <= 0.0 {
        return Err(CoreError::InvalidParameter(format!(
            "omega = {omega} rad/s must be > 0"
        )));
    }
    let p = ybar.len();
    let dt = 2.0 * std::f64::consts::PI / omega / p as f64;
    let u_omega = amplitude * omega;
    let s = (0..p)
        .map(|j| u_omega * (omega * (j as f64 * dt) - phi).sin())
        .collect();
    Ok((s, dt))
}

/// `0^nu` with the conventions of `numpy.power`: 0 for `nu > 0`, 1 for `nu = 0`, inf below.
fn zero_pow(nu: f64) -> f64 {
    0f64.powf(nu)
}

impl SlsProblem {
    /// Prepares one averaged period: `ybar` (length P >= 4, units of w), its time derivative
    /// `ydot` (length P, units of w per second), the input amplitude `amplitude` = U (!= 0),
    /// `omega` (rad/s, > 0) and the phase `phi` (rad) of `x(t) = U |G| cos(omega t - phi)`.
    ///
    /// Errors: [`CoreError::NonFinite`], [`CoreError::InvalidParameter`] (length mismatch,
    /// `omega <= 0`), [`CoreError::InsufficientData`] (P < 4), [`CoreError::ZeroAmplitude`]
    /// (`amplitude == 0`).
    pub fn new(ybar: &[f64], ydot: &[f64], amplitude: f64, omega: f64, phi: f64) -> Result<Self> {
        let (s, dt) = sls_inputs(ybar, ydot, amplitude, omega, phi)?;
        let sign = ybar
            .iter()
            .zip(ydot)
            .map(|(&yb, &yd)| sgn(yd) * sgn(yb))
            .collect();
        let ln_abs = ybar
            .iter()
            .map(|&yb| {
                if yb == 0.0 {
                    f64::NEG_INFINITY
                } else {
                    yb.abs().ln()
                }
            })
            .collect();
        Ok(Self {
            s,
            sign,
            ln_abs,
            ydot: ydot.to_vec(),
            dt,
        })
    }

    /// Samples per period P.
    pub fn len(&self) -> usize {
        self.s.len()
    }

    /// Never true for a constructed problem (P >= 4); provided for API symmetry with `len`.
    pub fn is_empty(&self) -> bool {
        self.s.is_empty()
    }

    /// Sample spacing `dt = T/P` (s).
    pub fn dt(&self) -> f64 {
        self.dt
    }

    /// `s_j = U omega sin(omega t_j - phi)`, length P (units of u per second).
    pub fn s(&self) -> &[f64] {
        &self.s
    }

    /// `|ybar_j|^nu` into `out` (length P).
    pub(crate) fn powers(&self, nu: f64, out: &mut [f64]) {
        let zero = zero_pow(nu);
        for (o, &l) in out.iter_mut().zip(&self.ln_abs) {
            *o = if l == f64::NEG_INFINITY {
                zero
            } else {
                (nu * l).exp()
            };
        }
    }

    /// Regressor (23) at exponent `nu`: P rows `[-s_j, s_j sgn sgn |ybar_j|^nu, s_j |ybar_j|^nu]`.
    ///
    /// Errors: [`CoreError::NonFinite`] for a NaN/inf `nu`.
    pub fn regressor(&self, nu: f64) -> Result<Vec<[f64; 3]>> {
        let nu = finite("nu", nu)?;
        let mut pw = vec![0.0; self.len()];
        self.powers(nu, &mut pw);
        Ok(self
            .s
            .iter()
            .zip(&self.sign)
            .zip(&pw)
            .map(|((&s, &sg), &p)| [-s, s * sg * p, s * p])
            .collect())
    }

    /// `M = dt sum psi psi^T` and `r = dt sum ydot psi` from precomputed powers.
    fn normal_from_powers(&self, pw: &[f64]) -> (Matrix3<f64>, Vector3<f64>) {
        let (mut m00, mut m01, mut m02, mut m11, mut m12, mut m22) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        let (mut r0, mut r1, mut r2) = (0.0, 0.0, 0.0);
        for (((&s, &sg), &p), &yd) in self.s.iter().zip(&self.sign).zip(pw).zip(&self.ydot) {
            let (q0, q1, q2) = (-s, s * sg * p, s * p);
            m00 += q0 * q0;
            m01 += q0 * q1;
            m02 += q0 * q2;
            m11 += q1 * q1;
            m12 += q1 * q2;
            m22 += q2 * q2;
            r0 += yd * q0;
            r1 += yd * q1;
            r2 += yd * q2;
        }
        let dt = self.dt;
        let m = Matrix3::new(m00, m01, m02, m01, m11, m12, m02, m12, m22) * dt;
        (m, Vector3::new(r0, r1, r2) * dt)
    }

    /// Normal equations of (22) at `nu`: `(M, r)`, `M` 3x3 symmetric, `r` 3-vector.
    ///
    /// Errors: [`CoreError::NonFinite`] for a NaN/inf `nu`.
    pub fn normal_equations(&self, nu: f64) -> Result<(Matrix3<f64>, Vector3<f64>)> {
        let nu = finite("nu", nu)?;
        let mut pw = vec![0.0; self.len()];
        self.powers(nu, &mut pw);
        Ok(self.normal_from_powers(&pw))
    }

    /// `theta(nu)` (22) and the cost (21) `I_N(nu) = dt sum_j (ydot_j - theta^T psi_j)^2`, the
    /// residual computed directly in a second pass (the normal-equation shortcut
    /// `ydot'ydot - r'theta` cancels catastrophically near a perfect fit).
    ///
    /// Errors: [`CoreError::NonFinite`], [`CoreError::SingularNormalMatrix`] (see
    /// [`solve_normal`]).
    pub fn cost(&self, nu: f64) -> Result<(Vector3<f64>, f64)> {
        let nu = finite("nu", nu)?;
        let mut pw = vec![0.0; self.len()];
        self.powers(nu, &mut pw);
        let (m, r) = self.normal_from_powers(&pw);
        let (theta, _) = solve_normal(&m, &r)?;
        let (t0, t1, t2) = (theta[0], theta[1], theta[2]);
        let mut acc = 0.0;
        for (((&s, &sg), &p), &yd) in self.s.iter().zip(&self.sign).zip(&pw).zip(&self.ydot) {
            let fit = -s * t0 + s * sg * p * t1 + s * p * t2;
            let res = yd - fit;
            acc += res * res;
        }
        Ok((theta, self.dt * acc))
    }
}

/// Solves the 3x3 normal equations `m theta = r` (`docs/design.md` §5).
///
/// Jacobi scaling `d_i = sqrt(m_ii)`, `S = m_ij/(d_i d_j)`; `rcond = lambda_min(S)/lambda_max(S)`
/// from the symmetric eigenvalues; `theta = D^-1 S^-1 D^-1 r` by Cholesky of `S`. Only the lower
/// triangle of `m` is read (as LAPACK's). Returns `(theta, rcond)`.
///
/// Errors: [`CoreError::NonFinite`] for a NaN/inf entry, [`CoreError::SingularNormalMatrix`] when
/// a diagonal entry is `<= 0` or `rcond < 1e-12`.
pub fn solve_normal(m: &Matrix3<f64>, r: &Vector3<f64>) -> Result<(Vector3<f64>, f64)> {
    if !(m.iter().all(|v| v.is_finite()) && r.iter().all(|v| v.is_finite())) {
        return Err(CoreError::NonFinite(
            "the normal equations hold a non-finite entry; check the regressor data".into(),
        ));
    }
    if m.diagonal().iter().any(|&v| v <= 0.0) {
        return Err(CoreError::SingularNormalMatrix {
            rcond: 0.0,
            context: "the normal matrix has a zero regressor column".into(),
        });
    }
    let d = m.diagonal().map(f64::sqrt);
    let scaled = Matrix3::from_fn(|i, j| m[(i, j)] / (d[i] * d[j]));
    let singular = |rcond: f64, context: &str| CoreError::SingularNormalMatrix {
        rcond,
        context: context.into(),
    };
    let eig = SymmetricEigen::try_new(scaled, f64::EPSILON, EIGEN_MAX_ITER)
        .ok_or_else(|| singular(0.0, "the eigenvalue solver did not converge"))?;
    let (lmin, lmax) = (eig.eigenvalues.min(), eig.eigenvalues.max());
    let rcond = if lmax > 0.0 { lmin / lmax } else { 0.0 };
    if rcond < RCOND_MIN {
        return Err(singular(rcond, "the normal matrix is badly conditioned"));
    }
    let chol = scaled
        .cholesky()
        .ok_or_else(|| singular(rcond, "the scaled normal matrix is not positive definite"))?;
    let z = chol.solve(&r.component_div(&d));
    Ok((z.component_div(&d), rcond))
}

/// Golden-section minimisation of `f` on `[lo, hi]` to a bracket width `tol`
/// (`docs/design.md` §5, exactly that update order).
///
/// `x` is the midpoint of the final bracket and `fx = f(x)` is evaluated there. At most
/// `max_iter` reductions are made (see [`GOLDEN_MAX_ITER`]).
///
/// Errors: [`CoreError::NonFinite`] (bounds, tol, or a non-finite value of `f`),
/// [`CoreError::InvalidParameter`] (`lo >= hi`, `tol <= 0` or `tol >= hi - lo`, `max_iter < 1`),
/// [`CoreError::SearchAtBound`] when `a` never left `lo` or `b` never left `hi`; any error of `f`.
pub fn golden_section<F>(f: F, lo: f64, hi: f64, tol: f64, max_iter: usize) -> Result<Golden>
where
    F: FnMut(f64) -> Result<f64>,
{
    golden_section_with(f, lo, hi, tol, max_iter)
}

/// [`golden_section`] for an objective with its own error type `E` (e.g. a Python exception),
/// which is propagated unchanged; the search's own errors convert through `From<CoreError>`.
pub fn golden_section_with<E, F>(
    mut f: F,
    lo: f64,
    hi: f64,
    tol: f64,
    max_iter: usize,
) -> std::result::Result<Golden, E>
where
    E: From<CoreError>,
    F: FnMut(f64) -> std::result::Result<f64, E>,
{
    let lo = finite("lo", lo)?;
    let hi = finite("hi", hi)?;
    let tol = finite("tol", tol)?;
    // Both are finite here, so `>=` is the exact negation of `<`.
    if lo >= hi {
        return Err(CoreError::InvalidParameter(format!(
            "the bracket [{lo}, {hi}] is empty: lo must be < hi"
        ))
        .into());
    }
    if !(0.0 < tol && tol < hi - lo) {
        return Err(CoreError::InvalidParameter(format!(
            "tol = {tol} must be > 0 and smaller than the bracket width {}",
            hi - lo
        ))
        .into());
    }
    // Below a few ulps of the bracket's scale the interior points stop moving and the search
    // would only burn `max_iter` evaluations on rounding noise.
    let resolution = 8.0 * f64::EPSILON * lo.abs().max(hi.abs()).max(f64::MIN_POSITIVE);
    if tol < resolution {
        return Err(CoreError::InvalidParameter(format!(
            "tol = {tol:e} is below the floating-point resolution {resolution:e} of the bracket \
             [{lo}, {hi}]; pass tol >= {resolution:e}"
        ))
        .into());
    }
    if max_iter < 1 {
        return Err(
            CoreError::InvalidParameter(format!("max_iter = {max_iter} must be >= 1")).into(),
        );
    }
    let mut eval = |x: f64| -> std::result::Result<f64, E> {
        let v = f(x)?;
        if v.is_finite() {
            Ok(v)
        } else {
            Err(CoreError::NonFinite(format!(
                "the objective returned {v} at x = {x}; it must be finite on the whole bracket"
            ))
            .into())
        }
    };
    let rho = GOLDEN_RATIO_CONJ;
    let (mut a, mut b) = (lo, hi);
    let mut c = b - rho * (b - a);
    let mut d = a + rho * (b - a);
    let mut fc = eval(c)?;
    let mut fd = eval(d)?;
    let mut iterations = 0;
    while b - a > tol && iterations < max_iter {
        if fc < fd {
            b = d;
            d = c;
            fd = fc;
            c = b - rho * (b - a);
            fc = eval(c)?;
        } else {
            a = c;
            c = d;
            fc = fd;
            d = a + rho * (b - a);
            fd = eval(d)?;
        }
        iterations += 1;
    }
    if a == lo || b == hi {
        let lower = a == lo;
        return Err(CoreError::SearchAtBound {
            bound: if lower { lo } else { hi },
            lower,
            tol,
        }
        .into());
    }
    let x = 0.5 * (a + b);
    let fx = eval(x)?;
    Ok(Golden { x, fx, iterations })
}

/// Checks the `mu` bracket's lower end: the model needs `mu >= 1`.
///
/// Errors: [`CoreError::InvalidParameter`] when `lo < 1`.
pub fn check_mu_bracket(lo: f64) -> Result<()> {
    if lo < 1.0 {
        return Err(CoreError::InvalidParameter(format!(
            "the mu bracket starts at {lo} < 1; the Bouc-Wen model needs mu >= 1"
        )));
    }
    Ok(())
}

/// Estimator (24a-b): golden-section search of `I_N(nu)` on `[lo, hi]` (`lo >= 1`) to a bracket
/// width `tol`, then `theta` at the minimiser `mu`.
///
/// Errors: those of [`check_mu_bracket`], [`golden_section`] and [`SlsProblem::cost`].
pub fn sls_search(
    problem: &SlsProblem,
    lo: f64,
    hi: f64,
    tol: f64,
    max_iter: usize,
) -> Result<SlsFit> {
    check_mu_bracket(lo)?;
    // golden_section's last evaluation is f(x) at the returned midpoint, so the theta kept here
    // is theta(mu) without a second solve.
    let mut theta = Vector3::zeros();
    let golden = golden_section(
        |nu| {
            let (t, cost) = problem.cost(nu)?;
            theta = t;
            Ok(cost)
        },
        lo,
        hi,
        tol,
        max_iter,
    )?;
    Ok(SlsFit {
        mu: golden.x,
        theta,
        cost: golden.fx,
        iterations: golden.iterations,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::average::periodic_average;
    use crate::bouc_wen::BoucWen;
    use crate::estimate::{gain_estimate, max_harmonics, spectral_derivative};
    use crate::linear::TransferFunction;
    use crate::simulate::{simulate, Input};
    use approx::assert_relative_eq;
    use std::f64::consts::PI;

    #[test]
    fn solve_normal_matches_a_hand_solution() {
        // [[4, 2, 0], [2, 5, 1], [0, 1, 3]] theta = [2, 7, 7] has theta = [0, 1, 2].
        let m = Matrix3::new(4.0, 2.0, 0.0, 2.0, 5.0, 1.0, 0.0, 1.0, 3.0);
        let r = Vector3::new(2.0, 7.0, 7.0);
        let (theta, rcond) = solve_normal(&m, &r).unwrap();
        assert_relative_eq!(theta, Vector3::new(0.0, 1.0, 2.0), epsilon = 1e-14);
        // Scaled matrix eigenvalues, by the characteristic polynomial of S.
        let d = [2.0, 5f64.sqrt(), 3f64.sqrt()];
        let s = Matrix3::from_fn(|i, j| m[(i, j)] / (d[i] * d[j]));
        let ev = s.symmetric_eigenvalues();
        assert_relative_eq!(rcond, ev.min() / ev.max(), max_relative = 1e-12);
        assert!(rcond > 0.1 && rcond < 1.0);
    }

    #[test]
    fn solve_normal_rejects_singular_and_non_finite() {
        let r = Vector3::new(1.0, 2.0, 3.0);
        // Rank 2: third row = first + second.
        let m = Matrix3::new(2.0, 1.0, 3.0, 1.0, 2.0, 3.0, 3.0, 3.0, 6.0);
        let e = solve_normal(&m, &r).unwrap_err();
        match e {
            CoreError::SingularNormalMatrix { rcond, .. } => assert!(rcond < RCOND_MIN),
            other => panic!("{other}"),
        }
        assert!(e.to_string().contains("singular normal matrix"), "{e}");
        let zero_col = Matrix3::new(1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0);
        let e = solve_normal(&zero_col, &r).unwrap_err();
        assert!(matches!(e, CoreError::SingularNormalMatrix { rcond, .. } if rcond == 0.0));
        // Indefinite: negative eigenvalue, rcond < 0.
        let indef = Matrix3::new(1.0, 2.0, 0.0, 2.0, 1.0, 0.0, 0.0, 0.0, 1.0);
        let e = solve_normal(&indef, &r).unwrap_err();
        assert!(matches!(e, CoreError::SingularNormalMatrix { rcond, .. } if rcond < 0.0));
        let mut nan = Matrix3::identity();
        nan[(2, 0)] = f64::NAN;
        let e = solve_normal(&nan, &r).unwrap_err();
        assert!(matches!(e, CoreError::NonFinite(_)), "{e}");
    }

    #[test]
    fn golden_section_finds_an_interior_minimum() {
        let g = golden_section(
            |x| Ok((x - 2.0) * (x - 2.0)),
            0.0,
            5.0,
            1e-8,
            GOLDEN_MAX_ITER,
        )
        .unwrap();
        assert_relative_eq!(g.x, 2.0, epsilon = 1e-8);
        assert_relative_eq!(g.fx, (g.x - 2.0).powi(2));
        // 5 rho^k <= 1e-8  <=>  k >= ln(2e-9)/ln(rho) = 41.6
        assert_eq!(g.iterations, 42);
        // The cap stops the search early without an error.
        let capped = golden_section(|x| Ok((x - 2.0).powi(2)), 0.0, 5.0, 1e-8, 5).unwrap();
        assert_eq!(capped.iterations, 5);
    }

    #[test]
    fn golden_section_errors() {
        let e = golden_section(|x| Ok((x + 1.0).powi(2)), 0.0, 5.0, 1e-6, 200).unwrap_err();
        assert_eq!(
            e,
            CoreError::SearchAtBound {
                bound: 0.0,
                lower: true,
                tol: 1e-6
            }
        );
        let e = golden_section(|x| Ok(-x), 0.0, 5.0, 1e-6, 200).unwrap_err();
        assert!(matches!(e, CoreError::SearchAtBound { bound, lower: false, .. } if bound == 5.0));
        assert!(e.to_string().contains("upper end 5"), "{e}");
        let inv = |r: Result<Golden>, text: &str| {
            let e = r.unwrap_err();
            assert!(matches!(e, CoreError::InvalidParameter(_)), "{e}");
            assert!(e.to_string().contains(text), "{e}");
        };
        let f = |x: f64| Ok(x * x);
        inv(golden_section(f, 1.0, 1.0, 1e-3, 200), "is empty");
        inv(golden_section(f, 0.0, 1.0, 0.0, 200), "tol = 0");
        inv(golden_section(f, 0.0, 1.0, 2.0, 200), "bracket width 1");
        inv(golden_section(f, 0.0, 1.0, 1e-3, 0), "max_iter = 0");
        inv(
            golden_section(f, 1.0, 3.0, 1e-300, usize::MAX),
            "below the floating-point resolution",
        );
        let e = golden_section(f, f64::NAN, 1.0, 1e-3, 200).unwrap_err();
        assert!(matches!(e, CoreError::NonFinite(_)), "{e}");
        let e = golden_section(|x| Ok(1.0 / (x - 0.5)), 0.0, 1.0, 1e-3, 200);
        assert!(e.is_ok() || matches!(e, Err(CoreError::NonFinite(_))));
        let e = golden_section(|_| Ok(f64::NAN), 0.0, 1.0, 1e-3, 200).unwrap_err();
        assert!(matches!(e, CoreError::NonFinite(_)), "{e}");
        // The objective's own errors pass through unchanged.
        let e = golden_section(
            |_| Err(CoreError::Unstable("x".into())),
            0.0,
            1.0,
            1e-3,
            200,
        );
        assert_eq!(e.unwrap_err(), CoreError::Unstable("x".into()));
    }

    /// One steady-state period of `w` for `x = U cos(omega t - phi)`, its exact derivative from
    /// (2a), and the spectral derivative of the average.
    struct Loop {
        ybar: Vec<f64>,
        ydot_exact: Vec<f64>,
        ydot_spectral: Vec<f64>,
    }

    const TRUE_BW: (f64, f64, f64) = (0.8, 0.3, 2.5); // beta, gamma, mu
    const U: f64 = 1.3;
    const OMEGA: f64 = 2.0;
    const PHI: f64 = 0.9;

    fn synthetic_loop(p: usize) -> Loop {
        let (beta, gamma, mu) = TRUE_BW;
        let bw = BoucWen::new(1.0, beta, gamma, mu, 0.0).unwrap();
        // G = 1 with delay phi/omega makes x = U cos(omega t - phi) exactly.
        let tf = TransferFunction::new(&[1.0], &[1.0], PHI / OMEGA).unwrap();
        let dt = 2.0 * PI / OMEGA / p as f64;
        let (settle, periods) = (4, 2);
        let n = (settle + periods) * p;
        let sim = simulate(
            &tf,
            &bw,
            Input::Sine {
                amplitude: U,
                omega: OMEGA,
            },
            dt,
            n,
            8,
        )
        .unwrap();
        let ybar = periodic_average(&sim.w, p, settle, periods).unwrap();
        let ydot_exact = ybar
            .iter()
            .enumerate()
            .map(|(j, &w)| {
                let xdot = -U * OMEGA * (OMEGA * j as f64 * dt - PHI).sin();
                bw.wdot(xdot, w)
            })
            .collect();
        let ydot_spectral = spectral_derivative(&ybar, OMEGA, max_harmonics(p)).unwrap();
        Loop {
            ybar,
            ydot_exact,
            ydot_spectral,
        }
    }

    #[test]
    fn cost_vanishes_at_the_true_exponent_with_the_exact_derivative() {
        let (beta, gamma, mu) = TRUE_BW;
        let data = synthetic_loop(512);
        let prob = SlsProblem::new(&data.ybar, &data.ydot_exact, U, OMEGA, PHI).unwrap();
        let (theta, cost) = prob.cost(mu).unwrap();
        assert_relative_eq!(theta, Vector3::new(1.0, beta, gamma), epsilon = 1e-10);
        assert!(cost < 1e-20, "{cost}");
        let fit = sls_search(&prob, 1.0, 10.0, 1e-9, GOLDEN_MAX_ITER).unwrap();
        assert_relative_eq!(fit.mu, mu, epsilon = 1e-7);
        assert_relative_eq!(fit.theta, Vector3::new(1.0, beta, gamma), epsilon = 1e-6);
        assert_eq!(fit.cost, prob.cost(fit.mu).unwrap().1);
        assert_eq!(fit.theta, prob.cost(fit.mu).unwrap().0);
        let g =
            gain_estimate(&data.ybar, &data.ydot_exact, U, OMEGA, PHI, beta, gamma, mu).unwrap();
        assert_relative_eq!(g, 1.0, epsilon = 1e-10);

        // Regressor and normal equations agree with their definitions.
        let psi = prob.regressor(1.7).unwrap();
        let (m, r) = prob.normal_equations(1.7).unwrap();
        let mut m2 = Matrix3::zeros();
        let mut r2 = Vector3::zeros();
        for (row, &yd) in psi.iter().zip(&data.ydot_exact) {
            let v = Vector3::from(*row);
            m2 += v * v.transpose() * prob.dt();
            r2 += v * yd * prob.dt();
        }
        assert_relative_eq!(m, m2, max_relative = 1e-12);
        assert_relative_eq!(r, r2, max_relative = 1e-12);
        assert_eq!(psi[3][0], -prob.s()[3]);
    }

    #[test]
    fn sls_search_recovers_the_loop_from_simulated_data() {
        let (beta, gamma, mu) = TRUE_BW;
        let data = synthetic_loop(1024);
        let prob = SlsProblem::new(&data.ybar, &data.ydot_spectral, U, OMEGA, PHI).unwrap();
        let fit = sls_search(&prob, 1.0, 10.0, 1e-8, GOLDEN_MAX_ITER).unwrap();
        assert_relative_eq!(fit.mu, mu, max_relative = 1e-6);
        assert_relative_eq!(
            fit.theta,
            Vector3::new(1.0, beta, gamma),
            max_relative = 1e-6
        );
        assert!(fit.iterations > 40);
    }

    #[test]
    fn input_validation() {
        let y = [0.1, 0.2, -0.1, 0.0];
        let e = SlsProblem::new(&y, &y[..3], 1.0, 1.0, 0.0).unwrap_err();
        assert!(matches!(e, CoreError::InvalidParameter(_)), "{e}");
        let e = SlsProblem::new(&y[..3], &y[..3], 1.0, 1.0, 0.0).unwrap_err();
        assert!(matches!(e, CoreError::InsufficientData(_)), "{e}");
        let e = SlsProblem::new(&y, &y, 0.0, 1.0, 0.0).unwrap_err();
        assert!(matches!(e, CoreError::ZeroAmplitude(_)), "{e}");
        let e = SlsProblem::new(&y, &y, 1.0, 0.0, 0.0).unwrap_err();
        assert!(matches!(e, CoreError::InvalidParameter(_)), "{e}");
        let e = SlsProblem::new(&y, &y, 1.0, 1.0, f64::NAN).unwrap_err();
        assert!(matches!(e, CoreError::NonFinite(_)), "{e}");
        let prob = SlsProblem::new(&y, &y, 1.0, 1.0, 0.0).unwrap();
        assert!(!prob.is_empty());
        assert!(matches!(
            prob.cost(f64::INFINITY),
            Err(CoreError::NonFinite(_))
        ));
        // ybar_j = 0 gives |0|^nu = 0 for nu > 0 and 1 for nu = 0, as numpy.
        assert_eq!(prob.regressor(2.0).unwrap()[3][2], 0.0);
        assert_eq!(prob.regressor(0.0).unwrap()[3][2], prob.s()[3]);
        let e = sls_search(&prob, 0.5, 10.0, 1e-6, 200).unwrap_err();
        assert!(matches!(e, CoreError::InvalidParameter(_)), "{e}");
        // A constant output cannot be fitted: the hysteresis columns are proportional.
        let flat = [0.5; 8];
        let yd = [0.0; 8];
        let prob = SlsProblem::new(&flat, &yd, 1.0, 1.0, 0.0).unwrap();
        assert!(matches!(
            prob.cost(2.0),
            Err(CoreError::SingularNormalMatrix { .. })
        ));
        let e = gain_estimate(&[0.0; 8], &yd, 1.0, 1.0, 0.0, 1.0, 0.0, 2.0);
        assert!(e.is_ok());
        let e = gain_estimate(&[1.0; 8], &yd, 1.0, 1.0, 0.0, 1.0, 0.0, f64::NAN).unwrap_err();
        assert!(matches!(e, CoreError::NonFinite(_)), "{e}");
        // chi = s (-1 + gamma |1|^mu) = 0 when gamma = 1 and sgn(ydot) = 0.
        let e = gain_estimate(&[1.0; 8], &yd, 1.0, 1.0, 0.0, 0.0, 1.0, 2.0).unwrap_err();
        assert!(matches!(e, CoreError::SingularNormalMatrix { .. }), "{e}");
    }
}
