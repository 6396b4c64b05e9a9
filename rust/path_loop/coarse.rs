//! The start values of the shooting: the fixed point of a coarse cycle (the fine segments merged),
//! by multiple shooting, or bracketed single shooting should that stray.

use super::nodes::{Segment, REVERSAL};
use super::rate::Shape;
use super::rk4::{shoot_pass, Pieces};
use super::shooting::{newton_steps, Start, PIECES, SHOOT_MAX_ITER, SHOOT_RTOL};
use crate::loop_kernel::Bracket;

/// Segments (merged runs of the fine ones) of the coarse cycle whose fixed point gives the start
/// values (more where the loop is stiff, see [`COARSE_STIFF`]): close enough to the fine fixed
/// point that the fine map needs one or two Newton steps before the converged pass (measured over
/// 200 random admissible loops at P = 256: 2.3 fine passes on average).
pub(super) const COARSE_SEGMENTS: usize = 32;

/// RK4 steps per coarse segment.
pub(super) const COARSE_SUBSTEPS: usize = 2;

/// Largest coarse RK4 step in x, times the loop's stiffness bound `max |dh/dw|`.
pub(super) const COARSE_STIFF: f64 = 0.5;

/// The coarse shooting stops after a Newton step below this fraction of `w_b`.
pub(super) const COARSE_STEP: f64 = 1e-6;

/// Newton steps allowed to the coarse multiple shooting before bracketed single shooting.
pub(super) const COARSE_MULTI_MAX_ITER: usize = 12;

/// The coarse cycle: the fine segments merged, within each piece and each half cycle, into runs
/// of up to `group` and up to `max_dx` of travel (unless one fine segment is longer), each one
/// RK4 segment; returns the segments and the pieces over them.
pub(super) fn coarse_segments<const K: usize>(
    segs: &[Segment],
    pc: &Pieces<K>,
    group: usize,
    max_dx: f64,
) -> (Vec<Segment>, Pieces<K>) {
    let mut out = Vec::with_capacity(segs.len() / group + 2 * K + 2);
    let mut cp = Pieces {
        start: [0; K],
        end: [0; K],
    };
    for i in 0..K {
        cp.start[i] = out.len();
        let mut k = pc.start[i];
        while k < pc.end[i] {
            let s = segs[k].s;
            let mut dx = 0.0;
            let mut n = 0;
            while k < pc.end[i]
                && segs[k].s == s
                && n < group
                && (n == 0 || (dx + segs[k].dx).abs() <= max_dx)
            {
                dx += segs[k].dx;
                n += 1;
                k += 1;
            }
            out.push(Segment {
                dx,
                ddx: [0.0; 4],
                s,
                end: REVERSAL,
            });
        }
        cp.end[i] = out.len();
    }
    (out, cp)
}

/// Start values by multiple shooting on the coarse cycle from `w = 0` at every piece start,
/// to a Newton step below [`COARSE_STEP`]` w_b` (each iterate clamped into `[-w_b, w_b]`);
/// `None` if it overflows or takes more than [`COARSE_MULTI_MAX_ITER`] steps.
pub(super) fn coarse_multiple(
    p: &Shape,
    coarse: &[Segment],
    pc: &Pieces<PIECES>,
    bound: f64,
    xp_top: f64,
) -> Option<[f64; PIECES]> {
    // Guess: w ~ xp (slope 1 through the origin, the small loop's limit) clipped to the two
    // saturation levels (the large loop's).
    let upper = (p.beta + p.gamma + p.delta).powf(-1.0 / p.mu);
    let lower = -(p.beta + p.gamma - p.delta).powf(-1.0 / p.mu);
    let mut v = [0.0; PIECES];
    let mut xp = xp_top;
    for i in 0..PIECES {
        v[i] = xp.max(lower).min(upper);
        xp += coarse[pc.start[i]..pc.end[i]]
            .iter()
            .map(|g| g.dx)
            .sum::<f64>();
    }
    if !v.iter().all(|x| x.is_finite()) {
        v = [0.0; PIECES];
    }
    for _ in 0..COARSE_MULTI_MAX_ITER {
        let (e, m) = shoot_pass(p, coarse, pc, &v, COARSE_SUBSTEPS);
        let r: [f64; PIECES] = std::array::from_fn(|i| e[i] - v[(i + 1) % PIECES]);
        let d = newton_steps(&r, &m);
        if !d.iter().all(|x| x.is_finite()) {
            return None;
        }
        // From w = 0 the first steps overshoot where the loop saturates: |w| <= w_b holds for
        // the loop, so clamping keeps the iterate admissible without losing the step's sense.
        for i in 0..PIECES {
            v[i] = (v[i] + d[i]).max(-bound).min(bound);
        }
        if d.iter().all(|x| x.abs() <= COARSE_STEP * bound) {
            return Some(v);
        }
    }
    None
}

/// Start values by bracketed single shooting on the coarse cycle (Newton safeguarded by
/// bisection on `[-w_b, w_b]`, from `w_0 = 0`), then the coarse loop's values at the piece starts.
pub(super) fn coarse_single(
    p: &Shape,
    coarse: &[Segment],
    pc: &Pieces<PIECES>,
    bound: f64,
) -> [f64; PIECES] {
    let whole = Pieces::<1> {
        start: [0],
        end: [coarse.len()],
    };
    let mut bracket = Bracket::new(bound);
    let mut w0 = 0.0;
    for _ in 0..SHOOT_MAX_ITER {
        let (e, m) = shoot_pass(p, coarse, &whole, &[w0], COARSE_SUBSTEPS);
        let g = e[0] - w0;
        if g.abs() <= SHOOT_RTOL * bound || g.is_nan() {
            break;
        }
        let next = bracket.next(w0, g, w0 + g / (1.0 - m[0]));
        let step = next - w0;
        w0 = next;
        // Quadratic convergence: the error after this step is about step^2 / w_b, far below
        // the coarse map's own distance to the fine one (>= 1e-9 w_b).
        if step.abs() <= COARSE_STEP * bound {
            break;
        }
    }
    let mut v = [w0; PIECES];
    for i in 1..PIECES {
        let piece = Pieces::<1> {
            start: [pc.start[i - 1]],
            end: [pc.end[i - 1]],
        };
        v[i] = shoot_pass(p, coarse, &piece, &[v[i - 1]], COARSE_SUBSTEPS).0[0];
    }
    v
}

impl Start<'_> {
    /// Start values at the piece starts: shooting on a coarse cycle, the fine segments merged
    /// into about [`COARSE_SEGMENTS`]; multiple shooting from `w = 0` at every piece start (the K
    /// chains overlap) when `multiple`, and should it stray, bracketed single shooting, which
    /// always has a safe step. `xp_top` is the played input at the top of x.
    pub(super) fn values(&self, xp_top: f64, multiple: bool) -> [f64; PIECES] {
        let group = self.segs.len().div_ceil(COARSE_SEGMENTS).max(1);
        // Coarse RK4 steps of at most COARSE_STIFF / L in x keep the coarse map stable and
        // accurate (RK4 is unstable beyond 2.8 / L) however stiff the loop.
        let max_dx = COARSE_SUBSTEPS as f64 * COARSE_STIFF / self.stiffness;
        let (coarse, coarse_pieces) = coarse_segments(self.segs, self.pieces, group, max_dx);
        match multiple {
            true => coarse_multiple(self.shape, &coarse, &coarse_pieces, self.bound, xp_top),
            false => None,
        }
        .unwrap_or_else(|| coarse_single(self.shape, &coarse, &coarse_pieces, self.bound))
    }
}
