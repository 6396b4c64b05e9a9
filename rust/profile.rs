//! Phase as a parameter of the separable fit (beyond the paper).
//!
//! The paper's phase estimator (9) times the averaged output's maximum, which is flat once the
//! hysteresis saturates and quantised to `2 pi / P`; and its regressor (23) takes `sgn(ydot)` from
//! a noisy derivative. Here the SLS cost (21) is profiled over the phase instead: for each
//! candidate `phi`, `sgn(xdot)` comes from the candidate itself (Proposition 2: `sgn(wdot) =
//! sgn(xdot)`, with `xdot = -|G| s(t)` for a positive gain), `mu` from a golden-section search and
//! `theta` from the 3x3 normal equations. A coarse grid, then a golden refinement, finds `phi`.
//!
//! With the candidate's sign, `phi -> phi + pi` flips `s` and `sgn(xdot)` together, which maps
//! `(G, beta, gamma)` to `(-G, -beta, gamma)` at the same cost: the profile is pi-periodic, so the
//! grid spans `[0, pi)` and the estimate is mapped to the branch with `|G| > 0`.
//!
//! ## Reference
//! *Wiener System Identification in Presence of Hysteresis Nonlinearity*, the seed paper whose
//! equation numbers are cited; for the Bouc-Wen properties it relies on (Propositions 1-2):
//! F. Ikhouane and J. Rodellar, *Systems with Hysteresis: Analysis, Identification and Control
//! using the Bouc-Wen Model*, Wiley, 2007.

use nalgebra::Vector3;

use crate::bouc_wen::sgn;
use crate::error::{CoreError, Result};
use crate::solve::{golden_section, sls_search, SlsProblem};
use std::f64::consts::PI;

/// Candidate phases of the coarse grid (over a half period) when the caller gives none.
pub const DEFAULT_PHASE_GRID: usize = 48;
/// Final bracket width of the phase refinement (rad).
const PHASE_TOL: f64 = 1e-9;

/// Outcome of [`profile_phase_sls`], canonical (`gain > 0`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProfileFit {
    /// Phase `phi` in [0, 2 pi).
    pub phi: f64,
    /// Exponent mu.
    pub mu: f64,
    /// `|G(j omega)|` (> 0).
    pub gain: f64,
    /// Bouc-Wen beta.
    pub beta: f64,
    /// Bouc-Wen gamma.
    pub gamma: f64,
    /// `I_N` at the optimum.
    pub cost: f64,
    /// Grid points skipped because their normal matrix was singular.
    pub skipped: usize,
}

/// An SLS problem whose sign column comes from the candidate phase, not from `ydot`.
fn problem_at(
    ybar: &[f64],
    ydot: &[f64],
    amplitude: f64,
    omega: f64,
    phi: f64,
) -> Result<SlsProblem> {
    let mut prob = SlsProblem::new(ybar, ydot, amplitude, omega, phi)?;
    for (sg, (&s, &yb)) in prob.sign.iter_mut().zip(prob.s.iter().zip(ybar)) {
        *sg = -sgn(s) * sgn(yb);
    }
    Ok(prob)
}

/// The separable fit at one candidate phase.
#[derive(Debug, Clone, Copy)]
struct Candidate {
    mu: f64,
    theta: Vector3<f64>,
    cost: f64,
    /// The mu search ended on this end of the bracket (`Some(true)` = lower).
    at_bound: Option<bool>,
}

/// Profiled cost at `phi`, or `None` where the normal matrix is singular. A mu search that ends on
/// its bracket gives the cost at that bound, flagged, so that a bound never wins silently.
fn profile_at(
    ybar: &[f64],
    ydot: &[f64],
    amplitude: f64,
    omega: f64,
    phi: f64,
    bracket: (f64, f64, f64),
) -> Result<Option<Candidate>> {
    let prob = problem_at(ybar, ydot, amplitude, omega, phi)?;
    match sls_search(
        &prob,
        bracket.0,
        bracket.1,
        bracket.2,
        crate::solve::GOLDEN_MAX_ITER,
    ) {
        Ok(fit) => Ok(Some(Candidate {
            mu: fit.mu,
            theta: fit.theta,
            cost: fit.cost,
            at_bound: None,
        })),
        Err(CoreError::SearchAtBound { bound, lower, .. }) => match prob.cost(bound) {
            Ok((theta, cost)) => Ok(Some(Candidate {
                mu: bound,
                theta,
                cost,
                at_bound: Some(lower),
            })),
            Err(CoreError::SingularNormalMatrix { .. }) => Ok(None),
            Err(e) => Err(e),
        },
        Err(CoreError::SingularNormalMatrix { .. }) => Ok(None),
        Err(e) => Err(e),
    }
}

/// Profile-phase separable least squares on one averaged period.
///
/// `ybar`, `ydot`: one period (length P) of the averaged output and its derivative;
/// `amplitude` = U; `omega` (rad/s); `(lo, hi, tol)`: the mu bracket and tolerance;
/// `grid`: coarse phase candidates over `[0, pi)`.
///
/// Errors: input errors of [`SlsProblem::new`]; [`CoreError::SingularNormalMatrix`] when no
/// candidate phase gives a solvable fit.
#[allow(clippy::too_many_arguments)]
pub fn profile_phase_sls(
    ybar: &[f64],
    ydot: &[f64],
    amplitude: f64,
    omega: f64,
    lo: f64,
    hi: f64,
    tol: f64,
    grid: usize,
) -> Result<ProfileFit> {
    if grid < 3 {
        return Err(CoreError::InvalidParameter(format!(
            "the phase grid needs at least 3 points, got {grid}"
        )));
    }
    let bracket = (lo, hi, tol);
    let step = PI / grid as f64;
    let mut best: Option<(usize, f64)> = None;
    let mut skipped = 0;
    for k in 0..grid {
        match profile_at(ybar, ydot, amplitude, omega, k as f64 * step, bracket)? {
            Some(cand) => {
                if best.is_none_or(|(_, c)| cand.cost < c) {
                    best = Some((k, cand.cost));
                }
            }
            None => skipped += 1,
        }
    }
    let Some((k, _)) = best else {
        return Err(CoreError::SingularNormalMatrix {
            rcond: 0.0,
            context: format!(
                "no candidate phase on a {grid}-point grid gave a solvable separable fit"
            ),
        });
    };
    // Refine on the two grid cells around the best point; a failed point counts as +inf cost.
    let centre = k as f64 * step;
    let refine =
        golden_section(
            |phi| {
                Ok(profile_at(ybar, ydot, amplitude, omega, phi, bracket)?
                    .map_or(f64::MAX, |c| c.cost))
            },
            centre - step,
            centre + step,
            PHASE_TOL,
            crate::solve::GOLDEN_MAX_ITER,
        );
    let phi = match refine {
        Ok(g) => g.x,
        // The grid point itself is the best that can be said when the refinement cannot move.
        Err(CoreError::SearchAtBound { .. }) => centre,
        Err(e) => return Err(e),
    };
    let cand = match profile_at(ybar, ydot, amplitude, omega, phi, bracket)? {
        Some(v) => v,
        None => profile_at(ybar, ydot, amplitude, omega, centre, bracket)?.ok_or_else(|| {
            CoreError::SingularNormalMatrix {
                rcond: 0.0,
                context: "the refined phase gave no solvable fit".into(),
            }
        })?,
    };
    if let Some(lower) = cand.at_bound {
        return Err(CoreError::SearchAtBound {
            bound: cand.mu,
            lower,
            tol,
        });
    }
    let (mu, theta, cost) = (cand.mu, cand.theta, cand.cost);
    let (mut gain, mut beta, gamma) = (theta[0], theta[1] / theta[0], theta[2] / theta[0]);
    let mut phi = phi;
    if gain < 0.0 {
        // (G, phi, beta, gamma) ~ (-G, phi + pi, -beta, gamma): report |G| > 0.
        gain = -gain;
        phi += PI;
        beta = -beta;
    }
    Ok(ProfileFit {
        phi: phi.rem_euclid(2.0 * PI),
        mu,
        gain,
        beta,
        gamma,
        cost,
        skipped,
    })
}

/// Gain and phase at a further frequency with the hysteresis known (the refined analogue of
/// (27b)): for each candidate `phi` the gain is the 1-parameter least-squares solution with
/// `chi_j = s_j (-1 + beta sgn(xdot_j) sgn(ybar_j) |ybar_j|^mu + gamma |ybar_j|^mu)`; the cost is
/// profiled over `[0, 2 pi)` on `grid` points then refined by golden section.
///
/// Returns `(gain > 0, phi in [0, 2 pi), cost)`.
#[allow(clippy::too_many_arguments)]
pub fn profile_phase_gain(
    ybar: &[f64],
    ydot: &[f64],
    amplitude: f64,
    omega: f64,
    beta: f64,
    gamma: f64,
    mu: f64,
    grid: usize,
) -> Result<(f64, f64, f64)> {
    if grid < 3 {
        return Err(CoreError::InvalidParameter(format!(
            "the phase grid needs at least 3 points, got {grid}"
        )));
    }
    let mut pw = vec![0.0; ybar.len()];
    let mut fit = |phi: f64| -> Result<Option<(f64, f64)>> {
        let prob = problem_at(ybar, ydot, amplitude, omega, phi)?;
        prob.powers(mu, &mut pw);
        let (mut num, mut den) = (0.0, 0.0);
        for (((&s, &sg), &p), &yd) in prob.s.iter().zip(&prob.sign).zip(&pw).zip(&prob.ydot) {
            let chi = s * (-1.0 + beta * sg * p + gamma * p);
            num += yd * chi;
            den += chi * chi;
        }
        if den <= 0.0 {
            return Ok(None);
        }
        let g = num / den;
        let cost: f64 = prob
            .s
            .iter()
            .zip(&prob.sign)
            .zip(&pw)
            .zip(&prob.ydot)
            .map(|(((&s, &sg), &p), &yd)| {
                let r = yd - g * s * (-1.0 + beta * sg * p + gamma * p);
                r * r
            })
            .sum::<f64>()
            * prob.dt();
        Ok(Some((g, cost)))
    };
    let step = 2.0 * PI / grid as f64;
    let mut best: Option<(usize, f64)> = None;
    for k in 0..grid {
        if let Some((g, c)) = fit(k as f64 * step)? {
            // Only the positive-gain branch is the physical one for a fixed (beta, gamma).
            if g > 0.0 && best.is_none_or(|(_, b)| c < b) {
                best = Some((k, c));
            }
        }
    }
    let Some((k, _)) = best else {
        return Err(CoreError::SingularNormalMatrix {
            rcond: 0.0,
            context: "no candidate phase gave a positive gain for the identified hysteresis".into(),
        });
    };
    let centre = k as f64 * step;
    let phi = match golden_section(
        |phi| Ok(fit(phi)?.map_or(f64::MAX, |(_, c)| c)),
        centre - step,
        centre + step,
        PHASE_TOL,
        crate::solve::GOLDEN_MAX_ITER,
    ) {
        Ok(g) => g.x,
        Err(CoreError::SearchAtBound { .. }) => centre,
        Err(e) => return Err(e),
    };
    let (g, c) = fit(phi)?.ok_or_else(|| CoreError::SingularNormalMatrix {
        rcond: 0.0,
        context: "the gain regressor chi is identically zero".into(),
    })?;
    let (g, phi) = if g < 0.0 { (-g, phi + PI) } else { (g, phi) };
    Ok((g, phi.rem_euclid(2.0 * PI), c))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::estimate::spectral_derivative;
    use crate::steady::steady_loop;

    fn loop_data(a: f64, phi: f64, p: usize, omega: f64) -> (Vec<f64>, Vec<f64>) {
        let w = steady_loop(a, 0.8, 0.2, 1.6, phi, p, 8).unwrap().w;
        let wd = spectral_derivative(&w, omega, (p - 1) / 2).unwrap();
        (w, wd)
    }

    #[test]
    fn recovers_phase_and_hysteresis_from_a_clean_loop() {
        let (omega, u, g, phi) = (3.0, 2.0, 0.9, 1.1);
        let (w, wd) = loop_data(u * g, phi, 512, omega);
        let fit = profile_phase_sls(&w, &wd, u, omega, 1.0, 10.0, 1e-8, 48).unwrap();
        assert!((fit.phi - phi).abs() < 2e-3, "{fit:?}");
        assert!((fit.gain - g).abs() < 5e-3, "{fit:?}");
        assert!((fit.beta - 0.8).abs() < 2e-2, "{fit:?}");
        assert!((fit.gamma - 0.2).abs() < 2e-2, "{fit:?}");
        assert!((fit.mu - 1.6).abs() < 2e-2, "{fit:?}");
    }

    #[test]
    fn canonicalises_a_negative_amplitude() {
        let (omega, g, phi) = (3.0, 0.9, 1.1);
        let (w, wd) = loop_data(-2.0 * g, phi, 256, omega);
        // u = -2 cos(omega t): the fit must still report |G| > 0, with the phase moved by pi.
        let fit = profile_phase_sls(&w, &wd, -2.0, omega, 1.0, 10.0, 1e-8, 48).unwrap();
        assert!(fit.gain > 0.0);
        assert!((fit.beta - 0.8).abs() < 5e-2, "{fit:?}");
        let (gg, pp, _) = profile_phase_gain(&w, &wd, 2.0, omega, 0.8, 0.2, 1.6, 64).unwrap();
        assert!(gg > 0.0);
        let d = (pp - (phi + PI)).rem_euclid(2.0 * PI);
        assert!(d.min(2.0 * PI - d) < 1e-2, "{pp}");
    }

    #[test]
    fn gain_profile_recovers_gain_and_phase() {
        let (omega, u, g, phi) = (5.0, 1.0, 1.3, 2.4);
        let (w, wd) = loop_data(u * g, phi, 512, omega);
        let (gg, pp, _) = profile_phase_gain(&w, &wd, u, omega, 0.8, 0.2, 1.6, 64).unwrap();
        assert!((gg - g).abs() < 5e-3, "{gg}");
        assert!((pp - phi).abs() < 2e-3, "{pp}");
    }
}
