//! Time-domain simulation of the augmented model (`docs/design.md` §9.4): the Wiener system of §1
//! with the physical terms of §9.1,
//!
//! ```text
//! y = y0 + Lag_tau[ w + k u + c udot + m uddot + f tanh(udot / (eps Vmax)) ],
//! wdot = alpha xpdot - nu (beta |xpdot| |w|^(mu-1) w + gamma xpdot |w|^mu + delta xpdot |w|^(mu-1) w),
//! xp = Play_b[x],   nu = 1 + delta_nu e,   edot = w xpdot,
//! ```
//!
//! i.e. with alpha = 1 the generalised Bouc-Wen rate of §9.2,
//! `wdot = xpdot [1 - |w|^mu (beta sgn(xpdot w) + gamma + delta sgn(w))]` (the asymmetry is the
//! `sgn(w)` term of Song & Der Kiureghian, J. Eng. Mech. 132(6), 2006), driven by the play operator
//! (backlash of half-width `b`) of `x`. With `G -> alpha G` the map `delta -> delta/alpha`,
//! `b -> alpha b` leaves `y` unchanged. `u` is the plant's (undelayed) input: analytic for a sine,
//! the Catmull-Rom interpolant of §1 for samples; `Vmax = |U| omega` for a sine and the exact
//! maximum of the interpolant's `|udot|` for samples.
//!
//! The plain simulation ([`super::simulate`]) is not touched: this is a separate integrator chosen
//! once per simulation, and when no term needs a state (no asymmetry, play or lag) the plain one is
//! called and the output terms are added at the samples, so `x` and `w` stay bit-identical.
//!
//! Scheme, per RK4 step `[t, t + h]` (classical RK4 on `[xs, w, xp]`, §1):
//! - **play**: the mode is frozen over the step from its start: *up* when `x - xp >= b` and
//!   `xdot > 0`, *down* when `x - xp <= -b` and `xdot < 0`, else *dwell*. In the up (down) mode
//!   `xpdot = max(xdot, 0)` (`min(xdot, 0)`) at every stage, in the dwell mode 0. After the step
//!   `xp` is clamped into `[x - b, x + b]` (the exact play operator for a monotone step), and the
//!   clamped travel `dxp` is fed through the rate-independent path map `dw/dxp` (one RK4 step in
//!   `xp`), so that an engagement inside a dwell step moves `w` too. The scheme is fourth order
//!   between events; a step holding a reversal or an engagement costs `O(h^2)` locally, so with two
//!   of each per period the global error is `O(h^2)`, as the plain integrator's own kinks at the
//!   reversals of x (measured on a first-order G: w's error falls 4-6x per halving of h, with or
//!   without play).
//!   `b = 0` is the identity (`xp = x`, no state). `xp(0) = clamp(0, x(0) - b, x(0) + b)`.
//! - **sensor lag** `tau ysdot = F - ys`, `ys(0) = 0`: `ys` does not feed back, so it is integrated
//!   exponentially over each step (exponential time differencing, as in the final stage of Cox &
//!   Matthews' ETDRK4, J. Comput. Phys. 176, 2002) with `F` replaced by the quadratic through
//!   `F_0 = F(t)`, `F_m = F(t + h/2)`, `F_1 = F(t + h)`: `ys+ = e^-r ys + r [c_0 F_0 + c_m F_m +
//!   c_1 F_1]`, `r = h/tau`, `c_0 = phi_1 - 3 phi_2 + 4 phi_3`, `c_m = 4 phi_2 - 8 phi_3`,
//!   `c_1 = 4 phi_3 - phi_2` at `-r`. `F_0`, `F_1` use the accepted states, `w(t + h/2)` the RK4
//!   step's third-order continuous extension `w + h (5 k_1 + 4 k_2 + 4 k_3 - k_4)/24`. It is exact
//!   for the decay, stable for every `tau > 0` (explicit RK4 would blow up for `h > 2.79 tau`),
//!   tends to Simpson's weights as `r -> 0` and to `ys = F` as `r -> inf` (so a vanishing lag
//!   gives the lag-free output). `tau = 0` is no lag (`y` from `F` at the samples).
//! - **degradation** (Baber & Noori, J. Eng. Mech. 111(8), 1985, strength degradation only):
//!   the dissipated hysteretic energy `e = int w dxp` rides along as one more RK4 state
//!   (`edot = w xpdot`, `e(0) = 0`, moved with `w` along the play's clamped travel) and
//!   `nu = 1 + delta_nu e` multiplies the beta, gamma and delta terms: the loop's saturation level
//!   `(alpha/(nu (beta + gamma)))^(1/mu)` falls as energy is dissipated (§10.6).
//! - **stiffness degradation** (Baber & Noori's `eta`): `eta = 1 + delta_eta e` on the same energy
//!   state divides the whole rate, `alpha` included: the loop keeps its saturation level
//!   `(alpha/(beta + gamma))^(1/mu)` but is reached over a longer travel (a softer loop).
//! - **pinching** (Baber & Noori 1986, in Foliente's form, 1995): the rate times
//!   `h = 1 - zeta1 exp(-((w sgn(xpdot) - q w_u) / (zeta2 w_u))^2)`, `w_u` the virgin saturation
//!   level `(alpha/(beta + gamma))^(1/mu)`, the shape fixed at `q = ` [`PINCHING_CENTRE`],
//!   `zeta2 = ` [`PINCHING_WIDTH`]: a band of w just past the zero crossing after each reversal
//!   where w slips (moves slowly with x). Rate independent (h depends on the direction only), so the
//!   play's path map carries it too.
//! - **series dashpot** (Spencer, Dyke, Sain & Carlson, J. Eng. Mech. 123(3), 1997, with their
//!   `c0 = k0 = 0`): the element sits behind a dashpot in series and is driven by its own travel
//!   `d = xp - q`; the dashpot carries the element's force, `c1 qdot = w`, so with `rho = 1/c1`
//!   `ddot = xpdot - rho w` at every stage (no new state: `q` is not needed). The element's energy is
//!   `e = int w dd`. A play's clamped travel is instantaneous, so the dashpot does not move in it.
//! - the **output terms** are evaluated at the sample times (and, inside `F`, at the stage times).
//! - **Dahl friction** (on u or on x): its force is one more RK4 state per place, stepped with the
//!   stage rates of u or x, added to the output, not fed back (`with_terms/dahl.rs`).
//!
//! Layout: this file holds the entry point, its checks and the choice of integrator; `with_terms/`
//! holds one job per file: `values.rs` (the terms' values by name), `derivatives.rs` (the input's
//! second derivative and peak rate, and the output terms on u), `lag.rs` (the exponential lag
//! step's weights), `dahl.rs` (Dahl friction's force state, with its tests), `rhs.rs` (the
//! right-hand side: play mode, pinching, the rate and the path map), `integrate.rs` (the RK4 loop)
//! and `tests.rs`.

use super::on_x::{linear_pass, Kinematics, OnX};
use super::{check_dt, simulate, try_zeros, Input, Simulation, Sine};
use crate::bouc_wen::BoucWen;
use crate::error::{CoreError, Result};
use crate::hermite::Hermite;
use crate::linear::TransferFunction;
use crate::terms::{PINCHING_CENTRE, PINCHING_WIDTH};

mod dahl;
mod derivatives;
mod integrate;
mod lag;
mod rhs;
#[cfg(test)]
mod tests;
mod values;

use derivatives::{Derivatives, Mechanical};
use rhs::{Augmented, Pinch};
pub use values::TermValues;

/// Simulated signals with terms, on the output grid `t_k = k dt`.
#[derive(Debug, Clone, PartialEq)]
pub struct TermSimulation {
    /// Linear output `x_k` (units of `x`).
    pub x: Vec<f64>,
    /// Hysteresis output `w_k` (driven by the played `xp`).
    pub w: Vec<f64>,
    /// Measured output `y_k` before noise (units of `y`).
    pub y: Vec<f64>,
}

/// Simulates the augmented model (§9.4): `tf` -> play -> generalised Bouc-Wen `bw` + `delta`,
/// plus the output terms and the sensor lag, driven by `input`.
///
/// Grid, `substeps` and the initial state as in [`simulate`]; `xp(0) = clamp(0, x(0) ± b)`,
/// `ys(0) = 0`. Returns `x`, `w`, `y`, each of length `n_samples`.
///
/// Errors: those of [`simulate`], then [`TermValues::validate`]'s.
pub fn simulate_with_terms(
    tf: &TransferFunction,
    bw: &BoucWen,
    terms: &TermValues,
    input: Input<'_>,
    dt: f64,
    n_samples: usize,
    substeps: usize,
) -> Result<TermSimulation> {
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
    terms.validate(bw)?;
    match input {
        Input::Sine { amplitude, omega } => {
            let src = Sine {
                amplitude,
                omega,
                neg_amplitude_omega: -amplitude * omega,
            };
            run(tf, bw, terms, input, &src, dt, n_samples, substeps)
        }
        Input::Sampled { u } => {
            let src = Hermite::new(u, dt);
            run(tf, bw, terms, input, &src, dt, n_samples, substeps)
        }
    }
}

#[allow(clippy::too_many_arguments)]
fn run<S: Derivatives>(
    tf: &TransferFunction,
    bw: &BoucWen,
    terms: &TermValues,
    input: Input<'_>,
    src: &S,
    dt: f64,
    n_samples: usize,
    substeps: usize,
) -> Result<TermSimulation> {
    let mech = Mechanical::new(terms, src);
    let comp = tf.realize();
    let delay = tf.delay();
    let delayed = |t: f64| delayed_with_second(src, delay, t);
    let mut on_x = if terms.on_x.is_active() {
        let peak = if terms.on_x.coulomb == 0.0 {
            0.0 // no friction on x: its scale is not used
        } else if let Some(steady) = src.steady_x_peak_rate(tf) {
            steady
        } else {
            let mut kin = Kinematics::new(&comp);
            let mut peak = 0.0f64;
            linear_pass(&comp, delayed, dt, n_samples, substeps, |_, t, xs| {
                peak = peak.max(kin.at(xs, delayed(t)).1.abs());
            });
            peak
        };
        Some(OnX::new(terms.on_x, &comp, peak))
    } else {
        None
    };
    if !terms.is_dynamic() {
        // Nothing changes x or w: the plain integrator, untouched, and the terms at the samples (the
        // terms on x from the linear part's states, stepped alone as the plain integrator steps them).
        let Simulation { x, w } = simulate(tf, bw, input, dt, n_samples, substeps)?;
        let mut y = try_zeros(n_samples)?;
        for (k, (yk, wk)) in y.iter_mut().zip(&w).enumerate() {
            *yk = wk + mech.at(k as f64 * dt);
        }
        if let Some(on_x) = on_x.as_mut() {
            linear_pass(&comp, delayed, dt, n_samples, substeps, |k, t, xs| {
                y[k] += on_x.at(xs, delayed(t));
            });
        }
        for yk in y.iter_mut() {
            *yk += terms.offset; // IEEE addition commutes: the same bits as offset + F
        }
        let out = TermSimulation { x, w, y };
        check_blow_up(tf, bw, terms, dt, &out)?;
        return Ok(out);
    }
    let mut out = TermSimulation {
        x: try_zeros(n_samples)?,
        w: try_zeros(n_samples)?,
        y: try_zeros(n_samples)?,
    };
    // Pinching's band in units of w: centre q w_u and width zeta2 w_u, w_u the virgin saturation level.
    let w_u = (bw.alpha() / (bw.beta() + bw.gamma())).powf(1.0 / bw.mu());
    let sys = Augmented {
        comp: &comp,
        alpha: bw.alpha(),
        beta: bw.beta(),
        gamma: bw.gamma(),
        mu: bw.mu(),
        delta: terms.asymmetry,
        degradation: terms.degradation,
        stiffness_degradation: terms.stiffness_degradation,
        pinch: Pinch {
            zeta1: terms.pinching,
            centre: PINCHING_CENTRE * w_u,
            width: PINCHING_WIDTH * w_u,
        },
        delay,
        src,
        mech,
    };
    sys.integrate(bw.w0(), terms, dt, substeps, &mut on_x, &mut out);
    crate::cancel::checkpoint()?;
    check_blow_up(tf, bw, terms, dt, &out)?;
    Ok(out)
}

/// The delayed input `(v, vdot, vddot)` at time `t` (0 before the delay has elapsed).
#[inline]
fn delayed_with_second<S: Derivatives>(src: &S, delay: f64, t: f64) -> (f64, f64, f64) {
    let tau = t - delay;
    if tau < 0.0 {
        (0.0, 0.0, 0.0)
    } else {
        let (v, vdot) = src.at(tau);
        (v, vdot, src.second(tau))
    }
}

/// A non-finite `x`, `w` or `y` is the model's blow-up, not the caller's data (the inputs were
/// checked finite): name the parameters, the terms and where it happened (as
/// `simulate::check_blow_up` for the plain model).
///
/// Errors: [`CoreError::NonFinite`].
fn check_blow_up(
    tf: &TransferFunction,
    bw: &BoucWen,
    terms: &TermValues,
    dt: f64,
    out: &TermSimulation,
) -> Result<()> {
    let first = [("x", &out.x), ("w", &out.w), ("y", &out.y)]
        .into_iter()
        .filter_map(|(name, v)| v.iter().position(|v| !v.is_finite()).map(|k| (k, name)))
        .min();
    let Some((k, signal)) = first else {
        return Ok(());
    };
    Err(CoreError::NonFinite(format!(
        "the simulation blew up: {signal} is not finite from sample {k} (t = {:.6e} s) on; the \
         model parameters (alpha = {:e}, beta = {:e}, gamma = {:e}, mu = {}, w0 = {:e}, G = \
         {:?}/{:?}) with the terms ({}) or the input level make the state overflow; use term \
         values and parameters of moderate size, a smaller amplitude or a finer step (substeps)",
        k as f64 * dt,
        bw.alpha(),
        bw.beta(),
        bw.gamma(),
        bw.mu(),
        bw.w0(),
        tf.num(),
        tf.den(),
        terms.describe(),
    )))
}
