//! Simulation of the Wiener system (1a)-(1b) of the seed paper: `x = g * u` through the
//! controllable canonical realisation of `G(s)`, then the Bouc-Wen hysteresis (2a), integrated
//! together by classical fourth-order Runge-Kutta (`docs/design.md` §1).
//!
//! State `z = [xs (n), w]`, `f(t, z)`: `xsdot = A xs + B v`, `xdot = C xsdot + D vdot`,
//! `wdot` from (2a), with `v(t) = u(t - tau)` (0 before the delay has elapsed).
//!
//! The step is written for speed: no allocation per step, the companion structure makes `A xs`
//! O(n), one `powf` per stage, the input is evaluated once for the two mid-step stages, and a
//! value is reused when a stage time repeats bitwise.
//!
//! Low orders (static gain, first and second order; up to [`FIXED_MAX_ORDER`]) run on fixed-size
//! stack arrays, so the state loops unroll and vanish for a static gain, in the operation order of
//! the generic path (the results are bitwise those of the generic path: an identification of
//! exactly negated data must stay exactly symmetric). Evaluating the sine input by angle addition
//! and `|w|^2` as `w * w` were tried (issue #8) and bought a few percent at most: the step is bound
//! by its four `powf`, as the C peer's (`benches/rk4_peer.c`).
//!
//! ## Reference
//! *Wiener System Identification in Presence of Hysteresis Nonlinearity*, the seed paper whose
//! equation numbers are cited; for the Bouc-Wen properties it relies on (Propositions 1-2):
//! F. Ikhouane and J. Rodellar, *Systems with Hysteresis: Analysis, Identification and Control
//! using the Bouc-Wen Model*, Wiley, 2007.

use crate::bouc_wen::BoucWen;
use crate::error::{all_finite, finite, CoreError, Result};
use crate::hermite::Hermite;
use crate::linear::{Companion, TransferFunction};

// The augmented model's integrator (design.md §9.4), kept apart so that this plain path is untouched.
mod on_x;
mod rk4;
mod with_terms;
pub use on_x::OnXValues;
pub use with_terms::{simulate_with_terms, TermSimulation, TermValues};

/// Input signal `u(t)`, `t >= 0` (`u = 0` before).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Input<'a> {
    /// `u(t) = amplitude cos(omega t)`; `omega` in rad/s.
    Sine {
        /// Amplitude `U` (units of `u`).
        amplitude: f64,
        /// Angular frequency (rad/s), `> 0`.
        omega: f64,
    },
    /// Samples `u_k = u(k dt)` on the output grid (length >= 2), interpolated by cubic Hermite
    /// with Catmull-Rom slopes; after the last sample `u` holds the last value (slope 0).
    Sampled {
        /// The samples.
        u: &'a [f64],
    },
}

impl Input<'_> {
    /// Checks the input alone (the sampled interpolant also needs `dt`, checked by
    /// [`simulate`]).
    ///
    /// Errors: [`CoreError::NonFinite`] for NaN/inf, [`CoreError::InvalidParameter`] for
    /// `omega <= 0`, [`CoreError::InsufficientData`] for fewer than 2 samples.
    pub fn validate(&self) -> Result<()> {
        match *self {
            Input::Sine { amplitude, omega } => {
                finite("amplitude", amplitude)?;
                finite("omega", omega)?;
                if omega <= 0.0 {
                    return Err(CoreError::InvalidParameter(format!(
                        "omega = {omega} rad/s must be > 0"
                    )));
                }
                Ok(())
            }
            Input::Sampled { u } => {
                all_finite("u", u)?;
                if u.len() < 2 {
                    return Err(CoreError::InsufficientData(format!(
                        "a sampled input needs at least 2 samples, got {}",
                        u.len()
                    )));
                }
                Ok(())
            }
        }
    }
}

/// Simulated inner signals on the output grid `t_k = k dt`.
#[derive(Debug, Clone, PartialEq)]
pub struct Simulation {
    /// `x_k = C xs(t_k) + D v(t_k)`, length `n_samples`.
    pub x: Vec<f64>,
    /// `w_k = w(t_k)`, length `n_samples`.
    pub w: Vec<f64>,
}

/// Number of RK4 steps [`simulate`] takes: `(n_samples - 1) substeps`.
pub fn rk4_step_count(n_samples: usize, substeps: usize) -> usize {
    n_samples.saturating_sub(1).saturating_mul(substeps)
}

/// Simulates the Wiener system `tf` -> `bw` driven by `input` (RK4, `docs/design.md` §1).
///
/// `dt` (s) is the output grid step, `n_samples >= 1` the number of output samples (`t_k = k dt`,
/// k = 0..n_samples-1), `substeps >= 1` the RK4 steps per sample (`h = dt/substeps`). The state
/// starts at rest: `xs(0) = 0`, `w(0) = w0`. A sampled input shares the output grid; past its end
/// it holds its last value.
///
/// Returns `x` and `w`, each of length `n_samples`.
///
/// Errors: [`CoreError::NonFinite`], [`CoreError::InvalidParameter`] (`dt <= 0`, `substeps < 1`,
/// `n_samples < 1`, `omega <= 0`, output too large to allocate), [`CoreError::InsufficientData`]
/// (fewer than 2 input samples).
pub fn simulate(
    tf: &TransferFunction,
    bw: &BoucWen,
    input: Input<'_>,
    dt: f64,
    n_samples: usize,
    substeps: usize,
) -> Result<Simulation> {
    input.validate()?;
    let dt = check_dt(dt)?;
    if substeps < 1 {
        return Err(CoreError::InvalidParameter(format!(
            "substeps = {substeps} must be >= 1"
        )));
    }
    if n_samples < 1 {
        return Err(CoreError::InvalidParameter(format!(
            "n_samples = {n_samples} must be >= 1"
        )));
    }
    crate::budget::check_simulation(n_samples, substeps)?;
    let mut out = Simulation {
        x: try_zeros(n_samples)?,
        w: try_zeros(n_samples)?,
    };
    let comp = tf.realize();
    let grid = Grid {
        dt,
        n_samples,
        substeps,
        delay: tf.delay(),
    };
    match input {
        Input::Sine { amplitude, omega } => {
            let src = Sine {
                amplitude,
                omega,
                neg_amplitude_omega: -amplitude * omega,
            };
            let mut stages = CachedStages::new(&src, grid.delay);
            integrate_any(&comp, bw, &mut stages, &grid, &mut out);
        }
        Input::Sampled { u } => {
            let src = Hermite::new(u, dt);
            let mut stages = CachedStages::new(&src, grid.delay);
            integrate_any(&comp, bw, &mut stages, &grid, &mut out);
        }
    }
    crate::cancel::checkpoint()?;
    check_blow_up(tf, bw, dt, &out)?;
    Ok(out)
}

/// A non-finite `x` or `w` is the model's blow-up, not the caller's data (the inputs were checked
/// finite): name the parameters and where it happened.
///
/// Errors: [`CoreError::NonFinite`].
fn check_blow_up(tf: &TransferFunction, bw: &BoucWen, dt: f64, out: &Simulation) -> Result<()> {
    let bad = |v: &[f64]| v.iter().position(|v| !v.is_finite());
    let (signal, k) = match (bad(&out.x), bad(&out.w)) {
        (None, None) => return Ok(()),
        (Some(i), Some(j)) if j < i => ("w", j),
        (Some(i), _) => ("x", i),
        (None, Some(j)) => ("w", j),
    };
    Err(CoreError::NonFinite(format!(
        "the simulation blew up: {signal} is not finite from sample {k} (t = {:.6e} s) on; the \
         model parameters (alpha = {:e}, beta = {:e}, gamma = {:e}, mu = {}, w0 = {:e}, G = \
         {:?}/{:?}) or the input level make the Bouc-Wen state overflow; use parameters of \
         moderate size, a smaller amplitude or a finer step (substeps)",
        k as f64 * dt,
        bw.alpha(),
        bw.beta(),
        bw.gamma(),
        bw.mu(),
        bw.w0(),
        tf.num(),
        tf.den(),
    )))
}

/// `Ok(dt)` for a finite time step `dt > 0` (s).
///
/// Errors: [`CoreError::NonFinite`], [`CoreError::InvalidParameter`].
pub fn check_dt(dt: f64) -> Result<f64> {
    let dt = finite("dt", dt)?;
    if dt <= 0.0 {
        return Err(CoreError::InvalidParameter(format!(
            "dt = {dt} s must be > 0"
        )));
    }
    Ok(dt)
}

/// A zeroed `Vec` of length `n`, or an error (rather than an abort) when it cannot be allocated.
fn try_zeros(n: usize) -> Result<Vec<f64>> {
    let mut v = Vec::new();
    v.try_reserve_exact(n).map_err(|_| {
        CoreError::InvalidParameter(format!(
            "n_samples = {n} is too large to allocate; simulate a shorter record"
        ))
    })?;
    v.resize(n, 0.0);
    Ok(v)
}

/// Time grid of a simulation.
struct Grid {
    dt: f64,
    n_samples: usize,
    substeps: usize,
    delay: f64,
}

/// Undelayed input `(u(tau), udot(tau))` for `tau >= 0`.
trait Source {
    fn at(&self, tau: f64) -> (f64, f64);
}

/// The delayed input `(v, vdot)` at the stage times of one output sample.
///
/// The integrator calls [`Stages::sample`] once per output sample `k` (time `t = k dt`), then
/// [`Stages::stage`] for stage `j` in `0..=2 substeps` at the time `t + j h / 2` (as computed by
/// the integrator: `t + s h`, `+ h/2`, `+ h`).
trait Stages {
    /// Moves to the output sample at time `t`; returns `v(t)` (for `x = C xs + D v`).
    fn sample(&mut self, t: f64) -> f64;
    /// `(v, vdot)` at stage `j` of the current sample, whose time is `time`.
    fn stage(&mut self, j: usize, time: f64) -> (f64, f64);
}

/// Any [`Source`], evaluated at every stage time, with a one-entry cache keyed on the exact stage
/// time: a step's last stage `ts + h` often rounds to the next step's first `t + (s+1) h` (or the
/// next sample's `k dt`), and reusing the value only when the times are bitwise equal changes no
/// result while saving an evaluation.
struct CachedStages<'s, S: Source> {
    src: &'s S,
    delay: f64,
    cached: (f64, (f64, f64)),
}

impl<'s, S: Source> CachedStages<'s, S> {
    fn new(src: &'s S, delay: f64) -> Self {
        Self {
            src,
            delay,
            cached: (f64::NAN, (0.0, 0.0)),
        }
    }

    #[inline(always)]
    fn input(&mut self, t: f64) -> (f64, f64) {
        if t == self.cached.0 {
            return self.cached.1;
        }
        let tau = t - self.delay;
        let value = if tau < 0.0 {
            (0.0, 0.0)
        } else {
            self.src.at(tau)
        };
        self.cached = (t, value);
        value
    }
}

impl<S: Source> Stages for CachedStages<'_, S> {
    #[inline(always)]
    fn sample(&mut self, t: f64) -> f64 {
        self.input(t).0
    }
    #[inline(always)]
    fn stage(&mut self, _j: usize, time: f64) -> (f64, f64) {
        self.input(time)
    }
}

struct Sine {
    amplitude: f64,
    omega: f64,
    /// `-U omega`, hoisted out of the stage evaluations.
    neg_amplitude_omega: f64,
}

impl Source for Sine {
    #[inline(always)]
    fn at(&self, tau: f64) -> (f64, f64) {
        let arg = self.omega * tau;
        (
            self.amplitude * arg.cos(),
            self.neg_amplitude_omega * arg.sin(),
        )
    }
}

impl Source for Hermite<'_> {
    #[inline(always)]
    fn at(&self, tau: f64) -> (f64, f64) {
        self.value_slope(tau)
    }
}

/// The linear part (companion form) and the hysteresis.
struct System<'a> {
    comp: &'a Companion,
    bw: &'a BoucWen,
}

impl System<'_> {
    /// `f(t, z)` with the input already evaluated: writes `xsdot` into `dxs`, returns `wdot`.
    #[inline(always)]
    fn rhs(&self, xs: &[f64], w: f64, (v, vdot): (f64, f64), dxs: &mut [f64]) -> f64 {
        self.comp.state_derivative(xs, v, dxs);
        let xdot = self.comp.output_row(dxs) + self.comp.d * vdot;
        self.bw.wdot(xdot, w)
    }

    /// `x = C xs + D v`.
    #[inline(always)]
    fn output(&self, xs: &[f64], v: f64) -> f64 {
        self.comp.output_row(xs) + self.comp.d * v
    }
}

/// The mask on the sample index of the integrators' Ctrl-C check, about every
/// `CHECK_EVERY_STEPS` RK4 steps: a power of two minus one, so the test is a mask, not a division.
fn cancel_mask(substeps: usize) -> usize {
    (crate::cancel::CHECK_EVERY_STEPS / substeps)
        .max(1)
        .next_power_of_two()
        - 1
}

/// Largest order run on fixed-size arrays by [`integrate_fixed`].
const FIXED_MAX_ORDER: usize = 4;

/// RK4 from rest over the whole grid, on fixed-size arrays for orders up to [`FIXED_MAX_ORDER`].
fn integrate_any<I: Stages>(
    comp: &Companion,
    bw: &BoucWen,
    src: &mut I,
    grid: &Grid,
    out: &mut Simulation,
) {
    // The arms below go up to FIXED_MAX_ORDER.
    const _: () = assert!(FIXED_MAX_ORDER == 4);
    match comp.order() {
        0 => integrate_fixed::<0, I>(comp, bw, src, grid, out),
        1 => integrate_fixed::<1, I>(comp, bw, src, grid, out),
        2 => integrate_fixed::<2, I>(comp, bw, src, grid, out),
        3 => integrate_fixed::<3, I>(comp, bw, src, grid, out),
        4 => integrate_fixed::<4, I>(comp, bw, src, grid, out),
        _ => integrate(comp, bw, src, grid, out),
    }
}

/// The companion form of order `N` and the hysteresis, by value, for [`integrate_fixed`].
struct Fixed<const N: usize> {
    a: [f64; N],
    c: [f64; N],
    d: f64,
    alpha: f64,
    beta: f64,
    gamma: f64,
    mu: f64,
}

impl<const N: usize> Fixed<N> {
    fn new(comp: &Companion, bw: &BoucWen) -> Self {
        let mut a = [0.0; N];
        let mut c = [0.0; N];
        a.copy_from_slice(&comp.a);
        c.copy_from_slice(&comp.c);
        Self {
            a,
            c,
            d: comp.d,
            alpha: bw.alpha(),
            beta: bw.beta(),
            gamma: bw.gamma(),
            mu: bw.mu(),
        }
    }

    /// `f(t, z)` with the input evaluated: `(xsdot, wdot)`, in the operation order of
    /// [`Companion::state_derivative`], [`Companion::output_row`] and [`BoucWen::wdot`].
    #[inline(always)]
    fn rhs(&self, xs: &[f64; N], w: f64, (v, vdot): (f64, f64)) -> ([f64; N], f64) {
        let mut dxs = [0.0; N];
        let mut xdot = 0.0;
        if N > 0 {
            let mut acc = 0.0;
            for (ai, xi) in self.a.iter().zip(xs) {
                acc += ai * xi;
            }
            dxs[0] = -acc + v;
            dxs[1..].copy_from_slice(&xs[..N - 1]);
            for (ci, di) in self.c.iter().zip(&dxs) {
                xdot += ci * di;
            }
        }
        xdot += self.d * vdot;
        let wmu = w.abs().powf(self.mu);
        let wdot = self.alpha * xdot
            - self.beta * xdot.abs() * crate::bouc_wen::sgn(w) * wmu
            - self.gamma * xdot * wmu;
        (dxs, wdot)
    }

    #[inline(always)]
    fn output(&self, xs: &[f64; N], v: f64) -> f64 {
        let mut acc = 0.0;
        for (ci, xi) in self.c.iter().zip(xs) {
            acc += ci * xi;
        }
        acc + self.d * v
    }
}

/// `xs + k * hk` for fixed-size states.
#[inline(always)]
fn axpy_fixed<const N: usize>(xs: &[f64; N], hk: f64, k: &[f64; N]) -> [f64; N] {
    let mut out = [0.0; N];
    for ((o, x), ki) in out.iter_mut().zip(xs).zip(k) {
        *o = x + hk * ki;
    }
    out
}

/// [`integrate`] for a state of compile-time order `N` (same steps and operation order).
fn integrate_fixed<const N: usize, I: Stages>(
    comp: &Companion,
    bw: &BoucWen,
    src: &mut I,
    grid: &Grid,
    out: &mut Simulation,
) {
    let sys = Fixed::<N>::new(comp, bw);
    let dt = grid.dt;
    let rk4::Steps { h, half_h, h_sixth } = rk4::Steps::new(dt, grid.substeps);
    let mut xs = [0.0; N];
    let mut w = bw.w0();
    let last = grid.n_samples - 1;
    let check_mask = cancel_mask(grid.substeps);
    for (k, (xo, wo)) in out.x.iter_mut().zip(out.w.iter_mut()).enumerate() {
        let t = k as f64 * dt;
        *xo = sys.output(&xs, src.sample(t));
        *wo = w;
        if k == last || (k & check_mask == 0 && crate::cancel::requested()) {
            break;
        }
        for s in 0..grid.substeps {
            let ts = t + s as f64 * h;
            let (k1, kw1) = sys.rhs(&xs, w, src.stage(2 * s, ts));
            // Stages 2 and 3 share the time t + h/2: evaluate the input once.
            let mid = src.stage(2 * s + 1, ts + half_h);
            let (k2, kw2) = sys.rhs(&axpy_fixed(&xs, half_h, &k1), w + half_h * kw1, mid);
            let (k3, kw3) = sys.rhs(&axpy_fixed(&xs, half_h, &k2), w + half_h * kw2, mid);
            let end = src.stage(2 * s + 2, ts + h);
            let (k4, kw4) = sys.rhs(&axpy_fixed(&xs, h, &k3), w + h * kw3, end);
            for ((((x, a), b), c), d) in xs.iter_mut().zip(&k1).zip(&k2).zip(&k3).zip(&k4) {
                *x += h_sixth * (a + 2.0 * b + 2.0 * c + d);
            }
            w += h_sixth * (kw1 + 2.0 * kw2 + 2.0 * kw3 + kw4);
        }
    }
}

/// RK4 from rest over the whole grid, writing the samples into `out` (any order).
///
/// The five state-sized buffers are allocated once; the loops run over them with iterators (no
/// bounds checks).
fn integrate<I: Stages>(
    comp: &Companion,
    bw: &BoucWen,
    src: &mut I,
    grid: &Grid,
    out: &mut Simulation,
) {
    let n = comp.order();
    let sys = System { comp, bw };
    let dt = grid.dt;
    let rk4::Steps { h, half_h, h_sixth } = rk4::Steps::new(dt, grid.substeps);

    let mut xs = vec![0.0; n];
    let mut w = bw.w0();
    let mut sc = rk4::Scratch::new(n);
    let last = grid.n_samples - 1;
    let check_mask = cancel_mask(grid.substeps);
    for (k, (xo, wo)) in out.x.iter_mut().zip(out.w.iter_mut()).enumerate() {
        let t = k as f64 * dt;
        *xo = sys.output(&xs, src.sample(t));
        *wo = w;
        if k == last || (k & check_mask == 0 && crate::cancel::requested()) {
            break;
        }
        for s in 0..grid.substeps {
            let ts = t + s as f64 * h;
            let kw1 = sys.rhs(&xs, w, src.stage(2 * s, ts), &mut sc.k1);
            // Stages 2 and 3 share the time t + h/2: evaluate the input once.
            let mid = src.stage(2 * s + 1, ts + half_h);
            rk4::axpy(&mut sc.tmp, &xs, half_h, &sc.k1);
            let kw2 = sys.rhs(&sc.tmp, w + half_h * kw1, mid, &mut sc.k2);
            rk4::axpy(&mut sc.tmp, &xs, half_h, &sc.k2);
            let kw3 = sys.rhs(&sc.tmp, w + half_h * kw2, mid, &mut sc.k3);
            rk4::axpy(&mut sc.tmp, &xs, h, &sc.k3);
            let end = src.stage(2 * s + 2, ts + h);
            let kw4 = sys.rhs(&sc.tmp, w + h * kw3, end, &mut sc.k4);
            sc.advance(&mut xs, h_sixth);
            w += h_sixth * (kw1 + 2.0 * kw2 + 2.0 * kw3 + kw4);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn sine(amplitude: f64, omega: f64) -> Input<'static> {
        Input::Sine { amplitude, omega }
    }

    /// `alpha = 1, beta = gamma = 0`: `w = x + w0 - x(0)`.
    fn linear_bw(w0: f64) -> BoucWen {
        BoucWen::new_unchecked(1.0, 0.0, 0.0, 2.0, w0)
    }

    /// Exact response of `1/(s+1)` to `U cos(omega t)` from rest.
    fn first_order_exact(u: f64, omega: f64, t: f64) -> f64 {
        u / (1.0 + omega * omega) * ((omega * t).cos() + omega * (omega * t).sin() - (-t).exp())
    }

    #[test]
    fn first_order_converges_to_steady_state_sine() {
        // G = e^{-0.3 s}/(s + 1): x -> U |G| cos(omega t - phi), phi = atan(omega) + 0.3 omega.
        let (u, omega, tau) = (1.7, 2.0, 0.3);
        let tf = TransferFunction::new(&[1.0], &[1.0, 1.0], tau).unwrap();
        let bw = BoucWen::new(1.0, 0.5, 0.1, 2.0, 0.0).unwrap();
        let dt = 0.01;
        let sim = simulate(&tf, &bw, sine(u, omega), dt, 3001, 4).unwrap();
        let (re, im) = tf.freq_response(omega);
        let (gain, phi) = (re.hypot(im), -im.atan2(re));
        assert_relative_eq!(phi, omega.atan() + omega * tau, max_relative = 1e-12);
        for k in 2500..3001 {
            let t = k as f64 * dt;
            let expected = u * gain * (omega * t - phi).cos();
            assert_relative_eq!(sim.x[k], expected, epsilon = 1e-9);
        }
    }

    #[test]
    fn rk4_error_shrinks_sixteenfold_when_step_halves() {
        let (u, omega) = (1.0, 2.0);
        let tf = TransferFunction::new(&[1.0], &[1.0, 1.0], 0.0).unwrap();
        let dt = 0.25;
        let n = 41;
        let errors: Vec<f64> = [1, 2, 4]
            .iter()
            .map(|&sub| {
                let sim = simulate(&tf, &linear_bw(0.4), sine(u, omega), dt, n, sub).unwrap();
                // alpha = 1, beta = gamma = 0 and D = 0: w - C xs is invariant under RK4.
                for k in 0..n {
                    assert_relative_eq!(sim.w[k], sim.x[k] + 0.4 - sim.x[0], epsilon = 1e-14);
                }
                (0..n)
                    .map(|k| (sim.x[k] - first_order_exact(u, omega, k as f64 * dt)).abs())
                    .fold(0.0, f64::max)
            })
            .collect();
        for pair in errors.windows(2) {
            let ratio = pair[0] / pair[1];
            assert!((13.0..19.0).contains(&ratio), "errors {errors:?}");
        }
    }

    #[test]
    fn seventh_order_reaches_its_frequency_response() {
        let bw = BoucWen::new(1.0, 0.8, 0.2, 1.5, 0.1).unwrap();
        let den7 = [1.0, 7.0, 21.0, 35.0, 35.0, 21.0, 7.0, 1.0]; // (s+1)^7
        let tf7 = TransferFunction::new(&[1.0, 0.5], &den7, 0.2).unwrap();
        let (u, omega) = (1.0, 0.8);
        let sim = simulate(&tf7, &bw, sine(u, omega), 0.05, 2001, 2).unwrap();
        let (re, im) = tf7.freq_response(omega);
        for k in 1900..2001 {
            let t = k as f64 * 0.05;
            let expected = u * (re * (omega * t).cos() - im * (omega * t).sin());
            assert_relative_eq!(sim.x[k], expected, epsilon = 1e-6);
        }
    }

    #[test]
    fn static_gain_with_delay_is_a_shifted_cosine() {
        let (u, omega, tau) = (0.9, 3.0, 0.37);
        let tf = TransferFunction::new(&[2.0], &[1.0], tau).unwrap();
        let sim = simulate(&tf, &linear_bw(0.0), sine(u, omega), 0.01, 500, 2).unwrap();
        for (k, &x) in sim.x.iter().enumerate() {
            let t = k as f64 * 0.01;
            let expected = if t < tau {
                0.0
            } else {
                2.0 * u * (omega * (t - tau)).cos()
            };
            assert_relative_eq!(x, expected, epsilon = 1e-15, max_relative = 1e-14);
        }
    }

    #[test]
    fn sampled_input_is_catmull_rom() {
        let dt = 0.1;
        // A quadratic is reproduced exactly in the interior (central slopes are exact), and a
        // half-step delay puts every output in the middle of an interval.
        let u: Vec<f64> = (0..50).map(|k| (k as f64 * dt).powi(2) - 0.5).collect();
        let tf = TransferFunction::new(&[1.0], &[1.0], 0.5 * dt).unwrap();
        let bw = linear_bw(0.25);
        let sim = simulate(&tf, &bw, Input::Sampled { u: &u }, dt, 60, 3).unwrap();
        for k in 2..49 {
            let tau = k as f64 * dt - 0.5 * dt;
            assert_relative_eq!(sim.x[k], tau * tau - 0.5, epsilon = 1e-13);
        }
        assert_eq!(sim.x[0], 0.0);
        // Past the end the input holds its last value.
        for k in 51..60 {
            assert_eq!(sim.x[k], u[49]);
        }

        // A ramp is exact everywhere, and w integrates its constant slope exactly.
        let ramp: Vec<f64> = (0..20).map(|k| 3.0 * k as f64 * dt + 1.0).collect();
        let tf = TransferFunction::new(&[1.0], &[1.0], 0.0).unwrap();
        let sim = simulate(&tf, &bw, Input::Sampled { u: &ramp }, dt, 20, 2).unwrap();
        for k in 0..19 {
            assert_relative_eq!(sim.x[k], ramp[k], max_relative = 1e-14);
            assert_relative_eq!(sim.w[k], 0.25 + ramp[k] - ramp[0], max_relative = 1e-13);
        }
        // The last RK4 stage lands on the last sample, where the input already holds (slope 0):
        // the final step misses that stage's h/6 share of the slope.
        let h = dt / 2.0;
        assert_relative_eq!(sim.x[19], ramp[19], max_relative = 1e-14);
        assert_relative_eq!(
            sim.w[19],
            0.25 + ramp[19] - ramp[0] - h / 6.0 * 3.0,
            max_relative = 1e-13
        );

        // A finely sampled sine matches the analytic sine input.
        let (amp, omega, dt) = (1.2, 2.0, 0.002);
        let us: Vec<f64> = (0..3000)
            .map(|k| amp * (omega * k as f64 * dt).cos())
            .collect();
        let tf = TransferFunction::new(&[1.0], &[0.5, 1.0], 0.0).unwrap();
        let bw = BoucWen::new(1.0, 1.0, 0.5, 1.5, 0.0).unwrap();
        let a = simulate(&tf, &bw, Input::Sampled { u: &us }, dt, 3000, 1).unwrap();
        let b = simulate(&tf, &bw, sine(amp, omega), dt, 3000, 1).unwrap();
        for k in 0..3000 {
            assert_relative_eq!(a.x[k], b.x[k], epsilon = 1e-7);
            assert_relative_eq!(a.w[k], b.w[k], epsilon = 1e-7);
        }
    }

    #[test]
    fn validation() {
        let tf = TransferFunction::new(&[1.0], &[1.0, 1.0], 0.0).unwrap();
        let bw = BoucWen::new(1.0, 1.0, 0.0, 2.0, 0.0).unwrap();
        let inv = |r: Result<Simulation>, text: &str| {
            let e = r.unwrap_err();
            assert!(matches!(e, CoreError::InvalidParameter(_)), "{e}");
            assert!(e.to_string().contains(text), "{e}");
        };
        inv(simulate(&tf, &bw, sine(1.0, 1.0), 0.0, 10, 1), "dt = 0");
        inv(
            simulate(&tf, &bw, sine(1.0, 1.0), 0.1, 10, 0),
            "substeps = 0",
        );
        inv(
            simulate(&tf, &bw, sine(1.0, 1.0), 0.1, 0, 1),
            "n_samples = 0",
        );
        inv(
            simulate(&tf, &bw, sine(1.0, -1.0), 0.1, 10, 1),
            "omega = -1",
        );
        // Refused by the budget before any allocation (rust/budget.rs).
        let e = simulate(&tf, &bw, sine(1.0, 1.0), 0.1, usize::MAX / 2, 1).unwrap_err();
        assert!(matches!(e, CoreError::BudgetExceeded(_)), "{e}");
        let e = simulate(&tf, &bw, sine(f64::NAN, 1.0), 0.1, 10, 1).unwrap_err();
        assert!(matches!(e, CoreError::NonFinite(_)), "{e}");
        let e = simulate(&tf, &bw, sine(1.0, 1.0), f64::INFINITY, 10, 1).unwrap_err();
        assert!(matches!(e, CoreError::NonFinite(_)), "{e}");
        let e = simulate(&tf, &bw, Input::Sampled { u: &[1.0] }, 0.1, 1, 1).unwrap_err();
        assert!(matches!(e, CoreError::InsufficientData(_)), "{e}");
        let e = simulate(
            &tf,
            &bw,
            Input::Sampled {
                u: &[1.0, f64::NAN],
            },
            0.1,
            2,
            1,
        )
        .unwrap_err();
        assert!(matches!(e, CoreError::NonFinite(_)), "{e}");
        assert_eq!(rk4_step_count(11, 4), 40);
        let one = simulate(&tf, &bw, sine(1.0, 1.0), 0.1, 1, 1).unwrap();
        assert_eq!((one.x, one.w), (vec![0.0], vec![0.0]));
    }

    #[test]
    fn a_blow_up_names_the_parameters_not_the_data() {
        let tf = TransferFunction::new(&[1.0], &[1.0, 1.0], 0.0).unwrap();
        let bw = BoucWen::new(1.0, 1e300, 0.1, 2.0, 0.0).unwrap();
        let e = simulate(&tf, &bw, sine(1.0, 1.0), 0.1, 50, 4).unwrap_err();
        assert!(matches!(e, CoreError::NonFinite(_)), "{e}");
        let msg = e.to_string();
        assert!(
            msg.contains("blew up") && msg.contains("beta = 1e300"),
            "{msg}"
        );
    }
}
