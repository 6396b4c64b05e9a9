//! The fine shooting: multiple shooting over the pieces (Newton on the joins), bracketed single
//! shooting as the fallback, the sensitivities folded around the cycle, and the error that says
//! why no loop was found.

use super::nodes::{Segment, REVERSAL};
use super::rate::Shape;
use super::rk4::{full_pass, shoot_pass, Pieces, Record};
use super::{LoopArgs, N_PD};
use crate::error::CoreError;
use crate::loop_kernel::{fold_row, Bracket};

/// Newton (or bisection) updates of `w_0` allowed on the full-resolution cycle map. Bisection
/// alone halves `[-w_b, w_b]` to the tolerance in about 45 steps.
pub(super) const SHOOT_MAX_ITER: usize = 60;

/// Relative tolerance of the periodicity condition `|W(w_0) - w_0| <= tol * w_b` (multiple
/// shooting: the sum of the joins' mismatches), a few hundred ulps of `w_b`, above the rounding
/// of a cycle's sum of about `P substeps` increments.
pub(super) const SHOOT_RTOL: f64 = 1e-13;

/// A Newton step below this fraction of `w_b` predicts (quadratic convergence) that the next pass
/// meets [`SHOOT_RTOL`], so that pass carries the sensitivities and is not repeated. Over 200
/// random admissible loops (P = 256) 1e-5 costs the fewest passes: 1.15 cheap and 1.12 full per
/// call, against 1.44 and 1.03 at 1e-6 (a full pass costs about 1.3 cheap ones).
pub(super) const FULL_PASS_STEP: f64 = 1e-5;

/// Classical RK4 is stable on `y' = -L y` for steps up to about 2.785 / L.
pub(super) const RK4_STABLE: f64 = 2.785;

/// Pieces of the cycle shot at once (their RK4 chains are independent, so a core overlaps them).
pub(super) const PIECES: usize = 4;

/// Newton updates allowed to the multiple shooting before bracketed single shooting takes over.
pub(super) const MULTI_MAX_ITER: usize = 8;

/// Newton correction of the piece starts from the joins' residuals `r_i = M_i(v_i) - v_{i+1}`
/// and slopes `m_i`: `delta_{i+1} = m_i delta_i + r_i` around the cycle, closed by
/// `delta_0 = c / (1 - prod m)`. For `K = 1` this is Newton on `W(w_0) - w_0`.
pub(super) fn newton_steps<const K: usize>(r: &[f64; K], m: &[f64; K]) -> [f64; K] {
    let (mut c, mut prod) = (0.0, 1.0);
    for i in 0..K {
        c = m[i] * c + r[i];
        prod *= m[i];
    }
    let mut d = [0.0; K];
    d[0] = c / (1.0 - prod);
    for i in 0..K - 1 {
        d[i + 1] = m[i] * d[i] + r[i];
    }
    d
}

/// How a shooting ended without a loop.
pub(super) enum Failure {
    /// Too many updates; the last residual.
    Iterations(f64),
    /// A non-finite value within a cycle.
    Diverged(f64),
    /// Multiple shooting overflowed or took too many steps: retry with single shooting.
    Unsafe,
}

/// Shooting on the piece starts `v` to `sum |r_i| <= tol`, then one pass with every sensitivity
/// at the converged starts, folded into `out` by the chain rule across pieces and around the
/// cycle. For `K = 1` (single shooting) Newton is safeguarded by bisection on
/// `[-bound, bound]`: `g = W(w_0) - w_0` is positive at `-bound` and negative at `bound`
/// (W maps the bracket into itself), so a positive residual raises the lower end; for `K > 1`
/// the iterates are clamped into `[-bound, bound]`. Returns the number of updates.
#[allow(clippy::too_many_arguments)]
pub(super) fn shoot<const K: usize>(
    p: &Shape,
    segs: &[Segment],
    pc: &Pieces<K>,
    mut v: [f64; K],
    substeps: usize,
    bound: f64,
    max_iter: usize,
    out: &mut Record<'_>,
) -> Result<usize, Failure> {
    let tol = SHOOT_RTOL * bound;
    let bracketed = K == 1;
    let mut bracket = Bracket::new(bound);
    let mut iterations = 0;
    let mut full = false;
    loop {
        let (e, m, t) = if full {
            full_pass(p, segs, pc, &v, substeps, out)
        } else {
            let (e, m) = shoot_pass(p, segs, pc, &v, substeps);
            (e, m, [[0.0; N_PD]; K])
        };
        let r: [f64; K] = std::array::from_fn(|i| e[i] - v[(i + 1) % K]);
        let resid: f64 = r.iter().map(|x| x.abs()).sum();
        if !resid.is_finite() {
            let worst = e.iter().copied().fold(
                0.0,
                |a: f64, b| if b.is_finite() { a.max(b.abs()) } else { b },
            );
            return Err(if bracketed {
                Failure::Diverged(worst)
            } else {
                Failure::Unsafe
            });
        }
        if resid <= tol {
            if !full {
                // Converged on a cheap pass: repeat it with the sensitivities (same w).
                full = true;
                continue;
            }
            // dv/dq around the cycle (the same recurrence as the Newton step, with the
            // partials T_end in place of the residuals); then every sample T_j + Phi_j dv_i/dq.
            let mut dv = [[0.0; N_PD]; K];
            for q in 0..N_PD {
                let tq: [f64; K] = std::array::from_fn(|i| t[i][q]);
                let d = newton_steps(&tq, &m);
                for i in 0..K {
                    dv[i][q] = d[i];
                }
            }
            for i in 0..K {
                for seg in &segs[pc.start[i]..pc.end[i]] {
                    if seg.end != REVERSAL {
                        fold_row(&mut out.jac[seg.end], out.phis[seg.end], &dv[i]);
                    }
                }
            }
            return Ok(iterations);
        }
        iterations += 1;
        if iterations > max_iter {
            return Err(if bracketed {
                Failure::Iterations(resid)
            } else {
                Failure::Unsafe
            });
        }
        let d = newton_steps(&r, &m);
        let step = if bracketed {
            // The bracket's ends are finite, so a non-finite Newton iterate is refused too.
            let next = bracket.next(v[0], r[0], v[0] + d[0]);
            let step = next - v[0];
            v[0] = next;
            step.abs()
        } else {
            if !d.iter().all(|x| x.is_finite()) {
                return Err(Failure::Unsafe);
            }
            // |w| <= w_b holds for the loop (a saturated one touches it to rounding), so a
            // step beyond is clamped back, and the residual test decides.
            for i in 0..K {
                v[i] = (v[i] + d[i]).max(-bound).min(bound);
            }
            d.iter().map(|x| x.abs()).fold(0.0, f64::max)
        };
        full = step <= FULL_PASS_STEP * bound;
    }
}

/// The shooting problem of one path loop: the fine segments, their pieces, the bound `w_b` and
/// the stiffness `L >= |dh/dw|` on `|w| <= w_b`.
pub(super) struct Start<'a> {
    pub(super) shape: &'a Shape,
    pub(super) segs: &'a [Segment],
    pub(super) pieces: &'a Pieces<PIECES>,
    pub(super) bound: f64,
    pub(super) stiffness: f64,
}

impl Start<'_> {
    /// Multiple shooting from the start values `v`; should it stray (or not be asked for),
    /// bracketed single shooting from the first of them, which always has a safe step. Returns
    /// the number of updates; `out` holds the loop.
    pub(super) fn solve(
        &self,
        v: [f64; PIECES],
        substeps: usize,
        multiple: bool,
        out: &mut Record<'_>,
    ) -> Result<usize, Failure> {
        let (shape, segs, bound) = (self.shape, self.segs, self.bound);
        let found = if multiple && v.iter().all(|x| x.is_finite() && x.abs() <= bound) {
            shoot(
                shape,
                segs,
                self.pieces,
                v,
                substeps,
                bound,
                MULTI_MAX_ITER,
                out,
            )
        } else {
            Err(Failure::Unsafe)
        };
        if found.is_ok() {
            return found;
        }
        let start = if v[0].is_finite() { v[0] } else { 0.0 };
        let whole = Pieces::<1> {
            start: [0],
            end: [segs.len()],
        };
        shoot(
            shape,
            segs,
            &whole,
            [start],
            substeps,
            bound,
            SHOOT_MAX_ITER,
            out,
        )
    }

    /// The error of a shooting that found no loop: why, and what to change.
    pub(super) fn not_converged(&self, f: Failure, args: LoopArgs, substeps: usize) -> CoreError {
        let (amplitude, beta, gamma, mu, delta, play, _) = args;
        let (bound, stiffness) = (self.bound, self.stiffness);
        let longest = self.segs.iter().map(|g| g.dx.abs()).fold(0.0, f64::max);
        let why = match f {
            Failure::Diverged(wn) => format!("diverged (w reached {wn:e} within one cycle)"),
            Failure::Iterations(g) => {
                format!("found no periodic loop in {SHOOT_MAX_ITER} iterations (residual {g:.3e})")
            }
            Failure::Unsafe => "left its bracket".to_string(),
        };
        let hint = if longest / substeps as f64 * stiffness > RK4_STABLE {
            format!(
                "its RK4 steps (up to {:.3e} in x) times the loop's stiffness (|dh/dw| up to \
                 {stiffness:.3e}) exceed RK4's stability limit {RK4_STABLE}: raise substeps to at \
                 least {}",
                longest / substeps as f64,
                (longest * stiffness / RK4_STABLE).ceil()
            )
        } else {
            "with beta < 0 the unloading branch runs away at large amplitudes: check the \
             parameters' signs and scale"
                .to_string()
        };
        CoreError::NotConverged(format!(
            "the path-loop shooting {why}, bound {bound:.3e}, for A = {amplitude}, beta = {beta}, \
             gamma = {gamma}, mu = {mu}, delta = {delta}, play = {play}; {hint}"
        ))
    }
}
