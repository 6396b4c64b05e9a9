//! The arithmetic every steady-loop solver of one scalar hysteretic state shares: the Jacobian's
//! columns of the shape parameters, the RK4 step with its sensitivities (forward, by dual numbers,
//! for a rate integrated in time; summed in reverse, for a rate integrated along the path), the
//! bracketed Newton step on the period map `W(w_0) - w_0`, the fold of a sample's partials
//! with the fixed point's own sensitivities, and the checks of `mu` and of the amplitude.
//!
//! Users: [`crate::path_loop`] (RK4 in the played input `xp`, weights of [`rk4_reverse_weights`],
//! four pieces shot at once) and [`crate::series_loop`] (RK4 in time with [`Dual`] numbers). A new
//! state term brings only its rate (or, in closed form, its segment map and the map's partials):
//! its columns start from the shared ones (`COL_*`), its RK4 stages are [`rk4_dual_step`] or
//! [`rk4_reverse_weights`] with [`rk4_combine`], its shooting steps with [`Bracket`], and each
//! sample's row is [`fold_row`] of its partials at a fixed start. Every function here evaluates
//! exactly the expressions its users had inline, in the same order, so that moving them here
//! changed no bit of any result.

use crate::error::{CoreError, Result};

/// d w / d beta: the column of `beta` in every steady loop's Jacobian row.
pub const COL_BETA: usize = 0;
/// d w / d gamma.
pub const COL_GAMMA: usize = 1;
/// d w / d mu.
pub const COL_MU: usize = 2;
/// d w / d A (A signed: the amplitude of x).
pub const COL_AMPLITUDE: usize = 3;
/// d w / d phi.
pub const COL_PHI: usize = 4;
/// d w / d delta (asymmetry).
pub const COL_DELTA: usize = 5;
/// Columns every steady loop has (`COL_*`); a loop's own columns follow them.
pub const N_SHARED_COLS: usize = 6;

/// `mu > 1`, as the identification model has it (`|w|^mu` differentiable at `w = 0`).
///
/// Errors: [`CoreError::InvalidParameter`] otherwise.
pub(crate) fn check_mu(mu: f64) -> Result<()> {
    if mu <= 1.0 {
        return Err(CoreError::InvalidParameter(format!(
            "mu = {mu} must be > 1 in the identification model"
        )));
    }
    Ok(())
}

/// A nonzero amplitude of x.
///
/// Errors: [`CoreError::ZeroAmplitude`] for `A = 0`: the loop is a point.
pub(crate) fn check_amplitude(amplitude: f64) -> Result<()> {
    if amplitude == 0.0 {
        return Err(CoreError::ZeroAmplitude(
            "the amplitude of x is 0: the loop is a point".into(),
        ));
    }
    Ok(())
}

/// One classical RK4 increment `y + h/6 (k_1 + 2 k_2 + 2 k_3 + k_4)` of a value, or of one of its
/// carried derivatives (the same expression for each).
#[inline(always)]
pub(crate) fn rk4_combine(y: f64, h: f64, k: [f64; 4]) -> f64 {
    y + h / 6.0 * (k[0] + 2.0 * k[1] + 2.0 * k[2] + k[3])
}

/// The sensitivities of one RK4 step of length `h` on a scalar state, summed in reverse: with
/// `a_i = dk_i/dw` at the stage states, the weights `l_4 = h/6`, `l_3 = h/3 + l_4 a_4 h`,
/// `l_2 = h/3 + l_3 a_3 h/2`, `l_1 = h/6 + l_2 a_2 h/2` give the step's derivative
/// `R = dw_new/dw = 1 + sum l_i a_i`, and `dw_new/dq = sum l_i b_i` for any parameter `q` with
/// `b_i = dk_i/dq` at fixed stage state: the derivatives of the augmented RK4 (forward
/// sensitivities riding along) with a few multiplications per parameter. Returns `(l, R)`.
#[inline(always)]
pub(crate) fn rk4_reverse_weights(h: f64, a: [f64; 4]) -> ([f64; 4], f64) {
    let l4 = h / 6.0;
    let l3 = h / 3.0 + l4 * a[3] * h;
    let l2 = h / 3.0 + l3 * a[2] * 0.5 * h;
    let l1 = h / 6.0 + l2 * a[1] * 0.5 * h;
    let r = 1.0 + l1 * a[0] + l2 * a[1] + l3 * a[2] + l4 * a[3];
    ([l1, l2, l3, l4], r)
}

/// A value with its derivatives in `N` carried directions (forward-mode differentiation).
#[derive(Clone, Copy)]
pub(crate) struct Dual<const N: usize> {
    /// The value.
    pub(crate) v: f64,
    /// Its derivatives.
    pub(crate) d: [f64; N],
}

impl<const N: usize> Dual<N> {
    /// `self + h k`, value and derivatives.
    #[inline(always)]
    pub(crate) fn axpy(&self, h: f64, k: &Dual<N>) -> Dual<N> {
        let mut d = self.d;
        for (a, b) in d.iter_mut().zip(&k.d) {
            *a += h * b;
        }
        Dual {
            v: self.v + h * k.v,
            d,
        }
    }
}

/// One classical RK4 step of length `h` from `(t, w)` of `dw/dt = f(t, w)`, value and carried
/// derivatives together: RK4 commutes with forward differentiation, so the derivatives are those of
/// the discrete map.
#[inline(always)]
pub(crate) fn rk4_dual_step<const N: usize>(
    f: impl Fn(f64, &Dual<N>) -> Dual<N>,
    t: f64,
    h: f64,
    w: &Dual<N>,
) -> Dual<N> {
    let k1 = f(t, w);
    let k2 = f(t + 0.5 * h, &w.axpy(0.5 * h, &k1));
    let k3 = f(t + 0.5 * h, &w.axpy(0.5 * h, &k2));
    let k4 = f(t + h, &w.axpy(h, &k3));
    let mut next = *w;
    next.v = rk4_combine(w.v, h, [k1.v, k2.v, k3.v, k4.v]);
    for (i, o) in next.d.iter_mut().enumerate() {
        *o = rk4_combine(*o, h, [k1.d[i], k2.d[i], k3.d[i], k4.d[i]]);
    }
    next
}

/// The bracket `[lo, hi]` of Newton safeguarded by bisection on `g(w_0) = W(w_0) - w_0` over
/// `[-w_b, w_b]`: `W` maps the bracket into itself, so `g > 0` at `-w_b` and `g < 0` at `w_b`.
pub(crate) struct Bracket {
    lo: f64,
    hi: f64,
}

impl Bracket {
    /// `[-bound, bound]`.
    pub(crate) fn new(bound: f64) -> Self {
        Self {
            lo: -bound,
            hi: bound,
        }
    }

    /// After a pass from `w0` with residual `g`: narrows the bracket (a positive residual raises
    /// the lower end) and returns the next iterate, `newton` if it lies strictly inside, else the
    /// midpoint (a NaN `newton`, a refused step, gives the midpoint).
    #[inline]
    pub(crate) fn next(&mut self, w0: f64, g: f64, newton: f64) -> f64 {
        if g > 0.0 {
            self.lo = w0;
        } else {
            self.hi = w0;
        }
        if newton > self.lo && newton < self.hi {
            newton
        } else {
            0.5 * (self.lo + self.hi)
        }
    }
}

/// `row += phi dv`: a sample's partials at a fixed start value, plus its slope `phi` to that start
/// times the start's own sensitivities `dv` (the fixed point's chain rule).
#[inline]
pub(crate) fn fold_row(row: &mut [f64], phi: f64, dv: &[f64]) {
    for (x, d) in row.iter_mut().zip(dv) {
        *x += phi * d;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dual_rk4_step_is_exact_on_a_linear_rate_and_carries_its_derivative() {
        // dw/dt = -c w with w and dw/dc carried: one RK4 step is the degree-4 Taylor polynomial
        // of exp(-c h), and its derivative in c the polynomial's.
        let (c, h) = (0.7, 0.3);
        let f = |_t: f64, w: &Dual<1>| Dual {
            v: -c * w.v,
            d: [-w.v - c * w.d[0]],
        };
        let next = rk4_dual_step(f, 0.0, h, &Dual { v: 1.0, d: [0.0] });
        let z: f64 = -c * h;
        let poly = 1.0 + z + z * z / 2.0 + z.powi(3) / 6.0 + z.powi(4) / 24.0;
        let dpoly = -h * (1.0 + z + z * z / 2.0 + z.powi(3) / 6.0);
        assert!((next.v - poly).abs() < 1e-15, "{} {poly}", next.v);
        assert!((next.d[0] - dpoly).abs() < 1e-15, "{} {dpoly}", next.d[0]);
    }

    #[test]
    fn reverse_weights_give_the_forward_derivative() {
        // On dw/dt = -c w, R = dw_new/dw is the same polynomial as the step itself.
        let (c, h) = (1.3, 0.2);
        let (l, r) = rk4_reverse_weights(h, [-c; 4]);
        let z: f64 = -c * h;
        let poly = 1.0 + z + z * z / 2.0 + z.powi(3) / 6.0 + z.powi(4) / 24.0;
        assert!((r - poly).abs() < 1e-15, "{r} {poly}");
        assert!(l.iter().all(|x| x.is_finite() && *x > 0.0));
    }

    #[test]
    fn bracket_takes_inside_newton_steps_and_bisects_otherwise() {
        let mut b = Bracket::new(2.0);
        assert_eq!(b.next(0.0, 1.0, 0.5), 0.5);
        assert_eq!(b.next(0.5, -1.0, 3.0), 0.25);
        assert_eq!(b.next(0.25, 1.0, f64::NAN), 0.375);
    }
}
