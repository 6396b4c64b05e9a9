//! Steady hysteresis loop along the input path, with asymmetry and play (`docs/design.md` 9.2).
//!
//! Generalised Bouc-Wen with alpha = 1 (the `sgn(w)` asymmetry term of Song & Der Kiureghian,
//! "Generalized Bouc-Wen model for highly asymmetric hysteresis", J. Eng. Mech. 132(6), 2006):
//! `wdot = xpdot [1 - |w|^mu (beta sgn(xpdot w) + gamma + delta sgn(w))]`, driven by
//! `xp = Play_b[x]`, the play (backlash) operator of half-width b, with `x = A cos(theta - phi)`.
//! The model is rate independent, so along a monotone stretch of the path
//! `dw/dxp = h(w, s) = 1 - |w|^mu (gamma + (beta s + delta) sgn(w))`, `s = sgn(xpdot)`, whatever
//! the speed: the loop is integrated in `xp`, from node to node (the P samples and the two
//! reversals of x, ordered from the top), never in time.
//!
//! Each segment map `w_b = Psi(w_a, dx)` is RK4 on `dw/dsigma = dx h(w, s)`, `sigma in [0, 1]`,
//! with the forward sensitivities `d/d(w_a, dx, beta, gamma, mu, delta)` riding along: RK4
//! commutes with forward differentiation, so these are the exact derivatives of the discrete map
//! (as in `steady.rs`, 7.2), here summed in reverse within each RK4 step. The steady state is the
//! fixed point of one full cycle of maps. It is found by multiple shooting: the cycle is cut into
//! four pieces whose RK4 chains are independent, so that a core overlaps their `ln`/`exp`
//! latencies, and Newton closes the joins (started from the same on a coarse cycle); bracketed
//! single shooting on the top value, Newton safeguarded by bisection on `[-w_b, w_b]`,
//! `w_b = (beta + gamma - |delta|)^(-1/mu)`, takes over should it stray. The chain rule carries
//! every sensitivity (also those of `xp` to `A`, `phi`, `b`) across the pieces and to every sample.
//!
//! The play output of a sine is exact at every node: after the top it dwells at `a - b` until x
//! has come down by `2b`, then follows `x + b`; after the bottom it dwells at `-a + b`, then
//! follows `x - b` (`a = |A|`).
//!
//! Layout: this file holds the public entry points, their checks and the Jacobian's columns;
//! `path_loop/` holds one job per file: `nodes.rs` (the cycle's nodes and the play output),
//! `waveform.rs` (a measured input waveform), `rate.rs` (`h(w, s)` and its partials), `rk4.rs` (the
//! segment maps with their sensitivities), `shooting.rs` (the fine shooting and its fallback),
//! `coarse.rs` (the start values) and `tests.rs`.

use crate::error::{finite, CoreError, Result};
use crate::loop_kernel::{check_amplitude, check_mu};
use crate::terms::PINCHING_WIDTH;

mod coarse;
mod nodes;
mod rate;
mod rk4;
mod shooting;
#[cfg(test)]
mod tests;
mod waveform;

use nodes::{distorted_segments, segments};
use rate::Shape;
use rk4::{Pieces, Record};
use shooting::{Start, PIECES};
pub use waveform::Waveform;

// Columns of a [`PathLoop::jac`] row: the shared ones first, then the path loop's own.
pub use crate::loop_kernel::{
    COL_AMPLITUDE as PD_AMPLITUDE, COL_BETA as PD_BETA, COL_DELTA as PD_DELTA,
    COL_GAMMA as PD_GAMMA, COL_MU as PD_MU, COL_PHI as PD_PHI,
};
/// d w / d b (play half-width).
pub const PD_PLAY: usize = crate::loop_kernel::N_SHARED_COLS;
/// d w / d lambda (the distortion of a measured input waveform, design.md 9.5).
pub const PD_DISTORT: usize = 7;
/// d w / d zeta1 (pinching, [`path_loop_pinched`]).
pub const PD_PINCH: usize = 8;
/// Columns of a [`PathLoop::jac`] row.
pub const N_PD: usize = 9;

/// The steady loop along the path on the sample grid and its Jacobian.
#[derive(Debug, Clone)]
pub struct PathLoop {
    /// `w(t_j)`, `t_j = j T / P`, j = 0..P (units of w).
    pub w: Vec<f64>,
    /// `d w(t_j) / d(beta, gamma, mu, A, phi, delta, b)`, one row per sample (columns `PD_*`).
    pub jac: Vec<[f64; N_PD]>,
    /// Newton (or bisection) updates of the shooting on the full-resolution map (the coarse start
    /// not counted).
    pub iterations: usize,
}

/// Steady loop of the generalised Bouc-Wen (alpha = 1, asymmetry `delta`) behind a play of
/// half-width `play`, driven by `x = amplitude cos(omega t - phi)` and sampled at `P` points per
/// period (`t_j = j T / P`), with `substeps` RK4 steps per segment between nodes.
///
/// `amplitude` is `A` (units of x, may be negative: its top is then at `theta - phi = pi`);
/// `beta`, `gamma`, `delta` in `1/[w]^mu`; `mu` dimensionless; `play` (b) in units of x; `phi`
/// in rad. Returns `w` (length P, units of w) and its Jacobian rows `d/d(beta, gamma, mu, A, phi,
/// delta, b)` (columns `PD_*`).
///
/// Errors: [`CoreError::NonFinite`] for a non-finite input or an overflowing loop;
/// [`CoreError::InvalidParameter`] for `mu <= 1`, `beta + gamma - |delta| <= 0`, `play < 0`,
/// `substeps < 1`, a grid above [`crate::steady::MAX_SAMPLES_PER_PERIOD`] /
/// [`crate::steady::MAX_STEPS_PER_PERIOD`];
/// [`CoreError::ZeroAmplitude`] for `amplitude == 0` or `play >= |amplitude|` (no motion reaches
/// the hysteresis); [`CoreError::InsufficientData`] for `P < 4`; [`CoreError::NotConverged`]
/// when the shooting finds no periodic loop.
#[allow(clippy::too_many_arguments)]
pub fn path_loop(
    amplitude: f64,
    beta: f64,
    gamma: f64,
    mu: f64,
    delta: f64,
    play: f64,
    phi: f64,
    samples_per_period: usize,
    substeps: usize,
) -> Result<PathLoop> {
    let args = (amplitude, beta, gamma, mu, delta, play, phi);
    path_loop_with(args, None, None, samples_per_period, substeps, true)
}

/// [`path_loop`] (or [`path_loop_distorted`], with a `waveform`) with pinching `zeta1` in
/// `[0, 1)`: `h(w, s)` times Foliente's `1 - zeta1 exp(-((w s - q w_u)/(zeta2 w_u))^2)`, `w_u =
/// (beta + gamma)^(-1/mu)`, the shape fixed (`crate::terms::PINCHING_CENTRE`, `PINCHING_WIDTH`).
/// The Jacobian's column [`PD_PINCH`] is `d w / d zeta1`; `zeta1 = 0` is [`path_loop`] to the bit.
///
/// Errors: those of [`path_loop`] / [`path_loop_distorted`], and
/// [`CoreError::InvalidParameter`] for `zeta1` outside `[0, 1)`.
#[allow(clippy::too_many_arguments)]
pub fn path_loop_pinched(
    amplitude: f64,
    beta: f64,
    gamma: f64,
    mu: f64,
    delta: f64,
    play: f64,
    phi: f64,
    pinch: f64,
    waveform: Option<&Waveform>,
    samples_per_period: usize,
    substeps: usize,
) -> Result<PathLoop> {
    finite("zeta1", pinch)?;
    if !(0.0..1.0).contains(&pinch) {
        return Err(CoreError::InvalidParameter(format!(
            "pinching zeta1 = {pinch} must be in [0, 1)"
        )));
    }
    let args = (amplitude, beta, gamma, mu, delta, play, phi);
    path_loop_with(
        args,
        Some(pinch),
        waveform,
        samples_per_period,
        substeps,
        true,
    )
}

/// [`path_loop`] along `x = A xi(theta - phi)`, a measured input waveform scaled by `lambda`
/// (design.md 9.5): the same loop, the Jacobian's column [`PD_DISTORT`] is `d w / d lambda`.
///
/// Errors: those of [`path_loop`] (with the half travel of x in place of `|A|` for the play),
/// and [`CoreError::InvalidParameter`] for a non-finite or odd-length `harmonics` or a waveform
/// with more than one maximum per period.
#[allow(clippy::too_many_arguments)]
pub fn path_loop_distorted(
    amplitude: f64,
    beta: f64,
    gamma: f64,
    mu: f64,
    delta: f64,
    play: f64,
    phi: f64,
    waveform: &Waveform,
    samples_per_period: usize,
    substeps: usize,
) -> Result<PathLoop> {
    let args = (amplitude, beta, gamma, mu, delta, play, phi);
    path_loop_with(
        args,
        None,
        Some(waveform),
        samples_per_period,
        substeps,
        true,
    )
}

/// The arguments of [`path_loop`]: `(amplitude, beta, gamma, mu, delta, play, phi)`.
type LoopArgs = (f64, f64, f64, f64, f64, f64, f64);

/// [`path_loop`], with the multiple shooting (`multiple`) or bracketed single shooting alone
/// (the fallback, exercised by the tests).
fn path_loop_with(
    args: LoopArgs,
    pinch: Option<f64>,
    waveform: Option<&Waveform>,
    samples_per_period: usize,
    substeps: usize,
    multiple: bool,
) -> Result<PathLoop> {
    let (amplitude, beta, gamma, mu, delta, play, phi) = args;
    check_arguments(args, waveform)?;
    crate::steady::check_grid(samples_per_period, substeps)?;
    let shape = Shape::new(beta, gamma, mu, delta, pinch);
    let p = samples_per_period;
    let (segs, half_travel) = match waveform {
        None => (segments(amplitude, phi, play, p), amplitude.abs()),
        Some(wf) => distorted_segments(amplitude, phi, play, wf, p)?,
    };
    let bound = loop_bound(beta + gamma - delta.abs(), mu)?;

    let mut w = vec![0.0; p];
    let mut jac = vec![[0.0; N_PD]; p];
    // dw_j / dv of each sample (v the start of its piece).
    let mut phis = vec![0.0; p];
    let mut out = Record {
        w: &mut w,
        jac: &mut jac,
        phis: &mut phis,
    };
    // |dh/dw| <= L on |w| <= w_b: it sizes the coarse RK4 steps and the advice on substeps.
    let mut stiffness = mu * bound.powf(mu - 1.0) * (beta.abs() + gamma.abs() + delta.abs());
    if let Some(pinch) = pinch {
        // |d(h_b P)/dw| <= L + max|h_b| max|dP/dw|, max|dP/dw| = zeta1 sqrt(2/e) / (zeta2 w_u).
        let hb_max = 1.0 + bound.powf(mu) * (beta.abs() + gamma.abs() + delta.abs());
        stiffness +=
            hb_max * pinch * (2.0f64 / std::f64::consts::E).sqrt() / (PINCHING_WIDTH * shape.w_u);
    }
    let pieces = Pieces::<PIECES>::split(segs.len());
    let start = Start {
        shape: &shape,
        segs: &segs,
        pieces: &pieces,
        bound,
        stiffness,
    };
    let v = start.values(half_travel - play, multiple);
    let iterations = start
        .solve(v, substeps, multiple, &mut out)
        .map_err(|f| start.not_converged(f, args, substeps))?;
    if !(w.iter().all(|v| v.is_finite()) && jac.iter().flatten().all(|v| v.is_finite())) {
        return Err(CoreError::NonFinite(format!(
            "the path loop or its sensitivities overflowed for A = {amplitude:e}, beta = {beta:e}, \
             gamma = {gamma:e}, mu = {mu}, delta = {delta:e}, play = {play:e}; rescale the data so \
             that the parameters are of moderate size"
        )));
    }
    Ok(PathLoop { w, jac, iterations })
}

/// The checks of [`path_loop`] and [`path_loop_distorted`] on their arguments, in order.
fn check_arguments(args: LoopArgs, waveform: Option<&Waveform>) -> Result<()> {
    let (amplitude, beta, gamma, mu, delta, play, phi) = args;
    for (name, v) in [
        ("amplitude", amplitude),
        ("beta", beta),
        ("gamma", gamma),
        ("mu", mu),
        ("delta", delta),
        ("play", play),
        ("phi", phi),
    ] {
        finite(name, v)?;
    }
    check_mu(mu)?;
    let margin = beta + gamma - delta.abs();
    if margin <= 0.0 {
        return Err(CoreError::InvalidParameter(format!(
            "beta + gamma - |delta| = {margin} must be > 0 (beta = {beta}, gamma = {gamma}, \
             delta = {delta}): otherwise one side of the loop is unbounded; shrink |delta| below \
             beta + gamma"
        )));
    }
    check_amplitude(amplitude)?;
    if play < 0.0 {
        return Err(CoreError::InvalidParameter(format!(
            "play = {play} must be >= 0 (it is the half-width of the backlash, in units of x)"
        )));
    }
    if let Some(wf) = waveform {
        finite("lambda", wf.lambda)?;
        if wf.harmonics.len() % 2 != 0 || !wf.harmonics.iter().all(|v| v.is_finite()) {
            return Err(CoreError::InvalidParameter(format!(
                "the waveform's harmonics must be finite (re, im) pairs for k = 2, 3, ...; got {} \
                 numbers",
                wf.harmonics.len()
            )));
        }
    } else if play >= amplitude.abs() {
        return Err(CoreError::ZeroAmplitude(format!(
            "play = {play} >= |amplitude| = {}: x never travels past the play, so no motion \
             reaches the hysteresis and its loop is undetermined; the play must be below |A|",
            amplitude.abs()
        )));
    }
    Ok(())
}

/// The bound `w_b = (beta + gamma - |delta|)^(-1/mu)` of the loop: `|w|` stays below the larger
/// of the two saturation levels `(beta + gamma -+ delta)^(-1/mu)`.
///
/// Errors: [`CoreError::InvalidParameter`] when it is not a usable number.
fn loop_bound(margin: f64, mu: f64) -> Result<f64> {
    let bound = (1.0 / margin).powf(1.0 / mu);
    if !(bound.is_finite() && bound > 0.0) {
        return Err(CoreError::InvalidParameter(format!(
            "beta + gamma - |delta| = {margin:e} with mu = {mu}: the loop's bound \
             (beta + gamma - |delta|)^(-1/mu) = {bound:e} is not a usable number; rescale w so \
             that the shape parameters are of moderate size"
        )));
    }
    Ok(bound)
}
