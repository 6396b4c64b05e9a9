//! The Wiener cascade on a sampled input of any waveform, with its exact parameter Jacobian
//! (issue #20: time-domain identification by output error).
//!
//! The model is the alpha-normalised plain cascade of `rust/simulate.rs`: `x = G v`,
//! `v(t) = u(t - tau)` (0 before the delay has elapsed), `G(s) = N(s)/D(s)` in controllable
//! canonical form with a monic `D`, and Bouc-Wen (2a) with alpha = 1,
//! `wdot = xdot (1 - (beta sgn(xdot) sgn(w) + gamma) |w|^mu)`, `y = w`. The input samples are
//! interpolated by the same cubic Hermite (Catmull-Rom slopes) as `simulate_sampled`, and the
//! state is integrated by the same classical RK4 on the same stage times, so a model simulated
//! here and by `simulate_sampled` agrees to rounding.
//!
//! ## Forward sensitivities
//! Every quantity of the step is carried as a forward-mode dual number `v + sum_i d_i e_i`, one
//! direction per parameter. Propagating the duals through the RK4 stages is the derivative of the
//! *discrete* RK4 map itself (the internal differentiation of the scheme; the same as integrating
//! the variational equations with the same stages, as `rust/steady.rs` does by hand), so the
//! Jacobian is exact for the discrete model the residuals are computed from, not a finite
//! difference. The delay enters through the interpolant: `dv/dtau = -u'(t - tau)`,
//! `dvdot/dtau = -u''(t - tau)` (the cubic's own derivatives; its knots are measure-zero).
//!
//! `|w|^mu` is `exp(mu ln|w|)` with its derivatives `mu |w|^(mu-1) sgn(w)` and `|w|^mu ln|w|`; at
//! `w = 0` both are 0 (mu > 1; the state starts there), and `sgn` is held constant.
//!
//! Parameter layout (length `m + n + 6 <= MAX_PARAMS`):
//! `[b_0..b_m, a_1..a_n, tau, beta, gamma, mu, w0]`, `N = b_0 s^m + ... + b_m`,
//! `D = s^n + a_1 s^(n-1) + ... + a_n`, `m <= n <= MAX_ORDER`.

use crate::bouc_wen::sgn;
use crate::error::{all_finite, CoreError, Result};
use crate::hermite::Hermite;

/// Largest denominator degree.
pub const MAX_ORDER: usize = 4;
/// Largest number of parameters (`m + n + 6` with `m <= n <= MAX_ORDER`).
pub const MAX_PARAMS: usize = 16;

/// A forward-mode dual number with [`MAX_PARAMS`] directions.
#[derive(Clone, Copy, Debug)]
struct Dual {
    v: f64,
    d: [f64; MAX_PARAMS],
}

impl Dual {
    #[inline(always)]
    const fn constant(v: f64) -> Self {
        Self {
            v,
            d: [0.0; MAX_PARAMS],
        }
    }

    #[inline(always)]
    fn variable(v: f64, i: usize) -> Self {
        let mut out = Self::constant(v);
        out.d[i] = 1.0;
        out
    }

    #[inline(always)]
    fn add(&self, o: &Self) -> Self {
        let mut d = self.d;
        for (di, oi) in d.iter_mut().zip(&o.d) {
            *di += oi;
        }
        Self { v: self.v + o.v, d }
    }

    #[inline(always)]
    fn sub(&self, o: &Self) -> Self {
        let mut d = self.d;
        for (di, oi) in d.iter_mut().zip(&o.d) {
            *di -= oi;
        }
        Self { v: self.v - o.v, d }
    }

    #[inline(always)]
    fn mul(&self, o: &Self) -> Self {
        let mut d = [0.0; MAX_PARAMS];
        for ((di, a), b) in d.iter_mut().zip(&self.d).zip(&o.d) {
            *di = a * o.v + self.v * b;
        }
        Self { v: self.v * o.v, d }
    }

    #[inline(always)]
    fn scale(&self, k: f64) -> Self {
        let mut d = self.d;
        for di in d.iter_mut() {
            *di *= k;
        }
        Self { v: self.v * k, d }
    }

    /// `self + k * o`.
    #[inline(always)]
    fn axpy(&self, k: f64, o: &Self) -> Self {
        let mut d = self.d;
        for (di, oi) in d.iter_mut().zip(&o.d) {
            *di += k * oi;
        }
        Self {
            v: self.v + k * o.v,
            d,
        }
    }

    /// `|self|^mu` for mu >= 1 (0 with zero derivatives at 0).
    #[inline(always)]
    fn pow_abs(&self, mu: &Self) -> Self {
        let aw = self.v.abs();
        if aw == 0.0 {
            return Self::constant(0.0);
        }
        let lnw = aw.ln();
        let val = (mu.v * lnw).exp();
        // d|w|^mu = |w|^mu (ln|w| dmu + mu sgn(w) dw / |w|)
        let dw = val * mu.v * sgn(self.v) / aw;
        let dm = val * lnw;
        let mut d = [0.0; MAX_PARAMS];
        for ((di, a), b) in d.iter_mut().zip(&self.d).zip(&mu.d) {
            *di = dw * a + dm * b;
        }
        Self { v: val, d }
    }
}

/// The model's parameters as duals, in the canonical form of `TransferFunction::realize`.
struct Model {
    n: usize,
    a: [Dual; MAX_ORDER],
    c: [Dual; MAX_ORDER],
    d: Dual,
    tau: f64,
    i_tau: usize,
    beta: Dual,
    gamma: Dual,
    mu: Dual,
    w0: Dual,
}

impl Model {
    fn new(m: usize, n: usize, theta: &[f64]) -> Self {
        let var = |i: usize| Dual::variable(theta[i], i);
        // b left-padded to length n + 1.
        let mut b = [Dual::constant(0.0); MAX_ORDER + 1];
        for k in 0..=m {
            b[n - m + k] = var(k);
        }
        let mut a = [Dual::constant(0.0); MAX_ORDER];
        for (j, aj) in a.iter_mut().enumerate().take(n) {
            *aj = var(m + 1 + j);
        }
        let d = b[0];
        let mut c = [Dual::constant(0.0); MAX_ORDER];
        for j in 0..n {
            c[j] = b[j + 1].sub(&d.mul(&a[j]));
        }
        let base = m + 1 + n;
        Self {
            n,
            a,
            c,
            d,
            tau: theta[base],
            i_tau: base,
            beta: var(base + 1),
            gamma: var(base + 2),
            mu: var(base + 3),
            w0: var(base + 4),
        }
    }

    /// `(v, vdot)` at the stage time `t` (s from the record's start).
    #[inline(always)]
    fn input(&self, src: &Hermite<'_>, t: f64) -> (Dual, Dual) {
        let s = t - self.tau;
        if s < 0.0 {
            return (Dual::constant(0.0), Dual::constant(0.0));
        }
        let (u, du, ddu) = src.value_slope_second(s);
        let mut v = Dual::constant(u);
        let mut vdot = Dual::constant(du);
        v.d[self.i_tau] = -du;
        vdot.d[self.i_tau] = -ddu;
        (v, vdot)
    }

    /// `(xsdot, wdot)`.
    #[inline(always)]
    fn rhs(
        &self,
        xs: &[Dual; MAX_ORDER],
        w: &Dual,
        (v, vdot): &(Dual, Dual),
    ) -> ([Dual; MAX_ORDER], Dual) {
        let n = self.n;
        let mut dxs = [Dual::constant(0.0); MAX_ORDER];
        let mut xdot = self.d.mul(vdot);
        if n > 0 {
            let mut acc = *v;
            for (aj, xj) in self.a.iter().zip(xs).take(n) {
                acc = acc.sub(&aj.mul(xj));
            }
            dxs[0] = acc;
            dxs[1..n].copy_from_slice(&xs[..n - 1]);
            for (cj, dj) in self.c.iter().zip(&dxs).take(n) {
                xdot = xdot.add(&cj.mul(dj));
            }
        }
        let wmu = w.pow_abs(&self.mu);
        let k = self.beta.scale(sgn(xdot.v) * sgn(w.v)).add(&self.gamma);
        let wdot = xdot.sub(&xdot.mul(&k.mul(&wmu)));
        (dxs, wdot)
    }
}

/// The simulated output `y_k = w(t_k)` and its Jacobian.
#[derive(Debug, Clone, PartialEq)]
pub struct Sensitivity {
    /// `y_k`, one per input sample.
    pub y: Vec<f64>,
    /// `d y_k / d theta_i`, row-major `(len(y), n_params)`.
    pub jac: Vec<f64>,
    /// Number of parameters `m + n + 6`.
    pub n_params: usize,
}

/// Number of parameters of the layout for numerator degree `m` and denominator degree `n`.
pub fn n_params(m: usize, n: usize) -> usize {
    m + n + 6
}

/// Checks the degrees, the parameter vector and the grid.
///
/// Errors: [`CoreError::InvalidParameter`], [`CoreError::NonFinite`],
/// [`CoreError::InsufficientData`].
fn check(m: usize, n: usize, theta: &[f64], u: &[f64], dt: f64, substeps: usize) -> Result<()> {
    if n > MAX_ORDER || m > n {
        return Err(CoreError::InvalidParameter(format!(
            "the degrees must satisfy m <= n <= {MAX_ORDER}, got m = {m}, n = {n}"
        )));
    }
    if theta.len() != n_params(m, n) {
        return Err(CoreError::InvalidParameter(format!(
            "theta must hold m + n + 6 = {} values, got {}",
            n_params(m, n),
            theta.len()
        )));
    }
    all_finite("theta", theta)?;
    all_finite("u", u)?;
    if u.len() < 2 {
        return Err(CoreError::InsufficientData(format!(
            "a sampled input needs at least 2 samples, got {}",
            u.len()
        )));
    }
    let dt = crate::simulate::check_dt(dt)?;
    let _ = dt;
    if substeps < 1 {
        return Err(CoreError::InvalidParameter(format!(
            "substeps = {substeps} must be >= 1"
        )));
    }
    let base = m + 1 + n;
    if theta[base] < 0.0 {
        return Err(CoreError::InvalidParameter(format!(
            "the delay = {} s must be >= 0",
            theta[base]
        )));
    }
    if theta[base + 3] < 1.0 {
        return Err(CoreError::InvalidParameter(format!(
            "mu = {} must be >= 1",
            theta[base + 3]
        )));
    }
    Ok(())
}

/// Simulates the cascade on the samples `u` (grid `k dt`) from rest (`xs = 0`, `w = w0`) and
/// returns `y = w` on the same grid with its exact Jacobian (module docs).
///
/// A model that blows up (an unstable G tried by a search, an overflowing Bouc-Wen state) returns
/// non-finite values rather than an error: the caller's search rejects that step.
///
/// Errors: bad degrees, parameters or grid ([`check`]); [`CoreError::Cancelled`]-like errors of
/// [`crate::cancel::checkpoint`] on Ctrl-C; [`crate::budget::check_simulation`].
pub fn simulate_sensitivities(
    m: usize,
    n: usize,
    theta: &[f64],
    u: &[f64],
    dt: f64,
    substeps: usize,
) -> Result<Sensitivity> {
    check(m, n, theta, u, dt, substeps)?;
    crate::budget::check_simulation(u.len(), substeps)?;
    let np = n_params(m, n);
    let model = Model::new(m, n, theta);
    let src = Hermite::new(u, dt);
    let n_samples = u.len();
    let mut y = Vec::new();
    let mut jac = Vec::new();
    y.try_reserve_exact(n_samples)
        .and_then(|_| jac.try_reserve_exact(n_samples * np))
        .map_err(|_| {
            CoreError::InvalidParameter(format!(
                "{n_samples} samples x {np} parameters are too many to allocate"
            ))
        })?;
    let h = dt / substeps as f64;
    let half_h = 0.5 * h;
    let h_sixth = h / 6.0;
    let mut xs = [Dual::constant(0.0); MAX_ORDER];
    let mut w = model.w0;
    let check_mask = (crate::cancel::CHECK_EVERY_STEPS / substeps)
        .max(1)
        .next_power_of_two()
        - 1;
    for k in 0..n_samples {
        y.push(w.v);
        jac.extend_from_slice(&w.d[..np]);
        if k + 1 == n_samples {
            break;
        }
        if k & check_mask == 0 {
            crate::cancel::checkpoint()?;
        }
        let t = k as f64 * dt;
        for s in 0..substeps {
            let ts = t + s as f64 * h;
            let start = model.input(&src, ts);
            let mid = model.input(&src, ts + half_h);
            let end = model.input(&src, ts + h);
            let (k1, kw1) = model.rhs(&xs, &w, &start);
            let (k2, kw2) = model.rhs(&stage(&xs, half_h, &k1, n), &w.axpy(half_h, &kw1), &mid);
            let (k3, kw3) = model.rhs(&stage(&xs, half_h, &k2, n), &w.axpy(half_h, &kw2), &mid);
            let (k4, kw4) = model.rhs(&stage(&xs, h, &k3, n), &w.axpy(h, &kw3), &end);
            for j in 0..n {
                let incr = k1[j]
                    .add(&k2[j].scale(2.0))
                    .add(&k3[j].scale(2.0))
                    .add(&k4[j]);
                xs[j] = xs[j].axpy(h_sixth, &incr);
            }
            let incr = kw1.add(&kw2.scale(2.0)).add(&kw3.scale(2.0)).add(&kw4);
            w = w.axpy(h_sixth, &incr);
        }
    }
    Ok(Sensitivity {
        y,
        jac,
        n_params: np,
    })
}

/// `xs + hk k` on the first `n` components.
#[inline(always)]
fn stage(xs: &[Dual; MAX_ORDER], hk: f64, k: &[Dual; MAX_ORDER], n: usize) -> [Dual; MAX_ORDER] {
    let mut out = *xs;
    for j in 0..n {
        out[j] = xs[j].axpy(hk, &k[j]);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn theta() -> Vec<f64> {
        // G = (0.5 s + 40) / (s^2 + 8 s + 400), tau = 0.0137, beta 0.8, gamma 0.2, mu 1.6, w0 0.
        vec![0.5, 40.0, 8.0, 400.0, 0.0137, 0.8, 0.2, 1.6, 0.0]
    }

    fn input(n: usize, dt: f64) -> Vec<f64> {
        (0..n)
            .map(|k| {
                let t = k as f64 * dt;
                (13.0 * t).sin() + 0.6 * (37.0 * t + 1.0).sin() + 0.3 * (71.0 * t).cos()
            })
            .collect()
    }

    #[test]
    fn jacobian_matches_central_differences() {
        let (dt, n_s) = (2e-3, 400);
        let u = input(n_s, dt);
        let th = theta();
        let sim = simulate_sensitivities(1, 2, &th, &u, dt, 2).unwrap();
        for i in 0..th.len() {
            let step = 1e-6 * th[i].abs().max(1e-2);
            let mut hi = th.clone();
            let mut lo = th.clone();
            hi[i] += step;
            lo[i] -= step;
            let yh = simulate_sensitivities(1, 2, &hi, &u, dt, 2).unwrap().y;
            let yl = simulate_sensitivities(1, 2, &lo, &u, dt, 2).unwrap().y;
            let mut worst = 0.0_f64;
            let mut size = 0.0_f64;
            for k in 0..n_s {
                let fd = (yh[k] - yl[k]) / (2.0 * step);
                let an = sim.jac[k * sim.n_params + i];
                worst = worst.max((fd - an).abs());
                size = size.max(an.abs());
            }
            assert!(size > 0.0, "parameter {i} does not move the output");
            assert!(
                worst <= 1e-5 * size,
                "parameter {i}: {worst} against {size}"
            );
        }
    }

    #[test]
    fn matches_the_plain_simulator() {
        let (dt, n_s) = (2e-3, 300);
        let u = input(n_s, dt);
        let th = theta();
        let sim = simulate_sensitivities(1, 2, &th, &u, dt, 3).unwrap();
        let tf =
            crate::linear::TransferFunction::new(&[0.5, 40.0], &[1.0, 8.0, 400.0], 0.0137).unwrap();
        let bw = crate::bouc_wen::BoucWen::new(1.0, 0.8, 0.2, 1.6, 0.0).unwrap();
        let plain = crate::simulate::simulate(
            &tf,
            &bw,
            crate::simulate::Input::Sampled { u: &u },
            dt,
            n_s,
            3,
        )
        .unwrap();
        for k in 0..n_s {
            assert!((plain.w[k] - sim.y[k]).abs() <= 1e-12 * (1.0 + plain.w[k].abs()));
        }
    }

    #[test]
    fn bad_input_is_named() {
        let u = input(10, 1e-3);
        assert!(matches!(
            simulate_sensitivities(3, 2, &theta(), &u, 1e-3, 1),
            Err(CoreError::InvalidParameter(_))
        ));
        let mut th = theta();
        th[4] = -1.0;
        assert!(matches!(
            simulate_sensitivities(1, 2, &th, &u, 1e-3, 1),
            Err(CoreError::InvalidParameter(_))
        ));
        th = theta();
        th[0] = f64::NAN;
        assert!(matches!(
            simulate_sensitivities(1, 2, &th, &u, 1e-3, 1),
            Err(CoreError::NonFinite(_))
        ));
        assert!(matches!(
            simulate_sensitivities(1, 2, &theta(), &u[..1], 1e-3, 1),
            Err(CoreError::InsufficientData(_))
        ));
    }
}
