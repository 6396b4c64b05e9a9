//! Steady loop of the hysteretic element behind Spencer's series dashpot (`docs/diagnosis.md`,
//! "Series dashpot"; Spencer, Dyke, Sain & Carlson, J. Eng. Mech. 123(3), 1997, with their
//! `c0 = k0 = 0`).
//!
//! The element is driven by its own travel `d = x - q`, the dashpot carrying its force
//! (`c1 qdot = w`, `rho = 1/c1`): with alpha = 1 and `x = A cos(theta - phi)`,
//! `theta = omega t`,
//!
//! ```text
//! dw/dtheta = v [1 - |w|^mu (beta sgn(v w) + gamma + delta sgn(w))],
//! v = dd/dtheta = -A sin(theta - phi) - r w,   r = rho / omega,
//! ```
//!
//! rate dependent through `r`, so the loop is integrated in time (theta), not along the path. The
//! right-hand side is Lipschitz (the bracket jumps only where `v = 0`), `|w| <= w_b =
//! (beta + gamma - |delta|)^(-1/mu)` is invariant, and the period map `W(w_0)` is increasing, so
//! the steady loop is the root of `W(w_0) - w_0` on `[-w_b, w_b]`: Newton, safeguarded by
//! bisection. Each pass is classical RK4 in theta with the forward sensitivities of `w` to
//! `(w_0, beta, gamma, mu, A, phi, delta, r)` riding along (dual numbers: RK4 commutes with
//! forward differentiation, so these are the derivatives of the discrete map). At the fixed point
//! `dw_0/dp = (dW/dp) / (1 - dW/dw_0)` and every sample's row is `dw_j/dp + dw_j/dw_0 dw_0/dp`.
//!
//! Steps per sample interval: at least `substeps`, and enough that a step times the bound
//! `L >= |dF/dw|` on `|w| <= w_b` stays below 1 (RK4 is stable up to 2.79). The NumPy oracle is
//! `reference/series_loop.py`.

use crate::bouc_wen::sgn;
use crate::error::{finite, CoreError, Result};
use crate::loop_kernel::{
    check_amplitude, check_mu, fold_row, rk4_dual_step, Bracket, Dual as DualN,
};
use std::f64::consts::PI;

/// Derivatives carried: `w_0, beta, gamma, mu, A, phi, delta, r`.
const ND: usize = 8;
/// Column of `d/dw_0` in the carried derivatives.
const DW0: usize = 0;
// Columns of a [`SeriesLoop::jac`] row: `d w / d(beta, gamma, mu, A, phi, delta, r)`, the shared
// ones first.
pub use crate::loop_kernel::{
    COL_AMPLITUDE as SD_AMPLITUDE, COL_BETA as SD_BETA, COL_DELTA as SD_DELTA,
    COL_GAMMA as SD_GAMMA, COL_MU as SD_MU, COL_PHI as SD_PHI,
};
/// d w / d r (`r = rho / omega`, per radian).
pub const SD_R: usize = crate::loop_kernel::N_SHARED_COLS;
/// Columns of a [`SeriesLoop::jac`] row.
pub const N_SD: usize = 7;

/// Newton (or bisection) passes allowed.
const MAX_ITER: usize = 80;
/// Relative tolerance of `|W(w_0) - w_0| <= tol w_b`.
const RTOL: f64 = 1e-12;
/// Most RK4 steps per sample interval: beyond, the loop is too stiff for this explicit solver (a
/// named error, which a fit's trial step takes as a rejected step) rather than minutes per call.
pub const MAX_STEPS_PER_SAMPLE: usize = 256;

/// The steady loop on the sample grid and its Jacobian.
#[derive(Debug, Clone)]
pub struct SeriesLoop {
    /// `w(theta_j)`, `theta_j = 2 pi j / P`.
    pub w: Vec<f64>,
    /// `d w(theta_j) / d(beta, gamma, mu, A, phi, delta, r)` (columns `SD_*`).
    pub jac: Vec<[f64; N_SD]>,
    /// Newton (or bisection) passes.
    pub iterations: usize,
}

/// A value with its derivatives in the [`ND`] carried directions.
type Dual = DualN<ND>;

/// The model's parameters.
#[derive(Clone, Copy)]
struct Params {
    a: f64,
    beta: f64,
    gamma: f64,
    mu: f64,
    delta: f64,
    phi: f64,
    r: f64,
}

/// `F(theta, w)` and its derivatives (through `w`'s and the parameters' own directions).
fn rhs(p: &Params, theta: f64, w: &Dual) -> Dual {
    let (s, c) = (theta - p.phi).sin_cos();
    // v = -A sin(theta - phi) - r w.
    let v = -p.a * s - p.r * w.v;
    let mut dv = [0.0; ND];
    for (o, dw) in dv.iter_mut().zip(&w.d) {
        *o = -p.r * dw;
    }
    dv[4] += -s;
    dv[5] += p.a * c;
    dv[7] += -w.v;
    let (sw, svw) = (sgn(w.v), sgn(v * w.v));
    let aw = w.v.abs();
    let m = aw.powf(p.mu);
    // d|w|^mu/dw = mu |w|^(mu-1) sgn(w) (mu > 1: 0 at w = 0); d/dmu = |w|^mu ln|w| (0 at w = 0).
    let (dm_dw, dm_dmu) = if aw > 0.0 {
        (p.mu * m / aw * sw, m * aw.ln())
    } else {
        (0.0, 0.0)
    };
    let bracket = p.beta * svw + p.gamma + p.delta * sw;
    let h = 1.0 - m * bracket;
    let mut dh = [0.0; ND];
    for (o, dw) in dh.iter_mut().zip(&w.d) {
        *o = -dm_dw * dw * bracket;
    }
    dh[1] -= m * svw;
    dh[2] -= m;
    dh[3] -= dm_dmu * bracket;
    dh[6] -= m * sw;
    let mut d = [0.0; ND];
    for ((o, a), b) in d.iter_mut().zip(&dv).zip(&dh) {
        *o = a * h + v * b;
    }
    Dual { v: v * h, d }
}

/// One pass over the period from `w_0`: `W` with its derivatives, and (when `record`) the samples.
fn pass(p: &Params, w0: f64, n: usize, m: usize, record: Option<&mut Vec<Dual>>) -> Dual {
    let mut d = [0.0; ND];
    d[DW0] = 1.0;
    let mut w = Dual { v: w0, d };
    let h = 2.0 * PI / (n * m) as f64;
    let mut rec = record;
    for j in 0..n {
        if let Some(r) = rec.as_deref_mut() {
            r.push(w);
        }
        for s in 0..m {
            let t = h * (j * m + s) as f64;
            w = rk4_dual_step(|t, w| rhs(p, t, w), t, h, &w);
        }
    }
    w
}

/// RK4 steps per sample interval: `substeps`, or enough that `h L <= 1`, `L` the bound of
/// `|dF/dw|` on `|w| <= w_b`.
fn steps_per_sample(p: &Params, bound: f64, n: usize, substeps: usize) -> usize {
    let bg = p.beta.abs() + p.gamma.abs() + p.delta.abs();
    let vmax = p.a.abs() + p.r * bound;
    let stiff = vmax * p.mu * bg * bound.powf(p.mu - 1.0) + p.r * (1.0 + bg * bound.powf(p.mu));
    let need = (stiff * 2.0 * PI / n as f64).ceil();
    if !need.is_finite() || need > MAX_STEPS_PER_SAMPLE as f64 {
        MAX_STEPS_PER_SAMPLE + 1
    } else if need > substeps as f64 {
        need as usize
    } else {
        substeps
    }
}

/// The steady loop of the element behind the series dashpot at `P` samples (module header).
///
/// `amplitude` is the signed A of x, `r = rho/omega >= 0` per radian; `substeps` the least RK4
/// steps per sample interval.
///
/// Errors: [`CoreError::NonFinite`]; [`CoreError::InvalidParameter`] for `mu <= 1`,
/// `beta + gamma <= |delta|`, `r < 0`, `substeps < 1`; [`CoreError::ZeroAmplitude`] for `A = 0`;
/// [`CoreError::InsufficientData`] for `P < 4`; [`CoreError::NotConverged`] when no loop is
/// found.
#[allow(clippy::too_many_arguments)]
pub fn series_loop(
    amplitude: f64,
    beta: f64,
    gamma: f64,
    mu: f64,
    delta: f64,
    phi: f64,
    r: f64,
    p: usize,
    substeps: usize,
) -> Result<SeriesLoop> {
    for (name, v) in [
        ("amplitude", amplitude),
        ("beta", beta),
        ("gamma", gamma),
        ("mu", mu),
        ("delta", delta),
        ("phi", phi),
        ("series_dashpot r", r),
    ] {
        finite(name, v)?;
    }
    check_mu(mu)?;
    let margin = beta + gamma - delta.abs();
    if margin <= 0.0 {
        return Err(CoreError::InvalidParameter(format!(
            "beta + gamma - |delta| = {margin} must be > 0: otherwise one side of the loop is \
             unbounded"
        )));
    }
    if r < 0.0 {
        return Err(CoreError::InvalidParameter(format!(
            "series_dashpot r = rho/omega = {r} must be >= 0"
        )));
    }
    check_amplitude(amplitude)?;
    if p < 4 {
        return Err(CoreError::InsufficientData(format!(
            "P = {p} samples per period; the steady loop needs at least 4"
        )));
    }
    if substeps < 1 {
        return Err(CoreError::InvalidParameter(format!(
            "substeps = {substeps} must be >= 1"
        )));
    }
    let bound = (1.0 / margin).powf(1.0 / mu);
    if !(bound.is_finite() && bound > 0.0) {
        return Err(CoreError::InvalidParameter(format!(
            "the loop's bound (beta + gamma - |delta|)^(-1/mu) = {bound:e} is not a usable number"
        )));
    }
    let prm = Params {
        a: amplitude,
        beta,
        gamma,
        mu,
        delta,
        phi,
        r,
    };
    let m = steps_per_sample(&prm, bound, p, substeps);
    if m > MAX_STEPS_PER_SAMPLE.max(substeps) {
        return Err(CoreError::NotConverged(format!(
            "the series-dashpot loop is too stiff for its explicit RK4 (more than \
             {MAX_STEPS_PER_SAMPLE} steps per sample) at A = {amplitude}, beta = {beta}, \
             gamma = {gamma}, mu = {mu}, delta = {delta}, r = rho/omega = {r}: w's bound \
             (beta + gamma - |delta|)^(-1/mu) = {bound:e} or r is too large"
        )));
    }
    let (w0, out, iterations) = shoot(&prm, bound, p, m)?;
    let mut samples = Vec::with_capacity(p);
    let _ = pass(&prm, w0, p, m, Some(&mut samples));
    let slope = 1.0 - out.d[DW0];
    let dw0: Vec<f64> = (1..ND).map(|i| out.d[i] / slope).collect();
    let w = samples.iter().map(|s| s.v).collect();
    let jac = samples
        .iter()
        .map(|s| {
            let mut row = [0.0; N_SD];
            row.copy_from_slice(&s.d[DW0 + 1..]);
            fold_row(&mut row, s.d[DW0], &dw0);
            row
        })
        .collect();
    Ok(SeriesLoop { w, jac, iterations })
}

/// Safeguarded Newton on `g(w_0) = W(w_0) - w_0` over `[-w_b, w_b]`: the fixed point, the last
/// pass's `W` (with its derivatives) and the passes taken.
fn shoot(p: &Params, bound: f64, n: usize, m: usize) -> Result<(f64, Dual, usize)> {
    let mut bracket = Bracket::new(bound);
    let mut w0 = 0.0;
    for it in 1..=MAX_ITER {
        let out = pass(p, w0, n, m, None);
        if !out.v.is_finite() {
            return Err(CoreError::NotConverged(format!(
                "the series-dashpot loop diverged (w = {} after one period) for A = {}, beta = {}, \
                 gamma = {}, mu = {}, delta = {}, r = {}",
                out.v, p.a, p.beta, p.gamma, p.mu, p.delta, p.r
            )));
        }
        let g = out.v - w0;
        if g.abs() <= RTOL * bound {
            return Ok((w0, out, it));
        }
        // Newton only where W - w_0 decreases (else a NaN step: bisection).
        let slope = out.d[DW0] - 1.0;
        let newton = if slope < 0.0 {
            w0 - g / slope
        } else {
            f64::NAN
        };
        w0 = bracket.next(w0, g, newton);
    }
    Err(CoreError::NotConverged(format!(
        "the series-dashpot loop found no periodic solution in {MAX_ITER} passes for A = {}, \
         beta = {}, gamma = {}, mu = {}, delta = {}, r = {}",
        p.a, p.beta, p.gamma, p.mu, p.delta, p.r
    )))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::path_loop::path_loop;

    #[test]
    fn zero_dashpot_is_the_path_loop() {
        let (a, beta, gamma, mu, delta, phi) = (1.7, 0.6, 0.3, 1.6, 0.1, 0.4);
        let s = series_loop(a, beta, gamma, mu, delta, phi, 0.0, 64, 8).unwrap();
        let l = path_loop(a, beta, gamma, mu, delta, 0.0, phi, 64, 16).unwrap();
        let err =
            s.w.iter()
                .zip(&l.w)
                .map(|(x, y)| (x - y).abs())
                .fold(0.0, f64::max);
        assert!(err < 1e-5, "{err}");
    }

    #[test]
    fn jacobian_matches_central_differences() {
        let base = [1.3, 0.7, 0.2, 1.8, -0.15, 0.3, 0.4];
        let f = |q: &[f64; 7]| series_loop(q[0], q[1], q[2], q[3], q[4], q[5], q[6], 32, 4);
        let l = f(&base).unwrap();
        // Parameter order in `base`: A, beta, gamma, mu, delta, phi, r.
        let cols = [
            SD_AMPLITUDE,
            SD_BETA,
            SD_GAMMA,
            SD_MU,
            SD_DELTA,
            SD_PHI,
            SD_R,
        ];
        for (i, &col) in cols.iter().enumerate() {
            let h = 1e-6;
            let (mut up, mut dn) = (base, base);
            up[i] += h;
            dn[i] -= h;
            let (wu, wd) = (f(&up).unwrap().w, f(&dn).unwrap().w);
            for j in 0..32 {
                let fd = (wu[j] - wd[j]) / (2.0 * h);
                let an = l.jac[j][col];
                assert!(
                    (fd - an).abs() <= 1e-5 * (1.0 + an.abs()),
                    "column {col} sample {j}: fd {fd} analytic {an}"
                );
            }
        }
    }

    #[test]
    fn too_stiff_a_loop_is_a_named_error_not_a_hang() {
        let r = series_loop(1.0, 0.5, 0.5, 2.0, 0.0, 0.0, 1e5, 32, 2);
        assert!(matches!(r, Err(CoreError::NotConverged(_))), "{r:?}");
    }

    #[test]
    fn bad_input_is_named() {
        assert!(matches!(
            series_loop(1.0, 0.5, 0.5, 2.0, 0.0, 0.0, -0.1, 32, 2),
            Err(CoreError::InvalidParameter(_))
        ));
        assert!(matches!(
            series_loop(0.0, 0.5, 0.5, 2.0, 0.0, 0.0, 0.1, 32, 2),
            Err(CoreError::ZeroAmplitude(_))
        ));
        assert!(matches!(
            series_loop(1.0, 0.5, 0.5, 2.0, 0.0, 0.0, 0.1, 3, 2),
            Err(CoreError::InsufficientData(_))
        ));
        assert!(matches!(
            series_loop(1.0, 0.5, 0.5, 2.0, 0.0, f64::NAN, 0.1, 32, 2),
            Err(CoreError::NonFinite(_))
        ));
    }
}
